// rs_camera_fisheye.c -- fisheye lenses as mrcal's CAHVORE at linearity 0: the equidistant
// triple (r = f theta) exactly, OpenCV's fisheye model (Kannala-Brandt) exactly when k3 = k4 = 0
// and by a checked least-squares fit otherwise. See rs_camera.h and docs/conventions.md ("Fisheye
// lenses"). The files that carry these lenses are read by rs_camera.c and rs_opencv.cc.
#include <math.h>
#include <string.h>

#include "core/rs_camera.h"
#include "core/rs_units.h"

// mrcal's CAHVORE intrinsics: fx fy cx cy alpha beta r0 r1 r2 e0 e1 e2.
enum { CAHVORE_N = 12, CAHVORE_R0 = 6 };

// CAHVORE with linearity 0: the pixel radius, in units of the focal length, of a ray theta off
// the axis is theta (1 + r0 + r1 theta^2 + r2 theta^4).
static const mrcal_lensmodel_t cahvore0 = {.type = MRCAL_LENSMODEL_CAHVORE,
                                           .LENSMODEL_CAHVORE__config = {.linearity = 0.0}};

// The fit's samples of theta over [0, theta_max] and the check's (denser).
enum { FIT_SAMPLES = 400, CHECK_SAMPLES = 4000 };

static rs_status init_cahvore0(rs_camera *cam, const double core[4], const double r[3], int width, int height,
                               rs_err *err)
{
    double intrinsics[CAHVORE_N] = {core[0], core[1], core[2], core[3]};
    memcpy(&intrinsics[CAHVORE_R0], r, 3 * sizeof(double));
    return rs_camera_init(cam, &cahvore0, intrinsics, width, height, err);
}

rs_status rs_camera_init_equidistant(rs_camera *cam, double f_px, double x0_px, double y0_px, int width, int height,
                                     rs_err *err)
{
    memset(cam, 0, sizeof *cam);
    if (!(isfinite(f_px) && f_px > 0 && isfinite(x0_px) && isfinite(y0_px)))
        return rs_err_set(err, RS_ERR_INVALID, "f = %g, x0 = %g, y0 = %g: need a finite f > 0 and a finite centre",
                          f_px, x0_px, y0_px);
    const double core[4] = {f_px, f_px, x0_px, y0_px}, r[3] = {0, 0, 0};
    return init_cahvore0(cam, core, r, width, height, err);
}

// Kannala-Brandt's theta_d / theta - 1 at theta: k1 t^2 + k2 t^4 + k3 t^6 + k4 t^8.
static double kb_excess(const double k[4], double t)
{
    const double t2 = t * t;
    return t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])));
}

// The angle theta whose Kannala-Brandt radius theta (1 + kb_excess) is theta_d, by Newton's
// method from theta_d; NAN when it does not converge within [0, pi] (the polynomial folds back
// before reaching theta_d).
static double kb_theta(const double k[4], double theta_d)
{
    double t = theta_d;
    for (int it = 0; it < 50; it++) {
        const double t2 = t * t;
        const double g = t * (1 + kb_excess(k, t)) - theta_d;
        const double dg = 1 + t2 * (3 * k[0] + t2 * (5 * k[1] + t2 * (7 * k[2] + t2 * 9 * k[3])));
        if (!(dg > 0)) return NAN;
        const double step = g / dg;
        t -= step;
        if (!(t >= 0 && t <= M_PI)) return NAN;
        if (fabs(step) < 1e-15) break;
    }
    return fabs(t * (1 + kb_excess(k, t)) - theta_d) < 1e-9 ? t : NAN;
}

// The widest angle off the axis that the image shows: the largest theta of its four corners;
// pi / 2 without an image size or when a corner is beyond the model's reach.
static double widest_theta(const double core[4], const double k[4], int width, int height)
{
    if (width < 1 || height < 1) return M_PI / 2;
    const double us[2] = {-0.5, width - 0.5}, vs[2] = {-0.5, height - 0.5};
    double widest = 0;
    for (int i = 0; i < 4; i++) {
        const double theta_d = hypot((us[i & 1] - core[2]) / core[0], (vs[i >> 1] - core[3]) / core[1]);
        const double t = kb_theta(k, theta_d);
        if (!isfinite(t)) return M_PI / 2;
        widest = fmax(widest, t);
    }
    return widest;
}

// Least squares of the pixel radius error f theta ((r0 + r1 t^2 + r2 t^4) - kb_excess) over
// theta in (0, theta_max]: 3 normal equations, solved by Gaussian elimination with pivoting.
static void fit_r(double r[3], const double k[4], double f, double theta_max)
{
    double A[3][4] = {{0}};
    for (int s = 1; s <= FIT_SAMPLES; s++) {
        const double t = theta_max * s / FIT_SAMPLES, t2 = t * t;
        const double row[3] = {f * t, f * t * t2, f * t * t2 * t2}, b = f * t * kb_excess(k, t);
        for (int i = 0; i < 3; i++) {
            for (int j = 0; j < 3; j++) A[i][j] += row[i] * row[j];
            A[i][3] += row[i] * b;
        }
    }
    for (int c = 0; c < 3; c++) {
        int p = c;
        for (int i = c + 1; i < 3; i++)
            if (fabs(A[i][c]) > fabs(A[p][c])) p = i;
        for (int j = 0; j < 4; j++) {
            const double tmp = A[c][j];
            A[c][j] = A[p][j], A[p][j] = tmp;
        }
        for (int i = c + 1; i < 3; i++) {
            const double m = A[i][c] / A[c][c];
            for (int j = c; j < 4; j++) A[i][j] -= m * A[c][j];
        }
    }
    for (int i = 2; i >= 0; i--) {
        double s = A[i][3];
        for (int j = i + 1; j < 3; j++) s -= A[i][j] * r[j];
        r[i] = s / A[i][i];
    }
}

rs_status rs_camera_init_kannala_brandt(rs_camera *cam, double *fit_error_px, const double core[4], const double k[4],
                                        int width, int height, const char *path, rs_err *err)
{
    memset(cam, 0, sizeof *cam);
    if (fit_error_px) *fit_error_px = 0;
    double r[3] = {0, k[0], k[1]};
    if (k[2] == 0 && k[3] == 0) return init_cahvore0(cam, core, r, width, height, err); // exact
    const double theta_max = widest_theta(core, k, width, height), f = fmax(core[0], core[1]);
    fit_r(r, k, f, theta_max);
    double worst = 0;
    for (int s = 0; s <= CHECK_SAMPLES; s++) {
        const double t = theta_max * s / CHECK_SAMPLES, t2 = t * t;
        const double e = f * t * fabs(r[0] + t2 * (r[1] + t2 * r[2]) - kb_excess(k, t));
        worst = isfinite(e) ? fmax(worst, e) : INFINITY;
    }
    if (fit_error_px) *fit_error_px = worst;
    if (!(worst <= RS_CAMERA_FISHEYE_FIT_MAX_PX))
        return rs_err_set(err, RS_ERR_UNSUPPORTED,
                          "%s: distortion_coefficients: k3 = %g, k4 = %g: the nearest mrcal CAHVORE (linearity 0) "
                          "is off by up to %.3g px within the %.1f degrees off axis the image shows (more than %g px)",
                          path, k[2], k[3], worst, theta_max * RS_DEG_PER_RAD, RS_CAMERA_FISHEYE_FIT_MAX_PX);
    return init_cahvore0(cam, core, r, width, height, err);
}

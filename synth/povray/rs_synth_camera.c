// rs_synth_camera.c -- the POV-Ray camera of a calibrated camera; the pinhole canvas of a
// distorted lens. See rs_synth_camera.h and docs/povray.md.
#include "synth/povray/rs_synth_camera.h"
#include "core/rs_lens.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>

#include <mrcal/poseutils.h>

void rs_synth_enu_to_pov(double p_pov[3], const double p_enu[3])
{
    const double e = p_enu[0], n = p_enu[1], u = p_enu[2];
    p_pov[0] = e;
    p_pov[1] = u;
    p_pov[2] = n;
}

rs_status rs_synth_povcam_init(rs_synth_povcam *cam, const double fxycxy[4], int width, int height,
                               const double rt_cam_enu[6], rs_err *err)
{
    for (int i = 0; i < 4; i++)
        if (!isfinite(fxycxy[i])) return rs_err_set(err, RS_ERR_INVALID, "intrinsics[%d]: not finite", i);
    for (int i = 0; i < 6; i++)
        if (!isfinite(rt_cam_enu[i])) return rs_err_set(err, RS_ERR_INVALID, "rt_cam_enu[%d]: not finite", i);
    if (!(fxycxy[0] > 0) || !(fxycxy[1] > 0))
        return rs_err_set(err, RS_ERR_INVALID, "fx, fy: must be > 0 (got %g, %g)", fxycxy[0], fxycxy[1]);
    if (width <= 0 || height <= 0)
        return rs_err_set(err, RS_ERR_INVALID, "image size: must be > 0 (got %dx%d)", width, height);
    const double fx = fxycxy[0], fy = fxycxy[1], cx = fxycxy[2], cy = fxycxy[3];
    double R_cam_enu[9];
    mrcal_R_from_r(R_cam_enu, NULL, rt_cam_enu);
    // Rows of R_cam_enu are the camera axes expressed in ENU.
    const double *x_cam = &R_cam_enu[0], *y_cam = &R_cam_enu[3], *z_cam = &R_cam_enu[6];
    double centre_enu[3], right_enu[3], up_enu[3], dir_enu[3];
    const double ax = ((width - 1) * 0.5 - cx) / fx, ay = ((height - 1) * 0.5 - cy) / fy;
    for (int k = 0; k < 3; k++) {
        // centre = -R^T t
        centre_enu[k] =
            -(R_cam_enu[0 + k] * rt_cam_enu[3] + R_cam_enu[3 + k] * rt_cam_enu[4] + R_cam_enu[6 + k] * rt_cam_enu[5]);
        right_enu[k] = (width / fx) * x_cam[k];
        up_enu[k] = -(height / fy) * y_cam[k];
        dir_enu[k] = z_cam[k] + ax * x_cam[k] + ay * y_cam[k];
    }
    rs_synth_enu_to_pov(cam->location, centre_enu);
    rs_synth_enu_to_pov(cam->right, right_enu);
    rs_synth_enu_to_pov(cam->up, up_enu);
    rs_synth_enu_to_pov(cam->direction, dir_enu);
    cam->width = width;
    cam->height = height;
    cam->fisheye_deg = 0;
    return RS_OK;
}

rs_status rs_synth_povcam_init_fisheye(rs_synth_povcam *cam, double angle_deg, int size, const double rt_cam_enu[6],
                                       rs_err *err)
{
    for (int i = 0; i < 6; i++)
        if (!isfinite(rt_cam_enu[i])) return rs_err_set(err, RS_ERR_INVALID, "rt_cam_enu[%d]: not finite", i);
    if (!(angle_deg > 0 && angle_deg <= 360))
        return rs_err_set(err, RS_ERR_INVALID, "fisheye angle: must be in (0, 360] degrees (got %g)", angle_deg);
    if (size <= 0) return rs_err_set(err, RS_ERR_INVALID, "image size: must be > 0 (got %d)", size);
    double R_cam_enu[9], centre_enu[3], up_enu[3];
    mrcal_R_from_r(R_cam_enu, NULL, rt_cam_enu);
    for (int k = 0; k < 3; k++) {
        centre_enu[k] =
            -(R_cam_enu[0 + k] * rt_cam_enu[3] + R_cam_enu[3 + k] * rt_cam_enu[4] + R_cam_enu[6 + k] * rt_cam_enu[5]);
        up_enu[k] = -R_cam_enu[3 + k];
    }
    rs_synth_enu_to_pov(cam->location, centre_enu);
    rs_synth_enu_to_pov(cam->right, &R_cam_enu[0]);
    rs_synth_enu_to_pov(cam->up, up_enu);
    rs_synth_enu_to_pov(cam->direction, &R_cam_enu[6]);
    cam->width = cam->height = size;
    cam->fisheye_deg = angle_deg;
    return RS_OK;
}

rs_status rs_synth_povcam_for_canvas(rs_synth_povcam *cam, const rs_synth_canvas *canvas, const double rt_cam_enu[6],
                                     rs_err *err)
{
    if (canvas->fisheye_deg > 0)
        return rs_synth_povcam_init_fisheye(cam, canvas->fisheye_deg, canvas->width, rt_cam_enu, err);
    return rs_synth_povcam_init(cam, canvas->fxycxy, canvas->width, canvas->height, rt_cam_enu, err);
}

void rs_synth_povcam_crop(rs_synth_povcam *out, const rs_synth_povcam *in, const int region[4])
{
    *out = *in;
    const double W = in->width, H = in->height, w = region[2] - region[0] + 1, h = region[3] - region[1] + 1;
    const double a = region[0] / W - 0.5 + w / (2 * W), b = 0.5 - region[1] / H - h / (2 * H);
    for (int k = 0; k < 3; k++) {
        out->right[k] = in->right[k] * (w / W);
        out->up[k] = in->up[k] * (h / H);
        out->direction[k] = in->direction[k] + a * in->right[k] + b * in->up[k];
    }
    out->width = (int)w;
    out->height = (int)h;
}

rs_status rs_synth_povcam_write(FILE *f, const rs_synth_povcam *cam, rs_err *err)
{
    fprintf(f,
            "camera {\n  %s\n"
            "  location  <%.17g, %.17g, %.17g>\n"
            "  right     <%.17g, %.17g, %.17g>\n"
            "  up        <%.17g, %.17g, %.17g>\n"
            "  direction <%.17g, %.17g, %.17g>\n",
            cam->fisheye_deg > 0 ? "fisheye" : "perspective", cam->location[0], cam->location[1], cam->location[2],
            cam->right[0], cam->right[1], cam->right[2], cam->up[0], cam->up[1], cam->up[2], cam->direction[0],
            cam->direction[1], cam->direction[2]);
    if (cam->fisheye_deg > 0) fprintf(f, "  angle %.17g\n", cam->fisheye_deg);
    fprintf(f, "}\n");
    if (ferror(f)) return rs_err_set(err, RS_ERR_IO, "writing the camera: stream error");
    return RS_OK;
}

bool rs_synth_canvas_project(double q[2], const rs_synth_canvas *canvas, const double v[3])
{
    const double *k = canvas->fxycxy;
    if (!(canvas->fisheye_deg > 0)) {
        if (!(v[2] > 0)) return false;
        q[0] = k[0] * (v[0] / v[2]) + k[2];
        q[1] = k[1] * (v[1] / v[2]) + k[3];
        return isfinite(q[0]) && isfinite(q[1]);
    }
    const double s = hypot(v[0], v[1]), theta = atan2(s, v[2]);
    if (!(theta <= canvas->fisheye_deg * (M_PI / 360))) return false;
    const double g = s > 0 ? theta / s : 0;
    q[0] = k[0] * g * v[0] + k[2];
    q[1] = k[1] * g * v[1] + k[3];
    return isfinite(q[0]) && isfinite(q[1]);
}

// Unprojects one pixel through the real lens and projects the ray through the canvas pinhole
// (fx, fy of the canvas, cx = cy = 0): *ok = 0 when the ray is not usable.
static void lens_to_pinhole(double q_out[2], int *ok, const double q_in[2], const mrcal_lensmodel_t *lensmodel,
                            const double *intrinsics, const double fxy[2], double max_tan)
{
    mrcal_point2_t q = {.x = q_in[0], .y = q_in[1]};
    mrcal_point3_t v;
    *ok = 0;
    if (!rs_lens_unproject(&v, &q, 1, lensmodel, intrinsics)) return;
    if (!(v.z > 0) || !isfinite(v.x) || !isfinite(v.y)) return;
    const double tx = v.x / v.z, ty = v.y / v.z;
    if (hypot(tx, ty) > max_tan) return;
    q_out[0] = fxy[0] * tx;
    q_out[1] = fxy[1] * ty;
    *ok = 1;
}

// The fisheye canvas of a wide lens (rs_synth_canvas_for_lens).
static rs_status fisheye_canvas(rs_synth_canvas *canvas, const mrcal_lensmodel_t *lensmodel, const double *intrinsics,
                                int width, int height, double scale, rs_err *err)
{
    const int S = 8, Nx = (width - 1) / S + 1, Ny = (height - 1) / S + 1;
    const int Nborder = 2 * (width + 1) + 2 * (height + 1), N = Nborder + Nx * Ny;
    mrcal_point2_t *q = malloc((size_t)N * sizeof(*q));
    mrcal_point3_t *v = malloc((size_t)N * sizeof(*v));
    if (!q || !v) {
        free(q), free(v);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    for (int k = 0; k < Nborder; k++) {
        int t = k;
        if (t < 2 * (width + 1))
            q[k] = (mrcal_point2_t){.x = t / 2 - 0.5, .y = (t % 2) ? height - 0.5 : -0.5};
        else
            t -= 2 * (width + 1), q[k] = (mrcal_point2_t){.x = (t % 2) ? width - 0.5 : -0.5, .y = t / 2 - 0.5};
    }
    for (int j = 0; j < Ny; j++)
        for (int i = 0; i < Nx; i++)
            q[Nborder + j * Nx + i] =
                (mrcal_point2_t){.x = i == Nx - 1 ? width - 1 : i * S, .y = j == Ny - 1 ? height - 1 : j * S};
    const bool ok = rs_lens_unproject(v, q, N, lensmodel, intrinsics);
    double theta_max = 0, ppr = fmax(intrinsics[0], intrinsics[1]); // radial pixels per radian
    for (int k = 0; ok && k < N; k++) {
        const double s = hypot(v[k].x, v[k].y), theta = atan2(s, v[k].z);
        if (!isfinite(theta)) {
            theta_max = M_PI; // the lens's circle lies inside the image: everything it sees
            continue;
        }
        theta_max = fmax(theta_max, theta);
        if (theta > 1e-3) ppr = fmax(ppr, hypot(q[k].x - intrinsics[2], q[k].y - intrinsics[3]) / theta);
    }
    free(q), free(v);
    if (!ok) return rs_err_set(err, RS_ERR_EXTERNAL, "fisheye canvas: the lens cannot unproject");
    const double f = scale * ppr, theta_c = fmin(M_PI, theta_max + 3 / f);
    const double size = 2 * ceil(f * theta_c);
    if (size > 16384)
        return rs_err_set(err, RS_ERR_UNSUPPORTED, "the fisheye canvas would be %.0fx%.0f pixels (limit 16384)", size,
                          size);
    canvas->width = canvas->height = (int)size;
    canvas->fxycxy[0] = canvas->fxycxy[1] = size / (2 * theta_c);
    canvas->fxycxy[2] = canvas->fxycxy[3] = (size - 1) / 2;
    canvas->scale = scale;
    canvas->identity = 0;
    canvas->fisheye_deg = 2 * theta_c * (180 / M_PI);
    return RS_OK;
}

// The pinhole canvas (rs_synth_canvas_for_lens); RS_ERR_UNSUPPORTED when it cannot hold the lens.
static rs_status pinhole_canvas(rs_synth_canvas *canvas, const mrcal_lensmodel_t *lensmodel, const double *intrinsics,
                                int width, int height, double scale, rs_err *err)
{
    const double fxy[2] = {intrinsics[0] * scale, intrinsics[1] * scale};
    canvas->fisheye_deg = 0;
    if (lensmodel->type == MRCAL_LENSMODEL_PINHOLE && scale == 1) {
        for (int i = 0; i < 4; i++) canvas->fxycxy[i] = intrinsics[i];
        canvas->width = width;
        canvas->height = height;
        canvas->scale = 1;
        canvas->identity = 1;
        return RS_OK;
    }
    // The outer edges of the pixel grid (x in [-0.5, W-0.5], y in [-0.5, H-0.5]) every pixel,
    // and the centre.
    const double max_tan = tan(80.0 * M_PI / 180.0);
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    const int Nsamples = 2 * (width + 1) + 2 * (height + 1) + 1;
    for (int k = 0; k < Nsamples; k++) {
        double q[2];
        int t = k;
        if (t < 2 * (width + 1)) {
            q[0] = t / 2 - 0.5;
            q[1] = (t % 2) ? height - 0.5 : -0.5;
        } else if ((t -= 2 * (width + 1)) < 2 * (height + 1)) {
            q[0] = (t % 2) ? width - 0.5 : -0.5;
            q[1] = t / 2 - 0.5;
        } else {
            q[0] = (width - 1) * 0.5;
            q[1] = (height - 1) * 0.5;
        }
        double p[2];
        int ok;
        lens_to_pinhole(p, &ok, q, lensmodel, intrinsics, fxy, max_tan);
        if (!ok)
            return rs_err_set(err, RS_ERR_UNSUPPORTED,
                              "pixel (%g, %g) looks more than 80 degrees off the axis or cannot "
                              "be unprojected: the pinhole canvas cannot cover this lens",
                              q[0], q[1]);
        for (int i = 0; i < 2; i++) {
            lo[i] = fmin(lo[i], p[i]);
            hi[i] = fmax(hi[i], p[i]);
        }
    }
    // Canvas pixel (0,0) centre sits at pinhole coordinate lo - margin.
    const double margin = 2;
    const double x0 = floor(lo[0] - margin), y0 = floor(lo[1] - margin);
    const double w = ceil(hi[0] + margin) - x0 + 1, h = ceil(hi[1] + margin) - y0 + 1;
    if (w > 16384 || h > 16384)
        return rs_err_set(err, RS_ERR_UNSUPPORTED, "the pinhole canvas would be %.0fx%.0f pixels (limit 16384)", w, h);
    canvas->fxycxy[0] = fxy[0];
    canvas->fxycxy[1] = fxy[1];
    canvas->fxycxy[2] = -x0;
    canvas->fxycxy[3] = -y0;
    canvas->width = (int)w;
    canvas->height = (int)h;
    canvas->scale = scale;
    canvas->identity = 0;
    return RS_OK;
}

rs_status rs_synth_canvas_for_lens(rs_synth_canvas *canvas, const mrcal_lensmodel_t *lensmodel,
                                   const double *intrinsics, int width, int height, double scale, rs_err *err)
{
    if (!(scale >= 1) || !isfinite(scale))
        return rs_err_set(err, RS_ERR_INVALID, "canvas scale: must be >= 1 (got %g)", scale);
    if (width <= 0 || height <= 0)
        return rs_err_set(err, RS_ERR_INVALID, "image size: must be > 0 (got %dx%d)", width, height);
    if (!(intrinsics[0] > 0) || !(intrinsics[1] > 0)) return rs_err_set(err, RS_ERR_INVALID, "fx, fy: must be > 0");
    rs_err e2 = {0};
    const rs_status st = pinhole_canvas(canvas, lensmodel, intrinsics, width, height, scale, &e2);
    if (st != RS_ERR_UNSUPPORTED) {
        if (st && err) *err = e2;
        return st;
    }
    return fisheye_canvas(canvas, lensmodel, intrinsics, width, height, scale, err);
}

// ---- the resampling map: a grid of unprojections, interpolated, every pixel checked ----

// Catmull-Rom weights of the 4 nodes round a point at fraction t in [0, 1) of the cell between
// nodes 1 and 2 (the cubic convolution of Keys, IEEE Trans. ASSP 29(6), 1981, a = -0.5).
static void catmull_rom(double w[4], double t)
{
    w[0] = ((-0.5 * t + 1) * t - 0.5) * t;
    w[1] = (1.5 * t - 2.5) * t * t + 1;
    w[2] = ((-1.5 * t + 2) * t + 0.5) * t;
    w[3] = (0.5 * t - 0.5) * t * t;
}

// Writes map pixel i from the camera-frame direction v (a pinhole canvas: v = (x/z, y/z, 1)):
// NaN where the canvas does not see it.
static void map_from_direction(float *map, size_t i, const rs_synth_canvas *canvas, const double v[3])
{
    double q[2];
    const bool ok = rs_synth_canvas_project(q, canvas, v);
    map[2 * i] = ok ? (float)q[0] : NAN;
    map[2 * i + 1] = ok ? (float)q[1] : NAN;
}

rs_status rs_synth_canvas_map(float **map_xy, const rs_synth_canvas *canvas, const mrcal_lensmodel_t *lensmodel,
                              const double *intrinsics, int width, int height, rs_err *err)
{
    *map_xy = NULL;
    if (width <= 0 || height <= 0)
        return rs_err_set(err, RS_ERR_INVALID, "canvas map: image size must be > 0 (got %dx%d)", width, height);
    const int S = RS_SYNTH_CANVAS_MAP_STEP;
    // nodes at pixel (a - 1) S, a = 0 .. Nx - 1 (one before the image, two past its last cell)
    const int Nx = (width - 1) / S + 4, Ny = (height - 1) / S + 4;
    const size_t Npx = (size_t)width * (size_t)height, Nnodes = (size_t)Nx * (size_t)Ny;
    float *map = malloc(Npx * 2 * sizeof(float));
    mrcal_point2_t *q = malloc((Nnodes > (size_t)width ? Nnodes : (size_t)width) * sizeof(*q));
    mrcal_point3_t *v = malloc((Nnodes > (size_t)width ? Nnodes : (size_t)width) * sizeof(*v));
    // a node's direction: (x/z, y/z, 1) on a pinhole canvas, the unit vector on a fisheye one
    const bool fisheye = canvas->fisheye_deg > 0;
    double *t_node = malloc(Nnodes * 3 * sizeof(double));    // (Ny, Nx, 3); NaN: no direction
    double *t_row = malloc((size_t)Nx * 3 * sizeof(double)); // (Nx, 3) one row interpolated in y
    double *w_col = malloc((size_t)S * 4 * sizeof(double));  // (S, 4) Catmull-Rom weights per x mod S
    size_t *redo = NULL, Nredo = 0;                          // the pixels unprojected on their own
    rs_status st = RS_OK;
    if (!map || !q || !v || !t_node || !t_row || !w_col) {
        st = rs_err_set(err, RS_ERR_NOMEM, "canvas map: out of memory");
        goto done;
    }
    // 1. the nodes, unprojected by mrcal
    for (int b = 0; b < Ny; b++)
        for (int a = 0; a < Nx; a++)
            q[(size_t)b * Nx + a] = (mrcal_point2_t){.x = (double)(a - 1) * S, .y = (double)(b - 1) * S};
    if (!rs_lens_unproject(v, q, (int)Nnodes, lensmodel, intrinsics)) {
        st = rs_err_set(err, RS_ERR_EXTERNAL, "canvas map: mrcal_unproject failed");
        goto done;
    }
    for (size_t i = 0; i < Nnodes; i++) {
        const bool ok = (fisheye || v[i].z > 0) && isfinite(v[i].x) && isfinite(v[i].y) && isfinite(v[i].z);
        const double n = fisheye ? sqrt(v[i].x * v[i].x + v[i].y * v[i].y + v[i].z * v[i].z) : v[i].z;
        t_node[3 * i] = ok ? v[i].x / n : NAN;
        t_node[3 * i + 1] = ok ? v[i].y / n : NAN;
        t_node[3 * i + 2] = ok ? (fisheye ? v[i].z / n : 1) : NAN;
    }
    for (int r = 0; r < S; r++) catmull_rom(&w_col[4 * r], (double)r / S);
    // 2. every pixel interpolated (separable: along y into t_row, then along x), then checked
    // by projecting its direction back through the lens (closed form, cheap)
    for (int y = 0; y < height; y++) {
        const int j = y / S;
        double wy[4];
        catmull_rom(wy, (double)(y - j * S) / S);
        for (int a = 0; a < Nx; a++)
            for (int c = 0; c < 3; c++) {
                double s = 0;
                for (int b = 0; b < 4; b++) s += wy[b] * t_node[3 * ((size_t)(j + b) * Nx + a) + c];
                t_row[3 * a + c] = s; // NaN when a node is
            }
        for (int x = 0; x < width; x++) {
            const int i = x / S;
            const double *wx = &w_col[4 * (x - i * S)];
            double t[3];
            for (int c = 0; c < 3; c++)
                t[c] = wx[0] * t_row[3 * i + c] + wx[1] * t_row[3 * (i + 1) + c] + wx[2] * t_row[3 * (i + 2) + c] +
                       wx[3] * t_row[3 * (i + 3) + c];
            if (!fisheye && isfinite(t[2])) t[2] = 1;
            const bool finite = isfinite(t[0]) && isfinite(t[1]) && isfinite(t[2]);
            v[x] = finite ? (mrcal_point3_t){.x = t[0], .y = t[1], .z = t[2]} : (mrcal_point3_t){.z = 1};
            map_from_direction(map, (size_t)y * width + x, canvas, t);
        }
        if (!rs_lens_project(q, NULL, NULL, v, width, lensmodel, intrinsics)) {
            st = rs_err_set(err, RS_ERR_EXTERNAL, "canvas map: mrcal_project failed");
            goto done;
        }
        for (int x = 0; x < width; x++) {
            const size_t i = (size_t)y * width + x;
            const double e = hypot(q[x].x - x, q[x].y - y);
            if (isfinite(map[2 * i]) && isfinite(map[2 * i + 1]) && e <= RS_SYNTH_CANVAS_MAP_CHECK_PX) continue;
            if (Nredo % 4096 == 0) {
                size_t *grown = realloc(redo, (Nredo + 4096) * sizeof(*redo));
                if (!grown) {
                    st = rs_err_set(err, RS_ERR_NOMEM, "canvas map: out of memory");
                    goto done;
                }
                redo = grown;
            }
            redo[Nredo++] = i;
        }
    }
    // 3. the pixels that failed the check: unprojected on their own, as mrcal does
    for (size_t k0 = 0; k0 < Nredo; k0 += (size_t)width) {
        const int n = (int)(Nredo - k0 < (size_t)width ? Nredo - k0 : (size_t)width);
        for (int k = 0; k < n; k++) {
            const size_t i = redo[k0 + k];
            q[k] = (mrcal_point2_t){.x = (double)(i % (size_t)width), .y = (double)(i / (size_t)width)};
        }
        if (!rs_lens_unproject(v, q, n, lensmodel, intrinsics)) {
            st = rs_err_set(err, RS_ERR_EXTERNAL, "canvas map: mrcal_unproject failed");
            goto done;
        }
        for (int k = 0; k < n; k++) {
            const size_t i = redo[k0 + k];
            const double d[3] = {v[k].x, v[k].y, v[k].z};
            if (isfinite(d[0]) && isfinite(d[1]) && isfinite(d[2])) map_from_direction(map, i, canvas, d);
            if (!isfinite(map[2 * i]) || !isfinite(map[2 * i + 1]) || !isfinite(d[0]))
                map[2 * i] = map[2 * i + 1] = -1e6f; // outside: remap gives 0
        }
    }
    *map_xy = map;
    map = NULL;
done:
    free(map);
    free(q);
    free(v);
    free(t_node);
    free(t_row);
    free(w_col);
    free(redo);
    return st;
}

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
    return RS_OK;
}

rs_status rs_synth_povcam_write(FILE *f, const rs_synth_povcam *cam, rs_err *err)
{
    fprintf(f,
            "camera {\n  perspective\n"
            "  location  <%.17g, %.17g, %.17g>\n"
            "  right     <%.17g, %.17g, %.17g>\n"
            "  up        <%.17g, %.17g, %.17g>\n"
            "  direction <%.17g, %.17g, %.17g>\n}\n",
            cam->location[0], cam->location[1], cam->location[2], cam->right[0], cam->right[1], cam->right[2],
            cam->up[0], cam->up[1], cam->up[2], cam->direction[0], cam->direction[1], cam->direction[2]);
    if (ferror(f)) return rs_err_set(err, RS_ERR_IO, "writing the camera: stream error");
    return RS_OK;
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

rs_status rs_synth_canvas_for_lens(rs_synth_canvas *canvas, const mrcal_lensmodel_t *lensmodel,
                                   const double *intrinsics, int width, int height, double scale, rs_err *err)
{
    if (!(scale >= 1) || !isfinite(scale))
        return rs_err_set(err, RS_ERR_INVALID, "canvas scale: must be >= 1 (got %g)", scale);
    if (width <= 0 || height <= 0)
        return rs_err_set(err, RS_ERR_INVALID, "image size: must be > 0 (got %dx%d)", width, height);
    const double fxy[2] = {intrinsics[0] * scale, intrinsics[1] * scale};
    if (!(fxy[0] > 0) || !(fxy[1] > 0)) return rs_err_set(err, RS_ERR_INVALID, "fx, fy: must be > 0");
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

// Writes map pixel i from the direction (tx, ty, 1) in the camera frame (tx = x/z, ty = y/z).
static void map_from_tangent(float *map, size_t i, const rs_synth_canvas *canvas, double tx, double ty)
{
    map[2 * i] = (float)(canvas->fxycxy[0] * tx + canvas->fxycxy[2]);
    map[2 * i + 1] = (float)(canvas->fxycxy[1] * ty + canvas->fxycxy[3]);
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
    double *t_node = malloc(Nnodes * 2 * sizeof(double));    // (Ny, Nx, 2) tx, ty; NaN: no direction
    double *t_row = malloc((size_t)Nx * 2 * sizeof(double)); // (Nx, 2) one row interpolated in y
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
        const bool ok = v[i].z > 0 && isfinite(v[i].x) && isfinite(v[i].y) && isfinite(v[i].z);
        t_node[2 * i] = ok ? v[i].x / v[i].z : NAN;
        t_node[2 * i + 1] = ok ? v[i].y / v[i].z : NAN;
    }
    for (int r = 0; r < S; r++) catmull_rom(&w_col[4 * r], (double)r / S);
    // 2. every pixel interpolated (separable: along y into t_row, then along x), then checked
    // by projecting its direction back through the lens (closed form, cheap)
    for (int y = 0; y < height; y++) {
        const int j = y / S;
        double wy[4];
        catmull_rom(wy, (double)(y - j * S) / S);
        for (int a = 0; a < Nx; a++)
            for (int c = 0; c < 2; c++) {
                double s = 0;
                for (int b = 0; b < 4; b++) s += wy[b] * t_node[2 * ((size_t)(j + b) * Nx + a) + c];
                t_row[2 * a + c] = s; // NaN when a node is
            }
        for (int x = 0; x < width; x++) {
            const int i = x / S;
            const double *wx = &w_col[4 * (x - i * S)];
            double t[2];
            for (int c = 0; c < 2; c++)
                t[c] = wx[0] * t_row[2 * i + c] + wx[1] * t_row[2 * (i + 1) + c] + wx[2] * t_row[2 * (i + 2) + c] +
                       wx[3] * t_row[2 * (i + 3) + c];
            v[x] = (mrcal_point3_t){.x = isfinite(t[0]) ? t[0] : 0, .y = isfinite(t[1]) ? t[1] : 0, .z = 1};
            map_from_tangent(map, (size_t)y * width + x, canvas, t[0], t[1]);
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
            if (v[k].z > 0 && isfinite(v[k].x) && isfinite(v[k].y))
                map_from_tangent(map, i, canvas, v[k].x / v[k].z, v[k].y / v[k].z);
            else
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

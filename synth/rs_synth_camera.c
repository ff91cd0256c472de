// rs_synth_camera.c -- the POV-Ray camera of a calibrated camera; the pinhole canvas of a
// distorted lens. See rs_synth_camera.h and docs/povray.md.
#include "synth/rs_synth_camera.h"

#include <math.h>
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
    if (!mrcal_unproject(&v, &q, 1, lensmodel, intrinsics)) return;
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

rs_status rs_synth_canvas_map(float **map_xy, const rs_synth_canvas *canvas, const mrcal_lensmodel_t *lensmodel,
                              const double *intrinsics, int width, int height, rs_err *err)
{
    *map_xy = NULL;
    const size_t Npx = (size_t)width * (size_t)height;
    float *map = malloc(Npx * 2 * sizeof(float));
    mrcal_point2_t *q = malloc(Npx * sizeof(*q));
    mrcal_point3_t *v = malloc(Npx * sizeof(*v));
    rs_status st = RS_OK;
    if (!map || !q || !v) {
        st = rs_err_set(err, RS_ERR_NOMEM, "canvas map: out of memory");
        goto done;
    }
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++) q[(size_t)y * width + x] = (mrcal_point2_t){.x = x, .y = y};
    if (!mrcal_unproject(v, q, (int)Npx, lensmodel, intrinsics)) {
        st = rs_err_set(err, RS_ERR_EXTERNAL, "canvas map: mrcal_unproject failed");
        goto done;
    }
    for (size_t i = 0; i < Npx; i++) {
        if (v[i].z > 0 && isfinite(v[i].x) && isfinite(v[i].y)) {
            map[2 * i] = (float)(canvas->fxycxy[0] * v[i].x / v[i].z + canvas->fxycxy[2]);
            map[2 * i + 1] = (float)(canvas->fxycxy[1] * v[i].y / v[i].z + canvas->fxycxy[3]);
        } else {
            map[2 * i] = map[2 * i + 1] = -1e6f; // outside: remap gives 0
        }
    }
    *map_xy = map;
    map = NULL;
done:
    free(map);
    free(q);
    free(v);
    return st;
}

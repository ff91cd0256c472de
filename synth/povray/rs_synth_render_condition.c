// rs_synth_render_condition.c -- the passes a background's condition needs besides the colour
// pass (issue 40; rs_synth_render.h, docs/conditions.md): the headlights' irradiance on the
// ground (rasterised here) and the wet road's mirror image (the colour pass seen by the camera
// mirrored in the ground plane, rendered by POV-Ray, weighted by Fresnel's reflectance here).
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <mrcal/mrcal.h>

#include "synth/backdrop/rs_synth_condition.h"
#include "synth/backdrop/rs_synth_opencv.h"
#include "synth/povray/internal/rs_synth_render_internal.h"

// The camera centre in ENU and R_enu_cam (row-major), from rt_cam_enu.
static void camera_frame(double c_enu[3], double R_enu_cam[9], const double rt_cam_enu[6])
{
    double R_cam_enu[9];
    mrcal_R_from_r(R_cam_enu, NULL, rt_cam_enu);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) R_enu_cam[3 * i + j] = R_cam_enu[3 * j + i];
    for (int i = 0; i < 3; i++)
        c_enu[i] = -(R_enu_cam[3 * i] * rt_cam_enu[3] + R_enu_cam[3 * i + 1] * rt_cam_enu[4] +
                     R_enu_cam[3 * i + 2] * rt_cam_enu[5]);
}

// The ray of canvas pixel (u, v) in ENU (not unit), pinhole canvas.
static void canvas_ray(double d_enu[3], const double R_enu_cam[9], const double fxycxy[4], double u, double v)
{
    const double x = (u - fxycxy[2]) / fxycxy[0], y = (v - fxycxy[3]) / fxycxy[1];
    for (int i = 0; i < 3; i++) d_enu[i] = R_enu_cam[3 * i] * x + R_enu_cam[3 * i + 1] * y + R_enu_cam[3 * i + 2];
}

void rs_synth_povcam_mirror(rs_synth_povcam *m, const rs_synth_povcam *cam, const double g_enu[3], double offset_m)
{
    // POV-Ray's world <e, u, n>: the plane n_pov . p = offset / |n|
    const double gn = sqrt(g_enu[0] * g_enu[0] + g_enu[1] * g_enu[1] + g_enu[2] * g_enu[2]);
    const double n[3] = {g_enu[0] / gn, g_enu[2] / gn, g_enu[1] / gn}, d0 = offset_m / gn;
    *m = *cam;
    const double *src[4] = {cam->location, cam->right, cam->up, cam->direction};
    double *dst[4] = {m->location, m->right, m->up, m->direction};
    for (int k = 0; k < 4; k++) {
        const double s = n[0] * src[k][0] + n[1] * src[k][1] + n[2] * src[k][2] - (k == 0 ? d0 : 0);
        for (int c = 0; c < 3; c++) dst[k][c] = src[k][c] - 2 * s * n[c];
    }
}

bool rs_synth_mirror_rect(int rect[4], const rs_synth_canvas *canvas, const double rt_cam_enu[6],
                          const double corners_enu_m[8][3], const double g_enu[3], double offset_m)
{
    const double gn = sqrt(g_enu[0] * g_enu[0] + g_enu[1] * g_enu[1] + g_enu[2] * g_enu[2]);
    double m[8][3];
    for (int k = 0; k < 8; k++) {
        const double *p = corners_enu_m[k];
        const double s = (g_enu[0] * p[0] + g_enu[1] * p[1] + g_enu[2] * p[2] - offset_m) / gn;
        for (int c = 0; c < 3; c++) m[k][c] = p[c] - 2 * s * g_enu[c] / gn;
    }
    return rs_synth_vehicle_rect(rect, canvas, rt_cam_enu, (const double(*)[3])m, 0.05);
}

rs_status rs_synth_mirror_weight(rs_image *mirror, const rs_synth_canvas *canvas, const double rt_cam_enu[6],
                                 const double g_enu[3], rs_err *err)
{
    // premultiplied, then resized from half the canvas to the canvas (linear)
    const size_t n2 = (size_t)mirror->width * mirror->height;
    for (size_t i = 0; i < n2; i++)
        for (int k = 0; k < 3; k++) mirror->data[4 * i + k] *= mirror->data[4 * i + 3];
    rs_image full = {0}, blurred = {0};
    rs_status st = rs_synth_image_resize(&full, mirror, canvas->width, canvas->height, err);
    if (st) return st;
    double c[3], R[9];
    camera_frame(c, R, rt_cam_enu);
    const double gn = sqrt(g_enu[0] * g_enu[0] + g_enu[1] * g_enu[1] + g_enu[2] * g_enu[2]);
    for (int v = 0; v < full.height; v++)
        for (int u = 0; u < full.width; u++) {
            float *p = &full.data[4 * ((size_t)v * full.width + u)];
            if (!(p[3] > 0)) {
                memset(p, 0, 4 * sizeof(float));
                continue;
            }
            double d[3];
            canvas_ray(d, R, canvas->fxycxy, u, v);
            const double dn = (d[0] * g_enu[0] + d[1] * g_enu[1] + d[2] * g_enu[2]) / gn;
            const double cos_i = -dn / sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            const double Rf = cos_i > 0 ? rs_synth_fresnel_water(cos_i) : 0;
            for (int k = 0; k < 4; k++) p[k] = (float)(Rf * p[k]);
        }
    // ripples: a little blur (1 px) of the premultiplied reflection
    if (!(st = rs_synth_image_blur(&blurred, &full, 1.0, err))) {
        rs_image_free(mirror);
        *mirror = blurred;
    }
    rs_image_free(&full);
    return st;
}

rs_status rs_synth_headlight_ground(rs_image *irr, const rs_synth_canvas *canvas, const double rt_cam_enu[6],
                                    const double g_enu[3], double offset_m, const rs_synth_prepared *vehicles,
                                    const uint8_t *include, double intensity, rs_err *err)
{
    // at half the canvas's resolution (the light varies slowly), then resized to the canvas
    const int W2 = (canvas->width + 1) / 2, H2 = (canvas->height + 1) / 2, N = vehicles->N;
    if (!(intensity > 0)) intensity = RS_SYNTH_HEADLIGHT_INTENSITY;
    rs_image half = {0};
    rs_status st = rs_image_alloc(&half, W2, H2, 1, err);
    double(*lamp)[3] = malloc(sizeof(double[3]) * 2 * (size_t)(N > 0 ? N : 1));
    double(*axis)[3] = malloc(sizeof(double[3]) * (size_t)(N > 0 ? N : 1));
    if (!st && (!lamp || !axis)) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (st) goto done;
    const double gn = sqrt(g_enu[0] * g_enu[0] + g_enu[1] * g_enu[1] + g_enu[2] * g_enu[2]);
    const double n[3] = {g_enu[0] / gn, g_enu[1] / gn, g_enu[2] / gn}, off = offset_m / gn;
    for (int i = 0; i < N; i++) {
        const rs_synth_vehicle *v = &vehicles->v[i];
        rs_synth_scene_headlights((double(*)[3])lamp[2 * i], axis[i], v,
                                  rs_synth_ground_up_m(g_enu, offset_m, v->e_m, v->n_m));
    }
    const double cos_edge = cos(RS_SYNTH_BEAM_EDGE_DEG * M_PI / 180);
    double c[3], R[9];
    camera_frame(c, R, rt_cam_enu);
    const double hc = n[0] * c[0] + n[1] * c[1] + n[2] * c[2] - off; // camera's height over the ground
    for (int y = 0; y < H2; y++)
        for (int x = 0; x < W2; x++) {
            double d[3];
            canvas_ray(d, R, canvas->fxycxy, 2 * x + 0.5, 2 * y + 0.5);
            const double dn = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
            double e = 0;
            if (dn < 0 && hc > 0) {
                const double t = hc / -dn, p[3] = {c[0] + t * d[0], c[1] + t * d[1], c[2] + t * d[2]};
                for (int i = 0; i < N; i++) {
                    if (include && !include[i]) continue;
                    for (int k = 0; k < 2; k++) {
                        const double *l = lamp[2 * i + k];
                        const double w[3] = {p[0] - l[0], p[1] - l[1], p[2] - l[2]};
                        const double r2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2], r = sqrt(r2);
                        const double ca = (w[0] * axis[i][0] + w[1] * axis[i][1] + w[2] * axis[i][2]) / r;
                        if (!(ca > cos_edge) || r2 < 0.01) continue;
                        const double cos_inc = -(w[0] * n[0] + w[1] * n[1] + w[2] * n[2]) / r;
                        if (cos_inc <= 0) continue;
                        e += intensity * rs_synth_scene_beam(acos(ca > 1 ? 1 : ca) * 180 / M_PI) * cos_inc / r2;
                    }
                }
            }
            half.data[(size_t)y * W2 + x] = (float)e;
        }
    st = rs_synth_image_resize(irr, &half, canvas->width, canvas->height, err);
done:
    rs_image_free(&half);
    free(lamp);
    free(axis);
    return st;
}

rs_status rs_synth_condition_into_lens(rs_synth_render_result *out, rs_image *mirror, rs_image *headlights,
                                       const float *map, rs_err *err)
{
    rs_image *img[2] = {mirror, headlights};
    for (int k = 0; k < 2; k++) {
        rs_image lens = {0};
        if (!img[k]->data || !map) continue;
        rs_status st = rs_synth_remap(&lens, img[k], map, out->width, out->height, 1, err);
        if (st) return st;
        rs_image_free(img[k]);
        *img[k] = lens;
    }
    out->mirror = *mirror;
    out->headlight_irradiance = headlights->data; // owned by out now
    *mirror = *headlights = (rs_image){0};
    return RS_OK;
}

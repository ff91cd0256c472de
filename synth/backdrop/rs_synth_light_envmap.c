// rs_synth_light_envmap.c -- the environment map a background shows: every direction round the
// scene, the photograph's pixel where the camera sees it (synth/backdrop/rs_synth_light.h,
// docs/fleet.md "Reflections of the scene").
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_pose.h"
#include "synth/backdrop/rs_synth_light.h"
#include "synth/backdrop/rs_synth_opencv.h"

// 0 at the image's border, rising smoothly to 1 at feather_px inside it (q_px NaN: 0).
static double border_weight(const double q_px[2], int width, int height, double feather_px)
{
    if (!isfinite(q_px[0]) || !isfinite(q_px[1])) return 0;
    const double d = fmin(fmin(q_px[0] + 0.5, width - 0.5 - q_px[0]), fmin(q_px[1] + 0.5, height - 0.5 - q_px[1]));
    const double t = d <= 0 ? 0 : d >= feather_px ? 1 : d / feather_px;
    return t * t * (3 - 2 * t);
}

void rs_synth_env_map_direction(double d_enu[3], int col, int row, int width)
{
    const int height = width / 2;
    const double u = (col + 0.5) / width, v = 1.0 - (row + 0.5) / height;
    const double el = (v - 0.5) * M_PI, az = 2 * M_PI * u;
    // POV-Ray's spherical map: <cos(el) cos(az), sin(el), cos(el) sin(az)> in <e, u, n>
    d_enu[0] = cos(el) * cos(az), d_enu[1] = cos(el) * sin(az), d_enu[2] = sin(el);
}

rs_status rs_synth_env_map(rs_image *map, const rs_image *img, const rs_camera *cam, const double ground_normal_enu[3],
                           const double zenith_rgb[3], const double horizon_rgb[3], const double ground_rgb[3],
                           int width, rs_err *err)
{
    *map = (rs_image){0};
    if (width < 8 || width % 2)
        return rs_err_set(err, RS_ERR_INVALID, "environment map: width %d (even, at least 8)", width);
    if (img->width != cam->width || img->height != cam->height || img->channels < 3)
        return rs_err_set(err, RS_ERR_INVALID, "background: %dx%dx%d, the camera is %dx%d (RGB)", img->width,
                          img->height, img->channels, cam->width, cam->height);
    const double *g = ground_normal_enu;
    const double gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    if (!(gn > 0)) return rs_err_set(err, RS_ERR_INVALID, "environment map: no ground normal");
    const int height = width / 2;
    const size_t Nmap = (size_t)width * height;
    // the photograph shrunk to about one of its pixels per map pixel (INTER_AREA: the mean over
    // each footprint), so that a map pixel is the mean of what it covers, not one sample of it
    const double px_per_map = cam->intrinsics[0] * 2 * M_PI / width;
    const int shrink = px_per_map < 1.5 ? 1 : px_per_map > 16 ? 16 : (int)lround(px_per_map);
    const int sw = (img->width + shrink - 1) / shrink, sh = (img->height + shrink - 1) / shrink;
    rs_image rgb = {0}, small = {0}, direct = {0}, mirrored = {0};
    float *xy = malloc(sizeof(float) * 4 * Nmap);
    double *w = malloc(sizeof(double) * 2 * Nmap);
    rs_status st = xy && w ? rs_image_alloc(&rgb, img->width, img->height, 3, err)
                           : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (st) goto done;
    for (size_t i = 0; i < (size_t)img->width * img->height; i++)
        for (int c = 0; c < 3; c++) rgb.data[3 * i + c] = img->data[i * (size_t)img->channels + (size_t)c];
    if ((st = rs_synth_image_resize(&small, &rgb, sw, sh, err))) goto done;
    // the camera's position, and its forward direction along the ground (the mirror's normal)
    double c_enu[3], R[3][3], f[3];
    rs_pose_position_from_rt(c_enu, NULL, cam->rt_cam_enu);
    mrcal_R_from_r(&R[0][0], NULL, cam->rt_cam_enu);
    double fg = 0, fn = 0;
    for (int k = 0; k < 3; k++) f[k] = R[2][k], fg += f[k] * g[k] / gn; // camera z in ENU: row 2 of R_cam_enu
    for (int k = 0; k < 3; k++) f[k] -= fg * g[k] / gn, fn += f[k] * f[k];
    fn = sqrt(fn);
    for (int k = 0; k < 3; k++) f[k] = fn > 1e-9 ? f[k] / fn : 0;
    const double max_tan = rs_camera_max_tan(cam);
    const double feather_px = 0.06 * (cam->width < cam->height ? cam->width : cam->height);
    for (int row = 0; row < height; row++)
        for (int col = 0; col < width; col++) {
            const size_t i = (size_t)row * width + col;
            double d[2][3], dn = 0;
            rs_synth_env_map_direction(d[0], col, row, width);
            for (int k = 0; k < 3; k++) dn += d[0][k] * f[k];
            for (int k = 0; k < 3; k++) d[1][k] = d[0][k] - 2 * dn * f[k]; // mirrored front to back
            for (int m = 0; m < 2; m++) {
                double p[3], q[2] = {NAN, NAN};
                for (int k = 0; k < 3; k++) p[k] = c_enu[k] + 1e4 * d[m][k];
                const bool up = d[m][0] * g[0] + d[m][1] * g[1] + d[m][2] * g[2] > 0;
                if (up) rs_camera_project_visible(q, cam, max_tan, p);
                w[2 * i + m] = up ? border_weight(q, cam->width, cam->height, feather_px) : 0;
                xy[4 * i + 2 * m] = (float)((q[0] + 0.5) / shrink - 0.5);
                xy[4 * i + 2 * m + 1] = (float)((q[1] + 0.5) / shrink - 0.5);
                if (!(w[2 * i + m] > 0)) xy[4 * i + 2 * m] = xy[4 * i + 2 * m + 1] = -1;
            }
        }
    // the two samples as images through OpenCV's remap: the map's (x, y) pairs interleaved by
    // direction, so each remap reads every other pair
    float *xy1 = malloc(sizeof(float) * 2 * Nmap);
    if (!xy1) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    for (int m = 0; m < 2 && !st; m++) {
        for (size_t i = 0; i < Nmap; i++) xy1[2 * i] = xy[4 * i + 2 * m], xy1[2 * i + 1] = xy[4 * i + 2 * m + 1];
        st = rs_synth_remap(m ? &mirrored : &direct, &small, xy1, width, height, 1, err);
    }
    free(xy1);
    if (st || (st = rs_image_alloc(map, width, height, 3, err))) goto done;
    const double sin_lo = sin(10.0 * M_PI / 180), sin_hi = sin(30.0 * M_PI / 180);
    for (int row = 0; row < height; row++)
        for (int col = 0; col < width; col++) {
            const size_t i = (size_t)row * width + col;
            double d[3];
            rs_synth_env_map_direction(d, col, row, width);
            const double s_el = (d[0] * g[0] + d[1] * g[1] + d[2] * g[2]) / gn;
            // outside the view: the horizon colour up to 10 deg, the zenith's above 30, blended
            const double t = s_el <= sin_lo ? 0 : s_el >= sin_hi ? 1 : (s_el - sin_lo) / (sin_hi - sin_lo);
            const double wd = w[2 * i], wm = w[2 * i + 1];
            for (int c = 0; c < 3; c++) {
                const double fill = s_el < 0 ? ground_rgb[c] : (1 - t) * horizon_rgb[c] + t * zenith_rgb[c];
                const double behind = wm * mirrored.data[3 * i + c] + (1 - wm) * fill;
                map->data[3 * i + c] = (float)(wd * direct.data[3 * i + c] + (1 - wd) * behind);
            }
        }
done:
    if (st) rs_image_free(map);
    rs_image_free(&rgb);
    rs_image_free(&small);
    rs_image_free(&direct);
    rs_image_free(&mirrored);
    free(xy);
    free(w);
    return st;
}

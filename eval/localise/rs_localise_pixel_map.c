// rs_localise_pixel_map.c -- every pixel of a camera to the ground (rs_localise.h,
// rs_localise_pixel_map_compute): the detection rule of rs_localise_detection_locate applied at
// each pixel, lat/lon one image row at a time.
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "eval/localise/rs_localise.h"

void rs_localise_pixel_map_free(rs_localise_pixel_map *map)
{
    if (!map) return;
    free(map->e_m); // one block holds the five arrays
    memset(map, 0, sizeof *map);
}

rs_status rs_localise_pixel_map_compute(rs_localise_pixel_map *map, const rs_localise_view *view, double pixel_sigma_px,
                                        rs_err *err)
{
    memset(map, 0, sizeof *map);
    const int W = view->camera->width, H = view->camera->height;
    if (W <= 0 || H <= 0) return rs_err_set(err, RS_ERR_INVALID, "the camera has no image size");
    if (!(pixel_sigma_px >= 0) || !isfinite(pixel_sigma_px))
        return rs_err_set(err, RS_ERR_INVALID, "pixel sigma %g: must be finite and >= 0", pixel_sigma_px);
    const size_t N = (size_t)W * (size_t)H;
    double *block = malloc(5 * N * sizeof *block), *enu = malloc(3 * (size_t)W * sizeof *enu),
           *llh = malloc(3 * (size_t)W * sizeof *llh);
    if (!block || !enu || !llh) {
        free(block);
        free(enu);
        free(llh);
        return rs_err_set(err, RS_ERR_NOMEM, "pixel map of %d x %d: out of memory", W, H);
    }
    *map = (rs_localise_pixel_map){W, H, block, block + N, block + 2 * N, block + 3 * N, block + 4 * N};
    rs_localise_view no_origin = *view; // lat/lon a row at a time below
    no_origin.origin = NULL;
    const rs_localise_options opt = {.point = RS_LOCALISE_POINT_CENTER, .pixel_sigma_px = pixel_sigma_px};
    rs_status st = RS_OK;
    for (int v = 0; v < H && !st; v++) {
        for (int u = 0; u < W && !st; u++) {
            const size_t k = (size_t)v * (size_t)W + (size_t)u;
            rs_localise_detection det = {.has_bottom_center = true, .bottom_center_px = {u, v}, .time_s = NAN};
            rs_localise_row row;
            rs_err e = {0};
            rs_status s = rs_localise_detection_locate(&row, &det, &no_origin, &opt, &e);
            if (s && s != RS_ERR_DEGENERATE) {
                st = s;
                if (err) *err = e;
            }
            const bool ok = s == RS_OK;
            map->e_m[k] = ok ? row.e_m : NAN;
            map->n_m[k] = ok ? row.n_m : NAN;
            map->sigma_m[k] = ok ? hypot(row.sigma_e_m, row.sigma_n_m) : NAN;
            enu[3 * u] = ok ? row.e_m : 0;
            enu[3 * u + 1] = ok ? row.n_m : 0;
            enu[3 * u + 2] = ok ? row.u_m : 0;
        }
        double *lat = &map->lat_deg[(size_t)v * (size_t)W], *lon = &map->lon_deg[(size_t)v * (size_t)W];
        if (!st && view->origin) st = rs_geo_enu_to_llh(llh, view->origin, enu, W, err);
        for (int u = 0; u < W && !st; u++) {
            const bool ok = view->origin && isfinite(map->e_m[(size_t)v * (size_t)W + (size_t)u]);
            lat[u] = ok ? llh[3 * u] : NAN;
            lon[u] = ok ? llh[3 * u + 1] : NAN;
        }
    }
    free(enu);
    free(llh);
    if (st) rs_localise_pixel_map_free(map);
    return st;
}

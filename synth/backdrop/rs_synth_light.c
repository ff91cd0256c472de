// rs_synth_light.c -- the light a background image shows: its level and colour on the road, the
// environment the vehicles reflect, the sun's direction from the poles' shadows
// (synth/backdrop/rs_synth_light.h, docs/backgrounds.md).
#include "synth/backdrop/rs_synth_light.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_pose.h"
#include "core/rs_stats.h"
#include "core/rs_units.h"
#include "synth/backdrop/rs_synth_appearance.h"
#include "synth/fleet/rs_synth_vehicle.h"

// ---- the light model ----

void rs_synth_env_default(double zenith_rgb[3], double horizon_rgb[3], double ground_rgb[3], bool overcast)
{
    static const double clear[3][3] = {{0.20, 0.30, 0.55}, {0.50, 0.55, 0.60}, {0.20, 0.19, 0.18}};
    static const double grey[3][3] = {{0.95, 0.97, 1.00}, {0.80, 0.82, 0.84}, {0.16, 0.16, 0.16}};
    const double(*e)[3] = overcast ? grey : clear;
    for (int c = 0; c < 3; c++) zenith_rgb[c] = e[0][c], horizon_rgb[c] = e[1][c], ground_rgb[c] = e[2][c];
}

// ---- the light a background shows ----

static int cmp_float(const void *a, const void *b)
{
    const float x = *(const float *)a, y = *(const float *)b;
    return x < y ? -1 : x > y;
}

// The road pixels of the last camera seen (issue 18's cost): which pixels of the step_px grid
// are road depends on the camera, the ground and the lanes, not on the image, and finding them
// (a ground point per pixel through mrcal's iterative unprojection) is nearly all of this
// function's time: 0.076 s at 720x480, step 4. A `roadside synth` worker estimating the light of
// several backgrounds of its camera finds them once. The key is those inputs themselves, compared
// exactly (lens name with its configuration, intrinsics, pose, size, plane, lanes, step), so a
// hit gives the same pixels in the same order: the same estimate. One per process; not
// thread-safe (roadside's workers are processes).
static struct {
    char lens[160];
    double *key; // owned
    size_t Nkey;
    size_t *px; // (Npx,) owned: offsets y * width + x, in scan order
    size_t Npx;
    // the environment's pixels (rs_synth_env_from_image), found in the same pass: ground within
    // 60 m, sky up to RS_SYNTH_ENV_HORIZON_DEG above the horizon, sky above it. (Nenv[k],) owned.
    size_t *env[3];
    size_t Nenv[3];
} road_cache;

// The key of road_cache for these inputs (malloc'ed, *n doubles), NULL when out of memory.
static double *road_key(size_t *n, const rs_camera *cam, const rs_site *site, const rs_lanes *lanes, int step_px)
{
    size_t N = (size_t)cam->Nintrinsics + 15; // intrinsics, rt 6, normal 3, offset, width, height, step, Ni, Nlanes
    for (int l = 0; l < lanes->N; l++) N += 2 + 3 * (size_t)lanes->lane[l].Npoints;
    double *k = malloc(N * sizeof(double));
    if (!k) return NULL;
    size_t m = 0;
    for (int i = 0; i < cam->Nintrinsics; i++) k[m++] = cam->intrinsics[i];
    for (int i = 0; i < 6; i++) k[m++] = cam->rt_cam_enu[i];
    for (int i = 0; i < 3; i++) k[m++] = site->ground_normal_enu[i];
    k[m++] = site->ground_offset_m, k[m++] = cam->width, k[m++] = cam->height, k[m++] = step_px;
    k[m++] = cam->Nintrinsics, k[m++] = lanes->N;
    for (int l = 0; l < lanes->N; l++) {
        const rs_lane *ln = &lanes->lane[l];
        k[m++] = ln->width_m, k[m++] = ln->Npoints;
        for (int q = 0; q < ln->Npoints; q++)
            for (int c = 0; c < 3; c++) k[m++] = ln->p_enu_m[q][c];
    }
    *n = m;
    return k;
}

// The road pixels of the step_px grid (rs_synth_light_from_image), from road_cache or found:
// *px borrowed from the cache (valid until the next call).
static rs_status road_pixels(const size_t **px, size_t *Npx, const rs_camera *cam, const rs_site *site,
                             const rs_lanes *lanes, int step_px, rs_err *err)
{
    // The environment's pixel classes: none, ground (within 60 m), low sky, high sky.
    enum { ENV_NONE = -1, ENV_GROUND = 0, ENV_HORIZON = 1, ENV_ZENITH = 2 };
    char lens[160];
    size_t Nkey = 0;
    double *key = road_key(&Nkey, cam, site, lanes, step_px);
    if (!key || !mrcal_lensmodel_name(lens, sizeof(lens), &cam->lensmodel)) {
        free(key);
        return rs_err_set(err, key ? RS_ERR_INVALID : RS_ERR_NOMEM,
                          key ? "background: unknown lens model" : "out of memory");
    }
    if (road_cache.key && road_cache.Nkey == Nkey && !strcmp(road_cache.lens, lens) &&
        !memcmp(road_cache.key, key, Nkey * sizeof(double))) {
        free(key);
        *px = road_cache.px, *Npx = road_cache.Npx;
        return RS_OK;
    }
    const size_t cap = (size_t)((cam->width + step_px - 1) / step_px) * (size_t)((cam->height + step_px - 1) / step_px);
    size_t *out = malloc(sizeof(size_t) * (cap ? cap : 1)), n = 0;
    size_t *env[3] = {malloc(sizeof(size_t) * (cap ? cap : 1)), malloc(sizeof(size_t) * (cap ? cap : 1)),
                      malloc(sizeof(size_t) * (cap ? cap : 1))},
           Nenv[3] = {0, 0, 0};
    if (!out || !env[0] || !env[1] || !env[2]) {
        free(key), free(out), free(env[0]), free(env[1]), free(env[2]);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    // the camera's position: where rays start (rt_cam_enu maps ENU into the camera)
    double c_enu[3];
    rs_pose_position_from_rt(c_enu, NULL, cam->rt_cam_enu);
    const double *g = site->ground_normal_enu;
    const double gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    // a plane 10 km above the camera, parallel to the ground: the rays of the sky meet it
    const double sky_offset_m = (g[0] * c_enu[0] + g[1] * c_enu[1] + g[2] * c_enu[2]) + 1e4 * gn;
    const double sin_band = sin(RS_SYNTH_ENV_HORIZON_DEG * RS_RAD_PER_DEG);
    for (int y = step_px / 2; y < cam->height; y += step_px)
        for (int x = step_px / 2; x < cam->width; x += step_px) {
            const double q[2] = {x, y};
            const size_t o = (size_t)y * cam->width + x;
            double p[3];
            const rs_status sg = rs_camera_locate_ground(p, cam, q, g, site->ground_offset_m, NULL);
            if (sg == RS_ERR_DEGENERATE && gn > 0 && !rs_camera_locate_ground(p, cam, q, g, sky_offset_m, NULL)) {
                // the sky: the ray rises; its elevation above the ground plane's horizon
                double d[3], dd = 0, up = 0;
                for (int c = 0; c < 3; c++) d[c] = p[c] - c_enu[c], dd += d[c] * d[c], up += d[c] * g[c] / gn;
                const int k = up / sqrt(dd) <= sin_band ? ENV_HORIZON : ENV_ZENITH;
                if (dd > 0) env[k][Nenv[k]++] = o;
                continue;
            }
            if (sg) continue;
            if (hypot(p[0] - c_enu[0], p[1] - c_enu[1]) > 60.0) continue;
            env[ENV_GROUND][Nenv[ENV_GROUND]++] = o;
            bool road = false;
            for (int l = 0; l < lanes->N && !road; l++)
                road = rs_lane_distance_m(NULL, &lanes->lane[l], p) <= 0.5 * lanes->lane[l].width_m - 0.4;
            if (road) out[n++] = o;
        }
    (void)ENV_NONE;
    free(road_cache.key);
    free(road_cache.px);
    for (int k = 0; k < 3; k++) free(road_cache.env[k]), road_cache.env[k] = env[k], road_cache.Nenv[k] = Nenv[k];
    snprintf(road_cache.lens, sizeof(road_cache.lens), "%s", lens);
    road_cache.key = key, road_cache.Nkey = Nkey, road_cache.px = out, road_cache.Npx = n;
    *px = out, *Npx = n;
    return RS_OK;
}

// The road pixels of a background img seen by cam (road_pixels), after checking that img is
// that camera's RGB image.
static rs_status background_pixels(const size_t **px, size_t *Npx, const rs_image *img, const rs_camera *cam,
                                   const rs_site *site, const rs_lanes *lanes, int step_px, rs_err *err)
{
    if (img->width != cam->width || img->height != cam->height || img->channels < 3)
        return rs_err_set(err, RS_ERR_INVALID, "background: %dx%dx%d, the camera is %dx%d (RGB)", img->width,
                          img->height, img->channels, cam->width, cam->height);
    return road_pixels(px, Npx, cam, site, lanes, step_px < 1 ? 1 : step_px, err);
}

// The estimate from the pixels px (n >= 50 offsets into img): the per-channel interquartile mean
// of their linear values over RS_SYNTH_ROAD_ALBEDO.
static rs_status light_from_pixels(rs_synth_light_estimate *out, const rs_image *img, const size_t *px, size_t n,
                                   rs_err *err)
{
    float *v = malloc(sizeof(float) * 3 * n);
    if (!v) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) v[c * n + i] = img->data[px[i] * (size_t)img->channels + (size_t)c];
    out->Nroad_px = (int)n;
    for (int c = 0; c < 3; c++) {
        qsort(v + c * n, n, sizeof(float), cmp_float);
        const float *s = v + c * n;
        double sum = 0; // the interquartile mean
        const size_t a = n / 4, b = n - n / 4;
        for (size_t i = a; i < b; i++) sum += s[i];
        out->road_rgb[c] = sum / (double)(b - a);
        out->irradiance_rgb[c] = out->road_rgb[c] / RS_SYNTH_ROAD_ALBEDO;
    }
    free(v);
    out->level = (out->irradiance_rgb[0] + out->irradiance_rgb[1] + out->irradiance_rgb[2]) / 3;
    for (int c = 0; c < 3; c++) out->tint_rgb[c] = out->level > 0 ? out->irradiance_rgb[c] / out->level : 1;
    return RS_OK;
}

rs_status rs_synth_light_from_image(rs_synth_light_estimate *out, const rs_image *img, const rs_camera *cam,
                                    const rs_site *site, const rs_lanes *lanes, int step_px, rs_err *err)
{
    *out = (rs_synth_light_estimate){0};
    const size_t *px = NULL;
    size_t n = 0;
    rs_status st = background_pixels(&px, &n, img, cam, site, lanes, step_px, err);
    if (st) return st;
    if (n < 50) return rs_err_set(err, RS_ERR_DEGENERATE, "background: %zu road pixels in view, at least 50 needed", n);
    return light_from_pixels(out, img, px, n, err);
}

const char *rs_synth_light_source_name(rs_synth_light_source source)
{
    return source == RS_SYNTH_LIGHT_FROM_LANES    ? "the road in the lanes"
           : source == RS_SYNTH_LIGHT_FROM_GROUND ? "the ground plane within 60 m"
                                                  : "the lower half of the image";
}

rs_status rs_synth_light_from_background(rs_synth_light_estimate *out, const rs_image *img, const rs_camera *cam,
                                         const rs_site *site, const rs_lanes *lanes, int step_px, rs_err *err)
{
    rs_status st = rs_synth_light_from_image(out, img, cam, site, lanes, step_px, err);
    if (st != RS_ERR_DEGENERATE) return st;
    // the ground plane in view: road_cache's ground class, filled by the call above; its grey
    // pixels when at least 50 (asphalt, concrete, kerbs: not the verges' grass and soil)
    if (road_cache.Nenv[0] >= 50) {
        size_t *grey = malloc(sizeof(size_t) * road_cache.Nenv[0]), Ngrey = 0;
        if (!grey) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        for (size_t i = 0; i < road_cache.Nenv[0]; i++) {
            const float *v = img->data + road_cache.env[0][i] * (size_t)img->channels;
            const float hi = fmaxf(v[0], fmaxf(v[1], v[2])), lo = fminf(v[0], fminf(v[1], v[2]));
            if (hi > 0 && hi - lo <= RS_SYNTH_LIGHT_GREY_CHROMA * hi) grey[Ngrey++] = road_cache.env[0][i];
        }
        *out = (rs_synth_light_estimate){0};
        st = Ngrey >= 50 ? light_from_pixels(out, img, grey, Ngrey, err)
                         : light_from_pixels(out, img, road_cache.env[0], road_cache.Nenv[0], err);
        out->source = RS_SYNTH_LIGHT_FROM_GROUND;
        free(grey);
        return st;
    }
    // the lower half of the image, on the same grid
    const int s = step_px < 1 ? 1 : step_px;
    const size_t cap = (size_t)((img->width + s - 1) / s) * (size_t)((img->height + s - 1) / s) + 1;
    size_t *px = malloc(sizeof(size_t) * cap), n = 0;
    if (!px) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int y = s / 2; y < img->height; y += s)
        for (int x = s / 2; x < img->width && 2 * y >= img->height; x += s) px[n++] = (size_t)y * img->width + x;
    *out = (rs_synth_light_estimate){0};
    st = n >= 50 ? light_from_pixels(out, img, px, n, err)
                 : rs_err_set(err, RS_ERR_DEGENERATE, "background: %dx%d, too small for a light estimate", img->width,
                              img->height);
    out->source = RS_SYNTH_LIGHT_FROM_LOWER_IMAGE;
    free(px);
    return st;
}

// out->sky_rgb, Nsky_px: the mean of the pixels above the horizon (both bands of road_cache)
// whose linear luminance is at or above their 90th percentile.
static rs_status sky_from_brightest(rs_synth_env_estimate *out, const rs_image *img, rs_err *err)
{
    const size_t n = road_cache.Nenv[1] + road_cache.Nenv[2];
    if (n == 0) return RS_OK;
    double *lum = malloc(sizeof(double) * n), *sorted = malloc(sizeof(double) * n);
    if (!lum || !sorted) {
        free(lum), free(sorted);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    size_t m = 0;
    for (int k = 1; k <= 2; k++)
        for (size_t i = 0; i < road_cache.Nenv[k]; i++) {
            const float *v = img->data + road_cache.env[k][i] * (size_t)img->channels;
            const double y = 0.2126 * v[0] + 0.7152 * v[1] + 0.0722 * v[2];
            lum[m++] = isfinite(y) ? y : -1;
        }
    memcpy(sorted, lum, sizeof(double) * m);
    const double y90 = rs_stats_quantile(sorted, (int)m, 0.9);
    double sum[3] = {0, 0, 0};
    int Nsky = 0;
    m = 0;
    for (int k = 1; k <= 2; k++)
        for (size_t i = 0; i < road_cache.Nenv[k]; i++, m++) {
            if (!(lum[m] >= y90 && lum[m] >= 0)) continue;
            const float *v = img->data + road_cache.env[k][i] * (size_t)img->channels;
            for (int c = 0; c < 3; c++) sum[c] += v[c];
            Nsky++;
        }
    out->Nsky_px = Nsky;
    for (int c = 0; c < 3; c++) out->sky_rgb[c] = Nsky ? sum[c] / Nsky : 0;
    free(lum), free(sorted);
    return RS_OK;
}

rs_status rs_synth_env_from_image(rs_synth_env_estimate *out, const rs_image *img, const rs_camera *cam,
                                  const rs_site *site, const rs_lanes *lanes, int step_px, rs_err *err)
{
    *out = (rs_synth_env_estimate){0};
    const size_t *px = NULL;
    size_t n = 0;
    rs_status st = background_pixels(&px, &n, img, cam, site, lanes, step_px, err);
    if (st) return st;
    double *rgb[3] = {out->ground_rgb, out->horizon_rgb, out->zenith_rgb};
    int *N[3] = {&out->Nground_px, &out->Nhorizon_px, &out->Nzenith_px};
    for (int k = 0; k < 3; k++) {
        double sum[3] = {0, 0, 0};
        size_t m = 0;
        for (size_t i = 0; i < road_cache.Nenv[k]; i++) {
            const float *v = img->data + road_cache.env[k][i] * (size_t)img->channels;
            if (!(isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]))) continue;
            for (int c = 0; c < 3; c++) sum[c] += v[c];
            m++;
        }
        *N[k] = (int)m;
        for (int c = 0; c < 3; c++) rgb[k][c] = m ? sum[c] / (double)m : 0;
    }
    return sky_from_brightest(out, img, err);
}

void rs_synth_env_match(double zenith_rgb[3], double horizon_rgb[3], double ground_rgb[3],
                        const rs_synth_env_estimate *env, const double light_rgb_scale[3], bool overcast)
{
    rs_synth_env_default(zenith_rgb, horizon_rgb, ground_rgb, overcast);
    const double *ls = light_rgb_scale;
    const bool matched = ls && (ls[0] > 0 || ls[1] > 0 || ls[2] > 0);
    for (int c = 0; c < 3 && matched; c++) zenith_rgb[c] *= ls[c], horizon_rgb[c] *= ls[c], ground_rgb[c] *= ls[c];
    if (!env) return;
    for (int c = 0; c < 3; c++) {
        if (env->Nground_px >= RS_SYNTH_ENV_MIN_PX) ground_rgb[c] = env->ground_rgb[c];
        if (env->Nhorizon_px >= RS_SYNTH_ENV_MIN_PX) horizon_rgb[c] = env->horizon_rgb[c];
        if (env->Nzenith_px >= RS_SYNTH_ENV_MIN_PX)
            zenith_rgb[c] = env->zenith_rgb[c];
        else if (env->Nsky_px >= RS_SYNTH_ENV_MIN_PX)
            zenith_rgb[c] = env->sky_rgb[c];
    }
}

void rs_synth_light_match(double scale_rgb[3], const rs_synth_light_estimate *est, bool sun, double sun_elevation_deg)
{
    static const double sun_rgb[3] = {1.0, 0.97, 0.92}; // the scene's sun colour (rs_synth_scene.c)
    const double s = sun && sun_elevation_deg > 0 ? sin(sun_elevation_deg * RS_RAD_PER_DEG) : 0;
    const double sky = s > 0 ? RS_SYNTH_SKY_CLEAR : RS_SYNTH_SKY_OVERCAST;
    for (int c = 0; c < 3; c++) scale_rgb[c] = est->irradiance_rgb[c] / (s * sun_rgb[c] + sky);
}

// ---- the sun's direction from the shadows of poles ----

enum { SH_NAZ = 360, SH_NT = 250 }; // azimuth steps of 1 degree; 0.1 m steps out to 25 m
#define SH_DT   0.1
#define SH_DARK 0.25 // a sun shadow removes the sun's share, 0.5..0.75 of the light above 20 degrees

// Linear luminance at pixel (x, y), bilinear; NaN outside the image.
static double luminance(const rs_image *img, double x, double y)
{
    if (!(x >= 0 && y >= 0 && x <= img->width - 1.001 && y <= img->height - 1.001)) return NAN;
    const int x0 = (int)x, y0 = (int)y;
    const double fx = x - x0, fy = y - y0;
    double v = 0;
    for (int k = 0; k < 4; k++) {
        const int xi = x0 + (k & 1), yi = y0 + (k >> 1);
        const double w = ((k & 1) ? fx : 1 - fx) * ((k >> 1) ? fy : 1 - fy);
        const float *p = img->data + ((size_t)yi * img->width + xi) * (size_t)img->channels;
        v += w * (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]);
    }
    return v;
}

// Distance from q to the segment a-b, pixels.
static double seg_dist(const double q[2], const double a[2], const double b[2])
{
    const double dx = b[0] - a[0], dy = b[1] - a[1], L2 = dx * dx + dy * dy;
    double t = L2 > 0 ? ((q[0] - a[0]) * dx + (q[1] - a[1]) * dy) / L2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return hypot(q[0] - a[0] - t * dx, q[1] - a[1] - t * dy);
}

// The luminance of the ground point (e, n) seen by cam (max_tan: rs_camera_max_tan(cam), computed
// once: this runs a million times); NaN when not in view or within pole_r_px of the pole's image
// (pole_q: base and top pixels).
static double ground_lum(const rs_image *img, const rs_camera *cam, double max_tan, const rs_site *site, double e,
                         double n, const double pole_q[2][2], double pole_r_px)
{
    double p[3] = {e, n, rs_synth_ground_up_m(site->ground_normal_enu, site->ground_offset_m, e, n)}, q[2];
    if (!rs_camera_project_visible(q, cam, max_tan, p) || !isfinite(q[0] + q[1])) return NAN;
    if (seg_dist(q, pole_q[0], pole_q[1]) < pole_r_px) return NAN;
    return luminance(img, q[0], q[1]);
}

rs_status rs_synth_sun_from_shadows(rs_synth_sun_estimate *out, const rs_image *img, const rs_camera *cam,
                                    const rs_site *site, rs_err *err)
{
    *out = (rs_synth_sun_estimate){.azimuth_deg = NAN, .elevation_deg = NAN};
    if (img->width != cam->width || img->height != cam->height || img->channels < 3)
        return rs_err_set(err, RS_ERR_INVALID, "background: %dx%dx%d, the camera is %dx%d (RGB)", img->width,
                          img->height, img->channels, cam->width, cam->height);
    int Np = 0;
    for (int i = 0; i < site->Nlandmarks; i++) Np += site->landmarks[i].shape == RS_SITE_POLE;
    if (!Np) return rs_err_set(err, RS_ERR_NOT_FOUND, "%s: no pole among the landmarks: no shadow to read", site->dir);
    // per pole: D(az, t) and its validity, as prefix sums over t
    double *S = malloc(sizeof(double) * (size_t)Np * SH_NAZ * (SH_NT + 1));
    int *C = malloc(sizeof(int) * (size_t)Np * SH_NAZ * (SH_NT + 1));
    double *h = malloc(sizeof(double) * (size_t)Np);
    if (!S || !C || !h) {
        free(S), free(C), free(h);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    const double max_tan = rs_camera_max_tan(cam);
    int np = 0;
    for (int i = 0; i < site->Nlandmarks; i++) {
        const rs_site_landmark *L = &site->landmarks[i];
        const double *b = L->vertices_enu_m;
        if (L->shape != RS_SITE_POLE || !b || !isfinite(b[0] + b[1] + b[2]) || !(L->pole_height_m > 0.5)) continue;
        double ends[12] = {b[0],       b[1], b[2], b[0], b[1],       b[2] + L->pole_height_m,
                           b[0] + 0.3, b[1], b[2], b[0], b[1] + 0.3, b[2]},
               pq[4][2];
        if (rs_camera_project(&pq[0][0], cam, ends, 4) != 4) continue;
        // the pole's image and 0.3 m round it at its base (a pole up to 0.3 m thick), at least 4 px
        const double r_px = fmax(4.0, fmax(hypot(pq[2][0] - pq[0][0], pq[2][1] - pq[0][1]),
                                           hypot(pq[3][0] - pq[0][0], pq[3][1] - pq[0][1])));
        double *s = S + (size_t)np * SH_NAZ * (SH_NT + 1);
        int *c = C + (size_t)np * SH_NAZ * (SH_NT + 1), seen = 0;
        for (int a = 0; a < SH_NAZ; a++) {
            const double az = a * RS_RAD_PER_DEG; // the sun's azimuth; the shadow runs the other way
            const double de = -sin(az), dn = -cos(az);
            s[a * (SH_NT + 1)] = 0, c[a * (SH_NT + 1)] = 0;
            for (int k = 0; k < SH_NT; k++) {
                const double t = (k + 0.5) * SH_DT, e = b[0] + t * de, n = b[1] + t * dn;
                const double on = ground_lum(img, cam, max_tan, site, e, n, pq, r_px);
                const double l1 = ground_lum(img, cam, max_tan, site, e - 0.6 * dn, n + 0.6 * de, pq, r_px);
                const double l2 = ground_lum(img, cam, max_tan, site, e + 0.6 * dn, n - 0.6 * de, pq, r_px);
                // darker than both sides: the lesser side (an edge between road and sidewalk is
                // no shadow); one side when the other is not in view
                double side = isfinite(l1) && isfinite(l2) ? fmin(l1, l2) : isfinite(l1) ? l1 : l2;
                const bool ok = isfinite(on) && isfinite(side) && side > 1e-4;
                // shadow-like: at least SH_DARK darker than the lesser side
                const double D = ok ? 1.0 - on / side : 0;
                s[a * (SH_NT + 1) + k + 1] = s[a * (SH_NT + 1) + k] + (D >= SH_DARK);
                c[a * (SH_NT + 1) + k + 1] = c[a * (SH_NT + 1) + k] + ok;
                seen += ok;
            }
        }
        if (seen < SH_NAZ * 10) continue; // its surroundings are hardly in view
        h[np++] = L->pole_height_m;
    }
    double best = -INFINITY;
    for (int a = 0; a < SH_NAZ; a++)
        for (int el = 1; el <= 85; el++) {
            double sum = 0;
            int used = 0;
            for (int p = 0; p < np; p++) {
                const double len = h[p] / tan(el * RS_RAD_PER_DEG);
                if (len > SH_NT * SH_DT - 1.5) continue; // the shadow runs out of the window
                const int k0 = 5, k1 = (int)lround(len / SH_DT), k2 = (int)lround((len + 1.5) / SH_DT);
                if (k1 < 25) continue; // shadows shorter than 2.5 m are not read
                const double *s = S + ((size_t)p * SH_NAZ + a) * (SH_NT + 1);
                const int *c = C + ((size_t)p * SH_NAZ + a) * (SH_NT + 1);
                const int n_in = c[k1] - c[k0], n_out = c[k2] - c[k1];
                if (n_in < (k1 - k0) / 2 || n_out < (k2 - k1) / 2) continue;
                sum += (s[k1] - s[k0]) / n_in - (s[k2] - s[k1]) / n_out;
                used++;
            }
            // the mean over the poles whose shadow (and the 1.5 m beyond) is in view at this
            // candidate, at least two of them when two or more are seen
            if (used >= (np < 2 ? np : 2) && used && sum / used > best) {
                best = sum / used;
                out->azimuth_deg = a, out->elevation_deg = el, out->contrast = best, out->Npoles = used;
            }
        }
    free(S), free(C), free(h);
    if (!isfinite(best))
        return rs_err_set(err, RS_ERR_NOT_FOUND, "no pole's shadow region is in the camera's view (%d poles)", Np);
    if (best < 0.55)
        return rs_err_set(err, RS_ERR_DEGENERATE, "no sun shadow of the poles: best score %.3f (overcast?)", best);
    return RS_OK;
}

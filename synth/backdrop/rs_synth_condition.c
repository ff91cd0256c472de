// rs_synth_condition.c -- a background's condition from its tags or its image, and the ground
// terms of the vehicles in it (rs_synth_condition.h, docs/conditions.md).
#include "synth/backdrop/rs_synth_condition.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_stats.h"
#include "synth/backdrop/rs_synth_sun.h"

const char *rs_synth_condition_time_name(rs_synth_time_of_day t)
{
    return t == RS_SYNTH_TOD_NIGHT ? "night" : t == RS_SYNTH_TOD_DUSK ? "dusk" : "day";
}

const char *rs_synth_condition_surface_name(rs_synth_surface s)
{
    return s == RS_SYNTH_SURFACE_SNOW ? "snow" : s == RS_SYNTH_SURFACE_WET ? "wet" : "dry";
}

void rs_synth_condition_label(char *buf, int size, const rs_synth_condition *c)
{
    snprintf(buf, (size_t)size, "%s-%s", rs_synth_condition_time_name(c->time_of_day),
             rs_synth_condition_surface_name(c->surface));
}

rs_status rs_synth_condition_parse(rs_synth_condition *c, const char *label, rs_err *err)
{
    memset(c, 0, sizeof(*c));
    for (int t = 0; t < 3; t++)
        for (int s = 0; s < 3; s++) {
            const rs_synth_condition x = {.time_of_day = (rs_synth_time_of_day)t, .surface = (rs_synth_surface)s};
            char buf[16];
            rs_synth_condition_label(buf, sizeof(buf), &x);
            if (strcmp(buf, label) != 0) continue;
            *c = x;
            c->overcast = t != 0 || s != 0;
            return RS_OK;
        }
    return rs_err_set(err, RS_ERR_USAGE,
                      "condition '%s': expected TIME-SURFACE, TIME day, dusk or night, SURFACE dry, "
                      "wet or snow (e.g. night-wet)",
                      label);
}

rs_status rs_synth_condition_from_tags(rs_synth_condition *c, bool *known, const rs_site_background *bg, double lat_deg,
                                       double lon_deg, rs_err *err)
{
    memset(c, 0, sizeof(*c));
    *known = false;
    const char *cond = rs_site_background_tag(bg, "conditions");
    const char *time_iso = rs_site_background_tag(bg, "time");
    const char *surface = rs_site_background_tag(bg, "surface");
    const char *where = bg->name ? bg->name : bg->file ? bg->file : "background";
    if (time_iso) {
        double t_s, az, el;
        rs_status st = rs_synth_parse_iso8601(&t_s, time_iso, "time", err);
        if (st) return rs_err_set(err, RS_ERR_PARSE, "%s: tag time: '%s' is not an ISO 8601 time", where, time_iso);
        rs_synth_sun_position(&az, &el, lat_deg, lon_deg, t_s);
        c->time_of_day = el < RS_SYNTH_DUSK_LOW_DEG     ? RS_SYNTH_TOD_NIGHT
                         : el <= RS_SYNTH_DUSK_HIGH_DEG ? RS_SYNTH_TOD_DUSK
                                                        : RS_SYNTH_TOD_DAY;
        c->overcast = el <= 0;
        *known = true;
    }
    if (cond) {
        *known = true;
        c->overcast = c->overcast || strcmp(cond, "sunny") != 0;
        if (!strcmp(cond, "night"))
            c->time_of_day = RS_SYNTH_TOD_NIGHT;
        else if (!strcmp(cond, "dusk"))
            c->time_of_day = RS_SYNTH_TOD_DUSK;
        else if (!strcmp(cond, "rain"))
            c->surface = RS_SYNTH_SURFACE_WET;
        else if (!strcmp(cond, "snow"))
            c->surface = RS_SYNTH_SURFACE_SNOW;
    }
    if (surface) {
        *known = true;
        if (!strcmp(surface, "dry"))
            c->surface = RS_SYNTH_SURFACE_DRY;
        else if (!strcmp(surface, "wet"))
            c->surface = RS_SYNTH_SURFACE_WET;
        else if (!strcmp(surface, "snow"))
            c->surface = RS_SYNTH_SURFACE_SNOW;
        else
            return rs_err_set(err, RS_ERR_PARSE, "%s: tag surface: '%s' is not one of dry, wet, snow", where, surface);
    }
    if (c->time_of_day != RS_SYNTH_TOD_DAY) c->overcast = true;
    return RS_OK;
}

// Classifier thresholds (rs_synth_condition.h), linear luminance.
#define NIGHT_GROUND_LUM 0.012
#define NIGHT_SKY_LUM    0.05
#define DUSK_GROUND_LUM  0.035
#define SNOW_GROUND_LUM  0.25
#define SNOW_GROUND_SAT  0.10

rs_status rs_synth_condition_estimate(rs_synth_condition *c, const rs_image *img, rs_err *err)
{
    memset(c, 0, sizeof(*c));
    if (!img->data || img->width < 1 || img->height < 4 || img->channels < 3)
        return rs_err_set(err, RS_ERR_INVALID, "condition estimate: not an RGB image");
    const int W = img->width, H = img->height, ch = img->channels;
    const int g0 = H - (int)(0.4 * H), s1 = (int)ceil(0.15 * H);
    // every other pixel of every other row: 1/4 of the pixels, plenty for medians
    const size_t cap = (size_t)((W + 1) / 2) * (size_t)((H + 1) / 2) + 4;
    double *gl = malloc(cap * sizeof(double)), *gs = malloc(cap * sizeof(double)), *sl = malloc(cap * sizeof(double));
    if (!gl || !gs || !sl) {
        free(gl), free(gs), free(sl);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    int ng = 0, ns = 0;
    for (int v = 0; v < H; v += 2)
        for (int u = 0; u < W; u += 2) {
            const float *p = &img->data[((size_t)v * W + u) * ch];
            const double lum = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
            if (v >= g0) {
                const double mx = fmax(p[0], fmax(p[1], p[2])), mn = fmin(p[0], fmin(p[1], p[2]));
                gl[ng] = lum;
                gs[ng++] = mx > 1e-6 ? (mx - mn) / mx : 0;
            } else if (v < s1)
                sl[ns++] = lum;
        }
    c->ground_lum = ng ? rs_stats_median(gl, ng) : 0;
    c->ground_sat = ng ? rs_stats_median(gs, ng) : 0;
    c->sky_lum = ns ? rs_stats_median(sl, ns) : 0;
    free(gl), free(gs), free(sl);
    c->estimated = true;
    if (c->ground_lum < NIGHT_GROUND_LUM && c->sky_lum < NIGHT_SKY_LUM)
        c->time_of_day = RS_SYNTH_TOD_NIGHT;
    else if (c->ground_lum < DUSK_GROUND_LUM)
        c->time_of_day = RS_SYNTH_TOD_DUSK;
    else if (c->ground_lum > SNOW_GROUND_LUM && c->ground_sat < SNOW_GROUND_SAT)
        c->surface = RS_SYNTH_SURFACE_SNOW;
    // no sun shadow is looked for here (rs_synth_sun_from_shadows does): sunny unless dim or snowy
    c->overcast = c->time_of_day != RS_SYNTH_TOD_DAY || c->surface == RS_SYNTH_SURFACE_SNOW;
    return RS_OK;
}

void rs_synth_condition_add_headlights(rs_image *bg_lin, const float *irradiance, const uint16_t *ids,
                                       const double road_albedo_rgb[3])
{
    const size_t n = (size_t)bg_lin->width * (size_t)bg_lin->height;
    for (size_t i = 0; i < n; i++) {
        if ((ids && ids[i]) || !(irradiance[i] > 0)) continue;
        for (int k = 0; k < 3; k++) bg_lin->data[3 * i + k] += (float)(irradiance[i] * road_albedo_rgb[k]);
    }
}

void rs_synth_condition_add_wet(rs_image *bg_lin, const rs_image *mirror, const uint16_t *ids, const double sky_rgb[3])
{
    const size_t n = (size_t)bg_lin->width * (size_t)bg_lin->height;
    for (size_t i = 0; i < n; i++) {
        const float *m = &mirror->data[4 * i];
        if ((ids && ids[i]) || !(m[3] > 0)) continue;
        for (int k = 0; k < 3; k++) {
            float *b = &bg_lin->data[3 * i + k];
            const double base = sky_rgb ? fmax(0, *b - m[3] * sky_rgb[k]) : (1 - m[3]) * *b;
            *b = (float)(base + m[k]);
        }
    }
}

double rs_synth_fresnel_water(double cos_i)
{
    const double n = 1.33;
    const double ci = cos_i < 0 ? 0 : cos_i > 1 ? 1 : cos_i;
    const double si2 = 1 - ci * ci, st2 = si2 / (n * n), ct = sqrt(1 - st2);
    const double rs = (ci - n * ct) / (ci + n * ct), rp = (n * ci - ct) / (n * ci + ct);
    return 0.5 * (rs * rs + rp * rp);
}

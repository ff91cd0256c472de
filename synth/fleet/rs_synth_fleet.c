// rs_synth_fleet.c -- the fleet's classes: names, dimension ranges, the class mix (default,
// parsing, drawing), the paint colours, and resolving what a vehicle left to chance from its
// variant. docs/fleet.md gives the sources. The meshes: rs_synth_fleet_build.c (procedural),
// rs_synth_fleet_model.c (user models), rs_synth_fleet_pov.c (POV-Ray output); what they share:
// synth/fleet/internal/rs_synth_fleet_internal.h.
#include "synth/fleet/rs_synth_fleet.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_color.h"
#include "core/rs_rng.h"
#include "synth/fleet/internal/rs_synth_fleet_internal.h"

// ---------------------------------------------------------------- classes and ranges

static const char *const class_names[RS_SYNTH_NCLASSES] = {
    "sedan", "hatchback", "suv", "pickup", "van", "bus", "box_truck", "articulated_truck", "motorcycle", "bicycle"};

// Length, width, height: [min, max] and the normal's mean and standard deviation, metres
// (docs/fleet.md gives the sources: Inovev's 2022 European average car, the Euro car segments'
// lengths, SUMO's vehicle-type defaults, the EU limits for buses and trucks; the spreads are our
// estimates). Two-wheelers' boxes hold the rider (height = the rider's head).
static const rs_synth_class_range class_ranges[RS_SYNTH_NCLASSES] = {
    {{4.30, 5.00}, {1.72, 1.88}, {1.38, 1.50}, {4.60, 1.81, 1.45}, {0.20, 0.04, 0.03}},   // sedan
    {{3.60, 4.40}, {1.62, 1.80}, {1.42, 1.56}, {4.05, 1.76, 1.49}, {0.22, 0.04, 0.03}},   // hatchback
    {{4.20, 5.10}, {1.78, 2.00}, {1.60, 1.85}, {4.45, 1.85, 1.66}, {0.22, 0.05, 0.06}},   // SUV
    {{5.00, 5.90}, {1.85, 2.05}, {1.75, 1.95}, {5.35, 1.90, 1.83}, {0.25, 0.05, 0.05}},   // pickup
    {{4.80, 6.00}, {1.90, 2.05}, {1.95, 2.60}, {5.30, 1.99, 2.20}, {0.35, 0.03, 0.20}},   // van
    {{10.50, 13.50}, {2.50, 2.55}, {3.00, 3.40}, {12.0, 2.53, 3.15}, {0.60, 0.02, 0.10}}, // bus
    {{6.50, 9.50}, {2.30, 2.55}, {3.00, 3.80}, {8.00, 2.45, 3.40}, {0.80, 0.06, 0.20}},   // box truck
    {{15.50, 16.50}, {2.50, 2.55}, {3.80, 4.00}, {16.3, 2.53, 3.95}, {0.20, 0.02, 0.05}}, // articulated truck
    {{1.80, 2.40}, {0.65, 0.95}, {1.30, 1.60}, {2.10, 0.80, 1.45}, {0.12, 0.06, 0.06}},   // motorcycle + rider
    {{1.55, 1.90}, {0.50, 0.70}, {1.55, 1.90}, {1.72, 0.60, 1.72}, {0.06, 0.04, 0.06}},   // bicycle + rider
};

const char *rs_synth_class_name(rs_synth_class cls)
{
    if (cls == RS_SYNTH_USER_MODEL) return "model";
    if ((int)cls < 0 || cls >= RS_SYNTH_NCLASSES) return NULL;
    return class_names[cls];
}

rs_status rs_synth_class_from_name(rs_synth_class *cls, const char *name, rs_err *err)
{
    for (int i = 0; i < RS_SYNTH_NCLASSES; i++)
        if (name && strcmp(name, class_names[i]) == 0) {
            *cls = (rs_synth_class)i;
            return RS_OK;
        }
    return rs_err_set(err, RS_ERR_NOT_FOUND,
                      "class: unknown vehicle class (valid: sedan, hatchback, suv, pickup, van, "
                      "bus, box_truck, articulated_truck, motorcycle, bicycle)");
}

rs_status rs_synth_class_range_get(rs_synth_class_range *out, rs_synth_class cls, rs_err *err)
{
    if ((int)cls < 0 || cls >= RS_SYNTH_NCLASSES)
        return rs_err_set(err, RS_ERR_INVALID, "class: %d is not a procedural class", (int)cls);
    *out = class_ranges[cls];
    return RS_OK;
}

// ---------------------------------------------------------------- deterministic draws

rs_rng rs_synth_fleet_stream(uint64_t variant, int which)
{
    rs_rng rng;
    rs_rng_seed(&rng, variant * 0x9E3779B97F4A7C15ull + (uint64_t)which * 0xD1B54A32D192ED03ull);
    return rng;
}

// Normal(mean, sd) truncated to range: redrawn until inside (the ranges hold >= 68 % of each
// normal, so 64 draws fail with probability < 1e-30; then the mean, clamped).
static double truncated_normal(rs_rng *rng, double mean, double sd, const double range[2])
{
    for (int i = 0; i < 64; i++) {
        double x = mean + sd * rs_rng_normal(rng);
        if (x >= range[0] && x <= range[1]) return x;
    }
    return fmin(fmax(mean, range[0]), range[1]);
}

// Paint colours and their shares. Shares from Axalta's 2022 Global Automotive Color Popularity
// Report (press release of 15 Dec 2022: white 34 %, black 21 %, grey 19 %, blue 8 %, red 5 %,
// green 1 %; white, black, grey and silver together 82 %, hence silver 8 %); the remaining 4 %
// split between beige/brown (3 %) and yellow/orange (1 %) is our estimate, and so are the RGB
// values (sRGB, converted to linear) and their jitter.
typedef struct {
    double share;
    double srgb[3]; // [0,1]
    double jitter;  // +- per channel, sRGB
} paint;
static const paint paints[] = {
    {0.34, {0.93, 0.93, 0.92}, 0.03}, // white
    {0.21, {0.05, 0.05, 0.06}, 0.02}, // black
    {0.19, {0.42, 0.43, 0.45}, 0.08}, // grey
    {0.08, {0.72, 0.73, 0.75}, 0.04}, // silver
    {0.08, {0.10, 0.22, 0.50}, 0.06}, // blue
    {0.05, {0.62, 0.06, 0.07}, 0.06}, // red
    {0.03, {0.55, 0.45, 0.33}, 0.06}, // beige / brown
    {0.01, {0.12, 0.32, 0.18}, 0.05}, // green
    {0.01, {0.85, 0.70, 0.10}, 0.06}, // yellow / orange
};

static void draw_paint(double rgb[3], uint64_t variant)
{
    rs_rng rng = rs_synth_fleet_stream(variant, RS_SYNTH_FLEET_STREAM_COLOUR);
    double u = rs_rng_uniform(&rng), acc = 0;
    size_t n = sizeof paints / sizeof paints[0], k = n - 1;
    for (size_t i = 0; i < n; i++) {
        acc += paints[i].share;
        if (u < acc) {
            k = i;
            break;
        }
    }
    double d = (2 * rs_rng_uniform(&rng) - 1) * paints[k].jitter; // brightness
    for (int c = 0; c < 3; c++) {
        double e = (2 * rs_rng_uniform(&rng) - 1) * paints[k].jitter * 0.3; // hue
        rgb[c] = rs_color_srgb_decode_exact(paints[k].srgb[c] + d + e);
    }
}

// ---------------------------------------------------------------- class mix

void rs_synth_class_mix_default(rs_synth_class_mix *mix)
{
    // The motor vehicles' assumed mix (docs/traffic.md, "Class mix") scaled by 0.975, and the
    // two-wheelers' shares of urban road traffic in Great Britain (DfT road traffic estimates,
    // docs/traffic.md): motorcycles 0.8 %, pedal cycles 1.7 %. The weights sum to 1.
    static const double motor[RS_SYNTH_MOTORCYCLE] = {0.24, 0.22, 0.30, 0.03, 0.10, 0.02, 0.06, 0.03};
    for (int c = 0; c < RS_SYNTH_MOTORCYCLE; c++) mix->weight[c] = 0.975 * motor[c];
    mix->weight[RS_SYNTH_MOTORCYCLE] = 0.008;
    mix->weight[RS_SYNTH_BICYCLE] = 0.017;
}

rs_status rs_synth_class_mix_parse(rs_synth_class_mix *mix, const char *text, rs_err *err)
{
    rs_synth_class_mix m = {{0}};
    double total = 0;
    const char *p = text ? text : "";
    for (int item = 1;; item++) {
        const char *end = strchr(p, ',');
        size_t n = end ? (size_t)(end - p) : strlen(p);
        const char *eq = memchr(p, '=', n);
        if (!eq) return rs_err_set(err, RS_ERR_USAGE, "--mix: item %d '%.*s': expected CLASS=WEIGHT", item, (int)n, p);
        char name[32];
        rs_synth_class c = RS_SYNTH_SEDAN;
        size_t nl = (size_t)(eq - p);
        if (nl >= sizeof name || (memcpy(name, p, nl), name[nl] = '\0', rs_synth_class_from_name(&c, name, NULL)))
            return rs_err_set(err, RS_ERR_USAGE,
                              "--mix: item %d: unknown class '%.*s' (sedan, hatchback, suv, pickup, van, bus, "
                              "box_truck, articulated_truck, motorcycle, bicycle)",
                              item, (int)nl, p);
        char num[64];
        size_t nn = n - (size_t)(eq + 1 - p);
        if (nn == 0 || nn >= sizeof num)
            return rs_err_set(err, RS_ERR_USAGE, "--mix: item %d: no weight for '%s'", item, name);
        memcpy(num, eq + 1, nn);
        num[nn] = '\0';
        char *stop;
        errno = 0;
        double w = strtod(num, &stop);
        if (*stop || errno || !isfinite(w) || w < 0)
            return rs_err_set(err, RS_ERR_USAGE, "--mix: item %d: weight '%s' of '%s' is not a number >= 0", item, num,
                              name);
        m.weight[c] = w;
        total += w;
        if (!end) break;
        p = end + 1;
    }
    if (!(total > 0)) return rs_err_set(err, RS_ERR_USAGE, "--mix: all weights are 0");
    *mix = m;
    return RS_OK;
}

rs_synth_class rs_synth_class_mix_draw(const rs_synth_class_mix *mix, double u)
{
    double total = 0;
    for (int k = 0; k < RS_SYNTH_NCLASSES; k++) total += mix->weight[k];
    u *= total;
    int last = 0;
    for (int k = 0; k < RS_SYNTH_NCLASSES; k++) {
        if (!(mix->weight[k] > 0)) continue;
        last = k;
        if (u < mix->weight[k]) return (rs_synth_class)k;
        u -= mix->weight[k];
    }
    return (rs_synth_class)last;
}

rs_status rs_synth_fleet_resolve(rs_synth_vehicle *out, const rs_synth_vehicle *in, rs_err *err)
{
    rs_synth_vehicle v = *in;
    double *dims[3] = {&v.length_m, &v.width_m, &v.height_m};
    const char *names[3] = {"length", "width", "height"};
    for (int i = 0; i < 3; i++)
        if (!isfinite(*dims[i]) || *dims[i] < 0 || (*dims[i] > 0 && (*dims[i] < 0.5 || *dims[i] > 30)))
            return rs_err_set(err, RS_ERR_INVALID, "%s: %g m is not 0 (drawn) or in [0.5, 30] m", names[i], *dims[i]);
    if (v.cls != RS_SYNTH_USER_MODEL) {
        if ((int)v.cls < 0 || v.cls >= RS_SYNTH_NCLASSES)
            return rs_err_set(err, RS_ERR_INVALID, "class: %d is not a vehicle class", (int)v.cls);
        const rs_synth_class_range *r = &class_ranges[v.cls];
        const double *ranges[3] = {r->length_m, r->width_m, r->height_m};
        for (int i = 0; i < 3; i++)
            if (*dims[i] == 0) {
                rs_rng rng = rs_synth_fleet_stream(v.variant, RS_SYNTH_FLEET_STREAM_LENGTH + i);
                *dims[i] = truncated_normal(&rng, r->mean_m[i], r->sd_m[i], ranges[i]);
            }
    }
    if (!(v.rgb[0] >= 0)) draw_paint(v.rgb, v.variant);
    for (int c = 0; c < 3; c++)
        if (!(v.rgb[c] >= 0 && v.rgb[c] <= 1))
            return rs_err_set(err, RS_ERR_INVALID, "colour: channel %d = %g is not in [0, 1]", c, v.rgb[c]);
    *out = v;
    return RS_OK;
}

rs_status rs_synth_fleet_random(rs_synth_vehicle *out, uint64_t seed, rs_err *err)
{
    rs_rng rng = rs_synth_fleet_stream(seed, RS_SYNTH_FLEET_STREAM_CLASS);
    rs_synth_class_mix mix;
    rs_synth_class_mix_default(&mix);
    rs_synth_vehicle v = {0};
    v.cls = rs_synth_class_mix_draw(&mix, rs_rng_uniform(&rng));
    v.rgb[0] = v.rgb[1] = v.rgb[2] = -1;
    v.variant = seed;
    return rs_synth_fleet_resolve(out, &v, err);
}

// The paint family of a linear RGB colour, for the metallic share: 0 white, 1 black, 2 grey or
// silver, 3 chromatic.
static int paint_family(const double rgb[3])
{
    double mx = fmax(rgb[0], fmax(rgb[1], rgb[2])), mn = fmin(rgb[0], fmin(rgb[1], rgb[2]));
    if (mx - mn > 0.25 * mx + 0.01) return 3;
    if (mn > 0.6) return 0;
    if (mx < 0.01) return 1;
    return 2;
}

void rs_synth_fleet_look(rs_synth_look *look, const rs_synth_vehicle *v)
{
    rs_rng rng = rs_synth_fleet_stream(v->variant, RS_SYNTH_FLEET_STREAM_LOOK);
    // Shares of metallic finishes per family (our estimates: solid white and metallic greys
    // are the common finishes; silver is metallic by definition).
    static const double metallic_share[4] = {0.25, 0.45, 0.85, 0.55};
    for (int c = 0; c < 3; c++) look->paint_rgb[c] = v->rgb[c];
    look->metallic = rs_rng_uniform(&rng) < metallic_share[paint_family(v->rgb)] ? 0.5 + 0.5 * rs_rng_uniform(&rng) : 0;
    double u = rs_rng_uniform(&rng); // dirt: most vehicles nearly clean, a fifth visibly dirty
    look->dirt = u < 0.8 ? 0.25 * u / 0.8 : 0.25 + 0.75 * (u - 0.8) / 0.2;
}

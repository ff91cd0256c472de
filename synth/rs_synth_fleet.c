// rs_synth_fleet.c -- procedural vehicles (lofted bodies, wheels, glazing, lights), class ranges
// and colours, POV-Ray mesh2 declarations. docs/fleet.md explains the shapes and the sources.
#include "synth/rs_synth_fleet.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_io.h"
#include "core/rs_rng.h"

// ---------------------------------------------------------------- classes and ranges

static const char *const class_names[RS_SYNTH_NCLASSES] = {
    "sedan", "hatchback", "suv", "pickup", "van", "bus", "box_truck", "articulated_truck"};

// Length, width, height ranges, metres (docs/fleet.md: estimates from manufacturers' data of
// common models and SUMO's vehicle-type defaults).
static const rs_synth_class_range class_ranges[RS_SYNTH_NCLASSES] = {
    {{4.30, 5.00}, {1.72, 1.88}, {1.38, 1.50}},   // sedan
    {{3.60, 4.40}, {1.62, 1.80}, {1.42, 1.56}},   // hatchback
    {{4.20, 5.10}, {1.78, 2.00}, {1.60, 1.85}},   // SUV
    {{5.00, 5.90}, {1.85, 2.05}, {1.75, 1.95}},   // pickup
    {{4.80, 6.00}, {1.90, 2.05}, {1.95, 2.60}},   // van
    {{10.50, 13.50}, {2.50, 2.55}, {3.00, 3.40}}, // bus
    {{6.50, 9.50}, {2.30, 2.55}, {3.00, 3.80}},   // box truck
    {{15.50, 16.50}, {2.50, 2.55}, {3.80, 4.00}}, // articulated truck (tractor + semi-trailer)
};

const char *rs_synth_class_name(rs_synth_class cls) {
    if (cls == RS_SYNTH_USER_MODEL) return "model";
    if ((int)cls < 0 || cls >= RS_SYNTH_NCLASSES) return NULL;
    return class_names[cls];
}

rs_status rs_synth_class_from_name(rs_synth_class *cls, const char *name, rs_err *err) {
    for (int i = 0; i < RS_SYNTH_NCLASSES; i++)
        if (name && strcmp(name, class_names[i]) == 0) {
            *cls = (rs_synth_class)i;
            return RS_OK;
        }
    return rs_err_set(err, RS_ERR_NOT_FOUND,
                      "class: unknown vehicle class (valid: sedan, hatchback, suv, pickup, van, "
                      "bus, box_truck, articulated_truck)");
}

rs_status rs_synth_class_range_get(rs_synth_class_range *out, rs_synth_class cls, rs_err *err) {
    if ((int)cls < 0 || cls >= RS_SYNTH_NCLASSES)
        return rs_err_set(err, RS_ERR_INVALID, "class: %d is not a procedural class", (int)cls);
    *out = class_ranges[cls];
    return RS_OK;
}

// ---------------------------------------------------------------- deterministic draws

// Independent streams per drawn quantity, so that giving one value never changes the others.
enum { STREAM_LENGTH = 1, STREAM_WIDTH, STREAM_HEIGHT, STREAM_COLOUR, STREAM_SHAPE, STREAM_CLASS };

static rs_rng stream(uint64_t variant, int which) {
    rs_rng rng;
    rs_rng_seed(&rng, variant * 0x9E3779B97F4A7C15ull + (uint64_t)which * 0xD1B54A32D192ED03ull);
    return rng;
}

static double uniform_in(rs_rng *rng, const double range[2]) {
    return range[0] + (range[1] - range[0]) * rs_rng_uniform(rng);
}

// Paint colours and their shares. Shares from Axalta's 2022 Global Automotive Color Popularity
// Report (press release of 15 Dec 2022: white 34 %, black 21 %, grey 19 %, blue 8 %, red 5 %,
// green 1 %; white, black, grey and silver together 82 %, hence silver 8 %); the remaining 4 %
// split between beige/brown (3 %) and yellow/orange (1 %) is our estimate, and so are the RGB
// values (sRGB, converted to linear) and their jitter.
typedef struct {
    double share;
    double srgb[3];  // [0,1]
    double jitter;   // +- per channel, sRGB
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

static double srgb_to_linear(double c) {
    c = c < 0 ? 0 : c > 1 ? 1 : c;
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

static void draw_paint(double rgb[3], uint64_t variant) {
    rs_rng rng = stream(variant, STREAM_COLOUR);
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
        rgb[c] = srgb_to_linear(paints[k].srgb[c] + d + e);
    }
}

// Traffic mix of rs_synth_fleet_random (our estimate for urban arterial roads).
static const double class_mix[RS_SYNTH_NCLASSES] = {0.30, 0.20, 0.22, 0.06, 0.08, 0.03, 0.06, 0.05};

rs_status rs_synth_fleet_resolve(rs_synth_vehicle *out, const rs_synth_vehicle *in, rs_err *err) {
    rs_synth_vehicle v = *in;
    double *dims[3] = {&v.length_m, &v.width_m, &v.height_m};
    const char *names[3] = {"length", "width", "height"};
    for (int i = 0; i < 3; i++)
        if (!isfinite(*dims[i]) || *dims[i] < 0 || (*dims[i] > 0 && (*dims[i] < 0.5 || *dims[i] > 30)))
            return rs_err_set(err, RS_ERR_INVALID, "%s: %g m is not 0 (drawn) or in [0.5, 30] m",
                              names[i], *dims[i]);
    if (v.cls != RS_SYNTH_USER_MODEL) {
        if ((int)v.cls < 0 || v.cls >= RS_SYNTH_NCLASSES)
            return rs_err_set(err, RS_ERR_INVALID, "class: %d is not a vehicle class", (int)v.cls);
        const rs_synth_class_range *r = &class_ranges[v.cls];
        const double *ranges[3] = {r->length_m, r->width_m, r->height_m};
        for (int i = 0; i < 3; i++)
            if (*dims[i] == 0) {
                rs_rng rng = stream(v.variant, STREAM_LENGTH + i);
                *dims[i] = uniform_in(&rng, ranges[i]);
            }
    }
    if (!(v.rgb[0] >= 0)) draw_paint(v.rgb, v.variant);
    for (int c = 0; c < 3; c++)
        if (!(v.rgb[c] >= 0 && v.rgb[c] <= 1))
            return rs_err_set(err, RS_ERR_INVALID, "colour: channel %d = %g is not in [0, 1]", c,
                              v.rgb[c]);
    *out = v;
    return RS_OK;
}

rs_status rs_synth_fleet_random(rs_synth_vehicle *out, uint64_t seed, rs_err *err) {
    rs_rng rng = stream(seed, STREAM_CLASS);
    double u = rs_rng_uniform(&rng), acc = 0;
    rs_synth_vehicle v = {0};
    v.cls = RS_SYNTH_NCLASSES - 1;
    for (int i = 0; i < RS_SYNTH_NCLASSES; i++) {
        acc += class_mix[i];
        if (u < acc) {
            v.cls = (rs_synth_class)i;
            break;
        }
    }
    v.rgb[0] = v.rgb[1] = v.rgb[2] = -1;
    v.variant = seed;
    return rs_synth_fleet_resolve(out, &v, err);
}

// ---------------------------------------------------------------- mesh building

typedef struct {
    rs_synth_mesh m;
    int cap_v, cap_t;
    int failed;
    int nseg, nwheel; // uniform stations along a body, sides of a wheel (level of detail)
} builder;

void rs_synth_mesh_free(rs_synth_mesh *mesh) {
    if (!mesh) return;
    free(mesh->v);
    free(mesh->vn);
    free(mesh->tri);
    free(mesh->part);
    memset(mesh, 0, sizeof *mesh);
}

void rs_synth_mesh_bounds(double lo[3], double hi[3], const rs_synth_mesh *mesh) {
    for (int k = 0; k < 3; k++) lo[k] = hi[k] = 0;
    for (int i = 0; i < mesh->Nv; i++)
        for (int k = 0; k < 3; k++) {
            double x = mesh->v[i][k];
            if (i == 0 || x < lo[k]) lo[k] = x;
            if (i == 0 || x > hi[k]) hi[k] = x;
        }
}

static int add_v(builder *b, double x, double y, double z) {
    if (b->failed) return 0;
    if (b->m.Nv == b->cap_v) {
        int cap = b->cap_v ? 2 * b->cap_v : 256;
        void *p = realloc(b->m.v, (size_t)cap * sizeof *b->m.v);
        if (!p) {
            b->failed = 1;
            return 0;
        }
        b->m.v = p;
        b->cap_v = cap;
    }
    b->m.v[b->m.Nv][0] = x;
    b->m.v[b->m.Nv][1] = y;
    b->m.v[b->m.Nv][2] = z;
    return b->m.Nv++;
}

static void add_t(builder *b, int i, int j, int k, int part) {
    if (b->failed) return;
    if (b->m.Ntri == b->cap_t) {
        int cap = b->cap_t ? 2 * b->cap_t : 512;
        void *p = realloc(b->m.tri, (size_t)cap * sizeof *b->m.tri);
        void *q = p ? realloc(b->m.part, (size_t)cap) : NULL;
        if (p) b->m.tri = p;
        if (!q) {
            b->failed = 1;
            return;
        }
        b->m.part = q;
        b->cap_t = cap;
    }
    b->m.tri[b->m.Ntri][0] = i;
    b->m.tri[b->m.Ntri][1] = j;
    b->m.tri[b->m.Ntri][2] = k;
    b->m.part[b->m.Ntri] = (uint8_t)part;
    b->m.Ntri++;
}

// Quad a b c d, counter-clockwise from outside (flip: the reverse).
static void add_q(builder *b, int a, int bb, int c, int d, int part, int flip) {
    if (flip) {
        add_t(b, a, c, bb, part);
        add_t(b, a, d, c, part);
    } else {
        add_t(b, a, bb, c, part);
        add_t(b, a, c, d, part);
    }
}

static void add_tf(builder *b, int a, int bb, int c, int part, int flip) {
    if (flip) add_t(b, a, c, bb, part);
    else add_t(b, a, bb, c, part);
}

// A side profile: the roof line z_top(t) / H at t = (x - x_rear) / (x_front - x_rear).
#define MAXPROF 10
typedef struct {
    int n;
    double t[MAXPROF], z[MAXPROF];
} profile;

static double profile_at(const profile *p, double t) {
    if (t <= p->t[0]) return p->z[0];
    for (int i = 1; i < p->n; i++)
        if (t <= p->t[i]) {
            double f = (t - p->t[i - 1]) / (p->t[i] - p->t[i - 1]);
            return p->z[i - 1] + f * (p->z[i] - p->z[i - 1]);
        }
    return p->z[p->n - 1];
}

// One lofted body: stations along x, each a 10-point convex section (y, z).
typedef struct {
    double x_rear, x_front;   // m
    double half_width;        // m, the widest section
    double height;            // m, top of the profile's 1.0
    double clearance;         // m, underside
    double belt;              // fraction of height: the greenhouse starts above it
    double tumble;            // roof-edge inset per metre above the belt
    double end_len, end_taper;// plan rounding: fraction of length, fraction of half width
    double glass_t[2];        // side glass only for t in this range
    profile prof;
} body_spec;

#define NSEC 10
#define NSEG 56
#define NSEG_COARSE 8 // level of detail for vehicles a few pixels tall (rs_synth_fleet_build_lod)

static void section(double y[NSEC], double z[NSEC], const body_spec *s, double t, int *greenhouse) {
    double H = s->height, ztop = H * profile_at(&s->prof, t);
    double zbelt = s->belt * H, zc = s->clearance;
    double zs = fmin(zbelt, ztop - 0.04 * H);
    double zlb = zc + 0.6 * (zs - zc), z1 = zc + 0.15 * (zs - zc);
    double a = fabs(t - 0.5) - (0.5 - s->end_len);
    double q = a > 0 ? a / s->end_len : 0;
    double wb = s->half_width * (1 - s->end_taper * q * q);
    double wt = ztop > zbelt ? wb - s->tumble * (ztop - zs) : wb - 0.03;
    double wbb = wb - 0.04;
    *greenhouse = ztop > zbelt + 0.02 * H;
    const double yy[NSEC] = {wbb, wb, wb, wb, wt, -wt, -wb, -wb, -wb, -wbb};
    const double zz[NSEC] = {zc, z1, zlb, zs, ztop, ztop, zs, zlb, z1, zc};
    memcpy(y, yy, sizeof yy);
    memcpy(z, zz, sizeof zz);
}

// A flat end cap of the section `idx` at the front (flip = 0, outward +x) or rear (flip = 1):
// bumper bands, a light band split into two lights and a grille, the upper band glass when it
// reaches above the belt line (windscreen of a bus, van or cab), else paint.
static void add_cap(builder *b, const int idx[NSEC], int greenhouse, int flip, int light_part) {
    const double *p2 = b->m.v[idx[2]], *p3 = b->m.v[idx[3]], *p6 = b->m.v[idx[6]],
                 *p7 = b->m.v[idx[7]];
    double f = 0.28, P[4][3];
    for (int k = 0; k < 3; k++) {
        P[0][k] = p2[k] + f * (p7[k] - p2[k]);       // a
        P[1][k] = p3[k] + f * (p6[k] - p3[k]);       // b
        P[2][k] = p2[k] + (1 - f) * (p7[k] - p2[k]); // c
        P[3][k] = p3[k] + (1 - f) * (p6[k] - p3[k]); // d
    }
    int a = add_v(b, P[0][0], P[0][1], P[0][2]), bb = add_v(b, P[1][0], P[1][1], P[1][2]);
    int c = add_v(b, P[2][0], P[2][1], P[2][2]), d = add_v(b, P[3][0], P[3][1], P[3][2]);
    add_q(b, idx[0], idx[1], idx[8], idx[9], RS_SYNTH_PART_TRIM, flip);
    add_tf(b, idx[1], idx[2], a, RS_SYNTH_PART_TRIM, flip); // bumper: polygon 1 2 a c 7 8
    add_tf(b, idx[1], a, c, RS_SYNTH_PART_TRIM, flip);
    add_tf(b, idx[1], c, idx[7], RS_SYNTH_PART_TRIM, flip);
    add_tf(b, idx[1], idx[7], idx[8], RS_SYNTH_PART_TRIM, flip);
    add_q(b, idx[2], idx[3], bb, a, light_part, flip);
    add_q(b, a, bb, d, c, RS_SYNTH_PART_TRIM, flip);
    add_q(b, c, d, idx[6], idx[7], light_part, flip);
    int top = greenhouse ? RS_SYNTH_PART_GLASS : RS_SYNTH_PART_PAINT;
    add_tf(b, idx[4], idx[5], idx[6], top, flip);
    add_tf(b, idx[4], idx[6], d, top, flip);
    add_tf(b, idx[4], d, bb, top, flip);
    add_tf(b, idx[4], bb, idx[3], top, flip);
}

static void add_body(builder *b, const body_spec *s) {
    double L = s->x_front - s->x_rear;
    // Stations: uniform, plus the profile's control points (so the roof line is exact).
    double ts[NSEG + 1 + MAXPROF];
    int n = 0;
    for (int i = 0; i <= b->nseg; i++) ts[n++] = (double)i / b->nseg;
    for (int i = 0; i < s->prof.n; i++) {
        int dup = 0;
        for (int j = 0; j < n; j++) dup |= fabs(ts[j] - s->prof.t[i]) < 1e-4;
        if (!dup) ts[n++] = s->prof.t[i];
    }
    for (int i = 1; i < n; i++) // insertion sort
        for (int j = i; j > 0 && ts[j] < ts[j - 1]; j--) {
            double tmp = ts[j];
            ts[j] = ts[j - 1];
            ts[j - 1] = tmp;
        }
    int prev[NSEC], cur[NSEC], prev_gh = 0, first[NSEC];
    double gh_lo = 2, gh_hi = -1; // greenhouse extent in t, for the pillars
    for (int i = 0; i < n; i++) {
        double y[NSEC], z[NSEC];
        int gh;
        section(y, z, s, ts[i], &gh);
        if (gh) {
            gh_lo = fmin(gh_lo, ts[i]);
            gh_hi = fmax(gh_hi, ts[i]);
        }
    }
    double pillar = 0.12 / L;
    for (int i = 0; i < n; i++) {
        double y[NSEC], z[NSEC];
        int gh;
        section(y, z, s, ts[i], &gh);
        double x = s->x_rear + ts[i] * L;
        if (i == n - 1) x = s->x_front; // exact
        for (int k = 0; k < NSEC; k++) cur[k] = add_v(b, x, y[k], z[k]);
        if (i == 0) memcpy(first, cur, sizeof cur);
        if (i > 0 && !b->failed) {
            double tm = 0.5 * (ts[i] + ts[i - 1]);
            int both = gh && prev_gh;
            double slope = fabs(b->m.v[cur[4]][2] - b->m.v[prev[4]][2]) / (L * (ts[i] - ts[i - 1]));
            int side_glass = both && tm > s->glass_t[0] && tm < s->glass_t[1] &&
                             tm > gh_lo + pillar && tm < gh_hi - pillar;
            int end = i == 1 ? -1 : i == n - 1 ? 1 : 0;
            for (int k = 0; k < NSEC; k++) {
                int k1 = (k + 1) % NSEC, part = RS_SYNTH_PART_PAINT;
                if (k == NSEC - 1) part = RS_SYNTH_PART_TRIM; // underside
                else if ((k == 0 || k == 8 || k == 1 || k == 7) && end) part = RS_SYNTH_PART_TRIM;
                else if ((k == 2 || k == 6) && end)
                    part = end > 0 ? RS_SYNTH_PART_HEADLIGHT : RS_SYNTH_PART_TAILLIGHT;
                else if ((k == 3 || k == 5) && side_glass) part = RS_SYNTH_PART_GLASS;
                else if (k == 4 && both && slope > 0.6) part = RS_SYNTH_PART_GLASS;
                add_q(b, prev[k], prev[k1], cur[k1], cur[k], part, 0);
            }
        }
        memcpy(prev, cur, sizeof cur);
        prev_gh = gh;
        if (i == n - 1) add_cap(b, cur, gh, 0, RS_SYNTH_PART_HEADLIGHT);
    }
    {
        double y[NSEC], z[NSEC];
        int gh;
        section(y, z, s, 0, &gh);
        add_cap(b, first, gh, 1, RS_SYNTH_PART_TAILLIGHT);
    }
}

// A wheel: a cylinder along y, tread and inner face TYRE, outer face a TYRE ring round a RIM
// disc. It touches the ground (a vertex at z = 0) and its outer face is at y_outer.
#define NWHEEL 24
#define NWHEEL_COARSE 8
static void add_wheel(builder *b, double x, double y_outer, double y_inner, double r) {
    int flip = y_outer < 0; // mirror image: reverse the winding
    int out[NWHEEL], in[NWHEEL], ring[NWHEEL];
    const int nw = b->nwheel;
    for (int k = 0; k < nw; k++) {
        double a = -M_PI / 2 + 2 * M_PI * k / nw;
        double dx = r * cos(a), dz = r * sin(a);
        if (k == 0) dx = 0, dz = -r; // exactly on the ground
        out[k] = add_v(b, x + dx, y_outer, r + dz);
        in[k] = add_v(b, x + dx, y_inner, r + dz);
        ring[k] = add_v(b, x + 0.62 * dx, y_outer, r + 0.62 * dz);
    }
    int co = add_v(b, x, y_outer, r), ci = add_v(b, x, y_inner, r);
    for (int k = 0; k < nw; k++) {
        int k1 = (k + 1) % nw;
        // With y_outer > 0 (left side) the outer face looks to +y; increasing k turns from
        // -z towards +x, which seen from +y is clockwise, so the outer face uses (k1, k).
        add_q(b, in[k], out[k], out[k1], in[k1], RS_SYNTH_PART_TYRE, flip);
        add_q(b, ring[k], ring[k1], out[k1], out[k], RS_SYNTH_PART_TYRE, flip);
        add_tf(b, co, ring[k1], ring[k], RS_SYNTH_PART_RIM, flip);
        add_tf(b, ci, in[k], in[k1], RS_SYNTH_PART_TYRE, flip);
    }
}

static void add_wheel_pair(builder *b, double x, double half_width, double tyre_w, double r) {
    add_wheel(b, x, half_width, half_width - tyre_w, r);
    add_wheel(b, x, -half_width, -(half_width - tyre_w), r);
}

// Jitters a profile (variant-driven): t by +-dt, z by +-dz, keeping order, roof points (z = 1)
// fixed at 1 so the height stays exact.
static void jitter_profile(profile *p, rs_rng *rng, double dt, double dz) {
    for (int i = 0; i < p->n; i++) {
        if (i > 0 && i < p->n - 1) {
            double t = p->t[i] + dt * (2 * rs_rng_uniform(rng) - 1);
            double lo = p->t[i - 1] + 0.005, hi = p->t[i + 1] - 0.005;
            p->t[i] = t < lo ? lo : t > hi ? hi : t;
        }
        if (p->z[i] < 1) p->z[i] = fmin(0.97, p->z[i] + dz * (2 * rs_rng_uniform(rng) - 1));
    }
}

static double jit(rs_rng *rng, double x, double d) {
    return x + d * (2 * rs_rng_uniform(rng) - 1);
}

static profile make_profile(int n, const double tz[][2]) {
    profile p = {n, {0}, {0}};
    for (int i = 0; i < n; i++) p.t[i] = tz[i][0], p.z[i] = tz[i][1];
    return p;
}
#define MAKE_PROFILE(arr) make_profile((int)(sizeof(arr) / sizeof((arr)[0])), arr)

static const double prof_sedan[][2] = {{0, .50}, {.04, .66}, {.22, .69}, {.36, 1}, {.62, 1}, {.76, .68}, {.96, .62}, {1, .46}};
static const double prof_hatch[][2] = {{0, .55}, {.03, .70}, {.10, .96}, {.16, 1}, {.58, 1}, {.75, .66}, {.96, .60}, {1, .45}};
static const double prof_suv[][2] = {{0, .60}, {.02, .95}, {.06, 1}, {.64, 1}, {.76, .70}, {.96, .64}, {1, .50}};
static const double prof_pickup[][2] = {{0, .55}, {.02, .58}, {.38, .58}, {.40, 1}, {.60, 1}, {.70, .70}, {.96, .66}, {1, .52}};
static const double prof_van[][2] = {{0, .90}, {.02, 1}, {.78, 1}, {.90, .60}, {.98, .50}, {1, .40}};
static const double prof_bus[][2] = {{0, .96}, {.01, 1}, {.985, 1}, {1, .96}};
static const double prof_cab[][2] = {{0, .96}, {.04, 1}, {.90, 1}, {1, .90}};
static const double prof_box[][2] = {{0, 1}, {1, 1}};
static const double prof_tractor[][2] = {{0, .32}, {.40, .32}, {.42, .97}, {.45, 1}, {.93, 1}, {1, .88}};

static body_spec car_body(double L, double W, double H, double clearance, double belt,
                          profile prof, double glass_lo, double glass_hi) {
    body_spec s = {-L / 2, L / 2, W / 2 - 0.03, H, clearance, belt, 0.25, 0.09, 0.10,
                   {glass_lo, glass_hi}, prof};
    return s;
}

rs_status rs_synth_fleet_build(rs_synth_mesh *mesh, const rs_synth_vehicle *v, rs_err *err) {
    return rs_synth_fleet_build_lod(mesh, v, false, err);
}

rs_status rs_synth_fleet_build_lod(rs_synth_mesh *mesh, const rs_synth_vehicle *v, bool coarse,
                                   rs_err *err) {
    memset(mesh, 0, sizeof *mesh);
    if ((int)v->cls < 0 || v->cls >= RS_SYNTH_NCLASSES)
        return rs_err_set(err, RS_ERR_INVALID, "class: %d is not a procedural class", (int)v->cls);
    double L = v->length_m, W = v->width_m, H = v->height_m;
    if (!(L >= 0.5 && W >= 0.5 && H >= 0.5 && L <= 30 && W <= 30 && H <= 30))
        return rs_err_set(err, RS_ERR_INVALID,
                          "dimensions: %g x %g x %g m not resolved (rs_synth_fleet_resolve)", L, W,
                          H);
    rs_rng rng = stream(v->variant, STREAM_SHAPE);
    builder b = {.nseg = coarse ? NSEG_COARSE : NSEG, .nwheel = coarse ? NWHEEL_COARSE : NWHEEL};
    double r, tw;
    switch (v->cls) {
    case RS_SYNTH_SEDAN:
    case RS_SYNTH_HATCHBACK:
    case RS_SYNTH_SUV:
    case RS_SYNTH_PICKUP:
    case RS_SYNTH_VAN: {
        profile p;
        double belt, clear, glo = 0, ghi = 1;
        if (v->cls == RS_SYNTH_SEDAN) p = MAKE_PROFILE(prof_sedan), belt = .64, clear = .15;
        else if (v->cls == RS_SYNTH_HATCHBACK) p = MAKE_PROFILE(prof_hatch), belt = .62, clear = .15;
        else if (v->cls == RS_SYNTH_SUV) p = MAKE_PROFILE(prof_suv), belt = .60, clear = .21;
        else if (v->cls == RS_SYNTH_PICKUP) p = MAKE_PROFILE(prof_pickup), belt = .57, clear = .24;
        else p = MAKE_PROFILE(prof_van), belt = .45, clear = .17, glo = .62;
        jitter_profile(&p, &rng, 0.015, 0.03);
        belt = jit(&rng, belt, 0.025);
        for (int i = 0; i < p.n; i++) // the greenhouse must stay above the belt line
            if (p.z[i] < 1 && p.z[i] > belt - 0.01 && p.z[i] < belt + 0.05) p.z[i] = belt - 0.01;
        body_spec s = car_body(L, W, H, jit(&rng, clear, 0.02), belt, p, glo, ghi);
        s.tumble = jit(&rng, v->cls == RS_SYNTH_VAN ? 0.10 : 0.25, 0.05);
        s.end_taper = jit(&rng, 0.09, 0.03);
        if (s.clearance > 0.4 * belt * H) s.clearance = 0.4 * belt * H;
        add_body(&b, &s);
        r = fmin(jit(&rng, v->cls >= RS_SYNTH_SUV ? 0.37 : 0.32, 0.025), 0.25 * H);
        tw = jit(&rng, 0.21, 0.02);
        double of = jit(&rng, 0.19, 0.02) * L, orr = jit(&rng, 0.21, 0.02) * L;
        add_wheel_pair(&b, L / 2 - of, W / 2, tw, r);
        add_wheel_pair(&b, -L / 2 + orr, W / 2, tw, r);
        break;
    }
    case RS_SYNTH_BUS: {
        profile p = MAKE_PROFILE(prof_bus);
        body_spec s = {-L / 2, L / 2, W / 2, H, jit(&rng, 0.32, 0.04), jit(&rng, 0.30, 0.03),
                       0.02, 0.012, 0.02, {0.03, 0.97}, p};
        add_body(&b, &s);
        r = jit(&rng, 0.50, 0.02);
        tw = 0.30;
        add_wheel_pair(&b, L / 2 - jit(&rng, 2.6, 0.2), W / 2 - 0.05, tw, r);
        add_wheel_pair(&b, -L / 2 + jit(&rng, 3.2, 0.3), W / 2 - 0.05, tw, r);
        break;
    }
    case RS_SYNTH_BOX_TRUCK: {
        double cab_len = jit(&rng, 2.1, 0.15), cab_h = jit(&rng, 0.74, 0.05) * H;
        profile pc = MAKE_PROFILE(prof_cab), pb = MAKE_PROFILE(prof_box);
        jitter_profile(&pc, &rng, 0.01, 0.03);
        body_spec cab = {L / 2 - cab_len, L / 2, W / 2 - 0.08, cab_h, 0.45, 0.45, 0.08, 0.05,
                         0.06, {0.3, 0.95}, pc};
        body_spec box = {-L / 2, L / 2 - cab_len - 0.10, W / 2, H, jit(&rng, 0.95, 0.08), 1.0,
                         0.0, 0.01, 0.01, {2, 2}, pb};
        add_body(&b, &cab);
        add_body(&b, &box);
        r = jit(&rng, 0.48, 0.03);
        tw = 0.28;
        add_wheel_pair(&b, L / 2 - jit(&rng, 1.25, 0.1), W / 2 - 0.06, tw, r);
        add_wheel_pair(&b, -L / 2 + jit(&rng, 0.24, 0.03) * L, W / 2 - 0.06, tw, r);
        break;
    }
    case RS_SYNTH_ARTICULATED_TRUCK:
    default: {
        double tl = jit(&rng, 6.0, 0.3), th = jit(&rng, 0.93, 0.04) * H;
        profile pt = MAKE_PROFILE(prof_tractor), pb = MAKE_PROFILE(prof_box);
        jitter_profile(&pt, &rng, 0.01, 0.02);
        body_spec tractor = {L / 2 - tl, L / 2, W / 2 - 0.05, th, 0.45, 0.52, 0.06, 0.05, 0.04,
                             {0.55, 0.95}, pt};
        double trailer_front = L / 2 - tl + jit(&rng, 2.2, 0.2);
        body_spec trailer = {-L / 2, trailer_front, W / 2, H, jit(&rng, 1.15, 0.05), 1.0, 0.0,
                             0.01, 0.005, {2, 2}, pb};
        add_body(&b, &tractor);
        add_body(&b, &trailer);
        r = jit(&rng, 0.50, 0.02);
        tw = 0.30;
        double yw = W / 2 - 0.06;
        add_wheel_pair(&b, L / 2 - 1.35, yw, tw, r);
        add_wheel_pair(&b, L / 2 - 1.35 - jit(&rng, 3.7, 0.2), yw, tw, r);
        double xa = -L / 2 + jit(&rng, 2.4, 0.3);
        for (int k = 0; k < 3; k++) add_wheel_pair(&b, xa + 1.31 * k, yw, tw, r);
        break;
    }
    }
    if (b.failed) {
        rs_synth_mesh_free(&b.m);
        return rs_err_set(err, RS_ERR_NOMEM, "vehicle mesh: out of memory");
    }
    *mesh = b.m;
    return RS_OK;
}

// ---------------------------------------------------------------- POV-Ray output

static int valid_identifier(const char *s) {
    if (!s || !*s || strlen(s) > 40) return 0;
    if (!((s[0] >= 'A' && s[0] <= 'Z') || s[0] == '_')) return 0;
    for (const char *p = s; *p; p++)
        if (!((*p >= 'A' && *p <= 'Z') || (*p >= 'a' && *p <= 'z') || (*p >= '0' && *p <= '9') ||
              *p == '_'))
            return 0;
    return 1;
}

// Built-in textures of the fixed parts (paint is written from the vehicle's colour).
static const char *const part_textures[RS_SYNTH_NPARTS] = {
    NULL,
    "pigment { rgb <0.015, 0.02, 0.025> } finish { specular 0.8 roughness 0.005 reflection 0.12 }",
    "pigment { rgb <0.85, 0.85, 0.80> } finish { specular 0.9 roughness 0.005 reflection 0.2 }",
    "pigment { rgb <0.45, 0.015, 0.02> } finish { specular 0.7 roughness 0.01 reflection 0.08 }",
    "pigment { rgb <0.018, 0.018, 0.02> } finish { specular 0.05 roughness 0.1 }",
    "pigment { rgb <0.30, 0.30, 0.32> } finish { specular 0.5 roughness 0.02 metallic }",
    "pigment { rgb <0.035, 0.035, 0.04> } finish { specular 0.2 roughness 0.05 }",
};

// One mesh2 of the triangles of `part` (< 0: all), its vertices renumbered.
static int write_mesh2(FILE *f, const rs_synth_mesh *m, int part, int *map) {
    int Nv = 0, Nt = 0;
    for (int i = 0; i < m->Nv; i++) map[i] = -1;
    for (int t = 0; t < m->Ntri; t++)
        if (part < 0 || m->part[t] == part) {
            Nt++;
            for (int k = 0; k < 3; k++)
                if (map[m->tri[t][k]] < 0) map[m->tri[t][k]] = Nv++;
        }
    if (Nt == 0) return 0;
    // vertices in the order of their new numbers
    int *inv = malloc((size_t)Nv * sizeof *inv);
    if (!inv) return -1;
    for (int i = 0; i < m->Nv; i++)
        if (map[i] >= 0) inv[map[i]] = i;
    fprintf(f, "  mesh2 {\n    vertex_vectors { %d", Nv);
    for (int j = 0; j < Nv; j++) {
        const double *p = m->v[inv[j]];
        fprintf(f, ",\n      <%.6f, %.6f, %.6f>", -p[1], p[2], p[0]);
    }
    fprintf(f, " }\n");
    if (m->vn) {
        fprintf(f, "    normal_vectors { %d", Nv);
        for (int j = 0; j < Nv; j++) {
            const double *n = m->vn[inv[j]];
            fprintf(f, ",\n      <%.6f, %.6f, %.6f>", -n[1], n[2], n[0]);
        }
        fprintf(f, " }\n");
    }
    free(inv);
    // The map (x,y,z)_v -> (-y, z, x) has determinant -1 and POV-Ray's frame is left-handed: a
    // triangle keeps its outward side, whatever the order; the order is kept.
    for (int pass = 0; pass < (m->vn ? 2 : 1); pass++) {
        fprintf(f, "    %s { %d", pass ? "normal_indices" : "face_indices", Nt);
        for (int t = 0; t < m->Ntri; t++)
            if (part < 0 || m->part[t] == part)
                fprintf(f, ",\n      <%d, %d, %d>", map[m->tri[t][0]], map[m->tri[t][1]],
                        map[m->tri[t][2]]);
        fprintf(f, " }\n");
    }
    return 1;
}

rs_status rs_synth_fleet_write_declare(FILE *f, const char *name, const rs_synth_mesh *mesh,
                                       rs_synth_declare_style style, const double paint_rgb[3],
                                       rs_err *err) {
    if (!valid_identifier(name))
        return rs_err_set(err, RS_ERR_INVALID,
                          "declare: name is not an upper-case POV-Ray identifier of at most 40 "
                          "characters");
    if (mesh->Ntri == 0) return rs_err_set(err, RS_ERR_INVALID, "declare %s: empty mesh", name);
    if (style == RS_SYNTH_DECLARE_TEXTURED &&
        !(paint_rgb && paint_rgb[0] >= 0 && paint_rgb[0] <= 1 && paint_rgb[1] >= 0 &&
          paint_rgb[1] <= 1 && paint_rgb[2] >= 0 && paint_rgb[2] <= 1))
        return rs_err_set(err, RS_ERR_INVALID, "declare %s: paint not in [0, 1]", name);
    int *map = malloc((size_t)(mesh->Nv > 0 ? mesh->Nv : 1) * sizeof *map);
    if (!map) return rs_err_set(err, RS_ERR_NOMEM, "declare %s: out of memory", name);
    int rc = 0;
    if (style == RS_SYNTH_DECLARE_BARE) {
        fprintf(f, "#declare %s =\n", name);
        rc = write_mesh2(f, mesh, -1, map);
        fprintf(f, "  }\n");
    } else {
        fprintf(f, "#declare %s = union {\n", name);
        for (int part = 0; part < RS_SYNTH_NPARTS && rc >= 0; part++) {
            rc = write_mesh2(f, mesh, part, map);
            if (rc <= 0) continue;
            if (part == RS_SYNTH_PART_PAINT)
                fprintf(f, "    texture { pigment { rgb <%.6f, %.6f, %.6f> } finish { specular 0.6 "
                           "roughness 0.01 reflection 0.06 } }\n  }\n",
                        paint_rgb[0], paint_rgb[1], paint_rgb[2]);
            else fprintf(f, "    texture { %s }\n  }\n", part_textures[part]);
        }
        fprintf(f, "}\n");
    }
    free(map);
    if (rc < 0) return rs_err_set(err, RS_ERR_NOMEM, "declare %s: out of memory", name);
    if (ferror(f)) return rs_err_set(err, RS_ERR_IO, "declare %s: write failed", name);
    return RS_OK;
}

rs_status rs_synth_fleet_write_placement(FILE *f, const rs_synth_vehicle *v, double up_m,
                                         rs_err *err) {
    if (!(isfinite(v->yaw_deg) && isfinite(v->e_m) && isfinite(v->n_m) && isfinite(up_m)))
        return rs_err_set(err, RS_ERR_INVALID, "placement: non-finite yaw or position");
    fprintf(f, " rotate <0, %.9f, 0> translate <%.6f, %.6f, %.6f>", v->yaw_deg, v->e_m, up_m,
            v->n_m);
    if (ferror(f)) return rs_err_set(err, RS_ERR_IO, "placement: write failed");
    return RS_OK;
}

void rs_synth_vehicle_to_enu(double p_enu_m[3], const rs_synth_vehicle *v, double up_m,
                             const double p_v_m[3]) {
    double y = v->yaw_deg * M_PI / 180, s = sin(y), c = cos(y);
    double x = p_v_m[0], l = p_v_m[1], z = p_v_m[2];
    p_enu_m[0] = v->e_m + x * s - l * c;
    p_enu_m[1] = v->n_m + x * c + l * s;
    p_enu_m[2] = up_m + z;
}

// ---------------------------------------------------------------- OBJ user models

// "+x" -> axis 0, sign +1, ...; returns 0 when not an axis.
static int parse_axis(const char *s, int *axis, double *sign) {
    if (!s || strlen(s) != 2 || (s[0] != '+' && s[0] != '-') || s[1] < 'x' || s[1] > 'z') return 0;
    *axis = s[1] - 'x';
    *sign = s[0] == '+' ? 1 : -1;
    return 1;
}

typedef struct {
    double (*a)[3];
    int n, cap;
} vec3_list;

static int vec3_push(vec3_list *l, const double x[3]) {
    if (l->n == l->cap) {
        int cap = l->cap ? 2 * l->cap : 256;
        void *p = realloc(l->a, (size_t)cap * sizeof *l->a);
        if (!p) return 0;
        l->a = p;
        l->cap = cap;
    }
    memcpy(l->a[l->n++], x, sizeof(double[3]));
    return 1;
}

// One face corner "v", "v/vt", "v//vn" or "v/vt/vn" -> 0-based v and vn (-1 if absent).
static int parse_corner(const char *tok, int nv, int nvn, int *iv, int *ivn) {
    char *end;
    long a = strtol(tok, &end, 10);
    if (end == tok) return 0;
    long n = 0;
    if (*end == '/') {
        end++;
        if (*end != '/') (void)strtol(end, &end, 10); // texture index: ignored
        if (*end == '/') {
            char *e2;
            n = strtol(end + 1, &e2, 10);
            if (e2 == end + 1) return 0;
            end = e2;
        }
    }
    if (*end) return 0;
    a = a < 0 ? nv + a : a - 1;
    if (a < 0 || a >= nv) return -1;
    if (n != 0) {
        n = n < 0 ? nvn + n : n - 1;
        if (n < 0 || n >= nvn) return -1;
    } else n = -1;
    *iv = (int)a;
    *ivn = (int)n;
    return 1;
}

static void rotate3(double y[3], const double R[3][3], const double x[3], double scale) {
    for (int r = 0; r < 3; r++) y[r] = scale * (R[r][0] * x[0] + R[r][1] * x[1] + R[r][2] * x[2]);
}

// Drops zero-area triangles, moves the box's footprint centre to the origin and its bottom to
// z = 0, normalises the normals.
static rs_status obj_finish(builder *b, const char *path, rs_err *err) {
    int Nt = 0;
    for (int t = 0; t < b->m.Ntri; t++) {
        const double *a = b->m.v[b->m.tri[t][0]], *p = b->m.v[b->m.tri[t][1]],
                     *c = b->m.v[b->m.tri[t][2]];
        double u[3], w[3], n[3];
        for (int k = 0; k < 3; k++) u[k] = p[k] - a[k], w[k] = c[k] - a[k];
        n[0] = u[1] * w[2] - u[2] * w[1];
        n[1] = u[2] * w[0] - u[0] * w[2];
        n[2] = u[0] * w[1] - u[1] * w[0];
        if (n[0] * n[0] + n[1] * n[1] + n[2] * n[2] > 1e-24) {
            memcpy(b->m.tri[Nt], b->m.tri[t], sizeof b->m.tri[t]);
            b->m.part[Nt++] = b->m.part[t];
        }
    }
    b->m.Ntri = Nt;
    if (Nt == 0) return rs_err_set(err, RS_ERR_INVALID, "%s: no face with a non-zero area", path);
    double lo[3], hi[3];
    rs_synth_mesh_bounds(lo, hi, &b->m);
    double c[3] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), lo[2]};
    for (int i = 0; i < b->m.Nv; i++) {
        for (int k = 0; k < 3; k++) b->m.v[i][k] -= c[k];
        if (b->m.vn) {
            double *n = b->m.vn[i], l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            if (l > 0)
                for (int k = 0; k < 3; k++) n[k] /= l;
        }
    }
    return RS_OK;
}

rs_status rs_synth_obj_load(rs_synth_mesh *mesh, const rs_synth_obj_spec *spec, rs_err *err) {
    memset(mesh, 0, sizeof *mesh);
    int fa, ua;
    double fs, us;
    if (!spec || !spec->path) return rs_err_set(err, RS_ERR_INVALID, "model: no path");
    if (!(spec->scale > 0 && isfinite(spec->scale)))
        return rs_err_set(err, RS_ERR_INVALID, "%s: scale: %g is not a positive number", spec->path,
                          spec->scale);
    if (!parse_axis(spec->forward, &fa, &fs))
        return rs_err_set(err, RS_ERR_INVALID, "%s: forward: not one of +x -x +y -y +z -z",
                          spec->path);
    if (!parse_axis(spec->up, &ua, &us) || ua == fa)
        return rs_err_set(err, RS_ERR_INVALID,
                          "%s: up: not one of +x -x +y -y +z -z, or the same axis as forward",
                          spec->path);
    // Rows of the OBJ -> vehicle rotation: x_v = forward, z_v = up, y_v = z_v x x_v.
    double R[3][3] = {{0}};
    R[0][fa] = fs;
    R[2][ua] = us;
    R[1][0] = R[2][1] * R[0][2] - R[2][2] * R[0][1];
    R[1][1] = R[2][2] * R[0][0] - R[2][0] * R[0][2];
    R[1][2] = R[2][0] * R[0][1] - R[2][1] * R[0][0];

    char *text = NULL;
    rs_status st = rs_io_read_file(&text, NULL, spec->path, err);
    if (st) return st;
    vec3_list V = {0}, VN = {0}, outn = {0}; // outn: the normal of each output vertex
    builder b = {0};
    int *cv = NULL, *cn = NULL, ccap = 0, all_normals = 1, line = 0;
    for (char *p = text; *p && !st;) {
        char *eol = strchr(p, '\n');
        if (eol) *eol = 0;
        line++;
        char *s = p;
        p = eol ? eol + 1 : p + strlen(p);
        char *hash = strchr(s, '#');
        if (hash) *hash = 0;
        char *save = NULL, *kw = strtok_r(s, " \t\r", &save);
        if (!kw) continue;
        if (strcmp(kw, "v") == 0 || strcmp(kw, "vn") == 0) {
            double x[3];
            for (int k = 0; k < 3 && !st; k++) {
                char *tok = strtok_r(NULL, " \t\r", &save), *end = NULL;
                x[k] = tok ? strtod(tok, &end) : NAN;
                if (!tok || *end || !isfinite(x[k]))
                    st = rs_err_set(err, RS_ERR_PARSE, "%s:%d: %s: coordinate %d is not a number",
                                    spec->path, line, kw, k + 1);
            }
            if (!st && !vec3_push(kw[1] ? &VN : &V, x))
                st = rs_err_set(err, RS_ERR_NOMEM, "%s:%d: out of memory", spec->path, line);
        } else if (strcmp(kw, "f") == 0) {
            int n = 0;
            for (char *tok; !st && (tok = strtok_r(NULL, " \t\r", &save)); n++) {
                if (n == ccap) {
                    ccap = ccap ? 2 * ccap : 16;
                    int *a = realloc(cv, (size_t)ccap * sizeof *cv);
                    if (a) cv = a;
                    int *c = a ? realloc(cn, (size_t)ccap * sizeof *cn) : NULL;
                    if (c) cn = c;
                    if (!c) {
                        st = rs_err_set(err, RS_ERR_NOMEM, "%s:%d: out of memory", spec->path, line);
                        break;
                    }
                }
                int r = parse_corner(tok, V.n, VN.n, &cv[n], &cn[n]);
                if (r == 0)
                    st = rs_err_set(err, RS_ERR_PARSE, "%s:%d: f: corner %d '%.40s' is not v, "
                                    "v/vt, v//vn or v/vt/vn", spec->path, line, n + 1, tok);
                else if (r < 0)
                    st = rs_err_set(err, RS_ERR_PARSE, "%s:%d: f: corner %d: index out of range "
                                    "(%d vertices, %d normals so far)", spec->path, line, n + 1,
                                    V.n, VN.n);
                else if (cn[n] < 0) all_normals = 0;
            }
            if (!st && n < 3)
                st = rs_err_set(err, RS_ERR_PARSE, "%s:%d: f: %d corners, at least 3 needed",
                                spec->path, line, n);
            // Every corner becomes its own vertex (positions and normals may pair differently).
            int base = b.m.Nv;
            for (int k = 0; k < n && !st; k++) {
                double y[3], nn[3] = {0, 0, 0};
                rotate3(y, R, V.a[cv[k]], spec->scale);
                add_v(&b, y[0], y[1], y[2]);
                if (cn[k] >= 0) rotate3(nn, R, VN.a[cn[k]], 1);
                if (!vec3_push(&outn, nn)) b.failed = 1;
            }
            for (int k = 1; k + 1 < n && !st; k++) add_t(&b, base, base + k, base + k + 1, 0);
            if (!st && b.failed)
                st = rs_err_set(err, RS_ERR_NOMEM, "%s:%d: out of memory", spec->path, line);
        }
    }
    free(text);
    free(cv);
    free(cn);
    free(V.a);
    free(VN.a);
    if (!st && b.m.Ntri == 0)
        st = rs_err_set(err, RS_ERR_INVALID, "%s: no faces", spec->path);
    if (!st && all_normals) {
        b.m.vn = outn.a;
        outn.a = NULL;
    }
    free(outn.a);
    if (!st) st = obj_finish(&b, spec->path, err);
    if (st) {
        rs_synth_mesh_free(&b.m);
        return st;
    }
    *mesh = b.m;
    return RS_OK;
}

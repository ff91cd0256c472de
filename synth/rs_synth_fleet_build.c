// rs_synth_fleet_build.c -- procedural vehicles (rs_synth_fleet_build, _build_lod): bodies
// lofted from a class side profile and plan shape, end caps with lights, grille and windscreen,
// wheels; the shape details drawn from the vehicle's variant. docs/fleet.md explains the shapes.
#include "synth/rs_synth_fleet.h"

#include <math.h>
#include <string.h>

#include "core/rs_rng.h"
#include "synth/internal/rs_synth_fleet_internal.h"

// Quad a b c d, counter-clockwise from outside (flip: the reverse).
static void add_q(rs_synth_fleet_builder *b, int a, int bb, int c, int d, int part, int flip)
{
    if (flip) {
        rs_synth_fleet_add_t(b, a, c, bb, part);
        rs_synth_fleet_add_t(b, a, d, c, part);
    } else {
        rs_synth_fleet_add_t(b, a, bb, c, part);
        rs_synth_fleet_add_t(b, a, c, d, part);
    }
}

static void add_tf(rs_synth_fleet_builder *b, int a, int bb, int c, int part, int flip)
{
    if (flip)
        rs_synth_fleet_add_t(b, a, c, bb, part);
    else
        rs_synth_fleet_add_t(b, a, bb, c, part);
}

// A side profile: the roof line z_top(t) / H at t = (x - x_rear) / (x_front - x_rear).
#define MAXPROF 10
typedef struct {
    int n;
    double t[MAXPROF], z[MAXPROF];
} profile;

static double profile_at(const profile *p, double t)
{
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
    double x_rear, x_front;    // m
    double half_width;         // m, the widest section
    double height;             // m, top of the profile's 1.0
    double clearance;          // m, underside
    double belt;               // fraction of height: the greenhouse starts above it
    double tumble;             // roof-edge inset per metre above the belt
    double end_len, end_taper; // plan rounding: fraction of length, fraction of half width
    double glass_t[2];         // side glass only for t in this range
    profile prof;
} body_spec;

#define NSEC        10
#define NSEG        56
#define NSEG_COARSE 8 // level of detail for vehicles a few pixels tall (rs_synth_fleet_build_lod)

static void section(double y[NSEC], double z[NSEC], const body_spec *s, double t, int *greenhouse)
{
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
static void add_cap(rs_synth_fleet_builder *b, const int idx[NSEC], int greenhouse, int flip, int light_part)
{
    const double *p2 = b->m.v[idx[2]], *p3 = b->m.v[idx[3]], *p6 = b->m.v[idx[6]], *p7 = b->m.v[idx[7]];
    double f = 0.28, P[4][3];
    for (int k = 0; k < 3; k++) {
        P[0][k] = p2[k] + f * (p7[k] - p2[k]);       // a
        P[1][k] = p3[k] + f * (p6[k] - p3[k]);       // b
        P[2][k] = p2[k] + (1 - f) * (p7[k] - p2[k]); // c
        P[3][k] = p3[k] + (1 - f) * (p6[k] - p3[k]); // d
    }
    int a = rs_synth_fleet_add_v(b, P[0][0], P[0][1], P[0][2]);
    int bb = rs_synth_fleet_add_v(b, P[1][0], P[1][1], P[1][2]);
    int c = rs_synth_fleet_add_v(b, P[2][0], P[2][1], P[2][2]);
    int d = rs_synth_fleet_add_v(b, P[3][0], P[3][1], P[3][2]);
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

static void add_body(rs_synth_fleet_builder *b, const body_spec *s)
{
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
        for (int k = 0; k < NSEC; k++) cur[k] = rs_synth_fleet_add_v(b, x, y[k], z[k]);
        if (i == 0) memcpy(first, cur, sizeof cur);
        if (i > 0 && !b->failed) {
            double tm = 0.5 * (ts[i] + ts[i - 1]);
            int both = gh && prev_gh;
            double slope = fabs(b->m.v[cur[4]][2] - b->m.v[prev[4]][2]) / (L * (ts[i] - ts[i - 1]));
            int side_glass =
                both && tm > s->glass_t[0] && tm < s->glass_t[1] && tm > gh_lo + pillar && tm < gh_hi - pillar;
            int end = i == 1 ? -1 : i == n - 1 ? 1 : 0;
            for (int k = 0; k < NSEC; k++) {
                int k1 = (k + 1) % NSEC, part = RS_SYNTH_PART_PAINT;
                if (k == NSEC - 1)
                    part = RS_SYNTH_PART_TRIM; // underside
                else if ((k == 0 || k == 8 || k == 1 || k == 7) && end)
                    part = RS_SYNTH_PART_TRIM;
                else if ((k == 2 || k == 6) && end)
                    part = end > 0 ? RS_SYNTH_PART_HEADLIGHT : RS_SYNTH_PART_TAILLIGHT;
                else if ((k == 3 || k == 5) && side_glass)
                    part = RS_SYNTH_PART_GLASS;
                else if (k == 4 && both && slope > 0.6)
                    part = RS_SYNTH_PART_GLASS;
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
#define NWHEEL        24
#define NWHEEL_COARSE 8
static void add_wheel(rs_synth_fleet_builder *b, double x, double y_outer, double y_inner, double r)
{
    int flip = y_outer < 0; // mirror image: reverse the winding
    int out[NWHEEL], in[NWHEEL], ring[NWHEEL];
    const int nw = b->nwheel;
    for (int k = 0; k < nw; k++) {
        double a = -M_PI / 2 + 2 * M_PI * k / nw;
        double dx = r * cos(a), dz = r * sin(a);
        if (k == 0) dx = 0, dz = -r; // exactly on the ground
        out[k] = rs_synth_fleet_add_v(b, x + dx, y_outer, r + dz);
        in[k] = rs_synth_fleet_add_v(b, x + dx, y_inner, r + dz);
        ring[k] = rs_synth_fleet_add_v(b, x + 0.62 * dx, y_outer, r + 0.62 * dz);
    }
    int co = rs_synth_fleet_add_v(b, x, y_outer, r);
    int ci = rs_synth_fleet_add_v(b, x, y_inner, r);
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

static void add_wheel_pair(rs_synth_fleet_builder *b, double x, double half_width, double tyre_w, double r)
{
    add_wheel(b, x, half_width, half_width - tyre_w, r);
    add_wheel(b, x, -half_width, -(half_width - tyre_w), r);
}

// Jitters a profile (variant-driven): t by +-dt, z by +-dz, keeping order, roof points (z = 1)
// fixed at 1 so the height stays exact.
static void jitter_profile(profile *p, rs_rng *rng, double dt, double dz)
{
    for (int i = 0; i < p->n; i++) {
        if (i > 0 && i < p->n - 1) {
            double t = p->t[i] + dt * (2 * rs_rng_uniform(rng) - 1);
            double lo = p->t[i - 1] + 0.005, hi = p->t[i + 1] - 0.005;
            p->t[i] = t < lo ? lo : t > hi ? hi : t;
        }
        if (p->z[i] < 1) p->z[i] = fmin(0.97, p->z[i] + dz * (2 * rs_rng_uniform(rng) - 1));
    }
}

static double jit(rs_rng *rng, double x, double d) { return x + d * (2 * rs_rng_uniform(rng) - 1); }

static profile make_profile(int n, const double tz[][2])
{
    profile p = {n, {0}, {0}};
    for (int i = 0; i < n; i++) p.t[i] = tz[i][0], p.z[i] = tz[i][1];
    return p;
}
#define MAKE_PROFILE(arr) make_profile((int)(sizeof(arr) / sizeof((arr)[0])), arr)

static const double prof_sedan[][2] = {{0, .50}, {.04, .66}, {.22, .69}, {.36, 1},
                                       {.62, 1}, {.76, .68}, {.96, .62}, {1, .46}};
static const double prof_hatch[][2] = {{0, .55}, {.03, .70}, {.10, .96}, {.16, 1},
                                       {.58, 1}, {.75, .66}, {.96, .60}, {1, .45}};
static const double prof_suv[][2] = {{0, .60}, {.02, .95}, {.06, 1}, {.64, 1}, {.76, .70}, {.96, .64}, {1, .50}};
static const double prof_pickup[][2] = {{0, .55}, {.02, .58}, {.38, .58}, {.40, 1},
                                        {.60, 1}, {.70, .70}, {.96, .66}, {1, .52}};
static const double prof_van[][2] = {{0, .90}, {.02, 1}, {.78, 1}, {.90, .60}, {.98, .50}, {1, .40}};
static const double prof_bus[][2] = {{0, .96}, {.01, 1}, {.985, 1}, {1, .96}};
static const double prof_cab[][2] = {{0, .96}, {.04, 1}, {.90, 1}, {1, .90}};
static const double prof_box[][2] = {{0, 1}, {1, 1}};
static const double prof_tractor[][2] = {{0, .32}, {.40, .32}, {.42, .97}, {.45, 1}, {.93, 1}, {1, .88}};

static body_spec car_body(double L, double W, double H, double clearance, double belt, profile prof, double glass_lo,
                          double glass_hi)
{
    body_spec s = {-L / 2, L / 2, W / 2 - 0.03, H, clearance, belt, 0.25, 0.09, 0.10, {glass_lo, glass_hi}, prof};
    return s;
}

rs_status rs_synth_fleet_build(rs_synth_mesh *mesh, const rs_synth_vehicle *v, rs_err *err)
{
    return rs_synth_fleet_build_lod(mesh, v, false, err);
}

rs_status rs_synth_fleet_build_lod(rs_synth_mesh *mesh, const rs_synth_vehicle *v, bool coarse, rs_err *err)
{
    memset(mesh, 0, sizeof *mesh);
    if ((int)v->cls < 0 || v->cls >= RS_SYNTH_NCLASSES)
        return rs_err_set(err, RS_ERR_INVALID, "class: %d is not a procedural class", (int)v->cls);
    double L = v->length_m, W = v->width_m, H = v->height_m;
    if (!(L >= 0.5 && W >= 0.5 && H >= 0.5 && L <= 30 && W <= 30 && H <= 30))
        return rs_err_set(err, RS_ERR_INVALID, "dimensions: %g x %g x %g m not resolved (rs_synth_fleet_resolve)", L, W,
                          H);
    rs_rng rng = rs_synth_fleet_stream(v->variant, RS_SYNTH_FLEET_STREAM_SHAPE);
    rs_synth_fleet_builder b = {.nseg = coarse ? NSEG_COARSE : NSEG, .nwheel = coarse ? NWHEEL_COARSE : NWHEEL};
    double r, tw;
    switch (v->cls) {
    case RS_SYNTH_SEDAN:
    case RS_SYNTH_HATCHBACK:
    case RS_SYNTH_SUV:
    case RS_SYNTH_PICKUP:
    case RS_SYNTH_VAN: {
        profile p;
        double belt, clear, glo = 0, ghi = 1;
        if (v->cls == RS_SYNTH_SEDAN)
            p = MAKE_PROFILE(prof_sedan), belt = .64, clear = .15;
        else if (v->cls == RS_SYNTH_HATCHBACK)
            p = MAKE_PROFILE(prof_hatch), belt = .62, clear = .15;
        else if (v->cls == RS_SYNTH_SUV)
            p = MAKE_PROFILE(prof_suv), belt = .60, clear = .21;
        else if (v->cls == RS_SYNTH_PICKUP)
            p = MAKE_PROFILE(prof_pickup), belt = .57, clear = .24;
        else
            p = MAKE_PROFILE(prof_van), belt = .45, clear = .17, glo = .62;
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
        body_spec s = {-L / 2, L / 2, W / 2,        H, jit(&rng, 0.32, 0.04), jit(&rng, 0.30, 0.03), 0.02,
                       0.012,  0.02,  {0.03, 0.97}, p};
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
        body_spec cab = {L / 2 - cab_len, L / 2, W / 2 - 0.08, cab_h, 0.45, 0.45, 0.08, 0.05, 0.06, {0.3, 0.95}, pc};
        body_spec box = {-L / 2, L / 2 - cab_len - 0.10, W / 2, H, jit(&rng, 0.95, 0.08), 1.0, 0.0, 0.01, 0.01, {2, 2},
                         pb};
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
        body_spec tractor = {L / 2 - tl, L / 2, W / 2 - 0.05, th, 0.45, 0.52, 0.06, 0.05, 0.04, {0.55, 0.95}, pt};
        double trailer_front = L / 2 - tl + jit(&rng, 2.2, 0.2);
        body_spec trailer = {-L / 2, trailer_front, W / 2, H, jit(&rng, 1.15, 0.05), 1.0, 0.0, 0.01, 0.005, {2, 2}, pb};
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

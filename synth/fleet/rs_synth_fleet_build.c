// rs_synth_fleet_build.c -- procedural vehicles (rs_synth_fleet_build, _build_lod): bodies
// lofted from a class side profile and plan shape, end caps with lights, grille and windscreen,
// wheels; the shape details drawn from the vehicle's variant. docs/fleet.md explains the shapes.
#include "synth/fleet/rs_synth_fleet.h"

#include <math.h>
#include <string.h>

#include "core/rs_rng.h"
#include "synth/fleet/internal/rs_synth_fleet_internal.h"

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

#define NWHEEL        20 // sides of a wheel (a multiple of 4: the lowest, front, top and rear
#define NWHEEL_MEDIUM 12 // points of every ring are exact)
#define NWHEEL_COARSE 8
#define NWHEEL_MAX    20

static void add_tri(rs_synth_fleet_builder *b, int a, int bb, int c, int part, int flip)
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

// One lofted body: stations along x, each section a closed loop of 2 NLEV points: the left
// side's NLEV levels from the underside up to the roof, then the right side's back down.
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
    int front_lights, rear_lights; // end caps: lights (and the bumper's plate) or plain panels
    int chrome_grille;             // front grille bars CHROME instead of TRIM
    int mirrors;                   // door mirrors reaching mirror_y (m) at the A-pillars
    double mirror_y;
} body_spec;

#define NLEV        10 // levels per side of a section (rounded sill, bumper, lights, shoulder, roof)
#define NSEC        (2 * NLEV)
#define NSEG        56
#define NSEG_MEDIUM 20 // levels of detail (rs_synth_lod, rs_synth_fleet_build_lod)
#define NSEG_COARSE 8
#define S45         0.70710678118654752

// The left side (y >= 0) of the section at t: levels bottom to top, y[i] and z[i] (m). Every
// level has its mirror image on the right at the same height, so an end cap is a stack of
// horizontal bands. Heights strictly increase.
static void section(double y[NLEV], double z[NLEV], const body_spec *s, double t, int *greenhouse)
{
    double H = s->height, ztop = H * profile_at(&s->prof, t);
    double zbelt = s->belt * H, zc = s->clearance;
    double zs = fmin(zbelt, ztop - 0.04 * H);
    double a = fabs(t - 0.5) - (0.5 - s->end_len);
    double q = a > 0 ? a / s->end_len : 0;
    double wb = s->half_width * (1 - s->end_taper * q * q);
    double d = zs - zc, rb = fmin(0.07, 0.25 * d), rs = fmin(0.06, 0.25 * d);
    double g = ztop - zs, rr = fmin(0.10, 0.45 * g);
    double wt = ztop > zbelt ? wb - rs - s->tumble * g : wb - rs - 0.01;
    if (wt - rr < 0.3 * wb) wt = 0.3 * wb + rr;
    *greenhouse = ztop > zbelt + 0.02 * H;
    const double yy[NLEV] = {wb - rb, wb - rb * (1 - S45), wb,     wb, wb, wb - rs * (1 - S45), wb - rs,
                             wt,      wt - rr * (1 - S45), wt - rr};
    const double zz[NLEV] = {zc,        zc + rb * (1 - S45),   zc + rb, zc + 0.38 * d, zs - rs, zs - rs * (1 - S45), zs,
                             ztop - rr, ztop - rr * (1 - S45), ztop};
    memcpy(y, yy, sizeof yy);
    memcpy(z, zz, sizeof zz);
}

// The flat end cap of a section (loop vertices idx) at the front (front = 1, outward +x) or the
// rear: bands between the levels, each cut into three columns (the middle one 0.56 m wide at
// most): under-bumper and bumper TRIM with the number PLATE in the middle, the light band with
// two lights and a grille (rear: paint), body panels, and glass above the belt line when the
// section has a greenhouse (windscreen or rear window of a van, bus or cab).
static void add_cap(rs_synth_fleet_builder *b, const int idx[NSEC], int greenhouse, int front, int lights,
                    int chrome_grille)
{
    int col[NLEV][4];
    for (int i = 0; i < NLEV; i++) {
        double p[3]; // a copy: adding vertices may move b->m.v
        memcpy(p, b->m.v[idx[i]], sizeof p);
        double f = fmin(0.30 * p[1], 0.28);
        col[i][0] = idx[i];
        col[i][3] = idx[NSEC - 1 - i];
        // the lowest and highest levels are edges of the loft (underside, roof): not split
        int edge = i == 0 || i == NLEV - 1;
        col[i][1] = edge ? col[i][0] : rs_synth_fleet_add_v(b, p[0], f, p[2]);
        col[i][2] = edge ? col[i][3] : rs_synth_fleet_add_v(b, p[0], -f, p[2]);
    }
    const int light = front ? RS_SYNTH_PART_HEADLIGHT : RS_SYNTH_PART_TAILLIGHT;
    for (int i = 0; i + 1 < NLEV; i++)
        for (int c = 0; c < 3; c++) {
            int part = RS_SYNTH_PART_PAINT;
            if (i <= 1)
                part = RS_SYNTH_PART_TRIM;
            else if (i == 2)
                part = c == 1 && lights ? RS_SYNTH_PART_PLATE : RS_SYNTH_PART_TRIM;
            else if (i == 3 && lights)
                part = c != 1  ? light
                       : front ? (chrome_grille ? RS_SYNTH_PART_CHROME : RS_SYNTH_PART_TRIM)
                               : RS_SYNTH_PART_PAINT;
            else if (i == 6 && greenhouse)
                part = RS_SYNTH_PART_GLASS;
            int q[4] = {col[i][c], col[i][c + 1], col[i + 1][c + 1], col[i + 1][c]};
            if (q[0] == q[1])
                add_tri(b, q[0], q[2], q[3], part, front);
            else if (q[2] == q[3])
                add_tri(b, q[0], q[1], q[2], part, front);
            else
                add_q(b, q[0], q[1], q[2], q[3], part, front);
        }
}

// A convex polygon (x, z) (n points, either order) extruded along y over [y0, y1]: a closed
// prism of one part, wound outward.
static void add_prism(rs_synth_fleet_builder *b, const double (*xz)[2], int n, double y0, double y1, int part)
{
    const int t0 = b->m.Ntri;
    int lo[16], hi[16];
    for (int k = 0; k < n; k++) {
        lo[k] = rs_synth_fleet_add_v(b, xz[k][0], y0, xz[k][1]);
        hi[k] = rs_synth_fleet_add_v(b, xz[k][0], y1, xz[k][1]);
    }
    for (int k = 0; k < n; k++) {
        int k1 = (k + 1) % n;
        add_q(b, lo[k], lo[k1], hi[k1], hi[k], part, 0);
    }
    for (int k = 1; k + 1 < n; k++) {
        rs_synth_fleet_add_t(b, lo[0], lo[k + 1], lo[k], part);
        rs_synth_fleet_add_t(b, hi[0], hi[k], hi[k + 1], part);
    }
    rs_synth_fleet_orient(b, t0);
}

// A bar of thickness th (in the x-z plane) from (xa, za) to (xb, zb), over [y0, y1].
static void add_bar(rs_synth_fleet_builder *b, double xa, double za, double xb, double zb, double th, double y0,
                    double y1, int part)
{
    double dx = xb - xa, dz = zb - za, l = sqrt(dx * dx + dz * dz);
    double nx = -dz / l * th / 2, nz = dx / l * th / 2;
    const double p[4][2] = {{xa + nx, za + nz}, {xb + nx, zb + nz}, {xb - nx, zb - nz}, {xa - nx, za - nz}};
    add_prism(b, p, 4, y0, y1, part);
}

// The parts of the loft's band between stations t0 and t1 (sections (y0, z0, gh0), (y1, z1,
// gh1)), k = 0 .. NSEC - 1 round the loop; end: -1 the rear band, 1 the front one, 0 between.
static void band_parts(int part[NSEC], const body_spec *s, double t0, double t1, double z0_top, double z1_top, int gh0,
                       int gh1, int end, double gh_lo, double gh_hi)
{
    const double L = s->x_front - s->x_rear, pillar = 0.12 / L, tm = 0.5 * (t0 + t1);
    const int both = gh0 && gh1;
    const double slope = fabs(z1_top - z0_top) / (L * (t1 - t0));
    const int side_glass =
        both && tm > s->glass_t[0] && tm < s->glass_t[1] && tm > gh_lo + pillar && tm < gh_hi - pillar;
    const int lights = end > 0 ? s->front_lights : end < 0 ? s->rear_lights : 0;
    for (int k = 0; k < NSEC; k++) {
        int lev = k < NLEV - 1 ? k : k >= NLEV ? NSEC - 2 - k : -1; // side band's lower level
        part[k] = RS_SYNTH_PART_PAINT;
        if (k == NSEC - 1)
            part[k] = RS_SYNTH_PART_TRIM; // underside
        else if (lev < 0)
            part[k] = both && slope > 0.6 ? RS_SYNTH_PART_GLASS : RS_SYNTH_PART_PAINT; // roof
        else if (lev <= 2 && end && lights)
            part[k] = RS_SYNTH_PART_TRIM; // the bumper wraps round the corner
        else if (lev == 3 && end && lights)
            part[k] = end > 0 ? RS_SYNTH_PART_HEADLIGHT : RS_SYNTH_PART_TAILLIGHT;
        else if (lev == 6 && side_glass)
            part[k] = RS_SYNTH_PART_GLASS;
    }
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
    double y[NSEG + 1 + MAXPROF][NLEV], z[NSEG + 1 + MAXPROF][NLEV];
    int gh[NSEG + 1 + MAXPROF];
    double gh_lo = 2, gh_hi = -1; // greenhouse extent in t, for the pillars
    for (int i = 0; i < n; i++) {
        section(y[i], z[i], s, ts[i], &gh[i]);
        if (gh[i]) {
            gh_lo = fmin(gh_lo, ts[i]);
            gh_hi = fmax(gh_hi, ts[i]);
        }
    }
    // The stations kept: where a run of bands is straight (every section between its ends on
    // the lines between them, within b->loft_tol_m) and of the same parts, one band spans it
    // (the middle of a body is ruled: its sections change linearly between the profile's
    // points). The end bands (lights and bumpers wrap round them) are kept as they are.
    int keep[NSEG + 1 + MAXPROF], Nkeep = 0;
    keep[Nkeep++] = 0;
    for (int a = 0; a < n - 1;) {
        int j = a + 1;
        while (a >= 1 && j + 1 <= n - 2 && b->loft_tol_m >= 0) { // can the band a .. j grow to j + 1?
            const int c = j + 1;
            int pa[NSEC], pc[NSEC], ok = gh[c] == gh[a];
            band_parts(pa, s, ts[a], ts[a + 1], z[a][NLEV - 1], z[a + 1][NLEV - 1], gh[a], gh[a + 1], 0, gh_lo, gh_hi);
            band_parts(pc, s, ts[a], ts[c], z[a][NLEV - 1], z[c][NLEV - 1], gh[a], gh[c], 0, gh_lo, gh_hi);
            ok = ok && !memcmp(pa, pc, sizeof pa);
            for (int m = a + 1; m < c && ok; m++) {
                int pm[NSEC];
                band_parts(pm, s, ts[m], ts[m + 1], z[m][NLEV - 1], z[m + 1][NLEV - 1], gh[m], gh[m + 1], 0, gh_lo,
                           gh_hi);
                const double f = (ts[m] - ts[a]) / (ts[c] - ts[a]);
                ok = gh[m] == gh[a] && !memcmp(pa, pm, sizeof pa);
                for (int l = 0; l < NLEV && ok; l++)
                    ok = fabs(y[m][l] - (y[a][l] + f * (y[c][l] - y[a][l]))) <= b->loft_tol_m &&
                         fabs(z[m][l] - (z[a][l] + f * (z[c][l] - z[a][l]))) <= b->loft_tol_m;
            }
            if (!ok) break;
            j = c;
        }
        keep[Nkeep++] = j;
        a = j;
    }
    // A kept station is a crease or a change of part; its neighbours stay too, so that the
    // smooth normals blending across it (rs_synth_fleet_smooth) still blend over one band of
    // the uniform stations, not over the long band beyond (a dark wedge on a roof).
    uint8_t kept[NSEG + 1 + MAXPROF] = {0};
    for (int q = 0; q < Nkeep; q++) {
        const int i = keep[q];
        kept[i] = 1;
        if (i > 0) kept[i - 1] = 1;
        if (i + 1 < n) kept[i + 1] = 1;
    }
    Nkeep = 0;
    for (int i = 0; i < n; i++)
        if (kept[i]) keep[Nkeep++] = i;
    int prev[NSEC] = {0}, cur[NSEC] = {0}, first[NSEC] = {0};
    for (int q = 0; q < Nkeep; q++) {
        const int i = keep[q];
        double x = s->x_rear + ts[i] * L;
        if (i == n - 1) x = s->x_front; // exact
        for (int k = 0; k < NSEC; k++) {
            int lev = k < NLEV ? k : NSEC - 1 - k;
            cur[k] = rs_synth_fleet_add_v(b, x, k < NLEV ? y[i][lev] : -y[i][lev], z[i][lev]);
        }
        if (q == 0) memcpy(first, cur, sizeof cur);
        if (q > 0 && !b->failed) {
            const int h = keep[q - 1];
            int part[NSEC];
            band_parts(part, s, ts[h], ts[i], b->m.v[prev[NLEV - 1]][2], b->m.v[cur[NLEV - 1]][2], gh[h], gh[i],
                       q == 1           ? -1
                       : q == Nkeep - 1 ? 1
                                        : 0,
                       gh_lo, gh_hi);
            for (int k = 0; k < NSEC; k++)
                add_q(b, prev[k], prev[(k + 1) % NSEC], cur[(k + 1) % NSEC], cur[k], part[k], 0);
        }
        memcpy(prev, cur, sizeof cur);
        if (q == Nkeep - 1) add_cap(b, cur, gh[i], 1, s->front_lights, s->chrome_grille);
    }
    add_cap(b, first, gh[0], 0, s->rear_lights, 0);
    if (s->mirrors && gh_hi > gh_lo) {
        // door mirrors at the front of the greenhouse, just above the belt line
        double y[NLEV], z[NLEV];
        int gh;
        section(y, z, s, gh_hi, &gh);
        double xm = s->x_rear + gh_hi * L - 0.12, zm = z[6] + 0.10;
        const double p[6][2] = {{xm - 0.10, zm - 0.05}, {xm + 0.06, zm - 0.06}, {xm + 0.10, zm},
                                {xm + 0.07, zm + 0.07}, {xm - 0.08, zm + 0.06}, {xm - 0.11, zm}};
        double yin = y[6] - 0.04;
        add_prism(b, p, 6, yin, s->mirror_y, RS_SYNTH_PART_PAINT);
        add_prism(b, p, 6, -s->mirror_y, -yin, RS_SYNTH_PART_PAINT);
    }
}

// A surface of revolution about the axis through (x, ?, zc) along y: profile points (rho, d)
// (d: depth from the outer face y_outer towards the vehicle's middle), band j between points j
// and j + 1 of part[j] (-1: spokes, RIM and TRIM sectors alternating). A point with rho = 0 is
// one vertex on the axis; ring = 1 closes the profile into a loop (a torus-like ring). Wound
// outward. The lowest vertex of a ring of radius rho is exactly at zc - rho, and so on round.
#define MAXLATHE 12
static void add_lathe(rs_synth_fleet_builder *b, double x, double zc, double y_outer, const double (*pr)[2],
                      const int *part, int np, int ring)
{
    const int t0 = b->m.Ntri, nw = b->nwheel;
    const double s = y_outer > 0 ? -1 : 1;
    int id[MAXLATHE][NWHEEL_MAX];
    for (int j = 0; j < np; j++)
        for (int k = 0; k < nw; k++) {
            double r = pr[j][0], y = y_outer + s * pr[j][1];
            if (r == 0) {
                id[j][k] = k ? id[j][0] : rs_synth_fleet_add_v(b, x, y, zc);
                continue;
            }
            double a = -M_PI / 2 + 2 * M_PI * k / nw, dx = r * cos(a), dz = r * sin(a);
            if (4 * k == 0) dx = 0, dz = -r;
            if (4 * k == nw) dx = r, dz = 0;
            if (4 * k == 2 * nw) dx = 0, dz = r;
            if (4 * k == 3 * nw) dx = -r, dz = 0;
            id[j][k] = rs_synth_fleet_add_v(b, x + dx, y, zc + dz);
        }
    for (int j = 0; j < (ring ? np : np - 1); j++) {
        int j1 = (j + 1) % np;
        for (int k = 0; k < nw; k++) {
            int k1 = (k + 1) % nw, p = part[j];
            if (p < 0) p = (nw >= 20 && (k * 10 / nw) % 2) ? RS_SYNTH_PART_TRIM : RS_SYNTH_PART_RIM;
            if (pr[j][0] == 0)
                rs_synth_fleet_add_t(b, id[j][k], id[j1][k], id[j1][k1], p);
            else if (pr[j1][0] == 0)
                rs_synth_fleet_add_t(b, id[j][k], id[j1][k], id[j][k1], p);
            else
                add_q(b, id[j][k], id[j1][k], id[j1][k1], id[j][k1], p, 0);
        }
    }
    rs_synth_fleet_orient(b, t0);
}

// A car or truck wheel: tyre (rounded shoulders) round a dished rim with five spokes (in full
// detail), touching the ground (a vertex at z = 0), its outer face at y_outer.
static void add_wheel(rs_synth_fleet_builder *b, double x, double y_outer, double y_inner, double r)
{
    double tw = fabs(y_outer - y_inner), sh = fmin(0.035, 0.2 * tw);
    const double pr[10][2] = {{0, 0.035},    {0.18 * r, 0.03}, {0.58 * r, 0.04}, {0.64 * r, 0.005}, {0.68 * r, 0},
                              {0.86 * r, 0}, {r, sh},          {r, tw - sh},     {0.86 * r, tw},    {0, tw}};
    const int part[9] = {RS_SYNTH_PART_RIM,  -1,
                         RS_SYNTH_PART_RIM,  RS_SYNTH_PART_RIM,
                         RS_SYNTH_PART_TYRE, RS_SYNTH_PART_TYRE,
                         RS_SYNTH_PART_TYRE, RS_SYNTH_PART_TYRE,
                         RS_SYNTH_PART_TYRE};
    add_lathe(b, x, r, y_outer, pr, part, 10, 0);
}

static void add_wheel_pair(rs_synth_fleet_builder *b, double x, double half_width, double tyre_w, double r)
{
    add_wheel(b, x, half_width, half_width - tyre_w, r);
    add_wheel(b, x, -half_width, -(half_width - tyre_w), r);
}

// Wheel-arch liners: dark half-discs (radius r + 0.06 m, clipped below z_max) standing 4 mm
// proud of the body side at y_side, behind the wheel at x.
static void add_arch_pair(rs_synth_fleet_builder *b, double x, double r, double y_side, double z_max)
{
    double ra = fmin(r + 0.06, z_max - r);
    if (ra < r + 0.01) return;
    double p[16][2];
    int n = b->nwheel >= NWHEEL_MEDIUM ? 12 : 6;
    for (int k = 0; k < n; k++) {
        double a = (-15 + 210.0 * k / (n - 1)) * M_PI / 180;
        p[k][0] = x + ra * cos(a), p[k][1] = r + ra * sin(a);
    }
    add_prism(b, (const double(*)[2])p, n, y_side - 0.03, y_side + 0.004, RS_SYNTH_PART_TRIM);
    add_prism(b, (const double(*)[2])p, n, -y_side - 0.004, -y_side + 0.03, RS_SYNTH_PART_TRIM);
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

static body_spec car_body(double L, double half_width, double H, double clearance, double belt, profile prof,
                          double glass_lo, double glass_hi)
{
    body_spec s = {-L / 2, L / 2, half_width, H, clearance, belt, 0.25, 0.09, 0.10, {glass_lo, glass_hi},
                   prof,   1,     1,          0, 0,         0};
    return s;
}

// A two-wheeler with its rider (docs/fleet.md): wheels at both ends of the box (their treads
// reach x = +-L/2), the handlebar spans the width, the rider's head reaches the height.
static void add_two_wheeler(rs_synth_fleet_builder *b, const rs_synth_vehicle *v, rs_rng *rng)
{
    const double L = v->length_m, W = v->width_m, H = v->height_m;
    const int motor = v->cls == RS_SYNTH_MOTORCYCLE;
    const double r = motor ? jit(rng, 0.31, 0.02) : jit(rng, 0.34, 0.01);
    const double xr = -L / 2 + r, xf = L / 2 - r;
    const int P = RS_SYNTH_PART_PAINT, T = RS_SYNTH_PART_TRIM, C = RS_SYNTH_PART_CHROME, R = RS_SYNTH_PART_RIDER;
    for (int w = 0; w < 2; w++) {
        double x = w ? xf : xr;
        if (motor) {
            const double tw = 0.13, pr[8][2] = {{0, 0.02}, {0.55 * r, 0.01}, {0.62 * r, 0},  {0.80 * r, 0},
                                                {r, 0.03}, {r, tw - 0.03},   {0.80 * r, tw}, {0, tw}};
            const int part[7] = {-1,
                                 RS_SYNTH_PART_RIM,
                                 RS_SYNTH_PART_TYRE,
                                 RS_SYNTH_PART_TYRE,
                                 RS_SYNTH_PART_TYRE,
                                 RS_SYNTH_PART_TYRE,
                                 RS_SYNTH_PART_TYRE};
            add_lathe(b, x, r, tw / 2, pr, part, 8, 0);
        } else {
            const double tw = 0.035, pr[4][2] = {{0.86 * r, 0}, {r, 0}, {r, tw}, {0.86 * r, tw}};
            const int part[4] = {RS_SYNTH_PART_RIM, RS_SYNTH_PART_TYRE, RS_SYNTH_PART_TYRE, RS_SYNTH_PART_RIM};
            add_lathe(b, x, r, tw / 2, pr, part, 4, 1);
            add_bar(b, x - 0.04, r, x + 0.04, r, 0.08, -0.05, 0.05, RS_SYNTH_PART_RIM); // hub
            for (int k = 0; k < 3; k++) {                                               // spokes, seen edge-on
                double a = M_PI * k / 3;
                add_bar(b, x - 0.84 * r * cos(a), r - 0.84 * r * sin(a), x + 0.84 * r * cos(a), r + 0.84 * r * sin(a),
                        0.008, -0.004, 0.004, RS_SYNTH_PART_RIM);
            }
        }
    }
    const double hw = W / 2, grip = hw - 0.06;
    if (motor) {
        const double eng[6][2] = {{-0.25, 0.22}, {0.25, 0.20},  {0.35, 0.45},
                                  {0.25, 0.68},  {-0.20, 0.70}, {-0.30, 0.45}};
        add_prism(b, eng, 6, -0.17, 0.17, RS_SYNTH_PART_RIM); // engine
        const double tank[5][2] = {{-0.12, 0.72}, {0.38, 0.72}, {0.42, 0.90}, {0.25, 0.99}, {-0.08, 0.95}};
        add_prism(b, tank, 5, -0.16, 0.16, P);
        const double seat[4][2] = {{-0.55, 0.76}, {-0.10, 0.76}, {-0.10, 0.88}, {-0.55, 0.86}};
        add_prism(b, seat, 4, -0.14, 0.14, T);
        const double tail[4][2] = {{xr - 0.10, 0.74}, {-0.52, 0.70}, {-0.52, 0.90}, {xr - 0.08, 0.88}};
        add_prism(b, tail, 4, -0.10, 0.10, P);
        add_bar(b, xr - 0.12, 0.78, xr - 0.10, 0.86, 0.04, -0.07, 0.07, RS_SYNTH_PART_TAILLIGHT);
        add_bar(b, xr - 0.14, 0.58, xr - 0.13, 0.70, 0.02, -0.09, 0.09, RS_SYNTH_PART_PLATE);
        add_bar(b, -0.20, 0.35, xr, r, 0.07, -0.12, 0.12, T);           // swing arm
        add_bar(b, 0.10, 0.25, xr + 0.05, 0.42, 0.08, -0.24, -0.15, C); // exhaust
        add_bar(b, xf, r, xf - 0.26, 1.00, 0.05, -0.11, 0.11, C);       // fork
        add_bar(b, xf - 0.30, 1.04, xf - 0.26, 1.06, 0.04, -hw, hw, C); // handlebar
        add_bar(b, xf - 0.14, 0.86, xf - 0.12, 0.98, 0.08, -0.09, 0.09, RS_SYNTH_PART_HEADLIGHT);
        add_bar(b, xf - 0.20, 1.00, xf - 0.30, fmin(1.22, H - 0.25), 0.012, -0.16, 0.16, RS_SYNTH_PART_GLASS);
        // the rider, leaning forward; helmet TRIM
        const double hip_x = -0.30, hip_z = 0.92, sh_x = 0.02, sh_z = H - 0.36, rh = 0.13;
        add_bar(b, hip_x, hip_z, sh_x, sh_z, 0.30, -0.19, 0.19, R);
        add_bar(b, sh_x, sh_z + 0.02, xf - 0.30, 1.05, 0.09, grip - 0.09, grip, R);
        add_bar(b, sh_x, sh_z + 0.02, xf - 0.30, 1.05, 0.09, -grip, -grip + 0.09, R);
        for (int sgn = -1; sgn <= 1; sgn += 2) {
            double y0 = sgn > 0 ? 0.10 : -0.24, y1 = sgn > 0 ? 0.24 : -0.10;
            add_bar(b, hip_x, hip_z, 0.12, 0.68, 0.15, y0, y1, R);
            add_bar(b, 0.12, 0.68, -0.05, 0.30, 0.12, y0, y1, R);
        }
        const double head[7][2] = {{0, 0},     {rh * 0.5, rh * 0.13}, {rh * 0.87, rh * 0.5},
                                   {rh, rh},   {rh * 0.87, rh * 1.5}, {rh * 0.5, rh * 1.87},
                                   {0, 2 * rh}};
        const int hp[6] = {T, T, T, T, T, T};
        add_lathe(b, sh_x + 0.08, H - rh, rh, head, hp, 7, 0);
    } else {
        const double bbx = xr + 0.42, bbz = 0.29, seat_x = xr + 0.26, seat_z = 0.92;
        const double head_x = xf - 0.20, head_z = 0.92, steer_z = 0.74;
        add_bar(b, bbx, bbz, seat_x, seat_z, 0.035, -0.02, 0.02, P);                                  // seat tube
        add_bar(b, seat_x, seat_z - 0.05, head_x, head_z, 0.035, -0.02, 0.02, P);                     // top tube
        add_bar(b, bbx, bbz, head_x + 0.03, steer_z, 0.04, -0.02, 0.02, P);                           // down tube
        add_bar(b, bbx, bbz, xr, r, 0.025, -0.05, 0.05, P);                                           // chain stays
        add_bar(b, seat_x, seat_z - 0.05, xr, r, 0.022, -0.05, 0.05, P);                              // seat stays
        add_bar(b, head_x + 0.04, steer_z, xf, r, 0.03, -0.05, 0.05, C);                              // fork
        add_bar(b, head_x, head_z, head_x - 0.06, 1.06, 0.03, -0.02, 0.02, C);                        // stem
        add_bar(b, head_x - 0.08, 1.05, head_x - 0.04, 1.07, 0.025, -hw, hw, C);                      // handlebar
        add_bar(b, seat_x - 0.12, seat_z + 0.02, seat_x + 0.10, seat_z + 0.03, 0.05, -0.07, 0.07, T); // saddle
        add_bar(b, head_x + 0.02, 0.98, head_x + 0.05, 0.98, 0.05, -0.03, 0.03, RS_SYNTH_PART_HEADLIGHT);
        add_bar(b, seat_x - 0.14, seat_z - 0.08, seat_x - 0.13, seat_z - 0.02, 0.02, -0.03, 0.03,
                RS_SYNTH_PART_TAILLIGHT);
        // the rider, upright; head RIDER (bare or a cap)
        const double hip_x = seat_x, hip_z = seat_z + 0.08, sh_x = seat_x + 0.22, sh_z = H - 0.34, rh = 0.11;
        add_bar(b, hip_x, hip_z, sh_x, sh_z, 0.26, -0.17, 0.17, R);
        add_bar(b, sh_x, sh_z + 0.02, head_x - 0.06, 1.06, 0.08, grip - 0.08, grip, R);
        add_bar(b, sh_x, sh_z + 0.02, head_x - 0.06, 1.06, 0.08, -grip, -grip + 0.08, R);
        for (int sgn = -1; sgn <= 1; sgn += 2) {
            double y0 = sgn > 0 ? 0.05 : -0.17, y1 = sgn > 0 ? 0.17 : -0.05;
            double kx = hip_x + 0.36, kz = 0.62;
            add_bar(b, hip_x, hip_z, kx, kz, 0.13, y0, y1, R);
            add_bar(b, kx, kz, bbx + 0.05 * sgn, bbz - 0.05 * sgn + 0.02, 0.10, y0, y1, R);
        }
        const double head[7][2] = {{0, 0},     {rh * 0.5, rh * 0.13}, {rh * 0.87, rh * 0.5},
                                   {rh, rh},   {rh * 0.87, rh * 1.5}, {rh * 0.5, rh * 1.87},
                                   {0, 2 * rh}};
        const int hp[6] = {R, R, R, R, R, R};
        add_lathe(b, sh_x + 0.06, H - rh, rh, head, hp, 7, 0);
    }
}

rs_status rs_synth_fleet_build(rs_synth_mesh *mesh, const rs_synth_vehicle *v, rs_err *err)
{
    return rs_synth_fleet_build_lod(mesh, v, RS_SYNTH_LOD_FULL, err);
}

rs_status rs_synth_fleet_build_lod(rs_synth_mesh *mesh, const rs_synth_vehicle *v, rs_synth_lod lod, rs_err *err)
{
    return rs_synth_fleet_build_loft(mesh, v, lod, RS_SYNTH_LOFT_TOLERANCE_M, err);
}

rs_status rs_synth_fleet_build_loft(rs_synth_mesh *mesh, const rs_synth_vehicle *v, rs_synth_lod lod,
                                    double loft_tolerance_m, rs_err *err)
{
    memset(mesh, 0, sizeof *mesh);
    if ((int)v->cls < 0 || v->cls >= RS_SYNTH_NCLASSES)
        return rs_err_set(err, RS_ERR_INVALID, "class: %d is not a procedural class", (int)v->cls);
    double L = v->length_m, W = v->width_m, H = v->height_m;
    if (!(L >= 0.5 && W >= 0.3 && H >= 0.5 && L <= 30 && W <= 30 && H <= 30))
        return rs_err_set(err, RS_ERR_INVALID, "dimensions: %g x %g x %g m not resolved (rs_synth_fleet_resolve)", L, W,
                          H);
    rs_rng rng = rs_synth_fleet_stream(v->variant, RS_SYNTH_FLEET_STREAM_SHAPE);
    rs_synth_fleet_builder b = {.nseg = lod == RS_SYNTH_LOD_COARSE ? NSEG_COARSE
                                        : lod                      ? NSEG_MEDIUM
                                                                   : NSEG,
                                .nwheel = lod == RS_SYNTH_LOD_COARSE ? NWHEEL_COARSE
                                          : lod                      ? NWHEEL_MEDIUM
                                                                     : NWHEEL,
                                .loft_tol_m = loft_tolerance_m};
    double r, tw;
    int chrome = rs_rng_uniform(&rng) < 0.35;
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
        // The box's width is the mirrors'; the body is 0.10 m narrower, the tyres flush with it.
        double hb = W / 2 - 0.05;
        body_spec s = car_body(L, hb, H, jit(&rng, clear, 0.02), belt, p, glo, ghi);
        s.tumble = jit(&rng, v->cls == RS_SYNTH_VAN ? 0.10 : 0.25, 0.05);
        s.end_taper = jit(&rng, 0.09, 0.03);
        s.chrome_grille = chrome;
        s.mirrors = 1, s.mirror_y = W / 2;
        if (s.clearance > 0.4 * belt * H) s.clearance = 0.4 * belt * H;
        add_body(&b, &s);
        r = fmin(jit(&rng, v->cls >= RS_SYNTH_SUV ? 0.37 : 0.32, 0.025), 0.25 * H);
        tw = jit(&rng, 0.21, 0.02);
        double of = jit(&rng, 0.19, 0.02) * L, orr = jit(&rng, 0.21, 0.02) * L;
        add_wheel_pair(&b, L / 2 - of, hb + 0.008, tw, r);
        add_wheel_pair(&b, -L / 2 + orr, hb + 0.008, tw, r);
        add_arch_pair(&b, L / 2 - of, r, hb, belt * H - 0.08);
        add_arch_pair(&b, -L / 2 + orr, r, hb, belt * H - 0.08);
        break;
    }
    case RS_SYNTH_BUS: {
        profile p = MAKE_PROFILE(prof_bus);
        body_spec s = {-L / 2,
                       L / 2,
                       W / 2,
                       H,
                       jit(&rng, 0.32, 0.04),
                       jit(&rng, 0.30, 0.03),
                       0.02,
                       0.012,
                       0.02,
                       {0.03, 0.97},
                       p,
                       1,
                       1,
                       1,
                       0,
                       0};
        add_body(&b, &s);
        r = jit(&rng, 0.50, 0.02);
        tw = 0.30;
        double xf = L / 2 - jit(&rng, 2.6, 0.2), xr = -L / 2 + jit(&rng, 3.2, 0.3);
        add_wheel_pair(&b, xf, W / 2 - 0.04, tw, r);
        add_wheel_pair(&b, xr, W / 2 - 0.04, tw, r);
        add_arch_pair(&b, xf, r, W / 2 - 0.004, s.belt * H + 0.3);
        add_arch_pair(&b, xr, r, W / 2 - 0.004, s.belt * H + 0.3);
        break;
    }
    case RS_SYNTH_BOX_TRUCK: {
        double cab_len = jit(&rng, 2.1, 0.15), cab_h = jit(&rng, 0.74, 0.05) * H;
        profile pc = MAKE_PROFILE(prof_cab), pb = MAKE_PROFILE(prof_box);
        jitter_profile(&pc, &rng, 0.01, 0.03);
        body_spec cab = {
            L / 2 - cab_len, L / 2, W / 2 - 0.12, cab_h, 0.45, 0.45, 0.08, 0.05, 0.06, {0.3, 0.95}, pc, 1, 0,
            chrome,          1,     W / 2};
        body_spec box = {-L / 2,
                         L / 2 - cab_len - 0.10,
                         W / 2,
                         H,
                         jit(&rng, 0.95, 0.08),
                         1.0,
                         0.0,
                         0.01,
                         0.01,
                         {2, 2},
                         pb,
                         0,
                         1,
                         0,
                         0,
                         0};
        add_body(&b, &cab);
        add_body(&b, &box);
        r = jit(&rng, 0.48, 0.03);
        tw = 0.28;
        add_wheel_pair(&b, L / 2 - jit(&rng, 1.25, 0.1), W / 2 - 0.10, tw, r);
        add_wheel_pair(&b, -L / 2 + jit(&rng, 0.24, 0.03) * L, W / 2 - 0.06, tw, r);
        break;
    }
    case RS_SYNTH_ARTICULATED_TRUCK: {
        double tl = jit(&rng, 6.0, 0.3), th = jit(&rng, 0.93, 0.04) * H;
        profile pt = MAKE_PROFILE(prof_tractor), pb = MAKE_PROFILE(prof_box);
        jitter_profile(&pt, &rng, 0.01, 0.02);
        body_spec tractor = {L / 2 - tl, L / 2,        W / 2 - 0.09, th, 0.45, 0.52,   0.06, 0.05,
                             0.04,       {0.55, 0.95}, pt,           1,  0,    chrome, 1,    W / 2};
        double trailer_front = L / 2 - tl + jit(&rng, 2.2, 0.2);
        body_spec trailer = {
            -L / 2, trailer_front, W / 2, H, jit(&rng, 1.15, 0.05), 1.0, 0.0, 0.01, 0.005, {2, 2}, pb, 0, 1, 0, 0, 0};
        add_body(&b, &tractor);
        add_body(&b, &trailer);
        r = jit(&rng, 0.50, 0.02);
        tw = 0.30;
        double yw = W / 2 - 0.06;
        add_wheel_pair(&b, L / 2 - 1.35, yw - 0.03, tw, r);
        add_wheel_pair(&b, L / 2 - 1.35 - jit(&rng, 3.7, 0.2), yw - 0.03, tw, r);
        double xa = -L / 2 + jit(&rng, 2.4, 0.3);
        for (int k = 0; k < 3; k++) add_wheel_pair(&b, xa + 1.31 * k, yw, tw, r);
        break;
    }
    case RS_SYNTH_MOTORCYCLE:
    case RS_SYNTH_BICYCLE:
    default: add_two_wheeler(&b, v, &rng); break;
    }
    rs_synth_fleet_smooth(&b, 40);
    if (b.failed) {
        rs_synth_mesh_free(&b.m);
        return rs_err_set(err, RS_ERR_NOMEM, "vehicle mesh: out of memory");
    }
    *mesh = b.m;
    return RS_OK;
}

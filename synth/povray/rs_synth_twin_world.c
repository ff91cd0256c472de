// rs_synth_twin_world.c -- the digital twin's world (synth/povray/internal/rs_synth_twin_world.h): sky, sun and sky
// lights, asphalt, raised sidewalks with kerbs, and the road markings the site's lanes describe
// (lane edges, stop bars, crosswalks, turn arrows). docs/backgrounds.md describes what is drawn
// and where; tests/synth/povray/test_twin_markings.py checks it against lanes.geojson read by numpy.
#include "synth/povray/internal/rs_synth_twin_world.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_units.h"
#include "synth/povray/rs_synth_scene.h"

// Weather appearance: sky light, sun strength, asphalt colour/finish, marking brightness,
// sidewalk (concrete) albedo.
typedef struct {
    const char *name;
    double sky_light, sun, sky_rgb[3], asphalt, asphalt_reflection, marking, concrete;
} weather_look;

static const weather_look looks[] = {
    {"sunny", 0.35, 1.0, {0.45, 0.62, 0.95}, 0.10, 0.0, 0.80, 0.28},
    {"cloudy", 0.80, 0.0, {0.70, 0.72, 0.75}, 0.10, 0.0, 0.80, 0.28},
    {"rain", 0.55, 0.0, {0.55, 0.57, 0.60}, 0.06, 0.15, 0.65, 0.16},
    {"snow", 0.80, 0.0, {0.80, 0.81, 0.83}, 0.75, 0.0, 0.85, 0.80},
    {"night", 0.03, 0.0, {0.01, 0.01, 0.02}, 0.10, 0.0, 0.80, 0.28},
};

const rs_synth_twin_dims rs_synth_twin_dims_default = {
    .crosswalk_gap_m = 0.5,
    .crosswalk_depth_m = 3.0,
    .crosswalk_period_m = 1.0,
    .stop_gap_m = 1.2,
    .stop_depth_m = 0.40,
    .arrow_tip_m = 8.0,
    .arrow_length_m = 5.0,
    .kerb_height_m = 0.12,
    .shoulder_m = 0.5,
    .road_extend_m = 100.0,
};

// ---- lane roles and movements ----

static bool is_junction(const rs_lane *l) { return l->kind && !strcmp(l->kind, "junction"); }

rs_synth_twin_role rs_synth_twin_lane_role(const rs_lanes *lanes, int i)
{
    const rs_lane *l = &lanes->lane[i];
    rs_synth_twin_role r = {0};
    if (is_junction(l)) return r;
    for (int k = 0; k < l->Nnext; k++)
        if (is_junction(&lanes->lane[l->next[k]])) {
            r.enters_junction = true;
            // the turn: the heading at the junction path's end against the lane's last heading
            const rs_lane *j = &lanes->lane[l->next[k]];
            double h0, h1, p[2];
            rs_lane_point(p, &h0, l, rs_lane_length_m(l));
            rs_lane_point(p, &h1, j, rs_lane_length_m(j));
            const double d = remainder(h1 - h0, 360.0);
            if (fabs(d) <= RS_SYNTH_TWIN_STRAIGHT_DEG)
                r.straight = true;
            else if (d < 0)
                r.left = true;
            else
                r.right = true;
        }
    for (int m = 0; m < lanes->N; m++) {
        const rs_lane *o = &lanes->lane[m];
        for (int k = 0; k < o->Nnext; k++)
            if (o->next[k] == i) {
                r.has_predecessor = true;
                if (is_junction(o)) r.leaves_junction = true;
            }
    }
    return r;
}

// ---- writing ----

static void pov_point(FILE *f, double e, double n, double up) { fprintf(f, "<%.9g, %.9g, %.9g>", e, up, n); }

static double ground_up(const rs_site *site, double e, double n)
{
    return rs_synth_ground_up_m(site->ground_normal_enu, site->ground_offset_m, e, n);
}

// A flat quadrilateral (four ENU (e, n) corners in order) 5 mm above the ground, two triangles.
static void quad(FILE *f, const rs_site *site, const double q[4][2])
{
    for (int t = 0; t < 2; t++) {
        const int idx[2][3] = {{0, 1, 2}, {0, 2, 3}};
        fprintf(f, "  triangle { ");
        for (int k = 0; k < 3; k++) {
            const int j = idx[t][k];
            pov_point(f, q[j][0], q[j][1], ground_up(site, q[j][0], q[j][1]) + 0.005);
            fprintf(f, k < 2 ? ", " : " }\n");
        }
    }
}

static void tri(FILE *f, const rs_site *site, const double a[2], const double b[2], const double c[2])
{
    const double *p[3] = {a, b, c};
    fprintf(f, "  triangle { ");
    for (int k = 0; k < 3; k++) {
        pov_point(f, p[k][0], p[k][1], ground_up(site, p[k][0], p[k][1]) + 0.005);
        fprintf(f, k < 2 ? ", " : " }\n");
    }
}

// One lane-edge marking along a polyline offset sideways by `offset_m` (left positive).
static void edge_line(FILE *f, const rs_lane *lane, double offset_m, double half_w, const rs_site *site)
{
    for (int i = 0; i + 1 < lane->Npoints; i++) {
        const double *a = lane->p_enu_m[i], *b = lane->p_enu_m[i + 1];
        const double de = b[0] - a[0], dn = b[1] - a[1], len = hypot(de, dn);
        if (len < 1e-6) continue;
        const double le = -dn / len, ln = de / len; // left normal
        double q[4][2];
        for (int k = 0; k < 4; k++) {
            const double *p = k < 2 ? a : b;
            const double s = offset_m + ((k == 0 || k == 3) ? -half_w : half_w);
            q[k][0] = p[0] + s * le;
            q[k][1] = p[1] + s * ln;
        }
        quad(f, site, q);
    }
}

// A lane-local frame at arc length s: origin, forward and left unit vectors (ENU e, n).
typedef struct {
    double o[2], fw[2], lt[2];
} lane_frame;

static lane_frame frame_at(const rs_lane *lane, double s)
{
    lane_frame F;
    double h;
    rs_lane_point(F.o, &h, lane, s);
    const double r = h * M_PI / 180.0;
    F.fw[0] = sin(r), F.fw[1] = cos(r);
    F.lt[0] = -cos(r), F.lt[1] = sin(r);
    return F;
}

static void at(double p[2], const lane_frame *F, double u, double v)
{
    p[0] = F->o[0] + u * F->fw[0] + v * F->lt[0];
    p[1] = F->o[1] + u * F->fw[1] + v * F->lt[1];
}

// A band across the lane from arc length s0 to s1 (s0 < s1), lateral [v0, v1] (left positive):
// each end placed with the lane's own frame there, so it follows a curve.
static void band(FILE *f, const rs_site *site, const rs_lane *lane, double s0, double s1, double v0, double v1)
{
    const lane_frame A = frame_at(lane, s0), B = frame_at(lane, s1);
    double q[4][2];
    at(q[0], &A, 0, v0);
    at(q[1], &A, 0, v1);
    at(q[2], &B, 0, v1);
    at(q[3], &B, 0, v0);
    quad(f, site, q);
}

// A rectangle in the frame F: u in [u0, u1], v in [v0, v1].
static void rect(FILE *f, const rs_site *site, const lane_frame *F, double u0, double u1, double v0, double v1)
{
    double q[4][2];
    at(q[0], F, u0, v0);
    at(q[1], F, u0, v1);
    at(q[2], F, u1, v1);
    at(q[3], F, u1, v0);
    quad(f, site, q);
}

// The zebra stripes of a crosswalk band [s0, s1] across a lane of width w.
static void crosswalk(FILE *f, const rs_site *site, const rs_lane *lane, double s0, double s1,
                      const rs_synth_twin_dims *D)
{
    int n = (int)lround(lane->width_m / D->crosswalk_period_m);
    if (n < 1) n = 1;
    const double p = lane->width_m / n;
    for (int k = 0; k < n; k++) {
        const double v = -0.5 * lane->width_m + p * (k + 0.5);
        band(f, site, lane, s0, s1, v - 0.25 * p, v + 0.25 * p);
    }
}

// The turn arrow of an approach lane: its tail at arc length s_tail, pointing along the lane,
// with a straight head and/or left/right branches (lane-local shape in rs_synth_twin.h).
static void arrow(FILE *f, const rs_site *site, const rs_lane *lane, double s_tail, rs_synth_twin_role r,
                  const rs_synth_twin_dims *D)
{
    const lane_frame F = frame_at(lane, s_tail);
    const double k = D->arrow_length_m / 5.0; // the shape is drawn for a 5 m arrow, then scaled
    const double hw = 0.10 * k;
    rect(f, site, &F, 0, (r.straight ? 3.4 : 2.1) * k, -hw, hw);
    if (r.straight) {
        double a[2], b[2], c[2];
        at(a, &F, 3.4 * k, -0.45 * k);
        at(b, &F, 5.0 * k, 0);
        at(c, &F, 3.4 * k, 0.45 * k);
        tri(f, site, a, b, c);
    }
    for (int side = -1; side <= 1; side += 2) {
        if (!(side > 0 ? r.left : r.right)) continue;
        const double c45 = sqrt(0.5);
        // branch from (2.0, 0) along (c45, side c45), 0.9 long, then a head 1.1 long
        lane_frame B = F;
        at(B.o, &F, 2.0 * k, 0);
        for (int j = 0; j < 2; j++) B.fw[j] = c45 * F.fw[j] + side * c45 * F.lt[j];
        B.lt[0] = -B.fw[1]; // fw turned 90 degrees to the left
        B.lt[1] = B.fw[0];
        rect(f, site, &B, -hw, 0.9 * k, -hw, hw);
        double a[2], b[2], c[2];
        at(a, &B, 0.9 * k, -0.4 * k);
        at(b, &B, 2.0 * k, 0);
        at(c, &B, 0.9 * k, 0.4 * k);
        tri(f, site, a, b, c);
    }
}

// The markings of every lane: edges of non-junction lanes; at a lane's end into the junction a
// crosswalk, a stop bar and a turn arrow; at an exit's start a crosswalk.
static void write_markings(FILE *f, const rs_site *site, const rs_lanes *lanes, double marking_width_m)
{
    const rs_synth_twin_dims *D = &rs_synth_twin_dims_default;
    for (int i = 0; i < lanes->N; i++) {
        const rs_lane *l = &lanes->lane[i];
        if (is_junction(l)) continue; // paths across the junction carry no markings
        const double hw = 0.5 * l->width_m;
        edge_line(f, l, hw, 0.5 * marking_width_m, site);
        edge_line(f, l, -hw, 0.5 * marking_width_m, site);
        const rs_synth_twin_role r = rs_synth_twin_lane_role(lanes, i);
        const double L = rs_lane_length_m(l);
        const double cw1 = D->crosswalk_gap_m, cw2 = cw1 + D->crosswalk_depth_m;
        if (r.enters_junction) {
            if (L >= cw2) crosswalk(f, site, l, L - cw2, L - cw1, D);
            const double sb1 = cw2 + D->stop_gap_m, sb2 = sb1 + D->stop_depth_m;
            if (L >= sb2) band(f, site, l, L - sb2, L - sb1, -hw, hw);
            const double tail = D->arrow_tip_m + D->arrow_length_m;
            if (L >= tail) arrow(f, site, l, L - tail, r, D);
        }
        if (r.leaves_junction && L >= cw2) crosswalk(f, site, l, cw1, cw2, D);
    }
}

// A closed polygon in the ENU plane (e, n), its first corner not repeated.
typedef struct {
    double (*p)[2]; // (N, 2) owned
    int N;
} polygon;

// The road's outline of one lane: the centre line offset by +-(width/2 + shoulder) with mitred
// corners, extended at open ends. Returns false when out of memory (or fewer than 2 points).
static bool lane_outline(polygon *out, const rs_lane *l, bool extend_start, bool extend_end,
                         const rs_synth_twin_dims *D)
{
    const int n = l->Npoints;
    double(*p)[2] = malloc(sizeof(double[2]) * (size_t)n);
    out->p = malloc(sizeof(double[2]) * (size_t)(2 * n));
    out->N = 0;
    if (!p || !out->p) {
        free(p);
        return false;
    }
    int m = 0;
    for (int i = 0; i < n; i++) {
        if (m > 0 && hypot(l->p_enu_m[i][0] - p[m - 1][0], l->p_enu_m[i][1] - p[m - 1][1]) < 1e-6) continue;
        p[m][0] = l->p_enu_m[i][0], p[m][1] = l->p_enu_m[i][1], m++;
    }
    if (m < 2) {
        free(p);
        return false;
    }
    if (extend_start) {
        const double de = p[0][0] - p[1][0], dn = p[0][1] - p[1][1], L = hypot(de, dn);
        p[0][0] += de / L * D->road_extend_m, p[0][1] += dn / L * D->road_extend_m;
    }
    if (extend_end) {
        const double de = p[m - 1][0] - p[m - 2][0], dn = p[m - 1][1] - p[m - 2][1], L = hypot(de, dn);
        p[m - 1][0] += de / L * D->road_extend_m, p[m - 1][1] += dn / L * D->road_extend_m;
    }
    const double h = 0.5 * l->width_m + D->shoulder_m;
    for (int side = 0; side < 2; side++)
        for (int t = 0; t < m; t++) {
            const int i = side ? m - 1 - t : t;
            // mitred normal: the mean of the adjacent segments' left normals
            double nl[2] = {0, 0};
            for (int s = i - 1; s <= i; s++) {
                if (s < 0 || s + 1 >= m) continue;
                const double de = p[s + 1][0] - p[s][0], dn = p[s + 1][1] - p[s][1], L = hypot(de, dn);
                nl[0] += -dn / L, nl[1] += de / L;
            }
            const double nn = hypot(nl[0], nl[1]);
            nl[0] /= nn, nl[1] /= nn;
            double scale = h;
            if (i > 0) {
                const double de = p[i][0] - p[i - 1][0], dn = p[i][1] - p[i - 1][1], L = hypot(de, dn);
                const double c = (-dn / L) * nl[0] + (de / L) * nl[1];
                scale = h / fmax(c, 0.5); // mitre, limited to twice the half-width
            }
            const double sgn = side ? -1.0 : 1.0;
            out->p[out->N][0] = p[i][0] + sgn * scale * nl[0];
            out->p[out->N][1] = p[i][1] + sgn * scale * nl[1];
            out->N++;
        }
    free(p);
    return true;
}

static int cmp_pt(const void *a, const void *b)
{
    const double *p = a, *q = b;
    return p[0] < q[0] ? -1 : p[0] > q[0] ? 1 : p[1] < q[1] ? -1 : p[1] > q[1];
}

static double cross(const double o[2], const double a[2], const double b[2])
{
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

// The convex hull of the junction paths' points (Andrew's monotone chain), so the junction's
// interior is road even where no path passes. Returns false when there is none.
static bool junction_hull(polygon *out, const rs_lanes *lanes)
{
    int n = 0;
    out->p = NULL;
    out->N = 0;
    for (int i = 0; i < lanes->N; i++)
        if (is_junction(&lanes->lane[i])) n += lanes->lane[i].Npoints;
    if (n < 3) return false;
    double(*p)[2] = malloc(sizeof(double[2]) * (size_t)n), (*h)[2] = malloc(sizeof(double[2]) * (size_t)(2 * n + 1));
    if (!p || !h) {
        free(p);
        free(h);
        return false;
    }
    n = 0;
    for (int i = 0; i < lanes->N; i++)
        if (is_junction(&lanes->lane[i]))
            for (int k = 0; k < lanes->lane[i].Npoints; k++)
                p[n][0] = lanes->lane[i].p_enu_m[k][0], p[n][1] = lanes->lane[i].p_enu_m[k][1], n++;
    qsort(p, (size_t)n, sizeof(double[2]), cmp_pt);
    int k = 0;
    for (int i = 0; i < n; i++) {
        while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) k--;
        h[k][0] = p[i][0], h[k][1] = p[i][1], k++;
    }
    for (int i = n - 2, t = k + 1; i >= 0; i--) {
        while (k >= t && cross(h[k - 2], h[k - 1], p[i]) <= 0) k--;
        h[k][0] = p[i][0], h[k][1] = p[i][1], k++;
    }
    free(p);
    if (k < 4) { // a closed hull has k - 1 >= 3 distinct corners, the first repeated at the end
        free(h);
        return false;
    }
    out->p = h;
    out->N = k - 1;
    return true;
}

// Even-odd point in polygon.
static bool inside(const polygon *P, double e, double n)
{
    bool in = false;
    for (int i = 0, j = P->N - 1; i < P->N; j = i++) {
        const double *a = P->p[i], *b = P->p[j];
        if ((a[1] > n) != (b[1] > n) && e < (b[0] - a[0]) * (n - a[1]) / (b[1] - a[1]) + a[0]) in = !in;
    }
    return in;
}

// The kerbs: one vertical quad (ground to kh) per run of 0.1 m samples of an outline's edge
// that lie inside no other outline. Writes nothing with f NULL; returns the number of quads.
static int kerb_faces(FILE *f, const rs_site *site, const polygon *P, int NP, double kh)
{
    int Nruns = 0;
    const double step = 0.1;
    for (int k = 0; k < NP; k++)
        for (int i = 0; i < P[k].N; i++) {
            const double *a = P[k].p[i], *b = P[k].p[(i + 1) % P[k].N];
            const double L = hypot(b[0] - a[0], b[1] - a[1]);
            const int ns = (int)ceil(L / step);
            int run0 = -1; // the first sample of the current run of exposed samples
            for (int s = 0; s <= ns; s++) {
                bool exposed = false;
                if (s < ns) {
                    const double tm = (s + 0.5) / ns;
                    const double me = a[0] + tm * (b[0] - a[0]), mn = a[1] + tm * (b[1] - a[1]);
                    exposed = true;
                    for (int o = 0; o < NP && exposed; o++) exposed = o == k || !inside(&P[o], me, mn);
                }
                if (exposed && run0 < 0) run0 = s;
                if (exposed || run0 < 0) continue;
                // one quad for the run [run0, s)
                const double t0 = (double)run0 / ns, t1 = (double)s / ns;
                run0 = -1;
                const double e0 = a[0] + t0 * (b[0] - a[0]), n0 = a[1] + t0 * (b[1] - a[1]);
                const double e1 = a[0] + t1 * (b[0] - a[0]), n1 = a[1] + t1 * (b[1] - a[1]);
                const double g0 = ground_up(site, e0, n0), g1 = ground_up(site, e1, n1);
                Nruns++;
                if (!f) continue;
                fprintf(f, "  triangle { ");
                pov_point(f, e0, n0, g0);
                fprintf(f, ", ");
                pov_point(f, e1, n1, g1);
                fprintf(f, ", ");
                pov_point(f, e1, n1, g1 + kh);
                fprintf(f, " }\n  triangle { ");
                pov_point(f, e0, n0, g0);
                fprintf(f, ", ");
                pov_point(f, e1, n1, g1 + kh);
                fprintf(f, ", ");
                pov_point(f, e0, n0, g0 + kh);
                fprintf(f, " }\n");
            }
        }
    return Nruns;
}

// Sidewalks: the ground raised by the kerb height, clipped away over the road (every lane's
// outline and the junction's hull: POV-Ray prisms, inverse), and kerbs: vertical faces along
// the parts of each outline that lie inside no other outline (sampled every 0.1 m).
// (A CSG difference of the raised ground and the prisms draws the same but traces 5 x slower.)
static void write_sidewalks(FILE *f, const rs_site *site, const rs_lanes *lanes, const weather_look *look)
{
    const rs_synth_twin_dims *D = &rs_synth_twin_dims_default;
    polygon *P = calloc((size_t)lanes->N + 1, sizeof(polygon));
    if (!P) return;
    int NP = 0;
    for (int i = 0; i < lanes->N; i++) {
        const rs_lane *l = &lanes->lane[i];
        const rs_synth_twin_role r = rs_synth_twin_lane_role(lanes, i);
        if (lane_outline(&P[NP], l, !r.has_predecessor && !is_junction(l), l->Nnext == 0 && !is_junction(l), D))
            NP++;
        else
            free(P[NP].p);
    }
    if (junction_hull(&P[NP], lanes)) NP++;
    if (!NP) { // no usable outline: no sidewalks
        free(P);
        return;
    }
    const double *nrm = site->ground_normal_enu;
    const double nn = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
    const double c = look->concrete, kh = D->kerb_height_m;
    fprintf(f,
            "// sidewalks %.3g m above the road outside it; the road: every lane's outline (+%.3g m shoulder)\n"
            "plane { <%.17g, %.17g, %.17g>, %.17g\n"
            "  texture { pigment { bozo scale 1.5 pigment_map {\n"
            "      [0 granite scale 0.02 color_map { [0 rgb %.4g] [1 rgb %.4g] }]\n"
            "      [1 granite scale 0.02 color_map { [0 rgb %.4g] [1 rgb %.4g] }] } }\n"
            "            normal { granite 0.1 scale 0.03 } finish { ambient 0 diffuse 0.8 } }\n"
            "  clipped_by { union {\n",
            kh, D->shoulder_m, nrm[0] / nn, nrm[2] / nn, nrm[1] / nn, site->ground_offset_m / nn + kh * nrm[2] / nn,
            0.8 * c, 1.0 * c, 0.9 * c, 1.15 * c);
    for (int k = 0; k < NP; k++) {
        double lo = INFINITY, hi = -INFINITY;
        for (int i = 0; i < P[k].N; i++) {
            const double g = ground_up(site, P[k].p[i][0], P[k].p[i][1]);
            lo = fmin(lo, g), hi = fmax(hi, g);
        }
        fprintf(f, "    prism { linear_sweep linear_spline %.9g, %.9g, %d", lo - 0.01, hi + kh + 0.01, P[k].N + 1);
        for (int i = 0; i <= P[k].N; i++) fprintf(f, ", <%.9g, %.9g>", P[k].p[i % P[k].N][0], P[k].p[i % P[k].N][1]);
        fprintf(f, " }\n");
    }
    fprintf(f, "  inverse } }\n}\n");
    if (kerb_faces(NULL, site, P, NP, kh) > 0) {
        fprintf(f, "// kerbs\nmesh {\n");
        kerb_faces(f, site, P, NP, kh);
        fprintf(f,
                "  texture { pigment { granite color_map { [0 rgb %.4g] [1 rgb %.4g] } scale 0.02 }\n"
                "            finish { ambient 0 diffuse 0.8 } }\n}\n",
                1.0 * c, 1.3 * c);
    }
    for (int k = 0; k < NP; k++) free(P[k].p);
    free(P);
}

bool rs_synth_twin_weather_ok(const char *weather)
{
    for (size_t i = 0; i < sizeof(looks) / sizeof(looks[0]); i++)
        if (weather && !strcmp(weather, looks[i].name)) return true;
    return false;
}

rs_status rs_synth_twin_world_write(FILE *f, const rs_site *site, const rs_lanes *lanes, const char *weather,
                                    double sun_az, double sun_el, double marking_width_m, bool sky_shadows, rs_err *err)
{
    const weather_look *look = NULL;
    for (size_t i = 0; i < sizeof(looks) / sizeof(looks[0]); i++)
        if (weather && !strcmp(weather, looks[i].name)) look = &looks[i];
    if (!look)
        return rs_err_set(err, RS_ERR_INVALID, "weather: '%s' is not one of sunny, cloudy, rain, snow, night",
                          weather ? weather : "");
    fprintf(f, "background { rgb <%.4g, %.4g, %.4g> }\n", look->sky_rgb[0], look->sky_rgb[1], look->sky_rgb[2]);
    const double az = sun_az * RS_RAD_PER_DEG, el = sun_el * RS_RAD_PER_DEG;
    if (look->sun > 0 && sun_el > 0) {
        fprintf(f, "// sun: azimuth %.6g deg, elevation %.6g deg\nlight_source { ", sun_az, sun_el);
        pov_point(f, 1e6 * sin(az) * cos(el), 1e6 * cos(az) * cos(el), 1e6 * sin(el));
        fprintf(f, " color rgb <1.0, 0.97, 0.92> parallel point_at <0, 0, 0> }\n");
    }
    // The sky: the scene's own 7 parallel lights (rs_synth_scene.h: one at the zenith, six at
    // zenith 60 deg, 0.413 and 0.587 of the irradiance on the ground), casting shadows, so that
    // kerbs get the soft shadow of a sky. Their irradiance on horizontal ground sums to sky_light.
    {
        const double edge = sin(40.0 * RS_RAD_PER_DEG) * sin(40.0 * RS_RAD_PER_DEG);
        const double zen[2] = {0, 60}, share[2] = {edge, 1.0 - edge};
        const int count[2] = {1, 6};
        fprintf(f, "// sky: %.4g on horizontal ground, %d parallel lights\n", look->sky_light, RS_SYNTH_SKY_LIGHTS);
        for (int b = 0; b < 2; b++)
            for (int k = 0; k < count[b]; k++) {
                const double z = zen[b] * RS_RAD_PER_DEG, a = 60.0 * k * RS_RAD_PER_DEG;
                fprintf(f, "light_source { ");
                pov_point(f, 1e6 * sin(a) * sin(z), 1e6 * cos(a) * sin(z), 1e6 * cos(z));
                fprintf(f, " color rgb %.6g parallel point_at <0, 0, 0>%s }\n",
                        look->sky_light * share[b] / count[b] / cos(z), sky_shadows ? "" : " shadowless");
            }
    }
    const double *nrm = site->ground_normal_enu;
    const double nn = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
    const double a0 = look->asphalt;
    // asphalt: fine granite grain, a bump map, lighter and darker patches (bozo, 4 m), and
    // sharp-edged darker repairs where the patch pattern is above 0.78
    fprintf(f,
            "plane { <%.17g, %.17g, %.17g>, %.17g\n"
            "  texture {\n"
            "    pigment { bozo scale 4 turbulence 0.4 pigment_map {\n"
            "      [0.00 granite scale 0.05 color_map { [0 rgb %.4g] [1 rgb %.4g] }]\n"
            "      [0.78 granite scale 0.05 color_map { [0 rgb %.4g] [1 rgb %.4g] }]\n"
            "      [0.78 granite scale 0.03 color_map { [0 rgb %.4g] [1 rgb %.4g] }]\n"
            "      [1.00 granite scale 0.03 color_map { [0 rgb %.4g] [1 rgb %.4g] }] } }\n"
            "    normal { granite 0.25 scale 0.015 }\n"
            "    finish { ambient 0 diffuse 0.8 reflection %.3g } } }\n",
            nrm[0] / nn, nrm[2] / nn, nrm[1] / nn, site->ground_offset_m / nn, a0 * 0.75, a0 * 1.15, a0 * 0.9, a0 * 1.3,
            a0 * 0.6, a0 * 0.8, a0 * 0.6, a0 * 0.8, look->asphalt_reflection);
    // the site's poles (landmarks with a height: lamp and signal posts): grey cylinders 0.16 m
    // thick from 0.2 m below their surveyed base to their top, casting shadows
    int Npoles = 0;
    for (int i = 0; i < site->Nlandmarks; i++) {
        const rs_site_landmark *L = &site->landmarks[i];
        const double *b = L->vertices_enu_m;
        if (L->shape != RS_SITE_POLE || !b || !isfinite(b[0] + b[1] + b[2]) || !(L->pole_height_m > 0)) continue;
        if (!Npoles++) fprintf(f, "// poles\nunion {\n");
        fprintf(f, "  cylinder { ");
        pov_point(f, b[0], b[1], b[2] - 0.2);
        fprintf(f, ", ");
        pov_point(f, b[0], b[1], b[2] + L->pole_height_m);
        fprintf(f, ", 0.08 }\n");
    }
    if (Npoles) fprintf(f, "  texture { pigment { rgb 0.35 } finish { ambient 0 diffuse 0.7 specular 0.2 } }\n}\n");
    if (lanes && lanes->N > 0) {
        write_sidewalks(f, site, lanes, look);
        const double m = look->marking;
        bool any = false; // a mesh needs a triangle: only junction paths draw none
        for (int i = 0; i < lanes->N; i++) any = any || !is_junction(&lanes->lane[i]);
        if (any) {
            fprintf(f, "// road markings: lane edges, crosswalks, stop bars, arrows (%d lanes)\nmesh {\n", lanes->N);
            write_markings(f, site, lanes, marking_width_m);
            // worn paint: a fine granite between 0.75 and 1 of the marking's albedo
            fprintf(
                f,
                "  texture { pigment { granite scale 0.04 color_map { [0 rgb %.4g] [0.6 rgb %.4g] [1 rgb %.4g] } }\n"
                "            finish { ambient 0 diffuse 0.8 } }\n"
                "  no_shadow\n}\n",
                0.75 * m, m, m);
        }
    }
    return ferror(f) ? rs_err_set(err, RS_ERR_IO, "write error") : RS_OK;
}

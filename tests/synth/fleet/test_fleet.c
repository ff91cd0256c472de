// tests/synth/fleet/test_fleet.c -- the procedural fleet and OBJ import, checked on the written mesh2:
// box = declared dimensions within 1 mm (parsed back from the POV-Ray text), closed and outward
// (every edge used once in each direction, positive signed volume per connected part), no
// zero-area triangle, deterministic, >= 200 distinct variants, colour shares, OBJ conversion
// (assimp) and its error messages.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "synth/fleet/rs_synth_fleet.h"
#include "tests/synth/test_fleet_check.h"

// Parses every "vertex_vectors { N, <a, b, c>, ... }" of a POV-Ray text and returns the bounds
// of the vertices mapped back to the vehicle frame (x_v = z_pov, y_v = -x_pov, z_v = y_pov).
static int parse_pov_bounds(const char *text, double lo[3], double hi[3])
{
    int count = 0;
    for (const char *p = text; (p = strstr(p, "vertex_vectors {"));) {
        p += strlen("vertex_vectors {");
        int n = (int)strtol(p, (char **)&p, 10);
        for (int i = 0; i < n; i++) {
            double a, b, c;
            p = strchr(p, '<');
            if (!p || sscanf(p, "<%lf, %lf, %lf>", &a, &b, &c) != 3) return -1;
            p++;
            double v[3] = {c, -a, b};
            for (int k = 0; k < 3; k++) {
                if (!isfinite(v[k])) return -1;
                if (count == 0 || v[k] < lo[k]) lo[k] = v[k];
                if (count == 0 || v[k] > hi[k]) hi[k] = v[k];
            }
            count++;
        }
    }
    return count;
}

static char *declare_text(const rs_synth_mesh *m, rs_synth_declare_style style, const double *rgb)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    rs_err err = {0};
    rs_status st = rs_synth_fleet_write_declare(f, "VEHICLE_1", m, style, rgb, &err);
    fclose(f);
    CHECK(st == RS_OK, "write_declare: %s", err.msg);
    return buf;
}

static int cmp_edge(const void *a, const void *b)
{
    const long long *x = a, *y = b;
    return (*x > *y) - (*x < *y);
}

static int find(int *parent, int i)
{
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
}

// Closed, consistently wound, outward (signed volume of every connected part > 0), no
// zero-area triangle. Returns the number of problems.
static int check_closed_outward(const rs_synth_mesh *m, const char *what)
{
    int bad = 0;
    long long *e = malloc((size_t)m->Ntri * 3 * sizeof *e);
    for (int t = 0; t < m->Ntri; t++)
        for (int k = 0; k < 3; k++) e[3 * t + k] = (long long)m->tri[t][k] * m->Nv + m->tri[t][(k + 1) % 3];
    qsort(e, (size_t)m->Ntri * 3, sizeof *e, cmp_edge);
    for (int i = 0; i < 3 * m->Ntri; i++) {
        long long a = e[i] / m->Nv, b = e[i] % m->Nv, rev = b * m->Nv + a;
        if (i > 0 && e[i] == e[i - 1]) bad++;                                   // used twice
        if (!bsearch(&rev, e, (size_t)m->Ntri * 3, sizeof *e, cmp_edge)) bad++; // open edge
    }
    free(e);
    CHECK(bad == 0, "%s: %d edges not paired with their reverse exactly once", what, bad);
    int *parent = malloc((size_t)m->Nv * sizeof *parent);
    double *vol = calloc((size_t)m->Nv, sizeof *vol);
    for (int i = 0; i < m->Nv; i++) parent[i] = i;
    for (int t = 0; t < m->Ntri; t++)
        for (int k = 1; k < 3; k++) parent[find(parent, m->tri[t][k])] = find(parent, m->tri[t][0]);
    int degenerate = 0;
    for (int t = 0; t < m->Ntri; t++) {
        const double *a = m->v[m->tri[t][0]], *b = m->v[m->tri[t][1]], *c = m->v[m->tri[t][2]];
        double u[3], w[3], n[3];
        for (int k = 0; k < 3; k++) u[k] = b[k] - a[k], w[k] = c[k] - a[k];
        n[0] = u[1] * w[2] - u[2] * w[1];
        n[1] = u[2] * w[0] - u[0] * w[2];
        n[2] = u[0] * w[1] - u[1] * w[0];
        if (0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) < 1e-7) degenerate++;
        vol[find(parent, m->tri[t][0])] += (a[0] * n[0] + a[1] * n[1] + a[2] * n[2]) / 6;
    }
    int negative = 0, parts = 0;
    for (int i = 0; i < m->Nv; i++)
        if (find(parent, i) == i) {
            parts++;
            if (!(vol[i] > 1e-6)) negative++;
        }
    CHECK(degenerate == 0, "%s: %d triangles with area < 1e-7 m^2", what, degenerate);
    CHECK(negative == 0, "%s: %d of %d connected parts with volume <= 0 (inward)", what, negative, parts);
    free(parent);
    free(vol);
    return bad + degenerate + negative;
}

static unsigned long long hash_mesh(const rs_synth_mesh *m, const double rgb[3])
{
    unsigned long long h = 1469598103934665603ull;
    for (int i = 0; i < m->Nv; i++)
        for (int k = 0; k < 3; k++) {
            long long q = llround(m->v[i][k] * 1e6);
            h = (h ^ (unsigned long long)q) * 1099511628211ull;
        }
    for (int k = 0; k < 3; k++) h = (h ^ (unsigned long long)llround(rgb[k] * 1e6)) * 1099511628211ull;
    return h;
}

static int cmp_u64(const void *a, const void *b)
{
    const unsigned long long *x = a, *y = b;
    return (*x > *y) - (*x < *y);
}

static void test_fleet(void)
{
    enum { N = 400 };
    unsigned long long hashes[N];
    int per_class[RS_SYNTH_NCLASSES] = {0};
    double worst = 0, tri_full = 0, tri_coarse = 0, tri_medium = 0;
    for (int s = 0; s < N; s++) {
        rs_synth_vehicle v;
        rs_err err = {0};
        // the first NCLASSES * 10 seeds cover every class; then the traffic mix
        if (s < RS_SYNTH_NCLASSES * 10) {
            rs_synth_vehicle in = {
                .cls = (rs_synth_class)(s % RS_SYNTH_NCLASSES), .variant = (uint64_t)s, .rgb = {-1, -1, -1}};
            CHECK(rs_synth_fleet_resolve(&v, &in, &err) == RS_OK, "seed %d: %s", s, err.msg);
        } else
            CHECK(rs_synth_fleet_random(&v, (uint64_t)s, &err) == RS_OK, "seed %d: %s", s, err.msg);
        per_class[v.cls]++;
        rs_synth_class_range r;
        CHECK(rs_synth_class_range_get(&r, v.cls, NULL) == RS_OK, "range");
        CHECK(v.length_m >= r.length_m[0] && v.length_m <= r.length_m[1] && v.width_m >= r.width_m[0] &&
                  v.width_m <= r.width_m[1] && v.height_m >= r.height_m[0] && v.height_m <= r.height_m[1],
              "seed %d: dimensions out of the class range", s);
        rs_synth_mesh m, m2;
        CHECK(rs_synth_fleet_build(&m, &v, &err) == RS_OK, "seed %d: build: %s", s, err.msg);
        CHECK(rs_synth_fleet_build(&m2, &v, &err) == RS_OK, "seed %d: build: %s", s, err.msg);
        CHECK(m.Nv == m2.Nv && m.Ntri == m2.Ntri && memcmp(m.v, m2.v, (size_t)m.Nv * sizeof *m.v) == 0,
              "seed %d: not deterministic", s);
        rs_synth_mesh_free(&m2);
        char what[64];
        snprintf(what, sizeof what, "seed %d (%s)", s, rs_synth_class_name(v.cls));
        double mlo[3], mhi[3]; // in memory: exact (1e-9 m)
        rs_synth_mesh_bounds(mlo, mhi, &m);
        CHECK(fabs(mlo[0] + v.length_m / 2) < 1e-9 && fabs(mhi[0] - v.length_m / 2) < 1e-9 &&
                  fabs(mlo[1] + v.width_m / 2) < 1e-9 && fabs(mhi[1] - v.width_m / 2) < 1e-9 && fabs(mlo[2]) < 1e-9 &&
                  fabs(mhi[2] - v.height_m) < 1e-9,
              "%s: mesh bounds [%g %g %g] [%g %g %g] are not the box", what, mlo[0], mlo[1], mlo[2], mhi[0], mhi[1],
              mhi[2]);
        check_closed_outward(&m, what);
        int parts_seen[RS_SYNTH_NPARTS] = {0};
        for (int t = 0; t < m.Ntri; t++) parts_seen[m.part[t]] = 1;
        CHECK(parts_seen[RS_SYNTH_PART_PAINT] && parts_seen[RS_SYNTH_PART_TYRE] &&
                  parts_seen[RS_SYNTH_PART_HEADLIGHT] && parts_seen[RS_SYNTH_PART_TAILLIGHT] &&
                  (parts_seen[RS_SYNTH_PART_GLASS] || v.cls == RS_SYNTH_BICYCLE) && parts_seen[RS_SYNTH_PART_RIM] &&
                  (parts_seen[RS_SYNTH_PART_PLATE] || v.cls == RS_SYNTH_BICYCLE),
              "%s: a part is missing", what);
        for (int style = 0; style < 2; style++) {
            char *text = declare_text(&m, (rs_synth_declare_style)style, v.rgb);
            double lo[3], hi[3];
            int n = parse_pov_bounds(text, lo, hi);
            CHECK(n > 0, "%s: no vertices parsed", what);
            double want_lo[3] = {-v.length_m / 2, -v.width_m / 2, 0};
            double want_hi[3] = {v.length_m / 2, v.width_m / 2, v.height_m};
            for (int k = 0; k < 3; k++) {
                double d = fmax(fabs(lo[k] - want_lo[k]), fabs(hi[k] - want_hi[k]));
                worst = fmax(worst, d);
                CHECK(d < 1e-3, "%s: axis %d: mesh2 box [%.6f, %.6f], declared [%.6f, %.6f]", what, k, lo[k], hi[k],
                      want_lo[k], want_hi[k]);
            }
            free(text);
        }
        // the coarser levels of detail: the same box exactly, closed and outward, every part;
        // against the full level with every station of the loft (rs_synth_fleet_build_loft, no
        // tolerance): coarse at most a third of the triangles (two-wheelers, mostly thin bars:
        // two thirds), medium at most two thirds (two-wheelers: three quarters), and more than
        // coarse
        rs_synth_mesh mx;
        CHECK(rs_synth_fleet_build_loft(&mx, &v, RS_SYNTH_LOD_FULL, -1, &err) == RS_OK, "seed %d: exact: %s", s,
              err.msg);
        const int Nexact = mx.Ntri;
        rs_synth_mesh_free(&mx);
        int Ncoarse = 0;
        for (int lod = RS_SYNTH_LOD_COARSE; lod >= RS_SYNTH_LOD_MEDIUM; lod--) {
            const char *level = lod == RS_SYNTH_LOD_COARSE ? "coarse" : "medium";
            rs_synth_mesh mc;
            CHECK(rs_synth_fleet_build_lod(&mc, &v, (rs_synth_lod)lod, &err) == RS_OK, "seed %d: %s: %s", s, level,
                  err.msg);
            double clo[3], chi[3];
            rs_synth_mesh_bounds(clo, chi, &mc);
            CHECK(fabs(clo[0] + v.length_m / 2) < 1e-9 && fabs(chi[0] - v.length_m / 2) < 1e-9 &&
                      fabs(clo[1] + v.width_m / 2) < 1e-9 && fabs(chi[1] - v.width_m / 2) < 1e-9 &&
                      fabs(clo[2]) < 1e-9 && fabs(chi[2] - v.height_m) < 1e-9,
                  "%s: %s mesh bounds [%g %g %g] [%g %g %g] are not the box", what, level, clo[0], clo[1], clo[2],
                  chi[0], chi[1], chi[2]);
            check_closed_outward(&mc, what);
            int lod_parts[RS_SYNTH_NPARTS] = {0};
            for (int t = 0; t < mc.Ntri; t++) lod_parts[mc.part[t]] = 1;
            CHECK(memcmp(lod_parts, parts_seen, sizeof parts_seen) == 0, "%s: the %s mesh has other parts", what,
                  level);
            const int two_wheeler = v.cls == RS_SYNTH_MOTORCYCLE || v.cls == RS_SYNTH_BICYCLE;
            if (lod == RS_SYNTH_LOD_COARSE) {
                CHECK((two_wheeler ? 3 * mc.Ntri <= 2 * Nexact : 3 * mc.Ntri <= Nexact),
                      "%s: coarse %d triangles vs %d", what, mc.Ntri, Nexact);
                tri_coarse += mc.Ntri;
                Ncoarse = mc.Ntri;
            } else {
                CHECK((two_wheeler ? 4 * mc.Ntri <= 3 * Nexact : 3 * mc.Ntri <= 2 * Nexact) && mc.Ntri > Ncoarse,
                      "%s: medium %d triangles vs %d full, %d coarse", what, mc.Ntri, Nexact, Ncoarse);
                tri_medium += mc.Ntri;
            }
            rs_synth_mesh_free(&mc);
        }
        tri_full += m.Ntri;
        hashes[s] = hash_mesh(&m, v.rgb);
        rs_synth_mesh_free(&m);
    }
    qsort(hashes, N, sizeof hashes[0], cmp_u64);
    int distinct = 1;
    for (int i = 1; i < N; i++) distinct += hashes[i] != hashes[i - 1];
    CHECK(distinct == N, "%d distinct variants of %d", distinct, N);
    for (int c = 0; c < RS_SYNTH_NCLASSES; c++)
        CHECK(per_class[c] >= 10, "class %s drawn %d times", rs_synth_class_name(c), per_class[c]);
    printf("fleet: %d vehicles, %d distinct, worst mesh2 box error %.2g m; medium meshes: %.1f%%, coarse meshes: "
           "%.1f%% of the triangles\n",
           N, distinct, worst, 100.0 * tri_medium / tri_full, 100.0 * tri_coarse / tri_full);
}

// The closest point of triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5): its
// squared distance.
static double dist2_point_triangle(const double p[3], const double a[3], const double b[3], const double c[3])
{
    double ab[3], ac[3], ap[3], q[3];
    for (int k = 0; k < 3; k++) ab[k] = b[k] - a[k], ac[k] = c[k] - a[k], ap[k] = p[k] - a[k];
#define DOT(u, w) ((u)[0] * (w)[0] + (u)[1] * (w)[1] + (u)[2] * (w)[2])
    const double d1 = DOT(ab, ap), d2 = DOT(ac, ap);
    double bp[3], cp[3];
    for (int k = 0; k < 3; k++) bp[k] = p[k] - b[k], cp[k] = p[k] - c[k];
    const double d3 = DOT(ab, bp), d4 = DOT(ac, bp), d5 = DOT(ab, cp), d6 = DOT(ac, cp);
#undef DOT
    const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
    if (d1 <= 0 && d2 <= 0)
        memcpy(q, a, sizeof q);
    else if (d3 >= 0 && d4 <= d3)
        memcpy(q, b, sizeof q);
    else if (d6 >= 0 && d5 <= d6)
        memcpy(q, c, sizeof q);
    else if (vc <= 0 && d1 >= 0 && d3 <= 0)
        for (int k = 0; k < 3; k++) q[k] = a[k] + d1 / (d1 - d3) * ab[k];
    else if (vb <= 0 && d2 >= 0 && d6 <= 0)
        for (int k = 0; k < 3; k++) q[k] = a[k] + d2 / (d2 - d6) * ac[k];
    else if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        for (int k = 0; k < 3; k++) q[k] = b[k] + w * (c[k] - b[k]);
    } else {
        const double den = 1 / (va + vb + vc), v = vb * den, w = vc * den;
        for (int k = 0; k < 3; k++) q[k] = a[k] + ab[k] * v + ac[k] * w;
    }
    return (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]);
}

static void part_areas(double area[RS_SYNTH_NPARTS], const rs_synth_mesh *m)
{
    memset(area, 0, sizeof(double) * RS_SYNTH_NPARTS);
    for (int t = 0; t < m->Ntri; t++) {
        const double *a = m->v[m->tri[t][0]], *b = m->v[m->tri[t][1]], *c = m->v[m->tri[t][2]];
        const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        const double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        area[m->part[t]] += 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    }
}

// The loft's tolerance (RS_SYNTH_LOFT_TOLERANCE_M): against the same vehicle with every station
// (brute force over all triangles), every vertex of the exact mesh lies within 0.6 mm of the
// default mesh, each part's area is within 0.5 % (the windows and lights where they were), the
// box is the same; a car loses at least a fifth of its triangles.
static void test_loft_tolerance(void)
{
    double worst = 0, saved = 0;
    int Nveh = 0;
    for (int s = 0; s < 3 * RS_SYNTH_NCLASSES; s++) {
        rs_synth_vehicle in = {.cls = (rs_synth_class)(s % RS_SYNTH_NCLASSES),
                               .variant = (uint64_t)(1000 + s),
                               .rgb = {-1, -1, -1}},
                         v;
        rs_err err = {0};
        CHECK(rs_synth_fleet_resolve(&v, &in, &err) == RS_OK, "loft seed %d: %s", s, err.msg);
        for (int lod = RS_SYNTH_LOD_FULL; lod <= RS_SYNTH_LOD_COARSE; lod++) {
            rs_synth_mesh ex, de;
            CHECK(rs_synth_fleet_build_loft(&ex, &v, (rs_synth_lod)lod, -1, &err) == RS_OK, "loft %d: %s", s, err.msg);
            CHECK(rs_synth_fleet_build_lod(&de, &v, (rs_synth_lod)lod, &err) == RS_OK, "loft %d: %s", s, err.msg);
            const char *cls = rs_synth_class_name(v.cls);
            double lo[3], hi[3], lo2[3], hi2[3];
            rs_synth_mesh_bounds(lo, hi, &ex);
            rs_synth_mesh_bounds(lo2, hi2, &de);
            for (int k = 0; k < 3; k++)
                CHECK(fabs(lo[k] - lo2[k]) < 1e-12 && fabs(hi[k] - hi2[k]) < 1e-12, "loft %d (%s): box axis %d", s, cls,
                      k);
            double far2 = 0;
            for (int i = 0; i < ex.Nv; i++) {
                double best = INFINITY;
                for (int t = 0; t < de.Ntri && best > 1e-14; t++) {
                    const double d2 =
                        dist2_point_triangle(ex.v[i], de.v[de.tri[t][0]], de.v[de.tri[t][1]], de.v[de.tri[t][2]]);
                    if (d2 < best) best = d2;
                }
                if (best > far2) far2 = best;
            }
            worst = fmax(worst, sqrt(far2));
            CHECK(sqrt(far2) <= 0.0006, "loft %d (%s, level %d): a vertex of the exact mesh is %.2f mm off", s, cls,
                  lod, 1e3 * sqrt(far2));
            double ae[RS_SYNTH_NPARTS], ad[RS_SYNTH_NPARTS];
            part_areas(ae, &ex);
            part_areas(ad, &de);
            for (int p = 0; p < RS_SYNTH_NPARTS; p++)
                CHECK(fabs(ad[p] - ae[p]) <= 0.005 * ae[p] + 1e-9, "loft %d (%s, level %d): part %d area %.5f vs %.5f",
                      s, cls, lod, p, ad[p], ae[p]);
            const bool car = v.cls <= RS_SYNTH_VAN;
            if (lod == RS_SYNTH_LOD_FULL && car) {
                CHECK(5 * de.Ntri <= 4 * ex.Ntri, "loft %d (%s): %d triangles of %d", s, cls, de.Ntri, ex.Ntri);
                saved += 1 - (double)de.Ntri / ex.Ntri;
                Nveh++;
            }
            rs_synth_mesh_free(&ex);
            rs_synth_mesh_free(&de);
        }
    }
    printf("loft tolerance: every exact vertex within %.3f mm; cars at full detail: %.0f %% fewer triangles\n",
           1e3 * worst, 100 * saved / (Nveh ? Nveh : 1));
}

static void test_resolve_and_colours(void)
{
    // Given values are kept, the others drawn; the same variant gives the same draws.
    rs_synth_vehicle in = {.cls = RS_SYNTH_SEDAN, .length_m = 4.5, .variant = 7, .rgb = {-1, 0, 0}};
    rs_synth_vehicle a, b;
    CHECK(rs_synth_fleet_resolve(&a, &in, NULL) == RS_OK, "resolve");
    in.length_m = 0;
    CHECK(rs_synth_fleet_resolve(&b, &in, NULL) == RS_OK, "resolve");
    CHECK(a.length_m == 4.5 && a.width_m == b.width_m && a.height_m == b.height_m && a.rgb[0] == b.rgb[0],
          "given length changed the other draws");
    in.height_m = -1;
    rs_err err = {0};
    CHECK(rs_synth_fleet_resolve(&a, &in, &err) == RS_ERR_INVALID && strstr(err.msg, "height"), "negative height: %s",
          err.msg);
    // Colour shares (Axalta 2022): white 34 %, black 21 % (seeded, 20000 draws, +-1.5 %).
    int white = 0, black = 0, n = 20000;
    for (int s = 0; s < n; s++) {
        rs_synth_vehicle r;
        CHECK(rs_synth_fleet_random(&r, (uint64_t)s + 1000000, NULL) == RS_OK, "random");
        double m = (r.rgb[0] + r.rgb[1] + r.rgb[2]) / 3;
        white += m > 0.7;
        black += m < 0.02;
    }
    CHECK(fabs(white / (double)n - 0.34) < 0.015, "white share %.3f, want 0.34 (seeds 1000000+)", white / (double)n);
    CHECK(fabs(black / (double)n - 0.21) < 0.015, "black share %.3f, want 0.21 (seeds 1000000+)", black / (double)n);
    printf("colours: white %.3f black %.3f of %d\n", white / (double)n, black / (double)n, n);
    rs_synth_class c;
    CHECK(rs_synth_class_from_name(&c, "box_truck", NULL) == RS_OK && c == RS_SYNTH_BOX_TRUCK, "class name");
    CHECK(rs_synth_class_from_name(&c, "tank", &err) == RS_ERR_NOT_FOUND && strstr(err.msg, "sedan"),
          "unknown class: %s", err.msg);
}

static void test_declare_names(void)
{
    rs_synth_vehicle v;
    rs_synth_mesh m;
    CHECK(rs_synth_fleet_random(&v, 3, NULL) == RS_OK && rs_synth_fleet_build(&m, &v, NULL) == RS_OK, "build");
    const char *bad[] = {"car", "A\"B", "A#B", "A\nB", "", "A B", "ABCDEFGHIJKLMNOPQRSTUVWXYZABCDEFGHIJKLMNO"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char *buf = NULL;
        size_t len = 0;
        FILE *f = open_memstream(&buf, &len);
        CHECK(rs_synth_fleet_write_declare(f, bad[i], &m, RS_SYNTH_DECLARE_BARE, NULL, NULL) == RS_ERR_INVALID,
              "name %zu accepted", i);
        fclose(f);
        CHECK(len == 0, "name %zu: something written", i);
        free(buf);
    }
    // Placement: the rotation POV-Ray applies (rotate y by yaw) agrees with rs_synth_vehicle_to_enu.
    v.yaw_deg = 30;
    v.e_m = 10;
    v.n_m = -5;
    double p_v[3] = {2, 1, 0.5}, p_enu[3];
    rs_synth_vehicle_to_enu(p_enu, &v, 100, p_v);
    // POV-Ray: declared point (x, y, z)_pov = (-y_v, z_v, x_v); rotate about y by a:
    // x' = x cos a + z sin a, z' = -x sin a + z cos a; then translate <e, up, n>.
    double a = 30 * M_PI / 180, x = -p_v[1], z = p_v[0];
    double e = x * cos(a) + z * sin(a) + 10, n = -x * sin(a) + z * cos(a) - 5;
    CHECK(fabs(e - p_enu[0]) < 1e-12 && fabs(n - p_enu[1]) < 1e-12 && p_enu[2] == 100.5,
          "placement: POV-Ray (%g, %g) vs ENU (%g, %g)", e, n, p_enu[0], p_enu[1]);
    rs_synth_mesh_free(&m);
    rs_synth_mesh_free(NULL);
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    fputs(text, f);
    fclose(f);
}

static void test_obj(const char *dir)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/tiny.obj", dir);
    // A unit cube in centimetres, y up, front towards -z; quads, negative indices and normals.
    write_text(path, "# tiny cube\no cube\n"
                     "v 0 0 0\nv 200 0 0\nv 200 100 0\nv 0 100 0\n"
                     "v 0 0 400\nv 200 0 400\nv 200 100 400\nv 0 100 400\n"
                     "vn 0 0 -1\nvn 0 0 1\nvn -1 0 0\nvn 1 0 0\nvn 0 -1 0\nvn 0 1 0\n"
                     "f 1//1 4//1 3//1 2//1\nf 5//2 6//2 7//2 8//2\n"
                     "f 1//3 5//3 8//3 4//3\nf 2//4 3//4 7//4 6//4\n"
                     "f 1//5 2//5 6//5 5//5\nf -5//6 -1//6 -2//6 -6//6\n");
    rs_synth_obj_spec spec = {.path = path, .scale = 0.01, .forward = "-z", .up = "+y"};
    rs_synth_mesh m;
    rs_err err = {0};
    CHECK(rs_synth_obj_load(&m, &spec, &err) == RS_OK, "obj: %s", err.msg);
    if (m.Ntri) {
        CHECK(m.Ntri == 12 && m.vn != NULL, "obj: %d triangles, normals %p", m.Ntri, (void *)m.vn);
        double lo[3], hi[3];
        char *text = declare_text(&m, RS_SYNTH_DECLARE_BARE, NULL);
        CHECK(parse_pov_bounds(text, lo, hi) == 24, "obj: mesh2 vertex count");
        CHECK(strstr(text, "normal_vectors") && strstr(text, "normal_indices"), "obj: normals");
        free(text);
        // 4 m long (OBJ z), 2 m wide (OBJ x), 1 m high (OBJ y); footprint centred, bottom at 0
        double want_lo[3] = {-2, -1, 0}, want_hi[3] = {2, 1, 1};
        for (int k = 0; k < 3; k++)
            CHECK(fabs(lo[k] - want_lo[k]) < 1e-9 && fabs(hi[k] - want_hi[k]) < 1e-9, "obj: axis %d box [%g, %g]", k,
                  lo[k], hi[k]);
        // Forward is OBJ -z: the OBJ face at z = 0 (normal (0,0,-1)) is the vehicle's front,
        // x_v = +2, and its normal maps to +x_v.
        for (int t = 0; t < m.Ntri; t++)
            for (int k = 0; k < 3; k++)
                if (fabs(m.v[m.tri[t][k]][0] - 2) < 1e-9 && fabs(m.vn[m.tri[t][k]][0] - 1) < 1e-9) goto found;
        CHECK(0, "obj: front face (OBJ z = 0) not at x_v = +2 with normal +x_v");
    found:; // (a label is followed by a statement in C11)
        // winding agrees with the OBJ's normals (outward)
        int inward = 0;
        for (int t = 0; t < m.Ntri; t++) {
            const double *a = m.v[m.tri[t][0]], *b = m.v[m.tri[t][1]], *c = m.v[m.tri[t][2]];
            double u[3], w[3];
            for (int k = 0; k < 3; k++) u[k] = b[k] - a[k], w[k] = c[k] - a[k];
            double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
            const double *vn = m.vn[m.tri[t][0]];
            inward += n[0] * vn[0] + n[1] * vn[1] + n[2] * vn[2] <= 0;
        }
        CHECK(inward == 0, "obj: %d triangles wound against their normals", inward);
    }
    rs_synth_mesh_free(&m);
    // Errors name the file and carry assimp's message (it reads the model since issue 40; its
    // OBJ reader names no line).
    struct {
        const char *text, *want;
    } bad[] = {
        {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "tiny.obj: assimp: OBJ: vertex index out of range"},
        {"v 0 0 0\nv 1 0 zero\n", "tiny.obj: assimp: "},
        {"v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2\n", "tiny.obj: assimp: "},
        {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/x\n", "tiny.obj: assimp: OBJ: Invalid face index"},
        {"v 0 0 0\n", "tiny.obj: assimp: OBJ-file is too small"},
        {"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "no face with a non-zero area"},
        {"\x89PNG not a model at all, just some bytes of text\n", "tiny.obj: assimp: "},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        write_text(path, bad[i].text);
        rs_status st = rs_synth_obj_load(&m, &spec, &err);
        CHECK(st != RS_OK && strstr(err.msg, bad[i].want), "bad obj %zu: got '%s', want '%s'", i, err.msg, bad[i].want);
        CHECK(m.Nv == 0 && m.v == NULL, "bad obj %zu: mesh not zeroed", i);
    }
    rs_synth_obj_spec bad_axes = {.path = path, .scale = 1, .forward = "+y", .up = "+y"};
    CHECK(rs_synth_obj_load(&m, &bad_axes, &err) == RS_ERR_INVALID && strstr(err.msg, "up"), "same axes: %s", err.msg);
    spec.path = "/nonexistent/x.obj";
    CHECK(rs_synth_obj_load(&m, &spec, &err) == RS_ERR_IO, "missing file: %s", err.msg);
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : ".";
    test_fleet();
    test_loft_tolerance();
    test_resolve_and_colours();
    test_declare_names();
    test_obj(dir);
    if (failures) fprintf(stderr, "%d failures (seeds as printed)\n", failures);
    return failures ? 1 : 0;
}

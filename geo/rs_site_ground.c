// rs_site_ground.c -- the ground model of a site (geo/rs_site.h, rs_site_ground_model): the
// heights of landmarks whose height is unreliable or unknown, from a plane fitted robustly to the
// heights that can be trusted (or the site's ground_plane), with the plane's own uncertainty. The
// reader calls it once every landmark is in ENU (rs_site__ground_model,
// geo/internal/rs_site_internal.h); it calls the report (rs_site__diag), the geodesy
// (rs_geo_llh_to_enu) and core's random generator (the fixed-seed draws of the robust start).
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_io.h"
#include "core/rs_rng.h"
#include "core/rs_stats.h"
#include "geo/internal/rs_site_internal.h"

// The robust start tries every triple of up to ALL_TRIPLES_MAX points, else DRAWN_TRIPLES triples
// drawn from a fixed seed, each scored on at most SCORE_POINTS_MAX points (a fixed draw): the cost
// stays O(N) for a million landmarks.
enum { ALL_TRIPLES_MAX = 24, DRAWN_TRIPLES = 600, SCORE_POINTS_MAX = 4096, MAX_ITERATIONS = 50, MAX_NAMED = 10 };
static const uint64_t SEED = 0x67726f756e64ULL; // "ground"

// Points closer to a line than this (RMS across the principal direction, metres), or flatter
// than this ratio of the two spreads, do not fix a plane.
#define COLLINEAR_SPREAD_M 0.01
#define COLLINEAR_RATIO    1e-3
// The ground_plane's normal must be at least this close to vertical to give heights (84 deg).
#define SITE_PLANE_NZ_MIN  0.1

// ---- small numerics ----

// Inverse of a symmetric positive definite 3x3 (row-major) by cofactors; false if singular.
static bool inverse3(double out[9], const double m[9])
{
    const double c00 = m[4] * m[8] - m[5] * m[7], c01 = m[5] * m[6] - m[3] * m[8], c02 = m[3] * m[7] - m[4] * m[6];
    const double det = m[0] * c00 + m[1] * c01 + m[2] * c02;
    if (!(fabs(det) > 0) || !isfinite(det)) return false;
    out[0] = c00 / det;
    out[1] = (m[2] * m[7] - m[1] * m[8]) / det;
    out[2] = (m[1] * m[5] - m[2] * m[4]) / det;
    out[3] = c01 / det;
    out[4] = (m[0] * m[8] - m[2] * m[6]) / det;
    out[5] = (m[2] * m[3] - m[0] * m[5]) / det;
    out[6] = c02 / det;
    out[7] = (m[1] * m[6] - m[0] * m[7]) / det;
    out[8] = (m[0] * m[4] - m[1] * m[3]) / det;
    return true;
}

// ---- the plane ----

// A plane fitted to the heights of points idx[0..n) of p (ENU, 3 per point).
typedef struct {
    double centre[2], up, slope[2];
    double AtA_inv[9]; // (A^T A)^-1 for the rows (1, de, dn)
    double rss;
} plane_fit;

static double plane_up(const plane_fit *f, const double *p)
{
    return f->up + f->slope[0] * (p[0] - f->centre[0]) + f->slope[1] * (p[1] - f->centre[1]);
}

// True when the horizontal positions of idx[0..n) fix a plane: at least 3, not on one line.
static bool spread_ok(const double *p, const int *idx, int n)
{
    if (n < 3) return false;
    double c[2] = {0, 0}, s[3] = {0, 0, 0};
    for (int i = 0; i < n; i++)
        for (int k = 0; k < 2; k++) c[k] += p[3 * idx[i] + k] / n;
    for (int i = 0; i < n; i++) {
        const double de = p[3 * idx[i]] - c[0], dn = p[3 * idx[i] + 1] - c[1];
        s[0] += de * de / n, s[1] += de * dn / n, s[2] += dn * dn / n;
    }
    // eigenvalues of [[s0, s1], [s1, s2]]
    const double mean = 0.5 * (s[0] + s[2]), d = sqrt(0.25 * (s[0] - s[2]) * (s[0] - s[2]) + s[1] * s[1]);
    const double lmin = mean - d, lmax = mean + d;
    return lmin >= COLLINEAR_SPREAD_M * COLLINEAR_SPREAD_M && lmin >= COLLINEAR_RATIO * COLLINEAR_RATIO * lmax;
}

// Least squares over idx[0..n) (n >= 3, spread_ok). False if the normal equations are singular.
static bool fit_plane(plane_fit *f, const double *p, const int *idx, int n)
{
    double c[2] = {0, 0};
    for (int i = 0; i < n; i++)
        for (int k = 0; k < 2; k++) c[k] += p[3 * idx[i] + k] / n;
    double AtA[9] = {0}, Atb[3] = {0};
    for (int i = 0; i < n; i++) {
        const double *q = &p[3 * idx[i]];
        const double x[3] = {1, q[0] - c[0], q[1] - c[1]};
        for (int a = 0; a < 3; a++) {
            Atb[a] += x[a] * q[2];
            for (int b = 0; b < 3; b++) AtA[3 * a + b] += x[a] * x[b];
        }
    }
    if (!inverse3(f->AtA_inv, AtA)) return false;
    double sol[3];
    for (int a = 0; a < 3; a++)
        sol[a] = f->AtA_inv[3 * a] * Atb[0] + f->AtA_inv[3 * a + 1] * Atb[1] + f->AtA_inv[3 * a + 2] * Atb[2];
    f->centre[0] = c[0], f->centre[1] = c[1];
    f->up = sol[0], f->slope[0] = sol[1], f->slope[1] = sol[2];
    f->rss = 0;
    for (int i = 0; i < n; i++) {
        const double r = p[3 * idx[i] + 2] - plane_up(f, &p[3 * idx[i]]);
        f->rss += r * r;
    }
    return isfinite(f->rss);
}

// The plane through three points; false when they (nearly) lie on one line.
static bool plane_through(plane_fit *f, const double *a, const double *b, const double *c)
{
    const double e1 = b[0] - a[0], n1 = b[1] - a[1], u1 = b[2] - a[2];
    const double e2 = c[0] - a[0], n2 = c[1] - a[1], u2 = c[2] - a[2];
    const double det = e1 * n2 - e2 * n1; // twice the triangle's area
    const double scale = (e1 * e1 + n1 * n1) + (e2 * e2 + n2 * n2);
    if (!(fabs(det) > 1e-6 * scale) || !(scale > 0)) return false;
    f->centre[0] = a[0], f->centre[1] = a[1], f->up = a[2];
    f->slope[0] = (u1 * n2 - u2 * n1) / det;
    f->slope[1] = (e1 * u2 - e2 * u1) / det;
    return isfinite(f->slope[0]) && isfinite(f->slope[1]);
}

// The robust fit over the points p[0..n) (n >= 3, spread_ok): least median of squares over
// triples, then least squares on the points within REJECT_K sigmas until stable, the sigma of
// point i being the robust one (1.4826 x the median absolute residual of all points x
// sqrt(n / (n - 3)), the residuals' shrinkage by the fit undone) or its own,
// floor_m[i], whichever is larger: a point is never left out for a residual its stated noise
// explains. out: *f, keep[0..n) (true: used). Returns the number used, 0 when no plane could be
// fitted, -1 when out of memory.
static int robust_fit(plane_fit *f, bool *keep, const double *p, const double *floor_m, int n)
{
    double *r = malloc((size_t)n * sizeof *r), *work = malloc((size_t)n * sizeof *work);
    int *used = malloc((size_t)n * sizeof *used), *score = NULL;
    bool *next = malloc((size_t)n * sizeof *next);
    int nkept = -1;
    if (!r || !work || !used || !next) goto done;
    for (int i = 0; i < n; i++) keep[i] = true;
    if (n > 3) {
        // the start: the plane through three of the points with the least median squared
        // residual, scored on all points or on a fixed draw of SCORE_POINTS_MAX of them
        rs_rng rng;
        rs_rng_seed(&rng, SEED);
        int nscore = n;
        if (n > SCORE_POINTS_MAX) {
            if (!(score = malloc(SCORE_POINTS_MAX * sizeof *score))) goto done;
            for (int i = 0; i < SCORE_POINTS_MAX; i++) score[i] = (int)(rs_rng_u64(&rng) % (uint64_t)n);
            nscore = SCORE_POINTS_MAX;
        }
        double best = INFINITY;
        plane_fit start = {0};
        const long ntriples = n <= ALL_TRIPLES_MAX ? (long)n * (n - 1) * (n - 2) / 6 : DRAWN_TRIPLES;
        int t[3] = {0, 1, 2};
        for (long k = 0; k < ntriples; k++) {
            if (n <= ALL_TRIPLES_MAX) { // the k-th triple in lexicographic order
                if (k > 0) {
                    int j = 2;
                    while (t[j] == n - 3 + j) j--;
                    t[j]++;
                    for (int m = j + 1; m < 3; m++) t[m] = t[m - 1] + 1;
                }
            } else {
                do {
                    for (int m = 0; m < 3; m++) t[m] = (int)(rs_rng_u64(&rng) % (uint64_t)n);
                } while (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]);
            }
            plane_fit g;
            if (!plane_through(&g, &p[3 * t[0]], &p[3 * t[1]], &p[3 * t[2]])) continue;
            for (int i = 0; i < nscore; i++) {
                const double *q = &p[3 * (score ? score[i] : i)];
                const double d = q[2] - plane_up(&g, q);
                work[i] = d * d;
            }
            const double m = rs_stats_median(work, nscore);
            if (m < best) best = m, start = g;
        }
        if (isfinite(best)) { // Rousseeuw's scale of the LMedS residuals, small-sample corrected
            const double sigma = 1.4826 * (1 + 5.0 / (n - 3)) * sqrt(best);
            int m = 0;
            for (int i = 0; i < n; i++)
                if ((next[i] = fabs(p[3 * i + 2] - plane_up(&start, &p[3 * i])) <=
                               RS_SITE_GROUND_REJECT_K * fmax(sigma, floor_m[i])))
                    used[m++] = i;
            if (spread_ok(p, used, m)) memcpy(keep, next, (size_t)n * sizeof *keep);
        }
    }
    nkept = 0;
    for (int it = 0; it < MAX_ITERATIONS; it++) {
        int m = 0;
        for (int i = 0; i < n; i++)
            if (keep[i]) used[m++] = i;
        plane_fit g;
        if (!fit_plane(&g, p, used, m)) { // cannot happen for a set that passed spread_ok
            nkept = 0;
            break;
        }
        *f = g;
        nkept = m;
        if (n == 3) break;
        for (int i = 0; i < n; i++) work[i] = r[i] = fabs(p[3 * i + 2] - plane_up(f, &p[3 * i]));
        // the residuals of a least-squares plane are shrunk by sqrt((n - 3) / n): undone
        const double sigma = 1.4826 * rs_stats_median(work, n) * sqrt((double)n / (n - 3));
        int k = 0;
        bool same = true;
        for (int i = 0; i < n; i++) {
            next[i] = r[i] <= RS_SITE_GROUND_REJECT_K * fmax(sigma, floor_m[i]);
            same = same && next[i] == keep[i];
            if (next[i]) used[k++] = i;
        }
        if (same || !spread_ok(p, used, k) || it == MAX_ITERATIONS - 1) break; // keep[] is *f's set
        memcpy(keep, next, (size_t)n * sizeof *keep);
    }
done:
    free(r);
    free(work);
    free(used);
    free(next);
    free(score);
    return nkept;
}

// ---- the public face ----

void rs_site_ground_predict(double *up_m, double *sigma_plane_m, const rs_site_ground_model *m, double e_m, double n_m)
{
    double up = NAN, sigma = NAN;
    if (m->source != RS_SITE_GROUND_NONE) {
        const double x[3] = {1, e_m - m->centre_en_m[0], n_m - m->centre_en_m[1]};
        up = m->up_m + m->slope[0] * x[1] + m->slope[1] * x[2];
        double v = 0;
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) v += x[a] * m->cov[3 * a + b] * x[b];
        sigma = sqrt(fmax(v, 0));
    }
    if (up_m) *up_m = up;
    if (sigma_plane_m) *sigma_plane_m = sigma;
}

// ---- the reader's part ----

static bool usable(const rs_site_landmark *l)
{
    return isfinite(l->p_enu_m[0]) && isfinite(l->p_enu_m[1]) && isfinite(l->llh.lat_deg) && isfinite(l->llh.lon_deg);
}

static bool modelled(const rs_site_landmark *l)
{
    return l->height == RS_SITE_HEIGHT_UNRELIABLE || l->height == RS_SITE_HEIGHT_UNKNOWN;
}

// The heights a plane can rest on are those of points, of pole bases and of every vertex of a
// line (a lane marking or kerb surveyed vertex by vertex is the ground there): Nvertices per
// landmark (a zeroed struct counts as one).
static int nvertices(const rs_site_landmark *l) { return l->Nvertices > 0 ? l->Nvertices : 1; }

// Collects the vertices of the landmarks of height kind `h` on the ground with a usable given
// height: their landmark indices into idx and vertex indices into vtx, their ENU (east, north,
// given up) into p, 3 per point, and the least sigma that may leave them out of the fit into
// floor_m: hypot(stated sigma_v, SCATTER_MIN). Until the model is applied, a vertex's ENU is
// its given position.
static int candidates(int *idx, int *vtx, double *p, double *floor_m, const rs_site *site, rs_site_height h)
{
    int n = 0;
    for (int i = 0; i < site->Nlandmarks; i++) {
        const rs_site_landmark *l = &site->landmarks[i];
        if (l->height != h || l->above_ground_m != 0 || !usable(l) || !isfinite(l->given_up_m)) continue;
        for (int k = 0; k < nvertices(l); k++) {
            const double *q = k == 0 || !l->vertices_enu_m ? l->p_enu_m : &l->vertices_enu_m[3 * k];
            const double up = k == 0 ? l->given_up_m : q[2];
            if (!isfinite(up)) continue;
            p[3 * n] = q[0], p[3 * n + 1] = q[1], p[3 * n + 2] = up;
            floor_m[n] = hypot(l->given_sigma_v_m, RS_SITE_GROUND_SCATTER_MIN_M);
            vtx[n] = k;
            idx[n++] = i;
        }
    }
    return n;
}

// Fits the plane to the candidates (idx, p)[0..n) into the model. keep: (n,) scratch, out: the
// points used. Returns 1 on success, 0 when no plane fits, -1 when out of memory.
static int fit_model(rs_site_ground_model *m, bool *keep, rs_site *site, const int *idx, const double *p,
                     const double *floor_m, int n)
{
    plane_fit f;
    const int nused = robust_fit(&f, keep, p, floor_m, n);
    if (nused < 3) return nused < 0 ? -1 : 0;
    double stated2 = 0;
    for (int i = 0; i < n; i++) {
        rs_site_landmark *l = &site->landmarks[idx[i]];
        l->ground_used = l->ground_used || keep[i];
        if (keep[i]) stated2 += l->given_sigma_v_m * l->given_sigma_v_m / nused;
    }
    m->Ncandidates = n;
    m->Nused = nused;
    m->centre_en_m[0] = f.centre[0], m->centre_en_m[1] = f.centre[1];
    m->up_m = f.up;
    m->slope[0] = f.slope[0], m->slope[1] = f.slope[1];
    m->rms_m = nused > 3 ? sqrt(f.rss / (nused - 3)) : NAN;
    m->stated_sigma_m = sqrt(stated2);
    m->scale_m = nused > 3 ? fmax(m->rms_m, m->stated_sigma_m) : m->stated_sigma_m;
    for (int k = 0; k < 9; k++) m->cov[k] = m->scale_m * m->scale_m * f.AtA_inv[k];
    const double floor2 = RS_SITE_GROUND_SCATTER_MIN_M * RS_SITE_GROUND_SCATTER_MIN_M;
    m->scatter_m = nused > 3 ? sqrt(fmax(m->rms_m * m->rms_m - stated2, floor2)) : RS_SITE_GROUND_SCATTER_MIN_M;
    return 1;
}

// Moves the height of one position (llh_io, p_enu_io: (3,) each) onto the model, above_ground_m
// above it, keeping its lat and lon; out: its vertical sigma.
static bool apply_one(double llh_io[3], double p_enu_io[3], double *sigma_v_m, const rs_site_landmark *l,
                      const rs_site *site, const rs_site_ground_model *m)
{
    double llh[3] = {llh_io[0], llh_io[1], llh_io[2]}, p[3];
    if (!isfinite(llh[2])) llh[2] = site->origin.h_m;
    double sigma_plane = 0;
    // the up direction at the point is within a milliradian of the origin's within 6 km: each
    // step shrinks the height error a thousandfold
    for (int k = 0; k < 3; k++) {
        if (rs_geo_llh_to_enu(p, &site->origin, llh, 1, NULL) != RS_OK) return false;
        double up;
        rs_site_ground_predict(&up, &sigma_plane, m, p[0], p[1]);
        llh[2] += up + l->above_ground_m - p[2];
    }
    if (rs_geo_llh_to_enu(p, &site->origin, llh, 1, NULL) != RS_OK || !isfinite(p[2])) return false;
    llh_io[2] = llh[2];
    memcpy(p_enu_io, p, sizeof p);
    *sigma_v_m = m->source == RS_SITE_GROUND_SITE_PLANE ? l->given_sigma_v_m
                                                        : sqrt(sigma_plane * sigma_plane + m->scatter_m * m->scatter_m);
    return true;
}

// Moves landmark l's height onto the model (keeping its lat and lon), with its sigma: every
// vertex of a line, a pole's base (its top stays pole_height_m above it).
static bool apply(rs_site_landmark *l, const rs_site *site, const rs_site_ground_model *m)
{
    double llh[3] = {l->llh.lat_deg, l->llh.lon_deg, l->llh.h_m}, p[3], sigma;
    if (!apply_one(llh, p, &sigma, l, site, m)) return false;
    for (int k = 1; k < l->Nvertices; k++) {
        rs_llh *v = &l->vertices_llh[k];
        double vllh[3] = {v->lat_deg, v->lon_deg, v->h_m}, vp[3];
        if (!apply_one(vllh, vp, &l->vertices_sigma_v_m[k], l, site, m)) return false;
        v->h_m = vllh[2];
        memcpy(&l->vertices_enu_m[3 * k], vp, sizeof vp);
    }
    l->llh.h_m = llh[2];
    memcpy(l->p_enu_m, p, sizeof p);
    l->sigma_v_m = sigma;
    if (l->Nvertices > 0) { // vertex 0 is the landmark's own position
        l->vertices_llh[0] = l->llh;
        memcpy(l->vertices_enu_m, p, sizeof p);
        l->vertices_sigma_v_m[0] = sigma;
    }
    l->height_modelled = true;
    return true;
}

static const char *source_text(rs_site_ground_source s)
{
    switch (s) {
    case RS_SITE_GROUND_FIT_SURVEYED: return "the plane fitted to the surveyed heights";
    case RS_SITE_GROUND_FIT_UNRELIABLE: return "the plane fitted to the unreliable heights";
    case RS_SITE_GROUND_SITE_PLANE: return "the site's ground_plane";
    default: return "no ground model";
    }
}

// Warnings for the candidates (idx, vtx, p)[0..n) left out of the fit (the first MAX_NAMED by
// name; a line's vertex by its index).
static void report_rejected(rs_site__report *r, const rs_site *site, const rs_site_ground_model *m, const int *idx,
                            const int *vtx, const double *p, const bool *keep, int n, const char *landmarks_path)
{
    int named = 0;
    for (int i = 0; i < n; i++) {
        if (keep[i]) continue;
        const rs_site_landmark *l = &site->landmarks[idx[i]];
        double up;
        rs_site_ground_predict(&up, NULL, m, p[3 * i], p[3 * i + 1]);
        const double d = p[3 * i + 2] - up;
        char field[48] = "coordinates";
        if (l->shape == RS_SITE_LINE) snprintf(field, sizeof field, "coordinates[%d]", vtx[i]);
        if (named++ < MAX_NAMED)
            rs_site__diag(r, RS_SITE_WARNING, RS_OK, landmarks_path, 0, l->feature, l->id, field,
                          "height %.2f m %s %s: left out of that fit as an outlier (a wrong height, or a point "
                          "above the ground: say so with properties.above_ground_m)",
                          fabs(d), d > 0 ? "above" : "below", source_text(m->source));
    }
    if (named > MAX_NAMED)
        rs_site__diag(r, RS_SITE_WARNING, RS_OK, landmarks_path, 0, -1, NULL, NULL,
                      "%d more heights left out of the ground fit as outliers (%d in all, of %d)", named - MAX_NAMED,
                      named, n);
}

// Given unreliable heights against the model: warnings for those off by more than DISAGREE_K
// sigmas (the first MAX_NAMED by name) and one summary.
static void report_disagreement(rs_site__report *r, rs_site *site, const char *landmarks_path, const char *site_path)
{
    rs_site_ground_model *m = &site->ground;
    double sum = 0, max_abs = 0;
    int n = 0;
    for (int i = 0; i < site->Nlandmarks; i++) {
        const rs_site_landmark *l = &site->landmarks[i];
        if (!l->height_modelled || l->height != RS_SITE_HEIGHT_UNRELIABLE || !isfinite(l->given_up_m)) continue;
        for (int k = 0; k < nvertices(l); k++) {
            // a line's further vertices: the difference of the heights, which is that of up to 1e-6
            // relative within 6 km of the origin
            const double d = k == 0 ? l->given_up_m - l->p_enu_m[2] : l->vertices_given_h_m[k] - l->vertices_llh[k].h_m;
            const double sigma_v = k == 0 ? l->sigma_v_m : l->vertices_sigma_v_m[k];
            const double sigma = sqrt(l->given_sigma_v_m * l->given_sigma_v_m + sigma_v * sigma_v);
            if (!isfinite(d)) continue;
            sum += d, n++;
            max_abs = fmax(max_abs, fabs(d));
            if (!(fabs(d) > RS_SITE_GROUND_DISAGREE_K * sigma)) continue;
            char field[48] = "coordinates";
            if (l->shape == RS_SITE_LINE) snprintf(field, sizeof field, "coordinates[%d]", k);
            if (m->Ndisagree++ < MAX_NAMED)
                rs_site__diag(
                    r, RS_SITE_WARNING, RS_OK, landmarks_path, 0, l->feature, l->id, field,
                    "the given (unreliable) height is %.2f m %s %s, more than %g sigma (%.2f m: stated %.2g m, "
                    "model %.2g m); its modelled height is used",
                    fabs(d), d > 0 ? "above" : "below", source_text(m->source), RS_SITE_GROUND_DISAGREE_K,
                    RS_SITE_GROUND_DISAGREE_K * sigma, l->given_sigma_v_m, sigma_v);
        }
    }
    m->mean_given_minus_model_m = n ? sum / n : NAN;
    m->max_abs_given_minus_model_m = n ? max_abs : NAN;
    if (m->Ndisagree)
        rs_site__diag(r, RS_SITE_WARNING, RS_OK, site_path, 0, -1, NULL, "landmark_heights",
                      "%d of %d given unreliable heights differ from %s by more than %g sigma (their stated sigma_v "
                      "and the model's); mean given - model %+.2f m, largest %.2f m: heights in another system "
                      "(\"heights\": ellipsoidal vs orthometric and its N)? stated sigmas too small?",
                      m->Ndisagree, n, source_text(m->source), RS_SITE_GROUND_DISAGREE_K, m->mean_given_minus_model_m,
                      m->max_abs_given_minus_model_m);
}

// ---- heights nobody declared ----

// The judgement needs this many heights on the ground (7 degrees of freedom about the plane).
enum { JUDGE_MIN_HEIGHTS = 10 };
// The heights' statement is tested at one-sided alpha 0.1 %, the standard normal's 99.9 % point:
// the level of the calibration's own outlier tests (docs/calibration.md, section 3).
#define JUDGE_Z               3.090
// Heights yield to the plane they show only when it predicts them this many times more precisely
// than they are stated (four times their weight): the plane's errors are shared by every
// landmark, which calibration takes as independent.
#define JUDGE_PRECISION_RATIO 2.0

const char *rs_site_heights_judgement(char *buf, size_t n, const rs_site_ground_model *g)
{
    if (n == 0) return buf;
    buf[0] = 0;
    if (!g->heights_judged_unreliable) return buf;
    snprintf(buf, n,
             "the plane %d landmark heights on the ground show (RMS %.2f m about it; chi-square %.0f at their stated "
             "%.2g m, within its 99.9%% quantile %.0f) predicts them to %.2f m (RMS), more than %g times better than "
             "their stated %.2g m, and the site gives no ground_plane: taken from the ground model; declare "
             "\"landmark_heights\": \"unreliable\" to silence this, or \"surveyed\" to keep them as given",
             g->judged_Nheights, g->judged_rms_m, g->judged_chi2, g->judged_stated_m, g->judged_chi2_limit,
             g->judged_model_m, JUDGE_PRECISION_RATIO, g->judged_stated_m);
    return buf;
}

// True when the site says nothing of how far its heights can be trusted (no landmark_heights in
// site.json, no properties.height on any landmark) nor where its ground is (no ground_plane).
static bool heights_undeclared(const rs_site *site)
{
    if (site->landmark_heights_given || site->ground_plane_given || site->Nlandmarks == 0) return false;
    for (int i = 0; i < site->Nlandmarks; i++)
        if (site->landmarks[i].height_stated != RS_SITE_HEIGHT_DEFAULT) return false;
    return true;
}

// Heights nobody declared (heights_undeclared), judged against the plane fitted
// robustly to those on the ground (docs/site-format.md, "Heights nobody declared"). They are
// unreliable when the plane predicts them JUDGE_PRECISION_RATIO times better than they are
// stated (the RMS over the points used of sqrt(plane^2 + scatter^2), the sigma a modelled height
// gets) and their residuals about it are consistent with that statement: sum r^2 / (stated^2 +
// SCATTER_MIN^2) within the 99.9 % quantile of chi-square(Nused - 3), the road's least scatter
// about a plane allowed for. (Residuals beyond it are noisier heights or points above the
// ground nobody declared, sign tops, which the heights alone cannot tell apart: they stay as
// given.) Then the heights of the landmarks the plane rests on become UNRELIABLE (the model
// that follows gives them, as for a site that says "landmark_heights": "unreliable"; those it
// left out keep theirs: a wrong height, or a point above the ground, as the fit's warnings say)
// and a warning at site.json says why, with the numbers (also in site->ground). Scratch: idx,
// vtx, local, p, floor_m, keep, as rs_site__ground_model's. Returns 1 when judged unreliable, 0
// when not, -1 when out of memory.
static int judge_heights(rs_site__report *r, rs_site *site, const char *site_path, int *idx, int *vtx, int *local,
                         double *p, double *floor_m, bool *keep)
{
    const int n = candidates(idx, vtx, p, floor_m, site, RS_SITE_HEIGHT_SURVEYED);
    for (int i = 0; i < n; i++) local[i] = i;
    if (n < JUDGE_MIN_HEIGHTS || !spread_ok(p, local, n)) return 0;
    rs_site_ground_model m = {.source = RS_SITE_GROUND_FIT_SURVEYED};
    const int ok = fit_model(&m, keep, site, idx, p, floor_m, n);
    for (int i = 0; i < site->Nlandmarks; i++) site->landmarks[i].ground_used = false; // a trial fit
    if (ok <= 0 || m.Nused < JUDGE_MIN_HEIGHTS) return ok < 0 ? -1 : 0;
    const int dof = m.Nused - 3;
    const double floor2 = RS_SITE_GROUND_SCATTER_MIN_M * RS_SITE_GROUND_SCATTER_MIN_M;
    const double chi2 = dof * m.rms_m * m.rms_m / (m.stated_sigma_m * m.stated_sigma_m + floor2);
    const double limit = rs_stats_chi2_quantile(dof, JUDGE_Z);
    double model2 = 0;
    for (int i = 0; i < n; i++) {
        if (!keep[i]) continue;
        double sigma_plane;
        rs_site_ground_predict(NULL, &sigma_plane, &m, p[3 * i], p[3 * i + 1]);
        model2 += (sigma_plane * sigma_plane + m.scatter_m * m.scatter_m) / m.Nused;
    }
    if (!(chi2 <= limit && JUDGE_PRECISION_RATIO * sqrt(model2) < m.stated_sigma_m)) return 0;
    rs_site_ground_model *g = &site->ground;
    g->heights_judged_unreliable = true;
    g->judged_Nheights = m.Nused;
    g->judged_rms_m = m.rms_m, g->judged_stated_m = m.stated_sigma_m, g->judged_model_m = sqrt(model2);
    g->judged_chi2 = chi2, g->judged_chi2_limit = limit;
    for (int i = 0; i < n; i++) // the heights the plane rests on; those it left out may be above the ground
        if (keep[i]) site->landmarks[idx[i]].height = RS_SITE_HEIGHT_UNRELIABLE;
    char msg[512];
    rs_site__diag(r, RS_SITE_WARNING, RS_OK, site_path, 0, -1, NULL, "landmark_heights", "%s",
                  rs_site_heights_judgement(msg, sizeof msg, g));
    return 1;
}

void rs_site__ground_model(rs_site__report *r, rs_site *site)
{
    rs_site_ground_model *m = &site->ground;
    *m = (rs_site_ground_model){.source = RS_SITE_GROUND_NONE,
                                .rms_m = NAN,
                                .stated_sigma_m = NAN,
                                .scale_m = NAN,
                                .scatter_m = NAN,
                                .sigma_min_m = NAN,
                                .sigma_max_m = NAN,
                                .mean_given_minus_model_m = NAN,
                                .max_abs_given_minus_model_m = NAN,
                                .judged_rms_m = NAN,
                                .judged_stated_m = NAN,
                                .judged_model_m = NAN,
                                .judged_chi2 = NAN,
                                .judged_chi2_limit = NAN};
    int Nmodel = 0;
    for (int i = 0; i < site->Nlandmarks; i++) Nmodel += modelled(&site->landmarks[i]) && usable(&site->landmarks[i]);
    const bool undeclared = heights_undeclared(site);
    if (Nmodel == 0 && !undeclared) return;

    char *landmarks_path = rs_io_join(site->dir, RS_SITE_LANDMARKS), *site_path = rs_io_join(site->dir, RS_SITE_JSON);
    const int N = site->Nlandmarks;
    size_t Nv = 0; // every vertex of every landmark: the most candidates there can be
    for (int i = 0; i < N; i++) Nv += (size_t)nvertices(&site->landmarks[i]);
    int *idx = malloc(Nv * sizeof *idx), *local = malloc(Nv * sizeof *local), *vtx = malloc(Nv * sizeof *vtx);
    double *p = malloc(Nv * 3 * sizeof *p), *floor_m = malloc(Nv * sizeof *floor_m);
    bool *keep = malloc(Nv * sizeof *keep);
    if (Nv > INT_MAX || !landmarks_path || !site_path || !idx || !local || !vtx || !p || !floor_m || !keep) {
        r->nomem = true;
        goto done;
    }
    int judged = 0; // heights nobody declared judged unreliable: the model rests on them, not on those left out
    if (undeclared) {
        judged = judge_heights(r, site, site_path, idx, vtx, local, p, floor_m, keep);
        if (judged < 0) {
            r->nomem = true;
            goto done;
        }
        for (int i = 0; judged && i < N; i++) Nmodel += modelled(&site->landmarks[i]) && usable(&site->landmarks[i]);
        if (Nmodel == 0) goto done;
    }
    static const rs_site_height tiers[2] = {RS_SITE_HEIGHT_SURVEYED, RS_SITE_HEIGHT_UNRELIABLE};
    static const rs_site_ground_source sources[2] = {RS_SITE_GROUND_FIT_SURVEYED, RS_SITE_GROUND_FIT_UNRELIABLE};
    int n = 0, Nheights = 0;
    for (int t = judged; t < 2 && m->source == RS_SITE_GROUND_NONE; t++) {
        n = candidates(idx, vtx, p, floor_m, site, tiers[t]);
        Nheights += n;
        for (int i = 0; i < n; i++) local[i] = i;
        if (!spread_ok(p, local, n)) continue;
        const int ok = fit_model(m, keep, site, idx, p, floor_m, n);
        if (ok < 0) {
            r->nomem = true;
            goto done;
        }
        if (ok) m->source = sources[t];
    }
    if (m->source == RS_SITE_GROUND_NONE) {
        // the site's ground_plane n . p = offset: up = (offset - nx e - ny n) / nz
        const double *nv = site->ground_normal_enu;
        if (!(fabs(nv[2]) >= SITE_PLANE_NZ_MIN)) {
            rs_site__diag(r, RS_SITE_ERROR, RS_ERR_INVALID, site_path, 0, -1, NULL, "ground_plane.normal_enu",
                          "(%g, %g, %g) is steeper than %.0f degrees: it gives no height to the %d landmarks whose "
                          "height is unreliable or unknown, and there are too few heights to fit a ground plane",
                          nv[0], nv[1], nv[2], acos(SITE_PLANE_NZ_MIN) * 180 / M_PI, Nmodel);
            goto done;
        }
        m->source = RS_SITE_GROUND_SITE_PLANE;
        m->up_m = site->ground_offset_m / nv[2];
        m->slope[0] = -nv[0] / nv[2], m->slope[1] = -nv[1] / nv[2];
        if (Nheights > 0)
            rs_site__diag(r, RS_SITE_WARNING, RS_OK, site_path, 0, -1, NULL, "landmark_heights",
                          "%d height%s on the ground to fit a ground plane to (at least 3, not on one line, are "
                          "needed): the site's ground_plane gives the heights of the %d landmarks whose height is "
                          "unreliable or unknown, with their stated sigma_v",
                          Nheights, Nheights == 1 ? "" : "s", Nmodel);
    } else {
        if (m->Nused < m->Ncandidates) report_rejected(r, site, m, idx, vtx, p, keep, n, landmarks_path);
        if (!site->ground_plane_given) { // the fitted plane is the site's best knowledge of its ground
            const double nv[3] = {-m->slope[0], -m->slope[1], 1}, norm = sqrt(nv[0] * nv[0] + nv[1] * nv[1] + 1);
            for (int k = 0; k < 3; k++) site->ground_normal_enu[k] = nv[k] / norm;
            site->ground_offset_m =
                (m->up_m - m->slope[0] * m->centre_en_m[0] - m->slope[1] * m->centre_en_m[1]) / norm;
        }
    }

    for (int i = 0; i < N; i++) {
        rs_site_landmark *l = &site->landmarks[i];
        if (!modelled(l) || !usable(l)) continue;
        if (!apply(l, site, m)) {
            rs_site__diag(r, RS_SITE_ERROR, RS_ERR_INVALID, landmarks_path, 0, l->feature, l->id, "coordinates",
                          "the ground model (%s) gives no usable height here", source_text(m->source));
            continue;
        }
        m->Nmodelled++;
        m->Nunreliable += l->height == RS_SITE_HEIGHT_UNRELIABLE;
        m->Nunknown += l->height == RS_SITE_HEIGHT_UNKNOWN;
        m->sigma_min_m = m->Nmodelled == 1 ? l->sigma_v_m : fmin(m->sigma_min_m, l->sigma_v_m);
        m->sigma_max_m = m->Nmodelled == 1 ? l->sigma_v_m : fmax(m->sigma_max_m, l->sigma_v_m);
        for (int k = 1; k < l->Nvertices; k++) {
            m->sigma_min_m = fmin(m->sigma_min_m, l->vertices_sigma_v_m[k]);
            m->sigma_max_m = fmax(m->sigma_max_m, l->vertices_sigma_v_m[k]);
        }
    }
    report_disagreement(r, site, landmarks_path, site_path);
done:
    free(idx);
    free(vtx);
    free(local);
    free(p);
    free(floor_m);
    free(keep);
    free(landmarks_path);
    free(site_path);
}

// rs_calib_intrinsics.c -- nominal intrinsics with a stated uncertainty, and their test against
// the image (calib/internal/rs_calib_intrinsics.h has the method; docs/calibration.md,
// "Intrinsics with uncertainty").
#include "calib/internal/rs_calib_intrinsics.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mrcal/poseutils.h>

#include "calib/internal/rs_calib_noise.h"
#include "calib/internal/rs_calib_noise_model.h"
#include "calib/internal/rs_calib_opencv.h"
#include "calib/internal/rs_calib_result.h"
#include "calib/internal/rs_calib_solve_state.h"
#include "core/rs_lens.h"
#include "core/rs_pose.h"

// ---------------------------------------------------------------- hook 1: the options

rs_status rs_calib__intrinsics_options(rs_calib_options *opt, const rs_calib_problem *pb, rs_err *err)
{
    const double fs = pb->focal_rel_sigma, cs = pb->center_sigma_px;
    if (!(isfinite(fs) && fs >= 0.0 && fs <= 1.0))
        return rs_err_set(err, RS_ERR_INVALID,
                          "focal_rel_sigma: %g: the focal length's relative 1-sigma must be in [0, 1] (0: exact)", fs);
    if (!(isfinite(cs) && cs >= 0.0 && cs <= 1e4))
        return rs_err_set(err, RS_ERR_INVALID,
                          "center_sigma_px: %g: the principal point's 1-sigma must be in [0, 1e4] px (0: exact)", cs);
    if (!(fs > 0.0) && !(cs > 0.0)) return RS_OK;
    if (!pb->camera || !mrcal_lensmodel_metadata(&pb->camera->lensmodel).has_core)
        return rs_err_set(err, RS_ERR_UNSUPPORTED,
                          "focal_rel_sigma/center_sigma_px: this lens model has no (fx, fy, cx, cy) core to "
                          "state an uncertainty of");
    if (fs > 0.0 && !(opt->refine & RS_CALIB_REFINE_FOCAL)) {
        opt->refine |= RS_CALIB_REFINE_FOCAL;
        opt->focal_prior_rel_sigma = fs;
        opt->focal_search_min = opt->focal_search_max = 1.0; // start at the nominal: the prior is about it
    }
    if (cs > 0.0 && !(opt->refine & RS_CALIB_REFINE_CENTER)) {
        opt->refine |= RS_CALIB_REFINE_CENTER;
        opt->center_prior_sigma_px = cs;
    }
    return RS_OK;
}

// ---------------------------------------------------------------- hook 2: the test

enum { NC_MAX = 6 + 1 + 2 + 64 }; // rt, focal scale, centre, distortion
enum { G_NONE, G_FOCAL, G_CENTER };

// The whitened sum of squares of the data (pixels, surveys, the position prior) at the solution
// and its redundancy before the camera's parameters are counted.
typedef struct {
    double ssr;
    int dof;
} fit;

// The columns of the linearised problem: rt, then the intrinsics that are refined or tested.
typedef struct {
    int nc, Ni;
    int kind[NC_MAX];       // -1: rt; -2: the focal scale; j >= 0: intrinsics[j]
    int group[NC_MAX];      // G_FOCAL, G_CENTER: tested; G_NONE: rt or only refined
    bool refined[NC_MAX];   // a parameter of the adjustment (with its prior below)
    double prior_w[NC_MAX]; // 1/sigma of its prior in the adjustment, 0: none
    double value[NC_MAX];   // its value at the solution minus the nominal (focal: the scale s)
} columns;

static void add_column(columns *c, int kind, int group, bool refined, double prior_sigma, double value)
{
    c->kind[c->nc] = kind;
    c->group[c->nc] = group;
    c->refined[c->nc] = refined;
    c->prior_w[c->nc] = refined && prior_sigma > 0.0 ? 1.0 / prior_sigma : 0.0;
    c->value[c->nc] = value;
    c->nc++;
}

// The whitened rows of one landmark: pixel u, v and its free survey axes. A (rows x nc) the camera
// columns, B (rows x k) its free position axes, e the residuals (predicted - observed over sigma).
typedef struct {
    int m, k;
    double A[5][NC_MAX], B[5][4], e[5]; // B: up to 3 axes, and s for a landmark picked along a segment
} block;

static bool landmark_block(block *b, const columns *cl, const rs_calib_solve_state *w, const rs_pose_prepared *pose,
                           const double *intrinsics, int i, double *dq_dintr)
{
    const rs_calib_refine_problem *rp = &w->rp;
    memset(b, 0, sizeof *b);
    const double *p = &w->p_c[3 * i];
    double pc[3], dpc_drt[18], dpc_dp[9], seen[3], d[3];
    const bool slides = rs_calib__seen_point(seen, d, w->p_c, w->along_c, w->s_along, i);
    rs_pose_prepared_apply(pc, dpc_drt, dpc_dp, pose, seen);
    mrcal_point2_t q;
    mrcal_point3_t dq_dpc[2];
    if (!(pc[2] > 0.0) ||
        !rs_lens_project(&q, dq_dpc, dq_dintr, (const mrcal_point3_t *)pc, 1, rp->lensmodel, intrinsics))
        return false;
    const double sp = rp->sigma_px ? rp->sigma_px[i] : 1.0;
    const double *nominal = rp->intrinsics_nominal;
    for (int r = 0; r < 2; r++, b->m++) {
        b->e[b->m] = (q.xy[r] - rp->q_px[2 * i + r]) / sp;
        for (int c = 0; c < cl->nc; c++) {
            double v = 0;
            if (cl->kind[c] == -1)
                for (int j = 0; j < 3; j++) v += dq_dpc[r].xyz[j] * dpc_drt[j * 6 + c];
            else if (cl->kind[c] == -2)
                v = nominal[0] * dq_dintr[r * cl->Ni + 0] + nominal[1] * dq_dintr[r * cl->Ni + 1];
            else
                v = dq_dintr[r * cl->Ni + cl->kind[c]];
            b->A[b->m][c] = v / sp;
        }
    }
    for (int a = 0; a < 3; a++) {
        const double sa = rp->sigma_enu_m ? rp->sigma_enu_m[3 * i + a] : 0.0;
        if (!(sa > 0)) continue; // held exactly
        const double axis[3] = {a == 0, a == 1, a == 2};
        double col[2];
        rs_calib__position_column(col, dq_dpc, dpc_dp, axis, sp);
        b->B[0][b->k] = col[0], b->B[1][b->k] = col[1];
        b->e[b->m] = (p[a] - rp->p_survey_c_m[3 * i + a]) / sa;
        b->B[b->m][b->k] = 1.0 / sa;
        b->m++, b->k++;
    }
    if (slides) { // s: the pixel rows' dependence on the seen point, along d
        double col[2];
        rs_calib__position_column(col, dq_dpc, dpc_dp, d, sp);
        b->B[0][b->k] = col[0], b->B[1][b->k] = col[1];
        b->k++;
    }
    return true;
}

// Adds landmark i's contribution, its position eliminated, to S (nc x nc) and g (nc): with
// N = B'B, P = I - B N^-1 B' (the projector that removes the position's share),
//   S += A' P A,  g += A' P e.
static rs_status add_landmark(double *S, double *g, const block *b, int nc, rs_err *err)
{
    double PA[5][NC_MAX];
    memcpy(PA, b->A, sizeof PA);
    if (b->k > 0) {
        double N[16] = {0}, Ninv[16];
        for (int x = 0; x < b->k; x++)
            for (int y = 0; y < b->k; y++)
                for (int r = 0; r < b->m; r++) N[x * b->k + y] += b->B[r][x] * b->B[r][y];
        rs_status st = rs_calib_opencv_inverse_spd(Ninv, N, b->k, err);
        if (st) return st;
        double BA[4][NC_MAX] = {{0}};
        for (int x = 0; x < b->k; x++)
            for (int r = 0; r < b->m; r++) {
                for (int c = 0; c < nc; c++) BA[x][c] += b->B[r][x] * b->A[r][c];
            }
        for (int r = 0; r < b->m; r++)
            for (int x = 0; x < b->k; x++)
                for (int y = 0; y < b->k; y++) {
                    const double h = b->B[r][x] * Ninv[x * b->k + y];
                    for (int c = 0; c < nc; c++) PA[r][c] -= h * BA[y][c];
                }
    }
    // P is a projector: A' P A = (PA)'(PA) and A' P e = (PA)' e
    for (int r = 0; r < b->m; r++)
        for (int a = 0; a < nc; a++) {
            g[a] += PA[r][a] * b->e[r];
            for (int c = 0; c < nc; c++) S[a * nc + c] += PA[r][a] * PA[r][c];
        }
    return RS_OK;
}

// The data-alone step for one tested group: solves S_G d = -g_G over the columns rt, the group
// and the refined columns outside it (those with their priors), and returns the group's estimate
// k = value + d (n entries, n <= 2), its covariance Q (n,n) and B (6) = d rt / d k_0, the change
// of the pose per unit change of the group's first parameter (Q_rt,k / Q_kk).
// RS_ERR_DEGENERATE when S_G is singular.
static rs_status group_step(double *k, double *Q, double B[6], int *n_out, fit *alt, const columns *cl, const double *S,
                            const double *g, int group, rs_err *err)
{
    int idx[NC_MAX], n = 0, ng = 0;
    for (int c = 0; c < cl->nc; c++)
        if (cl->kind[c] == -1 || cl->group[c] == group || (cl->refined[c] && cl->group[c] == G_NONE)) idx[n++] = c;
    double *Sg = malloc((size_t)n * (size_t)n * sizeof *Sg), *Qg = malloc((size_t)n * (size_t)n * sizeof *Qg);
    double gg[NC_MAX], D[NC_MAX];
    rs_status st = Sg && Qg ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "intrinsics test: out of memory");
    for (int a = 0; !st && a < n; a++) {
        const int ca = idx[a];
        const bool prior = cl->refined[ca] && cl->group[ca] == G_NONE && cl->kind[ca] != -1;
        gg[a] = g[ca] + (prior ? cl->prior_w[ca] * cl->prior_w[ca] * cl->value[ca] : 0.0);
        if (prior && cl->prior_w[ca] > 0) { // the other priors are observations of the alternative
            alt->ssr += cl->prior_w[ca] * cl->value[ca] * cl->prior_w[ca] * cl->value[ca];
            alt->dof++;
        }
        for (int b = 0; b < n; b++) Sg[a * n + b] = S[ca * cl->nc + idx[b]];
        if (prior) Sg[a * n + a] += cl->prior_w[ca] * cl->prior_w[ca];
    }
    // equilibrated: the columns span px per radian, per metre and per unit focal scale
    for (int a = 0; !st && a < n; a++) {
        D[a] = Sg[a * n + a] > 0 ? 1.0 / sqrt(Sg[a * n + a]) : 0.0;
        if (!(D[a] > 0)) st = rs_err_set(err, RS_ERR_DEGENERATE, "intrinsics test: a column without data");
    }
    for (int a = 0; !st && a < n; a++)
        for (int b = 0; b < n; b++) Sg[a * n + b] *= D[a] * D[b];
    if (!st) st = rs_calib_opencv_inverse_spd(Qg, Sg, n, err);
    if (!st) {
        for (int a = 0; a < n; a++)
            for (int b = 0; b < n; b++) Qg[a * n + b] *= D[a] * D[b];
        double d[NC_MAX];
        for (int a = 0; a < n; a++) {
            d[a] = 0;
            for (int b = 0; b < n; b++) d[a] -= Qg[a * n + b] * gg[b];
        }
        // the alternative (the group free, data alone): its sum of squares drops by g' S^-1 g, and
        // its redundancy loses the n parameters
        for (int a = 0; a < n; a++) alt->ssr += d[a] * gg[a];
        alt->dof -= n;
        int pos[2] = {0, 0};
        for (int a = 0; a < n; a++)
            if (cl->group[idx[a]] == group && ng < 2) pos[ng++] = a;
        // the pose's regression on the group's first parameter (rt comes first): Q_rt,k / Q_kk
        for (int a = 0; a < 6; a++) B[a] = Qg[a * n + pos[0]] / Qg[pos[0] * n + pos[0]];
        for (int x = 0; x < ng; x++) {
            k[x] = cl->value[idx[pos[x]]] + d[pos[x]];
            for (int y = 0; y < ng; y++) Q[x * ng + y] = Qg[pos[x] * n + pos[y]];
        }
    }
    *n_out = ng;
    free(Sg);
    free(Qg);
    return st;
}

// The variance factor of the alternative's residuals, chi2/dof: the noise model estimated the
// noise with the intrinsics held, so a wrong focal partly shows as noise; the test's own scale
// comes from the fit in which the tested intrinsics are free (the F-test of nested least squares,
// Koch 1999, 4.3). Within [1e-4, 1e4]; 1 when the alternative has no redundancy.
static double variance_factor(const fit *alt)
{
    if (alt->dof < 1) return 1.0;
    return fmin(1e4, fmax(1e-4, alt->ssr / alt->dof));
}

// The critical value of the statistic d' (v Q + Sigma)^-1 d for m = 1 or 2 tested parameters and
// nu degrees of freedom of the variance factor v, alpha 0.1%: m F(m, nu) at 0.999. m = 2: the
// closed form of F(2, nu), x = (nu/2) (alpha^(-2/nu) - 1); m = 1: t(nu)^2 at 0.9995 by the
// Cornish-Fisher expansion of Student's t in the normal quantile z = 3.2905 (Abramowitz and
// Stegun 26.7.5; within 0.5% of the exact quantile for nu >= 8). Without a variance factor
// (nu < 1): chi-square m dof.
static double critical(int m, int nu)
{
    if (nu < 1) return m == 1 ? RS_CALIB_INTRINSICS_CHI2_1DOF : RS_CALIB_INTRINSICS_CHI2_2DOF;
    if (m == 2) return 2.0 * (nu / 2.0) * (pow(1e-3, -2.0 / nu) - 1.0);
    const double z = 3.2905, z3 = z * z * z, z5 = z3 * z * z, z7 = z5 * z * z, n = nu;
    const double t = z + (z3 + z) / (4 * n) + (5 * z5 + 16 * z3 + 3 * z) / (96 * n * n) +
                     (3 * z7 + 19 * z5 + 17 * z3 - 15 * z) / (384 * n * n * n);
    return t * t;
}

// d' (Q + s^2 I)^-1 d for n = 1 or 2.
static double chi2_of(const double *d, const double *Q, double s, int n)
{
    if (n == 1) return d[0] * d[0] / (Q[0] + s * s);
    const double a = Q[0] + s * s, b = Q[1], c = Q[2], e = Q[3] + s * s;
    const double det = a * e - b * c;
    if (!(det > 0)) return NAN;
    return (e * d[0] * d[0] - (b + c) * d[0] * d[1] + a * d[1] * d[1]) / det;
}

// x' C^-1 x for the 6x6 block of cov (stride ld); NAN when C is singular.
static double mahalanobis6(const double x[6], const double *cov, int ld)
{
    double C[36], Ci[36];
    for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++) C[a * 6 + b] = cov[a * ld + b];
    rs_err e = {0};
    if (rs_calib_opencv_inverse_spd(Ci, C, 6, &e)) return NAN;
    double s = 0;
    for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++) s += x[a] * Ci[a * 6 + b] * x[b];
    return s;
}

// The camera-position change of a small pose step d_rt at rt (metres).
static double position_shift(const double rt[6], const double d_rt[6])
{
    double C[3], dC_drt[18];
    rs_pose_position_from_rt(C, dC_drt, rt);
    double s = 0;
    for (int k = 0; k < 3; k++) {
        double v = 0;
        for (int a = 0; a < 6; a++) v += dC_drt[k * 6 + a] * d_rt[a];
        s += v * v;
    }
    return sqrt(s);
}

// The columns of the check at the solution x (Ni,), nominal (Ni,): rt, then the focal and the
// centre where tested or refined, the distortion where refined.
static void check_columns(columns *cl, const rs_calib_solve_state *s, bool test_focal, bool test_center)
{
    const rs_calib_options *opt = s->opt;
    const double *nominal = s->rp.intrinsics_nominal, *x = s->res->intrinsics;
    *cl = (columns){.Ni = s->res->Nintrinsics};
    for (int k = 0; k < 6; k++) add_column(cl, -1, G_NONE, false, 0, 0);
    if (test_focal || (opt->refine & RS_CALIB_REFINE_FOCAL))
        add_column(cl, -2, test_focal ? G_FOCAL : G_NONE, opt->refine & RS_CALIB_REFINE_FOCAL,
                   opt->focal_prior_rel_sigma, x[0] / nominal[0] - 1.0);
    if (test_center || (opt->refine & RS_CALIB_REFINE_CENTER))
        for (int j = 2; j < 4; j++)
            add_column(cl, j, test_center ? G_CENTER : G_NONE, opt->refine & RS_CALIB_REFINE_CENTER,
                       opt->center_prior_sigma_px, x[j] - nominal[j]);
    if (opt->refine & RS_CALIB_REFINE_DISTORTION)
        for (int j = 4; j < cl->Ni && cl->nc < NC_MAX; j++)
            add_column(cl, j, G_NONE, true, opt->distortion_prior_sigma, x[j] - nominal[j]);
}

// The data's normal matrix S (nc,nc, zeroed) and gradient g (nc, zeroed) at the solution of s,
// the landmarks eliminated, and *f the data's sum of squares and redundancy with the landmarks
// free. dq_dintr: scratch (2,Ni). false: a landmark in use does not project.
static bool check_normal(double *S, double *g, fit *f, const columns *cl, const rs_calib_solve_state *s,
                         double *dq_dintr)
{
    const rs_calib_refine_problem *rp = &s->rp;
    const int nc = cl->nc;
    rs_err ignore = {0};
    bool ok = true;
    rs_pose_prepared pose;
    rs_pose_prepare(&pose, s->rt_c);
    for (int i = 0; ok && i < s->pb->N; i++) {
        if (!s->use[i]) continue;
        block b;
        ok = landmark_block(&b, cl, s, &pose, s->res->intrinsics, i, dq_dintr) &&
             add_landmark(S, g, &b, nc, &ignore) == RS_OK;
        for (int r = 0; ok && r < b.m; r++) f->ssr += b.e[r] * b.e[r];
        f->dof += b.m - b.k;
    }
    if (ok && rp->has_position_prior && rp->prior_sigma_m > 0) { // the camera position's prior
        double C[3], dC_drt[18];
        rs_pose_position_from_rt(C, dC_drt, s->rt_c);
        const double wp = 1.0 / rp->prior_sigma_m;
        for (int k = 0; k < 3; k++) {
            const double e = (C[k] - rp->prior_position_c_m[k]) * wp;
            f->ssr += e * e;
            f->dof++;
            for (int a = 0; a < 6; a++) {
                g[a] += dC_drt[k * 6 + a] * wp * e;
                for (int b = 0; b < 6; b++) S[a * nc + b] += dC_drt[k * 6 + a] * dC_drt[k * 6 + b] * wp * wp;
            }
        }
    }
    return ok;
}

// The focal's test, linearised (group_step), and where that does not decide, its alternative
// (the focal free, the noise model estimated again; rs_calib_intrinsics.h): fills t and
// res->intrinsics_check's focal figures, except where the alternative is to be solved in full
// (t->need_full: rs_calib__intrinsics_verdict finishes them).
static void check_focal(rs_calib_intrinsics_test *t, const columns *cl, const double *S, const double *g, const fit *f,
                        const rs_calib_solve_state *s)
{
    rs_calib_intrinsics_check *ck = &s->res->intrinsics_check;
    const rs_calib_problem *pb = s->pb;
    rs_err ignore = {0};
    double k, Q;
    int n;
    fit alt = *f;
    if (group_step(&k, &Q, t->B_focal, &n, &alt, cl, S, g, G_FOCAL, &ignore) != RS_OK || n != 1 || !(Q > 0)) return;
    Q *= variance_factor(&alt);
    ck->focal_tested = true;
    ck->focal_rel = k;
    ck->sigma_focal_rel = sqrt(Q);
    ck->critical_focal = critical(1, alt.dof);
    // the alternative: the focal free (--refine focal's weak prior) and the noise model
    // estimated again, so that what a wrong focal left in the residuals is no longer taken
    // for survey noise. Not with fewer than 3 degrees of freedom left (4 landmarks): the
    // critical value is then t(2)^2 = 999 or more, only a 31-sigma focal error could pass
    // it, and the linear step stands.
    // Where the solution kept every landmark, first by Gauss-Newton on the adjustment
    // linearised at the surveyed landmarks (rs_calib__focal_alternative: tens of
    // microseconds instead of a whole solve), which decides where its chi-square is a
    // factor RS_CALIB_ALTERNATIVE_MARGIN or more from the critical value. The full solve
    // is a Cauchy M-estimate, the linearised one least squares: on 248 cameras of
    // tests/calib/test_calib_focal_error.c their focals differed by up to 1.4 of the
    // full solve's sigmas, their sigmas by up to 1.7x, chi-squares by up to 2x. Near the
    // critical value, where that does not converge, and where the solution rejected a
    // landmark, the alternative is solved in full from every landmark (t->need_full, solved by
    // rs_calib.c): a wrong focal makes the solution reject good landmarks, and the alternative
    // with the solution's verdict lost a third of the significant x1.3 warnings there.
    // Scale-free (s->scale_free: the pixels the one noise group, no priors) and every
    // landmark kept, the linear step is already the alternative's first Gauss-Newton
    // step, its variance factor that of the fit with the focal free (no survey group for
    // a focal error to hide in): where its chi-square is RS_CALIB_ALTERNATIVE_MARGIN or
    // more below the critical value it stands (the iterated alternative took about a
    // tenth of an exact survey's calibration; tests/calib/test_scale_free.c compares the
    // two paths).
    double k_alt, Q_alt;
    rs_status st_alt = RS_ERR_DEGENERATE;
    bool all_in = true;
    for (int i = 0; i < pb->N; i++) all_in = all_in && s->use[i];
    const bool linear_stands =
        s->scale_free && all_in &&
        chi2_of(&k, &Q, pb->focal_rel_sigma, 1) <= critical(1, alt.dof) / RS_CALIB_ALTERNATIVE_MARGIN;
    if (alt.dof >= 3 && !linear_stands) {
        rs_err e_alt = {0};
        if (all_in) st_alt = rs_calib__focal_alternative(&k_alt, &Q_alt, s, &e_alt);
        const double crit = critical(1, alt.dof), c2 = chi2_of(&k_alt, &Q_alt, pb->focal_rel_sigma, 1);
        if (st_alt == RS_OK && !(c2 <= crit / RS_CALIB_ALTERNATIVE_MARGIN) &&
            !(c2 >= crit * RS_CALIB_ALTERNATIVE_MARGIN))
            st_alt = RS_ERR_NOCONVERGE; // near the critical value
        if (st_alt != RS_OK) {          // solved in full (rs_calib.c), then rs_calib__intrinsics_verdict
            t->need_full = true;
            t->Q_focal = Q;
            return;
        }
    }
    if (st_alt == RS_OK) {
        k = k_alt, Q = Q_alt;
        ck->focal_rel = k;
        ck->sigma_focal_rel = sqrt(Q);
        ck->critical_focal = critical(1, alt.dof);
    }
    ck->chi2_focal = chi2_of(&ck->focal_rel, &Q, pb->focal_rel_sigma, 1);
}

// The centre's test, linearised (group_step): res->intrinsics_check's centre figures.
static void check_center(const columns *cl, const double *S, const double *g, const fit *f,
                         const rs_calib_solve_state *s)
{
    rs_calib_intrinsics_check *ck = &s->res->intrinsics_check;
    rs_err ignore = {0};
    double k[2], Q[4], B_center[6];
    int n;
    fit alt = *f;
    if (group_step(k, Q, B_center, &n, &alt, cl, S, g, G_CENTER, &ignore) == RS_OK && n == 2 && Q[0] > 0 && Q[3] > 0) {
        const double v = variance_factor(&alt);
        for (int a = 0; a < 4; a++) Q[a] *= v;
        ck->critical_center = critical(2, alt.dof);
        ck->center_tested = true;
        for (int a = 0; a < 2; a++) {
            ck->center_px[a] = k[a];
            ck->sigma_center_px[a] = sqrt(Q[3 * a]);
        }
        ck->chi2_center = chi2_of(k, Q, s->pb->center_sigma_px, 2);
    }
}

rs_status rs_calib__intrinsics_test(rs_calib_intrinsics_test *t, const rs_calib_solve_state *s, rs_err *err)
{
    rs_calib_result *res = s->res;
    const rs_calib_problem *pb = s->pb;
    memset(t, 0, sizeof *t);
    rs_calib_intrinsics_check *ck = &res->intrinsics_check;
    memset(ck, 0, sizeof *ck);
    ck->focal_stated_rel = pb->focal_rel_sigma;
    ck->center_stated_px = pb->center_sigma_px;
    if (!mrcal_lensmodel_metadata(s->rp.lensmodel).has_core) return RS_OK;
    const double *nominal = s->rp.intrinsics_nominal;
    if (!(nominal[0] > 0.0 && nominal[1] > 0.0)) return RS_OK;
    const bool test_focal = !(s->user_refine & RS_CALIB_REFINE_FOCAL);
    const bool test_center = !(s->user_refine & RS_CALIB_REFINE_CENTER);
    if (!test_focal && !test_center) return RS_OK;

    columns cl;
    check_columns(&cl, s, test_focal, test_center);
    // the data's normal matrix and gradient, landmarks eliminated
    const int nc = cl.nc;
    double *S = calloc((size_t)nc * (size_t)nc, sizeof *S), *g = calloc((size_t)nc, sizeof *g);
    double *dq_dintr = malloc((size_t)2 * (size_t)(cl.Ni > 0 ? cl.Ni : 1) * sizeof *dq_dintr);
    rs_status st = S && g && dq_dintr ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "intrinsics test: out of memory");
    fit f = {0}; // the data's sum of squares and its redundancy, with the landmarks free
    const bool ok = st == RS_OK && check_normal(S, g, &f, &cl, s, dq_dintr);
    if (ok && test_focal) check_focal(t, &cl, S, g, &f, s);
    if (ok && test_center) check_center(&cl, S, g, &f, s);
    free(S);
    free(g);
    free(dq_dintr);
    return st;
}

void rs_calib__intrinsics_verdict(rs_calib_solve_state *s, const rs_calib_intrinsics_test *t)
{
    rs_calib_result *res = s->res;
    const rs_calib_problem *pb = s->pb;
    rs_calib_intrinsics_check *ck = &res->intrinsics_check;
    if (t->need_full) { // the alternative solved in full (rs_calib.c)
        double Q = t->Q_focal;
        if (t->full_status == RS_OK) {
            Q = t->Q_full;
            ck->focal_rel = t->k_full;
            ck->sigma_focal_rel = sqrt(Q);
            ck->critical_focal = critical(1, t->dof_full);
        }
        ck->chi2_focal = chi2_of(&ck->focal_rel, &Q, pb->focal_rel_sigma, 1);
    }

    // how far the pose rests on a focal held exact: Baarda's external reliability of the focal,
    // the pose change that its minimal detectable error (alpha 0.1%, power 80%) would cause
    const int ld = 6 + res->Nintrinsics;
    if (ck->focal_tested && !(pb->focal_rel_sigma > 0)) {
        ck->focal_mdb_rel = RS_CALIB_INTRINSICS_DELTA0 * ck->sigma_focal_rel;
        double d_rt[6];
        for (int a = 0; a < 6; a++) d_rt[a] = t->B_focal[a] * ck->focal_mdb_rel;
        ck->shift_position_m = position_shift(s->rt_c, d_rt);
        ck->shift_mahalanobis2 = mahalanobis6(d_rt, s->cov, ld);
    }

    // the warnings: the image says the intrinsics are off (significant), or a focal taken as exact
    // that the landmarks cannot check carries the pose beyond its ellipsoid
    const bool focal_off = ck->focal_tested && ck->chi2_focal > ck->critical_focal;
    const bool center_off = ck->center_tested && ck->chi2_center > ck->critical_center;
    const bool rests = ck->focal_tested && !(pb->focal_rel_sigma > 0) && !(ck->shift_mahalanobis2 <= res->region_m2);
    if (focal_off) {
        char stated[64] = "stated exact";
        if (pb->focal_rel_sigma > 0)
            snprintf(stated, sizeof stated, "beyond its stated %.3g%%", 100 * pb->focal_rel_sigma);
        rs_calib__warn(
            res,
            "the pose may be wrong because of the intrinsics: the image says the focal length is %.0f%% (+-%.0f%%) "
            "%s than the nominal (%s; chi-square %.1f > %.2f, alpha 0.1%%): run with --refine focal, or state the "
            "camera's intrinsics_sigma%s",
            100 * fabs(ck->focal_rel), 100 * ck->sigma_focal_rel, ck->focal_rel >= 0 ? "longer" : "shorter", stated,
            ck->chi2_focal, ck->critical_focal, pb->focal_rel_sigma > 0 ? " larger" : "");
        ck->warned = true;
    } else if (rests) {
        rs_calib__warn(
            res,
            "the pose may be wrong because of the intrinsics: the focal length is taken as exact, but these "
            "landmarks cannot check it: an error of %.0f%% would go unnoticed (alpha 0.1%%, power 80%%) and would "
            "move the camera %.2g m, outside the pose's 99.9%% ellipsoid: state the camera's intrinsics_sigma (the "
            "covariance then includes it), or run with --refine focal",
            100 * ck->focal_mdb_rel, ck->shift_position_m);
        ck->warned = true;
    }
    if (center_off) {
        char stated[64] = "stated exact";
        if (pb->center_sigma_px > 0) snprintf(stated, sizeof stated, "beyond its stated %.3g px", pb->center_sigma_px);
        rs_calib__warn(
            res,
            "the pose may be wrong because of the intrinsics: the image says the principal point is (%+.0f, %+.0f) "
            "px (+-%.0f, +-%.0f) from the nominal (%s; chi-square %.1f > %.2f, alpha 0.1%%): run with --refine "
            "center, or state the camera's intrinsics_sigma%s",
            ck->center_px[0], ck->center_px[1], ck->sigma_center_px[0], ck->sigma_center_px[1], stated, ck->chi2_center,
            ck->critical_center, pb->center_sigma_px > 0 ? " larger" : "");
        ck->warned = true;
    }
}

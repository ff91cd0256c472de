// rs_calib_noise_model.c -- the noise model's place in rs_calib_solve: variance components
// alternating with data snooping, and the reliability of the final adjustment
// (calib/internal/rs_calib_noise_model.h; the numbers themselves: rs_calib_noise.c, rs_calib_vce.c).
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "calib/internal/rs_calib_noise_model.h"

#include "calib/internal/rs_calib_noise.h"
#include "calib/internal/rs_calib_opencv.h"
#include "calib/internal/rs_calib_refine.h"
#include "calib/internal/rs_calib_solve_state.h"
#include "calib/internal/rs_calib_vce.h"
#include "calib/rs_calib.h"
#include "core/rs_pose.h"

// The redundancy number of landmark i's component j as the variance components count it: a
// survey component shared by k picks (problem.survey_shared) counts 1/k.
static double vce_redundancy(const rs_calib_solve_state *s, int i, int j)
{
    const double r = s->r[RS_NOISE_NCOMP * i + j];
    return j < RS_NOISE_E ? r : r / s->share[i];
}

// The noise model's view of s's adjustment at the pose rt_c (6,) and the intrinsics (Ni,), with
// opt's intrinsics refined and their priors.
static rs_calib_noise_state noise_state(const rs_calib_solve_state *s, const double rt_c[6], const double *intrinsics,
                                        const rs_calib_options *opt)
{
    const rs_calib_refine_problem *rp = &s->rp;
    return (rs_calib_noise_state){.N = rp->N,
                                  .rt_cam_c = rt_c,
                                  .p_c_m = s->p_c,
                                  .p_survey_c_m = s->p_survey_c,
                                  .sigma_enu_m = rp->sigma_enu_m,
                                  .q_px = rp->q_px,
                                  .sigma_px = rp->sigma_px,
                                  .use = s->use,
                                  .along_c = s->along_c,
                                  .s_along_m = s->s_along,
                                  .lensmodel = rp->lensmodel,
                                  .intrinsics = intrinsics,
                                  .intrinsics_nominal = rp->intrinsics_nominal,
                                  .refine = opt->refine,
                                  .focal_prior_rel_sigma = opt->focal_prior_rel_sigma,
                                  .center_prior_sigma_px = opt->center_prior_sigma_px,
                                  .distortion_prior_sigma = opt->distortion_prior_sigma,
                                  .has_position_prior = rp->has_position_prior,
                                  .prior_sigma_m = rp->prior_sigma_m,
                                  .prior_position_c_m = rp->prior_position_c_m};
}

// Baarda's w of landmark i: the largest |e| / sqrt(r) among its observations (r > RS_CALIB_MIN_TESTABLE_R).
static double landmark_w(const rs_calib_solve_state *s, int i)
{
    double m = 0;
    for (int j = 0; j < RS_NOISE_NCOMP; j++) {
        const double r = s->r[RS_NOISE_NCOMP * i + j];
        if (r > RS_CALIB_MIN_TESTABLE_R) m = fmax(m, fabs(s->e[RS_NOISE_NCOMP * i + j]) / sqrt(r));
    }
    return m;
}

// The variance factors' posterior mode (rs_calib__vce_estimate) on the landmarks in use at the
// state of s, whose sigmas are the stated ones scaled by s->log_theta: next (in: the start, out),
// sd (may be NULL) as rs_calib__vce_estimate's; the state need not be a solution
// (rs_calib__vce_build).
static rs_status vce_at(double next[RS_NOISE_NGROUPS], double sd[RS_NOISE_NGROUPS], const rs_calib_solve_state *s,
                        rs_err *err)
{
    const rs_calib_result *res = s->res;
    const rs_calib_options *opt = s->opt;
    const double *rt_c = s->rt_c, *log_theta = s->log_theta;
    const rs_calib_noise_state ns = noise_state(s, rt_c, res->intrinsics, opt);
    rs_calib__vce *v = NULL;
    rs_status st = rs_calib__vce_build(&v, &ns, s->share, log_theta, err);
    if (st == RS_OK) st = rs_calib__vce_estimate(next, sd, v, opt->noise_prior_factor, err);
    rs_calib__vce_free(v);
    return st;
}

// 3b. The noise model, alternating with plain solves: variance components to convergence
// (Förstner's estimator, rs_calib__vce_estimate), then Baarda's data snooping -- the landmark
// with the largest |w| above opt->snooping_critical leaves the adjustment, one at a time -- and
// again, until no w exceeds it or a quarter of the landmarks would be gone (then it stops and
// says that the noise model is wrong). in,out: rt_c, the landmarks and the sigmas in w,
// log_theta, *Noutliers.
rs_status rs_calib__noise_model(rs_calib_solve_state *s, rs_err *err)
{
    rs_calib_result *res = s->res;
    const rs_calib_problem *pb = s->pb;
    const rs_calib_options *opt = s->opt;
    const rs_calib_refine_problem *rp = &s->rp;
    const rs_calib_refine_options *ro = &s->ro;
    double *rt_c = s->rt_c, *log_theta = s->log_theta;
    int *Noutliers = &s->Noutliers;
    const int N = pb->N;
    const rs_calib_noise_state ns = noise_state(s, rt_c, res->intrinsics, opt);
    const rs_calib_noise_out out = {
        .e = s->e, .r = s->r, .dpos_m = s->dpos, .dground_m = s->dground, .chi2_excluded = s->chi2_excluded};
    const int max_rejected = (int)floor(opt->max_rejected_fraction * N);
    if (*Noutliers > max_rejected) res->noise_model_wrong = true;
    s->snooped = false;
    for (int round = 0; round <= N; round++) {
        // variance components (rs_calib_vce.c) on the adjustment linearised at each solution,
        // alternating with plain solves until every factor moves by less than 1% or a tenth of
        // its own posterior 1-sigma (the larger: 1% is a tenth of it at r = 200; a group the data
        // barely see, 1-sigma 3 in log variance, crept by 0.1 per round), RS_CALIB_NOISE_SOLVES
        // solves at most. The first estimate of each round is made ahead of the solve, on the
        // adjustment linearised at the state as it is (the robust solution, or the last one with
        // the landmark just rejected still in) and stepped to its solution there: the solve that
        // follows is then at sigmas all but final, and the estimate at its solution settles
        // (where a solve at the robust stage's sigmas came first, it took one solve more: 6% of a
        // calibration). It settles nothing by itself; if it fails, the solve comes first.
        // Scale-free (s->scale_free): the solution does not depend on the variance factor, so
        // one solve (none where it is s->rt_ls, every landmark in) and one estimate at it, in
        // closed form from its chi-square (rs_calib__vce_one).
        int used = 0;
        for (int i = 0; i < N; i++) used += s->use[i];
        const bool have_ls = s->scale_free && s->ls_valid && used == N;
        double chi2_0 = have_ls ? s->chi2_ls0 : NAN; // the solution's chi-square at the stated sigmas
        if (have_ls) memcpy(rt_c, s->rt_ls, 6 * sizeof(double));
        for (int it = s->scale_free; it < RS_CALIB_NOISE_SOLVES + 1; it++) { // the first, ahead, solves nothing
            const bool ahead = it == 0 && opt->estimate_noise;
            if (!ahead && !have_ls) {
                rs_calib_refine_summary sum;
                rs_status st = rs_calib_refine_run(rt_c, res->intrinsics, s->p_c, &sum, NULL, NULL, NULL, rp, ro, err);
                if (st == RS_ERR_NOCONVERGE && round == 0 && it <= 1)
                    return RS_OK; // no noise model on a problem that does not converge: the final
                                  // solve reports it (or its cause, such as landmarks behind)
                if (st != RS_OK) {
                    rs_err_prefix(err, "noise model");
                    return st;
                }
                res->iterations += sum.iterations;
                chi2_0 = sum.chi2 * exp(log_theta[RS_NOISE_PIXEL]);
            }
            if (!opt->estimate_noise) break;
            double next[RS_NOISE_NGROUPS], sd[RS_NOISE_NGROUPS] = {0};
            bool settled = !ahead;
            memcpy(next, log_theta, sizeof next);
            rs_status st = RS_OK;
            if (s->scale_free)
                next[RS_NOISE_PIXEL] =
                    rs_calib__vce_one(&sd[RS_NOISE_PIXEL], chi2_0, 2.0 * used - 6.0, opt->noise_prior_factor);
            else
                st = vce_at(next, sd, s, err);
            if (st != RS_OK && ahead) continue; // the solve first, then the estimate at its solution
            if (st != RS_OK) {
                rs_err_prefix(err, "noise model");
                return st;
            }
            for (int g = 0; g < RS_NOISE_NGROUPS; g++)
                settled = settled && fabs(next[g] - log_theta[g]) < fmax(1e-2, 0.1 * sd[g]);
            memcpy(log_theta, next, sizeof next);
            rs_calib__scale_sigmas(s, log_theta);
            if (settled || s->scale_free) break;
        }
        rs_status st = rs_calib__noise_redundancy(&out, &ns, err);
        if (st != RS_OK) {
            rs_err_prefix(err, "noise model");
            return st;
        }
        s->snooped = true;
        if (!(opt->robust_scale > 0.0)) break;
        int worst = -1;
        double wmax = 0;
        for (int i = 0; i < N; i++) {
            const double wi = s->use[i] ? landmark_w(s, i) : 0;
            if (wi > wmax) wmax = wi, worst = i;
        }
        if (worst < 0 || !(wmax > opt->snooping_critical)) break;
        if (*Noutliers + 1 > max_rejected || N - *Noutliers - 1 < 4) {
            res->noise_model_wrong = true;
            break;
        }
        s->use[worst] = false;
        s->snooped = false;
        res->w_test[worst] = wmax;
        memcpy(&s->p_c[3 * worst], &s->p_survey_c[3 * worst], 3 * sizeof(double));
        (*Noutliers)++;
        res->Nrejected_snooping++;
    }
    return RS_OK;
}

rs_status rs_calib__readmit(rs_calib_solve_state *s, rs_err *err)
{
    rs_calib_result *res = s->res;
    const rs_calib_problem *pb = s->pb;
    const rs_calib_options *opt = s->opt;
    int *Noutliers = &s->Noutliers;
    // not past the quarter the snooping may reject: it could not reject them again (bench calib,
    // 50% outliers: position 1.09x -> 1.26x the CRB when they came back)
    if (*Noutliers > (int)floor(opt->max_rejected_fraction * pb->N)) return RS_OK;
    const double limit = RS_CALIB_READMIT_FACTOR * opt->outlier_threshold * opt->outlier_threshold;
    for (int round = 0; round < RS_CALIB_READMIT_ROUNDS; round++) { // the noise rises as they come back
        int back = 0;
        for (int i = 0; i < pb->N; i++) {
            if (s->use[i] || !isnan(res->w_test[i])) continue; // in, or rejected by the snooping
            if (s->chi2_excluded[i] <= limit) {                // at the noise model's last state
                s->use[i] = true;
                back++;
            }
        }
        if (back == 0) return RS_OK;
        *Noutliers -= back;
        res->noise_model_wrong = false; // judged again on what is left
        rs_status st = rs_calib__noise_model(s, err);
        if (st != RS_OK) return st;
    }
    return RS_OK;
}

rs_status rs_calib__reject_behind(int *Nbehind, rs_calib_solve_state *s, int Ninliers, bool last, rs_err *err)
{
    const rs_calib_result *res = s->res;
    const double *rt_c = s->rt_c;
    *Nbehind = 0;
    for (int i = 0; i < res->N; i++) {
        if (!s->use[i]) continue;
        double pc[3], seen[3], d[3];
        rs_calib__seen_point(seen, d, s->p_c, s->along_c, s->s_along, i);
        mrcal_transform_point_rt(pc, NULL, NULL, rt_c, seen);
        if (pc[2] > 0.0) continue;
        if (last || Ninliers - *Nbehind - 1 < 4)
            return rs_err_set(err, RS_ERR_DEGENERATE, "landmark %d: behind the camera at the solution (z_cam = %.3g m)",
                              i, pc[2]);
        (*Nbehind)++;
        s->use[i] = false;
        s->snooped = false;
        memcpy(&s->p_c[3 * i], &s->p_survey_c[3 * i], 3 * sizeof(double));
    }
    return RS_OK;
}

// The noise groups and each landmark's reliability (rs_calib.h): in the least-squares adjustment
// at the estimated noise where data snooping stopped (s->snooped: the w-tests are those the
// snooping read), else at the final adjustment.
rs_status rs_calib__reliability(rs_calib_solve_state *s, rs_err *err)
{
    rs_calib_result *res = s->res;
    const rs_calib_problem *pb = s->pb;
    const rs_calib_options *opt = s->opt;
    const double *rt_c = s->rt_c, *log_theta = s->log_theta;
    const int N = pb->N;
    const rs_calib_noise_state ns = noise_state(s, rt_c, res->intrinsics, opt);
    const rs_calib_noise_out out = {.e = s->e, .r = s->r, .dpos_m = s->dpos, .dground_m = s->dground};
    rs_status st = s->snooped ? RS_OK : rs_calib__noise_redundancy(&out, &ns, err);
    if (st != RS_OK) {
        rs_err_prefix(err, "reliability");
        return st;
    }
    const double delta0 = 4.13; // alpha 0.1%, power 80% (Baarda 1968)
    double stated2[RS_NOISE_NGROUPS] = {0};
    memset(res->noise, 0, sizeof res->noise);
    for (int i = 0; i < N; i++) {
        double wmax = 0, rsum = 0, mdb_px = 0, mdb_m = NAN, ext = 0, ext_g = 0;
        for (int j = 0; j < RS_NOISE_NCOMP && s->use[i]; j++) {
            const int k = RS_NOISE_NCOMP * i + j;
            const bool pixel = j < RS_NOISE_E;
            const double sigma = pixel ? s->sigma_px[i] : s->sigma_enu[3 * i + (j - RS_NOISE_E)];
            if (!(sigma > 0)) continue; // a held axis
            const double stated =
                pixel ? (pb->sigma_px ? pb->sigma_px[i] : 1.0) : pb->sigma_enu_m[3 * i + j - RS_NOISE_E];
            rs_calib_noise_group *g = &res->noise[rs_calib__noise_group(j)];
            g->redundancy += vce_redundancy(s, i, j);
            g->Nobservations++;
            stated2[rs_calib__noise_group(j)] += stated * stated;
            rsum += s->r[k];
            const double delta = s->r[k] > 1e-9 ? delta0 / sqrt(s->r[k]) : INFINITY; // in sigmas
            if (s->r[k] > RS_CALIB_MIN_TESTABLE_R) wmax = fmax(wmax, fabs(s->e[k]) / sqrt(s->r[k]));
            if (pixel)
                mdb_px = fmax(mdb_px, delta * sigma);
            else
                mdb_m = isnan(mdb_m) ? delta * sigma : fmax(mdb_m, delta * sigma);
            const double *dp = &s->dpos[3 * k], *dg = &s->dground[2 * k];
            ext = fmax(ext, delta * sqrt(dp[0] * dp[0] + dp[1] * dp[1] + dp[2] * dp[2]));
            ext_g = isnan(dg[0]) ? NAN : fmax(ext_g, delta * hypot(dg[0], dg[1]));
        }
        res->redundancy[i] = rsum;
        if (s->use[i]) {
            res->w_test[i] = wmax;
            res->mdb_px[i] = mdb_px;
            res->mdb_m[i] = mdb_m;
            res->external_m[i] = ext;
            res->external_ground_m[i] = ext_g;
        } else {
            res->mdb_px[i] = res->mdb_m[i] = res->external_m[i] = res->external_ground_m[i] = NAN;
        }
    }
    for (int g = 0; g < RS_NOISE_NGROUPS; g++) {
        rs_calib_noise_group *n = &res->noise[g];
        if (!n->Nobservations) continue;
        n->stated = sqrt(stated2[g] / n->Nobservations);
        n->estimated = n->stated * exp(0.5 * log_theta[g]);
        n->estimated_from_data = opt->estimate_noise && n->redundancy >= opt->noise_min_redundancy;
        if (n->estimated_from_data) { // posterior 1-sigma of log(variance), halved for the sigma
            const double lp = 2.0 * log(opt->noise_prior_factor);
            const double precision = n->redundancy / 2.0 + (lp > 0 ? 1.0 / (lp * lp) : 0.0);
            n->sigma_estimated = n->estimated * 0.5 / sqrt(precision);
        }
    }
    return RS_OK;
}

rs_status rs_calib__redundancy_at(rs_calib_solve_state *s, rs_err *err)
{
    const rs_calib_result *res = s->res;
    const rs_calib_options *opt = s->opt;
    const double *rt_c = s->rt_c;
    const rs_calib_noise_state ns = noise_state(s, rt_c, res->intrinsics, opt);
    const rs_calib_noise_out out = {.e = s->e, .r = s->r};
    return rs_calib__noise_redundancy(&out, &ns, err);
}

// How far below noise_min_redundancy every group's redundancy must be for the spread to be
// skipped without building its model (the redundancy numbers are data snooping's, a solve ago)
#define RS_CALIB_SPREAD_MARGIN 0.1

rs_status rs_calib__cov_spread(rs_calib_solve_state *s, rs_err *err)
{
    rs_calib_result *res = s->res;
    const rs_calib_refine_problem *rp = &s->rp;
    const rs_calib_options *opt = s->opt;
    const double *rt_c = s->rt_c, *log_theta = s->log_theta;
    const int n = 6 + res->Nintrinsics;
    if (s->scale_free) { // one group, no priors: rs_calib__vce_cov_spread in closed form
        // The covariance is exactly proportional to the one factor, the group's redundancy is
        // r = 2 N_in - 6 and its Fisher information r / 2, so nu = r + 2 / lp^2 (at least 3), and
        // the unscented points at +-acosh(1 + 2 / (nu - 2)) widen the pose block by nu / (nu - 2);
        // tests/calib/test_scale_free.c checks it against the general path
        int used = 0;
        for (int i = 0; i < rp->N; i++) used += s->use[i];
        const double lp = 2.0 * log(opt->noise_prior_factor), r = 2.0 * used - 6.0;
        if (!(lp > 0) || !(r >= opt->noise_min_redundancy)) return RS_OK;
        const double nu = fmax(r + 2.0 / (lp * lp), 3.0);
        for (int a = 0; a < 6; a++)
            for (int b = 0; b < 6; b++) s->cov[a * n + b] *= nu / (nu - 2.0);
        res->pose_dof = nu;
        res->region_m2 = rs_calib__pose_region_m2(1e-3, nu, nu / (nu - 2.0));
        return RS_OK;
    }
    // No group estimated from the data, none spread: where the redundancy numbers at which data
    // snooping stopped (s->snooped; the final solve moved the state by a fraction of a sigma)
    // leave every group RS_CALIB_SPREAD_MARGIN or more below noise_min_redundancy, the model
    // (which would find the same, rs_calib__vce_cov_spread) is not built: on 4 landmarks, whose
    // 2 N - 6 = 2 are shared among the groups, that was about 5% of the calibration (harness of the
    // bench's 4-landmark problems: 67.7 -> 64 us)
    if (s->snooped) {
        double rg[RS_NOISE_NGROUPS] = {0};
        for (int i = 0; i < rp->N; i++)
            for (int j = 0; j < RS_NOISE_NCOMP && s->use[i]; j++)
                rg[rs_calib__noise_group(j)] += vce_redundancy(s, i, j);
        bool none = true;
        for (int g = 0; g < RS_NOISE_NGROUPS; g++)
            none = none && rg[g] < opt->noise_min_redundancy - RS_CALIB_SPREAD_MARGIN;
        if (none) return RS_OK; // res->pose_dof INFINITY, the region 22.46 (rs_calib.c sets them)
    }
    const rs_calib_noise_state ns = noise_state(s, rt_c, res->intrinsics, opt);
    rs_calib__vce *v = NULL;
    rs_status st = rs_calib__vce_build(&v, &ns, s->share, log_theta, err);
    const int nc = st == RS_OK ? 6 + rs_calib__vce_Nintrinsics(v) : 0;
    double *dQ = st == RS_OK ? malloc((size_t)nc * nc * sizeof *dQ) : NULL;
    if (st == RS_OK && !dQ) st = rs_err_set(err, RS_ERR_NOMEM, "covariance: out of memory");
    if (st == RS_OK)
        st = rs_calib__vce_cov_spread(dQ, &res->pose_dof, &res->region_m2, v, log_theta, opt->noise_prior_factor,
                                      opt->noise_min_redundancy, err);
    // the pose block spread (the refined intrinsics are parametrised otherwise here); it must stay
    // positive definite (checked on its correlation matrix: OpenCV's Cholesky has an absolute
    // threshold, and variances of 1e-20 are real at 1e-6 px), which fails only where the final
    // solve's covariance and the variance components' linearisation disagree
    double C[36], R[36], Ri[36];
    bool pd = st == RS_OK;
    for (int a = 0; st == RS_OK && a < 6; a++)
        for (int b = 0; b < 6; b++) C[a * 6 + b] = s->cov[a * n + b] + dQ[a * nc + b];
    for (int a = 0; pd && a < 6; a++) pd = C[a * 6 + a] > 0 && isfinite(C[a * 6 + a]);
    for (int a = 0; pd && a < 6; a++)
        for (int b = 0; b < 6; b++) R[a * 6 + b] = C[a * 6 + b] / sqrt(C[a * 6 + a] * C[b * 6 + b]);
    rs_err ignore = {0};
    if (st == RS_OK && (!pd || rs_calib_opencv_inverse_spd(Ri, R, 6, &ignore) != RS_OK))
        st = rs_err_set(err, RS_ERR_DEGENERATE,
                        "its spread over the estimated noise is not positive definite: the landmarks do not "
                        "determine the noise (too few of them, or too many outliers)");
    for (int a = 0; st == RS_OK && a < 6; a++)
        for (int b = 0; b < 6; b++) s->cov[a * n + b] = C[a * 6 + b];
    free(dQ);
    rs_calib__vce_free(v);
    if (st != RS_OK) rs_err_prefix(err, "covariance");
    return st;
}

rs_status rs_calib__focal_alternative(double *k_rel, double *Q_rel, const rs_calib_solve_state *s, rs_err *err)
{
    const rs_calib_result *res = s->res;
    const rs_calib_refine_problem *rp = &s->rp;
    const rs_calib_options *opt = s->opt;
    const double *rt_c = s->rt_c;
    const int Ni = res->Nintrinsics;
    const double *nominal = rp->intrinsics_nominal;
    rs_calib_options o = *opt;
    o.refine |= RS_CALIB_REFINE_FOCAL;
    o.focal_prior_rel_sigma = 1.0; // rs_calib_options_default's: weak
    double rt[6], L[RS_NOISE_NGROUPS], dc[RS_NOISE_NC_MAX];
    double *x = malloc((size_t)Ni * sizeof *x), *Q = malloc((size_t)RS_NOISE_NC_MAX * RS_NOISE_NC_MAX * sizeof *Q);
    rs_status st = x && Q ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "intrinsics test: out of memory");
    if (st == RS_OK) {
        memcpy(rt, rt_c, sizeof rt);
        memcpy(x, res->intrinsics, (size_t)Ni * sizeof *x);
        memcpy(L, s->log_theta, sizeof L);
    }
    for (int it = 0; st == RS_OK; it++) {
        if (it == RS_CALIB_ALTERNATIVE_ITERATIONS) {
            st = rs_err_set(err, RS_ERR_NOCONVERGE, "the focal left free: no convergence in %d steps", it);
            break;
        }
        const rs_calib_noise_state ns = noise_state(s, rt, x, &o);
        rs_calib__vce *v = NULL;
        // the focal freed: not the solution of this model, the priors' own gradient
        if ((st = rs_calib__vce_build(&v, &ns, s->share, s->log_theta, err)) != RS_OK) break;
        const int nc = 6 + rs_calib__vce_Nintrinsics(v);
        if (opt->estimate_noise) st = rs_calib__vce_estimate(L, NULL, v, opt->noise_prior_factor, err);
        if (st == RS_OK) st = rs_calib__vce_step(dc, Q, v, L, err);
        rs_calib__vce_free(v);
        if (st != RS_OK) break;
        for (int a = 0; a < 6; a++) rt[a] += dc[a];
        for (int a = 0; a < 2; a++) x[a] += nominal[a] * dc[6];
        *k_rel = x[0] / nominal[0] - 1.0;
        *Q_rel = Q[6 * nc + 6];
        if (!(*Q_rel > 0) || !isfinite(*k_rel)) {
            st = rs_err_set(err, RS_ERR_DEGENERATE, "the focal left free is not determined");
            break;
        }
        if (fabs(dc[6]) <= RS_CALIB_ALTERNATIVE_TOL * sqrt(*Q_rel)) break;
    }
    free(x);
    free(Q);
    return st;
}

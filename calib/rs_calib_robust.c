// rs_calib_robust.c -- steps 2 and 3 of rs_calib_solve: the robust solve on every landmark, the
// noise's scale per group taken from the landmarks that agree with it, and the coarse outlier
// test (calib/internal/rs_calib_robust.h, docs/calibration.md 3a).
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "calib/internal/rs_calib_robust.h"

#include <stdlib.h>

#include "calib/internal/rs_calib_along.h"
#include "calib/internal/rs_calib_noise.h"
#include "calib/internal/rs_calib_noise_model.h"
#include "calib/internal/rs_calib_refine.h"
#include "calib/internal/rs_calib_solve_state.h"
#include "calib/rs_calib.h"
#include "core/rs_stats.h"

// A group's variance factor from the data: the median of x = e^2 / r over its observations, a
// chi-square(1) times the factor where the model holds (median CHI2_1_MEDIAN). The log of the
// median of n has the standard deviation SCALE_SD / sqrt(n) (1 / (2 f(m) sqrt(n)) for the
// median m of the density f, relative to m; 2.28 and 2.31 by Monte Carlo at n 20 and 50); a
// quarter of 10-20 sigma outliers make it 0.6 high (the 67% quantile of the rest).
#define CHI2_1_MEDIAN    0.45494
#define SCALE_SD         2.33
// The coarse test is narrower than stated only on SCALE_NARROW_OBS or more testable observations
// of the group, and only by what the median shows at SCALE_MARGIN of its sigmas: a small survey
// whose residuals are small by chance must not lose the landmark that disagrees with them
// (tests/calib/test_calib_focal_error.c, focal errors drawn from a stated 10%: on 2 of 240
// cameras of 12 landmarks, narrowed on 20 survey observations, the landmark that showed the
// focal error left and the pose became confident and wrong; mean NEES 7.26 -> 9.1). The
// survey's vertical group, one observation per landmark, is narrowed on fewer where its
// horizontal one was narrowed on this many (data_scale): the survey stated 5x too loose with
// a quarter of 20-40 px outliers, tests/calib/test_noise_model.c, 90.3% -> 96.6% of those of
// 10+ sigma flagged, the focal test's figures unchanged.
#define SCALE_NARROW_OBS 30
#define SCALE_MARGIN     2.0
// A group's scale is its own with this many testable observations or more.
#define SCALE_MIN_OBS    5
// The scale settles when no group's log variance factor moves by more than this (10% in sigma).
#define SCALE_SETTLED    0.2
#define SCALE_PASSES     4

// Median of x (n,) (core/rs_stats.h), using scratch (n,); NAN for n = 0.
static double median(const double *x, int n, double *scratch)
{
    if (n > 0) memcpy(scratch, x, (size_t)n * sizeof *x);
    return rs_stats_median(scratch, n);
}

// One robust solve (s->ro) of s from s->rt_c: s->rt_c, the landmarks and s->block_chi2 at its
// solution; res->iterations counts its iterations.
static rs_status robust_run(rs_calib_solve_state *s, rs_err *err)
{
    rs_calib_result *res = s->res;
    rs_calib_refine_summary sum;
    rs_status st =
        rs_calib_refine_run(s->rt_c, res->intrinsics, s->p_c, &sum, NULL, s->block_chi2, NULL, &s->rp, &s->ro, err);
    if (st != RS_OK) {
        rs_err_prefix(err, "robust refinement");
        return st;
    }
    res->iterations += sum.iterations;
    return RS_OK;
}

// The scale of the noise from the data, per group (the robust start of a geodetic adjustment:
// Koch, "Parameter Estimation and Hypothesis Testing in Linear Models", 1999, 3.8; Hampel et al.,
// "Robust Statistics", 1986, 2.3): the median of e^2 / r over the group's observations (whitened
// residual e, redundancy number r > RS_CALIB_MIN_TESTABLE_R, every landmark in, at the robust
// solution), then the robust solve again at the sigmas so scaled, until they settle (SCALE_PASSES
// at most). Wider than stated as the median says, up to the common factor of the median block
// chi2 (a group's median is the more contaminated: an outlier pick drags its landmark, and both
// survey components show it; roadside bench calib, 25% outliers: 2 wrong poses in 50 without
// the cap); narrower as above. A group without enough
// testable observations (picks whose survey is loose have none: the landmark moves to them) keeps
// its scale, widened only, with the others, by the median block chi2. The variance components on
// every landmark would let outliers set the scale instead (a quarter of 10-20 sigma outliers hid
// 28% of themselves where the survey was stated 5x too loose), and the stated sigmas alone cannot
// test anything finer than the statement. fixed: rt_c is a least-squares solution with one
// noise group (rs_calib__robust_stage): one pass, its chi-squares scaled, no solve. Scratch:
// s->dpos, s->q_pred.
static rs_status data_scale(rs_calib_solve_state *s, bool fixed, rs_err *err)
{
    const int N = s->pb->N;
    double *log_theta = s->log_theta;
    const double lim = 2.0 * log(RS_NOISE_MAX_FACTOR);
    double *x = s->dpos, *scratch = s->dpos + (size_t)N * RS_NOISE_NCOMP; // (N,5,3): room for two (N,5)
    for (int pass = 0; pass < SCALE_PASSES; pass++) {
        rs_status st = rs_calib__redundancy_at(s, err);
        if (st != RS_OK) {
            rs_err_prefix(err, "robust refinement");
            return st;
        }
        double next[RS_NOISE_NGROUPS];
        // the common factor: the median block chi2 against a 2-dof chi-square's median 1.3863
        // (a group without testable observations keeps its scale, widened only by it)
        const double widen = fmax(0.0, log(median(s->block_chi2, N, s->q_pred) / 1.3863));
        int nobs[RS_NOISE_NGROUPS];
        for (int g = 0; g < RS_NOISE_NGROUPS; g++) {
            int n = 0;
            for (int k = 0; k < N * RS_NOISE_NCOMP; k++)
                if (rs_calib__noise_group(k % RS_NOISE_NCOMP) == g && s->r[k] > RS_CALIB_MIN_TESTABLE_R)
                    x[n++] = s->e[k] * s->e[k] / s->r[k];
            nobs[g] = n;
            next[g] = log_theta[g] + widen;
            if (n >= SCALE_MIN_OBS) {
                next[g] = log_theta[g] + fmin(widen, log(median(x, n, scratch) / CHI2_1_MEDIAN));
                if (next[g] < 0.0) { // narrower: only by what the median shows at SCALE_MARGIN
                    const double upper = next[g] + SCALE_MARGIN * SCALE_SD / sqrt(n);
                    next[g] = n >= SCALE_NARROW_OBS || g == RS_NOISE_SURVEY_V ? fmin(0.0, upper) : 0.0;
                }
            }
            next[g] = fmin(lim, fmax(-lim, next[g]));
        }
        // the survey's heights, too few to be narrowed on by themselves, follow its horizontal
        // coordinates where those were (a survey stated too loose is usually so in all three
        // axes): never below the horizontal factor, nor below what their own median shows
        const int H = RS_NOISE_SURVEY_H, V = RS_NOISE_SURVEY_V;
        if (nobs[V] < SCALE_NARROW_OBS && next[V] < 0.0)
            next[V] = nobs[H] >= SCALE_NARROW_OBS && next[H] < 0.0 ? fmax(next[H], next[V]) : 0.0;
        bool settled = true;
        for (int g = 0; g < RS_NOISE_NGROUPS; g++) settled = settled && fabs(next[g] - log_theta[g]) < SCALE_SETTLED;
        if (settled) break; // the block chi2 are those of the last solve at sigmas within 10%
        if (fixed) {        // the least-squares solution, every chi-square scaled with the one factor
            for (int i = 0; i < N; i++) s->block_chi2[i] *= exp(log_theta[RS_NOISE_PIXEL] - next[RS_NOISE_PIXEL]);
            memcpy(log_theta, next, sizeof next);
            rs_calib__scale_sigmas(s, log_theta);
            break;
        }
        memcpy(log_theta, next, sizeof next);
        rs_calib__scale_sigmas(s, log_theta);
        if ((st = robust_run(s, err)) != RS_OK) return st;
    }
    return RS_OK;
}

rs_status rs_calib__robust_stage(rs_calib_solve_state *s, bool init_all, rs_err *err)
{
    rs_calib_result *res = s->res;
    const rs_calib_problem *pb = s->pb;
    const rs_calib_options *opt = s->opt;
    const int N = pb->N;
    s->Noutliers = 0;
    rs_status st = RS_OK;
    s->ls_valid = false;
    if (s->scale_free && init_all) {
        // Cauchy's loss from the initial pose (a linear or minimal solution, about a pixel off)
        // overshoots: on the bench's exact surveys its solve took 13 evaluations, rejected
        // steps and then a linear crawl. From the least-squares solution (3 evaluations from
        // the initial pose, Gauss-Newton converging quadratically) it takes 4, and the noise
        // model needs that solution anyway.
        rs_calib_refine_options plain = s->ro;
        plain.robust_scale = 0.0;
        rs_calib_refine_summary sum;
        if (rs_calib_refine_run(s->rt_c, res->intrinsics, s->p_c, &sum, NULL, s->block_chi2, NULL, &s->rp, &plain,
                                err) == RS_OK) {
            memcpy(s->rt_ls, s->rt_c, sizeof s->rt_ls);
            s->chi2_ls0 = sum.chi2 * exp(s->log_theta[RS_NOISE_PIXEL]); // at the stated sigmas
            s->ls_valid = true;
            res->iterations += sum.iterations;
        }
    }
    // And then the least-squares solution stands for the robust one here (fixed): the initial
    // pose agreed with every landmark within the RANSAC threshold (no gross outlier to drag it),
    // the scale from the data is the median's at it, exact in one pass (with one group and no
    // priors neither the solution nor the redundancy numbers depend on the factor), and the
    // coarse test reads its chi-squares at that scale. Data snooping (3c) tests what the Cauchy
    // solve would have down-weighted, and the final solve is the same M-estimate, started from
    // here (stage timers on the bench's 50 exact-survey problems: the robust stage 48 -> 30 us
    // in the median, the final solve 28 -> 35 us; roadside bench calib's error figures the same).
    const bool fixed = s->ls_valid && opt->estimate_noise;
    if (!fixed) st = robust_run(s, err);
    if (st == RS_OK && opt->estimate_noise) st = data_scale(s, fixed, err);
    if (st != RS_OK) return st;
    if (pb->along) { // the segments the along picks are on, at the robust pose (better than the initial one)
        rs_calib__along_choose(s);
        if ((st = robust_run(s, err)) != RS_OK) return st;
    }
    const double thr2 = opt->outlier_threshold * opt->outlier_threshold;
    for (int i = 0; i < N; i++) {
        s->use[i] = s->block_chi2[i] <= thr2;
        res->w_test[i] = NAN;
        if (!s->use[i]) {
            s->Noutliers++;
            memcpy(&s->p_c[3 * i], &s->p_survey_c[3 * i], 3 * sizeof(double));
        }
    }
    snprintf(s->robust_desc, sizeof s->robust_desc, " + ceres-cauchy(%g) + outliers>%g sigma%s", opt->robust_scale,
             opt->outlier_threshold, opt->estimate_noise ? " of the data" : "");
    return RS_OK;
}

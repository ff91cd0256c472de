// rs_calib_intrinsics.h -- internal: nominal intrinsics with a stated uncertainty, and the test
// of the intrinsics against what the image says (calib/rs_calib_intrinsics.c; docs/calibration.md,
// "Intrinsics with uncertainty"). rs_calib.c calls both hooks; the check's full alternative (a
// solve with the focal free) is rs_calib.c's too: the check hands it the request and takes back
// its figures, so that this file never calls the solver.
//
// 1. A stated uncertainty (rs_calib_problem.focal_rel_sigma, .center_sigma_px) turns the stated
//    intrinsics into parameters of the adjustment with that prior (the focal as one scale of fx
//    and fy, the centre as (cx, cy); rs_calib_refine.h): the pose's covariance, the landmarks
//    and the intrinsics marginalised, then includes their uncertainty. An intrinsic the caller
//    asks to refine (rs_calib_options.refine) keeps the option's prior and search instead: the
//    request wins over the statement (it is the fix the warning names).
//
// 2. The test (after the final adjustment): the data ALONE -- the picks and the survey, every
//    other statement as given -- estimate the focal scale s (f = f_nominal (1 + s)) and the
//    centre shift c (px). Linearised at the solution: one Gauss-Newton step on the whitened
//    problem with the landmarks eliminated (Schur complement) and the tested group's prior left
//    out, S d = -g, Q_k = (S^-1)_kk, S the normal matrix (J'J + the other priors) of [rt,
//    intrinsics], g its gradient J'e: for intrinsics held (stated exact) Rao's score test (Rao
//    1948), for intrinsics estimated with their prior the test of the prior as a pseudo-
//    observation (Baarda 1968). Its variance is scaled by the variance factor of the fit with the
//    group free (the F test of nested least squares, Koch 1999, 4.3). The focal, whose error the
//    noise model (run with the focal held) partly takes for survey noise, is then estimated in
//    full: by Gauss-Newton on the linearised adjustment (rs_calib__focal_alternative) where that
//    decides, else rs_calib_solve again with the focal free (weak prior, from the solution, no
//    search), noise model and all; its k and sigma replace the linearised ones. The statistic
//      T = k' (Q_k + Sigma_k)^-1 k   (Sigma_k the stated covariance, 0 for exact)
//    is compared with m F(m, dof) at 0.999 (m = 1 focal, m = 2 centre; each alpha 0.1%).
//
//    A focal held exact can be wrong by more than the data can detect: the focal length and the
//    camera's distance trade off (one view of a road). For it the hook also computes Baarda's
//    external reliability: the minimal detectable focal error 4.13 sigma (alpha 0.1%, power 80%)
//    and the pose change it causes, B mdb with B = Q_rt,f / Q_ff (the pose's regression on the
//    focal); when that change lies outside the reported pose's 99.9% region (rs_calib_result.
//    region_m2: 22.46, chi-square 6 dof, with the noise as stated) the warning says that the pose
//    may be wrong because of the intrinsics.
#pragma once
#include <stdbool.h>

#include "calib/internal/rs_calib_solve_state.h"
#include "calib/rs_calib.h"
#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// The statement's thresholds (alpha 0.1%).
#define RS_CALIB_INTRINSICS_CHI2_1DOF 10.828 // chi-square 1 dof, 99.9%
#define RS_CALIB_INTRINSICS_CHI2_2DOF 13.816 // chi-square 2 dof, 99.9%
#define RS_CALIB_INTRINSICS_DELTA0    4.13   // Baarda's non-centrality: alpha 0.1%, power 80%
// The linearised alternative (rs_calib__focal_alternative) decides the focal test where its
// chi-square is this factor or more from the critical value; nearer, the full solve does
// (rs_calib_intrinsics.c: the two differed by up to 2x in chi-square).
#define RS_CALIB_ALTERNATIVE_MARGIN   4.0

// Hook 1 (before the solve): the options the solve runs with. in,out: *opt (the caller's options
// on entry). A stated focal sigma adds RS_CALIB_REFINE_FOCAL with focal_prior_rel_sigma = the
// statement and no focal search, unless opt->refine already has FOCAL; a stated centre sigma
// likewise CENTER with center_prior_sigma_px. Errors: RS_ERR_INVALID (a sigma not finite or
// negative, or out of its physical range: focal_rel_sigma <= 1, center_sigma_px <= 1e4),
// RS_ERR_UNSUPPORTED (a stated sigma on a lens model without an (fx, fy, cx, cy) core).
rs_status rs_calib__intrinsics_options(rs_calib_options *opt, const rs_calib_problem *pb, rs_err *err);

// Hook 2 (after the final adjustment, in the centred frame), in two steps around the one solve
// it may need. The test's figures between them:
typedef struct {
    // out of rs_calib__intrinsics_test: the focal's alternative is to be solved in full -- the
    // problem with focal_rel_sigma 0, the options with RS_CALIB_REFINE_FOCAL, focal_prior_rel_sigma
    // 1 and no focal search, from the solution of s (rs_calib.c) -- and its figures set below
    bool need_full;
    // in to rs_calib__intrinsics_verdict when need_full: that solve's status, and where RS_OK its
    // focal relative to the nominal minus 1, that focal's variance and the solve's dof
    rs_status full_status;
    double k_full, Q_full;
    int dof_full;
    // between the two steps
    double Q_focal;    // the linearised focal variance (scaled), where the full solve fails
    double B_focal[6]; // d rt / d focal_rel: the pose's regression on the focal
} rs_calib_intrinsics_test;

// Step 1: fills res->intrinsics_check (s->res) but for the focal's verdict where t->need_full,
// and t. user_refine (s->user_refine): the caller's own rs_calib_options.refine (those
// intrinsics are not tested: they are already refined); s->opt: the options the solve ran with;
// s->rp: the final adjustment's problem (the sigmas in use); s->rt_c, res->intrinsics: the
// solution. Errors: RS_ERR_NOMEM only; a test that cannot be made (a singular normal matrix, a
// model without a core) is reported as not made.
rs_status rs_calib__intrinsics_test(rs_calib_intrinsics_test *t, const rs_calib_solve_state *s, rs_err *err);

// Step 2: finishes the focal's figures from the full alternative (t->need_full), then computes
// the focal's external reliability (against s->cov, (6+Ni)^2, the final covariance in the centred
// frame, and res->region_m2) and, when the intrinsics are off beyond their statement or the pose
// rests on them beyond its ellipsoid, appends the warning (rs_calib__warn).
void rs_calib__intrinsics_verdict(rs_calib_solve_state *s, const rs_calib_intrinsics_test *t);

#ifdef __cplusplus
}
#endif

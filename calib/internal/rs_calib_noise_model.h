// rs_calib_noise_model.h -- internal: the noise model's place in rs_calib_solve (steps 3b to 4 of
// rs_calib.c): variance components alternating with Baarda's data snooping, the coarse test's
// rejections tested again, landmarks seen behind the camera, the covariance's spread over the
// variance factors, the reliability of the final adjustment and the intrinsics check's
// linearised alternative (calib/rs_calib_noise_model.c; the numbers themselves: rs_calib_noise.h,
// rs_calib_vce.h; docs/calibration.md, "Noise model"). Every function works on the state of one
// solve (rs_calib_solve_state.h) in the centred frame.
#pragma once
#include <stdbool.h>

#include "calib/internal/rs_calib_solve_state.h"
#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// An observation with a smaller redundancy number is all but uncontrolled: its w would be
// noise over noise (its minimal detectable bias is over 18 sigma); it is neither tested nor
// counted in a robust scale.
#define RS_CALIB_MIN_TESTABLE_R 0.05

// The noise model's solves per round of data snooping, at most (rs_calib__noise_model). Where the
// factors do not settle -- on hard problems of `roadside bench calib --stress` (half the
// landmarks outliers, survey sigmas of metres) they can alternate between two basins for good --
// the round ends at the last estimate: on 15,000 such problems, ending one solve earlier (an odd
// count of solves instead of an even one) left 95 poses failing that had not and mended 54.
#define RS_CALIB_NOISE_SOLVES 10

// 3b of rs_calib_solve: variance components to convergence alternating with Baarda's data
// snooping (one landmark at a time, opt->snooping_critical; stops before rejecting more than
// opt->max_rejected_fraction and sets res->noise_model_wrong), solved with s->ro. in,out:
// s->rt_c, the landmarks, use and sigmas, s->log_theta, s->Noutliers; out: s->e, s->r, s->dpos,
// s->dground, s->chi2_excluded, s->snooped, res->w_test of the rejected. Errors: the solves'
// (rs_calib_refine_run), the noise model's (rs_calib__noise_redundancy, rs_calib__vce_build).
rs_status rs_calib__noise_model(rs_calib_solve_state *s, rs_err *err);

// The coarse outlier test's rejections (step 3 of rs_calib_solve), tested again at the noise the
// model estimated: that test had one scale for every group and cannot tell whose noise a
// residual is (a survey stated 5x too precise lost 2.85% of its good landmarks there), and a noise
// estimated without them is low (their tails are cut). A landmark whose 2-dof chi-square
// (chi2_excluded, rs_calib_noise_out) is now below RS_CALIB_READMIT_FACTOR times the coarse limit comes
// back, rs_calib__noise_model, whose data snooping is the fine test, runs again and decides, and
// so on while landmarks come back (RS_CALIB_READMIT_ROUNDS at most: the noise estimate rises as
// they do). Not when more than opt->max_rejected_fraction are out (the snooping could not reject
// them again). The factor trades false alarms against moderate outliers let back to mask each
// other (tests/calib/test_noise_model.c, docs/calibration.md 3c): 1.5 keeps clean data with
// mis-stated sigmas under 0.5% flagged. in,out as rs_calib__noise_model's.
#define RS_CALIB_READMIT_FACTOR 1.5
#define RS_CALIB_READMIT_ROUNDS 3
rs_status rs_calib__readmit(rs_calib_solve_state *s, rs_err *err);

// The landmarks in use that lie behind the camera at s->rt_c (their adjusted, seen positions):
// each leaves (use false, back at its survey), counted in *Nbehind; an error
// (RS_ERR_DEGENERATE) instead when `last` or when fewer than 4 of the Ninliers would remain. A
// pick and a survey that agree only behind the camera are a blunder: a large survey sigma lets
// the adjustment move the landmark there, where points project too.
rs_status rs_calib__reject_behind(int *Nbehind, rs_calib_solve_state *s, int Ninliers, bool last, rs_err *err);

// The noise groups (res->noise) and each landmark's w, redundancy, MDBs and external
// reliability at the final adjustment (s->rt_c, s->log_theta).
rs_status rs_calib__reliability(rs_calib_solve_state *s, rs_err *err);

// Adds to s->cov ((6+Ni,6+Ni): the camera parameters' covariance of the final solve) its spread
// over the variance factors' posterior (rs_calib__vce_cov_spread) at the state of s. Also sets
// res->pose_dof and res->region_m2 (rs_calib.h). RS_ERR_DEGENERATE when the spread pose block is
// not positive definite (the final solve's covariance and the variance components'
// linearisation disagree: the landmarks do not determine the noise).
rs_status rs_calib__cov_spread(rs_calib_solve_state *s, rs_err *err);

// The intrinsics check's alternative (rs_calib_intrinsics.c): the model of the solution at
// s->rt_c and res->intrinsics, on the landmarks in use, with the focal free (a weak prior, 100%)
// and the variance factors estimated again from s->log_theta (so that what a wrong focal left in
// the residuals is not taken for survey noise), solved by Gauss-Newton on the adjustment
// linearised at the surveyed landmarks (rs_calib_vce.c), relinearised until the focal's step is
// below RS_CALIB_ALTERNATIVE_TOL of its sigma. out: *k_rel, the focal relative to the nominal,
// minus 1; *Q_rel, its variance. Errors: RS_ERR_NOCONVERGE (RS_CALIB_ALTERNATIVE_ITERATIONS
// steps), RS_ERR_DEGENERATE (the focal is not determined), RS_ERR_NOMEM.
#define RS_CALIB_ALTERNATIVE_ITERATIONS 20
#define RS_CALIB_ALTERNATIVE_TOL        1e-2
rs_status rs_calib__focal_alternative(double *k_rel, double *Q_rel, const rs_calib_solve_state *s, rs_err *err);

// s->e and s->r (rs_calib_noise_out) at the state of s (s->rt_c, res->intrinsics, the sigmas in
// use).
rs_status rs_calib__redundancy_at(rs_calib_solve_state *s, rs_err *err);

#ifdef __cplusplus
}
#endif

// rs_calib_robust.h -- internal: steps 2 and 3 of rs_calib_solve, the robust stage: the robust
// solve on every landmark, the noise's scale per group taken from the landmarks that agree with
// it, and the coarse outlier test (calib/rs_calib_robust.c; docs/calibration.md 3a).
#pragma once
#include <stdbool.h>

#include "calib/internal/rs_calib_solve_state.h"
#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// The robust solve (s->ro, Cauchy's loss) on every landmark from s->rt_c; with opt->estimate_noise,
// the variance factors s->log_theta (in,out) from the data -- a common one from the median block
// chi2, then each group's from the variance components of the landmarks that agree at that
// scale, corrected for the trimming, the robust solve again at those sigmas, until they settle;
// then the coarse test: a landmark whose block chi2 exceeds opt->outlier_threshold^2 leaves
// (use false, back at its survey, w_test NAN), counted in s->Noutliers. Along picks choose their
// segment at the robust pose. out: s->robust_desc, the method's description of this stage.
// With s->scale_free and init_all (the initial pose agreed with every landmark), the robust
// solve starts from the least-squares solution on every landmark, kept in s->rt_ls (s->ls_valid).
// Errors: the solves' (rs_calib_refine_run), the redundancy numbers' (rs_calib__redundancy_at).
rs_status rs_calib__robust_stage(rs_calib_solve_state *s, bool init_all, rs_err *err);

#ifdef __cplusplus
}
#endif

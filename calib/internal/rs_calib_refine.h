// rs_calib_refine.h -- internal: one refinement of a camera pose with landmark priors (errors in
// variables), optional intrinsics, and the covariance: variable projection solved by Ceres'
// TinySolver (the method is at the top of rs_calib_refine_ceres.cc). The C face of
// rs_calib_refine_ceres.cc; rs_calib.c drives it (robust solve, outliers, plain re-solve).
//
// Problem (all positions in a frame CENTRED on the landmarks' centroid c: p_c = p_enu - c,
// rt_cam_c = (r, t + R c); rs_calib.c converts):
//   minimise  sum_i rho( |(q(i) - q_obs_i)/sigma_px_i|^2 + sum_k ((p_ik - p_survey_ik)/s_ik)^2 )
//           + |(C - C_prior)/sigma_prior|^2                       (optional camera position prior)
//           + sum_j ((x_j - x_nominal_j)/sigma_j)^2               (priors of refined intrinsics)
//   q(i) = rs_lens_project(mrcal_transform_point_rt(rt_cam_c, p_i), intrinsics)
// over rt_cam_c (6), the landmarks p_i (3 each; axis k with s_ik = 0 is held exactly) and the
// refined intrinsics. rho is Cauchy's loss a^2 log(1 + s/a^2), a = robust_scale, on each landmark's
// block (none when robust_scale <= 0). The landmarks are solved for inside each evaluation
// (variable projection), so the solver's unknowns are rt and the intrinsics only.
// Jacobians are analytic: mrcal_project's dq_dp and dq_dintrinsics chained with
// mrcal_transform_point_rt's dp_cam/drt and dp_cam/dp.
// Intrinsics: FOCAL moves (fx, fy) along (fx0, fy0) (one scale); CENTER frees (cx, cy);
// DISTORTION frees the rest. Their priors: focal (fx - fx0)/(rel_sigma fx0), center (c - c0)/
// sigma_px, distortion (d - d0)/sigma.
#pragma once
#include <mrcal/mrcal.h>
#include <stdbool.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    int N;
    const double *p_survey_c_m; // (N,3) surveyed landmark positions, centred frame, m
    const double *sigma_enu_m;  // (N,3) survey 1-sigma per axis, m; 0: exact. May be NULL
    const double *q_px;         // (N,2) observed pixels
    const double *sigma_px;     // (N,) pixel 1-sigma. May be NULL: 1 px
    const bool *use;            // (N,) which landmarks enter the solve. May be NULL: all
    // Landmarks picked along a segment (rs_calib_polyline): the point seen is p_i + s_i d_i, with
    // d_i the segment's unit direction and s_i free (no prior): the pick's residual is then its
    // distance to the projected line, and the survey prior acts on p_i only.
    const double *along_c; // (N,3) d_i, unit, or 0 for a point. May be NULL: all points
    double *s_along_m;     // (N,) in,out: s_i, metres (the solve's state: start -> solution);
                           //   may be NULL when along_c is
    const mrcal_lensmodel_t *lensmodel;
    const double *intrinsics_nominal; // (Nintrinsics,) centre of the intrinsics priors
    bool has_position_prior;
    double prior_position_c_m[3]; // camera position prior, centred frame, m
    double prior_sigma_m;
} rs_calib_refine_problem;

typedef struct {
    unsigned refine;     // rs_calib_refine_flags (rs_calib.h)
    double robust_scale; // Cauchy scale, sigmas; <= 0: plain least squares
    int max_iterations;
    double focal_prior_rel_sigma;  // 0: no prior
    double center_prior_sigma_px;  // 0: no prior
    double distortion_prior_sigma; // 0: no prior
    bool covariance;               // compute the covariance and the condition number
    bool rough;                    // an intermediate pass (robust, or the noise model's): looser
                                   //   parameter and gradient tolerances, and reaching
                                   //   max_iterations is no error (every pass stops after a step
                                   //   of 1e-2 sigma: rs_calib_refine_ceres.cc)
} rs_calib_refine_options;

// The weight rho'(s) of a landmark block with chi2 s under Cauchy's loss of scale a (robust_scale
// below): 1 / (1 + s / a^2); 1 without a loss (a <= 0).
static inline double rs_calib_refine_weight(double s, double robust_scale)
{
    return robust_scale > 0.0 ? 1.0 / (1.0 + s / (robust_scale * robust_scale)) : 1.0;
}

typedef struct {
    double chi2;           // sum of squared whitened residuals (loss NOT applied)
    int Nresiduals, Nfree; // counts of the solve; dof = Nresiduals - Nfree
    int iterations;
    double condition_number; // equilibrated Jacobian, landmarks eliminated (NAN: not computed)
} rs_calib_refine_summary;

// Runs one solve from the given starting point.
// in,out: rt_cam_c (6,), intrinsics (Nintrinsics,) (start -> solution), p_c_m (N,3) landmark
//   positions (start -> solution; landmarks not used are left untouched).
// out: cov (6+Nintrinsics)^2 row-major covariance of [rt_cam_c, intrinsics] (absolute scaling;
//   zero rows/columns for intrinsics not refined), may be NULL (needs opt->covariance);
//   block_chi2 (N,) each landmark's |pixel residual|^2 + |prior residual|^2 at the solution
//   (unused landmarks: pixel part only, at p_c_m), may be NULL; q_pred_px (N,2), may be NULL.
// Errors: RS_ERR_NOCONVERGE, RS_ERR_DEGENERATE (covariance rank-deficient, or the projection
// failed), RS_ERR_EXTERNAL (exception), RS_ERR_INVALID (bad sizes).
rs_status rs_calib_refine_run( // in,out
    double rt_cam_c[6], double *intrinsics, double *p_c_m,
    // out
    rs_calib_refine_summary *summary, double *cov, double *block_chi2, double *q_pred_px,
    // in
    const rs_calib_refine_problem *problem, const rs_calib_refine_options *opt, rs_err *err);

// For tests: the worst relative disagreement, over every landmark residual block of problem
// (use ignored) at the given point, between the analytic Jacobians (rt, landmark, all
// intrinsics) and central differences of the same residuals (step 1e-6 max(1, |x|)).
// Relative to the largest entry of that Jacobian row. Returns NAN if a residual fails.
double rs_calib_refine_jacobian_check(const double rt_cam_c[6], const double *intrinsics, const double *p_c_m,
                                      const rs_calib_refine_problem *problem);

#ifdef __cplusplus
}
#endif

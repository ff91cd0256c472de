// rs_calib_result.h -- internal: the result of one solve (rs_calib_result, rs_calib.h): its
// allocation, its warnings, and its assembly from the solve's state -- the pose and its
// covariance carried from the centred frame to ENU, the per-landmark figures, the warnings in
// plain words (calib/rs_calib_result.c; steps 5 and 6 of rs_calib.c).
#pragma once
#include <stdbool.h>

#include "calib/internal/rs_calib_solve_state.h"
#include "calib/rs_calib.h"
#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// Allocates r's arrays for N landmarks and Ni intrinsics (zeroed; r->N, r->Nintrinsics set);
// r: zeroed by the caller, freed by rs_calib_result_free (also after an error). RS_ERR_NOMEM
// (without a message).
rs_status rs_calib__result_alloc(rs_calib_result *r, int N, int Ni);

// Appends a warning (printf's fmt) to r->warnings, "; "-separated; dropped when it is full.
void rs_calib__warn(rs_calib_result *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

// Whether every x[0..n) is finite.
bool rs_calib__all_finite(const double *x, int n);

// Step 5 of rs_calib_solve: the pose of s (s->rt_c, s->cov) into res -- rt_cam_enu (its rotation
// normalised to |r| <= pi; s->rt_c too) and its covariance, the intrinsics' covariance and sigmas,
// yaw/pitch/roll and the camera position with their sigmas. RS_ERR_DEGENERATE when any of them is
// not finite (the landmarks do not determine the pose).
rs_status rs_calib__result_pose(rs_calib_solve_state *s, rs_err *err);

// Step 5 of rs_calib_solve, the landmarks: inliers, refined (seen) positions in ENU, predicted
// pixels, residuals, normalised residuals and weights; the fit's rms, chi2, dof, variance factor,
// condition number and res->method. RS_ERR_DEGENERATE when the camera is more than 1 m below every
// landmark in use, looking up (a mirrored pose, or heights in another datum).
rs_status rs_calib__result_landmarks(rs_calib_solve_state *s, rs_err *err);

// Step 6 of rs_calib_solve: the warnings in plain words (outliers, weak geometry, a poorly
// determined pose or focal, noise far from its statement, the fit against the stated sigmas, few
// inliers, a camera looking straight up or down, landmarks bunched in the image).
void rs_calib__result_warnings(rs_calib_solve_state *s);

#ifdef __cplusplus
}
#endif

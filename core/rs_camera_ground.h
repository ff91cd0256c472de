// rs_camera_ground.h -- a pixel located on the ground plane through a camera, and the 2x2
// covariance of the located point from the pose's 6x6 covariance and the pixel's 2x2 covariance.
// The one home of this propagation: audit's uncertainty map (audit/rs_audit.h,
// rs_audit_ground_sigma) and `roadside localise` (eval/localise/rs_localise.h) both call it.
//
// Method: a ground point g = (E, N) seen at pixel q is the solution of
//   q = project(intrinsics, R(r) p(g) + t),  p(g) = (E, N, (offset - n_E E - n_N N) / n_U)
// on the plane n . p = offset. By the implicit function theorem, with A = dq/dg (2,2) and
// B = dq/drt (2,6) (mrcal_transform_point_rt and core/rs_lens.h's projection, analytic gradients):
//   dg/drt = -A^-1 B,  dg/dq = A^-1,
//   Cov(g) = A^-1 (B C_rt B^T + C_q) A^-T
// with C_rt the 6x6 covariance of rt_cam_enu (rs_calib_solve's covariance_rt_cam_enu) and C_q
// the pixel's 2x2 covariance (sigma_px^2 I for an isotropic detection noise). First order: the
// pose and the pixel errors must be small against the curvature of the projection (a Monte Carlo
// run of rs_camera_locate_ground with poses drawn from C_rt agrees within 10%,
// tests/audit/test_audit.c; tests/eval/localise checks the NEES of the located points).
//
// Conventions (docs/conventions.md): rt_cam_enu maps site ENU into the camera; pixel (0,0) is the
// centre of the top-left pixel; covariances are row-major; the plane's normal need not be unit
// length but may not be horizontal-free (n_U != 0: the ground is a graph over (E, N)).
#pragma once
#include "core/rs_camera.h"
#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// RS_OK when the plane n . p = offset is a graph over (E, N): n finite, |n_U| > 1e-9; else
// RS_ERR_INVALID ("ground plane normal (...): must be finite and not vertical").
rs_status rs_camera_ground_check_plane(const double ground_normal_enu[3], rs_err *err); // err may be NULL

// The ground point seen at pixel q_px (rs_camera_locate_ground: the full lens model, 1e-9 px) and
// its horizontal covariance (Method above).
// out:  p_enu_m (3,) the point on the plane, metres
//       cov_en_m2 (2,2) row-major, Cov of (E, N), m^2; may be NULL (only the point)
// in:   cam: calibrated (intrinsics, pose)
//       covariance_rt (6,6) row-major of rt_cam_enu; may be NULL (a pose without error)
//       q_px (2,) the pixel
//       cov_q_px2 (2,2) row-major covariance of the pixel, px^2; may be NULL (an exact pixel)
//       ground_normal_enu (3,), ground_offset_m: the plane n . p = offset
// Errors: RS_ERR_INVALID (plane, non-finite pixel), RS_ERR_UNSUPPORTED (lens model without
// unprojection), RS_ERR_DEGENERATE (the ray misses the plane in front of the camera, or the
// covariance is undefined: a ray grazing the plane).
rs_status rs_camera_ground_locate( // out
    double p_enu_m[3],
    double cov_en_m2[4], // (2,2), may be NULL
    // in
    const rs_camera *cam,
    const double covariance_rt[36], // (6,6), may be NULL
    const double q_px[2],
    const double cov_q_px2[4], // (2,2), may be NULL
    const double ground_normal_enu[3], double ground_offset_m,
    rs_err *err); // may be NULL

// The same from the ground side: the covariance of the point (E, N) of the plane, and the pixel it
// projects to. Returns false (outputs NaN) when the point is behind the camera, mrcal cannot
// project it, or A is singular; the pixel may lie outside the image (the caller's test).
// out:  cov_en_m2 (2,2) m^2; q_px (2,) may be NULL
// in:   as rs_camera_ground_locate, en_m (2,) the point's (E, N), metres
bool rs_camera_ground_covariance_at( // out
    double cov_en_m2[4], double q_px[2],
    // in
    const rs_camera *cam,
    const double covariance_rt[36], // (6,6), may be NULL
    const double en_m[2],
    const double cov_q_px2[4], // (2,2), may be NULL
    const double ground_normal_enu[3], double ground_offset_m);

#ifdef __cplusplus
}
#endif

// rs_calib_opencv.h -- the OpenCV shim of the pose solver (calib/rs_calib_opencv.cc): the
// planarity test's singular values, IPPE and the SPD inverses of the noise model. Internal to
// calib.
//
// Every exception is caught there and turned into RS_ERR_EXTERNAL. Poses are mrcal rt (== OpenCV
// rvec, tvec): p_cam = R(r) p_ref + t.
#pragma once
#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// The 3 singular values s (descending; 0 past the N-th) of the N points p (N,3; the caller centres
// them), by cv::SVD: the planarity test's. Errors: RS_ERR_EXTERNAL (OpenCV threw).
rs_status rs_calib_opencv_singular_values3( // out
    double *s,                              // (3,)
    // in
    const double *p, // (N,3)
    int N,           // >= 1
    rs_err *err);    // may be NULL

// The pose solvers of rs_calib_opencv_pnp.
typedef enum { RS_CALIB_OPENCV_IPPE, RS_CALIB_OPENCV_SQPNP } rs_calib_opencv_pnp_method;

// Pose from N landmarks by cv::solvePnP with K = identity on normalised image coordinates
// xy = (v_x/v_z, v_y/v_z) of bearings in front of the camera:
// - RS_CALIB_OPENCV_IPPE: N >= 4 coplanar landmarks (Collins & Bartoli, "Infinitesimal
//   Plane-Based Pose Estimation", IJCV 2014);
// - RS_CALIB_OPENCV_SQPNP: N >= 3 landmarks in any configuration, the global minimum of the
//   squared object-space error (Terzakis & Lourakis, "A Consistently Fast and Globally Optimal
//   Solution to the Perspective-n-Point Problem", ECCV 2020).
// Returns RS_ERR_EXTERNAL when OpenCV refuses the input (e.g. points not coplanar enough for
// IPPE) or throws, RS_ERR_DEGENERATE when it returns no pose or a non-finite one.
rs_status rs_calib_opencv_pnp( // out
    double *rt_cam_ref,        // (6,)
    // in
    const double *xy,    // (N,2) normalised image coordinates
    const double *p_ref, // (N,3) landmarks, metres
    int N, rs_calib_opencv_pnp_method method,
    rs_err *err); // may be NULL

// Normalised image coordinates xy = (x/z, y/z) of N pixels through OpenCV's distortion model, by
// cv::undistortPoints' fixed-point iteration (at most 20 iterations; it stops where its own
// reprojection error is below 1e-9 px). mrcal's LENSMODEL_OPENCV4/5/8/12 are OpenCV's model with
// OpenCV's coefficients in OpenCV's order: intrinsics = (fx, fy, cx, cy, k1, k2, p1, p2[, k3[, k4,
// k5, k6[, s1..s4]]]), Ndistortion = 4, 5, 8 or 12. The iteration reports no failure (a pixel far
// outside a strongly distorting lens's valid region can end anywhere): the caller checks the
// result by projecting it again (rs_calib_init.c, through mrcal). RS_ERR_INVALID for another
// Ndistortion, RS_ERR_EXTERNAL when OpenCV throws.
rs_status rs_calib_opencv_undistort( // out
    double *xy,                      // (N,2)
    // in
    const double *q_px,       // (N,2)
    int N,                    // >= 1
    const double *intrinsics, // (4 + Ndistortion,)
    int Ndistortion, rs_err *err);

// The inverse of the symmetric positive definite n x n matrix A (row-major) by OpenCV's
// Cholesky (cv::hal::Cholesky64f; cv::invert for n <= 3): the normal matrices of the noise model
// (rs_calib_noise.c). RS_ERR_DEGENERATE when A is not positive definite, RS_ERR_EXTERNAL when
// OpenCV throws. inv may not alias A.
rs_status rs_calib_opencv_inverse_spd( // out
    double *inv,                       // (n,n)
    // in
    const double *A, int n, rs_err *err);

// The same, and the natural log of det A (from the Cholesky factor; for n <= 3 cv::determinant of
// A scaled to a unit diagonal): the
// restricted likelihood of the variance components (rs_calib_vce.c).
rs_status rs_calib_opencv_inverse_spd_logdet( // out
    double *inv,                              // (n,n)
    double *logdet,
    // in
    const double *A, int n, rs_err *err);

// The eigenvalues (n,), in descending order, and eigenvectors (n,n: one per row) of the
// symmetric n x n matrix A (cv::eigen). RS_ERR_EXTERNAL when OpenCV throws.
rs_status rs_calib_opencv_eigen_sym(double *values, double *vectors, const double *A, int n, rs_err *err);

// Writes a camera in OpenCV's own YAML layout (cv::FileStorage), for users of cv::projectPoints:
// image_width, image_height (int), camera_matrix (3x3 K from fx fy cx cy),
// distortion_coefficients (1xNdistortion, OpenCV's order -- mrcal's LENSMODEL_OPENCVn order),
// rvec, tvec (3x1: rt_cam_enu, mapping site ENU into the camera), and R_cam_enu (3x3).
// Writes `path` directly: the caller makes it atomic (rs_io_atomic_*).
// Returns RS_ERR_IO if the file cannot be written, RS_ERR_EXTERNAL if OpenCV throws.
#ifdef __cplusplus
}
#endif

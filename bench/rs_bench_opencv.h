// rs_bench_opencv.h -- OpenCV's pose solvers for `roadside bench calib` (bench/rs_bench_opencv.cc):
// one calling convention for every OpenCV method the benchmark compares with roadside's solver.
#pragma once
#include <stdbool.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// One calling convention for every OpenCV pose method the benchmark compares: landmarks and
// pixels in, rt_cam_ref out, with the camera's K and OpenCV distortion (mrcal's
// LENSMODEL_OPENCVn order) passed as OpenCV users pass them.
typedef enum {
    RS_BENCH_OPENCV_PNP_ITERATIVE = 0, // cv::SOLVEPNP_ITERATIVE (DLT/homography init + LM)
    RS_BENCH_OPENCV_PNP_EPNP = 1,      // cv::SOLVEPNP_EPNP (Lepetit et al., IJCV 2009)
    RS_BENCH_OPENCV_PNP_SQPNP = 2,     // cv::SOLVEPNP_SQPNP (Terzakis & Lourakis, ECCV 2020)
    RS_BENCH_OPENCV_PNP_IPPE = 3,      // cv::SOLVEPNP_IPPE (coplanar landmarks only)
    RS_BENCH_OPENCV_PNP_RANSAC = 4,    // cv::solvePnPRansac, ITERATIVE inside, 100 iterations,
                                       //   confidence 0.99, threshold ransac_threshold_px
} rs_bench_opencv_pnp_method;

// Runs `method` on N landmarks; with refine_lm, then cv::solvePnPRefineLM (on the RANSAC
// inliers for RS_BENCH_OPENCV_PNP_RANSAC). inlier (N,) may be NULL; else the RANSAC inliers
// (all true for the other methods).
// Returns RS_ERR_DEGENERATE when OpenCV finds no pose or a non-finite one, RS_ERR_EXTERNAL when
// it throws (its message is kept: e.g. IPPE's "points are not coplanar"), RS_ERR_USAGE for a
// bad Ndistortion. Never prints.
rs_status rs_bench_opencv_pnp( // out
    double *rt_cam_ref,        // (6,)
    bool *inlier,              // (N,) may be NULL
    // in
    const double *p_ref, // (N,3) landmarks, metres
    const double *q_px,  // (N,2) observed pixels
    int N,
    const double *intrinsics, // (4 + Ndistortion,) fx fy cx cy k...
    int Ndistortion,          // 0, 4, 5, 8, 12 or 14
    rs_bench_opencv_pnp_method method, bool refine_lm,
    double ransac_threshold_px, // RANSAC only, pixels
    rs_err *err);               // may be NULL

// The same for a fisheye camera, as OpenCV users calibrate one: the pixels are undistorted by
// cv::fisheye::undistortPoints (Kannala-Brandt, intrinsics (8,) = fx fy cx cy k1 k2 k3 k4), then
// `method` runs on the normalised coordinates (K = I, no distortion; RANSAC's threshold divided
// by the mean focal length). Points more than 90 degrees off the axis cannot be used this way.
rs_status rs_bench_opencv_pnp_fisheye( // out
    double *rt_cam_ref,                // (6,)
    bool *inlier,                      // (N,) may be NULL
    // in
    const double *p_ref, const double *q_px, int N,
    const double *intrinsics, // (8,) fx fy cx cy k1 k2 k3 k4
    rs_bench_opencv_pnp_method method, bool refine_lm, double ransac_threshold_px, rs_err *err);

#ifdef __cplusplus
}
#endif

// rs_calib_init.h -- initial camera pose from surveyed landmarks and their clicked pixels.
//
// Purpose: a pose good enough to start the Ceres refinement (rs_calib_refine.h) from, found
// without any prior guess, robust to gross mistakes in the clicked pixels, for any mrcal lens
// model. The refinement, not this step, is what makes the pose accurate.
//
// Method (docs/calibration-init.md has the details and references):
//   1. Every pixel q_px is unprojected through the lens model with rs_lens_unproject() and
//      normalised to a unit bearing vector in the camera frame. For LENSMODEL_OPENCVn (OpenCV's
//      own model) OpenCV's cv::undistortPoints goes first, and its answer is kept where mrcal
//      projects it back within 1e-6 px of the pixel (tests/calib/test_undistort.c).
//   2. The input is checked for degeneracy: fewer than 4 usable points (repeated landmarks
//      count once: later copies are left out of this step), collinear landmarks (singular values of the centred landmarks, s2/s1 < 1e-3), all
//      bearings within 0.2 deg of each other (every pixel in a tiny image patch).
//   3. RANSAC (OpenGV's sac::Ransac) over OpenGV's P3P (Kneip, Scaramuzza, Siegwart, CVPR 2011;
//      Gao's solver on samples where Kneip's finds nothing), scored by reprojection error in
//      PIXELS through rs_lens_project(); landmarks behind the camera never count. OpenGV's sampler
//      is reseeded from opt->seed: same input and seed, same answer, bit for bit. With 6 usable
//      observations or fewer, every triple is tried instead (rs_calib_opengv.h). The best pose
//      must be supported by a majority of the usable observations (and by 4 at least).
//   4. Non-minimal solves on the inliers: OpenCV's IPPE (Collins & Bartoli, IJCV 2014) if the
//      landmarks are coplanar (s3/s2 < planarity_ratio), OpenGV's EPnP (Lepetit et al.,
//      IJCV 2009) unless they are exactly coplanar. The pose kept is the one among {RANSAC
//      model, IPPE, EPnP} with the lowest RMS reprojection error over the inliers, in pixels,
//      and with every inlier in front of the camera (z_cam > 0).
//      All solvers work in coordinates centred on the landmarks' centroid.
//
// Conventions (docs/conventions.md): rt_cam_enu is an mrcal rt (Rodrigues r, translation t,
// metres) with p_cam = R(r) p_enu + t; camera x right, y down, z forward; pixel (0,0) is the
// centre of the top-left pixel.
//
// Accuracy (tests/calib/test_init*.c*, simulated pole cameras 5..100 m up, landmarks up to 600 m
// away, pinhole/OPENCV8/CAHVOR): noise-free pixels give the truth to 3e-9 (rotation in rad,
// position relative to the landmark range), N = 4..30. With 1 px noise and 30% gross outliers
// (N = 20) every outlier was flagged and the pose moves the landmarks' pixels by 0.77 px RMS
// (median; 3.5 px worst of 1800) -- a linear/minimal solution, which the refinement polishes.
// Time: 50..150 us per call for 20 landmarks.
#pragma once
#include "core/rs_status.h"
#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif
// mrcal.h has no extern "C" of its own
#include <mrcal/mrcal.h>

typedef struct {
    double ransac_threshold_px; // inlier threshold on reprojection error, pixels (default 8)
    int ransac_max_iterations;  // default 500 (adaptive stop at 99.9% confidence)
    uint64_t seed;              // RANSAC sampling seed (default 1)
    double planarity_ratio;     // planar if s3/s2 of the centred landmarks' SVD < this (default 0.02)
    // Survey noise in the inlier test: landmark i is an inlier of a hypothesis when its
    // reprojection error is below sqrt(T^2 + (k f s_i / z_i)^2) px, T = ransac_threshold_px,
    // k = survey_sigmas, f = the larger focal length of the lens core, s_i = the largest of
    // landmark i's three survey sigmas and z_i its depth under that hypothesis: a near landmark
    // surveyed to 0.3 m is off by tens of pixels without being an outlier.
    const double *sigma_enu_m; // (N,3) survey 1-sigma of E, N, U, metres; NULL: exact
    double survey_sigmas;      // k above (default 3)
} rs_calib_init_options;

// Fills opt with the defaults above. opt must not be NULL.
void rs_calib_init_options_default(rs_calib_init_options *opt);

typedef struct {
    double rt_cam_enu[6]; // initial pose (mrcal rt, maps ENU into camera)
    int Ninliers;
    bool planar;     // landmarks judged coplanar
    double rms_px;   // RMS reprojection error of the inliers at this pose
    char method[96]; // e.g. "opengv-p3p-kneip-ransac + opencv-ippe"
} rs_calib_init_result;

// Finds an initial pose. inlier may be NULL; else (N,) filled with the RANSAC inlier flags.
// Observations whose unprojection fails or that are non-finite are never inliers.
// Errors: RS_ERR_DEGENERATE with the cause in err (fewer than 4 usable points, collinear,
// all points in a tiny image patch, no pose with points in front of the camera), RS_ERR_INVALID
// for NaN/inf input naming the index.
// Also: RS_ERR_DEGENERATE for fewer than 4 distinct landmark positions and when no pose is supported by a majority
// of the observations; RS_ERR_INVALID for bad options or non-finite intrinsics;
// RS_ERR_USAGE for NULL
// arguments; RS_ERR_EXTERNAL if OpenGV/OpenCV threw. On any error `result` is not filled and
// every inlier flag is false. Thread-safe (no global state); never prints.
rs_status rs_calib_init_pose( // out
    rs_calib_init_result *result,
    bool *inlier, // (N,) may be NULL
    // in
    const mrcal_lensmodel_t *lensmodel,
    const double *intrinsics, // (Nintrinsics,)
    const double *p_enu_m,    // (N,3)
    const double *q_px,       // (N,2)
    int N,
    const rs_calib_init_options *opt, // may be NULL: defaults
    rs_err *err);

// The least-squares homography H_dst_from_src (3,3, row-major, H[8] = 1 unless it is ~0) with
// dst ~ H src over N >= 4 point pairs: OpenCV's cv::findHomography with method 0 (every point,
// no RANSAC; a normalised DLT refined by Levenberg-Marquardt on the error in dst). The ground
// mapping of a camera whose focal length the points cannot tell from its distance (pixels of an
// undistorted image to a plane's (E, N), rs_calib_result.H_ground_from_px_fit), and the baseline
// `roadside bench sparse` compares leave-one-out ground errors with.
// Errors: RS_ERR_DEGENERATE when OpenCV finds none (collinear points, N < 4), RS_ERR_EXTERNAL
// when it throws.
rs_status rs_calib_homography_fit( // out
    double H_dst_from_src[9],
    // in
    const double *src, // (N,2)
    const double *dst, // (N,2)
    int N, rs_err *err);

#ifdef __cplusplus
}
#endif

// rs_calib_init.h -- initial camera pose from surveyed landmarks and their clicked pixels.
//
// Purpose: a pose good enough to start the Ceres refinement (rs_calib_refine.h) from, found
// without any prior guess, robust to gross mistakes in the clicked pixels, for any mrcal lens
// model. The refinement, not this step, is what makes the pose accurate.
//
// Method (docs/calibration-init.md has the details and references):
//   1. Every pixel q_px is unprojected through the lens model with mrcal_unproject() and
//      normalised to a unit bearing vector in the camera frame.
//   2. The input is checked for degeneracy: fewer than 4 usable points, repeated landmarks,
//      collinear landmarks (singular values of the centred landmarks, s2/s1 tiny), all
//      bearings within a tiny cone (every pixel in a tiny image patch).
//   3. RANSAC over OpenGV's minimal P3P solver (Kneip, Scaramuzza, Siegwart, CVPR 2011; Gao's
//      solver as a fallback), scored by reprojection error in PIXELS through mrcal_project().
//      Sampling uses a private generator seeded from opt->seed: same input, same answer.
//   4. Non-minimal solve on the inliers: for coplanar landmarks (s3/s2 < planarity_ratio)
//      OpenCV's IPPE (Collins & Bartoli, IJCV 2014), else OpenGV's EPnP (Lepetit et al.,
//      IJCV 2009). The better of {RANSAC model, non-minimal} by inlier RMS in pixels is kept.
//      All solvers work in coordinates centred on the landmarks' centroid.
//
// Conventions (docs/conventions.md): rt_cam_enu is an mrcal rt (Rodrigues r, translation t,
// metres) with p_cam = R(r) p_enu + t; camera x right, y down, z forward; pixel (0,0) is the
// centre of the top-left pixel.
//
// Accuracy: with noise-free pixels the pose agrees with the truth to better than 1e-6
// (relative) for 4..30 landmarks; with 1 px noise it is as good as a linear/minimal method
// allows (a few pixels RMS at worst), which is all the refinement needs.
#pragma once
#include <stdbool.h>
#include <stdint.h>
#include "rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif
// mrcal.h has no extern "C" of its own
#include <mrcal/mrcal.h>

typedef struct {
    double ransac_threshold_px;    // inlier threshold on reprojection error, pixels (default 8)
    int    ransac_max_iterations;  // default 500 (adaptive stop at 99.9% confidence)
    uint64_t seed;                 // RANSAC sampling seed (default 1)
    double planarity_ratio;        // planar if s3/s2 of the centred landmarks' SVD < this (default 0.02)
} rs_calib_init_options;

// Fills opt with the defaults above. opt must not be NULL.
void rs_calib_init_options_default(rs_calib_init_options *opt);

typedef struct {
    double rt_cam_enu[6];  // initial pose (mrcal rt, maps ENU into camera)
    int    Ninliers;
    bool   planar;         // landmarks judged coplanar
    double rms_px;         // RMS reprojection error of the inliers at this pose
    char   method[96];     // e.g. "opengv-p3p-kneip-ransac + opencv-ippe"
} rs_calib_init_result;

// Finds an initial pose. inlier may be NULL; else (N,) filled with the RANSAC inlier flags.
// Observations whose unprojection fails or that are non-finite are never inliers.
// Errors: RS_ERR_DEGENERATE with the cause in err (fewer than 4 usable points, collinear,
// all points in a tiny image patch, no pose with points in front of the camera), RS_ERR_INVALID
// for NaN/inf input naming the index.
rs_status rs_calib_init_pose(// out
                             rs_calib_init_result *result,
                             bool *inlier,                          // (N,) may be NULL
                             // in
                             const mrcal_lensmodel_t *lensmodel,
                             const double *intrinsics,              // (Nintrinsics,)
                             const double *p_enu_m,                 // (N,3)
                             const double *q_px,                    // (N,2)
                             int N,
                             const rs_calib_init_options *opt,      // may be NULL: defaults
                             rs_err *err);

#ifdef __cplusplus
}
#endif

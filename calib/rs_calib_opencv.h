// rs_calib_opencv.h -- internal C interface to the OpenCV pieces of the pose solver (calib only).
//
// Thin shim: the C++ lives in rs_calib_opencv.cc; every exception is caught there and turned
// into RS_ERR_EXTERNAL. Poses are mrcal rt (== OpenCV rvec, tvec): p_cam = R(r) p_ref + t.
#pragma once
#include "rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// Singular values of the (N,3) matrix p (the caller centres it), descending, by cv::SVD.
rs_status rs_calib_opencv_singular_values3(// out
                                           double *s,       // (3,)
                                           // in
                                           const double *p, // (N,3)
                                           int N,           // >= 1
                                           rs_err *err);    // may be NULL

// Pose from N >= 4 coplanar landmarks by OpenCV's IPPE (Collins & Bartoli, "Infinitesimal
// Plane-Based Pose Estimation", IJCV 2014) -- cv::solvePnP(SOLVEPNP_IPPE) with K = identity on
// normalised image coordinates xy = (v_x/v_z, v_y/v_z) of bearings in front of the camera.
// Returns RS_ERR_EXTERNAL when OpenCV refuses the input (e.g. points not coplanar enough) or
// throws, RS_ERR_DEGENERATE when it returns no pose or a non-finite one.
rs_status rs_calib_opencv_ippe(// out
                               double *rt_cam_ref,   // (6,)
                               // in
                               const double *xy,     // (N,2) normalised image coordinates
                               const double *p_ref,  // (N,3) coplanar landmarks, metres
                               int N,
                               rs_err *err);         // may be NULL

// Writes a camera in OpenCV's own YAML layout (cv::FileStorage), for users of cv::projectPoints:
// image_width, image_height (int), camera_matrix (3x3 K from fx fy cx cy),
// distortion_coefficients (1xNdistortion, OpenCV's order -- mrcal's LENSMODEL_OPENCVn order),
// rvec, tvec (3x1: rt_cam_enu, mapping site ENU into the camera), and R_cam_enu (3x3).
// Writes `path` directly: the caller makes it atomic (rs_io_atomic_*).
// Returns RS_ERR_IO if the file cannot be written, RS_ERR_EXTERNAL if OpenCV throws.
rs_status rs_calib_opencv_write_yaml(const char *path,
                                     const double *intrinsics,  // (4 + Ndistortion,)
                                     int Ndistortion,           // 0, 4, 5, 8, 12 or 14
                                     const double *rt_cam_enu,  // (6,)
                                     int width, int height,     // pixels
                                     rs_err *err);              // may be NULL

// ---- pose solvers side by side (roadside bench calib, issue 5) ----
// One calling convention for every OpenCV pose method the benchmark compares: landmarks and
// pixels in, rt_cam_ref out, with the camera's K and OpenCV distortion (mrcal's
// LENSMODEL_OPENCVn order) passed as OpenCV users pass them.
typedef enum {
    RS_CALIB_OPENCV_PNP_ITERATIVE = 0, // cv::SOLVEPNP_ITERATIVE (DLT/homography init + LM)
    RS_CALIB_OPENCV_PNP_EPNP      = 1, // cv::SOLVEPNP_EPNP (Lepetit et al., IJCV 2009)
    RS_CALIB_OPENCV_PNP_SQPNP     = 2, // cv::SOLVEPNP_SQPNP (Terzakis & Lourakis, ECCV 2020)
    RS_CALIB_OPENCV_PNP_IPPE      = 3, // cv::SOLVEPNP_IPPE (coplanar landmarks only)
    RS_CALIB_OPENCV_PNP_RANSAC    = 4, // cv::solvePnPRansac, ITERATIVE inside, 100 iterations,
                                       //   confidence 0.99, threshold ransac_threshold_px
} rs_calib_opencv_pnp_method;

// Runs `method` on N landmarks; with refine_lm, then cv::solvePnPRefineLM (on the RANSAC
// inliers for RS_CALIB_OPENCV_PNP_RANSAC). inlier (N,) may be NULL; else the RANSAC inliers
// (all true for the other methods).
// Returns RS_ERR_DEGENERATE when OpenCV finds no pose or a non-finite one, RS_ERR_EXTERNAL when
// it throws (its message is kept: e.g. IPPE's "points are not coplanar"), RS_ERR_USAGE for a
// bad Ndistortion. Never prints.
rs_status rs_calib_opencv_pnp(// out
                              double *rt_cam_ref,        // (6,)
                              bool *inlier,              // (N,) may be NULL
                              // in
                              const double *p_ref,       // (N,3) landmarks, metres
                              const double *q_px,        // (N,2) observed pixels
                              int N,
                              const double *intrinsics,  // (4 + Ndistortion,) fx fy cx cy k...
                              int Ndistortion,           // 0, 4, 5, 8, 12 or 14
                              rs_calib_opencv_pnp_method method,
                              bool refine_lm,
                              double ransac_threshold_px, // RANSAC only, pixels
                              rs_err *err);              // may be NULL

// ---- audits (roadside audit, issue 4) ----

// Convex hull of N points by cv::convexHull (Sklansky), its area by cv::contourArea, and for
// each of Nquery query points whether it lies inside or on the hull (cv::pointPolygonTest).
// N < 3 gives area 0 and nothing inside. Coordinates in any unit; area in that unit squared.
rs_status rs_calib_opencv_convex_hull(// out
                                      double *area,
                                      unsigned char *inside,  // (Nquery,) 1/0, may be NULL
                                      // in
                                      const double *xy,       // (N,2)
                                      int N,
                                      const double *query,    // (Nquery,2), may be NULL
                                      int Nquery,
                                      rs_err *err);           // may be NULL

// Singular values s (descending) and right singular vectors Vt (3,3 row-major: row k is the
// k-th principal direction) of the (N,3) matrix p (the caller centres it), by cv::SVD.
rs_status rs_calib_opencv_principal_axes3(// out
                                          double *s,       // (3,)
                                          double *Vt,      // (3,3)
                                          // in
                                          const double *p, // (N,3)
                                          int N,           // >= 1
                                          rs_err *err);    // may be NULL

// An OpenCV-style calibration file read by cv::FileStorage (.yaml/.yml/.json): the camera
// matrix under "camera_matrix" or "K" (3,3), distortion under "distortion_coefficients", "D" or
// "dist" (0, 4, 5, 8, 12 or 14 values; absent: none), the rotation as "R" / "R_cam_enu" (3,3)
// or "rvec" / "r" (3), the translation "tvec" / "t" (3), optionally "P" (3,4),
// "image_width", "image_height". Matrices may be OpenCV matrices or nested number lists.
typedef struct {
    double K[9];
    double dist[14];
    int Ndist;
    int width, height;      // 0 when absent
    int has_R;              // R (3,3) given; R_nearest and rvec are its nearest rotation
    double R[9];            // as given, row-major
    double rvec[3];         // Rodrigues vector of the rotation (given, or from R_nearest)
    double t[3];
    int has_P;
    double P[12];           // (3,4) row-major
} rs_calib_opencv_calibration;

// Returns RS_ERR_IO (cannot open), RS_ERR_PARSE (malformed, of the wrong shape or type),
// RS_ERR_INVALID (no pose, non-finite values, R with det <= 0), with "PATH: FIELD: what".
rs_status rs_calib_opencv_read_calibration(// out
                                           rs_calib_opencv_calibration *cal,
                                           // in
                                           const char *path, rs_err *err);

// ---- images (roadside report) ----

// Reads an image file (JPEG, or anything cv::imread decodes) as 8-bit B, G, R, A bytes per
// pixel, rows top to bottom without padding: the byte layout of cairo's CAIRO_FORMAT_ARGB32 on
// little-endian machines (alpha 255). *bgra is malloc'ed (caller frees); NULL on failure.
// Returns RS_ERR_PARSE (not a readable image), RS_ERR_NOMEM, RS_ERR_EXTERNAL (OpenCV threw).
rs_status rs_calib_opencv_read_image_bgra(// out
                                          unsigned char **bgra, // (height,width,4)
                                          int *width, int *height,
                                          // in
                                          const char *path, rs_err *err);

#ifdef __cplusplus
}
#endif

#ifdef __cplusplus
extern "C" {
#endif

// Rodrigues vector of a rotation matrix, correct for every rotation. mrcal 2.2's r_from_R
// returns r = 0 for a half-turn (e.g. diag(1,-1,-1): a camera looking straight down) and is
// wrong by pi within ~1e-6 rad of it (OpenCV's cv::Rodrigues snaps such rotations to exactly
// pi: 1e-6 off). So mrcal's answer is checked by turning it back into a matrix (max element
// difference 1e-12), and where it fails Eigen's AngleAxisd (through a quaternion) gives r.
// Accuracy: 1e-12 in the matrix, every rotation (tests/calib/test_r_from_R_halfturn.c).
// in: R (3,3) row-major rotation; out: r (3,) radians.
void rs_calib_r_from_R(double r[3], const double R[9]);

#ifdef __cplusplus
}
#endif

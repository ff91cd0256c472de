// rs_audit_opencv.h -- the OpenCV shim of the audit (audit/rs_audit_opencv.cc). Internal to audit.
#pragma once
#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// Convex hull of N points by cv::convexHull (Sklansky), its area by cv::contourArea, and for
// each of Nquery query points whether it lies inside or on the hull (cv::pointPolygonTest).
// N < 3 gives area 0 and nothing inside. Coordinates in any unit; area in that unit squared.
rs_status rs_audit_opencv_convex_hull( // out
    double *area,
    unsigned char *inside, // (Nquery,) 1/0, may be NULL
    // in
    const double *xy, // (N,2)
    int N,
    const double *query, // (Nquery,2), may be NULL
    int Nquery,
    rs_err *err); // may be NULL

// Singular values s (descending) and right singular vectors Vt (3,3 row-major: row k is the
// k-th principal direction) of the (N,3) matrix p (the caller centres it), by cv::SVD.
rs_status rs_audit_opencv_principal_axes3( // out
    double *s,                             // (3,)
    double *Vt,                            // (3,3)
    // in
    const double *p, // (N,3)
    int N,           // >= 1
    rs_err *err);    // may be NULL

// An OpenCV-style calibration file read by cv::FileStorage (.yaml/.yml/.json): the camera
// matrix under "camera_matrix" or "K" (3,3), distortion under "distortion_coefficients", "D" or
// "dist" (0, 4, 5, 8, 12 or 14 values; absent: none), the rotation as "R" / "R_cam_enu" (3,3)
// or "rvec" / "r" (3), the translation "tvec" / "t" (3), optionally "P" (3,4),
// "image_width", "image_height". Matrices may be OpenCV matrices or nested number lists.
#ifdef __cplusplus
}
#endif

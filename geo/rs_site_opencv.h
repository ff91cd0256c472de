// rs_site_opencv.h -- the OpenCV shim of the site module: reads OpenCV-style camera intrinsics
// (.yaml/.yml as written by cv::FileStorage, or .json) through cv::FileStorage.
// Internal to geo/; C header of geo/rs_site_opencv.cc.
#pragma once
#include "rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// Reads image_width, image_height, camera_matrix (3x3) and distortion_coefficients (0, 4, 5, 8,
// 12 or 14 values; a missing field means none) from `path`. Matrices may be OpenCV matrices
// ({"rows", "cols", "dt", "data"} / !!opencv-matrix) or plain (nested) number sequences.
//
// out: K (3,3) row-major; dist (14,) of which the first *Ndist are set; width, height in pixels
// Returns RS_ERR_IO (cannot open), RS_ERR_PARSE (malformed, a field missing or of the wrong
// type), RS_ERR_INVALID (a wrong count, a non-finite or non-positive value), with "PATH: FIELD:
// what" in err.
rs_status rs_site_opencv_read_intrinsics(// out
                                         double K[9], double dist[14], int *Ndist,
                                         int *width, int *height,
                                         // in
                                         const char *path, rs_err *err);

#ifdef __cplusplus
}
#endif

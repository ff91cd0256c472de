// rs_opencv.h -- the OpenCV shim of core (core/rs_opencv.cc): OpenCV-style camera files through
// cv::FileStorage. Internal to core: use core/rs_camera.h. (The image files of core/rs_image.h
// are implemented in the same shim, behind that public header.)
#pragma once
#include <stdbool.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// The fields of an OpenCV-style camera file, as found (rs_camera.h lists the keys).
typedef struct {
    double K[9]; // (3,3) row-major
    double dist[14];
    int Ndist;         // 0, 4, 5, 8, 12 or 14
    int width, height; // 0 when absent
    bool fisheye;      // distortion_model "fisheye", "equidistant" or "kannala_brandt": the 4
                       //   coefficients are OpenCV's fisheye k1..k4 (rs_camera_init_kannala_brandt)
    bool has_rotation; // R or rvec given
    bool has_R;        // R given: rvec is the Rodrigues vector of its nearest rotation
    double R[9];       // as given, row-major
    double rvec[3];
    bool has_t;
    double t[3];
    bool has_P;
    double P[12]; // (3,4) row-major
} rs_camera_opencv_file;

// Reads `path` with cv::FileStorage. Errors as "PATH: FIELD: what" (rs_camera_read).
rs_status rs_camera_opencv_read( // out
    rs_camera_opencv_file *f,
    // in
    const char *path, rs_err *err);

// The text of an OpenCV YAML camera file (rs_camera_write_opencv_yaml). *text is malloc'ed
// (caller frees). Returns RS_ERR_EXTERNAL when OpenCV throws, RS_ERR_NOMEM.
rs_status rs_camera_opencv_yaml_text( // out
    char **text,
    // in
    const double *intrinsics, // (4 + Ndistortion,)
    int Ndistortion, const double rt_cam_enu[6], int width, int height, rs_err *err);

#ifdef __cplusplus
}
#endif

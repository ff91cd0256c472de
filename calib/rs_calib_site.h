// rs_calib_site.h -- calibrating the cameras of a site: from an rs_site camera to an
// rs_calib_problem, the files `roadside calib` writes, and reading a calibrated camera back.
//
// Files written for camera <id> into the output folder (each atomically; docs/calibration.md
// describes every field):
//   <id>.cameramodel      mrcal .cameramodel: final intrinsics, extrinsics = rt_cam_enu (the
//                         reference frame is the site ENU); readable by mrcal's own tools
//   <id>.json             the result: pose, covariance, sigmas, yaw/pitch/roll, per-landmark
//                         residuals and inlier flags, solver statistics
//   <id>.opencv.yaml      K, distortion, R, t, image size (cv::FileStorage), written only when
//                         the lens model has an OpenCV equivalent (PINHOLE, OPENCV4/5/8/12)
//   <id>.homography.json  the 3x3 map H_ground_from_px from undistorted pixels (the pinhole
//                         core fx, fy, cx, cy; no distortion) to ground (E, N) on the site's
//                         ground plane, and its inverse H_px_from_ground
#pragma once
#include <stdbool.h>

#include <mrcal/mrcal.h>

#include "calib/rs_calib.h"
#include "core/rs_status.h"
#include "geo/rs_site.h"

#ifdef __cplusplus
extern "C" {
#endif

// The arrays an rs_calib_problem points into, for one camera of a site.
typedef struct {
    rs_calib_problem problem; // points into the arrays below and into the site (camera's lens
                              // model and intrinsics): valid while both live
    double *p_enu_m;          // (N,3) owned
    double *sigma_enu_m;      // (N,3) owned
    double *q_px;             // (N,2) owned
    double *sigma_px;         // (N,) owned
} rs_calib_site_problem;

// Builds camera icam's problem from the site: every observation, its landmark's surveyed ENU
// position with (sigma_h, sigma_h, sigma_v), the pixel and its sigma, the lens model and
// nominal intrinsics, the image size and the position prior if any.
rs_status rs_calib_site_problem_init( // out
    rs_calib_site_problem *sp,
    // in
    const rs_site *site, int icam, rs_err *err);
void rs_calib_site_problem_free(rs_calib_site_problem *sp); // NULL-safe

// Writes the four files of camera icam into out_dir (which must exist). The result must come
// from rs_calib_site_problem_init(site, icam) + rs_calib_solve.
rs_status rs_calib_site_write(const char *out_dir, const rs_site *site, int icam, const rs_calib_result *result,
                              rs_err *err);

// RMS reprojection error, in pixels, of the inliers' SURVEYED landmark positions through the
// solved pose and intrinsics: what a tool that trusts the survey (OpenCV's solvePnP, a
// homography) would call its reprojection error. (The result's rms_px is smaller: there the
// landmarks have moved within their survey sigmas.) q_px (N,2) receives every observation's
// projection (NaN where it fails); may be NULL. Returns NaN when no inlier projects.
double rs_calib_site_rms_surveyed_px(const rs_site *site, int icam, const rs_calib_result *result,
                                     double *q_px); // (N,2) may be NULL

// The result of one camera as JSON text (the content of <id>.json). Caller frees with free().
// Returns NULL when out of memory.
char *rs_calib_site_result_json(const rs_site *site, int icam, const rs_calib_result *result);

// The homography between undistorted pixels and the ground plane n . p = offset (n_up != 0),
// parametrised by (E, N): p = (E, N, (offset - n_e E - n_n N) / n_u).
// out: H_px_from_ground, H_ground_from_px (3,3) row-major, each scaled so that [2][2] = 1 when
//      that element is not ~0
// in:  fxycxy: the pinhole core (fx, fy, cx, cy) of the intrinsics
// Returns RS_ERR_DEGENERATE when the plane is vertical (n_u ~ 0) or the camera lies in it.
rs_status rs_calib_ground_homography( // out
    double H_px_from_ground[9], double H_ground_from_px[9],
    // in
    const double fxycxy[4], const double rt_cam_enu[6], const double plane_normal_enu[3], double plane_offset_m,
    rs_err *err);

// ---- reading <id>.json back (the report reads calibrations through this) ----

// One landmark of a calibration result file.
typedef struct {
    char *id; // owned
    bool inlier;
    double observed_px[2];      // the pick
    double predicted_px[2];     // the landmark's projection (refined position for inliers)
    double residual_px[2];      // predicted - observed
    double normalised_residual; // sqrt(block chi2), sigmas
} rs_calib_site_landmark;

// What <id>.json (rs_calib_site_write) says, read back: the pose summary, the solver's figures,
// the landmarks and the warnings. The fields are those of rs_calib_result with the same names.
typedef struct {
    double position_enu_m[3], sigma_position_enu_m[3]; // metres
    double position_llh[3];                            // lat_deg, lon_deg, h_m (ellipsoidal)
    double yaw_pitch_roll_deg[3], sigma_yaw_pitch_roll_deg[3];
    double rms_px, variance_factor, condition_number;
    int Nused, Nrejected; // landmarks used, rejected as outliers
    char *lensmodel;      // owned: the mrcal lens model name
    int N;
    rs_calib_site_landmark *landmarks; // (N,) owned
    int Nwarnings;
    char **warnings; // (Nwarnings,) owned strings
} rs_calib_site_result;

// Reads a calibration result file. *out is zeroed first; free it with rs_calib_site_result_free
// whatever the outcome. Errors: RS_ERR_IO (unreadable), RS_ERR_PARSE (not JSON, a field missing
// or of the wrong type: "PATH: FIELD: what"), RS_ERR_NOMEM.
rs_status rs_calib_site_result_read( // out
    rs_calib_site_result *out,
    // in
    const char *path, rs_err *err);
void rs_calib_site_result_free(rs_calib_site_result *r); // NULL-safe; zeroes *r

#ifdef __cplusplus
}
#endif

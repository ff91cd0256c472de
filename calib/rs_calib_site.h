// rs_calib_site.h -- calibrating the cameras of a site: from an rs_site camera to an
// rs_calib_problem, the files `roadside calib` writes, and reading a calibrated camera back.
//
// Files written for camera <id> into the output folder, all or nothing (rs_calib_site_write;
// docs/calibration.md describes every field):
//   <id>.cameramodel      mrcal .cameramodel: final intrinsics, extrinsics = rt_cam_enu (the
//                         reference frame is the site ENU); readable by mrcal's own tools
//   <id>.json             the result: pose, covariance, sigmas, yaw/pitch/roll, per-landmark
//                         residuals and inlier flags, solver statistics
//   <id>.opencv.yaml      K, distortion, R, t, image size (cv::FileStorage), written only when
//                         the lens model has an OpenCV equivalent (PINHOLE, OPENCV4/5/8/12)
//   <id>.homography.json  the 3x3 map H_ground_from_px from undistorted pixels (the pinhole
//                         core fx, fy, cx, cy; no distortion) to ground (E, N) on the site's
//                         ground plane, and its inverse H_px_from_ground; where the landmarks
//                         cannot determine a refined focal (rs_calib_result.focal_undetermined)
//                         also "least_squares": the homography they do determine, fitted to the
//                         inliers' picks, with its scatter
// and, last, the run record calib.run.json (rs_calib_site_run_write): which cameras this run
// wrote, which failed (and which of their earlier files it removed), which it did not touch.
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
    rs_calib_polyline *along; // (N,) owned, NULL when no pick is `along`: each along pick's
                              //   polyline (a line's vertices belong to the site)
    double *pole_vertices_m;  // (N,6) owned, with along: a pole's base and top
    int *survey_shared;       // (N,) owned: the landmark index of a pole's or line's pick, -1 for a point
} rs_calib_site_problem;

// Builds camera icam's problem from the site: every observation, its landmark's surveyed ENU
// position with (sigma_h, sigma_h, sigma_v) (a pick along a pole or a line: its polyline), the
// pixel and its sigma, the lens model and
// nominal intrinsics, the image size and the position prior if any.
rs_status rs_calib_site_problem_init( // out
    rs_calib_site_problem *sp,
    // in
    const rs_site *site, int icam, rs_err *err);
void rs_calib_site_problem_free(rs_calib_site_problem *sp); // NULL-safe

// Replaces the solver's "(index 2,5; ..." in a warning with the landmark ids of camera icam's
// observations ("(landmarks L003, L006; ..."), in place (text of size bytes, truncated if need be).
void rs_calib_site_name_landmarks(char *text, size_t size, const rs_site *site, int icam);

// The first warning of the "; "-separated list `warnings` (rs_calib_warning_len) as a sentence:
// capitalised, ending in a full stop, its landmarks named by id (rs_calib_site_name_landmarks).
// Returns where the next warning starts, NULL when warnings holds none (then sentence is "").
// out: sentence (size bytes, NUL-terminated, truncated if need be)
const char *rs_calib_site_warning_sentence(char *sentence, size_t size, const char *warnings, const rs_site *site,
                                           int icam);

// Writes the files of camera icam into out_dir (which must exist), all or nothing: every file is
// first written under a temporary name, and only when all are complete are they renamed into
// place. *written receives the bits (rs_calib_site_calib_outputs' suffixes) of the files
// written. On any failure none of the camera's files is left in out_dir, not even those of an
// earlier run (they no longer match the site): *removed receives the bits of the files removed. On success *removed
// has the bit of an earlier <id>.opencv.yaml that this camera's lens model no longer has (it is
// removed: it would describe another calibration). The result must come from
// rs_calib_site_problem_init(site, icam) + rs_calib_solve. An id whose <id>.json would be a run
// record's name (calib.run, audit.run) is refused (RS_ERR_INVALID).
rs_status rs_calib_site_write( // out
    unsigned *written,         // may be NULL: the bits of the files written
    unsigned *removed,         // may be NULL
    // in
    const char *out_dir, const rs_site *site, int icam, const rs_calib_result *result, rs_err *err);

// ---- the outputs of a run, and its record ----
//
// `roadside calib` and `roadside audit` write, per camera, a fixed set of files named
// <id><suffix> into one folder. A run's outputs are all or nothing per camera: a camera that
// fails leaves none of its files, and the files an earlier run wrote for it are removed (only
// the names <id><suffix> of that command, never anything else). The run ends by writing its
// record, atomically and last: OUT/<record>, a JSON object
//   {"command": "roadside calib", "site": "/absolute/site/folder", "complete": true|false,
//    "error": null | "why the run wrote nothing",
//    "cameras": [{"id": "cam1", "status": "written", "files": ["cam1.cameramodel", ...]},
//                {"id": "cam3", "status": "failed", "error": "...", "removed": [...]},
//                {"id": "cam2", "status": "not selected"}]}
// "complete" is true when every selected camera was written. A camera "not selected" (--camera)
// keeps whatever an earlier run wrote for it. The record's name cannot be an output of a camera:
// calib refuses the ids "calib.run" and "audit.run".

// What one command writes per camera.
typedef struct {
    const char *record;          // the run record's file name in the output folder
    const char *command;         // "roadside calib": written into the record
    const char *const *suffixes; // (Nsuffixes,) the ends of a camera's file names; bit k of a
                                 //   mask below stands for suffixes[k]
    int Nsuffixes;               // <= 16
} rs_calib_site_outputs;

// roadside calib's: .cameramodel, .json, .opencv.yaml, .homography.json; record calib.run.json.
// The two that are this module's own formats (the camera files are core's: RS_CAMERA_EXT_*);
// a path is rs_camera_path(out, n, calib_dir, id, RS_CALIB_SITE_EXT_JSON).
#define RS_CALIB_SITE_EXT_JSON       ".json"
#define RS_CALIB_SITE_EXT_HOMOGRAPHY ".homography.json"
extern const rs_calib_site_outputs rs_calib_site_calib_outputs;

typedef enum {
    RS_CALIB_SITE_RUN_WRITTEN,     // every file of the camera written by this run
    RS_CALIB_SITE_RUN_FAILED,      // nothing written; its earlier files removed
    RS_CALIB_SITE_RUN_NOT_SELECTED // not part of this run: earlier files, if any, left as they were
} rs_calib_site_run_status;

// One camera of a run.
typedef struct {
    const char *id;
    rs_calib_site_run_status status;
    unsigned files;    // WRITTEN: the files written; FAILED: the earlier files removed (bits of
                       //   the suffixes)
    const char *error; // FAILED: why; may be NULL
} rs_calib_site_run_camera;

// Removes camera id's outputs (out_dir/<id><suffix> for each suffix of `outputs`; a folder of
// that name is not removed, nor a run record calib.run.json or audit.run.json) from out_dir.
// out: *removed (may be NULL): the bits of the files that were there and are removed
// Errors: RS_ERR_INVALID (an id that cannot name a file), RS_ERR_IO (a file that could not be
// removed; the others are still tried), RS_ERR_NOMEM.
rs_status rs_calib_site_outputs_remove( // out
    unsigned *removed,                  // may be NULL
    // in
    const char *out_dir, const char *id, const rs_calib_site_outputs *outputs, rs_err *err);

// The file names of id's outputs in `mask`, ", "-separated ("cam3.cameramodel, cam3.json"; ""
// for an empty mask). Caller frees; NULL when out of memory.
char *rs_calib_site_outputs_names(const char *id, unsigned mask, const rs_calib_site_outputs *outputs);

// Writes the run record out_dir/<outputs->record> (see above) atomically. site_dir: the site
// folder as given (recorded resolved to an absolute path); error: why the run wrote nothing
// (may be NULL); cameras (N,): every camera of the site, in order.
rs_status rs_calib_site_run_write(const char *out_dir, const rs_calib_site_outputs *outputs, const char *site_dir,
                                  const char *error, const rs_calib_site_run_camera *cameras, int N, rs_err *err);

// What a run wrote and did not, in words, for the command to print (caller frees; NULL when out
// of memory): "written to OUT/: cam1, cam2" (or "no camera written: OUT/ holds no output of this
// run"), then one line per failed camera "not written: cam3: failed (ERROR); its earlier outputs
// removed: cam3.cameramodel, ..." and one for the cameras not selected. Every line ends in '\n'.
char *rs_calib_site_run_summary(const char *out_dir, const rs_calib_site_outputs *outputs,
                                const rs_calib_site_run_camera *cameras, int N);

// A run whose site could not be read (rs_site_load failed with `error`): no camera can be
// written, so the outputs an earlier run of the same command and the same site folder wrote
// into out_dir are superseded and removed. The cameras are those out_dir's run record lists
// as written or not selected, restricted to `only` when Nonly > 0 (--camera); then the record
// is rewritten (those cameras failed, the others not selected, `error` given). Nothing happens
// when out_dir holds no record of this command for this site folder (a mistyped SITE never
// empties another site's folder).
// out: *removed: the names of the files removed, ", "-separated, "" when none (caller frees)
// Errors: RS_ERR_IO (a file could not be removed, or the record not written), RS_ERR_NOMEM.
rs_status rs_calib_site_run_abandon( // out
    char **removed,
    // in
    const char *out_dir, const rs_calib_site_outputs *outputs, const char *site_dir, const char *const *only,
    int Nonly, // (Nonly,) camera ids; all when Nonly == 0
    const char *error, rs_err *err);

// rms_surveyed_px, the headline residual (docs/calibration.md, "Residuals: which is which"):
// the RMS reprojection error, in pixels, of the inliers' SURVEYED landmark positions through the
// solved pose and intrinsics: what anyone can check, and what a tool that trusts the survey
// (OpenCV's solvePnP, a homography) would call its reprojection error. (The result's rms_px,
// written as rms_adjusted_px, is smaller: there the landmarks have moved within their survey
// sigmas.) q_px (N,2) receives every observation's projection (NaN where it fails); may be NULL.
// Returns NaN when no inlier projects.
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

// One landmark of a calibration result file. "surveyed": the landmark's surveyed position
// projected through the calibrated camera; "adjusted": its position after the adjustment (moved
// within its survey sigmas; the surveyed one for outliers) projected (docs/calibration.md,
// "Residuals: which is which").
typedef struct {
    char *id; // owned
    bool inlier;
    double observed_px[2];           // the pick
    double predicted_surveyed_px[2]; // the surveyed position's projection (NaN: not in the file)
    double residual_surveyed_px[2];  // predicted_surveyed_px - observed (NaN: not in the file)
    double predicted_adjusted_px[2]; // the adjusted position's projection
    double residual_adjusted_px[2];  // predicted_adjusted_px - observed
    double normalised_residual;      // sqrt(block chi2), sigmas
} rs_calib_site_landmark;

// What <id>.json (rs_calib_site_write) says, read back: the pose summary, the solver's figures,
// the landmarks and the warnings. The fields are those of the file with the same names.
// Files written before the residuals were renamed are read too: their rms_px is
// rms_adjusted_px, their rms_px_surveyed rms_surveyed_px, their landmarks' predicted_px and
// residual_px the adjusted ones.
typedef struct {
    double position_enu_m[3], sigma_position_enu_m[3]; // metres
    double position_llh[3];                            // lat_deg, lon_deg, h_m (ellipsoidal)
    double yaw_pitch_roll_deg[3], sigma_yaw_pitch_roll_deg[3];
    double rms_surveyed_px; // the headline: RMS of the inliers' surveyed positions reprojected,
                            //   px; NaN when the file has none (null, or a file older than it)
    double rms_adjusted_px; // RMS after the landmarks moved within their survey sigmas, px
    double variance_factor, condition_number;
    int Nused, Nrejected; // landmarks used, rejected as outliers
    char *lensmodel;      // owned: the mrcal lens model name
    int N;
    rs_calib_site_landmark *landmarks; // (N,) owned
    int Nwarnings;
    char **warnings; // (Nwarnings,) owned strings
    // intrinsics_check (docs/calibration.md 7a): the image says the focal length (the principal
    // point) differs from the nominal beyond chance (chi2 above its critical value); focal_rel:
    // the data's f / f_nominal - 1 (NaN: not tested, or a file older than the check)
    bool focal_off, center_off;
    double focal_rel;
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

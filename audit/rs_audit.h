// rs_audit.h -- should this camera's calibration be trusted? The numbers behind `roadside audit`
// (and the tables and maps of `roadside report`).
//
// Purpose: for one camera, from its surveyed landmarks and pixel picks (an rs_calib_problem):
//   - leave-one-out cross-validation: every landmark is left out in turn, the pose re-solved with
//     rs_calib_solve() from the others, and the left-out landmark's surveyed position projected
//     (its predicted pixel error) and its observed pixel located on the ground plane through it
//     (its ground error in metres);
//   - normalised residuals and outlier flags, each flag with its reason in words;
//   - influence: how far leaving a landmark out moves the camera (metres) and turns it (degrees);
//   - coverage: the share of the image inside the convex hull of the inlier landmarks' picks, and
//     the share of the ground the camera sees (within opt->range_m) that their (E, N) hull spans;
//   - degeneracy indicators in plain words (condition number, near-collinear, clustered in the
//     image, near-planar landmarks seen almost head-on, few landmarks);
//   - a ground localisation uncertainty map (rs_audit_map) over the ground the camera sees;
//   - optionally (--against) a test of whether the camera has moved since its picks were made;
//   - optionally (--calib) the audit of a calibration made elsewhere (rs_audit_calibration):
//     its reprojection errors against the site's picks and whether its parts agree.
// Residuals are named as everywhere else (docs/calibration.md, "Residuals: which is which"):
// rms_surveyed_px, the headline and what the threshold applies to, is the RMS of the inliers'
// SURVEYED positions reprojected through the calibration audited; the solver's own RMS after
// the landmarks moved within their survey sigmas is rms_adjusted_px (solve.rms_px), and the
// leave-one-out figures are loo_*.
//
// Method:
//   Uncertainty of a ground point g = (E, N) located from a pixel q: g is the solution of
//   q = project(intrinsics, R(r) p(g) + t), p(g) = (E, N, (offset - n_E E - n_N N) / n_U) on the
//   ground plane n . p = offset. By the implicit function theorem, with A = dq/dg (2,2) and
//   B = dq/drt (2,6) from mrcal_project + mrcal_transform_point_rt (analytic gradients):
//     dg/drt = -A^-1 B,  dg/dq = A^-1,
//     Cov(g) = A^-1 (B C_rt B^T + sigma_det^2 I) A^-T
//   with C_rt the 6x6 pose covariance of rs_calib_solve and sigma_det the detection noise (px,
//   per axis). The map holds sqrt(trace Cov(g)) = sqrt(sigma_E^2 + sigma_N^2), the 1-sigma
//   horizontal radial error (first-order; tests/audit/test_audit.c checks it against a Monte
//   Carlo run of rs_camera_locate_ground with poses drawn from C_rt: within 10%).
//   Moved camera (--against): new picks q_new of the landmarks against the picks q_old the
//   calibration was made from. If the camera did not move, q_new - q_old ~ N(0, (s_old^2 +
//   s_new^2) I) per landmark -- independent of the survey errors, which both picks share. The
//   statistic T = sum |q_new - q_old|^2 / (s_old^2 + s_new^2) over the landmarks that are inliers
//   of both solves is chi-square with 2M degrees of freedom; the camera is declared moved when
//   P(chi2_2M > T) < opt->alpha. The rotation and shift are those between the stored pose and
//   the pose re-solved (rs_calib_solve) from the new picks.
//   Consistency of an external calibration with a projection matrix P (3,4): P is compared with
//   K [R | t] by projecting the site's landmarks through both (pinhole, no distortion: P has
//   none) after fixing P's free scale by least squares; they disagree when the largest pixel
//   difference exceeds opt->consistency_px. R must be a rotation (|R^T R - I| < 1e-6, det +1).
//
// Conventions (docs/conventions.md): rt_cam_enu maps site ENU into the camera; pixel (0,0) is
// the centre of the top-left pixel; ground grid rows go north, columns east.
//
// Cost: one full solve plus N leave-one-out solves (~1 ms each for 20 landmarks), plus the map
// (one projection and one rs_camera_locate_ground per cell within range). Measured: `roadside
// audit sites/demo` (4 cameras, 11-14 landmarks, 1 m cells to 100 m) 0.3 s wall on an idle
// 2-core machine, 1.8 s while other jobs ran; with --range-m 10 1.0 s under the same load.
#pragma once
#include <stdbool.h>
#include <stddef.h>

#include <mrcal/mrcal.h>

#include "calib/rs_calib.h"
#include "calib/rs_calib_site.h"
#include "core/rs_status.h"
#include "geo/rs_site.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    rs_calib_options calib;     // options of every solve: the full one and leave-one-out
                                //   (default rs_calib_options_default)
    double need_ground_m;       // what the site is for: the 1-sigma horizontal ground accuracy
                                //   needed where the landmarks are (the intersection), metres
                                //   (default 1). The thresholds below left at 0 derive from it
                                //   (rs_audit_result.thresholds says what they came to)
    double max_rms_surveyed_px; // the camera FAILS when rms_surveyed_px exceeds this; 0 (the
                                //   default): need_ground_m in pixels at the landmarks
                                //   (rs_audit_result.px_per_m): 23 px on the demo's cam1
    double max_loo_px;          // ... when the RMS of the inliers' leave-one-out pixel errors
                                //   exceeds this; 0 (default): need_ground_m in pixels, as above
    double max_loo_m;           // ... when the MEDIAN of the inliers' leave-one-out ground
                                //   errors exceeds this, metres; 0 (default): need_ground_m
    double max_ground_sigma_m;  // ... when the predicted 1-sigma ground error (the map) exceeds
                                //   this over 10% or more of the landmarks' area (its 90th
                                //   percentile there), metres; 0 (default): need_ground_m
    double detection_sigma_px;  // detection noise of a located vehicle, px per axis (default 1)
    double range_m;             // horizontal distance from the camera up to which the ground
                                //   counts as seen (map, ground coverage), metres (default 100)
    double cell_m;              // map cell size, metres (default 1)
    double alpha;               // significance of the moved-camera test (default 0.001)
    double consistency_px;      // P vs K[R|t]: largest tolerated pixel difference (default 0.5)
    bool leave_one_out;         // run the leave-one-out re-solves (default true)
    bool map;                   // compute the uncertainty map (default true)
} rs_audit_options;

// Fills opt with the defaults above. opt must not be NULL.
void rs_audit_options_default(rs_audit_options *opt);

// One landmark of the camera (index i of the problem's arrays).
typedef struct {
    bool inlier;                    // used by the full solve
    double residual_surveyed_px[2]; // its SURVEYED position projected through the full solve,
                                    //   minus observed (NaN when it does not project)
    double residual_adjusted_px[2]; // the solver's residual_px: its position after the
                                    //   adjustment projected, minus observed
    double normalised_residual;     // sqrt(block chi2) in sigmas (rs_calib_result)
    char reason[160];               // why it is flagged, in words; "" when it is fine
    bool loo_ok;                    // the re-solve without it succeeded (else loo_* are NaN)
    double loo_predicted_px[2];     // its SURVEYED position projected with the re-solved pose
    double loo_error_px;            // |loo_predicted_px - observed|, px
    double loo_normalised;          // loo_predicted_px - observed in sigmas: sqrt(d^T S^-1 d) with
                                    //   S = its pixel sigma^2 I + the propagated survey sigmas of
                                    //   the landmark + the re-solved pose covariance (2 dof; flagged
                                    //   when > calib.outlier_threshold)
    double loo_ground_error_m;      // distance from its surveyed position to where its observed
                                    //   pixel's ray (re-solved pose) meets the plane with the
                                    //   site's ground normal through it, metres
    double influence_m;             // |camera position without it - with it|, metres
    double influence_deg;           // rotation angle between the two orientations, degrees
    double sigma_ground_m;          // the map's predicted 1-sigma ground error at its surveyed
                                    //   (E, N) (nearest cell), metres; NaN without a map there
    double distance_m;              // horizontal distance from the camera, metres
} rs_audit_landmark;

// The ground localisation uncertainty map: a regular grid in site ENU (E, N) on the ground
// plane. Cell (iy, ix) has its CENTRE at (e0_m + ix cell_m, n0_m + iy cell_m).
typedef struct {
    double e0_m, n0_m;         // ENU east, north of the centre of cell (0, 0), metres
    double cell_m;             // cell size, metres
    int nx, ny;                // columns (east), rows (north)
    double *sigma_m;           // (ny,nx) row-major: 1-sigma horizontal error sqrt(sE^2 + sN^2)
                               //   in metres; NaN where the camera does not see the ground
                               //   (behind it, outside the image, beyond range_m) (owned)
    double detection_sigma_px; // the detection noise it assumes, px
    double range_m;            // the range it covers, metres
    double camera_en_m[2];     // the camera's (E, N), metres (for drawing)
} rs_audit_map;

// The moved-camera test (Method above).
typedef struct {
    int M;                         // landmarks compared (inliers of both solves)
    double chi2;                   // T
    int dof;                       // 2M
    double p_value;                // P(chi2_dof > T)
    bool moved;                    // p_value < alpha
    double rms_shift_px;           // RMS of |q_new - q_old| over the M landmarks
    double rotation_deg;           // angle of R_new R_stored^T, degrees
    double shift_m;                // |position_new - position_stored|, metres
    double dyaw_pitch_roll_deg[3]; // new - stored yaw, pitch, roll (yaw wrapped to +-180)
    double shift_enu_m[3];         // position_new - position_stored, metres
    double rt_cam_enu_new[6];      // the pose re-solved from the new picks
    char message[256];             // the verdict in words
} rs_audit_against;

// A calibration made elsewhere, to audit against the site. Read from an mrcal .cameramodel
// (extrinsics = rt_cam_enu) or an OpenCV-style file (.yaml/.yml/.json read by cv::FileStorage):
// camera_matrix or K (3,3), distortion_coefficients or D/dist (0,4,5,8,12 values), the pose as
// R (3,3, R_cam_enu) or rvec (3), and t or tvec (3) (p_cam = R p_enu + t), optionally P (3,4),
// image_width, image_height.
typedef struct {
    char *path;            // owned: the file read
    rs_camera camera;      // owned: lens, intrinsics, size (0 x 0: not given) and the pose
                           //   (from R as given, projected to the nearest rotation)
    rs_camera_extra extra; // what an OpenCV file gave beyond the camera: R as given, P
} rs_audit_calibration;

// Reads a calibration file (see above). out is zeroed on failure; free with
// rs_audit_calibration_free. Errors: RS_ERR_IO, RS_ERR_PARSE, RS_ERR_INVALID (missing pose,
// wrong shapes, non-finite values), RS_ERR_UNSUPPORTED (skew, tilted sensor), naming the file
// and field.
rs_status rs_audit_calibration_read( // out
    rs_audit_calibration *out,
    // in
    const char *path, rs_err *err);
void rs_audit_calibration_free(rs_audit_calibration *cal); // NULL-safe

// What the audit says about an external calibration.
typedef struct {
    double rms_surveyed_px;       // RMS of (its projection of the surveyed landmarks - picks)
                                  //   over the landmarks the site's solve keeps as inliers, px
    double max_px;                // the largest such error, px
    double *residual_surveyed_px; // (N,2) per landmark (owned)
    double rotation_deg;          // its orientation vs the site's solve, degrees
    double shift_m;               // its position vs the site's solve, metres
    double R_orthonormality;      // |R^T R - I|_F of R as given (0 without a matrix R)
    double P_max_px;              // largest pixel difference P vs K[R|t] over the landmarks
                                  //   (NaN without P)
    double P_scale;               // the scale s fitted in P ~ s K[R|t] (NaN without P)
    bool consistent;              // its parts agree (R is a rotation, P matches K[R|t])
    char consistency[512];        // what disagrees, in words ("" when consistent)
} rs_audit_external;

typedef struct {
    int N;                        // landmarks of the problem
    rs_calib_result solve;        // the full solve (owned: rs_audit_result_free frees it);
                                  //   solve.rms_px is its rms_adjusted_px
    rs_audit_landmark *landmarks; // (N,) (owned)

    // the headline: RMS of the inliers' SURVEYED positions reprojected through the calibration
    // audited -- the external one when given (= external.rms_surveyed_px), else the full
    // solve's -- minus their picks, px (NaN when none projects). Checked against
    // max_rms_surveyed_px.
    double rms_surveyed_px;

    // leave-one-out summary over the inliers whose re-solve succeeded
    int loo_count;
    double loo_rms_px, loo_max_px;  // px
    double loo_median_m, loo_max_m; // metres

    // coverage
    double image_hull_share;  // [0,1]: image area inside the hull of the inlier picks
    double ground_seen_m2;    // ground area the camera sees within range_m, m^2
    double ground_hull_share; // [0,1]: share of it inside the inliers' (E, N) hull
    // the predicted 1-sigma ground error (the map) inside the inliers' (E, N) hull, "where the
    // landmarks are": median and 90th percentile over its cells, metres (NaN without a map)
    double ground_sigma_inside_median_m, ground_sigma_inside_p90_m;

    // the thresholds applied (rs_audit_options, those left at 0 derived from need_ground_m)
    double px_per_m; // the pixel size of one metre of ground at the inlier landmarks: median of
                     //   sqrt(|det J|), J (2,2) = d(pixel)/d(ground E, N) at each, px/m
    struct {
        double need_ground_m, max_rms_surveyed_px, max_loo_px, max_loo_m, max_ground_sigma_m;
    } thresholds;

    // degeneracy indicators (numbers; the words are in `warnings`)
    double condition_number; // rs_calib_result.condition_number
    double collinearity;     // s2/s1 of the centred inlier landmarks (0: collinear)
    double planarity;        // s3/s1 (0: exactly planar)
    double head_on_deg;      // angle between the landmarks' best-fit plane normal and
                             //   the line of sight to their centroid (0: head-on)

    rs_audit_map map; // zeroed (sigma_m NULL) when opt->map is false

    bool has_against;
    rs_audit_against against;
    bool has_external;
    rs_audit_external external;

    bool pass;           // meets every threshold (and not moved, consistent)
    char failures[512];  // which thresholds fail, "; "-separated ("" when pass)
    char warnings[2048]; // degeneracy and other warnings in plain words,
                         //   "; "-separated ("" when none)
    char verdict[1536];  // the verdict in plain words for a city engineer, naming landmarks by
                         //   id: rs_audit_site_camera fills it (rs_audit_site_verdict); "" from
                         //   rs_audit_camera alone
} rs_audit_result;

// Audits one camera.
//
// out:  result (free with rs_audit_result_free, also on error: it is zeroed or filled)
// in:   problem: the camera's landmarks and picks (rs_calib_site_problem_init for a site camera)
//       ground_normal_enu (3), ground_offset_m: the ground plane n . p = offset
//       q_new_px (N,2), sigma_new_px (N,): new picks of the SAME landmarks for the moved-camera
//         test, rows with NaN u for landmarks not re-picked; may be NULL (no test)
//       external: a calibration made elsewhere; may be NULL. When given, its intrinsics replace
//         the problem's nominal ones in every solve, and its pose is the stored pose of the
//         moved-camera test (else the full solve's pose is).
// Errors: those of rs_calib_solve for the full solve (RS_ERR_DEGENERATE, ...) and for the
// solve of the new picks (prefixed "the new picks"), RS_ERR_INVALID (bad options, a vertical
// ground plane, a sigma_new_px <= 0), RS_ERR_DEGENERATE (fewer than 3 landmarks usable in both
// the old and the new picks), RS_ERR_NOMEM. A failing leave-one-out re-solve is not an error
// (loo_ok false); an external calibration whose image size differs is reported as inconsistent.
rs_status rs_audit_camera( // out
    rs_audit_result *result,
    // in
    const rs_calib_problem *problem, const double ground_normal_enu[3], double ground_offset_m,
    const double *q_new_px,               // (N,2), may be NULL
    const double *sigma_new_px,           // (N,), may be NULL: 1 px
    const rs_audit_calibration *external, // may be NULL
    const rs_audit_options *opt,          // may be NULL: defaults
    rs_err *err);                         // may be NULL

void rs_audit_result_free(rs_audit_result *result); // NULL-safe

// The 1-sigma horizontal radial error sqrt(sE^2 + sN^2) of the ground point seen at q_px
// (Method above; core/rs_camera_ground.h computes it, with C_q = detection_sigma_px^2 I), and
// optionally its 2x2 covariance. Returns RS_ERR_DEGENERATE when the pixel's
// ray misses the plane in front of the camera, RS_ERR_UNSUPPORTED for a lens model without
// unprojection.
rs_status rs_audit_ground_sigma( // out
    double *sigma_m,
    double *cov_en_m2, // (2,2) row-major, may be NULL
    double p_enu_m[3], // the located point, may be NULL
    // in
    const rs_camera *cam,           // calibrated: intrinsics, pose
    const double covariance_rt[36], // (6,6) row-major, of the pose
    const double q_px[2], double detection_sigma_px, const double ground_normal_enu[3], double ground_offset_m,
    rs_err *err); // may be NULL

// The same at a ground point (E, N) given in metres instead of a pixel: NaN (and RS_OK) when the
// camera does not see it (behind the camera or outside its image). Used for the map.
rs_status rs_audit_ground_sigma_at( // out
    double *sigma_m,
    // in
    const rs_camera *cam, // calibrated: intrinsics, size, pose
    const double covariance_rt[36], const double en_m[2], double detection_sigma_px, const double ground_normal_enu[3],
    double ground_offset_m, rs_err *err);

// ---- a site's cameras ----

// Audits camera icam of a site: its problem from the site (rs_calib_site_problem_init), the
// site's ground plane, new picks from against_csv (header "landmark,u,v[,sigma_px]", the site's
// observations format; may be NULL) and an external calibration file (may be NULL).
// Errors: those of rs_audit_camera, RS_ERR_IO/PARSE/NOT_FOUND for the CSV (file, line, field).
rs_status rs_audit_site_camera( // out
    rs_audit_result *result,
    // in
    const rs_site *site, int icam,
    const char *calib_path,      // may be NULL
    const char *against_csv,     // may be NULL
    const rs_audit_options *opt, // may be NULL
    rs_err *err);

// The verdict of an audit in plain words (what rs_audit_site_camera puts in result->verdict): the
// need it is judged against, the predicted ground accuracy where the landmarks are and at the
// farthest one, the held-out (leave-one-out) check, each outlier named by its landmark id with
// how far its pick lands from its survey on the ground and what to do, and the thresholds
// failed. `roadside audit` prints it and `roadside report` shows it: one text for both.
// out: text (size bytes, NUL-terminated, truncated if need be)
void rs_audit_site_verdict(char *text, size_t size, const rs_site *site, int icam, const rs_audit_result *result);

// The audit as JSON text (the content of <id>.audit.json; docs/audit.md lists the fields).
// Caller frees with free(); NULL when out of memory.
char *rs_audit_result_json(const rs_site *site, int icam, const rs_audit_result *result, const rs_audit_options *opt);

// Writes out_dir/<id>.audit.json atomically (out_dir must exist). On failure no <id>.audit.json
// is left in out_dir, not even an earlier run's (it would look like this run's).
rs_status rs_audit_site_write(const char *out_dir, const rs_site *site, int icam, const rs_audit_result *result,
                              const rs_audit_options *opt, rs_err *err);

// What `roadside audit` writes per camera (<id>.audit.json) and its run record audit.run.json:
// the run's outputs are all or nothing per camera, a camera that cannot be audited has its
// earlier <id>.audit.json removed (rs_calib_site_outputs_remove), and the record says which
// cameras were written, failed or not selected (calib/rs_calib_site.h describes it).
extern const rs_calib_site_outputs rs_audit_site_outputs;

#ifdef __cplusplus
}
#endif

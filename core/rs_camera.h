// rs_camera.h -- roadside's one camera type: an mrcal lens model, its intrinsics, the image size
// and the pose in the site frame. Every module uses it: the site's nominal cameras, the
// solver's problem, calibrated cameras read back, the simulator's true cameras, labels, eval.
//
// It is mrcal's mrcal_cameramodel_t (rt_cam_ref, imagersize, lensmodel, intrinsics) with the
// intrinsics held by pointer rather than as a flexible array, so that a camera can sit inside
// other structs and be copied by value as a view; the reference frame is always the site ENU
// frame, hence rt_cam_enu. .cameramodel files are read and written by mrcal itself; OpenCV-style
// YAML/JSON by cv::FileStorage (core/rs_opencv.cc). This file owns both formats: no
// other module reads or writes them.
//
// Conventions (docs/conventions.md): rt_cam_enu = mrcal Rodrigues r + translation t (metres),
// p_cam = R(r) p_enu + t; camera x right, y down, z forward; pixel (0,0) is the centre of the
// top-left pixel. OpenCV's K [fx 0 cx; 0 fy cy; 0 0 1] and distortion (k1 k2 p1 p2 [k3 [k4 k5
// k6 [s1 s2 s3 s4]]]) are mrcal's LENSMODEL_OPENCVn with the same coefficient order; no
// distortion (or all zero) is LENSMODEL_PINHOLE.
#pragma once
#include <stdbool.h>
#include <stddef.h>

#include <mrcal/mrcal.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    mrcal_lensmodel_t lensmodel;
    double *intrinsics;   // (Nintrinsics,) owned
    int Nintrinsics;      // mrcal_lensmodel_num_params(&lensmodel)
    int width, height;    // image size, pixels (0 x 0 only for an OpenCV file that gives none)
    double rt_cam_enu[6]; // the pose: maps site ENU into the camera (zero: no pose known)
} rs_camera;

// What an OpenCV-style file may carry beyond the camera (rs_camera_read with extra != NULL).
typedef struct {
    bool has_pose;       // a rotation (R or rvec) and a translation (t or tvec) were given
    bool has_R;          // the rotation was given as a matrix R (or R_cam_enu)
    double R_cam_enu[9]; // as given, row-major (the camera's pose uses its nearest rotation)
    bool has_P;          // a projection matrix was given
    double P[12];        // (3,4) row-major, as given
} rs_camera_extra;

// The file names of a camera: "<id><ext>" in a folder. .cameramodel (mrcal) and .opencv.yaml
// (OpenCV's FileStorage layout) are this file's formats; other modules name their own per-camera
// files with the same function (calib/rs_calib_site.h: <id>.json, <id>.homography.json;
// geo/rs_site.h: observations/<id>.csv).
#define RS_CAMERA_EXT_CAMERAMODEL ".cameramodel"
#define RS_CAMERA_EXT_OPENCV_YAML ".opencv.yaml"

// The path "<dir>/<id><ext>" of camera `id`'s file into out (n bytes), joined as rs_io_join does
// (trailing '/' of dir dropped; dir NULL or "": "<id><ext>"). ext includes its dot
// (RS_CAMERA_EXT_CAMERAMODEL). Returns false, with out empty, when the path needs more than
// n - 1 bytes.
bool rs_camera_path(char *out, size_t n, const char *dir, const char *id, const char *ext);

// Frees the intrinsics and zeroes the camera. Accepts NULL.
void rs_camera_free(rs_camera *cam);

// Makes *cam a camera of the given lens, a copy of `intrinsics` ((Nintrinsics,) of lensmodel),
// the image size and a zero pose. *cam is zeroed first (its old contents are not freed).
// Returns RS_ERR_INVALID for a lens model mrcal does not know, RS_ERR_NOMEM.
rs_status rs_camera_init( // out
    rs_camera *cam,
    // in
    const mrcal_lensmodel_t *lensmodel, const double *intrinsics, int width, int height, rs_err *err);

// A deep copy of `in` into *out (zeroed first). RS_ERR_NOMEM.
rs_status rs_camera_copy(rs_camera *out, const rs_camera *in, rs_err *err);

// Reads a camera file: an mrcal .cameramodel (by mrcal; extrinsics = rt_cam_enu), or, for a
// .json holding "f" and no camera_matrix or K, the equidistant fisheye triple {"f", "x0", "y0"}
// (optionally image_width, image_height; rs_camera_init_equidistant), or, for a
// name ending in .yaml, .yml or .json, an OpenCV-style file read by cv::FileStorage:
// image_width, image_height; camera_matrix or K (3,3); distortion_coefficients, D or dist (0, 4,
// 5, 8, 12 or 14 values; absent or empty: none; with distortion_model "fisheye", "equidistant" or
// "kannala_brandt", 4 values: OpenCV's fisheye, rs_camera_init_kannala_brandt); optionally the pose as R or R_cam_enu (3,3; its
// nearest rotation is used) or rvec or r (3), with tvec or t (3); optionally P (3,4). Matrices
// may be OpenCV matrices ({rows, cols, dt, data} / !!opencv-matrix) or nested number lists.
// out:  *cam (zeroed on failure); *extra (may be NULL): what else an OpenCV file said (all false
//       for a .cameramodel)
// Every value is checked: finite intrinsics, fx, fy > 0, an image size of 1..10^6 pixels when
// given (a .cameramodel always gives one), no skew, no tilted sensor.
// Errors, as "PATH: FIELD: what": RS_ERR_IO (cannot open), RS_ERR_PARSE (malformed, a field of
// the wrong type), RS_ERR_INVALID (a wrong count, non-finite or out-of-range value, R with
// det <= 0, only one of rotation and translation), RS_ERR_UNSUPPORTED (skew, tilted sensor: no
// mrcal equivalent), RS_ERR_NOMEM.
rs_status rs_camera_read( // out
    rs_camera *cam, rs_camera_extra *extra,
    // in
    const char *path, rs_err *err);

// What makes `text` (len bytes) unfit for mrcal's .cameramodel reader, with *line where; NULL
// when it has the shape of one: a Python-literal dict of quoted keys and values that are quoted
// one-line strings, numbers, lists and dicts (8 deep at most), comments, nothing after the '}'.
// mrcal 2.2 reads past its buffer on malformed text; rs_camera_read_cameramodel_text checks this
// first. Exported for the site reader's messages (file and line).
const char *rs_camera_cameramodel_problem(const char *text, size_t len, int *line);

// An mrcal .cameramodel held in memory (text, len bytes; it need not be NUL-terminated), checked
// as rs_camera_read does. `path` names it in messages.
rs_status rs_camera_read_cameramodel_text( // out
    rs_camera *cam,
    // in
    const char *text, size_t len, const char *path, rs_err *err);

// Checks a camera's values (the checks of rs_camera_read). Errors as "PATH: FIELD: what".
rs_status rs_camera_check(const rs_camera *cam, const char *path, rs_err *err);

// Writes an mrcal .cameramodel atomically (temporary name, then rename). Needs width, height > 0.
// Returns RS_ERR_IO, RS_ERR_EXTERNAL (mrcal could not write it), RS_ERR_NOMEM.
rs_status rs_camera_write_cameramodel(const rs_camera *cam, const char *path, rs_err *err);

// True when the lens model has an OpenCV equivalent (PINHOLE, OPENCV4/5/8/12).
bool rs_camera_has_opencv_equivalent(const rs_camera *cam);

// Writes the camera in OpenCV's own YAML layout (cv::FileStorage), atomically, for users of
// cv::projectPoints: image_width, image_height, camera_matrix (3x3), distortion_coefficients
// (1xN, OpenCV's order; a pinhole gets 5 zeros), rvec, tvec (3x1: rt_cam_enu, mapping site ENU
// into the camera) and R_cam_enu (3x3). RS_ERR_UNSUPPORTED when the lens has no OpenCV
// equivalent; RS_ERR_IO, RS_ERR_EXTERNAL (OpenCV threw).
rs_status rs_camera_write_opencv_yaml(const rs_camera *cam, const char *path, rs_err *err);

// ---- fisheye lenses (core/rs_camera_fisheye.c; docs/conventions.md, "Fisheye lenses") ----
//
// Both are mrcal's LENSMODEL_CAHVORE_linearity=0.00 with alpha = beta = 0 and e0 = e1 = e2 = 0,
// whose pixel is (fx, fy) * theta (1 + r0 + r1 theta^2 + r2 theta^4) * (x, y) / hypot(x, y) +
// (cx, cy) for a ray theta off the optical axis (projected and unprojected by core/rs_lens.h).

// The worst pixel error over the image's angles that a fitted OpenCV fisheye may keep.
#define RS_CAMERA_FISHEYE_FIT_MAX_PX 0.01

// The equidistant fisheye of the triple {f, x0, y0}: pixel radius r = f theta about (x0, y0),
// exactly (intrinsics f f x0 y0 0 0 0 0 0 0 0 0). *cam is zeroed first.
// Errors: RS_ERR_INVALID (f not > 0, non-finite), RS_ERR_NOMEM.
rs_status rs_camera_init_equidistant( // out
    rs_camera *cam,
    // in
    double f_px, double x0_px, double y0_px, int width, int height, rs_err *err);

// OpenCV's fisheye model (cv::fisheye, Kannala-Brandt: theta_d = theta (1 + k1 theta^2 + k2
// theta^4 + k3 theta^6 + k4 theta^8), pixel = (fx theta_d x / r + cx, fy theta_d y / r + cy)).
// k3 = k4 = 0: exactly CAHVORE with r0 = 0, r1 = k1, r2 = k2. Otherwise (r0, r1, r2) are fitted by
// least squares to the pixel radius over theta in [0, the widest angle the image's corners show]
// (90 degrees without an image size), and accepted only if the fit's worst pixel error there is
// at most RS_CAMERA_FISHEYE_FIT_MAX_PX.
// out: *cam (zeroed first); *fit_error_px (may be NULL): that worst error, 0 when exact
// in:  core (4,) fx fy cx cy; k (4,) k1..k4; path names the file in messages
// Errors: RS_ERR_UNSUPPORTED ("PATH: distortion_coefficients: k3 = ..., k4 = ...: ... off by up to
// E px ..."), RS_ERR_NOMEM.
rs_status rs_camera_init_kannala_brandt( // out
    rs_camera *cam, double *fit_error_px,
    // in
    const double core[4], const double k[4], int width, int height, const char *path, rs_err *err);

// ---- projection: the one "does this point project" rule ----
//
// A point p_cam = (x, y, z) of the camera frame projects (is visible) when
//   1. it is in front of the camera: z > 0, and
//   2. it is within the lens's valid field: its angle from the optical axis has
//      tan = hypot(x, y) / z <= max_tan, max_tan = rs_camera_max_tan(cam): the widest ray of the
//      image's four corners (mrcal_unproject of (-0.5, -0.5) ... (W-0.5, H-0.5)), times 1.15,
//      plus 0.02. A lens model is fitted to what the image shows; beyond its corners a distortion
//      polynomial can fold far off-axis points back into the image, at pixels that mean nothing.
//      The margin keeps lines that leave the image drawable up to its border.
//   3. mrcal projects it to finite pixel coordinates.
// The pixel may lie outside the image: "inside the image" (u in [-0.5, W-0.5], v in
// [-0.5, H-0.5], pixel (0,0) the centre of the top-left pixel) is the caller's further test
// where it needs one. docs/conventions.md, "Projection", says the same.

// The tangent of the lens's valid field (rule 2 above): 4 unprojections, so compute it once per
// camera for many points. A corner mrcal cannot unproject, or one at 90 degrees or more off
// axis (a fisheye), or one the distortion never reaches (mrcal returns NaN), counts as tan
// 1000 (no limit in practice); a camera without an image size
// (width or height 0: an OpenCV file that gives none) has no limit (INFINITY).
double rs_camera_max_tan(const rs_camera *cam);

// Rules 1 and 2 for a point of the camera frame.
bool rs_camera_in_field(const double p_cam[3], double max_tan);

// Projects one point of the site ENU frame (mrcal_transform_point_rt, mrcal_project) if it is
// visible by the rules above with the given max_tan (rs_camera_max_tan(cam)); false, and q_px
// NaN, if not.
bool rs_camera_project_visible(double q_px[2], const rs_camera *cam, double max_tan, const double p_enu_m[3]);

// Projects N points of the site ENU frame through the camera: rs_camera_project_visible with
// rs_camera_max_tan(cam) computed once. q_px (N,2); a point that does not project gets NaN.
// Returns the number of points projected.
int rs_camera_project( // out
    double *q_px,      // (N,2)
    // in
    const rs_camera *cam,
    const double *p_enu_m, // (N,3)
    int N);

// The point of a polyline (vertices_enu_m (Nvertices,3), Nvertices >= 2) whose projection through
// cam is nearest the pixel q_pick_px: p_enu_m (3,) and its projection q_px (2,). Each segment is
// sampled at 256 points, then a ternary search around the nearest sample narrows it to 1e-6 of
// the segment (the distance is unimodal there for any segment shorter than the view). False
// when no part of it projects (both outputs NaN). Used for picks anywhere along a pole or a line.
bool rs_camera_nearest_on_polyline(double p_enu_m[3], double q_px[2], const rs_camera *cam,
                                   const double *vertices_enu_m, int Nvertices, const double q_pick_px[2]);

// Intersects the ray of pixel q_px (through the full lens model: mrcal_unproject, then
// Gauss-Newton steps on mrcal_project to polish) with the plane n . p = plane_offset_m.
// plane_normal_enu need not be unit length; (0,0,1) with offset h is the level plane U = h.
// Accuracy: the returned point projects back to q_px within 1e-9 px.
// Errors: RS_ERR_INVALID (non-finite input, zero normal), RS_ERR_UNSUPPORTED (lens model
// without unprojection), RS_ERR_DEGENERATE (ray parallel to the plane or the plane behind
// the camera).
rs_status rs_camera_locate_ground( // out
    double p_enu_m[3],
    // in
    const rs_camera *cam, const double q_px[2], const double plane_normal_enu[3], double plane_offset_m,
    rs_err *err); // may be NULL

#ifdef __cplusplus
}
#endif

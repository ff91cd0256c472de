// rs_localise.h -- `roadside localise`: every detection to the road, with its covariance.
//
// Purpose: a detection box [x, y, w, h] (COCO's bbox in roadside's pixel convention: (x, y) the
// top-left corner, pixel (0,0) the centre of the top-left pixel) becomes the ground point its
// camera sees at the box's ground-contact pixel, in site ENU and WGS84, with the 2x2 covariance
// of its (E, N) (docs/localise.md).
//
// Method:
//   - the ground-contact pixel q (rs_localise_point): CENTER (x + w/2, y + h/2), the centre of a
//     footprint box (what roadside's detector learns, the paper's convention); BOTTOM
//     (x + w/2, y + h), the bottom middle of an ordinary detector's box; SHIFT
//     (x + w/2, y + h/2 + K h), the paper's centre shift (K = 0.35 by default). A detection that
//     gives its ground pixel itself (COCO's optional "bottom_center": [u, v], as roadside's
//     labels do) uses it whatever the choice.
//   - the point: the ray of q through the full lens model met with the ground plane
//     n . p = offset (core/rs_camera_ground.h, rs_camera_locate_ground: 1e-9 px); a ray that
//     misses the plane in front of the camera, or whose point lies outside the lens's valid
//     field (core/rs_camera.h, rule 2), gives no point (RS_ERR_DEGENERATE).
//   - the covariance: Cov(E, N) = J_pose C_pose J_pose^T + J_px (sigma_px^2 I) J_px^T, the
//     first-order propagation of core/rs_camera_ground.h with C_pose the 6x6 covariance of
//     rt_cam_enu from `roadside calib` (NULL: pixel noise only) and sigma_px the detector's
//     pixel noise per axis (default RS_LOCALISE_PIXEL_SIGMA_PX).
//   - lat/lon/height: rs_geo_enu_to_llh at the site's origin (GeographicLib, nm-accurate).
// Accuracy: the point is exact to the lens model's unprojection (1e-9 px, well under 1e-6 m
// within 200 m); the covariance is first order (tests/eval/localise: NEES within [0.8, 1.25] x 2).
//
// Ownership: arrays returned through out pointers belong to the caller (free()).
#pragma once
#include <stdbool.h>
#include <stddef.h>

#include "core/rs_camera.h"
#include "core/rs_status.h"
#include "geo/rs_geo.h"

#ifdef __cplusplus
extern "C" {
#endif

// The default detection noise, pixels per axis (docs/localise.md, "Pixel noise": a good
// detector's box-centre error on vehicles at roadside resolutions).
#define RS_LOCALISE_PIXEL_SIGMA_PX 2.0
// The paper's centre shift K of RS_LOCALISE_POINT_SHIFT, fraction of the box height.
#define RS_LOCALISE_SHIFT_DEFAULT  0.35
// Camera ids are at most this many bytes (the NUL included).
#define RS_LOCALISE_ID_MAX         64

typedef enum {
    RS_LOCALISE_POINT_CENTER, // (x + w/2, y + h/2): footprint boxes
    RS_LOCALISE_POINT_BOTTOM, // (x + w/2, y + h): ordinary detectors' boxes
    RS_LOCALISE_POINT_SHIFT,  // (x + w/2, y + h/2 + K h)
} rs_localise_point;

// Parses "center", "bottom" or "shift"; false for anything else.
bool rs_localise_point_parse(rs_localise_point *point, const char *s);

// One detection read from a file (any of the three formats).
typedef struct {
    long long image_id;              // COCO image_id; MOT's frame number (1-based); Ultralytics:
                                     //   the file's stem if an integer, else its 1-based rank
    long long category_id;           // 1-based (COCO, Ultralytics class + 1; MOT: its class
                                     //   column if present and > 0, else 1)
    double bbox_px[4];               // x, y, w, h in roadside's convention
    double score;                    // 0..1 (1 when the format gives none)
    char camera[RS_LOCALISE_ID_MAX]; // "" when unknown
    long long frame;                 // 0-based frame of the input, -1 when unknown
    double time_s;                   // seconds from the input's start, NaN when unknown
    bool has_bottom_center;          // the detection gives its ground pixel itself
    double bottom_center_px[2];      // (u, v) when has_bottom_center
    int line;                        // 1-based line of the file it came from (messages)
} rs_localise_detection;

// Reads detections, the format by the path: a folder (Ultralytics txt: one <image>.txt per
// image, `class cx cy w h [conf]` normalised by the image size, corner origin as YOLO's:
// x_roadside = cx W - 0.5), a name ending in .json (COCO results: a list of {image_id,
// category_id, bbox, score} with the optional camera, frame, time_s, file_name and
// bottom_center), else MOT Challenge CSV (`frame,id,bb_left,bb_top,bb_width,bb_height,conf,...`,
// 1-based frames and MOT's 1-based pixel corner: x_roadside = bb_left - 1).
// out:  *dets (N,) owned by the caller (free()), *N
// in:   width, height: the image size in pixels, for Ultralytics' normalised boxes (ignored
//         otherwise; must be > 0 for a folder)
//       fps: frames per second for MOT and Ultralytics (time_s = frame / fps); <= 0: unknown
// Errors: RS_ERR_IO, RS_ERR_PARSE (a missing field, a wrong type, a number that is not finite),
// RS_ERR_INVALID (a negative box size, an id too long), each message "FILE:LINE: FIELD:
// what" (COCO: "FILE:LINE: entry N: FIELD: what"), RS_ERR_NOMEM.
rs_status rs_localise_read_detections( // out
    rs_localise_detection **dets, size_t *N,
    // in
    const char *path, int width, int height, double fps, rs_err *err);

// The ground-contact pixel of a box for a point choice (Method above); K the shift for SHIFT.
void rs_localise_box_point(double q_px[2], const double bbox_px[4], rs_localise_point point, double K);

// One located detection: the fields of the located-detections file (docs/localise.md), in its
// column order.
typedef struct {
    long long image_id;
    char camera[RS_LOCALISE_ID_MAX]; // "" when unknown
    long long frame;                 // -1 when unknown
    double time_s;                   // NaN when unknown (written empty / null)
    long long category_id;
    double score;
    double u_px, v_px;                      // the ground-contact pixel used
    double e_m, n_m, u_m;                   // site ENU of the ground point
    double lat_deg, lon_deg;                // NaN when the site's origin is unknown
    double sigma_e_m, sigma_n_m, cov_en_m2; // the horizontal covariance [[s_e^2, c], [c, s_n^2]]
    int line; // 1-based line of the file it was read from (messages; not written), 0 otherwise
} rs_localise_row;

// What a camera needs to place its detections.
typedef struct {
    const rs_camera *camera;     // calibrated: intrinsics, size, pose
    const double *covariance_rt; // (6,6) row-major of rt_cam_enu; may be NULL: pixel noise only
    double ground_normal_enu[3]; // the ground plane n . p = offset
    double ground_offset_m;
    const rs_llh *origin; // the site's origin; may be NULL: lat, lon NaN
    double max_tan;       // rs_camera_max_tan(camera), computed once
} rs_localise_view;

// The view of a camera (max_tan computed here); the pointers are kept, not copied.
rs_localise_view rs_localise_view_make(const rs_camera *camera,
                                       const double *covariance_rt, // (6,6), may be NULL
                                       const double ground_normal_enu[3], double ground_offset_m,
                                       const rs_llh *origin); // may be NULL

typedef struct {
    rs_localise_point point; // which pixel of the box
    double shift;            // K for RS_LOCALISE_POINT_SHIFT
    double pixel_sigma_px;   // the detection noise per axis, px, >= 0
} rs_localise_options;

// Places one detection (Method above) into *row (camera, frame, time_s copied from the
// detection). Errors: RS_ERR_DEGENERATE (the ray misses the ground: above the horizon, behind
// the camera, outside the lens's valid field; *row is then not to be written), RS_ERR_INVALID
// (bad options or plane), RS_ERR_UNSUPPORTED (a lens model without unprojection).
rs_status rs_localise_detection_locate( // out
    rs_localise_row *row,
    // in
    const rs_localise_detection *det, const rs_localise_view *view, const rs_localise_options *opt, rs_err *err);

// The header of the located-detections CSV (docs/localise.md; issue 39's interface 2).
#define RS_LOCALISE_CSV_HEADER                                                                                  \
    "image_id,camera,frame,time_s,category_id,score,u_px,v_px,e_m,n_m,u_m,lat_deg,lon_deg,sigma_e_m,sigma_n_m," \
    "cov_en_m2"

// Writes rows atomically (core/rs_io.h), the format by the extension: .csv (the header above),
// .jsonl (one object per line, the same keys; unknown time_s, lat_deg, lon_deg null) or .geojson
// (a FeatureCollection of Points [lon, lat]: properties the same keys; geometry null when the
// origin is unknown). CSV numbers with 15 significant digits (1e-12 m within 1 km).
// Errors: RS_ERR_USAGE (another extension), RS_ERR_IO, RS_ERR_NOMEM.
rs_status rs_localise_write(const char *path, const rs_localise_row *rows, size_t N, rs_err *err);

// Reads a located-detections CSV back (as rs_localise_write writes it): the one reader of the
// file (`roadside track` reads its input through it). Each row's `line` is its 1-based line;
// blank lines are skipped; a UTF-8 byte-order mark and CRLF line ends are accepted.
// out: *rows (N,) owned by the caller (free()); NULL with N = 0 for a file without rows.
// Errors: RS_ERR_IO, RS_ERR_PARSE ("FILE:LINE: FIELD: what": another header or an empty file, a
// missing field (with the row's number of fields) or one too many, a field that is not a
// (whole) number, a camera id of RS_LOCALISE_ID_MAX bytes or more; empty time_s, u_px, v_px,
// u_m, lat_deg, lon_deg read as NaN, the rest required), RS_ERR_NOMEM.
rs_status rs_localise_read( // out
    rs_localise_row **rows, size_t *N,
    // in
    const char *path, rs_err *err);

// Every pixel's ground point (`roadside export --pixel-map`; docs/localise.md, "Pixel map"): for
// pixel (u, v) of the camera's image, the point and the radial 1-sigma sqrt(sigma_e^2 +
// sigma_n^2) that rs_localise_detection_locate gives a detection there. Arrays (height, width)
// row-major, NaN where the pixel sees no ground (the same rule as for detections).
typedef struct {
    int width, height;
    double *e_m, *n_m;         // site ENU, metres
    double *lat_deg, *lon_deg; // WGS84; NaN everywhere without the view's origin
    double *sigma_m;           // radial 1-sigma, metres
} rs_localise_pixel_map;

// Computes the map of view->camera (its width x height, both > 0) with the detection noise
// pixel_sigma_px. *map is zeroed first; free it with rs_localise_pixel_map_free whatever the
// outcome. Cost: one ray-plane intersection and one 2x2 propagation per pixel: 12 s of CPU for
// 1920 x 1080 (the simulator's OPENCV8 lens, measured on the 2-core CI machine under load).
// Pixels near the horizon see ground kilometres away, with sigmas to match. Errors: RS_ERR_INVALID (no image size, bad sigma), those of
// rs_geo_enu_to_llh, RS_ERR_NOMEM.
rs_status rs_localise_pixel_map_compute( // out
    rs_localise_pixel_map *map,
    // in
    const rs_localise_view *view, double pixel_sigma_px, rs_err *err);

void rs_localise_pixel_map_free(rs_localise_pixel_map *map); // NULL-safe; zeroes *map

#ifdef __cplusplus
}
#endif

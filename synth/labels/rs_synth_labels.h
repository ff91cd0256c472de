// rs_synth_labels.h -- labels of synthetic images from the same camera model that rendered them
// (mrcal projection), and the COCO (YOLOX layout), YOLO and KITTI writers. docs/labels.md
// defines every field.
//
// Pixels: (0,0) is the centre of the top-left pixel (docs/conventions.md); an image W x H spans
// [-0.5, W-0.5] x [-0.5, H-0.5]. A box is (x0, y0, x1, y1) in those continuous coordinates; a
// pixel-set box (the visible box) spans its pixels' squares: (imin-0.5, jmin-0.5, imax+0.5,
// jmax+0.5). COCO's bbox and segmentation are in COCO's corner convention (those + 0.5: the
// top-left pixel's top-left corner is (0, 0)); the other COCO fields keep the pixel-centre origin.
//
// Method. Points go into the camera frame with mrcal_transform_point_rt and into pixels with
// mrcal_project. Every polygon (a face of the 3D box, the footprint) is first clipped in 3D to
// the half-space z_cam >= RS_SYNTH_LABEL_ZMIN_M (and, for a lens with distortion, to the frustum
// through the image border widened by 25 % in normalised coordinates, where the distortion
// polynomial is meaningful), then its edges are projected at dense samples (every 1/64 of an
// edge, plus the corners), so that a lens that bends straight edges is handled: the extreme of
// a projected convex solid lies on the image of its silhouette edges. Accuracy: exact for a
// pinhole (corners are extreme); with distortion the box is too small by at most the sagitta of
// an edge's image over 1/64 of its length (< 0.01 px for the lenses of tests/synth).
#pragma once
#include <stdbool.h>
#include <stdint.h>

#include "core/rs_camera.h"
#include "core/rs_status.h"
#include "geo/rs_geo.h"
#include "synth/fleet/rs_synth_fleet.h"
#include "synth/fleet/rs_synth_vehicle.h"

#ifdef __cplusplus
extern "C" {
#endif

// The version of the dataset contract (docs/labels.md) written in COCO's info.version.
#define RS_SYNTH_DATASET_CONTRACT_VERSION "2"

#define RS_SYNTH_LABEL_ZMIN_M 0.01 // points nearer than this along the optical axis are clipped

// The labels of one vehicle in one image. NaN marks a value that does not exist.
typedef struct {
    int index; // the vehicle's index k in the input (ID image value k + 1)
    rs_synth_class cls;
    double center_enu_m[3];          // centre of the 3D box, site ENU
    double dims_m[3];                // length, width, height
    double yaw_deg;                  // compass heading of the forward axis
    double corners_px[8][2];         // projected box corners, NaN if behind z_cam < ZMIN. Corner c:
                                     // x_v = +L/2 if c&1 else -L/2, y_v = +W/2 if c&2, z_v = H if c&4
    int in_image;                    // 1 when the projected box overlaps the image
    double body_box_full_px[4];      // tight box of the projected 3D box (clipped in 3D), unclipped
    double body_box_px[4];           // the same clipped to the image
    double truncation;               // 1 - area(body_box_px) / area(body_box_full_px), in [0, 1]
    double footprint_box_full_px[4]; // tight box of the projected footprint rectangle
    double footprint_box_px[4];      // the same clipped to the image (NaN if outside)
    double footprint_center_px[2];   // centre of footprint_box_full_px
    double bottom_center_px[2];      // projection of the footprint's centre (NaN if behind)
    double bottom_center_cam_m[3];   // the footprint's centre in the camera frame
    double bottom_center_enu_m[3];   // the footprint's centre on the ground, site ENU
    double bottom_center_llh[3];     // the same as latitude, longitude (degrees) and height (m,
                                     // ellipsoidal); NaN unless the caller fills it (it needs
                                     // the site's origin: rs_synth_labels_compute leaves NaN)
    double rotation_y_rad;           // KITTI heading: forward_cam = (cos r, ., -sin r) in x-z
    double forward_cam[3];           // the vehicle's forward axis (unit) in the camera frame
    // From the object-ID pass (all -1 / NaN when no ID image was given):
    long visible_px;          // pixels of the ID image holding k + 1
    long full_px;             // pixels the vehicle would cover in the image, unoccluded
                              // (its mesh, or its 3D box if none, rasterised at pixel centres)
    double visibility;        // visible_px / full_px, clamped to [0, 1]; 0 if full_px == 0
    double visible_box_px[4]; // box of the visible pixels (pixel squares), NaN if none
} rs_synth_label;

// What the labels of one image are computed from.
typedef struct {
    const rs_camera *cam;             // the camera (lens, intrinsics, image size, rt_cam_enu)
    const rs_synth_vehicle *vehicles; // (Nvehicles,) RESOLVED (rs_synth_fleet_resolve; user
    int Nvehicles;                    //   models with their box)
    const double *up_m;               // (Nvehicles,) ground height under each footprint centre, ENU m
    const rs_synth_mesh *meshes;      // (Nvehicles,) the meshes rendered, vehicle frame; may be NULL
                                      //   (full_px then counts the 3D box's pixels); a mesh with
                                      //   Ntri == 0 also means "use the box"
    const uint16_t *id_image;         // (height, width) row-major object-ID pass: 0 = no vehicle,
                                      //   k + 1 = vehicle k; may be NULL (no visibility)
    const rs_llh *origin;             // the site's origin: bottom_center_llh through GeographicLib
                                      //   (geo/rs_geo.h); may be NULL (bottom_center_llh NaN)
} rs_synth_label_input;

// Computes the labels of every vehicle (out[k] for vehicle k, in_image or not).
// out:  labels: (Nvehicles,) owned by the caller (free())
// Errors: RS_ERR_INVALID (unresolved dimensions, non-finite input, an ID value > Nvehicles),
// RS_ERR_EXTERNAL (mrcal could not project), RS_ERR_NOMEM; geo's errors for the origin.
rs_status rs_synth_labels_compute( // out
    rs_synth_label **labels,
    // in
    const rs_synth_label_input *in, rs_err *err);

// Which box a writer puts in `bbox` (COCO), the YOLO line and KITTI's 2D box.
typedef enum {
    RS_SYNTH_BBOX_FOOTPRINT = 0, // footprint_box_px (default: what the roadside detector learns)
    RS_SYNTH_BBOX_BODY,          // body_box_px (amodal, clipped to the image)
    RS_SYNTH_BBOX_VISIBLE        // visible_box_px (labels without visible pixels are dropped)
} rs_synth_bbox_kind;

// "footprint", "body", "visible" -> kind; RS_ERR_USAGE otherwise.
rs_status rs_synth_bbox_kind_parse(rs_synth_bbox_kind *kind, const char *name, rs_err *err);

// The kind's name ("footprint", "body", "visible"; "unknown" out of range).
const char *rs_synth_bbox_kind_name(rs_synth_bbox_kind kind);

// One sentence saying what the kind's box is (for the datasets' metadata: COCO's info, data.yaml,
// README.md): the footprint box is the vehicle's rectangle on the ground, not the vehicle.
const char *rs_synth_bbox_kind_meaning(rs_synth_bbox_kind kind);

typedef struct {
    rs_synth_bbox_kind bbox;
    double min_visibility; // drop labels whose visibility is below (only with an ID pass); 0 keeps all
    bool drop_invisible;   // with an ID pass, drop a vehicle with no visible pixel (visible_px 0)
                           // even when min_visibility is 0 (roadside synth's default)
} rs_synth_label_options;

// What the COCO writer records of an image beyond its file and size (docs/labels.md, "The
// dataset contract"): where it was seen from, over what, under which sky, with which
// calibration. Strings may be NULL (written as null); numbers NaN (null).
typedef struct {
    int index;                       // the image's index k in the dataset (-1: not written)
    const char *camera;              // camera id (site.json)
    const char *background;          // the background's name (else its file); NULL: the grey ground
    const char *weather;             // the background's "conditions" tag (sunny, cloudy, rain, snow,
                                     // night, dusk), else the estimated surface (dry, snow)
    const char *time_of_day;         // the background's condition (synth/backdrop/rs_synth_condition.h):
                                     // "day", "dusk", "night", tagged or estimated
    const char *time_iso;            // the background's "time" tag (ISO 8601), may be NULL
    double sun_azimuth_deg;          // the sun the vehicles were lit by (clockwise from north)
    double sun_elevation_deg;        // degrees above the horizon
    const char *camera_model;        // the camera the labels were projected with, at the image's size,
                                     // copied into the dataset: a path relative to the COCO file's
                                     // folder ("../cameras/<id>.cameramodel")
    const char *camera_model_sha256; // SHA-256 of that file, 64 hex digits
    const char *calib_source;        // the calibration file it was made from (as given)
    const char *calib_source_sha256; // SHA-256 of the calibration file
    double ground_normal_enu[3];     // the site's ground plane n . p_enu = offset
    double ground_offset_m;
    // the SUMO frame the image's vehicles came from (roadside synth --traffic-frames): its file
    // in that folder, SUMO's time in seconds, its index in frames.json; NULL file: none
    const char *traffic_frame_file;
    double traffic_frame_time_s;
    int traffic_frame_index;
    // issue 40: the background's condition (docs/conditions.md); NULL: not written
    const char *surface;      // "dry", "wet", "snow"
    const char *condition;    // "<time_of_day>-<surface>", e.g. "night-wet"
    bool condition_estimated; // estimated from the image, not tagged
} rs_synth_image_info;

// One labelled image for the writers.
typedef struct {
    const char *file_name;        // image file name inside the split's image folder
    int width, height;            // pixels
    const rs_synth_label *labels; // (Nlabels,)
    int Nlabels;
    const char *const *vehicle_ids;  // (Nvehicles,) vehicle_ids[labels[i].index]; may be NULL
    const rs_synth_image_info *info; // may be NULL: COCO gets id, file_name, width, height only
    const double *R0_rect;           // (3,3) row-major, KITTI only: the rectified frame x_rect =
                                     // R0_rect x_cam of location and rotation_y; NULL: identity
} rs_synth_label_image;

// Which labels a writer keeps: in_image, the chosen box exists with a positive area, visibility
// >= min_visibility (when known), at least one visible pixel (when known and drop_invisible). out: box (4,) the chosen box.
int rs_synth_label_kept(double box[4], const rs_synth_label *label, const rs_synth_label_options *opt);

// COCO in YOLOX's layout: writes DIR/annotations/instances_<split>.json (atomically; folders
// created) with images {id (1..), file_name, width, height}, categories {id = class + 1, name}
// for the 10 classes, info {..., box: which box bbox is}, and annotations {id, image_id,
// category_id, bbox (corner convention), segmentation (bbox's polygon), area (of bbox), iscrowd 0,
// bottom_center, footprint_center, footprint_bbox, body_bbox, body_bbox_full, truncation,
// corners_px, box3d {center_enu_m, dimensions_m, yaw_deg}, vehicle_index, vehicle_id,
// visible_pixels, full_pixels, visibility, visible_bbox} (docs/labels.md). The image folder
// DIR/<split>/ is created; the caller puts the images there.
// in: split: [A-Za-z0-9_-]+ (e.g. "train2017"); opt may be NULL (defaults).
rs_status rs_synth_labels_write_coco(const char *dir, const char *split, const rs_synth_label_image *images,
                                     int Nimages, const rs_synth_label_options *opt, rs_err *err);

// YOLO txt: DIR/labels/<split>/<stem>.txt per image, lines "class cx cy w h" normalised by the
// image size (YOLO's origin is the image corner: cx = (x0 + x1)/2 + 0.5 over width).
rs_status rs_synth_labels_write_yolo(const char *dir, const char *split, const rs_synth_label_image *images,
                                     int Nimages, const rs_synth_label_options *opt, rs_err *err);

// KITTI object labels: DIR/label_2/<stem>.txt per image, lines "type truncated occluded alpha
// x1 y1 x2 y2 h w l x y z rotation_y" with the location the bottom centre in the rectified
// frame (images[i].R0_rect x_cam; NULL: the camera frame) and rotation_y the heading about its
// y axis (docs/labels.md); occluded from visibility (0: >= 0.8, 1: >= 0.4, 2: below, 3: unknown).
// The 2D box is the labels' own (pixel-centre convention): give labels computed for the image
// the KITTI file goes with (roadside synth: the undistorted image's pinhole core camera).
rs_status rs_synth_labels_write_kitti(const char *dir, const rs_synth_label_image *images, int Nimages,
                                      const rs_synth_label_options *opt, rs_err *err);

// KITTI's frames of a roadside camera (docs/labels.md, "KITTI"): the rectified frame is the
// camera frame levelled, so that KITTI's upright 3D boxes (rotation_y about the y axis) hold on
// a tilted camera: its y axis is ENU down, its z axis the camera's optical axis projected onto
// the horizontal (for a camera looking straight down: the camera's up, -y, projected), x = y x z.
//   x_rect = R0_rect x_cam,  R0_rect rows (x_r, y_r, z_r) in camera coordinates
//   P2 = [K R0_rect^T | 0]: a point of the rectified frame to a pixel of the UNDISTORTED image
//        (the pinhole core K = (fx, fy, cx, cy) of cam, pixel (0,0) the centre of the top-left
//        pixel), so P2 R0_rect Tr_velo_to_cam maps site ENU into that image (KITTI's chain).
// A level camera (y axis down) gets R0_rect = I and P2 = [K | 0] as before.
// out: R0_rect (9,) row-major; P2 (12,) row-major (may be NULL)
// Returns RS_ERR_UNSUPPORTED for a lens model without fx, fy, cx, cy.
rs_status rs_synth_labels_kitti_rect( // out
    double R0_rect[9], double P2[12],
    // in
    const rs_camera *cam, rs_err *err);

// KITTI's calib file of one image (DIR/calib/<stem>.txt): P0..P3 = P2 and R0_rect of
// rs_synth_labels_kitti_rect, Tr_velo_to_cam = [R t] of rt_cam_enu (KITTI's "velodyne" frame
// taken to be the site's ENU frame), Tr_imu_to_velo = [I 0]. P2 is for the undistorted image: a
// lens with distortion needs the KITTI image undistorted to the pinhole core (roadside synth
// writes it so, docs/labels.md). Atomic.
rs_status rs_synth_labels_write_kitti_calib(const char *path, const rs_camera *cam, rs_err *err);

#ifdef __cplusplus
}
#endif

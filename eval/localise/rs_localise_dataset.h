// rs_localise_dataset.h -- what a roadside dataset records about the camera of each image
// (docs/labels.md, "The dataset contract"): the camera model (its path and SHA-256), the ground
// plane, and the pose covariance the calibration carried. `roadside localise --dataset` and
// `roadside eval --metres` (eval/rs_eval_ground.c) read it through this one file.
//
// The pose covariance: `roadside synth` copies calib's <id>.json (calib/rs_calib_site.h) beside
// the camera model it copies into DATASET/cameras/; eval may not include calib (docs/
// architecture.md), so its one field `covariance_rt_cam_enu` (6 lists of 6 numbers) is read here
// with cJSON.
#pragma once
#include <stdbool.h>
#include <stddef.h>

#include "core/rs_camera.h"
#include "core/rs_status.h"
#include "eval/localise/rs_localise.h"

#ifdef __cplusplus
extern "C" {
#endif

struct cJSON;

// An image's "calibration" record.
typedef struct {
    char *camera_model;                           // owned: the model's path (relative ones resolved against the
                                                  //   ground truth's folder)
    char *camera_model_sha256;                    // owned: its recorded SHA-256 (hex), NULL if none recorded
    double ground_normal_enu[3], ground_offset_m; // the plane n . p_enu = offset
} rs_localise_calibration;

// Frees the strings and zeroes *c. Accepts NULL.
void rs_localise_calibration_free(rs_localise_calibration *c);

// Reads an image's "calibration" object (the image object `image`'s member; gt_dir the ground
// truth's folder). *out is zeroed first (free it with rs_localise_calibration_free whatever the
// outcome). Errors (the message names the field, "calibration.camera_model: ...", the caller
// prefixes file and entry): RS_ERR_INVALID (missing, not a string / number, non-finite),
// RS_ERR_NOMEM.
rs_status rs_localise_calibration_parse( // out
    rs_localise_calibration *out,
    // in
    const struct cJSON *image, const char *gt_dir, rs_err *err);

// Reads the camera model `path` (rs_camera_read) and checks its SHA-256 against sha256 (may be
// NULL: not checked). Errors: those of rs_camera_read, RS_ERR_INVALID ("image ID: PATH: SHA-256
// X, the ground truth records Y (the file changed since the dataset was made)").
rs_status rs_localise_camera_read_checked( // out
    rs_camera *cam,
    // in
    const char *path, const char *sha256, long long image_id, rs_err *err);

// The pose covariance a calibration carried: covariance_rt_cam_enu of calib's <id>.json at the
// path of the camera model with ".cameramodel" replaced by ".json". *found false (and RS_OK) when
// there is no such file. Errors: RS_ERR_PARSE ("PATH: covariance_rt_cam_enu: ..."), RS_ERR_IO.
rs_status rs_localise_covariance_read( // out
    double covariance_rt[36], bool *found,
    // in
    const char *camera_model_path, rs_err *err);

// One image of a dataset's COCO file, as localise needs it.
typedef struct {
    long long id;
    char camera[RS_LOCALISE_ID_MAX]; // "" when the image names none
    double time_s;                   // traffic_frame.time_s, NaN when absent
    long long frame;                 // traffic_frame.index, -1 when absent
    rs_localise_calibration calibration;
} rs_localise_image;

// Reads the "images" of a COCO ground truth (DATASET/annotations/instances_<split>.json).
// out: *images (N,) owned (rs_localise_images_free)
// Errors: RS_ERR_IO, RS_ERR_PARSE / RS_ERR_INVALID ("FILE:LINE: images[K]: FIELD: what"),
// RS_ERR_NOMEM.
rs_status rs_localise_images_read( // out
    rs_localise_image **images, size_t *N,
    // in
    const char *gt_path, rs_err *err);

void rs_localise_images_free(rs_localise_image *images, size_t N); // NULL-safe

#ifdef __cplusplus
}
#endif

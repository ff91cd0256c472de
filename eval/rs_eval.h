// rs_eval.h -- distance-threshold average precision of vehicle detections: a detection counts when
// its bottom-centre point lies within a pixel distance of a ground-truth bottom centre.
//
// Method (docs/evaluation.md states every rule; this is a summary):
//   - one point per object, in pixels (pixel (0,0) is the centre of the top-left pixel): the
//     object's `bottom_center` [u, v] if present, else the centre of its `bbox` [x, y, w, h];
//     for detections without `bottom_center`, (x + w/2, y + h/2 + K h) with K the centre shift.
//   - at most max_dets detections per image, the highest scores (ties: input order).
//   - for each threshold theta: all detections of the scope in descending score (ties: input
//     order); each takes the nearest (smallest du^2 + dv^2) candidate of its image among the
//     not-yet-matched ground truths and the ignore regions (`iscrowd` = 1, never used up); on a
//     tie of distance a ground truth wins over an ignore region, then the earlier annotation.
//     With d = sqrt(du^2 + dv^2) < theta the detection is a true positive (the ground truth is
//     now matched) or, if the candidate is an ignore region, dropped (no precision-recall
//     point); otherwise it is a false positive.
//   - AP: area under the precision-recall curve with precision made non-increasing from the
//     right (all-point interpolation, PASCAL VOC 2010 and later: M. Everingham et al., "The
//     PASCAL Visual Object Classes Challenge: A Retrospective", IJCV 111, 98-136 (2015)); recall
//     at theta is the final recall; mAP and AR are the means over the thresholds. The matching
//     follows nuScenes' centre-distance criterion (H. Caesar et al., CVPR 2020) in the image.
//   - a scope without ground truth has AP, recall, mAP and AR = NaN (printed "null").
// Accuracy: exact but for the rounding of the sums in double precision (relative error below
// D x 1.1e-16 for D detections, typically far less); agrees with an independent brute force to
// 1e-12 on hundreds of random datasets (tests/eval/test_eval_random.py).
// Cost: O(D) for ordering the scores (stable radix sort), O(sum over detections of the
// annotation count of the detection's image) for finding each detection's candidates (the
// annotations closer than the largest threshold), then O(D + G) per threshold and scope
// (D detections, G annotations); memory O(D + G) besides the input text, which is freed after
// parsing. 10^6 detections over 10^4 images: about 1.6 s of CPU, docs/benchmarks.md.
//
// Ownership: every object returned through an out pointer belongs to the caller, freed with the
// matching _free (which accepts NULL).
#pragma once
#include <stdbool.h>
#include <stddef.h>

#include "core/rs_status.h"
#include "geo/rs_site.h"

#ifdef __cplusplus
extern "C" {
#endif

// Ground truth and detections, parsed and checked. Opaque.
typedef struct rs_eval_data rs_eval_data;

typedef struct {
    double center_shift;       // K (unitless, fraction of the box height); 0 = the box centre
    const char *group_key;     // image-level field to group by (`--by`), may be NULL
    const char *camera_key;    // image-level field naming each image's camera (for
                               //   rs_eval_data_to_ground), may be NULL
    bool recorded_calibration; // read each image's "calibration" (the dataset contract,
                               //   docs/labels.md: camera model path relative to the ground
                               //   truth's folder, its SHA-256, the ground plane) for
                               //   rs_eval_data_to_ground_recorded
} rs_eval_load_options;

// Reads a COCO ground-truth file and a COCO results file (a JSON list of {image_id,
// category_id, bbox, score}, optionally bottom_center).
// Errors: RS_ERR_IO (cannot read), RS_ERR_PARSE (not JSON, wrong types, missing fields),
// RS_ERR_INVALID (negative box size, non-finite number, duplicate image id), RS_ERR_NOT_FOUND
// (a detection or annotation for an unknown image or category). The message names the file,
// its line and the entry (0-based index in its list, as jq's .[N]) and field.
rs_status rs_eval_load( // out
    rs_eval_data **data,
    // in
    const char *gt_path, const char *dets_path,
    const rs_eval_load_options *opt, // may be NULL: K = 0, no groups
    rs_err *err);

// The same from text in memory; the names are used in messages only.
rs_status rs_eval_parse( // out
    rs_eval_data **data,
    // in
    const char *gt_text, size_t gt_len, const char *gt_name, const char *dets_text, size_t dets_len,
    const char *dets_name,
    const rs_eval_load_options *opt, // may be NULL
    rs_err *err);

void rs_eval_data_free(rs_eval_data *data);

// Metric evaluation: replaces every point (ground truths and detections, after the centre
// shift) by its ground position (E, N) in metres, so that thresholds are then distances on the
// ground. Each image's camera is named by the image field given as camera_key at load time;
// calib_dir/<camera>.cameramodel (as written by `roadside calib`) gives the camera, the site
// its ground plane. Each pixel's ray goes through the full lens model (rs_camera_locate_ground).
// A point whose ray misses the ground (above the horizon, or a ray parallel to it) can match
// nothing: such a detection is a false positive and such a ground truth stays unmatched.
// Errors: RS_ERR_INVALID (data loaded without camera_key, an image without a camera),
// RS_ERR_NOT_FOUND (a camera the site or calib_dir lacks), RS_ERR_IO / RS_ERR_PARSE (model).
rs_status rs_eval_data_to_ground( // in,out
    rs_eval_data *data,
    // in
    const rs_site *site, const char *calib_dir,
    size_t *Nmissed, // may be NULL: points whose ray misses the ground
    rs_err *err);

// Metric evaluation from the dataset itself: as rs_eval_data_to_ground, with each image's
// camera model and ground plane from its recorded "calibration" (data loaded with
// recorded_calibration). Each model file's SHA-256 is checked against the recorded one.
// Errors: RS_ERR_INVALID (loaded without recorded_calibration, a checksum that differs),
// RS_ERR_IO / RS_ERR_PARSE (a model file).
rs_status rs_eval_data_to_ground_recorded( // in,out
    rs_eval_data *data,
    // in
    size_t *Nmissed, // may be NULL: points whose ray misses the ground
    rs_err *err);

// Counts: images, non-crowd ground truths, ignore regions, detections (before max-dets).
void rs_eval_data_counts(const rs_eval_data *data, size_t *Nimages, size_t *Ngt, size_t *Ncrowd, size_t *Ndets);
// Bytes held by data (its arrays, not the input text).
size_t rs_eval_data_bytes(const rs_eval_data *data);

#define RS_EVAL_MAX_THRESHOLDS 64

typedef struct {
    const double *thresholds; // (Nthresholds) > 0, finite, distinct: pixels, or metres for data
                              //   on the ground (rs_eval_data_to_ground); NULL: 2,5,10,15,20,50
    int Nthresholds;          // 1..RS_EVAL_MAX_THRESHOLDS (ignored when thresholds NULL)
    int max_dets;             // per image, >= 1 (0 selects the default, 100)
    bool per_class;           // also one row per category
    bool by_group;            // also one row per value of the load-time group_key
} rs_eval_options;

// The metrics of one scope: the whole dataset, one group of images or one category.
typedef struct {
    char *name;            // group value or category name; NULL for the whole dataset
    long long category_id; // for category rows; 0 otherwise
    size_t num_gt;         // non-crowd ground truths in the scope
    size_t num_det;        // detections in the scope kept by max-dets (dropped ones included)
    double *ap;            // (Nthresholds) NaN when num_gt == 0
    double *recall;        // (Nthresholds) NaN when num_gt == 0
    size_t *num_dropped;   // (Nthresholds) detections dropped by ignore regions
    double map, ar;        // means over the thresholds; NaN when num_gt == 0
} rs_eval_metrics;

typedef struct {
    int Nthresholds;
    double *thresholds; // (Nthresholds) in pixels, or metres (`metres`) after
                        //   rs_eval_data_to_ground
    bool metres;        // the thresholds are ground distances in metres
    int max_dets;
    rs_eval_metrics all; // class-agnostic, every image
    int Ngroups;
    rs_eval_metrics *groups; // (Ngroups) class-agnostic, first-appearance order; NULL if none
    int Nclasses;
    rs_eval_metrics *classes; // (Nclasses) in the ground truth's category order; NULL if none
} rs_eval_result;

// Evaluates. Errors: RS_ERR_USAGE for bad options (naming the option), RS_ERR_NOMEM.
rs_status rs_eval_run( // out
    rs_eval_result **result,
    // in
    const rs_eval_data *data,
    const rs_eval_options *opt, // may be NULL: the defaults
    rs_err *err);

void rs_eval_result_free(rs_eval_result *result);

// Writes the result as JSON (atomically): {"thresholds": [...] (or "thresholds_m"), "max_dets": N, "AP": {"2":
// ..., ...}, "mAP": ..., "AR": ..., "recall": {...}, "num_gt": ..., "num_det": ...,
// "num_dropped": {...}, "groups": {VALUE: {...}}, "classes": {ID: {"name": ..., ...}}}. Keys of
// the per-threshold objects are the thresholds printed with %.15g. NaN is written as null.
rs_status rs_eval_result_write_json(const rs_eval_result *result, const char *path, rs_err *err);

// The same JSON as a malloc'ed string (caller frees), or NULL when out of memory.
char *rs_eval_result_json(const rs_eval_result *result);

#ifdef __cplusplus
}
#endif

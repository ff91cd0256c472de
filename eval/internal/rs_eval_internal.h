// rs_eval_internal.h -- the parsed dataset shared by the eval module's files (not installed).
#pragma once
#include <stddef.h>

#include "eval/rs_eval.h"

// Ground truth grouped by image (images in ground-truth file order; annotations of one image in
// file order); detections in input order. Indices, not ids, everywhere.
struct rs_eval_data {
    int Nimages;
    long long *image_id; // (Nimages)
    int *image_group;    // (Nimages) index into group_names; NULL without a group key
    int Ngroups;
    char **group_names;  // (Ngroups) first-appearance order
    char **image_camera; // (Nimages) camera of each image (camera_key), NULL without the key
    bool metres;         // points were mapped to the ground (rs_eval_data_to_ground)
    // each image's recorded calibration (rs_eval_load_options.recorded_calibration), else NULL:
    int Nrecorded;             // entries filled (== Nimages after a successful load)
    char **image_model;        // (Nimages) the camera model's path (resolved)
    char **image_model_sha256; // (Nimages) its recorded SHA-256, NULL if none recorded
    double *image_ground;      // (Nimages,4) ground plane n . p_enu = offset: n (3), offset

    int Ncategories;
    long long *category_id; // (Ncategories)
    char **category_name;   // (Ncategories) never NULL (the id printed when the file has none)

    size_t Ngt;              // annotations, crowd included
    size_t *gt_begin;        // (Nimages+1) annotations of image m: gt_begin[m] .. gt_begin[m+1]-1
    double *gt_point;        // (Ngt,2) the point of each annotation: (u, v) pixels, or (E, N)
                             //   site ENU metres once `metres` (named for neither: it holds both)
    int *gt_category;        // (Ngt)
    unsigned char *gt_crowd; // (Ngt) 1 = ignore region

    size_t Ndets;
    double *det_point; // (Ndets,2) likewise, after the centre shift
    double *det_score; // (Ndets)
    int *det_image;    // (Ndets)
    int *det_category; // (Ndets)
};

// JSON lists and objects are read one member at a time: core/rs_json.h.

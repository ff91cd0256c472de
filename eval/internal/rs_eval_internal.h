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

// Streaming over one JSON container (eval/rs_eval_json.c). cJSON builds a tree of about 900
// bytes per detection and takes ~3 s for 10^6 of them; parsing a list one element at a time
// (cJSON stops where a value ends) keeps memory at the input size and is 3-4x faster. Objects
// are cut into members by a scanner that only finds where each value ends (strings, escapes,
// nesting), so that the ground truth's "annotations" list can be streamed in turn.

struct cJSON;

// Calls each(ctx, index, item, offset) for every element of the JSON list that text[begin,
// end) holds (surrounding white space allowed); item is the element parsed by cJSON (deleted
// after the call), offset the byte offset of its text. Stops at the first non-OK return and
// returns it. Syntax errors: RS_ERR_PARSE, "NAME:LINE: what".
typedef rs_status (*rs_eval_json_item_fn)(void *ctx, size_t index, const struct cJSON *item, size_t offset,
                                          rs_err *err);
rs_status rs_eval_json_array(const char *text, size_t begin, size_t end, const char *name, rs_eval_json_item_fn each,
                             void *ctx, rs_err *err);

// Calls each(ctx, key, begin, end) for every member of the JSON object that text[begin, end)
// holds, with its name (unescaped) and the span of its value's text, which is not parsed.
typedef rs_status (*rs_eval_json_span_fn)(void *ctx, const char *key, size_t begin, size_t end, rs_err *err);
rs_status rs_eval_json_object(const char *text, size_t begin, size_t end, const char *name, rs_eval_json_span_fn each,
                              void *ctx, rs_err *err);

// Parses text[begin, end) with cJSON. out: *item, owned by the caller (cJSON_Delete).
rs_status rs_eval_json_parse(struct cJSON **item, const char *text, size_t begin, size_t end, const char *name,
                             rs_err *err);

// 1-based line number of byte `offset` of text.
int rs_eval_json_line(const char *text, size_t offset);

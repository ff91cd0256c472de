// fuzz_eval_json.c -- libFuzzer harness of the eval loader (rs_eval_parse, eval/rs_eval.h): both
// sides of an evaluation from one input, split at its first NUL byte (which JSON text never
// holds): the COCO ground truth before it, the COCO results (detections) after it. An input
// without a NUL is all ground truth, with the detections "[]". Corpus: tests/fuzz/corpus/eval_json/.
//
// Each input is parsed twice: without options, and with a centre shift of 0.5 and the image field
// "camera" as both the group key and the camera key. Every dataset that parses is evaluated
// (rs_eval_run, per class and per group) and held to what eval/rs_eval.h promises, a breach
// aborting: the scope of everything counts every non-crowd ground truth and at most every
// detection; AP and recall lie in [0, 1] with AP <= recall (all-point interpolation: the area
// under a precision of at most 1 up to the final recall), both NaN exactly when the scope has no
// ground truth; mAP and AR are their means (to 1e-12); the result's JSON text parses (cJSON).
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "eval/rs_eval.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void breach(const char *what, const char *detail)
{
    fprintf(stderr, "fuzz_eval_json: contract broken: %s%s%s\n", what, detail ? ": " : "", detail ? detail : "");
    abort();
}

// A copy of text[0, len) in a buffer of exactly len bytes (no NUL after it): a read past the
// end is AddressSanitizer's to see. malloc(0) may return NULL: one byte is asked for then.
static char *exact_copy(const uint8_t *text, size_t len)
{
    char *p = malloc(len ? len : 1);
    if (!p) breach("out of memory", NULL);
    if (len) memcpy(p, text, len);
    return p;
}

static void check_metrics(const rs_eval_metrics *m, int Nthresholds, const char *scope)
{
    bool none = m->num_gt == 0;
    double sum_ap = 0, sum_recall = 0;
    for (int t = 0; t < Nthresholds; t++) {
        double ap = m->ap[t], r = m->recall[t];
        if (none) {
            if (!isnan(ap) || !isnan(r)) breach("AP or recall of a scope without ground truth is not NaN", scope);
            continue;
        }
        if (!(ap >= 0 && ap <= 1 && r >= 0 && r <= 1)) breach("AP or recall outside [0, 1]", scope);
        if (ap > r + 1e-12) breach("AP above the final recall", scope);
        sum_ap += ap;
        sum_recall += r;
    }
    if (none) {
        if (!isnan(m->map) || !isnan(m->ar)) breach("mAP or AR of a scope without ground truth is not NaN", scope);
    } else if (!(fabs(m->map - sum_ap / Nthresholds) <= 1e-12 && fabs(m->ar - sum_recall / Nthresholds) <= 1e-12)) {
        breach("mAP or AR is not the mean over the thresholds", scope);
    }
}

static void evaluate(const rs_eval_data *d, bool by_group)
{
    size_t Nimages = 0, Ngt = 0, Ncrowd = 0, Ndets = 0;
    rs_eval_data_counts(d, &Nimages, &Ngt, &Ncrowd, &Ndets);
    (void)rs_eval_data_bytes(d);
    const rs_eval_options opt = {.per_class = true, .by_group = by_group};
    rs_eval_result *res = NULL;
    rs_err err = {0};
    if (rs_eval_run(&res, d, &opt, &err) != RS_OK || !res)
        breach("rs_eval_run failed on a dataset that parsed", err.msg);
    if (res->all.num_gt != Ngt || res->all.num_det > Ndets) breach("the counts of the whole dataset disagree", NULL);
    check_metrics(&res->all, res->Nthresholds, "all");
    for (int g = 0; g < res->Ngroups; g++) check_metrics(&res->groups[g], res->Nthresholds, res->groups[g].name);
    for (int c = 0; c < res->Nclasses; c++) check_metrics(&res->classes[c], res->Nthresholds, res->classes[c].name);
    char *json = rs_eval_result_json(res);
    if (!json) breach("rs_eval_result_json returned NULL", NULL);
    cJSON *back = cJSON_Parse(json);
    if (!back) breach("rs_eval_result_json wrote text that is not JSON", json);
    cJSON_Delete(back);
    free(json);
    rs_eval_result_free(res);
}

static void parse(const char *gt, size_t gt_len, const char *dets, size_t dets_len, const rs_eval_load_options *opt)
{
    rs_eval_data *d = NULL;
    rs_err err = {0};
    rs_status st = rs_eval_parse(&d, gt, gt_len, "gt.json", dets, dets_len, "dets.json", opt, &err);
    if (st == RS_OK) {
        if (!d) breach("rs_eval_parse returned RS_OK and no data", NULL);
        evaluate(d, opt && opt->group_key);
    } else {
        if (d) breach("rs_eval_parse failed and returned data", NULL);
        if (!err.msg[0]) breach("rs_eval_parse failed without a message", NULL);
    }
    rs_eval_data_free(d);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const uint8_t *nul = size ? memchr(data, 0, size) : NULL;
    size_t gt_len = nul ? (size_t)(nul - data) : size;
    char *gt = exact_copy(data, gt_len);
    char *dets = nul ? exact_copy(nul + 1, size - gt_len - 1) : exact_copy((const uint8_t *)"[]", 2);
    size_t dets_len = nul ? size - gt_len - 1 : 2;

    parse(gt, gt_len, dets, dets_len, NULL);
    const rs_eval_load_options camera = {.center_shift = 0.5, .group_key = "camera", .camera_key = "camera"};
    parse(gt, gt_len, dets, dets_len, &camera);

    free(gt);
    free(dets);
    return 0;
}

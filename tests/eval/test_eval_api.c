// The eval library through its C API (eval/rs_eval.h): parsing from memory, default options,
// option errors, error statuses and messages, NULL-accepting frees. The expected metrics are
// worked out by hand in the comments (the rules: docs/evaluation.md). Exact comparisons, with
// tolerance 1e-15, and NaN checked explicitly.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "eval/rs_eval.h"

static int failures = 0;

static void check(int ok, const char *what)
{
    if (!ok) {
        failures++;
        printf("FAIL %s\n", what);
    }
}

static void check_near(double got, double want, const char *what)
{
    if (!(fabs(got - want) <= 1e-15)) { // false for NaN
        failures++;
        printf("FAIL %s: %.17g, expected %.17g\n", what, got, want);
    }
}

// One image, ground truths at (100,100) and (200,100), an ignore region at (400,100); detections
// .9 at d=1 from the first, .8 far from all, .7 at d=3 from the second, .6 on the ignore region.
static const char gt[] = "{\"images\": [{\"id\": 1, \"condition\": \"rain\"}],\n"
                         " \"categories\": [{\"id\": 1, \"name\": \"car\"}],\n"
                         " \"annotations\": [\n"
                         "  {\"image_id\": 1, \"category_id\": 1, \"bottom_center\": [100, 100]},\n"
                         "  {\"image_id\": 1, \"category_id\": 1, \"bbox\": [190, 90, 20, 20]},\n"
                         "  {\"image_id\": 1, \"category_id\": 1, \"bottom_center\": [400, 100], \"iscrowd\": 1}]}\n";
static const char dets[] = "[{\"image_id\": 1, \"category_id\": 1, \"bbox\": [100, 99, 2, 2], \"score\": 0.9},\n"
                           " {\"image_id\": 1, \"category_id\": 1, \"bbox\": [300, 300, 2, 2], \"score\": 0.8},\n"
                           " {\"image_id\": 1, \"category_id\": 1, \"bbox\": [199, 102, 2, 2], \"score\": 0.7},\n"
                           " {\"image_id\": 1, \"category_id\": 1, \"bbox\": [399, 99, 2, 2], \"score\": 0.6}]\n";

int main(void)
{
    rs_eval_data_free(NULL);
    rs_eval_result_free(NULL);

    rs_err err = {0};
    rs_eval_data *data = NULL;
    const rs_eval_load_options lo = {.center_shift = 0, .group_key = "condition"};
    rs_status st = rs_eval_parse(&data, gt, strlen(gt), "gt", dets, strlen(dets), "dets", &lo, &err);
    check(st == RS_OK, "parse");
    if (st != RS_OK) {
        printf("%s\n", err.msg);
        return 1;
    }
    size_t Nimages, Ngt, Ncrowd, Ndets;
    rs_eval_data_counts(data, &Nimages, &Ngt, &Ncrowd, &Ndets);
    check(Nimages == 1 && Ngt == 2 && Ncrowd == 1 && Ndets == 4, "counts");
    check(rs_eval_data_bytes(data) > 4 * 24, "bytes");

    // Defaults: thresholds 2,5,10,15,20,50, max-dets 100.
    // theta 2: .9 TP (P 1), .8 FP, .7 FP (3 >= 2), .6 dropped: AP 1/2, recall 1/2.
    // theta >= 5: .9 TP, .8 FP, .7 TP (P 2/3), .6 dropped: AP (1 + 2/3) / 2 = 5/6, recall 1.
    rs_eval_result *r = NULL;
    st = rs_eval_run(&r, data, NULL, &err);
    check(st == RS_OK && r && r->Nthresholds == 6 && r->max_dets == 100, "run with defaults");
    if (st == RS_OK) {
        check(r->thresholds[0] == 2 && r->thresholds[5] == 50, "default thresholds");
        check_near(r->all.ap[0], 0.5, "AP@2");
        check_near(r->all.recall[0], 0.5, "recall@2");
        for (int t = 1; t < 6; t++) check_near(r->all.ap[t], 5.0 / 6.0, "AP@5..50");
        check_near(r->all.map, (0.5 + 5 * 5.0 / 6.0) / 6, "mAP");
        check_near(r->all.ar, (0.5 + 5.0) / 6, "AR");
        check(r->all.num_gt == 2 && r->all.num_det == 4 && r->all.num_dropped[0] == 1, "num_gt, num_det, dropped");
        check(r->groups == NULL && r->classes == NULL, "no rows unless asked");
        char *json = rs_eval_result_json(r);
        check(json && strstr(json, "\"mAP\"") && strstr(json, "\"num_dropped\""), "JSON");
        free(json);
    }
    rs_eval_result_free(r);

    // Rows, one threshold, max-dets 2: kept .9 TP and .8 FP -> AP 1/2 at 5.
    const double theta[1] = {5};
    rs_eval_options opt = {.thresholds = theta, .Nthresholds = 1, .max_dets = 2, .per_class = true, .by_group = true};
    st = rs_eval_run(&r, data, &opt, &err);
    check(st == RS_OK && r->Ngroups == 1 && r->Nclasses == 1, "rows");
    if (st == RS_OK) {
        check_near(r->all.ap[0], 0.5, "max-dets 2: AP@5");
        check(r->all.num_det == 2, "max-dets 2: num_det");
        check(!strcmp(r->groups[0].name, "rain") && !strcmp(r->classes[0].name, "car") &&
                  r->classes[0].category_id == 1,
              "row names");
        check_near(r->groups[0].ap[0], 0.5, "group AP");
        check_near(r->classes[0].ap[0], 0.5, "class AP");
    }
    rs_eval_result_free(r);

    // Option errors.
    const double twice[2] = {5, 5}, negative[1] = {-1};
    opt = (rs_eval_options){.thresholds = twice, .Nthresholds = 2};
    check(rs_eval_run(&r, data, &opt, &err) == RS_ERR_USAGE && r == NULL && strstr(err.msg, "twice"),
          "repeated threshold");
    opt = (rs_eval_options){.thresholds = negative, .Nthresholds = 1};
    check(rs_eval_run(&r, data, &opt, &err) == RS_ERR_USAGE, "negative threshold");
    opt = (rs_eval_options){.max_dets = -1};
    check(rs_eval_run(&r, data, &opt, &err) == RS_ERR_USAGE, "negative max-dets");
    rs_eval_data_free(data);

    // Without the group key, by_group is a usage error.
    st = rs_eval_parse(&data, gt, strlen(gt), "gt", dets, strlen(dets), "dets", NULL, &err);
    opt = (rs_eval_options){.by_group = true};
    check(st == RS_OK && rs_eval_run(&r, data, &opt, &err) == RS_ERR_USAGE, "by_group without key");
    rs_eval_data_free(data);

    // Empty ground truth: NaN, not zero.
    const char empty_gt[] = "{\"images\": [{\"id\": 1}], \"annotations\": [], \"categories\": [{\"id\": 1}]}";
    st = rs_eval_parse(&data, empty_gt, strlen(empty_gt), "gt", dets, strlen(dets), "dets", NULL, &err);
    check(st == RS_OK, "parse empty ground truth");
    if (st == RS_OK && rs_eval_run(&r, data, NULL, &err) == RS_OK) {
        check(isnan(r->all.ap[0]) && isnan(r->all.recall[0]) && isnan(r->all.map) && isnan(r->all.ar) &&
                  r->all.num_gt == 0,
              "empty ground truth gives NaN");
        char *json = rs_eval_result_json(r);
        check(json && strstr(json, "\"mAP\":\tnull"), "NaN written as null");
        free(json);
        rs_eval_result_free(r);
    }
    rs_eval_data_free(data);

    // Error statuses and messages name the file, line and entry; *data stays NULL.
    const char bad_image[] = "[\n{\"image_id\": 1, \"category_id\": 1, \"bbox\": [0,0,1,1], \"score\": 1},\n"
                             "{\"image_id\": 9, \"category_id\": 1, \"bbox\": [0,0,1,1], \"score\": 1}]";
    st = rs_eval_parse(&data, gt, strlen(gt), "gt", bad_image, strlen(bad_image), "dets", NULL, &err);
    check(st == RS_ERR_NOT_FOUND && data == NULL &&
              !strcmp(err.msg, "dets:3: entry 1: image_id 9 not in the ground truth"),
          "unknown image");
    if (st != RS_ERR_NOT_FOUND) printf("   got %d: %s\n", st, err.msg);
    const char neg[] = "[{\"image_id\": 1, \"category_id\": 1, \"bbox\": [0,0,-1,1], \"score\": 1}]";
    st = rs_eval_parse(&data, gt, strlen(gt), "gt", neg, strlen(neg), "dets", NULL, NULL); // err may be NULL
    check(st == RS_ERR_INVALID && data == NULL, "negative width, err NULL");
    st = rs_eval_load(&data, "/nonexistent/gt.json", "/nonexistent/dets.json", NULL, &err);
    check(st == RS_ERR_IO && data == NULL && strstr(err.msg, "/nonexistent/gt.json"), "missing file");

    printf("%d failures\n", failures);
    return failures ? 1 : 0;
}

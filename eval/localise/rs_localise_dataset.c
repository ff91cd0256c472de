// rs_localise_dataset.c -- a dataset's record of each image's camera (rs_localise_dataset.h).
#define _POSIX_C_SOURCE 200809L // strdup, strndup
#include "eval/localise/rs_localise_dataset.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_hash.h"
#include "core/rs_io.h"
#include "core/rs_json.h"

void rs_localise_calibration_free(rs_localise_calibration *c)
{
    if (!c) return;
    free(c->camera_model);
    free(c->camera_model_sha256);
    *c = (rs_localise_calibration){0};
}

rs_status rs_localise_calibration_parse(rs_localise_calibration *out, const cJSON *image, const char *gt_dir,
                                        rs_err *err)
{
    *out = (rs_localise_calibration){0};
    const cJSON *cal = cJSON_GetObjectItemCaseSensitive(image, "calibration");
    if (!cJSON_IsObject(cal))
        return rs_err_set(err, RS_ERR_INVALID,
                          "calibration: missing (the dataset's own record of each image's camera: roadside synth "
                          "writes it; or give --site and --calib)");
    const cJSON *m = cJSON_GetObjectItemCaseSensitive(cal, "camera_model");
    const cJSON *h = cJSON_GetObjectItemCaseSensitive(cal, "camera_model_sha256");
    const cJSON *off = cJSON_GetObjectItemCaseSensitive(cal, "ground_offset_m");
    const cJSON *n = cJSON_GetObjectItemCaseSensitive(cal, "ground_normal_enu");
    if (!cJSON_IsString(m) || !*m->valuestring)
        return rs_err_set(err, RS_ERR_INVALID, "calibration.camera_model: missing or not a string");
    if (!cJSON_IsNumber(off) || !isfinite(off->valuedouble))
        return rs_err_set(err, RS_ERR_INVALID, "calibration.ground_offset_m: missing or not a number");
    if (!cJSON_IsArray(n) || cJSON_GetArraySize(n) != 3)
        return rs_err_set(err, RS_ERR_INVALID, "calibration.ground_normal_enu: not a list of 3 numbers");
    int i = 0;
    for (const cJSON *e = n->child; e; e = e->next, i++) {
        if (!cJSON_IsNumber(e) || !isfinite(e->valuedouble))
            return rs_err_set(err, RS_ERR_INVALID, "calibration.ground_normal_enu: element %d is not a finite number",
                              i);
        out->ground_normal_enu[i] = e->valuedouble;
    }
    out->ground_offset_m = off->valuedouble;
    out->camera_model = m->valuestring[0] == '/' ? strdup(m->valuestring) : rs_io_join(gt_dir, m->valuestring);
    if (!out->camera_model || (cJSON_IsString(h) && !(out->camera_model_sha256 = strdup(h->valuestring))))
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    return RS_OK;
}

rs_status rs_localise_camera_read_checked(rs_camera *cam, const char *path, const char *sha256, long long image_id,
                                          rs_err *err)
{
    rs_status st = rs_camera_read(cam, NULL, path, err);
    if (st || !sha256) return st;
    char hex[65];
    if ((st = rs_hash_sha256_file(hex, NULL, path, err))) {
        rs_camera_free(cam);
        return st;
    }
    if (strcmp(hex, sha256) != 0) {
        rs_camera_free(cam);
        return rs_err_set(err, RS_ERR_INVALID,
                          "image %lld: %s: SHA-256 %s, the ground truth records %s (the file changed since the "
                          "dataset was made)",
                          image_id, path, hex, sha256);
    }
    return RS_OK;
}

rs_status rs_localise_covariance_read(double C[36], bool *found, const char *model_path, rs_err *err)
{
    *found = false;
    for (int k = 0; k < 36; k++) C[k] = NAN;
    size_t len = strlen(model_path), ext = strlen(RS_CAMERA_EXT_CAMERAMODEL);
    if (len < ext || strcmp(model_path + len - ext, RS_CAMERA_EXT_CAMERAMODEL) != 0) return RS_OK;
    char *path = malloc(len - ext + 6);
    if (!path) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    memcpy(path, model_path, len - ext);
    strcpy(path + len - ext, ".json");
    rs_status st = rs_io_check_regular(path, SIZE_MAX, NULL);
    char *text = NULL;
    size_t n = 0;
    if (st) { // no calibration record beside the model: no covariance
        free(path);
        return RS_OK;
    }
    if ((st = rs_io_read_file(&text, &n, path, err))) {
        free(path);
        return st;
    }
    cJSON *doc = NULL;
    st = rs_json_parse(&doc, text, 0, n, path, err);
    const cJSON *m = st ? NULL : cJSON_GetObjectItemCaseSensitive(doc, "covariance_rt_cam_enu");
    if (!st && (!cJSON_IsArray(m) || cJSON_GetArraySize(m) != 6))
        st = rs_err_set(err, RS_ERR_PARSE, "%s: covariance_rt_cam_enu: missing or not 6 lists of 6 numbers", path);
    int i = 0;
    for (const cJSON *row = m ? m->child : NULL; row && !st; row = row->next, i++) {
        int j = 0;
        if (!cJSON_IsArray(row) || cJSON_GetArraySize(row) != 6)
            st = rs_err_set(err, RS_ERR_PARSE, "%s: covariance_rt_cam_enu: row %d is not a list of 6 numbers", path, i);
        for (const cJSON *e = row->child; e && !st; e = e->next, j++) {
            if (!cJSON_IsNumber(e) || !isfinite(e->valuedouble))
                st = rs_err_set(err, RS_ERR_PARSE, "%s: covariance_rt_cam_enu: [%d][%d] is not a finite number", path,
                                i, j);
            else
                C[6 * i + j] = e->valuedouble;
        }
    }
    cJSON_Delete(doc);
    free(text);
    free(path);
    if (!st) *found = true;
    return st;
}

// ---- a ground truth's images ----

typedef struct {
    const char *name, *text;
    char *gt_dir;
    size_t span[2];
    bool has_images;
    rs_localise_image *images;
    size_t N, cap;
} images_ctx;

static rs_status top(void *vctx, const char *key, size_t begin, size_t end, rs_err *err)
{
    (void)err;
    images_ctx *c = vctx;
    if (!strcmp(key, "images")) {
        c->span[0] = begin;
        c->span[1] = end;
        c->has_images = true;
    }
    return RS_OK;
}

static rs_status one_image(void *vctx, size_t index, const cJSON *o, size_t offset, rs_err *err)
{
    images_ctx *c = vctx;
    const int line = rs_json_line(c->text, offset);
    if (!cJSON_IsObject(o))
        return rs_err_set(err, RS_ERR_PARSE, "%s:%d: images[%zu]: not an object", c->name, line, index);
    if (c->N == c->cap) {
        size_t cap = c->cap ? 2 * c->cap : 256;
        rs_localise_image *p = realloc(c->images, cap * sizeof *p);
        if (!p) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", c->name);
        c->images = p;
        c->cap = cap;
    }
    rs_localise_image *im = &c->images[c->N++];
    *im = (rs_localise_image){.time_s = NAN, .frame = -1};
    const cJSON *id = cJSON_GetObjectItemCaseSensitive(o, "id");
    if (!cJSON_IsNumber(id) || id->valuedouble != floor(id->valuedouble) || fabs(id->valuedouble) > 9007199254740992.0)
        return rs_err_set(err, RS_ERR_PARSE, "%s:%d: images[%zu]: id: missing or not an integer", c->name, line, index);
    im->id = (long long)id->valuedouble;
    const cJSON *cam = cJSON_GetObjectItemCaseSensitive(o, "camera");
    if (cJSON_IsString(cam)) {
        if (strlen(cam->valuestring) >= sizeof im->camera)
            return rs_err_set(err, RS_ERR_INVALID, "%s:%d: images[%zu]: camera: longer than %d bytes", c->name, line,
                              index, RS_LOCALISE_ID_MAX - 1);
        strcpy(im->camera, cam->valuestring);
    }
    const cJSON *tf = cJSON_GetObjectItemCaseSensitive(o, "traffic_frame");
    if (cJSON_IsObject(tf)) {
        const cJSON *t = cJSON_GetObjectItemCaseSensitive(tf, "time_s");
        const cJSON *k = cJSON_GetObjectItemCaseSensitive(tf, "index");
        if (cJSON_IsNumber(t) && isfinite(t->valuedouble)) im->time_s = t->valuedouble;
        if (cJSON_IsNumber(k) && k->valuedouble >= 0 && k->valuedouble == floor(k->valuedouble))
            im->frame = (long long)k->valuedouble;
    }
    rs_status st = rs_localise_calibration_parse(&im->calibration, o, c->gt_dir, err);
    if (st) rs_err_prefix(err, "%s:%d: images[%zu]", c->name, line, index);
    return st;
}

rs_status rs_localise_images_read(rs_localise_image **images, size_t *N, const char *gt_path, rs_err *err)
{
    *images = NULL;
    *N = 0;
    char *text = NULL;
    size_t len = 0;
    rs_status st = rs_io_read_file(&text, &len, gt_path, err);
    if (st) return st;
    const char *slash = strrchr(gt_path, '/');
    images_ctx c = {.name = gt_path,
                    .text = text,
                    .gt_dir = slash ? strndup(gt_path, (size_t)(slash - gt_path + (slash == gt_path))) : strdup(".")};
    if (!c.gt_dir) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) st = rs_json_object(text, 0, len, gt_path, top, &c, err);
    if (!st && !c.has_images)
        st = rs_err_set(err, RS_ERR_PARSE, "%s:1: top level: no \"images\" list (a COCO ground-truth file has one)",
                        gt_path);
    if (!st) st = rs_json_array(text, c.span[0], c.span[1], gt_path, one_image, &c, err);
    free(text);
    free(c.gt_dir);
    if (st) {
        rs_localise_images_free(c.images, c.N);
        return st;
    }
    *images = c.images;
    *N = c.N;
    return RS_OK;
}

void rs_localise_images_free(rs_localise_image *images, size_t N)
{
    if (!images) return;
    for (size_t i = 0; i < N; i++) rs_localise_calibration_free(&images[i].calibration);
    free(images);
}

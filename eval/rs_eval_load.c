// rs_eval_load.c -- reading a COCO ground-truth file and a COCO results file into rs_eval_data.
#define _POSIX_C_SOURCE 200809L // strndup
#include <cjson/cJSON.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_io.h"
#include "core/rs_json.h"
#include "eval/internal/rs_eval_internal.h"
#include "eval/localise/rs_localise_dataset.h"

// ---- small helpers ----

// Ensures room for n + 1 elements of `size` bytes in *p (capacity *cap, doubling).
static bool grow(void *pp, size_t *cap, size_t n, size_t size)
{
    void **p = (void **)pp;
    if (n < *cap) return true;
    size_t c = *cap ? 2 * *cap : 64;
    void *q = realloc(*p, c * size);
    if (!q) return false;
    *p = q;
    *cap = c;
    return true;
}

// Where a message points: file, byte offset (for the line), entry: "LIST[INDEX]" ("images[3]"),
// or "entry INDEX" for a list at the top level (list NULL), or "top level" (index SIZE_MAX).
typedef struct {
    const char *text, *name;
    size_t at;
    const char *list;
    size_t index;
} where;

__attribute__((format(printf, 4, 5))) static rs_status bad(const where *w, rs_err *err, rs_status st, const char *fmt,
                                                           ...)
{
    char msg[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    char entry[64];
    if (w->index == SIZE_MAX)
        snprintf(entry, sizeof entry, "top level");
    else if (!w->list)
        snprintf(entry, sizeof entry, "entry %zu", w->index);
    else
        snprintf(entry, sizeof entry, "%s[%zu]", w->list, w->index);
    return rs_err_set(err, st, "%s:%d: %s: %s", w->name, rs_json_line(w->text, w->at), entry, msg);
}

static rs_status nomem(const where *w, rs_err *err)
{
    return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", w->name);
}

// An id -> index map: a sorted array searched by bisection.
typedef struct {
    long long id;
    int index;
} id_index;

static int cmp_id_index(const void *a, const void *b)
{
    const id_index *x = a, *y = b;
    if (x->id != y->id) return x->id < y->id ? -1 : 1;
    return x->index < y->index ? -1 : x->index > y->index;
}

static int find_id(const id_index *map, int N, long long id)
{
    int lo = 0, hi = N;
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (map[mid].id < id)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < N && map[lo].id == id ? map[lo].index : -1;
}

// ids are JSON numbers holding exact integers within +-2^53.
static rs_status get_id(const where *w, const cJSON *o, const char *field, long long *id, rs_err *err)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, field);
    if (!v) return bad(w, err, RS_ERR_PARSE, "%s: missing", field);
    double x = v->valuedouble;
    if (!cJSON_IsNumber(v) || !isfinite(x) || x != floor(x) || fabs(x) > 9007199254740992.0)
        return bad(w, err, RS_ERR_PARSE, "%s: not an integer", field);
    *id = (long long)x;
    return RS_OK;
}

// A list of N finite numbers.
static rs_status get_numbers(const where *w, const cJSON *v, const char *field, int N, double *x, rs_err *err)
{
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != N)
        return bad(w, err, RS_ERR_PARSE, "%s: not a list of %d numbers", field, N);
    int i = 0;
    for (const cJSON *e = v->child; e; e = e->next, i++) {
        if (!cJSON_IsNumber(e)) return bad(w, err, RS_ERR_PARSE, "%s: element %d is not a number", field, i);
        if (!isfinite(e->valuedouble)) return bad(w, err, RS_ERR_INVALID, "%s: element %d is not finite", field, i);
        x[i] = e->valuedouble;
    }
    return RS_OK;
}

// The point of an annotation or detection (docs/evaluation.md, rule 1), the same rule for both:
// the centre of `footprint_bbox` [x, y, w, h] if present (the dataset contract, docs/labels.md:
// the box the roadside detector is trained on), else `bottom_center` [u, v], else
// (x + w/2 - 0.5, y + h/2 - 0.5 + K h) from `bbox` (COCO's corner convention made pixel-centre;
// K: the centre shift, detections only). A present bbox is checked in every case.
static rs_status get_point(const where *w, const cJSON *o, double K, double q[2], rs_err *err)
{
    const cJSON *fp = cJSON_GetObjectItemCaseSensitive(o, "footprint_bbox");
    const cJSON *bc = cJSON_GetObjectItemCaseSensitive(o, "bottom_center");
    const cJSON *bb = cJSON_GetObjectItemCaseSensitive(o, "bbox");
    if (cJSON_IsNull(bc)) bc = NULL;
    if (cJSON_IsNull(fp)) fp = NULL;
    rs_status st;
    if (bb) {
        double b[4];
        if ((st = get_numbers(w, bb, "bbox", 4, b, err))) return st;
        if (b[2] < 0) return bad(w, err, RS_ERR_INVALID, "bbox: negative width %g", b[2]);
        if (b[3] < 0) return bad(w, err, RS_ERR_INVALID, "bbox: negative height %g", b[3]);
        // bbox is in COCO's corner convention ((0, 0) the top-left pixel's corner); points are
        // in roadside's pixel-centre one (docs/conventions.md): 0.5 px less
        q[0] = b[0] + 0.5 * b[2] - 0.5;
        q[1] = b[1] + 0.5 * b[3] + K * b[3] - 0.5;
    }
    if (fp) {
        double b[4];
        if ((st = get_numbers(w, fp, "footprint_bbox", 4, b, err))) return st;
        if (b[2] < 0 || b[3] < 0) return bad(w, err, RS_ERR_INVALID, "footprint_bbox: negative width or height");
        q[0] = b[0] + 0.5 * b[2];
        q[1] = b[1] + 0.5 * b[3];
        return RS_OK;
    }
    if (bc) return get_numbers(w, bc, "bottom_center", 2, q, err);
    if (!bb) return bad(w, err, RS_ERR_PARSE, "bbox: missing (and no footprint_bbox or bottom_center)");
    return RS_OK;
}

// Every entry of a list must be an object.
static rs_status check_entry(where *w, const cJSON *o, size_t offset, rs_err *err)
{
    w->at = offset;
    if (!cJSON_IsObject(o)) return bad(w, err, RS_ERR_PARSE, "not an object");
    const char *in = NULL, *twice = rs_json_repeated_key(o, &in);
    return twice ? bad(w, err, RS_ERR_PARSE, "\"%.100s\" appears twice in %s%.100s (which one is meant?)", twice,
                       *in ? "member " : "the entry", in)
                 : RS_OK;
}

// ---- ground truth ----

typedef struct {
    rs_eval_data *d;
    where w;
    const char *group_key;
    const char *camera_key;
    bool recorded;       // read each image's recorded calibration (rs_eval_load_options)
    char *gt_dir;        // owned: the ground truth's folder (recorded camera models are relative to it)
    size_t cap_recorded; // capacity of d's image_model, image_model_sha256, image_ground
    size_t span[3][2];   // images, annotations, categories: [begin, end)
    bool has[3];

    size_t cap_images;
    size_t *image_at;    // (Nimages) offset of each image entry
    char **image_value;  // (Nimages) the group value, owned
    id_index *image_map; // (Nimages) sorted
    size_t cap_categories;
    id_index *category_map; // (Ncategories) sorted
    bool categories_listed; // a "categories" list exists: annotations must use its ids

    size_t cap_ann;
    int *ann_image; // (Ngt) in file order
    double *ann_q;
    int *ann_category;
    unsigned char *ann_crowd;
} gt_ctx;

static const char *const gt_keys[3] = {"images", "annotations", "categories"};

static rs_status gt_top(void *vctx, const char *key, size_t begin, size_t end, rs_err *err)
{
    gt_ctx *c = vctx;
    for (int k = 0; k < 3; k++)
        if (!strcmp(key, gt_keys[k])) {
            if (c->has[k]) // cJSON would take the first, a reader of the text the last
                return rs_err_set(err, RS_ERR_PARSE, "%s: \"%s\" appears twice in the file (which one is meant?)",
                                  c->w.name, key);
            c->span[k][0] = begin;
            c->span[k][1] = end;
            c->has[k] = true;
        }
    return RS_OK;
}

// The group value of an image: a string as is, a number printed, a boolean as true/false,
// absent or null as "(missing)".
static rs_status group_value(const where *w, const cJSON *o, const char *key, char **out, rs_err *err)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    char buf[64];
    const char *s;
    if (!v || cJSON_IsNull(v))
        s = "(missing)";
    else if (cJSON_IsString(v))
        s = v->valuestring;
    else if (cJSON_IsBool(v))
        s = cJSON_IsTrue(v) ? "true" : "false";
    else if (cJSON_IsNumber(v)) {
        snprintf(buf, sizeof buf, "%.15g", v->valuedouble);
        s = buf;
    } else
        return bad(w, err, RS_ERR_PARSE, "%s: not a string, number or boolean", key);
    *out = strdup(s);
    return *out ? RS_OK : nomem(w, err);
}

// The calibration an image records (docs/labels.md, the dataset contract), read by
// eval/localise/rs_localise_dataset.h: its strings move into d's arrays.
static rs_status recorded_calibration(gt_ctx *c, const cJSON *o, size_t n, rs_err *err)
{
    rs_eval_data *d = c->d;
    size_t cap = c->cap_recorded;
    if (!grow(&d->image_model, &cap, n, sizeof *d->image_model) ||
        !grow(&d->image_model_sha256, &(size_t){c->cap_recorded}, n, sizeof *d->image_model_sha256) ||
        !grow(&d->image_ground, &(size_t){c->cap_recorded}, n, 4 * sizeof *d->image_ground))
        return nomem(&c->w, err);
    c->cap_recorded = cap;
    d->image_model[n] = d->image_model_sha256[n] = NULL;
    d->Nrecorded = (int)n + 1;
    rs_localise_calibration cal;
    rs_err e = {0};
    rs_status st = rs_localise_calibration_parse(&cal, o, c->gt_dir, &e);
    if (st) {
        rs_localise_calibration_free(&cal);
        return st == RS_ERR_NOMEM ? nomem(&c->w, err) : bad(&c->w, err, st, "%s", e.msg);
    }
    memcpy(&d->image_ground[4 * n], cal.ground_normal_enu, 3 * sizeof(double));
    d->image_ground[4 * n + 3] = cal.ground_offset_m;
    d->image_model[n] = cal.camera_model;
    d->image_model_sha256[n] = cal.camera_model_sha256;
    return RS_OK;
}

static rs_status gt_image(void *vctx, size_t index, const cJSON *o, size_t offset, rs_err *err)
{
    gt_ctx *c = vctx;
    rs_eval_data *d = c->d;
    c->w.list = "images";
    c->w.index = index;
    if (index >= (size_t)INT_MAX) return bad(&c->w, err, RS_ERR_INVALID, "too many images");
    rs_status st = check_entry(&c->w, o, offset, err);
    if (st != RS_OK) return st;
    long long id = 0;
    size_t n = (size_t)d->Nimages, cap = c->cap_images;
    if ((st = get_id(&c->w, o, "id", &id, err))) return st;
    if (!grow(&d->image_id, &cap, n, sizeof *d->image_id) ||
        !grow(&c->image_at, &(size_t){c->cap_images}, n, sizeof *c->image_at) ||
        !grow(&c->image_value, &(size_t){c->cap_images}, n, sizeof *c->image_value) ||
        (c->camera_key && !grow(&d->image_camera, &(size_t){c->cap_images}, n, sizeof *d->image_camera)))
        return nomem(&c->w, err);
    c->cap_images = cap;
    d->image_id[n] = id;
    c->image_at[n] = offset;
    c->image_value[n] = NULL;
    if (c->camera_key) d->image_camera[n] = NULL;
    d->Nimages++;
    if (c->camera_key) {
        const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, c->camera_key);
        if (!cJSON_IsString(v))
            return bad(&c->w, err, RS_ERR_INVALID, "%s: missing or not a string (it names the image's camera)",
                       c->camera_key);
        if (!(d->image_camera[n] = strdup(v->valuestring))) return nomem(&c->w, err);
    }
    if (c->recorded && (st = recorded_calibration(c, o, n, err))) return st;
    return c->group_key ? group_value(&c->w, o, c->group_key, &c->image_value[n], err) : RS_OK;
}

// Registers a category (id, name) at the end of d's list.
static rs_status add_category(gt_ctx *c, long long id, const char *name, rs_err *err)
{
    rs_eval_data *d = c->d;
    size_t n = (size_t)d->Ncategories, cap = c->cap_categories;
    if (!grow(&d->category_id, &cap, n, sizeof *d->category_id) ||
        !grow(&d->category_name, &(size_t){c->cap_categories}, n, sizeof *d->category_name) ||
        !grow(&c->category_map, &(size_t){c->cap_categories}, n, sizeof *c->category_map))
        return nomem(&c->w, err);
    c->cap_categories = cap;
    char buf[32];
    if (!name) {
        snprintf(buf, sizeof buf, "%lld", id);
        name = buf;
    }
    if (!(d->category_name[n] = strdup(name))) return nomem(&c->w, err);
    d->category_id[n] = id;
    c->category_map[n] = (id_index){id, (int)n};
    d->Ncategories++;
    qsort(c->category_map, n + 1, sizeof *c->category_map, cmp_id_index);
    return RS_OK;
}

static rs_status gt_category(void *vctx, size_t index, const cJSON *o, size_t offset, rs_err *err)
{
    gt_ctx *c = vctx;
    c->w.list = "categories";
    c->w.index = index;
    rs_status st = check_entry(&c->w, o, offset, err);
    if (st != RS_OK) return st;
    long long id = 0;
    if ((st = get_id(&c->w, o, "id", &id, err))) return st;
    if (find_id(c->category_map, c->d->Ncategories, id) >= 0)
        return bad(&c->w, err, RS_ERR_INVALID, "id: category %lld listed twice", id);
    const cJSON *name = cJSON_GetObjectItemCaseSensitive(o, "name");
    return add_category(c, id, cJSON_IsString(name) ? name->valuestring : NULL, err);
}

static rs_status gt_annotation(void *vctx, size_t index, const cJSON *o, size_t offset, rs_err *err)
{
    gt_ctx *c = vctx;
    rs_eval_data *d = c->d;
    c->w.list = "annotations";
    c->w.index = index;
    rs_status st = check_entry(&c->w, o, offset, err);
    if (st != RS_OK) return st;
    long long image_id = 0, category_id = 0;
    double q[2];
    int crowd = 0;
    if ((st = get_id(&c->w, o, "image_id", &image_id, err)) ||
        (st = get_id(&c->w, o, "category_id", &category_id, err)) || (st = get_point(&c->w, o, 0, q, err)))
        return st;
    int image = find_id(c->image_map, d->Nimages, image_id);
    if (image < 0) return bad(&c->w, err, RS_ERR_NOT_FOUND, "image_id %lld not in \"images\"", image_id);
    int category = find_id(c->category_map, d->Ncategories, category_id);
    if (category < 0) {
        if (c->categories_listed)
            return bad(&c->w, err, RS_ERR_NOT_FOUND, "category_id %lld not in \"categories\"", category_id);
        if ((st = add_category(c, category_id, NULL, err))) return st;
        category = d->Ncategories - 1;
    }
    const cJSON *ic = cJSON_GetObjectItemCaseSensitive(o, "iscrowd");
    if (ic && !cJSON_IsNull(ic)) {
        if (cJSON_IsBool(ic))
            crowd = cJSON_IsTrue(ic);
        else if (cJSON_IsNumber(ic) && (ic->valuedouble == 0 || ic->valuedouble == 1))
            crowd = ic->valuedouble == 1;
        else
            return bad(&c->w, err, RS_ERR_PARSE, "iscrowd: not 0, 1, true or false");
    }
    size_t n = d->Ngt, cap = c->cap_ann;
    if (!grow(&c->ann_image, &cap, n, sizeof *c->ann_image) ||
        !grow(&c->ann_q, &(size_t){c->cap_ann}, n, 2 * sizeof *c->ann_q) ||
        !grow(&c->ann_category, &(size_t){c->cap_ann}, n, sizeof *c->ann_category) ||
        !grow(&c->ann_crowd, &(size_t){c->cap_ann}, n, sizeof *c->ann_crowd))
        return nomem(&c->w, err);
    c->cap_ann = cap;
    c->ann_image[n] = image;
    c->ann_q[2 * n] = q[0];
    c->ann_q[2 * n + 1] = q[1];
    c->ann_category[n] = category;
    c->ann_crowd[n] = (unsigned char)crowd;
    d->Ngt++;
    return st;
}

typedef struct {
    const char *s;
    int image;
} named_image;

static int cmp_named_image(const void *a, const void *b)
{
    const named_image *x = a, *y = b;
    int k = strcmp(x->s, y->s);
    return k ? k : (x->image > y->image) - (x->image < y->image);
}

static int cmp_named_image_by_image(const void *a, const void *b)
{
    const named_image *x = a, *y = b;
    return (x->image > y->image) - (x->image < y->image);
}

// Numbers the distinct group values in order of first appearance (sort by value, then by the
// first image of each value): O(N log N) for any number of distinct values.
static rs_status make_groups(gt_ctx *c, rs_err *err)
{
    rs_eval_data *d = c->d;
    int N = d->Nimages;
    d->image_group = malloc((size_t)(N ? N : 1) * sizeof *d->image_group);
    named_image *v = malloc((size_t)(N ? N : 1) * sizeof *v);
    if (!d->image_group || !v) {
        free(v);
        return nomem(&c->w, err);
    }
    for (int i = 0; i < N; i++) v[i] = (named_image){c->image_value[i], i};
    qsort(v, (size_t)N, sizeof *v, cmp_named_image);
    int Nu = 0; // distinct values: v[k] for the first image of each value, moved to the front
    for (int i = 0; i < N; i++)
        if (i == 0 || strcmp(v[i].s, v[i - 1].s)) v[Nu++] = v[i];
    qsort(v, (size_t)Nu, sizeof *v, cmp_named_image_by_image);
    d->group_names = calloc((size_t)(Nu ? Nu : 1), sizeof *d->group_names);
    rs_status st = d->group_names ? RS_OK : nomem(&c->w, err);
    for (int g = 0; g < Nu && st == RS_OK; g++) {
        d->group_names[g] = strdup(v[g].s);
        d->Ngroups++;
        if (!d->group_names[g]) st = nomem(&c->w, err);
    }
    if (st == RS_OK) {
        // every image's group: its value's position among the distinct values
        for (int g = 0; g < Nu; g++) v[g].image = g;
        named_image *byname = malloc((size_t)(Nu ? Nu : 1) * sizeof *byname);
        if (!byname)
            st = nomem(&c->w, err);
        else {
            memcpy(byname, v, (size_t)Nu * sizeof *v);
            qsort(byname, (size_t)Nu, sizeof *byname, cmp_named_image);
            for (int i = 0; i < N; i++) {
                named_image key = {c->image_value[i], -1};
                int lo = 0, hi = Nu;
                while (lo < hi) {
                    int mid = lo + (hi - lo) / 2;
                    if (strcmp(byname[mid].s, key.s) < 0)
                        lo = mid + 1;
                    else
                        hi = mid;
                }
                d->image_group[i] = byname[lo].image;
            }
            free(byname);
        }
    }
    free(v);
    return st;
}

// Groups the annotations by image (stable counting sort) into d's arrays.
static rs_status gather_annotations(gt_ctx *c, rs_err *err)
{
    rs_eval_data *d = c->d;
    size_t G = d->Ngt ? d->Ngt : 1;
    d->gt_begin = calloc((size_t)d->Nimages + 1, sizeof *d->gt_begin);
    d->gt_point = malloc(2 * G * sizeof *d->gt_point);
    d->gt_category = malloc(G * sizeof *d->gt_category);
    d->gt_crowd = malloc(G);
    size_t *next = malloc(((size_t)d->Nimages + 1) * sizeof *next);
    if (!d->gt_begin || !d->gt_point || !d->gt_category || !d->gt_crowd || !next) {
        free(next);
        return nomem(&c->w, err);
    }
    for (size_t a = 0; a < d->Ngt; a++) d->gt_begin[c->ann_image[a] + 1]++;
    for (int m = 0; m < d->Nimages; m++) d->gt_begin[m + 1] += d->gt_begin[m];
    memcpy(next, d->gt_begin, ((size_t)d->Nimages + 1) * sizeof *next);
    for (size_t a = 0; a < d->Ngt; a++) {
        size_t k = next[c->ann_image[a]]++;
        d->gt_point[2 * k] = c->ann_q[2 * a];
        d->gt_point[2 * k + 1] = c->ann_q[2 * a + 1];
        d->gt_category[k] = c->ann_category[a];
        d->gt_crowd[k] = c->ann_crowd[a];
    }
    free(next);
    return RS_OK;
}

static rs_status load_gt(gt_ctx *c, size_t len, rs_err *err)
{
    rs_eval_data *d = c->d;
    c->w.index = SIZE_MAX;
    rs_status st = rs_json_object(c->w.text, 0, len, c->w.name, gt_top, c, err);
    if (st != RS_OK) return st;
    for (int k = 0; k < 2; k++)
        if (!c->has[k])
            return bad(&c->w, err, RS_ERR_PARSE, "no \"%s\" list (a COCO ground-truth file has one)", gt_keys[k]);

    if ((st = rs_json_array(c->w.text, c->span[0][0], c->span[0][1], c->w.name, gt_image, c, err))) return st;
    c->image_map = malloc((size_t)(d->Nimages ? d->Nimages : 1) * sizeof *c->image_map);
    if (!c->image_map) return nomem(&c->w, err);
    for (int i = 0; i < d->Nimages; i++) c->image_map[i] = (id_index){d->image_id[i], i};
    qsort(c->image_map, (size_t)d->Nimages, sizeof *c->image_map, cmp_id_index);
    for (int i = 1; i < d->Nimages; i++)
        if (c->image_map[i].id == c->image_map[i - 1].id) {
            int twice = c->image_map[i].index, first = c->image_map[i - 1].index;
            c->w.at = c->image_at[twice];
            c->w.list = "images";
            c->w.index = (size_t)twice;
            return bad(&c->w, err, RS_ERR_INVALID, "id: image %lld already listed as images[%d]", c->image_map[i].id,
                       first);
        }
    if (c->group_key && (st = make_groups(c, err))) return st;

    if (c->has[2]) {
        c->categories_listed = true;
        if ((st = rs_json_array(c->w.text, c->span[2][0], c->span[2][1], c->w.name, gt_category, c, err))) return st;
    }
    if ((st = rs_json_array(c->w.text, c->span[1][0], c->span[1][1], c->w.name, gt_annotation, c, err))) return st;
    return gather_annotations(c, err);
}

static void gt_ctx_free(gt_ctx *c)
{
    if (c->image_value)
        for (int i = 0; i < c->d->Nimages; i++) free(c->image_value[i]);
    free(c->image_value);
    free(c->image_at);
    free(c->ann_image);
    free(c->ann_q);
    free(c->ann_category);
    free(c->ann_crowd);
}

// ---- detections ----

typedef struct {
    rs_eval_data *d;
    const id_index *image_map, *category_map;
    double K;
    where w;
    size_t cap;
} det_ctx;

static rs_status det_entry(void *vctx, size_t index, const cJSON *o, size_t offset, rs_err *err)
{
    det_ctx *c = vctx;
    rs_eval_data *d = c->d;
    c->w.index = index;
    rs_status st = check_entry(&c->w, o, offset, err);
    if (st != RS_OK) return st;
    long long image_id = 0, category_id = 0;
    double q[2];
    if ((st = get_id(&c->w, o, "image_id", &image_id, err)) ||
        (st = get_id(&c->w, o, "category_id", &category_id, err)))
        return st;
    const cJSON *score = cJSON_GetObjectItemCaseSensitive(o, "score");
    if (!score) return bad(&c->w, err, RS_ERR_PARSE, "score: missing");
    if (!cJSON_IsNumber(score) || !isfinite(score->valuedouble))
        return bad(&c->w, err, RS_ERR_PARSE, "score: not a finite number");
    if ((st = get_point(&c->w, o, c->K, q, err))) return st;
    int image = find_id(c->image_map, d->Nimages, image_id);
    if (image < 0) return bad(&c->w, err, RS_ERR_NOT_FOUND, "image_id %lld not in the ground truth", image_id);
    int category = find_id(c->category_map, d->Ncategories, category_id);
    if (category < 0) return bad(&c->w, err, RS_ERR_NOT_FOUND, "category_id %lld not in the ground truth", category_id);
    size_t n = d->Ndets, cap = c->cap;
    if (!grow(&d->det_point, &cap, n, 2 * sizeof *d->det_point) ||
        !grow(&d->det_score, &(size_t){c->cap}, n, sizeof *d->det_score) ||
        !grow(&d->det_image, &(size_t){c->cap}, n, sizeof *d->det_image) ||
        !grow(&d->det_category, &(size_t){c->cap}, n, sizeof *d->det_category))
        return nomem(&c->w, err);
    c->cap = cap;
    d->det_point[2 * n] = q[0];
    d->det_point[2 * n + 1] = q[1];
    d->det_score[n] = score->valuedouble;
    d->det_image[n] = image;
    d->det_category[n] = category;
    d->Ndets++;
    return st;
}

// ---- public ----

rs_status rs_eval_parse(rs_eval_data **data, const char *gt_text, size_t gt_len, const char *gt_name,
                        const char *dets_text, size_t dets_len, const char *dets_name, const rs_eval_load_options *opt,
                        rs_err *err)
{
    *data = NULL;
    double K = opt ? opt->center_shift : 0;
    if (!isfinite(K)) return rs_err_set(err, RS_ERR_USAGE, "center shift: not finite");
    rs_eval_data *d = calloc(1, sizeof *d);
    if (!d) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    gt_ctx g = {.d = d,
                .w = {.text = gt_text, .name = gt_name},
                .group_key = opt ? opt->group_key : NULL,
                .camera_key = opt ? opt->camera_key : NULL,
                .recorded = opt && opt->recorded_calibration};
    if (g.recorded) {
        // the folder of the ground truth file: recorded camera models are relative to it
        const char *slash = strrchr(gt_name, '/');
        g.gt_dir = slash ? strndup(gt_name, (size_t)(slash - gt_name + (slash == gt_name))) : strdup(".");
        if (!g.gt_dir) {
            free(d);
            return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        }
    }
    rs_status st = load_gt(&g, gt_len, err);
    if (st == RS_OK) {
        det_ctx c = {.d = d,
                     .image_map = g.image_map,
                     .category_map = g.category_map,
                     .K = K,
                     .w = {.text = dets_text, .name = dets_name, .index = SIZE_MAX}};
        st = rs_json_array(dets_text, 0, dets_len, dets_name, det_entry, &c, err);
    }
    free(g.image_map);
    free(g.category_map);
    free(g.gt_dir);
    gt_ctx_free(&g);
    if (st != RS_OK) {
        rs_eval_data_free(d);
        return st;
    }
    *data = d;
    return RS_OK;
}

rs_status rs_eval_load(rs_eval_data **data, const char *gt_path, const char *dets_path, const rs_eval_load_options *opt,
                       rs_err *err)
{
    *data = NULL;
    char *gt = NULL, *dets = NULL;
    size_t gt_len = 0, dets_len = 0;
    rs_status st = rs_io_read_file(&gt, &gt_len, gt_path, err);
    if (st == RS_OK) st = rs_io_read_file(&dets, &dets_len, dets_path, err);
    if (st == RS_OK) st = rs_eval_parse(data, gt, gt_len, gt_path, dets, dets_len, dets_path, opt, err);
    free(gt);
    free(dets);
    return st;
}

void rs_eval_data_free(rs_eval_data *d)
{
    if (!d) return;
    free(d->image_id);
    free(d->image_group);
    if (d->image_camera)
        for (int i = 0; i < d->Nimages; i++) free(d->image_camera[i]);
    free(d->image_camera);
    for (int i = 0; i < d->Nrecorded; i++) {
        free(d->image_model[i]);
        free(d->image_model_sha256[i]);
    }
    free(d->image_model);
    free(d->image_model_sha256);
    free(d->image_ground);
    for (int g = 0; g < d->Ngroups; g++) free(d->group_names[g]);
    free(d->group_names);
    free(d->category_id);
    for (int k = 0; k < d->Ncategories; k++) free(d->category_name[k]);
    free(d->category_name);
    free(d->gt_begin);
    free(d->gt_point);
    free(d->gt_category);
    free(d->gt_crowd);
    free(d->det_point);
    free(d->det_score);
    free(d->det_image);
    free(d->det_category);
    free(d);
}

void rs_eval_data_counts(const rs_eval_data *d, size_t *Nimages, size_t *Ngt, size_t *Ncrowd, size_t *Ndets)
{
    size_t crowd = 0;
    for (size_t a = 0; a < d->Ngt; a++) crowd += d->gt_crowd[a];
    if (Nimages) *Nimages = (size_t)d->Nimages;
    if (Ngt) *Ngt = d->Ngt - crowd;
    if (Ncrowd) *Ncrowd = crowd;
    if (Ndets) *Ndets = d->Ndets;
}

size_t rs_eval_data_bytes(const rs_eval_data *d)
{
    size_t b = sizeof *d + (size_t)d->Nimages * (sizeof(long long) + sizeof(size_t)) + sizeof(size_t);
    if (d->image_group) b += (size_t)d->Nimages * sizeof(int);
    b += (size_t)d->Ncategories * (sizeof(long long) + sizeof(char *));
    b += d->Ngt * (2 * sizeof(double) + sizeof(int) + 1);
    b += d->Ndets * (3 * sizeof(double) + 2 * sizeof(int));
    return b;
}

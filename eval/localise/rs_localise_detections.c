// rs_localise_detections.c -- detections read from COCO results JSON, MOT Challenge CSV and
// Ultralytics txt folders (rs_localise.h, rs_localise_read_detections).
#define _POSIX_C_SOURCE 200809L // strtok_r
#include <cjson/cJSON.h>
#include <dirent.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "core/rs_io.h"
#include "core/rs_json.h"
#include "core/rs_text.h"
#include "eval/localise/rs_localise.h"

typedef struct {
    rs_localise_detection *d;
    size_t N, cap;
    const char *name, *text; // the file read (messages)
    double fps;
} reader;

static rs_localise_detection *push(reader *r)
{
    if (r->N == r->cap) {
        size_t c = r->cap ? 2 * r->cap : 256;
        rs_localise_detection *p = realloc(r->d, c * sizeof *p);
        if (!p) return NULL;
        r->d = p;
        r->cap = c;
    }
    rs_localise_detection *x = &r->d[r->N++];
    *x = (rs_localise_detection){.frame = -1, .time_s = NAN, .score = 1, .category_id = 1};
    return x;
}

// ---- COCO results ----

typedef struct {
    reader *r;
    size_t index;
    int line;
} coco_where;

__attribute__((format(printf, 4, 5))) static rs_status coco_bad(const coco_where *w, rs_err *err, rs_status st,
                                                                const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return rs_err_set(err, st, "%s:%d: entry %zu: %s", w->r->name, w->line, w->index, msg);
}

// An integer field (exact in a double); absent: RS_ERR_NOT_FOUND unless optional (*x unchanged).
static rs_status coco_int(const coco_where *w, const cJSON *o, const char *key, bool optional, long long *x,
                          rs_err *err)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    if (!v || cJSON_IsNull(v)) return optional ? RS_OK : coco_bad(w, err, RS_ERR_PARSE, "%s: missing", key);
    if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble) || v->valuedouble != floor(v->valuedouble) ||
        fabs(v->valuedouble) > 9007199254740992.0)
        return coco_bad(w, err, RS_ERR_PARSE, "%s: not an integer", key);
    *x = (long long)v->valuedouble;
    return RS_OK;
}

static rs_status coco_numbers(const coco_where *w, const cJSON *v, const char *key, int n, double *x, rs_err *err)
{
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != n)
        return coco_bad(w, err, RS_ERR_PARSE, "%s: not a list of %d numbers", key, n);
    int i = 0;
    for (const cJSON *e = v->child; e; e = e->next, i++) {
        if (!cJSON_IsNumber(e) || !isfinite(e->valuedouble))
            return coco_bad(w, err, RS_ERR_PARSE, "%s: element %d is not a finite number", key, i);
        x[i] = e->valuedouble;
    }
    return RS_OK;
}

static rs_status coco_entry(void *ctx, size_t index, const cJSON *o, size_t offset, rs_err *err)
{
    reader *r = ctx;
    coco_where w = {r, index, rs_json_line(r->text, offset)};
    if (!cJSON_IsObject(o)) return coco_bad(&w, err, RS_ERR_PARSE, "not an object");
    const char *in = NULL, *twice = rs_json_repeated_key(o, &in);
    if (twice)
        return coco_bad(&w, err, RS_ERR_PARSE, "\"%.100s\" appears twice in %s%.100s (which one is meant?)", twice,
                        *in ? "member " : "the entry", in);
    rs_localise_detection *d = push(r);
    if (!d) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", r->name);
    d->line = w.line;
    rs_status st;
    if ((st = coco_int(&w, o, "image_id", false, &d->image_id, err)) ||
        (st = coco_int(&w, o, "category_id", false, &d->category_id, err)) ||
        (st = coco_int(&w, o, "frame", true, &d->frame, err)))
        return st;
    const cJSON *bb = cJSON_GetObjectItemCaseSensitive(o, "bbox");
    if (!bb) return coco_bad(&w, err, RS_ERR_PARSE, "bbox: missing");
    if ((st = coco_numbers(&w, bb, "bbox", 4, d->bbox_px, err))) return st;
    if (d->bbox_px[2] < 0 || d->bbox_px[3] < 0)
        return coco_bad(&w, err, RS_ERR_INVALID, "bbox: negative width or height (%g, %g)", d->bbox_px[2],
                        d->bbox_px[3]);
    // COCO's corner origin: its (0, 0) is the top-left pixel's corner, roadside's (-0.5, -0.5)
    d->bbox_px[0] -= 0.5;
    d->bbox_px[1] -= 0.5;
    const cJSON *s = cJSON_GetObjectItemCaseSensitive(o, "score");
    if (!s) return coco_bad(&w, err, RS_ERR_PARSE, "score: missing");
    if (!cJSON_IsNumber(s) || !isfinite(s->valuedouble))
        return coco_bad(&w, err, RS_ERR_PARSE, "score: not a finite number");
    d->score = s->valuedouble;
    if (d->frame < -1) return coco_bad(&w, err, RS_ERR_INVALID, "frame: %lld is negative", d->frame);
    const cJSON *t = cJSON_GetObjectItemCaseSensitive(o, "time_s");
    if (t && !cJSON_IsNull(t)) {
        if (!cJSON_IsNumber(t) || !isfinite(t->valuedouble))
            return coco_bad(&w, err, RS_ERR_PARSE, "time_s: not a finite number");
        d->time_s = t->valuedouble;
    }
    const cJSON *c = cJSON_GetObjectItemCaseSensitive(o, "camera");
    if (c && !cJSON_IsNull(c)) {
        if (!cJSON_IsString(c)) return coco_bad(&w, err, RS_ERR_PARSE, "camera: not a string");
        if (strlen(c->valuestring) >= sizeof d->camera)
            return coco_bad(&w, err, RS_ERR_INVALID, "camera: longer than %d bytes", RS_LOCALISE_ID_MAX - 1);
        strcpy(d->camera, c->valuestring);
    }
    const cJSON *f = cJSON_GetObjectItemCaseSensitive(o, "file_name");
    if (f && !cJSON_IsNull(f) && !cJSON_IsString(f)) return coco_bad(&w, err, RS_ERR_PARSE, "file_name: not a string");
    const cJSON *bc = cJSON_GetObjectItemCaseSensitive(o, "bottom_center");
    if (bc && !cJSON_IsNull(bc)) {
        if ((st = coco_numbers(&w, bc, "bottom_center", 2, d->bottom_center_px, err))) return st;
        d->has_bottom_center = true;
    }
    return RS_OK;
}

static rs_status read_coco(reader *r, const char *path, rs_err *err)
{
    char *text = NULL;
    size_t len = 0;
    rs_status st = rs_io_read_file(&text, &len, path, err);
    if (st) return st;
    r->text = text;
    st = rs_json_array(text, 0, len, path, coco_entry, r, err);
    r->text = NULL;
    free(text);
    return st;
}

// ---- text lines (MOT CSV, Ultralytics txt) ----

// A finite number filling the whole field.
static bool number(const char *s, double *x)
{
    while (*s == ' ' || *s == '\t') s++;
    size_t n = strlen(s);
    while (n && (s[n - 1] == ' ' || s[n - 1] == '\t' || s[n - 1] == '\r')) n--;
    char t[64];
    if (n == 0 || n >= sizeof t) return false;
    memcpy(t, s, n);
    t[n] = 0;
    if (!rs_text_is_decimal(t)) return false; // (strtod would take 0x10, inf, nan)
    char *end;
    errno = 0;
    *x = strtod(t, &end);
    return *end == '\0' && errno != ERANGE && isfinite(*x);
}

// Splits line (modified) at any of `seps` into at most max fields; returns the count.
static int split(char *line, const char *seps, char **field, int max)
{
    int n = 0;
    char *save = NULL;
    for (char *t = strtok_r(line, seps, &save); t && n < max; t = strtok_r(NULL, seps, &save)) field[n++] = t;
    return n;
}

// Splits line (modified) at every comma, empty fields kept; returns the count (at most max).
static int split_commas(char *line, char **field, int max)
{
    int n = 0;
    for (char *p = line; n < max;) {
        field[n++] = p;
        p = strchr(p, ',');
        if (!p) break;
        *p++ = '\0';
    }
    return n;
}

static bool blank(const char *s)
{
    for (; *s; s++)
        if (*s != ' ' && *s != '\t' && *s != '\r') return false;
    return true;
}

static const char *const mot_fields[] = {"frame", "id", "bb_left", "bb_top", "bb_width", "bb_height", "conf", "x"};

static rs_status mot_line(reader *r, char *line, int lineno, rs_err *err)
{
    char *f[16];
    int n = split_commas(line, f, 16);
    if (n < 7)
        return rs_err_set(err, RS_ERR_PARSE,
                          "%s:%d: %s: missing (a MOT line has frame,id,bb_left,bb_top,"
                          "bb_width,bb_height,conf,...)",
                          r->name, lineno, mot_fields[n < 0 ? 0 : n]);
    double x[8];
    for (int k = 0; k < 7; k++)
        if (!number(f[k], &x[k]))
            return rs_err_set(err, RS_ERR_PARSE, "%s:%d: %s: '%s' is not a finite number", r->name, lineno,
                              mot_fields[k], f[k]);
    if (x[0] != floor(x[0]) || x[0] < 1 || x[0] > 1e15)
        return rs_err_set(err, RS_ERR_INVALID, "%s:%d: frame: %g is not a whole number >= 1", r->name, lineno, x[0]);
    if (x[4] < 0 || x[5] < 0)
        return rs_err_set(err, RS_ERR_INVALID, "%s:%d: bb_width, bb_height: negative (%g, %g)", r->name, lineno, x[4],
                          x[5]);
    rs_localise_detection *d = push(r);
    if (!d) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", r->name);
    d->line = lineno;
    d->image_id = (long long)x[0];
    d->frame = (long long)x[0] - 1;
    d->time_s = r->fps > 0 ? (double)d->frame / r->fps : NAN;
    // MOT's pixel corner is 1-based: its (1, 1) is roadside's (0, 0)
    d->bbox_px[0] = x[2] - 1;
    d->bbox_px[1] = x[3] - 1;
    d->bbox_px[2] = x[4];
    d->bbox_px[3] = x[5];
    d->score = x[6];
    // a class column (MOT's ground truth: frame,id,...,conf,class,visibility) when it is a
    // whole number >= 1 (detection files put -1 there, the unused x)
    if (n >= 8 && number(f[7], &x[7]) && x[7] >= 1 && x[7] == floor(x[7]) && x[7] < 1e9)
        d->category_id = (long long)x[7];
    return RS_OK;
}

static const char *const yolo_fields[] = {"class", "cx", "cy", "w", "h", "conf"};

static rs_status yolo_line(reader *r, char *line, int lineno, long long image_id, long long frame, int W, int H,
                           rs_err *err)
{
    char *f[8];
    int n = split(line, " \t", f, 8);
    if (n < 5)
        return rs_err_set(err, RS_ERR_PARSE, "%s:%d: %s: missing (an Ultralytics line is class cx cy w h [conf])",
                          r->name, lineno, yolo_fields[n]);
    if (n > 6)
        return rs_err_set(err, RS_ERR_PARSE, "%s:%d: more than 6 fields (class cx cy w h [conf])", r->name, lineno);
    double x[6] = {0, 0, 0, 0, 0, 1};
    for (int k = 0; k < n; k++)
        if (!number(f[k], &x[k]))
            return rs_err_set(err, RS_ERR_PARSE, "%s:%d: %s: '%s' is not a finite number", r->name, lineno,
                              yolo_fields[k], f[k]);
    if (x[0] != floor(x[0]) || x[0] < 0 || x[0] > 1e9)
        return rs_err_set(err, RS_ERR_INVALID, "%s:%d: class: %g is not a whole number >= 0", r->name, lineno, x[0]);
    if (x[3] < 0 || x[4] < 0)
        return rs_err_set(err, RS_ERR_INVALID, "%s:%d: w, h: negative (%g, %g)", r->name, lineno, x[3], x[4]);
    rs_localise_detection *d = push(r);
    if (!d) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", r->name);
    d->line = lineno;
    d->image_id = image_id;
    d->frame = frame;
    d->time_s = r->fps > 0 ? (double)frame / r->fps : NAN;
    d->category_id = (long long)x[0] + 1;
    // YOLO's corner origin: its cx W is roadside's x + 0.5 (docs/labels.md, "YOLO")
    d->bbox_px[2] = x[3] * W;
    d->bbox_px[3] = x[4] * H;
    d->bbox_px[0] = x[1] * W - 0.5 - 0.5 * d->bbox_px[2];
    d->bbox_px[1] = x[2] * H - 0.5 - 0.5 * d->bbox_px[3];
    d->score = x[5];
    return RS_OK;
}

typedef rs_status (*line_fn)(reader *r, char *line, int lineno, void *ctx, rs_err *err);

// Calls fn for every non-blank line of the file (a '#' line is a comment).
static rs_status each_line(reader *r, const char *path, line_fn fn, void *ctx, rs_err *err)
{
    char *text = NULL;
    size_t len = 0;
    rs_status st = rs_io_read_file(&text, &len, path, err);
    if (st) return st;
    if ((st = rs_text_check_no_nul(text, len, path, err))) {
        free(text);
        return st;
    }
    const char *saved = r->name;
    r->name = path;
    int lineno = 0;
    for (char *p = text, *next; p && *p && !st; p = next) {
        lineno++;
        next = strchr(p, '\n');
        if (next) *next++ = '\0';
        if (blank(p) || *p == '#') continue;
        st = fn(r, p, lineno, ctx, err);
    }
    r->name = saved;
    free(text);
    return st;
}

static rs_status mot_fn(reader *r, char *line, int lineno, void *ctx, rs_err *err)
{
    (void)ctx;
    return mot_line(r, line, lineno, err);
}

typedef struct {
    long long image_id, frame;
    int W, H;
} yolo_ctx;

static rs_status yolo_fn(reader *r, char *line, int lineno, void *ctx, rs_err *err)
{
    const yolo_ctx *y = ctx;
    return yolo_line(r, line, lineno, y->image_id, y->frame, y->W, y->H, err);
}

static int cmp_str(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

// A folder of <image>.txt: the files in name order; image k (0-based) is frame k.
static rs_status read_yolo(reader *r, const char *dir, int W, int H, rs_err *err)
{
    if (W <= 0 || H <= 0)
        return rs_err_set(err, RS_ERR_INVALID, "%s: Ultralytics boxes need the image size (the camera's)", dir);
    DIR *dp = opendir(dir);
    if (!dp) return rs_err_set(err, RS_ERR_IO, "%s: %s", dir, strerror(errno));
    char **names = NULL;
    size_t N = 0, cap = 0;
    rs_status st = RS_OK;
    for (struct dirent *e; (e = readdir(dp)) && !st;) {
        size_t len = strlen(e->d_name);
        if (len <= 4 || strcmp(e->d_name + len - 4, ".txt") != 0 || e->d_name[0] == '.') continue;
        if (N == cap) {
            cap = cap ? 2 * cap : 64;
            char **p = realloc(names, cap * sizeof *p);
            if (!p) {
                st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", dir);
                break;
            }
            names = p;
        }
        if (!(names[N] = strdup(e->d_name)))
            st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", dir);
        else
            N++;
    }
    closedir(dp);
    if (!st && N == 0) st = rs_err_set(err, RS_ERR_NOT_FOUND, "%s: no <image>.txt file (Ultralytics labels)", dir);
    if (names) qsort(names, N, sizeof *names, cmp_str);
    for (size_t k = 0; k < N && !st; k++) {
        char *path = rs_io_join(dir, names[k]);
        if (!path) {
            st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", dir);
            break;
        }
        // the image id: the stem when it is a whole number, else the file's 1-based rank
        char *end;
        errno = 0;
        long long id = strtoll(names[k], &end, 10);
        if (end == names[k] || strcmp(end, ".txt") != 0 || errno) id = (long long)k + 1;
        yolo_ctx y = {id, (long long)k, W, H};
        st = each_line(r, path, yolo_fn, &y, err);
        free(path);
    }
    for (size_t k = 0; k < N; k++) free(names[k]);
    free(names);
    return st;
}

rs_status rs_localise_read_detections(rs_localise_detection **dets, size_t *N, const char *path, int width, int height,
                                      double fps, rs_err *err)
{
    *dets = NULL;
    *N = 0;
    reader r = {.name = path, .fps = fps};
    struct stat sb;
    rs_status st;
    if (stat(path, &sb) == 0 && S_ISDIR(sb.st_mode))
        st = read_yolo(&r, path, width, height, err);
    else if (rs_io_has_extension(path, "json"))
        st = read_coco(&r, path, err);
    else
        st = each_line(&r, path, mot_fn, NULL, err);
    if (st) {
        free(r.d);
        return st;
    }
    *dets = r.d;
    *N = r.N;
    return RS_OK;
}

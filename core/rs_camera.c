// rs_camera.c -- the camera type, its files (mrcal .cameramodel, OpenCV YAML), projection and
// ground location. See rs_camera.h.
#include "core/rs_camera.h"

#include <cjson/cJSON.h>
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include <mrcal/poseutils.h>

#include "core/internal/rs_opencv.h"
#include "core/rs_io.h"
#include "core/rs_lens.h"
#include "core/rs_pose.h"
#include "core/rs_text.h"

#define MAX_IMAGE_SIDE_PX 1000000
#define MAX_TAN_FIELD     1000 // tan of the widest half-field: 89.94 deg
#define MAX_ASPECT        10   // fx / fy, either way
#define MAX_DISTORTION    1e4  // a distortion (or spline) parameter's magnitude
#define MAX_ROTATION_RAD  100  // a rotation vector's component: any rotation is within pi
#define MAX_TRANSLATION_M 1e7  // the local ENU frame: Earth-sized

void rs_camera_free(rs_camera *cam)
{
    if (!cam) return;
    free(cam->intrinsics);
    memset(cam, 0, sizeof *cam);
}

rs_status rs_camera_init(rs_camera *cam, const mrcal_lensmodel_t *lensmodel, const double *intrinsics, int width,
                         int height, rs_err *err)
{
    memset(cam, 0, sizeof *cam);
    const int n = mrcal_lensmodel_num_params(lensmodel);
    if (n <= 0) return rs_err_set(err, RS_ERR_INVALID, "lensmodel: not a lens model mrcal knows");
    cam->intrinsics = malloc((size_t)n * sizeof(double));
    if (!cam->intrinsics) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    memcpy(cam->intrinsics, intrinsics, (size_t)n * sizeof(double));
    cam->lensmodel = *lensmodel;
    cam->Nintrinsics = n;
    cam->width = width;
    cam->height = height;
    return RS_OK;
}

rs_status rs_camera_copy(rs_camera *out, const rs_camera *in, rs_err *err)
{
    rs_status st = rs_camera_init(out, &in->lensmodel, in->intrinsics, in->width, in->height, err);
    if (st == RS_OK) memcpy(out->rt_cam_enu, in->rt_cam_enu, sizeof out->rt_cam_enu);
    return st;
}

rs_status rs_camera_check(const rs_camera *cam, const char *path, rs_err *err)
{
    if (cam->width < 0 || cam->height < 0 || cam->width > MAX_IMAGE_SIDE_PX || cam->height > MAX_IMAGE_SIDE_PX)
        return rs_err_set(err, RS_ERR_INVALID, "%s: imagersize: %d x %d is not an image size", path, cam->width,
                          cam->height);
    for (int k = 0; k < cam->Nintrinsics; k++)
        if (!isfinite(cam->intrinsics[k]))
            return rs_err_set(err, RS_ERR_INVALID, "%s: intrinsics: not all finite", path);
    for (int i = 0; i < 6; i++)
        if (!isfinite(cam->rt_cam_enu[i])) return rs_err_set(err, RS_ERR_INVALID, "%s: extrinsics: non-finite", path);

    // Numbers no camera has. Beyond these bounds mrcal 2.2's unprojection (libdogleg) can loop for
    // ever (tests/fuzz found cx = 6.4e11 px, fy = 1e19 px, a distortion coefficient of 1e153), and
    // what would come out is not a camera: each bound is orders of magnitude past real lenses.
    const double *k = cam->intrinsics;
    const bool core = mrcal_lensmodel_metadata(&cam->lensmodel).has_core;
    if (core && !(k[0] > 0 && k[1] > 0))
        return rs_err_set(err, RS_ERR_INVALID, "%s: intrinsics: fx = %g, fy = %g: both must be > 0", path, k[0], k[1]);
    if (core && !(k[0] <= MAX_ASPECT * k[1] && k[1] <= MAX_ASPECT * k[0]))
        return rs_err_set(err, RS_ERR_INVALID,
                          "%s: intrinsics: fx = %g, fy = %g: pixels %g times as tall as wide (at most %g either way)",
                          path, k[0], k[1], k[0] / k[1], (double)MAX_ASPECT);
    if (core) {
        // No pixel more than MAX_TAN_FIELD focal lengths from the principal point (tan 89.94 deg
        // for a pinhole); without an image size the pixel (0, 0) stands in.
        const double u = fmax(fabs(k[2]), fabs((cam->width ? cam->width : 1) - 1 - k[2])) / k[0];
        const double v = fmax(fabs(k[3]), fabs((cam->height ? cam->height : 1) - 1 - k[3])) / k[1];
        if (!(u <= MAX_TAN_FIELD && v <= MAX_TAN_FIELD))
            return rs_err_set(err, RS_ERR_INVALID,
                              "%s: intrinsics: fx = %g, fy = %g, cx = %g, cy = %g put the image's edge %.3g focal "
                              "lengths from the principal point (at most %g)",
                              path, k[0], k[1], k[2], k[3], fmax(u, v), (double)MAX_TAN_FIELD);
    }
    for (int i = core ? 4 : 0; i < cam->Nintrinsics; i++)
        if (!(fabs(k[i]) <= MAX_DISTORTION))
            return rs_err_set(err, RS_ERR_INVALID,
                              "%s: intrinsics: value %d of %s is %g: a lens parameter is at most %g in magnitude", path,
                              i + 1, mrcal_lensmodel_name_unconfigured(&cam->lensmodel), k[i], (double)MAX_DISTORTION);
    for (int i = 0; i < 6; i++) {
        const double bound = i < 3 ? MAX_ROTATION_RAD : MAX_TRANSLATION_M;
        if (!(fabs(cam->rt_cam_enu[i]) <= bound))
            return rs_err_set(err, RS_ERR_INVALID, "%s: extrinsics: value %d is %g: %s at most %g in magnitude", path,
                              i + 1, cam->rt_cam_enu[i], i < 3 ? "a rotation (rad) is" : "a translation (m) is", bound);
    }
    return RS_OK;
}

// ---- what is handed to mrcal and OpenCV ----
// mrcal 2.2's .cameramodel parser reads past the end of its buffer on some malformed text (a
// comment or a string that runs to the end, mismatched quotes: tests/fuzz, docs/fuzzing.md), and
// OpenCV 4.6's FileStorage hangs on some malformed YAML ("---- 1") and allocates a matrix's
// rows x cols before counting its data. So only text of the shape these files have is handed
// over: a strict check of the syntax, not a second parser (mrcal and OpenCV still read it).

enum { MAX_DEPTH = 8, MAX_MATRIX_SIDE = 64 };

typedef struct {
    const char *p, *end;
    int line;
} scan;

static void skip_blank(scan *s)
{
    while (s->p < s->end) {
        if (*s->p == '#')
            while (s->p < s->end && *s->p != '\n') s->p++;
        else if (*s->p == '\n')
            s->line++, s->p++;
        else if (*s->p == ' ' || *s->p == '\t' || *s->p == '\r')
            s->p++;
        else
            break;
    }
}

// A Python literal of the .cameramodel subset: a dict of 'string': value, values strings (one
// line, printable, no backslash), numbers, lists and dicts, MAX_DEPTH deep.
static const char *literal(scan *s, int depth)
{
    skip_blank(s);
    if (s->p >= s->end) return "the text ends where a value should be";
    const char c = *s->p;
    if (c == '\'' || c == '"') {
        for (s->p++; s->p < s->end && *s->p != c; s->p++)
            if (*s->p == '\n' || *s->p == '\\' || (unsigned char)*s->p < 32 || (unsigned char)*s->p > 126)
                return "a quoted string that does not close on its line (or holds a backslash or a control byte)";
        if (s->p >= s->end) return "a quoted string that is never closed";
        s->p++;
        return NULL;
    }
    if (c == '{' || c == '[') {
        if (depth >= MAX_DEPTH) return "nested too deep";
        const char close = c == '{' ? '}' : ']';
        s->p++;
        for (;;) {
            skip_blank(s);
            if (s->p < s->end && *s->p == close) {
                s->p++;
                return NULL;
            }
            if (c == '{') {
                if (s->p >= s->end || (*s->p != '\'' && *s->p != '"')) return "a dict key that is not a quoted string";
                const char *bad = literal(s, depth + 1);
                if (bad) return bad;
                skip_blank(s);
                if (s->p >= s->end || *s->p != ':') return "a ':' missing after a key";
                s->p++;
            }
            const char *bad = literal(s, depth + 1);
            if (bad) return bad;
            skip_blank(s);
            if (s->p < s->end && *s->p == ',') {
                s->p++;
                continue;
            }
            if (s->p < s->end && *s->p == close) {
                s->p++;
                return NULL;
            }
            return c == '{' ? "a ',' or '}' missing in a dict" : "a ',' or ']' missing in a list";
        }
    }
    const char *start = s->p; // a number
    if (s->p < s->end && (*s->p == '+' || *s->p == '-')) s->p++;
    int digits = 0;
    while (s->p < s->end && ((*s->p >= '0' && *s->p <= '9') || *s->p == '.')) digits += *s->p++ != '.';
    if (digits && s->p < s->end && (*s->p == 'e' || *s->p == 'E')) {
        s->p++;
        if (s->p < s->end && (*s->p == '+' || *s->p == '-')) s->p++;
        int e = 0;
        while (s->p < s->end && *s->p >= '0' && *s->p <= '9') s->p++, e++;
        if (!e) return "a number with an empty exponent";
    }
    if (!digits || s->p == start) return "not a string, number, list or dict";
    return NULL;
}

const char *rs_camera_cameramodel_problem(const char *text, size_t len, int *line)
{
    if (len == 0) return "the file is empty";
    if (memchr(text, '\0', len)) return "the file contains a NUL byte";
    scan s = {text, text + len, 1};
    skip_blank(&s);
    const char *bad = s.p < s.end && *s.p == '{' ? literal(&s, 0) : "the text is not a dict {'lensmodel': ...}";
    if (!bad) {
        skip_blank(&s);
        if (s.p < s.end) bad = "text after the closing '}'";
    }
    *line = s.line;
    return bad;
}

// OpenCV's YAML as cv::FileStorage writes it: "%YAML:1.0", "---", then lines "key: value" (a
// number, a word, a quoted string, "!!opencv-matrix", or a flow list "[ ... ]" that may continue
// over lines of numbers), indented or not; rows and cols at most MAX_MATRIX_SIDE.
static const char *opencv_yaml_problem(const char *text, size_t len, int *line)
{
    if (memchr(text, '\0', len)) return "the file contains a NUL byte";
    const char *p = text, *end = text + len;
    bool header = false, in_list = false;
    for (*line = 1; p < end; (*line)++) {
        const char *eol = memchr(p, '\n', (size_t)(end - p));
        if (!eol) eol = end;
        const char *a = p, *b = eol;
        p = eol < end ? eol + 1 : end;
        while (a < b && (*a == ' ' || *a == '\t')) a++;
        while (b > a && (b[-1] == ' ' || b[-1] == '\t' || b[-1] == '\r')) b--;
        if (a == b || *a == '#') continue;
        const size_t n = (size_t)(b - a);
        if (!header) {
            if (n < 9 || strncmp(a, "%YAML", 5) || (a[5] != ':' && a[5] != ' ') || strncmp(a + 6, "1.", 2))
                return "not OpenCV YAML: the first line must be %YAML:1.0";
            header = true;
            continue;
        }
        if (n == 3 && !strncmp(a, "---", 3) && !in_list) continue;
        const char *v = a;
        if (!in_list) { // key: value
            if (!(isalpha((unsigned char)*v) || *v == '_')) return "a line that is not 'key: value'";
            while (v < b && (isalnum((unsigned char)*v) || *v == '_')) v++;
            const size_t klen = (size_t)(v - a);
            if (v >= b || *v != ':') return "a line that is not 'key: value'";
            v++;
            while (v < b && *v == ' ') v++;
            const bool side = (klen == 4 && (!strncmp(a, "rows", 4) || !strncmp(a, "cols", 4)));
            if (side && !(b - v >= 1 && b - v <= 2 && isdigit((unsigned char)v[0]) &&
                          (b - v == 1 || isdigit((unsigned char)v[1])) && atoi(v) <= MAX_MATRIX_SIDE))
                return "a matrix of more than 64 rows or columns (a camera file has 3x3 and 1x14 at most)";
            if (v == b || !strncmp(v, "!!opencv-matrix", 15)) continue;
            if (*v == '"') {
                if (b - v < 2 || b[-1] != '"' || memchr(v + 1, '"', (size_t)(b - v - 2))) return "a malformed string";
                continue;
            }
            if (*v != '[') {
                for (const char *t = v; t < b; t++)
                    if (!isalnum((unsigned char)*t) && !strchr("+-._", *t))
                        return "a value that is not a number or a word";
                continue;
            }
            v++;
            in_list = true;
        }
        for (; v < b; v++) { // inside a flow list: numbers and commas up to ']'
            if (*v == ']') {
                in_list = false;
                if (v + 1 != b) return "text after a list's ']'";
                break;
            }
            if (!isalnum((unsigned char)*v) && !strchr("+-., ", *v)) return "a list of something else than numbers";
        }
    }
    if (!header) return "the file is empty";
    if (in_list) return "a list '[' that is never closed";
    return NULL;
}

// mrcal's model (flexible array) -> rs_camera, checked.
static rs_status from_mrcal(rs_camera *cam, const mrcal_cameramodel_t *m, const char *path, rs_err *err)
{
    if (m->imagersize[0] < 1 || m->imagersize[1] < 1 || m->imagersize[0] > MAX_IMAGE_SIDE_PX ||
        m->imagersize[1] > MAX_IMAGE_SIDE_PX)
        return rs_err_set(err, RS_ERR_INVALID, "%s: imagersize: %u x %u is not an image size", path, m->imagersize[0],
                          m->imagersize[1]);
    rs_status st = rs_camera_init(cam, &m->lensmodel, m->intrinsics, (int)m->imagersize[0], (int)m->imagersize[1], err);
    if (st) return st;
    memcpy(cam->rt_cam_enu, m->rt_cam_ref, sizeof cam->rt_cam_enu);
    if ((st = rs_camera_check(cam, path, err))) rs_camera_free(cam);
    return st;
}

rs_status rs_camera_read_cameramodel_text(rs_camera *cam, const char *text, size_t len, const char *path, rs_err *err)
{
    memset(cam, 0, sizeof *cam);
    if (len > (size_t)0x7fffffff) return rs_err_set(err, RS_ERR_INVALID, "%s: too large for a .cameramodel", path);
    int line = 0;
    const char *bad = rs_camera_cameramodel_problem(text, len, &line);
    if (bad) return rs_err_set(err, RS_ERR_PARSE, "%s:%d: not a valid mrcal .cameramodel: %s", path, line, bad);
    // mrcal's reader also wants the last line ended (a comment at the very end runs past it)
    char *ended = NULL;
    if (text[len - 1] != '\n') {
        if (!(ended = malloc(len + 2))) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        memcpy(ended, text, len);
        ended[len] = '\n', ended[len + 1] = '\0';
    }
    mrcal_cameramodel_t *m = mrcal_read_cameramodel_string(ended ? ended : text, (int)(ended ? len + 1 : len));
    free(ended);
    if (!m)
        return rs_err_set(err, RS_ERR_PARSE,
                          "%s: not a valid mrcal .cameramodel (mrcal's reader prints the reason on stderr; it "
                          "needs lensmodel, intrinsics, imagersize and extrinsics)",
                          path);
    rs_status st = from_mrcal(cam, m, path, err);
    mrcal_free_cameramodel(&m);
    return st;
}

// OpenCV's ordinary (pinhole) distortion -> the mrcal model with the same projection
// (LENSMODEL_OPENCVn keeps OpenCV's coefficient order; no coefficients, or all zero:
// LENSMODEL_PINHOLE).
static rs_status from_opencv_distortion(rs_camera *cam, const double core[4], const rs_camera_opencv_file *f,
                                        const char *path, rs_err *err)
{
    int Nd = f->Ndist;
    if (Nd == 14) {
        if (f->dist[12] != 0 || f->dist[13] != 0)
            return rs_err_set(err, RS_ERR_UNSUPPORTED,
                              "%s: distortion_coefficients: 14 values with a tilted sensor (tauX = %g, tauY = %g): "
                              "mrcal has no equivalent model",
                              path, f->dist[12], f->dist[13]);
        Nd = 12; // zero tilt: exactly the 12-coefficient model
    }
    bool any = false;
    for (int i = 0; i < Nd; i++) any = any || f->dist[i] != 0;
    if (!any) Nd = 0;
    const mrcal_lensmodel_t lm = {.type = Nd == 0   ? MRCAL_LENSMODEL_PINHOLE
                                          : Nd == 4 ? MRCAL_LENSMODEL_OPENCV4
                                          : Nd == 5 ? MRCAL_LENSMODEL_OPENCV5
                                          : Nd == 8 ? MRCAL_LENSMODEL_OPENCV8
                                                    : MRCAL_LENSMODEL_OPENCV12};
    double intrinsics[16] = {core[0], core[1], core[2], core[3]};
    memcpy(intrinsics + 4, f->dist, (size_t)Nd * sizeof(double));
    return rs_camera_init(cam, &lm, intrinsics, f->width, f->height, err);
}

// OpenCV K and distortion -> the mrcal model with the same projection: the ordinary model
// above, or a fisheye distortion_model through rs_camera_init_kannala_brandt.
static rs_status from_opencv(rs_camera *cam, rs_camera_extra *extra, const rs_camera_opencv_file *f, const char *path,
                             rs_err *err)
{
    const double *K = f->K;
    if (K[3] != 0 || K[6] != 0 || K[7] != 0 || K[8] != 1)
        return rs_err_set(err, RS_ERR_INVALID, "%s: camera_matrix: not of the form [fx 0 cx; 0 fy cy; 0 0 1]", path);
    if (!(K[0] > 0 && K[4] > 0))
        return rs_err_set(err, RS_ERR_INVALID, "%s: camera_matrix: fx = %g, fy = %g: both must be > 0", path, K[0],
                          K[4]);
    if (K[1] != 0)
        return rs_err_set(err, RS_ERR_UNSUPPORTED, "%s: camera_matrix: skew %g: mrcal lens models have no skew term",
                          path, K[1]);
    if (f->has_rotation != f->has_t)
        return rs_err_set(err, RS_ERR_INVALID, "%s: %s: missing, a pose needs both the rotation and the translation",
                          path, f->has_rotation ? "tvec (or t)" : "R (or rvec)");
    const double core[4] = {K[0], K[4], K[2], K[5]};
    rs_status st;
    if (f->fisheye && f->Ndist != 4)
        return rs_err_set(err, RS_ERR_INVALID,
                          "%s: distortion_coefficients: %d values, a fisheye distortion_model needs 4 (k1 k2 k3 k4)",
                          path, f->Ndist);
    if (f->fisheye)
        st = rs_camera_init_kannala_brandt(cam, NULL, core, f->dist, f->width, f->height, path, err);
    else
        st = from_opencv_distortion(cam, core, f, path, err);
    if (st) return st;
    if (f->has_rotation) {
        memcpy(cam->rt_cam_enu, f->rvec, 3 * sizeof(double));
        memcpy(cam->rt_cam_enu + 3, f->t, 3 * sizeof(double));
    }
    if (extra) {
        extra->has_pose = f->has_rotation;
        extra->has_R = f->has_R;
        memcpy(extra->R_cam_enu, f->R, sizeof extra->R_cam_enu);
        extra->has_P = f->has_P;
        memcpy(extra->P, f->P, sizeof extra->P);
    }
    return RS_OK;
}

// The text OpenCV will read from `path`: YAML of the shape above, or JSON (cJSON) whose "rows"
// and "cols" are at most MAX_MATRIX_SIDE.
static bool json_sides_ok(const cJSON *j)
{
    for (const cJSON *e = j ? j->child : NULL; e; e = e->next) {
        if (e->string && (!strcmp(e->string, "rows") || !strcmp(e->string, "cols")) &&
            !(cJSON_IsNumber(e) && e->valuedouble <= MAX_MATRIX_SIDE))
            return false;
        if (!json_sides_ok(e)) return false;
    }
    return true;
}

// image_width and image_height as written: OpenCV reads an integer into an int, so 2^40 came out
// as 0 ("image_width: 0 is not ..."); the number as the file writes it is checked here first.
static rs_status opencv_size_text_check(const char *text, const char *path, rs_err *err)
{
    static const char *const keys[2] = {"image_width", "image_height"};
    for (int k = 0; k < 2; k++) {
        const size_t n = strlen(keys[k]);
        for (const char *p = strstr(text, keys[k]); p; p = strstr(p + n, keys[k])) {
            const char *q = p + n;
            if (p > text && !strchr("\n\"{ \t,", p[-1])) continue; // part of a longer name
            if (*q == '"') q++;
            while (*q == ' ' || *q == '\t') q++;
            if (*q != ':') continue;
            for (q++; *q == ' ' || *q == '\t'; q++) {}
            char token[48];
            size_t t = strcspn(q, " \t\r\n,}#");
            if (t == 0 || t >= sizeof token || !strchr("+-0123456789.", *q)) break; // OpenCV's to judge
            memcpy(token, q, t);
            token[t] = '\0';
            long long v;
            char why[RS_TEXT_WHY_BYTES];
            if (!rs_text_parse_integer(&v, why, token, 1, 1000000))
                return rs_err_set(err, RS_ERR_INVALID,
                                  "%s: %s: %s (a positive whole number of pixels, at most 1000000)", path, keys[k],
                                  why);
            break;
        }
    }
    return RS_OK;
}

static rs_status opencv_text_check(const char *text, size_t len, const char *path, rs_err *err)
{
    rs_status st = opencv_size_text_check(text, path, err);
    if (st) return st;
    if (rs_io_has_extension(path, "json")) {
        cJSON *j = cJSON_ParseWithLength(text, len);
        const bool ok = j && json_sides_ok(j);
        cJSON_Delete(j);
        return ok ? RS_OK
                  : rs_err_set(err, RS_ERR_PARSE, "%s: not OpenCV JSON (invalid JSON, or a matrix over %dx%d)", path,
                               MAX_MATRIX_SIDE, MAX_MATRIX_SIDE);
    }
    int line = 0;
    const char *bad = opencv_yaml_problem(text, len, &line);
    if (!bad) return RS_OK;
    if (line > 0)
        return rs_err_set(err, RS_ERR_PARSE, "%s:%d: not OpenCV YAML as cv::FileStorage writes it: %s", path, line,
                          bad);
    return rs_err_set(err, RS_ERR_PARSE, "%s: not OpenCV YAML as cv::FileStorage writes it: %s", path, bad);
}

// A number member of a JSON object into *out: false when absent; an error when not a finite number.
static rs_status json_number(double *out, bool *found, const cJSON *obj, const char *key, const char *path, rs_err *err)
{
    const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
    *found = it != NULL;
    if (!it) return RS_OK;
    if (!cJSON_IsNumber(it) || !isfinite(it->valuedouble))
        return rs_err_set(err, RS_ERR_INVALID, "%s: %s: not a finite number", path, key);
    *out = it->valuedouble;
    return RS_OK;
}

// The equidistant fisheye triple {"f": 340.0, "x0": 640, "y0": 480} (optionally image_width and
// image_height) of a .json without camera_matrix or K: *triple tells whether the text is one.
static rs_status read_equidistant_triple(rs_camera *cam, bool *triple, const char *text, size_t len, const char *path,
                                         rs_err *err)
{
    cJSON *j = cJSON_ParseWithLength(text, len);
    *triple = j && cJSON_IsObject(j) && cJSON_GetObjectItemCaseSensitive(j, "f") &&
              !cJSON_GetObjectItemCaseSensitive(j, "camera_matrix") && !cJSON_GetObjectItemCaseSensitive(j, "K");
    double v[5] = {NAN, NAN, NAN, 0, 0};
    static const char *const keys[5] = {"f", "x0", "y0", "image_width", "image_height"};
    rs_status st = RS_OK;
    for (int i = 0; *triple && i < 5 && st == RS_OK; i++) {
        bool found;
        st = json_number(&v[i], &found, j, keys[i], path, err);
        if (st == RS_OK && !found && i < 3)
            st = rs_err_set(err, RS_ERR_PARSE, "%s: %s: missing (an equidistant fisheye is {\"f\", \"x0\", \"y0\"})",
                            path, keys[i]);
        if (st == RS_OK && i >= 3 && !(v[i] >= 0 && v[i] <= MAX_IMAGE_SIDE_PX && v[i] == floor(v[i])))
            st = rs_err_set(err, RS_ERR_INVALID, "%s: %s: %g is not a whole number of pixels", path, keys[i], v[i]);
    }
    cJSON_Delete(j);
    if (*triple && st == RS_OK && !(v[0] > 0))
        st = rs_err_set(err, RS_ERR_INVALID, "%s: f: %g: must be > 0", path, v[0]);
    if (*triple && st == RS_OK) st = rs_camera_init_equidistant(cam, v[0], v[1], v[2], (int)v[3], (int)v[4], err);
    if (*triple && st == RS_OK) st = rs_camera_check(cam, path, err);
    return st;
}

rs_status rs_camera_read(rs_camera *cam, rs_camera_extra *extra, const char *path, rs_err *err)
{
    memset(cam, 0, sizeof *cam);
    if (extra) memset(extra, 0, sizeof *extra);
    rs_status st;
    if (rs_io_has_extension(path, "yaml") || rs_io_has_extension(path, "yml") || rs_io_has_extension(path, "json")) {
        rs_camera_opencv_file f;
        char *text = NULL;
        size_t len = 0;
        st = rs_io_read_file_max(&text, &len, path, RS_IO_MAX_SMALL_FILE_BYTES, err); // a regular file, bounded
        bool triple = false;
        if (st == RS_OK && rs_io_has_extension(path, "json"))
            st = read_equidistant_triple(cam, &triple, text, len, path, err);
        if (st == RS_OK && !triple) st = opencv_text_check(text, len, path, err);
        free(text);
        if (st == RS_OK && !triple) st = rs_camera_opencv_read(&f, path, err);
        if (st == RS_OK && !triple) st = from_opencv(cam, extra, &f, path, err);
        if (st == RS_OK && !triple) st = rs_camera_check(cam, path, err); // numbers no camera has
    } else {
        char *text = NULL;
        size_t len = 0;
        st = rs_io_read_file_max(&text, &len, path, RS_IO_MAX_SMALL_FILE_BYTES, err);
        if (st == RS_OK) st = rs_camera_read_cameramodel_text(cam, text, len, path, err);
        free(text);
    }
    if (st) rs_camera_free(cam);
    return st;
}

rs_status rs_camera_write_cameramodel(const rs_camera *cam, const char *path, rs_err *err)
{
    mrcal_cameramodel_t *m = calloc(1, sizeof *m + (size_t)cam->Nintrinsics * sizeof(double));
    if (!m) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    memcpy(m->rt_cam_ref, cam->rt_cam_enu, sizeof m->rt_cam_ref);
    m->imagersize[0] = (unsigned)cam->width;
    m->imagersize[1] = (unsigned)cam->height;
    m->lensmodel = cam->lensmodel;
    memcpy(m->intrinsics, cam->intrinsics, (size_t)cam->Nintrinsics * sizeof(double));
    // mrcal writes by file name only: it writes the temporary file, which is then committed
    // (fsync'ed and renamed into place) like any other output.
    rs_io_atomic a;
    rs_status st = rs_io_atomic_open(&a, path, err);
    if (st == RS_OK) st = rs_io_atomic_release(&a, err);
    if (st == RS_OK && !mrcal_write_cameramodel_file(a.tmp_path, m))
        st = rs_err_set(err, RS_ERR_EXTERNAL, "%s: mrcal could not write the camera model", path);
    if (st == RS_OK)
        st = rs_io_atomic_commit(&a, err);
    else
        rs_io_atomic_abort(&a);
    free(m);
    return st;
}

bool rs_camera_has_opencv_equivalent(const rs_camera *cam)
{
    switch (cam->lensmodel.type) {
    case MRCAL_LENSMODEL_PINHOLE:
    case MRCAL_LENSMODEL_OPENCV4:
    case MRCAL_LENSMODEL_OPENCV5:
    case MRCAL_LENSMODEL_OPENCV8:
    case MRCAL_LENSMODEL_OPENCV12: return true;
    default: return false;
    }
}

rs_status rs_camera_write_opencv_yaml(const rs_camera *cam, const char *path, rs_err *err)
{
    if (!rs_camera_has_opencv_equivalent(cam))
        return rs_err_set(err, RS_ERR_UNSUPPORTED, "%s: lens model %s has no OpenCV equivalent", path,
                          mrcal_lensmodel_name_unconfigured(&cam->lensmodel));
    char *text = NULL;
    rs_status st = rs_camera_opencv_yaml_text(&text, cam->intrinsics, cam->Nintrinsics - 4, cam->rt_cam_enu, cam->width,
                                              cam->height, err);
    if (st == RS_OK) st = rs_io_write_file(path, text, strlen(text), err);
    free(text);
    return st;
}

double rs_camera_max_tan(const rs_camera *cam)
{
    if (cam->width < 1 || cam->height < 1) return INFINITY; // no image size: no corners to go by
    const double W = cam->width, H = cam->height;
    const double corners[4][2] = {{-0.5, -0.5}, {W - 0.5, -0.5}, {-0.5, H - 0.5}, {W - 0.5, H - 0.5}};
    double max_tan = 0;
    for (int i = 0; i < 4; i++) {
        mrcal_point2_t q = {.x = corners[i][0], .y = corners[i][1]};
        mrcal_point3_t v;
        double t = 1e3;
        if (rs_lens_unproject(&v, &q, 1, &cam->lensmodel, cam->intrinsics) && v.z > 1e-9) t = hypot(v.x, v.y) / v.z;
        if (!isfinite(t)) t = 1e3; // mrcal "succeeds" with NaN where the distortion never reaches the corner
        if (t > max_tan) max_tan = t;
    }
    return max_tan * 1.15 + 0.02;
}

bool rs_camera_in_field(const double p_cam[3], double max_tan)
{
    return p_cam[2] > 0 && !(hypot(p_cam[0], p_cam[1]) / p_cam[2] > max_tan);
}

bool rs_camera_project_visible(double q_px[2], const rs_camera *cam, double max_tan, const double p_enu_m[3])
{
    mrcal_point3_t pc;
    mrcal_point2_t q;
    mrcal_transform_point_rt(pc.xyz, NULL, NULL, cam->rt_cam_enu, p_enu_m);
    const bool ok = rs_camera_in_field(pc.xyz, max_tan) &&
                    rs_lens_project(&q, NULL, NULL, &pc, 1, &cam->lensmodel, cam->intrinsics) && isfinite(q.x) &&
                    isfinite(q.y);
    q_px[0] = ok ? q.x : NAN;
    q_px[1] = ok ? q.y : NAN;
    return ok;
}

int rs_camera_project(double *q_px, const rs_camera *cam, const double *p_enu_m, int N)
{
    const double max_tan = rs_camera_max_tan(cam);
    int n = 0;
    for (int i = 0; i < N; i++) n += rs_camera_project_visible(&q_px[2 * i], cam, max_tan, &p_enu_m[3 * i]);
    return n;
}

rs_status rs_camera_locate_ground(double p_enu_m[3], const rs_camera *cam, const double q_px[2],
                                  const double plane_normal_enu[3], double plane_offset_m, rs_err *err)
{
    if (!p_enu_m || !cam || !cam->intrinsics || !q_px || !plane_normal_enu)
        return rs_err_set(err, RS_ERR_INVALID, "rs_camera_locate_ground: NULL argument");
    const mrcal_lensmodel_t *lensmodel = &cam->lensmodel;
    const double *intrinsics = cam->intrinsics, *rt_cam_enu = cam->rt_cam_enu;
    double nn = 0.0;
    bool finite = isfinite(plane_offset_m) && isfinite(q_px[0]) && isfinite(q_px[1]);
    for (int i = 0; i < 3; i++) {
        nn += plane_normal_enu[i] * plane_normal_enu[i];
        finite = finite && isfinite(plane_normal_enu[i]);
    }
    for (int i = 0; i < 6; i++) finite = finite && isfinite(rt_cam_enu[i]);
    if (!finite) return rs_err_set(err, RS_ERR_INVALID, "rs_camera_locate_ground: non-finite input");
    if (!(nn > 0.0)) return rs_err_set(err, RS_ERR_INVALID, "plane_normal_enu: zero vector");
    nn = sqrt(nn);
    double n[3];
    for (int i = 0; i < 3; i++) n[i] = plane_normal_enu[i] / nn;
    const double offset = plane_offset_m / nn;

    mrcal_point2_t q = {.x = q_px[0], .y = q_px[1]};
    mrcal_point3_t v;
    if (!rs_lens_unproject(&v, &q, 1, lensmodel, intrinsics) || !isfinite(v.x) || !isfinite(v.y) || !isfinite(v.z))
        return rs_err_set(err, RS_ERR_UNSUPPORTED,
                          "pixel (%g, %g): the lens model gives it no ray (outside what the lens sees)", q_px[0],
                          q_px[1]);
    double R[9], C[3], d[3];
    mrcal_R_from_r(R, NULL, rt_cam_enu);
    rs_pose_position_from_rt(C, NULL, rt_cam_enu);
    const double vn = sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    for (int i = 0; i < 3; i++) d[i] = (R[i] * v.x + R[3 + i] * v.y + R[6 + i] * v.z) / vn; // R^T v
    const double nd = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
    const double nC = n[0] * C[0] + n[1] * C[1] + n[2] * C[2];
    if (fabs(nd) < 1e-12)
        return rs_err_set(err, RS_ERR_DEGENERATE, "pixel (%g, %g): its ray is parallel to the plane", q_px[0], q_px[1]);
    const double lambda = (offset - nC) / nd;
    if (!(lambda > 0.0))
        return rs_err_set(err, RS_ERR_DEGENERATE, "pixel (%g, %g): the plane is behind the camera along its ray",
                          q_px[0], q_px[1]);
    double p[3];
    for (int i = 0; i < 3; i++) p[i] = C[i] + lambda * d[i];

    // Polish: rs_lens_unproject() is iterative; a few Gauss-Newton steps on rs_lens_project() within
    // the plane (basis u, w) bring the reprojection error to the last bits.
    double u[3], w[3];
    {
        const int k = fabs(n[0]) < 0.9 ? 0 : 1; // any axis not along n
        double a[3] = {0, 0, 0};
        a[k] = 1.0;
        const double an = a[0] * n[0] + a[1] * n[1] + a[2] * n[2];
        for (int i = 0; i < 3; i++) u[i] = a[i] - an * n[i];
        const double un = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        for (int i = 0; i < 3; i++) u[i] /= un;
        w[0] = n[1] * u[2] - n[2] * u[1];
        w[1] = n[2] * u[0] - n[0] * u[2];
        w[2] = n[0] * u[1] - n[1] * u[0];
    }
    for (int iter = 0; iter < 4; iter++) {
        mrcal_point3_t pc, dq_dpc[2];
        mrcal_point2_t qp;
        double dpc_dp[9];
        mrcal_transform_point_rt(pc.xyz, NULL, dpc_dp, rt_cam_enu, p);
        if (!rs_lens_project(&qp, dq_dpc, NULL, &pc, 1, lensmodel, intrinsics)) break;
        const double e0 = qp.x - q.x, e1 = qp.y - q.y;
        double J[4]; // (2,2): dq/d(a,b)
        for (int r = 0; r < 2; r++) {
            double g[3];
            for (int j = 0; j < 3; j++)
                g[j] =
                    dq_dpc[r].xyz[0] * dpc_dp[j] + dq_dpc[r].xyz[1] * dpc_dp[3 + j] + dq_dpc[r].xyz[2] * dpc_dp[6 + j];
            J[r * 2] = g[0] * u[0] + g[1] * u[1] + g[2] * u[2];
            J[r * 2 + 1] = g[0] * w[0] + g[1] * w[1] + g[2] * w[2];
        }
        const double det = J[0] * J[3] - J[1] * J[2];
        if (!(fabs(det) > 0.0)) break;
        const double da = -(J[3] * e0 - J[1] * e1) / det, db = -(-J[2] * e0 + J[0] * e1) / det;
        for (int i = 0; i < 3; i++) p[i] += da * u[i] + db * w[i];
        if (fabs(e0) + fabs(e1) < 1e-13) break;
    }
    memcpy(p_enu_m, p, sizeof(p));
    return RS_OK;
}

// The squared pixel distance from q of the point a + t (b - a), its projection in qt; INFINITY
// when it does not project.
static double seen_distance2(double qt[2], double p[3], double t, const double a[3], const double b[3],
                             const double q[2], const rs_camera *cam, double max_tan)
{
    for (int k = 0; k < 3; k++) p[k] = a[k] + t * (b[k] - a[k]);
    if (!rs_camera_project_visible(qt, cam, max_tan, p)) return INFINITY;
    return (qt[0] - q[0]) * (qt[0] - q[0]) + (qt[1] - q[1]) * (qt[1] - q[1]);
}

bool rs_camera_nearest_on_polyline(double p_enu_m[3], double q_px[2], const rs_camera *cam,
                                   const double *vertices_enu_m, int Nvertices, const double q_pick_px[2])
{
    enum { SAMPLES = 256 };
    const double max_tan = rs_camera_max_tan(cam);
    double best = INFINITY, p[3], q[2];
    for (int s = 0; s + 1 < Nvertices; s++) {
        const double *a = &vertices_enu_m[3 * s], *b = &vertices_enu_m[3 * s + 3];
        int kbest = -1;
        double dbest = INFINITY;
        for (int k = 0; k <= SAMPLES; k++) {
            const double d = seen_distance2(q, p, (double)k / SAMPLES, a, b, q_pick_px, cam, max_tan);
            if (d < dbest) dbest = d, kbest = k;
        }
        if (kbest < 0) continue;
        // ternary search in the bracket around the best sample (the distance is unimodal there)
        double lo = fmax(0.0, (kbest - 1.0) / SAMPLES), hi = fmin(1.0, (kbest + 1.0) / SAMPLES);
        while (hi - lo > 1e-6) {
            const double m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
            if (seen_distance2(q, p, m1, a, b, q_pick_px, cam, max_tan) <
                seen_distance2(q, p, m2, a, b, q_pick_px, cam, max_tan))
                hi = m2;
            else
                lo = m1;
        }
        const double d = seen_distance2(q, p, 0.5 * (lo + hi), a, b, q_pick_px, cam, max_tan);
        if (d < best) {
            best = d;
            memcpy(p_enu_m, p, sizeof p);
            q_px[0] = q[0], q_px[1] = q[1];
        }
    }
    if (isfinite(best)) return true;
    p_enu_m[0] = p_enu_m[1] = p_enu_m[2] = NAN;
    q_px[0] = q_px[1] = NAN;
    return false;
}

bool rs_camera_path(char *out, size_t n, const char *dir, const char *id, const char *ext)
{
    size_t nd = dir ? strlen(dir) : 0;
    while (nd > 1 && dir[nd - 1] == '/') nd--;
    const int len = nd ? snprintf(out, n, "%.*s/%s%s", (int)nd, dir, id, ext) : snprintf(out, n, "%s%s", id, ext);
    if (len >= 0 && (size_t)len < n) return true;
    if (n) out[0] = 0;
    return false;
}

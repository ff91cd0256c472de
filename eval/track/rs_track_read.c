// rs_track_read.c -- the located-detections CSV read for `roadside track` (rs_track_io.h).
// One function, rs_track_read_located: the reader of `roadside localise` is to replace it.
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_io.h"
#include "eval/track/rs_track_io.h"

enum { NFIELDS = 16 };
static const char *const field_names[NFIELDS] = {
    "image_id", "camera", "frame", "time_s",  "category_id", "score",     "u_px",      "v_px",
    "e_m",      "n_m",    "u_m",   "lat_deg", "lon_deg",     "sigma_e_m", "sigma_n_m", "cov_en_m2"};

// Parses field k: a double (empty -> NaN when optional) or, for integers, a long long.
static rs_status number(double *x, const char *s, bool optional, const char *path, int line, int k, rs_err *err)
{
    if (!*s) {
        if (optional) return *x = NAN, RS_OK;
        return rs_err_set(err, RS_ERR_PARSE, "%s:%d: %s: empty", path, line, field_names[k]);
    }
    char *end = NULL;
    errno = 0;
    *x = strtod(s, &end);
    if (*end || errno == ERANGE || !isfinite(*x))
        return rs_err_set(err, RS_ERR_PARSE, "%s:%d: %s: '%.40s' is not a finite number", path, line, field_names[k],
                          s);
    return RS_OK;
}

static rs_status integer(long long *x, const char *s, const char *path, int line, int k, rs_err *err)
{
    char *end = NULL;
    errno = 0;
    *x = strtoll(s, &end, 10);
    if (!*s || *end || errno == ERANGE)
        return rs_err_set(err, RS_ERR_PARSE, "%s:%d: %s: '%.40s' is not a whole number", path, line, field_names[k], s);
    return RS_OK;
}

static rs_status parse_row(rs_track_located *d, char *text, const char *path, int line, rs_err *err)
{
    char *f[NFIELDS];
    int n = 0;
    for (char *p = text;; p++) {
        if (n < NFIELDS) f[n] = p;
        n++;
        p = strchr(p, ',');
        if (!p) break;
        *p = '\0';
    }
    if (n != NFIELDS)
        return rs_err_set(err, RS_ERR_PARSE, "%s:%d: %d fields, the header has %d", path, line, n, NFIELDS);
    *d = (rs_track_located){.line = line};
    long long ll;
    rs_status st;
    if ((st = integer(&d->image_id, f[0], path, line, 0, err))) return st;
    if (strlen(f[1]) >= RS_TRACK_CAMERA_BYTES)
        return rs_err_set(err, RS_ERR_INVALID, "%s:%d: camera: longer than %d bytes", path, line,
                          RS_TRACK_CAMERA_BYTES - 1);
    strcpy(d->camera, f[1]);
    if (!*f[2])
        d->frame = -1;
    else if ((st = integer(&ll, f[2], path, line, 2, err)))
        return st;
    else
        d->frame = (long)ll;
    if ((st = number(&d->time_s, f[3], true, path, line, 3, err))) return st;
    if ((st = integer(&ll, f[4], path, line, 4, err))) return st;
    if (ll < -2147483647 || ll > 2147483647)
        return rs_err_set(err, RS_ERR_PARSE, "%s:%d: category_id: %lld is out of range", path, line, ll);
    d->category_id = (int)ll;
    double *const x[] = {&d->score,   &d->u_px,    &d->v_px,      &d->e_m,       &d->n_m,      &d->u_m,
                         &d->lat_deg, &d->lon_deg, &d->sigma_e_m, &d->sigma_n_m, &d->cov_en_m2};
    static const bool optional[] = {false, true, true, false, false, true, true, true, false, false, false};
    for (int k = 5; k < NFIELDS; k++)
        if ((st = number(x[k - 5], f[k], optional[k - 5], path, line, k, err))) return st;
    if (!(d->sigma_e_m > 0) || !(d->sigma_n_m > 0) || !(fabs(d->cov_en_m2) < d->sigma_e_m * d->sigma_n_m))
        return rs_err_set(err, RS_ERR_INVALID,
                          "%s:%d: sigma_e_m, sigma_n_m, cov_en_m2: (%g, %g, %g) is not a positive definite covariance "
                          "(sigmas > 0, |cov| < sigma_e sigma_n)",
                          path, line, d->sigma_e_m, d->sigma_n_m, d->cov_en_m2);
    return RS_OK;
}

rs_status rs_track_read_located(rs_track_located **out, size_t *N, const char *path, rs_err *err)
{
    *out = NULL;
    *N = 0;
    char *text = NULL;
    size_t len = 0;
    rs_status st = rs_io_read_file(&text, &len, path, err);
    if (st) return st;
    if (strlen(text) != len) {
        free(text);
        return rs_err_set(err, RS_ERR_PARSE, "%s: holds a NUL byte: not a CSV text file", path);
    }
    rs_track_located *dets = NULL;
    size_t n = 0, cap = 0;
    int line = 0;
    char *p = text;
    if (!strncmp(p, "\xEF\xBB\xBF", 3)) p += 3;
    while (*p && st == RS_OK) {
        line++;
        char *eol = strchr(p, '\n');
        char *next = eol ? eol + 1 : p + strlen(p);
        if (eol) *eol = '\0';
        size_t l = strlen(p);
        if (l && p[l - 1] == '\r') p[--l] = '\0';
        if (line == 1) {
            if (strcmp(p, RS_TRACK_LOCATED_HEADER))
                st = rs_err_set(err, RS_ERR_PARSE, "%s:1: header: expected '%s'", path, RS_TRACK_LOCATED_HEADER);
        } else if (l) {
            if (n == cap) {
                cap = cap ? 2 * cap : 1024;
                rs_track_located *q = realloc(dets, cap * sizeof *q);
                if (!q) {
                    st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory (%zu detections)", path, n);
                    break;
                }
                dets = q;
            }
            st = parse_row(&dets[n], p, path, line, err);
            if (st == RS_OK) n++;
        }
        p = next;
    }
    if (st == RS_OK && line == 0) st = rs_err_set(err, RS_ERR_PARSE, "%s: empty file (no header)", path);
    free(text);
    if (st) {
        free(dets);
        return st;
    }
    *out = dets;
    *N = n;
    return RS_OK;
}

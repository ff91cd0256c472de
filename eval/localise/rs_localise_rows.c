// rs_localise_rows.c -- the located-detections file: written as CSV, JSON lines or GeoJSON, and
// the CSV read back (rs_localise.h, rs_localise_write, rs_localise_read).
#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_io.h"
#include "core/rs_text.h"
#include "eval/localise/rs_localise.h"

enum { NCOLS = 16 };
static const char *const cols[NCOLS] = {"image_id", "camera",    "frame",     "time_s",   "category_id", "score",
                                        "u_px",     "v_px",      "e_m",       "n_m",      "u_m",         "lat_deg",
                                        "lon_deg",  "sigma_e_m", "sigma_n_m", "cov_en_m2"};

// The numbers of a row in column order from u_px on (10 of them).
static void row_numbers(const rs_localise_row *r, double x[10])
{
    const double v[10] = {r->u_px,    r->v_px,    r->e_m,       r->n_m,       r->u_m,
                          r->lat_deg, r->lon_deg, r->sigma_e_m, r->sigma_n_m, r->cov_en_m2};
    memcpy(x, v, sizeof v);
}

// A number with 15 significant digits (1e-12 m within 1 km), "" for NaN.
static void num(FILE *f, double x)
{
    if (isfinite(x)) fprintf(f, "%.15g", x);
}

static void write_csv_row(FILE *f, const rs_localise_row *r)
{
    fprintf(f, "%lld,", r->image_id);
    if (strpbrk(r->camera, ",\"\n\r")) {
        fputc('"', f);
        for (const char *c = r->camera; *c; c++) {
            if (*c == '"') fputc('"', f);
            fputc(*c, f);
        }
        fputc('"', f);
    } else
        fputs(r->camera, f);
    fprintf(f, ",%lld,", r->frame);
    num(f, r->time_s);
    fprintf(f, ",%lld,", r->category_id);
    num(f, r->score);
    double x[10];
    row_numbers(r, x);
    for (int k = 0; k < 10; k++) {
        fputc(',', f);
        num(f, x[k]);
    }
    fputc('\n', f);
}

// The row as a JSON object (unknown numbers null); NULL when out of memory.
static cJSON *row_object(const rs_localise_row *r)
{
    cJSON *o = cJSON_CreateObject();
    if (!o) return NULL;
    cJSON_AddNumberToObject(o, "image_id", (double)r->image_id);
    cJSON_AddStringToObject(o, "camera", r->camera);
    cJSON_AddNumberToObject(o, "frame", (double)r->frame);
    cJSON_AddItemToObject(o, "time_s", isfinite(r->time_s) ? cJSON_CreateNumber(r->time_s) : cJSON_CreateNull());
    cJSON_AddNumberToObject(o, "category_id", (double)r->category_id);
    cJSON_AddNumberToObject(o, "score", r->score);
    double x[10];
    row_numbers(r, x);
    for (int k = 0; k < 10; k++)
        cJSON_AddItemToObject(o, cols[6 + k], isfinite(x[k]) ? cJSON_CreateNumber(x[k]) : cJSON_CreateNull());
    return o;
}

static bool print_json(FILE *f, const cJSON *o)
{
    char *s = cJSON_PrintUnformatted(o);
    if (!s) return false;
    fputs(s, f);
    free(s);
    return true;
}

rs_status rs_localise_write(const char *path, const rs_localise_row *rows, size_t N, rs_err *err)
{
    enum { CSV, JSONL, GEOJSON } kind;
    if (rs_io_has_extension(path, "csv"))
        kind = CSV;
    else if (rs_io_has_extension(path, "jsonl"))
        kind = JSONL;
    else if (rs_io_has_extension(path, "geojson"))
        kind = GEOJSON;
    else
        return rs_err_set(err, RS_ERR_USAGE, "%s: the output's extension must be .csv, .jsonl or .geojson", path);
    rs_io_atomic a;
    rs_status st = rs_io_atomic_open(&a, path, err);
    if (st) return st;
    bool ok = true;
    if (kind == CSV) fputs(RS_LOCALISE_CSV_HEADER "\n", a.f);
    if (kind == GEOJSON) fputs("{\"type\": \"FeatureCollection\", \"features\": [", a.f);
    for (size_t i = 0; i < N && ok; i++) {
        if (kind == CSV) {
            write_csv_row(a.f, &rows[i]);
            continue;
        }
        cJSON *o = row_object(&rows[i]);
        if (kind == JSONL) {
            ok = o && print_json(a.f, o);
            fputc('\n', a.f);
        } else {
            cJSON *feature = cJSON_CreateObject(), *geometry = NULL;
            if (isfinite(rows[i].lat_deg) && isfinite(rows[i].lon_deg)) {
                geometry = cJSON_CreateObject();
                const double lonlat[2] = {rows[i].lon_deg, rows[i].lat_deg};
                if (geometry) {
                    cJSON_AddStringToObject(geometry, "type", "Point");
                    cJSON_AddItemToObject(geometry, "coordinates", cJSON_CreateDoubleArray(lonlat, 2));
                }
            }
            ok = feature && o;
            if (ok) {
                cJSON_AddStringToObject(feature, "type", "Feature");
                cJSON_AddItemToObject(feature, "geometry", geometry ? geometry : cJSON_CreateNull());
                cJSON_AddItemToObject(feature, "properties", o);
                o = NULL;
                fputs(i ? ",\n" : "\n", a.f);
                ok = print_json(a.f, feature);
            } else
                cJSON_Delete(geometry);
            cJSON_Delete(feature);
        }
        cJSON_Delete(o);
    }
    if (kind == GEOJSON) fputs("\n]}\n", a.f);
    if (!ok) {
        rs_io_atomic_abort(&a);
        return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
    }
    return rs_io_atomic_commit(&a, err);
}

// ---- reading the CSV back ----

// Cuts the next CSV field off *p (quotes "" inside a quoted field); NULL at the end of the line.
static char *next_field(char **p)
{
    char *s = *p;
    if (!s) return NULL;
    if (*s == '"') {
        char *w = s, *r = s + 1;
        for (;;) {
            if (!*r) break;
            if (*r == '"' && r[1] == '"') {
                *w++ = '"';
                r += 2;
            } else if (*r == '"') {
                r++;
                break;
            } else
                *w++ = *r++;
        }
        *w = '\0';
        *p = *r == ',' ? r + 1 : NULL;
        return s;
    }
    char *c = strchr(s, ',');
    if (c) *c = '\0';
    *p = c ? c + 1 : NULL;
    return s;
}

static bool parse_number(const char *s, double *x, bool empty_nan)
{
    if (!*s) {
        *x = NAN;
        return empty_nan;
    }
    if (!rs_text_is_decimal(s)) return false; // (strtod would take 0x10, inf, nan)
    char *end;
    errno = 0;
    *x = strtod(s, &end);
    return *end == '\0' && errno != ERANGE && isfinite(*x);
}

static bool parse_int(const char *s, long long *x)
{
    if (!rs_text_is_decimal(s) || strpbrk(s, ".eE")) return false;
    char *end;
    errno = 0;
    *x = strtoll(s, &end, 10);
    return *s && *end == '\0' && errno == 0;
}

static rs_status read_row(rs_localise_row *r, char *line, const char *path, int lineno, rs_err *err)
{
    char *p = line, *f[NCOLS];
    for (int k = 0; k < NCOLS; k++)
        if (!(f[k] = next_field(&p)))
            return rs_err_set(err, RS_ERR_PARSE, "%s:%d: %s: missing (%d fields, the header has %d)", path, lineno,
                              cols[k], k, NCOLS);
    if (p) {
        int n = NCOLS;
        while (next_field(&p)) n++;
        return rs_err_set(err, RS_ERR_PARSE, "%s:%d: %d fields, the header has %d", path, lineno, n, NCOLS);
    }
    *r = (rs_localise_row){.line = lineno};
    if (strlen(f[1]) >= sizeof r->camera)
        return rs_err_set(err, RS_ERR_PARSE, "%s:%d: camera: longer than %d bytes", path, lineno,
                          RS_LOCALISE_ID_MAX - 1);
    strcpy(r->camera, f[1]);
    long long *ints[3] = {&r->image_id, &r->frame, &r->category_id};
    const int int_col[3] = {0, 2, 4};
    for (int k = 0; k < 3; k++)
        if (int_col[k] == 2 && !*f[2]) // an empty frame: unknown
            r->frame = -1;
        else if (!parse_int(f[int_col[k]], ints[k]))
            return rs_err_set(err, RS_ERR_PARSE, "%s:%d: %s: '%s' is not a whole number", path, lineno,
                              cols[int_col[k]], f[int_col[k]]);
    double *dbl[12] = {&r->time_s, &r->score,   &r->u_px,    &r->v_px,      &r->e_m,       &r->n_m,
                       &r->u_m,    &r->lat_deg, &r->lon_deg, &r->sigma_e_m, &r->sigma_n_m, &r->cov_en_m2};
    const int dbl_col[12] = {3, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15};
    for (int k = 0; k < 12; k++) {
        const int c = dbl_col[k];
        const bool may_be_empty = c == 3 || c == 6 || c == 7 || c == 10 || c == 11 || c == 12;
        if (!parse_number(f[c], dbl[k], may_be_empty))
            return rs_err_set(err, RS_ERR_PARSE, "%s:%d: %s: '%s' is not a finite number", path, lineno, cols[c], f[c]);
    }
    return RS_OK;
}

rs_status rs_localise_read(rs_localise_row **rows, size_t *N, const char *path, rs_err *err)
{
    *rows = NULL;
    *N = 0;
    char *text = NULL;
    size_t len_text = 0;
    rs_status st = rs_io_read_file(&text, &len_text, path, err);
    if (st) return st;
    if (strlen(text) != len_text) {
        free(text);
        return rs_err_set(err, RS_ERR_PARSE, "%s: holds a NUL byte: not a CSV text file", path);
    }
    rs_localise_row *out = NULL;
    size_t n = 0, cap = 0;
    int lineno = 0;
    char *start = text;
    if (!strncmp(start, "\xEF\xBB\xBF", 3)) start += 3; // a UTF-8 byte-order mark
    for (char *p = start, *next; p && *p && !st; p = next) {
        lineno++;
        next = strchr(p, '\n');
        if (next) *next++ = '\0';
        size_t len = strlen(p);
        if (len && p[len - 1] == '\r') p[--len] = '\0';
        if (lineno == 1) {
            if (strcmp(p, RS_LOCALISE_CSV_HEADER) != 0)
                st = rs_err_set(err, RS_ERR_PARSE, "%s:1: header: expected \"%s\"", path, RS_LOCALISE_CSV_HEADER);
            continue;
        }
        if (!len) continue;
        if (n == cap) {
            cap = cap ? 2 * cap : 256;
            rs_localise_row *q = realloc(out, cap * sizeof *q);
            if (!q) {
                st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
                break;
            }
            out = q;
        }
        if (!(st = read_row(&out[n], p, path, lineno, err))) n++;
    }
    if (!st && lineno == 0) st = rs_err_set(err, RS_ERR_PARSE, "%s:1: header: missing (an empty file)", path);
    free(text);
    if (st) {
        free(out);
        return st;
    }
    *rows = out;
    *N = n;
    return RS_OK;
}

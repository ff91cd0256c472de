// rs_site_import_read.c -- the one reader of `site import`'s point files: point-pair JSON and
// CSVs of lat,lon,u,v / e,n,u,v (geo/internal/rs_site_import_points.h). The CSV's fields and
// numbers follow the observations CSV's rules (rs_site__split_csv; lines and numbers: core/rs_text.h).
#include <cjson/cJSON.h>
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/rs_io.h"
#include "core/rs_json.h"
#include "core/rs_text.h"
#include "geo/internal/rs_site_import_points.h"
#include "geo/internal/rs_site_internal.h"

enum { MIN_POINTS = 4, MAXFIELDS = 32 };

void rs_site__import_points_free(rs_site__import_points *pts)
{
    if (!pts) return;
    for (int i = 0; i < pts->N; i++) free(pts->points[i].id);
    free(pts->points);
    memset(pts, 0, sizeof *pts);
}

// Appends p (its id copied) after checking the id; errors name the file and line.
static rs_status add_point(rs_site__import_points *pts, rs_site__import_point p, const char *id, const char *path,
                           const char *id_field, rs_err *err)
{
    const char *bad = rs_io_name_problem(id);
    if (bad) return rs_err_set(err, RS_ERR_INVALID, "%s:%d: %s: '%.64s' %s", path, p.line, id_field, id, bad);
    for (int i = 0; i < pts->N; i++)
        if (!strcmp(pts->points[i].id, id))
            return rs_err_set(err, RS_ERR_INVALID, "%s:%d: %s: '%s' repeated (first at line %d)", path, p.line,
                              id_field, id, pts->points[i].line);
    rs_site__import_point *grown = realloc(pts->points, ((size_t)pts->N + 1) * sizeof *grown);
    if (!grown) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    pts->points = grown;
    if (!(p.id = strdup(id))) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    pts->points[pts->N++] = p;
    pts->any_h = pts->any_h || isfinite(p.h_m);
    return RS_OK;
}

// The checks every point gets, whichever file it came from.
static rs_status check_point(const rs_site__import_point *p, bool geographic, const char *path, rs_err *err)
{
    if (geographic && !(fabs(p->y) <= 90))
        return rs_err_set(err, RS_ERR_INVALID, "%s:%d: lat: %.17g is outside [-90, 90]", path, p->line, p->y);
    if (geographic && !(fabs(p->x) <= 180))
        return rs_err_set(err, RS_ERR_INVALID, "%s:%d: lon: %.17g is outside [-180, 180]", path, p->line, p->x);
    if (isfinite(p->h_m) && !(p->h_m >= RS_SITE_HEIGHT_MIN_M && p->h_m <= RS_SITE_HEIGHT_MAX_M))
        return rs_err_set(err, RS_ERR_INVALID, "%s:%d: h: %g m is not near the Earth's surface ([-1000, 10000] m)",
                          path, p->line, p->h_m);
    if (isfinite(p->sigma_px) &&
        !(p->sigma_px >= RS_SITE_PIXEL_SIGMA_MIN_PX && p->sigma_px <= RS_SITE_PIXEL_SIGMA_MAX_PX))
        return rs_err_set(err, RS_ERR_INVALID, "%s:%d: sigma_px: %g is outside [0.01, 1000] px", path, p->line,
                          p->sigma_px);
    return RS_OK;
}

static rs_status no_nul(const char *text, size_t len, const char *path, rs_err *err)
{
    const char *nul = memchr(text, '\0', len);
    return nul ? rs_err_set(err, RS_ERR_PARSE, "%s:%d: a NUL byte: not a text file", path,
                            rs_json_line(text, (size_t)(nul - text)))
               : RS_OK;
}

// ---- point-pair JSON ----

typedef struct {
    rs_site__import_points *pts;
    const char *path, *text;
    size_t results[2]; // the span of "results"; results[1] == 0: none
} json_reader;

static rs_status json_top(void *ctx, const char *key, size_t begin, size_t end, rs_err *err)
{
    json_reader *r = ctx;
    (void)err;
    if (!strcmp(key, "results")) r->results[0] = begin, r->results[1] = end;
    return RS_OK;
}

// results[index].key as a finite number into *v; `optional` members may be absent (*v NAN).
static rs_status json_number(double *v, const cJSON *item, const char *key, bool optional, size_t index, int line,
                             const char *path, rs_err *err)
{
    const cJSON *it = cJSON_GetObjectItemCaseSensitive(item, key);
    *v = NAN;
    if (!it && optional) return RS_OK;
    if (!it) return rs_err_set(err, RS_ERR_PARSE, "%s:%d: results[%zu].%s: missing", path, line, index, key);
    if (!cJSON_IsNumber(it))
        return rs_err_set(err, RS_ERR_PARSE, "%s:%d: results[%zu].%s: not a number", path, line, index, key);
    if (!isfinite(it->valuedouble))
        return rs_err_set(err, RS_ERR_INVALID, "%s:%d: results[%zu].%s: not finite", path, line, index, key);
    *v = it->valuedouble;
    return RS_OK;
}

static rs_status json_item(void *ctx, size_t index, const cJSON *item, size_t offset, rs_err *err)
{
    json_reader *r = ctx;
    const int line = rs_json_line(r->text, offset);
    if (!cJSON_IsObject(item))
        return rs_err_set(err, RS_ERR_PARSE,
                          "%s:%d: results[%zu]: not an object {\"x\", \"y\", \"lat\", \"lng\", \"id\"}", r->path, line,
                          index);
    rs_site__import_point p = {.line = line, .sigma_px = NAN};
    const char *lon_key = cJSON_GetObjectItemCaseSensitive(item, "lon") ? "lon" : "lng";
    rs_status st = json_number(&p.q_px[0], item, "x", false, index, line, r->path, err);
    if (!st) st = json_number(&p.q_px[1], item, "y", false, index, line, r->path, err);
    if (!st) st = json_number(&p.y, item, "lat", false, index, line, r->path, err);
    if (!st) st = json_number(&p.x, item, lon_key, false, index, line, r->path, err);
    if (!st) st = json_number(&p.h_m, item, "h", true, index, line, r->path, err);
    if (!st) st = check_point(&p, true, r->path, err);
    if (st) return st;
    char id[64], field[48];
    const cJSON *jid = cJSON_GetObjectItemCaseSensitive(item, "id");
    snprintf(field, sizeof field, "results[%zu].id", index);
    if (cJSON_IsString(jid)) return add_point(r->pts, p, jid->valuestring, r->path, field, err);
    if (jid && !(cJSON_IsNumber(jid) && jid->valuedouble == floor(jid->valuedouble) && fabs(jid->valuedouble) < 1e15))
        return rs_err_set(err, RS_ERR_PARSE, "%s:%d: %s: not a text or a whole number", r->path, line, field);
    snprintf(id, sizeof id, jid ? "%.0f" : "P%.0f", jid ? jid->valuedouble : (double)index + 1);
    return add_point(r->pts, p, id, r->path, field, err);
}

static rs_status read_json(rs_site__import_points *pts, const char *text, size_t len, const char *path, rs_err *err)
{
    json_reader r = {.pts = pts, .path = path, .text = text};
    pts->geographic = true;
    rs_status st = rs_json_object(text, 0, len, path, json_top, &r, err);
    if (st) return st;
    if (!r.results[1])
        return rs_err_set(err, RS_ERR_PARSE, "%s: results: missing (a point-pair file is {\"results\": [...]})", path);
    return rs_json_array(text, r.results[0], r.results[1], path, json_item, &r, err);
}

// ---- CSV ----

enum { C_LAT, C_LON, C_E, C_N, C_U, C_V, C_H, C_ID, C_SIGMA, NCOLS };
// Each column's accepted names, '|'-separated, the first one the column's name in messages.
static const char *const column_names[NCOLS] = {
    "lat|latitude", "lon|lng|longitude", "e|east|easting", "n|north|northing", "u", "v",
    "h|height",     "id|landmark",       "sigma_px"};

static int column_of(const char *name)
{
    for (int c = 0; c < NCOLS; c++)
        for (const char *p = column_names[c]; *p;) {
            const size_t n = strcspn(p, "|");
            if (strlen(name) == n && !strncasecmp(name, p, n)) return c;
            p += n + (p[n] == '|');
        }
    return -1;
}

static rs_status csv_header(int col[NCOLS], bool *geographic, char **f, int n, int line, const char *path, rs_err *err)
{
    for (int c = 0; c < NCOLS; c++) col[c] = -1;
    for (int i = 0; i < n && i < MAXFIELDS; i++) {
        const int c = column_of(f[i]);
        if (c < 0)
            return rs_err_set(err, RS_ERR_PARSE,
                              "%s:%d: header: unknown column '%.40s' (lat,lon,u,v or e,n,u,v; optional h, id, "
                              "sigma_px)",
                              path, line, f[i]);
        if (col[c] >= 0) return rs_err_set(err, RS_ERR_PARSE, "%s:%d: header: column '%s' twice", path, line, f[i]);
        col[c] = i;
    }
    *geographic = col[C_LAT] >= 0 || col[C_LON] >= 0;
    const bool projected = col[C_E] >= 0 || col[C_N] >= 0;
    const char *missing = *geographic && projected ? "lat,lon or e,n, not both"
                          : *geographic            ? (col[C_LAT] < 0   ? "lat"
                                                      : col[C_LON] < 0 ? "lon"
                                                                       : NULL)
                          : projected              ? (col[C_E] < 0   ? "e"
                                                      : col[C_N] < 0 ? "n"
                                                                     : NULL)
                                                   : "lat,lon or e,n";
    if (!missing) missing = col[C_U] < 0 ? "u" : col[C_V] < 0 ? "v" : NULL;
    return missing ? rs_err_set(err, RS_ERR_PARSE,
                                "%s:%d: header: %s missing (the first line names the columns: lat,lon,u,v[,h] or "
                                "e,n,u,v[,h])",
                                path, line, missing)
                   : RS_OK;
}

// Column c of a row as a number into *v (NAN when the column is absent or, for optional ones, empty).
static rs_status csv_number(double *v, char **f, const int col[NCOLS], int c, int line, const char *path, rs_err *err)
{
    *v = NAN;
    if (col[c] < 0) return RS_OK;
    const char *t = f[col[c]], *name = column_names[c];
    const int nlen = (int)strcspn(name, "|");
    if (!*t && (c == C_H || c == C_SIGMA || c == C_ID)) return RS_OK;
    char why[RS_TEXT_WHY_BYTES];
    if (!rs_text_parse_double(v, why, t))
        return rs_err_set(err, strncmp(why, "not finite", 10) ? RS_ERR_PARSE : RS_ERR_INVALID, "%s:%d: %.*s: %s", path,
                          line, nlen, name, why);
    return RS_OK;
}

static rs_status csv_row(rs_site__import_points *pts, char **f, const int col[NCOLS], int row, int line,
                         const char *path, rs_err *err)
{
    rs_site__import_point p = {.line = line};
    const int cx = pts->geographic ? C_LON : C_E, cy = pts->geographic ? C_LAT : C_N;
    rs_status st = csv_number(&p.x, f, col, cx, line, path, err);
    if (!st) st = csv_number(&p.y, f, col, cy, line, path, err);
    if (!st) st = csv_number(&p.q_px[0], f, col, C_U, line, path, err);
    if (!st) st = csv_number(&p.q_px[1], f, col, C_V, line, path, err);
    if (!st) st = csv_number(&p.h_m, f, col, C_H, line, path, err);
    if (!st) st = csv_number(&p.sigma_px, f, col, C_SIGMA, line, path, err);
    if (!st) st = check_point(&p, pts->geographic, path, err);
    if (st) return st;
    char id[32];
    snprintf(id, sizeof id, "P%d", row);
    return add_point(pts, p, col[C_ID] >= 0 && *f[col[C_ID]] ? f[col[C_ID]] : id, path, "id", err);
}

static rs_status read_csv(rs_site__import_points *pts, char *text, size_t len, const char *path, rs_err *err)
{
    rs_text_lines lines;
    rs_text_lines_init(&lines, text, len, RS_TEXT_MAX_LINE_BYTES);
    int nheader = 0, row = 0, col[NCOLS];
    rs_status st = RS_OK;
    char *s;
    while (st == RS_OK && (st = rs_text_next_line(&s, &lines, path, err)) == RS_OK && s) {
        const int line = lines.line;
        while (isspace((unsigned char)*s)) s++;
        if (!*s || *s == '#') continue;
        char *f[MAXFIELDS];
        const int n = rs_site__split_csv(s, f, MAXFIELDS);
        if (n < 0 || n > MAXFIELDS)
            st =
                rs_err_set(err, RS_ERR_PARSE, "%s:%d: malformed quoting or more than %d fields", path, line, MAXFIELDS);
        else if (!nheader)
            st = csv_header(col, &pts->geographic, f, nheader = n, line, path, err);
        else if (n != nheader)
            st = rs_err_set(err, RS_ERR_PARSE, "%s:%d: %d field%s, the header has %d%s", path, line, n,
                            n == 1 ? "" : "s", nheader, n > nheader ? " (a decimal comma? write 12.5, not 12,5)" : "");
        else
            st = csv_row(pts, f, col, ++row, line, path, err);
    }
    if (st == RS_OK && !nheader)
        st = rs_err_set(err, RS_ERR_PARSE, "%s: header: the file is empty (the first line names the columns)", path);
    return st;
}

rs_status rs_site__import_read(rs_site__import_points *pts, const char *path, rs_err *err)
{
    memset(pts, 0, sizeof *pts);
    char *text = NULL;
    size_t len = 0;
    rs_status st = rs_io_read_file_max(&text, &len, path, RS_IO_MAX_SMALL_FILE_BYTES, err);
    if (st == RS_OK) st = no_nul(text, len, path, err);
    if (st == RS_OK)
        st = rs_io_has_extension(path, "json") ? read_json(pts, text, len, path, err)
                                               : read_csv(pts, text, len, path, err);
    if (st == RS_OK && pts->N < MIN_POINTS)
        st = rs_err_set(err, RS_ERR_INVALID, "%s: %d point%s: a camera needs at least %d", path, pts->N,
                        pts->N == 1 ? "" : "s", MIN_POINTS);
    free(text);
    return st;
}

rs_status rs_site_import_read_points(rs_site_import_points *pts, const char *path, rs_err *err)
{
    return rs_site__import_read(pts, path, err);
}

void rs_site_import_points_free(rs_site_import_points *pts) { rs_site__import_points_free(pts); }

// rs_track_write.c -- the tracks as CSV, GeoJSON and SDSM-style JSON lines (rs_track_io.h).
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "core/rs_io.h"
#include "eval/track/rs_track_io.h"

// The geodetic points (Nrows, 3) of the tracker's rows; NULL with err set on failure.
static double *rows_llh(const rs_track_tracker *t, const rs_llh *origin, rs_err *err)
{
    size_t N;
    const rs_track_row *rows = rs_track_tracker_rows(t, &N);
    double *enu = malloc(sizeof(double) * (3 * N + 3)), *llh = malloc(sizeof(double) * (3 * N + 3));
    if (!enu || !llh) {
        free(enu), free(llh);
        rs_err_set(err, RS_ERR_NOMEM, "out of memory (%zu rows)", N);
        return NULL;
    }
    for (size_t k = 0; k < N; k++) enu[3 * k] = rows[k].e_m, enu[3 * k + 1] = rows[k].n_m, enu[3 * k + 2] = rows[k].u_m;
    rs_status st = RS_OK;
    for (size_t k = 0; k < N && st == RS_OK; k += 1 << 20) {
        const size_t n = N - k < ((size_t)1 << 20) ? N - k : (size_t)1 << 20;
        st = rs_geo_enu_to_llh(llh + 3 * k, origin, enu + 3 * k, (int)n, err);
    }
    free(enu);
    if (st) {
        free(llh);
        return NULL;
    }
    return llh;
}

// The row's cameras joined by '+' into buf, in the byte order of their ids.
static void cameras_text(char *buf, size_t n, const rs_track_tracker *t, uint64_t mask)
{
    const char *by_rank[RS_TRACK_MAX_CAMERAS] = {NULL};
    for (int k = 0; k < RS_TRACK_MAX_CAMERAS; k++)
        if (mask >> k & 1) by_rank[rs_track_tracker_camera_rank(t, k)] = rs_track_tracker_camera(t, k, NULL);
    size_t used = 0;
    buf[0] = '\0';
    for (int r = 0; r < RS_TRACK_MAX_CAMERAS && used < n; r++)
        if (by_rank[r]) used += (size_t)snprintf(buf + used, n - used, "%s%s", used ? "+" : "", by_rank[r]);
}

// Writes s as a JSON string (cJSON's escaping); false when out of memory.
static bool json_string(FILE *f, const char *s)
{
    cJSON *item = cJSON_CreateString(s);
    char *text = item ? cJSON_PrintUnformatted(item) : NULL;
    if (text) fputs(text, f);
    cJSON_free(text);
    cJSON_Delete(item);
    return text != NULL;
}

// Writes the file's text into f; false when out of memory (the output is then abandoned).
typedef bool (*writer)(FILE *f, const rs_track_tracker *t, const double *llh);

// Opens path, calls w, commits; abandons the output on a write error or when w fails.

static rs_status write_with(const char *path, const rs_track_tracker *t, const rs_llh *origin, writer w, rs_err *err)
{
    double *llh = rows_llh(t, origin, err);
    if (!llh) return err ? err->status : RS_ERR_NOMEM;
    rs_io_atomic a;
    rs_status st = rs_io_atomic_open(&a, path, err);
    if (st == RS_OK) {
        const bool ok = w(a.f, t, llh);
        st = rs_io_atomic_finish(&a, ok ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path), err);
    }
    free(llh);
    return st;
}

enum { CAMERAS_TEXT = RS_TRACK_MAX_CAMERAS * RS_TRACK_CAMERA_BYTES + 1 };

static bool csv_rows(FILE *f, const rs_track_tracker *t, const double *llh)
{
    size_t N;
    const rs_track_row *rows = rs_track_tracker_rows(t, &N);
    char *cams = malloc(CAMERAS_TEXT);
    if (!cams) return false;
    fprintf(f, "%s\n", RS_TRACK_TRACKS_HEADER);
    for (size_t k = 0; k < N; k++) {
        const rs_track_row *r = &rows[k];
        cameras_text(cams, CAMERAS_TEXT, t, r->camera_mask);
        fprintf(f, "%.9g,%d,%.9f,%.9f,%.10f,%.10f,%.6f,%.6f,%.9f,%.9f,%.12g,%.6f,%.6f,%.6f,%d,%s\n", r->time_s,
                r->track_id, r->e_m, r->n_m, llh[3 * k], llh[3 * k + 1], r->speed_mps, r->heading_deg, r->sigma_e_m,
                r->sigma_n_m, r->cov_en_m2, r->sigma_speed_mps, r->sigma_heading_deg, r->age_s, r->detections, cams);
    }
    free(cams);
    return true;
}

rs_status rs_track_write_csv(const char *path, const rs_track_tracker *t, const rs_llh *origin, rs_err *err)
{
    return write_with(path, t, origin, csv_rows, err);
}

static int cmp_track_time(const void *a, const void *b)
{
    const rs_track_row *x = *(const rs_track_row *const *)a, *y = *(const rs_track_row *const *)b;
    if (x->track_id != y->track_id) return x->track_id < y->track_id ? -1 : 1;
    if (x->time_s != y->time_s) return x->time_s < y->time_s ? -1 : 1;
    return (x > y) - (x < y);
}

// One property array of the feature's vertices rows[a..b): the double at byte offset `off`.
static void prop_array(FILE *f, const char *name, const rs_track_row *const *v, size_t a, size_t b, size_t off,
                       const char *fmt)
{
    fprintf(f, ",\"%s\":[", name);
    for (size_t k = a; k < b; k++) {
        const double x = *(const double *)((const char *)v[k] + off);
        if (k > a) fputc(',', f);
        fprintf(f, fmt, x);
    }
    fputc(']', f);
}

static bool geojson_features(FILE *f, const rs_track_tracker *t, const double *llh)
{
    size_t N;
    const rs_track_row *rows = rs_track_tracker_rows(t, &N);
    const rs_track_row **v = malloc(sizeof(*v) * (N + 1));
    char *cams = malloc(CAMERAS_TEXT);
    if (!v || !cams) {
        free(v), free(cams);
        return false;
    }
    fputs("{\"type\":\"FeatureCollection\",\"features\":[", f);
    for (size_t k = 0; k < N; k++) v[k] = &rows[k];
    qsort(v, N, sizeof *v, cmp_track_time);
    for (size_t a = 0, nf = 0; a < N; nf++) {
        size_t b = a;
        while (b < N && v[b]->track_id == v[a]->track_id) b++;
        const bool line = b - a >= 2; // a LineString needs two positions (RFC 7946 3.1.4)
        fprintf(f, "%s\n{\"type\":\"Feature\",\"id\":%d,\"geometry\":{\"type\":\"%s\",\"coordinates\":%s",
                nf ? "," : "", v[a]->track_id, line ? "LineString" : "Point", line ? "[" : "");
        for (size_t k = a; k < b; k++) {
            const size_t r = (size_t)(v[k] - rows);
            fprintf(f, "%s[%.10f,%.10f,%.3f]", k > a ? "," : "", llh[3 * r + 1], llh[3 * r], llh[3 * r + 2]);
        }
        fprintf(f, "%s},\"properties\":{\"track_id\":%d,\"category_id\":%d", line ? "]" : "", v[a]->track_id,
                v[b - 1]->category_id);
        prop_array(f, "time_s", v, a, b, offsetof(rs_track_row, time_s), "%.9g");
        prop_array(f, "e_m", v, a, b, offsetof(rs_track_row, e_m), "%.4f");
        prop_array(f, "n_m", v, a, b, offsetof(rs_track_row, n_m), "%.4f");
        prop_array(f, "speed_mps", v, a, b, offsetof(rs_track_row, speed_mps), "%.4f");
        prop_array(f, "heading_deg", v, a, b, offsetof(rs_track_row, heading_deg), "%.4f");
        prop_array(f, "sigma_e_m", v, a, b, offsetof(rs_track_row, sigma_e_m), "%.5f");
        prop_array(f, "sigma_n_m", v, a, b, offsetof(rs_track_row, sigma_n_m), "%.5f");
        prop_array(f, "cov_en_m2", v, a, b, offsetof(rs_track_row, cov_en_m2), "%.6g");
        prop_array(f, "sigma_speed_mps", v, a, b, offsetof(rs_track_row, sigma_speed_mps), "%.4f");
        prop_array(f, "sigma_heading_deg", v, a, b, offsetof(rs_track_row, sigma_heading_deg), "%.4f");
        prop_array(f, "age_s", v, a, b, offsetof(rs_track_row, age_s), "%.6g");
        fputs(",\"detections\":[", f);
        for (size_t k = a; k < b; k++) fprintf(f, "%s%d", k > a ? "," : "", v[k]->detections);
        fputs("],\"cameras\":[", f);
        for (size_t k = a; k < b; k++) {
            cameras_text(cams, CAMERAS_TEXT, t, v[k]->camera_mask);
            if (k > a) fputc(',', f);
            if (!json_string(f, cams)) {
                free(v), free(cams);
                return false;
            }
        }
        fputs("]}}", f);
        a = b;
    }
    fputs("\n]}\n", f);
    free(v), free(cams);
    return true;
}

rs_status rs_track_write_geojson(const char *path, const rs_track_tracker *t, const rs_llh *origin, rs_err *err)
{
    return write_with(path, t, origin, geojson_features, err);
}

// The J2735/J3224 confidence class of a 95 % value v: the code of the finest class whose bound
// (bounds (Nbounds,), coarsest first, codes 1, 2, ...) still covers v; 0 (unavailable) when even
// the coarsest does not, or v is not finite.
static int confidence_class(double v, const double *bounds, int Nbounds)
{
    if (!(v <= bounds[0])) return 0;
    int code = 1;
    for (int k = 1; k < Nbounds && bounds[k] >= v; k++) code = k + 1;
    return code;
}

// A J3224 integer field: x / unit rounded, clamped to [lo, hi].
static long coded(double x, double unit, long lo, long hi)
{
    const double q = round(x / unit);
    return q < lo ? lo : q > hi ? hi : (long)q;
}

static bool sdsm_lines(FILE *f, const rs_track_tracker *t, const double *llh)
{
    // PositionConfidence a500m .. a1cm; SpeedConfidence prec100ms .. prec0-01ms; HeadingConfidence
    // prec10deg .. prec0-01deg (J2735 DE_PositionConfidence, DE_SpeedConfidence, DE_HeadingConfidence)
    static const double pos_bounds_m[] = {500, 200, 100, 50, 20, 10, 5, 2, 1, 0.5, 0.2, 0.1, 0.05, 0.02, 0.01};
    static const double speed_bounds_mps[] = {100, 10, 5, 1, 0.1, 0.05, 0.01};
    static const double heading_bounds_deg[] = {10, 5, 1, 0.1, 0.05, 0.01};
    const double r95_2d = 2.4477468306808166; // sqrt of the chi-square 2-dof 95 % point, 5.991
    const double z95 = 1.959963984540054;
    size_t N;
    const rs_track_row *rows = rs_track_tracker_rows(t, &N);
    char *cams = malloc(CAMERAS_TEXT);
    if (!cams) return false;
    for (size_t k = 0; k < N; k++) {
        const rs_track_row *r = &rows[k];
        // the semi-major axis of the position covariance: its larger eigenvalue
        const double a = r->sigma_e_m * r->sigma_e_m, b = r->sigma_n_m * r->sigma_n_m, c = r->cov_en_m2;
        const double major_m = sqrt(0.5 * (a + b) + sqrt(0.25 * (a - b) * (a - b) + c * c));
        cameras_text(cams, CAMERAS_TEXT, t, r->camera_mask);
        fprintf(f,
                "{\"time_s\":%.9g,\"objectID\":%d,\"objType\":1,\"category_id\":%d,\"measurementTime\":0,"
                "\"pos\":{\"offsetX\":%ld,\"offsetY\":%ld},\"posConfidence\":{\"pos\":%d},"
                "\"speed\":%ld,\"speedConfidence\":%d,\"heading\":%ld,\"headingConf\":%d,"
                "\"e_m\":%.4f,\"n_m\":%.4f,\"lat_deg\":%.10f,\"lon_deg\":%.10f,\"speed_mps\":%.4f,\"heading_deg\":%.4f,"
                "\"pos_r95_m\":%.4f,\"speed_r95_mps\":%.4f,\"heading_r95_deg\":%.4f,\"age_s\":%.6g,\"detections\":%d,"
                "\"cameras\":",
                r->time_s, r->track_id % 65536, r->category_id, coded(r->e_m, 0.1, -32767, 32767),
                coded(r->n_m, 0.1, -32767, 32767), confidence_class(r95_2d * major_m, pos_bounds_m, 15),
                coded(r->speed_mps, 0.02, 0, 8190), confidence_class(z95 * r->sigma_speed_mps, speed_bounds_mps, 7),
                coded(r->heading_deg, 0.0125, 0, 28799) % 28800,
                confidence_class(z95 * r->sigma_heading_deg, heading_bounds_deg, 6), r->e_m, r->n_m, llh[3 * k],
                llh[3 * k + 1], r->speed_mps, r->heading_deg, r95_2d * major_m, z95 * r->sigma_speed_mps,
                z95 * r->sigma_heading_deg, r->age_s, r->detections);
        if (!json_string(f, cams)) {
            free(cams);
            return false;
        }
        fputs("}\n", f);
    }
    free(cams);
    return true;
}

rs_status rs_track_write_sdsm(const char *path, const rs_track_tracker *t, const rs_llh *origin, rs_err *err)
{
    return write_with(path, t, origin, sdsm_lines, err);
}

// rs_site_read.c -- the one reader of a site folder, behind both rs_site_load and
// rs_site_check (geo/rs_site.h): reads landmarks.geojson here, site.json (with each camera's
// entry and background_images) through rs_site_read_json.c, each camera's model and observations through rs_site_read_camera.c,
// and reports every problem on the way; it only reads and reports. Calls rs_site_read_camera.c,
// rs_site_check.c (positions, the whole site), rs_site_report.c and rs_site.c (rs_site_free);
// nothing calls back into it (the layers: geo/internal/rs_site_internal.h).
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <cjson/cJSON.h>

#include "core/rs_io.h"
#include "core/rs_json.h"
#include "geo/internal/rs_site_internal.h"

enum { DEFAULT_MAX_LANDMARK_DISTANCE_M = 1000 };

// ---- landmarks.geojson ----

// One GeoJSON position [lon, lat, h] (or [lon, lat] where the height does not count) at `field`
// into given = (lat, lon, h). The height of a position whose height does not count (absent, or
// given and ignored) is the origin's until the ground model gives it one. False after reporting.
static bool read_position(rs_site__reader *c, const cJSON *xyz, bool height_counts, const char *field, double given[3])
{
    const rs_site *site = c->site;
    const int n = cJSON_GetArraySize(xyz);
    if (!cJSON_IsArray(xyz) || (n != 2 && n != 3)) {
        ERR(c, RS_ERR_PARSE, field, "expected [lon, lat, h] (3 numbers)%s",
            height_counts ? "" : " or [lon, lat] (the height is unknown)");
        return false;
    }
    if (n == 2 && height_counts) {
        ERR(c, RS_ERR_PARSE, field,
            "the height is missing: expected [lon, lat, h] (a point picked on imagery, without a height, says "
            "so: properties.height \"unknown\", or site.json \"landmark_heights\": \"unknown\")");
        return false;
    }
    double v[3] = {0, 0, site->origin.h_m - site->geoid_undulation_m};
    bool ok = true;
    for (int k = 0; k < n; k++) {
        const cJSON *x = cJSON_GetArrayItem(xyz, k);
        const char *name = k == 0 ? "lon" : k == 1 ? "lat" : "h";
        if (!cJSON_IsNumber(x)) {
            char got[64] = "";
            rs_site__json_excerpt(got, sizeof got, x);
            ERR(c, RS_ERR_PARSE, field, "%s (%s) is not a number", name, got);
        } else if (!isfinite(x->valuedouble)) {
            ERR(c, RS_ERR_INVALID, field, "%s is not finite", name);
        } else {
            v[k] = x->valuedouble;
        }
        ok = ok && cJSON_IsNumber(x) && isfinite(x->valuedouble);
    }
    if (!height_counts) v[2] = site->origin.h_m - site->geoid_undulation_m;
    given[0] = v[1], given[1] = v[0], given[2] = v[2];
    return ok;
}

// The vertices of a landmark as read: n positions, (n,3) each, NaN where unusable.
typedef struct {
    int n;
    double *llh, *enu;
} vertices;

// A LineString's coordinates into *out (allocated; NaN where a vertex is unusable): 2 ..
// RS_SITE_LINE_VERTICES_MAX positions, no zero-length segment. False after reporting when the
// line cannot be used.
static bool read_line(rs_site__reader *c, const cJSON *xyz, bool height_counts, vertices *out)
{
    const rs_site *site = c->site;
    const int n = cJSON_GetArraySize(xyz);
    if (!cJSON_IsArray(xyz)) {
        ERR(c, RS_ERR_PARSE, "coordinates", "expected a list of positions [[lon, lat, h], [lon, lat, h], ...]");
        return false;
    }
    if (n < 2) {
        ERR(c, RS_ERR_INVALID, "coordinates",
            "%d position%s: a line needs at least 2 distinct positions [[lon, lat, h], [lon, lat, h], ...]", n,
            n == 1 ? "" : "s");
        return false;
    }
    if (n > RS_SITE_LINE_VERTICES_MAX) {
        ERR(c, RS_ERR_INVALID, "coordinates", "%d positions, more than %d: split the line into several", n,
            RS_SITE_LINE_VERTICES_MAX);
        return false;
    }
    out->n = n;
    out->llh = malloc((size_t)n * 3 * sizeof *out->llh);
    out->enu = malloc((size_t)n * 3 * sizeof *out->enu);
    if (!out->llh || !out->enu) {
        c->r->nomem = true;
        return false;
    }
    bool ok = true;
    int k = 0, Nzero = 0, first_zero = -1;
    for (const cJSON *x = xyz->child; x; x = x->next, k++) {
        char field[48];
        snprintf(field, sizeof field, "coordinates[%d]", k);
        double given[3], *llh = &out->llh[3 * k], *p = &out->enu[3 * k];
        for (int j = 0; j < 3; j++) llh[j] = p[j] = NAN;
        if (!read_position(c, x, height_counts, field, given) ||
            !rs_site__check_position(llh, p, c->r, site, c->origin_ok, c->file, c->feature, c->fid, field, true,
                                     given)) {
            ok = false;
            continue;
        }
        if (k > 0 && isfinite(p[-3])) {
            const double d = sqrt((p[0] - p[-3]) * (p[0] - p[-3]) + (p[1] - p[-2]) * (p[1] - p[-2]) +
                                  (p[2] - p[-1]) * (p[2] - p[-1]));
            if (!(d >= RS_SITE_COINCIDENT_M)) {
                if (first_zero < 0) first_zero = k;
                Nzero++;
            }
        }
    }
    if (Nzero) {
        char field[48];
        snprintf(field, sizeof field, "coordinates[%d]", first_zero);
        ERR(c, RS_ERR_INVALID, field,
            "at the same position as coordinates[%d] (within %g mm): a zero-length segment; remove the repeated "
            "position%s",
            first_zero - 1, RS_SITE_COINCIDENT_M * 1e3,
            Nzero > 1 ? " (the line has more such segments: every pair of consecutive positions must differ)" : "");
        ok = false;
    }
    return ok;
}

// A pole's height_m and sigma_height_m of properties (geometry a Point); both NAN when absent.
// False after reporting a bad value.
static bool read_pole(rs_site__reader *c, const cJSON *props, double *height_m, double *sigma_m)
{
    *height_m = *sigma_m = NAN;
    if (!props) return true;
    bool ok = true;
    double v;
    if (cJSON_GetObjectItemCaseSensitive(props, "height_m")) {
        if (!rs_site__get_number(c, props, "properties", "height_m", false, &v))
            ok = false;
        else if (!(v > 0 && v <= RS_SITE_POLE_HEIGHT_MAX_M)) {
            ERR(c, RS_ERR_INVALID, "properties.height_m",
                "%g m is outside (0, %g] m: a pole's height, from its base (the point) to its top", v,
                RS_SITE_POLE_HEIGHT_MAX_M);
            ok = false;
        } else
            *height_m = v;
    }
    if (cJSON_GetObjectItemCaseSensitive(props, "sigma_height_m")) {
        if (!rs_site__get_in_range(c, props, "properties", "sigma_height_m", false, RS_SITE_SURVEY_SIGMA_MIN_M,
                                   RS_SITE_SURVEY_SIGMA_MAX_M, "m", RS_SITE__SURVEY_SIGMA_RANGE, &v))
            ok = false;
        else
            *sigma_m = v;
        if (!cJSON_GetObjectItemCaseSensitive(props, "height_m")) {
            ERR(c, RS_ERR_INVALID, "properties.sigma_height_m",
                "given without properties.height_m: it is the 1-sigma of a pole's height");
            ok = false;
        }
    }
    return ok;
}

static void read_feature(rs_site__reader *c, const cJSON *f, int i)
{
    rs_site *site = c->site;
    c->feature = i;
    c->fid = NULL;
    vertices vx = {0};
    if (!cJSON_IsObject(f)) {
        ERR(c, RS_ERR_PARSE, NULL, "not an object (a GeoJSON Feature)");
        goto done;
    }
    const char *type = NULL;
    if (rs_site__get_string(c, f, NULL, "type", true, &type) && strcmp(type, "Feature"))
        ERR(c, RS_ERR_PARSE, "type", "'%s', expected \"Feature\"", type);
    const cJSON *props = rs_site__get_object(c, f, NULL, "properties", true, "{\"id\": \"...\"}");
    const char *id = NULL, *kind = NULL, *note = NULL;
    double sigma_h = site->landmark_sigma_h_m, sigma_v = site->landmark_sigma_v_m, above_ground = 0;
    rs_site_height height_stated = RS_SITE_HEIGHT_DEFAULT;
    bool sigma_h_stated = false, sigma_v_stated = false;
    if (props) {
        const cJSON *jid = cJSON_GetObjectItemCaseSensitive(props, "id");
        if (cJSON_IsNumber(jid))
            ERR(c, RS_ERR_PARSE, "properties.id", "must be a string: write \"%g\"", jid->valuedouble);
        else if (rs_site__get_string(c, props, "properties", "id", true, &id)) {
            c->fid = id;
            const char *bad_id = rs_io_name_problem(id);
            if (bad_id) ERR(c, RS_ERR_INVALID, "properties.id", "'%.80s' %s", id, bad_id);
        }
        rs_site__get_in_range(c, props, "properties", "sigma_h_m", false, RS_SITE_SURVEY_SIGMA_MIN_M,
                              RS_SITE_SURVEY_SIGMA_MAX_M, "m", RS_SITE__SURVEY_SIGMA_RANGE, &sigma_h);
        rs_site__get_in_range(c, props, "properties", "sigma_v_m", false, RS_SITE_SURVEY_SIGMA_MIN_M,
                              RS_SITE_SURVEY_SIGMA_MAX_M, "m", RS_SITE__SURVEY_SIGMA_RANGE, &sigma_v);
        sigma_h_stated = cJSON_GetObjectItemCaseSensitive(props, "sigma_h_m") != NULL;
        sigma_v_stated = cJSON_GetObjectItemCaseSensitive(props, "sigma_v_m") != NULL;
        rs_site__get_string(c, props, "properties", "kind", false, &kind);
        rs_site__get_string(c, props, "properties", "note", false, &note);
        rs_site__read_height_trust(c, props, "properties", "height", &height_stated);
        double v;
        if (cJSON_GetObjectItemCaseSensitive(props, "above_ground_m") &&
            rs_site__get_number(c, props, "properties", "above_ground_m", false, &v)) {
            if (v >= 0 && v <= RS_SITE__ABOVE_GROUND_MAX_M)
                above_ground = v;
            else
                ERR(c, RS_ERR_INVALID, "properties.above_ground_m",
                    "%g m is outside [0, %g] m: how far the point is above the road surface (0: on it)", v,
                    RS_SITE__ABOVE_GROUND_MAX_M);
        }
    }
    const rs_site_height height = height_stated != RS_SITE_HEIGHT_DEFAULT ? height_stated : site->landmark_heights;
    const bool height_counts = height != RS_SITE_HEIGHT_UNKNOWN;
    rs_site__check_duplicate_keys(c, f, NULL); // after the id is known: messages name it

    rs_site_shape shape = RS_SITE_POINT;
    double pole_height = NAN, sigma_pole = NAN;
    bool coords_ok = false;
    const cJSON *geometry =
        rs_site__get_object(c, f, NULL, "geometry", true, "{\"type\": \"Point\", \"coordinates\": [lon, lat, h]}");
    if (geometry) {
        const char *gtype = NULL;
        const cJSON *xyz = cJSON_GetObjectItemCaseSensitive(geometry, "coordinates");
        const bool is_line =
            rs_site__get_string(c, geometry, "geometry", "type", true, &gtype) && !strcmp(gtype, "LineString");
        if (gtype && strcmp(gtype, "Point") && !is_line) {
            ERR(c, RS_ERR_INVALID, "geometry.type",
                "'%s': a landmark is a \"Point\" (a point, or with properties.height_m a pole) or a \"LineString\" "
                "(a line)",
                gtype);
        } else if (!xyz) {
            ERR(c, RS_ERR_PARSE, "coordinates", is_line ? "missing ([[lon, lat, h], ...])" : "missing ([lon, lat, h])");
        } else if (is_line) {
            shape = RS_SITE_LINE;
            if (props && cJSON_GetObjectItemCaseSensitive(props, "height_m"))
                ERR(c, RS_ERR_INVALID, "properties.height_m",
                    "a line has no height_m (only a pole, a Point feature, does): the heights are its coordinates'");
            else if (props && cJSON_GetObjectItemCaseSensitive(props, "sigma_height_m"))
                ERR(c, RS_ERR_INVALID, "properties.sigma_height_m",
                    "a line has no sigma_height_m (only a pole, a Point feature, does)");
            coords_ok = read_line(c, xyz, height_counts, &vx);
        } else {
            if (read_pole(c, props, &pole_height, &sigma_pole) && isfinite(pole_height)) shape = RS_SITE_POLE;
            vx.n = 1;
            vx.llh = malloc(3 * sizeof *vx.llh);
            vx.enu = malloc(3 * sizeof *vx.enu);
            if (!vx.llh || !vx.enu) {
                c->r->nomem = true;
                goto done;
            }
            for (int k = 0; k < 3; k++) vx.llh[k] = vx.enu[k] = NAN;
            double given[3];
            coords_ok = read_position(c, xyz, height_counts, "coordinates", given) &&
                        rs_site__check_position(vx.llh, vx.enu, c->r, site, c->origin_ok, c->file, i, c->fid,
                                                "coordinates", true, given);
        }
    }
    if (!coords_ok) // unusable: NaN everywhere (reported above)
        for (int k = 0; k < 3 * vx.n; k++) vx.llh[k] = vx.enu[k] = NAN;
    if (id) {
        rs_site_landmark *l = &site->landmarks[site->Nlandmarks++];
        *l = (rs_site_landmark){0};
        l->id = rs_site__dup(c, id);
        l->feature = i;
        l->llh = vx.n ? (rs_llh){vx.llh[0], vx.llh[1], vx.llh[2]} : (rs_llh){NAN, NAN, NAN};
        for (int k = 0; k < 3; k++) l->p_enu_m[k] = vx.n ? vx.enu[k] : NAN;
        l->sigma_h_m = sigma_h;
        l->sigma_v_m = sigma_v;
        l->sigma_h_stated = sigma_h_stated;
        l->sigma_v_stated = sigma_v_stated;
        l->kind = rs_site__dup(c, kind);
        l->note = rs_site__dup(c, note);
        l->height_stated = height_stated;
        l->height = height;
        l->above_ground_m = above_ground;
        l->height_modelled = false; // until the ground model gives it a height (rs_site_ground.c)
        l->given_h_m = height_counts ? l->llh.h_m : NAN;
        l->given_up_m = height_counts ? l->p_enu_m[2] : NAN;
        l->given_sigma_v_m = sigma_v;
        l->ground_used = false;
        l->shape = shape;
        l->pole_height_m = shape == RS_SITE_POLE ? pole_height : 0;
        l->sigma_pole_height_m = shape == RS_SITE_POLE ? (isfinite(sigma_pole) ? sigma_pole : sigma_v) : 0;
        // every landmark has its vertices: a point or pole one, (NaN when its geometry is unusable)
        const int n = vx.n ? vx.n : 1;
        l->vertices_enu_m = malloc((size_t)n * 3 * sizeof *l->vertices_enu_m);
        l->vertices_llh = malloc((size_t)n * sizeof *l->vertices_llh);
        l->vertices_sigma_v_m = malloc((size_t)n * sizeof *l->vertices_sigma_v_m);
        l->vertices_given_h_m = malloc((size_t)n * sizeof *l->vertices_given_h_m);
        if (!l->vertices_enu_m || !l->vertices_llh || !l->vertices_sigma_v_m || !l->vertices_given_h_m) {
            c->r->nomem = true;
            goto done;
        }
        l->Nvertices = n;
        for (int k = 0; k < n; k++) {
            for (int j = 0; j < 3; j++) l->vertices_enu_m[3 * k + j] = vx.n ? vx.enu[3 * k + j] : NAN;
            l->vertices_llh[k] =
                vx.n ? (rs_llh){vx.llh[3 * k], vx.llh[3 * k + 1], vx.llh[3 * k + 2]} : (rs_llh){NAN, NAN, NAN};
            l->vertices_sigma_v_m[k] = sigma_v;
            l->vertices_given_h_m[k] = height_counts ? l->vertices_llh[k].h_m : NAN;
        }
    }
done:
    free(vx.llh);
    free(vx.enu);
    c->feature = -1;
    c->fid = NULL;
}
// landmarks.geojson is read one feature at a time (core/rs_json.h): memory is the file's text
// and the landmarks, not a cJSON tree of ~1 kB per feature (1,000,000 landmarks: 1.5 GB that
// way).
typedef struct {
    rs_site__reader *c;
    size_t span[2][2]; // the text of "type" and "features"
    bool has[2];
    char **keys; // every top-level key, for repeats
    int Nkeys, cap;
    int cap_landmarks;
} landmarks_ctx;

static rs_status landmarks_top(void *ctx, const char *key, size_t begin, size_t end, rs_err *err)
{
    landmarks_ctx *t = ctx;
    if (t->Nkeys == t->cap) {
        int cap = t->cap ? 2 * t->cap : 8;
        char **grown = realloc(t->keys, (size_t)cap * sizeof *grown);
        if (!grown) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        t->keys = grown, t->cap = cap;
    }
    if (!(t->keys[t->Nkeys] = strdup(key))) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    t->Nkeys++;
    const int k = !strcmp(key, "type") ? 0 : !strcmp(key, "features") ? 1 : -1;
    if (k >= 0 && !t->has[k]) { // the first, as cJSON would (a repeat is an error anyway)
        t->span[k][0] = begin, t->span[k][1] = end;
        t->has[k] = true;
    }
    return RS_OK;
}

static rs_status landmarks_feature(void *ctx, size_t index, const cJSON *f, size_t offset, rs_err *err)
{
    (void)offset;
    landmarks_ctx *t = ctx;
    rs_site *site = t->c->site;
    if (index >= INT_MAX) return rs_err_set(err, RS_ERR_INVALID, "features: more than %d", INT_MAX - 1);
    if (site->Nlandmarks == t->cap_landmarks) {
        int cap = t->cap_landmarks ? (t->cap_landmarks < INT_MAX / 2 ? 2 * t->cap_landmarks : INT_MAX) : 64;
        rs_site_landmark *grown = realloc(site->landmarks, (size_t)cap * sizeof *grown);
        if (!grown) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        site->landmarks = grown, t->cap_landmarks = cap;
    }
    read_feature(t->c, f, (int)index);
    return t->c->r->nomem ? rs_err_set(err, RS_ERR_NOMEM, "out of memory") : RS_OK;
}

// A syntax error of core/rs_json.h ("PATH:LINE: JSON syntax...") as a diagnostic at its line.
static void json_syntax_error(rs_site__reader *c, const rs_err *e)
{
    if (e->status == RS_ERR_NOMEM) {
        c->r->nomem = true;
        return;
    }
    const char *m = e->msg;
    const size_t n = strlen(c->file);
    int line = 0;
    if (!strncmp(m, c->file, n) && m[n] == ':') {
        char *after;
        long v = strtol(m + n + 1, &after, 10);
        if (*after == ':' && v > 0 && v < INT_MAX) line = (int)v, m = after + 1;
    }
    while (*m == ' ') m++;
    if (!strncmp(m, "JSON syntax: ", 13))
        m += 13;
    else if (!strncmp(m, "JSON syntax error ", 18))
        m += 18;
    ERR_AT(c, e->status, line, NULL, "invalid JSON: %s", m);
}

static void read_landmarks(rs_site__reader *c)
{
    rs_site *site = c->site;
    char *path = rs_site__join(c, site->dir, RS_SITE_LANDMARKS);
    if (!path) return;
    c->file = path;
    size_t len = 0;
    char *text = rs_site__read_file(c, "the surveyed landmarks; 'roadside site init' writes an empty one",
                                    RS_IO_MAX_FILE_BYTES, &len);
    landmarks_ctx t = {.c = c};
    rs_err e = {0};
    cJSON *type = NULL;
    if (!text) goto done;
    size_t i = strncmp(text, "\xEF\xBB\xBF", 3) ? 0 : 3;
    while (i < len && strchr(" \t\r\n", text[i])) i++;
    if (i == len) {
        ERR(c, RS_ERR_PARSE, NULL, "invalid JSON: the file is empty");
        goto done;
    }
    if (text[i] != '{') {
        ERR(c, RS_ERR_PARSE, NULL, "the top level must be a GeoJSON FeatureCollection object");
        goto done;
    }
    if (rs_json_object(text, 0, len, path, landmarks_top, &t, &e) != RS_OK) {
        json_syntax_error(c, &e);
        goto done;
    }
    qsort(t.keys, (size_t)t.Nkeys, sizeof *t.keys, rs_site__cmp_key);
    for (int k = 1; k < t.Nkeys; k++)
        if (!strcmp(t.keys[k], t.keys[k - 1]) && (k == 1 || strcmp(t.keys[k], t.keys[k - 2])))
            ERR(c, RS_ERR_PARSE, t.keys[k],
                "appears more than once at the top level: JSON readers disagree on which one counts; keep one");
    if (!t.has[0]) {
        ERR(c, RS_ERR_PARSE, "type", "missing (a string)");
        goto done;
    }
    if (rs_json_parse(&type, text, t.span[0][0], t.span[0][1], path, &e) != RS_OK) {
        json_syntax_error(c, &e);
        goto done;
    }
    if (!cJSON_IsString(type)) {
        rs_site__wrong_type(c, "type", type, "a string in double quotes");
        goto done;
    }
    if (strcmp(type->valuestring, "FeatureCollection")) {
        ERR(c, RS_ERR_PARSE, "type", "'%s', expected \"FeatureCollection\"", type->valuestring);
        goto done;
    }
    if (!t.has[1] || text[t.span[1][0]] != '[') {
        ERR(c, RS_ERR_PARSE, "features", "%s (a list of Point features)", t.has[1] ? "not a list" : "missing");
        goto done;
    }
    c->landmarks_ok = true;
    if (rs_json_array(text, t.span[1][0], t.span[1][1], path, landmarks_feature, &t, &e) != RS_OK) {
        json_syntax_error(c, &e);
        c->landmarks_ok = false;
        goto done;
    }
    if (site->Nlandmarks == 0) ERR(c, RS_ERR_INVALID, "features", "empty: add one Point feature per surveyed landmark");
    // the picks find their landmarks through these (an id lost to a failed allocation is left out)
    if (site->Nlandmarks > 0 && (rs_index_init_strided(&c->ids, (const char *const *)&site->landmarks[0].id,
                                                       sizeof *site->landmarks, site->Nlandmarks, false, &e) ||
                                 rs_index_init_strided(&c->ids_nocase, (const char *const *)&site->landmarks[0].id,
                                                       sizeof *site->landmarks, site->Nlandmarks, true, &e)))
        c->r->nomem = true, c->landmarks_ok = false;
done:
    cJSON_Delete(type);
    for (int k = 0; k < t.Nkeys; k++) free(t.keys[k]);
    free(t.keys);
    free(text);
    c->file = NULL;
    free(path);
}

// ---- the reader ----

// The one reader behind rs_site_load and rs_site_check: reads every file of the site folder it
// can, fills *site with everything that could be read (landmarks whose position is unusable get
// NaN coordinates) and reports every problem into r. *site is NULL only when out of memory.
static void read_site(rs_site **out, rs_site__report *r, const char *dir)
{
    *out = NULL;
    rs_site *site = calloc(1, sizeof *site);
    if (!site || !(site->dir = strdup(dir))) {
        free(site);
        r->nomem = true;
        return;
    }
    site->max_landmark_distance_m = DEFAULT_MAX_LANDMARK_DISTANCE_M;
    site->ground_normal_enu[2] = 1;
    site->landmark_sigma_h_m = site->landmark_sigma_v_m = NAN;
    site->landmark_heights = RS_SITE_HEIGHT_SURVEYED;
    rs_site__reader c = {.r = r, .site = site, .feature = -1};

    rs_site__read_site_json(&c);
    read_landmarks(&c);
    if (c.origin_ok) rs_site__ground_model(r, site);
    for (int i = 0; i < site->Ncameras; i++) {
        rs_site_camera *cam = &site->cameras[i];
        if (cam->model_path) rs_site__read_camera_model(&c, cam, i);
        if (cam->observations_path) rs_site__read_observations(&c, cam, i);
    }
    rs_site__check_site(r, site);
    rs_index_free(&c.ids);
    rs_index_free(&c.ids_nocase);
    free(c.picked);
    *out = site;
}

// ---- public ----

static rs_status load(rs_site **out, const char *dir, bool picking, rs_err *err)
{
    *out = NULL;
    rs_site__report *r = calloc(1, sizeof *r);
    if (!r) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", dir);
    r->picking = picking;
    rs_site *site = NULL;
    read_site(&site, r, dir);
    rs_status st = RS_OK;
    if (!site || r->nomem) {
        st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory while reading the site", dir);
    } else {
        for (int i = 0; i < r->pub.N && st == RS_OK; i++) {
            const rs_site_diag *d = &r->pub.diags[i];
            if (d->severity != RS_SITE_ERROR) continue;
            char msg[sizeof err->msg];
            rs_site_diag_format(msg, sizeof msg, d);
            st = rs_err_set(err, d->status, "%s", msg);
        }
    }
    rs_site_report_free(&r->pub);
    if (st != RS_OK)
        rs_site_free(site);
    else
        *out = site;
    return st;
}

rs_status rs_site_load(rs_site **out, const char *dir, rs_err *err) { return load(out, dir, false, err); }
rs_status rs_site_load_for_picking(rs_site **out, const char *dir, rs_err *err) { return load(out, dir, true, err); }

rs_status rs_site_check(rs_site_report **report, const char *dir, rs_err *err)
{
    *report = NULL;
    rs_site__report *r = calloc(1, sizeof *r);
    if (!r) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", dir);
    rs_site *site = NULL;
    read_site(&site, r, dir);
    if (site) r->pub.ground = site->ground;
    rs_site_free(site);
    if (!site || r->nomem) {
        rs_site_report_free(&r->pub);
        return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory while checking", dir);
    }
    *report = &r->pub;
    return RS_OK;
}

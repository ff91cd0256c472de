// rs_site.c -- reading a site folder (site.json, landmarks.geojson, camera models, observation
// CSVs) into an rs_site, reporting every problem on the way; rs_site_load, rs_site_free and the
// lookups. The plausibility checks that need more than one value live in rs_site_check.c.
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include <cjson/cJSON.h>

#include "core/rs_io.h"
#include "geo/internal/rs_site_internal.h"

enum { DEFAULT_MAX_LANDMARK_DISTANCE_M = 1000 };
static const double DEFAULT_SIGMA_PX = 1.0;

// The state of one read: where diagnostics go, what is being read (for messages).
typedef struct {
    rs_site__report *r;
    rs_site *site;
    const char *file;   // the file being read
    int feature;        // the GeoJSON feature being read, or -1
    const char *fid;    // its id, may be NULL
    bool origin_ok;     // site.json gave a valid origin and heights: positions can be checked
    bool landmarks_ok;  // landmarks.geojson was read: observations can be matched to landmarks
} reader;

static void say(reader *c, rs_site_severity severity, rs_status status, int line,
                const char *field, const char *fmt, ...) __attribute__((format(printf, 6, 7)));
static void say(reader *c, rs_site_severity severity, rs_status status, int line,
                const char *field, const char *fmt, ...)
{
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    rs_site__diag(c->r, severity, status, c->file, line, c->feature, c->fid, field, "%s", msg);
}
#define ERR(c, status, field, ...) say(c, RS_SITE_ERROR, status, 0, field, __VA_ARGS__)
#define ERR_AT(c, status, line, field, ...) say(c, RS_SITE_ERROR, status, line, field, __VA_ARGS__)
#define WARN(c, field, ...) say(c, RS_SITE_WARNING, RS_OK, 0, field, __VA_ARGS__)
#define WARN_AT(c, line, field, ...) say(c, RS_SITE_WARNING, RS_OK, line, field, __VA_ARGS__)

static char *dup_checked(reader *c, const char *s)
{
    if (!s) return NULL;
    char *d = strdup(s);
    if (!d) c->r->nomem = true;
    return d;
}

static char *join_checked(reader *c, const char *dir, const char *rel)
{
    char *p = rs_io_join(dir, rel);
    if (!p) c->r->nomem = true;
    return p;
}

// ---- files and JSON ----

// Reports a missing file, or a folder, at c->file; `why` says what the file is for. True if
// there is a file.
static bool site_file_exists(reader *c, const char *why)
{
    struct stat sb;
    if (stat(c->file, &sb) != 0) ERR(c, RS_ERR_IO, NULL, "missing file (%s)", why);
    else if (S_ISDIR(sb.st_mode)) ERR(c, RS_ERR_IO, NULL, "is a folder, expected a file (%s)", why);
    else return true;
    return false;
}

// Reads one file of the site (c->file). Returns the malloc'ed, NUL-terminated contents (and
// their length, which may be NULL), or NULL after reporting the problem.
static char *read_site_file(reader *c, const char *why, size_t *len)
{
    if (!site_file_exists(c, why)) return NULL;
    char *text = NULL;
    rs_err e = {0};
    if (rs_io_read_file(&text, len, c->file, &e) != RS_OK) {
        ERR(c, e.status, NULL, "cannot read: %s", e.msg);
        return NULL;
    }
    return text;
}

// Parses JSON text; reports a syntax error with its line and column.
static cJSON *parse_json(reader *c, const char *text)
{
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithOpts(text, &end, 1);
    if (root) return root;
    if (!c->r->nomem && !*text) {
        ERR(c, RS_ERR_PARSE, NULL, "invalid JSON: the file is empty");
        return NULL;
    }
    int line = 1, column = 1;
    for (const char *p = text; end && p < end && *p; p++) {
        if (*p == '\n') line++, column = 1;
        else column++;
    }
    char near[32] = "";
    int n = 0;
    for (const char *p = end; p && *p && n < 20; p++) near[n++] = (*p == '\n' || *p == '\r' || *p == '\t') ? ' ' : *p;
    near[n] = '\0';
    if (n) ERR_AT(c, RS_ERR_PARSE, line, NULL, "invalid JSON at column %d, near '%s'", column, near);
    else ERR_AT(c, RS_ERR_PARSE, line, NULL, "invalid JSON at column %d: unexpected end of file", column);
    return NULL;
}

// Reads and parses the JSON file `name` of the site folder, reporting what is wrong with it.
// c->file is *path (owned by the caller, free() it and reset c->file) until the caller is done.
static cJSON *read_json_file(reader *c, char **path, const char *name, const char *why)
{
    *path = join_checked(c, c->site->dir, name);
    if (!*path) return NULL;
    c->file = *path;
    char *text = read_site_file(c, why, NULL);
    const char *json = text && !strncmp(text, "\xEF\xBB\xBF", 3) ? text + 3 : text; // UTF-8 BOM
    cJSON *root = json ? parse_json(c, json) : NULL;
    free(text);
    return root;
}

// "prefix.key" (or "key") into buf.
static const char *field_name(char *buf, size_t size, const char *prefix, const char *key)
{
    if (prefix) snprintf(buf, size, "%s.%s", prefix, key);
    else snprintf(buf, size, "%s", key);
    return buf;
}

// A short rendering of a JSON value for messages: the value itself, truncated.
static void json_excerpt(char *buf, size_t size, const cJSON *item)
{
    char *s = cJSON_PrintUnformatted(item);
    snprintf(buf, size, "%s", s ? s : "?");
    if (s && strlen(s) >= size && size > 4) strcpy(buf + size - 4, "...");
    cJSON_free(s);
}

// Looks up obj[key], writing its full name ("prefix.key") into field. A missing member is
// reported if required ("missing (EXPECTED)"); returns NULL then.
static const cJSON *member(reader *c, const cJSON *obj, const char *prefix, const char *key,
                           bool required, const char *expected, char *field, size_t size)
{
    field_name(field, size, prefix, key);
    const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!it && required) ERR(c, RS_ERR_PARSE, field, "missing (%s)", expected);
    return it;
}

// Reports a member of the wrong JSON type, quoting what was found.
static void wrong_type(reader *c, const char *field, const cJSON *it, const char *expected)
{
    char got[64];
    json_excerpt(got, sizeof got, it);
    ERR(c, RS_ERR_PARSE, field, "not %s (%s)", expected, got);
}

// Reads obj[key] as a finite number. Reports a missing required field, a wrong type or a
// non-finite value; returns false then (and for a missing optional field).
static bool get_number(reader *c, const cJSON *obj, const char *prefix, const char *key,
                       bool required, double *out)
{
    char field[256];
    const cJSON *it = member(c, obj, prefix, key, required, "a number", field, sizeof field);
    if (!it) return false;
    if (!cJSON_IsNumber(it)) {
        wrong_type(c, field, it, "a number");
        return false;
    }
    if (!isfinite(it->valuedouble)) {
        ERR(c, RS_ERR_INVALID, field, "not a finite number");
        return false;
    }
    *out = it->valuedouble;
    return true;
}

// get_number, and the value must be > 0.
static bool get_positive(reader *c, const cJSON *obj, const char *prefix, const char *key,
                         bool required, double *out)
{
    double v;
    if (!get_number(c, obj, prefix, key, required, &v)) return false;
    if (v <= 0) {
        char field[256];
        ERR(c, RS_ERR_INVALID, field_name(field, sizeof field, prefix, key), "%g must be > 0", v);
        return false;
    }
    *out = v;
    return true;
}

// Reads obj[key] as a non-empty string (pointer into the JSON tree).
static bool get_string(reader *c, const cJSON *obj, const char *prefix, const char *key,
                       bool required, const char **out)
{
    char field[256];
    const cJSON *it = member(c, obj, prefix, key, required, "a string", field, sizeof field);
    if (!it) return false;
    if (!cJSON_IsString(it)) {
        wrong_type(c, field, it, "a string in double quotes");
        return false;
    }
    if (!it->valuestring[0]) {
        ERR(c, RS_ERR_INVALID, field, "empty");
        return false;
    }
    *out = it->valuestring;
    return true;
}

// Reads obj[key] as a JSON object; NULL if missing (reported if required) or not an object.
static const cJSON *get_object(reader *c, const cJSON *obj, const char *prefix, const char *key,
                               bool required, const char *expected)
{
    char field[256];
    const cJSON *it = member(c, obj, prefix, key, required, expected, field, sizeof field);
    if (it && !cJSON_IsObject(it)) {
        ERR(c, RS_ERR_PARSE, field, "not an object (expected %s)", expected);
        return NULL;
    }
    return it;
}

// Warns about members of obj not in `known` (NULL-terminated): most often a misspelt name.
static void warn_unknown_keys(reader *c, const cJSON *obj, const char *prefix,
                              const char *const *known)
{
    for (const cJSON *it = obj ? obj->child : NULL; it; it = it->next) {
        bool found = false;
        for (int i = 0; known[i] && !found; i++) found = it->string && !strcmp(it->string, known[i]);
        if (found) continue;
        char field[256];
        WARN(c, field_name(field, sizeof field, prefix, it->string ? it->string : "?"),
             "unknown field, ignored (misspelt?)");
    }
}

// ---- site.json ----

// Reads {lat, lon, h} (and sigma_m for a prior) of obj into given = (lat, lon, h).
static bool get_llh(reader *c, const cJSON *obj, const char *prefix, double given[3])
{
    bool ok = get_number(c, obj, prefix, "lat", true, &given[0]);
    ok = get_number(c, obj, prefix, "lon", true, &given[1]) && ok;
    ok = get_number(c, obj, prefix, "h", true, &given[2]) && ok;
    return ok;
}

static void read_heights(reader *c, const cJSON *root, bool *ok)
{
    const cJSON *it = cJSON_GetObjectItemCaseSensitive(root, "heights");
    const char *expected = "\"ellipsoidal\" or {\"orthometric\": N}, N = geoid undulation in metres";
    if (!it) {
        ERR(c, RS_ERR_PARSE, "heights", "missing (%s)", expected);
        *ok = false;
    } else if (cJSON_IsString(it) && !strcmp(it->valuestring, "ellipsoidal")) {
        c->site->heights_orthometric = false;
        c->site->geoid_undulation_m = 0;
    } else if (cJSON_IsObject(it) && cJSON_GetObjectItemCaseSensitive(it, "orthometric")) {
        static const char *const known[] = {"orthometric", NULL};
        warn_unknown_keys(c, it, "heights", known);
        c->site->heights_orthometric = true;
        if (!get_number(c, it, "heights", "orthometric", true, &c->site->geoid_undulation_m)) *ok = false;
        else if (fabs(c->site->geoid_undulation_m) > 120) {
            ERR(c, RS_ERR_INVALID, "heights.orthometric",
                "%g m is not a geoid undulation (|N| < 110 m on Earth)", c->site->geoid_undulation_m);
            *ok = false;
        }
    } else {
        char got[64];
        json_excerpt(got, sizeof got, it);
        ERR(c, RS_ERR_INVALID, "heights", "%s: expected %s", got, expected);
        *ok = false;
    }
}

static void read_ground_plane(reader *c, const cJSON *root)
{
    const cJSON *g = get_object(c, root, NULL, "ground_plane", false, "{\"normal_enu\": [0, 0, 1], \"offset_m\": 0}");
    if (!g) return;
    static const char *const known[] = {"normal_enu", "offset_m", NULL};
    warn_unknown_keys(c, g, "ground_plane", known);
    const cJSON *n = cJSON_GetObjectItemCaseSensitive(g, "normal_enu");
    double v[3], offset = 0;
    bool ok = cJSON_IsArray(n) && cJSON_GetArraySize(n) == 3;
    for (int k = 0; ok && k < 3; k++) {
        const cJSON *x = cJSON_GetArrayItem(n, k);
        ok = cJSON_IsNumber(x) && isfinite(x->valuedouble);
        if (ok) v[k] = x->valuedouble;
    }
    double norm = ok ? sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) : 0;
    if (!ok || !(norm > 0)) {
        ERR(c, n ? RS_ERR_INVALID : RS_ERR_PARSE, "ground_plane.normal_enu",
            "%s: expected 3 finite numbers, not all zero (e.g. [0, 0, 1])", n ? "invalid" : "missing");
        return;
    }
    if (cJSON_GetObjectItemCaseSensitive(g, "offset_m") &&
        !get_number(c, g, "ground_plane", "offset_m", false, &offset))
        return;
    for (int k = 0; k < 3; k++) c->site->ground_normal_enu[k] = v[k] / norm;
    c->site->ground_offset_m = offset / norm;
}

static void read_camera_entry(reader *c, const cJSON *item, int i)
{
    rs_site *site = c->site;
    rs_site_camera *cam = &site->cameras[site->Ncameras++];
    char prefix[64], field[128];
    snprintf(prefix, sizeof prefix, "cameras[%d]", i);
    if (!cJSON_IsObject(item)) {
        ERR(c, RS_ERR_PARSE, prefix, "not an object ({\"id\": ..., \"model\": ..., \"observations\": ...})");
        cam->id = dup_checked(c, prefix);
        return;
    }
    static const char *const known[] = {"id", "model", "observations", "backgrounds",
                                        "background_images", "position_prior", "note", NULL};
    warn_unknown_keys(c, item, prefix, known);
    const char *s;
    cam->id = dup_checked(c, get_string(c, item, prefix, "id", true, &s) ? s : prefix);
    if (get_string(c, item, prefix, "model", true, &s)) cam->model_path = join_checked(c, site->dir, s);
    if (get_string(c, item, prefix, "observations", true, &s))
        cam->observations_path = join_checked(c, site->dir, s);
    if (get_string(c, item, prefix, "backgrounds", false, &s)) {
        cam->backgrounds_path = join_checked(c, site->dir, s);
        struct stat sb;
        if (cam->backgrounds_path && (stat(cam->backgrounds_path, &sb) != 0 || !S_ISDIR(sb.st_mode)))
            WARN(c, field_name(field, sizeof field, prefix, "backgrounds"), "'%s' is not a folder",
                 cam->backgrounds_path);
    }
    if (get_string(c, item, prefix, "note", false, &s)) cam->note = dup_checked(c, s);

    field_name(field, sizeof field, prefix, "position_prior");
    const cJSON *prior = get_object(c, item, prefix, "position_prior", false, "{lat, lon, h, sigma_m}");
    if (prior) {
        static const char *const known_prior[] = {"lat", "lon", "h", "sigma_m", NULL};
        warn_unknown_keys(c, prior, field, known_prior);
        double given[3], llh[3];
        bool ok = get_llh(c, prior, field, given);
        ok = get_positive(c, prior, field, "sigma_m", true, &cam->prior_sigma_m) && ok;
        if (ok && rs_site__check_position(llh, cam->prior_p_enu_m, c->r, site, c->origin_ok, c->file,
                                          -1, NULL, field, false, given)) {
            cam->has_position_prior = true;
            cam->prior_llh = (rs_llh){llh[0], llh[1], llh[2]};
        }
    }
}

static void read_site_json(reader *c)
{
    rs_site *site = c->site;
    char *path = NULL;
    cJSON *root = read_json_file(c, &path, "site.json", "every site has one; 'roadside site init' writes a skeleton");
    if (!root) goto done;
    if (!cJSON_IsObject(root)) {
        ERR(c, RS_ERR_PARSE, NULL, "the top level must be an object {\"name\": ..., \"origin\": ...}");
        goto done;
    }
    // "simulated": how `roadside site simulate` made the site (free-form, for people and tools)
    static const char *const known[] = {"name", "origin", "heights", "landmark_sigma_m",
                                        "ground_plane", "max_landmark_distance_m", "cameras",
                                        "simulated", NULL};
    warn_unknown_keys(c, root, NULL, known);

    const char *name;
    if (get_string(c, root, NULL, "name", true, &name)) site->name = dup_checked(c, name);

    bool origin_ok = true;
    double given[3] = {NAN, NAN, NAN};
    const cJSON *origin = get_object(c, root, NULL, "origin", true, "{\"lat\": deg, \"lon\": deg, \"h\": m}");
    if (origin) {
        static const char *const known_origin[] = {"lat", "lon", "h", NULL};
        warn_unknown_keys(c, origin, "origin", known_origin);
        origin_ok = get_llh(c, origin, "origin", given);
        if (origin_ok && !(given[0] >= -90 && given[0] <= 90)) {
            ERR(c, RS_ERR_INVALID, "origin.lat", "%.9g is out of range [-90, 90]", given[0]);
            origin_ok = false;
        }
        if (origin_ok && !(given[1] >= -180 && given[1] <= 180)) {
            ERR(c, RS_ERR_INVALID, "origin.lon", "%.9g is out of range [-180, 180]", given[1]);
            origin_ok = false;
        }
    } else {
        origin_ok = false;
    }
    read_heights(c, root, &origin_ok);
    site->origin = (rs_llh){given[0], given[1], given[2] + site->geoid_undulation_m};
    c->origin_ok = origin_ok;

    const char *sigma_form = "{\"horizontal\": m, \"vertical\": m}";
    const cJSON *sigma = get_object(c, root, NULL, "landmark_sigma_m", true, sigma_form);
    if (sigma) {
        static const char *const known_sigma[] = {"horizontal", "vertical", NULL};
        warn_unknown_keys(c, sigma, "landmark_sigma_m", known_sigma);
        get_positive(c, sigma, "landmark_sigma_m", "horizontal", true, &site->landmark_sigma_h_m);
        get_positive(c, sigma, "landmark_sigma_m", "vertical", true, &site->landmark_sigma_v_m);
    }
    read_ground_plane(c, root);
    get_positive(c, root, NULL, "max_landmark_distance_m", false, &site->max_landmark_distance_m);

    const cJSON *cameras = cJSON_GetObjectItemCaseSensitive(root, "cameras");
    if (!cameras) {
        ERR(c, RS_ERR_PARSE, "cameras", "missing (a list of cameras)");
    } else if (!cJSON_IsArray(cameras)) {
        ERR(c, RS_ERR_PARSE, "cameras", "not a list [...]");
    } else if (cJSON_GetArraySize(cameras) == 0) {
        ERR(c, RS_ERR_INVALID, "cameras", "empty: a site needs at least one camera");
    } else {
        site->cameras = calloc((size_t)cJSON_GetArraySize(cameras), sizeof *site->cameras);
        if (!site->cameras) c->r->nomem = true;
        int i = 0;
        for (const cJSON *it = cameras->child; it && site->cameras; it = it->next) read_camera_entry(c, it, i++);
    }
done:
    cJSON_Delete(root);
    c->file = NULL;
    free(path);
}

// ---- landmarks.geojson ----

static void read_feature(reader *c, const cJSON *f, int i)
{
    rs_site *site = c->site;
    c->feature = i;
    c->fid = NULL;
    if (!cJSON_IsObject(f)) {
        ERR(c, RS_ERR_PARSE, NULL, "not an object (a GeoJSON Feature)");
        goto done;
    }
    const char *type = NULL;
    if (get_string(c, f, NULL, "type", true, &type) && strcmp(type, "Feature"))
        ERR(c, RS_ERR_PARSE, "type", "'%s', expected \"Feature\"", type);
    const cJSON *props = get_object(c, f, NULL, "properties", true, "{\"id\": \"...\"}");
    const char *id = NULL, *kind = NULL, *note = NULL;
    double sigma_h = site->landmark_sigma_h_m, sigma_v = site->landmark_sigma_v_m;
    if (props) {
        const cJSON *jid = cJSON_GetObjectItemCaseSensitive(props, "id");
        if (cJSON_IsNumber(jid)) ERR(c, RS_ERR_PARSE, "properties.id", "must be a string: write \"%g\"", jid->valuedouble);
        else if (get_string(c, props, "properties", "id", true, &id)) c->fid = id;
        get_positive(c, props, "properties", "sigma_h_m", false, &sigma_h);
        get_positive(c, props, "properties", "sigma_v_m", false, &sigma_v);
        get_string(c, props, "properties", "kind", false, &kind);
        get_string(c, props, "properties", "note", false, &note);
    }

    double given[3], llh[3] = {NAN, NAN, NAN}, p_enu[3] = {NAN, NAN, NAN};
    bool coords_ok = false;
    const cJSON *geometry = get_object(c, f, NULL, "geometry", true, "{\"type\": \"Point\", \"coordinates\": [lon, lat, h]}");
    if (geometry) {
        const char *gtype;
        const cJSON *xyz = cJSON_GetObjectItemCaseSensitive(geometry, "coordinates");
        int n = cJSON_GetArraySize(xyz);
        if (get_string(c, geometry, "geometry", "type", true, &gtype) && strcmp(gtype, "Point")) {
            ERR(c, RS_ERR_INVALID, "geometry.type", "'%s': a landmark is a \"Point\"", gtype);
        } else if (!xyz) {
            ERR(c, RS_ERR_PARSE, "coordinates", "missing ([lon, lat, h])");
        } else if (!cJSON_IsArray(xyz) || (n != 2 && n != 3)) {
            ERR(c, RS_ERR_PARSE, "coordinates", "expected [lon, lat, h] (3 numbers)");
        } else if (n == 2) {
            ERR(c, RS_ERR_PARSE, "coordinates", "the height is missing: expected [lon, lat, h]");
        } else {
            double v[3];
            coords_ok = true;
            for (int k = 0; k < 3; k++) {
                const cJSON *x = cJSON_GetArrayItem(xyz, k);
                char got[64];
                json_excerpt(got, sizeof got, x);
                if (!cJSON_IsNumber(x)) ERR(c, RS_ERR_PARSE, "coordinates", "%s (%s) is not a number", k == 0 ? "lon" : k == 1 ? "lat" : "h", got);
                else if (!isfinite(x->valuedouble)) ERR(c, RS_ERR_INVALID, "coordinates", "%s is not finite", k == 0 ? "lon" : k == 1 ? "lat" : "h");
                else v[k] = x->valuedouble;
                coords_ok = coords_ok && cJSON_IsNumber(x) && isfinite(x->valuedouble);
            }
            given[0] = v[1], given[1] = v[0], given[2] = v[2];
        }
    }
    if (coords_ok)
        rs_site__check_position(llh, p_enu, c->r, site, c->origin_ok, c->file, i, c->fid,
                                "coordinates", true, given);
    if (id) {
        rs_site_landmark *l = &site->landmarks[site->Nlandmarks++];
        l->id = dup_checked(c, id);
        l->feature = i;
        l->llh = (rs_llh){llh[0], llh[1], llh[2]};
        memcpy(l->p_enu_m, p_enu, sizeof p_enu);
        l->sigma_h_m = sigma_h;
        l->sigma_v_m = sigma_v;
        l->kind = dup_checked(c, kind);
        l->note = dup_checked(c, note);
    }
done:
    c->feature = -1;
    c->fid = NULL;
}

static void read_landmarks(reader *c)
{
    rs_site *site = c->site;
    char *path = NULL;
    cJSON *root = read_json_file(c, &path, "landmarks.geojson",
                                 "the surveyed landmarks; 'roadside site init' writes an empty one");
    if (!root) goto done;
    const char *type;
    const cJSON *features = cJSON_GetObjectItemCaseSensitive(root, "features");
    if (!cJSON_IsObject(root)) {
        ERR(c, RS_ERR_PARSE, NULL, "the top level must be a GeoJSON FeatureCollection object");
    } else if (get_string(c, root, NULL, "type", true, &type) && strcmp(type, "FeatureCollection")) {
        ERR(c, RS_ERR_PARSE, "type", "'%s', expected \"FeatureCollection\"", type);
    } else if (!cJSON_IsArray(features)) {
        ERR(c, RS_ERR_PARSE, "features", "%s (a list of Point features)", features ? "not a list" : "missing");
    } else {
        c->landmarks_ok = true;
        int n = cJSON_GetArraySize(features);
        if (n == 0) ERR(c, RS_ERR_INVALID, "features", "empty: add one Point feature per surveyed landmark");
        site->landmarks = calloc((size_t)(n ? n : 1), sizeof *site->landmarks);
        if (!site->landmarks) c->r->nomem = true;
        int i = 0;
        for (const cJSON *f = features->child; f && site->landmarks; f = f->next) read_feature(c, f, i++);
    }
done:
    cJSON_Delete(root);
    c->file = NULL;
    free(path);
}

// ---- camera models ----

static bool has_extension(const char *path, const char *ext)
{
    const char *dot = strrchr(path, '.');
    return dot && !strchr(dot, '/') && !strcasecmp(dot + 1, ext);
}

// mrcal 2.2's .cameramodel reader reads past the end of its buffer when a quoted string is not
// closed (found by tests/site/test_site_fuzz.py under AddressSanitizer), so such files are refused
// before mrcal sees them; everything else is left to mrcal. Returns NULL if the text may be
// handed to mrcal, else what is wrong (and *line where).
static const char *cameramodel_precheck(const char *text, size_t len, int *line)
{
    *line = 0;
    if (len == 0) return "the file is empty";
    if (strlen(text) != len) return "the file contains a NUL byte";
    char quote = 0;
    int quote_line = 0, l = 1;
    bool comment = false;
    for (const char *p = text; *p; p++) {
        if (*p == '\n') l++;
        if (comment) comment = *p != '\n';
        else if (quote) quote = *p == quote ? 0 : quote;
        else if (*p == '\'' || *p == '"') quote = *p, quote_line = l;
        else if (*p == '#') comment = true;
    }
    if (!quote) return NULL;
    *line = quote_line;
    return "a quoted string that is never closed";
}

// Reports a failed core camera read as a diagnostic: its message is "PATH: FIELD: what", and
// the diagnostic names the file already.
static void camera_error(reader *c, const rs_site_camera *cam, const rs_err *e)
{
    if (e->status == RS_ERR_NOMEM) c->r->nomem = true;
    size_t n = strlen(cam->model_path);
    const char *what = strncmp(e->msg, cam->model_path, n) ? e->msg : e->msg + n + (e->msg[n] == ':' ? 2 : 0);
    ERR(c, e->status, NULL, "%s", what);
}

static void read_camera_model(reader *c, rs_site_camera *cam, int i)
{
    char why[160];
    snprintf(why, sizeof why, "named by cameras[%d].model in site.json", i);
    c->file = cam->model_path;
    if (!site_file_exists(c, why)) goto done;
    rs_err e = {0};
    if (has_extension(cam->model_path, "yaml") || has_extension(cam->model_path, "yml") ||
        has_extension(cam->model_path, "json")) {
        if (rs_camera_read(&cam->camera, NULL, cam->model_path, &e)) camera_error(c, cam, &e);
        else if (cam->camera.width == 0 || cam->camera.height == 0) {
            ERR(c, RS_ERR_PARSE, cam->camera.width == 0 ? "image_width" : "image_height", "missing");
            rs_camera_free(&cam->camera);
        }
        goto done;
    }
    size_t len = 0;
    char *text = read_site_file(c, why, &len);
    if (!text) goto done;
    int line = 0;
    const char *bad = cameramodel_precheck(text, len, &line);
    if (bad) ERR_AT(c, RS_ERR_PARSE, line, NULL, "not a valid mrcal .cameramodel: %s", bad);
    else if (rs_camera_read_cameramodel_text(&cam->camera, text, len, cam->model_path, &e)) camera_error(c, cam, &e);
    else memset(cam->camera.rt_cam_enu, 0, sizeof cam->camera.rt_cam_enu); // intrinsics only
    free(text);
done:
    c->file = NULL;
}

// ---- observations/<id>.csv ----

// Splits one CSV line in place into fields (RFC 4180 quoting, surrounding blanks trimmed).
// Stores at most maxf fields; returns how many there are, or -1 for malformed quoting.
static int split_csv(char *s, char **fields, int maxf)
{
    int n = 0;
    for (;;) {
        while (*s == ' ' || *s == '\t') s++;
        char *start = s, *out = s;
        if (*s == '"') {
            for (s++;; s++) {
                if (!*s) return -1;
                if (*s == '"' && s[1] == '"') *out++ = *s++;
                else if (*s == '"') break;
                else *out++ = *s;
            }
            s++;
            while (*s == ' ' || *s == '\t') s++;
            if (*s && *s != ',') return -1;
        } else {
            while (*s && *s != ',') s++;
            out = s;
            while (out > start && (out[-1] == ' ' || out[-1] == '\t')) out--;
        }
        char sep = *s;
        *out = '\0';
        if (n < maxf) fields[n] = start;
        n++;
        if (sep != ',') return n;
        s++;
    }
}

static bool parse_csv_number(reader *c, int line, const char *field, const char *text, double *out)
{
    char *end;
    double v = strtod(text, &end);
    if (!*text || *end) {
        ERR_AT(c, RS_ERR_PARSE, line, field, "not a number ('%s')", text);
        return false;
    }
    if (!isfinite(v)) {
        ERR_AT(c, RS_ERR_INVALID, line, field, "not finite ('%s')", text);
        return false;
    }
    *out = v;
    return true;
}

enum { COL_LANDMARK, COL_U, COL_V, COL_SIGMA, NCOLS, MAXFIELDS = 32 };
static const char *const column_names[NCOLS] = {"landmark", "u", "v", "sigma_px"};

// Reads the header line; fills col[] with the index of each known column (-1 if absent).
static bool read_csv_header(reader *c, int line, char **fields, int nfields, int col[NCOLS])
{
    for (int k = 0; k < NCOLS; k++) col[k] = -1;
    for (int f = 0; f < nfields && f < MAXFIELDS; f++) {
        int k = 0;
        while (k < NCOLS && strcmp(fields[f], column_names[k])) k++;
        if (k == NCOLS) WARN_AT(c, line, "header", "unknown column '%s', ignored", fields[f]);
        else if (col[k] >= 0) ERR_AT(c, RS_ERR_PARSE, line, "header", "column '%s' appears twice", fields[f]);
        else col[k] = f;
    }
    for (int k = 0; k < COL_SIGMA; k++)
        if (col[k] < 0) {
            bool other_separator = nfields == 1 && strpbrk(fields[0], ";\t");
            ERR_AT(c, RS_ERR_PARSE, line, "header",
                   "no column '%s': the first line must be the header landmark,u,v (and optionally "
                   ",sigma_px)%s", column_names[k],
                   other_separator ? "; separate the fields with commas, not semicolons or tabs" : "");
            return false;
        }
    return true;
}

// Suggests an id that differs only in case (the commonest mismatch), or NULL.
static const char *similar_landmark(const rs_site *site, const char *id)
{
    for (int i = 0; i < site->Nlandmarks; i++)
        if (!strcasecmp(site->landmarks[i].id, id)) return site->landmarks[i].id;
    return NULL;
}

static void read_observation_row(reader *c, rs_site_camera *cam, int line, char **fields,
                                 const int col[NCOLS])
{
    const char *id = fields[col[COL_LANDMARK]];
    rs_site_observation obs = {.ilandmark = -1, .sigma_px = DEFAULT_SIGMA_PX, .line = line};
    bool ok = true;
    if (!*id) {
        ERR_AT(c, RS_ERR_PARSE, line, "landmark", "empty");
        ok = false;
    }
    ok = parse_csv_number(c, line, "u", fields[col[COL_U]], &obs.q_px[0]) && ok;
    ok = parse_csv_number(c, line, "v", fields[col[COL_V]], &obs.q_px[1]) && ok;
    if (col[COL_SIGMA] >= 0 && *fields[col[COL_SIGMA]]) {
        if (!parse_csv_number(c, line, "sigma_px", fields[col[COL_SIGMA]], &obs.sigma_px)) ok = false;
        else if (obs.sigma_px <= 0) {
            ERR_AT(c, RS_ERR_INVALID, line, "sigma_px", "%g must be > 0", obs.sigma_px);
            ok = false;
        }
    }
    if (!ok || !c->landmarks_ok) return;
    obs.ilandmark = rs_site_find_landmark(c->site, id);
    if (obs.ilandmark < 0) {
        const char *like = similar_landmark(c->site, id);
        ERR_AT(c, RS_ERR_NOT_FOUND, line, "landmark", "'%s' is not a landmark of landmarks.geojson%s%s%s",
               id, like ? " (ids are case-sensitive: '" : "", like ? like : "", like ? "'?)" : "");
        return;
    }
    if (!rs_site__check_observation(c->r, cam, &obs, c->site)) return;
    rs_site_observation *grown = realloc(cam->observations, (size_t)(cam->Nobservations + 1) * sizeof obs);
    if (!grown) {
        c->r->nomem = true;
        return;
    }
    cam->observations = grown;
    cam->observations[cam->Nobservations++] = obs;
}

static void read_observations(reader *c, rs_site_camera *cam, int i)
{
    char why[160];
    snprintf(why, sizeof why, "named by cameras[%d].observations in site.json", i);
    c->file = cam->observations_path;
    char *text = read_site_file(c, why, NULL);
    if (!text) goto done;
    char *p = text;
    if (!strncmp(p, "\xEF\xBB\xBF", 3)) p += 3; // UTF-8 byte order mark
    int line = 0, nheader = 0, col[NCOLS];
    bool have_header = false;
    while (*p) {
        line++;
        char *eol = strchr(p, '\n'), *next = eol ? eol + 1 : p + strlen(p);
        if (eol) *eol = '\0';
        if (eol && eol > p && eol[-1] == '\r') eol[-1] = '\0';
        char *s = p;
        p = next;
        while (isspace((unsigned char)*s)) s++;
        if (!*s || *s == '#') continue; // blank lines and comments
        char *fields[MAXFIELDS];
        int n = split_csv(s, fields, MAXFIELDS);
        if (n < 0) {
            ERR_AT(c, RS_ERR_PARSE, line, NULL, "malformed quoting (a \" that is not closed, or text after it)");
            continue;
        }
        if (!have_header) {
            if (!read_csv_header(c, line, fields, n, col)) goto done;
            have_header = true;
            nheader = n;
            continue;
        }
        if (n != nheader) {
            ERR_AT(c, RS_ERR_PARSE, line, NULL, "%d field%s, the header has %d%s", n, n == 1 ? "" : "s",
                   nheader, n > nheader ? " (a decimal comma? write 12.5, not 12,5)" : "");
            continue;
        }
        read_observation_row(c, cam, line, fields, col);
    }
    if (!have_header)
        ERR(c, RS_ERR_PARSE, "header", "the file is empty: the first line must be the header landmark,u,v");
    else if (c->landmarks_ok)
        rs_site__check_camera(c->r, cam);
done:
    free(text);
    c->file = NULL;
}

// ---- the reader ----

void rs_site__read(rs_site **out, rs_site__report *r, const char *dir)
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
    reader c = {.r = r, .site = site, .feature = -1};

    read_site_json(&c);
    read_landmarks(&c);
    for (int i = 0; i < site->Ncameras; i++) {
        rs_site_camera *cam = &site->cameras[i];
        if (cam->model_path) read_camera_model(&c, cam, i);
        if (cam->observations_path) read_observations(&c, cam, i);
    }
    rs_site__check_site(r, site);
    *out = site;
}

// ---- public ----

rs_status rs_site_load(rs_site **out, const char *dir, rs_err *err)
{
    *out = NULL;
    rs_site__report *r = calloc(1, sizeof *r);
    if (!r) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", dir);
    rs_site *site = NULL;
    rs_site__read(&site, r, dir);
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
    if (st != RS_OK) rs_site_free(site);
    else *out = site;
    return st;
}

void rs_site_free(rs_site *site)
{
    if (!site) return;
    for (int i = 0; i < site->Nlandmarks; i++) {
        free(site->landmarks[i].id);
        free(site->landmarks[i].kind);
        free(site->landmarks[i].note);
    }
    free(site->landmarks);
    for (int i = 0; i < site->Ncameras; i++) {
        rs_site_camera *cam = &site->cameras[i];
        free(cam->id);
        free(cam->model_path);
        free(cam->observations_path);
        free(cam->backgrounds_path);
        free(cam->note);
        rs_camera_free(&cam->camera);
        free(cam->observations);
    }
    free(site->cameras);
    free(site->dir);
    free(site->name);
    free(site);
}

int rs_site_find_camera(const rs_site *site, const char *id)
{
    for (int i = 0; i < site->Ncameras; i++)
        if (site->cameras[i].id && !strcmp(site->cameras[i].id, id)) return i;
    return -1;
}

int rs_site_find_landmark(const rs_site *site, const char *id)
{
    for (int i = 0; i < site->Nlandmarks; i++)
        if (site->landmarks[i].id && !strcmp(site->landmarks[i].id, id)) return i;
    return -1;
}

int rs_site_landmark_extent(double *min_enu_m, double *max_enu_m, double *dmin_m, double *dmax_m,
                            const rs_site *site, int icam)
{
    int n = icam < 0 ? site->Nlandmarks : site->cameras[icam].Nobservations;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double dlo = INFINITY, dhi = -INFINITY;
    for (int i = 0; i < n; i++) {
        int il = icam < 0 ? i : site->cameras[icam].observations[i].ilandmark;
        const double *p = site->landmarks[il].p_enu_m;
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], p[k]);
            hi[k] = fmax(hi[k], p[k]);
        }
        double d = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        dlo = fmin(dlo, d);
        dhi = fmax(dhi, d);
    }
    if (n == 0) return 0;
    if (min_enu_m) memcpy(min_enu_m, lo, sizeof lo);
    if (max_enu_m) memcpy(max_enu_m, hi, sizeof hi);
    if (dmin_m) *dmin_m = dlo;
    if (dmax_m) *dmax_m = dhi;
    return n;
}

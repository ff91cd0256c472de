// rs_site_read.c -- the one reader of a site folder, behind both rs_site_load and
// rs_site_check (geo/rs_site.h): reads site.json (with each camera's background_images) and
// landmarks.geojson here, each camera's model and observations through rs_site_read_camera.c,
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

// ---- site.json ----

// obj[key] ("prefix.key" in messages), if present, as how far heights can be trusted: "surveyed",
// "unreliable" or "unknown" (docs/site-format.md). False (after reporting) when it is not one.
static bool read_height_trust(rs_site__reader *c, const cJSON *obj, const char *prefix, const char *key,
                              rs_site_height *out)
{
    char field[128];
    const cJSON *it = rs_site__member(c, obj, prefix, key, false, "", field, sizeof field);
    if (!it) return true;
    static const char *const expected = "\"surveyed\", \"unreliable\" (given but noisy: raw GNSS) or \"unknown\" "
                                        "(picked on imagery)";
    if (!cJSON_IsString(it)) {
        char got[64];
        rs_site__json_excerpt(got, sizeof got, it);
        ERR(c, RS_ERR_PARSE, field, "%s: expected %s: how far the heights can be trusted%s", got, expected,
            cJSON_IsNumber(it) ? " (a height itself is the third of the coordinates)" : "");
        return false;
    }
    for (rs_site_height h = RS_SITE_HEIGHT_SURVEYED; h <= RS_SITE_HEIGHT_UNKNOWN; h++)
        if (!strcmp(it->valuestring, rs_site_height_name(h))) {
            *out = h;
            return true;
        }
    ERR(c, RS_ERR_INVALID, field, "'%.80s': expected %s", it->valuestring, expected);
    return false;
}

// Reads {lat, lon, h} (and sigma_m for a prior) of obj into given = (lat, lon, h).
static bool get_llh(rs_site__reader *c, const cJSON *obj, const char *prefix, double given[3])
{
    bool ok = rs_site__get_number(c, obj, prefix, "lat", true, &given[0]);
    ok = rs_site__get_number(c, obj, prefix, "lon", true, &given[1]) && ok;
    ok = rs_site__get_number(c, obj, prefix, "h", true, &given[2]) && ok;
    return ok;
}

static void read_heights(rs_site__reader *c, const cJSON *root, bool *ok)
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
        rs_site__warn_unknown_keys(c, it, "heights", known);
        c->site->heights_orthometric = true;
        if (!rs_site__get_number(c, it, "heights", "orthometric", true, &c->site->geoid_undulation_m))
            *ok = false;
        else if (fabs(c->site->geoid_undulation_m) > 120) {
            ERR(c, RS_ERR_INVALID, "heights.orthometric", "%g m is not a geoid undulation (|N| < 110 m on Earth)",
                c->site->geoid_undulation_m);
            *ok = false;
        }
    } else {
        char got[64];
        rs_site__json_excerpt(got, sizeof got, it);
        ERR(c, RS_ERR_INVALID, "heights", "%s: expected %s", got, expected);
        *ok = false;
    }
}

static void read_ground_plane(rs_site__reader *c, const cJSON *root)
{
    const cJSON *g =
        rs_site__get_object(c, root, NULL, "ground_plane", false, "{\"normal_enu\": [0, 0, 1], \"offset_m\": 0}");
    if (!g) return;
    static const char *const known[] = {"normal_enu", "offset_m", NULL};
    rs_site__warn_unknown_keys(c, g, "ground_plane", known);
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
        !rs_site__get_number(c, g, "ground_plane", "offset_m", false, &offset))
        return;
    for (int k = 0; k < 3; k++) c->site->ground_normal_enu[k] = v[k] / norm;
    c->site->ground_offset_m = offset / norm;
    c->site->ground_plane_given = true;
}

// One entry of a camera's "background_images" into *bg (docs/backgrounds.md). False (after
// reporting) when it cannot be used: not an object, no "file", a wrong type.
static bool read_background(rs_site__reader *c, rs_site_background *bg, const cJSON *e, const char *prefix)
{
    if (!cJSON_IsObject(e)) {
        ERR(c, RS_ERR_PARSE, prefix, "not an object ({\"name\": ..., \"file\": ..., \"tags\": {...}})");
        return false;
    }
    static const char *const known[] = {"name", "file", "synthetic", "tags", "source", NULL};
    rs_site__warn_unknown_keys(c, e, prefix, known);
    char field[256];
    const char *file = NULL, *name = NULL;
    bool ok = rs_site__get_string(c, e, prefix, "file", true, &file);
    if (cJSON_GetObjectItemCaseSensitive(e, "name")) ok = rs_site__get_string(c, e, prefix, "name", false, &name) && ok;
    const cJSON *synthetic = rs_site__member(c, e, prefix, "synthetic", false, "", field, sizeof field);
    if (synthetic && !cJSON_IsBool(synthetic)) {
        rs_site__wrong_type(c, field, synthetic, "true or false");
        ok = false;
    }
    rs_site__field_name(field, sizeof field, prefix, "tags");
    const cJSON *tags = rs_site__get_object(c, e, prefix, "tags", false, "{\"time\": ..., \"conditions\": ..., ...}");
    if (!ok || (cJSON_GetObjectItemCaseSensitive(e, "tags") && !tags)) return false;

    bg->name = rs_site__dup(c, name);
    bg->file = rs_site__dup(c, file);
    bg->path = rs_site__join(c, c->site->dir, file);
    if (bg->path && !rs_site__inside(c, bg->path)) {
        ERR(c, RS_ERR_INVALID, rs_site__field_name(field, sizeof field, prefix, "file"),
            "'%.200s' is outside the site folder: a site's files live inside it (links are followed)", file);
        return false;
    }
    bg->synthetic = cJSON_IsTrue(synthetic);
    bg->tags = calloc((size_t)cJSON_GetArraySize(tags) + 1, sizeof *bg->tags);
    if (!bg->tags) c->r->nomem = true;
    for (const cJSON *t = tags ? tags->child : NULL; t && bg->tags; t = t->next) {
        if (!cJSON_IsString(t) && !cJSON_IsBool(t)) {
            char sub[300];
            WARN(c, rs_site__field_name(sub, sizeof sub, field, t->string ? t->string : "?"),
                 "not text or a boolean, ignored");
            continue;
        }
        rs_site_tag *tag = &bg->tags[bg->Ntags++];
        tag->key = rs_site__dup(c, t->string ? t->string : "");
        tag->value = rs_site__dup(c, cJSON_IsString(t) ? t->valuestring : cJSON_IsTrue(t) ? "true" : "false");
    }
    return true;
}

// A camera's "background_images" list, if it has one.
static void read_background_images(rs_site__reader *c, rs_site_camera *cam, const cJSON *item, const char *prefix)
{
    char field[96];
    const cJSON *list = rs_site__member(c, item, prefix, "background_images", false, "", field, sizeof field);
    if (!list) return;
    if (!cJSON_IsArray(list)) {
        rs_site__wrong_type(c, field, list, "a list [...]");
        return;
    }
    cam->background_images = calloc((size_t)cJSON_GetArraySize(list) + 1, sizeof *cam->background_images);
    if (!cam->background_images) {
        c->r->nomem = true;
        return;
    }
    int j = 0;
    for (const cJSON *e = list->child; e; e = e->next, j++) {
        char entry[128];
        snprintf(entry, sizeof entry, "%s[%d]", field, j);
        if (read_background(c, &cam->background_images[cam->Nbackground_images], e, entry)) cam->Nbackground_images++;
    }
}

static void read_camera_entry(rs_site__reader *c, const cJSON *item, int i)
{
    rs_site *site = c->site;
    rs_site_camera *cam = &site->cameras[site->Ncameras++];
    char prefix[64], field[128];
    snprintf(prefix, sizeof prefix, "cameras[%d]", i);
    if (!cJSON_IsObject(item)) {
        ERR(c, RS_ERR_PARSE, prefix, "not an object ({\"id\": ..., \"model\": ..., \"observations\": ...})");
        cam->id = rs_site__dup(c, prefix);
        return;
    }
    static const char *const known[] = {
        "id", "model", "observations", "backgrounds", "background_images", "position_prior", "note", NULL};
    rs_site__warn_unknown_keys(c, item, prefix, known);
    const char *s;
    cam->id = rs_site__dup(c, rs_site__get_string(c, item, prefix, "id", true, &s) ? s : prefix);
    const char *bad_id = s && cam->id && strcmp(cam->id, prefix) ? rs_io_name_problem(cam->id) : NULL;
    if (bad_id)
        ERR(c, RS_ERR_INVALID, rs_site__field_name(field, sizeof field, prefix, "id"),
            "'%.80s' %s: a camera id names its files (<id>.cameramodel, <id>.json, ...); use letters, digits, "
            "'-', '_' or '.'",
            cam->id, bad_id);
    if (rs_site__get_string(c, item, prefix, "model", true, &s)) cam->model_path = rs_site__join(c, site->dir, s);
    if (rs_site__get_string(c, item, prefix, "observations", true, &s))
        cam->observations_path = rs_site__join(c, site->dir, s);
    if (rs_site__get_string(c, item, prefix, "backgrounds", false, &s)) {
        cam->backgrounds_path = rs_site__join(c, site->dir, s);
        struct stat sb;
        if (cam->backgrounds_path && !rs_site__inside(c, cam->backgrounds_path))
            ERR(c, RS_ERR_INVALID, rs_site__field_name(field, sizeof field, prefix, "backgrounds"),
                "'%.200s' is outside the site folder: a site's files live inside it (links are followed)", s);
        else if (cam->backgrounds_path && (stat(cam->backgrounds_path, &sb) != 0 || !S_ISDIR(sb.st_mode)))
            WARN(c, rs_site__field_name(field, sizeof field, prefix, "backgrounds"), "'%s' is not a folder",
                 cam->backgrounds_path);
    }
    if (rs_site__get_string(c, item, prefix, "note", false, &s)) cam->note = rs_site__dup(c, s);
    read_background_images(c, cam, item, prefix);

    rs_site__field_name(field, sizeof field, prefix, "position_prior");
    const cJSON *prior = rs_site__get_object(c, item, prefix, "position_prior", false, "{lat, lon, h, sigma_m}");
    if (prior) {
        static const char *const known_prior[] = {"lat", "lon", "h", "sigma_m", NULL};
        rs_site__warn_unknown_keys(c, prior, field, known_prior);
        double given[3], llh[3];
        bool ok = get_llh(c, prior, field, given);
        ok = rs_site__get_in_range(c, prior, field, "sigma_m", true, RS_SITE_PRIOR_SIGMA_MIN_M,
                                   RS_SITE_PRIOR_SIGMA_MAX_M, "m", "the 1-sigma of a surveyed camera position",
                                   &cam->prior_sigma_m) &&
             ok;
        if (ok && rs_site__check_position(llh, cam->prior_p_enu_m, c->r, site, c->origin_ok, c->file, -1, NULL, field,
                                          false, given)) {
            cam->has_position_prior = true;
            cam->prior_llh = (rs_llh){llh[0], llh[1], llh[2]};
        }
    }
}

static void read_site_json(rs_site__reader *c)
{
    rs_site *site = c->site;
    char *path = NULL;
    cJSON *root =
        rs_site__read_json_file(c, &path, "site.json", "every site has one; 'roadside site init' writes a skeleton",
                                RS_IO_MAX_SMALL_FILE_BYTES);
    if (!root) goto done;
    if (!cJSON_IsObject(root)) {
        ERR(c, RS_ERR_PARSE, NULL, "the top level must be an object {\"name\": ..., \"origin\": ...}");
        goto done;
    }
    rs_site__check_duplicate_keys(c, root, NULL);
    // "simulated": how `roadside site simulate` made the site (free-form, for people and tools)
    static const char *const known[] = {"name",
                                        "origin",
                                        "heights",
                                        "landmark_sigma_m",
                                        "landmark_heights",
                                        "ground_plane",
                                        "max_landmark_distance_m",
                                        "cameras",
                                        "simulated",
                                        NULL};
    rs_site__warn_unknown_keys(c, root, NULL, known);

    const char *name;
    if (rs_site__get_string(c, root, NULL, "name", true, &name)) site->name = rs_site__dup(c, name);

    bool origin_ok = true;
    double given[3] = {NAN, NAN, NAN};
    const cJSON *origin = rs_site__get_object(c, root, NULL, "origin", true, "{\"lat\": deg, \"lon\": deg, \"h\": m}");
    if (origin) {
        static const char *const known_origin[] = {"lat", "lon", "h", NULL};
        rs_site__warn_unknown_keys(c, origin, "origin", known_origin);
        origin_ok = get_llh(c, origin, "origin", given);
        if (origin_ok && !(given[0] >= -90 && given[0] <= 90)) {
            ERR(c, RS_ERR_INVALID, "origin.lat", "%.9g is out of range [-90, 90]", given[0]);
            origin_ok = false;
        }
        if (origin_ok && !(given[1] >= -180 && given[1] <= 180)) {
            ERR(c, RS_ERR_INVALID, "origin.lon", "%.9g is out of range [-180, 180]", given[1]);
            origin_ok = false;
        }
        if (origin_ok && !(given[2] >= RS_SITE_HEIGHT_MIN_M && given[2] <= RS_SITE_HEIGHT_MAX_M)) {
            ERR(c, RS_ERR_INVALID, "origin.h", "%.9g m is not a height near the Earth's surface ([%g, %g] m)", given[2],
                RS_SITE_HEIGHT_MIN_M, RS_SITE_HEIGHT_MAX_M);
            origin_ok = false;
        }
    } else {
        origin_ok = false;
    }
    read_heights(c, root, &origin_ok);
    site->origin = (rs_llh){given[0], given[1], given[2] + site->geoid_undulation_m};
    c->origin_ok = origin_ok;

    const char *sigma_form = "{\"horizontal\": m, \"vertical\": m}";
    const cJSON *sigma = rs_site__get_object(c, root, NULL, "landmark_sigma_m", true, sigma_form);
    if (sigma) {
        static const char *const known_sigma[] = {"horizontal", "vertical", NULL};
        rs_site__warn_unknown_keys(c, sigma, "landmark_sigma_m", known_sigma);
        rs_site__get_in_range(c, sigma, "landmark_sigma_m", "horizontal", true, RS_SITE_SURVEY_SIGMA_MIN_M,
                              RS_SITE_SURVEY_SIGMA_MAX_M, "m", RS_SITE__SURVEY_SIGMA_RANGE, &site->landmark_sigma_h_m);
        rs_site__get_in_range(c, sigma, "landmark_sigma_m", "vertical", true, RS_SITE_SURVEY_SIGMA_MIN_M,
                              RS_SITE_SURVEY_SIGMA_MAX_M, "m", RS_SITE__SURVEY_SIGMA_RANGE, &site->landmark_sigma_v_m);
    }
    read_height_trust(c, root, NULL, "landmark_heights", &site->landmark_heights);
    read_ground_plane(c, root);
    rs_site__get_positive(c, root, NULL, "max_landmark_distance_m", false, &site->max_landmark_distance_m);

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

static void read_feature(rs_site__reader *c, const cJSON *f, int i)
{
    rs_site *site = c->site;
    c->feature = i;
    c->fid = NULL;
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
        rs_site__get_string(c, props, "properties", "kind", false, &kind);
        rs_site__get_string(c, props, "properties", "note", false, &note);
        read_height_trust(c, props, "properties", "height", &height_stated);
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

    double given[3], llh[3] = {NAN, NAN, NAN}, p_enu[3] = {NAN, NAN, NAN};
    bool coords_ok = false;
    const cJSON *geometry =
        rs_site__get_object(c, f, NULL, "geometry", true, "{\"type\": \"Point\", \"coordinates\": [lon, lat, h]}");
    if (geometry) {
        const char *gtype;
        const cJSON *xyz = cJSON_GetObjectItemCaseSensitive(geometry, "coordinates");
        int n = cJSON_GetArraySize(xyz);
        if (rs_site__get_string(c, geometry, "geometry", "type", true, &gtype) && strcmp(gtype, "Point")) {
            ERR(c, RS_ERR_INVALID, "geometry.type", "'%s': a landmark is a \"Point\"", gtype);
        } else if (!xyz) {
            ERR(c, RS_ERR_PARSE, "coordinates", "missing ([lon, lat, h])");
        } else if (!cJSON_IsArray(xyz) || (n != 2 && n != 3)) {
            ERR(c, RS_ERR_PARSE, "coordinates", "expected [lon, lat, h] (3 numbers)%s",
                height_counts ? "" : " or [lon, lat] (the height is unknown)");
        } else if (n == 2 && height_counts) {
            ERR(c, RS_ERR_PARSE, "coordinates",
                "the height is missing: expected [lon, lat, h] (a point picked on imagery, without a height, says "
                "so: properties.height \"unknown\", or site.json \"landmark_heights\": \"unknown\")");
        } else {
            // an unknown height (absent, or given and ignored) is placed at the origin's height
            // until the ground model gives it one
            double v[3] = {0, 0, site->origin.h_m - site->geoid_undulation_m};
            coords_ok = true;
            for (int k = 0; k < n; k++) {
                const cJSON *x = cJSON_GetArrayItem(xyz, k);
                char got[64] = "";
                if (!cJSON_IsNumber(x)) rs_site__json_excerpt(got, sizeof got, x);
                if (!cJSON_IsNumber(x))
                    ERR(c, RS_ERR_PARSE, "coordinates", "%s (%s) is not a number",
                        k == 0   ? "lon"
                        : k == 1 ? "lat"
                                 : "h",
                        got);
                else if (!isfinite(x->valuedouble))
                    ERR(c, RS_ERR_INVALID, "coordinates", "%s is not finite", k == 0 ? "lon" : k == 1 ? "lat" : "h");
                else
                    v[k] = x->valuedouble;
                coords_ok = coords_ok && cJSON_IsNumber(x) && isfinite(x->valuedouble);
            }
            if (!height_counts) v[2] = site->origin.h_m - site->geoid_undulation_m;
            given[0] = v[1], given[1] = v[0], given[2] = v[2];
        }
    }
    if (coords_ok)
        rs_site__check_position(llh, p_enu, c->r, site, c->origin_ok, c->file, i, c->fid, "coordinates", true, given);
    if (id) {
        rs_site_landmark *l = &site->landmarks[site->Nlandmarks++];
        l->id = rs_site__dup(c, id);
        l->feature = i;
        l->llh = (rs_llh){llh[0], llh[1], llh[2]};
        memcpy(l->p_enu_m, p_enu, sizeof p_enu);
        l->sigma_h_m = sigma_h;
        l->sigma_v_m = sigma_v;
        l->kind = rs_site__dup(c, kind);
        l->note = rs_site__dup(c, note);
        l->height_stated = height_stated;
        l->height = height;
        l->above_ground_m = above_ground;
        l->height_modelled = false; // until the ground model gives it a height (rs_site_ground.c)
        l->given_h_m = height_counts ? llh[2] : NAN;
        l->given_up_m = height_counts ? p_enu[2] : NAN;
        l->given_sigma_v_m = sigma_v;
        l->ground_used = false;
    }
done:
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
    char *path = rs_site__join(c, site->dir, "landmarks.geojson");
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

    read_site_json(&c);
    read_landmarks(&c);
    if (c.origin_ok) rs_site__ground_model(r, site);
    for (int i = 0; i < site->Ncameras; i++) {
        rs_site_camera *cam = &site->cameras[i];
        if (cam->model_path) rs_site__read_camera_model(&c, cam, i);
        if (cam->observations_path) rs_site__read_observations(&c, cam, i);
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

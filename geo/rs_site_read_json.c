// rs_site_read_json.c -- site.json: the site's origin, heights, ground plane and its cameras'
// entries (files, prior, stated intrinsics uncertainty, background images), for the one reader
// of a site folder (rs_site_read.c; the layers: geo/internal/rs_site_internal.h).
#include <ctype.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <cjson/cJSON.h>

#include "core/rs_io.h"
#include "core/rs_units.h"
#include "geo/internal/rs_site_internal.h"

// ---- site.json ----

// obj[key] ("prefix.key" in messages), if present, as how far heights can be trusted: "surveyed",
// "unreliable" or "unknown" (docs/site-format.md). False (after reporting) when it is not one.
bool rs_site__read_height_trust(rs_site__reader *c, const cJSON *obj, const char *prefix, const char *key,
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
bool rs_site__get_llh(rs_site__reader *c, const cJSON *obj, const char *prefix, double given[3])
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
    const double tilt_deg = acos(fmin(1.0, fabs(v[2]) / norm)) * RS_DEG_PER_RAD;
    if (!(tilt_deg <= RS_SITE_GROUND_TILT_MAX_DEG)) {
        ERR(c, RS_ERR_INVALID, "ground_plane.normal_enu",
            "[%g, %g, %g] tilts the ground %.1f degrees from level: at most %g (a road; [0, 0, 1] is level)", v[0],
            v[1], v[2], tilt_deg, RS_SITE_GROUND_TILT_MAX_DEG);
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
        "id", "model", "observations", "backgrounds", "background_images", "position_prior", "note", "intrinsics_sigma",
        NULL};
    rs_site__warn_unknown_keys(c, item, prefix, known);
    const char *s;
    cam->id = rs_site__dup(c, rs_site__get_string(c, item, prefix, "id", true, &s) ? s : prefix);
    const char *bad_id = s && cam->id && strcmp(cam->id, prefix) ? rs_io_name_problem(cam->id) : NULL;
    // the documented characters only (docs/site-format.md): a blank, a comma or a quote in a
    // camera id breaks the tools its files go to (SUMO's netconvert, shells)
    for (const unsigned char *p = (const unsigned char *)(bad_id || !s ? "" : cam->id); *p && !bad_id; p++)
        if (!(isalnum(*p) || *p == '-' || *p == '_' || *p == '.' || *p >= 0x80))
            bad_id = "contains a character other than a letter, a digit, '-', '_' or '.'";
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
        bool ok = rs_site__get_llh(c, prior, field, given);
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

    // how well the nominal intrinsics are known: {"focal_rel": 0.1, "center_px": 20}, each optional
    rs_site__field_name(field, sizeof field, prefix, "intrinsics_sigma");
    const cJSON *isig =
        rs_site__get_object(c, item, prefix, "intrinsics_sigma", false, "{\"focal_rel\": 0.1, \"center_px\": 20}");
    if (isig) {
        static const char *const known_isig[] = {"focal_rel", "center_px", NULL};
        rs_site__warn_unknown_keys(c, isig, field, known_isig);
        rs_site__get_in_range(
            c, isig, field, "focal_rel", false, RS_SITE_FOCAL_REL_SIGMA_MIN, RS_SITE_FOCAL_REL_SIGMA_MAX, "(relative)",
            "the 1-sigma of the focal length relative to the nominal (0.1: known to 10%)", &cam->focal_rel_sigma);
        rs_site__get_in_range(c, isig, field, "center_px", false, RS_SITE_CENTER_SIGMA_MIN_PX,
                              RS_SITE_CENTER_SIGMA_MAX_PX, "px", "the 1-sigma of the principal point, pixels",
                              &cam->center_sigma_px);
    }
}

void rs_site__read_site_json(rs_site__reader *c)
{
    rs_site *site = c->site;
    char *path = NULL;
    cJSON *root =
        rs_site__read_json_file(c, &path, RS_SITE_JSON, "every site has one; 'roadside site init' writes a skeleton",
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
        origin_ok = rs_site__get_llh(c, origin, "origin", given);
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
    site->landmark_heights_given = cJSON_GetObjectItemCaseSensitive(root, "landmark_heights") != NULL;
    rs_site__read_height_trust(c, root, NULL, "landmark_heights", &site->landmark_heights);
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

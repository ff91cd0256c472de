// rs_site_write.c -- writing a site's files (geo/rs_site_write.h): site.json from a spec,
// landmarks.geojson, observation CSVs, a background record in site.json; and the two JSON
// layouts every geo writer uses (geo/internal/rs_site_json.h, also for lanes.geojson).
// Calls core/ (rs_io) and cJSON only; called by rs_site_init.c and rs_lanes.c, and by the
// simulator and synth/ through the public header.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "core/rs_io.h"
#include "geo/internal/rs_site_json.h"

// ---- layouts ----

// Text being laid out; nomem once an allocation failed.
typedef struct {
    char *s;
    size_t n, cap;
    bool nomem;
} text;

static void put(text *t, const char *s)
{
    size_t len = strlen(s);
    if (t->nomem) return;
    if (t->n + len + 1 > t->cap) {
        size_t cap = t->cap ? t->cap : 1024;
        while (t->n + len + 1 > cap) cap *= 2;
        char *grown = realloc(t->s, cap);
        if (!grown) {
            t->nomem = true;
            return;
        }
        t->s = grown;
        t->cap = cap;
    }
    memcpy(t->s + t->n, s, len + 1);
    t->n += len;
}

// A value without children (string, number, boolean, null), as cJSON prints it.
static void put_leaf(text *t, const cJSON *item)
{
    char *s = cJSON_PrintUnformatted(item);
    if (!s)
        t->nomem = true;
    else
        put(t, s);
    cJSON_free(s);
}

// `"key": ` with the key escaped as a JSON string.
static void put_key(text *t, const char *key)
{
    cJSON *k = cJSON_CreateString(key ? key : "");
    if (!k)
        t->nomem = true;
    else
        put_leaf(t, k);
    cJSON_Delete(k);
    put(t, ": ");
}

// A value on one line: {"a": 1, "b": [1, 2]}.
static void put_inline(text *t, const cJSON *item)
{
    bool object = cJSON_IsObject(item);
    if (!object && !cJSON_IsArray(item)) {
        put_leaf(t, item);
        return;
    }
    put(t, object ? "{" : "[");
    for (const cJSON *c = item->child; c; c = c->next) {
        if (c != item->child) put(t, ", ");
        if (object) put_key(t, c->string);
        put_inline(t, c);
    }
    put(t, object ? "}" : "]");
}

// A list of objects, one per entry: its first three members on the first line, every further
// member on a line of its own, aligned after the '{'.
static void put_entries(text *t, const cJSON *list)
{
    put(t, "[\n");
    for (const cJSON *e = list->child; e; e = e->next) {
        put(t, "    {");
        int k = 0;
        for (const cJSON *m = e->child; m; m = m->next, k++) {
            if (k > 0) put(t, k < 3 ? ", " : ",\n     ");
            put_key(t, m->string);
            put_inline(t, m);
        }
        put(t, e->next ? "},\n" : "}\n");
    }
    put(t, "  ]");
}

static bool is_list_of_objects(const cJSON *item)
{
    if (!cJSON_IsArray(item) || !item->child) return false;
    for (const cJSON *c = item->child; c; c = c->next)
        if (!cJSON_IsObject(c)) return false;
    return true;
}

// RS_SITE_LAYOUT_HAND (geo/rs_site_write.h).
static void put_hand(text *t, const cJSON *root)
{
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(root, "type");
    if (cJSON_IsString(type) && !strcmp(type->valuestring, "FeatureCollection")) {
        put(t, "{");
        for (const cJSON *m = root->child; m; m = m->next) {
            if (m != root->child) put(t, ", ");
            put_key(t, m->string);
            if (!cJSON_IsArray(m) || strcmp(m->string, "features")) {
                put_inline(t, m);
                continue;
            }
            put(t, "[");
            for (const cJSON *f = m->child; f; f = f->next) {
                put(t, f == m->child ? "\n  " : ",\n  ");
                put_inline(t, f);
            }
            put(t, m->child ? "\n]" : "]");
        }
        put(t, "}");
        return;
    }
    put(t, "{\n");
    for (const cJSON *m = root->child; m; m = m->next) {
        put(t, "  ");
        put_key(t, m->string);
        if (is_list_of_objects(m))
            put_entries(t, m);
        else
            put_inline(t, m);
        put(t, m->next ? ",\n" : "\n");
    }
    put(t, "}");
}

rs_status rs_site__write_json(const char *path, const cJSON *root, rs_site_layout layout, rs_err *err)
{
    text t = {0};
    if (layout == RS_SITE_LAYOUT_HAND) {
        put_hand(&t, root);
    } else {
        char *s = cJSON_Print(root);
        if (!s)
            t.nomem = true;
        else
            put(&t, s);
        cJSON_free(s);
    }
    put(&t, "\n");
    rs_status st =
        t.nomem ? rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path) : rs_io_write_file(path, t.s, t.n, err);
    free(t.s);
    return st;
}

bool rs_site__add_number(cJSON *obj, const char *key, double x)
{
    return isfinite(x) && cJSON_AddNumberToObject(obj, key, x);
}

cJSON *rs_site__numbers(const double *x, int n)
{
    for (int i = 0; i < n; i++)
        if (!isfinite(x[i])) return NULL;
    return cJSON_CreateDoubleArray(x, n);
}

// Adds `value` (taken over, deleted on failure) as obj[key].
static bool add_item(cJSON *obj, const char *key, cJSON *value)
{
    if (value && cJSON_AddItemToObject(obj, key, value)) return true;
    cJSON_Delete(value);
    return false;
}

// {"lat": .., "lon": .., "h": ..}, or NULL.
static cJSON *llh_object(const rs_llh *llh)
{
    cJSON *o = cJSON_CreateObject();
    if (o && rs_site__add_number(o, "lat", llh->lat_deg) && rs_site__add_number(o, "lon", llh->lon_deg) &&
        rs_site__add_number(o, "h", llh->h_m))
        return o;
    cJSON_Delete(o);
    return NULL;
}

// Writes `root` as DIR/name; a NULL root means that building it failed (a non-finite number, or
// out of memory).
static rs_status write_document(const char *dir, const char *name, const cJSON *root, rs_site_layout layout,
                                rs_err *err)
{
    char *path = rs_io_join(dir, name);
    rs_status st;
    if (!path)
        st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", name);
    else if (!root)
        st = rs_err_set(err, RS_ERR_INVALID, "%s: a number is not finite (or out of memory)", path);
    else
        st = rs_site__write_json(path, root, layout, err);
    free(path);
    return st;
}

// ---- site.json ----

static cJSON *camera_object(const rs_site_spec_camera *c)
{
    cJSON *o = cJSON_CreateObject();
    bool ok = o && cJSON_AddStringToObject(o, "id", c->id) && cJSON_AddStringToObject(o, "model", c->model) &&
              cJSON_AddStringToObject(o, "observations", c->observations);
    if (ok && c->backgrounds) ok = cJSON_AddStringToObject(o, "backgrounds", c->backgrounds);
    if (ok && c->position_prior) {
        cJSON *prior = llh_object(c->position_prior);
        ok = add_item(o, "position_prior", prior) && rs_site__add_number(prior, "sigma_m", c->prior_sigma_m);
    }
    if (ok && c->note) ok = cJSON_AddStringToObject(o, "note", c->note);
    if (ok) return o;
    cJSON_Delete(o);
    return NULL;
}

// The site.json document of a spec; NULL for a non-finite number or no memory.
static cJSON *site_document(const rs_site_spec *spec)
{
    cJSON *j = cJSON_CreateObject(), *sigma = NULL, *cams = NULL;
    bool ok = j && cJSON_AddStringToObject(j, "name", spec->name) && add_item(j, "origin", llh_object(&spec->origin));
    if (ok && spec->geoid_undulation_m) {
        cJSON *h = cJSON_CreateObject();
        ok = add_item(j, "heights", h) && rs_site__add_number(h, "orthometric", *spec->geoid_undulation_m);
    } else if (ok) {
        ok = cJSON_AddStringToObject(j, "heights", "ellipsoidal");
    }
    ok = ok && (sigma = cJSON_AddObjectToObject(j, "landmark_sigma_m")) &&
         rs_site__add_number(sigma, "horizontal", spec->landmark_sigma_h_m) &&
         rs_site__add_number(sigma, "vertical", spec->landmark_sigma_v_m);
    if (ok && spec->landmark_heights != RS_SITE_HEIGHT_DEFAULT)
        ok = cJSON_AddStringToObject(j, "landmark_heights", rs_site_height_name(spec->landmark_heights));
    if (ok && spec->ground_normal_enu) {
        cJSON *g = cJSON_AddObjectToObject(j, "ground_plane");
        ok = g && add_item(g, "normal_enu", rs_site__numbers(spec->ground_normal_enu, 3)) &&
             rs_site__add_number(g, "offset_m", spec->ground_offset_m);
    }
    if (ok && spec->max_landmark_distance_m > 0)
        ok = rs_site__add_number(j, "max_landmark_distance_m", spec->max_landmark_distance_m);
    ok = ok && (cams = cJSON_AddArrayToObject(j, "cameras"));
    for (int i = 0; ok && i < spec->Ncameras; i++) {
        cJSON *c = camera_object(&spec->cameras[i]);
        ok = c && cJSON_AddItemToArray(cams, c);
        if (!ok) cJSON_Delete(c);
    }
    if (ok) return j;
    cJSON_Delete(j);
    return NULL;
}

rs_status rs_site_write_json(const char *dir, const rs_site_spec *spec, rs_site_layout layout, rs_err *err)
{
    if (!spec->name) return rs_err_set(err, RS_ERR_INVALID, "%s/site.json: name: missing", dir);
    for (int i = 0; i < spec->Ncameras; i++) {
        const rs_site_spec_camera *c = &spec->cameras[i];
        if (!c->id || !c->model || !c->observations)
            return rs_err_set(err, RS_ERR_INVALID, "%s/site.json: cameras[%d]: %s missing", dir, i,
                              !c->id      ? "id"
                              : !c->model ? "model"
                                          : "observations");
    }
    cJSON *j = site_document(spec);
    rs_status st = RS_OK;
    if (j && spec->extra_name) {
        cJSON *extra = spec->extra_json ? cJSON_Parse(spec->extra_json) : NULL;
        if (!extra)
            st = rs_err_set(err, RS_ERR_PARSE, "%s/site.json: %s: not JSON", dir, spec->extra_name);
        else if (!add_item(j, spec->extra_name, extra))
            st = rs_err_set(err, RS_ERR_NOMEM, "%s/site.json: out of memory", dir);
    }
    if (!st) st = write_document(dir, RS_SITE_JSON, j, layout, err);
    cJSON_Delete(j);
    return st;
}

// ---- landmarks.geojson ----

// A line's coordinates [[lon, lat, h], ...] as given (NULL for a non-finite number, or when
// out of memory): each vertex [lon, lat] where its height is unknown.
static cJSON *line_coordinates(const rs_site_landmark *l, bool unknown, double geoid_undulation_m)
{
    cJSON *list = cJSON_CreateArray();
    for (int k = 0; list && k < l->Nvertices; k++) {
        const rs_llh *v = &l->vertices_llh[k];
        const double h = l->height_modelled ? l->vertices_given_h_m[k] : v->h_m;
        const double lonlath[3] = {v->lon_deg, v->lat_deg, h - geoid_undulation_m};
        cJSON *position = rs_site__numbers(lonlath, unknown && isnan(h) ? 2 : 3);
        if (!position || !cJSON_AddItemToArray(list, position)) {
            cJSON_Delete(position);
            cJSON_Delete(list);
            return NULL;
        }
    }
    return list;
}

static cJSON *landmark_feature(const rs_site_landmark *l, double geoid_undulation_m)
{
    // what was given, not what the ground model made of it
    const double h = l->height_modelled ? l->given_h_m : l->llh.h_m;
    const double sigma_v = l->height_modelled ? l->given_sigma_v_m : l->sigma_v_m;
    const bool unknown = l->height == RS_SITE_HEIGHT_UNKNOWN || l->height_stated == RS_SITE_HEIGHT_UNKNOWN;
    const bool line = l->shape == RS_SITE_LINE;
    const double lonlath[3] = {l->llh.lon_deg, l->llh.lat_deg, h - geoid_undulation_m};
    cJSON *f = cJSON_CreateObject(), *g = NULL, *p = NULL;
    bool ok = f && cJSON_AddStringToObject(f, "type", "Feature") && (g = cJSON_AddObjectToObject(f, "geometry")) &&
              cJSON_AddStringToObject(g, "type", line ? "LineString" : "Point") &&
              add_item(g, "coordinates",
                       line ? line_coordinates(l, unknown, geoid_undulation_m)
                            : rs_site__numbers(lonlath, unknown && isnan(h) ? 2 : 3)) &&
              (p = cJSON_AddObjectToObject(f, "properties")) && cJSON_AddStringToObject(p, "id", l->id);
    if (ok && l->kind) ok = cJSON_AddStringToObject(p, "kind", l->kind);
    if (ok && isfinite(l->sigma_h_m) && l->sigma_h_m > 0) ok = rs_site__add_number(p, "sigma_h_m", l->sigma_h_m);
    if (ok && isfinite(sigma_v) && sigma_v > 0) ok = rs_site__add_number(p, "sigma_v_m", sigma_v);
    if (ok && l->shape == RS_SITE_POLE) {
        ok = rs_site__add_number(p, "height_m", l->pole_height_m);
        if (ok && isfinite(l->sigma_pole_height_m) && l->sigma_pole_height_m > 0)
            ok = rs_site__add_number(p, "sigma_height_m", l->sigma_pole_height_m);
    }
    if (ok && l->height_stated != RS_SITE_HEIGHT_DEFAULT)
        ok = cJSON_AddStringToObject(p, "height", rs_site_height_name(l->height_stated));
    if (ok && l->above_ground_m > 0) ok = rs_site__add_number(p, "above_ground_m", l->above_ground_m);
    if (ok && l->note) ok = cJSON_AddStringToObject(p, "note", l->note);
    if (ok) return f;
    cJSON_Delete(f);
    return NULL;
}

rs_status rs_site_write_landmarks(const char *dir, const rs_site_landmark *landmarks, int Nlandmarks,
                                  double geoid_undulation_m, rs_site_layout layout, rs_err *err)
{
    for (int i = 0; i < Nlandmarks; i++) {
        const rs_site_landmark *l = &landmarks[i];
        if (!l->id) return rs_err_set(err, RS_ERR_INVALID, "%s/landmarks.geojson: feature %d: id missing", dir, i);
        if (l->shape == RS_SITE_LINE && (l->Nvertices < 2 || !l->vertices_llh || !l->vertices_given_h_m))
            return rs_err_set(err, RS_ERR_INVALID, "%s/landmarks.geojson: feature %d (id '%s'): a line needs %s", dir,
                              i, l->id,
                              l->Nvertices < 2 ? "at least 2 vertices" : "vertices_llh and vertices_given_h_m");
        if (l->shape == RS_SITE_POLE && !(l->pole_height_m > 0 && l->pole_height_m <= RS_SITE_POLE_HEIGHT_MAX_M))
            return rs_err_set(err, RS_ERR_INVALID,
                              "%s/landmarks.geojson: feature %d (id '%s'): pole height %g m is "
                              "outside (0, %g] m",
                              dir, i, l->id, l->pole_height_m, RS_SITE_POLE_HEIGHT_MAX_M);
    }
    cJSON *j = cJSON_CreateObject(), *features = NULL;
    bool ok = j && cJSON_AddStringToObject(j, "type", "FeatureCollection") &&
              (features = cJSON_AddArrayToObject(j, "features"));
    for (int i = 0; ok && i < Nlandmarks; i++) {
        cJSON *f = landmark_feature(&landmarks[i], geoid_undulation_m);
        ok = f && cJSON_AddItemToArray(features, f);
        if (!ok) cJSON_Delete(f);
    }
    rs_status st = write_document(dir, RS_SITE_LANDMARKS, ok ? j : NULL, layout, err);
    cJSON_Delete(j);
    return st;
}

// ---- observations/<id>.csv ----

rs_status rs_site_write_observations(const char *path, const rs_site_observation *obs, int Nobservations,
                                     const rs_site_landmark *landmarks, rs_err *err)
{
    // the column `at` only where a pick is of a pole or line (a site of points is written as ever)
    bool with_at = false;
    for (int i = 0; i < Nobservations; i++)
        with_at = with_at || obs[i].at != RS_SITE_AT_POINT || landmarks[obs[i].ilandmark].shape != RS_SITE_POINT;
    rs_io_atomic a;
    rs_status st = rs_io_atomic_open(&a, path, err);
    if (st) return st;
    fprintf(a.f, with_at ? "landmark,u,v,sigma_px,at\n" : "landmark,u,v,sigma_px\n");
    for (int i = 0; i < Nobservations; i++) {
        fprintf(a.f, "%s,%.6f,%.6f,%g", landmarks[obs[i].ilandmark].id, obs[i].q_px[0], obs[i].q_px[1],
                obs[i].sigma_px);
        fprintf(a.f, with_at ? ",%s\n" : "\n", rs_site_at_name(obs[i].at));
    }
    return rs_io_atomic_commit(&a, err);
}

// ---- background records ----

char *rs_site_background_file(const char *camera_id, const char *name)
{
    const size_t n = strlen(camera_id) + strlen(name) + sizeof "backgrounds//.png";
    char *p = malloc(n);
    if (p) snprintf(p, n, "backgrounds/%s/%s.png", camera_id, name);
    return p;
}

// The entry of a background record (rs_site_record_background); NULL when out of memory.
static cJSON *background_entry(const char *file, const char *name, bool synthetic, const char *const *keys,
                               const char *const *values, int Ntags, cJSON *source)
{
    cJSON *e = cJSON_CreateObject(), *tags = NULL;
    bool ok = e && cJSON_AddStringToObject(e, "name", name) && cJSON_AddStringToObject(e, "file", file) &&
              cJSON_AddBoolToObject(e, "synthetic", synthetic) && (tags = cJSON_AddObjectToObject(e, "tags"));
    for (int i = 0; ok && i < Ntags; i++) {
        cJSON_DeleteItemFromObjectCaseSensitive(tags, keys[i]);
        ok = cJSON_AddStringToObject(tags, keys[i], values[i]);
    }
    if (ok && source) ok = add_item(e, "source", cJSON_Duplicate(source, true));
    if (ok) return e;
    cJSON_Delete(e);
    return NULL;
}

rs_status rs_site_record_background(const char *dir, const char *camera_id, const char *name, bool synthetic,
                                    const char *const *keys, const char *const *values, int Ntags,
                                    const char *source_json, rs_err *err)
{
    char *path = rs_io_join(dir, RS_SITE_JSON), *text = NULL, *file = NULL;
    cJSON *root = NULL, *source = NULL;
    rs_status st = RS_OK;
    if (!path || !(file = rs_site_background_file(camera_id, name))) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    if (source_json && !(source = cJSON_Parse(source_json))) {
        st = rs_err_set(err, RS_ERR_PARSE, "%s: background '%s': source: not JSON", path, name);
        goto done;
    }
    if ((st = rs_io_read_file(&text, NULL, path, err))) goto done;
    const char *json = strncmp(text, "\xEF\xBB\xBF", 3) ? text : text + 3; // UTF-8 BOM
    if (!(root = cJSON_Parse(json))) {
        st = rs_err_set(err, RS_ERR_PARSE, "%s: not valid JSON", path);
        goto done;
    }
    cJSON *cams = cJSON_GetObjectItemCaseSensitive(root, "cameras"), *cam = NULL, *it;
    cJSON_ArrayForEach(it, cams)
    {
        const cJSON *id = cJSON_GetObjectItemCaseSensitive(it, "id");
        if (cJSON_IsString(id) && !strcmp(id->valuestring, camera_id)) cam = it;
    }
    if (!cam || !cJSON_IsObject(cam)) {
        st = rs_err_set(err, RS_ERR_NOT_FOUND, "%s: cameras: no camera with id '%s'", path, camera_id);
        goto done;
    }
    char folder[512];
    snprintf(folder, sizeof folder, "backgrounds/%s", camera_id);
    if (!cJSON_GetObjectItemCaseSensitive(cam, "backgrounds")) cJSON_AddStringToObject(cam, "backgrounds", folder);
    cJSON *list = cJSON_GetObjectItemCaseSensitive(cam, "background_images");
    if (!list) list = cJSON_AddArrayToObject(cam, "background_images");
    if (!cJSON_IsArray(list)) {
        st = rs_err_set(err, RS_ERR_PARSE, "%s: cameras[id %s].background_images: not a list", path, camera_id);
        goto done;
    }
    cJSON *e = background_entry(file, name, synthetic, keys, values, Ntags, source);
    if (!e) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    // replace an entry of the same name, else append
    int i = 0, found = -1;
    cJSON_ArrayForEach(it, list)
    {
        const cJSON *nm = cJSON_GetObjectItemCaseSensitive(it, "name");
        if (cJSON_IsString(nm) && !strcmp(nm->valuestring, name)) found = i;
        i++;
    }
    if (found >= 0)
        cJSON_ReplaceItemInArray(list, found, e);
    else
        cJSON_AddItemToArray(list, e);
    st = rs_site__write_json(path, root, RS_SITE_LAYOUT_TOOL, err);
done:
    cJSON_Delete(root);
    cJSON_Delete(source);
    free(text);
    free(file);
    free(path);
    return st;
}

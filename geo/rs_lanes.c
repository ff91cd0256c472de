// rs_lanes.c -- lanes.geojson: the reader, the writer and a lane's geometry. See rs_lanes.h.
// Calls the geodesy (rs_geo.h) and, to write, the JSON layouts of rs_site_write.c.
#include "geo/rs_lanes.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_index.h"
#include "core/rs_io.h"
#include "core/rs_units.h"
#include "geo/internal/rs_site_json.h"

void rs_lanes_free(rs_lanes *lanes)
{
    if (!lanes) return;
    for (int i = 0; i < lanes->N; i++) {
        free(lanes->lane[i].id);
        free(lanes->lane[i].kind);
        free(lanes->lane[i].p_enu_m);
        free(lanes->lane[i].next);
    }
    free(lanes->lane);
    lanes->lane = NULL;
    lanes->N = 0;
}

double rs_lane_length_m(const rs_lane *lane)
{
    double L = 0;
    for (int i = 1; i < lane->Npoints; i++)
        L += hypot(lane->p_enu_m[i][0] - lane->p_enu_m[i - 1][0], lane->p_enu_m[i][1] - lane->p_enu_m[i - 1][1]);
    return L;
}

static double heading_of(double de, double dn)
{
    double h = atan2(de, dn) / RS_RAD_PER_DEG;
    if (h < 0) h += 360.0;
    return h >= 360.0 ? h - 360.0 : h;
}

void rs_lane_point(double p_enu_m[2], double *heading_deg, const rs_lane *lane, double s_m)
{
    if (s_m < 0) s_m = 0;
    int i = 1;
    double seg = 0;
    for (; i < lane->Npoints; i++) {
        seg = hypot(lane->p_enu_m[i][0] - lane->p_enu_m[i - 1][0], lane->p_enu_m[i][1] - lane->p_enu_m[i - 1][1]);
        if (s_m <= seg || i == lane->Npoints - 1) break;
        s_m -= seg;
    }
    const double *a = lane->p_enu_m[i - 1], *b = lane->p_enu_m[i];
    double t = seg > 0 ? fmin(1.0, s_m / seg) : 0;
    p_enu_m[0] = a[0] + t * (b[0] - a[0]);
    p_enu_m[1] = a[1] + t * (b[1] - a[1]);
    if (heading_deg) *heading_deg = heading_of(b[0] - a[0], b[1] - a[1]);
}

double rs_lane_distance_m(double *heading_deg, const rs_lane *lane, const double p_enu_m[2])
{
    double best = INFINITY;
    int best_i = 0;
    for (int i = 1; i < lane->Npoints; i++) {
        const double *a = lane->p_enu_m[i - 1], *b = lane->p_enu_m[i];
        double de = b[0] - a[0], dn = b[1] - a[1], L2 = de * de + dn * dn;
        double t = L2 > 0 ? ((p_enu_m[0] - a[0]) * de + (p_enu_m[1] - a[1]) * dn) / L2 : 0;
        t = fmax(0.0, fmin(1.0, t));
        double d = hypot(p_enu_m[0] - a[0] - t * de, p_enu_m[1] - a[1] - t * dn);
        if (d < best) best = d, best_i = i;
    }
    if (heading_deg) { // the nearest segment's, computed once (atan2 per segment was most of the cost)
        const double *a = lane->p_enu_m[best_i > 0 ? best_i - 1 : 0], *b = lane->p_enu_m[best_i];
        *heading_deg = best_i > 0 ? heading_of(b[0] - a[0], b[1] - a[1]) : NAN;
    }
    return best;
}

// Reads feature i's properties and geometry into lane (ENU at origin).
static rs_status read_lane(rs_lane *lane, const cJSON *f, int i, const char *path, const rs_site *site, rs_err *err)
{
    lane->feature = i;
    lane->speed_mps = NAN;
    const cJSON *props = cJSON_GetObjectItemCaseSensitive(f, "properties");
    const cJSON *id = cJSON_GetObjectItemCaseSensitive(props, "id");
    if (!cJSON_IsString(id) || !*id->valuestring)
        return rs_err_set(err, RS_ERR_PARSE, "%s: feature %d: properties.id: missing or not a non-empty string", path,
                          i);
    if (!(lane->id = strdup(id->valuestring))) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
#define LANE_FAIL(code, field, ...) rs_err_set(err, code, "%s: feature %d (id '%s'): " field ": " __VA_ARGS__)
    const cJSON *w = cJSON_GetObjectItemCaseSensitive(props, "width_m");
    if (!cJSON_IsNumber(w))
        return LANE_FAIL(RS_ERR_PARSE, "properties.width_m", "missing or not a number", path, i, lane->id);
    lane->width_m = w->valuedouble;
    if (!(lane->width_m > 0) || !isfinite(lane->width_m))
        return LANE_FAIL(RS_ERR_INVALID, "properties.width_m", "%g: must be > 0", path, i, lane->id, lane->width_m);
    const cJSON *d = cJSON_GetObjectItemCaseSensitive(props, "direction");
    if (d && !cJSON_IsNull(d)) {
        if (cJSON_IsString(d) && !strcmp(d->valuestring, "forward"))
            lane->direction = RS_LANE_FORWARD;
        else if (cJSON_IsString(d) && !strcmp(d->valuestring, "both"))
            lane->direction = RS_LANE_BOTH;
        else
            return LANE_FAIL(RS_ERR_INVALID, "properties.direction", "must be \"forward\" or \"both\"", path, i,
                             lane->id);
    }
    const cJSON *sp = cJSON_GetObjectItemCaseSensitive(props, "speed_mps");
    if (sp && !cJSON_IsNull(sp)) {
        if (!cJSON_IsNumber(sp) || !(sp->valuedouble > 0) || !isfinite(sp->valuedouble))
            return LANE_FAIL(RS_ERR_INVALID, "properties.speed_mps", "must be a number > 0", path, i, lane->id);
        lane->speed_mps = sp->valuedouble;
    }
    const cJSON *kind = cJSON_GetObjectItemCaseSensitive(props, "kind");
    if (cJSON_IsString(kind) && !(lane->kind = strdup(kind->valuestring)))
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    const cJSON *g = cJSON_GetObjectItemCaseSensitive(f, "geometry");
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(g, "type");
    if (!cJSON_IsString(type) || strcmp(type->valuestring, "LineString"))
        return LANE_FAIL(RS_ERR_PARSE, "geometry.type", "not a LineString", path, i, lane->id);
    const cJSON *coords = cJSON_GetObjectItemCaseSensitive(g, "coordinates");
    int n = cJSON_GetArraySize(coords);
    if (!cJSON_IsArray(coords) || n < 2)
        return LANE_FAIL(RS_ERR_INVALID, "geometry.coordinates", "fewer than 2 points", path, i, lane->id);
    double *llh = malloc(sizeof *llh * 3 * (size_t)n), *enu = malloc(sizeof *enu * 3 * (size_t)n);
    bool *on_ground = malloc(sizeof *on_ground * (size_t)n);
    lane->p_enu_m = malloc(sizeof *lane->p_enu_m * (size_t)n);
    rs_status st = RS_OK;
    if (!llh || !enu || !on_ground || !lane->p_enu_m) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    int k = 0;
    for (const cJSON *c = coords->child; c; c = c->next, k++) {
        int m = cJSON_GetArraySize(c);
        const cJSON *lon = cJSON_GetArrayItem(c, 0), *lat = cJSON_GetArrayItem(c, 1);
        if (!cJSON_IsArray(c) || m < 2 || m > 3 || !cJSON_IsNumber(lon) || !cJSON_IsNumber(lat)) {
            st = rs_err_set(err, RS_ERR_PARSE, "%s: feature %d (id '%s'): geometry.coordinates[%d]: not [lon, lat]",
                            path, i, lane->id, k);
            goto done;
        }
        const cJSON *h = cJSON_GetArrayItem(c, 2);
        if (m == 3 && (!cJSON_IsNumber(h) || !isfinite(h->valuedouble))) {
            st = rs_err_set(err, RS_ERR_PARSE, "%s: feature %d (id '%s'): geometry.coordinates[%d][2]: not a number",
                            path, i, lane->id, k);
            goto done;
        }
        llh[3 * k] = lat->valuedouble;
        llh[3 * k + 1] = lon->valuedouble;
        llh[3 * k + 2] = m == 3 ? h->valuedouble + site->geoid_undulation_m : site->origin.h_m;
        on_ground[k] = m == 2;
    }
    if ((st = rs_geo_llh_to_enu(enu, &site->origin, llh, n, err))) {
        rs_err_prefix(err, "%s: feature %d (id '%s'): geometry.coordinates", path, i, lane->id);
        goto done;
    }
    lane->Npoints = 0;
    for (k = 0; k < n; k++) {
        if (hypot(enu[3 * k], enu[3 * k + 1]) > 1e5) {
            st = rs_err_set(err, RS_ERR_INVALID,
                            "%s: feature %d (id '%s'): geometry.coordinates[%d]: %.0f m from the site origin "
                            "(longitude first: [lon, lat])",
                            path, i, lane->id, k, hypot(enu[3 * k], enu[3 * k + 1]));
            goto done;
        }
        int q = lane->Npoints;
        if (q > 0 && hypot(enu[3 * k] - lane->p_enu_m[q - 1][0], enu[3 * k + 1] - lane->p_enu_m[q - 1][1]) < 1e-3)
            continue; // repeated point
        const double *n_up = site->ground_normal_enu;
        lane->p_enu_m[q][0] = enu[3 * k];
        lane->p_enu_m[q][1] = enu[3 * k + 1];
        lane->p_enu_m[q][2] = on_ground[k]
                                  ? (site->ground_offset_m - n_up[0] * enu[3 * k] - n_up[1] * enu[3 * k + 1]) / n_up[2]
                                  : enu[3 * k + 2];
        lane->Npoints++;
    }
    if (lane->Npoints < 2)
        st = LANE_FAIL(RS_ERR_INVALID, "geometry.coordinates", "fewer than 2 distinct points", path, i, lane->id);
done:
    free(llh);
    free(enu);
    free(on_ground);
    return st;
}

// Resolves every lane's "next" ids into indices, through ids (the lanes by id: O(log N) each).
static rs_status resolve_next(rs_lanes *lanes, const rs_index *ids, const cJSON *features, const char *path,
                              rs_err *err)
{
    int i = 0;
    for (const cJSON *f = features->child; f; f = f->next, i++) {
        rs_lane *lane = &lanes->lane[i];
        const cJSON *next = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(f, "properties"), "next");
        if (!next || cJSON_IsNull(next)) continue;
        if (!cJSON_IsArray(next))
            return LANE_FAIL(RS_ERR_PARSE, "properties.next", "not a list of lane ids", path, i, lane->id);
        int n = cJSON_GetArraySize(next);
        if (n == 0) continue;
        if (!(lane->next = malloc(sizeof *lane->next * (size_t)n)))
            return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        for (const cJSON *x = next->child; x; x = x->next) {
            if (!cJSON_IsString(x))
                return LANE_FAIL(RS_ERR_PARSE, "properties.next", "not a list of lane ids", path, i, lane->id);
            int j = rs_index_find(ids, x->valuestring);
            if (j < 0)
                return LANE_FAIL(RS_ERR_NOT_FOUND, "properties.next", "'%s' is not a lane of this file", path, i,
                                 lane->id, x->valuestring);
            lane->next[lane->Nnext++] = j;
        }
    }
    return RS_OK;
}
#undef LANE_FAIL

rs_status rs_lanes_read(rs_lanes *lanes, const char *path, const rs_site *site, rs_err *err)
{
    lanes->lane = NULL;
    lanes->N = 0;
    rs_index ids = {0};
    char *text = NULL;
    rs_status st = rs_io_read_file(&text, NULL, path, err);
    if (st) return st;
    cJSON *j = cJSON_Parse(text);
    free(text);
    if (!j) return rs_err_set(err, RS_ERR_PARSE, "%s: not valid JSON", path);
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(j, "type");
    const cJSON *features = cJSON_GetObjectItemCaseSensitive(j, "features");
    if (!cJSON_IsString(type) || strcmp(type->valuestring, "FeatureCollection") || !cJSON_IsArray(features)) {
        st = rs_err_set(err, RS_ERR_PARSE, "%s: type: not a GeoJSON FeatureCollection with features", path);
        goto done;
    }
    int n = cJSON_GetArraySize(features);
    if (n == 0) {
        st = rs_err_set(err, RS_ERR_INVALID, "%s: features: no lanes", path);
        goto done;
    }
    if (!(lanes->lane = calloc((size_t)n, sizeof *lanes->lane))) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    int i = 0;
    for (const cJSON *f = features->child; f; f = f->next, i++) {
        lanes->N = i + 1;
        if ((st = read_lane(&lanes->lane[i], f, i, path, site, err))) goto done;
    }
    // ids through a sorted index (50,000 lanes took 18 s pairwise); the first repeat in file order
    if ((st = rs_index_init_strided(&ids, (const char *const *)&lanes->lane[0].id, sizeof *lanes->lane, lanes->N, false,
                                    err)))
        goto done;
    for (i = 0; i < lanes->N; i++) {
        const int dup = rs_index_find(&ids, lanes->lane[i].id);
        if (dup < i) {
            st = rs_err_set(err, RS_ERR_INVALID, "%s: feature %d: properties.id: '%s' is also feature %d's id", path, i,
                            lanes->lane[i].id, dup);
            goto done;
        }
    }
    st = resolve_next(lanes, &ids, features, path, err);
done:
    rs_index_free(&ids);
    cJSON_Delete(j);
    if (st) rs_lanes_free(lanes);
    return st;
}

// ---- writing ----

// One lane as a GeoJSON LineString feature into *out (owned by the caller).
static rs_status lane_feature(cJSON **out, const rs_lanes *lanes, int i, const rs_llh *origin, double N,
                              bool with_height, const char *path, rs_err *err)
{
    const rs_lane *lane = &lanes->lane[i];
    *out = NULL;
    if (!lane->id) return rs_err_set(err, RS_ERR_INVALID, "%s: lane %d: id missing", path, i);
    for (int k = 0; k < lane->Nnext; k++)
        if (lane->next[k] < 0 || lane->next[k] >= lanes->N || !lanes->lane[lane->next[k]].id)
            return rs_err_set(err, RS_ERR_INVALID, "%s: lane '%s': next[%d] = %d is not a lane", path, lane->id, k,
                              lane->next[k]);
    double(*llh)[3] = malloc(sizeof *llh * (size_t)(lane->Npoints > 0 ? lane->Npoints : 1));
    if (!llh) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_status st =
        lane->Npoints > 0 ? rs_geo_enu_to_llh(&llh[0][0], origin, &lane->p_enu_m[0][0], lane->Npoints, err) : RS_OK;
    if (st) {
        free(llh);
        rs_err_prefix(err, "%s: lane '%s'", path, lane->id);
        return st;
    }
    cJSON *f = cJSON_CreateObject(), *g = NULL, *c = NULL, *p = NULL, *nx = NULL;
    bool ok = f && cJSON_AddStringToObject(f, "type", "Feature") && (g = cJSON_AddObjectToObject(f, "geometry")) &&
              cJSON_AddStringToObject(g, "type", "LineString") && (c = cJSON_AddArrayToObject(g, "coordinates"));
    for (int k = 0; ok && k < lane->Npoints; k++) {
        const double lonlath[3] = {llh[k][1], llh[k][0], llh[k][2] - N};
        cJSON *xy = rs_site__numbers(lonlath, with_height ? 3 : 2);
        ok = xy && cJSON_AddItemToArray(c, xy);
        if (!ok) cJSON_Delete(xy);
    }
    free(llh);
    ok = ok && (p = cJSON_AddObjectToObject(f, "properties")) && cJSON_AddStringToObject(p, "id", lane->id);
    if (ok && lane->kind) ok = cJSON_AddStringToObject(p, "kind", lane->kind);
    ok = ok && rs_site__add_number(p, "width_m", lane->width_m) &&
         cJSON_AddStringToObject(p, "direction", lane->direction == RS_LANE_BOTH ? "both" : "forward");
    if (ok && !isnan(lane->speed_mps)) ok = rs_site__add_number(p, "speed_mps", lane->speed_mps);
    ok = ok && (nx = cJSON_AddArrayToObject(p, "next"));
    for (int k = 0; ok && k < lane->Nnext; k++) {
        cJSON *id = cJSON_CreateString(lanes->lane[lane->next[k]].id);
        ok = id && cJSON_AddItemToArray(nx, id);
        if (!ok) cJSON_Delete(id);
    }
    if (ok) {
        *out = f;
        return RS_OK;
    }
    cJSON_Delete(f);
    return rs_err_set(err, RS_ERR_INVALID, "%s: lane '%s': a number is not finite (or out of memory)", path, lane->id);
}

rs_status rs_lanes_write(const char *path, const rs_lanes *lanes, const rs_llh *origin, double geoid_undulation_m,
                         bool with_height, rs_site_layout layout, rs_err *err)
{
    cJSON *j = cJSON_CreateObject(), *features = NULL;
    if (!j || !cJSON_AddStringToObject(j, "type", "FeatureCollection") ||
        !(features = cJSON_AddArrayToObject(j, "features"))) {
        cJSON_Delete(j);
        return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
    }
    rs_status st = RS_OK;
    for (int i = 0; i < lanes->N && !st; i++) {
        cJSON *f = NULL;
        st = lane_feature(&f, lanes, i, origin, geoid_undulation_m, with_height, path, err);
        if (!st && !cJSON_AddItemToArray(features, f)) {
            cJSON_Delete(f);
            st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
        }
    }
    if (!st) st = rs_site__write_json(path, j, layout, err);
    cJSON_Delete(j);
    return st;
}

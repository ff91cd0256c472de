// rs_pick_server.c -- the local HTTP server of `roadside pick` (libmicrohttpd): the page, its JSON
// API, and the checks that keep it the surveyor's own (rs_pick.h, docs/pick.md "Security").
#include <arpa/inet.h>
#include <math.h>
#include <netinet/in.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cjson/cJSON.h>
#include <microhttpd.h>

#include "core/rs_image.h"
#include "core/rs_io.h"
#include "core/rs_json.h"
#include "geo/rs_geo.h"
#include "geo/rs_geo_raster.h"
#include "geo/rs_lanes.h"
#include "pick/internal/rs_pick_internal.h"
#include "pick/rs_pick.h"

// Connections: at most PER_CLIENT_CONNECTION_LIMIT from one address (a browser opens 6 per
// server), CONNECTION_LIMIT in all, so that one client holding its most leaves room for another;
// a connection silent for CONNECTION_TIMEOUT_S seconds is closed.
enum { CONNECTION_LIMIT = 512, PER_CLIENT_CONNECTION_LIMIT = 128, CONNECTION_TIMEOUT_S = 5 };

struct rs_pick_server {
    struct MHD_Daemon *daemon;
    rs_pick_session *session; // borrowed
    size_t max_body;
    int port;
    char host[64];
    char url[128];
    char host_ok[2][128];   // the Host headers accepted: "HOST:PORT", "localhost:PORT"
    char origin_ok[2][128]; // the Origins accepted: "http://HOST:PORT", "http://localhost:PORT"
    unsigned char *image;   // (H, W, 3) owned: the camera image; NULL: none
    int image_w, image_h;
    rs_geo_tiles *ortho; // borrowed; may be NULL
    char *map_json;      // owned: the map's grid and the lanes, fixed for the session
    char csp[512];       // the page's Content-Security-Policy (the tile origin allowed)
    unsigned char *tile; // (RS_GEO_TILE_PX, RS_GEO_TILE_PX, 4) owned: the tile being sent
};

#define RS_PICK_CSP "default-src 'self'; img-src 'self' data: blob:%s%s; connect-src 'self'; frame-ancestors 'none'"

void rs_pick_server_options_default(rs_pick_server_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->host = "127.0.0.1";
    opt->max_body = 65536;
    opt->tiles_max_zoom = 19;
}

// ---- responses ----

static enum MHD_Result send_bytes_csp(struct MHD_Connection *c, unsigned status, const char *mime, const void *data,
                                      size_t len, enum MHD_ResponseMemoryMode mode, const char *csp)
{
    struct MHD_Response *r = MHD_create_response_from_buffer(len, (void *)data, mode);
    if (!r) return MHD_NO;
    MHD_add_response_header(r, "Content-Type", mime);
    MHD_add_response_header(r, "Cache-Control", "no-store");
    MHD_add_response_header(r, "X-Content-Type-Options", "nosniff");
    MHD_add_response_header(r, "Referrer-Policy", "no-referrer");
    MHD_add_response_header(r, "Content-Security-Policy", csp);
    enum MHD_Result ret = MHD_queue_response(c, status, r);
    MHD_destroy_response(r);
    return ret;
}

static enum MHD_Result send_bytes(struct MHD_Connection *c, unsigned status, const char *mime, const void *data,
                                  size_t len, enum MHD_ResponseMemoryMode mode)
{
    char csp[256];
    snprintf(csp, sizeof csp, RS_PICK_CSP, "", "");
    return send_bytes_csp(c, status, mime, data, len, mode, csp);
}

// {"error": "..."} with the status.
static enum MHD_Result send_error(struct MHD_Connection *c, unsigned status, const char *fmt, ...)
{
    char msg[600];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "error", msg);
    char *text = cJSON_PrintUnformatted(o);
    cJSON_Delete(o);
    if (!text) return MHD_NO;
    enum MHD_Result r = send_bytes(c, status, "application/json", text, strlen(text), MHD_RESPMEM_MUST_COPY);
    cJSON_free(text);
    return r;
}

static enum MHD_Result send_state(struct MHD_Connection *c, const rs_pick_server *srv)
{
    char *text = rs_pick_state_json(srv->session);
    if (!text) return send_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, "out of memory");
    enum MHD_Result r = send_bytes(c, MHD_HTTP_OK, "application/json", text, strlen(text), MHD_RESPMEM_MUST_COPY);
    free(text);
    return r;
}

// ---- one request ----

typedef struct {
    char *body; // owned
    size_t len;
    bool too_big;
} request;

static void request_done(void *cls, struct MHD_Connection *c, void **con_cls, enum MHD_RequestTerminationCode toe)
{
    (void)cls, (void)c, (void)toe;
    request *rq = *con_cls;
    if (rq) {
        free(rq->body);
        free(rq);
    }
    *con_cls = NULL;
}

static bool header_is(struct MHD_Connection *c, const char *name, const char ok[][128], int n)
{
    const char *v = MHD_lookup_connection_value(c, MHD_HEADER_KIND, name);
    if (!v) return false;
    for (int i = 0; i < n; i++)
        if (ok[i][0] && !strcmp(v, ok[i])) return true;
    return false;
}

// A number member of a JSON object, or false.
static bool get_num(const cJSON *o, const char *k, double *x)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, k);
    if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble)) return false;
    *x = v->valuedouble;
    return true;
}

static const char *get_str(const cJSON *o, const char *k)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, k);
    return cJSON_IsString(v) && v->valuestring && strlen(v->valuestring) < 256 ? v->valuestring : NULL;
}

// The status of a session error: what the client asked cannot be done (404 / 422), or failed.
static unsigned status_of(rs_status st)
{
    switch (st) {
    case RS_ERR_NOT_FOUND: return MHD_HTTP_NOT_FOUND;
    case RS_ERR_INVALID:
    case RS_ERR_UNSUPPORTED: return MHD_HTTP_UNPROCESSABLE_CONTENT;
    default: return MHD_HTTP_INTERNAL_SERVER_ERROR;
    }
}

// The ground point of a request: "e", "n" (site ENU metres) or "lat", "lon" (WGS84 degrees,
// converted exactly by geo at the site origin's height; the landmark then sits on the ground plane).
static bool en_of(const rs_pick_server *srv, const cJSON *o, double *e, double *n)
{
    double lat, lon;
    if (get_num(o, "e", e) && get_num(o, "n", n)) return true;
    if (!get_num(o, "lat", &lat) || !get_num(o, "lon", &lon) || fabs(lat) > 90 || fabs(lon) > 180) return false;
    const rs_site *site = rs_pick_session_site(srv->session);
    const double llh[3] = {lat, lon, site->origin.h_m};
    double p[3];
    if (rs_geo_llh_to_enu(p, &site->origin, llh, 1, NULL) != RS_OK) return false;
    *e = p[0], *n = p[1];
    return true;
}

// A point-pair file sent as text: written to a private temporary file (the suffix from the
// name's extension, .json or .csv: the reader's two formats; no other part of the name is used),
// read by rs_pick_import (site import's reader), removed.
static rs_status import_text(rs_pick_server *srv, const char *name, const char *text, int *Nadded, int *Npicked,
                             rs_err *err)
{
    const char *ext = strrchr(name, '.');
    if (!ext || (strcasecmp(ext, ".json") != 0 && strcasecmp(ext, ".csv") != 0))
        return rs_err_set(err, RS_ERR_INVALID, "%s: a point-pair file is .json or .csv", name);
    const bool json = !strcasecmp(ext, ".json");
    char path[64];
    snprintf(path, sizeof path, "/tmp/roadside-pick-import-XXXXXX%s", json ? ".json" : ".csv");
    const int fd = mkstemps(path, json ? 5 : 4);
    if (fd < 0) return rs_err_set(err, RS_ERR_IO, "cannot make a temporary file for %s", name);
    const size_t len = strlen(text);
    const bool ok = write(fd, text, len) == (ssize_t)len;
    close(fd);
    rs_status st = ok ? rs_pick_import(srv->session, Nadded, Npicked, path, err)
                      : rs_err_set(err, RS_ERR_IO, "cannot write a temporary file for %s", name);
    unlink(path);
    if (st && err) { // the user's file name, not the temporary one
        char msg[sizeof err->msg];
        const char *at = strstr(err->msg, path);
        if (at) {
            snprintf(msg, sizeof msg, "%.*s%.200s%.600s", (int)(at - err->msg), err->msg, name, at + strlen(path));
            memcpy(err->msg, msg, sizeof msg);
        }
    }
    return st;
}

rs_status rs_pick_request_parse(cJSON **obj, const char *body, size_t len, rs_err *err)
{
    *obj = NULL;
    if (memchr(body, '\0', len)) return rs_err_set(err, RS_ERR_PARSE, "the body holds a NUL byte: not JSON text");
    rs_err e = {0};
    if (rs_json_parse(obj, body, 0, len, "the body", &e) != RS_OK)
        return rs_err_set(err, RS_ERR_PARSE, "the body is not a JSON object: %s", e.msg);
    if (!cJSON_IsObject(*obj)) {
        cJSON_Delete(*obj);
        *obj = NULL;
        return rs_err_set(err, RS_ERR_PARSE, "the body is not a JSON object");
    }
    return RS_OK;
}

static enum MHD_Result post(struct MHD_Connection *c, rs_pick_server *srv, const char *url, const request *rq)
{
    // exactly application/json, parameters (charset) allowed: not application/jsonx
    const char *ct = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Content-Type");
    if (!ct || strncasecmp(ct, "application/json", 16) != 0 || (ct[16] && !strchr(" \t;", ct[16])))
        return send_error(c, MHD_HTTP_UNSUPPORTED_MEDIA_TYPE, "the body must be application/json");
    cJSON *o = NULL;
    rs_err perr = {0};
    if (rs_pick_request_parse(&o, rq->body ? rq->body : "", rq->len, &perr))
        return send_error(c, MHD_HTTP_BAD_REQUEST, "%s", perr.msg);
    rs_err err = {0};
    rs_status st = RS_OK;
    char added[32] = "";
    double u = 0, v = 0, e = 0, n = 0;
    const char *id = get_str(o, "landmark");
    enum MHD_Result ret;
    if (!strcmp(url, "/api/pick") || !strcmp(url, "/api/move")) {
        if (!id || !get_num(o, "u", &u) || !get_num(o, "v", &v)) {
            cJSON_Delete(o);
            return send_error(c, MHD_HTTP_BAD_REQUEST, "expected {\"landmark\": ID, \"u\": px, \"v\": px}");
        }
        st = rs_pick_set(srv->session, id, u, v, &err);
    } else if (!strcmp(url, "/api/delete")) {
        if (!id) {
            cJSON_Delete(o);
            return send_error(c, MHD_HTTP_BAD_REQUEST, "expected {\"landmark\": ID}");
        }
        st = rs_pick_delete(srv->session, id, &err);
    } else if (!strcmp(url, "/api/refine")) {
        const char *words = get_str(o, "refine");
        if (!words) {
            cJSON_Delete(o);
            return send_error(c, MHD_HTTP_BAD_REQUEST,
                              "expected {\"refine\": \"focal+center\"} (calib's --refine words)");
        }
        st = rs_pick_set_refine(srv->session, words, &err);
    } else if (!strcmp(url, "/api/sigma")) {
        // a number sets the landmark's own sigma, null (or absent) returns it to the site-wide one
        const cJSON *jh = cJSON_GetObjectItemCaseSensitive(o, "sigma_h_m"),
                    *jv = cJSON_GetObjectItemCaseSensitive(o, "sigma_v_m");
        const bool ok_h = !jh || cJSON_IsNull(jh) || get_num(o, "sigma_h_m", &e),
                   ok_v = !jv || cJSON_IsNull(jv) || get_num(o, "sigma_v_m", &n);
        if (!id || !ok_h || !ok_v) {
            cJSON_Delete(o);
            return send_error(c, MHD_HTTP_BAD_REQUEST,
                              "expected {\"landmark\": ID, \"sigma_h_m\": m or null, \"sigma_v_m\": m or null}");
        }
        st = rs_pick_set_sigma(srv->session, id, cJSON_IsNumber(jh) ? e : NAN, cJSON_IsNumber(jv) ? n : NAN, &err);
    } else if (!strcmp(url, "/api/import")) {
        const char *name = get_str(o, "name"), *text = NULL;
        const cJSON *t = cJSON_GetObjectItemCaseSensitive(o, "text");
        if (cJSON_IsString(t)) text = t->valuestring;
        int Nadded = 0, Npicked = 0;
        if (!name || !text) {
            cJSON_Delete(o);
            return send_error(c, MHD_HTTP_BAD_REQUEST,
                              "expected {\"name\": \"pairs.json\" or \".csv\", \"text\": ...}");
        }
        st = import_text(srv, name, text, &Nadded, &Npicked, &err);
    } else if (!strcmp(url, "/api/landmark/move")) {
        if (!id || !en_of(srv, o, &e, &n)) {
            cJSON_Delete(o);
            return send_error(c, MHD_HTTP_BAD_REQUEST,
                              "expected {\"landmark\": ID, \"e\": m, \"n\": m} or \"lat\", \"lon\"");
        }
        st = rs_pick_move_landmark(srv->session, id, e, n, &err);
    } else if (!strcmp(url, "/api/landmark")) {
        const bool has_u = get_num(o, "u", &u), has_v = get_num(o, "v", &v);
        if (!en_of(srv, o, &e, &n) || has_u != has_v) {
            cJSON_Delete(o);
            return send_error(
                c, MHD_HTTP_BAD_REQUEST,
                "expected {\"e\": m, \"n\": m} or {\"lat\": deg, \"lon\": deg}, and optionally \"u\", \"v\" px");
        }
        st = rs_pick_add_landmark(srv->session, added, e, n, &err);
        if (!st && has_u) {
            st = rs_pick_set(srv->session, added, u, v, &err);
            if (st) (void)rs_pick_undo(srv->session, NULL); // the pair or nothing
        }
    } else if (!strcmp(url, "/api/undo")) {
        st = rs_pick_undo(srv->session, &err);
    } else if (!strcmp(url, "/api/save")) {
        st = rs_pick_save(srv->session, &err);
    } else {
        cJSON_Delete(o);
        return send_error(c, MHD_HTTP_NOT_FOUND, "%s: no such endpoint", url);
    }
    cJSON_Delete(o);
    // a save refused because the site changed on disk, or another save holds it: 409 Conflict
    if (st == RS_ERR_INVALID && !strcmp(url, "/api/save")) return send_error(c, MHD_HTTP_CONFLICT, "%s", err.msg);
    if (st) return send_error(c, status_of(st), "%s", err.msg[0] ? err.msg : rs_strerror(st));
    ret = send_state(c, srv);
    return ret;
}

static enum MHD_Result get(struct MHD_Connection *c, rs_pick_server *srv, const char *url)
{
    if (!strcmp(url, "/api/state")) return send_state(c, srv);
    if (!strcmp(url, "/api/map")) {
        return send_bytes(c, MHD_HTTP_OK, "application/json", srv->map_json, strlen(srv->map_json),
                          MHD_RESPMEM_PERSISTENT);
    }
    if (!strcmp(url, "/api/image.rgb")) {
        if (!srv->image) return send_error(c, MHD_HTTP_NOT_FOUND, "no camera image");
        return send_bytes(c, MHD_HTTP_OK, "application/octet-stream", srv->image,
                          (size_t)srv->image_w * srv->image_h * 3, MHD_RESPMEM_PERSISTENT);
    }
    int level, tx, ty, end = 0;
    if (sscanf(url, "/api/tiles/%d/%d/%d%n", &level, &tx, &ty, &end) == 3 && url[end] == '\0') {
        if (!srv->ortho) return send_error(c, MHD_HTTP_NOT_FOUND, "no orthophoto");
        rs_err err = {0};
        rs_status st = rs_geo_tiles_read(srv->ortho, level, tx, ty, srv->tile, &err);
        if (st) return send_error(c, st == RS_ERR_EXTERNAL ? MHD_HTTP_BAD_GATEWAY : MHD_HTTP_NOT_FOUND, "%s", err.msg);
        return send_bytes(c, MHD_HTTP_OK, "application/octet-stream", srv->tile,
                          (size_t)RS_GEO_TILE_PX * RS_GEO_TILE_PX * 4, MHD_RESPMEM_MUST_COPY);
    }
    if (!strcmp(url, "/api/export.json") || !strcmp(url, "/api/export.csv")) {
        const bool csv = !strcmp(url, "/api/export.csv");
        char *text = rs_pick_export(srv->session, csv);
        if (!text) return send_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, "out of memory");
        enum MHD_Result r = send_bytes(c, MHD_HTTP_OK, csv ? "text/csv" : "application/json", text, strlen(text),
                                       MHD_RESPMEM_MUST_COPY);
        free(text);
        return r;
    }
    for (int i = 0; i < rs_pick_Nassets; i++)
        if (!strcmp(url, rs_pick_assets[i].path))
            return send_bytes_csp(c, MHD_HTTP_OK, rs_pick_assets[i].mime, rs_pick_assets[i].data, rs_pick_assets[i].len,
                                  MHD_RESPMEM_PERSISTENT, srv->csp);
    return send_error(c, MHD_HTTP_NOT_FOUND, "%s: not found", url);
}

static enum MHD_Result handle(void *cls, struct MHD_Connection *c, const char *url, const char *method,
                              const char *version, const char *upload_data, size_t *upload_data_size, void **con_cls)
{
    (void)version;
    rs_pick_server *srv = cls;
    request *rq = *con_cls;
    if (!rq) { // the headers: check them before any body is read
        rq = calloc(1, sizeof *rq);
        if (!rq) return MHD_NO;
        *con_cls = rq;
        // DNS rebinding: the Host must be this server's own address
        if (!header_is(c, MHD_HTTP_HEADER_HOST, srv->host_ok, 2))
            return send_error(c, MHD_HTTP_FORBIDDEN, "Host refused: this server answers only to %s", srv->url);
        // cross-site requests: an Origin, when sent, must be this server's; a POST must send one
        const char *origin = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Origin");
        const bool is_post = !strcmp(method, MHD_HTTP_METHOD_POST);
        if ((origin || is_post) && !header_is(c, "Origin", srv->origin_ok, 2))
            return send_error(c, MHD_HTTP_FORBIDDEN, "Origin refused: only the page served by %s may call the API",
                              srv->url);
        if (!is_post && strcmp(method, MHD_HTTP_METHOD_GET) != 0)
            return send_error(c, MHD_HTTP_METHOD_NOT_ALLOWED, "only GET and POST");
        const char *cl = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_LENGTH);
        if (cl && strtoull(cl, NULL, 10) > srv->max_body)
            return send_error(c, MHD_HTTP_CONTENT_TOO_LARGE, "body over %zu bytes", srv->max_body);
        return MHD_YES;
    }
    if (*upload_data_size) { // a part of the body
        if (!rq->too_big && rq->len + *upload_data_size <= srv->max_body) {
            char *b = realloc(rq->body, rq->len + *upload_data_size + 1);
            if (!b) return MHD_NO;
            memcpy(b + rq->len, upload_data, *upload_data_size);
            rq->body = b;
            rq->len += *upload_data_size;
            b[rq->len] = '\0';
        } else {
            rq->too_big = true; // read and dropped: the answer is 413
        }
        *upload_data_size = 0;
        return MHD_YES;
    }
    if (rq->too_big) return send_error(c, MHD_HTTP_CONTENT_TOO_LARGE, "body over %zu bytes", srv->max_body);
    if (!strcmp(method, MHD_HTTP_METHOD_POST)) return post(c, srv, url, rq);
    return get(c, srv, url);
}

// ---- start and stop ----

// The map: the orthophoto's grid (or null) and the lanes' centre lines and widths, site ENU.
static char *map_json(const rs_site *site, rs_geo_tiles *ortho, const rs_pick_server_options *opt)
{
    cJSON *root = cJSON_CreateObject();
    if (!root) return NULL;
    if (ortho) {
        const rs_geo_grid *grid = rs_geo_tiles_grid(ortho);
        cJSON *g = cJSON_AddObjectToObject(root, "ortho");
        cJSON_AddNumberToObject(g, "width", grid->width);
        cJSON_AddNumberToObject(g, "height", grid->height);
        cJSON_AddNumberToObject(g, "e0_m", grid->e0_m);
        cJSON_AddNumberToObject(g, "n0_m", grid->n0_m);
        cJSON_AddNumberToObject(g, "cell_m", grid->cell_m);
        cJSON_AddNumberToObject(g, "levels", rs_geo_tiles_levels(ortho));
        cJSON_AddNumberToObject(g, "tile_px", RS_GEO_TILE_PX);
        cJSON_AddStringToObject(g, "crs", rs_geo_tiles_crs_name(ortho));
        cJSON_AddBoolToObject(g, "warped", rs_geo_tiles_warped(ortho));
    } else {
        cJSON_AddNullToObject(root, "ortho");
    }
    if (opt->tiles_url) {
        cJSON *t = cJSON_AddObjectToObject(root, "tiles");
        cJSON_AddStringToObject(t, "url", opt->tiles_url);
        cJSON_AddStringToObject(t, "attribution", opt->tiles_attribution ? opt->tiles_attribution : "");
        cJSON_AddNumberToObject(t, "max_zoom", opt->tiles_max_zoom);
    } else {
        cJSON_AddNullToObject(root, "tiles");
    }
    // lat, lon <-> E, N near the origin for the page's readout and its web tiles: the origin and
    // the Jacobian d(E, N)/d(lon, lat) in metres per degree, by central differences of geo's exact
    // conversion (the linearisation is off by ~d^2 / R: 1.4 cm at 300 m; typed coordinates are
    // converted exactly by the server)
    const double d = 1e-4, o[3] = {site->origin.lat_deg, site->origin.lon_deg, site->origin.h_m};
    const double llh[12] = {o[0], o[1] + d, o[2], o[0], o[1] - d, o[2], o[0] + d, o[1], o[2], o[0] - d, o[1], o[2]};
    double p[12];
    cJSON *geo = cJSON_AddObjectToObject(root, "geo");
    if (rs_geo_llh_to_enu(p, &site->origin, llh, 4, NULL) == RS_OK) {
        cJSON_AddNumberToObject(geo, "lat0", o[0]);
        cJSON_AddNumberToObject(geo, "lon0", o[1]);
        const double J[4] = {(p[0] - p[3]) / (2 * d), (p[6] - p[9]) / (2 * d), (p[1] - p[4]) / (2 * d),
                             (p[7] - p[10]) / (2 * d)};
        cJSON_AddItemToObject(geo, "den_dlonlat",
                              cJSON_CreateDoubleArray(J, 4)); // [dE/dlon, dE/dlat, dN/dlon, dN/dlat]
    }
    cJSON *la = cJSON_AddArrayToObject(root, "lanes");
    char *path = rs_io_join(site->dir, RS_SITE_LANES);
    rs_lanes lanes = {0};
    if (path && access(path, F_OK) == 0 && rs_lanes_read(&lanes, path, site, NULL) == RS_OK) {
        for (int i = 0; i < lanes.N; i++) {
            cJSON *l = cJSON_CreateObject();
            cJSON_AddItemToArray(la, l);
            cJSON_AddNumberToObject(l, "width_m", lanes.lane[i].width_m);
            cJSON_AddBoolToObject(l, "junction", lanes.lane[i].kind && !strcmp(lanes.lane[i].kind, "junction"));
            cJSON *pts = cJSON_AddArrayToObject(l, "en_m");
            for (int k = 0; k < lanes.lane[i].Npoints; k++) {
                const double en[2] = {lanes.lane[i].p_enu_m[k][0], lanes.lane[i].p_enu_m[k][1]};
                cJSON_AddItemToArray(pts, cJSON_CreateDoubleArray(en, 2));
            }
        }
    }
    rs_lanes_free(&lanes);
    free(path);
    char *text = cJSON_PrintUnformatted(root);
    cJSON_Delete(root);
    return text;
}

// The origin "http(s)://host[:port]" of a tile URL template, for the page's CSP; false when the
// template is not http(s), lacks {z}, {x} or {y}, or holds characters that would break the policy.
static bool tile_origin(char *out, size_t n, const char *url)
{
    const char *rest = !strncmp(url, "https://", 8) ? url + 8 : !strncmp(url, "http://", 7) ? url + 7 : NULL;
    if (!rest || !strstr(url, "{z}") || !strstr(url, "{x}") || !strstr(url, "{y}") || strpbrk(url, " ;,'\"\\<>"))
        return false;
    const size_t host = strcspn(rest, "/?#");
    if (host == 0 || rest[host] != '/' || (size_t)(rest - url) + host >= n || strchr(rest, '@') ||
        memchr(rest, '{', host))
        return false;
    snprintf(out, n, "%.*s", (int)((size_t)(rest - url) + host), url);
    return true;
}

rs_status rs_pick_server_start(rs_pick_server **out, rs_pick_session *s, const rs_pick_server_options *opt_in,
                               rs_err *err)
{
    *out = NULL;
    rs_pick_server_options opt;
    if (opt_in)
        opt = *opt_in;
    else
        rs_pick_server_options_default(&opt);
    if (!opt.host) opt.host = "127.0.0.1";
    if (!opt.max_body) opt.max_body = 65536;
    if (opt.port < 0 || opt.port > 65535)
        return rs_err_set(err, RS_ERR_INVALID, "port %d: not in [0, 65535]", opt.port);
    struct sockaddr_in addr = {.sin_family = AF_INET, .sin_port = htons((uint16_t)opt.port)};
    if (strlen(opt.host) >= 64 || inet_pton(AF_INET, opt.host, &addr.sin_addr) != 1)
        return rs_err_set(err, RS_ERR_INVALID, "host '%s': expected an IPv4 address such as 127.0.0.1", opt.host);
    rs_pick_server *srv = calloc(1, sizeof *srv);
    if (!srv) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    srv->session = s;
    srv->max_body = opt.max_body;
    srv->ortho = opt.ortho;
    char origin[256] = "";
    if (opt.tiles_url && !tile_origin(origin, sizeof origin, opt.tiles_url)) {
        free(srv);
        return rs_err_set(
            err, RS_ERR_INVALID,
            "tiles '%.200s': expected http(s)://HOST[:PORT]/...{z}...{x}...{y}... (no quote, space or ';')",
            opt.tiles_url);
    }
    snprintf(srv->csp, sizeof srv->csp, RS_PICK_CSP, origin[0] ? " " : "", origin);
    srv->tile = malloc((size_t)RS_GEO_TILE_PX * RS_GEO_TILE_PX * 4);
    snprintf(srv->host, sizeof srv->host, "%s", opt.host);
    rs_status st = RS_OK;
    const rs_site *site = rs_pick_session_site(s);
    const rs_camera *cam = &site->cameras[rs_pick_session_camera(s)].camera;
    if (opt.image_path) {
        rs_image img = {0};
        // the camera's size checked against the file's header, before decoding
        if ((st = cam->width > 0 ? rs_image_read_sized(&img, opt.image_path, cam->width, cam->height, err)
                                 : rs_image_read(&img, opt.image_path, err))) {
            free(srv);
            return st;
        }
        srv->image = malloc((size_t)img.width * img.height * 3);
        if (srv->image) {
            srv->image_w = img.width, srv->image_h = img.height;
            for (size_t p = 0; p < (size_t)img.width * img.height; p++)
                for (int k = 0; k < 3; k++) {
                    const float x = img.data[p * img.channels + (img.channels >= 3 ? k : 0)];
                    srv->image[3 * p + k] = (unsigned char)lrintf(255.0f * (x < 0 ? 0 : x > 1 ? 1 : x));
                }
        }
        rs_image_free(&img);
        if (!srv->image) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    if (!st && srv->image && cam->width > 0 && (srv->image_w != cam->width || srv->image_h != cam->height))
        st = rs_err_set(err, RS_ERR_INVALID, "%s: the image is %dx%d, camera %s is %dx%d", opt.image_path, srv->image_w,
                        srv->image_h, site->cameras[rs_pick_session_camera(s)].id, cam->width, cam->height);
    if (!st && !srv->tile) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st && !(srv->map_json = map_json(site, opt.ortho, &opt))) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) {
        // under load (issue 42: 64 slow connections locked the user out for as long as they lasted):
        // poll rather than select (no FD_SETSIZE ceiling; epoll mishandled half-closed clients:
        // tests/pick pick_fuzz went from 1 s to over 120 s), room for many more connections
        // than one client may hold, and a client idle for CONNECTION_TIMEOUT_S (headers never
        // finished) is dropped
        srv->daemon = MHD_start_daemon(MHD_USE_POLL_INTERNAL_THREAD, (uint16_t)opt.port, NULL, NULL, handle, srv,
                                       MHD_OPTION_SOCK_ADDR, (struct sockaddr *)&addr, MHD_OPTION_NOTIFY_COMPLETED,
                                       request_done, NULL, MHD_OPTION_CONNECTION_LIMIT, (unsigned)CONNECTION_LIMIT,
                                       MHD_OPTION_PER_IP_CONNECTION_LIMIT, (unsigned)PER_CLIENT_CONNECTION_LIMIT,
                                       MHD_OPTION_CONNECTION_TIMEOUT, (unsigned)CONNECTION_TIMEOUT_S, MHD_OPTION_END);
        if (!srv->daemon) st = rs_err_set(err, RS_ERR_IO, "cannot listen on %s:%d (in use?)", opt.host, opt.port);
    }
    if (!st) {
        const union MHD_DaemonInfo *info = MHD_get_daemon_info(srv->daemon, MHD_DAEMON_INFO_BIND_PORT);
        srv->port = info ? info->port : opt.port;
        snprintf(srv->url, sizeof srv->url, "http://%s:%d/", srv->host, srv->port);
        snprintf(srv->host_ok[0], sizeof srv->host_ok[0], "%s:%d", srv->host, srv->port);
        snprintf(srv->origin_ok[0], sizeof srv->origin_ok[0], "http://%s:%d", srv->host, srv->port);
        if (!strcmp(srv->host, "127.0.0.1")) {
            snprintf(srv->host_ok[1], sizeof srv->host_ok[1], "localhost:%d", srv->port);
            snprintf(srv->origin_ok[1], sizeof srv->origin_ok[1], "http://localhost:%d", srv->port);
        }
    }
    if (st) {
        rs_pick_server_stop(srv);
        return st;
    }
    *out = srv;
    return RS_OK;
}

int rs_pick_server_port(const rs_pick_server *srv) { return srv->port; }
const char *rs_pick_server_url(const rs_pick_server *srv) { return srv->url; }

void rs_pick_server_stop(rs_pick_server *srv)
{
    if (!srv) return;
    if (srv->daemon) MHD_stop_daemon(srv->daemon);
    free(srv->image);
    free(srv->map_json);
    free(srv->tile);
    free(srv);
}

// rs_pick.h -- survey onboarding in the browser (`roadside pick`, docs/pick.md): a session that
// holds one camera's picks and the site's landmarks, re-solved with the calibration's own solver
// after every change, and the local HTTP server (libmicrohttpd) that serves the page and its
// JSON API.
//
// The session: the site as rs_site_load read it (geo/rs_site.h); its camera's observations and
// the landmarks are edited in memory: a pick is set (added or moved) or deleted for a landmark,
// a landmark is added where the surveyor clicked the map (its up on the site's ground plane, its
// sigmas the site's defaults). After every change the camera is re-solved exactly as `roadside
// calib` does: rs_calib_site_problem_init (calib/rs_calib_site.h) and rs_calib_solve with
// rs_calib_options_default (no intrinsics refined), from four picks on. A pick is rounded to
// 1e-6 px when it is set, the resolution the observations file keeps, so the saved files give
// calib the same problem. Save writes landmarks.geojson, then the camera's observations CSV,
// each atomically through geo/rs_site_write.h (a temporary name, then rename): a kill at any
// moment leaves each file either the old or the new one, and since landmarks are only ever
// added, old observations with new landmarks are a consistent site. Then the site is read back
// from disk and re-solved, so the pose shown is the pose `roadside calib` finds.
//
// The server (rs_pick_server_start): binds host:port (127.0.0.1 by default), one thread polling
// all connections (so the session is never used by two requests at once). Security (docs/pick.md,
// "Security"): a request whose Host header is not the server's own address is refused (403: DNS
// rebinding), a POST whose Origin is not the server's own origin, or absent, is refused (403:
// cross-site requests), a body over max_body bytes is refused (413), a body that is not a JSON
// object of the expected fields is refused (400), and no request ever names a file: the files
// are the site's, fixed when the session is opened.
#pragma once
#include <stdbool.h>
#include <stddef.h>

#include "core/rs_status.h"
#include "geo/rs_geo_raster.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct rs_pick_session rs_pick_session;

// Opens the site folder and selects camera camera_id; solves the picks it already has.
// out: *s (rs_pick_session_free)
// Errors: those of rs_site_load, RS_ERR_NOT_FOUND (no such camera), RS_ERR_NOMEM.
rs_status rs_pick_session_open( // out
    rs_pick_session **s,
    // in
    const char *site_dir, const char *camera_id, rs_err *err);
void rs_pick_session_free(rs_pick_session *s); // NULL-safe

// Sets camera's pick of landmark `id` to (u, v) px (added, or moved when it has one); re-solves.
// RS_ERR_NOT_FOUND (no such landmark), RS_ERR_INVALID (non-finite, or outside the image by more
// than one image size).
rs_status rs_pick_set(rs_pick_session *s, const char *id, double u_px, double v_px, rs_err *err);
// Deletes the pick of landmark `id`; re-solves. RS_ERR_NOT_FOUND when it has none.
rs_status rs_pick_delete(rs_pick_session *s, const char *id, rs_err *err);
// Adds a landmark at (e, n) metres of the site's ENU frame on the ground plane, id "P<k>" (the
// first free k); re-solves. id_out (may be NULL) receives the id. RS_ERR_INVALID for a point
// farther than the site's max_landmark_distance_m from the origin or not finite.
rs_status rs_pick_add_landmark(rs_pick_session *s, char id_out[32], double e_m, double n_m, rs_err *err);
// Undoes the last change (pick set, pick deleted, landmark added); re-solves. RS_ERR_NOT_FOUND
// when there is nothing to undo. Undo reaches back over saves.
rs_status rs_pick_undo(rs_pick_session *s, rs_err *err);
// Sets what every re-solve refines besides the pose, in the words of `calib --refine` ("focal",
// "center", "focal+center", "none" or ""; rs_calib_refine_parse); re-solves. Not an undo step, not
// saved (it is calib's option, not the site's). RS_ERR_INVALID on an unknown word.
rs_status rs_pick_set_refine(rs_pick_session *s, const char *words, rs_err *err);
// Moves landmark `id` to (e, n) metres of the site's ENU on the ground plane; re-solves. Only a
// landmark picked on the map (kind "map-pick") moves: RS_ERR_UNSUPPORTED for a surveyed one,
// RS_ERR_NOT_FOUND, RS_ERR_INVALID (farther than max_landmark_distance_m, not finite).
rs_status rs_pick_move_landmark(rs_pick_session *s, const char *id, double e_m, double n_m, rs_err *err);
// Gives landmark `id` sigmas of its own (1-sigma horizontal per axis and vertical, metres, in
// the site format's range), or NAN: back to site.json's site-wide value (then not saved with the
// landmark); re-solves; an undo step. A modelled height keeps the ground model's vertical sigma
// in the solve (the stated one is saved). RS_ERR_NOT_FOUND, RS_ERR_INVALID (out of range).
rs_status rs_pick_set_sigma(rs_pick_session *s, const char *id, double sigma_h_m, double sigma_v_m, rs_err *err);
// Imports a point-pair file (`roadside site import`'s reader, geo/rs_site_import.h: a point-pair
// JSON or a lat,lon,u,v CSV): each pair's landmark id that the site has gets that pick (added or
// moved); a new id becomes a landmark (kind "map-pick") at its lat, lon on the site's ground
// plane (a given height is not used) with its pick. All or nothing; one undo step.
// out: Nadded, Npicked: landmarks added, picks set
// Errors: those of the reader ("PATH:LINE: FIELD: what"), RS_ERR_INVALID (e,n columns: no CRS
// here), those of rs_pick_set / rs_pick_add_landmark with the file's line.
rs_status rs_pick_import( // out
    rs_pick_session *s, int *Nadded, int *Npicked,
    // in
    const char *path, rs_err *err);
// The camera's point picks as a point-pair file rs_pick_import (and `site import`) reads back:
// csv false: JSON {"results": [{"id", "x": u, "y": v, "lat", "lng"}, ...]}; true: CSV
// "id,lat,lon,u,v,sigma_px" (degrees to 1e-9, pixels to 1e-6). Caller frees; NULL: no memory.
char *rs_pick_export(const rs_pick_session *s, bool csv);

// Writes landmarks.geojson and the camera's observations (see above), reads the site back and
// re-solves. A landmark's sigma_h_m / sigma_v_m are written only when it had its own when read
// (rs_site_landmark.sigma_*_stated) or the page gave it some (rs_pick_set_sigma): the others keep
// following site.json's site-wide sigmas. Errors: those of the writers and of rs_site_load (the files are then written but
// the session keeps its own state).
rs_status rs_pick_save(rs_pick_session *s, rs_err *err);

// The state as JSON text (docs/pick.md, "API"): camera (id, image size), landmarks (id, kind,
// e/n/u, added or surveyed, pick, predicted pixel, residual, normalised residual, inlier, flag
// and its reason), the solve (status, message, rt_cam_enu, its covariance, position and its
// 2x2 E-N covariance, yaw/pitch/roll and sigmas, rms, variance factor, warnings, time), the
// ground uncertainty over the view, can_undo, unsaved changes. Caller frees; NULL: no memory.
char *rs_pick_state_json(const rs_pick_session *s);

// The wall time of the last re-solve (problem built, rs_calib_solve, predictions, ground
// uncertainty), milliseconds; NAN when none ran.
double rs_pick_last_solve_ms(const rs_pick_session *s);
// The number of picks of the session's camera.
int rs_pick_count(const rs_pick_session *s);

// ---- the server ----

typedef struct {
    const char *host;              // address to bind (default "127.0.0.1"); the Host header must name it
    int port;                      // 0: any free port
    size_t max_body;               // request bodies larger are refused with 413 (default 65536)
    const char *image_path;        // the camera image (PNG/JPEG; read by core); may be NULL: a grey canvas
    rs_geo_tiles *ortho;           // the orthophoto on the site's grid, served as tiles read at the
                                   //   view's resolution (GET /api/tiles/L/X/Y); may be NULL: none
                                   //   (borrowed: must outlive the server; used by its thread only)
    const char *tiles_url;         // a web tile URL template "http(s)://HOST/.../{z}/{x}/{y}.png"
                                   //   (web mercator) the page loads itself; may be NULL. The page's
                                   //   Content-Security-Policy allows images from that origin only
    const char *tiles_attribution; // shown under the map; may be NULL
    int tiles_max_zoom;            // the template's deepest zoom (default 19)
} rs_pick_server_options;
void rs_pick_server_options_default(rs_pick_server_options *opt);

typedef struct rs_pick_server rs_pick_server;

// Starts serving the session (borrowed: it must outlive the server) on its own thread.
// Errors: RS_ERR_IO (cannot bind; the message names host and port), those of reading the image,
// RS_ERR_INVALID (a tiles_url that is not http(s)://HOST/... with {z}, {x} and {y}).
rs_status rs_pick_server_start( // out
    rs_pick_server **srv,
    // in
    rs_pick_session *s, const rs_pick_server_options *opt, rs_err *err);
// The port bound, and the page's URL ("http://127.0.0.1:PORT/").
int rs_pick_server_port(const rs_pick_server *srv);
const char *rs_pick_server_url(const rs_pick_server *srv);
void rs_pick_server_stop(rs_pick_server *srv); // NULL-safe: stops and frees

struct cJSON;
// A POST body of the API as the server reads it: one JSON object (core/rs_json.h rs_json_parse:
// nothing but blanks after it), no NUL byte. out: *obj, owned by the caller (cJSON_Delete); NULL
// on failure. Errors: RS_ERR_PARSE with what is wrong ("the body is not a JSON object: ...").
rs_status rs_pick_request_parse( // out
    struct cJSON **obj,
    // in
    const char *body, size_t len, rs_err *err);

#ifdef __cplusplus
}
#endif

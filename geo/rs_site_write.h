// rs_site_write.h -- writing a site's files from C structs: site.json, landmarks.geojson and the
// observation CSVs, and recording a background image in site.json. With the reader
// (geo/rs_site.h) and lanes.geojson's reader and writer (geo/rs_lanes.h), geo is the only code
// that reads or writes these files (docs/site-format.md); `roadside site init`, `roadside site
// simulate` and the backgrounds of synth/ write through here.
//
// Every file is written atomically (rs_io_write_file: a temporary name, then rename), so an
// error or a crash never leaves a half-written file under the final name. JSON strings are
// escaped and numbers printed by cJSON (the shortest text that reads back as the same double;
// an integral value as an integer). Heights are written in the site's declared heights: the
// structs carry ellipsoidal heights where geo/rs_site.h's do, and the writer subtracts the
// geoid undulation N given to it (0 for an ellipsoidal site).
#pragma once
#include <stdbool.h>

#include "core/rs_status.h"
#include "geo/rs_geo.h"
#include "geo/rs_site.h"

#ifdef __cplusplus
extern "C" {
#endif

// How a JSON file is laid out. Both read back the same.
typedef enum {
    RS_SITE_LAYOUT_TOOL, // cJSON's indented layout: one member per line, indented with tabs
                         //   (what tools write and rewrite: `site simulate`, background records)
    RS_SITE_LAYOUT_HAND  // the layout of docs/site-format.md, for files people fill in: site.json
                         //   one top-level member per line (objects and lists inline, `": "` and
                         //   `", "` separators), one camera per entry with its id, model and
                         //   observations on the first line and every further member on a line of
                         //   its own; a FeatureCollection one feature per line
} rs_site_layout;

// One camera of site.json, as written (paths relative to the site folder).
typedef struct {
    const char *id;               // unique within the site
    const char *model;            // the intrinsics file, e.g. "cameras/<id>.cameramodel"
    const char *observations;     // the observations CSV, e.g. "observations/<id>.csv"
    const char *backgrounds;      // a folder of background images; may be NULL (not written)
    const rs_llh *position_prior; // surveyed camera position: lat_deg, lon_deg, h_m in the
                                  //   declared heights; may be NULL (no prior)
    double prior_sigma_m;         // 1-sigma of the prior per axis, metres, > 0 (with a prior)
    const char *note;             // may be NULL
} rs_site_spec_camera;

// Everything site.json says (docs/site-format.md "site.json"), as written.
typedef struct {
    const char *name;
    rs_llh origin;                    // lat_deg, lon_deg, h_m in the declared heights
    const double *geoid_undulation_m; // NULL: "heights": "ellipsoidal"; else
                                      //   {"orthometric": N} with N = *geoid_undulation_m, metres
    double landmark_sigma_h_m;        // site-wide 1-sigma of the landmarks, metres, > 0
    double landmark_sigma_v_m;
    rs_site_height landmark_heights;    // "landmark_heights"; RS_SITE_HEIGHT_DEFAULT: not written
    const double *ground_normal_enu;    // (3,) the ground plane n . p_enu = offset; may be NULL:
    double ground_offset_m;             //   no "ground_plane" (the default up = 0)
    double max_landmark_distance_m;     // > 0; 0: not written (the default 1000 m applies)
    const rs_site_spec_camera *cameras; // (Ncameras,) in order
    int Ncameras;
    const char *extra_name; // one more top-level member after "cameras", e.g.
    const char *extra_json; //   "simulated", and its value as JSON text; NULL: none
} rs_site_spec;

// Writes DIR/site.json. Members in the order of docs/site-format.md: name, origin, heights,
// landmark_sigma_m, landmark_heights, ground_plane, max_landmark_distance_m, cameras (id, model,
// observations, backgrounds, position_prior {lat, lon, h, sigma_m}, note), then the extra member.
// Returns RS_ERR_INVALID for a missing name or camera string or a non-finite number,
// RS_ERR_PARSE when extra_json is not JSON, RS_ERR_IO, RS_ERR_NOMEM.
rs_status rs_site_write_json( // in
    const char *dir, const rs_site_spec *spec, rs_site_layout layout, rs_err *err);

// Writes DIR/landmarks.geojson: a FeatureCollection of Point features (points and poles),
// coordinates [lon_deg, lat_deg, h_m] (RFC 7946 order; h = llh.h_m - geoid_undulation_m), and
// LineString features (lines), coordinates [[lon, lat, h], ...] from vertices_llh; properties id,
// then kind, sigma_h_m, sigma_v_m, (poles) height_m and sigma_height_m, height, above_ground_m
// and note where given (docs/site-format.md "Landmark kinds"). What is written
// is what was given: for a landmark whose height the ground model gave (height_modelled, as
// rs_site_load leaves it) the height is given_h_m and sigma_v_m given_sigma_v_m.
// in: landmarks (Nlandmarks,), may be NULL when Nlandmarks is 0: id, llh (ellipsoidal height,
//     as rs_site_load gives it; NAN, or a NAN given_h_m when modelled, writes [lon, lat] when
//     the height is unknown: height or height_stated RS_SITE_HEIGHT_UNKNOWN), kind and note
//     (NULL: not written), sigma_h_m and sigma_v_m (written only when finite and > 0: NAN means
//     the site-wide default), height_stated (properties.height; DEFAULT: not written),
//     above_ground_m (written when > 0); shape: POLE writes pole_height_m (in (0, 100] m, else
//     RS_ERR_INVALID) and sigma_pole_height_m (when finite and > 0); LINE writes vertices_llh
//     (Nvertices >= 2, else RS_ERR_INVALID), each vertex's height vertices_given_h_m when
//     height_modelled ([lon, lat] where it is NAN and the height unknown); feature, p_enu_m,
//     given_up_m, ground_used, vertices_enu_m and vertices_sigma_v_m are ignored
//     geoid_undulation_m: N of the site's "heights" (0 for an ellipsoidal site)
// Returns RS_ERR_INVALID (no id, a non-finite coordinate), RS_ERR_IO, RS_ERR_NOMEM.
rs_status rs_site_write_landmarks( // in
    const char *dir, const rs_site_landmark *landmarks, int Nlandmarks, double geoid_undulation_m,
    rs_site_layout layout, rs_err *err);

// Writes an observations CSV: the header "landmark,u,v,sigma_px", then one line per pick,
// "ID,u,v,sigma" with u and v to 1e-6 px ("%.6f") and sigma_px as "%g"; when some pick is of a
// pole or line (or its `at` is not POINT), the header "landmark,u,v,sigma_px,at" and each line
// ends ",AT" (rs_site_at_name: "point", "base", "top", "along").
// in: obs (Nobservations,), may be NULL when Nobservations is 0: ilandmark (an index into
//     landmarks, whose id is written), q_px, sigma_px, at; line is ignored
//     landmarks: the site's landmarks (only their ids and shapes are used)
// Returns RS_ERR_IO, RS_ERR_NOMEM.
rs_status rs_site_write_observations( // in
    const char *path, const rs_site_observation *obs, int Nobservations, const rs_site_landmark *landmarks,
    rs_err *err);

// The file of background `name` of camera `camera_id`, relative to the site folder:
// "backgrounds/<camera_id>/<name>.png". Malloc'ed (caller frees); NULL when out of memory.
char *rs_site_background_file(const char *camera_id, const char *name);

// Records a background in DIR/site.json (docs/backgrounds.md): the camera's
// "background_images" gets the entry
//   {"name": NAME, "file": rs_site_background_file(camera_id, NAME), "synthetic": bool,
//    "tags": {KEY: VALUE, ...}, "source": SOURCE}
// replacing the entry of the same name, else appended; the camera's "backgrounds" folder is set
// to "backgrounds/<camera_id>" when it has none. Tags are set in the order given, a key given
// twice keeping the last value (moved to the end). Everything else in site.json is kept as it
// was (member order included); the file is rewritten in RS_SITE_LAYOUT_TOOL.
// Validating names and tag values is the caller's (synth/backdrop/rs_synth_background.h).
// in: keys, values (Ntags,) text; source_json: how the image was made, any JSON value as text,
//     may be NULL (no "source")
// Returns RS_ERR_IO / RS_ERR_PARSE for site.json (or a source_json that is not JSON),
// RS_ERR_NOT_FOUND for an unknown camera, RS_ERR_NOMEM.
rs_status rs_site_record_background( // in
    const char *dir, const char *camera_id, const char *name, bool synthetic, const char *const *keys,
    const char *const *values, int Ntags, const char *source_json, rs_err *err);

#ifdef __cplusplus
}
#endif

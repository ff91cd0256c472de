// rs_site.h -- the site survey format: load a site folder, check it, create a skeleton.
//
// A site is a folder (docs/site-format.md describes it fully, with an example):
//
//   site.json                  name; origin {lat, lon, h}; heights ("ellipsoidal" or
//                              {"orthometric": N_m}); landmark_sigma_m {horizontal, vertical};
//                              optional ground_plane, max_landmark_distance_m; cameras[] (each
//                              with its files, optional prior, note and background_images)
//   landmarks.geojson          FeatureCollection of Point features [lon, lat, h] (RFC 7946
//                              order); properties: id (unique string), optional sigma_h_m,
//                              sigma_v_m, kind, note
//   cameras/<id>.cameramodel   intrinsics as an mrcal .cameramodel (or OpenCV-style .yaml/.yml/
//                              .json: image_width, image_height, camera_matrix,
//                              distortion_coefficients)
//   observations/<id>.csv      header "landmark,u,v[,sigma_px]": pixel picks of landmarks
//   backgrounds/<id>/...       optional background images
//
// Conventions (docs/conventions.md): geodetic llh = (lat_deg, lon_deg, h_m) on WGS84; every
// height in a site follows its "heights" declaration and is converted on load to ellipsoidal
// (h_ell = h_orth + N for {"orthometric": N}); the site ENU frame is GeographicLib's
// LocalCartesian at the origin (x east, y north, z up, metres), computed by rs_geo_llh_to_enu;
// pixel (0,0) is the centre of the top-left pixel, so a pixel lies inside a W x H image when
// u in [-0.5, W-0.5] and v in [-0.5, H-0.5].
//
// One reader serves both entry points. rs_site_check() reads everything it can and collects
// every problem as a diagnostic; rs_site_load() runs the same reader and succeeds only when
// there is no error-severity diagnostic (warnings are allowed), so a site that loads is exactly
// a site that `roadside site check` passes. Which problems are errors and which are warnings is
// listed in docs/site-format.md ("What site check reports").
//
// The reader is geo/rs_site_read.c (and the files it calls, geo/internal/rs_site_internal.h);
// the writers are geo/rs_site_write.h. No other module reads or writes these files.
//
// Accuracy: landmark and prior ENU coordinates are those of rs_geo_llh_to_enu (nanometres);
// no rounding happens in between (JSON numbers are read as doubles).
#pragma once
#include <stdbool.h>
#include <stddef.h>

#include "core/rs_camera.h"
#include "core/rs_status.h"
#include "geo/rs_geo.h"

#ifdef __cplusplus
extern "C" {
#endif

// What a site may state, checked by the reader (rs_site_check refuses values outside, naming the
// landmark and field): physical ranges, not tuning. A survey sigma under 1 mm is better than any
// survey of a road feature and one over 100 m is no survey; a pick sigma under 0.01 px is beyond
// any corner detector and one over 1000 px is no pick; a height outside [-1000, 10000] m
// (ellipsoidal or orthometric) is not near the Earth's surface (Dead Sea shore -430 m, geoid
// -106..+85 m, Everest 8849 m). Landmarks closer than RS_SITE_COINCIDENT_M to each other are
// reported as coincident (a warning: a copied coordinate, most often).
#define RS_SITE_SURVEY_SIGMA_MIN_M 1e-3
#define RS_SITE_SURVEY_SIGMA_MAX_M 100.0
#define RS_SITE_PIXEL_SIGMA_MIN_PX 1e-2
#define RS_SITE_PIXEL_SIGMA_MAX_PX 1000.0
#define RS_SITE_PRIOR_SIGMA_MIN_M  1e-3
#define RS_SITE_PRIOR_SIGMA_MAX_M  1e5
#define RS_SITE_HEIGHT_MIN_M       (-1000.0)
#define RS_SITE_HEIGHT_MAX_M       10000.0
#define RS_SITE_COINCIDENT_M       1e-3

// A surveyed landmark, in the site ENU frame.
typedef struct {
    char *id;          // owned; unique within the site
    int feature;       // index in landmarks.geojson's "features" (from 0)
    rs_llh llh;        // as surveyed, height converted to ellipsoidal
    double p_enu_m[3]; // (3,) east, north, up, metres
    double sigma_h_m;  // 1-sigma horizontal uncertainty (per axis), metres, > 0
    double sigma_v_m;  // 1-sigma vertical uncertainty, metres, > 0
    char *kind;        // owned, may be NULL (free-form: "road-marking", "pole-base", ...)
    char *note;        // owned, may be NULL
} rs_site_landmark;

// One pixel pick of a landmark in one camera.
typedef struct {
    int ilandmark;   // index into rs_site.landmarks
    double q_px[2];  // (2,) u, v in pixels, (0,0) = centre of the top-left pixel
    double sigma_px; // 1-sigma pick uncertainty per axis, pixels, > 0 (default 1.0)
    int line;        // line number in the observations CSV (from 1), for messages
} rs_site_observation;

// One tag of a background image: key = value, both text.
typedef struct {
    char *key;   // owned
    char *value; // owned; a JSON boolean reads as "true" / "false"
} rs_site_tag;

// A background image of a camera's empty scene: one entry of the camera's "background_images"
// in site.json (docs/backgrounds.md), as `roadside background` and `roadside site
// render-backgrounds` record it (rs_site_record_background, geo/rs_site_write.h).
typedef struct {
    char *name;        // owned; may be NULL (the entry gives none)
    char *file;        // owned; as written in site.json, relative to the site folder
    char *path;        // owned; `file` joined to the site folder
    bool synthetic;    // rendered, not photographed (default false)
    rs_site_tag *tags; // owned, (Ntags,) in file order: "time" (ISO 8601 with a zone),
    int Ntags;         //   "conditions" (sunny, cloudy, rain, snow, night) and free tags;
                       //   tags that are neither text nor boolean are skipped (a warning)
} rs_site_background;

typedef struct {
    char *id;                // owned; unique within the site
    char *model_path;        // owned; path of the intrinsics file (site folder joined)
    char *observations_path; // owned; path of the observations CSV
    char *backgrounds_path;  // owned; may be NULL (no "backgrounds" given)
    char *note;              // owned; may be NULL

    rs_site_background *background_images; // owned, (Nbackground_images,) in site.json order
    int Nbackground_images;

    rs_camera camera; // owned: the nominal lens model, intrinsics and image size
                      //   (OpenCV files are converted); pose zero. Zeroed (no
                      //   intrinsics, size 0 x 0) when the model file is unusable

    rs_site_observation *observations; // owned, (Nobservations,)
    int Nobservations;

    bool has_position_prior; // a surveyed camera position was given
    rs_llh prior_llh;        // height ellipsoidal; valid if has_position_prior
    double prior_p_enu_m[3]; // (3,) prior position in ENU, metres
    double prior_sigma_m;    // 1-sigma of the prior per axis, metres, > 0
} rs_site_camera;

typedef struct {
    char *dir;                      // owned; the site folder as given
    char *name;                     // owned
    rs_llh origin;                  // ENU origin, height converted to ellipsoidal
    bool heights_orthometric;       // the site's heights were declared orthometric
    double geoid_undulation_m;      // N: h_ell = h_orth + N (0 for ellipsoidal sites)
    double landmark_sigma_h_m;      // site-wide default 1-sigma, horizontal, metres
    double landmark_sigma_v_m;      // site-wide default 1-sigma, vertical, metres
    double ground_normal_enu[3];    // (3,) unit normal of the ground plane n . p_enu = offset
    double ground_offset_m;         // (default: n = (0,0,1), offset 0, i.e. up = 0)
    double max_landmark_distance_m; // check warns about landmarks farther (default 1000)

    rs_site_landmark *landmarks; // owned, (Nlandmarks,) in file order
    int Nlandmarks;
    rs_site_camera *cameras; // owned, (Ncameras,) in site.json order
    int Ncameras;
} rs_site;

// Loads and validates a site folder. Succeeds only if rs_site_check() would report no error.
//
// out:  *out, the site, owned by the caller (rs_site_free); NULL on failure
// in:   dir: the site folder
// err:  may be NULL; on failure the FIRST error, "FILE:LINE: FIELD: what" (run rs_site_check
//       for all of them)
// Returns RS_OK, or the status of the first error: RS_ERR_IO (missing or unreadable file),
// RS_ERR_PARSE (malformed JSON/GeoJSON/CSV/model), RS_ERR_INVALID (well-formed but wrong),
// RS_ERR_NOT_FOUND (an observation of an unknown landmark), RS_ERR_UNSUPPORTED (OpenCV
// intrinsics with no mrcal equivalent), RS_ERR_NOMEM.
rs_status rs_site_load( // out
    rs_site **out,
    // in
    const char *dir, rs_err *err);

// Frees a site and everything it owns. Accepts NULL.
void rs_site_free(rs_site *site);

// Index of the camera / landmark with this id, or -1 if there is none. Linear search.
int rs_site_find_camera(const rs_site *site, const char *id);
int rs_site_find_landmark(const rs_site *site, const char *id);

// The value a background has for `key`: its tag `key` if it has one, else its own "name",
// "file" (as written in site.json) or "synthetic" ("true" / "false"); NULL if none of these.
// What `roadside synth --backgrounds KEY=VALUE` matches. The pointer is the background's own
// (or a static string); valid while the site is.
const char *rs_site_background_tag(const rs_site_background *bg, const char *key);

// Axis-aligned ENU extent and the range of distances from the origin of a set of landmarks:
// all of them (icam < 0) or those observed by camera icam.
// out:  min_enu_m, max_enu_m: (3,) each; dmin_m, dmax_m: metres (any may be NULL)
// Returns the number of landmarks in the set (0: outputs untouched).
int rs_site_landmark_extent( // out
    double *min_enu_m,
    double *max_enu_m, // (3,) each, may be NULL
    double *dmin_m,
    double *dmax_m, // may be NULL
    // in
    const rs_site *site, int icam);

// ---- checking ----

typedef enum { RS_SITE_ERROR, RS_SITE_WARNING } rs_site_severity;

// One problem found in a site.
typedef struct {
    rs_site_severity severity;
    rs_status status; // the status rs_site_load returns for this problem (RS_OK for warnings)
    char *file;       // owned; path of the file at fault (site folder joined), never NULL
    int line;         // line in that file (from 1), 0 if none applies
    int feature;      // GeoJSON feature index (from 0), -1 if none applies
    char *feature_id; // owned; that feature's id, may be NULL
    char *field;      // owned; the field at fault ("coordinates", "cameras[1].model", "u"),
                      // may be NULL
    char *message;    // owned; what is wrong and, where known, what it should be
} rs_site_diag;

typedef struct {
    rs_site_diag *diags; // owned, (N,) in the order found: site.json, landmarks, cameras
    int N;
    int Nerrors, Nwarnings;
} rs_site_report;

// Reads the site folder and collects ALL problems, not just the first. Never stops at a bad
// file: whatever can still be checked is checked (e.g. observations are checked against the
// landmarks even when the camera model is missing).
//
// out:  *report, owned by the caller (rs_site_report_free); never NULL on RS_OK
// in:   dir: the site folder
// Returns RS_OK whenever the check itself ran (whatever it found: look at Nerrors), or
// RS_ERR_NOMEM.
rs_status rs_site_check( // out
    rs_site_report **report,
    // in
    const char *dir, rs_err *err);

void rs_site_report_free(rs_site_report *report); // accepts NULL

// Formats one diagnostic on one line, without a newline:
//   "FILE[:LINE]: [feature F (id 'ID'): ][FIELD: ]MESSAGE"
// in the size-limited manner of snprintf. Returns the length the full text needs.
int rs_site_diag_format( // out
    char *buf, size_t size,
    // in
    const rs_site_diag *diag);

// ---- creating ----
//
// Writing a site's files from C structs (site.json, landmarks.geojson, observation CSVs) and
// recording a background in site.json: geo/rs_site_write.h; lanes.geojson: geo/rs_lanes.h.

// Creates a skeleton site folder `dir`: site.json (with the given name, origin and heights, and
// one example camera "cam1" to rename), an empty landmarks.geojson FeatureCollection, cameras/,
// observations/ (with a header-only cam1.csv), backgrounds/cam1/, and a README.md telling the
// surveyor what to fill in. The skeleton does NOT pass rs_site_check until filled in: it lacks
// landmarks, cameras/cam1.cameramodel and cam1's observations.
//
// in:  dir: the folder to create; it must not exist or be empty (else RS_ERR_INVALID)
//      name: the site name (JSON-escaped on output)
//      origin: lat_deg in [-90, 90], lon_deg in [-180, 180], h_m in the declared heights
//      geoid_undulation_m: NULL for ellipsoidal heights, else N of {"orthometric": N}
// Every file is written atomically (rs_io_write_file).
rs_status rs_site_init(const char *dir, const char *name, const rs_llh *origin,
                       const double *geoid_undulation_m, // may be NULL
                       rs_err *err);

#ifdef __cplusplus
}
#endif

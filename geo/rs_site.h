// rs_site.h -- the site survey format: load a site folder, check it, create a skeleton.
//
// A site is a folder (docs/site-format.md describes it fully, with an example):
//
//   site.json                  name; origin {lat, lon, h}; heights ("ellipsoidal" or
//                              {"orthometric": N_m}); landmark_sigma_m {horizontal, vertical};
//                              optional landmark_heights ("surveyed", "unreliable", "unknown"),
//                              ground_plane, max_landmark_distance_m; cameras[] (each
//                              with its files, optional prior, note and background_images)
//   landmarks.geojson          FeatureCollection of Point features [lon, lat, h] (RFC 7946
//                              order; [lon, lat] where the height is unknown); properties: id
//                              (unique string), optional sigma_h_m, sigma_v_m, height,
//                              above_ground_m, kind, note; a Point with height_m (and optional
//                              sigma_height_m) is a pole; LineString features are lines
//                              (rs_site_shape below)
//   cameras/<id>.cameramodel   intrinsics as an mrcal .cameramodel (or OpenCV-style .yaml/.yml/
//                              .json: image_width, image_height, camera_matrix,
//                              distortion_coefficients)
//   observations/<id>.csv      header "landmark,u,v[,sigma_px][,at]": pixel picks of landmarks
//                              (at: where on a pole or line, rs_site_at below)
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
// Heights a survey does not have: a site may say that its landmark heights are "unreliable"
// (given but noisy: raw GNSS) or "unknown" (points picked on imagery), site-wide or per landmark.
// Those heights then come from the site's ground model (rs_site_ground_model below,
// geo/rs_site_ground.c), fitted at load time to the heights that are reliable, with the model's
// own uncertainty as their vertical sigma. A site that says nothing is read as before: every
// height surveyed, no model.
//
// Accuracy: landmark and prior ENU coordinates are those of rs_geo_llh_to_enu (nanometres);
// no rounding happens in between (JSON numbers are read as doubles). Modelled heights: see
// rs_site_ground_model.
#pragma once
#include <stdbool.h>
#include <stddef.h>

#include "core/rs_camera.h"
#include "core/rs_status.h"
#include "geo/rs_geo.h"

#ifdef __cplusplus
extern "C" {
#endif

// The names of a site's files and folders (docs/site-format.md), relative to the site folder:
// everyone outside geo/ joins these (rs_io_join(site_dir, RS_SITE_LANES)), never spells them.
// A camera's picks are RS_SITE_OBSERVATIONS_DIR/<id>RS_SITE_OBSERVATIONS_EXT and its nominal
// model, by default, RS_SITE_CAMERAS_DIR/<id>.cameramodel (rs_camera_path, core/rs_camera.h).
#define RS_SITE_JSON             "site.json"
#define RS_SITE_LANDMARKS        "landmarks.geojson"
#define RS_SITE_LANES            "lanes.geojson"
#define RS_SITE_CAMERAS_DIR      "cameras"
#define RS_SITE_OBSERVATIONS_DIR "observations"
#define RS_SITE_OBSERVATIONS_EXT ".csv"

// What a site may state, checked by the reader (rs_site_check refuses values outside, naming the
// landmark and field): physical ranges, not tuning. A survey sigma under 1 mm is better than any
// survey of a road feature and one over 100 m is no survey; a pick sigma under 0.01 px is beyond
// any corner detector and one over 1000 px is no pick; a height outside [-1000, 10000] m
// (ellipsoidal or orthometric) is not near the Earth's surface (Dead Sea shore -430 m, geoid
// -106..+85 m, Everest 8849 m). Landmarks closer than RS_SITE_COINCIDENT_M to each other are
// reported as coincident (a warning: a copied coordinate, most often).
#define RS_SITE_SURVEY_SIGMA_MIN_M  1e-3
#define RS_SITE_SURVEY_SIGMA_MAX_M  100.0
#define RS_SITE_PIXEL_SIGMA_MIN_PX  1e-2
#define RS_SITE_PIXEL_SIGMA_MAX_PX  1000.0
#define RS_SITE_PRIOR_SIGMA_MIN_M   1e-3
#define RS_SITE_PRIOR_SIGMA_MAX_M   1e5
#define RS_SITE_HEIGHT_MIN_M        (-1000.0)
#define RS_SITE_HEIGHT_MAX_M        10000.0
#define RS_SITE_COINCIDENT_M        1e-3
// A pole is at most RS_SITE_POLE_HEIGHT_MAX_M tall (a lamp or gantry post; a taller thing is no
// roadside pole); a line has at most RS_SITE_LINE_VERTICES_MAX vertices (a kerb surveyed every
// 10 cm over 1 km; split anything longer). Consecutive vertices of a line closer than
// RS_SITE_COINCIDENT_M make a zero-length segment, an error.
#define RS_SITE_POLE_HEIGHT_MAX_M   100.0
#define RS_SITE_LINE_VERTICES_MAX   10000
// A camera's intrinsics calib can use (issue 42: focal 1e300, cx = -1e9, k1 = 1e10 passed and calib
// blamed the observations): a focal length (fx, fy) between RS_SITE_FOCAL_MIN_W and
// RS_SITE_FOCAL_MAX_W image widths (a 216-degree fisheye is 0.27 W, a 100x telephoto 100 W); a
// principal point (cx, cy) within half an image of the image ([-W/2, 3W/2] x [-H/2, 3H/2]); an
// OpenCV distortion coefficient of at most RS_SITE_DISTORTION_MAX in magnitude. A ground plane
// at most RS_SITE_GROUND_TILT_MAX_DEG from level (the steepest streets are 20 degrees): its
// normal's up component at least the cosine of that.
#define RS_SITE_FOCAL_MIN_W         0.05
#define RS_SITE_FOCAL_MAX_W         100.0
#define RS_SITE_DISTORTION_MAX      1000.0
#define RS_SITE_GROUND_TILT_MAX_DEG 45.0

// How far a landmark's height can be trusted: site.json "landmark_heights" (site-wide) and a
// feature's properties.height (that landmark), docs/site-format.md.
typedef enum {
    RS_SITE_HEIGHT_DEFAULT = 0, // not stated: the landmark follows the site, the site is "surveyed"
    RS_SITE_HEIGHT_SURVEYED,    // "surveyed": levelled or surveyed, used as given
    RS_SITE_HEIGHT_UNRELIABLE,  // "unreliable": given but noisy (raw GNSS): the ground model's height
                                //   replaces it; its stated sigma_v is the noise of the given height
    RS_SITE_HEIGHT_UNKNOWN,     // "unknown": none (picked on imagery; coordinates may be [lon, lat]):
                                //   the ground model's height; a height given anyway is ignored
} rs_site_height;

// "surveyed", "unreliable", "unknown" ("default" for RS_SITE_HEIGHT_DEFAULT, "?" out of range).
const char *rs_site_height_name(rs_site_height h);

// What a landmark is (docs/site-format.md "Landmark kinds"):
typedef enum {
    RS_SITE_POINT = 0, // a surveyed point (GeoJSON Point): picked where it is
    RS_SITE_POLE,      // a vertical pole (GeoJSON Point with properties.height_m): a surveyed base
                       //   (the point) and a top pole_height_m straight up (ENU up at the site
                       //   origin) from it; picked at its base, its top, or anywhere along it
    RS_SITE_LINE,      // a surveyed polyline (GeoJSON LineString: a lane marking, stop bar, kerb):
                       //   picked anywhere along it
} rs_site_shape;

// Where on its landmark a pick lies: the observations CSV's column `at` (docs/site-format.md).
typedef enum {
    RS_SITE_AT_POINT = 0, // "point": the point itself (points only; their default)
    RS_SITE_AT_BASE,      // "base": a pole's base (the surveyed point); at most once per camera
    RS_SITE_AT_TOP,       // "top": a pole's top; at most once per camera
    RS_SITE_AT_ALONG,     // "along": anywhere on a pole's segment or a line's polyline (the default
                          //   for both); may repeat: each row is one pick somewhere on it
} rs_site_at;

// "point", "pole", "line" / "point", "base", "top", "along" ("?" out of range).
const char *rs_site_shape_name(rs_site_shape shape);
const char *rs_site_at_name(rs_site_at at);

// A surveyed landmark, in the site ENU frame. For a pole, every field of a point describes its
// base; for a line, its first vertex (p_enu_m, llh, given_*), so that code that knows only points
// sees a point on it.
typedef struct {
    char *id;          // owned; unique within the site
    int feature;       // index in landmarks.geojson's "features" (from 0)
    rs_llh llh;        // as surveyed, height converted to ellipsoidal (modelled: see height_modelled)
    double p_enu_m[3]; // (3,) east, north, up, metres
    double sigma_h_m;  // 1-sigma horizontal uncertainty (per axis), metres, > 0
    double sigma_v_m;  // 1-sigma vertical uncertainty, metres, > 0 (modelled: the model's)
    char *kind;        // owned, may be NULL (free-form: "road-marking", "pole-base", ...)
    char *note;        // owned, may be NULL

    // its properties.sigma_h_m / sigma_v_m were given (else the site-wide default applies, and
    // `roadside pick` saves it without them)
    bool sigma_h_stated, sigma_v_stated;

    rs_site_height height_stated; // its properties.height; RS_SITE_HEIGHT_DEFAULT when absent
    rs_site_height height;        // what counts: height_stated, else the site's landmark_heights
                                  //   (never DEFAULT in a loaded site)
    double above_ground_m;        // properties.above_ground_m: how far the point is above the road
                                  //   surface, metres, >= 0 (default 0: on the ground). Such a point
                                  //   never carries the ground model; a modelled one is put this
                                  //   far above it
    bool height_modelled;         // llh.h_m, p_enu_m[2] and sigma_v_m come from the site's ground
                                  //   model (height is UNRELIABLE or UNKNOWN); llh's lat and lon and
                                  //   p_enu_m's east and north are the given position's
    double given_h_m;             // the height as given, ellipsoidal, metres; NAN when none counts
                                  //   (UNKNOWN). Equal to llh.h_m when not modelled
    double given_up_m;            // ENU up of the position as given; NAN likewise
    double given_sigma_v_m;       // the vertical 1-sigma stated for the given height (its
                                  //   sigma_v_m, else the site's), metres
    bool ground_used;             // the fitted ground plane rests on this landmark's height (a
                                  //   line: on one of its vertices' heights at least)

    rs_site_shape shape;        // POINT (0: what a zeroed struct is), POLE or LINE
    double pole_height_m;       // POLE: the top is this far above the base along ENU up, metres,
                                //   in (0, RS_SITE_POLE_HEIGHT_MAX_M]; 0 otherwise
    double sigma_pole_height_m; // POLE: 1-sigma of pole_height_m, metres, > 0 (properties.
                                //   sigma_height_m; default the stated sigma_v, given_sigma_v_m);
                                //   0 otherwise
    int Nvertices;              // 1 for a point or pole; 2..RS_SITE_LINE_VERTICES_MAX for a line
                                //   (0 in structs not made by the reader: the writer then uses llh)
    double *vertices_enu_m;     // owned, (Nvertices,3) east, north, up, metres: vertices_enu_m[0..2]
                                //   == p_enu_m (a pole: its base; the top is the base +
                                //   (0, 0, pole_height_m)); NaN where the position is unusable
    rs_llh *vertices_llh;       // owned, (Nvertices,): vertices_llh[0] == llh; heights ellipsoidal,
                                //   modelled ones as modelled
    double *vertices_sigma_v_m; // owned, (Nvertices,) each vertex's vertical 1-sigma, metres
                                //   ([0] == sigma_v_m; modelled heights have their own)
    double *vertices_given_h_m; // owned, (Nvertices,) each vertex's height as given, ellipsoidal,
                                //   metres; NAN where none counts ([0] == given_h_m)
} rs_site_landmark;

// One pixel pick of a landmark in one camera.
typedef struct {
    int ilandmark;   // index into rs_site.landmarks
    double q_px[2];  // (2,) u, v in pixels, (0,0) = centre of the top-left pixel
    double sigma_px; // 1-sigma pick uncertainty per axis, pixels, > 0 (default 1.0)
    int line;        // line number in the observations CSV (from 1), for messages
    rs_site_at at;   // where on the landmark (column `at`); after load always the resolved value:
                     //   POINT for a point, BASE, TOP or ALONG for a pole, ALONG for a line.
                     //   The residual of an ALONG pick is the pixel's distance to the projected
                     //   segment (pole) or polyline (line), one number, not two
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

// A camera's stated intrinsics uncertainty (site.json cameras[].intrinsics_sigma): a relative focal
// 1-sigma under 1e-5 is beyond any calibration and one over 1 (100%) is no statement; a principal
// point 1-sigma under 0.01 px likewise, over 1e4 px beyond any image.
#define RS_SITE_FOCAL_REL_SIGMA_MIN 1e-5
#define RS_SITE_FOCAL_REL_SIGMA_MAX 1.0
#define RS_SITE_CENTER_SIGMA_MIN_PX 1e-2
#define RS_SITE_CENTER_SIGMA_MAX_PX 1e4

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

    // How well the nominal intrinsics are known (site.json "intrinsics_sigma"); 0: not stated,
    // the intrinsics are exact (docs/site-format.md)
    double focal_rel_sigma; // 1-sigma of the focal length relative to the nominal (0.1: 10%)
    double center_sigma_px; // 1-sigma of the principal point (cx and cy each), px
} rs_site_camera;

// The ground model of a site: where the heights of its UNRELIABLE and UNKNOWN landmarks come from.
// Built by the reader (geo/rs_site_ground.c) after every landmark is in ENU, and only when some
// landmark's height is to be modelled (else source is RS_SITE_GROUND_NONE and nothing was fitted).
//
// Method: a plane up = up_m + slope . ((e, n) - centre_en_m), fitted by unweighted least squares
// (the scatter about a plane is the road's own, the same for every point) to the heights it rests
// on, chosen in this order:
//   1. the SURVEYED heights of landmarks on the ground (above_ground_m == 0), if there are at least
//      3 not on one line;
//   2. else the UNRELIABLE heights of landmarks on the ground, likewise (their noise averages out
//      over the plane);
//   3. else the site's ground_plane (no fit; a modelled landmark keeps its stated sigma_v).
// Robustly: a least-median-of-squares start over triples of points (all triples up to 24 points,
// else 600 drawn with core/rs_rng.h from a fixed seed), then least squares on the points within
// RS_SITE_GROUND_REJECT_K sigmas, repeated until the set is stable; a point's sigma is the robust
// one (1.4826 x the median absolute residual of all candidates x sqrt(n / (n - 3))) or its own
// stated sigma_v combined with RS_SITE_GROUND_SCATTER_MIN_M, whichever is larger, so that no
// height is left out for a residual its stated noise explains. One wrong height (or a point above
// the ground) cannot tilt the plane; the final plane is the plain least-squares plane of the
// points kept. Accuracy: measured against numpy's least squares on the points kept and the
// closed-form sigmas (tests/geo/test_site_heights_model.py, the oracle's ENU printed to 1e-9 m):
// modelled heights within 2e-9 m, sigmas within 1e-8 relative.
//
// Uncertainty: s = sqrt(RSS / (Nused - 3)) (for Nused == 3: the RMS of their stated sigmas), at
// least the RMS of their stated sigmas; cov = s^2 (A^T A)^-1 for the rows A = (1, de, dn). The
// road's own scatter about the plane is scatter_m = sqrt(max(s^2 - stated_sigma_m^2,
// RS_SITE_GROUND_SCATTER_MIN_M^2)): the residuals less what the stated noise of the heights
// explains (for a plane resting on raw GNSS heights, most of the residual is their noise, which a
// modelled height does not carry). A modelled landmark at (e, n) gets
//   up = up_m + slope . (e - ce, n - cn) + above_ground_m,
//   sigma_v = sqrt(x^T cov x + scatter_m^2),  x = (1, e - ce, n - cn).
// The plane lives in the site ENU frame: over 1 km the Earth's curvature departs from it by 8 cm,
// which the residuals take up. The modelled height keeps the given lat and lon (the point's ENU
// east and north move by under 1 mm within 1 km of the origin).
typedef enum {
    RS_SITE_GROUND_NONE = 0,       // no height is modelled: no model
    RS_SITE_GROUND_FIT_SURVEYED,   // a plane fitted to the surveyed heights
    RS_SITE_GROUND_FIT_UNRELIABLE, // a plane fitted to the unreliable heights themselves
    RS_SITE_GROUND_SITE_PLANE,     // the site's ground_plane (too few heights to fit one)
} rs_site_ground_source;

#define RS_SITE_GROUND_SCATTER_MIN_M 0.05 // the road departs from a plane by at least this (1-sigma)
#define RS_SITE_GROUND_REJECT_K      3.0  // fit: heights beyond this many robust sigmas are left out
#define RS_SITE_GROUND_DISAGREE_K    3.0  // check: a given unreliable height this many sigmas off

typedef struct {
    rs_site_ground_source source;
    int Nmodelled;                   // landmarks whose height the model gives
    int Nunreliable;                 //   of which given but unreliable
    int Nunknown;                    //   of which unknown
    int Ncandidates;                 // heights the plane could rest on (source FIT_*), landmarks of that kind on
                                     //   the ground with a usable position
    int Nused;                       // those it rests on; Ncandidates - Nused were rejected as outliers
    double centre_en_m[2];           // (2,) east, north of the centroid of the points used, metres
    double up_m;                     // the plane's up at centre_en_m, metres
    double slope[2];                 // (2,) d up / d east, d up / d north (dimensionless; 0.01 = 1 %)
    double cov[9];                   // (3,3) row-major covariance of (up_m, slope[0], slope[1]); zero for
                                     //   SITE_PLANE
    double rms_m;                    // sqrt(RSS / (Nused - 3)) of the points used; NAN when Nused == 3
    double stated_sigma_m;           // RMS of the stated vertical sigmas of the points used
    double scale_m;                  // s of the covariance: max(rms_m, stated_sigma_m)
    double scatter_m;                // the road's scatter about the plane added to every modelled sigma
    double sigma_min_m, sigma_max_m; // the modelled landmarks' vertical sigmas (NAN when none)
    int Ndisagree;                   // given UNRELIABLE heights more than RS_SITE_GROUND_DISAGREE_K x
                                     //   sqrt(stated^2 + modelled^2) sigmas from the model (warnings)
    double mean_given_minus_model_m; // over the given UNRELIABLE heights (NAN when none): an
                                     //   offset here means heights in another system
    double max_abs_given_minus_model_m;
    // Heights nobody declared (no landmark_heights, no properties.height, no ground_plane)
    // judged unreliable: the plane they show predicts them decisively better than they are
    // stated (docs/site-format.md, "Heights nobody declared"); the numbers of that judgement
    // (NAN when there was none): the heights' RMS about the plane, their stated sigma (RMS), the
    // plane's own RMS predictive sigma at them, the chi-square of their residuals at the
    // statement and its 99.9 % quantile.
    bool heights_judged_unreliable;
    int judged_Nheights; // the heights on the ground the plane rests on
    double judged_rms_m, judged_stated_m, judged_model_m, judged_chi2, judged_chi2_limit;
} rs_site_ground_model;

// The ground model's up at (east, north) and the 1-sigma of the plane there (its prediction
// alone, sqrt(x^T cov x); a modelled landmark's sigma_v adds scatter_m). For SITE_PLANE the plane
// is the site's, sigma 0. Source NONE: NAN for both.
// out: up_m, sigma_plane_m (either may be NULL)
void rs_site_ground_predict( // out
    double *up_m, double *sigma_plane_m,
    // in
    const rs_site_ground_model *model, double e_m, double n_m);

// The judgement of heights nobody declared (model->heights_judged_unreliable) in words: what
// was found, with its numbers, that the heights were taken from the ground model and how to
// silence it; "" when there was none. out: buf (n chars, NUL-terminated). Returns buf.
const char *rs_site_heights_judgement( // out
    char *buf, size_t n,
    // in
    const rs_site_ground_model *model);

typedef struct {
    char *dir;                       // owned; the site folder as given
    char *name;                      // owned
    rs_llh origin;                   // ENU origin, height converted to ellipsoidal
    bool heights_orthometric;        // the site's heights were declared orthometric
    double geoid_undulation_m;       // N: h_ell = h_orth + N (0 for ellipsoidal sites)
    double landmark_sigma_h_m;       // site-wide default 1-sigma, horizontal, metres
    double landmark_sigma_v_m;       // site-wide default 1-sigma, vertical, metres
    double ground_normal_enu[3];     // (3,) unit normal of the ground plane n . p_enu = offset
    double ground_offset_m;          // (default: the fitted ground model's plane when there is one,
                                     //   source FIT_*; else n = (0,0,1), offset 0, i.e. up = 0)
    bool ground_plane_given;         // site.json states the ground_plane
    double max_landmark_distance_m;  // check warns about landmarks farther (default 1000)
    rs_site_height landmark_heights; // site.json "landmark_heights" (SURVEYED when absent)
    bool landmark_heights_given;     // site.json states landmark_heights
    rs_site_ground_model ground;     // where modelled heights come from (source NONE: none is)

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

// rs_site_load for survey onboarding (`roadside pick`): a camera with too few picks to be
// calibrated (fewer than 4 points) loads, the problem a warning instead of an error, since picking
// starts from none. Everything else as rs_site_load.
rs_status rs_site_load_for_picking( // out
    rs_site **out,
    // in
    const char *dir, rs_err *err);

// Frees a site and everything it owns. Accepts NULL.
void rs_site_free(rs_site *site);

// Index of the camera / landmark with this id, or -1 if there is none. Linear search.
int rs_site_find_camera(const rs_site *site, const char *id);

// The surveyed point a pick is of, in ENU (metres), with its 1-sigma per axis: a point's or a
// pole's base as surveyed; a pole's top pole_height_m straight up from its base, its vertical
// sigma combined with sigma_pole_height_m. False for an `along` pick (a pole's segment or a
// line: no single point). site and o must not be NULL.
bool rs_site_observed_point(double p_enu_m[3], double sigma_enu_m[3], const rs_site *site,
                            const rs_site_observation *o);
int rs_site_find_landmark(const rs_site *site, const char *id);

// The polyline an `along` pick is on, ENU metres: a pole's base and top (written into
// pole_vertices_enu_m, (2,3)), or a line's own vertices (a pointer into the site). *vertices_enu_m
// receives it; returns its number of vertices, 0 for a pick that is not `along`. sigma_enu_m (3,)
// receives the landmark's survey 1-sigma (sigma_h, sigma_h, sigma_v). No argument may be NULL.
int rs_site_along_polyline(const double **vertices_enu_m, double pole_vertices_enu_m[6], double sigma_enu_m[3],
                           const rs_site *site, const rs_site_observation *o);

// The surveyed point a pick is of as a calibrated camera sees it: rs_site_observed_point for a
// point, a pole's base or top; for an `along` pick, the point of its polyline whose projection
// through cam is nearest the pick (each segment sampled at 256 points, then a ternary search:
// to 1e-6 of the segment). Its projection goes to q_px (2,), may be NULL. False when no part of
// the polyline projects (then p_enu_m and q_px are NaN).
bool rs_site_seen_point(double p_enu_m[3], double *q_px, const rs_site *site, const rs_site_observation *o,
                        const rs_camera *cam);

// The value a background has for `key`: its tag `key` if it has one, else its own "name",
// "file" (as written in site.json) or "synthetic" ("true" / "false"); NULL if none of these.
// What `roadside synth --backgrounds KEY=VALUE` matches. The pointer is the background's own
// (or a static string); valid while the site is.
const char *rs_site_background_tag(const rs_site_background *bg, const char *key);

// Axis-aligned ENU extent and the range of distances from the origin of a set of landmarks:
// all of them (icam < 0) or those observed by camera icam; of every vertex of a line and of a
// pole's base and top.
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
    rs_site_ground_model ground; // the site's ground model as far as it could be built (source
                                 //   NONE when no height is modelled or the landmarks are unusable)
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

// rs_simulate.h -- synthetic roadside camera problems and whole sites with a known truth.
//
// Purpose: test data whose answer is known exactly, for the solver's tests, the benchmarks and
// the bundled demo site (sites/demo). Two entry points:
//
//   rs_simulate_camera_problem()  one camera's problem in memory (no files): a true pose and
//                                 lens, landmarks in front of it, their surveyed (noisy)
//                                 positions and their picked (noisy, partly wrong) pixels.
//                                 Every knob a benchmark may sweep is an option.
//   rs_simulate_site()            a complete site folder (site.json, landmarks.geojson,
//                                 lanes.geojson, cameras/, observations/) plus a truth/ folder:
//                                 a four-approach intersection watched by cameras on poles at
//                                 its corners.
//
// Method: points are projected with rs_lens_project() through the TRUE lens model and pose; the
// picked pixel is that projection plus isotropic Gaussian noise (redrawn until it lies inside
// the image), or, for a gross outlier, a uniformly random pixel at least outlier_min_px away
// from the true one. Surveyed positions are the true ENU positions plus Gaussian noise (sigma_h
// on east and north, sigma_v on up); the site converts them to WGS84 with rs_geo_enu_to_llh().
// Randomness comes from core/rs_rng.h (xoshiro256** seeded through splitmix64, Box-Muller
// normals): the same seed and options give bit-identical results on every machine
// with IEEE doubles and the same libm, and a byte-identical site folder.
//
// Exactness: every true intrinsic and extrinsic is rounded to 1e-6 (the precision mrcal writes
// .cameramodel files with) BEFORE anything is projected, and true landmark positions to 1e-4 m,
// so that the files in truth/ reproduce the noise-free pixels to better than 1e-6 px.
//
// Conventions (docs/conventions.md): ENU metres, rt_cam_enu maps ENU into the camera frame,
// camera x right / y down / z forward, pixel (0,0) at the centre of the top-left pixel,
// yaw/pitch/roll as defined there.
#pragma once
#include <mrcal/mrcal.h>
#include <stdbool.h>
#include <stdint.h>

#include "core/rs_camera.h"

#include "core/rs_rng.h"
#include "core/rs_status.h"
#include "geo/rs_geo.h"
#include "geo/rs_site.h"

#ifdef __cplusplus
extern "C" {
#endif

// ---- the lens ----

// Draws the TRUE intrinsics of a camera of the given mrcal lens model:
//   core: fx = fy from the horizontal field of view (pinhole-like models, OPENCVn, CAHVOR(E):
//   fx = (W/2)/tan(hfov/2); stereographic and splined stereographic: fx = (W/2)/(2 tan(hfov/4));
//   LONLAT, LATLON: fx = (W/2)/(hfov/2 in radians)), scaled by 1 + N(0, 0.002); principal
//   point at the image centre ((W-1)/2, (H-1)/2) plus N(0, 0.4% of W and H) px.
//   distortion (if `distortion`): mild and realistic: OPENCVn k1 ~ -0.08, k2 ~ 0.03, p1, p2 ~
//   2e-4 (a few tens of pixels at the corners of a 60 degree 1080p image); CAHVOR(E) r1 ~ -0.05,
//   r2 ~ 0.01, alpha, beta ~ 1e-3; every other model (and every coefficient not named) zero.
//   All values rounded to 1e-6.
// Errors: RS_ERR_USAGE for an unknown or unconfigured lens model name (the message lists the
// names mrcal knows), a model without an intrinsics core, a field of view that the model cannot
// show (pinhole-like models: hfov must be below 170 degrees), a bad image size.
// out: *intrinsics is malloc'ed, (*Nintrinsics,), owned by the caller (free()).
rs_status rs_simulate_lens( // out
    mrcal_lensmodel_t *lensmodel, double **intrinsics, int *Nintrinsics,
    // in,out
    rs_rng *rng,
    // in
    const char *lensmodel_name, // e.g. "LENSMODEL_OPENCV8"
    int width_px, int height_px, double hfov_deg, bool distortion, rs_err *err);

// ---- one camera's problem, in memory ----

typedef struct {
    const char *lensmodel;   // mrcal lens model name (default "LENSMODEL_OPENCV8")
    int width_px, height_px; // image size (default 1920 x 1080)
    double hfov_deg;         // horizontal field of view (default 60)
    bool distortion;         // draw mild distortion (default true); false: all zero

    double camera_height_m; // camera height above the ground plane u = 0 (default 8)
    double distance_m;      // horizontal distance from the camera to the point it looks at,
                            // the ENU origin (default 25)
    double yaw_deg;         // heading of the camera (default 30)
    double roll_sigma_deg;  // roll ~ N(0, this) (default 1)
                            // pitch: the ENU origin appears at 62% of the image height

    int Nlandmarks;                        // landmarks to generate, all visible (default 12)
    double elevated_fraction;              // fraction above the ground (default 0.25); 0 = planar problem
    double elevated_min_m, elevated_max_m; // height range of those (default 2, 6)
    double max_range_m;                    // max horizontal distance camera -> landmark (default 80); keep
                                           // it well above distance_m, or little ground is left to use
    double margin_px;                      // landmarks project at least this far inside the image (20)

    double pixel_sigma_px;   // pixel noise (default 1)
    double survey_sigma_h_m; // survey noise, east and north (default 0.3)
    double survey_sigma_v_m; // survey noise, up (default 0.5)
    double outlier_fraction; // probability that a pick is a gross outlier (default 0.05)
    double outlier_min_px;   // an outlier is at least this far from the truth (default 30)
    uint64_t seed;           // default 1
} rs_simulate_camera_options;

// Fills o with the defaults above. o must not be NULL.
void rs_simulate_camera_options_default(rs_simulate_camera_options *o);

// One camera's problem. Owned by whoever rs_simulate_camera_problem() returned it to; free with
// rs_simulate_problem_free().
typedef struct {
    rs_camera camera;      // the TRUE camera: lens, intrinsics (owned), image size, pose
    double p_cam_enu_m[3]; // camera position in ENU, -R^T t
    double ypr_deg[3];     // yaw, pitch, roll of the true pose

    int Npoints;
    double *p_enu_true_m;   // (Npoints,3) true landmark positions
    double *p_enu_survey_m; // (Npoints,3) surveyed = true + survey noise
    double *q_true_px;      // (Npoints,2) exact projections of the true positions
    double *q_px;           // (Npoints,2) picked pixels: noisy, outliers replaced
    bool *outlier;          // (Npoints,) true where q_px is a gross outlier
    bool *elevated;         // (Npoints,) true where the landmark is above the ground
    int Noutliers;
} rs_simulate_problem;

// Generates one camera's problem. The landmarks are the intersections of rays through uniformly
// random pixels (inside the margin) with the ground (or, for elevated ones, with a horizontal
// plane at a random height), within max_range_m: every one of them is visible.
// Errors: RS_ERR_USAGE for bad options (the message names the field), RS_ERR_DEGENERATE when the
// camera sees too little ground to place the landmarks (e.g. it looks above the horizon).
// out: *problem, owned by the caller; NULL on failure.
rs_status rs_simulate_camera_problem( // out
    rs_simulate_problem **problem,
    // in
    const rs_simulate_camera_options *o, rs_err *err);

// Frees a problem. Accepts NULL.
void rs_simulate_problem_free(rs_simulate_problem *problem);

// ---- a whole site ----

// The fisheye lenses a site may be simulated with (rs_simulate_site_options.fisheye).
#define RS_SIMULATE_FISHEYE_LENS "LENSMODEL_CAHVORE_linearity=0.00"
typedef enum {
    RS_SIMULATE_FISHEYE_NONE,
    RS_SIMULATE_FISHEYE_EQUIDISTANT,
    RS_SIMULATE_FISHEYE_KANNALA_BRANDT
} rs_simulate_fisheye;

typedef struct {
    uint64_t seed;               // default 1; at most 2^53 (it is written to JSON)
    int Ncameras;                // 1..16 (default 4): the first 4 on the corners, then along
                                 // the approaches
    int landmarks_per_camera;    // 0..100 (default 12): each camera sees about this many points
                                 //   (at least 4 unless poles or lines are asked for)
    const char *lensmodel;       // mrcal lens model name (default "LENSMODEL_OPENCV8")
    int width_px, height_px;     // default 1920 x 1080
    double hfov_deg;             // default 60
    double pixel_sigma_px;       // default 1
    double survey_sigma_h_m;     // default 0.3
    double survey_sigma_v_m;     // default 0.5
    double outlier_fraction;     // default 0.05, in [0, 0.9]
    double focal_error;          // nominal focal length = true * this (default 1: exact), [0.5, 2]
    double focal_error_range;    // >= 1, <= 2 (default 1: none): each camera's nominal focal is
                                 //   further multiplied by a factor drawn log-uniformly in
                                 //   [1/this, this] (a focal nobody knows, as a map-picked camera's),
                                 //   from a stream of its own: the rest of the site is the same
    double pole_prior_sigma_m;   // > 0: each camera gets a position prior, its true position
                                 // plus N(0, this) per axis; 0 (default): no prior
    double elevated_fraction;    // share of each camera's landmarks above the ground (0.25); 0:
                                 //   every one on the ground (points picked on a map)
    rs_simulate_fisheye fisheye; // NONE (default): cameras on poles at the corners with
                                 //   `lensmodel`; otherwise every camera is an overhead fisheye
                                 //   (LENSMODEL_CAHVORE_linearity=0.00, docs/conventions.md "Fisheye
                                 //   lenses") on a mast over the junction, 8-11 m up, within 3 m
                                 //   of its centre, tilted so the centre shows at 62% of the
                                 //   image height: EQUIDISTANT (r = f theta) or KANNALA_BRANDT
                                 //   (k1, k2 drawn); `lensmodel` is then ignored
    rs_llh origin;               // default 48.1374, 11.5755, 560 (ellipsoidal)
    bool force;                  // replace an existing site folder (default false)

    // Heights a survey does not have (docs/site-format.md): both default to what sites always
    // were, nothing written and no noise.
    double height_noise_m;           // >= 0, <= 100 (default 0): N(0, this) more on the surveyed
                                     //   heights of the landmarks on the ground (raw GNSS), drawn
                                     //   from a stream of its own: the rest of the site is the
                                     //   same as without it; their declared sigma_v becomes
                                     //   hypot(survey_sigma_v_m, this)
    rs_site_height landmark_heights; // site.json "landmark_heights" for the landmarks on the
                                     //   ground (DEFAULT: not written). Unless SURVEYED, the
                                     //   landmarks above the ground say "height": "surveyed" and
                                     //   their above_ground_m; UNKNOWN ones are written
                                     //   [lon, lat]

    // Poles and lines as landmarks (docs/site-format.md "Landmark kinds"; issue 13, item 4). Both
    // default to 0: the site is what it always was, byte for byte. Drawn from a random stream of
    // their own: the cameras and points are those of the same site without them.
    int poles_per_camera; // 0..50: each camera sees about this many poles: delineator posts
                          //   (1.0-1.2 m) along the road edges, lamp posts (6-10 m) and sign posts
                          //   (3-4.5 m) beside the roads. A visible pole is picked at its base and
                          //   its top where those are in the image, and once along it (a random
                          //   point of the part of it in the image)
    int lines_per_camera; // 0..20: each camera sees about this many lines: stop bars, centre and
                          //   edge lines (a vertex every 4 m), kerbs round the corners (straight
                          //   runs and a 5 m radius arc); a visible line is picked 3 times along
                          //   it (random points of its visible part)
} rs_simulate_site_options;

// Fills o with the defaults above. o must not be NULL.
void rs_simulate_site_options_default(rs_simulate_site_options *o);

// Checks the options (ranges, the lens model name). RS_ERR_USAGE naming the field at fault.
rs_status rs_simulate_site_options_check(const rs_simulate_site_options *o, rs_err *err);

// Writes a simulated site into the folder `dir` (the layout is in sites/demo/README.md):
// site.json, landmarks.geojson, lanes.geojson (the intersection's 32 lanes, exact: no survey
// noise; docs/site-format.md "lanes.geojson"), cameras/<id>.cameramodel (NOMINAL intrinsics, zero
// extrinsics), observations/<id>.csv, truth/<id>.cameramodel (true intrinsics and pose),
// truth/landmarks_enu.csv, truth/truth.json. The site's own files are written by geo
// (geo/rs_site_write.h, rs_lanes_write), the camera models by core (rs_camera.h).
// The sigmas the site declares (site.json landmark_sigma_m, the csv's sigma_px) are the noise
// levels drawn, but at least 1 mm and 0.01 px: a noise-free site still has weights to solve with.
// The site is built in a temporary sibling folder and renamed into place when complete, so a
// failure never leaves a half site. `dir` may not exist, or be an empty folder; a non-empty one
// is replaced only with o->force, and only if it is a site this function wrote and holds nothing
// else (its record, .roadside-simulated, lists every file it wrote: a surveyor's site.json does not
// make a folder simulate's), otherwise RS_ERR_IO naming why and nothing is touched.
// With poles or lines: every pick of them is the true point picked (a pole's base or top, or a
// uniformly random point of the visible part of the segment or polyline) projected, plus the
// site's pixel noise (or an outlier, as for points); their survey is the true base, height and
// vertices plus the survey noise of points (sigma_h, sigma_v; the height sigma_v). truth/ then
// also holds vertices_enu.csv (id, shape, vertex, e, n, u: a pole's base and top, a line's
// vertices, true) and picks.csv (camera, row: the pick's data row in the observations CSV from
// 1, landmark, at, the true point picked e, n, u, its projection, outlier).
// Errors: RS_ERR_USAGE (bad options), RS_ERR_IO (folder exists, cannot write), RS_ERR_DEGENERATE
// (a camera sees fewer than 4 landmarks; with poles or lines, its picks fix fewer than 8
// numbers: docs/site-format.md), RS_ERR_EXTERNAL (mrcal failed).
rs_status rs_simulate_site( // in
    const char *dir, const rs_simulate_site_options *o, rs_err *err);

#ifdef __cplusplus
}
#endif

// rs_simulate_internal.h -- what the files of the simulator share. Not installed, not for other
// modules: use sim/rs_simulate.h.
//
// The files, each calling only those below it:
//
//   rs_simulate_site.c          a whole site: options, writing it through geo (rs_site_write.h,
//                               rs_lanes.h) and the truth, the folder built aside and renamed
//     rs_simulate_intersection.c  the intersection: its surveyable points, poles, landmarks
//                                 chosen, picks, survey, lanes -- everything before writing
//       rs_simulate_shapes.c        its poles and lines as landmarks (issue 13, item 4):
//                                   candidates, choice, picks at base, top or along, survey
//       rs_simulate_camera.c        one camera: pose, field of view, projection, picks; and one
//                                   camera's problem in memory (rs_simulate_camera_problem)
//         rs_simulate_lens.c          the true lens (rs_simulate_lens)
#pragma once
#include <math.h>
#include <stdbool.h>

#include "core/rs_camera.h"
#include "core/rs_rng.h"
#include "core/rs_status.h"
#include "core/rs_units.h"
#include "geo/rs_lanes.h"
#include "sim/rs_simulate.h"

// Rounds to a multiple of `quantum` (a power of ten below 1): the nearest double to that
// decimal, so that printing it with as many decimals and parsing it back gives the same double.
// Never returns -0.
static inline double rs_simulate__quantize(double x, double inv_quantum)
{
    return round(x * inv_quantum) / inv_quantum + 0.0;
}
#define Q_MODEL 1e6 // .cameramodel precision (mrcal writes "%f")
#define Q_ENU   1e4 // true landmark positions: 0.1 mm

// The random stream of the extra height noise (rs_rng_seed_derive(seed, this)): apart from the
// site's own stream, so that --height-noise changes nothing else.
#define HEIGHT_NOISE_STREAM 0x6865696768ULL // "heigh"
// The random stream of the per-camera focal errors (--focal-error-range): apart from the site's
// own, so that it changes nothing else.
#define FOCAL_ERROR_STREAM  0x666f63616cULL // "focal"
// The random stream of the poles and lines (rs_simulate_shapes.c): apart from the site's own, so
// that a site asked for poles or lines has the same cameras and points as without them.
#define SHAPES_STREAM       0x7368617065ULL // "shape"

// A check of one option: `ok` must hold, else RS_ERR_USAGE naming the field (in a function
// with an `rs_err *err`).
#define CHECK_OPTION(ok, field, fmt, value)                                                           \
    do {                                                                                              \
        if (!(ok)) return rs_err_set(err, RS_ERR_USAGE, "%s: " fmt " is out of range", field, value); \
    } while (0)

// ---- the lens (rs_simulate_lens.c) ----

// Parses a lens model name and checks it against the image size and field of view
// (RS_ERR_USAGE naming what is wrong). out: *lm.
rs_status rs_simulate__lens_check(mrcal_lensmodel_t *lm, const char *name, int width_px, int height_px, double hfov_deg,
                                  rs_err *err);

// ---- one camera (rs_simulate_camera.c) ----

typedef struct {
    rs_camera cam;  // the true camera (intrinsics owned)
    double cos_max; // points further off the optical axis than the image corners are ignored
    double R_cam_enu[9];
    double p_cam_enu_m[3];
    double ypr_deg[3];
} rs_simulate__camera;

// The widest angle off the optical axis that the image shows (its corners) into c->cos_max, for
// rejecting points that a distortion polynomial would fold back into the image from outside the
// field of view. RS_ERR_UNSUPPORTED when mrcal cannot unproject through the lens.
rs_status rs_simulate__camera_field_of_view(rs_simulate__camera *c, rs_err *err);

// Sets the pose of a camera at p_cam looking at `target`, turned by yaw_offset_deg and rolled by
// roll_deg, pitched so that the target appears at 62% of the image height. Rounds rt to 1e-6.
void rs_simulate__camera_look_at(rs_simulate__camera *c, const double p_cam[3], const double target[3],
                                 double yaw_offset_deg, double roll_deg);

// Projects p_enu through the camera into q_px (2,). True if the point is in front of the
// camera, inside its field of view, and projects at least margin_px inside the image.
bool rs_simulate__camera_sees(const rs_simulate__camera *c, double q_px[2], const double p_enu[3], double margin_px);

// Picks of N points: the true pixel plus N(0, sigma) noise kept inside the image (redrawn until
// it is), or, with probability outlier_fraction, a uniformly random pixel at least
// outlier_min_px away. out: q_px (N,2), outlier (N,). Returns the number of outliers.
int rs_simulate__camera_pick(rs_rng *rng, double *q_px, bool *outlier, const double *q_true_px, int N,
                             const rs_simulate__camera *c, double sigma_px, double outlier_fraction,
                             double outlier_min_px);

// Surveyed positions: p_true (N,3) plus N(0, sigma_h) on east and north, N(0, sigma_v) on up.
void rs_simulate__survey_noise(rs_rng *rng, double *p_survey, const double *p_true, int N, double sigma_h,
                               double sigma_v);

// ---- the intersection (rs_simulate_intersection.c) ----

// A surveyable point of the intersection.
typedef struct {
    double p_enu_m[3];
    const char *kind; // static string: "crosswalk_corner", "sign_top", ...
} rs_simulate__candidate;

typedef struct {
    rs_simulate__candidate *c; // (N,) owned
    int N, cap;
} rs_simulate__candidates;

// A pole or line of the intersection (rs_simulate_shapes.c): its true geometry and, once
// chosen, its survey.
typedef struct {
    rs_site_shape shape;  // RS_SITE_POLE or RS_SITE_LINE
    const char *kind;     // static string: "delineator_post", "lamp_post", "edge_line", "kerb", ...
    int Nvertices;        // a pole 2 (base, top), a line its vertices
    double *p_enu_m;      // (Nvertices,3) true, owned; rounded to 0.1 mm
    double height_m;      // a pole's true height (top - base), metres; 0 for a line
    double length_m;      // total length of the segments
    bool chosen;          // a landmark of the site
    double *survey_enu_m; // (Nsurveyed,3) owned: a pole's base (1), a line's vertices
    double *survey_llh;   // (Nsurveyed,3) owned, ellipsoidal
    double survey_height_m;
} rs_simulate__shape;

// One pick of a pole or line by one camera.
typedef struct {
    int cam;                // camera index
    int landmark;           // index among the site's landmarks: points first, then poles, then lines
    int shape;              // index into rs_simulate__site.shape
    rs_site_at at;          // BASE, TOP or ALONG
    double p_true_enu_m[3]; // the true point picked
    double q_true_px[2];    // its exact projection
    double q_px[2];         // the pick: noisy (or an outlier)
    bool outlier;
} rs_simulate__pick;

// Everything generated for a site, before it is written.
typedef struct {
    int Ncameras;
    rs_simulate__camera *cam;     // (Ncameras,)
    double *nominal;              // (Ncameras, Nintrinsics) the intrinsics the site's owner believes
    char (*note)[128];            // (Ncameras,)
    double *prior_llh;            // (Ncameras, 3) or NULL
    rs_simulate__candidates cand; // every surveyable point
    bool *visible;                // (Ncameras, cand.N)
    double *q_true_px;            // (Ncameras, cand.N, 2)
    int *landmark_of;             // (cand.N,) landmark index of a selected candidate, else -1
    int Nlandmarks;
    int *cand_of;         // (Nlandmarks,) candidate index of a landmark
    double *survey_enu_m; // (Nlandmarks, 3)
    double *survey_llh;   // (Nlandmarks, 3)
    double *q_px;         // (Ncameras, cand.N, 2) picks (selected and visible only)
    bool *outlier;        // (Ncameras, cand.N)
    int Nobservations, Noutliers;
    double road_azimuth_deg;
    double R_road[4]; // road frame -> ENU (2x2 row-major), for the lanes

    // poles and lines (rs_simulate_shapes.c): none unless asked for
    rs_simulate__shape *shape; // (Nshapes,) owned: every candidate, poles first
    int Nshapes;
    int *shape_of;            // (Npoles + Nlines,) the chosen, poles then lines, candidate order
    int Npoles, Nlines;       // chosen
    rs_simulate__pick *picks; // (Npicks,) owned, by camera, then landmark, then base/top/along
    int Npicks;
} rs_simulate__site;

// Draws the whole site for the (checked) options: the roads, the cameras on their poles, the
// landmarks, the picks, the survey, the nominal lenses and the pole priors. On failure *s may be
// partly filled: free it with rs_simulate__site_free either way.
rs_status rs_simulate__site_draw(rs_simulate__site *s, const rs_simulate_site_options *o, rs_err *err);
void rs_simulate__site_free(rs_simulate__site *s);

// The poles and lines of the site (o->poles_per_camera, o->lines_per_camera; nothing when both
// are 0): candidates along the intersection's roads, chosen so that each camera sees about that
// many, their picks and their survey, from the stream SHAPES_STREAM. Then checks that each camera
// has enough picks (points, poles and lines) to be calibrated. Called by rs_simulate__site_draw
// once its cameras and points are drawn. RS_ERR_DEGENERATE when a camera sees too little.
rs_status rs_simulate__shapes_draw(rs_simulate__site *s, const rs_simulate_site_options *o, rs_err *err);
void rs_simulate__shapes_free(rs_simulate__site *s);

// The ids of the site's poles and lines: "P001", ..., "LN001", ...
void rs_simulate__pole_id(char id[16], int i);
void rs_simulate__line_id(char id[16], int i);

// The intersection's 32 lanes (docs/site-format.md "lanes.geojson") in the site ENU frame, on the
// ground (up = 0), positions rounded to 0.1 mm. out: *lanes (owned; rs_lanes_free).
rs_status rs_simulate__lanes(rs_lanes *lanes, const rs_simulate__site *s, rs_err *err);

// The ids the site gives landmark i and camera k: "L001", ..., "cam1", ...
void rs_simulate__landmark_id(char id[16], int i);
void rs_simulate__camera_id(char id[16], int k);

// ---- the record of what simulate wrote (rs_simulate_record.c) ----

// The file in a simulated site that lists every file `site simulate` wrote there (relative
// paths, one a line, after a first line naming the writer): how --force recognises a folder it
// may replace (a surveyor's site.json alone does not make a folder simulate's).
#define RS_SIMULATE_RECORD ".roadside-simulated"

// Writes dir/RS_SIMULATE_RECORD listing every file now under dir (itself included). RS_ERR_IO,
// RS_ERR_NOMEM.
rs_status rs_simulate__record_write(const char *dir, rs_err *err);

// Whether dir is a site simulate wrote and nothing else: its record is there and every file
// under dir is listed in it. False with why filled ("holds no .roadside-simulated record ...",
// "holds 'notes.txt', which site simulate did not write") otherwise. why: n bytes
bool rs_simulate__record_matches(char *why, size_t n,
                                 // in
                                 const char *dir);

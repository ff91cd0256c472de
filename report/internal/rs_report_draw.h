// rs_report_draw.h -- the figures of `roadside report`, drawn with cairo on any surface (image
// surface for the HTML's PNGs, PDF surface for the PDF). Private to report/rs_report*.c.
// Files: rs_report_draw.c (shared helpers, camera geometry), rs_report_draw_image.c (the
// camera's image), rs_report_draw_map.c (the top-down maps, the best map).
//
// Geometry goes through the libraries: ENU -> camera with mrcal_transform_point_rt, camera ->
// pixel with mrcal_project (the full lens model), pixel -> ray with mrcal_unproject. Figures
// never fail: what cannot be drawn (a point behind the camera, a NaN) is left out.
#pragma once
#include <stdbool.h>

#include <cairo.h>

#include "audit/rs_audit.h"
#include "calib/rs_calib_site.h"
#include "geo/rs_geo_raster.h"
#include "geo/rs_site.h"
#include "report/rs_report.h"

#ifdef __cplusplus
extern "C" {
#endif

// One landmark of a camera as `roadside calib` wrote it in <id>.json (residuals named as in
// docs/calibration.md, "Residuals: which is which").
typedef struct {
    char *id;                        // owned
    int ilandmark;                   // index in site->landmarks, -1 when the site has no such id
    double observed_px[2];           // the pick
    double predicted_surveyed_px[2]; // the surveyed position through the calibration (drawn);
                                     //   NaN when <id>.json predates it
    double residual_surveyed_px[2];  // predicted_surveyed_px - observed (drawn, tabulated)
    double normalised;               // sqrt(block chi2), sigmas
    bool inlier;
} rs_report_landmark;

// Lane lines in site ENU, from the site's optional lanes.geojson: the two edges of a lane with a
// width_m (its centreline offset by +-width/2), else its centreline; junction connectors
// (kind "junction") as thin dashed centrelines.
typedef struct {
    int Nlines;
    int *start;      // (Nlines+1,) line k is points start[k] .. start[k+1]-1 (owned)
    double *p_enu_m; // (start[Nlines],3) owned
    bool *junction;  // (Nlines,) drawn thin and dashed (owned)
} rs_report_lanes;

struct rs_report_ctx;

// Everything drawn and tabulated for one camera.
typedef struct {
    const struct rs_report_ctx *rep;
    int icam;        // index in site->cameras
    int colour;      // index into the camera palette
    rs_camera model; // <id>.cameramodel (owned)
    // <id>.json
    double position_enu_m[3], sigma_position_enu_m[3], position_llh[3];
    double yaw_pitch_roll_deg[3], sigma_yaw_pitch_roll_deg[3];
    double rms_surveyed_px; // the headline (NaN when <id>.json predates it)
    double rms_adjusted_px; // labelled as such wherever it is shown
    double variance_factor, condition_number;
    int Nused, Nrejected;
    char *lensmodel; // owned
    int N;
    rs_report_landmark *landmarks; // (N,) owned
    char **warnings;               // (Nwarnings,) owned strings
    int Nwarnings;
    bool focal_off, center_off; // <id>.json's intrinsics_check: the image says the nominal is off
    double focal_rel;           //   the data's f / f_nominal - 1 (NaN: not tested)
    // derived for the figures
    double max_tan;   // rs_camera_max_tan(&model): points beyond the lens's valid field are not drawn
    double *fov_en_m; // (Nfov,2) ground seen within range, polygon (owned)
    int Nfov;
    double magnification;        // residual vectors drawn this many times longer
    char *background_path;       // owned, NULL: neutral canvas
    cairo_surface_t *background; // owned, may be NULL
    // the audit (rs_audit_site_camera); has_audit false when it failed (audit_error says why)
    bool has_audit;
    rs_audit_result audit;
    char audit_error[1100];
} rs_report_camera;

struct rs_report_ctx {
    const rs_site *site;
    rs_report_lanes lanes;
    rs_report_camera *cameras; // (Ncameras,) owned
    int Ncameras;
    double grid_m;                         // ground grid spacing, metres
    double range_m;                        // field of view on the ground cut at this distance
    double detection_sigma_px;             // detection noise of the uncertainty maps, px
    const rs_audit_options *audit_options; // the audit's thresholds; NULL: no audit requested
    const char *calib_dir;                 // where <id>.cameramodel and <id>.json were read
    const char *version;                   // the software version printed ("unknown" if NULL)
    long long written_utc_s;               // the date printed, seconds since 1970 UTC
    rs_geo_ortho ortho;                    // the site map's orthophoto on the ENU grid (owned; rgb
                                           //   NULL: none)
    char *ortho_path;                      // owned: its file, NULL: none
    rs_audit_map best_map;                 // the smallest 1-sigma of the cameras' maps at each cell
                                           //   (owned; sigma_m NULL when no camera has a map)
};

// Loads rep->cameras (rep->site, rep->calib_dir and rep->range_m set): each camera's
// <id>.cameramodel and <id>.json, its figure geometry, background and (opt->audit) its audit,
// then the lanes and the best map. Free with rs_report_free_cameras, also on error.
rs_status rs_report_load_cameras(struct rs_report_ctx *rep, const rs_report_options *opt, rs_err *err);
void rs_report_free_cameras(struct rs_report_ctx *rep);

// Fills rep->best_map from the cameras' audit maps: a grid of the cameras' cell size spanning
// all their maps, each cell the smallest sigma over the maps (nearest cell) that see it, NaN
// where none does. Leaves it zeroed when no camera has a map. False when out of memory.
bool rs_report_best_map(struct rs_report_ctx *rep);

// The camera's image (background or neutral canvas) with the ground grid, lanes, observed and
// reprojected landmarks and magnified residual vectors. ctx: const rs_report_camera *.
// Aspect height/width = model.height / model.width.
void rs_report_draw_camera(cairo_t *cr, double w, double h, const void *ctx);

// Top-down ENU map around one camera: the uncertainty map (colour scale, labelled contours),
// the ground the camera sees, its landmarks, lanes. ctx: const rs_report_camera *.
void rs_report_draw_camera_map(cairo_t *cr, double w, double h, const void *ctx);

// Top-down ENU map of the whole site: every camera's position and ground field of view, every
// landmark, lanes. ctx: const struct rs_report_ctx *.
void rs_report_draw_site_map(cairo_t *cr, double w, double h, const void *ctx);

// Fills cam->max_tan, cam->fov_en_m/Nfov (ground seen within range_m of the camera's (E, N),
// on the site's ground plane) and cam->magnification (1, 2, 2.5 or 5 times a power of ten,
// >= 1, making the median inlier residual ~1.5% of the image width). Returns false when out of memory.
bool rs_report_camera_geometry(rs_report_camera *cam);

#ifdef __cplusplus
}
#endif

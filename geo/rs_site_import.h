// rs_site_import.h -- a site built from what people already have (`roadside site import`,
// docs/site-format.md "Importing"): point pairs picked on a map and in a camera image (a
// point-pair JSON, or a CSV of lat,lon,u,v[,h] or e,n,u,v[,h] in any CRS GDAL/PROJ knows), the
// camera's intrinsics (an mrcal .cameramodel, OpenCV YAML/JSON, pinhole or fisheye, the
// equidistant triple {f, x0, y0}) or only its image size. The result passes `site check`, and
// a summary says what was assumed: heights, sigmas, the nominal lens.
//
// Part of geo's GDAL library (geo_raster_dep; the CRS conversion is geo/rs_geo_crs.h). The site's
// files are written through geo/rs_site_write.h and core/rs_camera.h, the point files read by
// rs_site_import_read.c (their one reader).
#pragma once
#include <stdbool.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// Where the landmark coordinates come from: sets the default landmark sigmas (horizontal per
// axis, vertical) in metres, and how far given heights are trusted.
typedef enum {
    RS_SITE_IMPORT_MAP = 0, // picked on a map or orthophoto: 0.5 m, 0.5 m; heights unreliable
    RS_SITE_IMPORT_GNSS,    // RTK GNSS: 0.05 m, 0.10 m; heights surveyed
    RS_SITE_IMPORT_SURVEY,  // total station / levelled survey: 0.01 m, 0.02 m; heights surveyed
} rs_site_import_source;

// "map", "gnss", "survey"; NULL out of range.
const char *rs_site_import_source_name(rs_site_import_source source);

// The default pick uncertainty of imported pixels (a point clicked in a frame), pixels.
#define RS_SITE_IMPORT_SIGMA_PX 3.0

// One camera: its point file and image.
typedef struct {
    const char *points; // a point-pair .json ({"results": [{"x", "y", "lat", "lng", "id"}, ...]}) or
                        //   a .csv with a header (lat,lon or e,n; u,v; optional h, id, sigma_px)
    const char *id;     // the camera's id; NULL: the points file's name without its extension
    const char *image;  // a frame of the camera (its size is the image size); NULL: the image
                        //   beside the points file with the same name (.jpg .jpeg .png .tif
                        //   .tiff .bmp), if there is one
} rs_site_import_camera;

typedef struct {
    const rs_site_import_camera *cameras; // (Ncameras,) >= 1
    int Ncameras;
    const char *name;       // the site's name; NULL: the folder's last part
    const char *crs;        // the CRS of every point file's coordinates ("EPSG:25832"); NULL:
                            //   WGS84 (EPSG:4326), which needs lat,lon columns; a projected CRS
                            //   needs e,n columns, a geographic one lat,lon
    const char *intrinsics; // a camera file rs_camera_read reads, for every camera; NULL: a
                            //   nominal pinhole (f = the image width, the image's centre)
    int width, height;      // the image size, pixels; 0: from the image, else the intrinsics file
    double sigma_px;        // pick 1-sigma for rows that give none, pixels; <= 0: RS_SITE_IMPORT_SIGMA_PX
    double sigma_h_m;       // landmark 1-sigma, metres; <= 0: the source's default
    double sigma_v_m;
    rs_site_import_source source;
    const double *geoid_undulation_m; // NULL: given heights are ellipsoidal; else orthometric, N
    bool force;                       // replace an existing site folder (one holding site.json)
} rs_site_import_options;

// Builds the site folder `dir` from the options: site.json, landmarks.geojson,
// cameras/<id>.cameramodel, observations/<id>.csv. The folder is built under a temporary name,
// checked by rs_site_check (no error allowed) and renamed into place, so a failure leaves nothing
// half-made; an existing non-empty `dir` is refused unless opt->force (and then only a site
// folder is replaced). Landmark ids are the files' ids (or "P<row>"), prefixed "<camera>:" when
// more than one camera is imported. The origin is the centroid of the landmarks (at the mean
// given height, else 0); landmarks without a height get it from the site's ground model, the
// level plane through the origin.
// out: *summary (may be NULL): malloc'ed text, one line per thing assumed (caller frees); NULL
//      on failure
// Errors, as "FILE:LINE: FIELD: what" where a file is at fault: RS_ERR_PARSE (malformed JSON or
// CSV, a missing field, a NUL byte, a value that is not a number), RS_ERR_INVALID (out of range,
// fewer than 4 points, a repeated id, a CRS GDAL does not know or of the wrong kind, no image
// size, a site check error), RS_ERR_UNSUPPORTED (intrinsics mrcal cannot hold), RS_ERR_IO,
// RS_ERR_NOMEM.
rs_status rs_site_import( // out
    char **summary,
    // in
    const char *dir, const rs_site_import_options *opt, rs_err *err);

// ---- the point files alone (`roadside pick` imports them into a session) ----

// One landmark picked in one camera's image.
typedef struct {
    char *id;        // owned: the file's id, or "P<row>" (the row or element from 1)
    double x, y;     // longitude, latitude in degrees (geographic) or easting, northing (projected)
    double h_m;      // the height as given, metres; NAN when none
    double q_px[2];  // u, v, pixels, as given
    double sigma_px; // the row's sigma_px; NAN when none
    int line;        // the line of the file it comes from (from 1), for messages
} rs_site_import_point;

typedef struct {
    rs_site_import_point *points; // owned, (N,)
    int N;
    bool geographic; // lat,lon (a point-pair JSON always) rather than e,n
    bool any_h;      // some point gives a height
} rs_site_import_points;

// Reads a point file as `site import` does (its one reader, rs_site_import_read.c): ".json"
// point pairs, else a CSV of lat,lon or e,n, u,v, optionally h, id, sigma_px; at least 4 points.
// out: *pts (zeroed first; rs_site_import_points_free even on failure)
// Errors as "PATH:LINE: FIELD: what": RS_ERR_PARSE, RS_ERR_INVALID, RS_ERR_IO, RS_ERR_NOMEM.
rs_status rs_site_import_read_points( // out
    rs_site_import_points *pts,
    // in
    const char *path, rs_err *err);
void rs_site_import_points_free(rs_site_import_points *pts); // accepts NULL

#ifdef __cplusplus
}
#endif

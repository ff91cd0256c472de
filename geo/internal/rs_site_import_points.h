// rs_site_import_points.h -- the point files of `site import` in memory (geo/rs_site_import.h):
// read by rs_site_import_read.c, the one reader of point-pair JSON and import CSVs; used by
// rs_site_import.c. Internal to geo.
#pragma once
#include <stdbool.h>

#include "core/rs_status.h"

// One landmark picked in one camera's image.
typedef struct {
    char *id;        // owned: the file's id, or "P<row>" (the row or element from 1)
    double x, y;     // longitude, latitude in degrees (geographic) or easting, northing (projected)
    double h_m;      // the height as given, metres; NAN when none
    double q_px[2];  // u, v, pixels, as given
    double sigma_px; // the row's sigma_px; NAN when none
    int line;        // the line of the file it comes from (from 1), for messages
} rs_site__import_point;

typedef struct {
    rs_site__import_point *points; // owned, (N,)
    int N;
    bool geographic; // lat,lon (a point-pair JSON always) rather than e,n
    bool any_h;      // some point gives a height
} rs_site__import_points;

// Reads a point file: ".json" point pairs {"results": [{"x", "y", "lat", "lng" (or "lon"), "id",
// "h" optional}, ...]}, else a CSV whose header names lat and lon (latitude, lng, longitude) or e
// and n (east, easting, north, northing), u and v, optionally h (height), id (landmark) and
// sigma_px (any case, any order). Every value is a plain decimal number; ids are unique and follow
// rs_io_name_problem; at least 4 points.
// out: *pts (zeroed first; rs_site__import_points_free even on failure)
// Errors as "PATH:LINE: FIELD: what": RS_ERR_PARSE, RS_ERR_INVALID, RS_ERR_IO, RS_ERR_NOMEM.
rs_status rs_site__import_read(rs_site__import_points *pts, const char *path, rs_err *err);

void rs_site__import_points_free(rs_site__import_points *pts); // accepts NULL

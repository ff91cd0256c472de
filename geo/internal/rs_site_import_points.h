// rs_site_import_points.h -- the point files of `site import` in memory (geo/rs_site_import.h):
// read by rs_site_import_read.c, the one reader of point-pair JSON and import CSVs; used by
// rs_site_import.c. Internal to geo.
#pragma once
#include <stdbool.h>

#include "core/rs_status.h"
#include "geo/rs_site_import.h"

// The public types (geo/rs_site_import.h) under geo's internal names.
typedef rs_site_import_point rs_site__import_point;
typedef rs_site_import_points rs_site__import_points;

// Reads a point file: ".json" point pairs {"results": [{"x", "y", "lat", "lng" (or "lon"), "id",
// "h" optional}, ...]}, else a CSV whose header names lat and lon (latitude, lng, longitude) or e
// and n (east, easting, north, northing), u and v, optionally h (height), id (landmark) and
// sigma_px (any case, any order). Every value is a plain decimal number; ids are unique and follow
// rs_io_name_problem; at least 4 points.
// out: *pts (zeroed first; rs_site__import_points_free even on failure)
// Errors as "PATH:LINE: FIELD: what": RS_ERR_PARSE, RS_ERR_INVALID, RS_ERR_IO, RS_ERR_NOMEM.
rs_status rs_site__import_read(rs_site__import_points *pts, const char *path, rs_err *err);

void rs_site__import_points_free(rs_site__import_points *pts); // accepts NULL

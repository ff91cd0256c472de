// rs_geo_crs.h -- coordinates of any coordinate reference system GDAL/PROJ knows (an EPSG code:
// UTM, state plane, national grids; WKT; PROJ strings) into WGS84 latitude and longitude, through
// GDAL's OGR coordinate transformation (PROJ underneath). Part of geo's GDAL library
// (geo_raster_dep): only its users link GDAL.
//
// Conventions: x, y in the CRS's "traditional GIS order" (easting then northing; longitude then
// latitude for a geographic CRS), whatever axis order the CRS's definition states; output
// llh = (lat_deg, lon_deg, h_m) with h passed through unchanged (heights are not transformed: a
// site declares its heights itself, docs/site-format.md).
//
// Accuracy: PROJ's, for the transformation PROJ picks between the CRS and WGS84 (EPSG:4326)
// without a grid (the same one `cs2cs EPSG:NNNN EPSG:4326` uses): exact to its arithmetic for
// WGS84-based projections such as UTM; for another datum (ETRS89, NAD83, ...) that transformation's
// own accuracy (EPSG states 1 m for ETRS89 -> WGS84, which it takes as the identity).
// tests/geo/test_site_import.py checks the ENU it leads to against cs2cs and cct to 1 mm.
#pragma once
#include <stdbool.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// Converts N points of `crs` (any text OSRSetFromUserInput takes: "EPSG:25832", a WKT, a PROJ
// string) into WGS84.
// out: llh (N,3) lat_deg, lon_deg, h_m; *geographic (may be NULL): whether `crs` is a geographic
//      CRS (its x, y are longitude, latitude) rather than a projected one, set once the CRS is
//      known even when a point then fails; *bad_row (may be NULL): the row (from 0) PROJ could not
//      transform, -1 when none
// in:  xyh (N,3) x, y (traditional GIS order, the CRS's units) and h (metres, passed through)
// Errors: RS_ERR_INVALID ("--crs CRS: not a CRS GDAL knows", a point PROJ cannot transform: "(x, y)
// of CRS: PROJ cannot transform it", with *bad_row), RS_ERR_EXTERNAL (GDAL could not make the transformation), RS_ERR_NOMEM.
rs_status rs_geo_crs_to_llh( // out
    double *llh, bool *geographic, int *bad_row,
    // in
    const char *crs, const double *xyh, int N, rs_err *err);

#ifdef __cplusplus
}
#endif

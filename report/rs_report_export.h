// rs_report_export.h -- a site's calibration for GIS tools (`roadside export`): cameras, their
// ground footprints, landmarks with their residuals and flags, lanes, as a GeoPackage or GeoJSON,
// and the ground uncertainty map as a georeferenced GeoTIFF. Written through GDAL/OGR (C API:
// gdal.h, ogr_api.h, ogr_srs_api.h), so any CRS PROJ knows is one option away.
//
// Layers (GeoPackage: one table each, with its description in gpkg_contents; GeoJSON: one
// FeatureCollection, each feature's "layer" property says which, since a GeoJSON file holds one
// layer):
//   cameras     Point Z at the camera centre: camera, east_m, north_m, up_m (site ENU), lat_deg,
//               lon_deg, h_m (WGS84 ellipsoidal), above_ground_m, heading_deg, pitch_deg,
//               roll_deg, their sigma_*, rms_surveyed_px, verdict (pass / FAIL / not audited),
//               need_ground_m, ground_sigma_median_m, ground_sigma_p90_m, loo_median_m, verdict_text,
//               enu_origin ("lat, lon, h" of the site's ENU origin)
//   footprints  Polygon: the ground each camera sees within range_m (the image border's rays on
//               the site's ground plane, through the full lens model; rs_report_camera_geometry),
//               camera, verdict
//   landmarks   Point Z at the surveyed position, one feature per landmark some camera picked:
//               landmark, east_m, north_m, up_m, sigma_h_m, sigma_v_m, cameras (", "-joined ids),
//               n_picks, n_inliers, loo_ground_error_m (the worst over its picks), flag
//   picks       Point Z at the surveyed position, one feature per (camera, pick): landmark,
//               camera, residual_u_px, residual_v_px, residual_px (surveyed, <id>.json),
//               normalised, inlier, loo_ground_error_m, loo_error_px, sigma_ground_m, flag (the
//               audit's reason in words, "" when fine)
//   lanes       LineString Z: the report's lane lines (edges, junction connectors), junction
// The GeoPackage also holds QGIS's layer_styles table (a default QML style for cameras and
// footprints by verdict, landmarks and picks on a leave-one-out ramp anchored at the need;
// report/internal/rs_report_export_style.h) and the site, origin, calibration folder and need as
// dataset metadata. The folders of the output paths are created.
// Coordinates: site ENU -> WGS84 (rs_geo_enu_to_llh, GeographicLib) -> the target CRS (OGR's
// coordinate transformation, PROJ). Default CRS EPSG:4326 written as (longitude, latitude,
// ellipsoidal height); with crs, e.g. "EPSG:25832", x and y are that CRS's and z stays the
// ellipsoidal height.
//
// The GeoTIFF: one Float32 band, the 1-sigma horizontal ground error in metres of a vehicle
// located by the best camera seeing each cell (the report's site map: the smallest of the
// cameras' rs_audit_map values), NaN (the band's nodata) where no camera sees the ground. Its
// native grid is the site's ENU (E, N) grid, written in the CRS "+proj=ortho" centred on the
// site's origin on WGS84, named "roadside site ENU at LAT, LON (orthographic on WGS84, metres)": the ellipsoidal orthographic projection is the tangent plane at the
// origin, so its (x, y) are the ENU (E, N) of points on the ellipsoid; for points at the site's
// height h they differ by about h d / R (9 mm at d = 100 m for h = 560 m), far below a cell.
// With crs the grid is warped into that CRS (nearest neighbour, GDALAutoCreateWarpedVRT).
//
// Every output is written under a temporary name and renamed into place; on failure none is
// left, not even an earlier one of the same name.
#pragma once
#include "audit/rs_audit.h"
#include "core/rs_status.h"
#include "geo/rs_site.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    const char *calib_dir;          // folder of <id>.cameramodel and <id>.json; NULL: SITE/calib
    const char *crs;                // target CRS (any text OSRSetFromUserInput takes); NULL: EPSG:4326
    double range_m;                 // footprints and maps within this distance, metres (default 100)
    rs_audit_options audit_options; // the audit of each camera (verdicts, flags, maps), as `roadside
                                    //   audit --calib CALIB_DIR` (default rs_audit_options_default)
} rs_report_export_options;

void rs_report_export_options_default(rs_report_export_options *opt);

typedef struct {
    int Ncameras, Nlandmarks, Npicks, Nlanes; // features written per layer (footprints: Ncameras)
    int raster_width, raster_height;          // the GeoTIFF's size (0 when none)
} rs_report_export_summary;

// Writes vector_path (.gpkg: GeoPackage; .geojson / .json: GeoJSON) and/or raster_path (.tif),
// either may be NULL (not both).
// Errors: RS_ERR_INVALID (unknown extension, a CRS GDAL does not know, naming it), those of
// loading the calibration files (as rs_report_write), RS_ERR_EXTERNAL (GDAL failed: its message),
// RS_ERR_IO, RS_ERR_NOMEM.
rs_status rs_report_export(            // out
    rs_report_export_summary *summary, // may be NULL
    // in
    const char *vector_path, // may be NULL
    const char *raster_path, // may be NULL
    const rs_site *site,
    const rs_report_export_options *opt, // may be NULL
    rs_err *err);                        // may be NULL

#ifdef __cplusplus
}
#endif

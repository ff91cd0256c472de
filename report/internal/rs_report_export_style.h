// rs_report_export_style.h -- what makes `roadside export`'s GeoPackage open styled in QGIS: the
// layer_styles table QGIS reads (one default QML style per layer: cameras and footprints coloured
// by the audit's verdict, landmarks and picks on a ramp of the leave-one-out ground error
// anchored at the need: green below need/2, yellow to the need, orange to twice the need, red
// beyond), and the dataset's metadata (site, origin, calibration folder, need). Private to
// report/ (rs_report_export_style.c).
#pragma once
#include <gdal.h>

#include "core/rs_status.h"
#include "geo/rs_site.h"

// Creates the layer_styles table in the GeoPackage ds (path: for messages) with QGIS's columns
// and one default style for each of the layers cameras, footprints, landmarks and picks.
// need_m: the need the ramp is anchored at, metres. Errors: RS_ERR_EXTERNAL (GDAL's message),
// RS_ERR_NOMEM.
rs_status rs_report_export_styles(GDALDatasetH ds, const char *path, double need_m, rs_err *err);

// Sets the dataset's metadata items: DESCRIPTION, ROADSIDE_SITE, ROADSIDE_SITE_DIR,
// ROADSIDE_CALIB_DIR, ROADSIDE_ENU_ORIGIN, ROADSIDE_NEED_GROUND_M.
void rs_report_export_metadata(GDALDatasetH ds, const rs_site *site, const char *calib_dir, double need_m);

// rs_synth_ortho.h -- an orthophoto of the site's digital twin (`roadside ortho`): the twin's
// world (the ground, the lane-edge markings, the sky light; rs_synth_twin.h's twin scene,
// the same scene code) seen from straight above by POV-Ray's orthographic camera.
//
// Method (rendered in tiles of at most 1024 pixels a side, one povray run each, each tile its own
// orthographic camera over its part of the grid): the camera looks down (direction -up) from above the highest ground point of the
// extent; its right vector is east, W cell_m long, its up vector north, H cell_m long. POV-Ray's
// orthographic camera shoots, for pixel column i and row j (no antialiasing), the ray starting at
//     location + ((i + 0.5)/W - 0.5) right + (0.5 - (j + 0.5)/H) up
// so pixel (i, j)'s centre looks at E = e_c + (i + 0.5 - W/2) cell_m, N = n_c - (j + 0.5 - H/2)
// cell_m: exactly the rs_geo_grid with e0 = e_c - (W - 1)/2 cell_m, n0 = n_c + (H - 1)/2 cell_m
// (geo/rs_geo_raster.h), what the GeoTIFF's geotransform then says. A tilted ground plane is
// drawn where it is (a true orthophoto: vertical projection).
//
// Accuracy: the geotransform is exact to double rounding for the twin's geometry; the markings'
// rendered edges are within half a cell (tests/pick/test_ortho.py measures the marking centres
// against PROJ's cs2cs of lanes.geojson and gdalinfo's geotransform).
#pragma once
#include "core/rs_image.h"
#include "core/rs_status.h"
#include "geo/rs_geo_raster.h"
#include "geo/rs_site.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    const char *povray;     // executable; NULL: $ROADSIDE_POVRAY, else "povray"
    double cell_m;          // ground sampling distance, metres (default 0.05), in [0.005, 10]
    double margin_m;        // extent: the lanes' edges and the landmarks, plus this (default 10)
    const char *weather;    // twin weather (default "cloudy": no cast shadows, flat light)
    double marking_width_m; // lane-edge marking width (default 0.15 m, as the backgrounds)
    int max_side;           // refuse an image larger than this on a side (default 8192)
} rs_synth_ortho_options;
void rs_synth_ortho_options_default(rs_synth_ortho_options *opt);

// Renders the orthophoto. Scene files go to work_dir (created if missing) and are removed.
// out: *image (H, W, 3) sRGB-encoded [0, 1] (rs_image_free); *grid, its site ENU grid
// in:  site (loaded), lanes_path (lanes.geojson; may be NULL: no markings), opt (may be NULL)
// Errors: RS_ERR_INVALID (options; an extent larger than max_side cells: the message gives the
// cell size that fits), RS_ERR_DEGENERATE (nothing to draw: no lane and no landmark),
// RS_ERR_EXTERNAL (povray missing or failed), those of reading the lanes.
rs_status rs_synth_ortho_render( // out
    rs_image *image, rs_geo_grid *grid,
    // in
    const char *work_dir, const rs_site *site, const char *lanes_path, const rs_synth_ortho_options *opt, rs_err *err);

#ifdef __cplusplus
}
#endif

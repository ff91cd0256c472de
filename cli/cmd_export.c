// roadside export: parse arguments, call rs_report_export, print what was written.
#include <getopt.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli/rs_cli.h"
#include "core/rs_io.h"
#include "eval/localise/rs_localise.h"
#include "eval/localise/rs_localise_dataset.h"
#include "geo/rs_geo_raster.h"
#include "geo/rs_site.h"
#include "report/rs_report_export.h"

static const char export_usage[] =
    "usage: roadside export SITE [--calib DIR] [-o OUT.gpkg|OUT.geojson] [--uncertainty OUT.tif]\n"
    "                       [--crs CRS] [options]\n"
    "       roadside export SITE [--calib DIR] --pixel-map OUT.tif|OUT.npz --camera ID\n"
    "                       [--pixel-sigma S]\n"
    "\n"
    "Writes a site's calibration for GIS tools (QGIS, ArcGIS, GDAL), through GDAL/OGR\n"
    "(docs/report.md, \"GIS export\"):\n"
    "  -o OUT.gpkg     a GeoPackage with five layers: cameras (position, height above the ground,\n"
    "                  heading, pitch, roll, their sigmas, the audit's verdict), footprints (the\n"
    "                  ground each camera sees within --range, a polygon), landmarks (one point per\n"
    "                  landmark picked: survey, cameras, worst leave-one-out ground error, flag),\n"
    "                  picks (one point per camera and pick: residuals, normalised residual,\n"
    "                  inlier, leave-one-out ground error, the audit's flag), lanes\n"
    "                  (SITE/lanes.geojson as drawn in the report); each layer with its description\n"
    "                  and a QGIS style (layer_styles: verdicts, a ramp anchored at the need)\n"
    "  -o OUT.geojson  the same in one GeoJSON FeatureCollection; each feature's \"layer\" property\n"
    "                  says which of the five it belongs to (no styles)\n"
    "  --uncertainty OUT.tif\n"
    "                  the ground uncertainty map as a GeoTIFF: per cell the 1-sigma horizontal\n"
    "                  error in metres of a vehicle located by the best camera seeing it (NaN:\n"
    "                  none sees it), in the site's ENU grid (a CRS named \"roadside site ENU at\n"
    "                  LAT, LON\": orthographic at the site's origin, metres) or warped into --crs\n"
    "  --pixel-map OUT.tif|OUT.npz\n"
    "                  for every pixel of camera --camera the ground point it sees and its 1-sigma\n"
    "                  (docs/localise.md, \"Pixel map\"): a GeoTIFF of the image's pixel grid with\n"
    "                  Float64 bands e_m, n_m, lat_deg, lon_deg, sigma_m, or a NumPy .npz of\n"
    "                  x_map (E), y_map (N), lat_map, lon_map, sigma_map (height x width); NaN\n"
    "                  where the pixel sees no ground. --pixel-sigma S: the detection noise (2 px)\n"
    "The folders of the outputs are created.\n"
    "The calibration is audited as 'roadside audit SITE --calib DIR' does (same thresholds), for\n"
    "the verdicts, flags and maps.\n"
    "\n"
    "Options:\n"
    "  --calib DIR           calibration folder (default SITE/calib)\n"
    "  --crs CRS             target CRS, any text GDAL accepts: EPSG:25832, EPSG:3857, a WKT or\n"
    "                        PROJ string (default EPSG:4326: longitude, latitude; z is always the\n"
    "                        WGS84 ellipsoidal height)\n"
    "  --range M             footprints and maps within M metres of each camera (default 100)\n"
    "  --cell M              uncertainty map cell size, metres (default 1)\n"
    "  --detection-px S      detection noise of the uncertainty map, px (default 1)\n"
    "  --need-ground-m X     the ground accuracy the site needs, for the verdicts (default 1)\n"
    "  -h, --help            this text\n"
    "\n"
    "Exit status: 0 when every file asked for was written, 1 when one could not be (then none\n"
    "is left under its name, not even an earlier export's), 2 on a usage error.\n";

// --pixel-map: camera `id`'s every pixel to the ground (eval/localise), written by geo's GDAL part.
static int export_pixel_map(const char *site_dir, const char *calib_dir, const char *id, const char *out,
                            double pixel_sigma)
{
    rs_site *site = rs_cli_load_site("export", site_dir);
    if (!site) return RS_EXIT_FAIL;
    if (rs_site_find_camera(site, id) < 0) {
        rs_site_free(site);
        return rs_cli_usage_error("export", "--camera: no camera \"%s\" in %s", id, site_dir);
    }
    rs_err err = {0};
    char *default_calib = calib_dir ? NULL : rs_io_join(site_dir, "calib"), model[4096];
    rs_camera cam = {0};
    double C[36];
    bool has_C = false;
    rs_localise_pixel_map map = {0};
    rs_status st =
        rs_camera_path(model, sizeof model, calib_dir ? calib_dir : default_calib, id, RS_CAMERA_EXT_CAMERAMODEL)
            ? RS_OK
            : rs_err_set(&err, RS_ERR_INVALID, "calibration folder: path too long");
    if (!st) st = rs_camera_read(&cam, NULL, model, &err);
    if (!st) st = rs_localise_covariance_read(C, &has_C, model, &err);
    if (!st) {
        if (!has_C)
            fprintf(stderr,
                    "roadside export: warning: %s: no pose covariance beside it: sigma_m holds the pixel "
                    "noise only\n",
                    model);
        const rs_localise_view view = rs_localise_view_make(&cam, has_C ? C : NULL, site->ground_normal_enu,
                                                            site->ground_offset_m, &site->origin);
        st = rs_localise_pixel_map_compute(&map, &view, pixel_sigma, &err);
    }
    size_t seen = 0;
    if (!st) {
        const bool npz = rs_io_has_extension(out, "npz");
        const double *band[5] = {map.e_m, map.n_m, map.lat_deg, map.lon_deg, map.sigma_m};
        const char *tif_names[5] = {"e_m", "n_m", "lat_deg", "lon_deg", "sigma_m"};
        const char *npz_names[5] = {"x_map", "y_map", "lat_map", "lon_map", "sigma_map"};
        const rs_geo_pixel_bands b = {map.width, map.height, 5, band, npz ? npz_names : tif_names};
        st = npz ? rs_geo_pixel_bands_write_npz(out, &b, &err) : rs_geo_pixel_bands_write_tiff(out, &b, &err);
        for (size_t k = 0; k < (size_t)map.width * (size_t)map.height; k++) seen += isfinite(map.e_m[k]);
    }
    if (!st)
        printf("%s: %d x %d pixels of %s, %zu see the ground (%.1f %%); pixel sigma %g px, pose covariance %s\n", out,
               map.width, map.height, id, seen, 100.0 * (double)seen / ((double)map.width * map.height), pixel_sigma,
               has_C ? "included" : "absent");
    rs_localise_pixel_map_free(&map);
    rs_camera_free(&cam);
    free(default_calib);
    rs_site_free(site);
    return st ? rs_cli_fail("export", st, &err) : RS_EXIT_OK;
}

int rs_cli_export(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        fputs(export_usage, stdout);
        return RS_EXIT_OK;
    }
    enum { O_CALIB = 256, O_UNC, O_CRS, O_RANGE, O_CELL, O_DET, O_NEED, O_PIXMAP, O_CAMERA, O_PIXSIGMA };
    static const struct option longopts[] = {
        {"output", required_argument, NULL, 'o'},
        {"calib", required_argument, NULL, O_CALIB},
        {"uncertainty", required_argument, NULL, O_UNC},
        {"crs", required_argument, NULL, O_CRS},
        {"range", required_argument, NULL, O_RANGE},
        {"cell", required_argument, NULL, O_CELL},
        {"detection-px", required_argument, NULL, O_DET},
        {"need-ground-m", required_argument, NULL, O_NEED},
        {"pixel-map", required_argument, NULL, O_PIXMAP},
        {"camera", required_argument, NULL, O_CAMERA},
        {"pixel-sigma", required_argument, NULL, O_PIXSIGMA},
        {NULL, 0, NULL, 0},
    };
    rs_report_export_options opt;
    rs_report_export_options_default(&opt);
    const char *vector = NULL, *raster = NULL, *pixel_map = NULL, *camera = NULL;
    double pixel_sigma = RS_LOCALISE_PIXEL_SIGMA_PX;
    optind = 1;
    int c, index = 0;
    double x = 0;
    while ((c = getopt_long(argc, argv, "o:", longopts, &index)) != -1) {
        switch (c) {
        case 'o': vector = optarg; break;
        case O_CALIB: opt.calib_dir = optarg; break;
        case O_UNC: raster = optarg; break;
        case O_CRS: opt.crs = optarg; break;
        case O_PIXMAP: pixel_map = optarg; break;
        case O_CAMERA: camera = optarg; break;
        case O_PIXSIGMA:
            if (!rs_cli_parse_double(optarg, &pixel_sigma) || pixel_sigma < 0)
                return rs_cli_usage_error("export", "--pixel-sigma: '%s': expected a number >= 0", optarg);
            break;
        case O_RANGE:
        case O_CELL:
        case O_DET:
        case O_NEED:
            if (!rs_cli_parse_double(optarg, &x) || !(x > 0))
                return rs_cli_usage_error("export", "--%s: '%s': expected a positive number", longopts[index].name,
                                          optarg);
            if (c == O_RANGE) opt.range_m = x;
            if (c == O_CELL) opt.audit_options.cell_m = x;
            if (c == O_DET) opt.audit_options.detection_sigma_px = x;
            if (c == O_NEED) opt.audit_options.need_ground_m = x;
            break;
        default: return rs_cli_usage_error("export", "unknown option or missing value: %s", argv[optind - 1]);
        }
    }
    if (optind != argc - 1) return rs_cli_usage_error("export", "expected one SITE folder");
    if (pixel_map || camera) {
        if (!pixel_map || !camera) return rs_cli_usage_error("export", "--pixel-map and --camera go together");
        if (vector || raster) return rs_cli_usage_error("export", "--pixel-map is an export of its own");
        if (!rs_io_has_extension(pixel_map, "tif") && !rs_io_has_extension(pixel_map, "npz"))
            return rs_cli_usage_error("export", "--pixel-map %s: expected OUT.tif or OUT.npz", pixel_map);
        return export_pixel_map(argv[optind], opt.calib_dir, camera, pixel_map, pixel_sigma);
    }
    if (!vector && !raster) return rs_cli_usage_error("export", "-o OUT.gpkg|OUT.geojson or --uncertainty OUT.tif");
    if (opt.range_m / opt.audit_options.cell_m > 4000)
        return rs_cli_usage_error("export", "--range / --cell = %g: at most 4000 cells across",
                                  opt.range_m / opt.audit_options.cell_m);
    const char *site_dir = argv[optind];
    rs_err err = {0};
    rs_site *site = NULL;
    rs_status st = rs_site_load(&site, site_dir, &err);
    if (st) {
        fprintf(stderr, "roadside export: %s\n(run 'roadside site check %s' for every problem)\n", err.msg, site_dir);
        return RS_EXIT_FAIL;
    }
    rs_report_export_summary sum;
    st = rs_report_export(&sum, vector, raster, site, &opt, &err);
    rs_site_free(site);
    if (st) {
        rs_cli_fail("export", st, &err);
        fprintf(stderr, "roadside export: nothing written\n");
        return RS_EXIT_FAIL;
    }
    if (vector)
        printf("%s: %d cameras, %d footprints, %d landmarks, %d picks, %d lane lines (%s)\n", vector, sum.Ncameras,
               sum.Ncameras, sum.Nlandmarks, sum.Npicks, sum.Nlanes, opt.crs ? opt.crs : "EPSG:4326");
    if (raster)
        printf("%s: %d x %d cells, 1-sigma ground error in metres (%s)\n", raster, sum.raster_width, sum.raster_height,
               opt.crs ? opt.crs : "the site's ENU grid");
    return RS_EXIT_OK;
}

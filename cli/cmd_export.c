// roadside export: parse arguments, call rs_report_export, print what was written.
#include <getopt.h>
#include <stdlib.h>
#include <string.h>

#include "cli/rs_cli.h"
#include "geo/rs_site.h"
#include "report/rs_report_export.h"

static const char export_usage[] =
    "usage: roadside export SITE [--calib DIR] [-o OUT.gpkg|OUT.geojson] [--uncertainty OUT.tif]\n"
    "                       [--crs CRS] [options]\n"
    "\n"
    "Writes a site's calibration for GIS tools (QGIS, ArcGIS, GDAL), through GDAL/OGR\n"
    "(docs/report.md, \"GIS export\"):\n"
    "  -o OUT.gpkg     a GeoPackage with four layers: cameras (position, height above the ground,\n"
    "                  heading, pitch, roll, their sigmas, the audit's verdict), footprints (the\n"
    "                  ground each camera sees within --range, a polygon), landmarks (one point per\n"
    "                  camera and pick: residuals, normalised residual, inlier, leave-one-out ground\n"
    "                  error, the audit's flag), lanes (SITE/lanes.geojson as drawn in the report)\n"
    "  -o OUT.geojson  the same in one GeoJSON FeatureCollection; each feature's \"layer\" property\n"
    "                  says which of the four it belongs to\n"
    "  --uncertainty OUT.tif\n"
    "                  the ground uncertainty map as a GeoTIFF: per cell the 1-sigma horizontal\n"
    "                  error in metres of a vehicle located by the best camera seeing it (NaN:\n"
    "                  none sees it), in the site's ENU grid (an orthographic CRS at the site's\n"
    "                  origin) or warped into --crs\n"
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

int rs_cli_export(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        fputs(export_usage, stdout);
        return RS_EXIT_OK;
    }
    enum { O_CALIB = 256, O_UNC, O_CRS, O_RANGE, O_CELL, O_DET, O_NEED };
    static const struct option longopts[] = {
        {"output", required_argument, NULL, 'o'},
        {"calib", required_argument, NULL, O_CALIB},
        {"uncertainty", required_argument, NULL, O_UNC},
        {"crs", required_argument, NULL, O_CRS},
        {"range", required_argument, NULL, O_RANGE},
        {"cell", required_argument, NULL, O_CELL},
        {"detection-px", required_argument, NULL, O_DET},
        {"need-ground-m", required_argument, NULL, O_NEED},
        {NULL, 0, NULL, 0},
    };
    rs_report_export_options opt;
    rs_report_export_options_default(&opt);
    const char *vector = NULL, *raster = NULL;
    optind = 1;
    int c, index = 0;
    double x = 0;
    while ((c = getopt_long(argc, argv, "o:", longopts, &index)) != -1) {
        switch (c) {
        case 'o': vector = optarg; break;
        case O_CALIB: opt.calib_dir = optarg; break;
        case O_UNC: raster = optarg; break;
        case O_CRS: opt.crs = optarg; break;
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
        default: return rs_cli_usage_error("export", "unknown option");
        }
    }
    if (optind != argc - 1) return rs_cli_usage_error("export", "expected one SITE folder");
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
        printf("%s: %d cameras, %d footprints, %d landmark picks, %d lane lines (%s)\n", vector, sum.Ncameras,
               sum.Ncameras, sum.Nlandmarks, sum.Nlanes, opt.crs ? opt.crs : "EPSG:4326");
    if (raster)
        printf("%s: %d x %d cells, 1-sigma ground error in metres (%s)\n", raster, sum.raster_width, sum.raster_height,
               opt.crs ? opt.crs : "the site's ENU grid");
    return RS_EXIT_OK;
}

// roadside site import -- a site from point pairs and intrinsics (geo/rs_site_import.h).
#include <stdlib.h>
#include <string.h>

#include "cli/rs_cli.h"
#include "geo/rs_site_import.h"

static const char *const CMD = "site import";

enum { MAX_POINT_FILES = 64 };

static void usage(FILE *out)
{
    fprintf(out,
            "usage: roadside site import DIR --points FILE [--camera ID] [--image IMG]\n"
            "                            [--points FILE [--camera ID] [--image IMG] ...]\n"
            "                            [--crs EPSG:NNNN] [--intrinsics FILE] [--image-size WxH]\n"
            "                            [--source map|gnss|survey] [--sigma-px S] [--sigma-h-m S]\n"
            "                            [--sigma-v-m S] [--orthometric N] [--name TEXT] [--force]\n"
            "\n"
            "Builds the site folder DIR from landmarks picked both on a map and in a camera's image,\n"
            "one points file per camera, and prints what it assumed. The site passes 'site check';\n"
            "then 'roadside calib DIR' (with '--refine focal' when no intrinsics were given).\n"
            "\n"
            "  --points FILE     a camera's point pairs (repeatable, one file per camera):\n"
            "                    .json  {\"results\": [{\"x\": 412, \"y\": 380, \"lat\": 40.44231,\n"
            "                           \"lng\": -79.94562, \"id\": \"0\"}, ...]} (x, y: pixels)\n"
            "                    .csv   a header, then rows: lat,lon,u,v[,h] or e,n,u,v[,h] (any order;\n"
            "                           optional columns id and sigma_px)\n"
            "  --camera ID       the id of the camera of the --points before it (default: the file's\n"
            "                    name without its extension)\n"
            "  --image IMG       a frame of that camera: its size is the image size (default: an image\n"
            "                    beside the points file with the same name, .jpg .png .tif ...)\n"
            "  --crs CRS         the CRS of the coordinates: EPSG:25832 (UTM 32N, ETRS89), a state\n"
            "                    plane, a national grid, any text GDAL accepts; e,n columns need a\n"
            "                    projected CRS, lat,lon a geographic one (default EPSG:4326, WGS84)\n"
            "  --intrinsics FILE the lens of every camera: an mrcal .cameramodel, OpenCV YAML/JSON\n"
            "                    (pinhole, or distortion_model fisheye), or the equidistant fisheye\n"
            "                    {\"f\": 340.0, \"x0\": 640, \"y0\": 480} (.json, r = f theta). Without it:\n"
            "                    a nominal pinhole, f = the image width; calibrate with --refine focal\n"
            "  --image-size WxH  the image size, pixels, without an image (with --intrinsics: it must\n"
            "                    agree with the file's, or give the size a file lacks)\n"
            "  --source S        where the coordinates come from, which sets the landmark sigmas\n"
            "                    (horizontal, vertical): map (picked on a map or orthophoto: 0.5 m,\n"
            "                    0.5 m; the default), gnss (RTK: 0.05 m, 0.10 m), survey (0.01 m, 0.02 m)\n"
            "  --sigma-h-m S, --sigma-v-m S   the landmark sigmas, metres, instead of the source's\n"
            "  --sigma-px S      the pick sigma of rows without sigma_px, pixels [%g]\n"
            "  --orthometric N   given heights are orthometric, N = geoid undulation in metres\n"
            "  --name TEXT       the site's name (default: the folder's last part)\n"
            "  --force           replace DIR if it is a site folder (never anything else)\n"
            "\n"
            "Heights: rows without h get theirs from the site's ground model (\"landmark_heights\":\n"
            "\"unknown\": the level plane through the origin, the centroid of the landmarks). With\n"
            "several cameras, landmark ids are prefixed '<camera>:'. Bad input is reported as\n"
            "FILE:LINE: FIELD: what, and nothing is written.\n"
            "\n"
            "Exit status: 0 ok, 1 failure, 2 usage error.\n",
            RS_SITE_IMPORT_SIGMA_PX);
}

// The value of a numeric option; false (with the usage error printed) when it is not a number.
static bool number_option(double *out, const char *opt, const char *v)
{
    if (rs_cli_parse_double(v, out) && *out > 0) return true;
    rs_cli_usage_error(CMD, "%s: '%s' is not a positive number", opt, v);
    return false;
}

// One option with its value v into o / cams; returns RS_EXIT_OK or the usage error's code.
static int option(rs_site_import_options *o, rs_site_import_camera *cams, double *N, const char *opt, const char *v)
{
    const int last = o->Ncameras - 1;
    if (!strcmp(opt, "--points")) {
        if (o->Ncameras == MAX_POINT_FILES) return rs_cli_usage_error(CMD, "more than %d --points", MAX_POINT_FILES);
        cams[o->Ncameras++] = (rs_site_import_camera){.points = v};
    } else if (!strcmp(opt, "--camera") || !strcmp(opt, "--image")) {
        if (last < 0) return rs_cli_usage_error(CMD, "%s applies to the --points before it: give --points first", opt);
        *(!strcmp(opt, "--camera") ? &cams[last].id : &cams[last].image) = v;
    } else if (!strcmp(opt, "--crs")) {
        o->crs = v;
    } else if (!strcmp(opt, "--intrinsics")) {
        o->intrinsics = v;
    } else if (!strcmp(opt, "--image-size")) {
        double w, h;
        if (!rs_cli_parse_pair(v, 'x', &w, &h) || w != (int)w || h != (int)h || w < 1 || h < 1 || w > 1e6 || h > 1e6)
            return rs_cli_usage_error(CMD, "--image-size: '%s' is not WIDTHxHEIGHT in pixels", v);
        o->width = (int)w, o->height = (int)h;
    } else if (!strcmp(opt, "--source")) {
        o->source = !strcmp(v, "map")    ? RS_SITE_IMPORT_MAP
                    : !strcmp(v, "gnss") ? RS_SITE_IMPORT_GNSS
                                         : RS_SITE_IMPORT_SURVEY;
        if (strcmp(v, rs_site_import_source_name(o->source)))
            return rs_cli_usage_error(CMD, "--source: '%s' is not map, gnss or survey", v);
    } else if (!strcmp(opt, "--sigma-px") || !strcmp(opt, "--sigma-h-m") || !strcmp(opt, "--sigma-v-m")) {
        double *dst = !strcmp(opt, "--sigma-px")    ? &o->sigma_px
                      : !strcmp(opt, "--sigma-h-m") ? &o->sigma_h_m
                                                    : &o->sigma_v_m;
        if (!number_option(dst, opt, v)) return RS_EXIT_USAGE;
    } else if (!strcmp(opt, "--orthometric")) {
        if (!rs_cli_parse_double(v, N))
            return rs_cli_usage_error(CMD, "--orthometric: '%s' is not a number of metres", v);
        o->geoid_undulation_m = N;
    } else if (!strcmp(opt, "--name")) {
        o->name = v;
    } else {
        return rs_cli_usage_error(CMD, "unknown option '%s'", opt);
    }
    return RS_EXIT_OK;
}

int rs_cli_site_import(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        usage(stdout);
        return RS_EXIT_OK;
    }
    rs_site_import_camera cams[MAX_POINT_FILES];
    rs_site_import_options o = {.cameras = cams};
    double N = 0;
    const char *dir = NULL;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--force")) {
            o.force = true;
        } else if (argv[i][0] == '-' && argv[i][1]) {
            if (i + 1 >= argc) return rs_cli_usage_error(CMD, "%s needs a value", argv[i]);
            const int rc = option(&o, cams, &N, argv[i], argv[i + 1]);
            if (rc != RS_EXIT_OK) return rc;
            i++;
        } else if (dir) {
            return rs_cli_usage_error(CMD, "one DIR only ('%s' and '%s')", dir, argv[i]);
        } else {
            dir = argv[i];
        }
    }
    if (!dir) return rs_cli_usage_error(CMD, "missing DIR (the site folder to create)");
    if (!o.Ncameras) return rs_cli_usage_error(CMD, "missing --points FILE");
    char *summary = NULL;
    rs_err err = {0};
    rs_status st = rs_site_import(&summary, dir, &o, &err);
    if (st != RS_OK) return rs_cli_fail(CMD, st, &err);
    printf("imported %s: %d camera%s\nassumed:\n", dir, o.Ncameras, o.Ncameras == 1 ? "" : "s");
    for (char *line = summary, *next; line && *line; line = next) {
        next = strchr(line, '\n');
        if (next) *next++ = '\0';
        printf("  %s\n", line);
    }
    free(summary);
    printf("next: roadside site check %s; roadside calib %s%s\n", dir, dir, o.intrinsics ? "" : " --refine focal");
    return RS_EXIT_OK;
}

// roadside ortho: parse arguments, render the digital twin's orthophoto (synth/povray/rs_synth_ortho.h),
// write it as a GeoTIFF (geo/rs_geo_raster.h), print its grid.
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli/rs_cli.h"
#include "core/rs_io.h"
#include "geo/rs_geo_raster.h"
#include "geo/rs_site.h"
#include "synth/povray/rs_synth_ortho.h"

static const char ortho_usage[] =
    "usage: roadside ortho SITE -o ORTHO.tif [--gsd M] [--margin M] [--weather W] [--crs CRS]\n"
    "\n"
    "Renders an orthophoto of the site's digital twin (textured asphalt, the lane edges, crosswalks,\n"
    "stop bars and arrows of SITE/lanes.geojson, kerbs, sidewalks and poles; the scene of 'roadside\n"
    "site render-backgrounds', docs/backgrounds.md) with POV-Ray's\n"
    "orthographic camera looking straight down, and writes it as a georeferenced RGB GeoTIFF\n"
    "through GDAL (docs/pick.md, \"roadside ortho\"). The extent covers the lanes and the\n"
    "landmarks plus --margin. The GeoTIFF's CRS is the site's ENU grid (an orthographic\n"
    "projection at the site's origin: x = east, y = north in metres), or --crs.\n"
    "A demo and the tests use it as the orthophoto of 'roadside pick'; with a real site it shows\n"
    "whether an orthophoto's georeference agrees with the survey (overlay the two in a GIS).\n"
    "\n"
    "Options:\n"
    "  -o, --output FILE   the GeoTIFF (.tif), written atomically (required)\n"
    "  --gsd M             ground sampling distance, metres per pixel (default 0.05)\n"
    "  --margin M          metres around the lanes and landmarks (default 10)\n"
    "  --weather W         sunny, cloudy, rain, snow or night (default cloudy: no cast shadows)\n"
    "  --crs CRS           warp into this CRS (EPSG:25832, ...; nearest neighbour)\n"
    "  -h, --help          this text\n"
    "\n"
    "Exit status: 0 written, 1 failed (nothing left under the name), 2 usage error.\n";

int rs_cli_ortho(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        fputs(ortho_usage, stdout);
        return RS_EXIT_OK;
    }
    enum { O_GSD = 256, O_MARGIN, O_WEATHER, O_CRS };
    static const struct option longopts[] = {
        {"output", required_argument, NULL, 'o'},      {"gsd", required_argument, NULL, O_GSD},
        {"margin", required_argument, NULL, O_MARGIN}, {"weather", required_argument, NULL, O_WEATHER},
        {"crs", required_argument, NULL, O_CRS},       {NULL, 0, NULL, 0},
    };
    rs_synth_ortho_options opt;
    rs_synth_ortho_options_default(&opt);
    const char *out = NULL, *crs = NULL;
    optind = 1;
    int c;
    while ((c = getopt_long(argc, argv, "o:", longopts, NULL)) != -1) {
        switch (c) {
        case 'o': out = optarg; break;
        case O_GSD:
            if (!rs_cli_parse_double(optarg, &opt.cell_m) || !(opt.cell_m >= 0.005 && opt.cell_m <= 10))
                return rs_cli_usage_error("ortho", "--gsd: '%s': expected metres per pixel in [0.005, 10]", optarg);
            break;
        case O_MARGIN:
            if (!rs_cli_parse_double(optarg, &opt.margin_m) || !(opt.margin_m >= 0 && opt.margin_m <= 1000))
                return rs_cli_usage_error("ortho", "--margin: '%s': expected metres in [0, 1000]", optarg);
            break;
        case O_WEATHER: opt.weather = optarg; break;
        case O_CRS: crs = optarg; break;
        default: return rs_cli_usage_error("ortho", "unknown option or missing value: %s", argv[optind - 1]);
        }
    }
    if (optind != argc - 1) return rs_cli_usage_error("ortho", "expected one SITE folder");
    if (!out) return rs_cli_usage_error("ortho", "-o ORTHO.tif is required");
    if (!rs_io_has_extension(out, "tif") && !rs_io_has_extension(out, "tiff"))
        return rs_cli_usage_error("ortho", "-o %s: expected a .tif file name", out);
    const char *site_dir = argv[optind];
    // as `pick` reads it: a site being onboarded may have cameras without picks yet
    rs_err err = {0};
    rs_site *site = NULL;
    rs_status lst = rs_site_load_for_picking(&site, site_dir, &err);
    if (lst) return rs_cli_fail("ortho", lst, &err);

    char *lanes = rs_io_join(site_dir, RS_SITE_LANES);
    if (lanes && access(lanes, F_OK) != 0) {
        fprintf(stderr, "roadside ortho: %s: none; the orthophoto shows the ground only\n", lanes);
        free(lanes);
        lanes = NULL;
    }
    // povray's work folder: a fresh one next to the output (povray may write only there)
    char *work = NULL;
    {
        const char *slash = strrchr(out, '/');
        const size_t dl = slash ? (size_t)(slash - out) : 1;
        work = malloc(dl + 32);
        if (work) snprintf(work, dl + 32, "%.*s/.ortho-work-XXXXXX", (int)dl, slash ? out : ".");
    }
    rs_status st = work ? RS_OK : rs_err_set(&err, RS_ERR_NOMEM, "out of memory");
    const bool made = !st && mkdtemp(work);
    if (!st && !made)
        st = errno == ENOSPC
                 ? rs_err_set(&err, RS_ERR_IO, "disk full writing %s", work)
                 : rs_err_set(&err, RS_ERR_IO, "%s: cannot create the work folder: %s", work, strerror(errno));
    rs_image img = {0};
    rs_geo_grid grid;
    unsigned char *rgb = NULL;
    int w = 0, h = 0;
    // progress on stderr: the render takes seconds to minutes (18 s for the demo at 0.1 m)
    if (!st)
        fprintf(stderr, "roadside ortho: rendering the digital twin from above with POV-Ray, %g m per pixel\n",
                opt.cell_m);
    if (!st) st = rs_synth_ortho_render(&img, &grid, work, site, lanes, &opt, &err);
    if (!st) fprintf(stderr, "roadside ortho: writing %s (%d x %d px)\n", out, img.width, img.height);
    if (!st && !(rgb = malloc((size_t)img.width * img.height * 3)))
        st = rs_err_set(&err, RS_ERR_NOMEM, "out of memory");
    if (!st) {
        for (size_t p = 0; p < (size_t)img.width * img.height * 3; p++) {
            const float v = img.data[p];
            rgb[p] = (unsigned char)lrintf(255.0f * (v < 0 ? 0 : v > 1 ? 1 : v));
        }
        const rs_geo_raster r = {.grid = grid,
                                 .Nbands = 3,
                                 .type = RS_GEO_RASTER_BYTE,
                                 .data = rgb,
                                 .description = "digital twin orthophoto (roadside ortho)",
                                 .crs = crs};
        st = rs_geo_raster_write(&w, &h, out, &site->origin, &r, &err);
    }
    if (made) rs_io_remove_tree(work); // a fresh folder of this run's own: gone whatever happened
    if (!st)
        printf("%s: %dx%d pixels of %g m; site ENU grid: pixel (0,0) centre at E %.3f N %.3f; %s\n", out, w, h,
               grid.cell_m, grid.e0_m, grid.n0_m, crs ? crs : "CRS: the site's ENU grid (+proj=ortho at the origin)");
    free(rgb);
    rs_image_free(&img);
    free(work);
    free(lanes);
    rs_site_free(site);
    return st ? rs_cli_fail("ortho", st, &err) : RS_EXIT_OK;
}

// roadside pick: parse arguments, open the picking session and its server (pick/rs_pick.h),
// print the URL, serve until interrupted.
#include <getopt.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli/rs_cli.h"
#include "geo/rs_geo_raster.h"
#include "geo/rs_site.h"
#include "pick/rs_pick.h"

static const char pick_usage[] =
    "usage: roadside pick SITE --camera ID [--image FRAME] [--ortho ORTHO.tif] [--port N] [--host ADDR]\n"
    "\n"
    "Survey onboarding in the browser (docs/pick.md). Starts a local web server and prints its\n"
    "URL; the page shows the camera image and the site from above side by side. Click a point in\n"
    "one view and its match in the other (or choose a surveyed landmark from the list and click it\n"
    "in the image). From four picks on, every change re-solves the camera with the solver of\n"
    "'roadside calib' (same problem, same options) and shows the residuals, the flagged landmarks\n"
    "and why, every landmark's predicted pixel, the camera's position, heading and uncertainty\n"
    "ellipse, and the ground uncertainty over the view. Save writes SITE/landmarks.geojson and the\n"
    "camera's observations CSV atomically; 'roadside calib SITE' then finds the same pose.\n"
    "\n"
    "Options:\n"
    "  --camera ID        the camera (required)\n"
    "  --image FRAME      the camera image (PNG, JPEG; default: the camera's first background in\n"
    "                     site.json, else a grey canvas)\n"
    "  --ortho FILE       a georeferenced orthophoto (GeoTIFF or any GDAL raster, any CRS:\n"
    "                     reprojected onto the site's ENU grid); default: a plain map of the\n"
    "                     landmarks and lanes ('roadside ortho' makes one of the digital twin)\n"
    "  --port N           port (default 0: any free one)\n"
    "  --host ADDR        IPv4 address to bind (default 127.0.0.1; anything else exposes the\n"
    "                     site's files to the network: the page has no login)\n"
    "  --max-side N       orthophoto decimated to at most N pixels a side (default 4096)\n"
    "  -h, --help         this text\n"
    "\n"
    "Stops on Ctrl-C (SIGINT) or SIGTERM; unsaved changes are lost (the page says when it has some).\n"
    "Exit status: 0 after a clean stop, 1 when the site, image or orthophoto cannot be read or the\n"
    "port not bound, 2 on a usage error.\n";

static volatile sig_atomic_t stop_requested;
static void on_signal(int sig)
{
    (void)sig;
    stop_requested = 1;
}

int rs_cli_pick(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        fputs(pick_usage, stdout);
        return RS_EXIT_OK;
    }
    enum { O_CAMERA = 256, O_IMAGE, O_ORTHO, O_PORT, O_HOST, O_MAXSIDE };
    static const struct option longopts[] = {
        {"camera", required_argument, NULL, O_CAMERA},
        {"image", required_argument, NULL, O_IMAGE},
        {"ortho", required_argument, NULL, O_ORTHO},
        {"port", required_argument, NULL, O_PORT},
        {"host", required_argument, NULL, O_HOST},
        {"max-side", required_argument, NULL, O_MAXSIDE},
        {NULL, 0, NULL, 0},
    };
    const char *camera = NULL, *image = NULL, *ortho_path = NULL;
    rs_pick_server_options sopt;
    rs_pick_server_options_default(&sopt);
    long port = 0, max_side = 4096;
    optind = 1;
    int c;
    while ((c = getopt_long(argc, argv, "", longopts, NULL)) != -1) {
        switch (c) {
        case O_CAMERA: camera = optarg; break;
        case O_IMAGE: image = optarg; break;
        case O_ORTHO: ortho_path = optarg; break;
        case O_PORT:
            if (!rs_cli_parse_int(optarg, 0, 65535, &port))
                return rs_cli_usage_error("pick", "--port: '%s': expected 0..65535", optarg);
            break;
        case O_HOST: sopt.host = optarg; break;
        case O_MAXSIDE:
            if (!rs_cli_parse_int(optarg, 16, 16384, &max_side))
                return rs_cli_usage_error("pick", "--max-side: '%s': expected 16..16384", optarg);
            break;
        default: return rs_cli_usage_error("pick", "unknown option or missing value: %s", argv[optind - 1]);
        }
    }
    if (optind != argc - 1) return rs_cli_usage_error("pick", "expected one SITE folder");
    if (!camera) return rs_cli_usage_error("pick", "--camera ID is required");
    const char *site_dir = argv[optind];
    sopt.port = (int)port;

    rs_err err = {0};
    rs_pick_session *s = NULL;
    rs_status st = rs_pick_session_open(&s, site_dir, camera, &err);
    if (st) return rs_cli_fail("pick", st, &err);
    rs_site *site = NULL; // for the background's path and the origin
    if ((st = rs_site_load_for_picking(&site, site_dir, &err))) {
        rs_pick_session_free(s);
        return rs_cli_fail("pick", st, &err);
    }
    const rs_site_camera *cam = &site->cameras[rs_site_find_camera(site, camera)];
    if (!image && cam->Nbackground_images > 0) image = cam->background_images[0].path;
    if (!image) fprintf(stderr, "roadside pick: no --image and no background for %s: a grey canvas\n", camera);
    sopt.image_path = image;
    rs_geo_ortho ortho = {0};
    if (ortho_path && (st = rs_geo_ortho_read(&ortho, ortho_path, &site->origin, (int)max_side, &err))) {
        rs_site_free(site);
        rs_pick_session_free(s);
        return rs_cli_fail("pick", st, &err);
    }
    if (ortho_path) {
        sopt.ortho = &ortho;
        printf("orthophoto %s (%s%s): %dx%d cells of %.3f m on the site's grid\n", ortho_path, ortho.crs_name,
               ortho.warped ? ", reprojected" : "", ortho.grid.width, ortho.grid.height, ortho.grid.cell_m);
    }
    rs_pick_server *srv = NULL;
    if ((st = rs_pick_server_start(&srv, s, &sopt, &err))) {
        rs_geo_ortho_free(&ortho);
        rs_site_free(site);
        rs_pick_session_free(s);
        return rs_cli_fail("pick", st, &err);
    }
    struct sigaction sa = {0};
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    printf("roadside pick: camera %s of %s, %d picks\n%s\n", camera, site_dir, rs_pick_count(s),
           rs_pick_server_url(srv));
    fflush(stdout);
    while (!stop_requested) pause();
    rs_pick_server_stop(srv);
    rs_geo_ortho_free(&ortho);
    rs_site_free(site);
    rs_pick_session_free(s);
    return RS_EXIT_OK;
}

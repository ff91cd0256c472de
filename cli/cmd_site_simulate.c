// roadside site simulate -- writes a synthetic site with a known truth (sim/rs_simulate.h).
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "cli/rs_cli.h"
#include "sim/rs_simulate.h"

static const char *const CMD = "site simulate";

static void usage(FILE *out, const rs_simulate_site_options *d)
{
    fprintf(out,
            "usage: roadside site simulate DIR --seed N [options]\n"
            "\n"
            "Writes a synthetic site into DIR: a four-approach intersection (two roads of two 3.5 m\n"
            "lanes each way, stop bars, crosswalks, lane marks, signs) watched by cameras on poles at\n"
            "its corners (then beside the approaches), in the site format (site.json,\n"
            "landmarks.geojson, cameras/, observations/), plus truth/ with the true poses,\n"
            "lenses and landmark positions. The same seed and options give a byte-identical site.\n"
            "\n"
            "Options (defaults in brackets):\n"
            "  --seed N                  random seed, 0 .. 2^53 (required)\n"
            "  --cameras K               number of cameras, 1..16 [%d]\n"
            "  --landmarks-per-camera M  about this many points seen by each camera, 4..100 (0..100\n"
            "                            with --poles or --lines) [%d]; --points M is the same\n"
            "  --poles N                 about this many poles seen by each camera, 0..50 [0]:\n"
            "                            delineator posts (1.0-1.2 m) along the road edges, lamp posts\n"
            "                            (6-10 m) and sign posts (3-4.5 m); each picked at its base and\n"
            "                            top where they are in the image, and once along it\n"
            "  --lines N                 about this many lines seen by each camera, 0..20 [0]: stop\n"
            "                            bars, centre and edge lines, kerbs round the corners; each\n"
            "                            picked 3 times along its visible part\n"
            "  --lens MODEL              any mrcal lens model name [%s]; configured models in\n"
            "                            full, e.g. LENSMODEL_SPLINED_STEREOGRAPHIC_order=3_Nx=16_Ny=12_fov_x_deg=100\n"
            "  --fisheye KIND            every camera an overhead fisheye on a mast over the junction\n"
            "                            (8-11 m up): equidistant (r = f theta) or kannala-brandt\n"
            "                            (k1, k2 drawn), as mrcal's LENSMODEL_CAHVORE_linearity=0.00;\n"
            "                            image 1280x960 and --hfov-deg 216 (f = 340 px) unless given\n"
            "  --image WxH               image size in pixels [%dx%d]\n"
            "  --hfov-deg D              horizontal field of view, degrees [%g]\n"
            "  --pixel-sigma PX          pixel noise of the picks, pixels [%g]\n"
            "  --survey-sigma H,V        survey noise of the landmarks, horizontal and vertical, m [%g,%g]\n"
            "  --outliers FRACTION       share of picks replaced by a wrong pixel > 30 px away [%g]\n"
            "  --focal-error FACTOR      nominal focal length in cameras/ = true one * FACTOR [%g]\n"
            "  --focal-error-range S     and each camera's further times a factor drawn log-uniformly\n"
            "                            in [1/S, S], 1..2 (a focal nobody knows) [%g]\n"
            "  --elevated-fraction F     share of each camera's points above the ground (sign tops,\n"
            "                            poles), 0..1; 0: points picked on a map, all on the ground [%g]\n"
            "  --pole-prior SIGMA_M      give each camera a position prior: its true position plus\n"
            "                            N(0, SIGMA_M) noise per axis [none]\n"
            "  --origin LAT,LON,H        site origin, degrees, degrees, m ellipsoidal [%g,%g,%g]\n"
            "  --height-noise M          more noise on the heights of the landmarks on the ground,\n"
            "                            N(0, M) metres (raw GNSS heights), declared in their sigma\n"
            "                            (the rest of the site is the same as without it) [0]\n"
            "  --landmark-heights H      site.json \"landmark_heights\" for the landmarks on the\n"
            "                            ground: surveyed, unreliable or unknown (written [lon, lat]);\n"
            "                            those above it then say \"height\": \"surveyed\" and their\n"
            "                            above_ground_m (docs/site-format.md) [not written]\n"
            "  --force                   replace DIR if it holds a site this command wrote and\n"
            "                            nothing else (its .roadside-simulated record lists the files)\n"
            "\n"
            "A site of only poles and lines: --points 0 --poles N --lines M. Their picks' truth (the\n"
            "true point picked) is in truth/picks.csv, their true geometry in truth/vertices_enu.csv.\n"
            "\n"
            "With zero noise the site still declares sigmas of 1 mm and 0.01 px (a site needs\n"
            "sigmas > 0); site.json's \"simulated\" records the noise actually drawn.\n"
            "DIR must not exist, be empty, or (with --force) hold a simulated site: a surveyor's site,\n"
            "or a simulated one with files added, is never replaced. The site is built in a\n"
            "hidden sibling folder and renamed into place, so a failure never leaves half a site.\n"
            "Exit status: 0 written, 1 failed (nothing written), 2 bad arguments.\n",
            d->Ncameras, d->landmarks_per_camera, d->lensmodel, d->width_px, d->height_px, d->hfov_deg,
            d->pixel_sigma_px, d->survey_sigma_h_m, d->survey_sigma_v_m, d->outlier_fraction, d->focal_error,
            d->focal_error_range, d->elevated_fraction, d->origin.lat_deg, d->origin.lon_deg, d->origin.h_m);
}

int rs_cli_site_simulate(int argc, char **argv)
{
    rs_simulate_site_options o;
    rs_simulate_site_options_default(&o);
    if (rs_cli_wants_help(argc, argv)) {
        usage(stdout, &o);
        return RS_EXIT_OK;
    }
    const char *dir = NULL;
    bool have_seed = false, have_image = false, have_hfov = false;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "--force") == 0) {
            o.force = true;
            continue;
        }
        if (strncmp(a, "--", 2) != 0 || strcmp(a, "--") == 0) {
            if (strcmp(a, "--") == 0 && i + 1 < argc) a = argv[++i];
            if (dir) return rs_cli_usage_error(CMD, "one folder only: '%s' and '%s'", dir, a);
            dir = a;
            continue;
        }
        if (i + 1 >= argc) return rs_cli_usage_error(CMD, "%s: needs a value", a);
        const char *v = argv[++i];
        long n;
        double x, y;
        if (strcmp(a, "--seed") == 0) {
            if (!rs_cli_parse_int(v, 0, 9007199254740992L, &n))
                return rs_cli_usage_error(CMD, "--seed: '%s' is not an integer in 0 .. 2^53", v);
            o.seed = (uint64_t)n;
            have_seed = true;
        } else if (strcmp(a, "--cameras") == 0) {
            if (!rs_cli_parse_int(v, 1, 16, &n)) return rs_cli_usage_error(CMD, "--cameras: '%s' is not in 1..16", v);
            o.Ncameras = (int)n;
        } else if (strcmp(a, "--landmarks-per-camera") == 0 || strcmp(a, "--points") == 0) {
            if (!rs_cli_parse_int(v, 0, 100, &n))
                return rs_cli_usage_error(CMD, "%s: '%s' is not in 0..100 (at least 4 without poles or lines)", a, v);
            o.landmarks_per_camera = (int)n;
        } else if (strcmp(a, "--poles") == 0) {
            if (!rs_cli_parse_int(v, 0, 50, &n)) return rs_cli_usage_error(CMD, "--poles: '%s' is not in 0..50", v);
            o.poles_per_camera = (int)n;
        } else if (strcmp(a, "--lines") == 0) {
            if (!rs_cli_parse_int(v, 0, 20, &n)) return rs_cli_usage_error(CMD, "--lines: '%s' is not in 0..20", v);
            o.lines_per_camera = (int)n;
        } else if (strcmp(a, "--lens") == 0) {
            o.lensmodel = v;
        } else if (strcmp(a, "--fisheye") == 0) {
            if (strcmp(v, "equidistant") == 0)
                o.fisheye = RS_SIMULATE_FISHEYE_EQUIDISTANT;
            else if (strcmp(v, "kannala-brandt") == 0)
                o.fisheye = RS_SIMULATE_FISHEYE_KANNALA_BRANDT;
            else
                return rs_cli_usage_error(CMD, "--fisheye: '%s' is not equidistant or kannala-brandt", v);
        } else if (strcmp(a, "--image") == 0) {
            if (!rs_cli_parse_pair(v, 'x', &x, &y) || x != (int)x || y != (int)y)
                return rs_cli_usage_error(CMD, "--image: '%s' is not WIDTHxHEIGHT in pixels", v);
            o.width_px = (int)x;
            o.height_px = (int)y;
            have_image = true;
        } else if (strcmp(a, "--hfov-deg") == 0) {
            if (!rs_cli_parse_double(v, &o.hfov_deg))
                return rs_cli_usage_error(CMD, "--hfov-deg: '%s' is not a number", v);
            have_hfov = true;
        } else if (strcmp(a, "--pixel-sigma") == 0) {
            if (!rs_cli_parse_double(v, &o.pixel_sigma_px))
                return rs_cli_usage_error(CMD, "--pixel-sigma: '%s' is not a number", v);
        } else if (strcmp(a, "--survey-sigma") == 0) {
            if (!rs_cli_parse_pair(v, ',', &o.survey_sigma_h_m, &o.survey_sigma_v_m))
                return rs_cli_usage_error(CMD, "--survey-sigma: '%s' is not H,V in metres", v);
        } else if (strcmp(a, "--outliers") == 0) {
            if (!rs_cli_parse_double(v, &o.outlier_fraction))
                return rs_cli_usage_error(CMD, "--outliers: '%s' is not a number", v);
        } else if (strcmp(a, "--focal-error") == 0) {
            if (!rs_cli_parse_double(v, &o.focal_error))
                return rs_cli_usage_error(CMD, "--focal-error: '%s' is not a number", v);
        } else if (strcmp(a, "--focal-error-range") == 0) {
            if (!rs_cli_parse_double(v, &o.focal_error_range))
                return rs_cli_usage_error(CMD, "--focal-error-range: '%s' is not a number", v);
        } else if (strcmp(a, "--elevated-fraction") == 0) {
            if (!rs_cli_parse_double(v, &o.elevated_fraction))
                return rs_cli_usage_error(CMD, "--elevated-fraction: '%s' is not a number", v);
        } else if (strcmp(a, "--pole-prior") == 0) {
            if (!rs_cli_parse_double(v, &o.pole_prior_sigma_m) || !(o.pole_prior_sigma_m > 0))
                return rs_cli_usage_error(CMD, "--pole-prior: '%s' is not a positive number of metres", v);
        } else if (strcmp(a, "--height-noise") == 0) {
            if (!rs_cli_parse_double(v, &o.height_noise_m))
                return rs_cli_usage_error(CMD, "--height-noise: '%s' is not a number of metres", v);
        } else if (strcmp(a, "--landmark-heights") == 0) {
            rs_site_height h = RS_SITE_HEIGHT_SURVEYED;
            while (h <= RS_SITE_HEIGHT_UNKNOWN && strcmp(v, rs_site_height_name(h))) h++;
            if (h > RS_SITE_HEIGHT_UNKNOWN)
                return rs_cli_usage_error(CMD, "--landmark-heights: '%s' is not surveyed, unreliable or unknown", v);
            o.landmark_heights = h;
        } else if (strcmp(a, "--origin") == 0) {
            if (!rs_cli_parse_llh(v, &o.origin))
                return rs_cli_usage_error(CMD, "--origin: '%s' is not LAT,LON,H (degrees, degrees, metres)", v);
        } else {
            return rs_cli_usage_error(CMD, "unknown option '%s'", a);
        }
    }
    if (!dir) return rs_cli_usage_error(CMD, "no site folder given");
    if (o.fisheye != RS_SIMULATE_FISHEYE_NONE) { // a GridSmart-style overhead camera
        if (!have_image) {
            o.width_px = 1280;
            o.height_px = 960;
        }
        if (!have_hfov) o.hfov_deg = 216;
    }
    if (!have_seed) return rs_cli_usage_error(CMD, "--seed is required (the same seed gives the same site)");
    rs_err err = {0};
    rs_status st = rs_simulate_site_options_check(&o, &err);
    if (st) return rs_cli_usage_error(CMD, "%s", err.msg);
    st = rs_simulate_site(dir, &o, &err);
    if (st) return rs_cli_fail("site simulate", st, &err);
    printf("wrote %s: a synthetic site of %d cameras, seed %llu; the true answer is in its truth/ folder\n", dir,
           o.Ncameras, (unsigned long long)o.seed);
    return RS_EXIT_OK;
}

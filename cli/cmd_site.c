// roadside site -- check, describe, initialise (and, in cmd_site_simulate.c, simulate) a site
// survey folder through rs_site.
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli/rs_cli.h"
#include "core/rs_io.h"
#include "geo/rs_site.h"
#include "synth/traffic/rs_synth_traffic.h"

static void usage(FILE *out)
{
    fprintf(out, "usage: roadside site check SITE\n"
                 "       roadside site describe [--landmarks] SITE\n"
                 "       roadside site init NAME --origin LAT,LON,H [--orthometric N] [--name TEXT]\n"
                 "       roadside site import DIR --points FILE ...   (see 'roadside site import --help')\n"
                 "       roadside site simulate ...   (see 'roadside site simulate --help')\n"
                 "       roadside site render-backgrounds ...   (see its --help)\n"
                 "\n"
                 "A site is a folder: site.json, landmarks.geojson, cameras/<id>.cameramodel,\n"
                 "observations/<id>.csv, backgrounds/<id>/ (format: docs/site-format.md).\n"
                 "\n"
                 "  check     reads every file of SITE and prints one line per problem,\n"
                 "            \"FILE[:LINE]: [feature F (id 'ID'): ]FIELD: what\", then\n"
                 "            \"N errors, M warnings\". Exit status 0 when the site is usable (warnings\n"
                 "            alone do not fail), 1 when it has errors. An optional lanes.geojson is read\n"
                 "            too once the rest is free of errors (its first problem is one error).\n"
                 "            When landmark heights are unreliable or unknown, check also prints the\n"
                 "            ground model that gives them (docs/site-format.md, \"Heights a survey does\n"
                 "            not have\") before the counts.\n"
                 "  describe  loads SITE and summarises it: name, origin, heights, landmarks and their\n"
                 "            ENU extent, how far their heights are trusted and the ground model, and\n"
                 "            per camera the lens model, image size, observations, position prior and\n"
                 "            the extent and distance of the landmarks it sees.\n"
                 "            --landmarks also lists every landmark in ENU (metres, 9 decimals), with\n"
                 "            where its height comes from (surveyed, or model(unreliable|unknown)).\n"
                 "            Exit status 1 if SITE does not load (run 'check' to see every problem).\n"
                 "  init      creates the folder NAME (it must not exist, or be empty) with a skeleton\n"
                 "            site.json (origin, heights, one example camera 'cam1'), an empty\n"
                 "            landmarks.geojson, cameras/, observations/cam1.csv (header only),\n"
                 "            backgrounds/cam1/ and a README.md saying what to fill in. The skeleton\n"
                 "            passes 'check' only once filled in: check lists what is missing.\n"
                 "            --origin LAT,LON,H  the ENU origin: degrees, degrees, metres\n"
                 "            --orthometric N     heights are orthometric, N = geoid undulation in\n"
                 "                                metres (h_ell = h + N); default: ellipsoidal\n"
                 "            --name TEXT         the site's name (default: the folder's last part)\n"
                 "  import    builds a site from point pairs (a point-pair JSON, or a CSV of lat,lon,u,v\n"
                 "            or e,n,u,v in any CRS) and intrinsics or an image size (see its --help).\n"
                 "  simulate  makes a synthetic site with known cameras (see its --help).\n"
                 "  render-backgrounds  ray-traces synthetic backgrounds of the site's ground.\n"
                 "\n"
                 "Exit status: 0 ok, 1 failure, 2 usage error.\n");
}

// x, with what prints as -0.000 as 0.000.
static double tidy(double x) { return fabs(x) < 5e-4 ? 0.0 : x; }

// The ground model's plane in words: its up at its centre, its slope and which way it falls.
static void print_plane(const rs_site_ground_model *m, const char *indent)
{
    const double g = hypot(m->slope[0], m->slope[1]);
    printf("%sup %.3f m at ENU (%.3f, %.3f) m; ", indent, tidy(m->up_m), tidy(m->centre_en_m[0]),
           tidy(m->centre_en_m[1]));
    if (g > 0) {
        double azimuth = atan2(-m->slope[0], -m->slope[1]) * 180 / M_PI; // downhill, from north, clockwise
        if (azimuth < 0) azimuth += 360;
        printf("slope %.2f %% falling towards azimuth %.1f deg\n", 100 * g, azimuth);
    } else {
        printf("level\n");
    }
}

// The ground model (geo/rs_site.h, rs_site_ground_model) that gives the unreliable and unknown
// heights: where it comes from, its plane, its uncertainty and how the given heights agree.
static void print_ground_model(const rs_site_ground_model *m, const char *indent)
{
    if (m->source == RS_SITE_GROUND_NONE) return;
    static const char *const kind[] = {"", "surveyed", "unreliable"};
    if (m->source == RS_SITE_GROUND_SITE_PLANE) {
        printf("%sground model: the site's ground_plane (too few heights on the ground to fit a plane)\n", indent);
    } else {
        printf("%sground model: plane fitted to the %s heights: rests on %d of %d", indent, kind[m->source], m->Nused,
               m->Ncandidates);
        if (m->Ncandidates > m->Nused) printf(" (%d left out as outliers)", m->Ncandidates - m->Nused);
        printf("\n");
    }
    char sub[64];
    snprintf(sub, sizeof sub, "%s  ", indent);
    print_plane(m, sub);
    if (m->source == RS_SITE_GROUND_SITE_PLANE) {
        printf("%smodelled heights keep their stated sigma_v (the ground_plane states no uncertainty)\n", sub);
    } else {
        char rms[32] = "n/a (3 points)";
        if (isfinite(m->rms_m)) snprintf(rms, sizeof rms, "%.3f m", m->rms_m);
        printf("%sresidual RMS %s, stated sigma_v %.3f m: the road's scatter about the plane %.3f m (at least %g m); "
               "plane 1-sigma at its centre %.3f m\n",
               sub, rms, m->stated_sigma_m, m->scatter_m, RS_SITE_GROUND_SCATTER_MIN_M, sqrt(m->cov[0]));
    }
    printf("%s%d height%s modelled (%d unreliable, %d unknown), sigma_v %.3f .. %.3f m\n", sub, m->Nmodelled,
           m->Nmodelled == 1 ? "" : "s", m->Nunreliable, m->Nunknown, m->sigma_min_m, m->sigma_max_m);
    if (m->Nunreliable > 0)
        printf("%sgiven unreliable heights - model: mean %+.3f m, largest %.3f m; %d beyond %g sigma\n", sub,
               tidy(m->mean_given_minus_model_m), m->max_abs_given_minus_model_m, m->Ndisagree,
               RS_SITE_GROUND_DISAGREE_K);
}

static int cmd_check(int argc, char **argv)
{
    if (argc == 2 && argv[1][0] == '-') // an option it does not have, not a folder named "--x"
        return rs_cli_usage_error("site", "check: unknown option '%s' (it takes one SITE folder)", argv[1]);
    if (argc != 2) return rs_cli_usage_error("site", "check takes one SITE folder");
    rs_site_report *report = NULL;
    rs_err err = {0};
    rs_status st = rs_site_check(&report, argv[1], &err);
    if (st != RS_OK) return rs_cli_fail("site check", st, &err);
    char line[2048];
    for (int i = 0; i < report->N; i++) {
        rs_site_diag_format(line, sizeof line, &report->diags[i]);
        printf("%s\n", line);
    }
    // lanes.geojson, if present, once the site itself loads (its origin places the lanes): the
    // first problem of the lanes file as one more error.
    int Nerrors = report->Nerrors;
    char *lanes_path = rs_io_join(argv[1], RS_SITE_LANES);
    struct stat sb; // (lstat: a link loop there is read, and reported as such)
    if (lanes_path && lstat(lanes_path, &sb) == 0 && Nerrors == 0) {
        rs_site *site = NULL;
        if (rs_site_load(&site, argv[1], NULL) == RS_OK) {
            rs_lanes lanes;
            rs_err lerr = {0};
            if (rs_lanes_read(&lanes, lanes_path, site, &lerr) != RS_OK) {
                printf("%s\n", lerr.msg);
                Nerrors++;
            } else {
                rs_lanes_free(&lanes);
            }
            rs_site_free(site);
        }
    }
    free(lanes_path);
    // SITE/ortho.tif, the report's orthophoto when there is one, is read by GDAL by name: only a
    // regular file (a FIFO there would block `report` forever)
    char *ortho_path = rs_io_join(argv[1], "ortho.tif");
    rs_err oerr = {0};
    if (ortho_path && lstat(ortho_path, &sb) == 0 && rs_io_check_regular(ortho_path, SIZE_MAX, &oerr) != RS_OK) {
        printf("error: %s\n", oerr.msg);
        Nerrors++;
    }
    free(ortho_path);
    print_ground_model(&report->ground, "");
    printf("%d error%s, %d warning%s\n", Nerrors, Nerrors == 1 ? "" : "s", report->Nwarnings,
           report->Nwarnings == 1 ? "" : "s");
    int rc = Nerrors ? RS_EXIT_FAIL : RS_EXIT_OK;
    rs_site_report_free(report);
    return rc;
}

static void print_extent(const rs_site *site, int icam, const char *indent)
{
    double lo[3], hi[3], dmin, dmax;
    if (!rs_site_landmark_extent(lo, hi, &dmin, &dmax, site, icam)) return;
    printf("%sENU extent: east [%.1f, %.1f] m, north [%.1f, %.1f] m, up [%.1f, %.1f] m\n", indent, lo[0], hi[0], lo[1],
           hi[1], lo[2], hi[2]);
    printf("%sdistance from the origin: %.1f .. %.1f m\n", indent, dmin, dmax);
}

static void describe_camera(const rs_site *site, int icam)
{
    const rs_site_camera *cam = &site->cameras[icam];
    char lensmodel[128];
    if (!mrcal_lensmodel_name(lensmodel, sizeof lensmodel, &cam->camera.lensmodel))
        snprintf(lensmodel, sizeof lensmodel, "%s", mrcal_lensmodel_name_unconfigured(&cam->camera.lensmodel));
    printf("  camera '%s'%s%s\n", cam->id, cam->note ? ": " : "", cam->note ? cam->note : "");
    printf("    model: %s\n", cam->model_path);
    printf("    lens model: %s, image %d x %d px\n", lensmodel, cam->camera.width, cam->camera.height);
    printf("    intrinsics:");
    for (int i = 0; i < cam->camera.Nintrinsics; i++) printf(" %.12g", cam->camera.intrinsics[i]);
    printf("\n");
    double sigma_lo = INFINITY, sigma_hi = 0;
    for (int i = 0; i < cam->Nobservations; i++) {
        sigma_lo = fmin(sigma_lo, cam->observations[i].sigma_px);
        sigma_hi = fmax(sigma_hi, cam->observations[i].sigma_px);
    }
    printf("    observations: %d in %s (sigma %g .. %g px)\n", cam->Nobservations, cam->observations_path, sigma_lo,
           sigma_hi);
    if (cam->has_position_prior) {
        const double *p = cam->prior_p_enu_m;
        printf("    position prior: ENU (%.3f, %.3f, %.3f) m, sigma %g m, %.1f m from the origin\n", p[0], p[1], p[2],
               cam->prior_sigma_m, sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]));
    } else {
        printf("    position prior: none\n");
    }
    if (cam->backgrounds_path) printf("    backgrounds: %s\n", cam->backgrounds_path);
    printf("    landmarks seen:\n");
    print_extent(site, icam, "      ");
}

static int cmd_describe(int argc, char **argv)
{
    bool list = false;
    const char *dir = NULL;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--landmarks"))
            list = true;
        else if (argv[i][0] == '-')
            return rs_cli_usage_error("site", "describe: unknown option '%s'", argv[i]);
        else if (dir)
            return rs_cli_usage_error("site", "describe takes one SITE folder");
        else
            dir = argv[i];
    }
    if (!dir) return rs_cli_usage_error("site", "describe: missing SITE folder");
    rs_site *site = NULL;
    rs_err err = {0};
    rs_status st = rs_site_load(&site, dir, &err);
    if (st != RS_OK) {
        int rc = rs_cli_fail("site describe", st, &err);
        fprintf(stderr, "roadside: 'roadside site check %s' lists every problem\n", dir);
        return rc;
    }
    printf("site '%s' (%s)\n", site->name, site->dir);
    printf("origin: lat %.9f, lon %.9f, h %.3f m (ellipsoidal)\n", site->origin.lat_deg, site->origin.lon_deg,
           site->origin.h_m);
    if (site->heights_orthometric)
        printf("heights: orthometric in the files, N = %g m (h_ellipsoidal = h + N)\n", site->geoid_undulation_m);
    else
        printf("heights: ellipsoidal\n");
    printf("ground plane: n = (%g, %g, %g), n . p = %g m%s\n", site->ground_normal_enu[0], site->ground_normal_enu[1],
           site->ground_normal_enu[2], site->ground_offset_m,
           site->ground_plane_given || site->ground.source == RS_SITE_GROUND_NONE ||
                   site->ground.source == RS_SITE_GROUND_SITE_PLANE
               ? ""
               : " (none in site.json: the ground model's plane)");
    printf("landmarks: %d (default sigma %g m horizontal, %g m vertical)\n", site->Nlandmarks, site->landmark_sigma_h_m,
           site->landmark_sigma_v_m);
    print_extent(site, -1, "  ");
    int Nshape[3] = {0}, Nvertices = 0; // poles and lines (docs/site-format.md "Landmark kinds")
    for (int i = 0; i < site->Nlandmarks; i++) {
        Nshape[site->landmarks[i].shape]++;
        if (site->landmarks[i].shape == RS_SITE_LINE) Nvertices += site->landmarks[i].Nvertices;
    }
    if (Nshape[RS_SITE_POLE] || Nshape[RS_SITE_LINE])
        printf("  kinds: %d points, %d poles, %d lines (%d vertices); the extent includes every vertex and pole "
               "top\n",
               Nshape[RS_SITE_POINT], Nshape[RS_SITE_POLE], Nshape[RS_SITE_LINE], Nvertices);
    int Nkind[4] = {0};
    for (int i = 0; i < site->Nlandmarks; i++) Nkind[site->landmarks[i].height]++;
    printf("  landmark heights: \"%s\" site-wide; %d surveyed, %d unreliable, %d unknown\n",
           rs_site_height_name(site->landmark_heights), Nkind[RS_SITE_HEIGHT_SURVEYED],
           Nkind[RS_SITE_HEIGHT_UNRELIABLE], Nkind[RS_SITE_HEIGHT_UNKNOWN]);
    print_ground_model(&site->ground, "  ");
    printf("cameras: %d\n", site->Ncameras);
    for (int i = 0; i < site->Ncameras; i++) describe_camera(site, i);
    if (list) {
        printf("landmarks (ENU, metres):\n");
        printf("  %-16s %16s %16s %16s %9s %9s  %-17s  %s\n", "id", "east", "north", "up", "sigma_h", "sigma_v",
               "height", "kind");
        for (int i = 0; i < site->Nlandmarks; i++) {
            const rs_site_landmark *l = &site->landmarks[i];
            char height[32];
            snprintf(height, sizeof height, l->height_modelled ? "model(%s)" : "%s", rs_site_height_name(l->height));
            printf("  %-16s %16.9f %16.9f %16.9f %9g %9g  %-17s  %s\n", l->id, l->p_enu_m[0], l->p_enu_m[1],
                   l->p_enu_m[2], l->sigma_h_m, l->sigma_v_m, height, l->kind ? l->kind : "-");
        }
    }
    rs_site_free(site);
    return RS_EXIT_OK;
}

static int cmd_init(int argc, char **argv)
{
    const char *dir = NULL, *name = NULL;
    rs_llh origin;
    bool have_origin = false;
    double N;
    bool orthometric = false;
    for (int i = 1; i < argc; i++) {
        const char *opt = argv[i];
        if (!strcmp(opt, "--origin") || !strcmp(opt, "--orthometric") || !strcmp(opt, "--name")) {
            if (i + 1 >= argc) return rs_cli_usage_error("site", "init: %s needs a value", opt);
            const char *v = argv[++i];
            if (!strcmp(opt, "--origin")) {
                if (!rs_cli_parse_llh(v, &origin) || fabs(origin.lon_deg) > 180)
                    return rs_cli_usage_error("site",
                                              "init: --origin '%s' is not LAT,LON,H (degrees, "
                                              "degrees, metres; |LAT| <= 90, |LON| <= 180)",
                                              v);
                have_origin = true;
            } else if (!strcmp(opt, "--orthometric")) {
                if (!rs_cli_parse_double(v, &N))
                    return rs_cli_usage_error("site", "init: --orthometric '%s' is not a number of metres", v);
                orthometric = true;
            } else {
                name = v;
            }
        } else if (opt[0] == '-') {
            return rs_cli_usage_error("site", "init: unknown option '%s'", opt);
        } else if (dir) {
            return rs_cli_usage_error("site", "init takes one NAME");
        } else {
            dir = opt;
        }
    }
    if (!dir) return rs_cli_usage_error("site", "init: missing NAME (the folder to create)");
    if (!have_origin) return rs_cli_usage_error("site", "init: missing --origin LAT,LON,H");
    char base[256];
    if (!name) {
        size_t n = strlen(dir);
        while (n > 1 && dir[n - 1] == '/') n--;
        size_t start = n;
        while (start > 0 && dir[start - 1] != '/') start--;
        snprintf(base, sizeof base, "%.*s", (int)(n - start), dir + start);
        name = base;
    }
    rs_err err = {0};
    rs_status st = rs_site_init(dir, name, &origin, orthometric ? &N : NULL, &err);
    if (st != RS_OK) return rs_cli_fail("site init", st, &err);
    printf("created %s: fill in what %s/README.md says, then run 'roadside site check %s'\n", dir, dir, dir);
    return RS_EXIT_OK;
}

int rs_cli_site(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return RS_EXIT_USAGE;
    }
    const char *sub = argv[1];
    if (!strcmp(sub, "simulate")) return rs_cli_site_simulate(argc - 1, argv + 1);
    if (!strcmp(sub, "import")) return rs_cli_site_import(argc - 1, argv + 1);
    if (!strcmp(sub, "render-backgrounds")) return rs_cli_site_render_backgrounds(argc - 1, argv + 1);
    if (!strcmp(sub, "-h") || !strcmp(sub, "--help") || rs_cli_wants_help(argc - 1, argv + 1)) {
        usage(stdout);
        return RS_EXIT_OK;
    }
    if (!strcmp(sub, "check")) return cmd_check(argc - 1, argv + 1);
    if (!strcmp(sub, "describe")) return cmd_describe(argc - 1, argv + 1);
    if (!strcmp(sub, "init")) return cmd_init(argc - 1, argv + 1);
    return rs_cli_usage_error(
        "site", "unknown subcommand '%s': check, describe, init, import, simulate or render-backgrounds", sub);
}

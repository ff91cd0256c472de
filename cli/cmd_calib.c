// roadside calib / roadside locate: parse arguments, call calib/, print.
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "calib/rs_calib.h"
#include "calib/rs_calib_site.h"
#include "cli/rs_cli.h"
#include "core/rs_io.h"
#include "core/rs_text.h"
#include "geo/rs_site.h"

static const char calib_usage[] =
    "usage: roadside calib SITE [-o OUT] [--camera ID]... [--refine WHAT] [--json]\n"
    "\n"
    "Calibrates the cameras of a site from its surveyed landmarks and their pixel picks:\n"
    "every landmark at once (OpenCV's SQPnP, and IPPE where they are planar) and RANSAC over\n"
    "P3P, then a Ceres adjustment in which the landmarks move within their survey sigmas,\n"
    "outliers are flagged and dropped, and the pose covariance is reported\n"
    "(docs/calibration.md, docs/calibration-init.md).\n"
    "\n"
    "For each camera it writes into OUT (default SITE/calib):\n"
    "  <id>.cameramodel      mrcal model, extrinsics = rt_cam_enu (reference frame: site ENU)\n"
    "  <id>.json             pose, covariance, sigmas, yaw/pitch/roll, residuals per landmark\n"
    "  <id>.opencv.yaml      K, distortion, R, t (lens models with an OpenCV equivalent)\n"
    "  <id>.homography.json  undistorted pixels <-> ground (E, N) on the site's ground plane\n"
    "The .cameramodel has no optimization_inputs (the solve is roadside's, not mrcal's\n"
    "optimizer): mrcal-show-projection-uncertainty and mrcal-show-residuals cannot read it;\n"
    "the pose's uncertainty is in <id>.json and 'roadside audit SITE --calib OUT' maps it.\n"

    "All or nothing: a camera that fails leaves none of these, and an earlier run's files of it\n"
    "are removed. Last, OUT/calib.run.json records which cameras this run wrote, which failed\n"
    "and which it did not select. It prints a summary table: landmarks used and rejected as\n"
    "outliers; rms_surveyed_px, the RMS reprojection error of the inliers' SURVEYED positions\n"
    "through the calibrated camera (the headline: what anyone can check, and what OpenCV\n"
    "would report); rms_adjusted_px, the RMS after the landmarks moved within their survey\n"
    "sigmas (small by construction; docs/calibration.md, \"Residuals: which is which\"); the\n"
    "1-sigma of the camera position (metres, E N U combined) and of its yaw (degrees); the\n"
    "variance factor chi2/dof (about 1 when the stated sigmas are right); then which cameras\n"
    "were written and which were not.\n"
    "\n"
    "Options:\n"
    "  -o, --output DIR   output folder (created if needed; default SITE/calib)\n"
    "  --camera ID        calibrate only this camera (repeatable; default all)\n"
    "  --refine WHAT      also refine intrinsics: focal, center, distortion, joined with '+'\n"
    "                     (e.g. focal+center). focal refines one scale of fx and fy.\n"
    "  --json             print the per-camera results as a JSON array instead of the table\n"
    "  -h, --help         this text\n"
    "\n"
    "Exit status: 0 when every selected camera calibrated, 1 when any failed (the others are\n"
    "still written) or the site could not be read (then the files an earlier run wrote for\n"
    "this site into OUT, as its calib.run.json lists them, are removed), 2 on a usage error.\n";

static const char locate_usage[] =
    "usage: roadside locate SITE --camera ID [--calib DIR] [U V]\n"
    "\n"
    "Maps pixels to the point of the site's ground plane that each pixel's ray hits, through the\n"
    "camera's full lens model (from DIR/<ID>.cameramodel, as written by 'roadside calib').\n"
    "With U V on the command line, locates that pixel; otherwise reads lines 'u v' on standard\n"
    "input (blank lines and lines starting with # are skipped). Pixel (0,0) is the centre of the\n"
    "top-left pixel.\n"
    "\n"
    "Prints one line per pixel: 'e n u lat lon h' (ENU metres; degrees; ellipsoidal metres).\n"
    "\n"
    "Options:\n"
    "  --camera ID    the camera (required)\n"
    "  --calib DIR    calibration folder (default SITE/calib)\n"
    "  -h, --help     this text\n"
    "A negative U on the command line needs '--' before it: locate SITE --camera c -- -0.3 12\n"
    "\n"
    "Exit status: 0 when every pixel was located, 1 when any could not be (its line says why).\n";

// The columns are named as in <id>.json (docs/calibration.md, "Residuals: which is which").
static void print_summary_header(void)
{
    printf("%-12s %5s %8s %15s %15s %12s %10s %10s  %s\n", "camera", "used", "rejected", "rms_surveyed_px",
           "rms_adjusted_px", "sigma_pos_m", "sigma_yaw", "var_factor", "warnings");
}

static void print_summary_row(const rs_site *site, int icam, const rs_calib_result *r)
{
    const double *s = r->sigma_position_enu_m;
    double sigma_pos = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    char warnings[sizeof r->warnings + 512]; // landmarks named by id, as in <id>.json
    snprintf(warnings, sizeof warnings, "%s", r->warnings[0] ? r->warnings : "-");
    rs_calib_site_name_landmarks(warnings, sizeof warnings, site, icam);
    printf("%-12s %5d %8d %15.3f %15.3f %12.3f %10.4f %10.3f  %s\n", site->cameras[icam].id, r->Ninliers,
           r->N - r->Ninliers, rs_calib_site_rms_surveyed_px(site, icam, r, NULL), r->rms_px, sigma_pos,
           r->sigma_yaw_pitch_roll_deg[0], r->variance_factor, warnings);
}

int rs_cli_calib(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        fputs(calib_usage, stdout);
        return RS_EXIT_OK;
    }
    static const struct option longopts[] = {
        {"output", required_argument, NULL, 'o'},
        {"camera", required_argument, NULL, 'c'},
        {"refine", required_argument, NULL, 'r'},
        {"json", no_argument, NULL, 'j'},
        {NULL, 0, NULL, 0},
    };
    const char *out_dir = NULL;
    const char **only = calloc((size_t)argc, sizeof *only);
    if (!only) return rs_cli_fail("calib", RS_ERR_NOMEM, NULL);
    int Nonly = 0;
    bool json = false;
    rs_calib_options opt;
    rs_calib_options_default(&opt);
    optind = 1;
    int c;
    while ((c = getopt_long(argc, argv, "o:", longopts, NULL)) != -1) {
        switch (c) {
        case 'o': out_dir = optarg; break;
        case 'c': only[Nonly++] = optarg; break;
        case 'r':
            if (!rs_calib_refine_parse(optarg, &opt.refine)) {
                free(only);
                return rs_cli_usage_error(
                    "calib", "--refine: '%s': expected focal, center or distortion, joined with '+'", optarg);
            }
            break;
        case 'j': json = true; break;
        default:
            free(only);
            return rs_cli_usage_error("calib", "unknown option or missing value: %s", argv[optind - 1]);
        }
    }
    if (optind != argc - 1) {
        free(only);
        return rs_cli_usage_error("calib", "expected one SITE folder");
    }
    const char *site_dir = argv[optind];

    rs_err err = {0};
    char *default_out = out_dir ? NULL : rs_io_join(site_dir, "calib");
    if (!out_dir) out_dir = default_out;
    if (!out_dir) {
        free(only);
        return rs_cli_fail("calib", RS_ERR_NOMEM, NULL);
    }
    const rs_calib_site_outputs *outputs = &rs_calib_site_calib_outputs;
    rs_site *site = rs_cli_load_site_or_abandon("calib", "outputs", site_dir, out_dir, outputs, only, Nonly);
    if (!site) {
        free(only);
        free(default_out);
        return RS_EXIT_FAIL;
    }
    char judged[512]; // heights nobody declared, taken from the ground model: said once, for every camera
    if (rs_site_heights_judgement(judged, sizeof judged, &site->ground)[0])
        fprintf(stderr, "roadside calib: %s/site.json: warning: %s\n", site_dir, judged);
    rs_status st = RS_OK;
    int usage = rs_cli_check_cameras("calib", site, only, Nonly);
    struct stat sb;
    const bool out_existed = stat(out_dir, &sb) == 0;
    if (!usage && (st = rs_io_mkdir_p(out_dir, &err))) usage = rs_cli_fail("calib", st, &err);
    rs_calib_site_run_camera *runs = usage ? NULL : calloc((size_t)site->Ncameras + 1, sizeof *runs);
    char **errors = usage ? NULL : calloc((size_t)site->Ncameras + 1, sizeof *errors);
    if (!usage && (!runs || !errors)) usage = rs_cli_fail("calib", RS_ERR_NOMEM, NULL);
    if (usage) {
        free(runs);
        free(errors);
        free(only);
        free(default_out);
        rs_site_free(site);
        return usage;
    }

    int failed = 0, written = 0;
    bool first = true;
    if (json)
        printf("[\n");
    else
        print_summary_header();
    for (int icam = 0; icam < site->Ncameras; icam++) {
        const char *id = site->cameras[icam].id;
        bool selected = Nonly == 0;
        for (int i = 0; i < Nonly; i++) selected |= !strcmp(only[i], id);
        runs[icam] = (rs_calib_site_run_camera){.id = id, .status = RS_CALIB_SITE_RUN_NOT_SELECTED};
        if (!selected) continue;

        rs_calib_site_problem sp;
        rs_calib_result r;
        memset(&r, 0, sizeof r);
        err.msg[0] = '\0';
        unsigned files = 0, removed = 0;
        st = rs_calib_site_problem_init(&sp, site, icam, &err);
        if (st == RS_OK) st = rs_calib_solve(&r, &sp.problem, &opt, &err);
        if (st == RS_OK) {
            st = rs_calib_site_write(&files, &removed, out_dir, site, icam, &r, &err);
        } else { // not calibrated: its earlier outputs no longer match the site
            char why[sizeof err.msg];
            snprintf(why, sizeof why, "%s", err.msg[0] ? err.msg : rs_strerror(st));
            rs_err rerr = {0};
            if (rs_calib_site_outputs_remove(&removed, out_dir, id, outputs, &rerr))
                rs_err_set(&err, st, "%s; and %s", why, rerr.msg);
        }
        if (st) {
            failed++;
            errors[icam] = strdup(err.msg[0] ? err.msg : rs_strerror(st));
            runs[icam] = (rs_calib_site_run_camera){id, RS_CALIB_SITE_RUN_FAILED, removed, errors[icam]};
            fprintf(stderr, "roadside calib: camera %s: %s\n", id, err.msg[0] ? err.msg : rs_strerror(st));
        } else {
            written++;
            runs[icam] = (rs_calib_site_run_camera){id, RS_CALIB_SITE_RUN_WRITTEN, files, NULL};
            if (json) {
                char *text = rs_calib_site_result_json(site, icam, &r);
                if (text) printf("%s%s", first ? "" : ",\n", text);
                free(text);
                first = false;
            } else {
                print_summary_row(site, icam, &r);
            }
        }
        rs_calib_result_free(&r);
        rs_calib_site_problem_free(&sp);
    }
    if (json) printf("\n]\n");
    // the run record, last; a folder this run created and left empty is removed instead
    if (written || out_existed) {
        st = rs_calib_site_run_write(out_dir, outputs, site_dir, NULL, runs, site->Ncameras, &err);
        if (st) {
            fprintf(stderr, "roadside calib: %s\n", err.msg);
            failed++;
        }
    } else
        (void)rmdir(out_dir);
    // what was written and what was not: on stdout under the table, on stderr after --json
    char *summary = rs_calib_site_run_summary(out_dir, outputs, runs, site->Ncameras);
    if (summary) fputs(summary, json ? stderr : stdout);
    free(summary);
    for (int icam = 0; icam < site->Ncameras; icam++) free(errors[icam]);
    free(errors);
    free(runs);
    free(only);
    free(default_out);
    rs_site_free(site);
    return failed ? RS_EXIT_FAIL : RS_EXIT_OK;
}

// One pixel -> one output line; false (and a message on stderr) when it cannot be located.
static bool locate_one(const rs_site *site, const rs_camera *cam, const double q[2], const char *where)
{
    double p[3], llh[3];
    rs_err err = {0};
    rs_status st = rs_camera_locate_ground(p, cam, q, site->ground_normal_enu, site->ground_offset_m, &err);
    if (st == RS_OK) st = rs_geo_enu_to_llh(llh, &site->origin, p, 1, &err);
    if (st) {
        if (strncmp(err.msg, "pixel (", 7) == 0) // the message names the pixel already
            fprintf(stderr, "roadside locate: %s: %s\n", where, err.msg);
        else
            fprintf(stderr, "roadside locate: %s: pixel (%g, %g): %s\n", where, q[0], q[1],
                    err.msg[0] ? err.msg : rs_strerror(st));
        return false;
    }
    printf("%.4f %.4f %.4f %.10f %.10f %.4f\n", p[0], p[1], p[2], llh[0], llh[1], llh[2]);
    return true;
}

int rs_cli_locate(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        fputs(locate_usage, stdout);
        return RS_EXIT_OK;
    }
    static const struct option longopts[] = {
        {"camera", required_argument, NULL, 'c'},
        {"calib", required_argument, NULL, 'd'},
        {NULL, 0, NULL, 0},
    };
    const char *camera = NULL, *calib_dir = NULL;
    optind = 1;
    int c;
    while ((c = getopt_long(argc, argv, "", longopts, NULL)) != -1) {
        switch (c) {
        case 'c': camera = optarg; break;
        case 'd': calib_dir = optarg; break;
        default:
            return rs_cli_usage_error(
                "locate", "unknown option or missing value: %s (a negative U needs '--' before it)", argv[optind - 1]);
        }
    }
    if (optind >= argc) return rs_cli_usage_error("locate", "expected a SITE folder");
    const char *site_dir = argv[optind++];
    if (!camera) return rs_cli_usage_error("locate", "--camera ID is required");
    int npos = argc - optind;
    double q[2];
    if (npos != 0 && npos != 2)
        return rs_cli_usage_error("locate", "expected U V, or no pixel and lines on standard input");
    if (npos == 2 && (!rs_cli_parse_double(argv[optind], &q[0]) || !rs_cli_parse_double(argv[optind + 1], &q[1])))
        return rs_cli_usage_error("locate", "U V: '%s %s' is not a pair of finite numbers", argv[optind],
                                  argv[optind + 1]);

    rs_err err = {0};
    rs_site *site = rs_cli_load_site("locate", site_dir);
    if (!site) return RS_EXIT_FAIL;
    const char *ids[1] = {camera};
    int usage = rs_cli_check_cameras("locate", site, ids, 1);
    if (usage) {
        rs_site_free(site);
        return usage;
    }
    char *default_dir = calib_dir ? NULL : rs_io_join(site_dir, "calib");
    if (!calib_dir) calib_dir = default_dir;
    char path[4096];
    rs_camera cam;
    rs_status st = rs_camera_path(path, sizeof path, calib_dir, camera, RS_CAMERA_EXT_CAMERAMODEL)
                       ? rs_camera_read(&cam, NULL, path, &err)
                       : rs_err_set(&err, RS_ERR_INVALID, "%s: path too long", calib_dir);
    free(default_dir);
    if (st) {
        rs_site_free(site);
        return rs_cli_fail("locate", st, &err);
    }

    bool ok = true;
    if (npos == 2) {
        ok = locate_one(site, &cam, q, "argument");
    } else {
        // one line per point; the whole line or an error (core/rs_text.h: a NUL byte, a line over
        // RS_TEXT_MAX_LINE_BYTES, a number that is not decimal), never half of it
        char *line = NULL;
        size_t cap = 0;
        int lineno = 0;
        for (bool more = true; more;) {
            rs_err e = {0};
            if (rs_text_read_line(&line, &cap, &more, &lineno, stdin, RS_TEXT_MAX_LINE_BYTES, "<stdin>", &e)) {
                fprintf(stderr, "roadside locate: %s\n", e.msg);
                ok = false;
                if (e.status == RS_ERR_NOMEM || e.status == RS_ERR_IO) break;
                continue;
            }
            if (!more) break;
            char *save = NULL, *field[3] = {NULL, NULL, NULL};
            int n = 0;
            for (char *tok = strtok_r(line, " \t", &save); tok && n < 3; tok = strtok_r(NULL, " \t", &save))
                field[n++] = tok;
            if (n == 0 || field[0][0] == '#') continue;
            char where[64], why[2][RS_TEXT_WHY_BYTES] = {"", ""};
            snprintf(where, sizeof where, "<stdin>:%d", lineno);
            if (n != 2) {
                fprintf(stderr, "roadside locate: %s: expected 'u v' (two numbers), found %s\n", where,
                        n < 2 ? "one" : "more");
                ok = false;
                continue;
            }
            const bool u_ok = rs_text_parse_double(&q[0], why[0], field[0]);
            const bool v_ok = rs_text_parse_double(&q[1], why[1], field[1]);
            if (!u_ok || !v_ok) {
                fprintf(stderr, "roadside locate: %s: %s: %s (expected 'u v', two decimal numbers)\n", where,
                        u_ok ? "v" : "u", u_ok ? why[1] : why[0]);
                ok = false;
                continue;
            }
            ok &= locate_one(site, &cam, q, where);
        }
        free(line);
    }
    rs_camera_free(&cam);
    rs_site_free(site);
    return ok ? RS_EXIT_OK : RS_EXIT_FAIL;
}

// roadside audit: parse arguments, call audit/rs_audit.h, print.
#include <getopt.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "audit/rs_audit.h"
#include "cli/rs_cli.h"
#include "core/rs_io.h"
#include "geo/rs_site.h"

static const char audit_usage[] =
    "usage: roadside audit SITE [--calib PATH] [--against OBS] [--camera ID]... [-o OUT] [--json]\n"
    "\n"
    "Says whether each camera's calibration can be trusted (docs/audit.md). Per camera it solves\n"
    "the pose from the site's landmarks and picks, then reports:\n"
    "  - leave-one-out: each landmark left out in turn, the pose re-solved from the others, its\n"
    "    predicted pixel error and its ground error in metres;\n"
    "  - normalised residuals and outlier flags with their reasons, and each landmark's influence\n"
    "    (how far leaving it out moves the camera, metres and degrees);\n"
    "  - coverage: image share inside the landmarks' hull, ground share they span within range;\n"
    "  - degeneracy warnings in plain words; a ground uncertainty map (1-sigma metres per cell);\n"
    "  - with --against: whether the camera has moved since its picks were made (chi-square test\n"
    "    on the re-picked pixels) and the estimated rotation and shift;\n"
    "  - with --calib: the audit of a calibration made elsewhere: its reprojection errors against\n"
    "    the site's picks and whether its parts (K, R, t, P) agree.\n"
    "The headline residual, rms_surveyed_px, is the RMS of the inliers' SURVEYED positions\n"
    "reprojected through the calibration audited (the --calib one when given, else the audit's\n"
    "own solve): the figure 'roadside calib' and 'roadside report' print under the same name\n"
    "(docs/calibration.md, \"Residuals: which is which\").\n"
    "Writes OUT/<id>.audit.json per camera (a camera that cannot be audited gets none, and an\n"
    "earlier run's is removed), then OUT/audit.run.json, the record of which cameras this run\n"
    "wrote, which failed and which it did not select, and prints a summary.\n"
    "\n"
    "Options:\n"
    "  --calib PATH           a calibration to audit: a file (mrcal .cameramodel, or OpenCV-style\n"
    "                         .yaml/.yml/.json with K, distortion, R or rvec, t, optional P) or a\n"
    "                         folder holding <id>.cameramodel / <id>.opencv.yaml / <id>.yaml /\n"
    "                         <id>.yml / <id>.json per camera\n"
    "  --against OBS          new picks \"landmark,u,v[,sigma_px]\": a CSV file (needs --camera\n"
    "                         unless the site has one camera) or a folder of <id>.csv\n"
    "  --camera ID            audit only this camera (repeatable; default all)\n"
    "  -o, --output DIR       where <id>.audit.json go (created; default SITE/calib)\n"
    "  --json                 print the audits as a JSON array instead of the summary\n"
    "  --need-ground-m X      what the site is for: the 1-sigma ground accuracy needed where\n"
    "                         the landmarks are, metres (default 1). The thresholds below\n"
    "                         derive from it unless given: X metres in pixels at the landmarks\n"
    "                         for the pixel ones (printed as px_per_m), X for the metre ones\n"
    "  --max-rms-surveyed-px X\n"
    "                         fail when rms_surveyed_px exceeds X px (the old name --max-rms-px\n"
    "                         is accepted and means the same)\n"
    "  --max-loo-px X         fail when the RMS leave-one-out pixel error exceeds X px\n"
    "  --max-loo-m X          fail when the median leave-one-out ground error exceeds X m\n"
    "  --max-ground-sigma-m X fail when the predicted 1-sigma ground error exceeds X m over 10%\n"
    "                         or more of the landmarks' area\n"
    "  --detection-sigma-px X detection noise for the uncertainty map, px (default 1)\n"
    "  --range-m X            ground range for the map and coverage, m (default 100)\n"
    "  --cell-m X             map cell size, m (default 1)\n"
    "  --alpha X              significance of the moved-camera test (default 0.001)\n"
    "  --consistency-px X     largest tolerated P vs K[R|t] difference, px (default 0.5)\n"
    "  -h, --help             this text\n"
    "\n"
    "Exit status: 0 when every selected camera passes, 1 when any fails a threshold, has moved,\n"
    "has an inconsistent calibration or cannot be audited, or the site cannot be read (then the\n"
    "<id>.audit.json an earlier run wrote for this site, as its audit.run.json lists them, are\n"
    "removed), 2 on a usage error.\n";

static bool is_dir(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0 && S_ISDIR(sb.st_mode);
}

// The columns are named as in <id>.audit.json and <id>.json (docs/calibration.md, "Residuals:
// which is which"); the leave-one-out ones start with loo_.
static void print_header(void)
{
    printf("%-12s %5s %15s %10s %12s %9s %6s %6s %6s  %s\n", "camera", "used", "rms_surveyed_px", "loo_rms_px",
           "loo_median_m", "loo_max_m", "image", "ground", "moved", "verdict");
}

static void print_row(const char *id, const rs_audit_result *r)
{
    char moved[16] = "-";
    if (r->has_against) snprintf(moved, sizeof moved, "%s", r->against.moved ? "MOVED" : "no");
    printf("%-12s %5d %15.3f %10.3f %12.2f %9.2f %5.0f%% %5.0f%% %6s  %s\n", id, r->solve.Ninliers, r->rms_surveyed_px,
           r->loo_rms_px, r->loo_median_m, r->loo_max_m, 100 * r->image_hull_share, 100 * r->ground_hull_share, moved,
           r->pass ? "pass" : "FAIL");
}

static void print_details(const rs_site *site, int icam, const rs_audit_result *r)
{
    const char *id = site->cameras[icam].id;
    if (r->verdict[0]) printf("  %s verdict: %s\n", id, r->verdict);
    printf("  %s thresholds: need %g m; rms_surveyed_px and loo_rms_px at most %.3g px (%.1f px/m at the "
           "landmarks), loo_median_m at most %g m, predicted ground error at most %g m\n",
           id, r->thresholds.need_ground_m, r->thresholds.max_rms_surveyed_px, r->px_per_m, r->thresholds.max_loo_m,
           r->thresholds.max_ground_sigma_m);
    if (r->failures[0]) printf("  %s fails: %s\n", id, r->failures);
    if (r->warnings[0]) printf("  %s warnings: %s\n", id, r->warnings);
    const rs_site_camera *sc = &site->cameras[icam];
    for (int i = 0; i < r->N; i++)
        if (r->landmarks[i].reason[0]) {
            const int il = i < sc->Nobservations ? sc->observations[i].ilandmark : -1;
            printf("  %s landmark %s: %s\n", id, il >= 0 && il < site->Nlandmarks ? site->landmarks[il].id : "?",
                   r->landmarks[i].reason);
        }
    if (r->has_against) printf("  %s against: %s\n", id, r->against.message);
    if (r->has_external)
        printf("  %s external: rms_surveyed_px %.3f, max %.3f px, %.3f deg and %.3f m from the site's solve; %s\n", id,
               r->external.rms_surveyed_px, r->external.max_px, r->external.rotation_deg, r->external.shift_m,
               r->external.consistent ? "its parts agree" : r->external.consistency);
}

// What rs_cli_audit parsed and prepared for the run.
typedef struct {
    const rs_site *site;
    const char *site_dir, *out_dir, *calib, *against;
    bool against_dir, json, out_existed;
    const char **only;
    int Nonly;
    const rs_audit_options *opt;
    const rs_calib_site_outputs *outputs;
    rs_calib_site_run_camera *runs; // (site->Ncameras,) filled here
    char **errors;                  // (site->Ncameras,) filled here, owned by the caller
} audit_run;

// Audits the selected cameras and prints the table (or the JSON), then writes the run record and
// prints what was written. Returns the count of failures.
static int audit_cameras(const audit_run *a)
{
    const rs_site *site = a->site;
    const char *out_dir = a->out_dir, *against = a->against, **only = a->only;
    const int Nonly = a->Nonly;
    const bool against_dir = a->against_dir, json = a->json;
    const rs_audit_options *opt = a->opt;
    const rs_calib_site_outputs *outputs = a->outputs;
    rs_calib_site_run_camera *runs = a->runs;
    char **errors = a->errors;
    rs_err err = {0};
    rs_status st;
    int failed = 0, written = 0;
    bool first = true;
    if (json)
        printf("[\n");
    else
        print_header();
    for (int icam = 0; icam < site->Ncameras; icam++) {
        const char *id = site->cameras[icam].id;
        bool selected = Nonly == 0;
        for (int i = 0; i < Nonly; i++) selected |= !strcmp(only[i], id);
        runs[icam] = (rs_calib_site_run_camera){.id = id, .status = RS_CALIB_SITE_RUN_NOT_SELECTED};
        if (!selected) continue;
        char *obs = NULL;
        if (against_dir) {
            char name[512];
            snprintf(name, sizeof name, "%s.csv", id);
            obs = rs_io_join(against, name);
            struct stat osb;
            if (obs && stat(obs, &osb) != 0) {
                free(obs); // this camera was not re-picked
                obs = NULL;
            }
        }
        rs_audit_result r;
        err.msg[0] = '\0';
        st = rs_audit_site_camera(&r, site, icam, a->calib, against_dir ? obs : against, opt, &err);
        if (st == RS_OK) st = rs_audit_site_write(out_dir, site, icam, &r, opt, &err);
        free(obs);
        if (st) {
            // not audited: an earlier run's <id>.audit.json would look like this run's
            unsigned removed = 0;
            char why[sizeof err.msg];
            snprintf(why, sizeof why, "%s", err.msg[0] ? err.msg : rs_strerror(st));
            rs_err rerr = {0};
            if (rs_calib_site_outputs_remove(&removed, out_dir, id, outputs, &rerr))
                rs_err_set(&err, st, "%s; and %s", why, rerr.msg);
            failed++;
            errors[icam] = strdup(err.msg[0] ? err.msg : rs_strerror(st));
            runs[icam] = (rs_calib_site_run_camera){id, RS_CALIB_SITE_RUN_FAILED, removed, errors[icam]};
            fprintf(stderr, "roadside audit: camera %s: %s\n", id, err.msg[0] ? err.msg : rs_strerror(st));
        } else {
            written++;
            runs[icam] = (rs_calib_site_run_camera){id, RS_CALIB_SITE_RUN_WRITTEN, 1u, NULL};
            failed += !r.pass;
            if (json) {
                char *text = rs_audit_result_json(site, icam, &r, opt);
                if (text) printf("%s%s", first ? "" : ",\n", text);
                free(text);
                first = false;
            } else {
                print_row(id, &r);
                print_details(site, icam, &r);
            }
        }
        rs_audit_result_free(&r);
    }
    if (json) printf("\n]\n");
    // the run record, last; a folder this run created and left empty is removed instead
    if (written || a->out_existed) {
        st = rs_calib_site_run_write(out_dir, outputs, a->site_dir, NULL, runs, site->Ncameras, &err);
        if (st) {
            fprintf(stderr, "roadside audit: %s\n", err.msg);
            failed++;
        }
    } else
        (void)rmdir(out_dir);
    // what was written and what was not: on stdout under the table, on stderr after --json
    char *summary = rs_calib_site_run_summary(out_dir, outputs, runs, site->Ncameras);
    if (summary) fputs(summary, json ? stderr : stdout);
    free(summary);
    return failed;
}

int rs_cli_audit(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        fputs(audit_usage, stdout);
        return RS_EXIT_OK;
    }
    enum { O_CALIB = 256, O_AGAINST, O_CAMERA, O_JSON, O_DOUBLE };
    static const struct option longopts[] = {
        {"calib", required_argument, NULL, O_CALIB},
        {"against", required_argument, NULL, O_AGAINST},
        {"camera", required_argument, NULL, O_CAMERA},
        {"output", required_argument, NULL, 'o'},
        {"json", no_argument, NULL, O_JSON},
        {"max-rms-surveyed-px", required_argument, NULL, O_DOUBLE + 0},
        {"max-loo-px", required_argument, NULL, O_DOUBLE + 1},
        {"max-loo-m", required_argument, NULL, O_DOUBLE + 2},
        {"detection-sigma-px", required_argument, NULL, O_DOUBLE + 3},
        {"range-m", required_argument, NULL, O_DOUBLE + 4},
        {"cell-m", required_argument, NULL, O_DOUBLE + 5},
        {"alpha", required_argument, NULL, O_DOUBLE + 6},
        {"consistency-px", required_argument, NULL, O_DOUBLE + 7},
        {"need-ground-m", required_argument, NULL, O_DOUBLE + 8},
        {"max-ground-sigma-m", required_argument, NULL, O_DOUBLE + 9},
        {"max-rms-px", required_argument, NULL, O_DOUBLE + 0}, // the old name: the same threshold
        {NULL, 0, NULL, 0},
    };
    rs_audit_options opt;
    rs_audit_options_default(&opt);
    double *dst[] = {&opt.max_rms_surveyed_px,
                     &opt.max_loo_px,
                     &opt.max_loo_m,
                     &opt.detection_sigma_px,
                     &opt.range_m,
                     &opt.cell_m,
                     &opt.alpha,
                     &opt.consistency_px,
                     &opt.need_ground_m,
                     &opt.max_ground_sigma_m};
    const char *calib = NULL, *against = NULL, *out_dir = NULL;
    const char **only = calloc((size_t)argc, sizeof *only);
    int Nonly = 0;
    bool json = false;
    optind = 1;
    int c, option_index = 0;
    while ((c = getopt_long(argc, argv, "o:", longopts, &option_index)) != -1) {
        if (c >= O_DOUBLE && c < O_DOUBLE + 10) {
            double v;
            if (!rs_cli_parse_double(optarg, &v) || !(v > 0) || (c == O_DOUBLE + 6 && !(v < 1))) {
                free(only);
                return rs_cli_usage_error("audit", "--%s: '%s': expected a number > 0%s", longopts[option_index].name,
                                          optarg, c == O_DOUBLE + 6 ? " and < 1" : "");
            }
            *dst[c - O_DOUBLE] = v;
            continue;
        }
        switch (c) {
        case O_CALIB: calib = optarg; break;
        case O_AGAINST: against = optarg; break;
        case O_CAMERA: only[Nonly++] = optarg; break;
        case 'o': out_dir = optarg; break;
        case O_JSON: json = true; break;
        default:
            free(only);
            return rs_cli_usage_error("audit", "unknown option or missing value: %s", argv[optind - 1]);
        }
    }
    if (optind != argc - 1) {
        free(only);
        return rs_cli_usage_error("audit", "expected one SITE folder");
    }
    if (opt.range_m / opt.cell_m > 4000) {
        free(only);
        return rs_cli_usage_error("audit", "--range-m / --cell-m = %g: at most 4000 cells across",
                                  opt.range_m / opt.cell_m);
    }
    const char *site_dir = argv[optind];
    rs_err err = {0};
    char *default_out = out_dir ? NULL : rs_io_join(site_dir, "calib");
    if (!out_dir) out_dir = default_out;
    if (!out_dir) {
        free(only);
        return rs_cli_fail("audit", RS_ERR_NOMEM, NULL);
    }
    const rs_calib_site_outputs *outputs = &rs_audit_site_outputs;
    rs_site *site = rs_cli_load_site_or_abandon("audit", "audits", site_dir, out_dir, outputs, only, Nonly);
    if (!site) {
        free(only);
        free(default_out);
        return RS_EXIT_FAIL;
    }
    rs_status st = RS_OK;
    int usage = rs_cli_check_cameras("audit", site, only, Nonly);
    int Nselected = Nonly ? Nonly : site->Ncameras;
    bool against_dir = against && is_dir(against);
    if (!usage && against && !against_dir && Nselected != 1)
        usage = rs_cli_usage_error("audit", "--against %s is one file: say which camera with --camera ID", against);
    bool calib_dir = calib && is_dir(calib);
    if (!usage && calib && !calib_dir && Nselected != 1)
        usage = rs_cli_usage_error("audit", "--calib %s is one file: say which camera with --camera ID", calib);
    struct stat sb;
    const bool out_existed = stat(out_dir, &sb) == 0;
    if (!usage && (st = rs_io_mkdir_p(out_dir, &err))) usage = rs_cli_fail("audit", st, &err);
    rs_calib_site_run_camera *runs = usage ? NULL : calloc((size_t)site->Ncameras + 1, sizeof *runs);
    char **errors = usage ? NULL : calloc((size_t)site->Ncameras + 1, sizeof *errors);
    if (!usage && (!runs || !errors)) usage = rs_cli_fail("audit", RS_ERR_NOMEM, NULL);
    if (usage) {
        free(runs);
        free(errors);
        free(only);
        free(default_out);
        rs_site_free(site);
        return usage;
    }

    audit_run run = {.site = site,
                     .site_dir = site_dir,
                     .out_dir = out_dir,
                     .calib = calib,
                     .against = against,
                     .against_dir = against_dir,
                     .json = json,
                     .out_existed = out_existed,
                     .only = only,
                     .Nonly = Nonly,
                     .opt = &opt,
                     .outputs = outputs,
                     .runs = runs,
                     .errors = errors};
    const int failed = audit_cameras(&run);
    for (int icam = 0; icam < site->Ncameras; icam++) free(errors[icam]);
    free(errors);
    free(runs);
    free(only);
    free(default_out);
    rs_site_free(site);
    return failed ? RS_EXIT_FAIL : RS_EXIT_OK;
}

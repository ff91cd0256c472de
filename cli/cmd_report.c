// roadside report: parse arguments, call rs_report_write, print where the report is.
#include <getopt.h>
#include <stdlib.h>
#include <string.h>

#include "cli/rs_cli.h"
#include "core/rs_io.h"
#include "geo/rs_site.h"
#include "report/rs_report.h"

#ifndef RS_VERSION
#define RS_VERSION "unknown"
#endif

static const char report_usage[] =
    "usage: roadside report SITE [--calib DIR] -o DIR [options]\n"
    "\n"
    "Writes the calibration report of a site, for an engineer to send on; it opens with each\n"
    "camera's verdict in plain words (what its ground positions are good to, what to fix), then\n"
    "the evidence, the date, the version and the SHA-256 of every input. DIR/report.html (one\n"
    "self-contained file: figures embedded, no external resource) and DIR/report.pdf (the same\n"
    "content). It reads the cameras' <id>.cameramodel and <id>.json written by 'roadside calib'\n"
    "and audits that calibration exactly as 'roadside audit SITE --calib DIR' does, with its\n"
    "default thresholds (leave-one-out, coverage, ground uncertainty map, warnings): the\n"
    "verdict it shows per camera is that audit's. The headline residual is rms_surveyed_px, the\n"
    "RMS of the inliers' surveyed positions reprojected through the calibration, the figure\n"
    "'roadside calib' and 'roadside audit' print under the same name (docs/calibration.md,\n"
    "\"Residuals: which is which\").\n"
    "\n"
    "Per camera: its image (first PNG or JPEG of its backgrounds folder, else a neutral\n"
    "canvas) with the picks, the surveyed landmarks reprojected and the magnified residual\n"
    "vectors, the ground grid and lane lines (SITE/lanes.geojson, optional) drawn through the\n"
    "lens model; a top-down map with the 1-sigma ground localisation error as a colour scale\n"
    "with labelled contours; tables of the pose with sigmas, residuals and leave-one-out\n"
    "figures; the audit's warnings in words. The first page has a summary table and a map of\n"
    "the whole site (docs/report.md).\n"
    "\n"
    "Options:\n"
    "  -o, --output DIR      output folder (created if needed; required)\n"
    "  --calib DIR           calibration folder (default SITE/calib)\n"
    "  --range M             ground shown within M metres of each camera (default 100)\n"
    "  --grid M              ground grid spacing in the images, metres (default range/10)\n"
    "  --detection-px S      detection noise of the uncertainty map, px (default 1)\n"
    "  --cell M              uncertainty map cell size, metres (default 1)\n"
    "  --width PX            width of the HTML figures, pixels (default 1000)\n"
    "  --need-ground-m X     the ground accuracy the site needs, 1 sigma, metres (default 1): the\n"
    "                        verdicts are judged against it, as in 'roadside audit'\n"
    "  --max-rms-surveyed-px X, --max-loo-px X, --max-loo-m X, --max-ground-sigma-m X\n"
    "                        the audit's thresholds (default: derived from --need-ground-m)\n"
    "  --ortho FILE          the orthophoto the site map is drawn on (any georeferenced image,\n"
    "                        any CRS; default SITE/ortho.tif when there is one: 'roadside ortho')\n"
    "  --no-audit            skip the audit (no leave-one-out, no uncertainty map; every\n"
    "                        camera 'not audited')\n"
    "  -h, --help            this text\n"
    "\n"
    "Exit status: 0 when the report was written, 1 when it could not be (then neither file is\n"
    "left in DIR, not even an earlier report's: it would look current), 2 on a usage error. A\n"
    "camera failing the audit's thresholds is reported in the report and on stdout, and does\n"
    "not change the exit status (see 'roadside audit').\n";

// The report's progress, one line per stage on stderr (stdout keeps the summary).
static void report_progress(void *ctx, const char *what)
{
    (void)ctx;
    fprintf(stderr, "roadside report: %s\n", what);
}

int rs_cli_report(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        fputs(report_usage, stdout);
        return RS_EXIT_OK;
    }
    static const struct option longopts[] = {
        {"output", required_argument, NULL, 'o'},
        {"calib", required_argument, NULL, 'c'},
        {"range", required_argument, NULL, 'r'},
        {"grid", required_argument, NULL, 'g'},
        {"detection-px", required_argument, NULL, 'd'},
        {"cell", required_argument, NULL, 'l'},
        {"width", required_argument, NULL, 'w'},
        {"no-audit", no_argument, NULL, 'n'},
        {"ortho", required_argument, NULL, 'O'},
        {"need-ground-m", required_argument, NULL, 'N'},
        {"max-rms-surveyed-px", required_argument, NULL, '1'},
        {"max-loo-px", required_argument, NULL, '2'},
        {"max-loo-m", required_argument, NULL, '3'},
        {"max-ground-sigma-m", required_argument, NULL, '4'},
        {NULL, 0, NULL, 0},
    };
    rs_report_options opt;
    rs_report_options_default(&opt);
    opt.version = RS_VERSION;
    opt.progress = report_progress;
    const char *epoch = getenv("SOURCE_DATE_EPOCH"); // reproducible builds' convention for "now"
    if (epoch && *epoch) opt.written_utc_s = strtoll(epoch, NULL, 10);
    const char *out_dir = NULL;
    optind = 1;
    int c;
    long width = 0;
    double x = 0;
    while ((c = getopt_long(argc, argv, "o:", longopts, NULL)) != -1) {
        switch (c) {
        case 'o': out_dir = optarg; break;
        case 'c': opt.calib_dir = optarg; break;
        case 'O': opt.ortho_path = optarg; break;
        case 'r':
            if (!rs_cli_parse_double(optarg, &x) || !(x > 0))
                return rs_cli_usage_error("report", "--range: '%s': expected a positive number of metres", optarg);
            opt.range_m = opt.audit_options.range_m = x;
            break;
        case 'g':
            if (!rs_cli_parse_double(optarg, &x) || !(x > 0))
                return rs_cli_usage_error("report", "--grid: '%s': expected a positive number of metres", optarg);
            opt.grid_m = x;
            break;
        case 'd':
            if (!rs_cli_parse_double(optarg, &x) || !(x > 0))
                return rs_cli_usage_error("report", "--detection-px: '%s': expected a positive number of pixels",
                                          optarg);
            opt.audit_options.detection_sigma_px = x;
            break;
        case 'l':
            if (!rs_cli_parse_double(optarg, &x) || !(x > 0))
                return rs_cli_usage_error("report", "--cell: '%s': expected a positive number of metres", optarg);
            opt.audit_options.cell_m = x;
            break;
        case 'w':
            if (!rs_cli_parse_int(optarg, 200, 10000, &width))
                return rs_cli_usage_error("report", "--width: '%s': expected pixels in [200, 10000]", optarg);
            opt.figure_width_px = (int)width;
            break;
        case 'n': opt.audit = false; break;
        case 'N':
        case '1':
        case '2':
        case '3':
        case '4': {
            double *dst[] = {&opt.audit_options.need_ground_m, &opt.audit_options.max_rms_surveyed_px,
                             &opt.audit_options.max_loo_px, &opt.audit_options.max_loo_m,
                             &opt.audit_options.max_ground_sigma_m};
            if (!rs_cli_parse_double(optarg, &x) || !(x > 0))
                return rs_cli_usage_error("report",
                                          "'%s': expected a positive number (the thresholds of 'roadside "
                                          "audit')",
                                          optarg);
            *dst[c == 'N' ? 0 : c - '0'] = x;
            break;
        }
        default: return rs_cli_usage_error("report", "unknown option or missing value: %s", argv[optind - 1]);
        }
    }
    if (optind != argc - 1) return rs_cli_usage_error("report", "expected one SITE folder");
    if (!out_dir) return rs_cli_usage_error("report", "-o DIR is required");
    const char *site_dir = argv[optind];

    rs_err err = {0};
    rs_site *site = NULL;
    rs_status st = rs_site_load(&site, site_dir, &err);
    rs_report_summary sum = {0};
    if (st) {
        fprintf(stderr, "roadside report: %s\n(run 'roadside site check %s' for every problem)\n", err.msg, site_dir);
        // no report: an earlier one left in OUT would look like this run's
        rs_err rerr = {0};
        if (rs_report_remove(&sum.Nremoved, out_dir, &rerr)) fprintf(stderr, "roadside report: %s\n", rerr.msg);
    } else {
        st = rs_report_write(&sum, out_dir, site, &opt, &err);
        rs_site_free(site);
        if (st) rs_cli_fail("report", st, &err);
    }
    if (st) {
        if (sum.Nremoved)
            fprintf(stderr, "roadside report: no report written; the earlier report in %s/ is removed (%d file%s)\n",
                    out_dir, sum.Nremoved, sum.Nremoved == 1 ? "" : "s");
        else
            fprintf(stderr, "roadside report: no report written\n");
        return RS_EXIT_FAIL;
    }
    printf("report of %d camera%s, %d figures", sum.Ncameras, sum.Ncameras == 1 ? "" : "s", sum.Nfigures);
    if (sum.Naudit_fail) printf("; %d camera%s FAIL the audit", sum.Naudit_fail, sum.Naudit_fail == 1 ? "" : "s");
    if (sum.Naudit_failed)
        printf("; the audit could not run for %d camera%s", sum.Naudit_failed, sum.Naudit_failed == 1 ? "" : "s");
    printf("\n  %s/report.html\n  %s/report.pdf\n", out_dir, out_dir);
    return RS_EXIT_OK;
}

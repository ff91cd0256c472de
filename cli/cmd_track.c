// roadside track -- multi-object tracking in metres over all the site's cameras (eval/track).
#include <getopt.h>
#include <stdlib.h>
#include <string.h>

#include "cli/rs_cli.h"
#include "eval/track/rs_track.h"
#include "eval/track/rs_track_io.h"

static void usage(FILE *out)
{
    fprintf(out, "usage: roadside track SITE LOCATED.csv... -o TRACKS.csv [--geojson F] [--sdsm F.jsonl]\n"
                 "                      [--accel-sigma A] [--gate P] [--max-age S] [--min-hits M[/N]]\n"
                 "                      [--coast S] [--init-speed-sigma V]\n"
                 "\n"
                 "Tracks vehicles on the site's ground in metres, over all its cameras at once: a\n"
                 "constant-velocity Kalman filter per vehicle in the site's ENU frame, each detection's own\n"
                 "covariance as its noise, Mahalanobis gating and optimal (Hungarian) assignment camera by\n"
                 "camera, so that two cameras seeing one vehicle feed one track.\n"
                 "\n"
                 "  SITE               the site folder (its origin gives the tracks' latitude and longitude)\n"
                 "  LOCATED.csv        located detections ('roadside localise'), one file per camera or\n"
                 "                     several cameras in one; merged by time_s, which every row must have\n"
                 "  -o TRACKS.csv      the tracks: one row per confirmed track per time step (header\n"
                 "                     time_s,track_id,e_m,n_m,lat_deg,lon_deg,speed_mps,heading_deg,...)\n"
                 "  --geojson F        also the tracks as GeoJSON, one LineString per track (WGS84)\n"
                 "  --sdsm F.jsonl     also JSON lines mirroring SAE J3224's detected objects\n"
                 "  --accel-sigma A    white-noise acceleration, m/s^2 (default 3: braking and turning\n"
                 "                     at an intersection)\n"
                 "  --gate P           gate probability, chi-square 2 dof (default 0.999)\n"
                 "  --max-age S        a track dies after S seconds without detection (default 1)\n"
                 "  --min-hits M[/N]   a track is confirmed when detected at M of its first N chances\n"
                 "                     (steps at which a camera that saw it delivers; default 3/4)\n"
                 "  --coast S          report a confirmed track up to S seconds without detection, its\n"
                 "                     predicted state (default 0.3)\n"
                 "  --init-speed-sigma V  a new track's velocity sigma per axis, m/s (default 15)\n"
                 "\n"
                 "Model, defaults and outputs: docs/track.md. Exit status: 0 ok, 1 bad input (the message\n"
                 "names the file, line and field), 2 usage error.\n");
}

typedef struct {
    const char *site, *out, *geojson, *sdsm;
    char **inputs;
    int Ninputs;
    rs_track_options opt;
} track_args;

static int parse_args(int argc, char **argv, track_args *a)
{
    *a = (track_args){0};
    rs_track_options_default(&a->opt);
    enum { O_GEOJSON = 256, O_SDSM, O_ACCEL, O_GATE, O_MAXAGE, O_MINHITS, O_COAST, O_INITSPEED };
    static const struct option options[] = {{"output", required_argument, NULL, 'o'},
                                            {"geojson", required_argument, NULL, O_GEOJSON},
                                            {"sdsm", required_argument, NULL, O_SDSM},
                                            {"accel-sigma", required_argument, NULL, O_ACCEL},
                                            {"gate", required_argument, NULL, O_GATE},
                                            {"max-age", required_argument, NULL, O_MAXAGE},
                                            {"min-hits", required_argument, NULL, O_MINHITS},
                                            {"coast", required_argument, NULL, O_COAST},
                                            {"init-speed-sigma", required_argument, NULL, O_INITSPEED},
                                            {NULL, 0, NULL, 0}};
    opterr = 0;
    optind = 0; // glibc: full re-initialisation
    int c, li = 0;
    double x;
    while ((c = getopt_long(argc, argv, ":o:", options, &li)) != -1) {
        switch (c) {
        case 'o': a->out = optarg; break;
        case O_GEOJSON: a->geojson = optarg; break;
        case O_SDSM: a->sdsm = optarg; break;
        case O_ACCEL:
        case O_MAXAGE:
        case O_COAST:
            if (!rs_cli_parse_double(optarg, &x) || x < 0)
                return rs_cli_usage_error("track", "--%s: '%s' is not a number >= 0", options[li].name, optarg);
            *(c == O_ACCEL ? &a->opt.accel_sigma_mps2 : c == O_MAXAGE ? &a->opt.max_age_s : &a->opt.coast_s) = x;
            break;
        case O_GATE:
            if (!rs_cli_parse_double(optarg, &x) || !(x > 0 && x < 1))
                return rs_cli_usage_error("track", "--gate: '%s' is not a probability in (0, 1)", optarg);
            a->opt.gate_p = x;
            break;
        case O_MINHITS: {
            char buf[64];
            long m, n;
            snprintf(buf, sizeof buf, "%s", optarg);
            char *slash = strchr(buf, '/');
            if (slash) *slash = '\0';
            if (!rs_cli_parse_int(buf, 1, 1000, &m) || (slash && !rs_cli_parse_int(slash + 1, m, 1000, &n)))
                return rs_cli_usage_error("track", "--min-hits: '%s' is not M or M/N with 1 <= M <= N <= 1000", optarg);
            a->opt.min_hits = (int)m;
            a->opt.hit_window = slash ? (int)n : (int)m + 1;
            break;
        }
        case O_INITSPEED:
            if (!rs_cli_parse_double(optarg, &x) || !(x > 0))
                return rs_cli_usage_error("track", "--init-speed-sigma: '%s' is not a number > 0", optarg);
            a->opt.init_speed_sigma_mps = x;
            break;
        case ':': return rs_cli_usage_error("track", "%s needs a value", argv[optind - 1]);
        default: return rs_cli_usage_error("track", "unknown option '%s'", argv[optind - 1]);
        }
    }
    if (argc - optind < 2)
        return rs_cli_usage_error("track", "expected SITE and at least one LOCATED.csv, got %d argument(s)",
                                  argc - optind);
    if (!a->out) return rs_cli_usage_error("track", "-o TRACKS.csv is required");
    a->site = argv[optind];
    a->inputs = argv + optind + 1;
    a->Ninputs = argc - optind - 1;
    return RS_EXIT_OK;
}

// Reads every input into one array (localise's reader); a row unfit to track (rs_track_check_located:
// no time_s, a covariance not positive definite, ...) is an error naming its file, line and field.
static rs_status read_inputs(rs_localise_row **all, size_t *Nall, const track_args *a, rs_err *err)
{
    *all = NULL;
    *Nall = 0;
    size_t cap = 0;
    for (int f = 0; f < a->Ninputs; f++) {
        rs_localise_row *d = NULL;
        size_t n = 0;
        rs_status st = rs_localise_read(&d, &n, a->inputs[f], err);
        if (st == RS_OK) st = rs_track_check_located(d, n, a->inputs[f], err);
        if (st == RS_OK && *Nall + n > cap) {
            cap = 2 * (*Nall + n) + 16;
            rs_localise_row *q = realloc(*all, cap * sizeof *q);
            if (!q)
                st = rs_err_set(err, RS_ERR_NOMEM, "out of memory (%zu detections)", *Nall + n);
            else
                *all = q;
        }
        if (st) {
            free(d);
            free(*all);
            *all = NULL;
            *Nall = 0;
            return st;
        }
        if (n) memcpy(*all + *Nall, d, n * sizeof *d);
        *Nall += n;
        free(d);
    }
    return RS_OK;
}

int rs_cli_track(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        usage(stdout);
        return RS_EXIT_OK;
    }
    track_args a;
    int rc = parse_args(argc, argv, &a);
    if (rc) return rc;
    rs_site *site = rs_cli_load_site("track", a.site);
    if (!site) return RS_EXIT_FAIL;
    const rs_llh origin = site->origin;
    rs_site_free(site);
    rs_err err = {0};
    rs_localise_row *dets = NULL;
    size_t N = 0;
    rs_status st = read_inputs(&dets, &N, &a, &err);
    if (st) return rs_cli_fail("track", st, &err);
    rs_track_tracker *tracker = NULL;
    st = rs_track_run(&tracker, dets, N, &a.opt, &err);
    free(dets);
    if (st) return rs_cli_fail("track", st, &err);
    st = rs_track_write_csv(a.out, tracker, &origin, &err);
    if (st == RS_OK && a.geojson) st = rs_track_write_geojson(a.geojson, tracker, &origin, &err);
    if (st == RS_OK && a.sdsm) st = rs_track_write_sdsm(a.sdsm, tracker, &origin, &err);
    if (st) {
        rs_track_tracker_free(tracker);
        return rs_cli_fail("track", st, &err);
    }
    size_t Nrows;
    rs_track_tracker_rows(tracker, &Nrows);
    int Nconfirmed, Nmerged, Ncameras;
    rs_track_tracker_counts(tracker, &Nconfirmed, &Nmerged);
    rs_track_tracker_camera(tracker, 0, &Ncameras);
    printf("%zu detections from %d file(s), %d camera(s): %d confirmed track(s), %zu rows, %d duplicate "
           "track(s) merged -> %s\n",
           N, a.Ninputs, Ncameras, Nconfirmed, Nrows, Nmerged, a.out);
    rs_track_tracker_free(tracker);
    return RS_EXIT_OK;
}

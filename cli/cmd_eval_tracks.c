// roadside eval --tracks -- tracking metrics in metres: a tracker's tracks against the ground-truth
// tracks of a synthetic sequence (eval/mot/rs_mot.h). Called by cmd_eval.c when --tracks is given.
#include <getopt.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli/rs_cli.h"
#include "eval/mot/rs_mot.h"

static void usage(FILE *out)
{
    fprintf(out, "usage: roadside eval --tracks TRACKS.csv --gt-tracks DATASET/tracks_gt.csv\n"
                 "                     [--threshold-m D] [--visible-only | --all-gt] [-o METRICS.json]\n"
                 "       roadside eval --located LOCATED.csv --gt-tracks DATASET/tracks_gt.csv\n"
                 "                     [--threshold-m D] [--all-gt]\n"
                 "\n"
                 "Tracking metrics in metres on the ground (docs/evaluation.md, \"Tracking metrics\"):\n"
                 "CLEAR MOT (MOTA, MOTP in metres, FP, FN, IDSW, fragmentations), IDF1, HOTA (DetA,\n"
                 "AssA, LocA with the similarity max(0, 1 - d/D)), the position RMSE over matches, the\n"
                 "covariances' predicted RMS and the NEES (2 expected), and the share of crossings\n"
                 "between disjoint camera sets that keep their track id.\n"
                 "\n"
                 "  --tracks TRACKS.csv   roadside track's tracks (time_s, track_id, e_m, n_m; sigma_e_m,\n"
                 "                        sigma_n_m, cov_en_m2 for the NEES)\n"
                 "  --located LOC.csv     instead of tracks, roadside localise's detections: each\n"
                 "                        camera's matched step by step to the vehicles (one each);\n"
                 "                        prints the localisation RMSE, the covariances' prediction\n"
                 "                        and the NEES (2 expected)\n"
                 "  --gt-tracks GT.csv    roadside synth --sequence's DATASET/tracks_gt.csv\n"
                 "  --threshold-m D       a track and a vehicle match only closer than D metres on the\n"
                 "                        ground (east-north distance; default 2)\n"
                 "  --visible-only        count only the vehicles some camera sees (the default)\n"
                 "  --all-gt              count every vehicle of the ground truth, seen or not\n"
                 "  -o, --json OUT        write the metrics as JSON to OUT\n"
                 "\n"
                 "Time steps are the ground truth's times; a track row matches a step within 1e-6 s.\n"
                 "Exit status: 0 ok, 1 bad input (the message names the file, line and field), 2 usage\n"
                 "error.\n");
}

static void print_result(const rs_mot_result *r)
{
    printf("steps %d, ground truth %ld rows of %d vehicles (%s), tracks %ld rows of %d ids "
           "(%ld ignored near unseen vehicles, %ld at no ground-truth time); D = %g m\n",
           r->Nsteps, r->Ngt, r->Nvehicles, r->all_gt ? "all" : "seen by a camera", r->Nhyp, r->Ntracks, r->Nignored,
           r->Nrows_off_step, r->threshold_m);
    printf("CLEAR MOT  MOTA %.4f  MOTP %.3f m  matches %ld  FP %ld  FN %ld  IDSW %ld  Frag %ld\n", r->mota, r->motp_m,
           r->matches, r->fp, r->fn, r->idsw, r->frag);
    printf("IDF1       IDF1 %.4f  IDP %.4f  IDR %.4f  IDTP %ld  IDFP %ld  IDFN %ld\n", r->idf1, r->idp, r->idr, r->idtp,
           r->idfp, r->idfn);
    printf("HOTA       HOTA %.4f  DetA %.4f  AssA %.4f  LocA %.4f\n", r->hota, r->deta, r->assa, r->loca);
    printf("position   RMSE %.3f m  predicted RMS %.3f m  NEES %.3f (%ld matches; 2 expected)\n", r->rmse_m,
           r->predicted_rms_m, r->nees, r->Nnees);
    printf("crossings  %ld between disjoint camera sets, %ld kept their track id (share %.4f)\n", r->crossings,
           r->crossings_kept, r->crossings_share);
}

int rs_cli_eval_tracks(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        usage(stdout);
        return RS_EXIT_OK;
    }
    enum { O_TRACKS = 256, O_LOCATED, O_GT, O_THRESHOLD, O_VISIBLE, O_ALL };
    static const struct option options[] = {{"tracks", required_argument, NULL, O_TRACKS},
                                            {"located", required_argument, NULL, O_LOCATED},
                                            {"gt-tracks", required_argument, NULL, O_GT},
                                            {"threshold-m", required_argument, NULL, O_THRESHOLD},
                                            {"visible-only", no_argument, NULL, O_VISIBLE},
                                            {"all-gt", no_argument, NULL, O_ALL},
                                            {"json", required_argument, NULL, 'o'},
                                            {"output", required_argument, NULL, 'o'},
                                            {NULL, 0, NULL, 0}};
    const char *tracks = NULL, *located = NULL, *gt = NULL, *json = NULL;
    rs_mot_options opt = {0};
    bool visible_only = false;
    opterr = 0;
    optind = 0; // glibc: full re-initialisation
    int c;
    while ((c = getopt_long(argc, argv, ":o:", options, NULL)) != -1) {
        switch (c) {
        case O_TRACKS: tracks = optarg; break;
        case O_LOCATED: located = optarg; break;
        case O_GT: gt = optarg; break;
        case O_THRESHOLD:
            if (!rs_cli_parse_double(optarg, &opt.threshold_m) || !(opt.threshold_m > 0))
                return rs_cli_usage_error("eval", "--threshold-m: '%s' is not a positive number of metres", optarg);
            break;
        case O_VISIBLE: visible_only = true; break;
        case O_ALL: opt.all_gt = true; break;
        case 'o': json = optarg; break;
        case ':': return rs_cli_usage_error("eval", "%s needs a value", argv[optind - 1]);
        default: return rs_cli_usage_error("eval", "unknown option '%s' (with --tracks)", argv[optind - 1]);
        }
    }
    if (optind != argc) return rs_cli_usage_error("eval", "--tracks takes no file argument ('%s')", argv[optind]);
    if (visible_only && opt.all_gt) return rs_cli_usage_error("eval", "--visible-only and --all-gt exclude each other");
    rs_err err = {0};
    if (located) {
        if (tracks || !gt || json) return rs_cli_usage_error("eval", "--located goes with --gt-tracks alone");
        rs_mot_located_result lr;
        rs_status st = rs_mot_located_run(&lr, located, gt, &opt, &err);
        if (st) return rs_cli_fail("eval", st, &err);
        printf("located    %ld detections of %d camera(s) (%ld at no ground-truth time); D = %g m\n", lr.Nrows,
               lr.Ncameras, lr.Noff_step, lr.threshold_m);
        printf("           %ld matched to a vehicle, %ld without one, %ld near unseen vehicles only\n", lr.matched,
               lr.unmatched, lr.ignored);
        printf("position   RMSE %.3f m  predicted RMS %.3f m  NEES %.3f (%ld matches; 2 expected)\n", lr.rmse_m,
               lr.predicted_rms_m, lr.nees, lr.Nnees);
        return RS_EXIT_OK;
    }
    if (!tracks || !gt) return rs_cli_usage_error("eval", "--tracks and --gt-tracks go together");
    rs_mot_data *data = NULL;
    rs_mot_result r;
    rs_status st = rs_mot_load(&data, tracks, gt, &err);
    if (!st) st = rs_mot_run(&r, data, &opt, &err);
    rs_mot_data_free(data);
    if (st) return rs_cli_fail("eval", st, &err);
    print_result(&r);
    if (json && (st = rs_mot_result_write_json(&r, json, &err))) return rs_cli_fail("eval", st, &err);
    return RS_EXIT_OK;
}

// roadside eval -- distance-threshold AP of COCO detections against COCO ground truth.
#include <getopt.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli/rs_cli.h"
#include "eval/rs_eval.h"
#include "geo/rs_site.h"

static void usage(FILE *out)
{
    fprintf(out, "usage: roadside eval GT.json DETS.json [--center-shift K] [--thresholds LIST]\n"
                 "                     [--max-dets N] [--per-class] [--by KEY] [--json OUT]\n"
                 "                     [--metres | --site SITE --calib DIR [--camera-field KEY]]\n"
                 "\n"
                 "Average precision of vehicle detections judged by where they are: a detection is a\n"
                 "true positive when its bottom-centre point lies closer than a pixel threshold to the\n"
                 "bottom centre of a ground truth not matched yet (nearest first, highest scores first).\n"
                 "\n"
                 "  GT.json            COCO ground truth: images, annotations (footprint_bbox,\n"
                 "                     bottom_center [u, v] or bbox [x, y, w, h]; iscrowd = 1 marks an\n"
                 "                     ignore region), categories. roadside synth's own COCO as it is\n"
                 "  DETS.json          COCO results: a list of {image_id, category_id, bbox, score}\n"
                 "  --center-shift K   detection point (x + w/2, y + h/2 + K h) (default 0: the box\n"
                 "                     centre, right for detectors trained on footprint boxes; for\n"
                 "                     body boxes 0.5 is the bottom edge; the seed paper used 0.35)\n"
                 "  Points: an object's point is the centre of its footprint_bbox, else its\n"
                 "  bottom_center, else its bbox's centre (docs/evaluation.md, rule 1).\n"
                 "  --thresholds LIST  distances in pixels, comma-separated (default 2,5,10,15,20,50)\n"
                 "  --max-dets N       keep the N highest-scoring detections per image (default 100)\n"
                 "  --per-class        also one row per category, matching only within it\n"
                 "  --by KEY           also one row per value of the image field KEY (e.g. condition)\n"
                 "  --json OUT         write the metrics as JSON to OUT\n"
                 "  --site SITE, --calib DIR\n"
                 "                     metric thresholds: map every point to the site's ground plane\n"
                 "                     through its image's camera (DIR/<camera>.cameramodel from\n"
                 "                     'roadside calib', full lens model); thresholds are then metres\n"
                 "                     (default 0.5,1,2,4: nuScenes' centre distances)\n"
                 "  --camera-field KEY the image field naming its camera (default camera)\n"
                 "  --metres           metric thresholds with the cameras and ground plane the ground\n"
                 "                     truth records itself (each image's \"calibration\", as roadside\n"
                 "                     synth writes it: docs/labels.md); checksums checked\n"
                 "\n"
                 "Prints AP at each threshold, mAP (mean AP over the thresholds) and AR (mean final\n"
                 "recall); '-' (null in JSON) where there is no ground truth. The exact rules (ignore\n"
                 "regions, ties, max-dets): docs/evaluation.md. Tracking metrics in metres:\n"
                 "roadside eval --tracks TRACKS.csv --gt-tracks GT.csv, and located detections with\n"
                 "--located LOCATED.csv --gt-tracks GT.csv (roadside eval --tracks --help).\n"
                 "Exit status: 0 ok, 1 bad input (the\n"
                 "message names the file, line, entry and field), 2 usage error.\n");
}

typedef struct {
    const char *gt, *dets, *json, *by, *site, *calib, *camera_field;
    bool metres; // the ground truth's recorded calibration
    double center_shift;
    double thresholds[RS_EVAL_MAX_THRESHOLDS];
    int Nthresholds; // 0: the default
    int max_dets;
    bool per_class;
} eval_args;

// "2,5,10" -> thresholds. False if any part is not a positive finite number or there are too many.
static bool parse_list(const char *s, double *x, int *N)
{
    char buf[1024];
    if (strlen(s) >= sizeof buf) return false;
    strcpy(buf, s);
    *N = 0;
    char *save = NULL;
    for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        if (*N == RS_EVAL_MAX_THRESHOLDS || !rs_cli_parse_double(tok, &x[*N]) || x[*N] <= 0) return false;
        ++*N;
    }
    return *N > 0;
}

static int parse_args(int argc, char **argv, eval_args *a)
{
    *a = (eval_args){0};
    enum { O_SHIFT = 256, O_THRESHOLDS, O_MAXDETS, O_PERCLASS, O_BY, O_JSON, O_SITE, O_CALIB, O_CAMFIELD, O_METRES };
    static const struct option options[] = {{"center-shift", required_argument, NULL, O_SHIFT},
                                            {"thresholds", required_argument, NULL, O_THRESHOLDS},
                                            {"max-dets", required_argument, NULL, O_MAXDETS},
                                            {"per-class", no_argument, NULL, O_PERCLASS},
                                            {"by", required_argument, NULL, O_BY},
                                            {"json", required_argument, NULL, O_JSON},
                                            {"site", required_argument, NULL, O_SITE},
                                            {"calib", required_argument, NULL, O_CALIB},
                                            {"camera-field", required_argument, NULL, O_CAMFIELD},
                                            {"metres", no_argument, NULL, O_METRES},
                                            {NULL, 0, NULL, 0}};
    opterr = 0;
    optind = 0; // glibc: full re-initialisation
    int c;
    long n;
    while ((c = getopt_long(argc, argv, ":", options, NULL)) != -1) {
        switch (c) {
        case O_SHIFT:
            if (!rs_cli_parse_double(optarg, &a->center_shift))
                return rs_cli_usage_error("eval", "--center-shift: '%s' is not a finite number", optarg);
            break;
        case O_THRESHOLDS:
            if (!parse_list(optarg, a->thresholds, &a->Nthresholds))
                return rs_cli_usage_error("eval", "--thresholds: '%s' is not a list of 1 to %d positive numbers",
                                          optarg, RS_EVAL_MAX_THRESHOLDS);
            break;
        case O_MAXDETS:
            if (!rs_cli_parse_int(optarg, 1, 1000000000, &n))
                return rs_cli_usage_error("eval", "--max-dets: '%s' is not a whole number >= 1", optarg);
            a->max_dets = (int)n;
            break;
        case O_PERCLASS: a->per_class = true; break;
        case O_BY: a->by = optarg; break;
        case O_JSON: a->json = optarg; break;
        case O_SITE: a->site = optarg; break;
        case O_CALIB: a->calib = optarg; break;
        case O_CAMFIELD: a->camera_field = optarg; break;
        case O_METRES: a->metres = true; break;
        case ':': return rs_cli_usage_error("eval", "%s needs a value", argv[optind - 1]);
        default: return rs_cli_usage_error("eval", "unknown option '%s'", argv[optind - 1]);
        }
    }
    if (argc - optind != 2)
        return rs_cli_usage_error("eval", "expected GT.json and DETS.json, got %d file argument(s)", argc - optind);
    if (!a->site != !a->calib) return rs_cli_usage_error("eval", "--site and --calib go together");
    if (a->metres && a->site)
        return rs_cli_usage_error("eval", "--metres reads the ground truth's own calibration: "
                                          "give it or --site/--calib, not both");
    if (a->camera_field && !a->site) return rs_cli_usage_error("eval", "--camera-field needs --site and --calib");
    if (a->site && !a->camera_field) a->camera_field = "camera";
    a->gt = argv[optind];
    a->dets = argv[optind + 1];
    return RS_EXIT_OK;
}

static void print_row(const char *label, const rs_eval_result *r, const rs_eval_metrics *m)
{
    printf("%-24s %8zu %9zu", label, m->num_gt, m->num_det);
    for (int t = 0; t < r->Nthresholds; t++)
        if (isnan(m->ap[t]))
            printf(" %7s", "-");
        else
            printf(" %7.4f", m->ap[t]);
    if (isnan(m->map))
        printf(" %7s %7s\n", "-", "-");
    else
        printf(" %7.4f %7.4f\n", m->map, m->ar);
}

static void print_table(const rs_eval_result *r, const char *by)
{
    printf("%-24s %8s %9s", "scope", "num_gt", "num_det");
    for (int t = 0; t < r->Nthresholds; t++) {
        char h[32];
        snprintf(h, sizeof h, "AP@%g", r->thresholds[t]);
        printf(" %7s", h);
    }
    printf(" %7s %7s\n", "mAP", "AR");
    print_row("all", r, &r->all);
    char label[256];
    for (int g = 0; g < r->Ngroups; g++) {
        snprintf(label, sizeof label, "%s=%s", by, r->groups[g].name);
        print_row(label, r, &r->groups[g]);
    }
    for (int c = 0; c < r->Nclasses; c++) {
        snprintf(label, sizeof label, "class %s (%lld)", r->classes[c].name, r->classes[c].category_id);
        print_row(label, r, &r->classes[c]);
    }
    printf("thresholds in %s; max %d detections per image; '-': no ground truth\n",
           r->metres ? "metres on the ground" : "pixels", r->max_dets);
}

int rs_cli_eval(int argc, char **argv)
{
    for (int i = 1; i < argc; i++)
        if (!strcmp(argv[i], "--tracks") || !strncmp(argv[i], "--tracks=", 9) || !strcmp(argv[i], "--located") ||
            !strncmp(argv[i], "--located=", 10))
            return rs_cli_eval_tracks(argc, argv);
    if (rs_cli_wants_help(argc, argv)) {
        usage(stdout);
        return RS_EXIT_OK;
    }
    eval_args a;
    int rc = parse_args(argc, argv, &a);
    if (rc) return rc;
    rs_err err = {0};
    rs_eval_data *data = NULL;
    rs_eval_result *result = NULL;
    const rs_eval_load_options lo = {.center_shift = a.center_shift,
                                     .group_key = a.by,
                                     .camera_key = a.camera_field,
                                     .recorded_calibration = a.metres};
    rs_status st = rs_eval_load(&data, a.gt, a.dets, &lo, &err);
    if (st != RS_OK) return rs_cli_fail("eval", st, &err);
    if (a.metres) {
        size_t missed = 0;
        st = rs_eval_data_to_ground_recorded(data, &missed, &err);
        if (st != RS_OK) {
            rs_eval_data_free(data);
            return rs_cli_fail("eval", st, &err);
        }
        if (missed)
            fprintf(stderr, "roadside eval: %zu point(s) whose ray misses the ground can match nothing\n", missed);
    } else if (a.site) {
        rs_site *site = NULL;
        size_t missed = 0;
        st = rs_site_load(&site, a.site, &err);
        if (st == RS_OK) st = rs_eval_data_to_ground(data, site, a.calib, &missed, &err);
        rs_site_free(site);
        if (st != RS_OK) {
            rs_eval_data_free(data);
            return rs_cli_fail("eval", st, &err);
        }
        if (missed)
            fprintf(stderr, "roadside eval: %zu point(s) whose ray misses the ground can match nothing\n", missed);
    }
    const rs_eval_options opt = {.thresholds = a.Nthresholds ? a.thresholds : NULL,
                                 .Nthresholds = a.Nthresholds,
                                 .max_dets = a.max_dets,
                                 .per_class = a.per_class,
                                 .by_group = a.by != NULL};
    st = rs_eval_run(&result, data, &opt, &err);
    rs_eval_data_free(data);
    if (st != RS_OK) return rs_cli_fail("eval", st, &err);
    print_table(result, a.by);
    if (a.json) st = rs_eval_result_write_json(result, a.json, &err);
    rs_eval_result_free(result);
    if (st != RS_OK) return rs_cli_fail("eval", st, &err);
    return RS_EXIT_OK;
}

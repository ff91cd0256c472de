// roadside synth: parse arguments, make a dataset (or merge shards) through synth/, print.
#include <errno.h>
#include <getopt.h>
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cli/rs_cli.h"
#include "cli/rs_cli_synth.h"
#include "synth/backdrop/rs_synth_condition.h"
#include "synth/dataset/rs_synth_dataset.h"
#include "synth/labels/rs_synth_labels.h"

static const char synth_usage[] =
    "usage: roadside synth SITE --calib DIR --count N -o DATASET [--seed S]\n"
    "                      [--backgrounds TAG=VALUE]... [--shard I/N] [--camera ID]...\n"
    "                      [--size WxH] [--vehicles N] [--split NAME] [--no-shadows]\n"
    "                      [--no-appearance]\n"
    "                      [--jobs J] [--separate-processes]\n"
    "                      [--bbox footprint|body|visible] [--min-visibility V] [--keep-invisible]\n"
    "                      [--no-junction-traffic | --traffic-frames DIR] [--models FILE]\n"
    "                      [--val-fraction F] [--val-camera ID]...\n"
    "                      [--sequence [--frames A:B] [--labels-only]]\n"
    "                      [--val-backgrounds TAG=VALUE]... [--val-split NAME]\n"
    "       roadside synth merge DATASET... -o OUT\n"
    "\n"
    "Synthesises a labelled dataset (docs/synth.md): image k (0 <= k < N) is seen by camera\n"
    "k mod (number of cameras), over a background drawn among the camera's tagged backgrounds\n"
    "(site.json background_images; without any, a neutral grey ground rendered by POV-Ray:\n"
    "make backgrounds first with `roadside site render-backgrounds` or `roadside background`),\n"
    "with the built-in traffic on SITE/lanes.geojson and domain randomisation (or SUMO's:\n"
    "one frame of --traffic-frames DIR per image), the sun from the background's time tag,\n"
    "rendered with POV-Ray, shadows cast onto the background by differential rendering, the\n"
    "vehicles matched to the background's exposure, noise, blur and JPEG quality, and\n"
    "labelled through mrcal. Image k depends only on (seed, k): reruns and shard splits give\n"
    "identical files. A rerun skips finished images after checking their files (a missing or\n"
    "corrupt one is remade, named on stderr). One run per DATASET at a time: a second fails\n"
    "at once, naming the first's pid (DATASET/.lock). Writes DATASET/<split>/*.png,\n"
    "DATASET/annotations/instances_<split>.json (COCO, YOLOX's layout), DATASET/images/<split>,\n"
    "labels/<split>, data.yaml (Ultralytics YOLO), DATASET/kitti/training/{image_2,label_2,\n"
    "calib} (KITTI), DATASET/cameras/ (the camera models the labels were made with) and\n"
    "DATASET/run.json (the run's options), DATASET/README.md (the layouts and the box type:\n"
    "the ground footprint by default, not the vehicle). DATASET must be new, empty or made by\n"
    "roadside synth (DATASET/.roadside-dataset): any other folder is refused, untouched.\n"
    "`synth merge` checks every input first (every shard finished, every image decoded, every\n"
    "label accounted for) and writes nothing if one fails.\n"
    "The fields of every file: docs/labels.md.\n"
    "\n"
    "Options:\n"
    "  --calib DIR            calibrated <camera>.cameramodel files (roadside calib -o DIR)\n"
    "  --count N              images in the whole dataset, all shards together\n"
    "  -o, --output DATASET   output folder: new, empty or a dataset of roadside's (created if needed)\n"
    "  --seed S               seed (default 0)\n"
    "  --backgrounds K=V      use only backgrounds whose tag K is V (repeatable; tags: time,\n"
    "                         conditions, synthetic, name and free tags)\n"
    "  --shard I/N            make only the images k with k mod N == I (0 <= I < N)\n"
    "  --camera ID            use this camera (repeatable; default every camera of the site)\n"
    "  --size WxH             output size (the camera's intrinsics scaled; same aspect)\n"
    "  --vehicles N           at most N vehicles of traffic per image (default 10)\n"
    "  --split NAME           COCO split (default train2017)\n"
    "  --val-fraction F       put a share F of the images (drawn per image) in the validation split\n"
    "                         (default 0.1; with 2 images or more never none; 0: no validation)\n"
    "  --val-camera ID        put every image of camera ID in the validation split (repeatable)\n"
    "  --val-backgrounds K=V  put every image over a background whose tag K is V in the\n"
    "                         validation split (repeatable, all must match; name=... holds out\n"
    "                         one background)\n"
    "  --val-split NAME       the validation split's name (default val2017)\n"
    "  --bbox KIND            the box of COCO's bbox, YOLO and KITTI: footprint (default: what the\n"
    "                         roadside detector learns), body (amodal) or visible\n"
    "  --min-visibility V     no label for a vehicle less visible than V in [0, 1] (default 0)\n"
    "  --keep-invisible       label vehicles with no visible pixel too (default: not)\n"
    "  --no-junction-traffic  no vehicles on the junction's own lanes (default: turning\n"
    "                         movements through the junction, docs/traffic.md; built-in\n"
    "                         traffic only)\n"
    "  --traffic-frames DIR   SUMO's traffic instead of the built-in one: DIR is a folder written\n"
    "                         by `roadside traffic SITE --sumo -o DIR` (frames.json and its\n"
    "                         frame_NNNNNN.json). Image k takes the vehicles of one frame,\n"
    "                         drawn from (seed, k), where SUMO put them (no positional\n"
    "                         randomisation here; `roadside traffic` randomised the frames\n"
    "                         unless --no-randomise), with fresh looks (paint, dirt, shape\n"
    "                         details) per image; at most --vehicles of those the camera sees.\n"
    "                         Every frame is read and checked first; run.json records the\n"
    "                         frames' count and SHA-256, so merge refuses other traffic\n"
    "  --models FILE          a library of user models (docs/fleet.md, \"User models\"): a JSON\n"
    "                         list of {\"model\": OBJ/glTF path relative to FILE, \"class\",\n"
    "                         \"length\" (m) or \"scale\", \"forward\", \"up\", \"paint_materials\"};\n"
    "                         a vehicle of a class the library has becomes one of its models\n"
    "                         of that class, drawn from (seed, k); labels carry the class and\n"
    "                         the model's box. Every model is read once, before the images\n"
    "  --sequence             with --traffic-frames: the frames in order instead of drawn ones\n"
    "                         (no --count): image k shows frame A + k / C to camera k mod C (C\n"
    "                         cameras), every vehicle the camera sees, each with the same looks in\n"
    "                         every frame; a camera's background is the same in every frame.\n"
    "                         Writes DATASET/tracks_gt.csv: every vehicle of each frame (time_s,\n"
    "                         vehicle_id, class, e_m, n_m: the labels' bottom_center_enu_m,\n"
    "                         speed_mps: SUMO's, heading_deg, cameras: those labelling it).\n"
    "                         Make the frames with `roadside traffic --sumo --no-randomise`: the\n"
    "                         randomisation draws every frame's offsets afresh (docs/synth.md)\n"
    "  --frames A:B           a sequence of frames A <= i < B of frames.json (default: all)\n"
    "  --labels-only          a sequence's labels without POV-Ray: visibility from the\n"
    "                         rasterised ID pass; no image, YOLO or KITTI files (annotations/,\n"
    "                         parts/, cameras/, run.json and tracks_gt.csv only)\n"
    "  --no-shadows           no differential-rendering shadows (the shadow pass: the sun's\n"
    "                         shadow and the sky's soft one of each vehicle on the background)\n"
    "  --no-appearance        vehicles composited clean and sharp over the backgrounds; by\n"
    "                         default they and their shadows take the look of the camera\n"
    "                         estimated from each background (gain, blur, noise as a function\n"
    "                         of brightness, JPEG quality; docs/appearance.md), recorded in\n"
    "                         DATASET/backgrounds.json and shown by `roadside dataset stats`\n"
    "  --jobs J               images made at once, in J worker processes (default: the CPUs\n"
    "                         this process may use: its affinity mask, its cgroup's cpu.max\n"
    "                         quota and $SLURM_CPUS_PER_TASK, the smallest; never more)\n"
    "  --separate-processes   the passes' povray processes one after the other (for\n"
    "                         benchmarks; default: an image's passes all at once)\n"
    "  $ROADSIDE_POVRAY       the povray executable (default: povray on PATH)\n"
    "  $ROADSIDE_POVRAY_SANDBOX=off   povray without Landlock (see roadside render --help)\n"
    "  -h, --help             this text\n"
    "\n"
    "Progress goes to stderr (a bar with rate and time left on a terminal, else a line every\n"
    "10 images). Prints a summary line and where each output is.\n"
    "Exit status: 0 done, 1 failed, 2 usage error.\n";

enum {
    OPT_CALIB = 1000,
    OPT_COUNT,
    OPT_SEED,
    OPT_BG,
    OPT_SHARD,
    OPT_CAMERA,
    OPT_SIZE,
    OPT_VEHICLES,
    OPT_SPLIT,
    OPT_NO_SHADOWS,
    OPT_NO_LOOK,
    OPT_JOBS,
    OPT_SEPARATE,
    OPT_BBOX,
    OPT_MIN_VIS,
    OPT_KEEP_INVISIBLE,
    OPT_NO_JUNCTION,
    OPT_VAL_FRACTION,
    OPT_VAL_CAMERA,
    OPT_VAL_BG,
    OPT_VAL_SPLIT,
    OPT_TRAFFIC_FRAMES,
    OPT_MODELS,
    OPT_SEQUENCE,
    OPT_FRAMES,
    OPT_LABELS_ONLY
};

// "TAG=VALUE" -> keys[*N], values[*N] (kv[*N] owns the copy). RS_EXIT_OK or a usage error.
static int parse_tag(const char *opt_name, const char *arg, char **kv, const char **keys, const char **values, int *N)
{
    const char *eq = strchr(arg, '=');
    if (!eq || eq == arg || !eq[1])
        return rs_cli_usage_error("synth", "%s: expected TAG=VALUE, got \"%s\"", opt_name, arg);
    kv[*N] = strdup(arg);
    if (!kv[*N]) return rs_cli_fail("synth", RS_ERR_NOMEM, NULL);
    kv[*N][eq - arg] = 0;
    keys[*N] = kv[*N];
    values[*N] = kv[*N] + (eq - arg) + 1;
    (*N)++;
    return RS_EXIT_OK;
}

typedef struct {
    double t0;
    bool tty;
} progress_state;

static double wall_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void progress(void *ctx, int done, int total, int skipped)
{
    progress_state *p = ctx;
    const double dt = wall_s() - p->t0;
    const int made = done - skipped;
    const double rate = dt > 0 ? made / dt : 0;
    const double left = rate > 0 ? (total - done) / rate : 0;
    if (p->tty) {
        char bar[31];
        const int fill = total > 0 ? 30 * done / total : 30;
        for (int i = 0; i < 30; i++) bar[i] = i < fill ? '#' : '.';
        bar[30] = 0;
        fprintf(stderr, "\r[%s] %d/%d  %.2f img/s  %.0f s left ", bar, done, total, rate, left);
        if (done == total) fputc('\n', stderr);
    } else if (done % 10 == 0 || done == total) {
        fprintf(stderr, "synth: %d/%d images (%d skipped), %.2f img/s, %.0f s left\n", done, total, skipped, rate,
                left);
    }
}

// Resume notices: an image found damaged and remade, a part file left out of the COCO file.
static void notice(void *ctx, const char *msg)
{
    (void)ctx;
    fprintf(stderr, "synth: %s\n", msg);
}

static int synth_merge(int argc, char **argv)
{
    const char *out = NULL;
    const char **inputs = calloc((size_t)argc, sizeof(char *));
    int Ninputs = 0;
    if (!inputs) return rs_cli_fail("synth merge", RS_ERR_NOMEM, NULL);
    for (int i = 2; i < argc; i++) {
        if (!strcmp(argv[i], "-o") || !strcmp(argv[i], "--output")) {
            if (i + 1 >= argc) {
                free(inputs);
                return rs_cli_usage_error("synth merge", "-o: missing value");
            }
            out = argv[++i];
        } else if (argv[i][0] == '-') {
            free(inputs);
            return rs_cli_usage_error("synth merge", "unknown option: %s", argv[i]);
        } else {
            inputs[Ninputs++] = argv[i];
        }
    }
    if (!out || Ninputs == 0) {
        free(inputs);
        return rs_cli_usage_error("synth merge", "expected DATASET... -o OUT");
    }
    int Nimages = 0, Nanns = 0;
    rs_err err = {0};
    rs_status st = rs_synth_dataset_merge(&Nimages, &Nanns, out, inputs, Ninputs, &err);
    free(inputs);
    if (st) return rs_cli_fail("synth merge", st, &err);
    printf("merged %d datasets: %d images, %d annotations -> %s/annotations\n", Ninputs, Nimages, Nanns, out);
    return RS_EXIT_OK;
}

// What `roadside synth` made and where: a line of counts and times, then the dataset's files.
static void print_summary(const rs_synth_dataset_options *opt, const rs_synth_dataset_summary *sum)
{
    printf("synth: shard %d/%d: %d images (%d made, %d already done, %d over the grey ground), "
           "%d annotations in the dataset, %.1f s (%.1f s in povray, %.3f s/image)\n",
           opt->shard_index, opt->shard_count, sum->Nimages, sum->Nmade, sum->Nskipped, sum->Ngrey, sum->Nannotations,
           sum->seconds, sum->seconds_povray, sum->Nmade > 0 ? sum->seconds / sum->Nmade : 0.0);
    printf("conditions:  "); // issue 40: the mix of this shard's images (also in run.json)
    int Nlisted = 0;
    for (int i = 0; i < 9; i++) {
        if (!sum->Ncondition[i]) continue;
        char label[16];
        const rs_synth_condition c = {.time_of_day = (rs_synth_time_of_day)(i / 3),
                                      .surface = (rs_synth_surface)(i % 3)};
        rs_synth_condition_label(label, sizeof(label), &c);
        printf("%s%s %d", Nlisted++ ? ", " : "", label, sum->Ncondition[i]);
    }
    printf("%s\n", Nlisted ? "" : "none (no background)");
    if (sum->Nremade > 0 || sum->Nleft_out > 0)
        printf("resume:      %d of the images made were found damaged and remade; %d part files left out of the "
               "COCO file (stderr names each)\n",
               sum->Nremade, sum->Nleft_out);
    const bool val = opt->val_fraction > 0 || opt->Nval_cameras > 0 || opt->Nval_bg > 0;
    printf("images:      %s/%s/%s%s%s\n", opt->out_dir, opt->split, val ? "  and  " : "", val ? opt->val_split : "",
           val ? "/" : "");
    printf("COCO:        %s/annotations/instances_%s.json%s%s%s\n", opt->out_dir, opt->split,
           val ? "  and  instances_" : "", val ? opt->val_split : "", val ? ".json" : "");
    printf("YOLO:        %s/data.yaml   (images/<split>/, labels/<split>/)\n", opt->out_dir);
    printf("KITTI:       %s/kitti/training/   (image_2/, label_2/, calib/; kitti/ImageSets/)\n", opt->out_dir);
    printf("cameras:     %s/cameras/   (the camera models of the labels; eval --metres reads them)\n", opt->out_dir);
    if (opt->traffic_frames_dir)
        printf("traffic:     SUMO's frames in %s (run.json: traffic_frames, their count and SHA-256)\n",
               opt->traffic_frames_dir);
    if (opt->models_path) printf("models:      the library %s (docs/fleet.md, \"User models\")\n", opt->models_path);
    if (opt->sequence)
        printf("tracks:      %s/tracks_gt.csv%s\n", opt->out_dir,
               sum->tracks_gt ? "" : "   (not yet: images of other shards unfinished)");
}

// Runs the dataset pipeline with a progress line on stderr, then prints its summary.
static int synth_run(rs_synth_dataset_options *opt)
{
    progress_state ps = {.t0 = wall_s(), .tty = isatty(2) != 0};
    opt->progress = progress;
    opt->progress_ctx = &ps;
    opt->notice = notice;
    rs_synth_dataset_summary sum;
    rs_err err = {0};
    rs_cli_synth_sandbox_note("synth");
    rs_status st = rs_synth_dataset_run(&sum, opt, &err);
    if (st) return rs_cli_fail("synth", st, &err);
    print_summary(opt, &sum);
    return RS_EXIT_OK;
}

int rs_cli_synth(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        fputs(synth_usage, stdout);
        return RS_EXIT_OK;
    }
    if (argc >= 2 && !strcmp(argv[1], "merge")) return synth_merge(argc, argv);
    static const struct option longopts[] = {{"calib", required_argument, NULL, OPT_CALIB},
                                             {"count", required_argument, NULL, OPT_COUNT},
                                             {"seed", required_argument, NULL, OPT_SEED},
                                             {"backgrounds", required_argument, NULL, OPT_BG},
                                             {"shard", required_argument, NULL, OPT_SHARD},
                                             {"camera", required_argument, NULL, OPT_CAMERA},
                                             {"size", required_argument, NULL, OPT_SIZE},
                                             {"vehicles", required_argument, NULL, OPT_VEHICLES},
                                             {"split", required_argument, NULL, OPT_SPLIT},
                                             {"no-shadows", no_argument, NULL, OPT_NO_SHADOWS},
                                             {"no-appearance", no_argument, NULL, OPT_NO_LOOK},
                                             {"jobs", required_argument, NULL, OPT_JOBS},
                                             {"separate-processes", no_argument, NULL, OPT_SEPARATE},
                                             {"bbox", required_argument, NULL, OPT_BBOX},
                                             {"min-visibility", required_argument, NULL, OPT_MIN_VIS},
                                             {"keep-invisible", no_argument, NULL, OPT_KEEP_INVISIBLE},
                                             {"no-junction-traffic", no_argument, NULL, OPT_NO_JUNCTION},
                                             {"val-fraction", required_argument, NULL, OPT_VAL_FRACTION},
                                             {"val-camera", required_argument, NULL, OPT_VAL_CAMERA},
                                             {"val-backgrounds", required_argument, NULL, OPT_VAL_BG},
                                             {"val-split", required_argument, NULL, OPT_VAL_SPLIT},
                                             {"traffic-frames", required_argument, NULL, OPT_TRAFFIC_FRAMES},
                                             {"models", required_argument, NULL, OPT_MODELS},
                                             {"sequence", no_argument, NULL, OPT_SEQUENCE},
                                             {"frames", required_argument, NULL, OPT_FRAMES},
                                             {"labels-only", no_argument, NULL, OPT_LABELS_ONLY},
                                             {"output", required_argument, NULL, 'o'},
                                             {"help", no_argument, NULL, 'h'},
                                             {NULL, 0, NULL, 0}};
    rs_synth_dataset_options opt;
    rs_synth_dataset_options_default(&opt);
    opt.jobs = rs_synth_dataset_usable_cpus(NULL, 0);
    const size_t n = (size_t)argc + 1;
    const char **cams = calloc(n, sizeof(char *)), **keys = calloc(n, sizeof(char *)),
               **values = calloc(n, sizeof(char *)), **val_cams = calloc(n, sizeof(char *)),
               **val_keys = calloc(n, sizeof(char *)), **val_values = calloc(n, sizeof(char *));
    char **kv = calloc(n, sizeof(char *)), **val_kv = calloc(n, sizeof(char *));
    int Nkv = 0, Nval_kv = 0, rc = RS_EXIT_OK, c;
    double x;
    long l;
    bool have_count = false, have_frames = false;
    if (!cams || !keys || !values || !kv || !val_cams || !val_keys || !val_values || !val_kv) {
        rc = rs_cli_fail("synth", RS_ERR_NOMEM, NULL);
        goto done;
    }
    optind = 1;
    opterr = 0;
    while (rc == RS_EXIT_OK && (c = getopt_long(argc, argv, "o:h", longopts, NULL)) != -1) {
        switch (c) {
        case OPT_CALIB: opt.calib_dir = optarg; break;
        case 'o': opt.out_dir = optarg; break;
        case OPT_COUNT:
            if (!rs_cli_parse_int(optarg, 1, 100000000, &l))
                rc = rs_cli_usage_error("synth", "--count: expected an integer >= 1");
            opt.count = (int)l;
            have_count = true;
            break;
        case OPT_SEED: {
            char *end;
            errno = 0;
            opt.seed = strtoull(optarg, &end, 10);
            if (!*optarg || *end || errno || optarg[0] == '-')
                rc = rs_cli_usage_error("synth", "--seed: expected an integer >= 0");
            break;
        }
        case OPT_BG: rc = parse_tag("--backgrounds", optarg, kv, keys, values, &Nkv); break;
        case OPT_VAL_BG: rc = parse_tag("--val-backgrounds", optarg, val_kv, val_keys, val_values, &Nval_kv); break;
        case OPT_VAL_CAMERA: val_cams[opt.Nval_cameras++] = optarg; break;
        case OPT_VAL_FRACTION:
            if (!rs_cli_parse_double(optarg, &x) || x < 0 || x > 1)
                rc = rs_cli_usage_error("synth", "--val-fraction: expected a number in [0, 1], got \"%s\"", optarg);
            opt.val_fraction = x;
            break;
        case OPT_MIN_VIS:
            if (!rs_cli_parse_double(optarg, &x) || x < 0 || x > 1)
                rc = rs_cli_usage_error("synth", "--min-visibility: expected a number in [0, 1], got \"%s\"", optarg);
            opt.min_visibility = x;
            break;
        case OPT_KEEP_INVISIBLE: opt.keep_invisible = true; break;
        case OPT_NO_JUNCTION: opt.junction_traffic = false; break;
        case OPT_TRAFFIC_FRAMES:
            if (!*optarg) rc = rs_cli_usage_error("synth", "--traffic-frames: empty folder name");
            opt.traffic_frames_dir = optarg;
            break;
        case OPT_MODELS:
            if (!*optarg) rc = rs_cli_usage_error("synth", "--models: empty file name");
            opt.models_path = optarg;
            break;
        case OPT_SEQUENCE: opt.sequence = true; break;
        case OPT_LABELS_ONLY: opt.labels_only = true; break;
        case OPT_FRAMES: {
            int used = 0;
            if (sscanf(optarg, "%d:%d%n", &opt.frame_first, &opt.frame_end, &used) != 2 || optarg[used] ||
                opt.frame_first < 0 || opt.frame_end <= opt.frame_first)
                rc = rs_cli_usage_error("synth", "--frames: expected A:B with 0 <= A < B, got \"%s\"", optarg);
            have_frames = true;
            break;
        }
        case OPT_BBOX: {
            rs_synth_bbox_kind kind;
            rs_err e = {0};
            if (rs_synth_bbox_kind_parse(&kind, optarg, &e) != RS_OK) rc = rs_cli_usage_error("synth", "%s", e.msg);
            opt.bbox = (int)kind;
            break;
        }
        case OPT_SHARD: {
            int i, N, used = 0;
            if (sscanf(optarg, "%d/%d%n", &i, &N, &used) != 2 || optarg[used] || N < 1 || i < 0 || i >= N)
                rc = rs_cli_usage_error("synth",
                                        "--shard: expected I/N with 0 <= I < N, got "
                                        "\"%s\"",
                                        optarg);
            opt.shard_index = i;
            opt.shard_count = N;
            break;
        }
        case OPT_CAMERA: cams[opt.Ncameras++] = optarg; break;
        case OPT_NO_SHADOWS: opt.shadows = false; break;
        case OPT_NO_LOOK: opt.no_appearance = true; break;
        case OPT_SIZE: {
            int used = 0;
            if (sscanf(optarg, "%dx%d%n", &opt.width, &opt.height, &used) != 2 || optarg[used] || opt.width < 8 ||
                opt.height < 8 || opt.width > 20000 || opt.height > 20000)
                rc = rs_cli_usage_error("synth", "--size: expected WxH (8..20000), got \"%s\"", optarg);
            break;
        }
        case OPT_JOBS:
            if (!rs_cli_parse_int(optarg, 1, 256, &l))
                rc = rs_cli_usage_error("synth", "--jobs: expected an integer in [1, 256]");
            opt.jobs = (int)l;
            break;
        case OPT_SEPARATE: opt.separate_processes = true; break;
        case OPT_VEHICLES:
            if (!rs_cli_parse_int(optarg, 0, 10000, &l))
                rc = rs_cli_usage_error("synth", "--vehicles: expected an integer >= 0");
            opt.vehicles = (int)l;
            break;
        case OPT_SPLIT:
        case OPT_VAL_SPLIT:
            for (const char *p = optarg; *p; p++)
                if (!((*p >= 'A' && *p <= 'Z') || (*p >= 'a' && *p <= 'z') || (*p >= '0' && *p <= '9') || *p == '_' ||
                      *p == '-'))
                    rc = rs_cli_usage_error("synth", "%s: use only [A-Za-z0-9_-]",
                                            c == OPT_SPLIT ? "--split" : "--val-split");
            if (!*optarg) rc = rs_cli_usage_error("synth", "%s: empty", c == OPT_SPLIT ? "--split" : "--val-split");
            if (c == OPT_SPLIT)
                opt.split = optarg;
            else
                opt.val_split = optarg;
            break;
        default: rc = rs_cli_usage_error("synth", "unknown option or missing value: %s", argv[optind - 1]);
        }
    }
    if (rc != RS_EXIT_OK) goto done;
    if (optind + 1 != argc) {
        rc = rs_cli_usage_error("synth", "expected one SITE folder");
        goto done;
    }
    if (opt.sequence && (!opt.traffic_frames_dir || have_count)) {
        rc = rs_cli_usage_error("synth", "--sequence takes --traffic-frames DIR and no --count (one image per frame "
                                         "and camera)");
        goto done;
    }
    if ((have_frames || opt.labels_only) && !opt.sequence) {
        rc = rs_cli_usage_error("synth", "%s is for sequences: add --sequence",
                                have_frames ? "--frames" : "--labels-only");
        goto done;
    }
    if (!opt.calib_dir || !opt.out_dir || (!have_count && !opt.sequence)) {
        rc = rs_cli_usage_error("synth", "--calib, --count (or --sequence) and -o are required");
        goto done;
    }
    opt.site_dir = argv[optind];
    opt.cameras = cams;
    opt.filter_keys = keys;
    opt.filter_values = values;
    opt.Nfilters = Nkv;
    opt.val_cameras = val_cams;
    opt.val_bg_keys = val_keys;
    opt.val_bg_values = val_values;
    opt.Nval_bg = Nval_kv;
    if (opt.traffic_frames_dir && !opt.junction_traffic) {
        rc =
            rs_cli_usage_error("synth", "--no-junction-traffic is for the built-in traffic, not with --traffic-frames");
        goto done;
    }
    if (strcmp(opt.split, opt.val_split) == 0) {
        rc = rs_cli_usage_error("synth", "--split and --val-split name the same split \"%s\"", opt.split);
        goto done;
    }
    rc = synth_run(&opt);
done:
    for (int i = 0; i < Nkv; i++) free(kv[i]);
    for (int i = 0; i < Nval_kv; i++) free(val_kv[i]);
    free(kv);
    free(val_kv);
    free(val_cams);
    free(val_keys);
    free(val_values);
    free(cams);
    free(keys);
    free(values);
    return rc;
}

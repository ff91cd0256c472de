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
#include "synth/rs_synth_dataset.h"

static const char synth_usage[] =
    "usage: roadside synth SITE --calib DIR --count N -o DATASET [--seed S]\n"
    "                      [--backgrounds TAG=VALUE]... [--shard I/N] [--camera ID]...\n"
    "                      [--size WxH] [--vehicles N] [--split NAME] [--no-shadows]\n"
    "                      [--jobs J] [--separate-processes]\n"
    "       roadside synth merge DATASET... -o OUT\n"
    "\n"
    "Synthesises a labelled dataset (docs/synth.md): image k (0 <= k < N) is seen by camera\n"
    "k mod (number of cameras), over a background drawn among the camera's tagged backgrounds\n"
    "(site.json background_images; without any, a neutral grey ground rendered by POV-Ray:\n"
    "make backgrounds first with `roadside site render-backgrounds` or `roadside background`),\n"
    "with the built-in traffic on SITE/lanes.geojson and domain randomisation, the sun from\n"
    "the background's time tag, rendered with POV-Ray, shadows cast onto the background by\n"
    "differential rendering, the vehicles matched to the background's exposure, noise, blur\n"
    "and JPEG quality, and labelled through mrcal. Image k\n"
    "depends only on (seed, k): reruns and shard splits give identical files. A rerun skips\n"
    "finished images after checking their files (a missing or corrupt one is remade, named on\n"
    "stderr). One run per DATASET at a time: a second fails at once, naming the first's pid\n"
    "(DATASET/.lock). Writes DATASET/<split>/*.png, DATASET/annotations/instances_<split>.json\n"
    "(COCO, YOLOX's layout), DATASET/labels/<split>/*.txt (YOLO), DATASET/label_2/*.txt (KITTI).\n"
    "\n"
    "Options:\n"
    "  --calib DIR            calibrated <camera>.cameramodel files (roadside calib -o DIR)\n"
    "  --count N              images in the whole dataset, all shards together\n"
    "  -o, --output DATASET   output folder (created if needed)\n"
    "  --seed S               seed (default 0)\n"
    "  --backgrounds K=V      use only backgrounds whose tag K is V (repeatable; tags: time,\n"
    "                         conditions, synthetic, name and free tags)\n"
    "  --shard I/N            make only the images k with k mod N == I (0 <= I < N)\n"
    "  --camera ID            use this camera (repeatable; default every camera of the site)\n"
    "  --size WxH             output size (the camera's intrinsics scaled; same aspect)\n"
    "  --vehicles N           at most N vehicles of traffic per image (default 10)\n"
    "  --split NAME           COCO split (default train2017)\n"
    "  --no-shadows           no differential-rendering shadows (the shadow pass: the sun's\n"
    "                         shadow and the sky's soft one of each vehicle on the background)\n"
    "  --jobs J               images made at once, in J worker processes (default: 4 per\n"
    "                         core: povray spends much of its time waiting on itself,\n"
    "                         docs/benchmarks.md)\n"
    "  --separate-processes   one povray process per pass (for benchmarks; default: the\n"
    "                         passes of an image are the frames of one povray process)\n"
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
    OPT_JOBS,
    OPT_SEPARATE
};

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
                                             {"jobs", required_argument, NULL, OPT_JOBS},
                                             {"separate-processes", no_argument, NULL, OPT_SEPARATE},
                                             {"output", required_argument, NULL, 'o'},
                                             {"help", no_argument, NULL, 'h'},
                                             {NULL, 0, NULL, 0}};
    rs_synth_dataset_options opt;
    rs_synth_dataset_options_default(&opt);
    const long cores = sysconf(_SC_NPROCESSORS_ONLN);
    opt.jobs = cores > 0 ? (int)(4 * (cores < 8 ? cores : 8)) : 4;
    const size_t n = (size_t)argc + 1;
    const char **cams = calloc(n, sizeof(char *)), **keys = calloc(n, sizeof(char *)),
               **values = calloc(n, sizeof(char *));
    char **kv = calloc(n, sizeof(char *));
    int Nkv = 0, rc = RS_EXIT_OK, c;
    long l;
    bool have_count = false;
    if (!cams || !keys || !values || !kv) {
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
        case OPT_BG: {
            char *eq = strchr(optarg, '=');
            if (!eq || eq == optarg || !eq[1]) {
                rc = rs_cli_usage_error("synth", "--backgrounds: expected TAG=VALUE, got \"%s\"", optarg);
                break;
            }
            kv[Nkv] = strdup(optarg);
            if (!kv[Nkv]) {
                rc = rs_cli_fail("synth", RS_ERR_NOMEM, NULL);
                break;
            }
            kv[Nkv][eq - optarg] = 0;
            keys[Nkv] = kv[Nkv];
            values[Nkv] = kv[Nkv] + (eq - optarg) + 1;
            Nkv++;
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
            for (const char *p = optarg; *p; p++)
                if (!((*p >= 'A' && *p <= 'Z') || (*p >= 'a' && *p <= 'z') || (*p >= '0' && *p <= '9') || *p == '_' ||
                      *p == '-'))
                    rc = rs_cli_usage_error("synth", "--split: use only [A-Za-z0-9_-]");
            if (!*optarg) rc = rs_cli_usage_error("synth", "--split: empty");
            opt.split = optarg;
            break;
        default: rc = rs_cli_usage_error("synth", "unknown option or missing value: %s", argv[optind - 1]);
        }
    }
    if (rc != RS_EXIT_OK) goto done;
    if (optind + 1 != argc) {
        rc = rs_cli_usage_error("synth", "expected one SITE folder");
        goto done;
    }
    if (!opt.calib_dir || !opt.out_dir || !have_count) {
        rc = rs_cli_usage_error("synth", "--calib, --count and -o are required");
        goto done;
    }
    opt.site_dir = argv[optind];
    opt.cameras = cams;
    opt.filter_keys = keys;
    opt.filter_values = values;
    opt.Nfilters = Nkv;
    progress_state ps = {.t0 = wall_s(), .tty = isatty(2) != 0};
    opt.progress = progress;
    opt.progress_ctx = &ps;
    opt.notice = notice;
    rs_synth_dataset_summary sum;
    rs_err err = {0};
    rs_cli_synth_sandbox_note("synth");
    rs_status st = rs_synth_dataset_run(&sum, &opt, &err);
    if (st) {
        rc = rs_cli_fail("synth", st, &err);
        goto done;
    }
    printf("synth: shard %d/%d: %d images (%d made, %d already done, %d over the grey ground), "
           "%d annotations in the dataset, %.1f s (%.1f s in povray, %.3f s/image)\n",
           opt.shard_index, opt.shard_count, sum.Nimages, sum.Nmade, sum.Nskipped, sum.Ngrey, sum.Nannotations,
           sum.seconds, sum.seconds_povray, sum.Nmade > 0 ? sum.seconds / sum.Nmade : 0.0);
    if (sum.Nremade > 0 || sum.Nleft_out > 0)
        printf("resume:      %d of the images made were found damaged and remade; %d part files left out of the "
               "COCO file (stderr names each)\n",
               sum.Nremade, sum.Nleft_out);
    printf("images:      %s/%s/\n", opt.out_dir, opt.split);
    printf("COCO:        %s/annotations/instances_%s.json\n", opt.out_dir, opt.split);
    printf("YOLO:        %s/labels/%s/\n", opt.out_dir, opt.split);
    printf("KITTI:       %s/label_2/\n", opt.out_dir);
done:
    for (int i = 0; i < Nkv; i++) free(kv[i]);
    free(kv);
    free(cams);
    free(keys);
    free(values);
    return rc;
}

// roadside bench -- benchmarks: `bench eval` (here), `bench calib` (cmd_bench_calib.c),
// `bench synth` (cmd_bench_synth.c), `bench site` (cmd_bench_site.c) and `bench track`
// (cmd_bench_track.c).
#include <getopt.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "bench/rs_bench_eval.h"
#include "cli/rs_cli.h"
#include "cli/rs_cli_detect.h"
#include "core/rs_io.h"

static void usage(FILE *out)
{
    fprintf(out, "usage: roadside bench eval [--images N] [--dets N] [--seed S] [--csv FILE] [--dir DIR]\n"
                 "       roadside bench calib ...   (see 'roadside bench calib --help')\n"
                 "       roadside bench synth ...   (see 'roadside bench synth --help')\n"
                 "       roadside bench site ...    (see 'roadside bench site --help')\n"
                 "       roadside bench pick ...    (see 'roadside bench pick --help')\n"
                 "       roadside bench sparse ...  (see 'roadside bench sparse --help')\n"
                 "       roadside bench detect ...  (see 'roadside bench detect --help')\n"
                 "       roadside bench track ...   (see 'roadside bench track --help')\n"
                 "\n"
                 "Benchmarks are programs: each prints a table and writes CSV.\n"
                 "\n"
                 "  eval  writes a synthetic COCO ground truth and COCO results (1920x1080 images,\n"
                 "        3 categories, an ignore region in every 20th image, detections +-6 px off\n"
                 "        their vehicle plus clutter), then times `roadside eval --center-shift 0.5`\n"
                 "        on them: parsing and evaluation separately, with the peak resident memory.\n"
                 "    --images N   images (default 10000)\n"
                 "    --dets N     detections, spread evenly over the images (default 1000000)\n"
                 "    --seed S     random seed (default 1)\n"
                 "    --csv FILE   write the figures as CSV to FILE\n"
                 "    --dir DIR    write gt.json and dets.json into DIR and keep them (default: a\n"
                 "                 temporary folder under $TMPDIR or /tmp, removed afterwards)\n"
                 "\n"
                 "Exit status: 0 ok, 1 failure, 2 usage error. Figures: docs/benchmarks.md.\n");
}

typedef struct {
    long images, dets, seed;
    const char *csv, *dir;
} bench_eval_args;

static int parse_bench_eval(int argc, char **argv, bench_eval_args *a)
{
    *a = (bench_eval_args){.images = 10000, .dets = 1000000, .seed = 1};
    enum { O_IMAGES = 256, O_DETS, O_SEED, O_CSV, O_DIR };
    static const struct option options[] = {
        {"images", required_argument, NULL, O_IMAGES}, {"dets", required_argument, NULL, O_DETS},
        {"seed", required_argument, NULL, O_SEED},     {"csv", required_argument, NULL, O_CSV},
        {"dir", required_argument, NULL, O_DIR},       {NULL, 0, NULL, 0}};
    opterr = 0;
    optind = 0; // glibc: full re-initialisation
    int c;
    while ((c = getopt_long(argc, argv, ":", options, NULL)) != -1) {
        switch (c) {
        case O_IMAGES:
            if (!rs_cli_parse_int(optarg, 1, 100000000, &a->images))
                return rs_cli_usage_error("bench eval", "--images: '%s' is not a whole number in [1, 1e8]", optarg);
            break;
        case O_DETS:
            if (!rs_cli_parse_int(optarg, 0, 1000000000, &a->dets))
                return rs_cli_usage_error("bench eval", "--dets: '%s' is not a whole number in [0, 1e9]", optarg);
            break;
        case O_SEED:
            if (!rs_cli_parse_int(optarg, 0, 2147483647, &a->seed))
                return rs_cli_usage_error("bench eval", "--seed: '%s' is not a whole number >= 0", optarg);
            break;
        case O_CSV: a->csv = optarg; break;
        case O_DIR: a->dir = optarg; break;
        case ':': return rs_cli_usage_error("bench eval", "%s needs a value", argv[optind - 1]);
        default: return rs_cli_usage_error("bench eval", "unknown option '%s'", argv[optind - 1]);
        }
    }
    if (optind != argc) return rs_cli_usage_error("bench eval", "unexpected argument '%s'", argv[optind]);
    return RS_EXIT_OK;
}

static int bench_eval(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        usage(stdout);
        return RS_EXIT_OK;
    }
    bench_eval_args a;
    int rc = parse_bench_eval(argc, argv, &a);
    if (rc) return rc;

    rs_err err = {0};
    rs_status st = RS_OK;
    char tmpdir[4096] = "";
    const char *dir = a.dir;
    if (!dir) {
        const char *base = getenv("TMPDIR");
        snprintf(tmpdir, sizeof tmpdir, "%s/roadside-bench-eval.XXXXXX", base && *base ? base : "/tmp");
        if (!mkdtemp(tmpdir)) return rs_cli_fail("bench eval: cannot create a temporary folder", RS_ERR_IO, NULL);
        dir = tmpdir;
    } else if ((st = rs_io_mkdir_p(dir, &err)))
        return rs_cli_fail("bench eval", st, &err);
    char *gt_path = rs_io_join(dir, "gt.json"), *dets_path = rs_io_join(dir, "dets.json");
    rs_bench_eval_figures f = {0};
    if (!gt_path || !dets_path)
        st = rs_err_set(&err, RS_ERR_NOMEM, "out of memory");
    else
        st = rs_bench_eval_run(&f, (int)a.images, a.dets, (uint64_t)a.seed, gt_path, dets_path, &err);
    if (!a.dir) {
        if (gt_path) unlink(gt_path);
        if (dets_path) unlink(dets_path);
        rmdir(tmpdir);
    }
    free(gt_path);
    free(dets_path);
    if (st != RS_OK) return rs_cli_fail("bench eval", st, &err);

    const double per_det = a.dets ? 1.0 / (double)a.dets : 0;
    const double rss_mib = f.rss_after / 1048576.0;
    const double rss_per_det = (f.rss_after - f.rss_before) * per_det;
    printf("%7s %8s %7s %8s %7s %8s %9s %8s %9s %8s %9s %10s %6s %6s\n", "images", "dets", "gt", "parse_s", "eval_s",
           "total_s", "parse_cpu", "eval_cpu", "total_cpu", "peak_MiB", "rss_B/det", "data_B/det", "mAP", "AR");
    printf("%7ld %8ld %7zu %8.3f %7.3f %8.3f %9.3f %8.3f %9.3f %8.1f %9.1f %10.1f %6.4f %6.4f\n", a.images, a.dets,
           f.gt, f.parse_s, f.eval_s, f.parse_s + f.eval_s, f.parse_cpu_s, f.eval_cpu_s, f.parse_cpu_s + f.eval_cpu_s,
           rss_mib, rss_per_det, f.data_bytes * per_det, f.map, f.ar);
    printf("%zu ignore regions; writing the files took %.3f s. _s: wall clock, _cpu: CPU time of this\n"
           "process (user + system), seconds; rss_B/det: growth of the peak resident memory over parsing\n"
           "and evaluation per detection (input text included); data_B/det: the parsed arrays.\n",
           f.crowd, f.generate_s);
    if (a.csv) {
        char csv[1024];
        int n = snprintf(csv, sizeof csv,
                         "images,dets,gt,ignore_regions,seed,parse_s,eval_s,total_s,parse_cpu_s,eval_cpu_s,total_cpu_s,"
                         "peak_rss_mib,rss_bytes_per_det,data_bytes_per_det,mAP,AR\n"
                         "%ld,%ld,%zu,%zu,%ld,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.3f,%.3f,%.3f,%.9g,%.9g\n",
                         a.images, a.dets, f.gt, f.crowd, a.seed, f.parse_s, f.eval_s, f.parse_s + f.eval_s,
                         f.parse_cpu_s, f.eval_cpu_s, f.parse_cpu_s + f.eval_cpu_s, rss_mib, rss_per_det,
                         f.data_bytes * per_det, f.map, f.ar);
        if ((st = rs_io_write_file(a.csv, csv, (size_t)n, &err))) return rs_cli_fail("bench eval", st, &err);
    }
    return RS_EXIT_OK;
}

int rs_cli_bench(int argc, char **argv)
{
    if (argc < 2) return rs_cli_usage_error("bench", "missing benchmark: eval, calib, synth or site");
    if (!strcmp(argv[1], "eval")) return bench_eval(argc - 1, argv + 1);
    if (!strcmp(argv[1], "calib")) return rs_cli_bench_calib(argc - 1, argv + 1);
    if (!strcmp(argv[1], "synth")) return rs_cli_bench_synth(argc - 1, argv + 1);
    if (!strcmp(argv[1], "site")) return rs_cli_bench_site(argc - 1, argv + 1);
    if (!strcmp(argv[1], "pick")) return rs_cli_bench_pick(argc - 1, argv + 1);
    if (!strcmp(argv[1], "sparse")) return rs_cli_bench_sparse(argc - 1, argv + 1);
    if (!strcmp(argv[1], "detect")) return rs_cli_bench_detect(argc - 1, argv + 1);
    if (!strcmp(argv[1], "track")) return rs_cli_bench_track(argc - 1, argv + 1);
    if (!strcmp(argv[1], "-h") || !strcmp(argv[1], "--help")) {
        usage(stdout);
        return RS_EXIT_OK;
    }
    return rs_cli_usage_error("bench", "unknown benchmark '%s': eval, calib, synth, site, pick, sparse or track",
                              argv[1]);
}

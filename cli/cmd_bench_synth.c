// roadside bench synth -- the time of `roadside synth` with each saving turned off in turn
// (bench/rs_bench_synth.h). Parses, calls the library, prints.
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "bench/rs_bench_synth.h"
#include "cli/rs_cli.h"
#include "core/rs_io.h"

static const char bench_synth_usage[] =
    "usage: roadside bench synth SITE --calib DIR [--count N] [--size WxH] [--vehicles N]\n"
    "                            [--jobs J] [--seed S] [--csv FILE] [--dir DIR] [--quick]\n"
    "                            [--variants LIST] [--memory-every N] [--models FILE]\n"
    "\n"
    "Times `roadside synth` on SITE (its backgrounds: make them first with `roadside site\n"
    "render-backgrounds`) with every saving, then with each saving turned off in turn, on the\n"
    "same images: all (every saving), jobs=1 (one image at a time), separate (the passes'\n"
    "povray processes one after the other instead of at once), full-frame (no culling, no\n"
    "region rendering), no-shadows (the shadow pass skipped), full-detail (no medium or\n"
    "coarse meshes for vehicles under 120 and 40 px), no-appearance (the camera's look not applied: its cost).\n"
    "Prints a table: wall and CPU\n"
    "seconds per image (CPU of roadside, its workers and povray), vehicles per image, and\n"
    "the time 4 cameras x 1000 images would take at that rate; memory: the peak resident set\n"
    "of roadside during the variant (VmHWM) and of its largest finished child so far\n"
    "(getrusage), and the resident set of the live process tree read from /proc every N\n"
    "images, with its growth per 100 images (first checkpoint to last).\n"
    "\n"
    "  --calib DIR   calibrated <camera>.cameramodel files\n"
    "  --count N     images per variant (default 48; --quick: 8)\n"
    "  --size WxH    output size (default 720x405: 720 wide at the demo's 16:9)\n"
    "  --vehicles N  at most N vehicles per image, among those the camera sees (default 10)\n"
    "  --jobs J      workers of every variant but jobs=1 (default: 4 per core)\n"
    "  --seed S      seed (default 1)\n"
    "  --csv FILE    write the table as CSV (atomically)\n"
    "  --dir DIR     scratch folder (default: a new folder under $TMPDIR or /tmp, removed)\n"
    "  --quick       8 images, variants all and jobs=1 only (for the test suite)\n"
    "  --variants LIST  comma-separated variants to run, in the order above (e.g. all)\n"
    "  --memory-every N  a memory checkpoint every N images (default: a tenth of --count)\n"
    "  --models FILE  a library of user models, as `roadside synth --models` (the cost of\n"
    "                textured models, docs/benchmarks.md)\n"
    "\n"
    "Exit status: 0 ok, 1 failure, 2 usage error. Figures: docs/benchmarks.md.\n";

enum {
    O_CALIB = 3000,
    O_COUNT,
    O_SIZE,
    O_VEHICLES,
    O_JOBS,
    O_SEED,
    O_CSV,
    O_DIR,
    O_QUICK,
    O_VARIANTS,
    O_MEMORY_EVERY,
    O_MODELS
};

// The table of the variants on stdout and, in text (size bytes), the same as CSV; returns the
// CSV's length (snprintf's: may exceed size).
static int print_table(const rs_bench_synth_row *rows, int Nrows, char *text, size_t size)
{
    printf("\n%-11s %4s %6s %8s %8s %9s %10s %10s %12s %9s %9s %9s %11s  %s\n", "variant", "jobs", "images", "veh/img",
           "wall_s", "s/image", "cpu_s/img", "4x1000_min", "povray_s/img", "peak_MiB", "child_MiB", "tree_MiB",
           "MiB/100img", "what");
    int n = snprintf(text, size,
                     "variant,jobs,images,vehicles_per_image,wall_s,"
                     "s_per_image,cpu_s_per_image,povray_s_per_image,peak_rss_self_mib,peak_rss_children_mib,"
                     "rss_roadside_first_mib,rss_roadside_last_mib,rss_tree_max_mib,rss_growth_mib_per_100_images,"
                     "rss_slope_mib_per_100_images,memory_checkpoints\n");
    for (int k = 0; k < Nrows; k++) {
        const rs_bench_synth_row *r = &rows[k];
        const double per = r->wall_s / (r->Nimages > 0 ? r->Nimages : 1);
        const double vpi = (double)r->Nannotations / (r->Nimages > 0 ? r->Nimages : 1);
        long tree_max = 0;
        for (int i = 0; i < r->Ncheckpoints; i++)
            if (r->cp_rss_tree_kib[i] > tree_max) tree_max = r->cp_rss_tree_kib[i];
        int last = -1;
        const double growth = rs_bench_synth_growth_kib_per_100(r, &last, NULL) / 1024;
        printf("%-11s %4d %6d %8.1f %8.1f %9.3f %10.3f %10.1f %12.3f %9.1f %9.1f %9.1f %11.2f  %s\n", r->name, r->jobs,
               r->Nimages, vpi, r->wall_s, per, r->cpu_s / (r->Nimages > 0 ? r->Nimages : 1), 4000 * per / 60,
               r->povray_s / (r->Nimages > 0 ? r->Nimages : 1), r->peak_self_kib / 1024.0,
               r->peak_children_kib / 1024.0, tree_max / 1024.0, growth, r->what);
        if (n < (int)size)
            n += snprintf(text + n, size - (size_t)n,
                          "%s,%d,%d,%.3f,%.3f,%.4f,%.4f,%.4f,%.1f,%.1f,%.1f,%.1f,%.1f,%.3f,%.3f,%d\n", r->name, r->jobs,
                          r->Nimages, vpi, r->wall_s, per, r->cpu_s / (r->Nimages > 0 ? r->Nimages : 1),
                          r->povray_s / (r->Nimages > 0 ? r->Nimages : 1), r->peak_self_kib / 1024.0,
                          r->peak_children_kib / 1024.0, last >= 0 ? r->cp_rss_roadside_kib[0] / 1024.0 : NAN,
                          last >= 0 ? r->cp_rss_roadside_kib[last] / 1024.0 : NAN, tree_max / 1024.0, growth,
                          rs_bench_synth_slope_kib_per_100(r) / 1024, r->Ncheckpoints);
    }
    return n;
}

// The memory checkpoints of each variant and their growth per 100 images.
static void print_memory(const rs_bench_synth_row *rows, int Nrows)
{
    // memory over the run: the sampled resident sets at each checkpoint, and their growth
    printf("\nmemory: resident set of the live process tree (/proc/PID/statm), MiB, every %d images\n",
           Nrows > 0 ? rows[0].memory_every : 0);
    for (int k = 0; k < Nrows; k++) {
        const rs_bench_synth_row *r = &rows[k];
        printf("%-11s images   ", r->name);
        for (int i = 0; i < r->Ncheckpoints; i++) printf(" %7d", r->cp_images[i]);
        printf("\n%-11s roadside ", "");
        for (int i = 0; i < r->Ncheckpoints; i++) printf(" %7.1f", r->cp_rss_roadside_kib[i] / 1024.0);
        printf("\n%-11s tree     ", "");
        for (int i = 0; i < r->Ncheckpoints; i++) printf(" %7.1f", r->cp_rss_tree_kib[i] / 1024.0);
        printf("\n%-11s largest  ", "");
        for (int i = 0; i < r->Ncheckpoints; i++) printf(" %7.1f", r->cp_rss_largest_kib[i] / 1024.0);
        printf("\n%-11s roadside processes", "");
        for (int i = 0; i < r->Ncheckpoints; i++) printf(" %d", r->cp_roadside[i]);
        printf(", all processes");
        for (int i = 0; i < r->Ncheckpoints; i++) printf(" %d", r->cp_processes[i]);
        int last = -1;
        double largest = NAN;
        const double growth = rs_bench_synth_growth_kib_per_100(r, &last, &largest) / 1024;
        if (isfinite(growth))
            printf("\n%-11s growth per 100 images: roadside %.1f -> %.1f MiB from image %d to %d (%d roadside "
                   "processes): %+.2f MiB per 100 images; largest process %.1f -> %.1f MiB: %+.2f MiB per 100 "
                   "images\n",
                   "", r->cp_rss_roadside_kib[0] / 1024.0, r->cp_rss_roadside_kib[last] / 1024.0, r->cp_images[0],
                   r->cp_images[last], r->cp_roadside[0], growth, r->cp_rss_largest_kib[0] / 1024.0,
                   r->cp_rss_largest_kib[last] / 1024.0, largest / 1024);
        if (isfinite(growth))
            printf("%-11s least-squares slope through those checkpoints: %+.2f MiB per 100 images\n", "",
                   rs_bench_synth_slope_kib_per_100(r) / 1024);
        else
            printf("\n%-11s growth per 100 images: fewer than 2 checkpoints with every worker alive\n", "");
        // the later half alone: per-process caches (a background's resampling, estimates) fill
        // as each worker meets each background, a leak keeps growing
        int mid = 0;
        while (last > 0 && mid < last && 2 * r->cp_images[mid] < r->cp_images[last]) mid++;
        if (isfinite(growth) && mid > 0 && mid < last)
            printf("%-11s later half: roadside %.1f -> %.1f MiB from image %d to %d: %+.2f MiB per 100 images\n", "",
                   r->cp_rss_roadside_kib[mid] / 1024.0, r->cp_rss_roadside_kib[last] / 1024.0, r->cp_images[mid],
                   r->cp_images[last],
                   100.0 * (r->cp_rss_roadside_kib[last] - r->cp_rss_roadside_kib[mid]) / 1024.0 /
                       (r->cp_images[last] - r->cp_images[mid]));
    }
}

int rs_cli_bench_synth(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        fputs(bench_synth_usage, stdout);
        return RS_EXIT_OK;
    }
    static const struct option longopts[] = {{"calib", required_argument, NULL, O_CALIB},
                                             {"count", required_argument, NULL, O_COUNT},
                                             {"size", required_argument, NULL, O_SIZE},
                                             {"vehicles", required_argument, NULL, O_VEHICLES},
                                             {"jobs", required_argument, NULL, O_JOBS},
                                             {"seed", required_argument, NULL, O_SEED},
                                             {"csv", required_argument, NULL, O_CSV},
                                             {"dir", required_argument, NULL, O_DIR},
                                             {"quick", no_argument, NULL, O_QUICK},
                                             {"variants", required_argument, NULL, O_VARIANTS},
                                             {"memory-every", required_argument, NULL, O_MEMORY_EVERY},
                                             {"models", required_argument, NULL, O_MODELS},
                                             {NULL, 0, NULL, 0}};
    rs_synth_dataset_options o;
    rs_synth_dataset_options_default(&o);
    o.width = 720;
    o.height = 405;
    o.seed = 1;
    const long cores = sysconf(_SC_NPROCESSORS_ONLN);
    int J = cores > 0 ? (int)(4 * (cores < 8 ? cores : 8)) : 4, count = -1;
    bool quick = false;
    const char *csv = NULL, *dir = NULL, *variants = NULL;
    int memory_every = 0;
    long l;
    int c;
    optind = 1;
    opterr = 0;
    while ((c = getopt_long(argc, argv, "h", longopts, NULL)) != -1) {
        switch (c) {
        case O_CALIB: o.calib_dir = optarg; break;
        case O_COUNT:
            if (!rs_cli_parse_int(optarg, 1, 1000000, &l))
                return rs_cli_usage_error("bench synth", "--count: expected an integer >= 1");
            count = (int)l;
            break;
        case O_SIZE: {
            int used = 0;
            if (sscanf(optarg, "%dx%d%n", &o.width, &o.height, &used) != 2 || optarg[used] || o.width < 8 ||
                o.height < 8 || o.width > 20000 || o.height > 20000)
                return rs_cli_usage_error("bench synth", "--size: expected WxH (8..20000), got \"%s\"", optarg);
            break;
        }
        case O_VEHICLES:
            if (!rs_cli_parse_int(optarg, 0, 10000, &l))
                return rs_cli_usage_error("bench synth", "--vehicles: expected an integer >= 0");
            o.vehicles = (int)l;
            break;
        case O_JOBS:
            if (!rs_cli_parse_int(optarg, 1, 256, &l))
                return rs_cli_usage_error("bench synth", "--jobs: expected an integer in [1, 256]");
            J = (int)l;
            break;
        case O_SEED:
            if (!rs_cli_parse_int(optarg, 0, 1000000000, &l))
                return rs_cli_usage_error("bench synth", "--seed: expected an integer >= 0");
            o.seed = (uint64_t)l;
            break;
        case O_MODELS: o.models_path = optarg; break;
        case O_CSV: csv = optarg; break;
        case O_DIR: dir = optarg; break;
        case O_QUICK: quick = true; break;
        case O_VARIANTS: variants = optarg; break;
        case O_MEMORY_EVERY:
            if (!rs_cli_parse_int(optarg, 1, 1000000, &l))
                return rs_cli_usage_error("bench synth", "--memory-every: expected an integer >= 1");
            memory_every = (int)l;
            break;
        default: return rs_cli_usage_error("bench synth", "unknown option or missing value: %s", argv[optind - 1]);
        }
    }
    if (optind != argc - 1) return rs_cli_usage_error("bench synth", "expected one SITE folder");
    if (!o.calib_dir) return rs_cli_usage_error("bench synth", "--calib DIR is required");
    o.site_dir = argv[optind];
    o.count = count > 0 ? count : quick ? 8 : 48;

    char tmpl[4096];
    char *scratch = NULL;
    if (!dir && !(scratch = rs_cli_scratch_dir(tmpl, "bench-synth"))) return RS_EXIT_FAIL;
    rs_bench_synth_row rows[RS_SYNTH_BENCH_VARIANTS];
    rs_bench_synth_variants(rows, J);
    int Nrows = quick ? 2 : RS_SYNTH_BENCH_VARIANTS;
    if (variants) { // keep the named rows, in the table's order
        int kept = 0;
        for (int k = 0; k < RS_SYNTH_BENCH_VARIANTS; k++) {
            const size_t len = strlen(rows[k].name);
            for (const char *p = variants; *p;) {
                const size_t n = strcspn(p, ",");
                if (n == len && !strncmp(p, rows[k].name, n)) {
                    rows[kept++] = rows[k];
                    break;
                }
                p += n + (p[n] == ',');
            }
        }
        for (const char *p = variants; *p;) { // every name must be a variant
            const size_t n = strcspn(p, ",");
            bool known = false;
            for (int k = 0; k < kept; k++) known |= strlen(rows[k].name) == n && !strncmp(p, rows[k].name, n);
            if (!known)
                return rs_cli_usage_error("bench synth",
                                          "--variants: \"%.*s\" is not one of all, jobs=1, separate, full-frame, "
                                          "no-shadows, full-detail, no-appearance",
                                          (int)n, p);
            p += n + (p[n] == ',');
        }
        if (!kept) return rs_cli_usage_error("bench synth", "--variants: no variant named");
        Nrows = kept;
    }
    for (int k = 0; k < Nrows; k++) rows[k].memory_every = memory_every;
    printf("roadside bench synth: %s, %d images of %dx%d per variant, at most %d vehicles each, "
           "seed %llu, %ld cores\n",
           o.site_dir, o.count, o.width, o.height, o.vehicles, (unsigned long long)o.seed, cores);
    fflush(stdout);
    rs_err err = {0};
    rs_status st = rs_bench_synth_run(rows, Nrows, &o, dir ? dir : scratch, &err);
    if (scratch) rs_io_remove_tree(scratch);
    if (st) return rs_cli_fail("bench synth", st, &err);
    char text[8192];
    int n = print_table(rows, Nrows, text, sizeof(text));
    print_memory(rows, Nrows);
    // the peaks over the whole bench: this process and the largest of its finished children (a
    // worker or a povray process), getrusage(2)'s ru_maxrss in KiB
    struct rusage self = {0}, kids = {0};
    getrusage(RUSAGE_SELF, &self);
    getrusage(RUSAGE_CHILDREN, &kids);
    printf("\npeak RSS: roadside %.1f MiB, largest child (worker or povray) %.1f MiB, over %d images a variant\n",
           self.ru_maxrss / 1024.0, kids.ru_maxrss / 1024.0, o.count);
    if (csv && (st = rs_io_write_file(csv, text, (size_t)n, &err))) return rs_cli_fail("bench synth", st, &err);
    return RS_EXIT_OK;
}

// roadside bench sparse -- sparse map-picked surveys with an unknown focal length: leave-one-out
// ground errors of roadside's calibration against a least-squares homography
// (bench/rs_bench_sparse.h). Parses, calls the library, prints.
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench/rs_bench_sparse.h"
#include "cli/rs_cli.h"
#include "core/rs_io.h"
#include "core/rs_stats.h"

static const char bench_sparse_usage[] =
    "usage: roadside bench sparse [--sites N] [--seed S] [--points A,B] [--focal-range F] [--lens MODEL]\n"
    "                             [--true-intrinsics] [--csv FILE] [--dir DIR] [--verbose] [--folds]\n"
    "\n"
    "Sparse, map-picked surveys with an unknown focal length (issue 38, item 2). Each site is\n"
    "`roadside site simulate --cameras 1 --points M --elevated-fraction 0 --landmark-heights unknown\n"
    "--survey-sigma 0.5,0 --pixel-sigma 3 --outliers 0 --focal-error-range F --seed S+k` with M drawn\n"
    "in A..B. Per site, leave-one-out over its points: `calib --refine focal` on the others, the\n"
    "left-out pick located on the ground, its horizontal distance to the truth; the same with a\n"
    "least-squares homography (OpenCV's findHomography, method 0) from pixels to (E, N).\n"
    "\n"
    "  --sites N        sites (default 100)\n"
    "  --seed S         seed of the first site (default 1)\n"
    "  --points A,B     points per site, drawn in A..B (default 6,8)\n"
    "  --focal-range F  nominal focal off by a factor log-uniform in [1/F, F] (default 1.5; 1..2)\n"
    "  --lens MODEL     lens model (default LENSMODEL_PINHOLE)\n"
    "  --csv FILE       one row per site, written atomically\n"
    "  --dir DIR        scratch folder (default: a new folder under $TMPDIR or /tmp, removed)\n"
    "  --true-intrinsics  calibrate with the TRUE intrinsics, held: the reference no estimate of\n"
    "                   the focal can be expected to beat (the homography's share is not 100%\n"
    "                   even then: 6..8 noisy points)\n"
    "  --verbose        one line per site\n"
    "  --folds          and each fold's figures\n"
    "\n"
    "Prints: folds and sites without a pose, the share of sites where roadside's leave-one-out\n"
    "median is at most the homography's, and the medians over all folds' site medians.\n"
    "Exit status: 0 ok, 1 failure, 2 usage error. Figures: docs/benchmarks.md.\n";

enum { O_SITES = 3200, O_SEED, O_POINTS, O_FOCAL, O_LENS, O_CSV, O_DIR, O_VERBOSE, O_FOLDS, O_TRUE };

// The summary of Nsites rows.
static void print_summary(const rs_bench_sparse_row *rows, int Nsites)
{
    int folds = 0, no_pose = 0, sites_no_pose = 0, not_worse = 0, no_location = 0;
    double *ours = malloc(sizeof(double) * (size_t)(Nsites + 1)),
           *homog = malloc(sizeof(double) * (size_t)(Nsites + 1));
    for (int k = 0; k < Nsites; k++) {
        folds += rows[k].Npoints;
        no_pose += rows[k].Nno_pose;
        no_location += rows[k].Nno_location;
        sites_no_pose += rows[k].Nno_pose > 0;
        not_worse += rows[k].loo_median_m <= rows[k].homography_median_m;
        if (ours) ours[k] = rows[k].loo_median_m;
        if (homog) homog[k] = rows[k].homography_median_m;
    }
    printf("sites %d, folds %d: folds without a pose %d (sites with one %d); folds whose pose puts the left-out\n"
           "pick above the horizon %d\n",
           Nsites, folds, no_pose, sites_no_pose, no_location);
    printf("sites where roadside's leave-one-out median <= the homography's: %d of %d (%.1f%%)\n", not_worse, Nsites,
           Nsites ? 100.0 * not_worse / Nsites : 0.0);
    if (ours && homog && Nsites > 0)
        printf("median of the sites' leave-one-out medians: roadside %.2f m, homography %.2f m\n",
               rs_stats_median(ours, Nsites), rs_stats_median(homog, Nsites));
    free(ours), free(homog);
}

// Parses the options into o and the rest; RS_EXIT_OK or the usage error's exit code.
static int parse(int argc, char **argv, rs_bench_sparse_options *o, long *Nsites, const char **csv, const char **dir,
                 bool *verbose)
{
    static const struct option longopts[] = {{"sites", required_argument, NULL, O_SITES},
                                             {"seed", required_argument, NULL, O_SEED},
                                             {"points", required_argument, NULL, O_POINTS},
                                             {"focal-range", required_argument, NULL, O_FOCAL},
                                             {"lens", required_argument, NULL, O_LENS},
                                             {"csv", required_argument, NULL, O_CSV},
                                             {"dir", required_argument, NULL, O_DIR},
                                             {"verbose", no_argument, NULL, O_VERBOSE},
                                             {"folds", no_argument, NULL, O_FOLDS},
                                             {"true-intrinsics", no_argument, NULL, O_TRUE},
                                             {NULL, 0, NULL, 0}};
    int c, pts[2], Npts;
    long seed;
    optind = 1;
    opterr = 0;
    while ((c = getopt_long(argc, argv, "h", longopts, NULL)) != -1) {
        switch (c) {
        case O_SITES:
            if (!rs_cli_parse_int(optarg, 1, 1000000, Nsites))
                return rs_cli_usage_error("bench sparse", "--sites: expected an integer in 1..1e6");
            break;
        case O_SEED:
            if (!rs_cli_parse_int(optarg, 0, 1000000000, &seed))
                return rs_cli_usage_error("bench sparse", "--seed: expected an integer >= 0");
            o->seed = (uint64_t)seed;
            break;
        case O_POINTS:
            if (!rs_cli_parse_int_list(optarg, 5, 100, pts, 2, &Npts) || Npts != 2 || pts[0] > pts[1])
                return rs_cli_usage_error("bench sparse", "--points: expected A,B with 5 <= A <= B <= 100");
            o->points_min = pts[0], o->points_max = pts[1];
            break;
        case O_FOCAL:
            if (!rs_cli_parse_double(optarg, &o->focal_error_range) || !(o->focal_error_range >= 1.0) ||
                o->focal_error_range > 2.0)
                return rs_cli_usage_error("bench sparse", "--focal-range: expected a number in 1..2");
            break;
        case O_LENS: o->lensmodel = optarg; break;
        case O_CSV: *csv = optarg; break;
        case O_DIR: *dir = optarg; break;
        case O_VERBOSE: *verbose = true; break;
        case O_FOLDS: *verbose = o->verbose_folds = true; break;
        case O_TRUE: o->true_intrinsics = true; break;
        default: return rs_cli_usage_error("bench sparse", "unknown option or missing value: %s", argv[optind - 1]);
        }
    }
    if (optind != argc) return rs_cli_usage_error("bench sparse", "unexpected argument '%s'", argv[optind]);
    return RS_EXIT_OK;
}

int rs_cli_bench_sparse(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        fputs(bench_sparse_usage, stdout);
        return RS_EXIT_OK;
    }
    rs_bench_sparse_options o;
    rs_bench_sparse_options_default(&o);
    long Nsites = 100;
    const char *csv = NULL, *dir = NULL;
    bool verbose = false;
    int rc = parse(argc, argv, &o, &Nsites, &csv, &dir, &verbose);
    if (rc != RS_EXIT_OK) return rc;
    char tmpl[4096];
    char *scratch = NULL;
    if (!dir && !(scratch = rs_cli_scratch_dir(tmpl, "bench-sparse"))) return RS_EXIT_FAIL;
    rs_bench_sparse_row *rows = calloc((size_t)Nsites, sizeof *rows);
    size_t cap = 128 + (size_t)Nsites * 320, n = 0;
    char *text = malloc(cap);
    rs_err err = {0};
    rs_status st = rows && text ? RS_OK : rs_err_set(&err, RS_ERR_NOMEM, "bench sparse: out of memory");
    if (text)
        n += (size_t)snprintf(text, cap,
                              "seed,points,focal_nominal_rel,no_pose,no_location,loo_median_m,"
                              "homography_median_m,loo_max_m,homography_max_m,first_error\n");
    int done = 0;
    for (int k = 0; k < Nsites && st == RS_OK; k++, done++) {
        rs_bench_sparse_row *r = &rows[k];
        st = rs_bench_sparse_site(r, &o, k, dir ? dir : scratch, &err);
        if (st) break;
        if (verbose || r->Nno_pose || r->Nno_location)
            printf("site %llu: %d points, focal %.3f x true: no pose %d, no location %d; LOO median %.2f m (homography "
                   "%.2f m)%s%s\n",
                   (unsigned long long)r->seed, r->Npoints, r->focal_nominal_rel, r->Nno_pose, r->Nno_location,
                   r->loo_median_m, r->homography_median_m, r->first_error[0] ? ": " : "", r->first_error);
        for (char *c = r->first_error; *c; c++)
            if (*c == ',' || *c == '\n' || *c == '"') *c = ';';
        n += (size_t)snprintf(text + n, cap - n, "%llu,%d,%.4f,%d,%d,%.4f,%.4f,%.4f,%.4f,%s\n",
                              (unsigned long long)r->seed, r->Npoints, r->focal_nominal_rel, r->Nno_pose,
                              r->Nno_location, r->loo_median_m, r->homography_median_m, r->loo_max_m,
                              r->homography_max_m, r->first_error);
        fflush(stdout);
    }
    if (scratch) rs_io_remove_tree(scratch);
    if (st == RS_OK) print_summary(rows, done);
    if (st == RS_OK && csv) st = rs_io_write_file(csv, text, n, &err);
    free(rows);
    free(text);
    if (st) return rs_cli_fail("bench sparse", st, &err);
    return RS_EXIT_OK;
}

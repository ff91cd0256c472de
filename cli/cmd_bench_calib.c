// roadside bench calib -- pose solvers side by side against the Cramer-Rao bound (issue 5);
// the numerical stress run. The work is in bench/rs_bench_calib.h; this file parses and prints.
#include <getopt.h>
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "bench/rs_bench_calib.h"
#include "cli/rs_cli.h"

static void usage(FILE *out)
{
    fprintf(out, "usage: roadside bench calib [--trials N] [--csv FILE] [--plot FILE.png] [--quick] [--seed S]\n"
                 "       roadside bench calib --stress N [--seed S]\n"
                 "\n"
                 "Runs roadside's pose solver (full, initialisation only, survey taken as exact), OpenCV's\n"
                 "solvePnP (ITERATIVE, EPNP, SQPNP, IPPE; each alone and + solvePnPRefineLM; solvePnPRansac\n"
                 "alone and + LM) and OpenGV's (P3P Kneip/Gao in RANSAC, EPnP, UPnP, EPnP + non-linear\n"
                 "optimisation) on identical simulated problems, sweeping one knob at a time away from a\n"
                 "baseline (20 landmarks, 1 px, 0.3 m survey sigma, no outliers, camera 8 m up, 25 m away):\n"
                 "pixel noise, landmark count, outlier fraction, survey noise, planar landmarks, camera\n"
                 "height, distance. For each method and configuration it prints the median and 90th\n"
                 "percentile CPU time (us) of a call made right after an untimed one (every method timed\n"
                 "warm), the RMS rotation, position and ground-localisation errors, the failure rate and\n"
                 "the Cramer-Rao bound (CRB) of the same configuration.\n"
                 "\n"
                 "  --trials N     problems per configuration (default 50; --quick: 3)\n"
                 "  --quick        a small grid (3 configurations), for the test suite\n"
                 "  --csv FILE     write every row as CSV (written atomically)\n"
                 "  --plot FILE    write a PNG: time against error / CRB, one panel per family\n"
                 "  --seed S       seed of the problems (default 1)\n"
                 "  --stress N     instead: solve N random problems with roadside's solver and check that\n"
                 "                 every output is finite and every failure is named; the seed is random\n"
                 "                 (and printed) unless --seed is given\n"
                 "\n"
                 "Exit status: 0 ok (for --stress: no finding), 1 failure, 2 usage error.\n"
                 "Definitions and the last full run: docs/benchmarks.md.\n");
}

static void progress(int done, int total, void *cookie)
{
    (void)cookie;
    fprintf(stderr, "\rroadside bench calib: configuration %d/%d", done, total);
    if (done == total) fputc('\n', stderr);
}

static void print_table(const rs_bench_calib_row *rows, int Nrows)
{
    printf("%-15s %-19s %5s %7s %9s %9s %10s %10s %10s %9s %9s %7s %7s  %s\n", "config", "method", "fail", "med_us",
           "p90_us", "rot_deg", "pos_m", "ground_m", "crb_rot", "crb_pos", "rot/crb", "pos/crb", "cond",
           "first failure");
    const char *last = "";
    for (int i = 0; i < Nrows; i++) {
        const rs_bench_calib_row *r = &rows[i];
        if (strcmp(last, r->config)) printf("\n");
        last = r->config;
        char fail[16];
        snprintf(fail, sizeof fail, "%d/%d", r->failures, r->trials);
        printf("%-15s %-19s %5s %7.0f %9.0f %9.3g %10.3g %10.3g %10.3g %9.3g %9.3g %7.3g %7.3g  %s\n", r->config,
               r->method, fail, r->time_med_us, r->time_p90_us, r->rot_rms_deg, r->pos_rms_m, r->ground_rms_m,
               r->crb_rot_deg, r->crb_pos_m, r->rot_ratio, r->pos_ratio, r->cond_median, r->failure);
    }
}

static int run_stress(long N, bool have_seed, uint64_t seed)
{
    if (!have_seed) {
        struct timespec t;
        clock_gettime(CLOCK_REALTIME, &t);
        seed = ((uint64_t)t.tv_sec * 1000000007ull) ^ (uint64_t)t.tv_nsec ^ ((uint64_t)getpid() << 32);
        seed &= (1ull << 53) - 1;
    }
    printf("stress: %ld problems, seed %" PRIu64 " (problem k uses seed + k)\n", N, seed);
    fflush(stdout);
    rs_bench_calib_stress_summary S;
    rs_err err = {0};
    const rs_status st = rs_bench_calib_stress(&S, (int)N, seed, &err);
    if (st != RS_OK) return rs_cli_fail("bench calib --stress", st, &err);
    printf("generated %d, poses %d, flagged (condition number > 100) %d, largest condition number %.3g\n", S.Ngenerated,
           S.Nok, S.Nflagged, S.cond_max);
    for (int c = 1; c < 16; c++)
        if (S.Nerror[c]) printf("errors %-28s %d\n", rs_strerror((rs_status)c), S.Nerror[c]);
    printf("findings: non-finite %d, unnamed errors %d, unflagged condition %d, confident wrong poses %d\n",
           S.Nnonfinite, S.Nunnamed, S.Nunflagged, S.Nbad);
    printf("tail: %d poses (%.3f%%) outside their 99.9%% region (%d of them without any warning, %d with no warning "
           "but that the focal cannot be checked: %.3f%% of the %d poses without a specific warning, 0.1%% by "
           "chance), %d beyond 10 sigma (%d of them with no warning but that one); %d poses (%.1f%%) carry a warning\n",
           S.Nout999, 100.0 * S.Nout999 / (S.Nok ? S.Nok : 1), S.Nout999_unwarned, S.Nout999_bare,
           100.0 * S.Nout999_bare / (S.Nbare ? S.Nbare : 1), S.Nbare, S.Nbeyond10, S.Nbeyond10_bare, S.Nwarned,
           100.0 * S.Nwarned / (S.Nok ? S.Nok : 1));
    if (S.first_bad[0]) printf("first finding: seed %" PRIu64 ": %s\n", S.first_bad_seed, S.first_bad);
    return S.Nnonfinite || S.Nunnamed || S.Nunflagged || S.Nbad ? RS_EXIT_FAIL : RS_EXIT_OK;
}

int rs_cli_bench_calib(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        usage(stdout);
        return RS_EXIT_OK;
    }
    static const struct option longopts[] = {{"trials", required_argument, 0, 't'},
                                             {"csv", required_argument, 0, 'c'},
                                             {"plot", required_argument, 0, 'p'},
                                             {"quick", no_argument, 0, 'q'},
                                             {"seed", required_argument, 0, 's'},
                                             {"stress", required_argument, 0, 'S'},
                                             {0, 0, 0, 0}};
    rs_bench_calib_options o;
    rs_bench_calib_options_default(&o);
    const char *csv = NULL, *plot = NULL;
    long trials = -1, stress = 0, seed = 1;
    bool have_seed = false;
    optind = 1;
    opterr = 0;
    int c;
    while ((c = getopt_long(argc, argv, "", longopts, NULL)) != -1) {
        switch (c) {
        case 't':
            if (!rs_cli_parse_int(optarg, 1, 1000000, &trials))
                return rs_cli_usage_error("bench calib", "--trials: '%s' is not an integer in [1, 1000000]", optarg);
            break;
        case 'c': csv = optarg; break;
        case 'p': plot = optarg; break;
        case 'q': o.quick = true; break;
        case 's':
            if (!rs_cli_parse_int(optarg, 0, 9007199254740991L, &seed))
                return rs_cli_usage_error("bench calib", "--seed: '%s' is not an integer in [0, 2^53)", optarg);
            have_seed = true;
            break;
        case 'S':
            if (!rs_cli_parse_int(optarg, 1, 100000000, &stress))
                return rs_cli_usage_error("bench calib", "--stress: '%s' is not an integer in [1, 1e8]", optarg);
            break;
        default: return rs_cli_usage_error("bench calib", "unknown or incomplete option '%s'", argv[optind - 1]);
        }
    }
    if (optind < argc) return rs_cli_usage_error("bench calib", "unexpected argument '%s'", argv[optind]);
    if (stress) return run_stress(stress, have_seed, (uint64_t)seed);

    o.trials = trials > 0 ? (int)trials : o.quick ? 3 : o.trials;
    o.seed = (uint64_t)seed;
    rs_bench_calib_row *rows = NULL;
    int Nrows = 0;
    rs_err err = {0};
    rs_status st = rs_bench_calib_run(&rows, &Nrows, &o, isatty(2) ? progress : NULL, NULL, &err);
    if (st != RS_OK) return rs_cli_fail("bench calib", st, &err);
    printf("roadside bench calib: %d trials per configuration, seed %ld; times are thread CPU us; errors RMS;\n"
           "crb = Cramer-Rao bound (RMS); fail = no pose or rotation > 5 deg or position > 20%% of the range\n\n",
           o.trials, seed);
    print_table(rows, Nrows);
    if (csv && st == RS_OK) st = rs_bench_calib_write_csv(csv, rows, Nrows, &err);
    if (plot && st == RS_OK) st = rs_bench_calib_plot(plot, rows, Nrows, &err);
    free(rows);
    if (st != RS_OK) return rs_cli_fail("bench calib", st, &err);
    return RS_EXIT_OK;
}

// roadside bench site -- reading and checking sites of N landmarks (bench/rs_bench_site.h).
// Parses, calls the library, prints.
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench/rs_bench_site.h"
#include "cli/rs_cli.h"
#include "core/rs_io.h"

static const char bench_site_usage[] =
    "usage: roadside bench site [--landmarks N[,N...]] [--picks P] [--unknown U] [--seed S] [--csv FILE]\n"
    "                           [--dir DIR]\n"
    "\n"
    "Writes a site of N landmarks (within 500 m of the origin, one camera, a repeated id and two\n"
    "landmarks at one position planted), then runs `roadside site check` on it in a child\n"
    "process: wall and CPU seconds, the child's peak resident memory, and whether exactly the\n"
    "two planted defects were reported. One row per N.\n"
    "\n"
    "  --landmarks N,...  site sizes (default 10000,100000,1000000; each 4..100000000)\n"
    "  --picks P          the camera's picks, of P distinct landmarks (default 4; at most N - 1)\n"
    "  --unknown U        with --picks: U more picks of ids no landmark has, each an error the\n"
    "                     check must report (default 0)\n"
    "  --seed S           seed (default 1)\n"
    "  --csv FILE         write the table as CSV (atomically)\n"
    "  --dir DIR          scratch folder (default: a new folder under $TMPDIR or /tmp, removed)\n"
    "\n"
    "Exit status: 0 ok, 1 failure (also when a planted defect was missed), 2 usage error.\n"
    "Figures: docs/benchmarks.md.\n";

enum { O_LANDMARKS = 3100, O_SEED, O_CSV, O_DIR, O_PICKS, O_UNKNOWN, MAX_SIZES = 16 };

int rs_cli_bench_site(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        fputs(bench_site_usage, stdout);
        return RS_EXIT_OK;
    }
    static const struct option longopts[] = {{"landmarks", required_argument, NULL, O_LANDMARKS},
                                             {"seed", required_argument, NULL, O_SEED},
                                             {"picks", required_argument, NULL, O_PICKS},
                                             {"unknown", required_argument, NULL, O_UNKNOWN},
                                             {"csv", required_argument, NULL, O_CSV},
                                             {"dir", required_argument, NULL, O_DIR},
                                             {NULL, 0, NULL, 0}};
    int sizes[MAX_SIZES] = {10000, 100000, 1000000}, Nsizes = 3;
    long seed = 1, picks = 0, unknown = 0;
    const char *csv = NULL, *dir = NULL;
    int c;
    optind = 1;
    opterr = 0;
    while ((c = getopt_long(argc, argv, "h", longopts, NULL)) != -1) {
        switch (c) {
        case O_LANDMARKS:
            if (!rs_cli_parse_int_list(optarg, 4, 100000000, sizes, MAX_SIZES, &Nsizes))
                return rs_cli_usage_error("bench site", "--landmarks: expected up to %d integers in [4, 1e8]",
                                          MAX_SIZES);
            break;
        case O_SEED:
            if (!rs_cli_parse_int(optarg, 0, 1000000000, &seed))
                return rs_cli_usage_error("bench site", "--seed: expected an integer >= 0");
            break;
        case O_PICKS:
            if (!rs_cli_parse_int(optarg, 0, 100000000, &picks))
                return rs_cli_usage_error("bench site", "--picks: expected an integer in [0, 1e8]");
            break;
        case O_UNKNOWN:
            if (!rs_cli_parse_int(optarg, 0, 100000000, &unknown))
                return rs_cli_usage_error("bench site", "--unknown: expected an integer in [0, 1e8]");
            break;
        case O_CSV: csv = optarg; break;
        case O_DIR: dir = optarg; break;
        default: return rs_cli_usage_error("bench site", "unknown option or missing value: %s", argv[optind - 1]);
        }
    }
    if (optind != argc) return rs_cli_usage_error("bench site", "unexpected argument '%s'", argv[optind]);
    char tmpl[4096];
    char *scratch = NULL;
    if (!dir && !(scratch = rs_cli_scratch_dir(tmpl, "bench-site"))) return RS_EXIT_FAIL;
    if (unknown && !picks) return rs_cli_usage_error("bench site", "--unknown needs --picks");
    printf("%10s %7s %7s %9s %8s %8s %8s %9s %9s %9s %7s %9s  %s\n", "landmarks", "picks", "unknown", "file_MiB",
           "write_s", "check_s", "cpu_s", "us/lmk", "peak_MiB", "B/lmk", "errors", "warnings", "found");
    char text[4096];
    int n = snprintf(
        text, sizeof text,
        "landmarks,picks,unknown,file_mib,write_s,check_s,check_cpu_s,us_per_landmark,peak_mib,peak_bytes_per_landmark,"
        "errors,warnings,found\n");
    rs_err err = {0};
    rs_status st = RS_OK;
    bool all_found = true;
    for (int k = 0; k < Nsizes && st == RS_OK; k++) {
        rs_bench_site_row r;
        st = rs_bench_site_run(&r, sizes[k], (int)picks, (int)unknown, (uint64_t)seed, dir ? dir : scratch, &err);
        if (st != RS_OK) break;
        const double us = 1e6 * r.check_s / r.Nlandmarks, bpl = r.peak_mib * 1048576.0 / r.Nlandmarks;
        printf("%10d %7d %7d %9.1f %8.2f %8.2f %8.2f %9.2f %9.1f %9.0f %7d %9d  %s\n", r.Nlandmarks, r.Npicks,
               r.Nunknown, r.file_mib, r.write_s, r.check_s, r.check_cpu_s, us, r.peak_mib, bpl, r.Nerrors, r.Nwarnings,
               r.found ? "yes" : "NO");
        fflush(stdout);
        all_found = all_found && r.found;
        if (n < (int)sizeof text)
            n += snprintf(text + n, sizeof text - (size_t)n, "%d,%d,%d,%.3f,%.4f,%.4f,%.4f,%.4f,%.3f,%.1f,%d,%d,%d\n",
                          r.Nlandmarks, r.Npicks, r.Nunknown, r.file_mib, r.write_s, r.check_s, r.check_cpu_s, us,
                          r.peak_mib, bpl, r.Nerrors, r.Nwarnings, r.found);
    }
    if (scratch) rs_io_remove_tree(scratch);
    if (st) return rs_cli_fail("bench site", st, &err);
    printf("check_s, cpu_s: `site check` in a child process (reading, checking, the report); peak_MiB: its\n"
           "peak resident memory (the file's text included); found: exactly the planted duplicate id\n"
           "(an error) and coincident pair (a warning), and each unknown id (an error), were reported.\n");
    if (csv && (st = rs_io_write_file(csv, text, (size_t)n, &err))) return rs_cli_fail("bench site", st, &err);
    if (!all_found) {
        fprintf(stderr, "roadside bench site: a planted defect was not reported (or something else was)\n");
        return RS_EXIT_FAIL;
    }
    return RS_EXIT_OK;
}

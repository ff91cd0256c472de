// roadside bench pick -- how long a re-solve of `roadside pick` takes after a click (pick/rs_pick.h
// on a simulated site: rs_calib_site_problem_init + rs_calib_solve + the predictions and the
// ground uncertainty of the view). Parses, calls the libraries, prints.
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli/rs_cli.h"
#include "core/rs_io.h"
#include "core/rs_rng.h"
#include "core/rs_stats.h"
#include "geo/rs_geo_raster.h"
#include "geo/rs_site.h"
#include "pick/rs_pick.h"
#include "sim/rs_simulate.h"

static const char bench_pick_usage[] =
    "usage: roadside bench pick [--landmarks N[,N...]] [--clicks K] [--seed S] [--csv FILE] [--dir DIR]\n"
    "                          [--ortho SOURCE]\n"
    "\n"
    "Simulates a one-camera site with about N landmarks seen (roadside site simulate), opens a\n"
    "`roadside pick` session on it and moves a random pick by a random sub-pixel amount K times:\n"
    "each move re-solves the camera as the page does (the problem built by calib/rs_calib_site.h,\n"
    "rs_calib_solve with calib's default options, every landmark's predicted pixel, the ground\n"
    "uncertainty of the view). Prints the median and 90th percentile of the re-solve's wall time\n"
    "per N (the target: under 50 ms for 30 landmarks).\n"
    "\n"
    "  --landmarks N,...  landmarks per camera (default 10,30,60; each 6..100)\n"
    "  --clicks K         re-solves per size (default 200)\n"
    "  --seed S           seed (default 1)\n"
    "  --csv FILE         write the table as CSV (atomically)\n"
    "  --dir DIR          scratch folder (default: a new folder under $TMPDIR or /tmp, removed)\n"
    "  --ortho SOURCE     also time an orthophoto as `pick --ortho` serves it, at the simulated\n"
    "                     site's origin: opening it, the tiles of a 1280x860 view of the whole\n"
    "                     image (its coarsest level) and of a view of its own pixels at its centre\n"
    "                     (level 0), and, for comparison, the whole image shrunk to 4096 px (what\n"
    "                     pick read before issue 41)\n"
    "\n"
    "Exit status: 0 ok, 1 failure, 2 usage error. Figures: docs/pick.md.\n";

enum { O_LANDMARKS = 3200, O_CLICKS, O_SEED, O_CSV, O_DIR, O_ORTHO, MAX_SIZES = 16 };

static double since_ms(const struct timespec *t0)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)(t.tv_sec - t0->tv_sec) * 1e3 + (double)(t.tv_nsec - t0->tv_nsec) * 1e-6;
}

// Reads the tiles of level L that a W x H screen-pixel view centred on full-resolution pixel
// (ci, cj) shows (1 screen px per cell of the level), as the page asks for them; returns the
// count, or -1 on an error (in err).
static int view_tiles(rs_geo_tiles *t, unsigned char *rgba, int L, double ci, double cj, int W, int H, rs_err *err)
{
    const rs_geo_grid *g = rs_geo_tiles_grid(t);
    const double span = (double)RS_GEO_TILE_PX * (1 << L);
    const int nx = (int)ceil(g->width / span), ny = (int)ceil(g->height / span);
    const int i0 = (int)fmax(0, floor((ci - W / 2.0 * (1 << L)) / span)),
              i1 = (int)fmin(nx - 1, floor((ci + W / 2.0 * (1 << L)) / span));
    const int j0 = (int)fmax(0, floor((cj - H / 2.0 * (1 << L)) / span)),
              j1 = (int)fmin(ny - 1, floor((cj + H / 2.0 * (1 << L)) / span));
    int n = 0;
    for (int j = j0; j <= j1; j++)
        for (int i = i0; i <= i1; i++, n++)
            if (rs_geo_tiles_read(t, L, i, j, rgba, err)) return -1;
    return n;
}

// The orthophoto's figures (see the usage).
static rs_status bench_ortho(const char *path, const char *site_dir, rs_err *err)
{
    rs_site *site = NULL;
    rs_status st = rs_site_load_for_picking(&site, site_dir, err);
    if (st) return st;
    struct timespec t0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    rs_geo_tiles *t = NULL;
    unsigned char *rgba = malloc((size_t)RS_GEO_TILE_PX * RS_GEO_TILE_PX * 4);
    st = rgba ? rs_geo_tiles_open(&t, path, &site->origin, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    const double open_ms = since_ms(&t0);
    if (!st) {
        const rs_geo_grid *g = rs_geo_tiles_grid(t);
        const int L = rs_geo_tiles_levels(t) - 1;
        printf("orthophoto %s: %dx%d cells of %.3f m%s, %d levels; opened in %.1f ms\n", path, g->width, g->height,
               g->cell_m, rs_geo_tiles_warped(t) ? " (reprojected)" : "", L + 1, open_ms);
        clock_gettime(CLOCK_MONOTONIC, &t0);
        const int n_all = view_tiles(t, rgba, L, g->width / 2.0, g->height / 2.0, 1280, 860, err);
        const double all_ms = since_ms(&t0);
        clock_gettime(CLOCK_MONOTONIC, &t0);
        const int n_full = n_all < 0 ? -1 : view_tiles(t, rgba, 0, g->width / 2.0, g->height / 2.0, 1280, 860, err);
        const double full_ms = since_ms(&t0);
        if (n_all < 0 || n_full < 0)
            st = err->status ? err->status : RS_ERR_EXTERNAL;
        else
            printf("a 1280x860 view: the whole image (level %d) %d tiles in %.1f ms; its own pixels (level 0) %d tiles "
                   "in %.1f ms\n",
                   L, n_all, all_ms, n_full, full_ms);
    }
    rs_geo_tiles_close(t);
    free(rgba);
    if (!st) {
        rs_geo_ortho o = {0};
        clock_gettime(CLOCK_MONOTONIC, &t0);
        st = rs_geo_ortho_read(&o, path, &site->origin, 4096, err);
        if (!st)
            printf("before issue 41: the whole image shrunk to %dx%d (cells of %.3f m) in %.1f ms\n", o.grid.width,
                   o.grid.height, o.grid.cell_m, since_ms(&t0));
        rs_geo_ortho_free(&o);
    }
    rs_site_free(site);
    return st;
}

// The picked landmarks' ids and pixels, from the session's state.
static rs_status one_size(double *median_ms, double *p90_ms, int *Npicks, int *Nfailed, const char *dir, int N, int K,
                          uint64_t seed, rs_err *err)
{
    rs_simulate_site_options o;
    rs_simulate_site_options_default(&o);
    o.Ncameras = 1;
    o.landmarks_per_camera = N;
    o.seed = seed;
    o.force = true;
    rs_status st = rs_simulate_site(dir, &o, err);
    if (st) return st;
    rs_pick_session *s = NULL;
    if ((st = rs_pick_session_open(&s, dir, "cam1", err))) return st;
    *Npicks = rs_pick_count(s);
    // the ids and pixels of the picks, from the state the page gets
    char *text = rs_pick_state_json(s);
    double *ms = malloc(sizeof(double) * (size_t)K);
    char(*ids)[64] = malloc(sizeof *ids * (size_t)(*Npicks > 0 ? *Npicks : 1));
    double(*q)[2] = malloc(sizeof *q * (size_t)(*Npicks > 0 ? *Npicks : 1));
    int n = 0;
    if (!text || !ms || !ids || !q) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (const char *p = text; !st && p && (p = strstr(p, "{\"id\":\"")); p++) {
        char id[64];
        double u, v;
        const char *pk = strstr(p, "\"pick_px\":");
        const char *next = strstr(p + 1, "{\"id\":\"");
        if (sscanf(p, "{\"id\":\"%63[^\"]\"", id) != 1 || !pk || (next && pk > next)) continue;
        if (sscanf(pk, "\"pick_px\":[%lf,%lf]", &u, &v) == 2 && n < *Npicks) {
            snprintf(ids[n], sizeof ids[n], "%s", id);
            q[n][0] = u, q[n][1] = v;
            n++;
        }
    }
    rs_rng rng;
    rs_rng_seed(&rng, seed);
    *Nfailed = 0;
    for (int k = 0; !st && k < K && n > 0; k++) {
        const int i = (int)(rs_rng_uniform(&rng) * n) % n;
        const double du = rs_rng_uniform(&rng) - 0.5, dv = rs_rng_uniform(&rng) - 0.5;
        if ((st = rs_pick_set(s, ids[i], q[i][0] + du, q[i][1] + dv, err))) break;
        ms[k] = rs_pick_last_solve_ms(s);
        char *state = rs_pick_state_json(s);
        if (state && strstr(state, "\"solve\":{\"ok\":false")) (*Nfailed)++;
        free(state);
    }
    if (!st && n == 0) st = rs_err_set(err, RS_ERR_DEGENERATE, "%s: no pick found in the session's state", dir);
    if (!st) {
        rs_stats_sort(ms, K);
        *median_ms = rs_stats_median_sorted(ms, K);
        *p90_ms = rs_stats_quantile_sorted(ms, K, 0.9);
    }
    free(text);
    free(ms);
    free(ids);
    free(q);
    rs_pick_session_free(s);
    return st;
}

int rs_cli_bench_pick(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        fputs(bench_pick_usage, stdout);
        return RS_EXIT_OK;
    }
    static const struct option longopts[] = {{"landmarks", required_argument, NULL, O_LANDMARKS},
                                             {"clicks", required_argument, NULL, O_CLICKS},
                                             {"seed", required_argument, NULL, O_SEED},
                                             {"csv", required_argument, NULL, O_CSV},
                                             {"dir", required_argument, NULL, O_DIR},
                                             {"ortho", required_argument, NULL, O_ORTHO},
                                             {NULL, 0, NULL, 0}};
    int sizes[MAX_SIZES] = {10, 30, 60}, Nsizes = 3;
    long seed = 1, K = 200;
    const char *csv = NULL, *dir = NULL, *ortho = NULL;
    int c;
    optind = 1;
    opterr = 0;
    while ((c = getopt_long(argc, argv, "h", longopts, NULL)) != -1) {
        switch (c) {
        case O_LANDMARKS:
            if (!rs_cli_parse_int_list(optarg, 6, 100, sizes, MAX_SIZES, &Nsizes))
                return rs_cli_usage_error("bench pick", "--landmarks: expected up to %d integers in [6, 100]",
                                          MAX_SIZES);
            break;
        case O_CLICKS:
            if (!rs_cli_parse_int(optarg, 1, 100000, &K))
                return rs_cli_usage_error("bench pick", "--clicks: expected an integer in [1, 100000]");
            break;
        case O_SEED:
            if (!rs_cli_parse_int(optarg, 0, 1000000000, &seed))
                return rs_cli_usage_error("bench pick", "--seed: expected an integer >= 0");
            break;
        case O_CSV: csv = optarg; break;
        case O_DIR: dir = optarg; break;
        case O_ORTHO: ortho = optarg; break;
        default: return rs_cli_usage_error("bench pick", "unknown option or missing value: %s", argv[optind - 1]);
        }
    }
    if (optind != argc) return rs_cli_usage_error("bench pick", "unexpected argument '%s'", argv[optind]);
    char tmpl[4096];
    char *scratch = NULL;
    if (!dir && !(scratch = rs_cli_scratch_dir(tmpl, "bench-pick"))) return RS_EXIT_FAIL;
    printf("%10s %6s %7s %10s %10s %8s\n", "landmarks", "picks", "clicks", "median_ms", "p90_ms", "failed");
    char text[4096];
    int n = snprintf(text, sizeof text, "landmarks,picks,clicks,median_ms,p90_ms,failed\n");
    rs_err err = {0};
    rs_status st = RS_OK;
    char site[4200] = "";
    for (int k = 0; k < Nsizes && st == RS_OK; k++) {
        snprintf(site, sizeof site, "%s/site-%d", dir ? dir : scratch, sizes[k]);
        double med = NAN, p90 = NAN;
        int Npicks = 0, Nfailed = 0;
        if ((st = one_size(&med, &p90, &Npicks, &Nfailed, site, sizes[k], (int)K, (uint64_t)seed, &err))) break;
        printf("%10d %6d %7ld %10.2f %10.2f %8d\n", sizes[k], Npicks, K, med, p90, Nfailed);
        fflush(stdout);
        if (n < (int)sizeof text)
            n += snprintf(text + n, sizeof text - (size_t)n, "%d,%d,%ld,%.4f,%.4f,%d\n", sizes[k], Npicks, K, med, p90,
                          Nfailed);
    }
    if (!st && ortho) st = bench_ortho(ortho, site, &err);
    if (scratch) rs_io_remove_tree(scratch);
    if (st) return rs_cli_fail("bench pick", st, &err);
    printf("a re-solve: the problem built from the site, rs_calib_solve (calib's defaults: RANSAC, the robust\n"
           "adjustment, the noise model, covariance), every landmark projected, the view's ground uncertainty\n"
           "(12 x 7 samples); failed: re-solves that did not give a pose.\n");
    if (csv && (st = rs_io_write_file(csv, text, (size_t)n, &err))) return rs_cli_fail("bench pick", st, &err);
    return RS_EXIT_OK;
}

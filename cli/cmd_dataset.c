// roadside dataset -- look at a dataset before training on it: `stats` (what it holds: splits,
// cameras, conditions, visibility, vehicles near the junction) and `view` (contact sheets with
// the labels drawn). Counting and drawing are synth/'s (rs_synth_dataset_stats,
// rs_synth_dataset_view); this file parses and prints.
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/rs_cli.h"
#include "synth/dataset/rs_synth_dataset.h"

static const char dataset_usage[] =
    "usage: roadside dataset stats DATASET [--site SITE] [--radius M]\n"
    "       roadside dataset view DATASET -o DIR [--max N] [--per-page P] [--columns C]\n"
    "                             [--tile-width PX]\n"
    "\n"
    "What a dataset made by `roadside synth` holds (docs/labels.md): images and labels per\n"
    "split, images per camera, weather and time of day, the labels' visibility, and the share\n"
    "of labelled vehicles whose bottom centre (bottom_center_enu_m) is within M metres\n"
    "(default 15) of the junction's centre: the mean of SITE's junction lanes (lanes.geojson,\n"
    "kind \"junction\"), or the site's ENU origin without --site.\n"
    "\n"
    "view: contact sheets of the first N images (default 48; 0: all; splits in name order):\n"
    "DIR/page_001.png ... (P images a page, default 12, in C columns, default 4; tiles at most\n"
    "PX wide, default 480), DIR/index.html (pages, legend, a table of the images) and\n"
    "DIR/index.json. Drawn on each image: footprint box (green), body box (orange), visible box\n"
    "(blue), 3D box edges (yellow), bottom centre (magenta dot), visibility (the number above\n"
    "the footprint box).\n"
    "Exit status: 0 done, 1 failed, 2 usage error.\n";

static void print_counts(const char *what, const rs_synth_dataset_count *c, int N, int total)
{
    printf("%-12s", what);
    for (int i = 0; i < N; i++)
        printf("%s %s %d (%.0f %%)", i ? "," : "", c[i].value, c[i].images, total ? 100.0 * c[i].images / total : 0.0);
    printf("\n");
}

static int dataset_stats(int argc, char **argv)
{
    const char *ds = NULL, *site = NULL;
    double radius = 15;
    for (int i = 2; i < argc; i++) {
        if (!strcmp(argv[i], "--site") && i + 1 < argc)
            site = argv[++i];
        else if (!strcmp(argv[i], "--radius") && i + 1 < argc) {
            if (!rs_cli_parse_double(argv[++i], &radius) || radius <= 0)
                return rs_cli_usage_error("dataset stats", "--radius: expected a positive number of metres");
        } else if (argv[i][0] == '-')
            return rs_cli_usage_error("dataset stats", "unknown option or missing value: %s", argv[i]);
        else if (ds)
            return rs_cli_usage_error("dataset stats", "one DATASET expected");
        else
            ds = argv[i];
    }
    if (!ds) return rs_cli_usage_error("dataset stats", "expected DATASET");
    rs_err err = {0};
    double centre[2] = {0, 0};
    if (site) {
        rs_status st = rs_synth_junction_centre(centre, site, &err);
        if (st) return rs_cli_fail("dataset stats", st, &err);
    }
    rs_synth_dataset_stats_result *r = malloc(sizeof(*r));
    if (!r) return rs_cli_fail("dataset stats", RS_ERR_NOMEM, NULL);
    rs_status st = rs_synth_dataset_stats(r, ds, centre, radius, &err);
    if (st) {
        free(r);
        return rs_cli_fail("dataset stats", st, &err);
    }
    printf("dataset:     %s: %d images, %d labels (%.1f per image)\n", ds, r->images, r->labels,
           r->images ? (double)r->labels / r->images : 0.0);
    for (int s = 0; s < r->Nsplits; s++)
        printf("split:       %s: %d images, %d labels\n", r->splits[s].value, r->splits[s].images, r->splits[s].labels);
    print_counts("cameras:", r->cameras, r->Ncameras, r->images);
    print_counts("weather:", r->weather, r->Nweather, r->images);
    print_counts("time:", r->time_of_day, r->Ntime_of_day, r->images);
    printf("conditions: ");
    for (int i = 0; i < r->Nconditions; i++)
        printf("%s %s: %d images, %d labels", i ? ";" : "", r->conditions[i].value, r->conditions[i].images,
               r->conditions[i].labels);
    printf("\n");
    printf("visibility:  ");
    for (int b = 0; b < 10; b++)
        printf("%s[%.1f,%.1f%c %d", b ? ", " : "", b / 10.0, (b + 1) / 10.0, b == 9 ? ']' : ')', r->visibility_hist[b]);
    printf("; %d labels with no visible pixel\n", r->invisible);
    printf(
        "junction:    %d of %d labelled vehicles (%.1f %%) within %g m of (E %.2f, N %.2f)%s; mean distance %.1f m\n",
        r->labels_near, r->labels_located, r->labels_located ? 100.0 * r->labels_near / r->labels_located : 0.0, radius,
        centre[0], centre[1], site ? " (the junction lanes' centre)" : " (the ENU origin)",
        r->labels_located ? r->distance_sum_m / r->labels_located : 0.0);
    if (r->looks_found)
        printf("look:        the camera's look estimated per background, %s\n",
               r->looks_applied ? "applied to the vehicles" : "NOT applied (--no-appearance)");
    for (int i = 0; i < r->Nlooks; i++) {
        const rs_synth_appearance *a = &r->looks[i].look;
        if (!r->looks[i].ok)
            printf("  %s: not estimated: %s\n", r->looks[i].background, r->looks[i].why);
        else
            printf("  %s: noise variance %.3g + %.3g v (sigma %.4f at v 0.5), blur %.2f px, jpeg quality %d%s, "
                   "blockiness %.3f, gain %.3f %.3f %.3f\n",
                   r->looks[i].background, a->noise_a, a->noise_b, rs_synth_appearance_noise_sigma(a, 0.5),
                   a->blur_sigma_px, a->jpeg_quality, a->jpeg_quality && !a->jpeg_exact ? " (nearest IJG)" : "",
                   a->blockiness, a->gain[0], a->gain[1], a->gain[2]);
    }
    free(r);
    return RS_EXIT_OK;
}

static int dataset_view(int argc, char **argv)
{
    const char *ds = NULL, *out = NULL;
    rs_synth_view_options opt;
    rs_synth_view_options_default(&opt);
    for (int i = 2; i < argc; i++) {
        long v = 0;
        if ((!strcmp(argv[i], "-o") || !strcmp(argv[i], "--output")) && i + 1 < argc)
            out = argv[++i];
        else if (!strcmp(argv[i], "--max") && i + 1 < argc) {
            if (!rs_cli_parse_int(argv[++i], 0, 1000000000, &v))
                return rs_cli_usage_error("dataset view", "--max: expected a count >= 0 (0: all)");
            opt.max_images = (int)v;
        } else if (!strcmp(argv[i], "--per-page") && i + 1 < argc) {
            if (!rs_cli_parse_int(argv[++i], 1, 1000, &v))
                return rs_cli_usage_error("dataset view", "--per-page: expected 1..1000");
            opt.per_page = (int)v;
        } else if (!strcmp(argv[i], "--columns") && i + 1 < argc) {
            if (!rs_cli_parse_int(argv[++i], 1, 100, &v))
                return rs_cli_usage_error("dataset view", "--columns: expected 1..100");
            opt.columns = (int)v;
        } else if (!strcmp(argv[i], "--tile-width") && i + 1 < argc) {
            if (!rs_cli_parse_int(argv[++i], 16, 8192, &v))
                return rs_cli_usage_error("dataset view", "--tile-width: expected 16..8192 pixels");
            opt.max_tile_width_px = (int)v;
        } else if (argv[i][0] == '-')
            return rs_cli_usage_error("dataset view", "unknown option or missing value: %s", argv[i]);
        else if (ds)
            return rs_cli_usage_error("dataset view", "one DATASET expected");
        else
            ds = argv[i];
    }
    if (!ds) return rs_cli_usage_error("dataset view", "expected DATASET");
    if (!out) return rs_cli_usage_error("dataset view", "expected -o DIR");
    rs_err err = {0};
    rs_synth_view_summary sum;
    rs_status st = rs_synth_dataset_view(&sum, ds, out, &opt, &err);
    if (st) return rs_cli_fail("dataset view", st, &err);
    printf("view:        %d images, %d labels on %d pages (tiles %dx%d, scale %.3g)\n", sum.images, sum.labels,
           sum.pages, sum.tile_width, sum.tile_height, sum.scale);
    printf("pages:       %s/index.html  (page_001.png ... page_%03d.png, index.json)\n", out, sum.pages);
    return RS_EXIT_OK;
}

int rs_cli_dataset(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv) || argc < 2) {
        fputs(dataset_usage, argc < 2 ? stderr : stdout);
        return argc < 2 ? RS_EXIT_USAGE : RS_EXIT_OK;
    }
    if (!strcmp(argv[1], "stats")) return dataset_stats(argc, argv);
    if (!strcmp(argv[1], "view")) return dataset_view(argc, argv);
    return rs_cli_usage_error("dataset", "unknown subcommand '%s' (stats, view)", argv[1]);
}

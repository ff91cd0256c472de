// fuzz_import_points.c -- libFuzzer harness of `site import`'s point-file reader
// (rs_site__import_read, geo/internal/rs_site_import_points.h, in geo/rs_site_import_read.c): the
// input is written to a per-process temporary file and read back, as points.json when its first
// non-blank byte is '{' and as points.csv otherwise (the name picks the reader). Corpus:
// tests/fuzz/corpus/import_points/.
//
// Held to the header's contract, a breach aborting: points that read are at least 4, each with a
// unique id that follows rs_io_name_problem, a finite position (a latitude within [-90, 90] and a
// longitude within [-180, 180] when geographic), finite pixels, a height and a sigma_px each NAN or
// finite, and a line from 1; a failed read says why.
#include <ctype.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_io.h"
#include "geo/internal/rs_site_import_points.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static char *dir, *json_path, *csv_path; // the per-process folder and its two file names

static void breach(const char *what, const char *detail)
{
    fprintf(stderr, "fuzz_import_points: contract broken: %s%s%s\n", what, detail ? ": " : "", detail ? detail : "");
    abort();
}

static void remove_dir(void)
{
    if (dir) rs_io_remove_tree(dir);
    free(dir), free(json_path), free(csv_path);
    dir = json_path = csv_path = NULL;
}

static void make_dir(void)
{
    const char *tmp = getenv("TMPDIR");
    dir = rs_io_join(tmp && *tmp ? tmp : "/tmp", "roadside-fuzz-XXXXXX");
    if (!dir || !mkdtemp(dir)) breach("cannot make a temporary folder", dir);
    atexit(remove_dir);
    json_path = rs_io_join(dir, "points.json");
    csv_path = rs_io_join(dir, "points.csv");
    if (!json_path || !csv_path) breach("out of memory", NULL);
}

static void check_points(const rs_site__import_points *pts)
{
    if (pts->N < 4) breach("fewer than 4 points read", NULL);
    for (int i = 0; i < pts->N; i++) {
        const rs_site__import_point *p = &pts->points[i];
        if (!p->id || rs_io_name_problem(p->id)) breach("an id that breaks the rule for ids", p->id);
        for (int k = 0; k < i; k++)
            if (!strcmp(pts->points[k].id, p->id)) breach("a repeated id", p->id);
        if (!(isfinite(p->x) && isfinite(p->y) && isfinite(p->q_px[0]) && isfinite(p->q_px[1])))
            breach("a non-finite position or pixel", p->id);
        if (pts->geographic && !(fabs(p->y) <= 90 && fabs(p->x) <= 180))
            breach("a latitude or longitude out of range", p->id);
        if (isinf(p->h_m) || isinf(p->sigma_px) || p->line < 1)
            breach("an infinite height or sigma, or no line", p->id);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!dir) make_dir();
    size_t i = 0;
    while (i < size && isspace(data[i])) i++;
    const char *path = i < size && data[i] == '{' ? json_path : csv_path;
    // A scratch input rewritten for every run: plain stdio (an atomic write would fsync each time).
    FILE *f = fopen(path, "wb");
    if (!f || (size && fwrite(data, 1, size, f) != size) || fclose(f) != 0) breach("cannot write", path);

    rs_site__import_points pts;
    rs_err err = {0};
    if (rs_site__import_read(&pts, path, &err) == RS_OK)
        check_points(&pts);
    else if (!err.msg[0])
        breach("a failed read without a message", NULL);
    rs_site__import_points_free(&pts);
    return 0;
}

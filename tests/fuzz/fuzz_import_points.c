// fuzz_import_points.c -- libFuzzer harness of `site import`'s point-file reader
// (rs_site__import_read, geo/internal/rs_site_import_points.h, in geo/rs_site_import_read.c): the
// input is written to a per-process temporary file (tests/fuzz/fuzz_scratch.h) and read back, as
// points.json when its first non-blank byte is '{' and as points.csv otherwise (the name picks the
// reader). Corpus: tests/fuzz/corpus/import_points/.
//
// Held to the header's contract, a breach aborting: points that read are at least 4, each with a
// unique id that follows rs_io_name_problem, a finite position (a latitude within [-90, 90] and a
// longitude within [-180, 180] when geographic), finite pixels, a height and a sigma_px each NAN or
// finite, and a line from 1; a failed read says why.
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "core/rs_io.h"
#include "fuzz_scratch.h"
#include "geo/internal/rs_site_import_points.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void breach(const char *what, const char *detail) { fuzz_breach("fuzz_import_points", what, detail); }

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
    const char *path = fuzz_scratch_write("fuzz_import_points", data, size, "points.json", "points.csv");
    rs_site__import_points pts;
    rs_err err = {0};
    if (rs_site__import_read(&pts, path, &err) == RS_OK)
        check_points(&pts);
    else if (!err.msg[0])
        breach("a failed read without a message", NULL);
    rs_site__import_points_free(&pts);
    return 0;
}

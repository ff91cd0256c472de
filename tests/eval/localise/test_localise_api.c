// The localise library through its C API (eval/localise/rs_localise.h): the box's ground pixel
// against hand-computed values, the located-detections CSV written and read back (values to
// 1e-12 relative: 15 significant digits; unknown time and lat/lon stay NaN; a camera id with a
// comma and a quote survives), the three extensions, and the reader's messages (file, line, field).
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "eval/localise/rs_localise.h"
#include "tests/common/rs_test.h"

static bool near(double a, double b) { return (isnan(a) && isnan(b)) || fabs(a - b) <= 1e-12 * fmax(1, fabs(b)); }

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    fputs(text, f);
    fclose(f);
}

int main(void)
{
    // the ground pixel of a box [10, 20, 30, 40]
    const double b[4] = {10, 20, 30, 40};
    double q[2];
    rs_localise_box_point(q, b, RS_LOCALISE_POINT_CENTER, 0.35);
    CHECK(q[0] == 25 && q[1] == 40, "center (%g, %g), expected (25, 40)", q[0], q[1]);
    rs_localise_box_point(q, b, RS_LOCALISE_POINT_BOTTOM, 0.35);
    CHECK(q[0] == 25 && q[1] == 60, "bottom (%g, %g), expected (25, 60)", q[0], q[1]);
    rs_localise_box_point(q, b, RS_LOCALISE_POINT_SHIFT, 0.35);
    CHECK(q[0] == 25 && fabs(q[1] - 54) < 1e-12, "shift (%g, %g), expected (25, 54)", q[0], q[1]);
    rs_localise_point pt;
    CHECK(rs_localise_point_parse(&pt, "bottom") && pt == RS_LOCALISE_POINT_BOTTOM, "parse bottom");
    CHECK(!rs_localise_point_parse(&pt, "top"), "parse top: refused");

    char dir[] = "/tmp/roadside-localise-api-XXXXXX";
    if (!mkdtemp(dir)) return 1;
    char csv[128], jsonl[128], bad[128];
    snprintf(csv, sizeof csv, "%s/a.csv", dir);
    snprintf(jsonl, sizeof jsonl, "%s/a.jsonl", dir);
    snprintf(bad, sizeof bad, "%s/a.txt", dir);
    rs_localise_row rows[2] = {{.image_id = 7,
                                .camera = "cam,\"1\"",
                                .frame = -1,
                                .time_s = NAN,
                                .category_id = 3,
                                .score = 0.25,
                                .u_px = 1234.567890123,
                                .v_px = 987.654321,
                                .e_m = -12.3456789012345,
                                .n_m = 45.678901234567,
                                .u_m = 0.125,
                                .lat_deg = NAN,
                                .lon_deg = NAN,
                                .sigma_e_m = 0.31,
                                .sigma_n_m = 0.42,
                                .cov_en_m2 = -0.011},
                               {.image_id = 8,
                                .camera = "cam2",
                                .frame = 12,
                                .time_s = 1.2,
                                .category_id = 1,
                                .score = 1,
                                .u_px = 1,
                                .v_px = 2,
                                .e_m = 3,
                                .n_m = 4,
                                .u_m = 5,
                                .lat_deg = 48.137412345678,
                                .lon_deg = 11.575512345678,
                                .sigma_e_m = 0.1,
                                .sigma_n_m = 0.2,
                                .cov_en_m2 = 0.003}};
    rs_err err = {0};
    CHECK(rs_localise_write(csv, rows, 2, &err) == RS_OK, "write csv: %s", err.msg);
    CHECK(rs_localise_write(jsonl, rows, 2, &err) == RS_OK, "write jsonl: %s", err.msg);
    CHECK(rs_localise_write(bad, rows, 2, &err) == RS_ERR_USAGE && access(bad, F_OK) != 0,
          "write .txt: refused, nothing written: %s", err.msg);
    rs_localise_row *back = NULL;
    size_t N = 0;
    CHECK(rs_localise_read(&back, &N, csv, &err) == RS_OK && N == 2, "read back: %s (N %zu)", err.msg, N);
    for (size_t i = 0; back && i < N; i++) {
        const rs_localise_row *a = &rows[i], *r = &back[i];
        CHECK(a->image_id == r->image_id && a->frame == r->frame && a->category_id == r->category_id &&
                  !strcmp(a->camera, r->camera),
              "row %zu: ids or camera ('%s')", i, r->camera);
        const double x[] = {a->time_s, a->score,   a->u_px,    a->v_px,      a->e_m,       a->n_m,
                            a->u_m,    a->lat_deg, a->lon_deg, a->sigma_e_m, a->sigma_n_m, a->cov_en_m2};
        const double y[] = {r->time_s, r->score,   r->u_px,    r->v_px,      r->e_m,       r->n_m,
                            r->u_m,    r->lat_deg, r->lon_deg, r->sigma_e_m, r->sigma_n_m, r->cov_en_m2};
        for (int k = 0; k < 12; k++)
            CHECK(near(y[k], x[k]), "row %zu, number %d: %.17g, expected %.17g", i, k, y[k], x[k]);
    }
    free(back);

    // the reader's messages
    write_text(csv, "image_id,camera\n1,cam1\n");
    CHECK(rs_localise_read(&back, &N, csv, &err) == RS_ERR_PARSE && strstr(err.msg, "a.csv:1: header"),
          "wrong header: %s", err.msg);
    write_text(csv, RS_LOCALISE_CSV_HEADER "\n1,cam1,-1,,1,1,2,3,4,5,6,,,0.1,0.1,0\n"
                                           "2,cam1,-1,,1,1,2,3,x,5,6,,,0.1,0.1,0\n");
    CHECK(rs_localise_read(&back, &N, csv, &err) == RS_ERR_PARSE && strstr(err.msg, "a.csv:3: e_m: 'x'") && !back,
          "bad number: %s", err.msg);
    write_text(csv, RS_LOCALISE_CSV_HEADER "\n1,cam1,-1,,1,1,2,3,4,5,6,,,0.1,0.1\n");
    CHECK(rs_localise_read(&back, &N, csv, &err) == RS_ERR_PARSE && strstr(err.msg, "a.csv:2: cov_en_m2: missing"),
          "short row: %s", err.msg);
    write_text(csv, RS_LOCALISE_CSV_HEADER "\n1,cam1,-1,,1,1,2,3,4,5,nan,,,0.1,0.1,0\n");
    CHECK(rs_localise_read(&back, &N, csv, &err) == RS_ERR_PARSE && strstr(err.msg, "a.csv:2: u_m"), "NaN: %s",
          err.msg);
    remove(csv);
    remove(jsonl);
    rmdir(dir);
    return rs_test_end("localise_api");
}

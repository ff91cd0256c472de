// tests/synth/povray/test_canvas_map.c -- issue 18's speed bar: rs_synth_canvas_map interpolates
// mrcal_unproject between the nodes of a grid (every RS_SYNTH_CANVAS_MAP_STEP pixels) instead
// of unprojecting every pixel (0.28 s at 720x480 in every dataset worker). The oracle is what
// the map was before: mrcal_unproject of every pixel, then the canvas pinhole, in double.
//
// For each lens below, on every pixel of the image:
//   - the map agrees with the oracle within 0.01 canvas px (the bound the dataset relies on;
//     the largest difference is printed: about 5e-5 px, float rounding included, for the
//     demo's OPENCV8 lenses);
//   - a pixel the oracle gives no direction (behind the camera, not finite) is (-1e6, -1e6) in
//     the map, and a pixel with one is not;
//   - no value is NaN.
// Lenses: the demo site's cam1 (OPENCV8, 720x480, as `roadside calib` gave it), the same at
// canvas scale 2, a pinhole on a scale-1.5 canvas (no distortion: the map is affine), a strong
// barrel OPENCV4 (k1 = -0.3) and an OPENCV4 that folds back just outside its image (k1 = -0.45:
// the grid's nodes past the fold are unprojected to the wrong side or not at all, and the
// pixels next to them must be caught by the check and unprojected on their own), and an
// odd size (not a multiple of the step). Fisheyes (issue 38: CAHVORE at linearity 0, on the
// fisheye canvas; the oracle is then rs_lens_unproject, mrcal 2.2 has no CAHVORE unprojection,
// and the equidistant canvas written out here): 1280x960 equidistant f = 340, Kannala-Brandt
// k1 0.02, k2 -0.004, and f = 170 whose 180-degree circle lies inside the image (the pixels
// outside it have no direction: (-1e6, -1e6)).
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <mrcal/mrcal.h>

#include "core/rs_lens.h"
#include "synth/povray/rs_synth_camera.h"
#include "tests/common/rs_test.h"

#define TOL_PX 0.01

typedef struct {
    const char *name;
    mrcal_lensmodel_type_t type;
    double intrinsics[12];
    int width, height;
    double scale;
    bool some_without_direction; // a fisheye whose circle lies inside the image
} lens_case;

// The oracle's canvas pixel of direction v: the pinhole, or the equidistant fisheye canvas
// (docs/povray.md, "Fisheye lenses"); false when the direction is unusable.
static bool oracle_pixel(double q[2], const rs_synth_canvas *c, const mrcal_point3_t *v)
{
    if (!isfinite(v->x) || !isfinite(v->y) || !isfinite(v->z)) return false;
    if (c->fisheye_deg > 0) {
        const double s = hypot(v->x, v->y), theta = atan2(s, v->z);
        q[0] = c->fxycxy[0] * (s > 0 ? theta * v->x / s : 0) + c->fxycxy[2];
        q[1] = c->fxycxy[1] * (s > 0 ? theta * v->y / s : 0) + c->fxycxy[3];
        return true;
    }
    if (!(v->z > 0)) return false;
    q[0] = c->fxycxy[0] * v->x / v->z + c->fxycxy[2];
    q[1] = c->fxycxy[1] * v->y / v->z + c->fxycxy[3];
    return true;
}

// Every row_stride-th row of each image is checked (1: every pixel; the sanitizer build checks
// every 3rd, where the oracle's per-pixel unprojection costs most of the test's time).
static int row_stride = 1;

// Checks one lens; prints the largest difference.
static void check_lens(const lens_case *lc)
{
    const mrcal_lensmodel_t lm = {.type = lc->type};
    rs_synth_canvas canvas;
    rs_err e = {0};
    rs_status st = rs_synth_canvas_for_lens(&canvas, &lm, lc->intrinsics, lc->width, lc->height, lc->scale, &e);
    CHECK(st == RS_OK, "%s: canvas: %s", lc->name, e.msg);
    if (st) return;
    float *map = NULL;
    st = rs_synth_canvas_map(&map, &canvas, &lm, lc->intrinsics, lc->width, lc->height, &e);
    CHECK(st == RS_OK && map, "%s: map: %s", lc->name, e.msg);
    if (st) return;
    const size_t W = (size_t)lc->width, Nrows = ((size_t)lc->height + (size_t)row_stride - 1) / (size_t)row_stride,
                 N = W * Nrows;
    mrcal_point2_t *q = malloc(N * sizeof(*q));
    mrcal_point3_t *v = malloc(N * sizeof(*v));
    if (!q || !v) {
        CHECK(0, "out of memory");
        free(q), free(v), free(map);
        return;
    }
    for (size_t i = 0; i < N; i++)
        q[i] = (mrcal_point2_t){.x = (double)(i % W), .y = (double)(i / W * (size_t)row_stride)};
    const bool cahvore = lc->type == MRCAL_LENSMODEL_CAHVORE;
    CHECK(cahvore ? rs_lens_unproject(v, q, (int)N, &lm, lc->intrinsics)
                  : mrcal_unproject(v, q, (int)N, &lm, lc->intrinsics),
          "%s: oracle: unprojection failed", lc->name);
    double worst = 0;
    size_t worst_i = 0, Nvalid = 0, Nbad = 0;
    for (size_t i = 0; i < N; i++) {
        const size_t at = (size_t)q[i].y * W + i % W; // the pixel's index in the map
        const float mx = map[2 * at], my = map[2 * at + 1];
        if (!isfinite(mx) || !isfinite(my)) {
            if (Nbad++ < 5) CHECK(0, "%s: pixel (%g, %g): map not finite", lc->name, q[i].x, q[i].y);
            continue;
        }
        double o[2];
        const bool valid = oracle_pixel(o, &canvas, &v[i]);
        if (!valid) {
            if (!(mx == -1e6f && my == -1e6f) && Nbad++ < 5)
                CHECK(0, "%s: pixel (%g, %g): no direction, but the map gives (%g, %g)", lc->name, q[i].x, q[i].y, mx,
                      my);
            continue;
        }
        Nvalid++;
        const double d = hypot(mx - o[0], my - o[1]);
        if (!(d <= worst)) worst = d, worst_i = i;
    }
    CHECK(Nbad == 0, "%s: %zu pixel(s) wrong (first 5 above)", lc->name, Nbad);
    CHECK(lc->some_without_direction ? Nvalid < N && Nvalid > N / 2 : Nvalid == N,
          "%s: %zu of %zu pixels have a direction (expected %s)", lc->name, Nvalid, N,
          lc->some_without_direction ? "most, not all" : "all");
    CHECK(worst <= TOL_PX, "%s: map differs from per-pixel mrcal_unproject by %.3g px at (%g, %g) (bound %g)", lc->name,
          worst, q[worst_i].x, q[worst_i].y, TOL_PX);
    printf("%-28s %4dx%-4d canvas %4dx%-4d scale %.1f%s: max |map - unprojection| = %.2g px over %zu pixels\n",
           lc->name, lc->width, lc->height, canvas.width, canvas.height, lc->scale,
           canvas.fisheye_deg > 0 ? " (fisheye)" : "", worst, Nvalid);
    free(q);
    free(v);
    free(map);
}

int main(int argc, char **argv)
{
    if (argc > 1) row_stride = atoi(argv[1]) > 0 ? atoi(argv[1]) : 1;
    static const lens_case cases[] = {
        {"demo cam1 OPENCV8",
         MRCAL_LENSMODEL_OPENCV8,
         {622.883811, 622.883811, 359.540609, 244.938700, -0.117129, 0.024064, 0.000003, -0.000284, -0.003054,
          -0.001950, 0, 0},
         720,
         480,
         1,
         false},
        {"demo cam1 OPENCV8 scale 2",
         MRCAL_LENSMODEL_OPENCV8,
         {622.883811, 622.883811, 359.540609, 244.938700, -0.117129, 0.024064, 0.000003, -0.000284, -0.003054,
          -0.001950, 0, 0},
         720,
         480,
         2,
         false},
        {"pinhole scale 1.5", MRCAL_LENSMODEL_PINHOLE, {800, 790, 321.3, 238.7}, 640, 480, 1.5, false},
        {"OPENCV4 barrel k1 -0.3",
         MRCAL_LENSMODEL_OPENCV4,
         {500, 500, 320, 240, -0.3, 0.05, 0.001, -0.002},
         640,
         480,
         1,
         false},
        {"OPENCV4 fold k1 -0.45", MRCAL_LENSMODEL_OPENCV4, {500, 500, 210, 160, -0.45, 0, 0, 0}, 420, 320, 1, false},
        {"OPENCV8 odd size",
         MRCAL_LENSMODEL_OPENCV8,
         {410.5, 409.2, 250.1, 171.9, -0.2, 0.08, 0.0005, -0.0007, -0.01, 0.02, 0.001, 0.004},
         501,
         343,
         1,
         false},
        {"fisheye equidistant f 340",
         MRCAL_LENSMODEL_CAHVORE,
         {340, 340, 641.3, 478.2, 0, 0, 0, 0, 0, 0, 0, 0},
         1280,
         960,
         1,
         false},
        {"fisheye Kannala-Brandt",
         MRCAL_LENSMODEL_CAHVORE,
         {340, 340, 641.3, 478.2, 0, 0, 0, 0.02, -0.004, 0, 0, 0},
         1280,
         960,
         1,
         false},
        {"fisheye f 170 circle inside",
         MRCAL_LENSMODEL_CAHVORE,
         {170, 170, 639.5, 479.5, 0, 0, 0, 0, 0, 0, 0, 0},
         1280,
         960,
         1,
         true},
    };
    for (size_t c = 0; c < sizeof(cases) / sizeof(cases[0]); c++) check_lens(&cases[c]);
    return rs_test_end("test_canvas_map");
}

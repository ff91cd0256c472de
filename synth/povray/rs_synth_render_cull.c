// rs_synth_render_cull.c -- the canvas rectangle of a vehicle's box: culling and the render's
// regions (rs_synth_vehicle_rect, synth/povray/rs_synth_render.h), on a pinhole or a fisheye canvas;
// the colour pass's clusters (rs_synth_colour_clusters, synth/povray/internal/rs_synth_render_internal.h).
#include "synth/povray/rs_synth_render.h"

#include <stdlib.h>

#include <math.h>
#include <string.h>

#include <mrcal/poseutils.h>

#include "synth/povray/internal/rs_synth_render_internal.h"

// Clips [lo, hi] (canvas pixels, widened by margin_px) to the canvas into rect; false if it misses.
static bool clip_rect(int rect[4], const double lo[2], const double hi[2], double margin_px, int width, int height)
{
    if (hi[0] < -0.5 - margin_px || hi[1] < -0.5 - margin_px || lo[0] > width - 0.5 + margin_px ||
        lo[1] > height - 0.5 + margin_px)
        return false;
    // Pixel k covers [k - 0.5, k + 0.5]
    rect[0] = (int)fmax(0, floor(lo[0] + 0.5 - margin_px));
    rect[1] = (int)fmax(0, floor(lo[1] + 0.5 - margin_px));
    rect[2] = (int)fmin(width - 1, floor(hi[0] + 0.5 + margin_px));
    rect[3] = (int)fmin(height - 1, floor(hi[1] + 0.5 + margin_px));
    return true;
}

// A fisheye canvas's rectangle of the convex hull of the 8 camera-frame points p (a box, or a
// shadow's corners on the ground): its outline is made of segments between them, so every pair
// is sampled at 33 points (the segments' curvature between samples is covered by a margin of
// 2 px plus 2 % of the rectangle's size); a hull reaching out of the canvas's angle gets the
// whole canvas.
static bool fisheye_rect(int rect[4], const rs_synth_canvas *canvas, const double p[8][3])
{
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    int Nin = 0, Nout = 0;
    for (int a = 0; a < 8; a++)
        for (int b = a + 1; b < 8; b++)
            for (int k = 0; k <= 32; k++) {
                double v[3], q[2];
                for (int c = 0; c < 3; c++) v[c] = p[a][c] + k / 32.0 * (p[b][c] - p[a][c]);
                if (!rs_synth_canvas_project(q, canvas, v)) {
                    Nout++;
                    continue;
                }
                Nin++;
                lo[0] = fmin(lo[0], q[0]), hi[0] = fmax(hi[0], q[0]);
                lo[1] = fmin(lo[1], q[1]), hi[1] = fmax(hi[1], q[1]);
            }
    if (Nin == 0) return false;
    if (Nout > 0) {
        lo[0] = lo[1] = 0;
        hi[0] = canvas->width - 1, hi[1] = canvas->height - 1;
    }
    return clip_rect(rect, lo, hi, 2 + 0.02 * fmax(hi[0] - lo[0], hi[1] - lo[1]), canvas->width, canvas->height);
}

bool rs_synth_vehicle_rect(int rect[4], const rs_synth_canvas *canvas, const double rt_cam_enu[6],
                           const double corners_enu_m[8][3], double near_m)
{
    double p[8][3];
    for (int k = 0; k < 8; k++) mrcal_transform_point_rt(p[k], NULL, NULL, rt_cam_enu, corners_enu_m[k]);
    if (canvas->fisheye_deg > 0) return fisheye_rect(rect, canvas, (const double(*)[3])p);
    const double *fxycxy = canvas->fxycxy;
    // The box clipped to z >= near is the convex hull of its corners in front and of the
    // crossings of its 12 edges with the plane z = near: their projections bound its image.
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    int Nin = 0;
    for (int a = 0; a < 8; a++) {
        for (int b = a; b < 8; b++) {
            const int diff = a ^ b;
            double q[3];
            if (a == b) {
                if (!(p[a][2] >= near_m)) continue;
                memcpy(q, p[a], sizeof(q));
            } else if (diff == 1 || diff == 2 || diff == 4) {
                const double za = p[a][2] - near_m, zb = p[b][2] - near_m;
                if (!((za < 0 && zb > 0) || (za > 0 && zb < 0))) continue;
                const double t = za / (za - zb);
                for (int k = 0; k < 3; k++) q[k] = p[a][k] + t * (p[b][k] - p[a][k]);
                q[2] = near_m;
            } else {
                continue;
            }
            const double u = fxycxy[0] * q[0] / q[2] + fxycxy[2], v = fxycxy[1] * q[1] / q[2] + fxycxy[3];
            lo[0] = fmin(lo[0], u), hi[0] = fmax(hi[0], u);
            lo[1] = fmin(lo[1], v), hi[1] = fmax(hi[1], v);
            Nin++;
        }
    }
    const int width = canvas->width, height = canvas->height;
    if (Nin == 0 || hi[0] < -0.5 || hi[1] < -0.5 || lo[0] > width - 0.5 || lo[1] > height - 0.5) return false;
    // Pixel k covers [k - 0.5, k + 0.5]; one pixel of margin on each side.
    rect[0] = (int)fmax(0, floor(lo[0] + 0.5) - 1);
    rect[1] = (int)fmax(0, floor(lo[1] + 0.5) - 1);
    rect[2] = (int)fmin(width - 1, floor(hi[0] + 0.5) + 1);
    rect[3] = (int)fmin(height - 1, floor(hi[1] + 0.5) + 1);
    return true;
}

void rs_synth_rect_grow(int rect[4], const int r[4])
{
    for (int k = 0; k < 4; k++)
        rect[k] = rect[2] < rect[0] ? r[k]
                  : k < 2           ? (r[k] < rect[k] ? r[k] : rect[k])
                                    : (r[k] > rect[k] ? r[k] : rect[k]);
}

// ---- the colour pass in clusters (rs_synth_colour_clusters) ----

// POV-Ray's time in the colour pass goes as the pixels it traces, and in the one rectangle
// around every vehicle most pixels show none (a street's vehicles spread across the frame).
// The vehicles are grouped instead: each rectangle grown by CLUSTER_MARGIN_PX, overlapping ones
// merged (so no other vehicle's rectangle meets a group's); then, while a merge saves more than
// it costs, the two whose union grows least are merged: a group of its own costs a povray
// process (CLUSTER_PROCESS_PX: its start and the scene's lights and environment, about 24 ms of
// CPU, what tracing and writing 50,000 pixels that show no vehicle takes), and there are at
// most RS_SYNTH_MAX_CLUSTERS. Each group is one povray process on its own rectangle with its
// vehicles, plus those whose shadow may fall there (their rectangle widened by their shadows
// meets it: a vehicle shading another stays exact) and, added by the renderer, those near
// enough to be seen reflected in its paint and glass.
enum { CLUSTER_MARGIN_PX = 4 };
#define CLUSTER_PROCESS_PX 50000.0

bool rs_synth_rects_meet(const int a[4], const int b[4])
{
    return a[0] <= b[2] && b[0] <= a[2] && a[1] <= b[3] && b[1] <= a[3];
}

static double rect_area(const int r[4]) { return r[2] < r[0] ? 0 : (double)(r[2] - r[0] + 1) * (r[3] - r[1] + 1); }

// Merges cluster b into a (a < b < n): its rectangle, its vehicles; the last takes b's place.
static void merge_clusters(int r[][4], int *of, int N, int a, int b, int n)
{
    rs_synth_rect_grow(r[a], r[b]);
    for (int i = 0; i < N; i++) of[i] = of[i] == b ? a : of[i] == n - 1 ? b : of[i];
    memcpy(r[b], r[n - 1], sizeof(r[b]));
}

int rs_synth_colour_clusters(int rect[RS_SYNTH_MAX_CLUSTERS][4], uint8_t *include, int N, const uint8_t *included,
                             const int (*rects)[4], const int (*reach)[4], int W, int H, const int region[4])
{
    int *of = malloc(sizeof(int) * (size_t)(N > 0 ? N : 1)); // each vehicle's cluster, -1: none
    int(*r)[4] = malloc(sizeof(*r) * (size_t)(N > 0 ? N : 1));
    if (!of || !r) {
        free(of), free(r);
        return 0;
    }
    int n = 0;
    for (int i = 0; i < N; i++) {
        of[i] = -1;
        const int *q = rects[i];
        if (!included[i] || q[2] < q[0]) continue;
        r[n][0] = q[0] - CLUSTER_MARGIN_PX < 0 ? 0 : q[0] - CLUSTER_MARGIN_PX;
        r[n][1] = q[1] - CLUSTER_MARGIN_PX < 0 ? 0 : q[1] - CLUSTER_MARGIN_PX;
        r[n][2] = q[2] + CLUSTER_MARGIN_PX >= W ? W - 1 : q[2] + CLUSTER_MARGIN_PX;
        r[n][3] = q[3] + CLUSTER_MARGIN_PX >= H ? H - 1 : q[3] + CLUSTER_MARGIN_PX;
        of[i] = n++;
    }
    for (bool merged = true; merged;) { // overlapping clusters merged until none overlap
        merged = false;
        for (int a = 0; a < n && !merged; a++)
            for (int b = a + 1; b < n && !merged; b++)
                if (rs_synth_rects_meet(r[a], r[b])) merge_clusters(r, of, N, a, b, n--), merged = true;
    }
    while (n > 1) { // the pair whose union grows least, while that saves a process's cost
        double best = INFINITY;
        int ba = 0, bb = 1;
        for (int x = 0; x < n; x++)
            for (int y = x + 1; y < n; y++) {
                int u[4] = {r[x][0], r[x][1], r[x][2], r[x][3]};
                rs_synth_rect_grow(u, r[y]);
                const double cost = rect_area(u) - rect_area(r[x]) - rect_area(r[y]);
                if (cost < best) best = cost, ba = x, bb = y;
            }
        if (n <= RS_SYNTH_MAX_CLUSTERS && best >= CLUSTER_PROCESS_PX) break;
        merge_clusters(r, of, N, ba, bb, n--);
    }
    // (and one rectangle round them all, the region, when that costs no more)
    double sum = 0;
    for (int c = 0; c < n; c++) sum += rect_area(r[c]);
    const bool worth = n >= 2 && rect_area(region) - sum >= (n - 1) * CLUSTER_PROCESS_PX;
    for (int c = 0; worth && c < n; c++) {
        memcpy(rect[c], r[c], sizeof(rect[c]));
        uint8_t *inc = &include[(size_t)c * N];
        for (int i = 0; i < N; i++)
            inc[i] = of[i] == c || (included[i] && of[i] >= 0 && rs_synth_rects_meet(reach[i], r[c]));
    }
    free(of);
    free(r);
    return worth ? n : 0;
}

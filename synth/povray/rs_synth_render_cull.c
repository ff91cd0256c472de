// rs_synth_render_cull.c -- the canvas rectangle of a vehicle's box: culling and the render's
// regions (rs_synth_vehicle_rect, synth/povray/rs_synth_render.h), on a pinhole or a fisheye canvas.
#include "synth/povray/rs_synth_render.h"

#include <math.h>
#include <string.h>

#include <mrcal/poseutils.h>

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

// rs_report_draw_image.c -- the camera's image figure (rs_report_draw_camera): background or
// neutral canvas, ground grid, lanes, picks, reprojections and magnified residuals, legend.
#include "core/rs_pose.h"
#include "report/internal/rs_report_doc.h"
#include "report/internal/rs_report_draw.h"
#include "report/internal/rs_report_draw_internal.h"

#include <math.h>
#include <stdio.h>

#include <mrcal/mrcal.h>

// ---- projection ----

// ENU point -> pixel through the camera's full lens model, core's rule (rs_camera_project_visible):
// false when behind the camera or beyond the lens's valid field.
static bool project(const rs_report_camera *cam, const double p_enu[3], double q[2])
{
    return rs_camera_project_visible(q, &cam->model, cam->max_tan, p_enu);
}

// Draws the ENU polyline p (Np,3) into the image (drawing scale s: pixel (u,v) is drawn at
// ((u+0.5)s, (v+0.5)s)), sampled every `step_m` metres, broken where it leaves the image.
static void image_polyline(cairo_t *cr, const rs_report_camera *cam, double s, const double *p, int Np, double step_m)
{
    double W = cam->model.width, H = cam->model.height;
    bool pen = false;
    for (int i = 0; i + 1 < Np; i++) {
        const double *a = &p[3 * i], *b = &p[3 * i + 3];
        double len =
            sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) + (b[2] - a[2]) * (b[2] - a[2]));
        int n = (int)ceil(len / step_m);
        if (n < 1) n = 1;
        if (n > 4000) n = 4000;
        for (int k = (i == 0 ? 0 : 1); k <= n; k++) {
            double t = (double)k / n, x[3], q[2];
            for (int j = 0; j < 3; j++) x[j] = a[j] + t * (b[j] - a[j]);
            bool ok = project(cam, x, q) && q[0] > -0.25 * W && q[0] < 1.25 * W && q[1] > -0.25 * H && q[1] < 1.25 * H;
            if (!ok) {
                pen = false;
                continue;
            }
            if (pen)
                cairo_line_to(cr, (q[0] + 0.5) * s, (q[1] + 0.5) * s);
            else
                cairo_move_to(cr, (q[0] + 0.5) * s, (q[1] + 0.5) * s);
            pen = true;
        }
    }
}

// Height of the site's ground plane n . p = offset at (e, n).
static double ground_up(const rs_site *site, double e, double n)
{
    const double *nn = site->ground_normal_enu;
    return (site->ground_offset_m - nn[0] * e - nn[1] * n) / nn[2];
}

// ---- the camera's image ----

typedef enum { LEGEND_CIRCLE, LEGEND_CROSS, LEGEND_DOT, LEGEND_LINE } legend_shape;

// One legend row: a sample (shape, colour, line width lw_fs * fs) and its text.
static void legend_row(cairo_t *cr, double x, double y, double fs, legend_shape shape, double r, double g, double b,
                       double lw_fs, const char *text)
{
    double cx = x + fs * 0.6, cy = y - fs * 0.35;
    cairo_save(cr);
    cairo_set_source_rgb(cr, r, g, b);
    cairo_set_line_width(cr, fs * lw_fs);
    switch (shape) {
    case LEGEND_CIRCLE: rs_report_marker_circle(cr, cx, cy, fs * 0.4); break;
    case LEGEND_CROSS: rs_report_marker_cross(cr, cx, cy, fs * 0.4); break;
    case LEGEND_DOT: rs_report_marker_circle(cr, cx, cy, fs * 0.2); break;
    case LEGEND_LINE:
        cairo_move_to(cr, x, cy);
        cairo_line_to(cr, x + fs * 1.2, cy);
        break;
    }
    if (shape == LEGEND_DOT)
        cairo_fill(cr);
    else
        cairo_stroke(cr);
    cairo_restore(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_move_to(cr, x + fs * 1.6, y);
    rs_doc_show_text(cr, text);
}

void rs_report_draw_camera(cairo_t *cr, double w, double h, const void *ctx)
{
    const rs_report_camera *cam = ctx;
    const struct rs_report_ctx *rep = cam->rep;
    double W = cam->model.width, H = cam->model.height;
    double s = fmin(w / W, h / H), fs = w / 75;

    cairo_save(cr);
    cairo_rectangle(cr, 0, 0, W * s, H * s);
    cairo_clip(cr);
    if (cam->background) {
        cairo_save(cr);
        cairo_scale(cr, W * s / cairo_image_surface_get_width(cam->background),
                    H * s / cairo_image_surface_get_height(cam->background));
        cairo_set_source_surface(cr, cam->background, 0, 0);
        cairo_paint(cr);
        cairo_restore(cr);
    } else {
        cairo_set_source_rgb(cr, 0.86, 0.86, 0.84);
        cairo_paint(cr);
    }

    // ground grid: lines of constant E and constant N around the camera, every grid_m
    double C[3];
    rs_pose_position_from_rt(C, NULL, cam->model.rt_cam_enu);
    double g = rep->grid_m, R = rep->range_m;
    cairo_set_source_rgba(cr, 0.2, 0.7, 0.9, 0.85);
    cairo_set_line_width(cr, fmax(w / 900, 0.4));
    for (int axis = 0; axis < 2; axis++)
        for (double c = floor((C[axis] - R) / g) * g; c <= C[axis] + R; c += g) {
            double p[2 * 3];
            for (int k = 0; k < 2; k++) {
                double a = C[1 - axis] - R + 2 * R * k;
                double e = axis == 0 ? c : a, nn = axis == 0 ? a : c;
                p[3 * k] = e, p[3 * k + 1] = nn, p[3 * k + 2] = ground_up(rep->site, e, nn);
            }
            image_polyline(cr, cam, s, p, 2, g / 8);
        }
    cairo_stroke(cr);

    // lanes: edges, then junction connectors thin and light (solid: dashes on many crossing curves
    // read as scattered specks)
    for (int pass = 0; pass < 2; pass++) {
        cairo_set_source_rgba(cr, 1, 0.8, 0, pass ? 0.45 : 0.95);
        cairo_set_line_width(cr, fmax(w / (pass ? 1200 : 450), pass ? 0.4 : 0.8));
        for (int k = 0; k < rep->lanes.Nlines; k++)
            if (rep->lanes.junction[k] == (pass == 1))
                image_polyline(cr, cam, s, &rep->lanes.p_enu_m[3 * rep->lanes.start[k]],
                               rep->lanes.start[k + 1] - rep->lanes.start[k], 0.5);
        cairo_stroke(cr);
    }
    cairo_set_dash(cr, NULL, 0, 0);

    // landmarks: pick, reprojection, magnified residual
    double lw = fmax(w / 600, 0.6), rmark = w / 160;
    for (int i = 0; i < cam->N; i++) {
        const rs_report_landmark *l = &cam->landmarks[i];
        double x = (l->observed_px[0] + 0.5) * s, y = (l->observed_px[1] + 0.5) * s;
        // inliers: residual magnified; outliers: true length, dashed red (they are large)
        double m = l->inlier ? cam->magnification : 1, dash = lw * 4;
        cairo_set_line_width(cr, lw * 1.5);
        if (l->inlier)
            cairo_set_source_rgb(cr, 1, 0.2, 0.6);
        else {
            cairo_set_source_rgb(cr, 0.9, 0.1, 0.1);
            cairo_set_dash(cr, &dash, 1, 0);
        }
        // the residual against the SURVEYED position; none drawn when <id>.json predates it
        const double *d = l->residual_surveyed_px;
        const bool surveyed = isfinite(d[0]) && isfinite(d[1]);
        if (surveyed) {
            cairo_move_to(cr, x, y);
            cairo_line_to(cr, x + m * d[0] * s, y + m * d[1] * s);
            cairo_stroke(cr);
        }
        cairo_set_dash(cr, NULL, 0, 0);
        cairo_set_line_width(cr, lw);
        if (l->inlier) {
            cairo_set_source_rgb(cr, 0.1, 0.75, 0.1);
            rs_report_marker_circle(cr, x, y, rmark);
        } else {
            cairo_set_source_rgb(cr, 0.9, 0.1, 0.1);
            rs_report_marker_cross(cr, x, y, rmark);
        }
        cairo_stroke(cr);
        if (surveyed) {
            cairo_set_source_rgb(cr, 0.1, 0.3, 1);
            rs_report_marker_circle(cr, (l->predicted_surveyed_px[0] + 0.5) * s,
                                    (l->predicted_surveyed_px[1] + 0.5) * s, rmark * 0.35);
            cairo_fill(cr);
        }
        rs_report_font(cr, fs * 0.8, false);
        cairo_set_source_rgb(cr, 0, 0, 0);
        rs_report_label(cr, x + rmark * 1.3, y - rmark * 1.3, l->id, 0.6);
    }

    // legend (top left) and the residual scale bar
    char buf[128];
    rs_report_font(cr, fs, false);
    double lx = fs * 0.6, ly = fs * 0.6, lh = fs * 1.35;
    double bar_px = rs_report_nice_ceil(0.08 * W / cam->magnification); // residual px whose bar is ~8% of W
    int rows = rep->lanes.Nlines ? 7 : 6;
    cairo_set_source_rgba(cr, 1, 1, 1, 0.82);
    cairo_rectangle(cr, lx, ly, fs * 20, lh * rows + fs * 0.6);
    cairo_fill(cr);
    double y = ly + lh;
    legend_row(cr, lx + fs * 0.4, y, fs, LEGEND_CIRCLE, 0.1, 0.75, 0.1, 0.15, "pick (inlier)"), y += lh;
    legend_row(cr, lx + fs * 0.4, y, fs, LEGEND_CROSS, 0.9, 0.1, 0.1, 0.15, "pick (outlier), residual true size"),
        y += lh;
    legend_row(cr, lx + fs * 0.4, y, fs, LEGEND_DOT, 0.1, 0.3, 1, 0.15, "surveyed landmark reprojected"), y += lh;
    snprintf(buf, sizeof buf, "inlier residual x%g", cam->magnification);
    legend_row(cr, lx + fs * 0.4, y, fs, LEGEND_LINE, 1, 0.2, 0.6, 0.15, buf), y += lh;
    snprintf(buf, sizeof buf, "ground grid, %g m", g);
    legend_row(cr, lx + fs * 0.4, y, fs, LEGEND_LINE, 0.2, 0.7, 0.9, 0.15, buf), y += lh;
    if (rep->lanes.Nlines) legend_row(cr, lx + fs * 0.4, y, fs, LEGEND_LINE, 1, 0.8, 0, 0.25, "lane lines"), y += lh;
    // scale bar
    double bx = lx + fs * 0.4, by = y - fs * 0.3, blen = bar_px * cam->magnification * s;
    cairo_set_source_rgb(cr, 1, 0.2, 0.6);
    cairo_set_line_width(cr, lw * 2);
    cairo_move_to(cr, bx, by);
    cairo_line_to(cr, bx + blen, by);
    cairo_move_to(cr, bx, by - fs * 0.3);
    cairo_line_to(cr, bx, by + fs * 0.3);
    cairo_move_to(cr, bx + blen, by - fs * 0.3);
    cairo_line_to(cr, bx + blen, by + fs * 0.3);
    cairo_stroke(cr);
    snprintf(buf, sizeof buf, "%g px", bar_px);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_move_to(cr, bx + blen + fs * 0.4, by + fs * 0.35);
    rs_doc_show_text(cr, buf);

    if (!cam->background) {
        rs_report_font(cr, fs, false);
        cairo_set_source_rgb(cr, 0.45, 0.45, 0.45);
        snprintf(buf, sizeof buf, "no background image: neutral canvas, %d x %d px", cam->model.width,
                 cam->model.height);
        cairo_move_to(cr, W * s - rs_report_text_w(cr, buf) - fs * 0.6, H * s - fs * 0.6);
        rs_doc_show_text(cr, buf);
    }
    cairo_restore(cr);
}

// rs_report_draw.c -- the report's figures (see rs_report_draw.h).
#include "report/rs_report_draw.h"
#include "report/rs_report_doc.h"
#include "core/rs_pose.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mrcal/mrcal.h>
#include <mrcal/poseutils.h>

// ---- small helpers ----

// The smallest 1-2-5 number >= x (x > 0).
static double nice_ceil(double x)
{
    double e = pow(10, floor(log10(x)));
    for (int i = 0; i < 4; i++) {
        static const double m[4] = {1, 2, 5, 10};
        if (m[i] * e >= x * (1 - 1e-9)) return m[i] * e;
    }
    return 10 * e;
}

// Qualitative palette for cameras (Tableau 10).
static void camera_rgb(cairo_t *cr, int k, double alpha)
{
    static const double pal[10][3] = {{0.12, 0.47, 0.71}, {1.00, 0.50, 0.05}, {0.17, 0.63, 0.17},
                                      {0.84, 0.15, 0.16}, {0.58, 0.40, 0.74}, {0.55, 0.34, 0.29},
                                      {0.89, 0.47, 0.76}, {0.50, 0.50, 0.50}, {0.74, 0.74, 0.13},
                                      {0.09, 0.75, 0.81}};
    const double *c = pal[k % 10];
    cairo_set_source_rgba(cr, c[0], c[1], c[2], alpha);
}

// Viridis, sampled at 9 stops and interpolated linearly; t in [0,1].
static void viridis(double t, double rgb[3])
{
    static const double stop[9][3] = {{68, 1, 84},    {71, 44, 122},  {59, 81, 139},
                                      {44, 113, 142}, {33, 144, 141}, {39, 173, 129},
                                      {92, 200, 99},  {170, 220, 50}, {253, 231, 37}};
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double x = t * 8;
    int i = (int)x;
    if (i > 7) i = 7;
    double f = x - i;
    for (int k = 0; k < 3; k++) rgb[k] = ((1 - f) * stop[i][k] + f * stop[i + 1][k]) / 255;
}

static void font(cairo_t *cr, double size, bool bold)
{
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                           bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, size);
}

// Text with its left baseline at (x, y) on a translucent white box.
static void label(cairo_t *cr, double x, double y, const char *s, double box_alpha)
{
    cairo_text_extents_t e;
    rs_doc_text_extents(cr, s, &e);
    double pad = 0.25 * e.height + 1;
    cairo_save(cr);
    if (box_alpha > 0) {
        cairo_set_source_rgba(cr, 1, 1, 1, box_alpha);
        cairo_rectangle(cr, x + e.x_bearing - pad, y + e.y_bearing - pad, e.width + 2 * pad, e.height + 2 * pad);
        cairo_fill(cr);
    }
    cairo_restore(cr);
    cairo_move_to(cr, x, y);
    rs_doc_show_text(cr, s);
}

static double text_w(cairo_t *cr, const char *s)
{
    cairo_text_extents_t e;
    rs_doc_text_extents(cr, s, &e);
    return e.x_advance;
}

// ---- projection ----

// ENU point -> pixel through the camera's full lens model. False when behind the camera or
// farther off-axis than the model can be trusted (distortion polynomials fold back there).
static bool project(const rs_report_camera *cam, const double p_enu[3], double q[2])
{
    mrcal_point3_t pc;
    mrcal_transform_point_rt(pc.xyz, NULL, NULL, cam->model.rt_cam_enu, p_enu);
    if (!(pc.z > 1e-6)) return false;
    if (hypot(pc.x, pc.y) / pc.z > cam->max_tan) return false;
    mrcal_point2_t qq;
    if (!mrcal_project(&qq, NULL, NULL, &pc, 1, &cam->model.lensmodel, cam->model.intrinsics)) return false;
    if (!isfinite(qq.x) || !isfinite(qq.y)) return false;
    q[0] = qq.x;
    q[1] = qq.y;
    return true;
}

// Draws the ENU polyline p (Np,3) into the image (drawing scale s: pixel (u,v) is drawn at
// ((u+0.5)s, (v+0.5)s)), sampled every `step_m` metres, broken where it leaves the image.
static void image_polyline(cairo_t *cr, const rs_report_camera *cam, double s, const double *p, int Np, double step_m)
{
    double W = cam->model.width, H = cam->model.height;
    bool pen = false;
    for (int i = 0; i + 1 < Np; i++) {
        const double *a = &p[3 * i], *b = &p[3 * i + 3];
        double len = sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) + (b[2] - a[2]) * (b[2] - a[2]));
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

bool rs_report_camera_geometry(rs_report_camera *cam)
{
    const rs_camera *m = &cam->model;
    const rs_site *site = cam->rep->site;
    double W = m->width, H = m->height;

    // off-axis guard: the widest image corner, plus 15%
    double corners[4][2] = {{-0.5, -0.5}, {W - 0.5, -0.5}, {-0.5, H - 0.5}, {W - 0.5, H - 0.5}};
    cam->max_tan = 0;
    for (int i = 0; i < 4; i++) {
        mrcal_point2_t q = {.x = corners[i][0], .y = corners[i][1]};
        mrcal_point3_t v;
        double t = 1e3;
        if (mrcal_unproject(&v, &q, 1, &m->lensmodel, m->intrinsics) && v.z > 1e-9) t = hypot(v.x, v.y) / v.z;
        if (t > cam->max_tan) cam->max_tan = t;
    }
    cam->max_tan = cam->max_tan * 1.15 + 0.02;

    // field of view on the ground: the image border's rays, cut at range_m horizontally
    enum { PER_SIDE = 48 };
    cam->fov_en_m = malloc(4 * PER_SIDE * 2 * sizeof(double));
    if (!cam->fov_en_m) return false;
    cam->Nfov = 0;
    double C[3];
    rs_pose_position_from_rt(C, NULL, m->rt_cam_enu);
    const double *n = site->ground_normal_enu;
    for (int side = 0; side < 4; side++)
        for (int k = 0; k < PER_SIDE; k++) {
            double t = (double)k / PER_SIDE;
            mrcal_point2_t q;
            switch (side) { // clockwise in the image: top, right, bottom, left
            case 0: q.x = -0.5 + t * W, q.y = -0.5; break;
            case 1: q.x = W - 0.5, q.y = -0.5 + t * H; break;
            case 2: q.x = W - 0.5 - t * W, q.y = H - 0.5; break;
            default: q.x = -0.5, q.y = H - 0.5 - t * H; break;
            }
            mrcal_point3_t v;
            if (!mrcal_unproject(&v, &q, 1, &m->lensmodel, m->intrinsics)) continue;
            double d[3];
            mrcal_rotate_point_r_inverted(d, NULL, NULL, m->rt_cam_enu, v.xyz);
            double dh = hypot(d[0], d[1]);
            if (!(dh > 1e-9)) continue;
            double nd = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
            double sray = nd != 0 ? (site->ground_offset_m - (n[0] * C[0] + n[1] * C[1] + n[2] * C[2])) / nd : -1;
            double *out = &cam->fov_en_m[2 * cam->Nfov];
            if (sray > 0 && sray * dh <= cam->rep->range_m) {
                out[0] = C[0] + sray * d[0];
                out[1] = C[1] + sray * d[1];
            } else {
                out[0] = C[0] + cam->rep->range_m * d[0] / dh;
                out[1] = C[1] + cam->rep->range_m * d[1] / dh;
            }
            cam->Nfov++;
        }

    // magnification: median inlier residual drawn as ~1.5% of the image width
    double *r = malloc((size_t)(cam->N > 0 ? cam->N : 1) * sizeof *r);
    if (!r) return false;
    int Nr = 0;
    for (int i = 0; i < cam->N; i++)
        if (cam->landmarks[i].inlier) r[Nr++] = hypot(cam->landmarks[i].residual_px[0], cam->landmarks[i].residual_px[1]);
    double med = 0;
    if (Nr) {
        for (int i = 1; i < Nr; i++) // insertion sort: a few dozen values
            for (int j = i; j > 0 && r[j] < r[j - 1]; j--) {
                double tmp = r[j];
                r[j] = r[j - 1];
                r[j - 1] = tmp;
            }
        med = r[Nr / 2];
    }
    free(r);
    double target = 0.015 * W;
    cam->magnification = med > 1e-6 ? nice_ceil(target / med) / 2 : 1;
    if (cam->magnification < 1) cam->magnification = 1;
    return true;
}

// ---- the camera's image ----

static void draw_marker_circle(cairo_t *cr, double x, double y, double r)
{
    cairo_new_sub_path(cr);
    cairo_arc(cr, x, y, r, 0, 2 * M_PI);
}

static void draw_marker_cross(cairo_t *cr, double x, double y, double r)
{
    cairo_move_to(cr, x - r, y - r);
    cairo_line_to(cr, x + r, y + r);
    cairo_move_to(cr, x - r, y + r);
    cairo_line_to(cr, x + r, y - r);
}

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
    case LEGEND_CIRCLE: draw_marker_circle(cr, cx, cy, fs * 0.4); break;
    case LEGEND_CROSS: draw_marker_cross(cr, cx, cy, fs * 0.4); break;
    case LEGEND_DOT: draw_marker_circle(cr, cx, cy, fs * 0.2); break;
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

    // lanes: edges solid, junction connectors thin and dashed
    for (int pass = 0; pass < 2; pass++) {
        cairo_set_source_rgba(cr, 1, 0.8, 0, pass ? 0.5 : 0.95);
        cairo_set_line_width(cr, fmax(w / (pass ? 1000 : 450), pass ? 0.4 : 0.8));
        double dash = w / 150;
        cairo_set_dash(cr, &dash, pass, 0);
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
        cairo_move_to(cr, x, y);
        cairo_line_to(cr, x + m * l->residual_px[0] * s, y + m * l->residual_px[1] * s);
        cairo_stroke(cr);
        cairo_set_dash(cr, NULL, 0, 0);
        cairo_set_line_width(cr, lw);
        if (l->inlier) {
            cairo_set_source_rgb(cr, 0.1, 0.75, 0.1);
            draw_marker_circle(cr, x, y, rmark);
        } else {
            cairo_set_source_rgb(cr, 0.9, 0.1, 0.1);
            draw_marker_cross(cr, x, y, rmark);
        }
        cairo_stroke(cr);
        cairo_set_source_rgb(cr, 0.1, 0.3, 1);
        draw_marker_circle(cr, (l->predicted_px[0] + 0.5) * s, (l->predicted_px[1] + 0.5) * s, rmark * 0.35);
        cairo_fill(cr);
        font(cr, fs * 0.8, false);
        cairo_set_source_rgb(cr, 0, 0, 0);
        label(cr, x + rmark * 1.3, y - rmark * 1.3, l->id, 0.6);
    }

    // legend (top left) and the residual scale bar
    char buf[128];
    font(cr, fs, false);
    double lx = fs * 0.6, ly = fs * 0.6, lh = fs * 1.35;
    double bar_px = nice_ceil(0.08 * W / cam->magnification); // residual px whose bar is ~8% of W
    int rows = rep->lanes.Nlines ? 7 : 6;
    cairo_set_source_rgba(cr, 1, 1, 1, 0.82);
    cairo_rectangle(cr, lx, ly, fs * 20, lh * rows + fs * 0.6);
    cairo_fill(cr);
    double y = ly + lh;
    legend_row(cr, lx + fs * 0.4, y, fs, LEGEND_CIRCLE, 0.1, 0.75, 0.1, 0.15, "pick (inlier)"), y += lh;
    legend_row(cr, lx + fs * 0.4, y, fs, LEGEND_CROSS, 0.9, 0.1, 0.1, 0.15, "pick (outlier), residual true size"), y += lh;
    legend_row(cr, lx + fs * 0.4, y, fs, LEGEND_DOT, 0.1, 0.3, 1, 0.15, "reprojected landmark"), y += lh;
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
        font(cr, fs, false);
        cairo_set_source_rgb(cr, 0.45, 0.45, 0.45);
        snprintf(buf, sizeof buf, "no background image: neutral canvas, %d x %d px", cam->model.width,
                 cam->model.height);
        cairo_move_to(cr, W * s - text_w(cr, buf) - fs * 0.6, H * s - fs * 0.6);
        rs_doc_show_text(cr, buf);
    }
    cairo_restore(cr);
}

// ---- top-down maps ----

// Maps ENU (E, N) to the drawing: x = ox + k E, y = oy - k N.
typedef struct {
    double ox, oy, k;
} map_view;

static void map_xy(const map_view *v, double e, double n, double *x, double *y)
{
    *x = v->ox + v->k * e;
    *y = v->oy - v->k * n;
}

// A view showing [e0,e1] x [n0,n1] inside (w, h) with a margin, at equal scale.
static map_view map_fit(double e0, double e1, double n0, double n1, double w, double h, double margin)
{
    double de = fmax(e1 - e0, 1), dn = fmax(n1 - n0, 1);
    map_view v;
    v.k = fmin((w - 2 * margin) / de, (h - 2 * margin) / dn);
    v.ox = w / 2 - v.k * (e0 + e1) / 2;
    v.oy = h / 2 + v.k * (n0 + n1) / 2;
    return v;
}

static void extent_add(double ext[4], double e, double n)
{
    if (!isfinite(e) || !isfinite(n)) return;
    if (e < ext[0]) ext[0] = e;
    if (e > ext[1]) ext[1] = e;
    if (n < ext[2]) ext[2] = n;
    if (n > ext[3]) ext[3] = n;
}

static void map_lanes(cairo_t *cr, const map_view *v, const rs_report_lanes *lanes, double lw)
{
    for (int pass = 0; pass < 2; pass++) { // edges solid, junction connectors thin and dashed
        cairo_set_source_rgba(cr, 0.85, 0.65, 0, pass ? 0.6 : 0.9);
        cairo_set_line_width(cr, pass ? lw / 2 : lw);
        double dash = lw * 6;
        cairo_set_dash(cr, &dash, pass, 0);
        for (int k = 0; k < lanes->Nlines; k++) {
            if (lanes->junction[k] != (pass == 1)) continue;
            for (int i = lanes->start[k]; i < lanes->start[k + 1]; i++) {
                double x, y;
                map_xy(v, lanes->p_enu_m[3 * i], lanes->p_enu_m[3 * i + 1], &x, &y);
                if (i == lanes->start[k])
                    cairo_move_to(cr, x, y);
                else
                    cairo_line_to(cr, x, y);
            }
        }
        cairo_stroke(cr);
    }
    cairo_set_dash(cr, NULL, 0, 0);
}

static void map_fov(cairo_t *cr, const map_view *v, const rs_report_camera *cam, double fill_alpha, double lw)
{
    if (cam->Nfov < 3) return;
    for (int i = 0; i < cam->Nfov; i++) {
        double x, y;
        map_xy(v, cam->fov_en_m[2 * i], cam->fov_en_m[2 * i + 1], &x, &y);
        if (i == 0)
            cairo_move_to(cr, x, y);
        else
            cairo_line_to(cr, x, y);
    }
    cairo_close_path(cr);
    if (fill_alpha > 0) {
        camera_rgb(cr, cam->colour, fill_alpha);
        cairo_fill_preserve(cr);
    }
    camera_rgb(cr, cam->colour, 1);
    cairo_set_line_width(cr, lw);
    double dash = lw * 4;
    cairo_set_dash(cr, &dash, 1, 0);
    cairo_stroke(cr);
    cairo_set_dash(cr, NULL, 0, 0);
}

// The camera: a filled disc and an arrow along its heading, with its id.
static void map_camera(cairo_t *cr, const map_view *v, const rs_report_camera *cam, double fs)
{
    double x, y, yaw = cam->yaw_pitch_roll_deg[0] * M_PI / 180;
    map_xy(v, cam->position_enu_m[0], cam->position_enu_m[1], &x, &y);
    double L = fs * 2.5;
    camera_rgb(cr, cam->colour, 1);
    cairo_set_line_width(cr, fs * 0.2);
    cairo_move_to(cr, x, y);
    cairo_line_to(cr, x + L * sin(yaw), y - L * cos(yaw));
    cairo_stroke(cr);
    draw_marker_circle(cr, x, y, fs * 0.45);
    cairo_fill_preserve(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, fs * 0.08);
    cairo_stroke(cr);
    font(cr, fs, true);
    label(cr, x + fs * 0.7, y + fs * 1.2, cam->rep->site->cameras[cam->icam].id, 0.7);
}

// Scale bar (bottom left) and north arrow (top right).
static void map_furniture(cairo_t *cr, const map_view *v, double w, double h, double fs)
{
    double len_m = nice_ceil(0.18 * w / v->k), len = len_m * v->k;
    if (len > 0.3 * w) len_m /= 2, len /= 2;
    double x = fs, y = h - fs;
    cairo_set_source_rgba(cr, 1, 1, 1, 0.75);
    cairo_rectangle(cr, x - fs * 0.4, y - fs * 1.7, len + fs * 4.5, fs * 2.2);
    cairo_fill(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, fs * 0.15);
    cairo_move_to(cr, x, y - fs * 0.6);
    cairo_line_to(cr, x, y);
    cairo_line_to(cr, x + len, y);
    cairo_line_to(cr, x + len, y - fs * 0.6);
    cairo_stroke(cr);
    char buf[32];
    snprintf(buf, sizeof buf, "%g m", len_m);
    font(cr, fs, false);
    cairo_move_to(cr, x + len + fs * 0.4, y);
    rs_doc_show_text(cr, buf);

    double nx = fs * 1.6, ny = fs * 1.2;
    cairo_move_to(cr, nx, ny);
    cairo_line_to(cr, nx - fs * 0.6, ny + fs * 2);
    cairo_line_to(cr, nx, ny + fs * 1.5);
    cairo_line_to(cr, nx + fs * 0.6, ny + fs * 2);
    cairo_close_path(cr);
    cairo_fill(cr);
    font(cr, fs, true);
    cairo_move_to(cr, nx - fs * 0.35, ny + fs * 3.3);
    rs_doc_show_text(cr, "N");
}

// Landmarks of the site: observed by `cam` (if not NULL) drawn as inlier / outlier, the rest
// as small grey dots; ids written when `ids`.
static void map_landmarks(cairo_t *cr, const map_view *v, const struct rs_report_ctx *rep, const rs_report_camera *cam,
                          double fs, bool ids)
{
    const rs_site *site = rep->site;
    for (int i = 0; i < site->Nlandmarks; i++) {
        int state = 0; // 0 not seen, 1 inlier, 2 outlier
        if (cam)
            for (int k = 0; k < cam->N; k++)
                if (cam->landmarks[k].ilandmark == i) state = cam->landmarks[k].inlier ? 1 : 2;
        double x, y;
        map_xy(v, site->landmarks[i].p_enu_m[0], site->landmarks[i].p_enu_m[1], &x, &y);
        cairo_set_line_width(cr, fs * 0.12);
        if (state == 2) {
            cairo_set_source_rgb(cr, 0.9, 0.1, 0.1);
            draw_marker_cross(cr, x, y, fs * 0.4);
            cairo_stroke(cr);
        } else {
            if (state == 1)
                cairo_set_source_rgb(cr, 0, 0, 0);
            else
                cairo_set_source_rgb(cr, 0.45, 0.45, 0.45);
            draw_marker_circle(cr, x, y, fs * (state ? 0.28 : 0.18));
            cairo_fill(cr);
        }
        if (ids && (state || !cam)) {
            font(cr, fs * 0.7, false);
            cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
            cairo_move_to(cr, x + fs * 0.35, y - fs * 0.35);
            rs_doc_show_text(cr, site->landmarks[i].id);
        }
    }
}

// Contour segments of `map` at `level` by marching squares over the cell centres (cells with a
// NaN corner are skipped); up to 3 places far apart get the level written next to them.
static void map_contour(cairo_t *cr, const map_view *v, const rs_audit_map *map, double level, double fs)
{
    int nx = map->nx, ny = map->ny, Nlab = 0;
    double lx[3], ly[3];
    for (int iy = 0; iy + 1 < ny; iy++)
        for (int ix = 0; ix + 1 < nx; ix++) {
            // corners counter-clockwise from (ix, iy): a b c d
            double val[4] = {map->sigma_m[iy * nx + ix], map->sigma_m[iy * nx + ix + 1],
                             map->sigma_m[(iy + 1) * nx + ix + 1], map->sigma_m[(iy + 1) * nx + ix]};
            double ce[4] = {ix, ix + 1, ix + 1, ix}, cn[4] = {iy, iy, iy + 1, iy + 1};
            if (!isfinite(val[0]) || !isfinite(val[1]) || !isfinite(val[2]) || !isfinite(val[3])) continue;
            // crossing points on the 4 edges
            double pe[4], pn[4];
            int Np = 0;
            for (int k = 0; k < 4; k++) {
                double a = val[k], b = val[(k + 1) % 4];
                if ((a < level) == (b < level)) continue;
                double t = (level - a) / (b - a);
                pe[Np] = ce[k] + t * (ce[(k + 1) % 4] - ce[k]);
                pn[Np] = cn[k] + t * (cn[(k + 1) % 4] - cn[k]);
                Np++;
            }
            for (int k = 0; k + 1 < Np; k += 2) { // 2 or 4 crossings: pair them in edge order
                double x0, y0, x1, y1;
                map_xy(v, map->e0_m + pe[k] * map->cell_m, map->n0_m + pn[k] * map->cell_m, &x0, &y0);
                map_xy(v, map->e0_m + pe[k + 1] * map->cell_m, map->n0_m + pn[k + 1] * map->cell_m, &x1, &y1);
                cairo_move_to(cr, x0, y0);
                cairo_line_to(cr, x1, y1);
                bool far = Nlab < 3;
                for (int j = 0; j < Nlab && far; j++) far = hypot(x0 - lx[j], y0 - ly[j]) > 20 * fs;
                if (far) lx[Nlab] = x0, ly[Nlab] = y0, Nlab++;
            }
        }
    cairo_set_source_rgba(cr, 1, 1, 1, 0.9);
    cairo_set_line_width(cr, fs * 0.12);
    cairo_stroke(cr);
    char buf[32];
    snprintf(buf, sizeof buf, "%g m", level);
    font(cr, fs * 0.8, true);
    cairo_set_source_rgb(cr, 0, 0, 0);
    for (int j = 0; j < Nlab; j++) label(cr, lx[j], ly[j], buf, 0.75);
}

// The 90th percentile of the finite map values (0 when none).
static double map_p90(const rs_audit_map *map)
{
    int n = map->nx * map->ny, Nf = 0;
    double lo = INFINITY, hi = 0;
    for (int i = 0; i < n; i++)
        if (isfinite(map->sigma_m[i])) {
            Nf++;
            lo = fmin(lo, map->sigma_m[i]);
            hi = fmax(hi, map->sigma_m[i]);
        }
    if (!Nf) return 0;
    // bisection on the value: count below
    for (int it = 0; it < 50; it++) {
        double mid = (lo + hi) / 2;
        int below = 0;
        for (int i = 0; i < n; i++)
            if (isfinite(map->sigma_m[i]) && map->sigma_m[i] <= mid) below++;
        if (below >= 0.9 * Nf)
            hi = mid;
        else
            lo = mid;
    }
    return hi;
}

// The map's colour field (one image pixel per cell, painted at the cells' place) and its
// contours at 1/5 .. 4/5 of vmax.
static void map_field(cairo_t *cr, const map_view *v, const rs_audit_map *map, double vmax, double fs)
{
    cairo_surface_t *img = cairo_image_surface_create(CAIRO_FORMAT_ARGB32, map->nx, map->ny);
    cairo_surface_flush(img);
    unsigned char *data = cairo_image_surface_get_data(img);
    int stride = cairo_image_surface_get_stride(img);
    for (int iy = 0; iy < map->ny && data; iy++)
        for (int ix = 0; ix < map->nx; ix++) {
            double sv = map->sigma_m[iy * map->nx + ix], rgb[3];
            uint32_t px = 0;
            if (isfinite(sv)) {
                viridis(sv / vmax, rgb);
                px = 0xff000000u | (uint32_t)(rgb[0] * 255 + 0.5) << 16 | (uint32_t)(rgb[1] * 255 + 0.5) << 8 |
                     (uint32_t)(rgb[2] * 255 + 0.5);
            }
            // image row 0 is the NORTHERNMOST row of cells
            memcpy(data + (size_t)(map->ny - 1 - iy) * (size_t)stride + 4 * (size_t)ix, &px, 4);
        }
    cairo_surface_mark_dirty(img);
    double x0, y0;
    map_xy(v, map->e0_m - map->cell_m / 2, map->n0_m + (map->ny - 0.5) * map->cell_m, &x0, &y0);
    cairo_save(cr);
    cairo_translate(cr, x0, y0);
    cairo_scale(cr, v->k * map->cell_m, v->k * map->cell_m);
    cairo_set_source_surface(cr, img, 0, 0);
    cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
    cairo_paint_with_alpha(cr, 0.85);
    cairo_restore(cr);
    cairo_surface_destroy(img);
    for (int k = 1; k <= 4; k++) map_contour(cr, v, map, vmax * k / 5, fs);
}

// The colour bar in the strip [w - cbar_w, w] on the right.
static void map_colourbar(cairo_t *cr, double w, double h, double cbar_w, double fs, double vmax,
                          double detection_sigma_px)
{
    double bx = w - cbar_w + fs * 1.2, by = fs * 5, bw = fs * 1.2, bh = h - fs * 10;
    for (int i = 0; i < 100; i++) {
        double rgb[3];
        viridis((i + 0.5) / 100, rgb);
        cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
        cairo_rectangle(cr, bx, by + bh * (1 - (i + 1) / 100.0), bw, bh / 100 + 0.5);
        cairo_fill(cr);
    }
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, fs * 0.08);
    cairo_rectangle(cr, bx, by, bw, bh);
    cairo_stroke(cr);
    font(cr, fs * 0.8, false);
    char buf[32];
    for (int k = 0; k <= 5; k++) {
        double y = by + bh * (1 - k / 5.0);
        cairo_move_to(cr, bx + bw, y);
        cairo_line_to(cr, bx + bw + fs * 0.3, y);
        cairo_stroke(cr);
        snprintf(buf, sizeof buf, k == 5 ? ">=%g" : "%g", vmax * k / 5);
        cairo_move_to(cr, bx + bw + fs * 0.45, y + fs * 0.3);
        rs_doc_show_text(cr, buf);
    }
    font(cr, fs * 0.8, true);
    static const char *title[3] = {"1-sigma", "ground", "error, m"};
    for (int k = 0; k < 3; k++) {
        cairo_move_to(cr, w - fs * 0.4 - text_w(cr, title[k]), by - fs * (3.4 - k));
        rs_doc_show_text(cr, title[k]);
    }
    font(cr, fs * 0.7, false);
    snprintf(buf, sizeof buf, "(%g px", detection_sigma_px);
    cairo_move_to(cr, w - fs * 0.4 - text_w(cr, buf), by + bh + fs * 1.2);
    rs_doc_show_text(cr, buf);
    cairo_move_to(cr, w - fs * 0.4 - text_w(cr, "detection)"), by + bh + fs * 2.1);
    rs_doc_show_text(cr, "detection)");
}

void rs_report_draw_camera_map(cairo_t *cr, double w, double h, const void *ctx)
{
    const rs_report_camera *cam = ctx;
    const struct rs_report_ctx *rep = cam->rep;
    const rs_audit_map *map = cam->has_audit && cam->audit.map.sigma_m ? &cam->audit.map : NULL;
    double fs = w / 65;

    double ext[4] = {INFINITY, -INFINITY, INFINITY, -INFINITY};
    extent_add(ext, cam->position_enu_m[0], cam->position_enu_m[1]);
    for (int i = 0; i < cam->Nfov; i++) extent_add(ext, cam->fov_en_m[2 * i], cam->fov_en_m[2 * i + 1]);
    for (int i = 0; i < cam->N; i++)
        if (cam->landmarks[i].ilandmark >= 0) {
            const double *p = rep->site->landmarks[cam->landmarks[i].ilandmark].p_enu_m;
            extent_add(ext, p[0], p[1]);
        }
    double cbar_w = map ? fs * 7 : 0; // room on the right for the colour bar
    map_view v = map_fit(ext[0], ext[1], ext[2], ext[3], w - cbar_w, h, fs * 4); // room for the furniture

    cairo_set_source_rgb(cr, 0.97, 0.97, 0.96);
    cairo_paint(cr);
    double vmax = map ? nice_ceil(fmax(map_p90(map), 1e-3)) : 0;
    if (map) map_field(cr, &v, map, vmax, fs);
    map_lanes(cr, &v, &rep->lanes, fs * 0.15);
    map_fov(cr, &v, cam, map ? 0 : 0.15, fs * 0.12);
    map_landmarks(cr, &v, rep, cam, fs, true);
    map_camera(cr, &v, cam, fs);
    map_furniture(cr, &v, w - cbar_w, h, fs);
    if (map)
        map_colourbar(cr, w, h, cbar_w, fs, vmax, map->detection_sigma_px);
    else {
        font(cr, fs, false);
        cairo_set_source_rgb(cr, 0.5, 0.1, 0.1);
        cairo_move_to(cr, fs, fs * 1.5);
        rs_doc_show_text(cr, "no uncertainty map (the audit did not run: see below)");
    }
}

void rs_report_draw_site_map(cairo_t *cr, double w, double h, const void *ctx)
{
    const struct rs_report_ctx *rep = ctx;
    const rs_site *site = rep->site;
    double fs = w / 65;
    double ext[4] = {INFINITY, -INFINITY, INFINITY, -INFINITY};
    for (int i = 0; i < site->Nlandmarks; i++) extent_add(ext, site->landmarks[i].p_enu_m[0], site->landmarks[i].p_enu_m[1]);
    for (int c = 0; c < rep->Ncameras; c++) {
        const rs_report_camera *cam = &rep->cameras[c];
        extent_add(ext, cam->position_enu_m[0], cam->position_enu_m[1]);
    }
    if (!isfinite(ext[0])) ext[0] = ext[2] = -10, ext[1] = ext[3] = 10;
    // show the fields of view around the landmarks, not all the way to range_m
    double pad = fmax(10, 0.35 * fmax(ext[1] - ext[0], ext[3] - ext[2]));
    const rs_audit_map *best = rep->best_map.sigma_m ? &rep->best_map : NULL;
    double cbar_w = best ? fs * 7 : 0; // room on the right for the colour bar
    double wmap = w - cbar_w;
    map_view v = map_fit(ext[0] - pad, ext[1] + pad, ext[2] - pad, ext[3] + pad, wmap, h, fs * 2);

    cairo_set_source_rgb(cr, 0.97, 0.97, 0.96);
    cairo_paint(cr);
    cairo_save(cr);
    cairo_rectangle(cr, 0, 0, wmap, h);
    cairo_clip(cr);
    double vmax = best ? nice_ceil(fmax(map_p90(best), 1e-3)) : 0;
    if (best) map_field(cr, &v, best, vmax, fs);
    // a light ENU graticule
    double step = nice_ceil(0.12 * w / v.k);
    cairo_set_source_rgb(cr, 0.85, 0.85, 0.85);
    cairo_set_line_width(cr, fs * 0.05);
    font(cr, fs * 0.7, false);
    for (double e = ceil(-v.ox / v.k / step) * step; v.ox + v.k * e < wmap; e += step) {
        cairo_move_to(cr, v.ox + v.k * e, 0);
        cairo_line_to(cr, v.ox + v.k * e, h);
    }
    for (double n = ceil((v.oy - h) / v.k / step) * step; v.oy - v.k * n > 0; n += step) {
        cairo_move_to(cr, 0, v.oy - v.k * n);
        cairo_line_to(cr, wmap, v.oy - v.k * n);
    }
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0.5, 0.5, 0.5);
    char buf[64];
    for (double e = ceil(-v.ox / v.k / step) * step; v.ox + v.k * e < wmap; e += step) {
        snprintf(buf, sizeof buf, "E %g", e);
        cairo_move_to(cr, v.ox + v.k * e + fs * 0.2, h - fs * 2.6);
        rs_doc_show_text(cr, buf);
    }
    for (double n = ceil((v.oy - h) / v.k / step) * step; v.oy - v.k * n > 0; n += step) {
        snprintf(buf, sizeof buf, "N %g", n);
        cairo_move_to(cr, fs * 0.2, v.oy - v.k * n - fs * 0.2);
        rs_doc_show_text(cr, buf);
    }

    for (int c = 0; c < rep->Ncameras; c++) map_fov(cr, &v, &rep->cameras[c], best ? 0 : 0.12, fs * 0.1);
    map_lanes(cr, &v, &rep->lanes, fs * 0.15);
    map_landmarks(cr, &v, rep, NULL, fs, site->Nlandmarks <= 80);
    for (int c = 0; c < rep->Ncameras; c++) map_camera(cr, &v, &rep->cameras[c], fs);
    map_furniture(cr, &v, wmap, h, fs);
    // origin
    double x, y;
    map_xy(&v, 0, 0, &x, &y);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, fs * 0.1);
    draw_marker_cross(cr, x, y, fs * 0.5);
    cairo_stroke(cr);
    font(cr, fs * 0.75, false);
    label(cr, x + fs * 0.5, y + fs * 1.1, "origin", 0.6);
    cairo_restore(cr);
    if (best) map_colourbar(cr, w, h, cbar_w, fs, vmax, best->detection_sigma_px);
}

bool rs_report_best_map(struct rs_report_ctx *rep)
{
    rs_audit_map *b = &rep->best_map;
    memset(b, 0, sizeof *b);
    double e0 = INFINITY, e1 = -INFINITY, n0 = INFINITY, n1 = -INFINITY, cell = 0;
    for (int c = 0; c < rep->Ncameras; c++) {
        const rs_report_camera *cam = &rep->cameras[c];
        if (!cam->has_audit || !cam->audit.map.sigma_m) continue;
        const rs_audit_map *m = &cam->audit.map;
        if (cell == 0 || m->cell_m < cell) cell = m->cell_m;
        e0 = fmin(e0, m->e0_m), n0 = fmin(n0, m->n0_m);
        e1 = fmax(e1, m->e0_m + (m->nx - 1) * m->cell_m), n1 = fmax(n1, m->n0_m + (m->ny - 1) * m->cell_m);
        b->detection_sigma_px = m->detection_sigma_px;
        b->range_m = m->range_m;
    }
    if (!(cell > 0)) return true;
    int nx = (int)ceil((e1 - e0) / cell) + 1, ny = (int)ceil((n1 - n0) / cell) + 1;
    if (nx > 4000 || ny > 4000) { // keep the figure's image reasonable: coarser cells
        double f = fmax(nx, ny) / 4000.0;
        cell *= f;
        nx = (int)ceil((e1 - e0) / cell) + 1, ny = (int)ceil((n1 - n0) / cell) + 1;
    }
    b->sigma_m = malloc((size_t)nx * (size_t)ny * sizeof *b->sigma_m);
    if (!b->sigma_m) return false;
    b->e0_m = e0, b->n0_m = n0, b->cell_m = cell, b->nx = nx, b->ny = ny;
    for (int iy = 0; iy < ny; iy++)
        for (int ix = 0; ix < nx; ix++) {
            double e = e0 + ix * cell, n = n0 + iy * cell, best = NAN;
            for (int c = 0; c < rep->Ncameras; c++) {
                const rs_report_camera *cam = &rep->cameras[c];
                if (!cam->has_audit || !cam->audit.map.sigma_m) continue;
                const rs_audit_map *m = &cam->audit.map;
                long jx = lround((e - m->e0_m) / m->cell_m), jy = lround((n - m->n0_m) / m->cell_m);
                if (jx < 0 || jy < 0 || jx >= m->nx || jy >= m->ny) continue;
                double sv = m->sigma_m[jy * m->nx + jx];
                if (isfinite(sv) && !(sv >= best)) best = sv;
            }
            b->sigma_m[iy * nx + ix] = best;
        }
    return true;
}

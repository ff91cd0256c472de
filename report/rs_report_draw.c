// rs_report_draw.c -- the drawing helpers the report's figures share
// (report/internal/rs_report_draw_internal.h) and the cameras' figure geometry
// (rs_report_camera_geometry). The figures: rs_report_draw_image.c, rs_report_draw_map.c.
#include "report/internal/rs_report_draw.h"
#include "core/rs_lens.h"
#include "core/rs_pose.h"
#include "core/rs_stats.h"
#include "report/internal/rs_report_doc.h"
#include "report/internal/rs_report_draw_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mrcal/mrcal.h>
#include <mrcal/poseutils.h>

// ---- small helpers ----

// The smallest 1-2-5 number >= x (x > 0).
double rs_report_nice_ceil(double x)
{
    double e = pow(10, floor(log10(x)));
    for (int i = 0; i < 4; i++) {
        static const double m[4] = {1, 2, 5, 10};
        if (m[i] * e >= x * (1 - 1e-9)) return m[i] * e;
    }
    return 10 * e;
}

// Qualitative palette for cameras (Tableau 10).
void rs_report_camera_rgb(cairo_t *cr, int k, double alpha)
{
    static const double pal[10][3] = {{0.12, 0.47, 0.71}, {1.00, 0.50, 0.05}, {0.17, 0.63, 0.17}, {0.84, 0.15, 0.16},
                                      {0.58, 0.40, 0.74}, {0.55, 0.34, 0.29}, {0.89, 0.47, 0.76}, {0.50, 0.50, 0.50},
                                      {0.74, 0.74, 0.13}, {0.09, 0.75, 0.81}};
    const double *c = pal[k % 10];
    cairo_set_source_rgba(cr, c[0], c[1], c[2], alpha);
}

// Viridis, sampled at 9 stops and interpolated linearly; t in [0,1].
void rs_report_viridis(double t, double rgb[3])
{
    static const double stop[9][3] = {{68, 1, 84},    {71, 44, 122}, {59, 81, 139},  {44, 113, 142}, {33, 144, 141},
                                      {39, 173, 129}, {92, 200, 99}, {170, 220, 50}, {253, 231, 37}};
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double x = t * 8;
    int i = (int)x;
    if (i > 7) i = 7;
    double f = x - i;
    for (int k = 0; k < 3; k++) rgb[k] = ((1 - f) * stop[i][k] + f * stop[i + 1][k]) / 255;
}

void rs_report_font(cairo_t *cr, double size, bool bold)
{
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                           bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, size);
}

// Text with its left baseline at (x, y) on a translucent white box.
void rs_report_label(cairo_t *cr, double x, double y, const char *s, double box_alpha)
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

double rs_report_text_w(cairo_t *cr, const char *s)
{
    cairo_text_extents_t e;
    rs_doc_text_extents(cr, s, &e);
    return e.x_advance;
}

void rs_report_marker_circle(cairo_t *cr, double x, double y, double r)
{
    cairo_new_sub_path(cr);
    cairo_arc(cr, x, y, r, 0, 2 * M_PI);
}

void rs_report_marker_cross(cairo_t *cr, double x, double y, double r)
{
    cairo_move_to(cr, x - r, y - r);
    cairo_line_to(cr, x + r, y + r);
    cairo_move_to(cr, x - r, y + r);
    cairo_line_to(cr, x + r, y - r);
}

// ---- the cameras' figure geometry ----

bool rs_report_camera_geometry(rs_report_camera *cam)
{
    const rs_camera *m = &cam->model;
    const rs_site *site = cam->rep->site;
    double W = m->width, H = m->height;

    cam->max_tan = rs_camera_max_tan(m); // the lens's valid field (core/rs_camera.h)

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
            if (!rs_lens_unproject(&v, &q, 1, &m->lensmodel, m->intrinsics)) continue;
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

    // magnification: median inlier residual (surveyed, as drawn) drawn as ~1.5% of the image width
    double *r = malloc((size_t)(cam->N > 0 ? cam->N : 1) * sizeof *r);
    if (!r) return false;
    int Nr = 0;
    for (int i = 0; i < cam->N; i++) {
        const double *d = cam->landmarks[i].residual_surveyed_px;
        if (cam->landmarks[i].inlier && isfinite(d[0]) && isfinite(d[1])) r[Nr++] = hypot(d[0], d[1]);
    }
    const double med = Nr ? rs_stats_median(r, Nr) : 0;
    free(r);
    double target = 0.015 * W;
    cam->magnification = med > 1e-6 ? rs_report_nice_ceil(target / med) / 2 : 1;
    if (cam->magnification < 1) cam->magnification = 1;
    return true;
}

// ---- label placement ----

static void placer_log(const rs_report_placer *p, const char *kind, const double b[4], const char *s);

void rs_report_placer_init(rs_report_placer *p, const char *figure, double w, double h)
{
    memset(p, 0, sizeof *p);
    p->figure = figure;
    p->w = w, p->h = h;
    const double none[4] = {0, 0, 0, 0};
    placer_log(p, "begin", none, NULL);
}

void rs_report_placer_free(rs_report_placer *p)
{
    free(p->box);
    memset(p, 0, sizeof *p);
}

static void placer_log(const rs_report_placer *p, const char *kind, const double b[4], const char *s)
{
    const char *path = getenv("ROADSIDE_REPORT_LABEL_BOXES");
    if (!path || !*path || p->w <= 400) return;
    FILE *f = fopen(path, "a");
    if (!f) return;
    fprintf(f, "%s %s %.3f %.3f %.3f %.3f %.3f %.3f %s\n", p->figure, kind, b[0], b[1], b[2], b[3], p->w, p->h,
            s ? s : "-");
    fclose(f);
}

static bool placer_add(rs_report_placer *p, const double b[4])
{
    if (p->N == p->capacity) {
        int cap = p->capacity ? 2 * p->capacity : 64;
        double(*nb)[4] = realloc(p->box, (size_t)cap * sizeof *nb);
        if (!nb) return false;
        p->box = nb, p->capacity = cap;
    }
    memcpy(p->box[p->N++], b, 4 * sizeof(double));
    return true;
}

void rs_report_placer_reserve(rs_report_placer *p, double x0, double y0, double x1, double y1)
{
    const double b[4] = {fmin(x0, x1), fmin(y0, y1), fmax(x0, x1), fmax(y0, y1)};
    if (placer_add(p, b)) placer_log(p, "reserved", b, NULL);
}

bool rs_report_placer_label(rs_report_placer *p, cairo_t *cr, double x, double y, double gap, const char *s,
                            double box_alpha)
{
    cairo_text_extents_t e;
    rs_doc_text_extents(cr, s, &e);
    const double pad = 0.25 * e.height + 1, bw = e.width + 2 * pad, bh = e.height + 2 * pad;
    // the box's top-left corner for each candidate, relative to the anchor
    for (int ring = 0; ring < 2; ring++, gap = 3 * gap + bh) { // then once more, farther out
        const double cx[8] = {gap, -gap - bw, gap, -gap - bw, gap, -gap - bw, -bw / 2, -bw / 2};
        const double cy[8] = {-gap - bh, -gap - bh, gap, gap, -bh / 2, -bh / 2, -gap - bh, gap};
        for (int k = 0; k < 8; k++) {
            const double b[4] = {x + cx[k], y + cy[k], x + cx[k] + bw, y + cy[k] + bh};
            bool free_place = b[0] >= 0 && b[1] >= 0 && b[2] <= p->w && b[3] <= p->h;
            for (int i = 0; i < p->N && free_place; i++)
                free_place =
                    b[2] <= p->box[i][0] || b[0] >= p->box[i][2] || b[3] <= p->box[i][1] || b[1] >= p->box[i][3];
            if (!free_place) continue;
            if (placer_add(p, b)) placer_log(p, "label", b, s);
            // rs_report_label puts the box at (x + x_bearing - pad, y + y_bearing - pad)
            rs_report_label(cr, b[0] + pad - e.x_bearing, b[1] + pad - e.y_bearing, s, box_alpha);
            return true;
        }
    }
    return false;
}

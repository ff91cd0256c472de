// rs_report_draw_map.c -- the report's top-down ENU maps: around one camera
// (rs_report_draw_camera_map) and of the whole site (rs_report_draw_site_map), with the layers
// they share (lanes, fields of view, cameras, landmarks, uncertainty field and contours, colour
// bar, scale and north arrow), and the site's best uncertainty map (rs_report_best_map).
#include "report/internal/rs_report_doc.h"
#include "report/internal/rs_report_draw.h"
#include "report/internal/rs_report_draw_internal.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
    for (int pass = 0; pass < 2; pass++) { // edges, then junction connectors thin and light (solid: dashes
                                           // on dozens of crossing curves read as scattered specks)
        cairo_set_source_rgba(cr, 0.85, 0.65, 0, pass ? 0.45 : 0.9);
        cairo_set_line_width(cr, pass ? lw / 2.5 : lw);
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
        rs_report_camera_rgb(cr, cam->colour, fill_alpha);
        cairo_fill_preserve(cr);
    }
    rs_report_camera_rgb(cr, cam->colour, 1);
    cairo_set_line_width(cr, lw);
    double dash = lw * 4;
    cairo_set_dash(cr, &dash, 1, 0);
    cairo_stroke(cr);
    cairo_set_dash(cr, NULL, 0, 0);
}

// The camera: a filled disc and an arrow along its heading, with its id.
static void map_camera(cairo_t *cr, const map_view *v, const rs_report_camera *cam, double fs, rs_report_placer *pl)
{
    double x, y, yaw = cam->yaw_pitch_roll_deg[0] * M_PI / 180;
    map_xy(v, cam->position_enu_m[0], cam->position_enu_m[1], &x, &y);
    double L = fs * 2.5;
    rs_report_camera_rgb(cr, cam->colour, 1);
    cairo_set_line_width(cr, fs * 0.2);
    cairo_move_to(cr, x, y);
    cairo_line_to(cr, x + L * sin(yaw), y - L * cos(yaw));
    cairo_stroke(cr);
    rs_report_marker_circle(cr, x, y, fs * 0.45);
    cairo_fill_preserve(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, fs * 0.08);
    cairo_stroke(cr);
    rs_report_font(cr, fs, true);
    rs_report_placer_label(pl, cr, x, y, fs * 0.5, cam->rep->site->cameras[cam->icam].id, 0.7);
}

// The camera's disc as a reserved box (labels keep off it).
static void map_camera_reserve(const map_view *v, const rs_report_camera *cam, double fs, rs_report_placer *pl)
{
    double x, y;
    map_xy(v, cam->position_enu_m[0], cam->position_enu_m[1], &x, &y);
    rs_report_placer_reserve(pl, x - fs * 0.5, y - fs * 0.5, x + fs * 0.5, y + fs * 0.5);
}

// Scale bar (bottom left) and north arrow (top left): their boxes reserved first (reserve true),
// then drawn last (reserve false), over everything else.
static void map_furniture(cairo_t *cr, const map_view *v, double w, double h, double fs, rs_report_placer *pl,
                          bool reserve)
{
    double len_m = rs_report_nice_ceil(0.18 * w / v->k), len = len_m * v->k;
    if (len > 0.3 * w) len_m /= 2, len /= 2;
    double x = fs, y = h - fs;
    double nx = fs * 1.6, ny = fs * 1.2;
    if (reserve) {
        rs_report_placer_reserve(pl, x - fs * 0.4, y - fs * 1.7, x + len + fs * 4.1, y + fs * 0.5);
        rs_report_placer_reserve(pl, nx - fs * 0.8, ny - fs * 0.3, nx + fs * 0.8, ny + fs * 3.6);
        return;
    }
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
    rs_report_font(cr, fs, false);
    cairo_move_to(cr, x + len + fs * 0.4, y);
    rs_doc_show_text(cr, buf);

    cairo_move_to(cr, nx, ny);
    cairo_line_to(cr, nx - fs * 0.6, ny + fs * 2);
    cairo_line_to(cr, nx, ny + fs * 1.5);
    cairo_line_to(cr, nx + fs * 0.6, ny + fs * 2);
    cairo_close_path(cr);
    cairo_fill(cr);
    rs_report_font(cr, fs, true);
    cairo_move_to(cr, nx - fs * 0.35, ny + fs * 3.3);
    rs_doc_show_text(cr, "N");
}

// Landmarks of the site: observed by `cam` (if not NULL) drawn as inlier / outlier, the rest
// as small grey dots; ids written when `ids`.
static void map_camera(cairo_t *cr, const map_view *v, const rs_report_camera *cam, double fs, rs_report_placer *pl);

// ... then the cameras (`cam` alone, else every camera of rep), their labels placed after every
// marker is reserved and before the landmarks' ids.
static void map_landmarks(cairo_t *cr, const map_view *v, const struct rs_report_ctx *rep, const rs_report_camera *cam,
                          double fs, bool ids, rs_report_placer *pl)
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
            rs_report_marker_cross(cr, x, y, fs * 0.4);
            cairo_stroke(cr);
        } else {
            if (state == 1)
                cairo_set_source_rgb(cr, 0, 0, 0);
            else
                cairo_set_source_rgb(cr, 0.45, 0.45, 0.45);
            rs_report_marker_circle(cr, x, y, fs * (state ? 0.28 : 0.18));
            cairo_fill(cr);
        }
        if (ids && (state || !cam))
            rs_report_placer_reserve(pl, x - fs * 0.2, y - fs * 0.2, x + fs * 0.2, y + fs * 0.2);
    }
    if (cam)
        map_camera(cr, v, cam, fs, pl);
    else
        for (int c = 0; c < rep->Ncameras; c++) map_camera(cr, v, &rep->cameras[c], fs, pl);
    // the ids, once every marker is reserved, in site order
    for (int i = 0; ids && i < site->Nlandmarks; i++) {
        bool seen = !cam;
        for (int k = 0; cam && k < cam->N; k++) seen |= cam->landmarks[k].ilandmark == i;
        if (!seen) continue;
        double x, y;
        map_xy(v, site->landmarks[i].p_enu_m[0], site->landmarks[i].p_enu_m[1], &x, &y);
        rs_report_font(cr, fs * 0.7, false);
        cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
        rs_report_placer_label(pl, cr, x, y, fs * 0.25, site->landmarks[i].id, 0.6);
    }
}

// Contour segments of `map` at `level` by marching squares over the cell centres (cells with a
// NaN corner are skipped); up to 3 places far apart get the level written next to them. need:
// the level is the site's need (drawn thick and red, labelled so).
static void map_contour(cairo_t *cr, const map_view *v, const rs_audit_map *map, double level, bool need, double fs,
                        rs_report_placer *pl)
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
                if (!pl) {
                    cairo_move_to(cr, x0, y0);
                    cairo_line_to(cr, x1, y1);
                }
                bool far = Nlab < 3;
                for (int j = 0; j < Nlab && far; j++) far = hypot(x0 - lx[j], y0 - ly[j]) > 20 * fs;
                if (far) lx[Nlab] = x0, ly[Nlab] = y0, Nlab++;
            }
        }
    if (!pl) { // the lines: the need's own contour thick and red, the others thin and white
        if (need)
            cairo_set_source_rgba(cr, 0.85, 0.1, 0.1, 0.95);
        else
            cairo_set_source_rgba(cr, 1, 1, 1, 0.9);
        cairo_set_line_width(cr, fs * (need ? 0.3 : 0.12));
        cairo_stroke(cr);
        return;
    }
    char buf[48]; // the labels, where they find room
    snprintf(buf, sizeof buf, need ? "%g m (need)" : "%g m", level);
    rs_report_font(cr, fs * 0.8, true);
    cairo_set_source_rgb(cr, 0, 0, 0);
    for (int j = 0; j < Nlab; j++) rs_report_placer_label(pl, cr, lx[j], ly[j], fs * 0.1, buf, 0.75);
}

// The colour scale of the uncertainty maps, anchored at the need (rs_audit_options.need_ground_m):
// 0 .. 2 x need, contours at need/2, need (the need's own, drawn red) and 3 need/2, so a map shows
// at a glance where the site meets its need and where it does not.
enum { MAP_NCONTOURS = 3 };
static double map_vmax(const struct rs_report_ctx *rep)
{
    const double need =
        rep->audit_options && rep->audit_options->need_ground_m > 0 ? rep->audit_options->need_ground_m : 1;
    return 2 * need;
}

// An orthophoto on the ENU grid under the map: its pixel (i, j) centred at (e0 + i cell, n0 - j cell).
static void map_ortho(cairo_t *cr, const map_view *v, const rs_geo_ortho *o)
{
    const rs_geo_grid *g = &o->grid;
    cairo_surface_t *img = cairo_image_surface_create(CAIRO_FORMAT_RGB24, g->width, g->height);
    cairo_surface_flush(img);
    unsigned char *data = cairo_image_surface_get_data(img);
    const int stride = cairo_image_surface_get_stride(img);
    for (int j = 0; j < g->height && data; j++)
        for (int i = 0; i < g->width; i++) {
            const unsigned char *p = &o->rgb[3 * ((size_t)j * (size_t)g->width + (size_t)i)];
            const uint32_t px = 0xff000000u | (uint32_t)p[0] << 16 | (uint32_t)p[1] << 8 | p[2];
            memcpy(data + (size_t)j * (size_t)stride + 4 * (size_t)i, &px, 4);
        }
    cairo_surface_mark_dirty(img);
    double x0, y0;
    map_xy(v, g->e0_m - g->cell_m / 2, g->n0_m + g->cell_m / 2, &x0, &y0);
    cairo_save(cr);
    cairo_translate(cr, x0, y0);
    cairo_scale(cr, v->k * g->cell_m, v->k * g->cell_m);
    cairo_set_source_surface(cr, img, 0, 0);
    cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_GOOD);
    cairo_paint(cr);
    cairo_restore(cr);
    cairo_surface_destroy(img);
}

// The map's colour field (one image pixel per cell, painted at the cells' place) and its
// contours at 1/4 .. 3/4 of vmax (map_vmax).
static void map_field(cairo_t *cr, const map_view *v, const rs_audit_map *map, double alpha, double vmax, double fs)
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
                rs_report_viridis(sv / vmax, rgb);
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
    cairo_paint_with_alpha(cr, alpha);
    cairo_restore(cr);
    cairo_surface_destroy(img);
    for (int k = 1; k <= MAP_NCONTOURS; k++) map_contour(cr, v, map, vmax * k / 4, k == 2, fs, NULL);
}

// The contour labels (after the other labels: they give way).
static void map_contour_labels(cairo_t *cr, const map_view *v, const rs_audit_map *map, double vmax, double fs,
                               rs_report_placer *pl)
{
    for (int k = 1; k <= MAP_NCONTOURS; k++) map_contour(cr, v, map, vmax * k / 4, k == 2, fs, pl);
}

// The colour bar in the strip [w - cbar_w, w] on the right.
static void map_colourbar(cairo_t *cr, double w, double h, double cbar_w, double fs, double vmax,
                          double detection_sigma_px)
{
    double bx = w - cbar_w + fs * 1.2, by = fs * 5, bw = fs * 1.2, bh = h - fs * 10;
    for (int i = 0; i < 100; i++) {
        double rgb[3];
        rs_report_viridis((i + 0.5) / 100, rgb);
        cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
        cairo_rectangle(cr, bx, by + bh * (1 - (i + 1) / 100.0), bw, bh / 100 + 0.5);
        cairo_fill(cr);
    }
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, fs * 0.08);
    cairo_rectangle(cr, bx, by, bw, bh);
    cairo_stroke(cr);
    rs_report_font(cr, fs * 0.8, false);
    char buf[32];
    for (int k = 0; k <= 4; k++) { // ticks at 0, need/2, need, 3 need/2, >= 2 need
        double y = by + bh * (1 - k / 4.0);
        cairo_move_to(cr, bx + bw, y);
        cairo_line_to(cr, bx + bw + fs * 0.3, y);
        cairo_stroke(cr);
        snprintf(buf, sizeof buf, k == 4 ? ">=%g" : k == 2 ? "%g (need)" : "%g", vmax * k / 4);
        cairo_move_to(cr, bx + bw + fs * 0.45, y + fs * 0.3);
        rs_doc_show_text(cr, buf);
    }
    rs_report_font(cr, fs * 0.8, true);
    static const char *title[3] = {"1-sigma", "ground", "error, m"};
    for (int k = 0; k < 3; k++) {
        cairo_move_to(cr, w - fs * 0.4 - rs_report_text_w(cr, title[k]), by - fs * (3.4 - k));
        rs_doc_show_text(cr, title[k]);
    }
    rs_report_font(cr, fs * 0.7, false);
    snprintf(buf, sizeof buf, "(%g px", detection_sigma_px);
    cairo_move_to(cr, w - fs * 0.4 - rs_report_text_w(cr, buf), by + bh + fs * 1.2);
    rs_doc_show_text(cr, buf);
    cairo_move_to(cr, w - fs * 0.4 - rs_report_text_w(cr, "detection)"), by + bh + fs * 2.1);
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
    double cbar_w = map ? fs * 7 : 0;                                            // room on the right for the colour bar
    map_view v = map_fit(ext[0], ext[1], ext[2], ext[3], w - cbar_w, h, fs * 4); // room for the furniture

    cairo_set_source_rgb(cr, 0.97, 0.97, 0.96);
    cairo_paint(cr);
    rs_report_placer pl;
    rs_report_placer_init(&pl, "camera_map", w - cbar_w, h);
    map_furniture(cr, &v, w - cbar_w, h, fs, &pl, true);
    double vmax = map ? map_vmax(rep) : 0;
    if (map) map_field(cr, &v, map, 0.85, vmax, fs);
    map_lanes(cr, &v, &rep->lanes, fs * 0.15);
    map_fov(cr, &v, cam, map ? 0 : 0.15, fs * 0.12);
    map_camera_reserve(&v, cam, fs, &pl);
    map_landmarks(cr, &v, rep, cam, fs, true, &pl);
    if (map) map_contour_labels(cr, &v, map, vmax, fs, &pl);
    map_furniture(cr, &v, w - cbar_w, h, fs, &pl, false);
    rs_report_placer_free(&pl);
    if (map)
        map_colourbar(cr, w, h, cbar_w, fs, vmax, map->detection_sigma_px);
    else {
        rs_report_font(cr, fs, false);
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
    for (int i = 0; i < site->Nlandmarks; i++)
        extent_add(ext, site->landmarks[i].p_enu_m[0], site->landmarks[i].p_enu_m[1]);
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
    rs_report_placer pl;
    rs_report_placer_init(&pl, "site_map", wmap, h);
    map_furniture(cr, &v, wmap, h, fs, &pl, true);
    if (rep->ortho.rgb) map_ortho(cr, &v, &rep->ortho);
    double vmax = best ? map_vmax(rep) : 0;
    if (best) map_field(cr, &v, best, rep->ortho.rgb ? 0.5 : 0.85, vmax, fs);
    // a light ENU graticule
    double step = rs_report_nice_ceil(0.12 * w / v.k);
    cairo_set_source_rgb(cr, 0.8, 0.8, 0.8);
    cairo_set_line_width(cr, fs * 0.05);
    for (double e = ceil(-v.ox / v.k / step) * step; v.ox + v.k * e < wmap; e += step) {
        cairo_move_to(cr, v.ox + v.k * e, 0);
        cairo_line_to(cr, v.ox + v.k * e, h);
    }
    for (double n = ceil((v.oy - h) / v.k / step) * step; v.oy - v.k * n > 0; n += step) {
        cairo_move_to(cr, 0, v.oy - v.k * n);
        cairo_line_to(cr, wmap, v.oy - v.k * n);
    }
    cairo_stroke(cr);
    // the axis labels (metres east / north of the origin): E along the top, N down the left,
    // on white boxes, reserved before the map's own labels
    rs_report_font(cr, fs * 0.8, false);
    cairo_set_source_rgb(cr, 0.25, 0.25, 0.25);
    char buf[64];
    for (double e = ceil(-v.ox / v.k / step) * step; v.ox + v.k * e < wmap; e += step) {
        snprintf(buf, sizeof buf, "E %g m", e == 0 ? 0 : e);
        rs_report_placer_label(&pl, cr, v.ox + v.k * e, 0, fs * 0.15, buf, 0.8);
    }
    for (double n = ceil((v.oy - h) / v.k / step) * step; v.oy - v.k * n > 0; n += step) {
        snprintf(buf, sizeof buf, "N %g m", n == 0 ? 0 : n);
        rs_report_placer_label(&pl, cr, 0, v.oy - v.k * n, fs * 0.15, buf, 0.8);
    }

    for (int c = 0; c < rep->Ncameras; c++) map_fov(cr, &v, &rep->cameras[c], best ? 0 : 0.12, fs * 0.1);
    map_lanes(cr, &v, &rep->lanes, fs * 0.15);
    // origin
    double x, y;
    map_xy(&v, 0, 0, &x, &y);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, fs * 0.1);
    rs_report_marker_cross(cr, x, y, fs * 0.5);
    cairo_stroke(cr);
    rs_report_placer_reserve(&pl, x - fs * 0.5, y - fs * 0.5, x + fs * 0.5, y + fs * 0.5);
    for (int c = 0; c < rep->Ncameras; c++) map_camera_reserve(&v, &rep->cameras[c], fs, &pl);
    map_landmarks(cr, &v, rep, NULL, fs, site->Nlandmarks <= 80, &pl);
    rs_report_font(cr, fs * 0.75, false);
    cairo_set_source_rgb(cr, 0, 0, 0);
    rs_report_placer_label(&pl, cr, x, y, fs * 0.5, "origin", 0.6);
    if (best) map_contour_labels(cr, &v, best, vmax, fs, &pl);
    map_furniture(cr, &v, wmap, h, fs, &pl, false);
    rs_report_placer_free(&pl);
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

// rs_report_plot.c -- log-log scatter panels as a PNG (see rs_report_plot.h).
#include "report/rs_report_plot.h"
#include "core/rs_io.h"
#include "report/internal/rs_report_doc.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cairo.h>

static void series_colour(int m, double rgb[3])
{
    // hues spread around the circle, lightness alternating so neighbours stay apart
    const double h = 6.0 * fmod(m * 0.61803398875, 1.0);
    const double v = (m % 2) ? 0.85 : 0.55, s = 0.9;
    const int i = (int)h;
    const double f = h - i, p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
    const double tab[6][3] = {{v, t, p}, {q, v, p}, {p, v, t}, {p, q, v}, {t, p, v}, {v, p, q}};
    memcpy(rgb, tab[i % 6], sizeof tab[0]);
}

static void marker(cairo_t *cr, const rs_report_plot_loglog *plot, int m, double x, double y)
{
    const double s = 6.0;
    double rgb[3];
    series_colour(m, rgb);
    cairo_new_path(cr);
    cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
    switch (plot->series[m].marker) {
    case RS_REPORT_PLOT_CIRCLE: cairo_arc(cr, x, y, s, 0, 2 * M_PI); break;
    case RS_REPORT_PLOT_SQUARE: cairo_rectangle(cr, x - s, y - s, 2 * s, 2 * s); break;
    case RS_REPORT_PLOT_TRIANGLE:
        cairo_move_to(cr, x, y - s * 1.2);
        cairo_line_to(cr, x + s * 1.1, y + s * 0.8);
        cairo_line_to(cr, x - s * 1.1, y + s * 0.8);
        cairo_close_path(cr);
        break;
    }
    cairo_fill_preserve(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 0.8);
    cairo_stroke(cr);
}

typedef struct {
    double x0, y0, w, h;       // panel in device units
    double lx0, lx1, ly0, ly1; // log10 ranges
} panel;

static double px(const panel *p, double v) { return p->x0 + p->w * (log10(v) - p->lx0) / (p->lx1 - p->lx0); }
static double py(const panel *p, double v) { return p->y0 + p->h - p->h * (log10(v) - p->ly0) / (p->ly1 - p->ly0); }

static void draw_axes(cairo_t *cr, const panel *p, const char *title, const char *x_label)
{
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 1.0);
    cairo_rectangle(cr, p->x0, p->y0, p->w, p->h);
    cairo_stroke(cr);
    cairo_set_font_size(cr, 11);
    char s[32];
    for (int e = (int)ceil(p->lx0); e <= (int)floor(p->lx1); e++) {
        const double x = px(p, pow(10, e));
        cairo_set_source_rgb(cr, 0.85, 0.85, 0.85);
        cairo_move_to(cr, x, p->y0);
        cairo_line_to(cr, x, p->y0 + p->h);
        cairo_stroke(cr);
        cairo_set_source_rgb(cr, 0, 0, 0);
        snprintf(s, sizeof s, "1e%d", e);
        cairo_move_to(cr, x - 10, p->y0 + p->h + 14);
        rs_doc_show_text(cr, s);
    }
    for (int e = (int)ceil(p->ly0); e <= (int)floor(p->ly1); e++) {
        const double y = py(p, pow(10, e));
        cairo_set_source_rgb(cr, e == 0 ? 0.3 : 0.85, e == 0 ? 0.6 : 0.85, e == 0 ? 0.3 : 0.85);
        cairo_move_to(cr, p->x0, y);
        cairo_line_to(cr, p->x0 + p->w, y);
        cairo_stroke(cr);
        cairo_set_source_rgb(cr, 0, 0, 0);
        snprintf(s, sizeof s, "1e%d", e);
        cairo_move_to(cr, p->x0 - 30, y + 4);
        rs_doc_show_text(cr, s);
    }
    cairo_move_to(cr, p->x0 + p->w / 2 - 40, p->y0 + p->h + 28);
    rs_doc_show_text(cr, x_label);
    cairo_set_font_size(cr, 13);
    cairo_move_to(cr, p->x0 + 4, p->y0 - 6);
    rs_doc_show_text(cr, title);
    cairo_new_path(cr);
}

rs_status rs_report_plot_loglog_png(const char *path, const rs_report_plot_loglog *plot, rs_err *err)
{
    if (!(plot && plot->width_px > 0 && plot->height_px > 0 && plot->Npanels >= 0 && plot->Nseries >= 0 &&
          plot->title && plot->x_label && (plot->Npanels == 0 || plot->panel_titles) &&
          (plot->Nseries == 0 || plot->series) && (plot->Npanels * plot->Nseries == 0 || (plot->x && plot->y))))
        return rs_err_set(err, RS_ERR_INVALID, "%s: plot: bad size, counts or missing arrays", path);
    const int Nf = plot->Npanels, Ns = plot->Nseries;
    const double *X = plot->x, *Y = plot->y;

    // common log10 ranges over the finite points; y always includes 1
    double xmin = INFINITY, xmax = -INFINITY, ymin = INFINITY, ymax = -INFINITY;
    for (int i = 0; i < Nf * Ns; i++)
        if (isfinite(X[i]) && isfinite(Y[i])) {
            xmin = fmin(xmin, X[i]);
            xmax = fmax(xmax, X[i]);
            ymin = fmin(ymin, Y[i]);
            ymax = fmax(ymax, Y[i]);
        }
    if (!(xmin <= xmax)) xmin = 1, xmax = 10, ymin = 1, ymax = 10;
    const double lx0 = floor(log10(xmin)), lx1 = fmax(ceil(log10(xmax)), lx0 + 1);
    const double ly0 = fmin(floor(log10(ymin)), 0.0), ly1 = fmax(ceil(log10(ymax)), ly0 + 1);

    const int W = plot->width_px, H = plot->height_px, cols = 4, legend_w = 230;
    const int rows_p = Nf > cols ? (Nf + cols - 1) / cols : 1;
    cairo_surface_t *surf = cairo_image_surface_create(CAIRO_FORMAT_RGB24, W, H);
    cairo_t *cr = cairo_create(surf);
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_font_size(cr, 16);
    cairo_move_to(cr, 20, 24);
    rs_doc_show_text(cr, plot->title);
    const double cw = (double)(W - legend_w - 20) / cols, ch = (double)(H - 50) / rows_p;
    for (int f = 0; f < Nf; f++) {
        panel p = {20 + 50 + (f % cols) * cw, 50 + 20 + (f / cols) * ch, cw - 70, ch - 60, lx0, lx1, ly0, ly1};
        char title[64];
        snprintf(title, sizeof title, "%s", plot->panel_titles[f]);
        draw_axes(cr, &p, title, plot->x_label);
        for (int m = 0; m < Ns; m++) {
            const double x = X[f * Ns + m], y = Y[f * Ns + m];
            if (isfinite(x) && isfinite(y)) marker(cr, plot, m, px(&p, x), py(&p, y));
        }
    }
    cairo_set_font_size(cr, 12);
    for (int m = 0; m < Ns; m++) {
        const double x = W - legend_w + 10, y = 80 + 24.0 * m;
        marker(cr, plot, m, x, y);
        cairo_set_source_rgb(cr, 0, 0, 0);
        cairo_move_to(cr, x + 14, y + 4);
        rs_doc_show_text(cr, plot->series[m].name);
    }
    if (plot->legend_note) {
        cairo_move_to(cr, W - legend_w + 10, 80 + 24.0 * Ns + 10);
        rs_doc_show_text(cr, plot->legend_note);
    }
    cairo_destroy(cr);

    rs_status st = RS_OK;
    if (cairo_surface_status(surf) != CAIRO_STATUS_SUCCESS)
        st =
            rs_err_set(err, RS_ERR_EXTERNAL, "%s: cairo: %s", path, cairo_status_to_string(cairo_surface_status(surf)));
    unsigned char *png = NULL;
    size_t len = 0;
    if (st == RS_OK) st = rs_doc_png(&png, &len, surf, err);
    if (st == RS_OK) st = rs_io_write_file(path, png, len, err);
    free(png);
    cairo_surface_destroy(surf);
    return st;
}

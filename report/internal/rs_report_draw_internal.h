// rs_report_draw_internal.h -- drawing helpers shared by the report's figures
// (report/rs_report_draw*.c): number rounding for scales, palettes, text and markers.
// Internal to report; the figures' API is report/internal/rs_report_draw.h.
//
//   rs_report_draw.c        these helpers; the cameras' figure geometry (rs_report_camera_geometry)
//   rs_report_draw_image.c  the camera's image (rs_report_draw_camera)
//   rs_report_draw_map.c    the top-down maps (rs_report_draw_camera_map, _site_map), the best map
#pragma once
#include <stdbool.h>

#include <cairo.h>

// The smallest 1-2-5 number >= x (x > 0), to 1e-9 relative: 0.3 -> 0.5, 7 -> 10.
double rs_report_nice_ceil(double x);

// Sets cr's source to colour k of the qualitative camera palette (Tableau 10, k modulo 10) with
// the given alpha in [0, 1].
void rs_report_camera_rgb(cairo_t *cr, int k, double alpha);

// Viridis at t (clamped to [0, 1]), sampled at 9 stops and interpolated linearly.
// out: rgb (3,) in [0, 1]
void rs_report_viridis(double t, double rgb[3]);

// Selects the figures' font: sans-serif, `size` user units, bold or normal.
void rs_report_font(cairo_t *cr, double size, bool bold);

// Shows s with its left baseline at (x, y), on a white box of opacity box_alpha (0: no box).
// Leaves the current point after the text; the source is the caller's (the text's colour).
void rs_report_label(cairo_t *cr, double x, double y, const char *s, double box_alpha);

// The advance width of s in the current font, user units.
double rs_report_text_w(cairo_t *cr, const char *s);

// Adds to the path (does not stroke or fill): a circle of radius r as a new sub-path, or an X
// whose arms reach r along both axes, centred at (x, y).
void rs_report_marker_circle(cairo_t *cr, double x, double y, double r);
void rs_report_marker_cross(cairo_t *cr, double x, double y, double r);

// ---- label placement ----
// A figure's labels are placed one by one, each at the first of 8 positions around its anchor
// (right-above, left-above, right-below, left-below, right, left, above, below) whose box
// overlaps no box placed or reserved before and lies inside the figure; a label with no such
// position is not drawn. Reserved boxes are furniture (scale bar, north arrow, colour bar, axis
// labels). With the environment variable ROADSIDE_REPORT_LABEL_BOXES set to a file name, every
// box of a figure drawn at figure width > 400 user units is appended to that file, one line
// "figure kind x0 y0 x1 y1 w h text" (kind: begin -- a new figure --, label or reserved), for tests.
typedef struct {
    double w, h;      // the figure's size, user units
    double (*box)[4]; // (N,4) x0, y0, x1, y1 (owned)
    int N, capacity;
    const char *figure; // the figure's name, for the boxes file
} rs_report_placer;

// Starts an empty placer for figure `figure` of size w x h user units (logs "begin" to the boxes file).
void rs_report_placer_init(rs_report_placer *p, const char *figure, double w, double h);
void rs_report_placer_free(rs_report_placer *p);
// Reserves a box (furniture): later labels avoid it.
void rs_report_placer_reserve(rs_report_placer *p, double x0, double y0, double x1, double y1);
// Places and draws s (current font, source = text colour) near the anchor (x, y), at least gap
// away, on a white box of opacity box_alpha. Returns false when it found no free place.
bool rs_report_placer_label(rs_report_placer *p, cairo_t *cr, double x, double y, double gap, const char *s,
                            double box_alpha);

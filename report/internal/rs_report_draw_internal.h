// rs_report_draw_internal.h -- drawing helpers shared by the report's figures
// (report/rs_report_draw*.c): number rounding for scales, palettes, text and markers.
// Internal to report; the figures' API is report/rs_report_draw.h.
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

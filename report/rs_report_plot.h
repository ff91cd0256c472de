// rs_report_plot.h -- a log-log scatter plot written as a PNG: a row of panels sharing their
// axes, one marker per series in each panel, a legend on the right. Drawn with cairo (report/
// is the project's only cairo user); used by `roadside bench calib --plot`
// (bench/rs_bench_calib.h: median time against position error / Cramer-Rao bound, one panel
// per configuration family, one series per method).
//
// Layout (device pixels, width_px x height_px): the title at the top left; panels 4 to a row
// (fewer panels: one row) to the left of a 230 px legend column; each panel a framed log-log
// plot with a grid line and a "1eK" label at every power of ten, the line y = 1 green (a
// reference, e.g. "at the bound"), x_label under it and its title above. The axes are common to
// all panels: x from the floor to the ceiling of log10 of the finite points' x (at least one
// decade), y the same but always including 1 (log10 0); with no finite point, 1..10 on both.
// Series k is drawn in colour k of a fixed palette (hues spread by the golden ratio, lightness
// alternating) with its marker shape, black outline.
#pragma once

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// Marker shapes.
typedef enum { RS_REPORT_PLOT_CIRCLE = 0, RS_REPORT_PLOT_SQUARE, RS_REPORT_PLOT_TRIANGLE } rs_report_plot_marker;

typedef struct {
    const char *name;             // legend text
    rs_report_plot_marker marker; // its shape
} rs_report_plot_series;

typedef struct {
    int width_px, height_px;             // image size, > 0 (the bench: 1600 x 1000)
    const char *title;                   // one line at the top
    const char *x_label;                 // under every panel
    const char *legend_note;             // one line under the legend; may be NULL
    int Npanels;                         // >= 0
    const char *const *panel_titles;     // (Npanels,) shown up to 63 bytes
    int Nseries;                         // >= 0
    const rs_report_plot_series *series; // (Nseries,)
    const double *x, *y;                 // (Npanels, Nseries) row-major: the point of series s
                                         //   in panel p is (x[p Nseries + s], y[p Nseries + s]),
                                         //   both > 0; a non-finite x or y: no point
} rs_report_plot_loglog;

// Draws `plot` and writes it to `path` as an RGB PNG, atomically (core/rs_io.h).
// Returns RS_ERR_INVALID (non-positive size, negative counts, missing arrays), RS_ERR_EXTERNAL
// (cairo could not draw), RS_ERR_NOMEM, RS_ERR_IO (writing failed; nothing is left at path).
rs_status rs_report_plot_loglog_png(const char *path,
                                    // in
                                    const rs_report_plot_loglog *plot, rs_err *err);

#ifdef __cplusplus
}
#endif

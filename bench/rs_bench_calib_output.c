// rs_bench_calib_output.c -- the outputs of roadside bench calib: the rows as CSV and the plot
// (the per-family figures computed here, drawn by report/rs_report_plot.h).
#include "bench/internal/rs_bench_calib_internal.h"
#include "bench/rs_bench_calib.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/rs_io.h"
#include "report/rs_report_plot.h"

// ---- CSV ----

rs_status rs_bench_calib_write_csv(const char *path, const rs_bench_calib_row *rows, int Nrows, rs_err *err)
{
    rs_io_atomic a;
    rs_status st = rs_io_atomic_open(&a, path, err);
    if (st != RS_OK) return st;
    fprintf(a.f, "family,config,method,trials,failures,time_med_us,time_p90_us,rot_rms_deg,pos_rms_m,"
                 "ground_rms_m,crb_rot_deg,crb_pos_m,rot_ratio,pos_ratio,cond_median,failure\n");
    for (int i = 0; i < Nrows; i++) {
        const rs_bench_calib_row *r = &rows[i];
        char failure[sizeof r->failure];
        snprintf(failure, sizeof failure, "%s", r->failure);
        for (char *p = failure; *p; p++)
            if (*p == '"' || *p == '\n' || *p == '\r') *p = '\'';
        fprintf(a.f, "%s,%s,%s,%d,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,\"%s\"\n", r->family, r->config,
                r->method, r->trials, r->failures, r->time_med_us, r->time_p90_us, r->rot_rms_deg, r->pos_rms_m,
                r->ground_rms_m, r->crb_rot_deg, r->crb_pos_m, r->rot_ratio, r->pos_ratio, r->cond_median, failure);
    }
    return rs_io_atomic_commit(&a, err); // (checks every write above, naming the cause)
}

// ---- the plot ----

rs_status rs_bench_calib_plot(const char *path, const rs_bench_calib_row *rows, int Nrows, rs_err *err)
{
    // families in order of appearance; per family and method: median time, geometric mean ratio
    enum { MAXF = 16 };
    const char *fam[MAXF];
    int Nf = 0;
    for (int i = 0; i < Nrows; i++) {
        int f = 0;
        while (f < Nf && strcmp(fam[f], rows[i].family)) f++;
        if (f == Nf && Nf < MAXF) fam[Nf++] = rows[i].family;
    }
    double X[MAXF][RS_BENCH_CALIB_NMETHODS], Y[MAXF][RS_BENCH_CALIB_NMETHODS];
    for (int f = 0; f < Nf; f++)
        for (int m = 0; m < RS_BENCH_CALIB_NMETHODS; m++) {
            double lt = 0, lr = 0;
            int nt = 0, nr = 0;
            for (int i = 0; i < Nrows; i++) {
                if (strcmp(rows[i].family, fam[f]) || strcmp(rows[i].method, rs_bench_calib_methods[m].name)) continue;
                if (rows[i].time_med_us > 0) lt += log(rows[i].time_med_us), nt++;
                if (rows[i].pos_ratio > 0 && isfinite(rows[i].pos_ratio)) lr += log(rows[i].pos_ratio), nr++;
            }
            X[f][m] = nt && nr ? exp(lt / nt) : NAN;
            Y[f][m] = nt && nr ? exp(lr / nr) : NAN;
        }

    // the methods' markers: one shape per library
    static const rs_report_plot_marker shape[] = {
        [RS_BENCH_CALIB_LIB_ROADSIDE] = RS_REPORT_PLOT_CIRCLE,
        [RS_BENCH_CALIB_LIB_OPENCV] = RS_REPORT_PLOT_SQUARE,
        [RS_BENCH_CALIB_LIB_OPENGV] = RS_REPORT_PLOT_TRIANGLE,
    };
    rs_report_plot_series series[RS_BENCH_CALIB_NMETHODS];
    for (int m = 0; m < RS_BENCH_CALIB_NMETHODS; m++)
        series[m] = (rs_report_plot_series){rs_bench_calib_methods[m].name, shape[rs_bench_calib_methods[m].lib]};
    const rs_report_plot_loglog plot = {
        .width_px = 1600,
        .height_px = 1000,
        .title = "roadside bench calib: median CPU time (us) vs position error / Cramer-Rao bound "
                 "(log-log; 1 = at the bound; one point per method per configuration family)",
        .x_label = "median time, us",
        .legend_note = "x: time (us), y: pos err / CRB",
        .Npanels = Nf,
        .panel_titles = fam,
        .Nseries = RS_BENCH_CALIB_NMETHODS,
        .series = series,
        .x = &X[0][0],
        .y = &Y[0][0],
    };
    return rs_report_plot_loglog_png(path, &plot, err);
}

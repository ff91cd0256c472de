// rs_bench_calib_internal.h -- what the files of `roadside bench calib` share: the table of the
// methods compared. Internal to bench; the API is bench/rs_bench_calib.h.
//
//   rs_bench_calib.c         the methods, the sweep, one trial, the Cramer-Rao bound, the run
//   rs_bench_calib_output.c  the CSV and the plot (drawn by report/rs_report_plot.h)
//   rs_bench_calib_stress.c  the stress run
#pragma once
#include <stdbool.h>

// The library a method comes from (its marker in the plot).
typedef enum { RS_BENCH_CALIB_LIB_ROADSIDE, RS_BENCH_CALIB_LIB_OPENCV, RS_BENCH_CALIB_LIB_OPENGV } rs_bench_calib_lib;

typedef struct {
    const char *name; // as in the rows and the CSV, e.g. "cv-ransac+lm"
    rs_bench_calib_lib lib;
    int variant;    // roadside: 0 full, 1 init, 2 no prior; OpenCV/OpenGV: the shim's enum
    bool refine_lm; // OpenCV: + solvePnPRefineLM
} rs_bench_calib_method;

enum { RS_BENCH_CALIB_NMETHODS = 18 };

// The methods in the order of the rows of each configuration (rs_bench_calib_run).
extern const rs_bench_calib_method rs_bench_calib_methods[RS_BENCH_CALIB_NMETHODS];

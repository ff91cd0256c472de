// rs_bench_calib.h -- run time against error: roadside's pose solver next to OpenCV's and
// OpenGV's on identical simulated problems, each figure next to the Cramer-Rao bound; and the
// numerical stress run (many random problems, nothing non-finite, every failure named).
//
// Purpose: `roadside bench calib` (issue 5). The library computes the rows; the cli prints them,
// writes the CSV (rs_bench_calib_write_csv) and the plot (rs_bench_calib_plot).
// Files: rs_bench_calib.c (methods, sweep, trials, the bound, the run), rs_bench_calib_output.c
// (CSV, plot), rs_bench_calib_stress.c (the stress run).
//
// Problems: rs_simulate_camera_problem() (sim/rs_simulate.h), LENSMODEL_OPENCV8 with mild
// distortion (so that OpenCV gets the exact lens as K + distortion, and OpenGV exact bearings
// from mrcal_unproject), 1920x1080, 60 degree field of view. The sweep moves one knob at a time
// away from a baseline (20 landmarks, 1 px, survey sigma 0.3 m on every axis, no outliers, 25%
// of the landmarks 2-6 m above the ground, camera 8 m up, 25 m from the point it looks at);
// the families and their values are the table in bench/rs_bench_calib.c (and docs/benchmarks.md).
//
// Methods (the rows' `method` names): roadside (rs_calib_solve, full: RANSAC, Ceres with
// landmark priors, outliers, covariance), roadside-init (rs_calib_init_pose alone),
// roadside-noprior (rs_calib_solve with the survey taken as exact); OpenCV solvePnP ITERATIVE,
// EPNP, SQPNP, IPPE, each alone and followed by solvePnPRefineLM, solvePnPRansac alone and + LM;
// OpenGV P3P Kneip and Gao in RANSAC, EPnP, UPnP, EPnP + optimize_nonlinear. OpenCV gets the
// pixels and K + distortion; OpenGV gets mrcal-unprojected bearings (the unprojection is timed).
//
// Figures per method and configuration, over the trials:
//   time: median and 90th percentile, microseconds of THREAD CPU time (CLOCK_THREAD_CPUTIME_ID:
//     insensitive to other processes on a loaded machine), every call counted.
//   failure: no pose (the error message of the first failure is kept), or a wrong pose:
//     rotation error > 5 degrees or position error > 20% of the camera-to-target distance.
//   errors, RMS over the trials that did not fail: rotation (angle of R_est R_true^T, degrees),
//     camera position (metres), ground localisation (metres): a grid of 12 x 8 pixels over the
//     image whose true rays meet the ground within max_range_m are located on the ground plane
//     (rs_calib_locate_ground, true intrinsics) with the estimated and with the true pose.
//   Cramer-Rao bound: the covariance of the pose at the TRUE parameters under the solver's own
//     errors-in-variables model (pixel sigma, survey sigmas; the true outliers removed), i.e.
//     the inverse Fisher information J^T J at the truth, the landmarks marginalised: computed by
//     rs_calib_solve on the noise-free version of the same trial (it converges at the truth, and
//     its covariance is absolutely scaled). crb_rot_deg = sqrt(trace) of the covariance of the
//     rotation error vector (propagated through mrcal_compose_r), crb_pos_m = sqrt(trace) of the
//     position covariance, both RMS over the trials; rot_ratio = rot_rms / crb_rot (1 = at the
//     bound; an unbiased estimator cannot go below 1 except by chance).
#pragma once
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    int trials;    // problems per configuration (default 50)
    bool quick;    // the small grid: 2-3 configurations, for the test suite
    uint64_t seed; // trial k of configuration c uses seed + 1000003 c + k (default 1)
} rs_bench_calib_options;

// Fills o with the defaults above. o must not be NULL.
void rs_bench_calib_options_default(rs_bench_calib_options *o);

typedef struct {
    char family[24]; // "baseline", "noise", "landmarks", "outliers", "survey", "planar",
                     //   "height", "distance"
    char config[40]; // e.g. "noise=0.1px"
    char method[28]; // e.g. "cv-ransac+lm"
    int trials, failures;
    double time_med_us, time_p90_us;
    double rot_rms_deg, pos_rms_m, ground_rms_m; // NAN when every trial failed
    double crb_rot_deg, crb_pos_m;               // NAN when the bound could not be computed
    double rot_ratio, pos_ratio;                 // error / bound; NAN as above
    double cond_median;                          // median condition number (roadside methods; NAN for the others)
    char failure[120];                           // the first failure's cause ("" when none)
} rs_bench_calib_row;

// Runs the benchmark.
// out: *rows, malloc'ed (*Nrows,), owned by the caller (free()).
// progress: called after each configuration (done, total) -- may be NULL.
// Errors: RS_ERR_USAGE (bad options), RS_ERR_NOMEM. A configuration whose problems cannot be
// generated gives rows with trials = 0 and the generator's message in `failure`.
rs_status rs_bench_calib_run( // out
    rs_bench_calib_row **rows, int *Nrows,
    // in
    const rs_bench_calib_options *o, void (*progress)(int done, int total, void *cookie), // may be NULL
    void *cookie, rs_err *err);

// Writes the rows as CSV (header line, one row per method and configuration; NAN written as
// "nan"), atomically. Errors: RS_ERR_IO.
rs_status rs_bench_calib_write_csv(const char *path, const rs_bench_calib_row *rows, int Nrows, rs_err *err);

// Writes a PNG (1600 x 1000, drawn by rs_report_plot_loglog_png, report/rs_report_plot.h): one
// log-log panel per configuration family (the first 16), x = median time (us), y = position
// error / Cramer-Rao bound (geometric mean over the family's configurations), one marker per
// method (circle: roadside, square: OpenCV, triangle: OpenGV), a shared legend. Atomic.
// Errors: RS_ERR_IO, RS_ERR_EXTERNAL (cairo), RS_ERR_NOMEM.
rs_status rs_bench_calib_plot(const char *path, const rs_bench_calib_row *rows, int Nrows, rs_err *err);

// ---- the stress run ----

typedef struct {
    int Nproblems;  // asked for
    int Ngenerated; // problems the simulator produced (the rest: options it refused)
    int Nok;        // rs_calib_solve returned a pose
    int Nerror[16]; // errors, by rs_status code
    int Nflagged;   // poses whose condition number exceeded the bound (and were warned)
    int Nnonfinite; // poses with a NaN/inf anywhere in the result (or a 99.9% region not
                    //   positive): must be 0
    int Nunnamed;   // errors without a cause in the message: must be 0
    int Nunflagged; // condition number beyond the bound without a warning: must be 0
    int Nbad;       // poses more than 10 reported sigmas (Mahalanobis) from the truth
                    //   while not flagged (a confident wrong answer)
    // The same tail measured without the warnings (which speak of much else: an unchecked focal,
    // a loose rotation): how often the truth lies outside the reported ellipsoid at all.
    int Nout999;             // poses outside their 99.9% region (Mahalanobis^2 > the result's
                             //   region_m2: 22.46, chi-square 6 dof, with the noise as stated,
                             //   6 F(6, pose_dof) when it is estimated): 0.1% of Nok when the
                             //   covariance is exact
    int Nout999_unwarned;    //   of them, with no warning at all
    int Nout999_bare;        //   of them, with no warning but the generic one below (the issue's
                             //   "a pose outside its 99.9% ellipsoid carries a warning that says so")
    int Nbare;               // poses with no warning but the generic one: 0.1% of them outside by chance
    int Nbeyond10;           // poses beyond 10 reported sigmas, warned or not
    int Nwarned;             // poses that carry any warning
    int Nbeyond10_bare;      // beyond 10 sigma with no warning but the generic one that the focal,
                             //   taken as exact, cannot be checked by the landmarks (the stress
                             //   problems' focal IS exact: that warning does not explain their error)
    double cond_max;         // largest condition number of a returned pose
    uint64_t first_bad_seed; // seed of the first problem counted in Nnonfinite, Nunnamed,
                             //   Nunflagged or Nbad
    char first_bad[200];     // what was wrong with it ("" when nothing was)
} rs_bench_calib_stress_summary;

// Solves Nproblems random problems with rs_calib_solve: lens pinhole / OPENCV8 / CAHVOR,
// 4..40 landmarks, pixel noise 1e-3..5 px, outliers 0..50%, survey sigma 0..2 m, planar or not,
// camera 3..100 m up, 10..2000 m away, 20..90 degree field of view. Problem k uses seed + k
// (every one reproducible on its own). Checks: every returned pose is finite (rt, covariance,
// position, yaw/pitch/roll and their sigmas, rms, condition number), its covariance has a
// positive diagonal, a condition number beyond the bound (rs_calib_options.condition_warn,
// default 100) comes with a warning naming it, every error has a message.
// Errors: RS_ERR_USAGE for Nproblems < 1. The findings are in *summary, not in the status.
rs_status rs_bench_calib_stress( // out
    rs_bench_calib_stress_summary *summary,
    // in
    int Nproblems, uint64_t seed, rs_err *err);

#ifdef __cplusplus
}
#endif

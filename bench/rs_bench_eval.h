// rs_bench_eval.h -- the data of `roadside bench eval` (bench/rs_bench_eval.c).
#pragma once
#include <stddef.h>
#include <stdint.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// A synthetic dataset for benchmarks: Nimages images of 1920x1080 with about Ndets / Nimages /
// 4 vehicles each (3 categories, image field "condition" in normal/rain/night, one ignore region
// in every 20th image), and Ndets detections: a noisy detection (+-6 px) of most vehicles, the
// rest spread at random. Writes gt_path and dets_path atomically. Deterministic in seed (core/rs_rng.h).
rs_status rs_bench_eval_write_data(const char *gt_path, const char *dets_path, int Nimages, long Ndets, uint64_t seed,
                                   rs_err *err);

// What `roadside bench eval` measures: the data written, then parsed (rs_eval_load, centre
// shift 0.5) and evaluated (rs_eval_run, defaults). Times in seconds (wall, and CPU of this
// process); peak resident set size before parsing and after evaluating, bytes.
typedef struct {
    size_t gt, crowd;                   // ground truths and ignore regions parsed
    double generate_s, parse_s, eval_s; // wall
    double parse_cpu_s, eval_cpu_s;     // CPU
    double rss_before, rss_after;       // peak RSS, bytes
    double data_bytes;                  // rs_eval_data_bytes
    double map, ar;                     // the evaluation's mAP and AR
} rs_bench_eval_figures;

// Writes the synthetic data (rs_bench_eval_write_data) to gt_path and dets_path, then parses and
// evaluates it, filling *f.
rs_status rs_bench_eval_run( // out
    rs_bench_eval_figures *f,
    // in
    int Nimages, long Ndets, uint64_t seed, const char *gt_path, const char *dets_path, rs_err *err);

#ifdef __cplusplus
}
#endif

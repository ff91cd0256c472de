// rs_bench_eval.h -- the data of `roadside bench eval` (bench/rs_bench_eval.c).
#pragma once
#include <stdint.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// A synthetic dataset for benchmarks: Nimages images of 1920x1080 with about Ndets / Nimages /
// 4 vehicles each (3 categories, image field "condition" in normal/rain/night, one ignore region
// in every 20th image), and Ndets detections: a noisy detection (+-6 px) of most vehicles, the
// rest spread at random. Writes gt_path and dets_path atomically. Deterministic in seed (core/rs_rng.h).
rs_status rs_bench_eval_write_data(const char *gt_path, const char *dets_path, int Nimages,
                                  long Ndets, uint64_t seed, rs_err *err);

#ifdef __cplusplus
}
#endif

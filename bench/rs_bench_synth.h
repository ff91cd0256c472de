// rs_synth_bench.h -- `roadside bench synth`: the time of `roadside synth` on a site, with each of
// its savings turned off in turn, so that what each brings is measured on the same images
// (docs/benchmarks.md).
//
// Variants (rs_bench_synth_variants): "all" (every saving: region rendering, the passes as the
// frames of one povray process, the shadow pass replacing two ground passes, J workers),
// "jobs=1" (one image at a time), "separate" (one povray process per pass), "full-frame" (no
// culling, no region), "no-shadows" (the shadow pass skipped: its cost), "full-detail" (no
// coarse meshes for vehicles under 40 px). Every variant makes
// the same images (same seed, count, size) into a folder of its own, removed afterwards.
#pragma once
#include <stdbool.h>

#include "core/rs_status.h"
#include "synth/rs_synth_dataset.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    // the variant
    char name[32];
    char what[96];
    int jobs;
    bool separate_processes, full_frame, shadows, full_detail;
    // figures
    int Nimages, Nannotations;
    double wall_s;   // the whole run: loading, images, assembling the COCO file
    double cpu_s;    // CPU of this process and of its children (workers, povray), user + sys
    double povray_s; // wall time inside povray, summed over the images
} rs_bench_synth_row;

#define RS_SYNTH_BENCH_VARIANTS 6

// Fills rows (RS_SYNTH_BENCH_VARIANTS,) with the variants above; J: the workers of every
// variant but "jobs=1".
void rs_bench_synth_variants(rs_bench_synth_row *rows, int J);

// Runs each row's variant: base's site, calib, count, seed, size, vehicles, povray, with the
// row's jobs / separate / full-frame / shadows, output into work_dir/<name> (created, then
// removed). base->progress is ignored. Fills the figures. Stops at the first error.
rs_status rs_bench_synth_run(rs_bench_synth_row *rows, int Nrows, const rs_synth_dataset_options *base,
                             const char *work_dir, rs_err *err);

#ifdef __cplusplus
}
#endif

// rs_bench_synth.h -- `roadside bench synth`: the time of `roadside synth` on a site, with each of
// its savings turned off in turn, so that what each brings is measured on the same images
// (docs/benchmarks.md).
//
// Variants (rs_bench_synth_variants): "all" (every saving: region rendering, the passes as the
// frames of one povray process, the shadow pass replacing two ground passes, J workers),
// "jobs=1" (one image at a time), "separate" (one povray process per pass), "full-frame" (no
// culling, no region), "no-shadows" (the shadow pass skipped: its cost), "full-detail" (no
// coarse meshes for vehicles under 40 px), "no-appearance" (the camera's look not applied:
// its cost, issue 40). Every variant makes
// the same images (same seed, count, size) into a folder of its own, removed afterwards.
//
// Memory (issue 17, "memory flat over 1,000 images"), per variant:
//   peak_self_kib      the peak resident set of this process (the run's parent: scene, traffic,
//                      COCO assembly) during the variant: /proc/self/status VmHWM, reset before
//                      the variant by writing 5 to /proc/self/clear_refs (Linux >= 4.0, proc(5));
//                      where that reset fails, getrusage(RUSAGE_SELF) ru_maxrss (the process's
//                      peak so far, so it includes the earlier variants)
//   peak_children_kib  getrusage(RUSAGE_CHILDREN) ru_maxrss after the variant: the largest peak
//                      of any finished descendant (a worker or a povray process) so far in this
//                      process, earlier variants included (the kernel keeps no per-variant figure)
//   checkpoints        every `memory_every` images (and after the last one), from the progress
//                      callback in this process: the resident sets (/proc/PID/statm) of the live
//                      process tree under this process, summed over the roadside processes (this
//                      one and its forked workers) and over every process (povray included).
//                      A page shared by several processes (the workers are forked) counts once
//                      per process. Also the largest single roadside process, and how many there
//                      are (workers end one by one after their last image).
//   growth             per 100 images, of the roadside sum: (last - first) / (images between) x
//                      100, between the first checkpoint and the last one that has as many
//                      roadside processes alive as the first (so that workers ending do not read
//                      as memory freed); and the least-squares slope through those checkpoints
#include <stdbool.h>

#include "core/rs_status.h"
#include "synth/dataset/rs_synth_dataset.h"

#define RS_BENCH_SYNTH_MAX_CHECKPOINTS 128

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
    // memory (above), KiB; 0 where not measured
    long peak_self_kib, peak_children_kib;
    int memory_every; // checkpoint spacing in images (in: <= 0 picks count / 10, at least 1;
                      // widened so that at most RS_BENCH_SYNTH_MAX_CHECKPOINTS are taken)
    int Ncheckpoints; // checkpoints taken
    int cp_images[RS_BENCH_SYNTH_MAX_CHECKPOINTS];            // images done at checkpoint i
    long cp_rss_roadside_kib[RS_BENCH_SYNTH_MAX_CHECKPOINTS]; // this process + its workers
    long cp_rss_tree_kib[RS_BENCH_SYNTH_MAX_CHECKPOINTS];     // every live descendant too (povray)
    long cp_rss_largest_kib[RS_BENCH_SYNTH_MAX_CHECKPOINTS];  // the largest roadside process
    int cp_roadside[RS_BENCH_SYNTH_MAX_CHECKPOINTS];          // live roadside processes (this one, workers)
    int cp_processes[RS_BENCH_SYNTH_MAX_CHECKPOINTS];         // live processes in the tree, this one included
    bool no_appearance; // the variant: the camera's look not applied (issue 40: its cost)
} rs_bench_synth_row;

#define RS_SYNTH_BENCH_VARIANTS 7

// The growth of the sampled resident set of the roadside processes (sum and largest) between
// the first checkpoint and the last one with as many roadside processes alive, KiB per 100
// images; NaN (both) when there are not two such checkpoints. out: *last (may be NULL): the
// index of that last checkpoint, -1 if none; *largest_kib_per_100 may be NULL.
double rs_bench_synth_growth_kib_per_100(const rs_bench_synth_row *r, int *last, double *largest_kib_per_100);

// The least-squares slope of the roadside processes' resident set over the images, through
// every checkpoint up to that last one with as many roadside processes alive as the first,
// KiB per 100 images: less sensitive than two checkpoints to the image each worker is on when
// sampled. NaN with fewer than 2 such checkpoints.
double rs_bench_synth_slope_kib_per_100(const rs_bench_synth_row *r);

// The resident set of the live process tree under (and including) process `root`, read from
// /proc: *roadside_kib sums root and its children whose command name (/proc/PID/stat) is root's
// own (its forked workers; a worker's child between fork and exec is not one), *largest_kib is
// the largest of them, *Nroadside counts them;
// *tree_kib sums every process, *Nprocesses counts them. Processes that end while being read
// and zombies (ended, not yet waited for) are skipped. Returns RS_ERR_IO when /proc cannot be read.
rs_status rs_bench_synth_tree_rss(long *roadside_kib, long *largest_kib, int *Nroadside, long *tree_kib,
                                  int *Nprocesses, int root, rs_err *err);

// Fills rows (RS_SYNTH_BENCH_VARIANTS,) with the variants above; J: the workers of every
// variant but "jobs=1".
void rs_bench_synth_variants(rs_bench_synth_row *rows, int J);

// Runs each row's variant: base's site, calib, count, seed, size, vehicles, povray, with the
// row's jobs / separate / full-frame / shadows, output into work_dir/<name> (created, then
// removed). base->progress is ignored (the memory checkpoints use it). Fills the figures, the
// memory ones included (rows[k].memory_every in). Stops at the first error.
rs_status rs_bench_synth_run(rs_bench_synth_row *rows, int Nrows, const rs_synth_dataset_options *base,
                             const char *work_dir, rs_err *err);

#ifdef __cplusplus
}
#endif

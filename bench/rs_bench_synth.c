// rs_synth_bench.c -- `roadside bench synth` (rs_synth_bench.h).
#include "bench/rs_bench_synth.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include "core/rs_io.h"

void rs_bench_synth_variants(rs_bench_synth_row *rows, int J)
{
    static const struct {
        const char *name, *what;
        bool one_job, separate, full_frame, no_shadows, full_detail;
    } v[RS_SYNTH_BENCH_VARIANTS] = {
        {"all", "every saving", false, false, false, false, false},
        {"jobs=1", "one image at a time", true, false, false, false, false},
        {"separate", "the passes' povray processes one after the other", false, true, false, false, false},
        {"full-frame", "no culling, no region: the whole image rendered", false, false, true, false, false},
        {"no-shadows", "the shadow pass skipped", false, false, false, true, false},
        {"full-detail", "every vehicle's mesh in full detail (no coarse meshes)", false, false, false, false, true},
    };
    for (int k = 0; k < RS_SYNTH_BENCH_VARIANTS; k++) {
        memset(&rows[k], 0, sizeof(rows[k]));
        snprintf(rows[k].name, sizeof(rows[k].name), "%s", v[k].name);
        snprintf(rows[k].what, sizeof(rows[k].what), "%s", v[k].what);
        rows[k].jobs = v[k].one_job ? 1 : J;
        rows[k].separate_processes = v[k].separate;
        rows[k].full_frame = v[k].full_frame;
        rows[k].shadows = !v[k].no_shadows;
        rows[k].full_detail = v[k].full_detail;
    }
}

static double wall_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

// user + system CPU of this process and of its waited-for children, seconds
static double cpu_now(void)
{
    struct rusage self, kids;
    getrusage(RUSAGE_SELF, &self);
    getrusage(RUSAGE_CHILDREN, &kids);
    return self.ru_utime.tv_sec + self.ru_stime.tv_sec + kids.ru_utime.tv_sec + kids.ru_stime.tv_sec +
           1e-6 * (self.ru_utime.tv_usec + self.ru_stime.tv_usec + kids.ru_utime.tv_usec + kids.ru_stime.tv_usec);
}

rs_status rs_bench_synth_run(rs_bench_synth_row *rows, int Nrows, const rs_synth_dataset_options *base,
                             const char *work_dir, rs_err *err)
{
    rs_status st = rs_io_mkdir_p(work_dir, err);
    for (int k = 0; k < Nrows && !st; k++) {
        rs_bench_synth_row *r = &rows[k];
        char *out = rs_io_join(work_dir, r->name);
        if (!out) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        rs_io_remove_tree(out);
        rs_synth_dataset_options o = *base;
        o.out_dir = out;
        o.jobs = r->jobs;
        o.separate_processes = r->separate_processes;
        o.full_frame = r->full_frame;
        o.shadows = r->shadows;
        if (r->full_detail) o.coarse_below_px = 0;
        o.shard_index = 0;
        o.shard_count = 1;
        o.progress = NULL;
        rs_synth_dataset_summary sum;
        const double w0 = wall_now(), c0 = cpu_now();
        st = rs_synth_dataset_run(&sum, &o, err);
        r->wall_s = wall_now() - w0;
        r->cpu_s = cpu_now() - c0;
        if (!st) {
            r->Nimages = sum.Nmade;
            r->Nannotations = sum.Nannotations;
            r->povray_s = sum.seconds_povray;
        }
        rs_io_remove_tree(out);
        free(out);
    }
    return st;
}

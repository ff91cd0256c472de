// rs_bench_synth.c -- `roadside bench synth` (rs_bench_synth.h).
#include "bench/rs_bench_synth.h"

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "core/rs_io.h"

void rs_bench_synth_variants(rs_bench_synth_row *rows, int J)
{
    static const struct {
        const char *name, *what;
        bool one_job, separate, full_frame, no_shadows, full_detail, no_appearance;
    } v[RS_SYNTH_BENCH_VARIANTS] = {
        {"all", "every saving", false, false, false, false, false, false},
        {"jobs=1", "one image at a time", true, false, false, false, false, false},
        {"separate", "the passes' povray processes one after the other", false, true, false, false, false, false},
        {"full-frame", "no culling, no region: the whole image rendered", false, false, true, false, false, false},
        {"no-shadows", "the shadow pass skipped", false, false, false, true, false, false},
        {"full-detail", "every vehicle's mesh in full detail (no medium or coarse meshes)", false, false, false, false,
         true, false},
        {"no-appearance", "the camera's look not applied (clean, sharp vehicles)", false, false, false, false, false,
         true},
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
        rows[k].no_appearance = v[k].no_appearance;
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

// ---- memory ----

// Reads /proc/PID/stat: its command name (between the parentheses), state and parent's pid.
static bool proc_stat(int pid, char comm[64], char *state, int *ppid)
{
    char path[64], buf[1024];
    snprintf(path, sizeof(path), "/proc/%d/stat", pid);
    FILE *f = fopen(path, "r");
    if (!f) return false;
    const size_t n = fread(buf, 1, sizeof(buf) - 1, f);
    fclose(f);
    buf[n] = 0;
    // "pid (comm) state ppid ...": comm may hold spaces and parentheses, so the last ')'
    char *open = strchr(buf, '('), *close = strrchr(buf, ')');
    if (!open || !close || close < open) return false;
    snprintf(comm, 64, "%.*s", (int)(close - open - 1), open + 1);
    return sscanf(close + 1, " %c %d", state, ppid) == 2;
}

// Resident set of PID in KiB (/proc/PID/statm's second field, in pages); -1 if it is gone.
static long proc_rss_kib(int pid)
{
    char path[64];
    snprintf(path, sizeof(path), "/proc/%d/statm", pid);
    FILE *f = fopen(path, "r");
    if (!f) return -1;
    long size = 0, resident = -1;
    if (fscanf(f, "%ld %ld", &size, &resident) != 2) resident = -1;
    fclose(f);
    const long page_kib = sysconf(_SC_PAGESIZE) / 1024;
    return resident < 0 ? -1 : resident * (page_kib > 0 ? page_kib : 4);
}

rs_status rs_bench_synth_tree_rss(long *roadside_kib, long *largest_kib, int *Nroadside, long *tree_kib,
                                  int *Nprocesses, int root, rs_err *err)
{
    *roadside_kib = *largest_kib = *tree_kib = 0;
    *Nprocesses = *Nroadside = 0;
    DIR *dir = opendir("/proc");
    if (!dir) return rs_err_set(err, RS_ERR_IO, "/proc: %s", strerror(errno));
    // every process's (pid, ppid, comm): the machine has a few hundred
    int cap = 512, n = 0;
    struct proc_entry {
        int pid, ppid;
        bool in_tree;
        char state; // 'Z': a zombie (ended, not yet waited for), no memory: not counted
        char comm[64];
    } *p = malloc((size_t)cap * sizeof(*p));
    if (!p) {
        closedir(dir);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    const struct dirent *de;
    while ((de = readdir(dir))) {
        if (!isdigit((unsigned char)de->d_name[0])) continue;
        if (n == cap) {
            struct proc_entry *q = realloc(p, (size_t)(cap *= 2) * sizeof(*p));
            if (!q) {
                free(p);
                closedir(dir);
                return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            }
            p = q;
        }
        p[n].pid = atoi(de->d_name);
        p[n].in_tree = p[n].pid == root;
        if (proc_stat(p[n].pid, p[n].comm, &p[n].state, &p[n].ppid)) n++; // else it ended meanwhile
    }
    closedir(dir);
    const char *root_comm = NULL;
    for (int i = 0; i < n; i++)
        if (p[i].pid == root) root_comm = p[i].comm;
    if (!root_comm) {
        free(p);
        return rs_err_set(err, RS_ERR_IO, "/proc/%d: not found", root);
    }
    // the descendants of root: mark children of marked processes until nothing changes
    for (bool grew = true; grew;) {
        grew = false;
        for (int i = 0; i < n; i++)
            if (!p[i].in_tree)
                for (int j = 0; j < n; j++)
                    if (p[j].in_tree && p[j].pid == p[i].ppid) {
                        p[i].in_tree = grew = true;
                        break;
                    }
    }
    for (int i = 0; i < n; i++) {
        if (!p[i].in_tree || p[i].state == 'Z' || p[i].state == 'X') continue;
        const long kib = proc_rss_kib(p[i].pid);
        if (kib < 0) continue;
        *tree_kib += kib;
        // roadside: root and its forked workers (its children); a grandchild by root's name is a
        // worker's child between fork and exec (of povray), a copy of the worker: not counted
        if (!strcmp(p[i].comm, root_comm) && (p[i].pid == root || p[i].ppid == root)) {
            *roadside_kib += kib;
            if (kib > *largest_kib) *largest_kib = kib;
            ++*Nroadside;
        }
        ++*Nprocesses;
    }
    free(p);
    return RS_OK;
}

double rs_bench_synth_growth_kib_per_100(const rs_bench_synth_row *r, int *last, double *largest_kib_per_100)
{
    int b = r->Ncheckpoints - 1;
    while (b > 0 && r->cp_roadside[b] != r->cp_roadside[0]) b--;
    if (last) *last = r->Ncheckpoints > 0 ? b : -1;
    if (largest_kib_per_100) *largest_kib_per_100 = NAN;
    if (b < 1 || r->cp_images[b] <= r->cp_images[0]) return NAN;
    const double di = r->cp_images[b] - r->cp_images[0];
    if (largest_kib_per_100)
        *largest_kib_per_100 = 100.0 * (double)(r->cp_rss_largest_kib[b] - r->cp_rss_largest_kib[0]) / di;
    return 100.0 * (double)(r->cp_rss_roadside_kib[b] - r->cp_rss_roadside_kib[0]) / di;
}

double rs_bench_synth_slope_kib_per_100(const rs_bench_synth_row *r)
{
    int last = -1;
    (void)rs_bench_synth_growth_kib_per_100(r, &last, NULL);
    // least squares over the checkpoints 0..last that have as many roadside processes as the first
    double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (int i = 0; i <= last; i++) {
        if (r->cp_roadside[i] != r->cp_roadside[0]) continue;
        const double x = r->cp_images[i], y = (double)r->cp_rss_roadside_kib[i];
        n++, sx += x, sy += y, sxx += x * x, sxy += x * y;
    }
    const double den = n * sxx - sx * sx;
    return n >= 2 && den > 0 ? 100.0 * (n * sxy - sx * sy) / den : NAN;
}

// The progress callback of a variant's run: a checkpoint every r->memory_every images and
// after the last one.
static void memory_checkpoint(void *ctx, int done, int total, int skipped)
{
    (void)skipped;
    rs_bench_synth_row *r = ctx;
    if (r->Ncheckpoints >= RS_BENCH_SYNTH_MAX_CHECKPOINTS || (done % r->memory_every != 0 && done != total)) return;
    const int i = r->Ncheckpoints;
    rs_err e = {0};
    if (rs_bench_synth_tree_rss(&r->cp_rss_roadside_kib[i], &r->cp_rss_largest_kib[i], &r->cp_roadside[i],
                                &r->cp_rss_tree_kib[i], &r->cp_processes[i], (int)getpid(), &e))
        return; // no /proc: no checkpoint
    r->cp_images[i] = done;
    r->Ncheckpoints++;
}

// Resets this process's VmHWM to its current resident set (proc(5), /proc/PID/clear_refs).
static bool reset_peak_rss(void)
{
    FILE *f = fopen("/proc/self/clear_refs", "w");
    if (!f) return false;
    const bool ok = fputs("5", f) >= 0;
    return fclose(f) == 0 && ok;
}

// VmHWM of /proc/self/status in KiB, -1 if unreadable.
static long peak_rss_kib(void)
{
    FILE *f = fopen("/proc/self/status", "r");
    if (!f) return -1;
    char line[256];
    long kib = -1;
    while (fgets(line, sizeof(line), f))
        if (sscanf(line, "VmHWM: %ld kB", &kib) == 1) break;
    fclose(f);
    return kib;
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
        if (r->full_detail) o.coarse_below_px = o.medium_below_px = 0;
        o.no_appearance = r->no_appearance;
        o.shard_index = 0;
        o.shard_count = 1;
        int every = r->memory_every > 0 ? r->memory_every : (o.count + 9) / 10;
        const int least = (o.count + RS_BENCH_SYNTH_MAX_CHECKPOINTS - 2) / (RS_BENCH_SYNTH_MAX_CHECKPOINTS - 1);
        r->memory_every = every > least ? every : least; // room for the last image's checkpoint
        r->Ncheckpoints = 0;
        o.progress = memory_checkpoint;
        o.progress_ctx = r;
        const bool reset = reset_peak_rss();
        rs_synth_dataset_summary sum;
        const double w0 = wall_now(), c0 = cpu_now();
        st = rs_synth_dataset_run(&sum, &o, err);
        r->wall_s = wall_now() - w0;
        r->cpu_s = cpu_now() - c0;
        struct rusage self = {0}, kids = {0};
        getrusage(RUSAGE_SELF, &self);
        getrusage(RUSAGE_CHILDREN, &kids);
        const long hwm = reset ? peak_rss_kib() : -1;
        r->peak_self_kib = hwm > 0 ? hwm : self.ru_maxrss;
        r->peak_children_kib = kids.ru_maxrss;
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

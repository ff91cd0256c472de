// rs_bench_eval.c -- a synthetic COCO ground truth and detections, for `roadside bench eval`.
#include "bench/rs_bench_eval.h"

#include <stdio.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <time.h>

#include "core/rs_io.h"
#include "core/rs_rng.h"
#include "eval/rs_eval.h"

static const char *const conditions[3] = {"normal", "rain", "night"};
static const char *const categories[3] = {"car", "truck", "bus"};

typedef struct {
    double x, y, w, h;
    int category;
} box;

rs_status rs_bench_eval_write_data(const char *gt_path, const char *dets_path, int Nimages, long Ndets, uint64_t seed,
                                   rs_err *err)
{
    if (Nimages < 1 || Ndets < 0)
        return rs_err_set(err, RS_ERR_USAGE, "synthetic data: need at least one image and no negative count");
    rs_rng rng;
    rs_rng_seed(&rng, seed);
    long per_image = Ndets / Nimages, extra = Ndets % Nimages;
    int mean_vehicles = per_image / 4 > 1 ? (int)(per_image / 4) : 1;
    box *v = malloc((size_t)(2 * mean_vehicles) * sizeof *v);
    rs_io_atomic gt = {0}, dets = {0};
    rs_status st = v ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (st == RS_OK) st = rs_io_atomic_open(&gt, gt_path, err);
    if (st == RS_OK) st = rs_io_atomic_open(&dets, dets_path, err);
    if (st != RS_OK) goto fail;

    fprintf(gt.f, "{\"images\": [\n");
    for (int m = 0; m < Nimages; m++)
        fprintf(gt.f, "%s{\"id\": %d, \"width\": 1920, \"height\": 1080, \"condition\": \"%s\"}\n", m ? "," : "", m + 1,
                conditions[(int)(3 * rs_rng_uniform(&rng))]);
    fprintf(gt.f, "], \"categories\": [\n");
    for (int k = 0; k < 3; k++) fprintf(gt.f, "%s{\"id\": %d, \"name\": \"%s\"}\n", k ? "," : "", k + 1, categories[k]);
    fprintf(gt.f, "], \"annotations\": [\n");
    fprintf(dets.f, "[\n");
    long n_ann = 0, n_det = 0;
    for (int m = 0; m < Nimages; m++) {
        int Nv = 1 + (int)((2 * mean_vehicles - 1) * rs_rng_uniform(&rng));
        for (int j = 0; j < Nv; j++) {
            box *b = &v[j];
            b->w = rs_rng_uniform_in(&rng, 30, 200);
            b->h = 0.8 * b->w;
            b->x = rs_rng_uniform_in(&rng, 0, 1920 - b->w);
            b->y = rs_rng_uniform_in(&rng, 300, 1080 - b->h);
            b->category = 1 + (int)(3 * rs_rng_uniform(&rng));
            fprintf(gt.f,
                    "%s{\"id\": %ld, \"image_id\": %d, \"category_id\": %d, \"bbox\": [%.2f, %.2f, %.2f, %.2f], "
                    "\"bottom_center\": [%.2f, %.2f], \"iscrowd\": 0}\n",
                    n_ann ? "," : "", n_ann + 1, m + 1, b->category, b->x, b->y, b->w, b->h, b->x + b->w / 2,
                    b->y + b->h);
            n_ann++;
        }
        if (m % 20 == 0) {
            double x = rs_rng_uniform_in(&rng, 0, 1500), y = rs_rng_uniform_in(&rng, 300, 800);
            fprintf(gt.f,
                    ",{\"id\": %ld, \"image_id\": %d, \"category_id\": 1, \"bbox\": [%.2f, %.2f, 400, 200], "
                    "\"iscrowd\": 1}\n",
                    n_ann + 1, m + 1, x, y);
            n_ann++;
        }
        long quota = per_image + (m < extra);
        for (long k = 0; k < quota; k++) {
            box b;
            double score;
            if (k < Nv && rs_rng_uniform(&rng) < 0.9) { // a detection of vehicle k, +-6 px
                b = v[k];
                b.x += rs_rng_uniform_in(&rng, -6, 6);
                b.y += rs_rng_uniform_in(&rng, -6, 6);
                if (rs_rng_uniform(&rng) < 0.05) b.category = 1 + (int)(3 * rs_rng_uniform(&rng));
                score = rs_rng_uniform_in(&rng, 0.3, 1);
            } else { // clutter
                b.w = rs_rng_uniform_in(&rng, 20, 200);
                b.h = 0.8 * b.w;
                b.x = rs_rng_uniform_in(&rng, 0, 1920 - b.w);
                b.y = rs_rng_uniform_in(&rng, 300, 1080 - b.h);
                b.category = 1 + (int)(3 * rs_rng_uniform(&rng));
                score = rs_rng_uniform_in(&rng, 0, 0.6);
            }
            fprintf(dets.f,
                    "%s{\"image_id\": %d, \"category_id\": %d, \"bbox\": [%.2f, %.2f, %.2f, %.2f], \"score\": %.5f}\n",
                    n_det ? "," : "", m + 1, b.category, b.x, b.y, b.w, b.h, score);
            n_det++;
        }
    }
    fprintf(gt.f, "]}\n");
    fprintf(dets.f, "]\n");
    free(v);
    v = NULL;
    st = rs_io_atomic_commit(&gt, err);
    if (st == RS_OK) return rs_io_atomic_commit(&dets, err);
fail:
    free(v);
    rs_io_atomic_abort(&gt);
    rs_io_atomic_abort(&dets);
    return st;
}

// ---- the run ----

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

// CPU time of this process so far (user + system), seconds: the figure that does not depend on
// what else the machine runs.
static double cpu_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

// Peak resident set size of this process so far, bytes.
static double peak_rss_bytes(void)
{
    struct rusage u;
    getrusage(RUSAGE_SELF, &u);
    return 1024.0 * (double)u.ru_maxrss;
}

rs_status rs_bench_eval_run(rs_bench_eval_figures *f, int Nimages, long Ndets, uint64_t seed, const char *gt_path,
                            const char *dets_path, rs_err *err)
{
    double t0 = now_s();
    rs_status st = rs_bench_eval_write_data(gt_path, dets_path, Nimages, Ndets, seed, err);
    if (st != RS_OK) return st;
    f->generate_s = now_s() - t0;
    f->rss_before = peak_rss_bytes();

    rs_eval_data *data = NULL;
    rs_eval_result *r = NULL;
    const rs_eval_load_options lo = {.center_shift = 0.5};
    t0 = now_s();
    double c0 = cpu_s();
    if ((st = rs_eval_load(&data, gt_path, dets_path, &lo, err))) return st;
    f->parse_s = now_s() - t0;
    f->parse_cpu_s = cpu_s() - c0;
    f->data_bytes = (double)rs_eval_data_bytes(data);
    rs_eval_data_counts(data, NULL, &f->gt, &f->crowd, NULL);
    t0 = now_s();
    c0 = cpu_s();
    st = rs_eval_run(&r, data, NULL, err);
    f->eval_s = now_s() - t0;
    f->eval_cpu_s = cpu_s() - c0;
    f->rss_after = peak_rss_bytes();
    if (st == RS_OK) {
        f->map = r->all.map;
        f->ar = r->all.ar;
    }
    rs_eval_result_free(r);
    rs_eval_data_free(data);
    return st;
}

// rs_eval_synth.c -- a synthetic COCO ground truth and detections, for `roadside bench eval`.
#include <stdlib.h>

#include "rs_eval.h"
#include "rs_io.h"

static const char *const conditions[3] = {"normal", "rain", "night"};
static const char *const categories[3] = {"car", "truck", "bus"};

static double uniform(unsigned short xsubi[3], double lo, double hi) { return lo + (hi - lo) * erand48(xsubi); }

typedef struct {
    double x, y, w, h;
    int category;
} box;

rs_status rs_eval_write_synthetic(const char *gt_path, const char *dets_path, int Nimages, long Ndets,
                                  unsigned long seed, rs_err *err)
{
    if (Nimages < 1 || Ndets < 0)
        return rs_err_set(err, RS_ERR_USAGE, "synthetic data: need at least one image and no negative count");
    unsigned short xsubi[3] = {(unsigned short)seed, (unsigned short)(seed >> 16), (unsigned short)((seed >> 16 >> 16) ^ 0x330e)};
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
        fprintf(gt.f, "%s{\"id\": %d, \"width\": 1920, \"height\": 1080, \"condition\": \"%s\"}\n", m ? "," : "",
                m + 1, conditions[(int)(3 * erand48(xsubi))]);
    fprintf(gt.f, "], \"categories\": [\n");
    for (int k = 0; k < 3; k++) fprintf(gt.f, "%s{\"id\": %d, \"name\": \"%s\"}\n", k ? "," : "", k + 1, categories[k]);
    fprintf(gt.f, "], \"annotations\": [\n");
    fprintf(dets.f, "[\n");
    long n_ann = 0, n_det = 0;
    for (int m = 0; m < Nimages; m++) {
        int Nv = 1 + (int)((2 * mean_vehicles - 1) * erand48(xsubi));
        for (int j = 0; j < Nv; j++) {
            box *b = &v[j];
            b->w = uniform(xsubi, 30, 200);
            b->h = 0.8 * b->w;
            b->x = uniform(xsubi, 0, 1920 - b->w);
            b->y = uniform(xsubi, 300, 1080 - b->h);
            b->category = 1 + (int)(3 * erand48(xsubi));
            fprintf(gt.f,
                    "%s{\"id\": %ld, \"image_id\": %d, \"category_id\": %d, \"bbox\": [%.2f, %.2f, %.2f, %.2f], "
                    "\"bottom_center\": [%.2f, %.2f], \"iscrowd\": 0}\n",
                    n_ann ? "," : "", n_ann + 1, m + 1, b->category, b->x, b->y, b->w, b->h, b->x + b->w / 2,
                    b->y + b->h);
            n_ann++;
        }
        if (m % 20 == 0) {
            double x = uniform(xsubi, 0, 1500), y = uniform(xsubi, 300, 800);
            fprintf(gt.f,
                    ",{\"id\": %ld, \"image_id\": %d, \"category_id\": 1, \"bbox\": [%.2f, %.2f, 400, 200], \"iscrowd\": 1}\n",
                    n_ann + 1, m + 1, x, y);
            n_ann++;
        }
        long quota = per_image + (m < extra);
        for (long k = 0; k < quota; k++) {
            box b;
            double score;
            if (k < Nv && erand48(xsubi) < 0.9) { // a detection of vehicle k, +-6 px
                b = v[k];
                b.x += uniform(xsubi, -6, 6);
                b.y += uniform(xsubi, -6, 6);
                if (erand48(xsubi) < 0.05) b.category = 1 + (int)(3 * erand48(xsubi));
                score = uniform(xsubi, 0.3, 1);
            } else { // clutter
                b.w = uniform(xsubi, 20, 200);
                b.h = 0.8 * b.w;
                b.x = uniform(xsubi, 0, 1920 - b.w);
                b.y = uniform(xsubi, 300, 1080 - b.h);
                b.category = 1 + (int)(3 * erand48(xsubi));
                score = uniform(xsubi, 0, 0.6);
            }
            fprintf(dets.f, "%s{\"image_id\": %d, \"category_id\": %d, \"bbox\": [%.2f, %.2f, %.2f, %.2f], \"score\": %.5f}\n",
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

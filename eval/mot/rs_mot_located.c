// rs_mot_located.c -- located detections (roadside localise's file) against a synthetic
// sequence's ground truth: the localisation error and its NEES (rs_mot.h, rs_mot_located_run).
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_io.h"
#include "eval/localise/rs_localise.h"
#include "eval/mot/rs_mot.h"

// One camera's rows as a tracks file in memory, each row a track of its own (id = its index).
static char *camera_as_tracks(const rs_localise_row *rows, size_t N, const char *camera, long *Nrows)
{
    size_t cap = 128 + 160 * N, len = 0;
    char *text = malloc(cap);
    if (!text) return NULL;
    len += (size_t)snprintf(text, cap, "time_s,track_id,e_m,n_m,sigma_e_m,sigma_n_m,cov_en_m2\n");
    *Nrows = 0;
    for (size_t i = 0; i < N; i++) {
        if (strcmp(rows[i].camera, camera)) continue;
        len += (size_t)snprintf(text + len, cap - len, "%.17g,%zu,%.17g,%.17g,%.17g,%.17g,%.17g\n", rows[i].time_s, i,
                                rows[i].e_m, rows[i].n_m, rows[i].sigma_e_m, rows[i].sigma_n_m, rows[i].cov_en_m2);
        (*Nrows)++;
    }
    return text;
}

rs_status rs_mot_located_run(rs_mot_located_result *r, const char *located_path, const char *gt_path,
                             const rs_mot_options *opt, rs_err *err)
{
    memset(r, 0, sizeof *r);
    rs_localise_row *rows = NULL;
    size_t N = 0;
    char *gt = NULL;
    rs_status st = rs_localise_read(&rows, &N, located_path, err);
    if (!st) st = rs_io_read_file(&gt, NULL, gt_path, err);
    for (size_t i = 0; !st && i < N; i++)
        if (!isfinite(rows[i].time_s))
            st = rs_err_set(err, RS_ERR_INVALID, "%s:%d: time_s: empty (the ground truth is matched by time)",
                            located_path, rows[i].line);
    double sse = 0, pred_ss = 0, nees_sum = 0;
    for (size_t i = 0; !st && i < N; i++) {
        bool first = true; // each camera once, at its first row
        for (size_t k = 0; k < i && first; k++) first = strcmp(rows[k].camera, rows[i].camera) != 0;
        if (!first) continue;
        long n = 0;
        char *text = camera_as_tracks(rows, N, rows[i].camera, &n);
        rs_mot_data *data = NULL;
        rs_mot_result m;
        if (!text) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        if (!st) st = rs_mot_parse(&data, text, located_path, gt, gt_path, err);
        if (!st) st = rs_mot_run(&m, data, opt, err);
        rs_mot_data_free(data);
        free(text);
        if (st) break;
        r->Ncameras++;
        r->Nrows += n;
        r->Noff_step += m.Nrows_off_step;
        r->matched += m.matches;
        r->unmatched += m.fp;
        r->ignored += m.Nignored;
        if (m.matches > 0) sse += m.rmse_m * m.rmse_m * (double)m.matches;
        if (m.matches > 0 && isfinite(m.predicted_rms_m))
            pred_ss += m.predicted_rms_m * m.predicted_rms_m * (double)m.matches;
        if (m.Nnees > 0) nees_sum += m.nees * (double)m.Nnees, r->Nnees += m.Nnees;
        r->threshold_m = m.threshold_m;
    }
    r->rmse_m = r->matched > 0 ? sqrt(sse / (double)r->matched) : NAN;
    r->predicted_rms_m = r->matched > 0 ? sqrt(pred_ss / (double)r->matched) : NAN;
    r->nees = r->Nnees > 0 ? nees_sum / (double)r->Nnees : NAN;
    free(rows);
    free(gt);
    return st;
}

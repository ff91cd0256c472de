// rs_bench_sparse.c -- `roadside bench sparse` (bench/rs_bench_sparse.h): leave-one-out ground
// errors of roadside's calibration and of a least-squares homography on sparse simulated sites.
#include "bench/rs_bench_sparse.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "calib/rs_calib.h"
#include "calib/rs_calib_init.h"
#include "calib/rs_calib_site.h"
#include "core/rs_camera.h"
#include "core/rs_io.h"
#include "core/rs_rng.h"
#include "core/rs_stats.h"
#include "geo/rs_site.h"
#include "sim/rs_simulate.h"

void rs_bench_sparse_options_default(rs_bench_sparse_options *o)
{
    *o = (rs_bench_sparse_options){.seed = 1,
                                   .points_min = 6,
                                   .points_max = 8,
                                   .focal_error_range = 1.5,
                                   .pixel_sigma_px = 3.0,
                                   .survey_sigma_h_m = 0.5,
                                   .lensmodel = "LENSMODEL_PINHOLE",
                                   .hfov_deg = 60.0};
}

// The true (E, N) of each of the site's landmarks from truth/landmarks_enu.csv (id,e,n,u; the
// landmarks in the site's order). out: en_m (Nlandmarks,2).
static rs_status read_truth(double *en_m, const rs_site *site, const char *dir, rs_err *err)
{
    char *path = rs_io_join(dir, "truth/landmarks_enu.csv"), *text = NULL;
    size_t len = 0;
    rs_status st = path ? rs_io_read_file(&text, &len, path, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    free(path);
    if (st) return st;
    for (int i = 0; i < site->Nlandmarks; i++) en_m[2 * i] = en_m[2 * i + 1] = NAN;
    const char *line = strchr(text, '\n');
    while (line && *++line) {
        char id[32];
        double e, n, u;
        if (sscanf(line, "%31[^,],%lf,%lf,%lf", id, &e, &n, &u) == 4)
            for (int i = 0; i < site->Nlandmarks; i++)
                if (!strcmp(site->landmarks[i].id, id)) en_m[2 * i] = e, en_m[2 * i + 1] = n;
        line = strchr(line, '\n');
    }
    free(text);
    return RS_OK;
}

// problem without observation k into sub (its arrays, (N-1) rows each, in buf).
static void leave_out(rs_calib_problem *sub, double *buf, const rs_calib_problem *pb, int k)
{
    const int N = pb->N, M = N - 1;
    double *p = buf, *sp = p + 3 * M, *q = sp + 3 * M, *sq = q + 2 * M;
    for (int i = 0, j = 0; i < N; i++) {
        if (i == k) continue;
        memcpy(&p[3 * j], &pb->p_enu_m[3 * i], 3 * sizeof(double));
        memcpy(&sp[3 * j], &pb->sigma_enu_m[3 * i], 3 * sizeof(double));
        memcpy(&q[2 * j], &pb->q_px[2 * i], 2 * sizeof(double));
        sq[j++] = pb->sigma_px[i];
    }
    *sub = *pb;
    sub->N = M;
    sub->p_enu_m = p, sub->sigma_enu_m = sp, sub->q_px = q, sub->sigma_px = sq;
    sub->along = NULL, sub->survey_shared = NULL;
}

// What the folds of one site share: the site read back, its true camera, the options.
typedef struct {
    const rs_site *site;
    const rs_camera *truth; // the true camera (its intrinsics: o->true_intrinsics)
    const rs_bench_sparse_options *o;
} site_folds;

// roadside's fold k: the horizontal error of the left-out pick located through the calibration
// of the others; +inf (and *no_pose or *no_location) when there is none.
static double fold_roadside(bool *no_pose, bool *no_location, char *why, size_t why_len, const rs_calib_problem *pb,
                            int k, const double *truth_en, const site_folds *f, double *buf)
{
    const rs_site *site = f->site;
    rs_calib_problem sub;
    leave_out(&sub, buf, pb, k);
    rs_calib_options opt;
    rs_calib_options_default(&opt);
    opt.refine = RS_CALIB_REFINE_FOCAL;
    if (f->o->true_intrinsics) { // the reference: the truth's intrinsics, held
        sub.camera = f->truth;
        opt.refine = RS_CALIB_REFINE_NONE;
    }
    rs_calib_result r;
    rs_err e = {0};
    rs_status st = rs_calib_solve(&r, &sub, &opt, &e);
    double err_m = INFINITY;
    *no_location = false;
    if (st == RS_OK) {
        rs_camera cam;
        st = rs_camera_copy(&cam, pb->camera, &e);
        if (st == RS_OK) {
            memcpy(cam.intrinsics, r.intrinsics, (size_t)cam.Nintrinsics * sizeof(double));
            if (f->o->verbose_folds)
                printf("  fold %d: focal %.4g px (sigma %.2g%%), %d of %d landmarks, method %s; warnings: %s\n", k,
                       r.intrinsics[0], 100.0 * r.sigma_intrinsics[0] / r.intrinsics[0], r.Ninliers, r.N, r.method,
                       r.warnings[0] ? r.warnings : "none");
            memcpy(cam.rt_cam_enu, r.rt_cam_enu, sizeof cam.rt_cam_enu);
            double p[3];
            st = rs_camera_locate_ground(p, &cam, &pb->q_px[2 * k], site->ground_normal_enu, site->ground_offset_m, &e);
            if (st == RS_OK) err_m = hypot(p[0] - truth_en[0], p[1] - truth_en[1]);
            *no_location = st != RS_OK;
            rs_camera_free(&cam);
        }
        rs_calib_result_free(&r);
    }
    *no_pose = st != RS_OK && !*no_location;
    if (st != RS_OK && why[0] == '\0') snprintf(why, why_len, "fold %d: %.120s", k, e.msg[0] ? e.msg : rs_strerror(st));
    return err_m;
}

// The homography's fold k: pixels to (E, N) by least squares on the others.
static double fold_homography(const rs_calib_problem *pb, int k, const double *truth_en, double *buf)
{
    const int N = pb->N;
    double *src = buf, *dst = buf + 2 * N;
    int n = 0;
    for (int i = 0; i < N; i++) {
        if (i == k) continue;
        memcpy(&src[2 * n], &pb->q_px[2 * i], 2 * sizeof(double));
        memcpy(&dst[2 * n], &pb->p_enu_m[3 * i], 2 * sizeof(double));
        n++;
    }
    double H[9];
    if (rs_calib_homography_fit(H, src, dst, n, NULL) != RS_OK) return INFINITY;
    const double *q = &pb->q_px[2 * k];
    const double w = H[6] * q[0] + H[7] * q[1] + H[8];
    const double e = (H[0] * q[0] + H[1] * q[1] + H[2]) / w, nn = (H[3] * q[0] + H[4] * q[1] + H[5]) / w;
    const double d = hypot(e - truth_en[0], nn - truth_en[1]);
    return isfinite(d) ? d : INFINITY;
}

static double max_of(const double *x, int n)
{
    double m = 0.0;
    for (int i = 0; i < n; i++) m = fmax(m, x[i]);
    return m;
}

// The folds of camera 0 of a site read back.
static rs_status run_folds(rs_bench_sparse_row *row, const site_folds *f, const char *dir, rs_err *err)
{
    const rs_site *site = f->site;
    rs_calib_site_problem sp;
    rs_status st = rs_calib_site_problem_init(&sp, site, 0, err);
    if (st) return st;
    const rs_calib_problem *pb = &sp.problem;
    const int N = pb->N;
    double *truth = malloc(sizeof(double) * 2 * (size_t)(site->Nlandmarks + 1));
    double *ours = malloc(sizeof(double) * (size_t)N), *homog = malloc(sizeof(double) * (size_t)N);
    double *buf = malloc(sizeof(double) * 10 * (size_t)N);
    if (!truth || !ours || !homog || !buf) st = rs_err_set(err, RS_ERR_NOMEM, "bench sparse: out of memory");
    if (st == RS_OK) st = read_truth(truth, site, dir, err);
    row->Npoints = N;
    row->Nno_pose = row->Nno_location = 0;
    row->first_error[0] = '\0';
    for (int k = 0; st == RS_OK && k < N; k++) {
        const double *t = &truth[2 * site->cameras[0].observations[k].ilandmark];
        bool no_pose, no_location;
        ours[k] = fold_roadside(&no_pose, &no_location, row->first_error, sizeof row->first_error, pb, k, t, f, buf);
        row->Nno_pose += no_pose;
        row->Nno_location += no_location;
        homog[k] = fold_homography(pb, k, t, buf);
        if (f->o->verbose_folds) printf("  fold %d: ground error %.2f m, homography's %.2f m\n", k, ours[k], homog[k]);
    }
    if (st == RS_OK) {
        row->loo_max_m = max_of(ours, N);
        row->homography_max_m = max_of(homog, N);
        row->loo_median_m = rs_stats_median(ours, N);
        row->homography_median_m = rs_stats_median(homog, N);
    }
    free(truth), free(ours), free(homog), free(buf);
    rs_calib_site_problem_free(&sp);
    return st;
}

rs_status rs_bench_sparse_site(rs_bench_sparse_row *row, const rs_bench_sparse_options *o, int k, const char *work_dir,
                               rs_err *err)
{
    memset(row, 0, sizeof *row);
    rs_simulate_site_options so;
    rs_simulate_site_options_default(&so);
    so.seed = o->seed + (uint64_t)k;
    rs_rng rng; // the number of points, from the site's seed
    rs_rng_seed(&rng, so.seed);
    so.Ncameras = 1;
    so.landmarks_per_camera = o->points_min + (int)(rs_rng_uniform(&rng) * (o->points_max - o->points_min + 1));
    if (so.landmarks_per_camera > o->points_max) so.landmarks_per_camera = o->points_max;
    so.lensmodel = o->lensmodel;
    so.hfov_deg = o->hfov_deg;
    so.pixel_sigma_px = o->pixel_sigma_px;
    so.survey_sigma_h_m = o->survey_sigma_h_m;
    so.survey_sigma_v_m = 0.0;
    so.outlier_fraction = 0.0;
    so.elevated_fraction = 0.0;
    so.focal_error_range = o->focal_error_range;
    so.landmark_heights = RS_SITE_HEIGHT_UNKNOWN;
    so.force = true;
    row->seed = so.seed;
    char name[64];
    snprintf(name, sizeof name, "site%d", k);
    char *dir = rs_io_join(work_dir, name);
    if (!dir) return rs_err_set(err, RS_ERR_NOMEM, "bench sparse: out of memory");
    rs_site *site = NULL;
    rs_status st = rs_simulate_site(dir, &so, err);
    if (st == RS_OK) st = rs_site_load(&site, dir, err);
    rs_camera truth_cam = {0};
    char *path = rs_io_join(dir, "truth/cam1" RS_CAMERA_EXT_CAMERAMODEL);
    if (st == RS_OK)
        st = path ? rs_camera_read(&truth_cam, NULL, path, err) : rs_err_set(err, RS_ERR_NOMEM, "no memory");
    free(path);
    if (st == RS_OK) {
        row->focal_nominal_rel = site->cameras[0].camera.intrinsics[0] / truth_cam.intrinsics[0];
        const site_folds f = {.site = site, .truth = &truth_cam, .o = o};
        st = run_folds(row, &f, dir, err);
    }
    rs_camera_free(&truth_cam);
    rs_site_free(site);
    rs_io_remove_tree(dir);
    free(dir);
    return st;
}

// rs_calib_bench.c -- roadside bench calib: methods side by side, the Cramer-Rao bound, the
// stress run. See rs_calib_bench.h.
#include "bench/rs_bench_calib.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cairo.h>
#include <mrcal/mrcal.h>
#include <mrcal/poseutils.h>

#include "calib/rs_calib.h"
#include "calib/rs_calib_init.h"
#include "bench/rs_bench_opencv.h"
#include "calib/rs_calib_opengv.h"
#include "core/rs_io.h"
#include "sim/rs_simulate.h"
#include "core/rs_pose.h"
#include "core/rs_rng.h"

#define DEG (180.0 / M_PI)

// ---- the methods ----

typedef enum { LIB_ROADSIDE, LIB_OPENCV, LIB_OPENGV } bench_lib;

typedef struct {
    const char *name;
    bench_lib lib;
    int variant;    // roadside: 0 full, 1 init, 2 no prior; OpenCV/OpenGV: the shim's enum
    bool refine_lm; // OpenCV: + solvePnPRefineLM
} bench_method;

static const bench_method methods[] = {
    {"roadside", LIB_ROADSIDE, 0, false},
    {"roadside-init", LIB_ROADSIDE, 1, false},
    {"roadside-noprior", LIB_ROADSIDE, 2, false},
    {"cv-iterative", LIB_OPENCV, RS_BENCH_OPENCV_PNP_ITERATIVE, false},
    {"cv-iterative+lm", LIB_OPENCV, RS_BENCH_OPENCV_PNP_ITERATIVE, true},
    {"cv-epnp", LIB_OPENCV, RS_BENCH_OPENCV_PNP_EPNP, false},
    {"cv-epnp+lm", LIB_OPENCV, RS_BENCH_OPENCV_PNP_EPNP, true},
    {"cv-sqpnp", LIB_OPENCV, RS_BENCH_OPENCV_PNP_SQPNP, false},
    {"cv-sqpnp+lm", LIB_OPENCV, RS_BENCH_OPENCV_PNP_SQPNP, true},
    {"cv-ippe", LIB_OPENCV, RS_BENCH_OPENCV_PNP_IPPE, false},
    {"cv-ippe+lm", LIB_OPENCV, RS_BENCH_OPENCV_PNP_IPPE, true},
    {"cv-ransac", LIB_OPENCV, RS_BENCH_OPENCV_PNP_RANSAC, false},
    {"cv-ransac+lm", LIB_OPENCV, RS_BENCH_OPENCV_PNP_RANSAC, true},
    {"gv-p3p-kneip-ransac", LIB_OPENGV, RS_CALIB_OPENGV_POSE_P3P_KNEIP_RANSAC, false},
    {"gv-p3p-gao-ransac", LIB_OPENGV, RS_CALIB_OPENGV_POSE_P3P_GAO_RANSAC, false},
    {"gv-epnp", LIB_OPENGV, RS_CALIB_OPENGV_POSE_EPNP, false},
    {"gv-upnp", LIB_OPENGV, RS_CALIB_OPENGV_POSE_UPNP, false},
    {"gv-epnp+nonlin", LIB_OPENGV, RS_CALIB_OPENGV_POSE_EPNP_NONLINEAR, false},
};
enum { Nmethods = (int)(sizeof(methods) / sizeof(methods[0])) };

// ---- the configurations ----

typedef struct {
    const char *family;
    char config[40];
    rs_simulate_camera_options sim;
} bench_config;

static void baseline(rs_simulate_camera_options *s)
{
    rs_simulate_camera_options_default(s);
    s->lensmodel = "LENSMODEL_OPENCV8";
    s->Nlandmarks = 20;
    s->pixel_sigma_px = 1.0;
    s->survey_sigma_h_m = s->survey_sigma_v_m = 0.3;
    s->outlier_fraction = 0.0;
}

// Fills c (capacity 64) with the sweep; returns the count.
static int make_configs(bench_config *c, bool quick)
{
    int n = 0;
#define ADD(fam, fmt, val, field, expr)                                                           \
    do {                                                                                           \
        c[n].family = fam;                                                                         \
        snprintf(c[n].config, sizeof c[n].config, fmt, val);                                       \
        baseline(&c[n].sim);                                                                       \
        c[n].sim.field = (expr);                                                                   \
        n++;                                                                                       \
    } while (0)
    ADD("baseline", "%s", "baseline", Nlandmarks, 20);
    static const double noise_full[] = {0.1, 0.5, 2, 5}, noise_quick[] = {5};
    static const int lm_full[] = {4, 8, 50, 200}, lm_quick[] = {8};
    static const double out_full[] = {0.1, 0.25, 0.5}, out_quick[] = {0.25};
    static const double survey_full[] = {0, 1, 2};
    static const double height_full[] = {4, 20, 100};
    static const double dist_full[] = {10, 200, 2000};
    const double *noise = quick ? noise_quick : noise_full;
    const int *lm = quick ? lm_quick : lm_full;
    const double *out = quick ? out_quick : out_full;
    for (int i = 0; i < (quick ? 1 : 4); i++) ADD("noise", "noise=%gpx", noise[i], pixel_sigma_px, noise[i]);
    for (int i = 0; i < (quick ? 1 : 4); i++) ADD("landmarks", "N=%d", lm[i], Nlandmarks, lm[i]);
    for (int i = 0; i < (quick ? 1 : 3); i++)
        ADD("outliers", "outliers=%g%%", 100 * out[i], outlier_fraction, out[i]);
    if (quick) return n;
    for (int i = 0; i < 3; i++) {
        ADD("survey", "survey=%gm", survey_full[i], survey_sigma_h_m, survey_full[i]);
        c[n - 1].sim.survey_sigma_v_m = survey_full[i];
    }
    ADD("planar", "%s", "planar", elevated_fraction, 0.0);
    for (int i = 0; i < 3; i++) ADD("height", "height=%gm", height_full[i], camera_height_m, height_full[i]);
    for (int i = 0; i < 3; i++) {
        ADD("distance", "distance=%gm", dist_full[i], distance_m, dist_full[i]);
        c[n - 1].sim.max_range_m = fmax(80.0, 2.0 * dist_full[i]);
    }
#undef ADD
    return n;
}

void rs_bench_calib_options_default(rs_bench_calib_options *o)
{
    o->trials = 50;
    o->quick = false;
    o->seed = 1;
}

// ---- one trial ----

static double thread_cpu_us(void)
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return 1e6 * (double)t.tv_sec + 1e-3 * (double)t.tv_nsec;
}

enum { GRID_U = 12, GRID_V = 8 };

typedef struct {
    const rs_simulate_problem *P;
    const rs_simulate_camera_options *sim;
    double *sigma_enu;   // (N,3)
    double *sigma_px;    // (N,)
    double *v_cam;       // (N,3) scratch: bearings
    double q_grid[GRID_U * GRID_V][2];
    double g_true[GRID_U * GRID_V][3];
    int Ngrid;
} bench_trial;

// Rotation error vector e = r_est o r_true^-1 (mrcal_compose_r), and optionally de/dr_est.
static double rotation_error_deg(const double *r_est, const double *r_true, double *de_dr)
{
    const double r_inv[3] = {-r_true[0], -r_true[1], -r_true[2]};
    double e[3];
    mrcal_compose_r(e, de_dr, NULL, r_est, r_inv);
    return DEG * sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
}

static void fill_problem(rs_calib_problem *cp, const bench_trial *T, const double *p, const double *q,
                         int N, bool survey_exact)
{
    memset(cp, 0, sizeof *cp);
    cp->N = N;
    cp->p_enu_m = p;
    cp->sigma_enu_m = survey_exact ? NULL : T->sigma_enu;
    cp->q_px = q;
    cp->sigma_px = T->sigma_px;
    cp->camera = &T->P->camera;
}

// Runs method m on the trial's noisy data. *cond: condition number (roadside full/noprior).
static rs_status run_method(double rt[6], double *cond, int m, bench_trial *T, rs_err *err)
{
    const rs_simulate_problem *P = T->P;
    const bench_method *bm = &methods[m];
    *cond = NAN;
    if (bm->lib == LIB_ROADSIDE) {
        if (bm->variant == 1) {
            rs_calib_init_result ir;
            rs_calib_init_options io;
            rs_calib_init_options_default(&io);
            io.sigma_enu_m = T->sigma_enu; // as rs_calib_solve passes them
            const rs_status st = rs_calib_init_pose(&ir, NULL, &P->camera.lensmodel, P->camera.intrinsics,
                                                    P->p_enu_survey_m, P->q_px, P->Npoints, &io, err);
            if (st == RS_OK) memcpy(rt, ir.rt_cam_enu, sizeof ir.rt_cam_enu);
            return st;
        }
        rs_calib_problem cp;
        fill_problem(&cp, T, P->p_enu_survey_m, P->q_px, P->Npoints, bm->variant == 2);
        rs_calib_result res;
        const rs_status st = rs_calib_solve(&res, &cp, NULL, err);
        if (st == RS_OK) {
            memcpy(rt, res.rt_cam_enu, sizeof res.rt_cam_enu);
            *cond = res.condition_number;
        }
        rs_calib_result_free(&res);
        return st;
    }
    if (bm->lib == LIB_OPENCV)
        return rs_bench_opencv_pnp(rt, NULL, P->p_enu_survey_m, P->q_px, P->Npoints, P->camera.intrinsics,
                                   P->camera.Nintrinsics - 4, (rs_bench_opencv_pnp_method)bm->variant,
                                   bm->refine_lm, 8.0, err);
    if (!mrcal_unproject((mrcal_point3_t *)T->v_cam, (const mrcal_point2_t *)P->q_px, P->Npoints,
                         &P->camera.lensmodel, P->camera.intrinsics))
        return rs_err_set(err, RS_ERR_EXTERNAL, "mrcal_unproject failed");
    for (int i = 0; i < P->Npoints; i++) {
        double *v = &T->v_cam[3 * i];
        const double n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        for (int k = 0; k < 3; k++) v[k] /= n;
    }
    double Rt[12];
    const rs_status st = rs_calib_opengv_pose(Rt, T->v_cam, P->p_enu_survey_m, P->Npoints,
                                              (rs_calib_opengv_pose_method)bm->variant,
                                              atan(8.0 / P->camera.intrinsics[0]), 500, err);
    if (st == RS_OK) mrcal_rt_from_Rt(rt, NULL, Rt);
    return st;
}

// The Cramer-Rao bound of the trial: traces of the rotation-error and position covariances at
// the truth (see the header). False if the solver could not give it.
static bool crb(double *tr_rot_rad2, double *tr_pos_m2, bench_trial *T)
{
    const rs_simulate_problem *P = T->P;
    const int N = P->Npoints;
    double *p = malloc(sizeof(double) * 3 * (size_t)N), *q = malloc(sizeof(double) * 2 * (size_t)N);
    bool ok = false;
    if (p && q) {
        int n = 0;
        for (int i = 0; i < N; i++) {
            if (P->outlier[i]) continue;
            memcpy(&p[3 * n], &P->p_enu_true_m[3 * i], 3 * sizeof(double));
            memcpy(&q[2 * n], &P->q_true_px[2 * i], 2 * sizeof(double));
            n++;
        }
        rs_calib_problem cp;
        fill_problem(&cp, T, p, q, n, false);
        rs_calib_options opt;
        rs_calib_options_default(&opt);
        opt.robust_scale = 0.0;
        rs_calib_result res;
        if (rs_calib_solve(&res, &cp, &opt, NULL) == RS_OK) {
            double D[9], C[9];
            rotation_error_deg(res.rt_cam_enu, P->camera.rt_cam_enu, D);
            *tr_rot_rad2 = 0.0;
            for (int a = 0; a < 3; a++) {
                for (int b = 0; b < 3; b++) {
                    C[3 * a + b] = 0.0;
                    for (int k = 0; k < 3; k++) C[3 * a + b] += D[3 * a + k] * res.covariance_rt_cam_enu[6 * k + b];
                }
                for (int k = 0; k < 3; k++) *tr_rot_rad2 += C[3 * a + k] * D[3 * a + k];
            }
            *tr_pos_m2 = 0.0;
            for (int k = 0; k < 3; k++) *tr_pos_m2 += res.sigma_position_enu_m[k] * res.sigma_position_enu_m[k];
            ok = isfinite(*tr_rot_rad2) && isfinite(*tr_pos_m2);
        }
        rs_calib_result_free(&res);
    }
    free(p);
    free(q);
    return ok;
}

// The area of interest: a GRID_U x GRID_V grid of pixels whose true rays meet the ground
// within max_range_m of the camera.
static void ground_grid(bench_trial *T)
{
    const rs_simulate_problem *P = T->P;
    const double n_up[3] = {0, 0, 1};
    T->Ngrid = 0;
    for (int j = 0; j < GRID_V; j++)
        for (int i = 0; i < GRID_U; i++) {
            double *q = T->q_grid[T->Ngrid], *g = T->g_true[T->Ngrid];
            q[0] = (i + 0.5) * P->camera.width / GRID_U;
            q[1] = (j + 0.5) * P->camera.height / GRID_V;
            if (rs_camera_locate_ground(g, &P->camera, q, n_up, 0.0, NULL) != RS_OK)
                continue;
            if (hypot(g[0] - P->p_cam_enu_m[0], g[1] - P->p_cam_enu_m[1]) <= T->sim->max_range_m)
                T->Ngrid++;
        }
}

// ---- accumulation ----

typedef struct {
    double *time_us; // (trials,)
    double *cond;    // (trials,)
    int Ncalls, Nok, Nfail, Ncond, Nground;
    double ss_rot, ss_pos, ss_ground;
    char failure[120];
} bench_acc;

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double quantile(double *v, int n, double p)
{
    if (n <= 0) return NAN;
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    const double k = p * (n - 1);
    const int i = (int)floor(k);
    return i + 1 < n ? v[i] + (k - i) * (v[i + 1] - v[i]) : v[n - 1];
}

static void trial_method(bench_acc *A, int m, bench_trial *T, double scale_m)
{
    const rs_simulate_problem *P = T->P;
    rs_err e = {0};
    double rt[6], cond;
    const double t0 = thread_cpu_us();
    const rs_status st = run_method(rt, &cond, m, T, &e);
    A->time_us[A->Ncalls++] = thread_cpu_us() - t0;
    if (st != RS_OK) {
        A->Nfail++;
        if (!A->failure[0])
            snprintf(A->failure, sizeof A->failure, "%s: %.100s", rs_strerror(st), e.msg[0] ? e.msg : "-");
        return;
    }
    double C[3];
    rs_pose_position_from_rt(C, NULL, rt);
    const double drot = rotation_error_deg(rt, P->camera.rt_cam_enu, NULL);
    const double dpos = hypot(hypot(C[0] - P->p_cam_enu_m[0], C[1] - P->p_cam_enu_m[1]), C[2] - P->p_cam_enu_m[2]);
    if (!(drot <= 5.0 && dpos <= 0.2 * scale_m)) {
        A->Nfail++;
        if (!A->failure[0])
            snprintf(A->failure, sizeof A->failure, "wrong pose: rotation off by %.3g deg, position by %.3g m",
                     drot, dpos);
        return;
    }
    A->Nok++;
    A->ss_rot += drot * drot;
    A->ss_pos += dpos * dpos;
    if (isfinite(cond)) A->cond[A->Ncond++] = cond;
    const double n_up[3] = {0, 0, 1};
    for (int g = 0; g < T->Ngrid; g++) {
        double p[3];
        rs_camera estimated = P->camera;
        memcpy(estimated.rt_cam_enu, rt, sizeof estimated.rt_cam_enu);
        if (rs_camera_locate_ground(p, &estimated, T->q_grid[g], n_up, 0.0, NULL) != RS_OK)
            p[0] = p[1] = p[2] = INFINITY; // the estimated ray misses the ground: counted, huge
        const double d2 = (p[0] - T->g_true[g][0]) * (p[0] - T->g_true[g][0]) +
                          (p[1] - T->g_true[g][1]) * (p[1] - T->g_true[g][1]);
        A->ss_ground += isfinite(d2) ? d2 : scale_m * scale_m;
        A->Nground++;
    }
}

static rs_status run_config(rs_bench_calib_row *rows, const bench_config *c, int ic,
                            const rs_bench_calib_options *o, bench_acc *acc)
{
    const int N = c->sim.Nlandmarks;
    bench_trial T = {0};
    T.sim = &c->sim;
    T.sigma_enu = malloc(sizeof(double) * 3 * (size_t)N);
    T.sigma_px = malloc(sizeof(double) * (size_t)N);
    T.v_cam = malloc(sizeof(double) * 3 * (size_t)N);
    if (!T.sigma_enu || !T.sigma_px || !T.v_cam) {
        free(T.sigma_enu);
        free(T.sigma_px);
        free(T.v_cam);
        return RS_ERR_NOMEM;
    }
    for (int i = 0; i < N; i++) {
        T.sigma_px[i] = c->sim.pixel_sigma_px;
        T.sigma_enu[3 * i] = T.sigma_enu[3 * i + 1] = c->sim.survey_sigma_h_m;
        T.sigma_enu[3 * i + 2] = c->sim.survey_sigma_v_m;
    }
    const double scale_m = hypot(c->sim.camera_height_m, c->sim.distance_m);
    double ss_crb_rot = 0.0, ss_crb_pos = 0.0;
    int Ncrb = 0, Ngen = 0;
    char genfail[120] = "";
    for (int k = 0; k < o->trials; k++) {
        rs_simulate_camera_options sim = c->sim;
        sim.seed = o->seed + 1000003ull * (uint64_t)ic + (uint64_t)k;
        rs_simulate_problem *P = NULL;
        rs_err e = {0};
        const rs_status st = rs_simulate_camera_problem(&P, &sim, &e);
        if (st != RS_OK) {
            if (!genfail[0]) snprintf(genfail, sizeof genfail, "simulator: %.100s", e.msg);
            continue;
        }
        Ngen++;
        T.P = P;
        ground_grid(&T);
        double tr_r, tr_p;
        if (crb(&tr_r, &tr_p, &T)) {
            ss_crb_rot += tr_r;
            ss_crb_pos += tr_p;
            Ncrb++;
        }
        for (int m = 0; m < Nmethods; m++) trial_method(&acc[m], m, &T, scale_m);
        rs_simulate_problem_free(P);
    }
    free(T.sigma_enu);
    free(T.sigma_px);
    free(T.v_cam);

    const double crb_rot = Ncrb ? DEG * sqrt(ss_crb_rot / Ncrb) : NAN;
    const double crb_pos = Ncrb ? sqrt(ss_crb_pos / Ncrb) : NAN;
    for (int m = 0; m < Nmethods; m++) {
        bench_acc *A = &acc[m];
        rs_bench_calib_row *r = &rows[m];
        memset(r, 0, sizeof *r);
        snprintf(r->family, sizeof r->family, "%s", c->family);
        snprintf(r->config, sizeof r->config, "%s", c->config);
        snprintf(r->method, sizeof r->method, "%s", methods[m].name);
        r->trials = Ngen;
        r->failures = A->Nfail;
        r->time_med_us = quantile(A->time_us, A->Ncalls, 0.5);
        r->time_p90_us = quantile(A->time_us, A->Ncalls, 0.9);
        r->rot_rms_deg = A->Nok ? sqrt(A->ss_rot / A->Nok) : NAN;
        r->pos_rms_m = A->Nok ? sqrt(A->ss_pos / A->Nok) : NAN;
        r->ground_rms_m = A->Nground ? sqrt(A->ss_ground / A->Nground) : NAN;
        r->crb_rot_deg = crb_rot;
        r->crb_pos_m = crb_pos;
        r->rot_ratio = r->rot_rms_deg / crb_rot;
        r->pos_ratio = r->pos_rms_m / crb_pos;
        r->cond_median = quantile(A->cond, A->Ncond, 0.5);
        snprintf(r->failure, sizeof r->failure, "%s", Ngen ? A->failure : genfail);
    }
    return RS_OK;
}

rs_status rs_bench_calib_run(rs_bench_calib_row **rows, int *Nrows, const rs_bench_calib_options *o,
                             void (*progress)(int done, int total, void *cookie), void *cookie,
                             rs_err *err)
{
    *rows = NULL;
    *Nrows = 0;
    if (!o || o->trials < 1 || o->trials > 1000000)
        return rs_err_set(err, RS_ERR_USAGE, "trials: must be in [1, 1000000]");
    bench_config cfg[64];
    const int Nc = make_configs(cfg, o->quick);
    rs_bench_calib_row *out = calloc((size_t)Nc * Nmethods, sizeof *out);
    bench_acc acc[Nmethods];
    memset(acc, 0, sizeof acc);
    bool ok = out != NULL;
    for (int m = 0; m < Nmethods && ok; m++) {
        acc[m].time_us = malloc(sizeof(double) * (size_t)o->trials);
        acc[m].cond = malloc(sizeof(double) * (size_t)o->trials);
        ok = acc[m].time_us && acc[m].cond;
    }
    rs_status st = ok ? RS_OK : RS_ERR_NOMEM;
    for (int c = 0; c < Nc && st == RS_OK; c++) {
        for (int m = 0; m < Nmethods; m++) {
            double *t = acc[m].time_us, *k = acc[m].cond;
            memset(&acc[m], 0, sizeof acc[m]);
            acc[m].time_us = t;
            acc[m].cond = k;
        }
        st = run_config(&out[c * Nmethods], &cfg[c], c, o, acc);
        if (progress) progress(c + 1, Nc, cookie);
    }
    for (int m = 0; m < Nmethods; m++) {
        free(acc[m].time_us);
        free(acc[m].cond);
    }
    if (st != RS_OK) {
        free(out);
        return rs_err_set(err, st, "bench calib: out of memory");
    }
    *rows = out;
    *Nrows = Nc * Nmethods;
    return RS_OK;
}

// ---- CSV ----

rs_status rs_bench_calib_write_csv(const char *path, const rs_bench_calib_row *rows, int Nrows, rs_err *err)
{
    rs_io_atomic a;
    rs_status st = rs_io_atomic_open(&a, path, err);
    if (st != RS_OK) return st;
    fprintf(a.f, "family,config,method,trials,failures,time_med_us,time_p90_us,rot_rms_deg,pos_rms_m,"
                 "ground_rms_m,crb_rot_deg,crb_pos_m,rot_ratio,pos_ratio,cond_median,failure\n");
    for (int i = 0; i < Nrows; i++) {
        const rs_bench_calib_row *r = &rows[i];
        char failure[sizeof r->failure];
        snprintf(failure, sizeof failure, "%s", r->failure);
        for (char *p = failure; *p; p++)
            if (*p == '"' || *p == '\n' || *p == '\r') *p = '\'';
        fprintf(a.f, "%s,%s,%s,%d,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,\"%s\"\n", r->family,
                r->config, r->method, r->trials, r->failures, r->time_med_us, r->time_p90_us, r->rot_rms_deg,
                r->pos_rms_m, r->ground_rms_m, r->crb_rot_deg, r->crb_pos_m, r->rot_ratio, r->pos_ratio,
                r->cond_median, failure);
    }
    if (ferror(a.f)) {
        rs_io_atomic_abort(&a);
        return rs_err_set(err, RS_ERR_IO, "%s: write failed", path);
    }
    return rs_io_atomic_commit(&a, err);
}

// ---- the plot ----

static void method_colour(int m, double rgb[3])
{
    // hues spread around the circle, lightness alternating so neighbours stay apart
    const double h = 6.0 * fmod(m * 0.61803398875, 1.0);
    const double v = (m % 2) ? 0.85 : 0.55, s = 0.9;
    const int i = (int)h;
    const double f = h - i, p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
    const double tab[6][3] = {{v, t, p}, {q, v, p}, {p, v, t}, {p, q, v}, {t, p, v}, {v, p, q}};
    memcpy(rgb, tab[i % 6], sizeof tab[0]);
}

static void marker(cairo_t *cr, int m, double x, double y)
{
    const double s = 6.0;
    double rgb[3];
    method_colour(m, rgb);
    cairo_new_path(cr);
    cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
    switch (methods[m].lib) {
    case LIB_ROADSIDE: cairo_arc(cr, x, y, s, 0, 2 * M_PI); break;
    case LIB_OPENCV: cairo_rectangle(cr, x - s, y - s, 2 * s, 2 * s); break;
    case LIB_OPENGV:
        cairo_move_to(cr, x, y - s * 1.2);
        cairo_line_to(cr, x + s * 1.1, y + s * 0.8);
        cairo_line_to(cr, x - s * 1.1, y + s * 0.8);
        cairo_close_path(cr);
        break;
    }
    cairo_fill_preserve(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 0.8);
    cairo_stroke(cr);
}

typedef struct {
    double x0, y0, w, h;          // panel in device units
    double lx0, lx1, ly0, ly1;    // log10 ranges
} panel;

static double px(const panel *p, double v) { return p->x0 + p->w * (log10(v) - p->lx0) / (p->lx1 - p->lx0); }
static double py(const panel *p, double v) { return p->y0 + p->h - p->h * (log10(v) - p->ly0) / (p->ly1 - p->ly0); }

static void draw_axes(cairo_t *cr, const panel *p, const char *title)
{
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 1.0);
    cairo_rectangle(cr, p->x0, p->y0, p->w, p->h);
    cairo_stroke(cr);
    cairo_set_font_size(cr, 11);
    char s[32];
    for (int e = (int)ceil(p->lx0); e <= (int)floor(p->lx1); e++) {
        const double x = px(p, pow(10, e));
        cairo_set_source_rgb(cr, 0.85, 0.85, 0.85);
        cairo_move_to(cr, x, p->y0);
        cairo_line_to(cr, x, p->y0 + p->h);
        cairo_stroke(cr);
        cairo_set_source_rgb(cr, 0, 0, 0);
        snprintf(s, sizeof s, "1e%d", e);
        cairo_move_to(cr, x - 10, p->y0 + p->h + 14);
        cairo_show_text(cr, s);
    }
    for (int e = (int)ceil(p->ly0); e <= (int)floor(p->ly1); e++) {
        const double y = py(p, pow(10, e));
        cairo_set_source_rgb(cr, e == 0 ? 0.3 : 0.85, e == 0 ? 0.6 : 0.85, e == 0 ? 0.3 : 0.85);
        cairo_move_to(cr, p->x0, y);
        cairo_line_to(cr, p->x0 + p->w, y);
        cairo_stroke(cr);
        cairo_set_source_rgb(cr, 0, 0, 0);
        snprintf(s, sizeof s, "1e%d", e);
        cairo_move_to(cr, p->x0 - 30, y + 4);
        cairo_show_text(cr, s);
    }
    cairo_move_to(cr, p->x0 + p->w / 2 - 40, p->y0 + p->h + 28);
    cairo_show_text(cr, "median time, us");
    cairo_set_font_size(cr, 13);
    cairo_move_to(cr, p->x0 + 4, p->y0 - 6);
    cairo_show_text(cr, title);
    cairo_new_path(cr);
}

rs_status rs_bench_calib_plot(const char *path, const rs_bench_calib_row *rows, int Nrows, rs_err *err)
{
    // families in order of appearance; per family and method: median time, geometric mean ratio
    enum { MAXF = 16 };
    const char *fam[MAXF];
    int Nf = 0;
    for (int i = 0; i < Nrows; i++) {
        int f = 0;
        while (f < Nf && strcmp(fam[f], rows[i].family)) f++;
        if (f == Nf && Nf < MAXF) fam[Nf++] = rows[i].family;
    }
    double X[MAXF][Nmethods], Y[MAXF][Nmethods];
    double xmin = INFINITY, xmax = -INFINITY, ymin = INFINITY, ymax = -INFINITY;
    for (int f = 0; f < Nf; f++)
        for (int m = 0; m < Nmethods; m++) {
            double lt = 0, lr = 0;
            int nt = 0, nr = 0;
            for (int i = 0; i < Nrows; i++) {
                if (strcmp(rows[i].family, fam[f]) || strcmp(rows[i].method, methods[m].name)) continue;
                if (rows[i].time_med_us > 0) lt += log(rows[i].time_med_us), nt++;
                if (rows[i].pos_ratio > 0 && isfinite(rows[i].pos_ratio)) lr += log(rows[i].pos_ratio), nr++;
            }
            X[f][m] = nt && nr ? exp(lt / nt) : NAN;
            Y[f][m] = nt && nr ? exp(lr / nr) : NAN;
            if (isfinite(X[f][m]) && isfinite(Y[f][m])) {
                xmin = fmin(xmin, X[f][m]);
                xmax = fmax(xmax, X[f][m]);
                ymin = fmin(ymin, Y[f][m]);
                ymax = fmax(ymax, Y[f][m]);
            }
        }
    if (!(xmin <= xmax)) xmin = 1, xmax = 10, ymin = 1, ymax = 10;
    const double lx0 = floor(log10(xmin)), lx1 = fmax(ceil(log10(xmax)), lx0 + 1);
    const double ly0 = fmin(floor(log10(ymin)), 0.0), ly1 = fmax(ceil(log10(ymax)), ly0 + 1);

    const int W = 1600, H = 1000, cols = 4, legend_w = 230;
    const int rows_p = Nf > cols ? (Nf + cols - 1) / cols : 1;
    cairo_surface_t *surf = cairo_image_surface_create(CAIRO_FORMAT_RGB24, W, H);
    cairo_t *cr = cairo_create(surf);
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_font_size(cr, 16);
    cairo_move_to(cr, 20, 24);
    cairo_show_text(cr, "roadside bench calib: median CPU time (us) vs position error / Cramer-Rao bound "
                        "(log-log; 1 = at the bound; one point per method per configuration family)");
    const double cw = (double)(W - legend_w - 20) / cols, ch = (double)(H - 50) / rows_p;
    for (int f = 0; f < Nf; f++) {
        panel p = {20 + 50 + (f % cols) * cw, 50 + 20 + (f / cols) * ch, cw - 70, ch - 60, lx0, lx1, ly0, ly1};
        char title[64];
        snprintf(title, sizeof title, "%s", fam[f]);
        draw_axes(cr, &p, title);
        for (int m = 0; m < Nmethods; m++)
            if (isfinite(X[f][m]) && isfinite(Y[f][m])) marker(cr, m, px(&p, X[f][m]), py(&p, Y[f][m]));
    }
    cairo_set_font_size(cr, 12);
    for (int m = 0; m < Nmethods; m++) {
        const double x = W - legend_w + 10, y = 80 + 24.0 * m;
        marker(cr, m, x, y);
        cairo_set_source_rgb(cr, 0, 0, 0);
        cairo_move_to(cr, x + 14, y + 4);
        cairo_show_text(cr, methods[m].name);
    }
    cairo_move_to(cr, W - legend_w + 10, 80 + 24.0 * Nmethods + 10);
    cairo_show_text(cr, "x: time (us), y: pos err / CRB");
    cairo_destroy(cr);

    rs_io_atomic a;
    rs_status st = cairo_surface_status(surf) == CAIRO_STATUS_SUCCESS
                       ? rs_io_atomic_open(&a, path, err)
                       : rs_err_set(err, RS_ERR_EXTERNAL, "%s: cairo: %s", path,
                                    cairo_status_to_string(cairo_surface_status(surf)));
    if (st == RS_OK) st = rs_io_atomic_release(&a, err);
    if (st == RS_OK) {
        const cairo_status_t cs = cairo_surface_write_to_png(surf, a.tmp_path);
        if (cs != CAIRO_STATUS_SUCCESS) {
            rs_io_atomic_abort(&a);
            st = rs_err_set(err, RS_ERR_IO, "%s: cairo: %s", path, cairo_status_to_string(cs));
        } else {
            st = rs_io_atomic_commit(&a, err);
        }
    }
    cairo_surface_destroy(surf);
    return st;
}

// ---- the stress run ----

static bool all_finite(const double *v, int n)
{
    for (int i = 0; i < n; i++)
        if (!isfinite(v[i])) return false;
    return true;
}

// Random options of stress problem `seed` (see the header for the ranges).
static void stress_options(rs_simulate_camera_options *s, uint64_t seed)
{
    static const char *const lens[] = {"LENSMODEL_PINHOLE", "LENSMODEL_OPENCV8", "LENSMODEL_CAHVOR"};
    rs_rng rng;
    rs_rng_seed(&rng, seed ^ 0x5eed5eed5eedull);
#define U() rs_rng_uniform(&rng)
    rs_simulate_camera_options_default(s);
    s->seed = seed;
    s->lensmodel = lens[(int)(3 * U())];
    s->hfov_deg = 20 + 70 * U();
    s->Nlandmarks = 4 + (int)(37 * U());
    s->pixel_sigma_px = pow(10.0, -3.0 + 3.7 * U());
    s->outlier_fraction = U() < 0.3 ? 0.0 : 0.5 * U();
    s->survey_sigma_h_m = U() < 0.2 ? 0.0 : 2.0 * U();
    s->survey_sigma_v_m = s->survey_sigma_h_m * (0.5 + U());
    s->elevated_fraction = U() < 0.4 ? 0.0 : 0.5 * U();
    s->camera_height_m = 3.0 * pow(100.0 / 3.0, U());
    s->distance_m = 10.0 * pow(200.0, U());
    s->max_range_m = s->distance_m * (1.5 + 2.0 * U());
    s->roll_sigma_deg = 3.0 * U();
#undef U
}

// Cholesky solve of the 6x6 SPD covariance: returns d^T C^-1 d, or NAN if C is not SPD.
static double mahalanobis2(const double *C, const double *d)
{
    double L[36] = {0}, y[6];
    for (int i = 0; i < 6; i++)
        for (int j = 0; j <= i; j++) {
            double s = C[6 * i + j];
            for (int k = 0; k < j; k++) s -= L[6 * i + k] * L[6 * j + k];
            if (i == j) {
                if (!(s > 0)) return NAN;
                L[6 * i + i] = sqrt(s);
            } else {
                L[6 * i + j] = s / L[6 * j + j];
            }
        }
    double m2 = 0;
    for (int i = 0; i < 6; i++) {
        double s = d[i];
        for (int k = 0; k < i; k++) s -= L[6 * i + k] * y[k];
        y[i] = s / L[6 * i + i];
        m2 += y[i] * y[i];
    }
    return m2;
}

// d = r_est - r_true in the chart of r_est (where the covariance is stated), with r_true written
// as whichever of its two Rodrigues vectors (angle theta about u, or theta - 2 pi about u) is
// nearer: near a half-turn the same rotation has r and nearly -r, and a plain difference of the
// vectors would call a perfect estimate wrong.
static void rotation_difference(double d[3], const double r_est[3], const double r_true[3])
{
    const double th = sqrt(r_true[0] * r_true[0] + r_true[1] * r_true[1] + r_true[2] * r_true[2]);
    double best = INFINITY;
    for (int alt = 0; alt < 2; alt++) {
        if (alt && !(th > 0)) break;
        const double s = alt ? 1.0 - 2.0 * M_PI / th : 1.0;
        double e[3], n2 = 0;
        for (int k = 0; k < 3; k++) {
            e[k] = r_est[k] - s * r_true[k];
            n2 += e[k] * e[k];
        }
        if (n2 < best) {
            best = n2;
            memcpy(d, e, sizeof e);
        }
    }
}

static void stress_bad(rs_bench_calib_stress_summary *S, uint64_t seed, const char *what, double v)
{
    if (S->first_bad[0]) return;
    S->first_bad_seed = seed;
    snprintf(S->first_bad, sizeof S->first_bad, "%s (%.3g)", what, v);
}

// Solves one stress problem and checks the result (see the header).
static void stress_one(rs_bench_calib_stress_summary *S, uint64_t seed)
{
    rs_simulate_camera_options s;
    stress_options(&s, seed);
    rs_simulate_problem *P = NULL;
    if (rs_simulate_camera_problem(&P, &s, NULL) != RS_OK) return;
    S->Ngenerated++;
    const int N = P->Npoints;
    double *sig = malloc(sizeof(double) * 4 * (size_t)N);
    if (!sig) {
        rs_simulate_problem_free(P);
        return;
    }
    for (int i = 0; i < N; i++) {
        sig[3 * i] = sig[3 * i + 1] = s.survey_sigma_h_m;
        sig[3 * i + 2] = s.survey_sigma_v_m;
        sig[3 * N + i] = fmax(s.pixel_sigma_px, 1e-3);
    }
    rs_calib_problem cp = {.N = N, .p_enu_m = P->p_enu_survey_m, .sigma_enu_m = sig, .q_px = P->q_px,
                           .sigma_px = sig + 3 * N, .camera = &P->camera};
    rs_calib_options opt;
    rs_calib_options_default(&opt);
    rs_calib_result r;
    rs_err e = {0};
    const rs_status st = rs_calib_solve(&r, &cp, &opt, &e);
    if (st != RS_OK) {
        S->Nerror[(unsigned)st < 16 ? st : 15]++;
        if (strlen(e.msg) < 8) {
            S->Nunnamed++;
            stress_bad(S, seed, "an error without a message, status", st);
        }
    } else {
        S->Nok++;
        const bool finite = all_finite(r.rt_cam_enu, 6) && all_finite(r.covariance_rt_cam_enu, 36) &&
                            all_finite(r.position_enu_m, 3) && all_finite(r.sigma_position_enu_m, 3) &&
                            all_finite(r.yaw_pitch_roll_deg, 3) && all_finite(r.sigma_yaw_pitch_roll_deg, 3) &&
                            isfinite(r.rms_px) && isfinite(r.condition_number) && isfinite(r.variance_factor);
        bool diag = true;
        for (int k = 0; k < 6; k++) diag = diag && r.covariance_rt_cam_enu[7 * k] > 0;
        if (!finite || !diag) {
            S->Nnonfinite++;
            stress_bad(S, seed, finite ? "covariance diagonal not positive" : "non-finite output", 0);
        }
        const bool flagged = r.condition_number > opt.condition_warn;
        if (flagged) {
            S->Nflagged++;
            if (!strstr(r.warnings, "condition number")) {
                S->Nunflagged++;
                stress_bad(S, seed, "condition number beyond the bound without a warning", r.condition_number);
            }
        }
        if (isfinite(r.condition_number)) S->cond_max = fmax(S->cond_max, r.condition_number);
        double d[6];
        rotation_difference(d, r.rt_cam_enu, P->camera.rt_cam_enu);
        for (int k = 3; k < 6; k++) d[k] = r.rt_cam_enu[k] - P->camera.rt_cam_enu[k];
        const double m2 = mahalanobis2(r.covariance_rt_cam_enu, d);
        if (!flagged && !r.warnings[0] && !(m2 <= 100.0)) {
            S->Nbad++;
            stress_bad(S, seed, "a confident wrong pose: Mahalanobis distance", sqrt(m2));
        }
    }
    rs_calib_result_free(&r);
    free(sig);
    rs_simulate_problem_free(P);
}

rs_status rs_bench_calib_stress(rs_bench_calib_stress_summary *summary, int Nproblems, uint64_t seed,
                                rs_err *err)
{
    memset(summary, 0, sizeof *summary);
    if (Nproblems < 1) return rs_err_set(err, RS_ERR_USAGE, "stress: Nproblems = %d, must be >= 1", Nproblems);
    summary->Nproblems = Nproblems;
    for (int k = 0; k < Nproblems; k++) stress_one(summary, seed + (uint64_t)k);
    return RS_OK;
}

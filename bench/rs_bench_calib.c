// rs_bench_calib.c -- roadside bench calib: the methods side by side on the sweep of simulated
// problems, with the Cramer-Rao bound. See rs_bench_calib.h; the CSV and the plot are in
// rs_bench_calib_output.c, the stress run in rs_bench_calib_stress.c.
#include "bench/rs_bench_calib.h"
#include "bench/internal/rs_bench_calib_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <mrcal/mrcal.h>
#include <mrcal/poseutils.h>

#include "bench/rs_bench_opencv.h"
#include "calib/rs_calib.h"
#include "calib/rs_calib_init.h"
#include "calib/rs_calib_opengv.h"
#include "core/rs_lens.h"
#include "core/rs_pose.h"
#include "core/rs_stats.h"
#include "core/rs_units.h"
#include "sim/rs_simulate.h"

// ---- the methods ----

const rs_bench_calib_method rs_bench_calib_methods[RS_BENCH_CALIB_NMETHODS] = {
    {"roadside", RS_BENCH_CALIB_LIB_ROADSIDE, 0, false},
    {"roadside-init", RS_BENCH_CALIB_LIB_ROADSIDE, 1, false},
    {"roadside-noprior", RS_BENCH_CALIB_LIB_ROADSIDE, 2, false},
    {"cv-iterative", RS_BENCH_CALIB_LIB_OPENCV, RS_BENCH_OPENCV_PNP_ITERATIVE, false},
    {"cv-iterative+lm", RS_BENCH_CALIB_LIB_OPENCV, RS_BENCH_OPENCV_PNP_ITERATIVE, true},
    {"cv-epnp", RS_BENCH_CALIB_LIB_OPENCV, RS_BENCH_OPENCV_PNP_EPNP, false},
    {"cv-epnp+lm", RS_BENCH_CALIB_LIB_OPENCV, RS_BENCH_OPENCV_PNP_EPNP, true},
    {"cv-sqpnp", RS_BENCH_CALIB_LIB_OPENCV, RS_BENCH_OPENCV_PNP_SQPNP, false},
    {"cv-sqpnp+lm", RS_BENCH_CALIB_LIB_OPENCV, RS_BENCH_OPENCV_PNP_SQPNP, true},
    {"cv-ippe", RS_BENCH_CALIB_LIB_OPENCV, RS_BENCH_OPENCV_PNP_IPPE, false},
    {"cv-ippe+lm", RS_BENCH_CALIB_LIB_OPENCV, RS_BENCH_OPENCV_PNP_IPPE, true},
    {"cv-ransac", RS_BENCH_CALIB_LIB_OPENCV, RS_BENCH_OPENCV_PNP_RANSAC, false},
    {"cv-ransac+lm", RS_BENCH_CALIB_LIB_OPENCV, RS_BENCH_OPENCV_PNP_RANSAC, true},
    {"gv-p3p-kneip-ransac", RS_BENCH_CALIB_LIB_OPENGV, RS_CALIB_OPENGV_POSE_P3P_KNEIP_RANSAC, false},
    {"gv-p3p-gao-ransac", RS_BENCH_CALIB_LIB_OPENGV, RS_CALIB_OPENGV_POSE_P3P_GAO_RANSAC, false},
    {"gv-epnp", RS_BENCH_CALIB_LIB_OPENGV, RS_CALIB_OPENGV_POSE_EPNP, false},
    {"gv-upnp", RS_BENCH_CALIB_LIB_OPENGV, RS_CALIB_OPENGV_POSE_UPNP, false},
    {"gv-epnp+nonlin", RS_BENCH_CALIB_LIB_OPENGV, RS_CALIB_OPENGV_POSE_EPNP_NONLINEAR, false},
};

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
#define ADD(fam, fmt, val, field, expr)                      \
    do {                                                     \
        c[n].family = fam;                                   \
        snprintf(c[n].config, sizeof c[n].config, fmt, val); \
        baseline(&c[n].sim);                                 \
        c[n].sim.field = (expr);                             \
        n++;                                                 \
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
    for (int i = 0; i < (quick ? 1 : 3); i++) ADD("outliers", "outliers=%g%%", 100 * out[i], outlier_fraction, out[i]);
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
    // fisheye: one overhead camera over the junction, 1280x960, 20 ground points (issue 38)
    static const char *const fisheye[2] = {"equidistant", "kannala-brandt"};
    for (int i = 0; i < 2; i++) {
        c[n].family = "fisheye";
        snprintf(c[n].config, sizeof c[n].config, "%s", fisheye[i]);
        baseline(&c[n].sim);
        rs_simulate_camera_options *s = &c[n].sim;
        s->lensmodel = "LENSMODEL_CAHVORE_linearity=0.00";
        s->width_px = 1280;
        s->height_px = 960;
        s->hfov_deg = 216; // f = 640 px / (108 deg in radians) = 340 px
        s->distortion = i == 1;
        s->camera_height_m = 10;
        s->distance_m = 3;
        s->max_range_m = 40;
        s->elevated_fraction = 0;
        n++;
    }
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
    double *sigma_enu; // (N,3)
    double *sigma_px;  // (N,)
    double *v_cam;     // (N,3) scratch: bearings
    double q_grid[GRID_U * GRID_V][2];
    double g_true[GRID_U * GRID_V][3];
    int Ngrid;
} bench_trial;

static void fill_problem(rs_calib_problem *cp, const bench_trial *T, const double *p, const double *q, int N,
                         bool survey_exact)
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
    const rs_bench_calib_method *bm = &rs_bench_calib_methods[m];
    *cond = NAN;
    if (bm->lib == RS_BENCH_CALIB_LIB_ROADSIDE) {
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
    if (bm->lib == RS_BENCH_CALIB_LIB_OPENCV && P->camera.lensmodel.type == MRCAL_LENSMODEL_CAHVORE) {
        // a fisheye (docs/conventions.md, "Fisheye lenses"): k1, k2 = r1, r2
        const double *in = P->camera.intrinsics, kb[8] = {in[0], in[1], in[2], in[3], in[7], in[8], 0, 0};
        return rs_bench_opencv_pnp_fisheye(rt, NULL, P->p_enu_survey_m, P->q_px, P->Npoints, kb,
                                           (rs_bench_opencv_pnp_method)bm->variant, bm->refine_lm, 8.0, err);
    }
    if (bm->lib == RS_BENCH_CALIB_LIB_OPENCV)
        return rs_bench_opencv_pnp(rt, NULL, P->p_enu_survey_m, P->q_px, P->Npoints, P->camera.intrinsics,
                                   P->camera.Nintrinsics - 4, (rs_bench_opencv_pnp_method)bm->variant, bm->refine_lm,
                                   8.0, err);
    if (!rs_lens_unproject((mrcal_point3_t *)T->v_cam, (const mrcal_point2_t *)P->q_px, P->Npoints,
                           &P->camera.lensmodel, P->camera.intrinsics))
        return rs_err_set(err, RS_ERR_EXTERNAL, "mrcal_unproject failed");
    for (int i = 0; i < P->Npoints; i++) {
        double *v = &T->v_cam[3 * i];
        const double n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        for (int k = 0; k < 3; k++) v[k] /= n;
    }
    double Rt[12];
    const rs_status st =
        rs_calib_opengv_pose(Rt, T->v_cam, P->p_enu_survey_m, P->Npoints, (rs_calib_opengv_pose_method)bm->variant,
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
        opt.estimate_noise = false; // the bound is at the true noise: noise-free data estimate none
        rs_calib_result res;
        if (rs_calib_solve(&res, &cp, &opt, NULL) == RS_OK) {
            double D[9], C[9];
            rs_pose_rotation_between(NULL, D, res.rt_cam_enu, P->camera.rt_cam_enu); // D = de/dr_est
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
            if (rs_camera_locate_ground(g, &P->camera, q, n_up, 0.0, NULL) != RS_OK) continue;
            if (hypot(g[0] - P->p_cam_enu_m[0], g[1] - P->p_cam_enu_m[1]) <= T->sim->max_range_m) T->Ngrid++;
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

static void trial_method(bench_acc *A, int m, bench_trial *T, double scale_m)
{
    const rs_simulate_problem *P = T->P;
    rs_err e = {0};
    double rt[6], cond;
    // One untimed call first, the same method on the same problem: every method is timed warm,
    // whatever ran before it. (Timed cold, each method paid for what the one before it had put
    // in the caches: cv-ransac+lm ran right after cv-ransac, its own code, and roadside after
    // OpenGV's methods and the simulator; on 4 landmarks that made roadside 1.10-1.14x
    // OpenCV's time where, each alternating with the other, it is 0.90x; docs/benchmarks.md.)
    run_method(rt, &cond, m, T, &e);
    e = (rs_err){0};
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
    const double drot = RS_DEG_PER_RAD * rs_pose_rotation_between(NULL, NULL, rt, P->camera.rt_cam_enu);
    const double dpos = hypot(hypot(C[0] - P->p_cam_enu_m[0], C[1] - P->p_cam_enu_m[1]), C[2] - P->p_cam_enu_m[2]);
    if (!(drot <= 5.0 && dpos <= 0.2 * scale_m)) {
        A->Nfail++;
        if (!A->failure[0])
            snprintf(A->failure, sizeof A->failure, "wrong pose: rotation off by %.3g deg, position by %.3g m", drot,
                     dpos);
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
        const double d2 =
            (p[0] - T->g_true[g][0]) * (p[0] - T->g_true[g][0]) + (p[1] - T->g_true[g][1]) * (p[1] - T->g_true[g][1]);
        A->ss_ground += isfinite(d2) ? d2 : scale_m * scale_m;
        A->Nground++;
    }
}

static rs_status run_config(rs_bench_calib_row *rows, const bench_config *c, int ic, const rs_bench_calib_options *o,
                            bench_acc *acc)
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
        for (int m = 0; m < RS_BENCH_CALIB_NMETHODS; m++) trial_method(&acc[m], m, &T, scale_m);
        rs_simulate_problem_free(P);
    }
    free(T.sigma_enu);
    free(T.sigma_px);
    free(T.v_cam);

    const double crb_rot = Ncrb ? RS_DEG_PER_RAD * sqrt(ss_crb_rot / Ncrb) : NAN;
    const double crb_pos = Ncrb ? sqrt(ss_crb_pos / Ncrb) : NAN;
    for (int m = 0; m < RS_BENCH_CALIB_NMETHODS; m++) {
        bench_acc *A = &acc[m];
        rs_bench_calib_row *r = &rows[m];
        memset(r, 0, sizeof *r);
        snprintf(r->family, sizeof r->family, "%s", c->family);
        snprintf(r->config, sizeof r->config, "%s", c->config);
        snprintf(r->method, sizeof r->method, "%s", rs_bench_calib_methods[m].name);
        r->trials = Ngen;
        r->failures = A->Nfail;
        r->time_med_us = rs_stats_median(A->time_us, A->Ncalls);
        r->time_p90_us = rs_stats_quantile(A->time_us, A->Ncalls, 0.9);
        r->rot_rms_deg = A->Nok ? sqrt(A->ss_rot / A->Nok) : NAN;
        r->pos_rms_m = A->Nok ? sqrt(A->ss_pos / A->Nok) : NAN;
        r->ground_rms_m = A->Nground ? sqrt(A->ss_ground / A->Nground) : NAN;
        r->crb_rot_deg = crb_rot;
        r->crb_pos_m = crb_pos;
        r->rot_ratio = r->rot_rms_deg / crb_rot;
        r->pos_ratio = r->pos_rms_m / crb_pos;
        r->cond_median = rs_stats_median(A->cond, A->Ncond);
        snprintf(r->failure, sizeof r->failure, "%s", Ngen ? A->failure : genfail);
    }
    return RS_OK;
}

rs_status rs_bench_calib_run(rs_bench_calib_row **rows, int *Nrows, const rs_bench_calib_options *o,
                             void (*progress)(int done, int total, void *cookie), void *cookie, rs_err *err)
{
    *rows = NULL;
    *Nrows = 0;
    if (!o || o->trials < 1 || o->trials > 1000000)
        return rs_err_set(err, RS_ERR_USAGE, "trials: must be in [1, 1000000]");
    bench_config cfg[64];
    const int Nc = make_configs(cfg, o->quick);
    rs_bench_calib_row *out = calloc((size_t)Nc * RS_BENCH_CALIB_NMETHODS, sizeof *out);
    bench_acc acc[RS_BENCH_CALIB_NMETHODS];
    memset(acc, 0, sizeof acc);
    bool ok = out != NULL;
    for (int m = 0; m < RS_BENCH_CALIB_NMETHODS && ok; m++) {
        acc[m].time_us = malloc(sizeof(double) * (size_t)o->trials);
        acc[m].cond = malloc(sizeof(double) * (size_t)o->trials);
        ok = acc[m].time_us && acc[m].cond;
    }
    rs_status st = ok ? RS_OK : RS_ERR_NOMEM;
    for (int c = 0; c < Nc && st == RS_OK; c++) {
        for (int m = 0; m < RS_BENCH_CALIB_NMETHODS; m++) {
            double *t = acc[m].time_us, *k = acc[m].cond;
            memset(&acc[m], 0, sizeof acc[m]);
            acc[m].time_us = t;
            acc[m].cond = k;
        }
        st = run_config(&out[c * RS_BENCH_CALIB_NMETHODS], &cfg[c], c, o, acc);
        if (progress) progress(c + 1, Nc, cookie);
    }
    for (int m = 0; m < RS_BENCH_CALIB_NMETHODS; m++) {
        free(acc[m].time_us);
        free(acc[m].cond);
    }
    if (st != RS_OK) {
        free(out);
        return rs_err_set(err, st, "bench calib: out of memory");
    }
    *rows = out;
    *Nrows = Nc * RS_BENCH_CALIB_NMETHODS;
    return RS_OK;
}

// test_solve_gen.c -- see test_solve_gen.h.
#include "test_solve_gen.h"
#include "core/rs_pose.h"
#include "core/rs_rng.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include <mrcal/poseutils.h>

int gen_failures = 0;
static FILE *caught;
static int saved_stderr = -1;

void gen_begin(void)
{
    setvbuf(stdout, NULL, _IOLBF, 0);
    caught = tmpfile();
    saved_stderr = dup(2);
    if (!caught || saved_stderr < 0 || dup2(fileno(caught), 2) < 0) {
        printf("FAIL: cannot capture stderr\n");
        gen_failures++;
    }
}

int gen_end(const char *seeds)
{
    fflush(stderr);
    if (caught && saved_stderr >= 0) {
        dup2(saved_stderr, 2);
        rewind(caught);
        char line[512];
        while (fgets(line, sizeof(line), caught)) {
            gen_failures++;
            printf("FAIL: the library printed: %s", line);
        }
        fclose(caught);
    }
    if (gen_failures) {
        printf("%d failure(s); seeds %s\n", gen_failures, seeds);
        return 1;
    }
    printf("all passed\n");
    return 0;
}

void gen_seed(gen_rng *g, uint64_t seed) { rs_rng_seed(&g->r, seed); }
double gen_uniform(gen_rng *g, double a, double b) { return rs_rng_uniform_in(&g->r, a, b); }
double gen_normal(gen_rng *g) { return rs_rng_normal(&g->r); }

static void set_lens(gen_problem *g, gen_lens lens)
{
    g->width = 1920;
    g->height = 1080;
    const double core[4] = {1200.0, 1200.0, 959.5, 539.5};
    memset(g->intrinsics, 0, sizeof(g->intrinsics));
    memcpy(g->intrinsics, core, sizeof(core));
    switch (lens) {
    case GEN_PINHOLE: g->lensmodel.type = MRCAL_LENSMODEL_PINHOLE; break;
    case GEN_OPENCV8: {
        g->lensmodel.type = MRCAL_LENSMODEL_OPENCV8;
        const double d[8] = {-0.21, 0.06, 0.0008, -0.0005, -0.01, 0.02, -0.005, 0.003};
        memcpy(&g->intrinsics[4], d, sizeof(d));
        break;
    }
    case GEN_CAHVOR: {
        g->lensmodel.type = MRCAL_LENSMODEL_CAHVOR;
        const double d[5] = {0.01, -0.02, 0.0, -0.03, 0.01}; // alpha, beta, r0, r1, r2
        memcpy(&g->intrinsics[4], d, sizeof(d));
        break;
    }
    }
    g->Nintrinsics = mrcal_lensmodel_num_params(&g->lensmodel);
}

static bool project(double q[2], const gen_problem *g, const double p_enu[3])
{
    mrcal_point3_t pc;
    mrcal_point2_t qq;
    mrcal_transform_point_rt(pc.xyz, NULL, NULL, g->rt_true, p_enu);
    if (!(pc.z > 0.0)) return false;
    if (!mrcal_project(&qq, NULL, NULL, &pc, 1, &g->lensmodel, g->intrinsics)) return false;
    q[0] = qq.x;
    q[1] = qq.y;
    return isfinite(q[0]) && isfinite(q[1]);
}

bool gen_make(gen_problem *g, gen_rng *rng, gen_lens lens, int N, double sigma_px, double sigma_m)
{
    memset(g, 0, sizeof(*g));
    if (N > GEN_MAXN) return false;
    set_lens(g, lens);
    const double ground = gen_uniform(rng, -5.0, 40.0); // road height in the site frame
    g->position_true[0] = gen_uniform(rng, 200.0, 600.0);
    g->position_true[1] = gen_uniform(rng, -600.0, -200.0);
    g->position_true[2] = ground + gen_uniform(rng, 6.0, 15.0);
    const double ypr[3] = {gen_uniform(rng, 0.0, 360.0), gen_uniform(rng, -30.0, -8.0), gen_uniform(rng, -3.0, 3.0)};
    rs_pose_rt_from_ypr(g->rt_true, ypr, g->position_true);
    double Rt[12]; // rows 0-2: R_cam_enu; row 3: t
    mrcal_Rt_from_rt(Rt, NULL, g->rt_true);
    g->N = N;
    double range_sum = 0.0;
    for (int i = 0; i < N; i++) {
        int tries = 0;
        for (;; tries++) {
            if (tries > 1000) return false;
            mrcal_point2_t q = {.x = gen_uniform(rng, 0.03, 0.97) * g->width,
                                .y = gen_uniform(rng, 0.03, 0.97) * g->height};
            mrcal_point3_t v;
            if (!mrcal_unproject(&v, &q, 1, &g->lensmodel, g->intrinsics)) continue;
            double d[3]; // R^T v
            for (int k = 0; k < 3; k++) d[k] = Rt[k] * v.x + Rt[3 + k] * v.y + Rt[6 + k] * v.z;
            // 80% on the road (+-0.5 m relief), 20% on poles/signs up to 4 m
            const double h =
                ground + (gen_uniform(rng, 0, 1) < 0.8 ? gen_uniform(rng, -0.5, 0.5) : gen_uniform(rng, 0.5, 4.0));
            if (d[2] > -1e-6) continue;
            const double lambda = (h - g->position_true[2]) / d[2];
            double *p = &g->p_true[3 * i];
            for (int k = 0; k < 3; k++) p[k] = g->position_true[k] + lambda * d[k];
            const double range = sqrt((p[0] - g->position_true[0]) * (p[0] - g->position_true[0]) +
                                      (p[1] - g->position_true[1]) * (p[1] - g->position_true[1]) +
                                      (p[2] - g->position_true[2]) * (p[2] - g->position_true[2]));
            if (range < 12.0 || range > 150.0) continue;
            if (!project(&g->q_true[2 * i], g, p)) continue;
            range_sum += range;
            break;
        }
        for (int k = 0; k < 3; k++) {
            g->sigma_enu[3 * i + k] = sigma_m;
            g->p_survey[3 * i + k] = g->p_true[3 * i + k] + sigma_m * gen_normal(rng);
        }
        g->sigma_px[i] = sigma_px > 0.0 ? sigma_px : 1.0;
        for (int k = 0; k < 2; k++) g->q_obs[2 * i + k] = g->q_true[2 * i + k] + sigma_px * gen_normal(rng);
    }
    g->mean_range_m = range_sum / N;
    return true;
}

void gen_add_outliers(gen_problem *g, gen_rng *rng, int Nout) { gen_add_outliers_px(g, rng, Nout, 200.0, 500.0); }

void gen_add_outliers_px(gen_problem *g, gen_rng *rng, int Nout, double lo_px, double hi_px)
{
    for (int i = g->N - Nout; i < g->N; i++) {
        const double a = gen_uniform(rng, 0, 2 * M_PI), r = gen_uniform(rng, lo_px, hi_px);
        g->q_obs[2 * i] = g->q_true[2 * i] + r * cos(a);
        g->q_obs[2 * i + 1] = g->q_true[2 * i + 1] + r * sin(a);
        g->outlier[i] = true;
    }
}

double gen_pick_sigmas(const gen_problem *g, int i)
{
    // C = sigma_px^2 I + J S J', J = dq/dp by central differences (1 mm: q is smooth there)
    double C[4] = {g->sigma_px[i] * g->sigma_px[i], 0, 0, g->sigma_px[i] * g->sigma_px[i]};
    for (int a = 0; a < 3; a++) {
        double p[3], qp[2], qm[2];
        memcpy(p, &g->p_true[3 * i], sizeof p);
        p[a] += 1e-3;
        const bool ok = project(qp, g, p);
        p[a] -= 2e-3;
        if (!ok || !project(qm, g, p)) return NAN;
        const double J[2] = {(qp[0] - qm[0]) / 2e-3, (qp[1] - qm[1]) / 2e-3},
                     s2 = g->sigma_enu[3 * i + a] * g->sigma_enu[3 * i + a];
        for (int r = 0; r < 2; r++)
            for (int c = 0; c < 2; c++) C[2 * r + c] += J[r] * s2 * J[c];
    }
    const double e[2] = {g->q_obs[2 * i] - g->q_true[2 * i], g->q_obs[2 * i + 1] - g->q_true[2 * i + 1]};
    const double det = C[0] * C[3] - C[1] * C[2];
    return sqrt((C[3] * e[0] * e[0] - 2 * C[1] * e[0] * e[1] + C[0] * e[1] * e[1]) / det);
}

void gen_append_outliers(gen_problem *g, gen_rng *rng, int Nout, double sigma_m)
{
    // new landmarks: copies of random existing ones moved along the road by 2-10 m
    int added = 0;
    for (int tries = 0; added < Nout && g->N < GEN_MAXN && tries < 1000; tries++) {
        const int j = (int)gen_uniform(rng, 0, g->N - added);
        const int i = g->N;
        double *p = &g->p_true[3 * i];
        memcpy(p, &g->p_true[3 * j], 3 * sizeof(double));
        p[0] += gen_uniform(rng, -10, 10);
        p[1] += gen_uniform(rng, -10, 10);
        const double range = sqrt((p[0] - g->position_true[0]) * (p[0] - g->position_true[0]) +
                                  (p[1] - g->position_true[1]) * (p[1] - g->position_true[1]) +
                                  (p[2] - g->position_true[2]) * (p[2] - g->position_true[2]));
        if (range < 12.0 || range > 150.0) continue;
        if (!project(&g->q_true[2 * i], g, p)) continue;
        if (g->q_true[2 * i] < 0 || g->q_true[2 * i] > g->width - 1 || g->q_true[2 * i + 1] < 0 ||
            g->q_true[2 * i + 1] > g->height - 1)
            continue; // in view: only a mistake about a visible landmark is a mistake
        for (int k = 0; k < 3; k++) {
            g->sigma_enu[3 * i + k] = sigma_m;
            g->p_survey[3 * i + k] = p[k] + sigma_m * gen_normal(rng);
        }
        g->sigma_px[i] = g->sigma_px[0];
        g->N++;
        added++;
        gen_add_outliers(g, rng, 1);
    }
}

rs_camera gen_camera(const gen_problem *g, const double rt[6])
{
    rs_camera c = {.lensmodel = g->lensmodel,
                   .intrinsics = (double *)g->intrinsics,
                   .Nintrinsics = g->Nintrinsics,
                   .width = g->width,
                   .height = g->height};
    memcpy(c.rt_cam_enu, rt, sizeof c.rt_cam_enu);
    return c;
}

rs_calib_problem gen_view(gen_problem *g, const double *intrinsics_nominal)
{
    g->nominal = gen_camera(g, g->rt_true);
    if (intrinsics_nominal) g->nominal.intrinsics = (double *)intrinsics_nominal;
    rs_calib_problem pb = {.N = g->N,
                           .p_enu_m = g->p_survey,
                           .sigma_enu_m = g->sigma_enu,
                           .q_px = g->q_obs,
                           .sigma_px = g->sigma_px,
                           .camera = &g->nominal};
    return pb;
}

double gen_nees(const double *e, const double *C, int n)
{
    double L[36 * 36];
    if (n > 36) return NAN;
    for (int i = 0; i < n; i++)
        for (int j = 0; j <= i; j++) {
            double s = C[i * n + j];
            for (int k = 0; k < j; k++) s -= L[i * n + k] * L[j * n + k];
            if (i == j) {
                if (!(s > 0.0)) return NAN;
                L[i * n + i] = sqrt(s);
            } else {
                L[i * n + j] = s / L[j * n + j];
            }
        }
    double y[36], nees = 0.0;
    for (int i = 0; i < n; i++) {
        double s = e[i];
        for (int k = 0; k < i; k++) s -= L[i * n + k] * y[k];
        y[i] = s / L[i * n + i];
        nees += y[i] * y[i];
    }
    return nees;
}

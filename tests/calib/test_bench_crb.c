// test_bench_crb.c -- the Cramer-Rao bound that `roadside bench calib` reports is
// rs_calib_solve's covariance on the noise-free version of a trial (bench/rs_bench_calib.h). This test
// checks that construction against brute force: the inverse Fisher information of the
// errors-in-variables model, built here from central differences of mrcal_project (pixel
// residuals / sigma_px, survey priors / sigma_m), the landmarks marginalised by a Schur
// complement, inverted by Gauss-Jordan. Tolerance: 1e-6 relative (Frobenius; about 1e-10 is
// found), well above the error of the differences. Three seeds, pinhole and OPENCV8, with and without elevated landmarks.
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <mrcal/mrcal.h>
#include <mrcal/poseutils.h>

#include "calib/rs_calib.h"
#include "sim/rs_simulate.h"
#include "test_solve_gen.h"

// Inverts the (n,n) matrix A in place by Gauss-Jordan with partial pivoting; false if singular.
static bool invert(double *A, int n)
{
    double I[36 * 36];
    if (n > 36) return false;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) I[i * n + j] = i == j;
    for (int c = 0; c < n; c++) {
        int p = c;
        for (int r = c + 1; r < n; r++)
            if (fabs(A[r * n + c]) > fabs(A[p * n + c])) p = r;
        if (A[p * n + c] == 0) return false;
        for (int j = 0; j < n; j++) {
            double t = A[c * n + j];
            A[c * n + j] = A[p * n + j], A[p * n + j] = t;
            t = I[c * n + j];
            I[c * n + j] = I[p * n + j], I[p * n + j] = t;
        }
        const double d = A[c * n + c];
        for (int j = 0; j < n; j++) A[c * n + j] /= d, I[c * n + j] /= d;
        for (int r = 0; r < n; r++) {
            if (r == c) continue;
            const double f = A[r * n + c];
            for (int j = 0; j < n; j++) A[r * n + j] -= f * A[c * n + j], I[r * n + j] -= f * I[c * n + j];
        }
    }
    memcpy(A, I, sizeof(double) * (size_t)(n * n));
    return true;
}

static void project(double q[2], const rs_simulate_problem *s, const double rt[6], const double p[3])
{
    mrcal_point3_t pc;
    mrcal_transform_point_rt(pc.xyz, NULL, NULL, rt, p);
    mrcal_project((mrcal_point2_t *)q, NULL, NULL, &pc, 1, &s->camera.lensmodel, s->camera.intrinsics);
}

// Brute-force marginal covariance of rt at the truth.
static bool brute_crb(double cov[36], const rs_simulate_problem *s, double sigma_px, double sigma_m)
{
    double S[36] = {0};
    for (int i = 0; i < s->Npoints; i++) {
        const double *p = &s->p_enu_true_m[3 * i];
        double Jr[2][6], Jp[2][3];
        for (int j = 0; j < 9; j++) {
            double rt[6], pp[3], qa[2], qb[2];
            const double h = j < 3 ? 1e-6 : 1e-5;
            for (int sgn = 0; sgn < 2; sgn++) {
                memcpy(rt, s->camera.rt_cam_enu, sizeof rt);
                memcpy(pp, p, sizeof pp);
                const double d = sgn ? -h : h;
                if (j < 6)
                    rt[j] += d;
                else
                    pp[j - 6] += d;
                project(sgn ? qb : qa, s, rt, pp);
            }
            for (int k = 0; k < 2; k++) {
                const double g = (qa[k] - qb[k]) / (2 * h) / sigma_px;
                if (j < 6)
                    Jr[k][j] = g;
                else
                    Jp[k][j - 6] = g;
            }
        }
        // Fisher blocks of this landmark: A = Jr'Jr, B = Jr'Jp, D = Jp'Jp + I/sigma_m^2
        double B[6][3], D[9];
        for (int a = 0; a < 6; a++) {
            for (int b = 0; b < 6; b++) S[6 * a + b] += Jr[0][a] * Jr[0][b] + Jr[1][a] * Jr[1][b];
            for (int b = 0; b < 3; b++) B[a][b] = Jr[0][a] * Jp[0][b] + Jr[1][a] * Jp[1][b];
        }
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++)
                D[3 * a + b] = Jp[0][a] * Jp[0][b] + Jp[1][a] * Jp[1][b] + (a == b ? 1 / (sigma_m * sigma_m) : 0);
        if (!invert(D, 3)) return false;
        for (int a = 0; a < 6; a++)
            for (int b = 0; b < 6; b++)
                for (int k = 0; k < 3; k++)
                    for (int l = 0; l < 3; l++) S[6 * a + b] -= B[a][k] * D[3 * k + l] * B[b][l];
    }
    memcpy(cov, S, sizeof S);
    return invert(cov, 6);
}

int main(void)
{
    gen_begin();
    static const struct {
        const char *lens;
        double elevated;
        uint64_t seed;
    } cases[] = {{"LENSMODEL_PINHOLE", 0.25, 31}, {"LENSMODEL_OPENCV8", 0.25, 32}, {"LENSMODEL_OPENCV8", 0.0, 33}};
    const double sigma_px = 1.0, sigma_m = 0.3;
    for (size_t c = 0; c < sizeof cases / sizeof *cases; c++) {
        rs_simulate_camera_options o;
        rs_simulate_camera_options_default(&o);
        o.lensmodel = cases[c].lens, o.seed = cases[c].seed, o.elevated_fraction = cases[c].elevated;
        o.Nlandmarks = 15, o.pixel_sigma_px = 0, o.outlier_fraction = 0, o.survey_sigma_h_m = o.survey_sigma_v_m = 0;
        rs_simulate_problem *s = NULL;
        rs_err e = {0};
        CHECK(rs_simulate_camera_problem(&s, &o, &e) == RS_OK, "simulator: %s", e.msg);
        if (!s) continue;
        double sig_enu[3 * 15], sig_px[15];
        for (int i = 0; i < s->Npoints; i++) {
            sig_px[i] = sigma_px;
            for (int k = 0; k < 3; k++) sig_enu[3 * i + k] = sigma_m;
        }
        const rs_calib_problem cp = {.N = s->Npoints,
                                     .p_enu_m = s->p_enu_true_m,
                                     .sigma_enu_m = sig_enu,
                                     .q_px = s->q_true_px,
                                     .sigma_px = sig_px,
                                     .camera = &s->camera};
        rs_calib_options opt;
        rs_calib_options_default(&opt);
        opt.robust_scale = 0;
        opt.estimate_noise = false; // the covariance at the stated sigmas is what the Fisher information predicts
        rs_calib_result r;
        const rs_status st = rs_calib_solve(&r, &cp, &opt, &e);
        double ref[36];
        const bool ok = brute_crb(ref, s, sigma_px, sigma_m);
        CHECK(st == RS_OK && ok, "%s seed %llu: solve %s (%s), brute force %d", cases[c].lens,
              (unsigned long long)cases[c].seed, rs_strerror(st), e.msg, ok);
        if (st == RS_OK && ok) {
            double num = 0, den = 0;
            for (int k = 0; k < 36; k++) {
                num += (r.covariance_rt_cam_enu[k] - ref[k]) * (r.covariance_rt_cam_enu[k] - ref[k]);
                den += ref[k] * ref[k];
            }
            const double rel = sqrt(num / den);
            printf("%s, elevated %.2f, seed %llu: sigma_t (brute force) %.4g %.4g %.4g m, relative difference "
                   "of the 6x6 covariance %.3g\n",
                   cases[c].lens, cases[c].elevated, (unsigned long long)cases[c].seed, sqrt(ref[21]), sqrt(ref[28]),
                   sqrt(ref[35]), rel);
            CHECK(rel < 1e-6, "covariance differs from the inverse Fisher information by %.3g", rel);
        }
        rs_calib_result_free(&r);
        rs_simulate_problem_free(s);
    }
    return gen_end("31, 32, 33");
}

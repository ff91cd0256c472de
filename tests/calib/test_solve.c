// test_solve.c -- rs_calib_solve and the pose helpers on REFINE's simulated problems
// (test_solve_gen.c): noise-free recovery for three lens models, focal refinement from x2 and
// x0.5, the camera position prior, degenerate inputs, yaw/pitch/roll against the closed form
// of docs/conventions.md, rs_camera_locate_ground, and the analytic Jacobians against Ceres'
// finite differences. Fixed seeds, printed on failure.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mrcal/poseutils.h>

#include "calib/internal/rs_calib_refine.h"
#include "calib/rs_calib.h"
#include "core/rs_pose.h"
#include "test_solve_gen.h"

static const char *lens_name[] = {"PINHOLE", "OPENCV8", "CAHVOR"};

static double norm3(const double *a, const double *b)
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

// Noise-free: the truth to 1e-9 relative (rotation in rad, position relative to the range).
static void test_noise_free(void)
{
    double worst_r = 0, worst_c = 0;
    for (int lens = 0; lens < 3; lens++)
        for (uint64_t seed = 1; seed <= 10; seed++) {
            gen_rng rng;
            gen_seed(&rng, seed);
            gen_problem g;
            const int N = 8 + (int)(seed * 3 % 23);
            if (!gen_make(&g, &rng, (gen_lens)lens, N, 0.0, 0.0)) {
                CHECK(0, "seed %llu: generator failed", (unsigned long long)seed);
                continue;
            }
            // survey sigmas stated (0.3 m) although the data are exact: still the exact answer
            for (int i = 0; i < 3 * N; i++) g.sigma_enu[i] = seed % 2 ? 0.3 : 0.0;
            rs_calib_problem pb = gen_view(&g, NULL);
            if (seed % 5 == 0) { // the NULL defaults: exact survey, 1 px
                pb.sigma_enu_m = NULL;
                pb.sigma_px = NULL;
            }
            rs_calib_result res;
            rs_err err = {0};
            rs_status st = rs_calib_solve(&res, &pb, NULL, &err);
            CHECK(st == RS_OK, "%s seed %llu: %s", lens_name[lens], (unsigned long long)seed, err.msg);
            if (st == RS_OK) {
                const double dr = norm3(res.rt_cam_enu, g.rt_true);
                const double dc = norm3(res.position_enu_m, g.position_true) / g.mean_range_m;
                worst_r = fmax(worst_r, dr);
                worst_c = fmax(worst_c, dc);
                CHECK(dr < 1e-9 && dc < 1e-9, "%s seed %llu N %d: |dr| %.3g rad, |dC|/range %.3g", lens_name[lens],
                      (unsigned long long)seed, N, dr, dc);
                CHECK(res.Ninliers == N, "%s seed %llu: %d of %d inliers", lens_name[lens], (unsigned long long)seed,
                      res.Ninliers, N);
                CHECK(res.rms_px < 1e-6, "rms %g", res.rms_px);
            }
            rs_calib_result_free(&res);
        }
    printf("noise-free: worst |dr| %.3g rad, worst |dC|/range %.3g\n", worst_r, worst_c);
}

// A ground pixel maps back to its ground point (OPENCV8, CAHVOR).
static void test_locate_ground(void)
{
    double worst = 0;
    for (int lens = 1; lens < 3; lens++) {
        gen_rng rng;
        gen_seed(&rng, 5 + lens);
        gen_problem g;
        CHECK(gen_make(&g, &rng, (gen_lens)lens, 30, 0.0, 0.0), "generator");
        for (int i = 0; i < g.N; i++) {
            const double n[3] = {0, 0, 2.0}; // not unit on purpose
            double p[3];
            rs_err err = {0};
            const rs_camera cam = gen_camera(&g, g.rt_true);
            rs_status st = rs_camera_locate_ground(p, &cam, &g.q_true[2 * i], n, 2.0 * g.p_true[3 * i + 2], &err);
            CHECK(st == RS_OK, "%s landmark %d: %s", lens_name[lens], i, err.msg);
            const double e = norm3(p, &g.p_true[3 * i]);
            worst = fmax(worst, e);
            CHECK(e < 1e-9, "%s landmark %d: error %g m", lens_name[lens], i, e);
        }
        // a pixel above the horizon never meets the ground
        const double n[3] = {0, 0, 1}, q_sky[2] = {959.5, 0.0};
        double p[3], rt_up[6], ypr[3] = {10, 20, 0};
        rs_pose_rt_from_ypr(rt_up, ypr, g.position_true);
        rs_err err = {0};
        const rs_camera cam_up = gen_camera(&g, rt_up);
        CHECK(rs_camera_locate_ground(p, &cam_up, q_sky, n, g.position_true[2] - 10, &err) == RS_ERR_DEGENERATE,
              "sky pixel: %s", err.msg);
    }
    printf("locate_ground: worst error %.3g m\n", worst);
}

// --refine focal from x2 and x0.5 (on the search grid) and x1.3, x0.63 (off it): within 4 of
// its reported sigmas (1 px, 0.3 m noise).
static void test_focal(void)
{
    const double factors[] = {2.0, 0.5, 1.3, 0.63};
    for (int lens = 0; lens < 3; lens++)
        for (int fi = 0; fi < 4; fi++)
            for (uint64_t seed = 100; seed < 103; seed++) {
                gen_rng rng;
                gen_seed(&rng, seed);
                gen_problem g;
                CHECK(gen_make(&g, &rng, (gen_lens)lens, 25, 1.0, 0.3), "generator");
                double nominal[16];
                memcpy(nominal, g.intrinsics, sizeof(nominal));
                nominal[0] *= factors[fi];
                nominal[1] *= factors[fi];
                rs_calib_problem pb = gen_view(&g, nominal);
                rs_calib_options opt;
                rs_calib_options_default(&opt);
                opt.refine = RS_CALIB_REFINE_FOCAL;
                rs_calib_result res;
                rs_err err = {0};
                rs_status st = rs_calib_solve(&res, &pb, &opt, &err);
                CHECK(st == RS_OK, "%s x%g seed %llu: %s", lens_name[lens], factors[fi], (unsigned long long)seed,
                      err.msg);
                if (st == RS_OK) {
                    const double df = res.intrinsics[0] - g.intrinsics[0];
                    const double sf = res.sigma_intrinsics[0];
                    printf("focal %s x%g seed %llu: f %.2f (truth %.0f) sigma %.2f, ratio fy/fx %.12f, %s\n",
                           lens_name[lens], factors[fi], (unsigned long long)seed, res.intrinsics[0], g.intrinsics[0],
                           sf, res.intrinsics[1] / res.intrinsics[0], res.method);
                    CHECK(sf > 0 && sf < 0.05 * g.intrinsics[0] && fabs(df) < 4.0 * sf,
                          "%s x%g seed %llu: focal %.3f truth %.3f sigma %.3f", lens_name[lens], factors[fi],
                          (unsigned long long)seed, res.intrinsics[0], g.intrinsics[0], sf);
                    CHECK(fabs(res.intrinsics[1] / res.intrinsics[0] - 1.0) < 1e-12, "aspect changed");
                }
                rs_calib_result_free(&res);
            }
}

// --refine focal+center (and +distortion): nominal focal 10% long, centre 20 px and 15 px off,
// distortion 20% off: the focal length and the centre within 4 reported sigmas.
static void test_focal_center(void)
{
    for (int lens = 0; lens < 3; lens++)
        for (int mode = 0; mode < 2; mode++)
            for (uint64_t seed = 3000; seed < 3004; seed++) {
                gen_rng rng;
                gen_seed(&rng, seed);
                gen_problem g;
                CHECK(gen_make(&g, &rng, (gen_lens)lens, 25, 1.0, 0.1), "generator");
                double nominal[16];
                memcpy(nominal, g.intrinsics, sizeof(nominal));
                nominal[0] *= 1.1;
                nominal[1] *= 1.1;
                nominal[2] += 20;
                nominal[3] -= 15;
                if (mode == 1)
                    for (int k = 4; k < g.Nintrinsics; k++) nominal[k] *= 1.2;
                rs_calib_problem pb = gen_view(&g, nominal);
                rs_calib_options opt;
                rs_calib_options_default(&opt);
                opt.refine = RS_CALIB_REFINE_FOCAL | RS_CALIB_REFINE_CENTER | (mode ? RS_CALIB_REFINE_DISTORTION : 0);
                rs_calib_result res;
                rs_err err = {0};
                rs_status st = rs_calib_solve(&res, &pb, &opt, &err);
                CHECK(st == RS_OK, "%s mode %d seed %llu: %s", lens_name[lens], mode, (unsigned long long)seed,
                      err.msg);
                for (int k = 0; k < 4 && st == RS_OK; k++) {
                    const double z = (res.intrinsics[k] - g.intrinsics[k]) / res.sigma_intrinsics[k];
                    CHECK(res.sigma_intrinsics[k] > 0 && fabs(z) < 4,
                          "%s mode %d seed %llu: intrinsic %d "
                          "%.3f truth %.3f sigma %.3f",
                          lens_name[lens], mode, (unsigned long long)seed, k, res.intrinsics[k], g.intrinsics[k],
                          res.sigma_intrinsics[k]);
                }
                rs_calib_result_free(&res);
            }
}

// A tight prior on the camera position: the solution follows it and its sigma shrinks.
static void test_position_prior(void)
{
    for (uint64_t seed = 200; seed < 205; seed++) {
        gen_rng rng;
        gen_seed(&rng, seed);
        gen_problem g;
        CHECK(gen_make(&g, &rng, GEN_PINHOLE, 12, 1.0, 0.5), "generator");
        rs_calib_problem pb = gen_view(&g, NULL);
        rs_calib_result free_, prior;
        rs_err err = {0};
        CHECK(rs_calib_solve(&free_, &pb, NULL, &err) == RS_OK, "seed %llu: %s", (unsigned long long)seed, err.msg);
        pb.has_position_prior = true;
        const double offset[3] = {0.02, -0.01, 0.015}; // a pole surveyed 2 cm off
        for (int k = 0; k < 3; k++) pb.prior_position_enu_m[k] = g.position_true[k] + offset[k];
        pb.prior_sigma_m = 0.01;
        CHECK(rs_calib_solve(&prior, &pb, NULL, &err) == RS_OK, "seed %llu: %s", (unsigned long long)seed, err.msg);
        for (int k = 0; k < 3; k++) {
            CHECK(prior.sigma_position_enu_m[k] < 0.0101 &&
                      prior.sigma_position_enu_m[k] < free_.sigma_position_enu_m[k],
                  "seed %llu axis %d: sigma %g (without prior %g)", (unsigned long long)seed, k,
                  prior.sigma_position_enu_m[k], free_.sigma_position_enu_m[k]);
            CHECK(fabs(prior.position_enu_m[k] - pb.prior_position_enu_m[k]) < 4 * 0.01,
                  "seed %llu axis %d: position %.4f prior %.4f", (unsigned long long)seed, k, prior.position_enu_m[k],
                  pb.prior_position_enu_m[k]);
        }
        if (seed == 200)
            printf("position prior: sigma E,N,U free %.3f %.3f %.3f m -> with 1 cm prior %.4f %.4f %.4f m\n",
                   free_.sigma_position_enu_m[0], free_.sigma_position_enu_m[1], free_.sigma_position_enu_m[2],
                   prior.sigma_position_enu_m[0], prior.sigma_position_enu_m[1], prior.sigma_position_enu_m[2]);
        rs_calib_result_free(&free_);
        rs_calib_result_free(&prior);
    }
}

// Degenerate input: a clear status and a message naming the cause; never a silent pose.
static void expect_fail(const char *what, rs_calib_problem *pb, rs_status want, const char *word)
{
    rs_calib_result res;
    rs_err err = {0};
    rs_status st = rs_calib_solve(&res, pb, NULL, &err);
    printf("degenerate %-14s -> %s: %s\n", what, rs_strerror(st), err.msg);
    CHECK(st == want, "%s: status %d (%s), want %d; %s", what, st, rs_strerror(st), want, err.msg);
    CHECK(!word || strstr(err.msg, word), "%s: message '%s' lacks '%s'", what, err.msg, word);
    CHECK(res.intrinsics == NULL && res.inlier == NULL, "%s: result not zeroed", what);
    rs_calib_result_free(&res);
}

static void test_degenerate(void)
{
    gen_rng rng;
    gen_seed(&rng, 300);
    gen_problem g;
    CHECK(gen_make(&g, &rng, GEN_PINHOLE, 20, 1.0, 0.3), "generator");
    rs_calib_problem pb = gen_view(&g, NULL);

    pb.N = 3;
    expect_fail("3 landmarks", &pb, RS_ERR_DEGENERATE, "3");
    pb.N = 0;
    expect_fail("0 landmarks", &pb, RS_ERR_DEGENERATE, NULL);
    pb.N = 20;

    gen_problem h = g; // NaN pixel, NaN survey, bad sigma
    h.q_obs[2 * 7 + 1] = NAN;
    pb = gen_view(&h, NULL);
    expect_fail("NaN pixel", &pb, RS_ERR_INVALID, "landmark 7");
    h = g;
    h.p_survey[3 * 4] = INFINITY;
    pb = gen_view(&h, NULL);
    expect_fail("inf survey", &pb, RS_ERR_INVALID, "landmark 4");
    h = g;
    h.sigma_px[2] = 0.0;
    pb = gen_view(&h, NULL);
    expect_fail("zero sigma_px", &pb, RS_ERR_INVALID, "sigma_px");

    // collinear: every landmark on one straight line (a kerb)
    h = g;
    for (int i = 0; i < h.N; i++) {
        double *p = &h.p_true[3 * i];
        const double s = 5.0 + 3.0 * i;
        p[0] = g.p_true[0] + s * 0.6;
        p[1] = g.p_true[1] + s * 0.8;
        p[2] = g.p_true[2];
        memcpy(&h.p_survey[3 * i], p, 3 * sizeof(double));
        mrcal_point3_t pc;
        mrcal_point2_t q;
        mrcal_transform_point_rt(pc.xyz, NULL, NULL, h.rt_true, p);
        mrcal_project(&q, NULL, NULL, &pc, 1, &h.lensmodel, h.intrinsics);
        h.q_obs[2 * i] = q.x;
        h.q_obs[2 * i + 1] = q.y;
    }
    pb = gen_view(&h, NULL);
    expect_fail("collinear", &pb, RS_ERR_DEGENERATE, "collinear");

    // tiny patch: every pixel within a few pixels (landmarks far away and bunched)
    h = g;
    for (int i = 0; i < h.N; i++) {
        h.q_obs[2 * i] = 700.0 + 3.0 * gen_uniform(&rng, 0, 1);
        h.q_obs[2 * i + 1] = 400.0 + 3.0 * gen_uniform(&rng, 0, 1);
    }
    pb = gen_view(&h, NULL);
    expect_fail("tiny patch", &pb, RS_ERR_DEGENERATE, NULL);

    // behind the camera: the landmarks mirrored through the camera centre (a pinhole sees
    // them at the same pixels, but a real camera cannot) mixed with real ones
    h = g;
    for (int i = 0; i < h.N; i += 2)
        for (int k = 0; k < 3; k++) {
            h.p_true[3 * i + k] = 2 * h.position_true[k] - g.p_true[3 * i + k];
            h.p_survey[3 * i + k] = h.p_true[3 * i + k];
        }
    pb = gen_view(&h, NULL);
    {
        rs_calib_result res;
        rs_err err = {0};
        rs_status st = rs_calib_solve(&res, &pb, NULL, &err);
        printf("degenerate %-14s -> %s: %s%s\n", "behind camera", rs_strerror(st), err.msg,
               st == RS_OK ? res.warnings : "");
        CHECK(st == RS_ERR_DEGENERATE || (st == RS_OK && strstr(res.warnings, "outlier")),
              "behind camera: status %s, warnings '%s'", rs_strerror(st), st == RS_OK ? res.warnings : "");
        rs_calib_result_free(&res);
    }

    // CAHVORE at linearity 1 without distortion is a pinhole: its gradients come from
    // core/rs_lens.c, not mrcal; the solve must agree with the pinhole's (oracle) within 1e-8
    h = g;
    pb = gen_view(&h, NULL);
    rs_calib_result res_pin, res_cahvore;
    rs_err e1 = {0}, e2 = {0};
    const rs_status st_pin = rs_calib_solve(&res_pin, &pb, NULL, &e1);
    mrcal_lensmodel_t cahvore = {.type = MRCAL_LENSMODEL_CAHVORE};
    cahvore.LENSMODEL_CAHVORE__config.linearity = 1.0;
    double intr[12] = {0};
    memcpy(intr, pb.camera->intrinsics, 4 * sizeof(double));
    const rs_camera cam_cahvore = {
        .lensmodel = cahvore, .intrinsics = intr, .Nintrinsics = 12, .width = h.width, .height = h.height};
    pb.camera = &cam_cahvore;
    const rs_status st_cahvore = rs_calib_solve(&res_cahvore, &pb, NULL, &e2);
    CHECK(st_pin == RS_OK && st_cahvore == RS_OK, "pinhole: %s; CAHVORE: %s", e1.msg, e2.msg);
    if (st_pin == RS_OK && st_cahvore == RS_OK) {
        double worst = 0;
        for (int k = 0; k < 6; k++) worst = fmax(worst, fabs(res_pin.rt_cam_enu[k] - res_cahvore.rt_cam_enu[k]));
        printf("CAHVORE (linearity 1) vs pinhole: pose differs by %.2g at most\n", worst);
        CHECK(worst < 1e-8, "CAHVORE (linearity 1) pose differs from the pinhole's by %.3g", worst);
    }
    if (st_pin == RS_OK) rs_calib_result_free(&res_pin);
    if (st_cahvore == RS_OK) rs_calib_result_free(&res_cahvore);
}

// The analytic Jacobians (mrcal chain) against central differences of the same residuals,
// every lens model, at a perturbed pose, then a full solve with every intrinsic refined and the
// position prior.
static void test_gradients(void)
{
    for (int lens = 0; lens < 3; lens++) {
        gen_rng rng;
        gen_seed(&rng, 400 + lens);
        gen_problem g;
        CHECK(gen_make(&g, &rng, (gen_lens)lens, 10, 1.0, 0.3), "generator");
        double c[3] = {0, 0, 0}, p_c[GEN_MAXN * 3], p_s[GEN_MAXN * 3], rt_c[6], Rc[3];
        for (int i = 0; i < g.N; i++)
            for (int k = 0; k < 3; k++) c[k] += g.p_survey[3 * i + k] / g.N;
        for (int i = 0; i < 3 * g.N; i++) p_s[i] = p_c[i] = g.p_survey[i] - c[i % 3];
        mrcal_rotate_point_r(Rc, NULL, NULL, g.rt_true, c);
        for (int k = 0; k < 3; k++) {
            rt_c[k] = g.rt_true[k] + 0.01;
            rt_c[3 + k] = g.rt_true[3 + k] + Rc[k] + 0.5;
        }
        double intr[16];
        memcpy(intr, g.intrinsics, sizeof(intr));
        rs_calib_refine_problem rp = {.N = g.N,
                                      .p_survey_c_m = p_s,
                                      .sigma_enu_m = g.sigma_enu,
                                      .q_px = g.q_obs,
                                      .sigma_px = g.sigma_px,
                                      .lensmodel = &g.lensmodel,
                                      .intrinsics_nominal = g.intrinsics,
                                      .has_position_prior = true,
                                      .prior_sigma_m = 1.0};
        const double worst = rs_calib_refine_jacobian_check(rt_c, intr, p_c, &rp);
        printf("jacobian %s: worst relative error %.3g\n", lens_name[lens], worst);
        CHECK(worst < 1e-6, "%s: analytic vs numeric Jacobian: %g", lens_name[lens], worst);

        double C[3];
        rs_pose_position_from_rt(C, NULL, rt_c);
        memcpy(rp.prior_position_c_m, C, sizeof(C));
        rs_calib_refine_options ro = {.refine =
                                          RS_CALIB_REFINE_FOCAL | RS_CALIB_REFINE_CENTER | RS_CALIB_REFINE_DISTORTION,
                                      .robust_scale = 2.0,
                                      .max_iterations = 50,
                                      .focal_prior_rel_sigma = 1.0,
                                      .center_prior_sigma_px = 50,
                                      .distortion_prior_sigma = 0.1,
                                      .covariance = true};
        rs_calib_refine_summary sum;
        double cov[(6 + 16) * (6 + 16)];
        rs_err err = {0};
        rs_status st = rs_calib_refine_run(rt_c, intr, p_c, &sum, cov, NULL, NULL, &rp, &ro, &err);
        CHECK(st == RS_OK, "%s: refine everything: %s", lens_name[lens], err.msg);
        const int n = 6 + g.Nintrinsics;
        for (int i = 0; i < n && st == RS_OK; i++)
            CHECK(isfinite(cov[i * n + i]) && cov[i * n + i] > 0, "%s: cov[%d] = %g", lens_name[lens], i,
                  cov[i * n + i]);
    }
}

int main(void)
{
    gen_begin();
    test_noise_free();
    test_locate_ground();
    test_gradients();
    test_position_prior();
    test_focal();
    test_focal_center();
    test_degenerate();
    return gen_end("1-10 (6-7 for locate_ground), 77, 100-102, 3000-3003, 200-204, 300, 400-402");
}

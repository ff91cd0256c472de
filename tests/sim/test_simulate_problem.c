// test_simulate_problem.c -- the in-memory simulator (rs_simulate_camera_problem and friends)
// against brute-force oracles written here: a textbook Rodrigues formula and pinhole projection,
// the yaw/pitch/roll definition of docs/conventions.md, and sample statistics with explicit
// binomial / chi tolerances. Fixed seeds, printed on failure.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_pose.h"
#include "core/rs_rng.h"
#include "sim/rs_simulate.h"
#include "tests/common/rs_test.h"

// p_cam = R(r) p + t with the textbook Rodrigues formula.
static void oracle_transform(double out[3], const double rt[6], const double p[3])
{
    double th = sqrt(rt[0] * rt[0] + rt[1] * rt[1] + rt[2] * rt[2]);
    double k[3] = {0, 0, 0};
    if (th > 0)
        for (int i = 0; i < 3; i++) k[i] = rt[i] / th;
    double kxp[3] = {k[1] * p[2] - k[2] * p[1], k[2] * p[0] - k[0] * p[2], k[0] * p[1] - k[1] * p[0]};
    double kp = k[0] * p[0] + k[1] * p[1] + k[2] * p[2];
    for (int i = 0; i < 3; i++) out[i] = p[i] * cos(th) + kxp[i] * sin(th) + k[i] * kp * (1 - cos(th)) + rt[3 + i];
}

// Noise-free, distortion-free pinhole problem: every pixel is the brute-force projection.
static void test_geometry(void)
{
    rs_simulate_camera_options o;
    rs_simulate_camera_options_default(&o);
    o.lensmodel = "LENSMODEL_PINHOLE";
    o.distortion = false;
    o.pixel_sigma_px = 0;
    o.outlier_fraction = 0;
    o.Nlandmarks = 40;
    o.seed = rs_test_seed = 11;
    rs_simulate_problem *P = NULL;
    rs_err err = {0};
    rs_status st = rs_simulate_camera_problem(&P, &o, &err);
    CHECK(st == RS_OK && P, "problem: %s", err.msg);
    if (!P) return;
    CHECK(P->Npoints == 40 && P->camera.Nintrinsics == 4 && P->Noutliers == 0, "counts %d %d %d", P->Npoints,
          P->camera.Nintrinsics, P->Noutliers);
    const double *in = P->camera.intrinsics;
    double worst = 0;
    int Nelevated = 0;
    for (int i = 0; i < P->Npoints; i++) {
        const double *p = P->p_enu_true_m + 3 * i;
        double pc[3];
        oracle_transform(pc, P->camera.rt_cam_enu, p);
        CHECK(pc[2] > 0, "point %d behind the camera", i);
        double q[2] = {in[0] * pc[0] / pc[2] + in[2], in[1] * pc[1] / pc[2] + in[3]};
        for (int k = 0; k < 2; k++) {
            double e = fabs(q[k] - P->q_true_px[2 * i + k]);
            worst = fmax(worst, e);
            CHECK(e < 1e-8, "point %d: oracle %g, simulator %g", i, q[k], P->q_true_px[2 * i + k]);
            CHECK(P->q_px[2 * i + k] == P->q_true_px[2 * i + k], "noise-free pick differs");
        }
        CHECK(q[0] >= o.margin_px / 2 && q[1] >= o.margin_px / 2 && q[0] <= 1919 - o.margin_px / 2 &&
                  q[1] <= 1079 - o.margin_px / 2,
              "point %d outside the image: %g %g", i, q[0], q[1]);
        CHECK(hypot(p[0] - P->p_cam_enu_m[0], p[1] - P->p_cam_enu_m[1]) <= o.max_range_m + 1e-3, "point %d too far", i);
        if (P->elevated[i]) {
            Nelevated++;
            CHECK(p[2] >= o.elevated_min_m - 1e-4 && p[2] <= o.elevated_max_m + 1e-4, "elevated height %g", p[2]);
        } else {
            CHECK(p[2] == 0, "ground point %d at u = %g", i, p[2]);
        }
    }
    CHECK(Nelevated == 10, "%d elevated, want 25%% of 40", Nelevated);
    // Pose: where the options put it (rounded to 1e-6), looking at the ENU origin at 62% height.
    double yaw = o.yaw_deg * M_PI / 180;
    double want[3] = {-o.distance_m * sin(yaw), -o.distance_m * cos(yaw), o.camera_height_m};
    for (int k = 0; k < 3; k++)
        CHECK(fabs(P->p_cam_enu_m[k] - want[k]) < 1e-4, "camera position %d: %g", k, P->p_cam_enu_m[k]);
    CHECK(fabs(P->ypr_deg[0] - o.yaw_deg) < 1e-3, "yaw %g", P->ypr_deg[0]);
    CHECK(P->ypr_deg[1] < -10 && P->ypr_deg[1] > -30, "pitch %g", P->ypr_deg[1]);
    double zero[3] = {0, 0, 0}, pc[3];
    oracle_transform(pc, P->camera.rt_cam_enu, zero);
    double v0 = in[1] * pc[1] / pc[2] + in[3];
    CHECK(fabs(v0 - 0.62 * 1079) < 0.1 * 1080, "the ENU origin appears at v = %g", v0);
    printf("geometry: 40 noise-free pinhole pixels agree with the brute-force projection to %.2e px\n", worst);
    rs_simulate_problem_free(P);
}

// Noise statistics with many points: pixel noise, outlier share and distance, survey noise.
static void test_noise(void)
{
    rs_simulate_camera_options o;
    rs_simulate_camera_options_default(&o);
    o.Nlandmarks = 2000;
    o.outlier_fraction = 0.1;
    o.pixel_sigma_px = 1.5;
    o.seed = rs_test_seed = 5;
    rs_simulate_problem *P = NULL;
    rs_err err = {0};
    CHECK(rs_simulate_camera_problem(&P, &o, &err) == RS_OK, "%s", err.msg);
    if (!P) return;
    int N = P->Npoints, k = 0, n_in = 0;
    double s2 = 0, sh2 = 0, sv2 = 0;
    for (int i = 0; i < N; i++) {
        double du = P->q_px[2 * i] - P->q_true_px[2 * i], dv = P->q_px[2 * i + 1] - P->q_true_px[2 * i + 1];
        CHECK(isfinite(du) && isfinite(dv), "pick %d not finite", i);
        if (P->outlier[i]) {
            k++;
            CHECK(hypot(du, dv) >= o.outlier_min_px, "outlier %d only %g px off", i, hypot(du, dv));
        } else {
            n_in++;
            s2 += du * du + dv * dv;
        }
        CHECK(P->q_px[2 * i] >= -0.5 && P->q_px[2 * i] <= 1919.5 && P->q_px[2 * i + 1] >= -0.5 &&
                  P->q_px[2 * i + 1] <= 1079.5,
              "pick %d outside the image", i);
        const double *t = P->p_enu_true_m + 3 * i, *s = P->p_enu_survey_m + 3 * i;
        sh2 += (s[0] - t[0]) * (s[0] - t[0]) + (s[1] - t[1]) * (s[1] - t[1]);
        sv2 += (s[2] - t[2]) * (s[2] - t[2]);
    }
    CHECK(k == P->Noutliers, "Noutliers %d, flags %d", P->Noutliers, k);
    double tol = 4 * sqrt(N * 0.1 * 0.9);
    CHECK(fabs(k - 0.1 * N) <= tol, "%d outliers of %d, want %g +- %g", k, N, 0.1 * N, tol);
    // Sample sigmas: relative standard error 1/sqrt(2 n); 5 of them.
    double sig = sqrt(s2 / (2 * n_in)), sh = sqrt(sh2 / (2 * N)), sv = sqrt(sv2 / N);
    CHECK(fabs(sig / 1.5 - 1) < 5 / sqrt(4.0 * n_in), "pixel sigma %g, want 1.5", sig);
    CHECK(fabs(sh / 0.3 - 1) < 5 / sqrt(4.0 * N), "survey sigma h %g, want 0.3", sh);
    CHECK(fabs(sv / 0.5 - 1) < 5 / sqrt(2.0 * N), "survey sigma v %g, want 0.5", sv);
    printf("noise: %d/%d outliers; pixel sigma %.3f (1.5); survey sigma %.3f (0.3), %.3f (0.5)\n", k, N, sig, sh, sv);

    // Same seed: identical; another seed: different.
    rs_simulate_problem *Q = NULL, *R = NULL;
    CHECK(rs_simulate_camera_problem(&Q, &o, &err) == RS_OK, "%s", err.msg);
    o.seed = 6;
    CHECK(rs_simulate_camera_problem(&R, &o, &err) == RS_OK, "%s", err.msg);
    if (Q && R) {
        CHECK(!memcmp(P->q_px, Q->q_px, sizeof(double) * 2 * N) &&
                  !memcmp(P->camera.rt_cam_enu, Q->camera.rt_cam_enu, 48) &&
                  !memcmp(P->p_enu_survey_m, Q->p_enu_survey_m, sizeof(double) * 3 * N),
              "same seed, different problems");
        CHECK(memcmp(P->q_px, R->q_px, sizeof(double) * 2 * N) != 0, "seeds 5 and 6 give the same picks");
    }
    rs_simulate_problem_free(P);
    rs_simulate_problem_free(Q);
    rs_simulate_problem_free(R);
}

// Lens models, planar problems, steep cameras, and bad options.
static void test_variants(void)
{
    static const char *const lenses[] = {"LENSMODEL_OPENCV4",
                                         "LENSMODEL_OPENCV8",
                                         "LENSMODEL_OPENCV12",
                                         "LENSMODEL_CAHVOR",
                                         "LENSMODEL_CAHVORE_linearity=0.00",
                                         "LENSMODEL_STEREOGRAPHIC",
                                         "LENSMODEL_LONLAT"};
    rs_err err = {0};
    for (size_t i = 0; i < sizeof lenses / sizeof lenses[0]; i++) {
        rs_simulate_camera_options o;
        rs_simulate_camera_options_default(&o);
        o.lensmodel = lenses[i];
        o.elevated_fraction = 0;
        o.camera_height_m = 5 + 3 * (double)i;
        o.distance_m = 3 + 5 * (double)i;
        o.seed = rs_test_seed = 100 + i;
        rs_simulate_problem *P = NULL;
        rs_status st = rs_simulate_camera_problem(&P, &o, &err);
        CHECK(st == RS_OK, "%s: %s", lenses[i], err.msg);
        if (!P) continue;
        char name[128];
        CHECK(mrcal_lensmodel_name(name, sizeof name, &P->camera.lensmodel) && !strcmp(name, lenses[i]), "%s: lens %s",
              lenses[i], name);
        for (int j = 0; j < P->Npoints; j++) CHECK(P->p_enu_true_m[3 * j + 2] == 0, "%s: not planar", lenses[i]);
        // The TRUE pixels are mrcal's projections of the true points.
        mrcal_point3_t pc[12];
        mrcal_point2_t q[12];
        for (int j = 0; j < P->Npoints && j < 12; j++)
            mrcal_transform_point_rt(pc[j].xyz, NULL, NULL, P->camera.rt_cam_enu, P->p_enu_true_m + 3 * j);
        CHECK(mrcal_project(q, NULL, NULL, pc, P->Npoints, &P->camera.lensmodel, P->camera.intrinsics), "%s: project",
              lenses[i]);
        for (int j = 0; j < P->Npoints && j < 12; j++)
            CHECK(hypot(q[j].x - P->q_true_px[2 * j], q[j].y - P->q_true_px[2 * j + 1]) < 1e-9, "%s: pixel %d",
                  lenses[i], j);
        rs_simulate_problem_free(P);
    }
    struct {
        const char *what;
        rs_simulate_camera_options o;
    } bad[6];
    for (int i = 0; i < 6; i++) rs_simulate_camera_options_default(&bad[i].o);
    bad[0].what = "unknown lens", bad[0].o.lensmodel = "LENSMODEL_NOPE";
    bad[1].what = "no landmarks", bad[1].o.Nlandmarks = 0;
    bad[2].what = "NaN pixel sigma", bad[2].o.pixel_sigma_px = NAN;
    bad[3].what = "outliers 1", bad[3].o.outlier_fraction = 1.0;
    bad[4].what = "hfov 200 pinhole", bad[4].o.hfov_deg = 200;
    bad[5].what = "camera underground", bad[5].o.camera_height_m = -1;
    for (int i = 0; i < 6; i++) {
        rs_simulate_problem *P = (rs_simulate_problem *)&err; // must be reset to NULL
        err.msg[0] = '\0';
        rs_status st = rs_simulate_camera_problem(&P, &bad[i].o, &err);
        CHECK(st == RS_ERR_USAGE && P == NULL && strlen(err.msg) > 10, "%s: status %d, '%s'", bad[i].what, st, err.msg);
    }
    // A camera that sees no ground within range: RS_ERR_DEGENERATE, nothing returned.
    rs_simulate_camera_options o;
    rs_simulate_camera_options_default(&o);
    o.max_range_m = 2;
    o.elevated_fraction = 0;
    rs_simulate_problem *P = NULL;
    rs_status st = rs_simulate_camera_problem(&P, &o, &err);
    CHECK(st == RS_ERR_DEGENERATE && P == NULL && strstr(err.msg, "visible"), "no ground in range: %d '%s'", st,
          err.msg);
    rs_simulate_problem_free(NULL);
    printf("variants: %zu lens models, planar problems; 6 bad option sets refused\n", sizeof lenses / sizeof lenses[0]);
}

int main(void)
{
    test_geometry();
    test_noise();
    test_variants();
    return rs_test_end("test_simulate_problem");
}

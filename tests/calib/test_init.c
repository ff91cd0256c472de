// test_init.c -- rs_calib_init_pose against the truth of simulated pole cameras
// (test_init_gen.h): noise-free recovery, noise + gross outliers, degenerate input, timing.
// Fixed seeds; every failure prints its seed. The OpenCV solvePnPRansac comparison is in
// test_init_opencv.cc. The library must never print: stderr is captured during the run and
// must stay empty (this test reports on stdout).
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <mrcal/poseutils.h>

#include "calib/rs_calib_init.h"
#include "core/rs_stats.h"
#include "core/rs_units.h"
#include "test_init_gen.h"
#include "tests/common/rs_test.h"

// The terrains: a flat road, a road with crown and kerbs (nearly planar), street furniture.
enum { NTERRAIN = 3 };
static const double terrain_relief_m[NTERRAIN] = {0.0, 0.3, 8.0};
static const char *const terrain_name[NTERRAIN] = {"planar", "nearly-planar", "3d"};

// tg_make, or a failed check naming the test and seed.
static bool make(tg_problem *pb, const char *what, uint64_t seed, tg_lens lens, double relief_m, int N, double noise_px,
                 double outlier_fraction)
{
    const bool ok = tg_make(pb, seed, lens, relief_m, N, noise_px, outlier_fraction);
    CHECK(ok, "%s seed %llu: generator failed", what, (unsigned long long)seed);
    return ok;
}

// The pc-th percentile of x (n,) (core/rs_stats.h: linear between order statistics; x is sorted).
static double percentile(double *x, int n, double pc) { return rs_stats_quantile(x, n, pc / 100.0); }

// 1. Noise-free: the truth comes back to 1e-6 (rotation in rad, position relative to range),
// every observation an inlier, RMS ~ 0; 200 seeds x 3 lenses x 3 terrains, N = 4..30.
static void test_noise_free(void)
{
    double worst_rot = 0, worst_pos = 0;
    int Ntrials = 0, Nnonminimal = 0;
    for (int lens = 0; lens < TG_NLENS; lens++)
        for (int terrain = 0; terrain < NTERRAIN; terrain++)
            for (uint64_t seed = 1; seed <= 200; seed++) {
                const int N = 4 + (int)(seed % 27);
                const bool planar = terrain == 0;
                tg_problem pb;
                if (!make(&pb, "noise-free", seed, (tg_lens)lens, terrain_relief_m[terrain], N, 0.0, 0.0)) continue;
                rs_calib_init_result res;
                bool inl[TG_NMAX];
                rs_err err = {0};
                const rs_status st =
                    rs_calib_init_pose(&res, inl, &pb.lensmodel, pb.intrinsics, pb.p_enu_m, pb.q_px, N, NULL, &err);
                Ntrials++;
                CHECK(st == RS_OK, "noise-free seed %llu %s %s N=%d: status %d: %s", (unsigned long long)seed,
                      tg_lens_name(lens), terrain_name[terrain], N, st, err.msg);
                if (st) continue;
                Nnonminimal += strstr(res.method, " + ") != NULL;
                const double rot = tg_rotation_error_rad(res.rt_cam_enu, pb.rt_cam_enu);
                const double pos = tg_position_error_m(res.rt_cam_enu, pb.rt_cam_enu) / pb.range_m;
                // NaN fails these comparisons
                CHECK(rot < 1e-6 && pos < 1e-6 && res.rms_px < 1e-4 && res.Ninliers == N,
                      "noise-free seed %llu %s %s N=%d: rotation error %.3g rad, position "
                      "error %.3g of range, rms %.3g px, %d/%d inliers, planar judged %d, %s",
                      (unsigned long long)seed, tg_lens_name(lens), terrain_name[terrain], N, rot, pos, res.rms_px,
                      res.Ninliers, N, res.planar, res.method);
                CHECK(!planar || res.planar, "noise-free seed %llu %s N=%d: planar set not judged planar",
                      (unsigned long long)seed, tg_lens_name(lens), N);
                if (!(rot <= worst_rot)) worst_rot = rot;
                if (!(pos <= worst_pos)) worst_pos = pos;
            }
    printf("noise-free: %d trials, worst rotation error %.3g rad, worst position error %.3g of "
           "range (tolerance 1e-6); non-minimal pose kept in %d\n",
           Ntrials, worst_rot, worst_pos, Nnonminimal);
}

// 2. 1 px noise + 30% gross outliers (moved >= 25 px), N = 20.
// Outliers: >= 95% of them flagged as non-inliers over all trials.
// Pose: judged in the image, where the refinement needs it -- e_model, the RMS over the
// landmarks of the pixel displacement between the truth and the estimate. A maximum-
// likelihood estimate from n inliers with sigma = 1 px has E[e_model^2] = 6 sigma^2 / n
// (6 pose parameters), i.e. e_model ~ 0.65 px for n = 14. The initial pose is a linear
// (EPnP/IPPE) or minimal (P3P) solution, not ML: we allow 8x that per trial (5 px, far inside
// the refinement's basin of convergence, tens of pixels) and 2x it (1.3 px) for the median.
static void test_outliers(void)
{
    enum { N = 20, TRIALS = 200 };
    int Nout = 0, Nout_flagged = 0, Nin_true = 0, Nin_kept = 0;
    static double emodel[TG_NLENS * NTERRAIN * TRIALS], rot[TG_NLENS * NTERRAIN * TRIALS],
        pos[TG_NLENS * NTERRAIN * TRIALS];
    int n = 0, Nnonminimal = 0;
    for (int lens = 0; lens < TG_NLENS; lens++)
        for (int terrain = 0; terrain < NTERRAIN; terrain++)
            for (uint64_t seed = 1001; seed < 1001 + TRIALS; seed++) {
                tg_problem pb;
                if (!make(&pb, "outliers", seed, (tg_lens)lens, terrain_relief_m[terrain], N, 1.0, 0.3)) continue;
                rs_calib_init_result res;
                bool inl[TG_NMAX];
                rs_err err = {0};
                const rs_status st = tg_init_pose(&res, inl, &pb, seed, &err);
                CHECK(st == RS_OK, "outliers seed %llu %s %s: status %d: %s", (unsigned long long)seed,
                      tg_lens_name(lens), terrain_name[terrain], st, err.msg);
                if (st) continue;
                Nnonminimal += strstr(res.method, " + ") != NULL;
                for (int i = 0; i < N; i++) {
                    if (pb.outlier[i]) {
                        Nout++;
                        Nout_flagged += !inl[i];
                    } else {
                        Nin_true++;
                        Nin_kept += inl[i];
                    }
                }
                emodel[n] = tg_model_error_px(&pb, res.rt_cam_enu, pb.rt_cam_enu);
                rot[n] = tg_rotation_error_rad(res.rt_cam_enu, pb.rt_cam_enu) * RS_DEG_PER_RAD;
                pos[n] = tg_position_error_m(res.rt_cam_enu, pb.rt_cam_enu) / pb.range_m;
                CHECK(emodel[n] < 5.0,
                      "outliers seed %llu %s %s: e_model %.3g px >= 5 px "
                      "(rotation %.3g deg, position %.3g of range, %s)",
                      (unsigned long long)seed, tg_lens_name(lens), terrain_name[terrain], emodel[n], rot[n], pos[n],
                      res.method);
                n++;
            }
    const double recall = Nout ? (double)Nout_flagged / Nout : 0.0;
    const double kept = Nin_true ? (double)Nin_kept / Nin_true : 0.0;
    CHECK(recall >= 0.95, "outlier recall %.4f < 0.95 (%d of %d)", recall, Nout_flagged, Nout);
    const double med = n ? percentile(emodel, n, 50) : INFINITY;
    CHECK(med < 1.3, "median e_model %.3g px >= 1.3 px", med);
    printf("outliers (N=%d, 1 px noise, 30%% gross): %d trials, outlier recall %.4f (%d/%d), good "
           "points kept %.4f; e_model median %.3g px, 95%% %.3g px, max %.3g px; rotation error "
           "median %.3g deg, 95%% %.3g deg; position error median %.3g, 95%% %.3g of range; "
           "non-minimal pose kept in %d\n",
           N, n, recall, Nout_flagged, Nout, kept, med, n ? percentile(emodel, n, 95) : 0,
           n ? percentile(emodel, n, 100) : 0, n ? percentile(rot, n, 50) : 0, n ? percentile(rot, n, 95) : 0,
           n ? percentile(pos, n, 50) : 0, n ? percentile(pos, n, 95) : 0, Nnonminimal);
}

// 2b. Few landmarks, where every triple is tried instead of RANSAC's samples
// (RS_CALIB_OPENGV_EXHAUSTIVE_MAX): N = 5 with 1 gross outlier and N = 6 with 2, 1 px noise,
// 1800 trials. A pose from 4 good landmarks is a poor one (e_model is 1.5x-2x that of 20), and
// a gross error can sit where a wrong pose puts it: at most 0.5% of the trials may flag a
// landmark wrongly (OpenGV's RANSAC, sampling 4 at a time: 1.0%; every triple: 0.17%), at most
// 0.2% may find no pose (no triple's pose puts the 4 good landmarks within 8 px: 1 of 1800),
// and the median e_model must be below 2 px.
static void test_outliers_few(void)
{
    enum { TRIALS = 100 };
    static double emodel[2 * TG_NLENS * NTERRAIN * TRIALS];
    int n = 0, Nwrong = 0, Nfail = 0;
    for (int N = 5; N <= 6; N++)
        for (int lens = 0; lens < TG_NLENS; lens++)
            for (int terrain = 0; terrain < NTERRAIN; terrain++)
                for (uint64_t seed = 7001; seed < 7001 + TRIALS; seed++) {
                    tg_problem pb;
                    if (!make(&pb, "few outliers", seed, (tg_lens)lens, terrain_relief_m[terrain], N, 1.0,
                              N == 5 ? 0.2 : 0.3))
                        continue;
                    rs_calib_init_result res;
                    bool inl[TG_NMAX];
                    rs_err err = {0};
                    const rs_status st = tg_init_pose(&res, inl, &pb, seed, &err);
                    CHECK(st == RS_OK || st == RS_ERR_DEGENERATE, "few outliers N %d seed %llu %s %s: status %d: %s", N,
                          (unsigned long long)seed, tg_lens_name(lens), terrain_name[terrain], st, err.msg);
                    Nfail += st != RS_OK;
                    if (st) continue;
                    int wrong = 0;
                    for (int i = 0; i < N; i++) wrong += inl[i] == pb.outlier[i];
                    Nwrong += wrong > 0;
                    emodel[n++] = tg_model_error_px(&pb, res.rt_cam_enu, pb.rt_cam_enu);
                }
    const double med = n ? percentile(emodel, n, 50) : INFINITY;
    CHECK(n >= 1700, "few outliers: only %d trials", n);
    CHECK(Nfail <= 0.002 * (n + Nfail), "few outliers: %d of %d trials found no pose (> 0.2%%)", Nfail, n + Nfail);
    CHECK(Nwrong <= 0.005 * n, "few outliers: %d of %d trials flag a landmark wrongly (> 0.5%%)", Nwrong, n);
    CHECK(med < 2.0, "few outliers: median e_model %.3g px >= 2 px", med);
    printf("few outliers (N = 5 with 1, N = 6 with 2; every triple tried): %d trials, %d without a pose, %d with a "
           "wrong flag; e_model median %.3g px, 95%% %.3g px\n",
           n + Nfail, Nfail, Nwrong, med, n ? percentile(emodel, n, 95) : 0);
}

static void expect_error(const char *what, rs_status want, const char *needle, const tg_problem *pb, const double *p,
                         const double *q, int N)
{
    rs_calib_init_result res;
    bool inl[TG_NMAX + 1];
    rs_err err = {0};
    const rs_status st = rs_calib_init_pose(&res, inl, &pb->lensmodel, pb->intrinsics, p, q, N, NULL, &err);
    CHECK(st == want && strstr(err.msg, needle),
          "%s: status %d (want %d), message '%s' (want "
          "'%s')",
          what, st, want, err.msg, needle);
    for (int i = 0; i < N && i < TG_NMAX; i++) CHECK(!inl[i], "%s: observation %d flagged inlier on failure", what, i);
    printf("degenerate %-22s -> %d: %s\n", what, st, err.msg);
}

// 3. Degenerate input: the right status and a message naming the cause, no crash.
static void test_degenerate(void)
{
    tg_problem pb;
    const uint64_t seed = 77;
    if (!make(&pb, "degenerate", seed, TG_PINHOLE, 8.0, 12, 0.0, 0.0)) return;
    double p[3 * TG_NMAX], q[2 * TG_NMAX];

    expect_error("3 points", RS_ERR_DEGENERATE, "need at least 4", &pb, pb.p_enu_m, pb.q_px, 3);
    expect_error("0 points", RS_ERR_DEGENERATE, "need at least 4", &pb, NULL, NULL, 0);

    memcpy(p, pb.p_enu_m, sizeof(p));
    p[3 * 5 + 1] = NAN;
    expect_error("NaN landmark", RS_ERR_INVALID, "p_enu_m[5]", &pb, p, pb.q_px, 12);
    memcpy(q, pb.q_px, sizeof(q));
    q[2 * 7] = INFINITY;
    expect_error("inf pixel", RS_ERR_INVALID, "q_px[7]", &pb, pb.p_enu_m, q, 12);

    // a repeated landmark (same point, same pixel; a copied coordinate): the initial pose uses
    // the first copy only and is still exact on noise-free data (issue 14, finding 4)
    memcpy(p, pb.p_enu_m, sizeof(p));
    memcpy(q, pb.q_px, sizeof(q));
    memcpy(&p[3 * 9], &p[3 * 2], 3 * sizeof(double));
    memcpy(&q[2 * 9], &q[2 * 2], 2 * sizeof(double));
    {
        rs_calib_init_result res;
        bool inl[TG_NMAX];
        rs_err err = {0};
        const rs_status st = rs_calib_init_pose(&res, inl, &pb.lensmodel, pb.intrinsics, p, q, 12, NULL, &err);
        double dr = 0, dt = 0;
        for (int k = 0; k < 3; k++)
            dr = fmax(dr, fabs(res.rt_cam_enu[k] - pb.rt_cam_enu[k])),
            dt = fmax(dt, fabs(res.rt_cam_enu[3 + k] - pb.rt_cam_enu[3 + k]));
        CHECK(st == RS_OK && dr < 1e-6 && dt < 1e-4 && inl[2] && !inl[9] && res.Ninliers == 11,
              "repeated landmark: status %d '%s', |dr| %.3g rad, |dt| %.3g m, inliers %d (want 11: the copy "
              "is left out)",
              st, err.msg, dr, dt, res.Ninliers);
        printf("repeated landmark            -> pose, |dr| %.3g rad, |dt| %.3g m, %d inliers\n", dr, dt, res.Ninliers);
    }
    // ... but 3 distinct positions (landmarks 3, 4, 5 copies of 0, 1, 2) are too few
    for (int i = 3; i < 6; i++) memcpy(&p[3 * i], &p[3 * (i - 3)], 3 * sizeof(double));
    expect_error("3 distinct positions", RS_ERR_DEGENERATE, "distinct", &pb, p, q, 6);

    // collinear: all on the segment between landmarks 0 and 1, pixels through the truth pose
    for (int i = 0; i < 12; i++) {
        const double s = i / 11.0;
        for (int k = 0; k < 3; k++) p[3 * i + k] = pb.p_enu_m[k] + s * (pb.p_enu_m[3 + k] - pb.p_enu_m[k]);
        mrcal_point3_t pc;
        mrcal_transform_point_rt(pc.xyz, NULL, NULL, pb.rt_cam_enu, &p[3 * i]);
        mrcal_project((mrcal_point2_t *)&q[2 * i], NULL, NULL, &pc, 1, &pb.lensmodel, pb.intrinsics);
    }
    expect_error("collinear", RS_ERR_DEGENERATE, "collinear", &pb, p, q, 12);

    // tiny patch: the landmark cloud shrunk 1000x about landmark 0, seen through the truth pose
    for (int i = 0; i < 12; i++) {
        for (int k = 0; k < 3; k++) p[3 * i + k] = pb.p_enu_m[k] + 1e-3 * (pb.p_enu_m[3 * i + k] - pb.p_enu_m[k]);
        mrcal_point3_t pc;
        mrcal_transform_point_rt(pc.xyz, NULL, NULL, pb.rt_cam_enu, &p[3 * i]);
        mrcal_project((mrcal_point2_t *)&q[2 * i], NULL, NULL, &pc, 1, &pb.lensmodel, pb.intrinsics);
    }
    expect_error("tiny patch", RS_ERR_DEGENERATE, "tiny patch", &pb, p, q, 12);

    // behind: a 3D cloud 20..80 m behind a pinhole camera; the pinhole formula mirrors it into
    // the image. No rigid pose puts a non-planar cloud in front with these bearings.
    tg_rng r;
    tg_seed(&r, seed);
    double rt_enu_cam[6];
    mrcal_invert_rt(rt_enu_cam, NULL, NULL, pb.rt_cam_enu);
    for (int i = 0; i < 12; i++) {
        const double pc[3] = {tg_uniform(&r, -30, 30), tg_uniform(&r, -30, 30), tg_uniform(&r, -80, -20)};
        mrcal_transform_point_rt(&p[3 * i], NULL, NULL, rt_enu_cam, pc);
        q[2 * i] = pb.intrinsics[0] * pc[0] / pc[2] + pb.intrinsics[2];
        q[2 * i + 1] = pb.intrinsics[1] * pc[1] / pc[2] + pb.intrinsics[3];
    }
    expect_error("behind the camera", RS_ERR_DEGENERATE, "in front of the camera", &pb, p, q, 12);

    // a bad option
    rs_calib_init_options opt;
    rs_calib_init_options_default(&opt);
    opt.ransac_threshold_px = NAN;
    rs_calib_init_result res;
    rs_err err = {0};
    const rs_status st =
        rs_calib_init_pose(&res, NULL, &pb.lensmodel, pb.intrinsics, pb.p_enu_m, pb.q_px, 12, &opt, &err);
    CHECK(st == RS_ERR_INVALID && strstr(err.msg, "ransac_threshold_px"), "NaN threshold: status %d, '%s'", st,
          err.msg);
}

// 4. Same input and seed, same answer, bit for bit.
static void test_deterministic(void)
{
    tg_problem pb;
    const uint64_t seed = 4242;
    if (!make(&pb, "deterministic", seed, TG_OPENCV8, 0.0, 25, 1.0, 0.3)) return;
    rs_calib_init_result a, b;
    bool ia[TG_NMAX], ib[TG_NMAX];
    const rs_status sa =
        rs_calib_init_pose(&a, ia, &pb.lensmodel, pb.intrinsics, pb.p_enu_m, pb.q_px, pb.N, NULL, NULL);
    const rs_status sb =
        rs_calib_init_pose(&b, ib, &pb.lensmodel, pb.intrinsics, pb.p_enu_m, pb.q_px, pb.N, NULL, NULL);
    CHECK(sa == RS_OK && sb == RS_OK && !memcmp(a.rt_cam_enu, b.rt_cam_enu, sizeof(a.rt_cam_enu)) &&
              !memcmp(ia, ib, (size_t)pb.N * sizeof(bool)),
          "deterministic seed %llu: two identical calls differ", (unsigned long long)seed);
}

// 5. Time per call, 20 landmarks (printed, not asserted).
static void time_calls(void)
{
    for (int outliers = 0; outliers < 2; outliers++)
        for (int lens = 0; lens < TG_NLENS; lens++) {
            enum { REPS = 100 };
            tg_problem pb[8];
            for (int k = 0; k < 8; k++)
                if (!tg_make(&pb[k], 5000 + (uint64_t)k, (tg_lens)lens, 0.0, 20, 1.0, outliers ? 0.3 : 0.0)) return;
            struct timespec t0, t1;
            clock_gettime(CLOCK_MONOTONIC, &t0);
            for (int rep = 0; rep < REPS; rep++) {
                rs_calib_init_result res;
                const tg_problem *b = &pb[rep % 8];
                rs_calib_init_pose(&res, NULL, &b->lensmodel, b->intrinsics, b->p_enu_m, b->q_px, 20, NULL, NULL);
            }
            clock_gettime(CLOCK_MONOTONIC, &t1);
            const double us = ((double)(t1.tv_sec - t0.tv_sec) * 1e9 + (double)(t1.tv_nsec - t0.tv_nsec)) / 1e3 / REPS;
            printf("time per call, 20 landmarks, %s, %s: %.1f us\n", tg_lens_name(lens),
                   outliers ? "1 px noise + 30% outliers" : "1 px noise", us);
        }
}

int main(void)
{
    // capture stderr: OpenGV and OpenCV print on some inputs, and the library must not let them
    fflush(stderr);
    FILE *captured = tmpfile();
    const int saved_stderr = dup(STDERR_FILENO);
    if (!captured || saved_stderr < 0 || dup2(fileno(captured), STDERR_FILENO) < 0) {
        printf("FAIL: cannot capture stderr\n");
        return 1;
    }
    test_noise_free();
    test_outliers();
    test_outliers_few();
    test_degenerate();
    test_deterministic();
    time_calls();
    fflush(stderr);
    dup2(saved_stderr, STDERR_FILENO);
    close(saved_stderr);
    fseek(captured, 0, SEEK_END); // written through the descriptor: the FILE's position is stale
    const long Nprinted = ftell(captured);
    if (Nprinted > 0) {
        char buf[512] = {0};
        rewind(captured);
        const size_t n = fread(buf, 1, sizeof(buf) - 1, captured);
        buf[n] = 0;
        CHECK(0, "the library printed %ld bytes to stderr, starting with: %s", Nprinted, buf);
    }
    fclose(captured);
    return rs_test_end("test_init");
}

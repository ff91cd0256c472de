// test_audit.c -- rs_audit_camera against oracles written here:
//   1. leave-one-out: every figure (predicted pixel, pixel error, ground error, influence in m and
//      deg) against a brute-force re-solve without each landmark, projected with mrcal_project,
//      located by mrcal_unproject + a ray/plane intersection, rotations compared by a textbook
//      Rodrigues formula;
//   2. the ground uncertainty map against a Monte Carlo run (poses drawn from the covariance by
//      a Cholesky factor, detection noise added, located with rs_camera_locate_ground, spread
//      taken) within 10% at three cells (near, middle, far);
//   3. the moved-camera test: a camera turned by 0.5 deg is found moved in every draw, with the
//      rotation estimated within 0.1 deg; an unmoved camera's false alarm rate over 300 noise
//      draws is binomially consistent with alpha = 0.05;
//   4. bad input: options, NaN picks, too few new picks;
//   5. degeneracy words and the image coverage on a hand-made problem whose hull is known.
// Fixed seeds, printed on failure.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mrcal/mrcal.h>
#include <mrcal/poseutils.h>

#include "audit/rs_audit.h"
#include "core/rs_pose.h"
#include "core/rs_rng.h"
#include "sim/rs_simulate.h"
#include "tests/common/rs_test.h"

// ---- oracles ----

// Textbook Rodrigues: R = I + sin(th) K + (1 - cos(th)) K^2.
static void oracle_R(double R[9], const double r[3])
{
    double th = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    double k[3] = {0, 0, 0};
    if (th > 0)
        for (int i = 0; i < 3; i++) k[i] = r[i] / th;
    const double K[9] = {0, -k[2], k[1], k[2], 0, -k[0], -k[1], k[0], 0};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double K2 = 0;
            for (int m = 0; m < 3; m++) K2 += K[3 * i + m] * K[3 * m + j];
            R[3 * i + j] = (i == j) + sin(th) * K[3 * i + j] + (1 - cos(th)) * K2;
        }
}

static void oracle_position(double c[3], const double rt[6])
{
    double R[9];
    oracle_R(R, rt);
    for (int i = 0; i < 3; i++) c[i] = -(R[i] * rt[3] + R[3 + i] * rt[4] + R[6 + i] * rt[5]);
}

static double oracle_angle_deg(const double ra[3], const double rb[3])
{
    double A[9], B[9], tr = 0;
    oracle_R(A, ra);
    oracle_R(B, rb);
    for (int i = 0; i < 9; i++) tr += A[i] * B[i];
    double c = (tr - 1) / 2;
    return acos(c > 1 ? 1 : c < -1 ? -1 : c) * 180 / M_PI;
}

static bool oracle_project(double q[2], const rs_simulate_problem *sp, const double *intrinsics, const double rt[6],
                           const double p[3])
{
    double R[9], pc[3];
    oracle_R(R, rt);
    for (int i = 0; i < 3; i++) pc[i] = R[3 * i] * p[0] + R[3 * i + 1] * p[1] + R[3 * i + 2] * p[2] + rt[3 + i];
    mrcal_point2_t qq;
    if (!mrcal_project(&qq, NULL, NULL, (const mrcal_point3_t *)pc, 1, &sp->camera.lensmodel, intrinsics)) return false;
    q[0] = qq.x;
    q[1] = qq.y;
    return true;
}

// Ray of q (mrcal_unproject) from the camera centre, intersected with the plane U = h.
static bool oracle_locate(double g[3], const rs_simulate_problem *sp, const double *intrinsics, const double rt[6],
                          const double q[2], double h)
{
    mrcal_point3_t v;
    mrcal_point2_t qq = {.x = q[0], .y = q[1]};
    if (!mrcal_unproject(&v, &qq, 1, &sp->camera.lensmodel, intrinsics)) return false;
    double R[9], c[3], d[3];
    oracle_R(R, rt);
    oracle_position(c, rt);
    for (int i = 0; i < 3; i++) d[i] = R[i] * v.x + R[3 + i] * v.y + R[6 + i] * v.z; // R^T v
    double s = (h - c[2]) / d[2];
    if (!(s > 0)) return false;
    for (int i = 0; i < 3; i++) g[i] = c[i] + s * d[i];
    return true;
}

static rs_calib_problem view(const rs_simulate_problem *sp, double *sigma_enu, double *sigma_px, double s_h, double s_v,
                             double s_px)
{
    for (int i = 0; i < sp->Npoints; i++) {
        sigma_enu[3 * i] = sigma_enu[3 * i + 1] = s_h;
        sigma_enu[3 * i + 2] = s_v;
        sigma_px[i] = s_px;
    }
    rs_calib_problem pb = {
        .N = sp->Npoints,
        .p_enu_m = sp->p_enu_survey_m,
        .sigma_enu_m = sigma_enu,
        .q_px = sp->q_px,
        .sigma_px = sigma_px,
        .camera = &sp->camera,
    };
    return pb;
}

static rs_simulate_problem *simulate(unsigned long long seed, int N, double outliers, double s_h, double s_v)
{
    rs_test_seed = seed;
    rs_simulate_camera_options o;
    rs_simulate_camera_options_default(&o);
    o.seed = seed;
    o.Nlandmarks = N;
    o.outlier_fraction = outliers;
    o.survey_sigma_h_m = s_h;
    o.survey_sigma_v_m = s_v;
    rs_simulate_problem *sp = NULL;
    rs_err err = {0};
    rs_status st = rs_simulate_camera_problem(&sp, &o, &err);
    CHECK(st == RS_OK, "simulate: %s", err.msg);
    return sp;
}

static const double up[3] = {0, 0, 1};

// A simulated camera problem (landmark sigmas as simulated, 1 px picks) and default options.
typedef struct {
    rs_simulate_problem *sp;
    double sig_enu[3 * 64], sig_px[64];
    rs_calib_problem pb;
    rs_audit_options opt;
} fixture;

static bool fixture_make(fixture *f, unsigned long long seed, int N, double outliers, double s_h, double s_v)
{
    f->sp = simulate(seed, N, outliers, s_h, s_v);
    if (!f->sp) return false;
    f->pb = view(f->sp, f->sig_enu, f->sig_px, s_h, s_v, 1);
    rs_audit_options_default(&f->opt);
    return true;
}

// ---- 1. leave-one-out vs brute force ----

static void test_leave_one_out(unsigned long long seed)
{
    fixture f;
    if (!fixture_make(&f, seed, 14, 0.08, 0.05, 0.08)) return;
    rs_simulate_problem *sp = f.sp;
    rs_calib_problem pb = f.pb;
    const double *sig_enu = f.sig_enu, *sig_px = f.sig_px;
    rs_audit_options opt = f.opt;
    opt.map = false;
    rs_audit_result r;
    rs_err err = {0};
    rs_status st = rs_audit_camera(&r, &pb, up, 0, NULL, NULL, NULL, &opt, &err);
    CHECK(st == RS_OK, "audit: %s", err.msg);
    if (st) {
        rs_audit_result_free(&r);
        rs_simulate_problem_free(sp);
        return;
    }
    const int N = pb.N;
    int checked = 0;
    for (int i = 0; i < N; i++) {
        // the re-solve, independently
        double p[64 * 3], s3[64 * 3], q[64 * 2], s1[64];
        int k = 0;
        for (int j = 0; j < N; j++) {
            if (j == i) continue;
            memcpy(&p[3 * k], &pb.p_enu_m[3 * j], sizeof(double[3]));
            memcpy(&s3[3 * k], &sig_enu[3 * j], sizeof(double[3]));
            memcpy(&q[2 * k], &pb.q_px[2 * j], sizeof(double[2]));
            s1[k++] = sig_px[j];
        }
        rs_calib_problem sub = pb;
        sub.N = k;
        sub.p_enu_m = p;
        sub.sigma_enu_m = s3;
        sub.q_px = q;
        sub.sigma_px = s1;
        rs_calib_result lr;
        rs_status sst = rs_calib_solve(&lr, &sub, NULL, NULL);
        const rs_audit_landmark *L = &r.landmarks[i];
        CHECK((sst == RS_OK) == L->loo_ok, "landmark %d: brute force status %d, audit loo_ok %d", i, sst, L->loo_ok);
        if (sst == RS_OK && L->loo_ok) {
            const double *pi = &pb.p_enu_m[3 * i], *qi = &pb.q_px[2 * i];
            double qp[2], g[3], c_loo[3], c_full[3];
            bool ok = oracle_project(qp, sp, lr.intrinsics, lr.rt_cam_enu, pi) &&
                      oracle_locate(g, sp, lr.intrinsics, lr.rt_cam_enu, qi, pi[2]);
            CHECK(ok, "landmark %d: oracle projection/location failed", i);
            oracle_position(c_loo, lr.rt_cam_enu);
            oracle_position(c_full, r.solve.rt_cam_enu);
            double e_px = hypot(qp[0] - qi[0], qp[1] - qi[1]);
            double e_m = sqrt((g[0] - pi[0]) * (g[0] - pi[0]) + (g[1] - pi[1]) * (g[1] - pi[1]) +
                              (g[2] - pi[2]) * (g[2] - pi[2]));
            double inf_m =
                sqrt((c_loo[0] - c_full[0]) * (c_loo[0] - c_full[0]) + (c_loo[1] - c_full[1]) * (c_loo[1] - c_full[1]) +
                     (c_loo[2] - c_full[2]) * (c_loo[2] - c_full[2]));
            double inf_deg = oracle_angle_deg(lr.rt_cam_enu, r.solve.rt_cam_enu);
            CHECK(fabs(L->loo_predicted_px[0] - qp[0]) < 1e-6 && fabs(L->loo_predicted_px[1] - qp[1]) < 1e-6,
                  "landmark %d: predicted (%.9f, %.9f) vs brute force (%.9f, %.9f)", i, L->loo_predicted_px[0],
                  L->loo_predicted_px[1], qp[0], qp[1]);
            CHECK(fabs(L->loo_error_px - e_px) < 1e-6, "landmark %d: loo px %.9f vs %.9f", i, L->loo_error_px, e_px);
            CHECK(fabs(L->loo_ground_error_m - e_m) < 1e-6 * (1 + e_m), "landmark %d: loo m %.9f vs %.9f", i,
                  L->loo_ground_error_m, e_m);
            CHECK(fabs(L->influence_m - inf_m) < 1e-7, "landmark %d: influence %.9f m vs %.9f", i, L->influence_m,
                  inf_m);
            CHECK(fabs(L->influence_deg - inf_deg) < 1e-5, "landmark %d: influence %.9f deg vs %.9f", i,
                  L->influence_deg, inf_deg);
            CHECK(isfinite(L->loo_normalised) && L->loo_normalised >= 0, "landmark %d: loo_normalised %g", i,
                  L->loo_normalised);
            // a gross outlier's pick is far from what the others predict
            if (sp->outlier[i])
                CHECK(L->loo_normalised > 3.717 && L->reason[0], "landmark %d: outlier, loo %.1f sigma, reason '%s'", i,
                      L->loo_normalised, L->reason);
            checked++;
        }
        rs_calib_result_free(&lr);
    }
    CHECK(checked >= N - 1, "only %d of %d landmarks compared", checked, N);
    for (int i = 0; i < N; i++)
        if (!r.landmarks[i].inlier) CHECK(r.landmarks[i].reason[0], "landmark %d dropped without a reason", i);
    printf("leave-one-out (seed %llu): %d landmarks, %d outliers simulated, LOO RMS %.2f px, median %.3f m\n", seed, N,
           sp->Noutliers, r.loo_rms_px, r.loo_median_m);
    rs_audit_result_free(&r);
    rs_simulate_problem_free(sp);
}

// ---- 2. the uncertainty map vs Monte Carlo ----

// Lower Cholesky factor of a (6,6) covariance; false if not positive definite.
static bool cholesky6(double L[36], const double C[36])
{
    memset(L, 0, 36 * sizeof(double));
    for (int i = 0; i < 6; i++)
        for (int j = 0; j <= i; j++) {
            double s = C[6 * i + j];
            for (int k = 0; k < j; k++) s -= L[6 * i + k] * L[6 * j + k];
            if (i == j) {
                if (!(s > 0)) return false;
                L[6 * i + i] = sqrt(s);
            } else {
                L[6 * i + j] = s / L[6 * j + j];
            }
        }
    return true;
}

static void test_map(unsigned long long seed)
{
    fixture f;
    if (!fixture_make(&f, seed, 12, 0, 0.3, 0.5)) return;
    rs_simulate_problem *sp = f.sp;
    rs_calib_problem pb = f.pb;
    rs_audit_options opt = f.opt;
    opt.leave_one_out = false;
    opt.range_m = 60;
    opt.cell_m = 2;
    opt.detection_sigma_px = 2;
    // the linear map against Monte Carlo at the pose covariance of the stated noise: this draw's
    // survey-horizontal variance is estimated at 1.8x the stated one, and that covariance takes
    // the 60 m cells out of the linear regime (map 9.3 m, Monte Carlo 10.6 m)
    opt.calib.estimate_noise = false;
    rs_audit_result r;
    rs_err err = {0};
    rs_status st = rs_audit_camera(&r, &pb, up, 0, NULL, NULL, NULL, &opt, &err);
    CHECK(st == RS_OK, "audit: %s", err.msg);
    const rs_audit_map *m = &r.map;
    CHECK(st != RS_OK || (m->sigma_m && m->nx > 0 && m->ny > 0), "no map");
    if (st || !m->sigma_m) {
        rs_audit_result_free(&r);
        rs_simulate_problem_free(sp);
        return;
    }
    // every finite cell is in range and in the image; the camera's own cell is not seen
    int nfinite = 0;
    for (int k = 0; k < m->nx * m->ny; k++) {
        if (!isfinite(m->sigma_m[k])) continue;
        nfinite++;
        double e = m->e0_m + (k % m->nx) * m->cell_m, n = m->n0_m + (k / m->nx) * m->cell_m;
        double d = hypot(e - m->camera_en_m[0], n - m->camera_en_m[1]);
        CHECK(d <= opt.range_m + 1e-9, "cell (%g, %g) at %g m > range", e, n, d);
        CHECK(m->sigma_m[k] > 0, "cell (%g, %g): sigma %g", e, n, m->sigma_m[k]);
    }
    CHECK(nfinite > 50, "only %d cells seen", nfinite);
    // three cells: the nearest seen, one at the median distance and the farthest
    int pick[3] = {-1, -1, -1};
    double dmin = INFINITY, dmax = -1;
    for (int k = 0; k < m->nx * m->ny; k++) {
        if (!isfinite(m->sigma_m[k])) continue;
        double e = m->e0_m + (k % m->nx) * m->cell_m, n = m->n0_m + (k / m->nx) * m->cell_m;
        double d = hypot(e - m->camera_en_m[0], n - m->camera_en_m[1]);
        if (d < dmin) dmin = d, pick[0] = k;
        if (d > dmax) dmax = d, pick[2] = k;
    }
    double dmid = 0.5 * (dmin + dmax), best = INFINITY;
    for (int k = 0; k < m->nx * m->ny; k++) {
        if (!isfinite(m->sigma_m[k])) continue;
        double e = m->e0_m + (k % m->nx) * m->cell_m, n = m->n0_m + (k / m->nx) * m->cell_m;
        double d = fabs(hypot(e - m->camera_en_m[0], n - m->camera_en_m[1]) - dmid);
        if (d < best) best = d, pick[1] = k;
    }
    double Lc[36];
    bool pd = cholesky6(Lc, r.solve.covariance_rt_cam_enu);
    CHECK(pd, "pose covariance not positive definite");
    rs_rng rng;
    rs_rng_seed(&rng, seed + 1000);
    const int K = 4000;
    for (int c = 0; pd && c < 3; c++) {
        int k = pick[c];
        double p[3] = {m->e0_m + (k % m->nx) * m->cell_m, m->n0_m + (k / m->nx) * m->cell_m, 0}, q[2];
        CHECK(oracle_project(q, sp, r.solve.intrinsics, r.solve.rt_cam_enu, p), "cell %d: projection", k);
        double se = 0, sn = 0, se2 = 0, sn2 = 0;
        int n_ok = 0;
        for (int s = 0; s < K; s++) {
            double z[6], rt[6], qs[2], g[3];
            for (int a = 0; a < 6; a++) z[a] = rs_rng_normal(&rng);
            for (int a = 0; a < 6; a++) {
                rt[a] = r.solve.rt_cam_enu[a];
                for (int b = 0; b <= a; b++) rt[a] += Lc[6 * a + b] * z[b];
            }
            qs[0] = q[0] + opt.detection_sigma_px * rs_rng_normal(&rng);
            qs[1] = q[1] + opt.detection_sigma_px * rs_rng_normal(&rng);
            rs_camera sample = rs_calib_result_camera(&sp->camera, &r.solve);
            memcpy(sample.rt_cam_enu, rt, sizeof sample.rt_cam_enu);
            if (rs_camera_locate_ground(g, &sample, qs, up, 0, NULL)) continue;
            se += g[0], sn += g[1], se2 += g[0] * g[0], sn2 += g[1] * g[1];
            n_ok++;
        }
        CHECK(n_ok == K, "cell %d: %d of %d samples could not be located", k, K - n_ok, K);
        double ve = se2 / n_ok - (se / n_ok) * (se / n_ok), vn = sn2 / n_ok - (sn / n_ok) * (sn / n_ok);
        double mc = sqrt(ve + vn), lin = m->sigma_m[k];
        double dist = hypot(p[0] - m->camera_en_m[0], p[1] - m->camera_en_m[1]);
        printf("map (seed %llu): cell at %.1f m from the camera: map %.4f m, Monte Carlo %.4f m (%d samples), "
               "ratio %.3f\n",
               seed, dist, lin, mc, n_ok, lin / mc);
        CHECK(fabs(lin / mc - 1) < 0.10, "cell at %.1f m: map %.4f m vs Monte Carlo %.4f m", dist, lin, mc);
        // rs_audit_ground_sigma through the pixel gives the same number as the cell
        double s_px;
        const rs_camera cal = rs_calib_result_camera(&sp->camera, &r.solve);
        st = rs_audit_ground_sigma(&s_px, NULL, NULL, &cal, r.solve.covariance_rt_cam_enu, q, opt.detection_sigma_px,
                                   up, 0, NULL);
        CHECK(st == RS_OK && fabs(s_px - lin) < 1e-6 * lin, "ground_sigma(q) %.9f vs map %.9f", s_px, lin);
    }
    CHECK(r.image_hull_share > 0 && r.image_hull_share <= 1, "image hull share %g", r.image_hull_share);
    CHECK(r.ground_hull_share > 0 && r.ground_hull_share <= 1, "ground hull share %g", r.ground_hull_share);
    rs_audit_result_free(&r);
    rs_simulate_problem_free(sp);
}

// ---- 3. the moved-camera test ----

// New picks: the true landmarks seen by the camera turned by `turn_deg` about its own y axis
// (a pan), plus fresh pixel noise.
static void new_picks(double *q_new, const rs_simulate_problem *sp, double turn_deg, rs_rng *rng)
{
    double rt[6];
    const double turn[6] = {0, turn_deg * M_PI / 180, 0, 0, 0, 0};
    mrcal_compose_rt(rt, NULL, NULL, NULL, NULL, turn, sp->camera.rt_cam_enu); // camera turned after the pose
    for (int i = 0; i < sp->Npoints; i++) {
        double q[2];
        oracle_project(q, sp, sp->camera.intrinsics, rt, &sp->p_enu_true_m[3 * i]);
        q_new[2 * i] = q[0] + rs_rng_normal(rng);
        q_new[2 * i + 1] = q[1] + rs_rng_normal(rng);
    }
}

static void test_moved(unsigned long long seed)
{
    fixture f;
    if (!fixture_make(&f, seed, 12, 0, 0.3, 0.5)) return;
    rs_simulate_problem *sp = f.sp;
    rs_calib_problem pb = f.pb;
    double q_new[128];
    rs_audit_options opt = f.opt;
    opt.leave_one_out = false;
    opt.map = false;
    rs_rng rng;
    rs_rng_seed(&rng, seed + 7);
    rs_err err = {0};
    // moved by 0.5 deg: detected every time at alpha = 0.001, rotation estimated
    int detected = 0;
    const int Nmoved = 20;
    double worst_rot = 0;
    for (int d = 0; d < Nmoved; d++) {
        new_picks(q_new, sp, 0.5, &rng);
        rs_audit_result r;
        rs_status st = rs_audit_camera(&r, &pb, up, 0, q_new, NULL, NULL, &opt, &err);
        CHECK(st == RS_OK && r.has_against, "moved draw %d: %s", d, err.msg);
        if (st == RS_OK) {
            detected += r.against.moved;
            double e = fabs(r.against.rotation_deg - 0.5);
            if (e > worst_rot) worst_rot = e;
            CHECK(!r.pass && strstr(r.failures, "moved"), "moved draw %d: pass %d, failures '%s'", d, r.pass,
                  r.failures);
        }
        rs_audit_result_free(&r);
    }
    CHECK(detected == Nmoved, "0.5 deg turn detected in %d of %d draws", detected, Nmoved);
    CHECK(worst_rot < 0.1, "rotation estimate off by up to %.3f deg", worst_rot);
    // unmoved: false alarms at alpha = 0.05 over 300 draws ~ Binomial(300, 0.05): mean 15, sd 3.8
    opt.alpha = 0.05;
    int alarms = 0;
    const int Ndraws = 300;
    for (int d = 0; d < Ndraws; d++) {
        new_picks(q_new, sp, 0, &rng);
        rs_audit_result r;
        rs_status st = rs_audit_camera(&r, &pb, up, 0, q_new, NULL, NULL, &opt, &err);
        CHECK(st == RS_OK && r.has_against, "unmoved draw %d: %s", d, err.msg);
        if (st == RS_OK) alarms += r.against.moved;
        rs_audit_result_free(&r);
    }
    printf("moved (seed %llu): 0.5 deg detected %d/%d (rotation within %.3f deg); unmoved false alarms %d/%d at "
           "alpha 0.05\n",
           seed, detected, Nmoved, worst_rot, alarms, Ndraws);
    // 4 standard deviations either side of 15
    CHECK(alarms >= 1 && alarms <= 31, "false alarm rate %d/%d, expected about 15", alarms, Ndraws);
    rs_simulate_problem_free(sp);
}

// ---- 4. bad input ----

static void test_errors(void)
{
    fixture f;
    if (!fixture_make(&f, 5, 8, 0, 0.1, 0.1)) return;
    rs_simulate_problem *sp = f.sp;
    rs_calib_problem pb = f.pb;
    double q_new[128];
    rs_audit_options opt = f.opt;
    opt.leave_one_out = false;
    opt.map = false;
    rs_audit_result r;
    rs_err err = {0};
    opt.alpha = 1.5;
    CHECK(rs_audit_camera(&r, &pb, up, 0, NULL, NULL, NULL, &opt, &err) == RS_ERR_INVALID && strstr(err.msg, "alpha"),
          "alpha 1.5: '%s'", err.msg);
    rs_audit_result_free(&r);
    opt.alpha = 0.01;
    const double vertical[3] = {1, 0, 0};
    CHECK(rs_audit_camera(&r, &pb, vertical, 0, NULL, NULL, NULL, &opt, &err) == RS_ERR_INVALID,
          "vertical ground plane accepted");
    rs_audit_result_free(&r);
    for (int i = 0; i < 2 * pb.N; i++) q_new[i] = NAN;
    q_new[0] = sp->q_px[0], q_new[1] = sp->q_px[1];
    rs_status st = rs_audit_camera(&r, &pb, up, 0, q_new, NULL, NULL, &opt, &err);
    CHECK(st != RS_OK, "one new pick accepted");
    rs_audit_result_free(&r);
    rs_audit_result_free(NULL);
    rs_audit_calibration_free(NULL);
    rs_simulate_problem_free(sp);
}

// ---- 5. degeneracy words and image coverage ----

// A pinhole camera 20 m up looking almost straight down at 12 ground landmarks picked on a
// 300 x 100 px grid: planar landmarks seen head-on, clustered in 3.75% of the image (the hull
// of the picks is that rectangle exactly).
static void test_degeneracy(void)
{
    rs_test_seed = 0;
    double intrinsics[4] = {800, 800, 499.5, 399.5};
    const rs_camera cam = {.lensmodel = {.type = MRCAL_LENSMODEL_PINHOLE},
                           .intrinsics = intrinsics,
                           .Nintrinsics = 4,
                           .width = 1000,
                           .height = 800};
    const double ypr[3] = {10, -85, 0}, pos[3] = {0, 0, 20};
    double rt[6], p[12 * 3], q[12 * 2], s3[12 * 3], s1[12];
    rs_pose_rt_from_ypr(rt, ypr, pos);
    int N = 0;
    for (int iu = 0; iu < 4; iu++)
        for (int iv = 0; iv < 3; iv++, N++) {
            q[2 * N] = 300 + 100 * iu;
            q[2 * N + 1] = 300 + 50 * iv;
            rs_camera at_rt = cam;
            memcpy(at_rt.rt_cam_enu, rt, sizeof at_rt.rt_cam_enu);
            CHECK(rs_camera_locate_ground(&p[3 * N], &at_rt, &q[2 * N], up, 0, NULL) == RS_OK, "locate %d", N);
            s3[3 * N] = s3[3 * N + 1] = s3[3 * N + 2] = 0.01;
            s1[N] = 1;
        }
    rs_calib_problem pb = {.N = N, .p_enu_m = p, .sigma_enu_m = s3, .q_px = q, .sigma_px = s1, .camera = &cam};
    rs_audit_options opt;
    rs_audit_options_default(&opt);
    opt.cell_m = 0.5;
    opt.range_m = 30;
    rs_audit_result r;
    rs_err err = {0};
    rs_status st = rs_audit_camera(&r, &pb, up, 0, NULL, NULL, NULL, &opt, &err);
    CHECK(st == RS_OK, "audit: %s", err.msg);
    if (st == RS_OK) {
        CHECK(fabs(r.image_hull_share - 0.0375) < 1e-6, "image hull share %.9f, expected 0.0375", r.image_hull_share);
        CHECK(r.planarity < 1e-6, "planarity %g", r.planarity);
        // oracle: the landmarks lie on the level ground, so the plane normal is vertical
        double c[3] = {0, 0, 0};
        for (int i = 0; i < N; i++)
            for (int k = 0; k < 3; k++) c[k] += p[3 * i + k] / N;
        double d[3] = {c[0] - pos[0], c[1] - pos[1], c[2] - pos[2]};
        double head_on = acos(fabs(d[2]) / sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])) * 180 / M_PI;
        CHECK(fabs(r.head_on_deg - head_on) < 1e-6, "head-on angle %.9f deg, expected %.9f", r.head_on_deg, head_on);
        CHECK(strstr(r.warnings, "of the image") && strstr(r.warnings, "head-on"), "warnings '%s'", r.warnings);
        CHECK(r.collinearity > 0.2, "collinearity %g", r.collinearity);
        CHECK(!strstr(r.warnings, "line"), "collinear warning on a 2-D grid: '%s'", r.warnings);
        printf("degeneracy: image share %.4f, planarity %.1e, head-on %.2f deg, warnings: %s\n", r.image_hull_share,
               r.planarity, r.head_on_deg, r.warnings);
    }
    rs_audit_result_free(&r);
}

int main(void)
{
    test_leave_one_out(11);
    test_leave_one_out(12);
    test_map(21);
    test_moved(31);
    test_errors();
    test_degeneracy();
    return rs_test_end("test_audit");
}

// test_pose.c -- core/rs_pose.h against closed forms (docs/conventions.md): the optical axis of
// yaw/pitch/roll is (sin y cos p, cos y cos p, sin p), roll turns x_cam towards the down vector;
// R -> ypr -> R and rt -> ypr -> rt round trips; the convention at pitch = +-90 deg; the camera
// position -R^T t and its Jacobian against central differences. Fixed seeds, printed on failure.
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <mrcal/poseutils.h>

#include "core/rs_pose.h"
#include "core/rs_rng.h"
#include "tests/common/rs_test.h"

static double dist3(const double *a, const double *b)
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

// Random yaw/pitch/roll away from the poles: the closed-form axes and both round trips.
static void test_ypr_round_trip(void)
{
    rs_test_seed = 77;
    rs_rng rng;
    rs_rng_seed(&rng, rs_test_seed);
    double worst = 0;
    for (int k = 0; k < 2000; k++) {
        const double ypr[3] = {rs_rng_uniform_in(&rng, 0, 360), rs_rng_uniform_in(&rng, -89, 89),
                               rs_rng_uniform_in(&rng, -179, 179)};
        const double C[3] = {rs_rng_uniform_in(&rng, -500, 500), rs_rng_uniform_in(&rng, -500, 500),
                             rs_rng_uniform_in(&rng, 0, 50)};
        double R[9], Rr[9], rt[6], back[3], back_rt[3], Cb[3];
        rs_pose_R_from_ypr(R, ypr);
        const double y = ypr[0] * M_PI / 180, p = ypr[1] * M_PI / 180, r = ypr[2] * M_PI / 180;
        const double f[3] = {sin(y) * cos(p), cos(y) * cos(p), sin(p)};
        const double right0[3] = {cos(y), -sin(y), 0}, down0[3] = {sin(y) * sin(p), cos(y) * sin(p), -cos(p)};
        double xcam[3];
        for (int i = 0; i < 3; i++) xcam[i] = cos(r) * right0[i] + sin(r) * down0[i];
        const double e_axes = fmax(dist3(&R[6], f), dist3(&R[0], xcam)); // rows z_cam, x_cam
        rs_pose_ypr_from_R(back, R);
        rs_pose_rt_from_ypr(rt, ypr, C);
        mrcal_R_from_r(Rr, NULL, rt);
        double e_R = 0;
        for (int i = 0; i < 9; i++) e_R = fmax(e_R, fabs(Rr[i] - R[i]));
        rs_pose_ypr_from_rt(back_rt, Cb, rt);
        double d = 0;
        for (int i = 0; i < 3; i++) {
            const double a = i == 1 ? back[i] - ypr[i] : remainder(back[i] - ypr[i], 360.0);
            const double b = i == 1 ? back_rt[i] - ypr[i] : remainder(back_rt[i] - ypr[i], 360.0);
            d = fmax(d, fmax(fabs(a), fabs(b)));
        }
        worst = fmax(worst, d);
        CHECK(e_axes < 1e-12 && e_R < 1e-12 && d < 1e-9 && dist3(C, Cb) < 1e-9 && back[0] >= 0 && back[0] < 360 &&
                  back[2] > -180 && back[2] <= 180,
              "ypr (%.12g %.12g %.12g): axes %g, R(r) %g, back (%.12g %.12g %.12g), C err %g", ypr[0], ypr[1], ypr[2],
              e_axes, e_R, back[0], back[1], back[2], dist3(C, Cb));
    }
    printf("ypr round trip, 2000 poses: worst %.3g deg (tolerance 1e-9)\n", worst);
}

// At pitch = +-90 yaw is undefined: yaw 0, the whole turn in roll, the same rotation back.
static void test_ypr_poles(void)
{
    rs_test_seed = 0;
    for (int s = -1; s <= 1; s += 2)
        for (int k = 0; k < 12; k++) {
            const double ypr[3] = {30.0 * k, 90.0 * s, 17.0};
            double R[9], back[3], R2[9];
            rs_pose_R_from_ypr(R, ypr);
            rs_pose_ypr_from_R(back, R);
            rs_pose_R_from_ypr(R2, back);
            double e = 0;
            for (int i = 0; i < 9; i++) e = fmax(e, fabs(R2[i] - R[i]));
            CHECK(back[0] == 0 && fabs(back[1] - 90.0 * s) < 1e-9 && e < 1e-12,
                  "pole ypr (%g %g %g) -> (%.12g %.12g %.12g), R error %g", ypr[0], ypr[1], ypr[2], back[0], back[1],
                  back[2], e);
        }
}

// Camera position and its Jacobian against central differences.
static void test_position(void)
{
    rs_test_seed = 5;
    rs_rng rng;
    rs_rng_seed(&rng, rs_test_seed);
    double worst = 0;
    for (int k = 0; k < 200; k++) {
        double rt[6];
        for (int i = 0; i < 3; i++) rt[i] = rs_rng_uniform_in(&rng, -2, 2);
        for (int i = 3; i < 6; i++) rt[i] = rs_rng_uniform_in(&rng, -100, 100);
        double C[3], J[18], R[9];
        rs_pose_position_from_rt(C, J, rt);
        mrcal_R_from_r(R, NULL, rt);
        double Cc[3]; // -R^T t by hand
        for (int i = 0; i < 3; i++) Cc[i] = -(R[i] * rt[3] + R[3 + i] * rt[4] + R[6 + i] * rt[5]);
        CHECK(dist3(C, Cc) < 1e-9, "position %g off", dist3(C, Cc));
        for (int j = 0; j < 6; j++) {
            double a[6], b[6], Ca[3], Cb[3];
            memcpy(a, rt, sizeof a);
            memcpy(b, rt, sizeof b);
            a[j] += 1e-6;
            b[j] -= 1e-6;
            rs_pose_position_from_rt(Ca, NULL, a);
            rs_pose_position_from_rt(Cb, NULL, b);
            for (int i = 0; i < 3; i++) {
                const double num = (Ca[i] - Cb[i]) / 2e-6, rel = fabs(num - J[6 * i + j]) / fmax(1, fabs(num));
                worst = fmax(worst, rel);
            }
        }
    }
    CHECK(worst < 1e-6, "dpos/drt vs central differences: %g", worst);
    printf("position Jacobian vs central differences: worst relative %.3g (tolerance 1e-6)\n", worst);
}

// A prepared pose against mrcal_transform_point_rt: the point and both gradients.
static void test_prepared(void)
{
    rs_test_seed = 11;
    rs_rng rng;
    rs_rng_seed(&rng, rs_test_seed);
    double worst = 0;
    for (int k = 0; k < 200; k++) {
        double rt[6], p[3];
        for (int i = 0; i < 3; i++) rt[i] = rs_rng_uniform_in(&rng, -3, 3);
        for (int i = 3; i < 6; i++) rt[i] = rs_rng_uniform_in(&rng, -100, 100);
        for (int i = 0; i < 3; i++) p[i] = rs_rng_uniform_in(&rng, -200, 200);
        rs_pose_prepared pose;
        rs_pose_prepare(&pose, rt);
        double pc[3], drt[18], dp[9], pc0[3], drt0[18], dp0[9];
        rs_pose_prepared_apply(pc, drt, dp, &pose, p);
        mrcal_transform_point_rt(pc0, drt0, dp0, rt, p);
        for (int i = 0; i < 3; i++) worst = fmax(worst, fabs(pc[i] - pc0[i]) / fmax(1, fabs(pc0[i])));
        for (int i = 0; i < 18; i++) worst = fmax(worst, fabs(drt[i] - drt0[i]) / fmax(1, fabs(drt0[i])));
        for (int i = 0; i < 9; i++) worst = fmax(worst, fabs(dp[i] - dp0[i]));
        double pc1[3];
        rs_pose_prepared_apply(pc1, NULL, NULL, &pose, p); // the gradients are optional
        CHECK(dist3(pc1, pc) == 0, "without gradients: %g", dist3(pc1, pc));
    }
    CHECK(worst < 1e-12, "prepared pose vs mrcal_transform_point_rt: %g", worst);
    printf("prepared pose vs mrcal_transform_point_rt: worst relative %.3g (tolerance 1e-12)\n", worst);
}

// The 3x3 helpers against brute force, aliasing included.
static void test_mat3(void)
{
    rs_test_seed = 9;
    rs_rng rng;
    rs_rng_seed(&rng, rs_test_seed);
    double a[9], b[9], c[9], ref[9], t[9];
    for (int i = 0; i < 9; i++) a[i] = rs_rng_normal(&rng), b[i] = rs_rng_normal(&rng);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            ref[3 * i + j] = 0;
            for (int k = 0; k < 3; k++) ref[3 * i + j] += a[3 * i + k] * b[3 * k + j];
        }
    rs_pose_mat3_mul(c, a, b);
    memcpy(t, a, sizeof t);
    rs_pose_mat3_mul(t, t, b); // aliasing the output with an input
    double e = 0;
    for (int i = 0; i < 9; i++) e = fmax(e, fmax(fabs(c[i] - ref[i]), fabs(t[i] - ref[i])));
    memcpy(t, a, sizeof t);
    rs_pose_mat3_transpose(t, t);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) e = fmax(e, fabs(t[3 * i + j] - a[3 * j + i]));
    CHECK(e < 1e-15, "mat3 helpers off by %g", e);
}

// rs_pose_rotation_between against two oracles: the angle theta the test built R_a from
// (R_a = R(theta u) R_b, u a random unit axis, r_a from the matrix by rs_pose_r_from_R), within
// 2e-12 rad over [0, pi] with 500 angles within 1e-3 rad of pi and 500 under 1e-6 rad; and
// acos((trace(R_a R_b^T) - 1) / 2), within 1e-7 rad (acos loses half the digits near 0 and pi).
// Also r_ab against R_a R_b^T (1e-12 per element) and dr_ab/dr_a against central differences.
static void test_rotation_between(void)
{
    rs_test_seed = 4242;
    rs_rng rng;
    rs_rng_seed(&rng, rs_test_seed);
    double worst_theta = 0, worst_acos = 0, worst_R = 0, worst_J = 0;
    enum { N = 6000 };
    for (int k = 0; k < N; k++) {
        double u[3], n2 = 0, r_b[3];
        for (int i = 0; i < 3; i++) u[i] = rs_rng_uniform_in(&rng, -1, 1), n2 += u[i] * u[i];
        for (int i = 0; i < 3; i++) u[i] /= sqrt(n2), r_b[i] = rs_rng_uniform_in(&rng, -1.8, 1.8);
        const double theta = k < 500     ? M_PI - 1e-3 * rs_rng_uniform(&rng)
                             : k < 1000  ? 1e-6 * rs_rng_uniform(&rng)
                             : k == 1000 ? M_PI
                             : k == 1001 ? 0
                                         : M_PI * rs_rng_uniform(&rng);
        const double r_turn[3] = {theta * u[0], theta * u[1], theta * u[2]};
        double R_turn[9], R_b[9], R_a[9], r_a[3], R_ab[9], Rt_b[9];
        mrcal_R_from_r(R_turn, NULL, r_turn);
        mrcal_R_from_r(R_b, NULL, r_b);
        rs_pose_mat3_mul(R_a, R_turn, R_b);
        rs_pose_r_from_R(r_a, R_a);
        double r_ab[3], J[9];
        const double got = rs_pose_rotation_between(r_ab, J, r_a, r_b);
        CHECK(got >= 0 && got <= M_PI, "k %d: angle %.17g outside [0, pi]", k, got);
        worst_theta = fmax(worst_theta, fabs(got - theta));
        CHECK(fabs(got - theta) < 2e-12, "k %d: angle %.17g, built %.17g", k, got, theta);
        // acos oracle on the matrices
        mrcal_R_from_r(R_a, NULL, r_a);
        rs_pose_mat3_transpose(Rt_b, R_b);
        rs_pose_mat3_mul(R_ab, R_a, Rt_b);
        const double c = fmax(-1.0, fmin(1.0, 0.5 * (R_ab[0] + R_ab[4] + R_ab[8] - 1)));
        worst_acos = fmax(worst_acos, fabs(got - acos(c)));
        CHECK(fabs(got - acos(c)) < 1e-7, "k %d: angle %.17g, acos %.17g", k, got, acos(c));
        // r_ab is the rotation R_a R_b^T (compared as matrices: r is ambiguous at pi)
        double R_from[9];
        mrcal_R_from_r(R_from, NULL, r_ab);
        for (int i = 0; i < 9; i++) worst_R = fmax(worst_R, fabs(R_from[i] - R_ab[i]));
        // dr_ab/dr_a by central differences, away from pi (r wraps there)
        if (theta < M_PI - 0.1)
            for (int j = 0; j < 3; j++) {
                const double h = 1e-6;
                double rp[3], rm[3], qp[3], qm[3];
                memcpy(rp, r_a, sizeof rp), memcpy(rm, r_a, sizeof rm);
                rp[j] += h, rm[j] -= h;
                rs_pose_rotation_between(qp, NULL, rp, r_b);
                rs_pose_rotation_between(qm, NULL, rm, r_b);
                for (int i = 0; i < 3; i++) worst_J = fmax(worst_J, fabs((qp[i] - qm[i]) / (2 * h) - J[3 * i + j]));
            }
    }
    CHECK(worst_R < 1e-12, "r_ab: R(r_ab) differs from R_a R_b^T by %.3g", worst_R);
    CHECK(worst_J < 1e-6, "dr_ab/dr_a: %.3g from central differences", worst_J);
    CHECK(rs_pose_rotation_between(NULL, NULL, (const double[3]){0.3, -0.2, 0.1}, (const double[3]){0.3, -0.2, 0.1}) ==
              0,
          "the angle of a rotation to itself is not 0");
    printf("rotation_between: %d rotations (500 within 1e-3 rad of pi, 500 under 1e-6 rad): worst %.3g rad from the "
           "built angle, %.3g from acos((trace - 1) / 2), R(r_ab) %.3g, Jacobian %.3g\n",
           N, worst_theta, worst_acos, worst_R, worst_J);
}

int main(void)
{
    test_ypr_round_trip();
    test_ypr_poles();
    test_position();
    test_prepared();
    test_mat3();
    test_rotation_between();
    return rs_test_end("test_pose");
}

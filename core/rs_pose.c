// rs_pose.c -- rotations, yaw/pitch/roll, camera position, r_from_R. See rs_pose.h.
#include "core/rs_pose.h"

#include <math.h>
#include <string.h>

#include <mrcal/poseutils.h>

#include "core/internal/rs_pose_eigen.h"
#include "core/rs_units.h"

// A level camera looking north: columns x_cam -> east, y_cam -> down, z_cam -> north.
static const double R_enu_cam0[9] = {1, 0, 0, 0, 0, 1, 0, -1, 0};

void rs_pose_mat3_mul(double out[9], const double a[9], const double b[9])
{
    double m[9];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) m[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
    memcpy(out, m, sizeof m);
}

void rs_pose_mat3_transpose(double out[9], const double a[9])
{
    double m[9];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) m[3 * j + i] = a[3 * i + j];
    memcpy(out, m, sizeof m);
}

void rs_pose_Rx(double R[9], double a)
{
    const double c = cos(a), s = sin(a);
    const double m[9] = {1, 0, 0, 0, c, -s, 0, s, c};
    memcpy(R, m, sizeof m);
}

void rs_pose_Rz(double R[9], double a)
{
    const double c = cos(a), s = sin(a);
    const double m[9] = {c, -s, 0, s, c, 0, 0, 0, 1};
    memcpy(R, m, sizeof m);
}

void rs_pose_R_from_ypr(double R_cam_enu[9], const double ypr_deg[3])
{
    double A[9], B[9], R[9];
    rs_pose_Rz(A, -ypr_deg[0] * RS_RAD_PER_DEG);
    rs_pose_Rx(B, ypr_deg[1] * RS_RAD_PER_DEG);
    rs_pose_mat3_mul(R, A, B);
    rs_pose_mat3_mul(R, R, R_enu_cam0);
    rs_pose_Rz(A, ypr_deg[2] * RS_RAD_PER_DEG);
    rs_pose_mat3_mul(R, R, A); // R_enu_cam
    rs_pose_mat3_transpose(R_cam_enu, R);
}

void rs_pose_ypr_from_R(double ypr_deg[3], const double R_cam_enu[9])
{
    double R_enu_cam[9];
    rs_pose_mat3_transpose(R_enu_cam, R_cam_enu);
    // optical axis in ENU = third column of R_enu_cam = (sin y cos p, cos y cos p, sin p)
    const double fx = R_enu_cam[2], fy = R_enu_cam[5], fz = R_enu_cam[8];
    const double h = hypot(fx, fy);
    const double pitch = atan2(fz, h);
    const double yaw = h > 1e-14 ? atan2(fx, fy) : 0.0;
    // Rz(roll) = (Rz(-yaw) Rx(pitch) R0)^T R_enu_cam
    double A[9], Rx[9], M[9];
    rs_pose_Rz(A, -yaw);
    rs_pose_Rx(Rx, pitch);
    rs_pose_mat3_mul(A, A, Rx);
    rs_pose_mat3_mul(A, A, R_enu_cam0);
    rs_pose_mat3_transpose(A, A);
    rs_pose_mat3_mul(M, A, R_enu_cam);
    const double roll = atan2(M[3], M[0]);
    double yaw_deg = yaw * RS_DEG_PER_RAD, roll_deg = roll * RS_DEG_PER_RAD;
    if (yaw_deg < 0.0) yaw_deg += 360.0;
    if (yaw_deg >= 360.0) yaw_deg -= 360.0;
    if (roll_deg <= -180.0) roll_deg += 360.0;
    ypr_deg[0] = yaw_deg;
    ypr_deg[1] = pitch * RS_DEG_PER_RAD;
    ypr_deg[2] = roll_deg;
}

void rs_pose_position_from_rt(double position_enu_m[3], double *dpos_drt, const double rt_cam_enu[6])
{
    double rt_enu_cam[6], dt_dr[9], dt_dt[9];
    mrcal_invert_rt(rt_enu_cam, dt_dr, dt_dt, rt_cam_enu);
    memcpy(position_enu_m, &rt_enu_cam[3], 3 * sizeof(double));
    if (dpos_drt)
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                dpos_drt[i * 6 + j] = dt_dr[i * 3 + j];
                dpos_drt[i * 6 + 3 + j] = dt_dt[i * 3 + j];
            }
}

void rs_pose_ypr_from_rt(double ypr_deg[3], double position_enu_m[3], const double rt_cam_enu[6])
{
    double R_cam_enu[9];
    mrcal_R_from_r(R_cam_enu, NULL, rt_cam_enu);
    rs_pose_ypr_from_R(ypr_deg, R_cam_enu);
    if (position_enu_m) rs_pose_position_from_rt(position_enu_m, NULL, rt_cam_enu);
}

void rs_pose_rt_from_ypr(double rt_cam_enu[6], const double ypr_deg[3], const double position_enu_m[3])
{
    double R[9];
    rs_pose_R_from_ypr(R, ypr_deg);
    rs_pose_r_from_R(rt_cam_enu, R); // not mrcal's alone: wrong at a half-turn (looking down)
    for (int i = 0; i < 3; i++)
        rt_cam_enu[3 + i] =
            -(R[i * 3] * position_enu_m[0] + R[i * 3 + 1] * position_enu_m[1] + R[i * 3 + 2] * position_enu_m[2]);
}

void rs_pose_r_from_R(double r[3], const double R[9])
{
    mrcal_r_from_R(r, NULL, R);
    double back[9];
    mrcal_R_from_r(back, NULL, r);
    double worst = 0;
    for (int i = 0; i < 9; i++) worst = fmax(worst, fabs(back[i] - R[i]));
    if (worst <= 1e-12) return;
    rs_pose_eigen_r_from_R(r, R);
}

void rs_pose_prepare(rs_pose_prepared *pose, const double rt[6])
{
    mrcal_R_from_r(pose->R, pose->dR_dr, rt);
    for (int k = 0; k < 3; k++) pose->t[k] = rt[3 + k];
}

void rs_pose_prepared_apply(double p_cam[3], double *dpcam_drt, double *dpcam_dp, const rs_pose_prepared *pose,
                            const double p[3])
{
    const double *R = pose->R, *dR = pose->dR_dr;
    for (int i = 0; i < 3; i++) p_cam[i] = R[3 * i] * p[0] + R[3 * i + 1] * p[1] + R[3 * i + 2] * p[2] + pose->t[i];
    if (dpcam_drt)
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 3; k++) {
                dpcam_drt[6 * i + k] = dR[9 * i + k] * p[0] + dR[9 * i + 3 + k] * p[1] + dR[9 * i + 6 + k] * p[2];
                dpcam_drt[6 * i + 3 + k] = i == k;
            }
    if (dpcam_dp) memcpy(dpcam_dp, R, 9 * sizeof *R);
}

double rs_pose_rotation_between(double r_ab[3], double dr_ab_dr_a[9], const double r_a[3], const double r_b[3])
{
    const double minus_r_b[3] = {-r_b[0], -r_b[1], -r_b[2]};
    double r[3], J[9];
    mrcal_compose_r(r, dr_ab_dr_a ? J : NULL, NULL, r_a, minus_r_b);
    const double norm = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    // mrcal_compose_r returns |r| in [0, 2 pi): beyond pi it is the turn of 2 pi - |r| about -r,
    // r' = s r with s = 1 - 2 pi / |r|, dr'/dr = s I + (2 pi / |r|^3) r r^T
    const bool wrap = norm > M_PI;
    const double s = wrap ? 1 - 2 * M_PI / norm : 1, g = wrap ? 2 * M_PI / (norm * norm * norm) : 0;
    if (r_ab)
        for (int i = 0; i < 3; i++) r_ab[i] = s * r[i];
    if (dr_ab_dr_a)
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                double d = 0;
                for (int k = 0; k < 3; k++) d += ((i == k) * s + g * r[i] * r[k]) * J[3 * k + j];
                dr_ab_dr_a[3 * i + j] = d;
            }
    return wrap ? 2 * M_PI - norm : norm;
}

// rs_camera_ground.c -- a pixel's ground point and its covariance (rs_camera_ground.h, Method).
#include "core/rs_camera_ground.h"

#include <math.h>
#include <string.h>

#include <mrcal/poseutils.h>

#include "core/rs_lens.h"

rs_status rs_camera_ground_check_plane(const double n[3], rs_err *err)
{
    if (!(isfinite(n[0]) && isfinite(n[1]) && isfinite(n[2])) || !(fabs(n[2]) > 1e-9))
        return rs_err_set(err, RS_ERR_INVALID, "ground plane normal (%g, %g, %g): must be finite and not vertical",
                          n[0], n[1], n[2]);
    return RS_OK;
}

// Cov(g) of the ground point p (on the plane n) seen by the camera, and its pixel; false if
// degenerate.
static bool ground_cov(double cov[4], double q_out[2], const rs_camera *cam, const double *C_rt, const double p[3],
                       const double *C_q, const double n[3])
{
    double pc[3], dpc_drt[18], dpc_dp[9];
    mrcal_transform_point_rt(pc, dpc_drt, dpc_dp, cam->rt_cam_enu, p);
    if (!(pc[2] > 0)) return false;
    mrcal_point2_t q;
    mrcal_point3_t dq_dpc[2];
    if (!rs_lens_project(&q, dq_dpc, NULL, (const mrcal_point3_t *)pc, 1, &cam->lensmodel, cam->intrinsics))
        return false;
    if (q_out) q_out[0] = q.x, q_out[1] = q.y;
    const double dp_dg[6] = {1, 0, 0, 1, -n[0] / n[2], -n[1] / n[2]}; // (3,2)
    double A[4] = {0}, B[12] = {0};                                   // (2,2), (2,6)
    for (int i = 0; i < 2; i++) {
        double dq_dp[3] = {0};
        for (int k = 0; k < 3; k++)
            for (int j = 0; j < 3; j++) dq_dp[k] += dq_dpc[i].xyz[j] * dpc_dp[3 * j + k];
        for (int c = 0; c < 2; c++)
            for (int k = 0; k < 3; k++) A[2 * i + c] += dq_dp[k] * dp_dg[2 * k + c];
        for (int c = 0; c < 6; c++)
            for (int j = 0; j < 3; j++) B[6 * i + c] += dq_dpc[i].xyz[j] * dpc_drt[6 * j + c];
    }
    double det = A[0] * A[3] - A[1] * A[2];
    if (!(fabs(det) > 0) || !isfinite(det)) return false;
    const double Ai[4] = {A[3] / det, -A[1] / det, -A[2] / det, A[0] / det};
    double M[4] = {0}; // B C_rt B^T + C_q
    if (C_q) memcpy(M, C_q, sizeof M);
    if (C_rt)
        for (int i = 0; i < 2; i++)
            for (int j = 0; j < 2; j++)
                for (int a = 0; a < 6; a++)
                    for (int b = 0; b < 6; b++) M[2 * i + j] += B[6 * i + a] * C_rt[6 * a + b] * B[6 * j + b];
    double T[4] = {0};
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2; j++)
            for (int k = 0; k < 2; k++) T[2 * i + j] += Ai[2 * i + k] * M[2 * k + j];
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2; j++) {
            cov[2 * i + j] = 0;
            for (int k = 0; k < 2; k++) cov[2 * i + j] += T[2 * i + k] * Ai[2 * j + k];
        }
    return isfinite(cov[0]) && isfinite(cov[1]) && isfinite(cov[3]);
}

rs_status rs_camera_ground_locate(double p_enu_m[3], double cov_en_m2[4], const rs_camera *cam,
                                  const double covariance_rt[36], const double q_px[2], const double cov_q_px2[4],
                                  const double ground_normal_enu[3], double ground_offset_m, rs_err *err)
{
    p_enu_m[0] = p_enu_m[1] = p_enu_m[2] = NAN;
    if (cov_en_m2) cov_en_m2[0] = cov_en_m2[1] = cov_en_m2[2] = cov_en_m2[3] = NAN;
    rs_status st = rs_camera_ground_check_plane(ground_normal_enu, err);
    if (st) return st;
    double p[3], cov[4];
    if ((st = rs_camera_locate_ground(p, cam, q_px, ground_normal_enu, ground_offset_m, err))) return st;
    if (cov_en_m2 && !ground_cov(cov, NULL, cam, covariance_rt, p, cov_q_px2, ground_normal_enu))
        return rs_err_set(err, RS_ERR_DEGENERATE, "pixel (%g, %g): the ground point's covariance is undefined", q_px[0],
                          q_px[1]);
    memcpy(p_enu_m, p, sizeof p);
    if (cov_en_m2) memcpy(cov_en_m2, cov, sizeof cov);
    return RS_OK;
}

bool rs_camera_ground_covariance_at(double cov_en_m2[4], double q_px[2], const rs_camera *cam,
                                    const double covariance_rt[36], const double en_m[2], const double cov_q_px2[4],
                                    const double ground_normal_enu[3], double ground_offset_m)
{
    const double *n = ground_normal_enu;
    const double p[3] = {en_m[0], en_m[1], (ground_offset_m - n[0] * en_m[0] - n[1] * en_m[1]) / n[2]};
    double q[2];
    if (ground_cov(cov_en_m2, q, cam, covariance_rt, p, cov_q_px2, n)) {
        if (q_px) q_px[0] = q[0], q_px[1] = q[1];
        return true;
    }
    cov_en_m2[0] = cov_en_m2[1] = cov_en_m2[2] = cov_en_m2[3] = NAN;
    if (q_px) q_px[0] = q_px[1] = NAN;
    return false;
}

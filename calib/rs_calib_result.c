// rs_calib_result.c -- the result of one solve: its allocation and release, its warnings, and
// its assembly from the solve's state in ENU (calib/internal/rs_calib_result.h).
#include "calib/internal/rs_calib_result.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mrcal/poseutils.h>

#include "calib/internal/rs_calib_noise.h"
#include "calib/internal/rs_calib_refine.h"
#include "calib/internal/rs_calib_solve_state.h"
#include "core/rs_pose.h"
#include "core/rs_stats.h"

void rs_calib_result_free(rs_calib_result *result)
{
    if (!result) return;
    free(result->intrinsics);
    free(result->sigma_intrinsics);
    free(result->covariance_intrinsics);
    free(result->predicted_px);
    free(result->residual_px);
    free(result->normalised_residual);
    free(result->inlier);
    free(result->p_enu_refined_m);
    free(result->w_test);
    free(result->weight);
    free(result->redundancy);
    free(result->mdb_px);
    free(result->mdb_m);
    free(result->external_m);
    free(result->external_ground_m);
    memset(result, 0, sizeof(*result));
}

rs_camera rs_calib_result_camera(const rs_camera *nominal, const rs_calib_result *result)
{
    rs_camera c = *nominal;
    c.intrinsics = result->intrinsics;
    c.Nintrinsics = result->Nintrinsics;
    memcpy(c.rt_cam_enu, result->rt_cam_enu, sizeof c.rt_cam_enu);
    return c;
}

rs_status rs_calib__result_alloc(rs_calib_result *r, int N, int Ni)
{
    r->N = N;
    r->Nintrinsics = Ni;
    r->intrinsics = calloc((size_t)Ni, sizeof(double));
    r->sigma_intrinsics = calloc((size_t)Ni, sizeof(double));
    r->covariance_intrinsics = calloc((size_t)Ni * (size_t)Ni, sizeof(double));
    r->predicted_px = calloc((size_t)N * 2, sizeof(double));
    r->residual_px = calloc((size_t)N * 2, sizeof(double));
    r->normalised_residual = calloc((size_t)N, sizeof(double));
    r->inlier = calloc((size_t)N, sizeof(bool));
    r->p_enu_refined_m = calloc((size_t)N * 3, sizeof(double));
    double **per_landmark[] = {&r->w_test, &r->redundancy, &r->mdb_px,           &r->mdb_m,
                               &r->weight, &r->external_m, &r->external_ground_m};
    bool ok = true;
    for (size_t k = 0; k < sizeof per_landmark / sizeof *per_landmark; k++)
        ok = (*per_landmark[k] = calloc((size_t)(N > 0 ? N : 1), sizeof(double))) && ok;
    if (!ok || !r->intrinsics || !r->sigma_intrinsics || !r->covariance_intrinsics || !r->predicted_px ||
        !r->residual_px || !r->normalised_residual || !r->inlier || !r->p_enu_refined_m)
        return RS_ERR_NOMEM;
    return RS_OK;
}

void rs_calib__warn(rs_calib_result *r, const char *fmt, ...)
{
    size_t len = strlen(r->warnings);
    if (len + 3 >= sizeof(r->warnings)) return;
    if (len) {
        strcat(r->warnings, "; ");
        len += 2;
    }
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->warnings + len, sizeof(r->warnings) - len, fmt, ap);
    va_end(ap);
}

size_t rs_calib_warning_len(const char *warnings)
{
    int depth = 0;
    for (const char *s = warnings; *s; s++) {
        depth += *s == '(' ? 1 : *s == ')' && depth > 0 ? -1 : 0;
        if (depth == 0 && s[0] == ';' && s[1] == ' ') return (size_t)(s - warnings);
    }
    return strlen(warnings);
}

bool rs_calib__all_finite(const double *x, int n)
{
    for (int i = 0; i < n; i++)
        if (!isfinite(x[i])) return false;
    return true;
}

// ---------------------------------------------------------------- the pose in ENU

// out (n,n) = J (n,m) C (m,m) J^T
static void sandwich(double *out, const double *J, const double *C, int n, int m)
{
    for (int a = 0; a < n; a++)
        for (int b = 0; b < n; b++) {
            double s = 0.0;
            for (int i = 0; i < m; i++)
                for (int j = 0; j < m; j++) s += J[a * m + i] * C[i * m + j] * J[b * m + j];
            out[a * n + b] = s;
        }
}

// rt in the centred frame (p_c = p_enu - c) <-> ENU: t_enu = t_c - R c. J (6,6) = d rt_enu / d rt_c.
static void rt_enu_from_centred(double rt_enu[6], double J[36], const double rt_c[6], const double c[3])
{
    double Rc[3], dRc_dr[9];
    mrcal_rotate_point_r(Rc, dRc_dr, NULL, rt_c, c);
    double out[6];
    for (int i = 0; i < 3; i++) {
        out[i] = rt_c[i];
        out[3 + i] = rt_c[3 + i] - Rc[i];
    }
    memcpy(rt_enu, out, sizeof(out));
    if (J) {
        memset(J, 0, 36 * sizeof(double));
        for (int i = 0; i < 3; i++) {
            J[i * 6 + i] = 1.0;
            J[(3 + i) * 6 + 3 + i] = 1.0;
            for (int j = 0; j < 3; j++) J[(3 + i) * 6 + j] = -dRc_dr[i * 3 + j];
        }
    }
}
// Ceres moves r additively and may leave it beyond |r| = pi; the same rotation with
// |r| <= pi (mrcal_r_from_R) is reported, the covariance carried through dr'/dr (chain of
// mrcal's R_from_r and r_from_R gradients). cov_rt (6,6) in,out.
static void normalise_r(double rt[6], double cov_rt[36])
{
    const double th = sqrt(rt[0] * rt[0] + rt[1] * rt[1] + rt[2] * rt[2]);
    if (th <= M_PI) return;
    double R[9], dR_dr[27], r[3], dr_dR[27], J[9];
    mrcal_R_from_r(R, dR_dr, rt);
    mrcal_r_from_R(r, dr_dR, R);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double s = 0.0;
            for (int k = 0; k < 9; k++) s += dr_dR[i * 9 + k] * dR_dr[k * 3 + j];
            J[i * 3 + j] = s;
        }
    double J6[36] = {0}, out[36];
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) J6[i * 6 + j] = J[i * 3 + j];
        J6[(3 + i) * 6 + 3 + i] = 1.0;
    }
    sandwich(out, J6, cov_rt, 6, 6);
    memcpy(cov_rt, out, sizeof(out));
    memcpy(rt, r, sizeof(r));
}

// sigma of yaw/pitch/roll: cov_r (3,3) propagated through d(ypr)/dr, by central differences of
// rs_pose_ypr_from_rt() (step 1e-7 rad; yaw and roll differences wrapped to (-180, 180]).
static void ypr_sigma(double sigma_deg[3], const double rt[6], const double cov_r[9])
{
    double J[9];
    const double h = 1e-7;
    for (int j = 0; j < 3; j++) {
        double rp[6], rm[6], yp[3], ym[3];
        memcpy(rp, rt, sizeof(rp));
        memcpy(rm, rt, sizeof(rm));
        rp[j] += h;
        rm[j] -= h;
        rs_pose_ypr_from_rt(yp, NULL, rp);
        rs_pose_ypr_from_rt(ym, NULL, rm);
        for (int i = 0; i < 3; i++) {
            double d = yp[i] - ym[i];
            d = remainder(d, 360.0);
            J[i * 3 + j] = d / (2.0 * h);
        }
    }
    double C[9];
    sandwich(C, J, cov_r, 3, 3);
    for (int i = 0; i < 3; i++) sigma_deg[i] = sqrt(C[i * 3 + i]);
}

rs_status rs_calib__result_pose(rs_calib_solve_state *s, rs_err *err)
{
    rs_calib_result *res = s->res;
    const int Ni = res->Nintrinsics;
    double *rt_c = s->rt_c;
    const double *c = s->centroid_enu_m;
    const int n = 6 + Ni;
    double J[36], cov_c[36];
    for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++) cov_c[a * 6 + b] = s->cov[a * n + b];
    normalise_r(rt_c, cov_c);
    rt_enu_from_centred(res->rt_cam_enu, J, rt_c, c);
    sandwich(res->covariance_rt_cam_enu, J, cov_c, 6, 6);
    for (int a = 0; a < Ni; a++) {
        for (int b = 0; b < Ni; b++) res->covariance_intrinsics[a * Ni + b] = s->cov[(6 + a) * n + 6 + b];
        res->sigma_intrinsics[a] = sqrt(fmax(0.0, res->covariance_intrinsics[a * Ni + a]));
    }
    double dpos_drt[18], cov_pos[9], C_c[3];
    rs_pose_position_from_rt(C_c, dpos_drt, rt_c);
    sandwich(cov_pos, dpos_drt, cov_c, 3, 6);
    double cov_r[9];
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) cov_r[a * 3 + b] = cov_c[a * 6 + b];
    rs_pose_ypr_from_rt(res->yaw_pitch_roll_deg, res->position_enu_m, res->rt_cam_enu);
    ypr_sigma(res->sigma_yaw_pitch_roll_deg, rt_c, cov_r);
    for (int k = 0; k < 3; k++) {
        res->position_enu_m[k] = C_c[k] + c[k]; // the same point, without cancellation
        res->sigma_position_enu_m[k] = sqrt(cov_pos[k * 3 + k]);
    }
    if (!rs_calib__all_finite(res->covariance_rt_cam_enu, 36) || !rs_calib__all_finite(res->sigma_position_enu_m, 3) ||
        !rs_calib__all_finite(res->sigma_yaw_pitch_roll_deg, 3) || !rs_calib__all_finite(res->rt_cam_enu, 6))
        return rs_err_set(err, RS_ERR_DEGENERATE,
                          "the pose or its covariance is not finite: the landmarks do not "
                          "determine the pose");
    return RS_OK;
}

rs_status rs_calib__result_landmarks(rs_calib_solve_state *s, rs_err *err)
{
    rs_calib_result *res = s->res;
    const rs_calib_problem *pb = s->pb;
    const rs_calib_options *opt = s->opt;
    const int N = pb->N, Ninl = N - s->Noutliers;
    const double *c = s->centroid_enu_m;
    double sse = 0.0;
    for (int i = 0; i < N; i++) {
        res->inlier[i] = s->use[i];
        double seen[3], d[3];
        rs_calib__seen_point(seen, d, s->p_c, s->along_c, s->s_along, i);
        for (int k = 0; k < 3; k++) res->p_enu_refined_m[3 * i + k] = seen[k] + c[k];
        for (int k = 0; k < 2; k++) {
            res->predicted_px[2 * i + k] = s->q_pred[2 * i + k];
            res->residual_px[2 * i + k] = s->q_pred[2 * i + k] - pb->q_px[2 * i + k];
        }
        res->normalised_residual[i] = sqrt(s->block_chi2[i]);
        res->weight[i] = s->use[i] ? rs_calib_refine_weight(s->block_chi2[i], opt->robust_scale) : 0.0;
        if (s->use[i])
            sse += res->residual_px[2 * i] * res->residual_px[2 * i] +
                   res->residual_px[2 * i + 1] * res->residual_px[2 * i + 1];
    }
    res->Ninliers = Ninl;
    res->rms_px = sqrt(sse / Ninl);
    res->chi2 = s->final.chi2;
    res->dof = s->final.Nresiduals - s->final.Nfree;
    res->variance_factor = res->dof > 0 ? s->final.chi2 / res->dof : NAN;
    res->condition_number = s->final.condition_number;
    char focal_desc[48] = "";
    if (s->focal_scale != 1.0) snprintf(focal_desc, sizeof(focal_desc), " + focal-search(x%.3g)", s->focal_scale);
    snprintf(res->method, sizeof(res->method), "%s%s", s->init.method, focal_desc); // fits: 95 + 47 < 224
    const size_t len = strlen(res->method);
    snprintf(res->method + len, sizeof(res->method) - len, "%s + ceres-wls + covariance(absolute)", s->robust_desc);

    // a roadside camera looks down at its landmarks: one below them all looking up is the mirror
    // of the true pose (a pinhole projects points behind it too) or a sign of wrong heights
    double up_min = INFINITY;
    for (int i = 0; i < N; i++)
        if (s->use[i]) up_min = fmin(up_min, res->p_enu_refined_m[3 * i + 2]);
    if (res->position_enu_m[2] < up_min - 1.0 && res->yaw_pitch_roll_deg[1] > 0.0)
        return rs_err_set(err, RS_ERR_DEGENERATE,
                          "the solution has the camera %.3g m below every landmark, looking up (pitch %.3g deg): "
                          "a mirrored pose (points behind a camera project too) or landmark heights in another "
                          "datum; check the heights and the picks",
                          up_min - res->position_enu_m[2], res->yaw_pitch_roll_deg[1]);
    return RS_OK;
}

void rs_calib__result_warnings(rs_calib_solve_state *s)
{
    rs_calib_result *res = s->res;
    const rs_calib_problem *pb = s->pb;
    const rs_calib_options *opt = s->opt;
    const int N = pb->N, Ninl = N - s->Noutliers;
    if (s->Noutliers > 0) {
        char list[160] = "";
        size_t len = 0;
        for (int i = 0; i < N && len + 12 < sizeof(list); i++)
            if (!s->use[i]) len += (size_t)snprintf(list + len, sizeof(list) - len, "%s%d", len ? "," : "", i);
        char behind[64] = "";
        if (s->Nbehind > 0) snprintf(behind, sizeof behind, ", %d seen only behind the camera", s->Nbehind);
        rs_calib__warn(res, "%d of %d landmarks flagged as outliers and dropped (index %s; %d by data snooping%s)",
                       s->Noutliers, N, list, res->Nrejected_snooping, behind);
    }
    if (res->condition_number > opt->condition_warn)
        rs_calib__warn(res,
                       "weak geometry: condition number %.3g > %.3g (landmarks nearly collinear, bunched "
                       "in a small part of the image, or too few): the pose is poorly determined, read "
                       "the sigmas",
                       res->condition_number, opt->condition_warn);
    const double *sy = res->sigma_yaw_pitch_roll_deg;
    const double sigma_rot_deg = fmax(sy[0], fmax(sy[1], sy[2]));
    if (opt->sigma_rotation_warn_deg > 0 && sigma_rot_deg > opt->sigma_rotation_warn_deg)
        rs_calib__warn(res,
                       "the pose is poorly determined: yaw/pitch/roll sigmas %.2g, %.2g, %.2g deg (> %g): "
                       "the covariance, a first-order approximation, understates errors this large (add "
                       "landmarks spread over the image, or survey them more accurately)",
                       sy[0], sy[1], sy[2], opt->sigma_rotation_warn_deg);
    static const char *const group_name[RS_NOISE_NGROUPS] = {"pixel", "survey horizontal", "survey vertical"};
    static const char *const unit[RS_NOISE_NGROUPS] = {"px", "m", "m"};
    for (int g = 0; g < RS_NOISE_NGROUPS && opt->estimate_noise; g++) {
        const rs_calib_noise_group *n = &res->noise[g];
        if (!n->Nobservations) continue;
        if (!n->estimated_from_data) continue; // said in the result (and <id>.json), not a warning
        const double ratio = n->estimated / n->stated;
        if (ratio > 2.0 || ratio < 0.5)
            rs_calib__warn(
                res,
                "%s noise estimated from the data at %.3g %s (+- %.2g, redundancy %.1f), %.2gx the stated %.3g %s: "
                "the pose and its covariance use the estimate; state it next time",
                group_name[g], n->estimated, unit[g], n->sigma_estimated, n->redundancy, ratio, n->stated, unit[g]);
    }
    if (res->noise_model_wrong)
        rs_calib__warn(
            res,
            "the noise model is wrong: data snooping would reject more than %.0f%% of the landmarks (%d of %d "
            "rejected, the rest kept): check the pixel picks and the survey's datum, heights and sigmas before "
            "trusting this pose",
            100 * opt->max_rejected_fraction, N - Ninl, N);
    if (res->dof > 0 && !opt->estimate_noise) {
        const double lo = rs_stats_chi2_quantile(res->dof, -2.576) / res->dof;
        const double hi = rs_stats_chi2_quantile(res->dof, 2.576) / res->dof;
        if (res->variance_factor > hi)
            rs_calib__warn(res,
                           "residuals larger than the stated sigmas allow (variance factor %.3g, 99%% "
                           "bound %.3g): sigma_px or the survey sigmas are optimistic, or a mistake "
                           "remains; the reported covariance is then too small",
                           res->variance_factor, hi);
        else if (res->variance_factor < lo)
            rs_calib__warn(res,
                           "residuals smaller than the stated sigmas suggest (variance factor %.3g, 99%% "
                           "bound %.3g): the sigmas are pessimistic; the reported covariance is too large",
                           res->variance_factor, lo);
    } else if (res->dof <= 0) {
        rs_calib__warn(res, "no redundancy (dof %d): the fit cannot be checked against the sigmas", res->dof);
    }
    if ((s->user_refine & RS_CALIB_REFINE_FOCAL) && res->sigma_intrinsics[0] > 0.05 * res->intrinsics[0])
        rs_calib__warn(res,
                       "the focal length is poorly determined (sigma %.1f%%): the landmarks' depth "
                       "range or their spread in the image is too small to separate it from the distance",
                       100.0 * res->sigma_intrinsics[0] / res->intrinsics[0]);
    if (Ninl < 6) rs_calib__warn(res, "only %d inlying landmarks: little redundancy to catch a further mistake", Ninl);
    if (fabs(res->yaw_pitch_roll_deg[1]) > 89.0)
        rs_calib__warn(res, "camera looks nearly straight %s: yaw and roll are ill-defined",
                       res->yaw_pitch_roll_deg[1] > 0 ? "up" : "down");
    if (pb->camera->width > 0 && pb->camera->height > 0) {
        double qmin[2] = {INFINITY, INFINITY}, qmax[2] = {-INFINITY, -INFINITY};
        for (int i = 0; i < N; i++)
            if (s->use[i])
                for (int k = 0; k < 2; k++) {
                    qmin[k] = fmin(qmin[k], pb->q_px[2 * i + k]);
                    qmax[k] = fmax(qmax[k], pb->q_px[2 * i + k]);
                }
        const double area = (qmax[0] - qmin[0]) * (qmax[1] - qmin[1]);
        if (area < 0.05 * pb->camera->width * pb->camera->height)
            rs_calib__warn(res,
                           "the inlying landmarks cover only %.1f%% of the image: the pose is "
                           "sensitive to their errors",
                           100.0 * area / (pb->camera->width * pb->camera->height));
    }
}

// rs_calib.c -- rs_calib_solve: initial pose, robust refinement, outliers, plain re-solve,
// uncertainty; and the pose helpers (yaw/pitch/roll, camera position, ground intersection).
// API and method: rs_calib.h; the Ceres part: rs_calib_refine_ceres.cc; docs/calibration.md.
#include "calib/rs_calib.h"
#include "core/rs_pose.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <mrcal/poseutils.h>

#include "calib/internal/rs_calib_intrinsics.h"
#include "calib/internal/rs_calib_noise.h"
#include "calib/internal/rs_calib_refine.h"

#define DEG (180.0 / M_PI)

void rs_calib_options_default(rs_calib_options *opt)
{
    memset(opt, 0, sizeof(*opt));
    opt->refine = RS_CALIB_REFINE_NONE;
    opt->robust_scale = 2.0;
    opt->outlier_threshold = 3.717; // sqrt(chi2inv(0.999, 2)) = sqrt(13.8155)
    rs_calib_init_options_default(&opt->init);
    opt->max_iterations = 500;
    opt->focal_prior_rel_sigma = 1.0;
    opt->center_prior_sigma_px = 50.0;
    opt->distortion_prior_sigma = 0.1;
    opt->focal_search_min = 0.25;
    opt->focal_search_max = 4.0;
    opt->condition_warn = 100.0;
    opt->sigma_rotation_warn_deg = 2.0;
    opt->estimate_noise = true;
    opt->noise_prior_factor = 5.0;
    opt->noise_min_redundancy = 2.0;
    opt->snooping_critical = 3.29;
    opt->max_rejected_fraction = 0.25;
}

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

// ---------------------------------------------------------------- small helpers

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

// ---------------------------------------------------------------- rs_calib_solve

static void warn(rs_calib_result *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void warn(rs_calib_result *r, const char *fmt, ...)
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

static bool all_finite(const double *x, int n)
{
    for (int i = 0; i < n; i++)
        if (!isfinite(x[i])) return false;
    return true;
}

static rs_status validate(const rs_calib_problem *pb, const rs_calib_options *opt, int Ni, rs_err *err)
{
    if (!pb->camera || !pb->camera->intrinsics) return rs_err_set(err, RS_ERR_INVALID, "lensmodel/intrinsics: NULL");
    if ((&pb->camera->lensmodel)->type == MRCAL_LENSMODEL_CAHVORE)
        return rs_err_set(err, RS_ERR_UNSUPPORTED,
                          "lensmodel: CAHVORE has no projection gradients in mrcal; not supported");
    if (Ni <= 0) return rs_err_set(err, RS_ERR_INVALID, "lensmodel: invalid");
    if (!all_finite(pb->camera->intrinsics, Ni)) return rs_err_set(err, RS_ERR_INVALID, "intrinsics: not finite");
    if (opt->refine != RS_CALIB_REFINE_NONE) {
        if (opt->refine & ~(unsigned)(RS_CALIB_REFINE_FOCAL | RS_CALIB_REFINE_CENTER | RS_CALIB_REFINE_DISTORTION))
            return rs_err_set(err, RS_ERR_INVALID, "options: refine: unknown flags 0x%x", opt->refine);
        if (!mrcal_lensmodel_metadata((&pb->camera->lensmodel)).has_core)
            return rs_err_set(err, RS_ERR_UNSUPPORTED, "refine: this lens model has no (fx, fy, cx, cy) core");
        if ((opt->refine & RS_CALIB_REFINE_FOCAL) &&
            !(pb->camera->intrinsics[0] > 0.0 && pb->camera->intrinsics[1] > 0.0))
            return rs_err_set(err, RS_ERR_INVALID, "intrinsics: focal lengths must be > 0");
    }
    if (!(opt->outlier_threshold > 0.0) || !isfinite(opt->robust_scale) || !(opt->focal_search_min > 0.0) ||
        !(opt->focal_search_max >= opt->focal_search_min) || !(opt->focal_prior_rel_sigma >= 0.0) ||
        !(opt->center_prior_sigma_px >= 0.0) || !(opt->distortion_prior_sigma >= 0.0))
        return rs_err_set(err, RS_ERR_INVALID, "options: out of range");
    if (pb->N < 0) return rs_err_set(err, RS_ERR_INVALID, "N: %d < 0", pb->N);
    if (pb->N > 0 && (!pb->p_enu_m || !pb->q_px)) return rs_err_set(err, RS_ERR_INVALID, "p_enu_m/q_px: NULL");
    for (int i = 0; i < pb->N; i++) {
        if (!all_finite(&pb->p_enu_m[3 * i], 3))
            return rs_err_set(err, RS_ERR_INVALID, "landmark %d: p_enu_m: not finite", i);
        if (!all_finite(&pb->q_px[2 * i], 2))
            return rs_err_set(err, RS_ERR_INVALID, "landmark %d: q_px: not finite", i);
        if (pb->sigma_px && !(pb->sigma_px[i] > 0.0 && isfinite(pb->sigma_px[i])))
            return rs_err_set(err, RS_ERR_INVALID, "landmark %d: sigma_px: must be finite and > 0", i);
        if (pb->sigma_enu_m)
            for (int k = 0; k < 3; k++)
                if (!(pb->sigma_enu_m[3 * i + k] >= 0.0 && isfinite(pb->sigma_enu_m[3 * i + k])))
                    return rs_err_set(err, RS_ERR_INVALID, "landmark %d: sigma_enu_m[%d]: must be finite and >= 0", i,
                                      k);
    }
    if (pb->has_position_prior &&
        (!all_finite(pb->prior_position_enu_m, 3) || !(pb->prior_sigma_m > 0.0 && isfinite(pb->prior_sigma_m))))
        return rs_err_set(err, RS_ERR_INVALID, "position prior: position must be finite and prior_sigma_m > 0");
    int Npoints = pb->N;
    rs_status st = rs_calib__along_validate(&Npoints, pb, err);
    if (st != RS_OK) return st;
    if (Npoints < 4 && pb->N >= 4)
        return rs_err_set(err, RS_ERR_DEGENERATE,
                          "only %d point landmarks (points, poles' bases and tops): the initial pose needs 4; "
                          "picks along poles and lines only refine it",
                          Npoints);
    if (pb->N < 4)
        return rs_err_set(err, RS_ERR_DEGENERATE,
                          "only %d landmarks: a pose needs at least 4 (6 unknowns, 2 per landmark, "
                          "and one more to pick among the P3P solutions)",
                          pb->N);
    return RS_OK;
}

// rs_calib_init_pose() with its pixel threshold doubled up to 4 times while it finds no
// consensus: a survey sigma of 0.3 m on a landmark 12 m away is 30 px at f = 1200 px, so the
// user's threshold (default 8 px) can be too tight for the near landmarks. *T_used receives the
// threshold that worked. Invalid input is not retried.
static rs_status init_escalating(rs_calib_init_result *init, double *T_used, const double *intrinsics,
                                 const rs_calib_problem *pb, const rs_calib_options *opt, rs_err *err)
{
    rs_calib_init_options io = opt->init;
    if (!(io.ransac_threshold_px > 0.0)) io.ransac_threshold_px = 8.0;
    io.sigma_enu_m = pb->sigma_enu_m;
    rs_status st = RS_ERR_DEGENERATE;
    rs_err e = {RS_OK, ""};
    for (int k = 0; k < 5; k++, io.ransac_threshold_px *= 2.0) {
        st =
            rs_calib_init_pose(init, NULL, (&pb->camera->lensmodel), intrinsics, pb->p_enu_m, pb->q_px, pb->N, &io, &e);
        *T_used = io.ransac_threshold_px;
        if (st != RS_ERR_DEGENERATE) break;
    }
    if (st != RS_OK && err) *err = e;
    return st;
}

// MSAC cost (Torr & Zisserman 2000) of a pose over ALL landmarks: sum_i min(e_i^2, T^2), e_i the
// reprojection error in pixels through the given intrinsics; a landmark behind the camera or
// that does not project costs T^2.
static double msac_cost(const double rt_cam_enu[6], const double *intrinsics, const rs_calib_problem *pb, double T)
{
    double cost = 0.0;
    for (int i = 0; i < pb->N; i++) {
        mrcal_point3_t pc;
        mrcal_point2_t q;
        mrcal_transform_point_rt(pc.xyz, NULL, NULL, rt_cam_enu, &pb->p_enu_m[3 * i]);
        double e2 = T * T;
        if (pc.z > 0.0 && mrcal_project(&q, NULL, NULL, &pc, 1, (&pb->camera->lensmodel), intrinsics)) {
            const double dx = q.x - pb->q_px[2 * i], dy = q.y - pb->q_px[2 * i + 1];
            if (dx * dx + dy * dy < e2) e2 = dx * dx + dy * dy;
        }
        cost += e2;
    }
    return cost;
}

// Initial pose in the ENU frame. With focal refinement, a 1-D search over a focal scale s
// (quarter-octave steps over [focal_search_min, focal_search_max]) runs the initial pose at
// fx s, fy s and keeps the s whose pose has the smallest MSAC cost over all landmarks, with
// one truncation for every s: T = 4 x the RANSAC threshold (32 px by default), so that poses
// found at different escalated thresholds compare fairly. intrinsics receives the chosen scale.
static rs_status initial_pose(rs_calib_init_result *init, double *intrinsics, double *scale_out,
                              const rs_calib_problem *pb, const rs_calib_options *opt, int Ni, rs_err *err)
{
    const bool search = (opt->refine & RS_CALIB_REFINE_FOCAL) && opt->focal_search_max > opt->focal_search_min;
    double T;
    *scale_out = 1.0;
    if (!search) return init_escalating(init, &T, intrinsics, pb, opt, err);
    const int K = 1 + (int)ceil(4.0 * log2(opt->focal_search_max / opt->focal_search_min));
    const double T_score = 4.0 * (opt->init.ransac_threshold_px > 0.0 ? opt->init.ransac_threshold_px : 8.0);
    double best = INFINITY;
    rs_status last = RS_ERR_DEGENERATE;
    rs_err e_last = {RS_OK, ""};
    double *trial = malloc((size_t)Ni * sizeof(double));
    if (!trial) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int k = 0; k < K; k++) {
        const double s =
            opt->focal_search_min * pow(opt->focal_search_max / opt->focal_search_min, (double)k / (K - 1));
        memcpy(trial, pb->camera->intrinsics, (size_t)Ni * sizeof(double));
        trial[0] *= s;
        trial[1] *= s;
        rs_calib_init_result r;
        rs_err e = {RS_OK, ""};
        const rs_status st = init_escalating(&r, &T, trial, pb, opt, &e);
        if (st != RS_OK) {
            last = st;
            e_last = e;
            if (st != RS_ERR_DEGENERATE) break; // the input, not the scale, is at fault
            continue;
        }
        const double cost = msac_cost(r.rt_cam_enu, trial, pb, T_score);
        if (cost < best) {
            best = cost;
            *init = r;
            *scale_out = s;
        }
    }
    free(trial);
    if (!isfinite(best)) {
        if (err) *err = e_last;
        return last;
    }
    intrinsics[0] = pb->camera->intrinsics[0] * *scale_out;
    intrinsics[1] = pb->camera->intrinsics[1] * *scale_out;
    return RS_OK;
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
static void rt_centred_from_enu(double rt_c[6], const double rt_enu[6], const double c[3])
{
    double Rc[3];
    mrcal_rotate_point_r(Rc, NULL, NULL, rt_enu, c);
    for (int i = 0; i < 3; i++) {
        rt_c[i] = rt_enu[i];
        rt_c[3 + i] = rt_enu[3 + i] + Rc[i];
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

// Wilson-Hilferty approximation of the chi-square quantile with k dof at standard normal z.
static double chi2_quantile(int k, double z)
{
    const double a = 2.0 / (9.0 * k);
    const double b = 1.0 - a + z * sqrt(a);
    return k * b * b * b;
}

static rs_status alloc_result(rs_calib_result *r, int N, int Ni)
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

static void work_free(rs_calib__work *w)
{
    free(w->p_survey_c);
    free(w->p_c);
    free(w->cov);
    free(w->block_chi2);
    free(w->q_pred);
    free(w->use);
    free(w->sigma_px);
    free(w->sigma_enu);
    free(w->e);
    free(w->r);
    free(w->dpos);
    free(w->dground);
    free(w->chi2_excluded);
    free(w->along_c);
    free(w->share);
    free(w->s_along);
}

static rs_status solve(rs_calib_result *res, rs_calib__work *w, const rs_calib_problem *pb, const rs_calib_options *opt,
                       unsigned user_refine, int Ni, const rs_calib__warm *warm, rs_err *err)
{
    const int N = pb->N;
    rs_status st = validate(pb, opt, Ni, err);
    if (st != RS_OK) return st;
    if (alloc_result(res, N, Ni) != RS_OK) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    w->p_survey_c = malloc((size_t)N * 3 * sizeof(double));
    w->p_c = malloc((size_t)N * 3 * sizeof(double));
    w->cov = malloc((size_t)(6 + Ni) * (size_t)(6 + Ni) * sizeof(double));
    w->block_chi2 = malloc((size_t)N * sizeof(double));
    w->q_pred = malloc((size_t)N * 2 * sizeof(double));
    w->use = malloc((size_t)N * sizeof(bool));
    w->sigma_px = malloc((size_t)N * sizeof(double));
    w->sigma_enu = malloc((size_t)N * 3 * sizeof(double));
    w->e = malloc((size_t)N * RS_NOISE_NCOMP * sizeof(double));
    w->r = malloc((size_t)N * RS_NOISE_NCOMP * sizeof(double));
    w->dpos = malloc((size_t)N * RS_NOISE_NCOMP * 3 * sizeof(double));
    w->dground = malloc((size_t)N * RS_NOISE_NCOMP * 2 * sizeof(double));
    w->chi2_excluded = malloc((size_t)N * sizeof(double));
    w->share = malloc((size_t)(N > 0 ? N : 1) * sizeof(double));
    if (pb->along) {
        w->along_c = calloc((size_t)N * 3, sizeof(double));
        w->s_along = calloc((size_t)N, sizeof(double));
    }
    if (!w->p_survey_c || !w->p_c || !w->cov || !w->block_chi2 || !w->q_pred || !w->use || !w->sigma_px ||
        !w->sigma_enu || !w->e || !w->r || !w->dpos || !w->dground || !w->chi2_excluded || !w->share ||
        (pb->along && (!w->along_c || !w->s_along)))
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int i = 0; i < N; i++) w->chi2_excluded[i] = NAN;
    for (int i = 0; i < N; i++) { // picks sharing a survey error (quadratic: N is tens)
        w->share[i] = 1;
        for (int j = 0; j < N && pb->survey_shared && pb->survey_shared[i] >= 0; j++)
            w->share[i] += j != i && pb->survey_shared[j] == pb->survey_shared[i];
    }
    w->scale_free = rs_calib__scale_free(pb, opt);
    const double log_theta0[RS_NOISE_NGROUPS] = {0, 0, 0};
    rs_calib__scale_sigmas(w, pb, log_theta0);

    // centred frame
    double c[3] = {0, 0, 0};
    for (int i = 0; i < N; i++)
        for (int k = 0; k < 3; k++) c[k] += pb->p_enu_m[3 * i + k] / N;
    for (int i = 0; i < N; i++)
        for (int k = 0; k < 3; k++) w->p_survey_c[3 * i + k] = pb->p_enu_m[3 * i + k] - c[k];
    memcpy(w->p_c, w->p_survey_c, (size_t)N * 3 * sizeof(double));

    // 1. initial pose
    memcpy(res->intrinsics, pb->camera->intrinsics, (size_t)Ni * sizeof(double));
    rs_calib_init_result init = {.method = "warm-start"};
    double scale = 1.0, rt_c[6];
    if (warm) {
        memcpy(rt_c, warm->rt_c, sizeof rt_c);
        memcpy(res->intrinsics, warm->intrinsics, (size_t)Ni * sizeof(double));
        memcpy(w->p_c, warm->p_c, (size_t)N * 3 * sizeof(double));
    } else {
        double *points_buffer = NULL;
        rs_calib_problem points; // the point landmarks alone: picks along poles and lines come later
        st = rs_calib__point_problem(&points, &points_buffer, pb, err);
        if (st == RS_OK) st = initial_pose(&init, res->intrinsics, &scale, &points, opt, Ni, err);
        free(points_buffer);
        if (st != RS_OK) {
            rs_err_prefix(err, "initial pose");
            return st;
        }
        rt_centred_from_enu(rt_c, init.rt_cam_enu, c);
    }
    rs_calib__along_choose(w, pb, c, rt_c, res->intrinsics);

    rs_calib_refine_problem rp = {.N = N,
                                  .p_survey_c_m = w->p_survey_c,
                                  .sigma_enu_m = pb->sigma_enu_m ? w->sigma_enu : NULL,
                                  .q_px = pb->q_px,
                                  .sigma_px = w->sigma_px,
                                  .use = w->use,
                                  .along_c = w->along_c,
                                  .s_along_m = w->s_along,
                                  .lensmodel = (&pb->camera->lensmodel),
                                  .intrinsics_nominal = pb->camera->intrinsics,
                                  .has_position_prior = pb->has_position_prior,
                                  .prior_sigma_m = pb->prior_sigma_m};
    for (int k = 0; k < 3; k++) rp.prior_position_c_m[k] = pb->prior_position_enu_m[k] - c[k];
    rs_calib_refine_options ro = {.refine = opt->refine,
                                  .robust_scale = opt->robust_scale,
                                  .max_iterations = opt->max_iterations,
                                  .focal_prior_rel_sigma = opt->focal_prior_rel_sigma,
                                  .center_prior_sigma_px = opt->center_prior_sigma_px,
                                  .distortion_prior_sigma = opt->distortion_prior_sigma,
                                  .covariance = false,
                                  .rough = true};
    rs_calib_refine_summary sum;
    for (int i = 0; i < N; i++) w->use[i] = true;
    int Noutliers = 0;
    char robust_desc[96] = "";

    // 2. robust solve on every landmark, with the scale taken from the data; 3. gross outliers
    double log_theta[RS_NOISE_NGROUPS] = {0, 0, 0};
    if (warm && warm->no_gross) { // the first solve found no gross outlier (rs_calib__warm)
        if (warm->log_theta) {
            memcpy(log_theta, warm->log_theta, sizeof log_theta);
            rs_calib__scale_sigmas(w, pb, log_theta);
        }
        rs_calib__along_choose(w, pb, c, rt_c, res->intrinsics);
        for (int i = 0; i < N; i++) res->w_test[i] = NAN;
    } else if (opt->robust_scale > 0.0) {
        st = rs_calib__robust_stage(&Noutliers, log_theta, rt_c, res, w, &rp, &ro, pb, opt, c,
                                    !warm && init.Ninliers == N, robust_desc, sizeof robust_desc, err);
        if (st != RS_OK) return st;
    }
    double rt_robust[6]; // the robust stage's solution (rs_calib__scale_free: the final solve's start)
    memcpy(rt_robust, rt_c, sizeof rt_robust);
    if (N - Noutliers < 4)
        return rs_err_set(err, RS_ERR_DEGENERATE,
                          "only %d of %d landmarks agree with one pose (the rest are outliers "
                          "beyond %g sigma): a pose needs at least 4",
                          N - Noutliers, N, opt->outlier_threshold);

    // 3b. variance components and data snooping (rs_calib_noise.h), alternating; their solves
    // need not be tight (the variance factors change by 1e-3 in the end): the final solve is
    ro.robust_scale = 0.0;
    ro.rough = true;
    if (opt->estimate_noise || opt->robust_scale > 0.0) {
        st = rs_calib__noise_model(res, w, &rp, &ro, rt_c, log_theta, &Noutliers, pb, opt, err);
        if (st != RS_OK) return st;
    }
    if (opt->estimate_noise) { // 3b'. the coarse test's rejections at the estimated noise
        st = rs_calib__readmit(res, w, &rp, &ro, rt_c, log_theta, &Noutliers, pb, opt, err);
        if (st != RS_OK) return st;
    }
    memcpy(w->log_theta, log_theta, sizeof log_theta);
    // 3c. the pose's covariance is built on the variance factors' posterior mode (where w's
    // sigmas are), spread over their posterior below. A group with little redundancy is not
    // estimated from the data: its posterior rests mostly on the prior, its stated sigma (kept
    // there rather than reset to the statement: on the real GNSS survey the reset made the
    // leave-one-out median of the sigma set 1.0 m / 0.3 m / 3 px 1.77 m instead of 1.53 m)
    if (opt->estimate_noise) rs_calib__scale_sigmas(w, pb, log_theta);

    // 4. the inliers, still under Cauchy's loss (now at the estimated noise: an M-estimate, each
    // landmark weighted by 1 / (1 + chi2 / a^2), res->weight), with the covariance. A landmark
    // seen only behind the camera is a blunder (rs_calib__reject_behind): it leaves (named in the
    // outlier warning), and the solve runs again (twice at most; then, or below 4, an error)
    // scale-free, the final solve starts from the robust stage's solution, a Cauchy M-estimate
    // like it, at a scale near the one estimated (harness, exact surveys: -5%); elsewhere from the
    // noise model's (on the bench's other problems the robust stage's took more evaluations)
    if (w->scale_free) memcpy(rt_c, rt_robust, sizeof rt_robust);
    ro.robust_scale = opt->robust_scale;
    ro.covariance = true;
    ro.rough = false;
    int Nbehind = 0;
    for (int pass = 0;; pass++) {
        st = rs_calib_refine_run(rt_c, res->intrinsics, w->p_c, &sum, w->cov, w->block_chi2, w->q_pred, &rp, &ro, err);
        if (st != RS_OK) {
            rs_err_prefix(err, "refinement");
            return st;
        }
        res->iterations += sum.iterations;
        int n = 0;
        st = rs_calib__reject_behind(&n, res, w, rt_c, N - Noutliers, pass == 2, err);
        if (st != RS_OK) return st;
        if (n == 0) break;
        Noutliers += n, Nbehind += n;
    }
    const int Ninl = N - Noutliers;
    w->Ngross = Noutliers - res->Nrejected_snooping;
    res->pose_dof = INFINITY; // the noise as stated: the pose's 99.9% region is chi-square 6 dof
    res->region_m2 = rs_calib__pose_region_m2(1e-3, INFINITY, 1.0);
    if (opt->estimate_noise && !warm) { // the covariance carries the variance factors' own uncertainty
        st = rs_calib__cov_spread(w, &rp, rt_c, res, log_theta, 6 + Ni, opt, err);
        if (st != RS_OK) return st;
    }

    if (!warm && (st = rs_calib__reliability(res, w, &rp, rt_c, log_theta, pb, opt, err)) != RS_OK) return st;
    // ---- hook: the intrinsics against the image (rs_calib_intrinsics.c) ----
    if (!warm && (st = rs_calib__intrinsics_check(res, w, &rp, rt_c, w->cov, user_refine, pb, opt, warn, err)) != RS_OK)
        return st;
    // ---- end hook ----

    // 5. outputs in ENU
    const int n = 6 + Ni;
    double J[36], cov_c[36];
    for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++) cov_c[a * 6 + b] = w->cov[a * n + b];
    normalise_r(rt_c, cov_c);
    rt_enu_from_centred(res->rt_cam_enu, J, rt_c, c);
    sandwich(res->covariance_rt_cam_enu, J, cov_c, 6, 6);
    for (int a = 0; a < Ni; a++) {
        for (int b = 0; b < Ni; b++) res->covariance_intrinsics[a * Ni + b] = w->cov[(6 + a) * n + 6 + b];
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
    if (!all_finite(res->covariance_rt_cam_enu, 36) || !all_finite(res->sigma_position_enu_m, 3) ||
        !all_finite(res->sigma_yaw_pitch_roll_deg, 3) || !all_finite(res->rt_cam_enu, 6))
        return rs_err_set(err, RS_ERR_DEGENERATE,
                          "the pose or its covariance is not finite: the landmarks do not "
                          "determine the pose");

    double sse = 0.0;
    for (int i = 0; i < N; i++) {
        res->inlier[i] = w->use[i];
        double seen[3], d[3];
        rs_calib__seen_point(seen, d, w->p_c, w->along_c, w->s_along, i);
        for (int k = 0; k < 3; k++) res->p_enu_refined_m[3 * i + k] = seen[k] + c[k];
        for (int k = 0; k < 2; k++) {
            res->predicted_px[2 * i + k] = w->q_pred[2 * i + k];
            res->residual_px[2 * i + k] = w->q_pred[2 * i + k] - pb->q_px[2 * i + k];
        }
        res->normalised_residual[i] = sqrt(w->block_chi2[i]);
        res->weight[i] = w->use[i] ? rs_calib_refine_weight(w->block_chi2[i], opt->robust_scale) : 0.0;
        if (w->use[i])
            sse += res->residual_px[2 * i] * res->residual_px[2 * i] +
                   res->residual_px[2 * i + 1] * res->residual_px[2 * i + 1];
    }
    res->Ninliers = Ninl;
    res->rms_px = sqrt(sse / Ninl);
    res->chi2 = sum.chi2;
    res->dof = sum.Nresiduals - sum.Nfree;
    res->variance_factor = res->dof > 0 ? sum.chi2 / res->dof : NAN;
    res->condition_number = sum.condition_number;
    char focal_desc[48] = "";
    if (scale != 1.0) snprintf(focal_desc, sizeof(focal_desc), " + focal-search(x%.3g)", scale);
    snprintf(res->method, sizeof(res->method), "%s%s%s + ceres-wls + covariance(absolute)", init.method, focal_desc,
             robust_desc);

    // a roadside camera looks down at its landmarks: one below them all looking up is the mirror
    // of the true pose (a pinhole projects points behind it too) or a sign of wrong heights
    double up_min = INFINITY;
    for (int i = 0; i < N; i++)
        if (w->use[i]) up_min = fmin(up_min, res->p_enu_refined_m[3 * i + 2]);
    if (res->position_enu_m[2] < up_min - 1.0 && res->yaw_pitch_roll_deg[1] > 0.0)
        return rs_err_set(err, RS_ERR_DEGENERATE,
                          "the solution has the camera %.3g m below every landmark, looking up (pitch %.3g deg): "
                          "a mirrored pose (points behind a camera project too) or landmark heights in another "
                          "datum; check the heights and the picks",
                          up_min - res->position_enu_m[2], res->yaw_pitch_roll_deg[1]);

    // 6. warnings in plain words
    if (Noutliers > 0) {
        char list[160] = "";
        size_t len = 0;
        for (int i = 0; i < N && len + 12 < sizeof(list); i++)
            if (!w->use[i]) len += (size_t)snprintf(list + len, sizeof(list) - len, "%s%d", len ? "," : "", i);
        char behind[64] = "";
        if (Nbehind > 0) snprintf(behind, sizeof behind, ", %d seen only behind the camera", Nbehind);
        warn(res, "%d of %d landmarks flagged as outliers and dropped (index %s; %d by data snooping%s)", Noutliers, N,
             list, res->Nrejected_snooping, behind);
    }
    if (res->condition_number > opt->condition_warn)
        warn(res,
             "weak geometry: condition number %.3g > %.3g (landmarks nearly collinear, bunched "
             "in a small part of the image, or too few): the pose is poorly determined, read "
             "the sigmas",
             res->condition_number, opt->condition_warn);
    const double *sy = res->sigma_yaw_pitch_roll_deg;
    const double sigma_rot_deg = fmax(sy[0], fmax(sy[1], sy[2]));
    if (opt->sigma_rotation_warn_deg > 0 && sigma_rot_deg > opt->sigma_rotation_warn_deg)
        warn(res,
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
            warn(res,
                 "%s noise estimated from the data at %.3g %s (+- %.2g, redundancy %.1f), %.2gx the stated %.3g %s: "
                 "the pose and its covariance use the estimate; state it next time",
                 group_name[g], n->estimated, unit[g], n->sigma_estimated, n->redundancy, ratio, n->stated, unit[g]);
    }
    if (res->noise_model_wrong)
        warn(res,
             "the noise model is wrong: data snooping would reject more than %.0f%% of the landmarks (%d of %d "
             "rejected, the rest kept): check the pixel picks and the survey's datum, heights and sigmas before "
             "trusting this pose",
             100 * opt->max_rejected_fraction, N - Ninl, N);
    if (res->dof > 0 && !opt->estimate_noise) {
        const double lo = chi2_quantile(res->dof, -2.576) / res->dof;
        const double hi = chi2_quantile(res->dof, 2.576) / res->dof;
        if (res->variance_factor > hi)
            warn(res,
                 "residuals larger than the stated sigmas allow (variance factor %.3g, 99%% "
                 "bound %.3g): sigma_px or the survey sigmas are optimistic, or a mistake "
                 "remains; the reported covariance is then too small",
                 res->variance_factor, hi);
        else if (res->variance_factor < lo)
            warn(res,
                 "residuals smaller than the stated sigmas suggest (variance factor %.3g, 99%% "
                 "bound %.3g): the sigmas are pessimistic; the reported covariance is too large",
                 res->variance_factor, lo);
    } else if (res->dof <= 0) {
        warn(res, "no redundancy (dof %d): the fit cannot be checked against the sigmas", res->dof);
    }
    if ((user_refine & RS_CALIB_REFINE_FOCAL) && res->sigma_intrinsics[0] > 0.05 * res->intrinsics[0])
        warn(res,
             "the focal length is poorly determined (sigma %.1f%%): the landmarks' depth "
             "range or their spread in the image is too small to separate it from the distance",
             100.0 * res->sigma_intrinsics[0] / res->intrinsics[0]);
    if (Ninl < 6) warn(res, "only %d inlying landmarks: little redundancy to catch a further mistake", Ninl);
    if (fabs(res->yaw_pitch_roll_deg[1]) > 89.0)
        warn(res, "camera looks nearly straight %s: yaw and roll are ill-defined",
             res->yaw_pitch_roll_deg[1] > 0 ? "up" : "down");
    if (pb->camera->width > 0 && pb->camera->height > 0) {
        double qmin[2] = {INFINITY, INFINITY}, qmax[2] = {-INFINITY, -INFINITY};
        for (int i = 0; i < N; i++)
            if (w->use[i])
                for (int k = 0; k < 2; k++) {
                    qmin[k] = fmin(qmin[k], pb->q_px[2 * i + k]);
                    qmax[k] = fmax(qmax[k], pb->q_px[2 * i + k]);
                }
        const double area = (qmax[0] - qmin[0]) * (qmax[1] - qmin[1]);
        if (area < 0.05 * pb->camera->width * pb->camera->height)
            warn(res,
                 "the inlying landmarks cover only %.1f%% of the image: the pose is "
                 "sensitive to their errors",
                 100.0 * area / (pb->camera->width * pb->camera->height));
    }
    return RS_OK;
}

static rs_status solve_timed(rs_calib_result *result, const rs_calib_problem *problem, const rs_calib_options *opt_in,
                             const rs_calib__warm *warm, rs_err *err)
{
    if (!result || !problem) return rs_err_set(err, RS_ERR_INVALID, "rs_calib_solve: NULL result or problem");
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    memset(result, 0, sizeof(*result));
    rs_calib_options opt;
    if (opt_in)
        opt = *opt_in;
    else
        rs_calib_options_default(&opt);
    const int Ni = problem->camera ? mrcal_lensmodel_num_params(&problem->camera->lensmodel) : 0;
    // ---- hook: intrinsics with a stated uncertainty become parameters (rs_calib_intrinsics.c) ----
    const unsigned user_refine = opt.refine;
    rs_status st = rs_calib__intrinsics_options(&opt, problem, err);
    if (st != RS_OK) return st;
    // ---- end hook ----
    rs_calib__work w = {0};
    st = solve(result, &w, problem, &opt, user_refine, Ni, warm, err);
    work_free(&w);
    if (st != RS_OK) {
        rs_calib_result_free(result);
        return st;
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    result->time_us = (double)(t1.tv_sec - t0.tv_sec) * 1e6 + (double)(t1.tv_nsec - t0.tv_nsec) * 1e-3;
    return RS_OK;
}

rs_status rs_calib_solve(rs_calib_result *result, const rs_calib_problem *problem, const rs_calib_options *opt,
                         rs_err *err)
{
    return solve_timed(result, problem, opt, NULL, err);
}

rs_status rs_calib__solve_warm(rs_calib_result *result, const rs_calib_problem *problem, const rs_calib_options *opt,
                               const rs_calib__warm *from, rs_err *err)
{
    if (!from || !from->rt_c || !from->intrinsics || !from->p_c)
        return rs_err_set(err, RS_ERR_INVALID, "rs_calib__solve_warm: NULL start");
    return solve_timed(result, problem, opt, from, err);
}

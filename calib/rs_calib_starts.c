// rs_calib_starts.c -- where a solve starts (calib/internal/rs_calib_starts.h): the initial pose
// with its threshold escalated, the focal search, the alternative starts of a focal nobody knows
// (every scale of the grid, the ground homography's decomposition) and the score that compares
// the solves from them. Calls rs_calib_init.h (the minimal and non-minimal solvers, and OpenCV's
// homography) and mrcal.
#include "calib/internal/rs_calib_starts.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mrcal/poseutils.h>

#include "core/rs_lens.h"
#include "core/rs_pose.h"

// The focal search's grid: quarter-octave steps over [focal_search_min, focal_search_max].
static int grid_size(const rs_calib_options *opt)
{
    return 1 + (int)ceil(4.0 * log2(opt->focal_search_max / opt->focal_search_min));
}

static double grid_scale(const rs_calib_options *opt, int k, int K)
{
    return opt->focal_search_min * pow(opt->focal_search_max / opt->focal_search_min, (double)k / (K - 1));
}

// pb's nominal intrinsics (Ni,) with the focal lengths times s, into out.
static void scaled(double *out, const rs_calib_problem *pb, int Ni, double s)
{
    memcpy(out, pb->camera->intrinsics, (size_t)Ni * sizeof(double));
    out[0] *= s;
    out[1] *= s;
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
        if (pc.z > 0.0 && rs_lens_project(&q, NULL, NULL, &pc, 1, (&pb->camera->lensmodel), intrinsics)) {
            const double dx = q.x - pb->q_px[2 * i], dy = q.y - pb->q_px[2 * i + 1];
            if (dx * dx + dy * dy < e2) e2 = dx * dx + dy * dy;
        }
        cost += e2;
    }
    return cost;
}

rs_status rs_calib__initial_pose(rs_calib_init_result *init, double *intrinsics, double *scale_out,
                                 const rs_calib_problem *pb, const rs_calib_options *opt, int Ni, rs_err *err)
{
    const bool search = (opt->refine & RS_CALIB_REFINE_FOCAL) && opt->focal_search_max > opt->focal_search_min;
    double T;
    *scale_out = 1.0;
    if (!search) return init_escalating(init, &T, intrinsics, pb, opt, err);
    const int K = grid_size(opt);
    const double T_score = 4.0 * (opt->init.ransac_threshold_px > 0.0 ? opt->init.ransac_threshold_px : 8.0);
    double best = INFINITY;
    rs_status last = RS_ERR_DEGENERATE;
    rs_err e_last = {RS_OK, ""};
    double *trial = malloc((size_t)Ni * sizeof(double));
    if (!trial) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int k = 0; k < K; k++) {
        const double s = grid_scale(opt, k, K);
        scaled(trial, pb, Ni, s);
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

// Whether start a is within 1 deg, 1% of its range and 10% of focal scale of start b.
static bool same_start(const rs_calib__start *a, const rs_calib__start *b, const double centroid[3])
{
    if (fabs(log(a->focal_scale / b->focal_scale)) > log(1.1)) return false;
    if (rs_pose_rotation_between(NULL, NULL, a->init.rt_cam_enu, b->init.rt_cam_enu) > 1.0 * M_PI / 180.0) return false;
    double pa[3], pb[3];
    rs_pose_position_from_rt(pa, NULL, a->init.rt_cam_enu);
    rs_pose_position_from_rt(pb, NULL, b->init.rt_cam_enu);
    const double range = hypot(hypot(pa[0] - centroid[0], pa[1] - centroid[1]), pa[2] - centroid[2]);
    return hypot(hypot(pa[0] - pb[0], pa[1] - pb[1]), pa[2] - pb[2]) <= 0.01 * range;
}

// The decomposition of the ground homography (rs_calib__starts) into *st. False when the
// bearings, the homography or its focal give none.
static bool homography_start(rs_calib__start *st, const rs_calib_problem *pb, const rs_calib_options *opt,
                             const double centroid[3], double *buf)
{
    const int N = pb->N;
    double *en = buf, *xy = buf + 2 * N;
    mrcal_point3_t *v = (mrcal_point3_t *)(buf + 4 * N);
    if (!rs_lens_unproject(v, (const mrcal_point2_t *)pb->q_px, N, &pb->camera->lensmodel, pb->camera->intrinsics))
        return false;
    int n = 0;
    for (int i = 0; i < N; i++) {
        if (!(v[i].z > 1e-6) || (pb->along && pb->along[i].Nvertices > 0)) continue;
        xy[2 * n] = v[i].x / v[i].z, xy[2 * n + 1] = v[i].y / v[i].z;
        en[2 * n] = pb->p_enu_m[3 * i] - centroid[0], en[2 * n + 1] = pb->p_enu_m[3 * i + 1] - centroid[1];
        n++;
    }
    double H[9];
    if (n < 4 || rs_calib_homography_fit(H, en, xy, n, NULL) != RS_OK) return false;
    // the image of the absolute conic: m_j = (h_jx / s, h_jy / s, h_jz) orthogonal and of one length
    const double *h = H; // columns h_j = (H[j], H[3 + j], H[6 + j])
    const double a1 = h[0] * h[1] + h[3] * h[4], b1 = h[6] * h[7];
    const double a2 = h[0] * h[0] + h[3] * h[3] - h[1] * h[1] - h[4] * h[4], b2 = h[6] * h[6] - h[7] * h[7];
    const double w = -(a1 * b1 + a2 * b2) / (a1 * a1 + a2 * a2); // 1 / s^2
    double s = w > 0.0 && isfinite(w) ? 1.0 / sqrt(w) : 1.0;
    if (!(s >= opt->focal_search_min && s <= opt->focal_search_max)) s = 1.0;
    double m[3][3]; // m[j] = column j with the focal undone
    for (int j = 0; j < 3; j++) m[j][0] = h[j] / s, m[j][1] = h[3 + j] / s, m[j][2] = h[6 + j];
    const double n1 = sqrt(m[0][0] * m[0][0] + m[0][1] * m[0][1] + m[0][2] * m[0][2]);
    const double n2 = sqrt(m[1][0] * m[1][0] + m[1][1] * m[1][1] + m[1][2] * m[1][2]);
    if (!(n1 > 0.0 && n2 > 0.0)) return false;
    const double lambda = (m[2][2] < 0.0 ? -2.0 : 2.0) / (n1 + n2); // the landmarks in front
    double r1[3], r2[3], r3[3], t[3];
    for (int i = 0; i < 3; i++) r1[i] = m[0][i] / n1 * (lambda > 0 ? 1 : -1), t[i] = lambda * m[2][i];
    double d = 0.0;
    for (int i = 0; i < 3; i++) d += lambda * m[1][i] * r1[i];
    for (int i = 0; i < 3; i++) r2[i] = lambda * m[1][i] - d * r1[i];
    const double n2o = sqrt(r2[0] * r2[0] + r2[1] * r2[1] + r2[2] * r2[2]);
    if (!(n2o > 0.0)) return false;
    for (int i = 0; i < 3; i++) r2[i] /= n2o;
    r3[0] = r1[1] * r2[2] - r1[2] * r2[1], r3[1] = r1[2] * r2[0] - r1[0] * r2[2], r3[2] = r1[0] * r2[1] - r1[1] * r2[0];
    const double R[9] = {r1[0], r2[0], r3[0], r1[1], r2[1], r3[1], r1[2], r2[2], r3[2]};
    double rt[6], Rc[3];
    rs_pose_r_from_R(rt, R);
    mrcal_rotate_point_r(Rc, NULL, NULL, rt, centroid);
    for (int i = 0; i < 3; i++) rt[3 + i] = t[i] - Rc[i];
    for (int i = 0; i < 6; i++)
        if (!isfinite(rt[i])) return false;
    *st = (rs_calib__start){.init = {.Ninliers = n, .planar = true, .rms_px = NAN}, .focal_scale = s};
    memcpy(st->init.rt_cam_enu, rt, sizeof rt);
    snprintf(st->init.method, sizeof st->init.method, "ground-homography start(f x%.3g)", s);
    return true;
}

// The twin of a start whose camera is below the landmarks' centroid (a road camera never is): for
// (nearly) planar landmarks seen from afar, the image hardly tells a plane tilted one way from one
// tilted the other (IPPE's two-fold ambiguity): the pose reflected through the plane across the
// line of sight v to the centroid, with the landmarks reflected through their own (horizontal)
// plane to keep the rotation proper: R' = (I - 2 v v^T) R S0, S0 = diag(1, 1, -1), t' = c_cam - R' c.
// The camera comes out above. False when in's camera is not below.
static bool twin_start(rs_calib__start *out, const rs_calib__start *in, const double centroid[3])
{
    double C[3], R[9], c_cam[3];
    rs_pose_position_from_rt(C, NULL, in->init.rt_cam_enu);
    if (!(C[2] < centroid[2])) return false;
    mrcal_R_from_r(R, NULL, in->init.rt_cam_enu);
    mrcal_transform_point_rt(c_cam, NULL, NULL, in->init.rt_cam_enu, centroid);
    const double d = sqrt(c_cam[0] * c_cam[0] + c_cam[1] * c_cam[1] + c_cam[2] * c_cam[2]);
    if (!(d > 0.0)) return false;
    const double v[3] = {c_cam[0] / d, c_cam[1] / d, c_cam[2] / d};
    double R2[9], rt[6];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double x = 0.0; // ((I - 2 v v^T) R)[i][j]
            for (int k = 0; k < 3; k++) x += ((i == k) - 2.0 * v[i] * v[k]) * R[3 * k + j];
            R2[3 * i + j] = j == 2 ? -x : x; // times S0
        }
    rs_pose_r_from_R(rt, R2);
    double Rc[3];
    mrcal_rotate_point_r(Rc, NULL, NULL, rt, centroid);
    for (int i = 0; i < 3; i++) rt[3 + i] = c_cam[i] - Rc[i];
    *out = *in;
    out->twin = true;
    memcpy(out->init.rt_cam_enu, rt, sizeof rt);
    const size_t len = strlen(out->init.method);
    snprintf(out->init.method + len, sizeof out->init.method - len, " (its twin above)");
    return true;
}

// Adds *c to starts unless one of them is the same (same_start).
static void add_start(rs_calib__start *starts, int *Nstarts, int max, const rs_calib__start *c,
                      const double centroid[3])
{
    for (int j = 0; j < *Nstarts; j++)
        if (same_start(c, &starts[j], centroid)) return;
    if (*Nstarts < max) starts[(*Nstarts)++] = *c;
}

rs_status rs_calib__starts(rs_calib__start *starts, int *Nstarts, int max, const rs_calib_problem *pb,
                           const rs_calib_options *opt, int Ni, rs_err *err)
{
    *Nstarts = 0;
    const int N = pb->N, K = grid_size(opt);
    double centroid[3] = {0, 0, 0};
    for (int i = 0; i < N; i++)
        for (int j = 0; j < 3; j++) centroid[j] += pb->p_enu_m[3 * i + j] / N;
    double *buf = malloc(((size_t)Ni + 7 * (size_t)(N > 0 ? N : 1)) * sizeof(double));
    if (!buf) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    bool planar = false;
    for (int k = 0; k < K; k++) {
        rs_calib__start c = {.focal_scale = grid_scale(opt, k, K)};
        double T;
        scaled(buf, pb, Ni, c.focal_scale);
        if (init_escalating(&c.init, &T, buf, pb, opt, NULL) != RS_OK) continue;
        planar = planar || c.init.planar;
        add_start(starts, Nstarts, max, &c, centroid);
    }
    rs_calib__start c;
    if (planar && homography_start(&c, pb, opt, centroid, buf)) add_start(starts, Nstarts, max, &c, centroid);
    for (int k = 0, n = *Nstarts; k < n; k++) // the twins of those below
        if (twin_start(&c, &starts[k], centroid)) add_start(starts, Nstarts, max, &c, centroid);
    free(buf);
    return RS_OK;
}

double rs_calib__score(const double rt_cam_enu[6], const double *intrinsics, const rs_calib_problem *pb,
                       const rs_calib_options *opt)
{
    const double a2 = opt->robust_scale * opt->robust_scale;
    rs_pose_prepared pose;
    rs_pose_prepare(&pose, rt_cam_enu);
    double score = 0.0;
    for (int i = 0; i < pb->N; i++) {
        if (pb->along && pb->along[i].Nvertices > 0) continue;
        mrcal_point3_t pc, dq_dpc[2];
        mrcal_point2_t q;
        double dpc_dp[9];
        rs_pose_prepared_apply(pc.xyz, NULL, dpc_dp, &pose, &pb->p_enu_m[3 * i]);
        double chi2 = 1e4;
        if (pc.z > 0.0 && rs_lens_project(&q, dq_dpc, NULL, &pc, 1, &pb->camera->lensmodel, intrinsics)) {
            // C = sigma_px^2 I + J diag(sigma_enu^2) J^T, J = dq/dp_enu (2,3)
            const double sp = pb->sigma_px ? pb->sigma_px[i] : 1.0;
            double C[3] = {sp * sp, 0.0, sp * sp}; // C00, C01, C11
            for (int k = 0; k < 3 && pb->sigma_enu_m; k++) {
                const double sk = pb->sigma_enu_m[3 * i + k];
                double J[2] = {0, 0};
                for (int l = 0; l < 3; l++) J[0] += dq_dpc[0].xyz[l] * dpc_dp[3 * l + k];
                for (int l = 0; l < 3; l++) J[1] += dq_dpc[1].xyz[l] * dpc_dp[3 * l + k];
                C[0] += sk * sk * J[0] * J[0], C[1] += sk * sk * J[0] * J[1], C[2] += sk * sk * J[1] * J[1];
            }
            const double ex = q.x - pb->q_px[2 * i], ey = q.y - pb->q_px[2 * i + 1];
            const double det = C[0] * C[2] - C[1] * C[1];
            const double c2 = (C[2] * ex * ex - 2.0 * C[1] * ex * ey + C[0] * ey * ey) / det;
            if (det > 0.0 && isfinite(c2)) chi2 = fmin(c2, 1e4);
        }
        score += a2 > 0.0 ? a2 * log1p(chi2 / a2) : chi2;
    }
    return score;
}

void rs_calib__ground_fit(rs_calib_result *res, const rs_calib_problem *pb)
{
    const int N = pb->N;
    res->Nground_fit = 0;
    double *buf = malloc(7 * (size_t)(N > 0 ? N : 1) * sizeof(double));
    if (!buf) return;
    double *q = buf, *en = buf + 2 * N;
    mrcal_point3_t *v = (mrcal_point3_t *)(buf + 4 * N);
    int n = 0;
    for (int i = 0; i < N; i++) {
        if (!res->inlier[i] || (pb->along && pb->along[i].Nvertices > 0)) continue;
        memcpy(&q[2 * n], &pb->q_px[2 * i], 2 * sizeof(double));
        memcpy(&en[2 * n], &pb->p_enu_m[3 * i], 2 * sizeof(double));
        n++;
    }
    const double *k = res->intrinsics; // fx, fy, cx, cy
    bool ok = n >= 4 && rs_lens_unproject(v, (const mrcal_point2_t *)q, n, &pb->camera->lensmodel, k);
    for (int j = 0; ok && j < n; j++) {
        ok = v[j].z > 0.0;
        q[2 * j] = k[0] * v[j].x / v[j].z + k[2], q[2 * j + 1] = k[1] * v[j].y / v[j].z + k[3];
    }
    double *H = res->H_ground_from_px_fit;
    if (ok && rs_calib_homography_fit(H, q, en, n, NULL) == RS_OK) {
        double sse = 0.0;
        for (int j = 0; j < n; j++) {
            const double *p = &q[2 * j];
            const double w = H[6] * p[0] + H[7] * p[1] + H[8];
            const double de = (H[0] * p[0] + H[1] * p[1] + H[2]) / w - en[2 * j];
            const double dn = (H[3] * p[0] + H[4] * p[1] + H[5]) / w - en[2 * j + 1];
            sse += de * de + dn * dn;
        }
        res->Nground_fit = n;
        res->sigma_ground_fit_m = n > 4 ? sqrt(sse / (2 * n - 8)) : NAN;
    }
    free(buf);
}

// rs_audit.c -- one camera's audit: leave-one-out, influence, outlier reasons, coverage,
// degeneracy, the ground uncertainty map, the moved-camera test, external calibrations. See
// rs_audit.h for the method.
#include "audit/rs_audit.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mrcal/poseutils.h>

#include "audit/internal/rs_audit_internal.h"
#include "audit/internal/rs_audit_opencv.h"
#include "core/rs_camera_ground.h"
#include "core/rs_lens.h"
#include "core/rs_pose.h"
#include "core/rs_stats.h"
#include "core/rs_units.h"

void rs_audit_options_default(rs_audit_options *opt)
{
    memset(opt, 0, sizeof *opt);
    rs_calib_options_default(&opt->calib);
    opt->need_ground_m = 1;
    opt->max_rms_surveyed_px = 0; // 0: derived from need_ground_m
    opt->max_loo_px = 0;
    opt->max_loo_m = 0;
    opt->max_ground_sigma_m = 0;
    opt->detection_sigma_px = 1;
    opt->range_m = 100;
    opt->cell_m = 1;
    opt->alpha = 0.001;
    opt->consistency_px = 0.5;
    opt->leave_one_out = true;
    opt->map = true;
}

static rs_status check_options(const rs_audit_options *o, rs_err *err)
{
    const struct {
        const char *name;
        double v;
    } pos[] = {{"need_ground_m", o->need_ground_m},
               {"detection_sigma_px", o->detection_sigma_px},
               {"range_m", o->range_m},
               {"cell_m", o->cell_m},
               {"consistency_px", o->consistency_px}};
    for (size_t i = 0; i < sizeof pos / sizeof pos[0]; i++)
        if (!(pos[i].v > 0 && isfinite(pos[i].v)))
            return rs_err_set(err, RS_ERR_INVALID, "audit options: %s = %g: must be > 0", pos[i].name, pos[i].v);
    const double derivable[] = {o->max_rms_surveyed_px, o->max_loo_px, o->max_loo_m, o->max_ground_sigma_m};
    for (size_t i = 0; i < sizeof derivable / sizeof derivable[0]; i++)
        if (!(derivable[i] >= 0 && isfinite(derivable[i])))
            return rs_err_set(err, RS_ERR_INVALID,
                              "audit options: a max_ threshold is %g: must be >= 0 (0: derived "
                              "from need_ground_m)",
                              derivable[i]);
    if (!(o->alpha > 0 && o->alpha < 1))
        return rs_err_set(err, RS_ERR_INVALID, "audit options: alpha = %g: must be in (0, 1)", o->alpha);
    if (o->range_m / o->cell_m > 4000)
        return rs_err_set(err, RS_ERR_INVALID, "audit options: range_m / cell_m = %g: at most 4000 cells across",
                          o->range_m / o->cell_m);
    return RS_OK;
}

// Appends "; "-separated printf text to a fixed buffer (truncating).
__attribute__((format(printf, 3, 4))) static void append(char *buf, size_t size, const char *fmt, ...)
{
    size_t n = strlen(buf);
    if (n + 3 >= size) return;
    if (n) {
        strcpy(buf + n, "; ");
        n += 2;
    }
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf + n, size - n, fmt, ap);
    va_end(ap);
}

// ---- small geometry ----

// rms_surveyed_px (rs_audit.h): each landmark's SURVEYED position projected through (lm,
// intrinsics, rt) minus its pick into residual_px (N,2; NaN where it does not project); returns
// the RMS over the inliers (NaN when none projects), and the largest such error in *max_px (NaN
// likewise).
static double surveyed_residuals(double *residual_px, double *max_px, const rs_calib_problem *pb,
                                 const mrcal_lensmodel_t *lm, const double *intrinsics, const double rt[6],
                                 const bool *inlier)
{
    double ss = 0, worst = 0;
    int c = 0;
    rs_camera cam = *pb->camera; // a view: lens, these intrinsics and pose
    cam.lensmodel = *lm;
    cam.intrinsics = (double *)intrinsics;
    memcpy(cam.rt_cam_enu, rt, sizeof cam.rt_cam_enu);
    for (int i = 0; i < pb->N; i++) {
        double q[2], p[3], *res = &residual_px[2 * i];
        if (!rs_calib_problem_seen_point(p, q, pb, i, &cam)) { // along a pole or line: its nearest point
            res[0] = res[1] = NAN;
            continue;
        }
        res[0] = q[0] - pb->q_px[2 * i];
        res[1] = q[1] - pb->q_px[2 * i + 1];
        if (!inlier[i]) continue;
        const double e = hypot(res[0], res[1]);
        ss += e * e;
        if (e > worst) worst = e;
        c++;
    }
    if (max_px) *max_px = c ? worst : NAN;
    return c ? sqrt(ss / c) : NAN;
}

// The pixel size of one metre of ground at the inlier landmarks (rs_audit_result.px_per_m): at
// each, J (2,2) = d(pixel)/d(E, N) along the ground plane n (central differences of 5 cm), and
// the median of sqrt(|det J|) (the geometric mean of J's singular values: foreshortening counts
// half). NaN when no landmark projects.
static double pixels_per_metre(const rs_calib_problem *pb, const double n[3], const rs_calib_result *s)
{
    double *v = malloc((size_t)(pb->N > 0 ? pb->N : 1) * sizeof *v);
    if (!v) return NAN;
    int c = 0;
    const double h = 0.05;
    const rs_camera cal = rs_calib_result_camera(pb->camera, s);
    const double max_tan = rs_camera_max_tan(&cal);
    for (int i = 0; i < pb->N; i++) {
        if (!s->inlier[i]) continue;
        double J[2][2];
        bool ok = true;
        for (int k = 0; k < 2 && ok; k++) {
            // a step east (k = 0) or north (k = 1) with the up change that keeps it on the plane
            double d[3] = {k == 0 ? h : 0, k == 1 ? h : 0, 0}, pp[3], pm[3], qp[2], qm[2];
            d[2] = -(n[0] * d[0] + n[1] * d[1]) / n[2];
            for (int j = 0; j < 3; j++) pp[j] = pb->p_enu_m[3 * i + j] + d[j], pm[j] = pb->p_enu_m[3 * i + j] - d[j];
            ok = rs_camera_project_visible(qp, &cal, max_tan, pp) && rs_camera_project_visible(qm, &cal, max_tan, pm);
            if (ok) J[0][k] = (qp[0] - qm[0]) / (2 * h), J[1][k] = (qp[1] - qm[1]) / (2 * h);
        }
        if (ok) v[c++] = sqrt(fabs(J[0][0] * J[1][1] - J[0][1] * J[1][0]));
    }
    const double med = rs_stats_median(v, c);
    free(v);
    return med;
}

// ---- degeneracy ----

static rs_status compute_degeneracy(rs_audit_result *r, const rs_calib_problem *pb, const rs_audit_options *opt,
                                    rs_err *err)
{
    const rs_calib_result *s = &r->solve;
    int N = pb->N, Nin = 0;
    double c[3] = {0};
    for (int i = 0; i < N; i++)
        if (s->inlier[i]) {
            for (int k = 0; k < 3; k++) c[k] += pb->p_enu_m[3 * i + k];
            Nin++;
        }
    r->condition_number = s->condition_number;
    r->collinearity = r->planarity = r->head_on_deg = NAN;
    if (Nin >= 3) {
        double *p = malloc((size_t)Nin * 3 * sizeof *p);
        if (!p) return rs_err_set(err, RS_ERR_NOMEM, "degeneracy: out of memory");
        for (int k = 0; k < 3; k++) c[k] /= Nin;
        for (int i = 0, j = 0; i < N; i++)
            if (s->inlier[i]) {
                for (int k = 0; k < 3; k++) p[3 * j + k] = pb->p_enu_m[3 * i + k] - c[k];
                j++;
            }
        double sv[3], Vt[9];
        rs_status st = rs_audit_opencv_principal_axes3(sv, Vt, p, Nin, err);
        free(p);
        if (st) return st;
        if (sv[0] > 0) {
            r->collinearity = sv[1] / sv[0];
            r->planarity = sv[2] / sv[0];
            double d[3] = {c[0] - s->position_enu_m[0], c[1] - s->position_enu_m[1], c[2] - s->position_enu_m[2]};
            double dn = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            double dot = fabs(Vt[6] * d[0] + Vt[7] * d[1] + Vt[8] * d[2]) / dn;
            r->head_on_deg = acos(dot > 1 ? 1 : dot) * RS_DEG_PER_RAD;
        }
    }
    char *w = r->warnings;
    size_t ws = sizeof r->warnings;
    if (s->warnings[0]) append(w, ws, "%s", s->warnings);
    if (isfinite(r->condition_number) && r->condition_number > opt->calib.condition_warn)
        append(w, ws,
               "condition number %.0f: the pose is poorly determined by these landmarks (well-spread "
               "scenes give 1.5-10)",
               r->condition_number);
    if (r->collinearity < 0.1)
        append(w, ws,
               "the landmarks lie nearly on a line (spread across it only %.0f%% of that along it): the "
               "rotation about that line is weakly determined",
               100 * r->collinearity);
    if (r->image_hull_share < 0.15 && !strstr(s->warnings, "of the image")) // the solver's is at 5%
        append(w, ws,
               "the landmarks cover only %.0f%% of the image: they are clustered, and errors grow away "
               "from them",
               100 * r->image_hull_share);
    if (r->planarity < 0.05 && r->head_on_deg < 25)
        append(w, ws,
               "the landmarks are nearly planar and seen almost head-on (%.0f deg from the plane's "
               "normal): distance and focal length trade off",
               r->head_on_deg);
    if (r->ground_hull_share < 0.1)
        append(w, ws,
               "the landmarks span only %.0f%% of the ground the camera sees within %g m: vehicles "
               "located outside them are extrapolated",
               100 * r->ground_hull_share, opt->range_m);
    if (s->variance_factor > 4)
        append(w, ws, "variance factor %.1f: the residuals are larger than the stated pixel and survey sigmas",
               s->variance_factor);
    return RS_OK;
}

// The left-out landmark's prediction error in sigmas (rs_audit.h, loo_normalised): d = q_pred -
// q_obs with S = s_px^2 I + Jp diag(s_enu^2) Jp^T + Jrt C_rt Jrt^T. NaN when S is singular.
static double loo_sigmas(const mrcal_lensmodel_t *lm, const double *intrinsics, const double rt[6],
                         const double C_rt[36], const double p[3], const double s_enu[3], double s_px,
                         const double d[2])
{
    double pc[3], dpc_drt[18], dpc_dp[9];
    mrcal_transform_point_rt(pc, dpc_drt, dpc_dp, rt, p);
    mrcal_point2_t q;
    mrcal_point3_t dq_dpc[2];
    if (!rs_lens_project(&q, dq_dpc, NULL, (const mrcal_point3_t *)pc, 1, lm, intrinsics)) return NAN;
    double Jp[6] = {0}, Jr[12] = {0};
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 3; j++) {
            for (int k = 0; k < 3; k++) Jp[3 * i + k] += dq_dpc[i].xyz[j] * dpc_dp[3 * j + k];
            for (int k = 0; k < 6; k++) Jr[6 * i + k] += dq_dpc[i].xyz[j] * dpc_drt[6 * j + k];
        }
    double S[4] = {s_px * s_px, 0, 0, s_px * s_px};
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2; j++) {
            for (int k = 0; k < 3; k++) S[2 * i + j] += Jp[3 * i + k] * s_enu[k] * s_enu[k] * Jp[3 * j + k];
            for (int a = 0; a < 6; a++)
                for (int b = 0; b < 6; b++) S[2 * i + j] += Jr[6 * i + a] * C_rt[6 * a + b] * Jr[6 * j + b];
        }
    double det = S[0] * S[3] - S[1] * S[2];
    if (!(det > 0)) return NAN;
    return sqrt((S[3] * d[0] * d[0] - (S[1] + S[2]) * d[0] * d[1] + S[0] * d[1] * d[1]) / det);
}

// ---- sub-problems (leave-one-out, new picks) ----

// Some of a problem's landmarks, in arrays of its own.
typedef struct {
    rs_calib_problem pb;      // points into buf, along and shared
    double *buf;              // owned
    int *index;               // (pb.N,) owned: the landmark's index in the original problem
    rs_calib_polyline *along; // (pb.N,) owned: the original's (picks along poles and lines)
    int *shared;              // (pb.N,) owned: the original's survey_shared
} subset;

static rs_status subset_alloc(subset *s, int N, rs_err *err)
{
    memset(s, 0, sizeof *s);
    const size_t n = (size_t)(N > 0 ? N : 1);
    s->buf = malloc(n * 9 * sizeof *s->buf);
    s->index = malloc(n * sizeof *s->index);
    s->along = malloc(n * sizeof *s->along);
    s->shared = malloc(n * sizeof *s->shared);
    if (!s->buf || !s->index || !s->along || !s->shared) return rs_err_set(err, RS_ERR_NOMEM, "audit: out of memory");
    return RS_OK;
}

static void subset_free(subset *s)
{
    free(s->buf);
    free(s->index);
    free(s->along);
    free(s->shared);
}

// The landmarks of `from` except `skip` (-1: none) and those whose pixel in q_px is NaN, with
// the pixels q_px, sigma_px (NULL: from's own).
static void subset_fill(subset *s, const rs_calib_problem *from, int skip, const double *q_px, const double *sigma_px)
{
    const int N = from->N;
    double *p = s->buf, *sp = p + 3 * N, *q = sp + 3 * N, *sq = q + 2 * N;
    if (!q_px) q_px = from->q_px, sigma_px = from->sigma_px;
    int k = 0;
    for (int i = 0; i < N; i++) {
        if (i == skip || !isfinite(q_px[2 * i]) || !isfinite(q_px[2 * i + 1])) continue;
        memcpy(&p[3 * k], &from->p_enu_m[3 * i], 3 * sizeof(double));
        for (int c = 0; c < 3; c++) sp[3 * k + c] = from->sigma_enu_m ? from->sigma_enu_m[3 * i + c] : 0;
        memcpy(&q[2 * k], &q_px[2 * i], 2 * sizeof(double));
        sq[k] = sigma_px ? sigma_px[i] : 1;
        if (from->along) s->along[k] = from->along[i];
        if (from->survey_shared) s->shared[k] = from->survey_shared[i];
        s->index[k++] = i;
    }
    s->pb = *from;
    s->pb.along = from->along ? s->along : NULL;
    s->pb.survey_shared = from->survey_shared ? s->shared : NULL;
    s->pb.N = k;
    s->pb.p_enu_m = p;
    s->pb.sigma_enu_m = sp;
    s->pb.q_px = q;
    s->pb.sigma_px = sq;
}

// ---- leave-one-out ----

static rs_status leave_one_out(rs_audit_result *r, const rs_calib_problem *pb, const double n[3],
                               const rs_audit_options *opt, rs_err *err)
{
    const int N = pb->N;
    subset sub;
    rs_status sst = subset_alloc(&sub, N, err);
    if (sst) {
        subset_free(&sub);
        return sst;
    }
    for (int i = 0; i < N; i++) {
        rs_audit_landmark *L = &r->landmarks[i];
        subset_fill(&sub, pb, i, NULL, NULL);
        rs_calib_result lr;
        rs_status st = rs_calib_solve(&lr, &sub.pb, &opt->calib, NULL);
        const double *qi = &pb->q_px[2 * i];
        double g[3], pi[3]; // its surveyed point (along a pole or a line: the nearest one)
        const rs_camera loo_cam = rs_calib_result_camera(pb->camera, &lr);
        L->loo_ok =
            st == RS_OK && rs_calib_problem_seen_point(pi, L->loo_predicted_px, pb, i, &loo_cam) &&
            rs_camera_locate_ground(g, &loo_cam, qi, n, n[0] * pi[0] + n[1] * pi[1] + n[2] * pi[2], NULL) == RS_OK;
        if (L->loo_ok) {
            L->loo_error_px = hypot(L->loo_predicted_px[0] - qi[0], L->loo_predicted_px[1] - qi[1]);
            L->loo_ground_error_m = rs_audit__dist3(g, pi);
            const double s_enu[3] = {pb->sigma_enu_m ? pb->sigma_enu_m[3 * i] : 0,
                                     pb->sigma_enu_m ? pb->sigma_enu_m[3 * i + 1] : 0,
                                     pb->sigma_enu_m ? pb->sigma_enu_m[3 * i + 2] : 0};
            const double d[2] = {L->loo_predicted_px[0] - qi[0], L->loo_predicted_px[1] - qi[1]};
            L->loo_normalised = loo_sigmas(&pb->camera->lensmodel, lr.intrinsics, lr.rt_cam_enu,
                                           lr.covariance_rt_cam_enu, pi, s_enu, pb->sigma_px ? pb->sigma_px[i] : 1, d);
            L->influence_m = rs_audit__dist3(lr.position_enu_m, r->solve.position_enu_m);
            L->influence_deg =
                rs_pose_rotation_between(NULL, NULL, lr.rt_cam_enu, r->solve.rt_cam_enu) * RS_DEG_PER_RAD;
        }
        rs_calib_result_free(&lr);
    }
    subset_free(&sub);

    // summary over the inliers
    double *m = malloc((size_t)(N > 0 ? N : 1) * sizeof *m);
    if (!m) return rs_err_set(err, RS_ERR_NOMEM, "leave-one-out: out of memory");
    double ss = 0;
    int c = 0;
    r->loo_max_px = r->loo_max_m = 0;
    for (int i = 0; i < N; i++) {
        const rs_audit_landmark *L = &r->landmarks[i];
        if (!L->inlier || !L->loo_ok) continue;
        ss += L->loo_error_px * L->loo_error_px;
        if (L->loo_error_px > r->loo_max_px) r->loo_max_px = L->loo_error_px;
        if (L->loo_ground_error_m > r->loo_max_m) r->loo_max_m = L->loo_ground_error_m;
        m[c++] = L->loo_ground_error_m;
    }
    r->loo_count = c;
    r->loo_rms_px = c ? sqrt(ss / c) : NAN;
    r->loo_median_m = rs_stats_median(m, c);
    if (!c) r->loo_max_px = r->loo_max_m = NAN;
    // influence relative to the others
    int ci = 0;
    for (int i = 0; i < N; i++)
        if (r->landmarks[i].loo_ok) m[ci++] = r->landmarks[i].influence_m;
    const double med_inf = rs_stats_median(m, ci);
    free(m);
    for (int i = 0; i < N; i++) {
        rs_audit_landmark *L = &r->landmarks[i];
        if (!L->inlier || !L->loo_ok) continue;
        if (L->loo_normalised > opt->calib.outlier_threshold)
            append(L->reason, sizeof L->reason,
                   "the others predict its pixel %.1f px away, %.1f sigma (limit %.2f): "
                   "its pick or survey disagrees with the rest",
                   L->loo_error_px, L->loo_normalised, opt->calib.outlier_threshold);
        if (ci >= 5 && L->influence_m > 5 * med_inf && L->influence_m > 0.1)
            append(L->reason, sizeof L->reason,
                   "leaving it out moves the camera %.2f m (%.1f x the median): the "
                   "pose leans on it",
                   L->influence_m, L->influence_m / med_inf);
    }
    return RS_OK;
}

// ---- chi-square ----

// P(chi2_{2m} > T) = exp(-T/2) sum_{k<m} (T/2)^k / k! (exact for even degrees of freedom).
static double chi2_even_sf(double T, int m)
{
    double x = T / 2, term = 1, sum = 1;
    for (int k = 1; k < m; k++) {
        term *= x / k;
        sum += term;
        if (term < 1e-300) break;
    }
    // in logs: exp(-x) underflows long before the sum overflows
    double lg = -x + log(sum);
    return lg < -745 ? 0 : exp(lg);
}

// ---- the moved-camera test ----

static void ypr_diff(double d[3], const double a[6], const double b[6])
{
    double ya[3], yb[3];
    rs_pose_ypr_from_rt(ya, NULL, a);
    rs_pose_ypr_from_rt(yb, NULL, b);
    for (int k = 0; k < 3; k++) {
        d[k] = ya[k] - yb[k];
        if (k != 1) d[k] = remainder(d[k], 360.0);
    }
}

static rs_status against_test(rs_audit_result *r, const rs_calib_problem *pb, const double *q_new, const double *s_new,
                              const double rt_stored[6], const rs_audit_options *opt, rs_err *err)
{
    rs_audit_against *a = &r->against;
    const int N = pb->N;
    for (int i = 0; i < N; i++)
        if (isfinite(q_new[2 * i]) && s_new && !(s_new[i] > 0 && isfinite(s_new[i])))
            return rs_err_set(err, RS_ERR_INVALID, "new picks: landmark %d: sigma_px = %g: must be > 0", i, s_new[i]);
    subset sub;
    rs_status st = subset_alloc(&sub, N, err);
    if (st) goto done;
    subset_fill(&sub, pb, -1, q_new, s_new);
    const int k = sub.pb.N, *idx = sub.index;
    const double *q = sub.pb.q_px, *sq = sub.pb.sigma_px;
    rs_calib_result nr;
    st = rs_calib_solve(&nr, &sub.pb, &opt->calib, err);
    if (st) {
        rs_err_prefix(err, "the new picks");
        rs_calib_result_free(&nr);
        goto done;
    }
    memcpy(a->rt_cam_enu_new, nr.rt_cam_enu, sizeof a->rt_cam_enu_new);
    double T = 0, ss = 0;
    int M = 0;
    for (int j = 0; j < k; j++) {
        int i = idx[j];
        if (!nr.inlier[j] || !r->solve.inlier[i]) continue;
        double so = pb->sigma_px ? pb->sigma_px[i] : 1;
        double du = q[2 * j] - pb->q_px[2 * i], dv = q[2 * j + 1] - pb->q_px[2 * i + 1];
        T += (du * du + dv * dv) / (so * so + sq[j] * sq[j]);
        ss += du * du + dv * dv;
        M++;
    }
    double pos_stored[3];
    rs_pose_position_from_rt(pos_stored, NULL, rt_stored);
    rs_calib_result_free(&nr);
    if (M < 3) {
        st = rs_err_set(err, RS_ERR_DEGENERATE,
                        "the new picks share only %d usable landmarks with the old ones "
                        "(at least 3 are needed)",
                        M);
        goto done;
    }
    a->M = M;
    a->chi2 = T;
    a->dof = 2 * M;
    a->p_value = chi2_even_sf(T, M);
    a->moved = a->p_value < opt->alpha;
    a->rms_shift_px = sqrt(ss / M);
    a->rotation_deg = rs_pose_rotation_between(NULL, NULL, a->rt_cam_enu_new, rt_stored) * RS_DEG_PER_RAD;
    double pos_new[3];
    rs_pose_position_from_rt(pos_new, NULL, a->rt_cam_enu_new);
    for (int c = 0; c < 3; c++) a->shift_enu_m[c] = pos_new[c] - pos_stored[c];
    a->shift_m = rs_audit__dist3(pos_new, pos_stored);
    ypr_diff(a->dyaw_pitch_roll_deg, a->rt_cam_enu_new, rt_stored);
    snprintf(a->message, sizeof a->message,
             "%s: the %d re-picked landmarks moved %.2f px RMS (chi2 %.1f on %d dof, p = %.2g, alpha %g); "
             "estimated rotation %.3f deg, shift %.3f m",
             a->moved ? "MOVED" : "not moved", M, a->rms_shift_px, T, a->dof, a->p_value, opt->alpha, a->rotation_deg,
             a->shift_m);
    r->has_against = true;
done:
    subset_free(&sub);
    return st;
}

// ---- an external calibration ----

static void external_check(rs_audit_result *r, const rs_calib_problem *pb, const rs_audit_calibration *cal,
                           const rs_audit_options *opt)
{
    rs_audit_external *x = &r->external;
    const int N = pb->N;
    x->rms_surveyed_px = surveyed_residuals(x->residual_surveyed_px, &x->max_px, pb, &cal->camera.lensmodel,
                                            cal->camera.intrinsics, cal->camera.rt_cam_enu, r->solve.inlier);
    x->rotation_deg =
        rs_pose_rotation_between(NULL, NULL, cal->camera.rt_cam_enu, r->solve.rt_cam_enu) * RS_DEG_PER_RAD;
    double pos[3];
    rs_pose_position_from_rt(pos, NULL, cal->camera.rt_cam_enu);
    x->shift_m = rs_audit__dist3(pos, r->solve.position_enu_m);

    // the parts: R a rotation, P ~ K [R | t]
    double R[9];
    if (cal->extra.has_R)
        memcpy(R, cal->extra.R_cam_enu, sizeof R);
    else
        mrcal_R_from_r(R, NULL, cal->camera.rt_cam_enu);
    x->R_orthonormality = 0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double d = -(i == j);
            for (int k = 0; k < 3; k++) d += R[3 * k + i] * R[3 * k + j];
            x->R_orthonormality += d * d;
        }
    x->R_orthonormality = sqrt(x->R_orthonormality);
    x->consistency[0] = '\0';
    if (x->R_orthonormality > 1e-6)
        append(x->consistency, sizeof x->consistency, "R is not a rotation matrix (|R^T R - I| = %.2g)",
               x->R_orthonormality);
    x->P_max_px = x->P_scale = NAN;
    if (cal->extra.has_P) {
        const double *I = cal->camera.intrinsics; // fx fy cx cy
        const double K[9] = {I[0], 0, I[2], 0, I[1], I[3], 0, 0, 1};
        const double *t = &cal->camera.rt_cam_enu[3];
        double KRt[12] = {0};
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 4; j++)
                for (int k = 0; k < 3; k++) KRt[4 * i + j] += K[3 * i + k] * (j < 3 ? R[3 * k + j] : t[k]);
        double num = 0, den = 0;
        for (int i = 0; i < 12; i++) num += cal->extra.P[i] * KRt[i], den += KRt[i] * KRt[i];
        x->P_scale = den > 0 ? num / den : NAN;
        x->P_max_px = 0;
        for (int i = 0; i < N; i++) {
            const double *pe = &pb->p_enu_m[3 * i];
            double a[3], b[3];
            for (int row = 0; row < 3; row++) {
                a[row] = cal->extra.P[4 * row + 3];
                b[row] = KRt[4 * row + 3];
                for (int k = 0; k < 3; k++)
                    a[row] += cal->extra.P[4 * row + k] * pe[k], b[row] += KRt[4 * row + k] * pe[k];
            }
            double d = hypot(a[0] / a[2] - b[0] / b[2], a[1] / a[2] - b[1] / b[2]);
            if (!isfinite(d)) d = INFINITY;
            if (d > x->P_max_px) x->P_max_px = d;
        }
        if (!(x->P_max_px <= opt->consistency_px))
            append(x->consistency, sizeof x->consistency,
                   "the projection matrix P disagrees with K [R | t]: the landmarks land up to %.3g px apart "
                   "(limit %g px)",
                   x->P_max_px, opt->consistency_px);
    }
    if (cal->camera.width > 0 && cal->camera.height > 0 && pb->camera->width > 0 &&
        (cal->camera.width != pb->camera->width || cal->camera.height != pb->camera->height))
        append(x->consistency, sizeof x->consistency, "its image size %dx%d differs from the site camera's %dx%d",
               cal->camera.width, cal->camera.height, pb->camera->width, pb->camera->height);
    x->consistent = x->consistency[0] == '\0';
}

// ---- the audit ----

void rs_audit_result_free(rs_audit_result *r)
{
    if (!r) return;
    rs_calib_result_free(&r->solve);
    free(r->landmarks);
    free(r->map.sigma_m);
    free(r->external.residual_surveyed_px);
    memset(r, 0, sizeof *r);
}

rs_status rs_audit_camera(rs_audit_result *r, const rs_calib_problem *problem, const double ground_normal_enu[3],
                          double ground_offset_m, const double *q_new_px, const double *sigma_new_px,
                          const rs_audit_calibration *external, const rs_audit_options *opt, rs_err *err)
{
    memset(r, 0, sizeof *r);
    rs_audit_options defaults;
    if (!opt) {
        rs_audit_options_default(&defaults);
        opt = &defaults;
    }
    rs_status st = check_options(opt, err);
    if (st == RS_OK) st = rs_camera_ground_check_plane(ground_normal_enu, err);
    if (st) return st;
    rs_calib_problem pb = *problem;
    rs_camera external_nominal; // the external lens and intrinsics, the site camera's image size
    if (external) {
        external_nominal = external->camera;
        external_nominal.width = problem->camera->width;
        external_nominal.height = problem->camera->height;
        pb.camera = &external_nominal;
    }
    const int N = pb.N;
    st = rs_calib_solve(&r->solve, &pb, &opt->calib, err);
    if (st) return st;
    r->N = N;
    r->landmarks = calloc((size_t)(N > 0 ? N : 1), sizeof *r->landmarks);
    double *res_surveyed = malloc((size_t)(N > 0 ? N : 1) * 2 * sizeof *res_surveyed);
    if (!r->landmarks || !res_surveyed) {
        free(res_surveyed);
        return rs_err_set(err, RS_ERR_NOMEM, "audit: out of memory");
    }
    r->rms_surveyed_px = surveyed_residuals(res_surveyed, NULL, &pb, &pb.camera->lensmodel, r->solve.intrinsics,
                                            r->solve.rt_cam_enu, r->solve.inlier);
    for (int i = 0; i < N; i++) {
        rs_audit_landmark *L = &r->landmarks[i];
        L->inlier = r->solve.inlier[i];
        memcpy(L->residual_surveyed_px, &res_surveyed[2 * i], sizeof L->residual_surveyed_px);
        memcpy(L->residual_adjusted_px, &r->solve.residual_px[2 * i], sizeof L->residual_adjusted_px);
        L->normalised_residual = r->solve.normalised_residual[i];
        L->loo_predicted_px[0] = L->loo_predicted_px[1] = NAN;
        L->loo_error_px = L->loo_normalised = L->loo_ground_error_m = L->influence_m = L->influence_deg = NAN;
        if (!L->inlier)
            snprintf(L->reason, sizeof L->reason,
                     "normalised residual %.1f sigma > %.2f: dropped as an outlier (a wrong pick or survey point)",
                     L->normalised_residual, opt->calib.outlier_threshold);
    }
    free(res_surveyed);
    if (opt->leave_one_out && (st = leave_one_out(r, &pb, ground_normal_enu, opt, err))) return st;
    if (opt->map && (st = rs_audit__compute_map(r, &pb, ground_normal_enu, ground_offset_m, opt, err))) return st;
    if ((st = rs_audit__compute_coverage(r, &pb, err))) return st;
    if ((st = compute_degeneracy(r, &pb, opt, err))) return st;
    if (external) {
        r->has_external = true;
        r->external.residual_surveyed_px = malloc((size_t)(N > 0 ? N : 1) * 2 * sizeof(double));
        if (!r->external.residual_surveyed_px) return rs_err_set(err, RS_ERR_NOMEM, "audit: out of memory");
        external_check(r, &pb, external, opt);
        r->rms_surveyed_px = r->external.rms_surveyed_px; // the calibration audited is the external one
    }
    if (q_new_px && (st = against_test(r, &pb, q_new_px, sigma_new_px,
                                       external ? external->camera.rt_cam_enu : r->solve.rt_cam_enu, opt, err)))
        return st;

    // the thresholds: those not given derive from what the site needs on the ground
    r->px_per_m = pixels_per_metre(&pb, ground_normal_enu, &r->solve);
    const double need = opt->need_ground_m;
    const double need_px = isfinite(r->px_per_m) ? need * r->px_per_m : INFINITY; // nothing to derive from
    r->thresholds.need_ground_m = need;
    r->thresholds.max_rms_surveyed_px = opt->max_rms_surveyed_px > 0 ? opt->max_rms_surveyed_px : need_px;
    r->thresholds.max_loo_px = opt->max_loo_px > 0 ? opt->max_loo_px : need_px;
    r->thresholds.max_loo_m = opt->max_loo_m > 0 ? opt->max_loo_m : need;
    r->thresholds.max_ground_sigma_m = opt->max_ground_sigma_m > 0 ? opt->max_ground_sigma_m : need;
    const double max_rms = r->thresholds.max_rms_surveyed_px, max_loo_px = r->thresholds.max_loo_px;

    // the verdict
    char *f = r->failures;
    size_t fs = sizeof r->failures;
    // one rule, on the headline: the surveyed positions through the calibration audited
    if (!(r->rms_surveyed_px <= max_rms))
        append(f, fs, "the inliers' surveyed positions reproject %.2f px off (RMS) through %s > %.3g px",
               r->rms_surveyed_px, r->has_external ? "the calibration" : "the audit's solve", max_rms);
    if (r->loo_count && !(r->loo_rms_px <= max_loo_px))
        append(f, fs, "leave-one-out RMS %.2f px > %.3g px", r->loo_rms_px, max_loo_px);
    if (r->loo_count && r->loo_median_m > r->thresholds.max_loo_m)
        append(f, fs, "leave-one-out median ground error %.2f m > %g m", r->loo_median_m, r->thresholds.max_loo_m);
    if (isfinite(r->ground_sigma_inside_p90_m) && r->ground_sigma_inside_p90_m > r->thresholds.max_ground_sigma_m)
        append(f, fs, "predicted ground error %.2f m (1 sigma, 90th percentile where the landmarks are) > %g m",
               r->ground_sigma_inside_p90_m, r->thresholds.max_ground_sigma_m);
    if (r->has_against && r->against.moved)
        append(f, fs, "the camera has moved (%.3f deg, %.3f m)", r->against.rotation_deg, r->against.shift_m);
    if (r->has_external && !r->external.consistent)
        append(f, fs, "the external calibration is inconsistent: %s", r->external.consistency);
    if (opt->leave_one_out && r->loo_count == 0)
        append(f, fs,
               "no leave-one-out re-solve succeeded (too few landmarks): the calibration cannot be "
               "cross-checked");
    r->pass = f[0] == '\0';
    return RS_OK;
}

// rs_audit_ground.c -- where a camera puts a vehicle on the ground and how well: the ground
// uncertainty of a pixel or a ground point (rs_audit_ground_sigma, _at), the uncertainty map over
// the ground a camera sees, and the coverage of its landmarks in the image and on the ground.
// See rs_audit.h (Method) for the propagation.
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <mrcal/poseutils.h>

#include "audit/internal/rs_audit_internal.h"
#include "audit/internal/rs_audit_opencv.h"
#include "audit/rs_audit.h"
#include "core/rs_lens.h"
#include "core/rs_stats.h"

double rs_audit__dist3(const double *a, const double *b)
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

// ---- ground uncertainty (rs_audit.h, Method) ----

// Cov(g) of the ground point p (on the plane) seen by the camera; false if degenerate.
static bool ground_cov(double cov[4], double q_out[2], const mrcal_lensmodel_t *lm, const double *intrinsics,
                       const double rt[6], const double C_rt[36], const double p[3], double sigma_px, const double n[3])
{
    double pc[3], dpc_drt[18], dpc_dp[9];
    mrcal_transform_point_rt(pc, dpc_drt, dpc_dp, rt, p);
    if (!(pc[2] > 0)) return false;
    mrcal_point2_t q;
    mrcal_point3_t dq_dpc[2];
    if (!rs_lens_project(&q, dq_dpc, NULL, (const mrcal_point3_t *)pc, 1, lm, intrinsics)) return false;
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
    double M[4] = {sigma_px * sigma_px, 0, 0, sigma_px * sigma_px}; // B C B^T + s^2 I
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
    return isfinite(cov[0]) && isfinite(cov[3]);
}

rs_status rs_audit__check_plane(const double n[3], rs_err *err)
{
    if (!(isfinite(n[0]) && isfinite(n[1]) && isfinite(n[2])) || !(fabs(n[2]) > 1e-9))
        return rs_err_set(err, RS_ERR_INVALID, "ground plane normal (%g, %g, %g): must be finite and not vertical",
                          n[0], n[1], n[2]);
    return RS_OK;
}

rs_status rs_audit_ground_sigma(double *sigma_m, double *cov_en_m2, double p_enu_m[3], const rs_camera *cam,
                                const double covariance_rt[36], const double q_px[2], double detection_sigma_px,
                                const double ground_normal_enu[3], double ground_offset_m, rs_err *err)
{
    *sigma_m = NAN;
    rs_status st = rs_audit__check_plane(ground_normal_enu, err);
    if (st) return st;
    double p[3], cov[4];
    st = rs_camera_locate_ground(p, cam, q_px, ground_normal_enu, ground_offset_m, err);
    if (st) return st;
    if (!ground_cov(cov, NULL, &cam->lensmodel, cam->intrinsics, cam->rt_cam_enu, covariance_rt, p, detection_sigma_px,
                    ground_normal_enu))
        return rs_err_set(err, RS_ERR_DEGENERATE, "pixel (%g, %g): the ground point's covariance is undefined", q_px[0],
                          q_px[1]);
    *sigma_m = sqrt(cov[0] + cov[3]);
    if (cov_en_m2) memcpy(cov_en_m2, cov, sizeof cov);
    if (p_enu_m) memcpy(p_enu_m, p, sizeof p);
    return RS_OK;
}

static void plane_point(double p[3], const double en[2], const double n[3], double offset)
{
    p[0] = en[0];
    p[1] = en[1];
    p[2] = (offset - n[0] * en[0] - n[1] * en[1]) / n[2];
}

rs_status rs_audit_ground_sigma_at(double *sigma_m, const rs_camera *cam, const double covariance_rt[36],
                                   const double en_m[2], double detection_sigma_px, const double ground_normal_enu[3],
                                   double ground_offset_m, rs_err *err)
{
    *sigma_m = NAN;
    rs_status st = rs_audit__check_plane(ground_normal_enu, err);
    if (st) return st;
    double p[3], cov[4], q[2];
    plane_point(p, en_m, ground_normal_enu, ground_offset_m);
    if (!ground_cov(cov, q, &cam->lensmodel, cam->intrinsics, cam->rt_cam_enu, covariance_rt, p, detection_sigma_px,
                    ground_normal_enu))
        return RS_OK;
    if (!(q[0] >= -0.5 && q[0] <= cam->width - 0.5 && q[1] >= -0.5 && q[1] <= cam->height - 0.5)) return RS_OK;
    // the projection of a far point can fold back into the image: keep it only if the
    // pixel's ray really comes back to it
    double back[3];
    if (rs_camera_locate_ground(back, cam, q, ground_normal_enu, ground_offset_m, NULL) ||
        rs_audit__dist3(back, p) > 1e-3 * (1 + rs_audit__dist3(p, (double[3]){0, 0, 0})))
        return RS_OK;
    *sigma_m = sqrt(cov[0] + cov[3]);
    return RS_OK;
}

// ---- the map and coverage ----

rs_status rs_audit__compute_map(rs_audit_result *r, const rs_calib_problem *pb, const double n[3], double offset,
                                const rs_audit_options *opt, rs_err *err)
{
    rs_audit_map *m = &r->map;
    const rs_calib_result *s = &r->solve;
    const double *C = s->position_enu_m;
    const double cell = opt->cell_m, range = opt->range_m;
    int half = (int)ceil(range / cell);
    int nfull = 2 * half + 1;
    double *full = malloc((size_t)nfull * (size_t)nfull * sizeof *full);
    if (!full) return rs_err_set(err, RS_ERR_NOMEM, "uncertainty map: out of memory");
    double e0 = C[0] - half * cell, n0 = C[1] - half * cell;
    const rs_camera cal = rs_calib_result_camera(pb->camera, s);
    int xmin = nfull, xmax = -1, ymin = nfull, ymax = -1;
    for (int iy = 0; iy < nfull; iy++)
        for (int ix = 0; ix < nfull; ix++) {
            double en[2] = {e0 + ix * cell, n0 + iy * cell}, sig = NAN;
            double dE = en[0] - C[0], dN = en[1] - C[1];
            if (dE * dE + dN * dN <= range * range)
                rs_audit_ground_sigma_at(&sig, &cal, s->covariance_rt_cam_enu, en, opt->detection_sigma_px, n, offset,
                                         NULL);
            full[iy * nfull + ix] = sig;
            if (isfinite(sig)) {
                if (ix < xmin) xmin = ix;
                if (ix > xmax) xmax = ix;
                if (iy < ymin) ymin = iy;
                if (iy > ymax) ymax = iy;
            }
        }
    if (xmax < 0) xmin = xmax = ymin = ymax = half; // sees no ground: one NaN cell
    m->nx = xmax - xmin + 1;
    m->ny = ymax - ymin + 1;
    m->sigma_m = malloc((size_t)m->nx * (size_t)m->ny * sizeof *m->sigma_m);
    if (!m->sigma_m) {
        free(full);
        return rs_err_set(err, RS_ERR_NOMEM, "uncertainty map: out of memory");
    }
    for (int iy = 0; iy < m->ny; iy++)
        memcpy(&m->sigma_m[iy * m->nx], &full[(ymin + iy) * nfull + xmin], (size_t)m->nx * sizeof(double));
    free(full);
    m->e0_m = e0 + xmin * cell;
    m->n0_m = n0 + ymin * cell;
    m->cell_m = cell;
    m->detection_sigma_px = opt->detection_sigma_px;
    m->range_m = range;
    m->camera_en_m[0] = C[0];
    m->camera_en_m[1] = C[1];
    return RS_OK;
}

// Image hull share, and the ground hull share over the map's seen cells.
rs_status rs_audit__compute_coverage(rs_audit_result *r, const rs_calib_problem *pb, rs_err *err)
{
    const int N = pb->N;
    double *xy = calloc((size_t)(N > 0 ? N : 1) * 4, sizeof *xy), *en = xy + 2 * (N > 0 ? N : 1);
    if (!xy) return rs_err_set(err, RS_ERR_NOMEM, "coverage: out of memory");
    int Nin = 0;
    for (int i = 0; i < N; i++)
        if (r->solve.inlier[i]) {
            memcpy(&xy[2 * Nin], &pb->q_px[2 * i], 2 * sizeof(double));
            memcpy(&en[2 * Nin], &pb->p_enu_m[3 * i], 2 * sizeof(double));
            Nin++;
        }
    double area = 0;
    rs_status st = rs_audit_opencv_convex_hull(&area, NULL, xy, Nin, NULL, 0, err);
    r->image_hull_share =
        pb->camera->width > 0 && pb->camera->height > 0 ? area / ((double)pb->camera->width * pb->camera->height) : NAN;
    r->ground_seen_m2 = NAN;
    r->ground_hull_share = NAN;
    r->ground_sigma_inside_median_m = r->ground_sigma_inside_p90_m = NAN;
    const rs_audit_map *m = &r->map;
    for (int i = 0; i < N; i++) { // each landmark's predicted sigma (nearest cell) and distance
        const double *p = &pb->p_enu_m[3 * i];
        rs_audit_landmark *L = &r->landmarks[i];
        L->sigma_ground_m = NAN;
        L->distance_m = hypot(p[0] - r->solve.position_enu_m[0], p[1] - r->solve.position_enu_m[1]);
        if (!m->sigma_m) continue;
        long ix = lround((p[0] - m->e0_m) / m->cell_m), iy = lround((p[1] - m->n0_m) / m->cell_m);
        if (ix >= 0 && iy >= 0 && ix < m->nx && iy < m->ny) L->sigma_ground_m = m->sigma_m[iy * m->nx + ix];
    }
    if (st == RS_OK && m->sigma_m) {
        int ncell = m->nx * m->ny, nseen = 0;
        double *cells = malloc((size_t)ncell * 2 * sizeof *cells);
        unsigned char *inside = malloc((size_t)ncell);
        if (!cells || !inside) st = rs_err_set(err, RS_ERR_NOMEM, "coverage: out of memory");
        for (int k = 0; st == RS_OK && k < ncell; k++)
            if (isfinite(m->sigma_m[k])) {
                cells[2 * nseen] = m->e0_m + (k % m->nx) * m->cell_m;
                cells[2 * nseen + 1] = m->n0_m + (k / m->nx) * m->cell_m;
                nseen++;
            }
        if (st == RS_OK) st = rs_audit_opencv_convex_hull(&area, inside, en, Nin, cells, nseen, err);
        if (st == RS_OK) {
            int nin = 0;
            for (int k = 0; k < nseen; k++) nin += inside[k];
            r->ground_seen_m2 = nseen * m->cell_m * m->cell_m;
            r->ground_hull_share = nseen ? (double)nin / nseen : 0;
            // the predicted sigma where the landmarks are: cells[] is reused for the values
            int c = 0;
            for (int k = 0, j = 0; k < ncell; k++)
                if (isfinite(m->sigma_m[k])) {
                    if (inside[j]) cells[c++] = m->sigma_m[k];
                    j++;
                }
            if (c) {
                rs_stats_sort(cells, c);
                r->ground_sigma_inside_median_m = rs_stats_median_sorted(cells, c);
                r->ground_sigma_inside_p90_m = rs_stats_quantile_sorted(cells, c, 0.9);
            }
        }
        free(cells);
        free(inside);
    }
    free(xy);
    return st;
}

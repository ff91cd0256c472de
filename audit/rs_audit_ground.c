// rs_audit_ground.c -- where a camera puts a vehicle on the ground and how well: the ground
// uncertainty of a pixel or a ground point (rs_audit_ground_sigma, _at), the uncertainty map over
// the ground a camera sees, and the coverage of its landmarks in the image and on the ground.
// See rs_audit.h (Method) for the propagation.
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "audit/internal/rs_audit_internal.h"
#include "audit/internal/rs_audit_opencv.h"
#include "audit/rs_audit.h"
#include "core/rs_camera_ground.h"
#include "core/rs_stats.h"

double rs_audit__dist3(const double *a, const double *b)
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

// ---- ground uncertainty (rs_audit.h, Method; the propagation is core/rs_camera_ground.h's) ----

rs_status rs_audit_ground_sigma(double *sigma_m, double *cov_en_m2, double p_enu_m[3], const rs_camera *cam,
                                const double covariance_rt[36], const double q_px[2], double detection_sigma_px,
                                const double ground_normal_enu[3], double ground_offset_m, rs_err *err)
{
    *sigma_m = NAN;
    const double s2 = detection_sigma_px * detection_sigma_px, cov_q[4] = {s2, 0, 0, s2};
    double p[3], cov[4];
    rs_status st =
        rs_camera_ground_locate(p, cov, cam, covariance_rt, q_px, cov_q, ground_normal_enu, ground_offset_m, err);
    if (st) return st;
    *sigma_m = sqrt(cov[0] + cov[3]);
    if (cov_en_m2) memcpy(cov_en_m2, cov, sizeof cov);
    if (p_enu_m) memcpy(p_enu_m, p, sizeof p);
    return RS_OK;
}

rs_status rs_audit_ground_sigma_at(double *sigma_m, const rs_camera *cam, const double covariance_rt[36],
                                   const double en_m[2], double detection_sigma_px, const double ground_normal_enu[3],
                                   double ground_offset_m, rs_err *err)
{
    *sigma_m = NAN;
    rs_status st = rs_camera_ground_check_plane(ground_normal_enu, err);
    if (st) return st;
    const double s2 = detection_sigma_px * detection_sigma_px, cov_q[4] = {s2, 0, 0, s2};
    double cov[4], q[2];
    if (!rs_camera_ground_covariance_at(cov, q, cam, covariance_rt, en_m, cov_q, ground_normal_enu, ground_offset_m))
        return RS_OK;
    if (!(q[0] >= -0.5 && q[0] <= cam->width - 0.5 && q[1] >= -0.5 && q[1] <= cam->height - 0.5)) return RS_OK;
    // the projection of a far point can fold back into the image: keep it only if the
    // pixel's ray really comes back to it
    const double *n = ground_normal_enu;
    const double p[3] = {en_m[0], en_m[1], (ground_offset_m - n[0] * en_m[0] - n[1] * en_m[1]) / n[2]};
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

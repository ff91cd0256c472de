// rs_calib_along.c -- landmarks picked anywhere along a pole or a line (rs_calib_polyline,
// docs/calibration.md "Poles and lines"): their checks, the point landmarks the initial pose is
// made from, and the segment each pick is on.
//
// Method. A pick along a polyline is a landmark seen at p + s d: p a point of the segment the pick
// is on, held to the survey by the landmark's sigmas like any point, d the segment's direction and
// s free (rs_calib_refine.h). The pixel residual then has no component along the projected
// segment (s takes it up): it is the pick's distance to the projected line, as a 1-dof
// observation, and the survey error along the segment does not matter. Which segment, and p on
// it, are chosen here from the pose at hand: the point of each segment nearest the pick's viewing
// ray (closest points of two lines, the segment's parameter clamped to [0, 1]), the segment whose
// point projects nearest the pick. rs_calib.c chooses after the initial pose and rs_calib_robust.c again
// after the robust solve. A polyline's corners are thereby linearised per segment; the survey errors of
// picks along the same line are taken as independent (they share the line's vertices: a
// simplification that matters only where the survey sigma rivals the pixel's footprint).
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <mrcal/mrcal.h>
#include <mrcal/poseutils.h>

#include "calib/internal/rs_calib_along.h"
#include "calib/internal/rs_calib_solve_state.h"
#include "calib/rs_calib.h"
#include "core/rs_lens.h"
#include "core/rs_pose.h"

bool rs_calib__is_along(const rs_calib_problem *pb, int i) { return pb->along && pb->along[i].Nvertices > 0; }

rs_status rs_calib__along_validate(int *Npoints, const rs_calib_problem *pb, rs_err *err)
{
    *Npoints = pb->N;
    if (!pb->along) return RS_OK;
    for (int i = 0; i < pb->N; i++) {
        const rs_calib_polyline *l = &pb->along[i];
        if (l->Nvertices == 0) continue;
        (*Npoints)--;
        if (l->Nvertices < 2 || !l->p_enu_m)
            return rs_err_set(err, RS_ERR_INVALID, "landmark %d: along: %d vertices: a polyline needs 2 or more", i,
                              l->Nvertices);
        for (int v = 0; v < l->Nvertices; v++) {
            const double *a = &l->p_enu_m[3 * v];
            if (!isfinite(a[0]) || !isfinite(a[1]) || !isfinite(a[2]))
                return rs_err_set(err, RS_ERR_INVALID, "landmark %d: along: vertex %d: not finite", i, v);
            if (v > 0 && a[0] == a[-3] && a[1] == a[-2] && a[2] == a[-1])
                return rs_err_set(err, RS_ERR_INVALID, "landmark %d: along: vertices %d and %d coincide", i, v - 1, v);
        }
    }
    return RS_OK;
}

rs_status rs_calib__point_problem(rs_calib_problem *sub, double **buffer, const rs_calib_problem *pb, rs_err *err)
{
    *sub = *pb;
    *buffer = NULL;
    if (!pb->along) return RS_OK;
    double *b = malloc((size_t)(pb->N > 0 ? pb->N : 1) * 9 * sizeof(double));
    if (!b) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    double *p = b, *q = b + 3 * pb->N, *sp = b + 5 * pb->N, *se = b + 6 * pb->N;
    int n = 0;
    for (int i = 0; i < pb->N; i++) {
        if (rs_calib__is_along(pb, i)) continue;
        memcpy(&p[3 * n], &pb->p_enu_m[3 * i], 3 * sizeof(double));
        memcpy(&q[2 * n], &pb->q_px[2 * i], 2 * sizeof(double));
        sp[n] = pb->sigma_px ? pb->sigma_px[i] : 1.0;
        for (int k = 0; k < 3; k++) se[3 * n + k] = pb->sigma_enu_m ? pb->sigma_enu_m[3 * i + k] : 0.0;
        n++;
    }
    sub->N = n;
    sub->p_enu_m = p;
    sub->q_px = q;
    sub->sigma_px = sp;
    sub->sigma_enu_m = se;
    sub->along = NULL;
    *buffer = b;
    return RS_OK;
}

// The point of segment a + t u (t in [0, 1]) nearest the ray o + lambda r (lambda >= 0): t.
static double nearest_on_segment(const double o[3], const double r[3], const double a[3], const double u[3])
{
    double w[3], uu = 0, ur = 0, rr = 0, uw = 0, rw = 0;
    for (int k = 0; k < 3; k++) w[k] = a[k] - o[k];
    for (int k = 0; k < 3; k++) {
        uu += u[k] * u[k], ur += u[k] * r[k], rr += r[k] * r[k];
        uw += u[k] * w[k], rw += r[k] * w[k];
    }
    // minimise |w + t u - lambda r|^2: [uu -ur; -ur rr] [t; lambda] = [-uw; rw]
    const double det = uu * rr - ur * ur;
    double t = det > 1e-12 * uu * rr ? (-uw * rr + ur * rw) / det : -uw / uu; // parallel: nearest to o
    t = fmin(1.0, fmax(0.0, t));
    return t;
}

void rs_calib__along_choose(rs_calib_solve_state *s)
{
    const rs_calib_problem *pb = s->pb;
    const double *c = s->centroid_enu_m, *rt_c = s->rt_c, *intrinsics = s->res->intrinsics;
    if (!pb->along) return;
    const mrcal_lensmodel_t *lm = &pb->camera->lensmodel;
    double C[3], R[9];
    rs_pose_position_from_rt(C, NULL, rt_c);
    mrcal_R_from_r(R, NULL, rt_c);
    for (int i = 0; i < pb->N; i++) {
        if (!rs_calib__is_along(pb, i)) continue;
        const rs_calib_polyline *l = &pb->along[i];
        mrcal_point3_t v_cam;
        const mrcal_point2_t q = {.x = pb->q_px[2 * i], .y = pb->q_px[2 * i + 1]};
        double ray[3] = {0, 0, 0}; // R' v: the pick's viewing direction in the centred frame
        const bool have_ray = rs_lens_unproject(&v_cam, &q, 1, lm, intrinsics);
        for (int k = 0; k < 3 && have_ray; k++)
            ray[k] = R[k] * v_cam.xyz[0] + R[3 + k] * v_cam.xyz[1] + R[6 + k] * v_cam.xyz[2];
        double best = INFINITY, best_p[3], best_d[3];
        for (int v = 0; v + 1 < l->Nvertices; v++) {
            double a[3], u[3], len = 0;
            for (int k = 0; k < 3; k++) {
                a[k] = l->p_enu_m[3 * v + k] - c[k];
                u[k] = l->p_enu_m[3 * v + 3 + k] - l->p_enu_m[3 * v + k];
                len += u[k] * u[k];
            }
            len = sqrt(len);
            const double t = have_ray ? nearest_on_segment(C, ray, a, u) : 0.5;
            double p[3], pc[3];
            for (int k = 0; k < 3; k++) p[k] = a[k] + t * u[k];
            mrcal_transform_point_rt(pc, NULL, NULL, rt_c, p);
            mrcal_point2_t qp;
            double e = INFINITY;
            if (pc[2] > 0 && rs_lens_project(&qp, NULL, NULL, (const mrcal_point3_t *)pc, 1, lm, intrinsics))
                e = hypot(qp.x - q.x, qp.y - q.y);
            if (e < best || (v == 0 && !isfinite(best))) {
                best = e;
                for (int k = 0; k < 3; k++) best_p[k] = p[k], best_d[k] = u[k] / len;
            }
        }
        memcpy(&s->p_survey_c[3 * i], best_p, sizeof best_p);
        memcpy(&s->p_c[3 * i], best_p, sizeof best_p);
        memcpy(&s->along_c[3 * i], best_d, sizeof best_d);
        s->s_along[i] = 0.0;
    }
}

bool rs_calib_problem_seen_point(double p_enu_m[3], double q_px[2], const rs_calib_problem *pb, int i,
                                 const rs_camera *cam)
{
    if (rs_calib__is_along(pb, i))
        return rs_camera_nearest_on_polyline(p_enu_m, q_px, cam, pb->along[i].p_enu_m, pb->along[i].Nvertices,
                                             &pb->q_px[2 * i]);
    memcpy(p_enu_m, &pb->p_enu_m[3 * i], 3 * sizeof(double));
    if (rs_camera_project(q_px, cam, p_enu_m, 1) == 1) return true;
    q_px[0] = q_px[1] = NAN;
    return false;
}

// rs_calib_noise.c -- redundancy numbers, variance components and reliability of one camera's
// adjustment (calib/internal/rs_calib_noise.h has the model and the references).
#include "calib/internal/rs_calib_noise.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <mrcal/poseutils.h>

#include "calib/internal/rs_calib_opencv.h"
#include "calib/rs_calib.h"
#include "core/rs_lens.h"
#include "core/rs_pose.h"

void rs_calib__camera_params(rs_calib__params *pp, const rs_calib_noise_state *s)
{
    memset(pp, 0, sizeof *pp);
    pp->Ni = mrcal_lensmodel_num_params(s->lensmodel);
    rs_pose_prepare(&pp->pose, s->rt_cam_c);
    for (int k = 0; k < 6; k++) pp->kind[pp->nc++] = -1;
    if (s->refine & RS_CALIB_REFINE_FOCAL) {
        pp->prior_w[pp->nc] = s->focal_prior_rel_sigma > 0 ? 1.0 / s->focal_prior_rel_sigma : 0.0;
        pp->kind[pp->nc++] = -2;
    }
    if (s->refine & RS_CALIB_REFINE_CENTER)
        for (int j = 2; j < 4; j++) {
            pp->prior_w[pp->nc] = s->center_prior_sigma_px > 0 ? 1.0 / s->center_prior_sigma_px : 0.0;
            pp->kind[pp->nc++] = j;
        }
    if (s->refine & RS_CALIB_REFINE_DISTORTION)
        for (int j = 4; j < pp->Ni && pp->nc < RS_NOISE_NC_MAX; j++) {
            pp->prior_w[pp->nc] = s->distortion_prior_sigma > 0 ? 1.0 / s->distortion_prior_sigma : 0.0;
            pp->kind[pp->nc++] = j;
        }
}

void rs_calib__prior_normal(double *S, const rs_calib__params *pp, const rs_calib_noise_state *s)
{
    const int nc = pp->nc;
    for (int c = 0; c < nc; c++) S[c * nc + c] += pp->prior_w[c] * pp->prior_w[c];
    if (!(s->has_position_prior && s->prior_sigma_m > 0)) return;
    double C[3], dC_drt[18];
    rs_pose_position_from_rt(C, dC_drt, s->rt_cam_c);
    for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++)
            for (int k = 0; k < 3; k++)
                S[a * nc + b] += dC_drt[k * 6 + a] * dC_drt[k * 6 + b] / (s->prior_sigma_m * s->prior_sigma_m);
}

void rs_calib__prior_gradient(double *gamma, const rs_calib__params *pp, const rs_calib_noise_state *s)
{
    const double *x = s->intrinsics;
    for (int a = 0; a < pp->nc; a++) {
        const double w2 = pp->prior_w[a] * pp->prior_w[a];
        gamma[a] = pp->kind[a] == -1   ? 0.0
                   : pp->kind[a] == -2 ? w2 * (x[0] / s->intrinsics_nominal[0] - 1.0)
                                       : w2 * (x[pp->kind[a]] - s->intrinsics_nominal[pp->kind[a]]);
    }
    if (!(s->has_position_prior && s->prior_sigma_m > 0)) return;
    double C[3], dC_drt[18];
    rs_pose_position_from_rt(C, dC_drt, s->rt_cam_c);
    for (int k = 0; k < 3; k++)
        for (int a = 0; a < 6; a++)
            gamma[a] += dC_drt[k * 6 + a] * (C[k] - s->prior_position_c_m[k]) / (s->prior_sigma_m * s->prior_sigma_m);
}

bool rs_calib__pixel_jacobian(double q_px[2], double *G, double J[6], double dpc_dp[9], mrcal_point3_t dq_dpc[2],
                              const rs_calib_noise_state *s, const rs_calib__params *pp, const double seen[3],
                              double *dq_dintr)
{
    double pc[3], dpc_drt[18];
    rs_pose_prepared_apply(pc, dpc_drt, dpc_dp, &pp->pose, seen);
    mrcal_point2_t q;
    bool intrinsics = false; // their gradient only where a column needs it (it cost a third of the projection)
    for (int c = 0; c < pp->nc; c++) intrinsics = intrinsics || pp->kind[c] != -1;
    if (!rs_lens_project(&q, dq_dpc, intrinsics ? dq_dintr : NULL, (const mrcal_point3_t *)pc, 1, s->lensmodel,
                         s->intrinsics))
        return false;
    for (int r = 0; r < 2; r++) {
        q_px[r] = q.xy[r];
        for (int c = 0; c < pp->nc; c++) {
            double v = 0;
            if (pp->kind[c] == -1)
                for (int j = 0; j < 3; j++) v += dq_dpc[r].xyz[j] * dpc_drt[j * 6 + c];
            else if (pp->kind[c] == -2)
                v = s->intrinsics_nominal[0] * dq_dintr[r * pp->Ni + 0] +
                    s->intrinsics_nominal[1] * dq_dintr[r * pp->Ni + 1];
            else
                v = dq_dintr[r * pp->Ni + pp->kind[c]];
            G[r * pp->nc + c] = v;
        }
        for (int a = 0; a < 3; a++) {
            double v = 0;
            for (int j = 0; j < 3; j++) v += dq_dpc[r].xyz[j] * dpc_dp[j * 3 + a];
            J[r * 3 + a] = v;
        }
    }
    return true;
}

// The ground point (E, N) of the optical axis on the plane up = 0 of the centred frame (the
// landmarks' mean height), and G (2,6) = d ground / d rt; false (G NAN) when the axis does not
// come down to it. With C the camera's position and d = R' (0, 0, 1) the axis in the world
// (R's third row): g = C + lambda d, lambda = -C_U / d_U, so
// dg = dC + dlambda d + lambda dd, dlambda = -(dC_U + lambda dd_U) / d_U.
// (Central differences of g over the 6 parameters, 12 rotations, were a third of the redundancy
// numbers' time on 4 landmarks.)
bool rs_calib__axis_ground(double g[2], double G[12], const double rt[6])
{
    double C[3], dC[18], R[9], dR[27];
    rs_pose_position_from_rt(C, dC, rt);
    mrcal_R_from_r(R, dR, rt);
    const double d[3] = {R[6], R[7], R[8]};
    const double lambda = d[2] < -1e-9 ? -C[2] / d[2] : -1.0;
    if (!(lambda > 0)) {
        for (int j = 0; j < 12; j++) G[j] = NAN;
        return false;
    }
    for (int a = 0; a < 2; a++) g[a] = C[a] + lambda * d[a];
    for (int k = 0; k < 6; k++) {
        double dd[3] = {0, 0, 0}; // d d / d rt_k: the rotation only
        for (int j = 0; j < 3 && k < 3; j++) dd[j] = dR[9 * 2 + 3 * j + k];
        const double dlambda = (-dC[2 * 6 + k] - lambda * dd[2]) / d[2];
        for (int a = 0; a < 2; a++) G[a * 6 + k] = dC[a * 6 + k] + dlambda * d[a] + lambda * dd[a];
    }
    return true;
}

bool rs_calib__seen_point(double seen[3], double d[3], const double *p_c_m, const double *along_c,
                          const double *s_along_m, int i)
{
    const double *a = along_c ? &along_c[3 * i] : NULL;
    const bool slides = a && (a[0] != 0.0 || a[1] != 0.0 || a[2] != 0.0);
    for (int k = 0; k < 3; k++) {
        d[k] = slides ? a[k] : 0.0;
        seen[k] = p_c_m[3 * i + k] + (slides ? s_along_m[i] * a[k] : 0.0);
    }
    return slides;
}

void rs_calib__position_column(double col[2], const mrcal_point3_t dq_dpc[2], const double dpc_dp[9],
                               const double dir[3], double sigma_px)
{
    for (int r = 0; r < 2; r++) {
        double v = 0;
        for (int j = 0; j < 3; j++)
            for (int a = 0; a < 3; a++) v += dq_dpc[r].xyz[j] * dpc_dp[j * 3 + a] * dir[a];
        col[r] = v / sigma_px;
    }
}

// One landmark's whitened observations: rows (up to 5: u, v and the free survey axes) of A (nc
// columns) and B (k <= 4: the free position axes, and s for a landmark picked along a segment),
// the residuals e, which component each row is. A (m, nc) row-major lies in the caller's array
// of every landmark's (sized by nc, not RS_NOISE_NC_MAX: at that size the arrays of 200
// landmarks went to fresh pages from the kernel at every call, 40% of a calibration's time).
typedef struct {
    int m, k;
    int comp[RS_NOISE_NCOMP]; // row -> component
    double B[RS_NOISE_NCOMP][4], e[RS_NOISE_NCOMP];
    double *A;
} block;

static bool landmark_block(block *b, double *A, const rs_calib_noise_state *s, const rs_calib__params *pp, int i,
                           double *dq_dintr)
{
    b->m = b->k = 0;
    b->A = A;
    memset(b->B, 0, sizeof b->B);
    const double *p = &s->p_c_m[3 * i];
    double seen[3], d[3], q[2], G[2 * RS_NOISE_NC_MAX], J[6], dpc_dp[9];
    mrcal_point3_t dq_dpc[2];
    const bool slides = rs_calib__seen_point(seen, d, s->p_c_m, s->along_c, s->s_along_m, i);
    if (!rs_calib__pixel_jacobian(q, G, J, dpc_dp, dq_dpc, s, pp, seen, dq_dintr)) return false;
    const double sp = s->sigma_px ? s->sigma_px[i] : 1.0;
    for (int r = 0; r < 2; r++) {
        b->comp[b->m] = r;
        b->e[b->m] = (q[r] - s->q_px[2 * i + r]) / sp;
        for (int c = 0; c < pp->nc; c++) A[b->m * pp->nc + c] = G[r * pp->nc + c] / sp;
        b->m++;
    }
    for (int a = 0; a < 3; a++) {
        const double sa = s->sigma_enu_m ? s->sigma_enu_m[3 * i + a] : 0.0;
        if (!(sa > 0)) continue;
        b->B[0][b->k] = J[a] / sp, b->B[1][b->k] = J[3 + a] / sp; // the pixel rows' dependence on this axis
        b->comp[b->m] = RS_NOISE_E + a;
        b->e[b->m] = (p[a] - s->p_survey_c_m[3 * i + a]) / sa;
        b->B[b->m][b->k] = 1.0 / sa;
        for (int c = 0; c < pp->nc; c++) A[b->m * pp->nc + c] = 0.0; // a survey row: no camera
        b->m++, b->k++;
    }
    if (slides) { // s: the pixel rows' dependence on the seen point, along d
        double col[2];
        rs_calib__position_column(col, dq_dpc, dpc_dp, d, sp);
        b->B[0][b->k] = col[0], b->B[1][b->k] = col[1];
        b->k++;
    }
    return true;
}

// Ã = A - B N^-1 B'A (m x nc, row-major) into At; Ninv (k x k) out.
static rs_status reduce(double *At, double Ninv[16], const block *b, int nc, rs_err *err)
{
    double N[16] = {0};
    for (int x = 0; x < b->k; x++)
        for (int y = 0; y < b->k; y++)
            for (int r = 0; r < b->m; r++) N[x * b->k + y] += b->B[r][x] * b->B[r][y];
    if (b->k > 0) {
        rs_status st = rs_calib_opencv_inverse_spd(Ninv, N, b->k, err);
        if (st) return st;
    }
    // M = B'A (k x nc); At = A - B Ninv M
    double M[4][RS_NOISE_NC_MAX];
    for (int x = 0; x < b->k; x++)
        for (int c = 0; c < nc; c++) {
            M[x][c] = 0;
            for (int r = 0; r < b->m; r++) M[x][c] += b->B[r][x] * b->A[r * nc + c];
        }
    for (int r = 0; r < b->m; r++)
        for (int c = 0; c < nc; c++) {
            double v = b->A[r * nc + c];
            for (int x = 0; x < b->k; x++)
                for (int y = 0; y < b->k; y++) v -= b->B[r][x] * Ninv[x * b->k + y] * M[y][c];
            At[r * nc + c] = v;
        }
    return RS_OK;
}

static double excluded_chi2(const rs_calib_noise_state *s, const rs_calib__params *pp, const double *Q, int i,
                            double *dq_dintr);

rs_status rs_calib__noise_redundancy(const rs_calib_noise_out *out, const rs_calib_noise_state *s, rs_err *err)
{
    const int N = s->N;
    rs_calib__params pp;
    rs_calib__camera_params(&pp, s);
    const int nc = pp.nc;
    for (int i = 0; i < N && out->chi2_excluded; i++) out->chi2_excluded[i] = NAN;
    for (int i = 0; i < N; i++)
        for (int j = 0; j < RS_NOISE_NCOMP; j++) {
            if (out->e) out->e[RS_NOISE_NCOMP * i + j] = 0;
            if (out->r) out->r[RS_NOISE_NCOMP * i + j] = 0;
            for (int k = 0; k < 3 && out->dpos_m; k++) out->dpos_m[(RS_NOISE_NCOMP * i + j) * 3 + k] = 0;
            for (int k = 0; k < 2 && out->dground_m; k++) out->dground_m[(RS_NOISE_NCOMP * i + j) * 2 + k] = 0;
        }
    double *dq_dintr = malloc((size_t)2 * (size_t)pp.Ni * sizeof *dq_dintr);
    double *S = calloc((size_t)nc * (size_t)nc, sizeof *S), *Q = malloc((size_t)nc * (size_t)nc * sizeof *Q);
    block *blocks = malloc((size_t)(N > 0 ? N : 1) * sizeof *blocks);
    rs_status st = dq_dintr && S && Q && blocks ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "noise model: out of memory");

    // 1. per landmark: the whitened block, Ã_i; S = sum Ã'Ã + priors
    const size_t per = (size_t)RS_NOISE_NCOMP * (size_t)nc; // one landmark's rows of A and At
    double *A = NULL, *At = NULL;
    double(*Ninv)[16] = NULL;
    if (st == RS_OK) {
        A = malloc((size_t)(N > 0 ? N : 1) * per * sizeof *A);
        At = malloc((size_t)(N > 0 ? N : 1) * per * sizeof *At);
        Ninv = malloc((size_t)(N > 0 ? N : 1) * sizeof *Ninv);
        if (!A || !At || !Ninv) st = rs_err_set(err, RS_ERR_NOMEM, "noise model: out of memory");
    }
    for (int i = 0; st == RS_OK && i < N; i++) {
        if (!s->use[i]) continue;
        if (!landmark_block(&blocks[i], &A[i * per], s, &pp, i, dq_dintr)) {
            st = rs_err_set(err, RS_ERR_DEGENERATE, "landmark %d does not project at the solution", i);
            break;
        }
        const double *Ai = &At[i * per];
        if ((st = reduce(&At[i * per], Ninv[i], &blocks[i], nc, err))) break;
        for (int r = 0; r < blocks[i].m; r++)
            for (int a = 0; a < nc; a++)
                for (int b = 0; b < nc; b++) S[a * nc + b] += Ai[r * nc + a] * Ai[r * nc + b];
    }
    double dC_drt[18];
    double C[3];
    rs_pose_position_from_rt(C, dC_drt, s->rt_cam_c);
    if (st == RS_OK) {
        rs_calib__prior_normal(S, &pp, s);
        st = rs_calib_opencv_inverse_spd(Q, S, nc, err);
    }
    double G[12];
    double g_axis[2];
    const bool have_ground = st == RS_OK && out->dground_m && rs_calib__axis_ground(g_axis, G, s->rt_cam_c);

    // 2. per observation: H_jj, r = 1 - H_jj, the camera's response; the landmarks out: their test
    for (int i = 0; st == RS_OK && i < N; i++) {
        if (!s->use[i] && out->chi2_excluded) out->chi2_excluded[i] = excluded_chi2(s, &pp, Q, i, dq_dintr);
        if (!s->use[i]) continue;
        const block *b = &blocks[i];
        const double *Ai = &At[i * per];
        for (int r = 0; r < b->m; r++) {
            const int j = RS_NOISE_NCOMP * i + b->comp[r];
            double dc[RS_NOISE_NC_MAX], h = 0;
            for (int a = 0; a < nc; a++) {
                dc[a] = 0;
                for (int c = 0; c < nc; c++) dc[a] += Q[a * nc + c] * Ai[r * nc + c];
                h += Ai[r * nc + a] * dc[a];
            }
            for (int x = 0; x < b->k; x++)
                for (int y = 0; y < b->k; y++) h += b->B[r][x] * Ninv[i][x * b->k + y] * b->B[r][y];
            if (out->e) out->e[j] = b->e[r];
            if (out->r) out->r[j] = fmin(1.0, fmax(0.0, 1.0 - h));
            for (int k = 0; k < 3 && out->dpos_m; k++) {
                double v = 0;
                for (int a = 0; a < 6; a++) v += dC_drt[k * 6 + a] * dc[a];
                out->dpos_m[3 * j + k] = v;
            }
            for (int k = 0; k < 2 && out->dground_m; k++) {
                double v = 0;
                for (int a = 0; a < 6; a++) v += G[k * 6 + a] * dc[a];
                out->dground_m[2 * j + k] = have_ground ? v : NAN;
            }
        }
    }
    free(dq_dintr);
    free(S);
    free(Q);
    free(blocks);
    free(A);
    free(At);
    free(Ninv);
    return st;
}

// The 2-dof chi-square of landmark i's pick when it is not in the adjustment (rs_calib_noise.h,
// chi2_excluded): its pixel residual at its surveyed position against the covariance of that
// prediction, sigma_px^2 I + J_p S J_p' + G Q_cc G' (Q_cc (nc,nc): the camera's covariance).
static double excluded_chi2(const rs_calib_noise_state *s, const rs_calib__params *pp, const double *Q, int i,
                            double *dq_dintr)
{
    double p[3], d[3], q[2], G[2 * RS_NOISE_NC_MAX], J[6], dpc_dp[9];
    mrcal_point3_t dq_dpc[2];
    const bool slides = rs_calib__seen_point(p, d, s->p_survey_c_m, s->along_c, s->s_along_m, i);
    double pc[3];
    mrcal_transform_point_rt(pc, NULL, NULL, s->rt_cam_c, p);
    if (!(pc[2] > 0) || !rs_calib__pixel_jacobian(q, G, J, dpc_dp, dq_dpc, s, pp, p, dq_dintr)) return NAN;
    const double sp = s->sigma_px ? s->sigma_px[i] : 1.0;
    const int nc = pp->nc;
    double C[4] = {sp * sp, 0, 0, sp * sp};
    for (int r = 0; r < 2; r++)
        for (int c = 0; c < 2; c++) {
            for (int a = 0; a < 3; a++) {
                const double sa = s->sigma_enu_m ? s->sigma_enu_m[3 * i + a] : 0.0;
                C[2 * r + c] += J[3 * r + a] * sa * sa * J[3 * c + a];
            }
            for (int a = 0; a < nc; a++)
                for (int b = 0; b < nc; b++) C[2 * r + c] += G[r * nc + a] * Q[a * nc + b] * G[c * nc + b];
        }
    if (slides) { // anywhere along the segment: its image direction carries no information
        double col[2];
        rs_calib__position_column(col, dq_dpc, dpc_dp, d, 1.0);
        const double big = 1e6 * (C[0] + C[3]) / (col[0] * col[0] + col[1] * col[1] + 1e-300);
        for (int r = 0; r < 2; r++)
            for (int c = 0; c < 2; c++) C[2 * r + c] += col[r] * big * col[c];
    }
    const double e[2] = {q[0] - s->q_px[2 * i], q[1] - s->q_px[2 * i + 1]};
    const double det = C[0] * C[3] - C[1] * C[2];
    if (!(det > 0)) return NAN;
    return (C[3] * e[0] * e[0] - (C[1] + C[2]) * e[0] * e[1] + C[0] * e[1] * e[1]) / det;
}

int rs_calib__noise_group(int component)
{
    return component < RS_NOISE_E ? RS_NOISE_PIXEL : component < RS_NOISE_UP ? RS_NOISE_SURVEY_H : RS_NOISE_SURVEY_V;
}

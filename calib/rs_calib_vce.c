// rs_calib_vce.c -- variance components of one camera's adjustment by restricted maximum
// likelihood, on the adjustment linearised at its solution (calib/internal/rs_calib_vce.h).
//
// The landmarks are marginalised: landmark i's surveyed position enters its pick as a pixel
// error J_i e_survey, so that its pick, evaluated at the surveyed position, has the 2x2
// covariance
//   C_i(theta) = theta_px V_px,i + theta_h V_h,i + theta_v V_v,i,
//   V_px,i = sigma_px^2 I,  V_h,i = sum_{a = E, N} sigma_a^2 J_a J_a',  V_v,i = sigma_U^2 J_U J_U'
// (J = dq/dp, sigmas as stated, widened for shared survey errors; theta: the variance factors).
// For a linear model this is the same adjustment as the one with the landmarks as unknowns: the
// surveyed coordinates are a saturated block for p, and eliminating it leaves these picks with
// the same residuals, redundancy numbers and restricted likelihood (Koch 1999, section 3.7;
// Searle, Casella & McCulloch, "Variance Components", 1992, chapter 6). A landmark picked along
// a segment keeps its offset s as a fixed effect: W'_i = W_i - W_i b b' W_i / (b' W_i b), b = dq/ds.
//
// With W = blockdiag(W'_i), G_i = dq/dc, S = sum G' W' G (+ the camera priors), Q = S^-1 and
// P = W - W G Q G' W, the restricted log likelihood is
//   l(theta) = -1/2 (sum_i log det C_i [+ log b'W b] + log det S + e_hat' W e_hat)
// and its score and Fisher information in log theta are
//   dl/dlog theta_g = (q_g - r_g) / 2,  q_g = theta_g e_hat' W V_g W e_hat,  r_g = theta_g tr(P V_g)
//   F_gh = theta_g theta_h tr(P V_g P V_h) / 2
// (Förstner's estimator is the fixed point q_g = r_g of the same score: Förstner 1979, Koch
// 1999, section 3.6.3). Fisher scoring in log theta, with the stated sigmas as a log-normal
// prior, converges in a few steps where Förstner's iteration crawls: when two groups explain
// the same residuals, as pixel and survey noise often do on one camera. (Started also from
// each group 5x noisier than stated, it reached the same mode on every problem of
// tests/calib/test_noise_model.c, and one start is kept; but the posterior can have a second
// mode, which Newton's steps from farther than 0.3 sigma found: rs_calib__vce_estimate.)
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "calib/internal/rs_calib_opencv.h"
#include "calib/internal/rs_calib_vce.h"
#include "core/rs_pose.h"

typedef struct {
    double e[2];                   // pixel residual at the surveyed (seen) point, predicted - observed
    double V[RS_NOISE_NGROUPS][3]; // per group, its 2x2 covariance at theta = 1 (xx, xy, yy)
    double b[2];                   // dq/ds along the segment, when it slides
    bool slides;
    double share;                  // picks sharing the survey error (>= 1)
    double W[3];                   // W'_i at the last evaluation
    double Z[RS_NOISE_NGROUPS][4]; // W' V_g W' (2x2, row-major)
    double u[2];                   // W' e_hat at the last full evaluation (P y)
} vce_landmark;

struct rs_calib__vce {
    int n, nc;
    vce_landmark *lm;                // (n,)
    double *G;                       // (n,2,nc)
    double *P;                       // (nc,nc) the camera priors' normal matrix
    double *gamma;                   // (nc,) the priors' gradient at the state
    bool active[RS_NOISE_NGROUPS];   // groups with observations
    int ng, grp[RS_NOISE_NGROUPS];   // the active groups: the full evaluation skips the others
    double *S, *Q, *M, *QM, *g, *dc; // scratch: (nc,nc), (nc,nc), (3,nc,nc), (3,nc,nc), (nc,), (nc,)
};

static void sym2_mul(double out[4], const double a[4], const double b[4])
{
    out[0] = a[0] * b[0] + a[1] * b[2], out[1] = a[0] * b[1] + a[1] * b[3];
    out[2] = a[2] * b[0] + a[3] * b[2], out[3] = a[2] * b[1] + a[3] * b[3];
}

static void full2(double out[4], const double s[3]) { out[0] = s[0], out[1] = out[2] = s[1], out[3] = s[2]; }

void rs_calib__vce_free(rs_calib__vce *v)
{
    if (!v) return;
    free(v->lm);
    free(v->G);
    free(v->P);
    free(v->gamma);
    free(v->S);
    free(v->Q);
    free(v->M);
    free(v->QM);
    free(v->g);
    free(v->dc);
    free(v);
}

// Evaluates the model at log_theta: S, its inverse Q, the gradient g and the step dc = -Q g in v;
// with `full`, also the restricted log likelihood *loglik, q, r (with shared survey errors counted
// once) and the Fisher information F (3x3, in log theta) -- without, those are not touched.
// Groups without observations are skipped (zeros).
// nc = v->nc, given as an argument so that evaluate() below can have copies with it constant.
static inline __attribute__((always_inline)) rs_status
evaluate_nc(rs_calib__vce *v, const double L[RS_NOISE_NGROUPS], bool full, double *loglik, double q[RS_NOISE_NGROUPS],
            double r[RS_NOISE_NGROUPS], double F[RS_NOISE_NGROUPS * RS_NOISE_NGROUPS], rs_err *err, const int nc)
{
    double th[RS_NOISE_NGROUPS];
    for (int g = 0; g < RS_NOISE_NGROUPS; g++) th[g] = exp(L[g]);
    memcpy(v->S, v->P, (size_t)nc * nc * sizeof *v->S);
    for (int a = 0; a < v->ng && full; a++)
        memset(&v->M[(size_t)v->grp[a] * nc * nc], 0, (size_t)nc * nc * sizeof *v->M);
    memcpy(v->g, v->gamma, (size_t)nc * sizeof *v->g);
    double ld = 0;
    for (int i = 0; i < v->n; i++) {
        vce_landmark *l = &v->lm[i];
        const double *G = &v->G[2 * nc * i];
        double C[3] = {0, 0, 0};
        for (int g = 0; g < RS_NOISE_NGROUPS; g++)
            for (int k = 0; k < 3; k++) C[k] += th[g] * l->V[g][k];
        const double det = C[0] * C[2] - C[1] * C[1];
        if (!(det > 0))
            return rs_err_set(err, RS_ERR_DEGENERATE, "variance components: a pick's covariance is singular");
        ld += log(det);
        double W[3] = {C[2] / det, -C[1] / det, C[0] / det};
        if (l->slides) {
            const double Wb[2] = {W[0] * l->b[0] + W[1] * l->b[1], W[1] * l->b[0] + W[2] * l->b[1]};
            const double bWb = l->b[0] * Wb[0] + l->b[1] * Wb[1];
            if (!(bWb > 0)) return rs_err_set(err, RS_ERR_DEGENERATE, "variance components: a slide is not seen");
            ld += log(bWb);
            W[0] -= Wb[0] * Wb[0] / bWb, W[1] -= Wb[0] * Wb[1] / bWb, W[2] -= Wb[1] * Wb[1] / bWb;
        }
        memcpy(l->W, W, sizeof W);
        double Wf[4], Vf[4], t[4];
        full2(Wf, W);
        for (int ga = 0; ga < v->ng && full; ga++) {
            const int g = v->grp[ga];
            full2(Vf, l->V[g]);
            sym2_mul(t, Wf, Vf);
            sym2_mul(l->Z[g], t, Wf);
        }
        // S += G' W G, g += G' W e, M_g += G' Z_g G: the upper triangles (mirrored below)
        for (int a = 0; a < nc; a++) {
            const double ga[2] = {G[a], G[nc + a]};
            const double wa[2] = {W[0] * ga[0] + W[1] * ga[1], W[1] * ga[0] + W[2] * ga[1]};
            v->g[a] += wa[0] * l->e[0] + wa[1] * l->e[1];
            for (int b = a; b < nc; b++) v->S[a * nc + b] += wa[0] * G[b] + wa[1] * G[nc + b];
            for (int k = 0; k < v->ng && full; k++) {
                const int g = v->grp[k];
                const double *Z = l->Z[g];
                const double za[2] = {Z[0] * ga[0] + Z[2] * ga[1], Z[1] * ga[0] + Z[3] * ga[1]};
                double *M = &v->M[(size_t)g * nc * nc + (size_t)a * nc];
                for (int b = a; b < nc; b++) M[b] += za[0] * G[b] + za[1] * G[nc + b];
            }
        }
    }
    for (int a = 0; a < nc; a++)
        for (int b = 0; b < a; b++) {
            v->S[a * nc + b] = v->S[b * nc + a];
            for (int ga = 0; ga < v->ng && full; ga++) {
                const int g = v->grp[ga];
                v->M[(size_t)g * nc * nc + (size_t)a * nc + b] = v->M[(size_t)g * nc * nc + (size_t)b * nc + a];
            }
        }
    double ldS = 0;
    rs_status st = full ? rs_calib_opencv_inverse_spd_logdet(v->Q, &ldS, v->S, nc, err)
                        : rs_calib_opencv_inverse_spd(v->Q, v->S, nc, err);
    if (st != RS_OK) return st;
    for (int a = 0; a < nc; a++) { // the Gauss-Newton step from the state the model was built at
        v->dc[a] = 0;
        for (int b = 0; b < nc; b++) v->dc[a] -= v->Q[a * nc + b] * v->g[b];
    }
    if (!full) return RS_OK;
    double quad = 0;
    for (int a = 0; a < nc; a++) {
        quad += 2.0 * v->gamma[a] * v->dc[a];
        for (int b = 0; b < nc; b++) quad += v->dc[a] * v->P[a * nc + b] * v->dc[b];
    }
    memset(q, 0, RS_NOISE_NGROUPS * sizeof *q);
    memset(r, 0, RS_NOISE_NGROUPS * sizeof *r);
    memset(F, 0, RS_NOISE_NGROUPS * RS_NOISE_NGROUPS * sizeof *F);
    const int ng = v->ng, *grp = v->grp;
    double T[RS_NOISE_NGROUPS * RS_NOISE_NGROUPS] = {0}; // (ng,ng), the active groups'
    for (int i = 0; i < v->n; i++) {
        vce_landmark *l = &v->lm[i];
        const double *G = &v->G[2 * nc * i];
        double eh[2] = {l->e[0], l->e[1]}, GQ[2][RS_NOISE_NC_MAX];
        for (int k = 0; k < 2; k++)
            for (int a = 0; a < nc; a++) {
                eh[k] += G[k * nc + a] * v->dc[a];
                GQ[k][a] = 0;
                for (int b = 0; b < nc; b++) GQ[k][a] += G[k * nc + b] * v->Q[b * nc + a];
            }
        double H[4] = {0, 0, 0, 0}; // G Q G'
        for (int k = 0; k < 2; k++)
            for (int m = 0; m < 2; m++)
                for (int a = 0; a < nc; a++) H[2 * k + m] += GQ[k][a] * G[m * nc + a];
        const double *u = l->u;
        l->u[0] = l->W[0] * eh[0] + l->W[1] * eh[1], l->u[1] = l->W[1] * eh[0] + l->W[2] * eh[1];
        quad += eh[0] * u[0] + eh[1] * u[1];
        double Wf[4], WV[RS_NOISE_NGROUPS][4], ZH[RS_NOISE_NGROUPS][4];
        full2(Wf, l->W);
        for (int ga = 0; ga < ng; ga++) {
            const int g = grp[ga];
            double Vf[4];
            full2(Vf, l->V[g]);
            sym2_mul(WV[g], Wf, Vf);
            sym2_mul(ZH[g], l->Z[g], H);
            const double Vu[2] = {Vf[0] * u[0] + Vf[1] * u[1], Vf[2] * u[0] + Vf[3] * u[1]};
            q[g] += th[g] * (u[0] * Vu[0] + u[1] * Vu[1]);
            const double rg = th[g] * (WV[g][0] + WV[g][3] - ZH[g][0] - ZH[g][3]);
            r[g] += g == RS_NOISE_PIXEL ? rg : rg / l->share;
        }
        // tr(P V_g P V_h) = sum_i [tr(W V_g W V_h) - 2 tr(Z_g H W V_h)] + tr(Q M_g Q M_h): P's
        // off-diagonal blocks enter only through M_g (symmetric in g, h: the upper triangle)
        for (int ga = 0; ga < ng; ga++)
            for (int ha = ga; ha < ng; ha++) {
                const int g = grp[ga], h = grp[ha];
                double t[4], x[4];
                sym2_mul(t, WV[g], WV[h]);
                sym2_mul(x, ZH[g], WV[h]);
                T[ga * ng + ha] += t[0] + t[3] - 2.0 * (x[0] + x[3]);
            }
    }
    // + tr(Q M_g Q M_h)
    double *QM = v->QM;
    for (int ga = 0; ga < ng; ga++)
        for (int a = 0, g = grp[ga]; a < nc; a++)
            for (int b = 0; b < nc; b++) {
                double x = 0;
                for (int k = 0; k < nc; k++) x += v->Q[a * nc + k] * v->M[(size_t)g * nc * nc + (size_t)k * nc + b];
                QM[(size_t)g * nc * nc + (size_t)a * nc + b] = x;
            }
    for (int ga = 0; ga < ng; ga++)
        for (int ha = ga; ha < ng; ha++) {
            const int g = grp[ga], h = grp[ha];
            double x = 0;
            for (int a = 0; a < nc; a++)
                for (int b = 0; b < nc; b++)
                    x += QM[(size_t)g * nc * nc + (size_t)a * nc + b] * QM[(size_t)h * nc * nc + (size_t)b * nc + a];
            F[g * RS_NOISE_NGROUPS + h] = F[h * RS_NOISE_NGROUPS + g] = 0.5 * th[g] * th[h] * (T[ga * ng + ha] + x);
        }
    *loglik = -0.5 * (ld + ldS + quad);
    return RS_OK;
}

// The pose alone (nc = 6) and with the focal (7, the intrinsics test's alternative) are compiled
// with nc constant: their loops unrolled, a third of a 4-landmark calibration's variance
// components' time.
static rs_status evaluate(rs_calib__vce *v, const double L[RS_NOISE_NGROUPS], bool full, double *loglik,
                          double q[RS_NOISE_NGROUPS], double r[RS_NOISE_NGROUPS],
                          double F[RS_NOISE_NGROUPS * RS_NOISE_NGROUPS], rs_err *err)
{
    if (v->nc == 6) return evaluate_nc(v, L, full, loglik, q, r, F, err, 6);
    if (v->nc == 7) return evaluate_nc(v, L, full, loglik, q, r, F, err, 7);
    return evaluate_nc(v, L, full, loglik, q, r, F, err, v->nc);
}

// The observed information in log theta (3x3) at the last full evaluation (q, r, F its):
//   O_gh = A_gh - F_gh + [g = h] (r_g - q_g) / 2,  A_gh = theta_g theta_h y' P V_g P V_h P y
// (minus the score's derivative: dq_g/dlog theta_h = [g = h] q_g - 2 A_gh, dr_g/dlog theta_h =
// [g = h] r_g - 2 F_gh; A / 2 is the "average information" of Gilmour, Thompson & Cullis,
// Biometrics 51, 1995). With P y = W e_hat (u) and P = W - W G Q G' W: A_gh = sum y_g' W y_h -
// b_g' Q b_h, y_g = theta_g V_g u per pick, b_g = sum G' W y_g. Zero for inactive groups.
static void observed(double O[RS_NOISE_NGROUPS * RS_NOISE_NGROUPS], const rs_calib__vce *v,
                     const double L[RS_NOISE_NGROUPS], const double q[RS_NOISE_NGROUPS],
                     const double r[RS_NOISE_NGROUPS], const double F[RS_NOISE_NGROUPS * RS_NOISE_NGROUPS])
{
    enum { NG = RS_NOISE_NGROUPS };
    const int nc = v->nc, ng = v->ng, *grp = v->grp;
    double th[NG], Y[NG * NG] = {0}, b[NG][RS_NOISE_NC_MAX] = {{0}};
    for (int g = 0; g < NG; g++) th[g] = exp(L[g]);
    for (int i = 0; i < v->n; i++) {
        const vce_landmark *l = &v->lm[i];
        const double *G = &v->G[2 * nc * i];
        double y[NG][2];
        for (int ga = 0; ga < ng; ga++) {
            const double *V = l->V[grp[ga]];
            y[ga][0] = th[grp[ga]] * (V[0] * l->u[0] + V[1] * l->u[1]);
            y[ga][1] = th[grp[ga]] * (V[1] * l->u[0] + V[2] * l->u[1]);
            const double wy[2] = {l->W[0] * y[ga][0] + l->W[1] * y[ga][1], l->W[1] * y[ga][0] + l->W[2] * y[ga][1]};
            for (int a = 0; a < nc; a++) b[ga][a] += G[a] * wy[0] + G[nc + a] * wy[1];
            for (int ha = 0; ha <= ga; ha++) Y[ha * ng + ga] += y[ha][0] * wy[0] + y[ha][1] * wy[1];
        }
    }
    memset(O, 0, NG * NG * sizeof *O);
    for (int ga = 0; ga < ng; ga++)
        for (int ha = ga; ha < ng; ha++) {
            const int g = grp[ga], h = grp[ha];
            double bQb = 0;
            for (int a = 0; a < nc; a++)
                for (int c = 0; c < nc; c++) bQb += b[ga][a] * v->Q[a * nc + c] * b[ha][c];
            O[g * NG + h] = O[h * NG + g] =
                Y[ga * ng + ha] - bQb - F[g * NG + h] + (g == h ? 0.5 * (r[g] - q[g]) : 0.0);
        }
}

rs_status rs_calib__vce_build(rs_calib__vce **out, const rs_calib_noise_state *s, const double *share,
                              const double log_theta_ref[RS_NOISE_NGROUPS], rs_err *err)
{
    *out = NULL;
    rs_calib__params pp;
    rs_calib__camera_params(&pp, s);
    const int nc = pp.nc;
    int n = 0;
    for (int i = 0; i < s->N; i++) n += s->use[i];
    rs_calib__vce *v = calloc(1, sizeof *v);
    double *dq_dintr = malloc((size_t)2 * (size_t)pp.Ni * sizeof *dq_dintr);
    if (v) {
        v->n = n, v->nc = nc;
        v->lm = calloc((size_t)(n > 0 ? n : 1), sizeof *v->lm);
        v->G = malloc((size_t)(n > 0 ? n : 1) * 2 * nc * sizeof *v->G);
        v->P = calloc((size_t)nc * nc, sizeof *v->P);
        v->gamma = calloc((size_t)nc, sizeof *v->gamma);
        v->S = malloc((size_t)nc * nc * sizeof *v->S);
        v->Q = malloc((size_t)nc * nc * sizeof *v->Q);
        v->M = malloc((size_t)RS_NOISE_NGROUPS * nc * nc * sizeof *v->M);
        v->QM = calloc((size_t)RS_NOISE_NGROUPS * nc * nc, sizeof *v->QM); // 0 for an inactive group
        v->g = malloc((size_t)nc * sizeof *v->g);
        v->dc = malloc((size_t)nc * sizeof *v->dc);
    }
    if (!v || !dq_dintr || !v->lm || !v->G || !v->P || !v->gamma || !v->S || !v->Q || !v->M || !v->QM || !v->g ||
        !v->dc) {
        free(dq_dintr);
        rs_calib__vce_free(v);
        return rs_err_set(err, RS_ERR_NOMEM, "variance components: out of memory");
    }
    double f[RS_NOISE_NGROUPS]; // in-use sigma -> stated sigma
    for (int g = 0; g < RS_NOISE_NGROUPS; g++) f[g] = exp(-0.5 * log_theta_ref[g]);
    for (int i = 0, k = 0; i < s->N; i++) {
        if (!s->use[i]) continue;
        vce_landmark *l = &v->lm[k];
        double *G = &v->G[2 * nc * k];
        double seen[3], d[3], q[2], J[6], dpc_dp[9];
        mrcal_point3_t dq_dpc[2];
        l->slides = rs_calib__seen_point(seen, d, s->p_survey_c_m, s->along_c, s->s_along_m, i);
        if (!rs_calib__pixel_jacobian(q, G, J, dpc_dp, dq_dpc, s, &pp, seen, dq_dintr)) {
            free(dq_dintr);
            rs_calib__vce_free(v);
            return rs_err_set(err, RS_ERR_DEGENERATE, "landmark %d does not project at the solution", i);
        }
        for (int r = 0; r < 2; r++) l->e[r] = q[r] - s->q_px[2 * i + r];
        const double sp = (s->sigma_px ? s->sigma_px[i] : 1.0) * f[RS_NOISE_PIXEL];
        l->V[RS_NOISE_PIXEL][0] = l->V[RS_NOISE_PIXEL][2] = sp * sp;
        for (int a = 0; a < 3; a++) {
            const int g = a < 2 ? RS_NOISE_SURVEY_H : RS_NOISE_SURVEY_V;
            const double sa = (s->sigma_enu_m ? s->sigma_enu_m[3 * i + a] : 0.0) * f[g], s2 = sa * sa;
            l->V[g][0] += s2 * J[a] * J[a];
            l->V[g][1] += s2 * J[a] * J[3 + a];
            l->V[g][2] += s2 * J[3 + a] * J[3 + a];
        }
        for (int g = 0; g < RS_NOISE_NGROUPS; g++) v->active[g] |= l->V[g][0] + l->V[g][2] > 0;
        for (int r = 0; r < 2 && l->slides; r++) l->b[r] = J[3 * r] * d[0] + J[3 * r + 1] * d[1] + J[3 * r + 2] * d[2];
        l->share = share ? share[i] : 1.0;
        k++;
    }
    free(dq_dintr);
    for (int g = 0; g < RS_NOISE_NGROUPS; g++)
        if (v->active[g]) v->grp[v->ng++] = g;
    rs_calib__prior_normal(v->P, &pp, s);
    rs_calib__prior_gradient(v->gamma, &pp, s);
    *out = v;
    return RS_OK;
}

// rs_calib__vce_estimate's Newton steps: where Fisher's step is within this of a posterior 1-sigma
#define NEWTON_NEAR 0.3
#define NEWTON_LAST 0.1

rs_status rs_calib__vce_estimate(double log_theta[RS_NOISE_NGROUPS], double sd_out[RS_NOISE_NGROUPS], rs_calib__vce *v,
                                 double prior_factor, rs_err *err)
{
    enum { NG = RS_NOISE_NGROUPS };
    const double lp = 2.0 * log(prior_factor); // the prior's 1-sigma in log variance
    if (!(lp > 0)) return RS_OK;               // the stated sigmas are exact
    const double bound = 2.0 * log(RS_NOISE_MAX_FACTOR);
    double L[NG], r[NG], sd[NG] = {0};
    double from[NG] = {0}, step[NG] = {0}, post_from = -INFINITY, slope = 0; // the last accepted point
    memcpy(L, log_theta, sizeof L);
    for (int it = 0, halvings = 0; it < 30; it++) {
        double ll, q[NG], F[NG * NG], O[NG * NG];
        rs_status st = evaluate(v, L, true, &ll, q, r, F, err);
        if (st != RS_OK) return st;
        double post = ll; // the log posterior: the likelihood and the prior N(0, lp^2)
        for (int g = 0; g < NG; g++)
            if (v->active[g]) post -= 0.5 * L[g] * L[g] / (lp * lp);
        // Armijo's condition on the step from the last point: Fisher scoring steps with the
        // expected information, which on a few landmarks can be half the observed one: the steps
        // then overshoot by twice and settle into a two-cycle about the mode, ended by the step
        // limit at one of its points (25 of 146 estimates on the 50 problems of 4 landmarks of
        // `roadside bench calib`; 3 with this). Such a step is halved until the posterior rises.
        if (it > 0 && !(post >= post_from + 1e-4 * slope) && halvings < 10) {
            halvings++;
            for (int g = 0; g < NG; g++) L[g] = from[g] + (step[g] *= 0.5);
            continue;
        }
        halvings = 0;
        double grad[NG], H[NG * NG], Hinv[NG * NG], HN[NG * NG], HNinv[NG * NG];
        int idx[NG], m = 0;
        for (int g = 0; g < NG; g++)
            if (v->active[g]) idx[m++] = g;
        if (m == 0) break;
        for (int a = 0; a < m; a++) {
            grad[a] = 0.5 * (q[idx[a]] - r[idx[a]]) - L[idx[a]] / (lp * lp);
            for (int b = 0; b < m; b++) H[a * m + b] = F[idx[a] * NG + idx[b]] + (a == b ? 1.0 / (lp * lp) : 0.0);
        }
        if ((st = rs_calib_opencv_inverse_spd(Hinv, H, m, err)) != RS_OK) return st;
        // Newton's step with the observed information where it is positive definite and Fisher's
        // step is within NEWTON_NEAR of a posterior 1-sigma: scoring converges linearly, by the
        // ratio of the observed information to the expected, which on few landmarks crawled (a
        // third of the estimates of the bench's 4-landmark problems took 7 to 30 steps, now 6 at
        // most). Not from farther: there the posterior can have another mode (test_noise_model,
        // pixel sigma stated 5x too small, from 1-sigma on: the pixel noise at 0.6x the truth).
        double fisher[NG], newton[NG], worst = 0;
        bool small = true; // Fisher's step within the convergence test below: no Newton's needed
        for (int a = 0; a < m; a++) {
            fisher[a] = 0;
            for (int b = 0; b < m; b++) fisher[a] += Hinv[a * m + b] * grad[b];
            const double sd_a = sqrt(Hinv[a * m + a]);
            worst = fmax(worst, fabs(fisher[a]) / sd_a);
            small = small && fabs(fisher[a]) < fmax(1e-3, 0.01 * sd_a);
        }
        bool use_newton = worst < NEWTON_NEAR && !small;
        if (use_newton) {
            observed(O, v, L, q, r, F);
            for (int a = 0; a < m; a++)
                for (int b = 0; b < m; b++) HN[a * m + b] = O[idx[a] * NG + idx[b]] + (a == b ? 1.0 / (lp * lp) : 0.0);
            use_newton = rs_calib_opencv_inverse_spd(HNinv, HN, m, NULL) == RS_OK;
        }
        for (int a = 0; a < m; a++) {
            newton[a] = 0;
            for (int b = 0; b < m && use_newton; b++) newton[a] += HNinv[a * m + b] * grad[b];
        }
        // converged when every factor moves by less than 1% of its own posterior 1-sigma (or 0.1%
        // in a variance): Fisher scoring converges only linearly where the expected information
        // differs from the observed, and a group of little redundancy (posterior 1-sigma 1.5 in
        // log variance at r = 1) then crept by 1e-3 per step for ten steps
        // A Newton step within NEWTON_LAST of every factor's 1-sigma ends it too: Newton's error
        // after it is second order, about (0.1 sigma)^2 / sigma = 0.01 sigma, the tolerance
        // below, so the evaluation that would confirm it is skipped (on 4 landmarks, one of
        // about three per estimate).
        bool converged = true, last = use_newton;
        for (int a = 0; a < m && last; a++) last = fabs(newton[a]) < NEWTON_LAST * sqrt(Hinv[a * m + a]);
        memcpy(from, L, sizeof from);
        post_from = post, slope = 0;
        memset(step, 0, sizeof step);
        for (int a = 0; a < m; a++) {
            // at most a factor e in a variance per step
            const double d = fmax(-1.0, fmin(1.0, use_newton ? newton[a] : fisher[a]));
            const double next = fmax(-bound, fmin(bound, L[idx[a]] + d));
            sd[idx[a]] = sqrt(Hinv[a * m + a]);
            converged = converged && fabs(next - L[idx[a]]) < fmax(1e-3, 0.01 * sd[idx[a]]);
            step[idx[a]] = next - L[idx[a]];
            slope += grad[a] * step[idx[a]];
            L[idx[a]] = next;
        }
        if (converged || last) break;
    }
    memcpy(log_theta, L, sizeof L);
    if (sd_out) memcpy(sd_out, sd, sizeof sd);
    return RS_OK;
}

// s_g = d log det Q_pp / d log theta_g / 6 (Q_pp the pose's 6x6 block of Q = S^-1): each group's
// share of the pose covariance's scale (they sum to 1). dS/dlog theta_g = -theta_g M_g, so
// dQ/dlog theta_g = theta_g Q M_g Q; QM = Q M_g from evaluate(full); Qpp_inv (6,6).
static void pose_shares(double s[RS_NOISE_NGROUPS], const rs_calib__vce *v, const double L[RS_NOISE_NGROUPS],
                        const double Qpp_inv[36])
{
    const int nc = v->nc;
    for (int g = 0; g < RS_NOISE_NGROUPS; g++) {
        const double *QM = &v->QM[(size_t)g * nc * nc];
        double tr = 0;
        for (int a = 0; a < 6; a++)
            for (int b = 0; b < 6; b++) {
                double x = 0; // (Q M_g Q)_ba
                for (int k = 0; k < nc; k++) x += QM[(size_t)b * nc + k] * v->Q[(size_t)k * nc + a];
                tr += Qpp_inv[a * 6 + b] * x;
            }
        s[g] = exp(L[g]) * tr / 6.0;
    }
}

rs_status rs_calib__vce_cov_spread(double *dQ, double *pose_dof, double *region_m2, rs_calib__vce *v,
                                   const double log_theta[RS_NOISE_NGROUPS], double prior_factor, double min_redundancy,
                                   rs_err *err)
{
    enum { NG = RS_NOISE_NGROUPS };
    const int nc = v->nc;
    memset(dQ, 0, (size_t)nc * nc * sizeof *dQ);
    *pose_dof = INFINITY;
    *region_m2 = rs_calib__pose_region_m2(1e-3, INFINITY, 1.0);
    const double lp = 2.0 * log(prior_factor);
    if (!(lp > 0)) return RS_OK;
    double ll, q[NG], r[NG], F[NG * NG];
    rs_status st = evaluate(v, log_theta, true, &ll, q, r, F, err);
    if (st != RS_OK) return st;
    double *Q0 = malloc((size_t)nc * nc * sizeof *Q0);
    if (!Q0) return rs_err_set(err, RS_ERR_NOMEM, "variance components: out of memory");
    memcpy(Q0, v->Q, (size_t)nc * nc * sizeof *Q0);
    int idx[NG], m = 0; // the groups estimated from the data; the others keep their stated sigma
    for (int g = 0; g < NG; g++)
        if (v->active[g] && r[g] >= min_redundancy) idx[m++] = g;
    double H[NG * NG], C[NG * NG], lam[NG], E[NG * NG];
    for (int a = 0; a < m; a++)
        for (int b = 0; b < m; b++) H[a * m + b] = F[idx[a] * NG + idx[b]] + (a == b ? 1.0 / (lp * lp) : 0.0);
    if (m > 0 && (st = rs_calib_opencv_inverse_spd(C, H, m, err)) == RS_OK)
        st = rs_calib_opencv_eigen_sym(lam, E, C, m, err);
    // the degrees of freedom of the pose covariance's scale: var(log of that scale) = s' C s over
    // the estimated groups, and a scaled inverse chi-square with nu degrees of freedom has
    // var(log) = 2 / nu (at least 3, as below)
    double Qpp[36], Qpp_inv[36];
    for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++) Qpp[a * 6 + b] = Q0[a * nc + b];
    rs_err ignore = {0};
    if (st == RS_OK && m > 0 && rs_calib_opencv_inverse_spd(Qpp_inv, Qpp, 6, &ignore) == RS_OK) {
        double sh[NG], var = 0;
        pose_shares(sh, v, log_theta, Qpp_inv);
        for (int a = 0; a < m; a++)
            for (int b = 0; b < m; b++) var += sh[idx[a]] * C[a * m + b] * sh[idx[b]];
        *pose_dof = var > 0 ? fmax(2.0 / var, 3.0) : INFINITY;
    }
    // the unscented transform of Q over log theta's posterior: 2m points, weight 1/(2m) each, at
    // +-a_k along each eigenvector. The log-normal (Laplace) posterior understates the right
    // tail of a variance's: for one group with r degrees of freedom the exact posterior mean of
    // the factor (a scaled inverse chi-square's) is r / (r - 2) times the estimate, and a_k is
    // chosen so that the points reproduce it, with r_k = 2 / lambda_k the direction's degrees of
    // freedom (at least 3) -- a_k = acosh(1 + 2m / (r_k - 2)), which is sqrt(2 m lambda_k)
    // (twice the Laplace variance) for large r_k
    for (int k = 0; st == RS_OK && k < m; k++) {
        const double rk = fmax(2.0 / fmax(lam[k], 1e-300), 3.0), ak = acosh(1.0 + 2.0 * m / (rk - 2.0));
        for (int sign = -1; sign <= 1 && st == RS_OK; sign += 2) {
            double L[NG];
            memcpy(L, log_theta, sizeof L);
            for (int a = 0; a < m; a++) L[idx[a]] += sign * ak * E[k * m + a];
            if ((st = evaluate(v, L, false, &ll, q, r, F, err)) != RS_OK) break;
            for (int j = 0; j < nc * nc; j++) dQ[j] += (v->Q[j] - Q0[j]) / (2.0 * m);
        }
    }
    // the 99.9% region of the pose in the spread covariance: the pose is then Student-t
    // distributed with pose_dof degrees of freedom about the solution, its Mahalanobis distance
    // in Q_pp over 6 an F(6, nu) (Koch 1999, 3.7.3), and the spread widened Q_pp by the t's
    // nu / (nu - 2), as it does exactly for one group (its posterior mean). (The mean widening
    // of Q_pp's eigenvalues instead, tr(Q_pp^-1 (Q_pp + dQ_pp)) / 6, was tried: on 2,000 sites
    // of 8 landmarks, tests/calib/test_pose_region.c, 20.5% of the poses then lay outside the
    // 90% region and 4.1% outside the 99%, against 10.1% and 2.0% with this)
    if (st == RS_OK && isfinite(*pose_dof))
        *region_m2 = rs_calib__pose_region_m2(1e-3, *pose_dof, *pose_dof / (*pose_dof - 2.0));
    free(Q0);
    return st;
}

double rs_calib__vce_one(double *sd, double chi2_0, double r, double prior_factor)
{
    const double lp = 2.0 * log(prior_factor), bound = 2.0 * log(RS_NOISE_MAX_FACTOR);
    *sd = 0.0;
    if (!(lp > 0) || !(chi2_0 >= 0) || !(r > 0)) return 0.0;
    double L = 0.0;
    for (int it = 0; it < 50; it++) {
        const double grad = 0.5 * (chi2_0 * exp(-L) - r) - L / (lp * lp);
        const double curv = 0.5 * chi2_0 * exp(-L) + 1.0 / (lp * lp);
        const double step = fmax(-1.0, fmin(1.0, grad / curv));
        L = fmax(-bound, fmin(bound, L + step));
        if (fabs(step) < 1e-10) break;
    }
    *sd = 1.0 / sqrt(0.5 * r + 1.0 / (lp * lp));
    return L;
}

int rs_calib__vce_Nintrinsics(const rs_calib__vce *v) { return v->nc - 6; }

// P(F > f) for F ~ F(6, nu): with x = nu / (nu + 6 f) and b = nu / 2, the regularised incomplete
// beta I_x(b, 3) of an integer second argument is a finite sum (Abramowitz and Stegun 26.5.6 and
// 26.6.2): x^b (1 + b (1 - x) + b (b + 1) (1 - x)^2 / 2); nu = INFINITY: the chi-square 6 dof of
// 6 f, e^-t (1 + t + t^2 / 2) with t = 3 f.
static double f6_survival(double f, double nu)
{
    if (!isfinite(nu)) {
        const double t = 3.0 * f;
        return exp(-t) * (1.0 + t + 0.5 * t * t);
    }
    const double b = 0.5 * nu, y = 6.0 * f / (nu + 6.0 * f); // y = 1 - x
    return exp(-b * log1p(6.0 * f / nu)) * (1.0 + b * y + 0.5 * b * (b + 1.0) * y * y);
}

double rs_calib__pose_region_m2(double alpha, double nu, double kappa)
{
    double lo = 1e-6, hi = 1e9; // F's quantile, by bisection in log f (the survival falls monotonically)
    for (int it = 0; it < 200 && hi / lo > 1.0 + 1e-13; it++) {
        const double mid = sqrt(lo * hi);
        if (f6_survival(mid, nu) > alpha)
            lo = mid;
        else
            hi = mid;
    }
    return 6.0 * sqrt(lo * hi) / kappa;
}

rs_status rs_calib__vce_evaluate(rs_calib__vce *v, const double log_theta[RS_NOISE_NGROUPS], double *loglik,
                                 double q[RS_NOISE_NGROUPS], double r[RS_NOISE_NGROUPS],
                                 double F[RS_NOISE_NGROUPS * RS_NOISE_NGROUPS],
                                 double O[RS_NOISE_NGROUPS * RS_NOISE_NGROUPS], rs_err *err)
{
    rs_status st = evaluate(v, log_theta, true, loglik, q, r, F, err);
    if (st == RS_OK) observed(O, v, log_theta, q, r, F);
    return st;
}

rs_status rs_calib__vce_step(double *dc, double *Q, rs_calib__vce *v, const double log_theta[RS_NOISE_NGROUPS],
                             rs_err *err)
{
    double ll, q[RS_NOISE_NGROUPS], r[RS_NOISE_NGROUPS], F[RS_NOISE_NGROUPS * RS_NOISE_NGROUPS];
    rs_status st = evaluate(v, log_theta, false, &ll, q, r, F, err);
    if (st != RS_OK) return st;
    const int nc = v->nc;
    memcpy(dc, v->dc, (size_t)nc * sizeof *dc);
    memcpy(Q, v->Q, (size_t)nc * nc * sizeof *Q);
    return RS_OK;
}

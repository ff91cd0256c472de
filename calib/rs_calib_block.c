// rs_calib_block.c -- one landmark's block of the refinement: tiny QR, the closed-form point and
// Cauchy's loss (calib/internal/rs_calib_block.h has the method).
#include "calib/internal/rs_calib_block.h"

#include <math.h>
#include <string.h>

bool rs_calib__qr5_factor(rs_calib__qr5 *qr, const double J[5][4], int n)
{
    qr->n = n;
    memcpy(qr->a, J, sizeof qr->a);
    double(*a)[4] = qr->a;
    for (int j = 0; j < n; j++) {
        double norm2 = 0.0;
        for (int i = j; i < 5; i++) norm2 += a[i][j] * a[i][j];
        const double norm = sqrt(norm2);
        if (!(norm > 0.0)) return false;
        const double alpha = a[j][j] > 0 ? -norm : norm;
        qr->v0[j] = a[j][j] - alpha; // v = (v0, a[j+1..4][j])
        const double vtv = qr->v0[j] * qr->v0[j] + norm2 - a[j][j] * a[j][j];
        qr->beta[j] = vtv > 0.0 ? 2.0 / vtv : 0.0;
        qr->diag[j] = alpha;
        for (int k = j + 1; k < n; k++) {
            double s = qr->v0[j] * a[j][k];
            for (int i = j + 1; i < 5; i++) s += a[i][j] * a[i][k];
            s *= qr->beta[j];
            a[j][k] -= s * qr->v0[j];
            for (int i = j + 1; i < 5; i++) a[i][k] -= s * a[i][j];
        }
    }
    return true;
}

// b <- H_j b
static void reflect(const rs_calib__qr5 *qr, int j, double b[5])
{
    double s = qr->v0[j] * b[j];
    for (int i = j + 1; i < 5; i++) s += qr->a[i][j] * b[i];
    s *= qr->beta[j];
    b[j] -= s * qr->v0[j];
    for (int i = j + 1; i < 5; i++) b[i] -= s * qr->a[i][j];
}

void rs_calib__qr5_solve(const rs_calib__qr5 *qr, double x[4], const double b_in[5])
{
    double b[5];
    memcpy(b, b_in, sizeof b);
    for (int j = 0; j < qr->n; j++) reflect(qr, j, b);
    for (int j = qr->n - 1; j >= 0; j--) {
        double s = b[j];
        for (int k = j + 1; k < qr->n; k++) s -= qr->a[j][k] * x[k];
        x[j] = s / qr->diag[j];
    }
}

void rs_calib__qr5_basis(const rs_calib__qr5 *qr, double Q[5][4])
{
    for (int c = 0; c < qr->n; c++) {
        double e[5] = {0, 0, 0, 0, 0};
        e[c] = 1.0;
        for (int j = qr->n - 1; j >= 0; j--) reflect(qr, j, e);
        for (int a = 0; a < 5; a++) Q[a][c] = e[a];
    }
}

void rs_calib__point_block_factor(rs_calib__point_block *pt, const double dr_dp[15], const double w_m[3])
{
    double(*B)[3] = pt->B;
    for (int a = 0; a < 2; a++)
        for (int k = 0; k < 3; k++) B[a][k] = dr_dp[a * 3 + k] / w_m[k];
    const double k00 = B[0][0] * B[0][0] + B[0][1] * B[0][1] + B[0][2] * B[0][2];
    const double k11 = B[1][0] * B[1][0] + B[1][1] * B[1][1] + B[1][2] * B[1][2];
    const double k01 = B[0][0] * B[1][0] + B[0][1] * B[1][1] + B[0][2] * B[1][2];
    const double cx = B[0][1] * B[1][2] - B[0][2] * B[1][1], cy = B[0][2] * B[1][0] - B[0][0] * B[1][2],
                 cz = B[0][0] * B[1][1] - B[0][1] * B[1][0];
    const double det = 1.0 + k00 + k11 + cx * cx + cy * cy + cz * cz;
    pt->Mi[0][0] = (1.0 + k11) / det, pt->Mi[1][1] = (1.0 + k00) / det;
    pt->Mi[0][1] = pt->Mi[1][0] = -k01 / det;
}

void rs_calib__point_block_step(const rs_calib__point_block *pt, double dx[3], double dr[5], const double r[5],
                                const double w_m[3])
{
    const double(*B)[3] = pt->B, (*Mi)[2] = pt->Mi;
    double g[3], Bg[2], y[3];
    for (int k = 0; k < 3; k++) g[k] = B[0][k] * r[0] + B[1][k] * r[1] + r[2 + k];
    for (int a = 0; a < 2; a++) Bg[a] = B[a][0] * g[0] + B[a][1] * g[1] + B[a][2] * g[2];
    const double m[2] = {Mi[0][0] * Bg[0] + Mi[0][1] * Bg[1], Mi[1][0] * Bg[0] + Mi[1][1] * Bg[1]};
    for (int k = 0; k < 3; k++) y[k] = -(g[k] - B[0][k] * m[0] - B[1][k] * m[1]); // y = D dx
    for (int k = 0; k < 3; k++) dx[k] = y[k] / w_m[k];
    for (int a = 0; a < 2; a++) dr[a] = B[a][0] * y[0] + B[a][1] * y[1] + B[a][2] * y[2];
    for (int k = 0; k < 3; k++) dr[2 + k] = y[k];
}

void rs_calib__point_block_projector(const rs_calib__point_block *pt, double P[5][2])
{
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2; b++) P[a][b] = pt->Mi[a][b];
    for (int k = 0; k < 3; k++)
        for (int b = 0; b < 2; b++) P[2 + k][b] = -(pt->B[0][k] * pt->Mi[0][b] + pt->B[1][k] * pt->Mi[1][b]);
}

double rs_calib__cauchy_block(double *r, int m, double *J, int ld, int nc, double b)
{
    double s = 0.0;
    for (int a = 0; a < m; a++) s += r[a] * r[a];
    if (!(s > 1e-300)) return 0.0; // rho' = 1, h = 1 at 0
    const double t = s / b, rho = b * log1p(t), d1 = 1.0 / (1.0 + t), x = sqrt(s);
    const double h = fmax((1.0 - t) * d1 * d1, RS_CALIB_CAUCHY_MIN_CURVATURE * d1);
    const double sq = sqrt(d1), c = sqrt(h) - sq, k = d1 / sqrt(h);
    double u[RS_CALIB_BLOCK_MAX_ROWS]; // r / |r| once (r may alias J: the compiler cannot hoist it)
    for (int a = 0; a < m; a++) u[a] = r[a] / x;
    if (J)
        for (int j = 0; j < nc; j++) {
            double *col = &J[(size_t)j * (size_t)ld];
            double ut = 0.0;
            for (int a = 0; a < m; a++) ut += u[a] * col[a];
            const double cut = c * ut;
            for (int a = 0; a < m; a++) col[a] = sq * col[a] + cut * u[a];
        }
    for (int a = 0; a < m; a++) r[a] *= k;
    return rho - k * k * s;
}

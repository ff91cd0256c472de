// rs_calib_block.h -- internal: one landmark's block of the refinement (rs_calib_refine_ceres.cc):
// the tiny least-squares solves that eliminate the landmark's own unknowns (its free survey axes,
// and s for a pick along a segment), and Cauchy's loss on the block. By hand because the
// matrices are tiny and fixed: Eigen's blocked, dynamically sized QR took a third of the solve.
// Rows: the block's 5 residuals (pixel u, v; survey e, n, u), whitened. Matrices row-major.
#pragma once
#include <stdbool.h>

#ifdef __cplusplus
extern "C" {
#endif

// Householder QR of a landmark's Jacobian with respect to its own unknowns, (5, n), n <= 4.
typedef struct {
    double a[5][4]; // R above the diagonal, and the reflectors' tails below it
    double v0[4], beta[4], diag[4];
    int n;
} rs_calib__qr5;

// False when a column is zero (the axis does not enter the residual: cannot happen with a survey
// sigma > 0, whose prior row is that axis's own; a segment seen end-on has a zero s column).
bool rs_calib__qr5_factor(rs_calib__qr5 *qr, const double J[5][4], int n);
// x (n,) = argmin |J x - b|
void rs_calib__qr5_solve(const rs_calib__qr5 *qr, double x[4], const double b[5]);
// Q (5, n): an orthonormal basis of J's columns (the first n columns of H_0 ... H_{n-1}), so that
// (I - J J^+) b = b - Q Q' b: one small product per camera column instead of 2n reflections each
// (those were a quarter of a calibration's instructions).
void rs_calib__qr5_basis(const rs_calib__qr5 *qr, double Q[5][4]);

// The common landmark in closed form: a point (no slide) with all three axes free. Its Jacobian
// is Jp = [A; D] (A = the pixel rows, 2 x 3, D = diag(w_m)), and with B = A D^-1 (2 x 3) and
// M = I + B B' (2 x 2) the Woodbury identity gives what rs_calib__qr5 would:
//   the step        D dx = -(I - B' M^-1 B) g,  g = B' r_px + r_s
//   the projector   (I - Jp Jp^+)'s first two columns = [M^-1; -B' M^-1]
// (I - A N^-1 A' = M^-1 and D N^-1 A' = B' M^-1 for N = A'A + D^2). det M = 1 + |b0|^2 + |b1|^2
// + |b0 x b1|^2 (Lagrange's identity): a sum of squares, without the cancellation of m00 m11 -
// m01^2 when the two pixel rows are nearly parallel.
typedef struct {
    double B[2][3], Mi[2][2]; // B, M^-1
} rs_calib__point_block;

// dr_dp (5, 3): the block's Jacobian with respect to the point; w_m (3,): 1/sigma of its axes
void rs_calib__point_block_factor(rs_calib__point_block *pt, const double dr_dp[15], const double w_m[3]);
// dx (3,) = argmin |r + Jp dx| (in the axes' order), and dr = Jp dx (5,)
void rs_calib__point_block_step(const rs_calib__point_block *pt, double dx[3], double dr[5], const double r[5],
                                const double w_m[3]);
// P (5,2): the pixel columns of the block's residual projector I - Jp (Jp'Jp)^-1 Jp' (the one that
// removes the point's share; rows u, v, then the survey axes), in closed form: M^-1 over -B' M^-1.
void rs_calib__point_block_projector(const rs_calib__point_block *pt, double P[5][2]);

// Cauchy's loss rho(s) = b log(1 + s/b) on a block r (m <= RS_CALIB_BLOCK_MAX_ROWS) of squared norm s, with its Jacobian J
// (m, nc) column-major, leading dimension ld, may be NULL (b = scale^2: Ceres' CauchyLoss(scale)).
// TinySolver minimises half the squared norm of what it is given and steps with that Jacobian's
// J'J, so the block is given as r~ = k r, J~ = (sqrt(rho') I + c u u') J (u = r/|r|) such that
//   J~' r~ = rho' J' r                         the gradient of rho / 2, exact, and
//   J~' J~ = J' (rho' I + (h - rho') u u') J   with h = rho' + 2 s rho'': rho's Gauss-Newton
// Hessian (Triggs et al. 2000), clamped at h >= RS_CALIB_CAUCHY_MIN_CURVATURE rho' beyond s = b,
// where it turns negative. Then |r~|^2 = k^2 s is not rho: returns rho - k^2 s, which the caller
// adds back in a residual of its own (k^2 s < b / RS_CALIB_CAUCHY_MIN_CURVATURE keeps it real
// with that constant added), so that the cost by which TinySolver accepts a step is the
// M-estimator's. Ceres' Corrector keeps only rho' I wherever rho'' < 0, which is all of Cauchy's;
// Gauss-Newton on sqrt(rho) r / |r|, the previous form here, converged linearly (the error
// shrinking to a third per step: the final solve took 9 iterations to 1e-4 sigma, now 4).
#define RS_CALIB_CAUCHY_MIN_CURVATURE 0.1
#define RS_CALIB_BLOCK_MAX_ROWS       8
double rs_calib__cauchy_block(double *r, int m, double *J, int ld, int nc, double b);

#ifdef __cplusplus
}
#endif

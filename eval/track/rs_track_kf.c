// rs_track_kf.c -- the constant-velocity Kalman filter on the ground (rs_track_kf.h).
#include "eval/track/rs_track_kf.h"

#include <math.h>
#include <string.h>

#include "core/rs_units.h"

void rs_track_kf_init(double x[4], double P[16], const double z_en_m[2], const double R_en_m2[4],
                      double init_speed_sigma_mps)
{
    x[0] = z_en_m[0], x[1] = z_en_m[1], x[2] = 0, x[3] = 0;
    memset(P, 0, 16 * sizeof(double));
    P[0] = R_en_m2[0], P[1] = R_en_m2[1], P[4] = R_en_m2[2], P[5] = R_en_m2[3];
    P[10] = P[15] = init_speed_sigma_mps * init_speed_sigma_mps;
}

void rs_track_kf_predict(double x[4], double P[16], double dt_s, double accel_sigma_mps2)
{
    if (!(dt_s > 0)) return;
    const double dt = dt_s, q = accel_sigma_mps2 * accel_sigma_mps2;
    x[0] += dt * x[2];
    x[1] += dt * x[3];
    // F P F^T with F = [I dt I; 0 I]: first the rows (F P), then the columns ((F P) F^T)
    double A[16];
    for (int c = 0; c < 4; c++) {
        A[0 * 4 + c] = P[0 * 4 + c] + dt * P[2 * 4 + c];
        A[1 * 4 + c] = P[1 * 4 + c] + dt * P[3 * 4 + c];
        A[2 * 4 + c] = P[2 * 4 + c];
        A[3 * 4 + c] = P[3 * 4 + c];
    }
    for (int r = 0; r < 4; r++) {
        P[r * 4 + 0] = A[r * 4 + 0] + dt * A[r * 4 + 2];
        P[r * 4 + 1] = A[r * 4 + 1] + dt * A[r * 4 + 3];
        P[r * 4 + 2] = A[r * 4 + 2];
        P[r * 4 + 3] = A[r * 4 + 3];
    }
    const double qpp = q * dt * dt * dt / 3, qpv = q * dt * dt / 2, qvv = q * dt;
    P[0] += qpp, P[5] += qpp, P[10] += qvv, P[15] += qvv;
    P[2] += qpv, P[8] += qpv, P[7] += qpv, P[13] += qpv;
}

// S = P[0:2,0:2] + R and its inverse; false when S is not positive definite.
static bool innovation(double Si[4], const double P[16], const double R[4])
{
    const double s00 = P[0] + R[0], s01 = 0.5 * (P[1] + P[4] + R[1] + R[2]), s11 = P[5] + R[3];
    const double det = s00 * s11 - s01 * s01;
    if (!(s00 > 0) || !(det > 0) || !isfinite(det)) return false;
    Si[0] = s11 / det, Si[1] = Si[2] = -s01 / det, Si[3] = s00 / det;
    return true;
}

double rs_track_kf_mahal2(const double x[4], const double P[16], const double z_en_m[2], const double R_en_m2[4])
{
    double Si[4];
    if (!innovation(Si, P, R_en_m2)) return INFINITY;
    const double y0 = z_en_m[0] - x[0], y1 = z_en_m[1] - x[1];
    return y0 * (Si[0] * y0 + Si[1] * y1) + y1 * (Si[2] * y0 + Si[3] * y1);
}

bool rs_track_kf_update(double x[4], double P[16], const double z_en_m[2], const double R_en_m2[4])
{
    double Si[4];
    if (!innovation(Si, P, R_en_m2)) return false;
    // K = P H^T S^-1: (4,2)
    double K[8];
    for (int r = 0; r < 4; r++) {
        K[r * 2 + 0] = P[r * 4 + 0] * Si[0] + P[r * 4 + 1] * Si[2];
        K[r * 2 + 1] = P[r * 4 + 0] * Si[1] + P[r * 4 + 1] * Si[3];
    }
    const double y0 = z_en_m[0] - x[0], y1 = z_en_m[1] - x[1];
    for (int r = 0; r < 4; r++) x[r] += K[r * 2 + 0] * y0 + K[r * 2 + 1] * y1;
    // Joseph: P = A P A^T + K R K^T with A = I - K H
    double A[16], AP[16], Pn[16];
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++) A[r * 4 + c] = (r == c) - (c < 2 ? K[r * 2 + c] : 0);
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++) {
            double s = 0;
            for (int k = 0; k < 4; k++) s += A[r * 4 + k] * P[k * 4 + c];
            AP[r * 4 + c] = s;
        }
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++) {
            double s = 0;
            for (int k = 0; k < 4; k++) s += AP[r * 4 + k] * A[c * 4 + k];
            const double kr0 = K[r * 2 + 0], kr1 = K[r * 2 + 1], kc0 = K[c * 2 + 0], kc1 = K[c * 2 + 1];
            s += kr0 * (R_en_m2[0] * kc0 + R_en_m2[1] * kc1) + kr1 * (R_en_m2[2] * kc0 + R_en_m2[3] * kc1);
            Pn[r * 4 + c] = s;
        }
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++) P[r * 4 + c] = 0.5 * (Pn[r * 4 + c] + Pn[c * 4 + r]);
    return true;
}

void rs_track_kf_speed_heading(double *speed_mps, double *heading_deg, double *sigma_speed_mps,
                               double *sigma_heading_deg, const double x[4], const double P[16])
{
    const double ve = x[2], vn = x[3], s = hypot(ve, vn);
    const double pee = P[10], pen = 0.5 * (P[11] + P[14]), pnn = P[15];
    double h = s > 0 ? atan2(ve, vn) * RS_DEG_PER_RAD : 0;
    if (h < 0) h += 360;
    if (h >= 360) h -= 360;
    double sig_s, sig_h;
    if (s > 0) {
        const double ue = ve / s, un = vn / s;
        sig_s = sqrt(fmax(0, ue * ue * pee + 2 * ue * un * pen + un * un * pnn));
        const double ge = vn / (s * s), gn = -ve / (s * s);
        sig_h = sqrt(fmax(0, ge * ge * pee + 2 * ge * gn * pen + gn * gn * pnn)) * RS_DEG_PER_RAD;
    } else {
        sig_s = sqrt(fmax(0, 0.5 * (pee + pnn)));
        sig_h = 180;
    }
    if (!(sig_h <= 180)) sig_h = 180;
    if (speed_mps) *speed_mps = s;
    if (heading_deg) *heading_deg = h;
    if (sigma_speed_mps) *sigma_speed_mps = sig_s;
    if (sigma_heading_deg) *sigma_heading_deg = sig_h;
}

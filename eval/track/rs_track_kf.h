// rs_track_kf.h -- the constant-velocity Kalman filter of a vehicle on the site's ground, in the
// site ENU frame (docs/conventions.md), and what its state says about speed and heading.
//
// State x = (e_m, n_m, ve_mps, vn_mps), covariance P (4,4), both row-major.
// Motion: constant velocity driven by continuous white-noise acceleration of power spectral
// density q = accel_sigma^2 (m^2/s^3) on each axis (Y. Bar-Shalom, X. R. Li, T. Kirubarajan,
// "Estimation with Applications to Tracking and Navigation", Wiley 2001, section 6.2.2): over dt
//   x <- F x,  F = [I, dt I; 0, I]
//   P <- F P F^T + Q,  Q = q [dt^3/3 I, dt^2/2 I; dt^2/2 I, dt I]
// so that the velocity's standard deviation grows by accel_sigma sqrt(dt / 1 s) over dt seconds,
// whatever the steps dt is split into (two predictions of dt/2 equal one of dt, exactly up to
// rounding): the right model for cameras whose frames are not synchronous.
// Measurement: the ground point z = (e_m, n_m) of a detection, H = [I 0], with its own
// covariance R (2,2) (the located-detections CSV's sigma_e_m, sigma_n_m, cov_en_m2):
//   S = H P H^T + R,  K = P H^T S^-1,  x <- x + K (z - H x),
//   P <- (I - K H) P (I - K H)^T + K R K^T      (Joseph's form, symmetric and positive by
//                                                 construction), then symmetrised.
// Accuracy: the closed-form 2x2 inverse loses log10(cond(S)) digits; S is well conditioned for
// any R with sigmas >= 1 mm. tests/eval/track/test_track_kf.py checks the filter's reported
// states and covariances against numpy's evaluation of the same equations (worst 5e-10 m: the
// CSV's printing; tolerance 1e-8) and the normalised estimation error squared over 200 runs
// against chi-square bounds.
#pragma once
#include <stdbool.h>

#ifdef __cplusplus
extern "C" {
#endif

// A state just born from one detection: x = (z, 0, 0); P = [R, 0; 0, v0^2 I], v0 the
// standard deviation of the unknown velocity on each axis (m/s).
void rs_track_kf_init( // out
    double x[4], double P[16],
    // in
    const double z_en_m[2], const double R_en_m2[4], double init_speed_sigma_mps);

// Predicts x, P (in,out) forward by dt_s >= 0 seconds (dt_s = 0 leaves them unchanged).
void rs_track_kf_predict( // in,out
    double x[4], double P[16],
    // in
    double dt_s, double accel_sigma_mps2);

// The squared Mahalanobis distance (z - H x)^T S^-1 (z - H x) of a measurement z with covariance
// R from the predicted state; INFINITY when S is not positive definite.
double rs_track_kf_mahal2( // in
    const double x[4], const double P[16], const double z_en_m[2], const double R_en_m2[4]);

// The update by one measurement. False (x, P unchanged) when S is not positive definite.
bool rs_track_kf_update( // in,out
    double x[4], double P[16],
    // in
    const double z_en_m[2], const double R_en_m2[4]);

// Speed |v| (m/s) and heading (degrees clockwise from north, in [0, 360): atan2(ve, vn)) of the
// state, with their standard deviations by first-order propagation of P's velocity block:
//   d speed / d v = v^T / |v|,   d heading / d v = (vn, -ve) / |v|^2  (radians).
// The heading's sigma is capped at 180 degrees (a standing vehicle has no heading: speed 0
// gives heading 0 and sigma 180). All outputs may be NULL.
void rs_track_kf_speed_heading( // out
    double *speed_mps, double *heading_deg, double *sigma_speed_mps, double *sigma_heading_deg,
    // in
    const double x[4], const double P[16]);

#ifdef __cplusplus
}
#endif

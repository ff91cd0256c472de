// rs_calib_vce.h -- internal: variance components of one camera's adjustment by restricted
// maximum likelihood on the adjustment linearised at a state (calib/rs_calib_vce.c, which has the
// model and the references): the landmarks marginalised, each pick with the 2x2 covariance its
// own sigma and its survey's make. The state and the observation groups: rs_calib_noise.h.
#pragma once
#include "calib/internal/rs_calib_noise.h"
#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// The model linearised at one state (opaque).
typedef struct rs_calib__vce rs_calib__vce;
// Linearises at s, whose sigmas are the stated ones scaled by exp(log_theta_ref[group]); share
// (N,) may be NULL (rs_calib_solve_state.share). The priors' gradient in the model is their own at s
// (rs_calib__prior_gradient), and the model steps from s to its solution at each theta: s need
// not be a solution (a parameter freed, a prior changed, a robust solution, a rough solve).
// *out: free with rs_calib__vce_free.
rs_status rs_calib__vce_build(rs_calib__vce **out, const rs_calib_noise_state *s, const double *share,
                              const double log_theta_ref[RS_NOISE_NGROUPS], rs_err *err);
// The posterior mode of the log variance factors (log-normal prior: the stated sigma right to a
// factor prior_factor, 1-sigma), by Fisher scoring from log_theta (in,out), with Newton's steps
// (the observed information) once within 0.3 of a posterior 1-sigma of it, until every factor
// moves by less than 1% of its posterior 1-sigma (or 0.1% in a variance). sd_out (may be NULL):
// each log factor's posterior 1-sigma there (0 for a group without observations).
rs_status rs_calib__vce_estimate(double log_theta[RS_NOISE_NGROUPS], double sd_out[RS_NOISE_NGROUPS], rs_calib__vce *v,
                                 double prior_factor, rs_err *err);
// The camera covariance's spread over the variance factors' own posterior: dQ (nc,nc) =
// E[Q(theta)] - Q(theta_hat), Q the camera parameters' covariance (S^-1) of the linearised
// adjustment, the expectation over log theta ~ N(log_theta, (F + prior)^-1) by the unscented
// transform (Julier & Uhlmann 1997), over the groups with a redundancy of min_redundancy or more
// (the others are not estimated from the data: they keep their sigma). *pose_dof: the degrees of
// freedom of the pose covariance's scale (2 / var of its log over that posterior, at least 3;
// INFINITY when no group is estimated); *region_m2: the Mahalanobis distance^2 in the spread
// covariance's pose block within which the pose lies with probability 99.9%
// (rs_calib__pose_region_m2; 22.46, chi-square 6 dof, when pose_dof is INFINITY).
rs_status rs_calib__vce_cov_spread(double *dQ, double *pose_dof, double *region_m2, rs_calib__vce *v,
                                   const double log_theta[RS_NOISE_NGROUPS], double prior_factor, double min_redundancy,
                                   rs_err *err);
// The (1 - alpha) region of a 6-parameter estimate whose covariance's scale has nu degrees of
// freedom (INFINITY: known) and was widened by kappa (>= 1; the spread: nu / (nu - 2)) for that
// scale's uncertainty: 6 F(6, nu; 1 - alpha) / kappa (Koch 1999, 3.7.3; F by its closed form for
// an even first degree of freedom, solved to 1e-13 relative). alpha 1e-3, nu INFINITY, kappa 1:
// 22.458.
double rs_calib__pose_region_m2(double alpha, double nu, double kappa);
// The model at log_theta: the restricted log-likelihood (without the prior), q and r per group
// (r with shared survey errors once), the Fisher information F and the observed information O
// (3x3 each) in log theta. For the tests
// (tests/calib/test_vce.py checks them against the full adjustment with the landmarks as
// unknowns, in numpy).
rs_status rs_calib__vce_evaluate(rs_calib__vce *v, const double log_theta[RS_NOISE_NGROUPS], double *loglik,
                                 double q[RS_NOISE_NGROUPS], double r[RS_NOISE_NGROUPS],
                                 double F[RS_NOISE_NGROUPS * RS_NOISE_NGROUPS],
                                 double O[RS_NOISE_NGROUPS * RS_NOISE_NGROUPS], rs_err *err);
// At log_theta: the Gauss-Newton step dc (nc,) of the camera parameters from the state the model
// was built at, and their covariance Q (nc,nc) = S^-1.
rs_status rs_calib__vce_step(double *dc, double *Q, rs_calib__vce *v, const double log_theta[RS_NOISE_NGROUPS],
                             rs_err *err);
// One group without camera priors (rs_calib__scale_free): the posterior mode of its log variance
// factor L, given the chi-square chi2_0 of the least-squares solution at L = 0 (which does not
// depend on L) and the group's redundancy r. The restricted log-likelihood of a linear model
// with one variance factor is -(r L + chi2_0 e^-L) / 2 (Koch 1999, 3.6.3; what rs_calib__vce_estimate
// maximises, for one group), the prior -L^2 / (2 lp^2), lp = 2 log(prior_factor): concave, so
// Newton's steps (at most 1 each) from 0 reach the mode; within +-2 log(RS_NOISE_MAX_FACTOR).
// *sd: the posterior 1-sigma, 1 / sqrt(r / 2 + 1 / lp^2). 0 (sd 0) when prior_factor <= 1, r <= 0
// or chi2_0 is not a number.
double rs_calib__vce_one(double *sd, double chi2_0, double r, double prior_factor);
// The refined intrinsics' coordinates among its camera parameters (nc = 6 + this).
int rs_calib__vce_Nintrinsics(const rs_calib__vce *v);
// Frees v (may be NULL).
void rs_calib__vce_free(rs_calib__vce *v);

#ifdef __cplusplus
}
#endif

// rs_calib_noise.h -- internal: the noise model of one camera's adjustment -- redundancy
// numbers, variance components, Baarda's w-test and reliability (calib/rs_calib_noise.c).
// rs_calib.c drives it between plain solves (docs/calibration.md, "Noise model").
//
// The adjustment (rs_calib_refine.h) is a Gauss-Markov model whose observations are independent
// after whitening: per landmark i, the pixel (u, v) with sigma_px_i and the surveyed position
// (E, N, U) with s_i (an axis with s = 0 is held exactly: neither an observation nor a
// parameter). Parameters: the camera c (rt, 6, and the refined intrinsics with their priors) and
// each landmark's position p_i. With J the whitened Jacobian, the hat matrix H = J (J'J)^-1 J'
// gives each observation's redundancy number r = 1 - H_jj (its share of the redundancy; they sum
// to the degrees of freedom). Landmarks are eliminated per landmark (Schur complement): with A_i,
// B_i the whitened Jacobians of landmark i's 5 observations with respect to c and p_i,
// N_i = B_i'B_i, Ã_i = A_i - B_i N_i^-1 B_i'A_i, S = sum_i Ã_i'Ã_i + priors and Q_cc = S^-1:
//   H_ii = Ã_i Q_cc Ã_i' + B_i N_i^-1 B_i'     (5x5 block of landmark i)
//   dc/de_ij = Q_cc Ã_i' u_j                   (the camera's response to observation j)
// (Förstner 1979; Koch, "Parameter Estimation and Hypothesis Testing in Linear Models", 1999,
// sections 3.4 and 4.2; Niemeier, "Ausgleichungsrechnung", 2008, chapter 13.)
#pragma once
#include <mrcal/mrcal.h>
#include <stdbool.h>
#include <stddef.h>

#include "calib/internal/rs_calib_refine.h"
#include "calib/rs_calib.h"
#include "core/rs_pose.h"
#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// The components of a landmark's observations, in this order.
enum { RS_NOISE_U, RS_NOISE_V, RS_NOISE_E, RS_NOISE_N, RS_NOISE_UP, RS_NOISE_NCOMP };

// The variance component groups of one camera: its pixel picks, the survey's horizontal and
// vertical coordinates.
enum { RS_NOISE_PIXEL, RS_NOISE_SURVEY_H, RS_NOISE_SURVEY_V, RS_NOISE_NGROUPS };

// The adjustment at its solution, in the frame centred on the landmarks (rs_calib_refine.h).
typedef struct {
    int N;
    const double *rt_cam_c;     // (6,)
    const double *p_c_m;        // (N,3) adjusted landmark positions
    const double *p_survey_c_m; // (N,3) surveyed positions
    const double *sigma_enu_m;  // (N,3) survey 1-sigma in use (scaled); 0: held. May be NULL: all held
    const double *q_px;         // (N,2) observed pixels
    const double *sigma_px;     // (N,) pixel 1-sigma in use (scaled). May be NULL: 1 px
    const bool *use;            // (N,) landmarks in the adjustment
    const double *along_c;      // (N,3) direction of a landmark picked along a segment, 0: a point;
                                //   may be NULL (rs_calib_refine.h)
    const double *s_along_m;    // (N,) its offset along it: the seen point is p_c + s d
    const mrcal_lensmodel_t *lensmodel;
    const double *intrinsics;         // (Nintrinsics,) at the solution
    const double *intrinsics_nominal; // (Nintrinsics,) the focal scale's reference
    unsigned refine;                  // rs_calib_refine_flags: which intrinsics are parameters
    double focal_prior_rel_sigma, center_prior_sigma_px, distortion_prior_sigma; // 0: no prior
    bool has_position_prior;
    double prior_sigma_m;
    const double *prior_position_c_m; // (3,) the position prior's centre
} rs_calib_noise_state;

// Per landmark and component (N, RS_NOISE_NCOMP): the whitened residual e (observation minus
// adjusted value over its sigma, as used), the redundancy number r in [0, 1], and the shift of
// the camera position (3, metres) and of the ground point on the optical axis (2, E N metres)
// per unit whitened error of that observation (an error of one sigma). Unused landmarks and held
// axes: all 0. Per landmark NOT in the adjustment, chi2_excluded: the 2-dof chi-square of its pick
// against the adjusted camera, r' (sigma_px^2 I + J_p S J_p' + G Q_cc G')^-1 r with r the pixel
// residual at its surveyed position, S its survey variances, J_p = dq/dp, G = dq/dc and Q_cc the
// camera's covariance: the test of a landmark against a model fitted without it (Baarda's w^2
// of its pick were it in, 2 dof; Koch 1999, 4.4); NAN where it does not project and for the
// landmarks in. Any output may be NULL.
typedef struct {
    double *e, *r;         // (N,5)
    double *dpos_m;        // (N,5,3)
    double *dground_m;     // (N,5,2) NAN when the optical axis does not meet the ground
    double *chi2_excluded; // (N,)
} rs_calib_noise_out;

// The camera parameters of the adjustment: rt, then the refined intrinsics. For each, the
// column of dq/dc it is (a combination of mrcal's dq/dintrinsics) and its prior's weight.
enum { RS_NOISE_NC_MAX = 6 + 1 + 2 + 64 }; // rt, focal scale, centre, distortion
typedef struct {
    int nc;
    int Ni;                          // the lens model's intrinsics
    int kind[RS_NOISE_NC_MAX];       // -1: rt; -2: the focal scale; j >= 0: intrinsics[j]
    double prior_w[RS_NOISE_NC_MAX]; // 1/sigma of the parameter's prior, 0: none
    rs_pose_prepared pose;           // the state's rt_cam_c, prepared for many points
} rs_calib__params;
void rs_calib__camera_params(rs_calib__params *pp, const rs_calib_noise_state *s);

// Adds the camera priors' normal matrix (the intrinsics' priors, the position prior) to S (nc,nc).
void rs_calib__prior_normal(double *S, const rs_calib__params *pp, const rs_calib_noise_state *s);
// The camera priors' gradient gamma (nc,) at the state s: the position prior's and each refined
// intrinsic's, w^2 (x - nominal) (the focal scale's in relative units).
void rs_calib__prior_gradient(double *gamma, const rs_calib__params *pp, const rs_calib_noise_state *s);

// The ground point g (E, N) of the optical axis on the plane up = 0 of the centred frame, and
// G (2,6) = dg/drt (analytic); false (G NAN) when the axis does not come down to it. The
// external reliability on the ground (rs_calib_result.external_ground_m) is G times the
// camera's response. (tests/calib/test_axis_ground.c checks G against central differences.)
bool rs_calib__axis_ground(double g[2], double G[12], const double rt[6]);

// The pixel q_px (2,) of the point seen (3, centred frame) at the state s, its derivatives with
// respect to the camera parameters G (2,pp->nc) and to the point J (2,3), and mrcal's
// intermediate dpc_dp (3,3) and dq_dpc; dq_dintr: scratch (2,pp->Ni). false: it does not
// project.
bool rs_calib__pixel_jacobian(double q_px[2], double *G, double J[6], double dpc_dp[9], mrcal_point3_t dq_dpc[2],
                              const rs_calib_noise_state *s, const rs_calib__params *pp, const double seen[3],
                              double *dq_dintr);

// Fills out for the state s. Errors: RS_ERR_DEGENERATE (the normal matrix is singular: the
// camera is not determined), RS_ERR_EXTERNAL (OpenCV threw), RS_ERR_NOMEM.
rs_status rs_calib__noise_redundancy(const rs_calib_noise_out *out, const rs_calib_noise_state *s, rs_err *err);

// Variance factors stay within this factor of the stated sigma either way: beyond, the stated
// sigma was no statement (and a noise-free simulated survey would drive its variance to 0).
#define RS_NOISE_MAX_FACTOR 30.0

// The point landmark i is seen at: p_c_m[i] + s_along_m[i] along_c[i] (p_c_m[i] for a point).
// Returns whether the landmark slides along a segment (then d receives the direction).
bool rs_calib__seen_point(double seen[3], double d[3], const double *p_c_m, const double *along_c,
                          const double *s_along_m, int i);

// The whitened pixel rows' derivative (2,) with respect to moving the seen point along dir (3,):
// (dq/dp_cam dp_cam/dp dir) / sigma_px. One free survey axis (dir a unit axis) or a slide along
// a segment (dir its direction): a column of a landmark's block B.
void rs_calib__position_column(double col[2], const mrcal_point3_t dq_dpc[2], const double dpc_dp[9],
                               const double dir[3], double sigma_px);

// Variance components by restricted maximum likelihood on the adjustment linearised at the state
// s (rs_calib_vce.c, which has the model and the references): the landmarks marginalised, each
// pick with the 2x2 covariance its own sigma and its survey's make.
typedef struct rs_calib__vce rs_calib__vce;
// Linearises at s, whose sigmas are the stated ones scaled by exp(log_theta_ref[group]); share
// (N,) may be NULL (rs_calib__work). The priors' gradient in the model is their own at s
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
void rs_calib__vce_free(rs_calib__vce *v);

// ---- the solve's side (rs_calib_noise_model.c; driven by rs_calib.c) ----

// rs_calib_solve's scratch, (N,) arrays unless said.
typedef struct {
    double *p_survey_c, *p_c, *cov, *block_chi2, *q_pred;
    bool *use;
    double *sigma_px, *sigma_enu;       // (N,), (N,3): the sigmas in use (stated, scaled by the noise model)
    double *along_c, *s_along;          // (N,3), (N,): landmarks picked along segments (rs_calib_refine.h);
                                        //   NULL when the problem has none
    double *share;                      // (N,) how many picks share the landmark's survey error (>= 1)
    double *e, *r, *dpos, *dground;     // (N,5), (N,5), (N,5,3), (N,5,2): rs_calib_noise_out
    double *chi2_excluded;              // (N,): rs_calib_noise_out, at the noise model's last state
    bool snooped;                       // e, r, dpos, dground are the noise model's last, where data
                                        //   snooping stopped, on the landmarks in use
    int Ngross;                         // landmarks the robust stage (gross outliers) rejected
    double log_theta[RS_NOISE_NGROUPS]; // the noise model's variance factors at the solution
    // One noise group and no camera priors (the survey exact, no intrinsics refined, no
    // position prior, no picks along segments): the least-squares solution does not depend on
    // the variance factor (rs_calib__scale_free). Then, where the initial pose agreed with
    // every landmark, the robust stage starts from that solution (ls_valid, rt_ls: found on
    // every landmark), and the noise model takes it instead of solving again.
    bool scale_free, ls_valid;
    double rt_ls[6], chi2_ls0; // and its chi-square at the stated sigmas
} rs_calib__work;

// True when pb's least-squares solution does not depend on the variance factors: one noise
// group (the pixels: every survey sigma 0), no intrinsics refined, no position prior, no picks
// along segments.
bool rs_calib__scale_free(const rs_calib_problem *pb, const rs_calib_options *opt);

// A solve started from another solve's adjustment of the same problem (the intrinsics check's
// alternative with the focal free, rs_calib_intrinsics.c): the pose rt_c (6,) in the centred
// frame (the same landmarks, so the same centroid), the intrinsics (Ni,) it was found with and the
// adjusted landmarks p_c (N,3) are its start, instead of the initial pose (RANSAC and the focal
// search); the robust stage, the noise model and data snooping run as in any solve (starting from
// the first solve's verdict instead lost 54 of 342 significant focal errors in 358 simulated
// problems: a wrong focal makes the first solve reject good landmarks). No reliability figures,
// no intrinsics check and no spread of the pose covariance over the variance factors: the check
// reads only the alternative's intrinsics, their covariance (which that spread leaves alone) and
// its degrees of freedom.
// `no_gross`: the first solve's robust stage found no gross outlier, so this one starts its noise
// model from every landmark without a robust stage (a model with one more parameter fits the
// same landmarks at least as well as a whole; data snooping still runs), its variance factors
// from log_theta (RS_NOISE_NGROUPS,) if not NULL.
typedef struct {
    const double *rt_c, *intrinsics, *p_c;
    bool no_gross;
    const double *log_theta;
} rs_calib__warm;
// rs_calib_solve from `from` (not NULL). Same contract as rs_calib_solve otherwise.
rs_status rs_calib__solve_warm(rs_calib_result *result, const rs_calib_problem *problem, const rs_calib_options *opt,
                               const rs_calib__warm *from, rs_err *err);

// The sigmas in use: the problem's stated sigmas scaled by exp(log_theta[group]).
void rs_calib__scale_sigmas(rs_calib__work *w, const rs_calib_problem *pb, const double log_theta[RS_NOISE_NGROUPS]);
// The group of an observation component (RS_NOISE_U ... RS_NOISE_UP).
int rs_calib__noise_group(int component);
// The redundancy number of landmark i's component j as the variance components count it: a
// survey component shared by k picks (problem.survey_shared) counts 1/k.
double rs_calib__vce_redundancy(const rs_calib__work *w, int i, int j);
// Median of x (n,), using scratch (n,); NAN for n = 0.
double rs_calib__median(const double *x, int n, double *scratch);
// 3b of rs_calib_solve: variance components to convergence alternating with Baarda's data
// snooping (one landmark at a time, opt->snooping_critical; stops before rejecting more than
// opt->max_rejected_fraction and sets res->noise_model_wrong). in,out: rt_c, w's landmarks, use
// and sigmas, log_theta, *Noutliers.
rs_status rs_calib__noise_model(rs_calib_result *res, rs_calib__work *w, const rs_calib_refine_problem *rp,
                                const rs_calib_refine_options *ro, double rt_c[6], double log_theta[RS_NOISE_NGROUPS],
                                int *Noutliers, const rs_calib_problem *pb, const rs_calib_options *opt, rs_err *err);
// The coarse outlier test's rejections (step 3 of rs_calib_solve), tested again at the noise the
// model estimated: that test had one scale for every group and cannot tell whose noise a
// residual is (a survey stated 5x too precise lost 2.85% of its good landmarks there), and a noise
// estimated without them is low (their tails are cut). A landmark whose 2-dof chi-square
// (chi2_excluded, rs_calib_noise_out) is now below RS_CALIB_READMIT_FACTOR times the coarse limit comes
// back, rs_calib__noise_model, whose data snooping is the fine test, runs again and decides, and
// so on while landmarks come back (RS_CALIB_READMIT_ROUNDS at most: the noise estimate rises as
// they do). Not when more than opt->max_rejected_fraction are out (the snooping could not reject
// them again). The factor trades false alarms against moderate outliers let back to mask each
// other (tests/calib/test_noise_model.c, docs/calibration.md 3c): 1.5 keeps clean data with
// mis-stated sigmas under 0.5% flagged. in,out as rs_calib__noise_model's.
#define RS_CALIB_READMIT_FACTOR 1.5
#define RS_CALIB_READMIT_ROUNDS 3
rs_status rs_calib__readmit(rs_calib_result *res, rs_calib__work *w, const rs_calib_refine_problem *rp,
                            const rs_calib_refine_options *ro, double rt_c[6], double log_theta[RS_NOISE_NGROUPS],
                            int *Noutliers, const rs_calib_problem *pb, const rs_calib_options *opt, rs_err *err);
// The landmarks in use that lie behind the camera at rt_c (their adjusted, seen positions): each
// leaves (use false, back at its survey), counted in *Nbehind; an
// error instead when `last` or when fewer than 4 of the Ninliers would remain. A pick and a
// survey that agree only behind the camera are a blunder: a large survey sigma lets the
// adjustment move the landmark there, where points project too.
rs_status rs_calib__reject_behind(int *Nbehind, const rs_calib_result *res, rs_calib__work *w, const double rt_c[6],
                                  int Ninliers, bool last, rs_err *err);
// The noise groups (res->noise) and each landmark's w, redundancy, MDBs and external
// reliability at the final adjustment.
rs_status rs_calib__reliability(rs_calib_result *res, rs_calib__work *w, const rs_calib_refine_problem *rp,
                                const double rt_c[6], const double log_theta[RS_NOISE_NGROUPS],
                                const rs_calib_problem *pb, const rs_calib_options *opt, rs_err *err);
// Landmarks picked along poles and lines (rs_calib_along.c). Whether landmark i is one:
bool rs_calib__is_along(const rs_calib_problem *pb, int i);
// Checks pb->along (RS_ERR_INVALID naming the landmark); *Npoints: the point landmarks.
rs_status rs_calib__along_validate(int *Npoints, const rs_calib_problem *pb, rs_err *err);
// The point landmarks of pb alone (for the initial pose): *sub is pb itself when it has no along
// picks, else it points into *buffer (owned by the caller, free() it; NULL when not needed).
rs_status rs_calib__point_problem(rs_calib_problem *sub, double **buffer, const rs_calib_problem *pb, rs_err *err);
// For each along landmark, the segment its pick is on at the pose rt_c (centred frame, centroid
// c): sets w's p_survey_c and p_c to the point of the segment nearest the pick's ray, along_c to
// the segment's direction and s_along to 0.
void rs_calib__along_choose(rs_calib__work *w, const rs_calib_problem *pb, const double c[3], const double rt_c[6],
                            const double *intrinsics);

// Adds to w->cov (n,n: the camera parameters' covariance of the final solve) its spread over the
// variance factors' posterior (rs_calib__vce_cov_spread) at the state of w.
// Also sets res->pose_dof and res->region_m2 (rs_calib.h). RS_ERR_DEGENERATE when the spread
// pose block is not positive definite (the final solve's covariance and the variance components'
// linearisation disagree: the landmarks do not determine the noise).
rs_status rs_calib__cov_spread(rs_calib__work *w, const rs_calib_refine_problem *rp, const double rt_c[6],
                               rs_calib_result *res, const double log_theta[RS_NOISE_NGROUPS], int n,
                               const rs_calib_options *opt, rs_err *err);

// The noise model's solves per round of data snooping, at most (rs_calib__noise_model). Where the
// factors do not settle -- on hard problems of `roadside bench calib --stress` (half the
// landmarks outliers, survey sigmas of metres) they can alternate between two basins for good --
// the round ends at the last estimate: on 15,000 such problems, ending one solve earlier (an odd
// count of solves instead of an even one) left 95 poses failing that had not and mended 54.
#define RS_CALIB_NOISE_SOLVES 10

// The variance factors' posterior mode (rs_calib__vce_estimate) on the landmarks in w->use at the
// state of w, whose sigmas are the stated ones scaled by log_theta: next (in: the start, out),
// sd (may be NULL) as rs_calib__vce_estimate's; the state need not be a solution
// (rs_calib__vce_build).
rs_status rs_calib__vce_at(double next[RS_NOISE_NGROUPS], double sd[RS_NOISE_NGROUPS], const rs_calib_result *res,
                           const rs_calib__work *w, const rs_calib_refine_problem *rp, const double rt_c[6],
                           const double log_theta[RS_NOISE_NGROUPS], const rs_calib_options *opt, rs_err *err);

// The intrinsics check's alternative (rs_calib_intrinsics.c): the model of the solution at rt_c
// and res->intrinsics, on the landmarks in w->use, with the focal free (a weak prior, 100%) and
// the variance factors estimated again (so that what a wrong focal left in the residuals is not
// taken for survey noise), solved by Gauss-Newton on the adjustment linearised at the surveyed
// landmarks (rs_calib_vce.c), relinearised until the focal's step is below
// RS_CALIB_ALTERNATIVE_TOL of its sigma. *k_rel: the focal relative to the nominal, minus 1;
// *Q_rel: its variance. RS_ERR_NOCONVERGE, RS_ERR_DEGENERATE (the focal is not determined).
#define RS_CALIB_ALTERNATIVE_ITERATIONS 20
#define RS_CALIB_ALTERNATIVE_TOL        1e-2
rs_status rs_calib__focal_alternative(double *k_rel, double *Q_rel, const rs_calib_result *res, const rs_calib__work *w,
                                      const rs_calib_refine_problem *rp, const double rt_c[6],
                                      const rs_calib_options *opt, rs_err *err);
// w->e and w->r (rs_calib_noise_out) at the state of w.
rs_status rs_calib__redundancy_at(const rs_calib_result *res, rs_calib__work *w, const rs_calib_refine_problem *rp,
                                  const double rt_c[6], const rs_calib_options *opt, rs_err *err);
// An observation with a smaller redundancy number is all but uncontrolled: its w would be
// noise over noise (its minimal detectable bias is over 18 sigma); it is neither tested nor
// counted in a robust scale.
#define RS_CALIB_MIN_TESTABLE_R 0.05

// Steps 2 and 3 of rs_calib_solve (rs_calib_robust.c): the robust solve (ro, Cauchy's loss) on
// every landmark from rt_c; with opt->estimate_noise, the variance factors log_theta (in,out) from
// the data -- a common one from the median block chi2, then each group's from the variance
// components of the landmarks that agree at that scale, corrected for the trimming, the robust
// solve again at those sigmas, until they settle; then the coarse test: a landmark whose block
// chi2 exceeds opt->outlier_threshold^2 leaves (w->use false, back at its survey, w_test NAN),
// counted in *Noutliers. Along picks choose their segment (c: the centred frame's origin) at the
// robust pose. desc (desc_size): the method's description of this stage.
// With w->scale_free and init_all (the initial pose agreed with every landmark), the robust
// solve starts from the least-squares solution on every landmark, kept in w->rt_ls.
rs_status rs_calib__robust_stage(int *Noutliers, double log_theta[RS_NOISE_NGROUPS], double rt_c[6],
                                 rs_calib_result *res, rs_calib__work *w, const rs_calib_refine_problem *rp,
                                 const rs_calib_refine_options *ro, const rs_calib_problem *pb,
                                 const rs_calib_options *opt, const double c[3], bool init_all, char *desc,
                                 size_t desc_size, rs_err *err);

#ifdef __cplusplus
}
#endif

// rs_calib_noise.h -- internal: the redundancy numbers of one camera's adjustment, the
// whitened residuals Baarda's w-test reads and the camera's response to each observation (its
// reliability) (calib/rs_calib_noise.c). The variance components that share its model:
// rs_calib_vce.h; the noise model's place in the solve: rs_calib_noise_model.h
// (docs/calibration.md, "Noise model").
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

// The group (RS_NOISE_PIXEL ...) of an observation component (RS_NOISE_U ... RS_NOISE_UP).
int rs_calib__noise_group(int component);

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

// Sets pp for the state s: rt, then s->refine's intrinsics with their priors' weights, and
// s->rt_cam_c prepared.
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
#ifdef __cplusplus
}
#endif

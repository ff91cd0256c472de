// rs_calib.h -- one camera's pose (and optionally intrinsics) from surveyed landmarks and their
// clicked pixels, with an honest uncertainty. The public solver API of roadside.
//
// Purpose: given N landmarks surveyed in the site's ENU frame (each with its own survey sigma)
// and the pixels where they are seen, return the camera's pose rt_cam_enu, its 6x6 covariance,
// the camera position and yaw/pitch/roll with sigmas, the outliers, and plain-words warnings
// when the geometry is weak. Works for every mrcal lens model (CAHVORE's gradients from core/rs_lens.h).
//
// Method (docs/calibration.md has it end to end, with references):
//   1. Initial pose: rs_calib_init_pose() (RANSAC over P3P, then EPnP or planar IPPE). When
//      the focal length is refined, a 1-D search over a focal scale drives rs_calib_init_pose()
//      and keeps the scale with the smallest robust reprojection cost.
//   2. Refinement (errors in variables; Ceres' TinySolver on the variable-projection problem,
//      calib/rs_calib_refine_ceres.cc): parameters are rt (6), every landmark's ENU
//      position (3, held to its survey by a prior (p - p_survey)/sigma per axis; sigma 0 holds
//      that axis exactly) and optionally a subset of the intrinsics (with priors). Residual
//      (rs_lens_project(transform_rt(p)) - q_obs) / sigma_px with analytic Jacobians from mrcal.
//      Cauchy loss of scale opt->robust_scale on each landmark's normalised block (pixel +
//      survey prior). All in coordinates centred on the landmarks' centroid.
//   3. Outliers: a landmark whose block chi2 (2 dof) exceeds opt->outlier_threshold^2 is
//      flagged and dropped; the inliers are re-solved under the same loss at the sigmas in use
//      (the estimated ones, 3b): an M-estimate whose weights are result.weight.
//   3b. Noise model (rs_calib_noise.c, docs/calibration.md 3a-3c): the coarse rule of 3 at the
//      scale the data shows; variance components of the picks, the survey's horizontal and
//      vertical coordinates (Förstner's iteration on redundancy numbers, the stated sigmas as a
//      log-normal prior) alternating with Baarda's data snooping (w-test, one landmark at a
//      time, at most a quarter); per landmark w, redundancy, minimal detectable biases and
//      external reliability in the result.
//   3c. Intrinsics (rs_calib_intrinsics.c, docs/calibration.md 7a): a stated uncertainty
//      (problem.focal_rel_sigma, center_sigma_px) makes them parameters with that prior; then
//      the image's own estimate of the focal and centre is tested against the statement, and a
//      focal held exact that the landmarks cannot check is named in the warnings.
//   4. Covariance of rt (and the refined intrinsics) with the landmarks marginalised: the
//      inverse of the reduced problem's Gauss-Newton matrix (exactly the Schur complement),
//      from the QR and SVD of its column-equilibrated Jacobian; ABSOLUTE scaling (residuals
//      whitened by the estimated sigmas, at their posterior mean); the a-posteriori variance
//      factor chi2/dof is reported next to it.
//
// Conventions (docs/conventions.md): rt_cam_enu = mrcal Rodrigues r + translation t (metres),
// p_cam = R(r) p_enu + t; camera x right, y down, z forward; pixel (0,0) is the centre of the
// top-left pixel. yaw/pitch/roll in degrees: R_enu_cam = Rz(-yaw) Rx(pitch) R_enu_cam0 Rz(roll)
// with R_enu_cam0 a level camera looking north; yaw in [0,360) clockwise from north, pitch
// positive up, roll in (-180,180] positive clockwise seen from behind the camera.
//
// Accuracy: noise-free observations give the true pose to 1e-9 (relative); with noise the
// reported covariance is consistent with the errors (tests/calib/test_solve_nees.c: mean NEES
// of the 6-dof pose within [0.7,1.3] x 6 over 200+ trials).
#pragma once
#include <mrcal/mrcal.h>
#include <stdbool.h>

#include "core/rs_camera.h"

#include "calib/rs_calib_init.h"
#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// Which intrinsics rs_calib_solve refines (OR of flags). Needs a lens model with a core
// (fx, fy, cx, cy). FOCAL refines ONE focal scale: fx and fy move together, their ratio (the
// pixel aspect) stays nominal, because one view of 10-30 landmarks cannot separate them.
// CENTER refines (cx, cy). DISTORTION refines every intrinsic after the core.
typedef enum {
    RS_CALIB_REFINE_NONE = 0,
    RS_CALIB_REFINE_FOCAL = 1,
    RS_CALIB_REFINE_CENTER = 2,
    RS_CALIB_REFINE_DISTORTION = 4,
} rs_calib_refine_flags;

// A landmark picked anywhere along a polyline (docs/calibration.md, "Poles and lines"): a pole's
// segment from its base to its top, or a surveyed line (a lane marking, a stop bar, a kerb). The
// pick's residual is its distance to the projected polyline: the solver slides the landmark's
// point along the segment the pick is nearest to, so only the across-segment error counts.
typedef struct {
    int Nvertices;         // >= 2; 0: the landmark is a point (p_enu_m)
    const double *p_enu_m; // (Nvertices,3) its surveyed vertices, site ENU, metres; consecutive
                           //   vertices distinct. Their survey sigma is the landmark's sigma_enu_m
} rs_calib_polyline;

// One camera's observations.
typedef struct {
    int N;                          // number of landmarks observed by this camera
    const double *p_enu_m;          // (N,3) surveyed landmark positions, site ENU, metres
    const double *sigma_enu_m;      // (N,3) 1-sigma survey error of E, N, U, metres, >= 0;
                                    //   0 holds that coordinate exactly; NULL: all exact
    const double *q_px;             // (N,2) observed pixels
    const double *sigma_px;         // (N,) 1-sigma of each pixel coordinate, > 0; NULL: 1 px
    const rs_calib_polyline *along; // (N,) NULL: every landmark is a point. along[i].Nvertices
                                    //   >= 2: pick i is anywhere along that polyline, and
                                    //   p_enu_m[i] is one of its points (for the centroid only).
                                    //   The initial pose needs 4 point landmarks (points, poles'
                                    //   bases and tops); picks along refine it
    const int *survey_shared;       // (N,) NULL: every landmark's survey error is its own. Picks
                                    //   with the same id >= 0 share one (a pole's base, top and
                                    //   along picks; the picks along one line); -1: its own. The
                                    //   solver widens the survey sigmas of k sharing picks by
                                    //   sqrt(k) (an upper bound of the true covariance) and counts
                                    //   them once in the variance components
    const rs_camera *camera;        // the lens model, its NOMINAL intrinsics and the image
                                    //   size (for warnings; may be 0: unknown); its pose is
                                    //   not used
    bool has_position_prior;        // a surveyed camera position (a pole) is known
    double prior_position_enu_m[3]; //   its ENU position, metres
    double prior_sigma_m;           //   its isotropic 1-sigma, metres, > 0
    // How well the nominal intrinsics are known (docs/calibration.md, "Intrinsics with
    // uncertainty"); 0 (the default): exact. A stated sigma makes that intrinsic a parameter of
    // the adjustment with this prior, so that the pose's covariance includes it; the result's
    // intrinsics_check says whether the image agrees with the statement.
    double focal_rel_sigma; // 1-sigma of the focal length (fx and fy together), relative to the
                            //   nominal (0.1: known to 10%), in [0, 1]
    double center_sigma_px; // 1-sigma of the principal point (cx and cy each), px, in [0, 1e4]
} rs_calib_problem;

typedef struct {
    unsigned refine;                           // OR of rs_calib_refine_flags (default RS_CALIB_REFINE_NONE)
    double robust_scale;                       // Cauchy loss scale on each landmark's normalised residual
                                               //   block (pixel + survey prior), in sigmas (default 2);
                                               //   <= 0: no robust loss and no outlier rejection
    double outlier_threshold;                  // flag a landmark when sqrt(block chi2) > this, in sigmas
                                               //   (default 3.717 = sqrt of the 99.9% chi-square 2 dof)
    rs_calib_init_options init;                // options of the initial pose (rs_calib_init.h)
    int max_iterations;                        // Ceres iterations per solve (default 500; a well-posed
                                               //   problem needs 5-20, narrow valleys a few hundred)
    double focal_prior_rel_sigma;              // prior on the focal scale about the nominal, relative
                                               //   1-sigma (default 1.0: weak); 0: no prior
    double center_prior_sigma_px;              // prior on (cx, cy) about nominal, px (default 50); 0: none
    double distortion_prior_sigma;             // prior on each distortion coefficient about nominal, in
                                               //   its own unit (default 0.1); 0: none
    double focal_search_min, focal_search_max; // range of the focal scale search (default
                                               //   0.25, 4); min == max == 1 disables the search.
                                               //   With it and 12 landmarks or fewer, the whole solve
                                               //   runs from every scale's pose and the ground
                                               //   homography's, the best kept (docs/calibration.md
                                               //   section 1, "every start")
    double condition_warn;                     // warn when the condition number exceeds this (default 100;
                                               //   well-spread road scenes give 1.5-10)
    double sigma_rotation_warn_deg;            // warn when a yaw/pitch/roll sigma exceeds this (default 2):
                                               //   the covariance is a first-order approximation, and the stress run
                                               //   (issue 3) found poses this loose more than 10 sigmas off
    // The noise model (docs/calibration.md, "Noise model"):
    bool estimate_noise;          // estimate the noise from the data: variance components of the
                                  //   pixel picks, the survey's horizontal and vertical coordinates
                                  //   (default true); false: the stated sigmas are taken as exact
    double noise_prior_factor;    // the stated sigmas are right to within this factor (1-sigma, default
                                  //   5): the log-normal prior that keeps a small survey from
                                  //   collapsing. On the real GNSS data 5 gives leave-one-out medians
                                  //   of 1.66, 1.53, 1.60 m for the first three sigma sets; on
                                  //   simulated sites estimates within 12% with groups stated 5x off
                                  //   (tests/calib/test_noise_model.c, docs/calibration.md 3b)
    double noise_min_redundancy;  // a group with less partial redundancy is not estimated from the
                                  //   data: it rests on its prior (the stated sigma) and is not spread
                                  //   in the covariance (default 2)
    double snooping_critical;     // Baarda's w-test: reject the landmark with the largest |w| above this,
                                  //   one at a time (default 3.29: alpha 0.1% two-sided per observation)
    double max_rejected_fraction; // snooping stops before rejecting more than this fraction of the
                                  //   landmarks and says that the noise model is wrong (default 0.25)
} rs_calib_options;

// The variance component groups of one camera (rs_calib_result.noise).
enum { RS_CALIB_NOISE_PIXEL, RS_CALIB_NOISE_SURVEY_H, RS_CALIB_NOISE_SURVEY_V, RS_CALIB_NOISE_NGROUPS };

// One group's noise: stated, and estimated from the residuals with their redundancy numbers.
typedef struct {
    double stated;            // RMS of the stated 1-sigmas of the group's observations in the final
                              //   adjustment (px for pixels, m for the survey)
    double estimated;         // the 1-sigma used for the pose and its covariance (px or m): the
                              //   posterior mode of the group's variance factor
    double sigma_estimated;   // 1-sigma of `estimated` (from the redundancy and the prior); 0 if kept
    double redundancy;        // the group's partial redundancy: the sum of its redundancy numbers
    int Nobservations;        // its observations (pixel coordinates, or surveyed coordinates not held)
    bool estimated_from_data; // false: redundancy below noise_min_redundancy (or estimation off):
                              //   `estimated` rests mostly on the prior, the stated sigma
} rs_calib_noise_group;

// Fills opt with the defaults above. opt must not be NULL.
void rs_calib_options_default(rs_calib_options *opt);

// What the image says about the intrinsics that were held (stated exact) or constrained by a
// stated sigma: the picks and the survey alone, linearised at the solution (docs/calibration.md,
// "Intrinsics with uncertainty"; calib/internal/rs_calib_intrinsics.h has the method). The focal
// and the centre are tested apart, each at alpha 0.1%; an intrinsic refined at the caller's
// request (rs_calib_options.refine) is not tested.
typedef struct {
    bool focal_tested;         // false: focal refined on request, no (fx, fy, cx, cy) core, or the
                               //   test could not be made (the fields below are then 0)
    double focal_rel;          // the data's f / f_nominal - 1 (0.28: the image says 28% longer)
    double sigma_focal_rel;    //   its 1-sigma from the data alone
    double focal_stated_rel;   //   the stated 1-sigma (problem.focal_rel_sigma; 0: exact)
    double chi2_focal;         //   focal_rel^2 / (sigma^2 + stated^2): significant above
    double critical_focal;     //   this (alpha 0.1%: F(1, dof) of the fit with the focal free;
                               //   10.83, chi-square 1 dof, for a large dof)
    bool center_tested;        // likewise for the principal point
    double center_px[2];       // the data's (cx, cy) - nominal, px
    double sigma_center_px[2]; //   their 1-sigma from the data alone
    double center_stated_px;   //   the stated 1-sigma (problem.center_sigma_px; 0: exact)
    double chi2_center;        //   likewise (2 dof), significant above
    double critical_center;    //   this (2 F(2, dof) at 99.9%; 13.82 for a large dof)
    // A focal taken as exact (nothing stated): how much the pose rests on it (Baarda's external
    // reliability): the smallest focal error the test finds with power 80% (its MDB), and what
    // it does to the pose. 0 when the focal is stated, refined or not tested.
    double focal_mdb_rel;      // the minimal detectable focal error, relative (4.13 sigma)
    double shift_position_m;   //   how far an error of that size moves the camera centre, m
    double shift_mahalanobis2; //   that pose change in the reported covariance (6 dof): above
                               //   region_m2 the pose's 99.9% region does not cover it
    bool warned;               // the warnings say the pose may be wrong because of the intrinsics
} rs_calib_intrinsics_check;

typedef struct {
    double rt_cam_enu[6];             // the pose: maps ENU into the camera frame
    double covariance_rt_cam_enu[36]; // (6,6) row-major covariance of rt_cam_enu (r rad, t m)
    int Nintrinsics;
    double *intrinsics;                 // (Nintrinsics,) final intrinsics (owned)
    double *sigma_intrinsics;           // (Nintrinsics,) 1-sigma, 0 for those not refined (owned)
    double *covariance_intrinsics;      // (Nintrinsics,Nintrinsics) row-major (owned)
    double position_enu_m[3];           // camera centre in ENU, metres
    double sigma_position_enu_m[3];     // its 1-sigma in E, N, U, metres
    double yaw_pitch_roll_deg[3];       // orientation, degrees (conventions above)
    double sigma_yaw_pitch_roll_deg[3]; // their 1-sigma, degrees
    double rms_px;                      // RMS reprojection error of the inliers (pixel part), px
    int Ninliers;
    int N;                       // copy of problem->N: the length of the arrays below
    double *predicted_px;        // (N,2) projection of each landmark (refined position for
                                 //   inliers, surveyed for outliers) (owned)
    double *residual_px;         // (N,2) predicted_px - q_px (owned)
    double *normalised_residual; // (N,) sqrt(block chi2) in sigmas, the outlier statistic
                                 //   (owned)
    bool *inlier;                // (N,) (owned)
    double *p_enu_refined_m;     // (N,3) landmark positions after the adjustment (owned)
    double chi2;                 // sum of squared whitened residuals of the final solve
    int dof;                     // residuals - free parameters of the final solve
    double variance_factor;      // chi2/dof: ~1 when the stated sigmas are right
    double condition_number;     // of the equilibrated Jacobian, landmarks eliminated
    double region_m2;            // the pose's 99.9% confidence region: the true pose lies within
                                 //   d' C^-1 d <= region_m2 (C = covariance_rt_cam_enu, d the error
                                 //   of rt_cam_enu) with probability 0.999. 22.46 (chi-square 6
                                 //   dof) when the noise is as stated; larger when it is estimated
                                 //   from the data: 6 F(6, pose_dof) over the covariance's widening
                                 //   for that estimate (docs/calibration.md, "Noise model")
    double pose_dof;             // the degrees of freedom of the covariance's scale: the
                                 //   redundancy the estimated noise rests on, as it bears on the
                                 //   pose (INFINITY when no noise is estimated from the data)
    int iterations;              // Ceres iterations, all solves together
    double time_us;              // wall time of rs_calib_solve, microseconds
    char method[224];            // what was done, e.g. "opengv-p3p ... + ceres-cauchy(2)..."
    char warnings[2048];         // plain-words warnings, "; "-separated (a "; " inside parentheses
                                 //   belongs to its warning: rs_calib_warning_len); "" when none
                                 //   (2048: the intrinsics warning, 7a, comes first, ~350 bytes)

    rs_calib_noise_group noise[RS_CALIB_NOISE_NGROUPS]; // the noise model (RS_CALIB_NOISE_*)
    // Per landmark (N,), at the final adjustment (docs/calibration.md, "Outliers and reliability");
    // alpha 0.1%, power 80% (delta0 = 4.13) for the minimal detectable biases. Owned.
    double *w_test;            // Baarda's w: the largest |standardized residual| among the landmark's
                               //   observations (pixel u, v; surveyed E, N, U); for a landmark rejected by
                               //   data snooping, the w it was rejected at; NAN for a gross outlier
    double *redundancy;        // the sum of its observations' redundancy numbers (0..5); 0 when rejected
    double *weight;            // its weight in the final solve, Cauchy's 1 / (1 + chi2 / robust_scale^2)
                               //   at the estimated noise (1 without a robust loss); 0 when rejected
    double *mdb_px;            // minimal detectable bias of its pick, px (the larger of u, v); INFINITY
                               //   when uncontrolled (redundancy 0); NAN when rejected
    double *mdb_m;             // of its surveyed position, m (the largest free axis); NAN when all held
    double *external_m;        // camera-position shift an undetected error of MDB size would cause, m
    double *external_ground_m; // the shift of the optical axis's ground point it would cause, m
    int Nrejected_snooping;    // landmarks rejected by data snooping (within N - Ninliers)
    bool noise_model_wrong;    // snooping would have rejected more than max_rejected_fraction: it
                               //   stopped there, and the warnings say so
    rs_calib_intrinsics_check intrinsics_check; // the intrinsics against the image (above)
    // A focal refined that the landmarks cannot tell from the camera's distance (issue 38): its
    // sigma above 25% of it, or no solve with it free gave a pose (it is then held at the best
    // start's value, the warnings say so). The pose is still the best the data defends; what they
    // do determine is the ground mapping, recorded here as the least-squares homography of the
    // inliers' picks (undistorted through the final intrinsics, pinhole core) to their surveyed
    // (E, N) (rs_calib_homography_fit), with its scatter. All zero when focal_undetermined is false.
    bool focal_undetermined;
    bool focal_held;                // no solve with the focal free gave a pose: held at intrinsics[0]
    double H_ground_from_px_fit[9]; // (3,3) row-major, undistorted px -> (E, N) m, H[8] = 1
    double sigma_ground_fit_m;      // its residuals' RMS on the ground, m (2n - 8 dof; NaN for n = 4)
    int Nground_fit;                // landmarks it was fitted to (0: none could be fitted)
} rs_calib_result;

// The length in bytes of the first warning of a "; "-separated list (rs_calib_result.warnings):
// up to the first "; " outside parentheses, so "... dropped (index 2,5; 0 by data snooping)" is
// one warning. The next one starts after the "; ". Returns strlen(warnings) for the last one.
size_t rs_calib_warning_len(const char *warnings);

// Solves one camera's pose (see the method above). With RS_CALIB_REFINE_FOCAL on 12 landmarks or
// fewer, every alternative start is solved and the best kept; when none gives a pose with the
// focal free, the focal is held (result->focal_held) and then the camera kept above the landmarks
// by a weak position prior, each said in the warnings, before RS_ERR_DEGENERATE is returned.
//
// Returns RS_OK with result filled (free it with rs_calib_result_free even on error: it is
// always left either zeroed or filled). Errors, with the cause in err:
//   RS_ERR_INVALID     non-finite input or sigma (the index and field are named), N < 0,
//                      NULL arrays, bad options
//   RS_ERR_UNSUPPORTED intrinsics refinement on a model without a core
//   RS_ERR_DEGENERATE  fewer than 4 usable landmarks, collinear landmarks, all in a tiny image
//                      patch, landmarks behind the camera, too many outliers, or a pose the
//                      data cannot determine (rank-deficient covariance)
//   RS_ERR_NOCONVERGE  Ceres did not converge
//   RS_ERR_NOMEM, RS_ERR_EXTERNAL (a Ceres exception)
rs_status rs_calib_solve( // out
    rs_calib_result *result,
    // in
    const rs_calib_problem *problem,
    const rs_calib_options *opt, // may be NULL: defaults
    rs_err *err);                // may be NULL

// Frees the owned arrays of result and zeroes it. NULL-safe.
void rs_calib_result_free(rs_calib_result *result);

// The calibrated camera: `nominal`'s lens model and image size with the result's intrinsics
// and pose. A view, not a copy: its intrinsics belong to the result (never rs_camera_free it);
// valid while the result lives.
rs_camera rs_calib_result_camera(const rs_camera *nominal, const rs_calib_result *result);

// Landmark i's surveyed point as the camera cam sees it: p_enu_m[i] for a point; for a pick along
// a polyline (problem.along), its point whose projection is nearest the pick
// (rs_camera_nearest_on_polyline). p_enu_m (3,) and its projection q_px (2,) out; false when it
// does not project (NaN out). What "residual against the surveyed position" means for every kind.
bool rs_calib_problem_seen_point(double p_enu_m[3], double q_px[2], const rs_calib_problem *problem, int i,
                                 const rs_camera *cam);

// Pose helpers (yaw/pitch/roll, camera position, r_from_R) are core/rs_pose.h; ground location
// through a camera is core/rs_camera.h.

#ifdef __cplusplus
}
#endif

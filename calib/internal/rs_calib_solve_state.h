// rs_calib_solve_state.h -- internal: the state of one rs_calib_solve, which every stage reads and
// moves -- the problem and the options, the adjustment, the working pose and the variance
// factors, the landmarks in use and the sigmas in use (calib/rs_calib_solve_state.c). rs_calib.c
// owns one per solve and hands it to the stages in turn (the order: rs_calib.c's opening comment).
//
// Frames: positions and poses are in the frame centred on the landmarks' centroid (p_c = p_enu -
// centroid_enu_m, rt_cam_c = (r, t + R centroid); rs_calib_refine.h); the result assembly
// (rs_calib_result.h) converts to ENU.
#pragma once
#include <stdbool.h>

#include "calib/internal/rs_calib_noise.h"
#include "calib/internal/rs_calib_refine.h"
#include "calib/rs_calib.h"
#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    // in: the problem and the options the solve runs with (those after rs_calib__intrinsics_options)
    const rs_calib_problem *pb;
    const rs_calib_options *opt;
    unsigned user_refine; // the caller's own opt->refine (the intrinsics check tests the others)
    // out: the result being filled
    rs_calib_result *res;
    // the adjustment: rp points into the arrays below; each stage sets ro for its solves
    rs_calib_refine_problem rp;
    rs_calib_refine_options ro;
    double centroid_enu_m[3];           // the centred frame's origin
    double rt_c[6];                     // the working pose rt_cam_c
    double log_theta[RS_NOISE_NGROUPS]; // the variance factors' logs (0: the sigmas as stated); after the
                                        //   noise model, at the solution
    int Noutliers;                      // landmarks out of the adjustment (use false)
    int Nbehind;                        // of them, seen only behind the camera by the final solve
    int Ngross;                         // of them, rejected by the robust stage (gross outliers)
    rs_calib_init_result init;          // the initial pose (method "warm-start" for a warm solve)
    double focal_scale;                 // the focal search's scale (1: none)
    char robust_desc[96];               // the robust stage's part of res->method
    rs_calib_refine_summary final;      // the final solve's summary
    // (N,) arrays unless said; owned, freed by rs_calib__state_free
    double *p_survey_c, *p_c, *cov, *block_chi2, *q_pred; // cov: (6+Ni,6+Ni) the final solve's
    bool *use;
    double *sigma_px, *sigma_enu;   // (N,), (N,3): the sigmas in use (stated, scaled by the noise model)
    double *along_c, *s_along;      // (N,3), (N,): landmarks picked along segments (rs_calib_refine.h);
                                    //   NULL when the problem has none
    double *share;                  // (N,) how many picks share the landmark's survey error (>= 1)
    double *e, *r, *dpos, *dground; // (N,5), (N,5), (N,5,3), (N,5,2): rs_calib_noise_out
    double *chi2_excluded;          // (N,): rs_calib_noise_out, at the noise model's last state
    bool snooped;                   // e, r, dpos, dground are the noise model's last, where data
                                    //   snooping stopped, on the landmarks in use
    // One noise group and no camera priors (the survey exact, no intrinsics refined, no
    // position prior, no picks along segments): the least-squares solution does not depend on
    // the variance factor (rs_calib__scale_free). Then, where the initial pose agreed with
    // every landmark, the robust stage starts from that solution (ls_valid, rt_ls: found on
    // every landmark), and the noise model takes it instead of solving again.
    bool scale_free, ls_valid;
    double rt_ls[6], chi2_ls0; // and its chi-square at the stated sigmas
} rs_calib_solve_state;

// Sets up s for a solve of pb with opt (validated, Ni intrinsics) into res (allocated): the
// arrays, the shares of survey errors, the sigmas as stated, the centred frame (the landmarks'
// centroid; p_survey_c and p_c the surveyed positions in it), the adjustment's problem and its
// options (robust, rough, no covariance), every landmark in use; log_theta 0, no outliers.
// s: zeroed by the caller; free with rs_calib__state_free (also after an error).
// Errors: RS_ERR_NOMEM.
rs_status rs_calib__state_init(rs_calib_solve_state *s, rs_calib_result *res, const rs_calib_problem *pb,
                               const rs_calib_options *opt, unsigned user_refine, int Ni, rs_err *err);

// Frees s's arrays (not s, pb, opt or res).
void rs_calib__state_free(rs_calib_solve_state *s);

// Sets s's sigmas in use: the problem's stated sigmas scaled by exp(log_theta[group]) (the
// survey's widened by sqrt(share) for picks sharing one survey error). log_theta: (RS_NOISE_NGROUPS,).
void rs_calib__scale_sigmas(rs_calib_solve_state *s, const double log_theta[RS_NOISE_NGROUPS]);

// True when pb's least-squares solution does not depend on the variance factors: one noise
// group (the pixels: every survey sigma 0), no intrinsics refined, no position prior, no picks
// along segments.
bool rs_calib__scale_free(const rs_calib_problem *pb, const rs_calib_options *opt);

#ifdef __cplusplus
}
#endif

// rs_calib.c -- rs_calib_solve, the orchestrator: it checks the problem, owns the state of one
// solve (calib/internal/rs_calib_solve_state.h) and runs the stages on it in turn:
//   1.  the initial pose: RANSAC over the minimal solvers (rs_calib_init.h) with its threshold
//       escalated and, with the focal refined, a search over the focal's scale (rs_calib_starts.c);
//       or a warm start; with the focal refined on few landmarks, the whole solve from every
//       alternative start, the best kept (solve_multistart)
//   2.  the robust stage: Cauchy's loss on every landmark, the noise's scale from the data, and
//   3.  the coarse outlier test (rs_calib_robust.c)
//   3b. the noise model: variance components and data snooping, the coarse test's rejections
//       tested again (rs_calib_noise_model.c)
//   4.  the final solve with the covariance, landmarks seen behind the camera, the covariance's
//       spread over the variance factors, the reliability (rs_calib_noise_model.c)
//   4b. the intrinsics check (rs_calib_intrinsics.c); its full alternative, a solve with the
//       focal free, is run here and its figures handed back to it
//   5.  the result in ENU and 6. its warnings (rs_calib_result.c)
// API and method: rs_calib.h; docs/calibration.md. The pose helpers (yaw/pitch/roll, camera
// position, ground intersection) are core's: core/rs_pose.h, core/rs_camera.h.
//
// Layering: a file calls only the files listed below it, never one above (the stages also use
// rs_calib_solve_state.c, the state, rs_calib_refine_ceres.cc, one refinement, and the OpenCV shim's
// small dense algebra; rs_calib_site*.c, a site's cameras in and files out, use rs_calib.h alone):
//   rs_calib.c                 the orchestrator             -> intrinsics, robust, result,
//                                                           noise_model, vce, along, starts
//   rs_calib_intrinsics.c      the intrinsics hooks         -> noise_model, noise, result
//   rs_calib_robust.c          the robust stage             -> noise_model, along, noise
//   rs_calib_result.c          the result and its warnings  -> noise
//   rs_calib_noise_model.c     the noise model's stages     -> vce, noise
//   rs_calib_vce.c             variance components          -> noise
//   rs_calib_noise.c           redundancy numbers
//   rs_calib_along.c           picks along poles and lines
//   rs_calib_solve_state.c     the state: set-up, the sigmas in use
//   rs_calib_starts.c          starts, focal search, score  -> init, the OpenCV shim (homography)
//   rs_calib_init.c            the initial pose's RANSAC    -> the OpenGV and OpenCV shims
//   rs_calib_refine_ceres.cc   one refinement (Ceres)       -> rs_calib_block.c
#include "calib/rs_calib.h"
#include "core/rs_lens.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <mrcal/poseutils.h>

#include "calib/internal/rs_calib_along.h"
#include "calib/internal/rs_calib_intrinsics.h"
#include "calib/internal/rs_calib_noise_model.h"
#include "calib/internal/rs_calib_refine.h"
#include "calib/internal/rs_calib_result.h"
#include "calib/internal/rs_calib_robust.h"
#include "calib/internal/rs_calib_solve_state.h"
#include "calib/internal/rs_calib_starts.h"
#include "calib/internal/rs_calib_vce.h"
#include "core/rs_pose.h"

bool rs_calib_refine_parse(const char *words, unsigned *flags)
{
    char buf[128];
    *flags = 0;
    if (strlen(words) >= sizeof buf) return false;
    strcpy(buf, words);
    char *save = NULL;
    for (char *w = strtok_r(buf, "+,", &save); w; w = strtok_r(NULL, "+,", &save)) {
        if (!strcmp(w, "focal"))
            *flags |= RS_CALIB_REFINE_FOCAL;
        else if (!strcmp(w, "center") || !strcmp(w, "centre"))
            *flags |= RS_CALIB_REFINE_CENTER;
        else if (!strcmp(w, "distortion"))
            *flags |= RS_CALIB_REFINE_DISTORTION;
        else if (strcmp(w, "none") != 0)
            return false;
    }
    return true;
}

void rs_calib_refine_name(char *buf, size_t n, unsigned flags)
{
    snprintf(buf, n, "%s%s%s%s", flags & RS_CALIB_REFINE_FOCAL ? "+focal" : "",
             flags & RS_CALIB_REFINE_CENTER ? "+center" : "", flags & RS_CALIB_REFINE_DISTORTION ? "+distortion" : "",
             flags ? "" : "+none");
    memmove(buf, buf + 1, strlen(buf)); // the leading '+'
}

void rs_calib_options_default(rs_calib_options *opt)
{
    memset(opt, 0, sizeof(*opt));
    opt->refine = RS_CALIB_REFINE_NONE;
    opt->robust_scale = 2.0;
    opt->outlier_threshold = 3.717; // sqrt(chi2inv(0.999, 2)) = sqrt(13.8155)
    rs_calib_init_options_default(&opt->init);
    opt->max_iterations = 500;
    opt->focal_prior_rel_sigma = 1.0;
    opt->center_prior_sigma_px = 50.0;
    opt->distortion_prior_sigma = 0.1;
    opt->focal_search_min = 0.25;
    opt->focal_search_max = 4.0;
    opt->condition_warn = 100.0;
    opt->sigma_rotation_warn_deg = 2.0;
    opt->estimate_noise = true;
    opt->noise_prior_factor = 5.0;
    opt->noise_min_redundancy = 2.0;
    opt->snooping_critical = 3.29;
    opt->max_rejected_fraction = 0.25;
}

// ---------------------------------------------------------------- 0. the problem

// Checks the problem and the options (Ni: the lens model's intrinsics). Errors: RS_ERR_INVALID,
// RS_ERR_UNSUPPORTED, RS_ERR_DEGENERATE (too few landmarks), naming the field at fault.
static rs_status validate(const rs_calib_problem *pb, const rs_calib_options *opt, int Ni, rs_err *err)
{
    if (!pb->camera || !pb->camera->intrinsics) return rs_err_set(err, RS_ERR_INVALID, "lensmodel/intrinsics: NULL");
    if (Ni <= 0) return rs_err_set(err, RS_ERR_INVALID, "lensmodel: invalid");
    if (!rs_calib__all_finite(pb->camera->intrinsics, Ni))
        return rs_err_set(err, RS_ERR_INVALID, "intrinsics: not finite");
    if (opt->refine != RS_CALIB_REFINE_NONE) {
        if (opt->refine & ~(unsigned)(RS_CALIB_REFINE_FOCAL | RS_CALIB_REFINE_CENTER | RS_CALIB_REFINE_DISTORTION))
            return rs_err_set(err, RS_ERR_INVALID, "options: refine: unknown flags 0x%x", opt->refine);
        if (!mrcal_lensmodel_metadata((&pb->camera->lensmodel)).has_core)
            return rs_err_set(err, RS_ERR_UNSUPPORTED, "refine: this lens model has no (fx, fy, cx, cy) core");
        if ((opt->refine & RS_CALIB_REFINE_FOCAL) &&
            !(pb->camera->intrinsics[0] > 0.0 && pb->camera->intrinsics[1] > 0.0))
            return rs_err_set(err, RS_ERR_INVALID, "intrinsics: focal lengths must be > 0");
    }
    if (!(opt->outlier_threshold > 0.0) || !isfinite(opt->robust_scale) || !(opt->focal_search_min > 0.0) ||
        !(opt->focal_search_max >= opt->focal_search_min) || !(opt->focal_prior_rel_sigma >= 0.0) ||
        !(opt->center_prior_sigma_px >= 0.0) || !(opt->distortion_prior_sigma >= 0.0))
        return rs_err_set(err, RS_ERR_INVALID, "options: out of range");
    if (pb->N < 0) return rs_err_set(err, RS_ERR_INVALID, "N: %d < 0", pb->N);
    if (pb->N > 0 && (!pb->p_enu_m || !pb->q_px)) return rs_err_set(err, RS_ERR_INVALID, "p_enu_m/q_px: NULL");
    for (int i = 0; i < pb->N; i++) {
        if (!rs_calib__all_finite(&pb->p_enu_m[3 * i], 3))
            return rs_err_set(err, RS_ERR_INVALID, "landmark %d: p_enu_m: not finite", i);
        if (!rs_calib__all_finite(&pb->q_px[2 * i], 2))
            return rs_err_set(err, RS_ERR_INVALID, "landmark %d: q_px: not finite", i);
        if (pb->sigma_px && !(pb->sigma_px[i] > 0.0 && isfinite(pb->sigma_px[i])))
            return rs_err_set(err, RS_ERR_INVALID, "landmark %d: sigma_px: must be finite and > 0", i);
        if (pb->sigma_enu_m)
            for (int k = 0; k < 3; k++)
                if (!(pb->sigma_enu_m[3 * i + k] >= 0.0 && isfinite(pb->sigma_enu_m[3 * i + k])))
                    return rs_err_set(err, RS_ERR_INVALID, "landmark %d: sigma_enu_m[%d]: must be finite and >= 0", i,
                                      k);
    }
    if (pb->has_position_prior && (!rs_calib__all_finite(pb->prior_position_enu_m, 3) ||
                                   !(pb->prior_sigma_m > 0.0 && isfinite(pb->prior_sigma_m))))
        return rs_err_set(err, RS_ERR_INVALID, "position prior: position must be finite and prior_sigma_m > 0");
    int Npoints = pb->N;
    rs_status st = rs_calib__along_validate(&Npoints, pb, err);
    if (st != RS_OK) return st;
    if (Npoints < 4 && pb->N >= 4)
        return rs_err_set(err, RS_ERR_DEGENERATE,
                          "only %d point landmarks (points, poles' bases and tops): the initial pose needs 4; "
                          "picks along poles and lines only refine it",
                          Npoints);
    if (pb->N < 4)
        return rs_err_set(err, RS_ERR_DEGENERATE,
                          "only %d landmarks: a pose needs at least 4 (6 unknowns, 2 per landmark, "
                          "and one more to pick among the P3P solutions)",
                          pb->N);
    return RS_OK;
}

// ---------------------------------------------------------------- 1. the initial pose

// rt_c in the centred frame (p_c = p_enu - c) from rt_enu: t_c = t_enu + R c.
static void rt_centred_from_enu(double rt_c[6], const double rt_enu[6], const double c[3])
{
    double Rc[3];
    mrcal_rotate_point_r(Rc, NULL, NULL, rt_enu, c);
    for (int i = 0; i < 3; i++) {
        rt_c[i] = rt_enu[i];
        rt_c[3 + i] = rt_enu[3 + i] + Rc[i];
    }
}

// A solve started from another solve's adjustment of the same problem (the intrinsics check's
// alternative with the focal free, stage_intrinsics_check): the pose rt_c (6,) in the centred
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
static rs_status rs_calib__solve_warm(rs_calib_result *result, const rs_calib_problem *problem,
                                      const rs_calib_options *opt, const rs_calib__warm *from, rs_err *err);

// ---------------------------------------------------------------- the stages

// 1. The initial pose in the centred frame (s->rt_c, s->init, s->focal_scale, res->intrinsics at
// the chosen focal), from the point landmarks alone (picks along poles and lines come later); or
// warm's start; or `start` (rs_calib_starts.h: one of the alternatives solve_multistart runs).
// Then the along picks choose their segment at it.
static rs_status stage_start(rs_calib_solve_state *s, const rs_calib__warm *warm, const rs_calib__start *start,
                             rs_err *err)
{
    rs_calib_result *res = s->res;
    const rs_calib_problem *pb = s->pb;
    const int N = pb->N, Ni = res->Nintrinsics;
    memcpy(res->intrinsics, pb->camera->intrinsics, (size_t)Ni * sizeof(double));
    s->init = (rs_calib_init_result){.method = "warm-start"};
    if (warm) {
        memcpy(s->rt_c, warm->rt_c, sizeof s->rt_c);
        memcpy(res->intrinsics, warm->intrinsics, (size_t)Ni * sizeof(double));
        memcpy(s->p_c, warm->p_c, (size_t)N * 3 * sizeof(double));
    } else if (start) {
        s->init = start->init;
        s->focal_scale = start->focal_scale;
        res->intrinsics[0] *= start->focal_scale;
        res->intrinsics[1] *= start->focal_scale;
        rt_centred_from_enu(s->rt_c, s->init.rt_cam_enu, s->centroid_enu_m);
    } else {
        double *points_buffer = NULL;
        rs_calib_problem points; // the point landmarks alone: picks along poles and lines come later
        rs_status st = rs_calib__point_problem(&points, &points_buffer, pb, err);
        if (st == RS_OK)
            st = rs_calib__initial_pose(&s->init, res->intrinsics, &s->focal_scale, &points, s->opt, Ni, err);
        free(points_buffer);
        if (st != RS_OK) {
            rs_err_prefix(err, "initial pose");
            return st;
        }
        rt_centred_from_enu(s->rt_c, s->init.rt_cam_enu, s->centroid_enu_m);
    }
    rs_calib__along_choose(s);
    return RS_OK;
}

// 2. The robust solve on every landmark, with the scale taken from the data; 3. gross outliers
// (rs_calib__robust_stage). A warm start whose first solve found no gross outlier
// (rs_calib__warm.no_gross) skips it, at that solve's variance factors.
static rs_status stage_robust(rs_calib_solve_state *s, const rs_calib__warm *warm, rs_err *err)
{
    const int N = s->pb->N;
    if (warm && warm->no_gross) { // the first solve found no gross outlier (rs_calib__warm)
        if (warm->log_theta) {
            memcpy(s->log_theta, warm->log_theta, sizeof s->log_theta);
            rs_calib__scale_sigmas(s, s->log_theta);
        }
        rs_calib__along_choose(s);
        for (int i = 0; i < N; i++) s->res->w_test[i] = NAN;
    } else if (s->opt->robust_scale > 0.0) {
        rs_status st = rs_calib__robust_stage(s, !warm && s->init.Ninliers == N, err);
        if (st != RS_OK) return st;
    }
    if (N - s->Noutliers < 4)
        return rs_err_set(err, RS_ERR_DEGENERATE,
                          "only %d of %d landmarks agree with one pose (the rest are outliers "
                          "beyond %g sigma): a pose needs at least 4",
                          N - s->Noutliers, N, s->opt->outlier_threshold);
    return RS_OK;
}

// 3b. Variance components and data snooping (rs_calib_noise_model.h), alternating; their solves
// need not be tight (the variance factors change by 1e-3 in the end): the final solve is.
// 3b'. the coarse test's rejections at the estimated noise. 3c. the pose's covariance is built on
// the variance factors' posterior mode (where s's sigmas are), spread over their posterior in
// stage_final. A group with little redundancy is not estimated from the data: its posterior rests
// mostly on the prior, its stated sigma (kept there rather than reset to the statement: on the
// real GNSS survey the reset made the leave-one-out median of the sigma set 1.0 m / 0.3 m / 3 px
// 1.77 m instead of 1.53 m).
static rs_status stage_noise(rs_calib_solve_state *s, rs_err *err)
{
    const rs_calib_options *opt = s->opt;
    rs_status st;
    s->ro.robust_scale = 0.0;
    s->ro.rough = true;
    if (opt->estimate_noise || opt->robust_scale > 0.0) {
        st = rs_calib__noise_model(s, err);
        if (st != RS_OK) return st;
    }
    if (opt->estimate_noise) { // 3b'. the coarse test's rejections at the estimated noise
        st = rs_calib__readmit(s, err);
        if (st != RS_OK) return st;
    }
    if (opt->estimate_noise) rs_calib__scale_sigmas(s, s->log_theta);
    return RS_OK;
}

// 4. The inliers, still under Cauchy's loss (now at the estimated noise: an M-estimate, each
// landmark weighted by 1 / (1 + chi2 / a^2), res->weight), with the covariance. A landmark
// seen only behind the camera is a blunder (rs_calib__reject_behind): it leaves (named in the
// outlier warning), and the solve runs again (twice at most; then, or below 4, an error).
// Scale-free, the final solve starts from the robust stage's solution rt_robust (6,), a Cauchy
// M-estimate like it, at a scale near the one estimated (harness, exact surveys: -5%); elsewhere
// from the noise model's (on the bench's other problems the robust stage's took more
// evaluations). Then the covariance's spread over the variance factors (not for a warm start).
static rs_status stage_final(rs_calib_solve_state *s, const double rt_robust[6], bool warm, rs_err *err)
{
    rs_calib_result *res = s->res;
    const rs_calib_options *opt = s->opt;
    const int N = s->pb->N;
    rs_status st;
    if (s->scale_free) memcpy(s->rt_c, rt_robust, sizeof s->rt_c);
    s->ro.robust_scale = opt->robust_scale;
    s->ro.covariance = true;
    s->ro.rough = false;
    s->Nbehind = 0;
    for (int pass = 0;; pass++) {
        st = rs_calib_refine_run(s->rt_c, res->intrinsics, s->p_c, &s->final, s->cov, s->block_chi2, s->q_pred, &s->rp,
                                 &s->ro, err);
        if (st != RS_OK) {
            rs_err_prefix(err, "refinement");
            return st;
        }
        res->iterations += s->final.iterations;
        int n = 0;
        st = rs_calib__reject_behind(&n, s, N - s->Noutliers, pass == 2, err);
        if (st != RS_OK) return st;
        if (n == 0) break;
        s->Noutliers += n, s->Nbehind += n;
    }
    s->Ngross = s->Noutliers - res->Nrejected_snooping;
    res->pose_dof = INFINITY; // the noise as stated: the pose's 99.9% region is chi-square 6 dof
    res->region_m2 = rs_calib__pose_region_m2(1e-3, INFINITY, 1.0);
    if (opt->estimate_noise && !warm) { // the covariance carries the variance factors' own uncertainty
        st = rs_calib__cov_spread(s, err);
        if (st != RS_OK) return st;
    }
    return RS_OK;
}

// The intrinsics check's full alternative: rs_calib_solve of pb with the focal free (weak prior,
// no search), from `from`: the focal scale k (f / f_nominal - 1), its variance Q and the dof of
// that fit. The solve refines the focal at the caller's request, so that its own check leaves the
// focal alone (and it is warm: no check at all): no recursion beyond one level.
static rs_status solve_focal_free(double *k, double *Q, int *dof, const rs_calib_problem *pb,
                                  const rs_calib_options *opt, const rs_calib__warm *from)
{
    rs_calib_problem p = *pb;
    p.focal_rel_sigma = 0.0;
    rs_calib_options o = *opt;
    o.refine |= RS_CALIB_REFINE_FOCAL;
    o.focal_prior_rel_sigma = 1.0; // rs_calib_options_default's: weak
    o.focal_search_min = o.focal_search_max = 1.0;
    rs_calib_result r;
    rs_err e = {0};
    rs_status st = rs_calib__solve_warm(&r, &p, &o, from, &e);
    if (st == RS_OK) {
        const double f0 = pb->camera->intrinsics[0];
        *k = r.intrinsics[0] / f0 - 1.0;
        *Q = r.covariance_intrinsics[0] / (f0 * f0);
        *dof = r.dof;
        if (!(*Q > 0) || !isfinite(*k)) st = RS_ERR_DEGENERATE;
    }
    rs_calib_result_free(&r);
    return st;
}

// 4b. The intrinsics against the image (rs_calib_intrinsics.h): the test, the full alternative
// where it asks for one (solve_focal_free from this solve's solution), the verdict.
static rs_status stage_intrinsics_check(rs_calib_solve_state *s, rs_err *err)
{
    rs_calib_intrinsics_test t;
    rs_status st = rs_calib__intrinsics_test(&t, s, err);
    if (st != RS_OK) return st;
    if (t.need_full) {
        const rs_calib__warm from = {.rt_c = s->rt_c,
                                     .intrinsics = s->res->intrinsics,
                                     .p_c = s->p_c,
                                     .no_gross = s->Ngross == 0,
                                     .log_theta = s->log_theta};
        t.full_status = solve_focal_free(&t.k_full, &t.Q_full, &t.dof_full, s->pb, s->opt, &from);
    }
    rs_calib__intrinsics_verdict(s, &t);
    return RS_OK;
}

// One solve of pb with opt (those the solve runs with; user_refine: the caller's own refine) into
// res, on the state s (zeroed; the caller frees it); warm: its start, or NULL; start: the initial
// pose to start from, or NULL for the initial pose (stage_start).
static rs_status solve(rs_calib_solve_state *s, rs_calib_result *res, const rs_calib_problem *pb,
                       const rs_calib_options *opt, unsigned user_refine, int Ni, const rs_calib__warm *warm,
                       const rs_calib__start *start, rs_err *err)
{
    rs_status st = validate(pb, opt, Ni, err);
    if (st != RS_OK) return st;
    if (rs_calib__result_alloc(res, pb->N, Ni) != RS_OK) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if ((st = rs_calib__state_init(s, res, pb, opt, user_refine, Ni, err)) != RS_OK) return st;
    if ((st = stage_start(s, warm, start, err)) != RS_OK) return st;
    if ((st = stage_robust(s, warm, err)) != RS_OK) return st;
    double rt_robust[6]; // the robust stage's solution (rs_calib__scale_free: the final solve's start)
    memcpy(rt_robust, s->rt_c, sizeof rt_robust);
    if ((st = stage_noise(s, err)) != RS_OK) return st;
    if ((st = stage_final(s, rt_robust, warm != NULL, err)) != RS_OK) return st;
    if (!warm && (st = rs_calib__reliability(s, err)) != RS_OK) return st;
    if (!warm && (st = stage_intrinsics_check(s, err)) != RS_OK) return st;
    if ((st = rs_calib__result_pose(s, err)) != RS_OK) return st;
    if ((st = rs_calib__result_landmarks(s, err)) != RS_OK) return st;
    rs_calib__result_warnings(s);
    return RS_OK;
}

// One solve (solve()) on a state of its own, freed; result freed on failure.
static rs_status solve_once(rs_calib_result *result, const rs_calib_problem *problem, const rs_calib_options *opt,
                            unsigned user_refine, int Ni, const rs_calib__warm *warm, const rs_calib__start *start,
                            rs_err *err)
{
    rs_calib_solve_state s = {0};
    memset(result, 0, sizeof(*result));
    rs_status st = solve(&s, result, problem, opt, user_refine, Ni, warm, start, err);
    rs_calib__state_free(&s);
    if (st != RS_OK) rs_calib_result_free(result);
    return st;
}

// A focal nobody knows and few landmarks (issue 38): the focal search's best start need not be
// the right basin (the MSAC cost of a few landmarks with metres of survey noise hardly tells the
// scales apart), and a solve from the wrong one ends with a landmark behind the camera, no
// consensus, or a worse pose than a homography's. So the solve runs from every start
// (rs_calib__starts: the initial pose at each scale of the grid, the ground homography's
// decomposition) as well as from the usual one, and the solution with the smallest score
// (rs_calib__score: every landmark's surveyed position reprojected in the stated noise, Cauchy's
// loss) is kept. Only where the focal is refined and at most RS_CALIB_MULTISTART_MAX_N landmarks;
// elsewhere the usual solve alone.
#define RS_CALIB_MULTISTART_MAX_N  12
#define RS_CALIB_MULTISTART_STARTS 40
// The best solve so far of solve_multistart: the problem and options it is scored by.
typedef struct {
    rs_calib_result *result; // the best so far (filled when best is finite)
    double best;             // its score (rs_calib__score); INFINITY: none yet
    const rs_calib_problem *problem;
    const rs_calib_options *opt;
    unsigned user_refine;
    int Ni;
} multistart;

// The solve of pb with o from start; kept in m when it scores better (on m's problem and options).
static void try_start(multistart *m, const rs_calib_problem *pb, const rs_calib_options *o,
                      const rs_calib__start *start)
{
    rs_calib_result r;
    if (solve_once(&r, pb, o, m->user_refine, m->Ni, NULL, start, NULL) != RS_OK) return;
    const double score = rs_calib__score(r.rt_cam_enu, r.intrinsics, m->problem, m->opt);
    if (!(score < m->best)) {
        rs_calib_result_free(&r);
        return;
    }
    if (isfinite(m->best)) rs_calib_result_free(m->result);
    *m->result = r;
    m->best = score;
}

static rs_status solve_multistart(rs_calib_result *result, const rs_calib_problem *problem, const rs_calib_options *opt,
                                  unsigned user_refine, int Ni, rs_err *err)
{
    rs_calib__start starts[RS_CALIB_MULTISTART_STARTS];
    int Nstarts = 0;
    double *points_buffer = NULL;
    rs_calib_problem points;
    rs_status st = rs_calib__point_problem(&points, &points_buffer, problem, err);
    if (st == RS_OK) st = rs_calib__starts(starts, &Nstarts, RS_CALIB_MULTISTART_STARTS, &points, opt, Ni, err);
    free(points_buffer);
    if (st != RS_OK) return st;
    multistart m = {result, INFINITY, problem, opt, user_refine, Ni};
    for (int k = 0; k < Nstarts; k++) try_start(&m, problem, opt, &starts[k]);
    if (isfinite(m.best)) return RS_OK;
    // no start gave a pose with the focal free: the data cannot tell it from the distance. The
    // best pose with it held at each start's value instead (the warnings say so)
    rs_calib_options held = *opt;
    held.refine &= ~(unsigned)RS_CALIB_REFINE_FOCAL;
    for (int k = 0; k < Nstarts; k++) try_start(&m, problem, &held, &starts[k]);
    if (isfinite(m.best)) {
        result->focal_held = true;
        return RS_OK;
    }
    // still none (every solve ended below the landmarks, looking up: the mirror a few noisy
    // coplanar landmarks cannot rule out): the camera held above them by a weak prior on its
    // position, at each start's twin above (rs_calib__starts), 1-sigma its distance to them
    double c[3] = {0, 0, 0};
    for (int i = 0; i < problem->N; i++)
        for (int j = 0; j < 3; j++) c[j] += problem->p_enu_m[3 * i + j] / problem->N;
    for (int k = 0; k < Nstarts && !problem->has_position_prior; k++) {
        if (!starts[k].twin) continue;
        rs_calib_problem above = *problem;
        above.has_position_prior = true;
        double *C = above.prior_position_enu_m;
        rs_pose_position_from_rt(C, NULL, starts[k].init.rt_cam_enu);
        above.prior_sigma_m =
            sqrt((c[0] - C[0]) * (c[0] - C[0]) + (c[1] - C[1]) * (c[1] - C[1]) + (c[2] - C[2]) * (c[2] - C[2]));
        try_start(&m, &above, opt, &starts[k]);
    }
    if (isfinite(m.best)) {
        rs_calib__warn(result,
                       "every solve put the camera below the landmarks, looking up (the mirror image a few "
                       "coplanar landmarks cannot rule out): it is held above them by a weak prior on its position "
                       "(1-sigma its distance to them); check the pose against the site");
        return RS_OK;
    }
    // nothing gave a pose: the usual solve, for its error
    return solve_once(result, problem, opt, user_refine, Ni, NULL, NULL, err);
}

// A focal refined at the caller's request that the landmarks cannot determine (rs_calib_result.
// focal_undetermined): said in the warnings, with the ground mapping they do determine.
#define RS_CALIB_FOCAL_UNDETERMINED_REL 0.25
static void focal_verdict(rs_calib_result *res, const rs_calib_problem *pb)
{
    const double rel = res->sigma_intrinsics[0] / res->intrinsics[0];
    if (!res->focal_held && !(rel > RS_CALIB_FOCAL_UNDETERMINED_REL)) return;
    res->focal_undetermined = true;
    rs_calib__ground_fit(res, pb);
    char fit[160] = "no homography could be fitted to the picks";
    if (res->Nground_fit > 0)
        snprintf(fit, sizeof fit,
                 "the least-squares homography of the %d picks to the ground (scatter %.2g m), recorded beside the "
                 "pose",
                 res->Nground_fit, res->sigma_ground_fit_m);
    if (res->focal_held)
        rs_calib__warn(res,
                       "the landmarks cannot tell the focal length from the camera's distance: no solve with the "
                       "focal free gave a pose, so it is held at %.4g px (the best start's); the pose rests on that "
                       "value; what the data determine is the ground mapping: %s",
                       res->intrinsics[0], fit);
    else
        rs_calib__warn(res,
                       "the landmarks cannot tell the focal length from the camera's distance (focal sigma %.0f%%): "
                       "the pose slides along that trade-off; what the data determine is the ground mapping: %s",
                       100.0 * rel, fit);
}

// rs_calib_solve (warm NULL) or rs_calib__solve_warm: the options completed, the solve timed.
static rs_status solve_timed(rs_calib_result *result, const rs_calib_problem *problem, const rs_calib_options *opt_in,
                             const rs_calib__warm *warm, rs_err *err)
{
    if (!result || !problem) return rs_err_set(err, RS_ERR_INVALID, "rs_calib_solve: NULL result or problem");
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    memset(result, 0, sizeof(*result));
    rs_calib_options opt;
    if (opt_in)
        opt = *opt_in;
    else
        rs_calib_options_default(&opt);
    const int Ni = problem->camera ? mrcal_lensmodel_num_params(&problem->camera->lensmodel) : 0;
    // ---- hook: intrinsics with a stated uncertainty become parameters (rs_calib_intrinsics.c) ----
    const unsigned user_refine = opt.refine;
    rs_status st = rs_calib__intrinsics_options(&opt, problem, err);
    if (st != RS_OK) return st;
    // ---- end hook ----
    const bool multistart = !warm && (user_refine & RS_CALIB_REFINE_FOCAL) &&
                            opt.focal_search_max > opt.focal_search_min && problem->N <= RS_CALIB_MULTISTART_MAX_N;
    st = multistart ? solve_multistart(result, problem, &opt, user_refine, Ni, err)
                    : solve_once(result, problem, &opt, user_refine, Ni, warm, NULL, err);
    if (st != RS_OK) return st;
    if (!warm && (user_refine & RS_CALIB_REFINE_FOCAL)) focal_verdict(result, problem);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    result->time_us = (double)(t1.tv_sec - t0.tv_sec) * 1e6 + (double)(t1.tv_nsec - t0.tv_nsec) * 1e-3;
    return RS_OK;
}

rs_status rs_calib_solve(rs_calib_result *result, const rs_calib_problem *problem, const rs_calib_options *opt,
                         rs_err *err)
{
    return solve_timed(result, problem, opt, NULL, err);
}

static rs_status rs_calib__solve_warm(rs_calib_result *result, const rs_calib_problem *problem,
                                      const rs_calib_options *opt, const rs_calib__warm *from, rs_err *err)
{
    if (!from || !from->rt_c || !from->intrinsics || !from->p_c)
        return rs_err_set(err, RS_ERR_INVALID, "rs_calib__solve_warm: NULL start");
    return solve_timed(result, problem, opt, from, err);
}

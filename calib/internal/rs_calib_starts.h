// rs_calib_starts.h -- internal: where a solve starts (calib/rs_calib_starts.c). The initial pose
// at the nominal intrinsics (rs_calib_init.h, its RANSAC threshold escalated); with the focal
// refined, the focal search over a log grid of scales; and, for a focal nobody knows and few
// landmarks (issue 38), every alternative start the orchestrator runs the solve from (rs_calib.c,
// solve_multistart): the initial pose at every scale of the grid and the pose and focal of the
// ground homography's decomposition. And the one score those solves are compared by.
#pragma once
#include <stdbool.h>

#include "calib/rs_calib.h"
#include "calib/rs_calib_init.h"
#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// One start: an initial pose (its method says where it came from) at the nominal focal times
// focal_scale.
typedef struct {
    rs_calib_init_result init;
    double focal_scale;
    bool twin; // the twin above of a start whose camera was below the landmarks (rs_calib__starts)
} rs_calib__start;

// The initial pose of pb (its point landmarks alone) in ENU. With the focal refined, a 1-D search
// over a focal scale s (quarter-octave steps over [focal_search_min, focal_search_max]) runs the
// initial pose at fx s, fy s and keeps the s whose pose has the smallest MSAC cost over all
// landmarks, with one truncation for every s: T = 4 x the RANSAC threshold (32 px by default), so
// that poses found at different escalated thresholds compare fairly. intrinsics (Ni,) receives the
// nominal ones at the chosen scale, *scale_out the scale.
// Errors: those of rs_calib_init_pose (RS_ERR_DEGENERATE at every scale), RS_ERR_NOMEM.
rs_status rs_calib__initial_pose( // out
    rs_calib_init_result *init, double *intrinsics, double *scale_out,
    // in
    const rs_calib_problem *pb, const rs_calib_options *opt, int Ni, rs_err *err);

// Every start of pb (its point landmarks alone) worth a solve when the focal is refined and the
// landmarks are few: the initial pose at each scale of the focal search's grid where it finds one
// (poses within 1 deg and 1% of the range of an earlier one at a scale within 10% of its own
// left out), and the decomposition of the least-squares ground homography
// (rs_calib_homography_fit) from the bearings' normalised coordinates at the nominal intrinsics to
// the landmarks' (E, N): the focal scale from the two constraints a homography puts on the image
// of the absolute conic (square pixels, the principal point as nominal; Zhang 2000), then
// r1, r2, t from its columns, the sign that puts the landmarks in front (made only when the init
// judges the landmarks planar); and, for every start whose camera is below the landmarks, its
// twin above (IPPE's two-fold ambiguity of a plane seen from afar; twin set).
// out: starts (max,), *Nstarts (0 when none was found: RS_OK all the same)
rs_status rs_calib__starts( // out
    rs_calib__start *starts, int *Nstarts,
    // in
    int max, const rs_calib_problem *pb, const rs_calib_options *opt, int Ni, rs_err *err);

// The score the solves from different starts are compared by (smaller is better): over EVERY
// landmark of pb (point landmarks; a pick along a pole or line at its first vertex is not
// scored), Cauchy's rho(chi2_i) = a^2 log(1 + chi2_i / a^2), a = opt->robust_scale (chi2_i itself
// when it is 0), where chi2_i is the landmark's surveyed position reprojected through the pose
// rt_cam_enu and intrinsics, against its pick, in the STATED noise: the pick's sigma and the
// survey's covariance projected through the camera (first order). A landmark behind the camera
// or that does not project counts chi2 = 1e4. Independent of which landmarks a solve rejected or
// of the noise it estimated, so that solves compare fairly.
double rs_calib__score(const double rt_cam_enu[6], const double *intrinsics, const rs_calib_problem *pb,
                       const rs_calib_options *opt);

// The ground mapping a focal nobody can determine leaves (rs_calib_result.focal_undetermined):
// the least-squares homography (rs_calib_homography_fit) from the inliers' picks, undistorted
// through res->intrinsics (mrcal_unproject, then the pinhole core), to their surveyed (E, N),
// into res->H_ground_from_px_fit, its residuals' RMS on the ground (2n - 8 degrees of freedom)
// into res->sigma_ground_fit_m and n into res->Nground_fit (0 when fewer than 4 inliers unproject
// or OpenCV finds none). Point landmarks only; pb is the problem res was solved from.
void rs_calib__ground_fit(rs_calib_result *res, const rs_calib_problem *pb);

#ifdef __cplusplus
}
#endif

// rs_calib_opengv.h -- internal C interface to OpenGV's absolute-pose solvers (calib only).
//
// Thin shim: the C++ lives in rs_calib_opengv.cc; every exception is caught there and turned
// into RS_ERR_EXTERNAL. Poses cross this boundary in mrcal's Rt layout: a (4,3) array whose
// first 3 rows are R_cam_ref and whose last row is t, so that p_cam = R p_ref + t
// (mrcal_transform_point_Rt, mrcal_rt_from_Rt). The reference frame is whatever frame p_ref is
// given in; rs_calib_init.c passes landmarks centred on their centroid.
#pragma once
#include "core/rs_status.h"
#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

// Per-observation error of a pose hypothesis, in pixels, computed by the caller (through the
// lens model). err_px[k] belongs to observation indices[k]; +inf where the landmark is behind
// the camera or does not project.
typedef void rs_calib_opengv_score_fn( // out
    double *err_px,                    // (Nindices,)
    // in
    const double *Rt_cam_ref, // (4,3)
    const int *indices,       // (Nindices,)
    int Nindices, void *cookie);

enum { RS_CALIB_OPENGV_EXHAUSTIVE_MAX = 6 };
typedef enum {
    RS_CALIB_OPENGV_P3P_KNEIP = 0, // Kneip, Scaramuzza, Siegwart, CVPR 2011
    RS_CALIB_OPENGV_P3P_GAO = 1,   // Gao, Hou, Tang, Cheng, PAMI 2003
} rs_calib_opengv_p3p;

// RANSAC (OpenGV's sac::Ransac) over OpenGV's P3P solver. Each sample has 4 observations: P3P
// on the first 3, the 4th picks among the up to 4 solutions (OpenGV's AbsolutePoseSacProblem).
// When the chosen solver finds no solution for a sample, the other P3P solver is tried on the
// same sample (counted in *Nfallback). The hypotheses are scored by `score` in pixels: an
// observation is an inlier when its error is < threshold_px. The sampler is OpenGV's, with its
// std::mt19937 seeded from `seed`, so the result is a deterministic function of the input.
// Adaptive stop when a sample free of outliers has been drawn with probability `confidence`.
// With RS_CALIB_OPENGV_EXHAUSTIVE_MAX usable observations or fewer, no sampler: every triple
// (20 at most) goes through P3P, each of its solutions is scored on all of them, and the one
// with the most inliers wins (ties: the smaller sum of min(err^2, threshold^2)); it stops at a
// solution that every observation agrees with. *Niterations then counts the triples tried,
// and seed, max_iterations and confidence are not used. (A 4-landmark calibration spent 12%
// of its time in OpenGV's RANSAC, most of it seeding std::mt19937, for one sample.)
//
// Returns RS_ERR_DEGENERATE if no sample gave any pose, RS_ERR_EXTERNAL if OpenGV threw.
rs_status rs_calib_opengv_ransac_p3p( // out
    double *Rt_cam_ref,               // (4,3) best hypothesis
    bool *inlier,                     // (N,) its inliers
    int *Niterations,                 // may be NULL
    int *Nfallback,                   // may be NULL
    // in
    const double *v_cam, // (N,3) unit bearing vectors
    const double *p_ref, // (N,3) landmarks, metres
    int N,
    const int *usable, // (Nusable,) indices to sample from
    int Nusable,       // >= 4
    rs_calib_opengv_p3p method, double threshold_px, int max_iterations,
    double confidence, // e.g. 0.999
    uint64_t seed, rs_calib_opengv_score_fn *score, void *cookie,
    rs_err *err); // may be NULL

// ---- pose solvers side by side (roadside bench calib, issue 5) ----
// One calling convention for the OpenGV methods the benchmark compares, used as OpenGV's own
// examples use them: stock sample-consensus problem (angular threshold, OpenGV's fixed seed).
typedef enum {
    RS_CALIB_OPENGV_POSE_P3P_KNEIP_RANSAC = 0, // sac::Ransac over P3P Kneip (no refinement)
    RS_CALIB_OPENGV_POSE_P3P_GAO_RANSAC = 1,   // sac::Ransac over P3P Gao (no refinement)
    RS_CALIB_OPENGV_POSE_EPNP = 2,             // epnp() on all observations
    RS_CALIB_OPENGV_POSE_UPNP = 3,             // upnp() (Kneip, Li, Seo, ECCV 2014): of its
                                               //   solutions, the one with the least angular error
    RS_CALIB_OPENGV_POSE_EPNP_NONLINEAR = 4,   // epnp(), then optimize_nonlinear() (Levenberg-
                                               //   Marquardt on the angular residuals)
} rs_calib_opengv_pose_method;

// Pose from N bearing/landmark pairs by `method`. threshold_rad: the RANSAC inlier angle (as
// OpenGV wants it: 1 - cos(threshold_rad)); ignored by the others. max_iterations: RANSAC.
// Returns RS_ERR_DEGENERATE for no pose or a non-finite one, RS_ERR_EXTERNAL if OpenGV threw,
// RS_ERR_USAGE for N < 4 or an unknown method. Never prints.
rs_status rs_calib_opengv_pose( // out
    double *Rt_cam_ref,         // (4,3)
    // in
    const double *v_cam, // (N,3) unit bearing vectors
    const double *p_ref, // (N,3) landmarks, metres
    int N, rs_calib_opengv_pose_method method, double threshold_rad, int max_iterations,
    rs_err *err); // may be NULL

#ifdef __cplusplus
}
#endif

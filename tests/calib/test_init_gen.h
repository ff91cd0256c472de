// test_init_gen.h -- a small simulated roadside camera for the initial-pose tests.
//
// A camera on a pole 5..100 m up, looking down at a road, sees N landmarks on the ground
// (relief_m = 0: planar) or up to relief_m above it (street furniture: 8 m; a road's crown and
// kerbs: 0.3 m, nearly planar). Pixels are
// mrcal_project() of the landmarks through the truth pose, plus Gaussian noise, plus gross
// outliers (moved >= 25 px, anywhere in the image). Everything follows docs/conventions.md.
#pragma once
#include <stdbool.h>
#include <stdint.h>

#include "calib/rs_calib_init.h"

#ifdef __cplusplus
extern "C" {
#endif
// mrcal.h has no extern "C" of its own
#include <mrcal/mrcal.h>

#define TG_NMAX 64

typedef enum { TG_PINHOLE, TG_OPENCV8, TG_CAHVOR, TG_NLENS } tg_lens;

typedef struct {
    uint64_t state;
} tg_rng;

typedef struct {
    mrcal_lensmodel_t lensmodel;
    double intrinsics[16];
    int width, height;    // image size, pixels
    double rt_cam_enu[6]; // truth pose
    double c_enu_m[3];    // truth camera position
    double range_m;       // mean camera-landmark distance
    int N;
    double p_enu_m[3 * TG_NMAX];   // (N,3) landmarks
    double q_true_px[2 * TG_NMAX]; // (N,2) noise-free pixels
    double q_px[2 * TG_NMAX];      // (N,2) observed pixels
    bool outlier[TG_NMAX];         // (N,) gross mistakes
} tg_problem;

// Random draws (tg_seed sets the state; tg_uniform: in [a, b]; tg_gauss: N(0, 1), Box-Muller), a lens's name.
void tg_seed(tg_rng *r, uint64_t seed);
double tg_uniform(tg_rng *r, double a, double b);
double tg_gauss(tg_rng *r);
const char *tg_lens_name(tg_lens lens);

// Fills pb. Returns false if no valid layout was found (never with sane arguments).
bool tg_make(tg_problem *pb, uint64_t seed, tg_lens lens, double relief_m, int N, double noise_px,
             double outlier_fraction);

// rs_calib_init_pose() on pb with the default options and RANSAC seed `seed`.
rs_status tg_init_pose(rs_calib_init_result *res, bool *inlier, const tg_problem *pb, uint64_t seed, rs_err *err);

// R_enu_cam from yaw/pitch/roll (degrees), docs/conventions.md.
void tg_R_enu_cam(double *R, double yaw_deg, double pitch_deg, double roll_deg);

// Angle of R_a R_b^T, radians.
double tg_rotation_error_rad(const double *rt_a, const double *rt_b);
// Distance between the camera centres of two poses, metres.
double tg_position_error_m(const double *rt_a, const double *rt_b);
// RMS over all landmarks of |project(pose_a) - project(pose_b)|, pixels (+inf if any is behind).
double tg_model_error_px(const tg_problem *pb, const double *rt_a, const double *rt_b);

#ifdef __cplusplus
}
#endif

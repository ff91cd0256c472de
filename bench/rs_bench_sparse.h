// rs_bench_sparse.h -- `roadside bench sparse`: sparse, map-picked surveys with an unknown focal
// length (issue 38, item 2: "no failure where a homography answers").
//
// Each site is `roadside site simulate`'s (sim/rs_simulate.h) with one camera (PINHOLE by default),
// 6..8 points on the ground (no elevated landmark, heights unknown: taken from the site's ground
// plane, as for points picked on a map), horizontal survey noise 0.5 m, pixel noise 3 px, no gross
// outlier, and the nominal focal length off by a factor drawn log-uniformly in [1/1.5, 1.5]
// (`--focal-error-range`). Per site, leave-one-out over its points: calibrate on the others with
// rs_calib_solve (--refine focal), locate the left-out pick on the ground plane through the
// calibrated camera (rs_camera_locate_ground), and measure the horizontal distance to the landmark's true position (truth/); the same with
// a least-squares homography from pixels to the ground's (E, N) fitted on the same points
// (rs_calib_homography_fit: OpenCV's findHomography, method 0).
#pragma once
#include <stdbool.h>
#include <stdint.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    uint64_t seed;              // site k is simulated with seed + k
    int points_min, points_max; // points per site, drawn uniformly (default 6..8)
    double focal_error_range;   // nominal focal = true x a factor log-uniform in [1/this, this] (1.5)
    double pixel_sigma_px;      // 3
    double survey_sigma_h_m;    // 0.5
    const char *lensmodel;      // "LENSMODEL_PINHOLE"
    double hfov_deg;            // 60
    bool true_intrinsics;       // false; true: calibrate with the TRUE intrinsics, held -- the
                                //   reference no estimate of the focal can be expected to beat
    bool verbose_folds;         // false; true: print each fold's figures on stdout
} rs_bench_sparse_options;

// Fills o with the defaults above.
void rs_bench_sparse_options_default(rs_bench_sparse_options *o);

// One site's figures.
typedef struct {
    uint64_t seed;
    int Npoints;                // points the camera sees
    double focal_nominal_rel;   // nominal focal / true focal
    int Nno_pose;               // folds whose calibration returned no pose
    int Nno_location;           // folds whose pose puts the left-out pick above the horizon
    double loo_median_m;        // roadside's leave-one-out ground error, median over the folds
                                //   (a fold without a pose counts as +inf)
    double homography_median_m; // the least-squares homography's
    double loo_max_m, homography_max_m;
    char first_error[160]; // the first fold's failure, "" when none
} rs_bench_sparse_row;

// Simulates site `k` in work_dir (a folder of its own, removed afterwards) and runs its folds.
// RS_ERR_IO when the site cannot be written or read back, RS_ERR_NOMEM; a calibration that fails
// is a figure (Nno_pose), not an error.
rs_status rs_bench_sparse_site(rs_bench_sparse_row *row, const rs_bench_sparse_options *o, int k, const char *work_dir,
                               rs_err *err);

#ifdef __cplusplus
}
#endif

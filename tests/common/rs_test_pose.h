// rs_test_pose.h -- the pose error of a calibration against its truth, as the solver tests measure
// it (one copy for every test: test_solve_nees, test_fisheye, test_calib_focal_error). Header-only.
#pragma once
#include <math.h>
#include <string.h>

// e (6,) = rt_est - rt_true in the estimate's chart: r_true replaced by its equivalent
// r_true (1 + 2 pi k/|r_true|), k in {-1, 0, 1}, nearest to r_est (rotation vectors near
// |r| = pi have two representatives); the translations subtracted as they are.
static inline void rs_test_pose_error(double e[6], const double rt_est[6], const double rt_true[6])
{
    const double th = sqrt(rt_true[0] * rt_true[0] + rt_true[1] * rt_true[1] + rt_true[2] * rt_true[2]);
    double best = INFINITY;
    for (int k = -1; k <= 1; k++) {
        const double s = th > 0 ? 1.0 + 2.0 * M_PI * k / th : 1.0;
        double d[3], n2 = 0;
        for (int i = 0; i < 3; i++) {
            d[i] = rt_est[i] - s * rt_true[i];
            n2 += d[i] * d[i];
        }
        if (n2 < best) {
            best = n2;
            memcpy(e, d, sizeof(d));
        }
    }
    for (int k = 3; k < 6; k++) e[k] = rt_est[k] - rt_true[k];
}

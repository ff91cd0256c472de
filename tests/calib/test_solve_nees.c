// test_solve_nees.c -- statistics of rs_calib_solve over many simulated sites (fixed seeds):
//  1. consistency: 1 px pixel noise and 0.3 m survey noise, 12-30 landmarks, >= 200 trials:
//     the mean NEES of the 6-dof pose, e^T C^-1 e with C = covariance_rt_cam_enu as reported,
//     lies in [0.7, 1.3] x 6 (for 200 trials the 99.9% band of a correct mean is about +-0.6);
//  2. gross outliers: the same sites with outliers ADDED so that they are 25% of all landmarks
//     (the inliers and their noise draws identical): at least 99.5% of the outliers are flagged
//     (200-500 px mistakes on landmarks 12-150 m away, survey sigma 0.3 m), false flags rare, and the RMS pose error over the trials stays within 10% of the clean case;
//     and each reported sigma alone (position E, N, U; yaw, pitch, roll) has a mean squared
//     normalised error within [0.7, 1.3];
//  3. the time of one solve with 20 landmarks (printed, not asserted).
// The lens model cycles through pinhole, OPENCV8 and CAHVOR.
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "calib/rs_calib.h"
#include "core/rs_pose.h"
#include "test_solve_gen.h"
#include "tests/common/rs_test_pose.h"

#define NTRIALS 240

int main(void)
{
    gen_begin();
    double nees_sum = 0, nees_max = 0, vf_sum = 0;
    double sse_rot_clean = 0, sse_pos_clean = 0, sse_rot_out = 0, sse_pos_out = 0;
    double time_sum = 0, cond_min = INFINITY, cond_max = 0, z2_sum[6] = {0};
    int n_weak = 0;
    int n_ok = 0, n_time = 0, outliers_total = 0, outliers_missed = 0, false_flags = 0, inliers_total = 0;
    for (int t = 0; t < NTRIALS; t++) {
        const uint64_t seed = 1000 + (uint64_t)t;
        gen_rng rng;
        gen_seed(&rng, seed);
        const int N = 12 + (int)gen_uniform(&rng, 0, 19);
        gen_problem g;
        if (!gen_make(&g, &rng, (gen_lens)(t % 3), N, 1.0, 0.3)) {
            CHECK(0, "seed %llu: generator failed", (unsigned long long)seed);
            continue;
        }
        rs_calib_problem pb = gen_view(&g, NULL);
        rs_calib_result res;
        rs_err err = {0};
        rs_status st = rs_calib_solve(&res, &pb, NULL, &err);
        CHECK(st == RS_OK, "seed %llu: %s", (unsigned long long)seed, err.msg);
        if (st != RS_OK) continue;
        double e[6];
        rs_test_pose_error(e, res.rt_cam_enu, g.rt_true);
        const double nees = gen_nees(e, res.covariance_rt_cam_enu, 6);
        CHECK(isfinite(nees), "seed %llu: NEES not finite", (unsigned long long)seed);
        if (isfinite(nees)) {
            nees_sum += nees;
            nees_max = fmax(nees_max, nees);
            n_ok++;
        }
        vf_sum += res.variance_factor;
        { // each reported sigma alone: position E, N, U and yaw, pitch, roll
            double ypr_true[3];
            rs_pose_ypr_from_rt(ypr_true, NULL, g.rt_true);
            for (int k = 0; k < 3; k++) {
                const double zp = (res.position_enu_m[k] - g.position_true[k]) / res.sigma_position_enu_m[k];
                const double za =
                    remainder(res.yaw_pitch_roll_deg[k] - ypr_true[k], 360.0) / res.sigma_yaw_pitch_roll_deg[k];
                z2_sum[k] += zp * zp;
                z2_sum[3 + k] += za * za;
            }
        }
        cond_max = fmax(cond_max, res.condition_number);
        cond_min = fmin(cond_min, res.condition_number);
        if (strstr(res.warnings, "weak geometry")) n_weak++;
        double dC[3];
        for (int k = 0; k < 3; k++) dC[k] = res.position_enu_m[k] - g.position_true[k];
        sse_rot_clean += e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
        sse_pos_clean += dC[0] * dC[0] + dC[1] * dC[1] + dC[2] * dC[2];
        if (N == 20 || (n_time == 0 && t == NTRIALS - 1)) {
            time_sum += res.time_us;
            n_time++;
        }
        rs_calib_result_free(&res);

        // the same site with outliers appended: 25% of the total
        const int Nout = (N + 2) / 3;
        gen_append_outliers(&g, &rng, Nout, 0.3);
        pb = gen_view(&g, NULL);
        st = rs_calib_solve(&res, &pb, NULL, &err);
        CHECK(st == RS_OK, "seed %llu with %d outliers: %s", (unsigned long long)seed, Nout, err.msg);
        if (st != RS_OK) continue;
        for (int i = 0; i < g.N; i++) {
            if (g.outlier[i]) {
                outliers_total++;
                if (res.inlier[i]) {
                    outliers_missed++;
                    printf("seed %llu: outlier %d not flagged (normalised residual %.2f)\n", (unsigned long long)seed,
                           i, res.normalised_residual[i]);
                }
            } else {
                inliers_total++;
                if (!res.inlier[i]) false_flags++;
            }
        }
        rs_test_pose_error(e, res.rt_cam_enu, g.rt_true);
        for (int k = 0; k < 3; k++) dC[k] = res.position_enu_m[k] - g.position_true[k];
        sse_rot_out += e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
        sse_pos_out += dC[0] * dC[0] + dC[1] * dC[1] + dC[2] * dC[2];
        rs_calib_result_free(&res);
    }
    const double mean_nees = nees_sum / n_ok;
    printf("NEES over %d trials: mean %.3f (want %.1f..%.1f), max %.1f; mean variance factor %.3f\n", n_ok, mean_nees,
           0.7 * 6, 1.3 * 6, nees_max, vf_sum / n_ok);
    printf("condition numbers %.3g..%.3g; %d weak-geometry warnings\n", cond_min, cond_max, n_weak);
    CHECK(n_ok >= 200, "only %d usable trials", n_ok);
    CHECK(n_weak == 0, "weak-geometry warnings on well-posed sites");
    CHECK(mean_nees >= 0.7 * 6 && mean_nees <= 1.3 * 6, "mean NEES %.3f", mean_nees);
    static const char *zname[6] = {"E", "N", "U", "yaw", "pitch", "roll"};
    printf("mean (error/sigma)^2:");
    for (int k = 0; k < 6; k++) printf(" %s %.3f", zname[k], z2_sum[k] / n_ok);
    printf("\n");
    for (int k = 0; k < 6; k++)
        CHECK(z2_sum[k] / n_ok >= 0.7 && z2_sum[k] / n_ok <= 1.3, "%s: mean (error/sigma)^2 %.3f", zname[k],
              z2_sum[k] / n_ok);

    const double rr_c = sqrt(sse_rot_clean / n_ok), rp_c = sqrt(sse_pos_clean / n_ok);
    const double rr_o = sqrt(sse_rot_out / n_ok), rp_o = sqrt(sse_pos_out / n_ok);
    printf("outliers: %d of %d flagged, %d of %d inliers flagged falsely\n", outliers_total - outliers_missed,
           outliers_total, false_flags, inliers_total);
    printf("RMS pose error clean: rotation %.4g rad, position %.4g m; with 25%% outliers: %.4g rad "
           "(x%.3f), %.4g m (x%.3f)\n",
           rr_c, rp_c, rr_o, rr_o / rr_c, rp_o, rp_o / rp_c);
    // a 99.9% test cannot catch every mistake that happens to be marginal: demand 99.5%
    CHECK(outliers_missed <= 0.005 * outliers_total, "%d outliers not flagged", outliers_missed);
    CHECK(false_flags <= 0.01 * inliers_total + 2, "%d false flags", false_flags);
    CHECK(rr_o <= 1.1 * rr_c && rp_o <= 1.1 * rp_c, "pose error with outliers beyond 10%% of clean");
    if (n_time) printf("time per solve, 20 landmarks: %.0f us (mean of %d)\n", time_sum / n_time, n_time);
    char seeds[32];
    snprintf(seeds, sizeof(seeds), "1000..%d", 1000 + NTRIALS - 1);
    return gen_end(seeds);
}

// test_pose_region.c -- the pose's confidence region with the noise estimated from the data
// (rs_calib_result.region_m2, pose_dof; docs/calibration.md 3b, "The pose's 99.9% region").
// Oracle: the simulator's truth. On NTRIALS simulated sites of few landmarks (8, so that the
// estimated noise rests on about 10 degrees of freedom), 1 px picks and a 5 cm survey, stated
// right, the Mahalanobis distance of the true pose in the reported covariance is compared with
// the region at three levels (alpha 0.5, 0.1, 0.01; the region at alpha is 6 F(6, nu; 1 - alpha)
// / kappa, kappa recovered from region_m2 at 0.001): the fraction of poses outside lies within
// 4 binomial sigmas of alpha (plus 20% of alpha for the first-order covariance). The chi-square
// 6-dof ellipsoid at the same levels is printed for comparison; at alpha 0.01 it must leave out
// more poses than the region does (the heavier tail the estimated noise gives).
#include <math.h>
#include <stdio.h>

#include "calib/internal/rs_calib_noise.h"
#include "calib/rs_calib.h"
#include "test_solve_gen.h"

#define NTRIALS 2000

int main(void)
{
    gen_begin();
    static const double alphas[] = {0.5, 0.1, 0.01};
    enum { NA = sizeof alphas / sizeof alphas[0] };
    // chi-square 6 dof at 1 - alpha (the region with nu infinite)
    double chi2[NA];
    for (int a = 0; a < NA; a++) chi2[a] = rs_calib__pose_region_m2(alphas[a], INFINITY, 1.0);
    int n = 0, out_region[NA] = {0}, out_chi2[NA] = {0};
    double nu_sum = 0;
    for (int t = 0; t < NTRIALS; t++) {
        const uint64_t seed = 40000 + (uint64_t)t;
        gen_rng rng;
        gen_seed(&rng, seed);
        gen_problem g;
        if (!gen_make(&g, &rng, GEN_PINHOLE, 8, 1.0, 0.05)) continue;
        const rs_calib_problem pb = gen_view(&g, NULL);
        rs_calib_result r;
        rs_err err = {0};
        if (rs_calib_solve(&r, &pb, NULL, &err) != RS_OK) {
            rs_calib_result_free(&r);
            continue;
        }
        double e[6];
        for (int k = 0; k < 6; k++) e[k] = r.rt_cam_enu[k] - g.rt_true[k];
        const double m2 = gen_nees(e, r.covariance_rt_cam_enu, 6);
        const double nu = r.pose_dof;
        if (isfinite(m2) && isfinite(nu) && r.region_m2 > 0) {
            const double kappa = rs_calib__pose_region_m2(1e-3, nu, 1.0) / r.region_m2;
            for (int a = 0; a < NA; a++) {
                out_region[a] += !(m2 <= rs_calib__pose_region_m2(alphas[a], nu, kappa));
                out_chi2[a] += !(m2 <= chi2[a]);
            }
            nu_sum += nu;
            n++;
        }
        rs_calib_result_free(&r);
    }
    printf("%d of %d sites (8 landmarks, 1 px, 0.05 m), mean pose_dof %.1f\n", n, NTRIALS, n ? nu_sum / n : NAN);
    CHECK(n >= 0.95 * NTRIALS, "only %d of %d sites calibrated", n, NTRIALS);
    for (int a = 0; a < NA && n > 0; a++) {
        const double al = alphas[a], fr = (double)out_region[a] / n, fc = (double)out_chi2[a] / n;
        const double band = 4.0 * sqrt(al * (1 - al) / n) + 0.2 * al;
        printf("alpha %-5g outside the region %.4f, outside the chi-square ellipsoid %.4f (band %.4f .. %.4f)\n", al,
               fr, fc, al - band, al + band);
        CHECK(fabs(fr - al) <= band, "alpha %g: %.4f of the poses outside the region", al, fr);
    }
    CHECK(out_chi2[NA - 1] > out_region[NA - 1], "alpha 0.01: the chi-square ellipsoid leaves out %d, the region %d",
          out_chi2[NA - 1], out_region[NA - 1]);
    return gen_end("40000..41999");
}

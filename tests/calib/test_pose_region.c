// test_pose_region.c -- the pose's confidence region with the noise estimated from the data
// (rs_calib_result.region_m2, pose_dof; docs/calibration.md 3b, "The pose's 99.9% region").
// Oracle: the simulator's truth. NTRIALS simulated sites of few landmarks (8, so that the
// estimated noise rests on about 10 degrees of freedom), 1 px picks and a 5 cm survey, stated
// right, each solved twice: with the noise estimated (the default) and with the noise taken as
// stated (estimate_noise off: the covariance's scale is then known, and its chi-square ellipsoid
// is the first-order covariance's own calibration). The Mahalanobis distance of the true pose in
// the reported covariance is compared with the region at alpha 0.1 and 0.01 (the region at alpha
// is 6 F(6, nu; 1 - alpha) / kappa, kappa recovered from region_m2 at 0.001): the fraction of
// poses outside the estimated-noise region lies within 4 binomial sigmas (of a difference) of
// the fraction outside the known-noise ellipsoid -- the region makes an estimated noise as well
// calibrated as a known one. The chi-square ellipsoid with the noise estimated must leave out
// more at alpha 0.01 than the region does. Alpha 0.5 is printed, not asserted (the t's bulk is
// not the scale mixture's: 43% outside the median region where the known noise leaves 51%).
#include <math.h>
#include <stdio.h>

#include "calib/internal/rs_calib_vce.h"
#include "calib/rs_calib.h"
#include "test_solve_gen.h"

#define NTRIALS 2000

static bool solve(rs_calib_result *r, gen_problem *g, bool estimate_noise)
{
    const rs_calib_problem pb = gen_view(g, NULL);
    rs_calib_options o;
    rs_calib_options_default(&o);
    o.estimate_noise = estimate_noise;
    rs_err err = {0};
    return rs_calib_solve(r, &pb, &o, &err) == RS_OK;
}

int main(void)
{
    gen_begin();
    static const double alphas[] = {0.5, 0.1, 0.01};
    enum { NA = sizeof alphas / sizeof alphas[0] };
    // chi-square 6 dof at 1 - alpha (the region with nu infinite)
    double chi2[NA];
    for (int a = 0; a < NA; a++) chi2[a] = rs_calib__pose_region_m2(alphas[a], INFINITY, 1.0);
    int n = 0, out_region[NA] = {0}, out_chi2[NA] = {0}, out_known[NA] = {0};
    double nu_sum = 0;
    for (int t = 0; t < NTRIALS; t++) {
        const uint64_t seed = 40000 + (uint64_t)t;
        gen_rng rng;
        gen_seed(&rng, seed);
        gen_problem g;
        if (!gen_make(&g, &rng, GEN_PINHOLE, 8, 1.0, 0.05)) continue;
        rs_calib_result r, k;
        const bool ok = solve(&r, &g, true) && solve(&k, &g, false);
        double e[6], ek[6];
        for (int i = 0; ok && i < 6; i++) e[i] = r.rt_cam_enu[i] - g.rt_true[i], ek[i] = k.rt_cam_enu[i] - g.rt_true[i];
        const double m2 = ok ? gen_nees(e, r.covariance_rt_cam_enu, 6) : NAN;
        const double m2k = ok ? gen_nees(ek, k.covariance_rt_cam_enu, 6) : NAN;
        const double nu = ok ? r.pose_dof : NAN;
        if (ok && isfinite(m2) && isfinite(m2k) && isfinite(nu) && r.region_m2 > 0) {
            const double kappa = rs_calib__pose_region_m2(1e-3, nu, 1.0) / r.region_m2;
            for (int a = 0; a < NA; a++) {
                out_region[a] += !(m2 <= rs_calib__pose_region_m2(alphas[a], nu, kappa));
                out_chi2[a] += !(m2 <= chi2[a]);
                out_known[a] += !(m2k <= chi2[a]);
            }
            nu_sum += nu;
            n++;
        }
        rs_calib_result_free(&r);
        rs_calib_result_free(&k);
    }
    printf("%d of %d sites (8 landmarks, 1 px, 0.05 m), mean pose_dof %.1f; fraction of the true poses outside:\n", n,
           NTRIALS, n ? nu_sum / n : NAN);
    CHECK(n >= 0.95 * NTRIALS, "only %d of %d sites calibrated", n, NTRIALS);
    for (int a = 0; a < NA && n > 0; a++) {
        const double al = alphas[a], fr = (double)out_region[a] / n, fc = (double)out_chi2[a] / n;
        const double fk = (double)out_known[a] / n, band = 4.0 * sqrt(2.0 * al * (1 - al) / n);
        printf("alpha %-5g the region %.4f, the chi-square ellipsoid %.4f; the noise known: %.4f (band +-%.4f)\n", al,
               fr, fc, fk, band);
        if (al < 0.5)
            CHECK(fabs(fr - fk) <= band, "alpha %g: %.4f outside the region, %.4f with the noise known", al, fr, fk);
    }
    CHECK(out_chi2[NA - 1] > out_region[NA - 1], "alpha 0.01: the chi-square ellipsoid leaves out %d, the region %d",
          out_chi2[NA - 1], out_region[NA - 1]);
    return gen_end("40000..41999");
}

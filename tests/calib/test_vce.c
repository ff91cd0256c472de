// test_vce.c -- driver for test_vce.py: the variance components' model (calib/rs_calib_vce.c)
// on a simulated problem, printed as JSON for numpy to check against the full adjustment (the
// landmarks as unknowns, dense). One line: the problem (lens, intrinsics, pose, surveyed points,
// their sigmas, the picks), then per log theta the restricted log-likelihood, q, r, the Fisher
// and the observed information rs_calib__vce_evaluate reports, and the posterior mode
// rs_calib__vce_estimate finds with the prior factor 5; and the pose's confidence regions
// rs_calib__pose_region_m2 gives for a few (alpha, nu, kappa). Seed 7100.
#include <math.h>
#include <stdio.h>

#include "calib/internal/rs_calib_vce.h"
#include "calib/rs_calib.h"
#include "test_solve_gen.h"

static void print_array(const char *name, const double *x, int n)
{
    printf("\"%s\": [", name);
    for (int i = 0; i < n; i++) printf("%s%.17g", i ? ", " : "", x[i]);
    printf("]");
}

int main(void)
{
    gen_rng rng;
    gen_seed(&rng, 7100);
    gen_problem g;
    enum { N = 12 };
    if (!gen_make(&g, &rng, GEN_OPENCV8, N, 1.0, 0.05)) return 1;
    // the pose: the weighted least squares at the stated sigmas (no noise estimation), so that
    // the linearisation point is a solution, as in rs_calib_solve
    rs_calib_options o;
    rs_calib_options_default(&o);
    o.estimate_noise = false;
    o.robust_scale = 0.0;
    const rs_calib_problem pb = gen_view(&g, NULL);
    rs_calib_result res;
    rs_err err = {0};
    if (rs_calib_solve(&res, &pb, &o, &err) != RS_OK) {
        printf("{\"error\": \"%s\"}\n", err.msg);
        return 1;
    }
    bool use[N];
    for (int i = 0; i < N; i++) use[i] = true;
    const rs_calib_noise_state s = {.N = N,
                                    .rt_cam_c = res.rt_cam_enu,
                                    .p_c_m = g.p_survey,
                                    .p_survey_c_m = g.p_survey,
                                    .sigma_enu_m = g.sigma_enu,
                                    .q_px = g.q_obs,
                                    .sigma_px = g.sigma_px,
                                    .use = use,
                                    .lensmodel = &g.lensmodel,
                                    .intrinsics = g.intrinsics,
                                    .intrinsics_nominal = g.intrinsics};
    const double L0[3] = {0, 0, 0};
    rs_calib__vce *v = NULL;
    if (rs_calib__vce_build(&v, &s, NULL, L0, &err) != RS_OK) {
        printf("{\"error\": \"%s\"}\n", err.msg);
        return 1;
    }
    char name[64];
    mrcal_lensmodel_name(name, sizeof name, &g.lensmodel);
    printf("{\"lensmodel\": \"%s\", ", name);
    print_array("intrinsics", g.intrinsics, g.Nintrinsics);
    printf(", ");
    print_array("rt", res.rt_cam_enu, 6);
    printf(", ");
    print_array("p", g.p_survey, 3 * N);
    printf(", ");
    print_array("sigma_enu", g.sigma_enu, 3 * N);
    printf(", ");
    print_array("q", g.q_obs, 2 * N);
    printf(", ");
    print_array("sigma_px", g.sigma_px, N);
    printf(", \"evaluations\": [");
    static const double Ls[][3] = {{0, 0, 0}, {0.7, -0.4, 1.1}, {-1.2, 2.0, 0.3}, {2.5, -1.5, -2.0}};
    for (int k = 0; k < 4; k++) {
        double ll, q[3], r[3], F[9], O[9];
        if (rs_calib__vce_evaluate(v, Ls[k], &ll, q, r, F, O, &err) != RS_OK) {
            printf("]}\n");
            return 1;
        }
        printf("%s{", k ? ", " : "");
        print_array("L", Ls[k], 3);
        printf(", \"loglik\": %.17g, ", ll);
        print_array("q", q, 3);
        printf(", ");
        print_array("r", r, 3);
        printf(", ");
        print_array("F", F, 9);
        printf(", ");
        print_array("O", O, 9);
        printf("}");
    }
    double L[3] = {0, 0, 0};
    if (rs_calib__vce_estimate(L, NULL, v, 5.0, &err) != RS_OK) return 1;
    printf("], ");
    print_array("mode", L, 3);
    // the pose's confidence region (rs_calib__pose_region_m2): alpha, nu (1e300: INFINITY), kappa
    static const double regions[][3] = {{1e-3, 3, 1},      {1e-3, 5, 1},   {1e-3, 10, 1},    {1e-3, 20, 1},
                                        {1e-3, 50, 1},     {1e-3, 200, 1}, {1e-3, 1e300, 1}, {0.05, 7.5, 1.25},
                                        {0.01, 33.3, 1.1}, {1e-3, 1e6, 1}};
    printf(", \"regions\": [");
    for (int k = 0; k < (int)(sizeof regions / sizeof regions[0]); k++) {
        const double nu = regions[k][1] >= 1e300 ? INFINITY : regions[k][1];
        printf("%s[%.17g, %.17g, %.17g, %.17g]", k ? ", " : "", regions[k][0], regions[k][1], regions[k][2],
               rs_calib__pose_region_m2(regions[k][0], nu, regions[k][2]));
    }
    printf("], \"prior_factor\": 5}\n");
    rs_calib__vce_free(v);
    rs_calib_result_free(&res);
    return 0;
}

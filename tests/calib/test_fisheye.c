// test_fisheye.c -- rs_calib_solve on fisheye cameras (issue 38, "What must show", first line):
// one overhead camera over a junction, 1280x960, mrcal's LENSMODEL_CAHVORE_linearity=0.00 as
//   - an equidistant lens (r = f theta, f = 340 px, no distortion), and
//   - a Kannala-Brandt lens (k1, k2 drawn; r1 = k1, r2 = k2),
// 15-25 ground points, 1 px pixel noise, 0.3 m survey noise (sim/rs_simulate.h's camera
// problem, camera 10 m up, 3 m from the point it looks at), the sigmas stated as drawn, the
// solver's defaults (noise estimated from the data). Over NTRIALS (1000) problems per lens (200 leave the rotation ratio 3% noisy):
//   1. efficiency: the RMS rotation error (in the Rodrigues chart) and the RMS position error
//      within 1.1x of the Cramer-Rao bound -- the covariance of a solve on the exact data at the
//      true noise, averaged over the trials (bench/rs_bench_calib.c computes it the same way);
//   2. consistency: the mean NEES of the 6-dof pose, e^T C^-1 e with C = covariance_rt_cam_enu
//      as reported, within [0.7, 1.3] x 6.
// The pixels are CAHVORE's through core/rs_lens.c, whose projection tests/core/test_lens.c checks
// against mrcal and f theta. Fixed seeds, printed on failure.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "calib/rs_calib.h"
#include "sim/rs_simulate.h"
#include "test_solve_gen.h"
#include "tests/common/rs_test_pose.h"

#define NTRIALS 1000

static void fill(rs_calib_problem *cp, const rs_simulate_problem *P, const double *p, const double *q, double *sig_enu,
                 double *sig_px)
{
    memset(cp, 0, sizeof *cp);
    cp->N = P->Npoints;
    cp->camera = &P->camera;
    cp->p_enu_m = p;
    cp->q_px = q;
    for (int i = 0; i < P->Npoints; i++) {
        sig_px[i] = 1.0;
        for (int k = 0; k < 3; k++) sig_enu[3 * i + k] = 0.3;
    }
    cp->sigma_px = sig_px;
    cp->sigma_enu_m = sig_enu;
}

static void run(const char *name, bool distortion, uint64_t seed0)
{
    double ss_rot = 0, ss_pos = 0, crb_rot = 0, crb_pos = 0, nees_sum = 0;
    int n = 0;
    for (int t = 0; t < NTRIALS; t++) {
        rs_simulate_camera_options o;
        rs_simulate_camera_options_default(&o);
        o.lensmodel = "LENSMODEL_CAHVORE_linearity=0.00";
        o.width_px = 1280;
        o.height_px = 960;
        o.hfov_deg = 216;
        o.distortion = distortion;
        o.camera_height_m = 10;
        o.distance_m = 3;
        o.max_range_m = 40;
        o.elevated_fraction = 0;
        o.Nlandmarks = 15 + (int)(t % 11);
        o.pixel_sigma_px = 1;
        o.survey_sigma_h_m = o.survey_sigma_v_m = 0.3;
        o.outlier_fraction = 0;
        o.seed = seed0 + (uint64_t)t;
        rs_simulate_problem *P = NULL;
        rs_err err = {0};
        if (rs_simulate_camera_problem(&P, &o, &err) != RS_OK) {
            CHECK(0, "%s: seed %llu: simulate: %s", name, (unsigned long long)o.seed, err.msg);
            continue;
        }
        const int N = P->Npoints;
        double *sig_enu = malloc(sizeof(double) * 3 * (size_t)N), *sig_px = malloc(sizeof(double) * (size_t)N);
        rs_calib_problem cp;
        rs_calib_result res, bound;
        // the bound: exact data, the true noise, no robust loss
        fill(&cp, P, P->p_enu_true_m, P->q_true_px, sig_enu, sig_px);
        rs_calib_options opt;
        rs_calib_options_default(&opt);
        opt.robust_scale = 0.0;
        opt.estimate_noise = false;
        const rs_status st_bound = rs_calib_solve(&bound, &cp, &opt, &err);
        CHECK(st_bound == RS_OK, "%s: seed %llu: bound: %s", name, (unsigned long long)o.seed, err.msg);
        // the estimate: noisy data, defaults
        fill(&cp, P, P->p_enu_survey_m, P->q_px, sig_enu, sig_px);
        const rs_status st = rs_calib_solve(&res, &cp, NULL, &err);
        CHECK(st == RS_OK, "%s: seed %llu: solve: %s", name, (unsigned long long)o.seed, err.msg);
        if (st == RS_OK && st_bound == RS_OK) {
            double e[6];
            rs_test_pose_error(e, res.rt_cam_enu, P->camera.rt_cam_enu);
            ss_rot += e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
            for (int k = 0; k < 3; k++) {
                const double d = res.position_enu_m[k] - P->p_cam_enu_m[k];
                ss_pos += d * d;
                crb_rot += bound.covariance_rt_cam_enu[7 * k];
                crb_pos += bound.sigma_position_enu_m[k] * bound.sigma_position_enu_m[k];
            }
            const double nees = gen_nees(e, res.covariance_rt_cam_enu, 6);
            CHECK(isfinite(nees), "%s: NEES not finite", name);
            if (isfinite(nees)) nees_sum += nees;
            n++;
        }
        if (st == RS_OK) rs_calib_result_free(&res);
        if (st_bound == RS_OK) rs_calib_result_free(&bound);
        free(sig_enu);
        free(sig_px);
        rs_simulate_problem_free(P);
    }
    CHECK(n == NTRIALS, "%s: %d of %d trials solved", name, n, NTRIALS);
    if (!n) return;
    const double rot_ratio = sqrt(ss_rot / crb_rot), pos_ratio = sqrt(ss_pos / crb_pos), nees = nees_sum / n;
    printf("%s: %d trials: rotation RMS %.4f deg = %.3f x CRB, position RMS %.3f m = %.3f x CRB, mean NEES %.2f "
           "(6 dof)\n",
           name, n, sqrt(ss_rot / n) * 180 / M_PI, rot_ratio, sqrt(ss_pos / n), pos_ratio, nees);
    CHECK(rot_ratio <= 1.1, "%s: rotation RMS %.3f x the CRB (want <= 1.1)", name, rot_ratio);
    CHECK(pos_ratio <= 1.1, "%s: position RMS %.3f x the CRB (want <= 1.1)", name, pos_ratio);
    CHECK(nees >= 0.7 * 6 && nees <= 1.3 * 6, "%s: mean NEES %.2f (want %.1f..%.1f)", name, nees, 0.7 * 6, 1.3 * 6);
}

int main(void)
{
    gen_begin();
    run("equidistant", false, 3800);
    run("kannala-brandt", true, 5000);
    return gen_end("seeds 3800..4799 (equidistant), 5000..5999 (Kannala-Brandt)");
}

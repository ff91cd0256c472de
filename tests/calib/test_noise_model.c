// test_noise_model.c -- issue 13, items 1 and 2: noise estimated from the data (variance
// components) and survey-grade outlier tests (data snooping), on the solver's own simulated
// problems (test_solve_gen.h), against the truth the generator drew:
//   - stated sigmas wrong by 0.2x and 5x, pixel and survey separately: pose errors (RMS over the
//     trials) within 1.1x of those with the right sigmas, mean NEES of the 6-dof pose in
//     [0.7, 1.3] x 6, and each group estimated from the data within 20% of the truth (median
//     over the trials; 20-30 landmarks each);
//   - 25% gross outliers (200-500 px, 10+ sigma): at least 95% flagged, at most 2% of the good
//     landmarks flagged, with the right sigmas and each of the four mis-statements;
//   - clean data with mis-stated sigmas: at most the nominal 0.6% of the landmarks flagged (0.1%
//     for the coarse test, 0.1% per tested observation; 2.85% with the survey stated 5x too
//     precise until the coarse test's rejections were tested again at the estimated noise);
//   - 25% moderate outliers (20-40 px): those of 10+ sigma of the pick's whole noise flagged, 95%
//     (85% with the survey stated 5x too loose; below).
// The trials are independent: each draws its own xoshiro256** stream (test_solve_gen.h). (Until
// 2026-11-24 consecutive seeds gave one splitmix64 stream shifted by one draw, so the 100 trials
// shared their noise and a few unlucky draws counted many times: mean NEES 7.6 with the true
// sigmas and no estimation, against 6.2 for each geometry alone by Monte Carlo.)
// Truth: 1 px picks and a 5 cm survey, so that both groups carry redundancy.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mrcal/poseutils.h>

#include "calib/rs_calib.h"
#include "core/rs_pose.h"
#include "core/rs_stats.h"
#include "core/rs_units.h"
#include "test_solve_gen.h"

#define NTRIALS 100
static const double TRUE_PX = 1.0, TRUE_M = 0.05;

typedef struct {
    const char *name;
    double px, m; // stated / true
} config;

typedef struct {
    double sse_rot, sse_pos, nees_sum;
    int n;
    double ratio[RS_CALIB_NOISE_NGROUPS][NTRIALS];
    int nratio[RS_CALIB_NOISE_NGROUPS];
    int out_total, out_flagged, good_total, good_flagged;
    int out10_total, out10_flagged; // outliers of 10 sigma or more (gen_pick_sigmas)
} stats;

// outlier_px: the last quarter of the landmarks picked off by 200-500 px (outlier_px >= 200) or
// by outlier_px to 2 outlier_px; 0: none
static void run(stats *s, const config *c, double outlier_px)
{
    memset(s, 0, sizeof *s);
    for (int t = 0; t < NTRIALS; t++) {
        gen_rng rng;
        gen_seed(&rng, 5000 + (uint64_t)t);
        const int N = 20 + t % 11;
        gen_problem g;
        if (!gen_make(&g, &rng, (gen_lens)(t % 2), N, TRUE_PX, TRUE_M)) continue;
        if (outlier_px >= 200) // a quarter: the most snooping may take
            gen_add_outliers(&g, &rng, N / 4);
        else if (outlier_px > 0)
            gen_add_outliers_px(&g, &rng, N / 4, outlier_px, 2 * outlier_px);
        bool ten[GEN_MAXN]; // 10 sigma or more of the pick's whole noise, at the true sigmas
        for (int i = 0; i < g.N; i++) ten[i] = g.outlier[i] && gen_pick_sigmas(&g, i) >= 10.0;
        for (int i = 0; i < g.N; i++) {
            g.sigma_px[i] *= c->px;
            for (int k = 0; k < 3; k++) g.sigma_enu[3 * i + k] *= c->m;
        }
        const rs_calib_problem pb = gen_view(&g, NULL);
        rs_calib_result r;
        rs_err e = {0};
        const rs_status st = rs_calib_solve(&r, &pb, NULL, &e);
        CHECK(st == RS_OK, "%s trial %d: %s", c->name, t, e.msg);
        if (st != RS_OK) continue;
        const double drot = RS_DEG_PER_RAD * rs_pose_rotation_between(NULL, NULL, r.rt_cam_enu, g.rt_true);
        const double dpos =
            hypot(hypot(r.position_enu_m[0] - g.position_true[0], r.position_enu_m[1] - g.position_true[1]),
                  r.position_enu_m[2] - g.position_true[2]);
        double d[6];
        for (int k = 0; k < 6; k++) d[k] = r.rt_cam_enu[k] - g.rt_true[k];
        s->sse_rot += drot * drot;
        s->sse_pos += dpos * dpos;
        s->nees_sum += gen_nees(d, r.covariance_rt_cam_enu, 6);
        s->n++;
        const double truth[RS_CALIB_NOISE_NGROUPS] = {TRUE_PX, TRUE_M, TRUE_M};
        for (int k = 0; k < RS_CALIB_NOISE_NGROUPS; k++)
            if (r.noise[k].estimated_from_data) s->ratio[k][s->nratio[k]++] = r.noise[k].estimated / truth[k];
        for (int i = 0; i < g.N; i++) { // the final M-estimate's weights (rs_calib.h, weight)
            const double want =
                r.inlier[i] ? 1.0 / (1.0 + r.normalised_residual[i] * r.normalised_residual[i] / 4.0) : 0;
            CHECK(fabs(r.weight[i] - want) <= 1e-12, "%s trial %d landmark %d: weight %.15g, want %.15g", c->name, t, i,
                  r.weight[i], want);
        }
        for (int i = 0; i < g.N; i++) {
            if (g.outlier[i]) {
                s->out_total++;
                s->out_flagged += !r.inlier[i];
                s->out10_total += ten[i];
                s->out10_flagged += ten[i] && !r.inlier[i];
            } else {
                s->good_total++;
                s->good_flagged += !r.inlier[i];
            }
        }
        rs_calib_result_free(&r);
    }
}

int main(void)
{
    gen_begin();
    static const config configs[] = {{"right sigmas", 1, 1},
                                     {"pixel x0.2", 0.2, 1},
                                     {"pixel x5", 5, 1},
                                     {"survey x0.2", 1, 0.2},
                                     {"survey x5", 1, 5}};
    static stats s[5];
    static const char *const group[3] = {"pixel", "survey-h", "survey-v"};
    double rot0 = 0, pos0 = 0;
    printf("%-14s %9s %9s %7s %28s %8s\n", "stated", "rot_deg", "pos_m", "NEES", "estimated/true (median)", "flagged");
    for (int k = 0; k < 5; k++) {
        run(&s[k], &configs[k], 0);
        const double rot = sqrt(s[k].sse_rot / s[k].n), pos = sqrt(s[k].sse_pos / s[k].n);
        const double nees = s[k].nees_sum / s[k].n;
        if (k == 0) rot0 = rot, pos0 = pos;
        double med[3];
        for (int g = 0; g < 3; g++) med[g] = rs_stats_median(s[k].ratio[g], s[k].nratio[g]);
        printf("%-14s %9.4f %9.4f %7.2f %9.3f %9.3f %9.3f %7.2f%%\n", configs[k].name, rot, pos, nees, med[0], med[1],
               med[2], 100.0 * s[k].good_flagged / s[k].good_total);
        CHECK(s[k].n >= NTRIALS - 2, "%s: %d of %d trials solved", configs[k].name, s[k].n, NTRIALS);
        CHECK(rot <= 1.1 * rot0 && pos <= 1.1 * pos0, "%s: pose errors %.4f deg, %.4f m vs %.4f deg, %.4f m right",
              configs[k].name, rot, pos, rot0, pos0);
        // the bands: mean NEES in [0.7, 1.3] x 6, each group's median estimate within
        // 20% of the truth
        CHECK(nees >= 0.7 * 6 && nees <= 1.3 * 6, "%s: mean NEES %.2f", configs[k].name, nees);
        for (int g = 0; g < 3; g++) {
            // a group stated 5x too precise rests on its prior in some trials (little redundancy)
            const bool tight = configs[k].px < 1 || configs[k].m < 1;
            CHECK(s[k].nratio[g] >= (tight ? NTRIALS / 4 : NTRIALS / 2), "%s: %s estimated in only %d trials",
                  configs[k].name, group[g], s[k].nratio[g]);
            CHECK(fabs(med[g] - 1) <= 0.2, "%s: %s estimated at %.3f x the truth", configs[k].name, group[g], med[g]);
        }
        // the bar: no more than the nominal false-alarm rate, about 0.6% of the landmarks
        // (0.1% for the coarse test, 0.1% per tested observation of the snooping; 0.08-0.28%
        // measured, 2.85% with the survey stated 5x too precise before the coarse test's
        // rejections were tested again at the estimated noise, docs/calibration.md 3c)
        CHECK(s[k].good_flagged <= 0.006 * s[k].good_total, "%s: %d of %d clean landmarks flagged", configs[k].name,
              s[k].good_flagged, s[k].good_total);
    }
    // 25% gross outliers, right and mis-stated sigmas
    for (int k = 0; k < 5; k++) {
        static stats acc;
        run(&acc, &configs[k], 200);
        printf("%-14s 25%% outliers: %d of %d flagged (%.1f%%), %d of %d good flagged (%.2f%%)\n", configs[k].name,
               acc.out_flagged, acc.out_total, 100.0 * acc.out_flagged / acc.out_total, acc.good_flagged,
               acc.good_total, 100.0 * acc.good_flagged / acc.good_total);
        CHECK(acc.out_flagged >= 0.95 * acc.out_total, "%s: only %d of %d outliers flagged", configs[k].name,
              acc.out_flagged, acc.out_total);
        CHECK(acc.good_flagged <= 0.02 * acc.good_total, "%s: %d of %d good landmarks flagged", configs[k].name,
              acc.good_flagged, acc.good_total);
    }
    // 25% moderate outliers, 20-40 px: 20-40 sigma of the 1 px picks, but the 5 cm survey adds up
    // to 8 px to a pick's whole noise on a near landmark: 352 of the 590 are 10 sigma or more of it
    // (gen_pick_sigmas, at the true sigmas). The issue asks 95% flagged at 10+ sigma. Measured
    // (2026-11-25, the coarse test at the noise's scale from the data, rs_calib_robust.c): 100% /
    // 100% / 99.7% / 100% with the right sigmas, pixels 5x too precise, 5x too loose, survey 5x too
    // precise; 97.2% with the survey stated 5x too loose (since its vertical group follows the
    // horizontal one's narrowing: 90.1% before, 71.6% before the scale from the data). Guarded at
    // 95% in every row; all of them, 90% where the statement is not too loose (docs/calibration.md
    // 3a)
    for (int k = 0; k < 5; k++) {
        static stats acc;
        run(&acc, &configs[k], 20);
        printf("%-14s 25%% outliers 20-40 px: %d of %d flagged (%.1f%%; 10+ sigma %d of %d, %.1f%%), %d of %d good "
               "flagged (%.2f%%)\n",
               configs[k].name, acc.out_flagged, acc.out_total, 100.0 * acc.out_flagged / acc.out_total,
               acc.out10_flagged, acc.out10_total, 100.0 * acc.out10_flagged / acc.out10_total, acc.good_flagged,
               acc.good_total, 100.0 * acc.good_flagged / acc.good_total);
        if (configs[k].px <= 1 && configs[k].m <= 1)
            CHECK(acc.out_flagged >= 0.90 * acc.out_total, "%s: only %d of %d moderate outliers flagged",
                  configs[k].name, acc.out_flagged, acc.out_total);
        CHECK(acc.out10_flagged >= 0.95 * acc.out10_total, "%s: only %d of %d outliers of 10+ sigma flagged",
              configs[k].name, acc.out10_flagged, acc.out10_total);
        CHECK(acc.good_flagged <= 0.02 * acc.good_total, "%s: %d of %d good landmarks flagged", configs[k].name,
              acc.good_flagged, acc.good_total);
    }
    return gen_end("5000..5099");
}

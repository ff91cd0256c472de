// tests/synth/fleet/test_fleet_realism.c -- issue 18: the fleet's dimensions and colours against
// their cited distributions (docs/fleet.md), over many seeded draws (seeds printed on failure):
//   - every class: 4000 draws of length, width and height all inside [min, max]; their mean
//     within 4 standard errors of the closed-form mean of the truncated normal
//     (mu + sigma (phi(a) - phi(b)) / (Phi(b) - Phi(a))), the oracle;
//   - the classes rs_synth_fleet_random draws (40000 seeds): Pearson's chi-square against the one
//     default mix of docs/traffic.md ("Class mix", the weights written out below, the same as
//     the traffic's) below 27.88 (9 degrees of freedom, p = 0.001);
//   - the passenger cars (sedan, hatchback, SUV in that mix): mean length,
//     width, height within 0.08, 0.03, 0.05 m of Inovev's 2022 European average car
//     (4.36 x 1.81 x 1.55 m);
//   - the motorcycle (with rider): within 0.10 m of nuScenes' mean motorcycle box; the bus and
//     trucks' ranges within the EU's limits on width, height and length;
//   - two-wheelers: within 0.15 m of SUMO's defaults for the box with its rider (bicycle
//     1.6 x 0.65 x 1.7 m, motorcycle 2.2 x 0.9 x 1.5 m);
//   - colours: 20000 vehicles sorted into families by their nearest palette colour; Pearson's
//     chi-square against Axalta's 2022 shares below 26.12 (8 degrees of freedom, p = 0.001).
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/rs_color.h"
#include "synth/fleet/rs_synth_fleet.h"
#include "tests/synth/test_fleet_check.h"

static double phi(double x) { return exp(-0.5 * x * x) / sqrt(2 * M_PI); }
static double Phi(double x) { return 0.5 * erfc(-x / sqrt(2)); }

int main(void)
{
    enum { N = 4000 };
    double car_mean[3] = {0, 0, 0};
    int ncar = 0;
    for (int c = 0; c < RS_SYNTH_NCLASSES; c++) {
        rs_synth_class_range r;
        CHECK(rs_synth_class_range_get(&r, (rs_synth_class)c, NULL) == RS_OK, "range %d", c);
        const double *rng[3] = {r.length_m, r.width_m, r.height_m};
        double sum[3] = {0, 0, 0};
        int outside = 0;
        for (int s = 0; s < N; s++) {
            rs_synth_vehicle in = {.cls = (rs_synth_class)c, .variant = 777000 + (uint64_t)s, .rgb = {-1, -1, -1}}, v;
            CHECK(rs_synth_fleet_resolve(&v, &in, NULL) == RS_OK, "resolve class %d seed %d", c, 777000 + s);
            double d[3] = {v.length_m, v.width_m, v.height_m};
            for (int k = 0; k < 3; k++) {
                sum[k] += d[k];
                outside += d[k] < rng[k][0] || d[k] > rng[k][1];
            }
        }
        CHECK(outside == 0, "%s: %d dimensions outside the range (seeds 777000+)", rs_synth_class_name(c), outside);
        for (int k = 0; k < 3; k++) {
            double mu = r.mean_m[k], sd = r.sd_m[k], a = (rng[k][0] - mu) / sd, b = (rng[k][1] - mu) / sd;
            double Z = Phi(b) - Phi(a), m = mu + sd * (phi(a) - phi(b)) / Z;
            double var = sd * sd * (1 + (a * phi(a) - b * phi(b)) / Z - pow((phi(a) - phi(b)) / Z, 2));
            double got = sum[k] / N, se = sqrt(var / N);
            CHECK(fabs(got - m) < 4 * se, "%s dimension %d: mean %.4f m, truncated normal %.4f m (se %.4f)",
                  rs_synth_class_name(c), k, got, m, se);
            printf("%-18s dim %d: mean %.3f m (truncated normal %.3f m)\n", rs_synth_class_name(c), k, got, m);
        }
        // nuScenes' mean motorcycle box (2.100 x 0.763 x 1.444 m; docs/fleet.md): most are ridden,
        // the box holding the rider as ours does
        if (c == RS_SYNTH_MOTORCYCLE) {
            const double nus[3] = {2.100, 0.763, 1.444};
            for (int k = 0; k < 3; k++)
                CHECK(fabs(sum[k] / N - nus[k]) < 0.10, "motorcycle dimension %d: mean %.3f vs nuScenes %.3f m", k,
                      sum[k] / N, nus[k]);
        }
        // the EU limits (Directive 96/53/EC as amended by 2015/719): width 2.55 m, height 4.00 m,
        // length: two-axle bus 13.5 m, rigid truck 12.0 m, tractor and semi-trailer 16.5 m
        if (c == RS_SYNTH_BUS || c == RS_SYNTH_BOX_TRUCK || c == RS_SYNTH_ARTICULATED_TRUCK) {
            const double Lmax = c == RS_SYNTH_BUS ? 13.5 : c == RS_SYNTH_BOX_TRUCK ? 12.0 : 16.5;
            CHECK(r.length_m[1] <= Lmax && r.width_m[1] <= 2.55 && r.height_m[1] <= 4.00,
                  "%s: range up to %.2f x %.2f x %.2f m beyond the EU limits (%.1f x 2.55 x 4.00 m)",
                  rs_synth_class_name(c), r.length_m[1], r.width_m[1], r.height_m[1], Lmax);
        }
        if (c == RS_SYNTH_MOTORCYCLE || c == RS_SYNTH_BICYCLE) {
            const double sumo[2][3] = {{2.2, 0.9, 1.5}, {1.6, 0.65, 1.7}};
            const double *want = sumo[c == RS_SYNTH_BICYCLE];
            for (int k = 0; k < 3; k++)
                CHECK(fabs(sum[k] / N - want[k]) < 0.15, "%s dimension %d: mean %.3f vs SUMO %.2f m",
                      rs_synth_class_name(c), k, sum[k] / N, want[k]);
        }
    }
    // passenger cars as rs_synth_fleet_random draws them, and its class shares
    static const double mix[RS_SYNTH_NCLASSES] = {0.234,  0.2145, 0.2925,  0.02925, 0.0975,
                                                  0.0195, 0.0585, 0.02925, 0.008,   0.017};
    int nclass[RS_SYNTH_NCLASSES] = {0};
    const int Nr = 40000;
    for (int s = 0; s < Nr; s++) {
        rs_synth_vehicle v;
        CHECK(rs_synth_fleet_random(&v, 5000000 + (uint64_t)s, NULL) == RS_OK, "random %d", s);
        if ((int)v.cls >= 0 && v.cls < RS_SYNTH_NCLASSES) nclass[v.cls]++;
        if (v.cls != RS_SYNTH_SEDAN && v.cls != RS_SYNTH_HATCHBACK && v.cls != RS_SYNTH_SUV) continue;
        car_mean[0] += v.length_m, car_mean[1] += v.width_m, car_mean[2] += v.height_m;
        ncar++;
    }
    double chi2_mix = 0;
    for (int c = 0; c < RS_SYNTH_NCLASSES; c++) chi2_mix += pow(nclass[c] - Nr * mix[c], 2) / (Nr * mix[c]);
    printf("classes of rs_synth_fleet_random against the default mix: chi-square %.2f (9 dof, p = 0.001 at 27.88); "
           "motorcycles %d, bicycles %d of %d\n",
           chi2_mix, nclass[RS_SYNTH_MOTORCYCLE], nclass[RS_SYNTH_BICYCLE], Nr);
    CHECK(chi2_mix < 27.88, "class shares: chi-square %.2f >= 27.88 (seeds 5000000+)", chi2_mix);
    const double inovev[3] = {4.36, 1.81, 1.55}, tol[3] = {0.08, 0.03, 0.05};
    for (int k = 0; k < 3; k++) {
        car_mean[k] /= ncar;
        CHECK(fabs(car_mean[k] - inovev[k]) < tol[k], "cars: dimension %d mean %.3f m vs Inovev 2022 %.2f m", k,
              car_mean[k], inovev[k]);
    }
    printf("cars (%d): mean %.3f x %.3f x %.3f m; Inovev 2022: 4.36 x 1.81 x 1.55 m\n", ncar, car_mean[0], car_mean[1],
           car_mean[2]);
    // colours: nearest palette colour (linear RGB), the palette and shares of docs/fleet.md
    static const double share[9] = {0.34, 0.21, 0.19, 0.08, 0.08, 0.05, 0.03, 0.01, 0.01};
    static const double srgb[9][3] = {{0.93, 0.93, 0.92}, {0.05, 0.05, 0.06}, {0.42, 0.43, 0.45},
                                      {0.72, 0.73, 0.75}, {0.10, 0.22, 0.50}, {0.62, 0.06, 0.07},
                                      {0.55, 0.45, 0.33}, {0.12, 0.32, 0.18}, {0.85, 0.70, 0.10}};
    int count[9] = {0};
    const int Nc = 20000;
    for (int s = 0; s < Nc; s++) {
        rs_synth_vehicle v;
        CHECK(rs_synth_fleet_random(&v, 9000000 + (uint64_t)s, NULL) == RS_OK, "random %d", s);
        int best = 0;
        double bd = 1e9;
        for (int k = 0; k < 9; k++) {
            double d = 0;
            for (int ch = 0; ch < 3; ch++)
                d += pow(pow(v.rgb[ch], 1 / 2.2) - pow(rs_color_srgb_decode_exact(srgb[k][ch]), 1 / 2.2), 2);
            if (d < bd) bd = d, best = k;
        }
        count[best]++;
    }
    double chi2 = 0;
    for (int k = 0; k < 9; k++) chi2 += pow(count[k] - Nc * share[k], 2) / (Nc * share[k]);
    printf("colours: white %d black %d grey %d silver %d blue %d red %d beige %d green %d yellow %d of %d; "
           "chi-square %.2f (8 dof, p = 0.001 at 26.12)\n",
           count[0], count[1], count[2], count[3], count[4], count[5], count[6], count[7], count[8], Nc, chi2);
    CHECK(chi2 < 26.12, "colour shares: chi-square %.2f >= 26.12 (seeds 9000000+)", chi2);
    return failures ? 1 : 0;
}

// test_traffic_api -- C-level checks of synth/traffic/rs_synth_traffic.h and rs_synth_sumo.h.
//   test_traffic_api sat
//       rs_synth_footprints_overlap against a brute force (both rectangles rasterised on a 2 cm
//       grid: overlap iff some cell centre lies inside both, up to cells on the boundary) for
//       20000 random pairs, seed 11; and rs_synth_class_mix_parse's errors.
//   test_traffic_api fcd FCD GEO ZONE NORTH OFFX OFFY LAT0 LON0 H0 TYPE L W H
//       reads FCD with rs_synth_sumo_read_fcd and prints "id e n yaw_deg" per vehicle (for
//       tests/synth/traffic/test_traffic_sumo.py, which computes the truth with cct).
//   test_traffic_api lanes FILE LAT0 LON0 H0
//       reads a lanes file; prints "OK N" or the error message (exit 1).
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_rng.h"
#include "core/rs_units.h"
#include "sim/rs_simulate.h"
#include "synth/fleet/rs_synth_fleet.h"
#include "synth/traffic/rs_synth_sumo.h"
#include "synth/traffic/rs_synth_traffic.h"

// Inside the footprint rectangle of v, with a margin (negative: strictly inside by -margin).
static int inside(const rs_synth_vehicle *v, double e, double n, double margin)
{
    double f[2] = {sin(v->yaw_deg * RS_RAD_PER_DEG), cos(v->yaw_deg * RS_RAD_PER_DEG)};
    double de = e - v->e_m, dn = n - v->n_m;
    double x = de * f[0] + dn * f[1], y = -de * f[1] + dn * f[0];
    return fabs(x) <= 0.5 * v->length_m + margin && fabs(y) <= 0.5 * v->width_m + margin;
}

static int test_sat(void)
{
    const uint64_t seed = 11;
    rs_rng rng;
    rs_rng_seed(&rng, seed);
    const double h = 0.02;
    int fails = 0, Noverlap = 0, Nambiguous = 0;
    for (int t = 0; t < 20000; t++) {
        rs_synth_vehicle a = {0}, b = {0};
        a.length_m = 1 + 5 * rs_rng_uniform(&rng);
        a.width_m = 0.5 + 2 * rs_rng_uniform(&rng);
        a.yaw_deg = 360 * rs_rng_uniform(&rng);
        b.length_m = 1 + 5 * rs_rng_uniform(&rng);
        b.width_m = 0.5 + 2 * rs_rng_uniform(&rng);
        b.yaw_deg = 360 * rs_rng_uniform(&rng);
        b.e_m = -6 + 12 * rs_rng_uniform(&rng);
        b.n_m = -6 + 12 * rs_rng_uniform(&rng);
        bool sat = rs_synth_footprints_overlap(&a, &b);
        if (sat != rs_synth_footprints_overlap(&b, &a)) {
            fprintf(stderr, "pair %d: not symmetric\n", t);
            fails++;
        }
        // Brute force: a cell centre strictly inside both (by half a cell diagonal) proves an
        // overlap; none inside both even with that margin proves there is none.
        int strict = 0, loose = 0;
        double ra = 0.5 * hypot(a.length_m, a.width_m) + h, rb = 0.5 * hypot(b.length_m, b.width_m) + h;
        double e0 = fmax(a.e_m - ra, b.e_m - rb), e1 = fmin(a.e_m + ra, b.e_m + rb);
        double n0 = fmax(a.n_m - ra, b.n_m - rb), n1 = fmin(a.n_m + ra, b.n_m + rb);
        for (double e = e0; e <= e1; e += h)
            for (double n = n0; n <= n1; n += h) {
                if (!inside(&a, e, n, h) || !inside(&b, e, n, h)) continue;
                loose = 1;
                if (inside(&a, e, n, -h) && inside(&b, e, n, -h)) strict = 1;
            }
        if (strict != loose) {
            Nambiguous++; // touching within a cell: either answer is right
            continue;
        }
        Noverlap += strict;
        if (sat != strict) {
            fprintf(stderr, "pair %d: SAT says %d, brute force %d (seed %llu)\n", t, sat, strict,
                    (unsigned long long)seed);
            fails++;
        }
    }
    printf("sat: 20000 pairs, %d overlapping, %d within a cell of touching (skipped), %d disagreements\n", Noverlap,
           Nambiguous, fails);
    if (Noverlap < 1000 || Noverlap > 19000) {
        fprintf(stderr, "sat: unbalanced test (%d overlapping)\n", Noverlap);
        fails++;
    }
    // The class mix parser.
    rs_synth_class_mix m;
    rs_err err;
    const char *bad[] = {"", "car=1", "bus", "bus=-1", "bus=x", "bus=0,van=0", "bus=1,"};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++)
        if (rs_synth_class_mix_parse(&m, bad[i], &err) != RS_ERR_USAGE) {
            fprintf(stderr, "mix '%s' was accepted\n", bad[i]);
            fails++;
        }
    if (rs_synth_class_mix_parse(&m, "bus=2,van=1", &err) || m.weight[RS_SYNTH_BUS] != 2 ||
        m.weight[RS_SYNTH_VAN] != 1 || m.weight[RS_SYNTH_SEDAN] != 0) {
        fprintf(stderr, "mix 'bus=2,van=1' misread\n");
        fails++;
    }
    return fails ? 1 : 0;
}

int main(int argc, char **argv)
{
    if (argc >= 2 && !strcmp(argv[1], "sat")) return test_sat();
    if (argc == 15 && !strcmp(argv[1], "fcd")) {
        rs_synth_sumo_location loc = {atoi(argv[4]), atoi(argv[5]) != 0, {atof(argv[6]), atof(argv[7])}};
        rs_llh origin = {atof(argv[8]), atof(argv[9]), atof(argv[10])};
        rs_synth_sumo_vtype t = {{0}, RS_SYNTH_SEDAN, atof(argv[12]), atof(argv[13]), atof(argv[14])};
        snprintf(t.id, sizeof t.id, "%s", argv[11]);
        rs_synth_sumo_frames fr;
        rs_err err;
        if (rs_synth_sumo_read_fcd(&fr, argv[2], atoi(argv[3]) != 0, &loc, &origin, &t, 1, &err)) {
            printf("ERROR %s\n", err.msg);
            return 1;
        }
        for (int i = 0; i < fr.N; i++)
            for (int k = 0; k < fr.frame[i].N; k++) {
                const rs_synth_vehicle *v = &fr.frame[i].v[k];
                printf("%s %.6f %.6f %.6f\n", v->id, v->e_m, v->n_m, v->yaw_deg);
            }
        rs_synth_sumo_frames_free(&fr);
        return 0;
    }
    if (argc == 6 && !strcmp(argv[1], "lanes")) {
        // a site of its own: the origin given, ellipsoidal heights, the level ground plane U = 0
        rs_site site = {.origin = {atof(argv[3]), atof(argv[4]), atof(argv[5])}, .ground_normal_enu = {0, 0, 1}};
        rs_lanes lanes;
        rs_err err;
        if (rs_lanes_read(&lanes, argv[2], &site, &err)) {
            printf("%s\n", err.msg);
            return 1;
        }
        printf("OK %d\n", lanes.N);
        rs_lanes_free(&lanes);
        return 0;
    }
    fprintf(stderr, "usage: test_traffic_api sat | fcd ... | lanes ...\n");
    return 2;
}

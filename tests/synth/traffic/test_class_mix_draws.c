// test_class_mix_draws NSEEDS -- issue 18: the built-in traffic's default class mix
// (rs_synth_class_mix_default) over many draws. One straight lane 200 km long (so that the lane's
// end, where a long vehicle is likelier not to fit, drops one vehicle in thousands), speed limit
// 13.89 m/s, the default traffic options, seeds 1..NSEEDS. Prints one line per class, "NAME COUNT
// WEIGHT" (WEIGHT: the default mix's own weight, for the report; the test's oracle is its own),
// then "bicycle_speed MAX_MPS N" (the fastest bicycle, how many); for
// tests/synth/traffic/test_two_wheelers.py. Exit 1 on error.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "synth/fleet/rs_synth_fleet.h"
#include "synth/traffic/rs_synth_traffic.h"

int main(int argc, char **argv)
{
    const int Nseeds = argc > 1 ? atoi(argv[1]) : 10;
    double pts[2][3] = {{0, 0, 0}, {0, 200000, 0}};
    rs_lane lane = {
        .id = "long", .width_m = 3.5, .direction = RS_LANE_FORWARD, .speed_mps = 13.89, .p_enu_m = pts, .Npoints = 2};
    rs_lanes lanes = {.lane = &lane, .N = 1};
    long count[RS_SYNTH_NCLASSES] = {0}, Nbicycle = 0;
    double bicycle_max = 0;
    rs_synth_class_mix mix;
    rs_synth_class_mix_default(&mix);
    for (int s = 1; s <= Nseeds; s++) {
        rs_synth_traffic_options opt;
        rs_synth_traffic_options_default(&opt);
        opt.seed = (uint64_t)s;
        rs_synth_vehicle *v = NULL;
        int N = 0;
        rs_err err = {0};
        if (rs_synth_traffic_place(&v, &N, &lanes, &opt, &err)) {
            fprintf(stderr, "test_class_mix_draws: %s\n", err.msg);
            return 1;
        }
        for (int i = 0; i < N; i++) {
            count[v[i].cls]++;
            if (v[i].cls == RS_SYNTH_BICYCLE) Nbicycle++, bicycle_max = fmax(bicycle_max, v[i].speed_mps);
        }
        free(v);
    }
    for (int c = 0; c < RS_SYNTH_NCLASSES; c++)
        printf("%s %ld %.6f\n", rs_synth_class_name((rs_synth_class)c), count[c], mix.weight[c]);
    printf("bicycle_speed %.4f %ld\n", bicycle_max, Nbicycle);
    return 0;
}

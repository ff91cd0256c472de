// test_refine_locate.c -- driver for test_refine_locate.py: prints, one JSON object per line,
// pixels mapped to the ground by rs_camera_locate_ground() on simulated cameras (pinhole,
// OPENCV8, CAHVOR; seed 900 + lens), for mrcal's Python module to check independently.
#include <stdio.h>

#include "calib/rs_calib.h"
#include "test_solve_gen.h"

int main(void)
{
    for (int lens = 0; lens < 3; lens++) {
        gen_rng rng;
        gen_seed(&rng, 900 + (uint64_t)lens);
        gen_problem g;
        if (!gen_make(&g, &rng, (gen_lens)lens, 40, 0.0, 0.0)) return 1;
        char name[64];
        if (!mrcal_lensmodel_name(name, sizeof(name), &g.lensmodel)) return 1;
        const double ground = g.p_true[2]; // a level plane through the first landmark
        const double n[3] = {0, 0, 1};
        for (int k = 0; k < 40; k++) {
            // the pixels of the simulated landmarks (on the road or on poles up to 4 m, all below
            // the camera): their rays come down to the plane
            const double q[2] = {g.q_true[2 * k], g.q_true[2 * k + 1]};
            double p[3];
            rs_err err = {0};
            const rs_camera cam = gen_camera(&g, g.rt_true);
            const rs_status st = rs_camera_locate_ground(p, &cam, q, n, ground, &err);
            printf("{\"model\": \"%s\", \"intrinsics\": [", name);
            for (int i = 0; i < g.Nintrinsics; i++) printf("%s%.17g", i ? ", " : "", g.intrinsics[i]);
            printf("], \"rt\": [");
            for (int i = 0; i < 6; i++) printf("%s%.17g", i ? ", " : "", g.rt_true[i]);
            printf("], \"q\": [%.17g, %.17g], \"offset\": %.17g, \"status\": %d", q[0], q[1], ground, (int)st);
            if (st == RS_OK) printf(", \"p\": [%.17g, %.17g, %.17g]", p[0], p[1], p[2]);
            printf("}\n");
        }
    }
    return 0;
}

// test_axis_ground.c -- rs_calib__axis_ground's analytic Jacobian (the ground point of the
// optical axis, whose change is the external reliability on the ground) against central
// differences of its own ground point, on 2000 random poses looking down at the plane (yaw any,
// pitch 5-85 deg down, roll +-20 deg, the camera 2-100 m up and up to 300 m from the origin).
// Oracle: the differences, step 1e-6 (error ~1e-9 relative); tolerance 1e-6 of the largest
// entry of G. A pose looking up must say so (false, G NAN).
#include <math.h>
#include <stdio.h>

#include <mrcal/poseutils.h>

#include "calib/internal/rs_calib_noise.h"
#include "core/rs_pose.h"
#include "test_solve_gen.h"

int main(void)
{
    gen_begin();
    gen_rng rng;
    gen_seed(&rng, 8800);
    double worst = 0;
    int n = 0;
    for (int trial = 0; trial < 2000; trial++) {
        const double yaw = gen_uniform(&rng, -M_PI, M_PI), pitch = gen_uniform(&rng, 5, 85) * M_PI / 180;
        const double roll = gen_uniform(&rng, -20, 20) * M_PI / 180;
        const double C[3] = {gen_uniform(&rng, -300, 300), gen_uniform(&rng, -300, 300), gen_uniform(&rng, 2, 100)};
        // camera axes in the world: z forward (down by pitch), x right, y down
        const double f[3] = {cos(pitch) * sin(yaw), cos(pitch) * cos(yaw), -sin(pitch)};
        double x0[3] = {cos(yaw), -sin(yaw), 0}, y0[3];
        y0[0] = f[1] * x0[2] - f[2] * x0[1], y0[1] = f[2] * x0[0] - f[0] * x0[2], y0[2] = f[0] * x0[1] - f[1] * x0[0];
        double R[9]; // rows: the camera's x, y, z in the world (R_cam_world)
        for (int k = 0; k < 3; k++) {
            R[k] = cos(roll) * x0[k] + sin(roll) * y0[k];
            R[3 + k] = -sin(roll) * x0[k] + cos(roll) * y0[k];
            R[6 + k] = f[k];
        }
        double rt[6];
        mrcal_r_from_R(rt, NULL, R);
        for (int a = 0; a < 3; a++) rt[3 + a] = -(R[3 * a] * C[0] + R[3 * a + 1] * C[1] + R[3 * a + 2] * C[2]);
        double g[2], G[12];
        if (!rs_calib__axis_ground(g, G, rt)) {
            CHECK(0, "trial %d: a camera looking down at the plane has no ground point", trial);
            continue;
        }
        double scale = 0, err = 0;
        for (int j = 0; j < 12; j++) scale = fmax(scale, fabs(G[j]));
        for (int k = 0; k < 6; k++) {
            double rp[6], rm[6], gp[2], gm[2], Gs[12];
            for (int a = 0; a < 6; a++) rp[a] = rm[a] = rt[a];
            const double h = 1e-6 * fmax(1.0, fabs(rt[k]));
            rp[k] += h, rm[k] -= h;
            if (!rs_calib__axis_ground(gp, Gs, rp) || !rs_calib__axis_ground(gm, Gs, rm)) continue;
            for (int a = 0; a < 2; a++) err = fmax(err, fabs((gp[a] - gm[a]) / (2 * h) - G[a * 6 + k]));
        }
        worst = fmax(worst, err / scale);
        n++;
        CHECK(err <= 1e-6 * scale, "trial %d: |G - differences| %.3g of its largest entry %.3g", trial, err / scale,
              scale);
    }
    // looking up: no ground point
    const double up[6] = {M_PI / 2 + 0.3, 0, 0, 0, 0, -10};
    double g[2], G[12];
    const bool ok = rs_calib__axis_ground(g, G, up);
    CHECK(!ok && isnan(G[0]), "a camera looking up: ground point %s", ok ? "found" : "refused, but G not NAN");
    printf("axis ground Jacobian: %d poses, worst |analytic - central differences| %.3g of G's largest entry\n", n,
           worst);
    return gen_end("8800");
}

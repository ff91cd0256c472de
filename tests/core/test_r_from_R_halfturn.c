// Regression: mrcal 2.2's r_from_R returns r = 0 for a half-turn (diag(1,-1,-1)) and is wrong by
// pi within ~1e-6 rad of one, so a camera looking straight down came out looking straight up.
// rs_pose_r_from_R must be right for every rotation: checked by turning r back into a matrix
// (Rodrigues' formula written out here, independent of mrcal and OpenCV), to 1e-9.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "calib/rs_calib.h"
#include "core/rs_pose.h"

static void R_of_axis_angle(double R[9], const double a[3], double th)
{
    double c = cos(th), s = sin(th), C = 1 - c;
    double x = a[0], y = a[1], z = a[2];
    double M[9] = {c + x * x * C,     x * y * C - z * s, x * z * C + y * s, y * x * C + z * s, c + y * y * C,
                   y * z * C - x * s, z * x * C - y * s, z * y * C + x * s, c + z * z * C};
    for (int i = 0; i < 9; i++) R[i] = M[i];
}

static double check(const double R[9])
{
    double r[3], back[9];
    rs_pose_r_from_R(r, R);
    double th = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    double a[3] = {1, 0, 0};
    if (th > 0)
        for (int i = 0; i < 3; i++) a[i] = r[i] / th;
    R_of_axis_angle(back, a, th);
    double worst = th <= M_PI + 1e-12 ? 0 : INFINITY;
    for (int i = 0; i < 9; i++) worst = fmax(worst, fabs(back[i] - R[i]));
    return isnan(worst) ? INFINITY : worst;
}

int main(void)
{
    const unsigned seed = 20261122;
    srand(seed);
    int failures = 0;
    double worst = 0;
    const double eps[] = {0, 1e-12, 1e-9, 1e-6, 1e-3, 0.1};
    for (int k = 0; k < 2000; k++) {
        double a[3], n = 0;
        for (int i = 0; i < 3; i++) {
            a[i] = 2.0 * rand() / RAND_MAX - 1;
            n += a[i] * a[i];
        }
        if (k < 3) {
            a[0] = k == 0;
            a[1] = k == 1;
            a[2] = k == 2;
            n = 1;
        } // the coordinate axes
        for (int i = 0; i < 3; i++) a[i] /= sqrt(n);
        for (size_t e = 0; e < sizeof eps / sizeof eps[0]; e++) {
            double R[9];
            R_of_axis_angle(R, a, M_PI - eps[e]);
            double d = check(R);
            worst = fmax(worst, d);
            if (!(d < 1e-9)) {
                if (failures++ < 5)
                    printf("FAIL: axis (%g %g %g), angle pi - %g: R differs by %g\n", a[0], a[1], a[2], eps[e], d);
            }
        }
    }
    // a camera looking straight down, built from yaw/pitch/roll, must look down
    for (int yaw = 0; yaw < 360; yaw += 15) {
        double rt[6], ypr[3] = {yaw, -90, 0}, pos[3] = {1, 2, 10}, R[9];
        rs_pose_rt_from_ypr(rt, ypr, pos);
        // optical axis in ENU = third row of R_cam_enu, via Rodrigues
        double th = sqrt(rt[0] * rt[0] + rt[1] * rt[1] + rt[2] * rt[2]);
        double a[3] = {1, 0, 0};
        if (th > 0)
            for (int i = 0; i < 3; i++) a[i] = rt[i] / th;
        R_of_axis_angle(R, a, th);
        if (!(fabs(R[8] + 1) < 1e-9)) {
            if (failures++ < 10) printf("FAIL: yaw %d pitch -90: optical axis up component %g, not -1\n", yaw, R[8]);
        }
    }
    if (failures) {
        printf("%d failures (seed %u)\n", failures, seed);
        return 1;
    }
    printf("r_from_R: 12000 rotations within pi - {0..0.1} of a half-turn: worst %.2e; looking down ok\n", worst);
    return 0;
}

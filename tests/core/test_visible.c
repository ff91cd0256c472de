// test_visible.c -- the one "does this point project" rule (core/rs_camera.h): depth, the lens's
// valid field, finite pixels. Oracles: for a pinhole the field's tangent in closed form,
// max over the corners of hypot((u - cx) / fx, (v - cy) / fy), x 1.15 + 0.02 (within 1e-12);
// points built at a known angle just inside and just outside it (1e-9 relative either side);
// points behind the camera that mrcal_project itself would put inside the image (it projects
// -p like p) are refused; a far off-axis point that an OPENCV8 lens folds back into the image
// is refused; visible points project exactly as mrcal_project. Fixed seed, printed on failure.
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <mrcal/mrcal.h>
#include <mrcal/poseutils.h>

#include "core/rs_camera.h"
#include "core/rs_pose.h"
#include "core/rs_rng.h"
#include "tests/common/rs_test.h"

int main(void)
{
    rs_test_seed = 515;
    rs_rng rng;
    rs_rng_seed(&rng, rs_test_seed);
    const mrcal_lensmodel_t pinhole = {.type = MRCAL_LENSMODEL_PINHOLE};
    const double in[4] = {1400, 1350, 1000.5, 520.25};
    rs_camera cam;
    rs_err err = {0};
    CHECK(rs_camera_init(&cam, &pinhole, in, 1920, 1080, &err) == RS_OK, "init: %s", err.msg);
    double want = 0;
    for (int c = 0; c < 4; c++) {
        const double u = c % 2 ? 1919.5 : -0.5, v = c / 2 ? 1079.5 : -0.5;
        want = fmax(want, hypot((u - in[2]) / in[0], (v - in[3]) / in[1]));
    }
    want = want * 1.15 + 0.02;
    const double max_tan = rs_camera_max_tan(&cam);
    CHECK(fabs(max_tan - want) < 1e-12, "pinhole max_tan %.17g, closed form %.17g", max_tan, want);
    // a pose: camera 10 m up, looking north and down 20 degrees
    const double ypr[3] = {0, -20, 0}, pos[3] = {0, 0, 10};
    rs_pose_rt_from_ypr(cam.rt_cam_enu, ypr, pos);
    int Nin = 0, Nout = 0, Nbehind = 0;
    for (int k = 0; k < 3000; k++) {
        // a camera-frame direction at tan = max_tan (1 +- 1e-9) or well inside, at a random azimuth
        const double az = rs_rng_uniform_in(&rng, -M_PI, M_PI), z = rs_rng_uniform_in(&rng, 1, 200);
        const int kind = k % 3; // 0 well inside, 1 just inside, 2 just outside
        const double t = kind == 0 ? max_tan * rs_rng_uniform(&rng) : max_tan * (kind == 1 ? 1 - 1e-9 : 1 + 1e-9);
        double pc[3] = {z * t * cos(az), z * t * sin(az), z}, p[3], q[2];
        mrcal_transform_point_rt_inverted(p, NULL, NULL, cam.rt_cam_enu, pc);
        const bool seen = rs_camera_project_visible(q, &cam, max_tan, p);
        // recompute the camera-frame point as the rule sees it (the round trip moves it ~1e-15)
        double back[3];
        mrcal_transform_point_rt(back, NULL, NULL, cam.rt_cam_enu, p);
        CHECK(seen == (kind != 2), "k %d: tan %.17g (max %.17g): visible %d", k, t, max_tan, seen);
        CHECK(seen == rs_camera_in_field(back, max_tan), "k %d: project_visible and in_field disagree", k);
        if (seen) {
            mrcal_point2_t qq;
            mrcal_project(&qq, NULL, NULL, (const mrcal_point3_t *)back, 1, &cam.lensmodel, cam.intrinsics);
            CHECK(q[0] == qq.x && q[1] == qq.y, "k %d: pixel differs from mrcal_project", k);
            Nin++;
        } else {
            CHECK(isnan(q[0]) && isnan(q[1]), "k %d: refused point's pixel not NaN", k);
            Nout++;
        }
        // the same point behind the camera: mrcal projects it to the same pixel, the rule refuses it
        const double pb[3] = {-pc[0], -pc[1], -pc[2]};
        mrcal_transform_point_rt_inverted(p, NULL, NULL, cam.rt_cam_enu, pb);
        CHECK(!rs_camera_project_visible(q, &cam, max_tan, p), "k %d: a point behind the camera projects", k);
        Nbehind++;
    }
    double q4[8], p4[12];
    for (int i = 0; i < 4; i++) p4[3 * i] = 5.0 * i - 7, p4[3 * i + 1] = 60, p4[3 * i + 2] = 0;
    CHECK(rs_camera_project(q4, &cam, p4, 4) == 4, "rs_camera_project: ground points ahead not all projected");
    // an OPENCV8 lens with barrel distortion folds a point far off axis back into the image
    const mrcal_lensmodel_t cv8 = {.type = MRCAL_LENSMODEL_OPENCV8};
    const double in8[12] = {1000, 1000, 959.5, 539.5, -0.1, 0, 0, 0, 0, 0, 0, 0}; // r (1 - 0.1 r^2): folds at r 1.83
    rs_camera fish;
    CHECK(rs_camera_init(&fish, &cv8, in8, 1920, 1080, &err) == RS_OK, "init opencv8: %s", err.msg);
    const double mt8 = rs_camera_max_tan(&fish);
    int Nfold = 0;
    for (double t = mt8 * 1.01; t < 20; t *= 1.05) {
        const mrcal_point3_t pc = {.x = t, .y = 0, .z = 1};
        mrcal_point2_t qq;
        mrcal_project(&qq, NULL, NULL, &pc, 1, &fish.lensmodel, fish.intrinsics);
        double p[3], q[2];
        mrcal_transform_point_rt_inverted(p, NULL, NULL, fish.rt_cam_enu, pc.xyz);
        if (qq.x >= -0.5 && qq.x <= 1919.5) Nfold++; // mrcal puts it inside the image
        CHECK(!rs_camera_project_visible(q, &fish, mt8, p), "tan %g beyond the field (%g) projects", t, mt8);
    }
    CHECK(Nfold > 0, "the test lens folds nothing back: the test proves nothing");
    rs_camera sizeless = cam;
    sizeless.width = sizeless.height = 0;
    CHECK(isinf(rs_camera_max_tan(&sizeless)), "a camera without an image size has a field limit");
    printf("visible: pinhole max_tan %.6f (closed form %.6f); %d inside, %d outside within 1e-9 of the limit or "
           "beyond, %d behind the camera refused; opencv8 max_tan %.4f, %d folded-back directions refused\n",
           max_tan, want, Nin, Nout, Nbehind, mt8, Nfold);
    rs_camera_free(&cam);
    rs_camera_free(&fish);
    return rs_test_end("core_visible");
}

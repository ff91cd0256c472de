// tests/synth/povray/test_ids_raster.c -- the object-ID pass rasterised by roadside (synth/povray/rs_synth_raster.h)
// against the same pass rendered by the real POV-Ray (the oracle: rs_synth_render with
// povray_passes), on scenes made to be hard: 14 vehicles of every class crowded round the point the
// camera looks at (they hide one another), random headings, cameras from 1.5 m to 30 m up, a
// pinhole and a distorted lens (OPENCV8: the canvas and its resampling), a vehicle cut by the
// image border and one partly behind the camera (the near-plane clipping).
//
// Asserted, per scene and in total: the ID images (after resampling into the lens) differ at no
// more than 1 pixel in 100,000 vehicle pixels (the two can differ only where a pixel centre lies
// within rounding of a silhouette edge: about 1e-10 px; printed: 0 in every scene when written),
// and the colour pass's alpha, taken from the ID pass, likewise. Each scene must show at least
// 3,000 vehicle pixels and 6 vehicles, and in the two low scenes the bus beside the camera
// 1,000 pixels, so that the comparison means something.
// Exit 77 when povray is missing. usage: test_ids_raster OUTDIR
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_pose.h"
#include "core/rs_rng.h"
#include "synth/povray/rs_synth_render.h"
#include "tests/synth/test_fleet_check.h"

enum { W = 480, H = 320, NV = 14, NSCENES = 6 };

int main(int argc, char **argv)
{
    const char *out = argc > 1 ? argv[1] : ".";
    if (system("command -v povray > /dev/null 2>&1") != 0) {
        fprintf(stderr, "povray missing: skipped\n");
        return 77;
    }
    long total_px = 0, total_diff = 0, total_alpha = 0;
    for (int s = 0; s < NSCENES; s++) {
        rs_rng rng;
        rs_rng_seed(&rng, 1000 + (uint64_t)s);
        // the camera: pinhole for even scenes, OPENCV8 with visible barrel distortion for odd ones
        double intr[12] = {360, 362, (W - 1) / 2.0 + 7, (H - 1) / 2.0 - 5, -0.25, 0.07, 0.001, -0.002, 0, 0, 0, 0};
        rs_camera cam = {0};
        cam.lensmodel.type = s % 2 ? MRCAL_LENSMODEL_OPENCV8 : MRCAL_LENSMODEL_PINHOLE;
        cam.intrinsics = intr;
        cam.Nintrinsics = s % 2 ? 12 : 4;
        cam.width = W, cam.height = H;
        const double height_m = s < 2 ? 2.0 : rs_rng_uniform_in(&rng, 1.5, 30), back_m = rs_rng_uniform_in(&rng, 6, 30);
        const double pitch = -atan2(height_m, back_m) * 180 / M_PI, yaw = rs_rng_uniform_in(&rng, 0, 360);
        const double C[3] = {-back_m * sin(yaw * M_PI / 180), -back_m * cos(yaw * M_PI / 180), height_m};
        rs_pose_rt_from_ypr(cam.rt_cam_enu, (const double[3]){yaw, pitch, 0}, C);
        rs_synth_vehicle v[NV];
        memset(v, 0, sizeof v);
        for (int i = 0; i < NV; i++) {
            const double r = rs_rng_uniform_in(&rng, 0, 0.6 * back_m), a = rs_rng_uniform_in(&rng, 0, 2 * M_PI);
            v[i] = (rs_synth_vehicle){.cls = (rs_synth_class)(i % RS_SYNTH_NCLASSES),
                                      .e_m = r * cos(a),
                                      .n_m = r * sin(a),
                                      .yaw_deg = rs_rng_uniform_in(&rng, -180, 180),
                                      .variant = (int)(rs_rng_u64(&rng) % 1000),
                                      .rgb = {0.5, 0.5, 0.5}};
        }
        // one vehicle beside the camera, reaching behind it (near-plane clipping; in view when the
        // camera is low, as in scenes 0 and 1), one far to the side (cut by the image border)
        const double right[2] = {cos(yaw * M_PI / 180), -sin(yaw * M_PI / 180)};
        v[NV - 2].e_m = C[0] + 3 * right[0], v[NV - 2].n_m = C[1] + 3 * right[1], v[NV - 2].cls = RS_SYNTH_BUS;
        v[NV - 2].yaw_deg = yaw;
        v[NV - 1].e_m = 0.5 * back_m * right[0], v[NV - 1].n_m = 0.5 * back_m * right[1];
        rs_synth_prepared prep = {0};
        rs_err err = {0};
        if (rs_synth_prepare(&prep, v, NULL, NV, &err)) return fprintf(stderr, "prepare: %s\n", err.msg), 1;
        rs_synth_render_options ropt;
        rs_synth_render_options_default(&ropt);
        ropt.write_files = false;
        ropt.scene.ground_visible = false;
        const double normal[3] = {0, 0, 1};
        rs_synth_render_result r[2] = {{0}, {0}};
        for (int k = 0; k < 2; k++) {
            char dir[4200];
            snprintf(dir, sizeof dir, "%s/ids_raster/%d_%s", out, s, k ? "povray" : "roadside");
            ropt.povray_passes = k == 1;
            if (rs_synth_render(&r[k], dir, &cam, normal, 0, &prep, &ropt, &err))
                return fprintf(stderr, "scene %d: render: %s\n", s, err.msg), 1;
        }
        long px = 0, diff = 0, alpha = 0, beside = 0;
        int shown[NV + 1] = {0}, Nshown = 0;
        for (int i = 0; i < W * H; i++) {
            px += r[1].ids[i] != 0;
            beside += r[1].ids[i] == NV - 1;
            diff += r[0].ids[i] != r[1].ids[i];
            alpha += r[0].rgba.data[4 * (size_t)i + 3] != r[1].rgba.data[4 * (size_t)i + 3];
            if (r[1].ids[i] && r[1].ids[i] <= NV && !shown[r[1].ids[i]]) shown[r[1].ids[i]] = 1, Nshown++;
        }
        printf("scene %d (%s, camera %.1f m up, %.1f m back): %d vehicles shown, %ld vehicle pixels, %ld IDs and %ld "
               "alpha values differ; the bus beside the camera %ld px; povray processes %d (roadside's IDs) and %d\n",
               s, s % 2 ? "OPENCV8" : "pinhole", height_m, back_m, Nshown, px, diff, alpha, beside, r[0].Npovray,
               r[1].Npovray);
        CHECK(px >= 3000 && Nshown >= 6, "scene %d: only %ld vehicle pixels, %d vehicles", s, px, Nshown);
        CHECK(s >= 2 || beside > 1000, "scene %d: the bus beside the camera shows on %ld px only", s, beside);
        CHECK(diff * 100000 <= px, "scene %d: %ld of %ld ID pixels differ", s, diff, px);
        CHECK(alpha * 100000 <= px, "scene %d: %ld alpha values differ", s, alpha);
        CHECK(r[0].Npovray == r[1].Npovray - 1, "scene %d: the ID pass still ran povray", s);
        total_px += px, total_diff += diff, total_alpha += alpha;
        rs_synth_render_result_free(&r[0]);
        rs_synth_render_result_free(&r[1]);
        rs_synth_prepared_free(&prep);
    }
    printf("all: %ld vehicle pixels, %ld IDs and %ld alpha values differ from POV-Ray's ID pass\n", total_px,
           total_diff, total_alpha);
    CHECK(total_diff * 100000 <= total_px, "%ld of %ld ID pixels differ", total_diff, total_px);
    return failures ? 1 : 0;
}

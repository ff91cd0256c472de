// tests/synth/fleet/test_fleet_env.c -- issue 18: the paint reflects the environment. The same sedan
// (and a van, for its glass) rendered by the real POV-Ray (rs_synth_render, pinhole 160 x 120)
// under two environments, a blue sky over grey asphalt and an orange sky over red ground, with
// the same sun and sky lights:
//   - the object-ID image and the alpha channel are identical (labels and background stay);
//   - the vehicles' pixels change measurably: mean |difference| > 0.01 in linear RGB, and the
//     blue-minus-red of the vehicle pixels drops by > 0.01 when the sky turns orange (the
//     oracle: a reflection takes the colour of what it reflects);
//   - without any environment (env_off) the vehicles are darker than under the bright one.
// Exit 77 when povray is missing. usage: test_fleet_env OUTDIR
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_pose.h"
#include "synth/povray/rs_synth_render.h"
#include "synth/povray/rs_synth_scene.h"
#include "tests/synth/test_fleet_check.h"

static int render(rs_synth_render_result *r, const char *dir, const rs_camera *cam, const rs_synth_prepared *prep,
                  const double *zenith, const double *horizon, const double *ground, int off)
{
    rs_synth_render_options ropt;
    rs_synth_render_options_default(&ropt);
    ropt.write_files = false;
    ropt.full_frame = true;
    ropt.scene.ground_visible = false;
    ropt.scene.env_off = off;
    if (zenith) {
        ropt.scene.env_given = true;
        memcpy(ropt.scene.env_zenith_rgb, zenith, 3 * sizeof(double));
        memcpy(ropt.scene.env_horizon_rgb, horizon, 3 * sizeof(double));
        memcpy(ropt.scene.env_ground_rgb, ground, 3 * sizeof(double));
    }
    double normal[3] = {0, 0, 1};
    rs_err err = {0};
    if (rs_synth_render(r, dir, cam, normal, 0, prep, &ropt, &err)) {
        fprintf(stderr, "render: %s\n", err.msg);
        return 1;
    }
    return 0;
}

int main(int argc, char **argv)
{
    const char *out = argc > 1 ? argv[1] : ".";
    if (system("command -v povray > /dev/null 2>&1") != 0) {
        fprintf(stderr, "povray missing: skipped\n");
        return 77;
    }
    double intr[4] = {170, 170, 79.5, 59.5};
    rs_camera cam = {0};
    cam.lensmodel.type = MRCAL_LENSMODEL_PINHOLE;
    cam.intrinsics = intr;
    cam.Nintrinsics = 4;
    cam.width = 160, cam.height = 120;
    // a camera 5 m up, 12 m south of the vehicles, looking north 15 degrees down
    rs_pose_rt_from_ypr(cam.rt_cam_enu, (const double[3]){0, -15, 0}, (const double[3]){0, -12, 5});
    rs_synth_vehicle v[2] = {
        {.cls = RS_SYNTH_SEDAN, .e_m = -1.6, .n_m = 0, .yaw_deg = 60, .variant = 3, .rgb = {0.5, 0.5, 0.5}},
        {.cls = RS_SYNTH_VAN, .e_m = 2.2, .n_m = 2, .yaw_deg = 300, .variant = 4, .rgb = {0.05, 0.05, 0.05}},
    };
    rs_synth_prepared prep = {0};
    rs_err err = {0};
    if (rs_synth_prepare(&prep, v, NULL, 2, &err)) {
        fprintf(stderr, "prepare: %s\n", err.msg);
        return 1;
    }
    const double blue_z[3] = {0.15, 0.35, 0.9}, blue_h[3] = {0.5, 0.6, 0.8}, grey_g[3] = {0.2, 0.2, 0.2};
    const double orange_z[3] = {0.9, 0.45, 0.1}, orange_h[3] = {0.9, 0.6, 0.3}, red_g[3] = {0.4, 0.1, 0.05};
    rs_synth_render_result a = {0}, b = {0}, c = {0};
    char dir[3][4096];
    for (int k = 0; k < 3; k++) snprintf(dir[k], sizeof dir[k], "%s/env%d", out, k);
    if (render(&a, dir[0], &cam, &prep, blue_z, blue_h, grey_g, 0) ||
        render(&b, dir[1], &cam, &prep, orange_z, orange_h, red_g, 0) ||
        render(&c, dir[2], &cam, &prep, NULL, NULL, NULL, 1))
        return 1;
    const int n = cam.width * cam.height;
    long vehicle_px = 0, id_diff = 0, alpha_diff = 0;
    double sum_abs = 0, bmr_a = 0, bmr_b = 0, lum_a = 0, lum_c = 0;
    for (int i = 0; i < n; i++) {
        id_diff += a.ids[i] != b.ids[i] || a.ids[i] != c.ids[i];
        const float *pa = &a.rgba.data[4 * i], *pb = &b.rgba.data[4 * i], *pc = &c.rgba.data[4 * i];
        alpha_diff += fabsf(pa[3] - pb[3]) > 1e-6f || fabsf(pa[3] - pc[3]) > 1e-6f;
        if (!a.ids[i] || pa[3] < 0.999f) continue;
        vehicle_px++;
        for (int ch = 0; ch < 3; ch++) sum_abs += fabs(pa[ch] - pb[ch]) / 3;
        bmr_a += pa[2] - pa[0];
        bmr_b += pb[2] - pb[0];
        lum_a += (pa[0] + pa[1] + pa[2]) / 3;
        lum_c += (pc[0] + pc[1] + pc[2]) / 3;
    }
    CHECK(vehicle_px > 500, "only %ld vehicle pixels", vehicle_px);
    double m = vehicle_px ? 1.0 / vehicle_px : 0;
    printf("vehicle pixels %ld; ID differences %ld, alpha differences %ld; mean |diff| %.4f; blue-red %.4f -> %.4f; "
           "mean level %.4f (blue sky) vs %.4f (no environment)\n",
           vehicle_px, id_diff, alpha_diff, sum_abs * m, bmr_a * m, bmr_b * m, lum_a * m, lum_c * m);
    CHECK(id_diff == 0, "%ld ID pixels differ between environments", id_diff);
    CHECK(alpha_diff == 0, "%ld alpha values differ between environments", alpha_diff);
    CHECK(sum_abs * m > 0.01, "vehicle pixels changed by %.4f only", sum_abs * m);
    CHECK((bmr_a - bmr_b) * m > 0.01, "blue-red moved by %.4f only", (bmr_a - bmr_b) * m);
    CHECK(lum_a > lum_c, "no environment is not darker (%.4f vs %.4f)", lum_c * m, lum_a * m);
    rs_synth_render_result_free(&a);
    rs_synth_render_result_free(&b);
    rs_synth_render_result_free(&c);
    rs_synth_prepared_free(&prep);
    return failures ? 1 : 0;
}

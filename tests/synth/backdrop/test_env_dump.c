// test_env_dump CAMERA.cameramodel IMAGE.png STEP_PX [OUTDIR] -- issue 18: the environment a
// background shows (rs_synth_env_from_image over a level ground plane up = 0, no lanes), printed
// as three lines "ground|horizon|zenith R G B N" (linear RGB means, pixels sampled); then the
// colours rs_synth_env_match makes of it ("env zenith(3) horizon(3) ground(3)"). With OUTDIR: a
// grey sedan and a white hatchback rendered by the real POV-Ray over transparency in that
// environment (sun azimuth 135, elevation 45), and "paint R G B N", the mean linear colour of
// the vehicles' fully covered pixels. For tests/synth/backdrop/test_env_from_image.py.
// Exit 1 (with the message) on any error, 77 when OUTDIR is given and povray is missing.
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_camera.h"
#include "core/rs_color.h"
#include "core/rs_image.h"
#include "geo/rs_lanes.h"
#include "geo/rs_site.h"
#include "synth/backdrop/rs_synth_appearance.h"
#include "synth/backdrop/rs_synth_sun.h"
#include "synth/povray/rs_synth_render.h"
#include "synth/povray/rs_synth_scene.h"

int main(int argc, char **argv)
{
    if (argc != 4 && argc != 5) {
        fprintf(stderr, "usage: test_env_dump CAMERA.cameramodel IMAGE.png STEP_PX [OUTDIR]\n");
        return 2;
    }
    if (argc == 5 && system("command -v povray > /dev/null 2>&1") != 0) {
        fprintf(stderr, "povray missing: skipped\n");
        return 77;
    }
    rs_err err = {0};
    rs_camera cam = {0};
    rs_image img = {0};
    rs_site site = {0};
    site.ground_normal_enu[2] = 1;
    rs_lanes lanes = {0};
    rs_synth_env_estimate env;
    rs_synth_prepared prep = {0};
    rs_synth_render_result r = {0};
    rs_status st = rs_camera_read(&cam, NULL, argv[1], &err);
    if (!st) st = rs_image_read(&img, argv[2], &err);
    if (!st) {
        const size_t n = (size_t)img.width * img.height * img.channels;
        for (size_t i = 0; i < n; i++) img.data[i] = (float)rs_color_srgb_decode(img.data[i]);
        st = rs_synth_env_from_image(&env, &img, &cam, &site, &lanes, atoi(argv[3]), &err);
    }
    double z[3], h[3], g[3];
    if (!st) {
        printf("ground %.7f %.7f %.7f %d\n", env.ground_rgb[0], env.ground_rgb[1], env.ground_rgb[2], env.Nground_px);
        printf("horizon %.7f %.7f %.7f %d\n", env.horizon_rgb[0], env.horizon_rgb[1], env.horizon_rgb[2],
               env.Nhorizon_px);
        printf("zenith %.7f %.7f %.7f %d\n", env.zenith_rgb[0], env.zenith_rgb[1], env.zenith_rgb[2], env.Nzenith_px);
        printf("sky %.7f %.7f %.7f %d\n", env.sky_rgb[0], env.sky_rgb[1], env.sky_rgb[2], env.Nsky_px);
        rs_synth_env_match(z, h, g, &env, NULL, false);
        printf("env %.7f %.7f %.7f %.7f %.7f %.7f %.7f %.7f %.7f\n", z[0], z[1], z[2], h[0], h[1], h[2], g[0], g[1],
               g[2]);
    }
    if (!st && argc == 5) {
        rs_synth_vehicle v[2] = {
            {.cls = RS_SYNTH_SEDAN, .e_m = -1.8, .n_m = 0, .yaw_deg = 60, .variant = 3, .rgb = {0.5, 0.5, 0.5}},
            {.cls = RS_SYNTH_HATCHBACK, .e_m = 2.2, .n_m = 2, .yaw_deg = 300, .variant = 4, .rgb = {0.8, 0.8, 0.8}},
        };
        st = rs_synth_prepare(&prep, v, NULL, 2, &err);
        rs_synth_render_options ropt;
        rs_synth_render_options_default(&ropt);
        ropt.write_files = false;
        ropt.full_frame = true;
        ropt.scene.ground_visible = false;
        ropt.scene.env_given = true;
        memcpy(ropt.scene.env_zenith_rgb, z, sizeof z);
        memcpy(ropt.scene.env_horizon_rgb, h, sizeof h);
        memcpy(ropt.scene.env_ground_rgb, g, sizeof g);
        if (!st) st = rs_synth_render(&r, argv[4], &cam, site.ground_normal_enu, 0, &prep, &ropt, &err);
        if (!st) {
            double sum[3] = {0, 0, 0};
            long n = 0;
            for (int i = 0; i < cam.width * cam.height; i++) {
                const float *p = &r.rgba.data[4 * i];
                if (!r.ids[i] || p[3] < 0.999f) continue;
                for (int c = 0; c < 3; c++) sum[c] += p[c];
                n++;
            }
            printf("paint %.7f %.7f %.7f %ld\n", n ? sum[0] / n : 0, n ? sum[1] / n : 0, n ? sum[2] / n : 0, n);
        }
    }
    if (st) fprintf(stderr, "test_env_dump: %s\n", err.msg);
    rs_synth_render_result_free(&r);
    rs_synth_prepared_free(&prep);
    rs_image_free(&img);
    rs_camera_free(&cam);
    return st ? 1 : 0;
}

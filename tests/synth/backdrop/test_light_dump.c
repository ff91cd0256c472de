// test_light_dump SITE CAMERA.cameramodel IMAGE.png [sun | scene EL_DEG] -- prints the light a background shows
// (rs_synth_light_from_image over SITE/lanes.geojson, every 2nd pixel) as
// "road_r road_g road_b Nroad irr_r irr_g irr_b level tint_r tint_g tint_b", or with `sun` the
// sun's direction from the site's poles' shadows (rs_synth_sun_from_shadows) as
// "azimuth_deg elevation_deg contrast Npoles"; with `scene EL_DEG` the estimate's line, then a
// colour-pass scene (no vehicles) whose lights are matched to it (rs_synth_light_match, a sun at
// azimuth 135 and elevation EL_DEG, rs_synth_scene_options.light_rgb_scale); for
// tests/synth/backdrop/test_light_estimate.py.
// Exit 1 (with the message) on any error; 3 when no sun shadow was found (RS_ERR_DEGENERATE).
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_camera.h"
#include "core/rs_color.h"
#include "core/rs_image.h"
#include "core/rs_io.h"
#include "geo/rs_lanes.h"
#include "geo/rs_site.h"
#include "synth/backdrop/rs_synth_appearance.h"
#include "synth/backdrop/rs_synth_sun.h"
#include "synth/povray/rs_synth_camera.h"
#include "synth/povray/rs_synth_scene.h"

int main(int argc, char **argv)
{
    const bool sun = argc == 5 && !strcmp(argv[4], "sun");
    const bool scene = argc == 6 && !strcmp(argv[4], "scene");
    if (argc != 4 && !sun && !scene) {
        fprintf(stderr, "usage: test_light_dump SITE CAMERA.cameramodel IMAGE.png [sun]\n");
        return 2;
    }
    rs_err err = {0};
    rs_site *site = NULL;
    rs_lanes lanes = {0};
    rs_camera cam = {0};
    rs_image img = {0};
    rs_synth_light_estimate est;
    char *lanes_path = rs_io_join(argv[1], RS_SITE_LANES);
    rs_status st = rs_site_load(&site, argv[1], &err);
    if (!st) st = rs_lanes_read(&lanes, lanes_path, site, &err);
    if (!st) st = rs_camera_read(&cam, NULL, argv[2], &err);
    if (!st) st = rs_image_read(&img, argv[3], &err);
    if (!st) {
        const size_t n = (size_t)img.width * img.height * img.channels;
        for (size_t i = 0; i < n; i++) img.data[i] = (float)rs_color_srgb_decode(img.data[i]);
        if (sun) {
            rs_synth_sun_estimate se;
            st = rs_synth_sun_from_shadows(&se, &img, &cam, site, &err);
            if (!st || st == RS_ERR_DEGENERATE)
                printf("%.3f %.3f %.4f %d\n", se.azimuth_deg, se.elevation_deg, se.contrast, se.Npoles);
        } else {
            st = rs_synth_light_from_image(&est, &img, &cam, site, &lanes, 2, &err);
        }
    }
    if (st) {
        fprintf(stderr, "test_light_dump: %s\n", err.msg);
    } else if (!sun) {
        printf("%.6f %.6f %.6f %d %.6f %.6f %.6f %.6f %.6f %.6f %.6f\n", est.road_rgb[0], est.road_rgb[1],
               est.road_rgb[2], est.Nroad_px, est.irradiance_rgb[0], est.irradiance_rgb[1], est.irradiance_rgb[2],
               est.level, est.tint_rgb[0], est.tint_rgb[1], est.tint_rgb[2]);
        if (scene) {
            rs_synth_scene_options o;
            rs_synth_scene_options_default(&o);
            o.sun_elevation_deg = atof(argv[5]);
            rs_synth_light_match(o.light_rgb_scale, &est, true, o.sun_elevation_deg);
            rs_synth_povcam pc;
            rs_synth_prepared none = {0};
            const double fxy[2] = {cam.intrinsics[0], cam.intrinsics[1]};
            st = rs_synth_povcam_init(&pc, cam.intrinsics, cam.width, cam.height, cam.rt_cam_enu, &err);
            if (!st)
                st = rs_synth_scene_write(stdout, &pc, fxy, site->ground_normal_enu, site->ground_offset_m, &none, &o,
                                          &err);
            if (st) fprintf(stderr, "test_light_dump: %s\n", err.msg);
        }
    }
    rs_image_free(&img);
    rs_camera_free(&cam);
    rs_lanes_free(&lanes);
    rs_site_free(site);
    free(lanes_path);
    return st == RS_ERR_DEGENERATE ? 3 : st ? 1 : 0;
}

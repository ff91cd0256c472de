// rs_synth_scene_match.c -- a scene's lights and environment matched to its background, from the
// estimates of synth/backdrop/rs_synth_light.h (synth/povray/rs_synth_scene.h).
#include "synth/povray/rs_synth_scene.h"

#include "core/rs_color.h"
#include "synth/backdrop/rs_synth_appearance.h"
#include "synth/povray/internal/rs_synth_scene_internal.h"

void rs_synth_scene_match_background(rs_synth_scene_options *scene, const rs_synth_light_estimate *light,
                                     const rs_synth_env_estimate *env)
{
    rs_synth_light_match(scene->light_rgb_scale, light, !scene->overcast, scene->sun_elevation_deg);
    scene->env_given = true;
    rs_synth_env_match(scene->env_zenith_rgb, scene->env_horizon_rgb, scene->env_ground_rgb, env,
                       scene->light_rgb_scale, scene->overcast);
}

rs_status rs_synth_scene_env_map(rs_image *map, const rs_synth_scene_options *scene, const rs_image *linear_rgb,
                                 const rs_camera *cam, const rs_site *site, rs_err *err)
{
    double z[3], h[3], g[3];
    rs_synth_scene_env_colours(z, h, g, scene);
    return rs_synth_env_map(map, linear_rgb, cam, site->ground_normal_enu, z, h, g, RS_SYNTH_ENV_MAP_WIDTH, err);
}

rs_status rs_synth_scene_match_background_file(rs_synth_scene_options *scene, rs_synth_light_estimate *light,
                                               rs_image *env_map, const char *path, const rs_camera *cam,
                                               const rs_site *site, const rs_lanes *lanes, rs_err *err)
{
    if (env_map) *env_map = (rs_image){0};
    rs_image src = {0}, lin = {0};
    rs_status st = rs_image_read(&src, path, err);
    if (st) return st;
    if (src.channels < 3)
        st = rs_err_set(err, RS_ERR_INVALID, "%s: not an RGB image", path);
    else if (src.width != cam->width || src.height != cam->height)
        st = rs_err_set(err, RS_ERR_INVALID, "%s: the background is %dx%d, the camera %dx%d", path, src.width,
                        src.height, cam->width, cam->height);
    else
        st = rs_image_alloc(&lin, src.width, src.height, 3, err);
    if (!st) {
        for (size_t i = 0; i < (size_t)src.width * (size_t)src.height; i++)
            for (int c = 0; c < 3; c++)
                lin.data[3 * i + c] = (float)rs_color_srgb_decode(src.data[(size_t)src.channels * i + c]);
        rs_synth_light_estimate est;
        rs_synth_env_estimate env;
        if (!(st = rs_synth_light_from_background(&est, &lin, cam, site, lanes, 4, err))) {
            const bool env_ok = !rs_synth_env_from_image(&env, &lin, cam, site, lanes, 4, NULL);
            rs_synth_scene_match_background(scene, &est, env_ok ? &env : NULL);
            if (light) *light = est;
            if (env_map) st = rs_synth_scene_env_map(env_map, scene, &lin, cam, site, err);
        }
    }
    rs_image_free(&lin);
    rs_image_free(&src);
    return st;
}

// rs_synth_twin.c -- digital-twin backgrounds rendered by POV-Ray and recorded in site.json
// (synth/povray/rs_synth_twin.h, docs/backgrounds.md); the world they show is written by
// rs_synth_twin_world.c.
#include "synth/povray/rs_synth_twin.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "core/rs_io.h"
#include "core/rs_pose.h"
#include "synth/backdrop/rs_synth_background.h"
#include "synth/backdrop/rs_synth_opencv.h"
#include "synth/backdrop/rs_synth_sun.h"
#include "synth/povray/internal/rs_synth_twin_world.h"
#include "synth/povray/rs_synth_camera.h"
#include "synth/povray/rs_synth_render.h"
#include "synth/povray/rs_synth_scene.h"

void rs_synth_twin_options_default(rs_synth_twin_options *opt)
{
    memset(opt, 0, sizeof(*opt));
    opt->marking_width_m = 0.15;
    opt->canvas_scale = 1.0;
}

static rs_status write_twin_scene(const char *pov_path, const rs_synth_povcam *cam, const rs_site *site,
                                  const rs_lanes *lanes, const char *look, double sun_az, double sun_el,
                                  double marking_width_m, rs_err *err)
{
    rs_io_atomic a = {0};
    rs_status st = rs_io_atomic_open(&a, pov_path, err);
    if (st) return st;
    FILE *f = a.f;
    fprintf(f,
            "// Written by roadside site render-backgrounds: a digital-twin ground (%s).\n"
            "// POV-Ray world <x, y, z> = <east, up, north>, metres. No include files.\n"
            "#version 3.7;\n"
            "global_settings { assumed_gamma 1.0 max_trace_level 5 }\n",
            look);
    if (!(st = rs_synth_povcam_write(f, cam, err)))
        st = rs_synth_twin_world_write(f, site, lanes, look, sun_az, sun_el, marking_width_m, true, err);
    return rs_io_atomic_finish(&a, st, err); // a write error: the commit names its cause
}

// Runs `povray +Itwin.pov +Otwin.png +W +H ...` in work_dir (rs_synth_povray_run).
static rs_status run_twin_povray(const char *povray, const char *work_dir, int width, int height, int antialias,
                                 rs_err *err)
{
    char w[32], h[32], aa[32];
    snprintf(w, sizeof(w), "+W%d", width);
    snprintf(h, sizeof(h), "+H%d", height);
    if (antialias >= 2)
        snprintf(aa, sizeof(aa), "+R%d", antialias > 9 ? 9 : antialias);
    else
        snprintf(aa, sizeof(aa), "-A");
    const char *args[] = {
        "+Itwin.pov", "+Otwin.png", w, h, "-D", "+FN8", "File_Gamma=sRGB", antialias >= 2 ? "+A0.1" : "-A", aa, "+WT1"};
    return rs_synth_povray_run(povray, work_dir, args, (int)(sizeof(args) / sizeof(args[0])), NULL, err);
}

rs_status rs_synth_twin_render(double *sun_azimuth_deg, double *sun_elevation_deg, const char **conditions_out,
                               const char *out_png, const char *work_dir, const rs_site *site, const char *lanes_path,
                               const rs_camera *camera, double unix_time_s, const char *weather,
                               const rs_synth_twin_options *opt, rs_err *err)
{
    const mrcal_lensmodel_t *lensmodel = &camera->lensmodel;
    const double *intrinsics = camera->intrinsics, *rt_cam_enu = camera->rt_cam_enu;
    const int width = camera->width, height = camera->height;
    rs_synth_twin_options o;
    if (opt)
        o = *opt;
    else
        rs_synth_twin_options_default(&o);
    const char *povray = rs_synth_povray_exe(o.povray);
    const char *look = NULL; // a static string: one of rs_synth_background_conditions
    for (int i = 0; weather && rs_synth_background_conditions[i]; i++)
        if (!strcmp(weather, rs_synth_background_conditions[i])) look = rs_synth_background_conditions[i];
    if (!look || !rs_synth_twin_weather_ok(weather))
        return rs_err_set(err, RS_ERR_INVALID, "weather: '%s' is not one of sunny, cloudy, rain, snow, night",
                          weather ? weather : "");
    double az, el;
    rs_status st =
        rs_synth_sun_position_checked(&az, &el, site->origin.lat_deg, site->origin.lon_deg, unix_time_s, err);
    if (st) return st;
    if (el < -6.0) look = rs_synth_background_conditions[4]; // "night"
    if (sun_azimuth_deg) *sun_azimuth_deg = az;
    if (sun_elevation_deg) *sun_elevation_deg = el;
    if (conditions_out) *conditions_out = look;
    // A camera at or below the ground plane sees no ground from above: its extrinsics are wrong
    // (e.g. a camera looking straight down, a half-turn from ENU, written by mrcal 2.2's Python
    // r_from_R, which returns r = 0 for a half-turn: the model then looks up from underground).
    double c_enu[3];
    rs_pose_position_from_rt(c_enu, NULL, rt_cam_enu);
    const double h_m = c_enu[0] * site->ground_normal_enu[0] + c_enu[1] * site->ground_normal_enu[1] +
                       c_enu[2] * site->ground_normal_enu[2] - site->ground_offset_m;
    if (!(h_m > 0))
        return rs_err_set(err, RS_ERR_INVALID,
                          "the camera is %.2f m %s the site's ground plane (centre ENU %.2f, %.2f, %.2f m): its "
                          "extrinsics cannot be a roadside camera's (a rotation by 180 degrees written as r = 0?)",
                          fabs(h_m), h_m < 0 ? "below" : "on", c_enu[0], c_enu[1], c_enu[2]);

    rs_lanes lanes = {0};
    rs_synth_canvas canvas;
    rs_synth_povcam cam;
    rs_image img = {0}, lens = {0};
    float *map = NULL;
    char *pov = rs_io_join(work_dir, "twin.pov"), *png = rs_io_join(work_dir, "twin.png"),
         *log = rs_io_join(work_dir, "povray.log");
    if (!pov || !png || !log) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    if (lanes_path && (st = rs_lanes_read(&lanes, lanes_path, site, err))) goto done;
    if ((st = rs_io_mkdir_p(work_dir, err)) ||
        (st = rs_synth_canvas_for_lens(&canvas, lensmodel, intrinsics, width, height,
                                       o.canvas_scale >= 1 ? o.canvas_scale : 1, err)) ||
        (st = rs_synth_povcam_for_canvas(&cam, &canvas, rt_cam_enu, err)) ||
        (st = write_twin_scene(pov, &cam, site, &lanes, look, az, el, o.marking_width_m, err)) ||
        (st = run_twin_povray(povray, work_dir, canvas.width, canvas.height, o.antialias, err)) ||
        (st = rs_image_read(&img, png, err)))
        goto done;
    if (img.width != canvas.width || img.height != canvas.height) {
        st = rs_err_set(err, RS_ERR_EXTERNAL, "%s: povray wrote %dx%d, expected %dx%d", png, img.width, img.height,
                        canvas.width, canvas.height);
        goto done;
    }
    if (canvas.identity) {
        st = rs_image_write(out_png, &img, 8, err);
    } else {
        if ((st = rs_synth_canvas_map(&map, &canvas, lensmodel, intrinsics, width, height, err)) ||
            (st = rs_synth_remap(&lens, &img, map, width, height, 1, err)))
            goto done;
        st = rs_image_write(out_png, &lens, 8, err);
    }
    if (!st) {
        remove(pov);
        remove(png);
        remove(log);
    }
done:
    rs_lanes_free(&lanes);
    rs_image_free(&img);
    rs_image_free(&lens);
    free(map);
    free(pov);
    free(png);
    free(log);
    return st;
}

rs_status rs_synth_twin_backgrounds(const char *site_dir, const rs_site *site, const char *cam_id, const rs_camera *cam,
                                    const char *calibration, const char *lanes, const char *const *times, int Ntimes,
                                    const char *const *weathers, int Nweathers, const rs_synth_twin_options *opt,
                                    rs_synth_twin_progress progress, void *ctx, rs_err *err)
{
    char work[4096];
    snprintf(work, sizeof(work), "%s/backgrounds/%s/.twin-work", site_dir, cam_id);
    rs_status st = RS_OK;
    for (int t = 0; t < Ntimes && st == RS_OK; t++) {
        double unix_s;
        if ((st = rs_synth_parse_iso8601(&unix_s, times[t], "--times", err))) break;
        const time_t tt = (time_t)floor(unix_s);
        struct tm utc;
        char stamp[32];
        gmtime_r(&tt, &utc);
        strftime(stamp, sizeof(stamp), "%Y%m%dT%H%MZ", &utc);
        for (int w = 0; w < Nweathers && st == RS_OK; w++) {
            double az, el;
            const char *cond;
            char name[128], tmp[4200];
            double el0;
            rs_synth_sun_position(&az, &el0, site->origin.lat_deg, site->origin.lon_deg, unix_s);
            if (w > 0 && el0 < -6.0) continue; // night whatever the weather: one image per time (rendered at w = 0)
            // render under a temporary name first: the conditions (night?) decide the final name
            snprintf(tmp, sizeof(tmp), "%s/render.png", work);
            if ((st = rs_synth_twin_render(&az, &el, &cond, tmp, work, site, lanes, cam, unix_s, weathers[w], opt,
                                           err))) {
                if (st == RS_ERR_INVALID) rs_err_prefix(err, "camera %s (%s)", cam_id, calibration ? calibration : "");
                break;
            }
            snprintf(name, sizeof(name), "twin_%s_%s", stamp, cond);
            char *path = rs_synth_background_path(site_dir, cam_id, name);
            cJSON *source = cJSON_CreateObject();
            char azel[64];
            snprintf(azel, sizeof(azel), "%.3f", az);
            const char *keys[3] = {"sun_azimuth_deg", "sun_elevation_deg", "weather"};
            char elv[64];
            snprintf(elv, sizeof(elv), "%.3f", el);
            const char *values[3] = {azel, elv, weathers[w]};
            rs_synth_background_tags tags = {.name = name,
                                             .time_iso = times[t],
                                             .conditions = cond,
                                             .synthetic = true,
                                             .keys = keys,
                                             .values = values,
                                             .Ntags = 3};
            if (source) {
                cJSON_AddStringToObject(source, "method", "digital twin (POV-Ray)");
                cJSON_AddStringToObject(source, "calibration", calibration);
            }
            char *source_json = source ? cJSON_PrintUnformatted(source) : NULL;
            if (!path || !source_json)
                st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            else if (rename(tmp, path) != 0)
                st = rs_err_set(err, RS_ERR_IO, "%s: cannot rename to %s", tmp, path);
            else
                st = rs_synth_background_record(site_dir, cam_id, &tags, source_json, err);
            if (st == RS_OK && progress) progress(ctx, cam_id, path, az, el, cond);
            cJSON_Delete(source);
            cJSON_free(source_json);
            free(path);
        }
    }
    if (st == RS_OK) {
        char log[4200];
        snprintf(log, sizeof(log), "%s/povray.log", work);
        remove(log);
        rmdir(work);
    }
    return st;
}

// rs_synth_background.c -- temporal-median backgrounds, digital-twin backgrounds and their tags
// (rs_synth_background.h, docs/backgrounds.md); site.json is read and written by geo
// (rs_site_record_background), never here.
#include "synth/rs_synth_background.h"

#include <ctype.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "core/rs_io.h"
#include "core/rs_pose.h"
#include "geo/rs_site_write.h"
#include "synth/internal/rs_synth_twin.h"
#include "synth/rs_synth_camera.h"
#include "synth/rs_synth_opencv.h"
#include "synth/rs_synth_render.h"
#include "synth/rs_synth_scene.h"
#include "synth/rs_synth_sun.h"
#include "synth/rs_synth_traffic.h"

// ---- temporal median ----

size_t rs_synth_median_bytes_bound(int width, int height, int max_frames)
{
    return ((size_t)max_frames + 3) * (size_t)width * (size_t)height * 3;
}

void rs_synth_median_free(rs_synth_median *m)
{
    if (!m) return;
    free(m->rgb);
    memset(m, 0, sizeof(*m));
}

// The k-th smallest of a[0..n-1] (Hoare's selection; a is reordered).
static unsigned char select_kth(unsigned char *a, int n, int k)
{
    int lo = 0, hi = n - 1;
    while (lo < hi) {
        const unsigned char pivot = a[(lo + hi) / 2];
        int i = lo, j = hi;
        while (i <= j) {
            while (a[i] < pivot) i++;
            while (a[j] > pivot) j--;
            if (i <= j) {
                const unsigned char t = a[i];
                a[i++] = a[j];
                a[j--] = t;
            }
        }
        if (k <= j)
            hi = j;
        else if (k >= i)
            lo = i;
        else
            break;
    }
    return a[k];
}

rs_status rs_synth_background_median(rs_synth_median *out, const char *const *inputs, int Ninputs, int max_frames,
                                     rs_err *err)
{
    memset(out, 0, sizeof(*out));
    if (max_frames < 3 || max_frames > 255)
        return rs_err_set(err, RS_ERR_USAGE, "max_frames: %d is not in [3, 255]", max_frames);
    unsigned char *buf = NULL; // (max_frames, H, W, 3)
    size_t frame_bytes = 0;
    int n = 0, stride = 1, width = 0, height = 0;
    long index = 0;
    rs_status st = RS_OK;
    for (int in = 0; in < Ninputs && !st; in++) {
        rs_synth_frames *fr = NULL;
        if ((st = rs_synth_frames_open(&fr, inputs[in], err))) break;
        for (;;) {
            const unsigned char *rgb;
            int w, h, got;
            if ((st = rs_synth_frames_next(fr, &rgb, &w, &h, &got, err)) || !got) break;
            if (!buf) {
                width = w;
                height = h;
                frame_bytes = (size_t)w * h * 3;
                if (!(buf = malloc(frame_bytes * (size_t)max_frames))) {
                    st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory for %d frames of %dx%d", inputs[in],
                                    max_frames, w, h);
                    break;
                }
            } else if (w != width || h != height) {
                st = rs_err_set(err, RS_ERR_INVALID, "%s: frame %ld is %dx%d, the first frame was %dx%d", inputs[in],
                                index, w, h, width, height);
                break;
            }
            if (index % stride == 0) {
                if (n == max_frames) {
                    // full: keep buffer positions 0, 2, 4, ... and double the stride
                    int k = 0;
                    for (int i = 0; i < n; i += 2, k++)
                        if (k != i) memcpy(buf + k * frame_bytes, buf + i * frame_bytes, frame_bytes);
                    n = k;
                    stride *= 2;
                }
                if (index % stride == 0) memcpy(buf + (size_t)n++ * frame_bytes, rgb, frame_bytes);
            }
            index++;
        }
        rs_synth_frames_close(fr);
    }
    if (!st && n == 0) st = rs_err_set(err, RS_ERR_DEGENERATE, "no frame could be read from the %d input(s)", Ninputs);
    if (!st && !(out->rgb = malloc(frame_bytes))) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (st) {
        free(buf);
        memset(out, 0, sizeof(*out));
        return st;
    }
    unsigned char v[255];
    const int k = (n - 1) / 2;
    for (size_t p = 0; p < frame_bytes; p++) {
        for (int i = 0; i < n; i++) v[i] = buf[(size_t)i * frame_bytes + p];
        out->rgb[p] = select_kth(v, n, k);
    }
    free(buf);
    out->width = width;
    out->height = height;
    out->Nframes_read = index;
    out->Nframes_used = n;
    out->stride = stride;
    out->bytes_bound = rs_synth_median_bytes_bound(width, height, max_frames);
    return RS_OK;
}

// ---- tags and site.json ----

const char *const rs_synth_background_conditions[] = {"sunny", "cloudy", "rain", "snow", "night", NULL};

static bool is_safe_name(const char *s, size_t max)
{
    if (!s || !*s || *s == '.' || strlen(s) > max) return false;
    for (; *s; s++)
        if (!isalnum((unsigned char)*s) && *s != '_' && *s != '.' && *s != '-') return false;
    return true;
}

bool rs_synth_background_name_ok(const char *s) { return is_safe_name(s, 100); }

rs_status rs_synth_background_tags_check(const rs_synth_background_tags *t, rs_err *err)
{
    if (!rs_synth_background_name_ok(t->name))
        return rs_err_set(err, RS_ERR_USAGE,
                          "name: '%s' must be 1..100 characters of [A-Za-z0-9_.-], not starting "
                          "with '.'",
                          t->name ? t->name : "");
    if (t->time_iso) {
        double unix_s;
        rs_status st = rs_synth_parse_iso8601(&unix_s, t->time_iso, "tag time", err);
        if (st) return st;
    }
    if (t->conditions) {
        bool ok = false;
        for (int i = 0; rs_synth_background_conditions[i]; i++)
            ok = ok || !strcmp(t->conditions, rs_synth_background_conditions[i]);
        if (!ok)
            return rs_err_set(err, RS_ERR_USAGE, "tag conditions: '%s' is not one of sunny, cloudy, rain, snow, night",
                              t->conditions);
    }
    return RS_OK;
}

rs_status rs_synth_background_tag_parse(rs_synth_background_tags *t, const char **keys, const char **values, char *kv,
                                        rs_err *err)
{
    char *eq = strchr(kv, '=');
    if (!eq || eq == kv) return rs_err_set(err, RS_ERR_USAGE, "tag '%s': expected key=value", kv);
    *eq = 0;
    const char *key = kv, *value = eq + 1;
    if (!strcmp(key, "time"))
        t->time_iso = value;
    else if (!strcmp(key, "conditions"))
        t->conditions = value;
    else if (!strcmp(key, "synthetic") || !is_safe_name(key, 64)) {
        *eq = '=';
        return rs_err_set(err, RS_ERR_USAGE, "tag '%s': the key must be [A-Za-z0-9_.-]+ and not 'synthetic'", kv);
    } else {
        keys[t->Ntags] = key;
        values[t->Ntags] = value;
        t->Ntags++;
        t->keys = keys;
        t->values = values;
    }
    return RS_OK;
}

char *rs_synth_background_path(const char *site_dir, const char *camera_id, const char *name)
{
    char *rel = rs_site_background_file(camera_id, name);
    char *p = rel ? rs_io_join(site_dir, rel) : NULL;
    free(rel);
    return p;
}

rs_status rs_synth_background_record(const char *site_dir, const char *camera_id, const rs_synth_background_tags *t,
                                     const char *source_json, rs_err *err)
{
    // time and conditions first, then the free tags in the order given
    const char **keys = malloc(sizeof(char *) * (size_t)(t->Ntags + 2));
    const char **values = malloc(sizeof(char *) * (size_t)(t->Ntags + 2));
    int n = 0;
    rs_status st;
    if (!keys || !values) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    if (t->time_iso) keys[n] = "time", values[n++] = t->time_iso;
    if (t->conditions) keys[n] = "conditions", values[n++] = t->conditions;
    for (int i = 0; i < t->Ntags; i++) keys[n] = t->keys[i], values[n++] = t->values[i];
    st = rs_site_record_background(site_dir, camera_id, t->name, t->synthetic, keys, values, n, source_json, err);
done:
    free(keys);
    free(values);
    return st;
}

// ---- digital-twin backgrounds ----

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
    if ((st = rs_synth_povcam_write(f, cam, err)) ||
        (st = rs_synth_twin_world_write(f, site, lanes, look, sun_az, sun_el, marking_width_m, true, err))) {
        rs_io_atomic_abort(&a);
        return st;
    }
    if (ferror(f)) {
        rs_io_atomic_abort(&a);
        return rs_err_set(err, RS_ERR_IO, "%s: write error", pov_path);
    }
    return rs_io_atomic_commit(&a, err);
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

rs_status rs_synth_background_render_twin(double *sun_azimuth_deg, double *sun_elevation_deg,
                                          const char **conditions_out, const char *out_png, const char *work_dir,
                                          const rs_site *site, const char *lanes_path, const rs_camera *camera,
                                          double unix_time_s, const char *weather, const rs_synth_twin_options *opt,
                                          rs_err *err)
{
    const mrcal_lensmodel_t *lensmodel = &camera->lensmodel;
    const double *intrinsics = camera->intrinsics, *rt_cam_enu = camera->rt_cam_enu;
    const int width = camera->width, height = camera->height;
    rs_synth_twin_options o;
    if (opt)
        o = *opt;
    else
        rs_synth_twin_options_default(&o);
    const char *povray = o.povray ? o.povray : getenv("ROADSIDE_POVRAY");
    if (!povray || !*povray) povray = "povray";
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
        (st = rs_synth_povcam_init(&cam, canvas.fxycxy, canvas.width, canvas.height, rt_cam_enu, err)) ||
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

rs_status rs_synth_background_twins(const char *site_dir, const rs_site *site, const char *cam_id, const rs_camera *cam,
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
            if ((st = rs_synth_background_render_twin(&az, &el, &cond, tmp, work, site, lanes, cam, unix_s, weathers[w],
                                                      opt, err))) {
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

rs_status rs_synth_background_save_median(char **path_out, const char *site_dir, const char *camera_id,
                                          const rs_synth_background_tags *tags, const rs_synth_median *med,
                                          const char *const *inputs, int Ninputs, rs_err *err)
{
    *path_out = NULL;
    rs_image img = {0};
    char *path = NULL, *dir = NULL, *source_json = NULL;
    cJSON *source = NULL;
    rs_status st = rs_image_alloc(&img, med->width, med->height, 3, err);
    if (st) return st;
    for (size_t p = 0; p < (size_t)med->width * med->height * 3; p++) img.data[p] = med->rgb[p] / 255.0f;
    path = rs_synth_background_path(site_dir, camera_id, tags->name);
    dir = path ? strdup(path) : NULL;
    source = cJSON_CreateObject();
    if (!path || !dir || !source) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    *strrchr(dir, '/') = 0;
    cJSON_AddStringToObject(source, "method", "temporal median");
    cJSON *in = cJSON_AddArrayToObject(source, "inputs");
    for (int i = 0; i < Ninputs; i++) cJSON_AddItemToArray(in, cJSON_CreateString(inputs[i]));
    cJSON_AddNumberToObject(source, "frames_read", (double)med->Nframes_read);
    cJSON_AddNumberToObject(source, "frames_used", med->Nframes_used);
    cJSON_AddNumberToObject(source, "stride", med->stride);
    if (!(source_json = cJSON_PrintUnformatted(source))) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    if ((st = rs_io_mkdir_p(dir, err)) || (st = rs_image_write(path, &img, 8, err)) ||
        (st = rs_synth_background_record(site_dir, camera_id, tags, source_json, err)))
        goto done;
    *path_out = path;
    path = NULL;
done:
    cJSON_Delete(source);
    cJSON_free(source_json);
    free(path);
    free(dir);
    rs_image_free(&img);
    return st;
}

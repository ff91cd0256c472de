// roadside background / roadside site render-backgrounds -- backgrounds of a camera's view: the
// temporal median of video frames or images, and digital-twin grounds ray-traced with POV-Ray,
// stored in the site with tags (synth/backdrop/rs_synth_background.h, docs/backgrounds.md).
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cli/rs_cli.h"
#include "core/rs_camera.h"
#include "core/rs_io.h"
#include "geo/rs_site.h"
#include "synth/backdrop/rs_synth_background.h"
#include "synth/backdrop/rs_synth_opencv.h"
#include "synth/backdrop/rs_synth_sun.h"
#include "synth/povray/rs_synth_twin.h"

enum { MAX_TAGS = 64 };

static void usage_background(FILE *out)
{
    fprintf(out, "usage: roadside background SITE --camera ID INPUT... [--tag key=value]... [--name NAME]\n"
                 "\n"
                 "Makes a background image of camera ID's empty scene by the temporal median of the\n"
                 "frames of the INPUTs (videos, read with OpenCV, and/or image files, in order), and\n"
                 "stores it as SITE/backgrounds/ID/NAME.png, recorded in site.json (the camera's\n"
                 "\"background_images\" list, docs/backgrounds.md) with its tags.\n"
                 "\n"
                 "Streaming with bounded memory: at most --max-frames frames, evenly spaced over the whole\n"
                 "input, are kept (every s-th frame, s doubling whenever the buffer fills); the median is\n"
                 "exact over them. Memory: (max-frames + 3) x W x H x 3 bytes (174 MB at 1920x1080, 25).\n"
                 "\n"
                 "  --camera ID        the site's camera (required)\n"
                 "  --name NAME        file stem, [A-Za-z0-9_.-] [median]\n"
                 "  --tag key=value    time=ISO-8601-with-zone (e.g. 2024-06-21T14:30:00+02:00),\n"
                 "                     conditions=sunny|cloudy|rain|snow|night, or any other key; repeatable\n"
                 "  --max-frames K     frame budget, 3..255 [25]\n"
                 "\n"
                 "Exit status: 0 written, 1 failed (nothing written), 2 bad arguments.\n");
}

static void usage_render(FILE *out)
{
    fprintf(out, "usage: roadside site render-backgrounds SITE --calib DIR [--camera ID] [--times T1,T2,...]\n"
                 "                                        [--weather W1,W2,...]\n"
                 "\n"
                 "Ray-traces (POV-Ray) a digital twin of the site's ground through each calibrated camera\n"
                 "(DIR/<id>.cameramodel, as written by `roadside calib`): asphalt on the site's ground\n"
                 "plane, white markings along both edges of every lane of SITE/lanes.geojson, the sun at\n"
                 "its position for the site's origin and each time. Stores SITE/backgrounds/<id>/\n"
                 "twin_<UTC time>_<conditions>.png, recorded in site.json with synthetic = true and\n"
                 "tags time, conditions (docs/backgrounds.md).\n"
                 "\n"
                 "  --calib DIR        folder of calibrated .cameramodel files (required)\n"
                 "  --camera ID        only this camera [all the site's cameras]\n"
                 "  --times LIST       ISO 8601 times with zone, comma-separated\n"
                 "                     [2024-06-21 at mean solar 09:00, 12:00, 16:00 at the site]\n"
                 "  --weather LIST     of sunny, cloudy, rain, snow [sunny,cloudy]; a sun below -6 deg\n"
                 "                     makes it night whatever the weather\n"
                 "  --lanes FILE       lanes file [SITE/lanes.geojson; none: no markings]\n"
                 "  --antialias N      POV-Ray antialiasing depth, 0 or 2..9 [0]\n"
                 "\n"
                 "Exit status: 0 written, 1 failed, 2 bad arguments.\n");
}

int rs_cli_background(int argc, char **argv)
{
    static const char *const CMD = "background";
    if (rs_cli_wants_help(argc, argv)) {
        usage_background(stdout);
        return RS_EXIT_OK;
    }
    const char *site_dir = NULL, *camera = NULL;
    const char **inputs = calloc((size_t)argc + 1, sizeof(*inputs));
    const char *keys[MAX_TAGS + 1], *values[MAX_TAGS + 1];
    rs_synth_background_tags tags = {.name = "median"};
    int Ninputs = 0;
    long max_frames = 25;
    rs_err err = {0};
    int rc = RS_EXIT_OK;
    if (!inputs) return rs_cli_fail(CMD, RS_ERR_NOMEM, NULL);
    for (int i = 1; i < argc && rc == RS_EXIT_OK; i++) {
        const char *a = argv[i];
        const bool has_value = i + 1 < argc;
        if (!strcmp(a, "--camera") && has_value)
            camera = argv[++i];
        else if (!strcmp(a, "--name") && has_value)
            tags.name = argv[++i];
        else if (!strcmp(a, "--max-frames") && has_value) {
            if (!rs_cli_parse_int(argv[++i], 3, 255, &max_frames))
                rc = rs_cli_usage_error(CMD, "--max-frames: '%s' is not an integer in 3..255", argv[i]);
        } else if (!strcmp(a, "--tag") && has_value) {
            if (tags.Ntags >= MAX_TAGS)
                rc = rs_cli_usage_error(CMD, "--tag: at most %d tags", MAX_TAGS);
            else if (rs_synth_background_tag_parse(&tags, keys, values, argv[++i], &err))
                rc = rs_cli_usage_error(CMD, "--tag: %s", err.msg);
        } else if (a[0] == '-' && a[1])
            rc = rs_cli_usage_error(CMD, "unknown option or missing value: '%s'", a);
        else if (!site_dir)
            site_dir = a;
        else
            inputs[Ninputs++] = a;
    }
    if (rc == RS_EXIT_OK && (!site_dir || !camera || Ninputs == 0))
        rc = rs_cli_usage_error(CMD, "needs SITE, --camera ID and at least one INPUT");
    if (rc == RS_EXIT_OK && rs_synth_background_tags_check(&tags, &err)) rc = rs_cli_usage_error(CMD, "%s", err.msg);
    if (rc != RS_EXIT_OK) {
        free(inputs);
        return rc;
    }
    rs_site *site = NULL;
    rs_synth_median med = {0};
    char *path = NULL;
    rs_status st;
    const double t0 = (double)clock() / CLOCKS_PER_SEC;
    if ((st = rs_site_load(&site, site_dir, &err))) {
        rc = rs_cli_fail(site_dir, st, &err);
        goto done;
    }
    if (!rs_synth_background_name_ok(camera)) {
        rc = rs_cli_fail(CMD, RS_ERR_INVALID,
                         &(rs_err){RS_ERR_INVALID, "--camera: the id cannot be a folder name "
                                                   "([A-Za-z0-9_.-], not starting with '.')"});
        goto done;
    }
    if (rs_site_find_camera(site, camera) < 0) {
        rc = rs_cli_fail(CMD, RS_ERR_NOT_FOUND, &(rs_err){RS_ERR_NOT_FOUND, "--camera: the site has no such camera"});
        goto done;
    }
    if ((st = rs_synth_background_median(&med, (const char *const *)inputs, Ninputs, (int)max_frames, &err))) {
        rc = rs_cli_fail(CMD, st, &err);
        goto done;
    }
    const double seconds = (double)clock() / CLOCKS_PER_SEC - t0;
    const rs_camera *nominal = &site->cameras[rs_site_find_camera(site, camera)].camera;
    if (med.width != nominal->width || med.height != nominal->height)
        fprintf(stderr, "roadside background: warning: frames are %dx%d, camera %s is %dx%d\n", med.width, med.height,
                camera, nominal->width, nominal->height);
    if ((st = rs_synth_background_save_median(&path, site_dir, camera, &tags, &med, (const char *const *)inputs,
                                              Ninputs, &err))) {
        rc = rs_cli_fail(CMD, st, &err);
        goto done;
    }
    printf("background: %s (%dx%d)\n", path, med.width, med.height);
    printf("frames read %ld, median over %d (every %d-th), memory bound %.1f MB, %.2f ms/frame\n", med.Nframes_read,
           med.Nframes_used, med.stride, med.bytes_bound / 1e6, 1e3 * seconds / (double)med.Nframes_read);
    printf("recorded in %s/site.json (camera %s, name %s)\n", site_dir, camera, tags.name);
done:
    free(path);
    rs_synth_median_free(&med);
    rs_site_free(site);
    free(inputs);
    return rc;
}

// ---- roadside site render-backgrounds ----

// Splits a comma-separated list in place; returns the count (at most max).
static int split_list(char *s, char **out, int max)
{
    int n = 0;
    for (char *tok = strtok(s, ","); tok && n < max; tok = strtok(NULL, ",")) out[n++] = tok;
    return n;
}

// Prints each background as it is recorded.
static void twin_done(void *ctx, const char *camera_id, const char *path, double az_deg, double el_deg,
                      const char *conditions)
{
    (void)ctx;
    printf("%s: %s (sun azimuth %.2f, elevation %.2f deg, %s)\n", camera_id, path, az_deg, el_deg, conditions);
}

// Renders and records the backgrounds of one camera: every time x weather.
static int render_camera(const char *site_dir, const rs_site *site, const char *calib_dir, const char *cam_id,
                         const char *lanes, char **times, int Ntimes, char **weathers, int Nweathers,
                         const rs_synth_twin_options *opt)
{
    static const char *const WHAT = "site render-backgrounds";
    char model[4096];
    rs_camera cam = {0};
    rs_err err = {0};
    rs_status st = rs_camera_path(model, sizeof model, calib_dir, cam_id, RS_CAMERA_EXT_CAMERAMODEL)
                       ? rs_camera_read(&cam, NULL, model, &err)
                       : rs_err_set(&err, RS_ERR_INVALID, "%s: path too long", calib_dir);
    if (st == RS_OK)
        st = rs_synth_twin_backgrounds(site_dir, site, cam_id, &cam, model, lanes, (const char *const *)times, Ntimes,
                                       (const char *const *)weathers, Nweathers, opt, twin_done, NULL, &err);
    rs_camera_free(&cam);
    return st ? rs_cli_fail(WHAT, st, &err) : RS_EXIT_OK;
}

int rs_cli_site_render_backgrounds(int argc, char **argv)
{
    static const char *const CMD = "site render-backgrounds";
    if (rs_cli_wants_help(argc, argv)) {
        usage_render(stdout);
        return RS_EXIT_OK;
    }
    const char *site_dir = NULL, *calib = NULL, *camera = NULL, *lanes_opt = NULL;
    char *times_arg = NULL, *weather_arg = NULL;
    rs_synth_twin_options opt;
    rs_synth_twin_options_default(&opt);
    int rc = RS_EXIT_OK;
    for (int i = 1; i < argc && rc == RS_EXIT_OK; i++) {
        const char *a = argv[i];
        const bool v = i + 1 < argc;
        long n;
        if (!strcmp(a, "--calib") && v)
            calib = argv[++i];
        else if (!strcmp(a, "--camera") && v)
            camera = argv[++i];
        else if (!strcmp(a, "--times") && v)
            times_arg = argv[++i];
        else if (!strcmp(a, "--weather") && v)
            weather_arg = argv[++i];
        else if (!strcmp(a, "--lanes") && v)
            lanes_opt = argv[++i];
        else if (!strcmp(a, "--antialias") && v) {
            if (!rs_cli_parse_int(argv[++i], 0, 9, &n) || n == 1)
                rc = rs_cli_usage_error(CMD, "--antialias: '%s' is not 0 or 2..9", argv[i]);
            opt.antialias = (int)n;
        } else if (a[0] == '-' && a[1])
            rc = rs_cli_usage_error(CMD, "unknown option or missing value: '%s'", a);
        else if (!site_dir)
            site_dir = a;
        else
            rc = rs_cli_usage_error(CMD, "unexpected argument '%s'", a);
    }
    if (rc == RS_EXIT_OK && (!site_dir || !calib)) rc = rs_cli_usage_error(CMD, "needs SITE and --calib DIR");
    char *times[64], *weathers[8];
    char default_times[3][40];
    int Ntimes = 0, Nweathers = 0;
    char weather_default[] = "sunny,cloudy";
    if (rc == RS_EXIT_OK) {
        Nweathers = split_list(weather_arg ? weather_arg : weather_default, weathers, 8);
        for (int w = 0; w < Nweathers && rc == RS_EXIT_OK; w++)
            if (strcmp(weathers[w], "sunny") && strcmp(weathers[w], "cloudy") && strcmp(weathers[w], "rain") &&
                strcmp(weathers[w], "snow") && strcmp(weathers[w], "night"))
                rc = rs_cli_usage_error(CMD, "--weather: '%s' is not sunny, cloudy, rain or snow", weathers[w]);
        if (times_arg) Ntimes = split_list(times_arg, times, 64);
        if (rc == RS_EXIT_OK && Nweathers == 0) rc = rs_cli_usage_error(CMD, "--weather: empty list");
        if (rc == RS_EXIT_OK && times_arg && Ntimes == 0) rc = rs_cli_usage_error(CMD, "--times: empty list");
    }
    if (rc != RS_EXIT_OK) return rc;
    rs_site *site = NULL;
    rs_err err = {0};
    rs_status st = rs_site_load(&site, site_dir, &err);
    if (st) return rs_cli_fail(site_dir, st, &err);
    if (!times_arg) {
        // 2024-06-21 at mean solar 09:00, 12:00, 16:00: UTC = solar - longitude / 15 h
        const double solar_h[3] = {9, 12, 16};
        for (int k = 0; k < 3; k++) {
            const time_t t = (time_t)(1718928000.0 + 3600.0 * solar_h[k] - 240.0 * site->origin.lon_deg);
            struct tm utc;
            gmtime_r(&t, &utc);
            strftime(default_times[k], sizeof(default_times[k]), "%Y-%m-%dT%H:%M:%SZ", &utc);
            times[k] = default_times[k];
        }
        Ntimes = 3;
    }
    char *lanes = lanes_opt ? strdup(lanes_opt) : rs_io_join(site_dir, RS_SITE_LANES);
    if (!lanes) {
        rs_site_free(site);
        return rs_cli_fail(CMD, RS_ERR_NOMEM, NULL);
    }
    if (!lanes_opt && access(lanes, R_OK) != 0) {
        fprintf(stderr, "roadside %s: %s: no lanes file, rendering the ground without markings\n", CMD, lanes);
        free(lanes);
        lanes = NULL;
    }
    if (camera && rs_site_find_camera(site, camera) < 0)
        rc = rs_cli_usage_error(CMD, "--camera: the site has no camera '%s'", camera);
    for (int c = 0; c < site->Ncameras && rc == RS_EXIT_OK; c++)
        if (camera && strcmp(camera, site->cameras[c].id))
            continue;
        else if (!rs_synth_background_name_ok(site->cameras[c].id))
            rc = rs_cli_fail(CMD, RS_ERR_INVALID,
                             &(rs_err){RS_ERR_INVALID, "camera id cannot be a folder name "
                                                       "([A-Za-z0-9_.-], not starting with '.')"});
        else
            rc = render_camera(site_dir, site, calib, site->cameras[c].id, lanes, times, Ntimes, weathers, Nweathers,
                               &opt);
    free(lanes);
    rs_site_free(site);
    return rc;
}

// rs_synth_twin.h -- digital-twin backgrounds: the site ray-traced by POV-Ray as a calibrated camera
// sees it, at a time and in a weather (`roadside site render-backgrounds`, docs/backgrounds.md),
// recorded in site.json like any background (synth/backdrop/rs_synth_background.h).
#pragma once
#include "core/rs_camera.h"
#include "core/rs_status.h"
#include "geo/rs_site.h"

#ifdef __cplusplus
extern "C" {
#endif

// The weathers of a rendered background: "sunny", "cloudy", "rain", "snow" (conditions tag), and
// "night" is chosen automatically when the sun is below -6 degrees (civil twilight).
typedef struct {
    const char *povray;     // executable; NULL: $ROADSIDE_POVRAY, else "povray"
    double marking_width_m; // lane-edge marking width (default 0.15 m)
    double canvas_scale;    // distorted lenses: canvas pixels per core pixel (default 1)
    int antialias;          // 0 none, n >= 2: +A0.1 +AM2 +R(n) (default 0)
} rs_synth_twin_options;
void rs_synth_twin_options_default(rs_synth_twin_options *opt);

// Ray-traces the site's digital twin seen by a calibrated camera (synth/povray/rs_synth_twin_world.c,
// docs/backgrounds.md "What the twin draws"): the site's ground plane as asphalt (grain, bump,
// patches), the markings lanes.geojson describes (lane edges marking_width_m wide, and where a
// lane enters a junction path a crosswalk, a stop bar and a turn arrow of its movements, where
// one leaves it a crosswalk), raised sidewalks with kerbs outside the road, the site's poles, a
// sky, and the sun at the azimuth/elevation rs_synth_sun_position gives for the site's origin
// and the time. Weather changes the sky light, the sun (none when cloudy, rain or at
// night), the asphalt (darker and glossier in rain, white with faint markings in snow).
// Writes the 8-bit sRGB image to out_png atomically (a distorted lens is rendered on a pinhole
// canvas and resampled with mrcal's projection, rs_synth_camera.h). Temporary scene files go to
// work_dir (created if missing) and are removed.
// in: site (loaded), lanes_path (lanes.geojson; may be NULL: no markings), cam (calibrated);
//     unix_time_s; weather (one of sunny/cloudy/rain/snow; "night" also accepted); opt may be NULL
// out: *sun_azimuth_deg, *sun_elevation_deg (may be NULL); *conditions_out: the conditions tag
//      the image shows (static string; weather, or "night")
// Returns RS_ERR_EXTERNAL when povray is missing or fails, RS_ERR_INVALID for a bad weather.
rs_status rs_synth_twin_render( // out
    double *sun_azimuth_deg, double *sun_elevation_deg, const char **conditions_out,
    // in
    const char *out_png, const char *work_dir, const rs_site *site, const char *lanes_path, const rs_camera *cam,
    double unix_time_s, const char *weather, const rs_synth_twin_options *opt, rs_err *err);

// Called as each background is recorded: the camera, the image's path, the sun and the
// conditions tag (rs_synth_twin_backgrounds).
typedef void (*rs_synth_twin_progress)(void *ctx, const char *camera_id, const char *path, double sun_azimuth_deg,
                                       double sun_elevation_deg, const char *conditions);

// `roadside site render-backgrounds` for one camera: a digital-twin background
// (rs_synth_twin_render) for every time x weather (one image per time at night),
// each renamed to SITE/backgrounds/<id>/twin_<UTC stamp>_<conditions>.png and recorded in
// site.json (rs_synth_background_record: its time, conditions, sun and weather tags and its
// source, the calibration file it was made from). The work folder
// SITE/backgrounds/<id>/.twin-work is removed when all went well.
// in: site_dir, site (loaded), cam_id, cam (calibrated), calibration (its file, recorded),
//     lanes (may be NULL: no markings), times (Ntimes,) ISO 8601, weathers (Nweathers,),
//     opt (may be NULL); progress (may be NULL) and its ctx
// Errors: those of rs_synth_twin_render and rs_synth_background_record; a time
// that is not ISO 8601 is RS_ERR_USAGE naming "--times".
rs_status rs_synth_twin_backgrounds(const char *site_dir, const rs_site *site, const char *cam_id, const rs_camera *cam,
                                    const char *calibration, const char *lanes, const char *const *times, int Ntimes,
                                    const char *const *weathers, int Nweathers, const rs_synth_twin_options *opt,
                                    rs_synth_twin_progress progress, void *ctx, rs_err *err);

#ifdef __cplusplus
}
#endif

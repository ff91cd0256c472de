// rs_synth_light.h -- the light of roadside's scenes and the light a background image shows: the
// model (a sun and RS_SYNTH_SKY_LIGHTS sky lights, an environment the vehicles reflect), the
// level and colour of a background's light read from its road, its environment, and the sun's
// direction from the shadows of the site's poles (docs/backgrounds.md, "Lighting matched to the
// background"). POV-Ray draws the model: synth/povray/rs_synth_scene.h.
#pragma once
#include <stdbool.h>

#include "core/rs_camera.h"
#include "core/rs_image.h"
#include "core/rs_status.h"
#include "geo/rs_lanes.h"
#include "geo/rs_site.h"

#ifdef __cplusplus
extern "C" {
#endif

// ---- the light model ----

// The sky: RS_SYNTH_SKY_LIGHTS parallel lights standing for a uniform sky, the hemisphere cut
// into two bands of zenith angle, 0-40 and 40-90 deg, which give sin^2(40 deg) = 0.413 and
// 0.587 of a uniform sky's irradiance on the ground: one light at the zenith and 6 at zenith
// 60 deg (azimuths 0, 60, ..; near the band's cosine-weighted mean zenith angle, 61 deg). In
// the colour pass they are shadowless (soft light on every face of a vehicle); in the shadow
// pass they cast shadows. (13 lights in three bands, the lowest at 15 deg elevation, cost
// 1.9 x the shadow pass's trace time and widen its region by shadows 3.7 x a vehicle's height;
// the difference on the ground is a few percent of the light, docs/synth.md.)
#define RS_SYNTH_SKY_LIGHTS   7
// The sky's irradiance on the ground relative to a sun at the zenith (1): clear and overcast.
#define RS_SYNTH_SKY_CLEAR    0.35
#define RS_SYNTH_SKY_OVERCAST 1.0

typedef struct {
    double dir_enu[3]; // unit vector from the ground towards the light
    double irradiance; // on a surface facing the light (POV-Ray's light colour, grey)
} rs_synth_light;

// The default environment: a clear sky (blue zenith, pale horizon) or an overcast one (grey,
// as bright as RS_SYNTH_SKY_OVERCAST), over asphalt of albedo 0.18 lit by the sun and sky.
void rs_synth_env_default(double zenith_rgb[3], double horizon_rgb[3], double ground_rgb[3], bool overcast);

// ---- the light a background shows (docs/backgrounds.md, "Lighting matched to the background") ----

// The road's effective reflectance as POV-Ray renders it (pigment x diffuse): radiance = this x
// irradiance on the ground, in the units of roadside's scenes (a sun at the zenith gives
// irradiance 1). 0.078 is the digital twin's asphalt measured through the estimator below (its
// grain, patches and repairs around a pigment of 0.10, diffuse 0.8); a real road is assumed to
// reflect the same (aged asphalt: about 0.1, fresh 0.05, worn concrete 0.2 and more), so for a
// photograph the level is relative to that assumption and to the camera's exposure.
#define RS_SYNTH_ROAD_ALBEDO 0.078

// Where a light estimate comes from (rs_synth_light_from_background), best first.
typedef enum {
    RS_SYNTH_LIGHT_FROM_LANES = 0,      // the road inside lanes.geojson's lanes
    RS_SYNTH_LIGHT_FROM_GROUND = 1,     // the ground plane within 60 m of the camera
    RS_SYNTH_LIGHT_FROM_LOWER_IMAGE = 2 // the lower half of the image
} rs_synth_light_source;

// What the road of a background says about its light.
typedef struct {
    double road_rgb[3];           // per-channel interquartile mean of the road pixels, linear light
    int Nroad_px;                 // road pixels sampled
    double irradiance_rgb[3];     // road_rgb / RS_SYNTH_ROAD_ALBEDO: light on the ground per channel
    double level;                 // mean of irradiance_rgb
    double tint_rgb[3];           // irradiance_rgb / level (the light's colour; (1, 1, 1) is grey)
    rs_synth_light_source source; // the pixels used (Nroad_px of them)
} rs_synth_light_estimate;

// Estimates the light on the ground from a background image: the road pixels are those whose
// ray (rs_camera_locate_ground, the site's ground plane) meets the ground within 60 m of the
// camera and at least 0.4 m inside a lane of lanes.geojson (clear of the lane-edge markings),
// sampled every `step_px` pixels (>= 1); the per-channel interquartile mean of their linear
// values (the mean between the 25th and 75th percentiles: robust to markings, arrows,
// crosswalks, oil stains and stray vehicles while they cover less than a quarter of the lanes,
// and finer than the 8-bit steps a median would be stuck on) divided by RS_SYNTH_ROAD_ALBEDO.
// The road is assumed dry: a wet road mirrors the sky and a snowy one is white (the digital
// twin's rain reads 1.45 for a sky of 0.55), so callers use it for sunny, cloudy or untagged
// backgrounds only.
// Accuracy (tests/synth/backdrop/test_light_estimate.py, digital-twin renders of the demo site): the
// level within 5% of the rendered sky (overcast) or sun + sky (sunny), the tint within 1% of
// a tint applied to the image; for photographs it holds to the albedo assumption above.
// in: linear_rgb: (H, W, >= 3) linear light, the camera's size; cam; site (its ground plane);
//     lanes; step_px
// Returns RS_ERR_INVALID (image size differs from the camera's), RS_ERR_DEGENERATE (fewer than
// 50 road pixels in view), RS_ERR_NOMEM.
rs_status rs_synth_light_from_image( // out
    rs_synth_light_estimate *out,
    // in
    const rs_image *linear_rgb, const rs_camera *cam, const rs_site *site, const rs_lanes *lanes, int step_px,
    rs_err *err);

// A pixel is grey (asphalt, concrete, kerbs; not grass or soil) when max - min of its linear
// R, G, B is at most this fraction of the max.
#define RS_SYNTH_LIGHT_GREY_CHROMA 0.3

// The same, never silently without an estimate (issue 40: a site without lanes): the road in the
// lanes (rs_synth_light_from_image) when at least 50 of its pixels are in view; else the ground
// plane in view (the pixels whose ray meets the site's ground plane within 60 m of the camera,
// rs_synth_env_from_image's ground class: road, markings, kerbs, sidewalks, verges), its grey
// pixels (RS_SYNTH_LIGHT_GREY_CHROMA) when at least 50 of them, else all, at least 50; else
// every pixel of the image's lower half (rows >= H/2). The same interquartile mean over
// RS_SYNTH_ROAD_ALBEDO in each case; out->source says which was used. The grey rule assumes a
// light near white: under a strongly tinted one (dusk: the blue channel under 0.7 of the red)
// the road is no longer "grey" and the estimate falls back to all the ground pixels.
// Accuracy of the ground plane against the lanes (docs/backgrounds.md; four digital-twin
// backgrounds of the demo site through cam1 at 720 px, sunny and cloudy): the level +2.2 ..
// +4.4 % above the lanes' (the twin's pale sidewalks and kerbs), the tint within 0.1 %
// (tests/synth/povray/test_render_env.py: 6 % and 1 % at 360 px); a real site's paving moves
// it as far as it differs from the road and covers more than a quarter of the grey ground.
// in: as rs_synth_light_from_image (lanes may have N = 0)
// Returns RS_ERR_INVALID (size), RS_ERR_NOMEM, RS_ERR_DEGENERATE (an image of fewer than 50
// pixels on the grid's lower half).
rs_status rs_synth_light_from_background( // out
    rs_synth_light_estimate *out,
    // in
    const rs_image *linear_rgb, const rs_camera *cam, const rs_site *site, const rs_lanes *lanes, int step_px,
    rs_err *err);

// "the road in the lanes", "the ground plane within 60 m", "the lower half of the image".
const char *rs_synth_light_source_name(rs_synth_light_source source);

// The per-channel factor on every light of a scene (rs_synth_scene_options.light_rgb_scale) that
// makes the scene's own irradiance on level ground -- the sun, of colour (1, 0.97, 0.92) and
// irradiance sin(elevation) when `sun` and it is up, plus the sky, RS_SYNTH_SKY_CLEAR with a sun
// or RS_SYNTH_SKY_OVERCAST without -- equal the estimate's. out: scale_rgb (3,)
void rs_synth_light_match(double scale_rgb[3],
                          // in
                          const rs_synth_light_estimate *est, bool sun, double sun_elevation_deg);

// ---- the environment a background shows (what the vehicles reflect) ----

// Sky pixels up to this elevation above the ground plane's horizon are the environment's
// horizon colour, higher ones its zenith colour.
#define RS_SYNTH_ENV_HORIZON_DEG 20.0
// A class of pixels (ground, low sky, high sky) is used when at least this many were sampled.
#define RS_SYNTH_ENV_MIN_PX      20

// The colours of a background's ground and sky, linear RGB: the radiance the image shows, in the
// same units as rs_synth_light_from_image's road_rgb (and the scene's: a white surface under a
// sun at the zenith is 1, to the road-albedo assumption and the camera's exposure).
typedef struct {
    double ground_rgb[3];  // mean of the ground pixels (0 when none)
    int Nground_px;        // ground pixels sampled
    double horizon_rgb[3]; // mean of the sky pixels 0 .. RS_SYNTH_ENV_HORIZON_DEG above the horizon
    int Nhorizon_px;
    double zenith_rgb[3]; // mean of the sky pixels higher than that
    int Nzenith_px;
    double sky_rgb[3]; // mean of the brightest tenth (by linear luminance, at or above the 90th
                       // percentile) of all the pixels above the horizon, both bands: the open sky
                       // a daylight view shows, however low it sees (0 when none)
    int Nsky_px;
} rs_synth_env_estimate;

// The environment a background shows, for rs_synth_scene_options.env_* (issue 18: the vehicles
// reflect the scene itself). Pixels of the step_px grid (the same grid and the same per-camera
// cache as rs_synth_light_from_image, so a worker finds them once per camera):
//   - ground: the pixel's ray (rs_camera_locate_ground) meets the site's ground plane within
//     60 m (horizontal) of the camera -- road, markings, kerbs, sidewalks, whatever lies there;
//   - sky: the ray does not meet the ground plane but rises (it meets a plane parallel to the
//     ground 10 km above the camera); its elevation above the ground plane's horizon puts it in
//     the horizon band (<= RS_SYNTH_ENV_HORIZON_DEG) or the zenith band. Buildings and trees
//     above the horizon count as "sky": they are what a vehicle reflects there.
// Each colour is the plain per-channel mean of its pixels' linear values (a reflection averages
// what it sees; no robust trimming). Rays meeting the ground beyond 60 m (the far view) are
// neither. Exact: it is a mean over a mask (tests/synth/backdrop/test_env_from_image.py: numpy's mean
// over the same rule within 1e-6).
// in: linear_rgb (H, W, >= 3) linear light at the camera's size; cam; site (its ground plane);
//     lanes (only as the cache's key: pass the lanes given to rs_synth_light_from_image, or
//     lanes with N = 0); step_px >= 1
// Returns RS_ERR_INVALID (size), RS_ERR_NOMEM. A class with no pixel in view has N = 0.
rs_status rs_synth_env_from_image( // out
    rs_synth_env_estimate *out,
    // in
    const rs_image *linear_rgb, const rs_camera *cam, const rs_site *site, const rs_lanes *lanes, int step_px,
    rs_err *err);

// The environment colours of a scene matched to a background: start from
// rs_synth_env_default (clear, or overcast) times light_rgb_scale per channel (the lights'
// match, rs_synth_light_match; NULL or all 0: 1) -- the estimated sky, when the camera does not
// see it; then each of ground, horizon and zenith that the image shows with at least
// RS_SYNTH_ENV_MIN_PX pixels replaces it with the image's mean; a zenith the image does not
// show (a telephoto sees a few degrees above the horizon, where the zenith band begins at
// RS_SYNTH_ENV_HORIZON_DEG) takes the sky_rgb of its brightest pixels above the horizon when
// there are RS_SYNTH_ENV_MIN_PX of them: the real sky's colour, not the default clear blue
// (the Aalborg frame, 0 .. 2.4 degrees above its horizon, showed roofs and windows a saturated
// blue that none of its sky has). env may be NULL (the scaled
// default alone). out: zenith_rgb, horizon_rgb, ground_rgb (3,) each.
void rs_synth_env_match(double zenith_rgb[3], double horizon_rgb[3], double ground_rgb[3],
                        // in
                        const rs_synth_env_estimate *env, const double light_rgb_scale[3], bool overcast);

// ---- the environment map a background shows (issue 40: what the vehicles reflect) ----

// The map's file in a render's work folder (written by synth/povray/rs_synth_render.h, read by
// the colour pass's environment sphere: docs/povray.md), and its default width (height half).
#define RS_SYNTH_ENV_MAP_FILE  "rs_env.png"
#define RS_SYNTH_ENV_MAP_WIDTH 512

// The direction (unit, site ENU) of pixel (col, row) of an environment map `width` wide and
// width / 2 high: POV-Ray's spherical map (map_type 1) in its world <e, u, n>, the image's top
// row at the zenith, column u = (col + 0.5) / width at azimuth 2 pi u counted from east towards
// north (elevation (0.5 - (row + 0.5) / height) pi). out: d_enu (3,)
void rs_synth_env_map_direction(double d_enu[3], int col, int row, int width);

// The environment a background shows as a map of every direction (the sphere the vehicles
// reflect, in place of rs_synth_env_match's three colours):
//   - a direction above the ground plane's horizon that the camera sees (a point 10 km along it
//     from the camera projects visibly, rs_camera_project_visible) is the photograph's colour
//     there, the photograph first shrunk (cv::resize INTER_AREA) to about one pixel per map
//     pixel (a map pixel is the mean of its footprint) and sampled bilinearly (cv::remap);
//   - the hemisphere behind the camera is the view mirrored: a direction is reflected in the
//     vertical plane across the camera's forward direction along the ground (elevation kept) and
//     takes the photograph's colour there when the camera sees that (a vehicle facing the camera
//     reflects what is behind the camera, which no camera sees: the scene in front is the
//     likeliest stand-in, e.g. buildings and sky of the same street);
//   - directions neither sees: horizon_rgb up to 10 deg above the horizon, zenith_rgb above
//     30 deg, linearly between; ground_rgb below the horizon (the scene's ground plane hides that
//     half from the vehicles anyway: it has the photograph's ground colour, rs_synth_scene.h);
//   - both photo samples fade out over a border 6 % of the image's shorter side wide (smooth
//     step), so the view's edge is no seam.
// Values in the photograph's linear units (the scene's, rs_synth_env_estimate). The rules are
// checked end to end by tests/synth/povray/test_render_env.py (the vehicles' reflections follow
// the sky's colours and where they are; a change below the horizon beyond 60 m changes
// nothing); POV-Ray's spherical mapping was checked against rs_synth_env_map_direction by
// rendering such a map seen from its centre (docs/povray.md). Cost: docs/benchmarks.md, issue 40.
// out: map (width / 2, width, 3) allocated
// in: linear_rgb (H, W, >= 3) at the camera's size; cam; ground_normal_enu (3,); the fill
//     colours (3,) each (rs_synth_env_match's); width even, >= 8 (RS_SYNTH_ENV_MAP_WIDTH)
// Returns RS_ERR_INVALID (sizes, no normal), RS_ERR_NOMEM, RS_ERR_EXTERNAL (OpenCV).
rs_status rs_synth_env_map( // out
    rs_image *map,
    // in
    const rs_image *linear_rgb, const rs_camera *cam, const double ground_normal_enu[3], const double zenith_rgb[3],
    const double horizon_rgb[3], const double ground_rgb[3], int width, rs_err *err);

// ---- the sun's direction from shadows (a background without a time) ----

// The sun's direction that best explains the shadows of the site's poles (landmarks with a
// height: lamp and signal posts, docs/site-format.md) on the ground of a background image.
// Method: a pole of height h casts on level ground a shadow from its base, away from the sun
// (compass direction azimuth + 180), h / tan(elevation) long. For each pole and each azimuth
// (1 degree steps) the darkness along that direction, D(t) = 1 - lum(t) / lum_side(t), is read
// every 0.1 m out to 25 m (lum: linear luminance 0.2126 R + 0.7152 G + 0.0722 B, bilinear, at
// the point's projection through cam; lum_side: at +-0.6 m across; points whose pixel lies
// within max(4 px, 0.3 m at the base) of the pole's own image are skipped). A candidate scores
// the fraction of shadow-like samples (D >= 0.25, with lum_side the LESSER side: a road /
// sidewalk edge is no shadow) over the predicted shadow (0.5 m .. length) minus the fraction
// over the 1.5 m beyond its tip (so the length, hence the elevation, is where the darkness
// ends), averaged over the poles whose shadow is in view (at least two when two are seen); the
// best of the 1-degree grid (elevations 1..85) wins.
// Flat ground is assumed near each pole (the site's ground plane gives the height).
// Shadows shorter than 2.5 m are not read; a best score under 0.55 is no sun shadow.
// Accuracy (tests/synth/backdrop/test_light_estimate.py: digital-twin renders of the demo site with
// four 6..8 m poles, cam1 at 720x405): within 0.5 degree in azimuth and 1.4 in elevation at
// 2024-06-21 08:00, 12:00, 15:00 UTC (elevations 44, 64, 40; tested to 2 degrees), within 1
// degree at elevations 29 and 26; refused (DEGENERATE) when the shadows leave the view
// (elevation 20 there). Scores: sun 0.58..0.89, the overcast twin 0.47 -- a thin margin.
typedef struct {
    double azimuth_deg, elevation_deg; // the best candidate
    double contrast;                   // its score: the shadow-like fraction along the predicted
                                       //   shadow minus beyond it, [-1, 1] (0.58..0.89 in sun)
    int Npoles;                        // poles whose shadow region was in view
} rs_synth_sun_estimate;

// in: linear_rgb (H, W, >= 3) linear light at the camera's size; cam; site (poles, ground plane)
// Returns RS_ERR_NOT_FOUND when the site has no pole or none's shadow region is in view,
// RS_ERR_DEGENERATE when the best contrast is below 0.15 (no sun shadow: overcast, night),
// RS_ERR_INVALID (size), RS_ERR_NOMEM. *out is filled in every case but NOMEM/INVALID (the best
// candidate found).
rs_status rs_synth_sun_from_shadows( // out
    rs_synth_sun_estimate *out,
    // in
    const rs_image *linear_rgb, const rs_camera *cam, const rs_site *site, rs_err *err);

#ifdef __cplusplus
}
#endif

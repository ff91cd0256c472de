// rs_synth_condition.h -- the condition a background shows (issue 40): time of day (day, dusk,
// night) x road surface (dry, wet, snow), from its tags or estimated from the image, and the
// ground terms the vehicles add to a background in that condition: the road lit by their
// headlights (night, dusk) and their mirror image in a wet road (docs/conditions.md).
//
// What each condition does to the scene (lights on, street lights, snow on the vehicles) is
// written by synth/povray/rs_synth_scene.h (rs_synth_scene_apply_condition); the passes the
// ground terms need are rendered by synth/povray/rs_synth_render.h (headlight irradiance,
// mirror pass).
#pragma once
#include <stdbool.h>
#include <stdint.h>

#include "core/rs_image.h"
#include "core/rs_status.h"
#include "geo/rs_site.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum { RS_SYNTH_TOD_DAY = 0, RS_SYNTH_TOD_DUSK, RS_SYNTH_TOD_NIGHT } rs_synth_time_of_day;
typedef enum { RS_SYNTH_SURFACE_DRY = 0, RS_SYNTH_SURFACE_WET, RS_SYNTH_SURFACE_SNOW } rs_synth_surface;

// The sun's elevation bounds of dusk (civil twilight and the low sun above it), degrees: below
// RS_SYNTH_DUSK_LOW_DEG is night, above RS_SYNTH_DUSK_HIGH_DEG day.
#define RS_SYNTH_DUSK_LOW_DEG  -6.0
#define RS_SYNTH_DUSK_HIGH_DEG 6.0

typedef struct {
    rs_synth_time_of_day time_of_day;
    rs_synth_surface surface;
    bool overcast;  // no sun (cloudy, rain, snow, night, dusk; or estimated without a sun)
    bool estimated; // from the image (rs_synth_condition_estimate), not from tags
    // the image's figures the estimate used (0 when from tags): linear luminance
    // (0.2126 R + 0.7152 G + 0.0722 B)
    double ground_lum; // median over the lower 40 % of the rows (the road, mostly)
    double sky_lum;    // median over the upper 15 % of the rows
    double ground_sat; // median of (max - min) / max over the lower 40 % (0 grey .. 1 pure colour)
} rs_synth_condition;

// "day", "dusk", "night" / "dry", "wet", "snow" (static strings).
const char *rs_synth_condition_time_name(rs_synth_time_of_day t);
const char *rs_synth_condition_surface_name(rs_synth_surface s);
// The condition's label "<time>-<surface>" ("night-wet"): what `roadside synth` reports and
// `dataset stats` counts. out: buf (at least 16 bytes)
void rs_synth_condition_label(char *buf, int size, const rs_synth_condition *c);

// Parses a label "<time>-<surface>" (rs_synth_condition_label's form, e.g. "night-wet"; time
// day, dusk or night; surface dry, wet or snow) into *c (overcast unless day-dry).
// Returns RS_ERR_USAGE naming the label when it is neither.
rs_status rs_synth_condition_parse(rs_synth_condition *c, const char *label, rs_err *err);

// The condition from a background's tags (docs/backgrounds.md): `conditions` sunny / cloudy
// (day, dry), rain (wet), snow (snow), night (night), dusk (dusk); a free tag `surface` = dry,
// wet or snow overrides the surface; `time` (ISO 8601) gives the sun's elevation at (lat, lon)
// (rs_synth_sun_position): below RS_SYNTH_DUSK_LOW_DEG night, up to RS_SYNTH_DUSK_HIGH_DEG dusk
// (a `conditions` night or dusk tag wins over the time). overcast: every conditions tag but
// sunny, and a sun below 0.
// out: *c; *known false when neither conditions nor time nor surface is tagged (then estimate)
// in: bg (the site's record); lat_deg, lon_deg: the site's origin
// Returns RS_ERR_PARSE (naming the tag) for a time that does not parse or a surface value
// that is not dry, wet or snow.
rs_status rs_synth_condition_from_tags( // out
    rs_synth_condition *c, bool *known,
    // in
    const rs_site_background *bg, double lat_deg, double lon_deg, rs_err *err);

// The condition estimated from the image alone (an untagged background). A small classifier
// on three figures (rs_synth_condition's ground_lum, sky_lum, ground_sat):
//   night  when ground_lum < 0.012 and sky_lum < 0.05 (a street-lit road under a black sky);
//   dusk   when not night and ground_lum < 0.035 (a dim road: sun below the horizon);
//   snow   when ground_lum > 0.25 and ground_sat < 0.10 (a bright, unsaturated ground);
//   else day, dry. Wet is never estimated (a wet road's sheen depends on the view and the sky,
//   and the twin's rain reads like a darker cloudy day): tag it (`conditions rain` or
//   `surface wet`).
// Accuracy (tests/synth/backdrop/test_condition.py, digital-twin renders of the demo site's cam1):
// 6 of 6 correct on sunny, cloudy, snow, night, a 2-degree dusk sun and rain-as-dry.
// in: linear_rgb (H, W, >= 3) linear light
// Returns RS_ERR_INVALID for an empty or non-RGB image, RS_ERR_NOMEM.
rs_status rs_synth_condition_estimate( // out
    rs_synth_condition *c,
    // in
    const rs_image *linear_rgb, rs_err *err);

// ---- the ground terms (composited over the background in linear light) ----

// The road lit by the vehicles' headlights: on every background pixel (ids == 0; ids may be
// NULL: every pixel) adds irradiance[i] x road_albedo_rgb to the linear background (an
// additive term: the background already shows the road under its own light).
// in,out: bg_lin (H, W, 3) linear; in: irradiance (H, W) the headlights' irradiance on the
// ground (rs_synth_render_result.headlight_irradiance, the scene's units), ids (H, W) or NULL,
// road_albedo_rgb (3,): RS_SYNTH_ROAD_ALBEDO, or the background's own road colour / its light
void rs_synth_condition_add_headlights(rs_image *bg_lin,
                                       // in
                                       const float *irradiance, const uint16_t *ids, const double road_albedo_rgb[3]);

// A wet road mirroring the vehicles: the mirror pass (rs_synth_render_result.mirror, linear,
// premultiplied: rgb = R a L_vehicle, alpha = R a, R Fresnel's reflectance of water at the
// pixel's angle of incidence, a the mirrored vehicle's coverage) replaces the reflection of the
// sky the background shows there: on background pixels (ids == 0; may be NULL)
//   out = max(0, bg - alpha sky_rgb) + rgb
// sky_rgb: the radiance the wet road mirrors where no vehicle is (the background's sky, e.g.
// its environment's horizon colour); NULL: bg itself (out = (1 - alpha) bg + rgb).
// in,out: bg_lin (H, W, 3); in: mirror (H, W, 4); ids or NULL; sky_rgb (3,) or NULL
void rs_synth_condition_add_wet(rs_image *bg_lin,
                                // in
                                const rs_image *mirror, const uint16_t *ids, const double sky_rgb[3]);

// Fresnel's reflectance of unpolarised light at a smooth air-water surface (ior 1.33) for the
// cosine of the angle of incidence cos_i in [0, 1]: 0.020 head-on (cos_i = 1), 1 at grazing
// (cos_i = 0). Exact (Fresnel's equations, the mean of s and p).
double rs_synth_fresnel_water(double cos_i);

#ifdef __cplusplus
}
#endif

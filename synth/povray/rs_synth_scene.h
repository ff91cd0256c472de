// rs_synth_scene.h -- POV-Ray scenes of vehicles seen by a calibrated camera: the scene writer
// (`roadside scene`) and its lights matched to a background.
//
// A scene is self-contained: camera (rs_synth_camera.h), a sun (a parallel light from azimuth and
// elevation) and sky light, the site's ground plane n . p_enu = offset, the vehicles and optional
// pins, all in POV-Ray's world <e, u, n>. No #include, no file reads, no strings from input files
// except as sanitised comments (only [A-Za-z0-9 _.:-] kept, everything else becomes '_'), so an
// input can never inject a POV-Ray directive.
//
// Vehicles: each procedural vehicle and each distinct user model is declared once by
// rs_synth_fleet_write_declare (synth/fleet/rs_synth_fleet.h, POV-Ray axes of a vehicle at the ENU
// origin facing north) and placed with rs_synth_fleet_write_placement (rotate by yaw about the
// up axis, translate to the footprint centre on the ground plane).
//
// Passes: the colour pass (lit, textured) and the ID pass (no lights, every vehicle a flat
// emissive colour encoding its index: value k+1 = R + 256 G in 8-bit units, written by povray with
// File_Gamma 1 and no antialiasing, so that the values are exact).
#pragma once
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "core/rs_status.h"
#include "geo/rs_site.h"
#include "synth/backdrop/rs_synth_condition.h"
#include "synth/backdrop/rs_synth_light.h"
#include "synth/fleet/rs_synth_prepare.h"
#include "synth/povray/rs_synth_camera.h"

#ifdef __cplusplus
extern "C" {
#endif

// ---- the scene ----

// The light model (the sun, RS_SYNTH_SKY_LIGHTS sky lights, the environment) is
// synth/backdrop/rs_synth_light.h's; vehicles ready for a scene are synth/fleet/rs_synth_prepare.h's.

// RS_SYNTH_PASS_SHADOW: what differential rendering needs, as a single pass: the ground grey
// (pigment 0.25 so that nothing saturates, diffuse 1, no ambient), the vehicles casting shadows
// and seen as flat green marks (emission rgb <0, 1, 0>: no light spent on the ground they hide),
// lit by the lights of rs_synth_scene_shadow_lights (the sun unless overcast or below the
// horizon, and a sky of parallel lights that cast shadows too). A pixel's value divided by
// rs_synth_scene_shadow_unlit() is the fraction of the ground's light reaching that pixel:
// 1 in the open, sky/(sun+sky) in a sun shadow, less under and beside a vehicle (the soft
// sky-light shadow). The ground alone needs no pass: lit by parallel lights, it is uniform.
typedef enum { RS_SYNTH_PASS_COLOUR = 0, RS_SYNTH_PASS_ID = 1, RS_SYNTH_PASS_SHADOW = 2 } rs_synth_pass;

// Each headlight's intensity at night, scene units (irradiance at 1 m on a surface facing it):
// set so that the road 10 m ahead of a car (the beam at 1.2 deg grazing) gets about twice the
// irradiance of the digital twin's night sky (0.03): the pool of light a dipped beam throws in
// a street-lit scene, reaching about 50 m before it falls under 2 % of that sky.
#define RS_SYNTH_HEADLIGHT_INTENSITY 90.0
// The beam: full within RS_SYNTH_BEAM_FULL_DEG of its axis, smoothly (cosine) to 0 at
// RS_SYNTH_BEAM_EDGE_DEG (POV-Ray's spotlight radius / falloff); the axis aims at the ground
// RS_SYNTH_BEAM_AIM_M ahead of the lamp.
#define RS_SYNTH_BEAM_FULL_DEG       15.0
#define RS_SYNTH_BEAM_EDGE_DEG       30.0
#define RS_SYNTH_BEAM_AIM_M          30.0
// The street lights a scene may hold (rs_synth_scene_options.street_lights_enu_m).
#define RS_SYNTH_STREET_LIGHTS_MAX   8

typedef struct {
    rs_synth_pass pass;
    bool ground_visible;    // colour pass: draw the ground (false: the ground is left out,
                            // for compositing over a photograph)
    double sun_azimuth_deg; // sun direction (colour pass)
    double sun_elevation_deg;
    // Lighting matched to a background (rs_synth_light_match, synth/backdrop/rs_synth_light.h): in the
    // colour pass every light (sun and sky) times light_rgb_scale per channel; all 0 (the
    // default): 1. The shadow pass is a ratio and stays grey.
    double light_rgb_scale[3];
    const double *pins_enu_m; // (Npins,3) pin centres, may be NULL
    int Npins;
    double pin_radius_px;   // pins' radius in image pixels at their distance (default 3)
    const uint8_t *include; // (Nvehicles,) 0 = leave vehicle out (culled), may be NULL = all
    bool boxes;             // draw vehicles as plain boxes (no fleet meshes)
    bool overcast;          // no sun: the sky alone, RS_SYNTH_SKY_OVERCAST (colour and
                            // shadow passes)
    // The environment the vehicles reflect (colour pass): a sphere round the scene, seen only
    // in reflections (no_image), glowing from env_ground_rgb below the horizon through
    // env_horizon_rgb to env_zenith_rgb overhead, linear RGB in the units of the lights (a white
    // surface under a sun at the zenith is 1). env_given false: rs_synth_env_default's.
    // With env_given and ground_visible false (compositing over a photograph), the ground plane
    // the vehicles reflect also takes env_ground_rgb as its lit radiance (its pigment is
    // env_ground_rgb / (0.8 x the lights' irradiance on it), so shadows still darken it). From a
    // background: rs_synth_env_from_image and rs_synth_env_match (synth/backdrop/rs_synth_light.h).
    bool env_given;
    double env_zenith_rgb[3], env_horizon_rgb[3], env_ground_rgb[3];
    bool env_off; // no environment at all (reflections show the black background)
    // issue 40, the background's condition (rs_synth_scene_apply_condition; docs/conditions.md).
    // Colour pass only; all 0 (the default): daylight, clean, dry.
    bool lights_on;             // head- and tail lights glowing (rs_synth_look.lights_on) and a
                                // spot light at each headlight (rs_synth_scene_headlights)
    double headlight_intensity; // each headlight: irradiance on a surface facing it at 1 m
                                // (scene units; fades as 1/d^2); 0: RS_SYNTH_HEADLIGHT_INTENSITY
    double snow;                // 0..1: snow on the vehicles' upward-facing paint
    double dirt_add;            // 0..1: added to every vehicle's dirt (slush on the lower body)
    double street_lights_enu_m[RS_SYNTH_STREET_LIGHTS_MAX][3]; // lamps: shadowless point lights
    int Nstreet_lights;                                        //   fading as 1/d^2
    double street_light_rgb[3]; // each lamp's irradiance at 1 m per channel (scene units)
    // The environment as a map of the background (issue 40; rs_synth_env_map,
    // synth/backdrop/rs_synth_light.h): the sphere shows the 16-bit linear PNG
    // RS_SYNTH_ENV_MAP_FILE of the folder povray runs in (written there by rs_synth_render, from
    // rs_synth_render_options.env_map), its values times env_map_scale, in place of the three
    // colours above; env_ground_rgb still colours the ground plane the vehicles reflect.
    bool env_map;
    double env_map_scale;
} rs_synth_scene_options;

// A vehicle's two headlights: its box's front face (x = length / 2 + 0.02 m), 0.25 m inside
// each side (a two-wheeler: one lamp on the centre line, given twice), at 0.4 x its height
// (at most 0.75 m); the beam's axis from each lamp to the ground RS_SYNTH_BEAM_AIM_M ahead.
// out: p_enu_m (2,3), axis_enu (3,) unit; in: v, up_m (the ground's height under it)
void rs_synth_scene_headlights(double p_enu_m[2][3], double axis_enu[3],
                               // in
                               const rs_synth_vehicle *v, double up_m);

// The beam's relative intensity at angle_deg off its axis: 1 within RS_SYNTH_BEAM_FULL_DEG,
// (1 + cos(pi t)) / 2 beyond (t from 0 there to 1 at RS_SYNTH_BEAM_EDGE_DEG), 0 outside.
double rs_synth_scene_beam(double angle_deg);

// Matches a scene's lights and environment to its background, from the estimates of synth/backdrop/rs_synth_light.h (implemented in rs_synth_scene_match.c): the
// lights' per-channel factor (rs_synth_light_match, with a sun unless scene->overcast, at
// scene->sun_elevation_deg: set the sun first) and the environment the vehicles reflect
// (rs_synth_env_match; env NULL: the estimated sky alone). Writes scene->light_rgb_scale,
// env_given and env_zenith/horizon/ground_rgb; nothing else.
void rs_synth_scene_match_background(rs_synth_scene_options *scene,
                                     // in
                                     const rs_synth_light_estimate *light, const rs_synth_env_estimate *env);

// The environment map of a background for a scene matched to it (issue 40): rs_synth_env_map
// at RS_SYNTH_ENV_MAP_WIDTH, filled with the scene's env_*_rgb (env_given; else
// rs_synth_env_default's). out: *map allocated. in: scene (matched first); linear_rgb, cam and
// site as rs_synth_env_map's. Errors: rs_synth_env_map's.
rs_status rs_synth_scene_env_map(rs_image *map,
                                 // in
                                 const rs_synth_scene_options *scene, const rs_image *linear_rgb, const rs_camera *cam,
                                 const rs_site *site, rs_err *err);

// The same from a background file (`roadside render --background`; `roadside synth` keeps its
// decoded backgrounds and calls the above): the image (8-bit sRGB, the camera's size) decoded
// to linear light, the light estimated (rs_synth_light_from_background, every 4th pixel: the road
// in the lanes, else the ground plane in view, else the lower image; the road assumed dry; its
// source in light->source) and its environment (rs_synth_env_from_image), then matched; with
// env_map, also the environment map (rs_synth_scene_env_map).
// out: light (the estimate; may be NULL); env_map (may be NULL: not computed); scene as above.
// Returns RS_ERR_INVALID (size, not RGB), RS_ERR_IO, RS_ERR_NOMEM, RS_ERR_EXTERNAL.
rs_status rs_synth_scene_match_background_file(rs_synth_scene_options *scene, rs_synth_light_estimate *light,
                                               rs_image *env_map,
                                               // in
                                               const char *path, const rs_camera *cam, const rs_site *site,
                                               const rs_lanes *lanes, rs_err *err);

// What a condition (synth/backdrop/rs_synth_condition.h) does to a scene (docs/conditions.md):
//   night: lights_on, headlights RS_SYNTH_HEADLIGHT_INTENSITY, street lights (below), and when
//          the lights are not matched to the background (light_rgb_scale all 0) the sky dimmed
//          to 0.03 of an overcast day's;
//   dusk:  lights_on, the sky dimmed to 0.15 and warm (1, 0.85, 0.7) when not matched;
//   snow:  snow 0.8 and dirt_add 0.35 (slush); wet: dirt_add 0.15;
//   overcast: as the condition says (the sun only by day, or dusk above the horizon).
// Street lights at night: the site's poles (landmarks with a pole height of 4 m or more: lamp
// posts) nearest to the vehicles' centroid, at most RS_SYNTH_STREET_LIGHTS_MAX, each at its top;
// a site without poles gets one lamp 8 m up, 4 m to the right of each of the first four
// vehicles. LED white (1, 0.95, 0.85) x 1.0 at 1 m. An unmatched environment is set to the
// dimmed default (env_given). in,out: scene (its sun set first); in: site (poles), vehicles
void rs_synth_scene_apply_condition(rs_synth_scene_options *scene,
                                    // in
                                    const rs_synth_condition *cond, const rs_site *site,
                                    const rs_synth_prepared *vehicles);

// The lights of the colour and shadow passes: the sun (irradiance 1, when its elevation is
// above 0 and the sky is not overcast) first, then the RS_SYNTH_SKY_LIGHTS sky lights scaled
// to RS_SYNTH_SKY_CLEAR (or RS_SYNTH_SKY_OVERCAST) on horizontal ground. out: lights
// (RS_SYNTH_SKY_LIGHTS + 1,); returns how many were written.
int rs_synth_scene_lights(rs_synth_light *lights, const rs_synth_scene_options *opt);

// What the shadow pass shows on open ground, nothing in the way: sum of irradiance *
// max(0, n . dir) over the lights, n the unit ground normal (ENU, any length given).
double rs_synth_scene_shadow_unlit(const rs_synth_light *lights, int Nlights, const double ground_normal_enu[3]);

// Defaults: colour pass, ground visible, sun at azimuth 135, elevation 45, no pins, radius 3 px.
void rs_synth_scene_options_default(rs_synth_scene_options *opt);

// Several passes in one file, for one povray process rendering them as the frames of an
// animation (+KFI1 +KFF<Nframes>; rs_synth_scene_write_ini_frames): `#switch (frame_number)`,
// frame k + 1 being passes[k]. Each frame re-parses the file, but povray starts once (its
// start-up and shut-down cost about 0.35 s of waiting, measured in docs/povray.md).
rs_status rs_synth_scene_write_frames(FILE *f,
                                      // in
                                      const rs_synth_povcam *cam, const double fxy[2],
                                      const double ground_normal_enu[3], double ground_offset_m,
                                      const rs_synth_prepared *vehicles, const rs_synth_scene_options *passes,
                                      int Npasses, rs_err *err);

// Writes the .pov text of a scene to f.
// in: cam: the POV-Ray camera (the canvas camera for a distorted lens); fxy: its focal lengths
//     (for sizing pins); ground plane; the prepared vehicles
// Returns RS_ERR_IO on a stream error.
rs_status rs_synth_scene_write(FILE *f,
                               // in
                               const rs_synth_povcam *cam, const double fxy[2], const double ground_normal_enu[3],
                               double ground_offset_m, const rs_synth_prepared *vehicles,
                               const rs_synth_scene_options *opt, rs_err *err);

// Writes the texture images of the prepared vehicles' user models into dir (the folder povray
// runs in) under the generated names their scene text refers to ("rs_tex_RS_PART_<mesh>_<k>.png",
// rs_synth_fleet_write_textures): the only way an image reaches povray (docs/povray.md,
// "Confinement"). Returns RS_ERR_IO / RS_ERR_NOMEM.
rs_status rs_synth_scene_write_textures(const char *dir, const rs_synth_prepared *vehicles, rs_err *err);

// Removes what rs_synth_scene_write_textures wrote (missing files ignored).
void rs_synth_scene_remove_textures(const char *dir, const rs_synth_prepared *vehicles);

// Writes the .ini matching a scene, atomically: Input_File_Name (the .pov's base name, same
// folder; it may only use [A-Za-z0-9_.-]), Output_File_Name (the same with .png), Width/Height,
// File_Gamma 1 (linear output), 16-bit RGBA for the colour pass, 8-bit RGB for the ID pass.
// antialias: 0 none; n >= 2: n x n non-adaptive supersampling without jitter (+A0 +AM1 +Rn,
// colour pass only).
rs_status rs_synth_scene_write_ini(const char *ini_path, const char *pov_path, const rs_synth_povcam *cam,
                                   rs_synth_pass pass, int antialias, rs_err *err);

// The .ini of a file of Nframes passes (rs_synth_scene_write_frames): 16-bit RGBA with
// File_Gamma 1 for every frame (ID values stay exact: 257 x the 8-bit value), frames 1..Nframes
// written as <name>1.png, <name>2.png, ... (Nframes <= 9). antialias as above applies to
// every frame: give it only to a colour pass alone.
rs_status rs_synth_scene_write_ini_frames(const char *ini_path, const char *pov_path, const rs_synth_povcam *cam,
                                          int Nframes, int antialias, rs_err *err);

#ifdef __cplusplus
}
#endif

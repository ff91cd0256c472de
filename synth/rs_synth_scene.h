// rs_synth_scene.h -- POV-Ray scenes of vehicles seen by a calibrated camera: the vehicles file,
// the sun, and the scene writer (`roadside scene`).
//
// A scene is self-contained: camera (rs_synth_camera.h), a sun (a parallel light from azimuth and
// elevation) and sky light, the site's ground plane n . p_enu = offset, the vehicles and optional
// pins, all in POV-Ray's world <e, u, n>. No #include, no file reads, no strings from input files
// except as sanitised comments (only [A-Za-z0-9 _.:-] kept, everything else becomes '_'), so an
// input can never inject a POV-Ray directive.
//
// Vehicles: each procedural vehicle and each distinct user model is declared once by
// rs_synth_fleet_write_declare (synth/rs_synth_fleet.h, POV-Ray axes of a vehicle at the ENU
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
#include "synth/rs_synth.h"
#include "synth/rs_synth_camera.h"
#include "synth/rs_synth_fleet.h"
#include "synth/rs_synth_sun.h"

#ifdef __cplusplus
extern "C" {
#endif

// ---- the vehicles file ----

// A vehicles file read into memory. `v[i]`'s strings point into this list's storage.
typedef struct {
    rs_synth_vehicle *v; // (N,) owned
    int N;
    char **strings; // owned: every string v[] points to
    int Nstrings;
    rs_synth_obj_spec *obj; // (N,) owned: user models' specs (obj[i].path == v[i].model_path)
} rs_synth_vehicle_list;

// Reads a vehicles file: a JSON list of objects
//   {"class": "sedan" (rs_synth_class_name) | "model": "path.obj" (with "scale": metres per
//    unit, default 1, "forward": "+x".."-z", default "+x", "up", default "+z"),
//    "e": m, "n": m, "yaw_deg": deg,
//    "length": m, "width": m, "height": m,   (optional, > 0; default: drawn from the class)
//    "colour": [r, g, b] linear in [0,1] or "#rrggbb" sRGB (optional; default: drawn),
//    "variant": integer >= 0 (optional, default: the index), "id": string (optional)}
// yaw_deg is the compass heading of the vehicle's forward axis, clockwise from north.
// A relative "model" path is taken relative to the vehicles file's folder.
// Errors name the file, the list index and the field: "FILE: [3].yaw_deg: not a number".
rs_status rs_synth_vehicles_read( // out
    rs_synth_vehicle_list *list,
    // in
    const char *path, rs_err *err);
void rs_synth_vehicle_list_free(rs_synth_vehicle_list *list); // NULL-safe

// ---- the vehicle box ----

// The 8 corners of vehicle v's bounding box in ENU, metres, on the ground plane
// n . p = offset: corner k has x_v = +-L/2 (bit 0: +), y_v = +-W/2 (bit 1: +), z_v = 0 or H
// (bit 2: H). Requires v's length/width/height > 0 (resolve drawn dimensions first).
void rs_synth_vehicle_corners_enu( // out
    double corners_enu_m[8][3],
    // in
    const rs_synth_vehicle *v, const double ground_normal_enu[3], double ground_offset_m);

// Up coordinate of the ground plane n . p = offset at (e, n). n[2] must be non-zero.
double rs_synth_ground_up_m(const double ground_normal_enu[3], double ground_offset_m, double e_m, double n_m);

// ---- the sun ----

// The sun from a place and a time: rs_synth_sun_position (synth/rs_synth_sun.h).

// Parses an ISO 8601 time "YYYY-MM-DDTHH:MM[:SS[.fff]]" followed by "Z" or "+HH:MM"/"-HH:MM"
// (a zone is required). out: seconds since 1970 UTC. Returns RS_ERR_PARSE naming `field`.
rs_status rs_synth_parse_iso8601(double *unix_time_s, const char *s, const char *field, rs_err *err);

// ---- the scene ----

// RS_SYNTH_PASS_SHADOW: what differential rendering needs, as a single pass: the ground grey
// (pigment 0.25 so that nothing saturates, diffuse 1, no ambient), the vehicles casting shadows
// and seen as flat green marks (emission rgb <0, 1, 0>: no light spent on the ground they hide),
// lit by the lights of rs_synth_scene_shadow_lights (the sun unless overcast or below the
// horizon, and a sky of parallel lights that cast shadows too). A pixel's value divided by
// rs_synth_scene_shadow_unlit() is the fraction of the ground's light reaching that pixel:
// 1 in the open, sky/(sun+sky) in a sun shadow, less under and beside a vehicle (the soft
// sky-light shadow). The ground alone needs no pass: lit by parallel lights, it is uniform.
typedef enum { RS_SYNTH_PASS_COLOUR = 0, RS_SYNTH_PASS_ID = 1, RS_SYNTH_PASS_SHADOW = 2 } rs_synth_pass;

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

typedef struct {
    rs_synth_pass pass;
    bool ground_visible;    // colour pass: draw the ground (false: the ground is left out,
                            // for compositing over a photograph)
    double sun_azimuth_deg; // sun direction (colour pass)
    double sun_elevation_deg;
    // Lighting matched to a background (rs_synth_light_match, synth/rs_synth_sun.h): in the
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
    // surface under a sun at the zenith is 1). env_given false: rs_synth_scene_env_default's.
    // With env_given and ground_visible false (compositing over a photograph), the ground plane
    // the vehicles reflect also takes env_ground_rgb as its lit radiance (its pigment is
    // env_ground_rgb / (0.8 x the lights' irradiance on it), so shadows still darken it). From a
    // background: rs_synth_env_from_image and rs_synth_env_match (synth/rs_synth_sun.h).
    bool env_given;
    double env_zenith_rgb[3], env_horizon_rgb[3], env_ground_rgb[3];
    bool env_off; // no environment at all (reflections show the black background)
} rs_synth_scene_options;

// Matches a scene's lights and environment to its background, from the estimates of synth/rs_synth_sun.h (implemented in rs_synth_sun.c): the
// lights' per-channel factor (rs_synth_light_match, with a sun unless scene->overcast, at
// scene->sun_elevation_deg: set the sun first) and the environment the vehicles reflect
// (rs_synth_env_match; env NULL: the estimated sky alone). Writes scene->light_rgb_scale,
// env_given and env_zenith/horizon/ground_rgb; nothing else.
void rs_synth_scene_match_background(rs_synth_scene_options *scene,
                                     // in
                                     const rs_synth_light_estimate *light, const rs_synth_env_estimate *env);

// The same from a background file (`roadside render --background`; `roadside synth` keeps its
// decoded backgrounds and calls the above): the image (8-bit sRGB, the camera's size) decoded
// to linear light, the light estimated on its road (rs_synth_light_from_image, every 4th pixel;
// the road assumed dry) and its environment (rs_synth_env_from_image), then matched.
// out: light (the estimate; may be NULL); scene as above.
// Returns RS_ERR_DEGENERATE (scene untouched) when fewer than 50 road pixels are in view (no
// lanes, or none in view), RS_ERR_INVALID (size, not RGB), RS_ERR_IO, RS_ERR_NOMEM.
rs_status rs_synth_scene_match_background_file(rs_synth_scene_options *scene, rs_synth_light_estimate *light,
                                               // in
                                               const char *path, const rs_camera *cam, const rs_site *site,
                                               const rs_lanes *lanes, rs_err *err);

// The default environment: a clear sky (blue zenith, pale horizon) or an overcast one (grey,
// as bright as RS_SYNTH_SKY_OVERCAST), over asphalt of albedo 0.18 lit by the sun and sky.
void rs_synth_scene_env_default(double zenith_rgb[3], double horizon_rgb[3], double ground_rgb[3], bool overcast);

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

// Vehicles ready for a scene: resolved (rs_synth_fleet_resolve), meshes built; a user model is
// loaded once per distinct (path, scale, forward, up) and shared by its instances.
typedef struct {
    rs_synth_vehicle *v; // (N,) owned copies, resolved: dimensions > 0 (a user model's from its
                         // mesh bounds), paint set; strings still borrowed from the input
    int N;
    rs_synth_mesh *meshes; // (Nmeshes,) owned
    int Nmeshes;
    int *imesh; // (N,) owned: the mesh of each vehicle
} rs_synth_prepared;

// in: vehicles (N,); obj (N,) user models' specs (entries of procedural vehicles ignored), may be
//     NULL when there is no user model
// Errors are the fleet's, prefixed with "vehicle K (id ...): " (id sanitised).
rs_status rs_synth_prepare( // out
    rs_synth_prepared *out,
    // in
    const rs_synth_vehicle *vehicles, const rs_synth_obj_spec *obj, int N, rs_err *err);
void rs_synth_prepared_free(rs_synth_prepared *p); // NULL-safe; zeroes *p

// The same, with procedural vehicle i built coarse when coarse[i] (rs_synth_fleet_build_lod);
// coarse may be NULL (every vehicle in full detail).
rs_status rs_synth_prepare_lod( // out
    rs_synth_prepared *out,
    // in
    const rs_synth_vehicle *vehicles, const rs_synth_obj_spec *obj, int N, const uint8_t *coarse, rs_err *err);

// Writes the .pov text of a scene to f.
// in: cam: the POV-Ray camera (the canvas camera for a distorted lens); fxy: its focal lengths
//     (for sizing pins); ground plane; the prepared vehicles
// Returns RS_ERR_IO on a stream error.
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

rs_status rs_synth_scene_write(FILE *f,
                               // in
                               const rs_synth_povcam *cam, const double fxy[2], const double ground_normal_enu[3],
                               double ground_offset_m, const rs_synth_prepared *vehicles,
                               const rs_synth_scene_options *opt, rs_err *err);

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

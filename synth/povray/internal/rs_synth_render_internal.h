// rs_synth_render_internal.h -- the condition's passes (synth/povray/rs_synth_render_condition.c)
// that the renderer (synth/povray/rs_synth_render.c) runs beside the colour pass (issue 40,
// docs/conditions.md). Internal to synth/povray; the API is synth/povray/rs_synth_render.h.
#pragma once
#include <stdbool.h>
#include <stdint.h>

#include "core/rs_image.h"
#include "core/rs_status.h"
#include "synth/povray/rs_synth_camera.h"
#include "synth/povray/rs_synth_render.h"
#include "synth/povray/rs_synth_scene.h"

// The POV-Ray camera mirrored in the ground plane n . p_enu = offset_m: its location, right, up
// and direction reflected. Pixel (u, v) of the mirrored camera sees, beyond the ground, what the
// real camera's pixel (u, v) sees reflected in the ground (the ground itself is no_image in a
// colour pass over a background, so the rays pass it). out: *m; in: cam, g_enu (3,), offset_m
void rs_synth_povcam_mirror(rs_synth_povcam *m, const rs_synth_povcam *cam, const double g_enu[3], double offset_m);

// The canvas rectangle of a vehicle's mirror image: its box's corners reflected in the ground
// plane (rs_synth_vehicle_rect of those). false when it misses the canvas.
// out: rect (4,); in: canvas, rt_cam_enu (6,), corners_enu_m (8,3), g_enu (3,), offset_m
bool rs_synth_mirror_rect(int rect[4], const rs_synth_canvas *canvas, const double rt_cam_enu[6],
                          const double corners_enu_m[8][3], const double g_enu[3], double offset_m);

// The mirror pass (rendered at half the canvas's resolution: a reflection is soft, and the pass
// costs a second colour trace) made premultiplied, resized to the canvas (linear), weighted by
// Fresnel's reflectance of water at each canvas pixel's angle of incidence on the ground
// (rs_synth_fresnel_water; 0 where the ray does not meet the ground): rgb = R a L, alpha = R a;
// and blurred by 1 px (ripples).
// in,out: mirror (half canvas (H+1)/2, (W+1)/2, 4) straight alpha in, (canvas H, W, 4)
// premultiplied out; in: canvas (pinhole), rt_cam_enu (6,), g_enu (3,)
rs_status rs_synth_mirror_weight(rs_image *mirror, const rs_synth_canvas *canvas, const double rt_cam_enu[6],
                                 const double g_enu[3], rs_err *err);

// The headlights' irradiance on the ground plane at every canvas pixel whose ray meets it (0
// elsewhere): the sum over every included vehicle's two lamps (rs_synth_scene_headlights) of
// intensity x beam(angle off the axis) x cos(incidence) / d^2, computed at half the canvas's
// resolution and resized (linear). No shadows (a vehicle in the beam does not darken the road
// behind it).
// out: *irr (canvas H, W, 1); in: canvas (pinhole), rt_cam_enu, ground plane, vehicles,
// include (N,) or NULL, intensity (<= 0: RS_SYNTH_HEADLIGHT_INTENSITY)
rs_status rs_synth_headlight_ground(rs_image *irr, const rs_synth_canvas *canvas, const double rt_cam_enu[6],
                                    const double g_enu[3], double offset_m, const rs_synth_prepared *vehicles,
                                    const uint8_t *include, double intensity, rs_err *err);

// The condition's canvas images into the real lens (map: the canvas map, NULL when the canvas is
// the lens; linear interpolation, the mirror pass being premultiplied) and handed to out
// (out->mirror, out->headlight_irradiance); *mirror and *headlights are left empty.
// in,out: mirror (canvas H, W, 4) and headlights (canvas H, W, 1), either may be empty
rs_status rs_synth_condition_into_lens(rs_synth_render_result *out, rs_image *mirror, rs_image *headlights,
                                       const float *map, rs_err *err);

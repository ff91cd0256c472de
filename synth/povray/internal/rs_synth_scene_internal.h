// rs_synth_scene_internal.h -- what the scene writer (synth/povray/rs_synth_scene.c) tells the renderer
// (synth/povray/rs_synth_render.c) and the match (synth/povray/rs_synth_scene_match.c) about a scene. Internal to synth; the API is synth/povray/rs_synth_scene.h.
#pragma once
#include <stdbool.h>

#include "synth/povray/rs_synth_scene.h"

// Whether the ground plane can hide part of a vehicle from the camera: only when the camera is
// not above the ground (n . p > offset by more than 1e-6 m) or some vehicle that opt includes
// has a bottom corner of its box below the ground (a sloping ground under a vehicle placed
// level; 1e-9 m). A segment between two points above a plane never crosses it: otherwise the
// ID pass needs no ground (rs_synth_scene_write leaves it out), and every camera ray that meets
// a vehicle in the colour pass meets the same one in the ID pass.
bool rs_synth_scene_ground_occludes(const rs_synth_povcam *cam, const rs_synth_prepared *vehicles,
                                    const rs_synth_scene_options *opt, const double ground_normal_enu[3],
                                    double ground_offset_m);

// The environment's three colours of a scene: opt's env_*_rgb when env_given, else
// rs_synth_env_default's (clear, or overcast). out: zenith_rgb, horizon_rgb, ground_rgb (3,) each
void rs_synth_scene_env_colours(double zenith_rgb[3], double horizon_rgb[3], double ground_rgb[3],
                                const rs_synth_scene_options *opt);

// rs_synth_composite.h -- rendered vehicles over a photograph in the camera's own look: the one
// composite of `roadside render --background` and `roadside synth` (docs/appearance.md).
//
// Steps, all in the background's pixels (H, W):
//  1. the vehicle layer (linear RGBA, straight alpha) takes the look's gain and blur
//     (rs_synth_appearance_layer: sqrt(blur^2 - layer_blur^2) px on premultiplied colour);
//  2. the shadow pass's lit fraction s (differential rendering, Debevec 1998; 1 on the vehicles'
//     own pixels) is blurred by the same Gaussian (the camera's lens softens a shadow's edge as
//     it softens a vehicle's), clamped to [0, 1], and multiplies the background in linear light;
//  3. the condition's ground terms (issue 40, docs/conditions.md), on the shaded background in
//     linear light before the vehicles are laid over: a wet road's reflection of the vehicles
//     (rs_synth_condition_add_wet), then the road lit by their headlights
//     (rs_synth_condition_add_headlights) -- the one home of both formulas;
//  4. the layer over the background: a c + (1 - a) bg in linear light, sRGB-encoded;
//  5. noise to the level the camera gives each final value: the look's sigma(v) = sqrt(a + b v)
//     in stored units (rs_synth_appearance_noise_sigma) less what the pixel already holds,
//     (1 - alpha) s sigma(v_bg) carried from the background's stored value v_bg through the
//     linear-light mix (sRGB slopes, rs_color_srgb_decode_slope): white Gaussian noise of
//     sqrt(max(0, sigma(v)^2 - carried^2)) is added in stored units. So the vehicles get the
//     whole noise of their value, a shadowed background is topped up to its darker value's noise
//     (the multiplication scaled its own noise down), and open background pixels are untouched;
//  6. a JPEG round trip at the background's quality (rs_synth_appearance_jpeg; none for a PNG) of
//     the 16 x 16 blocks (the image's grid) that hold a pixel 1-5 changed; the others keep the
//     background's own compression.
// Without a look (opt->look NULL) steps 1, 5, 6 are skipped and the shadow is not blurred: the
// vehicles stay clean and sharp (`--no-appearance`).
#pragma once
#include <stdbool.h>
#include <stdint.h>

#include "core/rs_image.h"
#include "core/rs_status.h"
#include "synth/backdrop/rs_synth_appearance.h"
#include "synth/backdrop/rs_synth_condition.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    const rs_synth_appearance *look; // the camera's look (rs_synth_appearance_estimate); NULL: none
    double layer_blur_sigma_px;      // the rendered layer's own edge blur, against the background's
                                     // pixels (0 for an unantialiased render: both point-sampled)
    uint64_t seed;                   // the noise's generator (deterministic per seed)
    bool light_matched;              // the scene's lights were matched to this background
                                     // (rs_synth_scene_match_background): the layer has its light's
                                     // level and colour already, so the look's gain is not applied
                                     // (a grey-world gain on top tinted a dark car olive over the
                                     // Aalborg frame's grass: gain 1.12 1.10 0.78)
    // ---- the condition's ground terms (step 3; docs/conditions.md), each may be NULL ----
    const float *headlight_irradiance; // (H, W) the headlights' irradiance on the ground
                                       // (rs_synth_render_result.headlight_irradiance): adds the
                                       // road they light (rs_synth_condition_add_headlights)
    const double *road_albedo_rgb;     // (3,) the road's reflectance for it; NULL:
                                       // RS_SYNTH_ROAD_ALBEDO
    const rs_image *mirror;            // (H, W, 4) a wet road's mirror pass
                                       // (rs_synth_render_result.mirror): replaces the reflection
                                       // the background shows there (rs_synth_condition_add_wet)
    const uint16_t *ids;               // (H, W) the vehicles' pixels (not ground), or NULL
} rs_synth_composite_options;

// out:   *composite_srgb (H, W, 3) sRGB-encoded [0,1], allocated here (rs_image_free)
// in:    rgba_linear (H, W, 4): the colour pass, linear, straight alpha (not modified: a copy
//        takes the look); background_linear (H, W, 3) linear light; shadow (H, W) the lit
//        fraction, may be NULL; opt (may be NULL: no look, no extra terms)
// Errors: RS_ERR_INVALID (sizes or channels differ), RS_ERR_NOMEM, the shim's for blur and JPEG.
rs_status rs_synth_composite_background( // out
    rs_image *composite_srgb,
    // in
    const rs_image *rgba_linear, const rs_image *background_linear, const float *shadow,
    const rs_synth_composite_options *opt, rs_err *err);

#ifdef __cplusplus
}
#endif

// rs_synth_composite.c -- rendered vehicles over a photograph in the camera's look
// (rs_synth_composite.h, docs/appearance.md).
#include "synth/povray/rs_synth_composite.h"

#include <math.h>
#include <stdbool.h>
#include <string.h>

#include "core/rs_color.h"
#include "core/rs_rng.h"
#include "synth/backdrop/rs_synth_light.h"

static float clamp01(double v) { return (float)(v < 0 ? 0 : v > 1 ? 1 : v); }

rs_status rs_synth_composite_background(rs_image *out, const rs_image *rgba_in, const rs_image *bg,
                                        const float *shadow_in, const rs_synth_composite_options *opt, rs_err *err)
{
    memset(out, 0, sizeof(*out));
    const rs_synth_composite_options none = {0};
    if (!opt) opt = &none;
    rs_synth_appearance unit_gain;
    const rs_synth_appearance *look = opt->look;
    if (look && opt->light_matched) { // the lights carry the background's colour: no gain on top
        unit_gain = *look;
        unit_gain.gain[0] = unit_gain.gain[1] = unit_gain.gain[2] = 1;
        look = &unit_gain;
    }
    const int W = bg->width, H = bg->height;
    const rs_image *mir = opt->mirror;
    if (rgba_in->channels != 4 || bg->channels != 3 || rgba_in->width != W || rgba_in->height != H ||
        (mir && (mir->channels != 4 || mir->width != W || mir->height != H)))
        return rs_err_set(err, RS_ERR_INVALID,
                          "composite: the layer (%dx%dx%d, RGBA), the background (%dx%dx%d, RGB) and the ground "
                          "term must be of one size",
                          rgba_in->width, rgba_in->height, rgba_in->channels, W, H, bg->channels);
    const size_t N = (size_t)W * H;
    rs_image layer = {0}, sw = {0}, shb = {0}, ground = {0};
    rs_status st;
    if ((st = rs_image_alloc(&layer, W, H, 4, err)) || (st = rs_image_alloc(out, W, H, 3, err))) goto done;
    memcpy(layer.data, rgba_in->data, sizeof(float) * 4 * N);
    // 1. the layer's gain and blur
    const double s2 =
        look ? look->blur_sigma_px * look->blur_sigma_px - opt->layer_blur_sigma_px * opt->layer_blur_sigma_px : 0;
    if (look && (st = rs_synth_appearance_layer(&layer, look, opt->layer_blur_sigma_px, err))) goto done;
    // 2. the shadow, blurred like the camera's lens: a normalised convolution (Knutsson & Westin,
    // CVPR 1993) with the weight w = 1 - alpha, blur(s w) / blur(w), so that the pass's 1 under
    // the vehicles (it does not look there) does not leak a bright rim into their shadows
    const float *shadow = shadow_in;
    if (shadow && s2 > 1e-6) {
        if ((st = rs_image_alloc(&sw, W, H, 3, err))) goto done; // (s w, w, unused): one blur
        for (size_t i = 0; i < N; i++) {
            const float w = 1 - rgba_in->data[4 * i + 3];
            sw.data[3 * i] = shadow_in[i] * w;
            sw.data[3 * i + 1] = w;
        }
        if ((st = rs_synth_image_blur(&shb, &sw, sqrt(s2), err))) goto done;
        for (size_t i = 0; i < N; i++)
            shb.data[i] = shb.data[3 * i + 1] > 1e-3f ? shb.data[3 * i] / shb.data[3 * i + 1] : 1;
        shadow = shb.data;
    }
    // 3. the condition's ground terms on the shaded background (a copy)
    const bool terms = opt->headlight_irradiance || mir;
    if (terms) {
        if ((st = rs_image_alloc(&ground, W, H, 3, err))) goto done;
        for (size_t i = 0; i < N; i++) {
            const double s = shadow ? (shadow[i] < 0 ? 0 : shadow[i] > 0.9999f ? 1 : shadow[i]) : 1;
            for (int k = 0; k < 3; k++) ground.data[3 * i + k] = (float)(s * bg->data[3 * i + k]);
        }
        if (mir) rs_synth_condition_add_wet(&ground, mir, opt->ids, NULL);
        if (opt->headlight_irradiance) {
            const double albedo[3] = {RS_SYNTH_ROAD_ALBEDO, RS_SYNTH_ROAD_ALBEDO, RS_SYNTH_ROAD_ALBEDO};
            rs_synth_condition_add_headlights(&ground, opt->headlight_irradiance, opt->ids,
                                              opt->road_albedo_rgb ? opt->road_albedo_rgb : albedo);
        }
    }
    rs_rng rng;
    rs_rng_seed(&rng, opt->seed);
    int R[4] = {W, H, -1, -1}; // the pixels changed: vehicles, shadows, the condition's terms
    for (size_t i = 0; i < N; i++) {
        // (a blurred 1 may read 1 - 1e-7: open ground, as the pass says)
        const double s = shadow ? (shadow[i] < 0 ? 0 : shadow[i] > 0.9999f ? 1 : shadow[i]) : 1;
        const float *c = &layer.data[4 * i];
        const double al = c[3];
        bool changed = al > 0 || s < 1;
        for (int k = 0; k < 3 && terms && !changed; k++)
            changed = ground.data[3 * i + k] != (float)(s * bg->data[3 * i + k]);
        if (changed) {
            const int x = (int)(i % (size_t)W), y = (int)(i / (size_t)W);
            if (x < R[0]) R[0] = x;
            if (x > R[2]) R[2] = x;
            if (y < R[1]) R[1] = y;
            if (y > R[3]) R[3] = y;
        }
        for (int k = 0; k < 3; k++) {
            const double b0 = bg->data[3 * i + k];
            const double b = terms ? ground.data[3 * i + k] : s * b0; // shaded, with step 3
            // 4. the layer over it
            const double lin = al * c[k] + (1 - al) * b;
            double v = rs_color_srgb_encode(lin < 0 ? 0 : lin > 1 ? 1 : lin);
            // 5. noise topped up to the camera's at this value (where nothing changed, the
            // background's own noise is all there is to have)
            if (look && changed) {
                const double vb = rs_color_srgb_encode(b0);
                const double carried = (1 - al) * s * rs_synth_appearance_noise_sigma(look, vb) *
                                       rs_color_srgb_decode_slope(vb) / rs_color_srgb_decode_slope(v);
                const double want = rs_synth_appearance_noise_sigma(look, v);
                const double top2 = want * want - carried * carried;
                if (top2 > 0) v += sqrt(top2) * rs_rng_normal(&rng);
            }
            out->data[3 * i + k] = clamp01(v);
        }
    }
    // 6. the camera's JPEG, on the 16 px blocks (4:2:0's, on the image's own grid) that hold
    // what changed; the background around them keeps its own compression
    if (look && look->jpeg_quality > 0 && R[2] >= R[0]) {
        const int x0 = R[0] / 16 * 16, y0 = R[1] / 16 * 16;
        const int x1 = (R[2] / 16 * 16 + 15 < W ? R[2] / 16 * 16 + 15 : W - 1);
        const int y1 = (R[3] / 16 * 16 + 15 < H ? R[3] / 16 * 16 + 15 : H - 1);
        rs_image cut = {0};
        if (!(st = rs_image_alloc(&cut, x1 - x0 + 1, y1 - y0 + 1, 3, err))) {
            for (int y = y0; y <= y1; y++)
                memcpy(&cut.data[(size_t)(y - y0) * cut.width * 3], &out->data[((size_t)y * W + x0) * 3],
                       sizeof(float) * 3 * (size_t)cut.width);
            if (!(st = rs_synth_appearance_jpeg(&cut, look, err)))
                for (int y = y0; y <= y1; y++)
                    memcpy(&out->data[((size_t)y * W + x0) * 3], &cut.data[(size_t)(y - y0) * cut.width * 3],
                           sizeof(float) * 3 * (size_t)cut.width);
        }
        rs_image_free(&cut);
    }
done:
    rs_image_free(&layer);
    rs_image_free(&shb);
    rs_image_free(&sw);
    rs_image_free(&ground);
    if (st) rs_image_free(out);
    return st;
}

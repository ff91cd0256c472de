// rs_color.h -- the one sRGB transfer function (IEC 61966-2-1), both ways. "sRGB" values are the
// stored (gamma-encoded) values of a photograph or an 8-bit image, scaled to [0, 1]; "linear"
// ones are proportional to light. Used wherever a stored colour meets light: rendering over a
// background, the sun and light read from a photograph, a dataset's composites, vehicle paints.
//
//   decode (sRGB -> linear): v <= 0.04045 ? v / 12.92 : ((v + 0.055) / 1.055)^2.4
//   encode (linear -> sRGB): v <= 0.0031308 ? 12.92 v : 1.055 v^(1/2.4) - 0.055
//
// Inputs outside [0, 1] are clamped to it, NaN reads as 0.
// Two evaluations of the same formulas: _exact calls pow() each time (a colour at a time);
// rs_color_srgb_decode / _encode interpolate linearly in a table of the formula at 65,537
// points of [0, 1], filled once at first use (pthread_once): within 1e-6 of the formula over
// [0, 1] (tests/core/test_color.c, 10^7 points; the worst at the encoder's kink, 0.0031308),
// 1/4000 of an 8-bit step. A per-pixel pow() was a quarter of `roadside synth`'s own CPU.
#pragma once

#ifdef __cplusplus
extern "C" {
#endif

// The formulas above, with pow(): sRGB -> linear and linear -> sRGB.
double rs_color_srgb_decode_exact(double v);
double rs_color_srgb_encode_exact(double v);

// The same from the tables (within 1e-6): for images, a value per pixel and channel.
double rs_color_srgb_decode(double v);
double rs_color_srgb_encode(double v);

// d decode / dv at the stored value v in [0, 1]: how a small change of a stored value (noise in
// an image's units) maps into linear light; 1 / slope at v maps back. The decode table's slope
// over the interval of 1/65,536 holding v: within 1.2e-4 (relative) of the formula's derivative
// but at the kink 0.04045 (a mean of its two sides there); 1/12.92 below it.
double rs_color_srgb_decode_slope(double v);

#ifdef __cplusplus
}
#endif

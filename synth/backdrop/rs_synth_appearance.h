// rs_synth_appearance.h -- making a rendered vehicle layer look like it was photographed by the
// camera of its background: exposure and white balance, sensor noise, blur, JPEG quality
// (the seed paper's "reality enhancement", done classically; docs/appearance.md).
//
// Images are rs_image (synth/backdrop/rs_synth_opencv.h): floats in [0,1]. "sRGB" images hold the
// stored (gamma-encoded) values of a photograph; "linear" ones linear light (IEC 61966-2-1
// transfer function, core/rs_color.h). Filters go through OpenCV (rs_synth_image_filter / _blur).
#pragma once
#include "core/rs_status.h"
#include "synth/backdrop/rs_synth_opencv.h"
#include <stdint.h>
#ifdef __cplusplus
extern "C" {
#endif

// Sensor noise: 1-sigma of additive white noise in the image's stored values (units of [0,1]).
// Method: J. Immerkaer, "Fast noise variance estimation", CVIU 64(2), 1996: the kernel
// [1 -2 1; -2 4 -2; 1 -2 1] cancels locally linear image content and has gain 6 on white noise;
// made robust with the median absolute value (sigma = 1.4826 median|M * I| / 6, over every
// channel's interior pixels), so that edges and texture (a minority of pixels) do not count.
// Accuracy: within 3% on a flat image with sigma in [0.005, 0.05] (tests/synth/backdrop/test_appearance.py);
// texture covering most pixels biases it upwards.
rs_status rs_synth_estimate_noise(double *sigma, const rs_image *img, rs_err *err);

// Blur: the standard deviation (pixels) of a Gaussian blur of the image's edges.
// Method: re-blur gradient ratio (S. Zhuo, T. Sim, "Defocus map estimation from a single image",
// Pattern Recognition 44(9), 2011): at an edge blurred by sigma, re-blurring by sigma_r = 2 px
// divides the gradient maximum by R = sqrt(sigma^2 + sigma_r^2 + 1/3) / sqrt(sigma^2 + 1/3)
// (the 1/3: central differences average over 2 px, variance 2^2/12), so
// sigma^2 = sigma_r^2 / (R^2 - 1) - 1/3, taken as the median over edge pixels (gradient local
// maxima along the dominant axis stronger than 50% of the 99th percentile of the gradient: noise
// raises a weak edge's gradient maximum more than its re-blurred one and so reads it sharper;
// at 20% a 1.5 px blur under noise of sigma 0.02 and JPEG quality 90 read 1.36-1.38 px, at 50%
// 1.44-1.47 (tests/synth/povray/test_render_look.py's backgrounds)) that are isolated steps
// (the luma difference across the edge at +-6 px along the axis still 80 % of its largest within
// 6 px: a thin line's gradient falls more under the re-blur than a step's and read too sharp,
// the demo's digital twin blurred by 1.2 / 2.0 px read 0.60 / 1.39 px with its far lane markings
// counted, 1.12 / 1.94 without them, 1.06 / 1.65 under noise and JPEG 85) on
// the luma (mean of the channels). Accuracy: within 0.2 px for sigma in [1, 3] on step edges
// spaced > 8 sigma apart (tests); a perfectly sharp step reads about 0.6 px (pixel sampling).
// Returns RS_ERR_DEGENERATE when the image has fewer than 20 edge pixels.
rs_status rs_synth_estimate_blur(double *sigma_px, const rs_image *img, rs_err *err);

// Exposure and white balance: per-channel linear gains g_c with target ~ g_c reference,
// g_c = mean(target_c) / mean(reference_c) in linear light over the pixels where neither image
// is clipped (stored value in (0.02, 0.98) in every channel of both) and mask (may be NULL) is
// non-zero. Both inputs are sRGB-encoded, same size, 3 or 4 channels (alpha ignored).
// reference NULL: grey world, g_c = mean(target_c) / mean over c of mean(target_c): the colour
// cast of the target only, exposure 1.
// Accuracy: exact for noiseless data; 0.5% after 8-bit quantisation (tests).
// Returns RS_ERR_DEGENERATE with fewer than 100 usable pixels, RS_ERR_INVALID for size mismatch.
rs_status rs_synth_estimate_gain(double gain[3],
                                 // in
                                 const rs_image *target, const rs_image *reference, const uint8_t *mask, rs_err *err);

// JPEG quality of a file: its quantisation tables (DQT segments) compared with the IJG (libjpeg)
// tables at every quality 1..100 (the standard tables of ITU-T T.81 Annex K scaled by
// 5000/q for q < 50, 200 - 2q otherwise, rounded, clamped to [1, 255]); the quality with the
// smallest absolute difference wins. *exact = 1 when the tables equal IJG's at that quality
// (any libjpeg writer, e.g. OpenCV's), 0 for a foreign encoder (then the quality is the nearest
// IJG equivalent). *quality = 0 for a file that is not a JPEG (PNG: no compression loss).
// Returns RS_ERR_IO (unreadable), RS_ERR_PARSE (a JPEG without a valid DQT).
rs_status rs_synth_estimate_jpeg_quality(int *quality, int *exact,
                                         // in
                                         const char *path, rs_err *err);

// Signal-dependent sensor noise: the variance of the stored values v in [0,1] as
// sigma^2(v) = a + b v (read noise a, shot noise b v: the Poissonian-Gaussian model of A. Foi,
// M. Trimeche, V. Katkovnik, K. Egiazarian, "Practical Poissonian-Gaussian noise modeling and
// fitting for single-image raw-data", IEEE TIP 17(10), 2008, here on the stored values since the
// composite is made in them). Method as Foi's: local estimates on smooth pixels binned by level,
// then a fit. Per channel, at every second pixel of every second row, the residual r = M * I of Immerkaer's kernel (above; gain 6 on white
// noise) and the level m = the 5 x 5 mean; 16 bins of m over [0,1] (those within 0.03 of 0 or 1,
// where clipping bends the noise, and those with fewer than 300 samples left out); in each bin
// the smoother half of the pixels (the 5 x 5 mean's gradient below the bin's median) and
// sigma_k = 1.4826 median|r| / 6; then var = a + b v by least squares weighted by n_k / sigma_k^4
// (the variance of a MAD estimate), with a, b >= 0 (the other refitted alone when one is < 0).
// jpeg_quality > 0: the JPEG the background went through removed part of its noise, which the
// vehicles' noise will then go through again: each bin's sigma_k is replaced by the sigma whose
// white noise on a flat 64 x 64 patch of that level, JPEG round-tripped at that quality (OpenCV's
// libjpeg, as rs_synth_appearance_jpeg), measures sigma_k the same way (bisection in log sigma, 10 steps; about 0.1 s of CPU per
// background at 720 x 480).
// Accuracy (sigma(v) = sqrt(a + b v) against the truth a = 1e-4, b = 6e-4 of a 360 x 240
// background of flat patches blurred by 1.5 px): a PNG within 1 % over v in [0.2, 0.8]; JPEGs
// at quality 95 / 90 / 75 within 3 / 2 / 15 % (a JPEG at 90 leaves 0.0039 of a 0.0138 noise at
// v 0.15: the inversion is steep); tests/synth/povray/test_render_look.py prints its estimate.
// Returns RS_ERR_DEGENERATE when no bin has enough smooth pixels.
rs_status rs_synth_estimate_noise_model(double *a, double *b,
                                        // in
                                        const rs_image *img, int jpeg_quality, rs_err *err);

// JPEG blockiness: the ratio of the mean absolute luma difference across the 8-pixel block
// boundaries (between columns 8k-1 and 8k, and between such rows) to that between the
// neighbours inside the blocks, the average of the horizontal and vertical ratios (after the
// block-boundary measure of Z. Wang, A. C. Bovik, B. L. Evans, "Blind measurement of blocking
// artifacts in images", ICIP 2000). 1: no blocks; larger: visible 8 x 8 blocks. Luma: the mean of
// the channels. Returns RS_ERR_DEGENERATE for an image smaller than 16 x 16 or without texture.
rs_status rs_synth_estimate_blockiness(double *ratio, const rs_image *img, rs_err *err);

// What a background says about its camera.
typedef struct {
    double gain[3];       // linear per-channel gain to apply to the vehicle layer
    double noise_sigma;   // stored-value noise 1-sigma, [0,1] units (one figure for all levels)
    double blur_sigma_px; // Gaussian blur, pixels
    int jpeg_quality;     // 0: not a JPEG (no re-encoding)
    double noise_a;       // signal-dependent noise: variance a + b v of stored values v in [0,1]
    double noise_b;       //   (rs_synth_estimate_noise_model); both 0: noise_sigma at every level
    double blockiness;    // rs_synth_estimate_blockiness of the background (1: no blocks)
    int jpeg_exact;       // 1: the JPEG tables are IJG's at jpeg_quality exactly
} rs_synth_appearance;

// The noise 1-sigma (stored units) the appearance gives a pixel of stored value v in [0,1]:
// sqrt(a + b v), or noise_sigma when a = b = 0.
double rs_synth_appearance_noise_sigma(const rs_synth_appearance *a, double v);

// Estimates all of the above from a background image file. image: that file as rs_image_read
// decodes it, when the caller has it already, or NULL (then it is read here); the JPEG quality
// is always read from the file itself. reference: an sRGB image of the same view rendered with
// the nominal light the vehicles are rendered with (e.g. the digital-twin background,
// rs_synth_background.h) for the exposure; NULL for grey world (colour cast only).
rs_status rs_synth_appearance_estimate(rs_synth_appearance *out,
                                       // in
                                       const char *background_path, const rs_image *image, const rs_image *reference,
                                       rs_err *err);

// The layer's part of an appearance, in place (rgba_linear: linear light, straight alpha,
// (H,W,4)): colour x gain, then a Gaussian blur of sqrt(max(0, blur^2 - layer_blur^2)) px on the
// premultiplied colour and alpha, back to straight alpha. No noise: the composite adds it
// (synth/povray/rs_synth_composite.h), or rs_synth_appearance_apply.
rs_status rs_synth_appearance_layer( // in,out
    rs_image *rgba_linear,
    // in
    const rs_synth_appearance *a, double layer_blur_sigma_px, rs_err *err);

// Applies an appearance to a rendered vehicle layer (linear light, straight alpha, (H,W,4)), in
// place: colour x gain; then a Gaussian blur of sqrt(max(0, blur^2 - layer_blur^2)) px on the
// premultiplied colour and alpha (so edges blend as the camera's would); then Gaussian noise of
// the background's sigma in stored (sRGB) units, converted to linear light at each pixel's value
// (sigma_lin = sigma dDecode/dv), on pixels with alpha > 0, drawn from a generator seeded with
// `seed` (deterministic). JPEG quality is applied to the composite: rs_synth_appearance_jpeg.
// in: layer_blur_sigma_px: the layer's own blur (e.g. rs_synth_estimate_blur of its alpha)
rs_status rs_synth_appearance_apply( // in,out
    rs_image *rgba_linear,
    // in
    const rs_synth_appearance *a, double layer_blur_sigma_px, uint64_t seed, rs_err *err);

// JPEG round trip of an sRGB composite at a->jpeg_quality (nothing when 0), in place.
rs_status rs_synth_appearance_jpeg(rs_image *srgb, const rs_synth_appearance *a, rs_err *err);

#ifdef __cplusplus
}
#endif

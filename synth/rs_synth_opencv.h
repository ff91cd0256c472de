// rs_synth_opencv.h -- the OpenCV shim of the synthesis module: image files and resampling.
//
// Images are float (H, W, C) row-major, channels RGB / RGBA / single, values as stored in the
// file normalised to [0, 1] (8-bit /255, 16-bit /65535; no gamma conversion). Every OpenCV
// exception is caught and returned as an rs_status.
#pragma once
#include "rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    int width, height, channels; // channels: 1, 3 (RGB) or 4 (RGBA)
    float *data;                 // (height, width, channels) owned; free with rs_synth_image_free
} rs_synth_image;

// Allocates a zeroed image. Returns RS_ERR_NOMEM / RS_ERR_INVALID (bad sizes).
rs_status rs_synth_image_alloc(rs_synth_image *img, int width, int height, int channels,
                               rs_err *err);
void rs_synth_image_free(rs_synth_image *img); // NULL-safe; zeroes *img

// Reads PNG/JPEG/... (cv::imread, IMREAD_UNCHANGED); greyscale stays 1 channel, BGR(A) becomes
// RGB(A). Returns RS_ERR_IO when the file is missing or unreadable.
rs_status rs_synth_image_read(rs_synth_image *img, const char *path, rs_err *err);

// Writes an image with 8 or 16 bits per channel (values rounded, clamped to [0,1]), atomically
// (temporary name in the same folder, then rename). The format follows the extension (.png).
rs_status rs_synth_image_write(const char *path, const rs_synth_image *img, int bits, rs_err *err);

// Resamples `src` through map_xy (dst pixel (u,v) takes src at map_xy[v][u], OpenCV's remap
// convention, pixel (0,0) = centre of the top-left pixel). interpolation: 0 nearest, 1 linear,
// 3 cubic (OpenCV's INTER_*). Outside src: zero (transparent for RGBA).
// out: *dst, allocated (width, height, src->channels); in: map_xy (height, width, 2)
rs_status rs_synth_remap(rs_synth_image *dst,
                         // in
                         const rs_synth_image *src, const float *map_xy, int width, int height,
                         int interpolation, rs_err *err);

#ifdef __cplusplus
}
#endif

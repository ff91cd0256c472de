// rs_image.h -- images in memory and image files (PNG, JPEG, ... through OpenCV's imgcodecs,
// in core/rs_opencv.cc). The one reader and writer of image files: the data synthesis, the
// backgrounds and the report all use it.
//
// Images are float (H, W, C) row-major, channels RGB / RGBA / single, values as stored in the
// file normalised to [0, 1] (8-bit /255, 16-bit /65535; no gamma conversion). Every OpenCV
// exception is caught and returned as an rs_status.
#pragma once
#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    int width, height, channels; // channels: 1, 3 (RGB) or 4 (RGBA)
    float *data;                 // (height, width, channels) owned; free with rs_image_free
} rs_image;

// Allocates a zeroed image. Returns RS_ERR_NOMEM / RS_ERR_INVALID (bad sizes).
rs_status rs_image_alloc(rs_image *img, int width, int height, int channels, rs_err *err);
void rs_image_free(rs_image *img); // NULL-safe; zeroes *img

// The most pixels rs_image_read decodes (8192 x 8192; 1 GiB as float RGBA): a larger image is
// refused from its header, before anything is decoded.
#define RS_IMAGE_MAX_PIXELS ((long long)1 << 26)

// An image file's width and height (pixels) from its header, nothing decoded: PNG (libpng),
// JPEG (libjpeg). Only a regular file is opened (rs_io_check_regular). Errors: RS_ERR_IO
// (missing, not a regular file), RS_ERR_PARSE (a broken header), RS_ERR_UNSUPPORTED (another
// format: its size is known only once decoded).
rs_status rs_image_size( // out
    int *width, int *height,
    // in
    const char *path, rs_err *err);

// Reads PNG/JPEG/... (cv::imread, IMREAD_UNCHANGED); greyscale stays 1 channel, BGR(A) becomes
// RGB(A). Only a regular file reaches OpenCV (a FIFO or device is refused, never waited on), and
// a PNG or JPEG whose header says more than RS_IMAGE_MAX_PIXELS is refused before decoding.
// Returns RS_ERR_IO when the file is missing or unreadable, RS_ERR_INVALID when too large.
rs_status rs_image_read(rs_image *img, const char *path, rs_err *err);

// rs_image_read of an image that must be width x height pixels (a camera's frame): a PNG or JPEG
// of another size is refused from its header (RS_ERR_INVALID "PATH: the image is WxH, expected
// ..."), before decoding; another format after.
rs_status rs_image_read_sized(rs_image *img, const char *path, int width, int height, rs_err *err);

// Writes an image with 8 or 16 bits per channel (values rounded, clamped to [0,1]), atomically
// (temporary name in the same folder, then rename). The format follows the extension (.png).
rs_status rs_image_write(const char *path, const rs_image *img, int bits, rs_err *err);

#ifdef __cplusplus
}
#endif

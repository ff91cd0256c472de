// rs_synth_opencv.h -- the OpenCV shim of the synthesis module: resampling, video frames,
// filters, JPEG round trips, ONNX image translation. Images are core's rs_image (core/rs_image.h,
// which also reads and writes image files). Every OpenCV exception is caught and returned as an
// rs_status.
#pragma once
#include "core/rs_image.h"
#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// Resamples `src` through map_xy (dst pixel (u,v) takes src at map_xy[v][u], OpenCV's remap
// convention, pixel (0,0) = centre of the top-left pixel). interpolation: 0 nearest, 1 linear,
// 3 cubic (OpenCV's INTER_*). Outside src: zero (transparent for RGBA).
// out: *dst, allocated (width, height, src->channels); in: map_xy (height, width, 2)
rs_status rs_synth_remap(rs_image *dst,
                         // in
                         const rs_image *src, const float *map_xy, int width, int height, int interpolation,
                         rs_err *err);

// ---- backgrounds and appearance ----
// Owned by the backgrounds helper (synth/backdrop/rs_synth_background.h, rs_synth_appearance.h).

// A stream of 8-bit RGB frames from one input: an image file (one frame; any format
// cv::haveImageReader accepts) or a video (cv::VideoCapture, frame by frame). Opaque; at most
// one decoded frame is held at a time.
typedef struct rs_synth_frames rs_synth_frames;
// out: *frames (rs_synth_frames_close). Returns RS_ERR_IO when the file cannot be opened.
rs_status rs_synth_frames_open(rs_synth_frames **frames, const char *path, rs_err *err);
// The next frame: *rgb points to (height, width, 3) bytes owned by `frames`, valid until the next
// call; *got = 0 at the end of the stream (then *rgb is NULL).
rs_status rs_synth_frames_next(rs_synth_frames *frames,
                               // out
                               const unsigned char **rgb, int *width, int *height, int *got, rs_err *err);
void rs_synth_frames_close(rs_synth_frames *frames); // NULL-safe
// Convolution with a (kh, kw) kernel, row-major, anchor at its centre (cv::filter2D, border
// reflected about the edge pixel: BORDER_REFLECT_101). out: *dst allocated like src.
rs_status rs_synth_image_filter(rs_image *dst,
                                // in
                                const rs_image *src, const double *kernel, int kw, int kh, rs_err *err);
// Gaussian blur of standard deviation sigma_px (> 0) (cv::GaussianBlur, kernel 2 ceil(4 sigma)+1,
// BORDER_REFLECT_101). sigma_px <= 0 copies. out: *dst allocated like src.
rs_status rs_synth_image_blur(rs_image *dst,
                              // in
                              const rs_image *src, double sigma_px, rs_err *err);
// JPEG round trip of an RGB image at `quality` (1..100, libjpeg through cv::imencode/imdecode),
// the [0,1] values taken as 8-bit codes. out: *dst (H, W, 3) allocated.
rs_status rs_synth_image_jpeg_roundtrip(rs_image *dst,
                                        // in
                                        const rs_image *src, int quality, rs_err *err);
// Runs an ONNX image-translation model (e.g. a CUT/CycleGAN generator) through OpenCV's DNN
// module (cv::dnn::readNetFromONNX, CPU): input 1 x 3 x H x W float, RGB, values mapped from
// [0,1] to [-1,1] (x 2 - 1, the convention of those generators); output 1 x 3 x H x W mapped
// back ((y + 1) / 2) and clamped to [0,1]. The model is loaded on every call.
// out: *dst (H, W, 3) allocated; in: src RGB (H, W, 3)
// Returns RS_ERR_IO / RS_ERR_EXTERNAL (model unreadable or failing), RS_ERR_INVALID (shapes).
rs_status rs_synth_dnn_translate(rs_image *dst,
                                 // in
                                 const char *onnx_path, const rs_image *src, rs_err *err);

// ---- drawing (roadside dataset view, synth/dataset/rs_synth_dataset_view.c) ----
// On an RGB rs_image in place (other channel counts: RS_ERR_INVALID), colours `rgb` (3,) in the image's
// [0, 1] values; lines 1 px wide by default, not antialiased (cv::LINE_8: every drawn pixel has
// exactly the colour). Coordinates are pixel indices (integer centres, pixel (0,0) the top-left);
// what falls outside the image is clipped. Each returns RS_ERR_EXTERNAL on an OpenCV exception.

// The rectangle through pixel columns x0..x1 and rows y0..y1 (inclusive: its outline covers
// those pixels; cv::rectangle); thickness >= 1, centred on that outline.
rs_status rs_synth_draw_rect(rs_image *img, int x0, int y0, int x1, int y1, const float *rgb, int thickness,
                             rs_err *err);
// A straight segment between sub-pixel points p0_px, p1_px (2,) (cv::line with 4 bits of
// sub-pixel shift). Points farther than 1e6 px from the image are refused (not drawn, RS_OK).
rs_status rs_synth_draw_line(rs_image *img, const double *p0_px, const double *p1_px, const float *rgb, int thickness,
                             rs_err *err);
// A filled disc of radius_px (>= 1) at the sub-pixel point p_px (2,) (cv::circle).
rs_status rs_synth_draw_dot(rs_image *img, const double *p_px, int radius_px, const float *rgb, rs_err *err);
// Text in Hershey's simplex font (cv::putText), its baseline's left end at pixel (x, y), about
// height_px tall (cap height); bg_rgb (3,), may be NULL: a filled box behind the text.
// *width_px (may be NULL): the text's width.
rs_status rs_synth_draw_text(rs_image *img, int x, int y, const char *text, int height_px, const float *rgb,
                             const float *bg_rgb, int *width_px, rs_err *err);
// Resized copy of src to (width, height) (cv::resize, INTER_AREA: the mean over each output
// pixel's footprint when shrinking; linear when growing). out: *dst allocated.
rs_status rs_synth_image_resize(rs_image *dst,
                                // in
                                const rs_image *src, int width, int height, rs_err *err);

#ifdef __cplusplus
}
#endif

// rs_detect.h -- an ONNX object detector run through OpenCV's DNN module (`roadside detect`).
//
// Two families of single-stage detectors, each pre- and post-processed exactly as its own
// inference code does (docs/detect.md has the references):
//
//   YOLOX (Megvii, demo/ONNXRuntime/onnx_inference.py and yolox/utils/demo_utils.py): the frame,
//   BGR, resized by ratio r = min(H/h, W/w) to (int(w r), int(h r)) (bilinear) into the top-left
//   corner of a W x H canvas of 114; no normalisation. Output (1, N, 5 + C), N = sum over the
//   strides s = 8, 16, 32 of (W/s)(H/s), anchors in that order, row-major within a stride:
//   cx = (o0 + gx) s, cy = (o1 + gy) s, w = exp(o2) s, h = exp(o3) s, in net pixels; score =
//   objectness o4 times the best class score (class-agnostic NMS: demo_utils' default). Boxes
//   mapped back as x / r.
//
//   Ultralytics YOLOv8 and later (ultralytics/data/augment.py LetterBox, ultralytics/utils/ops.py
//   non_max_suppression and scale_boxes): the frame, RGB, /255, resized by the same r to
//   (round(w r), round(h r)) and centred on a W x H canvas of 114 (left = round(dw - 0.1), top =
//   round(dh - 0.1), dw, dh half the padding). Output (1, 4 + C, N): cx, cy, w, h in net pixels
//   and C class scores, no objectness; score = the best class score; NMS per class; boxes mapped
//   back as (x - left) / r and clipped to [0, w] x [0, h].
//
// Either way a box maps back through the inverse of the affine map the family's own training
// applies to its labels (x r + pad), so the boxes come out in the pixel convention of the labels
// the model was trained on: COCO's corner convention ((0, 0) = the top-left pixel's top-left
// corner) for a model trained on roadside's datasets, whose COCO and YOLO boxes are written in it
// (issue 41; roadside's own points are pixel-centre, docs/conventions.md: eval and localise take
// the 0.5 px off when they read a bbox). NMS is OpenCV's
// cv::dnn::NMSBoxes (IoU without the "+1" of YOLOX's numpy demo). Accuracy: the decode is double
// precision over the network's float32 output (boxes to ~1e-5 px at 4K).
#pragma once
#include <stdbool.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    RS_DETECT_AUTO = 0,    // told apart by the output's shape (rs_detect_layout_of)
    RS_DETECT_YOLOX,       // (1, N, 5 + C), raw grid outputs
    RS_DETECT_ULTRALYTICS, // (1, 4 + C, N), decoded boxes
} rs_detect_family;

// "yolox", "ultralytics", "auto"
const char *rs_detect_family_name(rs_detect_family family);

typedef struct {
    rs_detect_family family; // RS_DETECT_AUTO: from the output's shape
    int width_px, height_px; // the network's input size, multiples of 32
    double conf;             // keep scores > conf; < 0: the family's default (YOLOX 0.1, Ultralytics 0.25)
    double nms_iou;          // NMS IoU threshold; < 0: the family's default (YOLOX 0.45, Ultralytics 0.7)
    int max_dets;            // at most this many per frame, best first; 0: no limit; < 0: the family's
                             // default (YOLOX none, Ultralytics 300)
} rs_detect_options;

// One detection in the input frame's pixels.
typedef struct {
    double bbox_px[4]; // x, y (top-left corner), w, h: COCO's bbox
    double score;      // 0..1
    int category_id;   // 1-based: the network's class index + 1
} rs_detect_box;

// The letterbox of one frame: frame pixel x maps to network pixel x ratio + pad_x_px.
typedef struct {
    int width, height;        // the frame's size (px)
    double ratio;             // r = min(H/h, W/w)
    int resized_w, resized_h; // the frame's size once resized (px)
    int pad_x_px, pad_y_px;   // where its top-left corner lands on the canvas (YOLOX: 0, 0)
} rs_detect_letterbox;

// The letterbox of a width x height frame on a net_w x net_h input, as `family` computes it
// (RS_DETECT_YOLOX or RS_DETECT_ULTRALYTICS). RS_ERR_INVALID when the resized frame would be
// empty (an extreme aspect ratio).
rs_status rs_detect_letterbox_of( // out
    rs_detect_letterbox *lb,
    // in
    rs_detect_family family, int width, int height, int net_w, int net_h, rs_err *err);

// A network's output layout.
typedef struct {
    rs_detect_family family; // never RS_DETECT_AUTO once known
    int Nanchors, Nclasses;  // N and C
    int net_w, net_h;        // the input it was found for (px)
} rs_detect_layout;

// Which family an output of shape dims (Ndims,) belongs to, for a net_w x net_h input.
// asked: the caller's choice (RS_DETECT_AUTO: decide). out: *layout.
// YOLOX: (1, N, 5 + C) with N = sum over s = 8, 16, 32 of (W/s)(H/s); Ultralytics: (1, 4 + C, N)
// with the same N when auto, any N >= 1 when asked. RS_ERR_UNSUPPORTED when the shape fits
// neither, or both (then the message asks for --family).
rs_status rs_detect_layout_of( // out
    rs_detect_layout *layout,
    // in
    const int *dims, int Ndims, int net_w, int net_h, rs_detect_family asked, rs_err *err);

// A network loaded, its family and class count known. Opaque.
typedef struct rs_detect_net rs_detect_net;

// Time spent on one frame (milliseconds, wall clock).
typedef struct {
    double preprocess_ms; // letterbox and blob
    double forward_ms;    // the network
    double decode_ms;     // decoding, NMS, mapping back
} rs_detect_timing;

// Loads an ONNX model (cv::dnn::readNetFromONNX, CPU) and runs it once on a grey input to learn
// its output's shape and so its family (rs_detect_layout_of). opt is copied.
// Errors: RS_ERR_IO (missing, not a regular file), RS_ERR_EXTERNAL (OpenCV cannot load or run
// it), RS_ERR_UNSUPPORTED (an output neither family has), RS_ERR_INVALID (bad options).
// out: *net (rs_detect_net_free)
rs_status rs_detect_net_open(rs_detect_net **net,
                             // in
                             const char *onnx_path, const rs_detect_options *opt, rs_err *err);
void rs_detect_net_free(rs_detect_net *net); // NULL-safe

// The output layout found when the model was loaded (owned by net).
const rs_detect_layout *rs_detect_net_layout(const rs_detect_net *net);

// One frame in memory.
typedef struct {
    const unsigned char *bgr; // (height, width, 3) 8-bit, row-major, BGR order; not owned
    int width, height;        // pixels
} rs_detect_frame;

// Detects in one frame.
// out: *boxes (malloc'ed, caller frees; NULL when *Nboxes is 0), *Nboxes, best score first;
//      *timing (may be NULL)
// Errors: RS_ERR_EXTERNAL (OpenCV), RS_ERR_INVALID (bad size), RS_ERR_NOMEM.
rs_status rs_detect_net_run(rs_detect_net *net,
                            // out
                            rs_detect_box **boxes, int *Nboxes, rs_detect_timing *timing,
                            // in
                            const rs_detect_frame *frame, rs_err *err);

// Decodes a network's raw output (float32, the shape rs_detect_layout_of accepted) into the
// candidates scoring above conf, in the frame's pixels (before NMS). Pure C; the shim calls it.
// out: xyxy_px (4 Ncand,) corners, score (Ncand,), class_index (Ncand,): arrays of at least
//      layout->Nanchors entries; returns Ncand
// in:  output: (layout's shape) float32; lb: the frame's letterbox
int rs_detect_decode(double *xyxy_px, double *score, int *class_index,
                     // in
                     const float *output, const rs_detect_layout *layout, const rs_detect_letterbox *lb, double conf);

// The family's defaults filled into *opt where it asks for them (conf, nms_iou, max_dets < 0).
void rs_detect_options_resolve(rs_detect_options *opt, rs_detect_family family);

// OpenCV's thread count for everything after this call (cv::setNumThreads): n >= 1, or -1 for
// OpenCV's default.
void rs_detect_set_threads(int n);

// ---- frames from one input ----

// A stream of 8-bit BGR frames from an image file (one frame, read by core/rs_image.h), a video
// file, or a stream URL ("scheme://...", cv::VideoCapture). A path is checked with stat first:
// a FIFO, device, socket or folder is refused (nothing opens it, so nothing waits). "file://" URLs
// are checked as their path. Opaque.
typedef struct rs_detect_frames rs_detect_frames;

// Errors: RS_ERR_IO (missing, not a regular file, cannot be opened as an image or a video).
// out: *frames (rs_detect_frames_close)
rs_status rs_detect_frames_open(rs_detect_frames **frames,
                                // in
                                const char *input, rs_err *err);
// The next frame: frame->bgr points to bytes owned by `frames`, valid until the next call;
// *got = false at the end (then frame->bgr is NULL). RS_ERR_IO for an unreadable image.
rs_status rs_detect_frames_next(rs_detect_frames *frames,
                                // out
                                rs_detect_frame *frame, bool *got, rs_err *err);
// The video's frame rate (frames per second), 0 when unknown or a still image.
double rs_detect_frames_fps(const rs_detect_frames *frames);
void rs_detect_frames_close(rs_detect_frames *frames); // NULL-safe

// ---- a run: inputs in, the detections file out (rs_detect_run.c) ----

// How a run names and times its frames.
typedef struct {
    const char *camera_id;           // written as "camera"; may be NULL (not written)
    int camera_width, camera_height; // every frame must have this size (the camera model's), pixels
    double fps;                      // frames per second of image inputs (and of videos that do not say); 0: unknown
    int every;                       // detect in every every-th frame of each input (>= 1)
} rs_detect_run_options;

// What a run did.
typedef struct {
    long Nframes;           // frames detected in
    long Ndetections;       // detections written
    rs_detect_timing total; // summed over the frames (ms)
} rs_detect_summary;

// Runs `net` over the inputs (Ninputs,) in order -- image files, folders (their image files,
// .png .jpg .jpeg .bmp .tif .tiff .webp .ppm .pgm, in byte order of their names), video files,
// stream URLs -- and writes the detections file (docs/detect.md; interfaces of issue 39 item 1:
// a COCO results list with image_id (1-based over the frames detected in), category_id, bbox,
// score, camera, frame (0-based within its input; consecutive image files are one input, as a
// folder's images are), time_s (frame / fps; absent when unknown),
// file_name) to out_path atomically (core/rs_io.h): nothing is written on any error.
// Errors name the input (and frame): a frame whose size is not the camera's (RS_ERR_INVALID), an
// input that cannot be read (RS_ERR_IO), an empty folder (RS_ERR_NOT_FOUND), OpenCV's failures.
// out: *summary (may be NULL)
rs_status rs_detect_run(rs_detect_summary *summary,
                        // in
                        rs_detect_net *net, const char *const *inputs, int Ninputs, const rs_detect_run_options *opt,
                        const char *out_path, rs_err *err);

#ifdef __cplusplus
}
#endif

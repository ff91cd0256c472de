// rs_detect_decode.c -- the two families' letterbox, output layouts and decoding (eval/detect/rs_detect.h).
// Pure C: the OpenCV shim (rs_detect_opencv.cc) resizes, runs the network and calls these.
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "eval/detect/rs_detect.h"

// The strides of both families' three detection heads (P3, P4, P5).
static const int STRIDES[3] = {8, 16, 32};

const char *rs_detect_family_name(rs_detect_family family)
{
    switch (family) {
    case RS_DETECT_YOLOX: return "yolox";
    case RS_DETECT_ULTRALYTICS: return "ultralytics";
    default: return "auto";
    }
}

void rs_detect_options_resolve(rs_detect_options *opt, rs_detect_family family)
{
    const bool yolox = family == RS_DETECT_YOLOX;
    if (opt->conf < 0) opt->conf = yolox ? 0.1 : 0.25;       // onnx_inference.py score_thr / predictor conf
    if (opt->nms_iou < 0) opt->nms_iou = yolox ? 0.45 : 0.7; // nms_thr / predictor iou
    if (opt->max_dets < 0) opt->max_dets = yolox ? 0 : 300;  // YOLOX keeps all; max_det
}

rs_status rs_detect_letterbox_of(rs_detect_letterbox *lb, rs_detect_family family, int width, int height, int net_w,
                                 int net_h, rs_err *err)
{
    *lb = (rs_detect_letterbox){.width = width, .height = height};
    if (width < 1 || height < 1 || net_w < 1 || net_h < 1)
        return rs_err_set(err, RS_ERR_INVALID, "letterbox: bad sizes %dx%d on %dx%d", width, height, net_w, net_h);
    const double r = fmin((double)net_h / height, (double)net_w / width);
    lb->ratio = r;
    if (family == RS_DETECT_YOLOX) {
        // preproc: cv2.resize(img, (int(img.shape[1] * r), int(img.shape[0] * r))), top-left
        lb->resized_w = (int)(width * r);
        lb->resized_h = (int)(height * r);
    } else {
        // LetterBox: new_unpad = round(w r), round(h r) (Python's round: half to even, as
        // nearbyint in the default rounding mode); padding split with round(d -/+ 0.1)
        lb->resized_w = (int)nearbyint(width * r);
        lb->resized_h = (int)nearbyint(height * r);
        lb->pad_x_px = (int)nearbyint((net_w - lb->resized_w) / 2.0 - 0.1);
        lb->pad_y_px = (int)nearbyint((net_h - lb->resized_h) / 2.0 - 0.1);
    }
    if (lb->resized_w < 1 || lb->resized_h < 1 || lb->resized_w > net_w || lb->resized_h > net_h)
        return rs_err_set(err, RS_ERR_INVALID, "letterbox: a %dx%d frame resizes to %dx%d on the %dx%d input", width,
                          height, lb->resized_w, lb->resized_h, net_w, net_h);
    return RS_OK;
}

// The anchors of a net_w x net_h input: sum over the strides of (W/s)(H/s) (demo_postprocess's
// grids; Ultralytics' make_anchors for sizes that are multiples of 32).
static int anchors_of(int net_w, int net_h)
{
    int n = 0;
    for (int k = 0; k < 3; k++) n += (net_w / STRIDES[k]) * (net_h / STRIDES[k]);
    return n;
}

rs_status rs_detect_layout_of(rs_detect_layout *layout, const int *dims, int Ndims, int net_w, int net_h,
                              rs_detect_family asked, rs_err *err)
{
    *layout = (rs_detect_layout){.net_w = net_w, .net_h = net_h};
    char shape[96] = "(";
    for (int i = 0; i < Ndims && i < 6; i++) {
        size_t n = strlen(shape);
        snprintf(shape + n, sizeof shape - n, "%s%d", i ? ", " : "", dims[i]);
    }
    strcat(shape, Ndims > 6 ? ", ...)" : ")");
    const int N = anchors_of(net_w, net_h);
    const bool three = Ndims == 3 && dims[0] == 1;
    const bool yolox = three && dims[1] == N && dims[2] >= 6;
    const bool ultra_any = three && dims[1] >= 5 && dims[2] >= 1;
    const bool ultra = ultra_any && dims[2] == N;
    if (asked == RS_DETECT_YOLOX ? yolox : asked == RS_DETECT_ULTRALYTICS ? ultra_any : yolox != ultra) {
        const rs_detect_family f = asked != RS_DETECT_AUTO ? asked : yolox ? RS_DETECT_YOLOX : RS_DETECT_ULTRALYTICS;
        layout->family = f;
        layout->Nanchors = f == RS_DETECT_YOLOX ? dims[1] : dims[2];
        layout->Nclasses = f == RS_DETECT_YOLOX ? dims[2] - 5 : dims[1] - 4;
        return RS_OK;
    }
    if (asked == RS_DETECT_AUTO && yolox && ultra)
        return rs_err_set(err, RS_ERR_UNSUPPORTED,
                          "output %s fits both YOLOX's (1, N, 5+C) and Ultralytics' (1, 4+C, N) with N = %d: "
                          "say which with --family",
                          shape, N);
    if (asked == RS_DETECT_YOLOX)
        return rs_err_set(err, RS_ERR_UNSUPPORTED,
                          "output %s is not YOLOX's raw (1, N, 5+C) with N = %d anchors for a %dx%d input", shape, N,
                          net_w, net_h);
    if (asked == RS_DETECT_ULTRALYTICS)
        return rs_err_set(err, RS_ERR_UNSUPPORTED, "output %s is not Ultralytics' (1, 4+C, N)", shape);
    return rs_err_set(err, RS_ERR_UNSUPPORTED,
                      "output %s is neither YOLOX's raw (1, N, 5+C) nor Ultralytics' (1, 4+C, N) with N = %d anchors "
                      "for a %dx%d input (a different --size, or --family to force one)",
                      shape, N, net_w, net_h);
}

int rs_detect_decode(double *xyxy_px, double *score, int *class_index, const float *output,
                     const rs_detect_layout *layout, const rs_detect_letterbox *lb, double conf)
{
    const int Nanchors = layout->Nanchors, Nclasses = layout->Nclasses;
    int n = 0;
    if (layout->family == RS_DETECT_YOLOX) {
        // demo_postprocess: (out + grid) * stride, exp(out) * stride; scores = obj * cls;
        // multiclass_nms_class_agnostic: the best class, kept when > score_thr; boxes / ratio
        int a = 0;
        for (int k = 0; k < 3; k++) {
            const int s = STRIDES[k], gw = layout->net_w / s, gh = layout->net_h / s;
            for (int gy = 0; gy < gh; gy++)
                for (int gx = 0; gx < gw; gx++, a++) {
                    const float *o = output + (size_t)a * (5 + Nclasses);
                    int best = 0;
                    double best_score = (double)o[4] * o[5];
                    for (int c = 1; c < Nclasses; c++)
                        if ((double)o[4] * o[5 + c] > best_score) best_score = (double)o[4] * o[5 + c], best = c;
                    if (!(best_score > conf)) continue;
                    const double cx = (o[0] + (double)gx) * s, cy = (o[1] + (double)gy) * s;
                    const double w = exp((double)o[2]) * s, h = exp((double)o[3]) * s;
                    double *b = xyxy_px + 4 * n;
                    b[0] = (cx - w / 2) / lb->ratio;
                    b[1] = (cy - h / 2) / lb->ratio;
                    b[2] = (cx + w / 2) / lb->ratio;
                    b[3] = (cy + h / 2) / lb->ratio;
                    score[n] = best_score;
                    class_index[n++] = best;
                }
        }
        return n;
    }
    // Ultralytics: (1, 4 + C, N) row k holds quantity k of every anchor; xywh2xyxy; the best
    // class (multi_label False) kept when > conf; scale_boxes: (x - pad) / gain, clip_boxes
    for (int a = 0; a < Nanchors; a++) {
        int best = 0;
        double best_score = output[(size_t)4 * Nanchors + a];
        for (int c = 1; c < Nclasses; c++) {
            const double sc = output[(size_t)(4 + c) * Nanchors + a];
            if (sc > best_score) best_score = sc, best = c;
        }
        if (!(best_score > conf)) continue;
        const double cx = output[a], cy = output[(size_t)Nanchors + a];
        const double w = output[(size_t)2 * Nanchors + a], h = output[(size_t)3 * Nanchors + a];
        const double lim[4] = {lb->width, lb->height, lb->width, lb->height};
        const double xy[4] = {cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2};
        double *b = xyxy_px + 4 * n;
        for (int i = 0; i < 4; i++) {
            const double v = (xy[i] - (i % 2 ? lb->pad_y_px : lb->pad_x_px)) / lb->ratio;
            b[i] = fmin(fmax(v, 0.0), lim[i]);
        }
        score[n] = best_score;
        class_index[n++] = best;
    }
    return n;
}

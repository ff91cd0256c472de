// rs_detect_opencv.cc -- the OpenCV shim of eval/detect (rs_detect.h): the network (readNetFromONNX,
// blobFromImage, NMSBoxes), the letterbox's resize and border, frames from videos and streams
// (VideoCapture). Every exception is caught here and returned as an rs_status.
extern "C" {
#include "eval/detect/rs_detect.h"

#include "core/rs_image.h"
#include "core/rs_io.h"
}

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>
#include <numeric>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/dnn.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

struct rs_detect_net {
    cv::dnn::Net net;
    rs_detect_options opt; // resolved for the family
    rs_detect_layout layout;
    cv::Mat resized, canvas; // reused from frame to frame
    std::vector<double> xyxy, score;
    std::vector<int> class_index;
};

struct rs_detect_frames {
    std::string name; // the input as given, for messages
    bool still, done;
    double fps;
    cv::VideoCapture cap;
    cv::Mat bgr; // the current frame, 8-bit BGR, continuous
};

namespace {

// f() with every exception turned into RS_ERR_EXTERNAL naming `what`.
template <class F> rs_status catching(const char *what, rs_err *err, F f)
{
    try {
        return f();
    } catch (const cv::Exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "%s: OpenCV: %s", what, e.msg.c_str());
    } catch (const std::bad_alloc &) {
        return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", what);
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "%s: %s", what, e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "%s: unknown exception", what);
    }
}

double ms_since(std::chrono::steady_clock::time_point t0)
{
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// The family's letterboxed canvas of `frame` in n->canvas, then its blob (1, 3, H, W) float32.
rs_status preprocess(rs_detect_net *n, cv::Mat &blob, rs_detect_letterbox *lb, const cv::Mat &frame, rs_err *err)
{
    const int W = n->opt.width_px, H = n->opt.height_px;
    rs_status st = rs_detect_letterbox_of(lb, n->layout.family, frame.cols, frame.rows, W, H, err);
    if (st) return st;
    const cv::Size resized(lb->resized_w, lb->resized_h);
    if (n->layout.family == RS_DETECT_YOLOX) {
        // preproc: a canvas of 114, the frame resized into its top-left corner; BGR, 0..255
        n->canvas.create(H, W, CV_8UC3);
        n->canvas.setTo(cv::Scalar::all(114));
        cv::Mat roi = n->canvas(cv::Rect(0, 0, resized.width, resized.height));
        cv::resize(frame, roi, resized, 0, 0, cv::INTER_LINEAR);
        blob = cv::dnn::blobFromImage(n->canvas, 1.0, cv::Size(), cv::Scalar(), false, false, CV_32F);
    } else {
        // LetterBox: resized only when the size changes, bordered with 114; RGB, /255
        const cv::Mat *src = &frame;
        if (resized != frame.size()) {
            cv::resize(frame, n->resized, resized, 0, 0, cv::INTER_LINEAR);
            src = &n->resized;
        }
        cv::copyMakeBorder(*src, n->canvas, lb->pad_y_px, H - resized.height - lb->pad_y_px, lb->pad_x_px,
                           W - resized.width - lb->pad_x_px, cv::BORDER_CONSTANT, cv::Scalar::all(114));
        blob = cv::dnn::blobFromImage(n->canvas, 1.0 / 255.0, cv::Size(), cv::Scalar(), true, false, CV_32F);
    }
    return RS_OK;
}

// NMS (cv::dnn::NMSBoxes) over the candidates idx: the indices kept, best score first.
void nms(std::vector<int> &kept, const rs_detect_net *n, const std::vector<int> &idx)
{
    std::vector<cv::Rect2d> rects;
    std::vector<float> scores;
    for (int i : idx) {
        const double *b = &n->xyxy[4 * static_cast<size_t>(i)];
        rects.emplace_back(b[0], b[1], b[2] - b[0], b[3] - b[1]);
        scores.push_back(static_cast<float>(n->score[i]));
    }
    std::vector<int> k;
    cv::dnn::NMSBoxes(rects, scores, 0.0f, static_cast<float>(n->opt.nms_iou), k);
    for (int j : k) kept.push_back(idx[j]);
}

} // namespace

extern "C" void rs_detect_set_threads(int n)
{
    try {
        cv::setNumThreads(n);
    } catch (...) {}
}

extern "C" rs_status rs_detect_net_open(rs_detect_net **out, const char *onnx_path, const rs_detect_options *opt,
                                        rs_err *err)
{
    *out = nullptr;
    if (opt->width_px < 32 || opt->height_px < 32 || opt->width_px % 32 || opt->height_px % 32)
        return rs_err_set(err, RS_ERR_INVALID, "the input size %dx%d is not a multiple of 32", opt->width_px,
                          opt->height_px);
    rs_status st = rs_io_check_regular(onnx_path, RS_IO_MAX_FILE_BYTES, err); // read by name by OpenCV
    if (st) return st;
    rs_detect_net *n = new (std::nothrow) rs_detect_net;
    if (!n) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", onnx_path);
    n->opt = *opt;
    st = catching(onnx_path, err, [&]() -> rs_status {
        // the library never prints: OpenCV's importer logs its parse errors, which the message says
        const auto level = cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
        try {
            n->net = cv::dnn::readNetFromONNX(onnx_path);
            cv::utils::logging::setLogLevel(level);
        } catch (const cv::Exception &e) {
            cv::utils::logging::setLogLevel(level);
            return rs_err_set(err, RS_ERR_EXTERNAL, "%s: not an ONNX model OpenCV can load: %s", onnx_path,
                              e.msg.c_str());
        }
        if (n->net.empty()) return rs_err_set(err, RS_ERR_EXTERNAL, "%s: OpenCV loaded an empty network", onnx_path);
        n->net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
        n->net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
        // one run on a grey input: the output's shape tells the family
        const int shape[4] = {1, 3, opt->height_px, opt->width_px};
        cv::Mat probe(4, shape, CV_32F, cv::Scalar(0.5));
        n->net.setInput(probe);
        cv::Mat o;
        try {
            o = n->net.forward();
        } catch (const cv::Exception &e) {
            return rs_err_set(err, RS_ERR_EXTERNAL, "%s: the model fails on a 1x3x%dx%d input: %s", onnx_path,
                              opt->height_px, opt->width_px, e.msg.c_str());
        }
        std::vector<int> dims(o.size.p, o.size.p + o.dims);
        rs_status s =
            rs_detect_layout_of(&n->layout, dims.data(), o.dims, opt->width_px, opt->height_px, opt->family, err);
        if (s) return rs_err_prefix(err, "%s", onnx_path);
        if (o.depth() != CV_32F) return rs_err_set(err, RS_ERR_UNSUPPORTED, "%s: the output is not float32", onnx_path);
        rs_detect_options_resolve(&n->opt, n->layout.family);
        n->xyxy.resize(4 * static_cast<size_t>(n->layout.Nanchors));
        n->score.resize(n->layout.Nanchors);
        n->class_index.resize(n->layout.Nanchors);
        return RS_OK;
    });
    if (st) {
        delete n;
        return st;
    }
    *out = n;
    return RS_OK;
}

extern "C" void rs_detect_net_free(rs_detect_net *net)
{
    try {
        delete net;
    } catch (...) {}
}

extern "C" const rs_detect_layout *rs_detect_net_layout(const rs_detect_net *net) { return &net->layout; }

extern "C" rs_status rs_detect_net_run(rs_detect_net *n, rs_detect_box **boxes, int *Nboxes, rs_detect_timing *timing,
                                       const rs_detect_frame *f, rs_err *err)
{
    *boxes = nullptr;
    *Nboxes = 0;
    if (timing) *timing = rs_detect_timing{};
    return catching("detect", err, [&]() -> rs_status {
        auto t0 = std::chrono::steady_clock::now();
        const cv::Mat frame(f->height, f->width, CV_8UC3, const_cast<unsigned char *>(f->bgr));
        cv::Mat blob;
        rs_detect_letterbox lb;
        rs_status st = preprocess(n, blob, &lb, frame, err);
        if (st) return st;
        const double pre_ms = ms_since(t0);

        t0 = std::chrono::steady_clock::now();
        n->net.setInput(blob);
        cv::Mat out = n->net.forward();
        if (!out.isContinuous()) out = out.clone();
        const double fwd_ms = ms_since(t0);
        const rs_detect_layout *L = &n->layout;
        if (out.total() != static_cast<size_t>(L->Nanchors) * (L->Nclasses + (L->family == RS_DETECT_YOLOX ? 5 : 4)))
            return rs_err_set(err, RS_ERR_INVALID, "the model's output changed size from one frame to the next");

        t0 = std::chrono::steady_clock::now();
        const int Ncand = rs_detect_decode(n->xyxy.data(), n->score.data(), n->class_index.data(), out.ptr<float>(), L,
                                           &lb, n->opt.conf);
        std::vector<int> kept;
        if (L->family == RS_DETECT_YOLOX) { // class-agnostic (demo_utils' default)
            std::vector<int> all(Ncand);
            std::iota(all.begin(), all.end(), 0);
            nms(kept, n, all);
        } else { // per class (ops.non_max_suppression's class offsets)
            std::vector<std::vector<int>> per(L->Nclasses);
            for (int i = 0; i < Ncand; i++) per[n->class_index[i]].push_back(i);
            for (const auto &idx : per)
                if (!idx.empty()) nms(kept, n, idx);
            std::stable_sort(kept.begin(), kept.end(), [n](int a, int b) { return n->score[a] > n->score[b]; });
        }
        if (n->opt.max_dets > 0 && kept.size() > static_cast<size_t>(n->opt.max_dets)) kept.resize(n->opt.max_dets);
        if (!kept.empty()) {
            *boxes = static_cast<rs_detect_box *>(std::calloc(kept.size(), sizeof **boxes));
            if (!*boxes) return rs_err_set(err, RS_ERR_NOMEM, "detect: out of memory");
            for (size_t j = 0; j < kept.size(); j++) {
                const double *b = &n->xyxy[4 * static_cast<size_t>(kept[j])];
                rs_detect_box *d = &(*boxes)[j];
                d->bbox_px[0] = b[0];
                d->bbox_px[1] = b[1];
                d->bbox_px[2] = b[2] - b[0];
                d->bbox_px[3] = b[3] - b[1];
                d->score = n->score[kept[j]];
                d->category_id = n->class_index[kept[j]] + 1;
            }
            *Nboxes = static_cast<int>(kept.size());
        }
        if (timing) *timing = rs_detect_timing{pre_ms, fwd_ms, ms_since(t0)};
        return RS_OK;
    });
}

// ---- frames ----

namespace {

// A still image through core's one image reader (float RGB in [0, 1]) back to 8-bit BGR.
rs_status read_still(rs_detect_frames *f, rs_err *err)
{
    rs_image img;
    rs_status st = rs_image_read(&img, f->name.c_str(), err);
    if (st) return st;
    st = catching(f->name.c_str(), err, [&]() -> rs_status {
        const cv::Mat m(img.height, img.width, CV_MAKETYPE(CV_32F, img.channels), img.data);
        cv::Mat q;
        m.convertTo(q, CV_MAKETYPE(CV_8U, img.channels), 255.0);
        const int code = img.channels == 1   ? cv::COLOR_GRAY2BGR
                         : img.channels == 4 ? cv::COLOR_RGBA2BGR
                                             : cv::COLOR_RGB2BGR;
        cv::cvtColor(q, f->bgr, code);
        return RS_OK;
    });
    rs_image_free(&img);
    return st;
}

} // namespace

extern "C" rs_status rs_detect_frames_open(rs_detect_frames **frames, const char *input, rs_err *err)
{
    *frames = nullptr;
    rs_detect_frames *f = new (std::nothrow) rs_detect_frames;
    if (!f) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", input);
    rs_status st = catching(input, err, [&]() -> rs_status {
        f->name = input;
        f->still = f->done = false;
        f->fps = 0;
        const bool file_url = std::strncmp(input, "file://", 7) == 0;
        const char *path = file_url ? input + 7 : input;
        if (!file_url && std::strstr(input, "://")) {
            // a stream: FFmpeg's own protocols (rtsp, http, ...); nothing to stat
            if (!f->cap.open(input, cv::CAP_FFMPEG))
                return rs_err_set(err, RS_ERR_IO, "%s: cannot open the stream", input);
        } else {
            // stat first: a FIFO or a device handed to OpenCV would wait or read forever
            rs_status s = rs_io_check_regular(path, SIZE_MAX, err);
            if (s) return s;
            f->still = cv::haveImageReader(path);
            if (f->still) {
                f->name = path;
            } else if (!f->cap.open(path, cv::CAP_FFMPEG)) {
                return rs_err_set(err, RS_ERR_IO, "%s: cannot open as an image or a video", input);
            }
        }
        if (!f->still) {
            const double fps = f->cap.get(cv::CAP_PROP_FPS);
            f->fps = std::isfinite(fps) && fps > 0 ? fps : 0;
        }
        return RS_OK;
    });
    if (st) {
        delete f;
        return st;
    }
    *frames = f;
    return RS_OK;
}

extern "C" rs_status rs_detect_frames_next(rs_detect_frames *f, rs_detect_frame *frame, bool *got, rs_err *err)
{
    *frame = rs_detect_frame{};
    *got = false;
    if (f->done) return RS_OK;
    rs_status st;
    if (f->still) {
        f->done = true;
        st = read_still(f, err);
    } else {
        st = catching(f->name.c_str(), err, [&]() -> rs_status {
            cv::Mat raw;
            if (!f->cap.read(raw) || raw.empty()) {
                f->done = true;
                return RS_OK;
            }
            if (raw.type() == CV_8UC3)
                f->bgr = raw.isContinuous() ? raw : raw.clone();
            else if (raw.type() == CV_8UC1)
                cv::cvtColor(raw, f->bgr, cv::COLOR_GRAY2BGR);
            else
                return rs_err_set(err, RS_ERR_UNSUPPORTED, "%s: frames of OpenCV type %d", f->name.c_str(), raw.type());
            return RS_OK;
        });
        if (st == RS_OK && f->done) return RS_OK;
    }
    if (st) return st;
    *frame = rs_detect_frame{f->bgr.ptr<unsigned char>(0), f->bgr.cols, f->bgr.rows};
    *got = true;
    return RS_OK;
}

extern "C" double rs_detect_frames_fps(const rs_detect_frames *frames) { return frames->fps; }

extern "C" void rs_detect_frames_close(rs_detect_frames *frames)
{
    try {
        delete frames;
    } catch (...) {}
}

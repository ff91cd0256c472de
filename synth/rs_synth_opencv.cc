// rs_synth_opencv.cc -- OpenCV shim: image files and resampling (rs_synth_opencv.h).
// Every OpenCV exception is caught here and returned as an rs_status.
extern "C" {
#include "synth/rs_synth_opencv.h"

#include "core/rs_io.h"
}

#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace {

int cv_type(int channels) { return CV_MAKETYPE(CV_32F, channels); }

// A cv::Mat header over an rs_image (no copy).
cv::Mat wrap(const rs_image *img) { return cv::Mat(img->height, img->width, cv_type(img->channels), img->data); }

} // namespace

extern "C" rs_status rs_synth_remap(rs_image *dst, const rs_image *src, const float *map_xy, int width, int height,
                                    int interpolation, rs_err *err)
{
    *dst = rs_image{};
    if (interpolation != cv::INTER_NEAREST && interpolation != cv::INTER_LINEAR && interpolation != cv::INTER_CUBIC)
        return rs_err_set(err, RS_ERR_INVALID, "remap: interpolation %d", interpolation);
    rs_status st = rs_image_alloc(dst, width, height, src->channels, err);
    if (st) return st;
    try {
        cv::Mat map(height, width, CV_32FC2, const_cast<float *>(map_xy));
        cv::Mat out = wrap(dst);
        cv::remap(wrap(src), out, map, cv::noArray(), interpolation, cv::BORDER_CONSTANT, cv::Scalar::all(0));
        return RS_OK;
    } catch (const std::exception &e) {
        rs_image_free(dst);
        return rs_err_set(err, RS_ERR_EXTERNAL, "remap: OpenCV: %s", e.what());
    } catch (...) {
        rs_image_free(dst);
        return rs_err_set(err, RS_ERR_EXTERNAL, "remap: OpenCV: unknown exception");
    }
}

// ---- backgrounds and appearance ----
// Owned by the backgrounds helper (synth/rs_synth_background.h, rs_synth_appearance.h).

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <new>

#include <opencv2/dnn.hpp>
#include <opencv2/videoio.hpp>

struct rs_synth_frames {
    std::string path;
    bool still; // an image file: one frame
    bool done;
    cv::VideoCapture cap;
    cv::Mat rgb; // the current frame, 8-bit RGB, continuous
};

namespace {

// Runs f(), turning every exception into RS_ERR_EXTERNAL naming `what`.
template <class F> rs_status guarded(const char *what, rs_err *err, F f)
{
    try {
        return f();
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "%s: OpenCV: %s", what, e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "%s: OpenCV: unknown exception", what);
    }
}

// Any 8/16-bit or float, 1/3/4-channel BGR(A) frame to continuous 8-bit RGB.
void to_rgb8(const cv::Mat &in, cv::Mat &out)
{
    cv::Mat m = in;
    if (m.depth() == CV_16U)
        m.convertTo(m, CV_8U, 1.0 / 257.0);
    else if (m.depth() != CV_8U)
        m.convertTo(m, CV_8U, 255.0);
    if (m.channels() == 1)
        cv::cvtColor(m, out, cv::COLOR_GRAY2RGB);
    else if (m.channels() == 4)
        cv::cvtColor(m, out, cv::COLOR_BGRA2RGB);
    else
        cv::cvtColor(m, out, cv::COLOR_BGR2RGB);
    if (!out.isContinuous()) out = out.clone();
}

} // namespace

extern "C" rs_status rs_synth_frames_open(rs_synth_frames **frames, const char *path, rs_err *err)
{
    *frames = nullptr;
    rs_synth_frames *f = new (std::nothrow) rs_synth_frames;
    if (!f) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
    rs_status st = guarded(path, err, [&]() -> rs_status {
        f->path = path;
        f->done = false;
        // checked first: OpenCV would print warnings about a missing file (the library never
        // prints); videos through FFmpeg only, without the GStreamer fallback's messages
        if (FILE *probe = std::fopen(path, "rb"))
            std::fclose(probe);
        else
            return rs_err_set(err, RS_ERR_IO, "%s: cannot open: %s", path, std::strerror(errno));
        f->still = cv::haveImageReader(path);
        if (!f->still && !f->cap.open(path, cv::CAP_FFMPEG))
            return rs_err_set(err, RS_ERR_IO, "%s: cannot open as an image or a video", path);
        return RS_OK;
    });
    if (st) {
        delete f;
        return st;
    }
    *frames = f;
    return RS_OK;
}

extern "C" rs_status rs_synth_frames_next(rs_synth_frames *f, const unsigned char **rgb, int *width, int *height,
                                          int *got, rs_err *err)
{
    *rgb = nullptr;
    *got = 0;
    *width = *height = 0;
    if (f->done) return RS_OK;
    return guarded(f->path.c_str(), err, [&]() -> rs_status {
        cv::Mat raw;
        if (f->still) {
            raw = cv::imread(f->path, cv::IMREAD_UNCHANGED);
            f->done = true;
            if (raw.empty()) return rs_err_set(err, RS_ERR_IO, "%s: cannot read the image", f->path.c_str());
        } else if (!f->cap.read(raw) || raw.empty()) {
            f->done = true;
            return RS_OK;
        }
        to_rgb8(raw, f->rgb);
        *rgb = f->rgb.ptr<unsigned char>(0);
        *width = f->rgb.cols;
        *height = f->rgb.rows;
        *got = 1;
        return RS_OK;
    });
}

extern "C" void rs_synth_frames_close(rs_synth_frames *frames)
{
    try {
        delete frames;
    } catch (...) {}
}

namespace {

// Allocates *dst like src and fills it with f(out) (a cv::Mat over *dst) under guarded();
// *dst is freed and zeroed on failure.
template <class F> rs_status into_new(rs_image *dst, const rs_image *src, const char *what, rs_err *err, F f)
{
    *dst = rs_image{};
    rs_status st = rs_image_alloc(dst, src->width, src->height, src->channels, err);
    if (st) return st;
    st = guarded(what, err, [&]() -> rs_status {
        cv::Mat out = wrap(dst);
        f(out);
        return RS_OK;
    });
    if (st) rs_image_free(dst);
    return st;
}

} // namespace

extern "C" rs_status rs_synth_image_filter(rs_image *dst, const rs_image *src, const double *kernel, int kw, int kh,
                                           rs_err *err)
{
    return into_new(dst, src, "filter", err, [&](cv::Mat &out) {
        cv::Mat k(kh, kw, CV_64F, const_cast<double *>(kernel));
        cv::filter2D(wrap(src), out, CV_32F, k, cv::Point(-1, -1), 0, cv::BORDER_REFLECT_101);
    });
}

extern "C" rs_status rs_synth_image_blur(rs_image *dst, const rs_image *src, double sigma_px, rs_err *err)
{
    return into_new(dst, src, "blur", err, [&](cv::Mat &out) {
        if (!(sigma_px > 0)) {
            wrap(src).copyTo(out);
            return;
        }
        const int k = 2 * (int)std::ceil(4.0 * sigma_px) + 1;
        cv::GaussianBlur(wrap(src), out, cv::Size(k, k), sigma_px, sigma_px, cv::BORDER_REFLECT_101);
    });
}

extern "C" rs_status rs_synth_image_jpeg_roundtrip(rs_image *dst, const rs_image *src, int quality, rs_err *err)
{
    *dst = rs_image{};
    if (src->channels != 3 || quality < 1 || quality > 100)
        return rs_err_set(err, RS_ERR_INVALID, "jpeg: needs RGB and quality 1..100 (got %d, %d)", src->channels,
                          quality);
    return into_new(dst, src, "jpeg", err, [&](cv::Mat &out) {
        cv::Mat bgr8;
        wrap(src).convertTo(bgr8, CV_8U, 255.0);
        cv::cvtColor(bgr8, bgr8, cv::COLOR_RGB2BGR);
        std::vector<unsigned char> buf;
        cv::imencode(".jpg", bgr8, buf, {cv::IMWRITE_JPEG_QUALITY, quality});
        cv::Mat dec = cv::imdecode(buf, cv::IMREAD_COLOR);
        cv::cvtColor(dec, dec, cv::COLOR_BGR2RGB);
        dec.convertTo(out, CV_32F, 1.0 / 255.0);
    });
}

extern "C" rs_status rs_synth_dnn_translate(rs_image *dst, const char *onnx_path, const rs_image *src, rs_err *err)
{
    *dst = rs_image{};
    if (src->channels != 3)
        return rs_err_set(err, RS_ERR_INVALID, "%s: the input must be RGB (has %d channels)", onnx_path, src->channels);
    const int H = src->height, W = src->width;
    rs_status st = guarded(onnx_path, err, [&]() -> rs_status {
        cv::dnn::Net net = cv::dnn::readNetFromONNX(onnx_path);
        if (net.empty()) return rs_err_set(err, RS_ERR_IO, "%s: cannot read the ONNX model", onnx_path);
        cv::Mat scaled;
        wrap(src).convertTo(scaled, CV_32F, 2.0, -1.0);
        // HWC RGB -> NCHW, no channel swap, no resize
        net.setInput(cv::dnn::blobFromImage(scaled, 1.0, cv::Size(), cv::Scalar(), false, false, CV_32F));
        cv::Mat y = net.forward();
        if (y.dims != 4 || y.size[0] != 1 || y.size[1] != 3 || y.size[2] != H || y.size[3] != W)
            return rs_err_set(err, RS_ERR_INVALID, "%s: the output is not 1 x 3 x %d x %d", onnx_path, H, W);
        rs_status s = rs_image_alloc(dst, W, H, 3, err);
        if (s) return s;
        const float *p = y.ptr<float>();
        for (int c = 0; c < 3; c++)
            for (int i = 0; i < H * W; i++) {
                const float v = 0.5f * (p[(size_t)c * H * W + i] + 1.0f);
                dst->data[(size_t)i * 3 + c] = v < 0 ? 0 : v > 1 ? 1 : v;
            }
        return RS_OK;
    });
    if (st) rs_image_free(dst);
    return st;
}

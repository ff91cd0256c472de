// rs_synth_opencv.cc -- OpenCV shim: image files and resampling (rs_synth_opencv.h).
// Every OpenCV exception is caught here and returned as an rs_status.
extern "C" {
#include "synth/backdrop/rs_synth_opencv.h"

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
// Owned by the backgrounds helper (synth/backdrop/rs_synth_background.h, rs_synth_appearance.h).

#include <cerrno>
#include <cmath>
#include <cstdint>
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
        // prints) and wait forever on a FIFO; videos through FFmpeg only, without the GStreamer
        // fallback's messages
        const rs_status regular = rs_io_check_regular(path, SIZE_MAX, err);
        if (regular) return regular;
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

// ---- drawing (roadside dataset view) ----

namespace {

cv::Scalar colour(const float *rgb) { return cv::Scalar(rgb[0], rgb[1], rgb[2]); }

// Runs f(m) on a cv::Mat over the RGB image img under guarded().
template <class F> rs_status on_rgb(rs_image *img, const char *what, rs_err *err, F f)
{
    if (img->channels != 3 || !img->data)
        return rs_err_set(err, RS_ERR_INVALID, "%s: needs an RGB image (has %d channels)", what, img->channels);
    return guarded(what, err, [&]() -> rs_status {
        cv::Mat m = wrap(img);
        f(m);
        return RS_OK;
    });
}

const int kShift = 4; // sub-pixel bits of cv::line / cv::circle

cv::Point fixed_point(const double *p)
{
    return cv::Point((int)std::lround(p[0] * (1 << kShift)), (int)std::lround(p[1] * (1 << kShift)));
}

bool drawable(const rs_image *img, const double *p)
{
    return std::isfinite(p[0]) && std::isfinite(p[1]) && std::fabs(p[0]) < 1e6 + img->width &&
           std::fabs(p[1]) < 1e6 + img->height;
}

} // namespace

extern "C" rs_status rs_synth_draw_rect(rs_image *img, int x0, int y0, int x1, int y1, const float *rgb, int thickness,
                                        rs_err *err)
{
    return on_rgb(img, "draw rectangle", err, [&](cv::Mat &m) {
        cv::rectangle(m, cv::Point(x0, y0), cv::Point(x1, y1), colour(rgb), thickness < 1 ? 1 : thickness, cv::LINE_8);
    });
}

extern "C" rs_status rs_synth_draw_line(rs_image *img, const double *p0_px, const double *p1_px, const float *rgb,
                                        int thickness, rs_err *err)
{
    if (!drawable(img, p0_px) || !drawable(img, p1_px)) return RS_OK;
    return on_rgb(img, "draw line", err, [&](cv::Mat &m) {
        cv::line(m, fixed_point(p0_px), fixed_point(p1_px), colour(rgb), thickness < 1 ? 1 : thickness, cv::LINE_8,
                 kShift);
    });
}

extern "C" rs_status rs_synth_draw_dot(rs_image *img, const double *p_px, int radius_px, const float *rgb, rs_err *err)
{
    if (!drawable(img, p_px)) return RS_OK;
    return on_rgb(img, "draw dot", err, [&](cv::Mat &m) {
        cv::circle(m, fixed_point(p_px), (radius_px < 1 ? 1 : radius_px) << kShift, colour(rgb), cv::FILLED, cv::LINE_8,
                   kShift);
    });
}

extern "C" rs_status rs_synth_draw_text(rs_image *img, int x, int y, const char *text, int height_px, const float *rgb,
                                        const float *bg_rgb, int *width_px, rs_err *err)
{
    if (width_px) *width_px = 0;
    return on_rgb(img, "draw text", err, [&](cv::Mat &m) {
        const int font = cv::FONT_HERSHEY_SIMPLEX;
        // getFontScaleFromHeight gives the scale for a full height (ascent + descent); the cap
        // height of Hershey simplex is about 0.7 of it
        const double scale = cv::getFontScaleFromHeight(font, height_px < 4 ? 4 : (int)(height_px / 0.7), 1);
        int base = 0;
        const cv::Size sz = cv::getTextSize(text, font, scale, 1, &base);
        if (bg_rgb)
            cv::rectangle(m, cv::Point(x - 1, y - sz.height - 1), cv::Point(x + sz.width, y + base - 1), colour(bg_rgb),
                          cv::FILLED, cv::LINE_8);
        cv::putText(m, text, cv::Point(x, y), font, scale, colour(rgb), 1, cv::LINE_8);
        if (width_px) *width_px = sz.width;
    });
}

extern "C" rs_status rs_synth_image_resize(rs_image *dst, const rs_image *src, int width, int height, rs_err *err)
{
    *dst = rs_image{};
    rs_status st = rs_image_alloc(dst, width, height, src->channels, err);
    if (st) return st;
    st = guarded("resize", err, [&]() -> rs_status {
        cv::Mat out = wrap(dst);
        const bool shrink = width < src->width || height < src->height;
        cv::resize(wrap(src), out, cv::Size(width, height), 0, 0, shrink ? cv::INTER_AREA : cv::INTER_LINEAR);
        return RS_OK;
    });
    if (st) rs_image_free(dst);
    return st;
}

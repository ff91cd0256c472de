// rs_opencv.cc -- the OpenCV shim of core: OpenCV-style camera files (YAML/JSON) through
// cv::FileStorage, both ways (core/internal/rs_opencv.h), and image files (core/rs_image.h). C++ stays here; every exception is caught at the boundary and
// becomes an rs_status.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <initializer_list>
#include <new>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

extern "C" {
#include "core/internal/rs_opencv.h"
#include "core/rs_image.h"
#include "core/rs_io.h"
}

namespace {

// The numbers of a node (a number, a nested list or an OpenCV matrix) in row-major order;
// false when it holds anything else. An empty matrix or list gives no numbers.
bool node_numbers(const cv::FileNode &node, std::vector<double> &out)
{
    if (node.isInt() || node.isReal()) {
        out.push_back((double)node);
        return true;
    }
    if (node.isSeq()) {
        for (cv::FileNodeIterator it = node.begin(); it != node.end(); ++it)
            if (!node_numbers(*it, out)) return false;
        return true;
    }
    if (!node.isMap() || node["data"].empty()) return false;
    if (node["data"].isSeq() && node["data"].size() == 0) return true;
    cv::Mat m, md;
    node >> m;
    if (m.empty()) return true;
    m.reshape(1, (int)(m.total() * (size_t)m.channels())).convertTo(md, CV_64F);
    for (int i = 0; i < (int)md.total(); i++) out.push_back(md.at<double>(i));
    return true;
}

// Reads the first present key of `keys` into v; *found tells whether any was there. Checks the
// count against `counts` (`need` words them) and that every value is finite.
rs_status read_numbers(std::vector<double> &v, bool *found, const cv::FileStorage &fs,
                       std::initializer_list<const char *> keys, std::initializer_list<size_t> counts, const char *need,
                       const char *path, rs_err *err)
{
    v.clear();
    *found = false;
    for (const char *key : keys) {
        const cv::FileNode node = fs[key];
        if (node.empty()) continue;
        *found = true;
        if (!node_numbers(node, v))
            return rs_err_set(err, RS_ERR_PARSE, "%s: %s: not a number or a matrix of numbers", path, key);
        if (std::find(counts.begin(), counts.end(), v.size()) == counts.end())
            return rs_err_set(err, RS_ERR_INVALID, "%s: %s: %zu values, need %s", path, key, v.size(), need);
        for (size_t i = 0; i < v.size(); i++)
            if (!std::isfinite(v[i]))
                return rs_err_set(err, RS_ERR_INVALID, "%s: %s: value %zu is not finite", path, key, i);
        return RS_OK;
    }
    return RS_OK;
}

// distortion_model: OpenCV's fisheye under its names (OpenCV, ROS's "equidistant", others'
// "kannala_brandt"), any case, sets f->fisheye; other text (ROS's "plumb_bob", ...) is the
// ordinary model.
rs_status read_fisheye(rs_camera_opencv_file *f, const cv::FileStorage &fs, const char *path, rs_err *err)
{
    const cv::FileNode node = fs["distortion_model"];
    if (node.empty()) return RS_OK;
    if (!node.isString()) return rs_err_set(err, RS_ERR_PARSE, "%s: distortion_model: not a text", path);
    std::string name = (std::string)node;
    std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return (char)std::tolower(c); });
    f->fisheye = name == "fisheye" || name == "equidistant" || name == "kannala_brandt";
    return RS_OK;
}

rs_status read_file(rs_camera_opencv_file *f, const char *path, rs_err *err)
{
    cv::FileStorage fs;
    try {
        if (!fs.open(path, cv::FileStorage::READ))
            return rs_err_set(err, RS_ERR_IO, "%s: cannot open as OpenCV FileStorage (YAML/JSON)", path);
    } catch (const cv::Exception &e) {
        return rs_err_set(err, RS_ERR_PARSE,
                          "%s: not valid OpenCV YAML/JSON: %s (OpenCV's YAML starts with a line "
                          "\"%%YAML:1.0\")",
                          path, e.err.c_str());
    }
    std::vector<double> v;
    bool found;
    rs_status st;
    const char *sizes[2] = {"image_width", "image_height"};
    int *size_out[2] = {&f->width, &f->height};
    for (int i = 0; i < 2; i++) {
        const cv::FileNode node = fs[sizes[i]];
        if (node.empty()) continue;
        if (!node.isInt() && !node.isReal())
            return rs_err_set(err, RS_ERR_PARSE, "%s: %s: not a number", path, sizes[i]);
        const double d = (double)node;
        if (!std::isfinite(d) || d < 1 || d > 1e6 || d != std::floor(d))
            return rs_err_set(err, RS_ERR_INVALID, "%s: %s: %g is not a positive whole number of pixels", path,
                              sizes[i], d);
        *size_out[i] = (int)d;
    }
    if ((st = read_fisheye(f, fs, path, err))) return st;
    if ((st = read_numbers(v, &found, fs, {"camera_matrix", "K"}, {9}, "9 (3x3)", path, err))) return st;
    if (!found) return rs_err_set(err, RS_ERR_PARSE, "%s: camera_matrix: missing", path);
    std::copy(v.begin(), v.end(), f->K);
    if ((st = read_numbers(v, &found, fs, {"distortion_coefficients", "D", "dist"}, {0, 4, 5, 8, 12, 14},
                           "0, 4, 5, 8, 12 or 14", path, err)))
        return st;
    f->Ndist = (int)v.size();
    std::copy(v.begin(), v.end(), f->dist);
    if ((st = read_numbers(v, &found, fs, {"R", "R_cam_enu"}, {9}, "9 (3x3)", path, err))) return st;
    f->has_R = f->has_rotation = found;
    if (found) {
        std::copy(v.begin(), v.end(), f->R);
        // the nearest rotation (polar decomposition by SVD), then its Rodrigues vector
        cv::Mat R(3, 3, CV_64F, f->R), w, u, vt;
        cv::SVD::compute(R, w, u, vt);
        cv::Mat Rn = u * vt;
        if (cv::determinant(Rn) <= 0)
            return rs_err_set(err, RS_ERR_INVALID, "%s: R: determinant <= 0, not a rotation", path);
        cv::Mat r;
        cv::Rodrigues(Rn, r);
        for (int i = 0; i < 3; i++) f->rvec[i] = r.at<double>(i);
    } else {
        if ((st = read_numbers(v, &found, fs, {"rvec", "r"}, {3}, "3", path, err))) return st;
        f->has_rotation = found;
        if (found) std::copy(v.begin(), v.end(), f->rvec);
    }
    if ((st = read_numbers(v, &found, fs, {"tvec", "t"}, {3}, "3", path, err))) return st;
    f->has_t = found;
    if (found) std::copy(v.begin(), v.end(), f->t);
    if ((st = read_numbers(v, &found, fs, {"P"}, {12}, "12 (3x4)", path, err))) return st;
    f->has_P = found;
    if (found) std::copy(v.begin(), v.end(), f->P);
    return RS_OK;
}

} // namespace

extern "C" rs_status rs_camera_opencv_read(rs_camera_opencv_file *f, const char *path, rs_err *err)
{
    try {
        *f = rs_camera_opencv_file();
        return read_file(f, path, err);
    } catch (const cv::Exception &e) {
        return rs_err_set(err, RS_ERR_PARSE, "%s: OpenCV could not read it: %s", path, e.err.c_str());
    } catch (const std::bad_alloc &) {
        return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "%s: %s", path, e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "%s: unknown exception from OpenCV", path);
    }
}

extern "C" rs_status rs_camera_opencv_yaml_text(char **text, const double *intrinsics, int Ndistortion,
                                                const double rt_cam_enu[6], int width, int height, rs_err *err)
{
    *text = nullptr;
    try {
        if (Ndistortion < 0) return rs_err_set(err, RS_ERR_USAGE, "Ndistortion = %d", Ndistortion);
        const cv::Matx33d K(intrinsics[0], 0, intrinsics[2], 0, intrinsics[1], intrinsics[3], 0, 0, 1);
        // a pinhole gets 5 zeros: same projection, and readers always find a matrix
        const cv::Mat D = Ndistortion > 0 ? cv::Mat(1, Ndistortion, CV_64F, const_cast<double *>(intrinsics + 4))
                                          : cv::Mat::zeros(1, 5, CV_64F);
        const cv::Matx31d r(rt_cam_enu[0], rt_cam_enu[1], rt_cam_enu[2]);
        const cv::Matx31d t(rt_cam_enu[3], rt_cam_enu[4], rt_cam_enu[5]);
        cv::Matx33d R;
        cv::Rodrigues(r, R);
        // formatted in memory, written by the caller: OpenCV would log its own I/O errors
        cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
        fs << "image_width" << width << "image_height" << height;
        fs << "camera_matrix" << cv::Mat(K);
        fs << "distortion_coefficients" << D;
        fs << "rvec" << cv::Mat(r) << "tvec" << cv::Mat(t) << "R_cam_enu" << cv::Mat(R);
        const std::string s = fs.releaseAndGetString();
        char *out = static_cast<char *>(std::malloc(s.size() + 1));
        if (!out) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        std::memcpy(out, s.c_str(), s.size() + 1);
        *text = out;
        return RS_OK;
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV FileStorage threw: %s", e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV FileStorage threw an unknown exception");
    }
}

// ---- image files (core/rs_image.h) ----

namespace {

int cv_type(int channels) { return CV_MAKETYPE(CV_32F, channels); }

// A cv::Mat header over an rs_image (no copy).
cv::Mat wrap(const rs_image *img) { return cv::Mat(img->height, img->width, cv_type(img->channels), img->data); }

// File extension including the dot ("" when none), for cv::imencode.
std::string extension(const char *path)
{
    const char *slash = std::strrchr(path, '/');
    const char *dot = std::strrchr(path, '.');
    if (!dot || (slash && dot < slash)) return "";
    return dot;
}

} // namespace

extern "C" rs_status rs_image_alloc(rs_image *img, int width, int height, int channels, rs_err *err)
{
    *img = rs_image{};
    if (width <= 0 || height <= 0 || (channels != 1 && channels != 3 && channels != 4))
        return rs_err_set(err, RS_ERR_INVALID, "image: bad size %dx%dx%d", width, height, channels);
    img->data = static_cast<float *>(std::calloc(static_cast<size_t>(width) * height * channels, sizeof(float)));
    if (!img->data) return rs_err_set(err, RS_ERR_NOMEM, "image %dx%d: out of memory", width, height);
    img->width = width;
    img->height = height;
    img->channels = channels;
    return RS_OK;
}

extern "C" void rs_image_free(rs_image *img)
{
    if (!img) return;
    std::free(img->data);
    *img = rs_image{};
}

extern "C" rs_status rs_image_read(rs_image *img, const char *path, rs_err *err)
{
    *img = rs_image{};
    int w = 0, h = 0; // from the header: refused before decoding when too large
    rs_status checked = rs_image_size(&w, &h, path, err);
    if (checked == RS_ERR_UNSUPPORTED) checked = rs_io_check_regular(path, RS_IO_MAX_FILE_BYTES, err);
    if (checked) return checked;
    if ((long long)w * h > RS_IMAGE_MAX_PIXELS)
        return rs_err_set(err, RS_ERR_INVALID, "%s: %dx%d pixels, more than the %lld an image may have: not decoded",
                          path, w, h, RS_IMAGE_MAX_PIXELS);
    try {
        cv::Mat m = cv::imread(path, cv::IMREAD_UNCHANGED);
        if (m.empty())
            return rs_err_set(err, RS_ERR_IO,
                              "%s: cannot read the image (missing, or not an "
                              "image OpenCV can decode)",
                              path);
        double unit;
        switch (m.depth()) {
        case CV_8U: unit = 255.0; break;
        case CV_16U: unit = 65535.0; break;
        case CV_32F: unit = 1.0; break;
        default: return rs_err_set(err, RS_ERR_UNSUPPORTED, "%s: unsupported pixel depth", path);
        }
        const int channels = m.channels();
        if (channels == 3)
            cv::cvtColor(m, m, cv::COLOR_BGR2RGB);
        else if (channels == 4)
            cv::cvtColor(m, m, cv::COLOR_BGRA2RGBA);
        else if (channels != 1)
            return rs_err_set(err, RS_ERR_UNSUPPORTED, "%s: %d channels", path, channels);
        rs_status st = rs_image_alloc(img, m.cols, m.rows, channels, err);
        if (st) return st;
        cv::Mat out = wrap(img);
        m.convertTo(out, cv_type(channels), 1.0 / unit);
        return RS_OK;
    } catch (const std::exception &e) {
        rs_image_free(img);
        return rs_err_set(err, RS_ERR_EXTERNAL, "%s: OpenCV: %s", path, e.what());
    } catch (...) {
        rs_image_free(img);
        return rs_err_set(err, RS_ERR_EXTERNAL, "%s: OpenCV: unknown exception", path);
    }
}

extern "C" rs_status rs_image_read_sized(rs_image *img, const char *path, int width, int height, rs_err *err)
{
    *img = rs_image{};
    int w = 0, h = 0;
    const rs_status sized = rs_image_size(&w, &h, path, err);
    if (sized && sized != RS_ERR_UNSUPPORTED) return sized;
    if (!sized && (w != width || h != height))
        return rs_err_set(err, RS_ERR_INVALID, "%s: the image is %dx%d, expected %dx%d: not decoded", path, w, h, width,
                          height);
    rs_status st = rs_image_read(img, path, err);
    if (!st && (img->width != width || img->height != height)) {
        st = rs_err_set(err, RS_ERR_INVALID, "%s: the image is %dx%d, expected %dx%d", path, img->width, img->height,
                        width, height);
        rs_image_free(img);
    }
    return st;
}

extern "C" rs_status rs_image_write(const char *path, const rs_image *img, int bits, rs_err *err)
{
    if (bits != 8 && bits != 16)
        return rs_err_set(err, RS_ERR_INVALID, "%s: bits must be 8 or 16 (got %d)", path, bits);
    try {
        cv::Mat m = wrap(img), q;
        const double unit = bits == 8 ? 255.0 : 65535.0;
        m.convertTo(q, CV_MAKETYPE(bits == 8 ? CV_8U : CV_16U, img->channels), unit);
        if (img->channels == 3)
            cv::cvtColor(q, q, cv::COLOR_RGB2BGR);
        else if (img->channels == 4)
            cv::cvtColor(q, q, cv::COLOR_RGBA2BGRA);
        std::vector<unsigned char> buf;
        if (!cv::imencode(extension(path), q, buf))
            return rs_err_set(err, RS_ERR_IO, "%s: OpenCV cannot encode this format", path);
        return rs_io_write_file(path, buf.data(), buf.size(), err);
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "%s: OpenCV: %s", path, e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "%s: OpenCV: unknown exception", path);
    }
}

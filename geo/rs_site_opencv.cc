// rs_site_opencv.cc -- OpenCV shim of the site module: camera intrinsics through cv::FileStorage.
// C++ stays here; every exception is caught at the boundary and becomes an rs_status.
#include <cmath>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

extern "C" {
#include "rs_site_opencv.h"
}

namespace {

// Flattens a number, a sequence of numbers (possibly nested: [[fx,0,cx],[0,fy,cy],[0,0,1]]) or
// an OpenCV matrix node into `out`. Returns false if the node holds anything else.
bool flatten_numbers(const cv::FileNode &node, std::vector<double> &out)
{
    if (node.isInt() || node.isReal()) {
        out.push_back((double)node);
        return true;
    }
    if (node.isSeq()) {
        for (cv::FileNodeIterator it = node.begin(); it != node.end(); ++it)
            if (!flatten_numbers(*it, out)) return false;
        return true;
    }
    if (node.isMap() && !node["data"].empty()) {
        cv::Mat m;
        node >> m;
        if (m.empty()) return node["data"].isSeq() && node["data"].size() == 0;
        cv::Mat md;
        m.reshape(1, (int)m.total() * m.channels()).convertTo(md, CV_64F);
        for (int i = 0; i < (int)md.total(); i++) out.push_back(md.at<double>(i));
        return true;
    }
    return false;
}

rs_status read_size(int *v, const cv::FileNode &node, const char *path, const char *field,
                    rs_err *err)
{
    if (node.empty()) return rs_err_set(err, RS_ERR_PARSE, "%s: %s: missing", path, field);
    if (!node.isInt() && !node.isReal())
        return rs_err_set(err, RS_ERR_PARSE, "%s: %s: not a number", path, field);
    double d = (double)node;
    if (!std::isfinite(d) || d < 1 || d > 1e6 || d != std::floor(d))
        return rs_err_set(err, RS_ERR_INVALID, "%s: %s: %g is not a positive whole number of pixels",
                          path, field, d);
    *v = (int)d;
    return RS_OK;
}

rs_status read_intrinsics(double K[9], double dist[14], int *Ndist, int *width, int *height,
                          const char *path, rs_err *err)
{
    cv::FileStorage fs;
    try {
        if (!fs.open(path, cv::FileStorage::READ))
            return rs_err_set(err, RS_ERR_IO, "%s: cannot open as OpenCV FileStorage (YAML/JSON)", path);
    } catch (const cv::Exception &e) {
        return rs_err_set(err, RS_ERR_PARSE,
                          "%s: not valid OpenCV YAML/JSON: %s (OpenCV's YAML starts with a line "
                          "\"%%YAML:1.0\")", path, e.err.c_str());
    }
    rs_status st = read_size(width, fs["image_width"], path, "image_width", err);
    if (st == RS_OK) st = read_size(height, fs["image_height"], path, "image_height", err);
    if (st != RS_OK) return st;

    std::vector<double> k;
    cv::FileNode nk = fs["camera_matrix"];
    if (nk.empty()) return rs_err_set(err, RS_ERR_PARSE, "%s: camera_matrix: missing", path);
    if (!flatten_numbers(nk, k))
        return rs_err_set(err, RS_ERR_PARSE, "%s: camera_matrix: not a matrix of numbers", path);
    if (k.size() != 9)
        return rs_err_set(err, RS_ERR_INVALID, "%s: camera_matrix: %zu values, need 9 (3x3)", path,
                          k.size());

    std::vector<double> d;
    cv::FileNode nd = fs["distortion_coefficients"];
    if (!nd.empty() && !flatten_numbers(nd, d))
        return rs_err_set(err, RS_ERR_PARSE, "%s: distortion_coefficients: not a list of numbers",
                          path);
    size_t n = d.size();
    if (n != 0 && n != 4 && n != 5 && n != 8 && n != 12 && n != 14)
        return rs_err_set(err, RS_ERR_INVALID,
                          "%s: distortion_coefficients: %zu values, need 0, 4, 5, 8, 12 or 14",
                          path, n);
    for (size_t i = 0; i < 9; i++) {
        if (!std::isfinite(k[i]))
            return rs_err_set(err, RS_ERR_INVALID, "%s: camera_matrix: value %zu is not finite", path, i);
        K[i] = k[i];
    }
    for (size_t i = 0; i < n; i++) {
        if (!std::isfinite(d[i]))
            return rs_err_set(err, RS_ERR_INVALID, "%s: distortion_coefficients: value %zu is not finite",
                              path, i);
        dist[i] = d[i];
    }
    *Ndist = (int)n;
    return RS_OK;
}

} // namespace

extern "C" rs_status rs_site_opencv_read_intrinsics(double K[9], double dist[14], int *Ndist,
                                                    int *width, int *height, const char *path,
                                                    rs_err *err)
{
    try {
        return read_intrinsics(K, dist, Ndist, width, height, path, err);
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

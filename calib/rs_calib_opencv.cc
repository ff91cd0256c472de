// rs_calib_opencv.cc -- shim over OpenCV's SVD, pose solvers (IPPE; the solvePnP family for
// the benchmark) and YAML camera files; see rs_calib_opencv.h.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <initializer_list>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

extern "C" {
#include <mrcal/poseutils.h>

#include "rs_calib_opencv.h"
}

extern "C" rs_status rs_calib_opencv_singular_values3(double *s, const double *p, int N,
                                                      rs_err *err)
{
    try {
        const cv::Mat P(N, 3, CV_64F, const_cast<double *>(p)); // read only
        cv::Mat w;
        cv::SVD::compute(P, w, cv::SVD::NO_UV);
        for (int i = 0; i < 3; i++) s[i] = i < w.rows ? w.at<double>(i) : 0.0;
        return RS_OK;
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV SVD threw: %s", e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV SVD threw an unknown exception");
    }
}

extern "C" rs_status rs_calib_opencv_ippe(double *rt_cam_ref, const double *xy,
                                          const double *p_ref, int N, rs_err *err)
{
    try {
        const cv::Mat object(N, 3, CV_64F, const_cast<double *>(p_ref)); // read only
        const cv::Mat image(N, 2, CV_64F, const_cast<double *>(xy));     // read only
        cv::Mat rvec, tvec;
        if (!cv::solvePnP(object, image, cv::Mat::eye(3, 3, CV_64F), cv::noArray(), rvec, tvec,
                          false, cv::SOLVEPNP_IPPE))
            return rs_err_set(err, RS_ERR_DEGENERATE, "IPPE found no pose");
        for (int i = 0; i < 3; i++) {
            rt_cam_ref[i] = rvec.at<double>(i);
            rt_cam_ref[3 + i] = tvec.at<double>(i);
        }
        for (int i = 0; i < 6; i++)
            if (!std::isfinite(rt_cam_ref[i]))
                return rs_err_set(err, RS_ERR_DEGENERATE, "IPPE: non-finite pose");
        return RS_OK;
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV IPPE threw: %s", e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV IPPE threw an unknown exception");
    }
}

extern "C" rs_status rs_calib_opencv_write_yaml(const char *path, const double *intrinsics,
                                                int Ndistortion, const double *rt_cam_enu,
                                                int width, int height, rs_err *err)
{
    try {
        if (Ndistortion < 0)
            return rs_err_set(err, RS_ERR_USAGE, "%s: Ndistortion = %d", path, Ndistortion);
        const cv::Matx33d K(intrinsics[0], 0, intrinsics[2], 0, intrinsics[1], intrinsics[3], 0,
                            0, 1);
        // a pinhole gets 5 zeros: same projection, and readers always find a matrix
        const cv::Mat D = Ndistortion > 0
                              ? cv::Mat(1, Ndistortion, CV_64F, const_cast<double *>(intrinsics + 4))
                              : cv::Mat::zeros(1, 5, CV_64F);
        const cv::Matx31d r(rt_cam_enu[0], rt_cam_enu[1], rt_cam_enu[2]);
        const cv::Matx31d t(rt_cam_enu[3], rt_cam_enu[4], rt_cam_enu[5]);
        cv::Matx33d R;
        cv::Rodrigues(r, R);
        // formatted in memory, written with stdio: OpenCV would log its own I/O errors
        cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY |
                                        cv::FileStorage::FORMAT_YAML);
        fs << "image_width" << width << "image_height" << height;
        fs << "camera_matrix" << cv::Mat(K);
        fs << "distortion_coefficients" << D;
        fs << "rvec" << cv::Mat(r) << "tvec" << cv::Mat(t) << "R_cam_enu" << cv::Mat(R);
        const std::string text = fs.releaseAndGetString();
        FILE *fp = std::fopen(path, "w");
        if (!fp) return rs_err_set(err, RS_ERR_IO, "%s: %s", path, std::strerror(errno));
        const bool ok = std::fwrite(text.data(), 1, text.size(), fp) == text.size();
        if (std::fclose(fp) != 0 || !ok)
            return rs_err_set(err, RS_ERR_IO, "%s: write failed: %s", path, std::strerror(errno));
        return RS_OK;
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "%s: OpenCV FileStorage threw: %s", path, e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "%s: OpenCV FileStorage threw an unknown exception",
                          path);
    }
}

extern "C" rs_status rs_calib_opencv_pnp(double *rt_cam_ref, bool *inlier, const double *p_ref,
                                         const double *q_px, int N, const double *intrinsics,
                                         int Ndistortion, rs_calib_opencv_pnp_method method,
                                         bool refine_lm, double ransac_threshold_px, rs_err *err)
{
    static const char *const names[] = {"ITERATIVE", "EPNP", "SQPNP", "IPPE", "RANSAC"};
    const char *name = (unsigned)method < 5 ? names[method] : "?";
    try {
        if (Ndistortion < 0 || Ndistortion > 14 || (unsigned)method >= 5)
            return rs_err_set(err, RS_ERR_USAGE, "OpenCV %s: Ndistortion = %d", name, Ndistortion);
        const cv::Mat object(N, 3, CV_64F, const_cast<double *>(p_ref)); // read only
        const cv::Mat image(N, 2, CV_64F, const_cast<double *>(q_px));   // read only
        const cv::Matx33d K(intrinsics[0], 0, intrinsics[2], 0, intrinsics[1], intrinsics[3], 0,
                            0, 1);
        const cv::Mat D = Ndistortion > 0
                              ? cv::Mat(1, Ndistortion, CV_64F, const_cast<double *>(intrinsics + 4))
                              : cv::Mat();
        cv::Mat rvec, tvec;
        std::vector<int> inliers;
        bool ok;
        if (method == RS_CALIB_OPENCV_PNP_RANSAC) {
            ok = cv::solvePnPRansac(object, image, K, D, rvec, tvec, false, 100,
                                    (float)ransac_threshold_px, 0.99, inliers,
                                    cv::SOLVEPNP_ITERATIVE);
        } else {
            static const int flags[] = {cv::SOLVEPNP_ITERATIVE, cv::SOLVEPNP_EPNP,
                                        cv::SOLVEPNP_SQPNP, cv::SOLVEPNP_IPPE};
            ok = cv::solvePnP(object, image, K, D, rvec, tvec, false, flags[method]);
            for (int i = 0; i < N; i++) inliers.push_back(i);
        }
        if (!ok || rvec.total() != 3 || tvec.total() != 3)
            return rs_err_set(err, RS_ERR_DEGENERATE, "OpenCV %s found no pose%s", name,
                              method == RS_CALIB_OPENCV_PNP_IPPE
                                  ? " (IPPE needs exactly coplanar landmarks)"
                                  : "");
        rvec.convertTo(rvec, CV_64F);
        tvec.convertTo(tvec, CV_64F);
        if (refine_lm) {
            if (inliers.size() < 3)
                return rs_err_set(err, RS_ERR_DEGENERATE, "OpenCV %s: %zu inliers, too few to refine",
                                  name, inliers.size());
            cv::Mat obj_in((int)inliers.size(), 3, CV_64F), img_in((int)inliers.size(), 2, CV_64F);
            for (size_t k = 0; k < inliers.size(); k++) {
                object.row(inliers[k]).copyTo(obj_in.row((int)k));
                image.row(inliers[k]).copyTo(img_in.row((int)k));
            }
            cv::solvePnPRefineLM(obj_in, img_in, K, D, rvec, tvec);
        }
        for (int i = 0; i < 3; i++) {
            rt_cam_ref[i] = rvec.at<double>(i);
            rt_cam_ref[3 + i] = tvec.at<double>(i);
        }
        for (int i = 0; i < 6; i++)
            if (!std::isfinite(rt_cam_ref[i]))
                return rs_err_set(err, RS_ERR_DEGENERATE, "OpenCV %s: non-finite pose", name);
        if (inlier) {
            for (int i = 0; i < N; i++) inlier[i] = false;
            for (int i : inliers)
                if (i >= 0 && i < N) inlier[i] = true;
        }
        return RS_OK;
    } catch (const cv::Exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV %s threw: %s", name, e.err.c_str());
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV %s threw: %s", name, e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV %s threw an unknown exception", name);
    }
}

// ---- audits (roadside audit, issue 4) ----

extern "C" rs_status rs_calib_opencv_convex_hull(double *area, unsigned char *inside,
                                                 const double *xy, int N, const double *query,
                                                 int Nquery, rs_err *err)
{
    try {
        *area = 0;
        if (inside)
            for (int i = 0; i < Nquery; i++) inside[i] = 0;
        if (N < 3) return RS_OK;
        // single precision: what convexHull, contourArea and pointPolygonTest accept
        std::vector<cv::Point2f> pts((size_t)N), hull;
        for (int i = 0; i < N; i++) pts[(size_t)i] = cv::Point2f((float)xy[2 * i], (float)xy[2 * i + 1]);
        cv::convexHull(pts, hull);
        if (hull.size() < 3) return RS_OK;
        *area = cv::contourArea(hull);
        if (inside && query)
            for (int i = 0; i < Nquery; i++)
                inside[i] = cv::pointPolygonTest(hull, cv::Point2f((float)query[2 * i], (float)query[2 * i + 1]),
                                                 false) >= 0;
        return RS_OK;
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV convexHull threw: %s", e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV convexHull threw an unknown exception");
    }
}

extern "C" rs_status rs_calib_opencv_principal_axes3(double *s, double *Vt, const double *p,
                                                     int N, rs_err *err)
{
    try {
        const cv::Mat P(N, 3, CV_64F, const_cast<double *>(p)); // read only
        cv::Mat w, u, vt;
        cv::SVD::compute(P, w, u, vt, cv::SVD::FULL_UV);
        for (int i = 0; i < 3; i++) s[i] = i < w.rows ? w.at<double>(i) : 0.0;
        for (int i = 0; i < 9; i++) Vt[i] = vt.at<double>(i / 3, i % 3);
        return RS_OK;
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV SVD threw: %s", e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV SVD threw an unknown exception");
    }
}

// ---- images (roadside report) ----

extern "C" rs_status rs_calib_opencv_read_image_bgra(unsigned char **bgra, int *width, int *height,
                                                     const char *path, rs_err *err)
{
    *bgra = NULL;
    *width = *height = 0;
    try {
        cv::Mat img = cv::imread(path, cv::IMREAD_COLOR);
        if (img.empty()) return rs_err_set(err, RS_ERR_PARSE, "%s: not an image OpenCV can read", path);
        cv::Mat out;
        cv::cvtColor(img, out, cv::COLOR_BGR2BGRA);
        size_t row = (size_t)out.cols * 4;
        unsigned char *d = static_cast<unsigned char *>(std::malloc(row * (size_t)out.rows));
        if (!d) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
        for (int y = 0; y < out.rows; y++) memcpy(d + row * (size_t)y, out.ptr<unsigned char>(y), row);
        *bgra = d;
        *width = out.cols;
        *height = out.rows;
        return RS_OK;
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "%s: OpenCV imread threw: %s", path, e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "%s: OpenCV imread threw an unknown exception", path);
    }
}

namespace {

// The numbers of a node (a number, a nested list or an OpenCV matrix) in row-major order;
// false when it holds anything else.
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
    cv::Mat m, md;
    node >> m;
    m.reshape(1, (int)(m.total() * (size_t)m.channels())).convertTo(md, CV_64F);
    for (int i = 0; i < (int)md.total(); i++) out.push_back(md.at<double>(i));
    return true;
}

// Reads the first present key of `keys` into v; *found tells whether any was there. Checks the
// count against `counts` (a 0-terminated list) and that every value is finite.
rs_status read_numbers(std::vector<double> &v, bool *found, const cv::FileStorage &fs,
                       std::initializer_list<const char *> keys, std::initializer_list<int> counts,
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
        bool ok = false;
        for (int c : counts) ok = ok || (size_t)c == v.size();
        if (!ok) return rs_err_set(err, RS_ERR_PARSE, "%s: %s: %zu values, a wrong shape", path, key, v.size());
        for (double d : v)
            if (!std::isfinite(d)) return rs_err_set(err, RS_ERR_INVALID, "%s: %s: a non-finite value", path, key);
        return RS_OK;
    }
    return RS_OK;
}

rs_status read_calibration(rs_calib_opencv_calibration *cal, const char *path, rs_err *err)
{
    cv::FileStorage fs;
    try {
        if (!fs.open(path, cv::FileStorage::READ))
            return rs_err_set(err, RS_ERR_IO, "%s: cannot open as OpenCV FileStorage (YAML/JSON)", path);
    } catch (const cv::Exception &e) {
        return rs_err_set(err, RS_ERR_PARSE, "%s: not valid OpenCV YAML/JSON: %s", path, e.err.c_str());
    }
    std::vector<double> v;
    bool found;
    rs_status st = read_numbers(v, &found, fs, {"camera_matrix", "K"}, {9}, path, err);
    if (st) return st;
    if (!found) return rs_err_set(err, RS_ERR_PARSE, "%s: camera_matrix (or K): missing", path);
    std::copy(v.begin(), v.end(), cal->K);
    if ((st = read_numbers(v, &found, fs, {"distortion_coefficients", "D", "dist"}, {0, 4, 5, 8, 12, 14},
                           path, err)))
        return st;
    cal->Ndist = (int)v.size();
    std::copy(v.begin(), v.end(), cal->dist);
    const char *sizes[2] = {"image_width", "image_height"};
    int *size_out[2] = {&cal->width, &cal->height};
    for (int i = 0; i < 2; i++) {
        if ((st = read_numbers(v, &found, fs, {sizes[i]}, {1}, path, err))) return st;
        if (found && (v[0] < 1 || v[0] > 1e6 || v[0] != std::floor(v[0])))
            return rs_err_set(err, RS_ERR_INVALID, "%s: %s: %g is not a whole number of pixels", path,
                              sizes[i], v[0]);
        *size_out[i] = found ? (int)v[0] : 0;
    }
    if ((st = read_numbers(v, &found, fs, {"R", "R_cam_enu"}, {9}, path, err))) return st;
    cal->has_R = found;
    if (found) {
        std::copy(v.begin(), v.end(), cal->R);
        // the nearest rotation (polar decomposition by SVD), then its Rodrigues vector
        cv::Mat R(3, 3, CV_64F, cal->R), w, u, vt;
        cv::SVD::compute(R, w, u, vt);
        cv::Mat Rn = u * vt;
        if (cv::determinant(Rn) <= 0)
            return rs_err_set(err, RS_ERR_INVALID, "%s: R: determinant <= 0, not a rotation", path);
        cv::Mat r;
        cv::Rodrigues(Rn, r);
        for (int i = 0; i < 3; i++) cal->rvec[i] = r.at<double>(i);
    } else {
        if ((st = read_numbers(v, &found, fs, {"rvec", "r"}, {3}, path, err))) return st;
        if (!found) return rs_err_set(err, RS_ERR_INVALID, "%s: R (or rvec): missing, the rotation is needed", path);
        std::copy(v.begin(), v.end(), cal->rvec);
    }
    if ((st = read_numbers(v, &found, fs, {"tvec", "t"}, {3}, path, err))) return st;
    if (!found) return rs_err_set(err, RS_ERR_INVALID, "%s: tvec (or t): missing, the translation is needed", path);
    std::copy(v.begin(), v.end(), cal->t);
    if ((st = read_numbers(v, &found, fs, {"P"}, {12}, path, err))) return st;
    cal->has_P = found;
    if (found) std::copy(v.begin(), v.end(), cal->P);
    return RS_OK;
}

} // namespace

extern "C" rs_status rs_calib_opencv_read_calibration(rs_calib_opencv_calibration *cal,
                                                      const char *path, rs_err *err)
{
    try {
        *cal = rs_calib_opencv_calibration();
        return read_calibration(cal, path, err);
    } catch (const cv::Exception &e) {
        return rs_err_set(err, RS_ERR_PARSE, "%s: OpenCV threw: %s", path, e.err.c_str());
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "%s: OpenCV threw: %s", path, e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "%s: OpenCV threw an unknown exception", path);
    }
}

extern "C" void rs_calib_r_from_R(double r[3], const double R[9])
{
    mrcal_r_from_R(r, nullptr, R);
    double back[9];
    mrcal_R_from_r(back, nullptr, r);
    double worst = 0;
    for (int i = 0; i < 9; i++) worst = std::max(worst, std::fabs(back[i] - R[i]));
    if (worst <= 1e-12) return;
    // Eigen's AngleAxis goes through a quaternion (Shepperd's method): accurate at and near a
    // half-turn, where both mrcal's and OpenCV's Rodrigues lose it. Eigen does not throw.
    const Eigen::Matrix3d M = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(R);
    const Eigen::AngleAxisd aa(M);
    const Eigen::Vector3d v = aa.axis() * aa.angle();
    for (int i = 0; i < 3; i++) r[i] = v(i);
}

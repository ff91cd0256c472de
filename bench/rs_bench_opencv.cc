// rs_bench_opencv.cc -- the OpenCV shim of the benchmarks: OpenCV's own pose solvers, run as
// OpenCV users run them, to compare roadside's solver against. Every exception is caught at the
// boundary and becomes an rs_status.
#include <cmath>
#include <exception>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

extern "C" {
#include "bench/rs_bench_opencv.h"
}

namespace {
// The pose from landmarks `object` (N,3) and pixels `image` (N,2) through K and D (OpenCV's
// distortion, may be empty), as rs_bench_opencv_pnp documents. May throw.
rs_status pnp(double *rt_cam_ref, bool *inlier, const cv::Mat &object, const cv::Mat &image, int N,
              const cv::Matx33d &K, const cv::Mat &D, rs_bench_opencv_pnp_method method, bool refine_lm,
              double ransac_threshold_px, const char *name, rs_err *err)
{
    {
        cv::Mat rvec, tvec;
        std::vector<int> inliers;
        bool ok;
        if (method == RS_BENCH_OPENCV_PNP_RANSAC) {
            ok = cv::solvePnPRansac(object, image, K, D, rvec, tvec, false, 100, (float)ransac_threshold_px, 0.99,
                                    inliers, cv::SOLVEPNP_ITERATIVE);
        } else {
            static const int flags[] = {cv::SOLVEPNP_ITERATIVE, cv::SOLVEPNP_EPNP, cv::SOLVEPNP_SQPNP,
                                        cv::SOLVEPNP_IPPE};
            ok = cv::solvePnP(object, image, K, D, rvec, tvec, false, flags[method]);
            for (int i = 0; i < N; i++) inliers.push_back(i);
        }
        if (!ok || rvec.total() != 3 || tvec.total() != 3)
            return rs_err_set(err, RS_ERR_DEGENERATE, "OpenCV %s found no pose%s", name,
                              method == RS_BENCH_OPENCV_PNP_IPPE ? " (IPPE needs exactly coplanar landmarks)" : "");
        rvec.convertTo(rvec, CV_64F);
        tvec.convertTo(tvec, CV_64F);
        if (refine_lm) {
            if (inliers.size() < 3)
                return rs_err_set(err, RS_ERR_DEGENERATE, "OpenCV %s: %zu inliers, too few to refine", name,
                                  inliers.size());
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
    }
}

const char *method_name(rs_bench_opencv_pnp_method method)
{
    static const char *const names[] = {"ITERATIVE", "EPNP", "SQPNP", "IPPE", "RANSAC"};
    return (unsigned)method < 5 ? names[method] : "?";
}
} // namespace

#define RS_BENCH_OPENCV_CATCH(name)                                                          \
    catch (const cv::Exception &e)                                                           \
    {                                                                                        \
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV %s threw: %s", name, e.err.c_str()); \
    }                                                                                        \
    catch (const std::exception &e)                                                          \
    {                                                                                        \
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV %s threw: %s", name, e.what());      \
    }                                                                                        \
    catch (...) { return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV %s threw an unknown exception", name); }

extern "C" rs_status rs_bench_opencv_pnp(double *rt_cam_ref, bool *inlier, const double *p_ref, const double *q_px,
                                         int N, const double *intrinsics, int Ndistortion,
                                         rs_bench_opencv_pnp_method method, bool refine_lm, double ransac_threshold_px,
                                         rs_err *err)
{
    const char *name = method_name(method);
    try {
        if (Ndistortion < 0 || Ndistortion > 14 || (unsigned)method >= 5)
            return rs_err_set(err, RS_ERR_USAGE, "OpenCV %s: Ndistortion = %d", name, Ndistortion);
        const cv::Mat object(N, 3, CV_64F, const_cast<double *>(p_ref)); // read only
        const cv::Mat image(N, 2, CV_64F, const_cast<double *>(q_px));   // read only
        const cv::Matx33d K(intrinsics[0], 0, intrinsics[2], 0, intrinsics[1], intrinsics[3], 0, 0, 1);
        const cv::Mat D =
            Ndistortion > 0 ? cv::Mat(1, Ndistortion, CV_64F, const_cast<double *>(intrinsics + 4)) : cv::Mat();
        return pnp(rt_cam_ref, inlier, object, image, N, K, D, method, refine_lm, ransac_threshold_px, name, err);
    }
    RS_BENCH_OPENCV_CATCH(name)
}

extern "C" rs_status rs_bench_opencv_pnp_fisheye(double *rt_cam_ref, bool *inlier, const double *p_ref,
                                                 const double *q_px, int N, const double *intrinsics,
                                                 rs_bench_opencv_pnp_method method, bool refine_lm,
                                                 double ransac_threshold_px, rs_err *err)
{
    const char *name = method_name(method);
    try {
        if ((unsigned)method >= 5) return rs_err_set(err, RS_ERR_USAGE, "OpenCV fisheye: method %d", (int)method);
        const cv::Mat object(N, 3, CV_64F, const_cast<double *>(p_ref)); // read only
        const cv::Mat image(N, 1, CV_64FC2, const_cast<double *>(q_px)); // read only
        const cv::Matx33d K(intrinsics[0], 0, intrinsics[2], 0, intrinsics[1], intrinsics[3], 0, 0, 1);
        const cv::Vec4d D(intrinsics[4], intrinsics[5], intrinsics[6], intrinsics[7]);
        cv::Mat xy; // normalised image coordinates (x/z, y/z)
        cv::fisheye::undistortPoints(image, xy, K, D);
        const double f = 0.5 * (intrinsics[0] + intrinsics[1]);
        return pnp(rt_cam_ref, inlier, object, xy.reshape(1, N), N, cv::Matx33d::eye(), cv::Mat(), method, refine_lm,
                   ransac_threshold_px / f, name, err);
    }
    RS_BENCH_OPENCV_CATCH(name)
}

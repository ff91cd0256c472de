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

extern "C" rs_status rs_bench_opencv_pnp(double *rt_cam_ref, bool *inlier, const double *p_ref, const double *q_px,
                                         int N, const double *intrinsics, int Ndistortion,
                                         rs_bench_opencv_pnp_method method, bool refine_lm, double ransac_threshold_px,
                                         rs_err *err)
{
    static const char *const names[] = {"ITERATIVE", "EPNP", "SQPNP", "IPPE", "RANSAC"};
    const char *name = (unsigned)method < 5 ? names[method] : "?";
    try {
        if (Ndistortion < 0 || Ndistortion > 14 || (unsigned)method >= 5)
            return rs_err_set(err, RS_ERR_USAGE, "OpenCV %s: Ndistortion = %d", name, Ndistortion);
        const cv::Mat object(N, 3, CV_64F, const_cast<double *>(p_ref)); // read only
        const cv::Mat image(N, 2, CV_64F, const_cast<double *>(q_px));   // read only
        const cv::Matx33d K(intrinsics[0], 0, intrinsics[2], 0, intrinsics[1], intrinsics[3], 0, 0, 1);
        const cv::Mat D =
            Ndistortion > 0 ? cv::Mat(1, Ndistortion, CV_64F, const_cast<double *>(intrinsics + 4)) : cv::Mat();
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
    } catch (const cv::Exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV %s threw: %s", name, e.err.c_str());
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV %s threw: %s", name, e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV %s threw an unknown exception", name);
    }
}

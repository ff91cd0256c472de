// rs_calib_opencv.cc -- the OpenCV shim of the pose solver: planarity (cv::SVD), IPPE
// (cv::solvePnP) and SPD inverses (cv::invert). Every exception is caught at the boundary and becomes an rs_status.
#include <cmath>
#include <exception>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

extern "C" {
#include "calib/internal/rs_calib_opencv.h"
}

extern "C" rs_status rs_calib_opencv_singular_values3(double *s, const double *p, int N, rs_err *err)
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

extern "C" rs_status rs_calib_opencv_ippe(double *rt_cam_ref, const double *xy, const double *p_ref, int N, rs_err *err)
{
    try {
        const cv::Mat object(N, 3, CV_64F, const_cast<double *>(p_ref)); // read only
        const cv::Mat image(N, 2, CV_64F, const_cast<double *>(xy));     // read only
        cv::Mat rvec, tvec;
        if (!cv::solvePnP(object, image, cv::Mat::eye(3, 3, CV_64F), cv::noArray(), rvec, tvec, false,
                          cv::SOLVEPNP_IPPE))
            return rs_err_set(err, RS_ERR_DEGENERATE, "IPPE found no pose");
        for (int i = 0; i < 3; i++) {
            rt_cam_ref[i] = rvec.at<double>(i);
            rt_cam_ref[3 + i] = tvec.at<double>(i);
        }
        for (int i = 0; i < 6; i++)
            if (!std::isfinite(rt_cam_ref[i])) return rs_err_set(err, RS_ERR_DEGENERATE, "IPPE: non-finite pose");
        return RS_OK;
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV IPPE threw: %s", e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV IPPE threw an unknown exception");
    }
}

extern "C" rs_status rs_calib_opencv_inverse_spd(double *inv, const double *A, int n, rs_err *err)
{
    try {
        const cv::Mat M(n, n, CV_64F, const_cast<double *>(A)); // read only
        cv::Mat out(n, n, CV_64F, inv);
        if (cv::invert(M, out, cv::DECOMP_CHOLESKY) == 0)
            return rs_err_set(err, RS_ERR_DEGENERATE, "a %dx%d normal matrix is not positive definite", n, n);
        for (int i = 0; i < n * n; i++)
            if (!std::isfinite(inv[i]))
                return rs_err_set(err, RS_ERR_DEGENERATE, "a normal matrix inverse is not finite");
        return RS_OK;
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV invert threw: %s", e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV invert threw an unknown exception");
    }
}

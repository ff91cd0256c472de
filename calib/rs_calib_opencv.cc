// rs_calib_opencv.cc -- shim over OpenCV's SVD, IPPE pose solver and YAML camera files; see
// rs_calib_opencv.h.
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

extern "C" {
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

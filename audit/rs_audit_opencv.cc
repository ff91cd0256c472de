// rs_audit_opencv.cc -- the OpenCV shim of the audit: convex hulls (coverage) and principal
// axes (degeneracy). Every exception is caught at the boundary and becomes an rs_status.
#include <exception>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

extern "C" {
#include "audit/internal/rs_audit_opencv.h"
}

extern "C" rs_status rs_audit_opencv_convex_hull(double *area, unsigned char *inside, const double *xy, int N,
                                                 const double *query, int Nquery, rs_err *err)
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
                inside[i] =
                    cv::pointPolygonTest(hull, cv::Point2f((float)query[2 * i], (float)query[2 * i + 1]), false) >= 0;
        return RS_OK;
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV convexHull threw: %s", e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV convexHull threw an unknown exception");
    }
}

extern "C" rs_status rs_audit_opencv_principal_axes3(double *s, double *Vt, const double *p, int N, rs_err *err)
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

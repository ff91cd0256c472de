// rs_calib_opencv.cc -- the OpenCV shim of the pose solver: planarity (cv::SVD), IPPE
// and SQPnP (cv::solvePnP), SPD inverses (cv::hal::Cholesky64f, cv::invert), their log determinants and
// symmetric eigenproblems (cv::eigen). Every exception is caught at the boundary and becomes an
// rs_status.
#include <algorithm>
#include <cmath>
#include <exception>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/hal/hal.hpp>

extern "C" {
#include "calib/internal/rs_calib_opencv.h"
#include "calib/rs_calib_init.h"
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

extern "C" rs_status rs_calib_opencv_pnp(double *rt_cam_ref, const double *xy, const double *p_ref, int N,
                                         rs_calib_opencv_pnp_method method, rs_err *err)
{
    const char *name = method == RS_CALIB_OPENCV_IPPE ? "IPPE" : "SQPnP";
    try {
        const cv::Mat object(N, 3, CV_64F, const_cast<double *>(p_ref)); // read only
        const cv::Mat image(N, 2, CV_64F, const_cast<double *>(xy));     // read only
        cv::Mat rvec, tvec;
        if (!cv::solvePnP(object, image, cv::Mat::eye(3, 3, CV_64F), cv::noArray(), rvec, tvec, false,
                          method == RS_CALIB_OPENCV_IPPE ? cv::SOLVEPNP_IPPE : cv::SOLVEPNP_SQPNP))
            return rs_err_set(err, RS_ERR_DEGENERATE, "%s found no pose", name);
        for (int i = 0; i < 3; i++) {
            rt_cam_ref[i] = rvec.at<double>(i);
            rt_cam_ref[3 + i] = tvec.at<double>(i);
        }
        for (int i = 0; i < 6; i++)
            if (!std::isfinite(rt_cam_ref[i])) return rs_err_set(err, RS_ERR_DEGENERATE, "%s: non-finite pose", name);
        return RS_OK;
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV %s threw: %s", name, e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV %s threw an unknown exception", name);
    }
}

extern "C" rs_status rs_calib_opencv_undistort(double *xy, const double *q_px, int N, const double *intrinsics,
                                               int Ndistortion, rs_err *err)
{
    if (Ndistortion != 4 && Ndistortion != 5 && Ndistortion != 8 && Ndistortion != 12)
        return rs_err_set(err, RS_ERR_INVALID, "OpenCV undistortion: %d distortion coefficients (4, 5, 8 or 12)",
                          Ndistortion);
    try {
        const cv::Matx33d K(intrinsics[0], 0, intrinsics[2], 0, intrinsics[1], intrinsics[3], 0, 0, 1);
        const cv::Mat D(1, Ndistortion, CV_64F, const_cast<double *>(intrinsics + 4)); // read only
        const cv::Mat src(N, 1, CV_64FC2, const_cast<double *>(q_px));                 // read only
        cv::Mat dst(N, 1, CV_64FC2, xy); // written in place: OpenCV keeps a buffer of the right size
        cv::undistortPoints(src, dst, K, D, cv::noArray(), cv::noArray(),
                            cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 20, 1e-9));
        if (dst.data != reinterpret_cast<uchar *>(xy)) // cannot happen: the size and type are OpenCV's own
            return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV undistortPoints reallocated its output");
        return RS_OK;
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV undistortPoints threw: %s", e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV undistortPoints threw an unknown exception");
    }
}

namespace {
// inv = A^-1 by cv::hal::Cholesky64f, the routine cv::invert(DECOMP_CHOLESKY) calls for n > 3,
// without cv::invert's cv::Mat set-up (most of its cost for these 4x4 to 9x9 matrices: 18% of a
// 4-landmark calibration). For n <= 3 the closed forms cv::invert uses there, through
// cv::Matx::inv (no absolute pivot threshold: only a zero determinant fails). *logdet (may be NULL; n > 3 only): ln det A = 2 sum ln L_ii from a factorisation
// without right-hand side, whose diagonal is L's in both of OpenCV's implementations (its own
// stores 1/L_ii when it also solves; the LAPACK one of Debian's build does not).
bool inverse_spd(double *inv, double *logdet, const double *A, int n)
{
    if (n <= 3) { // fixed-size: no cv::Mat set-up (a third of rs_calib__noise_redundancy's time)
        bool ok = false;
        if (n == 1) {
            ok = A[0] != 0.0;
            inv[0] = 1.0 / A[0];
        } else if (n == 2) {
            const cv::Matx22d I = cv::Matx22d(A).inv(cv::DECOMP_LU, &ok);
            std::copy(I.val, I.val + 4, inv);
        } else {
            const cv::Matx33d I = cv::Matx33d(A).inv(cv::DECOMP_LU, &ok);
            std::copy(I.val, I.val + 9, inv);
        }
        return ok;
    }
    const size_t nn = (size_t)n * (size_t)n, step = (size_t)n * sizeof(double);
    std::vector<double> L(A, A + nn);
    if (logdet) {
        if (!cv::hal::Cholesky64f(L.data(), step, n, nullptr, 0, 0)) return false;
        double sum = 0;
        for (int a = 0; a < n; a++) sum += 2.0 * std::log(L[(size_t)a * (size_t)n + (size_t)a]);
        *logdet = sum;
        std::copy(A, A + nn, L.begin());
    }
    for (int a = 0; a < n; a++)
        for (int b = 0; b < n; b++) inv[a * n + b] = a == b ? 1.0 : 0.0;
    return cv::hal::Cholesky64f(L.data(), step, n, inv, step, n);
}
} // namespace

extern "C" rs_status rs_calib_opencv_inverse_spd(double *inv, const double *A, int n, rs_err *err)
{
    try {
        if (!inverse_spd(inv, nullptr, A, n))
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

extern "C" rs_status rs_calib_opencv_inverse_spd_logdet(double *inv, double *logdet, const double *A, int n,
                                                        rs_err *err)
{
    try {
        double ld = NAN;
        if (!inverse_spd(inv, &ld, A, n))
            return rs_err_set(err, RS_ERR_DEGENERATE, "a %dx%d normal matrix is not positive definite", n, n);
        for (int i = 0; i < n * n; i++)
            if (!std::isfinite(inv[i]))
                return rs_err_set(err, RS_ERR_DEGENERATE, "a normal matrix inverse is not finite");
        if (n > 3) {
            if (!std::isfinite(ld))
                return rs_err_set(err, RS_ERR_DEGENERATE, "a %dx%d normal matrix is not positive definite", n, n);
            *logdet = ld;
            return RS_OK;
        }
        // det A = prod(A_ii) det(D^-1/2 A D^-1/2): the scaled matrix has a unit diagonal, so its
        // determinant lies in (0, 1] and cannot overflow whatever the units of A
        cv::Mat M(n, n, CV_64F);
        double sum = 0;
        for (int a = 0; a < n; a++) sum += std::log(A[a * n + a]);
        for (int a = 0; a < n; a++)
            for (int b = 0; b < n; b++) M.at<double>(a, b) = A[a * n + b] / std::sqrt(A[a * n + a] * A[b * n + b]);
        const double d = cv::determinant(M);
        if (!(d > 0) || !std::isfinite(sum))
            return rs_err_set(err, RS_ERR_DEGENERATE, "a %dx%d normal matrix is not positive definite", n, n);
        *logdet = sum + std::log(d);
        return RS_OK;
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV invert threw: %s", e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV invert threw an unknown exception");
    }
}

extern "C" rs_status rs_calib_opencv_eigen_sym(double *values, double *vectors, const double *A, int n, rs_err *err)
{
    try {
        const cv::Mat M(n, n, CV_64F, const_cast<double *>(A)); // read only
        cv::Mat w(n, 1, CV_64F, values), V(n, n, CV_64F, vectors);
        if (!cv::eigen(M, w, V)) return rs_err_set(err, RS_ERR_DEGENERATE, "a %dx%d eigenproblem failed", n, n);
        return RS_OK;
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV eigen threw: %s", e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV eigen threw an unknown exception");
    }
}

extern "C" rs_status rs_calib_homography_fit(double H_dst_from_src[9], const double *src, const double *dst, int N,
                                             rs_err *err)
{
    try {
        if (N < 4) return rs_err_set(err, RS_ERR_DEGENERATE, "homography: %d point pairs, needs 4", N);
        const cv::Mat s(N, 2, CV_64F, const_cast<double *>(src)); // read only
        const cv::Mat d(N, 2, CV_64F, const_cast<double *>(dst)); // read only
        const cv::Mat H = cv::findHomography(s, d, 0);
        if (H.rows != 3 || H.cols != 3) return rs_err_set(err, RS_ERR_DEGENERATE, "homography: OpenCV found none");
        for (int i = 0; i < 9; i++) H_dst_from_src[i] = H.at<double>(i / 3, i % 3);
        for (int i = 0; i < 9; i++)
            if (!std::isfinite(H_dst_from_src[i]))
                return rs_err_set(err, RS_ERR_DEGENERATE, "homography: OpenCV's is not finite");
        return RS_OK;
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV findHomography threw: %s", e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenCV findHomography threw an unknown exception");
    }
}

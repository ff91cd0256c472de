// rs_calib_refine_ceres.cc -- Ceres shim: the pose refinement with landmark priors (errors in
// variables), optional intrinsics, and the covariance. Contract: rs_calib_refine.h.
//
// Jacobians are analytic (mrcal), not automatic or numeric: the landmark residual is
// r = (q - q_obs)/sigma_px with q = mrcal_project(p_cam), p_cam = mrcal_transform_point_rt(rt, p),
// so dr/drt = dq_dpcam dpcam_drt / sigma, dr/dp = dq_dpcam dpcam_dp / sigma and
// dr/dintrinsics = dq_dintrinsics / sigma (mrcal 2.2 reports dq_dintrinsics densely, (2,Nintr)
// per point; tests/calib/test_refine_jacobian.c checks the whole chain against differences).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <memory>
#include <vector>

// The prebuilt libceres.a shares Eigen's inline functions with this file (one definition
// each, picked by the linker). Under ASan, __SANITIZE_ADDRESS__ makes Eigen switch to its own
// aligned allocator, so a matrix allocated by one copy was freed by the other (ASan:
// bad-free in ceres::CovarianceImpl). glibc's x86-64 malloc is 16-byte aligned, which is what
// Eigen assumes without ASan: keep that assumption in every build.
#ifndef EIGEN_MALLOC_ALREADY_ALIGNED
#define EIGEN_MALLOC_ALREADY_ALIGNED 1
#endif
#include <Eigen/Dense>
#include <ceres/ceres.h>
#include <glog/logging.h>

extern "C" {
#include <mrcal/poseutils.h>

#include "calib/internal/rs_calib_refine.h"
#include "calib/rs_calib.h"
#include "core/rs_pose.h"
}

namespace {

// Ceres reports some conditions (a linear solver failure on an extreme problem, a covariance
// it cannot compute) through glog at WARNING/ERROR, whatever Solver::Options::logging_type
// says, and glog writes those to stderr. The library never prints: while one of these guards
// lives, glog keeps only FATAL messages (which abort anyway), then the level is restored.
class QuietGlog {
  public:
    QuietGlog() : saved_(FLAGS_minloglevel) { FLAGS_minloglevel = google::GLOG_FATAL; }
    ~QuietGlog() { FLAGS_minloglevel = saved_; }
    QuietGlog(const QuietGlog &) = delete;
    QuietGlog &operator=(const QuietGlog &) = delete;

  private:
    int saved_;
};

// The survey prior of one landmark axis with sigma 0 contributes nothing: the axis is held.
double inv_or_zero(double sigma) { return sigma > 0.0 ? 1.0 / sigma : 0.0; }

// One landmark seen by the camera: 2 pixel residuals + 3 survey-prior residuals, so that the
// robust loss acts on the landmark as a whole (an outlier cannot hide by pulling its landmark).
// out (2,n) = dq/dp_cam (2,3) . dp_cam/dx (3,n): the chain rule through the camera frame.
void chain_dq(double *out, const mrcal_point3_t dq_dpcam[2], const double *dpcam_dx, int n)
{
    for (int a = 0; a < 2; a++)
        for (int j = 0; j < n; j++) {
            double s = 0.0;
            for (int k = 0; k < 3; k++) s += dq_dpcam[a].xyz[k] * dpcam_dx[k * n + j];
            out[a * n + j] = s;
        }
}

class LandmarkCost final : public ceres::CostFunction {
  public:
    LandmarkCost(const mrcal_lensmodel_t *lensmodel, int Nintrinsics, const double q_obs[2], double sigma_px,
                 const double p_survey[3], const double sigma_m[3])
        : lensmodel_(lensmodel), Nintrinsics_(Nintrinsics), w_px_(1.0 / sigma_px)
    {
        for (int k = 0; k < 2; k++) q_obs_[k] = q_obs[k];
        for (int k = 0; k < 3; k++) {
            p_survey_[k] = p_survey[k];
            w_m_[k] = inv_or_zero(sigma_m ? sigma_m[k] : 0.0);
        }
        set_num_residuals(5);
        mutable_parameter_block_sizes()->push_back(6);
        mutable_parameter_block_sizes()->push_back(3);
        mutable_parameter_block_sizes()->push_back(Nintrinsics);
    }

    bool Evaluate(double const *const *x, double *residuals, double **jacobians) const override
    {
        const double *rt = x[0], *p = x[1], *intrinsics = x[2];
        const bool want_rt = jacobians && jacobians[0], want_p = jacobians && jacobians[1];
        const bool want_i = jacobians && jacobians[2];
        mrcal_point3_t p_cam;
        double dpcam_drt[18], dpcam_dp[9];
        mrcal_transform_point_rt(p_cam.xyz, want_rt ? dpcam_drt : nullptr, want_p ? dpcam_dp : nullptr, rt, p);
        mrcal_point2_t q;
        mrcal_point3_t dq_dpcam[2];
        std::vector<double> dq_di(want_i ? 2 * (size_t)Nintrinsics_ : 0);
        if (!mrcal_project(&q, dq_dpcam, want_i ? dq_di.data() : nullptr, &p_cam, 1, lensmodel_, intrinsics))
            return false;
        residuals[0] = (q.x - q_obs_[0]) * w_px_;
        residuals[1] = (q.y - q_obs_[1]) * w_px_;
        for (int k = 0; k < 3; k++) residuals[2 + k] = (p[k] - p_survey_[k]) * w_m_[k];
        if (!std::isfinite(residuals[0]) || !std::isfinite(residuals[1])) return false;

        if (want_rt) chain(jacobians[0], dq_dpcam, dpcam_drt, 6); // (5,6)
        if (want_p) {
            chain(jacobians[1], dq_dpcam, dpcam_dp, 3); // (5,3)
            for (int k = 0; k < 3; k++) jacobians[1][(2 + k) * 3 + k] = w_m_[k];
        }
        if (want_i) {
            double *J = jacobians[2]; // (5,Nintrinsics)
            std::memset(J, 0, sizeof(double) * 5 * (size_t)Nintrinsics_);
            for (int a = 0; a < 2; a++)
                for (int j = 0; j < Nintrinsics_; j++)
                    J[a * Nintrinsics_ + j] = dq_di[(size_t)a * Nintrinsics_ + j] * w_px_;
        }
        return true;
    }

  private:
    // J (5,n) = [dq_dpcam (2,3) . dpcam_dx (3,n) / sigma_px ; 0 (3,n)]
    void chain(double *J, const mrcal_point3_t dq_dpcam[2], const double *dpcam_dx, int n) const
    {
        std::memset(J, 0, sizeof(double) * 5 * (size_t)n);
        chain_dq(J, dq_dpcam, dpcam_dx, n);
        for (int j = 0; j < 2 * n; j++) J[j] *= w_px_;
    }

    const mrcal_lensmodel_t *lensmodel_;
    int Nintrinsics_;
    double w_px_;
    double q_obs_[2], p_survey_[3], w_m_[3];
};

// A landmark at its surveyed position, its survey sigmas folded into the pixel residual:
// r (2) = W (q(rt, p_survey) - q_obs), W = L^-1 with L L^T = sigma_px^2 I + J_p S J_p^T computed
// once, at the pose given to the constructor (rs_calib_refine_options.marginal).
class MarginalCost final : public ceres::CostFunction {
  public:
    MarginalCost(const mrcal_lensmodel_t *lensmodel, int Nintrinsics, const double q_obs[2], double sigma_px,
                 const double p_survey[3], const double sigma_m[3], const double rt0[6], const double *intrinsics0)
        : lensmodel_(lensmodel), Nintrinsics_(Nintrinsics)
    {
        for (int k = 0; k < 2; k++) q_obs_[k] = q_obs[k];
        for (int k = 0; k < 3; k++) p_survey_[k] = p_survey[k];
        mrcal_point3_t p_cam;
        double dpcam_dp[9];
        mrcal_transform_point_rt(p_cam.xyz, nullptr, dpcam_dp, rt0, p_survey);
        mrcal_point2_t q;
        mrcal_point3_t dq_dpcam[2];
        double C[3] = {sigma_px * sigma_px, 0.0, sigma_px * sigma_px}; // C00, C01, C11
        if (sigma_m && mrcal_project(&q, dq_dpcam, nullptr, &p_cam, 1, lensmodel, intrinsics0)) {
            double Jp[2][3];
            chain_dq(&Jp[0][0], dq_dpcam, dpcam_dp, 3);
            for (int k = 0; k < 3; k++) {
                const double v = sigma_m[k] * sigma_m[k];
                C[0] += Jp[0][k] * Jp[0][k] * v;
                C[1] += Jp[0][k] * Jp[1][k] * v;
                C[2] += Jp[1][k] * Jp[1][k] * v;
            }
        }
        const double a = std::sqrt(C[0]), b = C[1] / a, c = std::sqrt(C[2] - b * b);
        W_[0] = 1.0 / a;
        W_[1] = 0.0;
        W_[2] = -b / (a * c);
        W_[3] = 1.0 / c;
        set_num_residuals(2);
        mutable_parameter_block_sizes()->push_back(6);
        mutable_parameter_block_sizes()->push_back(Nintrinsics);
    }

    bool Evaluate(double const *const *x, double *residuals, double **jacobians) const override
    {
        const double *rt = x[0], *intrinsics = x[1];
        const bool want_rt = jacobians && jacobians[0], want_i = jacobians && jacobians[1];
        mrcal_point3_t p_cam;
        double dpcam_drt[18];
        mrcal_transform_point_rt(p_cam.xyz, want_rt ? dpcam_drt : nullptr, nullptr, rt, p_survey_);
        mrcal_point2_t q;
        mrcal_point3_t dq_dpcam[2];
        std::vector<double> dq_di(want_i ? 2 * (size_t)Nintrinsics_ : 0);
        if (!mrcal_project(&q, dq_dpcam, want_i ? dq_di.data() : nullptr, &p_cam, 1, lensmodel_, intrinsics))
            return false;
        const double e[2] = {q.x - q_obs_[0], q.y - q_obs_[1]};
        residuals[0] = W_[0] * e[0] + W_[1] * e[1];
        residuals[1] = W_[2] * e[0] + W_[3] * e[1];
        if (!std::isfinite(residuals[0]) || !std::isfinite(residuals[1])) return false;
        if (want_rt) {
            double dq[2][6];
            chain_dq(&dq[0][0], dq_dpcam, dpcam_drt, 6);
            for (int j = 0; j < 6; j++) {
                jacobians[0][j] = W_[0] * dq[0][j] + W_[1] * dq[1][j];
                jacobians[0][6 + j] = W_[2] * dq[0][j] + W_[3] * dq[1][j];
            }
        }
        if (want_i)
            for (int j = 0; j < Nintrinsics_; j++) {
                const double d0 = dq_di[(size_t)j], d1 = dq_di[(size_t)Nintrinsics_ + j];
                jacobians[1][j] = W_[0] * d0 + W_[1] * d1;
                jacobians[1][Nintrinsics_ + j] = W_[2] * d0 + W_[3] * d1;
            }
        return true;
    }

  private:
    const mrcal_lensmodel_t *lensmodel_;
    int Nintrinsics_;
    double q_obs_[2], p_survey_[3], W_[4];
};

// Prior on the camera centre C = -R^T t (a surveyed pole): (C - C_prior)/sigma.
class PositionPriorCost final : public ceres::SizedCostFunction<3, 6> {
  public:
    PositionPriorCost(const double C_prior[3], double sigma_m) : w_(1.0 / sigma_m)
    {
        for (int k = 0; k < 3; k++) C_prior_[k] = C_prior[k];
    }
    bool Evaluate(double const *const *x, double *residuals, double **jacobians) const override
    {
        double J[18];
        double C[3];
        rs_pose_position_from_rt(C, (jacobians && jacobians[0]) ? J : nullptr, x[0]);
        for (int k = 0; k < 3; k++) residuals[k] = (C[k] - C_prior_[k]) * w_;
        if (jacobians && jacobians[0])
            for (int k = 0; k < 18; k++) jacobians[0][k] = J[k] * w_;
        return true;
    }

  private:
    double C_prior_[3], w_;
};

// The refined intrinsics: x = x_start + B delta with B's orthonormal columns spanning the
// refined directions (the focal direction (fx0, fy0, 0...)/|.|, unit vectors for the centre
// and the distortion coefficients). A linear subspace, so Minus is exact: B^T (y - x).
class SubspaceManifold final : public ceres::Manifold {
  public:
    SubspaceManifold(int n, std::vector<double> B_colmajor)
        : n_(n), k_((int)(B_colmajor.size() / (size_t)n)), B_(std::move(B_colmajor))
    {}
    int AmbientSize() const override { return n_; }
    int TangentSize() const override { return k_; }
    bool Plus(const double *x, const double *delta, double *x_plus_delta) const override
    {
        for (int i = 0; i < n_; i++) {
            double s = x[i];
            for (int j = 0; j < k_; j++) s += B(i, j) * delta[j];
            x_plus_delta[i] = s;
        }
        return true;
    }
    bool PlusJacobian(const double *, double *jacobian) const override
    {
        for (int i = 0; i < n_; i++)
            for (int j = 0; j < k_; j++) jacobian[i * k_ + j] = B(i, j);
        return true;
    }
    bool Minus(const double *y, const double *x, double *y_minus_x) const override
    {
        for (int j = 0; j < k_; j++) {
            double s = 0.0;
            for (int i = 0; i < n_; i++) s += B(i, j) * (y[i] - x[i]);
            y_minus_x[j] = s;
        }
        return true;
    }
    bool MinusJacobian(const double *, double *jacobian) const override
    {
        for (int j = 0; j < k_; j++)
            for (int i = 0; i < n_; i++) jacobian[j * n_ + i] = B(i, j);
        return true;
    }

  private:
    double B(int i, int j) const { return B_[(size_t)j * n_ + i]; }
    int n_, k_;
    std::vector<double> B_;
};

// Priors of the refined intrinsics about their nominal values, one residual per prior.
class IntrinsicsPriorCost final : public ceres::CostFunction {
  public:
    // rows: (index into intrinsics, nominal, weight)
    struct Row {
        int index;
        double nominal, weight;
    };
    IntrinsicsPriorCost(int Nintrinsics, std::vector<Row> rows) : Nintrinsics_(Nintrinsics), rows_(std::move(rows))
    {
        set_num_residuals((int)rows_.size());
        mutable_parameter_block_sizes()->push_back(Nintrinsics);
    }
    bool Evaluate(double const *const *x, double *residuals, double **jacobians) const override
    {
        for (size_t r = 0; r < rows_.size(); r++)
            residuals[r] = (x[0][rows_[r].index] - rows_[r].nominal) * rows_[r].weight;
        if (jacobians && jacobians[0]) {
            std::memset(jacobians[0], 0, sizeof(double) * rows_.size() * (size_t)Nintrinsics_);
            for (size_t r = 0; r < rows_.size(); r++)
                jacobians[0][r * (size_t)Nintrinsics_ + (size_t)rows_[r].index] = rows_[r].weight;
        }
        return true;
    }

  private:
    int Nintrinsics_;
    std::vector<Row> rows_;
};

// Builds the subspace basis (column-major, Nintrinsics x k) and the prior rows.
void intrinsics_subspace(std::vector<double> *B, std::vector<IntrinsicsPriorCost::Row> *rows, int Nintrinsics,
                         const double *nominal, const rs_calib_refine_options *opt)
{
    auto unit = [&](int i) {
        size_t c = B->size();
        B->resize(c + (size_t)Nintrinsics, 0.0);
        (*B)[c + (size_t)i] = 1.0;
    };
    if (opt->refine & RS_CALIB_REFINE_FOCAL) {
        const double n = std::hypot(nominal[0], nominal[1]);
        size_t c = B->size();
        B->resize(c + (size_t)Nintrinsics, 0.0);
        (*B)[c + 0] = nominal[0] / n;
        (*B)[c + 1] = nominal[1] / n;
        if (opt->focal_prior_rel_sigma > 0.0)
            rows->push_back({0, nominal[0], 1.0 / (opt->focal_prior_rel_sigma * nominal[0])});
    }
    if (opt->refine & RS_CALIB_REFINE_CENTER)
        for (int i = 2; i < 4; i++) {
            unit(i);
            if (opt->center_prior_sigma_px > 0.0) rows->push_back({i, nominal[i], 1.0 / opt->center_prior_sigma_px});
        }
    if (opt->refine & RS_CALIB_REFINE_DISTORTION)
        for (int i = 4; i < Nintrinsics; i++) {
            unit(i);
            if (opt->distortion_prior_sigma > 0.0) rows->push_back({i, nominal[i], 1.0 / opt->distortion_prior_sigma});
        }
}

// Condition number of the Jacobian with the landmarks eliminated, computed without forming
// normal equations (pixel sigmas of 1e-3 px against survey sigmas of metres make J^T J lose
// every digit): the rows of each landmark's residual block are projected onto the orthogonal
// complement of that landmark's columns (Householder QR of its (rows x <=3) block), the
// projected head columns of all landmarks (and the rows without a landmark) are stacked, their
// columns scaled to unit norm, and sigma_max/sigma_min of that matrix is returned (inf when
// singular). Equilibration makes the number independent of units (radians against metres).
// Also returns the covariance of the head in its tangent space, (Rd^T Rd)^-1 from the SVD of
// the equilibrated Rd, in *cov_tangent (may be NULL), and the ratio of the largest to the
// smallest column norm of the whole Jacobian in *column_range (may be NULL).
double reduced_condition(ceres::Problem *problem, const std::vector<double *> &head,
                         const std::vector<double *> &landmarks, Eigen::MatrixXd *cov_tangent, double *column_range)
{
    ceres::Problem::EvaluateOptions eo;
    eo.parameter_blocks = head;
    eo.parameter_blocks.insert(eo.parameter_blocks.end(), landmarks.begin(), landmarks.end());
    eo.apply_loss_function = false;
    ceres::CRSMatrix crs;
    if (!problem->Evaluate(eo, nullptr, nullptr, nullptr, &crs)) return INFINITY;
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
    for (int r = 0; r < crs.num_rows; r++)
        for (int k = crs.rows[(size_t)r]; k < crs.rows[(size_t)r + 1]; k++)
            J(r, crs.cols[(size_t)k]) = crs.values[(size_t)k];
    int nh = 0;
    for (double *b : head) nh += problem->ParameterBlockTangentSize(b);

    // the landmark owning each row (-1: none), by its columns
    std::vector<int> first_col, size;
    int col = nh;
    for (double *b : landmarks) {
        first_col.push_back(col);
        size.push_back(problem->ParameterBlockTangentSize(b));
        col += size.back();
    }
    std::vector<std::vector<int>> rows_of(landmarks.size());
    std::vector<int> free_rows;
    for (int r = 0; r < J.rows(); r++) {
        int owner = -1;
        for (size_t l = 0; l < landmarks.size() && owner < 0; l++)
            if (J.row(r).segment(first_col[l], size[l]).squaredNorm() > 0.0) owner = (int)l;
        if (owner < 0)
            free_rows.push_back(r);
        else
            rows_of[(size_t)owner].push_back(r);
    }
    std::vector<Eigen::MatrixXd> pieces;
    int m = (int)free_rows.size();
    {
        Eigen::MatrixXd F(free_rows.size(), nh);
        for (size_t k = 0; k < free_rows.size(); k++) F.row((Eigen::Index)k) = J.row(free_rows[k]).head(nh);
        pieces.push_back(F);
    }
    for (size_t l = 0; l < landmarks.size(); l++) {
        const int nr = (int)rows_of[l].size(), nl = size[l];
        if (nr <= nl) continue; // nothing left once the landmark is solved for
        Eigen::MatrixXd Jl(nr, nl), Jh(nr, nh);
        for (int k = 0; k < nr; k++) {
            Jl.row(k) = J.row(rows_of[l][(size_t)k]).segment(first_col[l], nl);
            Jh.row(k) = J.row(rows_of[l][(size_t)k]).head(nh);
        }
        Eigen::HouseholderQR<Eigen::MatrixXd> qr(Jl);
        const Eigen::MatrixXd QtJh = qr.householderQ().transpose() * Jh;
        pieces.push_back(QtJh.bottomRows(nr - nl));
        m += nr - nl;
    }
    Eigen::MatrixXd Rd(m, nh);
    int row = 0;
    for (const Eigen::MatrixXd &p : pieces) {
        Rd.middleRows(row, p.rows()) = p;
        row += (int)p.rows();
    }
    if (column_range) {
        double cmax = 0.0, cmin = INFINITY;
        for (int j = 0; j < J.cols(); j++) {
            cmax = std::fmax(cmax, J.col(j).norm());
            cmin = std::fmin(cmin, J.col(j).norm());
        }
        *column_range = cmax / cmin;
    }
    if (m < nh) return INFINITY;
    Eigen::VectorXd scale(nh);
    for (int j = 0; j < nh; j++) {
        const double n = Rd.col(j).norm();
        if (!(n > 0.0) || !std::isfinite(n)) return INFINITY;
        Rd.col(j) /= n;
        scale(j) = 1.0 / n;
    }
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(Rd, Eigen::ComputeThinV);
    const auto &sv = svd.singularValues();
    const double smax = sv(0), smin = sv(nh - 1);
    if (!(smin > 0.0) || !std::isfinite(smax)) return INFINITY;
    if (cov_tangent) {
        const Eigen::MatrixXd W = svd.matrixV() * sv.cwiseInverse().asDiagonal();
        *cov_tangent = scale.asDiagonal() * (W * W.transpose()) * scale.asDiagonal();
    }
    return smax / smin;
}

// Beyond this condition number of the Jacobian the covariance is numerical noise.
const double kConditionSingular = 1e7;
// Beyond this ratio of the largest to the smallest column norm of the Jacobian, SuiteSparseQR's
// rank test inside ceres::Covariance (tolerance relative to the largest column) declares
// well-determined problems rank-deficient (pixel sigmas of 1e-3 px against survey sigmas of
// metres); the covariance then comes from the landmark-eliminated, equilibrated QR instead.
const double kColumnRangeCeres = 1e7;
// Up to this many free parameters ceres::Covariance factors with Eigen's sparse QR, beyond it
// with SuiteSparseQR (roadside bench calib: 20 landmarks, 66 parameters, faster with Eigen;
// 50 landmarks, 156, and more, faster with SuiteSparse).
const int kEigenCovarianceMax = 100;

rs_status refine(double rt[6], double *intrinsics, double *p_c, rs_calib_refine_summary *summary, double *cov,
                 double *block_chi2, double *q_pred, const rs_calib_refine_problem *pb,
                 const rs_calib_refine_options *opt, rs_err *err)
{
    const int Ni = mrcal_lensmodel_num_params(pb->lensmodel);
    if (Ni < 4 || pb->N < 0) return rs_err_set(err, RS_ERR_INVALID, "refine: bad sizes");
    const bool refine_i = opt->refine != RS_CALIB_REFINE_NONE;

    // Cost functions are owned here (the landmarks' also evaluate the unused ones at the end);
    // declared before the problem so that they outlive it.
    if (opt->marginal && opt->covariance)
        return rs_err_set(err, RS_ERR_USAGE, "refine: a marginal pass gives no covariance");
    std::vector<std::unique_ptr<LandmarkCost>> costs((size_t)pb->N);
    std::vector<std::unique_ptr<MarginalCost>> mcosts(opt->marginal ? (size_t)pb->N : 0);
    std::vector<std::unique_ptr<ceres::CostFunction>> priors;
    ceres::Problem::Options po;
    po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    po.loss_function_ownership = ceres::TAKE_OWNERSHIP;
    po.manifold_ownership = ceres::TAKE_OWNERSHIP;
    ceres::Problem problem(po);
    std::vector<double *> landmarks;
    int Nresiduals = 0, Nfree = 6;
    problem.AddParameterBlock(rt, 6);
    problem.AddParameterBlock(intrinsics, Ni);

    for (int i = 0; i < pb->N; i++) {
        const double *sig = pb->sigma_enu_m ? &pb->sigma_enu_m[3 * i] : nullptr;
        costs[(size_t)i].reset(new LandmarkCost(pb->lensmodel, Ni, &pb->q_px[2 * i],
                                                pb->sigma_px ? pb->sigma_px[i] : 1.0, &pb->p_survey_c_m[3 * i], sig));
        if (opt->marginal)
            mcosts[(size_t)i].reset(new MarginalCost(pb->lensmodel, Ni, &pb->q_px[2 * i],
                                                     pb->sigma_px ? pb->sigma_px[i] : 1.0, &pb->p_survey_c_m[3 * i],
                                                     sig, rt, intrinsics));
        if (pb->use && !pb->use[i]) continue;
        ceres::LossFunction *loss = opt->robust_scale > 0.0 ? new ceres::CauchyLoss(opt->robust_scale) : nullptr;
        if (opt->marginal) {
            problem.AddResidualBlock(mcosts[(size_t)i].get(), loss, rt, intrinsics);
            Nresiduals += 2;
            continue;
        }
        problem.AddResidualBlock(costs[(size_t)i].get(), loss, rt, &p_c[3 * i], intrinsics);
        Nresiduals += 2;
        std::vector<int> held;
        for (int k = 0; k < 3; k++) {
            if (sig && sig[k] > 0.0) {
                Nresiduals++;
                Nfree++;
            } else {
                held.push_back(k);
            }
        }
        if (held.size() == 3)
            problem.SetParameterBlockConstant(&p_c[3 * i]);
        else {
            if (!held.empty()) problem.SetManifold(&p_c[3 * i], new ceres::SubsetManifold(3, held));
            landmarks.push_back(&p_c[3 * i]);
        }
    }
    if (pb->has_position_prior) {
        priors.emplace_back(new PositionPriorCost(pb->prior_position_c_m, pb->prior_sigma_m));
        problem.AddResidualBlock(priors.back().get(), nullptr, rt);
        Nresiduals += 3;
    }
    if (refine_i) {
        std::vector<double> B;
        std::vector<IntrinsicsPriorCost::Row> rows;
        intrinsics_subspace(&B, &rows, Ni, pb->intrinsics_nominal, opt);
        Nfree += (int)(B.size() / (size_t)Ni);
        problem.SetManifold(intrinsics, new SubspaceManifold(Ni, B));
        if (!rows.empty()) {
            Nresiduals += (int)rows.size();
            priors.emplace_back(new IntrinsicsPriorCost(Ni, rows));
            problem.AddResidualBlock(priors.back().get(), nullptr, intrinsics);
        }
    } else {
        problem.SetParameterBlockConstant(intrinsics);
    }

    ceres::Solver::Options so;
    // DENSE_SCHUR first: the landmarks are eliminated, about 2x faster than DENSE_QR with free
    // landmarks. With pixel sigmas far below the survey sigmas (1e-3 px against metres) the
    // Schur complement's Cholesky factorisation can fail step after step (Ceres' glog messages
    // about it are silenced by QuietGlog); then the solve is restarted from the same start with
    // DENSE_QR, which forms no normal equations (tests/calib/test_stress_random: 42 of 3000
    // random problems did not converge with DENSE_SCHUR alone, 4 with DENSE_QR alone).
    so.linear_solver_type = ceres::DENSE_SCHUR;
    so.max_num_iterations = opt->max_iterations > 0 ? opt->max_iterations : 100;
    // tight: noise-free data must give the truth to 1e-9; a rough pass only needs the basin
    so.function_tolerance = opt->rough ? 1e-6 : 1e-12;
    so.parameter_tolerance = opt->rough ? 1e-8 : 1e-12;
    so.gradient_tolerance = opt->rough ? 1e-10 : 1e-14;
    so.logging_type = ceres::SILENT;
    so.minimizer_progress_to_stdout = false;
    so.num_threads = 1;
    const std::vector<double> rt0(rt, rt + 6), p0(p_c, p_c + 3 * (size_t)pb->N), i0(intrinsics, intrinsics + Ni);
    ceres::Solver::Summary sum;
    ceres::Solve(so, &problem, &sum);
    int iterations = (int)sum.iterations.size();
    if (!sum.IsSolutionUsable() || sum.termination_type == ceres::NO_CONVERGENCE) {
        std::copy(rt0.begin(), rt0.end(), rt);
        std::copy(p0.begin(), p0.end(), p_c);
        std::copy(i0.begin(), i0.end(), intrinsics);
        so.linear_solver_type = ceres::DENSE_QR;
        ceres::Solve(so, &problem, &sum);
        iterations += (int)sum.iterations.size();
    }
    summary->iterations = iterations;
    summary->Nresiduals = Nresiduals;
    summary->Nfree = Nfree;
    summary->condition_number = NAN;
    if (!sum.IsSolutionUsable() || (sum.termination_type == ceres::NO_CONVERGENCE && !opt->rough))
        return rs_err_set(err, RS_ERR_NOCONVERGE, "refine: Ceres did not converge in %d iterations (%s)",
                          summary->iterations, sum.message.c_str());

    // Per-landmark statistics and the whitened chi2, loss not applied.
    for (int i = 0; i < pb->N; i++) {
        double r[5] = {0, 0, 0, 0, 0};
        const double *x[3] = {rt, &p_c[3 * i], intrinsics};
        const double *xm[2] = {rt, intrinsics};
        const bool ok =
            opt->marginal ? mcosts[(size_t)i]->Evaluate(xm, r, nullptr) : costs[(size_t)i]->Evaluate(x, r, nullptr);
        if (!ok) {
            if (pb->use && !pb->use[i]) { // an outlier that no longer projects: report it as such
                if (block_chi2) block_chi2[i] = INFINITY;
                if (q_pred) q_pred[2 * i] = q_pred[2 * i + 1] = NAN;
                continue;
            }
            return rs_err_set(err, RS_ERR_DEGENERATE, "landmark %d: cannot be projected at the solution", i);
        }
        const double c2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + r[3] * r[3] + r[4] * r[4];
        if (block_chi2) block_chi2[i] = c2;
        if (q_pred && opt->marginal) { // the surveyed position projected
            mrcal_point3_t pc;
            mrcal_point2_t q = {.xy = {NAN, NAN}};
            mrcal_transform_point_rt(pc.xyz, nullptr, nullptr, rt, &pb->p_survey_c_m[3 * i]);
            mrcal_project(&q, nullptr, nullptr, &pc, 1, pb->lensmodel, intrinsics);
            q_pred[2 * i] = q.x;
            q_pred[2 * i + 1] = q.y;
        } else if (q_pred) {
            const double sig = pb->sigma_px ? pb->sigma_px[i] : 1.0;
            q_pred[2 * i] = pb->q_px[2 * i] + r[0] * sig;
            q_pred[2 * i + 1] = pb->q_px[2 * i + 1] + r[1] * sig;
        }
    }
    {
        ceres::Problem::EvaluateOptions eo;
        eo.apply_loss_function = false;
        double cost = 0.0;
        problem.Evaluate(eo, &cost, nullptr, nullptr, nullptr);
        summary->chi2 = 2.0 * cost; // includes the position and intrinsics priors
    }
    if (!opt->covariance) return RS_OK;

    std::vector<double *> head{rt};
    if (refine_i) head.push_back(intrinsics);
    Eigen::MatrixXd cov_tangent;
    double column_range = 1.0;
    summary->condition_number = reduced_condition(&problem, head, landmarks, &cov_tangent, &column_range);
    if (!(summary->condition_number < kConditionSingular))
        return rs_err_set(err, RS_ERR_DEGENERATE,
                          "the landmarks do not determine the pose%s: the Jacobian is "
                          "rank-deficient (condition number %.3g)",
                          refine_i ? " and the refined intrinsics" : "", summary->condition_number);
    const int n = 6 + Ni, m = 6 + (refine_i ? Ni : 0);
    std::vector<double> c((size_t)m * (size_t)m);
    summary->covariance_by_ceres = column_range < kColumnRangeCeres;
    if (summary->covariance_by_ceres) {
        ceres::Covariance::Options co;
        // Eigen's sparse QR for small problems, SuiteSparseQR for large ones: SuiteSparse's
        // set-up dominated small ones (20 landmarks: 0.29 of 1.0 ms per calibration, 0.18 with
        // Eigen's; DENSE_SVD took 1.2 ms more), Eigen's fill-in large ones (200 landmarks:
        // 25 ms against 7 ms). Where the Jacobian's columns span more than kColumnRangeCeres,
        // the landmark-eliminated QR below is used instead, as before.
        co.algorithm_type = ceres::SPARSE_QR;
        co.sparse_linear_algebra_library_type =
            Nfree <= kEigenCovarianceMax ? ceres::EIGEN_SPARSE : ceres::SUITE_SPARSE;
        co.apply_loss_function = false;
        ceres::Covariance covariance(co);
        std::vector<std::pair<const double *, const double *>> pairs;
        for (double *a : head)
            for (double *b : head) pairs.emplace_back(a, b);
        if (!covariance.Compute(pairs, &problem))
            return rs_err_set(err, RS_ERR_DEGENERATE,
                              "the covariance of the pose is rank-deficient: the landmarks do not "
                              "determine it");
        std::vector<const double *> blocks(head.begin(), head.end());
        if (!covariance.GetCovarianceMatrix(blocks, c.data()))
            return rs_err_set(err, RS_ERR_EXTERNAL, "Ceres: GetCovarianceMatrix failed");
    } else {
        // the landmark-eliminated QR's covariance, tangent -> ambient for the intrinsics
        Eigen::MatrixXd P = Eigen::MatrixXd::Zero(m, cov_tangent.rows());
        P.topLeftCorner(6, 6).setIdentity();
        if (refine_i) {
            const ceres::Manifold *mf = problem.GetManifold(intrinsics);
            const int k = mf->TangentSize();
            Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> Bm(Ni, k);
            mf->PlusJacobian(intrinsics, Bm.data());
            P.block(6, 6, Ni, k) = Bm;
        }
        const Eigen::MatrixXd C = P * cov_tangent * P.transpose();
        for (int a = 0; a < m; a++)
            for (int b = 0; b < m; b++) c[(size_t)a * m + b] = C(a, b);
    }
    if (cov) {
        std::fill(cov, cov + (size_t)n * n, 0.0);
        for (int a = 0; a < m; a++)
            for (int b = 0; b < m; b++) cov[a * n + b] = c[(size_t)a * m + b];
    }
    return RS_OK;
}

} // namespace

extern "C" double rs_calib_refine_jacobian_check(const double rt_cam_c[6], const double *intrinsics,
                                                 const double *p_c_m, const rs_calib_refine_problem *pb)
{
    QuietGlog quiet;
    try {
        const int Ni = mrcal_lensmodel_num_params(pb->lensmodel);
        double worst = 0.0;
        for (int i = 0; i < pb->N; i++) {
            LandmarkCost cost(pb->lensmodel, Ni, &pb->q_px[2 * i], pb->sigma_px ? pb->sigma_px[i] : 1.0,
                              &pb->p_survey_c_m[3 * i], pb->sigma_enu_m ? &pb->sigma_enu_m[3 * i] : nullptr);
            std::vector<double> x0(rt_cam_c, rt_cam_c + 6), x1(&p_c_m[3 * i], &p_c_m[3 * i] + 3),
                x2(intrinsics, intrinsics + Ni);
            std::vector<double> *blocks[3] = {&x0, &x1, &x2};
            std::vector<double> J0(30), J1(15), J2(5 * (size_t)Ni);
            double *J[3] = {J0.data(), J1.data(), J2.data()};
            const double *x[3] = {x0.data(), x1.data(), x2.data()};
            double r[5], rp[5], rm[5];
            if (!cost.Evaluate(x, r, J)) return NAN;
            for (int b = 0; b < 3; b++) {
                const int n = (int)blocks[b]->size();
                for (int row = 0; row < 5; row++) {
                    double scale = 0.0, err = 0.0;
                    for (int j = 0; j < n; j++) scale = std::fmax(scale, std::fabs(J[b][row * n + j]));
                    for (int j = 0; j < n; j++) {
                        double &xj = (*blocks[b])[(size_t)j];
                        const double saved = xj, h = 1e-6 * std::fmax(1.0, std::fabs(saved));
                        xj = saved + h;
                        if (!cost.Evaluate(x, rp, nullptr)) return NAN;
                        xj = saved - h;
                        if (!cost.Evaluate(x, rm, nullptr)) return NAN;
                        xj = saved;
                        err = std::fmax(err, std::fabs((rp[row] - rm[row]) / (2 * h) - J[b][row * n + j]));
                    }
                    if (scale > 0.0) worst = std::fmax(worst, err / scale);
                }
            }
        }
        return worst;
    } catch (...) {
        return NAN;
    }
}

extern "C" rs_status rs_calib_refine_run(double rt_cam_c[6], double *intrinsics, double *p_c_m,
                                         rs_calib_refine_summary *summary, double *cov, double *block_chi2,
                                         double *q_pred_px, const rs_calib_refine_problem *problem,
                                         const rs_calib_refine_options *opt, rs_err *err)
{
    QuietGlog quiet;
    try {
        return refine(rt_cam_c, intrinsics, p_c_m, summary, cov, block_chi2, q_pred_px, problem, opt, err);
    } catch (const std::bad_alloc &) {
        return rs_err_set(err, RS_ERR_NOMEM, "refine: out of memory");
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "refine: Ceres: %s", e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "refine: Ceres: unknown exception");
    }
}

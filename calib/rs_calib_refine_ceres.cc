// rs_calib_refine_ceres.cc -- Ceres shim: the pose refinement with landmark priors (errors in
// variables), optional intrinsics, and the covariance. Contract: rs_calib_refine.h.
//
// Method: variable projection (Golub & Pereyra 1973, with Kaufman's 1975 Jacobian) solved by
// Ceres' TinySolver (a dense Levenberg-Marquardt, header-only). The unknowns split in two:
//   c = (rt (6), the refined intrinsics' coordinates (k))   -- TinySolver's parameters
//   p_i = landmark i's position (its free axes, <= 3 each)  -- solved inside each evaluation
// For a given c every landmark's own small problem
//   min_p |(q(c, p) - q_obs)/sigma_px|^2 + sum_k ((p_k - p_survey_k)/s_k)^2
// is solved to convergence (Gauss-Newton on <= 3 unknowns, warm-started from the previous
// evaluation: for a point with all three axes free in closed form by the Woodbury identity,
// otherwise by Householder QR of its 5 x <=4 Jacobian J_p: calib/internal/rs_calib_block.h;
// started where the last evaluation's linearisation predicts it), and the landmark
// contributes its 5 residuals r_i at that optimum, with the Jacobian J_c - J_p (J_p^+ J_c): the
// landmark's columns projected out. The reduced problem has the joint problem's minimum (at the
// inner optimum J_p^T r = 0, so the reduced gradient is the joint one), and its Gauss-Newton
// matrix is the Schur complement of the joint one: (J_red^T J_red)^-1 is exactly the covariance
// of c with the landmarks marginalised. 6 (+ k) parameters instead of 6 + 3N: for 20 landmarks a
// solve costs tens of microseconds (`roadside bench calib`, docs/benchmarks.md).
//
// Robust loss: Cauchy rho(s) = a^2 log(1 + s/a^2) on each landmark's block |r_i|^2, given to
// TinySolver as residuals with the exact gradient and rho's Gauss-Newton Hessian, plus one
// residual that carries the rest of the cost, so that TinySolver minimises sum rho
// (rs_calib__cauchy_block). The inner optimum does not change (rho is monotone).
//
// Jacobians are analytic (mrcal), not automatic or numeric: the landmark residual is
// r = (q - q_obs)/sigma_px with q = rs_lens_project(p_cam), p_cam = mrcal_transform_point_rt(rt, p),
// so dr/drt = dq_dpcam dpcam_drt / sigma, dr/dp = dq_dpcam dpcam_dp / sigma and
// dr/dintrinsics = dq_dintrinsics / sigma (mrcal 2.2 reports dq_dintrinsics densely, (2,Nintr)
// per point; tests/calib/test_solve.c checks the chain against differences).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <vector>

#include <Eigen/Dense>
#include <ceres/tiny_solver.h>

extern "C" {
#include <mrcal/poseutils.h>

#include "calib/internal/rs_calib_block.h"
#include "calib/internal/rs_calib_refine.h"
#include "calib/rs_calib.h"
#include "core/rs_lens.h"
#include "core/rs_pose.h"
}

namespace {

using Mat = Eigen::MatrixXd;
using Vec = Eigen::VectorXd;

// The survey prior of one landmark axis with sigma 0 contributes nothing: the axis is held.
double inv_or_zero(double sigma) { return sigma > 0.0 ? 1.0 / sigma : 0.0; }

// A residual the solver can never accept: an evaluation that failed (a point that does not
// project) reports it, so that TinySolver, which does not look at the return value of a trial
// evaluation, rejects the step.
const double kFailed = 1e100;
// The largest predicted move (in the landmark's smallest survey sigma) that an inner solve starts
// from (Reduced::inner): at 1 an outlier of test_noise_model (survey stated 5x too loose) ended
// behind the camera; 0.3 keeps that test's and test_stress_random's outcomes and the saving
const double kPredictMax = 0.3;
// The inner solve's last step, in the landmark's smallest survey sigma (Reduced::inner).
const double kInnerTol = 1e-3;

// A pose rt, its rotation and the rotation's gradient computed once for all the landmarks.
struct Pose : rs_pose_prepared {
    explicit Pose(const double rt[6]) { rs_pose_prepare(this, rt); }
    // p_cam = R p + t; dpcam_drt (3,6) row-major, may be NULL
    void apply(double p_cam[3], double *dpcam_drt, const double p[3]) const
    {
        rs_pose_prepared_apply(p_cam, dpcam_drt, nullptr, this, p);
    }
};

// One landmark: 2 pixel residuals + 3 survey-prior residuals, so that the robust loss acts on
// the landmark as a whole (an outlier cannot hide by pulling its landmark). A landmark picked
// along a segment is seen at p + s d (d the segment's direction, s free: one more unknown with no
// prior row), so that its pixel residual is the distance to the projected line.
struct Landmark {
    double q_obs[2], w_px, p_survey[3], w_m[3], d[3];
    int free[3], naxes; // the axes with a survey sigma > 0: the landmark's own unknowns
    bool slides;        // picked along a segment: s is an unknown too
    int nfree;          // naxes + slides
    double sigma_min;   // the smallest free survey sigma, m (1 when none: s is in metres too)

    Landmark(const double q[2], double sigma_px, const double ps[3], const double *sigma_m, const double *along)
    {
        w_px = 1.0 / sigma_px;
        naxes = 0;
        slides = along && (along[0] != 0.0 || along[1] != 0.0 || along[2] != 0.0);
        for (int k = 0; k < 3; k++) d[k] = slides ? along[k] : 0.0;
        for (int k = 0; k < 2; k++) q_obs[k] = q[k];
        for (int k = 0; k < 3; k++) {
            p_survey[k] = ps[k];
            w_m[k] = inv_or_zero(sigma_m ? sigma_m[k] : 0.0);
            if (w_m[k] > 0.0) free[naxes++] = k;
        }
        nfree = naxes + (slides ? 1 : 0);
        double wmax = 0.0;
        for (int k = 0; k < 3; k++) wmax = std::max(wmax, w_m[k]);
        sigma_min = wmax > 0.0 ? 1.0 / wmax : 1.0;
    }

    // r (5,) at (pose, intrinsics, p, s); optionally dr/drt (5,6), dr/dp (5,3), dr/dintrinsics
    // (5,Ni), all row-major (the pixel rows of dr/dp are also those of dr/d(seen point)).
    // dq_di: scratch (2,Ni), needed with dr_di. False when the seen point does not project.
    bool evaluate(double r[5], double *dr_drt, double *dr_dp, double *dr_di, double *dq_di,
                  const mrcal_lensmodel_t *lensmodel, int Ni, const Pose &pose, const double *intrinsics,
                  const double p[3], double s) const
    {
        mrcal_point3_t p_cam;
        double dpcam_drt[18], seen[3];
        for (int k = 0; k < 3; k++) seen[k] = p[k] + s * d[k];
        pose.apply(p_cam.xyz, dr_drt ? dpcam_drt : nullptr, seen);
        mrcal_point2_t q;
        mrcal_point3_t dq_dpcam[2];
        if (!rs_lens_project(&q, dq_dpcam, dr_di ? dq_di : nullptr, &p_cam, 1, lensmodel, intrinsics)) return false;
        r[0] = (q.x - q_obs[0]) * w_px;
        r[1] = (q.y - q_obs[1]) * w_px;
        for (int k = 0; k < 3; k++) r[2 + k] = (p[k] - p_survey[k]) * w_m[k];
        if (!std::isfinite(r[0]) || !std::isfinite(r[1])) return false;
        auto chain = [&](double *J, const double *dpcam_dx, int n) { // (5,n): rows 2..4 zero
            std::memset(J, 0, sizeof(double) * 5 * (size_t)n);
            for (int a = 0; a < 2; a++)
                for (int j = 0; j < n; j++) {
                    double s = 0.0;
                    for (int k = 0; k < 3; k++) s += dq_dpcam[a].xyz[k] * dpcam_dx[k * n + j];
                    J[a * n + j] = s * w_px;
                }
        };
        if (dr_drt) chain(dr_drt, dpcam_drt, 6);
        if (dr_dp) {
            chain(dr_dp, pose.R, 3); // dp_cam/dp = R
            for (int k = 0; k < 3; k++) dr_dp[(2 + k) * 3 + k] = w_m[k];
        }
        if (dr_di) {
            std::memset(dr_di, 0, sizeof(double) * 5 * (size_t)Ni);
            for (int j = 0; j < 2 * Ni; j++) dr_di[j] = dq_di[j] * w_px;
        }
        return true;
    }
};

// The reduced problem (variable projection) in TinySolver's interface.
class Reduced {
  public:
    using Scalar = double;
    enum { NUM_RESIDUALS = Eigen::Dynamic, NUM_PARAMETERS = Eigen::Dynamic };

    struct PriorRow { // a refined intrinsic's prior: (intrinsics[index] - nominal) * weight
        int index;
        double nominal, weight;
    };

    Reduced(const rs_calib_refine_problem *pb, const rs_calib_refine_options *opt, const double *intrinsics_start,
            const double *p_start)
        : pb_(pb), lensmodel_(pb->lensmodel), Ni_(mrcal_lensmodel_num_params(pb->lensmodel)),
          i0_(intrinsics_start, intrinsics_start + Ni_),
          robust_b_(opt->robust_scale > 0.0 ? opt->robust_scale * opt->robust_scale : 0.0),
          p_(p_start, p_start + 3 * (size_t)pb->N), s_((size_t)pb->N, 0.0)
    {
        for (int i = 0; i < pb->N; i++) {
            landmarks_.emplace_back(&pb->q_px[2 * i], pb->sigma_px ? pb->sigma_px[i] : 1.0, &pb->p_survey_c_m[3 * i],
                                    pb->sigma_enu_m ? &pb->sigma_enu_m[3 * i] : nullptr,
                                    pb->along_c ? &pb->along_c[3 * i] : nullptr);
            if (pb->along_c && pb->s_along_m) s_[(size_t)i] = pb->s_along_m[i];
            if (!pb->use || pb->use[i]) used_.push_back(i);
        }
        subspace(opt);
        nc_ = 6 + k_;
        carrier_ = robust_b_ > 0.0;
        nres_ = 5 * (int)used_.size() + (pb->has_position_prior ? 3 : 0) + (int)priors_.size() + (carrier_ ? 1 : 0);
        intr_.resize((size_t)Ni_);
        dq_di_.resize(2 * (size_t)Ni_);
        dr_di_.resize(5 * (size_t)Ni_);
        cached_c_.resize((size_t)nc_);
        cached_r_.resize((size_t)nres_);
        cached_J_.resize((size_t)nres_ * (size_t)nc_);
        raw_r_.resize((size_t)nres_);
        raw_J_.resize((size_t)nres_ * (size_t)nc_);
        lin_c_.resize((size_t)nc_);
        lin_x_.resize((size_t)pb->N * (12 + 2 * (size_t)nc_));
    }

    int NumResiduals() const { return nres_; }
    int NumParameters() const { return nc_; }
    int k() const { return k_; }
    const std::vector<int> &used() const { return used_; }
    const std::vector<Landmark> &landmarks() const { return landmarks_; }
    const std::vector<double> &p() const { return p_; }
    const std::vector<double> &s() const { return s_; }
    // the basis of the refined intrinsics, column-major (Ni, k)
    const std::vector<double> &basis() const { return B_; }
    void set_robust(bool on, double b) { robust_b_ = on ? b : 0.0; }
    bool failed() const { return failed_; }
    // the carrier row's share of the cost: a constant (half its residual's offset) that keeps it
    // real whatever rs_calib__cauchy_block returns; 0 when there is no row or the loss is off
    bool carrier() const { return carrier_; }
    double carrier_cost() const
    {
        return carrier_ && robust_b_ > 0.0 ? 0.5 * (double)used_.size() * robust_b_ / RS_CALIB_CAUCHY_MIN_CURVATURE
                                           : 0.0;
    }

    // The intrinsics at c: i0 + B c[6..].
    const double *intrinsics(const double *c) const
    {
        for (int a = 0; a < Ni_; a++) {
            double s = i0_[(size_t)a];
            for (int j = 0; j < k_; j++) s += B_[(size_t)j * Ni_ + a] * c[6 + j];
            intr_[(size_t)a] = s;
        }
        return intr_.data();
    }

    // TinySolver's call: residuals (nres,), jacobian (nres, nc) column-major or NULL.
    // Each evaluation computes the Jacobian too, and is kept: TinySolver evaluates a trial point
    // without it, then, when it accepts the step, the same point again with it; and refine()
    // asks for the solution once more. Those are copies.
    bool operator()(const double *c, double *residuals, double *jacobian) const
    {
        const bool hit = cached_ && cached_robust_b_ == robust_b_ &&
                         std::memcmp(c, cached_c_.data(), sizeof(double) * (size_t)nc_) == 0;
        if (!hit) {
            cached_ok_ = evaluate_all(c, cached_r_.data(), cached_J_.data());
            std::memcpy(cached_c_.data(), c, sizeof(double) * (size_t)nc_);
            cached_robust_b_ = robust_b_;
            cached_ = true;
        }
        std::memcpy(residuals, cached_r_.data(), sizeof(double) * (size_t)nres_);
        if (jacobian) std::memcpy(jacobian, cached_J_.data(), sizeof(double) * (size_t)nres_ * (size_t)nc_);
        return cached_ok_;
    }

    // The residuals and Jacobian without the robust loss at c, where the last evaluation was:
    // kept by it before the loss reshaped them (the landmarks at the same inner optimum), so that
    // the statistics of a robust solve's solution cost no evaluation of their own (one in five
    // or six of a robust solve's). False when the last evaluation was elsewhere or failed: then
    // evaluate with the loss off.
    bool unrobust_at(const double *c, double *residuals, double *jacobian) const
    {
        if (!cached_ || !cached_ok_ || !(cached_robust_b_ > 0.0) ||
            std::memcmp(c, cached_c_.data(), sizeof(double) * (size_t)nc_) != 0)
            return false;
        std::memcpy(residuals, raw_r_.data(), sizeof(double) * (size_t)nres_);
        std::memcpy(jacobian, raw_J_.data(), sizeof(double) * (size_t)nres_ * (size_t)nc_);
        return true;
    }

  private:
    bool evaluate_all(const double *c, double *residuals, double *jacobian) const
    {
        failed_ = false;
        const double *intr = intrinsics(c);
        const Pose pose(c);
        int row = 0;
        const bool predict = lin_valid_;
        lin_valid_ = false; // until every landmark below has its linearisation at c
        double carried = 0.0;
        for (int i : used_) {
            if (!inner(i, c, predict, pose, intr, &residuals[row], jacobian ? &jacobian[row] : nullptr, nres_))
                return fail(residuals);
            if (robust_b_ > 0.0) {
                keep_raw(row, 5, residuals, jacobian);
                carried += rs_calib__cauchy_block(&residuals[row], 5, jacobian ? &jacobian[row] : nullptr, nres_, nc_,
                                                  robust_b_);
            }
            row += 5;
        }
        if (pb_->has_position_prior) {
            double C[3], dC_drt[18];
            rs_pose_position_from_rt(C, dC_drt, c);
            const double w = 1.0 / pb_->prior_sigma_m;
            for (int a = 0; a < 3; a++) {
                residuals[row + a] = (C[a] - pb_->prior_position_c_m[a]) * w;
                if (jacobian)
                    for (int j = 0; j < nc_; j++)
                        jacobian[(size_t)j * nres_ + row + a] = j < 6 ? dC_drt[a * 6 + j] * w : 0.0;
            }
            row += 3;
        }
        for (const PriorRow &pr : priors_) {
            residuals[row] = (intr[pr.index] - pr.nominal) * pr.weight;
            if (jacobian)
                for (int j = 0; j < nc_; j++)
                    jacobian[(size_t)j * nres_ + row] = j < 6 ? 0.0 : B_[(size_t)(j - 6) * Ni_ + pr.index] * pr.weight;
            row++;
        }
        if (robust_b_ > 0.0) keep_raw(5 * (int)used_.size(), row - 5 * (int)used_.size(), residuals, jacobian);
        if (carrier_) { // rs_calib__cauchy_block's cost, carried (0 when the loss is off)
            residuals[row] = robust_b_ > 0.0 ? std::sqrt(std::max(0.0, 2.0 * carrier_cost() + carried)) : 0.0;
            if (jacobian)
                for (int j = 0; j < nc_; j++) jacobian[(size_t)j * nres_ + row] = 0.0;
            if (robust_b_ > 0.0) keep_raw(row, 1, residuals, jacobian); // 0 without the loss
            row++;
        }
        if (jacobian) {
            std::memcpy(lin_c_.data(), c, sizeof(double) * (size_t)nc_);
            lin_valid_ = true;
        }
        return true;
    }

  public:
    // Landmark i's residuals at its own optimum for the pose and intrinsics (p_ updated), and if
    // J is not NULL its reduced Jacobian (5, nc) column-major with leading dimension ld. Gauss-
    // Newton from the previous position: a step below kInnerTol x the landmark's smallest
    // survey sigma ends it, applied to p and to r linearly. The error left is second order in
    // that step: about |dq/dp| step^2 / z, for a step of 1e-3 sigma at 20 m with f/sigma_px =
    // 1000 px/px and sigma 0.3 m 2e-7 of a sigma (the final pass used to go on to 1e-6: 19% of
    // its time, for nothing the tests or `roadside bench calib` could see).
    // False if the landmark does not project.
    // With predict, the solve starts where the last evaluation's linearisation puts the landmark
    // for c (its position there plus dp/dc (c - c_last), dp/dc = -Jp^+ Jc, the implicit function
    // of its optimum): one evaluation instead of two wherever the camera moved by a step
    // Gauss-Newton makes.
    bool inner(int i, const double *c, bool predict, const Pose &pose, const double *intr, double r[5], double *J,
               int ld) const
    {
        const Landmark &L = landmarks_[(size_t)i];
        const int nf = L.nfree;
        double *p = &p_[3 * (size_t)i], &s = s_[(size_t)i];
        const bool want_i = J && k_ > 0;
        double dr_drt[30], dr_dp[15], Jp[5][4];
        rs_calib__qr5 qr;
        rs_calib__point_block pt;
        const bool closed = L.naxes == 3 && !L.slides; // rs_calib__point_block's case
        // the last linearisation: p, s, G = -Jp^+'s pixel columns (4, 2), Jc's pixel rows (2, nc)
        double *lin = &lin_x_[(size_t)i * (12 + 2 * (size_t)nc_)];
        const double p_kept[3] = {p[0], p[1], p[2]}, s_kept = s;
        if (predict && nf > 0) {
            double dq[2] = {0, 0}; // the pixel change that the camera's step makes, whitened
            for (int j = 0; j < nc_; j++) {
                const double dc = c[j] - lin_c_[(size_t)j];
                dq[0] += lin[12 + j] * dc;
                dq[1] += lin[12 + nc_ + j] * dc;
            }
            double x[4], move = 0.0;
            for (int a = 0; a < 4; a++) {
                x[a] = lin[a] + lin[4 + 2 * a] * dq[0] + lin[5 + 2 * a] * dq[1];
                move = std::max(move, std::fabs(x[a] - (a < 3 ? p[a] : s)));
            }
            // not a long extrapolation: it can throw the landmark into another basin
            predict = move <= kPredictMax * L.sigma_min;
            if (predict) {
                for (int k = 0; k < 3; k++) p[k] = x[k];
                s = x[3];
            }
        }
        for (int it = 0;; it++) {
            if (!L.evaluate(r, dr_drt, dr_dp, want_i ? dr_di_.data() : nullptr, dq_di_.data(), lensmodel_, Ni_, pose,
                            intr, p, s)) {
                if (!predict || it > 0) return false;
                predict = false; // the prediction does not project: from where the landmark was
                std::memcpy(p, p_kept, sizeof p_kept);
                s = s_kept;
                it = -1;
                continue;
            }
            if (nf == 0) break;
            if (closed) {
                double dx[3], dr[5];
                rs_calib__point_block_factor(&pt, dr_dp, L.w_m);
                rs_calib__point_block_step(&pt, dx, dr, r, L.w_m);
                const double step = std::max(std::fabs(dx[0]), std::max(std::fabs(dx[1]), std::fabs(dx[2])));
                for (int k = 0; k < 3; k++) p[k] += dx[k];
                if (!std::isfinite(step)) return false;
                if (step <= kInnerTol * L.sigma_min || it == 25) {
                    for (int a = 0; a < 5; a++) r[a] += dr[a];
                    break;
                }
                continue;
            }
            for (int a = 0; a < 5; a++) {
                for (int f = 0; f < L.naxes; f++) Jp[a][f] = dr_dp[a * 3 + L.free[f]];
                if (L.slides) // the pixel rows only: s has no prior
                    Jp[a][L.naxes] =
                        a < 2 ? dr_dp[a * 3] * L.d[0] + dr_dp[a * 3 + 1] * L.d[1] + dr_dp[a * 3 + 2] * L.d[2] : 0.0;
            }
            if (!rs_calib__qr5_factor(&qr, Jp, nf)) return false;
            double dx[4], minus_r[5], step = 0.0;
            for (int a = 0; a < 5; a++) minus_r[a] = -r[a];
            rs_calib__qr5_solve(&qr, dx, minus_r);
            for (int f = 0; f < nf; f++) {
                if (f < L.naxes)
                    p[L.free[f]] += dx[f];
                else
                    s += dx[f];
                step = std::max(step, std::fabs(dx[f]));
            }
            if (!std::isfinite(step)) return false;
            if (step <= kInnerTol * L.sigma_min || it == 25) {
                for (int a = 0; a < 5; a++)
                    for (int f = 0; f < nf; f++) r[a] += Jp[a][f] * dx[f];
                break;
            }
        }
        if (!J) return true;
        // J_c (5, nc): rt columns, then the intrinsics' subspace, each column with the landmark's
        // columns projected out: (I - Q Q') col, where only col's pixel rows 0, 1 are not zero,
        // so that the projector's first two columns P (5, 2) are all it takes
        double Q[5][4], P[5][2];
        if (closed) {
            rs_calib__point_block_projector(&pt, P);
        } else {
            if (nf > 0) rs_calib__qr5_basis(&qr, Q);
            for (int a = 0; a < 5; a++)
                for (int b = 0; b < 2; b++) {
                    double s = a == b ? 1.0 : 0.0;
                    for (int f = 0; f < nf; f++) s -= Q[a][f] * Q[b][f];
                    P[a][b] = s;
                }
        }
        lin[0] = p[0], lin[1] = p[1], lin[2] = p[2], lin[3] = s;
        for (int b = 0; b < 2; b++) { // G's column b: -Jp^+ e_b
            double dx[4] = {0, 0, 0, 0}, g[4] = {0, 0, 0, 0};
            if (closed) {
                const double e[5] = {b == 0 ? 1.0 : 0.0, b == 1 ? 1.0 : 0.0, 0, 0, 0};
                double dr[5];
                rs_calib__point_block_step(&pt, dx, dr, e, L.w_m);
                for (int k = 0; k < 3; k++) g[k] = dx[k];
            } else if (nf > 0) {
                const double e[5] = {b == 0 ? -1.0 : 0.0, b == 1 ? -1.0 : 0.0, 0, 0, 0};
                rs_calib__qr5_solve(&qr, dx, e);
                for (int f = 0; f < nf; f++) g[f < L.naxes ? L.free[f] : 3] = dx[f];
            }
            for (int a = 0; a < 4; a++) lin[4 + 2 * a + b] = g[a];
        }
        for (int j = 0; j < nc_; j++) {
            double col[2];
            for (int a = 0; a < 2; a++) {
                if (j < 6) {
                    col[a] = dr_drt[a * 6 + j];
                } else {
                    double s = 0.0;
                    for (int b = 0; b < Ni_; b++) s += dr_di_[(size_t)a * Ni_ + b] * B_[(size_t)(j - 6) * Ni_ + b];
                    col[a] = s;
                }
            }
            double *out = &J[(size_t)j * ld];
            for (int a = 0; a < 5; a++) out[a] = P[a][0] * col[0] + P[a][1] * col[1];
            lin[12 + j] = col[0], lin[12 + nc_ + j] = col[1];
        }
        return true;
    }

    // Landmark i's residuals at its current position p_ (no inner solve): for landmarks left
    // out of the solve. False if it does not project.
    bool at_current(int i, const double *c, double r[5]) const
    {
        return landmarks_[(size_t)i].evaluate(r, nullptr, nullptr, nullptr, nullptr, lensmodel_, Ni_, Pose(c),
                                              intrinsics(c), &p_[3 * (size_t)i], s_[(size_t)i]);
    }

  private:
    // rows [row, row + m) of the residuals and the Jacobian (column-major, nres_ rows; NULL: not
    // evaluated) as they are without the loss, for unrobust_at; the carrier row (m = 1 at its
    // row) is 0 there
    void keep_raw(int row, int m, const double *residuals, const double *jacobian) const
    {
        const bool carrier_row = carrier_ && row == nres_ - 1;
        for (int a = row; a < row + m; a++) raw_r_[(size_t)a] = carrier_row ? 0.0 : residuals[a];
        if (!jacobian) return;
        for (int j = 0; j < nc_; j++)
            for (int a = row; a < row + m; a++)
                raw_J_[(size_t)j * nres_ + a] = carrier_row ? 0.0 : jacobian[(size_t)j * nres_ + a];
    }

    bool fail(double *residuals) const
    {
        failed_ = true;
        for (int a = 0; a < nres_; a++) residuals[a] = kFailed;
        return false;
    }

    // The refined intrinsics: x = x_start + B delta with B's orthonormal columns spanning the
    // refined directions (the focal direction (fx0, fy0, 0...)/|.|, unit vectors for the centre
    // and the distortion coefficients), and their priors about the nominal values.
    void subspace(const rs_calib_refine_options *opt)
    {
        const double *nominal = pb_->intrinsics_nominal;
        auto unit = [&](int i) {
            B_.resize(B_.size() + (size_t)Ni_, 0.0);
            B_[B_.size() - (size_t)Ni_ + (size_t)i] = 1.0;
        };
        if (opt->refine & RS_CALIB_REFINE_FOCAL) {
            const double n = std::hypot(nominal[0], nominal[1]);
            B_.resize(B_.size() + (size_t)Ni_, 0.0);
            B_[B_.size() - (size_t)Ni_ + 0] = nominal[0] / n;
            B_[B_.size() - (size_t)Ni_ + 1] = nominal[1] / n;
            if (opt->focal_prior_rel_sigma > 0.0)
                priors_.push_back({0, nominal[0], 1.0 / (opt->focal_prior_rel_sigma * nominal[0])});
        }
        if (opt->refine & RS_CALIB_REFINE_CENTER)
            for (int i = 2; i < 4; i++) {
                unit(i);
                if (opt->center_prior_sigma_px > 0.0)
                    priors_.push_back({i, nominal[i], 1.0 / opt->center_prior_sigma_px});
            }
        if (opt->refine & RS_CALIB_REFINE_DISTORTION)
            for (int i = 4; i < Ni_; i++) {
                unit(i);
                if (opt->distortion_prior_sigma > 0.0)
                    priors_.push_back({i, nominal[i], 1.0 / opt->distortion_prior_sigma});
            }
        k_ = (int)(B_.size() / (size_t)Ni_);
    }

    const rs_calib_refine_problem *pb_;
    const mrcal_lensmodel_t *lensmodel_;
    int Ni_, k_ = 0, nc_ = 6, nres_ = 0;
    std::vector<double> i0_, B_;
    std::vector<PriorRow> priors_;
    std::vector<Landmark> landmarks_;
    std::vector<int> used_;
    double robust_b_;
    bool carrier_ = false; // a last residual row for rs_calib__cauchy_block's cost
    // state of the evaluations: the landmarks' positions (warm start of the next inner solve)
    // and scratch
    mutable std::vector<double> p_, s_, intr_, dq_di_, dr_di_;
    mutable std::vector<double> cached_c_, cached_r_, cached_J_; // the last evaluation
    mutable std::vector<double> raw_r_, raw_J_;                  // the same without the loss
    mutable bool cached_ = false, cached_ok_ = false;
    mutable double cached_robust_b_ = 0.0;
    mutable bool failed_ = false;
    // the last evaluation with a Jacobian, for the next inner solves' start (inner)
    mutable std::vector<double> lin_c_, lin_x_;
    mutable bool lin_valid_ = false;
};

// Beyond this condition number of the equilibrated reduced Jacobian the covariance is
// numerical noise.
const double kConditionSingular = 1e7;

// Condition number and covariance from the reduced Jacobian J (m, nc), column-major: its
// columns scaled to unit norm (so the number does not depend on units, radians against metres),
// Householder QR, then the singular values of the (nc, nc) triangle R: sigma_max / sigma_min
// (inf when singular), and cov = S R^-1 R^-T S. No normal equations are formed (pixel sigmas of
// 1e-3 px against survey sigmas of metres would lose every digit in them).
template <int P> double reduced_condition_sized(Mat *cov, Mat J)
{
    using Square = Eigen::Matrix<double, P, P>;
    using Column = Eigen::Matrix<double, P, 1>;
    const int nc = (int)J.cols();
    if (J.rows() < nc) return INFINITY;
    Column scale(nc);
    for (int j = 0; j < nc; j++) {
        const double n = J.col(j).norm();
        if (!(n > 0.0) || !std::isfinite(n)) return INFINITY;
        J.col(j) /= n;
        scale(j) = 1.0 / n;
    }
    Eigen::HouseholderQR<Eigen::Matrix<double, Eigen::Dynamic, P>> qr(J);
    const Square R = qr.matrixQR().topRows(nc).template triangularView<Eigen::Upper>();
    const Column sv = Eigen::JacobiSVD<Square>(R).singularValues(); // no singular vectors: the
    const double smax = sv(0), smin = sv(nc - 1);                   // covariance needs none
    if (!(smin > 0.0) || !std::isfinite(smax)) return INFINITY;
    // (J'J)^-1 = R^-1 R^-T: R^-1 by back substitution on the triangle, instead of the SVD's
    // V Sigma^-2 V' (its vectors cost more than the triangle's inverse: the bench's exact
    // surveys, each one's best of 20 calibrations, 112.7 -> 106.3 us in the median)
    const Square Rinv = R.template triangularView<Eigen::Upper>().solve(Square::Identity(nc, nc));
    *cov = scale.asDiagonal() * (Rinv * Rinv.transpose()) * scale.asDiagonal();
    return smax / smin;
}

// The pose alone (nc = 6, no refined intrinsics) in Eigen's fixed-size algebra: the dynamic
// Jacobi SVD was 7% of a 4-landmark calibration.
double reduced_condition(Mat *cov, const Mat &J)
{
    return J.cols() == 6 ? reduced_condition_sized<6>(cov, J) : reduced_condition_sized<Eigen::Dynamic>(cov, J);
}

// Reduced seen by TinySolver with P parameters: P = 6 (no refined intrinsics) gives TinySolver
// fixed-size normal equations and step (its per-step algebra was as costly as the evaluations
// on 20 landmarks), Eigen::Dynamic any other count.
template <int P> struct Sized {
    using Scalar = double;
    enum { NUM_RESIDUALS = Eigen::Dynamic, NUM_PARAMETERS = P };
    const Reduced &f;
    int NumResiduals() const { return f.NumResiduals(); }
    int NumParameters() const { return f.NumParameters(); }
    bool operator()(const double *c, double *residuals, double *jacobian) const { return f(c, residuals, jacobian); }
};

// Levenberg-Marquardt (TinySolver) on f from c (in,out).
template <int P>
void solve_lm(int *iterations, bool *hit_max, const Reduced &f, Vec &c, const rs_calib_refine_options *opt)
{
    using Solver = ceres::TinySolver<Sized<P>>;
    Solver solver;
    solver.options.max_num_iterations = opt->max_iterations > 0 ? opt->max_iterations : 100;
    // TinySolver's function tolerance is an absolute change of the whitened chi-square (twice
    // its cost), and a Gauss-Newton step to the minimum changes it by the step's squared
    // Mahalanobis length: every pass stops after a step of 1e-2 of the parameters' own sigma,
    // which leaves less than half that (Cauchy's loss converges linearly, the error shrinking to
    // a third per step or faster; with noise-free data Gauss-Newton converges quadratically and
    // leaves nothing: the truth to 1e-9). It used to go on to steps of 1e-4 sigma in the final
    // pass and 5e-4 in the others: one evaluation in six more, for a thousandth of a sigma that
    // no figure of tests/calib or `roadside bench calib` showed.
    solver.options.function_tolerance = 1e-4;
    solver.options.parameter_tolerance = opt->rough ? 1e-8 : 1e-12;
    solver.options.gradient_tolerance = opt->rough ? 1e-10 : 1e-16;
    solver.options.cost_threshold = 0.0;
    typename Solver::Parameters x = c;
    const Sized<P> sized{f};
    const auto &sum = solver.Solve(sized, &x);
    c = x;
    *iterations = std::max(sum.iterations, 0);
    *hit_max = sum.status == Solver::HIT_MAX_ITERATIONS;
}

rs_status refine(double rt[6], double *intrinsics, double *p_c, rs_calib_refine_summary *summary, double *cov,
                 double *block_chi2, double *q_pred, const rs_calib_refine_problem *pb,
                 const rs_calib_refine_options *opt, rs_err *err)
{
    const int Ni = mrcal_lensmodel_num_params(pb->lensmodel);
    if (Ni < 4 || pb->N < 0) return rs_err_set(err, RS_ERR_INVALID, "refine: bad sizes");
    const bool refine_i = opt->refine != RS_CALIB_REFINE_NONE;
    Reduced f(pb, opt, intrinsics, p_c);
    const int nc = f.NumParameters(), nres = f.NumResiduals();

    Vec c = Vec::Zero(nc);
    for (int j = 0; j < 6; j++) c(j) = rt[j];
    Vec r0(nres);
    if (!f(c.data(), r0.data(), nullptr))
        return rs_err_set(err, RS_ERR_DEGENERATE, "refine: a landmark cannot be projected at the starting pose");

    int iterations = 0;
    bool hit_max = false;
    if (nc == 6) // no refined intrinsics (the common case): Eigen's fixed-size 6 x 6 algebra
        solve_lm<6>(&iterations, &hit_max, f, c, opt);
    else
        solve_lm<Eigen::Dynamic>(&iterations, &hit_max, f, c, opt);
    summary->iterations = iterations;
    summary->condition_number = NAN;
    if (hit_max && !opt->rough)
        return rs_err_set(err, RS_ERR_NOCONVERGE, "refine: no convergence in %d iterations", summary->iterations);

    // The solution, unrobust: residuals, reduced Jacobian, per-landmark statistics.
    Vec r(nres);
    Mat J(nres, nc);
    const bool kept = f.unrobust_at(c.data(), r.data(), J.data());
    f.set_robust(false, 0.0);
    if ((!kept && !f(c.data(), r.data(), J.data())) || !r.allFinite())
        return rs_err_set(err, RS_ERR_NOCONVERGE, "refine: the solution does not project every landmark");
    for (int j = 0; j < 6; j++) rt[j] = c(j);
    std::memcpy(intrinsics, f.intrinsics(c.data()), sizeof(double) * (size_t)Ni);
    summary->chi2 = r.squaredNorm(); // includes the position and intrinsics priors
    int Nfree = 6 + f.k(), Nresiduals = nres - 3 * (int)f.used().size() - (f.carrier() ? 1 : 0);
    std::vector<bool> used((size_t)pb->N, false);
    for (int i : f.used()) {
        used[(size_t)i] = true;
        Nfree += f.landmarks()[(size_t)i].nfree;
        Nresiduals += f.landmarks()[(size_t)i].naxes; // s has no prior row
        std::memcpy(&p_c[3 * i], &f.p()[3 * (size_t)i], 3 * sizeof(double));
        if (pb->along_c && pb->s_along_m) pb->s_along_m[i] = f.s()[(size_t)i];
    }
    summary->Nresiduals = Nresiduals;
    summary->Nfree = Nfree;
    int row = 0;
    for (int i = 0; i < pb->N; i++) {
        double ri[5];
        if (used[(size_t)i]) {
            std::memcpy(ri, &r((Eigen::Index)row), sizeof ri);
            row += 5;
        } else if (!f.at_current(i, c.data(), ri)) { // an outlier that does not project: say so
            if (block_chi2) block_chi2[i] = INFINITY;
            if (q_pred) q_pred[2 * i] = q_pred[2 * i + 1] = NAN;
            continue;
        }
        if (block_chi2) block_chi2[i] = ri[0] * ri[0] + ri[1] * ri[1] + ri[2] * ri[2] + ri[3] * ri[3] + ri[4] * ri[4];
        if (q_pred) {
            const double sig = pb->sigma_px ? pb->sigma_px[i] : 1.0;
            q_pred[2 * i] = pb->q_px[2 * i] + ri[0] * sig;
            q_pred[2 * i + 1] = pb->q_px[2 * i + 1] + ri[1] * sig;
        }
    }
    if (!opt->covariance) return RS_OK;

    Mat cov_tangent;
    summary->condition_number = reduced_condition(&cov_tangent, J);
    if (!(summary->condition_number < kConditionSingular))
        return rs_err_set(err, RS_ERR_DEGENERATE,
                          "the landmarks do not determine the pose%s: the Jacobian is "
                          "rank-deficient (condition number %.3g)",
                          refine_i ? " and the refined intrinsics" : "", summary->condition_number);
    if (cov) { // tangent -> ambient: rt as it is, the intrinsics through their basis
        const int n = 6 + Ni;
        Mat P = Mat::Zero(n, nc);
        P.topLeftCorner(6, 6).setIdentity();
        for (int j = 0; j < f.k(); j++)
            for (int a = 0; a < Ni; a++) P(6 + a, 6 + j) = f.basis()[(size_t)j * Ni + a];
        const Mat C = P * cov_tangent * P.transpose();
        for (int a = 0; a < n; a++)
            for (int b = 0; b < n; b++) cov[a * n + b] = C(a, b);
    }
    return RS_OK;
}

} // namespace

extern "C" double rs_calib_refine_jacobian_check(const double rt_cam_c[6], const double *intrinsics,
                                                 const double *p_c_m, const rs_calib_refine_problem *pb)
{
    try {
        const int Ni = mrcal_lensmodel_num_params(pb->lensmodel);
        double worst = 0.0;
        std::vector<double> dq_di(2 * (size_t)Ni), J2(5 * (size_t)Ni), x2(intrinsics, intrinsics + Ni);
        for (int i = 0; i < pb->N; i++) {
            const Landmark L(&pb->q_px[2 * i], pb->sigma_px ? pb->sigma_px[i] : 1.0, &pb->p_survey_c_m[3 * i],
                             pb->sigma_enu_m ? &pb->sigma_enu_m[3 * i] : nullptr, nullptr);
            std::vector<double> x0(rt_cam_c, rt_cam_c + 6), x1(&p_c_m[3 * i], &p_c_m[3 * i] + 3);
            std::vector<double> *blocks[3] = {&x0, &x1, &x2};
            double J0[30], J1[15];
            double *J[3] = {J0, J1, J2.data()};
            double r[5], rp[5], rm[5];
            auto eval = [&](double *out, bool jac) {
                return L.evaluate(out, jac ? J0 : nullptr, jac ? J1 : nullptr, jac ? J2.data() : nullptr, dq_di.data(),
                                  pb->lensmodel, Ni, Pose(x0.data()), x2.data(), x1.data(), 0.0);
            };
            if (!eval(r, true)) return NAN;
            for (int b = 0; b < 3; b++) {
                const int n = (int)blocks[b]->size();
                for (int row = 0; row < 5; row++) {
                    double scale = 0.0, e = 0.0;
                    for (int j = 0; j < n; j++) scale = std::fmax(scale, std::fabs(J[b][row * n + j]));
                    for (int j = 0; j < n; j++) {
                        double &xj = (*blocks[b])[(size_t)j];
                        const double saved = xj, h = 1e-6 * std::fmax(1.0, std::fabs(saved));
                        xj = saved + h;
                        if (!eval(rp, false)) return NAN;
                        xj = saved - h;
                        if (!eval(rm, false)) return NAN;
                        xj = saved;
                        e = std::fmax(e, std::fabs((rp[row] - rm[row]) / (2 * h) - J[b][row * n + j]));
                    }
                    if (scale > 0.0) worst = std::fmax(worst, e / scale);
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
    try {
        return refine(rt_cam_c, intrinsics, p_c_m, summary, cov, block_chi2, q_pred_px, problem, opt, err);
    } catch (const std::bad_alloc &) {
        return rs_err_set(err, RS_ERR_NOMEM, "refine: out of memory");
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "refine: %s", e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "refine: unknown exception");
    }
}

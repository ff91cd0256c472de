// rs_calib_opengv.cc -- shim over OpenGV's absolute-pose solvers; see rs_calib_opengv.h.
//
// Only the glue lives here: adapters, the seeded sampler, the pose layout conversion. The
// pixel scoring is the caller's (rs_calib_init.c), through a callback.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <functional>
#include <iostream>
#include <memory>
#include <new>
#include <random>
#include <vector>

#include <opengv/absolute_pose/CentralAbsoluteAdapter.hpp>
#include <opengv/absolute_pose/methods.hpp>
#include <opengv/sac/Ransac.hpp>
#include <opengv/sac_problems/absolute_pose/AbsolutePoseSacProblem.hpp>

extern "C" {
#include "calib/rs_calib_opengv.h"
}

namespace {

using opengv::sac_problems::absolute_pose::AbsolutePoseSacProblem;

// OpenGV writes to std::cout / std::cerr from inside its solvers (EPnP's "God damnit, A is
// singular" on flat or degenerate input). The library never prints: while one of these guards
// lives, both streams write nowhere. (Not thread-safe: the streams are global. roadside calls
// OpenGV from one thread at a time.)
class QuietStreams {
  public:
    QuietStreams() : out_(std::cout.rdbuf(nullptr)), err_(std::cerr.rdbuf(nullptr)) {}
    ~QuietStreams()
    {
        std::cout.rdbuf(out_);
        std::cerr.rdbuf(err_);
        std::cout.clear();
        std::cerr.clear();
    }
    QuietStreams(const QuietStreams &) = delete;
    QuietStreams &operator=(const QuietStreams &) = delete;

  private:
    std::streambuf *out_, *err_;
};

// OpenGV's transformation_t is [R_ref_cam | c_ref] (camera orientation and position in the
// reference frame). mrcal's Rt_cam_ref is the inverse, stored as (4,3): R_cam_ref then t.
void model_to_Rt(double *Rt, const opengv::transformation_t &T)
{
    const Eigen::Matrix3d R_cam_ref = T.block<3, 3>(0, 0).transpose();
    const Eigen::Vector3d t = -R_cam_ref * T.col(3);
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) Rt[3 * i + j] = R_cam_ref(i, j);
        Rt[9 + i] = t(i);
    }
}

struct Correspondences {
    opengv::bearingVectors_t v;
    opengv::points_t p;
    Correspondences(const double *v_cam, const double *p_ref, int N)
    {
        v.reserve((size_t)N);
        p.reserve((size_t)N);
        for (int i = 0; i < N; i++) {
            v.emplace_back(v_cam[3 * i], v_cam[3 * i + 1], v_cam[3 * i + 2]);
            p.emplace_back(p_ref[3 * i], p_ref[3 * i + 1], p_ref[3 * i + 2]);
        }
    }
};

// OpenGV's P3P sample-consensus problem with three changes: the sampler is seeded from the
// caller's seed, the distances are the caller's pixel errors, and a sample on which the chosen
// P3P solver finds nothing is retried with the other one (made when first needed).
// The engine takes the seed folded to one word, by its own seeding recurrence: std::seed_seq
// over its 624 words of state, and a second problem made for the rare fallback (another engine
// seeded), were half of a 4-landmark RANSAC's time.
class PixelP3pProblem : public AbsolutePoseSacProblem {
  public:
    PixelP3pProblem(adapter_t &adapter, algorithm_t primary, const std::vector<int> &indices, uint64_t seed,
                    rs_calib_opengv_score_fn *score, void *cookie)
        : AbsolutePoseSacProblem(adapter, primary, indices, false), adapter_(adapter),
          other_(primary == KNEIP ? GAO : KNEIP), indices_(indices), score_(score), cookie_(cookie)
    {
        rng_alg_.seed((uint32_t)(seed ^ (seed >> 32)));
        // OpenGV's generator binds a copy of rng_alg_: rebind it to the reseeded engine.
        rng_gen_.reset(new std::function<int()>(std::bind(*rng_dist_, rng_alg_)));
    }

    bool computeModelCoefficients(const std::vector<int> &indices, model_t &model) const override
    {
        if (AbsolutePoseSacProblem::computeModelCoefficients(indices, model) && model.allFinite()) return true;
        ++Nfallback;
        if (!fallback_) fallback_.reset(new AbsolutePoseSacProblem(adapter_, other_, indices_, false));
        return fallback_->computeModelCoefficients(indices, model) && model.allFinite();
    }

    void getSelectedDistancesToModel(const model_t &model, const std::vector<int> &indices,
                                     std::vector<double> &scores) const override
    {
        double Rt[12];
        model_to_Rt(Rt, model);
        const size_t n0 = scores.size();
        scores.resize(n0 + indices.size());
        score_(scores.data() + n0, Rt, indices.data(), (int)indices.size(), cookie_);
    }

    mutable int Nfallback = 0;

  private:
    adapter_t &adapter_;
    algorithm_t other_;
    std::vector<int> indices_;
    mutable std::unique_ptr<AbsolutePoseSacProblem> fallback_;
    rs_calib_opengv_score_fn *score_;
    void *cookie_;
};

// The solutions of one of OpenGV's solvers (upnp(), p3p_kneip(), p3p_gao()), a vector allocated
// inside libopengv with plain malloc (glibc's 16-byte alignment is Eigen's default). Under
// AddressSanitizer, Eigen switches THIS translation unit to its hand-made aligned allocator
// (Eigen/src/Core/util/Memory.h defines no EIGEN_MALLOC_ALREADY_ALIGNED with
// __SANITIZE_ADDRESS__), whose free() would not match; so there the buffer goes back to free()
// directly. Elsewhere the vector is destroyed as usual. `solve` returns the vector: it is moved
// in, never copied or reallocated here.
struct Solutions {
    alignas(opengv::transformations_t) unsigned char raw[sizeof(opengv::transformations_t)];
    opengv::transformations_t &Ts;
    template <class Solve> explicit Solutions(Solve solve) : Ts(*new (raw) opengv::transformations_t(solve())) {}
    ~Solutions()
    {
#if defined(__SANITIZE_ADDRESS__)
        std::free(Ts.data());
#else
        Ts.~vector();
#endif
    }
    Solutions(const Solutions &) = delete;
    Solutions &operator=(const Solutions &) = delete;
};

// Every triple of the usable observations through P3P (the other solver where the chosen one
// finds nothing), each solution scored on all of them: the most inliers win, ties to the
// smaller truncated sum of squares (MSAC). Stops at a solution every observation agrees with.
// For few observations, where a random sampler's setup (seeding std::mt19937) cost more than
// the samples; see rs_calib_opengv.h.
bool exhaustive_p3p(double *Rt_best, bool *inlier, int *Ntried, int *Nfallback,
                    const opengv::absolute_pose::CentralAbsoluteAdapter &adapter, int N, const int *usable, int Nusable,
                    rs_calib_opengv_p3p method, double threshold_px, rs_calib_opengv_score_fn *score, void *cookie)
{
    std::vector<double> err((size_t)Nusable);
    int best_count = -1;
    double best_cost = INFINITY, Rt[12];
    *Ntried = *Nfallback = 0;
    for (int a = 0; a < Nusable && best_count < Nusable; a++)
        for (int b = a + 1; b < Nusable && best_count < Nusable; b++)
            for (int c = b + 1; c < Nusable && best_count < Nusable; c++) {
                const size_t i0 = (size_t)usable[a], i1 = (size_t)usable[b], i2 = (size_t)usable[c];
                const bool kneip = method == RS_CALIB_OPENGV_P3P_KNEIP;
                auto p3p = [&](bool k) { // each a prvalue: built in place, in Solutions' storage
                    if (k) return opengv::absolute_pose::p3p_kneip(adapter, i0, i1, i2);
                    return opengv::absolute_pose::p3p_gao(adapter, i0, i1, i2);
                };
                Solutions first([&] { return p3p(kneip); });
                (*Ntried)++;
                (*Nfallback) += first.Ts.empty();
                Solutions other([&] {
                    if (first.Ts.empty()) return p3p(!kneip);
                    return opengv::transformations_t();
                });
                for (const opengv::transformation_t &T : first.Ts.empty() ? other.Ts : first.Ts) {
                    if (!T.allFinite()) continue;
                    model_to_Rt(Rt, T);
                    score(err.data(), Rt, usable, Nusable, cookie);
                    int count = 0;
                    double cost = 0;
                    for (int k = 0; k < Nusable; k++) {
                        count += err[(size_t)k] < threshold_px;
                        cost += std::fmin(err[(size_t)k] * err[(size_t)k], threshold_px * threshold_px);
                    }
                    if (count > best_count || (count == best_count && cost < best_cost)) {
                        best_count = count, best_cost = cost;
                        std::copy(Rt, Rt + 12, Rt_best);
                        for (int i = 0; i < N; i++) inlier[i] = false;
                        for (int k = 0; k < Nusable; k++) inlier[usable[k]] = err[(size_t)k] < threshold_px;
                    }
                }
            }
    return best_count >= 0;
}

} // namespace

extern "C" rs_status rs_calib_opengv_ransac_p3p(double *Rt_cam_ref, bool *inlier, int *Niterations, int *Nfallback,
                                                const double *v_cam, const double *p_ref, int N, const int *usable,
                                                int Nusable, rs_calib_opengv_p3p method, double threshold_px,
                                                int max_iterations, double confidence, uint64_t seed,
                                                rs_calib_opengv_score_fn *score, void *cookie, rs_err *err)
{
    QuietStreams quiet;
    try {
        Correspondences c(v_cam, p_ref, N);
        opengv::absolute_pose::CentralAbsoluteAdapter adapter(c.v, c.p);
        if (Nusable <= RS_CALIB_OPENGV_EXHAUSTIVE_MAX) {
            int Ntried = 0, Nfb = 0;
            const bool ok = exhaustive_p3p(Rt_cam_ref, inlier, &Ntried, &Nfb, adapter, N, usable, Nusable, method,
                                           threshold_px, score, cookie);
            if (Niterations) *Niterations = Ntried;
            if (Nfallback) *Nfallback = Nfb;
            if (!ok) return rs_err_set(err, RS_ERR_DEGENERATE, "P3P: no triple of observations gave a pose");
            return RS_OK;
        }
        const std::vector<int> indices(usable, usable + Nusable);
        auto problem = std::make_shared<PixelP3pProblem>(
            adapter, method == RS_CALIB_OPENGV_P3P_GAO ? AbsolutePoseSacProblem::GAO : AbsolutePoseSacProblem::KNEIP,
            indices, seed, score, cookie);
        opengv::sac::Ransac<AbsolutePoseSacProblem> ransac(max_iterations, threshold_px, confidence);
        ransac.sac_model_ = problem;
        const bool ok = ransac.computeModel(0);
        if (Niterations) *Niterations = ransac.iterations_;
        if (Nfallback) *Nfallback = problem->Nfallback;
        if (!ok || !ransac.model_coefficients_.allFinite())
            return rs_err_set(err, RS_ERR_DEGENERATE, "P3P RANSAC: no sample of 4 observations gave a pose");
        model_to_Rt(Rt_cam_ref, ransac.model_coefficients_);
        for (int i = 0; i < N; i++) inlier[i] = false;
        for (int i : ransac.inliers_)
            if (i >= 0 && i < N) inlier[i] = true;
        return RS_OK;
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenGV P3P RANSAC threw: %s", e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenGV P3P RANSAC threw an unknown exception");
    }
}

extern "C" rs_status rs_calib_opengv_pose(double *Rt_cam_ref, const double *v_cam, const double *p_ref, int N,
                                          rs_calib_opengv_pose_method method, double threshold_rad, int max_iterations,
                                          rs_err *err)
{
    static const char *const names[] = {"P3P Kneip RANSAC", "P3P Gao RANSAC", "EPnP", "UPnP",
                                        "EPnP + optimize_nonlinear"};
    const char *name = (unsigned)method < 5 ? names[method] : "?";
    QuietStreams quiet;
    try {
        if (N < 4 || (unsigned)method >= 5)
            return rs_err_set(err, RS_ERR_USAGE, "OpenGV %s: N = %d (needs >= 4)", name, N);
        Correspondences c(v_cam, p_ref, N);
        opengv::absolute_pose::CentralAbsoluteAdapter adapter(c.v, c.p);
        opengv::transformation_t T;
        if (method == RS_CALIB_OPENGV_POSE_P3P_KNEIP_RANSAC || method == RS_CALIB_OPENGV_POSE_P3P_GAO_RANSAC) {
            auto problem = std::make_shared<AbsolutePoseSacProblem>(adapter,
                                                                    method == RS_CALIB_OPENGV_POSE_P3P_GAO_RANSAC
                                                                        ? AbsolutePoseSacProblem::GAO
                                                                        : AbsolutePoseSacProblem::KNEIP,
                                                                    false);
            opengv::sac::Ransac<AbsolutePoseSacProblem> ransac(max_iterations, 1.0 - std::cos(threshold_rad), 0.99);
            ransac.sac_model_ = problem;
            if (!ransac.computeModel(0))
                return rs_err_set(err, RS_ERR_DEGENERATE, "OpenGV %s: no sample gave a pose", name);
            T = ransac.model_coefficients_;
        } else if (method == RS_CALIB_OPENGV_POSE_UPNP) {
            Solutions sol([&] { return opengv::absolute_pose::upnp(adapter); });
            const opengv::transformations_t &Ts = sol.Ts;
            double best = INFINITY;
            for (const opengv::transformation_t &Ti : Ts) {
                if (!Ti.allFinite()) continue;
                double e = 0.0;
                for (int i = 0; i < N; i++) {
                    const Eigen::Vector3d d =
                        (Ti.block<3, 3>(0, 0).transpose() * (c.p[(size_t)i] - Ti.col(3))).normalized();
                    e += 1.0 - d.dot(c.v[(size_t)i]);
                }
                if (e < best) {
                    best = e;
                    T = Ti;
                }
            }
            if (!(best < INFINITY)) return rs_err_set(err, RS_ERR_DEGENERATE, "OpenGV %s: no finite solution", name);
        } else {
            T = opengv::absolute_pose::epnp(adapter);
            if (method == RS_CALIB_OPENGV_POSE_EPNP_NONLINEAR && T.allFinite()) {
                adapter.sett(T.col(3));
                adapter.setR(T.block<3, 3>(0, 0));
                T = opengv::absolute_pose::optimize_nonlinear(adapter);
            }
        }
        if (!T.allFinite()) return rs_err_set(err, RS_ERR_DEGENERATE, "OpenGV %s: non-finite pose", name);
        model_to_Rt(Rt_cam_ref, T);
        return RS_OK;
    } catch (const std::exception &e) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenGV %s threw: %s", name, e.what());
    } catch (...) {
        return rs_err_set(err, RS_ERR_EXTERNAL, "OpenGV %s threw an unknown exception", name);
    }
}

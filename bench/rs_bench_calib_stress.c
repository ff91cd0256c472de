// rs_bench_calib_stress.c -- roadside bench calib --stress: many random problems solved with
// rs_calib_solve, every output checked for finiteness, every failure for a message, every
// ill-conditioned pose for its warning (see rs_bench_calib_stress in rs_bench_calib.h).
#include "bench/rs_bench_calib.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "calib/rs_calib.h"
#include "core/rs_rng.h"
#include "sim/rs_simulate.h"

static bool all_finite(const double *v, int n)
{
    for (int i = 0; i < n; i++)
        if (!isfinite(v[i])) return false;
    return true;
}

// Random options of stress problem `seed` (see the header for the ranges).
static void stress_options(rs_simulate_camera_options *s, uint64_t seed)
{
    static const char *const lens[] = {"LENSMODEL_PINHOLE", "LENSMODEL_OPENCV8", "LENSMODEL_CAHVOR"};
    rs_rng rng;
    rs_rng_seed(&rng, seed ^ 0x5eed5eed5eedull);
#define U() rs_rng_uniform(&rng)
    rs_simulate_camera_options_default(s);
    s->seed = seed;
    s->lensmodel = lens[(int)(3 * U())];
    s->hfov_deg = 20 + 70 * U();
    s->Nlandmarks = 4 + (int)(37 * U());
    s->pixel_sigma_px = pow(10.0, -3.0 + 3.7 * U());
    s->outlier_fraction = U() < 0.3 ? 0.0 : 0.5 * U();
    s->survey_sigma_h_m = U() < 0.2 ? 0.0 : 2.0 * U();
    s->survey_sigma_v_m = s->survey_sigma_h_m * (0.5 + U());
    s->elevated_fraction = U() < 0.4 ? 0.0 : 0.5 * U();
    s->camera_height_m = 3.0 * pow(100.0 / 3.0, U());
    s->distance_m = 10.0 * pow(200.0, U());
    s->max_range_m = s->distance_m * (1.5 + 2.0 * U());
    s->roll_sigma_deg = 3.0 * U();
#undef U
}

// Cholesky solve of the 6x6 SPD covariance: returns d^T C^-1 d, or NAN if C is not SPD.
static double mahalanobis2(const double *C, const double *d)
{
    double L[36] = {0}, y[6];
    for (int i = 0; i < 6; i++)
        for (int j = 0; j <= i; j++) {
            double s = C[6 * i + j];
            for (int k = 0; k < j; k++) s -= L[6 * i + k] * L[6 * j + k];
            if (i == j) {
                if (!(s > 0)) return NAN;
                L[6 * i + i] = sqrt(s);
            } else {
                L[6 * i + j] = s / L[6 * j + j];
            }
        }
    double m2 = 0;
    for (int i = 0; i < 6; i++) {
        double s = d[i];
        for (int k = 0; k < i; k++) s -= L[6 * i + k] * y[k];
        y[i] = s / L[6 * i + i];
        m2 += y[i] * y[i];
    }
    return m2;
}

// d = r_est - r_true in the chart of r_est (where the covariance is stated), with r_true written
// as whichever of its two Rodrigues vectors (angle theta about u, or theta - 2 pi about u) is
// nearer: near a half-turn the same rotation has r and nearly -r, and a plain difference of the
// vectors would call a perfect estimate wrong.
static void rotation_difference(double d[3], const double r_est[3], const double r_true[3])
{
    const double th = sqrt(r_true[0] * r_true[0] + r_true[1] * r_true[1] + r_true[2] * r_true[2]);
    double best = INFINITY;
    for (int alt = 0; alt < 2; alt++) {
        if (alt && !(th > 0)) break;
        const double s = alt ? 1.0 - 2.0 * M_PI / th : 1.0;
        double e[3], n2 = 0;
        for (int k = 0; k < 3; k++) {
            e[k] = r_est[k] - s * r_true[k];
            n2 += e[k] * e[k];
        }
        if (n2 < best) {
            best = n2;
            memcpy(d, e, sizeof e);
        }
    }
}

static void stress_bad(rs_bench_calib_stress_summary *S, uint64_t seed, const char *what, double v)
{
    if (S->first_bad[0]) return;
    S->first_bad_seed = seed;
    snprintf(S->first_bad, sizeof S->first_bad, "%s (%.3g)", what, v);
}

// Solves one stress problem and checks the result (see the header).
static void stress_one(rs_bench_calib_stress_summary *S, uint64_t seed)
{
    rs_simulate_camera_options s;
    stress_options(&s, seed);
    rs_simulate_problem *P = NULL;
    if (rs_simulate_camera_problem(&P, &s, NULL) != RS_OK) return;
    S->Ngenerated++;
    const int N = P->Npoints;
    double *sig = malloc(sizeof(double) * 4 * (size_t)N);
    if (!sig) {
        rs_simulate_problem_free(P);
        return;
    }
    for (int i = 0; i < N; i++) {
        sig[3 * i] = sig[3 * i + 1] = s.survey_sigma_h_m;
        sig[3 * i + 2] = s.survey_sigma_v_m;
        sig[3 * N + i] = fmax(s.pixel_sigma_px, 1e-3);
    }
    rs_calib_problem cp = {.N = N,
                           .p_enu_m = P->p_enu_survey_m,
                           .sigma_enu_m = sig,
                           .q_px = P->q_px,
                           .sigma_px = sig + 3 * N,
                           .camera = &P->camera};
    rs_calib_options opt;
    rs_calib_options_default(&opt);
    rs_calib_result r;
    rs_err e = {0};
    const rs_status st = rs_calib_solve(&r, &cp, &opt, &e);
    if (st != RS_OK) {
        S->Nerror[(unsigned)st < 16 ? st : 15]++;
        if (strlen(e.msg) < 8) {
            S->Nunnamed++;
            stress_bad(S, seed, "an error without a message, status", st);
        }
    } else {
        S->Nok++;
        const bool finite = all_finite(r.rt_cam_enu, 6) && all_finite(r.covariance_rt_cam_enu, 36) &&
                            all_finite(r.position_enu_m, 3) && all_finite(r.sigma_position_enu_m, 3) &&
                            all_finite(r.yaw_pitch_roll_deg, 3) && all_finite(r.sigma_yaw_pitch_roll_deg, 3) &&
                            isfinite(r.rms_px) && isfinite(r.condition_number) && isfinite(r.variance_factor) &&
                            r.region_m2 > 0 && isfinite(r.region_m2);
        bool diag = true;
        for (int k = 0; k < 6; k++) diag = diag && r.covariance_rt_cam_enu[7 * k] > 0;
        if (!finite || !diag) {
            S->Nnonfinite++;
            stress_bad(S, seed, finite ? "covariance diagonal not positive" : "non-finite output", 0);
        }
        const bool flagged = r.condition_number > opt.condition_warn;
        if (flagged) {
            S->Nflagged++;
            if (!strstr(r.warnings, "condition number")) {
                S->Nunflagged++;
                stress_bad(S, seed, "condition number beyond the bound without a warning", r.condition_number);
            }
        }
        if (isfinite(r.condition_number)) S->cond_max = fmax(S->cond_max, r.condition_number);
        double d[6];
        rotation_difference(d, r.rt_cam_enu, P->camera.rt_cam_enu);
        for (int k = 3; k < 6; k++) d[k] = r.rt_cam_enu[k] - P->camera.rt_cam_enu[k];
        const double m2 = mahalanobis2(r.covariance_rt_cam_enu, d);
        S->Nwarned += r.warnings[0] != 0;
        // a warning besides the generic one that the focal, taken as exact, cannot be checked
        bool other = flagged;
        char buf[sizeof r.warnings], *save = NULL;
        snprintf(buf, sizeof buf, "%s", r.warnings);
        for (char *w = strtok_r(buf, ";", &save); w && !other; w = strtok_r(NULL, ";", &save))
            other = strspn(w, " ") != strlen(w) && !strstr(w, "these landmarks cannot check it");
        S->Nbare += !other;
        if (!(m2 <= r.region_m2)) {
            S->Nout999++;
            S->Nout999_unwarned += !r.warnings[0] && !flagged;
            S->Nout999_bare += !other;
        }
        S->Nbeyond10 += !(m2 <= 100.0);
        S->Nbeyond10_bare += !(m2 <= 100.0) && !other;
        if (!flagged && !r.warnings[0] && !(m2 <= 100.0)) {
            S->Nbad++;
            stress_bad(S, seed, "a confident wrong pose: Mahalanobis distance", sqrt(m2));
        }
    }
    rs_calib_result_free(&r);
    free(sig);
    rs_simulate_problem_free(P);
}

rs_status rs_bench_calib_stress(rs_bench_calib_stress_summary *summary, int Nproblems, uint64_t seed, rs_err *err)
{
    memset(summary, 0, sizeof *summary);
    if (Nproblems < 1) return rs_err_set(err, RS_ERR_USAGE, "stress: Nproblems = %d, must be >= 1", Nproblems);
    summary->Nproblems = Nproblems;
    for (int k = 0; k < Nproblems; k++) stress_one(summary, seed + (uint64_t)k);
    return RS_OK;
}

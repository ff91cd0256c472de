// test_stress_ecef.c -- issue 5, "why ENU": the same noise-free camera solved with coordinates in
// the site ENU frame and in ECEF (values near 6.4e6 m).
//   1. OpenCV's solvePnP (ITERATIVE + solvePnPRefineLM, as a user would call it) in ENU recovers
//      the true camera position to < 1e-6 m; in ECEF it loses precision: the test measures the
//      loss and asserts it is at least 100x (or that OpenCV fails outright).
//   2. The conditioning explains it: the 6x6 Gauss-Newton matrix J^T J of the pixel residuals
//      with respect to rt (central differences through mrcal_project -- an oracle independent
//      of any solver) has a condition number at least 1e6 times larger in ECEF.
//   3. roadside never takes that route: rs_calib_solve, handed the ECEF coordinates directly,
//      still returns the truth (< 1e-6 m), because it solves about the landmarks' centroid; and
//      no source file of the solver path (calib/rs_calib*.c*, calib/rs_calib_site.c) mentions
//      ECEF at all: landmarks reach it as site ENU (geo/rs_site.h).
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mrcal/mrcal.h>
#include <mrcal/poseutils.h>

#include "bench/rs_bench_opencv.h"
#include "calib/rs_calib.h"
#include "core/rs_io.h"
#include "core/rs_pose.h"
#include "geo/rs_geo.h"
#include "sim/rs_simulate.h"
#include "test_solve_gen.h"

#define SEED 11
#define NL   20

static double position_error(const double rt[6], const double C_true[3])
{
    double C[3];
    rs_pose_position_from_rt(C, NULL, rt);
    return hypot(hypot(C[0] - C_true[0], C[1] - C_true[1]), C[2] - C_true[2]);
}

// Condition number of J^T J, J = d(pixels)/d(rt) by central differences (steps 1e-7 rad and
// 1e-4 m: well inside the linear range, far above rounding at 6e6 m), columns not scaled.
static double jtj_condition(const double rt[6], const double *p, const rs_simulate_problem *s)
{
    double J[2 * NL][6];
    for (int j = 0; j < 6; j++) {
        const double h = j < 3 ? 1e-7 : 1e-4;
        double rp[6], rm[6];
        memcpy(rp, rt, sizeof rp);
        memcpy(rm, rt, sizeof rm);
        rp[j] += h;
        rm[j] -= h;
        for (int i = 0; i < NL; i++) {
            mrcal_point3_t a, b;
            mrcal_point2_t qa, qb;
            mrcal_transform_point_rt(a.xyz, NULL, NULL, rp, &p[3 * i]);
            mrcal_transform_point_rt(b.xyz, NULL, NULL, rm, &p[3 * i]);
            mrcal_project(&qa, NULL, NULL, &a, 1, &s->camera.lensmodel, s->camera.intrinsics);
            mrcal_project(&qb, NULL, NULL, &b, 1, &s->camera.lensmodel, s->camera.intrinsics);
            J[2 * i][j] = (qa.x - qb.x) / (2 * h);
            J[2 * i + 1][j] = (qa.y - qb.y) / (2 * h);
        }
    }
    // eigenvalues of the symmetric 6x6 J^T J by cyclic Jacobi rotations
    double A[6][6];
    for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++) {
            A[a][b] = 0;
            for (int i = 0; i < 2 * NL; i++) A[a][b] += J[i][a] * J[i][b];
        }
    for (int sweep = 0; sweep < 100; sweep++) {
        double off = 0;
        for (int a = 0; a < 6; a++)
            for (int b = a + 1; b < 6; b++) off += A[a][b] * A[a][b];
        if (off < 1e-300) break;
        for (int a = 0; a < 6; a++)
            for (int b = a + 1; b < 6; b++) {
                if (A[a][b] == 0) continue;
                const double th = 0.5 * atan2(2 * A[a][b], A[b][b] - A[a][a]), c = cos(th), sn = sin(th);
                for (int k = 0; k < 6; k++) {
                    const double x = A[k][a], y = A[k][b];
                    A[k][a] = c * x - sn * y;
                    A[k][b] = sn * x + c * y;
                }
                for (int k = 0; k < 6; k++) {
                    const double x = A[a][k], y = A[b][k];
                    A[a][k] = c * x - sn * y;
                    A[b][k] = sn * x + c * y;
                }
            }
    }
    double lo = INFINITY, hi = 0;
    for (int a = 0; a < 6; a++) lo = fmin(lo, fabs(A[a][a])), hi = fmax(hi, fabs(A[a][a]));
    return hi / lo;
}

static bool mentions_ecef(const char *root, const char *rel)
{
    char *path = rs_io_join(root, rel), *text = NULL;
    const bool ok = path && rs_io_read_file(&text, NULL, path, NULL) == RS_OK;
    CHECK(ok, "cannot read %s", rel);
    bool found = false;
    for (char *c = text; ok && *c; c++) {
        if (tolower((unsigned char)c[0]) == 'e' && tolower((unsigned char)c[1]) == 'c' &&
            tolower((unsigned char)c[2]) == 'e' && tolower((unsigned char)c[3]) == 'f')
            found = true;
    }
    free(text);
    free(path);
    return found;
}

int main(void)
{
    gen_begin();
    rs_simulate_camera_options o;
    rs_simulate_camera_options_default(&o);
    o.seed = SEED, o.Nlandmarks = NL, o.pixel_sigma_px = 0, o.outlier_fraction = 0;
    o.survey_sigma_h_m = o.survey_sigma_v_m = 0;
    rs_simulate_problem *s = NULL;
    rs_err e = {0};
    CHECK(rs_simulate_camera_problem(&s, &o, &e) == RS_OK && s->Npoints == NL, "simulator: %s", e.msg);
    if (!s) return gen_end("11");

    // ENU -> ECEF at the demo site's origin (GeographicLib through rs_geo_enu_frame)
    const rs_llh origin = {48.1374, 11.5755, 560.0};
    double R_ecef_enu[9], o_ecef[3];
    CHECK(rs_geo_enu_frame(R_ecef_enu, o_ecef, &origin, &e) == RS_OK, "%s", e.msg);
    double p_ecef[3 * NL], C_enu[3], C_ecef[3];
    for (int i = 0; i < NL; i++)
        for (int a = 0; a < 3; a++) {
            p_ecef[3 * i + a] = o_ecef[a];
            for (int b = 0; b < 3; b++) p_ecef[3 * i + a] += R_ecef_enu[3 * a + b] * s->p_enu_true_m[3 * i + b];
        }
    memcpy(C_enu, s->p_cam_enu_m, sizeof C_enu);
    for (int a = 0; a < 3; a++) {
        C_ecef[a] = o_ecef[a];
        for (int b = 0; b < 3; b++) C_ecef[a] += R_ecef_enu[3 * a + b] * C_enu[b];
    }
    // the true pose in ECEF: R_cam_ecef = R_cam_enu R_ecef_enu^T, t = -R_cam_ecef C_ecef
    double R_cam_enu[9], Rt_cam_ecef[12], rt_cam_ecef[6];
    mrcal_R_from_r(R_cam_enu, NULL, s->camera.rt_cam_enu);
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) {
            Rt_cam_ecef[3 * a + b] = 0;
            for (int k = 0; k < 3; k++) Rt_cam_ecef[3 * a + b] += R_cam_enu[3 * a + k] * R_ecef_enu[3 * b + k];
        }
    for (int a = 0; a < 3; a++) {
        Rt_cam_ecef[9 + a] = 0;
        for (int k = 0; k < 3; k++) Rt_cam_ecef[9 + a] -= Rt_cam_ecef[3 * a + k] * C_ecef[k];
    }
    mrcal_rt_from_Rt(rt_cam_ecef, NULL, Rt_cam_ecef);

    // 1. OpenCV, both routes
    double rt[6];
    rs_status st = rs_bench_opencv_pnp(rt, NULL, s->p_enu_true_m, s->q_true_px, NL, s->camera.intrinsics,
                                       s->camera.Nintrinsics - 4, RS_BENCH_OPENCV_PNP_ITERATIVE, true, 8, &e);
    CHECK(st == RS_OK, "OpenCV in ENU: %s", e.msg);
    const double err_enu = st == RS_OK ? position_error(rt, C_enu) : NAN;
    st = rs_bench_opencv_pnp(rt, NULL, p_ecef, s->q_true_px, NL, s->camera.intrinsics, s->camera.Nintrinsics - 4,
                             RS_BENCH_OPENCV_PNP_ITERATIVE, true, 8, &e);
    const double err_ecef = st == RS_OK ? position_error(rt, C_ecef) : INFINITY;
    printf("OpenCV solvePnP ITERATIVE + RefineLM, noise-free: position error %.3g m in ENU, %.3g m in ECEF%s%s\n",
           err_enu, err_ecef, st == RS_OK ? "" : " -- failed: ", st == RS_OK ? "" : e.msg);
    CHECK(err_enu < 1e-6, "ENU route: %.3g m", err_enu);
    CHECK(!(err_ecef < 100 * fmax(err_enu, 1e-12)), "ECEF route lost less than 100x: %.3g vs %.3g m", err_ecef,
          err_enu);

    // 2. the conditioning at the truth
    const double k_enu = jtj_condition(s->camera.rt_cam_enu, s->p_enu_true_m, s);
    const double k_ecef = jtj_condition(rt_cam_ecef, p_ecef, s);
    printf("condition number of J^T J (rt, unscaled): %.3g in ENU, %.3g in ECEF (ratio %.3g)\n", k_enu, k_ecef,
           k_ecef / k_enu);
    CHECK(k_ecef > 1e6 * k_enu, "ECEF conditioning only %.3g x worse", k_ecef / k_enu);

    // 3. roadside, handed ECEF coordinates, still solves about the centroid
    double sig_px[NL];
    for (int i = 0; i < NL; i++) sig_px[i] = 0.01;
    const rs_calib_problem cp = {
        .N = NL, .p_enu_m = p_ecef, .q_px = s->q_true_px, .sigma_px = sig_px, .camera = &s->camera};
    rs_calib_result r;
    st = rs_calib_solve(&r, &cp, NULL, &e);
    CHECK(st == RS_OK, "roadside with ECEF coordinates: %s", e.msg);
    if (st == RS_OK) {
        const double d = position_error(r.rt_cam_enu, C_ecef);
        printf("roadside's solver handed the ECEF coordinates: position error %.3g m\n", d);
        CHECK(d < 1e-6, "roadside with ECEF coordinates: %.3g m", d);
    }
    rs_calib_result_free(&r);

    const char *root = getenv("ROADSIDE_SOURCE_ROOT");
    CHECK(root, "ROADSIDE_SOURCE_ROOT is not set");
    static const char *const solver_files[] = {
        "calib/rs_calib.c",      "calib/rs_calib_init.c",    "calib/rs_calib_refine_ceres.cc",
        "calib/rs_calib_site.c", "calib/rs_calib_opengv.cc", "calib/rs_calib_opencv.cc"};
    for (size_t i = 0; root && i < sizeof solver_files / sizeof *solver_files; i++)
        CHECK(!mentions_ecef(root, solver_files[i]), "%s mentions ECEF: the solver must work in site ENU",
              solver_files[i]);
    rs_simulate_problem_free(s);
    return gen_end("11");
}

// test_bench_adapters.c -- the benchmark's thin adapters over OpenCV (rs_bench_opencv_pnp) and
// OpenGV (rs_calib_opengv_pose): on noise-free simulated problems (exact mrcal projections of
// the simulator's true pose: the oracle) every method recovers the true pose; refusals come back
// as errors with a message, never as a throw or a print. Seed fixed, printed on failure.
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <mrcal/mrcal.h>
#include <mrcal/poseutils.h>

#include "bench/rs_bench_opencv.h"
#include "calib/rs_calib.h"
#include "calib/rs_calib_opengv.h"
#include "core/rs_pose.h"
#include "core/rs_units.h"
#include "sim/rs_simulate.h"
#include "test_solve_gen.h"

#define SEED 21

static rs_simulate_problem *noise_free(double elevated_fraction)
{
    rs_simulate_camera_options o;
    rs_simulate_camera_options_default(&o);
    o.seed = SEED, o.Nlandmarks = 20, o.pixel_sigma_px = 0, o.outlier_fraction = 0;
    o.survey_sigma_h_m = o.survey_sigma_v_m = 0, o.elevated_fraction = elevated_fraction;
    rs_simulate_problem *s = NULL;
    rs_err e = {0};
    CHECK(rs_simulate_camera_problem(&s, &o, &e) == RS_OK, "simulator: %s", e.msg);
    return s;
}

static void check_pose(const char *name, rs_status st, const rs_err *e, const double rt[6],
                       const rs_simulate_problem *s, double tol)
{
    CHECK(st == RS_OK, "%s: %s: %s", name, rs_strerror(st), e->msg);
    if (st != RS_OK) return;
    double C[3];
    rs_pose_position_from_rt(C, NULL, rt);
    const double drot = rs_pose_rotation_between(NULL, NULL, rt, s->camera.rt_cam_enu) * RS_DEG_PER_RAD;
    const double dpos = hypot(hypot(C[0] - s->p_cam_enu_m[0], C[1] - s->p_cam_enu_m[1]), C[2] - s->p_cam_enu_m[2]);
    printf("%-22s rotation error %.3g deg, position error %.3g m\n", name, drot, dpos);
    CHECK(drot < tol && dpos < tol, "%s: rotation %.3g deg, position %.3g m (tolerance %g)", name, drot, dpos, tol);
}

int main(void)
{
    gen_begin();
    rs_simulate_problem *s3d = noise_free(0.25), *s2d = noise_free(0.0);
    if (!s3d || !s2d) return gen_end("21");
    static const struct {
        const char *name;
        rs_bench_opencv_pnp_method m;
        bool lm, planar;
        double tol;
    } cv[] = {
        {"cv-iterative", RS_BENCH_OPENCV_PNP_ITERATIVE, false, false, 1e-6},
        {"cv-iterative+lm", RS_BENCH_OPENCV_PNP_ITERATIVE, true, false, 1e-6},
        {"cv-epnp", RS_BENCH_OPENCV_PNP_EPNP, false, false, 1e-3},
        {"cv-epnp+lm", RS_BENCH_OPENCV_PNP_EPNP, true, false, 1e-6},
        {"cv-sqpnp", RS_BENCH_OPENCV_PNP_SQPNP, false, false, 1e-5},
        {"cv-sqpnp+lm", RS_BENCH_OPENCV_PNP_SQPNP, true, false, 1e-6},
        {"cv-ippe (planar)", RS_BENCH_OPENCV_PNP_IPPE, false, true, 1e-6},
        {"cv-ippe+lm (planar)", RS_BENCH_OPENCV_PNP_IPPE, true, true, 1e-6},
        {"cv-ransac", RS_BENCH_OPENCV_PNP_RANSAC, false, false, 1e-6},
        {"cv-ransac+lm", RS_BENCH_OPENCV_PNP_RANSAC, true, false, 1e-6},
    };
    for (size_t i = 0; i < sizeof cv / sizeof *cv; i++) {
        const rs_simulate_problem *s = cv[i].planar ? s2d : s3d;
        double rt[6];
        bool inlier[20];
        rs_err e = {0};
        const rs_status st =
            rs_bench_opencv_pnp(rt, inlier, s->p_enu_true_m, s->q_true_px, s->Npoints, s->camera.intrinsics,
                                s->camera.Nintrinsics - 4, cv[i].m, cv[i].lm, 8.0, &e);
        check_pose(cv[i].name, st, &e, rt, s, cv[i].tol);
        int Nin = 0;
        for (int k = 0; k < s->Npoints; k++) Nin += inlier[k];
        CHECK(st != RS_OK || Nin == s->Npoints, "%s: %d inliers of %d exact points", cv[i].name, Nin, s->Npoints);
    }

    double v[3 * 20];
    CHECK(mrcal_unproject((mrcal_point3_t *)v, (const mrcal_point2_t *)s3d->q_true_px, s3d->Npoints,
                          &s3d->camera.lensmodel, s3d->camera.intrinsics),
          "mrcal_unproject");
    for (int i = 0; i < s3d->Npoints; i++) {
        const double n = sqrt(v[3 * i] * v[3 * i] + v[3 * i + 1] * v[3 * i + 1] + v[3 * i + 2] * v[3 * i + 2]);
        for (int k = 0; k < 3; k++) v[3 * i + k] /= n;
    }
    static const struct {
        const char *name;
        rs_calib_opengv_pose_method m;
        double tol;
    } gv[] = {
        {"gv-p3p-kneip-ransac", RS_CALIB_OPENGV_POSE_P3P_KNEIP_RANSAC, 1e-6},
        {"gv-p3p-gao-ransac", RS_CALIB_OPENGV_POSE_P3P_GAO_RANSAC, 1e-4},
        {"gv-epnp", RS_CALIB_OPENGV_POSE_EPNP, 1e-3},
        {"gv-upnp", RS_CALIB_OPENGV_POSE_UPNP, 1e-6},
        {"gv-epnp+nonlin", RS_CALIB_OPENGV_POSE_EPNP_NONLINEAR, 1e-6},
    };
    for (size_t i = 0; i < sizeof gv / sizeof *gv; i++) {
        double Rt[12], rt[6] = {0};
        rs_err e = {0};
        const rs_status st = rs_calib_opengv_pose(Rt, v, s3d->p_enu_true_m, s3d->Npoints, gv[i].m, 0.005, 500, &e);
        if (st == RS_OK) mrcal_rt_from_Rt(rt, NULL, Rt);
        check_pose(gv[i].name, st, &e, rt, s3d, gv[i].tol);
    }

    // the fisheye adapter (cv::fisheye::undistortPoints, then SQPnP) on an overhead Kannala-Brandt
    // camera (CAHVORE at linearity 0, r1 = k1, r2 = k2): the true pose from exact data
    {
        rs_simulate_camera_options o;
        rs_simulate_camera_options_default(&o);
        o.seed = SEED, o.Nlandmarks = 20, o.pixel_sigma_px = 0, o.outlier_fraction = 0;
        o.survey_sigma_h_m = o.survey_sigma_v_m = 0, o.elevated_fraction = 0.25;
        o.lensmodel = "LENSMODEL_CAHVORE_linearity=0.00", o.width_px = 1280, o.height_px = 960, o.hfov_deg = 216;
        o.camera_height_m = 10, o.distance_m = 3, o.max_range_m = 40;
        rs_simulate_problem *sf = NULL;
        rs_err ef = {0};
        CHECK(rs_simulate_camera_problem(&sf, &o, &ef) == RS_OK, "fisheye simulator: %s", ef.msg);
        if (sf) {
            const double *in = sf->camera.intrinsics, kb[8] = {in[0], in[1], in[2], in[3], in[7], in[8], 0, 0};
            double rtf[6] = {0};
            const rs_status stf = rs_bench_opencv_pnp_fisheye(rtf, NULL, sf->p_enu_true_m, sf->q_true_px, sf->Npoints,
                                                              kb, RS_BENCH_OPENCV_PNP_SQPNP, true, 8.0, &ef);
            check_pose("cv-sqpnp+lm (fisheye)", stf, &ef, rtf, sf, 1e-6);
        }
        rs_simulate_problem_free(sf);
    }

    // refusals: IPPE on landmarks that are not coplanar, OpenGV with 3 points, bad distortion
    double rt[6], Rt[12];
    rs_err e = {0};
    rs_status st =
        rs_bench_opencv_pnp(rt, NULL, s3d->p_enu_true_m, s3d->q_true_px, s3d->Npoints, s3d->camera.intrinsics,
                            s3d->camera.Nintrinsics - 4, RS_BENCH_OPENCV_PNP_IPPE, false, 8.0, &e);
    printf("IPPE, 3-D landmarks: %s: %s\n", rs_strerror(st), e.msg);
    CHECK(st == RS_ERR_EXTERNAL || st == RS_ERR_DEGENERATE, "IPPE on 3-D landmarks: %s", rs_strerror(st));
    CHECK(st == RS_OK || strlen(e.msg) > 10, "IPPE refusal without a message");
    e.msg[0] = 0;
    st = rs_calib_opengv_pose(Rt, v, s3d->p_enu_true_m, 3, RS_CALIB_OPENGV_POSE_EPNP, 0.005, 500, &e);
    CHECK(st == RS_ERR_USAGE && strstr(e.msg, "N = 3"), "OpenGV with 3 points: %s '%s'", rs_strerror(st), e.msg);
    st = rs_bench_opencv_pnp(rt, NULL, s3d->p_enu_true_m, s3d->q_true_px, s3d->Npoints, s3d->camera.intrinsics, -1,
                             RS_BENCH_OPENCV_PNP_EPNP, false, 8.0, &e);
    CHECK(st == RS_ERR_USAGE, "Ndistortion -1: %s", rs_strerror(st));
    rs_simulate_problem_free(s3d);
    rs_simulate_problem_free(s2d);
    return gen_end("21");
}

// test_stress_extreme.c -- issue 5's extreme geometries through rs_calib_solve: landmarks 2 km
// away, focal length 20,000 px, camera 100 m up, camera looking straight down (exactly: a
// half-turn from ENU), every landmark behind the camera, nearly collinear
// landmarks, all landmarks within a 5 px patch, 1e-6 px noise, repeated landmarks, huge
// (1e6..6e6 m) and tiny (millimetre) coordinates. Each ends either in a pose consistent with the
// truth (the oracle: the simulator's exact pose; NEES of the 6-dof pose below 50, i.e. far
// beyond any chi-square(6) tail) or in the error naming the cause. Fixed seeds, printed.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mrcal/mrcal.h>
#include <mrcal/poseutils.h>

#include "calib/rs_calib.h"
#include "core/rs_pose.h"
#include "sim/rs_simulate.h"
#include "test_solve_gen.h"

#define SEED 5

// A problem held in one place: the simulator's, or one built here through mrcal_project.
typedef struct {
    mrcal_lensmodel_t lens;
    double intrinsics[16];
    int N;
    double p[3 * 200], q[2 * 200], sigma_enu[3 * 200], sigma_px[200];
    double rt_true[6];
    int width, height;
} prob;

static void from_sim(prob *P, const rs_simulate_problem *s, double sigma_px, double sigma_m)
{
    memset(P, 0, sizeof *P);
    P->lens = s->camera.lensmodel;
    memcpy(P->intrinsics, s->camera.intrinsics, sizeof(double) * (size_t)s->camera.Nintrinsics);
    P->N = s->Npoints;
    memcpy(P->p, s->p_enu_survey_m, sizeof(double) * 3 * (size_t)P->N);
    memcpy(P->q, s->q_px, sizeof(double) * 2 * (size_t)P->N);
    for (int i = 0; i < P->N; i++) {
        P->sigma_px[i] = sigma_px;
        for (int k = 0; k < 3; k++) P->sigma_enu[3 * i + k] = sigma_m;
    }
    memcpy(P->rt_true, s->camera.rt_cam_enu, sizeof P->rt_true);
    P->width = (int)s->camera.width;
    P->height = (int)s->camera.height;
}

static bool simulate(prob *P, rs_simulate_camera_options *o, double sigma_px, double sigma_m)
{
    rs_simulate_problem *s = NULL;
    rs_err e = {0};
    o->seed = SEED;
    o->outlier_fraction = 0.0;
    o->pixel_sigma_px = sigma_px;
    o->survey_sigma_h_m = o->survey_sigma_v_m = sigma_m;
    const rs_status st = rs_simulate_camera_problem(&s, o, &e);
    CHECK(st == RS_OK, "simulator: %s", e.msg);
    if (st != RS_OK) return false;
    // the sigmas the solver is told: at least what was drawn, never zero pixels
    from_sim(P, s, fmax(sigma_px, 1e-9), sigma_m);
    rs_simulate_problem_free(s);
    return true;
}

// A pinhole camera (f px, 1920x1080) at `pos` with yaw/pitch/roll `ypr`, landmarks p (N,3),
// exact pixels + N(0, noise) from a fixed generator.
static void build(prob *P, double f, const double ypr[3], const double pos[3], const double *p, int N, double noise_px,
                  double sigma_m)
{
    memset(P, 0, sizeof *P);
    P->lens.type = MRCAL_LENSMODEL_PINHOLE;
    P->width = 1920;
    P->height = 1080;
    const double in[4] = {f, f, 959.5, 539.5};
    memcpy(P->intrinsics, in, sizeof in);
    // R_cam_enu from the simulator (exact at |pitch| = 90). A camera looking straight down is a
    // half-turn from ENU, where mrcal 2.2's r_from_R returns r = 0 (a camera looking UP); so
    // there r = pi * axis, the axis from R = 2 a a^T - I (signs relative to a[0] > 0: enough for
    // the yaw-0 case used here)
    double R[9];
    rs_pose_R_from_ypr(R, ypr);
    const double tr = R[0] + R[4] + R[8];
    if (tr < -1 + 1e-9) {
        double a[3];
        for (int k = 0; k < 3; k++) a[k] = sqrt(fmax(0.0, (R[4 * k] + 1) / 2));
        if (R[1] < 0) a[1] = -a[1]; // signs relative to the first nonzero component
        if (R[2] < 0) a[2] = -a[2];
        for (int k = 0; k < 3; k++) P->rt_true[k] = M_PI * a[k];
    } else {
        mrcal_r_from_R(P->rt_true, NULL, R);
    }
    for (int i = 0; i < 3; i++)
        P->rt_true[3 + i] = -(R[3 * i] * pos[0] + R[3 * i + 1] * pos[1] + R[3 * i + 2] * pos[2]);
    gen_rng g;
    gen_seed(&g, SEED);
    P->N = N;
    for (int i = 0; i < N; i++) {
        mrcal_point3_t pc;
        mrcal_transform_point_rt(pc.xyz, NULL, NULL, P->rt_true, &p[3 * i]);
        mrcal_point2_t q;
        mrcal_project(&q, NULL, NULL, &pc, 1, &P->lens, P->intrinsics);
        P->q[2 * i] = q.x + noise_px * gen_normal(&g);
        P->q[2 * i + 1] = q.y + noise_px * gen_normal(&g);
        memcpy(&P->p[3 * i], &p[3 * i], 3 * sizeof(double));
        P->sigma_px[i] = noise_px > 0 ? noise_px : 0.01;
        for (int k = 0; k < 3; k++) P->sigma_enu[3 * i + k] = sigma_m;
    }
}

// The optical axis in ENU (the third row of R_cam_enu).
static void facing(double f[3], const double rt[6])
{
    double R[9];
    mrcal_R_from_r(R, NULL, rt);
    memcpy(f, &R[6], 3 * sizeof(double));
}

static rs_status solve(rs_calib_result *r, const prob *P, rs_err *e)
{
    const rs_camera cam = {.lensmodel = P->lens,
                           .intrinsics = (double *)P->intrinsics,
                           .Nintrinsics = mrcal_lensmodel_num_params(&P->lens),
                           .width = P->width,
                           .height = P->height};
    const rs_calib_problem cp = {
        .N = P->N, .p_enu_m = P->p, .sigma_enu_m = P->sigma_enu, .q_px = P->q, .sigma_px = P->sigma_px, .camera = &cam};
    return rs_calib_solve(r, &cp, NULL, e);
}

static bool finite_result(const rs_calib_result *r)
{
    for (int k = 0; k < 6; k++)
        if (!isfinite(r->rt_cam_enu[k])) return false;
    for (int k = 0; k < 36; k++)
        if (!isfinite(r->covariance_rt_cam_enu[k])) return false;
    return isfinite(r->condition_number) && isfinite(r->rms_px);
}

// A case that must give a pose consistent with the truth. Returns the position error, m.
static double expect_pose(const char *name, const prob *P)
{
    rs_calib_result r;
    rs_err e = {0};
    const rs_status st = solve(&r, P, &e);
    double dpos = NAN;
    CHECK(st == RS_OK, "%s: %s: %s", name, rs_strerror(st), e.msg);
    if (st == RS_OK) {
        CHECK(finite_result(&r), "%s: non-finite result", name);
        double d[6], C[3];
        for (int k = 0; k < 6; k++) d[k] = r.rt_cam_enu[k] - P->rt_true[k];
        const double nees = gen_nees(d, r.covariance_rt_cam_enu, 6);
        rs_pose_position_from_rt(C, NULL, P->rt_true);
        dpos = hypot(hypot(r.position_enu_m[0] - C[0], r.position_enu_m[1] - C[1]), r.position_enu_m[2] - C[2]);
        printf("%-28s pose: position error %.3g m (sigma %.3g m), NEES %.3g, condition %.3g%s%s\n", name, dpos,
               sqrt(r.sigma_position_enu_m[0] * r.sigma_position_enu_m[0] +
                    r.sigma_position_enu_m[1] * r.sigma_position_enu_m[1] +
                    r.sigma_position_enu_m[2] * r.sigma_position_enu_m[2]),
               nees, r.condition_number, r.warnings[0] ? "; warning: " : "", r.warnings);
        CHECK(nees < 50.0, "%s: NEES %.3g: the pose is inconsistent with its covariance", name, nees);
    }
    rs_calib_result_free(&r);
    return dpos;
}

// A case that may be refused: an error of kind `want` whose message contains `cause`, or a pose
// that carries a warning (never a silent pose).
// 14 landmarks: 12 on the ground within 25 x 12 m of the origin and two 5 m posts (fixed seed).
static void ground_and_posts(double p[3 * 14])
{
    gen_rng g;
    gen_seed(&g, SEED);
    for (int i = 0; i < 14; i++) {
        p[3 * i] = gen_uniform(&g, -25, 25);
        p[3 * i + 1] = gen_uniform(&g, -12, 12);
        p[3 * i + 2] = i < 2 ? 5.0 : 0.0;
    }
}

static void expect_refusal(const char *name, const prob *P, rs_status want, const char *cause, bool pose_ok)
{
    rs_calib_result r;
    rs_err e = {0};
    const rs_status st = solve(&r, P, &e);
    if (st == RS_OK) {
        printf("%-28s pose with warning: %s\n", name, r.warnings);
        CHECK(pose_ok, "%s: a pose was returned, expected %s", name, rs_strerror(want));
        CHECK(r.warnings[0], "%s: a pose without any warning", name);
        CHECK(finite_result(&r), "%s: non-finite result", name);
    } else {
        printf("%-28s refused: %s: %s\n", name, rs_strerror(st), e.msg);
        CHECK(st == want && strstr(e.msg, cause), "%s: got %s '%s', expected %s naming '%s'", name, rs_strerror(st),
              e.msg, rs_strerror(want), cause);
    }
    rs_calib_result_free(&r);
}

int main(void)
{
    gen_begin();
    prob P;
    rs_simulate_camera_options o;

    rs_simulate_camera_options_default(&o); // landmarks 2 km away
    o.camera_height_m = 30, o.distance_m = 2000, o.max_range_m = 3000, o.Nlandmarks = 20;
    if (simulate(&P, &o, 1.0, 0.3)) expect_pose("landmarks 2 km away", &P);

    rs_simulate_camera_options_default(&o); // f = 20,000 px
    o.hfov_deg = 2.0 * atan(960.0 / 20000.0) * 180.0 / M_PI, o.camera_height_m = 20, o.distance_m = 800,
    o.max_range_m = 1200, o.Nlandmarks = 20;
    if (simulate(&P, &o, 1.0, 0.3)) expect_pose("focal length 20000 px", &P);

    rs_simulate_camera_options_default(&o); // 100 m up
    o.camera_height_m = 100, o.distance_m = 60, o.max_range_m = 200, o.Nlandmarks = 20;
    if (simulate(&P, &o, 1.0, 0.3)) expect_pose("camera 100 m up", &P);

    { // straight down from 40 m: ground points under the camera and two 5 m posts
        double p[3 * 14];
        ground_and_posts(p);
        const double ypr[3] = {0, -90, 0}, pos[3] = {0, 0, 40};
        build(&P, 1000, ypr, pos, p, 14, 0.5, 0.01);
        expect_pose("looking straight down", &P);
        double f[3];
        facing(f, P.rt_true);
        CHECK(f[2] < -0.999999, "straight down: the true camera's axis is %g %g %g", f[0], f[1], f[2]);
    }

    { // every landmark behind the camera: a camera 40 m up looking straight UP at the ground
        // points (pinhole pixels of points behind it are mirrored, not absent)
        double p[3 * 14];
        ground_and_posts(p);
        const double ypr[3] = {0, 90, 0}, pos[3] = {0, 0, 40};
        build(&P, 1000, ypr, pos, p, 14, 0.5, 0.01);
        // refused: the mirrored pose (the camera 40 m below the ground, looking up) agrees with
        // most picks, and rs_calib_solve refuses a camera below every landmark looking up
        expect_refusal("landmarks behind the camera", &P, RS_ERR_DEGENERATE, "below every landmark", false);
    }

    rs_simulate_camera_options_default(&o); // 1e-6 px noise, exact survey
    o.Nlandmarks = 20;
    if (simulate(&P, &o, 1e-6, 0.0)) {
        const double d = expect_pose("1e-6 px noise", &P);
        CHECK(d < 1e-4, "1e-6 px noise: position error %.3g m", d);
    }

    rs_simulate_camera_options_default(&o); // huge coordinates: the scene moved by ~6e6 m
    o.Nlandmarks = 20;
    if (simulate(&P, &o, 0.0, 0.0)) {
        const double off[3] = {3.1e6, 5.2e6, 1.1e3};
        double R[9];
        mrcal_R_from_r(R, NULL, P.rt_true);
        for (int i = 0; i < P.N; i++)
            for (int k = 0; k < 3; k++) P.p[3 * i + k] += off[k];
        for (int k = 0; k < 3; k++) // t' = t - R off keeps every p_cam
            P.rt_true[3 + k] -= R[3 * k] * off[0] + R[3 * k + 1] * off[1] + R[3 * k + 2] * off[2];
        for (int i = 0; i < P.N; i++) P.sigma_px[i] = 0.01;
        const double d = expect_pose("huge coordinates (6e6 m)", &P);
        CHECK(d < 1e-6, "huge coordinates: position error %.3g m (want < 1e-6 m)", d);
    }

    rs_simulate_camera_options_default(&o); // tiny coordinates: the scene scaled to millimetres
    o.Nlandmarks = 20;
    if (simulate(&P, &o, 0.0, 0.0)) {
        const double s = 1e-3;
        for (int i = 0; i < 3 * P.N; i++) P.p[i] *= s;
        for (int k = 3; k < 6; k++) P.rt_true[k] *= s;
        for (int i = 0; i < P.N; i++) P.sigma_px[i] = 0.01;
        const double d = expect_pose("tiny coordinates (mm)", &P);
        CHECK(d < 1e-9, "tiny coordinates: position error %.3g m (scene ~0.03 m; want < 1e-9 m)", d);
    }

    { // nearly collinear: 12 points along a line 20-60 m ahead with 1 mm of lateral jitter
        double p[3 * 12];
        gen_rng g;
        gen_seed(&g, SEED);
        for (int i = 0; i < 12; i++) {
            p[3 * i] = 1e-3 * gen_normal(&g);
            p[3 * i + 1] = 20 + 40.0 * i / 11;
            p[3 * i + 2] = 1e-3 * gen_normal(&g);
        }
        const double ypr[3] = {0, -12, 0}, pos[3] = {3, 0, 8};
        build(&P, 1500, ypr, pos, p, 12, 0.5, 0.05);
        expect_refusal("nearly collinear", &P, RS_ERR_DEGENERATE, "collinear", true);
    }

    { // every landmark within a 5 px patch: 10 points within 5 cm, 40 m ahead (f 1500: 2 px)
        double p[3 * 10];
        gen_rng g;
        gen_seed(&g, SEED);
        for (int i = 0; i < 10; i++) {
            p[3 * i] = gen_uniform(&g, -0.05, 0.05);
            p[3 * i + 1] = 40 + gen_uniform(&g, -0.05, 0.05);
            p[3 * i + 2] = gen_uniform(&g, 0, 0.1);
        }
        const double ypr[3] = {0, -10, 0}, pos[3] = {0, 0, 8};
        build(&P, 1500, ypr, pos, p, 10, 0.5, 0.01);
        double lo[2] = {1e9, 1e9}, hi[2] = {-1e9, -1e9};
        for (int i = 0; i < P.N; i++)
            for (int k = 0; k < 2; k++) lo[k] = fmin(lo[k], P.q[2 * i + k]), hi[k] = fmax(hi[k], P.q[2 * i + k]);
        CHECK(hi[0] - lo[0] < 5 && hi[1] - lo[1] < 5, "the patch is %.3g x %.3g px", hi[0] - lo[0], hi[1] - lo[1]);
        expect_refusal("all within a 5 px patch", &P, RS_ERR_DEGENERATE, "tiny patch", false);
    }

    rs_simulate_camera_options_default(&o); // a copied coordinate: landmark 5 given landmark 2's position
    o.Nlandmarks = 12;
    if (simulate(&P, &o, 1.0, 0.3)) {
        memcpy(&P.p[3 * 5], &P.p[3 * 2], 3 * sizeof(double));
        rs_calib_result r;
        rs_err e = {0};
        const rs_status st = solve(&r, &P, &e);
        // its pixel is elsewhere: the camera is calibrated and the copy flagged, not the camera refused
        CHECK(st == RS_OK && !r.inlier[5] && r.Ninliers == 11, "copied coordinate: %s '%s', landmark 5 %s, %d inliers",
              rs_strerror(st), e.msg, st == RS_OK && r.inlier[5] ? "kept" : "flagged", st == RS_OK ? r.Ninliers : 0);
        if (st == RS_OK) printf("%-28s pose, landmark 5 flagged: %s\n", "copied coordinate", r.warnings);
        rs_calib_result_free(&r);
    }
    rs_simulate_camera_options_default(&o); // only 3 distinct positions
    o.Nlandmarks = 6;
    if (simulate(&P, &o, 1.0, 0.3)) {
        for (int i = 3; i < 6; i++) memcpy(&P.p[3 * i], &P.p[3 * (i - 3)], 3 * sizeof(double));
        expect_refusal("3 distinct positions", &P, RS_ERR_DEGENERATE, "distinct", false);
    }

    rs_simulate_camera_options_default(&o); // a NaN: refused, naming the index and field
    o.Nlandmarks = 12;
    if (simulate(&P, &o, 1.0, 0.3)) {
        P.p[3 * 7 + 1] = NAN;
        expect_refusal("NaN coordinate", &P, RS_ERR_INVALID, "7", false);
    }

    char seeds[32];
    snprintf(seeds, sizeof seeds, "%d", SEED);
    return gen_end(seeds);
}

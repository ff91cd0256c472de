// test_init_gen.c -- see test_init_gen.h.
#include "test_init_gen.h"
#include "core/rs_pose.h"
#include "core/rs_rng.h"

#include <math.h>
#include <string.h>

#include <mrcal/poseutils.h>

void tg_seed(tg_rng *r, uint64_t seed) { r->state = seed * 0x9E3779B97F4A7C15ull + 1; }

// splitmix64 steps of core/rs_rng.h: the stream of its seed sequence
double tg_uniform(tg_rng *r, double a, double b) { return a + (b - a) * rs_rng_u01(rs_rng_seed_next(&r->state)); }

double tg_gauss(tg_rng *r)
{
    const double u = tg_uniform(r, 1e-300, 1.0), w = tg_uniform(r, 0.0, 2.0 * M_PI);
    return sqrt(-2.0 * log(u)) * cos(w);
}

const char *tg_lens_name(tg_lens lens)
{
    return lens == TG_PINHOLE ? "pinhole" : lens == TG_OPENCV8 ? "opencv8" : "cahvor";
}

static void matmul3(double *C, const double *A, const double *B)
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            C[3 * i + j] = 0.0;
            for (int k = 0; k < 3; k++) C[3 * i + j] += A[3 * i + k] * B[3 * k + j];
        }
}

void tg_R_enu_cam(double *R, double yaw_deg, double pitch_deg, double roll_deg)
{
    const double y = -yaw_deg * M_PI / 180, p = pitch_deg * M_PI / 180, r = roll_deg * M_PI / 180;
    const double Rz_yaw[9] = {cos(y), -sin(y), 0, sin(y), cos(y), 0, 0, 0, 1};
    const double Rx_pitch[9] = {1, 0, 0, 0, cos(p), -sin(p), 0, sin(p), cos(p)};
    const double R0[9] = {1, 0, 0, 0, 0, 1, 0, -1, 0};
    const double Rz_roll[9] = {cos(r), -sin(r), 0, sin(r), cos(r), 0, 0, 0, 1};
    double A[9], B[9];
    matmul3(A, Rz_yaw, Rx_pitch);
    matmul3(B, A, R0);
    matmul3(R, B, Rz_roll);
}

static void make_lens(tg_problem *pb, tg_rng *r, tg_lens lens)
{
    pb->width = 1920;
    pb->height = 1080;
    const double f = tg_uniform(r, 1000, 3000);
    double *in = pb->intrinsics;
    memset(in, 0, sizeof(pb->intrinsics));
    in[0] = f;
    in[1] = f * tg_uniform(r, 0.998, 1.002);
    in[2] = (pb->width - 1) / 2.0 + tg_uniform(r, -20, 20);
    in[3] = (pb->height - 1) / 2.0 + tg_uniform(r, -20, 20);
    if (lens == TG_PINHOLE) {
        pb->lensmodel.type = MRCAL_LENSMODEL_PINHOLE;
    } else if (lens == TG_OPENCV8) { // k1 k2 p1 p2 k3 k4 k5 k6
        pb->lensmodel.type = MRCAL_LENSMODEL_OPENCV8;
        in[4] = tg_uniform(r, -0.2, -0.05);
        in[5] = tg_uniform(r, 0.0, 0.05);
        in[6] = tg_uniform(r, -1e-3, 1e-3);
        in[7] = tg_uniform(r, -1e-3, 1e-3);
        in[8] = tg_uniform(r, -0.01, 0.01);
        in[9] = tg_uniform(r, 0.0, 0.05);
        in[10] = tg_uniform(r, 0.0, 0.01);
        in[11] = tg_uniform(r, 0.0, 0.005);
    } else { // alpha beta r0 r1 r2
        pb->lensmodel.type = MRCAL_LENSMODEL_CAHVOR;
        in[4] = tg_uniform(r, -0.01, 0.01);
        in[5] = tg_uniform(r, -0.01, 0.01);
        in[6] = 0.0;
        in[7] = tg_uniform(r, -0.1, 0.0);
        in[8] = tg_uniform(r, 0.0, 0.02);
    }
}

static bool project(mrcal_point2_t *q, const tg_problem *pb, const double *rt, const double *p)
{
    mrcal_point3_t pc;
    mrcal_transform_point_rt(pc.xyz, NULL, NULL, rt, p);
    return pc.z > 0 && mrcal_project(q, NULL, NULL, &pc, 1, &pb->lensmodel, pb->intrinsics);
}

bool tg_make(tg_problem *pb, uint64_t seed, tg_lens lens, double relief_m, int N, double noise_px,
             double outlier_fraction)
{
    if (N < 0 || N > TG_NMAX) return false;
    memset(pb, 0, sizeof(*pb));
    tg_rng r;
    tg_seed(&r, seed);
    make_lens(pb, &r, lens);

    // pole camera: 5..100 m up, anywhere within 300 m of the site origin, looking down
    const double z_road = tg_uniform(&r, -5, 5), h = tg_uniform(&r, 5, 100);
    double *c = pb->c_enu_m;
    c[0] = tg_uniform(&r, -300, 300);
    c[1] = tg_uniform(&r, -300, 300);
    c[2] = z_road + h;
    double R_enu_cam[9], R_cam_enu[9], t[3];
    tg_R_enu_cam(R_enu_cam, tg_uniform(&r, 0, 360), tg_uniform(&r, -60, -10), tg_uniform(&r, -3, 3));
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) R_cam_enu[3 * i + j] = R_enu_cam[3 * j + i];
    for (int i = 0; i < 3; i++)
        t[i] = -(R_cam_enu[3 * i] * c[0] + R_cam_enu[3 * i + 1] * c[1] + R_cam_enu[3 * i + 2] * c[2]);
    mrcal_r_from_R(pb->rt_cam_enu, NULL, R_cam_enu);
    memcpy(&pb->rt_cam_enu[3], t, sizeof(t));

    pb->N = N;
    int attempts = 0;
    double range_sum = 0.0;
    for (int i = 0; i < N; i++) {
        for (;;) {
            if (++attempts > 100000) return false;
            const mrcal_point2_t q = {.xy = {tg_uniform(&r, 20, pb->width - 21), tg_uniform(&r, 20, pb->height - 21)}};
            mrcal_point3_t v;
            if (!mrcal_unproject(&v, &q, 1, &pb->lensmodel, pb->intrinsics)) continue;
            double v_enu[3];
            for (int k = 0; k < 3; k++)
                v_enu[k] = R_enu_cam[3 * k] * v.x + R_enu_cam[3 * k + 1] * v.y + R_enu_cam[3 * k + 2] * v.z;
            const double nv = sqrt(v_enu[0] * v_enu[0] + v_enu[1] * v_enu[1] + v_enu[2] * v_enu[2]);
            if (!(v_enu[2] < -0.03 * nv)) continue; // at or above the horizon
            const double u = relief_m > 0.0 ? tg_uniform(&r, 0.0, fmin(relief_m, 0.6 * h)) : 0.0;
            const double s = (z_road + u - c[2]) / v_enu[2];
            if (!(s * nv < 600.0)) continue;
            double *p = &pb->p_enu_m[3 * i];
            for (int k = 0; k < 3; k++) p[k] = c[k] + s * v_enu[k];
            mrcal_point2_t qt;
            if (!project(&qt, pb, pb->rt_cam_enu, p) || fabs(qt.x - q.x) > 1e-3 || fabs(qt.y - q.y) > 1e-3)
                continue; // the lens does not round-trip here: pick another pixel
            pb->q_true_px[2 * i] = qt.x;
            pb->q_true_px[2 * i + 1] = qt.y;
            range_sum += s * nv;
            break;
        }
    }
    pb->range_m = N > 0 ? range_sum / N : 0.0;
    for (int i = 0; i < N; i++) {
        pb->q_px[2 * i] = pb->q_true_px[2 * i] + noise_px * tg_gauss(&r);
        pb->q_px[2 * i + 1] = pb->q_true_px[2 * i + 1] + noise_px * tg_gauss(&r);
    }
    // gross mistakes: a random subset, moved anywhere in the image at least 25 px away
    const int Nout = (int)lround(outlier_fraction * N);
    int idx[TG_NMAX];
    for (int i = 0; i < N; i++) idx[i] = i;
    for (int k = 0; k < Nout; k++) {
        const int j = k + (int)(rs_rng_seed_next(&r.state) % (uint64_t)(N - k));
        const int tmp = idx[k];
        idx[k] = idx[j];
        idx[j] = tmp;
        const int i = idx[k];
        pb->outlier[i] = true;
        double x, y;
        do {
            x = tg_uniform(&r, 0, pb->width - 1);
            y = tg_uniform(&r, 0, pb->height - 1);
        } while (hypot(x - pb->q_true_px[2 * i], y - pb->q_true_px[2 * i + 1]) < 25.0);
        pb->q_px[2 * i] = x;
        pb->q_px[2 * i + 1] = y;
    }
    return true;
}

rs_status tg_init_pose(rs_calib_init_result *res, bool *inlier, const tg_problem *pb, uint64_t seed, rs_err *err)
{
    rs_calib_init_options opt;
    rs_calib_init_options_default(&opt);
    opt.seed = seed;
    return rs_calib_init_pose(res, inlier, &pb->lensmodel, pb->intrinsics, pb->p_enu_m, pb->q_px, pb->N, &opt, err);
}

double tg_rotation_error_rad(const double *rt_a, const double *rt_b)
{
    return rs_pose_rotation_between(NULL, NULL, rt_a, rt_b);
}

double tg_position_error_m(const double *rt_a, const double *rt_b)
{
    double ia[6], ib[6];
    mrcal_invert_rt(ia, NULL, NULL, rt_a);
    mrcal_invert_rt(ib, NULL, NULL, rt_b);
    return sqrt((ia[3] - ib[3]) * (ia[3] - ib[3]) + (ia[4] - ib[4]) * (ia[4] - ib[4]) +
                (ia[5] - ib[5]) * (ia[5] - ib[5]));
}

double tg_model_error_px(const tg_problem *pb, const double *rt_a, const double *rt_b)
{
    double sum = 0.0;
    for (int i = 0; i < pb->N; i++) {
        mrcal_point2_t qa, qb;
        if (!project(&qa, pb, rt_a, &pb->p_enu_m[3 * i]) || !project(&qb, pb, rt_b, &pb->p_enu_m[3 * i]))
            return INFINITY;
        sum += (qa.x - qb.x) * (qa.x - qb.x) + (qa.y - qb.y) * (qa.y - qb.y);
    }
    return pb->N > 0 ? sqrt(sum / pb->N) : 0.0;
}

// rs_simulate_camera.c -- one simulated camera: its pose, field of view, projections and
// picks (sim/internal/rs_simulate_internal.h), and one camera's problem in memory
// (rs_simulate_camera_problem, sim/rs_simulate.h). Calls rs_simulate_lens.c, mrcal and core/.
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_lens.h"
#include "core/rs_pose.h"
#include "sim/internal/rs_simulate_internal.h"

// ---------------------------------------------------------------------------------------------
// one camera: pose, field of view, projection, picks

// The widest angle off the optical axis that the image shows (its corners), for rejecting points
// that a distortion polynomial would fold back into the image from outside the field of view.
rs_status rs_simulate__camera_field_of_view(rs_simulate__camera *c, rs_err *err)
{
    mrcal_point2_t q[8] = {
        {.x = -0.5, .y = -0.5},
        {.x = c->cam.width - 0.5, .y = -0.5},
        {.x = -0.5, .y = c->cam.height - 0.5},
        {.x = c->cam.width - 0.5, .y = c->cam.height - 0.5},
        {.x = 0.5 * c->cam.width, .y = -0.5},
        {.x = 0.5 * c->cam.width, .y = c->cam.height - 0.5},
        {.x = -0.5, .y = 0.5 * c->cam.height},
        {.x = c->cam.width - 0.5, .y = 0.5 * c->cam.height},
    };
    mrcal_point3_t v[8];
    if (!rs_lens_unproject(v, q, 8, &c->cam.lensmodel, c->cam.intrinsics))
        return rs_err_set(err, RS_ERR_UNSUPPORTED, "lens: mrcal cannot unproject through %s",
                          mrcal_lensmodel_name_unconfigured(&c->cam.lensmodel));
    double cos_min = 1.0;
    for (int i = 0; i < 8; i++) {
        double n = sqrt(v[i].x * v[i].x + v[i].y * v[i].y + v[i].z * v[i].z);
        double cz = n > 0 && isfinite(n) ? v[i].z / n : -1.0;
        if (cz < cos_min) cos_min = cz;
    }
    double theta = acos(cos_min) + 1.0 * RS_RAD_PER_DEG;
    c->cos_max = theta >= M_PI ? -1.0 : cos(theta);
    return RS_OK;
}

// Sets the pose of a camera at p_cam looking at `target`, turned by yaw_offset_deg and rolled by
// roll_deg, pitched so that the target appears at 62% of the image height. Rounds rt to 1e-6.
void rs_simulate__camera_look_at(rs_simulate__camera *c, const double p_cam[3], const double target[3],
                                 double yaw_offset_deg, double roll_deg)
{
    double d[3] = {target[0] - p_cam[0], target[1] - p_cam[1], target[2] - p_cam[2]};
    double yaw = atan2(d[0], d[1]) / RS_RAD_PER_DEG + yaw_offset_deg;
    double below = atan((0.62 * (c->cam.height - 1) - c->cam.intrinsics[3]) / c->cam.intrinsics[1]) / RS_RAD_PER_DEG;
    double pitch = atan2(d[2], hypot(d[0], d[1])) / RS_RAD_PER_DEG + below;
    const double ypr[3] = {yaw, pitch, roll_deg};
    double R[9];
    rs_pose_R_from_ypr(R, ypr);
    double *rt = c->cam.rt_cam_enu;
    rs_pose_r_from_R(rt, R);
    for (int i = 0; i < 3; i++) rt[i] = rs_simulate__quantize(rt[i], Q_MODEL);
    mrcal_R_from_r(c->R_cam_enu, NULL, rt);
    mrcal_rotate_point_R(rt + 3, NULL, NULL, c->R_cam_enu, p_cam);
    for (int i = 3; i < 6; i++) rt[i] = rs_simulate__quantize(-rt[i], Q_MODEL);
    // The position and angles of the pose as rounded.
    double minus_t[3] = {-rt[3], -rt[4], -rt[5]};
    mrcal_rotate_point_R_inverted(c->p_cam_enu_m, NULL, NULL, c->R_cam_enu, minus_t);
    rs_pose_ypr_from_R(c->ypr_deg, c->R_cam_enu);
}

// Projects p_enu through the camera. True if the point is in front of the camera, inside its
// field of view, and projects at least margin_px inside the image.
bool rs_simulate__camera_sees(const rs_simulate__camera *c, double q_px[2], const double p_enu[3], double margin_px)
{
    mrcal_point3_t pc;
    mrcal_point2_t q;
    mrcal_transform_point_rt(pc.xyz, NULL, NULL, c->cam.rt_cam_enu, p_enu);
    double n = sqrt(pc.x * pc.x + pc.y * pc.y + pc.z * pc.z);
    if (!(pc.z > 0.5) || pc.z < c->cos_max * n) return false;
    if (!rs_lens_project(&q, NULL, NULL, &pc, 1, &c->cam.lensmodel, c->cam.intrinsics)) return false;
    q_px[0] = q.x;
    q_px[1] = q.y;
    return isfinite(q.x) && isfinite(q.y) && q.x >= margin_px && q.y >= margin_px &&
           q.x <= c->cam.width - 1 - margin_px && q.y <= c->cam.height - 1 - margin_px;
}

// Picks: the true pixel plus N(0, sigma) noise kept inside the image (redrawn until it is), or,
// with probability outlier_fraction, a uniformly random pixel at least outlier_min_px away.
int rs_simulate__camera_pick(rs_rng *rng, double *q_px, bool *outlier, const double *q_true_px, int N,
                             const rs_simulate__camera *c, double sigma_px, double outlier_fraction,
                             double outlier_min_px)
{
    int Noutliers = 0;
    for (int i = 0; i < N; i++) {
        const double *qt = q_true_px + 2 * i;
        double *q = q_px + 2 * i;
        outlier[i] = outlier_fraction > 0 && rs_rng_uniform(rng) < outlier_fraction;
        if (outlier[i]) {
            Noutliers++;
            do {
                q[0] = rs_rng_uniform_in(rng, 0, c->cam.width - 1);
                q[1] = rs_rng_uniform_in(rng, 0, c->cam.height - 1);
            } while (hypot(q[0] - qt[0], q[1] - qt[1]) < outlier_min_px);
        } else {
            do {
                q[0] = qt[0] + sigma_px * rs_rng_normal(rng);
                q[1] = qt[1] + sigma_px * rs_rng_normal(rng);
            } while (q[0] < -0.5 || q[1] < -0.5 || q[0] > c->cam.width - 0.5 || q[1] > c->cam.height - 0.5);
        }
    }
    return Noutliers;
}

void rs_simulate__survey_noise(rs_rng *rng, double *p_survey, const double *p_true, int N, double sigma_h,
                               double sigma_v)
{
    for (int i = 0; i < N; i++) {
        p_survey[3 * i + 0] = p_true[3 * i + 0] + sigma_h * rs_rng_normal(rng);
        p_survey[3 * i + 1] = p_true[3 * i + 1] + sigma_h * rs_rng_normal(rng);
        p_survey[3 * i + 2] = p_true[3 * i + 2] + sigma_v * rs_rng_normal(rng);
    }
}

// ---------------------------------------------------------------------------------------------
// one camera's problem, in memory

void rs_simulate_camera_options_default(rs_simulate_camera_options *o)
{
    *o = (rs_simulate_camera_options){
        .lensmodel = "LENSMODEL_OPENCV8",
        .width_px = 1920,
        .height_px = 1080,
        .hfov_deg = 60,
        .distortion = true,
        .camera_height_m = 8,
        .distance_m = 25,
        .yaw_deg = 30,
        .roll_sigma_deg = 1,
        .Nlandmarks = 12,
        .elevated_fraction = 0.25,
        .elevated_min_m = 2,
        .elevated_max_m = 6,
        .max_range_m = 80,
        .margin_px = 20,
        .pixel_sigma_px = 1,
        .survey_sigma_h_m = 0.3,
        .survey_sigma_v_m = 0.5,
        .outlier_fraction = 0.05,
        .outlier_min_px = 30,
        .seed = 1,
    };
}

static rs_status camera_options_check(const rs_simulate_camera_options *o, rs_err *err)
{
    CHECK_OPTION(o->camera_height_m > 0.5 && o->camera_height_m <= 1000, "camera_height_m", "%g", o->camera_height_m);
    CHECK_OPTION(o->distance_m >= 0 && o->distance_m <= 10000, "distance_m", "%g", o->distance_m);
    CHECK_OPTION(isfinite(o->yaw_deg), "yaw_deg", "%g", o->yaw_deg);
    CHECK_OPTION(o->roll_sigma_deg >= 0 && o->roll_sigma_deg <= 45, "roll_sigma_deg", "%g", o->roll_sigma_deg);
    CHECK_OPTION(o->Nlandmarks >= 1 && o->Nlandmarks <= 100000, "Nlandmarks", "%d", o->Nlandmarks);
    CHECK_OPTION(o->elevated_fraction >= 0 && o->elevated_fraction <= 1, "elevated_fraction", "%g",
                 o->elevated_fraction);
    CHECK_OPTION(o->elevated_min_m > 0 && o->elevated_max_m >= o->elevated_min_m && o->elevated_max_m <= 1000,
                 "elevated_min_m", "%g", o->elevated_min_m);
    CHECK_OPTION(o->max_range_m > 0, "max_range_m", "%g", o->max_range_m);
    CHECK_OPTION(o->margin_px >= 0 && 4 * o->margin_px < o->height_px && 4 * o->margin_px < o->width_px, "margin_px",
                 "%g", o->margin_px);
    CHECK_OPTION(o->pixel_sigma_px >= 0 && o->pixel_sigma_px <= 50, "pixel_sigma_px", "%g", o->pixel_sigma_px);
    CHECK_OPTION(o->survey_sigma_h_m >= 0 && o->survey_sigma_h_m <= 1000, "survey_sigma_h_m", "%g",
                 o->survey_sigma_h_m);
    CHECK_OPTION(o->survey_sigma_v_m >= 0 && o->survey_sigma_v_m <= 1000, "survey_sigma_v_m", "%g",
                 o->survey_sigma_v_m);
    CHECK_OPTION(o->outlier_fraction >= 0 && o->outlier_fraction <= 0.9, "outlier_fraction", "%g", o->outlier_fraction);
    CHECK_OPTION(o->outlier_min_px >= 0 && 4 * o->outlier_min_px < o->height_px, "outlier_min_px", "%g",
                 o->outlier_min_px);
    return RS_OK;
}

void rs_simulate_problem_free(rs_simulate_problem *p)
{
    if (!p) return;
    rs_camera_free(&p->camera);
    free(p->p_enu_true_m);
    free(p->p_enu_survey_m);
    free(p->q_true_px);
    free(p->q_px);
    free(p->outlier);
    free(p->elevated);
    free(p);
}

// Places landmark i on a ray through a random pixel, on the ground or at a random height.
static bool place_landmark(rs_rng *rng, double p_enu[3], double q_true_px[2], const rs_simulate__camera *c,
                           bool elevated, const rs_simulate_camera_options *o)
{
    mrcal_point2_t q = {.x = rs_rng_uniform_in(rng, o->margin_px, c->cam.width - 1 - o->margin_px),
                        .y = rs_rng_uniform_in(rng, o->margin_px, c->cam.height - 1 - o->margin_px)};
    double h = elevated ? rs_rng_uniform_in(rng, o->elevated_min_m, o->elevated_max_m) : 0.0;
    mrcal_point3_t v;
    if (!rs_lens_unproject(&v, &q, 1, &c->cam.lensmodel, c->cam.intrinsics) || !isfinite(v.x)) return false;
    double d[3];
    mrcal_rotate_point_R_inverted(d, NULL, NULL, c->R_cam_enu, v.xyz);
    if (fabs(d[2]) < 1e-12) return false;
    double s = (h - c->p_cam_enu_m[2]) / d[2];
    if (!(s > 0)) return false;
    for (int k = 0; k < 3; k++) p_enu[k] = c->p_cam_enu_m[k] + s * d[k];
    if (hypot(p_enu[0] - c->p_cam_enu_m[0], p_enu[1] - c->p_cam_enu_m[1]) > o->max_range_m) return false;
    for (int k = 0; k < 3; k++) p_enu[k] = rs_simulate__quantize(p_enu[k], Q_ENU);
    return rs_simulate__camera_sees(c, q_true_px, p_enu, 0.5 * o->margin_px);
}

rs_status rs_simulate_camera_problem(rs_simulate_problem **problem, const rs_simulate_camera_options *o, rs_err *err)
{
    *problem = NULL;
    rs_status st = camera_options_check(o, err);
    if (st) return st;
    rs_rng rng;
    rs_rng_seed(&rng, o->seed);

    rs_simulate_problem *p = calloc(1, sizeof *p);
    if (!p) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_simulate__camera c = {.cam = {.width = o->width_px, .height = o->height_px}};
    st = rs_simulate_lens(&c.cam.lensmodel, &c.cam.intrinsics, &c.cam.Nintrinsics, &rng, o->lensmodel, o->width_px,
                          o->height_px, o->hfov_deg, o->distortion, err);
    if (st) goto fail;
    p->camera = c.cam; // p owns the intrinsics from here
    st = rs_simulate__camera_field_of_view(&c, err);
    if (st) goto fail;

    double yaw = o->yaw_deg * RS_RAD_PER_DEG;
    double p_cam[3] = {-o->distance_m * sin(yaw), -o->distance_m * cos(yaw), o->camera_height_m};
    double target[3] = {0, 0, 0};
    if (o->distance_m == 0) { // looking straight down: aim a hair north of the foot of the pole
        target[0] = 1e-6 * sin(yaw);
        target[1] = 1e-6 * cos(yaw);
    }
    rs_simulate__camera_look_at(&c, p_cam, target, 0.0, o->roll_sigma_deg * rs_rng_normal(&rng));
    memcpy(p->camera.rt_cam_enu, c.cam.rt_cam_enu, sizeof c.cam.rt_cam_enu);
    memcpy(p->p_cam_enu_m, c.p_cam_enu_m, sizeof c.p_cam_enu_m);
    memcpy(p->ypr_deg, c.ypr_deg, sizeof c.ypr_deg);

    int N = o->Nlandmarks;
    p->Npoints = N;
    p->p_enu_true_m = malloc(sizeof(double) * 3 * (size_t)N);
    p->p_enu_survey_m = malloc(sizeof(double) * 3 * (size_t)N);
    p->q_true_px = malloc(sizeof(double) * 2 * (size_t)N);
    p->q_px = malloc(sizeof(double) * 2 * (size_t)N);
    p->outlier = malloc(sizeof(bool) * (size_t)N);
    p->elevated = malloc(sizeof(bool) * (size_t)N);
    if (!p->p_enu_true_m || !p->p_enu_survey_m || !p->q_true_px || !p->q_px || !p->outlier || !p->elevated) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto fail;
    }
    int Nelevated = (int)lround(o->elevated_fraction * N);
    for (int i = 0; i < N; i++) {
        p->elevated[i] = i < Nelevated;
        int tries = 0;
        while (!place_landmark(&rng, p->p_enu_true_m + 3 * i, p->q_true_px + 2 * i, &c, p->elevated[i], o))
            if (++tries == 10000) {
                st = rs_err_set(err, RS_ERR_DEGENERATE,
                                "landmark %d: no %s point within %g m is visible (camera %g m high, pitch %.1f deg)", i,
                                p->elevated[i] ? "elevated" : "ground", o->max_range_m, o->camera_height_m,
                                c.ypr_deg[1]);
                goto fail;
            }
    }
    p->Noutliers = rs_simulate__camera_pick(&rng, p->q_px, p->outlier, p->q_true_px, N, &c, o->pixel_sigma_px,
                                            o->outlier_fraction, o->outlier_min_px);
    rs_simulate__survey_noise(&rng, p->p_enu_survey_m, p->p_enu_true_m, N, o->survey_sigma_h_m, o->survey_sigma_v_m);
    *problem = p;
    return RS_OK;
fail:
    if (!p->camera.intrinsics) free(c.cam.intrinsics);
    rs_simulate_problem_free(p);
    return st;
}

// rs_simulate.c -- synthetic camera problems and sites with a known truth (rs_simulate.h).
#define _XOPEN_SOURCE 700 // nftw()
#include "sim/rs_simulate.h"
#include "core/rs_pose.h"

#include <cjson/cJSON.h>
#include <dirent.h>
#include <errno.h>
#include <ftw.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/rs_io.h"
#include "core/rs_rng.h"
#include "core/rs_camera.h"

#define DEG (M_PI / 180.0)

// Rounds to a multiple of `quantum` (a power of ten below 1): the nearest double to that
// decimal, so that printing it with as many decimals and parsing it back gives the same double.
// Never returns -0.
static double quantize(double x, double inv_quantum) { return round(x * inv_quantum) / inv_quantum + 0.0; }
#define Q_MODEL 1e6 // .cameramodel precision (mrcal writes "%f")
#define Q_ENU 1e4   // true landmark positions: 0.1 mm

// The sigmas a site DECLARES are at least these (sites need sigmas > 0 to weight by), even when
// the noise actually drawn is zero; the noise drawn is recorded in site.json's "simulated".
#define DECLARED_SURVEY_SIGMA_MIN_M 1e-3
#define DECLARED_PIXEL_SIGMA_MIN_PX 1e-2

// ---------------------------------------------------------------------------------------------
// the lens

typedef enum { FAMILY_PINHOLE, FAMILY_STEREOGRAPHIC, FAMILY_ANGULAR } lens_family;

static lens_family family_of(mrcal_lensmodel_type_t t)
{
    switch (t) {
    case MRCAL_LENSMODEL_STEREOGRAPHIC:
    case MRCAL_LENSMODEL_SPLINED_STEREOGRAPHIC: return FAMILY_STEREOGRAPHIC;
    case MRCAL_LENSMODEL_LONLAT:
    case MRCAL_LENSMODEL_LATLON: return FAMILY_ANGULAR;
    default: return FAMILY_PINHOLE;
    }
}

// Parses and checks a lens model name against the image size and field of view.
static rs_status lens_check(mrcal_lensmodel_t *lm, const char *name, int W, int H, double hfov_deg, rs_err *err)
{
    if (!name || !*name) return rs_err_set(err, RS_ERR_USAGE, "lens: empty lens model name");
    if (!mrcal_lensmodel_from_name(lm, name) || !mrcal_lensmodel_type_is_valid(lm->type)) {
        if (lm->type == MRCAL_LENSMODEL_INVALID_BADCONFIG)
            return rs_err_set(err, RS_ERR_USAGE,
                              "lens: '%s' needs its configuration spelled out, e.g. "
                              "LENSMODEL_SPLINED_STEREOGRAPHIC_order=3_Nx=16_Ny=12_fov_x_deg=100 or "
                              "LENSMODEL_CAHVORE_linearity=0.00",
                              name);
        char known[512] = "";
        for (const char *const *n = mrcal_supported_lensmodel_names(); *n; n++) {
            size_t used = strlen(known);
            snprintf(known + used, sizeof known - used, "%s%s", used ? ", " : "", *n);
        }
        return rs_err_set(err, RS_ERR_USAGE, "lens: '%s' is not an mrcal lens model (known: %s)", name, known);
    }
    if (!mrcal_lensmodel_metadata(lm).has_core)
        return rs_err_set(err, RS_ERR_USAGE, "lens: %s has no intrinsics core (fx, fy, cx, cy)", name);
    if (W < 64 || H < 64 || W > 20000 || H > 20000)
        return rs_err_set(err, RS_ERR_USAGE, "image: %dx%d is outside 64x64 .. 20000x20000", W, H);
    double max_hfov = family_of(lm->type) == FAMILY_PINHOLE ? 170.0 : 340.0;
    if (!(hfov_deg >= 1.0 && hfov_deg <= max_hfov))
        return rs_err_set(err, RS_ERR_USAGE, "hfov_deg: %g is outside [1, %g] for %s", hfov_deg, max_hfov, name);
    return RS_OK;
}

rs_status rs_simulate_lens(mrcal_lensmodel_t *lensmodel, double **intrinsics, int *Nintrinsics,
                           rs_rng *rng, const char *lensmodel_name, int width_px, int height_px,
                           double hfov_deg, bool distortion, rs_err *err)
{
    *intrinsics = NULL;
    *Nintrinsics = 0;
    rs_status st = lens_check(lensmodel, lensmodel_name, width_px, height_px, hfov_deg, err);
    if (st) return st;
    int N = mrcal_lensmodel_num_params(lensmodel);
    double *p = calloc((size_t)N, sizeof *p);
    if (!p) return rs_err_set(err, RS_ERR_NOMEM, "lens: out of memory");

    double half = 0.5 * hfov_deg * DEG, f;
    switch (family_of(lensmodel->type)) {
    case FAMILY_STEREOGRAPHIC: f = 0.5 * width_px / (2.0 * tan(0.5 * half)); break;
    case FAMILY_ANGULAR: f = 0.5 * width_px / half; break;
    default: f = 0.5 * width_px / tan(half); break;
    }
    f *= 1.0 + 0.002 * rs_rng_normal(rng);
    p[0] = p[1] = f;
    p[2] = 0.5 * (width_px - 1) + 0.004 * width_px * rs_rng_normal(rng);
    p[3] = 0.5 * (height_px - 1) + 0.004 * height_px * rs_rng_normal(rng);

    if (distortion) {
        mrcal_lensmodel_type_t t = lensmodel->type;
        if (MRCAL_LENSMODEL_IS_OPENCV(t)) {
            p[4] = -0.08 + 0.02 * rs_rng_normal(rng); // k1
            p[5] = 0.03 + 0.01 * rs_rng_normal(rng);  // k2
            p[6] = 2e-4 * rs_rng_normal(rng);         // p1
            p[7] = 2e-4 * rs_rng_normal(rng);         // p2
            if (N > 8) p[8] = -0.005 + 0.002 * rs_rng_normal(rng); // k3
            if (N > 9) p[9] = 0.01 * rs_rng_normal(rng);           // k4 (k5, k6 = 0)
            for (int i = 12; i < N; i++) p[i] = 1e-4 * rs_rng_normal(rng); // s1..s4
        } else if (t == MRCAL_LENSMODEL_CAHVOR || t == MRCAL_LENSMODEL_CAHVORE) {
            p[4] = 1e-3 * rs_rng_normal(rng);          // alpha
            p[5] = 1e-3 * rs_rng_normal(rng);          // beta
            p[7] = -0.05 + 0.01 * rs_rng_normal(rng);  // r1 (r0 = 0)
            p[8] = 0.01 + 0.003 * rs_rng_normal(rng);  // r2 (CAHVORE's e = 0)
        }
    }
    for (int i = 0; i < N; i++) p[i] = quantize(p[i], Q_MODEL);
    *intrinsics = p;
    *Nintrinsics = N;
    return RS_OK;
}

// ---------------------------------------------------------------------------------------------
// one camera: pose, field of view, projection, picks

typedef struct {
    rs_camera cam;      // the true camera (intrinsics owned)
    double cos_max;     // points further off the optical axis than the image corners are ignored
    double R_cam_enu[9];
    double p_cam_enu_m[3];
    double ypr_deg[3];
} sim_camera;

// Unprojects pixels through the lens. mrcal 2.2 cannot unproject CAHVORE; its rays come from
// the pinhole core instead, which is close for the mild distortion drawn here: callers project
// the points they place with the true model again (camera_sees), so only the spread of the
// points depends on this approximation, never their pixels.
static bool camera_unproject(const sim_camera *c, mrcal_point3_t *v, const mrcal_point2_t *q, int N)
{
    if (c->cam.lensmodel.type == MRCAL_LENSMODEL_CAHVORE) {
        mrcal_unproject_pinhole(v, NULL, q, N, c->cam.intrinsics);
        return true;
    }
    return mrcal_unproject(v, q, N, &c->cam.lensmodel, c->cam.intrinsics);
}

// The widest angle off the optical axis that the image shows (its corners), for rejecting points
// that a distortion polynomial would fold back into the image from outside the field of view.
static rs_status camera_field_of_view(sim_camera *c, rs_err *err)
{
    mrcal_point2_t q[8] = {
        {.x = -0.5, .y = -0.5},           {.x = c->cam.width - 0.5, .y = -0.5},
        {.x = -0.5, .y = c->cam.height - 0.5},     {.x = c->cam.width - 0.5, .y = c->cam.height - 0.5},
        {.x = 0.5 * c->cam.width, .y = -0.5},     {.x = 0.5 * c->cam.width, .y = c->cam.height - 0.5},
        {.x = -0.5, .y = 0.5 * c->cam.height},     {.x = c->cam.width - 0.5, .y = 0.5 * c->cam.height},
    };
    mrcal_point3_t v[8];
    if (!camera_unproject(c, v, q, 8))
        return rs_err_set(err, RS_ERR_UNSUPPORTED, "lens: mrcal cannot unproject through %s",
                          mrcal_lensmodel_name_unconfigured(&c->cam.lensmodel));
    double cos_min = 1.0;
    for (int i = 0; i < 8; i++) {
        double n = sqrt(v[i].x * v[i].x + v[i].y * v[i].y + v[i].z * v[i].z);
        double cz = n > 0 && isfinite(n) ? v[i].z / n : -1.0;
        if (cz < cos_min) cos_min = cz;
    }
    double theta = acos(cos_min) + 1.0 * DEG;
    c->cos_max = theta >= M_PI ? -1.0 : cos(theta);
    return RS_OK;
}

// Sets the pose of a camera at p_cam looking at `target`, turned by yaw_offset_deg and rolled by
// roll_deg, pitched so that the target appears at 62% of the image height. Rounds rt to 1e-6.
static void camera_look_at(sim_camera *c, const double p_cam[3], const double target[3], double yaw_offset_deg,
                           double roll_deg)
{
    double d[3] = {target[0] - p_cam[0], target[1] - p_cam[1], target[2] - p_cam[2]};
    double yaw = atan2(d[0], d[1]) / DEG + yaw_offset_deg;
    double below = atan((0.62 * (c->cam.height - 1) - c->cam.intrinsics[3]) / c->cam.intrinsics[1]) / DEG;
    double pitch = atan2(d[2], hypot(d[0], d[1])) / DEG + below;
    const double ypr[3] = {yaw, pitch, roll_deg};
    double R[9];
    rs_pose_R_from_ypr(R, ypr);
    double *rt = c->cam.rt_cam_enu;
    rs_pose_r_from_R(rt, R);
    for (int i = 0; i < 3; i++) rt[i] = quantize(rt[i], Q_MODEL);
    mrcal_R_from_r(c->R_cam_enu, NULL, rt);
    mrcal_rotate_point_R(rt + 3, NULL, NULL, c->R_cam_enu, p_cam);
    for (int i = 3; i < 6; i++) rt[i] = quantize(-rt[i], Q_MODEL);
    // The position and angles of the pose as rounded.
    double minus_t[3] = {-rt[3], -rt[4], -rt[5]};
    mrcal_rotate_point_R_inverted(c->p_cam_enu_m, NULL, NULL, c->R_cam_enu, minus_t);
    rs_pose_ypr_from_R(c->ypr_deg, c->R_cam_enu);
}

// Projects p_enu through the camera. True if the point is in front of the camera, inside its
// field of view, and projects at least margin_px inside the image.
static bool camera_sees(const sim_camera *c, double q_px[2], const double p_enu[3], double margin_px)
{
    mrcal_point3_t pc;
    mrcal_point2_t q;
    mrcal_transform_point_rt(pc.xyz, NULL, NULL, c->cam.rt_cam_enu, p_enu);
    double n = sqrt(pc.x * pc.x + pc.y * pc.y + pc.z * pc.z);
    if (!(pc.z > 0.5) || pc.z < c->cos_max * n) return false;
    if (!mrcal_project(&q, NULL, NULL, &pc, 1, &c->cam.lensmodel, c->cam.intrinsics)) return false;
    q_px[0] = q.x;
    q_px[1] = q.y;
    return isfinite(q.x) && isfinite(q.y) && q.x >= margin_px && q.y >= margin_px && q.x <= c->cam.width - 1 - margin_px &&
           q.y <= c->cam.height - 1 - margin_px;
}

// Picks: the true pixel plus N(0, sigma) noise kept inside the image (redrawn until it is), or,
// with probability outlier_fraction, a uniformly random pixel at least outlier_min_px away.
static int camera_pick(rs_rng *rng, double *q_px, bool *outlier, const double *q_true_px, int N,
                       const sim_camera *c, double sigma_px, double outlier_fraction, double outlier_min_px)
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

static void survey_noise(rs_rng *rng, double *p_survey, const double *p_true, int N, double sigma_h,
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

// A check of one option: `ok` must hold, else RS_ERR_USAGE naming the field.
#define CHECK_OPTION(ok, field, fmt, value)                                                                \
    do {                                                                                                   \
        if (!(ok)) return rs_err_set(err, RS_ERR_USAGE, "%s: " fmt " is out of range", field, value);      \
    } while (0)

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
    CHECK_OPTION(o->outlier_fraction >= 0 && o->outlier_fraction <= 0.9, "outlier_fraction", "%g",
                 o->outlier_fraction);
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
static bool place_landmark(rs_rng *rng, double p_enu[3], double q_true_px[2], const sim_camera *c,
                           bool elevated, const rs_simulate_camera_options *o)
{
    mrcal_point2_t q = {.x = rs_rng_uniform_in(rng, o->margin_px, c->cam.width - 1 - o->margin_px),
                        .y = rs_rng_uniform_in(rng, o->margin_px, c->cam.height - 1 - o->margin_px)};
    double h = elevated ? rs_rng_uniform_in(rng, o->elevated_min_m, o->elevated_max_m) : 0.0;
    mrcal_point3_t v;
    if (!camera_unproject(c, &v, &q, 1)) return false;
    double d[3];
    mrcal_rotate_point_R_inverted(d, NULL, NULL, c->R_cam_enu, v.xyz);
    if (fabs(d[2]) < 1e-12) return false;
    double s = (h - c->p_cam_enu_m[2]) / d[2];
    if (!(s > 0)) return false;
    for (int k = 0; k < 3; k++) p_enu[k] = c->p_cam_enu_m[k] + s * d[k];
    if (hypot(p_enu[0] - c->p_cam_enu_m[0], p_enu[1] - c->p_cam_enu_m[1]) > o->max_range_m) return false;
    for (int k = 0; k < 3; k++) p_enu[k] = quantize(p_enu[k], Q_ENU);
    return camera_sees(c, q_true_px, p_enu, 0.5 * o->margin_px);
}

rs_status rs_simulate_camera_problem(rs_simulate_problem **problem, const rs_simulate_camera_options *o,
                                     rs_err *err)
{
    *problem = NULL;
    rs_status st = camera_options_check(o, err);
    if (st) return st;
    rs_rng rng;
    rs_rng_seed(&rng, o->seed);

    rs_simulate_problem *p = calloc(1, sizeof *p);
    if (!p) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    sim_camera c = {.cam = {.width = o->width_px, .height = o->height_px}};
    st = rs_simulate_lens(&c.cam.lensmodel, &c.cam.intrinsics, &c.cam.Nintrinsics, &rng, o->lensmodel, o->width_px,
                          o->height_px, o->hfov_deg, o->distortion, err);
    if (st) goto fail;
    p->camera = c.cam; // p owns the intrinsics from here
    st = camera_field_of_view(&c, err);
    if (st) goto fail;

    double yaw = o->yaw_deg * DEG;
    double p_cam[3] = {-o->distance_m * sin(yaw), -o->distance_m * cos(yaw), o->camera_height_m};
    double target[3] = {0, 0, 0};
    if (o->distance_m == 0) { // looking straight down: aim a hair north of the foot of the pole
        target[0] = 1e-6 * sin(yaw);
        target[1] = 1e-6 * cos(yaw);
    }
    camera_look_at(&c, p_cam, target, 0.0, o->roll_sigma_deg * rs_rng_normal(&rng));
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
                                "landmark %d: no %s point within %g m is visible (camera %g m high, pitch %.1f deg)",
                                i, p->elevated[i] ? "elevated" : "ground", o->max_range_m, o->camera_height_m,
                                c.ypr_deg[1]);
                goto fail;
            }
    }
    p->Noutliers = camera_pick(&rng, p->q_px, p->outlier, p->q_true_px, N, &c, o->pixel_sigma_px,
                               o->outlier_fraction, o->outlier_min_px);
    survey_noise(&rng, p->p_enu_survey_m, p->p_enu_true_m, N, o->survey_sigma_h_m, o->survey_sigma_v_m);
    *problem = p;
    return RS_OK;
fail:
    if (!p->camera.intrinsics) free(c.cam.intrinsics);
    rs_simulate_problem_free(p);
    return st;
}

// ---------------------------------------------------------------------------------------------
// the intersection

// Lane width 3.5 m, two lanes each way: the roads are 14 m wide. Distances "along" an approach
// are from the centre of the intersection; "s" is across it, positive on the inbound side.
#define LANE_M 3.5
#define ROAD_HALF_M (2 * LANE_M)

typedef struct {
    double p_enu_m[3];
    const char *kind;
} candidate;

typedef struct {
    candidate *c;
    int N, cap;
} candidate_list;

static bool add_candidate(candidate_list *l, const double R_road[4], double along, double s, double dx, double dy,
                          double h, const char *kind)
{
    if (l->N == l->cap) {
        int cap = l->cap ? 2 * l->cap : 256;
        candidate *grown = realloc(l->c, sizeof *grown * (size_t)cap);
        if (!grown) return false;
        l->c = grown;
        l->cap = cap;
    }
    // (along, s) along the approach whose outward direction is (dx, dy) in the road frame, with s
    // measured to the left of the outward direction, then the road frame rotated into ENU.
    double x = along * dx - s * dy, y = along * dy + s * dx;
    candidate *c = &l->c[l->N++];
    c->p_enu_m[0] = quantize(R_road[0] * x + R_road[1] * y, Q_ENU);
    c->p_enu_m[1] = quantize(R_road[2] * x + R_road[3] * y, Q_ENU);
    c->p_enu_m[2] = quantize(h, Q_ENU);
    c->kind = kind;
    return true;
}

// Every surveyable point of the intersection: crosswalk stripe corners, stop-bar ends, lane-mark
// corners on the ground; sign tops and signal pole tops (2 to 6 m) beside the roads.
static rs_status build_intersection(candidate_list *l, rs_rng *rng, const double R_road[4], rs_err *err)
{
    static const double dirs[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
    bool ok = true;
    for (int a = 0; a < 4; a++) {
        double dx = dirs[a][0], dy = dirs[a][1];
        // Crosswalk: 13 stripes 0.5 m wide at a 1 m pitch, 3 m long; the corners of every 4th.
        for (int k = 0; k <= 12; k += 4) {
            double s0 = -6.25 + k - 0.25, s1 = s0 + 0.5;
            ok &= add_candidate(l, R_road, 9.0, s0, dx, dy, 0, "crosswalk_corner");
            ok &= add_candidate(l, R_road, 9.0, s1, dx, dy, 0, "crosswalk_corner");
            ok &= add_candidate(l, R_road, 12.0, s0, dx, dy, 0, "crosswalk_corner");
            ok &= add_candidate(l, R_road, 12.0, s1, dx, dy, 0, "crosswalk_corner");
        }
        // Stop bar across the inbound lanes, 0.5 m deep.
        ok &= add_candidate(l, R_road, 13.0, 0.2, dx, dy, 0, "stop_bar_end");
        ok &= add_candidate(l, R_road, 13.0, ROAD_HALF_M - 0.2, dx, dy, 0, "stop_bar_end");
        ok &= add_candidate(l, R_road, 13.5, 0.2, dx, dy, 0, "stop_bar_end");
        ok &= add_candidate(l, R_road, 13.5, ROAD_HALF_M - 0.2, dx, dy, 0, "stop_bar_end");
        // Lane dividers (dashes 3 m long, 0.15 m wide, every 12 m) and the edge lines' ends.
        for (int side = -1; side <= 1; side += 2)
            for (double start = 16.0; start < 50.0; start += 12.0) {
                ok &= add_candidate(l, R_road, start, side * LANE_M + 0.075, dx, dy, 0, "lane_mark_corner");
                ok &= add_candidate(l, R_road, start + 3.0, side * LANE_M - 0.075, dx, dy, 0, "lane_mark_corner");
            }
        ok &= add_candidate(l, R_road, 14.0, ROAD_HALF_M - 0.1, dx, dy, 0, "lane_mark_corner");
        ok &= add_candidate(l, R_road, 14.0, -ROAD_HALF_M + 0.1, dx, dy, 0, "lane_mark_corner");
        // Signs on the verges.
        ok &= add_candidate(l, R_road, 18.0, ROAD_HALF_M + 2.0, dx, dy, rs_rng_uniform_in(rng, 2.0, 4.0), "sign_top");
        ok &= add_candidate(l, R_road, 32.0, ROAD_HALF_M + 2.0, dx, dy, rs_rng_uniform_in(rng, 2.0, 4.0), "sign_top");
        ok &= add_candidate(l, R_road, 46.0, ROAD_HALF_M + 2.0, dx, dy, rs_rng_uniform_in(rng, 2.0, 4.0), "sign_top");
        ok &= add_candidate(l, R_road, 25.0, -ROAD_HALF_M - 2.0, dx, dy, rs_rng_uniform_in(rng, 2.0, 4.0), "sign_top");
        // The corner to the left of this approach: a signal pole and a pedestrian signal.
        ok &= add_candidate(l, R_road, 10.5, 10.5, dx, dy, rs_rng_uniform_in(rng, 5.0, 6.0), "pole_top");
        ok &= add_candidate(l, R_road, 8.0, 9.2, dx, dy, rs_rng_uniform_in(rng, 2.5, 3.5), "sign_top");
    }
    return ok ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
}

// ---------------------------------------------------------------------------------------------
// a whole site

void rs_simulate_site_options_default(rs_simulate_site_options *o)
{
    *o = (rs_simulate_site_options){
        .seed = 1,
        .Ncameras = 4,
        .landmarks_per_camera = 12,
        .lensmodel = "LENSMODEL_OPENCV8",
        .width_px = 1920,
        .height_px = 1080,
        .hfov_deg = 60,
        .pixel_sigma_px = 1,
        .survey_sigma_h_m = 0.3,
        .survey_sigma_v_m = 0.5,
        .outlier_fraction = 0.05,
        .focal_error = 1.0,
        .pole_prior_sigma_m = 0,
        .elevated_fraction = 0.25,
        .origin = {.lat_deg = 48.1374, .lon_deg = 11.5755, .h_m = 560.0},
        .force = false,
    };
}

rs_status rs_simulate_site_options_check(const rs_simulate_site_options *o, rs_err *err)
{
    CHECK_OPTION(o->seed <= (1ULL << 53), "seed", "%llu", (unsigned long long)o->seed);
    CHECK_OPTION(o->Ncameras >= 1 && o->Ncameras <= 16, "cameras", "%d (1..16)", o->Ncameras);
    CHECK_OPTION(o->landmarks_per_camera >= 4 && o->landmarks_per_camera <= 100, "landmarks-per-camera",
                 "%d (4..100)", o->landmarks_per_camera);
    CHECK_OPTION(o->pixel_sigma_px >= 0 && o->pixel_sigma_px <= 20, "pixel-sigma", "%g (0..20 px)",
                 o->pixel_sigma_px);
    CHECK_OPTION(o->survey_sigma_h_m >= 0 && o->survey_sigma_h_m <= 100, "survey-sigma", "horizontal %g (0..100 m)",
                 o->survey_sigma_h_m);
    CHECK_OPTION(o->survey_sigma_v_m >= 0 && o->survey_sigma_v_m <= 100, "survey-sigma", "vertical %g (0..100 m)",
                 o->survey_sigma_v_m);
    CHECK_OPTION(o->outlier_fraction >= 0 && o->outlier_fraction <= 0.9, "outliers", "%g (0..0.9)",
                 o->outlier_fraction);
    CHECK_OPTION(o->focal_error >= 0.5 && o->focal_error <= 2.0, "focal-error", "%g (0.5..2)", o->focal_error);
    CHECK_OPTION(o->pole_prior_sigma_m >= 0 && o->pole_prior_sigma_m <= 1000, "pole-prior", "%g (0..1000 m)",
                 o->pole_prior_sigma_m);
    CHECK_OPTION(o->elevated_fraction >= 0 && o->elevated_fraction <= 1, "elevated_fraction", "%g (0..1)",
                 o->elevated_fraction);
    CHECK_OPTION(isfinite(o->origin.lat_deg) && fabs(o->origin.lat_deg) <= 89.0, "origin", "latitude %g (-89..89)",
                 o->origin.lat_deg);
    CHECK_OPTION(isfinite(o->origin.lon_deg) && fabs(o->origin.lon_deg) <= 360.0, "origin", "longitude %g",
                 o->origin.lon_deg);
    CHECK_OPTION(isfinite(o->origin.h_m) && fabs(o->origin.h_m) <= 10000.0, "origin", "height %g (-10000..10000 m)",
                 o->origin.h_m);
    mrcal_lensmodel_t lm;
    rs_status st = lens_check(&lm, o->lensmodel, o->width_px, o->height_px, o->hfov_deg, err);
    if (st) return st;
    // The pixel sizes must leave room for the 20 px margin and the 30 px outliers.
    return RS_OK;
}

// Everything generated for a site, before it is written.
typedef struct {
    int Ncameras;
    sim_camera *cam;       // (Ncameras,)
    double *nominal;       // (Ncameras, Nintrinsics) the intrinsics the site's owner believes
    char (*note)[128];     // (Ncameras,)
    double *prior_llh;     // (Ncameras, 3) or NULL
    candidate_list cand;
    bool *visible;         // (Ncameras, Ncand)
    double *q_true_px;     // (Ncameras, Ncand, 2)
    int *landmark_of;      // (Ncand,) landmark index of a selected candidate, else -1
    int Nlandmarks;
    int *cand_of;          // (Nlandmarks,) candidate index of a landmark
    double *survey_enu_m;  // (Nlandmarks, 3)
    double *survey_llh;    // (Nlandmarks, 3)
    double *q_px;          // (Ncameras, Ncand, 2) picks (selected and visible only)
    bool *outlier;         // (Ncameras, Ncand)
    int Nobservations, Noutliers;
    double road_azimuth_deg;
    double R_road[4];      // road frame -> ENU (2x2 row-major), for lanes.geojson
} site_data;

static void site_data_free(site_data *s)
{
    if (s->cam)
        for (int k = 0; k < s->Ncameras; k++) free(s->cam[k].cam.intrinsics);
    free(s->cam);
    free(s->nominal);
    free(s->note);
    free(s->prior_llh);
    free(s->cand.c);
    free(s->visible);
    free(s->q_true_px);
    free(s->landmark_of);
    free(s->cand_of);
    free(s->survey_enu_m);
    free(s->survey_llh);
    free(s->q_px);
    free(s->outlier);
}

static const char *compass_name(double azimuth_deg)
{
    static const char *const names[8] = {"north", "north-east", "east", "south-east",
                                         "south", "south-west", "west", "north-west"};
    int i = (int)floor(fmod(azimuth_deg + 360.0 + 22.5, 360.0) / 45.0);
    return names[i & 7];
}

// Poles: cameras 0..3 on the corners, the rest beside the approaches 30, 45, ... m out.
static void pole_position(rs_rng *rng, double p_enu[3], int k, const double R_road[4])
{
    double x, y;
    if (k < 4) {
        static const double corner[4][2] = {{1, 1}, {1, -1}, {-1, -1}, {-1, 1}};
        x = corner[k][0] * rs_rng_uniform_in(rng, 10.0, 14.0);
        y = corner[k][1] * rs_rng_uniform_in(rng, 10.0, 14.0);
    } else {
        static const double dirs[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
        int a = (k - 4) % 4, ring = (k - 4) / 4;
        double along = 30.0 + 15.0 * ring + rs_rng_uniform_in(rng, -3.0, 3.0);
        double s = (ring % 2 ? -1.0 : 1.0) * (ROAD_HALF_M + rs_rng_uniform_in(rng, 2.5, 4.5));
        x = along * dirs[a][0] - s * dirs[a][1];
        y = along * dirs[a][1] + s * dirs[a][0];
    }
    p_enu[0] = R_road[0] * x + R_road[1] * y;
    p_enu[1] = R_road[2] * x + R_road[3] * y;
    p_enu[2] = rs_rng_uniform_in(rng, 5.0, 12.0);
}

// Shuffles idx[0..n) (Fisher-Yates).
static void shuffle(rs_rng *rng, int *idx, int n)
{
    for (int i = n - 1; i > 0; i--) {
        int j = (int)(rs_rng_u64(rng) % (uint64_t)(i + 1));
        int t = idx[i];
        idx[i] = idx[j];
        idx[j] = t;
    }
}

static bool is_elevated(const candidate *c) { return c->p_enu_m[2] != 0.0; }

// Chooses landmarks so that each camera sees about landmarks_per_camera of them, about
// elevated_fraction of those above the ground; a landmark seen by several cameras counts once.
static rs_status select_landmarks(site_data *s, rs_rng *rng, const rs_simulate_site_options *o, rs_err *err)
{
    int Nc = s->cand.N;
    int *pool = malloc(sizeof *pool * (size_t)Nc);
    int *penalty = malloc(sizeof *penalty * (size_t)Nc);
    bool *chosen = calloc((size_t)Nc, sizeof *chosen);
    bool *full = calloc((size_t)s->Ncameras, sizeof *full);
    s->landmark_of = malloc(sizeof *s->landmark_of * (size_t)Nc);
    s->cand_of = malloc(sizeof *s->cand_of * (size_t)Nc);
    rs_status st = RS_OK;
    if (!pool || !penalty || !chosen || !full || !s->landmark_of || !s->cand_of) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    int M = o->landmarks_per_camera, M_elevated = (int)lround(o->elevated_fraction * M);
    int K = s->Ncameras;
    for (int k = 0; k < K; k++) {
        const bool *vis = s->visible + (size_t)k * Nc;
        int have = 0, have_elevated = 0;
        for (int j = 0; j < Nc; j++)
            if (vis[j] && chosen[j]) {
                have++;
                have_elevated += is_elevated(&s->cand.c[j]);
            }
        // The cameras that already have their share.
        for (int k2 = 0; k2 < K; k2++) {
            int n = 0;
            for (int j = 0; j < Nc; j++) n += chosen[j] && s->visible[(size_t)k2 * Nc + j];
            full[k2] = k2 != k && n >= M;
        }
        // First the elevated ones up to their share, then anything; in random order, but those
        // that would add to cameras that already have their share last.
        for (int pass = 0; pass < 2; pass++) {
            int n = 0;
            for (int j = 0; j < Nc; j++)
                if (vis[j] && !chosen[j] && (pass == 1 || is_elevated(&s->cand.c[j]))) pool[n++] = j;
            shuffle(rng, pool, n);
            for (int i = 0; i < n; i++) {
                penalty[pool[i]] = 0;
                for (int k2 = 0; k2 < K; k2++) penalty[pool[i]] += full[k2] && s->visible[(size_t)k2 * Nc + pool[i]];
            }
            for (int i = 1; i < n; i++) // stable insertion sort by penalty
                for (int m = i; m > 0 && penalty[pool[m - 1]] > penalty[pool[m]]; m--) {
                    int t = pool[m];
                    pool[m] = pool[m - 1];
                    pool[m - 1] = t;
                }
            for (int i = 0; i < n && have < M && (pass == 1 || have_elevated < M_elevated); i++) {
                chosen[pool[i]] = true;
                have++;
                have_elevated += is_elevated(&s->cand.c[pool[i]]);
            }
        }
    }
    s->Nlandmarks = 0;
    for (int j = 0; j < Nc; j++) {
        s->landmark_of[j] = chosen[j] ? s->Nlandmarks : -1;
        if (chosen[j]) s->cand_of[s->Nlandmarks++] = j;
    }
done:
    free(pool);
    free(penalty);
    free(chosen);
    free(full);
    return st;
}

static rs_status simulate_site_data(site_data *s, const rs_simulate_site_options *o, rs_err *err)
{
    rs_rng rng;
    rs_rng_seed(&rng, o->seed);
    rs_status st;
    int K = o->Ncameras;
    s->Ncameras = K;

    // The roads: one along the road frame's x axis, one along its y axis, turned by up to 30 deg.
    double theta = rs_rng_uniform_in(&rng, -30.0, 30.0) * DEG;
    double R_road[4] = {cos(theta), -sin(theta), sin(theta), cos(theta)};
    s->road_azimuth_deg = fmod(90.0 - theta / DEG + 360.0, 180.0);
    memcpy(s->R_road, R_road, sizeof R_road);
    if ((st = build_intersection(&s->cand, &rng, R_road, err))) return st;
    int Nc = s->cand.N;

    s->cam = calloc((size_t)K, sizeof *s->cam);
    s->note = calloc((size_t)K, sizeof *s->note);
    s->visible = calloc((size_t)K * Nc, sizeof *s->visible);
    s->q_true_px = calloc((size_t)K * Nc * 2, sizeof *s->q_true_px);
    s->q_px = calloc((size_t)K * Nc * 2, sizeof *s->q_px);
    s->outlier = calloc((size_t)K * Nc, sizeof *s->outlier);
    if (!s->cam || !s->note || !s->visible || !s->q_true_px || !s->q_px || !s->outlier)
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");

    for (int k = 0; k < K; k++) {
        sim_camera *c = &s->cam[k];
        c->cam.width = o->width_px;
        c->cam.height = o->height_px;
        if ((st = rs_simulate_lens(&c->cam.lensmodel, &c->cam.intrinsics, &c->cam.Nintrinsics, &rng, o->lensmodel, o->width_px,
                                   o->height_px, o->hfov_deg, true, err)))
            return st;
        if ((st = camera_field_of_view(c, err))) return rs_err_prefix(err, "camera %d", k + 1);
        // Draw the pole and the aim until the camera sees at least 4 candidates.
        int Nvisible = 0;
        for (int tries = 0; tries < 50 && Nvisible < 4; tries++) {
            double p_cam[3], centre[3] = {0, 0, 0};
            pole_position(&rng, p_cam, k, R_road);
            double roll = fmax(-3.0, fmin(3.0, rs_rng_normal(&rng)));
            camera_look_at(c, p_cam, centre, rs_rng_uniform_in(&rng, -10.0, 10.0), roll);
            Nvisible = 0;
            for (int j = 0; j < Nc; j++) {
                bool v = camera_sees(c, s->q_true_px + 2 * ((size_t)k * Nc + j), s->cand.c[j].p_enu_m, 20.0);
                s->visible[(size_t)k * Nc + j] = v;
                Nvisible += v;
            }
        }
        if (Nvisible < 4)
            return rs_err_set(err, RS_ERR_DEGENERATE, "camera %d: sees %d landmarks of the intersection, needs 4",
                              k + 1, Nvisible);
        double d = hypot(c->p_cam_enu_m[0], c->p_cam_enu_m[1]);
        double az = atan2(c->p_cam_enu_m[0], c->p_cam_enu_m[1]) / DEG;
        snprintf(s->note[k], sizeof s->note[k], "simulated camera on a %.1f m pole %.1f m %s of the centre",
                 c->p_cam_enu_m[2], d, compass_name(az));
    }
    if ((st = select_landmarks(s, &rng, o, err))) return st;

    // Picks of the chosen landmarks that each camera sees.
    for (int k = 0; k < K; k++)
        for (int j = 0; j < Nc; j++) {
            size_t kj = (size_t)k * Nc + j;
            if (s->landmark_of[j] < 0 || !s->visible[kj]) continue;
            s->Nobservations++;
            s->Noutliers += camera_pick(&rng, s->q_px + 2 * kj, s->outlier + kj, s->q_true_px + 2 * kj, 1,
                                        &s->cam[k], o->pixel_sigma_px, o->outlier_fraction, 30.0);
        }
    for (int k = 0; k < K; k++) {
        int n = 0;
        for (int j = 0; j < Nc; j++) n += s->landmark_of[j] >= 0 && s->visible[(size_t)k * Nc + j];
        if (n < 4)
            return rs_err_set(err, RS_ERR_DEGENERATE, "camera %d: observes %d landmarks, needs 4", k + 1, n);
    }

    // The survey: true positions plus noise, in WGS84.
    int L = s->Nlandmarks;
    double *p_true = malloc(sizeof(double) * 3 * (size_t)L);
    s->survey_enu_m = malloc(sizeof(double) * 3 * (size_t)L);
    s->survey_llh = malloc(sizeof(double) * 3 * (size_t)L);
    if (!p_true || !s->survey_enu_m || !s->survey_llh) {
        free(p_true);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    for (int i = 0; i < L; i++) memcpy(p_true + 3 * i, s->cand.c[s->cand_of[i]].p_enu_m, 3 * sizeof(double));
    survey_noise(&rng, s->survey_enu_m, p_true, L, o->survey_sigma_h_m, o->survey_sigma_v_m);
    free(p_true);
    if ((st = rs_geo_enu_to_llh(s->survey_llh, &o->origin, s->survey_enu_m, L, err)))
        return rs_err_prefix(err, "landmarks");

    // What the owner believes about the lenses, and where the poles are.
    int Ni = s->cam[0].cam.Nintrinsics;
    s->nominal = malloc(sizeof(double) * (size_t)K * Ni);
    if (!s->nominal) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int k = 0; k < K; k++) {
        double *n = s->nominal + (size_t)k * Ni;
        memcpy(n, s->cam[k].cam.intrinsics, sizeof(double) * Ni);
        n[0] = quantize(n[0] * o->focal_error, Q_MODEL);
        n[1] = quantize(n[1] * o->focal_error, Q_MODEL);
    }
    if (o->pole_prior_sigma_m > 0) {
        double *p = malloc(sizeof(double) * 3 * (size_t)K);
        s->prior_llh = malloc(sizeof(double) * 3 * (size_t)K);
        if (!p || !s->prior_llh) {
            free(p);
            return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        }
        for (int k = 0; k < K; k++)
            for (int i = 0; i < 3; i++)
                p[3 * k + i] = s->cam[k].p_cam_enu_m[i] + o->pole_prior_sigma_m * rs_rng_normal(&rng);
        st = rs_geo_enu_to_llh(s->prior_llh, &o->origin, p, K, err);
        free(p);
        if (st) return rs_err_prefix(err, "position priors");
    }
    return RS_OK;
}

// ---- writing ----

static rs_status write_json(const char *dir, const char *rel, cJSON *json, rs_err *err)
{
    char *path = rs_io_join(dir, rel);
    char *text = json ? cJSON_Print(json) : NULL;
    rs_status st;
    if (!path || !text) st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", rel);
    else {
        size_t n = strlen(text);
        char *with_newline = realloc(text, n + 2);
        if (!with_newline) st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", rel);
        else {
            text = with_newline;
            text[n] = '\n';
            text[n + 1] = '\0';
            st = rs_io_write_file(path, text, n + 1, err);
        }
    }
    free(text);
    free(path);
    return st;
}

// Writes camera c's lens and size with the given intrinsics and pose (core's writer: atomic).
static rs_status write_cameramodel(const char *dir, const char *rel, const sim_camera *c, const double *intrinsics,
                                   const double rt_cam_enu[6], rs_err *err)
{
    char *path = rs_io_join(dir, rel);
    if (!path) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", rel);
    rs_camera view = c->cam;
    view.intrinsics = (double *)intrinsics;
    memcpy(view.rt_cam_enu, rt_cam_enu, sizeof view.rt_cam_enu);
    rs_status st = rs_camera_write_cameramodel(&view, path, err);
    free(path);
    return st;
}

static cJSON *json_array(const double *x, int n)
{
    return cJSON_CreateDoubleArray(x, n);
}

static cJSON *json_llh(double lat, double lon, double h)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "lat", lat);
    cJSON_AddNumberToObject(o, "lon", lon);
    cJSON_AddNumberToObject(o, "h", h);
    return o;
}

static cJSON *json_options(const rs_simulate_site_options *o)
{
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "generator", "roadside site simulate");
    cJSON_AddNumberToObject(j, "seed", (double)o->seed);
    cJSON_AddNumberToObject(j, "cameras", o->Ncameras);
    cJSON_AddNumberToObject(j, "landmarks_per_camera", o->landmarks_per_camera);
    cJSON_AddStringToObject(j, "lens", o->lensmodel);
    double image[2] = {o->width_px, o->height_px};
    cJSON_AddItemToObject(j, "image", json_array(image, 2));
    cJSON_AddNumberToObject(j, "hfov_deg", o->hfov_deg);
    cJSON_AddNumberToObject(j, "pixel_sigma_px", o->pixel_sigma_px);
    cJSON *ss = cJSON_AddObjectToObject(j, "survey_sigma_m");
    cJSON_AddNumberToObject(ss, "horizontal", o->survey_sigma_h_m);
    cJSON_AddNumberToObject(ss, "vertical", o->survey_sigma_v_m);
    cJSON_AddNumberToObject(j, "outliers", o->outlier_fraction);
    cJSON_AddNumberToObject(j, "focal_error", o->focal_error);
    cJSON_AddNumberToObject(j, "pole_prior_sigma_m", o->pole_prior_sigma_m);
    cJSON_AddNumberToObject(j, "elevated_fraction", o->elevated_fraction);
    cJSON_AddItemToObject(j, "origin", json_llh(o->origin.lat_deg, o->origin.lon_deg, o->origin.h_m));
    return j;
}

static void landmark_id(char id[16], int i) { snprintf(id, 16, "L%03d", i + 1); }
static void camera_id(char id[16], int k) { snprintf(id, 16, "cam%d", k + 1); }

static rs_status write_site_json(const char *dir, const site_data *s, const rs_simulate_site_options *o, rs_err *err)
{
    cJSON *j = cJSON_CreateObject();
    char name[64];
    snprintf(name, sizeof name, "simulated intersection (seed %llu)", (unsigned long long)o->seed);
    cJSON_AddStringToObject(j, "name", name);
    cJSON_AddItemToObject(j, "origin", json_llh(o->origin.lat_deg, o->origin.lon_deg, o->origin.h_m));
    cJSON_AddStringToObject(j, "heights", "ellipsoidal");
    cJSON *ls = cJSON_AddObjectToObject(j, "landmark_sigma_m");
    cJSON_AddNumberToObject(ls, "horizontal", fmax(o->survey_sigma_h_m, DECLARED_SURVEY_SIGMA_MIN_M));
    cJSON_AddNumberToObject(ls, "vertical", fmax(o->survey_sigma_v_m, DECLARED_SURVEY_SIGMA_MIN_M));
    cJSON *gp = cJSON_AddObjectToObject(j, "ground_plane");
    static const double up[3] = {0, 0, 1};
    cJSON_AddItemToObject(gp, "normal_enu", json_array(up, 3));
    cJSON_AddNumberToObject(gp, "offset_m", 0.0);
    cJSON *cams = cJSON_AddArrayToObject(j, "cameras");
    for (int k = 0; k < s->Ncameras; k++) {
        char id[16], path[64];
        camera_id(id, k);
        cJSON *c = cJSON_CreateObject();
        cJSON_AddStringToObject(c, "id", id);
        snprintf(path, sizeof path, "cameras/%s.cameramodel", id);
        cJSON_AddStringToObject(c, "model", path);
        snprintf(path, sizeof path, "observations/%s.csv", id);
        cJSON_AddStringToObject(c, "observations", path);
        if (s->prior_llh) {
            const double *p = s->prior_llh + 3 * k;
            cJSON *pp = json_llh(p[0], p[1], p[2]);
            cJSON_AddNumberToObject(pp, "sigma_m", o->pole_prior_sigma_m);
            cJSON_AddItemToObject(c, "position_prior", pp);
        }
        cJSON_AddStringToObject(c, "note", s->note[k]);
        cJSON_AddItemToArray(cams, c);
    }
    cJSON_AddItemToObject(j, "simulated", json_options(o));
    rs_status st = write_json(dir, "site.json", j, err);
    cJSON_Delete(j);
    return st;
}

static rs_status write_landmarks_geojson(const char *dir, const site_data *s, rs_err *err)
{
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "type", "FeatureCollection");
    cJSON *features = cJSON_AddArrayToObject(j, "features");
    for (int i = 0; i < s->Nlandmarks; i++) {
        char id[16];
        landmark_id(id, i);
        const double *llh = s->survey_llh + 3 * i;
        double lonlath[3] = {llh[1], llh[0], llh[2]};
        cJSON *f = cJSON_CreateObject();
        cJSON_AddStringToObject(f, "type", "Feature");
        cJSON *g = cJSON_AddObjectToObject(f, "geometry");
        cJSON_AddStringToObject(g, "type", "Point");
        cJSON_AddItemToObject(g, "coordinates", json_array(lonlath, 3));
        cJSON *p = cJSON_AddObjectToObject(f, "properties");
        cJSON_AddStringToObject(p, "id", id);
        cJSON_AddStringToObject(p, "kind", s->cand.c[s->cand_of[i]].kind);
        cJSON_AddItemToArray(features, f);
    }
    rs_status st = write_json(dir, "landmarks.geojson", j, err);
    cJSON_Delete(j);
    return st;
}

// ---- lanes.geojson: the intersection's lanes (docs/site-format.md, "lanes.geojson") ----
//
// Right-hand traffic. Per approach a (A1..A4, outward directions +x, +y, -x, -y of the road
// frame): inbound lanes in1 (inner, s = 1.75 m) and in2 (outer, s = 5.25 m) from 60 m out to the
// stop bar at 13.5 m, outbound lanes out1/out2 (s = -1.75, -5.25 m) from 13.5 m to 60 m, and the
// junction lanes that join them: straight on from in1/in2 to out1/out2 of the opposite approach,
// left from in1 to out1 of the approach on the left, right from in2 to out2 of the approach on
// the right; each a cubic Bezier between the two lane ends, tangent to both, in 8 pieces.

#define LANE_FAR_M 60.0
#define LANE_STOP_M 13.5
#define LANE_SPEED_MPS 13.89 // 50 km/h
#define TURN_SPEED_MPS 8.33  // 30 km/h

// Road-frame point of (along, s) on approach a.
static void approach_point(double p[2], int a, double along, double s)
{
    static const double dirs[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
    double dx = dirs[a][0], dy = dirs[a][1];
    p[0] = along * dx - s * dy;
    p[1] = along * dy + s * dx;
}

static void lane_id(char *buf, size_t n, int a, bool in, int k)
{
    snprintf(buf, n, "A%d_%s%d", a % 10 + 1, in ? "in" : "out", k % 10);
}

// Appends one lane Feature; pts_road (Npts, 2) in the road frame.
static rs_status add_lane(cJSON *features, const site_data *s, const rs_simulate_site_options *o, const char *id,
                          const char *kind, double speed_mps, const double (*pts_road)[2], int Npts,
                          const char *const *next, int Nnext, rs_err *err)
{
    double enu[9][3], llh[9][3];
    for (int i = 0; i < Npts; i++) {
        enu[i][0] = quantize(s->R_road[0] * pts_road[i][0] + s->R_road[1] * pts_road[i][1], Q_ENU);
        enu[i][1] = quantize(s->R_road[2] * pts_road[i][0] + s->R_road[3] * pts_road[i][1], Q_ENU);
        enu[i][2] = 0.0;
    }
    rs_status st = rs_geo_enu_to_llh(&llh[0][0], &o->origin, &enu[0][0], Npts, err);
    if (st) return st;
    cJSON *f = cJSON_CreateObject();
    cJSON_AddItemToArray(features, f);
    cJSON_AddStringToObject(f, "type", "Feature");
    cJSON *g = cJSON_AddObjectToObject(f, "geometry");
    cJSON_AddStringToObject(g, "type", "LineString");
    cJSON *c = cJSON_AddArrayToObject(g, "coordinates");
    for (int i = 0; i < Npts; i++) {
        double lonlat[2] = {llh[i][1], llh[i][0]};
        cJSON_AddItemToArray(c, json_array(lonlat, 2));
    }
    cJSON *p = cJSON_AddObjectToObject(f, "properties");
    cJSON_AddStringToObject(p, "id", id);
    cJSON_AddStringToObject(p, "kind", kind);
    cJSON_AddNumberToObject(p, "width_m", LANE_M);
    cJSON_AddStringToObject(p, "direction", "forward");
    cJSON_AddNumberToObject(p, "speed_mps", speed_mps);
    cJSON *nx = cJSON_AddArrayToObject(p, "next");
    for (int i = 0; i < Nnext; i++) cJSON_AddItemToArray(nx, cJSON_CreateString(next[i]));
    return RS_OK;
}

static rs_status write_lanes_geojson(const char *dir, const site_data *s, const rs_simulate_site_options *o,
                                     rs_err *err)
{
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "type", "FeatureCollection");
    cJSON *features = cJSON_AddArrayToObject(j, "features");
    rs_status st = RS_OK;
    for (int a = 0; a < 4 && !st; a++)
        for (int k = 1; k <= 2 && !st; k++) {
            double s_in = LANE_M * (k - 0.5);
            char id[16], nid[2][48], jid[16];
            const char *next[3];
            double pts[9][2];
            // The manoeuvres of inbound lane k: straight on, then left (k = 1) or right (k = 2).
            int to[2] = {(a + 2) % 4, k == 1 ? (a + 3) % 4 : (a + 1) % 4};
            const char *how[2] = {"straight", k == 1 ? "left" : "right"};
            lane_id(id, sizeof id, a, true, k);
            for (int m = 0; m < 2; m++) {
                lane_id(jid, sizeof jid, to[m], false, k);
                snprintf(nid[m], sizeof nid[m], "%s_%s_%s", id, how[m], jid);
                next[m] = nid[m];
            }
            approach_point(pts[0], a, LANE_FAR_M, s_in);
            approach_point(pts[1], a, LANE_STOP_M, s_in);
            if ((st = add_lane(features, s, o, id, "approach", LANE_SPEED_MPS, (const double(*)[2])pts, 2, next, 2,
                               err)))
                break;
            for (int m = 0; m < 2 && !st; m++) {
                // Cubic Bezier from the stop bar of (a, k) to the start of outbound lane k of to[m].
                double p0[2], p3[2], d0[2], d3[2], q[2];
                approach_point(p0, a, LANE_STOP_M, s_in);
                approach_point(p3, to[m], LANE_STOP_M, -s_in);
                approach_point(q, a, LANE_STOP_M - 1.0, s_in);
                d0[0] = q[0] - p0[0], d0[1] = q[1] - p0[1];          // unit inbound direction
                approach_point(q, to[m], LANE_STOP_M + 1.0, -s_in);
                d3[0] = q[0] - p3[0], d3[1] = q[1] - p3[1];          // unit outbound direction
                double L = hypot(p3[0] - p0[0], p3[1] - p0[1]) / 3.0;
                double p1[2] = {p0[0] + L * d0[0], p0[1] + L * d0[1]};
                double p2[2] = {p3[0] - L * d3[0], p3[1] - L * d3[1]};
                for (int i = 0; i <= 8; i++) {
                    double t = i / 8.0, u = 1 - t;
                    for (int c = 0; c < 2; c++)
                        pts[i][c] = u * u * u * p0[c] + 3 * u * u * t * p1[c] + 3 * u * t * t * p2[c] + t * t * t * p3[c];
                }
                lane_id(jid, sizeof jid, to[m], false, k);
                const char *jn[1] = {jid};
                st = add_lane(features, s, o, nid[m], "junction", m == 0 ? LANE_SPEED_MPS : TURN_SPEED_MPS,
                              (const double(*)[2])pts, 9, jn, 1, err);
            }
        }
    for (int a = 0; a < 4 && !st; a++)
        for (int k = 1; k <= 2 && !st; k++) {
            char id[16];
            double pts[2][2];
            lane_id(id, sizeof id, a, false, k);
            approach_point(pts[0], a, LANE_STOP_M, -LANE_M * (k - 0.5));
            approach_point(pts[1], a, LANE_FAR_M, -LANE_M * (k - 0.5));
            st = add_lane(features, s, o, id, "exit", LANE_SPEED_MPS, (const double(*)[2])pts, 2, NULL, 0, err);
        }
    if (!st) st = write_json(dir, "lanes.geojson", j, err);
    cJSON_Delete(j);
    return st;
}

static rs_status write_observations(const char *dir, const site_data *s, int k, double sigma_px, rs_err *err)
{
    char id[16], rel[64];
    camera_id(id, k);
    snprintf(rel, sizeof rel, "observations/%s.csv", id);
    char *path = rs_io_join(dir, rel);
    if (!path) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", rel);
    rs_io_atomic a;
    rs_status st = rs_io_atomic_open(&a, path, err);
    free(path);
    if (st) return st;
    int Nc = s->cand.N;
    fprintf(a.f, "landmark,u,v,sigma_px\n");
    for (int i = 0; i < s->Nlandmarks; i++) {
        size_t kj = (size_t)k * Nc + s->cand_of[i];
        if (!s->visible[kj]) continue;
        char lid[16];
        landmark_id(lid, i);
        fprintf(a.f, "%s,%.6f,%.6f,%g\n", lid, s->q_px[2 * kj], s->q_px[2 * kj + 1], sigma_px);
    }
    return rs_io_atomic_commit(&a, err);
}

static rs_status write_truth_landmarks(const char *dir, const site_data *s, rs_err *err)
{
    char *path = rs_io_join(dir, "truth/landmarks_enu.csv");
    if (!path) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_io_atomic a;
    rs_status st = rs_io_atomic_open(&a, path, err);
    free(path);
    if (st) return st;
    fprintf(a.f, "id,e,n,u\n");
    for (int i = 0; i < s->Nlandmarks; i++) {
        char id[16];
        landmark_id(id, i);
        const double *p = s->cand.c[s->cand_of[i]].p_enu_m;
        fprintf(a.f, "%s,%.4f,%.4f,%.4f\n", id, p[0], p[1], p[2]);
    }
    return rs_io_atomic_commit(&a, err);
}

static rs_status write_truth_json(const char *dir, const site_data *s, const rs_simulate_site_options *o, rs_err *err)
{
    cJSON *j = cJSON_CreateObject();
    cJSON_AddNumberToObject(j, "seed", (double)o->seed);
    cJSON_AddItemToObject(j, "options", json_options(o));
    cJSON_AddNumberToObject(j, "road_azimuth_deg", s->road_azimuth_deg);
    cJSON_AddNumberToObject(j, "observations", s->Nobservations);
    cJSON_AddNumberToObject(j, "outliers", s->Noutliers);
    cJSON *cams = cJSON_AddArrayToObject(j, "cameras");
    int Nc = s->cand.N;
    for (int k = 0; k < s->Ncameras; k++) {
        const sim_camera *c = &s->cam[k];
        char id[16];
        camera_id(id, k);
        cJSON *cj = cJSON_CreateObject();
        cJSON_AddStringToObject(cj, "id", id);
        cJSON_AddItemToObject(cj, "rt_cam_enu", json_array(c->cam.rt_cam_enu, 6));
        cJSON_AddItemToObject(cj, "position_enu_m", json_array(c->p_cam_enu_m, 3));
        cJSON_AddItemToObject(cj, "yaw_pitch_roll_deg", json_array(c->ypr_deg, 3));
        cJSON_AddItemToObject(cj, "intrinsics", json_array(c->cam.intrinsics, c->cam.Nintrinsics));
        cJSON_AddItemToObject(cj, "nominal_intrinsics",
                              json_array(s->nominal + (size_t)k * c->cam.Nintrinsics, c->cam.Nintrinsics));
        cJSON *obs = cJSON_AddArrayToObject(cj, "observed");
        cJSON *out = cJSON_AddArrayToObject(cj, "outliers");
        for (int i = 0; i < s->Nlandmarks; i++) {
            size_t kj = (size_t)k * Nc + s->cand_of[i];
            if (!s->visible[kj]) continue;
            char lid[16];
            landmark_id(lid, i);
            cJSON_AddItemToArray(obs, cJSON_CreateString(lid));
            if (s->outlier[kj]) cJSON_AddItemToArray(out, cJSON_CreateString(lid));
        }
        cJSON_AddItemToArray(cams, cj);
    }
    cJSON *lms = cJSON_AddArrayToObject(j, "landmarks");
    for (int i = 0; i < s->Nlandmarks; i++) {
        char id[16];
        landmark_id(id, i);
        const candidate *c = &s->cand.c[s->cand_of[i]];
        double e[3];
        for (int a = 0; a < 3; a++) e[a] = s->survey_enu_m[3 * i + a] - c->p_enu_m[a];
        cJSON *l = cJSON_CreateObject();
        cJSON_AddStringToObject(l, "id", id);
        cJSON_AddStringToObject(l, "kind", c->kind);
        cJSON_AddItemToObject(l, "enu_m", json_array(c->p_enu_m, 3));
        cJSON_AddItemToObject(l, "survey_error_enu_m", json_array(e, 3));
        cJSON_AddItemToArray(lms, l);
    }
    rs_status st = write_json(dir, "truth/truth.json", j, err);
    cJSON_Delete(j);
    return st;
}

static rs_status write_site(const char *dir, const site_data *s, const rs_simulate_site_options *o, rs_err *err)
{
    rs_status st;
    static const char *const folders[3] = {"cameras", "observations", "truth"};
    for (int i = 0; i < 3; i++) {
        char *p = rs_io_join(dir, folders[i]);
        st = p ? rs_io_mkdir_p(p, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        free(p);
        if (st) return st;
    }
    if ((st = write_site_json(dir, s, o, err)) || (st = write_landmarks_geojson(dir, s, err)) ||
        (st = write_lanes_geojson(dir, s, o, err)) ||
        (st = write_truth_landmarks(dir, s, err)) || (st = write_truth_json(dir, s, o, err)))
        return st;
    static const double zero_rt[6] = {0};
    for (int k = 0; k < s->Ncameras; k++) {
        const sim_camera *c = &s->cam[k];
        char id[16], rel[64];
        camera_id(id, k);
        snprintf(rel, sizeof rel, "cameras/%s.cameramodel", id);
        if ((st = write_cameramodel(dir, rel, c, s->nominal + (size_t)k * c->cam.Nintrinsics, zero_rt, err))) return st;
        snprintf(rel, sizeof rel, "truth/%s.cameramodel", id);
        if ((st = write_cameramodel(dir, rel, c, c->cam.intrinsics, c->cam.rt_cam_enu, err))) return st;
        if ((st = write_observations(dir, s, k, fmax(o->pixel_sigma_px, DECLARED_PIXEL_SIGMA_MIN_PX), err)))
            return st;
    }
    return RS_OK;
}

// ---- the folder: built aside, renamed into place ----


// 0: does not exist; 1: empty folder; 2: a site folder (non-empty, holds site.json);
// 3: anything else (a file, a non-empty folder that is not a site).
static int target_state(const char *dir)
{
    struct stat sb;
    if (stat(dir, &sb) != 0) return errno == ENOENT ? 0 : 3;
    if (!S_ISDIR(sb.st_mode)) return 3;
    DIR *d = opendir(dir);
    if (!d) return 3;
    bool empty = true;
    for (struct dirent *e; (e = readdir(d));)
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) {
            empty = false;
            break;
        }
    closedir(d);
    if (empty) return 1;
    char *site = rs_io_join(dir, "site.json");
    bool is_site = site && stat(site, &sb) == 0 && S_ISREG(sb.st_mode);
    free(site);
    return is_site ? 2 : 3;
}

static rs_status check_target(const char *dir, bool force, rs_err *err)
{
    struct stat sb;
    if (stat(dir, &sb) != 0 && errno != ENOENT)
        return rs_err_set(err, RS_ERR_IO, "%s: cannot use it: %s", dir, strerror(errno));
    switch (target_state(dir)) {
    case 0:
    case 1: return RS_OK;
    case 2:
        return force ? RS_OK
                     : rs_err_set(err, RS_ERR_IO, "%s: a site is already there (use --force to replace it)", dir);
    default:
        return rs_err_set(err, RS_ERR_IO,
                          "%s: exists and is not an empty folder or a site folder; refusing to write there%s", dir,
                          force ? " even with --force" : "");
    }
}

// "<parent>/.<base>.<tag>.XXXXXX" for mkdtemp, beside dir.
static char *sibling_template(const char *dir, const char *tag)
{
    size_t n = strlen(dir);
    while (n > 1 && dir[n - 1] == '/') n--;
    size_t b = n;
    while (b > 0 && dir[b - 1] != '/') b--;
    size_t len = n + strlen(tag) + 16;
    char *t = malloc(len);
    if (t) snprintf(t, len, "%.*s.%.*s.%s.XXXXXX", (int)b, dir, (int)(n - b), dir + b, tag);
    return t;
}

static rs_status simulate_site_into(const char *dir, const rs_simulate_site_options *o, rs_err *err);

rs_status rs_simulate_site(const char *dir, const rs_simulate_site_options *o, rs_err *err)
{
    if (!dir || !*dir) return rs_err_set(err, RS_ERR_USAGE, "no site folder given");
    char *d = strdup(dir);
    if (!d) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (size_t n = strlen(d); n > 1 && d[n - 1] == '/'; n--) d[n - 1] = '\0';
    const char *base = strrchr(d, '/');
    base = base ? base + 1 : d;
    rs_status st;
    if (!*base || !strcmp(base, ".") || !strcmp(base, ".."))
        st = rs_err_set(err, RS_ERR_USAGE, "%s: name the site folder itself, not '.', '..' or '/'", dir);
    else
        st = simulate_site_into(d, o, err);
    free(d);
    return st;
}

static rs_status simulate_site_into(const char *dir, const rs_simulate_site_options *o, rs_err *err)
{
    rs_status st = rs_simulate_site_options_check(o, err);
    if (st) return st;
    if ((st = check_target(dir, o->force, err))) return st;

    site_data s = {0};
    char *tmp = NULL, *old = NULL, *parent = NULL;
    if ((st = simulate_site_data(&s, o, err))) goto done;

    // Build the site in a hidden sibling folder.
    tmp = sibling_template(dir, "tmp");
    if (!tmp) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    parent = strdup(tmp);
    if (!parent) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    char *slash = strrchr(parent, '/');
    if (slash && slash != parent) {
        *slash = '\0';
        if ((st = rs_io_mkdir_p(parent, err))) goto done;
    }
    if (!mkdtemp(tmp)) {
        st = rs_err_set(err, RS_ERR_IO, "%s: cannot create a temporary folder beside it: %s", dir, strerror(errno));
        free(tmp);
        tmp = NULL;
        goto done;
    }
    if ((st = write_site(tmp, &s, o, err))) goto done;

    // Put it in place: straight over a missing or empty folder; a site being replaced is moved
    // aside first and deleted once the new one is in.
    if ((st = check_target(dir, o->force, err))) goto done;
    if (target_state(dir) == 2) {
        old = sibling_template(dir, "old");
        if (!old || !mkdtemp(old)) {
            st = rs_err_set(err, RS_ERR_IO, "%s: cannot create a temporary folder beside it", dir);
            free(old);
            old = NULL;
            goto done;
        }
        if (rename(dir, old) != 0) {
            st = rs_err_set(err, RS_ERR_IO, "%s: cannot move the old site aside: %s", dir, strerror(errno));
            rmdir(old);
            goto done;
        }
    }
    if (rename(tmp, dir) != 0) {
        st = rs_err_set(err, RS_ERR_IO, "%s: cannot rename the new site into place: %s", dir, strerror(errno));
        if (old) rename(old, dir);
        goto done;
    }
    free(tmp);
    tmp = NULL;
    if (old) rs_io_remove_tree(old);
done:
    if (tmp) rs_io_remove_tree(tmp);
    free(tmp);
    free(old);
    free(parent);
    site_data_free(&s);
    return st;
}

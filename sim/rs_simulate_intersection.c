// rs_simulate_intersection.c -- the simulated intersection, everything drawn before a site is
// written (sim/internal/rs_simulate_internal.h): its surveyable points, the cameras on their
// poles, the landmarks chosen, the picks, the survey, the nominal lenses, the pole priors, and its
// lanes. Calls rs_simulate_camera.c, rs_simulate_lens.c (through it), geo (rs_geo_enu_to_llh)
// and core/.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sim/internal/rs_simulate_internal.h"

// ---------------------------------------------------------------------------------------------
// the intersection

// Lane width 3.5 m, two lanes each way: the roads are 14 m wide. Distances "along" an approach
// are from the centre of the intersection; "s" is across it, positive on the inbound side.
#define LANE_M      3.5
#define ROAD_HALF_M (2 * LANE_M)

static bool add_candidate(rs_simulate__candidates *l, const double R_road[4], double along, double s, double dx,
                          double dy, double h, const char *kind)
{
    if (l->N == l->cap) {
        int cap = l->cap ? 2 * l->cap : 256;
        rs_simulate__candidate *grown = realloc(l->c, sizeof *grown * (size_t)cap);
        if (!grown) return false;
        l->c = grown;
        l->cap = cap;
    }
    // (along, s) along the approach whose outward direction is (dx, dy) in the road frame, with s
    // measured to the left of the outward direction, then the road frame rotated into ENU.
    double x = along * dx - s * dy, y = along * dy + s * dx;
    rs_simulate__candidate *c = &l->c[l->N++];
    c->p_enu_m[0] = rs_simulate__quantize(R_road[0] * x + R_road[1] * y, Q_ENU);
    c->p_enu_m[1] = rs_simulate__quantize(R_road[2] * x + R_road[3] * y, Q_ENU);
    c->p_enu_m[2] = rs_simulate__quantize(h, Q_ENU);
    c->kind = kind;
    return true;
}

// Every surveyable point of the intersection: crosswalk stripe corners, stop-bar ends, lane-mark
// corners on the ground; sign tops and signal pole tops (2 to 6 m) beside the roads.
static rs_status build_intersection(rs_simulate__candidates *l, rs_rng *rng, const double R_road[4], rs_err *err)
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
// a whole site, drawn

void rs_simulate__site_free(rs_simulate__site *s)
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
    rs_simulate__shapes_free(s);
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

// An overhead fisheye's position: 8-11 m up, within 3 m of the junction's centre.
static void overhead_position(rs_rng *rng, double p_enu[3])
{
    const double r = 3.0 * sqrt(rs_rng_uniform(rng)), a = rs_rng_uniform_in(rng, 0, 2 * M_PI);
    p_enu[0] = r * sin(a);
    p_enu[1] = r * cos(a);
    p_enu[2] = rs_rng_uniform_in(rng, 8.0, 11.0);
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

static bool is_elevated(const rs_simulate__candidate *c) { return c->p_enu_m[2] != 0.0; }

// Chooses landmarks so that each camera sees about landmarks_per_camera of them, about
// elevated_fraction of those above the ground (none when it is 0: points picked on a map); a
// landmark seen by several cameras counts once.
static rs_status select_landmarks(rs_simulate__site *s, rs_rng *rng, const rs_simulate_site_options *o, rs_err *err)
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
    const bool ground_only = o->elevated_fraction == 0.0;
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
        // First the elevated ones up to their share, then anything (only those on the ground when
        // the share is 0); in random order, but those that would add to cameras that already have
        // their share last.
        for (int pass = 0; pass < 2; pass++) {
            int n = 0;
            for (int j = 0; j < Nc; j++)
                if (vis[j] && !chosen[j] &&
                    (pass == 1 ? !(ground_only && is_elevated(&s->cand.c[j])) : is_elevated(&s->cand.c[j])))
                    pool[n++] = j;
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

rs_status rs_simulate__site_draw(rs_simulate__site *s, const rs_simulate_site_options *o, rs_err *err)
{
    rs_rng rng;
    rs_rng_seed(&rng, o->seed);
    rs_status st;
    int K = o->Ncameras;
    s->Ncameras = K;

    // The roads: one along the road frame's x axis, one along its y axis, turned by up to 30 deg.
    double theta = rs_rng_uniform_in(&rng, -30.0, 30.0) * RS_RAD_PER_DEG;
    double R_road[4] = {cos(theta), -sin(theta), sin(theta), cos(theta)};
    s->road_azimuth_deg = fmod(90.0 - theta / RS_RAD_PER_DEG + 360.0, 180.0);
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
        rs_simulate__camera *c = &s->cam[k];
        c->cam.width = o->width_px;
        c->cam.height = o->height_px;
        const bool fisheye = o->fisheye != RS_SIMULATE_FISHEYE_NONE;
        if ((st = rs_simulate_lens(&c->cam.lensmodel, &c->cam.intrinsics, &c->cam.Nintrinsics, &rng,
                                   fisheye ? RS_SIMULATE_FISHEYE_LENS : o->lensmodel, o->width_px, o->height_px,
                                   o->hfov_deg, o->fisheye != RS_SIMULATE_FISHEYE_EQUIDISTANT, err)))
            return st;
        if ((st = rs_simulate__camera_field_of_view(c, err))) return rs_err_prefix(err, "camera %d", k + 1);
        // Draw the pole and the aim until the camera sees at least 4 candidates.
        int Nvisible = 0;
        for (int tries = 0; tries < 50 && Nvisible < 4; tries++) {
            double p_cam[3], centre[3] = {0, 0, 0};
            if (fisheye) // on a mast arm over the junction
                overhead_position(&rng, p_cam);
            else
                pole_position(&rng, p_cam, k, R_road);
            double roll = fmax(-3.0, fmin(3.0, rs_rng_normal(&rng)));
            rs_simulate__camera_look_at(c, p_cam, centre, rs_rng_uniform_in(&rng, -10.0, 10.0), roll);
            Nvisible = 0;
            for (int j = 0; j < Nc; j++) {
                bool v =
                    rs_simulate__camera_sees(c, s->q_true_px + 2 * ((size_t)k * Nc + j), s->cand.c[j].p_enu_m, 20.0);
                s->visible[(size_t)k * Nc + j] = v;
                Nvisible += v;
            }
        }
        if (Nvisible < 4)
            return rs_err_set(err, RS_ERR_DEGENERATE, "camera %d: sees %d landmarks of the intersection, needs 4",
                              k + 1, Nvisible);
        double d = hypot(c->p_cam_enu_m[0], c->p_cam_enu_m[1]);
        double az = atan2(c->p_cam_enu_m[0], c->p_cam_enu_m[1]) / RS_RAD_PER_DEG;
        snprintf(s->note[k], sizeof s->note[k], "simulated %s %.1f m %s %.1f m %s of the centre",
                 fisheye ? "overhead fisheye" : "camera on a", c->p_cam_enu_m[2], fisheye ? "up," : "pole", d,
                 compass_name(az));
    }
    if ((st = select_landmarks(s, &rng, o, err))) return st;

    // Picks of the chosen landmarks that each camera sees.
    for (int k = 0; k < K; k++)
        for (int j = 0; j < Nc; j++) {
            size_t kj = (size_t)k * Nc + j;
            if (s->landmark_of[j] < 0 || !s->visible[kj]) continue;
            s->Nobservations++;
            s->Noutliers += rs_simulate__camera_pick(&rng, s->q_px + 2 * kj, s->outlier + kj, s->q_true_px + 2 * kj, 1,
                                                     &s->cam[k], o->pixel_sigma_px, o->outlier_fraction, 30.0);
        }
    for (int k = 0; k < K && o->poles_per_camera == 0 && o->lines_per_camera == 0; k++) {
        int n = 0; // with poles or lines, rs_simulate__shapes_draw checks what all the picks fix
        for (int j = 0; j < Nc; j++) n += s->landmark_of[j] >= 0 && s->visible[(size_t)k * Nc + j];
        if (n < 4) return rs_err_set(err, RS_ERR_DEGENERATE, "camera %d: observes %d landmarks, needs 4", k + 1, n);
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
    rs_simulate__survey_noise(&rng, s->survey_enu_m, p_true, L, o->survey_sigma_h_m, o->survey_sigma_v_m);
    if (o->height_noise_m > 0) {
        // heights as unreliable as raw GNSS: more noise on the landmarks on the ground, from a
        // stream of its own (the rest of the site is the same as without it)
        rs_rng hrng;
        rs_rng_seed(&hrng, rs_rng_seed_derive(o->seed, HEIGHT_NOISE_STREAM));
        for (int i = 0; i < L; i++)
            if (p_true[3 * i + 2] == 0.0) s->survey_enu_m[3 * i + 2] += o->height_noise_m * rs_rng_normal(&hrng);
    }
    free(p_true);
    if ((st = rs_geo_enu_to_llh(s->survey_llh, &o->origin, s->survey_enu_m, L, err)))
        return rs_err_prefix(err, "landmarks");

    // What the owner believes about the lenses, and where the poles are.
    int Ni = s->cam[0].cam.Nintrinsics;
    s->nominal = malloc(sizeof(double) * (size_t)K * Ni);
    if (!s->nominal) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_rng frng; // the per-camera focal errors, from a stream of their own
    rs_rng_seed(&frng, rs_rng_seed_derive(o->seed, FOCAL_ERROR_STREAM));
    for (int k = 0; k < K; k++) {
        double *n = s->nominal + (size_t)k * Ni;
        memcpy(n, s->cam[k].cam.intrinsics, sizeof(double) * Ni);
        double factor = o->focal_error;
        if (o->focal_error_range > 1.0) factor *= pow(o->focal_error_range, rs_rng_uniform_in(&frng, -1.0, 1.0));
        n[0] = rs_simulate__quantize(n[0] * factor, Q_MODEL);
        n[1] = rs_simulate__quantize(n[1] * factor, Q_MODEL);
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
    // poles and lines, from a stream of their own (nothing unless asked for)
    return rs_simulate__shapes_draw(s, o, err);
}

void rs_simulate__landmark_id(char id[16], int i) { snprintf(id, 16, "L%03d", i + 1); }
void rs_simulate__camera_id(char id[16], int k) { snprintf(id, 16, "cam%d", k + 1); }

// ---------------------------------------------------------------------------------------------
// the lanes (docs/site-format.md, "lanes.geojson")
//
// Right-hand traffic. Per approach a (A1..A4, outward directions +x, +y, -x, -y of the road
// frame): inbound lanes in1 (inner, s = 1.75 m) and in2 (outer, s = 5.25 m) from 60 m out to the
// stop bar at 13.5 m, outbound lanes out1/out2 (s = -1.75, -5.25 m) from 13.5 m to 60 m, and the
// junction lanes that join them: straight on from in1/in2 to out1/out2 of the opposite approach,
// left from in1 to out1 of the approach on the left, right from in2 to out2 of the approach on
// the right; each a cubic Bezier between the two lane ends, tangent to both, in 8 pieces.
//
// In order: for each approach a and inbound lane k, the approach lane, then its straight and its
// turning junction lane; then the 8 exit lanes (a, k). So lane (a, k) of kind approach is
// 3 (2a + k - 1), its junction lanes follow it, and exit (a, k) is 24 + 2a + k - 1.

#define LANE_FAR_M     60.0
#define LANE_STOP_M    13.5
#define LANE_SPEED_MPS 13.89 // 50 km/h
#define TURN_SPEED_MPS 8.33  // 30 km/h
enum { NLANES = 32 };

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

static int exit_lane(int a, int k) { return 24 + 2 * a + k - 1; }

// Fills one lane: pts_road (Npts, 2) in the road frame, rotated into ENU, rounded to 0.1 mm, on
// the ground; continuing into the lanes next (Nnext,).
static bool set_lane(rs_lane *lane, const rs_simulate__site *s, const char *id, const char *kind, double speed_mps,
                     const double (*pts_road)[2], int Npts, const int *next, int Nnext)
{
    lane->id = strdup(id);
    lane->kind = strdup(kind);
    lane->p_enu_m = malloc(sizeof *lane->p_enu_m * (size_t)Npts);
    lane->next = malloc(sizeof *lane->next * (size_t)(Nnext ? Nnext : 1));
    if (!lane->id || !lane->kind || !lane->p_enu_m || !lane->next) return false;
    lane->width_m = LANE_M;
    lane->direction = RS_LANE_FORWARD;
    lane->speed_mps = speed_mps;
    lane->Npoints = Npts;
    for (int i = 0; i < Npts; i++) {
        lane->p_enu_m[i][0] =
            rs_simulate__quantize(s->R_road[0] * pts_road[i][0] + s->R_road[1] * pts_road[i][1], Q_ENU);
        lane->p_enu_m[i][1] =
            rs_simulate__quantize(s->R_road[2] * pts_road[i][0] + s->R_road[3] * pts_road[i][1], Q_ENU);
        lane->p_enu_m[i][2] = 0.0;
    }
    for (int i = 0; i < Nnext; i++) lane->next[i] = next[i];
    lane->Nnext = Nnext;
    return true;
}

rs_status rs_simulate__lanes(rs_lanes *lanes, const rs_simulate__site *s, rs_err *err)
{
    lanes->lane = calloc(NLANES, sizeof *lanes->lane);
    lanes->N = lanes->lane ? NLANES : 0;
    bool ok = lanes->lane != NULL;
    for (int a = 0; a < 4 && ok; a++)
        for (int k = 1; k <= 2 && ok; k++) {
            const int in = 3 * (2 * a + k - 1);
            double s_in = LANE_M * (k - 0.5);
            char id[16], nid[48], jid[16];
            double pts[9][2];
            // The manoeuvres of inbound lane k: straight on, then left (k = 1) or right (k = 2).
            int to[2] = {(a + 2) % 4, k == 1 ? (a + 3) % 4 : (a + 1) % 4};
            const char *how[2] = {"straight", k == 1 ? "left" : "right"};
            const int junctions[2] = {in + 1, in + 2};
            lane_id(id, sizeof id, a, true, k);
            approach_point(pts[0], a, LANE_FAR_M, s_in);
            approach_point(pts[1], a, LANE_STOP_M, s_in);
            ok =
                set_lane(&lanes->lane[in], s, id, "approach", LANE_SPEED_MPS, (const double(*)[2])pts, 2, junctions, 2);
            for (int m = 0; m < 2 && ok; m++) {
                // Cubic Bezier from the stop bar of (a, k) to the start of outbound lane k of to[m].
                double p0[2], p3[2], d0[2], d3[2], q[2];
                approach_point(p0, a, LANE_STOP_M, s_in);
                approach_point(p3, to[m], LANE_STOP_M, -s_in);
                approach_point(q, a, LANE_STOP_M - 1.0, s_in);
                d0[0] = q[0] - p0[0], d0[1] = q[1] - p0[1]; // unit inbound direction
                approach_point(q, to[m], LANE_STOP_M + 1.0, -s_in);
                d3[0] = q[0] - p3[0], d3[1] = q[1] - p3[1]; // unit outbound direction
                double L = hypot(p3[0] - p0[0], p3[1] - p0[1]) / 3.0;
                double p1[2] = {p0[0] + L * d0[0], p0[1] + L * d0[1]};
                double p2[2] = {p3[0] - L * d3[0], p3[1] - L * d3[1]};
                for (int i = 0; i <= 8; i++) {
                    double t = i / 8.0, u = 1 - t;
                    for (int c = 0; c < 2; c++)
                        pts[i][c] =
                            u * u * u * p0[c] + 3 * u * u * t * p1[c] + 3 * u * t * t * p2[c] + t * t * t * p3[c];
                }
                lane_id(jid, sizeof jid, to[m], false, k);
                snprintf(nid, sizeof nid, "%s_%s_%s", id, how[m], jid);
                const int out = exit_lane(to[m], k);
                ok = set_lane(&lanes->lane[junctions[m]], s, nid, "junction", m == 0 ? LANE_SPEED_MPS : TURN_SPEED_MPS,
                              (const double(*)[2])pts, 9, &out, 1);
            }
        }
    for (int a = 0; a < 4 && ok; a++)
        for (int k = 1; k <= 2 && ok; k++) {
            char id[16];
            double pts[2][2];
            lane_id(id, sizeof id, a, false, k);
            approach_point(pts[0], a, LANE_STOP_M, -LANE_M * (k - 0.5));
            approach_point(pts[1], a, LANE_FAR_M, -LANE_M * (k - 0.5));
            ok = set_lane(&lanes->lane[exit_lane(a, k)], s, id, "exit", LANE_SPEED_MPS, (const double(*)[2])pts, 2,
                          NULL, 0);
        }
    if (ok) return RS_OK;
    rs_lanes_free(lanes);
    return rs_err_set(err, RS_ERR_NOMEM, "lanes: out of memory");
}

// rs_bench_track.c -- synthetic traffic, simulated cameras, localise + track (rs_bench_track.h).
#include "bench/rs_bench_track.h"

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "core/rs_camera.h"
#include "core/rs_camera_ground.h"
#include "core/rs_pose.h"
#include "core/rs_rng.h"
#include "core/rs_units.h"
#include "eval/track/rs_track.h"

#define HALF_SIDE_M 50.0 // the square of traffic: [-50, 50]^2
#define MATCH_M     5.0  // a reported row matches the nearest true vehicle within this

void rs_bench_track_config_default(rs_bench_track_config *c)
{
    *c = (rs_bench_track_config){.Nvehicles = 50,
                                 .Ncameras = 4,
                                 .fps = 30,
                                 .duration_s = 20,
                                 .pixel_sigma = 1.0,
                                 .p_detect = 0.9,
                                 .accel_sigma_mps2 = 3.0,
                                 .seed = 1};
}

typedef struct {
    bool circle;
    double centre[2], radius_m, phase_rad, omega_radps; // circle
    double start[2], dir[2], speed_mps, t0_s;           // chord: start + speed (t - t0) dir
    long id;                                            // the true vehicle (a re-entry is a new one)
    double left_s; // when its previous vehicle left the square (-inf: none); for scoring, that one
    double prev_start[2], prev_dir[2], prev_speed_mps, prev_t0_s; // drives on, unseen, for 2 s
} vehicle;

static double thread_cpu_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

// A new chord across the square: a point on its border, heading inwards within 60 degrees of
// the inward normal.
static void new_chord(vehicle *v, rs_rng *rng, double t_s, long id)
{
    v->left_s = v->circle || id == 0 ? -INFINITY : t_s;
    memcpy(v->prev_start, v->start, sizeof v->start), memcpy(v->prev_dir, v->dir, sizeof v->dir);
    v->prev_speed_mps = v->speed_mps, v->prev_t0_s = v->t0_s;
    const int side = (int)(4 * rs_rng_uniform(rng));
    const double s = rs_rng_uniform_in(rng, -0.8, 0.8) * HALF_SIDE_M;
    const double inward[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
    const double a = rs_rng_uniform_in(rng, -60, 60) * RS_RAD_PER_DEG;
    const double *nrm = inward[side];
    v->circle = false;
    v->start[0] = nrm[0] ? -nrm[0] * HALF_SIDE_M : s;
    v->start[1] = nrm[1] ? -nrm[1] * HALF_SIDE_M : s;
    v->dir[0] = nrm[0] * cos(a) - nrm[1] * sin(a);
    v->dir[1] = nrm[0] * sin(a) + nrm[1] * cos(a);
    v->speed_mps = rs_rng_uniform_in(rng, 5, 15);
    v->t0_s = t_s;
    v->id = id;
}

static void position(double p[2], const vehicle *v, double t_s)
{
    if (v->circle) {
        const double a = v->phase_rad + v->omega_radps * t_s;
        p[0] = v->centre[0] + v->radius_m * cos(a), p[1] = v->centre[1] + v->radius_m * sin(a);
    } else {
        const double s = v->speed_mps * (t_s - v->t0_s);
        p[0] = v->start[0] + s * v->dir[0], p[1] = v->start[1] + s * v->dir[1];
    }
}

// Localises pixel q as `roadside localise` does (core/rs_camera_ground.h: the ground point and
// its covariance, here from the pixel noise alone: the simulated poses are exact); false when the
// ray misses the plane u = 0.
static bool localise(rs_localise_row *d, const rs_camera *cam, const double q[2], double pixel_sigma)
{
    static const double up[3] = {0, 0, 1};
    const double s2 = pixel_sigma * pixel_sigma, cov_q[4] = {s2, 0, 0, s2};
    double p[3], C[4];
    if (rs_camera_ground_locate(p, C, cam, NULL, q, cov_q, up, 0, NULL) != RS_OK) return false;
    d->e_m = p[0], d->n_m = p[1], d->u_m = 0;
    d->u_px = q[0], d->v_px = q[1];
    d->sigma_e_m = sqrt(C[0]), d->sigma_n_m = sqrt(C[3]), d->cov_en_m2 = C[1];
    return true;
}

static rs_status make_cameras(rs_camera *cams, int N, rs_err *err)
{
    const mrcal_lensmodel_t pinhole = {.type = MRCAL_LENSMODEL_PINHOLE};
    const double intrinsics[4] = {1371, 1371, 959.5, 539.5};
    const double distance_m = 150, height_m = 30;
    for (int c = 0; c < N; c++) {
        rs_status st = rs_camera_init(&cams[c], &pinhole, intrinsics, 1920, 1080, err);
        if (st) return st;
        const double az = 360.0 * c / N + 45; // the camera's bearing from the origin
        const double pos[3] = {distance_m * sin(az * RS_RAD_PER_DEG), distance_m * cos(az * RS_RAD_PER_DEG), height_m};
        const double ypr[3] = {fmod(az + 180, 360), -atan2(height_m, distance_m) * RS_DEG_PER_RAD, 0};
        rs_pose_rt_from_ypr(cams[c].rt_cam_enu, ypr, pos);
    }
    return RS_OK;
}

static rs_status check_config(const rs_bench_track_config *c, rs_err *err)
{
    if (c->Nvehicles < 1 || c->Nvehicles > 100000) return rs_err_set(err, RS_ERR_USAGE, "vehicles: 1..100000");
    if (c->Ncameras < 1 || c->Ncameras > 8) return rs_err_set(err, RS_ERR_USAGE, "cameras: 1..8");
    if (!(c->fps > 0 && c->fps <= 1000)) return rs_err_set(err, RS_ERR_USAGE, "fps: (0, 1000]");
    if (!(c->duration_s > 0 && c->duration_s <= 36000)) return rs_err_set(err, RS_ERR_USAGE, "duration: (0, 36000] s");
    if (!(c->pixel_sigma > 0 && c->pixel_sigma <= 100)) return rs_err_set(err, RS_ERR_USAGE, "pixel sigma: (0, 100]");
    if (!(c->p_detect > 0 && c->p_detect <= 1)) return rs_err_set(err, RS_ERR_USAGE, "detection probability: (0, 1]");
    return RS_OK;
}

typedef struct {
    double se2, pred2; // sums of squared errors and of predicted variances
    long n;
} error_sum;

// The reported rows of this step against the truth at time t_s (positions truth (Nv, 2): the
// vehicles, then those that left the square less than 2 s ago, unseen but still driving).
static void score_rows(rs_bench_track_figures *f, error_sum *e, const rs_track_row *rows, size_t Nrows,
                       const double *truth, int Nv)
{
    for (size_t k = 0; k < Nrows; k++) {
        double best = INFINITY;
        for (int v = 0; v < Nv; v++) {
            const double de = rows[k].e_m - truth[2 * v], dn = rows[k].n_m - truth[2 * v + 1];
            if (de * de + dn * dn < best) best = de * de + dn * dn;
        }
        f->rows++;
        if (best > MATCH_M * MATCH_M) {
            f->rows_unmatched++;
            continue;
        }
        e->se2 += best;
        e->pred2 += rows[k].sigma_e_m * rows[k].sigma_e_m + rows[k].sigma_n_m * rows[k].sigma_n_m;
        e->n++;
    }
}

rs_status rs_bench_track_run(rs_bench_track_figures *f, const rs_bench_track_config *c, rs_err *err)
{
    *f = (rs_bench_track_figures){0};
    rs_status st = check_config(c, err);
    if (st) return st;
    rs_rng rng;
    rs_rng_seed(&rng, c->seed);
    rs_camera cams[8] = {0};
    vehicle *veh = malloc(sizeof(vehicle) * (size_t)c->Nvehicles);
    double *truth = malloc(sizeof(double) * 4 * (size_t)c->Nvehicles); // vehicles, then those gone
    const size_t cap = (size_t)c->Nvehicles * (size_t)c->Ncameras;
    rs_localise_row *dets = malloc(sizeof(rs_localise_row) * cap);
    int *vehicle_of = malloc(sizeof(int) * cap), *camera_of = malloc(sizeof(int) * cap);
    rs_track_tracker *tracker = NULL;
    if (!veh || !truth || !dets || !vehicle_of || !camera_of) {
        st = rs_err_set(err, RS_ERR_NOMEM, "bench track: out of memory");
        goto done;
    }
    rs_track_options topt;
    rs_track_options_default(&topt);
    topt.accel_sigma_mps2 = c->accel_sigma_mps2;
    if ((st = make_cameras(cams, c->Ncameras, err)) || (st = rs_track_tracker_new(&tracker, &topt, err))) goto done;
    long next_id = 0;
    for (int v = 0; v < c->Nvehicles; v++) {
        if (v % 2 == 0) {
            vehicle *w = &veh[v];
            w->circle = true;
            w->radius_m = rs_rng_uniform_in(&rng, 10, 45);
            const double room = HALF_SIDE_M - w->radius_m - 2;
            w->centre[0] = rs_rng_uniform_in(&rng, -room, room), w->centre[1] = rs_rng_uniform_in(&rng, -room, room);
            w->phase_rad = rs_rng_uniform_in(&rng, 0, 2 * M_PI);
            // speed 5..15 m/s, at most what a lateral acceleration of 2.5 m/s^2 allows on the circle
            const double speed = fmin(rs_rng_uniform_in(&rng, 5, 15), sqrt(2.5 * w->radius_m));
            w->omega_radps = speed / w->radius_m * (rs_rng_uniform(&rng) < 0.5 ? -1 : 1);
            w->id = next_id++;
        } else {
            veh[v] = (vehicle){.circle = true};
            new_chord(&veh[v], &rng, 0, next_id++);
            veh[v].left_s = -INFINITY;
            // spread the chords' vehicles along their way at the start
            const double back = rs_rng_uniform_in(&rng, 0, 80) / veh[v].speed_mps;
            veh[v].t0_s -= back;
        }
    }
    const long Nframes = (long)floor(c->duration_s * c->fps);
    error_sum rows_err = {0}, det_err = {0};
    for (long frame = 0; frame < Nframes; frame++) {
        const double t_s = (double)frame / c->fps;
        for (int v = 0; v < c->Nvehicles; v++) {
            position(&truth[2 * v], &veh[v], t_s);
            if (fabs(truth[2 * v]) > HALF_SIDE_M + 1e-9 || fabs(truth[2 * v + 1]) > HALF_SIDE_M + 1e-9) {
                new_chord(&veh[v], &rng, t_s, next_id++);
                position(&truth[2 * v], &veh[v], t_s);
            }
        }
        // the pixels (simulation, not timed), then localising (timed)
        int N = 0;
        double q[2];
        for (int cam = 0; cam < c->Ncameras; cam++)
            for (int v = 0; v < c->Nvehicles; v++) {
                const double p[3] = {truth[2 * v], truth[2 * v + 1], 0};
                if (!rs_camera_project_visible(q, &cams[cam], rs_camera_max_tan(&cams[cam]), p)) continue;
                if (q[0] < -0.5 || q[0] > 1919.5 || q[1] < -0.5 || q[1] > 1079.5) continue;
                if (rs_rng_uniform(&rng) >= c->p_detect) continue;
                rs_localise_row *d = &dets[N];
                *d = (rs_localise_row){.image_id = frame * c->Ncameras + cam,
                                       .frame = frame,
                                       .time_s = t_s,
                                       .category_id = 1,
                                       .score = 1,
                                       .lat_deg = NAN,
                                       .lon_deg = NAN};
                snprintf(d->camera, sizeof d->camera, "cam%d", cam + 1);
                d->u_px = q[0] + c->pixel_sigma * rs_rng_normal(&rng);
                d->v_px = q[1] + c->pixel_sigma * rs_rng_normal(&rng);
                vehicle_of[N] = v, camera_of[N] = cam;
                N++;
            }
        const double t0 = thread_cpu_s();
        int Nloc = 0;
        for (int k = 0; k < N; k++) {
            const double qk[2] = {dets[k].u_px, dets[k].v_px};
            if (k != Nloc) dets[Nloc] = dets[k];
            if (localise(&dets[Nloc], &cams[camera_of[k]], qk, c->pixel_sigma))
                vehicle_of[Nloc] = vehicle_of[k], Nloc++;
        }
        const double t1 = thread_cpu_s();
        st = rs_track_tracker_step(tracker, t_s, dets, Nloc, err);
        const double t2 = thread_cpu_s();
        if (st) goto done;
        f->localise_cpu_s += t1 - t0;
        f->track_cpu_s += t2 - t1;
        f->detections += Nloc;
        for (int k = 0; k < Nloc; k++) {
            const double de = dets[k].e_m - truth[2 * vehicle_of[k]], dn = dets[k].n_m - truth[2 * vehicle_of[k] + 1];
            det_err.se2 += de * de + dn * dn;
            det_err.pred2 += dets[k].sigma_e_m * dets[k].sigma_e_m + dets[k].sigma_n_m * dets[k].sigma_n_m;
            det_err.n++;
        }
        size_t Nrows;
        const rs_track_row *rows = rs_track_tracker_rows(tracker, &Nrows);
        int Ntruth = c->Nvehicles;
        for (int v = 0; v < c->Nvehicles; v++)
            if (t_s - veh[v].left_s < 2.0) {
                const double s_m = veh[v].prev_speed_mps * (t_s - veh[v].prev_t0_s);
                truth[2 * Ntruth] = veh[v].prev_start[0] + s_m * veh[v].prev_dir[0];
                truth[2 * Ntruth + 1] = veh[v].prev_start[1] + s_m * veh[v].prev_dir[1];
                Ntruth++;
            }
        score_rows(f, &rows_err, rows, Nrows, truth, Ntruth);
        rs_track_tracker_clear_rows(tracker);
    }
    f->frames = Nframes;
    f->detections_per_frame = Nframes ? (double)f->detections / (double)Nframes / c->Ncameras : 0;
    f->realtime_factor = c->duration_s / (f->localise_cpu_s + f->track_cpu_s);
    f->track_realtime_factor = c->duration_s / f->track_cpu_s;
    f->vehicles = next_id;
    rs_track_tracker_counts(tracker, &f->confirmed, &f->merged);
    f->rmse_m = rows_err.n ? sqrt(rows_err.se2 / rows_err.n) : NAN;
    f->predicted_rmse_m = rows_err.n ? sqrt(rows_err.pred2 / rows_err.n) : NAN;
    f->det_rmse_m = det_err.n ? sqrt(det_err.se2 / det_err.n) : NAN;
    f->det_predicted_rmse_m = det_err.n ? sqrt(det_err.pred2 / det_err.n) : NAN;
done:
    for (int k = 0; k < 8; k++) rs_camera_free(&cams[k]);
    rs_track_tracker_free(tracker);
    free(veh), free(truth), free(dets), free(vehicle_of), free(camera_of);
    return st;
}

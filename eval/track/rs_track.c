// rs_track.c -- the multi-camera tracker: steps, association, birth, death, merge (rs_track.h).
#include "eval/track/rs_track.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_assign.h"
#include "eval/track/rs_track_kf.h"

#define MAX_CLASSES 8 // distinct category ids counted per track (more are not voted)

typedef struct {
    double x[4], P[16];
    double t_s; // the time x, P refer to
    double birth_s, last_update_s, u_m;
    int id;                // 0 while tentative
    int steps;             // opportunities since birth, the birth step included (rs_track.h)
    uint64_t seen_cameras; // cameras that have ever updated it
    int hits;              // steps with an update
    int detections;
    uint64_t step_cameras; // cameras that updated it at the current step
    int class_id[MAX_CLASSES], class_n[MAX_CLASSES], Nclasses;
} track;

struct rs_track_tracker {
    rs_track_options opt;
    double gate_mahal2;
    double last_time_s;
    bool started;
    track *tracks;
    int Ntracks;
    size_t cap_tracks;
    rs_track_row *rows;
    size_t Nrows, cap_rows;
    char cameras[RS_TRACK_MAX_CAMERAS][RS_TRACK_CAMERA_BYTES];
    int Ncameras;
    int rank[RS_TRACK_MAX_CAMERAS]; // each camera's place in the ids' byte order (strcmp)
    int Nconfirmed, Nmerged;
    // scratch, grown as needed
    double *cost;
    size_t cap_cost;
    int *col_of_row, *order, *cam_of_det;
    size_t cap_col, cap_order, cap_cam;
};

void rs_track_options_default(rs_track_options *opt)
{
    *opt = (rs_track_options){.accel_sigma_mps2 = 3.0,
                              .gate_p = 0.999,
                              .max_age_s = 1.0,
                              .min_hits = 3,
                              .hit_window = 4,
                              .init_speed_sigma_mps = 15.0,
                              .coast_s = 0.3,
                              .merge_pos_mahal2 = 9.21,
                              .merge_vel_mahal2 = 9.21,
                              .birth_exclusion_mahal2 = 27.63};
}

rs_status rs_track_options_check(const rs_track_options *o, rs_err *err)
{
    if (!(o->accel_sigma_mps2 >= 0) || !isfinite(o->accel_sigma_mps2))
        return rs_err_set(err, RS_ERR_USAGE, "accel-sigma: %g is not a finite number >= 0", o->accel_sigma_mps2);
    if (!(o->gate_p > 0 && o->gate_p < 1))
        return rs_err_set(err, RS_ERR_USAGE, "gate: %g is not a probability in (0, 1)", o->gate_p);
    if (!(o->max_age_s >= 0) || !isfinite(o->max_age_s))
        return rs_err_set(err, RS_ERR_USAGE, "max-age: %g is not a finite number of seconds >= 0", o->max_age_s);
    if (o->min_hits < 1 || o->hit_window < o->min_hits || o->hit_window > 1000)
        return rs_err_set(err, RS_ERR_USAGE, "min-hits: %d of %d: need 1 <= M <= N <= 1000", o->min_hits,
                          o->hit_window);
    if (!(o->init_speed_sigma_mps > 0) || !isfinite(o->init_speed_sigma_mps))
        return rs_err_set(err, RS_ERR_USAGE, "init-speed-sigma: %g is not a finite number > 0",
                          o->init_speed_sigma_mps);
    if (!(o->coast_s >= 0) || !isfinite(o->coast_s))
        return rs_err_set(err, RS_ERR_USAGE, "coast: %g is not a finite number of seconds >= 0", o->coast_s);
    if (!(o->merge_pos_mahal2 >= 0) || !(o->merge_vel_mahal2 >= 0) || !(o->birth_exclusion_mahal2 >= 0))
        return rs_err_set(err, RS_ERR_USAGE, "merge and birth-exclusion thresholds must be >= 0");
    return RS_OK;
}

rs_status rs_track_tracker_new(rs_track_tracker **out, const rs_track_options *opt, rs_err *err)
{
    *out = NULL;
    rs_track_options o;
    if (opt)
        o = *opt;
    else
        rs_track_options_default(&o);
    rs_status st = rs_track_options_check(&o, err);
    if (st) return st;
    rs_track_tracker *t = calloc(1, sizeof *t);
    if (!t) return rs_err_set(err, RS_ERR_NOMEM, "tracker: out of memory");
    t->opt = o;
    t->gate_mahal2 = -2.0 * log1p(-o.gate_p); // chi-square 2 dof: P(X <= g) = 1 - exp(-g/2)
    *out = t;
    return RS_OK;
}

void rs_track_tracker_free(rs_track_tracker *t)
{
    if (!t) return;
    free(t->tracks);
    free(t->rows);
    free(t->cost);
    free(t->col_of_row);
    free(t->order);
    free(t->cam_of_det);
    free(t);
}

const rs_track_row *rs_track_tracker_rows(const rs_track_tracker *t, size_t *Nrows)
{
    *Nrows = t->Nrows;
    return t->rows;
}

void rs_track_tracker_clear_rows(rs_track_tracker *t) { t->Nrows = 0; }

const char *rs_track_tracker_camera(const rs_track_tracker *t, int k, int *Ncameras)
{
    if (Ncameras) *Ncameras = t->Ncameras;
    return k >= 0 && k < t->Ncameras ? t->cameras[k] : NULL;
}

int rs_track_tracker_camera_rank(const rs_track_tracker *t, int k)
{
    return k >= 0 && k < t->Ncameras ? t->rank[k] : -1;
}

void rs_track_tracker_counts(const rs_track_tracker *t, int *Nconfirmed, int *Nmerged)
{
    if (Nconfirmed) *Nconfirmed = t->Nconfirmed;
    if (Nmerged) *Nmerged = t->Nmerged;
}

// Grows *p (elements of size sz) to hold at least n; false when out of memory.
static bool grow(void **p, size_t *cap, size_t n, size_t sz)
{
    if (n <= *cap) return true;
    size_t c = *cap ? *cap : 16;
    while (c < n) c *= 2;
    void *q = realloc(*p, c * sz);
    if (!q) return false;
    *p = q;
    *cap = c;
    return true;
}

static rs_status camera_index(int *k, rs_track_tracker *t, const char *camera, rs_err *err)
{
    for (int i = 0; i < t->Ncameras; i++)
        if (!strcmp(t->cameras[i], camera)) return *k = i, RS_OK;
    if (t->Ncameras == RS_TRACK_MAX_CAMERAS)
        return rs_err_set(err, RS_ERR_UNSUPPORTED, "camera '%s': more than %d cameras in one run", camera,
                          RS_TRACK_MAX_CAMERAS);
    snprintf(t->cameras[t->Ncameras], RS_TRACK_CAMERA_BYTES, "%s", camera);
    *k = t->Ncameras++;
    for (int i = 0; i < t->Ncameras; i++) { // the ranks anew (64 cameras at the most)
        t->rank[i] = 0;
        for (int j = 0; j < t->Ncameras; j++) t->rank[i] += strcmp(t->cameras[j], t->cameras[i]) < 0;
    }
    return RS_OK;
}

// The camera whose id comes r-th in byte order.
static int camera_of_rank(const rs_track_tracker *t, int r)
{
    for (int k = 0; k < t->Ncameras; k++)
        if (t->rank[k] == r) return k;
    return 0; // not reached: ranks are a permutation
}

// Whether detection d's position and covariance are usable; RS_ERR_INVALID naming the field
// otherwise, the message prefixed "PATH:LINE: " (path may be NULL: "line LINE: ").
static rs_status check_position(const rs_localise_row *d, const char *path, rs_err *err)
{
    char where[512];
    if (path)
        snprintf(where, sizeof where, "%s:%d", path, d->line);
    else
        snprintf(where, sizeof where, "line %d", d->line);
    if (!isfinite(d->e_m) || !isfinite(d->n_m))
        return rs_err_set(err, RS_ERR_INVALID, "%s: e_m, n_m: not finite", where);
    const double see = d->sigma_e_m * d->sigma_e_m, snn = d->sigma_n_m * d->sigma_n_m, c = d->cov_en_m2;
    if (!(d->sigma_e_m > 0) || !(d->sigma_n_m > 0) || !isfinite(see) || !isfinite(snn) || !isfinite(c) ||
        !(see * snn - c * c > 0))
        return rs_err_set(err, RS_ERR_INVALID,
                          "%s: sigma_e_m, sigma_n_m, cov_en_m2: (%g, %g, %g) is not a positive definite covariance "
                          "(sigmas > 0, |cov| < sigma_e sigma_n)",
                          where, d->sigma_e_m, d->sigma_n_m, d->cov_en_m2);
    return RS_OK;
}

rs_status rs_track_check_located(const rs_localise_row *rows, size_t N, const char *path, rs_err *err)
{
    for (size_t k = 0; k < N; k++) {
        const rs_localise_row *d = &rows[k];
        if (!isfinite(d->time_s))
            return rs_err_set(err, RS_ERR_INVALID, "%s:%d: time_s: empty (tracking needs each detection's time)", path,
                              d->line);
        if (d->category_id < INT_MIN || d->category_id > INT_MAX)
            return rs_err_set(err, RS_ERR_INVALID, "%s:%d: category_id: %lld is out of range", path, d->line,
                              d->category_id);
        rs_status st = check_position(d, path, err);
        if (st) return st;
    }
    return RS_OK;
}

// The detection's measurement z and covariance R; RS_ERR_INVALID when not usable.
static rs_status measurement(double z[2], double R[4], const rs_localise_row *d, rs_err *err)
{
    z[0] = d->e_m, z[1] = d->n_m;
    R[0] = d->sigma_e_m * d->sigma_e_m, R[3] = d->sigma_n_m * d->sigma_n_m, R[1] = R[2] = d->cov_en_m2;
    return check_position(d, NULL, err);
}

static void vote(track *tr, int category_id)
{
    for (int k = 0; k < tr->Nclasses; k++)
        if (tr->class_id[k] == category_id) {
            tr->class_n[k]++;
            return;
        }
    if (tr->Nclasses < MAX_CLASSES) tr->class_id[tr->Nclasses] = category_id, tr->class_n[tr->Nclasses++] = 1;
}

static int majority(const track *tr)
{
    int best = 0, n = 0;
    for (int k = 0; k < tr->Nclasses; k++)
        if (tr->class_n[k] > n || (tr->class_n[k] == n && tr->class_id[k] < best))
            best = tr->class_id[k], n = tr->class_n[k];
    return best;
}

static void take(track *tr, const rs_localise_row *d, int cam, double time_s)
{
    tr->detections++;
    tr->step_cameras |= (uint64_t)1 << cam;
    tr->last_update_s = time_s;
    tr->u_m = isfinite(d->u_m) ? d->u_m : 0;
    vote(tr, (int)d->category_id); // within an int: rs_track_check_located
}

// The detections idx (Nidx,) of one camera against every track: gate, assign, update, births.
static rs_status camera_batch(rs_track_tracker *t, const rs_localise_row *dets, const int *idx, int Nidx, int cam,
                              double time_s, rs_err *err)
{
    const int T = t->Ntracks;
    if (!grow((void **)&t->cost, &t->cap_cost, (size_t)T * (size_t)Nidx + 1, sizeof(double)) ||
        !grow((void **)&t->col_of_row, &t->cap_col, (size_t)T + 1, sizeof(int)))
        return rs_err_set(err, RS_ERR_NOMEM, "tracker: out of memory");
    double z[2], R[4];
    for (int j = 0; j < Nidx; j++) {
        rs_status st = measurement(z, R, &dets[idx[j]], err);
        if (st) return st;
        for (int i = 0; i < T; i++) {
            const double d2 = rs_track_kf_mahal2(t->tracks[i].x, t->tracks[i].P, z, R);
            t->cost[(size_t)i * (size_t)Nidx + (size_t)j] = d2 <= t->gate_mahal2 ? d2 : INFINITY;
        }
    }
    bool *taken = calloc((size_t)Nidx + 1, sizeof(bool));
    if (!taken) return rs_err_set(err, RS_ERR_NOMEM, "tracker: out of memory");
    rs_status st = rs_assign(t->col_of_row, NULL, NULL, NULL, t->cost, T, Nidx, t->gate_mahal2, err);
    for (int i = 0; i < T && st == RS_OK; i++) {
        const int j = t->col_of_row[i];
        if (j < 0) continue;
        taken[j] = true; // taken even when the update fails: no birth from it either
        const rs_localise_row *d = &dets[idx[j]];
        measurement(z, R, d, NULL);
        if (rs_track_kf_update(t->tracks[i].x, t->tracks[i].P, z, R)) take(&t->tracks[i], d, cam, time_s);
    }
    for (int j = 0; j < Nidx && st == RS_OK; j++) {
        if (taken[j]) continue;
        // no birth next to an existing track: an outlier of it, or a detector's second box on it;
        // but a track that took another of this camera's detections is another vehicle (a camera
        // sees a vehicle once), however close: a queue of cars seen from afar
        const rs_localise_row *dj = &dets[idx[j]];
        measurement(z, R, dj, NULL);
        bool near = false;
        for (int i = 0; i < T && !near; i++)
            near = t->col_of_row[i] < 0 &&
                   rs_track_kf_mahal2(t->tracks[i].x, t->tracks[i].P, z, R) < t->opt.birth_exclusion_mahal2;
        if (near) continue;
        if (!grow((void **)&t->tracks, &t->cap_tracks, (size_t)t->Ntracks + 1, sizeof(track))) {
            st = rs_err_set(err, RS_ERR_NOMEM, "tracker: out of memory");
            break;
        }
        const rs_localise_row *d = &dets[idx[j]];
        track *tr = &t->tracks[t->Ntracks++];
        memset(tr, 0, sizeof *tr);
        measurement(z, R, d, NULL);
        rs_track_kf_init(tr->x, tr->P, z, R, t->opt.init_speed_sigma_mps);
        tr->t_s = tr->birth_s = time_s;
        take(tr, d, cam, time_s);
    }
    free(taken);
    return st;
}

// The squared Mahalanobis distance of a - b with covariance Pa + Pb over the state components
// (k, k + 1): positions k = 0, velocities k = 2.
static double pair_mahal2(const track *a, const track *b, int k)
{
    const double d0 = a->x[k] - b->x[k], d1 = a->x[k + 1] - b->x[k + 1];
    const double s00 = a->P[k * 4 + k] + b->P[k * 4 + k], s11 = a->P[(k + 1) * 4 + k + 1] + b->P[(k + 1) * 4 + k + 1];
    const double s01 =
        0.5 * (a->P[k * 4 + k + 1] + a->P[(k + 1) * 4 + k] + b->P[k * 4 + k + 1] + b->P[(k + 1) * 4 + k]);
    const double det = s00 * s11 - s01 * s01;
    if (!(det > 0)) return INFINITY;
    return (d0 * d0 * s11 - 2 * d0 * d1 * s01 + d1 * d1 * s00) / det;
}

// True when track a is to be kept over b: more detections, then the older.
static bool keeps(const track *a, const track *b)
{
    if (a->detections != b->detections) return a->detections > b->detections;
    if (a->birth_s != b->birth_s) return a->birth_s < b->birth_s;
    return (a->id ? a->id : 1 << 30) <= (b->id ? b->id : 1 << 30);
}

// Drops the tracks (confirmed or tentative) not updated for more than max_age_s before time_s
// (before a step's association: a track dead by then takes no detection).
static void drop_dead(rs_track_tracker *t, double time_s)
{
    int n = 0;
    for (int i = 0; i < t->Ntracks; i++)
        if (time_s - t->tracks[i].last_update_s <= t->opt.max_age_s) t->tracks[n++] = t->tracks[i];
    t->Ntracks = n;
}

// Drops tracks on the same vehicle as another (rs_track.h), then the dead and the hopeless.
static void prune(rs_track_tracker *t, double time_s)
{
    bool *drop = calloc((size_t)t->Ntracks + 1, sizeof(bool));
    for (int a = 0; drop && a < t->Ntracks; a++)
        for (int b = a + 1; b < t->Ntracks && !drop[a]; b++) {
            if (drop[b]) continue;
            const track *ta = &t->tracks[a], *tb = &t->tracks[b];
            if (pair_mahal2(ta, tb, 0) >= t->opt.merge_pos_mahal2 || pair_mahal2(ta, tb, 2) >= t->opt.merge_vel_mahal2)
                continue;
            const int loser = keeps(ta, tb) ? b : a;
            drop[loser] = true;
            t->Nmerged++;
        }
    int n = 0;
    for (int i = 0; i < t->Ntracks; i++) {
        const track *tr = &t->tracks[i];
        bool dead = drop && drop[i];
        if (tr->id) // confirmed: dies without updates
            dead = dead || time_s - tr->last_update_s > t->opt.max_age_s;
        else // tentative: dies when M of the first N opportunities is out of reach
            dead = dead || tr->hits + (t->opt.hit_window - tr->steps) < t->opt.min_hits;
        if (!dead) t->tracks[n++] = *tr;
    }
    t->Ntracks = n;
    free(drop);
}

static int cmp_int_pair(const void *a, const void *b)
{
    const int *x = a, *y = b; // (camera, index)
    if (x[0] != y[0]) return x[0] < y[0] ? -1 : 1;
    return (x[1] > y[1]) - (x[1] < y[1]);
}

static int cmp_row_id(const void *a, const void *b)
{
    const rs_track_row *x = a, *y = b;
    return (x->track_id > y->track_id) - (x->track_id < y->track_id);
}

static rs_status report(rs_track_tracker *t, double time_s, rs_err *err)
{
    const size_t first = t->Nrows;
    for (int i = 0; i < t->Ntracks; i++) {
        track *tr = &t->tracks[i];
        if (!tr->id && tr->hits >= t->opt.min_hits) tr->id = ++t->Nconfirmed;
        if (!tr->id || time_s - tr->last_update_s > t->opt.coast_s) continue;
        if (!grow((void **)&t->rows, &t->cap_rows, t->Nrows + 1, sizeof(rs_track_row)))
            return rs_err_set(err, RS_ERR_NOMEM, "tracker: out of memory (%zu rows)", t->Nrows);
        rs_track_row *r = &t->rows[t->Nrows++];
        *r = (rs_track_row){.time_s = time_s,
                            .track_id = tr->id,
                            .e_m = tr->x[0],
                            .n_m = tr->x[1],
                            .u_m = tr->u_m,
                            .sigma_e_m = sqrt(tr->P[0]),
                            .sigma_n_m = sqrt(tr->P[5]),
                            .cov_en_m2 = 0.5 * (tr->P[1] + tr->P[4]),
                            .age_s = time_s - tr->birth_s,
                            .detections = tr->detections,
                            .camera_mask = tr->step_cameras,
                            .category_id = majority(tr)};
        rs_track_kf_speed_heading(&r->speed_mps, &r->heading_deg, &r->sigma_speed_mps, &r->sigma_heading_deg, tr->x,
                                  tr->P);
    }
    if (t->Nrows > first) qsort(t->rows + first, t->Nrows - first, sizeof(rs_track_row), cmp_row_id);
    return RS_OK;
}

rs_status rs_track_tracker_step(rs_track_tracker *t, double time_s, const rs_localise_row *dets, int N, rs_err *err)
{
    if (!isfinite(time_s)) return rs_err_set(err, RS_ERR_INVALID, "time_s: %g is not finite", time_s);
    if (t->started && time_s < t->last_time_s)
        return rs_err_set(err, RS_ERR_INVALID, "time_s: %.9g is before the previous step's %.9g", time_s,
                          t->last_time_s);
    t->started = true;
    t->last_time_s = time_s;
    drop_dead(t, time_s);
    for (int i = 0; i < t->Ntracks; i++) {
        track *tr = &t->tracks[i];
        rs_track_kf_predict(tr->x, tr->P, time_s - tr->t_s, t->opt.accel_sigma_mps2);
        tr->t_s = time_s;
        tr->step_cameras = 0;
    }
    const int T0 = t->Ntracks; // tracks born at this step count their birth step themselves
    // (camera, index) pairs sorted: each camera's batch in input order
    if (!grow((void **)&t->order, &t->cap_order, 2 * (size_t)N + 2, sizeof(int)) ||
        !grow((void **)&t->cam_of_det, &t->cap_cam, (size_t)N + 1, sizeof(int)))
        return rs_err_set(err, RS_ERR_NOMEM, "tracker: out of memory");
    rs_status st = RS_OK;
    for (int j = 0; j < N; j++) {
        if ((st = camera_index(&t->order[2 * j], t, dets[j].camera, err))) return st;
        t->order[2 * j + 1] = j;
    }
    // batches in the order of the camera ids, whatever the input's (ranks once all are known)
    for (int j = 0; j < N; j++) t->order[2 * j] = t->rank[t->order[2 * j]];
    qsort(t->order, (size_t)N, 2 * sizeof(int), cmp_int_pair);
    uint64_t step_mask = 0; // the cameras that delivered detections at this step
    for (int j = 0; j < N; j++) {
        t->cam_of_det[j] = t->order[2 * j + 1]; // detection indices, by camera
        step_mask |= (uint64_t)1 << camera_of_rank(t, t->order[2 * j]);
    }
    for (int a = 0; a < N;) {
        int b = a;
        while (b < N && t->order[2 * b] == t->order[2 * a]) b++;
        const int cam = camera_of_rank(t, t->order[2 * a]);
        if ((st = camera_batch(t, dets, t->cam_of_det + a, b - a, cam, time_s, err))) return st;
        a = b;
    }
    for (int i = 0; i < t->Ntracks; i++) {
        track *tr = &t->tracks[i];
        if (i >= T0)
            tr->steps = 1; // born at this step
        else if ((tr->seen_cameras | tr->step_cameras) & step_mask)
            tr->steps++; // one of its cameras delivered: an opportunity, taken or missed
        if (tr->step_cameras) tr->hits++;
        tr->seen_cameras |= tr->step_cameras;
    }
    prune(t, time_s);
    return report(t, time_s, err);
}

typedef struct {
    double time_s;
    size_t i;
} timed;

static int cmp_time(const void *a, const void *b)
{
    const timed *x = a, *y = b;
    if (x->time_s != y->time_s) return x->time_s < y->time_s ? -1 : 1;
    return (x->i > y->i) - (x->i < y->i);
}

rs_status rs_track_run(rs_track_tracker **out, const rs_localise_row *dets, size_t N, const rs_track_options *opt,
                       rs_err *err)
{
    *out = NULL;
    for (size_t k = 0; k < N; k++)
        if (!isfinite(dets[k].time_s))
            return rs_err_set(err, RS_ERR_INVALID, "line %d: time_s: missing (tracking needs each detection's time)",
                              dets[k].line);
    rs_track_tracker *t = NULL;
    rs_status st = rs_track_tracker_new(&t, opt, err);
    if (st) return st;
    timed *idx = malloc(sizeof(timed) * (N + 1));
    rs_localise_row *step = malloc(sizeof(rs_localise_row) * (N + 1));
    if (!idx || !step) {
        free(idx), free(step), rs_track_tracker_free(t);
        return rs_err_set(err, RS_ERR_NOMEM, "tracker: out of memory (%zu detections)", N);
    }
    for (size_t k = 0; k < N; k++) idx[k] = (timed){dets[k].time_s, k};
    qsort(idx, N, sizeof(timed), cmp_time); // stable by the index tie-break
    for (size_t a = 0; a < N && st == RS_OK;) {
        size_t b = a;
        while (b < N && idx[b].time_s == idx[a].time_s) step[b - a] = dets[idx[b].i], b++;
        if (b - a > (size_t)1 << 30)
            st = rs_err_set(err, RS_ERR_UNSUPPORTED, "more than 2^30 detections at one time");
        else
            st = rs_track_tracker_step(t, idx[a].time_s, step, (int)(b - a), err);
        a = b;
    }
    free(idx), free(step);
    if (st) {
        rs_track_tracker_free(t);
        return st;
    }
    *out = t;
    return RS_OK;
}

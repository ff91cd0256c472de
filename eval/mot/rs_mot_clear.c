// rs_mot_clear.c -- the per-step rows and matching, CLEAR MOT, IDF1, the position errors and the
// crossings (eval/mot/rs_mot.h states the rules and references). HOTA: rs_mot_hota.c.
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_assign.h"
#include "eval/mot/internal/rs_mot_internal.h"

#define DEFAULT_THRESHOLD_M 2.0

static rs_status nomem(rs_err *err) { return rs_err_set(err, RS_ERR_NOMEM, "out of memory"); }

// Costs (Ng, Nh): distance below D, else forbidden (+inf). cost has room for Ng * Nh.
static void distance_costs(double *cost, const rs_mot_data *d, const long *gi, int Ng, const long *hi, int Nh, double D)
{
    for (int a = 0; a < Ng; a++)
        for (int b = 0; b < Nh; b++) {
            const double dist = rs_mot__dist_m(&d->gt[gi[a]], &d->hyp[hi[b]]);
            cost[(size_t)a * Nh + b] = dist < D ? dist : INFINITY;
        }
}

long rs_mot__max_step_rows(const rs_mot_data *d)
{
    long max = 1;
    for (int s = 0; s < d->Nsteps; s++) {
        const long a = d->gt_first[s + 1] - d->gt_first[s], b = d->hyp_first[s + 1] - d->hyp_first[s];
        if (a > max) max = a;
        if (b > max) max = b;
    }
    return max;
}

rs_status rs_mot__step_rows(long *gt_idx, int *Ng, long *hyp_idx, int *Nh, const rs_mot_data *d, int s,
                            const rs_mot_options *opt, rs_err *err)
{
    *Ng = *Nh = 0;
    const long Nstep = d->gt_first[s + 1] - d->gt_first[s];
    long *un = malloc(sizeof(long) * (size_t)(Nstep > 0 ? Nstep : 1));
    int Nun = 0; // uncounted ground truth at this step
    if (!un) return nomem(err);
    for (long i = d->gt_first[s]; i < d->gt_first[s + 1]; i++)
        if (opt->all_gt || d->gt[i].seen)
            gt_idx[(*Ng)++] = i;
        else
            un[Nun++] = i;
    const int Nall = (int)(d->hyp_first[s + 1] - d->hyp_first[s]);
    for (int b = 0; b < Nall; b++) hyp_idx[b] = d->hyp_first[s] + b;
    if (Nun == 0 || Nall == 0) {
        *Nh = Nall;
        free(un);
        return RS_OK;
    }
    // a track row the step's assignment leaves unmatched, within D of an uncounted vehicle: ignored
    double *cost = malloc(sizeof(double) * ((size_t)*Ng * Nall + 1));
    int *col = malloc(sizeof(int) * (size_t)Nall);
    rs_status st = cost && col ? RS_OK : nomem(err);
    if (!st) {
        distance_costs(cost, d, gt_idx, *Ng, hyp_idx, Nall, opt->threshold_m);
        st = rs_assign(NULL, col, NULL, NULL, cost, *Ng, Nall, INFINITY, err);
    }
    for (int b = 0; b < Nall && !st; b++) {
        bool ignore = false;
        for (int u = 0; u < Nun && col[b] < 0 && !ignore; u++)
            ignore = rs_mot__dist_m(&d->gt[un[u]], &d->hyp[hyp_idx[b]]) < opt->threshold_m;
        if (!ignore) hyp_idx[(*Nh)++] = hyp_idx[b];
    }
    free(cost);
    free(col);
    free(un);
    return st;
}

// Per vehicle, what the walk over the steps remembers.
typedef struct {
    int last_track; // the track matched at its last matched step, -1 none (CLEAR's mapping)
    bool gap;       // matched before, unmatched since (a fragmentation if matched again)
    unsigned ref;   // crossings: the reference camera set, 0 before its first seen step
    bool pending;   // a crossing waits for its first matched step
    int before;     // the track before that crossing
} vehicle_state;

typedef struct {
    long *gi, *hi;       // (max rows of a step,) indices of the step's counted rows
    int *row, *col;      // (max,) the step's matching
    int *ra, *cb, *sub;  // (max,) clear_match's free rows and columns, their matching
    double *cost;        // (max^2,)
    int *overlap;        // (Nvehicles * Ntracks,) steps at which a vehicle and a track are within D
    bool *vused, *tused; // (Nvehicles,), (Ntracks,) counted anywhere
    vehicle_state *v;    // (Nvehicles,)
} work;

static void work_free(work *w)
{
    free(w->gi);
    free(w->hi);
    free(w->row);
    free(w->col);
    free(w->ra);
    free(w->cb);
    free(w->sub);
    free(w->cost);
    free(w->overlap);
    free(w->vused);
    free(w->tused);
    free(w->v);
}

static rs_status work_alloc(work *w, const rs_mot_data *d, rs_err *err)
{
    memset(w, 0, sizeof(*w));
    const long max = rs_mot__max_step_rows(d);
    const size_t V = (size_t)(d->Nvehicles > 0 ? d->Nvehicles : 1), T = (size_t)(d->Ntracks > 0 ? d->Ntracks : 1);
    w->gi = malloc(sizeof(long) * (size_t)max);
    w->hi = malloc(sizeof(long) * (size_t)max);
    w->row = malloc(sizeof(int) * (size_t)max);
    w->col = malloc(sizeof(int) * (size_t)max);
    w->ra = malloc(sizeof(int) * (size_t)max);
    w->cb = malloc(sizeof(int) * (size_t)max);
    w->sub = malloc(sizeof(int) * (size_t)max);
    w->cost = malloc(sizeof(double) * (size_t)max * (size_t)max);
    w->overlap = calloc(V * T, sizeof(int));
    w->vused = calloc(V, 1);
    w->tused = calloc(T, 1);
    w->v = malloc(sizeof(vehicle_state) * V);
    if (!w->gi || !w->hi || !w->row || !w->col || !w->ra || !w->cb || !w->sub || !w->cost || !w->overlap || !w->vused ||
        !w->tused || !w->v) {
        work_free(w);
        return nomem(err);
    }
    for (size_t i = 0; i < V; i++) w->v[i] = (vehicle_state){.last_track = -1, .before = -1};
    return RS_OK;
}

// CLEAR MOT's matching of one step: the previous correspondences kept while within D, the rest
// by rs_assign (most pairs, then least distance). out: w->row (Ng,) the matched position in w->hi, -1 none.
static rs_status clear_match(work *w, const rs_mot_data *d, int Ng, int Nh, double D, rs_err *err)
{
    for (int a = 0; a < Ng; a++) w->row[a] = -1;
    for (int b = 0; b < Nh; b++) w->col[b] = -1;
    for (int a = 0; a < Ng; a++) {
        const rs_mot__row *g = &d->gt[w->gi[a]];
        const int t = w->v[g->id].last_track;
        for (int b = 0; b < Nh && t >= 0; b++)
            if (d->hyp[w->hi[b]].id == t && w->col[b] < 0 && rs_mot__dist_m(g, &d->hyp[w->hi[b]]) < D) {
                w->row[a] = b;
                w->col[b] = a;
                break;
            }
    }
    // the rest: rows and columns still free
    int *ra = w->ra, *cb = w->cb, *sub = w->sub, Nr = 0, Nc = 0;
    for (int a = 0; a < Ng; a++)
        if (w->row[a] < 0) ra[Nr++] = a;
    for (int b = 0; b < Nh; b++)
        if (w->col[b] < 0) cb[Nc++] = b;
    for (int i = 0; i < Nr; i++)
        for (int j = 0; j < Nc; j++) {
            const double dist = rs_mot__dist_m(&d->gt[w->gi[ra[i]]], &d->hyp[w->hi[cb[j]]]);
            w->cost[(size_t)i * Nc + j] = dist < D ? dist : INFINITY;
        }
    rs_status st = rs_assign(sub, NULL, NULL, NULL, w->cost, Nr, Nc, INFINITY, err);
    for (int i = 0; i < Nr && !st; i++)
        if (sub[i] >= 0) w->row[ra[i]] = cb[sub[i]], w->col[cb[sub[i]]] = ra[i];
    return st;
}

// One match's position figures: d^2, and with a covariance its trace and d^T C^-1 d.
static void position(rs_mot_result *r, double *sum_d2, double *sum_tr, long *Ntr, double *sum_nees,
                     const rs_mot__row *g, const rs_mot__row *h)
{
    const double de = h->e_m - g->e_m, dn = h->n_m - g->n_m;
    *sum_d2 += de * de + dn * dn;
    const double a = h->cov_en[0], c = h->cov_en[1], b = h->cov_en[2];
    if (!isfinite(a) || !isfinite(b)) return;
    const double cc = isfinite(c) ? c : 0;
    *sum_tr += a + b;
    (*Ntr)++;
    const double det = a * b - cc * cc;
    if (!(a > 0 && det > 0)) return;
    *sum_nees += (b * de * de - 2 * cc * de * dn + a * dn * dn) / det;
    r->Nnees++;
}

// The crossings' walk for vehicle state v at a seen step with camera set cams, matched track h.
static void crossing_step(rs_mot_result *r, vehicle_state *v, unsigned cams, int h)
{
    if (cams) {
        if (!v->ref)
            v->ref = cams;
        else if (!(cams & v->ref)) {
            r->crossings++;
            v->pending = true;
            v->before = v->last_track;
            v->ref = cams;
        }
    }
    if (h >= 0 && v->pending) {
        r->crossings_kept += v->before >= 0 && v->before == h;
        v->pending = false;
    }
}

// The global ID matching: IDTP the largest sum of overlaps of a one-to-one vehicle-track matching.
static rs_status idf1(rs_mot_result *r, const work *w, int V, int T, rs_err *err)
{
    double *cost = malloc(sizeof(double) * ((size_t)V * T + 1));
    int *row = malloc(sizeof(int) * (size_t)(V + 1));
    if (!cost || !row) {
        free(cost);
        free(row);
        return nomem(err);
    }
    for (size_t k = 0; k < (size_t)V * T; k++) cost[k] = w->overlap[k] > 0 ? -(double)w->overlap[k] : INFINITY;
    rs_status st = rs_assign(row, NULL, NULL, NULL, cost, V, T, INFINITY, err);
    r->idtp = 0;
    for (int i = 0; i < V && !st; i++)
        if (row[i] >= 0) r->idtp += w->overlap[(size_t)i * T + row[i]];
    r->idfn = r->Ngt - r->idtp;
    r->idfp = r->Nhyp - r->idtp;
    r->idf1 = r->Ngt + r->Nhyp > 0 ? 2.0 * r->idtp / (double)(r->Ngt + r->Nhyp) : NAN;
    r->idp = r->Nhyp > 0 ? (double)r->idtp / r->Nhyp : NAN;
    r->idr = r->Ngt > 0 ? (double)r->idtp / r->Ngt : NAN;
    free(cost);
    free(row);
    return st;
}

rs_status rs_mot_run(rs_mot_result *r, const rs_mot_data *d, const rs_mot_options *opt_in, rs_err *err)
{
    rs_mot_options opt = opt_in ? *opt_in : (rs_mot_options){0};
    if (opt.threshold_m == 0) opt.threshold_m = DEFAULT_THRESHOLD_M;
    if (!(opt.threshold_m > 0) || !isfinite(opt.threshold_m))
        return rs_err_set(err, RS_ERR_USAGE, "--threshold-m: %g is not a positive distance in metres", opt.threshold_m);
    const double D = opt.threshold_m;
    memset(r, 0, sizeof(*r));
    r->threshold_m = D;
    r->all_gt = opt.all_gt;
    r->Nsteps = d->Nsteps;
    r->Nrows_off_step = d->Noff_step;
    work w;
    rs_status st = work_alloc(&w, d, err);
    if (st) return st;
    const int V = d->Nvehicles, T = d->Ntracks;
    double sum_d = 0, sum_d2 = 0, sum_tr = 0, sum_nees = 0;
    long Ntr = 0;
    for (int s = 0; s < d->Nsteps && !st; s++) {
        int Ng, Nh;
        if ((st = rs_mot__step_rows(w.gi, &Ng, w.hi, &Nh, d, s, &opt, err)) ||
            (st = clear_match(&w, d, Ng, Nh, D, err)))
            break;
        r->Nignored += (d->hyp_first[s + 1] - d->hyp_first[s]) - Nh;
        r->Ngt += Ng;
        r->Nhyp += Nh;
        for (int b = 0; b < Nh; b++) {
            w.tused[d->hyp[w.hi[b]].id] = true;
            r->fp += w.col[b] < 0;
        }
        for (int a = 0; a < Ng; a++) {
            const rs_mot__row *g = &d->gt[w.gi[a]];
            vehicle_state *v = &w.v[g->id];
            w.vused[g->id] = true;
            for (int b = 0; b < Nh; b++)
                if (rs_mot__dist_m(g, &d->hyp[w.hi[b]]) < D) w.overlap[(size_t)g->id * T + d->hyp[w.hi[b]].id]++;
            const int b = w.row[a];
            const int h = b >= 0 ? d->hyp[w.hi[b]].id : -1;
            crossing_step(r, v, g->cams, h);
            if (b < 0) {
                r->fn++;
                if (v->last_track >= 0) v->gap = true;
                continue;
            }
            r->matches++;
            if (v->last_track >= 0 && v->last_track != h) r->idsw++;
            if (v->gap) r->frag++;
            v->gap = false;
            v->last_track = h;
            sum_d += rs_mot__dist_m(g, &d->hyp[w.hi[b]]);
            position(r, &sum_d2, &sum_tr, &Ntr, &sum_nees, g, &d->hyp[w.hi[b]]);
        }
    }
    for (int i = 0; i < V; i++) r->Nvehicles += w.vused[i];
    for (int i = 0; i < T; i++) r->Ntracks += w.tused[i];
    if (!st) st = idf1(r, &w, V, T, err);
    work_free(&w);
    if (st) return st;
    r->mota = r->Ngt > 0 ? 1 - (double)(r->fn + r->fp + r->idsw) / r->Ngt : NAN;
    r->motp_m = r->matches > 0 ? sum_d / r->matches : NAN;
    r->rmse_m = r->matches > 0 ? sqrt(sum_d2 / r->matches) : NAN;
    r->predicted_rms_m = Ntr > 0 ? sqrt(sum_tr / Ntr) : NAN;
    r->nees = r->Nnees > 0 ? sum_nees / r->Nnees : NAN;
    r->crossings_share = r->crossings > 0 ? (double)r->crossings_kept / r->crossings : NAN;
    return rs_mot__hota(r, d, &opt, err);
}

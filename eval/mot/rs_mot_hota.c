// rs_mot_hota.c -- HOTA with a distance similarity S = max(0, 1 - d / D) (eval/mot/rs_mot.h):
// J. Luiten et al., IJCV 129, 548-578 (2021), computed as TrackEval's HOTA.py does: a global
// alignment score per (vehicle, track) from the soft per-step similarities, one matching per
// step maximising alignment x S, then per alpha the matches with S >= alpha.
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_assign.h"
#include "eval/mot/internal/rs_mot_internal.h"

#define EPS 2.220446049250313e-16 // numpy's float eps, as TrackEval compares

typedef struct {
    long *gi, *hi;
    double *sim, *cost;      // (max^2,)
    double *rowsum, *colsum; // (max,)
    int *row;                // (max,)
    double *pmc;             // (V * T,) potential matches count
    double *gcount, *tcount; // (V,), (T,)
    double *mcount;          // (RS_MOT_NALPHA * V * T,) matches per alpha
} hota_work;

static void hw_free(hota_work *w)
{
    free(w->gi);
    free(w->hi);
    free(w->sim);
    free(w->cost);
    free(w->rowsum);
    free(w->colsum);
    free(w->row);
    free(w->pmc);
    free(w->gcount);
    free(w->tcount);
    free(w->mcount);
}

static double alpha_of(int a) { return 0.05 * (a + 1); }

// Step s's counted rows and their similarities (Ng, Nh) in w->sim.
static rs_status step_sim(int *Ng, int *Nh, hota_work *w, const rs_mot_data *d, int s, const rs_mot_options *opt,
                          rs_err *err)
{
    rs_status st = rs_mot__step_rows(w->gi, Ng, w->hi, Nh, d, s, opt, err);
    for (int a = 0; a < *Ng && !st; a++)
        for (int b = 0; b < *Nh; b++) {
            const double x = 1 - rs_mot__dist_m(&d->gt[w->gi[a]], &d->hyp[w->hi[b]]) / opt->threshold_m;
            w->sim[(size_t)a * *Nh + b] = x > 0 ? x : 0;
        }
    return st;
}

rs_status rs_mot__hota(rs_mot_result *r, const rs_mot_data *d, const rs_mot_options *opt, rs_err *err)
{
    hota_work w = {0};
    const long max = rs_mot__max_step_rows(d);
    const size_t V = (size_t)(d->Nvehicles > 0 ? d->Nvehicles : 1), T = (size_t)(d->Ntracks > 0 ? d->Ntracks : 1);
    w.gi = malloc(sizeof(long) * (size_t)max);
    w.hi = malloc(sizeof(long) * (size_t)max);
    w.sim = malloc(sizeof(double) * (size_t)max * (size_t)max);
    w.cost = malloc(sizeof(double) * (size_t)max * (size_t)max);
    w.rowsum = malloc(sizeof(double) * (size_t)max);
    w.colsum = malloc(sizeof(double) * (size_t)max);
    w.row = malloc(sizeof(int) * (size_t)max);
    w.pmc = calloc(V * T, sizeof(double));
    w.gcount = calloc(V, sizeof(double));
    w.tcount = calloc(T, sizeof(double));
    w.mcount = calloc(RS_MOT_NALPHA * V * T, sizeof(double));
    rs_status st = RS_OK;
    if (!w.gi || !w.hi || !w.sim || !w.cost || !w.rowsum || !w.colsum || !w.row || !w.pmc || !w.gcount || !w.tcount ||
        !w.mcount)
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    // 1. the global alignment: soft matches S / (row sum + column sum - S) per step, summed
    for (int s = 0; s < d->Nsteps && !st; s++) {
        int Ng, Nh;
        if ((st = step_sim(&Ng, &Nh, &w, d, s, opt, err))) break;
        for (int a = 0; a < Ng; a++) w.rowsum[a] = 0;
        for (int b = 0; b < Nh; b++) w.colsum[b] = 0;
        for (int a = 0; a < Ng; a++)
            for (int b = 0; b < Nh; b++) {
                w.rowsum[a] += w.sim[(size_t)a * Nh + b];
                w.colsum[b] += w.sim[(size_t)a * Nh + b];
            }
        for (int a = 0; a < Ng; a++) {
            const int g = d->gt[w.gi[a]].id;
            w.gcount[g] += 1;
            for (int b = 0; b < Nh; b++) {
                const double x = w.sim[(size_t)a * Nh + b], den = w.rowsum[a] + w.colsum[b] - x;
                if (den > EPS) w.pmc[(size_t)g * T + d->hyp[w.hi[b]].id] += x / den;
            }
        }
        for (int b = 0; b < Nh; b++) w.tcount[d->hyp[w.hi[b]].id] += 1;
    }
    // 2. per step, one matching maximising alignment x S; per alpha the pairs with S >= alpha
    double tp[RS_MOT_NALPHA] = {0}, fn[RS_MOT_NALPHA] = {0}, fp[RS_MOT_NALPHA] = {0}, loc[RS_MOT_NALPHA] = {0};
    for (int s = 0; s < d->Nsteps && !st; s++) {
        int Ng, Nh;
        if ((st = step_sim(&Ng, &Nh, &w, d, s, opt, err))) break;
        for (int a = 0; a < Ng; a++) {
            const int g = d->gt[w.gi[a]].id;
            for (int b = 0; b < Nh; b++) {
                const int t = d->hyp[w.hi[b]].id;
                const double pm = w.pmc[(size_t)g * T + t];
                const double align = pm / (w.gcount[g] + w.tcount[t] - pm);
                const double score = align * w.sim[(size_t)a * Nh + b];
                w.cost[(size_t)a * Nh + b] = score > 0 ? -score : INFINITY;
            }
        }
        if ((st = rs_assign(w.row, NULL, NULL, NULL, w.cost, Ng, Nh, INFINITY, err))) break;
        for (int k = 0; k < RS_MOT_NALPHA; k++) {
            int n = 0;
            for (int a = 0; a < Ng; a++) {
                if (w.row[a] < 0) continue;
                const double x = w.sim[(size_t)a * Nh + w.row[a]];
                if (x < alpha_of(k) - EPS) continue;
                n++;
                loc[k] += x;
                w.mcount[((size_t)k * V + d->gt[w.gi[a]].id) * T + d->hyp[w.hi[w.row[a]]].id] += 1;
            }
            tp[k] += n;
            fn[k] += Ng - n;
            fp[k] += Nh - n;
        }
    }
    // 3. per alpha: DetA, AssA, LocA, HOTA; their means
    r->hota = r->deta = r->assa = r->loca = 0;
    for (int k = 0; k < RS_MOT_NALPHA && !st; k++) {
        double ass = 0;
        for (size_t g = 0; g < V; g++)
            for (size_t t = 0; t < T; t++) {
                const double m = w.mcount[((size_t)k * V + g) * T + t];
                if (m > 0) ass += m * m / fmax(1, w.gcount[g] + w.tcount[t] - m);
            }
        r->assa_alpha[k] = ass / fmax(1, tp[k]);
        r->deta_alpha[k] = tp[k] / fmax(1, tp[k] + fn[k] + fp[k]);
        r->loca_alpha[k] = fmax(1e-10, loc[k]) / fmax(1e-10, tp[k]);
        r->hota_alpha[k] = sqrt(r->deta_alpha[k] * r->assa_alpha[k]);
        r->hota += r->hota_alpha[k];
        r->deta += r->deta_alpha[k];
        r->assa += r->assa_alpha[k];
        r->loca += r->loca_alpha[k];
    }
    r->hota /= RS_MOT_NALPHA; // (sums first: 19 ones make exactly 1)
    r->deta /= RS_MOT_NALPHA;
    r->assa /= RS_MOT_NALPHA;
    r->loca /= RS_MOT_NALPHA;
    hw_free(&w);
    return st;
}

// rs_mot_internal.h -- what the files of eval/mot share (eval/mot/rs_mot.h). Not for other
// components. rs_mot_read.c fills rs_mot_data; rs_mot_clear.c (per-step matching, CLEAR MOT,
// IDF1, position, crossings) and rs_mot_hota.c read it.
#pragma once
#include <math.h>
#include <stdbool.h>

#include "core/rs_status.h"
#include "eval/mot/rs_mot.h"

// One row of either file, at its time step.
typedef struct {
    int step;         // index into rs_mot_data.t_s
    int id;           // dense id: vehicle index (ground truth) or track index (tracks)
    double e_m, n_m;  // site ENU, east and north
    double cov_en[3]; // tracks: s_e^2, c, s_n^2 (NaN when the row has none); ground truth: unused
    unsigned cams;    // ground truth: bit c set = seen by camera c (cams_names), 0 = by none
    bool seen;        // ground truth: seen by at least one camera
} rs_mot__row;

#define RS_MOT__MAX_CAMERAS 32 // distinct camera ids in a ground-truth file

struct rs_mot_data {
    double *t_s; // (Nsteps,) the ground truth's distinct times, ascending
    int Nsteps;
    rs_mot__row *gt; // (Ngt,) sorted by step; gt_first[s] .. gt_first[s + 1] - 1 are step s's
    long Ngt;
    long *gt_first;   // (Nsteps + 1,)
    rs_mot__row *hyp; // (Nhyp,) track rows at a step, sorted by step; hyp_first likewise
    long Nhyp;
    long *hyp_first; // (Nsteps + 1,)
    long Noff_step;  // track rows at no step
    int Nvehicles;   // distinct vehicle ids (ids 0 .. Nvehicles - 1)
    int Ntracks;     // distinct track ids
    int Ncams;       // distinct camera ids
};

// The rows of step s counted (opt->all_gt, or seen) and the track rows kept (not ignored), with
// the CLEAR MOT matching: out (caller's arrays, at least the step's counts):
//   gt_idx (*Ng,), hyp_idx (*Nh,): indices into data->gt / data->hyp
// Used by rs_mot_clear.c and rs_mot_hota.c. Errors: RS_ERR_NOMEM.
rs_status rs_mot__step_rows(long *gt_idx, int *Ng, long *hyp_idx, int *Nh, const rs_mot_data *data, int s,
                            const rs_mot_options *opt, rs_err *err);

// The most ground-truth or track rows of any step (at least 1): the size of per-step buffers.
long rs_mot__max_step_rows(const rs_mot_data *data);

// HOTA's figures into r (rs_mot_hota.c), from the rows rs_mot__step_rows keeps.
rs_status rs_mot__hota(rs_mot_result *r, const rs_mot_data *data, const rs_mot_options *opt, rs_err *err);

// East-north distance between a ground-truth row and a track row, metres.
static inline double rs_mot__dist_m(const rs_mot__row *g, const rs_mot__row *h)
{
    const double de = h->e_m - g->e_m, dn = h->n_m - g->n_m;
    return sqrt(de * de + dn * dn);
}

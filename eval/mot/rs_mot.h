// rs_mot.h -- tracking metrics in metres on the ground: a tracker's tracks (`roadside track`'s
// CSV) against the ground-truth tracks of a synthetic sequence (`roadside synth --sequence`'s
// DATASET/tracks_gt.csv). docs/evaluation.md, "Tracking metrics", states every rule.
//
// Time steps: the distinct times of the ground truth; a track row belongs to the step whose time
// is within 1e-6 s of its own (rows at no step are counted in Nrows_off_step and otherwise left
// out). Distances are east-north distances d = |(e, n)_track - (e, n)_gt| in metres; D is the
// threshold (a pair with d >= D never matches).
// Which ground truth counts: by default only the vehicles seen by at least one camera at that
// step (tracks_gt.csv's `cameras` not empty): a tracker cannot see the others. A track row that
// matches none of the counted vehicles but lies within D of an uncounted one is ignored (neither
// a false positive nor counted anywhere else): the ground truth's camera sets decide what a
// tracker is asked for, not whether it may keep a vehicle a little longer. all_gt counts every
// vehicle.
// Metrics:
//   CLEAR MOT (K. Bernardin and R. Stiefelhagen, "Evaluating multiple object tracking
//   performance: the CLEAR MOT metrics", EURASIP J. Image and Video Processing 2008:246309):
//   at each step the correspondences of the previous step are kept while d < D, the rest are
//   matched by a minimum-cost assignment on d (core/rs_assign.h with miss_cost +inf: most
//   pairs, then least total distance); FN = counted ground truths unmatched, FP = counted track rows unmatched, IDSW =
//   matches whose track differs from the last track the vehicle was matched to, Frag = times a
//   vehicle goes from matched to unmatched and is matched again later; MOTA = 1 - (FN + FP +
//   IDSW) / GT, MOTP = mean d over matches (metres).
//   IDF1 (E. Ristani, F. Solera, R. Zou, R. Cucchiara and C. Tomasi, "Performance measures and a
//   data set for multi-target, multi-camera tracking", ECCV 2016 workshops): one global
//   one-to-one matching of ground-truth vehicles to track ids maximising IDTP, the number of
//   steps at which a matched pair is within D; IDF1 = 2 IDTP / (GT + tracker rows).
//   HOTA (J. Luiten et al., "HOTA: a higher order metric for evaluating multi-object tracking",
//   IJCV 129, 548-578 (2021)), with the similarity S = max(0, 1 - d / D) in place of IoU: DetA,
//   AssA, LocA and HOTA = sqrt(DetA AssA) at alpha = 0.05, 0.10, .., 0.95 and their means; each
//   step's matching maximises (the pair's global alignment score) x S over pairs with S > 0, as
//   TrackEval does (its HOTA.py).
//   Position: RMSE of d over the CLEAR MOT matches; the covariance's prediction sqrt(mean
//   (s_e^2 + s_n^2)) over the matches with a covariance; the NEES, mean of d^T C^-1 d (C = [[s_e^2,
//   c], [c, s_n^2]] of the track row; rows without a positive-definite C are left out), 2 when
//   the covariances are right (chi-square with 2 degrees of freedom).
//   Crossings: for each vehicle, walking its counted steps, a crossing happens at the first step
//   whose camera set is disjoint from the reference set (at first the set of its first counted
//   step, then the set where the last crossing ended); it keeps its id when the track matched at
//   the last matched step before it equals the track matched at the first matched step from it
//   on (a crossing with no match on either side does not keep it). Reported: crossings, kept,
//   their share.
// Accuracy: counts are exact; sums in double precision (relative 1e-16 x the number of terms).
// Checked against a plain Python implementation of the papers' definitions on random and
// hand-made cases (tests/eval/test_mot_metrics.py).
// Cost: per step O(n^3) for n vehicles and tracks at that step (rs_assign), plus the global
// ID matching O(V^2 T) for V vehicles and T track ids, memory O(V T) for the pairs' counts.
//
// Ownership: rs_mot_data and rs_mot_result belong to the caller; their _free accepts NULL.
#pragma once
#include <stdbool.h>
#include <stddef.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// Tracks and ground truth, parsed and grouped by time step. Opaque.
typedef struct rs_mot_data rs_mot_data;

// Reads a tracks CSV (`roadside track`'s tracks file: the columns time_s, track_id,
// e_m, n_m are required, sigma_e_m, sigma_n_m, cov_en_m2 optional (empty cells allowed: no
// covariance for that row); other columns are ignored, in any order) and a ground-truth tracks
// CSV (time_s, vehicle_id, e_m, n_m, cameras required; cameras' ids joined by '+', empty: seen by
// none). Errors: RS_ERR_IO (cannot read), RS_ERR_PARSE ("FILE:LINE: FIELD: not a number", a
// missing column, a row with another count of fields), RS_ERR_INVALID (a non-finite value, a
// negative sigma, a vehicle or a track twice at one time step, an empty id, no ground truth).
rs_status rs_mot_load( // out
    rs_mot_data **data,
    // in
    const char *tracks_path, const char *gt_path, rs_err *err);

// The same from text in memory (NUL-terminated); the names are used in messages only.
rs_status rs_mot_parse( // out
    rs_mot_data **data,
    // in
    const char *tracks_text, const char *tracks_name, const char *gt_text, const char *gt_name, rs_err *err);

void rs_mot_data_free(rs_mot_data *data);

typedef struct {
    double threshold_m; // D > 0, metres (0 selects the default, 2 m)
    bool all_gt;        // count every ground-truth vehicle, seen or not (default: seen only)
} rs_mot_options;

#define RS_MOT_NALPHA 19 // HOTA's thresholds alpha = 0.05, 0.10, .., 0.95

typedef struct {
    double threshold_m;
    bool all_gt;
    int Nsteps;             // time steps (distinct ground-truth times)
    long Nrows_off_step;    // track rows at no ground-truth time (left out)
    long Nignored;          // track rows near an uncounted vehicle only (left out)
    long Ngt, Nhyp;         // counted ground-truth rows, counted track rows
    int Nvehicles, Ntracks; // distinct counted vehicle ids, distinct counted track ids
    // CLEAR MOT
    long matches, fp, fn, idsw, frag;
    double mota, motp_m; // NaN when Ngt == 0 / no match
    // IDF1
    long idtp, idfp, idfn;
    double idf1, idp, idr; // NaN when undefined (0 / 0)
    // HOTA: per alpha and the mean over alphas
    double hota_alpha[RS_MOT_NALPHA], deta_alpha[RS_MOT_NALPHA], assa_alpha[RS_MOT_NALPHA], loca_alpha[RS_MOT_NALPHA];
    double hota, deta, assa, loca;
    // position
    double rmse_m;          // over the CLEAR MOT matches; NaN without one
    double predicted_rms_m; // sqrt(mean(s_e^2 + s_n^2)) over the matches with a covariance
    double nees;            // mean d^T C^-1 d over the matches with a positive-definite C (2 expected)
    long Nnees;             // matches with one
    // crossings between disjoint camera sets
    long crossings, crossings_kept;
    double crossings_share; // kept / crossings; NaN without a crossing
} rs_mot_result;

// Evaluates. Errors: RS_ERR_USAGE (a threshold that is not positive and finite), RS_ERR_NOMEM.
rs_status rs_mot_run( // out
    rs_mot_result *result,
    // in
    const rs_mot_data *data,
    const rs_mot_options *opt, // may be NULL: the defaults
    rs_err *err);

// The figures of rs_mot_located_run.
typedef struct {
    double threshold_m;
    int Ncameras;
    long Nrows, Noff_step;   // detections; those at no ground-truth time
    long matched, unmatched; // detections matched to a vehicle; left without one
    long ignored;            // near an uncounted vehicle only
    double rmse_m;           // over the matches
    double predicted_rms_m;  // the covariances' prediction over the matches
    double nees;             // mean d^T C^-1 d over the matches (2 expected)
    long Nnees;
} rs_mot_located_result;

// Located detections (`roadside localise`'s CSV) against the ground truth: the localisation
// error and how well the reported covariances describe it. Each camera's detections are matched
// to the counted ground-truth vehicles step by step (one detection per vehicle and camera:
// rs_mot_run's per-step assignment on the east-north distance below D, every detection a track
// of its own), and the matches' figures summed over the cameras: RMSE of d, the covariances'
// predicted RMS sqrt(mean(s_e^2 + s_n^2)) and the NEES mean d^T C^-1 d (2 expected).
// Detections without a vehicle within D are counted as unmatched (ignored: near an uncounted
// vehicle only). Every row must have time_s.
// Errors: those of rs_localise_read (file, line, field) and rs_mot_load, RS_ERR_INVALID (a row
// without time_s, "FILE:LINE: time_s: empty").
rs_status rs_mot_located_run( // out
    rs_mot_located_result *result,
    // in
    const char *located_path, const char *gt_path,
    const rs_mot_options *opt, // may be NULL: the defaults
    rs_err *err);

// The result as JSON (keys as the struct's fields, HOTA's per-alpha values as objects keyed by
// alpha "%.2f"; NaN as null): a malloc'ed string (caller frees), NULL when out of memory.
char *rs_mot_result_json(const rs_mot_result *result);

// The same written atomically to path (core/rs_io.h).
rs_status rs_mot_result_write_json(const rs_mot_result *result, const char *path, rs_err *err);

#ifdef __cplusplus
}
#endif

// rs_track.h -- `roadside track`: multi-object tracking of vehicles in metres on the site's ground,
// over all the site's cameras at once (they share the site ENU frame, docs/conventions.md).
//
// Model (docs/track.md gives the reasons for every default):
//   - one constant-velocity Kalman filter per track (eval/track/rs_track_kf.h): state (e, n, ve,
//     vn) in site ENU, white-noise acceleration of density accel_sigma^2; each detection's own
//     2x2 covariance (the located-detections CSV's sigma_e_m, sigma_n_m, cov_en_m2) is its
//     measurement noise;
//   - time steps: the detections of one time_s (all cameras) form a step. All tracks are
//     predicted to it, then its detections are taken camera by camera (in the byte order of the
//     camera ids, so that the order of the input files does not matter), each camera's batch as sequential updates: gating by the
//     squared Mahalanobis distance of the innovation (chi-square with 2 degrees of freedom:
//     gate = -2 ln(1 - gate_p), exact for 2 dof), optimal assignment of the gated pairs
//     (core/rs_assign.h with miss_cost = gate: least total of (mahal2 - gate), the gate the
//     price of a miss), updates of
//     the matched tracks, and a new tentative track for every unmatched detection farther than
//     birth_exclusion_mahal2 from every track (closer, it is taken for an outlier of that track
//     or a detector's second box on it: a gate of 99.9 % misses 1 detection in 1,000, which at
//     4 cameras x 30 frames/s would start a twin of each track every 8 s), the tracks that took
//     another detection of this camera excepted (a camera sees a vehicle once). A second
//     camera's detection of the same vehicle at the same instant therefore updates the track the
//     first camera's detection updated (or gave birth to) instead of starting another;
//   - two tracks on one vehicle (e.g. born from two cameras whose locations disagree by more
//     than the gate) are merged after each step: when their positions differ by a squared
//     Mahalanobis distance (with the sum of their position covariances) below merge_pos_mahal2
//     and their velocities below merge_vel_mahal2, the one with fewer detections (then the
//     younger) is dropped. Twins split the detections between them and repel each other (each
//     takes the ones on its side), so the test is loose (99 % of chi-square 2 dof on each);
//     vehicles side by side are many sigmas apart, and vehicles crossing at an angle differ in
//     velocity, so both are kept apart;
//   - birth: a track is tentative until it has been updated at min_hits of its first
//     hit_window opportunities, and is dropped when it can no longer reach that; an opportunity
//     is a step at which a camera that has detected the track delivers detections (so cameras
//     whose frames are not synchronous, or one camera of several, do not count as misses the
//     steps at which only the others deliver); confirmed tracks get the next id (1, 2, ...);
//   - death: a track not updated for more than max_age_s seconds is dropped (before the next
//     step's association);
//   - reporting: at each step, every confirmed track updated at the step, and those coasting
//     (not updated) for at most coast_s seconds, their predicted state;
//   - class: the majority of the detections' category_id (ties: the smaller id).
// Cost per step: O(T D) gating and O(min(T, D)^2 max(T, D)) assignment per camera (T tracks, D
// detections), O(T^2) for the merge test.
//
// Ownership: a tracker belongs to the caller, freed by rs_track_tracker_free (accepts NULL).
#pragma once
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/rs_status.h"
#include "eval/localise/rs_localise.h"

#ifdef __cplusplus
extern "C" {
#endif

#define RS_TRACK_MAX_CAMERAS  64 // the cameras of one run (a bit each in a row's camera mask)
#define RS_TRACK_CAMERA_BYTES 65 // a camera id: up to 64 bytes (rs_io_name_problem) and a NUL

// The tracker's input is localise's located detection (rs_localise_row, eval/localise/rs_localise.h:
// the columns of the located-detections file, issue 39's interface 2), read by rs_localise_read.

// Checks that rows (N,) read from path are fit to track, before any tracking: time_s known,
// category_id within an int, e_m and n_m finite, the covariance positive definite (sigmas > 0,
// |cov_en_m2| < sigma_e_m sigma_n_m). Errors: RS_ERR_INVALID "PATH:LINE: FIELD: what" (the rows'
// `line`) for the first row at fault.
rs_status rs_track_check_located(const rs_localise_row *rows, size_t N, const char *path, rs_err *err);

typedef struct {
    double accel_sigma_mps2;     // white-noise acceleration (default 3 m/s^2)
    double gate_p;               // gate probability, in (0, 1) (default 0.999)
    double max_age_s;            // a confirmed track dies after this long without update (1 s)
    int min_hits, hit_window;    // M of N (default 3 of 4)
    double init_speed_sigma_mps; // a new track's velocity sigma on each axis (default 15 m/s)
    double coast_s;              // report a confirmed track up to this long without update (0.3 s)
    double merge_pos_mahal2;     // the merge test (default 9.21 and 9.21, the chi-square 2-dof 99 %)
    double merge_vel_mahal2;
    double birth_exclusion_mahal2; // no birth this close to a track (default 27.63: 2-dof tail 1e-6)
} rs_track_options;

// The defaults above.
void rs_track_options_default(rs_track_options *opt);

// Checks the options: RS_ERR_USAGE naming the first one out of range.
rs_status rs_track_options_check(const rs_track_options *opt, rs_err *err);

// One reported state: a row of the tracks CSV (issue 39's interface 3) and a little more.
typedef struct {
    double time_s;
    int track_id;                              // 1-based, in order of confirmation
    double e_m, n_m, u_m;                      // site ENU (u: the last detection's ground height)
    double speed_mps, heading_deg;             // heading clockwise from north, [0, 360)
    double sigma_e_m, sigma_n_m, cov_en_m2;    // the position covariance
    double sigma_speed_mps, sigma_heading_deg; // first-order from the velocity covariance
    double age_s;                              // since the track's first detection
    int detections;                            // detections the track has taken so far
    uint64_t camera_mask;                      // cameras that updated it at this step (bit k:
                                               //   rs_track_tracker_camera(k)); 0 when coasting
    int category_id;                           // the majority class so far
} rs_track_row;

typedef struct rs_track_tracker rs_track_tracker;

// A tracker with no track yet. RS_ERR_USAGE (options), RS_ERR_NOMEM.
rs_status rs_track_tracker_new( // out
    rs_track_tracker **tracker,
    // in
    const rs_track_options *opt, // may be NULL: the defaults
    rs_err *err);

void rs_track_tracker_free(rs_track_tracker *tracker);

// One time step: the detections dets (N,) of time time_s, any cameras, any order. Times must not
// decrease from step to step. Appends the step's reported rows (rs_track_tracker_rows).
// Errors: RS_ERR_INVALID (a time before the previous step's; a non-finite position or a
// covariance that is not positive definite, naming the detection's line), RS_ERR_UNSUPPORTED
// (more than RS_TRACK_MAX_CAMERAS cameras), RS_ERR_NOMEM.
rs_status rs_track_tracker_step( // in,out
    rs_track_tracker *tracker,
    // in
    double time_s, const rs_localise_row *dets, int N, rs_err *err);

// All rows reported so far, in order of time then track id; *Nrows their count.
const rs_track_row *rs_track_tracker_rows(const rs_track_tracker *tracker, size_t *Nrows);

// Forgets the rows reported so far (a streaming caller that has used them), keeping the tracks.
void rs_track_tracker_clear_rows(rs_track_tracker *tracker);

// The id of camera k (the order of first appearance), NULL past the last; *Ncameras may be NULL.
const char *rs_track_tracker_camera(const rs_track_tracker *tracker, int k, int *Ncameras);

// The place of camera k's id among the ids in byte order (strcmp), 0-based; -1 past the last.
int rs_track_tracker_camera_rank(const rs_track_tracker *tracker, int k);

// Counts: tracks confirmed so far, tracks dropped by the merge test.
void rs_track_tracker_counts(const rs_track_tracker *tracker, int *Nconfirmed, int *Nmerged);

// Tracks a whole input: dets (N,) in any order, each with a finite time_s (RS_ERR_INVALID naming
// the detection's line otherwise), grouped into steps by equal time_s (stable: the input order
// within a step). On success *tracker holds the rows.
rs_status rs_track_run( // out
    rs_track_tracker **tracker,
    // in
    const rs_localise_row *dets, size_t N,
    const rs_track_options *opt, // may be NULL: the defaults
    rs_err *err);

#ifdef __cplusplus
}
#endif

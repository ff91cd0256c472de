// rs_bench_track.h -- `roadside bench track`: the tracker (eval/track/rs_track.h) on synthetic
// traffic seen by several simulated cameras, localised through core's camera functions, timed on
// one core against real time, with its position errors against the truth.
//
// The scene, all in memory: Nvehicles vehicles in a 100 m x 100 m square around the site origin,
// half on circles (radius 10..45 m, 5..15 m/s but at most 2.5 m/s^2 across; curved paths), half on straight chords across the
// square at 5..15 m/s (a vehicle leaving the square re-enters on a new chord as a new vehicle).
// Ncameras pinhole cameras (1920 x 1080, fx = fy = 1371 px: 70 degrees across) stand 150 m from
// the origin on a circle, 30 m up, looking at the origin; every camera sees the whole square.
// Each frame (fps per second, all cameras at the same instants), each vehicle inside a camera's
// image is detected with probability p_detect at its ground point's pixel plus N(0, pixel_sigma^2)
// noise per axis; localising is rs_camera_locate_ground of that pixel, and the detection's 2x2
// covariance pixel_sigma^2 J J^T with J = d(e, n)/d(u, v) by central differences (two more
// rs_camera_locate_ground calls per axis). The tracker then takes each frame as one step.
// Timing: the thread's CPU time of localising (projection and noise excluded) and of tracking.
// Figures: every reported row is matched to the nearest true vehicle at its time (within
// 5 m; a vehicle that left the square is not detected any more but still counts for 2 s, so
// that a track coasting after it is scored against it): its position error; the predicted RMSE is sqrt(mean(sigma_e^2 + sigma_n^2)) over the
// same rows, the same for the detections against their truth.
#pragma once
#include <stdint.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    int Nvehicles;           // at any time (default 50)
    int Ncameras;            // 1..8 (default 4)
    double fps;              // frames per second per camera (default 30)
    double duration_s;       // simulated seconds (default 20)
    double pixel_sigma;      // detection noise, pixels per axis (default 1)
    double p_detect;         // detection probability (default 0.9)
    double accel_sigma_mps2; // the tracker's --accel-sigma (default: the tracker's, 3)
    uint64_t seed;
} rs_bench_track_config;

// The defaults above, seed 1.
void rs_bench_track_config_default(rs_bench_track_config *c);

typedef struct {
    long frames, detections;     // frames per camera, detections of all cameras
    double detections_per_frame; // per camera
    double localise_cpu_s, track_cpu_s;
    double realtime_factor;                  // duration / (localise + track CPU)
    double track_realtime_factor;            // duration / track CPU
    long vehicles;                           // true vehicles (re-entries count anew)
    int confirmed;                           // tracks confirmed
    int merged;                              // duplicate tracks merged
    long rows, rows_unmatched;               // reported rows; those with no true vehicle within 5 m
    double rmse_m, predicted_rmse_m;         // reported rows
    double det_rmse_m, det_predicted_rmse_m; // detections
} rs_bench_track_figures;

// Runs the bench. RS_ERR_USAGE (a configuration out of range), RS_ERR_NOMEM, or the tracker's.
rs_status rs_bench_track_run(rs_bench_track_figures *f, const rs_bench_track_config *c, rs_err *err);

#ifdef __cplusplus
}
#endif

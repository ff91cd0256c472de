// roadside bench track -- the tracker on synthetic traffic (bench/rs_bench_track.h). Parses,
// calls the library, prints.
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench/rs_bench_track.h"
#include "cli/rs_cli.h"
#include "core/rs_io.h"

static const char bench_track_usage[] =
    "usage: roadside bench track [--vehicles N] [--cameras N] [--fps F] [--duration S]\n"
    "                            [--pixel-sigma PX] [--p-detect P] [--accel-sigma A] [--seed S]\n"
    "                            [--csv FILE]\n"
    "\n"
    "Synthetic traffic in memory (half the vehicles on circles, half on straight chords across a\n"
    "100 m square), seen by N pinhole cameras 150 m away and 30 m up; each visible vehicle detected\n"
    "with probability P at its pixel plus noise, localised through core's camera functions\n"
    "(rs_camera_locate_ground, covariance from its Jacobian), then tracked (roadside track's\n"
    "tracker, default options). Prints the CPU time of localising and tracking on one core against\n"
    "the simulated time, and the position errors of the reported tracks and of the detections\n"
    "against the truth with the RMSE their covariances predict.\n"
    "\n"
    "  --vehicles N      vehicles at any time (default 50)\n"
    "  --cameras N       cameras, 1..8 (default 4)\n"
    "  --fps F           frames per second per camera (default 30)\n"
    "  --duration S      simulated seconds (default 20)\n"
    "  --pixel-sigma PX  detection noise per pixel axis (default 1)\n"
    "  --p-detect P      detection probability (default 0.9)\n"
    "  --accel-sigma A   the tracker's white-noise acceleration, m/s^2 (default 3)\n"
    "  --seed S          seed (default 1)\n"
    "  --csv FILE        write the figures as CSV (atomically)\n"
    "\n"
    "Exit status: 0 ok, 1 failure, 2 usage error. Figures: docs/track.md.\n";

enum { O_VEHICLES = 3300, O_CAMERAS, O_FPS, O_DURATION, O_PIXEL, O_PDETECT, O_SEED, O_CSV, O_ACCEL };

int rs_cli_bench_track(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        fputs(bench_track_usage, stdout);
        return RS_EXIT_OK;
    }
    static const struct option longopts[] = {
        {"vehicles", required_argument, NULL, O_VEHICLES}, {"cameras", required_argument, NULL, O_CAMERAS},
        {"fps", required_argument, NULL, O_FPS},           {"duration", required_argument, NULL, O_DURATION},
        {"pixel-sigma", required_argument, NULL, O_PIXEL}, {"p-detect", required_argument, NULL, O_PDETECT},
        {"seed", required_argument, NULL, O_SEED},         {"csv", required_argument, NULL, O_CSV},
        {"accel-sigma", required_argument, NULL, O_ACCEL}, {NULL, 0, NULL, 0}};
    rs_bench_track_config cfg;
    rs_bench_track_config_default(&cfg);
    const char *csv = NULL;
    long n;
    int c, li = 0;
    optind = 1;
    opterr = 0;
    while ((c = getopt_long(argc, argv, "h", longopts, &li)) != -1) {
        bool ok = true;
        switch (c) {
        case O_VEHICLES: ok = rs_cli_parse_int(optarg, 1, 100000, &n), cfg.Nvehicles = (int)n; break;
        case O_CAMERAS: ok = rs_cli_parse_int(optarg, 1, 8, &n), cfg.Ncameras = (int)n; break;
        case O_FPS: ok = rs_cli_parse_double(optarg, &cfg.fps) && cfg.fps > 0 && cfg.fps <= 1000; break;
        case O_DURATION:
            ok = rs_cli_parse_double(optarg, &cfg.duration_s) && cfg.duration_s > 0 && cfg.duration_s <= 36000;
            break;
        case O_PIXEL:
            ok = rs_cli_parse_double(optarg, &cfg.pixel_sigma) && cfg.pixel_sigma > 0 && cfg.pixel_sigma <= 100;
            break;
        case O_PDETECT: ok = rs_cli_parse_double(optarg, &cfg.p_detect) && cfg.p_detect > 0 && cfg.p_detect <= 1; break;
        case O_SEED: ok = rs_cli_parse_int(optarg, 0, 1000000000, &n), cfg.seed = (uint64_t)n; break;
        case O_CSV: csv = optarg; break;
        case O_ACCEL:
            ok = rs_cli_parse_double(optarg, &cfg.accel_sigma_mps2) && cfg.accel_sigma_mps2 >= 0 &&
                 cfg.accel_sigma_mps2 <= 100;
            break;
        default: return rs_cli_usage_error("bench track", "unknown option or missing value: %s", argv[optind - 1]);
        }
        if (!ok) return rs_cli_usage_error("bench track", "--%s: '%s' is out of range", longopts[li].name, optarg);
    }
    if (optind != argc) return rs_cli_usage_error("bench track", "unexpected argument '%s'", argv[optind]);
    rs_err err = {0};
    rs_bench_track_figures f;
    rs_status st = rs_bench_track_run(&f, &cfg, &err);
    if (st) return rs_cli_fail("bench track", st, &err);
    printf("%8s %7s %6s %9s %8s %10s %9s %8s %8s %7s %8s %6s %8s %8s %9s %9s %9s %9s\n", "vehicles", "cameras", "fps",
           "duration", "frames", "detections", "det/frame", "loc_cpu", "trk_cpu", "RTx", "RTx_trk", "truth", "tracks",
           "rows", "unmatched", "rmse_m", "pred_m", "det_rmse");
    printf("%8d %7d %6.1f %9.1f %8ld %10ld %9.1f %8.3f %8.3f %7.1f %8.1f %6ld %8d %8ld %9ld %9.4f %9.4f %9.4f\n",
           cfg.Nvehicles, cfg.Ncameras, cfg.fps, cfg.duration_s, f.frames, f.detections, f.detections_per_frame,
           f.localise_cpu_s, f.track_cpu_s, f.realtime_factor, f.track_realtime_factor, f.vehicles, f.confirmed, f.rows,
           f.rows_unmatched, f.rmse_m, f.predicted_rmse_m, f.det_rmse_m);
    printf("loc_cpu, trk_cpu: CPU seconds of localising and of tracking on one core; RTx: simulated\n"
           "seconds per CPU second of both (RTx_trk: tracking alone); truth: true vehicles (re-entries\n"
           "count anew); tracks: tracks confirmed (%d duplicates merged); rows: reported track states,\n"
           "unmatched: those with no true vehicle within 5 m; rmse_m: position error of the matched rows,\n"
           "pred_m: the RMSE their covariances predict; det_rmse: the detections' (predicted %.4f m).\n",
           f.merged, f.det_predicted_rmse_m);
    if (csv) {
        char text[2048];
        int len = snprintf(text, sizeof text,
                           "vehicles,cameras,fps,duration_s,seed,frames,detections,detections_per_frame,localise_cpu_s,"
                           "track_cpu_s,realtime_factor,track_realtime_factor,true_vehicles,tracks,merged,rows,"
                           "rows_unmatched,rmse_m,predicted_rmse_m,det_rmse_m,det_predicted_rmse_m\n"
                           "%d,%d,%g,%g,%llu,%ld,%ld,%.3f,%.6f,%.6f,%.3f,%.3f,%ld,%d,%d,%ld,%ld,%.6f,%.6f,%.6f,%.6f\n",
                           cfg.Nvehicles, cfg.Ncameras, cfg.fps, cfg.duration_s, (unsigned long long)cfg.seed, f.frames,
                           f.detections, f.detections_per_frame, f.localise_cpu_s, f.track_cpu_s, f.realtime_factor,
                           f.track_realtime_factor, f.vehicles, f.confirmed, f.merged, f.rows, f.rows_unmatched,
                           f.rmse_m, f.predicted_rmse_m, f.det_rmse_m, f.det_predicted_rmse_m);
        if ((st = rs_io_write_file(csv, text, (size_t)len, &err))) return rs_cli_fail("bench track", st, &err);
    }
    return RS_EXIT_OK;
}

"""`roadside bench track` runs (a short run: 20 vehicles, 4 cameras, 30 fps, 3 s), writes its CSV,
and its figures hold what the bench exists to show, timing aside (speed is not tested): the
detections' RMSE within 10 % of what their covariances predict (the localisation's Jacobian
covariance is right), the tracks' RMSE within 1.3x of theirs, every reported row within 5 m of
a true vehicle, and no more confirmed tracks than 1.2x the true vehicles. Plus a usage error.
"""
import csv
import os
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "common"))
from rs_check import check, finish, run  # noqa: E402

with tempfile.TemporaryDirectory() as tmp:
    out = os.path.join(tmp, "bench.csv")
    p = run("bench", "track", "--vehicles", "20", "--duration", "3", "--seed", "7", "--csv", out)
    print(p.stdout)
    check(p.returncode == 0, f"bench track failed: {p.stderr}")
    if p.returncode == 0:
        with open(out) as f:
            r = {k: float(v) for k, v in next(csv.DictReader(f)).items()}
        check(r["frames"] == 90 and r["detections"] > 0.8 * 90 * 4 * 20 * 0.9, f"frames, detections: {r}")
        check(abs(r["det_rmse_m"] / r["det_predicted_rmse_m"] - 1) < 0.1,
              f"detections: RMSE {r['det_rmse_m']:.4f} m vs predicted {r['det_predicted_rmse_m']:.4f} m")
        check(r["rmse_m"] < 1.3 * r["predicted_rmse_m"],
              f"tracks: RMSE {r['rmse_m']:.4f} m vs predicted {r['predicted_rmse_m']:.4f} m (want < 1.3x)")
        check(r["rows_unmatched"] == 0 and r["rows"] > 0, f"rows {r['rows']}, unmatched {r['rows_unmatched']}")
        check(r["tracks"] <= 1.2 * r["true_vehicles"], f"{r['tracks']} tracks for {r['true_vehicles']} vehicles")
        check(r["realtime_factor"] > 0, "a real-time factor")
    p = run("bench", "track", "--cameras", "9")
    check(p.returncode == 2 and "--cameras" in p.stderr, f"--cameras 9: exit {p.returncode}: {p.stderr}")
finish("test_bench_track")

"""The Kalman filter of `roadside track` (eval/track/rs_track_kf.h) on straight-ish constant-velocity
vehicles with known noise, through the whole command:

  1. numpy oracle: the same equations (birth at the first detection with P0 = [R, 0; 0, v0^2 I],
     continuous white-noise-acceleration prediction, Joseph update with each detection's own R)
     evaluated by numpy reproduce every reported position to 1e-8 m (the CSV prints nanometres),
     the position sigmas and covariance to 1e-8, speed and heading to 1e-5;
  2. NEES: 200 vehicles (1 km apart: independent runs in one file) whose truth follows the
     filter's own model (velocity drawn from the prior N(0, v0^2 I), acceleration the exact
     discretised white noise of density A^2), detections with random ellipses (sigmas 0.2..1 m,
     any orientation) drawn from each detection's stated covariance: the mean over the runs of
     the normalised estimation error squared of the reported positions, at each reported step,
     lies within the two-sided 99.9 % chi-square bounds (chi2(2 R) / R, R runs), and its grand
     mean over all steps within 2 +- 0.15.
Seed 3901 (numpy's default_rng). Runs in about a second.
"""
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(__file__))
from track_common import make_site, read_tracks, run_track, write_located  # noqa: E402
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "common"))
from rs_check import check, finish, need  # noqa: E402

np, stats = need("numpy", "scipy.stats")
SEED, RUNS, STEPS, DT, A, V0 = 3901, 200, 40, 0.1, 3.0, 15.0


def Q(dt):
    q = A * A
    return q * np.block([[dt ** 3 / 3 * np.eye(2), dt ** 2 / 2 * np.eye(2)], [dt ** 2 / 2 * np.eye(2), dt * np.eye(2)]])


def F(dt):
    return np.block([[np.eye(2), dt * np.eye(2)], [np.zeros((2, 2)), np.eye(2)]])


def oracle(dets):
    """The filter on one vehicle's detections [(t, z, R)]: the state after each, [(t, x, P)]."""
    out = []
    t0, z, R = dets[0]
    x = np.array([z[0], z[1], 0.0, 0.0])
    P = np.zeros((4, 4))
    P[:2, :2] = R
    P[2, 2] = P[3, 3] = V0 * V0
    out.append((t0, x.copy(), P.copy()))
    H = np.hstack([np.eye(2), np.zeros((2, 2))])
    cache = {}
    for t, z, R in dets[1:]:
        dt = t - t0
        t0 = t
        if dt not in cache:
            cache[dt] = (F(dt), Q(dt))
        Fd, Qd = cache[dt]
        x = Fd @ x
        P = Fd @ P @ Fd.T + Qd
        S = H @ P @ H.T + R
        K = P @ H.T @ np.linalg.inv(S)
        x = x + K @ (z - H @ x)
        IKH = np.eye(4) - K @ H
        P = IKH @ P @ IKH.T + K @ R @ K.T
        P = 0.5 * (P + P.T)
        out.append((t, x.copy(), P.copy()))
    return out


def main():
    rng = np.random.default_rng(SEED)
    rows, truth, per_vehicle = [], {}, []
    FD, LQ = F(DT), np.linalg.cholesky(Q(DT))
    for r in range(RUNS):
        base = np.array([1000.0 * (r % 20), 1000.0 * (r // 20)])
        x = np.concatenate([base + rng.uniform(-5, 5, 2), rng.normal(0, V0, 2)])
        dets = []
        for k in range(STEPS):
            t = k * DT
            if k:
                x = FD @ x + LQ @ rng.standard_normal(4)
            a = rng.uniform(0, np.pi)
            rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
            R = rot @ np.diag(rng.uniform(0.2, 1.0, 2) ** 2) @ rot.T
            z = x[:2] + np.linalg.cholesky(R) @ rng.standard_normal(2)
            rows.append(dict(camera="cam%d" % (1 + k % 2), time_s=t, e_m=z[0], n_m=z[1], cov=R))
            dets.append((t, z, R))
            truth[(r, round(t, 6))] = x.copy()
        per_vehicle.append(dets)
    with tempfile.TemporaryDirectory() as tmp:
        site = make_site(tmp)
        located, out = os.path.join(tmp, "located.csv"), os.path.join(tmp, "tracks.csv")
        write_located(located, rows)
        p = run_track(site, [located], out, "--gate", "0.999999999", "--accel-sigma", str(A), "--init-speed-sigma",
                      str(V0), "--coast", "0")
        check(p.returncode == 0, f"roadside track: {p.stderr}")
        if p.returncode:
            return
        tracks = read_tracks(out)
    # each track belongs to the vehicle whose 1 km cell holds it
    by_track = {}
    for row in tracks:
        r = int(round(row["e_m"] / 1000.0)) + 20 * int(round(row["n_m"] / 1000.0))
        by_track.setdefault(row["track_id"], set()).add(r)
    check(len(by_track) == RUNS and all(len(v) == 1 for v in by_track.values()),
          f"{len(by_track)} tracks for {RUNS} vehicles, each track on one vehicle")
    run_of = {tid: next(iter(v)) for tid, v in by_track.items()}
    oracles = [oracle(d) for d in per_vehicle]
    worst_pos = worst_cov = worst_sh = 0.0
    nees = {}
    for row in tracks:
        r = run_of[row["track_id"]]
        k = int(round(row["time_s"] / DT))
        t, x, P = oracles[r][k]
        worst_pos = max(worst_pos, abs(row["e_m"] - x[0]), abs(row["n_m"] - x[1]))
        worst_cov = max(worst_cov, abs(row["sigma_e_m"] - P[0, 0] ** 0.5), abs(row["sigma_n_m"] - P[1, 1] ** 0.5),
                        abs(row["cov_en_m2"] - P[0, 1]) / max(1e-3, abs(P[0, 1])))
        speed = float(np.hypot(x[2], x[3]))
        heading = float(np.degrees(np.arctan2(x[2], x[3])) % 360)
        dh = abs((row["heading_deg"] - heading + 180) % 360 - 180)
        worst_sh = max(worst_sh, abs(row["speed_mps"] - speed), dh)
        Pc = np.array([[row["sigma_e_m"] ** 2, row["cov_en_m2"]], [row["cov_en_m2"], row["sigma_n_m"] ** 2]])
        e = np.array([row["e_m"], row["n_m"]]) - truth[(r, round(row["time_s"], 6))][:2]
        nees.setdefault(k, []).append(float(e @ np.linalg.solve(Pc, e)))
    print(f"numpy oracle: worst position {worst_pos:.2e} m, covariance {worst_cov:.2e}, speed/heading {worst_sh:.2e}")
    check(worst_pos < 1e-8, f"positions differ from numpy's filter by {worst_pos:.3e} m (tolerance 1e-8)")
    check(worst_cov < 1e-8, f"covariances differ from numpy's filter by {worst_cov:.3e} (tolerance 1e-8)")
    check(worst_sh < 1e-5, f"speed/heading differ from numpy's by {worst_sh:.3e} (tolerance 1e-5)")
    check(sorted(nees) == list(range(2, STEPS)), f"reported steps {sorted(nees)[:3]}...: from the third on (3 of 4)")
    lo, hi = stats.chi2.ppf(0.0005, 2 * RUNS) / RUNS, stats.chi2.ppf(0.9995, 2 * RUNS) / RUNS
    means = {k: float(np.mean(v)) for k, v in nees.items()}
    outside = [(k, m) for k, m in means.items() if not (lo <= m <= hi) or len(nees[k]) != RUNS]
    grand = float(np.mean(list(means.values())))
    print(f"NEES: mean over {RUNS} runs per step in [{min(means.values()):.3f}, {max(means.values()):.3f}], "
          f"bounds [{lo:.3f}, {hi:.3f}]; grand mean {grand:.3f} (2 expected)")
    check(not outside, f"steps whose mean NEES is outside the 99.9 % bounds: {outside}")
    check(abs(grand - 2) < 0.15, f"grand mean NEES {grand:.3f}, expected 2 +- 0.15")


main()
finish("test_track_kf")

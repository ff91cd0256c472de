#!/usr/bin/env python3
"""Issue 13, item 5 (heights a satellite survey does not have), on real data: the GNSS probe
vehicle (../shared/real/gnss_probe_vehicle) with its RAW heights, which the site declares
"landmark_heights": "unreliable", so that roadside's own ground model (geo/rs_site_ground.c)
replaces them -- what tests/calib/test_real_gnss.py does by hand in Python.

Two arms under the leave-one-out protocol of test_real_gnss.py (its functions are imported, so the
hand arm IS that test's protocol): for each of the 43 rows, calibrate on the other 42 with
`roadside calib --refine focal`, locate the left-out box centre with `roadside locate`, and
measure the horizontal distance to its GNSS fix.
  hand:  the 42 heights snapped onto numpy's least-squares plane, sigma_v 0.3 m, that plane as the
         site's ground_plane (test_real_gnss.py);
  model: the 42 raw heights as given, "landmark_heights": "unreliable", no ground_plane: the site
         reader fits the plane, gives each landmark its modelled height and sigma_v, and its plane
         becomes the site's ground plane (what locate uses).
All arms state the same horizontal (1.0 m) and pixel (3 px) sigmas. The model arm is run twice,
with two vertical sigmas stated for the raw heights:
  1.0 m, their own noise, as a site should state raw GNSS heights (docs/site-format.md): the plane
         rests on all of them, the modelled sigma_v comes out at 0.16 .. 0.37 m;
  0.3 m, the hand arm's vertical sigma: the raw heights then scatter more than stated, and the 7
         of the first pass that lie 2.7 .. 3.1 m above the others are left out of the fit (and
         reported) as outliers.

Checks: the heights the reader models lie on numpy's least-squares plane of the points it says it
rests on (an independent oracle; with 1.0 m, all 43; both arms); the 1.0 m arm's leave-one-out
median is the same as the hand arm's or better (within MEDIAN_TOLERANCE_M). The 0.3 m arm's
leave-one-out is test_real_gnss_sigma_sets.py's second set (1.528 m on 2026-11-24, under issue
13's 1.70 m), not run twice. Prints both medians. Skips (77) when the data is absent.
"""
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_real_gnss as base  # noqa: E402  (the hand protocol: rows, ENU, plane, snapping, site)

ROADSIDE = os.environ["ROADSIDE"]
# the vertical sigmas stated for the raw heights: their own noise (raw GNSS heights of a probe
# vehicle: about 1 m, 1-sigma; their scatter about the road plane is 0.99 m here), and the hand
# arm's 0.3 m
RAW_SIGMAS_V_M = (1.0, 0.3)
# leave-one-out runs only the 1.0 m arm: the 0.3 m arm is the sigma set (1.0 m, 0.3 m, 3 px) of
# test_real_gnss_sigma_sets.py, which asserts the issue's bar on it (both tests are in suite slow)
LOO_SIGMAS_V_M = (1.0,)
MEDIAN_TOLERANCE_M = 0.02  # "the same": leave-one-out medians within 2 cm
ISSUE_BAR_M = 1.70  # issue 13: leave-one-out median under 1.70 m on raw heights


def write_raw_site(d, rows, origin, sigma_v):
    """The site a user would write from the raw data: heights as given, declared unreliable."""
    base.write_site(d, rows, origin, (np.array([0.0, 0.0, 1.0]), 0.0))
    p = os.path.join(d, "site.json")
    with open(p) as f:
        site = json.load(f)
    del site["ground_plane"]  # the ground model's plane becomes the site's
    site["landmark_heights"] = "unreliable"
    site["landmark_sigma_m"] = {"horizontal": base.SIGMA_H_M, "vertical": sigma_v}
    with open(p, "w") as f:
        json.dump(site, f, indent=1)


def roadside(*args):
    return subprocess.run([ROADSIDE, *args], capture_output=True, text=True)


def locate_error(d, q, p_true):
    """Calibrates site d, locates pixel q, returns the horizontal distance to p_true (or a message)."""
    p = roadside("calib", d, "--refine", "focal")
    if p.returncode != 0:
        return None, p.stdout + p.stderr
    p = roadside("locate", d, "--camera", "cam", "--", f"{q[0]}", f"{q[1]}")
    if p.returncode != 0:
        return None, p.stderr
    e, n = (float(v) for v in p.stdout.split()[:2])
    if not (math.isfinite(e) and math.isfinite(n)):
        return None, "non-finite location"
    return math.hypot(e - p_true[0], n - p_true[1]), ""


def check_plane(tmp, rows, origin, p_enu, sigma_v):
    """The reader's plane on the 43 raw heights against numpy's least squares on the points it
    rests on (all of them when their stated sigma is their noise)."""
    d = os.path.join(tmp, f"all{sigma_v}")
    write_raw_site(d, rows, origin, sigma_v)
    p = roadside("site", "check", d)
    print(f"site check, raw heights stated at {sigma_v} m:")
    print(p.stdout.strip())
    if p.returncode != 0:
        print(p.stderr)
        return "site check of the raw-height site failed"
    m = re.search(r"rests on (\d+) of (\d+)", p.stdout)
    left_out = set(re.findall(r"id '(fix\d\d)'\): coordinates: warning: height [0-9.]+ m (?:above|below) the plane "
                              r"fitted to the unreliable heights: left out", p.stdout))
    if not m or int(m.group(2)) != len(rows) or int(m.group(1)) != len(rows) - len(left_out):
        return "the ground model does not say which of the %d raw heights it rests on" % len(rows)
    if sigma_v == RAW_SIGMAS_V_M[0] and left_out:
        return "heights stated at their own noise were left out of the fit: %s" % sorted(left_out)
    p = roadside("site", "describe", "--landmarks", d)
    ups = {}
    table = False
    for line in p.stdout.splitlines():
        if line.startswith("landmarks (ENU"):
            table = True
        elif table and line.strip().startswith("fix"):
            f = line.split()
            ups[f[0]] = (float(f[1]), float(f[2]), float(f[3]), float(f[5]), f[6])
    if len(ups) != len(rows) or any(v[4] != "model(unreliable)" for v in ups.values()):
        return "describe does not list every landmark as modelled: %s" % p.stdout
    used = np.array([f"fix{r['i']:02d}" not in left_out for r in rows])
    A = np.c_[np.ones(len(p_enu)), p_enu[:, 0], p_enu[:, 1]]
    coef = np.linalg.lstsq(A[used], p_enu[used, 2], rcond=None)[0]
    worst = 0.0
    for i, r in enumerate(rows):
        e, n, up, sigma_v, _ = ups[f"fix{r['i']:02d}"]
        worst = max(worst, abs(up - (coef[0] + coef[1] * e + coef[2] * n)))
    print(f"modelled heights vs numpy's least-squares plane on the {used.sum()} points used: max difference "
          f"{worst:.2e} m; "
          f"modelled sigma_v {min(v[3] for v in ups.values()):.3f} .. {max(v[3] for v in ups.values()):.3f} m")
    if not worst < 1e-6:
        return "the modelled heights are not on numpy's least-squares plane (%.3g m off)" % worst
    return None


def load_data():
    """The 43 rows numbered (r["i"]), the ENU origin, their ENU fixes and box centres; None (with a
    SKIP line) when the data is absent. Shared with test_real_gnss_sigma_sets.py."""
    if not os.path.exists(base.DATA):
        print(f"SKIP: {base.DATA} is absent (real survey data lives in ../shared/real, never in the repo)")
        return None
    rows = base.load_rows()
    for i, r in enumerate(rows):
        r["i"] = i
    origin = (np.mean([r["lat"] for r in rows]), np.mean([r["lon"] for r in rows]), min(r["h"] for r in rows))
    return rows, origin, base.enu_of(rows, origin), np.array([[r["u"], r["v"]] for r in rows])


def main():
    data = load_data()
    if data is None:
        return 77
    rows, origin, p_enu, q = data

    tmp = tempfile.mkdtemp(prefix="roadside-gnss-raw-")
    try:
        for sigma_v in RAW_SIGMAS_V_M:
            problem = check_plane(tmp, rows, origin, p_enu, sigma_v)
            if problem:
                print("FAIL:", problem)
                return 1
        hand, model = [], {s: [] for s in LOO_SIGMAS_V_M}
        for k in range(len(rows)):
            train = [r for r in rows if r["i"] != k]
            ptrain = np.delete(p_enu, k, axis=0)
            plane = base.fit_plane(ptrain)
            d_hand = os.path.join(tmp, f"hand{k:02d}")
            base.write_site(d_hand, base.snap_to_plane(train, ptrain, plane, origin), origin, plane)
            arms = [(d_hand, hand)]
            for s in LOO_SIGMAS_V_M:
                arms.append((os.path.join(tmp, f"model{s}_{k:02d}"), model[s]))
                write_raw_site(arms[-1][0], train, origin, s)
            for d, out in arms:
                err, why = locate_error(d, q[k], p_enu[k])
                if err is None:
                    print(why)
                    print(f"FAIL: leave-one-out fold {k}: {os.path.basename(d)}: calibration or locate failed")
                    return 1
                out.append(err)
        hand = np.array(hand)
        print(f"leave-one-out ground error, heights snapped by hand (test_real_gnss.py), sigma_v 0.3 m: "
              f"median {np.median(hand):.3f} m, mean {hand.mean():.3f} m, max {hand.max():.3f} m")
        failed = False
        for s in LOO_SIGMAS_V_M:
            e = np.array(model[s])
            print(f"leave-one-out ground error, raw heights \"unreliable\" stated at {s} m (ground model): "
                  f"median {np.median(e):.3f} m, mean {e.mean():.3f} m, max {e.max():.3f} m")
            # issue 13's bar for raw heights: a leave-one-out median under 1.70 m whatever the user
            # states; and the model no worse than the hand snapping with the sigma the hand arm uses
            bar = ISSUE_BAR_M if s != 1.0 else np.median(hand) + MEDIAN_TOLERANCE_M
            if not np.median(e) < bar:
                print(f"FAIL: raw heights stated at {s} m: the ground model's leave-one-out median "
                      f"{np.median(e):.3f} m is not under {bar:.3f} m")
                failed = True
        return 1 if failed else 0
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())

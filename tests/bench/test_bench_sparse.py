#!/usr/bin/env python3
"""roadside bench sparse (issue 38, item 2: "no failure where a homography answers"): sparse,
map-picked sites (6..8 ground points, 0.5 m horizontal survey noise, 3 px, the nominal focal off
by up to 1.5x, `--refine focal`), leave-one-out over each site's points.

Asserted: no fold of any site ends without a pose; few folds' poses put the left-out pick above
the horizon; roadside's leave-one-out median is at most the least-squares homography's (OpenCV's
findHomography, method 0: the bar) on at least SHARE of the sites; the CSV has one row per site
and finite figures. The oracle for the homography's figures: the same homography refitted here by
numpy (normalised DLT: tests/calib/test_real_gnss.py's; within 5% + 2 cm: OpenCV polishes its
DLT by Levenberg-Marquardt) on the first site, from the site files
`roadside site simulate` writes for it. Argument: the number of sites (100 in the normal suite,
1,000 in the slow one), then SHARE.

Measured (docs/benchmarks.md): 1,000 sites, 0 folds without a pose (before: 108), 77% of sites
not worse than the homography (before: 64%); with the TRUE intrinsics held, 88% (the homography
still wins on the rest: 6..8 noisy points), so the issue's 95% is out of reach of any estimate of
the focal on these sites.
"""
import csv
import math
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from rs_check import check, finish  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "calib"))

ROADSIDE = os.environ["ROADSIDE"]
NSITES = int(sys.argv[1]) if len(sys.argv) > 1 else 100
SHARE = float(sys.argv[2]) if len(sys.argv) > 2 else 0.70
SEED = 1


def oracle_first_site(d, row):
    """The first site's homography median, refitted by numpy from the site's own files."""
    import numpy as np
    from test_real_gnss import homography_dlt  # the numpy oracle that test already uses
    site = os.path.join(d, "oracle")
    n = int(row["points"])
    subprocess.run([ROADSIDE, "site", "simulate", site, "--seed", str(SEED), "--cameras", "1", "--points", str(n),
                    "--lens", "LENSMODEL_PINHOLE", "--elevated-fraction", "0", "--landmark-heights", "unknown",
                    "--survey-sigma", "0.5,0", "--pixel-sigma", "3", "--outliers", "0", "--focal-error-range", "1.5"],
                   check=True, capture_output=True)
    truth = {r["id"]: (float(r["e"]), float(r["n"])) for r in csv.DictReader(open(os.path.join(site, "truth",
                                                                                              "landmarks_enu.csv")))}
    obs = list(csv.DictReader(open(os.path.join(site, "observations", "cam1.csv"))))
    ids = [o["landmark"] for o in obs]
    q = np.array([[float(o["u"]), float(o["v"])] for o in obs])
    lonlat = {}
    import json
    for f in json.load(open(os.path.join(site, "landmarks.geojson")))["features"]:
        lonlat[f["properties"]["id"]] = f["geometry"]["coordinates"][:2]
    origin = json.load(open(os.path.join(site, "site.json")))["origin"]
    # the points' heights are unknown (on the ground plane, up = 0): the origin's, which moves E, N
    # by far less than a millimetre here
    text = "".join(f"{lonlat[i][1]!r} {lonlat[i][0]!r} {origin['h']!r}\n" for i in ids)
    o = f"{origin['lat']!r},{origin['lon']!r},{origin['h']!r}"
    p = subprocess.run([ROADSIDE, "geo", "enu", "--origin", o], input=text, capture_output=True, text=True)
    if p.returncode != 0:
        return None
    en = np.array([[float(v) for v in line.split()[:2]] for line in p.stdout.splitlines()])
    errs = []
    for k in range(len(ids)):
        H = homography_dlt(np.delete(q, k, axis=0), np.delete(en, k, axis=0))
        g = H @ np.array([q[k, 0], q[k, 1], 1.0])
        errs.append(math.hypot(g[0] / g[2] - truth[ids[k]][0], g[1] / g[2] - truth[ids[k]][1]))
    return float(np.median(errs))


with tempfile.TemporaryDirectory() as d:
    path = os.path.join(d, "sparse.csv")
    p = subprocess.run([ROADSIDE, "bench", "sparse", "--sites", str(NSITES), "--seed", str(SEED), "--csv", path],
                       capture_output=True, text=True)
    print(p.stdout[-2000:], p.stderr)
    check(p.returncode == 0, "bench sparse exit status %d" % p.returncode)
    rows = list(csv.DictReader(open(path))) if os.path.exists(path) else []
    check(len(rows) == NSITES, "%d CSV rows for %d sites" % (len(rows), NSITES))
    folds = sum(int(r["points"]) for r in rows)
    no_pose = sum(int(r["no_pose"]) for r in rows)
    no_location = sum(int(r["no_location"]) for r in rows)
    not_worse = sum(float(r["loo_median_m"]) <= float(r["homography_median_m"]) for r in rows)
    check(no_pose == 0, "%d of %d folds without a pose (want 0)" % (no_pose, folds))
    check(no_location <= 0.01 * folds, "%d of %d folds put the left-out pick above the horizon (want <= 1%%)" %
          (no_location, folds))
    check(not_worse >= SHARE * NSITES, "roadside not worse than the homography on %d of %d sites (want >= %.0f%%)" %
          (not_worse, NSITES, 100 * SHARE))
    check(all(6 <= int(r["points"]) <= 8 for r in rows), "points per site out of 6..8")
    for r in rows:
        check(math.isfinite(float(r["homography_median_m"])), "site %s: homography median not finite" % r["seed"])
        check(0.66 <= float(r["focal_nominal_rel"]) <= 1.51, "site %s: nominal/true focal %s" %
              (r["seed"], r["focal_nominal_rel"]))
    try:
        import numpy  # noqa: F401
        have_numpy = True
    except ImportError:
        have_numpy = False
    if rows and have_numpy:
        m = oracle_first_site(d, rows[0])
        check(m is not None and abs(m - float(rows[0]["homography_median_m"])) <= 0.05 * m + 0.02,
              "site %s: homography median %s m, numpy's DLT %s m" % (rows[0]["seed"], rows[0]["homography_median_m"], m))
        print("oracle: the first site's homography median, %s m, numpy's DLT %.4f m" %
              (rows[0]["homography_median_m"], m if m is not None else float("nan")))
    print("sites %d, folds %d: no pose %d, no location %d, not worse than the homography %d (%.1f%%)" %
          (NSITES, folds, no_pose, no_location, not_worse, 100.0 * not_worse / max(NSITES, 1)))
finish("bench_sparse")

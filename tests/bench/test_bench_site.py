#!/usr/bin/env python3
"""roadside bench site (issue 14, finding 7: "Quadratic check"): the run completes on two sizes,
the CSV is well formed, and on each site exactly the planted defects were reported -- checked here
from the CSV's counts. The figures themselves (1,000,000 landmarks) are for people:
docs/benchmarks.md. A second, independent site written here by Python (not by geo's writer)
with a repeated id and a copied coordinate among 20,000 landmarks is checked by `site check`
and its messages compared with what was planted."""
import csv
import json
import math
import os
import random
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from rs_check import check, finish  # noqa: E402

ROADSIDE = os.environ["ROADSIDE"]
HEADER = ["landmarks", "picks", "unknown", "file_mib", "write_s", "check_s", "check_cpu_s", "us_per_landmark", "peak_mib",
          "peak_bytes_per_landmark", "errors", "warnings", "found"]

with tempfile.TemporaryDirectory() as d:
    path = os.path.join(d, "site.csv")
    p = subprocess.run([ROADSIDE, "bench", "site", "--landmarks", "2000,20000", "--csv", path],
                       capture_output=True, text=True, timeout=300)
    print(p.stdout, p.stderr)
    check(p.returncode == 0, "bench site exit status %d" % p.returncode)
    rows = list(csv.DictReader(open(path))) if os.path.exists(path) else []
    check(rows and list(rows[0].keys()) == HEADER, "CSV header %s" % (list(rows[0].keys()) if rows else None))
    check([int(r["landmarks"]) for r in rows] == [2000, 20000], "one row per size")
    for r in rows:
        check(r["errors"] == "1" and r["warnings"] == "1" and r["found"] == "1",
              "%s landmarks: %s errors, %s warnings, found %s (want exactly the 2 planted)" %
              (r["landmarks"], r["errors"], r["warnings"], r["found"]))
        for k in ("check_s", "peak_mib", "file_mib"):
            check(math.isfinite(float(r[k])) and float(r[k]) > 0, "%s: %s = %s" % (r["landmarks"], k, r[k]))

    # issue 42 ("site check is O(picks x landmarks)"): a pick of nearly every landmark and 300 rows
    # of unknown ids; each unknown id an error, nothing else
    p = subprocess.run([ROADSIDE, "bench", "site", "--landmarks", "20000", "--picks", "19999", "--unknown", "300",
                        "--csv", path], capture_output=True, text=True, timeout=300)
    print(p.stdout, p.stderr)
    rows = list(csv.DictReader(open(path))) if p.returncode == 0 else []
    check(len(rows) == 1 and rows[0]["picks"] == "19999" and rows[0]["unknown"] == "300" and
          rows[0]["errors"] == "301" and rows[0]["warnings"] == "1" and rows[0]["found"] == "1",
          "picks and unknown ids: exit %d, %s" % (p.returncode, rows))

    # an independent site: written here, a repeated id (feature 19999 repeats 'P00017') and a
    # copied coordinate (feature 19998 at feature 123's position)
    site = os.path.join(d, "indep")
    os.makedirs(os.path.join(site, "cameras"))
    os.makedirs(os.path.join(site, "observations"))
    rng = random.Random(7)
    lat0, lon0, h0 = 48.137, 11.575, 520.0
    feats = []
    for i in range(20000):
        e, n = rng.uniform(-400, 400), rng.uniform(-400, 400)
        lat = lat0 + n / 111195.0
        lon = lon0 + e / (111195.0 * math.cos(math.radians(lat0)))
        feats.append([lon, lat, h0 + rng.uniform(0, 10)])
    feats[19998] = list(feats[123])
    ids = ["P%05d" % i for i in range(20000)]
    ids[19999] = "P00017"
    with open(os.path.join(site, "landmarks.geojson"), "w") as f:
        json.dump({"type": "FeatureCollection", "features": [
            {"type": "Feature", "geometry": {"type": "Point", "coordinates": c}, "properties": {"id": i}}
            for c, i in zip(feats, ids)]}, f)
    with open(os.path.join(site, "site.json"), "w") as f:
        json.dump({"name": "indep", "origin": {"lat": lat0, "lon": lon0, "h": h0}, "heights": "ellipsoidal",
                   "landmark_sigma_m": {"horizontal": 0.3, "vertical": 0.5},
                   "cameras": [{"id": "c1", "model": "cameras/c1.cameramodel", "observations": "observations/c1.csv"}]},
                  f)
    with open(os.path.join(site, "cameras", "c1.cameramodel"), "w") as f:
        f.write("{'lensmodel': 'LENSMODEL_PINHOLE', 'intrinsics': [1000, 1000, 959.5, 539.5],"
                " 'imagersize': [1920, 1080], 'extrinsics': [0, 0, 0, 0, 0, 0]}\n")
    with open(os.path.join(site, "observations", "c1.csv"), "w") as f:
        f.write("landmark,u,v\nP00001,100,100\nP00002,900,200\nP00003,500,800\nP00004,1500,600\n")
    p = subprocess.run([ROADSIDE, "site", "check", site], capture_output=True, text=True, timeout=120)
    out = p.stdout.splitlines()
    check(p.returncode == 1, "site check exit %d (want 1: the repeated id)" % p.returncode)
    check(any("feature 19999 (id 'P00017'): properties.id: duplicate id (already used by feature 17)" in l for l in out),
          "the repeated id is reported against feature 17")
    check(any("feature 19998 (id 'P19998'): coordinates: warning: at the same position as 'P00123' (feature 123"
              in l for l in out), "the copied coordinate is reported against feature 123")
    check(out and out[-1] == "1 error, 1 warning", "summary %r (want exactly what was planted)" % (out[-1:],))
finish("bench_site_quadratic_check")

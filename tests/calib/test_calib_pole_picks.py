#!/usr/bin/env python3
# calib_pole_picks (issue 13 item 4, what calib does with the new landmark kinds today): a pick
# 'along' a pole or a line is refused with the file and line named, nothing half-written; with
# the along picks left out, a pole's base and top picks calibrate, and <id>.json states each top
# pick's surveyed position as the base + height_m straight up (oracle: the site's own
# landmarks.geojson read here, converted with PROJ's cct), within 1 mm.
import csv
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "common"))
from rs_check import check, failures, finish, run  # noqa: E402


def cct_llh_to_enu(origin, lat, lon, h):
    lat0, lon0, h0 = origin
    pipe = ["cct", "-d", "12", "+proj=pipeline", "+step", "+proj=cart", "+ellps=WGS84",
            "+step", "+proj=topocentric", "+ellps=WGS84", f"+lat_0={lat0}", f"+lon_0={lon0}", f"+h_0={h0}"]
    out = subprocess.run(pipe, input=f"{lon} {lat} {h} 0\n", capture_output=True, text=True, check=True).stdout
    return [float(x) for x in out.split()[:3]]


with tempfile.TemporaryDirectory() as tmp:
    site, out = os.path.join(tmp, "site"), os.path.join(tmp, "calib")
    r = run("site", "simulate", site, "--seed", "4", "--cameras", "1", "--poles", "10", "--points", "10")
    check(r.returncode == 0, f"site simulate: {r.stderr}")
    obs = os.path.join(site, "observations", "cam1.csv")
    rows = list(csv.DictReader(open(obs)))
    along = [i for i, row in enumerate(rows) if row.get("at") == "along"]
    check(len(along) > 0, "the simulated site has along picks")
    r = run("calib", site, "-o", out)
    first = along[0] + 2  # header on line 1
    check(f"cam1.csv line {first}: a pick 'along'" in r.stdout + r.stderr,
          f"calib names the file and line of the first along pick (line {first}): {r.stdout}{r.stderr}")
    check(not os.path.exists(os.path.join(out, "cam1.json")), "nothing written for the refused camera")

    keep = [row for row in rows if row.get("at") != "along"]
    with open(obs, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(keep)
    r = run("calib", site, "-o", out)
    check(r.returncode == 0 and os.path.exists(os.path.join(out, "cam1.json")),
          f"calib with base and top picks only: {r.stdout}{r.stderr}")
    sj = json.load(open(os.path.join(site, "site.json")))
    origin = (sj["origin"]["lat"], sj["origin"]["lon"], sj["origin"]["h"])
    feats = {f["properties"]["id"]: f for f in json.load(open(os.path.join(site, "landmarks.geojson")))["features"]}
    res = json.load(open(os.path.join(out, "cam1.json")))
    tops = 0
    for row, lm in zip(keep, res["landmarks"]):
        f = feats[row["landmark"]]
        lon, lat, h = f["geometry"]["coordinates"]
        base = cct_llh_to_enu(origin, lat, lon, h)
        expect = list(base)
        if row.get("at") == "top":
            expect[2] += f["properties"]["height_m"]  # straight up in ENU (docs/site-format.md)
            tops += 1
        err = max(abs(a - b) for a, b in zip(lm["p_enu_surveyed_m"], expect))
        check(lm["id"] == row["landmark"] and err < 1e-3,
              f"{row['landmark']} ({row.get('at')}): p_enu_surveyed_m {lm['p_enu_surveyed_m']} vs {expect} ({err:.2g} m)")
    check(tops > 0, "some top picks were checked")
    print(f"{len(keep)} picks checked, {tops} of them pole tops")
finish("calib_pole_picks")

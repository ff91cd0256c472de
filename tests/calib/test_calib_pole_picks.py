#!/usr/bin/env python3
# calib_pole_picks (issue 13 item 4): picks at a pole's base, top and anywhere along it calibrate
# together; <id>.json states each top pick's surveyed position as the base + height_m straight up,
# and each along pick's as the point of the pole nearest the pick (on the vertical through the
# base, between base and top), the oracle being the site's own landmarks.geojson read here and
# converted with PROJ's cct, within 1 mm; the along picks' surveyed residuals are across the pole (their
# size the pick's distance to the surveyed pole projected by mrcal's Python, within 1e-3 px). Then, with the along picks left out,
# the same checks on the base and top picks.
import csv
import json
import os
import subprocess
import sys
import tempfile

import mrcal
import numpy

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
    sj = json.load(open(os.path.join(site, "site.json")))
    origin = (sj["origin"]["lat"], sj["origin"]["lon"], sj["origin"]["h"])
    feats = {f["properties"]["id"]: f for f in json.load(open(os.path.join(site, "landmarks.geojson")))["features"]}

    def check_picks(picks, what):
        r = run("calib", site, "-o", out)
        check(r.returncode == 0 and os.path.exists(os.path.join(out, "cam1.json")), f"calib {what}: {r.stdout}{r.stderr}")
        if r.returncode:
            return
        res = json.load(open(os.path.join(out, "cam1.json")))
        counts = {"top": 0, "along": 0}
        for row, lm in zip(picks, res["landmarks"]):
            f = feats[row["landmark"]]
            lon, lat, h = f["geometry"]["coordinates"]
            base = cct_llh_to_enu(origin, lat, lon, h)
            expect, got = list(base), lm["p_enu_surveyed_m"]
            at = row.get("at")
            check(lm.get("at") == at, f"{row['landmark']}: at {lm.get('at')} vs {at}")
            if at == "top":
                expect[2] += f["properties"]["height_m"]  # straight up in ENU (docs/site-format.md)
            elif at == "along":  # on the pole: the base's vertical, between base and top
                expect[2] = min(max(got[2], base[2]), base[2] + f["properties"]["height_m"])
                # oracle: the pick's distance to the surveyed pole projected by mrcal's Python
                # (4001 points from base to top through cam1.cameramodel), against the residual
                model = mrcal.cameramodel(os.path.join(out, "cam1.cameramodel"))
                top = base[:2] + [base[2] + f["properties"]["height_m"]]
                P = numpy.linspace(base, top, 4001)
                q = mrcal.project(mrcal.transform_point_rt(model.extrinsics_rt_fromref(), P), *model.intrinsics())
                dist = numpy.min(numpy.linalg.norm(q - numpy.array(lm["observed_px"]), axis=1))
                res_px = numpy.linalg.norm(lm["residual_surveyed_px"])
                step = numpy.max(numpy.linalg.norm(numpy.diff(q, axis=0), axis=1))
                check(abs(res_px - dist) < 1e-3 + step,
                      f"{row['landmark']} along: residual_surveyed {res_px:.4f} px vs distance to the projected "
                      f"pole {dist:.4f} px")
                counts["along"] += 1
            if at in counts and at != "along":
                counts[at] += 1
            err = max(abs(a - b) for a, b in zip(got, expect))
            check(lm["id"] == row["landmark"] and err < 1e-3,
                  f"{row['landmark']} ({at}): p_enu_surveyed_m {got} vs {expect} ({err:.2g} m)")
        print(f"{what}: {len(picks)} picks checked, {counts['top']} pole tops, {counts['along']} along")
        return counts

    c = check_picks(rows, "with the along picks")
    check(c and c["top"] > 0 and c["along"] == len(along), "every along pick was checked")
    keep = [row for row in rows if row.get("at") != "along"]
    with open(obs, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(keep)
    c = check_picks(keep, "with base and top picks only")
    check(c and c["top"] > 0, "some top picks were checked")
finish("calib_pole_picks")

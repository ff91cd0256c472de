#!/usr/bin/env python3
# test_site_load.py -- the loader's landmark and prior ENU coordinates against PROJ's cct
# (an independent geodesy implementation), for ellipsoidal heights and for orthometric heights
# with a geoid undulation N; plus per-landmark sigma overrides and the observation counts.
# Tolerance: 1e-6 m on landmarks (printed with 9 decimals), 1e-3 m on the prior (3 decimals).
import math
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import site_fixture as fx  # noqa: E402

N_GEOID = 47.3


def cct_enu(origin_ell, llh_ell):
    lat0, lon0, h0 = origin_ell
    pipeline = ["+proj=pipeline", "+step", "+proj=cart", "+ellps=WGS84", "+step", "+proj=topocentric",
                "+ellps=WGS84", "+lat_0=%r" % lat0, "+lon_0=%r" % lon0, "+h_0=%r" % h0]
    text = "".join("%r %r %r\n" % (lon, lat, h) for lat, lon, h in llh_ell)
    p = subprocess.run(["cct", "-d", "9"] + pipeline, input=text, capture_output=True, text=True)
    if p.returncode != 0:
        fx.fail("cct failed", p.stdout, p.stderr)
    return [tuple(float(x) for x in line.split()[:3]) for line in p.stdout.splitlines() if line.strip()]


def describe(site):
    rc, out, err = fx.run("site", "describe", "--landmarks", site)
    if rc != 0:
        fx.fail("describe failed", out, err)
    rows, prior = {}, None
    in_table = False
    for line in out.splitlines():
        if line.startswith("landmarks (ENU"):
            in_table = True
            continue
        if "position prior: ENU" in line:
            inside = line.split("(")[1].split(")")[0]
            prior = tuple(float(x) for x in inside.split(","))
        if in_table and line.strip() and not line.strip().startswith("id "):
            f = line.split()
            rows[f[0]] = tuple(float(x) for x in f[1:6])
    return rows, prior, out


def check(heights, h_offset, label):
    with fx.TempSite(heights=heights, h_offset=h_offset) as site:
        rows, prior, out = describe(site)
        g = fx.load_json(os.path.join(site, "landmarks.geojson"))
        sj = fx.load_json(os.path.join(site, "site.json"))
    N = 0.0 if heights == "ellipsoidal" else heights["orthometric"]
    o = sj["origin"]
    origin = (o["lat"], o["lon"], o["h"] + N)
    llh = [(f["geometry"]["coordinates"][1], f["geometry"]["coordinates"][0],
            f["geometry"]["coordinates"][2] + N) for f in g["features"]]
    ids = [f["properties"]["id"] for f in g["features"]]
    ref = cct_enu(origin, llh)
    if len(rows) != len(ids):
        fx.fail("%s: %d landmarks printed, %d in the file" % (label, len(rows), len(ids)), out)
    worst = 0.0
    for i, (lid, r) in enumerate(zip(ids, ref)):
        got = rows[lid]
        for k in range(3):
            if not math.isfinite(got[k]):
                fx.fail("%s: %s: non-finite ENU" % (label, lid), out)
            worst = max(worst, abs(got[k] - r[k]))
        want_sigma = (0.05, 0.08) if lid == "L04" else (0.3, 0.5)
        if got[3:5] != want_sigma:
            fx.fail("%s: %s: sigmas %s, expected %s" % (label, lid, got[3:5], want_sigma), out)
    if worst > 1e-6:
        fx.fail("%s: landmark ENU differs from cct by %.3g m (> 1e-6)" % (label, worst), out)
    p = sj["cameras"][1]["position_prior"]
    pref = cct_enu(origin, [(p["lat"], p["lon"], p["h"] + N)])[0]
    dp = max(abs(a - b) for a, b in zip(prior, pref))
    if not dp <= 1e-3:
        fx.fail("%s: prior ENU %s, cct %s" % (label, prior, pref), out)
    for cam, n in (("north", 7), ("south", 7)):
        if "observations: %d in SITE/observations/%s.csv" % (n, cam) not in out:
            fx.fail("%s: camera %s should have %d observations" % (label, cam, n), out)
    print("%s: %d landmarks, max |ENU - cct| = %.2e m, prior %.2e m" % (label, len(ids), worst, dp))
    return rows


def main():
    ell = check("ellipsoidal", 0.0, "ellipsoidal")
    # The same physical points written as orthometric heights h - N: same ENU expected.
    orth = check({"orthometric": N_GEOID}, -N_GEOID, "orthometric N=%.1f" % N_GEOID)
    worst = max(abs(ell[k][i] - orth[k][i]) for k in ell for i in range(3))
    if worst > 1e-6:
        fx.fail("orthometric site differs from the ellipsoidal one by %.3g m: N applied wrongly" % worst)
    print("orthometric vs ellipsoidal: %.2e m" % worst)


if __name__ == "__main__":
    main()

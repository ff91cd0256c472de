#!/usr/bin/env python3
"""test_site_heights_model.py DUMP ROUNDTRIP CASE -- issue 13, item 5: heights a satellite survey
does not have. A site says its landmark heights are "unreliable" or "unknown" (site.json
"landmark_heights", properties.height); the reader gives them heights from its ground model
(geo/rs_site_ground.c). Each CASE builds a site from the fixture (site_fixture.py) with heights
drawn from a known plane (fixed seed), loads it through the C API (site_api_dump.c, every number
with 17 digits) and `roadside site check|describe`, and checks against independent oracles:

  plane_outlier    surveyed heights with one gross outlier, unknown heights given as [lon, lat]:
                   the outlier is left out (and reported), the plane equals numpy's least squares
                   on the other points (1e-9), the covariance, the road's scatter and every
                   modelled sigma_v equal the closed-form prediction variance
                   x^T s^2 (A^T A)^-1 x + scatter^2 (1e-6 relative: the oracle's ENU comes from
                   `roadside geo enu`, printed to 1e-9 m), and the modelled heights lie on the
                   plane (1e-6 m); the points left out are exactly those the documented rule
                   leaves out; a plain least-squares plane through the outlier is tilted
  unreliable_only  no surveyed height: the plane rests on the unreliable heights themselves;
                   their given heights are kept, the mean given - model is 0 (least squares with
                   an intercept), and the fitted plane becomes the site's ground plane
  mixed            per-landmark overrides in a surveyed site: unreliable and unknown landmarks,
                   an unknown height given anyway (ignored), above_ground_m (left out of the fit,
                   modelled above the plane), an unreliable height 5 m off (a warning naming it,
                   and the summary); and a site "unknown" site-wide with surveyed overrides
  datum_offset     unreliable heights 47 m above the surveyed plane (orthometric against
                   ellipsoidal): every one disagrees, the summary gives the mean offset
  site_plane       no height to fit: the site's ground_plane gives the heights with the stated
                   sigma (and a warning when there were 1 or 2 heights); a vertical ground_plane
                   is an error
  errors           bad values of landmark_heights, properties.height, above_ground_m and
                   coordinates: errors naming the file, feature and field
  roundtrip        geo's writers write back what was given ([lon, lat] for unknown heights, the
                   given height and sigma, height, above_ground_m), and the copy models the same
  many             8000 landmarks, 20 % of the surveyed heights gross outliers: all of them left
                   out, the plane equals numpy's on the points kept
  unchanged        the fixture as it always was: no model, every height surveyed and kept
"""
import json
import math
import os
import random
import re
import shutil
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "common"))
import site_fixture as fx  # noqa: E402
from rs_check import check, finish  # noqa: E402

SEED = 20261301
FLOOR = 0.05  # RS_SITE_GROUND_SCATTER_MIN_M
K = 3.0  # RS_SITE_GROUND_REJECT_K, RS_SITE_GROUND_DISAGREE_K
H0 = fx.ORIGIN[2]


def plane_true(e, n):
    return 0.4 + 0.03 * e - 0.02 * n


def feature(fid, e, n, u, props=None, two=False, h=None):
    lat, lon, hh = fx.llh_from_enu(e, n, u)
    coords = [lon, lat] if two else [lon, lat, hh if h is None else h]
    p = {"id": fid}
    p.update(props or {})
    return {"type": "Feature", "geometry": {"type": "Point", "coordinates": coords}, "properties": p}


def write_site(site, features, sigma_v=None, landmark_heights=None, ground_plane="keep"):
    sj = fx.site_json()  # the fixture's, afresh
    if sigma_v is not None:
        sj["landmark_sigma_m"]["vertical"] = sigma_v
    if landmark_heights is not None:
        sj["landmark_heights"] = landmark_heights
    if ground_plane is None:
        del sj["ground_plane"]
    elif ground_plane != "keep":
        sj["ground_plane"] = ground_plane
    with open(os.path.join(site, "site.json"), "w") as f:
        json.dump(sj, f, indent=1)
    with open(os.path.join(site, "landmarks.geojson"), "w") as f:
        json.dump({"type": "FeatureCollection", "features": features}, f, indent=1)


def observed(rng, noise, props=None, outlier=None):
    """L00..L09 (the ones the fixture's cameras observe) on the true plane plus noise."""
    feats = []
    for i in range(10):
        e, n = rng.uniform(-60, 60), rng.uniform(-60, 60)
        u = plane_true(e, n) + rng.gauss(0, noise) + (outlier[1] if outlier and outlier[0] == i else 0)
        feats.append(feature("L%02d" % i, e, n, u, dict(props or {})))
    return feats


def dump(site):
    p = subprocess.run([DUMP, site], capture_output=True, text=True, errors="replace")
    if p.returncode != 0 or "Sanitizer" in p.stderr or "runtime error:" in p.stderr:
        fx.fail("site_api_dump failed", p.stdout, p.stderr)
    d = {"lheight": {}, "raw": p.stdout}
    for line in p.stdout.splitlines():
        k, _, v = line.partition(" ")
        if k == "lheight":
            f = v.split()
            d["lheight"][f[0]] = dict(
                stated=f[1], height=f[2], modelled=f[3] == "1", used=f[4] == "1",
                **{name: float(x) for name, x in zip(
                    ("above", "given_h", "given_up", "given_sigma", "sigma_v", "h", "e", "n", "u", "pred_up",
                     "pred_sigma"), f[5:])})
        elif k == "ground_model":
            f = v.split()
            ints = [int(x) for x in f[:6]]
            x = [float(t) for t in f[6:]]
            d["model"] = dict(source=ints[0], Nmodelled=ints[1], Nunreliable=ints[2], Nunknown=ints[3],
                              Ncandidates=ints[4], Nused=ints[5], centre=x[0:2], up=x[2], slope=x[3:5],
                              cov=np.array(x[5:14]).reshape(3, 3), rms=x[14], stated=x[15], scale=x[16],
                              scatter=x[17], smin=x[18], smax=x[19], mean_diff=x[20], max_diff=x[21],
                              Ndisagree=int(f[-1]))
        else:
            d[k] = v
    return d


def loaded(d, what):
    return check(d.get("status") == "0 success", "%s: the site loads (%s)" % (what, d.get("message")))


def oracle_plane(points, stated):
    """numpy's least squares on (e, n, up) rows and the closed-form uncertainty of geo/rs_site.h."""
    P = np.array(points)
    c = P[:, :2].mean(0)
    A = np.c_[np.ones(len(P)), P[:, 0] - c[0], P[:, 1] - c[1]]
    coef, rss, _, _ = np.linalg.lstsq(A, P[:, 2], rcond=None)
    n = len(P)
    rss = float(np.sum((P[:, 2] - A @ coef) ** 2))
    stated_rms = math.sqrt(np.mean(np.square(stated)))
    s = math.sqrt(rss / (n - 3)) if n > 3 else float("nan")
    scale = max(s, stated_rms) if n > 3 else stated_rms
    cov = scale ** 2 * np.linalg.inv(A.T @ A)
    scatter = math.sqrt(max(s * s - stated_rms ** 2, FLOOR ** 2)) if n > 3 else FLOOR
    return dict(c=c, coef=coef, cov=cov, s=s, stated=stated_rms, scale=scale, scatter=scatter)


def predict(o, e, n):
    x = np.array([1.0, e - o["c"][0], n - o["c"][1]])
    return float(o["coef"] @ x), math.sqrt(float(x @ o["cov"] @ x))


def rel(a, b):
    return abs(a - b) / max(abs(b), 1e-300)


def check_model(d, o, what):
    """The reader's plane and uncertainty against the numpy oracle o."""
    m = d["model"]
    check(np.allclose(m["centre"], o["c"], rtol=0, atol=1e-9), "%s: centre %s vs %s" % (what, m["centre"], o["c"]))
    check(abs(m["up"] - o["coef"][0]) < 1e-9 and np.allclose(m["slope"], o["coef"][1:], rtol=0, atol=1e-11),
          "%s: plane up %.12g slope %s vs numpy %s" % (what, m["up"], m["slope"], o["coef"]))
    # s comes from residuals of centimetres, the oracle's ENU from `geo enu` printed to 1e-9 m:
    # 1e-6 relative
    check(np.allclose(m["cov"], o["cov"], rtol=1e-6, atol=1e-15), "%s: covariance differs from s^2 (A^T A)^-1" % what)
    check(rel(m["scale"], o["scale"]) < 1e-6 and rel(m["scatter"], o["scatter"]) < 1e-6 and
          rel(m["stated"], o["stated"]) < 1e-12,
          "%s: scale %.12g scatter %.12g stated %.12g vs %.12g %.12g %.12g" % (
              what, m["scale"], m["scatter"], m["stated"], o["scale"], o["scatter"], o["stated"]))


def check_rule(d, site, candidates, o, what):
    """The set a plane rests on is the fixed point of the documented rule: a candidate is used iff
    its residual is within 3 x max(robust sigma, hypot(stated sigma_v, 0.05)), the robust sigma being
    1.4826 x the median absolute residual of all candidates x sqrt(n / (n - 3))."""
    P = np.array(points_of(site, candidates))
    r = np.abs(P[:, 2] - np.array([predict(o, e, n)[0] for e, n, _ in P]))
    n = len(candidates)
    sigma = 1.4826 * float(np.median(r)) * math.sqrt(n / (n - 3))
    for lid, ri in zip(candidates, r):
        limit = K * max(sigma, math.hypot(d["lheight"][lid]["given_sigma"], FLOOR))
        check(d["lheight"][lid]["used"] == (ri <= limit),
              "%s: %s: residual %.4f m, limit %.4f m, used %s" % (what, lid, ri, limit, d["lheight"][lid]["used"]))
    print("%s: %d of %d candidates used, as the rule says (robust sigma %.3f m)" % (
        what, sum(d["lheight"][i]["used"] for i in candidates), n, sigma))


def check_modelled(d, o, ids, what, above=None):
    """Modelled landmarks on the oracle plane, with the closed-form sigma_v."""
    worst_up, worst_sigma = 0.0, 0.0
    for lid in ids:
        L = d["lheight"][lid]
        up, sp = predict(o, L["e"], L["n"])
        up += (above or {}).get(lid, 0.0)
        sigma = math.sqrt(sp * sp + o["scatter"] ** 2)
        check(L["modelled"], "%s: %s is not modelled" % (what, lid))
        worst_up = max(worst_up, abs(L["u"] - up))
        worst_sigma = max(worst_sigma, rel(L["sigma_v"], sigma), rel(L["pred_sigma"], sp))
        check(abs(L["pred_up"] + (above or {}).get(lid, 0.0) - up) < 1e-9,
              "%s: rs_site_ground_predict up at %s: %.12g vs %.12g" % (what, lid, L["pred_up"], up))
    check(worst_up < 1e-6, "%s: modelled heights off the plane by %.3g m" % (what, worst_up))
    check(worst_sigma < 1e-6, "%s: modelled sigma_v off the closed form by %.3g (relative)" % (what, worst_sigma))
    print("%s: %d modelled heights on numpy's plane within %.1e m, sigma_v = closed form within %.1e" % (
        what, len(ids), worst_up, worst_sigma))


def points_of(site, ids):
    """ENU of the landmarks `ids` as given in SITE/landmarks.geojson (the points a plane rests on:
    a modelled landmark's own ENU moves by micrometres as its height changes), through `roadside
    geo enu` (tested against PROJ's cct)."""
    feats = {f["properties"]["id"]: f for f in fx.load_json(os.path.join(site, "landmarks.geojson"))["features"]}
    text = "".join("%.17g %.17g %.17g\n" % (feats[i]["geometry"]["coordinates"][1],
                                            feats[i]["geometry"]["coordinates"][0],
                                            feats[i]["geometry"]["coordinates"][2]) for i in ids)
    p = subprocess.run([fx.roadside(), "geo", "enu", "--origin", "%.17g,%.17g,%.17g" % fx.ORIGIN], input=text,
                       capture_output=True, text=True)
    if p.returncode != 0:
        fx.fail("roadside geo enu failed", p.stdout, p.stderr)
    return [tuple(float(x) for x in line.split()[:3]) for line in p.stdout.splitlines() if line.strip()]


def stated_of(d, ids):
    return [d["lheight"][i]["given_sigma"] for i in ids]


# ---- cases ----

def case_plane_outlier(site):
    rng = random.Random(SEED)
    feats = observed(rng, 0.12, outlier=(7, 6.0))
    feats[4]["properties"]["sigma_v_m"] = 0.08
    unknown = ["U%02d" % i for i in range(5)]
    for fid in unknown:
        feats.append(feature(fid, rng.uniform(-80, 80), rng.uniform(-80, 80), 0, {"height": "unknown"}, two=True))
    write_site(site, feats, sigma_v=0.02)
    d = dump(site)
    if not loaded(d, "plane_outlier"):
        return
    m = d["model"]
    used = [i for i, L in d["lheight"].items() if L["used"]]
    check(m["source"] == 1 and m["Ncandidates"] == 10 and m["Nused"] == len(used) >= 8 and m["Nunknown"] == 5 and
          "L07" not in used, "plane_outlier: source/candidates/used %s, used %s" % (
              {k: m[k] for k in ("source", "Ncandidates", "Nused")}, used))
    o = oracle_plane(points_of(site, used), stated_of(d, used))
    check_model(d, o, "plane_outlier")
    check_rule(d, site, ["L%02d" % i for i in range(10)], o, "plane_outlier")
    check(o["scatter"] > FLOOR * 1.5, "plane_outlier: the scatter path above the floor is exercised")
    check_modelled(d, o, unknown, "plane_outlier")
    tilted = oracle_plane(points_of(site, ["L%02d" % i for i in range(10)]), [0.02] * 10)
    tilt = math.hypot(*(tilted["coef"][1:] - o["coef"][1:]))
    check(tilt > 0.01, "plane_outlier: least squares through the outlier is tilted by only %.4f" % tilt)
    print("plane_outlier: the outlier would have tilted a plain least-squares plane by %.1f %%" % (100 * tilt))
    rc, out, _ = fx.run("site", "check", site)
    check(rc == 0, "plane_outlier: check exit %d" % rc)
    check(re.search(r"^SITE/landmarks\.geojson: feature 7 \(id 'L07'\): coordinates: warning: height 5\.\d\d m above "
                    r"the plane fitted to the surveyed heights: left out of that fit as an outlier", out, re.M),
          "plane_outlier: the outlier is reported\n" + out)
    check("ground model: plane fitted to the surveyed heights: rests on %d of 10 (%d left out as outliers)" % (
        len(used), 10 - len(used)) in out, "plane_outlier: check prints the model\n" + out)
    rc, out, _ = fx.run("site", "describe", "--landmarks", site)
    rows = [l.split() for l in out.splitlines() if re.match(r"^  [LU]\d\d ", l)]
    check(len(rows) == 15 and all(r[6] == ("model(unknown)" if r[0][0] == "U" else "surveyed") for r in rows),
          "plane_outlier: describe --landmarks tells where each height comes from\n" + out)
    g = math.hypot(*o["coef"][1:])
    check(re.search(r"slope %.2f %% falling towards azimuth" % (100 * g), out),
          "plane_outlier: describe gives the slope %.2f %%\n%s" % (100 * g, out))


def case_unreliable_only(site):
    rng = random.Random(SEED + 1)
    feats = observed(rng, 0.4)
    for i in range(10):
        e, n = rng.uniform(-70, 70), rng.uniform(-70, 70)
        feats.append(feature("R%02d" % i, e, n, plane_true(e, n) + rng.gauss(0, 0.4)))
    write_site(site, feats, landmark_heights="unreliable", ground_plane=None)
    given = {f["properties"]["id"]: f["geometry"]["coordinates"][2] for f in feats}
    d = dump(site)
    if not loaded(d, "unreliable_only"):
        return
    m = d["model"]
    ids = list(given)
    check(m["source"] == 2 and m["Nused"] == 20 and m["Nmodelled"] == 20 and m["Nunreliable"] == 20,
          "unreliable_only: %s" % {k: m[k] for k in ("source", "Nused", "Nmodelled", "Nunreliable")})
    o = oracle_plane(points_of(site, ids), stated_of(d, ids))
    check_model(d, o, "unreliable_only")
    check_modelled(d, o, ids, "unreliable_only")
    check(all(abs(d["lheight"][i]["given_h"] - given[i]) < 1e-9 for i in ids), "unreliable_only: given heights kept")
    check(abs(m["mean_diff"]) < 1e-9, "unreliable_only: mean given - model %.3g (least squares: 0)" % m["mean_diff"])
    # the fitted plane is the site's ground plane (no ground_plane in site.json)
    gp = [float(x) for x in d["ground"].split()]
    nv = np.array([-o["coef"][1], -o["coef"][2], 1.0])
    nv /= np.linalg.norm(nv)
    off = (o["coef"][0] - o["coef"][1] * o["c"][0] - o["coef"][2] * o["c"][1]) * nv[2]
    check(np.allclose(gp[:3], nv, atol=1e-12) and abs(gp[3] - off) < 1e-9,
          "unreliable_only: site ground plane %s vs the model's %s %.12g" % (gp, nv, off))
    rc, out, _ = fx.run("site", "describe", site)
    check("(none in site.json: the ground model's plane)" in out and
          'heights: "unreliable" site-wide; 0 surveyed, 20 unreliable, 0 unknown' in out,
          "unreliable_only: describe\n" + out)


def mixed_features(rng):
    feats = observed(rng, 0.03)
    offsets = {}
    for i in range(4):
        e, n = rng.uniform(-60, 60), rng.uniform(-60, 60)
        off = 5.0 if i == 3 else 0.0
        feats.append(feature("R%02d" % i, e, n, plane_true(e, n) + rng.gauss(0, 0.2) + off,
                             {"height": "unreliable", "sigma_v_m": 0.3}))
    feats.append(feature("U00", 12.0, -30.0, 0, {"height": "unknown"}, two=True))
    feats.append(feature("U01", -25.0, 40.0, 0, {"height": "unknown", "note": "height given anyway"}, h=9000.0))
    feats.append(feature("U02", 30.0, 30.0, 0, {"height": "unknown", "above_ground_m": 2.5}, two=True))
    feats.append(feature("S00", -10.0, 5.0, plane_true(-10.0, 5.0) + 4.0, {"above_ground_m": 4.0,
                                                                            "kind": "sign_top"}))
    return feats


def case_mixed(site):
    write_site(site, mixed_features(random.Random(SEED + 2)), sigma_v=0.02)
    d = dump(site)
    if not loaded(d, "mixed"):
        return
    m = d["model"]
    check(m["source"] == 1 and m["Ncandidates"] == 10 and m["Nused"] == 10 and m["Nmodelled"] == 7 and
          m["Nunreliable"] == 4 and m["Nunknown"] == 3 and m["Ndisagree"] == 1,
          "mixed: %s" % {k: m[k] for k in ("source", "Ncandidates", "Nused", "Nmodelled", "Nunreliable", "Nunknown",
                                           "Ndisagree")})
    surveyed = ["L%02d" % i for i in range(10)]
    o = oracle_plane(points_of(site, surveyed), stated_of(d, surveyed))
    check_model(d, o, "mixed")
    check_modelled(d, o, ["R00", "R01", "R02", "R03", "U00", "U01", "U02"], "mixed", above={"U02": 2.5})
    L = d["lheight"]
    check(L["U01"]["stated"] == "unknown" and math.isnan(L["U01"]["given_h"]) and abs(L["U01"]["u"]) < 10,
          "mixed: the height given with an unknown one is ignored (%s)" % L["U01"])
    check(not L["S00"]["modelled"] and not L["S00"]["used"] and L["S00"]["height"] == "surveyed" and
          abs(L["S00"]["u"] - L["S00"]["given_up"]) < 1e-12,
          "mixed: a surveyed point above the ground keeps its height and carries no plane (%s)" % L["S00"])
    check(all(L["L%02d" % i]["stated"] == "default" and L["L%02d" % i]["height"] == "surveyed" for i in range(10)),
          "mixed: landmarks without a property follow the site")
    rc, out, _ = fx.run("site", "check", site)
    check(rc == 0 and out.splitlines()[-1] == "0 errors, 2 warnings", "mixed: check\n" + out)
    check(re.search(r"^SITE/landmarks\.geojson: feature 13 \(id 'R03'\): coordinates: warning: the given \(unreliable\) "
                    r"height is [45]\.\d\d m above the plane fitted to the surveyed heights, more than 3 sigma", out,
                    re.M), "mixed: R03's disagreement is reported\n" + out)
    check(re.search(r"^SITE/site\.json: landmark_heights: warning: 1 of 4 given unreliable heights differ from the "
                    r"plane fitted to the surveyed heights by more than 3 sigma", out, re.M),
          "mixed: the summary warning\n" + out)
    check("7 heights modelled (4 unreliable, 3 unknown)" in out,
          "mixed: check prints the counts\n" + out)

    # the other way round: unknown site-wide, surveyed where the survey has heights
    rng = random.Random(SEED + 3)
    feats = observed(rng, 0.05, props={"height": "surveyed"})
    for i in range(5):
        feats.append(feature("U%02d" % i, rng.uniform(-50, 50), rng.uniform(-50, 50), 0, two=True))
    write_site(site, feats, sigma_v=0.02, landmark_heights="unknown")
    d = dump(site)
    if loaded(d, "mixed (unknown site-wide)"):
        m = d["model"]
        check(m["source"] == 1 and m["Nused"] == 10 and m["Nunknown"] == 5 and
              all(d["lheight"]["U%02d" % i]["stated"] == "default" and d["lheight"]["U%02d" % i]["height"] ==
                  "unknown" for i in range(5)), "mixed (unknown site-wide): %s" % m)
        ids = ["L%02d" % i for i in range(10)]
        o = oracle_plane(points_of(site, ids), stated_of(d, ids))
        check_modelled(d, o, ["U%02d" % i for i in range(5)], "mixed (unknown site-wide)")


def case_datum_offset(site):
    rng = random.Random(SEED + 4)
    feats = observed(rng, 0.03)
    for i in range(6):
        e, n = rng.uniform(-60, 60), rng.uniform(-60, 60)
        feats.append(feature("R%02d" % i, e, n, plane_true(e, n) + 47.0 + rng.gauss(0, 0.2),
                             {"height": "unreliable", "sigma_v_m": 0.3}))
    write_site(site, feats, sigma_v=0.02)
    d = dump(site)
    if not loaded(d, "datum_offset"):
        return
    m = d["model"]
    check(m["Ndisagree"] == 6 and abs(m["mean_diff"] - 47.0) < 0.3,
          "datum_offset: %d disagree, mean given - model %.3f m (47 expected)" % (m["Ndisagree"], m["mean_diff"]))
    rc, out, _ = fx.run("site", "check", site)
    check(re.search(r"^SITE/site\.json: landmark_heights: warning: 6 of 6 given unreliable heights differ from the "
                    r"plane fitted to the surveyed heights by more than 3 sigma .*mean given - model \+4[67]\.\d\d m.*"
                    r"heights in another system", out, re.M), "datum_offset: the summary hints at the height system\n"
          + out)


def case_site_plane(site):
    rng = random.Random(SEED + 5)
    feats = [feature("L%02d" % i, rng.uniform(-60, 60), rng.uniform(-60, 60), 0, two=True) for i in range(10)]
    feats[4]["properties"]["sigma_v_m"] = 0.08
    plane = {"normal_enu": [0.02, -0.01, 1.0], "offset_m": 0.5}
    write_site(site, feats, landmark_heights="unknown", ground_plane=plane)
    d = dump(site)
    if loaded(d, "site_plane"):
        gp = [float(x) for x in d["ground"].split()]
        worst = 0.0
        for lid, L in d["lheight"].items():
            up = (gp[3] - gp[0] * L["e"] - gp[1] * L["n"]) / gp[2]
            worst = max(worst, abs(L["u"] - up))
            check(L["sigma_v"] == L["given_sigma"] == (0.08 if lid == "L04" else 0.5),
                  "site_plane: %s keeps its stated sigma (%g)" % (lid, L["sigma_v"]))
        check(d["model"]["source"] == 3 and worst < 1e-6,
              "site_plane: source %d, heights off the ground_plane by %.3g m" % (d["model"]["source"], worst))
        rc, out, _ = fx.run("site", "check", site)
        check(rc == 0 and out.splitlines()[-1] == "0 errors, 0 warnings" and
              "ground model: the site's ground_plane" in out, "site_plane: check\n" + out)
    # two surveyed heights: too few to fit, said
    feats[0] = feature("L00", 5.0, 5.0, 0.3, {"height": "surveyed"})
    feats[1] = feature("L01", -5.0, 9.0, 0.2, {"height": "surveyed"})
    write_site(site, feats, landmark_heights="unknown", ground_plane=plane)
    rc, out, _ = fx.run("site", "check", site)
    check(rc == 0 and re.search(r"^SITE/site\.json: landmark_heights: warning: 2 heights on the ground to fit a ground "
                                r"plane to \(at least 3, not on one line, are needed\)", out, re.M),
          "site_plane: too few heights is said\n" + out)
    # a vertical ground plane gives no height
    write_site(site, feats, landmark_heights="unknown", ground_plane={"normal_enu": [1, 0, 0], "offset_m": 0})
    rc, out, _ = fx.run("site", "check", site)
    # (issue 42: any ground plane over 45 degrees from level is refused, heights modelled or not)
    check(rc == 1 and re.search(r"^SITE/site\.json: ground_plane\.normal_enu: \[1, 0, 0\] tilts the ground 90\.0 degrees "
                                r"from level: at most 45", out, re.M), "site_plane: vertical\n" + out)


def case_errors(site):
    rng = random.Random(SEED + 6)
    base = observed(rng, 0.03)

    def expect(what, pattern, features=None, **kw):
        write_site(site, features or base, **kw)
        rc, out, _ = fx.run("site", "check", site)
        check(rc == 1 and re.search(pattern, out, re.M), "errors: %s\n%s" % (what, out))
        d = dump(site)
        check(d.get("site_is_null") == "1" and re.search(pattern.lstrip("^"), d.get("message", "")),
              "errors: %s: rs_site_load refuses with the same message (%s)" % (what, d.get("message")))

    expect("landmark_heights not a kind", r"^SITE/site\.json: landmark_heights: 'maybe': expected \"surveyed\", "
           r"\"unreliable\" \(given but noisy: raw GNSS\) or \"unknown\"", landmark_heights="maybe")
    expect("landmark_heights a number", r"^SITE/site\.json: landmark_heights: 3: expected \"surveyed\"",
           landmark_heights=3)

    def with_props(i, **props):
        f = json.loads(json.dumps(base))
        f[i]["properties"].update(props)
        return f
    expect("properties.height a number", r"^SITE/landmarks\.geojson: feature 2 \(id 'L02'\): properties\.height: 2\.5: "
           r"expected .*\(a height itself is the third of the coordinates\)", with_props(2, height=2.5))
    expect("properties.height not a kind", r"^SITE/landmarks\.geojson: feature 3 \(id 'L03'\): properties\.height: "
           r"'guess': expected", with_props(3, height="guess"))
    expect("above_ground_m negative", r"^SITE/landmarks\.geojson: feature 1 \(id 'L01'\): properties\.above_ground_m: "
           r"-1 m is outside \[0, 1000\] m", with_props(1, above_ground_m=-1))
    expect("above_ground_m text", r"^SITE/landmarks\.geojson: feature 1 \(id 'L01'\): properties\.above_ground_m: ",
           with_props(1, above_ground_m="high"))
    f = json.loads(json.dumps(base))
    f[5]["geometry"]["coordinates"] = f[5]["geometry"]["coordinates"][:2]
    expect("no height, not unknown", r"^SITE/landmarks\.geojson: feature 5 \(id 'L05'\): coordinates: the height is "
           r"missing: expected \[lon, lat, h\] \(a point picked on imagery, without a height, says so: "
           r"properties\.height \"unknown\"", f)
    f = with_props(6, height="unknown")
    f[6]["geometry"]["coordinates"] = f[6]["geometry"]["coordinates"] + [1.0]
    expect("4 coordinates", r"^SITE/landmarks\.geojson: feature 6 \(id 'L06'\): coordinates: expected \[lon, lat, h\] "
           r"\(3 numbers\) or \[lon, lat\] \(the height is unknown\)", f)
    f = with_props(6, height="unknown")
    f[6]["geometry"]["coordinates"] = f[6]["geometry"]["coordinates"][:1]
    expect("1 coordinate", r"^SITE/landmarks\.geojson: feature 6 \(id 'L06'\): coordinates: expected", f)


def case_roundtrip(site):
    write_site(site, mixed_features(random.Random(SEED + 2)), sigma_v=0.02)
    before = dump(site)
    os.makedirs("OUT")
    shutil.copytree(os.path.join(site, "cameras"), os.path.join("OUT", "cameras"))
    os.makedirs(os.path.join("OUT", "observations"))
    os.makedirs(os.path.join("OUT", "backgrounds", "north"))
    p = subprocess.run([ROUNDTRIP, site, "OUT", "hand"], capture_output=True, text=True)
    if not check(p.returncode == 0 and "status 0 done" in p.stdout, "roundtrip: the writers ran\n" + p.stdout):
        return
    written = {f["properties"]["id"]: f for f in fx.load_json(os.path.join("OUT", "landmarks.geojson"))["features"]}
    given = {f["properties"]["id"]: f for f in fx.load_json(os.path.join(site, "landmarks.geojson"))["features"]}
    for lid, f in written.items():
        c, g, props = f["geometry"]["coordinates"], given[lid]["geometry"]["coordinates"], f["properties"]
        if lid.startswith("U"):
            check(len(c) == 2, "roundtrip: %s: an unknown height is written [lon, lat]: %s" % (lid, c))
        else:
            check(len(c) == 3 and abs(c[2] - g[2]) < 1e-9, "roundtrip: %s: the given height %s, not %s" % (lid, g, c))
        for key in ("height", "above_ground_m"):
            check(props.get(key) == given[lid]["properties"].get(key),
                  "roundtrip: %s: %s %r vs %r" % (lid, key, props.get(key), given[lid]["properties"].get(key)))
        if lid.startswith("R"):
            check(props.get("sigma_v_m") == 0.3, "roundtrip: %s: the stated sigma_v, not the model's" % lid)
    after = dump("OUT")
    if loaded(after, "roundtrip copy"):
        # cJSON prints a number to within an ulp of it (1e-9 m in a latitude): not exactly
        worst = max(max(abs(after["lheight"][i][k] - L[k]) for k in ("u", "sigma_v", "h"))
                    for i, L in before["lheight"].items())
        check(worst < 1e-8, "roundtrip: the copy models heights %.3g off the original's" % worst)
        print("roundtrip: the copy of the mixed site models the same heights and sigmas (within %.1e)" % worst)


def case_many(site):
    rng = random.Random(SEED + 7)
    feats = observed(rng, 0.05)
    outliers = set()
    for i in range(6000):
        e, n = rng.uniform(-400, 400), rng.uniform(-400, 400)
        off = 0.0
        if i % 5 == 0:
            off = rng.choice((-1, 1)) * rng.uniform(3, 10)
            outliers.add("S%04d" % i)
        feats.append(feature("S%04d" % i, e, n, plane_true(e, n) + rng.gauss(0, 0.05) + off))
    for i in range(2000):
        feats.append(feature("U%04d" % i, rng.uniform(-400, 400), rng.uniform(-400, 400), 0, {"height": "unknown"},
                             two=True))
    write_site(site, feats, sigma_v=0.02)
    d = dump(site)
    if not loaded(d, "many"):
        return
    L = d["lheight"]
    used = [i for i, x in L.items() if x["used"]]
    inliers = 6010 - len(outliers)
    check(not (outliers & set(used)), "many: %d gross outliers used" % len(outliers & set(used)))
    check(len(used) >= 0.99 * inliers, "many: only %d of %d good heights used" % (len(used), inliers))
    o = oracle_plane(points_of(site, used), stated_of(d, used))
    check_model(d, o, "many")
    check_rule(d, site, ["L%02d" % i for i in range(10)] + ["S%04d" % i for i in range(6000)], o, "many")
    check_modelled(d, o, ["U%04d" % i for i in range(2000)], "many")
    print("many: %d of %d surveyed heights used, all %d gross outliers left out" % (len(used), 6010, len(outliers)))


def case_unchanged(site):
    d = dump(site)
    if not loaded(d, "unchanged"):
        return
    check(d["model"]["source"] == 0 and d["landmark_heights"] == "surveyed 1", "unchanged: no model %s" % d["model"])
    for lid, L in d["lheight"].items():
        check(L["stated"] == "default" and L["height"] == "surveyed" and not L["modelled"] and not L["used"] and
              L["given_h"] == L["h"] and L["given_up"] == L["u"] and L["given_sigma"] == L["sigma_v"] and
              L["above"] == 0, "unchanged: %s %s" % (lid, L))
    rc, out, _ = fx.run("site", "check", site)
    check(rc == 0 and "ground model" not in out and out.splitlines()[-1] == "0 errors, 0 warnings",
          "unchanged: check\n" + out)
    rc, out, _ = fx.run("site", "describe", site)
    check('heights: "surveyed" site-wide; 10 surveyed, 0 unreliable, 0 unknown' in out and "ground model" not in out,
          "unchanged: describe\n" + out)


CASES = {name[5:]: fn for name, fn in globals().items() if name.startswith("case_")}

if __name__ == "__main__":
    if len(sys.argv) != 4 or sys.argv[3] not in CASES:
        sys.exit("usage: test_site_heights_model.py DUMP ROUNDTRIP CASE (%s)" % ", ".join(CASES))
    DUMP, ROUNDTRIP = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    with fx.TempSite() as s:
        CASES[sys.argv[3]](s)
    finish("site_heights_model %s (seed %d)" % (sys.argv[3], SEED))

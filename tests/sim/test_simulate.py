#!/usr/bin/python3
"""Tests of `roadside site simulate` against independent oracles.

usage: test_simulate.py CHECK   with CHECK one of
  determinism  same seed -> byte-identical folders; different seeds -> different folders
  oracle       noise-free picks == mrcal's Python projection of truth/ (1e-6 px)
  geodesy      noise-free survey: landmarks.geojson -> PROJ's cct -> truth ENU (1e-6 m)
  visibility   every pick inside the image, every landmark in front of its camera, >= 4 picks
  outliers     the share of outliers matches --outliers (binomial, 4 sigma)
  options      bad options -> exit 2 with a message; an existing folder -> exit 1, untouched
  demo         sites/demo is exactly what `roadside site simulate sites/demo --seed 1` writes
  shapes       --points 0 --poles N --lines M (issue 13, item 4): a site of only poles and lines
               checks clean; every pick within 5 sigma of the projected true segment or
               polyline (mrcal's Python projection, distance computed in the test)
  heights      --height-noise 2 --landmark-heights unreliable|unknown (issue 13, item 5): the
               rest of the site as without them; the extra noise N(0, 2) on the ground heights
               only (4-sigma bounds); what site.json and landmarks.geojson declare; the site
               checks clean and its ground model gives the heights (unknown: exactly the true
               ground, up = 0)

Runs with Debian's python3 (numpy, mrcal). Environment: ROADSIDE = the roadside binary.
"""
import csv
import filecmp
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

ROADSIDE = os.environ.get("ROADSIDE", "roadside")
SEED = 7
failures = []


def fail(msg):
    failures.append(msg)
    print(f"FAIL (seed {SEED}): {msg}", file=sys.stderr)


def simulate(folder, *args, check=True):
    cmd = [ROADSIDE, "site", "simulate", folder, *args]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if check and r.returncode != 0:
        raise SystemExit(f"FAIL (seed {SEED}): {' '.join(cmd)} exited {r.returncode}: {r.stderr}")
    return r


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def finite(*xs):
    return all(math.isfinite(x) for x in xs)


def tree(folder):
    out = []
    for root, _, files in os.walk(folder):
        out += [os.path.relpath(os.path.join(root, f), folder) for f in files]
    return sorted(out)


def check_determinism(tmp):
    a, b, c = (os.path.join(tmp, x) for x in "abc")
    simulate(a, "--seed", str(SEED))
    simulate(b, "--seed", str(SEED))
    simulate(c, "--seed", str(SEED + 1))
    files = tree(a)
    if len(files) < 8:
        fail(f"only {len(files)} files written: {files}")
    if files != tree(b):
        fail(f"same seed, different file lists: {files} vs {tree(b)}")
    _, mismatch, errors = filecmp.cmpfiles(a, b, files, shallow=False)
    if mismatch or errors:
        fail(f"same seed, files differ: {mismatch + errors}")
    _, mismatch, _ = filecmp.cmpfiles(a, c, files, shallow=False)
    for must_differ in ("landmarks.geojson", "truth/truth.json", "observations/cam1.csv"):
        if must_differ not in mismatch:
            fail(f"seeds {SEED} and {SEED + 1} give the same {must_differ}")
    print(f"determinism: {len(files)} files identical for seed {SEED}; {len(mismatch)} differ for seed {SEED + 1}")
    # The sites pass the site checker (geo/rs_site), noise-free ones too.
    d = os.path.join(tmp, "d")
    simulate(d, "--seed", str(SEED), "--pixel-sigma", "0", "--survey-sigma", "0,0", "--outliers", "0",
             "--pole-prior", "0.5", "--lens", "LENSMODEL_CAHVOR")
    for site in (a, d):
        r = subprocess.run([ROADSIDE, "site", "check", site], capture_output=True, text=True)
        if r.returncode != 0:
            fail(f"roadside site check {site}: exit {r.returncode}: {r.stdout}{r.stderr}")
    with open(os.path.join(d, "site.json")) as f:
        declared = json.load(f)["landmark_sigma_m"]
    if declared != {"horizontal": 0.001, "vertical": 0.001}:
        fail(f"noise-free site declares landmark_sigma_m {declared}, want 1 mm")
    if {r["sigma_px"] for r in read_csv(os.path.join(d, "observations", "cam1.csv"))} != {"0.01"}:
        fail("noise-free site: sigma_px is not 0.01")
    print("determinism: simulated sites pass 'roadside site check', noise-free ones declare 1 mm and 0.01 px")


def truth_cameras(site):
    import mrcal
    with open(os.path.join(site, "site.json")) as f:
        cams = [c["id"] for c in json.load(f)["cameras"]]
    return {c: mrcal.cameramodel(os.path.join(site, "truth", f"{c}.cameramodel")) for c in cams}


def truth_landmarks(site):
    return {r["id"]: [float(r["e"]), float(r["n"]), float(r["u"])]
            for r in read_csv(os.path.join(site, "truth", "landmarks_enu.csv"))}


def check_oracle(tmp):
    import mrcal
    import numpy as np
    worst, n = 0.0, 0
    for lens in ("LENSMODEL_OPENCV8", "LENSMODEL_PINHOLE", "LENSMODEL_CAHVOR"):
        site = os.path.join(tmp, lens)
        simulate(site, "--seed", str(SEED), "--pixel-sigma", "0", "--outliers", "0", "--lens", lens,
                 "--cameras", "5")
        lm = truth_landmarks(site)
        for cam, m in truth_cameras(site).items():
            if m.intrinsics()[0] != lens:
                fail(f"{lens}: {cam} has lens {m.intrinsics()[0]}")
            for r in read_csv(os.path.join(site, "observations", f"{cam}.csv")):
                p = np.array(lm[r["landmark"]])
                q = mrcal.project(mrcal.transform_point_rt(m.extrinsics_rt_fromref(), p), *m.intrinsics())
                got = np.array([float(r["u"]), float(r["v"])])
                err = float(np.max(np.abs(q - got)))
                n += 1
                if not (err <= 1e-6):  # also catches NaN
                    fail(f"{lens} {cam} {r['landmark']}: csv {got}, mrcal {q}, |d| {err:.3g} px > 1e-6")
                worst = max(worst, err)
    if n < 30:
        fail(f"only {n} observations checked")
    print(f"oracle: {n} noise-free picks agree with mrcal.project to {worst:.2e} px (tolerance 1e-6)")
    # The nominal models in cameras/: the true intrinsics with fx, fy scaled by --focal-error,
    # zero extrinsics, the same lens and image size.
    site = os.path.join(tmp, "focal")
    simulate(site, "--seed", str(SEED), "--focal-error", "1.05")
    for cam, truth in truth_cameras(site).items():
        nominal = mrcal.cameramodel(os.path.join(site, "cameras", f"{cam}.cameramodel"))
        lt, it = truth.intrinsics()
        ln, inn = nominal.intrinsics()
        want = it.copy()
        want[:2] *= 1.05
        if ln != lt or not np.all(np.abs(inn - want) <= 1e-6) or np.any(nominal.extrinsics_rt_fromref() != 0) \
                or list(nominal.imagersize()) != list(truth.imagersize()):
            fail(f"focal error 1.05, {cam}: nominal {ln} {inn} {nominal.extrinsics_rt_fromref()}, true {lt} {it}")
    print("oracle: nominal models = true intrinsics with fx, fy * 1.05 (1e-6), zero extrinsics")


def check_sparse(tmp):
    """Map-picked sparse sites (issue 38): --elevated-fraction 0 puts every point on the ground;
    --focal-error-range S gives each camera a nominal focal of its own in [1/S, S] x the true one,
    from a stream of its own: the rest of the site is byte for byte the same as without it."""
    plain, ranged = os.path.join(tmp, "plain"), os.path.join(tmp, "ranged")
    common = ["--seed", str(SEED), "--cameras", "8", "--points", "7", "--elevated-fraction", "0"]
    simulate(plain, *common)
    simulate(ranged, *common, "--focal-error-range", "1.5")
    if any(abs(p[2]) > 0 for p in truth_landmarks(plain).values()):
        fail("--elevated-fraction 0: a landmark above the ground")
    import mrcal
    import numpy as np
    ratios = []
    for cam, truth in truth_cameras(ranged).items():
        nominal = mrcal.cameramodel(os.path.join(ranged, "cameras", f"{cam}.cameramodel"))
        it, inn = truth.intrinsics()[1], nominal.intrinsics()[1]
        r = inn[0] / it[0]
        if not (1 / 1.5 - 1e-6 <= r <= 1.5 + 1e-6) or abs(inn[1] / it[1] - r) > 1e-6 or np.any(inn[2:] != it[2:]):
            fail(f"--focal-error-range 1.5, {cam}: nominal {inn}, true {it}")
        ratios.append(r)
    if len(set(round(r, 6) for r in ratios)) < len(ratios):
        fail(f"--focal-error-range: the cameras share a focal error: {ratios}")
    # site.json and truth/truth.json record the options, cameras/ the nominal models
    skip = {"site.json", "truth/truth.json"} | {f"cameras/{c}.cameramodel" for c in truth_cameras(plain)}
    for rel in tree(plain):
        if rel in skip:
            continue
        with open(os.path.join(plain, rel), "rb") as a, open(os.path.join(ranged, rel), "rb") as b:
            if a.read() != b.read():
                fail(f"--focal-error-range changed {rel}")
    print(f"sparse: every landmark on the ground; nominal/true focal {min(ratios):.3f}..{max(ratios):.3f} "
          f"over {len(ratios)} cameras; the rest of the site unchanged")


def cct_to_enu(origin, lonlath):
    """PROJ's cct: WGS84 (lon, lat, h) rows -> ENU at origin (lat, lon, h)."""
    pipeline = ("+proj=pipeline +step +proj=cart +ellps=WGS84 +step +proj=topocentric +ellps=WGS84 "
                f"+lat_0={origin[0]!r} +lon_0={origin[1]!r} +h_0={origin[2]!r}")
    lines = "".join(f"{a!r} {b!r} {c!r}\n" for a, b, c in lonlath)
    r = subprocess.run(["cct", "-d", "9", *pipeline.split()], input=lines, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"FAIL: cct: {r.stderr}")
    return [list(map(float, l.split()[:3])) for l in r.stdout.splitlines() if l.strip()]


def check_geodesy(tmp):
    site = os.path.join(tmp, "s")
    origin = (47.3769, 8.5417, 408.0)
    simulate(site, "--seed", str(SEED), "--survey-sigma", "0,0", "--origin", ",".join(map(str, origin)),
             "--pole-prior", "0.001")
    with open(os.path.join(site, "landmarks.geojson")) as f:
        features = json.load(f)["features"]
    truth = truth_landmarks(site)
    rows = cct_to_enu(origin, [ft["geometry"]["coordinates"] for ft in features])
    if len(rows) != len(features) or len(features) != len(truth):
        fail(f"{len(features)} features, {len(rows)} cct rows, {len(truth)} truth rows")
    worst = 0.0
    for ft, enu in zip(features, rows):
        want = truth[ft["properties"]["id"]]
        err = max(abs(a - b) for a, b in zip(enu, want))
        if not (err <= 1e-6):
            fail(f"{ft['properties']['id']}: cct gives {enu}, truth {want}: {err:.3g} m > 1e-6")
        worst = max(worst, err)
    print(f"geodesy: {len(rows)} landmarks map back through cct to {worst:.2e} m (tolerance 1e-6)")
    # Pole position priors: the true camera position plus N(0, 0.001 m) per axis.
    with open(os.path.join(site, "site.json")) as f:
        cams = json.load(f)["cameras"]
    with open(os.path.join(site, "truth", "truth.json")) as f:
        true_pos = {c["id"]: c["position_enu_m"] for c in json.load(f)["cameras"]}
    priors = [c.get("position_prior", {}) for c in cams]
    if not all(set(p) == {"lat", "lon", "h", "sigma_m"} and p["sigma_m"] == 0.001 for p in priors):
        fail(f"position priors missing or malformed: {priors}")
        return
    enu = cct_to_enu(origin, [(p["lon"], p["lat"], p["h"]) for p in priors])
    worst = max(math.dist(e, true_pos[c["id"]]) for e, c in zip(enu, cams))
    if not worst < 0.001 * 6:
        fail(f"pole priors {worst:.4f} m from the true camera positions (sigma 0.001 m per axis)")
    print(f"geodesy: {len(cams)} pole priors within {worst * 1000:.2f} mm of the true positions (sigma 1 mm)")


def check_visibility(tmp):
    import mrcal
    import numpy as np
    n, ncams = 0, 0
    for args in (["--cameras", "8"], ["--lens", "LENSMODEL_STEREOGRAPHIC", "--hfov-deg", "100", "--pixel-sigma", "5"],
                 ["--image", "640x480", "--landmarks-per-camera", "6", "--outliers", "0.3"]):
        site = os.path.join(tmp, "s%d" % ncams)
        simulate(site, "--seed", str(SEED), *args)
        lm = truth_landmarks(site)
        for cam, m in truth_cameras(site).items():
            ncams += 1
            w, h = m.imagersize()
            rows = read_csv(os.path.join(site, "observations", f"{cam}.csv"))
            if len(rows) < 4:
                fail(f"{args} {cam}: {len(rows)} observations < 4")
            ids = [r["landmark"] for r in rows]
            if len(set(ids)) != len(ids):
                fail(f"{args} {cam}: a landmark is observed twice")
            for r in rows:
                u, v = float(r["u"]), float(r["v"])
                if not (finite(u, v) and -0.5 <= u <= w - 0.5 and -0.5 <= v <= h - 0.5):
                    fail(f"{args} {cam} {r['landmark']}: pixel ({u}, {v}) outside {w}x{h}")
                p_cam = mrcal.transform_point_rt(m.extrinsics_rt_fromref(), np.array(lm[r["landmark"]]))
                if not (p_cam[2] > 0):
                    fail(f"{args} {cam} {r['landmark']}: behind the camera (z = {p_cam[2]})")
                n += 1
    print(f"visibility: {n} picks in {ncams} cameras inside the image and in front, >= 4 per camera")


def check_outliers(tmp):
    site = os.path.join(tmp, "s")
    frac = 0.2
    simulate(site, "--seed", str(SEED), "--cameras", "8", "--landmarks-per-camera", "30", "--outliers", str(frac))
    import mrcal
    import numpy as np
    with open(os.path.join(site, "truth", "truth.json")) as f:
        truth = json.load(f)
    lm = truth_landmarks(site)
    models = truth_cameras(site)
    n, k = 0, 0
    for cam in truth["cameras"]:
        rows = {r["landmark"]: r for r in read_csv(os.path.join(site, "observations", f"{cam['id']}.csv"))}
        n += len(rows)
        k += len(cam["outliers"])
        m = models[cam["id"]]
        for lid, r in rows.items():
            q = mrcal.project(mrcal.transform_point_rt(m.extrinsics_rt_fromref(), np.array(lm[lid])), *m.intrinsics())
            d = float(np.hypot(*(q - [float(r["u"]), float(r["v"])])))
            if lid in cam["outliers"] and not d > 30:
                fail(f"{cam['id']} {lid}: outlier only {d:.1f} px from the truth")
            if lid not in cam["outliers"] and not d < 8:  # 1 px noise: 8 sigma
                fail(f"{cam['id']} {lid}: inlier {d:.1f} px from the truth")
    tol = 4 * math.sqrt(n * frac * (1 - frac))
    if not abs(k - n * frac) <= tol:
        fail(f"{k} outliers in {n} picks, expected {n * frac:.1f} +- {tol:.1f}")
    print(f"outliers: {k} of {n} picks ({k / n:.3f}), asked {frac}, tolerance +-{tol / n:.3f}")


def check_options(tmp):
    bad = [
        ["--seed", "x"], ["--seed", "-1"], [], ["--cameras", "0"], ["--cameras", "17"], ["--lens", "LENSMODEL_FOO"],
        ["--lens", "LENSMODEL_CAHVORE"], ["--image", "1920by1080"], ["--hfov-deg", "190"], ["--pixel-sigma", "-1"],
        ["--survey-sigma", "0.3"], ["--outliers", "1.5"], ["--focal-error", "0"], ["--pole-prior", "-2"],
        ["--origin", "95,11,500"], ["--landmarks-per-camera", "2"], ["--bogus", "1"], ["--seed"],
        ["--focal-error-range", "0.9"], ["--focal-error-range", "2.5"], ["--elevated-fraction", "1.5"],
        ["--elevated-fraction", "x"],
    ]
    for args in bad:
        folder = os.path.join(tmp, "never")
        full = args if args[:1] == ["--seed"] else ["--seed", "1", *args]
        if args == []:
            full = []
        r = simulate(folder, *full, check=False)
        if r.returncode != 2 or "roadside" not in r.stderr or len(r.stderr.strip()) < 20:
            fail(f"{full}: exit {r.returncode} (want 2), stderr {r.stderr!r}")
        if os.path.exists(folder):
            fail(f"{full}: wrote {folder}")
    r = simulate(os.path.join(tmp, "x"), "--seed", "1", "--lens", "LENSMODEL_FOO", check=False)
    if "LENSMODEL_OPENCV8" not in r.stderr:
        fail(f"unknown lens: the message does not list the known models: {r.stderr!r}")
    # An existing, non-empty folder: exit 1, untouched, with and without --force.
    busy = os.path.join(tmp, "busy")
    os.mkdir(busy)
    with open(os.path.join(busy, "mine.txt"), "w") as f:
        f.write("precious\n")
    for extra in ([], ["--force"]):
        r = simulate(busy, "--seed", "1", *extra, check=False)
        if r.returncode != 1 or not r.stderr.strip():
            fail(f"non-empty folder {extra}: exit {r.returncode} (want 1), stderr {r.stderr!r}")
        if tree(busy) != ["mine.txt"]:
            fail(f"non-empty folder {extra}: now holds {tree(busy)}")
    # An existing site: refused without --force, replaced with it.
    site = os.path.join(tmp, "site")
    simulate(site, "--seed", "1")
    before = open(os.path.join(site, "landmarks.geojson")).read()
    r = simulate(site, "--seed", "2", check=False)
    if r.returncode != 1 or open(os.path.join(site, "landmarks.geojson")).read() != before:
        fail(f"existing site without --force: exit {r.returncode}, or changed")
    simulate(site, "--seed", "2", "--force")
    if open(os.path.join(site, "landmarks.geojson")).read() == before:
        fail("--force did not replace the site")
    # issue 42, item 7: --force replaces only what simulate wrote (its .roadside-simulated record
    # lists every file): a real survey (a site.json of its own, no record) and a simulated site with
    # a user's file added are refused, untouched, even with --force
    real = os.path.join(tmp, "real")
    shutil.copytree(site, real)
    if os.path.exists(os.path.join(real, ".roadside-simulated")):
        os.remove(os.path.join(real, ".roadside-simulated"))
    with open(os.path.join(real, "survey-notes.txt"), "w") as f:
        f.write("GNSS base station log\n")
    added = os.path.join(tmp, "added")
    shutil.copytree(site, added)
    with open(os.path.join(added, "observations", "cam9-by-hand.csv"), "w") as f:
        f.write("landmark,u,v\n")
    for folder, why in ((real, "no .roadside-simulated record"), (added, "observations/cam9-by-hand.csv")):
        was = {f: open(os.path.join(folder, f), "rb").read() for f in tree(folder)}
        r = simulate(folder, "--seed", "3", "--force", check=False)
        if r.returncode != 1 or why not in r.stderr:
            fail(f"--force on {os.path.basename(folder)}: exit {r.returncode} (want 1 naming {why!r}): {r.stderr!r}")
        if {f: open(os.path.join(folder, f), "rb").read() for f in tree(folder)} != was:
            fail(f"--force on {os.path.basename(folder)}: the folder changed")
    leftovers = [e for e in os.listdir(tmp) if e.startswith(".")]
    if leftovers:
        fail(f"temporary folders left behind: {leftovers}")
    r = subprocess.run([ROADSIDE, "site", "simulate", "--help"], capture_output=True, text=True)
    if r.returncode != 0 or "--pole-prior" not in r.stdout:
        fail(f"--help: exit {r.returncode}")
    print(f"options: {len(bad)} bad argument lists exit 2; existing folders exit 1 and stay untouched")


def check_demo(tmp):
    demo = os.path.join(os.environ.get("ROADSIDE_SOURCE_ROOT", "."), "sites", "demo")
    if not os.path.isfile(os.path.join(demo, "site.json")):
        print(f"demo: {demo} not found: skipped")
        sys.exit(77)
    site = os.path.join(tmp, "demo")
    simulate(site, "--seed", "1")
    files = [f for f in tree(demo) if f != "README.md"]
    if files != tree(site):
        fail(f"sites/demo holds {files}, the simulator writes {tree(site)}")
    _, mismatch, errors = filecmp.cmpfiles(demo, site, files, shallow=False)
    if mismatch or errors:
        fail(f"sites/demo is not what 'roadside site simulate sites/demo --seed 1' writes: {mismatch + errors} "
             "differ (regenerate it)")
    with open(os.path.join(demo, "README.md")) as f:
        readme = f.read()
    for must in ("SYNTHETIC", "roadside site simulate sites/demo --seed 1", "truth/"):
        if must not in readme:
            fail(f"sites/demo/README.md does not say {must!r}")
    size = sum(os.path.getsize(os.path.join(demo, f)) for f in tree(demo))
    if size >= 200_000:
        fail(f"sites/demo is {size} bytes (limit 200 KB)")
    print(f"demo: sites/demo is byte-identical to a fresh --seed 1 site ({len(files)} files, {size} bytes)")


def check_heights(tmp):
    a, b, c = (os.path.join(tmp, x) for x in ("plain", "unreliable", "unknown"))
    simulate(a, "--seed", str(SEED))
    simulate(b, "--seed", str(SEED), "--height-noise", "2", "--landmark-heights", "unreliable")
    simulate(c, "--seed", str(SEED), "--landmark-heights", "unknown")
    same = [f for f in tree(a) if f.startswith(("cameras/", "observations/")) or f in (
        "lanes.geojson", "truth/landmarks_enu.csv")]
    _, mismatch, errors = filecmp.cmpfiles(a, b, same, shallow=False)
    if mismatch or errors:
        fail(f"--height-noise changed {mismatch + errors}")
    sa, sb = (json.load(open(os.path.join(x, "site.json"))) for x in (a, b))
    if sb.get("landmark_heights") != "unreliable" or "landmark_heights" in sa:
        fail(f"site.json landmark_heights: {sb.get('landmark_heights')!r} (default site: {sa.get('landmark_heights')!r})")
    if abs(sb["landmark_sigma_m"]["vertical"] - math.hypot(0.5, 2)) > 1e-12:
        fail(f"declared vertical sigma {sb['landmark_sigma_m']['vertical']}, expected hypot(0.5, 2)")
    if sb["simulated"].get("height_noise_m") != 2 or "height_noise_m" in sa["simulated"]:
        fail("site.json's simulated does not record --height-noise (or the default site does)")
    ta, tb = (json.load(open(os.path.join(x, "truth", "truth.json"))) for x in (a, b))
    fa, fb, fc = ({f["properties"]["id"]: f for f in json.load(open(os.path.join(x, "landmarks.geojson")))["features"]}
                  for x in (a, b, c))
    extra, ground = [], 0
    for la, lb in zip(ta["landmarks"], tb["landmarks"]):
        lid, up = la["id"], la["enu_m"][2]
        if la["survey_error_enu_m"][:2] != lb["survey_error_enu_m"][:2]:
            fail(f"{lid}: --height-noise moved the horizontal survey")
        d = lb["survey_error_enu_m"][2] - la["survey_error_enu_m"][2]
        pb, pc = fb[lid]["properties"], fc[lid]["properties"]
        if up == 0:
            ground += 1
            extra.append(d)
            if "height" in pb or "height" in pc or len(fc[lid]["geometry"]["coordinates"]) != 2:
                fail(f"{lid} (on the ground): {pb}, unknown site {fc[lid]}")
        else:
            if d != 0:
                fail(f"{lid} ({up} m above the ground): its height got the extra noise")
            for p, noise in ((pb, True), (pc, False)):
                if p.get("height") != "surveyed" or abs(p.get("above_ground_m", 0) - up) > 1e-9 or \
                        (noise and p.get("sigma_v_m") != 0.5):
                    fail(f"{lid} ({up} m above the ground) says {p}")
    n = len(extra)
    mean, std = sum(extra) / n, math.sqrt(sum(x * x for x in extra) / n)
    if not (abs(mean) < 4 * 2 / math.sqrt(n) and abs(std / 2 - 1) < 4 / math.sqrt(2 * n)):
        fail(f"extra height noise over {n} ground landmarks: mean {mean:.3f} m, rms {std:.3f} m; expected N(0, 2)")
    for site, source in ((b, "plane fitted to the unreliable heights"), (c, "the site's ground_plane")):
        r = subprocess.run([ROADSIDE, "site", "check", site], capture_output=True, text=True)
        if r.returncode != 0 or r.stdout.splitlines()[-1] != "0 errors, 0 warnings" or \
                f"ground model: {source}" not in r.stdout:
            fail(f"site check {site}: {r.stdout}")
        r = subprocess.run([ROADSIDE, "site", "describe", "--landmarks", site], capture_output=True, text=True)
        rows = {l.split()[0]: l.split() for l in r.stdout.split("landmarks (ENU, metres):")[-1].splitlines()[2:]}
        kind = "model(unreliable)" if site == b else "model(unknown)"
        for la in ta["landmarks"]:
            row = rows.get(la["id"])
            want = kind if la["enu_m"][2] == 0 else "surveyed"
            if not row or row[6] != want:
                fail(f"describe {site}: {la['id']}: {row}, expected {want}")
            elif site == c and la["enu_m"][2] == 0 and not (abs(float(row[3])) < 1e-6 and float(row[5]) == 0.5):
                fail(f"unknown site: {la['id']} modelled at up {row[3]}, sigma {row[5]}: expected the true 0, 0.5")
    for bad in (("--landmark-heights", "maybe"), ("--height-noise", "-1"), ("--height-noise", "x")):
        r = simulate(os.path.join(tmp, "bad"), "--seed", "1", *bad, check=False)
        if r.returncode != 2 or bad[0].lstrip("-") not in r.stderr:
            fail(f"{' '.join(bad)}: exit {r.returncode}, {r.stderr!r}")
    print(f"heights: {ground} ground landmarks got N(0, 2) more (mean {mean:+.2f} m, rms {std:.2f} m), the rest "
          f"of the site unchanged; unreliable and unknown sites check clean with their ground models")


def distance_to_projected(model, pts_enu, q, step_m=0.01):
    """Pixel distance from q to the projection (mrcal, the true model) of the polyline pts_enu
    (N,3): sampled every step_m, samples less than 0.5 m in front of the camera dropped, the kept
    consecutive samples joined by straight pieces in the image."""
    import mrcal
    import numpy as np
    P = np.asarray(pts_enu, float)
    samples = [P[0]]
    for a, b in zip(P[:-1], P[1:]):
        n = max(1, int(math.ceil(np.linalg.norm(b - a) / step_m)))
        samples += [a + (b - a) * t for t in np.arange(1, n + 1) / n]
    S = np.array(samples)
    pc = mrcal.transform_point_rt(model.extrinsics_rt_fromref(), S)
    front = pc[:, 2] > 0.5
    Q = mrcal.project(pc, *model.intrinsics())
    q = np.asarray(q, float)
    best = math.inf
    if len(Q) == 1:
        return float(np.linalg.norm(Q[0] - q)) if front[0] else math.inf
    A, B = Q[:-1], Q[1:]
    ok = front[:-1] & front[1:]
    AB = B - A
    t = np.clip(np.einsum("ij,ij->i", q - A, AB) / np.maximum(np.einsum("ij,ij->i", AB, AB), 1e-300), 0, 1)
    d = np.linalg.norm(A + AB * t[:, None] - q, axis=1)
    if ok.any():
        best = float(d[ok].min())
    return best


def check_shapes(tmp):
    """issue 13, item 4: --points 0 --poles N --lines M: a site of only poles and lines loads and
    checks clean; every pick lies within 5 sigma of the projected true segment or polyline (mrcal's
    Python projection of truth/, the distance computed here), at base or top within 5 sigma of
    the projected true point; truth/picks.csv's true point lies on the true geometry and projects
    to its recorded pixel; the cameras and points are those of the same site without poles and
    lines."""
    import mrcal
    import numpy as np
    plain, both, only = (os.path.join(tmp, x) for x in ("plain", "both", "only"))
    simulate(plain, "--seed", str(SEED))
    simulate(both, "--seed", str(SEED), "--poles", "4", "--lines", "3")
    same = [f for f in tree(plain) if f.startswith(("cameras/", "truth/cam")) or f in (
        "lanes.geojson", "truth/landmarks_enu.csv")]
    _, mismatch, errors = filecmp.cmpfiles(plain, both, same, shallow=False)
    if mismatch or errors:
        fail(f"--poles/--lines changed {mismatch + errors}")
    sigma = 1.0
    simulate(only, "--seed", str(SEED), "--points", "0", "--poles", "8", "--lines", "5", "--cameras", "6")
    r = subprocess.run([ROADSIDE, "site", "check", only], capture_output=True, text=True)
    if r.returncode != 0 or r.stdout.splitlines()[-1] != "0 errors, 0 warnings":
        fail(f"site check of the poles-and-lines site: exit {r.returncode}: {r.stdout}{r.stderr}")
    feats = json.load(open(os.path.join(only, "landmarks.geojson")))["features"]
    kinds = {("line" if f["geometry"]["type"] == "LineString" else
              "pole" if "height_m" in f["properties"] else "point") for f in feats}
    if kinds != {"pole", "line"}:
        fail(f"the site of only poles and lines has {kinds}")
    geometry = {}
    for row in read_csv(os.path.join(only, "truth", "vertices_enu.csv")):
        geometry.setdefault(row["id"], []).append([float(row["e"]), float(row["n"]), float(row["u"])])
    truth_picks = {(r["camera"], int(r["row"])): r for r in read_csv(os.path.join(only, "truth", "picks.csv"))}
    models = truth_cameras(only)
    worst, worst_true, n, n_out, on_geom = 0.0, 0.0, 0, 0, 0.0
    counts = {"base": 0, "top": 0, "along": 0}
    for cam, m in models.items():
        rows = read_csv(os.path.join(only, "observations", f"{cam}.csv"))
        for i, r in enumerate(rows, start=1):
            t = truth_picks.get((cam, i))
            if t is None or t["landmark"] != r["landmark"] or t["at"] != r["at"]:
                fail(f"{cam} row {i}: {r} has no matching truth/picks.csv row ({t})")
                continue
            g = geometry[r["landmark"]]
            p = np.array([float(t["e"]), float(t["n"]), float(t["u"])])
            # the true point picked lies on the true geometry, and projects where truth says
            d3 = min(float(np.linalg.norm(np.cross(b - a, p - a)) / np.linalg.norm(b - a))
                     if np.dot(p - a, b - a) >= 0 and np.dot(p - b, a - b) >= 0 else min(np.linalg.norm(p - a),
                                                                                          np.linalg.norm(p - b))
                     for a, b in zip(np.array(g[:-1]), np.array(g[1:])))
            on_geom = max(on_geom, d3)
            qt = mrcal.project(mrcal.transform_point_rt(m.extrinsics_rt_fromref(), p), *m.intrinsics())
            worst_true = max(worst_true, float(np.max(np.abs(qt - [float(t["u_true_px"]), float(t["v_true_px"])]))))
            q = [float(r["u"]), float(r["v"])]
            if r["at"] == "along":
                d = distance_to_projected(m, g, q)
            else:
                d = distance_to_projected(m, [g[0] if r["at"] == "base" else g[1]], q)
            counts[r["at"]] += 1
            n += 1
            if t["outlier"] == "1":
                n_out += 1
                continue
            if not (d <= 5 * sigma):  # also catches NaN
                fail(f"{cam} row {i} {r['landmark']} at {r['at']}: {d:.2f} px from the projected truth (> 5 sigma)")
            worst = max(worst, d)
    if on_geom > 1e-6 or worst_true > 1e-5:  # printed to 1e-9 m and px
        fail(f"truth/picks.csv: true points {on_geom:.2g} m off their geometry, {worst_true:.2g} px off mrcal")
    if n < 100 or min(counts.values()) < 10:
        fail(f"only {n} picks ({counts})")
    print(f"shapes: {n} picks of poles and lines ({counts}, {n_out} outliers) within {worst:.2f} px of the "
          f"projected true geometry (tolerance 5 sigma = {5 * sigma} px); true points on it to {on_geom:.1e} m, "
          f"projecting to {worst_true:.1e} px; the poles-and-lines site checks clean; cameras and points "
          f"unchanged by --poles/--lines")
    for bad in (("--poles", "51"), ("--lines", "x"), ("--points", "-1")):
        r = simulate(os.path.join(tmp, "bad"), "--seed", "1", *bad, check=False)
        if r.returncode != 2 or bad[0] not in r.stderr:
            fail(f"{' '.join(bad)}: exit {r.returncode}, {r.stderr!r}")


def main():
    checks = {name[len("check_"):]: f for name, f in globals().items() if name.startswith("check_")}
    if len(sys.argv) != 2 or sys.argv[1] not in checks:
        raise SystemExit(f"usage: {sys.argv[0]} {'|'.join(checks)}")
    with tempfile.TemporaryDirectory(prefix="rs-simulate-") as tmp:
        checks[sys.argv[1]](tmp)
    if failures:
        print(f"{len(failures)} failure(s), seed {SEED}", file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""`roadside audit` end to end, against independent oracles (numpy, OpenCV's Python).

A simulated two-camera site (`roadside site simulate`, fixed seed) is audited:
- --help, <id>.audit.json written for every camera, --json prints the same content;
- the landmark picks re-used as new picks (--against) are "not moved" (chi2 = 0); the picks
  shifted by 15 px, 3 px (a 0.5 deg pan at fx ~ 1660 px) are "moved", with the rotation
  estimated as atan(|shift| / fx) within 0.05 deg, and the exit status 1;
- an external OpenCV-style calibration (K, D, R, t and P = K [R | t], written by cv2.FileStorage
  from `roadside calib`'s own output) is consistent (P_max_px < 1e-6); the same file with P made
  from R turned by 1 deg is reported inconsistent, with P_max_px equal to numpy's largest
  difference of the landmarks' projections (1e-6 relative), and the exit status 1;
- the mrcal .cameramodel of `roadside calib` audited with --calib DIR agrees with the site's own
  solve (rotation < 1e-4 deg);
- bad input: the documented exit statuses and messages naming the file and line.
"""
import json
import math
import os
import sys
import tempfile

import cv2
import numpy as np

SEED = 13
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "common"))
from rs_check import check, failures, run  # noqa: E402


def write_yaml(path, entries):
    fs = cv2.FileStorage(path, cv2.FILE_STORAGE_WRITE)
    for k, v in entries:
        fs.write(k, v)
    fs.release()


def main():
    tmp = tempfile.mkdtemp(prefix="audit_cli_")
    site = os.path.join(tmp, "site")
    r = run("site", "simulate", site, "--seed", str(SEED), "--cameras", "2", "--outliers", "0")
    check(r.returncode == 0, f"simulate: {r.stderr}")

    r = run("audit", "--help")
    check(r.returncode == 0 and r.stdout.startswith("usage: roadside audit"), "audit --help")

    out = os.path.join(tmp, "out")
    r = run("audit", site, "-o", out)
    check(r.returncode in (0, 1), f"audit: exit {r.returncode}: {r.stderr}")
    check(r.stderr == "", f"audit printed on stderr (the library must not print): {r.stderr[:300]}")
    for cam in ("cam1", "cam2"):
        path = os.path.join(out, cam + ".audit.json")
        check(os.path.exists(path), f"{path} missing")
        if os.path.exists(path):
            a = json.load(open(path))
            check(a["camera"] == cam, "camera id")
            check(len(a["landmarks"]) > 4, "landmarks listed")
            check(a["leave_one_out"]["count"] >= len(a["landmarks"]) - 1, "leave-one-out count")
            m = a["uncertainty_map"]
            check(len(m["sigma_m"]) == m["ny"] and len(m["sigma_m"][0]) == m["nx"], "map shape")
            vals = [v for row in m["sigma_m"] for v in row if v is not None]
            check(len(vals) > 100 and all(v > 0 for v in vals), "map values")
            check(0 < a["coverage"]["image_hull_share"] <= 1, "image hull share")
    r = run("audit", site, "-o", out, "--json", "--camera", "cam1")
    try:
        arr = json.loads(r.stdout)
        check(len(arr) == 1 and arr[0]["camera"] == "cam1", "--json: one camera")
    except ValueError:
        check(False, f"--json output is not JSON: {r.stdout[:200]}")

    # --against: the same picks, then picks shifted as by a 0.5 deg pan
    obs = open(os.path.join(site, "observations", "cam1.csv")).read().splitlines()
    same = os.path.join(tmp, "same.csv")
    open(same, "w").write("\n".join(obs) + "\n")
    r = run("audit", site, "-o", out, "--camera", "cam1", "--against", same, "--json")
    a = json.loads(r.stdout)[0] if r.stdout.strip().startswith("[") else {}
    check(a.get("against", {}).get("moved") is False and a["against"]["chi2"] < 1e-12,
          f"same picks: {a.get('against')}")
    K = None
    model = open(os.path.join(site, "cameras", "cam1.cameramodel")).read()
    fx = float(model.split("'intrinsics':")[1].split("[")[1].split(",")[0])
    du, dv = 15.0, 3.0
    shifted = os.path.join(tmp, "shifted.csv")
    rows = [obs[0]]
    for line in obs[1:]:
        f = line.split(",")
        f[1] = "%.6f" % (float(f[1]) + du)
        f[2] = "%.6f" % (float(f[2]) + dv)
        rows.append(",".join(f))
    open(shifted, "w").write("\n".join(rows) + "\n")
    r = run("audit", site, "-o", out, "--camera", "cam1", "--against", shifted, "--json")
    check(r.returncode == 1, f"moved camera: exit {r.returncode}")
    a = json.loads(r.stdout)[0] if r.stdout.strip().startswith("[") else {}
    ag = a.get("against", {})
    expect = math.degrees(math.atan(math.hypot(du, dv) / fx))
    check(ag.get("moved") is True, f"shifted picks not moved: {ag}")
    check(abs(ag.get("rotation_deg", 0) - expect) < 0.05, f"rotation {ag.get('rotation_deg')} vs {expect}")
    r = run("audit", site, "-o", out, "--camera", "cam1", "--against", shifted)
    check("MOVED" in r.stdout, "summary says MOVED")

    # external calibrations: from roadside calib's own OpenCV output
    cal = os.path.join(tmp, "cal")
    r = run("calib", site, "-o", cal)
    check(r.returncode == 0, f"calib: {r.stderr}")
    fs = cv2.FileStorage(os.path.join(cal, "cam1.opencv.yaml"), cv2.FILE_STORAGE_READ)
    K = fs.getNode("camera_matrix").mat()
    D = fs.getNode("distortion_coefficients").mat()
    rvec = fs.getNode("rvec").mat()
    tvec = fs.getNode("tvec").mat()
    fs.release()
    R, _ = cv2.Rodrigues(rvec)
    P = K @ np.hstack([R, tvec])
    c, s = math.cos(math.radians(1)), math.sin(math.radians(1))
    Rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    P_bad = K @ np.hstack([Rz @ R, tvec])
    good = os.path.join(tmp, "good.yaml")
    bad = os.path.join(tmp, "bad.yaml")
    base = [("image_width", 1920), ("image_height", 1080), ("camera_matrix", K),
            ("distortion_coefficients", D), ("R", R), ("tvec", tvec)]
    write_yaml(good, base + [("P", P)])
    write_yaml(bad, base + [("P", 3.7 * P_bad)])  # any scale: P is projective
    r = run("audit", site, "-o", out, "--camera", "cam1", "--calib", good, "--json")
    a = json.loads(r.stdout)[0] if r.stdout.strip().startswith("[") else {}
    x = a.get("external", {})
    check(x.get("consistent") is True and x.get("P_max_px", 1) < 1e-6, f"good calibration: {x}")
    check(x.get("rotation_vs_site_deg", 1) < 1e-4, f"good calibration vs site: {x.get('rotation_vs_site_deg')}")
    r = run("audit", site, "-o", out, "--camera", "cam1", "--calib", bad, "--json")
    check(r.returncode == 1, f"inconsistent calibration: exit {r.returncode}")
    a = json.loads(r.stdout)[0] if r.stdout.strip().startswith("[") else {}
    x = a.get("external", {})
    check(x.get("consistent") is False and any("projection matrix" in s for s in x.get("inconsistencies", [])),
          f"bad calibration: {x}")
    # oracle: numpy projections of the surveyed landmarks through both matrices
    lm = json.load(open(os.path.join(cal, "cam1.json")))["landmarks"]
    pts = np.array([l["p_enu_surveyed_m"] + [1.0] for l in lm]).T
    qa = P_bad @ pts
    qb = P @ pts
    d = np.hypot(qa[0] / qa[2] - qb[0] / qb[2], qa[1] / qa[2] - qb[1] / qb[2]).max()
    check(abs(x.get("P_max_px", 0) - d) < 1e-6 * d, f"P_max_px {x.get('P_max_px')} vs numpy {d}")
    check(abs(x.get("P_scale", 0) - 3.7) < 0.05, f"P_scale {x.get('P_scale')}")
    print(f"external: consistent file P_max_px ~ 0, 1 deg off P: {x.get('P_max_px'):.3f} px (numpy {d:.3f})")
    # a calibration folder with roadside calib's .cameramodel files
    r = run("audit", site, "-o", out, "--calib", cal, "--json")
    try:
        arr = json.loads(r.stdout)
        for a in arr:
            check(a["external"]["rotation_vs_site_deg"] < 1e-4 and a["external"]["consistent"],
                  f"{a['camera']}: .cameramodel vs site: {a['external']}")
    except (ValueError, KeyError) as e:
        check(False, f"--calib DIR: {e}: {r.stdout[:200]} {r.stderr}")

    # bad input
    r = run("audit", site, "--bogus")
    check(r.returncode == 2, "unknown option: exit 2")
    r = run("audit", site, "--alpha", "2")
    check(r.returncode == 2 and "--alpha" in r.stderr, f"--alpha 2: {r.stderr}")
    r = run("audit", site, "--camera", "nope")
    check(r.returncode == 2 and "nope" in r.stderr, f"--camera nope: {r.stderr}")
    r = run("audit", site, "--against", same)
    check(r.returncode == 2 and "--camera" in r.stderr, f"--against file without --camera: {r.stderr}")
    r = run("audit", os.path.join(tmp, "missing"))
    check(r.returncode == 1, "missing site: exit 1")
    broken = os.path.join(tmp, "broken.csv")
    open(broken, "w").write("landmark,u,v\nL001,12,zz\n")
    out2 = os.path.join(tmp, "out2")
    r = run("audit", site, "-o", out2, "--camera", "cam1", "--against", broken)
    check(r.returncode == 1 and "broken.csv:2" in r.stderr and " v" in r.stderr, f"broken csv: {r.stderr}")
    check(not os.path.exists(os.path.join(out2, "cam1.audit.json")), "nothing written for a failed camera")
    open(broken, "w").write("landmark,u,v\nNOPE,12,13\n")
    r = run("audit", site, "-o", out2, "--camera", "cam1", "--against", broken)
    check(r.returncode == 1 and "NOPE" in r.stderr, f"unknown landmark: {r.stderr}")
    r = run("audit", site, "-o", out2, "--camera", "cam1", "--calib", os.path.join(tmp, "nothing.yaml"))
    check(r.returncode == 1 and "nothing.yaml" in r.stderr, f"missing calibration: {r.stderr}")
    nopose = os.path.join(tmp, "nopose.yaml")
    write_yaml(nopose, [("camera_matrix", K)])
    r = run("audit", site, "-o", out2, "--camera", "cam1", "--calib", nopose)
    check(r.returncode == 1 and "nopose.yaml" in r.stderr and "R" in r.stderr, f"no pose: {r.stderr}")

    if failures:
        print(f"{len(failures)} failure(s), seed {SEED}, folder {tmp}")
        return 1
    print("audit CLI: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())

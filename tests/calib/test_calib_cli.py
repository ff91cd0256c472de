#!/usr/bin/env python3
"""`roadside calib` and `roadside locate` end to end, against independent oracles.

A noise-free simulated site (OPENCV8 lenses) is calibrated; then
- each <id>.json pose equals the simulator's truth (truth/<id>.cameramodel) to 1e-8 relative;
- each <id>.cameramodel is read by mrcal's own Python and equals the truth to 1e-6 (mrcal's C
  writer prints 6 decimals);
- each <id>.opencv.yaml, read by OpenCV's FileStorage and pushed through cv2.projectPoints,
  projects the true landmarks where mrcal.project puts them through the truth model (1e-4 px);
- each <id>.homography.json maps ground landmarks (E, N) to where mrcal projects them through
  the truth's pinhole core (1e-6 px), and back (1e-6 m);
- yaw/pitch/roll equal the simulator's (1e-6 deg); position_llh equals PROJ's cct of
  position_enu_m (1e-6 m);
- `roadside locate` of the truth projection of ground points returns those points (1e-6 m);
- bad input: a clear message and the documented exit status, nothing half-written.
"""
import json
import math
import os
import subprocess
import sys
import tempfile

import cv2
import mrcal
import numpy as np

SEED = 7
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "common"))
from rs_check import check, failures, run  # noqa: E402


def cct_enu_to_llh(origin, p):
    lat0, lon0, h0 = origin
    pipe = ["cct", "-d", "12", "-I", "+proj=pipeline", "+step", "+proj=cart", "+ellps=WGS84",
            "+step", "+proj=topocentric", "+ellps=WGS84", f"+lat_0={lat0}", f"+lon_0={lon0}", f"+h_0={h0}"]
    out = subprocess.run(pipe, input=f"{p[0]} {p[1]} {p[2]} 0\n", capture_output=True, text=True, check=True).stdout
    lon, lat, h = (float(v) for v in out.split()[:3])
    return lat, lon, h


def relerr(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return np.max(np.abs(a - b)) / max(1.0, np.max(np.abs(b)))


def main():
    tmp = tempfile.mkdtemp(prefix="roadside-calib-cli-")
    site = os.path.join(tmp, "site")
    p = run("site", "simulate", site, "--seed", str(SEED), "--pixel-sigma", "0", "--survey-sigma", "0,0",
            "--outliers", "0")
    if p.returncode != 0:
        print(p.stderr)
        print(f"FAIL: simulate (seed {SEED})")
        return 1
    out = os.path.join(tmp, "calib")
    p = run("calib", site, "-o", out)
    check(p.returncode == 0, f"calib exit {p.returncode}: {p.stderr}")
    check("camera" in p.stdout and "rms_surveyed_px" in p.stdout and "rms_adjusted_px" in p.stdout,
          "calib prints a summary table with both residuals under their names")
    # the summary names a dropped landmark by its id, as <id>.json does (the demo's cam3 drops
    # L003), never by the solver's index
    demo = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "sites", "demo")
    p = run("calib", demo, "-o", os.path.join(tmp, "demo_calib"))
    row = [line for line in p.stdout.splitlines() if line.startswith("cam3 ")]
    check(p.returncode == 0 and row and "(landmark L003;" in row[0] and "(index" not in p.stdout,
          f"calib's summary names the outlier by id: {row}")
    sitej = json.load(open(os.path.join(site, "site.json")))
    origin = (sitej["origin"]["lat"], sitej["origin"]["lon"], sitej["origin"]["h"])
    truth = {c["id"]: c for c in json.load(open(os.path.join(site, "truth", "truth.json")))["cameras"]}
    lm = {}
    with open(os.path.join(site, "truth", "landmarks_enu.csv")) as f:
        next(f)
        for line in f:
            i, e, n, u = line.strip().split(",")
            lm[i] = np.array([float(e), float(n), float(u)])

    for cam in sitej["cameras"]:
        cid = cam["id"]
        mt = mrcal.cameramodel(os.path.join(site, "truth", f"{cid}.cameramodel"))
        res = json.load(open(os.path.join(out, f"{cid}.json")))
        for key in ("camera", "lensmodel", "intrinsics", "rt_cam_enu", "covariance_rt_cam_enu", "position_enu_m",
                    "position_llh", "yaw_pitch_roll_deg", "sigma_position_enu_m", "sigma_yaw_pitch_roll_deg",
                    "rms_surveyed_px", "rms_adjusted_px", "landmarks", "solver"):
            check(key in res, f"{cid}.json lacks '{key}'")
        # noise-free picks and survey: both residuals vanish (the surveyed one is the headline)
        check(res.get("rms_surveyed_px", 1) < 1e-6 and res.get("rms_adjusted_px", 1) < 1e-6,
              f"{cid}: noise-free residuals rms_surveyed_px {res.get('rms_surveyed_px')}, "
              f"rms_adjusted_px {res.get('rms_adjusted_px')}")
        rt = np.array(res["rt_cam_enu"])
        check(relerr(rt, mt.extrinsics_rt_fromref()) < 1e-8,
              f"{cid}: rt_cam_enu {rt} vs truth {mt.extrinsics_rt_fromref()} (rel {relerr(rt, mt.extrinsics_rt_fromref()):.2e})")
        cov = np.array(res["covariance_rt_cam_enu"])
        check(cov.shape == (6, 6) and np.all(np.isfinite(cov)) and np.allclose(cov, cov.T, atol=1e-15 + 1e-9 * abs(cov).max()),
              f"{cid}: covariance is not a finite symmetric 6x6")
        ypr_err = np.abs(((np.array(res["yaw_pitch_roll_deg"]) - truth[cid]["yaw_pitch_roll_deg"]) + 180) % 360 - 180)
        check(ypr_err.max() < 1e-6, f"{cid}: yaw/pitch/roll off by {ypr_err}")
        llh = cct_enu_to_llh(origin, res["position_enu_m"])
        dlat_m = (res["position_llh"][0] - llh[0]) * 111e3
        dlon_m = (res["position_llh"][1] - llh[1]) * 111e3 * math.cos(math.radians(llh[0]))
        check(abs(dlat_m) < 1e-6 and abs(dlon_m) < 1e-6 and abs(res["position_llh"][2] - llh[2]) < 1e-6,
              f"{cid}: position_llh vs cct differs ({dlat_m:.2e}, {dlon_m:.2e} m)")

        # the .cameramodel, through mrcal's own reader
        m = mrcal.cameramodel(os.path.join(out, f"{cid}.cameramodel"))
        check(relerr(m.extrinsics_rt_fromref(), mt.extrinsics_rt_fromref()) < 1e-6, f"{cid}.cameramodel extrinsics")
        check(relerr(m.intrinsics()[1], mt.intrinsics()[1]) < 1e-6, f"{cid}.cameramodel intrinsics")
        check(m.intrinsics()[0] == mt.intrinsics()[0], f"{cid}.cameramodel lens model")

        ids = [l["id"] for l in res["landmarks"]]
        P = np.array([lm[i] for i in ids])
        q_truth = mrcal.project(mrcal.transform_point_rt(mt.extrinsics_rt_fromref(), P), *mt.intrinsics())

        # the OpenCV yaml, through OpenCV
        fs = cv2.FileStorage(os.path.join(out, f"{cid}.opencv.yaml"), cv2.FILE_STORAGE_READ)
        K, dist = fs.getNode("camera_matrix").mat(), fs.getNode("distortion_coefficients").mat()
        rvec, tvec = fs.getNode("rvec").mat(), fs.getNode("tvec").mat()
        R = fs.getNode("R_cam_enu").mat()
        fs.release()
        q_cv = cv2.projectPoints(P.reshape(-1, 1, 3), rvec, tvec, K, dist)[0].reshape(-1, 2)
        check(np.abs(q_cv - q_truth).max() < 1e-4, f"{cid}.opencv.yaml: projectPoints vs mrcal: {np.abs(q_cv - q_truth).max():.2e} px")
        check(np.abs(cv2.Rodrigues(rvec)[0] - R).max() < 1e-9, f"{cid}.opencv.yaml: R_cam_enu disagrees with rvec")

        # the homography, against mrcal's pinhole projection of the truth core
        H = json.load(open(os.path.join(out, f"{cid}.homography.json")))
        Hpg, Hgp = np.array(H["H_px_from_ground"]), np.array(H["H_ground_from_px"])
        ground = np.array([p for p in P if abs(p[2]) < 1e-9])
        check(len(ground) >= 3, f"{cid}: too few ground landmarks to test the homography")
        core = mt.intrinsics()[1][:4]
        q_pin = mrcal.project(mrcal.transform_point_rt(mt.extrinsics_rt_fromref(), ground), "LENSMODEL_PINHOLE", core)
        g1 = np.c_[ground[:, :2], np.ones(len(ground))] @ Hpg.T
        check(np.abs(g1[:, :2] / g1[:, 2:] - q_pin).max() < 1e-6, f"{cid}: H_px_from_ground vs mrcal pinhole")
        g2 = np.c_[q_pin, np.ones(len(q_pin))] @ Hgp.T
        check(np.abs(g2[:, :2] / g2[:, 2:] - ground[:, :2]).max() < 1e-6, f"{cid}: H_ground_from_px round trip")

        # locate: truth projection of ground points (landmarks and a grid) back to the ground
        grid = np.array([[e, n, 0.0] for e in (-10, 0, 10) for n in (-10, 0, 10)])
        pts = np.r_[ground, grid]
        pc = mrcal.transform_point_rt(mt.extrinsics_rt_fromref(), pts)
        pts = pts[pc[:, 2] > 1]
        q = mrcal.project(mrcal.transform_point_rt(mt.extrinsics_rt_fromref(), pts), *mt.intrinsics())
        inside = (q[:, 0] > 0) & (q[:, 0] < 1919) & (q[:, 1] > 0) & (q[:, 1] < 1079)
        text = "".join(f"{u:.9f} {v:.9f}\n" for u, v in q[inside])
        p = run("locate", site, "--calib", out, "--camera", cid, stdin=text)
        check(p.returncode == 0, f"locate {cid} exit {p.returncode}: {p.stderr}")
        got = np.array([[float(v) for v in line.split()[:3]] for line in p.stdout.splitlines()])
        if got.shape == pts[inside].shape:
            # 1e-4 m: locate prints 4 decimals; the truth model is exact
            check(np.abs(got - pts[inside]).max() < 1.5e-4, f"locate {cid}: {np.abs(got - pts[inside]).max():.2e} m off")
        else:
            check(False, f"locate {cid}: {got.shape} lines for {pts[inside].shape}")

    # bad input
    p = run("calib", os.path.join(tmp, "nowhere"))
    check(p.returncode == 1 and "nowhere" in p.stderr, f"calib of a missing site: rc={p.returncode} {p.stderr!r}")
    p = run("calib", site, "--refine", "everything")
    check(p.returncode == 2 and "--refine" in p.stderr, f"--refine everything: rc={p.returncode}")
    p = run("calib", site, "--camera", "nope", "-o", os.path.join(tmp, "c2"))
    check(p.returncode == 2 and "nope" in p.stderr and not os.path.exists(os.path.join(tmp, "c2")),
          f"--camera nope: rc={p.returncode}")
    p = run("locate", site, "--camera", "cam1", "--calib", os.path.join(tmp, "none"), "1", "2")
    check(p.returncode == 1 and "cam1.cameramodel" in p.stderr, f"locate without calib: {p.stderr!r}")
    p = run("locate", site, "--camera", "cam1", "--calib", out, stdin="100 200\nabc\n")
    check(p.returncode == 1 and "<stdin>:2" in p.stderr and len(p.stdout.splitlines()) == 1,
          f"locate with a bad line: rc={p.returncode} {p.stderr!r}")
    p = run("locate", site, "--calib", out, "1", "2")
    check(p.returncode == 2 and "--camera" in p.stderr, "locate without --camera")
    left = [f for f in os.listdir(out) if ".tmp." in f]
    check(not left, f"temporary files left behind: {left}")

    # <id>.json says what the image makes of the intrinsics (docs/calibration.md 7a): on a site (30 points) whose
    # nominal focal is 1.3x the true one, the image's focal_rel agrees with the truth (truth.json:
    # true / nominal - 1) within 4 of its sigmas, and the camera is warned
    fsite, fout = os.path.join(tmp, "focal"), os.path.join(tmp, "focal-out")
    p = run("site", "simulate", fsite, "--seed", "5", "--cameras", "1", "--focal-error", "1.3", "--points", "30")
    check(p.returncode == 0, f"simulate --focal-error: {p.stderr}")
    p = run("calib", fsite, "-o", fout)
    check(p.returncode == 0, f"calib of the focal-error site: {p.stderr}")
    if p.returncode == 0:
        ic = json.load(open(os.path.join(fout, "cam1.json")))["intrinsics_check"]
        tcam = json.load(open(os.path.join(fsite, "truth", "truth.json")))["cameras"][0]
        want = tcam["intrinsics"][0] / tcam["nominal_intrinsics"][0] - 1
        check(ic["focal_rel"] is not None and abs(ic["focal_rel"] - want) < 4 * ic["sigma_focal_rel"] and ic["warned"],
              f"intrinsics_check focal_rel {ic['focal_rel']} +- {ic['sigma_focal_rel']} vs the truth's {want:.4f}, "
              f"warned {ic['warned']}")

    if failures:
        print(f"{len(failures)} failures (seed {SEED}, folder {tmp})")
        return 1
    print(f"calib cli: {len(sitej['cameras'])} cameras checked against truth, mrcal, OpenCV, cct")
    return 0


if __name__ == "__main__":
    sys.exit(main())

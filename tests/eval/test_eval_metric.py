#!/usr/bin/env python3
"""`roadside eval --site --calib`: thresholds in metres on the ground.

Oracle: ground truths are chosen on the ground in ENU metres; each detection is its ground truth
moved by a chosen ground distance; both are turned into pixels with mrcal's Python through the
simulator's true camera models (used as the calibration folder). Scores fall as the offset
grows, one vehicle per image, so with thresholds 0.5, 1, 2, 4 m and offsets 0.3, 0.8, 1.5, 3, 6 m
the expected AP at each threshold is exactly (number of offsets below it) / 5, and so is the
recall. A detection whose ray misses the ground (the sky) is a false positive. Bad input: a
missing camera field, an unknown camera, --site without --calib.
"""
import json
import math
import os
import shutil
import sys
import tempfile

import mrcal
import numpy as np

SEED = 11
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "common"))
from rs_check import check, failures, run  # noqa: E402


def main():
    tmp = tempfile.mkdtemp(prefix="roadside-eval-metric-")
    try:
        site = os.path.join(tmp, "site")
        p = run("site", "simulate", site, "--seed", str(SEED), "--cameras", "1")
        if p.returncode != 0:
            print(p.stderr)
            return 1
        calib = os.path.join(tmp, "calib")
        os.makedirs(calib)
        shutil.copy(os.path.join(site, "truth", "cam1.cameramodel"), calib)
        m = mrcal.cameramodel(os.path.join(calib, "cam1.cameramodel"))
        rt = m.extrinsics_rt_fromref()
        # a ground point the camera sees well: along the optical axis, on the ground (u = 0)
        R = mrcal.R_from_r(rt[:3])
        c = -R.T @ rt[3:]
        f = R.T @ np.array([0, 0, 1.0])
        s = -c[2] / f[2]
        centre = c + s * f
        side = np.cross(f, [0, 0, 1.0])
        side /= np.linalg.norm(side)

        offsets = [0.3, 0.8, 1.5, 3.0, 6.0]
        images, anns, dets = [], [], []
        for k, off in enumerate(offsets):
            g = centre + side * (k - 2) * 8.0  # spread the vehicles across the view
            d = g + np.array([off * math.cos(k), off * math.sin(k), 0.0])
            qg = mrcal.project(mrcal.transform_point_rt(rt, g), *m.intrinsics())
            qd = mrcal.project(mrcal.transform_point_rt(rt, d), *m.intrinsics())
            images.append({"id": k + 1, "width": 1920, "height": 1080, "camera": "cam1", "file_name": f"{k}.png"})
            anns.append({"id": k + 1, "image_id": k + 1, "category_id": 1, "bbox": [qg[0] - 20, qg[1] - 40, 40, 40],
                         "bottom_center": [float(qg[0]), float(qg[1])], "iscrowd": 0, "area": 1600})
            dets.append({"image_id": k + 1, "category_id": 1, "bbox": [qd[0] - 20, qd[1] - 40, 40, 40],
                         "bottom_center": [float(qd[0]), float(qd[1])], "score": 0.9 - 0.1 * k})
        # a detection in the sky of image 1, lowest score: a false positive after all others
        fh = np.array([f[0], f[1], 0.0]) / math.hypot(f[0], f[1])
        sky = mrcal.project(mrcal.transform_point_rt(rt, c + 100 * fh + np.array([0, 0, 30.0])), *m.intrinsics())
        dets.append({"image_id": 1, "category_id": 1, "bbox": [sky[0] - 10, sky[1] - 20, 20, 20],
                     "bottom_center": [float(sky[0]), float(sky[1])], "score": 0.01})
        gt = {"images": images, "annotations": anns, "categories": [{"id": 1, "name": "vehicle"}]}
        gt_path, det_path, out = (os.path.join(tmp, n) for n in ("gt.json", "dets.json", "out.json"))
        json.dump(gt, open(gt_path, "w"))
        json.dump(dets, open(det_path, "w"))

        p = run("eval", gt_path, det_path, "--site", site, "--calib", calib, "--json", out)
        check(p.returncode == 0, f"metric eval exit {p.returncode}: {p.stderr}")
        check("metres" in p.stdout, "the table says the thresholds are metres")
        check("misses the ground" in p.stderr, f"the sky detection is reported: {p.stderr!r}")
        r = json.load(open(out))
        check(r.get("thresholds_m") == [0.5, 1, 2, 4], f"thresholds_m {r.get('thresholds_m')}")
        for theta in (0.5, 1, 2, 4):
            n = sum(o < theta for o in offsets)
            ap, rec = r["AP"][f"{theta:g}"], r["recall"][f"{theta:g}"]
            check(abs(ap - n / 5) < 1e-12 and abs(rec - n / 5) < 1e-12,
                  f"theta {theta} m: AP {ap}, recall {rec}, expected {n / 5}")
        check(abs(r["mAP"] - 0.5) < 1e-12, f"mAP {r['mAP']} (expected 0.5)")
        # the same data in pixels gives other numbers: the option really changes the metric
        p = run("eval", gt_path, det_path, "--json", out)
        check(p.returncode == 0 and json.load(open(out)).get("thresholds_px") == [2, 5, 10, 15, 20, 50],
              "pixel evaluation unchanged")

        # bad input
        del gt["images"][2]["camera"]
        json.dump(gt, open(gt_path, "w"))
        p = run("eval", gt_path, det_path, "--site", site, "--calib", calib)
        check(p.returncode == 1 and "images[2]" in p.stderr and "camera" in p.stderr,
              f"missing camera field: rc={p.returncode} {p.stderr!r}")
        gt["images"][2]["camera"] = "cam9"
        json.dump(gt, open(gt_path, "w"))
        p = run("eval", gt_path, det_path, "--site", site, "--calib", calib)
        check(p.returncode == 1 and "cam9" in p.stderr, f"unknown camera: rc={p.returncode} {p.stderr!r}")
        p = run("eval", gt_path, det_path, "--site", site)
        check(p.returncode == 2 and "--calib" in p.stderr, "--site without --calib")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    if failures:
        print(f"{len(failures)} failures (seed {SEED})")
        return 1
    print("eval metric: AP per metre threshold as constructed")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""`roadside localise`: are the reported 2x2 covariances honest?

Truth: sites simulated with `roadside site simulate` (seeds SEEDS, CAMERAS cameras each, the
default survey and pick noise, no outliers), calibrated by `roadside calib`: the calibrated poses
differ from the true ones by the calibration's own error, which the pose covariance
(DIR/<id>.json, covariance_rt_cam_enu) describes. For every camera, pixels drawn uniformly over
the lower 55 % of the image (within 80 m) give truth ground points through the TRUE camera
(mrcal's Python: unproject, the ray meets the plane U = 0); each detection is that pixel moved by
Gaussian noise of sigma SIGMA_PX per axis (numpy, seed RNG_SEED), as the centre of a footprint
box. localise places them through the CALIBRATED cameras, all in one run of `--dataset`: a
hand-made dataset whose images record each calibrated model (absolute path, no checksum) and the
ground plane, the covariance read from the <id>.json beside each model.
Checks:
  - every row's camera, frame and time_s are its image's camera and traffic_frame index, time_s;
  - NEES = mean over >= 500 detections of d^T C^-1 d (d = located - truth (E, N), C the reported
    2x2) lies within [0.8, 1.25] x 2;
  - the pose part is real: the same detections through copies of the models without their
    <id>.json (pixel noise only; localise warns once) give a NEES far above 2 (> 5);
  - oracle for the ground point: mrcal's Python unproject + plane intersection through the
    calibrated model agrees with the located point to 1e-6 m on every row.
"""
import json
import math
import os
import shutil
import sys
import tempfile

import mrcal
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from localise_common import check, cleanup, ground_point, read_csv, run, simulate_and_calibrate  # noqa: E402
from rs_check import finish  # noqa: E402

SEEDS = (21, 22, 23, 24, 25, 26, 27, 28)
CAMERAS = 8
SIGMA_PX = 2.0
PER_CAMERA = 10
RNG_SEED = 39


def nees_of(rows, truths):
    out = []
    for r, t in zip(rows, truths):
        d = np.array([float(r["e_m"]) - t[0], float(r["n_m"]) - t[1]])
        se, sn, c = float(r["sigma_e_m"]), float(r["sigma_n_m"]), float(r["cov_en_m2"])
        out.append(float(d @ np.linalg.solve(np.array([[se * se, c], [c, sn * sn]]), d)))
    return out


def main():
    rng = np.random.default_rng(RNG_SEED)
    tmp = tempfile.mkdtemp(prefix="roadside-localise-nees-")
    try:
        images, images_px, dets, truths, models = [], [], [], [], {}
        bare = os.path.join(tmp, "bare")  # the models without their <id>.json
        os.makedirs(bare)
        for seed in SEEDS:
            site, calib = simulate_and_calibrate(tmp, seed, CAMERAS, ("--outliers", "0"))
            for cam in sorted(f[:-12] for f in os.listdir(calib) if f.endswith(".cameramodel")):
                truth = mrcal.cameramodel(os.path.join(site, "truth", cam + ".cameramodel"))
                model = os.path.abspath(os.path.join(calib, cam + ".cameramodel"))
                copy = os.path.join(bare, f"{seed}-{cam}.cameramodel")
                shutil.copy(model, copy)
                image_id = len(images) + 1
                models[image_id] = mrcal.cameramodel(model)
                plane = {"ground_normal_enu": [0, 0, 1], "ground_offset_m": 0}
                frame = {"file": "f.json", "time_s": 0.1 * image_id, "index": image_id}
                images.append({"id": image_id, "camera": cam, "traffic_frame": frame,
                               "calibration": {"camera_model": model, **plane}})
                images_px.append({"id": image_id, "camera": cam, "calibration": {"camera_model": copy, **plane}})
                W, H = truth.imagersize()
                near = ground_point(truth, [W / 2, H - 1])
                n = 0
                while n < PER_CAMERA:
                    q = np.array([rng.uniform(0, W - 1), rng.uniform(0.45 * H, H - 1)])
                    p = ground_point(truth, q)
                    if p is None or np.hypot(*(p[:2] - near[:2])) > 80:
                        continue
                    qd = q + rng.normal(0, SIGMA_PX, 2)
                    dets.append({"image_id": image_id, "category_id": 1, "score": 1.0,
                                 "bbox": [qd[0] - 15, qd[1] - 6, 30, 12]})
                    truths.append(p)
                    n += 1
        ds, ds_px = os.path.join(tmp, "ds"), os.path.join(tmp, "ds_px")
        for d, ims in ((ds, images), (ds_px, images_px)):
            os.makedirs(os.path.join(d, "annotations"))
            json.dump({"images": ims, "annotations": [], "categories": [{"id": 1, "name": "car"}]},
                      open(os.path.join(d, "annotations", "instances_test.json"), "w"))
        dpath, out = os.path.join(tmp, "dets.json"), os.path.join(tmp, "out.csv")
        json.dump(dets, open(dpath, "w"))

        p = run("localise", dpath, "--dataset", ds, "--pixel-sigma", str(SIGMA_PX), "-o", out)
        check(p.returncode == 0 and "warning" not in p.stderr, f"exit {p.returncode}: {p.stderr}")
        print(p.stdout.strip())
        rows = read_csv(out)
        check(len(rows) == len(dets), f"{len(rows)} rows of {len(dets)}")
        nees = nees_of(rows, truths)
        by_id = {im["id"]: im for im in images}
        check(all(r["camera"] == by_id[int(r["image_id"])]["camera"] and int(r["frame"]) == int(r["image_id"])
                  and abs(float(r["time_s"]) - 0.1 * int(r["image_id"])) < 1e-12 for r in rows),
              "camera, frame and time_s from each image's camera and traffic_frame")
        oracle_worst = 0.0
        for r in rows:
            g = ground_point(models[int(r["image_id"])], [float(r["u_px"]), float(r["v_px"])])
            oracle_worst = max(oracle_worst, float(np.max(np.abs(
                g - [float(r["e_m"]), float(r["n_m"]), float(r["u_m"])]))))

        p = run("localise", dpath, "--dataset", ds_px, "--pixel-sigma", str(SIGMA_PX), "-o", out)
        check(p.returncode == 0 and p.stderr.count("warning") == 1,
              f"without the covariance: exit {p.returncode}, one warning: {p.stderr!r}")
        nees_px = nees_of(read_csv(out), truths)
    finally:
        cleanup(tmp)
    mean, mean_px = float(np.mean(nees)), float(np.mean(nees_px))
    print(f"{len(nees)} detections, {len(SEEDS) * CAMERAS} calibrations: NEES {mean:.3f} (expected 2, "
          f"accepted [1.6, 2.5]); pixel noise only: NEES {mean_px:.1f}; ground point against "
          f"mrcal's Python: worst {oracle_worst:.2e} m")
    check(len(nees) >= 500, f"{len(nees)} detections (>= 500 wanted)")
    check(all(math.isfinite(x) for x in nees), "a NEES term is not finite")
    check(1.6 <= mean <= 2.5, f"NEES {mean:.3f} outside [1.6, 2.5] (seed {RNG_SEED}, sites {SEEDS})")
    check(mean_px > 5, f"NEES without the pose covariance {mean_px:.2f}: the pose error is not tested")
    check(oracle_worst < 1e-6, f"ground point against mrcal's Python: {oracle_worst:.2e} m (1e-6 wanted)")
    finish("localise_nees")


if __name__ == "__main__":
    main()

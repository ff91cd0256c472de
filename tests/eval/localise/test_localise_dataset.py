#!/usr/bin/env python3
"""`roadside localise DETS.json --dataset DATASET`: a dataset's own labels as detections come
back to the labels' ground points.

A small dataset: `roadside site simulate --seed SEED --cameras 2`, `roadside calib`, then
`roadside synth` (4 images of 320x180, real POV-Ray; skipped, exit 77, without it). Its
annotations become COCO results: bbox = the annotation's bbox (the footprint box, synth's
default), score 1, and the annotation's `bottom_center` pixel (docs/labels.md: the exact
projection of the footprint's centre -- the dataset's own ground point; the footprint box's
centre is not it, perspective and distortion move it).
Checks:
  - synth copies calib's <id>.json beside each model in DATASET/cameras/ (the pose covariance):
    its covariance_rt_cam_enu is calib's, element for element;
  - every located point is within 1 cm of the label's bottom_center_enu_m (east, north, up), and
    lat/lon within 1e-9 deg of its bottom_center_lat_deg/lon_deg (localise given --site for the
    origin); camera and the image's traffic frame carried over;
  - the footprint box centres alone (--point center, no bottom_center) land near the labels: the
    distances are printed (the convention's own offset; boxes clipped at the image border move
    most) and their median must stay under 0.5 m;
  - the dataset without the <id>.json copies: one warning, smaller covariances (pixel only);
  - an unknown image id, a changed camera model (SHA-256), a split that does not exist: exit 1,
    the message names the file, line and field (or the splits), no output written.
"""
import json
import os
import shutil
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from localise_common import check, cleanup, read_csv, run, simulate_and_calibrate  # noqa: E402
from rs_check import finish  # noqa: E402

SEED = 5


def main():
    if not shutil.which("povray"):
        print("skipped: no povray")
        sys.exit(77)
    tmp = tempfile.mkdtemp(prefix="roadside-localise-dataset-")
    try:
        site, calib = simulate_and_calibrate(tmp, SEED, 2)
        ds = os.path.join(tmp, "ds")
        p = run("synth", "--val-fraction", "0", site, "--calib", calib, "--count", "4", "--size", "320x180", "--vehicles", "12",
                "-o", ds, "--seed", str(SEED), "--jobs", "2")
        if p.returncode != 0:
            raise SystemExit(f"synth: {p.stderr}")
        for cam in ("cam1", "cam2"):
            copy = os.path.join(ds, "cameras", cam + ".json")
            if check(os.path.exists(copy), f"{copy}: synth did not copy calib's record"):
                a = np.array(json.load(open(copy))["covariance_rt_cam_enu"])
                b = np.array(json.load(open(os.path.join(calib, cam + ".json")))["covariance_rt_cam_enu"])
                check(a.shape == (6, 6) and np.array_equal(a, b), f"{copy}: covariance differs from calib's")
        gt = json.load(open(os.path.join(ds, "annotations", "instances_train2017.json")))
        anns = [a for a in gt["annotations"] if a.get("bottom_center") is not None]
        images = {im["id"]: im for im in gt["images"]}
        dets = [{"image_id": a["image_id"], "category_id": a["category_id"], "bbox": a["bbox"], "score": 1.0,
                 "bottom_center": a["bottom_center"]} for a in anns]
        dpath, out = os.path.join(tmp, "dets.json"), os.path.join(tmp, "out.csv")
        json.dump(dets, open(dpath, "w"))
        p = run("localise", dpath, "--dataset", ds, "--site", site, "--point", "center", "-o", out)
        check(p.returncode == 0 and "warning" not in p.stderr, f"exit {p.returncode}: {p.stderr}")
        rows = read_csv(out)
        check(len(rows) == len(anns) and len(anns) >= 10, f"{len(rows)} rows, {len(anns)} labels")
        worst, worst_deg = 0.0, 0.0
        for r, a in zip(rows, anns):
            d = np.array([float(r[k]) for k in ("e_m", "n_m", "u_m")]) - a["bottom_center_enu_m"]
            worst = max(worst, float(np.max(np.abs(d))))
            worst_deg = max(worst_deg, abs(float(r["lat_deg"]) - a["bottom_center_lat_deg"]),
                            abs(float(r["lon_deg"]) - a["bottom_center_lon_deg"]))
            check(r["camera"] == images[a["image_id"]]["camera"], f"camera {r['camera']}")
        check(worst < 0.01, f"labels' own ground points: {worst:.3e} m from bottom_center_enu_m (1 cm wanted)")
        check(worst_deg < 1e-9, f"lat/lon {worst_deg:.2e} deg from the labels'")
        sig = [float(r["sigma_e_m"]) for r in rows]

        # footprint box centres alone
        for d in dets:
            del d["bottom_center"]
        dpath2 = os.path.join(tmp, "dets-boxes.json")
        json.dump(dets, open(dpath2, "w"))
        p = run("localise", dpath2, "--dataset", ds, "-o", out)
        rows2 = read_csv(out)
        dist = [float(np.hypot(float(r["e_m"]) - a["bottom_center_enu_m"][0],
                               float(r["n_m"]) - a["bottom_center_enu_m"][1])) for r, a in zip(rows2, anns)]
        check(p.returncode == 0 and len(rows2) == len(anns) and np.median(dist) < 0.5,
              f"footprint box centres: {len(rows2)} rows, median {np.median(dist) if dist else None} m")
        print(f"{len(anns)} labels: their bottom_center back within {worst:.2e} m, lat/lon {worst_deg:.1e} deg; "
              f"footprint box centres: median {np.median(dist):.3f} m, worst {max(dist):.3f} m from the labels")

        # without the covariance copies: a warning, pixel noise only
        for cam in ("cam1", "cam2"):
            os.rename(os.path.join(ds, "cameras", cam + ".json"), os.path.join(tmp, cam + ".json"))
        p = run("localise", dpath, "--dataset", ds, "-o", out)
        sig_px = [float(r["sigma_e_m"]) for r in read_csv(out)]
        check(p.returncode == 0 and p.stderr.count("warning") == 1 and "covariance" in p.stderr,
              f"no covariance: {p.stderr!r}")
        check(all(a < b for a, b in zip(sig_px, sig)), "pixel-only sigmas are not all smaller")

        # bad input
        o = os.path.join(tmp, "bad.csv")
        bad = [dict(dets[0]), dict(dets[1], image_id=999)]
        bpath = os.path.join(tmp, "bad.json")
        with open(bpath, "w") as f:
            f.write("[\n" + ",\n".join(json.dumps(d) for d in bad) + "\n]\n")
        p = run("localise", bpath, "--dataset", ds, "-o", o)
        check(p.returncode == 1 and f"{bpath}:3: image_id: 999" in p.stderr and not os.path.exists(o),
              f"unknown image id: rc {p.returncode} {p.stderr!r}")
        p = run("localise", dpath, "--dataset", ds, "--split", "val2017", "-o", o)
        check(p.returncode == 1 and "train2017" in p.stderr and not os.path.exists(o),
              f"no such split: rc {p.returncode} {p.stderr!r}")
        with open(os.path.join(ds, "cameras", "cam1.cameramodel"), "a") as f:
            f.write("\n# changed\n")
        p = run("localise", dpath, "--dataset", ds, "-o", o)
        check(p.returncode == 1 and "SHA-256" in p.stderr and not os.path.exists(o),
              f"changed model: rc {p.returncode} {p.stderr!r}")
    finally:
        cleanup(tmp)
    finish("localise_dataset")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
# test_site_opencv.py -- OpenCV-style intrinsics (.yaml written by OpenCV's own cv2.FileStorage,
# .json by FileStorage and by hand) load as the equivalent mrcal lens model: the model and
# intrinsics `roadside site describe` reports project points exactly as cv2.projectPoints does
# with the original K and distortion (mrcal.project as the mrcal side). Tolerance 1e-6 px over
# 200 random points in front of the camera (seed printed on failure). Also: a tilted 14-value
# model and a skewed K are refused as unsupported.
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import site_fixture as fx  # noqa: E402

try:
    import cv2
    import mrcal
except ImportError as e:  # python3-opencv / python3-mrcal missing: skip
    print("skipped: %s" % e)
    sys.exit(77)

W, H = 1920, 1080
K = np.array([[1210.5, 0.0, 961.25], [0.0, 1190.75, 538.5], [0.0, 0.0, 1.0]])
DIST = [-0.21, 0.043, 0.0012, -0.0007, -0.004, 0.01, -0.002, 0.0005, 0.0011, -0.0004, 0.0007, 0.0002]

CASES = [
    # name, file, coefficients (None: field absent), writer, expected mrcal model
    ("none", "north.yaml", None, "opencv", "LENSMODEL_PINHOLE"),
    ("zeros5", "north.yaml", [0.0] * 5, "opencv", "LENSMODEL_PINHOLE"),
    ("4", "north.yaml", DIST[:4], "opencv", "LENSMODEL_OPENCV4"),
    ("5", "north.yml", DIST[:5], "opencv", "LENSMODEL_OPENCV5"),
    ("8", "north.yaml", DIST[:8], "opencv", "LENSMODEL_OPENCV8"),
    ("12", "north.yaml", DIST[:12], "opencv", "LENSMODEL_OPENCV12"),
    ("14-untilted", "north.yaml", DIST[:12] + [0.0, 0.0], "opencv", "LENSMODEL_OPENCV12"),
    ("8-json", "north.json", DIST[:8], "opencv", "LENSMODEL_OPENCV8"),
    ("5-plain-json", "north.json", DIST[:5], "plain", "LENSMODEL_OPENCV5"),
]


def write_intrinsics(path, dist, writer, k=K):
    if writer == "plain":
        with open(path, "w") as f:
            json.dump({"image_width": W, "image_height": H, "camera_matrix": k.tolist(),
                       "distortion_coefficients": dist}, f)
        return
    fs = cv2.FileStorage(path, cv2.FILE_STORAGE_WRITE)
    fs.write("image_width", W)
    fs.write("image_height", H)
    fs.write("camera_matrix", k)
    if dist is not None:
        fs.write("distortion_coefficients", np.array(dist, dtype=np.float64).reshape(1, -1))
    fs.release()


def use_model(site, filename):
    p = os.path.join(site, "site.json")
    sj = fx.load_json(p)
    sj["cameras"][0]["model"] = "cameras/" + filename
    with open(p, "w") as f:
        json.dump(sj, f, indent=2)
    os.remove(os.path.join(site, "cameras", "north.cameramodel"))


def loaded_model(site):
    rc, out, err = fx.run("site", "describe", site)
    if rc != 0:
        fx.fail("describe failed", out, err)
    lines = out.splitlines()
    i = next(i for i, l in enumerate(lines) if l.startswith("  camera 'north'"))
    lens = lines[i + 2].split("lens model: ")[1].split(",")[0]
    size = lines[i + 2].split("image ")[1].split(" px")[0]
    intr = np.array([float(x) for x in lines[i + 3].split("intrinsics:")[1].split()])
    return lens, size, intr, out


def main():
    rng = np.random.default_rng(fx.SEED)
    z = rng.uniform(2.0, 50.0, 200)
    p_cam = np.stack([rng.uniform(-0.7, 0.7, 200) * z, rng.uniform(-0.4, 0.4, 200) * z, z], axis=1)
    for name, filename, dist, writer, want in CASES:
        with fx.TempSite() as site:
            write_intrinsics(os.path.join(site, "cameras", filename), dist, writer)
            use_model(site, filename)
            lens, size, intr, out = loaded_model(site)
        if lens != want or size != "%d x %d" % (W, H):
            fx.fail("%s: loaded %s %s, expected %s %dx%d" % (name, lens, size, want, W, H), out)
        q_mrcal = mrcal.project(p_cam, lens, intr)
        d = np.zeros(5) if dist is None else np.array(dist)
        q_cv, _ = cv2.projectPoints(p_cam.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), K, d)
        err = np.abs(q_mrcal - q_cv.reshape(-1, 2)).max()
        if not np.isfinite(err) or err > 1e-6:
            fx.fail("%s: mrcal.project vs cv2.projectPoints differ by %.3g px (> 1e-6)" % (name, err), out)
        print("%-13s -> %-18s max |mrcal - OpenCV| = %.2e px" % (name, lens, err))

    # refused: tilted sensor, skew
    for name, dist, k, pattern in (
            ("14-tilted", DIST[:12] + [0.01, -0.02], K,
             r"^SITE/cameras/north\.yaml: distortion_coefficients: 14 values with a tilted sensor"),
            ("skew", DIST[:5], np.array([[1210.5, 0.5, 961.25], [0, 1190.75, 538.5], [0, 0, 1]]),
             r"^SITE/cameras/north\.yaml: camera_matrix: skew 0\.5: mrcal lens models have no skew")):
        with fx.TempSite() as site:
            write_intrinsics(os.path.join(site, "cameras", "north.yaml"), dist, "opencv", k)
            use_model(site, "north.yaml")
            rc, out, err = fx.run("site", "check", site)
            rc_d, out_d, err_d = fx.run("site", "describe", site)
        if rc != 1 or rc_d != 1:
            fx.fail("%s: check exit %d, describe exit %d, expected 1 and 1" % (name, rc, rc_d), out, err)
        fx.expect_line(out, pattern, name)
        if "unsupported" not in err_d and "no skew" not in err_d and "tilted" not in err_d:
            fx.fail("%s: describe should name the problem" % name, out_d, err_d)
        print("%-13s -> refused: %s" % (name, out.splitlines()[0].split(": ", 1)[1]))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Fisheye lenses read as mrcal's CAHVORE at linearity 0 (core/rs_camera_fisheye.c,
docs/conventions.md "Fisheye lenses"), checked against independent oracles:
- OpenCV fisheye YAML (written by cv2.FileStorage, distortion_model "fisheye", "equidistant" or
  "kannala_brandt") with k3 = k4 = 0: roadside's projection (test_camera_dump project: rs_camera_project
  through mrcal) of 500 random points up to 85 degrees off axis agrees with cv2.fisheye.projectPoints
  to 1e-6 px;
- with k3, k4 != 0 that a CAHVORE fits within 0.01 px over the image's angles: agreement to 0.01 px
  over the angles the image shows; a k4 too large to fit is refused (UNSUPPORTED) naming the file,
  distortion_coefficients and the error;
- the equidistant triple {"f", "x0", "y0"} (.json): the pixel radius is f * theta to 1e-9 px;
- a fisheye with 5 coefficients is refused naming the field.
Fixed seed 38, printed on failure."""
import json
import math
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from rs_check import check, finish, need  # noqa: E402

cv2, np = need("cv2", "numpy")

SEED = 38
W, H = 1280, 960


def run(*args, stdin=None):
    r = subprocess.run([DUMP, *args], input=stdin, capture_output=True, text=True)
    return r.returncode, r.stdout


def rays(rng, n, max_deg):
    """n unit rays of the camera frame, up to max_deg off the optical axis."""
    th = rng.uniform(0, math.radians(max_deg), n)
    ph = rng.uniform(0, 2 * math.pi, n)
    return np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], 1) * rng.uniform(1, 50, (n, 1))


def project(path, p):
    rc, out = run("project", path, stdin="".join("%.17g %.17g %.17g\n" % tuple(x) for x in p))
    return np.array([[float(v) for v in line.split()] for line in out.splitlines()]) if rc == 0 else None


def write_yaml(path, K, D, model):
    fs = cv2.FileStorage(path, cv2.FILE_STORAGE_WRITE)
    fs.write("image_width", W)
    fs.write("image_height", H)
    fs.write("camera_matrix", K)
    fs.write("distortion_coefficients", np.array(D, float).reshape(1, -1))
    fs.write("distortion_model", model)
    fs.release()


def opencv(p, K, D):
    q, _ = cv2.fisheye.projectPoints(p.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), K, np.array(D, float))
    return q.reshape(-1, 2)


def main():
    rng = np.random.default_rng(SEED)
    tmp = tempfile.mkdtemp()
    K = np.array([[345.5, 0, 641.25], [0, 338.75, 479.5], [0, 0, 1.0]])
    # exact: k3 = k4 = 0, every name of the model
    for model, D in (("fisheye", [0.03, -0.004, 0, 0]), ("equidistant", [-0.02, 0.001, 0, 0]),
                     ("KANNALA_BRANDT", [0.0, 0.0, 0, 0])):
        path = os.path.join(tmp, model + ".yaml")
        write_yaml(path, K, D, model)
        rc, out = run("read", path)
        check(rc == 0 and "CAHVORE" in out, f"{model}: not read as CAHVORE: {out.strip()}")
        p = rays(rng, 500, 85)
        q = project(path, p)
        if q is None:
            check(False, f"{model}: projection failed")
            continue
        err = np.abs(q - opencv(p, K, D)).max()
        print(f"{model} k={D}: max |roadside - cv2.fisheye.projectPoints| = {err:.3g} px over 500 rays <= 85 deg")
        check(err <= 1e-6, f"{model}: {err} px > 1e-6 (seed {SEED})")
    # fitted: k3, k4 small enough to fit within 0.01 px over the image's angles
    D = [0.02, -0.003, 3e-5, -2e-6]
    K = np.array([[600.5, 0, 641.25], [0, 598.75, 479.5], [0, 0, 1.0]])  # corners about 76 degrees off axis
    path = os.path.join(tmp, "fit.yaml")
    write_yaml(path, K, D, "fisheye")
    rc, out = run("read", path)
    check(rc == 0, f"fit: refused: {out.strip()}")
    if rc == 0:
        corners = np.array([[-0.5, -0.5], [W - 0.5, -0.5], [-0.5, H - 0.5], [W - 0.5, H - 0.5]])
        und = cv2.fisheye.undistortPoints(corners.reshape(-1, 1, 2), K, np.array(D)).reshape(-1, 2)
        widest = np.degrees(np.arctan(np.hypot(und[:, 0], und[:, 1]))).max()
        p = rays(rng, 500, widest)
        err = np.abs(project(path, p) - opencv(p, K, D)).max()
        print(f"fit k={D}: max error {err:.3g} px over 500 rays <= {widest:.1f} deg (the image's widest)")
        check(err <= 0.01, f"fit: {err} px > 0.01 (seed {SEED})")
    path = os.path.join(tmp, "nofit.yaml")
    write_yaml(path, K, [0.02, -0.003, 0.01, -0.02], "fisheye")
    rc, out = run("read", path)
    check(rc == 1 and "UNSUPPORTED" in out.upper() and "nofit.yaml: distortion_coefficients:" in out and " px" in out,
          f"a k4 that does not fit: {out.strip()}")
    print("refused:", out.strip())
    path = os.path.join(tmp, "five.yaml")
    write_yaml(path, K, [0.02, -0.003, 0, 0, 0.1], "fisheye")
    rc, out = run("read", path)
    check(rc == 1 and "five.yaml: distortion_coefficients: 5 values" in out, f"5 fisheye coefficients: {out.strip()}")
    # the equidistant triple: r = f theta
    path = os.path.join(tmp, "triple.json")
    with open(path, "w") as f:
        json.dump({"f": 340.0, "x0": 640, "y0": 480, "image_width": W, "image_height": H}, f)
    rc, out = run("read", path)
    check(rc == 0 and json.loads(out)["width"] == W, f"triple: {out.strip()}")
    p = rays(rng, 500, 85)
    q = project(path, p)
    theta = np.arctan2(np.hypot(p[:, 0], p[:, 1]), p[:, 2])
    err = np.abs(np.hypot(q[:, 0] - 640, q[:, 1] - 480) - 340.0 * theta).max()
    print(f"triple: max |r - f theta| = {err:.3g} px over 500 rays <= 85 deg")
    check(err <= 1e-9, f"triple: {err} px > 1e-9 (seed {SEED})")
    with open(path, "w") as f:
        json.dump({"f": 340.0, "x0": 640}, f)
    rc, out = run("read", path)
    check(rc == 1 and "triple.json: y0: missing" in out, f"triple without y0: {out.strip()}")
    finish("test_camera_fisheye")


if __name__ == "__main__":
    DUMP = sys.argv[1]
    main()

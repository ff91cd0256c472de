# Helpers shared by the synth tests (SCENE half): running roadside, scaled copies of the demo
# site's truth cameras, reading renders, parsing the spheres of a written scene.
import json
import os
import re
import subprocess
import sys

import numpy as np

ROADSIDE = os.environ.get("ROADSIDE", "roadside")
SOURCE = os.environ.get("ROADSIDE_SOURCE_ROOT", os.path.join(os.path.dirname(__file__), "..", ".."))
DEMO = os.path.join(SOURCE, "sites", "demo")


def fail(msg, seed=None):
    print("FAIL: " + msg + ("" if seed is None else " (seed %d)" % seed))
    sys.exit(1)


def need_povray():
    import shutil
    if not shutil.which(os.environ.get("ROADSIDE_POVRAY", "povray")):
        print("SKIP: povray not installed")
        sys.exit(77)


def run(args, expect=0):
    p = subprocess.run([ROADSIDE] + args, capture_output=True, text=True)
    if expect is not None and p.returncode != expect:
        fail("roadside %s: exit %d (expected %d)\nstdout: %s\nstderr: %s"
             % (" ".join(args), p.returncode, expect, p.stdout, p.stderr))
    return p


def scaled_camera(calib_dir, cam_id, width, pinhole, fy_over_fx=1.0, dcx=0.0, dcy=0.0):
    """Writes calib_dir/cam_id.cameramodel: the demo truth camera scaled to `width` pixels,
    pinhole core only (pinhole=True) or with its OPENCV8 distortion; returns the model."""
    import mrcal
    m = mrcal.cameramodel(os.path.join(DEMO, "truth", cam_id + ".cameramodel"))
    lens, intr = m.intrinsics()
    W0, H0 = m.imagersize()
    s = width / W0
    H = int(round(H0 * s))
    intr = np.array(intr, dtype=float)
    intr[0] *= s
    intr[1] *= s * fy_over_fx
    intr[2] = (intr[2] + 0.5) * s - 0.5 + dcx
    intr[3] = (intr[3] + 0.5) * s - 0.5 + dcy
    if pinhole:
        lens, intr = "LENSMODEL_PINHOLE", intr[:4]
    out = mrcal.cameramodel(intrinsics=(lens, intr), imagersize=(width, H),
                            extrinsics_rt_fromref=m.extrinsics_rt_fromref())
    os.makedirs(calib_dir, exist_ok=True)
    out.write(os.path.join(calib_dir, cam_id + ".cameramodel"))
    return out


def write_json(path, obj):
    with open(path, "w") as f:
        json.dump(obj, f)


def read_png(path):
    import cv2
    a = cv2.imread(path, cv2.IMREAD_UNCHANGED)
    if a is None:
        fail("cannot read " + path)
    if a.ndim == 3 and a.shape[2] == 4:
        a = a[:, :, [2, 1, 0, 3]]
    elif a.ndim == 3:
        a = a[:, :, ::-1]
    return a


def scene_spheres(pov_path):
    """(N,3) ENU centres and (N,) radii of the spheres in a written scene."""
    num = r"(-?[0-9.eE+-]+)"
    pat = re.compile(r"sphere \{ <" + num + ", " + num + ", " + num + ">, " + num)
    c, r = [], []
    for m in pat.finditer(open(pov_path).read()):
        x, y, z, rad = map(float, m.groups())
        c.append((x, z, y))  # <e, u, n> -> (e, n, u)
        r.append(rad)
    return np.array(c).reshape(-1, 3), np.array(r)

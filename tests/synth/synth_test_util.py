# Helpers shared by the synth tests (SCENE half): running roadside, scaled copies of the demo
# site's truth cameras, reading renders, parsing the spheres of a written scene.
import json
import os
import re
import shutil
import subprocess
import sys

import numpy as np

ROADSIDE = os.environ.get("ROADSIDE", "roadside")
SOURCE = os.environ.get("ROADSIDE_SOURCE_ROOT", os.path.join(os.path.dirname(__file__), "..", ".."))
DEMO = os.path.join(SOURCE, "sites", "demo")


def sanitized():
    """Whether ROADSIDE is built with AddressSanitizer (scripts/test's build-asan): its allocator
    keeps freed memory in quarantine and adds shadow memory, so resident-set figures say nothing
    about the program's own use."""
    exe = shutil.which(ROADSIDE) or ROADSIDE
    p = subprocess.run(["ldd", exe], capture_output=True, text=True)
    return "libasan" in p.stdout


def demo_calib(tmp):
    """TMP/calib holding the demo's true cam1 model (the calibration the dataset tests use)."""
    calib = os.path.join(tmp, "calib")
    os.makedirs(calib)
    with open(os.path.join(DEMO, "truth", "cam1.cameramodel"), "rb") as src, \
            open(os.path.join(calib, "cam1.cameramodel"), "wb") as dst:
        dst.write(src.read())
    return calib


def need_sumo():
    """Exit 77 (skipped) without SUMO's sumo and netconvert."""
    if not shutil.which("sumo") or not shutil.which("netconvert"):
        print("SKIP: sumo or netconvert not installed")
        sys.exit(77)


def demo_truth_calib_all(tmp, cams=("cam1", "cam2", "cam3", "cam4")):
    """TMP/calib holding the demo's true models of `cams`; returns its path."""
    calib = os.path.join(tmp, "calib")
    os.makedirs(calib)
    for cam in cams:
        shutil.copy(os.path.join(DEMO, "truth", cam + ".cameramodel"), calib)
    return calib


def fail(msg, seed=None):
    print("FAIL: " + msg + ("" if seed is None else " (seed %d)" % seed))
    sys.exit(1)


def need_povray():
    if not shutil.which(os.environ.get("ROADSIDE_POVRAY", "povray")):
        print("SKIP: povray not installed")
        sys.exit(77)


def run(args, expect=0):
    p = subprocess.run([ROADSIDE] + args, capture_output=True, text=True)
    if expect is not None and p.returncode != expect:
        fail("roadside %s: exit %d (expected %d)\nstdout: %s\nstderr: %s"
             % (" ".join(args), p.returncode, expect, p.stdout, p.stderr))
    return p


def scaled_camera(calib_dir, cam_id, width, pinhole, fy_over_fx=1.0, dcx=0.0, dcy=0.0,
                  height=None):
    """Writes calib_dir/cam_id.cameramodel: the demo truth camera scaled to `width` pixels,
    pinhole core only (pinhole=True) or with its OPENCV8 distortion; returns the model.
    `height` crops or extends the image symmetrically (default: the same aspect)."""
    import mrcal
    m = mrcal.cameramodel(os.path.join(DEMO, "truth", cam_id + ".cameramodel"))
    lens, intr = m.intrinsics()
    W0, H0 = m.imagersize()
    s = width / W0
    H = int(round(H0 * s)) if height is None else height
    dcy += (H - H0 * s) / 2
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


def ground_vehicles(model, N, seed, v_range=(0.45, 0.95), u_range=(0.05, 0.95)):
    """N vehicles of all classes standing on the ground plane up = 0 where random pixels of the
    model's image look (u uniform over the width, v in v_range of the height)."""
    import mrcal
    rng = np.random.default_rng(seed)
    lens, intr = model.intrinsics()
    W, H = model.imagersize()
    rt_enu_cam = mrcal.invert_rt(model.extrinsics_rt_fromref())
    classes = ["sedan", "hatchback", "suv", "pickup", "van", "bus", "box_truck",
               "articulated_truck"]
    out = []
    for i in range(N):
        q = np.array([rng.uniform(*u_range) * W, rng.uniform(*v_range) * H])
        d = mrcal.rotate_point_r(rt_enu_cam[:3], mrcal.unproject(q, lens, intr))
        c = rt_enu_cam[3:]
        p = c - c[2] / d[2] * d
        out.append({"class": classes[i % len(classes)], "e": float(p[0]), "n": float(p[1]),
                    "yaw_deg": float(rng.uniform(0, 360)), "id": "v%d" % i})
    return out


def box_corners_enu(v, L, W, H):
    """(8,3) corners of a vehicle's box on the ground up = 0 (synth/fleet/rs_synth_vehicle.h's frame)."""
    y = np.radians(v["yaw_deg"])
    f = np.array([np.sin(y), np.cos(y), 0.0])
    l = np.array([-np.cos(y), np.sin(y), 0.0])
    c = np.array([v["e"], v["n"], 0.0])
    return np.array([c + sx * L / 2 * f + sy * W / 2 * l + np.array([0, 0, z])
                     for z in (0, H) for sy in (-1, 1) for sx in (-1, 1)])


def shutil_which_povray():
    return shutil.which(os.environ.get("ROADSIDE_POVRAY", "povray"))


def small_pinhole(tmp, width=320, height=200):
    """The demo's cam1 as a small pinhole in tmp/calib: (calib_dir, model, W, H, lens, intr)."""
    calib = os.path.join(tmp, "calib")
    model = scaled_camera(calib, "cam1", width, True, height=height)
    W, H = model.imagersize()
    lens, intr = model.intrinsics()
    return calib, model, W, H, lens, intr

"""What the localise tests share: a simulated site calibrated by `roadside calib`, truth ground
points drawn in its images, and the ground point of a pixel by mrcal's Python (the oracle)."""
import os
import shutil
import sys

import mrcal
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "common"))
from rs_check import check, run  # noqa: E402,F401


def simulate_and_calibrate(tmp, seed, cameras=4, extra=()):
    """TMP/site-SEED (roadside site simulate) and TMP/calib-SEED (roadside calib): (site, calib)."""
    site = os.path.join(tmp, f"site-{seed}")
    calib = os.path.join(tmp, f"calib-{seed}")
    p = run("site", "simulate", site, "--seed", str(seed), "--cameras", str(cameras), *extra)
    if p.returncode != 0:
        raise SystemExit(f"site simulate: {p.stderr}")
    p = run("calib", site, "-o", calib)
    if p.returncode != 0:
        raise SystemExit(f"calib: {p.stderr}")
    return site, calib


def ground_point(model, q, n=(0.0, 0.0, 1.0), offset=0.0):
    """The point of the plane n . p = offset seen at pixel q (2,) through the cameramodel: mrcal's
    unproject (the full lens model) and a ray-plane intersection in ENU; None when it misses."""
    lens, intr = model.intrinsics()
    rt = model.extrinsics_rt_fromref()
    v_cam = mrcal.unproject(np.asarray(q, dtype=float), lens, intr, normalize=True)
    Rt = mrcal.invert_Rt(mrcal.Rt_from_rt(rt))  # camera -> ENU
    c = Rt[3]
    v = Rt[:3] @ v_cam
    n = np.asarray(n, dtype=float)
    den = n @ v
    if abs(den) < 1e-12:
        return None
    s = (offset - n @ c) / den
    return None if s <= 0 else c + s * v


def cleanup(tmp):
    shutil.rmtree(tmp, ignore_errors=True)


def read_csv(path):
    """The rows of a located-detections CSV as dicts (no quoting in these tests)."""
    lines = open(path).read().splitlines()
    head = lines[0].split(",")
    return [dict(zip(head, line.split(","))) for line in lines[1:]]

#!/usr/bin/env python3
# test_site_doc_example.py -- the complete example of docs/site-format.md is a valid site:
# extract every ```... file=PATH block into a temporary SITE folder, then
#  - `roadside site check SITE` passes with 0 errors and 0 warnings;
#  - `roadside site describe` loads south's OpenCV yaml as LENSMODEL_OPENCV5 with the stated
#    intrinsics;
#  - every pick equals mrcal.project of the landmark (ENU from `site describe --landmarks`) from
#    the pose the document states (yaw/pitch/roll of docs/conventions.md), to 0.06 px (the
#    picks are rounded to 0.1 px: 0.05 px, plus float noise).
import math
import os
import re
import shutil
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import site_fixture as fx  # noqa: E402

try:
    import mrcal
except ImportError as e:
    print("skipped: %s" % e)
    sys.exit(77)

# The poses the document states: camera centre in ENU (m), yaw, pitch, roll (degrees).
POSES = {"north": ((1.5, 24.0, 6.5), 180.0, -18.0, 0.0),
         "south": ((-2.0, -22.0, 6.0), 5.0, -16.0, 0.0)}


def rot_z(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def rot_x(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])


def R_enu_cam(yaw, pitch, roll):
    # docs/conventions.md: R_enu_cam = Rz(-yaw) Rx(pitch) R_enu_cam0 Rz(roll)
    R0 = np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])  # columns (1,0,0), (0,0,-1), (0,1,0)
    return rot_z(math.radians(-yaw)) @ rot_x(math.radians(pitch)) @ R0 @ rot_z(math.radians(roll))


def extract(doc, site):
    blocks = re.findall(r"^```\w* file=(\S+)\n(.*?)^```$", doc, re.S | re.M)
    if len(blocks) < 6:
        fx.fail("found %d example files in docs/site-format.md, expected 6" % len(blocks))
    for path, text in blocks:
        fx.write(os.path.join(site, path), text)
    os.makedirs(os.path.join(site, "backgrounds", "north"), exist_ok=True)
    return [p for p, _ in blocks]


def main():
    root = os.environ.get("ROADSIDE_SOURCE_ROOT", os.path.join(os.path.dirname(__file__), "..", ".."))
    with open(os.path.join(root, "docs", "site-format.md")) as f:
        doc = f.read()
    tmp = tempfile.mkdtemp(prefix="rs_site_doc_")
    site = os.path.join(tmp, "SITE")
    try:
        files = extract(doc, site)
        rc, out, err = fx.run("site", "check", site)
        if rc != 0 or out.splitlines()[-1] != "0 errors, 0 warnings":
            fx.fail("the documented example does not pass site check", out, err)
        rc, out, err = fx.run("site", "describe", "--landmarks", site)
        if rc != 0:
            fx.fail("describe of the documented example failed", out, err)
        if "lens model: LENSMODEL_OPENCV5, image 1280 x 720 px" not in out or \
                "intrinsics: 905.2 903.8 641.7 358.9 -0.112 0.031 0.0004 -0.0002 -0.004" not in out:
            fx.fail("south's OpenCV yaml did not load as the documented LENSMODEL_OPENCV5", out)
        enu, table = {}, False
        for line in out.splitlines():
            if line.startswith("landmarks (ENU"):
                table = True
            elif table and re.match(r"^  L\d\d ", line):
                f = line.split()
                enu[f[0]] = np.array([float(x) for x in f[1:4]])
        models = {"north": ("LENSMODEL_PINHOLE", [1150.0, 1150.0, 959.5, 539.5]),
                  "south": ("LENSMODEL_OPENCV5", [905.2, 903.8, 641.7, 358.9, -0.112, 0.031, 0.0004, -0.0002, -0.004])}
        worst = 0.0
        for cam, (c, yaw, pitch, roll) in POSES.items():
            R = R_enu_cam(yaw, pitch, roll)
            with open(os.path.join(site, "observations", cam + ".csv")) as f:
                rows = [l.split(",") for l in f.read().splitlines()[1:] if l.strip()]
            for row in rows:
                p_cam = R.T @ (enu[row[0]] - np.array(c))
                lens, intrinsics = models[cam]
                q = mrcal.project(p_cam, lens, np.array(intrinsics))
                d = np.abs(q - np.array([float(row[1]), float(row[2])])).max()
                if not np.isfinite(d) or d > 0.06:
                    fx.fail("%s %s: documented pick (%s, %s), projection (%.2f, %.2f)" %
                            (cam, row[0], row[1], row[2], q[0], q[1]))
                worst = max(worst, d)
        print("documented example: %d files, check passes, picks = projections of the stated poses "
              "to %.3f px" % (len(files), worst))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()

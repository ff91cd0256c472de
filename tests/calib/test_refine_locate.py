#!/usr/bin/python3
"""rs_camera_locate_ground against mrcal's Python module (an independent oracle).

Runs the driver test_refine_locate (argv[1]); for every pixel it mapped to the level plane
U = offset, checks with mrcal.transform_point_rt + mrcal.project that the point projects back
to the pixel within 1e-8 px and lies on the plane within 1e-9 m, and that the Python
unprojection ray meets the plane at the same point within 1e-6 m. Seeds 900-902."""
import json
import subprocess
import sys

try:
    import numpy as np
    import mrcal
except ImportError:
    print("mrcal's Python module is missing: skipped")
    sys.exit(77)

out = subprocess.run([sys.argv[1]], check=True, capture_output=True, text=True)
if out.stderr:
    print("FAIL: the library printed:", out.stderr)
    sys.exit(1)
fails = 0
n_ok = 0
worst = {"reproj_px": 0.0, "plane_m": 0.0, "ray_m": 0.0}
for line in out.stdout.splitlines():
    c = json.loads(line)
    if c["status"] != 0:
        print("FAIL: status", c["status"], "for", c["model"], c["q"])
        fails += 1
        continue
    intr = np.array(c["intrinsics"])
    rt = np.array(c["rt"])
    p = np.array(c["p"])
    q = np.array(c["q"])
    qp = mrcal.project(mrcal.transform_point_rt(rt, p), c["model"], intr)
    e_px = float(np.linalg.norm(qp - q))
    e_plane = abs(p[2] - c["offset"])
    # Python's own ray: camera centre + lambda R^T v
    v = mrcal.unproject(q, c["model"], intr)
    rt_enu_cam = mrcal.invert_rt(rt)
    C = rt_enu_cam[3:]
    d = mrcal.rotate_point_r(rt_enu_cam[:3], v)
    lam = (c["offset"] - C[2]) / d[2]
    e_ray = float(np.linalg.norm(C + lam * d - p))
    worst["reproj_px"] = max(worst["reproj_px"], e_px)
    worst["plane_m"] = max(worst["plane_m"], e_plane)
    worst["ray_m"] = max(worst["ray_m"], e_ray)
    if not (e_px < 1e-8 and e_plane < 1e-9 and e_ray < 1e-6):
        print(f"FAIL {c['model']} q {q}: reprojection {e_px:.3g} px, off plane {e_plane:.3g} m, "
              f"from the Python ray {e_ray:.3g} m")
        fails += 1
    n_ok += 1
print(f"{n_ok} pixels; worst reprojection {worst['reproj_px']:.3g} px, off plane "
      f"{worst['plane_m']:.3g} m, distance to mrcal-Python's ray intersection {worst['ray_m']:.3g} m")
if n_ok < 100:
    print("FAIL: too few pixels checked")
    fails += 1
sys.exit(1 if fails else 0)

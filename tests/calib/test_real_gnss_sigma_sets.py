#!/usr/bin/env python3
"""Issue 13, "What must show", first line, on real data: the GNSS probe vehicle
(../shared/real/gnss_probe_vehicle) with its RAW heights, calibrated with each of the four sets of
sigmas the issue names -- (horizontal m, vertical m, pixel px) = (0.5, 1.0, 8), (1.0, 0.3, 3),
(1.0, 3.0, 3), (2.0, 3.0, 5) -- under the leave-one-out protocol of test_real_gnss.py as a user
runs it: the site says "landmark_heights": "unreliable" (roadside's ground model replaces the raw
heights, docs/site-format.md), `roadside calib --refine focal` on 42 fixes, `roadside locate`
of the left-out box centre, its horizontal distance to the GNSS fix. Prints each set's median,
mean and worst, and the least-squares ground homography's (test_real_gnss.py, the oracle).

Asserted: every fold calibrates and locates, and every set's median is under the issue's 1.70 m:
1.599, 1.436, 1.508 and 1.575 m on 2026-11-24 (REML variance components, the final solve an
M-estimate under Cauchy's loss at the estimated noise; with a plain least-squares final solve the
fourth set was 1.911 m: docs/calibration.md, "Real data").
A second pass (issue 38, item 4) writes the same sites with NOTHING declared beyond the sigmas (no
"landmark_heights", no ground_plane): the site reader then judges the heights against the plane
they show (geo/rs_site_ground.c, docs/site-format.md "Heights nobody declared") and takes them
from the ground model, with a warning. Asserted: every set's median under the same 1.70 m
(2026-11-28: 1.592 / 1.603 / 1.588 / 1.587 m; 5.36 / 4.84 / 5.33 / 5.33 m before the judgement,
the raw heights taken as surveyed and the ground plane up = 0).
Skips (77) when the data is absent.
"""
import json
import os
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_real_gnss as base  # noqa: E402
import test_real_gnss_raw_heights as raw  # noqa: E402

SETS = [(0.5, 1.0, 8.0, True), (1.0, 0.3, 3.0, True), (1.0, 3.0, 3.0, True), (2.0, 3.0, 5.0, True)]
BAR_M = 1.70


def main():
    data = raw.load_data()
    if data is None:
        return 77
    rows, origin, p_enu, q = data
    failed = False
    with tempfile.TemporaryDirectory(prefix="roadside-gnss-sets-") as tmp:
        for (h, v, px, asserted), declared in [(s, True) for s in SETS] + [(s, False) for s in SETS]:
            base.SIGMA_H_M, base.SIGMA_PX = h, px  # what write_site states (the module's constants)
            errs = []
            for k in range(len(rows)):
                d = os.path.join(tmp, f"{h}_{v}_{px}_{declared}_{k:02d}")
                raw.write_raw_site(d, [r for r in rows if r["i"] != k], origin, v)
                if not declared:  # nothing beyond the sigmas: the reader judges the heights
                    with open(os.path.join(d, "site.json")) as f:
                        site = json.load(f)
                    del site["landmark_heights"]
                    with open(os.path.join(d, "site.json"), "w") as f:
                        json.dump(site, f, indent=1)
                err, why = raw.locate_error(d, q[k], p_enu[k])
                if err is None:
                    print(f"FAIL: sigmas {h}/{v}/{px}: fold {k}: {why}")
                    failed = True
                    err = np.inf
                errs.append(err)
            e = np.array(errs)
            ok = np.median(e) < BAR_M
            what = "raw heights \"unreliable\"" if declared else "raw heights, nothing declared"
            print(f"sigmas {h} m / {v} m / {px:g} px, {what}: leave-one-out median "
                  f"{np.median(e):.3f} m, mean {e[np.isfinite(e)].mean():.3f} m, max {e.max():.3f} m "
                  f"({'under' if ok else 'NOT under'} {BAR_M} m{'' if asserted else '; not asserted: open'})")
            if asserted and not ok:
                print(f"FAIL: sigmas {h}/{v}/{px}: median {np.median(e):.3f} m is not under {BAR_M} m")
                failed = True
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

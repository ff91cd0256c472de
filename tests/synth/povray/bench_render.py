#!/usr/bin/env python3
# Benchmark (not a test): `roadside render` (culling + region) against a plain full-frame render
# (--full-frame) of the same scene: 720x480 view of the demo site's cam1 (OPENCV8 lens and its
# pinhole core), N vehicles on the ground in view, composited onto a background.
# usage: bench_render.py [N=10] [repeats=3]   (ROADSIDE, ROADSIDE_SOURCE_ROOT as for the tests)
import os
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402


def timed(args):
    """CPU seconds (user + sys of roadside and povray: robust to a loaded machine), stdout."""
    import resource
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    p = u.run(args)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime), p.stdout.split()


def main():
    u.need_povray()
    import cv2
    N = int(sys.argv[1]) if len(sys.argv) > 1 else 10
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    print("%-8s %-9s %4s %10s %10s %8s %14s %14s" % ("lens", "placement", "N", "render_cpu", "full_cpu",
                                                 "speedup", "region", "povray_wall r/f"))
    placements = {"spread": ((0.55, 0.95), (0.05, 0.95)), "clustered": ((0.6, 0.8), (0.3, 0.6))}
    for lens, placement in [(a, b) for a in ("pinhole", "opencv8") for b in placements]:
        with tempfile.TemporaryDirectory() as tmp:
            calib = os.path.join(tmp, "calib")
            model = u.scaled_camera(calib, "cam1", 720, lens == "pinhole", height=480)
            W, H = model.imagersize()
            vs = u.ground_vehicles(model, N, 1, *placements[placement])
            veh = os.path.join(tmp, "veh.json")
            u.write_json(veh, vs)
            bg = os.path.join(tmp, "bg.png")
            cv2.imwrite(bg, np.full((H, W, 3), 90, np.uint8))
            base = ["render", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles", veh,
                    "--background", bg]
            tr, tf = [], []
            for k in range(repeats):
                t, wr = timed(base + ["-o", os.path.join(tmp, "r%d" % k)])
                tr.append(t)
                t, wf = timed(base + ["-o", os.path.join(tmp, "f%d" % k), "--full-frame"])
                tf.append(t)
            # the render composited and its ID pass holds the vehicles (the suite's check)
            img = u.read_png(os.path.join(tmp, "r0", "image.png"))
            ids = u.read_png(os.path.join(tmp, "r0", "ids.png"))
            seen = len(set(np.unique(ids).tolist()) - {0})
            if img.shape != (H, W, 3) or seen < N // 3:
                u.fail("%s %s: image %s, %d of %d vehicles in the ID pass"
                       % (lens, placement, img.shape, seen, N))
            region = "%sx%s" % (int(wr[7]) - int(wr[5]) + 1, int(wr[8]) - int(wr[6]) + 1)
            print("%-8s %-9s %4d %10.3f %10.3f %8.2f %14s %7s/%-6s" % (
                lens, placement, N, np.median(tr), np.median(tf), np.median(tf) / np.median(tr), region,
                wr[10], wf[10]))
    print("(median CPU seconds of %d runs each, roadside + povray; region = the canvas rectangle"
          " povray rendered; povray_wall = wall seconds inside povray, last run)" % repeats)


if __name__ == "__main__":
    main()

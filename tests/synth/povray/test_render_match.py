#!/usr/bin/env python3
# issue 18: `roadside render --background` matches the lights and the environment the vehicles
# reflect to its background, as `roadside synth` does (docs/fleet.md, "Reflections of the
# scene"). Real POV-Ray, the demo site with its lanes, 4 vehicles of every class in front of a
# small pinhole of cam1, the sun given by --sun.
#
# Backgrounds: flat 16-bit PNGs (no 8-bit steps) of linear colour B0 = (0.3, 0.3, 0.3) and
# B1 = (0.15, 0.3, 0.6), i.e. B0 times (0.5, 1, 2) per channel.
# Oracles:
#   - the printed light level is the road's linear value over the road albedo the docs state
#     (0.078: docs/backgrounds.md): 0.3 / 0.078 and 0.35 / 0.078 (the mean of B1's channels),
#     within 0.5 %;
#   - linearity: the scene's lights and its environment (ground, horizon, zenith) all take the
#     background's per-channel factor, and POV-Ray's colour pass is linear in them, so every
#     vehicle pixel of rgba.png (16-bit linear) over B1 is its value over B0 times (0.5, 1, 2).
#     Checked on the pixels of full alpha whose value over B0 is in (0.02, 0.45) (above the
#     16-bit steps, below clipping at 1 after doubling): the 2nd and 98th percentiles of the
#     per-pixel ratio within 2 % of the factor. Were only the lights matched (the environment
#     left at the default), the reflections would not scale and the blue ratio would fall short;
#   - --no-match-light keeps the defaults: rgba.png over B0 and over B1 are then identical
#     (the background is only composited afterwards, into image.png).
import os
import re
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

SEED = 4
B0 = np.array([0.3, 0.3, 0.3])
FACTOR = np.array([0.5, 1.0, 2.0])
ALBEDO = 0.078


def srgb_encode(x):
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def main():
    u.need_povray()
    import cv2
    with tempfile.TemporaryDirectory() as tmp:
        calib, model, W, H, lens, intr = u.small_pinhole(tmp, 240, 150)
        vs = u.ground_vehicles(model, 4, SEED, v_range=(0.55, 0.9))
        veh = os.path.join(tmp, "veh.json")
        u.write_json(veh, vs)
        bgs = []
        for k, lin in enumerate((B0, B0 * FACTOR)):
            img = np.empty((H, W, 3), np.uint16)
            img[...] = np.round(srgb_encode(lin)[::-1] * 65535).astype(np.uint16)  # BGR
            path = os.path.join(tmp, "bg%d.png" % k)
            cv2.imwrite(path, img)
            bgs.append((path, lin))
        rgba = {}
        for match in (True, False):
            for k, (path, lin) in enumerate(bgs):
                out = os.path.join(tmp, "out%d%d" % (match, k))
                args = ["render", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles", veh,
                        "--background", path, "--sun", "135,40", "-o", out]
                p = u.run(args + ([] if match else ["--no-match-light"]))
                line = [x for x in p.stdout.splitlines() if x.startswith("light matched")]
                print("match %d, background %d: %s" % (match, k, line[0] if line else "(not matched)"))
                if match:
                    m = re.search(r"level ([0-9.]+)", line[0]) if line else None
                    if not m:
                        u.fail("no 'light matched ... level' line: %r" % p.stdout, SEED)
                    want = lin.mean() / ALBEDO
                    if abs(float(m.group(1)) / want - 1) > 0.005:
                        u.fail("background %d: light level %s, want %.4f" % (k, m.group(1), want), SEED)
                elif line:
                    u.fail("--no-match-light still matched: %s" % line[0], SEED)
                rgba[match, k] = u.read_png(os.path.join(out, "rgba.png")).astype(float) / 65535
        a0, a1 = rgba[True, 0], rgba[True, 1]
        full = (a0[..., 3] > 0.9999) & (a1[..., 3] > 0.9999)
        if full.sum() < 500:
            u.fail("only %d vehicle pixels" % full.sum(), SEED)
        for c in range(3):
            sel = full & (a0[..., c] > 0.02) & (a0[..., c] < 0.45)
            r = a1[..., c][sel] / a0[..., c][sel]
            lo, hi = np.percentile(r, [2, 98])
            print("channel %d: %d pixels, ratio 2nd-98th percentile %.4f - %.4f (want %.2f, +-2 %%)"
                  % (c, sel.sum(), lo, hi, FACTOR[c]))
            if sel.sum() < 300 or lo < FACTOR[c] * 0.98 or hi > FACTOR[c] * 1.02:
                u.fail("channel %d: ratio %.4f - %.4f over %d pixels, want %.2f" % (c, lo, hi, sel.sum(), FACTOR[c]),
                       SEED)
        d = np.abs(rgba[False, 0] - rgba[False, 1]).max()
        print("--no-match-light: max |rgba over B0 - over B1| = %.6f" % d)
        if d > 0:
            u.fail("--no-match-light: the render depends on the background (max diff %g)" % d, SEED)
        print("ok")


if __name__ == "__main__":
    main()

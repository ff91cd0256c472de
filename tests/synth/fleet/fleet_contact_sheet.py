#!/usr/bin/python3
# The fleet's contact sheet for docs/fleet.md: one vehicle of every class, seen three-quarters
# front by the demo's cam1 (scaled to 960 px, pinhole), rendered by `roadside render` over the
# demo's digital-twin background in sun (with its sun shadows) and overcast, each cropped round
# its object-ID pixels. Writes OUT (default docs/fleet_contact_sheet.png) and prints the render
# time of each image.
#   ROADSIDE=build/cli/roadside python3 tests/synth/fleet/fleet_contact_sheet.py [OUT] [BACKGROUND_DIR]
# BACKGROUND_DIR holds twin_*_sunny.png and twin_*_cloudy.png for cam1 (default
# out/demo/site/backgrounds/cam1, made by `roadside site render-backgrounds`).
import os
import sys
import tempfile
import time

import cv2
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from synth_test_util import DEMO, SOURCE, read_png, run, scaled_camera, write_json  # noqa: E402

CLASSES = ["sedan", "hatchback", "suv", "pickup", "van", "bus", "box_truck", "articulated_truck",
           "motorcycle", "bicycle"]
TILE_W, TILE_H = 150, 100


def ground_point(model, q):
    import mrcal
    lens, intr = model.intrinsics()
    rt_enu_cam = mrcal.invert_rt(model.extrinsics_rt_fromref())
    d = mrcal.rotate_point_r(rt_enu_cam[:3], mrcal.unproject(np.array(q, float), lens, intr))
    c = rt_enu_cam[3:]
    return c - c[2] / d[2] * d, c


def tile(rgb, ids):
    ys, xs = np.nonzero(ids)
    if len(xs) == 0:
        return np.zeros((TILE_H, TILE_W, 3), np.uint8)
    x0, x1, y0, y1 = xs.min(), xs.max(), ys.min(), ys.max()
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    half_w = max((x1 - x0) * 0.62, (y1 - y0) * 0.62 * TILE_W / TILE_H, 12)
    half_h = half_w * TILE_H / TILE_W
    H, W = ids.shape
    a, b = int(max(0, cx - half_w)), int(min(W, cx + half_w))
    c, d = int(max(0, cy - half_h)), int(min(H, cy + half_h))
    return cv2.resize(rgb[c:d, a:b], (TILE_W, TILE_H), interpolation=cv2.INTER_AREA)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(SOURCE, "docs", "fleet_contact_sheet.png")
    bgdir = sys.argv[2] if len(sys.argv) > 2 else os.path.join(SOURCE, "out", "demo", "site", "backgrounds", "cam1")
    with tempfile.TemporaryDirectory() as tmp:
        calib = os.path.join(tmp, "calib")
        model = scaled_camera(calib, "cam1", 960, True)
        W, H = model.imagersize()
        bgs = {}
        for kind, pat in (("sun", "1500Z_sunny"), ("overcast", "1500Z_cloudy")):
            src = [f for f in sorted(os.listdir(bgdir)) if pat in f][0]
            img = cv2.imread(os.path.join(bgdir, src), cv2.IMREAD_COLOR)
            bgs[kind] = os.path.join(tmp, kind + ".png")
            cv2.imwrite(bgs[kind], cv2.resize(img, (W, H), interpolation=cv2.INTER_CUBIC))
        p, cam_c = ground_point(model, (0.5 * W, 0.70 * H))
        az = np.degrees(np.arctan2(cam_c[0] - p[0], cam_c[1] - p[1]))  # from the vehicle to the camera
        rows = {"sun": [], "overcast": []}
        for i, cls in enumerate(CLASSES):
            v = [{"class": cls, "e": float(p[0]), "n": float(p[1]), "yaw_deg": float(az + 40), "variant": 11 + i,
                  "id": cls}]
            vf = os.path.join(tmp, "v.json")
            write_json(vf, v)
            for kind in ("sun", "overcast"):
                o = os.path.join(tmp, "r_%s_%s" % (cls, kind))
                args = ["render", os.path.join(DEMO), "--calib", calib, "--camera", "cam1", "--vehicles", vf,
                        "-o", o, "--background", bgs[kind], "--shadows", "--time", "2024-06-21T15:00Z",
                        "--antialias", "2"]
                if kind == "overcast":
                    args.append("--overcast")
                t0 = time.time()
                run(args)
                print("%-18s %-8s %.2f s" % (cls, kind, time.time() - t0))
                rgb = cv2.imread(os.path.join(o, "image.png"), cv2.IMREAD_COLOR)
                ids = read_png(os.path.join(o, "ids.png"))
                if ids.ndim == 3:
                    ids = ids[..., 0]
                rows[kind].append(tile(rgb, ids))
        grid = []
        for half in (0, 1):
            for kind in ("sun", "overcast"):
                grid.append(np.hstack(rows[kind][5 * half:5 * half + 5]))
        sheet = np.vstack(grid)
        tmp_out = out + ".tmp.png"
        cv2.imwrite(tmp_out, sheet, [cv2.IMWRITE_PNG_COMPRESSION, 9])
        os.replace(tmp_out, out)
        print("wrote %s (%d bytes)" % (out, os.path.getsize(out)))


if __name__ == "__main__":
    main()

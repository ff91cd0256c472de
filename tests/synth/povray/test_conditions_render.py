#!/usr/bin/env python3
# issue 40, conditions (docs/conditions.md): `roadside render --background B --condition C` over
# digital-twin backgrounds of the demo site (cam1 scaled to a 480 x 270 pinhole), one car placed
# by the test ~25 m in front of the camera, real POV-Ray. Oracles: mrcal's projection of points
# the test computes from the car's box (headlights, the road ahead and behind, the roof, the box
# mirrored in the ground) and numpy on the rendered PNGs and the ID image.
#   night: the car faces the camera; its brightest pixels (top 1 % of the ID mask's luminance)
#          lie in the projected lamp band (the box's front 0.4 m, 0.3..1.0 m up: >= 80 % of
#          them); the road 2..10 m ahead
#          (background pixels) is brighter with night-dry than day-dry over the same night
#          background by >= 1.5x in linear luminance; 4..8 m behind it, within 3 % (no light).
#   wet:   the car seen side on over the rain background: day-wet and day-dry differ (mean
#          |diff| >= 3 / 255) over the projection of the car's box mirrored in the ground
#          (minus the car's own pixels), the difference is red like the car (R > G, B), and
#          elsewhere off the car the two images are equal (<= 1 / 255 on 99.9 % of pixels); the
#          dry render shows no mirror image: its mirror region equals the background PNG.
#   snow:  day-snow against day-dry over the snow background: the roof pixels (the box's top
#          face shrunk to 60 % round its centre, projected, within the ID mask) are whiter:
#          mean luminance x >= 1.3 and mean saturation lower.
import json
import math
import os
import shutil
import sys
import tempfile

import cv2
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

L, W, H = 4.6, 1.8, 1.45


def lin(img8):
    x = img8.astype(np.float64) / 255.0
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)


def lum(x):
    return 0.2126 * x[..., 0] + 0.7152 * x[..., 1] + 0.0722 * x[..., 2]


def vehicle_frame(v, p_v):
    y = math.radians(v["yaw_deg"])
    f = np.array([math.sin(y), math.cos(y), 0.0])
    l = np.array([-math.cos(y), math.sin(y), 0.0])
    p_v = np.atleast_2d(p_v)
    return np.array([v["e"], v["n"], 0.0]) + p_v[:, :1] * f + p_v[:, 1:2] * l + p_v[:, 2:3] * np.array([0, 0, 1.0])


def project(model, p_enu):
    import mrcal
    lens, intr = model.intrinsics()
    return mrcal.project(mrcal.transform_point_rt(model.extrinsics_rt_fromref(), p_enu), lens, intr)


def hull_mask(q, Wi, Hi):
    m = np.zeros((Hi, Wi), np.uint8)
    cv2.fillConvexPoly(m, cv2.convexHull(np.round(q).astype(np.int32)), 1)
    return m.astype(bool)


def render(tmp, site, calib, bg, vehicles, cond, name):
    veh = os.path.join(tmp, name + ".json")
    u.write_json(veh, vehicles)
    out = os.path.join(tmp, name)
    u.run(["render", site, "--calib", calib, "--camera", "cam1", "--vehicles", veh, "-o", out,
           "--background", bg, "--condition", cond, "--time", "2024-06-21T10:00:00Z"])
    img = u.read_png(os.path.join(out, "image.png"))
    ids = cv2.imread(os.path.join(out, "ids.png"), cv2.IMREAD_UNCHANGED)
    return img, ids


def main():
    u.need_povray()
    import mrcal
    with tempfile.TemporaryDirectory() as tmp:
        tmp = os.environ.get("KEEP_TMP", tmp)
        site, calib = os.path.join(tmp, "site"), os.path.join(tmp, "calib")
        shutil.copytree(u.DEMO, site, ignore=shutil.ignore_patterns("truth"))
        model = u.scaled_camera(calib, "cam1", 480, True)
        Wi, Hi = model.imagersize()
        u.run(["site", "render-backgrounds", site, "--calib", calib, "--camera", "cam1",
               "--times", "2024-06-21T10:00:00Z", "--weather", "rain,snow"])
        u.run(["site", "render-backgrounds", site, "--calib", calib, "--camera", "cam1",
               "--times", "2024-06-21T23:00:00Z", "--weather", "cloudy"])
        bgdir = os.path.join(site, "backgrounds", "cam1")
        bg = {c: os.path.join(bgdir, f) for f in os.listdir(bgdir) for c in ("rain", "snow", "night") if c in f}
        # the car: on the ground where pixel (0.5 W, v) looks
        lens, intr = model.intrinsics()
        rt_enu_cam = mrcal.invert_rt(model.extrinsics_rt_fromref())
        c = rt_enu_cam[3:]

        def place(v_frac):
            d = mrcal.rotate_point_r(rt_enu_cam[:3], mrcal.unproject(np.array([0.5 * Wi, v_frac * Hi]), lens, intr))
            p = c - c[2] / d[2] * d
            print("car at e %.2f n %.2f, %.1f m from the camera" % (p[0], p[1], math.hypot(*(c[:2] - p[:2]))))
            return ({"class": "sedan", "e": float(p[0]), "n": float(p[1]), "id": "car", "length": L, "width": W,
                     "height": H, "colour": [0.55, 0.04, 0.04]}, math.degrees(math.atan2(c[0] - p[0], c[1] - p[1])))
        car, to_cam = place(0.72)

        # ---- night: headlights the brightest, the road ahead lit ----
        facing = dict(car, yaw_deg=to_cam)
        on, ids = render(tmp, site, calib, bg["night"], [facing], "night-dry", "night_on")
        off, _ = render(tmp, site, calib, bg["night"], [facing], "day-dry", "night_off")
        veh = ids == 1
        lv = lum(lin(on))
        top = lv >= np.quantile(lv[veh], 0.99)
        ys, xs = np.nonzero(top & veh)
        # the lamp band: the box's front 0.4 m, 0.3 .. 1.0 m up, across its width
        band = np.array([[x, y, zz] for x in (L / 2 - 0.4, L / 2 + 0.05) for y in (-W / 2, W / 2) for zz in (0.3, 1.0)])
        lampm = hull_mask(project(model, vehicle_frame(facing, band)), Wi, Hi)
        near = np.mean(lampm[ys, xs])
        print("night: %d brightest vehicle pixels (luminance >= %.3f), %.0f %% in the lamp band"
              % (len(xs), np.quantile(lv[veh], 0.99), 100 * near))
        if near < 0.8:
            u.fail("night: only %.0f %% of the vehicle's brightest pixels are at its lights" % (100 * near))

        def road(x0, x1):
            g = np.array([[x, y, 0.0] for x in np.linspace(x0, x1, 9) for y in np.linspace(-1.5, 1.5, 5)])
            m = hull_mask(project(model, vehicle_frame(facing, g)), Wi, Hi)
            return m & (ids == 0)
        ahead, behind = road(L / 2 + 2, L / 2 + 10), road(-L / 2 - 8, -L / 2 - 4)
        r_ahead = lum(lin(on))[ahead].mean() / lum(lin(off))[ahead].mean()
        r_behind = lum(lin(on))[behind].mean() / max(1e-9, lum(lin(off))[behind].mean())
        print("night: road 2..10 m ahead x %.2f (%d px), 4..8 m behind x %.3f (%d px), lights on / off"
              % (r_ahead, ahead.sum(), r_behind, behind.sum()))
        if not (r_ahead >= 1.5) or ahead.sum() < 50:
            u.fail("night: the road ahead is x %.2f brighter with the lights on (>= 1.5 expected)" % r_ahead)
        if behind.sum() > 20 and abs(r_behind - 1) > 0.03:
            u.fail("night: the road behind changed x %.3f" % r_behind)

        # ---- wet: the mirror image below the car ----
        far, far_to_cam = place(0.42)  # farther: the camera's view of the road grazes more (Fresnel)
        side = dict(far, yaw_deg=far_to_cam + 90)
        wet, wids = render(tmp, site, calib, bg["rain"], [side], "day-wet", "wet")
        dry, _ = render(tmp, site, calib, bg["rain"], [side], "day-dry", "dry")
        box = np.array([[sx * L / 2, sy * W / 2, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (0, -H)])
        mirror = hull_mask(project(model, vehicle_frame(side, box)), Wi, Hi) & (wids == 0)
        diff = wet.astype(np.float64) - dry.astype(np.float64)
        inside = np.abs(diff[mirror]).mean()
        red = diff[mirror].mean(axis=0)
        off_car = (wids == 0) & ~hull_mask(project(model, vehicle_frame(side, box * [1.2, 1.2, 1.3])), Wi, Hi)
        outside = np.mean(np.abs(diff[off_car]).max(axis=1) <= 1)
        print("wet: mirror region %d px, mean |wet - dry| %.2f / 255, mean diff RGB %s; elsewhere %.4f equal"
              % (mirror.sum(), inside, np.round(red, 2).tolist(), outside))
        if inside < 2 or not (red[0] > red[1] + 1 and red[0] > red[2] + 1):
            u.fail("wet: no red mirror image below the car (mean |diff| %.2f, RGB %s)" % (inside, red))
        bgimg = u.read_png(bg["rain"]).astype(np.float64)
        dry_same = np.mean(np.abs(dry.astype(np.float64) - bgimg)[mirror].max(axis=1) <= 1)
        print("dry: the mirror region equals the background on %.4f of its pixels" % dry_same)
        if dry_same < 0.999:
            u.fail("dry: something below the car (%.4f of the mirror region equals the background)" % dry_same)
        if outside < 0.999:
            u.fail("wet: the wet render differs from the dry one away from the car (%.4f equal)" % outside)

        # ---- snow: a white roof ----
        side = dict(car, yaw_deg=to_cam + 90)
        snow, sids = render(tmp, site, calib, bg["snow"], [side], "day-snow", "snow")
        clean, _ = render(tmp, site, calib, bg["snow"], [side], "day-dry", "clean")
        roofp = np.array([[sx * 0.3 * L / 2 * 0.6, sy * W / 2 * 0.6, H] for sx in (-1, 1) for sy in (-1, 1)])
        roof = hull_mask(project(model, vehicle_frame(side, roofp)), Wi, Hi) & (sids == 1)
        ls, lc = lum(lin(snow))[roof].mean(), lum(lin(clean))[roof].mean()

        def sat(x):
            x = lin(x)[roof]
            return np.mean((x.max(axis=1) - x.min(axis=1)) / np.maximum(x.max(axis=1), 1e-9))
        print("snow: roof %d px, luminance %.4f vs %.4f (x %.2f), saturation %.3f vs %.3f"
              % (roof.sum(), ls, lc, ls / lc, sat(snow), sat(clean)))
        if roof.sum() < 5 or not (ls / lc >= 1.3 and sat(snow) < sat(clean)):
            u.fail("snow: the roof is not whiter with snow (x %.2f)" % (ls / lc))
    print("ok")


if __name__ == "__main__":
    main()

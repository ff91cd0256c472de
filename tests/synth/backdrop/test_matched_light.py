#!/usr/bin/env python3
# issue 18, lighting matched to the background, end to end: two digital-twin backgrounds of the
# demo site rendered at different times (`roadside site render-backgrounds --times
# 2024-06-21T08:00:00Z,2024-06-21T15:00:00Z --weather sunny`: the sun in the east-south-east,
# then in the west), then `roadside synth` over each (6 images, 10 vehicles, --keep-invisible so
# that every vehicle of the scene is labelled), and again with --no-shadows (the same images
# without the shadows the vehicles cast on the background).
# Measured from the images: the shadow pixels are those darker with the shadows than without
# (luminance, more than 12 of 255); the vehicles' pixels are those of the no-shadow image that
# differ from the background. For each candidate sun azimuth (1-degree steps; the elevation the
# oracle's) the shadows of the labelled vehicles' boxes (footprint from bottom_center_enu_m and
# box3d, swept away from the sun by height / tan(elevation) on the ground plane, projected
# through the dataset's camera model with mrcal, minus the vehicles' pixels) are compared with
# the shadow pixels (intersection over union, summed over a background's images); the best
# azimuth is the direction the vehicles' shadows show.
# Oracle: the sun's azimuth at the site's origin and the background's time from the PSA
# algorithm (Blanco-Muriel et al. 2001, written out in tests/synth/backdrop/test_sun.py, not roadside's
# NOAA code). Tolerance: 3 degrees for each background's joint fit, 15 for each image's own
# (measured: joint -1.9 and -1.4 degrees; images up to -12; a box is not a car's shape). Six
# images per background, not three: with the shadow pass rasterised at full resolution
# (synth/povray/rs_synth_raster.h) the three first images' joint fit moved from -1.4 to -3.4 degrees at
# 15:00 (their own errors -4.4, -1.4, -5.4), the estimator's noise; over six, -1.4.
# The camera: the demo's cam1 position is oblique (8 m high, vehicles 20 - 40 m away) and hides
# most of a shadow that falls away from it behind the vehicle, so the test uses its own steep
# camera over the junction (30 m up, 75 degrees down, pinhole 480 x 480; docs/fleet.md gives
# the oblique camera's figures: -12 and -1.4 degrees).
import json
import math
import os
import shutil
import sys
import tempfile

import cv2
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # test_sun
import synth_test_util as u  # noqa: E402
from test_sun import psa  # noqa: E402

SEED = 1
TIMES = ["2024-06-21T08:00:00Z", "2024-06-21T15:00:00Z"]
TOL_JOINT_DEG, TOL_IMAGE_DEG = 3.0, 15.0


def steep_camera(calib):
    import mrcal
    p = np.radians(-75.0)
    z = np.array([0, np.cos(p), np.sin(p)])
    x = np.array([1.0, 0, 0])
    R = np.array([x, np.cross(z, x), z])
    C = np.array([0, -8.0, 30.0])
    os.makedirs(calib)
    mrcal.cameramodel(intrinsics=("LENSMODEL_PINHOLE", np.array([300.0, 300.0, 239.5, 239.5])),
                      imagersize=(480, 480),
                      extrinsics_rt_fromref=np.concatenate([mrcal.r_from_R(R), -R @ C])).write(
        os.path.join(calib, "cam1.cameramodel"))


def lum(bgr):
    return 0.114 * bgr[..., 0] + 0.587 * bgr[..., 1] + 0.299 * bgr[..., 2]


def box_shadow_mask(anns, sun_az_deg, sun_el_deg, model, W, H):
    import mrcal
    lens, intr = model.intrinsics()
    rt = model.extrinsics_rt_fromref()
    a, e = math.radians(sun_az_deg), math.radians(sun_el_deg)
    s = np.array([math.sin(a), math.cos(a)])
    M = np.zeros((H, W), np.uint8)
    for x in anns:
        y = math.radians(x["box3d"]["yaw_deg"])
        L, Wd, h = x["box3d"]["dimensions_m"]
        f, l = np.array([math.sin(y), math.cos(y)]), np.array([-math.cos(y), math.sin(y)])
        c = np.array(x["bottom_center_enu_m"][:2])
        fp = [c + sx * L / 2 * f + sy * Wd / 2 * l for sx, sy in ((1, 1), (1, -1), (-1, -1), (-1, 1))]
        hull = cv2.convexHull(np.array(fp + [p - h / math.tan(e) * s for p in fp], np.float32))[:, 0, :]
        poly = np.array([hull[i] + t * (hull[(i + 1) % len(hull)] - hull[i])
                         for i in range(len(hull)) for t in np.linspace(0, 1, 8, endpoint=False)])
        q = mrcal.project(mrcal.transform_point_rt(rt, np.concatenate([poly, np.zeros((len(poly), 1))], 1)), lens,
                          intr)
        cv2.fillPoly(M, [np.round(q * 16).astype(np.int32)], 1, shift=4)
    return M > 0


def fit(ds, dsn, bg_dir, sun_el_deg):
    """Per image and joint: the sun azimuth whose box shadows best match the shadow pixels."""
    import mrcal
    coco = json.load(open(os.path.join(ds, "annotations", "instances_train2017.json")))
    model = mrcal.cameramodel(os.path.join(ds, "cameras", "cam1.cameramodel"))
    W, H = model.imagersize()
    TI, TU = np.zeros(360), np.zeros(360)
    per_image = []
    for im in coco["images"]:
        a = cv2.imread(os.path.join(ds, "train2017", im["file_name"])).astype(float)
        b = cv2.imread(os.path.join(dsn, "train2017", im["file_name"])).astype(float)
        bg = cv2.imread(os.path.join(bg_dir, im["background"] + ".png")).astype(float)
        dark = (lum(b) - lum(a)) > 12
        veh = np.abs(b - bg).max(-1) > 2
        anns = [x for x in coco["annotations"] if x["image_id"] == im["id"]]
        if dark.sum() < 500 or len(anns) < 3:
            u.fail("%s: %d shadow pixels, %d vehicles" % (im["file_name"], dark.sum(), len(anns)), SEED)
        iou = np.zeros(360)
        for az in range(360):
            M = box_shadow_mask(anns, az, sun_el_deg, model, W, H) & ~veh
            inter, uni = (M & dark).sum(), (M | dark).sum()
            iou[az] = inter / max(uni, 1)
            TI[az] += inter
            TU[az] += uni
        per_image.append((im["file_name"], int(iou.argmax()), iou.max(), int(dark.sum()), len(anns)))
    j = TI / np.maximum(TU, 1)
    return int(j.argmax()), j.max(), per_image


def adiff(a, b):
    return (a - b + 180) % 360 - 180


def main():
    u.need_povray()
    import calendar
    import time
    with tempfile.TemporaryDirectory() as tmp:
        site = os.path.join(tmp, "site")
        shutil.copytree(u.DEMO, site)
        calib = os.path.join(tmp, "calib")
        steep_camera(calib)
        p = u.run(["site", "render-backgrounds", site, "--calib", calib, "--camera", "cam1", "--times",
                   ",".join(TIMES), "--weather", "sunny"])
        print(p.stdout.strip())
        origin = json.load(open(os.path.join(site, "site.json")))["origin"]
        fitted = []
        for T in TIMES:
            t = calendar.timegm(time.strptime(T, "%Y-%m-%dT%H:%M:%SZ"))
            az, el = psa(origin["lat"], origin["lon"], t)
            name = "twin_%sZ_sunny" % T.replace("-", "").replace(":", "")[:13]
            dss = []
            for extra in ([], ["--no-shadows"]):
                ds = os.path.join(tmp, name + "".join(extra))
                u.run(["synth", "--val-fraction", "0", site, "--calib", calib, "--camera", "cam1", "--count", "6", "--seed", str(SEED),
                       "--vehicles", "10", "--keep-invisible", "--backgrounds", "name=" + name, "-o", ds,
                       "--jobs", "1"] + extra)
                dss.append(ds)
            best, best_iou, per_image = fit(dss[0], dss[1], os.path.join(site, "backgrounds", "cam1"), el)
            print("%s: sun (PSA) azimuth %.2f, elevation %.2f deg; the vehicles' shadows fit a sun at %d deg "
                  "(IoU %.3f; error %+.1f deg, tolerance %.0f)" % (T, az, el, best, best_iou, adiff(best, az),
                                                                  TOL_JOINT_DEG))
            for fn, b, iou, n, nv in per_image:
                print("  %s: %d vehicles, %d shadow px: sun at %d deg (IoU %.3f; error %+.1f, tolerance %.0f)"
                      % (fn, nv, n, b, iou, adiff(b, az), TOL_IMAGE_DEG))
                if abs(adiff(b, az)) > TOL_IMAGE_DEG:
                    u.fail("%s %s: shadows fit a sun at %d deg, PSA says %.2f" % (T, fn, b, az), SEED)
            if abs(adiff(best, az)) > TOL_JOINT_DEG:
                u.fail("%s: shadows fit a sun at %d deg, PSA says %.2f" % (T, best, az), SEED)
            fitted.append(best)
        if abs(adiff(fitted[0], fitted[1])) < 100:
            u.fail("the two backgrounds' vehicle shadows point the same way: %s" % fitted, SEED)
    print("OK")


if __name__ == "__main__":
    main()

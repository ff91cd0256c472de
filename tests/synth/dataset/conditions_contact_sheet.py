#!/usr/bin/python3
# Issue 40's figures for docs/fleet.md (not part of the suite; about 2 minutes):
#
# 1. docs/synth_conditions.jpg: `roadside synth` frames over camera-like backgrounds in day,
#    dusk, night, rain and snow. The site is the demo simulated at 720x480 (`site simulate
#    --seed 1`), calibrated, its cam1 digital-twin backgrounds rendered (09:00 local sunny,
#    rain, snow; 19:40 UTC cloudy, the sun 3.7 degrees below the horizon: dusk; 23:30 local:
#    night) and each degraded into what a camera stores (blur 1.2 px in linear light, noise
#    variance 4e-5 + 3e-4 v in stored units, JPEG quality 85), so that the camera's look has
#    something to match. Each tile is one `roadside synth --camera cam1 --backgrounds name=...
#    --count 1` image, at half size, the condition synth recorded for it written on it.
# 2. docs/fleet_side_by_side.jpg: the real Aalborg frame (../shared/real/aalborg_roadside:
#    imported and calibrated as a user does, `site import` + `calib --refine focal`) with a
#    rendered dark hatchback in the other lane at the real parked car's distance (the pixel
#    under the real car located on the ground, `roadside locate`), `roadside render
#    --background --shadows` at the frame's time of day, cropped round both cars, 2x.
#
#   ROADSIDE=build/cli/roadside /usr/bin/python3 tests/synth/dataset/conditions_contact_sheet.py [DOCS_DIR]
import json
import os
import subprocess
import sys
import tempfile

import cv2
import numpy as np

ROADSIDE = os.environ.get("ROADSIDE", "roadside")
SOURCE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..")
SHARED = os.environ.get("ROADSIDE_SHARED", os.path.join(SOURCE, "..", "shared"))
TILES = [("day (sunny)", "twin_20240621T0700Z_sunny"), ("dusk", "twin_20240621T1940Z_cloudy"),
         ("night", "twin_20240621T2130Z_night"), ("rain (wet road)", "twin_20240621T0700Z_rain"),
         ("snow", "twin_20240621T0700Z_snow")]


def run(*args, cwd=None):
    p = subprocess.run([ROADSIDE, *args], capture_output=True, text=True, cwd=cwd)
    if p.returncode != 0:
        sys.exit(f"roadside {' '.join(args)}: {p.stderr.strip()}")
    return p.stdout


def degrade(site, rng):
    """Each twin background of site.json into a camera-like JPEG; site.json points at them."""
    path = os.path.join(site, "site.json")
    s = json.load(open(path))
    for cam in s["cameras"]:
        for b in cam.get("background_images", []):
            p = os.path.join(site, b["file"])
            v = cv2.imread(p).astype(np.float64) / 255
            lin = np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)
            lin = cv2.GaussianBlur(lin, (0, 0), 1.2)
            v = np.where(lin <= 0.0031308, lin * 12.92, 1.055 * lin ** (1 / 2.4) - 0.055)
            v = v + rng.normal(size=v.shape) * np.sqrt(4e-5 + 3e-4 * np.clip(v, 0, 1))
            q = os.path.splitext(p)[0] + ".jpg"
            cv2.imwrite(q, np.clip(np.round(v * 255), 0, 255).astype(np.uint8), [cv2.IMWRITE_JPEG_QUALITY, 85])
            os.remove(p)
            b["file"] = os.path.splitext(b["file"])[0] + ".jpg"
    json.dump(s, open(path, "w"), indent=1)


def label(img, text):
    cv2.putText(img, text, (8, 24), cv2.FONT_HERSHEY_SIMPLEX, 0.7, (0, 0, 0), 4, cv2.LINE_AA)
    cv2.putText(img, text, (8, 24), cv2.FONT_HERSHEY_SIMPLEX, 0.7, (255, 255, 255), 1, cv2.LINE_AA)


def conditions_sheet(tmp, out_png):
    site, cal = os.path.join(tmp, "d480"), os.path.join(tmp, "cal")
    run("site", "simulate", site, "--seed", "1", "--image", "720x480")
    run("calib", site, "-o", cal)
    run("site", "render-backgrounds", site, "--calib", cal, "--camera", "cam1", "--times",
        "2024-06-21T09:00+02:00", "--weather", "sunny,rain,snow")
    run("site", "render-backgrounds", site, "--calib", cal, "--camera", "cam1", "--times", "2024-06-21T19:40Z",
        "--weather", "cloudy")
    run("site", "render-backgrounds", site, "--calib", cal, "--camera", "cam1", "--times", "2024-06-21T23:30+02:00")
    degrade(site, np.random.default_rng(1))
    tiles = []
    for k, (name, bg) in enumerate(TILES):
        out = os.path.join(tmp, f"ds{k}")
        run("synth", site, "--calib", cal, "--camera", "cam1", "--backgrounds", f"name={bg}", "--count", "1",
            "--seed", "3", "--vehicles", "12", "-o", out)
        coco = json.load(open(os.path.join(out, "annotations", "instances_train2017.json")))
        im = coco["images"][0]
        img = cv2.imread(os.path.join(out, "train2017", im["file_name"]))
        tile = cv2.resize(img[60:420, 0:720], (540, 270), interpolation=cv2.INTER_AREA)
        label(tile, f"{name}: {im.get('condition', '?')}, {len(coco['annotations'])} vehicles")
        tiles.append(tile)
        print(f"{name}: {bg}, condition {im.get('condition')}, {len(coco['annotations'])} labels")
    tiles.append(np.full_like(tiles[0], 255))
    sheet = np.vstack([np.hstack(tiles[0:3]), np.hstack(tiles[3:6])])
    cv2.imwrite(out_png, sheet, [cv2.IMWRITE_JPEG_QUALITY, 90])
    print(f"{out_png}: {sheet.shape[1]}x{sheet.shape[0]}")


def side_by_side(tmp, out_png):
    real = os.path.join(SHARED, "real", "aalborg_roadside")
    pix = [line.split(",") for line in open(os.path.join(real, "pix.csv")).read().split()]
    utm = [line.split(",") for line in open(os.path.join(real, "utm.csv")).read().split()]
    pts = os.path.join(tmp, "aalborg.csv")
    with open(pts, "w") as f:
        f.write("e,n,u,v\n" + "".join(f"{e},{n},{u},{v}\n" for (e, n), (u, v) in zip(utm, pix)))
    frame = os.path.join(tmp, "aalborg.jpg")
    with open(os.path.join(real, "frame.jpg"), "rb") as a, open(frame, "wb") as b:
        b.write(a.read())
    site = os.path.join(tmp, "aalborg")
    run("site", "import", site, "--points", pts, "--crs", "EPSG:25832")
    run("calib", site, "--refine", "focal")
    cal = os.path.join(site, "calib")
    # the real parked car stands with its wheels on row 324 around column 165; the other lane
    # at that distance is around column 320
    loc = run("locate", site, "--camera", "aalborg", "--calib", cal, "165", "324").split()
    other = run("locate", site, "--camera", "aalborg", "--calib", cal, "320", "324").split()
    e, n = float(other[0]), float(other[1])
    print(f"the real car's ground point: e {float(loc[0]):.1f} n {float(loc[1]):.1f} m; the rendered one: "
          f"e {e:.1f} n {n:.1f} m")
    veh = os.path.join(tmp, "veh.json")
    json.dump([{"class": "hatchback", "e": e, "n": n, "yaw_deg": 273, "colour": "#181818"}], open(veh, "w"))
    out = os.path.join(tmp, "render")
    print(run("render", site, "--calib", cal, "--camera", "aalborg", "--vehicles", veh, "-o", out, "--background",
              frame, "--shadows", "--time", "2024-09-10T11:00:00Z").strip())
    img = cv2.imread(os.path.join(out, "image.png"))
    crop = cv2.resize(img[200:380, 60:480], (840, 360), interpolation=cv2.INTER_CUBIC)
    label(crop, "left: the real car; right: rendered at the same distance")
    cv2.imwrite(out_png, crop, [cv2.IMWRITE_JPEG_QUALITY, 90])
    print(f"{out_png}: {crop.shape[1]}x{crop.shape[0]}")


def main():
    docs = sys.argv[1] if len(sys.argv) > 1 else os.path.join(SOURCE, "docs")
    with tempfile.TemporaryDirectory(prefix="rs_sheet40_") as tmp:
        conditions_sheet(tmp, os.path.join(docs, "synth_conditions.jpg"))
        side_by_side(tmp, os.path.join(docs, "fleet_side_by_side.jpg"))


if __name__ == "__main__":
    main()

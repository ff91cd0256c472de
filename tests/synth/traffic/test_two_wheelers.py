#!/usr/bin/env python3
# issue 18: two-wheelers in the default traffic mix (rs_synth_class_mix_default), labelled and
# rendered.
#  1. The default mix over many draws (test_class_mix_draws: one straight lane 200 km long, 20
#     seeds, about 180,000 vehicles) against the shares computed HERE from the cited figures
#     (docs/traffic.md, "Class mix"; DfT road traffic estimates for Great Britain):
#       urban motor traffic (urban A 49.9 + urban minor 66.6 bn vehicle miles, year to March 2017)
#       of all motor traffic (324.3); motorcycles 2.7 bn miles (2018), assumed urban in that
#       proportion; pedal cycles on minor urban roads 2.0 bn miles (60 % of 3.3, 2018);
#       shares of urban traffic (motor + those cycles): motorcycle 0.82 %, bicycle 1.69 %;
#     the motor vehicles keep their assumed mix (0.24, 0.22, 0.30, 0.03, 0.10, 0.02, 0.06, 0.03)
#     scaled to the rest. Pearson's chi-square over the ten classes below 27.88 (9 degrees of
#     freedom, p = 0.001), and each two-wheeler's count within 4 binomial sigmas of its share
#     (the code's weights are the cited shares rounded to 0.1 %). Bicycles ride at most SUMO's
#     bicycle default, 20 km/h (5.56 m/s) x the top speed fraction.
#  2. `roadside traffic --mix motorcycle=1,bicycle=1`: only those classes, both present; an
#     unknown class is refused naming the two-wheelers among the choices.
#  3. `roadside render --labels --bbox visible` of motorcycles and bicycles before the demo's cam1
#     (a small pinhole; real POV-Ray): each visible box equals the bounding box of that
#     vehicle's pixels in the ID pass (ids.png, the oracle; to 1e-9 px), the visible pixel counts
#     equal, the COCO category names are motorcycle / bicycle (ids 9 / 10), YOLO classes 8 / 9 in
#     data order, KITTI types Misc / Cyclist.
#  4. SUMO (when installed): `roadside traffic --sumo --mix motorcycle=1,bicycle=1` writes vTypes of
#     vClass motorcycle and bicycle, and `roadside synth --traffic-frames` over its frames labels
#     only motorcycles and bicycles, each with visible pixels and a box inside the image.
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

DRAWS = sys.argv[1]
SEED = 18
CLASSES = ["sedan", "hatchback", "suv", "pickup", "van", "bus", "box_truck", "articulated_truck",
           "motorcycle", "bicycle"]


def cited_shares():
    urban_motor = 49.9 + 66.6  # bn vehicle miles, urban A + urban minor roads, year to March 2017
    all_motor = 324.3
    moto = 2.7 * urban_motor / all_motor  # motorcycles' urban miles, assumed in that proportion
    cycles = 2.0  # pedal cycles on minor urban roads, 2018
    total = urban_motor + cycles
    p_moto, p_cyc = moto / total, cycles / total
    motor = np.array([0.24, 0.22, 0.30, 0.03, 0.10, 0.02, 0.06, 0.03])
    return np.concatenate([motor / motor.sum() * (1 - p_moto - p_cyc), [p_moto, p_cyc]])


def draws():
    p = subprocess.run([DRAWS, "20"], capture_output=True, text=True)
    if p.returncode != 0:
        u.fail("test_class_mix_draws: " + p.stderr, SEED)
    lines = [ln.split() for ln in p.stdout.splitlines()]
    counts = np.array([int(f[1]) for f in lines[:10]])
    if [f[0] for f in lines[:10]] != CLASSES:
        u.fail("class order %s" % [f[0] for f in lines[:10]], SEED)
    share = cited_shares()
    N = counts.sum()
    chi2 = float(((counts - N * share) ** 2 / (N * share)).sum())
    print("default mix over %d vehicles (chi-square %.2f, bound 27.88 at p = 0.001, 9 dof):" % (N, chi2))
    for c, n, p_ in zip(CLASSES, counts, share):
        print("  %-17s %6d  %.4f  (cited/assumed %.4f)" % (c, n, n / N, p_))
    if chi2 > 27.88:
        u.fail("default mix: chi-square %.2f > 27.88" % chi2, SEED)
    for k in (8, 9):
        sig = np.sqrt(N * share[k] * (1 - share[k]))
        if abs(counts[k] - N * share[k]) > 4 * sig:
            u.fail("%s: %d, expected %.0f +- %.0f" % (CLASSES[k], counts[k], N * share[k], 4 * sig), SEED)
    vmax, nb = float(lines[10][1]), int(lines[10][2])
    if nb == 0 or vmax > 5.56 * 1.0 + 1e-9:
        u.fail("bicycles: %d, fastest %.3f m/s (at most 5.56 x the top speed fraction)" % (nb, vmax), SEED)
    print("bicycles: fastest %.3f m/s of %d (bound 5.56 x the top speed fraction 1.0)" % (vmax, nb))


def traffic_mix(tmp):
    out = os.path.join(tmp, "two.json")
    u.run(["traffic", u.DEMO, "-o", out, "--seed", "3", "--mix", "motorcycle=1,bicycle=1"])
    vs = json.load(open(out))
    vs = vs["vehicles"] if isinstance(vs, dict) else vs
    got = sorted(set(v["class"] for v in vs))
    if got != ["bicycle", "motorcycle"]:
        u.fail("--mix motorcycle=1,bicycle=1 gave classes %s" % got, SEED)
    p = u.run(["traffic", u.DEMO, "-o", out, "--mix", "unicycle=1"], expect=None)
    if p.returncode == 0 or "motorcycle, bicycle" not in p.stderr:
        u.fail("--mix unicycle=1: exit %d, %r" % (p.returncode, p.stderr), SEED)
    print("roadside traffic --mix motorcycle=1,bicycle=1: %d vehicles, classes %s; unknown class: %s"
          % (len(vs), got, p.stderr.strip()))


def render_labels(tmp):
    import mrcal
    calib, model, W, H, lens, intr = u.small_pinhole(tmp)
    vs = u.ground_vehicles(model, 8, SEED, v_range=(0.5, 0.9), u_range=(0.1, 0.9))
    for i, v in enumerate(vs):
        v["class"] = "motorcycle" if i % 2 == 0 else "bicycle"
    veh = os.path.join(tmp, "veh.json")
    u.write_json(veh, vs)
    out = os.path.join(tmp, "out")
    u.run(["render", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles", veh, "-o", out, "--labels",
           "--bbox", "visible"])
    ids = u.read_png(os.path.join(out, "ids.png"))
    coco = json.load(open(os.path.join(out, "annotations", "instances_train2017.json")))
    cat = {c["id"]: c["name"] for c in coco["categories"]}
    if cat.get(9) != "motorcycle" or cat.get(10) != "bicycle":
        u.fail("COCO categories %s" % cat, SEED)
    by_index = {a["vehicle_index"]: a for a in coco["annotations"]}
    checked = {"motorcycle": 0, "bicycle": 0}
    yolo = [ln.split() for ln in open(os.path.join(out, "labels", "train2017", "image.txt"))]
    kitti = [ln.split() for ln in open(os.path.join(out, "label_2", "image.txt"))]
    for k, v in enumerate(vs):
        ys, xs = np.nonzero(ids == k + 1)
        a = by_index.get(k)
        if xs.size == 0:
            continue
        if a is None:
            u.fail("%s %d visible (%d px) but not labelled" % (v["class"], k, xs.size), SEED)
        want = [xs.min() - 0.5, ys.min() - 0.5, xs.max() - xs.min() + 1, ys.max() - ys.min() + 1]
        got = a["visible_bbox"]
        if np.max(np.abs(np.array(got, float) - want)) > 1e-9 or a["visible_pixels"] != xs.size:
            u.fail("%s %d: visible box %s / %s px, ID pass %s / %d px"
                   % (v["class"], k, got, a["visible_pixels"], want, xs.size), SEED)
        if cat[a["category_id"]] != v["class"]:
            u.fail("%s %d: category %s" % (v["class"], k, cat[a["category_id"]]), SEED)
        checked[v["class"]] += 1
    if min(checked.values()) < 2:
        u.fail("visible two-wheelers checked: %s (at least 2 of each)" % checked, SEED)
    ycls = sorted(set(int(r[0]) for r in yolo))
    ktypes = sorted(set(r[0] for r in kitti))
    if not set(ycls) <= {8, 9} or not set(ktypes) <= {"Misc", "Cyclist"} or len(yolo) != len(coco["annotations"]):
        u.fail("YOLO classes %s, KITTI types %s" % (ycls, ktypes), SEED)
    print("render: %s visible two-wheelers, each box equal to its ID pixels' box; YOLO classes %s, KITTI %s"
          % (checked, ycls, ktypes))


def sumo_synth(tmp):
    if not shutil.which("sumo") or not shutil.which("netconvert"):
        print("SUMO part skipped: sumo or netconvert not installed")
        return
    fr = os.path.join(tmp, "frames")
    u.run(["traffic", u.DEMO, "--sumo", "--seed", "3", "--duration", "90", "--warmup", "60", "--period", "5",
           "--mix", "motorcycle=1,bicycle=1", "-o", fr, "--keep", os.path.join(tmp, "sumo")])
    vcl = sorted(set(re.findall(r'vClass="([a-z]+)"', open(os.path.join(tmp, "sumo", "routes.rou.xml")).read())))
    if vcl != ["bicycle", "motorcycle"]:
        u.fail("SUMO vTypes of vClass %s" % vcl, SEED)
    print("SUMO routes: vClass %s" % vcl)
    calib = os.path.join(tmp, "calib_truth")
    os.makedirs(calib)
    for cam in ("cam1", "cam2", "cam3", "cam4"):
        shutil.copy(os.path.join(u.DEMO, "truth", cam + ".cameramodel"), calib)
    ds = os.path.join(tmp, "ds")
    u.run(["synth", "--val-fraction", "0", u.DEMO, "--calib", calib, "--count", "4", "-o", ds, "--seed", "5", "--size", "160x90",
           "--traffic-frames", fr, "--jobs", "1"])
    coco = json.load(open(os.path.join(ds, "annotations", "instances_train2017.json")))
    cat = {c["id"]: c["name"] for c in coco["categories"]}
    names = [cat[a["category_id"]] for a in coco["annotations"]]
    if not names or not set(names) <= {"motorcycle", "bicycle"}:
        u.fail("synth over the two-wheelers' frames labelled %s" % sorted(set(names)), SEED)
    W, H = 160, 90
    for a in coco["annotations"]:
        x, y, w, h = a["bbox"]
        # COCO's corner convention (issue 41): inside [0, W] x [0, H]
        if not (a["visible_pixels"] > 0 and w > 0 and h > 0 and x >= 0 and y >= 0 and x + w <= W + 1e-9
                and y + h <= H + 1e-9):
            u.fail("synth label %s" % a, SEED)
    print("synth over SUMO's two-wheelers: %d labels, %d motorcycles, %d bicycles"
          % (len(names), names.count("motorcycle"), names.count("bicycle")))


def main():
    draws()
    with tempfile.TemporaryDirectory() as tmp:
        traffic_mix(tmp)
        u.need_povray()
        render_labels(tmp)
        sumo_synth(tmp)
    print("OK")


if __name__ == "__main__":
    main()

#!/usr/bin/python3
# Issue 17: the dataset contract (docs/labels.md). One small `roadside synth` run (2 cameras,
# 4 images of 160x90, real POV-Ray), then:
#  - finding "images[0]: camera: missing": every image records its camera, background,
#    conditions, sun and calibration; the camera model copied into the dataset has the
#    recorded SHA-256 (hashlib) and projects each label's bottom_center_enu_m onto its
#    bottom_center (mrcal's Python, 1e-6 px); lat/lon agree with PROJ's cct (1e-9 deg);
#  - finding "perfect detector scores mAP 0.76": the dataset's own footprint boxes as detections
#    score mAP 1.0 in pixels and in metres with the calibration read from the dataset itself
#    (exactly 1 to 1e-9), and a detector whose boxes are shifted by 6 px scores less;
#  - no label for a vehicle with no visible pixel (--min-visibility default);
#  - the layouts the trainers load: COCO as pycocotools/YOLOX index it (info, licenses, ids,
#    file names under <split>/), Ultralytics YOLO (images/<split> -> labels/<split>, data.yaml,
#    normalised boxes in [0, 1]), KITTI (kitti/training/image_2, label_2, calib: 15 fields,
#    P2 3x4, numeric names; ImageSets).
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

SEED = 11
W, H = 160, 90


def sha256(path):
    return hashlib.sha256(open(path, "rb").read()).hexdigest()


def eval_json(tmp, gt, dets, extra=()):
    dpath = os.path.join(tmp, "dets.json")
    out = os.path.join(tmp, "eval.json")
    u.write_json(dpath, dets)
    u.run(["eval", gt, dpath, "--json", out] + list(extra))
    return json.load(open(out))


def check_contract(ds, coco, calib):
    import mrcal
    ann_dir = os.path.join(ds, "annotations")
    for im in coco["images"]:
        for key in ("camera", "background", "weather", "time_of_day", "sun_azimuth_deg",
                    "sun_elevation_deg", "calibration", "index"):
            if key not in im:
                u.fail("images[%d]: %s: missing" % (im["id"], key), SEED)
        cal = im["calibration"]
        model = os.path.normpath(os.path.join(ann_dir, cal["camera_model"]))
        if sha256(model) != cal["camera_model_sha256"]:
            u.fail("%s: SHA-256 differs from the recorded one" % model, SEED)
        src = os.path.join(calib, im["camera"] + ".cameramodel")
        if cal["source_sha256"] != sha256(src):
            u.fail("calibration source checksum differs for %s" % im["camera"], SEED)
        if tuple(mrcal.cameramodel(model).imagersize()) != (W, H):
            u.fail("%s: not at the dataset's size" % model, SEED)
    models = {im["id"]: mrcal.cameramodel(os.path.normpath(os.path.join(
        ann_dir, im["calibration"]["camera_model"]))) for im in coco["images"]}
    worst = 0.0
    enu = []
    for a in coco["annotations"]:
        m = models[a["image_id"]]
        p = np.array(a["bottom_center_enu_m"], dtype=float)
        lens, intr = m.intrinsics()
        q = mrcal.project(mrcal.transform_point_rt(m.extrinsics_rt_fromref(), p), lens, intr)
        if a.get("bottom_center") is not None:
            worst = max(worst, float(np.max(np.abs(q - np.array(a["bottom_center"])))))
        if a.get("visible_pixels", 1) <= 0:
            u.fail("annotation %d: a label for a vehicle with no visible pixel" % a["id"], SEED)
        for key in ("footprint_bbox", "body_bbox", "visible_bbox", "visibility", "box3d",
                    "bottom_center_lat_deg", "bottom_center_lon_deg"):
            if key not in a:
                u.fail("annotation %d: %s missing" % (a["id"], key), SEED)
        enu.append((p, a["bottom_center_lat_deg"], a["bottom_center_lon_deg"]))
    if worst > 1e-6:
        u.fail("bottom_center_enu_m projects %.3g px from bottom_center" % worst, SEED)
    print("contract: %d images, %d labels; bottom_center_enu_m reprojects within %.2g px"
          % (len(coco["images"]), len(coco["annotations"]), worst))
    # latitude/longitude against PROJ (cct, topocentric at the site origin)
    site = json.load(open(os.path.join(u.DEMO, "site.json")))
    o = site["origin"]
    if enu and shutil.which("cct"):
        pipe = ["cct", "-d", "12", "-I", "+proj=pipeline", "+step", "+proj=cart", "+ellps=WGS84",
                "+step", "+proj=topocentric", "+ellps=WGS84", "+lat_0=%r" % o["lat"],
                "+lon_0=%r" % o["lon"], "+h_0=%r" % o.get("h", 0.0)]
        text = "".join("%.12f %.12f %.12f 0\n" % tuple(p) for p, _, _ in enu)
        r = subprocess.run(pipe, input=text, capture_output=True, text=True)
        if r.returncode != 0:
            u.fail("cct: " + r.stderr)
        dmax = 0.0
        for line, (_, lat, lon) in zip(r.stdout.strip().splitlines(), enu):
            lon_c, lat_c = map(float, line.split()[:2])
            dmax = max(dmax, abs(lat_c - lat), abs(lon_c - lon))
        if dmax > 1e-9:
            u.fail("lat/lon differ from PROJ's by %.3g deg" % dmax, SEED)
        print("lat/lon agree with PROJ's cct within %.2g deg" % dmax)


def check_perfect(tmp, gt, coco):
    dets = [{"image_id": a["image_id"], "category_id": a["category_id"], "bbox": a["bbox"],
             "score": 1.0} for a in coco["annotations"]]
    if len(dets) < 3:
        u.fail("only %d labels: the test needs a few" % len(dets), SEED)
    px = eval_json(tmp, gt, dets)
    m = eval_json(tmp, gt, dets, ["--metres"])
    print("footprint boxes as detections: mAP %.12f (pixels), %.12f (metres, calibration from "
          "the dataset)" % (px["mAP"], m["mAP"]))
    for name, r in (("pixels", px), ("metres", m)):
        if abs(r["mAP"] - 1.0) > 1e-9 or abs(r["AR"] - 1.0) > 1e-9:
            u.fail("perfect detections: mAP %r AR %r in %s, expected 1" % (r["mAP"], r["AR"], name))
    if "thresholds_m" not in m:
        u.fail("--metres: the result is not in metres")
    bad = [dict(d, bbox=[d["bbox"][0] + 6.0] + d["bbox"][1:]) for d in dets]
    r = eval_json(tmp, gt, bad)
    print("boxes shifted by 6 px: mAP %.4f, AP@2 %s, AP@5 %s" % (r["mAP"], r["AP"]["2"], r["AP"]["5"]))
    # (a shifted box may land within 5 px of a neighbouring vehicle's point: AP@5 near 0)
    if not (r["mAP"] < 1.0 - 0.1 and r["AP"]["2"] == 0 and r["AP"]["5"] < 0.05):
        u.fail("a detector off by 6 px scores mAP %r" % r["mAP"])
    # --by weather works on the recorded tags (the finding: only "(missing)")
    g = eval_json(tmp, gt, dets, ["--by", "time_of_day"])
    if "(missing)" in g.get("groups", {}):
        u.fail("--by time_of_day: images without the tag")


def check_layouts(ds, coco):
    # COCO as pycocotools' COCO() indexes it and YOLOX's COCODataset reads it
    for key in ("info", "licenses", "images", "annotations", "categories"):
        if key not in coco:
            u.fail("COCO: %s missing" % key)
    ids = [im["id"] for im in coco["images"]]
    if len(set(ids)) != len(ids):
        u.fail("COCO: image ids repeat")
    imgs = {im["id"]: im for im in coco["images"]}
    cats = {c["id"] for c in coco["categories"]}
    aids = [a["id"] for a in coco["annotations"]]
    if len(set(aids)) != len(aids) or 0 in aids:
        u.fail("COCO: annotation ids repeat or are 0 (pycocotools treats 0 as none)")
    import cv2
    for im in coco["images"]:
        img = cv2.imread(os.path.join(ds, "train2017", im["file_name"]))
        if img is None or img.shape[:2] != (im["height"], im["width"]):
            u.fail("COCO: %s not under train2017/ at its size" % im["file_name"])
    for a in coco["annotations"]:
        x, y, w, h = a["bbox"]
        im = imgs[a["image_id"]]
        if a["category_id"] not in cats or w <= 0 or h <= 0 or a["iscrowd"] != 0:
            u.fail("COCO: annotation %d: bad category, box or iscrowd" % a["id"])
        # YOLOX: x1 = max(0, x), x2 = min(width, x1 + max(0, w)): boxes inside the image, in
        # COCO's corner convention (issue 41): [0, W] x [0, H], the footprint box + 0.5
        if x < -1e-9 or y < -1e-9 or x + w > im["width"] + 1e-9 or y + h > im["height"] + 1e-9:
            u.fail("COCO: annotation %d: box outside the image" % a["id"])
        fb = a["footprint_bbox"]
        if max(abs(x - fb[0] - 0.5), abs(y - fb[1] - 0.5), abs(w - fb[2]), abs(h - fb[3])) > 1e-12:
            u.fail("COCO: annotation %d: bbox %s is not footprint_bbox %s + 0.5" % (a["id"], a["bbox"], fb))
        seg = a.get("segmentation")
        if (np.array(seg).shape != (1, 8) or
                np.abs(np.array(seg[0]) - [x, y, x + w, y, x + w, y + h, x, y + h]).max() > 1e-9):
            u.fail("COCO: annotation %d: segmentation %s is not the box's polygon" % (a["id"], seg))
        if abs(a["area"] - w * h) > 1e-6 * max(1.0, w * h):
            u.fail("COCO: annotation %d: area is not w*h" % a["id"])
    # Ultralytics: img2label_paths replaces /images/ by /labels/ and the extension by .txt
    import re
    y = open(os.path.join(ds, "data.yaml")).read()
    fields = dict(re.findall(r"^(\w+):\s*(\S*)\s*$", y, re.M))
    names = re.findall(r"^\s+(\d+):\s*(\S+)\s*$", y, re.M)
    # no path: Ultralytics then takes the file's own folder as the root (issue 41: relocatable)
    # (run with --val-fraction 0: no val images, so val names the train images, as Ultralytics needs one)
    if "path" in fields or fields.get("train") != "images/train2017" or fields.get("val") != "images/train2017":
        u.fail("data.yaml: path/train/val wrong: %s" % fields)
    # the classes: 0..K-1 in the order of COCO's categories (by id), the same names
    cat_names = [c["name"] for c in sorted(coco["categories"], key=lambda c: c["id"])]
    if [int(i) for i, _ in names] != list(range(len(cat_names))) or [n for _, n in names] != cat_names:
        u.fail("data.yaml: names %s are not COCO's categories %s in order" % (names, cat_names))
    root = ds
    nlab = 0
    for f in sorted(os.listdir(os.path.join(root, fields["train"]))):
        ip = os.path.join(root, fields["train"], f)
        lp = os.path.splitext(ip.replace(os.sep + "images" + os.sep, os.sep + "labels" + os.sep))[0] + ".txt"
        if not os.path.isfile(lp):
            u.fail("YOLO: no label file where Ultralytics looks: " + lp)
        rows = np.loadtxt(lp, ndmin=2) if os.path.getsize(lp) else np.zeros((0, 5))
        if rows.size and (rows.shape[1] != 5 or rows[:, 1:].min() < 0 or rows[:, 1:].max() > 1
                          or rows[:, 0].max() > len(cat_names) - 1 or np.any(rows[:, 0] != np.round(rows[:, 0]))):
            u.fail("YOLO: %s: not class cx cy w h normalised to [0, 1]" % lp)
        nlab += len(rows)
    if nlab != len(coco["annotations"]):
        u.fail("YOLO: %d labels, COCO %d" % (nlab, len(coco["annotations"])))
    # KITTI: training/image_2/%06d.png, label_2/%06d.txt (15 fields), calib/%06d.txt (P2 3x4)
    kt = os.path.join(ds, "kitti", "training")
    nk = 0
    sets = open(os.path.join(ds, "kitti", "ImageSets", "train.txt")).read().split()
    for idx in sets:
        if not (len(idx) == 6 and idx.isdigit()):
            u.fail("KITTI: image name %s is not numeric" % idx)
        if cv2.imread(os.path.join(kt, "image_2", idx + ".png")) is None:
            u.fail("KITTI: image_2/%s.png missing" % idx)
        cal = {}
        for line in open(os.path.join(kt, "calib", idx + ".txt")):
            k, v = line.split(":", 1)
            cal[k] = np.array(v.split(), dtype=float)
        if cal["P2"].shape != (12,) or cal["R0_rect"].shape != (9,) or cal["Tr_velo_to_cam"].shape != (12,):
            u.fail("KITTI: calib/%s.txt: P2, R0_rect or Tr_velo_to_cam malformed" % idx)
        for line in open(os.path.join(kt, "label_2", idx + ".txt")):
            f = line.split()
            if len(f) != 15 or f[0] not in ("Car", "Van", "Bus", "Truck", "Cyclist", "Misc"):
                u.fail("KITTI: label_2/%s.txt: %r" % (idx, line))
            # the location projects through P2 onto the 2D box's bottom region
            P2 = cal["P2"].reshape(3, 4)
            X = np.array(list(map(float, f[11:14])) + [1.0])
            q = P2 @ X
            if not q[2] > 0:
                u.fail("KITTI: location behind the camera")
            nk += 1
    # KITTI's images are undistorted (issue 41, docs/labels.md "KITTI"): a vehicle at the border
    # whose box leaves the undistorted image is not in KITTI (42 of 43 here), never one more
    if not (0.9 * len(coco["annotations"]) <= nk <= len(coco["annotations"])):
        u.fail("KITTI: %d labels, COCO %d" % (nk, len(coco["annotations"])))
    print("layouts: COCO (info, licenses, %d images), YOLO (data.yaml, %d labels), KITTI (%d labels)"
          % (len(coco["images"]), nlab, nk))


def check_stats(ds, coco):
    """`roadside dataset stats` against counts made here from the COCO file and lanes.geojson: the
    images, the labels, and the labels whose bottom_center_enu_m lies within 15 m of the mean of
    the junction lanes' vertices (read here from lanes.geojson, converted to ENU with PROJ's cct)."""
    import re
    import subprocess
    p = u.run(["dataset", "stats", ds, "--site", u.DEMO])
    if p.returncode != 0:
        u.fail("dataset stats: exit %d: %s" % (p.returncode, p.stderr))
        return
    m = re.search(r"(\d+) images, (\d+) labels", p.stdout)
    if not m or (int(m.group(1)), int(m.group(2))) != (len(coco["images"]), len(coco["annotations"])):
        u.fail("dataset stats: images/labels %s vs COCO %d/%d" % (m and m.groups(), len(coco["images"]),
                                                                 len(coco["annotations"])))
    site = json.load(open(os.path.join(u.DEMO, "site.json")))
    o = site["origin"]
    lanes = json.load(open(os.path.join(u.DEMO, "lanes.geojson")))
    pts = [c for f in lanes["features"] if f["properties"].get("kind") == "junction"
           for c in f["geometry"]["coordinates"]]
    text = "".join("%.12f %.12f %.4f 0\n" % (c[0], c[1], c[2] if len(c) > 2 else o["h"]) for c in pts)
    pipe = ["cct", "-d", "9", "+proj=pipeline", "+step", "+proj=cart", "+ellps=WGS84", "+step",
            "+proj=topocentric", "+ellps=WGS84", "+lat_0=%r" % o["lat"], "+lon_0=%r" % o["lon"], "+h_0=%r" % o["h"]]
    enu = np.array([[float(v) for v in l.split()[:2]] for l in
                    subprocess.run(pipe, input=text, capture_output=True, text=True, check=True).stdout.splitlines()
                    if l.strip()])
    centre = enu.mean(axis=0)
    b = np.array([a["bottom_center_enu_m"][:2] for a in coco["annotations"] if a.get("bottom_center_enu_m")])
    near = int((np.hypot(*(b - centre).T) < 15).sum()) if len(b) else 0
    m = re.search(r"junction:\s+(\d+) of (\d+) labelled vehicles .* of \(E ([-\d.]+), N ([-\d.]+)\)", p.stdout)
    if not m or (int(m.group(1)), int(m.group(2))) != (near, len(b)) or \
            abs(float(m.group(3)) - centre[0]) > 0.01 or abs(float(m.group(4)) - centre[1]) > 0.01:
        u.fail("dataset stats: junction line %r vs %d of %d within 15 m of (%.2f, %.2f)" %
               (m and m.group(0), near, len(b), centre[0], centre[1]))
    print("dataset stats: %d of %d labels within 15 m of the junction centre (E %.2f, N %.2f), as counted here" %
          (near, len(b), centre[0], centre[1]))


def main():
    u.need_povray()
    with tempfile.TemporaryDirectory() as tmp:
        calib = os.path.join(tmp, "calib")
        os.makedirs(calib)
        for cam in ("cam1", "cam3"):
            shutil.copy(os.path.join(u.DEMO, "truth", cam + ".cameramodel"), calib)
        ds = os.path.join(tmp, "ds")
        p = u.run(["synth", u.DEMO, "--calib", calib, "--count", "4", "--val-fraction", "0", "-o", ds, "--seed", str(SEED),
                   "--camera", "cam1", "--camera", "cam3", "--size", "%dx%d" % (W, H),
                   "--vehicles", "12", "--jobs", "2"])
        print(p.stdout.strip())
        gt = os.path.join(ds, "annotations", "instances_train2017.json")
        coco = json.load(open(gt))
        check_contract(ds, coco, calib)
        check_perfect(tmp, gt, coco)
        check_layouts(ds, coco)
        check_stats(ds, coco)
    print("test_dataset_contract: ok")


if __name__ == "__main__":
    main()

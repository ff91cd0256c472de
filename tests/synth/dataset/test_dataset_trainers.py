#!/usr/bin/env python3
# issue 41, "datasets that a trainer takes unchanged": one `roadside synth` run with the default
# options (a validation split by default) loaded by Debian's torchvision through each layout's
# own documented rules, and one training step of a small torchvision detector on each:
#  - COCO: torchvision.datasets.CocoDetection(val2017, annotations/instances_val2017.json) and
#    the train split the same way;
#  - Ultralytics YOLO: data.yaml (no path: the file's folder is the root; train/val relative),
#    each image's label at its path with /images/ made /labels/ and the extension .txt, rows
#    "class cx cy w h" normalised;
#  - KITTI: torchvision.datasets.Kitti on its documented layout (ROOT/Kitti/raw/training/image_2,
#    label_2: a link tree onto DATASET/kitti/training), split by ImageSets/{train,val}.txt.
# Oracles and tolerances:
#  - COCO's bbox (corner convention) and the YOLO line of the same run agree within 1e-6 px;
#    bbox = footprint_bbox + 0.5 exactly (1e-12);
#  - KITTI: P2 R0_rect Tr_velo_to_cam = K [R t] (K the pinhole core of the copied camera model,
#    R t its pose; 1e-9 relative); R0_rect's y row is ENU down in the camera frame; each label's
#    location projected by P2 equals the bottom centre's projection through the pinhole core
#    (mrcal from bottom_center_enu_m, 0.01 px: the location has 4 decimals); the bottom face of
#    KITTI's box, built by KITTI's own rule from (location, l, w, rotation_y), projected by P2 and
#    boxed, is the 2D box (clipped; 0.01 px: 2 decimals) -- the footprint box of the undistorted
#    image; the KITTI image is the dataset image undistorted (OpenCV's initUndistortRectifyMap
#    with the OPENCV8 coefficients: mean absolute difference < 3 grey levels).
#  - a training step of fasterrcnn_mobilenet_v3_large_320_fpn (weights None, 11 classes) on each
#    layout's train split, as its loader gives it, has a finite loss (the val splits are loaded by
#    the same loaders and checked, not trained on: CPU time).
import json
import math
import os
import re
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

SEED = 11
COUNT = 8
W, H = 320, 180


def check(ok, msg):
    if not ok:
        u.fail(msg, SEED)


def coco_yolo_agree(ds, split, coco):
    by_img = {}
    for a in coco["annotations"]:
        by_img.setdefault(a["image_id"], []).append(a)
    worst = 0.0
    n = 0
    for im in coco["images"]:
        stem = os.path.splitext(im["file_name"])[0]
        rows = [list(map(float, l.split())) for l in open(os.path.join(ds, "labels", split, stem + ".txt"))]
        anns = by_img.get(im["id"], [])
        check(len(rows) == len(anns), "%s: %d YOLO rows, %d COCO annotations" % (stem, len(rows), len(anns)))
        for r, a in zip(rows, anns):
            x, y, w, h = a["bbox"]
            cx, cy = r[1] * im["width"], r[2] * im["height"]
            bw, bh = r[3] * im["width"], r[4] * im["height"]
            yolo = [cx - bw / 2, cy - bh / 2, bw, bh]
            worst = max(worst, max(abs(p - q) for p, q in zip(yolo, [x, y, w, h])))
            check(int(r[0]) == a["category_id"] - 1, "%s: YOLO class %d, COCO category %d" % (stem, r[0], a["category_id"]))
            fb = a["footprint_bbox"]
            check(max(abs(x - fb[0] - 0.5), abs(y - fb[1] - 0.5), abs(w - fb[2]), abs(h - fb[3])) <= 1e-12,
                  "bbox %s is not footprint_bbox %s + 0.5" % (a["bbox"], fb))
            seg = np.array(a["segmentation"], float)
            check(seg.shape == (1, 8) and np.abs(seg[0] - [x, y, x + w, y, x + w, y + h, x, y + h]).max() <= 1e-9,
                  "segmentation %s is not the box's polygon" % a["segmentation"])
            n += 1
    check(worst <= 1e-6, "COCO and YOLO boxes differ by %.3g px (> 1e-6)" % worst)
    check(n > 0 or not coco["annotations"], "no boxes compared")
    return worst, n


def coco_api():
    """pycocotools' COCO class, which torchvision's CocoDetection imports. pycocotools is not
    packaged in Debian 12: without it, a stand-in with the part of its API CocoDetection calls
    (COCO(annFile): the index createIndex builds -- imgs by id, anns by id, imgToAnns by
    image_id --, loadImgs, getAnnIds(imgIds), loadAnns), as pycocotools/coco.py defines them."""
    try:
        import pycocotools.coco  # noqa: F401
        return "pycocotools"
    except ImportError:
        pass
    import types

    class COCO:
        def __init__(self, annotation_file):
            with open(annotation_file) as f:
                self.dataset = json.load(f)
            assert type(self.dataset) == dict, "annotation file format not supported"
            self.anns, self.imgs, self.imgToAnns = {}, {}, {}
            for ann in self.dataset.get("annotations", []):
                self.imgToAnns.setdefault(ann["image_id"], []).append(ann)
                self.anns[ann["id"]] = ann
            for img in self.dataset.get("images", []):
                self.imgs[img["id"]] = img
            check(len(self.anns) == len(self.dataset["annotations"]), "COCO: annotation ids repeat")

        def loadImgs(self, ids):
            return [self.imgs[i] for i in (ids if isinstance(ids, list) else [ids])]

        def getAnnIds(self, imgIds=[]):
            imgIds = imgIds if isinstance(imgIds, list) else [imgIds]
            return [a["id"] for i in imgIds for a in self.imgToAnns.get(i, [])]

        def loadAnns(self, ids):
            return [self.anns[i] for i in ids]

    pkg = types.ModuleType("pycocotools")
    mod = types.ModuleType("pycocotools.coco")
    mod.COCO = COCO
    pkg.coco = mod
    sys.modules["pycocotools"], sys.modules["pycocotools.coco"] = pkg, mod
    return "a stand-in for pycocotools' COCO index (not in Debian 12)"


def step(model, images, targets, label):
    import torch
    model.train()
    opt = torch.optim.SGD(model.parameters(), lr=1e-3)
    losses = model(images, targets)
    loss = sum(losses.values())
    check(math.isfinite(float(loss)), "%s: training loss %r" % (label, float(loss)))
    opt.zero_grad()
    loss.backward()
    opt.step()
    print("%s: one training step, loss %.4f" % (label, float(loss)))


def tensor_target(boxes_xyxy, labels):
    import torch
    b = torch.tensor(boxes_xyxy, dtype=torch.float32).reshape(-1, 4)
    return {"boxes": b, "labels": torch.tensor(labels, dtype=torch.int64)}


def kitti_checks(ds, cocos, calib_models):
    import cv2
    import mrcal
    kt = os.path.join(ds, "kitti", "training")
    by_index, anns = {}, {}  # image index -> its COCO record, its annotations
    for coco in cocos:
        ids = {im["id"]: im["index"] for im in coco["images"]}
        for im in coco["images"]:
            by_index[im["index"]] = im
        for a in coco["annotations"]:
            anns.setdefault(ids[a["image_id"]], []).append(a)
    worst_loc = worst_box = 0.0
    nlab = 0
    for k, im in sorted(by_index.items()):
        cal = {}
        for line in open(os.path.join(kt, "calib", "%06d.txt" % k)):
            key, v = line.split(":", 1)
            cal[key] = np.array(v.split(), dtype=float)
        P2 = cal["P2"].reshape(3, 4)
        R0 = cal["R0_rect"].reshape(3, 3)
        Tr = cal["Tr_velo_to_cam"].reshape(3, 4)
        m = calib_models[im["camera"]]
        lens, intr = m.intrinsics()
        K = np.array([[intr[0], 0, intr[2]], [0, intr[1], intr[3]], [0, 0, 1]])
        rt = m.extrinsics_rt_fromref()  # ENU (ref) -> camera
        R = mrcal.R_from_r(rt[:3])
        check(np.allclose(Tr, np.hstack([R, rt[3:, None]]), rtol=0, atol=1e-9), "Tr_velo_to_cam is not the pose")
        full = P2 @ np.vstack([R0 @ Tr, [0, 0, 0, 1]])
        want = K @ np.hstack([R, rt[3:, None]])
        # (the copied model's intrinsics are printed to 1e-6 px: relative 1e-8 of f)
        check(np.abs(full - want).max() <= 1e-8 * np.abs(want).max(), "P2 R0_rect Tr != K [R t]: off %.3g"
              % np.abs(full - want).max())
        check(np.abs(R0 @ R0.T - np.eye(3)).max() < 1e-12, "R0_rect not a rotation")
        check(np.abs(R0[1] - R @ np.array([0, 0, -1.0])).max() < 1e-12, "R0_rect's y axis is not ENU down")
        # the KITTI image: the dataset's image undistorted to the pinhole core
        img = cv2.imread(os.path.join(ds, "train2017" if os.path.exists(os.path.join(ds, "train2017", im["file_name"]))
                                      else "val2017", im["file_name"]))
        kimg = cv2.imread(os.path.join(kt, "image_2", "%06d.png" % k))
        if lens.startswith("LENSMODEL_OPENCV"):
            mx, my = cv2.initUndistortRectifyMap(K, np.array(intr[4:]), None, K, (W, H), cv2.CV_32FC1)
            ref = cv2.remap(img, mx, my, cv2.INTER_LINEAR)
            inner = (slice(10, H - 10), slice(10, W - 10))
            d = np.abs(ref[inner].astype(float) - kimg[inner].astype(float)).mean()
            check(d < 3, "%06d.png: differs from OpenCV's undistortion by %.2f grey levels" % (k, d))
        lines = [l.split() for l in open(os.path.join(kt, "label_2", "%06d.txt" % k))]
        for f in lines:
            h, w, l = map(float, f[8:11])
            loc = np.array(list(map(float, f[11:14])))
            ry = float(f[14])
            box = list(map(float, f[4:8]))
            # the nearest COCO annotation by its bottom centre (the KITTI file has no ids)
            q = P2 @ np.append(loc, 1.0)
            q = q[:2] / q[2]
            best = None
            for a in anns.get(k, []):
                p_cam = R @ np.array(a["bottom_center_enu_m"]) + rt[3:]
                qq = (K @ p_cam)[:2] / p_cam[2]
                dd = np.abs(qq - q).max()
                if best is None or dd < best:
                    best = dd
            check(best is not None and best <= 0.01, "%06d: location projects %.3g px from every bottom centre" % (k, best or -1))
            worst_loc = max(worst_loc, best)
            # KITTI's box rule: bottom face corners x = +-l/2, z = +-w/2 rotated by ry about y
            c, s = math.cos(ry), math.sin(ry)
            pts = []
            for dx, dz in ((l / 2, w / 2), (l / 2, -w / 2), (-l / 2, -w / 2), (-l / 2, w / 2)):
                X = loc + np.array([c * dx + s * dz, 0, -s * dx + c * dz])
                p = P2 @ np.append(X, 1.0)
                pts.append(p[:2] / p[2])
            pts = np.array(pts)
            bb = [max(pts[:, 0].min(), -0.5), max(pts[:, 1].min(), -0.5),
                  min(pts[:, 0].max(), W - 0.5), min(pts[:, 1].max(), H - 0.5)]
            e = max(abs(a - b) for a, b in zip(bb, box))
            check(e <= 0.01, "%06d: KITTI 2D box %s vs its 3D box's projected footprint %s" % (k, box, bb))
            worst_box = max(worst_box, e)
            nlab += 1
    print("KITTI: %d labels; P2 R0_rect Tr = K [R t]; locations project onto bottom centres within %.2g px; "
          "the 3D boxes' footprints are the 2D boxes within %.2g px" % (nlab, worst_loc, worst_box))
    return nlab


def main():
    u.need_povray()
    try:
        import torch
        import torchvision
        from torchvision.models.detection import fasterrcnn_mobilenet_v3_large_320_fpn
    except ImportError as e:
        print("SKIP: torchvision: %s" % e)
        sys.exit(77)
    import mrcal
    torch.manual_seed(SEED)
    with tempfile.TemporaryDirectory() as tmp:
        calib = u.demo_truth_calib_all(tmp, ("cam1", "cam3"))
        ds = os.path.join(tmp, "ds")
        p = u.run(["synth", u.DEMO, "--calib", calib, "--count", str(COUNT), "-o", ds, "--seed", str(SEED),
                   "--camera", "cam1", "--camera", "cam3", "--size", "%dx%d" % (W, H), "--vehicles", "6",
                   "--jobs", "2"])
        print(p.stdout.splitlines()[0])
        tr = json.load(open(os.path.join(ds, "annotations", "instances_train2017.json")))
        va = json.load(open(os.path.join(ds, "annotations", "instances_val2017.json")))
        check(len(va["images"]) >= 1 and len(tr["images"]) >= 1 and len(tr["images"]) + len(va["images"]) == COUNT,
              "splits: %d train, %d val of %d" % (len(tr["images"]), len(va["images"]), COUNT))
        check(not {im["index"] for im in tr["images"]} & {im["index"] for im in va["images"]}, "an image in both splits")
        for coco in (tr, va):
            check(coco["info"].get("bbox_kind") == "footprint" and "ground" in coco["info"].get("bbox_meaning", ""),
                  "COCO info does not state the box type: %s" % coco["info"])
        readme = open(os.path.join(ds, "README.md")).read()
        check("ground footprint" in readme and "val2017" in readme, "README.md: no box type or splits")
        check("ground footprint" in open(os.path.join(ds, "kitti", "README.md")).read() or
              "rectified frame" in open(os.path.join(ds, "kitti", "README.md")).read(), "kitti/README.md")

        # COCO and YOLO of the same run agree in the corner convention
        worst = 0.0
        for split, coco in (("train2017", tr), ("val2017", va)):
            w, n = coco_yolo_agree(ds, split, coco)
            worst = max(worst, w)
        print("COCO bbox vs YOLO line: %d boxes agree within %.2g px (corner convention)" % (
            len(tr["annotations"]) + len(va["annotations"]), worst))

        ncls = len(tr["categories"]) + 1  # background + categories 1..10
        torch.set_num_threads(1)  # (two threads on a loaded 2-core machine: 2.5 x slower)
        # resized to half the images' size inside the model (min_size, max_size), one image a
        # step: about 4 s a step on the 2-core CI machine
        model = fasterrcnn_mobilenet_v3_large_320_fpn(weights=None, weights_backbone=None, num_classes=ncls,
                                                      min_size=H // 2, max_size=W // 2)
        tt = torchvision.transforms.functional

        # 1. COCO, as torchvision's CocoDetection reads it
        print("COCO index: " + coco_api())
        for split in ("val2017", "train2017"):
            cd = torchvision.datasets.CocoDetection(os.path.join(ds, split),
                                                    os.path.join(ds, "annotations", "instances_%s.json" % split))
            check(len(cd) >= 1, "CocoDetection(%s): empty" % split)
            images, targets = [], []
            for i in range(min(len(cd), 1)):
                img, anns = cd[i]
                check(img.size == (W, H), "CocoDetection: image size %s" % (img.size,))
                boxes = [[a["bbox"][0], a["bbox"][1], a["bbox"][0] + a["bbox"][2], a["bbox"][1] + a["bbox"][3]]
                         for a in anns]
                images.append(tt.to_tensor(img))
                targets.append(tensor_target(boxes, [a["category_id"] for a in anns]))
            if split == "train2017":  # (val2017 loaded and checked the same way)
                step(model, images, targets, "COCO %s (torchvision CocoDetection, %d images, %d boxes)"
                     % (split, len(cd), sum(len(t["boxes"]) for t in targets)))

        # 2. Ultralytics: data.yaml relative to its own folder, /images/ -> /labels/
        y = open(os.path.join(ds, "data.yaml")).read()
        fields = dict(re.findall(r"^(\w+):\s*(\S*)\s*$", y, re.M))
        names = dict(re.findall(r"^\s+(\d+):\s*(\S+)\s*$", y, re.M))
        check("path" not in fields and fields["train"] != fields["val"], "data.yaml: %s" % fields)
        check(len(names) == ncls - 1 and names["0"] == "sedan" and names["9"] == "bicycle", "data.yaml names %s" % names)
        check(fields.get("box_type") == "footprint", "data.yaml: box_type %s" % fields.get("box_type"))
        import cv2
        for key in ("val", "train"):
            folder = os.path.join(ds, fields[key])
            files = sorted(os.listdir(folder))
            check(files, "data.yaml %s: %s empty" % (key, folder))
            images, targets = [], []
            for fn in files[:1]:
                ip = os.path.join(folder, fn)
                lp = os.path.splitext(ip.replace(os.sep + "images" + os.sep, os.sep + "labels" + os.sep))[0] + ".txt"
                img = cv2.imread(ip)[:, :, ::-1].copy()
                rows = np.loadtxt(lp, ndmin=2) if os.path.getsize(lp) else np.zeros((0, 5))
                hh, ww = img.shape[:2]
                boxes = [[(r[1] - r[3] / 2) * ww, (r[2] - r[4] / 2) * hh, (r[1] + r[3] / 2) * ww,
                          (r[2] + r[4] / 2) * hh] for r in rows]
                images.append(tt.to_tensor(img))
                targets.append(tensor_target(boxes, [int(r[0]) + 1 for r in rows]))
            if key == "train":
                step(model, images, targets, "Ultralytics %s (%s, %d images)" % (key, fields[key], len(files)))

        # 3. KITTI, as torchvision's Kitti reads it: ROOT/Kitti/raw/training/{image_2,label_2}
        kroot = os.path.join(tmp, "kroot")
        os.makedirs(os.path.join(kroot, "Kitti", "raw"))
        os.symlink(os.path.join(ds, "kitti", "training"), os.path.join(kroot, "Kitti", "raw", "training"))
        kd = torchvision.datasets.Kitti(kroot, train=True, download=False)
        check(len(kd) == COUNT, "torchvision Kitti: %d images" % len(kd))
        sets = {s: open(os.path.join(ds, "kitti", "ImageSets", s + ".txt")).read().split() for s in ("train", "val")}
        check(sorted(sets["train"] + sets["val"]) == ["%06d" % k for k in range(COUNT)] and sets["val"],
              "ImageSets: %s" % sets)
        check(sorted(sets["val"]) == sorted("%06d" % im["index"] for im in va["images"]), "ImageSets/val.txt vs COCO val")
        kinds = {"Car": 1, "Van": 5, "Bus": 6, "Truck": 7, "Misc": 9, "Cyclist": 10}
        names = [os.path.splitext(os.path.basename(p))[0] for p in kd.images]
        for s in ("val", "train"):
            images, targets = [], []
            for idx in sets[s][:1]:
                img, target = kd[names.index(idx)]
                images.append(tt.to_tensor(img))
                targets.append(tensor_target([t["bbox"] for t in target], [kinds[t["type"]] for t in target]))
                for t in target:
                    check(len(t["location"]) == 3 and len(t["dimensions"]) == 3, "Kitti target %s" % t)
            if s == "train":
                step(model, images, targets, "KITTI %s (torchvision Kitti, ImageSets/%s.txt)" % (s, s))

        models = {c: mrcal.cameramodel(os.path.join(ds, "cameras", c + ".cameramodel")) for c in ("cam1", "cam3")}
        kitti_checks(ds, (tr, va), models)
    print("test_dataset_trainers: ok")


if __name__ == "__main__":
    main()

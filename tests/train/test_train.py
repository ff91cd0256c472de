#!/usr/bin/env python3
"""The reference trainer end to end (issue 39, item 6): roadside synth -> train/roadside_train.py
-> roadside detect -> roadside eval.

smoke:     24 images at 320x180, 2 epochs. Asserted: the trainer writes the model and its record
           (and itself checks OpenCV's DNN against PyTorch on the exported graph); `roadside
           detect` finds the model's Ultralytics layout and its boxes equal an independent decode
           here (cv2.dnn forward, the letterbox and box maths of Ultralytics written below,
           cv2.dnn.NMSBoxes) to 1e-3 px, scores to 1e-5, every box, with NMS at IoU 1 on both
           sides (an untrained net's near-tied junk boxes let NMS break ties either way; NMS
           itself is checked in tests/eval/detect).
reference: 600 images at 640x360 (about 500 for training, the rest held out by --val-fraction),
           at most 18 minutes of training on the machine's CPUs; AP@20px of the held-out images
           >= 0.5 (`roadside eval`, the dataset's own COCO ground truth).
"""
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from rs_check import check, finish  # noqa: E402

try:
    import cv2
    import numpy as np
    import torch  # noqa: F401
except ImportError as e:
    print(f"skipped: {e} (Debian's python3-torch and python3-opencv)")
    sys.exit(77)

ROADSIDE = os.environ["ROADSIDE"]
SRC = os.environ["ROADSIDE_SOURCE_ROOT"]
TRAINER = os.path.join(SRC, "train", "roadside_train.py")
SITE = os.path.join(SRC, "sites", "demo")


def run(args, **kw):
    r = subprocess.run(args, capture_output=True, text=True, **kw)
    if r.returncode != 0:
        sys.exit(f"{' '.join(args)}: exit {r.returncode}\n{r.stdout[-2000:]}\n{r.stderr[-2000:]}")
    return r


def dataset(tmp, count, size, seed):
    cal = os.path.join(tmp, "cal")
    run([ROADSIDE, "calib", SITE, "-o", cal])
    ds = os.path.join(tmp, "ds")
    run([ROADSIDE, "synth", SITE, "--calib", cal, "--count", str(count), "--size", size,
         "--val-fraction", "0.17", "--seed", "5", "-o", ds])
    return ds


def detect_split(tmp, ds, split, model, size, extra=()):
    """roadside detect per camera over a split; results keyed to the dataset's image ids."""
    coco = json.load(open(os.path.join(ds, "annotations", f"instances_{split}.json")))
    ids = {im["file_name"]: im["id"] for im in coco["images"]}
    cams = sorted({im["camera"] for im in coco["images"]})
    results = []
    for cam in cams:
        files = [os.path.join(ds, split, im["file_name"]) for im in coco["images"] if im["camera"] == cam]
        out = os.path.join(tmp, f"det_{cam}.json")
        run([ROADSIDE, "detect", SITE, "--calib", os.path.join(ds, "cameras"), "--camera", cam, "--model", model,
             "--family", "ultralytics", "--size", str(size), "-o", out, *extra, *files])
        for d in json.load(open(out)):
            d["image_id"] = ids[d["file_name"]]
            results.append(d)
    return coco, results


def oracle(path, model, size, conf, nms_iou):
    """Ultralytics' inference written from its documentation: centred letterbox (pad 114), RGB,
    /255; output (1, 4 + C, N); best class score > conf; NMS per class at nms_iou (OpenCV's);
    boxes (x - pad) / r clipped to the image."""
    bgr = cv2.imread(path)
    h, w = bgr.shape[:2]
    r = min(size / h, size / w)
    nw, nh = int(round(w * r)), int(round(h * r))
    left, top = int(round((size - nw) / 2 - 0.1)), int(round((size - nh) / 2 - 0.1))
    canvas = np.full((size, size, 3), 114, np.uint8)
    canvas[top:top + nh, left:left + nw] = cv2.resize(bgr, (nw, nh), interpolation=cv2.INTER_LINEAR)
    net = cv2.dnn.readNetFromONNX(model)
    # RGB / 255 by blobFromImage, as roadside detect makes it: the exported peak mask scales score
    # differences by 1e6, so a last-bit difference in the input (x / 255 vs x * (1 / 255)) moves
    # near-tied junk scores
    net.setInput(cv2.dnn.blobFromImage(canvas, scalefactor=1.0 / 255.0, swapRB=True))
    o = net.forward()[0].astype(np.float64)
    score, cls = o[4:].max(0), o[4:].argmax(0)
    keep = score > conf
    out = []
    for c in sorted(set(cls[keep].tolist())):
        sel = np.flatnonzero(keep & (cls == c))
        boxes = []
        for i in sel:
            cx, cy, bw, bh = o[:4, i]
            x0 = np.clip((cx - bw / 2 - left) / r, 0, w)
            y0 = np.clip((cy - bh / 2 - top) / r, 0, h)
            x1 = np.clip((cx + bw / 2 - left) / r, 0, w)
            y1 = np.clip((cy + bh / 2 - top) / r, 0, h)
            boxes.append([x0, y0, x1 - x0, y1 - y0])
        kept = range(len(sel)) if nms_iou >= 1 else cv2.dnn.NMSBoxes(boxes, score[sel].tolist(), conf, nms_iou)
        for j in np.array(kept).reshape(-1):
            out.append((int(c) + 1, float(score[sel[j]]), boxes[j]))
    return out


def smoke(tmp):
    ds = dataset(tmp, 24, "320x180", 5)
    model = os.path.join(tmp, "model.onnx")
    run(["/usr/bin/python3", TRAINER, ds, "-o", model, "--epochs", "2", "--size", "160", "--threads", "2"])
    check(os.path.exists(model) and os.path.exists(model + ".json"), "the model and its record are written")
    rec = json.load(open(model + ".json"))
    check(rec["family"] == "ultralytics" and rec["opencv_max_abs_diff"] < 1e-2,
          f"OpenCV's DNN reads the graph as PyTorch runs it (max |diff| {rec['opencv_max_abs_diff']:.2g})")
    conf = 0.02
    # NMS at IoU 1 suppresses nothing: an untrained net scores junk boxes within 1e-6 of each
    # other, where NMS may break ties either way between two runs of the same maths
    coco, dets = detect_split(tmp, ds, "train2017", model, 160,
                              ["--conf", str(conf), "--max-dets", "100000", "--nms-iou", "1"])
    files = {im["id"]: im["file_name"] for im in coco["images"]}
    # every box roadside writes is one of the oracle's, and every one of the oracle's is found
    nfound, nwant, nextra, ngot = 0, 0, 0, 0
    for im in coco["images"][:6]:
        got = [d for d in dets if d["image_id"] == im["id"]]
        want = oracle(os.path.join(ds, "train2017", files[im["id"]]), model, 160, conf, 1.0)

        def same(d, c, s, b):
            return d["category_id"] == c and abs(d["score"] - s) < 1e-5 and \
                max(abs(u - v) for u, v in zip(d["bbox"], b)) < 1e-3

        nfound += sum(any(same(d, c, s, b) for d in got) for c, s, b in want)
        nextra += sum(not any(same(d, c, s, b) for c, s, b in want) for d in got)
        nwant += len(want)
        ngot += len(got)
    check(nwant > 100, f"the oracle has boxes to compare ({nwant})")
    check(nfound == nwant, f"roadside detect finds the oracle's boxes to 1e-3 px, scores to 1e-5 ({nfound} of {nwant})")
    check(nextra == 0, f"roadside detect's boxes are the oracle's ({nextra} of {ngot} not)")


def reference(tmp):
    ds = dataset(tmp, 600, "640x360", 5)
    model = os.path.join(tmp, "model.onnx")
    r = run(["/usr/bin/python3", TRAINER, ds, "-o", model, "--minutes", "18", "--size", "320"])
    print(r.stdout[-600:])
    rec = json.load(open(model + ".json"))
    check(rec["train_minutes"] <= 20.0, f"trained for at most 20 minutes ({rec['train_minutes']:.1f})")
    check(rec["train_images"] >= 450, f"about 500 training images ({rec['train_images']})")
    _, dets = detect_split(tmp, ds, "val2017", model, 320, ["--conf", "0.05"])
    dpath = os.path.join(tmp, "dets.json")
    json.dump(dets, open(dpath, "w"))
    out = os.path.join(tmp, "ap.json")
    run([ROADSIDE, "eval", os.path.join(ds, "annotations", "instances_val2017.json"), dpath, "--thresholds", "20",
         "--json", out])
    m = json.load(open(out))
    ap = m["AP"]["20"]
    print(json.dumps(m)[:600])
    check(ap is not None and ap >= 0.5, f"AP@20px on the held-out images >= 0.5 ({ap})")


if __name__ == "__main__":
    with tempfile.TemporaryDirectory(dir=os.environ.get("KEEP_TMP")) as tmp:
        {"smoke": smoke, "reference": reference}[sys.argv[1]](tmp)
    finish("train_" + sys.argv[1])

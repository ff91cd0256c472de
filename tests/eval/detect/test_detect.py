#!/usr/bin/env python3
"""`roadside detect`: boxes of hand-built ONNX detectors (make_models.py) against an independent
numpy oracle, to 1e-4 px.

The oracle is written here from the families' documented code (docs/detect.md): YOLOX's preproc
(top-left letterbox of 114, ratio min(H/h, W/w), size int(w r), BGR, no /255), demo_postprocess
(grids of strides 8, 16, 32; xy = (out + grid) s, wh = exp(out) s; score = obj cls) and
class-agnostic multiclass NMS; Ultralytics' LetterBox (centred, round(w r), pad round(d -/+ 0.1),
RGB /255), non_max_suppression (best class, per-class NMS, max_det) and scale_boxes ((x - pad) /
gain, clipped). The models' outputs depend on chosen input pixels ("probes"), so a wrong channel
order, pad value, letterbox placement or normalisation changes the scores. Frames of sizes smaller
and larger than the network's input, non-square both; overlapping boxes for NMS; --conf,
--max-dets; a folder (name order, --fps); a video (MJPG .avi, its own fps, --every); the errors
(missing/garbage model, a layout of neither family, an ambiguous one, an unreadable image, a
video that cannot be opened, a FIFO, a frame of the wrong size): exit 1, no output file.
"""
import json
import math
import os
import stat
import sys
import tempfile

import cv2
import mrcal
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "common"))
sys.path.insert(0, os.path.dirname(__file__))
from rs_check import check, finish, run  # noqa: E402
import make_models as mm  # noqa: E402

TOL_PX = 1e-4
NET_W, NET_H = 128, 96  # a non-square network input
C = 3
COLOUR_BGR = (20, 60, 230)  # every test frame: B 20, G 60, R 230


# ---- the oracle ----

def letterbox(family, w, h):
    """(ratio, resized (w, h), pad (x, y)) as each family computes them."""
    r = min(NET_H / h, NET_W / w)
    if family == "yolox":
        return r, (int(w * r), int(h * r)), (0, 0)
    nw, nh = int(round(w * r)), int(round(h * r))
    dw, dh = (NET_W - nw) / 2, (NET_H - nh) / 2
    return r, (nw, nh), (int(round(dw - 0.1)), int(round(dh - 0.1)))


def blob_of(family, img):
    """The network's input (3, H, W) float32 as each family's preprocessing makes it."""
    h, w = img.shape[:2]
    r, (nw, nh), (px, py) = letterbox(family, w, h)
    if family == "yolox":
        canvas = np.full((NET_H, NET_W, 3), 114, np.uint8)
        canvas[:nh, :nw] = cv2.resize(img, (nw, nh), interpolation=cv2.INTER_LINEAR)
        return canvas.transpose(2, 0, 1).astype(np.float32)
    resized = img if (w, h) == (nw, nh) else cv2.resize(img, (nw, nh), interpolation=cv2.INTER_LINEAR)
    canvas = cv2.copyMakeBorder(resized, py, NET_H - nh - py, px, NET_W - nw - px, cv2.BORDER_CONSTANT,
                                value=(114, 114, 114))
    return (canvas[..., ::-1].transpose(2, 0, 1).astype(np.float32) / np.float32(255.0)).astype(np.float32)


def output_of(base, probes, blob):
    out = base.copy().reshape(-1)
    for c, y, x, i, scale in probes:
        out[i] = np.float32(out[i] + np.float32(scale) * blob[c, y, x])
    return out.reshape(base.shape)


def iou(a, b):
    iw = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
    ih = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
    inter = iw * ih
    return inter / ((a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter)


def greedy_nms(boxes, scores, thr):
    order = sorted(range(len(scores)), key=lambda i: -scores[i])
    keep = []
    for i in order:
        if all(iou(boxes[i], boxes[k]) <= thr for k in keep):
            keep.append(i)
    return keep


def expected(family, out, w, h, conf, nms_thr, max_det):
    """[(bbox xywh, score, category_id)] best first."""
    r, _, (px, py) = letterbox(family, w, h)
    out = out.astype(np.float64)
    cand = []
    if family == "yolox":
        pred = out[0].copy()
        grids, strides = [], []
        for gx, gy, s in mm.anchors(NET_W, NET_H):
            grids.append((gx, gy))
            strides.append(s)
        grids, strides = np.array(grids, float), np.array(strides, float)[:, None]
        pred[:, :2] = (pred[:, :2] + grids) * strides
        pred[:, 2:4] = np.exp(pred[:, 2:4]) * strides
        scores = pred[:, 4:5] * pred[:, 5:]
        for a in range(pred.shape[0]):
            c = int(np.argmax(scores[a]))
            if scores[a, c] > conf:
                cx, cy, bw, bh = pred[a, :4]
                cand.append(([(cx - bw / 2) / r, (cy - bh / 2) / r, (cx + bw / 2) / r, (cy + bh / 2) / r],
                             scores[a, c], c))
        keep = greedy_nms([b for b, _, _ in cand], [s for _, s, _ in cand], nms_thr)  # class-agnostic
    else:
        pred = out[0].T  # (N, 4 + C)
        for a in range(pred.shape[0]):
            c = int(np.argmax(pred[a, 4:]))
            if pred[a, 4 + c] > conf:
                cx, cy, bw, bh = pred[a, :4]
                xyxy = [cx - bw / 2 - px, cy - bh / 2 - py, cx + bw / 2 - px, cy + bh / 2 - py]
                xyxy = [min(max(v / r, 0.0), lim) for v, lim in zip(xyxy, (w, h, w, h))]
                cand.append((xyxy, pred[a, 4 + c], c))
        keep = []
        for c in range(C):  # per class
            idx = [i for i, k in enumerate(cand) if k[2] == c]
            keep += [idx[j] for j in greedy_nms([cand[i][0] for i in idx], [cand[i][1] for i in idx], nms_thr)]
        keep.sort(key=lambda i: -cand[i][1])
    if max_det:
        keep = keep[:max_det]
    return [([b[0], b[1], b[2] - b[0], b[3] - b[1]], s, c + 1) for b, s, c in (cand[i] for i in keep)]


def compare(label, got, want, tol_score=1e-6):
    check(len(got) == len(want), f"{label}: {len(got)} detections, expected {len(want)}:\n got {got}\n want {want}")
    if len(got) != len(want):
        return
    got = sorted(got, key=lambda d: -d["score"])
    for k, (d, (bbox, score, cat)) in enumerate(zip(got, want)):
        err = max(abs(a - b) for a, b in zip(d["bbox"], bbox))
        check(err <= TOL_PX and not math.isnan(err), f"{label} #{k}: bbox {d['bbox']} vs {bbox} (off {err:.3g} px)")
        check(abs(d["score"] - score) <= tol_score, f"{label} #{k}: score {d['score']} vs {score}")
        check(d["category_id"] == cat, f"{label} #{k}: category {d['category_id']} vs {cat}")


# ---- the models of the cases ----

def yolox_case():
    """Rows of a YOLOX output: two boxes overlapping (IoU ~0.7, different classes: class-agnostic NMS
    drops the weaker), one apart whose objectness is the canvas's pixel (0, 0), channel 2, / 255
    (the frame's R, 230, when the letterbox is top-left and BGR; B = 20 in RGB order, 114 in a
    centred letterbox's pad), one in stride 32."""
    rows = {
        10: [0.3, 0.6, math.log(2.5), math.log(1.8), 0.95, 0.9, 0.1, 0.2],
        11: [0.1, 0.6, math.log(2.5), math.log(1.8), 0.9, 0.1, 0.85, 0.1],
        40: [0.5, 0.5, math.log(1.2), math.log(1.3), 0.0, 0.05, 0.1, 1.0],
        251: [0.2, 0.7, math.log(1.5), math.log(0.8), 0.7, 0.2, 0.3, 0.6],
    }
    base = mm.yolox_base(NET_W, NET_H, C, rows)
    probes = [(2, 0, 0, 40 * (5 + C) + 4, 1.0 / 255.0)]
    return base, probes


def ultralytics_case():
    """Columns of an Ultralytics output: two overlapping boxes of one class (NMS keeps one), a third
    overlapping them in another class (kept: per-class NMS), one whose class-1 score is the
    canvas's pixel (H/2, W/2), channel 0 (R once RGB, /255), one whose class-0 score is the
    canvas's pixel (0, 0), channel 1 (G / 255 when the frame reaches the corner, 114/255 in a
    centred letterbox's pad)."""
    rows = {
        20: [70.0, 40.0, 30.0, 20.0, 0.9, 0.1, 0.05],
        21: [72.0, 41.0, 30.0, 20.0, 0.8, 0.1, 0.05],
        22: [71.0, 40.0, 30.0, 20.0, 0.1, 0.05, 0.7],
        100: [30.0, 60.0, 14.0, 30.0, 0.02, 0.0, 0.03],
        200: [100.0, 20.0, 12.0, 10.0, 0.0, 0.01, 0.02],
    }
    base = mm.ultralytics_base(NET_W, NET_H, C, rows)
    N = base.shape[2]
    probes = [(0, NET_H // 2, NET_W // 2, (4 + 1) * N + 100, 1.0), (1, 0, 0, 4 * N + 200, 1.0)]
    return base, probes


FAMILY_DEFAULTS = {"yolox": (0.1, 0.45, 0), "ultralytics": (0.25, 0.7, 300)}


class Fixture:
    def __init__(self, tmp):
        self.tmp = tmp
        self.site = os.path.join(tmp, "site")
        p = run("site", "simulate", self.site, "--seed", "3", "--cameras", "1")
        if p.returncode != 0:
            print(p.stderr)
            sys.exit(1)
        self.calib = os.path.join(tmp, "calib")
        os.makedirs(self.calib)
        self.models = {}
        for family, make in (("yolox", yolox_case), ("ultralytics", ultralytics_case)):
            base, probes = make()
            path = os.path.join(tmp, f"{family}.onnx")
            mm.make_model(path, NET_W, NET_H, base, probes)
            self.models[family] = (path, base, probes)

    def camera(self, w, h):
        m = mrcal.cameramodel(intrinsics=("LENSMODEL_PINHOLE", np.array([500.0, 500.0, (w - 1) / 2, (h - 1) / 2])),
                              imagersize=(w, h), extrinsics_rt_fromref=np.zeros(6))
        m.write(os.path.join(self.calib, "cam1.cameramodel"))

    def image(self, name, w, h, colour=COLOUR_BGR):
        img = np.empty((h, w, 3), np.uint8)
        img[:] = colour
        path = os.path.join(self.tmp, name)
        cv2.imwrite(path, img)
        return path, img

    def detect(self, model, out, inputs, *extra):
        if os.path.exists(out):
            os.remove(out)
        return run("detect", self.site, "--calib", self.calib, "--camera", "cam1", "--model", model,
                   "--size", f"{NET_W}x{NET_H}", "-o", out, *extra, *inputs, timeout=60)


def check_family(fx, family, sizes):
    model, base, probes = fx.models[family]
    conf, nms_thr, max_det = FAMILY_DEFAULTS[family]
    out = os.path.join(fx.tmp, "dets.json")
    for n, (w, h) in enumerate(sizes):
        fx.camera(w, h)
        path, img = fx.image(f"{family}_{w}x{h}.png", w, h)
        raw = output_of(base, probes, blob_of(family, img))
        variants = [([], conf, max_det)]
        if n == 0:  # the options, on the first size
            variants += [(["--conf", "0.5"], 0.5, max_det), (["--max-dets", "1"], conf, 1), (["--family", family], conf,
                                                                                             max_det)]
        for extra, c, m in variants:
            p = fx.detect(model, out, [path], *extra)
            label = f"{family} {w}x{h} {' '.join(extra)}"
            check(p.returncode == 0, f"{label}: exit {p.returncode}: {p.stderr}")
            if p.returncode:
                continue
            got = json.load(open(out))
            want = expected(family, raw, w, h, c, nms_thr, m)
            compare(label, got, want)
            check(all(d["image_id"] == 1 and d["frame"] == 0 and d["camera"] == "cam1" and
                      d["file_name"] == os.path.basename(path) and "time_s" not in d for d in got),
                  f"{label}: image_id, frame, camera, file_name, no time_s: {got[:1]}")
            if not extra:
                print(f"{label}: {len(got)} detections match the oracle (letterbox r = "
                      f"{letterbox(family, w, h)[0]:.4f}, pad {letterbox(family, w, h)[2]})")


def check_folder_and_video(fx):
    model, base, probes = fx.models["yolox"]
    w, h = 200, 120
    fx.camera(w, h)
    folder = os.path.join(fx.tmp, "frames")
    os.makedirs(folder)
    for name in ("b.png", "a.png", "c.jpg"):
        fx.image(os.path.join("frames", name), w, h)
    open(os.path.join(folder, "notes.txt"), "w").write("not an image\n")
    out = os.path.join(fx.tmp, "folder.json")
    p = fx.detect(model, out, [folder], "--fps", "2")
    check(p.returncode == 0, f"folder: exit {p.returncode}: {p.stderr}")
    if p.returncode == 0:
        got = json.load(open(out))
        frames = sorted({(d["image_id"], d["frame"], d["time_s"], d["file_name"]) for d in got})
        check(frames == [(1, 0, 0.0, "a.png"), (2, 1, 0.5, "b.png"), (3, 2, 1.0, "c.jpg")],
              f"folder: frames in name order with time_s = frame / fps: {frames}")
        print(f"folder: {len(got)} detections over {len(frames)} images in name order, time_s = frame / 2")
    # the same images given one by one (a shell glob): one sequence in the order given
    out = os.path.join(fx.tmp, "files.json")
    names = ["c.jpg", "a.png", "b.png"]
    p = fx.detect(model, out, [os.path.join(folder, n) for n in names], "--fps", "2")
    check(p.returncode == 0, f"image files: exit {p.returncode}: {p.stderr}")
    if p.returncode == 0:
        got = json.load(open(out))
        frames = sorted({(d["frame"], d["time_s"], d["file_name"]) for d in got})
        check(frames == [(0, 0.0, "c.jpg"), (1, 0.5, "a.png"), (2, 1.0, "b.png")],
              f"image files: one sequence in the order given, time_s = frame / fps: {frames}")

    # a video: MJPG in .avi at 10 fps, 5 frames
    video = os.path.join(fx.tmp, "clip.avi")
    vw = cv2.VideoWriter(video, cv2.VideoWriter_fourcc(*"MJPG"), 10.0, (w, h))
    for k in range(5):
        img = np.empty((h, w, 3), np.uint8)
        img[:] = COLOUR_BGR
        vw.write(img)
    vw.release()
    out = os.path.join(fx.tmp, "video.json")
    p = fx.detect(model, out, [video], "--every", "2")
    check(p.returncode == 0, f"video: exit {p.returncode}: {p.stderr}")
    if p.returncode == 0:
        got = json.load(open(out))
        frames = sorted({(d["image_id"], d["frame"]) for d in got})
        check(frames == [(1, 0), (2, 2), (3, 4)], f"video --every 2: frames {frames}")
        for d in got:
            check(abs(d["time_s"] - d["frame"] / 10.0) < 1e-9, f"video: time_s {d['time_s']} of frame {d['frame']}")
            check(d["file_name"] == "clip.avi", f"video: file_name {d['file_name']}")
        # the oracle's frames: the video decoded by OpenCV's Python (the probe reads a JPEG'd pixel)
        cap = cv2.VideoCapture(video)
        for k in range(5):
            ok, frame = cap.read()
            check(ok, f"video: cv2 decodes frame {k}")
            if ok and k % 2 == 0:
                want = expected("yolox", output_of(base, probes, blob_of("yolox", frame)), w, h, 0.1, 0.45, 0)
                compare(f"video frame {k}", [d for d in got if d["frame"] == k], want)
        # the same video as a file:// URL
        p = fx.detect(model, out, ["file://" + video], "--every", "2")
        check(p.returncode == 0 and json.load(open(out)) == got, f"video as file:// URL: exit {p.returncode}: {p.stderr}")
        print(f"video: frames {[f for _, f in frames]}, time_s = frame / 10, boxes match")


def check_errors(fx):
    w, h = 200, 120
    fx.camera(w, h)
    good, _ = fx.image("good.png", w, h)
    out = os.path.join(fx.tmp, "err.json")
    yolox = fx.models["yolox"][0]

    def fails(label, model, inputs, want, *extra, code=1):
        p = fx.detect(model, out, inputs, *extra)
        check(p.returncode == code, f"{label}: exit {p.returncode}, expected {code}: {p.stderr}")
        check(want in p.stderr, f"{label}: the message says {want!r}: {p.stderr!r}")
        check(not os.path.exists(out), f"{label}: no output file")
        check("ERROR" not in p.stderr.replace("roadside", ""), f"{label}: OpenCV's own log lines: {p.stderr!r}")

    fails("missing model", os.path.join(fx.tmp, "none.onnx"), [good], "none.onnx")
    garbage = os.path.join(fx.tmp, "garbage.onnx")
    open(garbage, "wb").write(bytes(range(256)) * 40)
    fails("garbage model", garbage, [good], "garbage.onnx")
    neither = os.path.join(fx.tmp, "neither.onnx")
    mm.make_model(neither, NET_W, NET_H, np.zeros((1, 7, 7), np.float32))
    fails("neither layout", neither, [good], "neither")
    N = len(mm.anchors(NET_W, NET_H))
    both = os.path.join(fx.tmp, "both.onnx")
    mm.make_model(both, NET_W, NET_H, np.zeros((1, N, N), np.float32))
    fails("ambiguous layout", both, [good], "--family")
    p = fx.detect(both, out, [good], "--family", "yolox")
    check(p.returncode == 0, f"ambiguous layout with --family yolox: exit {p.returncode}: {p.stderr}")
    if os.path.exists(out):
        os.remove(out)
    bad_png = os.path.join(fx.tmp, "bad.png")
    open(bad_png, "wb").write(b"\x89PNG\r\n\x1a\n" + b"\0" * 100)
    fails("unreadable image", yolox, [good, bad_png], "bad.png")
    bad_avi = os.path.join(fx.tmp, "bad.avi")
    open(bad_avi, "wb").write(b"RIFF not a video at all" * 10)
    fails("unopenable video", yolox, [bad_avi], "bad.avi")
    fifo = os.path.join(fx.tmp, "pipe.avi")
    os.mkfifo(fifo)
    check(stat.S_ISFIFO(os.stat(fifo).st_mode), "the FIFO exists")
    fails("FIFO input", yolox, [fifo], "pipe.avi")
    fails("device input", yolox, ["/dev/zero"], "/dev/zero")
    small, _ = fx.image("small.png", 100, 60)
    fails("frame size", yolox, [good, small], "small.png")
    p = run("detect", fx.site, "--calib", fx.calib, "--camera", "cam9", "--model", yolox, "-o", out, good)
    check(p.returncode == 2 and not os.path.exists(out), f"unknown camera: exit {p.returncode}: {p.stderr}")
    p = fx.detect(yolox, out, [good], "--size", "100")
    check(p.returncode == 2, f"--size 100 (not a multiple of 32): exit {p.returncode}")
    print("errors: missing, garbage, neither and ambiguous models, unreadable image, video, FIFO, device, "
          "frame size, unknown camera: exit 1/2, no output")


def main():
    with tempfile.TemporaryDirectory(prefix="roadside-detect-") as tmp:
        fx = Fixture(tmp)
        # larger than the input (both ways), smaller, the input's own size, a tall one
        # and 101 x 192: w r = 50.5 exactly, where Ultralytics' round (half to even) gives 50
        sizes = [(200, 120), (300, 400), (60, 90), (128, 96), (64, 200), (101, 192)]
        check_family(fx, "yolox", sizes)
        check_family(fx, "ultralytics", sizes)
        check_folder_and_video(fx)
        check_errors(fx)
    finish("test_detect")


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""roadside's reference trainer: a small ground-point detector trained on a roadside dataset.

    /usr/bin/python3 train/roadside_train.py DATASET -o MODEL.onnx [--minutes M] [--size S]

It shows the paper's loop on one machine (synth -> train -> detect -> localise -> track -> eval)
with Debian's PyTorch on the CPU and no downloaded weights. It is a smoke test of that path, not
a model to ship: for real use train YOLOX or Ultralytics YOLO on the same dataset (docs/train.md).

What it learns: the dataset's COCO `bbox` (by default roadside's footprint box: the vehicle's
ground rectangle, whose centre is the point `roadside localise --point center` maps to the road).
The network is CenterNet-like (X. Zhou et al., "Objects as Points", arXiv:1904.07850): a small
convolutional backbone with a feature pyramid to stride 4, a heatmap per class (focal loss on
Gaussian peaks), a sub-cell offset and a log box size at each centre.

What it writes: an ONNX graph in Ultralytics YOLOv8's output layout, so that `roadside detect
--family ultralytics` runs it exactly as it runs a YOLOv8 export:
  input  "images"  (1, 3, S, S) float, RGB / 255, the frame letterboxed into the centre (pad 114)
  output "output0" (1, 4 + C, N), N = (S/4)^2: per cell cx, cy, w, h in input pixels, then the
         class scores (sigmoid heatmap, zero where the cell is not a 3x3 local maximum, so that
         a vehicle gives one box; NMS does the rest).
Boxes are in the labels' own pixel convention (roadside: pixel (0,0) = centre of the top-left
pixel), mapped by the letterbox's gain and padding only, which is what `detect` inverts.
"""
import argparse
import json
import math
import os
import sys
import time

import cv2
import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F

STRIDE = 4


def letterbox_geometry(w, h, size):
    """Ultralytics' LetterBox (centred, auto=False, scaleup=True): gain, resized size, padding."""
    r = min(size / h, size / w)
    new_w, new_h = int(round(w * r)), int(round(h * r))
    dw, dh = (size - new_w) / 2.0, (size - new_h) / 2.0
    top, left = int(round(dh - 0.1)), int(round(dw - 0.1))
    return r, new_w, new_h, left, top


def letterbox(img_bgr, size):
    h, w = img_bgr.shape[:2]
    r, new_w, new_h, left, top = letterbox_geometry(w, h, size)
    if (new_w, new_h) != (w, h):
        img_bgr = cv2.resize(img_bgr, (new_w, new_h), interpolation=cv2.INTER_LINEAR)
    out = np.full((size, size, 3), 114, np.uint8)
    out[top:top + new_h, left:left + new_w] = img_bgr
    return out[:, :, ::-1].copy(), r, left, top  # RGB


def load_split(dataset, split, size):
    """Images (N, 3, S, S) uint8 and per image an array of (class, cx, cy, w, h) in net pixels."""
    path = os.path.join(dataset, "annotations", f"instances_{split}.json")
    with open(path) as f:
        coco = json.load(f)
    cats = sorted(c["id"] for c in coco["categories"])
    by_image = {}
    for a in coco["annotations"]:
        if a.get("iscrowd", 0) or not a.get("bbox"):
            continue
        by_image.setdefault(a["image_id"], []).append(a)
    images, targets, files = [], [], []
    for im in coco["images"]:
        p = os.path.join(dataset, split, im["file_name"])
        bgr = cv2.imread(p, cv2.IMREAD_COLOR)
        if bgr is None:
            sys.exit(f"{p}: cannot read the image of COCO image id {im['id']}")
        rgb, r, left, top = letterbox(bgr, size)
        t = []
        for a in by_image.get(im["id"], []):
            x, y, w, h = a["bbox"]
            t.append((cats.index(a["category_id"]), (x + w / 2) * r + left, (y + h / 2) * r + top, w * r, h * r))
        images.append(rgb.transpose(2, 0, 1))
        targets.append(np.array(t, np.float32).reshape(-1, 5))
        files.append(im["file_name"])
    return np.stack(images) if images else np.zeros((0, 3, size, size), np.uint8), targets, cats, coco


def conv(cin, cout, stride=1):
    return nn.Sequential(nn.Conv2d(cin, cout, 3, stride, 1, bias=False), nn.BatchNorm2d(cout), nn.ReLU(inplace=True))


class Net(nn.Module):
    """Backbone to stride 16, a feature pyramid back to stride 4, three heads."""

    def __init__(self, nclasses):
        super().__init__()
        self.s2 = nn.Sequential(conv(3, 16, 2), conv(16, 16))
        self.s4 = nn.Sequential(conv(16, 32, 2), conv(32, 32))
        self.s8 = nn.Sequential(conv(32, 64, 2), conv(64, 64))
        self.s16 = nn.Sequential(conv(64, 96, 2), conv(96, 96), conv(96, 96))
        self.lat8 = nn.Conv2d(64, 96, 1)
        self.lat4 = nn.Conv2d(32, 96, 1)
        self.fuse = conv(96, 64)
        self.heat = nn.Conv2d(64, nclasses, 1)
        self.offset = nn.Conv2d(64, 2, 1)
        self.size = nn.Conv2d(64, 2, 1)
        nn.init.constant_(self.heat.bias, -2.19)  # prior 0.1, CenterNet's

    def forward(self, x):
        c4 = self.s4(self.s2(x))
        c8 = self.s8(c4)
        c16 = self.s16(c8)
        p8 = self.lat8(c8) + F.interpolate(c16, scale_factor=2.0, mode="nearest")
        p4 = self.lat4(c4) + F.interpolate(p8, scale_factor=2.0, mode="nearest")
        f = self.fuse(p4)
        return self.heat(f), self.offset(f), self.size(f)


def gaussian_radius(w, h):
    """A Gaussian a third of the smaller box side, in cells (at least 1)."""
    return max(1.0, min(w, h) / STRIDE / 3.0)


def make_targets(tg, nclasses, g):
    """Heatmap (C, g, g), and for each object its cell index, offset and log size."""
    heat = np.zeros((nclasses, g, g), np.float32)
    ys, xs = np.mgrid[0:g, 0:g]
    idx, off, size = [], [], []
    for c, cx, cy, w, h in tg:
        gx, gy = cx / STRIDE, cy / STRIDE
        ix, iy = int(gx), int(gy)
        if not (0 <= ix < g and 0 <= iy < g) or w <= 0 or h <= 0:
            continue
        s = gaussian_radius(w, h)
        heat[int(c)] = np.maximum(heat[int(c)], np.exp(-((xs - ix) ** 2 + (ys - iy) ** 2) / (2 * s * s)))
        idx.append(iy * g + ix)
        off.append((gx - ix, gy - iy))
        size.append((math.log(w / STRIDE), math.log(h / STRIDE)))
    return heat, idx, off, size


def focal_loss(logits, gt):
    """CenterNet's penalty-reduced focal loss (alpha 2, beta 4), normalised by the peaks."""
    p = torch.sigmoid(logits).clamp(1e-4, 1 - 1e-4)
    pos = gt.eq(1).float()
    neg = 1 - pos
    pos_loss = torch.log(p) * (1 - p) ** 2 * pos
    neg_loss = torch.log(1 - p) * p ** 2 * (1 - gt) ** 4 * neg
    n = pos.sum().clamp(min=1)
    return -(pos_loss.sum() + neg_loss.sum()) / n


class Export(nn.Module):
    """The trained net with its decoding, in Ultralytics YOLOv8's output layout (1, 4 + C, N)."""

    def __init__(self, net, size):
        super().__init__()
        self.net = net
        g = size // STRIDE
        ys, xs = torch.meshgrid(torch.arange(g, dtype=torch.float32), torch.arange(g, dtype=torch.float32), indexing="ij")
        self.register_buffer("gx", xs.reshape(1, 1, -1))
        self.register_buffer("gy", ys.reshape(1, 1, -1))
        self.n = g * g

    def forward(self, x):
        heat, off, size = self.net(x)
        h = torch.sigmoid(heat)
        # 1 at a 3x3 local maximum, 0 below it (Relu and Sub only: every ONNX reader has them)
        peak = F.relu(1.0 - F.relu(F.max_pool2d(h, 3, 1, 1) - h) * 1e6)
        scores = (h * peak).reshape(1, -1, self.n)
        off = off.reshape(1, 2, self.n)
        wh = torch.exp(size.reshape(1, 2, self.n)) * STRIDE
        cx = (self.gx + off[:, 0:1]) * STRIDE
        cy = (self.gy + off[:, 1:2]) * STRIDE
        return torch.cat([cx, cy, wh, scores], dim=1)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dataset", help="a roadside dataset (roadside synth -o DATASET)")
    ap.add_argument("-o", "--output", required=True, help="the ONNX model to write")
    ap.add_argument("--split", default="train2017", help="the training split (default train2017)")
    ap.add_argument("--size", type=int, default=320, help="network input, a multiple of 16 (default 320)")
    ap.add_argument("--minutes", type=float, default=15.0, help="training time budget (default 15)")
    ap.add_argument("--epochs", type=int, default=0, help="stop after N epochs (default: the time budget)")
    ap.add_argument("--batch", type=int, default=16, help="batch size (default 16)")
    ap.add_argument("--threads", type=int, default=0, help="torch threads (default: the CPUs usable)")
    ap.add_argument("--seed", type=int, default=0, help="seed (default 0)")
    a = ap.parse_args()
    if a.size % 16 or a.size < 64:
        ap.error("--size must be a multiple of 16, at least 64")
    torch.manual_seed(a.seed)
    rng = np.random.default_rng(a.seed)
    torch.set_num_threads(a.threads or len(os.sched_getaffinity(0)))

    t0 = time.monotonic()
    images, targets, cats, _ = load_split(a.dataset, a.split, a.size)
    if len(images) == 0:
        sys.exit(f"{a.dataset}: split {a.split} has no images")
    nobj = sum(len(t) for t in targets)
    print(f"{len(images)} images, {nobj} objects, {len(cats)} classes, input {a.size}x{a.size}; "
          f"loaded in {time.monotonic() - t0:.0f} s", flush=True)
    g = a.size // STRIDE

    net = Net(len(cats))
    opt = torch.optim.AdamW(net.parameters(), lr=2e-3, weight_decay=1e-4)
    budget_s = a.minutes * 60.0
    t_train = time.monotonic()
    epoch = 0
    while True:
        frac = (time.monotonic() - t_train) / budget_s
        if frac >= 1.0 or (a.epochs and epoch >= a.epochs):
            break
        net.train()
        order = rng.permutation(len(images))
        total, nb = 0.0, 0
        for b in range(0, len(order), a.batch):
            frac = (time.monotonic() - t_train) / budget_s
            if frac >= 1.0 and not a.epochs:
                break
            for pg in opt.param_groups:  # cosine decay over the budget
                pg["lr"] = 2e-3 * 0.5 * (1 + math.cos(math.pi * min(frac, 1.0)))
            sel = order[b:b + a.batch]
            x = torch.from_numpy(images[sel]).float() / 255.0
            flip = rng.random(len(sel)) < 0.5
            x[flip] = x[flip].flip(-1)
            # targets of the (mirrored) objects: pixel column j of S goes to S - 1 - j
            prep = []
            for k, i in enumerate(sel):
                t = targets[i].copy()
                if flip[k]:
                    t[:, 1] = a.size - 1 - t[:, 1]
                prep.append(make_targets(t, len(cats), g))
            hl, ol, sl = net(x)
            loss = focal_loss(hl, torch.from_numpy(np.stack([p[0] for p in prep])))
            # offset and size at each object's centre cell
            bi, ci, to, ts = [], [], [], []
            for k, (_, idx, off, size) in enumerate(prep):
                for j, o, s in zip(idx, off, size):
                    bi.append(k), ci.append(j), to.append(o), ts.append(s)
            if bi:
                bi, ci = torch.tensor(bi), torch.tensor(ci)
                po = ol.flatten(2)[bi, :, ci]
                ps = sl.flatten(2)[bi, :, ci]
                loss = loss + F.l1_loss(po, torch.tensor(to)) + 0.5 * F.l1_loss(ps, torch.tensor(ts))
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += float(loss)
            nb += 1
        epoch += 1
        print(f"epoch {epoch}: loss {total / max(nb, 1):.3f}, {time.monotonic() - t_train:.0f} s", flush=True)

    net.eval()
    model = Export(net, a.size).eval()
    x = torch.zeros(1, 3, a.size, a.size)
    tmp = a.output + ".tmp"
    torch.onnx.export(model, x, tmp, input_names=["images"], output_names=["output0"], opset_version=12)
    # the graph as OpenCV reads it gives the same numbers as PyTorch (what `roadside detect` runs)
    probe = torch.from_numpy(images[:1]).float() / 255.0
    with torch.no_grad():
        ref = model(probe).numpy()
    cvnet = cv2.dnn.readNetFromONNX(tmp)
    cvnet.setInput(probe.numpy())
    got = cvnet.forward()
    err = float(np.max(np.abs(got.reshape(ref.shape) - ref)))
    if not err < 1e-2:
        os.unlink(tmp)
        sys.exit(f"{a.output}: OpenCV's DNN reads the exported graph differently from PyTorch (max {err:.3g})")
    os.replace(tmp, a.output)
    with open(a.output + ".json", "w") as f:
        json.dump({"family": "ultralytics", "input_size": a.size, "categories": cats, "epochs": epoch,
                   "train_images": len(images), "train_minutes": (time.monotonic() - t_train) / 60.0,
                   "opencv_max_abs_diff": err}, f, indent=1)
    print(f"wrote {a.output} ({epoch} epochs, {(time.monotonic() - t_train) / 60:.1f} min; "
          f"OpenCV vs PyTorch max |diff| {err:.2g})")


if __name__ == "__main__":
    main()

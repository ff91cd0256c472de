#!/usr/bin/python3
# Issue 17: the validation split of `roadside synth` (--val-fraction, --val-backgrounds,
# --val-camera). Tiny runs (160x90, 4 vehicles, real POV-Ray) over a copy of the demo site with
# two registered backgrounds per camera (bgA, bgB; `roadside background`), then:
#  - every image index 0..N-1 is in exactly one split (the COCO files, the split folders,
#    images/<split>, labels/<split>, KITTI's ImageSets), never in both, none missing;
#  - --val-backgrounds name=bgB: every image over bgB is in val and none over bgA is (the
#    image's `background` field, and the background file it was drawn over);
#  - --val-camera cam3: every cam3 image in val, every cam1 image in train;
#  - the layouts per split agree with each other: COCO ids unique and referenced, the label
#    counts per image equal in COCO, YOLO (labels/<split>/<stem>.txt) and KITTI
#    (label_2/<index>.txt), data.yaml's train/val name the split folders, the images under
#    <split>/ and images/<split>/ are the same files;
#  - --val-fraction 0.5 made as two shards (--shard 0/2, 1/2): each shard puts every image in
#    the split a one-shard run of the same options does, and `synth merge` keeps it.
# The oracle of "which split" is the image's own recorded background/camera (independent of the
# rule that chose it) and, for the fraction, the one-shard run.
import json
import os
import re
import shutil
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

SEED = 5
W, H = 160, 90
TRAIN, VAL = "train2017", "val2017"


def make_site(tmp):
    """A copy of the demo site with backgrounds bgA (greenish) and bgB (grey) on cam1 and cam3."""
    import cv2
    site = os.path.join(tmp, "site")
    shutil.copytree(u.DEMO, site)
    rng = np.random.default_rng(SEED)
    for name, rgb in (("bgA", (100, 120, 90)), ("bgB", (150, 140, 140))):
        img = np.empty((H, W, 3), np.uint8)
        img[:] = rgb[::-1]
        img += rng.integers(0, 8, img.shape, dtype=np.uint8)
        path = os.path.join(tmp, name + ".png")
        cv2.imwrite(path, img)
        for cam in ("cam1", "cam3"):
            u.run(["background", site, "--camera", cam, path, "--name", name,
                   "--tag", "conditions=cloudy"])
    return site


def synth(site, calib, out, count, extra):
    return u.run(["synth", site, "--calib", calib, "--count", str(count), "--val-fraction", "0", "-o", out,
                  "--seed", str(SEED), "--camera", "cam1", "--camera", "cam3",
                  "--size", "%dx%d" % (W, H), "--vehicles", "4", "--jobs", "2"] + extra)


def read_split(ds, split):
    p = os.path.join(ds, "annotations", "instances_%s.json" % split)
    return json.load(open(p)) if os.path.exists(p) else {"images": [], "annotations": []}


def check_layout(ds, count):
    """Checks one dataset's splits against each other; returns {index: (split, image record)}."""
    where = {}
    for split in (TRAIN, VAL):
        coco = read_split(ds, split)
        ids = [im["id"] for im in coco["images"]]
        aids = [a["id"] for a in coco["annotations"]]
        if len(set(ids)) != len(ids) or 0 in ids or len(set(aids)) != len(aids) or 0 in aids:
            u.fail("%s: COCO ids repeat or are 0" % split, SEED)
        per_image = {i: 0 for i in ids}
        for a in coco["annotations"]:
            if a["image_id"] not in per_image:
                u.fail("%s: annotation %d names no image of the split" % (split, a["id"]), SEED)
            per_image[a["image_id"]] += 1
        stems = set()
        for im in coco["images"]:
            k = im["index"]
            if k in where:
                u.fail("image %d in %s and %s" % (k, where[k][0], split), SEED)
            where[k] = (split, im)
            stem = os.path.splitext(im["file_name"])[0]
            stems.add(stem)
            if not stem.startswith("%06d_" % k):
                u.fail("%s: %s is not image %d's file" % (split, im["file_name"], k), SEED)
            a = os.path.join(ds, split, im["file_name"])
            b = os.path.join(ds, "images", split, im["file_name"])
            if not (os.path.isfile(a) and os.path.isfile(b) and os.path.samefile(a, b)):
                u.fail("%s: %s not the same file under %s/ and images/%s/" % (split, im["file_name"], split, split), SEED)
            lab = os.path.join(ds, "labels", split, stem + ".txt")
            nyolo = len(open(lab).read().split("\n")) - 1 if os.path.getsize(lab) else 0
            nkitti = len(open(os.path.join(ds, "kitti", "training", "label_2", "%06d.txt" % k)).readlines())
            if not (nyolo == nkitti == per_image[im["id"]]):
                u.fail("%s: image %d: %d COCO labels, %d YOLO, %d KITTI"
                       % (split, k, per_image[im["id"]], nyolo, nkitti), SEED)
        # nothing else in the split's folders
        for folder, ext in ((split, ".png"), (os.path.join("images", split), ".png"),
                            (os.path.join("labels", split), ".txt")):
            d = os.path.join(ds, folder)
            got = {f[:-len(ext)] for f in os.listdir(d)} if os.path.isdir(d) else set()
            if got != stems:
                u.fail("%s/: %s, COCO %s" % (folder, sorted(got), sorted(stems)), SEED)
        sets = os.path.join(ds, "kitti", "ImageSets", ("train" if split == TRAIN else "val") + ".txt")
        listed = sorted(map(int, open(sets).read().split())) if os.path.exists(sets) else []
        if listed != sorted(im["index"] for im in coco["images"]):
            u.fail("KITTI ImageSets/%s: %s" % (os.path.basename(sets), listed), SEED)
    if sorted(where) != list(range(count)):
        u.fail("images in the splits: %s, expected 0..%d" % (sorted(where), count - 1), SEED)
    y = open(os.path.join(ds, "data.yaml")).read()
    fields = dict(re.findall(r"^(\w+):\s*(\S*)\s*$", y, re.M))
    if fields.get("train") != "images/" + TRAIN:
        u.fail("data.yaml: train is %r" % fields.get("train"), SEED)
    nval = sum(1 for s, _ in where.values() if s == VAL)
    if nval and fields.get("val") != "images/" + VAL:
        u.fail("data.yaml: val is %r with %d validation images" % (fields.get("val"), nval), SEED)
    return where


def check_held_out(where, key, value, what):
    n = 0
    for k, (split, im) in sorted(where.items()):
        held = im[key] == value
        if held != (split == VAL):
            u.fail("%s: image %d (%s %s) is in %s" % (what, k, key, im[key], split), SEED)
        n += held
    if n == 0 or n == len(where):
        u.fail("%s: %d of %d images held out: the test needs both kinds" % (what, n, len(where)), SEED)
    print("%s: %d of %d images in %s, exactly those with %s %s" % (what, n, len(where), VAL, key, value))


def main():
    u.need_povray()
    with tempfile.TemporaryDirectory() as tmp:
        site = make_site(tmp)
        calib = os.path.join(tmp, "calib")
        os.makedirs(calib)
        for cam in ("cam1", "cam3"):
            shutil.copy(os.path.join(u.DEMO, "truth", cam + ".cameramodel"), calib)

        # hold out a background; the background an image was drawn over is recorded per image
        ds = os.path.join(tmp, "bg")
        synth(site, calib, ds, 8, ["--val-backgrounds", "name=bgB"])
        where = check_layout(ds, 8)
        for _, im in where.values():
            if im["background"] not in ("bgA", "bgB"):
                u.fail("image %d: background %r" % (im["index"], im["background"]), SEED)
        check_held_out(where, "background", "bgB", "--val-backgrounds name=bgB")

        # hold out a camera
        ds = os.path.join(tmp, "cam")
        synth(site, calib, ds, 4, ["--val-camera", "cam3"])
        check_held_out(check_layout(ds, 4), "camera", "cam3", "--val-camera cam3")

        # by fraction, one shard and two shards
        one = os.path.join(tmp, "one")
        synth(site, calib, one, 8, ["--val-fraction", "0.5"])
        ref = {k: s for k, (s, _) in check_layout(one, 8).items()}
        nval = sum(s == VAL for s in ref.values())
        if nval in (0, 8):
            u.fail("--val-fraction 0.5: %d of 8 in val" % nval, SEED)
        shards = []
        for i in range(2):
            d = os.path.join(tmp, "shard%d" % i)
            synth(site, calib, d, 8, ["--val-fraction", "0.5", "--shard", "%d/2" % i])
            shards.append(d)
            for split in (TRAIN, VAL):
                for im in read_split(d, split)["images"]:
                    if im["index"] % 2 != i:
                        u.fail("shard %d/2 holds image %d" % (i, im["index"]), SEED)
                    if ref[im["index"]] != split:
                        u.fail("shard %d/2 puts image %d in %s, one shard in %s"
                               % (i, im["index"], split, ref[im["index"]]), SEED)
        merged = os.path.join(tmp, "merged")
        u.run(["synth", "merge"] + shards + ["-o", merged])
        got = {k: s for k, (s, _) in check_layout(merged, 8).items()}
        if got != ref:
            u.fail("merged splits %s, one shard %s" % (got, ref), SEED)
        print("--val-fraction 0.5: %d of 8 in %s; two shards and their merge agree with one shard"
              % (nval, VAL))
    print("test_synth_val_split: ok")


if __name__ == "__main__":
    main()

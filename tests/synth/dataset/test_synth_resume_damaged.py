#!/usr/bin/python3
# Issue 14, finding 6 (second half): resume looked only at parts/*.json, so a deleted image was
# not remade and the COCO file still listed it, and a corrupt part file stopped the run with
# "not a COCO file". Now every image whose part is present is checked before it is skipped; a
# missing or corrupt file is remade with a notice naming it and the fault, and the COCO file
# lists only images that exist.
#
# Oracles: OpenCV (Python) decodes every file_name the COCO file lists at the width and height
# it states; the repaired dataset equals an undamaged run byte for byte (image k depends only on
# (seed, k)).
import filecmp
import json
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

SEED = 14
COUNT = 8


def synth(calib, out, extra=()):
    return subprocess.run([u.ROADSIDE, "synth", u.DEMO, "--calib", calib, "--count", str(COUNT), "--val-fraction", "0",
                           "-o", out, "--seed", str(SEED), "--camera", "cam1", "--size", "64x36",
                           "--vehicles", "3"] + list(extra),
                          capture_output=True, text=True, timeout=120)


def files(d):
    out = []
    for root, _, names in os.walk(d):
        out += [os.path.relpath(os.path.join(root, n), d) for n in names]
    return sorted(out)


def coco_images_decode(out):
    """Every image the COCO file lists exists and decodes (OpenCV) at its stated size."""
    import cv2
    coco = json.load(open(os.path.join(out, "annotations", "instances_train2017.json")))
    for im in coco["images"]:
        path = os.path.join(out, "train2017", im["file_name"])
        a = cv2.imread(path, cv2.IMREAD_UNCHANGED) if os.path.isfile(path) else None
        if a is None:
            u.fail("the COCO file lists %s, which does not exist or decode" % path, SEED)
        if a.shape[1] != im["width"] or a.shape[0] != im["height"]:
            u.fail("%s: %dx%d, the COCO file says %dx%d"
                   % (path, a.shape[1], a.shape[0], im["width"], im["height"]), SEED)
    return [im["file_name"] for im in coco["images"]]


def main():
    u.need_povray()
    import cv2
    import numpy as np
    with tempfile.TemporaryDirectory() as tmp:
        calib = u.demo_calib(tmp)
        ref = os.path.join(tmp, "ref")
        p = synth(calib, ref)
        if p.returncode != 0:
            u.fail("first run: %s" % p.stderr, SEED)
        out = os.path.join(tmp, "out")
        shutil.copytree(ref, out)
        stem = ["%06d_cam1" % k for k in range(COUNT)]
        png = [os.path.join(out, "train2017", s + ".png") for s in stem]
        part = [os.path.join(out, "parts", s + ".json") for s in stem]

        # Damage, one kind per image; expected: (file named in the notice, what it says)
        expected = {}
        os.remove(png[0])
        expected[0] = (png[0], "missing")
        data = open(png[1], "rb").read()
        open(png[1], "wb").write(data[: len(data) // 2])  # cut short
        expected[1] = (png[1], "cut short")
        cv2.imwrite(png[2], np.zeros((10, 12, 3), np.uint8))  # a valid PNG of another size
        expected[2] = (png[2], "12x10 pixels")
        tail = open(png[3], "rb").read()[-12:]
        open(png[3], "wb").write(b"\x89PNG\r\n\x1a\n" + b"\0" * 40 + tail)
        expected[3] = (png[3], "cannot read the image")  # ends like a PNG, decodes as none
        text = open(part[4]).read()
        open(part[4], "w").write(text[: len(text) // 2])  # the part cut short
        expected[4] = (part[4], "not JSON")
        yolo = os.path.join(out, "labels", "train2017", stem[5] + ".txt")
        os.remove(yolo)
        expected[5] = (yolo, "missing")
        kitti = os.path.join(out, "kitti", "training", "label_2", stem[6][:6] + ".txt")
        os.replace(kitti, kitti + ".saved")
        os.symlink(stem[6][:6] + ".txt.saved", kitti)  # a link in a file's place
        expected[6] = (kitti, "not a regular file")
        json.dump({"images": [], "annotations": []}, open(part[7], "w"))  # parses, lists nothing
        expected[7] = (part[7], "not the COCO file of the one image")

        # Shard 1/2 (k odd) remakes its own damaged images; the even ones are another shard's:
        # left out of the COCO file, each with a notice (before the fix, the COCO file listed
        # the missing image 0)
        p = synth(calib, out, ["--shard", "1/2"])
        if p.returncode != 0:
            u.fail("shard 1/2 over the damage: exit %d\n%s" % (p.returncode, p.stderr), SEED)
        listed = coco_images_decode(out)
        lines = p.stderr.splitlines()
        for k in range(COUNT):
            f, why = expected[k]
            tail = "remaking image %d" % k if k % 2 else "left out of the COCO file"
            if not [x for x in lines if f in x and why in x and tail in x]:
                u.fail("shard 1/2: no notice \"%s ... %s ... %s\":\n%s" % (f, why, tail, p.stderr),
                       SEED)
            if (stem[k] + ".png" in listed) != (k % 2 == 1):
                u.fail("shard 1/2: image %d %s listed" % (k, "not" if k % 2 else "damaged and"), SEED)
        print("shard 1/2: %d listed, each decodes; notices:\n  %s"
              % (len(listed), p.stderr.strip().replace("\n", "\n  ")))

        # The full rerun remakes the rest: each notice names the file and its fault
        p = synth(calib, out)
        if p.returncode != 0:
            u.fail("rerun: exit %d\n%s" % (p.returncode, p.stderr), SEED)
        for k in (0, 2, 4, 6):
            f, why = expected[k]
            if not [x for x in p.stderr.splitlines() if f in x and why in x and
                    "remaking image %d" % k in x]:
                u.fail("rerun: no notice for %s (%s):\n%s" % (f, why, p.stderr), SEED)
        if "4 made, 4 already done" not in p.stdout or "4 of the images made were found damaged" \
                not in p.stdout:
            u.fail("rerun summary: %s" % p.stdout, SEED)
        os.remove(kitti + ".saved")
        listed = coco_images_decode(out)
        if len(listed) != COUNT:
            u.fail("%d images listed after the repair, expected %d" % (len(listed), COUNT), SEED)
        if files(out) != files(ref):
            u.fail("files differ from an undamaged run:\n%s\n%s" % (files(out), files(ref)), SEED)
        for rel in files(ref):
            # data.yaml names its folder (Ultralytics' absolute "path"); run.json lists the
            # shards run into the folder
            if rel in ("data.yaml", "run.json"):
                continue
            if not filecmp.cmp(os.path.join(out, rel), os.path.join(ref, rel), shallow=False):
                u.fail("%s differs from an undamaged run's" % rel, SEED)
        print("rerun: %s; %d files byte-identical to an undamaged run"
              % (p.stdout.splitlines()[0], len(files(ref))))

        # A finished, intact dataset: nothing remade, no notice
        p = synth(calib, out)
        if p.returncode != 0 or "0 made, %d already done" % COUNT not in p.stdout or p.stderr.count(
                "remaking"):
            u.fail("intact rerun: %s %s" % (p.stdout, p.stderr), SEED)
    print("OK")


if __name__ == "__main__":
    main()

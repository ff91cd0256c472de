#!/usr/bin/python3
# Issue 17: `roadside dataset view DATASET -o DIR` (contact sheets with the labels drawn). One tiny
# `roadside synth` run (5 images of 160x90, one camera, real POV-Ray), then:
#  - --per-page 2 gives ceil(5 / 2) = 3 pages (page_001..003.png, no page_004), index.html shows
#    each page;
#  - each image's tile is where index.json says: of the offsets within 3 px, the one where most
#    page pixels equal the dataset's own image (read by OpenCV) exactly;
#  - at scale 1 the footprint box of every label is outlined through the outermost pixels whose
#    centres lie in it: columns ceil(x0) and floor(x1), rows ceil(y0) and floor(y1) of the
#    COCO footprint_bbox [x0, y0, x1 - x0, y1 - y0] (docs/labels.md conventions); the four
#    corner pixels on the page are exactly the footprint colour RGB (0, 230, 0);
#  - the same pages and footprint corners for a fisheye dataset (issue 38: 5 images of 320x240
#    through a Kannala-Brandt fisheye at cam1's pose, rendered on the fisheye canvas);
#  - bad input (no dataset, a JSON syntax error, a malformed box, a missing image, no -o) gives
#    a message naming the file (and line or field) and exit 1 (2 for usage), never a crash.
import json
import math
import os
import shutil
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

SEED = 9
W, H = 160, 90
FOOTPRINT_RGB = (0, 230, 0)


def check_pages(ds, out, W=W, H=H):
    p = u.run(["dataset", "view", ds, "-o", out, "--per-page", "2"])
    print(p.stdout.strip())
    for k in (1, 2, 3):
        if not os.path.isfile(os.path.join(out, "page_%03d.png" % k)):
            u.fail("page_%03d.png missing" % k, SEED)
    if os.path.exists(os.path.join(out, "page_004.png")):
        u.fail("a fourth page for 5 images at 2 a page", SEED)
    html = open(os.path.join(out, "index.html")).read()
    for k in (1, 2, 3):
        if 'src="page_%03d.png"' % k not in html:
            u.fail("index.html does not show page %d" % k, SEED)
    index = json.load(open(os.path.join(out, "index.json")))
    if index["pages"] != 3 or len(index["images"]) != 5 or index["scale"] != 1:
        u.fail("index.json: %d pages, %d images, scale %r" % (index["pages"], len(index["images"]), index["scale"]), SEED)
    coco = json.load(open(os.path.join(ds, "annotations", "instances_train2017.json")))
    anns = {}
    for a in coco["annotations"]:
        anns.setdefault(a["image_id"], []).append(a)
    ncorners = 0
    worst_share = 1.0
    for e in index["images"]:
        page = u.read_png(os.path.join(out, "page_%03d.png" % e["page"]))
        img = u.read_png(os.path.join(ds, "train2017", e["file_name"]))
        # the offset within 3 px of index.json's where most pixels are exactly the image's (at
        # scale 1 the tile is the image, 8-bit for 8-bit, where nothing is drawn over it)
        best = (-1.0, None)
        for dy in range(-3, 4):
            for dx in range(-3, 4):
                x0, y0 = e["x"] + dx, e["y"] + dy
                if x0 < 0 or y0 < 0 or x0 + W > page.shape[1] or y0 + H > page.shape[0]:
                    continue
                same = float(np.mean(np.all(page[y0:y0 + H, x0:x0 + W, :3] == img[:, :, :3], axis=2)))
                best = max(best, (same, (x0, y0)))
        bx, by = best[1]
        worst_share = min(worst_share, best[0])
        if (bx, by) != (e["x"], e["y"]) or best[0] < 0.5:
            u.fail("%s: index.json puts the tile at (%d, %d), the image is found at (%d, %d) (%.0f %% "
                   "of its pixels)" % (e["file_name"], e["x"], e["y"], bx, by, 100 * best[0]), SEED)
        for a in anns.get(e["image_id"], []):
            x, y, w, h = a["footprint_bbox"]
            c0, c1 = math.ceil(x), math.floor(x + w)
            r0, r1 = math.ceil(y), math.floor(y + h)
            if c0 > c1 or r0 > r1:
                continue  # narrower than a pixel: drawn at its centre
            for cx, cy in ((c0, r0), (c1, r0), (c0, r1), (c1, r1)):
                got = tuple(int(v) for v in page[e["y"] + cy, e["x"] + cx, :3])
                if got != FOOTPRINT_RGB:
                    u.fail("%s: annotation %d: footprint corner (%d, %d) is %s, expected %s"
                           % (e["file_name"], a["id"], cx, cy, got, FOOTPRINT_RGB), SEED)
                ncorners += 1
    if ncorners < 12:
        u.fail("only %d footprint corners checked: the test needs a few labels" % ncorners, SEED)
    print("view: 3 pages for 5 images; each image found at its tile (>= %.0f %% of its pixels "
          "unchanged); %d footprint corners in the footprint colour" % (100 * worst_share, ncorners))


def check_bad_input(tmp, ds):
    out = os.path.join(tmp, "v")
    p = u.run(["dataset", "view", os.path.join(tmp, "nothing"), "-o", out], expect=1)
    if "annotations" not in p.stderr:
        u.fail("no dataset: message %r" % p.stderr)
    p = u.run(["dataset", "view", ds], expect=2)
    if "-o" not in p.stderr:
        u.fail("no -o: message %r" % p.stderr)
    bad = os.path.join(tmp, "bad")
    shutil.copytree(ds, bad)
    gt = os.path.join(bad, "annotations", "instances_train2017.json")
    text = open(gt).read()
    coco = json.loads(text)
    # a syntax error on line 3
    with open(gt, "w") as f:
        f.write('{"images": [\n{"id": 1},\n{"id": ,}]}\n')
    p = u.run(["dataset", "view", bad, "-o", out], expect=1)
    if "instances_train2017.json:3" not in p.stderr:
        u.fail("JSON syntax error: message %r does not name the file and line 3" % p.stderr)
    # a malformed box
    c = json.loads(text)
    c["annotations"][0]["footprint_bbox"] = "wide"
    u.write_json(gt, c)
    p = u.run(["dataset", "view", bad, "-o", out], expect=1)
    if "annotations[0].footprint_bbox" not in p.stderr or "instances_train2017.json" not in p.stderr:
        u.fail("malformed box: message %r" % p.stderr)
    # a missing image
    u.write_json(gt, coco)
    os.remove(os.path.join(bad, "train2017", coco["images"][0]["file_name"]))
    p = u.run(["dataset", "view", bad, "-o", out], expect=1)
    if coco["images"][0]["file_name"] not in p.stderr:
        u.fail("missing image: message %r" % p.stderr)
    print("bad input: no dataset, JSON syntax (file:line), malformed field, missing image, no -o: "
          "named, exit 1/2")


def main():
    u.need_povray()
    with tempfile.TemporaryDirectory() as tmp:
        calib = u.demo_calib(tmp)
        ds = os.path.join(tmp, "ds")
        u.run(["synth", "--val-fraction", "0", u.DEMO, "--calib", calib, "--count", "5", "-o", ds, "--seed", str(SEED),
               "--camera", "cam1", "--size", "%dx%d" % (W, H), "--vehicles", "6", "--jobs", "2"])
        check_pages(ds, os.path.join(tmp, "view"))
        check_bad_input(tmp, ds)
        # issue 38: the same on a fisheye (1280x960 Kannala-Brandt at cam1's pose, made 320x240)
        sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "povray"))
        from test_pins import fisheye_camera
        fisheye_camera(os.path.join(tmp, "calib_fisheye"), (0.02, -0.004), 0)
        ds = os.path.join(tmp, "ds_fisheye")
        u.run(["synth", "--val-fraction", "0", u.DEMO, "--calib", os.path.join(tmp, "calib_fisheye"), "--count", "5", "-o", ds,
               "--seed", str(SEED), "--camera", "cam1", "--size", "320x240", "--vehicles", "6", "--jobs", "2"])
        check_pages(ds, os.path.join(tmp, "view_fisheye"), 320, 240)
    print("test_dataset_view: ok")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
# roadside render --labels, end to end with the real POV-Ray: every visible box in the COCO
# labels equals the bounding box of its vehicle's pixels in the ID pass; a vehicle hidden behind
# a bus has visibility 0 and no visible box; a vehicle cut by the image border is truncated; the
# COCO file has YOLOX's fields. Oracle: the ID image itself (ids.png) and mrcal for the geometry.
import json
import os
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

SEED = 11


def main():
    u.need_povray()
    import mrcal
    with tempfile.TemporaryDirectory() as tmp:
        calib, model, W, H, lens, intr = u.small_pinhole(tmp)
        rt_enu_cam = mrcal.invert_rt(model.extrinsics_rt_fromref())
        c = rt_enu_cam[3:]

        def ground(qx, qy):
            d = mrcal.rotate_point_r(rt_enu_cam[:3], mrcal.unproject(np.array([qx, qy]), lens,
                                                                     intr))
            return c - c[2] / d[2] * d, d

        # a bus broadside to the camera, a hatchback right behind it on the same ray
        p, d = ground(0.5 * W, 0.7 * H)
        az = np.degrees(np.arctan2(d[0], d[1]))
        h = d[:2] / np.hypot(*d[:2])
        behind = p[:2] + 3.0 * h
        vs = [{"class": "bus", "e": p[0], "n": p[1], "yaw_deg": az + 90, "length": 12,
               "width": 2.5, "height": 3.4, "id": "bus"},
              {"class": "hatchback", "e": behind[0], "n": behind[1], "yaw_deg": az + 90,
               "length": 3.5, "width": 1.6, "height": 1.2, "id": "hidden"}]
        # one cut by the left border, a few elsewhere
        q, _ = ground(2.0, 0.85 * H)
        vs.append({"class": "van", "e": q[0], "n": q[1], "yaw_deg": az + 90, "id": "cut"})
        vs += [dict(v, id="x%d" % i) for i, v in
               enumerate(u.ground_vehicles(model, 3, SEED, v_range=(0.45, 0.6),
                                           u_range=(0.1, 0.9)))]
        veh = os.path.join(tmp, "veh.json")
        u.write_json(veh, [{k: (float(x) if isinstance(x, np.floating) else x)
                            for k, x in v.items()} for v in vs])
        out = os.path.join(tmp, "out")
        p = u.run(["render", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles", veh,
                   "-o", out, "--labels", "--bbox", "visible"] + (["--keep"] if os.environ.get("KEEP") else []))
        if os.environ.get("KEEP"):
            import shutil
            shutil.copytree(out, os.environ["KEEP"], dirs_exist_ok=True)
        print(p.stdout.strip())
        ids = u.read_png(os.path.join(out, "ids.png"))
        if (ids == 2).any():
            u.fail("test setup: the hatchback is not hidden (%d pixels)" % (ids == 2).sum(), SEED)
        coco = json.load(open(os.path.join(out, "annotations", "instances_train2017.json")))
        for key in ("images", "annotations", "categories"):
            if key not in coco:
                u.fail("COCO without " + key)
        im = coco["images"][0]
        if (im["width"], im["height"]) != (W, H) or \
                not os.path.exists(os.path.join(out, "train2017", im["file_name"])):
            u.fail("COCO image entry %s" % im)
        by_index = {a["vehicle_index"]: a for a in coco["annotations"]}
        checked = 0
        for k in range(len(vs)):
            ys, xs = np.nonzero(ids == k + 1)
            a = by_index.get(k)
            if xs.size == 0:
                if a is not None and a.get("visible_bbox") is not None:
                    u.fail("vehicle %d has no ID pixels but a visible box %s" % (k, a["visible_bbox"]))
                continue
            if a is None:
                u.fail("vehicle %d visible (%d px) but not labelled" % (k, xs.size))
            want = [xs.min() - 0.5, ys.min() - 0.5, xs.max() - xs.min() + 1, ys.max() - ys.min() + 1]
            got = a["visible_bbox"]
            if np.max(np.abs(np.array(got, float) - want)) > 1e-9 or a["visible_pixels"] != xs.size:
                u.fail("vehicle %d: visible box %s / %s px, ID pass %s / %d px"
                       % (k, got, a["visible_pixels"], want, xs.size), SEED)
            corner = [got[0] + 0.5, got[1] + 0.5, got[2], got[3]]  # COCO's corner convention (issue 41)
            if np.max(np.abs(np.array(a["bbox"]) - corner)) > 1e-12 or a["iscrowd"] != 0 or "area" not in a:
                u.fail("vehicle %d: bbox (--bbox visible) %s, YOLOX fields" % (k, a["bbox"]))
            checked += 1
        if checked < 3:
            u.fail("only %d visible vehicles checked" % checked, SEED)
        # the hidden one: dropped with --bbox visible; with the default box, visibility 0
        p = u.run(["render", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles", veh,
                   "-o", out, "--labels"])
        coco = json.load(open(os.path.join(out, "annotations", "instances_train2017.json")))
        by_index = {a["vehicle_index"]: a for a in coco["annotations"]}
        hidden = by_index.get(1)
        if hidden is None or hidden["visibility"] != 0 or hidden.get("visible_bbox") is not None:
            u.fail("hidden vehicle: %s" % hidden)
        cut = by_index.get(2)
        if cut is None or not (0 < cut["truncation"] < 1):
            u.fail("vehicle cut by the border: truncation %s" % (cut and cut["truncation"]))
        print("%d visible boxes equal their ID pixels' boxes; hidden: visibility 0; cut by the "
              "border: truncation %.3f" % (checked, cut["truncation"]))
        for path in (os.path.join(out, "labels", "train2017", "image.txt"),
                     os.path.join(out, "label_2", "image.txt")):
            if not os.path.exists(path):
                u.fail("missing " + path)
    print("PASS")


if __name__ == "__main__":
    main()

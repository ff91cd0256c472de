#!/usr/bin/env python3
# issue 40, a background's condition (synth/backdrop/rs_synth_condition.h, docs/conditions.md):
# 1. The estimate from the image (test_condition_dump: rs_synth_condition_estimate) on digital-
#    twin renders of the demo site through cam1 at 320 px: sunny, cloudy, rain at 10:00Z, snow,
#    night (23:00Z), and a dusk made here with numpy from the cloudy one (linear light x 0.25,
#    tinted (1, 0.85, 0.7): the twin draws no dusk). Expected: day-dry, day-dry, day-dry (wet is
#    not estimated: tag it), day-snow, night-dry, dusk-dry: 6 of 6.
# 2. Fresnel's reflectance of water (rs_synth_fresnel_water) against the equations written out
#    here with numpy (ior 1.33), within 1e-9: 0.0201 head-on.
# 3. `roadside synth` over those backgrounds (the six tagged ones, and the night one again under
#    a name with no tags: estimated), 14 images of 160x90, 2 vehicles each: every image's COCO
#    record has the condition of its background (tagged: from `conditions` and `time`; untagged:
#    estimated, condition_estimated true), run.json's "conditions" counts equal the COCO
#    images' counts, and `roadside dataset stats` prints the same counts with their labels.
import collections
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

import cv2
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

DUMP = sys.argv[1]


def fresnel(ci, n=1.33):
    st = np.sqrt(1 - ci * ci) / n
    ct = np.sqrt(1 - st * st)
    rs = (ci - n * ct) / (ci + n * ct)
    rp = (n * ci - ct) / (n * ci + ct)
    return 0.5 * (rs * rs + rp * rp)


def main():
    u.need_povray()
    with tempfile.TemporaryDirectory() as tmp:
        site, calib = os.path.join(tmp, "site"), os.path.join(tmp, "calib")
        shutil.copytree(u.DEMO, site, ignore=shutil.ignore_patterns("truth"))
        u.scaled_camera(calib, "cam1", 320, True)
        u.run(["site", "render-backgrounds", site, "--calib", calib, "--camera", "cam1",
               "--times", "2024-06-21T10:00:00Z", "--weather", "sunny,cloudy,rain,snow"])
        u.run(["site", "render-backgrounds", site, "--calib", calib, "--camera", "cam1",
               "--times", "2024-06-21T23:00:00Z", "--weather", "cloudy"])
        bgdir = os.path.join(site, "backgrounds", "cam1")
        files = sorted(os.listdir(bgdir))
        # a dusk from the cloudy twin, in linear light
        cl = cv2.imread(os.path.join(bgdir, [f for f in files if "cloudy" in f][0]))[:, :, ::-1] / 255.0
        lin = np.where(cl <= 0.04045, cl / 12.92, ((cl + 0.055) / 1.055) ** 2.4) * 0.25 * np.array([1, 0.85, 0.7])
        srgb = np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * lin ** (1 / 2.4) - 0.055)
        dusk = os.path.join(tmp, "dusk.png")
        cv2.imwrite(dusk, np.round(srgb[:, :, ::-1] * 255).astype(np.uint8))
        expect = {"sunny": "day-dry", "cloudy": "day-dry", "rain": "day-dry", "snow": "day-snow",
                  "night": "night-dry", "dusk": "dusk-dry"}
        paths = [os.path.join(bgdir, f) for f in files] + [dusk]
        out = subprocess.run([DUMP] + paths, capture_output=True, text=True)
        if out.returncode != 0:
            u.fail("test_condition_dump: " + out.stderr)
        lines = out.stdout.strip().split("\n")
        right = 0
        for p, line in zip(paths, lines):
            kind = [k for k in expect if k in os.path.basename(p)][0]
            got = line.split()[0]
            right += got == expect[kind]
            print("estimate: %-34s %-10s (expected %s) ground %s sky %s sat %s"
                  % (os.path.basename(p), got, expect[kind], *line.split()[1:]))
        print("estimate: %d of %d right" % (right, len(paths)))
        if right != len(paths):
            u.fail("condition estimate: %d of %d right" % (right, len(paths)))
        f = [float(x) for x in lines[-1].split()[1:]]
        ref = [fresnel(c) for c in (1.0, 0.5, 0.1, 0.02)]
        print("fresnel: %s vs numpy %s" % (f, np.round(ref, 6).tolist()))
        if max(abs(a - b) for a, b in zip(f, ref)) > 2e-6:
            u.fail("fresnel: %s vs %s" % (f, ref))

        # 3. synth's mix: the night background again, untagged
        sj = os.path.join(site, "site.json")
        doc = json.load(open(sj))
        cam = [c for c in doc["cameras"] if c["id"] == "cam1"][0]
        night = [b for b in cam["background_images"] if b["tags"].get("conditions") == "night"][0]
        shutil.copy(os.path.join(site, night["file"]), os.path.join(bgdir, "untagged.png"))
        cam["background_images"].append({"name": "untagged", "file": "backgrounds/cam1/untagged.png", "tags": {}})
        json.dump(doc, open(sj, "w"), indent=1)
        ds = os.path.join(tmp, "ds")
        p = u.run(["synth", "--val-fraction", "0", site, "--calib", calib, "--camera", "cam1", "--count", "14", "--vehicles", "2",
                   "--size", "160x90", "--seed", "5", "--jobs", "4", "-o", ds])
        print([x for x in p.stdout.split("\n") if x.startswith("conditions:")][0])
        coco = json.load(open(os.path.join(ds, "annotations", "instances_train2017.json")))
        tags = {b["name"]: b["tags"] for b in cam["background_images"]}
        tagged = {"sunny": "day-dry", "cloudy": "day-dry", "rain": "day-wet", "snow": "day-snow", "night": "night-dry"}
        counts = collections.Counter()
        labels = collections.Counter()
        per_image = collections.Counter(a["image_id"] for a in coco["annotations"])
        for im in coco["images"]:
            t = tags[im["background"]]
            want = tagged[t["conditions"]] if "conditions" in t else "night-dry"
            if im.get("condition") != want or im.get("condition_estimated") != ("conditions" not in t):
                u.fail("image %s over %s: condition %s (estimated %s), expected %s"
                       % (im["file_name"], im["background"], im.get("condition"), im.get("condition_estimated"), want))
            counts[want] += 1
            labels[want] += per_image[im["id"]]
        mix = json.load(open(os.path.join(ds, "run.json")))["conditions"]["0/1"]
        print("run.json conditions %s; COCO %s" % (mix, dict(counts)))
        if mix != dict(counts):
            u.fail("run.json's mix %s differs from the images' %s" % (mix, dict(counts)))
        st = u.run(["dataset", "stats", ds]).stdout
        line = [x for x in st.split("\n") if x.startswith("conditions:")][0]
        print(line)
        got = {m.group(1): (int(m.group(2)), int(m.group(3)))
               for m in re.finditer(r"([a-z]+-[a-z]+): (\d+) images, (\d+) labels", line)}
        if got != {k: (counts[k], labels[k]) for k in counts}:
            u.fail("dataset stats: %s, expected %s" % (got, {k: (counts[k], labels[k]) for k in counts}))
    print("ok")


if __name__ == "__main__":
    main()

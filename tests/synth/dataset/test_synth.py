#!/usr/bin/python3
# roadside synth (issue 7): determinism, shards under GNU parallel + merge == 1 shard, resume,
# labels of the scaled camera against mrcal's own projection, usage errors. Real POV-Ray.
import filecmp
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

SEED = 7
COUNT = 4
W, H = 160, 90


def synth(calib, out, extra=()):
    return u.run(["synth", u.DEMO, "--calib", calib, "--count", str(COUNT), "--val-fraction", "0", "-o", out,
                  "--seed", str(SEED), "--camera", "cam1", "--camera", "cam3",
                  "--size", "%dx%d" % (W, H), "--vehicles", "12"] + list(extra))


def tree(d):
    """Relative paths of the dataset's files (the parts/ folder is the run's own bookkeeping)."""
    out = []
    for root, _, files in os.walk(d):
        for f in files:
            rel = os.path.relpath(os.path.join(root, f), d)
            # data.yaml names its dataset's own absolute path (Ultralytics' "path")
            if not rel.startswith("parts" + os.sep) and rel != "data.yaml":
                out.append(rel)
    return sorted(out)


def same_files(a, b, what):
    ta, tb = tree(a), tree(b)
    if ta != tb:
        u.fail("%s: different files:\n%s\n%s" % (what, ta, tb), SEED)
    for rel in ta:
        if not filecmp.cmp(os.path.join(a, rel), os.path.join(b, rel), shallow=False):
            u.fail("%s: %s differs" % (what, rel), SEED)
    return ta


def check_labels(out):
    import mrcal
    coco = json.load(open(os.path.join(out, "annotations", "instances_train2017.json")))
    if len(coco["images"]) != COUNT:
        u.fail("%d images in the COCO file, expected %d" % (len(coco["images"]), COUNT), SEED)
    models = {}
    for cam in ("cam1", "cam3"):
        m = mrcal.cameramodel(os.path.join(u.DEMO, "truth", cam + ".cameramodel"))
        lens, intr = m.intrinsics()
        W0, H0 = m.imagersize()
        intr = np.array(intr, dtype=float)
        sx, sy = W / W0, H / H0
        intr[0] *= sx
        intr[1] *= sy
        intr[2] = (intr[2] + 0.5) * sx - 0.5
        intr[3] = (intr[3] + 0.5) * sy - 0.5
        models[cam] = (lens, intr, m.extrinsics_rt_fromref())
    files = {im["id"]: im["file_name"] for im in coco["images"]}
    ids = [im["id"] for im in coco["images"]]
    if ids != list(range(1, COUNT + 1)) or sorted(files.values()) != [files[i] for i in ids]:
        u.fail("image ids not 1..N in file-name order: %s" % files, SEED)
    checked, worst = 0, 0.0
    for a in coco["annotations"]:
        name = files[a["image_id"]]
        cam = name.split("_", 1)[1][:-4]
        lens, intr, rt = models[cam]
        c = np.array(a["box3d"]["center_enu_m"], dtype=float)
        dims = a["box3d"]["dimensions_m"]
        p = c - np.array([0, 0, dims[2] / 2.0])
        bc = a.get("bottom_center")
        if bc is None or any(v is None for v in bc):
            continue
        q = mrcal.project(mrcal.transform_point_rt(rt, p), lens, intr)
        err = float(np.hypot(*(q - np.array(bc, dtype=float))))
        if not math.isfinite(err):
            u.fail("NaN bottom centre in %s" % name, SEED)
        worst = max(worst, err)
        checked += 1
    if checked == 0:
        u.fail("no annotation to check (no vehicle in view)", SEED)
    if worst > 1e-6:
        u.fail("bottom centre vs mrcal.project of the scaled camera: %.3g px > 1e-6" % worst, SEED)
    print("labels: %d annotations, bottom centre vs mrcal: worst %.2g px" % (checked, worst))


def check_interrupted(tmp, calib, ref):
    """A run killed (SIGKILL) part-way leaves only complete files; a rerun completes it into the
    same dataset as an uninterrupted run."""
    import time
    out = os.path.join(tmp, "killed")
    args = [u.ROADSIDE, "synth", u.DEMO, "--calib", calib, "--count", str(COUNT), "--val-fraction", "0", "-o", out,
            "--seed", str(SEED), "--camera", "cam1", "--camera", "cam3", "--size",
            "%dx%d" % (W, H), "--vehicles", "12"]
    for delay in (1.0, 2.5):
        p = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(delay)
        p.kill()
        p.wait()
        for root, _, files in os.walk(out):
            for f in files:
                if ".tmp" in f or f.startswith("."):
                    continue  # temporary names: never taken for outputs
                path = os.path.join(root, f)
                if f.endswith(".json") and "work" not in root:
                    json.load(open(path))  # complete JSON or an exception
    # what a kill while a label is being written leaves (CI, 2026-11-24): the rerun removes it
    stale = os.path.join(out, "labels", "train2017", "000000_cam1.txt.tmp.Heb7CJ")
    os.makedirs(os.path.dirname(stale), exist_ok=True)
    with open(stale, "w") as f:
        f.write("0 0.5 0.5")
    p = u.run(args[1:])
    if os.path.exists(stale):
        u.fail("rerun left a killed run's temporary: %s" % stale, SEED)
    same_files(out, ref, "run killed twice then rerun")
    print("interrupted: killed at 1.0 s and 2.5 s, rerun: byte-identical (%s)"
          % p.stdout.splitlines()[0])


def check_shadows(tmp):
    """Over a digital-twin background in sun, differential rendering only darkens background
    pixels (shadows), and darkens some clearly; without --no-shadows vs with it, the vehicle
    pixels are the same."""
    import cv2
    site = os.path.join(tmp, "site")
    shutil.copytree(u.DEMO, site)
    calib = os.path.join(tmp, "calib_small")
    u.scaled_camera(calib, "cam1", 240, pinhole=False)
    u.run(["site", "render-backgrounds", site, "--calib", calib, "--camera", "cam1",
           "--times", "2024-06-21T15:00+02:00", "--weather", "sunny"])
    outs = {}
    # --no-appearance in both: the camera's look tops up the noise of shadowed pixels (a darker
    # value's noise), which may lift a pixel by a few codes (tests/synth/povray/test_render_look.py)
    for name, extra in (("sh", []), ("nosh", ["--no-shadows"])):
        out = os.path.join(tmp, name)
        u.run(["synth", site, "--calib", calib, "--count", "2", "-o", out, "--seed", str(SEED),
               "--camera", "cam1", "--vehicles", "15", "--no-appearance"] + extra)
        outs[name] = out
    darker = 0
    for f in sorted(os.listdir(os.path.join(outs["sh"], "train2017"))):
        a = cv2.imread(os.path.join(outs["sh"], "train2017", f)).astype(float)
        b = cv2.imread(os.path.join(outs["nosh"], "train2017", f)).astype(float)
        if a.shape != b.shape or not np.isfinite(a).all():
            u.fail("shadow run: %s: shape or NaN" % f, SEED)
        if (a - b).max() > 1.0:
            u.fail("shadows brightened %s by %.1f codes" % (f, (a - b).max()), SEED)
        darker += int(((b - a).max(axis=2) > 10).sum())
    if darker < 20:
        u.fail("shadows: only %d pixels darker by > 10 codes" % darker, SEED)
    print("shadows: %d pixels darker by > 10 codes, none brighter" % darker)
    # issue 40: the look of each background a dataset used, in DATASET/backgrounds.json and in
    # `dataset stats`: the twin background is a PNG (no JPEG quality), its file named
    out = os.path.join(tmp, "look")
    u.run(["synth", site, "--calib", calib, "--count", "1", "-o", out, "--seed", str(SEED), "--camera", "cam1"])
    looks = json.load(open(os.path.join(out, "backgrounds.json")))
    want = "backgrounds/cam1/twin_20240621T1300Z_sunny.png"
    entry = [b for b in looks.get("backgrounds", []) if b.get("file") == want]
    if not looks.get("applied") or len(entry) != 1 or entry[0]["look"]["jpeg_quality"] != 0 or \
            not entry[0]["look"]["noise_sigma_at_0_5"] >= 0:
        u.fail("backgrounds.json: %r (want one entry for %s, applied, JPEG quality 0)" % (looks, want), SEED)
    p = u.run(["dataset", "stats", out])
    if not re.search(r"^  %s: noise variance .* jpeg quality 0," % re.escape(want), p.stdout, re.M):
        u.fail("dataset stats: no look line for %s: %r" % (want, p.stdout), SEED)
    print("backgrounds.json and dataset stats: %s, jpeg quality 0 (a PNG), noise sigma %.4f at 0.5"
          % (want, entry[0]["look"]["noise_sigma_at_0_5"]))


def main():
    u.need_povray()
    if not shutil.which("parallel"):
        print("SKIP: GNU parallel not installed")
        sys.exit(77)
    with tempfile.TemporaryDirectory() as tmp:
        calib = os.path.join(tmp, "calib")
        os.makedirs(calib)
        for cam in ("cam1", "cam3"):
            shutil.copy(os.path.join(u.DEMO, "truth", cam + ".cameramodel"), calib)
        one = os.path.join(tmp, "one")
        p = synth(calib, one)
        print(p.stdout.strip())
        if "4 made" not in p.stdout:
            u.fail("first run did not make 4 images: " + p.stdout, SEED)
        check_labels(one)

        # two shards under GNU parallel, then merge: the same files as one shard
        shards = [os.path.join(tmp, "shard%d" % i) for i in range(2)]
        cmd = [u.ROADSIDE, "synth", u.DEMO, "--calib", calib, "--count", str(COUNT), "--val-fraction", "0", "-o",
               os.path.join(tmp, "shard{}"), "--seed", str(SEED), "--camera", "cam1",
               "--camera", "cam3", "--size", "%dx%d" % (W, H), "--vehicles", "12",
               "--shard", "{}/2"]
        r = subprocess.run(["parallel", "--will-cite", "-j2", " ".join(cmd), ":::", "0", "1"],
                           capture_output=True, text=True)
        if r.returncode != 0:
            u.fail("parallel: exit %d\n%s\n%s" % (r.returncode, r.stdout, r.stderr), SEED)
        merged = os.path.join(tmp, "merged")
        p = u.run(["synth", "merge"] + shards + ["-o", merged])
        print(p.stdout.strip())
        rels = same_files(one, merged, "merge of 2 shards vs 1 shard")
        print("merge == 1 shard: %d files byte-identical" % len(rels))

        # resume: remove one finished image; a rerun makes only it, identical to before
        ref = os.path.join(tmp, "ref")
        shutil.copytree(one, ref)
        stem = sorted(os.listdir(os.path.join(one, "parts")))[2][:-5]
        os.remove(os.path.join(one, "parts", stem + ".json"))
        os.remove(os.path.join(one, "train2017", stem + ".png"))
        p = synth(calib, one)
        if "1 made, 3 already done" not in p.stdout:
            u.fail("resume: " + p.stdout, SEED)
        same_files(one, ref, "rerun after removing %s" % stem)
        if os.path.exists(os.path.join(one, "work")):
            u.fail("work folder left behind", SEED)
        print("resume: 1 made, 3 skipped, byte-identical")

        check_interrupted(tmp, calib, ref)
        check_shadows(tmp)

        # usage errors: exit 2, nothing written
        bad = os.path.join(tmp, "bad")
        for args in (["--shard", "2/2"], ["--size", "10"], ["--backgrounds", "time"]):
            p = u.run(["synth", u.DEMO, "--calib", calib, "--count", "2", "-o", bad] + args,
                      expect=2)
        p = u.run(["synth", u.DEMO, "--calib", calib, "-o", bad], expect=2)
        p = u.run(["synth", u.DEMO, "--calib", calib, "--count", "1", "-o", bad, "--camera",
                   "nosuch"], expect=2)
        if "nosuch" not in p.stderr:
            u.fail("unknown camera not named: " + p.stderr)
    print("OK")


if __name__ == "__main__":
    main()

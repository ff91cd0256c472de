#!/usr/bin/python3
# Issue 17, finding "synth merge silently merged shards made with different --count and --size":
# merge refuses shards of different runs (count, size, seed, calibration), names missing shards,
# and verifies every listed file; two shards made by a GNU parallel recipe (docs/scale-out.md,
# every option passed, --jobs included) merge into the files of one run. Tiny images (64x36),
# real POV-Ray, 2 images per shard.
import json
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

SEED = 5


def synth(calib, out, count=4, size="64x36", seed=SEED, shard="0/2"):
    return u.run(["synth", u.DEMO, "--calib", calib, "--count", str(count), "--val-fraction", "0", "-o", out,
                  "--seed", str(seed), "--camera", "cam1", "--size", size, "--vehicles", "4",
                  "--shard", shard, "--jobs", "1"])


def refused(args, want):
    p = u.run(["synth", "merge"] + args, expect=None)
    if p.returncode == 0 or want not in p.stderr:
        u.fail("merge %s: exit %d, stderr %r; expected a refusal naming %r"
               % (" ".join(args), p.returncode, p.stderr, want))
    print("refused: " + p.stderr.strip().splitlines()[-1])


def main():
    u.need_povray()
    with tempfile.TemporaryDirectory() as tmp:
        calib = u.demo_calib(tmp)
        s0, s1 = os.path.join(tmp, "s0"), os.path.join(tmp, "s1")
        # the recipe of docs/scale-out.md: GNU parallel, every option passed, --jobs per shard
        if shutil.which("parallel"):
            cmd = [u.ROADSIDE, "synth", u.DEMO, "--calib", calib, "--count", "4", "--val-fraction", "0", "-o",
                   os.path.join(tmp, "s{}"), "--seed", str(SEED), "--camera", "cam1", "--size",
                   "64x36", "--vehicles", "4", "--jobs", "1", "--shard", "{}/2"]
            r = subprocess.run(["parallel", "--will-cite", "--halt", "now,fail=1", "-j2",
                                " ".join(cmd), ":::", "0", "1"], capture_output=True, text=True)
            if r.returncode != 0:
                u.fail("parallel recipe: exit %d: %s" % (r.returncode, r.stderr))
        else:
            synth(calib, s0, shard="0/2")
            synth(calib, s1, shard="1/2")
        out = os.path.join(tmp, "merged")
        p = u.run(["synth", "merge", s0, s1, "-o", out])
        print(p.stdout.strip())
        coco = json.load(open(os.path.join(out, "annotations", "instances_train2017.json")))
        if len(coco["images"]) != 4 or "info" not in coco:
            u.fail("merged: %d images (expected 4), info %s" % (len(coco["images"]), "info" in coco))
        for im in coco["images"]:
            for rel in (os.path.join("train2017", im["file_name"]),
                        os.path.join("images", "train2017", im["file_name"]),
                        os.path.join("kitti", "training", "calib", "%06d.txt" % im["index"])):
                if not os.path.isfile(os.path.join(out, rel)):
                    u.fail("merged: %s missing" % rel)

        # a missing shard is named
        refused([s0, "-o", os.path.join(tmp, "m1")], "shard 1/2")
        # another --count, another --size, another seed, another calibration: refused
        other = {}
        other["count"] = os.path.join(tmp, "count")
        synth(calib, other["count"], count=6, shard="1/2")
        refused([s0, other["count"], "-o", os.path.join(tmp, "m2")], "count 4 vs 6")
        other["size"] = os.path.join(tmp, "size")
        synth(calib, other["size"], size="96x54", shard="1/2")
        refused([s0, other["size"], "-o", os.path.join(tmp, "m3")], "width 64 vs 96")
        other["seed"] = os.path.join(tmp, "seed")
        synth(calib, other["seed"], seed=SEED + 1, shard="1/2")
        refused([s0, other["seed"], "-o", os.path.join(tmp, "m4")], "seed")
        calib2 = os.path.join(tmp, "calib2")
        u.scaled_camera(calib2, "cam1", 1920, pinhole=True)  # the same camera without distortion
        other["calib"] = os.path.join(tmp, "calib_other")
        synth(calib2, other["calib"], shard="1/2")
        refused([s0, other["calib"], "-o", os.path.join(tmp, "m5")], "cameras")
        # a listed file that is missing, or a PNG that is not at the listed size
        os.remove(os.path.join(s1, "labels", "train2017",
                               sorted(os.listdir(os.path.join(s1, "labels", "train2017")))[0]))
        refused([s0, s1, "-o", os.path.join(tmp, "m6")], "missing")
    print("test_synth_merge_refuses: ok")


if __name__ == "__main__":
    main()

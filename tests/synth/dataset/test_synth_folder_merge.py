#!/usr/bin/env python3
# issue 42, items 3, 5 and 6 and "synth -o SITE": an output folder is roadside's before anything
# is written or deleted in it, and merge verifies like resume.
#  3. `synth -o DIR` on a user's folder (a file "x.tmp.AbC123" and another) is refused, exit 1,
#     the folder unchanged; `synth merge -o DIR` too. In a dataset folder of roadside's (marked
#     .roadside-dataset), a rerun removes its own stale temporaries (run.json.tmp.Zz9999,
#     train2017/000001_cam1.png.tmp.Qq1234) and keeps the user's x.tmp.AbC123 there and in a
#     subfolder of its own.
#     `synth -o SITE` (a copy of the demo site) is refused before anything is created in it.
#  5. merge of a shard without its completion record (a killed shard: the record removed; and
#     one whose run.json "finished" never came: simulated the same way) is refused naming the
#     shard and the folder; OUT is not created.
#  6. merge of a shard whose PNG is cut short is refused naming the file; OUT is not created;
#     a YOLO file missing a label is refused naming it (every label accounted for).
#  And the merge of the intact shards succeeds, with every image annotated.
# Oracle: the file trees before and after (os.walk, byte contents), the messages.
import json
import os
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

SEED = 3


def snapshot(d):
    """{relative path: bytes} of every file under d (links as their target text)."""
    out = {}
    for root, dirs, files in os.walk(d):
        for n in files + [x for x in dirs if os.path.islink(os.path.join(root, x))]:
            p = os.path.join(root, n)
            out[os.path.relpath(p, d)] = os.readlink(p) if os.path.islink(p) else open(p, "rb").read()
        for n in dirs:
            out.setdefault(os.path.relpath(os.path.join(root, n), d) + "/", b"")
    return out


def synth_args(calib, out, shard="0/1"):
    return ["synth", u.DEMO, "--calib", calib, "--count", "4", "-o", out, "--seed", str(SEED), "--camera", "cam1",
            "--size", "64x36", "--vehicles", "3", "--jobs", "1", "--shard", shard]


def refused(args, want, folder_gone=None, folder_same=None):
    before = snapshot(folder_same) if folder_same else None
    p = u.run(args, expect=None)
    if p.returncode != 1 or any(w not in p.stderr for w in want):
        u.fail("%s: exit %d, stderr %r; expected exit 1 naming %s" % (" ".join(args), p.returncode, p.stderr, want),
               SEED)
    if folder_gone and os.path.exists(folder_gone):
        u.fail("%s: %s was created: %s" % (" ".join(args), folder_gone, sorted(snapshot(folder_gone))), SEED)
    if folder_same is not None and snapshot(folder_same) != before:
        u.fail("%s: %s changed" % (" ".join(args), folder_same), SEED)
    print("refused: " + p.stderr.strip().splitlines()[-1][:200])


def main():
    u.need_povray()
    with tempfile.TemporaryDirectory() as tmp:
        calib = u.demo_calib(tmp)
        # 3. a user's folder
        home = os.path.join(tmp, "home")
        os.makedirs(os.path.join(home, "docs"))
        for rel in ("x.tmp.AbC123", "docs/notes.txt", "docs/y.tmp.Zz0001"):
            with open(os.path.join(home, rel), "w") as f:
                f.write("the user's\n")
        refused(synth_args(calib, home), [home, "not empty", ".roadside-dataset"],
                folder_same=home)
        # synth -o SITE: refused before anything is created in the site
        site = os.path.join(tmp, "site")
        shutil.copytree(u.DEMO, site)
        refused(synth_args(calib, site), [site, "not empty"], folder_same=site)

        # a dataset of roadside's: its own temporaries go, the user's stay
        s0, s1 = os.path.join(tmp, "s0"), os.path.join(tmp, "s1")
        u.run(synth_args(calib, s0, "0/2"))
        u.run(synth_args(calib, s1, "1/2"))
        if not os.path.isfile(os.path.join(s0, ".roadside-dataset")):
            u.fail("no .roadside-dataset marker in a new dataset", SEED)
        mine = ["run.json.tmp.Zz9999", "train2017/000000_cam1.png.tmp.Qq1234"]
        users = ["x.tmp.AbC123", "train2017/x.tmp.AbC123", "notes/y.json.tmp.AbC123"]
        os.makedirs(os.path.join(s0, "notes"))
        for rel in mine + users:
            with open(os.path.join(s0, rel), "w") as f:
                f.write("stale\n")
        u.run(synth_args(calib, s0, "0/2"))
        left = [r for r in mine if os.path.exists(os.path.join(s0, r))]
        gone = [r for r in users if not os.path.exists(os.path.join(s0, r))]
        if left or gone:
            u.fail("rerun: own temporaries left %s, user's files removed %s" % (left, gone), SEED)
        for rel in users:
            os.remove(os.path.join(s0, rel))
        os.rmdir(os.path.join(s0, "notes"))
        print("rerun: removed its own temporaries %s, kept the user's %s" % (mine, users))
        # merge into a user's folder: refused, unchanged
        refused(["synth", "merge", s0, s1, "-o", home], [home, "not empty"], folder_same=home)

        # 5. a killed shard: no completion record
        out = os.path.join(tmp, "merged")
        run_json = os.path.join(s1, "run.json")
        good = open(run_json).read()
        rec = json.loads(good)
        if rec.get("finished") != ["1/2"]:
            u.fail("s1/run.json: finished %s, expected [\"1/2\"]" % rec.get("finished"), SEED)
        rec["finished"] = []
        with open(run_json, "w") as f:
            json.dump(rec, f)
        refused(["synth", "merge", s0, s1, "-o", out], [s1, "shard 1/2 did not finish"], folder_gone=out)
        del rec["finished"]  # a dataset made before completion records: the same
        with open(run_json, "w") as f:
            json.dump(rec, f)
        refused(["synth", "merge", s0, s1, "-o", out], ["shard 1/2 did not finish"], folder_gone=out)
        with open(run_json, "w") as f:
            f.write(good)

        # 6. a truncated PNG (its header intact)
        png = os.path.join(s1, "train2017", "000001_cam1.png")
        data = open(png, "rb").read()
        with open(png, "wb") as f:
            f.write(data[:len(data) // 2])
        refused(["synth", "merge", s0, s1, "-o", out], [png, "cut short"], folder_gone=out)
        # a PNG cut short that still ends like one: only decoding tells
        with open(png, "wb") as f:
            f.write(data[:40] + data[-12:])
        refused(["synth", "merge", s0, s1, "-o", out], [png], folder_gone=out)
        with open(png, "wb") as f:
            f.write(data)
        # a label missing from a YOLO file
        coco = json.load(open(os.path.join(s1, "annotations", "instances_train2017.json")))
        counts = {}
        for a in coco["annotations"]:
            counts[a["image_id"]] = counts.get(a["image_id"], 0) + 1
        im = next(im for im in coco["images"] if counts.get(im["id"], 0) > 0)
        lab = os.path.join(s1, "labels", "train2017", os.path.splitext(im["file_name"])[0] + ".txt")
        text = open(lab).read()
        with open(lab, "w") as f:
            f.write("".join(text.splitlines(True)[1:]))
        refused(["synth", "merge", s0, s1, "-o", out], [lab, "labels"], folder_gone=out)
        with open(lab, "w") as f:
            f.write(text)

        # the intact shards merge: every image annotated where it should be
        p = u.run(["synth", "merge", s0, s1, "-o", out])
        print(p.stdout.strip())
        m = json.load(open(os.path.join(out, "run.json")))
        if m.get("finished") != ["0/1"] or not os.path.isfile(os.path.join(out, ".roadside-dataset")):
            u.fail("merged: run.json finished %s, marker %s" % (m.get("finished"),
                                                                os.path.isfile(os.path.join(out, ".roadside-dataset"))))
        listed = set()
        for split in ("train2017", "val2017"):
            path = os.path.join(out, "annotations", "instances_%s.json" % split)
            if os.path.exists(path):
                listed |= {os.path.join(split, im["file_name"]) for im in json.load(open(path))["images"]}
        on_disk = {os.path.join(s, f) for s in ("train2017", "val2017") if os.path.isdir(os.path.join(out, s))
                   for f in os.listdir(os.path.join(out, s))}
        if listed != on_disk or len(listed) != 4:
            u.fail("merged: images %s, annotated %s" % (sorted(on_disk), sorted(listed)), SEED)
        print("merged: 4 images, each listed in its split's COCO file")
    print("test_synth_folder_merge: ok")


if __name__ == "__main__":
    main()

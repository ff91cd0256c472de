#!/usr/bin/python3
# Issue 17, "memory flat over 1,000 images": the COCO assembly of `roadside synth` (and `synth
# merge`) held every image and annotation as cJSON trees, then duplicated them into one document
# and printed it whole: roadside's peak grew by about 0.15 MiB per image (docs/benchmarks.md).
# Now both index the sources (file name, where it lives) and write the file as a stream
# (synth/dataset/rs_synth_dataset_coco.c).
#
# Oracles:
#  - the COCO files equal, value for value (json.load), an independent assembly in Python of
#    the same parts/ files (or merge inputs): sorted by file_name, repeated names dropped (the
#    first kept), images and annotations renumbered 1.. in that order, damaged parts left out;
#  - memory: roadside's peak RSS (os.wait4's ru_maxrss, no timing) assembling 3,000 part files
#    (10 annotations each, copied from a real part) stays within ASSEMBLE_MIB of the same run
#    with its 2 real parts; merging them from 10 shard inputs, within MERGE_MIB of merging the
#    2-image inputs. Before the fix (/tmp/h18s/roadside_before): +534.9 MiB for the run (79.1 ->
#    614.0 MiB) and +528.7 MiB for the merge; after: +9.5 and +32.5 (docs/benchmarks.md).
import copy
import json
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

SEED = 17
COUNT_BIG = 3000      # images of the memory run; its shard 0/1500 renders 2 of them (k = 0, 1500)
ANNS_PER_IMAGE = 10   # in the synthetic parts
ASSEMBLE_MIB = 40.0   # measured +9.5 MiB (before the fix: +534.9 MiB)
MERGE_MIB = 80.0      # measured +32.5 MiB, one 4.4 MiB input's cJSON tree (before: +528.7 MiB)
SHARDS = 10


# Runs argv[1:], prints its exit status and peak RSS: from a fresh small process, since a
# child's ru_maxrss counts what it had before exec, the memory of the process that forked it.
RSS_WRAPPER = """
import os, subprocess, sys
p = subprocess.Popen(sys.argv[1:])
_, status, ru = os.wait4(p.pid, 0)
sys.stderr.write("\\nRSS %d %d\\n" % (os.waitstatus_to_exitcode(status), ru.ru_maxrss))
"""


def roadside_rss(args):
    """Runs roadside; returns (exit status, stdout, stderr, peak RSS in MiB)."""
    p = subprocess.run([sys.executable, "-c", RSS_WRAPPER, u.ROADSIDE] + args, capture_output=True, text=True)
    err, _, last = p.stderr.rstrip("\n").rpartition("\n")
    rc, kib = last.split()[1:]
    return int(rc), p.stdout, err, int(kib) / 1024.0


def synth_args(calib, out, count, extra=()):
    return ["synth", u.DEMO, "--calib", calib, "--count", str(count), "-o", out, "--seed", str(SEED),
            "--camera", "cam1", "--size", "64x36", "--vehicles", "6"] + list(extra)


def assemble(docs):
    """The oracle: COCO documents (in order) -> one, as docs/labels.md says synth assembles."""
    entries = []
    header = {}
    for doc in docs:
        for key in ("info", "licenses", "categories"):
            if key not in header and key in doc:
                header[key] = doc[key]
        for im in doc["images"]:
            anns = [a for a in doc["annotations"] if a["image_id"] == im["id"]]
            entries.append((im["file_name"], im, anns))
    entries.sort(key=lambda e: e[0])  # stable: the first of a repeated name is kept
    out = {}
    for key in ("info", "licenses"):
        if key in header:
            out[key] = header[key]
    out["images"], out["annotations"] = [], []
    seen = set()
    for name, im, anns in entries:
        if name in seen:
            continue
        seen.add(name)
        im = dict(im, id=len(out["images"]) + 1)
        out["images"].append(im)
        for a in anns:
            out["annotations"].append(dict(a, id=len(out["annotations"]) + 1, image_id=im["id"]))
    out["categories"] = header.get("categories", [])
    return out


def load_parts(ds, split, skip=()):
    """The parts/ files of DS whose image is in DS/<split>, in k order; those in skip left out."""
    docs = []
    for name in sorted(os.listdir(os.path.join(ds, "parts"))):
        if name in skip:
            continue
        doc = json.load(open(os.path.join(ds, "parts", name)))
        if os.path.isfile(os.path.join(ds, split, doc["images"][0]["file_name"])):
            docs.append(doc)
    return docs


def same(path, want, what):
    have = json.load(open(path))
    if have == want:
        return
    for key in want:
        if have.get(key) != want[key]:
            items = have.get(key)
            n = len(items) if isinstance(items, list) else None
            i = next((i for i in range(min(n or 0, len(want[key]))) if items[i] != want[key][i]), None)
            u.fail("%s: %s differs from the oracle's (%s items vs %d; first difference at %s: %s vs %s)"
                   % (what, key, n, len(want[key]), i, items[i] if i is not None else "",
                      want[key][i] if i is not None else ""), SEED)
    u.fail("%s: members differ: %s vs %s" % (what, sorted(have), sorted(want)), SEED)


def link_image_files(src, dst, k, split="train2017"):
    """Hard-links image k's files (cam1) from dataset src into dataset dst."""
    stem = "%06d_cam1" % k
    rels = ["%s/%s.png" % (split, stem), "images/%s/%s.png" % (split, stem),
            "labels/%s/%s.txt" % (split, stem), "kitti/training/image_2/%06d.png" % k,
            "kitti/training/label_2/%06d.txt" % k, "kitti/training/calib/%06d.txt" % k]
    for rel in rels:
        d = os.path.join(dst, rel)
        os.makedirs(os.path.dirname(d), exist_ok=True)
        if not os.path.exists(d):
            os.link(os.path.join(src, rel), d)


def fill_parts(ds, count, real):
    """Writes the part files (and hard-links the image files) of every k < count but `real`,
    copies of image 0's: its image object renamed, ANNS_PER_IMAGE of its annotations."""
    src = json.load(open(os.path.join(ds, "parts", "000000_cam1.json")))
    if not src["annotations"]:
        u.fail("image 0 of the memory run has no annotation to copy", SEED)
    for k in range(count):
        if k in real:
            continue
        stem = "%06d_cam1" % k
        for rel in ["train2017/%s.png", "images/train2017/%s.png"]:
            os.link(os.path.join(ds, rel % "000000_cam1"), os.path.join(ds, rel % stem))
        # one YOLO line per annotation of the copy (merge accounts for every label)
        with open(os.path.join(ds, "labels", "train2017", "000000_cam1.txt")) as f:
            lines = f.read().splitlines()
        with open(os.path.join(ds, "labels", "train2017", stem + ".txt"), "w") as f:
            f.write("".join(lines[j % len(lines)] + "\n" for j in range(ANNS_PER_IMAGE)))
        for rel in ["kitti/training/image_2/%s.png", "kitti/training/label_2/%s.txt",
                    "kitti/training/calib/%s.txt"]:
            os.link(os.path.join(ds, rel % "000000"), os.path.join(ds, rel % ("%06d" % k)))
        doc = copy.deepcopy(src)
        doc["images"][0].update(file_name=stem + ".png", index=k)
        doc["annotations"] = []
        for j in range(ANNS_PER_IMAGE):
            a = copy.deepcopy(src["annotations"][j % len(src["annotations"])])
            a.update(id=j + 1, vehicle_index=j)
            # values that differ per image, at 15 significant digits: cJSON prints a number
            # with 15 when that reads back within 1 ulp (print_number), so a value it wrote
            # reads back as written, and so must ours
            a["bbox"][0] = float("%.15g" % (a["bbox"][0] + 0.001 * k))
            doc["annotations"].append(a)
        with open(os.path.join(ds, "parts", stem + ".json"), "w") as f:
            json.dump(doc, f, separators=(",", ":"))


def make_shard_input(big, dst, i, n, docs, extra_k=None):
    """A merge input: shard i/n of `big` (run.json), the images k = i mod n of the oracle's
    assembled docs, their files hard-linked; extra_k: one more image (another shard's) listed."""
    os.makedirs(os.path.join(dst, "annotations"))
    run = json.load(open(os.path.join(big, "run.json")))
    run["shards"] = ["%d/%d" % (i, n)]
    run["finished"] = ["%d/%d" % (i, n)]  # its completion record (merge refuses a shard without)
    json.dump(run, open(os.path.join(dst, "run.json"), "w"))
    shutil.copytree(os.path.join(big, "cameras"), os.path.join(dst, "cameras"))
    mine = [d for d in docs if d["images"][0]["index"] % n == i or d["images"][0]["index"] == extra_k]
    coco = assemble(mine)
    if extra_k is not None:  # listed last, with one annotation less: the merge keeps input 0's
        coco["images"].sort(key=lambda im: im["index"] == extra_k)
        drop = [a for a in coco["annotations"] if a["image_id"] == coco["images"][-1]["id"]]
        coco["annotations"].remove(drop[0])
    for im in coco["images"]:
        link_image_files(big, dst, im["index"])
    if extra_k is not None:  # its YOLO file a line shorter too (merge accounts for every label)
        yolo = os.path.join(dst, "labels", "train2017", "%06d_cam1.txt" % extra_k)
        with open(yolo) as f:
            lines = f.read().splitlines()
        os.remove(yolo)  # (a hard link to the run's own file)
        with open(yolo, "w") as f:
            f.write("".join(line + "\n" for line in lines[1:]))
    with open(os.path.join(dst, "annotations", "instances_train2017.json"), "w") as f:
        json.dump(coco, f, separators=(",", ":"))
    return coco


def main():
    u.need_povray()
    with tempfile.TemporaryDirectory() as tmp:
        calib = u.demo_calib(tmp)

        # 1. a small run, two shards in two folders with a validation split, and their merge:
        # each assembled COCO file against the oracle's assembly of its parts
        shards = []
        for i in range(2):
            ds = os.path.join(tmp, "shard%d" % i)
            p = u.run(synth_args(calib, ds, 6, ["--shard", "%d/2" % i, "--val-fraction", "0.5"]))
            shards.append(ds)
            for split in ("train2017", "val2017"):
                path = os.path.join(ds, "annotations", "instances_%s.json" % split)
                if os.path.exists(path):
                    same(path, assemble(load_parts(ds, split)), "shard %d/2, %s" % (i, split))
        merged = os.path.join(tmp, "merged")
        u.run(["synth", "merge"] + shards + ["-o", merged])
        nsplit = 0
        for split in ("train2017", "val2017"):
            inputs = [os.path.join(s, "annotations", "instances_%s.json" % split) for s in shards]
            docs = [json.load(open(p)) for p in inputs if os.path.exists(p)]
            if docs:
                nsplit += 1
                same(os.path.join(merged, "annotations", "instances_%s.json" % split), assemble(docs),
                     "merge of the two shards, %s" % split)
        if nsplit != 2:
            u.fail("the small run made %d splits, expected train2017 and val2017" % nsplit, SEED)

        # 2. memory of the run's assembly: 3,000 parts (2 rendered, 2,998 copies, 2 damaged)
        big = os.path.join(tmp, "big")
        args = synth_args(calib, big, COUNT_BIG, ["--shard", "0/1500", "--val-fraction", "0"])
        u.run(args)
        rc, _, err, rss_2 = roadside_rss(args)  # the resume assembling 2 parts
        if rc != 0:
            u.fail("resume of the 2-image run: exit %d: %s" % (rc, err), SEED)
        fill_parts(big, COUNT_BIG, real={0, 1500})
        cut = os.path.join(big, "parts", "000007_cam1.json")
        text = open(cut).read()
        open(cut, "w").write(text[: len(text) // 2])  # cut short: left out, named
        gone = os.path.join(big, "train2017", "000009_cam1.png")
        os.remove(gone)  # its image missing: left out, named
        rc, out, err, rss_3000 = roadside_rss(args)
        print("assembly: peak RSS %.1f MiB with 2 parts, %.1f MiB with %d (+%.1f MiB; bound +%.0f)"
              % (rss_2, rss_3000, COUNT_BIG, rss_3000 - rss_2, ASSEMBLE_MIB))
        if rc != 0:
            u.fail("resume of the %d-part run: exit %d: %s" % (COUNT_BIG, rc, err), SEED)
        for path in (cut, gone):
            if path not in out + err:
                u.fail("the notices do not name %s:\n%s%s" % (path, out, err), SEED)
        docs = load_parts(big, "train2017", skip={"000007_cam1.json"})
        want = assemble(docs)
        if len(want["images"]) != COUNT_BIG - 2:
            u.fail("the oracle holds %d images, expected %d" % (len(want["images"]), COUNT_BIG - 2))
        same(os.path.join(big, "annotations", "instances_train2017.json"), want, "the 3,000-part run")
        train = open(os.path.join(big, "kitti", "ImageSets", "train.txt")).read().split()
        if train != ["%06d" % im["index"] for im in want["images"]]:
            u.fail("kitti/ImageSets/train.txt does not list the assembled images in order", SEED)
        if u.sanitized():
            print("memory bounds not checked: roadside is built with AddressSanitizer (its quarantine "
                  "keeps freed memory resident)")
        elif rss_3000 - rss_2 > ASSEMBLE_MIB:
            u.fail("assembling %d parts took %.1f MiB more than 2 (bound %.0f MiB)"
                   % (COUNT_BIG, rss_3000 - rss_2, ASSEMBLE_MIB), SEED)

        # 3. memory of merge: the run's 2,998 images from 10 shard inputs (input 1 also lists
        # image 0, with one annotation less: dropped as a repeat), against merging 2 images
        ins, coco_in = [], []
        for i in range(SHARDS):
            d = os.path.join(tmp, "in%d" % i)
            coco_in.append(make_shard_input(big, d, i, SHARDS, docs, extra_k=0 if i == 1 else None))
            ins.append(d)
        small_docs = [d for d in docs if d["images"][0]["index"] in (0, 1)]
        small = []
        for i in range(2):
            d = os.path.join(tmp, "small%d" % i)
            make_shard_input(big, d, i, 2, small_docs)
            small.append(d)
        rc, _, err, rss_small = roadside_rss(["synth", "merge"] + small + ["-o", os.path.join(tmp, "m2")])
        if rc != 0:
            u.fail("merge of 2 images: exit %d: %s" % (rc, err), SEED)
        m = os.path.join(tmp, "m3000")
        rc, out, err, rss_merge = roadside_rss(["synth", "merge"] + ins + ["-o", m])
        largest = max(os.path.getsize(os.path.join(d, "annotations", "instances_train2017.json")) for d in ins)
        print("merge: peak RSS %.1f MiB for 2 images, %.1f MiB for %d inputs of %d images (+%.1f MiB; "
              "largest input %.1f MiB; bound +%.0f)" % (rss_small, rss_merge, SHARDS, COUNT_BIG - 2,
                                                        rss_merge - rss_small, largest / 2**20, MERGE_MIB))
        if rc != 0:
            u.fail("merge of %d inputs: exit %d: %s" % (SHARDS, rc, err), SEED)
        want_m = assemble(coco_in)
        if len(want_m["images"]) != COUNT_BIG - 2:
            u.fail("the merge oracle holds %d images" % len(want_m["images"]))
        same(os.path.join(m, "annotations", "instances_train2017.json"), want_m, "merge of %d inputs" % SHARDS)
        if rss_merge - rss_small > MERGE_MIB and not u.sanitized():
            u.fail("merging %d images took %.1f MiB more than 2 (bound %.0f MiB)"
                   % (COUNT_BIG - 2, rss_merge - rss_small, MERGE_MIB), SEED)

        # 4. bad input: a merge input's COCO file cut short is named; OUT gets no COCO file
        bad = os.path.join(ins[3], "annotations", "instances_train2017.json")
        text = open(bad).read()
        open(bad, "w").write(text[: len(text) // 2])
        m_bad = os.path.join(tmp, "m_bad")
        p = u.run(["synth", "merge"] + ins + ["-o", m_bad], expect=1)
        if bad not in p.stderr:
            u.fail("merge of a damaged input: the message does not name %s: %s" % (bad, p.stderr), SEED)
        left = [n for n in os.listdir(os.path.join(m_bad, "annotations"))] \
            if os.path.isdir(os.path.join(m_bad, "annotations")) else []
        if left:
            u.fail("merge of a damaged input left %s in %s/annotations" % (left, m_bad), SEED)
    print("ok")


if __name__ == "__main__":
    main()

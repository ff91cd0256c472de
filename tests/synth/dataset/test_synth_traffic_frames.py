#!/usr/bin/python3
# Issue 17, "traffic through the junction": `roadside synth --traffic-frames DIR` takes each
# image's vehicles from one frame of a real SUMO run (`roadside traffic --sumo`, Debian's sumo
# and netconvert, on the demo site), rendered by the real POV-Ray (6 images of 160x90).
#  - oracle: the frames' own files. Image k's frame is recomputed here from the documented draw
#    (docs/synth.md: draw 2 of k's splitmix64 stream, mod the number of frames; splitmix64
#    written out below, not roadside's); every label's vehicle_id is a vehicle of THAT frame, its
#    bottom_center_enu_m is that vehicle's (e, n) and its box3d its (length, width, height,
#    yaw_deg) within 1e-9 (the label path copies the numbers: cJSON prints doubles so that they
#    read back exactly, so the expected difference is 0), on the site's ground plane (recorded
#    per image) within 1e-9 m; its category is the vehicle's class; no image has more labels
#    than --vehicles 3, and some image reaches 3 (the cap is exercised);
#  - run.json records the frames' count, vehicles and the SHA-256 of `sha256sum frames.json
#    FILE...` (hashlib);
#  - shards 0/2 and 1/2 (with --jobs 2) give the same per-image COCO, YOLO and KITTI files,
#    byte for byte, as one run, and merge into the same annotations;
#  - merge refuses a shard made with the built-in traffic next to one made with the frames,
#    naming traffic_frames, and a rerun into the frames dataset with the built-in traffic is
#    refused;
#  - every COCO image names its frame: "traffic_frame" {"file", "time_s", "index"} equals the
#    oracle's frame's frames.json entry (time_s within 1e-9); images of the built-in traffic
#    carry none;
#  - bad input: no frames.json, a frames.json or a frame file that does not parse (one JSON
#    error path, core/rs_json.h: "FILE:LINE: JSON syntax error ..."), an empty frames.json:
#    exit 1, a message naming the file (and line or field), no dataset folder created.
# Exit 77 without povray, sumo or netconvert.
import hashlib
import json
import os
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

SEED = 7
COUNT = 6
MAXV = 3
TOL = 1e-9
M64 = (1 << 64) - 1
GOLDEN = 0x9E3779B97F4A7C15


def mix64(z):
    """splitmix64's output function (Steele, Lea, Flood, OOPSLA 2014)."""
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & M64
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & M64
    return z ^ (z >> 31)


def frame_of(seed, k, nframes):
    """The frame of image k: its stream starts at mix64(seed + G (k + 1)); draw j is
    mix64(start + j G); the frame is draw 2 mod the number of frames."""
    start = mix64((seed + GOLDEN * (k + 1)) & M64)
    return mix64((start + 2 * GOLDEN) & M64) % nframes


def synth(out, frames, extra=(), expect=0):
    args = ["synth", "--val-fraction", "0", u.DEMO, "--calib", CALIB, "--count", str(COUNT), "-o", out, "--seed", str(SEED),
            "--size", "160x90", "--vehicles", str(MAXV)]
    if frames:
        args += ["--traffic-frames", frames]
    return u.run(args + list(extra), expect=expect)


def label_files(ds):
    """{relative path: bytes} of every per-image label file: parts/ (COCO), YOLO, KITTI."""
    out = {}
    for sub in ("parts", os.path.join("labels", "train2017"), os.path.join("kitti", "training", "label_2")):
        d = os.path.join(ds, sub)
        for name in sorted(os.listdir(d)):
            out[os.path.join(sub, name)] = open(os.path.join(d, name), "rb").read()
    return out


def check_labels(ds, fr_dir):
    index = json.load(open(os.path.join(fr_dir, "frames.json")))
    frames = [json.load(open(os.path.join(fr_dir, e["file"]))) for e in index]
    coco = json.load(open(os.path.join(ds, "annotations", "instances_train2017.json")))
    cat = {c["id"]: c["name"] for c in coco["categories"]}
    per_image = {im["id"]: [] for im in coco["images"]}
    for a in coco["annotations"]:
        per_image[a["image_id"]].append(a)
    if len(coco["images"]) != COUNT:
        u.fail("%d images, expected %d" % (len(coco["images"]), COUNT), SEED)
    worst_en = worst_up = worst_box = 0.0
    used, counts = set(), []
    for im in coco["images"]:
        k = im["index"]
        f = frame_of(SEED, k, len(frames))
        used.add(f)
        by_id = {v["id"]: v for v in frames[f]}
        anns = per_image[im["id"]]
        counts.append(len(anns))
        if len(anns) > MAXV:
            u.fail("image %d: %d labels, more than --vehicles %d" % (k, len(anns), MAXV), SEED)
        # the image names its frame (docs/labels.md "traffic_frame"): the oracle's choice
        tf = im.get("traffic_frame")
        if (not isinstance(tf, dict) or tf.get("index") != f or tf.get("file") != index[f]["file"]
                or not abs(tf.get("time_s", float("nan")) - index[f]["time_s"]) <= TOL):
            u.fail("image %d: traffic_frame %s, expected frame %d (%s, time_s %s)"
                   % (k, tf, f, index[f]["file"], index[f]["time_s"]), SEED)
        cal = im["calibration"]
        nrm, off = cal["ground_normal_enu"], cal["ground_offset_m"]
        for a in anns:
            v = by_id.get(a.get("vehicle_id"))
            if v is None:
                u.fail("image %d: label %s is not a vehicle of frame %d (%s)"
                       % (k, a.get("vehicle_id"), f, index[f]["file"]), SEED)
            p = a["bottom_center_enu_m"]
            d_en = max(abs(p[0] - v["e"]), abs(p[1] - v["n"]))
            d_up = abs(sum(nrm[i] * p[i] for i in range(3)) - off)
            b = a["box3d"]
            d_box = max(abs(b["dimensions_m"][0] - v["length"]), abs(b["dimensions_m"][1] - v["width"]),
                        abs(b["dimensions_m"][2] - v["height"]), abs(b["yaw_deg"] - v["yaw_deg"]))
            if not (d_en <= TOL and d_up <= TOL and d_box <= TOL):
                u.fail("image %d, %s: bottom centre %s, frame %s has (%.6f, %.6f): off by %.3g m; "
                       "ground %.3g m; box %.3g" % (k, v["id"], p, index[f]["file"], v["e"], v["n"], d_en,
                                                      d_up, d_box), SEED)
            if cat[a["category_id"]] != v["class"]:
                u.fail("image %d, %s: category %s, the frame says %s"
                       % (k, v["id"], cat[a["category_id"]], v["class"]), SEED)
            worst_en, worst_up, worst_box = max(worst_en, d_en), max(worst_up, d_up), max(worst_box, d_box)
    if sum(counts) < COUNT or max(counts) != MAXV:
        u.fail("labels per image %s: expected some, and the cap %d reached" % (counts, MAXV), SEED)
    print("traffic_frame: every image names the frame the oracle picks (file, time_s, index)")
    print("labels: %d over %d images (per image %s, cap %d), from %d of %d frames; max |bottom centre - "
          "frame (e, n)| %.3g m, max ground-plane residual %.3g m, max box/yaw difference %.3g"
          % (sum(counts), COUNT, counts, MAXV, len(used), len(frames), worst_en, worst_up, worst_box))
    return index


def check_run_record(ds, fr_dir, index):
    run = json.load(open(os.path.join(ds, "run.json")))["run"]
    tf = run.get("traffic_frames")
    manifest = "".join("%s  %s\n" % (hashlib.sha256(open(os.path.join(fr_dir, n), "rb").read()).hexdigest(), n)
                       for n in ["frames.json"] + [e["file"] for e in index])
    want = {"frames": len(index), "vehicles": sum(e["vehicles"] for e in index),
            "sha256": hashlib.sha256(manifest.encode()).hexdigest()}
    if tf != want:
        u.fail("run.json traffic_frames %s, expected %s" % (tf, want), SEED)
    print("run.json: traffic_frames %s (hashlib agrees)" % json.dumps(tf))


def bad_input(tmp, fr_dir):
    cases = []
    empty = os.path.join(tmp, "no_index")
    os.makedirs(empty)
    cases.append((empty, os.path.join(empty, "frames.json") + ": missing"))
    broken = os.path.join(tmp, "broken")
    shutil.copytree(fr_dir, broken)
    name = json.load(open(os.path.join(broken, "frames.json")))[1]["file"]
    with open(os.path.join(broken, name), "w") as f:
        f.write('[{"id": "a", "class": "sedan",\n "e": 1, "n": oops}]\n')
    cases.append((broken, os.path.join(broken, name) + ":2: JSON syntax error"))
    bad_index = os.path.join(tmp, "bad_index")  # frames.json itself does not parse
    shutil.copytree(fr_dir, bad_index)
    with open(os.path.join(bad_index, "frames.json"), "w") as f:
        f.write('[{"file": "frame_000000.json",\n "time_s": 60, "vehicles": }]\n')
    cases.append((bad_index, os.path.join(bad_index, "frames.json") + ":2: JSON syntax error"))
    zero = os.path.join(tmp, "zero")
    os.makedirs(zero)
    with open(os.path.join(zero, "frames.json"), "w") as f:
        f.write("[]\n")
    cases.append((zero, os.path.join(zero, "frames.json") + ": no frames"))
    nofield = os.path.join(tmp, "nofield")
    shutil.copytree(fr_dir, nofield)
    vs = json.load(open(os.path.join(nofield, name)))
    del vs[0]["height"]
    json.dump(vs, open(os.path.join(nofield, name), "w"))
    cases.append((nofield, os.path.join(nofield, name) + ": [0].height: missing"))
    for i, (d, want) in enumerate(cases):
        out = os.path.join(tmp, "bad%d" % i)
        p = synth(out, d, expect=None)
        if p.returncode != 1 or want not in p.stderr or os.path.exists(out):
            u.fail("bad input %s: exit %d, stderr %r, %s; expected exit 1 naming %r and no folder"
                   % (d, p.returncode, p.stderr.strip(), "folder made" if os.path.exists(out) else "no folder",
                      want))
        print("bad input: exit 1: " + p.stderr.strip())


def main():
    global CALIB
    u.need_povray()
    u.need_sumo()
    with tempfile.TemporaryDirectory() as tmp:
        CALIB = u.demo_truth_calib_all(tmp)
        fr = os.path.join(tmp, "frames")
        p = u.run(["traffic", u.DEMO, "--sumo", "--seed", "3", "--duration", "90", "--warmup", "60",
                   "--period", "5", "-o", fr])
        print(p.stdout.strip())
        bad_input(tmp, fr)

        full = os.path.join(tmp, "full")
        print(synth(full, fr, ["--jobs", "1"]).stdout.splitlines()[0])
        index = check_labels(full, fr)
        check_run_record(full, fr, index)

        # a rerun into the same folder with the built-in traffic: refused, the folder kept
        p = synth(full, None, ["--jobs", "1"], expect=None)
        if p.returncode != 1 or "holds the images of another run" not in p.stderr:
            u.fail("rerun with the built-in traffic into a frames dataset: exit %d, %r"
                   % (p.returncode, p.stderr.strip()), SEED)
        print("rerun with the built-in traffic: exit 1: " + p.stderr.strip())

        # another shard split, with workers: the same label files
        s0, s1 = os.path.join(tmp, "s0"), os.path.join(tmp, "s1")
        synth(s0, fr, ["--shard", "0/2", "--jobs", "2"])
        synth(s1, fr, ["--shard", "1/2", "--jobs", "2"])
        one, split = label_files(full), label_files(s0)
        split.update(label_files(s1))
        if one != split:
            diff = sorted(set(one) ^ set(split)) or [n for n in one if one[n] != split[n]]
            u.fail("shards 0/2 + 1/2 differ from one run: %s" % diff[:5], SEED)
        merged = os.path.join(tmp, "merged")
        u.run(["synth", "merge", s0, s1, "-o", merged])
        a = json.load(open(os.path.join(full, "annotations", "instances_train2017.json")))
        b = json.load(open(os.path.join(merged, "annotations", "instances_train2017.json")))
        if a["annotations"] != b["annotations"] or a["images"] != b["images"]:
            u.fail("merged shards' COCO file differs from one run's", SEED)
        print("shards 0/2 + 1/2 (--jobs 2): %d label files byte-identical to one run; merged COCO equal"
              % len(one))

        # the built-in traffic's shard 1/2 next to the frames' shard 0/2: refused
        builtin = os.path.join(tmp, "builtin")
        synth(builtin, None, ["--shard", "1/2", "--jobs", "2"])
        bi = json.load(open(os.path.join(builtin, "annotations", "instances_train2017.json")))
        if not bi["images"] or any("traffic_frame" in im for im in bi["images"]):
            u.fail("built-in traffic: images should carry no traffic_frame", SEED)
        p = u.run(["synth", "merge", s0, builtin, "-o", os.path.join(tmp, "m_bad")], expect=None)
        if p.returncode != 1 or "traffic_frames" not in p.stderr:
            u.fail("merge of frames and built-in shards: exit %d, %r" % (p.returncode, p.stderr.strip()), SEED)
        print("refused: " + p.stderr.strip())
    print("OK")


if __name__ == "__main__":
    main()

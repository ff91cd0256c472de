#!/usr/bin/python3
# Issue 39: `roadside synth --sequence --labels-only` on a real SUMO run of the demo site
# (`roadside traffic --sumo --period 0.1 --no-randomise`, Debian's sumo and netconvert), the four
# demo cameras (their true models), frames 5..24 at 480x270 (80 images, no POV-Ray).
#  - the frames: 0.1 s apart (SUMO steps by the period), each vehicle id moving at most
#    speed x 0.1 s + 0.5 m between consecutive frames (ids stay with their vehicles);
#  - image k is frame 5 + k // 4 seen by camera k % 4: its COCO "camera" and "traffic_frame"
#    {file, time_s, index} say so (oracle: frames.json);
#  - labels only: no PNG, YOLO or KITTI file; parts/ and annotations/ present;
#  - every vehicle id keeps its class and box3d dimensions in every image (one vehicle, one look);
#  - tracks_gt.csv: its exact header; per frame one row per vehicle of the frame's file, in file
#    order, at the frame's time (1e-6 s); e_m, n_m equal to the vehicle's e, n and to every
#    label's bottom_center_enu_m of that vehicle at that time within 1e-9 m; speed_mps SUMO's;
#    heading_deg in [0, 360) and the vehicle's yaw mod 360; cameras = exactly the cameras whose
#    image of that frame has a label of that vehicle (so every label's vehicle is there, with
#    its camera);
#  - resume: a rerun makes nothing, one removed part file is remade, tracks_gt.csv unchanged;
#  - bad input: --sequence without --traffic-frames or with --count, --frames without
#    --sequence or empty, --labels-only without --sequence, frames past the end: exit 2
#    naming frames.json; no dataset written by any of them.
# Exit 77 without sumo or netconvert.
import csv
import glob
import json
import math
import os
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

CAMS = ["cam1", "cam2", "cam3", "cam4"]
FIRST, END = 5, 25
TOL = 1e-9


def main():
    u.need_sumo()
    with tempfile.TemporaryDirectory() as tmp:
        calib = u.demo_truth_calib_all(tmp, CAMS)
        frames = os.path.join(tmp, "frames")
        u.run(["traffic", u.DEMO, "--sumo", "--seed", "3", "--period", "0.1", "--duration", "63", "--warmup", "60",
               "--no-randomise", "-o", frames])
        with open(os.path.join(frames, "frames.json")) as f:
            index = json.load(f)
        vehicles = []
        for e in index:
            with open(os.path.join(frames, e["file"])) as f:
                vehicles.append(json.load(f))
        for a, b, ea, eb in zip(vehicles, vehicles[1:], index, index[1:]):
            if abs(eb["time_s"] - ea["time_s"] - 0.1) > 1e-6:
                u.fail(f"frames {ea['file']}, {eb['file']}: {eb['time_s'] - ea['time_s']} s apart, not 0.1 s")
            va = {v["id"]: v for v in a}
            for v in b:
                if v["id"] in va:
                    w = va[v["id"]]
                    step = math.hypot(v["e"] - w["e"], v["n"] - w["n"])
                    if step > 0.1 * max(v["speed_mps"], w["speed_mps"]) + 0.5:
                        u.fail(f"{eb['file']}: vehicle {v['id']} jumped {step:.2f} m in 0.1 s")

        ds = os.path.join(tmp, "ds")
        u.run(["synth", "--val-fraction", "0", u.DEMO, "--calib", calib, "--traffic-frames", frames, "--sequence", "--labels-only",
               "--frames", f"{FIRST}:{END}", "--size", "480x270", "--jobs", "2", "--seed", "11", "-o", ds])
        if glob.glob(os.path.join(ds, "**", "*.png"), recursive=True) or \
                glob.glob(os.path.join(ds, "labels", "**", "*.txt"), recursive=True):
            u.fail("--labels-only wrote image or YOLO files")
        with open(os.path.join(ds, "annotations", "instances_train2017.json")) as f:
            coco = json.load(f)
        images = {im["id"]: im for im in coco["images"]}
        if len(images) != (END - FIRST) * len(CAMS):
            u.fail(f"{len(images)} images, expected {(END - FIRST) * len(CAMS)}")
        labels = {}  # (frame index, camera) -> {vehicle_id: annotation}
        for im in images.values():
            k = im["index"]
            fi = FIRST + k // len(CAMS)
            tf = im.get("traffic_frame") or {}
            if im["camera"] != CAMS[k % len(CAMS)] or tf.get("index") != fi or tf.get("file") != index[fi]["file"] \
                    or abs(tf.get("time_s", -1) - index[fi]["time_s"]) > 1e-9:
                u.fail(f"image {k}: camera {im['camera']}, traffic_frame {tf}; expected {CAMS[k % len(CAMS)]}, "
                       f"{index[fi]}")
            labels[(fi, im["camera"])] = {}
        looks = {}
        for a in coco["annotations"]:
            im = images[a["image_id"]]
            key = (im["traffic_frame"]["index"], im["camera"])
            labels[key][a["vehicle_id"]] = a
            look = (a["category_id"], tuple(a["box3d"]["dimensions_m"]))
            if looks.setdefault(a["vehicle_id"], look) != look:
                u.fail(f"vehicle {a['vehicle_id']}: class and size {look}, elsewhere {looks[a['vehicle_id']]}")
        if len(coco["annotations"]) < 20:
            u.fail(f"only {len(coco['annotations'])} labels in 80 images: the sequence sees too little to test")

        with open(os.path.join(ds, "tracks_gt.csv")) as f:
            header = f.readline().strip()
            rows = list(csv.DictReader(f, fieldnames=header.split(",")))
        if header != "time_s,vehicle_id,class,e_m,n_m,speed_mps,heading_deg,cameras":
            u.fail(f"tracks_gt.csv: header {header!r}")
        expected = [(fi, v) for fi in range(FIRST, END) for v in vehicles[fi]]
        if len(rows) != len(expected):
            u.fail(f"tracks_gt.csv: {len(rows)} rows, the frames hold {len(expected)} vehicles")
        listed = 0
        for r, (fi, v) in zip(rows, expected):
            where = f"tracks_gt.csv, frame {fi}, vehicle {v['id']}"
            if r["vehicle_id"] != v["id"] or abs(float(r["time_s"]) - index[fi]["time_s"]) > 1e-6:
                u.fail(f"{where}: row {r}")
            e, n = float(r["e_m"]), float(r["n_m"])
            if abs(e - v["e"]) > TOL or abs(n - v["n"]) > TOL or abs(float(r["speed_mps"]) - v["speed_mps"]) > 1e-4:
                u.fail(f"{where}: e, n, speed {e}, {n}, {r['speed_mps']}; the frame says {v}")
            h = float(r["heading_deg"])
            dh = (h - v["yaw_deg"]) % 360
            if not (0 <= h < 360) or min(dh, 360 - dh) > 1e-6:
                u.fail(f"{where}: heading {h}, yaw {v['yaw_deg']}")
            cams = set(r["cameras"].split("+")) if r["cameras"] else set()
            for c in CAMS:
                a = labels[(fi, c)].get(v["id"])
                if (a is not None) != (c in cams):
                    u.fail(f"{where}: cameras {sorted(cams)}, but {c} {'has' if a else 'has no'} label of it")
                if a is not None:
                    bc = a["bottom_center_enu_m"]
                    if abs(bc[0] - e) > TOL or abs(bc[1] - n) > TOL:
                        u.fail(f"{where}: {c}'s label's bottom_center_enu_m {bc}, tracks_gt {e}, {n}")
                    listed += 1
        if listed != len(coco["annotations"]):
            u.fail(f"tracks_gt.csv lists {listed} (vehicle, camera) pairs, the labels are {len(coco['annotations'])}")

        # resume: a rerun skips every image (the part files alone are checked); with one part file
        # removed it remakes that image; tracks_gt.csv stays byte for byte the same
        with open(os.path.join(ds, "tracks_gt.csv"), "rb") as f:
            before = f.read()
        args = ["synth", "--val-fraction", "0", u.DEMO, "--calib", calib, "--traffic-frames", frames, "--sequence", "--labels-only",
                "--frames", f"{FIRST}:{END}", "--size", "480x270", "--jobs", "2", "--seed", "11", "-o", ds]
        p = u.run(args)
        if "(0 made, 80 already done" not in p.stdout:
            u.fail(f"rerun: {p.stdout.splitlines()[0]}")
        os.remove(os.path.join(ds, "parts", "000013_cam2.json"))
        p = u.run(args)
        with open(os.path.join(ds, "tracks_gt.csv"), "rb") as f:
            after = f.read()
        if "(1 made, 79 already done" not in p.stdout or after != before:
            u.fail(f"rerun after removing a part: {p.stdout.splitlines()[0]}; tracks_gt.csv the same: {after == before}")

        # bad input: usage errors and frames past the end (2), nothing written
        bad = os.path.join(tmp, "bad")
        base = ["synth", "--val-fraction", "0", u.DEMO, "--calib", calib, "-o", bad]
        for extra, what in [(["--sequence"], "--traffic-frames"),
                            (["--sequence", "--traffic-frames", frames, "--count", "4"], "--count"),
                            (["--traffic-frames", frames, "--count", "4", "--frames", "0:2"], "--sequence"),
                            (["--traffic-frames", frames, "--count", "4", "--labels-only"], "--sequence"),
                            (["--sequence", "--traffic-frames", frames, "--frames", "3:3"], "--frames")]:
            p = u.run(base + extra, expect=2)
            if what not in p.stderr:
                u.fail(f"synth {' '.join(extra)}: stderr {p.stderr!r} does not name {what}")
        p = u.run(base + ["--sequence", "--labels-only", "--traffic-frames", frames, "--frames", "0:100000"], expect=2)
        if "frames.json" not in p.stderr:
            u.fail(f"frames past the end: stderr {p.stderr!r} does not name frames.json")
        if os.path.exists(os.path.join(bad, "tracks_gt.csv")) or os.path.exists(os.path.join(bad, "annotations")):
            u.fail("a refused run wrote a dataset")
    print(f"sequence of {END - FIRST} frames x {len(CAMS)} cameras: {len(coco['annotations'])} labels, "
          f"{len(rows)} ground-truth rows, all consistent")


if __name__ == "__main__":
    main()

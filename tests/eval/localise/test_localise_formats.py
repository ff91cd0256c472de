#!/usr/bin/env python3
"""`roadside localise --site --calib --camera`: the three input formats, the point choices, the
three output formats and bad input.

Site: `roadside site simulate --seed SEED --cameras 1`, calibrated by `roadside calib`. Boxes
drawn at random (numpy, seed SEED) over the lower image.
Checks:
  - the same boxes as COCO results JSON, MOT Challenge CSV (1-based frames and pixel corner) and
    a folder of Ultralytics txt (normalised, YOLO's corner origin: docs/labels.md) give the same
    rows: integers and camera identical, numbers within 1e-9 (relative; the normalisation's
    rounding);
  - --point center / bottom / shift (and --shift 0.2) write the hand-computed pixel
    (x + w/2, y + h/2), (x + w/2, y + h), (x + w/2, y + h/2 + K h) as u_px, v_px (1e-9 px); a
    COCO bottom_center wins over --point; MOT and Ultralytics default to bottom, COCO to center;
  - ground point: mrcal's Python unproject + plane intersection to 1e-6 m on every row;
    lat_deg, lon_deg from the site's origin agree with PROJ's cct (1e-9 deg) where cct exists;
  - .jsonl and .geojson hold the same values as the .csv;
  - a pixel above the horizon is not written and its count is printed;
  - bad input (a missing field, NaN in COCO (Python's bare NaN), MOT and Ultralytics, a bad type, a wrong extension, an unknown camera) -> exit 1
    or 2, the message names the file, line and field, no output written.
"""
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

import mrcal
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from localise_common import check, cleanup, ground_point, read_csv, run, simulate_and_calibrate  # noqa: E402
from rs_check import finish  # noqa: E402

SEED = 7
N = 24
FPS = 10.0


def same_rows(a, b, what):
    if not check(len(a) == len(b), f"{what}: {len(b)} rows, expected {len(a)}"):
        return
    worst = 0.0
    for ra, rb in zip(a, b):
        for k in ra:
            if k in ("image_id", "camera", "frame", "category_id"):
                check(ra[k] == rb[k], f"{what}: {k} {rb[k]!r}, expected {ra[k]!r}")
            elif ra[k] == "" or rb[k] == "":
                check(ra[k] == rb[k], f"{what}: {k} {rb[k]!r}, expected {ra[k]!r}")
            else:
                x, y = float(ra[k]), float(rb[k])
                worst = max(worst, abs(x - y) / max(1.0, abs(x)))
    check(worst < 1e-9, f"{what}: numbers differ by {worst:.2e} (relative)")
    return worst


def main():
    rng = np.random.default_rng(SEED)
    tmp = tempfile.mkdtemp(prefix="roadside-localise-formats-")
    try:
        site, calib = simulate_and_calibrate(tmp, SEED, 1)
        model = mrcal.cameramodel(os.path.join(calib, "cam1.cameramodel"))
        W, H = model.imagersize()
        boxes = []
        for k in range(N):
            w, h = rng.uniform(20, 120), rng.uniform(10, 60)
            x, y = rng.uniform(0, W - 1 - w), rng.uniform(0.5 * H, H - 1 - h)
            boxes.append((k // 3 + 1, int(rng.integers(1, 11)), [x, y, w, h], float(rng.uniform(0.1, 1))))
        # (b in roadside's pixels; COCO's bbox in its corner convention, + 0.5: docs/localise.md)
        coco = [{"image_id": f, "category_id": c, "bbox": [b[0] + 0.5, b[1] + 0.5, b[2], b[3]], "score": s,
                 "frame": f - 1, "time_s": (f - 1) / FPS} for f, c, b, s in boxes]
        p_coco = os.path.join(tmp, "dets.json")
        json.dump(coco, open(p_coco, "w"))
        p_mot = os.path.join(tmp, "dets.txt")
        with open(p_mot, "w") as f:
            for fr, c, b, s in boxes:
                f.write(f"{fr},-1,{b[0] + 1!r},{b[1] + 1!r},{b[2]!r},{b[3]!r},{s!r},{c},-1\n")
        p_yolo = os.path.join(tmp, "yolo")
        os.makedirs(p_yolo)
        for fr in sorted({b[0] for b in boxes}):
            with open(os.path.join(p_yolo, f"{fr:06d}.txt"), "w") as f:
                for fr2, c, b, s in boxes:
                    if fr2 == fr:
                        cx, cy = (b[0] + b[2] / 2 + 0.5) / W, (b[1] + b[3] / 2 + 0.5) / H
                        f.write(f"{c - 1} {cx!r} {cy!r} {b[2] / W!r} {b[3] / H!r} {s!r}\n")
        base = ["--site", site, "--calib", calib, "--camera", "cam1"]
        rows = {}
        for name, path in (("coco", p_coco), ("mot", p_mot), ("yolo", p_yolo)):
            out = os.path.join(tmp, f"{name}.csv")
            p = run("localise", path, *base, "--fps", str(FPS), "--point", "bottom", "-o", out) \
                if name != "coco" else run("localise", path, *base, "--point", "bottom", "-o", out)
            check(p.returncode == 0, f"{name}: exit {p.returncode}: {p.stderr}")
            rows[name] = read_csv(out) if p.returncode == 0 else []
        w_mot = same_rows(rows["coco"], rows["mot"], "MOT against COCO")
        w_yolo = same_rows(rows["coco"], rows["yolo"], "Ultralytics against COCO")
        # the default point per format
        out = os.path.join(tmp, "d.csv")
        run("localise", p_mot, *base, "--fps", str(FPS), "-o", out)
        check(read_csv(out) == rows["mot"], "MOT's default point is bottom")

        # point choices against hand-computed pixels; the oracle on every row
        oracle = 0.0
        for point, K, expect in (("center", None, lambda b: (b[0] + b[2] / 2, b[1] + b[3] / 2)),
                                 ("bottom", None, lambda b: (b[0] + b[2] / 2, b[1] + b[3])),
                                 ("shift", None, lambda b: (b[0] + b[2] / 2, b[1] + b[3] / 2 + 0.35 * b[3])),
                                 ("shift", 0.2, lambda b: (b[0] + b[2] / 2, b[1] + b[3] / 2 + 0.2 * b[3]))):
            args = ["--point", point] + (["--shift", str(K)] if K is not None else [])
            p = run("localise", p_coco, *base, *args, "-o", out)
            check(p.returncode == 0, f"--point {point}: {p.stderr}")
            got = read_csv(out)
            check(len(got) == N, f"--point {point}: {len(got)} rows")
            for r, (_, _, b, _) in zip(got, boxes):
                u, v = expect(b)
                check(abs(float(r["u_px"]) - u) < 1e-9 and abs(float(r["v_px"]) - v) < 1e-9,
                      f"--point {point} {args}: pixel ({r['u_px']}, {r['v_px']}), expected ({u}, {v})")
                g = ground_point(model, [float(r["u_px"]), float(r["v_px"])])
                oracle = max(oracle, float(np.max(np.abs(g - [float(r[k]) for k in ("e_m", "n_m", "u_m")]))))
        check(oracle < 1e-6, f"ground point against mrcal's Python: {oracle:.2e} m")
        # lat/lon against PROJ's cct (an independent geodesy), where it exists
        cct = shutil.which("cct")
        origin = json.load(open(os.path.join(site, "site.json")))["origin"]
        if cct:
            r = read_csv(out)[0]
            pipe = (f"+proj=pipeline +step +inv +proj=topocentric +ellps=WGS84 +lat_0={origin['lat']} "
                    f"+lon_0={origin['lon']} +h_0={origin['h']} +step +inv +proj=cart +ellps=WGS84")
            c = subprocess.run([cct, "-d", "12", *pipe.split()], input=f"{r['e_m']} {r['n_m']} {r['u_m']}\n",
                               capture_output=True, text=True)
            lon, lat = (float(x) for x in c.stdout.split()[:2])
            check(abs(lat - float(r["lat_deg"])) < 1e-9 and abs(lon - float(r["lon_deg"])) < 1e-9,
                  f"lat/lon {r['lat_deg']}, {r['lon_deg']} against cct {lat}, {lon}")
        # a COCO bottom_center wins over --point
        bc = [dict(coco[0], bottom_center=[coco[0]["bbox"][0] + 3.25, coco[0]["bbox"][1] + 1.5])]
        p_bc = os.path.join(tmp, "bc.json")
        json.dump(bc, open(p_bc, "w"))
        run("localise", p_bc, *base, "--point", "bottom", "-o", out)
        r = read_csv(out)[0]
        check(abs(float(r["u_px"]) - bc[0]["bottom_center"][0]) < 1e-9
              and abs(float(r["v_px"]) - bc[0]["bottom_center"][1]) < 1e-9,
              f"bottom_center: pixel ({r['u_px']}, {r['v_px']}), expected {bc[0]['bottom_center']}")

        # the same values as JSON lines and GeoJSON
        out_csv, out_jsonl, out_geo = (os.path.join(tmp, "o" + e) for e in (".csv", ".jsonl", ".geojson"))
        for o in (out_csv, out_jsonl, out_geo):
            check(run("localise", p_coco, *base, "-o", o).returncode == 0, f"-o {o}")
        csv_rows = read_csv(out_csv)
        jl = [json.loads(line) for line in open(out_jsonl)]
        gj = json.load(open(out_geo))
        check(gj.get("type") == "FeatureCollection" and len(gj["features"]) == N, "GeoJSON: N features")
        check(list(jl[0].keys()) == list(csv_rows[0].keys()), f"JSON lines keys {list(jl[0].keys())}")
        for r, j, f in zip(csv_rows, jl, gj["features"]):
            for k, v in r.items():
                for what, o in (("jsonl", j), ("geojson", f["properties"])):
                    if k == "camera":
                        check(o[k] == v, f"{what}: camera")
                    elif v == "":
                        check(o[k] is None, f"{what}: {k} {o[k]!r}, expected null")
                    else:
                        check(abs(float(o[k]) - float(v)) <= 1e-9 * max(1, abs(float(v))), f"{what}: {k}")
            check(f["geometry"]["coordinates"] == [f["properties"]["lon_deg"], f["properties"]["lat_deg"]],
                  "GeoJSON point is [lon, lat]")

        # a pixel above the horizon: not written, counted
        sky = [dict(coco[0], bbox=[W / 2, 2.0, 10, 4])] + coco[1:3]
        p_sky = os.path.join(tmp, "sky.json")
        json.dump(sky, open(p_sky, "w"))
        p = run("localise", p_sky, *base, "-o", out)
        check(p.returncode == 0 and "1 detection(s) miss the ground" in p.stdout and len(read_csv(out)) == 2,
              f"sky: {p.stdout!r} {p.stderr!r}")

        # bad input: message with file, line and field; exit 1; nothing written
        bad_cases = []
        lines = open(p_coco).read()
        no_score = [dict(d) for d in coco[:3]]
        del no_score[2]["score"]
        bad_cases.append(("coco-missing", no_score, "score: missing"))
        bad_type = [dict(d) for d in coco[:3]]
        bad_type[1]["bbox"] = [1, 2, "3", 4]
        bad_cases.append(("coco-type", bad_type, "bbox: element 2"))
        for name, data, needle in bad_cases:
            path = os.path.join(tmp, name + ".json")
            with open(path, "w") as f:
                f.write("[\n" + ",\n".join(json.dumps(d) for d in data) + "\n]\n")
            o = os.path.join(tmp, name + ".csv")
            p = run("localise", path, *base, "-o", o)
            line = 4 if name == "coco-missing" else 3
            check(p.returncode == 1 and f"{path}:{line}:" in p.stderr and needle in p.stderr
                  and not os.path.exists(o), f"{name}: rc {p.returncode}, {p.stderr!r}")
        # Python's json writes NaN as a bare NaN (not JSON): refused where it stands
        nan_path = os.path.join(tmp, "nan.json")
        with open(nan_path, "w") as f:
            f.write("[\n" + ",\n".join(json.dumps(d) for d in [coco[0], dict(coco[1], bbox=[1, float("nan"), 3, 4])])
                    + "\n]\n")
        o = os.path.join(tmp, "nan.csv")
        p = run("localise", nan_path, *base, "-o", o)
        check(p.returncode == 1 and f"{nan_path}:3:" in p.stderr and "NaN" in p.stderr and not os.path.exists(o),
              f"COCO NaN: rc {p.returncode}, {p.stderr!r}")
        mot_bad = os.path.join(tmp, "bad.txt")
        with open(mot_bad, "w") as f:
            f.write("1,-1,10,20,30,40,0.9\n2,-1,10,nan,30,40,0.9\n")
        o = os.path.join(tmp, "mot-bad.csv")
        p = run("localise", mot_bad, *base, "-o", o)
        check(p.returncode == 1 and f"{mot_bad}:2: bb_top" in p.stderr and not os.path.exists(o),
              f"MOT NaN: rc {p.returncode}, {p.stderr!r}")
        with open(mot_bad, "w") as f:
            f.write("1,-1,10,20,30,40,0.9\n2,-1,10,20,30\n")
        p = run("localise", mot_bad, *base, "-o", o)
        check(p.returncode == 1 and f"{mot_bad}:2: bb_height: missing" in p.stderr and not os.path.exists(o),
              f"MOT short line: rc {p.returncode}, {p.stderr!r}")
        # issue 42: a NUL byte dropped every later row; 0x10 read as 16
        with open(mot_bad, "w") as f:
            f.write("1,-1,10,20,30,40,0.9\n\0\n2,-1,10,20,30,40,0.9\n")
        p = run("localise", mot_bad, *base, "-o", o)
        check(p.returncode == 1 and f"{mot_bad}:2: a NUL byte" in p.stderr and not os.path.exists(o),
              f"MOT NUL: rc {p.returncode}, {p.stderr!r}")
        with open(mot_bad, "w") as f:
            f.write("1,-1,10,20,30,40,0.9\n2,-1,0x10,20,30,40,0.9\n")
        p = run("localise", mot_bad, *base, "-o", o)
        check(p.returncode == 1 and f"{mot_bad}:2: bb_left" in p.stderr and not os.path.exists(o),
              f"MOT hexadecimal: rc {p.returncode}, {p.stderr!r}")
        yolo_bad = os.path.join(tmp, "yolo-bad")
        os.makedirs(yolo_bad)
        with open(os.path.join(yolo_bad, "000001.txt"), "w") as f:
            f.write("0 0.5 0.5 0.1 0.1\n0 0.5 inf 0.1 0.1\n")
        p = run("localise", yolo_bad, *base, "-o", o)
        check(p.returncode == 1 and "000001.txt:2: cy" in p.stderr and not os.path.exists(o),
              f"Ultralytics inf: rc {p.returncode}, {p.stderr!r}")
        p = run("localise", p_coco, *base, "-o", os.path.join(tmp, "x.txt"))
        check(p.returncode == 2 and ".csv, .jsonl or .geojson" in p.stderr, f"bad extension: {p.stderr!r}")
        p = run("localise", p_coco, "--site", site, "--calib", calib, "--camera", "cam9", "-o", o)
        check(p.returncode == 2 and "cam9" in p.stderr and not os.path.exists(o), f"unknown camera: {p.stderr!r}")
        print(f"{N} boxes: MOT and Ultralytics rows against COCO within {w_mot:.1e}, {w_yolo:.1e}; "
              f"ground points against mrcal's Python within {oracle:.2e} m")
    finally:
        cleanup(tmp)
    finish("localise_formats")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
# test_site_api.py DUMP -- rs_site_load through the C API (site_api_dump.c) on the fixture:
# the observations equal the CSV values exactly (including default sigma_px 1.0 and line
# numbers), lookups and extents agree with a brute-force recomputation from the landmark list,
# a tilted ground normal is normalised; and the status of a failing load names the first
# error: RS_ERR_IO (missing file), RS_ERR_NOT_FOUND (unknown landmark), RS_ERR_PARSE (bad
# JSON), RS_ERR_INVALID (swapped coordinates), RS_ERR_UNSUPPORTED (skewed OpenCV K), with *out
# set to NULL.
import json
import math
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import site_fixture as fx  # noqa: E402

# rs_status values (core/rs_status.h)
RS = {"OK": 0, "IO": 1, "PARSE": 2, "INVALID": 3, "NOT_FOUND": 4, "UNSUPPORTED": 9}


def dump(exe, site):
    p = subprocess.run([exe, site], capture_output=True, text=True, errors="replace")
    if p.returncode != 0 or "Sanitizer" in p.stderr or "runtime error:" in p.stderr:
        fx.fail("site_api_dump failed", p.stdout, p.stderr)
    d = {"obs": [], "camera": [], "landmark": [], "lheight": [], "shape": [], "vertex": [], "obsat": []}
    for line in p.stdout.splitlines():
        k, _, v = line.partition(" ")
        if k in d:
            d[k].append(v.split())
        else:
            d[k] = v
    return d, p.stdout


def expect_status(exe, name, status, needle, inject):
    with fx.TempSite() as site:
        inject(site)
        d, out = dump(exe, site)
    if int(d["status"].split()[0]) != RS[status] or needle not in d["message"] or d.get("site_is_null") != "1":
        fx.fail("%s: expected status %s and a message with %r" % (name, status, needle), out)
    print("load %-20s -> %s: %s" % (name, status, d["message"]))


def main():
    exe = os.path.abspath(sys.argv[1])  # TempSite changes the working directory
    with fx.TempSite() as site:
        p = os.path.join(site, "site.json")
        sj = fx.load_json(p)
        sj["ground_plane"] = {"normal_enu": [0, 3, 4], "offset_m": 10.0}
        with open(p, "w") as f:
            json.dump(sj, f)
        d, out = dump(exe, site)
        csv = {cam: open(os.path.join(site, "observations", cam + ".csv")).read().splitlines()
               for cam in ("north", "south")}
    if d["status"] != "0 success":
        fx.fail("the fixture does not load", out)
    # observations: exact values, default sigma, line numbers
    for cam, lm, u, v, sigma, line in d["obs"]:
        row = csv[cam][int(line) - 1].split(",")
        want_sigma = float(row[3]) if len(row) > 3 and row[3] else 1.0
        if row[0] != lm or float(row[1]) != float(u) or float(row[2]) != float(v) or float(sigma) != want_sigma:
            fx.fail("observation %s line %s: %s, CSV has %s" % (cam, line, (lm, u, v, sigma), row), out)
    if len(d["obs"]) != 14:
        fx.fail("%d observations, expected 14" % len(d["obs"]), out)
    if [c[0] for c in d["camera"]] != ["north", "south"] or d["camera"][0][1:] != ["0", "4", "1920", "1080", "0"] \
            or d["camera"][1][1:] != ["6", "12", "1280", "720", "1"]:
        fx.fail("cameras: %s" % d["camera"], out)
    if (d["find_camera_south"], d["find_camera_nope"], d["find_landmark_L05"], d["find_landmark_l05"]) != \
            ("1", "-1", "5", "-1"):
        fx.fail("lookups", out)
    # extents by brute force
    enu = {l[0]: [float(x) for x in l[5:8]] for l in d["landmark"]}
    ext = [float(x) for x in d["extent"].split()]
    want = [min(p[k] for p in enu.values()) for k in range(3)] + [max(p[k] for p in enu.values()) for k in range(3)]
    dist = [math.sqrt(sum(x * x for x in p)) for p in enu.values()]
    want += [min(dist), max(dist)]
    if int(ext[0]) != 10 or max(abs(a - b) for a, b in zip(ext[1:], want)) > 1e-12:
        fx.fail("extent %s, brute force %s" % (ext, want), out)
    south = {o[1] for o in d["obs"] if o[0] == "south"}
    n, dmax = d["extent_south"].split()
    if int(n) != len(south) or abs(float(dmax) - max(math.sqrt(sum(x * x for x in enu[i])) for i in south)) > 1e-12:
        fx.fail("extent of south's landmarks", out)
    g = [float(x) for x in d["ground"].split()]
    if max(abs(a - b) for a, b in zip(g, [0, 0.6, 0.8, 2.0])) > 1e-15:
        fx.fail("ground plane not normalised: %s" % g, out)
    print("load fixture: 14 observations exact, lookups, extents (brute force), ground plane ok")

    def remove(path):
        return lambda s: os.remove(os.path.join(s, path))

    def csv_line(text):
        def f(s):
            with open(os.path.join(s, "observations", "north.csv"), "a") as fh:
                fh.write(text + "\n")
        return f

    def swap(s):
        p = os.path.join(s, "landmarks.geojson")
        g = fx.load_json(p)
        c = g["features"][2]["geometry"]["coordinates"]
        c[0], c[1] = c[1], c[0]
        with open(p, "w") as fh:
            json.dump(g, fh)

    def bad_json(s):
        with open(os.path.join(s, "site.json"), "a") as fh:
            fh.write("}")

    def skew(s):
        p = os.path.join(s, "site.json")
        sj = fx.load_json(p)
        sj["cameras"][0]["model"] = "cameras/k.json"
        with open(p, "w") as fh:
            json.dump(sj, fh)
        with open(os.path.join(s, "cameras", "k.json"), "w") as fh:
            json.dump({"image_width": 1920, "image_height": 1080,
                       "camera_matrix": [[1000, 1, 960], [0, 1000, 540], [0, 0, 1]]}, fh)

    expect_status(exe, "missing model", "IO", "SITE/cameras/south.cameramodel: missing file",
                  remove("cameras/south.cameramodel"))
    expect_status(exe, "unknown landmark", "NOT_FOUND", "SITE/observations/north.csv:9: landmark: 'L42'",
                  csv_line("L42,10,10"))
    expect_status(exe, "bad json", "PARSE", "SITE/site.json:", bad_json)
    expect_status(exe, "swapped", "INVALID", "feature 2 (id 'L02'): coordinates: looks like latitude", swap)
    expect_status(exe, "skewed K", "UNSUPPORTED", "SITE/cameras/k.json: camera_matrix: skew", skew)


if __name__ == "__main__":
    main()

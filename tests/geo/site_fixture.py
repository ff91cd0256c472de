# site_fixture.py -- a small valid site folder, generated in the test (fixed seed), and the
# helpers the site tests share: run `roadside`, assert on its output.
#
# The fixture: origin 48.137, 11.575 (Munich); 10 landmarks L00..L09 within 60 m of the origin;
# camera 'north' (mrcal LENSMODEL_PINHOLE, 1920x1080, backgrounds folder) with picks of L00..L06,
# one of them exactly on the image border u = 1919.5 (valid under the pixel-centre convention);
# camera 'south' (mrcal LENSMODEL_OPENCV8, 1280x720, surveyed position prior) with picks of
# L03..L09 and a sigma_px column. Pixel values are arbitrary in-image picks: the site format
# does not require them to be consistent with a pose.
import json
import math
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile

SEED = 20261122
ORIGIN = (48.137, 11.575, 520.0)
R_EARTH = 6378137.0


def llh_from_enu(e, n, u, origin=ORIGIN):
    """Small-offset approximation, good enough to place fixture points (the tests compare
    against PROJ's cct on whatever coordinates this produces)."""
    lat0, lon0, h0 = origin
    lat = lat0 + math.degrees(n / R_EARTH)
    lon = lon0 + math.degrees(e / (R_EARTH * math.cos(math.radians(lat0))))
    return lat, lon, h0 + u


def site_json(origin=ORIGIN, heights="ellipsoidal"):
    lat, lon, h = llh_from_enu(-3.0, -25.0, 6.5)
    return {
        "name": "fixture-intersection",
        "origin": {"lat": origin[0], "lon": origin[1], "h": origin[2]},
        "heights": heights,
        "landmark_sigma_m": {"horizontal": 0.3, "vertical": 0.5},
        "ground_plane": {"normal_enu": [0, 0, 1], "offset_m": 0.0},
        "max_landmark_distance_m": 1000,
        "cameras": [
            {"id": "north", "model": "cameras/north.cameramodel",
             "observations": "observations/north.csv", "backgrounds": "backgrounds/north",
             "note": "gantry, looking south"},
            {"id": "south", "model": "cameras/south.cameramodel",
             "observations": "observations/south.csv",
             "position_prior": {"lat": lat, "lon": lon, "h": h, "sigma_m": 2.0}},
        ],
    }


def landmarks(rng, h_offset=0.0):
    feats = []
    for i in range(10):
        e, n, u = rng.uniform(-60, 60), rng.uniform(-60, 60), rng.uniform(-0.3, 1.5)
        lat, lon, h = llh_from_enu(e, n, u)
        props = {"id": "L%02d" % i, "kind": "lane-marking-corner"}
        if i == 4:
            props["sigma_h_m"] = 0.05
            props["sigma_v_m"] = 0.08
        feats.append({"type": "Feature",
                      "geometry": {"type": "Point", "coordinates": [lon, lat, h + h_offset]},
                      "properties": props})
    return {"type": "FeatureCollection", "features": feats}


PINHOLE = ("{'lensmodel': 'LENSMODEL_PINHOLE',\n"
           " 'intrinsics': [1200.0, 1200.0, 959.5, 539.5],\n"
           " 'imagersize': [1920, 1080],\n"
           " 'extrinsics': [0, 0, 0, 0, 0, 0]}\n")
OPENCV8 = ("{'lensmodel': 'LENSMODEL_OPENCV8',\n"
           " 'intrinsics': [900.0, 905.0, 640.2, 359.7, -0.1, 0.02, 0.0005, -0.0003, 0.001, 0, 0, 0],\n"
           " 'imagersize': [1280, 720],\n"
           " 'extrinsics': [0, 0, 0, 0, 0, 0]}\n")


def write(path, text):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write(text)


def make_site(dirname, heights="ellipsoidal", h_offset=0.0):
    """Writes the fixture into `dirname` (created). Returns the site.json dict."""
    rng = random.Random(SEED)
    sj = site_json(heights=heights)
    # orthometric sites store h - N: the same physical points as the ellipsoidal fixture
    sj["origin"]["h"] += h_offset
    if "position_prior" in sj["cameras"][1]:
        sj["cameras"][1]["position_prior"]["h"] += h_offset
    write(os.path.join(dirname, "site.json"), json.dumps(sj, indent=2) + "\n")
    write(os.path.join(dirname, "landmarks.geojson"), json.dumps(landmarks(rng, h_offset), indent=1) + "\n")
    write(os.path.join(dirname, "cameras", "north.cameramodel"), PINHOLE)
    write(os.path.join(dirname, "cameras", "south.cameramodel"), OPENCV8)
    rows = ["landmark,u,v"]
    for i in range(7):
        u, v = rng.uniform(0, 1919), rng.uniform(0, 1079)
        if i == 2:
            u = 1919.5  # exactly on the border: valid
        rows.append("L%02d,%.2f,%.2f" % (i, u, v))
    write(os.path.join(dirname, "observations", "north.csv"), "\n".join(rows) + "\n")
    rows = ["landmark,u,v,sigma_px"]
    for i in range(3, 10):
        rows.append("L%02d,%.3f,%.3f,%s" % (i, rng.uniform(0, 1279), rng.uniform(0, 719),
                                            "" if i % 2 else "1.5"))
    write(os.path.join(dirname, "observations", "south.csv"), "\n".join(rows) + "\n")
    os.makedirs(os.path.join(dirname, "backgrounds", "north"), exist_ok=True)
    return sj


def roadside():
    exe = os.environ.get("ROADSIDE")
    if not exe:
        sys.exit("ROADSIDE is not set (run through meson test)")
    return exe


def run(*args):
    p = subprocess.run([roadside()] + list(args), capture_output=True, text=True, errors="replace")
    if "Sanitizer" in p.stderr or "runtime error:" in p.stderr:
        fail("roadside %s: sanitizer report" % " ".join(args), p.stdout, p.stderr)
    return p.returncode, p.stdout, p.stderr


class TempSite:
    """A temporary folder holding the fixture at <tmp>/SITE (so messages read SITE/...)."""

    def __init__(self, **kw):
        self.kw = kw

    def __enter__(self):
        self.tmp = tempfile.mkdtemp(prefix="rs_site_test_")
        self.cwd = os.getcwd()
        os.chdir(self.tmp)
        make_site("SITE", **self.kw)
        return "SITE"

    def __exit__(self, *exc):
        os.chdir(self.cwd)
        shutil.rmtree(self.tmp, ignore_errors=True)
        return False


def fail(msg, out="", err=""):
    print("FAIL (seed %d): %s" % (SEED, msg))
    if out:
        print("--- stdout\n" + out)
    if err:
        print("--- stderr\n" + err)
    sys.exit(1)


def expect_line(out, pattern, what):
    """Asserts that one line of `out` matches the regular expression `pattern`."""
    for line in out.splitlines():
        if re.search(pattern, line):
            return line
    fail("no line matches %r (%s)" % (pattern, what), out)


def load_json(path):
    with open(path) as f:
        return json.load(f)

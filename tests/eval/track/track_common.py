"""What the tests of `roadside track` share: located-detection CSVs written from numpy (issue 39's
interface 2, positions and covariances drawn directly, no images), a site folder to run on, and
the tracks CSV read back.

    sys.path.insert(0, os.path.dirname(__file__))
    from track_common import write_located, read_tracks, make_site, run_track
"""
import csv
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "common"))
from rs_check import run  # noqa: E402

HEADER = ("image_id,camera,frame,time_s,category_id,score,u_px,v_px,e_m,n_m,u_m,lat_deg,lon_deg,"
          "sigma_e_m,sigma_n_m,cov_en_m2")


def write_located(path, rows):
    """rows: dicts with camera, time_s, e_m, n_m, cov (2x2) and optionally frame, category_id;
    written in the item-2 format (positions to 1e-12 m)."""
    with open(path, "w") as f:
        f.write(HEADER + "\n")
        for k, r in enumerate(rows):
            c = r["cov"]
            t = "" if r.get("time_s") is None else "%.17g" % r["time_s"]
            f.write("%d,%s,%d,%s,%d,0.9,,,%.17g,%.17g,0,,,%.17g,%.17g,%.17g\n" % (
                k, r["camera"], r.get("frame", -1), t, r.get("category_id", 1), r["e_m"], r["n_m"],
                c[0][0] ** 0.5, c[1][1] ** 0.5, c[0][1]))


def read_tracks(path):
    """The tracks CSV as a list of dicts of floats (cameras kept as text)."""
    with open(path) as f:
        rows = list(csv.DictReader(f))
    out = []
    for r in rows:
        d = {k: (v if k == "cameras" else float(v)) for k, v in r.items()}
        d["track_id"] = int(d["track_id"])
        out.append(d)
    return out


def make_site(dirname):
    """A site folder that loads (`roadside site simulate --seed 1 --cameras 1`: the tracker only
    needs its origin); returns its path."""
    site = os.path.join(dirname, "site")
    r = run("site", "simulate", site, "--seed", "1", "--cameras", "1")
    if r.returncode != 0:
        print(r.stdout, r.stderr)
        raise SystemExit("cannot make a site: roadside site simulate failed")
    return site


def site_origin(site):
    """The site's origin (lat_deg, lon_deg, h_m) from its site.json."""
    import json
    with open(os.path.join(site, "site.json")) as f:
        o = json.load(f)["origin"]
    return o["lat"], o["lon"], o["h"]


def run_track(site, inputs, out, *extra):
    """roadside track SITE INPUTS... -o OUT EXTRA...: the completed process."""
    return run("track", site, *inputs, "-o", out, *extra)

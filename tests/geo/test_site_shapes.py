#!/usr/bin/env python3
"""test_site_shapes.py DUMP ROUNDTRIP CASE -- issue 13, item 4 (site side): poles and lines as
landmarks. A Point feature with properties.height_m is a pole (its base the point, its top
height_m straight up); a LineString feature is a line; the observations CSV's column `at` says
where on it a pick lies (point; base, top, along; along). Each CASE builds a site from the fixture
(site_fixture.py, fixed seed) with poles and lines added, and checks it against independent
oracles:

  read       every vertex's ENU (rs_site_load through site_api_dump.c, 17 digits) against PROJ's
             cct (cart + topocentric), 1e-8 m; vertex 0 is the landmark's own position; a pole's
             height and sigma (given, and the default: the stated sigma_v); the `at` of every
             pick resolved as documented (empty: point for points, along for poles and lines);
             `along` picks repeat; `roadside site check` passes it with no error or warning;
             a line with unknown heights ([lon, lat]) gets every vertex's height from the ground
             model, which equals numpy's least-squares plane through the surveyed points (1e-6 m)
  malformed  a table of malformed poles, lines and picks: each refused with its message naming
             the file, feature or line, and field (`roadside site check`), and the status
             rs_site_load returns (site_api_dump)
  roundtrip  geo's writers (site_write_roundtrip.c) write poles, lines and `at` back; the copy
             loads to exactly the same vertices, pole heights and sigmas, and picks (17 digits)
"""
import json
import math
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "common"))
import geo_oracle as go  # noqa: E402
import site_fixture as fx  # noqa: E402
from rs_check import check, finish  # noqa: E402

SEED = 20261304


def status_code(name):
    """The rs_status number of RS_ERR_<name> (or RS_OK), counted in core/rs_status.h's enum."""
    root = os.environ.get("ROADSIDE_SOURCE_ROOT", os.path.join(HERE, "..", ".."))
    text = open(os.path.join(root, "core", "rs_status.h")).read()
    names = re.findall(r"^\s*(RS_OK|RS_ERR_[A-Z_]+)\b", text[text.index("typedef enum"):], re.M)
    return names.index("RS_OK" if name == "OK" else "RS_ERR_" + name)


def pos(e, n, u, two=False):
    lat, lon, h = fx.llh_from_enu(e, n, u)
    return [lon, lat] if two else [lon, lat, h]


def pole(fid, e, n, u, height, sigma=None, extra=None):
    p = {"id": fid, "kind": "lamp_post", "height_m": height}
    if sigma is not None:
        p["sigma_height_m"] = sigma
    p.update(extra or {})
    return {"type": "Feature", "geometry": {"type": "Point", "coordinates": pos(e, n, u)}, "properties": p}


def line(fid, enu, two=False, extra=None):
    p = {"id": fid, "kind": "edge_line"}
    p.update(extra or {})
    return {"type": "Feature", "geometry": {"type": "LineString", "coordinates": [pos(*v, two=two) for v in enu]},
            "properties": p}


# the shapes every case starts from: two poles (one with its own height sigma), a curved line and
# a straight one
LINE1 = [(-20.0 + 8 * k, 4.0 + 0.3 * k * k, 0.02 * k) for k in range(6)]
LINE2 = [(30.0, -40.0, 0.1), (31.0, 10.0, 0.3)]


def base_shapes():
    return [pole("P1", 5.0, 10.0, 0.2, 6.5, sigma=0.1), pole("P2", -12.0, 20.0, 0.0, 1.1),
            line("LN1", LINE1), line("LN2", LINE2)]


NORTH_PICKS = "P1,100,200\nP1,110,300\nP2,400,420,,along\nLN1,500,500\nLN1,600,510,2.5,along\nLN2,700,700,,\n"
SOUTH_PICKS = "P1,100,100,,top\nP1,100,150,,base\nP1,120,130,,along\nLN2,300,300,,along\n"


def make(site, features=None, north=NORTH_PICKS, south=SOUTH_PICKS, sj=None):
    """The fixture in `site` with the shapes added; north.csv gains a column `at` (empty for the
    fixture's own rows), south.csv likewise."""
    fx.make_site(site)
    g = fx.load_json(os.path.join(site, "landmarks.geojson"))
    g["features"] += base_shapes() if features is None else features
    with open(os.path.join(site, "landmarks.geojson"), "w") as f:
        json.dump(g, f, indent=1)
    if sj is not None:
        with open(os.path.join(site, "site.json"), "w") as f:
            json.dump(sj, f, indent=1)
    for cam, extra in (("north", north), ("south", south)):
        path = os.path.join(site, "observations", cam + ".csv")
        rows = open(path).read().splitlines()
        ncols = rows[0].count(",") + 1
        rows = [rows[0] + ",at"] + [r + "," for r in rows[1:]]
        # extra rows are landmark,u,v[,sigma][,at]: padded to the header's columns
        for r in extra.splitlines():
            f = r.split(",")
            if ncols == 3:  # no sigma_px column: landmark,u,v,at
                f = f[:3] + [f[4] if len(f) > 4 else ""]
            else:
                f = (f + ["", ""])[:5]
            rows.append(",".join(f))
        with open(path, "w") as fh:
            fh.write("\n".join(rows) + "\n")


def dump(site):
    p = subprocess.run([DUMP, site], capture_output=True, text=True, errors="replace")
    if p.returncode != 0 or "Sanitizer" in p.stderr or "runtime error:" in p.stderr:
        fx.fail("site_api_dump failed", p.stdout, p.stderr)
    d = {"shape": {}, "vertex": {}, "obsat": [], "landmark": {}, "raw": p.stdout}
    for ln in p.stdout.splitlines():
        k, _, v = ln.partition(" ")
        f = v.split()
        if k == "shape":
            d["shape"][f[0]] = (f[1], float(f[2]), float(f[3]), int(f[4]))
        elif k == "vertex":
            d["vertex"].setdefault(f[0], []).append([float(x) for x in f[2:]])
        elif k == "obsat":
            d["obsat"].append((f[0], f[1], f[2], int(f[3])))
        elif k == "landmark":
            d["landmark"][f[0]] = [float(x) for x in f[2:8]]
        elif k not in d:
            d[k] = v
    return d


def cct_enu(origin, llh):
    return go.run_cct(go.topocentric(*origin), [(lon, lat, h) for lat, lon, h in llh], "%.15f %.15f %.10f")


def case_read(tmp):
    site = os.path.join(tmp, "SITE")
    make(site)
    rc, out, err = fx.run("site", "check", site)
    check(rc == 0 and re.search(r"^0 errors, 0 warnings$", out, re.M), "read: site check passes: %s%s" % (out, err))
    d = dump(site)
    check(d.get("status") == "0 success", "read: loads (%s)" % d.get("message"))
    o = fx.ORIGIN
    g = fx.load_json(os.path.join(site, "landmarks.geojson"))
    worst = 0.0
    for f in g["features"]:
        fid = f["properties"]["id"]
        gm = f["geometry"]
        coords = gm["coordinates"] if gm["type"] == "LineString" else [gm["coordinates"]]
        want_shape = "line" if gm["type"] == "LineString" else ("pole" if "height_m" in f["properties"] else "point")
        shape = d["shape"].get(fid)
        check(shape is not None and shape[0] == want_shape and shape[3] == len(coords),
              "read: %s is a %s of %d vertices: %s" % (fid, want_shape, len(coords), shape))
        ref = cct_enu(o, [(c[1], c[0], c[2]) for c in coords])
        got = d["vertex"].get(fid, [])
        for k, (r, v) in enumerate(zip(ref, got)):
            worst = max(worst, go.dist(r, v[3:6]))
            check(abs(v[0] - coords[k][1]) < 1e-12 and abs(v[1] - coords[k][0]) < 1e-12 and
                  abs(v[2] - coords[k][2]) < 1e-9 and abs(v[7] - coords[k][2]) < 1e-9,
                  "read: %s vertex %d llh %s vs file %s" % (fid, k, v[:3], coords[k]))
        check(len(got) == len(coords) and got and go.dist(got[0][3:6], d["landmark"][fid][3:6]) == 0.0,
              "read: %s vertex 0 is its p_enu_m" % fid)
    check(worst < 1e-8, "read: vertex ENU vs cct: worst %.3g m (tolerance 1e-8)" % worst)
    print("read: %d vertices of %d landmarks agree with cct to %.2e m" % (
        sum(len(v) for v in d["vertex"].values()), len(d["vertex"]), worst))
    check(d["shape"]["P1"][1:3] == (6.5, 0.1) and d["shape"]["P2"][1:3] == (1.1, 0.5) and
          d["shape"]["LN1"][1:3] == (0.0, 0.0) and d["shape"]["L00"][1:] == (0.0, 0.0, 1),
          "read: pole heights and sigmas (P2's default: the site's sigma_v 0.5): %s" % d["shape"])
    # `at`: resolved as documented; along picks repeat
    want = {("north", "P1"): ["along", "along"], ("north", "P2"): ["along"], ("north", "LN1"): ["along", "along"],
            ("north", "LN2"): ["along"], ("south", "P1"): ["top", "base", "along"], ("south", "LN2"): ["along"]}
    got = {}
    for cam, lid, at, _ in d["obsat"]:
        got.setdefault((cam, lid), []).append(at)
    for key, ats in want.items():
        check(got.get(key) == ats, "read: picks of %s in %s: %s, want %s" % (key[1], key[0], got.get(key), ats))
    check(all(at == "point" for (cam, lid), ats in got.items() if lid.startswith("L0") for at in ats),
          "read: every pick of a point resolves to 'point'")

    # unknown heights: the line's vertices get the ground model's heights; the fixture's points
    # are surveyed, so the model is their least-squares plane (they lie within 3 sigma of it)
    two = [line("LN3", [(-30.0, -30.0, 0), (0.0, -35.0, 0), (25.0, -20.0, 0)], two=True,
                extra={"height": "unknown"})]
    site2 = os.path.join(tmp, "SITE2")
    make(site2, features=base_shapes() + two)
    d2 = dump(site2)
    check(d2.get("status") == "0 success", "read: the site with an unknown line loads (%s)" % d2.get("message"))
    pts = np.array([d2["landmark"]["L%02d" % i][3:6] for i in range(10)] +
                   [v[3:6] for lid in ("P1", "P2", "LN1", "LN2") for v in d2["vertex"][lid]])
    c = pts[:, :2].mean(0)
    A = np.c_[np.ones(len(pts)), pts[:, 0] - c[0], pts[:, 1] - c[1]]
    coef = np.linalg.lstsq(A, pts[:, 2], rcond=None)[0]
    worst = 0.0
    for v in d2["vertex"].get("LN3", []):
        up = coef[0] + coef[1] * (v[3] - c[0]) + coef[2] * (v[4] - c[1])
        worst = max(worst, abs(v[5] - up))
        check(math.isnan(v[7]) and v[6] > 0.05, "read: LN3 vertex: no given height, a modelled sigma %.3f" % v[6])
    check(len(d2["vertex"].get("LN3", [])) == 3 and worst < 1e-6,
          "read: LN3's modelled vertex heights vs numpy's plane through the %d surveyed heights: %.3g m" % (
              len(pts), worst))
    print("read: an unknown line's 3 vertices lie on numpy's ground plane to %.2e m" % worst)


def feat_with(fid, geometry=None, props=None):
    """A pole of height 3 m, or a feature of the given geometry and properties."""
    f = pole(fid, 1.0, 2.0, 0.0, 3.0)
    if geometry is not None:
        f["geometry"] = geometry
        f["properties"] = {"id": fid}
    if props is not None:
        f["properties"] = dict(props, id=fid)
    return f


def lgeom(coords):
    return {"type": "LineString", "coordinates": coords}


P, Q, R = pos(0, 0, 0), pos(5, 0, 0), pos(5, 5, 0)
MALFORMED = [
    # name, features added, extra north picks, status, regex of a line of `site check`
    ("pole_height_zero", [feat_with("X", props={"height_m": 0})], "", "INVALID",
     r"feature 14 \(id 'X'\): properties\.height_m: 0 m is outside \(0, 100\] m"),
    ("pole_height_huge", [feat_with("X", props={"height_m": 150})], "", "INVALID",
     r"feature 14 \(id 'X'\): properties\.height_m: 150 m is outside \(0, 100\] m"),
    ("pole_height_string", [feat_with("X", props={"height_m": "6"})], "", "PARSE",
     r"feature 14 \(id 'X'\): properties\.height_m: "),
    ("pole_sigma_without_height", [feat_with("X", props={"sigma_height_m": 0.1})], "", "INVALID",
     r"feature 14 \(id 'X'\): properties\.sigma_height_m: given without properties\.height_m"),
    ("pole_sigma_tiny", [feat_with("X", props={"height_m": 2, "sigma_height_m": 1e-5})], "", "INVALID",
     r"feature 14 \(id 'X'\): properties\.sigma_height_m: "),
    ("line_one_position", [feat_with("X", geometry=lgeom([P]))], "", "INVALID",
     r"feature 14 \(id 'X'\): coordinates: 1 position: a line needs at least 2 distinct positions"),
    ("line_not_list", [feat_with("X", geometry=lgeom(P))], "", "PARSE",
     r"feature 14 \(id 'X'\): coordinates\[0\]: expected \[lon, lat, h\]"),
    ("line_zero_length", [feat_with("X", geometry=lgeom([P, Q, Q, R]))], "", "INVALID",
     r"feature 14 \(id 'X'\): coordinates\[2\]: at the same position as coordinates\[1\] \(within 1 mm\): "
     r"a zero-length segment"),
    ("line_all_same", [feat_with("X", geometry=lgeom([P, P]))], "", "INVALID",
     r"feature 14 \(id 'X'\): coordinates\[1\]: at the same position as coordinates\[0\]"),
    ("line_too_many", [feat_with("X", geometry=lgeom([pos(0.01 * k, 0, 0) for k in range(10001)]))], "", "INVALID",
     r"feature 14 \(id 'X'\): coordinates: 10001 positions, more than 10000: split the line"),
    ("line_vertex_no_height", [feat_with("X", geometry=lgeom([P, Q[:2], R]))], "", "PARSE",
     r"feature 14 \(id 'X'\): coordinates\[1\]: the height is missing"),
    ("line_vertex_swapped", [feat_with("X", geometry=lgeom([P, [Q[1], Q[0], Q[2]]]))], "", "INVALID",
     r"feature 14 \(id 'X'\): coordinates\[1\]: looks like latitude and longitude are exchanged"),
    ("line_vertex_not_number", [feat_with("X", geometry=lgeom([P, [Q[0], "x", 0]]))], "", "PARSE",
     r"feature 14 \(id 'X'\): coordinates\[1\]: lat \(\"x\"\) is not a number"),
    ("line_with_height_m", [feat_with("X", geometry=lgeom([P, Q]), props={"height_m": 3})], "", "INVALID",
     r"feature 14 \(id 'X'\): properties\.height_m: a line has no height_m"),
    ("polygon", [feat_with("X", geometry={"type": "Polygon", "coordinates": [[P, Q, R, P]]})], "", "INVALID",
     r"feature 14 \(id 'X'\): geometry\.type: 'Polygon': a landmark is a \"Point\""),
    ("at_unknown_word", [], "LN1,10,10,,tip", "PARSE",
     r"SITE/observations/north\.csv:15: at: 'tip': expected point \(a point\), base, top or along"),
    ("at_top_of_point", [], "L05,10,10,,top", "INVALID",
     r"SITE/observations/north\.csv:15: at: 'L05' is a point: it is picked at 'point' \(the default\), not at 'top'"),
    ("at_point_of_pole", [], "P1,10,10,,point", "INVALID",
     r"north\.csv:15: at: 'P1' is a pole: it is picked at 'base', 'top' or 'along' \(the default\), not at 'point'"),
    ("at_base_of_line", [], "LN1,10,10,,base", "INVALID",
     r"north\.csv:15: at: 'LN1' is a line: it is picked 'along' \(the default\), not at 'base'"),
    ("pole_top_twice", [], "P1,10,10,,top\nP1,12,12,,top", "INVALID",
     r"north\.csv:16: at: 'P1' is picked at its top twice in this camera \(first at line 15\)"),
    ("point_twice", [], "L03,10,10,,point", "INVALID",
     r"north\.csv:15: landmark: 'L03' is observed twice in this camera \(first at line 5\)"),
]


def case_malformed(tmp):
    for name, feats, picks, status, pattern in MALFORMED:
        site = os.path.join(tmp, name, "SITE")
        os.makedirs(os.path.dirname(site))
        make(site, features=base_shapes() + feats, north=NORTH_PICKS + picks + ("\n" if picks else ""))
        cwd = os.getcwd()
        os.chdir(os.path.dirname(site))
        rc, out, err = fx.run("site", "check", "SITE")
        os.chdir(cwd)
        ok = check(rc == 1 and any(re.search(pattern, ln) for ln in out.splitlines()) and "Sanitizer" not in err,
                   "malformed %s: exit %d, no line matches %r:\n%s%s" % (name, rc, pattern, out, err))
        d = dump(site)
        code = int(d.get("status", "-1 ?").split()[0])
        ok = check(code == status_code(status), "malformed %s: rs_site_load status %d, want %s (%s)" % (
            name, code, status, d.get("message"))) and ok
        print("malformed %-26s %s" % (name, "refused as documented" if ok else "WRONG"))
    # a camera whose picks fix too few numbers (a pole picked along twice, a line once: 2 + 1 < 8)
    site = os.path.join(tmp, "few", "SITE")
    os.makedirs(os.path.dirname(site))
    make(site, north="", south="")
    for cam in ("north",):
        with open(os.path.join(site, "observations", cam + ".csv"), "w") as f:
            f.write("landmark,u,v,at\nP1,10,10,along\nP1,20,20,along\nP1,30,30,along\nLN1,40,40,\nP2,50,50,base\n")
    rc, out, _ = fx.run("site", "check", site)
    check(rc == 1 and re.search(r"north\.csv: camera 'north': its 5 picks \(4 along a pole or line\) fix 5 numbers", out),
          "malformed too_few_numbers: %s" % out)
    # only along picks of parallel lines: a warning (nothing fixes the camera along them)
    site = os.path.join(tmp, "parallel", "SITE")
    os.makedirs(os.path.dirname(site))
    par = [line("A%d" % k, [(-30.0, 4.0 * k, 0.0), (0.0, 4.0 * k, 0.0), (30.0, 4.0 * k, 0.0)]) for k in range(4)]
    make(site, features=par, north="", south="")
    with open(os.path.join(site, "observations", "north.csv"), "w") as f:
        f.write("landmark,u,v\n" + "".join("A%d,%d,%d\n" % (k, 100 + 50 * j, 100 + 40 * k)
                                          for k in range(4) for j in range(3)))
    rc, out, _ = fx.run("site", "check", site)
    check(rc == 0 and re.search(r"north\.csv: warning: camera 'north': every pick is 'along' a pole or line, and "
                                r"they all run in one direction", out), "parallel lines warning: %s" % out)


def case_roundtrip(tmp):
    site, out = os.path.join(tmp, "SITE"), os.path.join(tmp, "OUT")
    two = [line("LN3", [(-30.0, -30.0, 0), (0.0, -35.0, 0), (25.0, -20.0, 0)], two=True,
                extra={"height": "unknown"})]
    make(site, features=base_shapes() + two)
    for layout in ("tool", "hand"):
        shutil.rmtree(out, ignore_errors=True)
        for sub in ("cameras", "observations"):
            os.makedirs(os.path.join(out, sub))
        for cam in ("north", "south"):
            shutil.copy(os.path.join(site, "cameras", cam + ".cameramodel"), os.path.join(out, "cameras"))
        p = subprocess.run([ROUNDTRIP, site, out, layout], capture_output=True, text=True)
        check(p.returncode == 0 and "status 0 done" in p.stdout, "roundtrip %s: %s%s" % (layout, p.stdout, p.stderr))
        a, b = dump(site), dump(out)
        check(b.get("status") == "0 success", "roundtrip %s: the copy loads (%s)" % (layout, b.get("message")))
        # the writer prints numbers as cJSON does (15 significant digits when they read back within
        # an ulp: a latitude may move by 7e-15 degrees, its ENU by 1.3e-9 m): 1e-8 in degrees and
        # metres; NaN (no given height) must stay NaN
        worst = 0.0
        for key in ("shape", "vertex", "landmark"):
            check(set(a[key]) == set(b[key]), "roundtrip %s: %s ids differ" % (layout, key))
            for lid in a[key]:
                x = np.array(a[key][lid], dtype=object).ravel().tolist() if key != "shape" else list(a[key][lid][1:])
                y = np.array(b[key].get(lid, []), dtype=object).ravel().tolist() if key != "shape" else \
                    list(b[key].get(lid, ("",))[1:])
                if key == "shape" and a[key][lid][0] != b[key].get(lid, ("",))[0]:
                    check(False, "roundtrip %s: %s changed shape" % (layout, lid))
                flat = lambda v: [float(t) for t in (np.ravel(v) if not isinstance(v, (int, float)) else [v])]
                x, y = sum((flat(t) for t in x), []), sum((flat(t) for t in y), [])
                same = len(x) == len(y) and all((math.isnan(p) and math.isnan(q)) or abs(p - q) <= 1e-8 for p, q in zip(x, y))
                check(same, "roundtrip %s: %s %s differ: %s vs %s" % (layout, key, lid, x, y))
                worst = max([worst] + [abs(p - q) for p, q in zip(x, y) if not math.isnan(p)])
        check([o[:3] for o in a["obsat"]] == [o[:3] for o in b["obsat"]],
              "roundtrip %s: picks and their `at` differ" % layout)
        g = fx.load_json(os.path.join(out, "landmarks.geojson"))
        ln3 = [f for f in g["features"] if f["properties"]["id"] == "LN3"]
        check(ln3 and all(len(c) == 2 for c in ln3[0]["geometry"]["coordinates"]),
              "roundtrip %s: a line of unknown heights is written [lon, lat]" % layout)
        header = open(os.path.join(out, "observations", "north.csv")).readline().strip()
        check(header == "landmark,u,v,sigma_px,at", "roundtrip %s: header %r" % (layout, header))
        print("roundtrip %s: %d landmarks, %d vertices, %d picks read back; largest difference %.2g "
              "(degrees or metres; tolerance 1e-8)" % (
                  layout, len(a["shape"]), sum(len(v) for v in a["vertex"].values()), len(a["obsat"]), worst))


if __name__ == "__main__":
    DUMP, ROUNDTRIP, CASE = sys.argv[1:4]
    random.seed(SEED)
    tmp = tempfile.mkdtemp(prefix="rs_shapes_")
    try:
        {"read": case_read, "malformed": case_malformed, "roundtrip": case_roundtrip}[CASE](tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    finish("site_shapes_" + CASE)

#!/usr/bin/env python3
"""`roadside site import` (geo/rs_site_import.h): a site from point pairs, checked against oracles.

Cases (argv[1]):
- aalborg: the real Aalborg survey (/work/shared/real/aalborg_roadside: pix.csv + utm.csv joined
  here into an e,n,u,v CSV in EPSG:25832, its frame beside it; skipped, 77, when absent): `site
  check` passes; every landmark's ENU against PROJ (cs2cs EPSG:25832 -> EPSG:4326, then cct's
  topocentric pipeline at the site origin) within 1 mm; the camera is the nominal pinhole (f = the
  width, the image's centre, 1920 x 1080); the frame is copied into backgrounds/aalborg/ (for the
  report); `roadside calib --refine focal` writes a pose.
- json_fisheye: a point-pair JSON with an image beside it and the equidistant triple
  {f, x0, y0}: 14 ground points seen by a known CAHVORE camera (mrcal.project, linearity 0), their
  lat/lng made by cct from ENU; the camera file is the triple (f f x0 y0 and 8 zeros); ENU within
  1 mm of cct; `calib --refine focal` recovers the camera's position within 0.01 m and f within
  0.01 px.
- kb_two_cameras: two point-pair JSONs and one OpenCV fisheye YAML (distortion_model fisheye, k1,
  k2): ids prefixed by camera, both camera files CAHVORE (fx fy cx cy 0 0 0 k1 k2 0 0 0), both
  positions recovered within 0.01 m.
- csv_latlon: a lat,lon,u,v,h CSV (survey heights) of a pinhole whose focal is the image width,
  --image-size: heights surveyed, ENU (all three) within 1 mm of cct, `calib --refine focal`
  recovers the position within 0.01 m.
- readme: README.md's two commands (import, calib) on sites/import/gate.json, run as written:
  calib recovers the position sites/import/README.md states within 0.01 m.
- bad_input: missing field, bad EPSG, a NUL byte, a value that is not a number, and more: each
  exits non-zero with "FILE:LINE: FIELD: what" (or the option at fault) and leaves no folder, not
  even a temporary one; an existing site is replaced only with --force.
Fixed seed 38 (printed on failure)."""
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from rs_check import check, finish, need, run  # noqa: E402

cv2, mrcal, np = need("cv2", "mrcal", "numpy")

SEED = 38
TOL_M = 1e-3
ORIGIN = (40.44231, -79.94562, 0.0)  # Pittsburgh, as the point-pair example


def cct(pipeline, rows, inverse=False):
    text = "".join("%.12f %.12f %.12f 0\n" % tuple(r) for r in rows)
    p = subprocess.run(["cct", "-d", "12"] + (["-I"] if inverse else []) + pipeline.split(), input=text,
                       capture_output=True, text=True)
    out = [[float(x) for x in line.split()[:3]] for line in p.stdout.splitlines() if line.strip()]
    if p.returncode or len(out) != len(rows):
        print("FAIL: cct failed:", p.stderr)
        sys.exit(1)
    return np.array(out)


def topocentric(lat, lon, h):
    return ("+proj=pipeline +step +proj=cart +ellps=WGS84 +step +proj=topocentric +ellps=WGS84 "
            f"+lat_0={lat!r} +lon_0={lon!r} +h_0={h!r}")


def describe_enu(site):
    """{id: (e, n, u)} from `site describe --landmarks`."""
    r = run("site", "describe", "--landmarks", site)
    check(r.returncode == 0, f"describe {site}: {r.stderr}")
    lines = r.stdout.splitlines()
    start = next((i for i, line in enumerate(lines) if line.startswith("landmarks (ENU")), len(lines))
    enu = {}
    for line in lines[start + 2:]:  # after the title and the column names
        f = line.split()
        enu[f[0]] = np.array([float(x) for x in f[1:4]])
    return enu


def site_origin(site):
    o = json.load(open(os.path.join(site, "site.json")))["origin"]
    return o["lat"], o["lon"], o["h"]


def check_enu(label, site, ids, lonlat_h, up_given):
    """The site's ENU of each landmark against cct at the site's origin, from (lon, lat, h)."""
    enu = describe_enu(site)
    oracle = cct(topocentric(*site_origin(site)), lonlat_h)
    worst = 0.0
    for i, lid in enumerate(ids):
        got = enu.get(lid)
        if got is None:
            check(False, f"{label}: landmark {lid} missing")
            continue
        d = got - oracle[i] if up_given else np.append(got[:2] - oracle[i][:2], got[2])  # modelled: up = 0
        worst = max(worst, float(np.abs(d).max()) if np.all(np.isfinite(d)) else math.inf)
    print(f"{label}: {len(ids)} landmarks, ENU vs PROJ (cct): worst {worst:.3g} m (tolerance {TOL_M} m)")
    check(worst <= TOL_M, f"{label}: ENU differs from PROJ by {worst} m (seed {SEED})")


def import_site(args, label):
    r = run("site", "import", *args)
    print(r.stdout.strip())
    check(r.returncode == 0, f"{label}: import failed: {r.stderr.strip()}")
    return r


def site_check(site, label):
    r = run("site", "check", site)
    check(r.returncode == 0 and "0 errors" in r.stdout, f"{label}: site check: {r.stdout.strip()}")


def in_site_frame(site, p_enu):
    """A point of ORIGIN's ENU frame in the site's (whose origin is the landmarks' centroid)."""
    lonlat_h = cct(topocentric(*ORIGIN), [p_enu], inverse=True)
    return cct(topocentric(*site_origin(site)), lonlat_h)[0]


def calibrate(site, cam, label, *args):
    r = run("calib", site, *args)
    check(r.returncode == 0, f"{label}: calib {' '.join(args)} failed: {r.stdout} {r.stderr}")
    path = os.path.join(site, "calib", cam + ".json")
    if not os.path.isfile(path):
        check(False, f"{label}: no {path}")
        return None
    res = json.load(open(path))
    check(all(math.isfinite(x) for x in res["rt_cam_enu"]), f"{label}: pose not finite")
    return res


# ---- a synthetic camera over ground points near ORIGIN ----

def synthetic(lens, intrinsics, size, rng, C=(2.0, -18.0, 7.0), yaw_deg=0.0, area=((-12, 14), (-8, 25))):
    """14 ground points (ENU up 0) in view of a camera at C (default (2, -18, 7)) looking yaw_deg from
    north, pitch -25 deg, drawn in area ((e0, e1), (n0, n1)): (ids, lon/lat/h rows from cct, pixels
    from mrcal.project, the camera's position)."""
    yaw, pitch = math.radians(yaw_deg), math.radians(-25)
    f = np.array([math.sin(yaw) * math.cos(pitch), math.cos(yaw) * math.cos(pitch), math.sin(pitch)])
    x = np.array([math.cos(yaw), -math.sin(yaw), 0])
    y = np.cross(f, x)
    R_cam_enu = np.stack([x, y, f])
    C = np.array(C)
    pts, q = [], []
    while len(pts) < 14:
        p = np.array([rng.uniform(*area[0]), rng.uniform(*area[1]), 0.0])
        pc = R_cam_enu @ (p - C)
        if pc[2] <= 1:
            continue
        qq = mrcal.project(pc, lens, intrinsics)
        if np.all(np.isfinite(qq)) and 20 < qq[0] < size[0] - 20 and 20 < qq[1] < size[1] - 20:
            pts.append(p)
            q.append(qq)
    llh = cct(topocentric(*ORIGIN), pts, inverse=True)  # lon lat h
    return [f"L{i + 1}" for i in range(len(pts))], llh, np.array(q), C


def case_json_fisheye(tmp, rng):
    size = (1280, 960)
    intr = np.array([340.0, 340.0, 640.0, 480.0] + [0.0] * 8)
    ids, llh, q, C = synthetic("LENSMODEL_CAHVORE_linearity=0.00", intr, size, rng)
    pairs = {"results": [{"x": float(q[i][0]), "y": float(q[i][1]), "lat": float(llh[i][1]), "lng": float(llh[i][0]),
                          "id": ids[i]} for i in range(len(ids))]}
    json.dump(pairs, open(os.path.join(tmp, "gate.json"), "w"), indent=1)
    cv2.imwrite(os.path.join(tmp, "gate.png"), np.zeros((size[1], size[0]), np.uint8))
    json.dump({"f": 340.0, "x0": 640, "y0": 480}, open(os.path.join(tmp, "lens.json"), "w"))
    r = run("site", "import", os.path.join(tmp, "other"), "--points", os.path.join(tmp, "gate.json"), "--intrinsics",
            os.path.join(tmp, "lens.json"), "--image-size", "1280x720")
    check(r.returncode == 1 and "gate.png: the image is 1280 x 960 px, --image-size says 1280 x 720" in r.stderr,
          f"json_fisheye: a size the image disagrees with: {r.stderr}")
    site = os.path.join(tmp, "site")
    import_site([site, "--points", os.path.join(tmp, "gate.json"), "--intrinsics", os.path.join(tmp, "lens.json")],
                "json_fisheye")
    site_check(site, "json_fisheye")
    model = mrcal.cameramodel(os.path.join(site, "cameras", "gate.cameramodel"))
    lens, got = model.intrinsics()
    check(lens == "LENSMODEL_CAHVORE_linearity=0.00" and np.array_equal(got, intr) and
          list(model.imagersize()) == list(size), f"json_fisheye: camera file {lens} {got} {model.imagersize()}")
    check_enu("json_fisheye", site, ids, [(r[0], r[1], 0.0) for r in llh], False)
    res = calibrate(site, "gate", "json_fisheye", "--refine", "focal")
    if res:
        C = in_site_frame(site, C)
        d = np.linalg.norm(np.array(res["position_enu_m"]) - C)
        print(f"json_fisheye: calibrated position {res['position_enu_m']}, truth {C.tolist()}: {d:.3g} m apart; "
              f"focal {res['intrinsics'][0]:.6f} px (truth 340)")
        check(d <= 0.01 and abs(res["intrinsics"][0] - 340) <= 0.01,
              f"json_fisheye: position {d} m from the truth, focal {res['intrinsics'][0]} (seed {SEED})")


def case_kb_two_cameras(tmp, rng):
    """Two cameras, one OpenCV fisheye YAML (Kannala-Brandt, k3 = k4 = 0) for both: the camera files
    are CAHVORE (fx, fy, cx, cy, 0, 0, 0, k1, k2, 0, 0, 0), ids prefixed, both poses recovered."""
    K, D = np.array([[352.5, 0, 641.5], [0, 350.25, 478.5], [0, 0, 1.0]]), [0.021, -0.0035, 0.0, 0.0]
    intr = np.array([352.5, 350.25, 641.5, 478.5, 0, 0, 0, D[0], D[1], 0, 0, 0])
    fs = cv2.FileStorage(os.path.join(tmp, "lens.yaml"), cv2.FILE_STORAGE_WRITE)
    for k, v in (("image_width", 1280), ("image_height", 960), ("camera_matrix", K),
                 ("distortion_coefficients", np.array(D).reshape(1, 4)), ("distortion_model", "fisheye")):
        fs.write(k, v)
    fs.release()
    args, truth = [], {}
    for name, C, yaw in (("east", (18.0, 1.0, 8.0), 270.0), ("south", (-1.0, -17.0, 6.5), 0.0)):
        ids, llh, q, C = synthetic("LENSMODEL_CAHVORE_linearity=0.00", intr, (1280, 960), rng, C, yaw,
                                   ((-25, 25), (-25, 25)))
        pairs = {"results": [{"x": float(q[i][0]), "y": float(q[i][1]), "lat": float(llh[i][1]),
                              "lng": float(llh[i][0]), "id": i} for i in range(len(ids))]}
        json.dump(pairs, open(os.path.join(tmp, name + ".json"), "w"))
        args += ["--points", os.path.join(tmp, name + ".json")]
        truth[name] = C
    site = os.path.join(tmp, "site")
    import_site([site, *args, "--intrinsics", os.path.join(tmp, "lens.yaml")], "kb_two_cameras")
    site_check(site, "kb_two_cameras")
    ids = [f["properties"]["id"] for f in json.load(open(os.path.join(site, "landmarks.geojson")))["features"]]
    check(ids[0] == "east:0" and ids[-1] == "south:13", f"kb_two_cameras: ids {ids[:2]} ... {ids[-2:]}")
    for name, C in truth.items():
        lens, got = mrcal.cameramodel(os.path.join(site, "cameras", name + ".cameramodel")).intrinsics()
        check(lens == "LENSMODEL_CAHVORE_linearity=0.00" and np.array_equal(got, intr),
              f"kb_two_cameras: {name}'s camera file {lens} {got}")
    calibrate(site, "east", "kb_two_cameras")
    for name, C in truth.items():
        res = json.load(open(os.path.join(site, "calib", name + ".json")))
        d = np.linalg.norm(np.array(res["position_enu_m"]) - in_site_frame(site, C))
        print(f"kb_two_cameras: {name}: calibrated position {d:.3g} m from the truth")
        check(d <= 0.01, f"kb_two_cameras: {name}: position {d} m from the truth (seed {SEED})")


def case_csv_latlon(tmp, rng):
    size = (1280, 960)
    intr = np.array([1280.0, 1280.0, 639.5, 479.5])
    ids, llh, q, C = synthetic("LENSMODEL_PINHOLE", intr, size, rng)
    path = os.path.join(tmp, "pole.csv")
    with open(path, "w") as f:
        f.write("id,lat,lon,u,v,h\n")
        for i, lid in enumerate(ids):
            f.write("%s,%.12f,%.12f,%.6f,%.6f,%.4f\n" % (lid, llh[i][1], llh[i][0], q[i][0], q[i][1], llh[i][2]))
    site = os.path.join(tmp, "site")
    import_site([site, "--points", path, "--image-size", "1280x960", "--source", "survey"], "csv_latlon")
    site_check(site, "csv_latlon")
    sj = json.load(open(os.path.join(site, "site.json")))
    check(sj["landmark_heights"] == "surveyed" and sj["landmark_sigma_m"] == {"horizontal": 0.01, "vertical": 0.02},
          f"csv_latlon: site.json {sj}")
    rounded = [(r[0], r[1], float("%.4f" % r[2])) for r in llh]
    check_enu("csv_latlon", site, ids, rounded, True)
    res = calibrate(site, "pole", "csv_latlon", "--refine", "focal")
    if res:
        C = in_site_frame(site, C)
        d = np.linalg.norm(np.array(res["position_enu_m"]) - C)
        print(f"csv_latlon: calibrated position {res['position_enu_m']}, truth {C.tolist()}: {d:.3g} m apart; "
              f"focal {res['intrinsics'][0]:.2f} px (truth 1280)")
        check(d <= 0.01, f"csv_latlon: position {d} m from the truth (seed {SEED})")


def case_aalborg(tmp):
    real = os.path.join(os.environ.get("ROADSIDE_SHARED", "/work/shared"), "real", "aalborg_roadside")
    if not all(os.path.isfile(os.path.join(real, f)) for f in ("pix.csv", "utm.csv", "frame.jpg")):
        print(f"skipped: {real} is absent")
        sys.exit(77)
    pix = [line.split(",") for line in open(os.path.join(real, "pix.csv")).read().split()]
    utm = [line.split(",") for line in open(os.path.join(real, "utm.csv")).read().split()]
    path = os.path.join(tmp, "aalborg.csv")
    with open(path, "w") as f:
        f.write("e,n,u,v\n" + "".join(f"{e},{n},{u},{v}\n" for (e, n), (u, v) in zip(utm, pix)))
    shutil.copy(os.path.join(real, "frame.jpg"), os.path.join(tmp, "aalborg.jpg"))
    site = os.path.join(tmp, "site")
    r = import_site([site, "--points", path, "--crs", "EPSG:25832"], "aalborg")
    check("--refine focal" in r.stdout, "aalborg: the summary does not say to refine the focal length")
    site_check(site, "aalborg")
    text = "".join(f"{e} {n}\n" for e, n in utm)
    p = subprocess.run(["cs2cs", "-d", "12", "EPSG:25832", "EPSG:4326"], input=text, capture_output=True, text=True)
    latlon = [[float(x) for x in line.split()[:2]] for line in p.stdout.splitlines()]
    check(p.returncode == 0 and len(latlon) == len(utm), f"aalborg: cs2cs failed: {p.stderr}")
    check_enu("aalborg", site, [f"P{i + 1}" for i in range(len(utm))], [(lon, lat, 0.0) for lat, lon in latlon], False)
    frame = os.path.join(site, "backgrounds", "aalborg", "frame.jpg")
    check(os.path.isfile(frame) and open(frame, "rb").read() == open(os.path.join(real, "frame.jpg"), "rb").read(),
          "aalborg: the frame beside the points is not backgrounds/aalborg/frame.jpg")
    model = mrcal.cameramodel(os.path.join(site, "cameras", "aalborg.cameramodel"))
    lens, intr = model.intrinsics()
    check(lens == "LENSMODEL_PINHOLE" and list(intr) == [1920, 1920, 959.5, 539.5] and
          list(model.imagersize()) == [1920, 1080], f"aalborg: nominal camera {lens} {intr} {model.imagersize()}")
    res = calibrate(site, "aalborg", "aalborg", "--refine", "focal")
    if res:
        print(f"aalborg: pose {res['position_enu_m']} m, yaw/pitch/roll {res['yaw_pitch_roll_deg']} deg, focal "
              f"{res['intrinsics'][0]:.0f} px, rms_surveyed {res['rms_surveyed_px']:.1f} px")


def case_readme(tmp):
    root = os.environ.get("ROADSIDE_SOURCE_ROOT", os.path.join(os.path.dirname(__file__), "..", ".."))
    readme = open(os.path.join(root, "README.md")).read()
    cmds = [line.split("#")[0].split() for line in readme.splitlines()
            if line.startswith(("roadside site import out/gate", "roadside calib out/gate"))]
    check(len(cmds) == 2, f"readme: the two commands not found in README.md: {cmds}")
    os.chdir(tmp)
    os.symlink(os.path.join(root, "sites"), "sites")
    for cmd in cmds:
        r = run(*cmd[1:])
        print(" ".join(cmd), "->", r.returncode)
        check(r.returncode == 0, f"readme: {' '.join(cmd)}: {r.stdout} {r.stderr}")
    path = os.path.join("out", "gate", "calib", "gate.json")
    if os.path.isfile(path):
        truth = cct(topocentric(*site_origin(os.path.join("out", "gate"))), [(-79.945596426, 40.442147901, 7.0)])[0]
        d = np.linalg.norm(np.array(json.load(open(path))["position_enu_m"]) - truth)
        print(f"readme: calibrated position {d:.3g} m from sites/import/README.md's camera")
        check(d <= 0.01, f"readme: position {d} m from the truth")


# ---- bad input ----

GOOD_ROWS = [(40.44231, -79.94562, 412, 380), (40.44241, -79.94552, 612, 420), (40.44221, -79.94572, 212, 500),
             (40.44251, -79.94582, 812, 300), (40.44211, -79.94542, 700, 700)]


def pairs_json(rows, drop=None):
    items = []
    for i, (lat, lng, x, y) in enumerate(rows):
        item = {"x": x, "y": y, "lat": lat, "lng": lng, "id": str(i)}
        if drop and i == 1:
            del item[drop]
        items.append(item)
    return '{"results": [\n' + ",\n".join(json.dumps(it) for it in items) + "\n]}\n"


def latlon_csv(rows):
    return "lat,lon,u,v\n" + "".join("%r,%r,%r,%r\n" % r for r in rows)


BAD = [
    # name, file name, content, extra arguments, expected message
    ("missing field", "p.json", pairs_json(GOOD_ROWS, drop="lat"), [], "p.json:3: results[1].lat: missing"),
    ("bad EPSG", "p.csv", latlon_csv(GOOD_ROWS), ["--crs", "EPSG:999999"], "--crs EPSG:999999: not a CRS GDAL knows"),
    ("NUL byte", "p.csv", latlon_csv(GOOD_ROWS).replace("412", "4\0" + "12"), [], "p.csv:2: a NUL byte"),
    ("not a number", "p.csv", latlon_csv(GOOD_ROWS).replace("612", "612px"), [], "p.csv:3: u: not a number ('612px')"),
    ("decimal comma", "p.csv", "lat;lon;u;v\n", [], "p.csv:1: header: unknown column"),
    ("no header", "p.csv", "40.1,-79.9,1,2\n", [], "p.csv:1: header: unknown column '40.1'"),
    ("e,n without a CRS", "p.csv", "e,n,u,v\n" + "559069.0,6319219.1,1,2\n" * 4, [], "give their CRS with --crs"),
    ("lat,lon in a projected CRS", "p.csv", latlon_csv(GOOD_ROWS), ["--crs", "EPSG:25832"],
     "lat,lon columns, but --crs EPSG:25832 is a projected CRS"),
    ("e,n in a geographic CRS", "p.csv", "e,n,u,v\n" + "559069.0,6319219.1,1,2\n" * 4, ["--crs", "EPSG:4326"],
     "e,n columns, but --crs EPSG:4326 is a geographic CRS"),
    ("a point PROJ cannot transform", "p.csv", "e,n,u,v\n559069,6319219,1,2\n1e9,6319219,1,2\n" + "559069,6319219,3,4\n" * 2,
     ["--crs", "EPSG:25832"], "p.csv:3: e,n: (1000000000, 6319219) of EPSG:25832: PROJ cannot transform it"),
    ("latitude out of range", "p.csv", latlon_csv(GOOD_ROWS).replace("40.44241", "140.44241"), [],
     "p.csv:3: lat: 140.44241 is outside [-90, 90]"),
    ("too few points", "p.csv", latlon_csv(GOOD_ROWS[:3]), [], "p.csv: 3 points: a camera needs at least 4"),
    ("repeated id", "p.json", pairs_json(GOOD_ROWS).replace('"id": "2"', '"id": "1"'), [],
     "p.json:4: results[2].id: '1' repeated (first at line 3)"),
    ("no image size", "p.csv", latlon_csv(GOOD_ROWS), [], "no image size"),
    ("pixel outside the image", "p.csv", latlon_csv(GOOD_ROWS).replace("812", "1812"), ["--image-size", "1280x960"],
     "would not pass 'site check': "),
]


def case_bad_input(tmp):
    for name, fname, content, extra, expected in BAD:
        d = tempfile.mkdtemp(dir=tmp)
        path = os.path.join(d, fname)
        open(path, "w").write(content)
        size = [] if name == "no image size" or "--image-size" in extra else ["--image-size", "1280x960"]
        r = run("site", "import", os.path.join(d, "site"), "--points", path, *size, *extra)
        left = sorted(os.listdir(d))
        ok = r.returncode == 1 and expected in r.stderr and left == [fname]
        print(f"{name}: exit {r.returncode}: {r.stderr.strip()}")
        check(ok, f"bad input '{name}': exit {r.returncode}, stderr {r.stderr.strip()!r}, expected {expected!r}, "
                  f"folder holds {left}")
    # an existing site is replaced only with --force, and a folder that is not a site never
    d = tempfile.mkdtemp(dir=tmp)
    path = os.path.join(d, "p.csv")
    open(path, "w").write(latlon_csv(GOOD_ROWS))
    site = os.path.join(d, "site")
    args = ["site", "import", site, "--points", path, "--image-size", "1280x960"]
    check(run(*args).returncode == 0, "import into a new folder failed")
    r = run(*args)
    check(r.returncode == 1 and "not overwriting it" in r.stderr, f"import over a site without --force: {r.stderr}")
    r = run(*args, "--force", "--name", "again")
    check(r.returncode == 0 and json.load(open(os.path.join(site, "site.json")))["name"] == "again",
          f"--force did not replace the site: {r.stderr}")
    other = os.path.join(d, "other")
    os.mkdir(other)
    open(os.path.join(other, "keep.txt"), "w").write("mine")
    r = run("site", "import", other, "--points", path, "--image-size", "1280x960", "--force")
    check(r.returncode == 1 and os.listdir(other) == ["keep.txt"], f"--force on a folder that is not a site: {r.stderr}")
    check(sorted(os.listdir(d)) == ["other", "p.csv", "site"], f"left behind: {sorted(os.listdir(d))}")


def main():
    case = sys.argv[1]
    rng = np.random.default_rng(SEED)
    tmp = tempfile.mkdtemp(prefix="rs_site_import_")
    try:
        if case == "aalborg":
            case_aalborg(tmp)
        elif case == "json_fisheye":
            case_json_fisheye(tmp, rng)
        elif case == "kb_two_cameras":
            case_kb_two_cameras(tmp, rng)
        elif case == "csv_latlon":
            case_csv_latlon(tmp, rng)
        elif case == "readme":
            case_readme(tmp)
        elif case == "bad_input":
            case_bad_input(tmp)
        else:
            check(False, f"unknown case {case}")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    finish(f"test_site_import {case}")


if __name__ == "__main__":
    main()

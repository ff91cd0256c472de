#!/usr/bin/env python3
"""Issue 16: nothing could be opened in QGIS. `roadside export` writes the cameras, their ground
footprints, the landmarks (one row each), the picks with residuals and flags, and the lanes as a
GeoPackage / GeoJSON, and the ground uncertainty map as a GeoTIFF; GDAL's own tools read them
back here. Issue 41: ogrinfo finds a QGIS style per layer in layer_styles (its QML parsed by
Python's XML parser: footprints by verdict, picks/landmarks on the leave-one-out ramp) and every
layer's description; gdalsrsinfo names the GeoTIFF's CRS with its unit; `-o new/dir/x.gpkg`
creates the folders; `--crs` prints nothing on stderr.

Oracles (independent of roadside's GDAL calls):
- ogr2ogr (GDAL's reader) converts the GeoPackage back to GeoJSON; each camera's point equals
  <id>.json's position_llh to 1 mm (degrees converted to metres on the WGS84 ellipsoid), and its
  height too; each landmark's point, taken through PROJ's cct (cart + topocentric at the site's
  origin), equals <id>.json's p_enu_surveyed_m to 1 mm; its residuals equal <id>.json's;
- with --crs EPSG:32632 the GeoJSON's camera points equal cct's UTM 32N of position_llh to 1 mm;
- gdalinfo -json reads the GeoTIFF's size, geotransform and CRS; gdallocationinfo reads the value
  at each camera's landmarks' cells, which equals the smallest of the cameras' maps in their
  <id>.audit.json (`roadside audit` with the same options) at that cell, to float32 precision;
- every camera's footprint polygon contains (ogr point-in-polygon by GDAL's own SQLite dialect is
  not needed: a ray-casting test here) the inlier landmarks it sees within range;
- the .cameramodel and .opencv.yaml carry the site origin in their comments, <id>.json its
  enu_origin; an unknown CRS and a bad extension exit 1 and leave no file.
"""
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "common"))
import rs_check  # noqa: E402
from rs_check import check, finish  # noqa: E402

SOURCE = os.environ["ROADSIDE_SOURCE_ROOT"]
CAMS = ["cam1", "cam2", "cam3", "cam4"]
TOL_M = 1e-3


def tool(*args):
    return subprocess.run(list(args), capture_output=True, text=True)


def metres_between(lon0, lat0, lon1, lat1):
    """Small horizontal distance on WGS84 (meridian and prime-vertical radii)."""
    a, f = 6378137.0, 1 / 298.257223563
    e2 = f * (2 - f)
    la = math.radians(lat0)
    w = math.sqrt(1 - e2 * math.sin(la) ** 2)
    m = a * (1 - e2) / w ** 3
    n = a / w
    return math.hypot(math.radians(lat1 - lat0) * m, math.radians(lon1 - lon0) * n * math.cos(la))


def features(path, layer=None):
    args = ["ogr2ogr", "-f", "GeoJSON", "/vsistdout/", path] + ([layer] if layer else [])
    p = tool(*args)
    check(p.returncode == 0, f"ogr2ogr {path} {layer}: {p.stderr}")
    return json.loads(p.stdout)["features"] if p.returncode == 0 else []


def cct(pipeline, pts):
    p = subprocess.run(["cct", "-d", "9"] + pipeline.split(), input="".join(f"{x} {y} {z} 0\n" for x, y, z in pts),
                       capture_output=True, text=True)
    check(p.returncode == 0, f"cct {pipeline}: {p.stderr}")
    return [list(map(float, line.split()[:3])) for line in p.stdout.strip().splitlines()]


def inside(poly, x, y):
    c = False
    for (x0, y0), (x1, y1) in zip(poly, poly[1:] + poly[:1]):
        if (y0 > y) != (y1 > y) and x < x0 + (y - y0) * (x1 - x0) / (y1 - y0):
            c = not c
    return c


def main():
    tmp = tempfile.mkdtemp(prefix="roadside-gis-")
    site = os.path.join(tmp, "site")
    shutil.copytree(os.path.join(SOURCE, "sites", "demo"), site)
    calib = os.path.join(tmp, "calib")
    p = rs_check.run("calib", site, "-o", calib)
    check(p.returncode == 0, f"calib: {p.stderr}")
    js = {c: json.load(open(os.path.join(calib, c + ".json"))) for c in CAMS}
    origin = js["cam1"].get("enu_origin", {})
    check(all(k in origin for k in ("lat_deg", "lon_deg", "h_m", "frame")), f"<id>.json enu_origin: {origin}")
    for c in CAMS:
        model = open(os.path.join(calib, c + ".cameramodel")).read()
        yaml = open(os.path.join(calib, c + ".opencv.yaml")).read()
        check(f"enu_origin: lat {origin['lat_deg']:.9f}" in model and "ENU" in model, f"{c}.cameramodel: no origin")
        check(yaml.startswith("%YAML:1.0\n---\n# roadside calib") and "rvec, tvec and R_cam_enu map site ENU" in yaml,
              f"{c}.opencv.yaml: no frame comment: {yaml[:300]}")

    gpkg, gj, tif = os.path.join(tmp, "site.gpkg"), os.path.join(tmp, "site.geojson"), os.path.join(tmp, "u.tif")
    p = rs_check.run("export", site, "--calib", calib, "-o", gpkg, "--uncertainty", tif)
    check(p.returncode == 0, f"export gpkg: exit {p.returncode}: {p.stderr}")
    print(p.stdout.strip())

    # cameras against <id>.json to 1 mm
    cams = {f["properties"]["camera"]: f for f in features(gpkg, "cameras")}
    check(sorted(cams) == CAMS, f"cameras layer: {sorted(cams)}")
    worst = 0
    for c, f in cams.items():
        lon, lat, h = f["geometry"]["coordinates"]
        jlat, jlon, jh = js[c]["position_llh"]
        d = max(metres_between(jlon, jlat, lon, lat), abs(h - jh))
        worst = max(worst, d)
        check(d <= TOL_M, f"{c}: exported point {lon, lat, h} is {d * 1000:.3f} mm from <id>.json's {jlon, jlat, jh}")
        pr = f["properties"]
        check(abs(pr["heading_deg"] - js[c]["yaw_pitch_roll_deg"][0]) < 1e-9 and
              abs(pr["sigma_east_m"] - js[c]["sigma_position_enu_m"][0]) < 1e-9 and pr["verdict"] in ("pass", "FAIL"),
              f"{c}: fields {pr}")
    print(f"cameras: worst {worst * 1000:.4f} mm from <id>.json")

    # picks through PROJ's cct into ENU, against p_enu_surveyed_m
    topo = (f"+proj=pipeline +step +proj=cart +ellps=WGS84 +step +proj=topocentric +ellps=WGS84 "
            f"+lat_0={origin['lat_deg']!r} +lon_0={origin['lon_deg']!r} +h_0={origin['h_m']!r}")
    lms = features(gpkg, "picks")
    enu = cct(topo, [f["geometry"]["coordinates"] for f in lms])
    worst, n = 0, 0
    for f, e in zip(lms, enu):
        pr = f["properties"]
        want = next(x for x in js[pr["camera"]]["landmarks"] if x["id"] == pr["landmark"])
        d = math.dist(e, want["p_enu_surveyed_m"])
        worst, n = max(worst, d), n + 1
        check(d <= TOL_M, f"{pr['camera']} {pr['landmark']}: {d * 1000:.3f} mm from p_enu_surveyed_m")
        r = want["residual_surveyed_px"]
        check(r is None or (abs(pr["residual_u_px"] - r[0]) < 1e-9 and abs(pr["residual_v_px"] - r[1]) < 1e-9),
              f"{pr['landmark']}: residuals {pr['residual_u_px']}, {pr['residual_v_px']} vs {r}")
        check(bool(pr["inlier"]) == want["inlier"], f"{pr['landmark']}: inlier flag")
    check(n == sum(len(js[c]["landmarks"]) for c in CAMS), f"picks layer: {n} features")
    check(any(not f["properties"]["inlier"] and f["properties"]["flag"] for f in lms), "an outlier with its flag")
    print(f"picks: {n}, worst {worst * 1000:.4f} mm from p_enu_surveyed_m (cct)")

    # landmarks: one feature per landmark picked, its picks counted as <id>.json lists them
    want_picks = {}
    for c in CAMS:
        for x in js[c]["landmarks"]:
            want_picks.setdefault(x["id"], []).append((c, x["inlier"], x["p_enu_surveyed_m"]))
    one = features(gpkg, "landmarks")
    ids = [f["properties"]["landmark"] for f in one]
    check(len(ids) == len(set(ids)) and set(ids) == set(want_picks), f"landmarks layer: {len(ids)} rows for "
          f"{len(want_picks)} landmarks picked")
    for f, e in zip(one, cct(topo, [f["geometry"]["coordinates"] for f in one])):
        pr = f["properties"]
        w = want_picks.get(pr["landmark"], [])
        check(pr["n_picks"] == len(w) and pr["n_inliers"] == sum(i for _, i, _ in w) and
              sorted(pr["cameras"].split(", ")) == sorted(c for c, _, _ in w), f"landmark {pr['landmark']}: {pr}")
        check(w and math.dist(e, w[0][2]) <= TOL_M, f"landmark {pr['landmark']}: position off (cct)")
    print(f"landmarks: {len(ids)} rows, one per landmark")

    # styles and descriptions, read by ogrinfo (GDAL's own reader)
    p = tool("ogrinfo", "-ro", "-q", "-sql", "SELECT f_table_name, f_geometry_column, useAsDefault, styleQML FROM "
             "layer_styles", gpkg)
    check(p.returncode == 0, f"ogrinfo layer_styles: {p.stderr}")
    import xml.etree.ElementTree as ET
    styled = {}
    for block in p.stdout.split("OGRFeature(")[1:]:
        name = block.split("f_table_name (String) = ")[1].split("\n")[0]
        qml = block.split("styleQML (String) = ")[1].strip()
        root = ET.fromstring(qml.split("\n", 1)[1])  # after the DOCTYPE line
        r = root.find("renderer-v2")
        styled[name] = (r.get("type"), r.get("attr"), "useAsDefault (Integer(Boolean)) = 1" in block)
    print("styles:", styled)
    check(styled.get("footprints", ("", "", False)) == ("categorizedSymbol", "verdict", True), "footprints style")
    check(styled.get("cameras", ("", "", False))[1] == "verdict", "cameras style")
    for layer in ("landmarks", "picks"):
        check(styled.get(layer, ("", "", False))[:2] == ("graduatedSymbol", "loo_ground_error_m"), f"{layer} style")
    for layer in ("cameras", "footprints", "landmarks", "picks", "lanes"):
        p = tool("ogrinfo", "-ro", "-so", gpkg, layer)
        d = [line for line in p.stdout.splitlines() if line.strip().startswith("DESCRIPTION=")]
        check(d and len(d[0]) > 40, f"{layer}: no description in ogrinfo -so: {p.stdout[:300]}")

    # footprints contain the inliers within range
    for f in features(gpkg, "footprints"):
        c = f["properties"]["camera"]
        ring = [tuple(x[:2]) for x in f["geometry"]["coordinates"][0]]
        pts = [g["geometry"]["coordinates"] for g in lms if g["properties"]["camera"] == c and g["properties"]["inlier"]]
        nin = sum(inside(ring, x, y) for x, y, _ in pts)
        check(nin == len(pts), f"{c}: footprint holds {nin} of its {len(pts)} inlier landmarks")
    check(len(features(gpkg, "lanes")) > 0, "lanes layer empty")

    # GeoJSON in UTM 32N against cct's UTM of position_llh
    p = rs_check.run("export", site, "--calib", calib, "-o", gj, "--crs", "EPSG:32632")
    check(p.returncode == 0, f"export geojson: {p.stderr}")
    fs = features(gj)
    cams = {f["properties"]["camera"]: f for f in fs if f["properties"]["layer"] == "cameras"}
    utm = cct("+proj=utm +zone=32 +ellps=WGS84", [(js[c]["position_llh"][1], js[c]["position_llh"][0], 0) for c in CAMS])
    for c, u in zip(CAMS, utm):
        x, y = cams[c]["geometry"]["coordinates"][:2]
        d = math.hypot(x - u[0], y - u[1])
        check(d <= TOL_M, f"{c}: UTM {x, y} is {d * 1000:.3f} mm from cct's {u[:2]}")
    check({f["properties"]["layer"] for f in fs} == {"cameras", "footprints", "landmarks", "picks", "lanes"},
          "GeoJSON layers")

    # the GeoTIFF against the audits' maps
    info = json.loads(tool("gdalinfo", "-json", tif).stdout)
    check("Orthographic" in info["coordinateSystem"]["wkt"], "GeoTIFF CRS: the site's orthographic ENU grid")
    p = tool("gdalsrsinfo", "-o", "wkt2", tif)  # the CRS named, its unit metres
    head = p.stdout.strip().splitlines()[0] if p.stdout.strip() else ""
    print("gdalsrsinfo:", head)
    check(head.startswith('PROJCRS["roadside site ENU at') and 'LENGTHUNIT["metre",1' in p.stdout,
          f"GeoTIFF CRS unnamed or without a unit: {p.stdout[:300]}")
    audit_dir = os.path.join(tmp, "audit")
    rs_check.run("audit", site, "--calib", calib, "-o", audit_dir)
    maps = [json.load(open(os.path.join(audit_dir, c + ".audit.json")))["uncertainty_map"] for c in CAMS]

    def best(e, n):
        v = math.inf
        for m in maps:
            ix, iy = round((e - m["e0_m"]) / m["cell_m"]), round((n - m["n0_m"]) / m["cell_m"])
            if 0 <= ix < m["nx"] and 0 <= iy < m["ny"] and m["sigma_m"][iy][ix] is not None:
                v = min(v, m["sigma_m"][iy][ix])
        return v

    m0 = maps[0]
    checked = 0
    for c in CAMS:
        for x in js[c]["landmarks"]:
            e, n = x["p_enu_surveyed_m"][:2]
            # the cell centre nearest the landmark on the maps' common 1 m grid
            e = m0["e0_m"] + round((e - m0["e0_m"]) / m0["cell_m"]) * m0["cell_m"]
            n = m0["n0_m"] + round((n - m0["n0_m"]) / m0["cell_m"]) * m0["cell_m"]
            p = tool("gdallocationinfo", "-valonly", "-geoloc", tif, repr(e), repr(n))
            want = best(e, n)
            if not math.isfinite(want):
                continue
            got = float(p.stdout.strip())
            check(abs(got - want) <= 1e-6 * max(1, want), f"GeoTIFF at E {e} N {n}: {got}, the audits' best {want}")
            checked += 1
    check(checked >= 20, f"only {checked} GeoTIFF cells checked")
    print(f"GeoTIFF {info['size']}: {checked} cells equal the audits' best map")

    # bad input: exit 1, nothing written
    bad = os.path.join(tmp, "bad.gpkg")
    p = rs_check.run("export", site, "--calib", calib, "-o", bad, "--crs", "EPSG:999999")
    check(p.returncode == 1 and "EPSG:999999" in p.stderr and not os.path.exists(bad), f"unknown CRS: {p.stderr}")
    p = rs_check.run("export", site, "--calib", calib, "-o", os.path.join(tmp, "x.shp"))
    check(p.returncode == 1 and ".gpkg" in p.stderr and not os.path.exists(os.path.join(tmp, "x.shp")),
          f"bad extension: {p.stderr}")
    p = rs_check.run("export", site, "--calib", calib)
    check(p.returncode == 2, "no output: usage error")
    # the output's folders are created; GDAL prints nothing of its own
    deep = os.path.join(tmp, "new", "dir", "x.gpkg")
    p = rs_check.run("export", site, "--calib", calib, "-o", deep, "--crs", "EPSG:32632", "--uncertainty",
                     os.path.join(tmp, "new2", "u.tif"))
    check(p.returncode == 0 and os.path.isfile(deep) and os.path.isfile(os.path.join(tmp, "new2", "u.tif")),
          f"export into new folders: {p.stderr}")
    check("ERROR" not in p.stderr and p.stderr == "", f"export --crs printed on stderr: {p.stderr}")
    shutil.rmtree(tmp)
    finish("GIS export")


if __name__ == "__main__":
    main()

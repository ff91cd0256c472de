#!/usr/bin/env python3
"""roadside ortho: the digital twin's orthophoto falls where its GeoTIFF's georeference says.

Oracle: GDAL's own gdalinfo (the geotransform and the CRS as it reads them back) and PROJ's cs2cs
(lanes.geojson's WGS84 vertices into that CRS) -- neither goes through roadside's geodesy
(GeographicLib) or its grid code. At the midpoint of every lane segment, both lane edges carry a
white marking 0.15 m wide (the twin's scene); the brightness profile across each edge, read from
the file GDAL wrote, must peak at the predicted position.
Tolerance: 0.6 cell (0.06 m at the 0.1 m GSD used): the markings are rendered without
antialiasing, so a stripe's rendered centre can be off by up to half a cell from its true one.
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from rs_check import check, finish, run  # noqa: E402

SRC = os.environ["ROADSIDE_SOURCE_ROOT"]
GSD = 0.1
TOL_CELLS = 0.6


def main():
    with tempfile.TemporaryDirectory() as tmp:
        site = os.path.join(tmp, "demo")
        shutil.copytree(os.path.join(SRC, "sites", "demo"), site)
        tif = os.path.join(tmp, "ortho.tif")
        r = run("ortho", site, "-o", tif, "--gsd", str(GSD), "--margin", "2")
        if not check(r.returncode == 0, f"roadside ortho failed: {r.stderr}"):
            finish("pick_ortho")
        info = json.loads(subprocess.run(["gdalinfo", "-json", tif], capture_output=True, text=True,
                                         check=True).stdout)
        gt = info["geoTransform"]
        W, H = info["size"]
        check(abs(gt[1] - GSD) < 1e-12 and abs(gt[5] + GSD) < 1e-12 and gt[2] == 0 and gt[4] == 0,
              f"geotransform {gt}: expected north-up {GSD} m cells")
        check(len(info["bands"]) == 3, "expected 3 bands (RGB)")
        proj4 = subprocess.run(["gdalsrsinfo", "-o", "proj4", tif], capture_output=True, text=True,
                               check=True).stdout.strip().strip("'")
        check("+proj=ortho" in proj4 and "+lat_0=48.1374" in proj4 and "+lon_0=11.5755" in proj4,
              f"CRS {proj4}: expected the orthographic projection at the site origin")
        # band 1 as raw bytes, through GDAL's own translation
        raw = os.path.join(tmp, "b1.raw")
        subprocess.run(["gdal_translate", "-q", "-of", "ENVI", "-b", "1", tif, raw], check=True)
        img = np.fromfile(raw, dtype=np.uint8).reshape(H, W).astype(float)

        lanes = json.load(open(os.path.join(site, "lanes.geojson")))["features"]
        pts, widths = [], []
        for f in lanes:
            if f["properties"].get("kind") == "junction":
                continue
            c = f["geometry"]["coordinates"]
            for a, b in zip(c[:-1], c[1:]):
                pts.append((a[0], a[1]))
                pts.append((b[0], b[1]))
                widths.append(f["properties"]["width_m"])
        text = "\n".join(f"{lon:.12f} {lat:.12f}" for lon, lat in pts) + "\n"
        out = subprocess.run(["cs2cs", "-f", "%.6f", "+proj=longlat", "+ellps=WGS84", "+to", *proj4.split()],
                             input=text, capture_output=True, text=True, check=True).stdout.split("\n")
        xy = np.array([[float(v) for v in line.split()[:2]] for line in out if line.strip()])

        def sample(x, y):
            # pixel centres: col = (x - gt0)/gt1 - 0.5; bilinear
            cf, rf = (x - gt[0]) / gt[1] - 0.5, (y - gt[3]) / gt[5] - 0.5
            c0, r0 = int(np.floor(cf)), int(np.floor(rf))
            if c0 < 0 or r0 < 0 or c0 + 1 >= W or r0 + 1 >= H:
                return np.nan
            fc, fr = cf - c0, rf - r0
            return ((1 - fc) * (1 - fr) * img[r0, c0] + fc * (1 - fr) * img[r0, c0 + 1] +
                    (1 - fc) * fr * img[r0 + 1, c0] + fc * fr * img[r0 + 1, c0 + 1])

        offsets = np.arange(-0.25, 0.2501, 0.005)
        worst, n = 0.0, 0
        for k, w in enumerate(widths):
            a, b = xy[2 * k], xy[2 * k + 1]
            d = b - a
            L = np.hypot(*d)
            if L < 2:
                continue
            left = np.array([-d[1], d[0]]) / L
            mid = 0.5 * (a + b)
            for side in (+1, -1):
                edge = mid + side * 0.5 * w * left
                prof = np.array([sample(*(edge + o * left)) for o in offsets])
                base = np.nanmedian(np.array([sample(*(edge + o * left)) for o in (-0.6, -0.5, 0.5, 0.6)]))
                wgt = np.clip(prof - base - 40, 0, None)
                if not check(np.nansum(wgt) > 0, f"lane segment {k} side {side}: no marking near {edge}"):
                    continue
                centre = float(np.nansum(wgt * offsets) / np.nansum(wgt))
                worst = max(worst, abs(centre))
                n += 1
                check(abs(centre) <= TOL_CELLS * GSD,
                      f"lane segment {k} side {side}: marking centre {centre:+.4f} m off the predicted edge "
                      f"(tolerance {TOL_CELLS * GSD} m)")
        check(n >= 16, f"only {n} marking profiles measured")
        print(f"{n} marking edges: worst offset {worst:.4f} m ({worst / GSD:.2f} cells)")
    finish("pick_ortho")


if __name__ == "__main__":
    main()

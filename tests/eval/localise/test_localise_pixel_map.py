#!/usr/bin/env python3
"""`roadside export SITE --pixel-map OUT.tif|OUT.npz --camera ID`: every pixel's ground point.

Site: `roadside site simulate --seed SEED --cameras 1 --image 160x90`, calibrated by
`roadside calib`. Checks:
  - the .npz (numpy.load) holds x_map, y_map, lat_map, lon_map, sigma_map of shape (90, 160),
    float64; the GeoTIFF (GDAL's Python) holds the same five bands, value for value;
  - on every 7th pixel, x_map/y_map agree with mrcal's Python (unproject, ray meets the plane
    U = 0) within 1e-6 m, and are NaN exactly where that ray misses the ground;
  - the same pixels as detections (`roadside localise`, bottom_center = the pixel): e, n,
    lat, lon and sqrt(sigma_e^2 + sigma_n^2) equal the map's (1e-9 relative);
  - a wrong extension, a camera the site lacks: exit 2, nothing written.
"""
import json
import math
import os
import sys
import tempfile

import mrcal
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from localise_common import check, cleanup, ground_point, read_csv, run, simulate_and_calibrate  # noqa: E402
from rs_check import finish, need  # noqa: E402

SEED = 9
W, H = 160, 90


def main():
    (gdal,) = need("osgeo.gdal")
    tmp = tempfile.mkdtemp(prefix="roadside-localise-pixel-map-")
    try:
        site, calib = simulate_and_calibrate(tmp, SEED, 1, ("--image", f"{W}x{H}"))
        model = mrcal.cameramodel(os.path.join(calib, "cam1.cameramodel"))
        tif, npz = os.path.join(tmp, "map.tif"), os.path.join(tmp, "map.npz")
        for out in (tif, npz):
            p = run("export", site, "--calib", calib, "--pixel-map", out, "--camera", "cam1")
            check(p.returncode == 0 and os.path.exists(out), f"{out}: exit {p.returncode}: {p.stderr}")
            print(p.stdout.strip())
        z = np.load(npz)
        names = ["x_map", "y_map", "lat_map", "lon_map", "sigma_map"]
        check(sorted(z.files) == sorted(names), f"npz arrays {z.files}")
        for n in names:
            check(z[n].shape == (H, W) and z[n].dtype == np.float64, f"{n}: {z[n].shape} {z[n].dtype}")
        ds = gdal.Open(tif)
        check(ds.RasterCount == 5 and ds.RasterXSize == W and ds.RasterYSize == H, "GeoTIFF: 5 bands of W x H")
        for k, n in enumerate(names):
            band = ds.GetRasterBand(k + 1).ReadAsArray()
            check(np.array_equal(band, z[n], equal_nan=True), f"GeoTIFF band {k + 1} differs from {n}")
        ds = None

        worst, nan_mismatch, pixels = 0.0, 0, []
        for v in range(0, H, 7):
            for u in range(0, W, 7):
                g = ground_point(model, [u, v])
                if g is None or not math.isfinite(z["x_map"][v, u]):
                    nan_mismatch += (g is None) != (not math.isfinite(z["x_map"][v, u]))
                    continue
                worst = max(worst, abs(g[0] - z["x_map"][v, u]), abs(g[1] - z["y_map"][v, u]))
                pixels.append((u, v))
        check(worst < 1e-6, f"x_map, y_map against mrcal's Python: {worst:.2e} m")
        check(nan_mismatch == 0, f"{nan_mismatch} pixels NaN on one side only")
        check(len(pixels) > 100, f"{len(pixels)} ground pixels sampled")

        dets = [{"image_id": 1, "category_id": 1, "bbox": [u, v, 0, 0], "score": 1, "bottom_center": [u, v]}
                for u, v in pixels]
        dpath, out = os.path.join(tmp, "dets.json"), os.path.join(tmp, "px.csv")
        json.dump(dets, open(dpath, "w"))
        p = run("localise", dpath, "--site", site, "--calib", calib, "--camera", "cam1", "-o", out)
        check(p.returncode == 0, f"localise: {p.stderr}")
        rel = 0.0
        for r, (u, v) in zip(read_csv(out), pixels):
            pairs = ((float(r["e_m"]), z["x_map"][v, u]), (float(r["n_m"]), z["y_map"][v, u]),
                     (float(r["lat_deg"]), z["lat_map"][v, u]), (float(r["lon_deg"]), z["lon_map"][v, u]),
                     (math.hypot(float(r["sigma_e_m"]), float(r["sigma_n_m"])), z["sigma_map"][v, u]))
            rel = max(rel, max(abs(a - b) / max(1.0, abs(b)) for a, b in pairs))
        check(rel < 1e-9, f"the map against localise's rows: {rel:.2e} (relative)")
        print(f"{len(pixels)} pixels: the map against mrcal's Python within {worst:.2e} m, against "
              f"localise within {rel:.1e}; {int(np.isfinite(z['x_map']).sum())} of {W * H} pixels see the ground")

        bad = os.path.join(tmp, "map.png")
        p = run("export", site, "--calib", calib, "--pixel-map", bad, "--camera", "cam1")
        check(p.returncode == 2 and not os.path.exists(bad), f"wrong extension: {p.returncode} {p.stderr!r}")
        p = run("export", site, "--calib", calib, "--pixel-map", npz + "2.npz", "--camera", "cam9")
        check(p.returncode == 2 and "cam9" in p.stderr and not os.path.exists(npz + "2.npz"),
              f"unknown camera: {p.returncode} {p.stderr!r}")
    finally:
        cleanup(tmp)
    finish("localise_pixel_map")


if __name__ == "__main__":
    main()

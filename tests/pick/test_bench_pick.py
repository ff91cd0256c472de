#!/usr/bin/env python3
"""`roadside bench pick` runs on a small size and writes its CSV: one row per size, the median not
above the 90th percentile, every re-solve giving a pose; with --ortho (a small UTM GeoTIFF made
by GDAL's Python) it prints the tile figures (a program that measures; nothing timed is
asserted)."""
import csv
import os
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from rs_check import check, finish, run  # noqa: E402

with tempfile.TemporaryDirectory() as tmp:
    out = os.path.join(tmp, "pick.csv")
    r = run("bench", "pick", "--landmarks", "8,12", "--clicks", "5", "--csv", out, "--dir", tmp)
    check(r.returncode == 0, f"bench pick: {r.stdout}{r.stderr}")
    rows = list(csv.DictReader(open(out))) if os.path.exists(out) else []
    check([int(x["landmarks"]) for x in rows] == [8, 12], f"rows: {rows}")
    for x in rows:
        check(0 < float(x["median_ms"]) <= float(x["p90_ms"]), f"median <= p90: {x}")
        check(int(x["failed"]) == 0 and int(x["picks"]) >= 4, f"every re-solve gave a pose: {x}")
    # --ortho: a 3000 x 3000 px UTM GeoTIFF around the simulated site's origin (bench's own: 48.1374, 11.5755)
    from osgeo import gdal, osr
    gdal.UseExceptions()
    wgs, utm = osr.SpatialReference(), osr.SpatialReference()
    wgs.ImportFromEPSG(4326)
    wgs.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    utm.ImportFromEPSG(32632)
    x, y, _ = osr.CoordinateTransformation(wgs, utm).TransformPoint(11.5755, 48.1374)
    tif = os.path.join(tmp, "o.tif")
    ds = gdal.GetDriverByName("GTiff").Create(tif, 3000, 3000, 3, gdal.GDT_Byte, ["TILED=YES", "COMPRESS=DEFLATE"])
    ds.SetProjection(utm.ExportToWkt())
    ds.SetGeoTransform([x - 150, 0.1, 0, y + 150, 0, -0.1])
    ds = None
    r = run("bench", "pick", "--landmarks", "8", "--clicks", "2", "--dir", tmp, "--ortho", tif)
    check(r.returncode == 0 and "its own pixels (level 0)" in r.stdout and "before issue 41" in r.stdout,
          f"bench pick --ortho: {r.stdout}{r.stderr}")
finish("pick_bench_runs")

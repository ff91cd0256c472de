#!/usr/bin/env python3
# roadside bench synth --quick: the benchmark runs end to end on the demo site (backgrounds
# rendered first), prints its table and writes its CSV; both variants made the same 8 images
# (same vehicles per image: the workers change the time, not the images).
import csv
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(__file__))
import synth_test_util as u  # noqa: E402


def main():
    u.need_povray()
    import shutil
    with tempfile.TemporaryDirectory() as tmp:
        site = os.path.join(tmp, "site")
        shutil.copytree(u.DEMO, site)
        calib = os.path.join(tmp, "calib")
        u.run(["calib", site, "-o", calib])
        u.run(["site", "render-backgrounds", site, "--calib", calib,
               "--camera", "cam1", "--times", "2024-06-21T09:00+02:00", "--weather", "sunny"])
        out = os.path.join(tmp, "bench.csv")
        p = u.run(["bench", "synth", site, "--calib", calib, "--quick", "--size", "320x180",
                   "--csv", out])
        print(p.stdout)
        rows = list(csv.DictReader(open(out)))
        if [r["variant"] for r in rows] != ["all", "jobs=1"]:
            u.fail("variants: %s" % [r["variant"] for r in rows])
        for r in rows:
            if int(r["images"]) != 8 or not float(r["s_per_image"]) > 0:
                u.fail("row %s: %s" % (r["variant"], r))
        if rows[0]["vehicles_per_image"] != rows[1]["vehicles_per_image"]:
            u.fail("the variants made different images: %s vs %s vehicles per image" %
                   (rows[0]["vehicles_per_image"], rows[1]["vehicles_per_image"]))
        if not float(rows[0]["vehicles_per_image"]) >= 3:
            u.fail("only %s vehicles per image" % rows[0]["vehicles_per_image"])
        for name in ("all", "jobs=1"):
            if not any(line.startswith(name) for line in p.stdout.splitlines()):
                u.fail("no table row for %s" % name)
    print("bench synth: table and CSV, the same images in both variants")


if __name__ == "__main__":
    main()

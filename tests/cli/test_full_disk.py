#!/usr/bin/env python3
"""Every write checked to the end (issue 42, item 4 and item 8): on a full disk each command exits
non-zero saying "disk full" and leaves nothing under the final name.

A 1 MB tmpfs (mounted in a mount namespace of this test's own: `unshare -m` as root, `unshare -rm`
otherwise), filled to its last few kilobytes, receives:
  export -o OUT.geojson, -o OUT.gpkg, --uncertainty OUT.tif   (GDAL's drivers)
  calib --json > res.json, site describe > d.txt              (standard output; also > /dev/full)
  ortho -o ORTHO.tif                                          (POV-Ray's work folder, then GDAL)
and calib into a folder remounted read-only after a first run names the earlier outputs it
cannot remove as stale (it said "no earlier output of it was there" while they stayed).
Before the fix export -o OUT.geojson exited 0 leaving a truncated file, the GeoPackage said "no
such table: gpkg_geometry_columns", calib --json and site describe exited 0 with a truncated or
empty file, and ortho left its .ortho-work-* folder. The oracle for "complete" is GDAL itself: with
room on the same file system the same commands write files ogrinfo/gdalinfo (osgeo) read whole.
Skipped (77) when no mount namespace can be made."""
import json
import os
import shutil
import subprocess
import sys
import tempfile

ROADSIDE = os.environ["ROADSIDE"]
SITE = os.path.join(os.environ["ROADSIDE_SOURCE_ROOT"], "sites", "demo")
INNER = "ROADSIDE_TEST_FULL_DISK_INNER"

if not os.environ.get(INNER):
    unshare = shutil.which("unshare")
    if not unshare:
        print("SKIP: no unshare")
        sys.exit(77)
    env = dict(os.environ, **{INNER: "1"})
    for args in (["-m"], ["-rm"]) if os.geteuid() == 0 else (["-rm"],):
        p = subprocess.run([unshare, *args, "--propagation", "private", sys.executable, *sys.argv], env=env)
        if p.returncode != 125:  # 125: this way of entering a namespace is not allowed here
            sys.exit(p.returncode)
    print("SKIP: no mount namespace")
    sys.exit(77)

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "common"))
from rs_check import check, finish  # noqa: E402


def run(args, stdout=None, timeout=120):
    p = subprocess.run([ROADSIDE, *args], stdout=stdout if stdout is not None else subprocess.PIPE,
                       stderr=subprocess.PIPE, text=True, timeout=timeout)
    return p.returncode, p.stderr


top = tempfile.mkdtemp(prefix="roadside-full-")
full = os.path.join(top, "full")
os.mkdir(full)
if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", full]).returncode != 0:
    print("SKIP: cannot mount a tmpfs")
    sys.exit(125)

calib = os.path.join(top, "calib")
rc, err = run(["calib", SITE, "-o", calib])
check(rc == 0, f"calib into {calib}: rc {rc}: {err}")


def fill(room_kb):
    """Fills `full` but for room_kb kilobytes."""
    filler = os.path.join(full, "filler")
    if os.path.exists(filler):
        os.remove(filler)
    st = os.statvfs(full)
    size = st.f_bavail * st.f_frsize - room_kb * 1024
    with open(filler, "wb") as f:
        f.write(b"\0" * max(size, 0))


def leftovers():
    return sorted(n for n in os.listdir(full) if n != "filler")


def out(name):
    return os.path.join(full, name)


# ---- GDAL's outputs: nothing under the final name, "disk full" ----
for name in ("out.geojson", "out.gpkg"):
    fill(16)
    rc, err = run(["export", SITE, "--calib", calib, "-o", out(name)])
    check(rc == 1 and f"disk full writing {out(name)}" in err, f"export -o {name}: rc {rc}, stderr {err!r}")
    check(leftovers() == [], f"export -o {name} left {leftovers()}")
fill(8)
rc, err = run(["export", SITE, "--calib", calib, "--cell", "0.25", "--uncertainty", out("u.tif")])
check(rc == 1 and "disk full writing" in err, f"export --uncertainty: rc {rc}, stderr {err!r}")
check(leftovers() == [], f"export --uncertainty left {leftovers()}")

# ---- standard output ----
for args, name in ((["calib", SITE, "--json", "-o", os.path.join(top, "calib2")], "res.json"),
                   (["site", "describe", SITE], "d.txt")):
    fill(1)
    with open(out(name), "w") as f:
        rc, err = run(args, stdout=f)
    check(rc == 1 and "disk full writing standard output" in err, f"{args[0]} > {name}: rc {rc}, stderr {err!r}")
    # the shell's file stays (it is the shell's), cut back to where the run began: nothing partial
    check(os.path.getsize(out(name)) == 0, f"{args[0]} > {name}: {os.path.getsize(out(name))} bytes left")
    os.remove(out(name))
    with open("/dev/full", "w") as f:
        rc, err = run(args, stdout=f)
    check(rc == 1 and "disk full writing standard output" in err, f"{args[0]} > /dev/full: rc {rc}, stderr {err!r}")

# ---- ortho: POV-Ray's work folder and the GeoTIFF ----
for room in (0, 200, 600):
    fill(room)
    rc, err = run(["ortho", SITE, "-o", out("o.tif"), "--gsd", "0.1"])
    check(rc == 1 and "disk full writing" in err, f"ortho with {room} kB free: rc {rc}, stderr {err!r}")
    check(leftovers() == [], f"ortho with {room} kB free left {leftovers()}")

# ---- calib into a folder made read-only after an earlier run: its old outputs are named stale ----
ro = os.path.join(top, "ro")
os.mkdir(ro)
subprocess.run(["mount", "-t", "tmpfs", "-o", "size=4m", "tmpfs", ro], check=True)
rc, err = run(["calib", SITE, "-o", os.path.join(ro, "c")])
check(rc == 0, f"calib into {ro}/c: rc {rc}: {err}")
subprocess.run(["mount", "-o", "remount,ro", ro], check=True)
p = subprocess.run([ROADSIDE, "calib", SITE, "-o", os.path.join(ro, "c")], capture_output=True, text=True, timeout=120)
said = p.stdout + p.stderr
check(p.returncode == 1 and "no earlier output of it was there" not in said
      and said.count("STALE, an earlier run's output that could not be removed") == 4,
      f"calib into a read-only folder: rc {p.returncode}: {said[-600:]!r}")
subprocess.run(["umount", ro])

# ---- the oracle: with room, the same outputs are whole files GDAL reads ----
os.remove(os.path.join(full, "filler"))
from osgeo import gdal, ogr  # noqa: E402

gdal.UseExceptions()
for name, layers in (("out.geojson", 1), ("out.gpkg", 4)):
    rc, err = run(["export", SITE, "--calib", calib, "-o", out(name)])
    check(rc == 0, f"export -o {name} with room: rc {rc}: {err}")
    ds = ogr.Open(out(name)) if rc == 0 else None
    check(ds is not None and ds.GetLayerCount() >= layers, f"{name}: fewer than {layers} layers")
    if ds is not None:
        n = sum(ds.GetLayer(i).GetFeatureCount() for i in range(ds.GetLayerCount()))
        check(n > 50, f"{name}: {n} features")
    os.remove(out(name))
with open(out("res.json"), "w") as f:
    rc, err = run(["calib", SITE, "--json", "-o", os.path.join(top, "calib3")], stdout=f)
check(rc == 0, f"calib --json with room: rc {rc}: {err}")
with open(out("res.json")) as f:
    json.load(f)  # whole JSON
os.remove(out("res.json"))

subprocess.run(["umount", full])
shutil.rmtree(top, ignore_errors=True)
finish("full disk (export GeoJSON/GeoPackage/GeoTIFF, calib --json, site describe, ortho, read-only calib)")

#!/usr/bin/env python3
"""No reader that can block (issue 42): only regular files reach OpenCV and GDAL, and an image's
size is read from its header before it is decoded.

Each case must end with exit status 1 and a message naming what is wrong; the subprocess timeout
(20 s) is the guard, not a measurement: before the fix the FIFO cases blocked forever in OpenCV's
or GDAL's open (killed by the timeout), `site check` passed a FIFO ortho.tif with 0 errors, and
`pick --image` decoded a 32000x32000 PNG (4 GB as float) before comparing its size with the
camera's 1920x1080. Also a loop of symbolic links is named as such, not "missing file".
The oversized PNG is built with zlib (its IHDR says 32000x32000; the deflate stream of its zero
rows is one full-flushed block repeated, with the true Adler-32 of all 1.02 GB)."""
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import zlib

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "common"))
from rs_check import ROADSIDE, check, finish  # noqa: E402

DEMO = os.path.join(os.environ["ROADSIDE_SOURCE_ROOT"], "sites", "demo")


def run(*args):
    try:
        p = subprocess.run([ROADSIDE, *args], capture_output=True, text=True, timeout=20)
        return p.returncode, p.stdout + p.stderr
    except subprocess.TimeoutExpired:
        return None, "blocked: killed after 20 s"


def big_png(path, width, height, rows_per_block=200):
    """A valid greyscale PNG of zeros, written without compressing its whole 1 GB."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    block = b"\0" * ((width + 1) * rows_per_block)
    c = zlib.compressobj(9)
    first = c.compress(block) + c.flush(zlib.Z_FULL_FLUSH)
    again = c.compress(block) + c.flush(zlib.Z_FULL_FLUSH)
    assert first[2:] == again  # after a full flush the same input deflates to the same bytes
    tail = c.flush(zlib.Z_FINISH)[:-4]
    adler = 1
    for _ in range(height // rows_per_block):
        adler = zlib.adler32(block, adler)
    idat = first + again * (height // rows_per_block - 1) + tail + struct.pack(">I", adler)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)))
        f.write(chunk(b"IDAT", idat) + chunk(b"IEND", b""))


top = tempfile.mkdtemp(prefix="roadside-noblock-")
site = os.path.join(top, "site")
shutil.copytree(DEMO, site)
calib = os.path.join(top, "calib")
rc, out = run("calib", site, "-o", calib)
check(rc == 0, f"calib: rc {rc}: {out}")

fifo = os.path.join(top, "fifo.mp4")
os.mkfifo(fifo)
fifo_tif = os.path.join(top, "fifo.tif")
os.mkfifo(fifo_tif)

rc, out = run("background", site, "--camera", "cam1", fifo)
check(rc == 1 and "not a regular file (a FIFO)" in out, f"background FIFO video: rc {rc}: {out}")
rc, out = run("pick", site, "--camera", "cam1", "--ortho", fifo_tif, "--port", "0")
check(rc == 1 and "not a regular file (a FIFO)" in out, f"pick --ortho FIFO: rc {rc}: {out}")
rc, out = run("report", site, "--calib", calib, "--ortho", fifo_tif, "-o", os.path.join(top, "rep1"))
check(rc == 1 and "not a regular file (a FIFO)" in out, f"report --ortho FIFO: rc {rc}: {out}")

# a FIFO as the site's own ortho.tif: site check refuses it, report does not wait on it
os.mkfifo(os.path.join(site, "ortho.tif"))
rc, out = run("site", "check", site)
check(rc == 1 and "ortho.tif: not a regular file (a FIFO)" in out, f"site check, FIFO ortho.tif: rc {rc}: {out}")
rc, out = run("report", site, "--calib", calib, "-o", os.path.join(top, "rep2"))
check(rc == 1 and "not a regular file (a FIFO)" in out, f"report, FIFO SITE/ortho.tif: rc {rc}: {out}")
os.remove(os.path.join(site, "ortho.tif"))

# an image 32000x32000: refused from its header, before decoding
png = os.path.join(top, "big.png")
big_png(png, 32000, 32000)
rc, out = run("pick", site, "--camera", "cam1", "--image", png, "--port", "0")
check(rc == 1 and "32000x32000" in out and "not decoded" in out, f"pick --image 32000x32000: rc {rc}: {out}")

# a loop of symbolic links named as such
obs = os.path.join(site, "observations", "cam1.csv")
os.remove(obs)
os.symlink("cam1.csv", obs)
rc, out = run("site", "check", site)
check(rc == 1 and "loop of symbolic links" in out and "missing file" not in out,
      f"site check, observations a link loop: rc {rc}: {out}")
shutil.copy(os.path.join(DEMO, "observations", "cam1.csv"), os.path.join(top, "cam1.csv"))
os.remove(obs)
shutil.copy(os.path.join(top, "cam1.csv"), obs)
lanes = os.path.join(site, "lanes.geojson")
os.remove(lanes)
os.symlink("lanes.geojson", lanes)
rc, out = run("site", "check", site)
check(rc == 1 and "symbolic links" in out, f"site check, lanes.geojson a link loop: rc {rc}: {out}")

shutil.rmtree(top, ignore_errors=True)
finish("no blocking (FIFO video, orthophotos in pick, report, site check; a 32000x32000 PNG; link loops)")

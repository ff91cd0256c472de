"""Shared helpers of the geo tests: run `roadside geo` and PROJ's `cct` (the oracle) on the
same points, and measure differences in metres. Every failure prints the seed."""
import math
import os
import shutil
import subprocess
import sys

SEED = 20261122
TOL_M = 1e-6  # 1 micrometre

# WGS84
A_M = 6378137.0
F = 1 / 298.257223563
E2 = F * (2 - F)


def fail(msg):
    print(f"FAIL (seed {SEED}): {msg}")
    sys.exit(1)


def roadside_exe():
    exe = os.environ.get("ROADSIDE")
    if not exe or not os.access(exe, os.X_OK):
        fail(f"$ROADSIDE ({exe!r}) is not an executable")
    return exe


def cct_exe():
    # cct is a declared dependency (proj-bin in scripts/debian-packages.txt): missing is a failure
    exe = shutil.which("cct")
    if not exe:
        fail("PROJ's cct is not on PATH: install proj-bin (scripts/debian-packages.txt)")
    return exe


def run_roadside(args, rows, fmt):
    """Runs `roadside geo ARGS` on rows (tuples of floats printed with fmt); returns the output
    lines split into fields (numbers as float, anything else as str)."""
    text = "".join(fmt % tuple(r) + "\n" for r in rows)
    p = subprocess.run([roadside_exe(), "geo"] + args, input=text, capture_output=True, text=True)
    if p.returncode != 0:
        fail(f"roadside geo {' '.join(args)} exited {p.returncode}: {p.stderr.strip()}")
    out = [line.split() for line in p.stdout.splitlines()]
    if len(out) != len(rows):
        fail(f"roadside geo {' '.join(args)}: {len(out)} output lines for {len(rows)} inputs")
    return [[to_number(f) for f in fields] for fields in out]


def to_number(s):
    try:
        v = float(s)
    except ValueError:
        return s
    if not math.isfinite(v):
        fail(f"non-finite output value {s!r}")
    return v


def run_cct(pipeline, rows, fmt, inverse=False):
    """Runs cct (12 decimals) with the proj-string `pipeline` on rows (x y z, printed with fmt,
    t = 0 appended); returns the (x, y, z) rows."""
    text = "".join(fmt % tuple(r) + " 0\n" for r in rows)
    args = [cct_exe(), "-d", "12"] + (["-I"] if inverse else []) + pipeline.split()
    p = subprocess.run(args, input=text, capture_output=True, text=True)
    lines = [line for line in p.stdout.splitlines() if line.strip() and not line.startswith("#")]
    if p.returncode != 0 or len(lines) != len(rows) or "ERROR" in p.stdout:
        fail(f"cct {pipeline} failed ({p.returncode}): {p.stderr.strip()} {p.stdout[:300]}")
    out = []
    for line in lines:
        v = [float(x) for x in line.split()[:3]]
        if not all(math.isfinite(x) for x in v):
            fail(f"cct {pipeline}: non-finite output {line!r}")
        out.append(v)
    return out


def topocentric(lat, lon, h):
    """The proj pipeline geodetic (lon lat h, degrees) -> ENU at the origin, as GeographicLib's
    LocalCartesian (the site ENU frame)."""
    return (f"+proj=pipeline +step +proj=cart +ellps=WGS84 +step +proj=topocentric +ellps=WGS84 "
            f"+lat_0={lat!r} +lon_0={lon!r} +h_0={h!r}")


def dist(a, b):
    """Euclidean distance of two 3-vectors, metres; inf on NaN so that NaN always fails."""
    d = math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)))
    return d if math.isfinite(d) else math.inf


def llh_dist_m(a, b):
    """Approximate distance in metres between two nearby geodetic points (lat, lon, h):
    latitude and longitude differences scaled by the radii of curvature at a."""
    lat = math.radians(a[0])
    w = math.sqrt(1 - E2 * math.sin(lat) ** 2)
    m_rad = A_M * (1 - E2) / w ** 3 + a[2]
    n_rad = A_M / w + a[2]
    dlon = (a[1] - b[1] + 180) % 360 - 180
    d = math.sqrt((math.radians(a[0] - b[0]) * m_rad) ** 2
                  + (math.radians(dlon) * n_rad * math.cos(lat)) ** 2 + (a[2] - b[2]) ** 2)
    return d if math.isfinite(d) else math.inf


def check_max(label, errors, tol=TOL_M):
    """Prints the largest error and fails if it exceeds tol (or is NaN)."""
    worst = max(errors)
    print(f"{label}: max error {worst:.3e} m over {len(errors)} points (tolerance {tol:g} m)")
    if not worst <= tol:
        fail(f"{label}: max error {worst:.3e} m > {tol:g} m")
    return worst

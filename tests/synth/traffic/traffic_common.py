"""Shared by the traffic tests: the demo site's origin, lanes in ENU through PROJ's cct (an
oracle independent of GeographicLib), footprints, and a brute-force raster overlap check."""
import json, math, os, shutil, subprocess, sys, tempfile

ROOT = os.environ.get("ROADSIDE_SOURCE_ROOT", os.path.join(os.path.dirname(__file__), "..", "..", ".."))
ROADSIDE = os.environ.get("ROADSIDE", "roadside")
DEMO = os.path.join(ROOT, "sites", "demo")


def site_origin(site):
    o = json.load(open(os.path.join(site, "site.json")))["origin"]
    return o["lat"], o["lon"], o["h"]


def llh_to_enu(origin, lonlat):
    """[(lon, lat)] -> [(e, n)] with cct's topocentric pipeline at origin (lat, lon, h)."""
    lat0, lon0, h0 = origin
    text = "".join("%.12f %.12f %.6f 0\n" % (lon, lat, h0) for lon, lat in lonlat)
    out = subprocess.run(["cct", "-d", "6", "+proj=pipeline", "+step", "+proj=cart", "+ellps=WGS84", "+step",
                          "+proj=topocentric", "+ellps=WGS84", "+lat_0=%.12f" % lat0, "+lon_0=%.12f" % lon0,
                          "+h_0=%.6f" % h0], input=text, capture_output=True, text=True, check=True)
    return [tuple(map(float, l.split()[:2])) for l in out.stdout.splitlines()]


def lanes_enu(site):
    lanes = json.load(open(os.path.join(site, "lanes.geojson")))["features"]
    origin = site_origin(site)
    out = []
    for f in lanes:
        pts = llh_to_enu(origin, f["geometry"]["coordinates"])
        out.append(dict(f["properties"], pts=pts))
    return out


def nearest_lanes(lanes, p):
    """[(distance, heading_deg, lane)] for every lane, nearest first."""
    res = []
    for lane in lanes:
        best = (math.inf, 0.0)
        pts = lane["pts"]
        for a, b in zip(pts, pts[1:]):
            de, dn = b[0] - a[0], b[1] - a[1]
            L2 = de * de + dn * dn
            t = max(0.0, min(1.0, ((p[0] - a[0]) * de + (p[1] - a[1]) * dn) / L2))
            d = math.hypot(p[0] - a[0] - t * de, p[1] - a[1] - t * dn)
            if d < best[0]:
                best = (d, math.degrees(math.atan2(de, dn)) % 360.0)
        res.append((best[0], best[1], lane))
    return sorted(res, key=lambda r: r[0])


def angle_diff(a, b):
    return abs((a - b + 180.0) % 360.0 - 180.0)


def raster_overlaps(vehicles, cell=0.05):
    """Brute force: rasterise every footprint (cells whose centre lies inside) on a grid and
    return the pairs of vehicles sharing a cell."""
    owner = {}
    pairs = set()
    for i, v in enumerate(vehicles):
        y = math.radians(v["yaw_deg"])
        f = (math.sin(y), math.cos(y))
        r = 0.5 * math.hypot(v["length"], v["width"])
        for ie in range(int(math.floor((v["e"] - r) / cell)), int(math.ceil((v["e"] + r) / cell)) + 1):
            for jn in range(int(math.floor((v["n"] - r) / cell)), int(math.ceil((v["n"] + r) / cell)) + 1):
                de, dn = (ie + 0.5) * cell - v["e"], (jn + 0.5) * cell - v["n"]
                x, yy = de * f[0] + dn * f[1], -de * f[1] + dn * f[0]
                if abs(x) < 0.5 * v["length"] and abs(yy) < 0.5 * v["width"]:
                    k = (ie, jn)
                    if k in owner and owner[k] != i:
                        pairs.add((owner[k], i))
                    owner[k] = i
    return pairs


def run(args, **kw):
    return subprocess.run([ROADSIDE] + args, capture_output=True, text=True, **kw)


def finite_vehicles(vs):
    keys = ["e", "n", "yaw_deg", "length", "width", "height"]
    return all(all(isinstance(v[k], (int, float)) and math.isfinite(v[k]) for k in keys) for v in vs)


FAILS = []


def check(cond, msg):
    """Records a failed check (the test goes on, to report every failure)."""
    if not cond:
        FAILS.append(msg)
        print("FAIL:", msg)


def run_test(body, prefix):
    """Runs body(tmp) in a fresh temporary folder (removed afterwards); the exit status is 1 if a
    check failed, else body's return value (None = 0; 77 = skipped)."""
    tmp = tempfile.mkdtemp(prefix=prefix)
    try:
        rc = body(tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    if FAILS:
        print("FAIL: %d checks" % len(FAILS))
        return 1
    return rc or 0

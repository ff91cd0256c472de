#!/usr/bin/env python3
"""SUMO in `roadside traffic`, against independent oracles (PROJ's cct):
  1. FCD fixtures written here (geo lon/lat, and projected UTM with a netOffset) for a site far
     from its UTM zone's central meridian (60 N, 11.9 E in zone 32: 2.9 deg off, convergence
     ~2.5 deg): a vehicle of known length heading true east and one heading true north-east.
     The expected centre = front bumper (cct topocentric ENU) - L/2 along the TRUE bearing; SUMO's
     grid angle = true bearing - gamma, gamma from cct by a finite difference (the grid bearing
     of true north). Tolerance 1 mm, 0.001 deg.
  2. The real sumo and netconvert on the demo site (--no-randomise): vehicles appear, every one
     lies within a lane width of a lane polyline (lanes in ENU by cct), moving vehicles within 1 m
     of an approach or exit lane and wholly beyond the stop bars head along it within 3 deg; the same seed gives the same frames;
     with randomisation no two footprints overlap (raster brute force).
  3. --osm with a hand-written OpenStreetMap crossing: vehicles on the two ways.
  4. Missing programs: a clear error, exit 1, nothing written.
Exit 77 when sumo or netconvert is not installed (parts 1 and 3 still run first).
Usage: test_traffic_sumo.py TEST_TRAFFIC_API"""
import json, math, os, shutil, subprocess, sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from traffic_common import *

def cct(args, rows):
    text = "".join(" ".join("%.12f" % x for x in r) + " 0\n" for r in rows)
    out = subprocess.run(["cct", "-d", "9"] + args, input=text, capture_output=True, text=True, check=True)
    return [tuple(map(float, l.split()[:3])) for l in out.stdout.splitlines()]


def fixture(api, tmp):
    lat0, lon0, h0 = 60.0, 11.9, 100.0
    zone, offx, offy = 32, -661000.0, -6654000.0
    utm = ["+proj=utm", "+zone=%d" % zone, "+ellps=WGS84"]
    topo = ["+proj=pipeline", "+step", "+proj=cart", "+ellps=WGS84", "+step", "+proj=topocentric", "+ellps=WGS84",
            "+lat_0=%.12f" % lat0, "+lon_0=%.12f" % lon0, "+h_0=%.6f" % h0]
    L = 4.6
    cases = [("east", lon0 + 0.0004, lat0 + 0.0001, 90.0), ("northeast", lon0 - 0.0003, lat0 - 0.0002, 45.0)]
    geo_rows, xy_rows, expect = [], [], {}
    for name, lon, lat, bearing in cases:
        E, N, _ = cct(utm, [(lon, lat, h0)])[0]
        E2, N2, _ = cct(utm, [(lon, lat + 1e-5, h0)])[0]
        gamma = -math.degrees(math.atan2(E2 - E, N2 - N))  # true north is at grid bearing -gamma
        angle = (bearing - gamma) % 360.0
        fe, fn, _ = cct(topo, [(lon, lat, h0)])[0]
        b = math.radians(bearing)
        expect[name] = (fe - L / 2 * math.sin(b), fn - L / 2 * math.cos(b), bearing, gamma)
        geo_rows.append('<vehicle id="%s" x="%.10f" y="%.10f" angle="%.6f" type="car" speed="5.0" pos="1" '
                        'lane="e3_0" slope="0.00"/>' % (name, lon, lat, angle))
        xy_rows.append('<vehicle id="%s" x="%.4f" y="%.4f" angle="%.6f" type="car" speed="5.0" pos="1" '
                       'lane=":n1_0_0" slope="0.00"/>' % (name, E + offx, N + offy, angle))
    for geo, rows in ((1, geo_rows), (0, xy_rows)):
        path = os.path.join(tmp, "fcd%d.xml" % geo)
        with open(path, "w") as f:
            f.write('<?xml version="1.0"?>\n<fcd-export>\n<timestep time="10.00">\n%s\n</timestep>\n</fcd-export>\n'
                    % "\n".join(rows))
        out = subprocess.run([api, "fcd", path, str(geo), str(zone), "1", str(offx), str(offy), str(lat0),
                              str(lon0), str(h0), "car", str(L), "1.8", "1.5"], capture_output=True, text=True)
        check(out.returncode == 0, "fcd reader (geo %d): %s" % (geo, out.stdout))
        got = {l.split()[0]: tuple(map(float, l.split()[1:])) for l in out.stdout.splitlines() if l.strip()}
        for name, (e, n, yaw, gamma) in expect.items():
            g = got.get(name)
            ok = g is not None and all(map(math.isfinite, g)) and math.hypot(g[0] - e, g[1] - n) < 1e-3 \
                and angle_diff(g[2], yaw) < 1e-3
            check(ok, "fcd geo=%d %s: got %s, expected %.4f %.4f %.4f" % (geo, name, g, e, n, yaw))
            if g:
                print("fcd geo=%d %s: gamma %.4f deg; centre error %.2e m, yaw error %.2e deg"
                      % (geo, name, gamma, math.hypot(g[0] - e, g[1] - n), angle_diff(g[2], yaw)))
    # a malformed file names the line and field
    path = os.path.join(tmp, "bad.xml")
    with open(path, "w") as f:
        f.write('<fcd-export>\n<timestep time="1">\n<vehicle id="a" x="1" y="zz" angle="0" type="car"/>\n'
                '</timestep>\n</fcd-export>\n')
    out = subprocess.run([api, "fcd", path, "1", "32", "1", "0", "0", "60", "11.9", "0", "car", "4", "2", "1.5"],
                         capture_output=True, text=True)
    check(out.returncode == 1 and "bad.xml:3: vehicle.y" in out.stdout, "bad FCD: %s" % out.stdout.strip())
    print("bad FCD:", out.stdout.strip())


def real_sumo(tmp):
    lanes = lanes_enu(DEMO)
    runs = []
    for k in range(2):
        out = os.path.join(tmp, "sumo%d" % k)
        r = run(["traffic", DEMO, "--sumo", "--no-randomise", "--seed", "1", "--duration", "150", "--warmup", "60",
                 "--period", "5", "-o", out, "--keep", os.path.join(tmp, "keep%d" % k)])
        check(r.returncode == 0, "traffic --sumo: exit %d: %s" % (r.returncode, r.stderr))
        if r.returncode:
            return
        print(r.stdout.strip())
        frames = json.load(open(os.path.join(out, "frames.json")))
        runs.append([json.load(open(os.path.join(out, f["file"]))) for f in frames])
    check(runs[0] == runs[1], "the same seed gave different SUMO frames")
    vs = [v for fr in runs[0] for v in fr]
    check(len(vs) >= 50 and finite_vehicles(vs), "only %d vehicles from SUMO, or NaN" % len(vs))
    worst_d = worst_h = 0.0
    nh = 0
    for v in vs:
        near = nearest_lanes(lanes, (v["e"], v["n"]))
        d, h, lane = near[0]
        worst_d = max(worst_d, d)
        check(d < lane["width_m"], "%s at (%.2f, %.2f) is %.2f m from the nearest lane" % (v["id"], v["e"], v["n"], d))
        straight = [x for x in near if x[0] < 1.0 and x[2].get("kind") != "junction"]
        # wholly on an approach or exit lane: beyond the stop bars (13.5 m from the centre)
        beyond = math.hypot(v["e"], v["n"]) > 13.5 + v["length"] / 2 + 1.0
        if straight and beyond and v["speed_mps"] > 0.5:
            dh = min(angle_diff(x[1], v["yaw_deg"]) for x in straight)
            worst_h = max(worst_h, dh)
            nh += 1
            check(dh < 3.0, "%s heads %.2f, lane %s %.2f" % (v["id"], v["yaw_deg"], straight[0][2]["id"], straight[0][1]))
    print("SUMO: %d vehicle states in %d frames; max distance to a lane %.3f m; %d headings on approach/exit lanes, "
          "max error %.3f deg" % (len(vs), len(runs[0]), worst_d, nh, worst_h))
    # randomised frames: no overlaps
    out = os.path.join(tmp, "sumo_r")
    r = run(["traffic", DEMO, "--sumo", "--seed", "2", "--duration", "120", "--warmup", "60", "--period", "10",
             "-o", out])
    check(r.returncode == 0, "traffic --sumo (randomised): %s" % r.stderr)
    if r.returncode == 0:
        for f in json.load(open(os.path.join(out, "frames.json"))):
            fr = json.load(open(os.path.join(out, f["file"])))
            pairs = raster_overlaps(fr)
            check(not pairs, "%s: footprints overlap: %s" % (f["file"], sorted(pairs)[:5]))


OSM = '''<?xml version="1.0" encoding="UTF-8"?>
<osm version="0.6" generator="test_traffic_sumo.py">
  <node id="1" lat="48.1374" lon="11.5755" version="1"/>
  <node id="2" lat="48.1384" lon="11.5755" version="1"/>
  <node id="3" lat="48.1364" lon="11.5755" version="1"/>
  <node id="4" lat="48.1374" lon="11.5770" version="1"/>
  <node id="5" lat="48.1374" lon="11.5740" version="1"/>
  <way id="10" version="1"><nd ref="3"/><nd ref="1"/><nd ref="2"/><tag k="highway" v="secondary"/></way>
  <way id="11" version="1"><nd ref="5"/><nd ref="1"/><nd ref="4"/><tag k="highway" v="residential"/></way>
</osm>
'''


def osm(tmp):
    """--osm: a hand-written OpenStreetMap crossing of a north-south and an east-west way through
    node 1; every vehicle within 6 m of one of the two ways' axes (ENU by cct)."""
    path = os.path.join(tmp, "cross.osm")
    open(path, "w").write(OSM)
    out = os.path.join(tmp, "osm")
    r = run(["traffic", DEMO, "--sumo", "--osm", path, "--no-randomise", "--seed", "1", "--duration", "120",
             "--warmup", "30", "--period", "10", "-o", out])
    check(r.returncode == 0, "traffic --sumo --osm: exit %d: %s" % (r.returncode, r.stderr))
    if r.returncode:
        return
    vs = [v for f in json.load(open(os.path.join(out, "frames.json")))
          for v in json.load(open(os.path.join(out, f["file"])))]
    (e0, n0), = llh_to_enu(site_origin(DEMO), [(11.5755, 48.1374)])
    worst = max([min(abs(v["e"] - e0), abs(v["n"] - n0)) for v in vs] or [math.inf])
    print("OSM: %d vehicle states; max distance to the ways' axes %.2f m" % (len(vs), worst))
    check(len(vs) >= 20 and worst < 6.0, "OSM vehicles: %d, max distance %.2f m" % (len(vs), worst))


def body(tmp):
    api = sys.argv[1]
    fixture(api, tmp)
    # missing programs
    out = os.path.join(tmp, "nosumo")
    env = dict(os.environ, PATH=os.path.join(tmp, "empty"))
    r = subprocess.run([ROADSIDE, "traffic", DEMO, "--sumo", "-o", out], capture_output=True, text=True, env=env)
    check(r.returncode == 1 and "not found" in r.stderr and not os.path.exists(out),
          "missing sumo: exit %d: %s" % (r.returncode, r.stderr.strip()))
    print("missing programs:", r.stderr.strip())
    if not shutil.which("sumo") or not shutil.which("netconvert"):
        print("SKIP: sumo or netconvert not installed")
        return 77
    real_sumo(tmp)
    osm(tmp)


if __name__ == "__main__":
    sys.exit(run_test(body, "test_traffic_sumo."))

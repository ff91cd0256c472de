#!/usr/bin/env python3
"""`roadside traffic` built-in traffic on the demo site, checked against independent oracles:
lanes converted to ENU by PROJ's cct, footprints rasterised by brute force.
  1. --no-randomise: every vehicle's centre lies on a lane polyline (1 cm), its yaw equals the
     lane's heading (0.01 deg), it lies wholly on the lane, consecutive vehicles on a lane keep
     the time-headway gap (>= s0, <= s0 + v_max T 1.5), dimensions within the class ranges.
  2. randomised (seeds 1..6): no two footprints share a raster cell (5 cm grid); the offsets
     from the unrandomised placement (matched by id) have sigma ~ sqrt(0.5) m along and across
     (0.6 .. 0.82) and yaw offsets within [-5, 5] deg.
  3. --mix bus=1: only buses; --count 7: 7 vehicles; the same seed gives the same file;
     bad arguments and a bad lanes file fail cleanly (exit 2 / 1, nothing written);
     `roadside site check` reports a bad lanes.geojson.
Usage: test_traffic.py TEST_TRAFFIC_API"""
import json, math, os, shutil, subprocess, sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from traffic_common import *

# The fleet's class ranges (synth/fleet/rs_synth_fleet.c, docs/fleet.md), copied here as the expectation.
RANGES = {"sedan": [(4.30, 5.00), (1.72, 1.88), (1.38, 1.50)], "hatchback": [(3.60, 4.40), (1.62, 1.80), (1.42, 1.56)],
          "suv": [(4.20, 5.10), (1.78, 2.00), (1.60, 1.85)], "pickup": [(5.00, 5.90), (1.85, 2.05), (1.75, 1.95)],
          "van": [(4.80, 6.00), (1.90, 2.05), (1.95, 2.60)], "bus": [(10.5, 13.5), (2.50, 2.55), (3.00, 3.40)],
          "box_truck": [(6.50, 9.50), (2.30, 2.55), (3.00, 3.80)],
          "articulated_truck": [(15.50, 16.50), (2.50, 2.55), (3.80, 4.00)],
          "motorcycle": [(1.80, 2.40), (0.65, 0.95), (1.30, 1.60)], "bicycle": [(1.55, 1.90), (0.50, 0.70), (1.55, 1.90)]}
def traffic(tmp, name, *args):
    out = os.path.join(tmp, name)
    r = run(["traffic", DEMO, "-o", out] + list(args))
    check(r.returncode == 0, "roadside traffic %s: exit %d: %s" % (" ".join(args), r.returncode, r.stderr))
    return json.load(open(out)) if r.returncode == 0 else []


def body(tmp):
    lanes = lanes_enu(DEMO)
    by_id = {l["id"]: l for l in lanes}
    # 1. placement without randomisation
    for seed in (1, 2):
        vs = traffic(tmp, "plain%d.json" % seed, "--seed", str(seed), "--no-randomise")
        check(len(vs) > 20 and finite_vehicles(vs), "seed %d: %d vehicles, or NaN" % (seed, len(vs)))
        on_lane = {}
        worst_d = worst_h = 0.0
        for v in vs:
            d, h, lane = nearest_lanes(lanes, (v["e"], v["n"]))[0]
            worst_d, worst_h = max(worst_d, d), max(worst_h, angle_diff(h, v["yaw_deg"]))
            check(d < 0.01 and angle_diff(h, v["yaw_deg"]) < 0.01,
                  "seed %d: %s is %.3f m off its lane, yaw %.3f vs lane %.3f" % (seed, v["id"], d, v["yaw_deg"], h))
            check(lane.get("kind") != "junction", "seed %d: %s on a junction lane" % (seed, v["id"]))
            r = RANGES[v["class"]]
            check(all(lo - 1e-4 <= v[k] <= hi + 1e-4 for (lo, hi), k in zip(r, ["length", "width", "height"])),
                  "seed %d: %s dimensions outside the %s ranges" % (seed, v["id"], v["class"]))
            # arc length of the centre along the (straight) lane
            a, b = lane["pts"][0], lane["pts"][-1]
            L = math.hypot(b[0] - a[0], b[1] - a[1])
            s = ((v["e"] - a[0]) * (b[0] - a[0]) + (v["n"] - a[1]) * (b[1] - a[1])) / L
            check(s - v["length"] / 2 > -1e-3 and s + v["length"] / 2 < L + 1e-3,
                  "seed %d: %s sticks out of lane %s" % (seed, v["id"], lane["id"]))
            on_lane.setdefault(lane["id"], []).append((s, v))
        ngaps = 0
        for lid, lst in on_lane.items():
            lst.sort(key=lambda x: x[0])
            vmax = by_id[lid]["speed_mps"]
            for (s1, v1), (s2, v2) in zip(lst, lst[1:]):
                gap = (s2 - v2["length"] / 2) - (s1 + v1["length"] / 2)
                ngaps += 1
                # the follower is the upstream one (v1): its gap is s0 + v1 T u
                check(2.0 - 1e-3 <= gap <= 2.0 + v1["speed_mps"] * 1.5 * 1.5 + 1e-3 and v1["speed_mps"] <= vmax,
                      "seed %d: gap %.3f m behind %s (speed %.2f) on %s" % (seed, gap, v2["id"], v1["speed_mps"], lid))
        print("seed %d: %d vehicles on %d lanes, %d gaps checked; max distance to lane %.2e m, max yaw error %.2e deg"
              % (seed, len(vs), len(on_lane), ngaps, worst_d, worst_h))

    # 2. randomised: no overlaps (brute force), offset statistics
    da, dc, dy = [], [], []
    for seed in range(1, 7):
        plain = {v["id"]: v for v in traffic(tmp, "p%d.json" % seed, "--seed", str(seed), "--no-randomise",
                                               "--junction-lanes")}
        vs = traffic(tmp, "r%d.json" % seed, "--seed", str(seed), "--junction-lanes")
        pairs = raster_overlaps(vs)
        check(not pairs and finite_vehicles(vs), "seed %d: footprints overlap: %s" % (seed, sorted(pairs)[:5]))
        for v in vs:
            if v["id"] not in plain:  # dropped as overlapping without randomisation
                continue
            p = plain[v["id"]]
            y = math.radians(p["yaw_deg"])
            de, dn = v["e"] - p["e"], v["n"] - p["n"]
            da.append(de * math.sin(y) + dn * math.cos(y))
            dc.append(-de * math.cos(y) + dn * math.sin(y))
            dy.append((v["yaw_deg"] - p["yaw_deg"] + 180) % 360 - 180)
        print("seed %d: %d of %d vehicles kept, no raster cell covered twice" % (seed, len(vs), len(plain)))
    sa = math.sqrt(sum(x * x for x in da) / len(da))
    sc = math.sqrt(sum(x * x for x in dc) / len(dc))
    print("offsets: %d vehicles, sigma along %.3f m, across %.3f m (expected 0.707); yaw offsets in [%.2f, %.2f]"
          % (len(da), sa, sc, min(dy), max(dy)))
    check(0.6 < sa < 0.82 and 0.6 < sc < 0.82, "offset sigmas %.3f %.3f not ~0.707" % (sa, sc))
    check(max(abs(x) for x in dy) <= 5.0 + 1e-3 and max(abs(x) for x in dy) > 4.0,
          "yaw offsets outside [-5, 5] or not spread")

    # 3. mix, count, determinism, errors
    vs = traffic(tmp, "bus.json", "--seed", "4", "--mix", "bus=1")
    check(vs and all(v["class"] == "bus" for v in vs), "--mix bus=1 gave other classes")
    vs = traffic(tmp, "c7.json", "--seed", "4", "--count", "7")
    check(len(vs) == 7, "--count 7 gave %d" % len(vs))
    traffic(tmp, "again.json", "--seed", "1", "--junction-lanes")
    check(open(os.path.join(tmp, "again.json")).read() == open(os.path.join(tmp, "r1.json")).read(),
          "the same seed gave a different file")
    for args in (["--mix", "car=1"], ["--count", "0"], ["--sigma", "-1"], ["--bogus"], [], ["--duration", "5"],
                 ["--sumo", "--count", "5"]):
        out = os.path.join(tmp, "bad.json")
        r = run(["traffic", DEMO] + (["-o", out] if args else []) + args)
        check(r.returncode == 2 and not os.path.exists(out) and "usage" not in r.stdout,
              "bad arguments %s: exit %d" % (args, r.returncode))
    # a broken lanes file: error names the file, feature and field; nothing written
    bad = json.load(open(os.path.join(DEMO, "lanes.geojson")))
    bad["features"][3]["properties"]["width_m"] = -1
    badp = os.path.join(tmp, "bad_lanes.geojson")
    json.dump(bad, open(badp, "w"))
    out = os.path.join(tmp, "bad2.json")
    r = run(["traffic", DEMO, "--lanes", badp, "-o", out])
    check(r.returncode == 1 and "feature 3" in r.stderr and "width_m" in r.stderr and not os.path.exists(out),
          "bad lanes file: exit %d, %s" % (r.returncode, r.stderr.strip()))
    print("bad lanes file:", r.stderr.strip())
    bad = json.load(open(os.path.join(DEMO, "lanes.geojson")))
    bad["features"][5]["properties"]["next"] = ["nope"]
    json.dump(bad, open(badp, "w"))
    api = subprocess.run([sys.argv[1], "lanes", badp] + ["%.12f" % x for x in site_origin(DEMO)],
                         capture_output=True, text=True)
    check(api.returncode == 1 and "'nope' is not a lane" in api.stdout, "unknown next id: %s" % api.stdout)
    # roadside site check reads lanes.geojson too
    r = run(["site", "check", DEMO])
    check(r.returncode == 0, "site check of the demo: %s" % r.stdout)
    site2 = os.path.join(tmp, "site")
    shutil.copytree(DEMO, site2)
    bad = json.load(open(os.path.join(DEMO, "lanes.geojson")))
    bad["features"][2]["geometry"]["coordinates"] = bad["features"][2]["geometry"]["coordinates"][:1]
    json.dump(bad, open(os.path.join(site2, "lanes.geojson"), "w"))
    r = run(["site", "check", site2])
    check(r.returncode == 1 and "lanes.geojson: feature 2" in r.stdout and "1 error" in r.stdout,
          "site check with a bad lanes.geojson: exit %d: %s" % (r.returncode, r.stdout))
    print("site check:", r.stdout.strip().replace("\n", " | "))
    r = run(["traffic", "--help"])
    check(r.returncode == 0 and r.stdout.startswith("usage: roadside traffic"), "--help")


if __name__ == "__main__":
    sys.exit(run_test(body, "test_traffic."))

"""`roadside track` on multi-camera scenarios written by numpy (fixed seed 3902), and its outputs:

  1. two cameras see one vehicle at the same instants (their ellipses crossed at 90 degrees):
     one track, both cameras in its rows' `cameras`, and its error below either camera's alone;
     the same detections as one file per camera, given in either order: byte-identical tracks;
  2. hand-over: detections from camera A only, then a 0.5 s gap (< --max-age 1 s), then B only:
     one id throughout; the same with a 1.5 s gap gives a second id (the rule can fail);
  3. an X: 20 pairs of vehicles crossing at 90 degrees at one instant (10 m/s, 0.3 m noise,
     10 Hz), 1 km apart: 40 tracks, none of them ever nearer the other vehicle of its pair
     (no swapped ids);
  4. asynchronous cameras and clutter: 30 vehicles on concentric circles (1..4 m/s), 3 cameras
     whose frames are 10 ms apart, each detecting with probability 0.8 (10 vehicles seen by one
     camera alone: the steps of the others are no misses for them), and 2 clutter detections
     per frame uniform over the area from a fourth camera: 30 tracks, each always within 2 m of
     its own vehicle, at most 2 % of the clutter confirmed as tracks of its own (3 of 4 hits;
     with 2 of 3, 8 %: docs/track.md),
     the class vote (80 % class 1) gives class 1;
  5. outputs: speed and heading of a straight vehicle within 3.3 of their sigmas in 99 % of its
     rows; the CSV's and the GeoJSON's latitude and longitude against PROJ's cct (topocentric at
     the site origin) within 1 mm; one GeoJSON LineString per track with one vertex per row; the
     SDSM lines' coded fields (0.1 m, 0.02 m/s, 0.0125 degree units; confidence classes) from the
     CSV's values.
"""
import json
import math
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(__file__))
from track_common import make_site, read_tracks, run_track, site_origin, write_located  # noqa: E402
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "common"))
from rs_check import check, finish, need  # noqa: E402

np, = need("numpy")
SEED = 3902
CLUTTER = 2  # false detections per frame in the asynchronous scenario
rng = np.random.default_rng(SEED)


def ellipse(sig_major, sig_minor, angle_deg):
    a = math.radians(angle_deg)
    rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    return rot @ np.diag([sig_major ** 2, sig_minor ** 2]) @ rot.T


def detect(p, cov, camera, t):
    """A detection of the point p drawn from N(p, cov) (2x2 Cholesky factor in closed form)."""
    l00 = math.sqrt(cov[0][0])
    l10 = cov[1][0] / l00
    l11 = math.sqrt(cov[1][1] - l10 * l10)
    n0, n1 = rng.standard_normal(2)
    return dict(camera=camera, time_s=t, e_m=p[0] + l00 * n0, n_m=p[1] + l10 * n0 + l11 * n1, cov=cov)


def track(tmp, site, name, rows, *extra):
    path, out = os.path.join(tmp, name + ".csv"), os.path.join(tmp, name + ".tracks.csv")
    write_located(path, rows)
    p = run_track(site, [path], out, *extra)
    check(p.returncode == 0, f"{name}: roadside track failed: {p.stderr}")
    return read_tracks(out) if p.returncode == 0 else []


def two_cameras(tmp, site):
    ca, cb = ellipse(0.8, 0.15, 30), ellipse(0.8, 0.15, 120)
    rows, truth = [], {}
    for k in range(100):
        t = 0.1 * k
        p = np.array([-30 + 8 * t, 10 + 2 * t])
        truth[round(t, 6)] = p
        rows += [detect(p, ca, "camA", t), detect(p, cb, "camB", t)]
    tr = track(tmp, site, "two", rows)
    # the same split into one file per camera, given in both orders: the same tracks, byte for byte
    outs = []
    for order in (("camA", "camB"), ("camB", "camA")):
        paths = []
        for cam in order:
            paths.append(os.path.join(tmp, f"two_{cam}.csv"))
            write_located(paths[-1], [r for r in rows if r["camera"] == cam])
        outs.append(os.path.join(tmp, "two_%s.tracks.csv" % order[0]))
        p = run_track(site, paths, outs[-1])
        check(p.returncode == 0, f"two files: {p.stderr}")
    with open(outs[0]) as f0, open(outs[1]) as f1, open(os.path.join(tmp, "two.tracks.csv")) as f2:
        a, b, c = f0.read(), f1.read(), f2.read()
    check(a == b == c, "one file per camera, in either order, gives the tracks of the merged file")
    ids = {r["track_id"] for r in tr}
    both = sum(r["cameras"] == "camA+camB" for r in tr)
    err = np.sqrt(np.mean([(r["e_m"] - truth[round(r["time_s"], 6)][0]) ** 2 +
                           (r["n_m"] - truth[round(r["time_s"], 6)][1]) ** 2 for r in tr]))
    single = math.sqrt(0.8 ** 2 + 0.15 ** 2)
    print(f"two cameras: {len(ids)} track(s), {both}/{len(tr)} rows from camA+camB, RMSE {err:.3f} m "
          f"(one detection's {single:.3f} m)")
    check(len(ids) == 1, f"two cameras on one vehicle: {len(ids)} tracks, want 1")
    check(both >= 0.95 * len(tr) and len(tr) >= 97, f"rows updated by both cameras: {both} of {len(tr)}")
    check(err < 0.5 * single, f"fused RMSE {err:.3f} m, want below half a detection's {single:.3f} m")


def handover(tmp, site, gap_s):
    rows = []
    for k in range(60):
        t = 0.1 * k
        if 3.0 <= t < 3.0 + gap_s - 1e-9:
            continue
        p = np.array([5 * t, -20.0])
        rows.append(detect(p, ellipse(0.4, 0.2, 0), "camA" if t < 3.0 else "camB", t))
    return {r["track_id"] for r in track(tmp, site, "handover%g" % gap_s, rows, "--max-age", "1")}


def crossing(tmp, site):
    rows, truth = [], []
    cov = ellipse(0.3, 0.3, 0)
    for pair in range(20):
        base = np.array([1000.0 * pair, 0.0])
        a = math.radians(rng.uniform(0, 360))
        d1, d2 = np.array([math.sin(a), math.cos(a)]), np.array([math.cos(a), -math.sin(a)]) # 90 degrees apart
        truth.append((base, d1, d2))
        for k in range(100):
            t = 0.1 * k
            for d in (d1, d2):
                rows.append(detect(base + 10 * (t - 5) * d, cov, "cam%d" % (1 + k % 2), t))
    tr = track(tmp, site, "crossing", rows)
    owner, swapped = {}, 0
    for r in tr:
        pair = int(round(r["e_m"] / 1000.0))
        base, d1, d2 = truth[pair]
        p = np.array([r["e_m"], r["n_m"]])
        e1 = np.linalg.norm(p - (base + 10 * (r["time_s"] - 5) * d1))
        e2 = np.linalg.norm(p - (base + 10 * (r["time_s"] - 5) * d2))
        v = (pair, 0 if e1 < e2 else 1)
        if abs(e1 - e2) < 0.5:  # at the crossing point itself either is as near
            continue
        if owner.setdefault(r["track_id"], v) != v:
            swapped += 1
    print(f"crossing: {len(owner)} tracks for 40 vehicles, {swapped} rows on the other vehicle")
    check(len(owner) == 40 and len(set(owner.values())) == 40, f"{len(owner)} tracks, want one per vehicle (40)")
    check(swapped == 0, f"{swapped} rows of a track nearer the other vehicle of its pair: ids swapped")


def asynchronous(tmp, site):
    rows = []

    def pos(v, t):
        return np.array([math.cos(v + 0.1 * t) * (10 + v), math.sin(v + 0.1 * t) * (10 + v)])

    for k in range(150):
        t = 0.1 * k
        for c in range(3):
            for v in range(30):
                if rng.uniform() < 0.2 or (v < 10 and c > 0):  # vehicles 0..9: seen by cam0 alone
                    continue
                cov = np.diag(rng.uniform(0.05, 0.3, 2) ** 2)
                d = detect(pos(v, t + 0.01 * c), cov, "cam%d" % c, t + 0.01 * c)
                d["category_id"] = 1 if rng.uniform() < 0.8 else 2
                rows.append(d)
        for j in range(CLUTTER):
            rows.append(dict(camera="clutter", time_s=t, e_m=rng.uniform(-45, 45), n_m=rng.uniform(-45, 45),
                             cov=np.diag([0.04, 0.04])))
    path, out, gj = (os.path.join(tmp, n) for n in ("async.csv", "async.tracks.csv", "async.geojson"))
    write_located(path, rows)
    p = run_track(site, [path], out, "--geojson", gj)
    check(p.returncode == 0, f"asynchronous: roadside track failed: {p.stderr}")
    if p.returncode:
        return
    near = {}  # track -> the nearest vehicle of each of its rows (None: none within 2 m)
    for r in read_tracks(out):
        d = [math.dist((r["e_m"], r["n_m"]), pos(v, r["time_s"])) for v in range(30)]
        v = int(np.argmin(d))
        near.setdefault(r["track_id"], []).append(v if d[v] <= 2.0 else None)
    # a vehicle's track: most of its rows on one vehicle; the others are tracks on clutter
    on_vehicles, false = {}, []
    for k, vs in near.items():
        top = max(set(vs), key=vs.count)
        if top is not None and vs.count(top) >= 0.9 * len(vs):
            on_vehicles[k] = (top, len(vs) - vs.count(top))
        else:
            false.append(k)
    with open(gj) as f:
        classes = {f["id"]: f["properties"]["category_id"] for f in json.load(f)["features"]}
    off = sum(n for _, n in on_vehicles.values())
    print(f"asynchronous cameras, {CLUTTER} clutter per frame ({CLUTTER * 150} in all): {len(on_vehicles)} tracks on "
          f"vehicles ({off} of their rows off it), {len(false)} on clutter; classes on vehicles "
          f"{sorted(set(classes[k] for k in on_vehicles))}")
    check(len(on_vehicles) == 30 and len(set(v for v, _ in on_vehicles.values())) == 30 and off == 0,
          f"tracks on vehicles: {on_vehicles}, want one per vehicle (30), each always on it")
    check(len(false) <= 0.02 * CLUTTER * 150, f"{len(false)} tracks on clutter, want at most 2 % of the clutter")
    check(set(classes[k] for k in on_vehicles) == {1}, "majority classes, want 1")


def cct_enu(origin, lonlath):
    lat0, lon0, h0 = origin
    topo = (f"+proj=pipeline +step +proj=cart +ellps=WGS84 +step +proj=topocentric +ellps=WGS84 "
            f"+lat_0={lat0!r} +lon_0={lon0!r} +h_0={h0!r}")
    p = subprocess.run(["cct", "-d", "9"] + topo.split(), input="".join(f"{x} {y} {z} 0\n" for x, y, z in lonlath),
                       capture_output=True, text=True)
    check(p.returncode == 0, f"cct: {p.stderr}")
    return np.array([list(map(float, line.split()[:3])) for line in p.stdout.strip().splitlines()])


def outputs(tmp, site):
    rows, truth = [], {}
    v = np.array([6.0, -8.0])  # 10 m/s, heading 143.13 degrees
    for k in range(80):
        t = 0.1 * k
        truth[round(t, 6)] = v
        rows.append(detect(np.array([-20.0, 40.0]) + v * t, ellipse(0.5, 0.2, 60), "camA", t))
        rows.append(detect(np.array([30.0, -10.0]) + np.array([0.0, 5.0]) * t, ellipse(0.5, 0.2, 0), "camB", t))
    path, out = os.path.join(tmp, "out.csv"), os.path.join(tmp, "out.tracks.csv")
    gj, sd = os.path.join(tmp, "out.geojson"), os.path.join(tmp, "out.jsonl")
    write_located(path, rows)
    p = run_track(site, [path], out, "--geojson", gj, "--sdsm", sd)
    check(p.returncode == 0, f"outputs: roadside track failed: {p.stderr}")
    if p.returncode:
        return
    tr = read_tracks(out)
    first = [r for r in tr if r["track_id"] == tr[0]["track_id"]]
    heading_true = math.degrees(math.atan2(v[0], v[1])) % 360
    ok_h = sum(abs((r["heading_deg"] - heading_true + 180) % 360 - 180) <= 3.3 * r["sigma_heading_deg"] for r in first)
    ok_s = sum(abs(r["speed_mps"] - 10.0) <= 3.3 * r["sigma_speed_mps"] for r in first)
    print(f"speed within 3.3 sigma in {ok_s}/{len(first)} rows, heading in {ok_h}/{len(first)}")
    check(ok_h >= 0.99 * len(first) - 1 and ok_s >= 0.99 * len(first) - 1, "speed/heading against their sigmas")
    origin = site_origin(site)
    # the CSV has no height: the ground point u = 0 is at the origin's height (to (e^2 + n^2) / 2R,
    # 0.3 mm at 60 m, whose effect on east and north is 1e-9 of it)
    enu = cct_enu(origin, [(r["lon_deg"], r["lat_deg"], origin[2]) for r in tr])
    worst_csv = max(math.hypot(e[0] - r["e_m"], e[1] - r["n_m"]) for e, r in zip(enu, tr))
    with open(gj) as f:
        fc = json.load(f)
    feats = fc["features"]
    ids = sorted({r["track_id"] for r in tr})
    check([f["id"] for f in feats] == ids and all(f["geometry"]["type"] == "LineString" for f in feats),
          f"GeoJSON: features {[f['id'] for f in feats]} for tracks {ids}, LineStrings")
    worst_gj = 0.0
    for f in feats:
        mine = [r for r in tr if r["track_id"] == f["id"]]
        coords = f["geometry"]["coordinates"]
        check(len(coords) == len(mine) == len(f["properties"]["time_s"]), f"track {f['id']}: vertices per row")
        g = cct_enu(origin, coords)
        worst_gj = max([worst_gj] + [math.hypot(e[0] - r["e_m"], e[1] - r["n_m"]) for e, r in zip(g, mine)])
    print(f"lat/lon against cct: CSV {worst_csv * 1000:.3f} mm, GeoJSON {worst_gj * 1000:.3f} mm")
    check(worst_csv < 1e-3 and worst_gj < 1e-3, f"lat/lon vs cct: {worst_csv}, {worst_gj} m")
    with open(sd) as f:
        lines = [json.loads(x) for x in f]
    check(len(lines) == len(tr), f"SDSM: {len(lines)} lines for {len(tr)} rows")
    pos_b = [500, 200, 100, 50, 20, 10, 5, 2, 1, 0.5, 0.2, 0.1, 0.05, 0.02, 0.01]
    bad = 0
    for s, r in zip(lines, tr):
        cov = np.array([[r["sigma_e_m"] ** 2, r["cov_en_m2"]], [r["cov_en_m2"], r["sigma_n_m"] ** 2]])
        r95 = math.sqrt(5.991464547107979 * np.linalg.eigvalsh(cov)[-1])
        code = s["posConfidence"]["pos"]
        bad += not (s["objectID"] == r["track_id"] and s["pos"]["offsetX"] == round(r["e_m"] * 10) and
                    s["pos"]["offsetY"] == round(r["n_m"] * 10) and abs(s["speed"] - r["speed_mps"] / 0.02) <= 0.51 and
                    abs(s["heading"] - r["heading_deg"] / 0.0125) <= 0.51 and 1 <= code <= 15 and
                    pos_b[code - 1] >= r95 - 1e-4 and (code == 15 or pos_b[code] < r95 + 1e-4))
    check(bad == 0, f"SDSM: {bad} lines whose fields disagree with the CSV")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        site = make_site(tmp)
        two_cameras(tmp, site)
        short, long_ = handover(tmp, site, 0.5), handover(tmp, site, 1.5)
        print(f"hand-over: gap 0.5 s -> {len(short)} id(s); gap 1.5 s -> {len(long_)} id(s)")
        check(len(short) == 1, f"hand-over with a 0.5 s gap: ids {short}, want one")
        check(len(long_) == 2, f"hand-over with a 1.5 s gap (> max-age 1 s): ids {long_}, want two")
        crossing(tmp, site)
        asynchronous(tmp, site)
        outputs(tmp, site)


main()
finish("test_track_scenarios")

"""`roadside geo enu` and `roadside geo llh` against PROJ's cct (cart + topocentric pipeline),
both ways, to 1 micrometre: random points up to 20 km horizontally and +-1 km vertically from
origins at latitudes from the equator to 0.1 degree from the pole and longitudes up to +-180."""
import math
import os
import random
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import geo_oracle as g  # noqa: E402

ORIGINS = [  # lat_deg, lon_deg, h_m
    (0.0, 0.0, 0.0),
    (45.0, 15.0, 250.0),
    (-33.9, 151.2, 40.0),
    (60.2, 24.9, 10.0),
    (81.5, -62.3, 100.0),
    (-85.0, 179.99, 2800.0),
    (89.9, -179.95, 0.0),
    (0.001, -179.999, -30.0),
    (-12.3, 180.0, 5.0),
]
NPOINTS = 160  # per origin


def random_enu(rng):
    """Uniform in a disc of radius 20 km, up within +-1 km; plus the origin and the extremes."""
    pts = [(0.0, 0.0, 0.0), (20000.0, 0.0, 1000.0), (0.0, -20000.0, -1000.0)]
    while len(pts) < NPOINTS:
        r = 20000.0 * math.sqrt(rng.random())
        t = rng.uniform(0, 2 * math.pi)
        pts.append((r * math.cos(t), r * math.sin(t), rng.uniform(-1000.0, 1000.0)))
    return pts


def main():
    rng = random.Random(g.SEED)
    print(f"seed {g.SEED}")
    err_enu, err_llh, err_trip = [], [], []
    for lat0, lon0, h0 in ORIGINS:
        pipe = g.topocentric(lat0, lon0, h0)
        origin = f"--origin={lat0!r},{lon0!r},{h0!r}"
        enu = random_enu(rng)
        # cct: ENU -> (lon, lat, h); these geodetic points are the inputs of the llh -> ENU check
        lonlath = g.run_cct(pipe, enu, "%.9f %.9f %.9f", inverse=True)
        llh_in = [(p[1], p[0], p[2]) for p in lonlath]

        # llh -> ENU: roadside and cct on the same printed geodetic points
        ours = g.run_roadside(["enu", origin], llh_in, "%.12f %.12f %.9f")
        theirs = g.run_cct(pipe, [(p[1], p[0], p[2]) for p in llh_in], "%.12f %.12f %.9f")
        err_enu += [g.dist(a, b) for a, b in zip(ours, theirs)]

        # ENU -> llh: roadside against cct's inverse, compared in metres ...
        ours_llh = g.run_roadside(["llh", origin], enu, "%.9f %.9f %.9f")
        err_llh += [g.llh_dist_m(a, b) for a, b in zip(ours_llh, llh_in)]
        # ... and round trip: roadside's geodetic output back through cct's forward pipeline
        back = g.run_cct(pipe, [(p[1], p[0], p[2]) for p in ours_llh], "%.12f %.12f %.9f")
        err_trip += [g.dist(a, b) for a, b in zip(back, enu)]

        worst = max(err_enu[-len(enu):] + err_llh[-len(enu):] + err_trip[-len(enu):])
        print(f"  origin {lat0:9.4f} {lon0:10.4f} {h0:7.1f}: max error {worst:.3e} m")

    g.check_max("llh -> enu (roadside geo enu vs cct)", err_enu)
    g.check_max("enu -> llh (roadside geo llh vs cct -I)", err_llh)
    g.check_max("enu -> llh -> enu (roadside geo llh, then cct)", err_trip)
    return 0


if __name__ == "__main__":
    sys.exit(main())

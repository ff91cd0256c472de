"""UTM/UPS against PROJ's cct, to 1 micrometre: `roadside geo enu --from utm:ZONE` against the
pipeline inverse utm/ups + cart + topocentric, and `roadside geo utm [--zone ZONE]` against
+proj=utm / +proj=ups, for random points within 20 km (+-1 km in height) of origins in both
hemispheres, across the equator, next to the antimeridian, in the polar caps, and in a
neighbouring zone."""
import math
import os
import random
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import geo_oracle as g  # noqa: E402

CASES = [  # zone (0 = UPS), north, origin lat_deg, lon_deg, h_m
    (33, True, 45.0, 15.0, 250.0),
    (34, True, 45.0, 15.0, 250.0),     # a neighbouring zone, 6 degrees from its central meridian
    (31, True, 0.05, 3.0, 0.0),        # across the equator: northings continue below 0
    (1, True, 10.0, -179.8, 20.0),
    (60, False, -40.0, 179.8, 300.0),
    (19, False, -33.0, -70.0, 1500.0),
    (0, True, 87.0, 30.0, 0.0),
    (0, False, -88.0, -100.0, 2800.0),
]
NPOINTS = 100  # per case


def proj_grid(zone, north):
    """The proj-string of the UTM/UPS zone."""
    south = "" if north else " +south"
    if zone == 0:
        return f"+proj=ups{south} +ellps=WGS84"
    return f"+proj=utm +zone={zone}{south} +ellps=WGS84"


def zone_str(zone, north):
    """The zone as roadside prints it (GeographicLib's EncodeZone)."""
    return ("" if zone == 0 else "%02d" % zone) + ("n" if north else "s")


def standard_zone(lat, lon):
    """The standard UTM/UPS zone of a point away from the Norway and Svalbard exceptions."""
    if lat >= 84 or lat < -80:
        return zone_str(0, lat >= 0)
    return zone_str(int(math.floor((lon + 180) / 6)) % 60 + 1, lat >= 0)


def main():
    rng = random.Random(g.SEED)
    print(f"seed {g.SEED}")
    err_enu, err_utm = [], []
    for zone, north, lat0, lon0, h0 in CASES:
        grid = proj_grid(zone, north)
        zs = zone_str(zone, north)
        e0, n0, _ = g.run_cct(grid, [(lon0, lat0, h0)], "%.12f %.12f %.9f")[0]
        enh = [(e0, n0, h0)] + [(e0 + rng.uniform(-20000, 20000), n0 + rng.uniform(-20000, 20000),
                                 h0 + rng.uniform(-1000, 1000)) for _ in range(NPOINTS - 1)]

        # UTM -> ENU
        pipe = (f"+proj=pipeline +step +inv {grid} +step +proj=cart +ellps=WGS84 "
                f"+step +proj=topocentric +ellps=WGS84 +lat_0={lat0!r} +lon_0={lon0!r} +h_0={h0!r}")
        ours = g.run_roadside(["enu", f"--origin={lat0!r},{lon0!r},{h0!r}", f"--from=utm:{zs.upper()}"],
                              enh, "%.9f %.9f %.9f")
        theirs = g.run_cct(pipe, enh, "%.9f %.9f %.9f")
        e1 = [g.dist(a, b) for a, b in zip(ours, theirs)]

        # geodetic -> UTM in the zone, and the standard zone of each point
        lonlath = g.run_cct(grid, enh, "%.9f %.9f %.9f", inverse=True)
        llh = [(p[1], p[0], p[2]) for p in lonlath]
        ours = g.run_roadside(["utm", "--zone", zs], llh, "%.12f %.12f %.9f")
        theirs = g.run_cct(grid, lonlath, "%.12f %.12f %.9f")
        e2 = [g.dist(a[:3], b) for a, b in zip(ours, theirs)]
        if any(o[3] != zs for o in ours):
            g.fail(f"geo utm --zone {zs} printed zones {sorted(set(o[3] for o in ours))}")
        standard = g.run_roadside(["utm"], llh, "%.12f %.12f %.9f")
        for p, o in zip(llh, standard):
            if o[3] != standard_zone(p[0], p[1]):
                g.fail(f"geo utm: point {p} in zone {o[3]}, expected {standard_zone(p[0], p[1])}")

        print(f"  zone {zs:>3} origin {lat0:8.3f} {lon0:9.3f}: max error enu {max(e1):.3e} m, "
              f"utm {max(e2):.3e} m")
        err_enu += e1
        err_utm += e2

    g.check_max("utm -> enu (roadside geo enu --from utm vs cct)", err_enu)
    g.check_max("llh -> utm (roadside geo utm --zone vs cct)", err_utm)
    return 0


if __name__ == "__main__":
    sys.exit(main())

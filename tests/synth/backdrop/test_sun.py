#!/usr/bin/env python3
"""rs_synth_sun_position (NOAA / Meeus) against an INDEPENDENT formulation, the PSA algorithm of
Blanco-Muriel, Alarcon-Padilla, Lopez-Moratalla and Lara-Coira, "Computing the solar vector",
Solar Energy 70(5):431-441, 2001 (written here from the paper's equations, geocentric: its
parallax term is left out because rs_synth_sun_position is geocentric), and against the
published worked example of NREL's SPA (Reda & Andreas, "Solar position algorithm for solar
radiation applications", NREL/TP-560-34302, 2003/2008, table A4.1).

Cases: latitudes -89..89 (polar day and polar night included), longitudes around the world,
dates 2000..2050 at all hours. Tolerance: 0.1 degree on elevation, on azimuth where the sun is
within 85 degrees of the horizon (azimuth is ill-conditioned near the zenith and nadir), and on the angle between the two sun directions.
Usage: test_sun.py DUMP_BINARY"""
import math, random, subprocess, sys, calendar

SEED = 7
TOL_DEG = 0.1


def psa(lat, lon, t):
    """Azimuth (clockwise from north) and geometric elevation, degrees."""
    n = t / 86400.0 + 2440587.5 - 2451545.0
    hours = (t % 86400.0) / 3600.0
    omega = 2.1429 - 0.0010394594 * n
    L = 4.8950630 + 0.017202791698 * n
    g = 6.2400600 + 0.0172019699 * n
    lam = L + 0.03341607 * math.sin(g) + 0.00034894 * math.sin(2 * g) - 0.0001134 - 0.0000203 * math.sin(omega)
    eps = 0.4090928 - 6.2140e-9 * n + 0.0000396 * math.cos(omega)
    ra = math.atan2(math.cos(eps) * math.sin(lam), math.cos(lam)) % (2 * math.pi)
    decl = math.asin(math.sin(eps) * math.sin(lam))
    gmst = 6.6974243242 + 0.0657098283 * n + hours
    lmst = math.radians(gmst * 15.0 + lon)
    H = lmst - ra
    phi = math.radians(lat)
    cosz = math.cos(phi) * math.cos(H) * math.cos(decl) + math.sin(decl) * math.sin(phi)
    z = math.acos(max(-1.0, min(1.0, cosz)))
    az = math.atan2(-math.sin(H), math.tan(decl) * math.cos(phi) - math.sin(phi) * math.cos(H)) % (2 * math.pi)
    return math.degrees(az), 90.0 - math.degrees(z)


def vec(az, el):
    a, e = math.radians(az), math.radians(el)
    return (math.sin(a) * math.cos(e), math.cos(a) * math.cos(e), math.sin(e))


def angle(u, v):
    d = sum(x * y for x, y in zip(u, v))
    c = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    return math.degrees(math.atan2(math.sqrt(sum(x * x for x in c)), d))


def main():
    rng = random.Random(SEED)
    cases = []
    lats = [-89.0, -70.0, -45.0, -23.4, 0.0, 23.4, 40.0, 52.5, 69.65, 78.2, 89.0]
    for lat in lats:
        for _ in range(60):
            lon = rng.uniform(-180, 180)
            t = rng.uniform(calendar.timegm((2000, 1, 1, 0, 0, 0)), calendar.timegm((2050, 12, 31, 0, 0, 0)))
            cases.append((lat, lon, t))
    # Polar day and night at Tromso (69.65 N, 18.96 E): midnight sun at local midnight on
    # 21 June, the sun below the horizon at local noon on 21 December; and the poles.
    polar = [
        (69.65, 18.96, calendar.timegm((2024, 6, 21, 22, 44, 0)), "up"),
        (69.65, 18.96, calendar.timegm((2024, 12, 21, 10, 44, 0)), "down"),
        (-89.0, 0.0, calendar.timegm((2024, 6, 21, 12, 0, 0)), "down"),
        (89.0, 0.0, calendar.timegm((2024, 6, 21, 0, 0, 0)), "up"),
    ]
    cases += [p[:3] for p in polar]
    # SPA's worked example: 2003-10-17 12:30:30 at -7 h = 19:30:30 UTC, 39.742476 N, 105.1786 W;
    # SPA's topocentric zenith 50.11162 (with refraction at 820 mbar, 11 C: about 0.016 deg) and
    # azimuth 194.34024. Geometric elevation ~ 90 - 50.11162 - 0.016.
    spa_t = calendar.timegm((2003, 10, 17, 19, 30, 30))
    cases.append((39.742476, -105.1786, spa_t))
    text = "".join("%.9f %.9f %.3f\n" % c for c in cases)
    out = subprocess.run([sys.argv[1]], input=text, capture_output=True, text=True)
    if out.returncode != 0:
        print(out.stderr)
        print("FAIL: dump exited %d (seed %d)" % (out.returncode, SEED))
        return 1
    rows = [tuple(map(float, l.split())) for l in out.stdout.splitlines()]
    if len(rows) != len(cases):
        print("FAIL: %d rows for %d cases" % (len(rows), len(cases)))
        return 1
    worst_el = worst_az = worst_ang = 0.0
    fails = 0
    for (lat, lon, t), (az, el) in zip(cases, rows):
        if not (math.isfinite(az) and math.isfinite(el)):
            print("FAIL: NaN at", lat, lon, t)
            fails += 1
            continue
        raz, rel = psa(lat, lon, t)
        d_el = abs(el - rel)
        d_az = abs((az - raz + 180.0) % 360.0 - 180.0)
        d_ang = angle(vec(az, el), vec(raz, rel))
        worst_el, worst_ang = max(worst_el, d_el), max(worst_ang, d_ang)
        if abs(rel) < 85.0:
            worst_az = max(worst_az, d_az)
        if d_el > TOL_DEG or d_ang > TOL_DEG or (abs(rel) < 85.0 and d_az > TOL_DEG):
            print("FAIL: lat %g lon %g t %.0f: az %.4f el %.4f, PSA az %.4f el %.4f" % (lat, lon, t, az, el, raz, rel))
            fails += 1
    for (lat, lon, t, expect), (az, el) in zip(polar, rows[len(cases) - len(polar) - 1:-1]):
        if (el > 0) != (expect == "up"):
            print("FAIL: polar case lat %g t %.0f: elevation %.3f, expected the sun %s" % (lat, t, el, expect))
            fails += 1
    az, el = rows[-1]
    spa_el = 90.0 - 50.11162 - 0.016
    print("SPA example: az %.4f (SPA 194.3402), el %.4f (SPA geometric ~%.4f)" % (az, el, spa_el))
    if abs(az - 194.34024) > TOL_DEG or abs(el - spa_el) > TOL_DEG:
        print("FAIL: SPA example")
        fails += 1
    print("%d cases: max |d elevation| %.5f deg, max |d azimuth| (|el| < 85) %.5f deg, max angle %.5f deg"
          % (len(cases), worst_el, worst_az, worst_ang))
    if fails:
        print("FAIL: %d cases (seed %d)" % (fails, SEED))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

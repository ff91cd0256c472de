#!/usr/bin/env python3
# The shadow pass of differential rendering (roadside render --shadows, synth/povray/rs_synth_scene.h)
# with the real POV-Ray, against ray casting in this test: every ground pixel's centre is
# unprojected with mrcal onto the ground, and rays from there towards the sun and towards each
# sky light are tested against each vehicle's box (slab test).
#
#   lit      the sun's ray misses every vehicle box: lit fraction >= S / (S + K) - 0.01
#            (S = sin(sun elevation), the sun's share; K = 0.35, the clear sky's)
#   shadow   the sun's ray passes through the solid core of a vehicle (the middle of its box,
#            away from glass, wheels and roof): lit fraction <= K / (S + K) + 0.01
#   open     no light's ray meets any box: lit fraction 1 within 0.002. This checks the ground
#            alone that the pass divides by (computed, not rendered) against what POV-Ray draws.
#   overcast (--overcast) no sun; where the ray towards one of the 6 lights of the sky's lower
#            band passes through a core the lit fraction is <= 1 - 0.587 / 6 + 0.01 (that
#            light's share of the sky); open pixels still 1.
#   Each class is checked without its border pixels (a 3 x 3 erosion: the shadow pass's
#   coarse meshes differ from the boxes by up to a pixel); and
#   without the vehicles' own pixels (ids.png > 0), where the shadow is 1 (the pass does not
#   look under the vehicles: they hide the ground as green marks).
#   at once  the default (roadside rasterises the ID and shadow passes while povray renders the
#            colour pass) gives the same files,
#            bit for bit, as one after the other (--separate-processes), and the region covers
#            every shadow. (The shadow pass is rasterised on coarse meshes;
#            tests/synth/povray/test_shadow_coarse.c compares it with POV-Ray's full pass.)
import os
import re
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

SEED = 17
DIMS = (4.6, 1.8, 1.5)
SUN_AZ, SUN_EL = 200.0, 35.0
SKY = 0.35


def unit(az_deg, el_deg):
    a, e = np.radians(az_deg), np.radians(el_deg)
    return np.array([np.sin(a) * np.cos(e), np.cos(a) * np.cos(e), np.sin(e)])


# The sky of rs_synth_scene_lights: the zenith, and 6 lights at zenith 60 deg, azimuths 0, 60, ..
SKY_DIRS = [unit(0, 90)] + [unit(60.0 * k, 30.0) for k in range(6)]


def hits(g, d, v, lo, hi):
    """Rays from ground points g (N,3) along unit d (3,) meet vehicle v's box part lo..hi
    (fractions: x of L, y of W, z of H, each (min, max)) -> (N,) bool."""
    L, W, H = DIMS
    yaw = np.radians(v["yaw_deg"])
    fwd = np.array([np.sin(yaw), np.cos(yaw), 0.0])   # heading clockwise from north
    left = np.array([-np.cos(yaw), np.sin(yaw), 0.0])
    up = np.array([0.0, 0.0, 1.0])
    c = np.array([v["e"], v["n"], 0.0])
    axes = (fwd, left, up)
    size = (L, W, H)
    tmin = np.zeros(len(g))
    tmax = np.full(len(g), np.inf)
    for k in range(3):
        o = (g - c) @ axes[k]
        dd = d @ axes[k]
        a, b = lo[k] * size[k], hi[k] * size[k]
        if abs(dd) < 1e-12:
            inside = (o >= a) & (o <= b)
            tmax = np.where(inside, tmax, -np.inf)
            continue
        t1, t2 = (a - o) / dd, (b - o) / dd
        tmin = np.maximum(tmin, np.minimum(t1, t2))
        tmax = np.minimum(tmax, np.maximum(t1, t2))
    return tmax >= tmin


BOX = ((-0.5, 0.5), (-0.5, 0.5), (0.0, 1.0))
CORE = ((-0.35, 0.35), (-0.35, 0.35), (0.35, 0.55))
MARGIN = 0.03  # metres added around the whole box for "misses"


def dilated(box):
    L, W, H = DIMS
    s = (L, W, H)
    return tuple((lo - MARGIN / s[k], hi + MARGIN / s[k]) for k, (lo, hi) in enumerate(box))


def main():
    u.need_povray()
    import cv2
    import mrcal
    with tempfile.TemporaryDirectory() as tmp:
        calib, model, W, H, lens, intr = u.small_pinhole(tmp)
        vs = u.ground_vehicles(model, 4, SEED, v_range=(0.55, 0.9))
        for v in vs:
            v["length"], v["width"], v["height"] = DIMS
        veh = os.path.join(tmp, "veh.json")
        u.write_json(veh, vs)
        bg = np.full((H, W, 3), 128, np.uint8)
        bg_path = os.path.join(tmp, "bg.png")
        cv2.imwrite(bg_path, bg)
        common = ["render", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles", veh,
                  "--background", bg_path, "--shadows"]

        # ground point of every pixel centre
        rt_enu_cam = mrcal.invert_rt(model.extrinsics_rt_fromref())
        q = np.stack(np.meshgrid(np.arange(W, dtype=float), np.arange(H, dtype=float)), -1)
        d = mrcal.rotate_point_r(rt_enu_cam[:3], mrcal.unproject(q.reshape(-1, 2), lens, intr))
        c = rt_enu_cam[3:]
        down = d[:, 2] < -1e-6
        t = np.where(down, -c[2] / np.where(down, d[:, 2], -1), 0)
        g = c + t[:, None] * d

        def classify(direction, box):
            lo, hi = tuple(b[0] for b in box), tuple(b[1] for b in box)
            m = np.zeros(len(g), bool)
            for v in vs:
                m |= hits(g, direction, v, lo, hi)
            return m & down

        sun = unit(SUN_AZ, SUN_EL)
        S = np.sin(np.radians(SUN_EL))
        near_any = classify(sun, dilated(BOX))
        for sd in SKY_DIRS:
            near_any |= classify(sd, dilated(BOX))
        def inner(m):
            """The mask m without its border pixels (a 3 x 3 erosion): the shadow pass works on
            coarse meshes, whose outline differs from the boxes' by up to a pixel."""
            return cv2.erode(m.reshape(H, W).astype(np.uint8), np.ones((3, 3), np.uint8)).reshape(-1) > 0

        open_px = inner(down & ~near_any)
        lit_px = inner(down & ~classify(sun, dilated(BOX)))
        shadow_px = inner(classify(sun, CORE))

        runs = {}
        for name, extra in (("at_once", []), ("separate", ["--separate-processes"])):
            out = os.path.join(tmp, name)
            p = u.run(common + ["--sun", "%g,%g" % (SUN_AZ, SUN_EL), "-o", out] + extra)
            print(p.stdout.strip())
            w = p.stdout.split()
            # the ID and shadow passes rasterised by roadside (rs_synth_raster.h): the povray
            # processes are the colour pass's, 1 to 4 clusters of vehicles (rs_synth_render_cull.c)
            m = re.search(r"passes 3 processes (\d+)", p.stdout)
            if not m or not 1 <= int(m.group(1)) <= 4:
                u.fail("%s: expected 'passes 3 processes 1..4' in: %s" % (name, p.stdout), SEED)
            runs[name] = out
            if w[3] != str(len(vs)):
                u.fail("%s: %s of %d vehicles rendered" % (name, w[3], len(vs)), SEED)
        for f in ("shadow.png", "ids.png", "rgba.png", "image.png"):
            a = open(os.path.join(runs["at_once"], f), "rb").read()
            b = open(os.path.join(runs["separate"], f), "rb").read()
            if a != b:
                u.fail("%s differs between the processes at once and one after the other" % f, SEED)
        print("at once: shadow, ids, rgba, image identical to the processes one after the other")

        frac = cv2.imread(os.path.join(runs["at_once"], "shadow.png"), -1).astype(float) / 65535
        frac = frac.reshape(-1)
        # the vehicles' own pixels: shadow 1 (the pass does not look under them), not checked
        vehicle = cv2.imread(os.path.join(runs["at_once"], "ids.png"), -1).reshape(-1) > 0
        if np.any(frac[vehicle] != 1):
            u.fail("shadow not 1 on %d vehicle pixels" % int((frac[vehicle] != 1).sum()), SEED)
        lit_px &= ~vehicle
        shadow_px &= ~vehicle
        open_px &= ~vehicle
        checks = [
            ("lit", lit_px, lambda x: x >= S / (S + SKY) - 0.01),
            ("shadow", shadow_px, lambda x: x <= SKY / (S + SKY) + 0.01),
            ("open", open_px, lambda x: np.abs(x - 1) <= 0.002),
        ]
        for name, mask, ok in checks:
            n = int(mask.sum())
            bad = int((~ok(frac[mask])).sum())
            print("sun %g/%g: %-6s %6d pixels, %d outside the bound (values %.4f..%.4f)" %
                  (SUN_AZ, SUN_EL, name, n, bad, frac[mask].min(), frac[mask].max()))
            if n < 30:
                u.fail("%s: only %d pixels to check" % (name, n), SEED)
            if bad:
                u.fail("%s: %d of %d pixels outside the bound" % (name, bad, n), SEED)

        out = os.path.join(tmp, "overcast")
        p = u.run(common + ["--sun", "%g,%g" % (SUN_AZ, SUN_EL), "--overcast", "-o", out])
        print(p.stdout.strip())
        frac = cv2.imread(os.path.join(out, "shadow.png"), -1).astype(float).reshape(-1) / 65535
        vehicle = cv2.imread(os.path.join(out, "ids.png"), -1).reshape(-1) > 0
        near_sky = np.zeros(len(g), bool)
        for sd in SKY_DIRS:
            near_sky |= classify(sd, dilated(BOX))
        # beside the vehicles: the ground whose ray towards one of the 6 lights of the sky's
        # lower band passes through a vehicle's solid core (the ground under a vehicle, in
        # the zenith light's shadow, is hidden by the vehicle itself from this camera)
        ring = np.zeros(len(g), bool)
        for sd in SKY_DIRS[1:]:
            ring |= classify(sd, CORE)
        ring = inner(ring) & ~vehicle
        share = (1 - np.sin(np.radians(40)) ** 2) / 6
        for name, mask, ok in (("beside", ring, lambda x: x <= 1 - share + 0.01),
                               ("open", inner(down & ~near_sky) & ~vehicle, lambda x: np.abs(x - 1) <= 0.002)):
            n = int(mask.sum())
            bad = int((~ok(frac[mask])).sum())
            print("overcast: %-6s %6d pixels, %d outside the bound (values %.4f..%.4f)" %
                  (name, n, bad, frac[mask].min(), frac[mask].max()))
            if n < 30 or bad:
                u.fail("overcast %s: %d pixels, %d outside the bound" % (name, n, bad), SEED)
    print("all shadow checks passed")


if __name__ == "__main__":
    main()

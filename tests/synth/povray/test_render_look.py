#!/usr/bin/env python3
# issue 40: `roadside render --background` composites the vehicles and their shadows in the
# camera's own look (synth/povray/rs_synth_composite.h, docs/appearance.md): a vehicle is as
# noisy, soft and blocky as the road around it. Real POV-Ray, the demo site, a 480 x 300 pinhole
# of cam1, 10 vehicles with shadows.
#
# The background is made here: a clean road (a vertical gradient, grey patches of random levels
# and sizes, white stripes with sharp vertical edges), then degraded the way a camera does,
# with KNOWN parameters: Gaussian blur SIGMA_B px (in linear light, as a lens), signal-dependent
# noise of variance A + B v (stored values v in [0,1]), JPEG at quality Q (OpenCV). Oracles (all
# measured here with numpy/OpenCV, none of roadside's estimators):
#   noise   sigma = std(r) / sqrt(1.25), r = I - mean of the 4 neighbours, over flat pixels
#           (the clean background's 9x9 neighbourhood within 0.004, the clean vehicle layer's
#           (rgba.png) within 0.05: r cancels its smooth shading), binned by the clean stored
#           level (bins of 0.1 over [0.1, 0.9): clipping narrows the noise nearer 0 and 1); the
#           vehicles' sigma over the background's, averaged over the bins both fill (>= 150
#           pixels each);
#           vehicles: ids.png eroded by 3 px, background: 6 px away from any vehicle, unshadowed;
#   edges   the Gaussian sigma of an erf fitted (least squares over a grid of centre and sigma)
#           to 13-px horizontal luma profiles across the vehicles' silhouettes (ids.png changes
#           along a row, the same id 6 px on each side, contrast > 0.08), median, in the
#           composite against the same profiles of what the camera would have made: the clean
#           vehicles (rgba.png) over the clean background, blurred by SIGMA_B in linear light
#           (the content near a silhouette, a wheel or a window, then counts alike on both
#           sides). The background's stripes measured the same way read SIGMA_B (printed);
#   blocks  the ratio of mean |luma difference| across the 8-px JPEG block boundaries to that
#           inside the blocks, over neighbour pairs inside each region's flat pixels (as noise).
# With the look, each vehicle figure is within 15 % of its reference; with --no-appearance none
# is (asserted: the test shows that the look is what makes them match). Seed 40: noise 0.99,
# edges 0.94, blockiness 0.95 (without the look 0.29, 0.12, 0.61). Seeds 40..49 (SEED changed
# by hand): 9 of 10 pass; seed 41's edge ratio is 0.848 (vehicles slightly sharper than the
# camera's image of them there).
import os
import re
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

SEED = 40
SIGMA_B = 1.5
A, B = 1.0e-4, 6.0e-4
Q = 90
TOL = 0.15


def srgb_decode(v):
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


def srgb_encode(x):
    x = np.clip(x, 0, 1)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def clean_background(W, H, rng):
    """(H, W, 3) stored values: gradient, grey patches, white stripes."""
    y = np.linspace(0.30, 0.55, H)[:, None, None]
    img = np.repeat(np.repeat(y, W, 1), 3, 2).copy()
    for _ in range(40):
        w, h = rng.integers(12, 60, 2)
        x0, y0 = rng.integers(0, W - w), rng.integers(0, H - h)
        img[y0:y0 + h, x0:x0 + w] = rng.uniform(0.1, 0.8) * np.array([1.0, rng.uniform(0.95, 1.05), 1.0])
    stripes = []
    for k in range(6):
        x0 = int(15 + k * W / 6 + rng.integers(0, 8))
        img[:, x0:x0 + 9] = 0.9
        stripes += [x0, x0 + 9]
    return img, stripes


def degrade(clean, rng):
    import cv2
    lin = srgb_decode(clean)
    b = srgb_encode(cv2.GaussianBlur(lin, (0, 0), SIGMA_B))  # the lens blurs light: in linear light
    n = b + np.sqrt(A + B * np.clip(b, 0, 1)) * rng.standard_normal(b.shape)
    return np.clip(np.round(n * 255), 0, 255).astype(np.uint8)


def residual(img):
    """r = I - mean of the 4 neighbours, NaN at the border; white noise: var x 1.25."""
    r = np.full(img.shape, np.nan)
    r[1:-1, 1:-1] = img[1:-1, 1:-1] - 0.25 * (img[:-2, 1:-1] + img[2:, 1:-1] + img[1:-1, :-2] + img[1:-1, 2:])
    return r


def flat(clean, thr):
    """Pixels whose clean 9x9 neighbourhood varies by less than thr in every channel (the blur
    spreads an edge over about 3 SIGMA_B px)."""
    import cv2
    k = np.ones((9, 9), np.uint8)
    ok = np.ones(clean.shape[:2], bool)
    for c in range(3):
        ch = clean[..., c].astype(np.float32)
        ok &= (cv2.dilate(ch, k) - cv2.erode(ch, k)) < thr
    return ok


def noise_by_level(img, clean, mask):
    """{bin: (sigma, n)}: the standard deviation of r / sqrt(1.25) over each channel's pixels in
    mask, binned by the clean level (0.1 wide). A plain standard deviation over pixels whose clean
    content is flat or linear (r cancels it): a median of |r| takes only a few values when a
    JPEG leaves two or three 8-bit codes of noise."""
    out = {}
    r = residual(img)
    for c in range(3):
        lv, rc = clean[..., c][mask], r[..., c][mask]
        good = np.isfinite(rc)
        lv, rc = lv[good], rc[good]
        for k in range(1, 9):  # not within 0.1 of 0 or 1, where clipping narrows the noise
            sel = (lv >= k / 10) & (lv < (k + 1) / 10)
            if sel.sum() >= 50:
                s, n = out.get(k, ([], 0))
                out[k] = (s + list(rc[sel]), n + sel.sum())
    return {k: (np.std(np.array(s)) / np.sqrt(1.25), n) for k, (s, n) in out.items()}


def erf_sigma(profiles):
    """Median Gaussian sigma of an erf step a + b Phi((x - x0) / sigma) fitted by least squares
    to each (13,) profile (x = -6..6; grids: sigma 0.2..4 by 0.05, x0 -1.5..1.5 by 0.25)."""
    from math import erf
    x = np.arange(-6, 7, dtype=float)
    P = np.asarray(profiles, float).T  # (13, n)
    best_e = np.full(P.shape[1], np.inf)
    best_s = np.zeros(P.shape[1])
    for s in np.arange(0.2, 4.0, 0.05):
        for x0 in np.arange(-1.5, 1.51, 0.25):
            m = 0.5 * (1 + np.array([erf(t) for t in (x - x0) / (np.sqrt(2) * s)]))
            M = np.stack([np.ones_like(m), m], 1)
            R = np.eye(13) - M @ np.linalg.pinv(M)  # residual projector
            e = np.sum((R @ P) ** 2, 0)
            better = e < best_e
            best_e[better], best_s[better] = e[better], s
    return float(np.median(best_s)), P.shape[1]


def blockiness(luma, mask):
    """Mean |difference| across the 8-px boundaries over that inside, both directions, pairs
    with both pixels in mask."""
    ratios = []
    for axis in (0, 1):
        d = np.abs(np.diff(luma, axis=axis))
        m = mask[:-1, :] & mask[1:, :] if axis == 0 else mask[:, :-1] & mask[:, 1:]
        idx = np.arange(d.shape[axis])
        boundary = ((idx + 1) % 8 == 0)
        bmask = boundary[:, None] if axis == 0 else boundary[None, :]
        across, inside = d[m & bmask], d[m & ~bmask]
        if across.size < 100 or inside.size < 100:
            return float("nan")
        ratios.append(across.mean() / inside.mean())
    return float(np.mean(ratios))


def measure(out, clean_bg, stripes, ref_luma):
    import cv2
    img = u.read_png(os.path.join(out, "image.png")).astype(float) / 255
    ids = u.read_png(os.path.join(out, "ids.png")).astype(np.int64)
    rgba = u.read_png(os.path.join(out, "rgba.png")).astype(float) / 65535
    shadow = u.read_png(os.path.join(out, "shadow.png")).astype(float) / 65535
    H, W = ids.shape
    veh = ids > 0
    k7 = np.ones((7, 7), np.uint8)
    veh_in = cv2.erode(veh.astype(np.uint8), k7).astype(bool)
    near = cv2.dilate(veh.astype(np.uint8), np.ones((13, 13), np.uint8)).astype(bool)
    bg_open = ~near & (shadow > 0.999)
    clean_veh = srgb_encode(rgba[..., :3])
    # noise, at matched levels
    flat_v, flat_b = veh_in & flat(clean_veh, 0.05), bg_open & flat(clean_bg, 0.004)
    nv = noise_by_level(img, clean_veh, flat_v)
    nb = noise_by_level(img, clean_bg, flat_b)
    common = [k for k in nv if k in nb and nv[k][1] >= 150 and nb[k][1] >= 150]
    if not common:
        u.fail("no brightness bin with 150 flat pixels in both the vehicles and the background", SEED)
    ratio_noise = float(np.average([nv[k][0] / nb[k][0] for k in common], weights=[nv[k][1] for k in common]))
    print("  noise by level bin: " + ", ".join("%d: %.4f (%d) / %.4f (%d)" % (k, nv[k][0], nv[k][1], nb[k][0], nb[k][1])
                                               for k in sorted(common)))
    # edges: the vehicles' silhouettes (rows where the id changes), in the composite and in what
    # the camera would have made of the same scene: the clean vehicles over the clean background
    # (rgba.png's alpha over, in linear light), blurred by SIGMA_B in linear light; the same
    # profiles in both, so that what lies near a silhouette counts alike
    lin = rgba[..., 3:4] * rgba[..., :3] + (1 - rgba[..., 3:4]) * srgb_decode(clean_bg)
    camera_luma = srgb_encode(cv2.GaussianBlur(lin, (0, 0), SIGMA_B)).mean(2)
    luma = img.mean(2)
    vprof, cprof, bprof = [], [], []
    for y in range(H):
        row = ids[y]
        for x in range(7, W - 7):
            if row[x] != row[x - 1] and (row[x] == 0 or row[x - 1] == 0):
                left, right = row[x - 6:x], row[x:x + 6]
                if (left == left[0]).all() and (right == right[0]).all():
                    p = camera_luma[y, x - 6:x + 7]
                    if abs(p[-3:].mean() - p[:3].mean()) > 0.08:
                        vprof.append(luma[y, x - 6:x + 7])
                        cprof.append(p)
    for x in stripes:
        for y in range(8, H - 8, 3):
            if not near[y, x - 7:x + 7].any() and (shadow[y, x - 7:x + 7] > 0.999).all():
                bprof.append(luma[y, x - 6:x + 7])
    if len(vprof) < 20 or len(bprof) < 20:
        u.fail("too few edges: %d on vehicles, %d on the background" % (len(vprof), len(bprof)), SEED)
    ev, nvp = erf_sigma(vprof)
    ec, _ = erf_sigma(cprof)
    eb, nbp = erf_sigma(bprof)
    # blockiness
    kv, kb = blockiness(luma, flat_v), blockiness(luma, flat_b)
    return {"noise": ratio_noise, "noise_bins": common, "edge_v": ev, "edge_c": ec, "edge_b": eb,
            "edge_n": (nvp, nbp), "edge": ev / ec, "block_v": kv, "block_b": kb, "block": kv / kb}


def main():
    u.need_povray()
    import cv2
    rng = np.random.default_rng(SEED)
    with tempfile.TemporaryDirectory() as tmp:
        calib, model, W, H, lens, intr = u.small_pinhole(tmp, 480, 300)
        vs = u.ground_vehicles(model, 10, SEED, v_range=(0.55, 0.95))
        veh = os.path.join(tmp, "veh.json")
        u.write_json(veh, vs)
        clean, stripes = clean_background(W, H, rng)
        bg = os.path.join(tmp, "bg.jpg")
        cv2.imwrite(bg, degrade(clean, rng)[..., ::-1], [cv2.IMWRITE_JPEG_QUALITY, Q])
        outs = {}
        for look in (False, True):
            out = os.path.join(tmp, "look%d" % look)
            args = ["render", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles", veh, "--background", bg,
                    "--sun", "135,40", "--shadows", "-o", out]
            p = u.run(args + ([] if look else ["--no-appearance"]))
            print(("look: " if look else "no-appearance: ") + p.stdout.strip().replace("\n", " | "))
            if look and not re.search(r"^look: .*jpeg quality %d" % Q, p.stdout, re.M):
                u.fail("no 'look: ... jpeg quality %d' line: %r %r" % (Q, p.stdout, p.stderr), SEED)
            if not look and "look:" in p.stdout:
                u.fail("--no-appearance still applied a look", SEED)
            outs[look] = out
        ref_luma = u.read_png(os.path.join(outs[False], "image.png")).astype(float).mean(2) / 255
        ok = True
        for look in (True, False):
            m = measure(outs[look], clean, stripes, ref_luma)
            print("%-14s noise ratio %.3f (bins %s); silhouettes' edge sigma %.2f / the camera's %.2f px = %.3f "
                  "(%d profiles; the background's stripes %.2f px, %d profiles); blockiness %.3f / %.3f = %.3f"
                  % ("look" if look else "no-appearance", m["noise"], m["noise_bins"], m["edge_v"], m["edge_c"],
                     m["edge"], m["edge_n"][0], m["edge_b"], m["edge_n"][1], m["block_v"], m["block_b"], m["block"]))
            within = {k: abs(m[k] - 1) <= TOL for k in ("noise", "edge", "block")}
            if look and not all(within.values()):
                print("FAIL: with the look, outside 15 %%: %s" % [k for k, v in within.items() if not v])
                ok = False
            if not look and any(within.values()):
                print("FAIL: without the look, a figure within 15 %% (the test shows nothing): %s" % within)
                ok = False
        if not ok:
            u.fail("see above", SEED)
        print("ok")


if __name__ == "__main__":
    main()

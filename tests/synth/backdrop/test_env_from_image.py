# issue 18 (reflections of the scene itself): the environment the vehicles reflect, taken from
# the background photograph (rs_synth_env_from_image, rs_synth_env_match, through test_env_dump).
# Synthetic backgrounds made here with numpy: sRGB 8-bit images of 160x120 whose lower part is a
# noisy ground and upper part a noisy sky, through two pinhole cameras written here as
# .cameramodel files (5 m above a level ground, looking north 15 degrees down: a sliver of sky;
# 10 degrees up: ground, low sky and high sky).
# Oracle: numpy's own mask, computed here from the camera's ray of each pixel of the step grid
# (K^-1 q rotated into ENU, from cv2.Rodrigues of the pose), with the rule of synth/backdrop/rs_synth_light.h
# (ground: meets the plane up = 0 within 60 m horizontally; sky: rises, elevation <= 20 degrees
# horizon band, above it zenith band), and numpy's mean of the sRGB-decoded 8-bit values over it:
# the counts must be equal and the means within 1e-5 (printed to 7 decimals). Then the real
# POV-Ray: a grey sedan and a white hatchback composited-style (no ground in the image) under the
# environment of a neutral-ground background and of a red-ground one (the sky identical): the
# vehicles' pixels must move toward the red ground's colour -- the change of their mean colour
# points along the change of the ground's mean (cosine > 0.9) and is at least 0.003 in linear
# RGB; the red channel rises and green falls.
import os
import subprocess
import sys
import tempfile

import cv2
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from synth_test_util import fail  # noqa: E402

DUMP = sys.argv[1]
W, H, F = 160, 120, 170.0
SEED = 18


def srgb_decode(v):
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


def srgb_encode(v):
    v = np.clip(v, 0, 1)
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055)


def camera(pitch_deg):
    """R_cam_enu (rows: camera x, y, z in ENU) and t for a camera at (0, -12, 5) facing north."""
    p = np.radians(pitch_deg)
    z = np.array([0, np.cos(p), np.sin(p)])  # forward
    x = np.array([1.0, 0, 0])  # right
    y = np.cross(z, x)  # down
    R = np.array([x, y, z])
    C = np.array([0, -12.0, 5.0])
    return R, -R @ C, C


def write_model(path, R, t):
    r = cv2.Rodrigues(R)[0].ravel()
    with open(path, "w") as f:
        f.write("{'lensmodel': 'LENSMODEL_PINHOLE', 'intrinsics': [%r, %r, %r, %r], "
                "'imagersize': [%d, %d], 'extrinsics': [%r, %r, %r, %r, %r, %r]}\n"
                % (F, F, (W - 1) / 2, (H - 1) / 2, W, H, *r, *t))


def masks(R, C, step):
    """numpy's classes of the step grid: 0 ground, 1 horizon band, 2 zenith band, -1 neither."""
    ys = np.arange(step // 2, H, step)
    xs = np.arange(step // 2, W, step)
    X, Y = np.meshgrid(xs, ys)
    d_cam = np.stack([(X - (W - 1) / 2) / F, (Y - (H - 1) / 2) / F, np.ones_like(X, float)], -1)
    d = d_cam @ R  # R^T d_cam for each pixel
    cls = np.full(X.shape, -1)
    s = -C[2] / np.where(d[..., 2] != 0, d[..., 2], 1e-300)
    hit = (d[..., 2] < 0) & (s > 0)
    dist = np.hypot(s * d[..., 0], s * d[..., 1])
    cls[hit & (dist <= 60)] = 0
    el = np.degrees(np.arcsin(d[..., 2] / np.linalg.norm(d, axis=-1)))
    cls[(d[..., 2] > 0) & (el <= 20)] = 1
    cls[(d[..., 2] > 0) & (el > 20)] = 2
    return Y, X, cls


def background(path, ground_lin, rng):
    """Sky (blue-grey, brighter upwards) over the top 14 rows (the horizon of the camera looking 15
    degrees down is at row 59.5 - 170 tan 15 = 13.95), the ground below; noise on both."""
    img = np.zeros((H, W, 3))
    rows = np.arange(H)[:, None, None]
    sky = np.array([0.45, 0.55, 0.75]) * (1.2 - 0.4 * rows / 14)
    img[:] = np.where(rows < 14, sky, np.array(ground_lin))
    img *= 1 + 0.15 * rng.standard_normal((H, W, 3))
    q = np.round(srgb_encode(img) * 255).astype(np.uint8)
    cv2.imwrite(path, q[:, :, ::-1])
    return srgb_decode(q.astype(float) / 255)


def dump(model, png, step, outdir=None):
    args = [DUMP, model, png, str(step)] + ([outdir] if outdir else [])
    p = subprocess.run(args, capture_output=True, text=True)
    if p.returncode == 77:
        print("povray missing: skipped")
        sys.exit(77)
    if p.returncode != 0:
        fail("test_env_dump %s: %s" % (" ".join(args[1:]), p.stderr), SEED)
    out = {}
    for line in p.stdout.splitlines():
        k, *v = line.split()
        out[k] = [float(x) for x in v]
    return out


def main():
    rng = np.random.default_rng(SEED)
    tmp = tempfile.mkdtemp(prefix="rs_env_")
    neutral = os.path.join(tmp, "neutral.png")
    red = os.path.join(tmp, "red.png")
    lin_n = background(neutral, [0.10, 0.10, 0.10], rng)
    lin_r = background(red, [0.30, 0.05, 0.035], rng)
    # the same sky in both: the red image's sky is the neutral's
    q_n = cv2.imread(neutral)
    q_r = cv2.imread(red)
    q_r[:14] = q_n[:14]
    cv2.imwrite(red, q_r)
    lin_r = srgb_decode(q_r[:, :, ::-1].astype(float) / 255)

    for pitch in (-15.0, 10.0):
        R, t, C = camera(pitch)
        model = os.path.join(tmp, "cam%+d.cameramodel" % pitch)
        write_model(model, R, t)
        for step in (1, 2, 4):
            Y, X, cls = masks(R, C, step)
            for png, lin in ((neutral, lin_n), (red, lin_r)):
                got = dump(model, png, step)
                for k, name in enumerate(("ground", "horizon", "zenith")):
                    sel = cls == k
                    n = int(sel.sum())
                    mean = lin[Y[sel], X[sel]].mean(axis=0) if n else np.zeros(3)
                    g = got[name]
                    if int(g[3]) != n or np.max(np.abs(np.array(g[:3]) - mean)) > 1e-5:
                        fail("pitch %g step %d %s %s: roadside %s (N %d), numpy %s (N %d)"
                             % (pitch, step, os.path.basename(png), name, g[:3], g[3], mean, n), SEED)
                    print("pitch %+5.1f step %d %-11s %-7s N %5d  mean %s  (numpy: the same mask, |d| < 1e-5)"
                          % (pitch, step, os.path.basename(png), name, n, np.round(mean, 4)))
                # the sky: the brightest tenth of the pixels above the horizon (numpy's quantile, the
                # same definition as core/rs_stats.h), their mean
                above = (cls == 1) | (cls == 2)
                px = lin[Y[above], X[above]]
                if len(px):
                    y = px @ np.array([0.2126, 0.7152, 0.0722])
                    top = px[y >= np.quantile(y, 0.9)]
                    g = got["sky"]
                    if int(g[3]) != len(top) or np.max(np.abs(np.array(g[:3]) - top.mean(axis=0))) > 1e-5:
                        fail("pitch %g step %d %s sky: roadside %s (N %d), numpy %s (N %d)"
                             % (pitch, step, os.path.basename(png), g[:3], g[3], top.mean(axis=0), len(top)), SEED)
                # the matched environment: the image's colours where seen (>= 20 px), the default else
                env = np.array(got["env"]).reshape(3, 3)  # zenith, horizon, ground
                if got["zenith"][3] < 20 and got["sky"][3] >= 20 and \
                        np.max(np.abs(env[0] - np.array(got["sky"][:3]))) > 1e-6:
                    fail("env_match did not take the image's brightest sky for an unseen zenith", SEED)
                for k, row in ((0, 2), (1, 1), (2, 0)):
                    if got[("ground", "horizon", "zenith")[k]][3] >= 20:
                        if np.max(np.abs(env[row] - np.array(got[("ground", "horizon", "zenith")[k]][:3]))) > 1e-6:
                            fail("env_match did not take the image's %s" % ("ground", "horizon", "zenith")[k], SEED)

    # the real POV-Ray: the paint reflects the background's ground
    R, t, C = camera(-15.0)
    model = os.path.join(tmp, "cam-15.cameramodel")
    a = dump(model, neutral, 2, os.path.join(tmp, "render_neutral"))
    b = dump(model, red, 2, os.path.join(tmp, "render_red"))
    if a["paint"][3] < 500 or a["paint"][3] != b["paint"][3]:
        fail("vehicle pixels: %d and %d" % (a["paint"][3], b["paint"][3]), SEED)
    dp = np.array(b["paint"][:3]) - np.array(a["paint"][:3])
    dg = np.array(b["ground"][:3]) - np.array(a["ground"][:3])
    cos = dp @ dg / (np.linalg.norm(dp) * np.linalg.norm(dg))
    print("vehicle pixels %d: mean colour %s (neutral ground %s) -> %s (red ground %s); change %s, "
          "cosine with the ground's change %.3f"
          % (a["paint"][3], np.round(a["paint"][:3], 4), np.round(a["ground"][:3], 4), np.round(b["paint"][:3], 4),
             np.round(b["ground"][:3], 4), np.round(dp, 4), cos))
    if not (cos > 0.9 and np.linalg.norm(dp) > 0.003 and dp[0] > 0 and dp[1] < 0):
        fail("the paint did not move toward the red ground: change %s, cosine %.3f" % (dp, cos), SEED)
    print("OK")


if __name__ == "__main__":
    main()

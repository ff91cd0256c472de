#!/usr/bin/env python3
# roadside render with the real POV-Ray: region rendering and culling change nothing, the ID pass
# is exact and inside each vehicle's projected box, the composite is straight alpha in linear
# light, culling skips povray, a missing povray is a clear error, the povray.conf is written
# (what really confines povray is Landlock: test_povray_sandbox.py).
#
# Oracles: a full-frame render of the same scene (region/culling), mrcal.project of the box
# corners (ID pixels), the sRGB formulas recomputed with numpy (composite).
# Issue 38, fisheye (check_fisheye): a 640x480 Kannala-Brandt fisheye at the demo camera's pose,
# rendered on the fisheye canvas with shadows: region and full-frame renders give the same IDs
# and shadow; every ID pixel lies within 1 px of its box's projection (mrcal.project of CAHVORE
# along every segment between two corners, 65 samples each: a fisheye bends edges; 1 px for the
# nearest-neighbour resampling of the canvas); a vehicle more than 90 degrees off the axis is
# drawn, one behind the camera (more than 145 degrees off the axis, beyond the canvas's angle) is culled.
import os
import shutil
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

SEED = 6
DIMS = (4.6, 1.8, 1.5)  # every test vehicle's given box: the oracle knows it


def srgb_decode(c):
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def srgb_encode(c):
    c = np.clip(c, 0, 1)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)


def main():
    u.need_povray()
    import cv2
    import mrcal
    with tempfile.TemporaryDirectory() as tmp:
        calib, model, W, H, lens, intr = u.small_pinhole(tmp)
        vs = u.ground_vehicles(model, 6, SEED, v_range=(0.5, 0.9))
        for v in vs:
            v["length"], v["width"], v["height"] = DIMS
        # one vehicle far outside the view (behind the camera): culled
        rt_enu_cam = mrcal.invert_rt(model.extrinsics_rt_fromref())
        back = rt_enu_cam[3:] - 30 * mrcal.rotate_point_r(rt_enu_cam[:3], np.array([0, 0, 1.0]))
        vs.append({"class": "sedan", "e": float(back[0]), "n": float(back[1]), "yaw_deg": 0,
                   "length": DIMS[0], "width": DIMS[1], "height": DIMS[2], "id": "behind"})
        veh = os.path.join(tmp, "veh.json")
        u.write_json(veh, vs)
        rng = np.random.default_rng(SEED)
        bg = rng.integers(0, 256, (H, W, 3), dtype=np.uint8)
        bg_path = os.path.join(tmp, "bg.png")
        cv2.imwrite(bg_path, bg[:, :, ::-1])
        # --no-appearance: the compositing formula itself (the camera's look over a background,
        # whose noise, blur and JPEG this random background would set: test_render_look.py)
        common = ["render", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles", veh,
                  "--background", bg_path, "--no-appearance"]
        out = os.path.join(tmp, "out")
        full = os.path.join(tmp, "full")
        p = u.run(common + ["-o", out, "--keep"])
        print(p.stdout.strip())
        words = p.stdout.split()
        if words[1] != str(len(vs)) or words[3] != str(len(vs) - 1):
            u.fail("expected %d vehicles, %d rendered: %s" % (len(vs), len(vs) - 1, p.stdout), SEED)
        u.run(common + ["-o", full, "--full-frame"])
        ids = u.read_png(os.path.join(out, "ids.png"))
        ids_full = u.read_png(os.path.join(full, "ids.png"))
        if ids.dtype != np.uint16 or ids.shape != (H, W):
            u.fail("ids.png: %s %s" % (ids.dtype, ids.shape))
        if not np.array_equal(ids, ids_full):
            u.fail("ID pass differs between region and full-frame renders in %d pixels"
                   % (ids != ids_full).sum(), SEED)
        vals = set(np.unique(ids).tolist())
        if not vals <= set(range(len(vs) + 1)) or len(vs) in vals:
            u.fail("ID values %s: expected within 0..%d, the culled vehicle absent"
                   % (sorted(vals), len(vs) - 1), SEED)
        if len(vals) < 4:
            u.fail("only %d vehicles visible" % (len(vals) - 1), SEED)
        # every ID pixel centre lies inside its vehicle's projected box (pixel k spans k +- 0.5)
        for k in sorted(vals - {0}):
            c = u.box_corners_enu(vs[k - 1], *DIMS)
            q = mrcal.project(mrcal.transform_point_rt(model.extrinsics_rt_fromref(), c), lens,
                              intr)
            ys, xs = np.nonzero(ids == k)
            lo, hi = q.min(axis=0), q.max(axis=0)
            if xs.min() < lo[0] - 0.5 or xs.max() > hi[0] + 0.5 or \
               ys.min() < lo[1] - 0.5 or ys.max() > hi[1] + 0.5:
                u.fail("vehicle %d: ID pixels [%d..%d]x[%d..%d] outside its box [%.2f..%.2f]x"
                       "[%.2f..%.2f]" % (k - 1, xs.min(), xs.max(), ys.min(), ys.max(), lo[0],
                                         hi[0], lo[1], hi[1]), SEED)
        # colour: region render equals the full frame on every vehicle pixel
        rgba = u.read_png(os.path.join(out, "rgba.png")).astype(float) / 65535
        rgba_full = u.read_png(os.path.join(full, "rgba.png")).astype(float) / 65535
        d = np.abs(rgba - rgba_full).max(axis=2)[ids > 0]
        print("region vs full frame: max colour difference on %d vehicle pixels %.2e"
              % (d.size, d.max()))
        if np.mean(d > 1e-3) > 0.002:
            u.fail("region and full-frame colours differ on %d of %d vehicle pixels"
                   % ((d > 1e-3).sum(), d.size), SEED)
        if np.any(rgba[:, :, 3][ids > 0] < 0.999):
            u.fail("vehicle pixels not opaque", SEED)
        # composite: straight alpha, linear light, sRGB encoded; the background where alpha = 0
        img = u.read_png(os.path.join(out, "image.png")).astype(float) / 255
        a = rgba[:, :, 3:4]
        want = srgb_encode(a * rgba[:, :, :3] + (1 - a) * srgb_decode(bg / 255.0))
        e = np.abs(img - want).max()
        print("composite vs numpy: max %.4f (tolerance 1/255 + 16-bit rounding)" % e)
        if not np.isfinite(e) or e > 1.01 / 255:
            u.fail("composite differs from the linear-light straight-alpha formula by %.4f" % e)
        if not np.array_equal((img[a[:, :, 0] == 0] * 255).round(), bg[a[:, :, 0] == 0]):
            u.fail("background changed where nothing was rendered")
        # the povray.conf roadside writes (POV-Ray 3.7.0.10 does not enforce it: Landlock
        # confines povray, tests/synth/povray/test_povray_sandbox.py)
        conf = open(os.path.join(out, ".povray", "3.7", "povray.conf")).read()
        if "restricted" not in conf or "read+write = ." not in conf:
            u.fail("povray.conf does not restrict I/O:\n" + conf)
        # culling: nothing in view -> povray is not run, the image is the background
        u.write_json(veh, [vs[-1]])
        none = os.path.join(tmp, "none")
        p = u.run(["render", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles", veh,
                   "--background", bg_path, "-o", none, "--keep"])
        if " rendered 0 " not in p.stdout or os.path.exists(os.path.join(none, "povray.log")):
            u.fail("all vehicles culled, povray should not run: " + p.stdout)
        img = u.read_png(os.path.join(none, "image.png"))
        if not np.array_equal(img, bg) or u.read_png(os.path.join(none, "ids.png")).any():
            u.fail("culled render: image must be the background and IDs 0")
        # povray missing: a clear error, exit 1
        env = dict(os.environ, ROADSIDE_POVRAY=os.path.join(tmp, "no-such-povray"))
        import subprocess
        u.write_json(veh, vs[:1])
        p = subprocess.run([u.ROADSIDE] + common[:-3] + ["-o", os.path.join(tmp, "x")],
                           capture_output=True, text=True, env=env)
        if p.returncode != 1 or "cannot run" not in p.stderr:
            u.fail("missing povray: exit %d, stderr %r" % (p.returncode, p.stderr))
        check_fisheye(tmp)
    print("PASS")


def check_fisheye(tmp):
    import mrcal
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from test_pins import fisheye_camera
    calib = os.path.join(tmp, "fisheye")
    m = fisheye_camera(calib, (0.02, -0.004), 0)
    lens, intr = m.intrinsics()
    intr = intr.copy()
    intr[:4] = [170, 170, (641.3 + 0.5) / 2 - 0.5, (478.2 + 0.5) / 2 - 0.5]
    m = mrcal.cameramodel(intrinsics=(lens, intr), imagersize=(640, 480),
                          extrinsics_rt_fromref=m.extrinsics_rt_fromref())
    m.write(os.path.join(calib, "cam1.cameramodel"))
    rt = m.extrinsics_rt_fromref()
    c = mrcal.invert_rt(rt)[3:]
    vs, angles = [], []
    for k, (az, dist) in enumerate([(a, d) for d in (7, 12, 18, 60) for a in range(0, 360, 20)]):
        e, n = c[0] + dist * np.sin(np.radians(az)), c[1] + dist * np.cos(np.radians(az))
        pc = mrcal.transform_point_rt(rt, np.array([e, n, 0.7]))
        theta = np.degrees(np.arctan2(np.hypot(pc[0], pc[1]), pc[2]))
        q = mrcal.project(pc, lens, intr)
        inside = np.all(np.isfinite(q)) and 20 < q[0] < 620 and 20 < q[1] < 460
        if (inside and len(vs) < 6 and theta < 90) or (inside and theta > 92 and not any(a > 90 for a in angles)) \
                or (theta > 145 and not any(a > 145 for a in angles)):
            vs.append({"class": "sedan", "e": e, "n": n, "yaw_deg": 30.0 * k, "length": DIMS[0],
                       "width": DIMS[1], "height": DIMS[2], "id": "f%d" % k})
            angles.append(theta)
    angles = np.array(angles)
    if not (angles > 145).any() or not ((angles > 90) & (angles < 145)).any():
        u.fail("fisheye test setup: off-axis angles %s" % angles.round(1))
    veh = os.path.join(tmp, "veh_fisheye.json")
    u.write_json(veh, vs)
    common = ["render", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles", veh, "--shadows"]
    out, full = os.path.join(tmp, "fe_out"), os.path.join(tmp, "fe_full")
    p = u.run(common + ["-o", out])
    print("fisheye:", p.stdout.strip())
    u.run(common + ["-o", full, "--full-frame"])
    ids, ids_full = u.read_png(os.path.join(out, "ids.png")), u.read_png(os.path.join(full, "ids.png"))
    sh, sh_full = u.read_png(os.path.join(out, "shadow.png")), u.read_png(os.path.join(full, "shadow.png"))
    if not np.array_equal(ids, ids_full) or np.abs(sh.astype(int) - sh_full.astype(int)).max() > 1:
        u.fail("fisheye: region and full-frame renders differ: %d ID pixels, shadow by %d"
               % ((ids != ids_full).sum(), np.abs(sh.astype(int) - sh_full.astype(int)).max()))
    culled = int(np.argmax(angles > 145)) + 1
    if (ids == culled).any() or " rendered %d " % (len(vs) - 1) not in p.stdout:
        u.fail("fisheye: the vehicle behind the camera (%.1f deg) is not culled: %s" % (angles[culled - 1], p.stdout))
    worst, drawn = 0.0, []
    for k in sorted(set(np.unique(ids).tolist()) - {0}):
        cn = u.box_corners_enu(vs[k - 1], *DIMS)
        t = np.linspace(0, 1, 65)[:, None]
        pts = np.concatenate([cn[a] + t * (cn[b] - cn[a]) for a in range(8) for b in range(a + 1, 8)])
        q = mrcal.project(mrcal.transform_point_rt(rt, pts), lens, intr)
        lo, hi = q.min(axis=0), q.max(axis=0)
        ys, xs = np.nonzero(ids == k)
        d = max(lo[0] - 0.5 - xs.min(), xs.max() - hi[0] - 0.5, lo[1] - 0.5 - ys.min(), ys.max() - hi[1] - 0.5)
        worst = max(worst, d)
        drawn.append(angles[k - 1])
        if d > 1.0:
            u.fail("fisheye vehicle %d (%.1f deg off the axis): ID pixels %.2f px outside its projected box"
                   % (k - 1, angles[k - 1], d))
    if max(drawn) < 90:
        u.fail("fisheye: no vehicle drawn beyond 90 degrees (%s)" % np.round(drawn, 1))
    print("fisheye: region = full frame (IDs, shadow); %d vehicles drawn up to %.1f deg off the axis, ID pixels "
          "at most %.2f px outside their boxes; the one %.1f deg off culled"
          % (len(drawn), max(drawn), worst, angles[culled - 1]))


if __name__ == "__main__":
    main()

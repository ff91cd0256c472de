#!/usr/bin/env python3
"""core/rs_camera.h against mrcal's and OpenCV's own Python modules (independent oracles):
- .cameramodel files written by mrcal are read exactly; files written by roadside are read back by
  mrcal to 1e-6 (mrcal writes %f), roadside's YAML by roadside to 1e-12 (intrinsics, imager size, extrinsics);
- OpenCV YAML written by cv2.FileStorage (K, distortion as an OpenCV matrix or a list, R or rvec,
  tvec, P) is read as the mrcal model with the same projection (checked by projecting through
  mrcal and cv2.projectPoints: 1e-6 px); roadside's YAML is read back by cv2.FileStorage exactly,
  its R_cam_enu is cv2.Rodrigues(rvec) to 1e-15;
- projection agrees with mrcal.project(mrcal.transform_point_rt(...)) to 1e-9 px;
- ground location: the point lies on the plane (1e-9 m) and mrcal projects it back to the pixel
  (1e-6 px), for a pinhole and an OPENCV8 lens;
- refusals name the file and field: skew, a tilted sensor, a missing file, a rotation without a
  translation, and numbers no camera has (a principal point 6e11 px away, fy = 1e19 px, k1 = 1e153,
  a translation of 1e308 m: mrcal's unprojection looped on the first three), each within 20 s."""
import json
import os
import subprocess
import sys
import tempfile

import cv2
import mrcal
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from rs_check import check, finish  # noqa: E402



def run(*args, stdin=None):
    r = subprocess.run([DUMP, *args], input=stdin, capture_output=True, text=True)
    return r.returncode, r.stdout, r.stderr


def read(path):
    rc, out, err = run("read", path)
    return (json.loads(out) if rc == 0 else out.strip()), rc


def opencv8_model(rt):
    intr = np.array([1210.5, 1190.75, 961.25, 538.5, -0.08, 0.03, 2e-4, -1e-4, 0.001, 0.002, -0.001, 0.0005])
    return mrcal.cameramodel(intrinsics=("LENSMODEL_OPENCV8", intr), imagersize=(1920, 1080), extrinsics_rt_fromref=rt)


def main():
    rng = np.random.default_rng(11)
    tmp = tempfile.mkdtemp()
    rt = np.array([1.2, -0.3, 0.4, 5.0, -2.0, 30.0])

    # mrcal writes, roadside reads; roadside writes, mrcal and OpenCV read
    for name, model in (("opencv8", opencv8_model(rt)),
                        ("pinhole", mrcal.cameramodel(intrinsics=("LENSMODEL_PINHOLE", np.array([800., 810, 399.5, 299.5])),
                                                      imagersize=(800, 600), extrinsics_rt_fromref=rt))):
        path = os.path.join(tmp, name + ".cameramodel")
        model.write(path)
        cam, rc = read(path)
        check(rc == 0, f"{name}: read failed: {cam}")
        if rc:
            continue
        lens, intr = model.intrinsics()
        check(cam["lensmodel"] == lens, f"{name}: lens {cam['lensmodel']} vs {lens}")
        check(np.array_equal(np.array(cam["intrinsics"]), intr), f"{name}: intrinsics differ")
        check([cam["width"], cam["height"]] == list(model.imagersize()), f"{name}: imager size")
        check(np.array_equal(np.array(cam["rt_cam_enu"]), model.extrinsics_rt_fromref()), f"{name}: extrinsics")
        out_model, out_yaml = os.path.join(tmp, name + ".out.cameramodel"), os.path.join(tmp, name + ".out.yaml")
        rc, out, _ = run("write", path, out_model, out_yaml)
        check(rc == 0, f"{name}: write failed: {out}")
        back = mrcal.cameramodel(out_model)
        check(back.intrinsics()[0] == lens and np.allclose(back.intrinsics()[1], intr, rtol=0, atol=1e-6),
              f"{name}: mrcal reads back other intrinsics")
        check(np.allclose(back.extrinsics_rt_fromref(), rt, rtol=0, atol=1e-6), f"{name}: mrcal reads back other extrinsics")
        fs = cv2.FileStorage(out_yaml, cv2.FILE_STORAGE_READ)
        K, D = fs.getNode("camera_matrix").mat(), fs.getNode("distortion_coefficients").mat().ravel()
        rvec, tvec, R = (fs.getNode(k).mat() for k in ("rvec", "tvec", "R_cam_enu"))
        check(np.array_equal(K, np.array([[intr[0], 0, intr[2]], [0, intr[1], intr[3]], [0, 0, 1]])), f"{name}: YAML K")
        check(np.array_equal(D[:len(intr) - 4], intr[4:]), f"{name}: YAML distortion")
        check(np.array_equal(rvec.ravel(), rt[:3]) and np.array_equal(tvec.ravel(), rt[3:]), f"{name}: YAML rvec/tvec")
        check(np.abs(R - cv2.Rodrigues(rvec)[0]).max() < 1e-15, f"{name}: YAML R_cam_enu is not Rodrigues(rvec)")
        # round trip through roadside's own YAML
        again, rc = read(out_yaml)
        # R_cam_enu is read in preference to rvec (its nearest rotation, then Rodrigues): the last bits
        check(rc == 0 and np.array_equal(np.array(again["intrinsics"]), intr) and
              np.abs(np.array(again["rt_cam_enu"]) - rt).max() < 1e-12,
              f"{name}: roadside does not read its own YAML back: {again}")

        # projection against mrcal
        p = np.column_stack([rng.uniform(-20, 20, 200), rng.uniform(-20, 20, 200), rng.uniform(0, 3, 200)])
        p_cam = mrcal.transform_point_rt(rt, p)
        front = p_cam[:, 2] > 1
        rc, out, _ = run("project", path, stdin="".join("%.17g %.17g %.17g\n" % tuple(x) for x in p[front]))
        q = np.array([list(map(float, l.split())) for l in out.splitlines()])
        q_ref = mrcal.project(p_cam[front], lens, intr)
        err = np.nanmax(np.abs(q - q_ref))
        check(err < 1e-9, f"{name}: projection differs from mrcal by {err} px")
        print(f"{name}: read/write exact, projection within {err:.2e} px of mrcal")

        # ground location: pixels of points on the plane n . p = c
        n, c = np.array([0.02, -0.01, 1.0]), 0.3
        g = np.column_stack([rng.uniform(-15, 15, 300), rng.uniform(-15, 15, 300)])
        g = np.column_stack([g, (c - n[0] * g[:, 0] - n[1] * g[:, 1]) / n[2]])
        gc = mrcal.transform_point_rt(rt, g)
        qg = mrcal.project(gc[gc[:, 2] > 1], lens, intr)
        W, H = model.imagersize()
        inside = (qg[:, 0] > 0) & (qg[:, 0] < W - 1) & (qg[:, 1] > 0) & (qg[:, 1] < H - 1)
        qg = qg[inside]
        rc, out, _ = run("locate", path, *map(str, n), str(c), stdin="".join("%.17g %.17g\n" % tuple(x) for x in qg))
        located = np.array([list(map(float, l.split())) for l in out.splitlines()])
        ok = np.isfinite(located).all(axis=1)
        check(ok.all() and len(located) == len(qg) and len(qg) > 20, f"{name}: {np.sum(~ok)} of {len(qg)} pixels not located")
        plane = np.abs(located[ok] @ n - c).max()
        back = mrcal.project(mrcal.transform_point_rt(rt, located[ok]), lens, intr)
        reproj = np.abs(back - qg[ok]).max()
        check(plane < 1e-9 and reproj < 1e-6, f"{name}: located points off the plane by {plane} m, reprojected {reproj} px")
        print(f"{name}: {len(qg)} pixels located: on the plane within {plane:.1e} m, back to the pixel within {reproj:.1e} px")

    # OpenCV files written by cv2.FileStorage
    K = np.array([[1210.5, 0, 961.25], [0, 1190.75, 538.5], [0, 0, 1]])
    D5 = np.array([-0.08, 0.03, 2e-4, -1e-4, 0.001])
    R, _ = cv2.Rodrigues(rt[:3])
    P = K @ np.hstack([R, rt[3:].reshape(3, 1)])
    for name, fields in (("R+t+P", dict(camera_matrix=K, distortion_coefficients=D5.reshape(1, 5), R=R,
                                        tvec=rt[3:].reshape(3, 1), P=P)),
                         ("rvec+t", dict(K=K, D=D5.reshape(5, 1), rvec=rt[:3].reshape(3, 1), t=rt[3:].reshape(3, 1))),
                         ("intrinsics only, empty distortion", dict(camera_matrix=K, distortion_coefficients=np.zeros((0, 0))))):
        path = os.path.join(tmp, "cv.yaml")
        fs = cv2.FileStorage(path, cv2.FILE_STORAGE_WRITE)
        fs.write("image_width", 1920)
        fs.write("image_height", 1080)
        for k, v in fields.items():
            fs.write(k, v)
        fs.release()
        cam, rc = read(path)
        check(rc == 0, f"OpenCV {name}: {cam}")
        if rc:
            continue
        has_pose = "rvec" in fields or "R" in fields
        check(cam["has_pose"] == has_pose and cam["has_R"] == ("R" in fields) and cam["has_P"] == ("P" in fields),
              f"OpenCV {name}: flags {cam}")
        if has_pose:
            check(np.abs(np.array(cam["rt_cam_enu"]) - rt).max() < 1e-12, f"OpenCV {name}: pose {cam['rt_cam_enu']}")
        p_cam = np.column_stack([rng.uniform(-5, 5, 50), rng.uniform(-3, 3, 50), rng.uniform(8, 30, 50)])
        q_m = mrcal.project(p_cam, cam["lensmodel"], np.array(cam["intrinsics"]))
        d = fields.get("distortion_coefficients", fields.get("D"))
        d = np.zeros(5) if d is None or d.size == 0 else d.ravel()
        q_cv = cv2.projectPoints(p_cam.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), K, d)[0].reshape(-1, 2)
        err = np.abs(q_m - q_cv).max()
        check(err < 1e-6, f"OpenCV {name}: {cam['lensmodel']} projects {err} px away from cv2.projectPoints")
        print(f"OpenCV {name}: read as {cam['lensmodel']}, within {err:.1e} px of cv2.projectPoints")

    # refusals
    def refused(fields, pattern, what):
        path = os.path.join(tmp, "bad.yaml")
        fs = cv2.FileStorage(path, cv2.FILE_STORAGE_WRITE)
        for k, v in fields.items():
            fs.write(k, v)
        fs.release()
        msg, rc = read(path)
        check(rc == 1 and isinstance(msg, str) and path in msg and pattern in msg, f"{what}: {msg}")
    refused(dict(camera_matrix=np.array([[1000, 0.5, 500], [0, 1000, 400], [0, 0, 1]])), "camera_matrix: skew 0.5", "skew")
    refused(dict(camera_matrix=K, distortion_coefficients=np.array([0.1] * 12 + [0.01, 0.02])),
            "distortion_coefficients: 14 values with a tilted sensor", "tilted sensor")
    refused(dict(camera_matrix=K, rvec=rt[:3].reshape(3, 1)), "tvec (or t): missing", "rotation without translation")
    refused(dict(camera_matrix=np.eye(2)), "camera_matrix: 4 values, need 9", "2x2 K")
    # numbers no camera has (tests/fuzz found mrcal's unprojection looping on each): refused at
    # once, naming the file and field, where before `read` never returned
    def refused_model(lensmodel, intrinsics, extrinsics, size, pattern, what):
        path = os.path.join(tmp, "bad.cameramodel")
        with open(path, "w") as f:
            f.write(f"{{ 'lensmodel': '{lensmodel}', 'intrinsics': {intrinsics}, 'extrinsics': {extrinsics},"
                    f" 'imagersize': {size} }}\n")
        try:
            r = subprocess.run([DUMP, "read", path], capture_output=True, text=True, timeout=20)
        except subprocess.TimeoutExpired:
            check(False, f"{what}: still reading after 20 s")
            return
        msg = r.stdout.strip() + r.stderr.strip()
        check(r.returncode == 1 and path in msg and pattern in msg, f"{what}: rc {r.returncode}: {msg}")
    refused_model("LENSMODEL_OPENCV4", [1000, 1000, 642949672968.5, 359.5, -0.2, 0, .001, 0], [2, 0, 0, 0, 0, 0],
                  [1280, 7200], "focal lengths from the principal point (at most 1000)", "principal point 6e11 px")
    refused_model("LENSMODEL_CAHVOR", [1000, 1e19, 639.5, 259.5, 1.01, -0.02, 0.001, 0.002, 0.003],
                  [5, 0, 0, 0, 0, 0], [1280, 720], "pixels 1e-16 times as tall as wide", "fy = 1e19 px")
    refused_model("LENSMODEL_OPENCV8", [1661.2, 1661.2, 959.6, 75, -0.11e154, 0.2, 3e-6, -1e-4, 0, 0, 0, 0],
                  [0, 0, -5, 0, 0, 0], [1920, 1080], "value 5 of LENSMODEL_OPENCV8 is -1.1e+153", "k1 = -1e153")
    refused_model("LENSMODEL_PINHOLE", [1000, 1000, 639.5, 359.5], [0, 0, 0, 0, 0, 1e308], [1280, 720],
                  "extrinsics: value 6 is 1e+308: a translation (m) is at most 1e+07", "translation 1e308 m")
    msg, rc = read(os.path.join(tmp, "missing.cameramodel"))
    check(rc == 1 and "missing.cameramodel" in msg, f"missing file: {msg}")

    finish("test_camera")


if __name__ == "__main__":
    DUMP = sys.argv[1]
    main()

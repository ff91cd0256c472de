#!/usr/bin/env python3
"""Issue 42: `site check` refuses what calib cannot use, and says what is wrong in words that name
the field: intrinsics outside physical ranges (focal 1e300, cx = -1e9, k1 = 1e10), a horizontal
ground normal, camera ids equal but for case or holding a bidirectional override, a symbolic link
loop (was "missing file"), OpenCV YAML whose image_width is 2^40 (was "image_width: 0 ...") or
whose first line is wrong (was "cam1.yaml: : ..."). Each case is a copy of a simulated site with
one thing changed; the oracle is the change itself (which field, which range)."""
import json
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from rs_check import check, finish, run  # noqa: E402

YAML = ("%YAML:1.0\n---\nimage_width: {w}\nimage_height: 1080\ncamera_matrix: !!opencv-matrix\n   rows: 3\n"
        "   cols: 3\n   dt: d\n   data: [ {fx}, 0., {cx}, 0., 1200., 540., 0., 0., 1. ]\n"
        "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n   data: [ {k1}, 0., 0., 0., 0. ]\n")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        base = os.path.join(tmp, "base")
        p = run("site", "simulate", base, "--seed", "3", "--cameras", "2")
        check(p.returncode == 0, f"site simulate: {p.stderr}")

        def case(name, edit, *want, rc=1):
            site = os.path.join(tmp, name)
            shutil.copytree(base, site, symlinks=True)
            sj = json.load(open(os.path.join(site, "site.json")))
            edit(site, sj)
            json.dump(sj, open(os.path.join(site, "site.json"), "w"))
            p = run("site", "check", site, timeout=30)
            ok = p.returncode == rc and all(w in p.stdout for w in want)
            check(ok, f"{name}: exit {p.returncode} (want {rc}), want {want} in {p.stdout[-500:]!r}")
            if ok and rc:
                print(f"{name}: {next(l for l in p.stdout.splitlines() if want[0] in l)}")

        def yaml(**kw):
            v = {"w": 1920, "fx": 1200.0, "cx": 960.0, "k1": -0.1}
            v.update(kw)
            def edit(site, sj):
                open(os.path.join(site, "cameras", "cam1.yaml"), "w").write(YAML.format(**v))
                sj["cameras"][0]["model"] = "cameras/cam1.yaml"
            return edit

        case("yaml_ok", yaml(), "0 errors", rc=0)
        # numbers no camera has are refused by the reader itself (core/rs_camera.c rs_camera_check:
        # mrcal's unprojection loops for ever on some), naming the file and the value
        case("focal_1e300", yaml(fx="1e300"), "cam1.yaml: intrinsics: fx = 1e+300, fy = 1200: pixels")
        case("cx_minus_1e9", yaml(cx="-1e9"), "cam1.yaml: intrinsics: fx = 1200, fy = 1200, cx = -1e+09",
             "focal lengths from the principal point (at most 1000)")
        case("k1_1e10", yaml(k1="1e10"), "cam1.yaml: intrinsics: value 5 of LENSMODEL_OPENCV5 is 1e+10")
        # the site's own ranges, tighter, for values a camera file could hold
        case("cx_4000", yaml(cx="4000"), "cam1.yaml: cx: 4000 px is outside [-960, 2880] px")
        case("k1_5000", yaml(k1="5000"), "cam1.yaml: distortion[0]: 5000 is outside [-1000, 1000]")
        case("width_2_40", yaml(w=2 ** 40), "cam1.yaml: image_width: 1099511627776 is outside [1, 1000000]")
        def bad_first_line(site, sj):
            open(os.path.join(site, "cameras", "cam1.yaml"), "w").write("image_width: 1920\n")
            sj["cameras"][0]["model"] = "cameras/cam1.yaml"
        case("yaml_first_line", bad_first_line, "cam1.yaml:1: not OpenCV YAML")
        site_out = run("site", "check", os.path.join(tmp, "yaml_first_line")).stdout
        check(": : " not in site_out, f"an empty field in the message: {site_out!r}")

        case("ground_horizontal_normal", lambda s, sj: sj.update(ground_plane={"normal_enu": [1, 0, 0], "offset_m": 0}),
             "ground_plane.normal_enu: [1, 0, 0] tilts the ground 90.0 degrees from level: at most 45")
        case("ground_tilted_10", lambda s, sj: sj.update(ground_plane={"normal_enu": [0, 0.17, 0.98], "offset_m": 0}),
             "0 errors", rc=0)

        def case_dup(site, sj):
            sj["cameras"][1]["id"] = "CAM1"
        case("camera_id_case", case_dup, "duplicate camera id 'CAM1' (already used by cameras[0] as 'cam1'")
        def bidi(site, sj):
            sj["cameras"][0]["id"] = "cam\u202e1"
        case("camera_id_bidi", bidi, "cameras[0].id", "invisible control character")
        def comma(site, sj):
            sj["cameras"][0]["id"] = "cam,1"
        case("camera_id_comma", comma, "cameras[0].id", "other than a letter, a digit")

        def loop(site, sj):
            os.symlink("loop_b.cameramodel", os.path.join(site, "cameras", "loop_a.cameramodel"))
            os.symlink("loop_a.cameramodel", os.path.join(site, "cameras", "loop_b.cameramodel"))
            sj["cameras"][0]["model"] = "cameras/loop_a.cameramodel"
        case("symlink_loop", loop, "loop_a.cameramodel: a loop of symbolic links")
    finish("test_site_ranges")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
# roadside scene: a self-contained .pov + .ini that povray renders at the camera's exact size;
# strings from the vehicles file cannot inject POV-Ray directives; bad input gives a message
# naming the file, index and field, exit 1, and nothing written.
import os
import re
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

EVIL = ['a"b', '#declare Evil = 1;', 'x\n#include "/etc/passwd"\n', '}} sphere { 0, 1e9 }',
        '//\n#fopen F "/tmp/owned" write', '\\" #end']


def check_camera(text, model):
    """POV-Ray's ray through the centre of pixel (i, j) (docs/povray.md: x_s = (i+0.5)/W - 0.5,
    y_s = 0.5 - (j+0.5)/H, D + x_s R + y_s U), taken back to ENU and projected by mrcal, must
    land on (i, j): 1e-9 px over a grid including the corners."""
    import mrcal
    import numpy as np
    vec = {}
    for name in ("location", "right", "up", "direction"):
        m = re.search(name + r"\s+<([^>]*)>", text)
        x, y, z = map(float, m.group(1).split(","))
        vec[name] = np.array([x, z, y])  # <e, u, n> -> ENU
    W, H = model.imagersize()
    lens, intr = model.intrinsics()
    i, j = np.meshgrid(np.linspace(0, W - 1, 9), np.linspace(0, H - 1, 7))
    xs = (i + 0.5) / W - 0.5
    ys = 0.5 - (j + 0.5) / H
    d = vec["direction"] + xs[..., None] * vec["right"] + ys[..., None] * vec["up"]
    p = vec["location"] + 50 * d
    q = mrcal.project(mrcal.transform_point_rt(model.extrinsics_rt_fromref(), p), lens, intr)
    err = np.abs(q - np.stack((i, j), axis=-1)).max()
    print("POV-Ray camera rays vs mrcal.project: max %.2e px (fx %.3f fy %.3f cx %.3f cy %.3f)"
          % (err, *intr[:4]))
    if not np.isfinite(err) or err > 1e-9:
        u.fail("POV-Ray camera rays miss their pixels by %.3g px" % err)


def main():
    with tempfile.TemporaryDirectory() as tmp:
        calib = os.path.join(tmp, "calib")
        model = u.scaled_camera(calib, "cam1", 160, True, height=100, fy_over_fx=0.93, dcx=-6.2,
                                dcy=3.7)
        vs = u.ground_vehicles(model, 6, 3)
        for v, evil in zip(vs, EVIL):
            v["id"] = evil
        vs[0]["colour"] = "#c0c0c0"
        vs[1]["colour"] = [0.1, 0.2, 0.3]
        vs[2].update(length=4.2, width=1.7, height=1.45, variant=17)
        veh = os.path.join(tmp, "veh.json")
        u.write_json(veh, vs)
        pov = os.path.join(tmp, "scene.pov")
        p = u.run(["scene", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles", veh,
                   "-o", pov, "--pins", "--time", "2024-06-21T14:00:00+02:00"])
        print(p.stdout.strip())
        text = open(pov).read()
        ini = open(os.path.join(tmp, "scene.ini")).read()
        # injection: every directive is one roadside writes itself; no raw id survives
        directives = set(re.findall(r"#\s*([a-z_]+)", text))
        if not directives <= {"version", "declare"}:
            u.fail("unexpected directives in the scene: %s" % sorted(directives))
        for evil in EVIL:
            if evil in text:
                u.fail("input string %r written into the scene" % evil)
        if "Width=160" not in ini or "Height=100" not in ini:
            u.fail("the .ini does not carry the exact size:\n" + ini)
        if "look_at" in text or "angle" in text:
            u.fail("the camera must use explicit vectors only")
        import mrcal
        check_camera(text, mrcal.cameramodel(os.path.join(calib, "cam1.cameramodel")))
        # povray parses and renders it (the evil ids must not break parsing either)
        if u.shutil_which_povray():
            os.makedirs(os.path.join(tmp, ".povray", "3.7"), exist_ok=True)
            with open(os.path.join(tmp, ".povray", "3.7", "povray.conf"), "w") as f:
                f.write("[File I/O Security]\nrestricted\n[Permitted Paths]\nread+write = .\n")
            r = subprocess.run(["povray", "scene.ini"], cwd=tmp, capture_output=True, text=True,
                               env=dict(os.environ, HOME=tmp))
            png = u.read_png(os.path.join(tmp, "scene.png"))
            if r.returncode != 0 or png.shape[:2] != (100, 160):
                u.fail("povray on the scene: exit %d, %s\n%s" % (r.returncode, png.shape,
                                                                  r.stderr[-2000:]))
            if os.path.exists("/tmp/owned"):
                u.fail("the scene wrote a file")
        # a user model used twice is declared once and instanced
        with open(os.path.join(tmp, "box.obj"), "w") as f:
            f.write("v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nv 0 0 1\nv 2 0 1\nv 2 1 1\nv 0 1 1\n"
                    "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n")
        two = [{"model": "box.obj", "scale": 2, "e": v["e"], "n": v["n"], "yaw_deg": 10 * k,
                "id": "m%d" % k} for k, v in enumerate(vs[:2])] + vs[2:3]
        u.write_json(os.path.join(tmp, "two.json"), two)
        pov2 = os.path.join(tmp, "two.pov")
        u.run(["scene", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles",
               os.path.join(tmp, "two.json"), "-o", pov2])
        text2 = open(pov2).read()
        decl = re.findall(r"#declare (RS_MESH_[0-9]+)", text2)
        uses = re.findall(r"object \{ (RS_MESH_[0-9]+)", text2)
        if len(decl) != 2 or len(uses) != 3 or uses[0] != uses[1]:
            u.fail("OBJ model twice + 1 procedural: declared %s, used %s" % (decl, uses))
        # bad inputs: exit 1, a message naming file, index and field, nothing written
        bad_cases = [
            ([{"class": "sedan", "e": 1, "n": 2}], "[0].yaw_deg"),
            ([{"class": "spaceship", "e": 1, "n": 2, "yaw_deg": 0}], "[0].class"),
            ([vs[0], {"class": "van", "e": "x", "n": 2, "yaw_deg": 0}], "[1].e"),
            ([{"class": "van", "e": 1, "n": 2, "yaw_deg": 0, "length": -1}], "[0].length"),
            ([{"class": "spaceship", "model": "a.obj", "e": 1, "n": 2, "yaw_deg": 0}], "[0].class"),
            ([{"model": "a.obj", "e": 1, "n": 2, "yaw_deg": 0, "width": 2}], "[0].width"),
            ([{"model": "a.obj", "e": 1, "n": 2, "yaw_deg": 0, "paint_materials": "Body"}],
             "[0].paint_materials"),
            ([{"class": "van", "e": 1, "n": 2, "yaw_deg": 0, "colour": "red"}], "[0].colour"),
            ({"class": "van"}, "list"),
        ]
        for k, (content, field) in enumerate(bad_cases):
            bad = os.path.join(tmp, "bad%d.json" % k)
            u.write_json(bad, content)
            out = os.path.join(tmp, "bad%d.pov" % k)
            p = u.run(["scene", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles", bad,
                       "-o", out], expect=1)
            if field not in p.stderr or bad not in p.stderr:
                u.fail("case %d: message %r does not name %s and %s" % (k, p.stderr, bad, field))
            if os.path.exists(out) or os.path.exists(out[:-4] + ".ini"):
                u.fail("case %d: output written despite the error" % k)
        with open(os.path.join(tmp, "broken.json"), "w") as f:
            f.write('[\n{"class": "van",\n "e": 1,,\n}]')
        p = u.run(["scene", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles",
                   os.path.join(tmp, "broken.json"), "-o", os.path.join(tmp, "b.pov")], expect=1)
        if "broken.json:3" not in p.stderr:
            u.fail("malformed JSON: message %r does not name line 3" % p.stderr)
        for args in (["--sun", "10"], ["--time", "2024-06-21 14:00"], ["--sun", "1,2", "--time",
                                                                        "2024-06-21T14:00Z"]):
            u.run(["scene", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles", veh, "-o",
                   os.path.join(tmp, "s.pov")] + args, expect=2)
        p = u.run(["scene", "--help"])
        if not p.stdout.startswith("usage: roadside scene"):
            u.fail("scene --help")
        p = u.run(["render", "--help"])
        if not p.stdout.startswith("usage: roadside render"):
            u.fail("render --help")
    print("PASS")


if __name__ == "__main__":
    main()

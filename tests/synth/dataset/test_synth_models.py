#!/usr/bin/env python3
# Issue 40: `roadside synth --models FILE`, a library of user models (docs/fleet.md, "User models").
# On the demo site at 160x90, a library of the test's textured box (tests/synth/synth_model_util.py)
# as a "sedan" of length 4.4 m (OBJ) and an "suv" of length 4.8 m (glTF, paint_materials): every
# sedan and suv label carries the class and the scaled model's box (box3d.dimensions_m = the box
# 4 x 2 x 1.5 scaled to the length, within 1e-6 m: the oracle is the scale computed here), the
# other classes stay procedural (their dimensions are not the models'); the same run without the
# library gives sedans of drawn sizes (so the check above can fail). The images are rendered
# (textures written once per run, linked into each image's work folder, the cache removed at
# the end). run.json records the library, so the folder refuses another. Bad libraries: errors
# name FILE, the entry and the field.
import json
import os
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402
from synth_model_util import texture, write_gltf, write_mtl, write_obj  # noqa: E402

SEED = 41
BOX = np.array([4.0, 2.0, 1.5])
LENGTHS = {"sedan": 4.4, "suv": 4.8}


def synth(calib, out, extra=(), expect=0):
    return u.run(["synth", "--val-fraction", "0", u.DEMO, "--calib", calib, "--count", "3", "-o", out, "--seed", str(SEED),
                  "--camera", "cam1", "--size", "160x90", "--vehicles", "10"] + list(extra), expect=expect)


def annotations(out):
    coco = json.load(open(os.path.join(out, "annotations", "instances_train2017.json")))
    names = {c["id"]: c["name"] for c in coco["categories"]}
    return [(names[a["category_id"]], np.array(a["box3d"]["dimensions_m"])) for a in coco["annotations"]]


def main():
    u.need_povray()
    import cv2
    with tempfile.TemporaryDirectory() as tmp:
        calib = u.demo_calib(tmp)
        lib_dir = os.path.join(tmp, "lib")
        os.makedirs(os.path.join(lib_dir, "box"))
        cv2.imwrite(os.path.join(lib_dir, "box", "skin.png"), texture()[:, :, ::-1])
        write_obj(os.path.join(lib_dir, "box", "box.obj"), "box.mtl")
        write_mtl(os.path.join(lib_dir, "box", "box.mtl"), "skin.png")
        write_gltf(os.path.join(lib_dir, "box", "box.gltf"), "skin.png")
        lib = os.path.join(lib_dir, "models.json")
        u.write_json(lib, [{"model": "box/box.obj", "class": "sedan", "length": LENGTHS["sedan"],
                            "forward": "+x", "up": "+z"},
                           {"model": "box/box.gltf", "class": "suv", "length": LENGTHS["suv"],
                            "forward": "+x", "up": "+z", "paint_materials": ["Skin"]}])
        out = os.path.join(tmp, "with")
        p = synth(calib, out, ["--models", lib])
        if "models:" not in p.stdout:
            u.fail("synth --models does not report the library: %r" % p.stdout)
        anns = annotations(out)
        n_model = {"sedan": 0, "suv": 0}
        for cls, dims in anns:
            if cls in LENGTHS:
                want = BOX * LENGTHS[cls] / BOX[0]
                if not np.allclose(dims, want, atol=1e-6):
                    u.fail("%s label: box %s, the model's is %s" % (cls, dims, want), SEED)
                n_model[cls] += 1
            elif any(np.allclose(dims, BOX * L / BOX[0], atol=1e-6) for L in LENGTHS.values()):
                u.fail("%s label has a model's box %s" % (cls, dims), SEED)
        print("with --models: %d labels, sedan models %d, suv models %d" % (len(anns), n_model["sedan"],
                                                                          n_model["suv"]))
        if n_model["sedan"] + n_model["suv"] < 2 or len(anns) - sum(n_model.values()) < 1:
            u.fail("too few labels to tell: %s of %d" % (n_model, len(anns)), SEED)
        if os.path.exists(os.path.join(out, "work")):  # the run's texture cache removed at its end
            u.fail("DATASET/work left behind: %s" % os.listdir(os.path.join(out, "work")))
        if len(os.listdir(os.path.join(out, "train2017"))) < 3:
            u.fail("images missing in %s" % os.listdir(os.path.join(out, "train2017")))
        # run.json records the library (entries, SHA-256): the same folder refuses another library
        run = json.load(open(os.path.join(out, "run.json")))["run"]
        if run.get("models", {}).get("entries") != 2 or len(run["models"].get("sha256", "")) != 64:
            u.fail("run.json: models %r" % run.get("models"))
        lib2 = os.path.join(lib_dir, "models2.json")
        u.write_json(lib2, [{"model": "box/box.obj", "class": "sedan", "length": 4.0}])
        p = synth(calib, out, ["--models", lib2], expect=1)
        if "another run" not in p.stderr:
            u.fail("another library into the same folder: %r" % p.stderr)
        # without the library the same sedans have drawn sizes
        out0 = os.path.join(tmp, "without")
        synth(calib, out0)
        sedans = [d for c, d in annotations(out0) if c == "sedan"]
        if sedans and all(np.allclose(d, BOX * LENGTHS["sedan"] / BOX[0], atol=1e-6) for d in sedans):
            u.fail("without --models the sedans have the model's box", SEED)
        # bad libraries: FILE, entry and field named, exit 1
        cases = [([{"model": "box/box.obj"}], "[0].class"),
                 ([{"model": "box/box.obj", "class": "sedan"}, {"model": "box/box.obj", "class": "tank"}], "[1].class"),
                 ([{"model": "box/none.obj", "class": "sedan"}], "[0].model"),
                 ([{"model": "box/box.obj", "class": "sedan", "length": -2}], "[0].length"),
                 ({"model": "box/box.obj"}, "list")]
        for k, (content, field) in enumerate(cases):
            bad = os.path.join(lib_dir, "bad%d.json" % k)
            u.write_json(bad, content)
            p = synth(calib, os.path.join(tmp, "bad%d" % k), ["--models", bad], expect=1)
            if bad not in p.stderr or field not in p.stderr:
                u.fail("bad library %d: message %r does not name %s and %s" % (k, p.stderr, bad, field))
        print("synth --models: labels carry the models' classes and boxes; bad libraries named")


if __name__ == "__main__":
    main()

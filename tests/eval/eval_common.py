"""Helpers shared by the tests of `roadside eval`: running the command on datasets written to a
temporary folder, and reading its JSON output."""
import json
import math
import os
import subprocess
import sys
import tempfile

ROADSIDE = os.environ.get("ROADSIDE")


def need_roadside():
    if not ROADSIDE or not os.path.exists(ROADSIDE):
        print("ROADSIDE not set or missing: skipped")
        sys.exit(77)


def coco_gt(images, annotations, categories=None):
    """A COCO ground truth. images: list of ids or dicts; annotations: dicts."""
    imgs = [im if isinstance(im, dict) else {"id": im} for im in images]
    gt = {"images": imgs, "annotations": annotations}
    if categories is not None:
        gt["categories"] = categories
    return gt


def ann(image_id, u, v, category_id=1, crowd=0, bbox=None):
    """A ground-truth annotation whose point is (u, v): bottom_center, or the centre of bbox."""
    a = {"image_id": image_id, "category_id": category_id, "iscrowd": crowd}
    if bbox is not None:
        a["bbox"] = bbox
    else:
        a["bottom_center"] = [u, v]
    return a


def det(image_id, u, v, score, category_id=1):
    """A detection whose box centre is (u, v) in roadside's pixels (a 2x2 box around it, written in
    COCO's corner convention: + 0.5, docs/evaluation.md rule 1)."""
    return {"image_id": image_id, "category_id": category_id, "bbox": [u - 0.5, v - 0.5, 2, 2], "score": score}


def run(args, gt=None, dets=None, check=True):
    """Runs `roadside eval GT DETS --json OUT ARGS` (GT/DETS dumped from Python objects, or passed
    as raw text when str). Returns (exit code, parsed JSON or None, stdout, stderr)."""
    with tempfile.TemporaryDirectory() as tmp:
        paths = []
        for name, obj in (("gt.json", gt), ("dets.json", dets)):
            p = os.path.join(tmp, name)
            with open(p, "w") as f:
                f.write(obj if isinstance(obj, str) else json.dumps(obj, indent=1))
            paths.append(p)
        out = os.path.join(tmp, "out.json")
        r = subprocess.run([ROADSIDE, "eval", paths[0], paths[1], "--json", out, *args],
                           capture_output=True, text=True)
        result = None
        if os.path.exists(out):
            with open(out) as f:
                result = json.load(f)
        if check and r.returncode != 0:
            raise AssertionError(f"roadside eval {' '.join(args)} exited {r.returncode}: {r.stderr}")
        return r.returncode, result, r.stdout, r.stderr


def close(a, b, tol=1e-12):
    """Equal within tol, None == None; NaN never passes."""
    if a is None or b is None:
        return a is None and b is None
    if isinstance(a, float) and math.isnan(a) or isinstance(b, float) and math.isnan(b):
        return False
    return abs(a - b) <= tol

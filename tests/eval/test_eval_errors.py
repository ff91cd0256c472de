"""Malformed input and bad options for `roadside eval`: each defect must give a non-zero exit (1 for
bad input, 2 for a usage error), a message naming the file, line, entry and field, and no JSON
output (nothing half-written)."""
import copy
import json
import os
import subprocess
import sys
import tempfile

from eval_common import ROADSIDE, coco_gt, det, need_roadside, run

GT = coco_gt([1, 2], [{"image_id": 1, "category_id": 1, "bbox": [0, 0, 10, 10]},
                      {"image_id": 2, "category_id": 1, "bottom_center": [5, 5], "iscrowd": 0}],
             [{"id": 1, "name": "car"}, {"id": 2, "name": "truck"}])
DETS = [det(1, 5, 5, .9), det(2, 5, 5, .8, 2)] + [det(1, 50 + i, 50, .1) for i in range(16)]


def with_det(i, **change):
    d = copy.deepcopy(DETS)
    for k, v in change.items():
        if v is None:
            del d[i][k]
        else:
            d[i][k] = v
    return d


def with_gt(f):
    g = copy.deepcopy(GT)
    f(g)
    return g


# name, gt, dets (objects or raw text), args, expected exit code, expected substrings of stderr
# (detections are dumped with indent=1: entry i starts on line 2 + 11 i, ground truth likewise)
BAD = [
    ("unknown image", GT, with_det(17, image_id=99), [], 1,
     ["dets.json:189: entry 17: image_id 99 not in the ground truth"]),
    ("missing score", GT, with_det(3, score=None), [], 1, ["dets.json:35: entry 3: score: missing"]),
    ("score not a number", GT, with_det(3, score="high"), [], 1, ["entry 3: score: not a finite number"]),
    ("negative width", GT, with_det(4, bbox=[1, 2, -3, 4]), [], 1, ["entry 4: bbox: negative width -3"]),
    ("negative height", GT, with_det(4, bbox=[1, 2, 3, -4]), [], 1, ["entry 4: bbox: negative height -4"]),
    ("short bbox", GT, with_det(5, bbox=[1, 2, 3]), [], 1, ["entry 5: bbox: not a list of 4 numbers"]),
    ("bbox with a string", GT, with_det(5, bbox=[1, "2", 3, 4]), [], 1, ["entry 5: bbox: element 1 is not a number"]),
    ("no bbox", GT, with_det(6, bbox=None), [], 1, ["entry 6: bbox: missing"]),
    ("unknown category", GT, with_det(2, category_id=7), [], 1,
     ["entry 2: category_id 7 not in the ground truth"]),
    ("missing image_id", GT, with_det(2, image_id=None), [], 1, ["entry 2: image_id: missing"]),
    ("fractional image_id", GT, with_det(2, image_id=1.5), [], 1, ["entry 2: image_id: not an integer"]),
    ("huge number", GT, json.dumps(DETS).replace('"score": 0.9', '"score": 1e999'), [], 1,
     ["entry 0: score: not a finite number"]),
    ("entry not an object", GT, json.dumps(DETS[:2] + [[1, 2]]), [], 1, ["entry 2: not an object"]),
    ("dets not a list", GT, json.dumps({"a": 1}), [], 1, ["dets.json:1: JSON syntax: expected a list"]),
    ("dets syntax error", GT, '[\n{"image_id": 1,\n "category_id": 1 "bbox": [0,0,1,1], "score": 1}]', [], 1,
     ["dets.json:3: JSON syntax error"]),
    ("dets unterminated", GT, '[\n{"image_id": 1, "category_id": 1, "bbox": [0,0,1,1], "score": 1},\n', [], 1,
     ["dets.json:", "JSON syntax"]),
    ("dets trailing text", GT, json.dumps(DETS) + " x", [], 1, ["unexpected text after the end"]),
    ("gt annotation for unknown image", with_gt(lambda g: g["annotations"][1].update(image_id=5)), DETS, [], 1,
     ["gt.json:", "annotations[1]: image_id 5 not in \"images\""]),
    ("gt annotation of unknown category", with_gt(lambda g: g["annotations"][0].update(category_id=9)), DETS, [], 1,
     ["annotations[0]: category_id 9 not in \"categories\""]),
    ("gt negative width", with_gt(lambda g: g["annotations"][0].update(bbox=[0, 0, -1, 1])), DETS, [], 1,
     ["annotations[0]: bbox: negative width -1"]),
    ("gt bad iscrowd", with_gt(lambda g: g["annotations"][0].update(iscrowd=2)), DETS, [], 1,
     ["annotations[0]: iscrowd: not 0, 1, true or false"]),
    ("gt bad bottom_center", with_gt(lambda g: g["annotations"][1].update(bottom_center=[1])), DETS, [], 1,
     ["annotations[1]: bottom_center: not a list of 2 numbers"]),
    ("gt duplicate image", with_gt(lambda g: g["images"].append({"id": 1})), DETS, [], 1,
     ["images[2]: id: image 1 already listed as images[0]"]),
    ("gt image without id", with_gt(lambda g: g["images"].append({"file": "x.jpg"})), DETS, [], 1,
     ["images[2]: id: missing"]),
    ("gt duplicate category", with_gt(lambda g: g["categories"].append({"id": 1})), DETS, [], 1,
     ["categories[2]: id: category 1 listed twice"]),
    ("gt without annotations", with_gt(lambda g: g.pop("annotations")), DETS, [], 1, ['no "annotations" list']),
    ("gt not an object", "[]", DETS, [], 1, ["gt.json:1: JSON syntax: expected an object"]),
    # a repeated key (issue 42): cJSON keeps both and would take the first, silently
    ("dets repeated key", GT, json.dumps(DETS).replace('"score": 0.9', '"score": 0.9, "score": 0.1', 1), [], 1,
     ['entry 0: "score" appears twice in the entry']),
    ("gt repeated key",
     json.dumps(GT).replace('"bbox": [0, 0, 10, 10]', '"bbox": [0, 0, 10, 10], "bbox": [5, 5, 1, 1]', 1),
     DETS, [], 1, ['annotations[0]: "bbox" appears twice in the entry']),
    ("gt repeated list", json.dumps(GT)[:-1] + ', "annotations": []}', DETS, [], 1,
     ['"annotations" appears twice in the file']),
    ("gt by value not scalar", with_gt(lambda g: g["images"][0].update(condition=[1])), DETS, ["--by", "condition"], 1,
     ["images[0]: condition: not a string, number or boolean"]),
    # usage errors: exit 2
    ("max-dets 0", GT, DETS, ["--max-dets", "0"], 2, ["--max-dets: '0'"]),
    ("negative threshold", GT, DETS, ["--thresholds", "5,-1"], 2, ["--thresholds: '5,-1'"]),
    ("repeated threshold", GT, DETS, ["--thresholds", "5,5"], 2, ["thresholds: 5 given twice"]),
    ("threshold not a number", GT, DETS, ["--thresholds", "5,x"], 2, ["--thresholds"]),
    ("center shift not a number", GT, DETS, ["--center-shift", "nan"], 2, ["--center-shift: 'nan'"]),
    ("unknown option", GT, DETS, ["--frobnicate"], 2, ["unknown option '--frobnicate'"]),
    ("option without value", GT, DETS, ["--by"], 2, ["--by needs a value"]),
    ("calib without site", GT, DETS, ["--calib", "sites/x"], 2, ["--site and --calib go together"]),
    ("site without calib", GT, DETS, ["--site", "sites/x"], 2, ["--site and --calib go together"]),
    ("camera field alone", GT, DETS, ["--camera-field", "cam"], 2, ["--camera-field needs --site and --calib"]),
]


def main():
    need_roadside()
    failures = 0
    for name, gt, dets, args, code, needles in BAD:
        rc, result, _, err = run(args, gt, dets, check=False)
        problems = []
        if rc != code:
            problems.append(f"exit {rc}, expected {code}")
        if result is not None:
            problems.append("wrote the JSON output")
        for n in needles:
            if n not in err:
                problems.append(f"message lacks {n!r}")
        if "Sanitizer" in err or "runtime error" in err:
            problems.append("sanitizer report")
        if problems:
            failures += 1
            print(f"FAIL {name}: {'; '.join(problems)}\n    stderr: {err.strip()}")

    # missing files and usage without files
    with tempfile.TemporaryDirectory() as tmp:
        gt = os.path.join(tmp, "gt.json")
        with open(gt, "w") as f:
            json.dump(GT, f)
        for argv, code, needle in ((["eval", gt, os.path.join(tmp, "none.json")], 1, "none.json: cannot open"),
                                   (["eval", gt], 2, "expected GT.json and DETS.json"),
                                   (["eval"], 2, "expected GT.json and DETS.json")):
            r = subprocess.run([ROADSIDE, *argv], capture_output=True, text=True)
            if r.returncode != code or needle not in r.stderr:
                failures += 1
                print(f"FAIL {argv[1:]}: exit {r.returncode}, stderr {r.stderr.strip()!r}")
        r = subprocess.run([ROADSIDE, "eval", "--help"], capture_output=True, text=True)
        if r.returncode != 0 or "usage: roadside eval" not in r.stdout:
            failures += 1
            print("FAIL eval --help")
    print(f"{len(BAD) + 4} checks, {failures} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

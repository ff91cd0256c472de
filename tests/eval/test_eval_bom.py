#!/usr/bin/env python3
"""Issue 14, finding 4: `eval` rejected a UTF-8 byte order mark that site files accept. Both files
with a BOM (and CRLF line ends, as Windows editors write them) must give exactly the result of
the same files without: the oracle is the run on the plain text, plus the hand-worked AP (one
image, two vehicles, one found within the threshold: AP 0.5)."""
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import eval_common as ec  # noqa: E402

ec.need_roadside()
gt = ec.coco_gt([1], [ec.ann(1, 100, 100), ec.ann(1, 500, 500)], [{"id": 1, "name": "car"}])
dets = [ec.det(1, 101, 100, 0.9)]
plain = [json.dumps(gt, indent=1), json.dumps(dets, indent=1)]
bom = ["\ufeff" + t.replace("\n", "\r\n") for t in plain]
failures = 0
rc0, r0, _, e0 = ec.run(["--thresholds", "5"], gt=plain[0], dets=plain[1], check=False)
rc1, r1, _, e1 = ec.run(["--thresholds", "5"], gt=bom[0], dets=bom[1], check=False)
if rc0 != 0 or rc1 != 0:
    print("FAIL: exit %d (plain) and %d (BOM): %s %s" % (rc0, rc1, e0, e1))
    failures += 1
elif r0 != r1:
    print("FAIL: the BOM changed the result:\n%s\n%s" % (r0, r1))
    failures += 1
else:
    ap = r1.get("mAP") if isinstance(r1, dict) else None
    if ap is None or abs(ap - 0.5) > 1e-12:
        print("FAIL: mAP %r, expected 0.5 (one of two vehicles found)" % ap)
        failures += 1
print("eval_bom: %s" % ("ok" if not failures else "%d failure(s)" % failures))
sys.exit(1 if failures else 0)

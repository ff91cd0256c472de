"""`roadside eval` on tiny datasets whose metrics were worked out by hand (docs/evaluation.md gives
the rules). Each case states its reasoning; every expected number is exact (tolerance 1e-12).
Detections are 2x2 boxes centred on the point given (so --center-shift 0 gives that point)."""
import sys

from eval_common import ann, close, coco_gt, det, need_roadside, run

CASES = []


def case(name, gt, dets, args, expect):
    CASES.append((name, gt, dets, args, expect))


# One image, ground truths g1 (100,100), g2 (200,100).
# A .9 at d=1 from g1; B .8 far from both; C .7 at d=3 from g2.
# theta 2: A TP (P=1, R=.5); B FP; C FP (3 >= 2). AP = .5 * 1 = .5; recall .5.
# theta 5: A TP; B FP; C TP (P=2/3, R=1). AP = .5 * max(1, 2/3) + .5 * 2/3 = 5/6; recall 1.
case("basic", coco_gt([1], [ann(1, 100, 100), ann(1, 200, 100)]),
     [det(1, 101, 100, .9), det(1, 300, 300, .8), det(1, 200, 103, .7)], ["--thresholds", "2,5"],
     {("AP", "2"): .5, ("AP", "5"): 5 / 6, ("recall", "2"): .5, ("recall", "5"): 1.0,
      ("mAP",): (.5 + 5 / 6) / 2, ("AR",): .75, ("num_gt",): 2, ("num_det",): 3})

# Equal scores keep input order. g (10,10); D1 at d=20, D2 at d=1, both score .5.
# Order D1, D2: D1 FP, D2 TP with P=1/2 -> AP .5.   Order D2, D1: D2 TP with P=1 -> AP 1.
tie_gt = coco_gt([1], [ann(1, 10, 10)])
case("score ties keep input order (far first)", tie_gt, [det(1, 10, 30, .5), det(1, 10, 11, .5)],
     ["--thresholds", "5"], {("AP", "5"): .5, ("recall", "5"): 1.0})
case("score ties keep input order (near first)", tie_gt, [det(1, 10, 11, .5), det(1, 10, 30, .5)],
     ["--thresholds", "5"], {("AP", "5"): 1.0, ("recall", "5"): 1.0})

# Nearest unmatched, not nearest overall. g1 (0,0), g2 (6,0). A .9 at (1,0) takes g1.
# B .8 at (2,0): g1 (d=2) is taken; the nearest unmatched is g2 at d=4.
# theta 3: B FP although g1 is within 3 -> AP .5, recall .5.  theta 5: B TP -> AP 1, recall 1.
case("nearest unmatched, not nearest overall", coco_gt([1], [ann(1, 0, 0), ann(1, 6, 0)]),
     [det(1, 1, 0, .9), det(1, 2, 0, .8)], ["--thresholds", "3,5"],
     {("AP", "3"): .5, ("recall", "3"): .5, ("AP", "5"): 1.0, ("recall", "5"): 1.0})

# Each detection, in score order, takes its own nearest. g1 (0,0), g2 (0,4).
# A .9 at (0,2.5): g2 (d=1.5) is nearer than g1 (2.5) -> TP at theta 2. B .8 at (0,0.5): g1
# (d=.5) -> TP. AP 1. (Matching A to g1, the first annotation, would leave B a false positive.)
case("greedy in score order", coco_gt([1], [ann(1, 0, 0), ann(1, 0, 4)]),
     [det(1, 0, 2.5, .9), det(1, 0, .5, .8)], ["--thresholds", "2"], {("AP", "2"): 1.0})

# Strict <: d exactly theta is a miss. g (0,0), detection at (3,4): d = 5.
case("distance equal to the threshold misses", coco_gt([1], [ann(1, 0, 0)]), [det(1, 3, 4, .9)],
     ["--thresholds", "5,5.5"], {("AP", "5"): 0.0, ("recall", "5"): 0.0, ("AP", "5.5"): 1.0})

# Ignore regions. g (0,0); crowd region c with bbox centre (10,0), not counted as ground truth.
# theta 5: A .9 (9,0) nearest c d=1 -> dropped; B .8 (11,0) -> dropped again (c is never used up);
#   C .7 (1,0) -> g TP (P=1); D .6 (5,0): g taken, c at d=5 not < 5 -> FP. AP 1, recall 1.
# theta 20: A, B dropped; C TP; D: c at d=5 < 20 -> dropped. 3 dropped, AP 1.
crowd_gt = coco_gt([1], [ann(1, 0, 0), ann(1, 0, 0, crowd=1, bbox=[5.5, -4.5, 10, 10])])  # (corner convention)
case("ignore regions drop detections, many times", crowd_gt,
     [det(1, 9, 0, .9), det(1, 11, 0, .8), det(1, 1, 0, .7), det(1, 5, 0, .6)], ["--thresholds", "5,20"],
     {("num_gt",): 1, ("num_det",): 4, ("AP", "5"): 1.0, ("recall", "5"): 1.0, ("num_dropped", "5"): 2,
      ("AP", "20"): 1.0, ("num_dropped", "20"): 3})
# F .95 at (5,0) is equidistant (5) from g and c: the ground truth is the nearest candidate.
# theta 5: F FP (5 not < 5), then C .7 (1,0) finds g unmatched: TP with P=1/2 -> AP .5.
# theta 20: F TP; C: g is taken, c at d=9 -> dropped, no precision-recall point -> AP 1.
case("equidistant ground truth beats ignore region", crowd_gt, [det(1, 5, 0, .95), det(1, 1, 0, .7)],
     ["--thresholds", "5,20"],
     {("AP", "5"): .5, ("num_dropped", "5"): 0, ("AP", "20"): 1.0, ("num_dropped", "20"): 1})
# An ignore region nearer than the unmatched ground truth, both within theta: dropped, and g stays
# unmatched: recall 0, AP 0 (no ground truth found). g (0,0), c (10,0), A at (6,0): c d=4 < g d=6.
case("nearer ignore region wins", crowd_gt, [det(1, 6, 0, .9)], ["--thresholds", "20"],
     {("AP", "20"): 0.0, ("recall", "20"): 0.0, ("num_dropped", "20"): 1})

# max-dets per image, highest scores. Image 1: g (0,0); FP .9, FP .8, TP .7. Image 2: g (0,0), TP .1.
# --max-dets 2: image 1 keeps the two FPs; image 2 keeps its TP (its own budget).
#   Order: FP, FP, TP(img2, P=1/3). AP = 1/2 * 1/3 = 1/6; recall 1/2; num_det 3.
# --max-dets 3: order FP .9, FP .8, TP .7 (P=1/3), TP .1 (P=2/4). AP = 1/2 (1/2) + 1/2 (1/2) = 1/2.
md_gt = coco_gt([1, 2], [ann(1, 0, 0), ann(2, 0, 0)])
md_dets = [det(1, 50, 50, .9), det(1, 60, 60, .8), det(1, 0, 0, .7), det(2, 0, 0, .1)]
case("max-dets 2", md_gt, md_dets, ["--thresholds", "5", "--max-dets", "2"],
     {("AP", "5"): 1 / 6, ("recall", "5"): .5, ("num_det",): 3})
case("max-dets 3", md_gt, md_dets, ["--thresholds", "5", "--max-dets", "3"],
     {("AP", "5"): .5, ("recall", "5"): 1.0, ("num_det",): 4})
# max-dets ties keep input order: two .5 detections, the far one first; --max-dets 1 keeps it.
case("max-dets ties keep input order", tie_gt, [det(1, 10, 30, .5), det(1, 10, 11, .5)],
     ["--thresholds", "5", "--max-dets", "1"], {("AP", "5"): 0.0, ("num_det",): 1})

# Empty ground truth (none, or only ignore regions): null, not zero.
for name, anns in (("no annotations", []), ("only ignore regions", [ann(1, 0, 0, crowd=1)])):
    case(f"empty ground truth ({name})", coco_gt([1], anns, [{"id": 1}]), [det(1, 0, 0, .9)], ["--thresholds", "5"],
         {("AP", "5"): None, ("recall", "5"): None, ("mAP",): None, ("AR",): None, ("num_gt",): 0,
          ("num_det",): 1})
# No detections at all: zero, not null. An image without detections: its ground truths are missed.
case("no detections", coco_gt([1], [ann(1, 0, 0)]), [], ["--thresholds", "5"],
     {("AP", "5"): 0.0, ("recall", "5"): 0.0, ("mAP",): 0.0, ("AR",): 0.0, ("num_det",): 0})
case("image without detections", coco_gt([1, 2], [ann(1, 0, 0), ann(2, 0, 0)]), [det(1, 0, 0, .9)],
     ["--thresholds", "5"], {("AP", "5"): .5, ("recall", "5"): .5})

# Default thresholds 2,5,10,15,20,50. g (0,0), one detection at d=7: FP at 2 and 5, TP from 10.
case("default thresholds", coco_gt([1], [ann(1, 0, 0)]), [det(1, 7, 0, .9)], [],
     {("AP", "2"): 0.0, ("AP", "5"): 0.0, ("AP", "10"): 1.0, ("AP", "50"): 1.0, ("mAP",): 4 / 6,
      ("AR",): 4 / 6})

# Per class. car g_c (0,0), truck g_t (3,0); truck crowd region at (100,0).
# car A .9 at (2.5,0); truck B .8 at (0.2,0); car C .7 at (101,0).
# Class-agnostic (all rows): A nearest g_t (.5) TP; B nearest unmatched g_c (.2) TP; C nearest
#   candidate the crowd region (1) -> dropped. AP 1 at 2 and 5, dropped 1.
# car: candidates g_c only (the crowd region is a truck). A: d 2.5 -> FP at 2, TP at 5;
#   C: g_c (101) -> FP. theta 2: AP 0; theta 5: A TP (P=1), C FP -> AP 1. Nothing dropped.
# truck: B: g_t at 2.8 -> FP at 2, TP at 5.
cats = [{"id": 1, "name": "car"}, {"id": 2, "name": "truck"}]
pc_gt = coco_gt([1], [ann(1, 0, 0, 1), ann(1, 3, 0, 2), ann(1, 100, 0, 2, crowd=1)], cats)
case("per class", pc_gt, [det(1, 2.5, 0, .9, 1), det(1, .2, 0, .8, 2), det(1, 101, 0, .7, 1)],
     ["--thresholds", "2,5", "--per-class"],
     {("AP", "2"): 1.0, ("AP", "5"): 1.0, ("num_dropped", "2"): 1,
      ("classes", "1", "name"): "car", ("classes", "1", "AP", "2"): 0.0, ("classes", "1", "AP", "5"): 1.0,
      ("classes", "1", "num_det"): 2, ("classes", "1", "num_dropped", "5"): 0,
      ("classes", "2", "AP", "2"): 0.0, ("classes", "2", "AP", "5"): 1.0, ("classes", "2", "num_gt"): 1})

# --by KEY: images 1 rain, 2 normal, 3 without the field -> "(missing)". One ground truth each;
# image 1 found, image 2 missed (FP), image 3 has no detection.
by_gt = coco_gt([{"id": 1, "condition": "rain"}, {"id": 2, "condition": "normal"}, {"id": 3}],
                [ann(1, 0, 0), ann(2, 0, 0), ann(3, 0, 0)])
case("by condition", by_gt, [det(1, 0, 0, .9), det(2, 40, 0, .8)], ["--thresholds", "5", "--by", "condition"],
     {("AP", "5"): 1 / 3, ("groups", "rain", "AP", "5"): 1.0, ("groups", "normal", "AP", "5"): 0.0,
      ("groups", "normal", "num_det"): 1, ("groups", "(missing)", "recall", "5"): 0.0,
      ("groups", "(missing)", "num_det"): 0})

# --center-shift: a 10x20 box at (0,0) (COCO: (0.5, 0.5)) -> (5, 10 + K 20). Ground truth bottom centre (5, 20).
# K = .5 puts the detection on it; K = 0 leaves it 10 px above. A detection's own bottom_center wins.
cs_gt = coco_gt([1], [ann(1, 5, 20)])
cs_det = [{"image_id": 1, "category_id": 1, "bbox": [0.5, 0.5, 10, 20], "score": .9}]  # (corner convention)
case("center shift 0.5", cs_gt, cs_det, ["--thresholds", "1", "--center-shift", "0.5"], {("AP", "1"): 1.0})
case("center shift 0", cs_gt, cs_det, ["--thresholds", "1"], {("AP", "1"): 0.0})
case("center shift 0.35", cs_gt, cs_det, ["--thresholds", "3.01,2.99", "--center-shift", "0.35"],
     {("AP", "3.01"): 1.0, ("AP", "2.99"): 0.0})
case("detection bottom_center", cs_gt, [dict(cs_det[0], bottom_center=[5, 20.5])],
     ["--thresholds", "1", "--center-shift", "3"], {("AP", "1"): 1.0})


def lookup(result, path):
    x = result
    for k in path:
        x = x[k]
    return x


def main():
    need_roadside()
    failures = 0
    for name, gt, dets, args, expect in CASES:
        _, result, _, _ = run(args, gt, dets)
        for path, want in expect.items():
            got = lookup(result, path)
            ok = got == want if isinstance(want, str) else close(got, want)
            if not ok:
                failures += 1
                print(f"FAIL {name}: {'.'.join(path)} = {got}, expected {want}")
    # the printed table: a row per scope, '-' where there is no ground truth
    _, _, out, _ = run(["--thresholds", "5", "--by", "condition", "--per-class"], by_gt, [det(1, 0, 0, .9)])
    for needle in ("AP@5", "condition=rain", "condition=(missing)", "class 1 (1)"):
        if needle not in out:
            failures += 1
            print(f"FAIL table lacks {needle!r}:\n{out}")
    _, _, out, _ = run(["--thresholds", "5"], coco_gt([1], [], [{"id": 1}]), [det(1, 0, 0, .9)])
    if " -" not in out.splitlines()[1]:
        failures += 1
        print(f"FAIL no ground truth is not printed as '-':\n{out}")
    print(f"{len(CASES)} cases, {failures} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

"""`roadside eval` against a brute force written here from the definition in docs/evaluation.md,
on random datasets full of ties: equal scores, equal distances, distances exactly at a threshold
(integer grid), ignore regions, several categories and images, max-dets, --per-class, --by.

The brute force shares no structure with the C code: it recomputes every candidate list from
scratch with min() over tuples, and computes AP from the explicit precision-recall points as
sum over recall steps of (step) x max{precision at any point with recall >= this recall}.
Every output must agree within 1e-12. Seed: fixed, printed; a failure prints the dataset's seed."""
import math
import random
import sys
from collections import defaultdict

from eval_common import close, coco_gt, need_roadside, run

BASE_SEED = 20261122
N_DATASETS = int(sys.argv[1]) if len(sys.argv) > 1 else 300  # meson: 100 in a sanitizer build
TOL = 1e-12


def point_gt(a):
    if "bottom_center" in a:
        return a["bottom_center"]
    x, y, w, h = a["bbox"]  # COCO's corner convention, the point pixel-centre (docs/evaluation.md rule 1)
    return [x + w / 2 - 0.5, y + h / 2 - 0.5]


def point_det(d, K):
    if "bottom_center" in d:
        return d["bottom_center"]
    x, y, w, h = d["bbox"]
    return [x + w / 2 - 0.5, y + h / 2 - 0.5 + K * h]


def brute_force(gt, dets, thresholds, max_dets, K, per_class, by):
    anns = gt["annotations"]
    image_value = {}
    for im in gt["images"]:
        v = im.get(by) if by else None
        image_value[im["id"]] = "(missing)" if v is None else v
    # max-dets: per image, descending score, then input order
    per_image = defaultdict(list)
    for idx, d in enumerate(dets):
        per_image[d["image_id"]].append((-d["score"], idx))
    kept = []
    for lst in per_image.values():
        kept += sorted(lst)[:max_dets]
    order = [idx for _, idx in sorted(kept)]

    def scope(image_ok, cat):
        in_scope = [i for i in order if image_ok(dets[i]["image_id"]) and cat in (None, dets[i]["category_id"])]
        gts = [j for j, a in enumerate(anns) if image_ok(a["image_id"]) and cat in (None, a["category_id"])]
        num_gt = sum(1 for j in gts if not anns[j]["iscrowd"])
        out = {"num_gt": num_gt, "num_det": len(in_scope), "AP": {}, "recall": {}, "num_dropped": {}}
        for theta in thresholds:
            key = "%.15g" % theta
            matched = set()
            points = []  # (recall, precision) after each detection that is not dropped
            tp = fp = dropped = 0
            for i in in_scope:
                d = dets[i]
                u, v = point_det(d, K)
                cands = []
                for j in gts:
                    a = anns[j]
                    if a["image_id"] != d["image_id"] or (j in matched and not a["iscrowd"]):
                        continue
                    p = point_gt(a)
                    cands.append(((p[0] - u) ** 2 + (p[1] - v) ** 2, a["iscrowd"], j))
                if cands:
                    d2, crowd, j = min(cands)
                    if math.sqrt(d2) < theta:
                        if crowd:
                            dropped += 1
                            continue
                        matched.add(j)
                        tp += 1
                        points.append((tp / num_gt, tp / (tp + fp)))
                        continue
                fp += 1
                if num_gt:
                    points.append((tp / num_gt, tp / (tp + fp)))
            out["num_dropped"][key] = dropped
            if num_gt == 0:
                out["AP"][key] = out["recall"][key] = None
                continue
            ap, prev = 0.0, 0.0
            for r, _ in points:
                if r > prev:
                    ap += (r - prev) * max(pp for rr, pp in points if rr >= r)
                    prev = r
            out["AP"][key] = ap
            out["recall"][key] = tp / num_gt
        if num_gt:
            out["mAP"] = sum(out["AP"].values()) / len(thresholds)
            out["AR"] = sum(out["recall"].values()) / len(thresholds)
        else:
            out["mAP"] = out["AR"] = None
        return out

    res = scope(lambda m: True, None)
    if by:
        values = []
        for im in gt["images"]:
            if image_value[im["id"]] not in values:
                values.append(image_value[im["id"]])
        res["groups"] = {str(g): scope(lambda m, g=g: image_value[m] == g, None) for g in values}
    if per_class:
        res["classes"] = {str(c["id"]): scope(lambda m: True, c["id"]) for c in gt["categories"]}
    return res


def random_dataset(rng):
    grid = rng.random() < 0.6  # integer coordinates: many equal distances and exact thresholds
    coord = (lambda: rng.randint(0, 12)) if grid else (lambda: rng.uniform(0, 12))
    n_images = rng.randint(1, 4)
    ids = rng.sample(range(1, 60), n_images)
    images = []
    for i in ids:
        im = {"id": i}
        c = rng.choice(["normal", "rain", "night", None])
        if c is not None:
            im["condition"] = c
        images.append(im)
    cats = [{"id": 1, "name": "car"}, {"id": 2, "name": "truck"}, {"id": 7, "name": "bus"}]
    cat_ids = [c["id"] for c in cats[:rng.randint(1, 3)]]
    anns = []
    for i in ids:
        for _ in range(rng.randint(0, 6)):
            a = {"image_id": i, "category_id": rng.choice(cat_ids), "iscrowd": int(rng.random() < 0.15)}
            if rng.random() < 0.7:
                a["bottom_center"] = [coord(), coord()]
            else:
                w, h = rng.randint(0, 6) * 2, rng.randint(0, 6) * 2
                a["bbox"] = [coord() - w / 2, coord() - h / 2, w, h]
            anns.append(a)
    rng.shuffle(anns)
    score_set = [0.1, 0.2, 0.3] if rng.random() < 0.5 else None
    dets = []
    for i in ids:
        for _ in range(rng.randint(0, 12)):
            d = {"image_id": i, "category_id": rng.choice(cat_ids),
                 "score": rng.choice(score_set) if score_set else round(rng.random(), 3)}
            if rng.random() < 0.2:
                d["bottom_center"] = [coord(), coord()]
                d["bbox"] = [0, 0, 1, 1]
            else:
                w, h = rng.randint(0, 6) * 2, rng.randint(0, 6) * 2
                d["bbox"] = [coord() - w / 2, coord() - h / 2, w, h]
            dets.append(d)
    rng.shuffle(dets)
    thresholds = rng.sample([0.5, 1, 2, 3, 5, 8, 13], rng.randint(1, 4))
    max_dets = rng.choice([None, 1, 2, 3, 5, 8])
    K = rng.choice([0, 0.5, 0.35, 0.25])
    per_class = rng.random() < 0.5
    by = "condition" if rng.random() < 0.5 else None
    return coco_gt(images, anns, cats), dets, thresholds, max_dets, K, per_class, by


def compare(got, want, where, errors):
    if isinstance(want, dict):
        if not isinstance(got, dict) or set(got) - {"name"} != set(want):
            errors.append(f"{where}: keys {sorted(got) if isinstance(got, dict) else got} != {sorted(want)}")
            return
        for k in want:
            compare(got[k], want[k], f"{where}.{k}", errors)
    elif not close(got, want, TOL):
        errors.append(f"{where}: roadside {got!r} != brute force {want!r}")


def main():
    need_roadside()
    print(f"seed {BASE_SEED}, {N_DATASETS} datasets")
    failed = 0
    for k in range(N_DATASETS):
        seed = BASE_SEED + k
        rng = random.Random(seed)
        gt, dets, thresholds, max_dets, K, per_class, by = random_dataset(rng)
        args = ["--thresholds", ",".join("%.15g" % t for t in thresholds), "--center-shift", repr(K)]
        if max_dets:
            args += ["--max-dets", str(max_dets)]
        if per_class:
            args.append("--per-class")
        if by:
            args += ["--by", by]
        _, got, _, _ = run(args, gt, dets)
        want = brute_force(gt, dets, thresholds, max_dets or 100, K, per_class, by)
        errors = []
        for key in want:
            compare(got.get(key), want[key], key, errors)
        if errors:
            failed += 1
            print(f"FAIL dataset seed {seed} (roadside eval ... {' '.join(args)}):")
            for e in errors[:10]:
                print("   ", e)
    print(f"{N_DATASETS - failed} of {N_DATASETS} datasets agree within {TOL}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""`roadside bench detect` runs and reports what it says it reports (no time is asserted): one row
per input size and thread setting, finite non-negative medians, the same rows in the CSV; a model that cannot take a size fails (exit
1), a size that is not a multiple of 32 is a usage error (exit 2)."""
import csv
import math
import os
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "common"))
sys.path.insert(0, os.path.dirname(__file__))
from rs_check import check, finish, run  # noqa: E402
import make_models as mm  # noqa: E402


def main():
    with tempfile.TemporaryDirectory(prefix="roadside-bench-detect-") as tmp:
        for family in ("yolox", "ultralytics"):
            model = os.path.join(tmp, f"{family}.onnx")
            rows = mm.demo_rows(family, 128, 96, 3)
            base = (mm.yolox_base if family == "yolox" else mm.ultralytics_base)(128, 96, 3, rows)
            mm.make_model(model, 128, 96, base)
            out = os.path.join(tmp, f"{family}.csv")
            p = run("bench", "detect", "--model", model, "--sizes", "128x96", "--frames", "3", "--frame", "320x200",
                    "--csv", out, timeout=120)
            check(p.returncode == 0, f"{family}: exit {p.returncode}: {p.stderr}")
            if p.returncode:
                continue
            print(p.stdout, end="")
            table = [line.split() for line in p.stdout.splitlines() if line.startswith("128x96")]
            check([r[1] for r in table] == ["1", "default"], f"{family}: one row per thread setting: {table}")
            for r in table:
                v = [float(x) for x in r[2:]]
                check(all(math.isfinite(x) and x >= 0 for x in v), f"{family}: finite non-negative medians {v}")
            got = list(csv.DictReader(open(out)))
            check(len(got) == 2 and all(g["net_w"] == "128" and g["net_h"] == "96" for g in got),
                  f"{family}: the CSV's rows {got}")
            p = run("bench", "detect", "--model", model, "--sizes", "160", "--frames", "1", timeout=120)
            check(p.returncode == 1 and "roadside" in p.stderr, f"{family}: a fixed 128x96 model at 160: exit "
                  f"{p.returncode}: {p.stderr}")
        p = run("bench", "detect", "--model", model, "--sizes", "100")
        check(p.returncode == 2, f"--sizes 100: exit {p.returncode}")
    finish("test_bench_detect")


if __name__ == "__main__":
    main()

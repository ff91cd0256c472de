"""`roadside bench eval` at a tiny size runs, prints its table and writes a well-formed CSV (one
header, one row, the same number of fields, finite numbers, the counts asked for); and `roadside
bench` rejects an unknown benchmark. The timings themselves are not tested: docs/benchmarks.md."""
import csv
import json
import math
import os
import subprocess
import sys
import tempfile

from eval_common import ROADSIDE, need_roadside

SEED = 7


def main():
    need_roadside()
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "bench.csv")
        keep = os.path.join(tmp, "data")
        r = subprocess.run([ROADSIDE, "bench", "eval", "--images", "20", "--dets", "503", "--seed", str(SEED),
                            "--csv", out, "--dir", keep], capture_output=True, text=True)
        if r.returncode != 0:
            print(f"bench eval exited {r.returncode}: {r.stderr}")
            return 1
        if "parse_s" not in r.stdout or "eval_s" not in r.stdout:
            failures.append(f"table lacks its columns: {r.stdout!r}")
        with open(out) as f:
            rows = list(csv.reader(f))
        if len(rows) != 2 or len(rows[0]) != len(rows[1]):
            failures.append(f"CSV is not one header and one row of equal length: {rows}")
        else:
            row = dict(zip(rows[0], rows[1]))
            for k, v in row.items():
                x = float(v)
                if not math.isfinite(x) or x < 0:
                    failures.append(f"{k} = {v} is not a finite non-negative number")
            if row.get("images") != "20" or row.get("dets") != "503" or row.get("seed") != str(SEED):
                failures.append(f"counts differ from the request: {row}")
            if not 0 < float(row.get("mAP", -1)) <= 1:
                failures.append(f"mAP {row.get('mAP')} not in (0, 1]")
            # the kept files evaluate to the same mAP through `roadside eval`
            e = subprocess.run([ROADSIDE, "eval", os.path.join(keep, "gt.json"), os.path.join(keep, "dets.json"),
                                "--center-shift", "0.5", "--json", os.path.join(tmp, "m.json")],
                               capture_output=True, text=True)
            if e.returncode != 0:
                failures.append(f"eval of the kept files failed: {e.stderr}")
            else:
                with open(os.path.join(tmp, "m.json")) as f:
                    m = json.load(f)
                if abs(m["mAP"] - float(row["mAP"])) > 1e-8 or m["num_det"] != 503:
                    failures.append(f"eval of the kept files: mAP {m['mAP']}, num_det {m['num_det']}")
        if [n for n in os.listdir(tmp) if ".tmp." in n]:
            failures.append("a temporary file was left behind")
    for argv, code in ((["bench"], 2), (["bench", "nosuch"], 2), (["bench", "eval", "--images", "0"], 2),
                       (["bench", "--help"], 0), (["bench", "eval", "--help"], 0)):
        r = subprocess.run([ROADSIDE, *argv], capture_output=True, text=True)
        if r.returncode != code:
            failures.append(f"{' '.join(argv)}: exit {r.returncode}, expected {code}")
    # `bench calib` is forwarded to its own command (cli/cmd_bench_calib.c), not refused here
    r = subprocess.run([ROADSIDE, "bench", "calib", "--help"], capture_output=True, text=True)
    if "unknown benchmark" in r.stderr:
        failures.append("bench calib is not forwarded")
    for f in failures:
        print("FAIL", f, f"(seed {SEED})")
    print(f"{len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""`roadside bench pick` runs on a small size and writes its CSV: one row per size, the median not
above the 90th percentile, every re-solve giving a pose (a program that measures; nothing timed
is asserted)."""
import csv
import os
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from rs_check import check, finish, run  # noqa: E402

with tempfile.TemporaryDirectory() as tmp:
    out = os.path.join(tmp, "pick.csv")
    r = run("bench", "pick", "--landmarks", "8,12", "--clicks", "5", "--csv", out, "--dir", tmp)
    check(r.returncode == 0, f"bench pick: {r.stdout}{r.stderr}")
    rows = list(csv.DictReader(open(out))) if os.path.exists(out) else []
    check([int(x["landmarks"]) for x in rows] == [8, 12], f"rows: {rows}")
    for x in rows:
        check(0 < float(x["median_ms"]) <= float(x["p90_ms"]), f"median <= p90: {x}")
        check(int(x["failed"]) == 0 and int(x["picks"]) >= 4, f"every re-solve gave a pose: {x}")
finish("pick_bench_runs")

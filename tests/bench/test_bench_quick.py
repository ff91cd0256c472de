#!/usr/bin/env python3
"""roadside bench calib --quick: the run completes, the CSV is well formed, the PNG is a PNG.

The figures are for people (docs/benchmarks.md); this test checks the shape of the output, that
every method appears for every configuration, that times are finite and positive, that no
error or bound is infinite, and that roadside's own solver posed the baseline problems.
"""
import csv
import math
import os
import subprocess
import sys
import tempfile

ROADSIDE = os.environ["ROADSIDE"]
SEED = 1
HEADER = ["family", "config", "method", "trials", "failures", "time_med_us", "time_p90_us",
          "rot_rms_deg", "pos_rms_m", "ground_rms_m", "crb_rot_deg", "crb_pos_m", "rot_ratio",
          "pos_ratio", "cond_median", "failure"]
METHODS = ["roadside", "roadside-init", "roadside-noprior", "cv-iterative", "cv-iterative+lm",
           "cv-epnp", "cv-epnp+lm", "cv-sqpnp", "cv-sqpnp+lm", "cv-ippe", "cv-ippe+lm",
           "cv-ransac", "cv-ransac+lm", "gv-p3p-kneip-ransac", "gv-p3p-gao-ransac", "gv-epnp",
           "gv-upnp", "gv-epnp+nonlin"]

# fontconfig (under cairo's text in the plot) keeps its state for the life of the process: the
# report's LSan suppression (that one library only) applies here too; our allocations are checked
ENV = dict(os.environ, LSAN_OPTIONS="suppressions=" + os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                                   "..", "report", "test_report.lsan.supp") + ":print_suppressions=0")
failures = []


def check(cond, msg):
    if not cond:
        failures.append(msg)
        print("FAIL:", msg)


with tempfile.TemporaryDirectory() as d:
    csv_path, png_path = os.path.join(d, "bench.csv"), os.path.join(d, "bench.png")
    p = subprocess.run([ROADSIDE, "bench", "calib", "--quick", "--seed", str(SEED), "--csv", csv_path,
                        "--plot", png_path], capture_output=True, text=True, timeout=120, env=ENV)
    check(p.returncode == 0, f"exit status {p.returncode}: {p.stderr}")
    check(p.stderr == "", f"stderr not empty: {p.stderr[:300]!r}")
    check("roadside" in p.stdout and "cv-ransac+lm" in p.stdout, "table lacks methods")
    with open(csv_path, newline="") as f:
        rows = list(csv.reader(f))
    check(rows and rows[0] == HEADER, f"header {rows[0] if rows else None}")
    data = [dict(zip(HEADER, r)) for r in rows[1:] if len(r) == len(HEADER)]
    check(all(len(r) == len(HEADER) for r in rows), "a row with the wrong number of fields")
    configs = sorted({r["config"] for r in data})
    check(len(configs) >= 3, f"configs {configs}")
    for c in configs:
        got = [r["method"] for r in data if r["config"] == c]
        check(got == METHODS, f"{c}: methods {got}")
    for r in data:
        where = f"{r['config']}/{r['method']}"
        trials, fails = int(r["trials"]), int(r["failures"])
        check(0 < trials and 0 <= fails <= trials, f"{where}: trials {trials} failures {fails}")
        t50, t90 = float(r["time_med_us"]), float(r["time_p90_us"])
        check(math.isfinite(t50) and 0 < t50 <= t90 < 1e7, f"{where}: times {t50} {t90}")
        for k in HEADER[7:15]:
            v = float(r[k])  # 'nan' parses; 'inf' must never appear
            check(not math.isinf(v) and (math.isnan(v) or v >= 0), f"{where}: {k} = {r[k]}")
        # an error figure exists exactly when some trial succeeded
        check(math.isnan(float(r["rot_rms_deg"])) == (fails == trials), f"{where}: rot vs failures")
        check((fails > 0) == (r["failure"] != ""), f"{where}: failures {fails} but cause {r['failure']!r}")
    base = [r for r in data if r["config"] == "baseline" and r["method"] == "roadside"]
    check(len(base) == 1 and int(base[0]["failures"]) == 0, "roadside failed a baseline problem")
    check(len(base) == 1 and math.isfinite(float(base[0]["crb_pos_m"])), "no Cramer-Rao bound at the baseline")
    with open(png_path, "rb") as f:
        check(f.read(8) == b"\x89PNG\r\n\x1a\n", "the plot is not a PNG")
    check(not [n for n in os.listdir(d) if ".tmp" in n], "temporary files left behind")

    # usage errors: exit 2, nothing written
    bad = subprocess.run([ROADSIDE, "bench", "calib", "--trials", "0", "--csv", os.path.join(d, "x.csv")],
                         capture_output=True, text=True)
    check(bad.returncode == 2 and not os.path.exists(os.path.join(d, "x.csv")), f"--trials 0: {bad.returncode}")
    h = subprocess.run([ROADSIDE, "bench", "calib", "--help"], capture_output=True, text=True)
    check(h.returncode == 0 and h.stdout.startswith("usage: roadside bench calib"), "--help")

if failures:
    print(f"{len(failures)} failure(s); seed {SEED}")
    sys.exit(1)
print("all passed")

#!/usr/bin/env python3
"""run_fuzz.py FUZZER CORPUS DICT ARTIFACTS -- the fixed-time run of one libFuzzer harness (suite
`fuzz`, tests/fuzz/meson.build; docs/fuzzing.md).

Copies the seed corpus CORPUS to a temporary folder (what the run adds to it is thrown away; the
source tree is never written), runs FUZZER on it with the dictionary DICT for
$ROADSIDE_FUZZ_SECONDS seconds (12 by default) with a fixed seed ($ROADSIDE_FUZZ_SEED, 1 by
default), and keeps libFuzzer's log as ARTIFACTS/last-run.log. Crash, leak, timeout and
out-of-memory inputs are written to ARTIFACTS/ by libFuzzer itself.

Fails when the fuzzer exits non-zero, when its log holds a sanitizer report (AddressSanitizer,
LeakSanitizer, UndefinedBehaviorSanitizer's "runtime error:") or a libFuzzer error, when it left a
new crash-, leak-, timeout- or oom- file, or when it did not get through every seed ("INITED":
the reproducers kept in the corpus are replayed on every run). On failure it re-runs the harness
on each new artifact, whose output then shows the sanitizer's stack or the contract it broke.
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from rs_check import check, finish  # noqa: E402

SECONDS = int(os.environ.get("ROADSIDE_FUZZ_SECONDS", "12"))  # 10 harnesses: ~120 s in all
SEED = int(os.environ.get("ROADSIDE_FUZZ_SEED", "1"))
RERUN_SECONDS = 15  # re-running an artifact for its report: a hang (timeout-) must not outlast the test
REPORTS = ["ERROR: AddressSanitizer", "ERROR: LeakSanitizer", "runtime error:", "ERROR: libFuzzer",
           "ERROR: UndefinedBehaviorSanitizer"]
ARTIFACT_KINDS = ("crash-", "leak-", "timeout-", "oom-")


def tail(text, n):
    lines = text.splitlines()
    return "\n".join(lines[-n:])


def main():
    fuzzer, corpus, dictionary, artifacts = sys.argv[1:5]
    name = os.path.basename(fuzzer)
    seeds = sorted(f for f in os.listdir(corpus) if os.path.isfile(os.path.join(corpus, f)))
    check(len(seeds) > 0, f"{name}: no seed in {corpus}")
    os.makedirs(artifacts, exist_ok=True)
    before = set(os.listdir(artifacts))
    log_path = os.path.join(artifacts, "last-run.log")
    with tempfile.TemporaryDirectory(prefix="roadside-fuzz-corpus-") as work:
        for s in seeds:
            shutil.copy(os.path.join(corpus, s), work)
        cmd = [fuzzer, work, f"-dict={dictionary}", f"-max_total_time={SECONDS}", f"-seed={SEED}",
               "-rss_limit_mb=2048", "-timeout=10", "-max_len=8192", "-close_fd_mask=3",
               "-print_final_stats=1", f"-artifact_prefix={artifacts}/",
               "-error_exitcode=101", "-timeout_exitcode=102"]
        print("$", " ".join(cmd))
        with open(log_path, "w") as log:
            rc = subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT,
                                timeout=SECONDS + 60).returncode
        grown = len(os.listdir(work))
    with open(log_path, errors="replace") as f:
        log = f.read()

    done = re.search(r"Done (\d+) runs in (\d+) second", log)
    cov = re.findall(r"cov: (\d+) ft: (\d+)", log)
    print(f"{name}: seed {SEED}, {len(seeds)} seeds -> {grown} corpus inputs, "
          f"{done.group(1) + ' runs in ' + done.group(2) + ' s' if done else 'no final count'}, "
          f"{'cov ' + cov[-1][0] + ' ft ' + cov[-1][1] if cov else 'no coverage line'}; log {log_path}")

    new = sorted(a for a in set(os.listdir(artifacts)) - before if a.startswith(ARTIFACT_KINDS))
    ok = check(rc == 0, f"{name}: libFuzzer exited with status {rc}")
    for r in REPORTS:
        ok = check(r not in log, f"{name}: the log holds '{r}'") and ok
    ok = check(not new, f"{name}: new artifacts in {artifacts}: {new}") and ok
    ok = check("INITED" in log, f"{name}: did not get through the seed corpus (no INITED line)") and ok
    ok = check(done is not None, f"{name}: no 'Done N runs' line: the run did not finish") and ok
    if not ok:
        print("---- end of the log:")
        print(tail(log, 60))
        for a in new:
            path = os.path.join(artifacts, a)
            try:  # a timeout- artifact hangs again: its stack is in the log above, so give up soon
                r = subprocess.run([fuzzer, path], capture_output=True, text=True, errors="replace",
                                   timeout=RERUN_SECONDS)
            except subprocess.TimeoutExpired:
                print(f"---- {fuzzer} {path}: still running after {RERUN_SECONDS} s (a hang)")
                continue
            print(f"---- {fuzzer} {path} (exit {r.returncode}):")
            print(tail(r.stdout + r.stderr, 80))
    finish(name)


if __name__ == "__main__":
    main()

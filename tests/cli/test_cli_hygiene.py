#!/usr/bin/env python3
"""Issue 41, CLI hygiene, as a new user meets it:

- a bad option prints ONE error line naming it (then the "Try ... --help" hint), exit 2, for every
  command that parses options with getopt (getopt's own "unrecognized option" line was a second);
- `calib --help` describes the initial solvers the code calls: the sources call OpenCV's
  SOLVEPNP_SQPNP and no EPnP (the oracle is the source text), and the help says SQPnP, not EPnP;
- `<id>.json` warnings are whole sentences (capitalised or opening with a figure, ending in a full stop; none begins with a
  fragment such as "chi-square" or "0 by data snooping") naming landmarks by id, never "index";
  the demo's cam3 outlier warning names L003;
- the .cameramodel says why mrcal's uncertainty tools cannot read it: mrcal's own Python finds no
  optimization_inputs (the oracle), and the file's comments name 'roadside audit' instead;
- `report` prints its progress on stderr, one line per camera and per file, and nothing of it on
  stdout.
"""
import json
import os
import re
import shutil
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "common"))
import rs_check  # noqa: E402
from rs_check import check, finish, need  # noqa: E402

SOURCE = os.environ["ROADSIDE_SOURCE_ROOT"]
GETOPT_COMMANDS = ["calib", "locate", "audit", "report", "export", "ortho", "pick", "localise", "detect", "track"]


def main():
    for c in GETOPT_COMMANDS:
        p = rs_check.run(c, "--no-such-option", "x")
        lines = [line for line in p.stderr.splitlines() if line.strip() and not line.startswith("Try ")]
        check(p.returncode == 2 and len(lines) == 1 and "--no-such-option" in lines[0],
              f"{c} --no-such-option: exit {p.returncode}, error lines {lines}")
    # a lone leading-dash argument is an option it does not have, not a site folder named so
    # (issue 42: `site check --bogus` read the folder "--bogus" and listed its missing files)
    for args in (["site", "check", "--bogus"], ["site", "describe", "--bogus"]):
        p = rs_check.run(*args)
        lines = [line for line in p.stderr.splitlines() if line.strip() and not line.startswith("Try ")]
        check(p.returncode == 2 and len(lines) == 1 and "unknown option '--bogus'" in lines[0],
              f"{' '.join(args)}: exit {p.returncode}, error lines {lines}")

    src = "".join(open(os.path.join(SOURCE, "calib", f)).read() for f in os.listdir(os.path.join(SOURCE, "calib"))
                  if f.endswith((".c", ".cc")))
    check("SOLVEPNP_SQPNP" in src and "SOLVEPNP_EPNP" not in src, "the calib sources: SQPnP called, EPnP not")
    p = rs_check.run("calib", "--help")
    check("SQPnP" in p.stdout and "EPnP" not in p.stdout, f"calib --help: {p.stdout[:400]}")

    tmp, site, calib = rs_check.demo_calibrated("roadside-h41-")
    for cam in ("cam1", "cam2", "cam3", "cam4"):
        warnings = json.load(open(os.path.join(calib, cam + ".json")))["warnings"]
        for w in warnings:
            check((w[:1].isupper() or w[:1].isdigit()) and w.endswith(".") and "index" not in w and w.count("(") == w.count(")"),
                  f"{cam}.json: not a whole sentence naming ids: {w!r}")
        if cam == "cam3":
            check(any(re.search(r"outliers and dropped \(landmark L003; ", w) for w in warnings),
                  f"cam3.json: the outlier by id: {warnings}")
    mrcal, = need("mrcal")
    model_path = os.path.join(calib, "cam1.cameramodel")
    m = mrcal.cameramodel(model_path)
    check(m.optimization_inputs() is None, "cam1.cameramodel has optimization_inputs after all: fix the note")
    text = open(model_path).read()
    check("mrcal-show-projection-uncertainty" in text and "roadside audit" in text,
          "the .cameramodel does not say which mrcal tools cannot read it and what to run instead")

    p = rs_check.run("report", site, "--calib", calib, "-o", os.path.join(tmp, "r"))
    prog = [line for line in p.stderr.splitlines() if line.startswith("roadside report: ")]
    check(p.returncode == 0 and len(prog) == 4 + 2 and "cam1 (1 of 4)" in prog[0] and "report.pdf" in prog[-1],
          f"report progress on stderr: {prog}")
    check("auditing" not in p.stdout and "drawing" not in p.stdout, f"progress on stdout: {p.stdout}")
    shutil.rmtree(tmp)
    finish("cli_hygiene")


if __name__ == "__main__":
    main()

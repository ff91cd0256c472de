#!/usr/bin/env python3
"""One of the CLI's small lies (issue 42): a comma in a path handed to SUMO is refused by name
(netconvert reads its file options as comma-separated lists: before, "netconvert failed (exit
status 1)" and a log about files that do not exist). Oracle: the message and exit status 1.
(A bad option blamed on the option: issue 41's tests/cli/test_cli_hygiene.py.)"""
import os
import subprocess
import sys
import tempfile

ROADSIDE = os.environ["ROADSIDE"]
DEMO = os.path.join(os.environ["ROADSIDE_SOURCE_ROOT"], "sites", "demo")
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print("FAIL: " + what)


def run(*args):
    p = subprocess.run([ROADSIDE, *args], capture_output=True, text=True, timeout=60)
    return p.returncode, p.stderr


with tempfile.TemporaryDirectory() as top:
    keep = os.path.join(top, "sumo,files")
    rc, err = run("traffic", DEMO, "--sumo", "-o", os.path.join(top, "out"), "--keep", keep)
    check(rc == 1 and f"{keep}: contains a comma" in err, f"traffic --sumo --keep DIR,WITH,COMMA: rc {rc}: {err!r}")

if failures:
    sys.exit(1)
print("arguments: a comma in SUMO's paths refused by name")

#!/usr/bin/env python3
"""One of the CLI's small lies (issue 42): a comma in a path handed to SUMO is refused by name
(netconvert reads its file options as comma-separated lists: before, "netconvert failed (exit
status 1)" and a log about files that do not exist). Oracle: the message and exit status 1.
(A bad option blamed on the option: issue 41's CLI tests.)"""
import os
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "common"))
from rs_check import check, finish, run  # noqa: E402

DEMO = os.path.join(os.environ["ROADSIDE_SOURCE_ROOT"], "sites", "demo")

with tempfile.TemporaryDirectory() as top:
    keep = os.path.join(top, "sumo,files")
    p = run("traffic", DEMO, "--sumo", "-o", os.path.join(top, "out"), "--keep", keep, timeout=60)
    check(p.returncode == 1 and f"{keep}: contains a comma" in p.stderr,
          f"traffic --sumo --keep DIR,WITH,COMMA: rc {p.returncode}: {p.stderr!r}")

finish("arguments (a comma in SUMO's paths refused by name)")

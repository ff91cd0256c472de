"""What the Python tests of several suites share: the roadside executable under test
($ROADSIDE, set by meson), a list of failed checks, and running roadside.

    sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "common"))
    from rs_check import ROADSIDE, check, failures, run

A test calls check(cond, what) for every assertion (a failure is printed and kept, the test
goes on to the end) and ends with finish(name), which prints the verdict and exits non-zero when
`failures` is not empty.
"""
import os
import subprocess
import sys

ROADSIDE = os.environ["ROADSIDE"]
failures = []


def check(cond, what):
    """Records `what` as a failure (and prints it) unless cond holds; returns cond."""
    if not cond:
        failures.append(what)
        print("FAIL:", what)
    return cond


def need(*modules):
    """Imports the named modules (a test's oracles: cv2, mrcal, numpy) and returns them in order, or
    exits 77 (skipped) naming the one that is missing."""
    import importlib
    try:
        return [importlib.import_module(m) for m in modules]
    except ImportError as e:
        print("skipped: %s" % e)
        sys.exit(77)


def run(*args, stdin=None, env=None, timeout=300):
    """roadside ARGS..., text in and out captured; stdin: text for its standard input."""
    return subprocess.run([ROADSIDE, *args], input=stdin, capture_output=True, text=True,
                          timeout=timeout, env=env)


def demo_calibrated(prefix, env=None):
    """A temporary folder with a copy of sites/demo (tmp/site) calibrated by `roadside calib` into
    tmp/calib: returns (tmp, site, calib); a failing calib is a failed check."""
    import shutil
    import tempfile
    tmp = tempfile.mkdtemp(prefix=prefix)
    site = os.path.join(tmp, "site")
    shutil.copytree(os.path.join(os.environ["ROADSIDE_SOURCE_ROOT"], "sites", "demo"), site)
    calib = os.path.join(tmp, "calib")
    p = run("calib", site, "-o", calib, env=env)
    check(p.returncode == 0, f"calib: {p.stderr}")
    return tmp, site, calib


def finish(name):
    """Prints the verdict of test `name` and exits: 1 when a check failed, else 0."""
    if failures:
        print(f"{name}: {len(failures)} check(s) failed")
        sys.exit(1)
    print(f"{name}: all checks passed")
    sys.exit(0)

#!/usr/bin/env python3
"""Issue 14, finding 5 (stale and partial outputs), for `roadside report`.

The report is report.html and report.pdf together or nothing, with no figure file beside them;
a report that fails leaves neither file, not even an earlier report's, and says so. On a copy of
sites/demo (the simulator's seed 1), calibrated:
- a good report: OUT holds exactly report.html and report.pdf (the figures are embedded);
- the PDF cannot be renamed into place (report.pdf is a folder): no report.html either, and no
  temporary file;
- cam3 broken and recalibrated (calib removes cam3's files): the report fails (exit 1, names
  cam3.json), neither file is left, stderr says the earlier report was removed and never that a
  report was written;
- into a folder that did not exist: no folder is left;
- the site unreadable (cam3 with 3 picks): the earlier report is removed too.
Oracle: the folder listings and SHA-256 (hashlib) of the files.
"""
import hashlib
import os
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "common"))
import rs_check  # noqa: E402
from rs_check import check, failures, finish  # noqa: E402

SOURCE = os.environ["ROADSIDE_SOURCE_ROOT"]
REPORT = ["report.html", "report.pdf"]
# fontconfig (under cairo's text) keeps its state for the process' life: suppressed for the
# sanitizer build, as in test_report.py
ENV = dict(os.environ, LSAN_OPTIONS="suppressions=" + os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                                   "test_report.lsan.supp") + ":print_suppressions=0")


def run(*args):
    return rs_check.run(*args, env=ENV)


def sha(folder):
    if not os.path.isdir(folder):
        return {}
    return {n: hashlib.sha256(open(os.path.join(folder, n), "rb").read()).hexdigest() for n in os.listdir(folder)}


def break_camera(site, cam, npicks=4):
    """Rewrites cam's picks: npicks landmarks all seen at one pixel (the pose is undetermined)."""
    path = os.path.join(site, "observations", cam + ".csv")
    lines = open(path).read().splitlines()
    rows = [l.split(",")[0] for l in lines[1:] if l.strip()][:npicks]
    open(path, "w").write("landmark,u,v,sigma_px\n" + "".join(f"{r},100,100,1\n" for r in rows))


def good_report(site, calib, out):
    check(run("calib", site, "-o", calib).returncode == 0, "calib of the good site")
    p = run("report", site, "--calib", calib, "-o", out, "--no-audit")
    check(p.returncode == 0, f"good report: exit {p.returncode}: {p.stderr}")
    files = sha(out)
    check(sorted(files) == REPORT, f"good report: OUT holds {sorted(files)}, expected exactly {REPORT}")
    return files


def main():
    tmp = tempfile.mkdtemp(prefix="roadside-stale-report-")
    site = os.path.join(tmp, "site")
    shutil.copytree(os.path.join(SOURCE, "sites", "demo"), site)
    calib, out = os.path.join(tmp, "calib"), os.path.join(tmp, "report")

    good_report(site, calib, out)

    # ---- the PDF cannot be put in place (report.pdf is a folder): no HTML without its PDF
    os.remove(os.path.join(out, "report.pdf"))
    os.mkdir(os.path.join(out, "report.pdf"))
    p = run("report", site, "--calib", calib, "-o", out, "--no-audit")
    left = sorted(os.listdir(out))
    check(p.returncode == 1 and left == ["report.pdf"] and os.path.isdir(os.path.join(out, "report.pdf")),
          f"PDF fails: exit {p.returncode}, left {left}: {p.stderr}")
    os.rmdir(os.path.join(out, "report.pdf"))
    good_report(site, calib, out)

    # ---- cam3 broken: calib removes its files, the report fails and leaves nothing
    break_camera(site, "cam3")
    p = run("calib", site, "-o", calib)
    check(p.returncode == 1 and not os.path.exists(os.path.join(calib, "cam3.json")), "calib removed cam3.json")
    p = run("report", site, "--calib", calib, "-o", out, "--no-audit")
    check(p.returncode == 1 and "cam3.json" in p.stderr, f"cam3 missing: exit {p.returncode}: {p.stderr}")
    check(sorted(sha(out)) == [], f"cam3 missing: OUT still holds {sorted(sha(out))}")
    check("earlier report" in p.stderr and "removed (2 files)" in p.stderr and "report.html\n" not in p.stdout,
          f"cam3 missing: says the earlier report was removed: {p.stderr}")

    # ---- into a new folder: no folder left
    fresh = os.path.join(tmp, "fresh")
    p = run("report", site, "--calib", calib, "-o", fresh, "--no-audit")
    check(p.returncode == 1 and not os.path.exists(fresh), f"new folder: exit {p.returncode}, folder left")

    # ---- the site unreadable: the earlier report removed as well
    shutil.rmtree(site)
    shutil.copytree(os.path.join(SOURCE, "sites", "demo"), site)
    good_report(site, calib, out)
    break_camera(site, "cam3", npicks=3)  # the site reader refuses a camera with 3 picks
    p = run("report", site, "--calib", calib, "-o", out, "--no-audit")
    check(p.returncode == 1 and "cam3.csv" in p.stderr and sorted(sha(out)) == [] and "earlier report" in p.stderr,
          f"site unreadable: exit {p.returncode}, left {sorted(sha(out))}: {p.stderr}")

    if failures:
        print(f"files kept in {tmp}")
    else:
        shutil.rmtree(tmp, ignore_errors=True)
    finish("report stale_partial_outputs")


if __name__ == "__main__":
    main()

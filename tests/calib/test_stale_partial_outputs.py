#!/usr/bin/env python3
"""Issue 14, finding 5 (stale and partial outputs), for `roadside calib`.

A camera that fails leaves none of its files, and the files an earlier run wrote for it are
removed; a failed rerun never leaves the previous run's files looking current; the summary says
what was written and what was not, and never "written to OUT/" when nothing was. On a copy of
sites/demo (the simulator's seed 1):
- a good run: the 4 files of each of the 4 cameras and the run record calib.run.json;
- cam3 broken (its 4 picks in one tiny patch: the solver refuses the pose): exit 1; none of
  cam3's files is left, cam1, cam2 and cam4 are rewritten (new inodes: renamed into place by
  this run), the summary and the record name cam3 as failed and its removed files;
- --camera cam1: cam1 rewritten, cam2 and cam4 untouched (same SHA-256 and inode), the record
  says "not selected" for them;
- a write that fails half-way (cam2.json is a folder, so the rename onto it fails after
  cam2.cameramodel was already in place): nothing of cam2 is left but that folder;
- every camera broken: exit 1, no "written to", no camera file left; into a new folder: no
  folder left at all;
- the site unreadable (cam3 with 3 picks): the outputs the earlier run wrote for this site are
  removed, the record says why; the folder of another site is left byte for byte as it was.
Oracle: the folder listings, SHA-256 (hashlib) and inode numbers of the files.
"""
import hashlib
import json
import os
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "common"))
from rs_check import check, failures, finish, run  # noqa: E402

SOURCE = os.environ["ROADSIDE_SOURCE_ROOT"]
CAMS = ["cam1", "cam2", "cam3", "cam4"]
SUFFIXES = [".cameramodel", ".json", ".opencv.yaml", ".homography.json"]
RECORD = "calib.run.json"


def files_of(cam):
    return [cam + s for s in SUFFIXES]


def state(folder):
    """{name: (sha256, inode)} of every file in folder ({} when there is no folder)."""
    if not os.path.isdir(folder):
        return {}
    out = {}
    for name in sorted(os.listdir(folder)):
        path = os.path.join(folder, name)
        if os.path.isfile(path):
            out[name] = (hashlib.sha256(open(path, "rb").read()).hexdigest(), os.stat(path).st_ino)
        else:
            out[name] = ("folder", os.stat(path).st_ino)
    return out


def break_camera(site, cam, npicks=4):
    """Rewrites cam's picks: npicks landmarks all seen at one pixel (the pose is undetermined)."""
    path = os.path.join(site, "observations", cam + ".csv")
    lines = open(path).read().splitlines()
    rows = [l.split(",")[0] for l in lines[1:] if l.strip()][:npicks]
    open(path, "w").write("landmark,u,v,sigma_px\n" + "".join(f"{r},100,100,1\n" for r in rows))


def record(out):
    """The run record, {} when there is none (check() then reports what it lacks)."""
    path = os.path.join(out, RECORD)
    return json.load(open(path)) if os.path.isfile(path) else {}


def main():
    tmp = tempfile.mkdtemp(prefix="roadside-stale-calib-")
    site = os.path.join(tmp, "site")
    shutil.copytree(os.path.join(SOURCE, "sites", "demo"), site)
    out = os.path.join(tmp, "out")

    # ---- a good run: every file of every camera, and the record
    p = run("calib", site, "-o", out)
    check(p.returncode == 0, f"good run: exit {p.returncode}: {p.stderr}")
    first = state(out)
    want = sorted([f for c in CAMS for f in files_of(c)] + [RECORD])
    check(sorted(first) == want, f"good run: files {sorted(first)}")
    check(f"written to {out}/: cam1, cam2, cam3, cam4" in p.stdout, f"good run: summary: {p.stdout[-300:]}")
    check("not written" not in p.stdout, "good run: nothing said not written")
    rec = record(out)
    check(rec.get("complete") is True and rec.get("error") is None and rec.get("site") == os.path.realpath(site),
          f"good run: record {rec}")
    got = [(c["id"], c["status"], c["files"]) for c in rec.get("cameras", [])]
    check(got == [(c, "written", files_of(c)) for c in CAMS],
          f"good run: record cameras {rec.get('cameras')}")

    # ---- cam3 fails: none of its files left, the others rewritten, the summary says so
    break_camera(site, "cam3")
    p = run("calib", site, "-o", out)
    check(p.returncode == 1, f"cam3 broken: exit {p.returncode} (1 documented when a camera fails)")
    check("camera cam3" in p.stderr and "tiny patch" in p.stderr, f"cam3 broken: stderr names it: {p.stderr}")
    second = state(out)
    check(sorted(second) == sorted([f for c in CAMS if c != "cam3" for f in files_of(c)] + [RECORD]),
          f"cam3 broken: files {sorted(second)}")
    for f in files_of("cam1") + files_of("cam2") + files_of("cam4"):
        if f in second:
            check(second[f][1] != first[f][1], f"cam3 broken: {f} rewritten by this run (new inode)")
    check(f"written to {out}/: cam1, cam2, cam4\n" in p.stdout, f"cam3 broken: summary of written: {p.stdout[-600:]}")
    check("not written: cam3: failed (" in p.stdout and "its earlier outputs removed: " + ", ".join(files_of("cam3"))
          in p.stdout, f"cam3 broken: summary of not written: {p.stdout[-600:]}")
    rec = record(out)
    c3 = [c for c in rec.get("cameras", []) if c["id"] == "cam3"]
    check(rec.get("complete") is False and len(c3) == 1 and c3[0]["status"] == "failed" and
          c3[0]["removed"] == files_of("cam3") and "tiny patch" in c3[0]["error"], f"cam3 broken: record {c3}")

    # ---- a second failing run: nothing of cam3 reappears, and nothing to remove any more
    p = run("calib", site, "-o", out)
    check(p.returncode == 1 and not any(f.startswith("cam3") for f in os.listdir(out)), "rerun: still no cam3 file")
    check("not written: cam3: failed (" in p.stdout and "no earlier output of it was there" in p.stdout,
          f"rerun: summary: {p.stdout[-400:]}")

    # ---- --camera cam1: cam1 rewritten, the others untouched and recorded as not selected
    before = state(out)
    p = run("calib", site, "-o", out, "--camera", "cam1")
    check(p.returncode == 0, f"--camera cam1: exit {p.returncode}: {p.stderr}")
    after = state(out)
    for f in files_of("cam2") + files_of("cam4"):
        check(after.get(f) == before.get(f), f"--camera cam1: {f} untouched (same SHA-256 and inode)")
    for f in files_of("cam1"):
        check(f in after and after[f][1] != before[f][1], f"--camera cam1: {f} rewritten")
    check(f"written to {out}/: cam1\n" in p.stdout and "not selected" in p.stdout and "cam2, cam3, cam4" in p.stdout,
          f"--camera cam1: summary: {p.stdout[-400:]}")
    rec = record(out)
    got = [c["status"] for c in rec.get("cameras", [])]
    check(got == ["written", "not selected", "not selected", "not selected"] and rec.get("complete") is True,
          f"--camera cam1: record {rec.get('cameras')}")

    # ---- a write failing half-way: cam2.json is a folder, the rename onto it fails
    os.remove(os.path.join(out, "cam2.json"))
    os.mkdir(os.path.join(out, "cam2.json"))
    p = run("calib", site, "-o", out, "--camera", "cam2")
    left = sorted(f for f in os.listdir(out) if f.startswith("cam2"))
    check(p.returncode == 1 and left == ["cam2.json"] and os.path.isdir(os.path.join(out, "cam2.json")),
          f"write fails half-way: exit {p.returncode}, cam2 files left {left}: {p.stderr}")
    check(not [f for f in os.listdir(out) if ".tmp." in f], "write fails half-way: no temporary file left")
    check("not written: cam2: failed (" in p.stdout and "written to" not in p.stdout,
          f"write fails half-way: summary: {p.stdout[-400:]}")
    os.rmdir(os.path.join(out, "cam2.json"))

    # ---- every camera fails: no "written to", no camera file left
    for c in CAMS:
        break_camera(site, c)
    p = run("calib", site, "-o", out)
    check(p.returncode == 1, f"all broken: exit {p.returncode}")
    check("written to" not in p.stdout and "no camera written" in p.stdout, f"all broken: summary: {p.stdout}")
    check(sorted(os.listdir(out)) == [RECORD], f"all broken: left {sorted(os.listdir(out))}")
    rec = record(out)
    check(rec.get("complete") is False and all(c["status"] == "failed" for c in rec.get("cameras", [])),
          "all broken: record")
    fresh = os.path.join(tmp, "fresh")
    p = run("calib", site, "-o", fresh)
    check(p.returncode == 1 and not os.path.exists(fresh), f"all broken, new folder: exit {p.returncode}, folder left")
    p = run("calib", site, "-o", fresh, "--json")
    check(p.returncode == 1 and json.loads(p.stdout) == [] and "written to" not in p.stdout + p.stderr and
          "no camera written" in p.stderr, f"all broken --json: {p.stdout!r} {p.stderr!r}")

    # ---- the site unreadable: the earlier outputs of this site removed; another site's untouched
    shutil.rmtree(site)
    shutil.copytree(os.path.join(SOURCE, "sites", "demo"), site)
    other_site = os.path.join(tmp, "other-site")
    shutil.copytree(os.path.join(SOURCE, "sites", "demo"), other_site)
    other = os.path.join(tmp, "other")
    check(run("calib", site, "-o", out).returncode == 0, "good run again")
    check(run("calib", other_site, "-o", other).returncode == 0, "good run of the other site")
    other_before = state(other)
    break_camera(site, "cam3", npicks=3)  # the site reader refuses a camera with 3 picks
    p = run("calib", site, "-o", out)
    check(p.returncode == 1 and "cam3.csv" in p.stderr, f"site unreadable: exit {p.returncode}: {p.stderr}")
    check(sorted(os.listdir(out)) == [RECORD], f"site unreadable: left {sorted(os.listdir(out))}")
    check("earlier outputs of this site" in p.stderr and "cam1.cameramodel" in p.stderr and "written to" not in
          p.stdout + p.stderr, f"site unreadable: message {p.stderr}")
    rec = record(out)
    check(rec.get("complete") is False and "cam3.csv" in (rec.get("error") or "") and
          all(c["status"] == "failed" and c["removed"] == files_of(c["id"]) for c in rec.get("cameras", [])),
          f"site unreadable: record {rec}")
    p = run("calib", site, "-o", other)
    check(p.returncode == 1 and state(other) == other_before, "site unreadable: another site's folder untouched")

    if failures:
        print(f"files kept in {tmp}")
    else:
        shutil.rmtree(tmp, ignore_errors=True)
    finish("calib stale_partial_outputs")


if __name__ == "__main__":
    main()

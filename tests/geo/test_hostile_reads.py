#!/usr/bin/env python3
"""Issue 14, findings 2 and 3 ("Unbounded reads", "Paths not confined to the site"): every path a
site names must resolve (links followed) inside the site folder, refused unread otherwise (so
"/etc/passwd" is never quoted in a message); only regular files are read, each kind with a size
cap.
`"observations": "/dev/zero"` made `site check` grow until the kernel killed it and a FIFO hung it
for ever; now both are refused at once with the file named (core/rs_io.h rs_io_read_file_max:
opened without waiting, fstat'ed, refused unless a regular file within its bound). Also a camera
model that is a FIFO (mrcal's reader and OpenCV's YAML reader open files by name: the check comes
first), and a site.json over its 16 MiB bound (a sparse file: nothing is read). Every command runs
under a 30 s timeout: a hang fails the test instead of stalling the suite."""
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from rs_check import check, finish, run  # noqa: E402


def refused(site, what, *patterns):
    try:
        p = run("site", "check", site, timeout=30)
    except subprocess.TimeoutExpired:
        check(False, f"{what}: site check hung (30 s)")
        return
    ok = p.returncode == 1 and all(s in p.stdout for s in patterns)
    check(ok, f"{what}: site check exit {p.returncode}, output {p.stdout[-400:]!r}")
    if ok:
        line = next(l for l in p.stdout.splitlines() if patterns[0] in l)
        print(f"{what}: refused: {line}")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        base = os.path.join(tmp, "base")
        p = run("site", "simulate", base, "--seed", "3", "--cameras", "1")
        check(p.returncode == 0, f"site simulate: {p.stderr}")
        p = run("site", "check", base)
        check(p.returncode == 0, f"the unmodified site passes: {p.stdout}")

        def variant(name, edit):
            site = os.path.join(tmp, name)
            subprocess.run(["cp", "-r", base, site], check=True)
            sj = json.load(open(os.path.join(site, "site.json")))
            edit(site, sj)
            json.dump(sj, open(os.path.join(site, "site.json"), "w"))
            return site

        # finding 3: paths stay inside the site folder, refused unread (no contents quoted)
        site = variant("devzero", lambda s, sj: sj["cameras"][0].update(observations="/dev/zero"))
        refused(site, "observations /dev/zero", "/dev/zero", "outside the site folder")
        for name, path in (("absolute", "/etc/passwd"), ("parent", "../../../../../../etc/passwd")):
            site = variant("passwd_" + name, lambda s, sj, path=path: sj["cameras"][0].update(observations=path))
            refused(site, f"observations {path}", "passwd", "outside the site folder")
            p = run("site", "check", site, timeout=30)
            check("root:" not in p.stdout + p.stderr, f"{name}: the file's contents are quoted: {p.stdout!r}")

        def link_out(s, sj):
            os.symlink("/etc/passwd", os.path.join(s, "observations", "link.csv"))
            sj["cameras"][0]["observations"] = "observations/link.csv"
        refused(variant("link_out", link_out), "a link inside the site to /etc/passwd", "link.csv",
                "outside the site folder")
        site = variant("bg_out", lambda s, sj: sj["cameras"][0].update(backgrounds="/tmp"))
        refused(site, "backgrounds /tmp", "cameras[0].backgrounds", "outside the site folder")

        # finding 2: inside the site, only regular files, each within its bound

        def fifo_obs(s, sj):
            os.mkfifo(os.path.join(s, "observations", "fifo.csv"))
            sj["cameras"][0]["observations"] = "observations/fifo.csv"
        refused(variant("fifo_obs", fifo_obs), "observations a FIFO", "fifo.csv", "not a regular file (a FIFO)")

        for ext in ("cameramodel", "yaml"):
            def fifo_model(s, sj, ext=ext):
                os.mkfifo(os.path.join(s, "cameras", "fifo." + ext))
                sj["cameras"][0]["model"] = "cameras/fifo." + ext
            refused(variant("fifo_" + ext, fifo_model), f"model a FIFO (.{ext})", "fifo." + ext, "a FIFO")

        site = variant("big", lambda s, sj: None)
        with open(os.path.join(site, "site.json"), "r+b") as f:
            f.truncate(17 << 20)  # sparse: 17 MiB of zeros after the JSON
        refused(site, "site.json of 17 MiB", "site.json", "more than the 16777216 bytes")
    finish("test_hostile_reads")


if __name__ == "__main__":
    main()

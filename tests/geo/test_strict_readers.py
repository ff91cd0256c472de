#!/usr/bin/env python3
"""Issue 42, item 2 and "every reader reads all of its file or refuses it": a NUL byte in an
observations CSV silently dropped every later row (site check: 0 errors, calib used 10 of 14
picks); `locate` on standard input split a line longer than 1023 bytes into two points, read
`0x10` as 16 and skipped a line with a NUL. Now every such line is an error naming the file and
the line (core/rs_text.h), in the observations CSV, the point import CSV and locate's stdin.

Oracles: the lines spoiled by the test itself (which line, which field); for locate, its answer
for the same pixel on a line of its own."""
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from rs_check import check, finish, run  # noqa: E402


def site_check(site):
    try:
        return run("site", "check", site, timeout=30)
    except subprocess.TimeoutExpired:
        check(False, f"{site}: site check hung (30 s)")
        return None


def spoil(base, tmp, name, edit):
    """A copy of base whose cam1.csv lines (bytes) go through edit; returns (site, csv path)."""
    site = os.path.join(tmp, name)
    shutil.copytree(base, site)
    csv = os.path.join(site, "observations", "cam1.csv")
    lines = open(csv, "rb").read().split(b"\n")
    open(csv, "wb").write(b"\n".join(edit(lines)))
    return site, csv


def main():
    with tempfile.TemporaryDirectory() as tmp:
        base = os.path.join(tmp, "base")
        p = run("site", "simulate", base, "--seed", "3", "--cameras", "1")
        check(p.returncode == 0, f"site simulate: {p.stderr}")
        rows = [l for l in open(os.path.join(base, "observations", "cam1.csv"), "rb").read().split(b"\n")[1:] if l]
        check(len(rows) >= 10, f"the simulated camera has {len(rows)} picks")
        p = site_check(base)
        check(p and p.returncode == 0, f"the unmodified site passes: {p and p.stdout}")

        # a NUL in the 9th pick (line 10): with 8 picks before it the site stayed calibratable and
        # the old reader said 0 errors; now refused at that line
        def nul(lines):
            lines[9] = lines[9] + b"\0junk"
            return lines
        site, _ = spoil(base, tmp, "nul", nul)
        p = site_check(site)
        check(p and p.returncode == 1 and "cam1.csv:10: a NUL byte" in p.stdout,
              f"NUL: exit {p and p.returncode}: {p and p.stdout[-400:]!r}")
        p = run("calib", site, "-o", os.path.join(tmp, "nul_out"))
        check(p.returncode != 0, f"NUL: calib ran on the picks before it (exit {p.returncode})")

        # a line of 5000 bytes (a pick with 4,980 blanks after it): an error, not a row cut in two
        def longline(lines):
            lines[3] = lines[3] + b" " * 5000
            return lines
        site, _ = spoil(base, tmp, "long", longline)
        p = site_check(site)
        check(p and p.returncode == 1 and "cam1.csv:4: the line is longer than 4096 bytes" in p.stdout,
              f"long line: {p and p.stdout[-400:]!r}")

        # numbers: hexadecimal, trailing text, nan: each an error at its line and field
        for name, bad, want in (("hex", b"0x10", "only decimal"), ("junk", b"12.5abc", "not a number"),
                                ("nan", b"nan", "not finite")):
            def number(lines, bad=bad):
                f = lines[2].split(b",")
                f[1] = bad
                lines[2] = b",".join(f)
                return lines
            site, _ = spoil(base, tmp, name, number)
            p = site_check(site)
            check(p and p.returncode == 1 and "cam1.csv:3: u: " in p.stdout and want in p.stdout,
                  f"{name}: {p and p.stdout[-400:]!r}")

        # the point import's CSV: a NUL and an overlong line are refused with the line
        pts = os.path.join(tmp, "points.csv")
        good = ["lat,lon,u,v"] + ["%.6f,%.6f,%d,%d" % (48.137 + 1e-4 * k, 11.575 + 2e-4 * (k % 3), 100 + 50 * k,
                                                        200 + 40 * k) for k in range(6)]
        for name, lines, want in (("nul", good[:4] + [good[4] + "\0"] + good[5:], "points.csv:5: a NUL byte"),
                                  ("long", good[:2] + [good[2] + " " * 5000] + good[3:],
                                   "points.csv:3: the line is longer than 4096 bytes")):
            open(pts, "w").write("\n".join(lines) + "\n")
            p = run("site", "import", os.path.join(tmp, "imp_" + name), "--points", pts, "--image-size",
                    "1920x1080")
            check(p.returncode != 0 and want in p.stderr, f"import {name}: exit {p.returncode}: {p.stderr!r}")

        # locate on standard input: one line, one answer or one error
        loc = ["locate", base, "--calib", os.path.join(base, "truth"), "--camera", "cam1"]
        p = run(*loc, stdin="960 900\n")
        check(p.returncode == 0 and len(p.stdout.splitlines()) == 1, f"locate one pixel: {p.stdout!r} {p.stderr!r}")
        one = p.stdout
        # 960 then 1100 blanks then 900: the old reader read 1023 bytes ("960" alone: an error) and
        # then "900" as a second, separate line; now one line, 1107 bytes, under the bound: one point
        p = run(*loc, stdin="960" + " " * 1100 + "900\n")
        check(p.returncode == 0 and p.stdout == one, f"locate 1107-byte line: {p.stdout!r} {p.stderr!r}")
        # over the bound (4096): one error naming line 1, and the next line still answered
        p = run(*loc, stdin="960" + " " * 5000 + "900\n960 900\n")
        check(p.returncode == 1 and p.stdout == one and "<stdin>:1: the line is longer" in p.stderr
              and p.stderr.count("\n") == 1, f"locate 5004-byte line: {p.stdout!r} {p.stderr!r}")
        for name, text, want in (("hex", "0x10 900\n", "<stdin>:1: u: not a number ('0x10'): only decimal"),
                                 ("nul", "960 900\0\n", "<stdin>:1: a NUL byte at byte 8"),
                                 ("junk", "960 900 7\n", "<stdin>:1: expected 'u v' (two numbers), found more"),
                                 ("nan", "960 nan\n", "<stdin>:1: v: not finite")):
            p = subprocess.run([os.environ["ROADSIDE"], *loc], input=text.encode(), capture_output=True, timeout=60)
            err = p.stderr.decode(errors="replace")
            check(p.returncode == 1 and not p.stdout and want in err, f"locate {name}: {p.stdout!r} {err!r}")
    finish("test_strict_readers")


if __name__ == "__main__":
    main()

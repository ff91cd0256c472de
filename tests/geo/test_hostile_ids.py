#!/usr/bin/env python3
"""Issue 14, finding 1 ("Writes outside the output folder"): a camera id is used as a file name.
The site format's one rule for ids (core/rs_io.h rs_io_name_problem: 1..64 bytes, no control
character, no '/' or '\\', no "..", no blank at either end) is checked by the site reader, so
`site check` names the field and `calib` refuses the site before it writes anything; landmark ids
follow the same rule (a newline in an id broke the summary table). A simulated site (which does
calibrate) is the fixture; after each refusal the test looks for any file named after the id
anywhere under its temporary folder."""
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from rs_check import check, finish, run  # noqa: E402

HOSTILE = {
    "parent escape": ("../../escaped_cam", "path separator"),
    "absolute": ("/tmp/abs_cam", "path separator"),
    "dot-dot": ("..", '".."'),
    "blank": (" ", "blank"),
    "newline": ("cam\nX", "control character"),
    "backslash": ("a\\b", "path separator"),
    "too long": ("c" * 65, "longer than 64"),
    "empty": ("", "empty"),
}


def files_under(root):
    return {os.path.relpath(os.path.join(dp, f), root) for dp, _, fn in os.walk(root) for f in fn}


def main():
    with tempfile.TemporaryDirectory() as tmp:
        base = os.path.join(tmp, "base")
        p = run("site", "simulate", base, "--seed", "3", "--cameras", "1")
        check(p.returncode == 0, f"site simulate: {p.stderr}")
        p = run("calib", base, "-o", os.path.join(tmp, "calib_ok"))
        check(p.returncode == 0, f"the unmodified site calibrates: {p.stderr}")
        for what, (cam_id, rule) in HOSTILE.items():
            site = os.path.join(tmp, "s_" + what.replace(" ", "_"))
            subprocess.run(["cp", "-r", base, site], check=True)
            sj = json.load(open(os.path.join(site, "site.json")))
            sj["cameras"][0]["id"] = cam_id
            json.dump(sj, open(os.path.join(site, "site.json"), "w"))
            before = files_under(tmp)
            p = run("site", "check", site)
            check(p.returncode == 1 and "cameras[0].id" in p.stdout and rule in p.stdout,
                  f"{what}: site check exit {p.returncode}, output {p.stdout!r}")
            out = os.path.join(site, "out", "a")
            p = run("calib", site, "-o", out)
            check(p.returncode != 0, f"{what}: calib accepted the id (exit {p.returncode})")
            new = files_under(tmp) - before
            check(not new, f"{what}: calib wrote {sorted(new)}")
            leaked = [f for f in files_under(tmp) if "escaped_cam" in f or "abs_cam" in f]
            check(not leaked and not os.path.exists("/tmp/abs_cam.cameramodel"), f"{what}: files named after the id: {leaked}")
            print(f"camera id {cam_id!r} ({what}): site check names cameras[0].id ({rule}); calib exit {p.returncode}, "
                  f"nothing written")
        # landmark ids follow the same rule
        site = os.path.join(tmp, "s_landmark")
        subprocess.run(["cp", "-r", base, site], check=True)
        lm = json.load(open(os.path.join(site, "landmarks.geojson")))
        lm["features"][0]["properties"]["id"] = "L001\nL002"
        json.dump(lm, open(os.path.join(site, "landmarks.geojson"), "w"))
        p = run("site", "check", site)
        check(p.returncode == 1 and "properties.id" in p.stdout and "control character" in p.stdout,
              f"landmark id with a newline: exit {p.returncode}, {p.stdout!r}")
        print("landmark id with a newline: refused by site check")
    finish("test_hostile_ids")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
# test_site_init.py -- `roadside site init`: the skeleton is valid JSON/GeoJSON, `site check`
# reports exactly its missing parts (no landmarks, cam1's model, cam1's picks) and nothing else,
# it passes once filled in with the fixture's files, init refuses a non-empty folder (leaving it
# untouched), accepts an empty one, records orthometric heights, and leaves no temporary folder.
import json
import os
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import site_fixture as fx  # noqa: E402


def main():
    tmp = tempfile.mkdtemp(prefix="rs_site_init_")
    os.chdir(tmp)
    try:
        o = fx.ORIGIN
        rc, out, err = fx.run("site", "init", "NEW", "--origin", "%r,%r,%r" % o)
        if rc != 0:
            fx.fail("init failed", out, err)
        for f in ("site.json", "landmarks.geojson", "README.md", "observations/cam1.csv"):
            if not os.path.isfile(os.path.join("NEW", f)):
                fx.fail("init did not write %s" % f)
        for d in ("cameras", "observations", "backgrounds/cam1"):
            if not os.path.isdir(os.path.join("NEW", d)):
                fx.fail("init did not make %s/" % d)
        sj = fx.load_json("NEW/site.json")   # raises on invalid JSON
        g = fx.load_json("NEW/landmarks.geojson")
        if (sj["origin"]["lat"], sj["origin"]["lon"], sj["origin"]["h"]) != o or sj["heights"] != "ellipsoidal":
            fx.fail("site.json origin/heights: %s" % json.dumps(sj))
        if sj["name"] != "NEW" or g != {"type": "FeatureCollection", "features": []}:
            fx.fail("name or landmarks wrong: %s %s" % (sj["name"], g))
        readme = open("NEW/README.md").read()
        for needed in ("[longitude, latitude, height]", "orthometric", "sigma", "centre", ".cameramodel",
                       "cv::FileStorage"):
            if needed.lower() not in readme.lower():
                fx.fail("README.md does not explain %r" % needed)

        # check reports exactly the missing parts
        rc, out, err = fx.run("site", "check", "NEW")
        want = ["NEW/landmarks.geojson: features: empty",
                "NEW/cameras/cam1.cameramodel: missing file",
                "NEW/observations/cam1.csv: camera 'cam1' has 0 usable observations"]
        lines = out.splitlines()
        if rc != 1 or lines[-1] != "3 errors, 0 warnings" or len(lines) != 4:
            fx.fail("check of the skeleton: exit %d, expected 1 and exactly 3 errors" % rc, out, err)
        for w in want:
            if not any(line.startswith(w) for line in lines):
                fx.fail("check of the skeleton does not report %r" % w, out)

        # refuses a non-empty folder and leaves it untouched
        before = open("NEW/site.json").read()
        rc, out, err = fx.run("site", "init", "NEW", "--origin", "1,2,3")
        if rc != 1 or "exists and is not empty" not in err or open("NEW/site.json").read() != before:
            fx.fail("init over a non-empty folder: exit %d" % rc, out, err)

        # an empty folder is fine; orthometric heights are recorded
        os.mkdir("EMPTY")
        rc, out, err = fx.run("site", "init", "EMPTY", "--origin", "48.1,11.5,470.25", "--orthometric", "47.3",
                              "--name", "my \"quoted\" site")
        sj2 = fx.load_json("EMPTY/site.json") if rc == 0 else {}
        if rc != 0 or sj2.get("heights") != {"orthometric": 47.3} or sj2.get("name") != 'my "quoted" site':
            fx.fail("init into an empty folder with --orthometric: exit %d, %s" % (rc, sj2), out, err)

        # usage errors
        for args in (["NEW2"], ["NEW2", "--origin", "95,0,0"], ["NEW2", "--origin", "1,2"]):
            rc, out, err = fx.run("site", "init", *args)
            if rc != 2 or os.path.exists("NEW2"):
                fx.fail("init %s: exit %d, expected 2 and no folder" % (args, rc), out, err)

        leftovers = [f for f in os.listdir(".") if ".tmp." in f]
        if leftovers:
            fx.fail("temporary folders left behind: %s" % leftovers)

        # filled in with the fixture's files, it passes
        fx.make_site("FIX")
        shutil.copy("FIX/landmarks.geojson", "NEW/landmarks.geojson")
        shutil.copy("FIX/cameras/north.cameramodel", "NEW/cameras/cam1.cameramodel")
        shutil.copy("FIX/observations/north.csv", "NEW/observations/cam1.csv")
        rc, out, err = fx.run("site", "check", "NEW")
        if rc != 0 or out.splitlines()[-1] != "0 errors, 0 warnings":
            fx.fail("the filled-in skeleton should pass", out, err)
        print("init: skeleton valid, check lists exactly %d missing parts, passes once filled in" % len(want))
    finally:
        os.chdir("/")
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()

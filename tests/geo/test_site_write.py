#!/usr/bin/env python3
# test_site_write.py ROUNDTRIP -- geo's writers (geo/rs_site_write.h, rs_lanes_write) against
# Python's json module and `roadside site check` as oracles. site_write_roundtrip.c loads the
# fixture (ellipsoidal, and orthometric with N = 47 m), writes it again from what it read in both
# layouts, records backgrounds and writes lanes. Asserted:
#   - site.json and landmarks.geojson parse (json) to the fixture's values: strings and
#     structure exactly, numbers to 1e-9 (heights go h + N - N), sigmas only where the fixture
#     gives them; the extra "simulated" member is the JSON given;
#   - the copy passes `roadside site check` with 0 errors and 0 warnings;
#   - the hand layout is docs/site-format.md's: one top-level member per line, one camera per
#     entry, one feature per line; the tool layout is cJSON's (tab-indented);
#   - background records: the entries written (json) and as the loader reads them back
#     (rs_site_background, rs_site_background_tag), a repeated tag keeping its last value, the
#     "backgrounds" folder set when absent and kept when present, NOT_FOUND for an unknown
#     camera, PARSE for a source that is not JSON;
#   - lanes written [lon, lat] and [lon, lat, h] read back (rs_lanes_read) within 1e-6 m.
import json
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import site_fixture as fx  # noqa: E402

TOL = 1e-9


def close(a, b, where):
    """a == b for JSON values, numbers within TOL."""
    if isinstance(a, bool) or isinstance(b, bool) or isinstance(a, str) or a is None:
        if a != b:
            fx.fail("%s: %r != %r" % (where, a, b))
    elif isinstance(a, (int, float)):
        if not isinstance(b, (int, float)) or abs(a - b) > TOL:
            fx.fail("%s: %r != %r" % (where, a, b))
    elif isinstance(a, list):
        if not isinstance(b, list) or len(a) != len(b):
            fx.fail("%s: %r != %r" % (where, a, b))
        for i, (x, y) in enumerate(zip(a, b)):
            close(x, y, "%s[%d]" % (where, i))
    elif isinstance(a, dict):
        if not isinstance(b, dict) or list(a) != list(b):
            fx.fail("%s: members %s != %s" % (where, list(a), list(b) if isinstance(b, dict) else b))
        for k in a:
            close(a[k], b[k], "%s.%s" % (where, k))


def run_roundtrip(exe, layout, heights, h_offset):
    with fx.TempSite(heights=heights, h_offset=h_offset) as site:
        os.makedirs("OUT")
        shutil.copytree(os.path.join(site, "cameras"), os.path.join("OUT", "cameras"))
        os.makedirs(os.path.join("OUT", "observations"))
        os.makedirs(os.path.join("OUT", "backgrounds", "north"))
        os.makedirs(os.path.join("OUT", "backgrounds", "south"))
        p = subprocess.run([exe, site, "OUT", layout], capture_output=True, text=True, errors="replace")
        out = p.stdout
        if p.returncode != 0 or "status 0 done" not in out or "Sanitizer" in p.stderr:
            fx.fail("site_write_roundtrip %s failed" % layout, out, p.stderr)
        want_site = fx.load_json(os.path.join(site, "site.json"))
        want_lm = fx.load_json(os.path.join(site, "landmarks.geojson"))
        text = {n: open(os.path.join("OUT", n)).read() for n in ("site.json", "landmarks.geojson")}
        # site.json as rewritten by the background records: they are taken out again below
        got_site = json.loads(text["site.json"])
        got_lm = json.loads(text["landmarks.geojson"])
        rc, check_out, check_err = fx.run("site", "check", "OUT")
        csv = {c: (open(os.path.join(site, "observations", c + ".csv")).read(),
                   open(os.path.join("OUT", "observations", c + ".csv")).read()) for c in ("north", "south")}
        lanes = {d: fx.load_json(os.path.join("OUT", "lanes_%s.geojson" % d)) for d in ("2d", "3d")}
        lanes_text = open(os.path.join("OUT", "lanes_2d.geojson")).read()
    return out, want_site, want_lm, got_site, got_lm, text, (rc, check_out, check_err), csv, lanes, lanes_text


def check(exe, layout, heights, h_offset):
    what = "%s layout, heights %s" % (layout, json.dumps(heights))
    out, want_site, want_lm, got_site, got_lm, text, chk, csv, lanes, lanes_text = \
        run_roundtrip(exe, layout, heights, h_offset)
    lines = dict(line.split(" ", 1) for line in out.splitlines() if line.startswith("record_"))
    # backgrounds: what was recorded, then take the records out to compare with the fixture
    north, south = got_site["cameras"]
    want_north = [
        {"name": "morning", "file": "backgrounds/north/morning.png", "synthetic": False,
         "tags": {"time": "2024-06-21T07:30:00+02:00", "conditions": "sunny", "foo": "3"},
         "source": {"method": "test", "frames": 3}},
        {"name": "evening", "file": "backgrounds/north/evening.png", "synthetic": False, "tags": {}},
    ]
    want_south = [{"name": "twin", "file": "backgrounds/south/twin.png", "synthetic": True,
                   "tags": {"conditions": "sunny"}}]
    close(want_north, north.pop("background_images"), what + ": north.background_images")
    close(want_south, south.pop("background_images"), what + ": south.background_images")
    if north.get("backgrounds") != "backgrounds/north" or south.pop("backgrounds", None) != "backgrounds/south":
        fx.fail(what + ": backgrounds folders: %s, %s" % (north.get("backgrounds"), south.get("backgrounds")))
    if "\t" not in text["site.json"]:
        fx.fail(what + ": a recorded site.json is in cJSON's tab layout", text["site.json"])
    if (lines.get("record_unknown_camera"), lines.get("record_bad_source")) != ("4", "2"):
        fx.fail(what + ": record errors: %s" % lines, out)
    # site.json and landmarks.geojson as the fixture says
    simulated = got_site.pop("simulated", None)
    close({"seed": 5, "values": [1, 2.5, -0.125], "text": 'a "quoted" word'}, simulated, what + ": simulated")
    close(want_site, got_site, what + ": site.json")
    close(want_lm, got_lm, what + ": landmarks.geojson")
    # the observations: same picks (the writer prints u, v to 1e-6 px)
    for cam, (want, got) in csv.items():
        w = [r.split(",") for r in want.splitlines()[1:]]
        g = [r.split(",") for r in got.splitlines()[1:]]
        if got.splitlines()[0] != "landmark,u,v,sigma_px" or len(w) != len(g) or any(
                a[0] != b[0] or abs(float(a[1]) - float(b[1])) > 1e-6 or abs(float(a[2]) - float(b[2])) > 1e-6 or
                float(b[3]) != (float(a[3]) if len(a) > 3 and a[3] else 1.0) for a, b in zip(w, g)):
            fx.fail(what + ": observations/%s.csv" % cam, got, want)
    rc, check_out, check_err = chk
    if rc != 0 or "0 errors, 0 warnings" not in check_out:
        fx.fail(what + ": site check of the copy", check_out, check_err)
    # the loader's view of the records
    bg = [line for line in out.splitlines() if line.startswith("background ")]
    want_bg = [
        "background north morning backgrounds/north/morning.png backgrounds/north/morning.png 0 "
        "time=2024-06-21T07:30:00+02:00 conditions=sunny foo=3 | time=2024-06-21T07:30:00+02:00 "
        "synthetic=false name=morning nope=-",
        "background north evening backgrounds/north/evening.png backgrounds/north/evening.png 0 "
        "| time=- synthetic=false name=evening nope=-",
        "background south twin backgrounds/south/twin.png backgrounds/south/twin.png 1 conditions=sunny "
        "| time=- synthetic=true name=twin nope=-",
    ]
    if bg != want_bg:
        fx.fail(what + ": the records as loaded:\n" + "\n".join(bg) + "\nexpected:\n" + "\n".join(want_bg), out)
    # lanes
    dev = {line.split()[1]: float(line.split()[2]) for line in out.splitlines() if line.startswith("lanes ")}
    if set(dev) != {"2d", "3d"} or max(dev.values()) > 1e-6:
        fx.fail(what + ": lanes read back differ: %s m" % dev, out)
    f2, f3 = lanes["2d"]["features"], lanes["3d"]["features"]
    if [len(p) for p in f2[0]["geometry"]["coordinates"]] != [2, 2, 2] or \
            [len(p) for p in f3[1]["geometry"]["coordinates"]] != [3, 3]:
        fx.fail(what + ": lane coordinates [lon, lat] / [lon, lat, h]", json.dumps(lanes))
    close({"id": "A1_in1", "kind": "approach", "width_m": 3.5, "direction": "forward", "speed_mps": 13.89,
           "next": ["track"]}, f2[0]["properties"], what + ": lane 0")
    close({"id": "track", "width_m": 2.75, "direction": "both", "next": []}, f2[1]["properties"], what + ": lane 1")
    # layouts
    lm_text, lanes_lines = text["landmarks.geojson"], lanes_text.splitlines()
    if layout == "hand":
        lm_lines = lm_text.splitlines()
        if lm_lines[0] != '{"type": "FeatureCollection", "features": [' or lm_lines[-1] != "]}" or \
                len(lm_lines) != len(want_lm["features"]) + 2 or len(lanes_lines) != 4:
            fx.fail(what + ": landmarks.geojson / lanes not one feature per line", lm_text + lanes_text)
    elif "\t" not in lm_text or len(lm_text.splitlines()) < 10 * len(want_lm["features"]):
        fx.fail(what + ": landmarks.geojson not in cJSON's layout", lm_text)
    print("ok: %s" % what)


def check_hand_site_json(exe):
    """The hand layout of site.json itself (before any record rewrites it): `site init`'s."""
    parent = tempfile.mkdtemp(prefix="rs_site_write_")
    tmp = os.path.join(parent, "init")
    rc, out, err = fx.run("site", "init", tmp, "--origin", "48.1,11.5,500", "--orthometric", "47.5", "--name", 'a "b"')
    if rc != 0:
        fx.fail("site init", out, err)
    got = open(os.path.join(tmp, "site.json")).read()
    shutil.rmtree(parent, ignore_errors=True)
    want = ('{\n'
            '  "name": "a \\"b\\"",\n'
            '  "origin": {"lat": 48.1, "lon": 11.5, "h": 500},\n'
            '  "heights": {"orthometric": 47.5},\n'
            '  "landmark_sigma_m": {"horizontal": 0.3, "vertical": 0.5},\n'
            '  "max_landmark_distance_m": 1000,\n'
            '  "cameras": [\n'
            '    {"id": "cam1", "model": "cameras/cam1.cameramodel", "observations": "observations/cam1.csv",\n'
            '     "backgrounds": "backgrounds/cam1",\n'
            '     "note": "example camera: rename it, add its model and its picks (README.md)"}\n'
            '  ]\n'
            '}\n')
    if got != want:
        fx.fail("site init's site.json is not in the hand layout", got, want)
    print("ok: hand layout of site.json (site init)")


def main():
    exe = os.path.abspath(sys.argv[1])  # TempSite changes the working directory
    for layout in ("tool", "hand"):
        check(exe, layout, "ellipsoidal", 0.0)
        check(exe, layout, {"orthometric": 47.0}, -47.0)
    check_hand_site_json(exe)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
# test_site_check.py DEFECT -- `roadside site check` on the fixture with one injected defect.
#
# Each defect is one meson test (tests/geo/meson.build lists them). The test copies the valid
# fixture, injects the defect, runs `roadside site check SITE` and asserts the exit status
# (1 for errors, 0 for warnings only) and that one output line names the file, the line or the
# feature, and the field, with the expected message. 'clean' checks the fixture itself passes.
import json
import math
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import site_fixture as fx  # noqa: E402


def load(path):
    with open(path) as f:
        return json.load(f)


def save(path, obj):
    with open(path, "w") as f:
        json.dump(obj, f, indent=2)
        f.write("\n")


def edit_text(path, old, new):
    with open(path) as f:
        text = f.read()
    if old not in text:
        fx.fail("fixture changed: %r not in %s" % (old, path))
    with open(path, "w") as f:
        f.write(text.replace(old, new, 1))
    return text[:text.index(old)].count("\n") + 1  # line of the edit


def set_feature(site, i, fn):
    p = os.path.join(site, "landmarks.geojson")
    g = load(p)
    fn(g["features"][i])
    save(p, g)
    return g["features"][i]


def set_site(site, fn):
    p = os.path.join(site, "site.json")
    s = load(p)
    fn(s)
    save(p, s)
    return s


def set_csv_line(site, cam, lineno, text):
    p = os.path.join(site, "observations", cam + ".csv")
    with open(p) as f:
        lines = f.read().splitlines()
    if lineno > len(lines):
        lines.append(text)
    else:
        lines[lineno - 1] = text
    with open(p, "w") as f:
        f.write("\n".join(lines) + "\n")


def coords(site, i):
    return load(os.path.join(site, "landmarks.geojson"))["features"][i]["geometry"]["coordinates"]


def fix(lon, lat, h):
    """A check on the corrected point "should it be [lon, lat, h]?": a callable pattern that
    compares the numbers (to 1e-9 degrees and 1 mm) instead of their rounding."""
    def match(line):
        m = re.search(r"should it be \[([-0-9.e]+), ([-0-9.e]+), ([-0-9.e]+)\]\?$", line)
        return bool(m) and abs(float(m.group(1)) - lon) < 1e-9 and \
            abs(float(m.group(2)) - lat) < 1e-9 and abs(float(m.group(3)) - h) < 1e-3
    return match


# Each defect: inject(site) -> list of (regex, what) that must each match one output line,
# and the expected exit status.
def d_clean(s):
    return 0, [(r"^0 errors, 0 warnings$", "summary")]


def d_missing_site_json(s):
    os.remove(os.path.join(s, "site.json"))
    return 1, [(r"^SITE/site\.json: missing file", "missing site.json")]


def d_missing_landmarks(s):
    os.remove(os.path.join(s, "landmarks.geojson"))
    return 1, [(r"^SITE/landmarks\.geojson: missing file", "missing landmarks")]


def d_missing_model(s):
    os.remove(os.path.join(s, "cameras", "north.cameramodel"))
    return 1, [(r"^SITE/cameras/north\.cameramodel: missing file \(named by cameras\[0\]\.model in site\.json\)",
                "missing model")]


def d_missing_observations(s):
    os.remove(os.path.join(s, "observations", "south.csv"))
    return 1, [(r"^SITE/observations/south\.csv: missing file \(named by cameras\[1\]\.observations",
                "missing observations")]


def d_invalid_json(s):
    line = edit_text(os.path.join(s, "site.json"), '"max_landmark_distance_m": 1000,',
                     '"max_landmark_distance_m": 1000,,')
    return 1, [(r"^SITE/site\.json:%d: invalid JSON at column \d+" % line, "JSON syntax")]


def d_invalid_geojson_syntax(s):
    line = edit_text(os.path.join(s, "landmarks.geojson"), '"L03"', '"L03" "kind2"')
    return 1, [(r"^SITE/landmarks\.geojson:%d: invalid JSON: " % line, "GeoJSON syntax")]


def d_not_feature_collection(s):
    p = os.path.join(s, "landmarks.geojson")
    g = load(p)
    g["type"] = "Feature"
    save(p, g)
    return 1, [(r"^SITE/landmarks\.geojson: type: 'Feature', expected \"FeatureCollection\"", "root type")]


def d_not_a_point(s):
    # a LineString is a line landmark (issue 13, item 4): any other geometry type is refused
    set_feature(s, 2, lambda f: f["geometry"].update(type="Polygon"))
    return 1, [(r"^SITE/landmarks\.geojson: feature 2 \(id 'L02'\): geometry\.type: 'Polygon'", "geometry")]


def d_missing_height(s):
    set_feature(s, 6, lambda f: f["geometry"]["coordinates"].pop())
    return 1, [(r"^SITE/landmarks\.geojson: feature 6 \(id 'L06'\): coordinates: the height is missing",
                "2D point")]


def d_nonfinite_json(s):
    edit_text(os.path.join(s, "site.json"), '"h": 520.0', '"h": 1e999')
    return 1, [(r"^SITE/site\.json: origin\.h: not a finite number", "inf in JSON")]


def d_nonfinite_csv(s):
    set_csv_line(s, "north", 5, "L03,nan,400")
    return 1, [(r"^SITE/observations/north\.csv:5: u: not finite \('nan'\)", "nan in CSV")]


def d_latitude_out_of_range(s):
    set_feature(s, 1, lambda f: f["geometry"].update(coordinates=[11.575, 95.0, 520.0]))
    return 1, [(r"^SITE/landmarks\.geojson: feature 1 \(id 'L01'\): coordinates: latitude 95 is out of range \[-90, 90\]",
                "latitude range")]


def d_longitude_out_of_range(s):
    set_site(s, lambda j: j["origin"].update(lon=200.0))
    return 1, [(r"^SITE/site\.json: origin\.lon: 200 is out of range \[-180, 180\]", "longitude range")]


def d_swapped(s):
    lon, lat, h = coords(s, 3)
    set_feature(s, 3, lambda f: f["geometry"].update(coordinates=[lat, lon, h]))
    return 1, [(r"^SITE/landmarks\.geojson: feature 3 \(id 'L03'\): coordinates: looks like latitude and "
                r"longitude are exchanged .*should it be \[", "swapped lat/lon"),
               (fix(lon, lat, h), "the corrected point")]


def d_radians(s):
    lon, lat, h = coords(s, 5)
    set_feature(s, 5, lambda f: f["geometry"].update(coordinates=[math.radians(lon), math.radians(lat), h]))
    return 1, [(r"^SITE/landmarks\.geojson: feature 5 \(id 'L05'\): coordinates: looks like radians .*"
                r"should it be \[", "radians"), (fix(lon, lat, h), "the corrected point")]


def d_swapped_prior(s):
    def swap(j):
        p = j["cameras"][1]["position_prior"]
        p["lat"], p["lon"] = p["lon"], p["lat"]
    set_site(s, swap)
    return 1, [(r"^SITE/site\.json: cameras\[1\]\.position_prior: looks like latitude and longitude are exchanged",
                "swapped prior")]


def d_duplicate_landmark_id(s):
    set_feature(s, 7, lambda f: f["properties"].update(id="L01"))
    return 1, [(r"^SITE/landmarks\.geojson: feature 7 \(id 'L01'\): properties\.id: duplicate id \(already used by feature 1\)",
                "duplicate id")]


def d_duplicate_landmark_ids_many(s):
    # three features share L02's id and two share L05's: each later one names the FIRST feature
    # with its id, in file order (the check sorts ids: O(N log N), issue 14 finding 7)
    set_feature(s, 6, lambda f: f["properties"].update(id="L05"))
    set_feature(s, 8, lambda f: f["properties"].update(id="L02"))
    set_feature(s, 9, lambda f: f["properties"].update(id="L02"))
    return 1, [(r"^SITE/landmarks\.geojson: feature 6 \(id 'L05'\): properties\.id: duplicate id \(already used by feature 5\)",
                "L05 once"),
               (r"^SITE/landmarks\.geojson: feature 8 \(id 'L02'\): properties\.id: duplicate id \(already used by feature 2\)",
                "L02 first repeat"),
               (r"^SITE/landmarks\.geojson: feature 9 \(id 'L02'\): properties\.id: duplicate id \(already used by feature 2\)",
                "L02 second repeat")]


def d_unknown_landmark(s):
    set_csv_line(s, "north", 4, "L99,100,200")
    return 1, [(r"^SITE/observations/north\.csv:4: landmark: 'L99' is not a landmark of landmarks\.geojson", "unknown")]


def d_unknown_landmark_case(s):
    set_csv_line(s, "north", 4, "l02,100,200")
    return 1, [(r"^SITE/observations/north\.csv:4: landmark: 'l02' is not a landmark .*'L02'", "case hint")]


def d_duplicate_observation(s):
    set_csv_line(s, "south", 6, "L04,10,20,")
    return 1, [(r"^SITE/observations/south\.csv:6: landmark: 'L04' is observed twice in this camera \(first at line 3\)",
                "duplicate observation")]


def d_pixel_outside(s):
    set_csv_line(s, "north", 3, "L01,1920,100")
    set_csv_line(s, "south", 7, "L08,100,-0.6,")
    return 1, [(r"^SITE/observations/north\.csv:3: u: 1920 is outside the image: valid u in \[-0\.5, 1919\.5\] "
                r"\(width 1920 in SITE/cameras/north\.cameramodel\)", "u outside"),
               (r"^SITE/observations/south\.csv:7: v: -0\.6 is outside the image: valid v in \[-0\.5, 719\.5\]",
                "v outside")]


def d_too_few_observations(s):
    p = os.path.join(s, "observations", "south.csv")
    with open(p) as f:
        lines = f.read().splitlines()
    with open(p, "w") as f:
        f.write("\n".join(lines[:4]) + "\n")
    return 1, [(r"^SITE/observations/south\.csv: camera 'south' has 3 usable observations: it needs at least 4",
                "too few")]


def d_too_far(s):
    lat, lon, h = fx.llh_from_enu(1500.0, 2000.0, 0.0)
    set_feature(s, 9, lambda f: f["geometry"].update(coordinates=[lon, lat, h]))
    return 0, [(r"^SITE/landmarks\.geojson: feature 9 \(id 'L09'\): coordinates: warning: 2[45]\d\d\.\d m from the "
                r"origin, farther than max_landmark_distance_m \(1000 m\)", "too far"),
               (r"^0 errors, 1 warning$", "warning only")]


def d_height_mismatch(s):
    lon, lat, h = coords(s, 3)   # L03 is 15.8 m from the origin
    set_feature(s, 3, lambda f: f["geometry"].update(coordinates=[lon, lat, h + 47.3]))
    return 0, [(r"^SITE/landmarks\.geojson: feature 3 \(id 'L03'\): coordinates: warning: 47\.5 m above the "
                r"origin, 15\.8 m from it horizontally: .*ellipsoidal vs orthometric", "height system"),
               (r"^0 errors, 1 warning$", "warning only")]


def d_decimal_comma_quoted(s):
    set_csv_line(s, "north", 6, 'L04,"812,5",604')
    return 1, [(r"^SITE/observations/north\.csv:6: u: not a number \('812,5'\)", "quoted decimal comma")]


def d_decimal_comma(s):
    set_csv_line(s, "north", 6, "L04,812,5,604")
    return 1, [(r"^SITE/observations/north\.csv:6: 4 fields, the header has 3 \(a decimal comma\?", "decimal comma")]


def d_not_a_number(s):
    set_csv_line(s, "south", 2, "L03,12.5,abc,")
    return 1, [(r"^SITE/observations/south\.csv:2: v: not a number \('abc'\)", "text for v")]


def d_missing_header(s):
    set_csv_line(s, "north", 1, "L99,1,2")
    return 1, [(r"^SITE/observations/north\.csv:1: header: no column 'landmark'", "no header")]


def d_semicolons(s):
    p = os.path.join(s, "observations", "north.csv")
    with open(p) as f:
        text = f.read()
    with open(p, "w") as f:
        f.write(text.replace(",", ";"))
    return 1, [(r"^SITE/observations/north\.csv:1: header: no column 'landmark'.*commas, not semicolons", "separator")]


def d_bom_crlf(s):
    # a UTF-8 byte-order mark and CRLF line ends (Windows editors) are accepted everywhere
    for name in ("site.json", "landmarks.geojson", "observations/south.csv"):
        p = os.path.join(s, name)
        with open(p) as f:
            text = f.read()
        with open(p, "wb") as f:
            f.write(b"\xef\xbb\xbf" + text.replace("\n", "\r\n").encode())
    return 0, [(r"^0 errors, 0 warnings$", "clean")]


def d_bad_sigma_px(s):
    set_csv_line(s, "south", 3, "L04,100,100,0")
    return 1, [(r"^SITE/observations/south\.csv:3: sigma_px: 0 px is outside \[0\.01, 1000\] px", "sigma_px")]


def d_misspelt_field(s):
    def misspell(j):
        j["landmark_sigma"] = j.pop("landmark_sigma_m")
    set_site(s, misspell)
    return 1, [(r"^SITE/site\.json: landmark_sigma: warning: unknown field, ignored", "typo warning"),
               (r"^SITE/site\.json: landmark_sigma_m: missing", "missing required")]


def d_bad_heights(s):
    set_site(s, lambda j: j.update(heights="orthometric"))
    return 1, [(r"^SITE/site\.json: heights: \"orthometric\": expected \"ellipsoidal\" or \{\"orthometric\": N\}",
                "heights")]


def d_bad_landmark_sigma(s):
    set_feature(s, 4, lambda f: f["properties"].update(sigma_h_m=-0.1))
    return 1, [(r"^SITE/landmarks\.geojson: feature 4 \(id 'L04'\): properties\.sigma_h_m: -0\.1 must be > 0", "sigma")]


def d_id_not_string(s):
    set_feature(s, 8, lambda f: f["properties"].update(id=8))
    return 1, [(r"^SITE/landmarks\.geojson: feature 8: properties\.id: must be a string: write \"8\"", "numeric id")]


def d_duplicate_camera_id(s):
    set_site(s, lambda j: j["cameras"][1].update(id="north"))
    return 1, [(r"^SITE/site\.json: cameras\[1\]\.id: duplicate camera id 'north' \(already used by cameras\[0\]\)",
                "camera id")]


def d_bad_background_images(s):
    # entries geo cannot use are errors; a tag of another type is skipped with a warning
    def bad(j):
        j["cameras"][0]["background_images"] = [
            {"name": "ok", "file": "backgrounds/north/ok.png", "tags": {"time": "2024-06-21T12:00:00Z", "n": 3}},
            {"name": "nofile"},
            "notanobject",
            {"file": "backgrounds/north/x.png", "synthetic": "yes", "extra": 1},
        ]
        j["cameras"][1]["background_images"] = {"file": "x.png"}
    set_site(s, bad)
    return 1, [(r"^SITE/site\.json: cameras\[0\]\.background_images\[0\]\.tags\.n: warning: not text or a boolean, ignored",
                "numeric tag"),
               (r"^SITE/site\.json: cameras\[0\]\.background_images\[1\]\.file: missing \(a string\)", "no file"),
               (r"^SITE/site\.json: cameras\[0\]\.background_images\[2\]: not an object", "not an object"),
               (r"^SITE/site\.json: cameras\[0\]\.background_images\[3\]\.extra: warning: unknown field", "unknown"),
               (r"^SITE/site\.json: cameras\[0\]\.background_images\[3\]\.synthetic: not true or false", "synthetic"),
               (r"^SITE/site\.json: cameras\[1\]\.background_images: not a list \[\.\.\.\]", "not a list"),
               (r"^4 errors, 2 warnings$", "summary")]


def d_background_images(s):
    # what `roadside background` records loads clean
    def good(j):
        j["cameras"][0]["background_images"] = [
            {"name": "m", "file": "backgrounds/north/m.png", "synthetic": False,
             "tags": {"time": "2024-06-21T12:00:00Z", "conditions": "sunny", "wet": True},
             "source": {"method": "temporal median", "inputs": ["a.mp4"], "frames_read": 10}}]
    set_site(s, good)
    return 0, [(r"^0 errors, 0 warnings$", "clean")]


def d_bad_cameramodel(s):
    with open(os.path.join(s, "cameras", "south.cameramodel"), "w") as f:
        f.write("{'lensmodel': 'LENSMODEL_PINHOLE', 'intrinsics': [1, 2, 3]}\n")
    return 1, [(r"^SITE/cameras/south\.cameramodel: not a valid mrcal \.cameramodel", "bad model")]


def d_no_cameras(s):
    set_site(s, lambda j: j.update(cameras=[]))
    return 1, [(r"^SITE/site\.json: cameras: empty: a site needs at least one camera", "no cameras")]


def d_no_landmarks(s):
    save(os.path.join(s, "landmarks.geojson"), {"type": "FeatureCollection", "features": []})
    return 1, [(r"^SITE/landmarks\.geojson: features: empty", "no landmarks")]


# ---- issue 14, finding 4: "site check passes unusable sites" -- everything calib would refuse
# is reported by check, by landmark id and field

def d_unusable_height_1e300(s):
    set_feature(s, 3, lambda f: f["geometry"]["coordinates"].__setitem__(2, 1e300))
    return 1, [(r"^SITE/landmarks\.geojson: feature 3 \(id 'L03'\): coordinates: height 1e\+300 m is not near "
                r"the Earth's surface \(\[-1000, 10000\] m\)", "absurd landmark height")]


def d_unusable_origin_height_1e300(s):
    set_site(s, lambda j: j["origin"].update(h=1e300))
    return 1, [(r"^SITE/site\.json: origin\.h: 1e\+300 m is not a height near the Earth's surface", "origin height")]


def d_unusable_landmark_sigma_tiny(s):
    set_site(s, lambda j: j["landmark_sigma_m"].update(horizontal=1e-300))
    return 1, [(r"^SITE/site\.json: landmark_sigma_m\.horizontal: 1e-300 m is outside \[0\.001, 100\] m: a 1-sigma "
                r"under 1 mm is better than any survey", "survey sigma 1e-300")]


def d_unusable_landmark_sigma_huge(s):
    set_site(s, lambda j: j["landmark_sigma_m"].update(vertical=1e300))
    return 1, [(r"^SITE/site\.json: landmark_sigma_m\.vertical: 1e\+300 m is outside \[0\.001, 100\] m",
                "survey sigma 1e300")]


def d_unusable_feature_sigma_tiny(s):
    set_feature(s, 4, lambda f: f["properties"].update(sigma_v_m=1e-9))
    return 1, [(r"^SITE/landmarks\.geojson: feature 4 \(id 'L04'\): properties\.sigma_v_m: 1e-09 m is outside",
                "per-landmark sigma")]


def d_unusable_sigma_px_tiny(s):
    set_csv_line(s, "south", 3, "L04,1091.944,231.702,1e-5")
    return 1, [(r"^SITE/observations/south\.csv:3: sigma_px: 1e-05 px is outside \[0\.01, 1000\] px", "pick sigma")]


def d_unusable_prior_sigma_huge(s):
    set_site(s, lambda j: j["cameras"][1]["position_prior"].update(sigma_m=1e300))
    return 1, [(r"^SITE/site\.json: cameras\[1\]\.position_prior\.sigma_m: 1e\+300 m is outside", "prior sigma")]


def d_unusable_coincident_landmarks(s):
    # L05 given L04's coordinates (a copied row): a warning naming both and what calib does
    c = coords(s, 4)
    set_feature(s, 5, lambda f: f["geometry"].update(coordinates=list(c)))
    return 0, [(r"^SITE/landmarks\.geojson: feature 5 \(id 'L05'\): coordinates: warning: at the same position as 'L04' "
                r"\(feature 4, within 1 mm\): a copied coordinate\? calib keeps both; .*flags whichever",
                "coincident")]


def d_unusable_duplicate_key_site(s):
    edit_text(os.path.join(s, "site.json"), '"h": 520.0', '"h": 520.0, "h": 9999.0')
    return 1, [(r"^SITE/site\.json: origin\.h: appears more than once in the same object", "repeated key")]


def d_unusable_duplicate_key_landmark(s):
    edit_text(os.path.join(s, "landmarks.geojson"), '"id": "L02"', '"id": "L02", "id": "L2b"')
    return 1, [(r"^SITE/landmarks\.geojson: feature 2 \(id 'L02'\): properties\.id: appears more than once",
                "repeated key in a feature")]


def d_unusable_duplicate_key_top(s):
    edit_text(os.path.join(s, "landmarks.geojson"), '"type": "FeatureCollection",',
              '"type": "FeatureCollection", "type": "Feature",')
    return 1, [(r"^SITE/landmarks\.geojson: type: appears more than once at the top level", "repeated top key")]


def d_unusable_hex_pixel(s):
    set_csv_line(s, "south", 3, "L04,0x620,231.702,1.5")
    return 1, [(r"^SITE/observations/south\.csv:3: u: not a number \('0x620'\): only decimal numbers", "hex")]


def d_unusable_inf_nan_words(s):
    set_csv_line(s, "south", 3, "L04,infinity,231.702,1.5")
    set_csv_line(s, "south", 4, "L05,171.177,nan,")
    return 1, [(r"^SITE/observations/south\.csv:3: u: not finite \('infinity'\)", "infinity"),
               (r"^SITE/observations/south\.csv:4: v: not finite \('nan'\)", "nan")]


def d_unusable_cr_only_line_ends(s):
    # classic-Mac line ends (CR only) are read as line ends: the site is clean, every row read
    p = os.path.join(s, "observations", "south.csv")
    with open(p) as f:
        text = f.read()
    with open(p, "wb") as f:
        f.write(text.replace("\n", "\r").encode())
    return 0, [(r"^0 errors, 0 warnings$", "clean")]


def main():
    name = sys.argv[1] if len(sys.argv) > 1 else ""
    inject = globals().get("d_" + name)
    if not inject:
        fx.fail("unknown defect %r" % name)
    with fx.TempSite() as site:
        status, patterns = inject(site)
        rc, out, err = fx.run("site", "check", site)
        if rc != status:
            fx.fail("%s: exit status %d, expected %d" % (name, rc, status), out, err)
        for pattern, what in patterns:
            if callable(pattern):
                if not any(pattern(line) for line in out.splitlines()):
                    fx.fail("%s: no line has %s" % (name, what), out, err)
            else:
                fx.expect_line(out, pattern, what)
        summary = out.splitlines()[-1] if out else ""
        m = re.match(r"^(\d+) errors?, (\d+) warnings?$", summary)
        if not m or (int(m.group(1)) == 0) != (status == 0):
            fx.fail("%s: bad summary line %r" % (name, summary), out, err)
        if "rror" in err and "cameramodel-parser" not in err:
            fx.fail("%s: unexpected stderr" % name, out, err)
    print("ok: %s" % name)


if __name__ == "__main__":
    main()

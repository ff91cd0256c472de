#!/usr/bin/env python3
"""roadside pick with real basemaps in headless Chromium (issue 41): a 20,000 x 20,000 px GeoTIFF
orthophoto (tiled, DEFLATE, sparse: transparent but for a 1-px checkerboard at each landmark,
with overviews; made by GDAL's Python in a second) and a local XYZ tile folder (web mercator,
each tile one solid colour) served by this test over HTTP and named with --tiles.

Checks, each against an oracle of its own:
- the page's Content-Security-Policy allows images from the tile server's origin and no other;
  the map runs the Leaflet version pick/web/package-lock.json pins (window.L.version), served by
  roadside, and every request the browser made (DevTools' Network log) went to roadside or to the
  tile server;
- zoomed in with the wheel at a landmark, the page asks for level-0 tiles (the raster's own
  pixels), and the tile served there equals GDAL's read of the same 256 x 256 window of the file,
  byte for byte (and holds the checkerboard, which the level-1 tile has averaged away);
- the page asked the XYZ server for zoom-19 tiles, and where the orthophoto is transparent the
  screen shows the colour of the web mercator tile that Python's own mercator formula puts there;
- a point-pair JSON (the demo's picks, and a new landmark at a lat, lon) imported through the
  page's file input: every pick set, the new landmark where GDAL/PROJ (osr) puts that lat, lon;
- refine focal chosen on the page: after the save, `roadside calib --refine focal` on the files
  finds the page's pose to 1e-6, and no warning tells the user to run an option;
- a pick dragged in the image moves to the pixel under the release point, a map pick dragged on
  the map moves on the ground (read back through the API);
- saved and reloaded in a new server and page: the files hold the import and both drags, only
  the landmark given sigmas on the page has sigma_h_m/sigma_v_m in the file, and a change of site.json's site-wide sigma after
  the save reaches every landmark but the one given sigmas of its own on the page."""
import json
import math
import os
import sys
import tempfile
import threading
import time
import urllib.request
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rs_check import check, finish, need, run  # noqa: E402
import rs_pick_test as pt  # noqa: E402

N = 20000   # the orthophoto's side, pixels
CELL = 0.02  # metres
CHECK = 32  # the checkerboard's side at each landmark, pixels
ZOOM = 19   # the XYZ folder's zoom
STATUS = "document.getElementById('status').textContent"


def tile_colour(x, y):
    return ((x * 67) % 200 + 40, (y * 101) % 200 + 40, ((x + y) * 37) % 200 + 40)


def mercator_tile(lat, lon, z):
    """Python's own web mercator: the fractional tile coordinates of lat, lon at zoom z."""
    k = 2 ** z
    r = math.radians(lat)
    return (lon + 180) / 360 * k, (1 - math.log(math.tan(r) + 1 / math.cos(r)) / math.pi) / 2 * k


def make_ortho(path, origin, landmarks):
    """The big GeoTIFF on the site's grid CRS (what roadside ortho writes), sparse RGBA: unwritten
    blocks cost nothing and read as transparent. Its overviews are made empty by GDAL ("NONE")
    and filled here where the checkerboards are (numpy block means, GDAL's AVERAGE), which keeps
    the file seconds to make on a loaded machine (GDAL averaging 1.6 G empty samples takes 20 s)."""
    gdal, osr = need("osgeo.gdal", "osgeo.osr")
    gdal.UseExceptions()
    gdal.SetConfigOption("SPARSE_OK_OVERVIEW", "ON")
    ds = gdal.GetDriverByName("GTiff").Create(path, N, N, 4, gdal.GDT_Byte, [
        "TILED=YES", "COMPRESS=DEFLATE", "SPARSE_OK=TRUE", "ALPHA=YES"])
    srs = osr.SpatialReference()
    srs.ImportFromProj4(f"+proj=ortho +lat_0={origin[0]:.10f} +lon_0={origin[1]:.10f} +x_0=0 +y_0=0 "
                        "+ellps=WGS84 +units=m +no_defs")
    ds.SetProjection(srs.ExportToWkt())
    e_edge, n_edge = -N * CELL / 2, N * CELL / 2
    ds.SetGeoTransform([e_edge, CELL, 0, n_edge, 0, -CELL])
    levels = [2, 4, 8, 16, 32, 64]
    ds.BuildOverviews("NONE", levels)
    board = (np.indices((CHECK, CHECK)).sum(0) % 2 * 255).astype(np.uint8)
    corners = []
    for e, n in landmarks:
        i, j = int((e - e_edge) / CELL) - CHECK // 2, int((n_edge - n) / CELL) - CHECK // 2
        corners.append((i, j))
        for b, a in enumerate([board, 255 - board, board, np.full_like(board, 255)]):
            ds.GetRasterBand(b + 1).WriteArray(a, i, j)
    for i, j in corners:
        for k, f in enumerate(levels):
            i0, j0 = i // f * f, j // f * f
            w, h = -(-(i + CHECK - i0) // f) * f, -(-(j + CHECK - j0) // f) * f
            for b in range(4):
                full = ds.GetRasterBand(b + 1).ReadAsArray(i0, j0, w, h).astype(float)
                mean = full.reshape(h // f, f, w // f, f).mean(axis=(1, 3))
                ds.GetRasterBand(b + 1).GetOverview(k).WriteArray(np.floor(mean + 0.5).astype(np.uint8), i0 // f, j0 // f)
    ds = None
    return e_edge, n_edge


class TileServer:
    """The XYZ folder over HTTP on a port of its own; .requests: the paths asked for."""

    def __init__(self, root):
        self.requests = []
        outer = self

        class H(SimpleHTTPRequestHandler):
            def __init__(self, *a, **k):
                super().__init__(*a, directory=root, **k)

            def log_message(self, *a):
                outer.requests.append(self.path)

        self.httpd = ThreadingHTTPServer(("127.0.0.1", 0), H)
        self.port = self.httpd.server_address[1]
        threading.Thread(target=self.httpd.serve_forever, daemon=True).start()

    def stop(self):
        self.httpd.shutdown()


def main():
    if not any(os.access(os.path.join(d, "chromium"), os.X_OK) for d in os.environ["PATH"].split(":")):
        print("chromium missing: skipped")
        sys.exit(77)
    gdal, osr, cv2 = need("osgeo.gdal", "osgeo.osr", "cv2")
    with tempfile.TemporaryDirectory() as tmp:
        site = pt.demo_copy(tmp, empty_camera="cam1")
        sj = json.load(open(os.path.join(site, "site.json")))
        origin = (sj["origin"]["lat"], sj["origin"]["lon"])
        picks = [l.strip().split(",") for l in open(os.path.join(pt.SRC, "sites", "demo", "observations", "cam1.csv"))][1:]
        lm = json.load(open(os.path.join(site, "landmarks.geojson")))["features"]
        lonlat = {f["properties"]["id"]: f["geometry"]["coordinates"][:2] for f in lm}
        wgs = osr.SpatialReference()
        wgs.ImportFromEPSG(4326)
        wgs.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
        grid = osr.SpatialReference()
        grid.ImportFromProj4(f"+proj=ortho +lat_0={origin[0]:.10f} +lon_0={origin[1]:.10f} +x_0=0 +y_0=0 "
                             "+ellps=WGS84 +units=m +no_defs")
        to_en = osr.CoordinateTransformation(wgs, grid)
        to_ll = osr.CoordinateTransformation(grid, wgs)
        en = {i: to_en.TransformPoint(lo, la)[:2] for i, (lo, la) in lonlat.items()}
        # the point pairs: the demo's picks and a new landmark 6 m east of L008 at a made-up pixel
        new_en = (en["L008"][0] + 6.0, en["L008"][1] - 2.0)
        new_lon, new_lat = to_ll.TransformPoint(*new_en)[:2]
        pairs = {"results": [{"id": i, "x": float(u), "y": float(v), "lat": lonlat[i][1], "lng": lonlat[i][0]}
                             for i, u, v, _ in picks]
                 + [{"id": "NEW1", "x": 1500.25, "y": 700.5, "lat": new_lat, "lng": new_lon}]}
        pairs_path = os.path.join(tmp, "pairs.json")
        json.dump(pairs, open(pairs_path, "w"))
        ortho = os.path.join(tmp, "ortho.tif")
        e_edge, n_edge = make_ortho(ortho, origin, list(en.values()) + [new_en])
        # the XYZ folder: zoom 19 around the site, each tile one colour
        xyz = os.path.join(tmp, "xyz")
        x0, y0 = mercator_tile(origin[0], origin[1], ZOOM)
        for x in range(int(x0) - 3, int(x0) + 4):
            for y in range(int(y0) - 3, int(y0) + 4):
                os.makedirs(os.path.join(xyz, str(ZOOM), str(x)), exist_ok=True)
                img = np.zeros((256, 256, 3), np.uint8)
                img[:] = tile_colour(x, y)[::-1]  # BGR
                cv2.imwrite(os.path.join(xyz, str(ZOOM), str(x), f"{y}.png"), img)
        ts = TileServer(xyz)
        tiles_url = f"http://127.0.0.1:{ts.port}/{{z}}/{{x}}/{{y}}.png"
        srv = pt.Server(site, "--camera", "cam1", "--ortho", ortho, "--tiles", tiles_url,
                        "--tiles-attribution", "test tiles, CC0", "--tiles-max-zoom", str(ZOOM))
        br = pt.Browser(tmp, 1280, 900)
        try:
            # the page's policy: images from itself and the tile server, nothing else
            with urllib.request.urlopen(srv.url) as r:
                csp = r.headers["Content-Security-Policy"]
            img_src = next(p for p in csp.split(";") if p.strip().startswith("img-src")).split()[1:]
            check(sorted(img_src) == sorted(["'self'", "data:", "blob:", f"http://127.0.0.1:{ts.port}"]),
                  f"img-src allows the tile origin alone: {csp}")
            check("default-src 'self'" in csp and "connect-src 'self'" in csp, f"nothing else fetched: {csp}")
            br.call("Network.enable")
            br.call("Page.navigate", url=srv.url)
            check(br.wait("window.rsPick && window.rsPick.ready"), "the page did not become ready")
            # the map is Leaflet's (npm's, compiled into roadside: pick/web/package-lock.json)
            version = br.eval("window.L && window.L.version")
            check(version == json.load(open(os.path.join(pt.SRC, "pick", "web", "package-lock.json")))
                  ["packages"]["node_modules/leaflet"]["version"], f"the page runs the locked Leaflet: {version}")
            M = json.loads(urllib.request.urlopen(srv.url + "api/map").read())
            check(M["ortho"]["width"] == N and abs(M["ortho"]["cell_m"] - CELL) < 1e-12,
                  f"the orthophoto at its own resolution: {M['ortho']}")
            check(br.eval("document.getElementById('attribution').textContent") == "test tiles, CC0",
                  "the attribution under the map")

            # ---- import the point pairs through the page's file input ----
            br.call("DOM.enable")
            root = br.call("DOM.getDocument")["root"]["nodeId"]
            node = br.call("DOM.querySelector", nodeId=root, selector="#import")["nodeId"]
            br.call("DOM.setFileInputFiles", files=[pairs_path], nodeId=node)
            check(br.wait(f"window.rsPick.state.picks === {len(picks) + 1}"),
                  f"import: {len(picks) + 1} picks (status: {br.eval(STATUS)})")
            S = br.eval("window.rsPick.state")
            L = {l["id"]: l for l in S["landmarks"]}
            got = {i: L[i]["pick_px"] for i in L if L[i]["pick_px"]}
            worst = max(max(abs(got[i][0] - float(u)), abs(got[i][1] - float(v))) for i, u, v, _ in picks)
            check(worst < 1e-6, f"imported picks as in the file: worst {worst:.2e} px")
            if check("NEW1" in L and L["NEW1"]["kind"] == "map-pick", "the new landmark imported"):
                d = math.hypot(L["NEW1"]["enu_m"][0] - new_en[0], L["NEW1"]["enu_m"][1] - new_en[1])
                # osr's x, y are on the ellipsoid, the site's ENU at its height: h d / R ~ 1 mm
                check(d < 0.01, f"NEW1 where GDAL/PROJ puts its lat, lon: {d:.4f} m off")
                print(f"import: {len(picks) + 1} pairs, NEW1 {d * 1000:.2f} mm from osr's E, N")
            check(S["solve"]["ok"], f"solved after the import: {S['solve']['message']}")

            # ---- zoom the map to full resolution at landmark L008 ----
            lid = "L008"
            e, n = L[lid]["enu_m"][:2]
            for _ in range(30):
                p = br.eval(f"window.rsPick.toScreen('map', {e}, {n})")
                br.call("Input.dispatchMouseEvent", type="mouseWheel", x=p["x"], y=p["y"], deltaX=0, deltaY=-100)
                if br.eval("window.rsPick.orthoLevel") == 0:
                    break
            i, j = int((e - e_edge) / CELL), int((n_edge - n) / CELL)
            key = f"0/{i // 256}/{j // 256}"
            check(br.wait(f"window.rsPick.orthoLevel === 0 && window.rsPick.tilesLoaded.includes('{key}')"),
                  f"zoomed to level 0 at {lid}: tile {key} loaded (level {br.eval('window.rsPick.orthoLevel')})")
            served = np.frombuffer(urllib.request.urlopen(srv.url + "api/tiles/" + key).read(), np.uint8)
            served = served.reshape(256, 256, 4)
            ds = gdal.Open(ortho)
            oracle = ds.ReadAsArray(256 * (i // 256), 256 * (j // 256), 256, 256).transpose(1, 2, 0)
            check(np.array_equal(served, oracle),
                  f"tile {key} is GDAL's read of the same window: {np.count_nonzero(served != oracle)} bytes differ")
            di, dj = i % 256, j % 256
            patch = served[max(0, dj - 4):dj + 4, max(0, di - 4):di + 4, 0].astype(int)
            check(patch.min() == 0 and patch.max() == 255, "level 0 holds the 1-px checkerboard (full resolution)")
            coarse = np.frombuffer(urllib.request.urlopen(
                srv.url + f"api/tiles/1/{i // 512}/{j // 512}").read(), np.uint8).reshape(256, 256, 4)
            ci, cj = (i % 512) // 2, (j % 512) // 2
            cpatch = coarse[cj - 2:cj + 2, ci - 2:ci + 2, 0].astype(int)
            check(cpatch.max() - cpatch.min() < 64, f"level 1 has averaged it (range {cpatch.max() - cpatch.min()})")
            ds = None

            # ---- the web tiles under the transparent orthophoto ----
            check(br.wait(f"window.rsPick.webZoom === {ZOOM}"), f"web tiles at zoom {ZOOM}")
            asked = [r for r in ts.requests if r.startswith(f"/{ZOOM}/")]
            check(len(asked) >= 1, f"the XYZ server was asked for zoom-{ZOOM} tiles: {ts.requests[:10]}")
            # a screen point near L008 where the orthophoto is transparent: 1.5 m from every
            # landmark (their dots, labels and checkerboards) and the camera, 0.3 m from tile edges
            S = br.eval("window.rsPick.state")
            busy = [l["enu_m"][:2] for l in S["landmarks"]] + [S["solve"]["position_enu_m"][:2]]
            spot = None
            for r in (2.0, 3.0, 4.0):
                for k in range(16):
                    pe, pn = e + r * math.cos(k * math.pi / 8), n + r * math.sin(k * math.pi / 8)
                    lon, lat = to_ll.TransformPoint(pe, pn)[:2]
                    fx, fy = mercator_tile(lat, lon, ZOOM)
                    edge_m = min(fx % 1, 1 - fx % 1, fy % 1, 1 - fy % 1) * 40075016.686 * math.cos(math.radians(lat)) / 2 ** ZOOM
                    if edge_m > 0.3 and min(math.hypot(pe - b[0], pn - b[1]) for b in busy) > 1.5:
                        spot = (pe, pn, fx, fy)
                        break
                if spot:
                    break
            if check(spot is not None, "a free spot near L008 for the web tile check"):
                pe, pn, fx, fy = spot
                br.eval(f"window.rsPick.zoomMap({pe}, {pn}, 50)")
                # screen positions in CSS pixels, which are device pixels here (scale factor 1)
                br.wait(f"window.rsPick.webZoom === {ZOOM}")
                time.sleep(1.0)  # the web tile's image decoded and drawn
                q = br.eval(f"window.rsPick.toScreen('map', {pe}, {pn})")
                shot = os.path.join(tmp, "map.png")
                br.screenshot(shot)
                px = cv2.imread(shot)[int(round(q["y"])), int(round(q["x"]))][::-1]
                want = tile_colour(int(fx), int(fy))
                check(max(abs(int(a) - b) for a, b in zip(px, want)) <= 3,
                      f"web tile {ZOOM}/{int(fx)}/{int(fy)} drawn where mercator puts it: screen {tuple(px)} vs {want}")

            # ---- drag a pick in the image ----
            u0, v0 = L[lid]["pick_px"]
            br.eval(f"window.rsPick.zoomImage({u0}, {v0}, 4)")
            a = br.eval(f"window.rsPick.toScreen('image', {u0}, {v0})")
            a = {"x": round(a["x"]), "y": round(a["y"])}  # whole CSS pixels: what an input event carries
            b = {"x": a["x"] + 37, "y": a["y"] - 23}
            drag(br, a, b)
            want_uv = br.eval(f"window.rsPick.toWorld('image', {b['x']}, {b['y']})")
            check(br.wait(f"(l => Math.abs(l.pick_px[0] - {want_uv[0]}) < 1e-5 && Math.abs(l.pick_px[1] - {want_uv[1]}) < 1e-5)"
                          f"(window.rsPick.state.landmarks.find(l => l.id === '{lid}'))"),
                  f"{lid}'s pick dragged to the release point {want_uv}")
            dragged_uv = next(l["pick_px"] for l in br.eval("window.rsPick.state")["landmarks"] if l["id"] == lid)
            print(f"drag: {lid} pick ({u0:.2f}, {v0:.2f}) -> ({dragged_uv[0]:.2f}, {dragged_uv[1]:.2f}) px")
            check(math.hypot(dragged_uv[0] - u0 - 37 / 4, dragged_uv[1] - v0 + 23 / 4) < 0.5,
                  "moved by the drag over the 4x zoom")
            # ---- drag the map pick NEW1 on the map; a surveyed landmark does not move ----
            ne = br.eval("window.rsPick.state.landmarks.find(l => l.id === 'NEW1').enu_m")
            br.eval(f"window.rsPick.zoomMap({ne[0]}, {ne[1]}, 40)")
            a = br.eval(f"window.rsPick.toScreen('map', {ne[0]}, {ne[1]})")
            a = {"x": round(a["x"]), "y": round(a["y"])}
            b = {"x": a["x"] + 60, "y": a["y"] + 20}
            drag(br, a, b)
            want_en = br.eval(f"window.rsPick.toWorld('map', {b['x']}, {b['y']})")
            check(br.wait(f"(l => Math.hypot(l.enu_m[0] - {want_en[0]}, l.enu_m[1] - {want_en[1]}) < 1e-6)"
                          "(window.rsPick.state.landmarks.find(l => l.id === 'NEW1'))"),
                  f"NEW1 dragged on the map to {want_en}")
            sv = br.eval("window.rsPick.state.landmarks.find(l => l.id === 'L009').enu_m")
            br.eval(f"window.rsPick.zoomMap({sv[0]}, {sv[1]}, 40)")
            a = br.eval(f"window.rsPick.toScreen('map', {sv[0]}, {sv[1]})")
            drag(br, a, {"x": a["x"] + 40, "y": a["y"]})
            sv2 = br.eval("window.rsPick.state.landmarks.find(l => l.id === 'L009').enu_m")
            check(sv2 == sv, "a surveyed landmark is not dragged")

            # ---- one landmark gets sigmas of its own (the API the table's sigma cell calls) ----
            req = urllib.request.Request(srv.url + "api/sigma", method="POST",
                                         data=json.dumps({"landmark": "L010", "sigma_h_m": 0.05, "sigma_v_m": 0.08}).encode(),
                                         headers={"Content-Type": "application/json", "Origin": srv.url.rstrip("/")})
            S = json.loads(urllib.request.urlopen(req).read())
            l10 = next(l for l in S["landmarks"] if l["id"] == "L010")
            check(l10["sigma_h_m"] == 0.05 and l10["sigma_stated"], f"L010's own sigma set: {l10}")
            br.eval("window.rsPick.state")  # the page's own state is refreshed by its next post (save)
            # ---- refine focal, chosen on the page ----
            br.eval("(s => { s.value = 'focal'; s.dispatchEvent(new Event('change')); })(document.getElementById('refine'))")
            check(br.wait("window.rsPick.state.refine === 'focal'"), "refine focal chosen on the page")
            # ---- save, then reload in a new server and page ----
            br.eval("document.getElementById('save').click()")
            check(br.wait("window.rsPick.state.unsaved === false"), "saved")
            S = br.eval("window.rsPick.state")
            w = S["solve"].get("warnings") or ""
            check("run with --" not in w, f"no warning names an option pick lacks: {w}")
            rt_page = np.array(S["solve"]["rt_cam_enu"]) if S["solve"]["ok"] else None
            # everything the page asked for came from roadside or the tile server (DevTools' log)
            tile_origin = f"http://127.0.0.1:{ts.port}/"
            away = [u for u in br.requests if not u.startswith((srv.url, tile_origin, "data:", "blob:"))]
            check(br.requests and not away, f"requests beyond roadside and the tile server: {away[:5]}")
            print(f"Leaflet {version}; {len(br.requests)} requests, "
                  f"{sum(u.startswith(tile_origin) for u in br.requests)} to the tile server, none elsewhere")
        finally:
            br.close()
            srv.stop()
        # the page's pose with focal refined is calib's with --refine focal on the saved files
        mrcal, = need("mrcal")
        r = run("calib", site, "--camera", "cam1", "--refine", "focal", "-o", os.path.join(tmp, "calib"))
        if check(r.returncode == 0 and rt_page is not None, f"calib --refine focal on the saved site: {r.stderr}"):
            rt_cli = mrcal.cameramodel(os.path.join(tmp, "calib", "cam1.cameramodel")).extrinsics_rt_fromref()
            d = np.max(np.abs(rt_cli - rt_page))
            print(f"page (refine focal) vs calib --refine focal: rt_cam_enu {d:.2e}")
            check(d < 1e-6, f"rt_cam_enu: page {rt_page} vs calib {rt_cli}: {d:.3e}")
        rows = {r.split(",")[0]: r.strip().split(",") for r in open(os.path.join(site, "observations", "cam1.csv"))}
        check("NEW1" in rows, "the import's new pick in the observations file")
        check(lid in rows and abs(float(rows[lid][1]) - dragged_uv[0]) < 1e-6 and abs(float(rows[lid][2]) - dragged_uv[1]) < 1e-6,
              f"the dragged pick in the observations file: {rows.get(lid)}")
        feats = json.load(open(os.path.join(site, "landmarks.geojson")))["features"]
        new = [f for f in feats if f["properties"]["id"] == "NEW1"]
        if check(len(new) == 1, "NEW1 in landmarks.geojson"):
            lo, la = new[0]["geometry"]["coordinates"][:2]
            x, y = to_en.TransformPoint(lo, la)[:2]
            d = math.hypot(x - want_en[0], y - want_en[1])
            check(d < 0.01, f"NEW1 saved where it was dragged (osr): {d:.4f} m")
        own = {f["properties"]["id"]: (f["properties"].get("sigma_h_m"), f["properties"].get("sigma_v_m"))
               for f in feats if "sigma_h_m" in f["properties"] or "sigma_v_m" in f["properties"]}
        check(own == {"L010": (0.05, 0.08)}, f"only L010, given its own on the page, has sigmas in the file: {own}")
        # the site-wide sigma changed after the save reaches every landmark
        sj["landmark_sigma_m"]["horizontal"] = 0.07
        json.dump(sj, open(os.path.join(site, "site.json"), "w"), indent=1)
        srv = pt.Server(site, "--camera", "cam1", "--ortho", ortho)
        br = pt.Browser(tmp, 1280, 900)
        try:
            br.call("Page.navigate", url=srv.url)
            check(br.wait("window.rsPick && window.rsPick.ready"), "the page did not become ready after the reload")
            S = br.eval("window.rsPick.state")
            L = {l["id"]: l for l in S["landmarks"]}
            check(S["picks"] == len(picks) + 1, f"reloaded: {S['picks']} picks")
            check(abs(L[lid]["pick_px"][0] - dragged_uv[0]) < 1e-6, "reloaded: the dragged pick")
            check("NEW1" in L and math.hypot(L["NEW1"]["enu_m"][0] - want_en[0], L["NEW1"]["enu_m"][1] - want_en[1]) < 0.01,
                  "reloaded: NEW1 where it was dragged")
            sig = sorted({l["sigma_h_m"] for l in S["landmarks"] if l["id"] != "L010"})
            check(sig == [0.07], f"site.json's new sigma_h 0.07 m on every landmark without its own: {sig}")
            check(L["L010"]["sigma_h_m"] == 0.05, f"L010 keeps its own: {L['L010']['sigma_h_m']}")
        finally:
            br.close()
            srv.stop()
            ts.stop()
    finish("pick_basemaps")


def drag(br, a, b, steps=8):
    """Presses at a, moves to b in steps, releases: a drag of the left button."""
    br.call("Input.dispatchMouseEvent", type="mouseMoved", x=a["x"], y=a["y"], button="none")
    br.call("Input.dispatchMouseEvent", type="mousePressed", x=a["x"], y=a["y"], button="left", clickCount=1)
    for k in range(1, steps + 1):
        br.call("Input.dispatchMouseEvent", type="mouseMoved", x=a["x"] + (b["x"] - a["x"]) * k / steps,
                y=a["y"] + (b["y"] - a["y"]) * k / steps, button="left", buttons=1)
    br.call("Input.dispatchMouseEvent", type="mouseReleased", x=b["x"], y=b["y"], button="left", clickCount=1)


if __name__ == "__main__":
    main()

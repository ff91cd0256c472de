#!/usr/bin/env python3
"""roadside pick in a real headless browser (Debian's chromium, DevTools protocol over a pipe) on
the demo site: camera cam1's picks are removed, then made again by clicking pairs on both views --
a landmark on the map, then its pixel in the image (the demo's own picks) -- and one new landmark
clicked on the orthophoto where no landmark is, paired with its pixel through the demo's true
camera (mrcal's projection: the oracle for where it is seen). Checks: residual numbers appear in
the page from the fourth pair on; an extra pick is undone with the 'u' key; 's' saves; then
`roadside calib` on the saved site finds the page's pose to 1e-6 (rt_cam_enu from the
.cameramodel, read by mrcal; position in metres and yaw/pitch/roll in degrees from cam1.json).
Also: the orthophoto's (RGB) edge tile the server sends is GDAL's read of the same window.
The browser's own screenshots go to $ROADSIDE_PICK_SHOTS when it is set (docs/pick.md's)."""
import glob
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rs_check import check, finish, run  # noqa: E402
import rs_pick_test as pt  # noqa: E402

TOL = 1e-6
NPAIRS = 7


def main():
    if not any(os.access(os.path.join(d, "chromium"), os.X_OK) for d in os.environ["PATH"].split(":")):
        print("chromium missing: skipped")
        sys.exit(77)
    import mrcal
    with tempfile.TemporaryDirectory() as tmp:
        site = pt.demo_copy(tmp, empty_camera="cam1")
        picks = [l.strip().split(",") for l in open(os.path.join(pt.SRC, "sites", "demo", "observations", "cam1.csv"))][1:]
        ortho = os.path.join(tmp, "ortho.tif")
        r = run("ortho", site, "-o", ortho, "--gsd", "0.2", "--margin", "5")
        check(r.returncode == 0, f"roadside ortho: {r.stderr}")
        shots = os.environ.get("ROADSIDE_PICK_SHOTS")
        image = []
        if shots:  # docs' screenshots: the camera's digital-twin background, as a user has a frame
            bg = os.path.join(tmp, "demo_bg")
            shutil.copytree(os.path.join(pt.SRC, "sites", "demo"), bg)
            r = run("calib", bg, "-o", os.path.join(tmp, "calib_bg"))
            r = r if r.returncode else run("site", "render-backgrounds", bg, "--calib", os.path.join(tmp, "calib_bg"),
                                           "--camera", "cam1", "--weather", "sunny",
                                           "--times", "2024-06-21T10:00:00+02:00")
            frames = glob.glob(os.path.join(bg, "backgrounds", "cam1", "*.png"))
            check(r.returncode == 0 and frames, f"a twin background for the screenshots: {r.stderr}")
            image = ["--image", frames[0]] if frames else []
        srv = pt.Server(site, "--camera", "cam1", "--ortho", ortho, *image)
        # roadside ortho's file is RGB (3 bands): its level-0 tile is GDAL's read of the window, opaque
        # (test_pick_basemaps checks an RGBA file; a 3-band read once packed 3 bytes a pixel)
        import urllib.request
        from osgeo import gdal
        ds = gdal.Open(ortho)
        tx, ty = (ds.RasterXSize - 1) // 256, (ds.RasterYSize - 1) // 256  # an edge tile: part image, part beyond
        w, h = ds.RasterXSize - 256 * tx, ds.RasterYSize - 256 * ty
        served = np.frombuffer(urllib.request.urlopen(f"{srv.url}api/tiles/0/{tx}/{ty}").read(), np.uint8).reshape(256, 256, 4)
        oracle = ds.ReadAsArray(256 * tx, 256 * ty, w, h).transpose(1, 2, 0)
        check(ds.RasterCount == 3 and np.array_equal(served[:h, :w, :3], oracle) and (served[:h, :w, 3] == 255).all()
              and not served[h:, :, 3].any() and not served[:, w:, 3].any(),
              f"RGB tile 0/{tx}/{ty}: GDAL's read of its {w}x{h} window, opaque, transparent beyond: "
              f"{np.count_nonzero(served[:h, :w, :3] != oracle)} bytes differ")
        ds = None
        br = pt.Browser(tmp, 1280, 860)
        try:
            br.call("Page.navigate", url=srv.url)
            check(br.wait("window.rsPick && window.rsPick.ready"), "the page did not become ready")
            S = br.eval("window.rsPick.state")
            check(S["picks"] == 0 and not S["solve"]["ok"], "expected a camera with no picks")
            enu = {l["id"]: l["enu_m"] for l in S["landmarks"]}
            Nmap = 0
            for k, (lid, u, v, _) in enumerate(picks[:NPAIRS]):
                # on the map when no other landmark is within 1 m (a pole's base and top share their
                # E, N); else in the list
                if min(np.hypot(e[0] - enu[lid][0], e[1] - enu[lid][1]) for i, e in enu.items() if i != lid) > 1:
                    p = br.eval(f"window.rsPick.toScreen('map', {enu[lid][0]}, {enu[lid][1]})")
                    Nmap += 1
                else:
                    p = br.eval(f"(r => ({{x: r.left + 5, y: r.top + r.height / 2}}))"
                                f"(document.querySelector('#landmarks tr[data-id=\"{lid}\"]').getBoundingClientRect())")
                br.click(p["x"], p["y"])
                check(br.wait(f"document.querySelector('#landmarks tr.selected')?.dataset.id === '{lid}'", 5),
                      f"{lid} not selected by its click")
                q = br.wheel_zoom("image", float(u), float(v), 12)  # ~4 screen px per image px
                br.click(q["x"], q["y"])
                check(br.wait(f"window.rsPick.state.picks === {k + 1}"), f"pair {k + 1} ({lid}) not taken")
                br.key("0")  # zoom reset
                if k + 1 >= 4:
                    nres = br.eval("[...document.querySelectorAll('#landmarks td.res')].filter(t => t.textContent).length")
                    # every re-solve is rs_calib_solve's: a pose with a residual per pick, or its
                    # refusal named on the page (cam1's first 4 picks admit a mirrored pose, the
                    # camera below the ground looking up, which the solver refuses by name)
                    solved = br.eval("window.rsPick.state.solve.ok")
                    msg = br.eval("window.rsPick.state.solve.message || ''")
                    check((solved and nres == k + 1) or (not solved and k + 1 < 6 and len(msg) > 20),
                          f"after {k + 1} pairs: solved and {k + 1} residuals shown (shown: {nres}), "
                          f"or the refusal named (message: {msg!r})")
                    if k + 1 == NPAIRS:
                        check(solved, f"after {NPAIRS} pairs: not solved: {msg}")
            check(Nmap >= 4, f"only {Nmap} pairs clicked on the map")
            # the pick landed where clicked, to the sub-pixel (the view is 1 screen px ~ 1.5 image px)
            S = br.eval("window.rsPick.state")
            got = {l["id"]: l["pick_px"] for l in S["landmarks"] if l["pick_px"]}
            worst = max(np.hypot(got[lid][0] - float(u), got[lid][1] - float(v)) for lid, u, v, _ in picks[:NPAIRS])
            check(worst < 0.5, f"picks within 0.5 px of the clicked pixels (zoomed ~4x: clicks land on whole screen pixels): worst {worst:.3f} px")
            print(f"picks: worst {worst:.3f} px from the pixel clicked")
            # a new landmark on the orthophoto, where none is, and its pixel through the true camera
            truth = mrcal.cameramodel(os.path.join(site, "truth", "cam1.cameramodel"))
            picked = np.array([enu[lid][:2] for lid, *_ in picks[:NPAIRS]])
            allen = np.array([l["enu_m"][:2] for l in S["landmarks"]])
            best = None
            for cand in picked.mean(axis=0) + np.array([[dx, dy] for dx in range(-8, 9, 2) for dy in range(-8, 9, 2)]):
                pc = mrcal.transform_point_rt(truth.extrinsics_rt_fromref(), np.array([cand[0], cand[1], 0.0]))
                q = mrcal.project(pc, *truth.intrinsics())
                if pc[2] > 0 and 50 < q[0] < 1870 and 50 < q[1] < 1030 and np.min(np.hypot(*(allen - cand).T)) > 3:
                    best = (cand, q)
                    break
            if check(best is not None, "no free ground point in view for a new landmark"):
                cand, q = best
                p = br.wheel_zoom("map", cand[0], cand[1], 10)  # ~30 screen px per metre
                br.click(p["x"], p["y"])
                s = br.wheel_zoom("image", q[0], q[1], 12)
                br.click(s["x"], s["y"])
                check(br.wait(f"window.rsPick.state.picks === {NPAIRS + 1}"), "the new landmark's pair was not taken")
                br.key("0")
                S = br.eval("window.rsPick.state")
                new = [l for l in S["landmarks"] if l["kind"] == "map-pick"]
                check(len(new) == 1 and abs(new[0]["enu_m"][0] - cand[0]) < 0.1 and abs(new[0]["enu_m"][1] - cand[1]) < 0.1,
                      f"new landmark at the clicked ground point (0.1 m: ~3 screen pixels of the zoomed map): {new}")
            # an extra pick, then undone with the keyboard
            lid, u, v, _ = picks[NPAIRS]
            p = br.eval(f"window.rsPick.toScreen('map', {enu[lid][0]}, {enu[lid][1]})")
            br.click(p["x"], p["y"])
            q = br.eval(f"window.rsPick.toScreen('image', {float(u) + 40}, {float(v)})")
            br.click(q["x"], q["y"])
            n_before = NPAIRS + 2
            check(br.wait(f"window.rsPick.state.picks === {n_before}"), "the extra pick was not taken")
            if shots:
                os.makedirs(shots, exist_ok=True)
                br.screenshot(os.path.join(shots, "pick-residuals.png"), {"x": 0, "y": 0, "width": 1280, "height": 640}, 0.55)
            br.key("u")
            check(br.wait(f"window.rsPick.state.picks === {n_before - 1}"), "'u' did not undo the extra pick")
            br.key("s")
            check(br.wait("window.rsPick.state.unsaved === false"), "'s' did not save")
            S = br.eval("window.rsPick.state")
            if shots:
                br.screenshot(os.path.join(shots, "pick-saved.png"), {"x": 0, "y": 0, "width": 1280, "height": 640}, 0.55)
            check(S["solve"]["ok"], "solved after save")
            rt_page = np.array(S["solve"]["rt_cam_enu"])
            # the saved site through the CLI
            out = os.path.join(tmp, "calib")
            r = run("calib", site, "--camera", "cam1", "-o", out)
            if check(r.returncode == 0, f"roadside calib on the saved site: {r.stdout}{r.stderr}"):
                rt_cli = mrcal.cameramodel(os.path.join(out, "cam1.cameramodel")).extrinsics_rt_fromref()
                j = json.load(open(os.path.join(out, "cam1.json")))
                d_rt = np.max(np.abs(rt_cli - rt_page))
                pos_cli = np.array(j["position_enu_m"]) if "position_enu_m" in j else np.array(j["pose"]["position_enu_m"])
                d_pos = np.max(np.abs(pos_cli - np.array(S["solve"]["position_enu_m"])))
                print(f"page vs calib: rt_cam_enu {d_rt:.2e}, position {d_pos:.2e} m")
                check(d_rt < TOL, f"rt_cam_enu: page {rt_page} vs calib {rt_cli}: {d_rt:.3e} > {TOL}")
                check(d_pos < TOL, f"position: {d_pos:.3e} m > {TOL}")
            check(srv.alive(), "the server died")
        finally:
            br.close()
            srv.stop()
    finish("pick_browser")


if __name__ == "__main__":
    main()

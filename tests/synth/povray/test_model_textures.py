#!/usr/bin/env python3
# Issue 40, "bring your own models": a user model read by assimp renders with its own materials and
# image textures (synth/fleet/rs_synth_fleet_model.c; docs/fleet.md, "User models").
#
# The test writes a box 4 x 2 x 1.5 m as OBJ + MTL + PNG and as glTF 2.0 (.gltf, the same PNG; .glb,
# the PNG embedded),
# each face mapped onto its own patch of the texture: the patch's upper half (towards the face's
# top) white, its lower half a colour of its own. `roadside render` (no background, fixed sun)
# renders it; at the projection (mrcal) of points a quarter and three quarters up each visible
# face, the linear colour pass must show the patch's colour and white in the texture's ratio:
# rendered(colour) / rendered(white) = srgb_decode(colour) / srgb_decode(white) per channel,
# within 0.03 + 10 % (the same face, the same light: the ratio is the texture's albedo ratio
# whatever the light's colour and strength; the tolerance covers bilinear filtering and
# antialiasing-free sampling noise). The wrong orientation of the texture's v axis swaps white
# and colour (ratio > 1): the check fails. An untextured OBJ (no MTL) renders in the vehicle's
# colour (channel ratios of the paint within 25 %: the sky and sun are not quite white). A
# paint_materials entry paints that material instead of its texture. Bad inputs: a missing
# texture image (an error naming the model, the material and the image), a file that is no
# model (assimp's message), paths with spaces.
import os
import shutil
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

from synth_model_util import (COLOURS, WHITE, faces, srgb_decode, texture, write_gltf,  # noqa: E402
                             write_mtl, write_obj)

SEED = 40


def vehicle_to_enu(v, p):
    y = np.radians(v["yaw_deg"])
    f = np.array([np.sin(y), np.cos(y), 0.0])
    l = np.array([-np.cos(y), np.sin(y), 0.0])
    return np.array([v["e"], v["n"], 0.0]) + p[0] * f + p[1] * l + np.array([0, 0, p[2]])


def render(tmp, calib, entry, name):
    veh = os.path.join(tmp, name + ".json")
    u.write_json(veh, [entry])
    out = os.path.join(tmp, "out_" + name)
    u.run(["render", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles", veh, "-o", out,
           "--sun", "150,50"])
    return u.read_png(os.path.join(out, "rgba.png")).astype(float) / 65535, \
        u.read_png(os.path.join(out, "ids.png"))


def check_textured(tag, rgba, ids, v, model):
    import mrcal
    lens, intr = model.intrinsics()
    rt = model.extrinsics_rt_fromref()
    cam_enu = mrcal.invert_rt(rt)[3:]
    tex_lin = [srgb_decode(c) for c in COLOURS]
    white_lin = srgb_decode(WHITE)
    checked = 0
    for k, (o, a, b) in enumerate(faces()):
        n_enu = vehicle_to_enu(v, np.cross(a, b)) - vehicle_to_enu(v, np.zeros(3))
        centre = vehicle_to_enu(v, o + 0.5 * a + 0.5 * b)
        if np.dot(n_enu, cam_enu - centre) <= 0:
            continue  # faces away from the camera
        q = [mrcal.project(mrcal.transform_point_rt(rt, vehicle_to_enu(v, o + 0.5 * a + t * b)), lens, intr)
             for t in (0.25, 0.75)]
        px = [np.round(x).astype(int) for x in q]
        Hh, Ww = ids.shape[:2]
        if any(not (1 <= p[0] < Ww - 1 and 1 <= p[1] < Hh - 1) for p in px) or np.linalg.norm(q[0] - q[1]) < 6:
            continue  # too small or outside the image to sample
        if any(ids[p[1], p[0]] != 1 for p in px):
            u.fail("%s: face %d: sample pixels %s are not the vehicle's" % (tag, k, px))
        colour, white = (rgba[p[1] - 1:p[1] + 2, p[0] - 1:p[0] + 2, :3].reshape(-1, 3).mean(0) for p in px)
        got = colour / np.maximum(white, 1e-6)
        want = tex_lin[k] / white_lin
        err = np.abs(got - want)
        print("%s: face %d at %s: rendered colour/white %s, texture %s" % (tag, k, px[0], np.round(got, 3),
                                                                           np.round(want, 3)))
        if not (np.all(err <= 0.03 + 0.1 * want) and white.min() > 0.01):
            u.fail("%s: face %d: rendered colour/white %s, texture's %s (white %s)" % (tag, k, got, want, white),
                   SEED)
        checked += 1
    if checked < 2:
        u.fail("%s: only %d faces large enough to check" % (tag, checked))
    return checked


def main():
    u.need_povray()
    import cv2
    with tempfile.TemporaryDirectory() as tmp:
        calib, model, Wpx, Hpx, lens, intr = u.small_pinhole(tmp, 480, 300)
        v = u.ground_vehicles(model, 1, SEED, v_range=(0.6, 0.7), u_range=(0.45, 0.55))[0]
        v["yaw_deg"] = 60.0
        folder = os.path.join(tmp, "my models")  # a path with a space
        os.makedirs(folder)
        cv2.imwrite(os.path.join(folder, "box skin.png"), texture()[:, :, ::-1])
        write_obj(os.path.join(folder, "box.obj"), "box.mtl")
        write_mtl(os.path.join(folder, "box.mtl"), "box skin.png")
        write_gltf(os.path.join(folder, "box.gltf"), "box skin.png")
        base = {"e": v["e"], "n": v["n"], "yaw_deg": v["yaw_deg"], "forward": "+x", "up": "+z", "id": "box",
                "length": 4.0}  # the box's own length: the description's scaling path, the same geometry
        n_obj = check_textured("obj", *render(tmp, calib, dict(base, model="my models/box.obj"), "obj"), v, model)
        n_gltf = check_textured("gltf", *render(tmp, calib, dict(base, model="my models/box.gltf"), "gltf"), v,
                                model)
        ok, png = cv2.imencode(".png", texture()[:, :, ::-1])
        write_gltf(os.path.join(folder, "box.glb"), None, png.tobytes())
        n_glb = check_textured("glb", *render(tmp, calib, dict(base, model="my models/box.glb"), "glb"), v,
                               model)
        # untextured: the OBJ without its MTL renders in the vehicle's colour; so does a material
        # named in paint_materials
        paint = [0.5, 0.12, 0.04]
        shutil.copy(os.path.join(folder, "box.obj"), os.path.join(folder, "plain.obj"))
        with open(os.path.join(folder, "plain.obj")) as f:
            text = f.read().replace("mtllib box.mtl\nusemtl Skin\n", "")
        with open(os.path.join(folder, "plain.obj"), "w") as f:
            f.write(text)
        for tag, entry in (("untextured", dict(base, model="my models/plain.obj", colour=paint)),
                           ("paint_materials", dict(base, model="my models/box.obj", colour=paint,
                                                    paint_materials=["Skin"]))):
            rgba, ids = render(tmp, calib, entry, tag)
            m = ids == 1
            if m.sum() < 50:
                u.fail("%s: %d vehicle pixels" % (tag, m.sum()))
            mean = rgba[m][:, :3].mean(0)
            got, want = mean / mean.sum(), np.array(paint) / sum(paint)
            print("%s: vehicle chromaticity %s, paint %s" % (tag, np.round(got, 3), np.round(want, 3)))
            if not np.all(np.abs(got - want) <= 0.25 * want + 0.02):
                u.fail("%s: vehicle chromaticity %s, paint %s" % (tag, got, want))
        # bad inputs: a missing texture names the model, material and image; a non-model file
        write_mtl(os.path.join(folder, "box.mtl"), "gone.png")
        veh = os.path.join(tmp, "bad.json")
        u.write_json(veh, [dict(base, model="my models/box.obj")])
        p = u.run(["render", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles", veh, "-o",
                   os.path.join(tmp, "bad")], expect=1)
        if not all(s in p.stderr for s in ("box.obj", "Skin", "gone.png")):
            u.fail("missing texture: message %r does not name the model, the material and the image" % p.stderr)
        with open(os.path.join(folder, "junk.obj"), "wb") as f:
            f.write(b"\x89PNG\r\n\x1a\n not a model at all\n")
        u.write_json(veh, [dict(base, model="my models/junk.obj")])
        p = u.run(["render", u.DEMO, "--calib", calib, "--camera", "cam1", "--vehicles", veh, "-o",
                   os.path.join(tmp, "bad2")], expect=1)
        if "junk.obj: assimp: " not in p.stderr:
            u.fail("not a model: message %r does not name the file and assimp" % p.stderr)
        print("textured model: %d OBJ faces, %d glTF faces, %d GLB (embedded texture) faces matched their "
              "texture; paint rule and errors ok" % (n_obj, n_gltf, n_glb))


if __name__ == "__main__":
    main()

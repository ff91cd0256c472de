#!/usr/bin/env python3
# Issue 40, "bring your own models": a user model read by assimp renders with its own materials and
# image textures (synth/fleet/rs_synth_fleet_model.c; docs/fleet.md, "User models").
#
# The test writes a box 4 x 2 x 1.5 m as OBJ + MTL + PNG and as glTF 2.0 (.gltf, the same PNG),
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
import base64
import json
import os
import shutil
import struct
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import synth_test_util as u  # noqa: E402

L, W, H = 4.0, 2.0, 1.5
PATCH = 64
COLOURS = [(220, 30, 30), (30, 200, 40), (30, 60, 220), (230, 210, 30), (200, 40, 200), (30, 200, 210)]
WHITE = (240, 240, 240)
SEED = 40


def srgb_decode(c):
    c = np.asarray(c, float) / 255
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def faces():
    """(origin, a, b) per face in the vehicle frame (x forward, y left, z up): the face is
    o + s a + t b, s, t in [0, 1], outward normal a x b, t up the patch."""
    x, y, z = np.eye(3)
    return [(np.array([L / 2, -W / 2, 0]), W * y, H * z),     # front
            (np.array([-L / 2, W / 2, 0]), -W * y, H * z),    # back
            (np.array([L / 2, W / 2, 0]), -L * x, H * z),     # left
            (np.array([-L / 2, -W / 2, 0]), L * x, H * z),    # right
            (np.array([-L / 2, -W / 2, H]), L * x, W * y),    # top
            (np.array([-L / 2, -W / 2, 0]), W * y, L * x)]    # bottom


def texture():
    img = np.zeros((2 * PATCH, 3 * PATCH, 3), np.uint8)
    for k, c in enumerate(COLOURS):
        r, col = divmod(k, 3)
        img[r * PATCH:r * PATCH + PATCH // 2, col * PATCH:(col + 1) * PATCH] = WHITE
        img[r * PATCH + PATCH // 2:(r + 1) * PATCH, col * PATCH:(col + 1) * PATCH] = c
    return img


def uv_of(k, s, t):
    """OpenGL-style (v up the image) texture coordinates of face k's point (s, t), 4 px inset."""
    r, col = divmod(k, 3)
    inset = 4 / PATCH
    s2, t2 = inset + s * (1 - 2 * inset), inset + t * (1 - 2 * inset)
    x_img = (col + s2) * PATCH
    y_img = (r + 1 - t2) * PATCH  # t = 1 at the patch's top row
    return x_img / (3 * PATCH), 1 - y_img / (2 * PATCH)


def write_obj(path, mtl=None, material="Skin"):
    lines = ["# a textured box, written by test_model_textures.py\n"]
    if mtl:
        lines.append("mtllib %s\n" % mtl)
        lines.append("usemtl %s\n" % material)
    for k, (o, a, b) in enumerate(faces()):
        n = np.cross(a, b)
        n /= np.linalg.norm(n)
        for s, t in ((0, 0), (1, 0), (1, 1), (0, 1)):
            p = o + s * a + t * b
            lines.append("v %.6f %.6f %.6f\n" % tuple(p))
            lines.append("vt %.6f %.6f\n" % uv_of(k, s, t))
        lines.append("vn %.6f %.6f %.6f\n" % tuple(n))
    for k in range(6):
        i = 4 * k + 1
        lines.append("f %d/%d/%d %d/%d/%d %d/%d/%d %d/%d/%d\n" % (i, i, k + 1, i + 1, i + 1, k + 1, i + 2, i + 2,
                                                                   k + 1, i + 3, i + 3, k + 1))
    with open(path, "w") as f:
        f.writelines(lines)


def write_mtl(path, tex, material="Skin"):
    with open(path, "w") as f:
        f.write("newmtl %s\nKa 0 0 0\nKd 1 1 1\nKs 0 0 0\nNs 10\nd 1\nmap_Kd %s\n" % (material, tex))


def write_gltf(path, tex):
    pos, nrm, uvs, idx = [], [], [], []
    for k, (o, a, b) in enumerate(faces()):
        n = np.cross(a, b)
        n /= np.linalg.norm(n)
        base = len(pos)
        for s, t in ((0, 0), (1, 0), (1, 1), (0, 1)):
            pos.append(o + s * a + t * b)
            nrm.append(n)
            uu, vv = uv_of(k, s, t)
            uvs.append((uu, 1 - vv))  # glTF: v down the image
        idx += [base, base + 1, base + 2, base, base + 2, base + 3]
    pos, nrm, uvs = (np.array(x, np.float32) for x in (pos, nrm, uvs))
    ind = np.array(idx, np.uint16)
    blob = pos.tobytes() + nrm.tobytes() + uvs.tobytes() + ind.tobytes()
    views, off = [], 0
    for arr in (pos, nrm, uvs, ind):
        views.append({"buffer": 0, "byteOffset": off, "byteLength": arr.nbytes})
        off += arr.nbytes
    g = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
         "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3,
                                     "material": 0}]}],
         "materials": [{"name": "Skin", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
                                                                  "metallicFactor": 0, "roughnessFactor": 1}}],
         "textures": [{"source": 0}], "images": [{"uri": tex}],
         "buffers": [{"byteLength": len(blob),
                      "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
         "bufferViews": views,
         "accessors": [{"bufferView": 0, "componentType": 5126, "count": len(pos), "type": "VEC3",
                        "min": pos.min(0).tolist(), "max": pos.max(0).tolist()},
                       {"bufferView": 1, "componentType": 5126, "count": len(pos), "type": "VEC3"},
                       {"bufferView": 2, "componentType": 5126, "count": len(pos), "type": "VEC2"},
                       {"bufferView": 3, "componentType": 5123, "count": len(ind), "type": "SCALAR"}]}
    with open(path, "w") as f:
        json.dump(g, f)
    assert struct  # (imported for symmetry with .glb writers; unused)


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
        base = {"e": v["e"], "n": v["n"], "yaw_deg": v["yaw_deg"], "forward": "+x", "up": "+z", "id": "box"}
        n_obj = check_textured("obj", *render(tmp, calib, dict(base, model="my models/box.obj"), "obj"), v, model)
        n_gltf = check_textured("gltf", *render(tmp, calib, dict(base, model="my models/box.gltf"), "gltf"), v,
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
        print("textured model: %d OBJ faces, %d glTF faces matched their texture; paint rule and errors ok"
              % (n_obj, n_gltf))


if __name__ == "__main__":
    main()

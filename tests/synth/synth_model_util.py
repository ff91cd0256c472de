# tests/synth/synth_model_util.py -- a textured user model the tests write themselves (issue 40):
# a box 4 x 2 x 1.5 m in the vehicle frame (x forward, y left, z up, metres), each face mapped
# onto its own 64 x 64 patch of a 192 x 128 texture, the patch's upper half white and its lower
# half a colour of its own; as OBJ + MTL and as glTF 2.0 (.gltf with its buffer inline, or .glb
# with the texture embedded).
import base64
import json
import struct

import numpy as np

L, W, H = 4.0, 2.0, 1.5
PATCH = 64
COLOURS = [(220, 30, 30), (30, 200, 40), (30, 60, 220), (230, 210, 30), (200, 40, 200), (30, 200, 210)]
WHITE = (240, 240, 240)
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


def write_gltf(path, tex, png_bytes=None):
    """.gltf with the image `tex` beside it; or, with png_bytes, a binary .glb holding the PNG
    itself (an embedded texture)."""
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
    parts = [pos.tobytes(), nrm.tobytes(), uvs.tobytes(), ind.tobytes()]
    if png_bytes is not None:
        parts.append(png_bytes)
    views, off = [], 0
    for p in parts:
        off += (-off) % 4  # glTF: accessors aligned to 4 bytes
        views.append({"buffer": 0, "byteOffset": off, "byteLength": len(p)})
        off += len(p)
    blob = bytearray(off)
    for p, v in zip(parts, views):
        blob[v["byteOffset"]:v["byteOffset"] + len(p)] = p
    blob = bytes(blob)
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
    if png_bytes is None:
        with open(path, "w") as f:
            json.dump(g, f)
        return
    # GLB: a 12-byte header, the JSON chunk, the BIN chunk (each padded to 4 bytes)
    g["images"] = [{"bufferView": 4, "mimeType": "image/png"}]
    blob += b"\0" * ((-len(blob)) % 4)
    g["buffers"] = [{"byteLength": len(blob)}]
    js = json.dumps(g).encode()
    js += b" " * ((-len(js)) % 4)
    out = struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(js) + 8 + len(blob))
    out += struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(blob), 0x004E4942) + blob
    with open(path, "wb") as f:
        f.write(out)



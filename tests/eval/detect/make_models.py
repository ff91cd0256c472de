#!/usr/bin/env python3
"""Hand-built ONNX detectors whose output is a known function of their input (onnx.helper).

The graph: a Conv whose kernels span the whole input (one output channel per probe, a one-hot
kernel picking input[0, c, y, x] times a scale), Flatten, a Gemm whose one-hot rows add each probe
to one chosen element of the output, a bias holding a fixed `base` output, and a Reshape to the
output's shape:

    output = base + sum over probes of scale * input[0, c, y, x] at flat index i

Every sum is of exact zeros and one product, so the output is exactly float32(base + scale x) and
a test can predict the boxes to the last bit. Used by tests/eval/detect/test_detect.py (oracle),
tests/eval/detect/test_bench_detect.py and the issue's umbrella test.

Layouts (docs/detect.md): YOLOX raw (1, N, 5 + C) and Ultralytics (1, 4 + C, N), N = the anchors
of strides 8, 16, 32 for a W x H input.

Command line (a demo model with a few fixed boxes, for `roadside bench detect`):
    make_models.py yolox|ultralytics OUT.onnx [--size WxH] [--classes C]
"""
import argparse
import sys

import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper

STRIDES = (8, 16, 32)


def anchors(net_w, net_h):
    """The anchors (gx, gy, stride) in output order: strides 8, 16, 32, row-major grids."""
    out = []
    for s in STRIDES:
        for gy in range(net_h // s):
            for gx in range(net_w // s):
                out.append((gx, gy, s))
    return out


def make_model(path, net_w, net_h, base, probes=()):
    """Writes an ONNX model with input "images" (1, 3, net_h, net_w) and output "output" of base's
    shape: base + the probes, each (c, y, x, flat_index, scale). Returns base as float32."""
    base = np.asarray(base, dtype=np.float32)
    probes = list(probes) or [(0, 0, 0, 0, 0.0)]  # the output must depend on the input
    P, M = len(probes), base.size
    kernel = np.zeros((P, 3, net_h, net_w), np.float32)
    gemm_b = np.zeros((M, P), np.float32)  # transB: OpenCV's fully connected layer's layout
    for p, (c, y, x, i, scale) in enumerate(probes):
        kernel[p, c, y, x] = 1.0
        gemm_b[i, p] = scale
    inits = [numpy_helper.from_array(kernel, "kernel"), numpy_helper.from_array(gemm_b, "gemm_b"),
             numpy_helper.from_array(base.reshape(M), "base"),
             numpy_helper.from_array(np.array(base.shape, np.int64), "shape")]
    nodes = [helper.make_node("Conv", ["images", "kernel"], ["picked"], kernel_shape=[net_h, net_w]),
             helper.make_node("Flatten", ["picked"], ["flat"], axis=1),
             helper.make_node("Gemm", ["flat", "gemm_b", "base"], ["sum"], transB=1),
             helper.make_node("Reshape", ["sum", "shape"], ["output"])]
    graph = helper.make_graph(nodes, "roadside_test_detector",
                              [helper.make_tensor_value_info("images", TensorProto.FLOAT, [1, 3, net_h, net_w])],
                              [helper.make_tensor_value_info("output", TensorProto.FLOAT, list(base.shape))], inits)
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 11)], producer_name="roadside tests")
    model.ir_version = 7
    onnx.checker.check_model(model)
    onnx.save(model, path)
    return base


def yolox_base(net_w, net_h, C, rows):
    """A YOLOX raw output (1, N, 5 + C): zeros, with rows {anchor: [o0, o1, o2, o3, obj, cls...]}."""
    N = len(anchors(net_w, net_h))
    base = np.zeros((1, N, 5 + C), np.float32)
    for a, v in rows.items():
        base[0, a, :len(v)] = v
    return base


def ultralytics_base(net_w, net_h, C, rows):
    """An Ultralytics output (1, 4 + C, N): zeros, with columns {anchor: [cx, cy, w, h, scores...]}."""
    N = len(anchors(net_w, net_h))
    base = np.zeros((1, 4 + C, N), np.float32)
    for a, v in rows.items():
        base[0, :len(v), a] = v
    return base


def demo_rows(family, net_w, net_h, C):
    """A few fixed, well-separated boxes for a demo model."""
    rows = {}
    for k, a in enumerate((0, 5, len(anchors(net_w, net_h)) - 1)):
        gx, gy, s = anchors(net_w, net_h)[a]
        if family == "yolox":
            rows[a] = [0.5, 0.5, np.log(2.0), np.log(1.5), 0.9 - 0.1 * k] + [0.9 if c == k % C else 0.1 for c in range(C)]
        else:
            rows[a] = [(gx + 0.5) * s, (gy + 0.5) * s, 2.0 * s, 1.5 * s] + [0.8 - 0.1 * k if c == k % C else 0.05
                                                                          for c in range(C)]
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("family", choices=["yolox", "ultralytics"])
    ap.add_argument("out")
    ap.add_argument("--size", default="640x640")
    ap.add_argument("--classes", type=int, default=3)
    a = ap.parse_args()
    w, h = (int(v) for v in a.size.split("x"))
    rows = demo_rows(a.family, w, h, a.classes)
    base = (yolox_base if a.family == "yolox" else ultralytics_base)(w, h, a.classes, rows)
    make_model(a.out, w, h, base)
    print(f"{a.out}: {a.family}, output {base.shape}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

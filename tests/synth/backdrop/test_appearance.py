# Appearance estimators (synth/backdrop/rs_synth_appearance.h) against known synthetic truths, made here
# with numpy/OpenCV: noise sigma added to a flat image; Gaussian blur of a known sigma on step
# edges; per-channel linear gains; JPEG quality written by OpenCV (libjpeg); and the application
# to a vehicle layer: the layer's blur and noise then match the background's; an ONNX model made
# with python3-onnx run through OpenCV's DNN module.
import os
import subprocess
import sys
import tempfile

import cv2
import numpy as np

SEED = 11
DUMP = sys.argv[1]
ok = True


def dump(*args):
    p = subprocess.run([DUMP] + [str(a) for a in args], capture_output=True, text=True)
    if p.returncode != 0:
        print("FAIL: %s: %s (seed %d)" % (" ".join(map(str, args)), p.stderr, SEED))
        sys.exit(1)
    v = [float(x) for x in p.stdout.split()]
    if not all(np.isfinite(v)):
        print("FAIL: NaN from %s" % " ".join(map(str, args)))
        sys.exit(1)
    return v


def check(name, got, want, tol):
    global ok
    good = abs(got - want) <= tol
    print("%-42s got %10.5f  truth %10.5f  tol %.4f  %s" % (name, got, want, tol,
                                                            "ok" if good else "FAIL"))
    ok = ok and good


def write16(path, rgb01):
    order = [2, 1, 0, 3][:rgb01.shape[2]]  # RGB(A) -> OpenCV's BGR(A)
    cv2.imwrite(path, np.round(np.clip(rgb01, 0, 1) * 65535).astype(np.uint16)[:, :, order])


def srgb_enc(v):
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.power(np.maximum(v, 0), 1 / 2.4) - 0.055)


def main():
    rng = np.random.default_rng(SEED)
    with tempfile.TemporaryDirectory() as tmp:
        f = lambda n: os.path.join(tmp, n)  # noqa: E731
        # noise: flat grey + N(0, sigma), 16-bit so quantisation is negligible
        for sigma in (0.005, 0.02, 0.05):
            img = 0.5 + sigma * rng.standard_normal((240, 320, 3))
            write16(f("n.png"), img)
            check("noise sigma %.3f (flat, 16-bit)" % sigma, dump("noise", f("n.png"))[0], sigma,
                  0.03 * sigma)
        # blur: a checkerboard of 40 px squares, blurred by OpenCV with known sigma, + tiny noise
        yy, xx = np.mgrid[0:240, 0:320]
        board = (((xx // 40) + (yy // 40)) % 2).astype(float) * 0.6 + 0.2
        for sigma in (1.0, 1.5, 2.0, 3.0):
            b = cv2.GaussianBlur(board, (0, 0), sigma)
            write16(f("b.png"), np.dstack([b] * 3) + 0.001 * rng.standard_normal((240, 320, 3)))
            check("blur sigma %.1f px (step edges)" % sigma, dump("blur", f("b.png"))[0], sigma,
                  0.2)
        # gain: a random linear scene and the same with known per-channel gains, 16-bit sRGB
        lin = np.clip(cv2.GaussianBlur(rng.uniform(0.05, 0.6, (240, 320, 3)), (0, 0), 3), 0, 1)
        gains = np.array([1.3, 0.95, 0.7])
        write16(f("ref.png"), srgb_enc(lin))
        write16(f("tgt.png"), srgb_enc(lin * gains))
        g = dump("gain", f("tgt.png"), f("ref.png"))
        for c in range(3):
            check("gain[%d] vs reference (16-bit)" % c, g[c], gains[c], 0.005 * gains[c])
        cv2.imwrite(f("tgt8.png"), np.round(srgb_enc(lin * gains) * 255).astype(np.uint8)[:, :, ::-1])
        cv2.imwrite(f("ref8.png"), np.round(srgb_enc(lin) * 255).astype(np.uint8)[:, :, ::-1])
        g = dump("gain", f("tgt8.png"), f("ref8.png"))
        for c in range(3):
            check("gain[%d] vs reference (8-bit)" % c, g[c], gains[c], 0.005 * gains[c])
        grey = np.full((100, 100, 3), 0.3) * gains
        write16(f("grey.png"), srgb_enc(grey))
        g = dump("gain", f("grey.png"))
        for c in range(3):
            check("grey-world cast[%d]" % c, g[c], gains[c] / gains.mean(), 0.005)
        # JPEG quality: OpenCV's libjpeg at known qualities; PNG reads 0
        scene = (srgb_enc(lin) * 255).astype(np.uint8)
        for q in (30, 50, 75, 90, 97):
            cv2.imwrite(f("j.jpg"), scene, [cv2.IMWRITE_JPEG_QUALITY, q])
            qq, exact = dump("jpeg", f("j.jpg"))
            check("jpeg quality %d (exact match %d)" % (q, exact), qq, q, 0)
            ok_exact = exact == 1
            if not ok_exact:
                print("FAIL: tables not recognised as IJG's")
                sys.exit(1)
        check("png: no jpeg quality", dump("jpeg", f("ref.png"))[0], 0, 0)
        # apply: a sharp RGBA square (vehicle), background blur 2 px, noise 0.02
        layer = np.zeros((200, 200, 4))
        layer[60:140, 50:150, :3] = 0.2
        layer[60:140, 50:150, 3] = 1
        write16(f("layer.png"), layer)
        dump("apply", f("layer.png"), f("out.png"), 1.5, 1.0, 0.5, 0.02, 2.0, 0.0, SEED)
        out = cv2.imread(f("out.png"), cv2.IMREAD_UNCHANGED).astype(float) / 65535
        out = out[:, :, [2, 1, 0, 3]]
        alpha = out[:, :, 3]
        cv2.imwrite(f("alpha.png"), np.round(alpha * 65535).astype(np.uint16))
        check("applied: blur of the alpha edge (px)", dump("blur", f("alpha.png"))[0], 2.0, 0.2)
        inner = out[75:125, 65:135, :3]
        enc = srgb_enc(inner)
        write16(f("inner.png"), enc)
        check("applied: noise in sRGB units", dump("noise", f("inner.png"))[0], 0.02, 0.002)
        for c, gc in enumerate((1.5, 1.0, 0.5)):
            check("applied: mean linear colour[%d]" % c, inner[:, :, c].mean(), 0.2 * gc, 0.004)
        # ONNX translation through OpenCV's DNN: a tiny affine model y = 0.5 x + 0.25 (on the
        # [-1,1] scale) made here with python3-onnx; expected output 0.5 v + 0.375 on [0,1]
        try:
            import onnx
            from onnx import TensorProto, helper
        except ImportError:
            onnx = None
            print("note: python3-onnx missing: the ONNX model path is not tested")
        if onnx is not None:
            Hh, Ww = 32, 48
            x = helper.make_tensor_value_info("x", TensorProto.FLOAT, [1, 3, Hh, Ww])
            y = helper.make_tensor_value_info("y", TensorProto.FLOAT, [1, 3, Hh, Ww])
            a = helper.make_tensor("a", TensorProto.FLOAT, [1], [0.5])
            b = helper.make_tensor("b", TensorProto.FLOAT, [1], [0.25])
            g = helper.make_graph([helper.make_node("Mul", ["x", "a"], ["t"]),
                                   helper.make_node("Add", ["t", "b"], ["y"])],
                                  "affine", [x], [y], [a, b])
            model = helper.make_model(g, opset_imports=[helper.make_opsetid("", 11)])
            model.ir_version = 7
            onnx.checker.check_model(model)
            onnx.save(model, f("affine.onnx"))
            src = rng.uniform(0, 1, (Hh, Ww, 3))
            src[:, :, 0] *= 0.5  # channels differ, so a channel swap would show
            write16(f("in.png"), src)
            dump("onnx", f("affine.onnx"), f("in.png"), f("onnx_out.png"))
            got = cv2.imread(f("onnx_out.png"), cv2.IMREAD_UNCHANGED)[:, :, ::-1] / 65535.0
            want = 0.5 * np.round(src * 65535) / 65535 + 0.375
            check("onnx affine model: max |error|", np.abs(got - want).max(), 0, 2e-5)
    if not ok:
        print("FAIL (seed %d)" % SEED)
        sys.exit(1)
    print("OK")


main()

#!/usr/bin/env python3
"""The rules of the house (docs/architecture.md), checked on the source tree and on the link lines
meson wrote into build.ninja. The table MAY_INCLUDE below is the one in docs/architecture.md; the
test also checks that the two agree.

Usage: test_layout.py SOURCE_ROOT BUILD_ROOT"""
import os
import re
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from rs_check import check, finish  # noqa: E402

MODULES = ["core", "geo", "calib", "sim", "audit", "report", "eval", "synth", "pick", "bench", "cli"]
# module -> the modules whose public headers it may include (besides its own)
MAY_INCLUDE = {
    "core": [],
    "geo": ["core"],
    "calib": ["core", "geo"],
    "sim": ["core", "geo"],
    "audit": ["core", "geo", "calib"],
    "report": ["core", "geo", "calib", "audit"],
    "eval": ["core", "geo"],
    "synth": ["core", "geo"],
    "pick": ["core", "geo", "calib", "audit"],
    "bench": ["core", "geo", "calib", "sim", "eval", "synth", "report"],
    "cli": ["core", "geo", "calib", "sim", "audit", "report", "eval", "synth", "pick", "bench"],
}
# libraries a module's link line must not carry (what it never calls)
MUST_NOT_LINK = {
    "eval": ["ceres", "cairo", "opengv", "opencv_dnn", "opencv_videoio", "expat"],
    "synth": ["ceres", "cairo", "opengv", "spqr", "cholmod"],
    "geo": ["ceres", "cairo", "opengv", "opencv_dnn"],
    "sim": ["ceres", "cairo", "opengv", "opencv_dnn"],
}
# a test executable per module whose link line shows what the module's dependency brings
LINK_PROBE = {"eval": "test_eval_api", "synth": "test_srgb", "geo": "test_geo_api", "sim": "test_simulate_problem"}
MAX_LINES = 800
SIZE_REASON = "Longer than 800 lines because"



def sources(root, module):
    for dp, _, fn in os.walk(os.path.join(root, module)):
        for f in sorted(fn):
            if f.endswith((".c", ".h", ".cc")):
                yield os.path.join(dp, f)


def main():
    root, build = sys.argv[1], sys.argv[2]
    include_re = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
    n_includes = 0
    for module in MODULES:
        for path in sources(root, module):
            rel = os.path.relpath(path, root)
            text = open(path, encoding="utf-8").read()
            for inc in include_re.findall(text):
                n_includes += 1
                parts = inc.split("/")
                check(len(parts) >= 2 and parts[0] in MODULES, f"{rel}: #include \"{inc}\" does not name its module")
                if len(parts) < 2 or parts[0] not in MODULES:
                    continue
                check(os.path.isfile(os.path.join(root, inc)), f"{rel}: #include \"{inc}\": no such file")
                target = parts[0]
                if target != module:
                    check(target in MAY_INCLUDE[module], f"{rel}: {module}/ may not include {target}/ (\"{inc}\")")
                    check("internal" not in parts[1:-1], f"{rel}: includes another module's internal header \"{inc}\"")
            if "<cairo" in text:
                check(module == "report", f"{rel}: includes cairo; the report is the only cairo user")
            lines = text.count("\n")
            if lines > MAX_LINES:
                check(SIZE_REASON in text, f"{rel}: {lines} lines and no stated reason ('{SIZE_REASON} ...')")
            if path.endswith(".cc"):
                check("extern \"C\"" in text and "catch" in text,
                      f"{rel}: a C++ shim must expose C entry points (extern \"C\") and catch at the boundary")
    print(f"{n_includes} includes checked in {len(MODULES)} modules")

    # docs/architecture.md states the same table
    doc = open(os.path.join(root, "docs", "architecture.md"), encoding="utf-8").read()
    for module, allowed in MAY_INCLUDE.items():
        m = re.search(r"^\|\s*`%s/`\s*\|[^|]*\|\s*([^|]*)\|" % module, doc, re.M)
        check(m is not None, f"docs/architecture.md: no row for `{module}/` in the table of rooms")
        if m:
            listed = sorted(re.findall(r"`([a-z]+)`", m.group(1)))
            check(listed == sorted(allowed), f"docs/architecture.md: `{module}/` may include {listed}, the test says {sorted(allowed)}")

    # link lines
    ninja = open(os.path.join(build, "build.ninja"), encoding="utf-8").read()
    for module, exe in LINK_PROBE.items():
        m = re.search(r"^build [^\n]*/%s: \w+_LINKER[^\n]*\n(?: [^\n]*\n)*" % re.escape(exe), ninja, re.M)
        check(m is not None, f"build.ninja: no link rule for {exe}")
        if not m:
            continue
        block = m.group(0)
        for lib in MUST_NOT_LINK[module]:
            check(not re.search(r"[-/]l?%s\b|lib%s[^ ]*\.(so|a)" % (lib, lib), block),
                  f"{module}: {exe} links {lib}, which {module}/ never calls")
        print(f"{module}: {exe} links none of {', '.join(MUST_NOT_LINK[module])}")
    finish("test_layout")


if __name__ == "__main__":
    main()

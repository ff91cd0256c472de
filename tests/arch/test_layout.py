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

LENS_HOME = "core/rs_lens.c"  # the only caller of mrcal_project and mrcal_unproject
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
    "eval": ["ceres", "cairo", "opengv", "opencv_dnn", "opencv_videoio", "expat", "assimp"],
    "synth": ["ceres", "cairo", "opengv", "spqr", "cholmod"],
    "geo": ["ceres", "cairo", "opengv", "opencv_dnn", "assimp"],
    "sim": ["ceres", "cairo", "opengv", "opencv_dnn", "assimp"],
}
# a test executable per module whose link line shows what the module's dependency brings
# synth/ is one library built from component folders (docs/architecture.md, "Inside synth/"):
# component -> the components whose headers it may include (besides its own). Every synth file
# lives in a component folder; a component's internal/ headers stay inside it.
SYNTH_COMPONENTS = {
    "fleet": [],
    "traffic": ["fleet"],
    "labels": ["fleet"],
    "backdrop": ["fleet"],
    "povray": ["fleet", "traffic", "labels", "backdrop"],
    "dataset": ["fleet", "traffic", "labels", "backdrop", "povray"],
}
LINK_PROBE = {"eval": "test_eval_api", "synth": "test_traffic_api", "geo": "test_geo_api", "sim": "test_simulate_problem"}
MAX_LINES = 800
SIZE_REASON = "Longer than 800 lines because"



def sources(root, module):
    for dp, _, fn in os.walk(os.path.join(root, module)):
        for f in sorted(fn):
            if f.endswith((".c", ".h", ".cc")):
                yield os.path.join(dp, f)


# eval/ likewise (docs/architecture.md, "Inside eval/"): its top-level files (the AP) and the
# rollout's component folders; component -> the components it may include besides its own. The
# top-level files may include localise/ (a dataset's recorded calibration).
EVAL_COMPONENTS = {
    "detect": [],
    "localise": [],
    "track": ["localise"],
    "mot": ["localise"],
}
EVAL_TOP_MAY_INCLUDE = ["localise"]


def doc_text(root):
    return open(os.path.join(root, "docs", "architecture.md"), encoding="utf-8").read()


def synth_component(rel):
    """The component of a path under synth/ ("synth/povray/rs_synth_scene.c" -> "povray"), None outside."""
    parts = rel.split("/")
    return parts[1] if len(parts) >= 3 and parts[0] == "synth" else None


def check_synth_components(root, include_re, doc):
    """Each synth file in a component folder; includes only down the order SYNTH_COMPONENTS gives;
    internal headers only within their component; docs/architecture.md's table says the same."""
    n = 0
    for dp, _, fn in os.walk(root):
        if "/.git" in dp or "/build" in dp or "/node_modules" in dp:
            continue
        for f in sorted(fn):
            if not f.endswith((".c", ".h", ".cc")):
                continue
            path = os.path.join(dp, f)
            rel = os.path.relpath(path, root)
            mine = synth_component(rel)
            if rel.startswith("synth/"):
                check(mine in SYNTH_COMPONENTS, f"{rel}: synth/ files live in a component folder ({', '.join(SYNTH_COMPONENTS)})")
            text = open(path, encoding="utf-8", errors="replace").read()
            for inc in include_re.findall(text):
                if not inc.startswith("synth/"):
                    continue
                n += 1
                theirs = synth_component(inc)
                check(theirs in SYNTH_COMPONENTS, f"{rel}: #include \"{inc}\" names no synth component")
                internal = "internal" in inc.split("/")[2:-1]
                if mine is None:
                    # outside synth (cli, bench, tests): public headers only
                    check(not internal, f"{rel}: includes synth's internal header \"{inc}\"")
                    continue
                if theirs == mine or theirs not in SYNTH_COMPONENTS:
                    continue
                check(theirs in SYNTH_COMPONENTS.get(mine, []),
                      f"{rel}: synth/{mine}/ may not include synth/{theirs}/ (\"{inc}\"): the order is {' < '.join(SYNTH_COMPONENTS)}")
                check(not internal, f"{rel}: includes another component's internal header \"{inc}\"")
    # tests/synth mirrors the components: a folder each, the shared helpers alone at its top
    shared = {"meson.build", "synth_test_util.py", "synth_model_util.py", "test_fleet_check.h"}
    tdir = os.path.join(root, "tests", "synth")
    for name in sorted(os.listdir(tdir)):
        if name == "__pycache__":
            continue
        isdir = os.path.isdir(os.path.join(tdir, name))
        check((isdir and name in SYNTH_COMPONENTS) or (not isdir and name in shared),
              f"tests/synth/{name}: synth's tests live in a folder per component ({', '.join(SYNTH_COMPONENTS)})")
    for comp in SYNTH_COMPONENTS:
        check(os.path.isdir(os.path.join(tdir, comp)), f"tests/synth/{comp}/: missing (synth/{comp}/ has no tests folder)")
    for comp, allowed in SYNTH_COMPONENTS.items():
        m = re.search(r"^\|\s*`synth/%s/`\s*\|[^|]*\|\s*([^|]*)\|" % comp, doc, re.M)
        check(m is not None, f"docs/architecture.md: no row for `synth/{comp}/` in the table of synth's components")
        if m:
            listed = sorted(re.findall(r"`([a-z]+)`", m.group(1)))
            check(listed == sorted(allowed), f"docs/architecture.md: `synth/{comp}/` may include {listed}, the test says {sorted(allowed)}")
    print(f"{n} synth includes checked against the component order {' < '.join(SYNTH_COMPONENTS)}")


def check_eval_components(root, include_re, doc):
    """eval's component folders include only what EVAL_COMPONENTS allows (never another's
    internal/ headers, never the top-level AP files); docs/architecture.md's table says the same."""
    n = 0
    for dp, _, fn in os.walk(os.path.join(root, "eval")):
        for f in sorted(fn):
            if not f.endswith((".c", ".h", ".cc")):
                continue
            rel = os.path.relpath(os.path.join(dp, f), root)
            parts = rel.split("/")
            mine = parts[1] if len(parts) >= 3 and parts[1] != "internal" else None  # None: the AP files
            check(mine is None or mine in EVAL_COMPONENTS, f"{rel}: eval/{mine}/ is no component of eval ({', '.join(EVAL_COMPONENTS)})")
            allowed = EVAL_COMPONENTS.get(mine, []) if mine else EVAL_TOP_MAY_INCLUDE
            text = open(os.path.join(root, rel), encoding="utf-8", errors="replace").read()
            for inc in include_re.findall(text):
                if not inc.startswith("eval/"):
                    continue
                n += 1
                ip = inc.split("/")
                theirs = ip[1] if len(ip) >= 3 and ip[1] != "internal" else None
                if theirs == mine:
                    continue
                check(theirs is not None and theirs in allowed,
                      f"{rel}: may not include \"{inc}\" (eval/{mine or ''}{'/' if mine else ''} may include {allowed})")
                check("internal" not in ip[2:-1], f"{rel}: includes another component's internal header \"{inc}\"")
    for comp, allowed in EVAL_COMPONENTS.items():
        check(os.path.isdir(os.path.join(root, "eval", comp)), f"eval/{comp}/: missing")
        m = re.search(r"^\|\s*`eval/%s/`\s*\|[^|]*\|\s*([^|]*)\|" % comp, doc, re.M)
        check(m is not None, f"docs/architecture.md: no row for `eval/{comp}/` in the table of eval's components")
        if m:
            listed = sorted(re.findall(r"`([a-z]+)`", m.group(1)))
            check(listed == sorted(allowed), f"docs/architecture.md: `eval/{comp}/` may include {listed}, the test says {sorted(allowed)}")
    print(f"{n} eval includes checked against its components {', '.join(EVAL_COMPONENTS)}")


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
            # one home for projection: CAHVORE's gradients and unprojection live in core/rs_lens.c
            if re.search(r"\bmrcal_(project|unproject)\s*\(", re.sub(r"//[^\n]*", "", text)):
                check(rel == LENS_HOME, f"{rel}: calls mrcal_project/mrcal_unproject; project through "
                      f"rs_lens_project/rs_lens_unproject ({LENS_HOME}), which add CAHVORE's gradients and unprojection")
            if "<cairo" in text:
                check(module == "report", f"{rel}: includes cairo; the report is the only cairo user")
            lines = text.count("\n")
            if lines > MAX_LINES:
                check(SIZE_REASON in text, f"{rel}: {lines} lines and no stated reason ('{SIZE_REASON} ...')")
            if path.endswith(".cc"):
                check("extern \"C\"" in text and "catch" in text,
                      f"{rel}: a C++ shim must expose C entry points (extern \"C\") and catch at the boundary")
    print(f"{n_includes} includes checked in {len(MODULES)} modules")
    check_synth_components(root, include_re, doc_text(root))
    check_eval_components(root, include_re, doc_text(root))

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

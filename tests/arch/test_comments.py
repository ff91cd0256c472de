#!/usr/bin/env python3
"""Comments stay true (docs/architecture.md; the house style's last rule): a comment that names a
file or a test names one that exists, and a doc comment sits directly above what it documents.

What is read. The comments of the project's C, C++ and header files (// and /* */, outside string
literals), of its Python files (# comments and docstrings), of its meson files and shell scripts
(# comments), in core geo calib sim synth eval audit report pick bench cli tests scripts .ci and
the top meson.build; and the whole text of docs/*.md and README.md.

1. Paths. A path is a token that starts with one of the project's top-level folders and a slash
   (core/ geo/ calib/ sim/ synth/ eval/ audit/ report/ pick/ bench/ cli/ tests/ docs/ scripts/
   sites/ .ci/), made of letters, digits and _ . + - /, with trailing sentence punctuation
   (. , : ;) dropped. It must name an existing file or folder, or, without an extension, the stem
   of a source file (`tests/calib/test_stress_random` names the test test_stress_random.c,
   `geo/rs_site` the pair rs_site.h/.c). Not paths, so not checked:
   - a token glued to what comes before it (a letter, digit, or one of . / $ < > { } ~ @ % + -):
     the folders roadside writes, written in docs as `out/calib/...`, `DATASET/cameras/`,
     `$BUILD/tests/...`, `build/cli/roadside`, are relative to an output folder, not the tree;
   - a template: a token followed directly by `<` `$` or `[` (`tests/<room>/`, `tests/fuzz/corpus/$f`).
   A token followed by `*` is a glob and must match at least one file; a token followed by a brace
   group (`synth/povray/rs_synth_scene.{c,h}`) is expanded and every name must exist.
   A bare file name of the project's own (rs_*, test_*, cmd_*, fuzz_*, bench_* with extension .c,
   .h, .cc or .py) must exist somewhere in the tree (the basename is matched), except the names
   in GENERATED, which the build writes.
2. A function named with its header. A comment that names a function and a header together
   (`NAME (FILE.h)`, `NAME, FILE.h`, `NAME in FILE.h`, `FILE.h's NAME`, `FILE.h: NAME`, backquotes
   allowed) names the header that declares it: NAME appears in the header's code (its comments
   removed). A function that moved to another header leaves such a comment behind.
3. Doc comments. In every header (internal ones too), a function prototype (a declaration at
   column 0 ending in `;`) that follows a blank line sits directly under a comment: mrcal.h's
   rule, every prototype under its own comment (prototypes written one after another under one
   comment are a group and need no comment each). When a comment drifts away from its function
   (another function's prototype put between them, or a blank line), this is what shows it.
   Ownership and defaults helpers (`*_free`, `*_options_default`), named in the comments of the
   types and functions they go with, are exempt.
4. A file's opening line that names a file (`// rs_synth_twin.c -- what it holds`) names itself.

Usage: test_comments.py SOURCE_ROOT"""
import ast
import glob
import io
import os
import re
import sys
import tokenize

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from rs_check import check, finish  # noqa: E402

TOP = ["core", "geo", "calib", "sim", "synth", "eval", "audit", "report", "pick", "bench", "cli", "tests",
       "docs", "scripts", "sites", ".ci"]
CODE_DIRS = ["core", "geo", "calib", "sim", "synth", "eval", "audit", "report", "pick", "bench", "cli", "tests",
             "scripts", ".ci"]
GLUED = r"(?<![\w./$<>{}~@%+-])"
PATH_RE = re.compile(GLUED + r"((?:" + "|".join(re.escape(t) for t in TOP) + r")/[\w.+/-]*)")
BARE_RE = re.compile(GLUED + r"((?:rs|test|cmd|fuzz|bench)_[\w+-]*\.(?:c|h|cc|py))(?![\w/])")
STEM_EXTS = (".c", ".h", ".cc", ".py")
# bare names the build writes (not in the tree), each with where it comes from
GENERATED = {
    "rs_pick_assets.c": "pick/meson.build: custom_target, written by pick/web/embed.py",
}
PAIR_FILE = r"((?:[\w-]+/)*[\w-]+\.h)\b"
PAIR_NAME = r"(rs_[a-z0-9_]+)\b(?![.(/])"
PAIR_RES = [re.compile(PAIR_NAME + r"(?:\(\))?(?:,| in| from| of)? \(?" + PAIR_FILE),
            re.compile(PAIR_FILE + r"(?:'s|:) " + PAIR_NAME)]
PROTO_RE = re.compile(r"^(?!typedef\b|return\b|static\b|extern\b|#|//|/\*|\s)[A-Za-z_][\w\s\*]*?\b([a-z_][a-z0-9_]*)\s*\(")
EXEMPT_RE = re.compile(r"_free$|_options_default$")


C_TOKEN_RE = re.compile(r"//[^\n]*|/\*.*?(?:\*/|\Z)|\"(?:\\.|[^\"\\\n])*\"?|'(?:\\.|[^'\\\n])*'?", re.S)


def c_comments(text):
    """[(line, text)] of the // and /* */ comments of C, C++ or header text (string and character
    literals skipped)."""
    out, line, pos = [], 1, 0
    for m in C_TOKEN_RE.finditer(text):
        if m.group(0)[0] == "/":
            line += text.count("\n", pos, m.start())
            pos = m.start()
            out.append((line, m.group(0)))
    return out


def hash_comments(text):
    """[(line, text)] of the # comments of meson or shell text (quoted strings skipped)."""
    out = []
    for k, line in enumerate(text.split("\n"), 1):
        bare = re.sub(r"'[^']*'|\"[^\"]*\"", lambda m: " " * len(m.group(0)), line)
        m = re.search(r"(?:^|\s)#", bare)
        if m:
            out.append((k, line[m.end() - 1:]))
    return out


def py_comments(text, rel):
    """[(line, text)] of the # comments and the docstrings of Python text."""
    out = []
    for tok in tokenize.generate_tokens(io.StringIO(text).readline):
        if tok.type == tokenize.COMMENT:
            out.append((tok.start[0], tok.string))
    for node in ast.walk(ast.parse(text, rel)):
        if isinstance(node, (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            doc = ast.get_docstring(node, clean=False)
            if doc:
                out.append((node.body[0].lineno, doc))
    return out


def code_of(text):
    """C text with its comments blanked."""
    for _, c in c_comments(text):
        text = text.replace(c, " ")
    return text


def comment_texts(root):
    """[(rel, line, text)]: every comment of the code, every line of the docs."""
    out = []
    files = [os.path.join(root, "meson.build"), os.path.join(root, "meson_options.txt")]
    for d in CODE_DIRS:
        for dp, dn, fn in os.walk(os.path.join(root, d)):
            dn.sort()
            files += [os.path.join(dp, f) for f in sorted(fn)]
    for path in files:
        rel = os.path.relpath(path, root)
        base = os.path.basename(path)
        if not os.path.isfile(path):
            continue
        text = open(path, encoding="utf-8", errors="replace").read()
        if base.endswith((".c", ".h", ".cc")):
            cs = c_comments(text)
        elif base.endswith(".py"):
            cs = py_comments(text, rel)
        elif base in ("meson.build", "meson_options.txt") or ("." not in base and text.startswith("#!")):
            cs = hash_comments(text)
        else:
            continue
        out += [(rel, ln, c) for ln, c in cs]
    docs = [os.path.join("docs", f) for f in sorted(os.listdir(os.path.join(root, "docs"))) if f.endswith(".md")]
    for rel in docs + ["README.md"]:
        for k, line in enumerate(open(os.path.join(root, rel), encoding="utf-8").read().split("\n"), 1):
            out.append((rel, k, line))
    return out


def tree_files(root):
    """{basename: [rel, ...]} of every file in the tree (not build folders, not .git)."""
    out = {}
    for dp, dn, fn in os.walk(root):
        dn[:] = [d for d in dn if d != ".git" and not os.path.isfile(os.path.join(dp, d, "build.ninja"))]
        for f in fn:
            out.setdefault(f, []).append(os.path.relpath(os.path.join(dp, f), root))
    return out


def path_exists(root, tok):
    """True when tok names a file or folder of the tree or, without an extension, a source stem."""
    p = os.path.join(root, tok)
    if tok.endswith("/"):
        return os.path.isdir(p)
    if os.path.exists(p):
        return True
    return "." not in os.path.basename(tok) and any(os.path.isfile(p + e) for e in STEM_EXTS)


def check_paths(root, texts, by_name):
    n = 0
    for rel, ln, c in texts:
        where = f"{rel}:{ln}"
        for m in PATH_RE.finditer(c):
            tok = m.group(1)
            after = c[m.end():m.end() + 1]
            if after and after in "<$[":
                continue  # a template
            n += 1
            if after == "*":
                pat = re.match(r"[\w.+/*-]*", c[m.start():]).group(0).rstrip(".,:;")
                check(glob.glob(os.path.join(root, pat)), f"{where}: `{pat}` matches no file")
                continue
            if after == "{":
                group = re.match(r"\{([\w.,+-]*)\}([\w.+-]*)", c[m.end():])
                if group:
                    for alt in group.group(1).split(","):
                        name = tok + alt + group.group(2)
                        check(os.path.exists(os.path.join(root, name)), f"{where}: `{name}` does not exist")
                    continue
            tok = tok.rstrip(".,:;")
            check(path_exists(root, tok), f"{where}: `{tok}` does not exist")
        for m in BARE_RE.finditer(c):
            n += 1
            name = m.group(1)
            check(name in by_name or name in GENERATED, f"{where}: `{name}`: no file of that name in the tree")
    return n


def joined(texts):
    """texts with the comments and doc lines on consecutive lines of a file joined (a name and
    its header may sit on two lines of one comment)."""
    out = []
    for rel, ln, c in texts:
        if out and out[-1][0] == rel and out[-1][3] + 1 == ln:
            out[-1][2] += "\n" + c
            out[-1][3] = ln + c.count("\n")
        else:
            out.append([rel, ln, c, ln + c.count("\n")])
    return [(rel, ln, c) for rel, ln, c, _ in out]


def check_pairs(root, texts, by_name):
    n = 0
    codes = {}
    for rel, ln0, text in joined(texts):
        # backquotes dropped, every run of white space one blank; lines[k]: the line of c[k]
        chars, lines, line = [], [], ln0
        for ch in text:
            if ch == "`" or (ch.isspace() and chars and chars[-1] == " "):
                line += ch == "\n"
                continue
            chars.append(" " if ch.isspace() else ch)
            lines.append(line)
            line += ch == "\n"
        c = "".join(chars)
        for k, pat in enumerate(PAIR_RES):
            for m in pat.finditer(c):
                name, f = (m.group(1), m.group(2)) if k == 0 else (m.group(2), m.group(1))
                if "/" in f:
                    cands = [f] if os.path.isfile(os.path.join(root, f)) else []
                else:
                    cands = by_name.get(f, [])
                if not cands:
                    continue  # a header that does not exist is check_paths' finding
                n += 1
                for x in cands:
                    if x not in codes:
                        codes[x] = code_of(open(os.path.join(root, x), encoding="utf-8", errors="replace").read())
                found = any(re.search(r"\b%s\b" % re.escape(name), codes[x]) for x in cands)
                check(found, f"{rel}:{lines[m.start()]}: `{name}` is named with {f}, which does not declare it")
    return n


def check_doc_comments(root, by_name):
    n = 0
    for rel in sorted(r for rs in by_name.values() for r in rs if r.endswith(".h")):
        if rel.split("/")[0] not in CODE_DIRS:
            continue
        lines = open(os.path.join(root, rel), encoding="utf-8").read().split("\n")
        for i, line in enumerate(lines):
            m = PROTO_RE.match(line)
            if not m:
                continue
            j = i
            while j < len(lines) and ";" not in lines[j] and "{" not in lines[j]:
                j += 1
            if j == len(lines) or "{" in lines[j].split("//")[0]:
                continue  # a definition (static inline), not a prototype
            n += 1
            name = m.group(1)
            if i == 0 or lines[i - 1].strip() != "" or EXEMPT_RE.search(name):
                continue
            above = [k for k in range(i - 1, -1, -1) if lines[k].strip()]
            drifted = ""
            if above and (lines[above[0]].lstrip().startswith("//") or lines[above[0]].rstrip().endswith("*/")):
                drifted = f" (the comment at line {above[0] + 1}, above a blank line, is it?)"
            check(False, f"{rel}:{i + 1}: {name}: no doc comment directly above the prototype{drifted}")
    return n


def check_opening_lines(root, by_name):
    n = 0
    opening = re.compile(r'^(?://|#|""")\s*([\w./-]+\.(?:c|h|cc|py))\s+--')
    for rel in sorted(r for rs in by_name.values() for r in rs if r.endswith((".c", ".h", ".cc", ".py"))):
        if rel.split("/")[0] not in CODE_DIRS:
            continue
        with open(os.path.join(root, rel), encoding="utf-8", errors="replace") as f:
            head = [f.readline() for _ in range(3)]
        m = next((opening.match(line) for line in head if opening.match(line)), None)
        if m:
            n += 1
            check(os.path.basename(m.group(1)) == os.path.basename(rel), f"{rel}: its opening line names {m.group(1)}")
    return n


def main():
    root = sys.argv[1]
    texts = comment_texts(root)
    by_name = tree_files(root)
    n_paths = check_paths(root, texts, by_name)
    print(f"{n_paths} paths and file names checked in {len(texts)} comments and doc lines")
    n_pairs = check_pairs(root, texts, by_name)
    print(f"{n_pairs} functions named with a header checked")
    n_protos = check_doc_comments(root, by_name)
    print(f"{n_protos} prototypes in headers checked for a doc comment directly above")
    n_open = check_opening_lines(root, by_name)
    print(f"{n_open} opening lines checked to name their own file")
    finish("test_comments")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Issue 41: a report that leads with the action. Modes:

demo -- on a copy of sites/demo calibrated by `roadside calib`: the PDF's first page, rendered to
  PNG by poppler's pdftoppm and read as text by pdftotext -f 1 -l 1, holds one row per camera with
  the verdict of `roadside audit --json` (the oracle) and an action; the first page is not a title
  alone; no page is less than a third full except the last (ink rows of the rendered page between
  the margins, the footer excluded); no `rms_surveyed_px` / `loo_` name in the report's paragraphs
  (tables keep the column names calib and audit print); no paragraph says the sigmas "can be
  trusted" in a section whose warnings say the pose may be wrong because of the intrinsics.
focal -- the synthetic gate camera of sites/import imported with a focal length of 900 px where
  the truth is 1280 px: the first page's action names `roadside calib SITE --refine focal`, not a
  survey, and so does the audit's verdict at the top of the camera's section; recalibrated with --refine focal, the action is gone (the camera passes).
aalborg -- the same on the real Aalborg frame (/work/shared/real/aalborg_roadside; skipped without
  it): imported with the nominal focal length (the image width), its action is --refine focal.
"""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "common"))
import rs_check  # noqa: E402
from rs_check import check, finish, need  # noqa: E402

SOURCE = os.environ["ROADSIDE_SOURCE_ROOT"]
MARGIN_PT, PAGE_H_PT = 42, 841.89


def run(*args):
    return rs_check.run(*args)


def first_page_text(pdf):
    return subprocess.run(["pdftotext", "-layout", "-f", "1", "-l", "1", pdf, "-"], capture_output=True,
                          text=True).stdout


def page_fill(pdf, tmp):
    """The share of each page's body (between the top and bottom margins) down to its last ink row,
    from poppler's rendering at 50 dpi."""
    cv2, np = need("cv2", "numpy")
    prefix = os.path.join(tmp, "page")
    subprocess.run(["pdftoppm", "-r", "50", "-png", pdf, prefix], check=True)
    fills = []
    for name in sorted(f for f in os.listdir(tmp) if f.startswith("page-") and f.endswith(".png")):
        im = cv2.imread(os.path.join(tmp, name), cv2.IMREAD_GRAYSCALE)
        h = im.shape[0]
        body = im[int(h * MARGIN_PT / PAGE_H_PT):int(h * (1 - MARGIN_PT / PAGE_H_PT)), :]
        rows = np.where((body < 200).any(axis=1))[0]
        fills.append((rows.max() + 1) / body.shape[0] if len(rows) else 0.0)
    return fills


def demo():
    tmp, site, calib = rs_check.demo_calibrated("roadside-fp41-")
    p = run("audit", site, "--calib", calib, "-o", os.path.join(tmp, "audit"), "--json")
    audits = {a["camera"]: a for a in json.loads(p.stdout)}
    out = os.path.join(tmp, "r")
    p = run("report", site, "--calib", calib, "-o", out)
    check(p.returncode == 0, f"report: {p.stderr}")
    pdf = os.path.join(out, "report.pdf")
    text = first_page_text(pdf)
    check("In short" in text and "what to do" in text, f"page 1 has no verdict table: {text[:400]}")
    for c, a in sorted(audits.items()):
        row = next((line for line in text.splitlines() if line.split()[:1] == [c]), "")
        want = "pass" if a["pass"] else "FAIL"
        check(row.split()[1:2] == [want], f"page 1: {c}'s row {row!r}, audit says {want}")
        check(len(row.split()) > 4, f"page 1: {c}'s row has no figure or action: {row!r}")
    fills = page_fill(pdf, tmp)
    print("page fill:", " ".join(f"{f:.2f}" for f in fills))
    check(len(fills) >= 2, f"{len(fills)} pages")
    check(fills[0] > 0.5, f"page 1 is {fills[0]:.2f} full (a title alone?)")
    for i, f in enumerate(fills[:-1]):
        check(f >= 1 / 3, f"page {i + 1} is {f:.2f} full (< 1/3; only the last may be)")
    html_text = open(os.path.join(out, "report.html"), encoding="utf-8").read()
    paras = [re.sub(r"<[^>]+>", "", m) for m in re.findall(r"<p[^>]*>(.*?)</p>", html_text, re.S)]
    own = [x for x in paras if not re.match(r"cam\d: (pass|FAIL)\. ", x)]  # the audit's verdict is its text
    for x in own:
        check("rms_surveyed_px" not in x and "loo_" not in x, f"a variable name in prose: {x[:160]}")
    sections = re.split(r"<h2>", html_text)
    for sec in sections:
        if "because of the intrinsics" in sec:
            check("can be trusted" not in sec, "a section says the sigmas can be trusted above 'the pose may be "
                  "wrong because of the intrinsics'")
    shutil.rmtree(tmp)


def action_of(pdf, cam):
    text = first_page_text(pdf)
    lines = text.splitlines()
    i = next((k for k, line in enumerate(lines) if line.split()[:1] == [cam]), None)
    return " ".join(" ".join(line.split()) for line in lines[i:i + 4]) if i is not None else ""


def calib_and_check_action(site, tmp, cam, what):
    """calib without --refine, report: the first page's action for cam is --refine focal, no survey."""
    run("calib", site)
    p = run("report", site, "-o", os.path.join(tmp, "r"))
    check(p.returncode == 0, f"report: {p.stderr}")
    row = action_of(os.path.join(tmp, "r", "report.pdf"), cam)
    print(f"{what}:", row)
    check("--refine focal" in row and "survey" not in row, f"{what}: the action is not --refine focal: {row}")
    text = open(os.path.join(tmp, "r", "report.html"), encoding="utf-8").read()
    check("survey the landmarks more accurately" not in text and text.count("--refine focal") >= 2,
          f"{what}: the camera's verdict words still ask for a survey, or do not name --refine focal")


def focal():
    tmp = tempfile.mkdtemp(prefix="roadside-ff41-")
    site = os.path.join(tmp, "gate")
    intr = os.path.join(tmp, "f900.json")
    with open(intr, "w") as f:
        json.dump({"f": 900, "x0": 639.5, "y0": 479.5}, f)
    p = run("site", "import", site, "--points", os.path.join(SOURCE, "sites", "import", "gate.json"),
            "--image-size", "1280x960", "--intrinsics", intr)
    check(p.returncode == 0, f"site import: {p.stderr}")
    calib_and_check_action(site, tmp, "gate", "focal 30% short")
    check(run("calib", site, "--refine", "focal").returncode == 0, "calib --refine focal")
    run("report", site, "-o", os.path.join(tmp, "r2"))
    row = action_of(os.path.join(tmp, "r2", "report.pdf"), "gate")
    print("refined:", row)
    check("--refine focal" not in row and " pass " in f" {row} ", f"after --refine focal: {row}")
    shutil.rmtree(tmp)


def aalborg():
    real = os.path.join(os.environ.get("ROADSIDE_SHARED", "/work/shared"), "real", "aalborg_roadside")
    if not os.path.isfile(os.path.join(real, "utm.csv")):
        print("skipped: no", real)
        sys.exit(77)
    tmp = tempfile.mkdtemp(prefix="roadside-fa41-")
    utm = [line.split() for line in open(os.path.join(real, "utm.csv")) if line.strip()]
    pix = [line.split() for line in open(os.path.join(real, "pix.csv")) if line.strip()]
    csv = os.path.join(tmp, "aalborg.csv")
    with open(csv, "w") as f:
        f.write("e,n,u,v\n")
        for a, b in zip(utm, pix):
            f.write(",".join(a[0].split(",")[:2] + b[0].split(",")[:2]) + "\n")
    site = os.path.join(tmp, "aal")
    p = run("site", "import", site, "--points", csv, "--crs", "EPSG:25832", "--image", os.path.join(real, "frame.jpg"))
    check(p.returncode == 0, f"site import: {p.stderr}")
    calib_and_check_action(site, tmp, "aalborg", "Aalborg, nominal focal")
    shutil.rmtree(tmp)


if __name__ == "__main__":
    {"demo": demo, "focal": focal, "aalborg": aalborg}[sys.argv[1]]()
    finish("report_first_page_" + sys.argv[1])

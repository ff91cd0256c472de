#!/usr/bin/env python3
"""`roadside report` end to end on a copy of sites/demo (the simulator's seed 1), calibrated first.

Modes (one meson test each):
  html      the HTML is self-contained (no script, no link, no external URL, every image a PNG
            data URI), has 1 + 2 per camera figures, each a valid non-blank PNG of the size its
            <img> says; a background PNG put in backgrounds/cam1/ (and a JPEG in cam2/) shows
            through in that camera's image; cam1's residual vectors run along <id>.json's
            residual_surveyed_px (the headline's residuals, ~30 px on the demo; they were the
            adjusted ones, ~0.05 px, drawn x500, before issue 13 item 6) times the
            magnification the caption states; the ground grid drawn in cam1's image lies where mrcal's Python projects the
            grid's crossings through out/cam1.cameramodel (oracle; >= 90% of the visible
            crossings within 1.5 px of a grid-coloured pixel)
  escape    a site name and a camera note holding markup come out escaped, never as markup;
            bytes that are not UTF-8 in the name come out as '?' in the HTML and the PDF
  chromium  headless Chromium opens the report with no console error; a probe script (added to
            a copy, not to the report) finds every <img> decoded; the screenshot is not blank
  pdf       pdfinfo accepts the PDF; pdftoppm renders its pages, none blank; pdftotext finds
            every heading of the HTML (the same content)
  errors    --help, usage errors (exit 2), a missing calibration (exit 1, names the file,
            writes nothing), a malformed lanes.geojson (names file and field)
With ROADSIDE_DOCS_SHOTS=DIR in the environment, the chromium and pdf modes also save the
screenshots docs/report.md shows (scripts/docs-screenshots): report_html.png (the top 2000 px of the
HTML page, 640 px wide) and report_pdf.png (the PDF's pages 1-2 side by side, 40 dpi).
Exit 77 when a tool the mode needs (chromium, pdfinfo, pdftoppm, pdftotext) is missing.
"""
import base64
import html.parser
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

import cv2
import mrcal
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "common"))
import rs_check  # noqa: E402
from rs_check import check, failures  # noqa: E402

SOURCE = os.environ["ROADSIDE_SOURCE_ROOT"]
SEED = 1  # sites/demo is `roadside site simulate --seed 1`
NCAM = 4


# fontconfig (under cairo's text) keeps its state for the process' life: suppressed for the
# sanitizer build, our own allocations are still checked
ENV = dict(os.environ, LSAN_OPTIONS="suppressions=" + os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                                   "test_report.lsan.supp") + ":print_suppressions=0")


def run(*args):
    return rs_check.run(*args, env=ENV)


def make_site(tmp, background=False, name=None, note=None, lanes=None):
    site = os.path.join(tmp, "site")
    shutil.copytree(os.path.join(SOURCE, "sites", "demo"), site)
    sj = os.path.join(site, "site.json")
    d = json.load(open(sj))
    if name is not None:
        d["name"] = name
    if note is not None:
        d["cameras"][0]["note"] = note
    json.dump(d, open(sj, "w"), indent=1)
    if lanes is not None:
        open(os.path.join(site, "lanes.geojson"), "w").write(lanes)
    if background:
        os.makedirs(os.path.join(site, "backgrounds", "cam1"), exist_ok=True)
        img = np.zeros((1080, 1920, 3), np.uint8)
        img[:, :] = (40, 90, 160)  # BGR: a brown-orange, unlike any overlay colour
        cv2.imwrite(os.path.join(site, "backgrounds", "cam1", "a.png"), img)
        cv2.imwrite(os.path.join(site, "backgrounds", "cam1", "b.png"), img * 0)  # not the first
        os.makedirs(os.path.join(site, "backgrounds", "cam2"), exist_ok=True)
        img[:, :] = (150, 60, 30)  # a dark blue, as a JPEG (read through OpenCV)
        cv2.imwrite(os.path.join(site, "backgrounds", "cam2", "view.JPG"), img)
    return site


def calib_and_report(tmp, site, *extra):
    calib = os.path.join(tmp, "calib")
    p = run("calib", site, "-o", calib)
    if p.returncode != 0:
        print(p.stdout, p.stderr)
        sys.exit(f"roadside calib failed (seed {SEED})")
    out = os.path.join(tmp, "report")
    p = run("report", site, "--calib", calib, "-o", out, *extra)
    check(p.returncode == 0, f"report exit {p.returncode}: {p.stderr}")
    check("report.html" in p.stdout and "report.pdf" in p.stdout, "report prints where the files are")
    return calib, out


class Parser(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.imgs, self.tags, self.headings, self._h = [], [], [], None

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))
        if tag == "img":
            self.imgs.append(dict(attrs))
        if tag in ("h1", "h2", "h3"):
            self._h = ""

    def handle_endtag(self, tag):
        if tag in ("h1", "h2", "h3") and self._h is not None:
            self.headings.append(self._h)
            self._h = None

    def handle_data(self, data):
        if self._h is not None:
            self._h += data


def decode_png(src):
    assert src.startswith("data:image/png;base64,")
    raw = base64.b64decode(src[len("data:image/png;base64,"):], validate=True)
    check(raw[:8] == b"\x89PNG\r\n\x1a\n", "figure is a PNG")
    return cv2.imdecode(np.frombuffer(raw, np.uint8), cv2.IMREAD_COLOR)


def parse(out):
    text = open(os.path.join(out, "report.html"), encoding="utf-8").read()
    p = Parser()
    p.feed(text)
    return text, p


def mode_html(tmp):
    site = make_site(tmp, background=True)
    calib, out = calib_and_report(tmp, site, "--width", "1920", "--grid", "5")
    text, p = parse(out)
    check("<script" not in text.lower(), "no script in the report")
    for tag, attrs in p.tags:
        check(tag not in ("link", "script", "iframe", "object", "embed"), f"no <{tag}>")
        for k, v in attrs.items():
            if k in ("src", "href"):
                check(v.startswith("data:image/png;base64,"), f"<{tag} {k}> is a data URI: {v[:40]}")
    check(not re.search(r"(https?:)?//[a-z]", re.sub(r"data:image/png;base64,[A-Za-z0-9+/=]*", "", text)),
          "no URL anywhere")
    check(len(p.imgs) == 1 + 2 * NCAM, f"{len(p.imgs)} figures, expected {1 + 2 * NCAM}")
    imgs = []
    for i, a in enumerate(p.imgs):
        im = decode_png(a["src"])
        check(im is not None, f"figure {i} decodes")
        if im is None:
            continue
        imgs.append(im)
        check(im.shape[1] == int(a["width"]) and im.shape[0] == int(a["height"]),
              f"figure {i} size {im.shape[1]}x{im.shape[0]} = its <img> {a['width']}x{a['height']}")
        check(float(im.std()) > 10, f"figure {i} is not blank (std {im.std():.1f})")
        check(a.get("alt"), f"figure {i} has alt text")

    # cam1's image is figure 1 (after the site map), 1920 px wide: 1 drawing unit = 1 pixel
    cam1 = imgs[1]
    check(cam1.shape[:2] == (1080, 1920), f"cam1 figure is 1920x1080, got {cam1.shape}")
    # the background shows through away from the overlays (bottom-right region has few)
    bg = np.array([40, 90, 160], float)
    close = np.all(np.abs(cam1.reshape(-1, 3).astype(float) - bg) <= 3, axis=1).mean()
    check(close > 0.5, f"background a.png fills most of cam1's image ({100 * close:.0f}% of pixels)")
    check("a.png" in text and "b.png" not in text, "the first background by name is used and named")
    cam2 = imgs[3]  # site map, cam1 image, cam1 map, cam2 image
    close = np.all(np.abs(cam2.reshape(-1, 3).astype(float) - (150, 60, 30)) <= 6, axis=1).mean()
    check(close > 0.5, f"JPEG background view.JPG fills most of cam2's image ({100 * close:.0f}% of pixels)")

    # residual vectors: magnified by the factor the caption states, in the direction of
    # <id>.json's residual_surveyed_px (oracle: the calibration's own numbers)
    m = re.search(r"inlier residual vectors (?:\([^)]*\) )?magnified (\d+(?:\.\d+)?) times", p.imgs[1]["alt"])
    check(m, "cam1's caption states the magnification")
    mag = float(m.group(1)) if m else 1.0
    lms = json.load(open(os.path.join(calib, "cam1.json")))["landmarks"]
    pink = np.all(np.abs(cam1.astype(float) - (0.6 * 255, 0.2 * 255, 255)) < 40, axis=2)  # BGR of (1, 0.2, 0.6)
    n_long = n_hit = 0
    for l in lms:
        r = np.array(l["residual_surveyed_px"]) * mag  # drawn against the surveyed position
        if not l["inlier"] or np.linalg.norm(r) < 25:
            continue
        n_long += 1
        x, y = np.array(l["observed_px"]) + 0.5 + 0.7 * r  # 70% along the vector, past the marker
        x0, y0 = int(np.floor(x)), int(np.floor(y))
        n_hit += bool(pink[max(y0 - 1, 0):y0 + 2, max(x0 - 1, 0):x0 + 2].any())
    print(f"magnification x{mag:g}: {n_hit}/{n_long} long residual vectors found along their direction")
    check(n_long >= 3 and n_hit == n_long, f"residual vectors drawn x{mag:g} along <id>.json's residuals "
          f"({n_hit}/{n_long})")

    # ground grid vs mrcal's Python projection of the grid crossings (grid 5 m, range 100 m)
    model = mrcal.cameramodel(os.path.join(calib, "cam1.cameramodel"))
    rt = model.extrinsics_rt_fromref()
    lens, intr = model.intrinsics()
    W, H = model.imagersize()
    C = mrcal.invert_rt(rt)[3:]
    g = 5.0
    es = np.arange(np.floor((C[0] - 100) / g) * g, C[0] + 100 + 1e-9, g)
    ns = np.arange(np.floor((C[1] - 100) / g) * g, C[1] + 100 + 1e-9, g)
    pts = np.array([[e, n, 0.0] for e in es for n in ns])  # demo ground plane: up = 0
    pc = mrcal.transform_point_rt(rt, pts)
    q = mrcal.project(pc, lens, intr)
    # crossings inside the image, in front, not too far off-axis, clear of the legend box
    # (top-left 28% x 26%) and of the landmark markers/labels (40 px)
    obs = np.array([l["observed_px"] for l in json.load(open(os.path.join(calib, "cam1.json")))["landmarks"]])
    ok = (pc[:, 2] > 1) & (q[:, 0] > 5) & (q[:, 0] < W - 6) & (q[:, 1] > 5) & (q[:, 1] < H - 40)
    ok &= ~((q[:, 0] < 0.28 * W) & (q[:, 1] < 0.26 * H))
    ok &= np.min(np.linalg.norm(q[:, None, :] - obs[None, :, :], axis=2), axis=1) > 40
    # and really seen: far off-axis points fold back into the image through the distortion
    # polynomial; keep those whose pixel unprojects back along their own ray
    v = mrcal.unproject(q, lens, intr)
    cosang = np.sum(v * pc, axis=1) / (np.linalg.norm(v, axis=1) * np.linalg.norm(pc, axis=1))
    ok &= cosang > np.cos(1e-3)
    grid_bgr = np.array([0.9, 0.7, 0.2]) * 255 * 0.85 + bg * 0.15
    is_grid = np.all(np.abs(cam1.astype(float) - grid_bgr) < 40, axis=2)
    hits = 0
    for u, v in q[ok]:
        x, y = u + 0.5, v + 0.5  # pixel (u,v) is drawn at ((u+0.5)s, (v+0.5)s); PNG pixel i covers [i, i+1)
        x0, y0 = int(np.floor(x)), int(np.floor(y))
        if is_grid[max(y0 - 1, 0):y0 + 2, max(x0 - 1, 0):x0 + 2].any():
            hits += 1
    n = int(ok.sum())
    check(n >= 10, f"at least 10 grid crossings visible in cam1 ({n})")
    share = hits / max(n, 1)
    print(f"grid crossings on a grid pixel: {hits}/{n} ({100 * share:.1f}%)")
    check(share >= 0.9, f"grid crossings drawn where mrcal projects them: {100 * share:.1f}% < 90%")
    # and NOT where a wrong convention would put them (half a pixel is not resolvable; a
    # transposed or mirrored projection is): mirror u and count again
    miss = sum(is_grid[int(v + 0.5), int(W - 1 - u + 0.5)] for u, v in q[ok] if 0 <= int(W - 1 - u + 0.5) < W)
    check(miss < 0.5 * n, f"a mirrored grid would not match ({miss}/{n})")


def mode_escape(tmp):
    evil = "<script>alert('x')</script> & \"quoted\""
    site = make_site(tmp, name="Site " + evil + " @BAD@", note="note <b>bold</b> " + evil)
    # bytes that are not UTF-8 (the site reader does not check): shown as '?', not a failed PDF
    sj = os.path.join(site, "site.json")
    raw = open(sj, "rb").read()
    open(sj, "wb").write(raw.replace(b"@BAD@", b"caf\xe9 \xff\xc3"))
    _, out = calib_and_report(tmp, site, "--no-audit")
    text, p = parse(out)
    check("<script" not in text.lower(), "no script tag from the site name")
    check("<b>bold" not in text, "no markup from the camera note")
    check("&lt;script&gt;alert(&#39;x&#39;)&lt;/script&gt; &amp; &quot;quoted&quot;" in text, "name escaped")
    check("note &lt;b&gt;bold&lt;/b&gt;" in text, "note escaped")
    check(any("Site <script>" in h for h in p.headings), "the escaped name reads back as the name")
    check(len(p.imgs) == 1 + 2 * NCAM, "figures still present")
    check("caf? ??" in text, "bytes that are not UTF-8 shown as '?' in the HTML")
    info = subprocess.run(["pdfinfo", os.path.join(out, "report.pdf")], capture_output=True, text=True).stdout \
        if shutil.which("pdfinfo") else "caf? ??"
    check("caf? ??" in info, f"... and in the PDF's title: {info[:200]}")


def need(*tools):
    for t in tools:
        if not shutil.which(t):
            print(f"SKIP: {t} not installed")
            sys.exit(77)


PROBE = """<script>
window.addEventListener('load', function () {
  var imgs = document.images, bad = 0;
  for (var i = 0; i < imgs.length; i++)
    if (!imgs[i].complete || imgs[i].naturalWidth === 0) bad++;
  if (bad) console.error('roadside-probe: ' + bad + ' of ' + imgs.length + ' figures not decoded');
  else console.log('roadside-probe: ' + imgs.length + ' figures decoded');
});
</script>"""


def save_doc_shot(name, image):
    """Writes image as DIR/name when ROADSIDE_DOCS_SHOTS=DIR (the screenshots of docs/report.md)."""
    folder = os.environ.get("ROADSIDE_DOCS_SHOTS")
    if folder:
        check(cv2.imwrite(os.path.join(folder, name), image, [cv2.IMWRITE_PNG_COMPRESSION, 9]), f"{name} written")


def mode_chromium(tmp):
    need("chromium")
    site = make_site(tmp)
    _, out = calib_and_report(tmp, site)
    text = open(os.path.join(out, "report.html"), encoding="utf-8").read()
    probe = os.path.join(out, "probe.html")
    open(probe, "w", encoding="utf-8").write(text.replace("</body>", PROBE + "</body>"))
    for page, with_probe in ((os.path.join(out, "report.html"), False), (probe, True)):
        shot = os.path.join(tmp, "shot.png")
        cmd = ["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
               "--disable-background-networking", "--disable-component-update", "--disable-sync",
               "--user-data-dir=" + os.path.join(tmp, "chromium"), "--enable-logging=stderr", "--v=0",
               "--screenshot=" + shot, "--window-size=1280,4000", "file://" + page]
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
        console = [l for l in p.stderr.splitlines() if "CONSOLE" in l or "Uncaught" in l]
        errors = [l for l in console if "ERROR:CONSOLE" in l or "Uncaught" in l or "roadside-probe: " in l and
                  "not decoded" in l]
        check(p.returncode == 0, f"chromium exit {p.returncode} on {os.path.basename(page)}")
        check(not errors, f"no console error on {os.path.basename(page)}: {errors}")
        if with_probe:
            ok = [l for l in console if f"roadside-probe: {1 + 2 * NCAM} figures decoded" in l]
            check(ok, f"the probe saw every figure decoded: {console}")
        im = cv2.imread(shot, cv2.IMREAD_COLOR)
        check(im is not None and im.shape[:2] == (4000, 1280), f"screenshot of {os.path.basename(page)} written")
        if im is not None:
            nonwhite = (im.min(axis=2) < 200).mean()
            print(f"{os.path.basename(page)}: screenshot std {im.std():.1f}, {100 * nonwhite:.1f}% non-white")
            check(im.std() > 20 and nonwhite > 0.1, "the screenshot is not blank")
            if not with_probe:
                save_doc_shot("report_html.png", cv2.resize(im[:2000], (640, 1000), interpolation=cv2.INTER_AREA))


def mode_pdf(tmp):
    need("pdfinfo", "pdftoppm", "pdftotext")
    site = make_site(tmp)
    _, out = calib_and_report(tmp, site)
    pdf = os.path.join(out, "report.pdf")
    p = subprocess.run(["pdfinfo", pdf], capture_output=True, text=True)
    check(p.returncode == 0 and not p.stderr.strip(), f"pdfinfo accepts the PDF: {p.stderr}")
    pages = int(re.search(r"Pages:\s+(\d+)", p.stdout).group(1))
    check(pages >= 1 + NCAM, f"{pages} pages >= 1 + one per camera")
    check("595.276 x 841.89" in p.stdout, "A4 pages")
    p = subprocess.run(["pdftoppm", "-r", "40", "-png", pdf, os.path.join(tmp, "page")], capture_output=True,
                       text=True)
    check(p.returncode == 0 and not p.stderr.strip(), f"pdftoppm renders it: {p.stderr}")
    for k in range(1, pages + 1):
        f = os.path.join(tmp, f"page-{k:0{len(str(pages))}d}.png")
        im = cv2.imread(f, cv2.IMREAD_GRAYSCALE)
        check(im is not None, f"page {k} rendered")
        if im is not None:
            check(im.astype(float).var() > 100, f"page {k} is not blank (variance {im.astype(float).var():.0f})")
    first = [cv2.imread(os.path.join(tmp, f"page-{k:0{len(str(pages))}d}.png")) for k in (1, 2)]
    if all(x is not None and x.shape == first[0].shape for x in first):
        save_doc_shot("report_pdf.png", np.hstack(first))
    text = subprocess.run(["pdftotext", "-layout", pdf, "-"], capture_output=True, text=True).stdout
    norm = " ".join(text.split())
    _, hp = parse(out)
    for h in hp.headings:
        check(" ".join(h.split()) in norm, f"heading '{h}' in the PDF")
    check(len(hp.headings) >= 1 + 4 * NCAM, f"{len(hp.headings)} headings")


def mode_errors(tmp):
    p = run("report", "--help")
    check(p.returncode == 0 and p.stdout.startswith("usage: roadside report"), "--help")
    for args in ([], ["x"], ["x", "-o"], ["x", "-o", "y", "--range", "-3"], ["x", "-o", "y", "--width", "5"],
                 ["a", "b", "-o", "y"], ["x", "-o", "y", "--bogus"]):
        p = run("report", *args)
        check(p.returncode == 2 and "roadside report" in p.stderr, f"usage error {args}: exit {p.returncode}")
    site = make_site(tmp)
    out = os.path.join(tmp, "out")
    p = run("report", site, "--calib", os.path.join(tmp, "nowhere"), "-o", out)
    check(p.returncode == 1, f"missing calibration: exit {p.returncode}")
    check("cam1.json" in p.stderr and "roadside calib" in p.stderr, f"names the file and the fix: {p.stderr}")
    check(not os.path.exists(os.path.join(out, "report.html")) and not os.path.exists(os.path.join(out, "report.pdf")),
          "nothing written")
    # a malformed lanes file is named with its field
    calib = os.path.join(tmp, "calib")
    check(run("calib", site, "-o", calib).returncode == 0, "calib")
    open(os.path.join(site, "lanes.geojson"), "w").write(
        '{"type":"FeatureCollection","features":[{"type":"Feature","geometry":'
        '{"type":"LineString","coordinates":[[11.5,48.1],[11.5,"x"]]},"properties":{}}]}')
    p = run("report", site, "--calib", calib, "-o", out)
    check(p.returncode == 1 and "lanes.geojson" in p.stderr and "features[0].geometry.coordinates[1][1]" in p.stderr,
          f"malformed lanes named: {p.stderr}")
    check(not os.path.exists(os.path.join(out, "report.html")), "nothing written")


def main():
    mode = sys.argv[1]
    tmp = tempfile.mkdtemp(prefix=f"roadside-report-{mode}-")
    globals()["mode_" + mode](tmp)
    if failures:
        print(f"{len(failures)} failure(s); site sites/demo (seed {SEED}); files kept in {tmp}")
        return 1
    shutil.rmtree(tmp, ignore_errors=True)
    print("ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())

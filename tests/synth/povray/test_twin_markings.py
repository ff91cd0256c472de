# issue 18 (backgrounds): the digital twin's road markings, kerbs and sidewalks land where the
# site's lanes.geojson says. One real POV-Ray render (`roadside site render-backgrounds`, cloudy:
# no cast shadows) of the demo site through a pinhole camera 50 m above the junction looking
# straight down, 800x800 (0.075 m per pixel on the ground). The oracle reads lanes.geojson with
# json + numpy (WGS84 -> ECEF -> ENU written here, not roadside's GeographicLib), decides each
# lane's role and turning movements itself (a lane entering a "junction" path gets a crosswalk,
# a stop bar and an arrow; one leaving it a crosswalk; a turn of more than 30 degrees between
# the lane's last heading and its junction path's end is left or right) and projects the
# documented positions (docs/backgrounds.md, "What the twin draws") with mrcal:
#   - at every crosswalk stripe centre, every stop bar (3 points across), every arrow stem and
#     every arrow head the lane's movements call for: a marking (brighter than the asphalt
#     median + 60 grey levels);
#   - between crosswalk stripes, between crosswalk and stop bar, beside the arrow stem and where
#     a head is NOT called for (e.g. no right head on a straight-and-left lane): asphalt (less
#     than the asphalt median + 25);
#   - on a grid, points 0.4 m or more outside every lane's outline (centre line +- width/2 +
#     0.5 m shoulder) and the junction paths' hull: sidewalk (median + 20 .. marking - 40), and
#     lane centres 20 m upstream of a lane's end: asphalt.
# Every sample is the pixel nearest to the projected point; the smallest feature sampled is the
# arrow stem, 0.2 m wide (2.7 pixels), so a marking displaced by more than 0.1 m fails.
import json
import os
import shutil
import sys
import tempfile

import cv2
import mrcal
import numpy as np
from matplotlib.path import Path
from scipy.spatial import ConvexHull

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from synth_test_util import DEMO, fail, need_povray, run  # noqa: E402

WGS84_A, WGS84_F = 6378137.0, 1 / 298.257223563
SIZE, HEIGHT_M, GSD = 800, 50.0, 0.075


def ecef(lat, lon, h):
    e2 = WGS84_F * (2 - WGS84_F)
    la, lo = np.radians(lat), np.radians(lon)
    n = WGS84_A / np.sqrt(1 - e2 * np.sin(la) ** 2)
    return np.array([(n + h) * np.cos(la) * np.cos(lo), (n + h) * np.cos(la) * np.sin(lo),
                     (n * (1 - e2) + h) * np.sin(la)])


def enu(o, lon, lat):
    la, lo = np.radians(o["lat"]), np.radians(o["lon"])
    R = np.array([[-np.sin(lo), np.cos(lo), 0],
                  [-np.sin(la) * np.cos(lo), -np.sin(la) * np.sin(lo), np.cos(la)],
                  [np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)]])
    return (R @ (ecef(lat, lon, o["h"]) - ecef(o["lat"], o["lon"], o["h"])))[:2]


class Lane:
    def __init__(self, f, origin):
        p = f["properties"]
        self.id, self.kind, self.w, self.next = p["id"], p.get("kind"), p["width_m"], p.get("next", [])
        self.P = np.array([enu(origin, c[0], c[1]) for c in f["geometry"]["coordinates"]])
        seg = np.diff(self.P, axis=0)
        self.seglen = np.hypot(seg[:, 0], seg[:, 1])
        self.L = self.seglen.sum()

    def frame(self, s):
        """Point, unit forward and unit left at arc length s."""
        s = min(max(s, 0.0), self.L)
        acc = np.concatenate([[0], np.cumsum(self.seglen)])
        i = min(np.searchsorted(acc, s, side="right") - 1, len(self.seglen) - 1)
        d = (self.P[i + 1] - self.P[i]) / self.seglen[i]
        return self.P[i] + d * (s - acc[i]), d, np.array([-d[1], d[0]])

    def at(self, s, v, u=0.0):
        o, fw, lt = self.frame(s)
        return o + fw * u + lt * v

    def dist(self, q):
        a, b = self.P[:-1], self.P[1:]
        d = b - a
        t = np.clip(np.sum((q - a) * d, axis=1) / np.sum(d * d, axis=1), 0, 1)
        return np.min(np.hypot(*(a + d * t[:, None] - q).T))


def heading(d):
    return np.degrees(np.arctan2(d[0], d[1]))


def expectations(site):
    """(points (N,2) ENU, wanted class (N,) 'mark' | 'asphalt' | 'sidewalk', what (N,))."""
    origin = json.load(open(os.path.join(site, "site.json")))["origin"]
    lanes = [Lane(f, origin) for f in json.load(open(os.path.join(site, "lanes.geojson")))["features"]]
    by_id = {l.id: l for l in lanes}
    junction = [l for l in lanes if l.kind == "junction"]
    pts, want, what = [], [], []

    def add(p, w, s):
        pts.append(p)
        want.append(w)
        what.append(s)

    for l in lanes:
        if l.kind == "junction":
            continue
        n = max(1, int(round(l.w / 1.0)))
        per = l.w / n
        stripes = [-l.w / 2 + per * (k + 0.5) for k in range(n)]
        enters = [by_id[j] for j in l.next if by_id[j].kind == "junction"]
        leaves = any(l.id in j.next for j in junction)
        if enters:
            E = l.L  # distances measured back from the lane's end
            for v in stripes:
                add(l.at(E - 2.0, v), "mark", "%s crosswalk stripe v=%+.2f" % (l.id, v))
            for v in stripes[:-1]:
                add(l.at(E - 2.0, v + per / 2), "asphalt", "%s between stripes" % l.id)
            for v in (-1.0, 0.0, 1.0):
                add(l.at(E - 4.9, v), "mark", "%s stop bar v=%+.1f" % (l.id, v))
            add(l.at(E - 4.1, 0), "asphalt", "%s between crosswalk and stop bar" % l.id)
            add(l.at(E - 6.5, 0), "asphalt", "%s before the stop bar" % l.id)
            add(l.at(E - 20.0, 0), "asphalt", "%s lane centre" % l.id)
            # movements from the junction paths' geometry
            h0 = heading(l.frame(l.L)[1])
            turns = set()
            for j in enters:
                dh = (heading(j.frame(j.L)[1]) - h0 + 180) % 360 - 180
                turns.add("straight" if abs(dh) <= 30 else "left" if dh < 0 else "right")
            tail = E - 13.0  # tip 8 m from the end, 5 m long
            add(l.at(tail, 0, 1.0), "mark", "%s arrow stem" % l.id)
            add(l.at(tail, 0.8, 1.0), "asphalt", "%s left of the arrow stem" % l.id)
            add(l.at(tail, -0.8, 1.0), "asphalt", "%s right of the arrow stem" % l.id)
            heads = {"straight": (3.93, 0.0), "left": (2.90, 0.90), "right": (2.90, -0.90)}
            for t, (u, v) in heads.items():
                add(l.at(tail, v, u), "mark" if t in turns else "asphalt",
                    "%s arrow head %s (movements %s)" % (l.id, t, sorted(turns)))
        if leaves:
            for v in stripes:
                add(l.at(2.0, v), "mark", "%s exit crosswalk stripe v=%+.2f" % (l.id, v))
            for v in stripes[:-1]:
                add(l.at(2.0, v + per / 2), "asphalt", "%s exit between stripes" % l.id)
    # sidewalks: grid points clear of every lane outline and the junction hull
    hull_pts = np.vstack([j.P for j in junction])
    hull = Path(hull_pts[ConvexHull(hull_pts).vertices])
    for e in np.arange(-29, 29.1, 2.0):
        for nn in np.arange(-29, 29.1, 2.0):
            q = np.array([e, nn])
            clear = min(l.dist(q) - l.w / 2 - 0.5 for l in lanes)
            if clear >= 0.4 and not hull.contains_point(q, radius=-0.8) and \
                    not hull.contains_point(q, radius=0.8):
                add(q, "sidewalk", "sidewalk at %.0f, %.0f" % (e, nn))
    return np.array(pts), np.array(want), what


def camera(calib_dir):
    """A pinhole camera HEIGHT_M above the site origin looking straight down, image up = north."""
    R0 = np.array([[1.0, 0, 0], [0, -1.0, 0], [0, 0, -1.0]])  # x east, y south, z down
    # tilted 3 degrees about the camera's x axis: a camera looking exactly down is a half-turn,
    # where r_from_R is ill-conditioned
    a = np.radians(3.0)
    R = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]]) @ R0
    if np.max(np.abs(mrcal.R_from_r(mrcal.r_from_R(R)) - R)) > 1e-12:
        fail("r_from_R round trip")
    C = np.array([0, 0, HEIGHT_M])
    f = HEIGHT_M / GSD
    rt = np.concatenate([mrcal.r_from_R(R), -R @ C])
    m = mrcal.cameramodel(intrinsics=("LENSMODEL_PINHOLE",
                                      np.array([f, f, (SIZE - 1) / 2, (SIZE - 1) / 2])),
                          imagersize=(SIZE, SIZE), extrinsics_rt_fromref=rt)
    os.makedirs(calib_dir, exist_ok=True)
    m.write(os.path.join(calib_dir, "cam1.cameramodel"))
    return m


def main():
    need_povray()
    with tempfile.TemporaryDirectory() as tmp:
        site = os.path.join(tmp, "site")
        shutil.copytree(DEMO, site, ignore=shutil.ignore_patterns("truth"))
        model = camera(os.path.join(tmp, "calib"))
        run(["site", "render-backgrounds", site, "--calib", os.path.join(tmp, "calib"),
             "--camera", "cam1", "--times", "2024-06-21T10:00:00Z", "--weather", "cloudy"])
        img = cv2.imread(os.path.join(site, "backgrounds", "cam1", "twin_20240621T1000Z_cloudy.png"),
                         cv2.IMREAD_GRAYSCALE).astype(float)
        P, want, what = expectations(site)
        P3 = np.hstack([P, np.zeros((len(P), 1))])
        q = mrcal.project(mrcal.transform_point_rt(model.extrinsics_rt_fromref(), P3),
                          *model.intrinsics())
        ok = (q[:, 0] > 1) & (q[:, 0] < SIZE - 2) & (q[:, 1] > 1) & (q[:, 1] < SIZE - 2)
        qi = np.round(q).astype(int)
        val = np.full(len(P), np.nan)
        val[ok] = img[qi[ok, 1], qi[ok, 0]]
        asphalt = np.median(val[ok & (want == "asphalt")])
        mark_min = np.min(val[ok & (want == "mark")])
        bad = []
        for k in np.nonzero(ok)[0]:
            v = val[k]
            good = {"mark": v > asphalt + 60, "asphalt": v < asphalt + 25,
                    "sidewalk": asphalt + 20 < v < mark_min - 40}[want[k]]
            if not good:
                bad.append("%s: %s expected at E %.2f N %.2f, pixel (%d, %d) = %.0f" %
                           (what[k], want[k], P[k, 0], P[k, 1], qi[k, 0], qi[k, 1], v))
        counts = {c: int(np.sum(ok & (want == c))) for c in ("mark", "asphalt", "sidewalk")}
        print("asphalt median %.0f, darkest marking sample %.0f; samples in view: %s; %d wrong"
              % (asphalt, mark_min, counts, len(bad)))
        for b in bad[:20]:
            print("  " + b)
        if counts["mark"] < 100 or counts["asphalt"] < 60 or counts["sidewalk"] < 40:
            fail("too few samples in view: %s" % counts)
        if bad:
            fail("%d of %d samples are not what lanes.geojson says" % (len(bad), int(ok.sum())))
    print("OK")


main()

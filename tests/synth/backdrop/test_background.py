# roadside background: the temporal median of a frame sequence with moving "vehicles" over a
# static background recovers the background exactly wherever a pixel is uncovered in more than
# half the frames; site.json records it with its tags and still passes `roadside site check`;
# peak memory does not grow with the number of frames (bounded buffer); a video input works.
import json
import os
import shutil
import subprocess
import sys
import tempfile

import cv2
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from synth_test_util import DEMO, ROADSIDE, fail, run  # noqa: E402

SEED = 7
W, H = 160, 90


def make_frames(folder, n, rng, bg):
    """n frames: bg with 3 rectangles moving across; returns the per-pixel covered count."""
    covered = np.zeros((H, W), int)
    paths = []
    for i in range(n):
        f = bg.copy()
        mask = np.zeros((H, W), bool)
        for k in range(3):
            x = int((i * (4 + 3 * k) + 40 * k) % (W + 30)) - 30
            y = 10 + 25 * k
            mask[y:y + 15, max(x, 0):max(x + 30, 0)] = True
        f[mask] = rng.integers(0, 256, (int(mask.sum()), 3))
        covered += mask
        p = os.path.join(folder, "f%05d.png" % i)
        cv2.imwrite(p, f[:, :, ::-1])
        paths.append(p)
    return paths, covered


def peak_rss_kb(args):
    # under AddressSanitizer, freed frames wait in its quarantine (up to 256 MB): disable it so
    # that the RSS shows the program's own memory (no effect on a plain build)
    env = dict(os.environ)
    env["ASAN_OPTIONS"] = ":".join(filter(None, [env.get("ASAN_OPTIONS"),
                                                 "quarantine_size_mb=0"]))
    p = subprocess.run(["/usr/bin/time", "-f", "RSS %M", ROADSIDE] + args, capture_output=True,
                       text=True, env=env)
    if p.returncode != 0:
        fail("roadside %s: exit %d: %s" % (" ".join(args), p.returncode, p.stderr), SEED)
    return int([l for l in p.stderr.splitlines() if l.startswith("RSS ")][-1].split()[1])


def main():
    rng = np.random.default_rng(SEED)
    bg = rng.integers(0, 256, (H, W, 3)).astype(np.uint8)
    with tempfile.TemporaryDirectory() as tmp:
        site = os.path.join(tmp, "site")
        shutil.copytree(DEMO, site, ignore=shutil.ignore_patterns("truth"))
        frames = os.path.join(tmp, "frames")
        os.makedirs(frames)
        n = 21  # within the default budget of 25: every frame is used
        paths, covered = make_frames(frames, n, rng, bg)
        p = run(["background", site, "--camera", "cam2", "--name", "day1",
                 "--tag", "time=2024-06-21T14:30:00+02:00", "--tag", "conditions=sunny",
                 "--tag", "source=test"] + paths)
        print(p.stdout.strip())
        out = cv2.imread(os.path.join(site, "backgrounds", "cam2", "day1.png"))[:, :, ::-1]
        good = covered * 2 < n
        if good.mean() < 0.5:
            fail("test frames cover too much (%.2f uncovered)" % good.mean(), SEED)
        bad = (out[good] != bg[good]).any(axis=1).sum()
        print("median: %d of %d mostly-uncovered pixels differ from the background (must be 0)"
              % (bad, good.sum()))
        if bad:
            fail("median differs from the background at %d pixels" % bad, SEED)
        s = json.load(open(os.path.join(site, "site.json")))
        cam = [c for c in s["cameras"] if c["id"] == "cam2"][0]
        e = cam["background_images"][0]
        if (e["file"] != "backgrounds/cam2/day1.png" or e["synthetic"] is not False
                or e["tags"] != {"time": "2024-06-21T14:30:00+02:00", "conditions": "sunny",
                                 "source": "test"}
                or e["source"]["frames_used"] != n or cam["backgrounds"] != "backgrounds/cam2"):
            fail("site.json entry: %s" % json.dumps(cam))
        orig = json.load(open(os.path.join(DEMO, "site.json")))
        for c in s["cameras"]:
            c.pop("background_images", None)
            c.pop("backgrounds", None)
        if s != orig:
            fail("site.json changed beyond the backgrounds")
        p = run(["site", "check", site])
        if "0 errors, 0 warnings" not in p.stdout + p.stderr:
            fail("site check warns: %s %s" % (p.stdout, p.stderr))
        # same name again replaces the entry; bad tags are usage errors
        run(["background", site, "--camera", "cam2", "--name", "day1"] + paths[:5])
        s = json.load(open(os.path.join(site, "site.json")))
        cam = [c for c in s["cameras"] if c["id"] == "cam2"][0]
        if len(cam["background_images"]) != 1 or "time" in cam["background_images"][0]["tags"]:
            fail("re-recording did not replace the entry")
        for bad_args in (["--tag", "conditions=foggy"], ["--tag", "time=2024-06-21T14:30"],
                         ["--name", "../x"], ["--tag", "noequals"]):
            run(["background", site, "--camera", "cam2"] + bad_args + paths[:3], expect=2)
        run(["background", site, "--camera", "nope"] + paths[:3], expect=1)
        if os.path.exists(os.path.join(site, "backgrounds", "x.png")):
            fail("a bad name wrote a file")
        # bounded memory: 40 vs 400 frames (larger images so the buffer dominates), budget 9
        big = os.path.join(tmp, "big")
        os.makedirs(big)
        img = rng.integers(0, 256, (480, 720, 3)).astype(np.uint8)
        cv2.imwrite(os.path.join(big, "a.png"), img)
        for i in range(400):
            os.link(os.path.join(big, "a.png"), os.path.join(big, "f%04d.png" % i))
        seq = sorted(os.path.join(big, f) for f in os.listdir(big) if f.startswith("f"))
        r40 = peak_rss_kb(["background", site, "--camera", "cam1", "--name", "m40",
                           "--max-frames", "9"] + seq[:40])
        r400 = peak_rss_kb(["background", site, "--camera", "cam1", "--name", "m400",
                            "--max-frames", "9"] + seq)
        bound_kb = (9 + 3) * 720 * 480 * 3 / 1024
        print("peak RSS: 40 frames %d kB, 400 frames %d kB (buffer bound %.0f kB)"
              % (r40, r400, bound_kb))
        if r400 > r40 * 1.1 + 2048:
            fail("peak RSS grows with the frame count: %d -> %d kB" % (r40, r400))
        # a video (lossless FFV1 when this OpenCV has it): same median as the image sequence
        vid = os.path.join(tmp, "v.avi")
        vw = cv2.VideoWriter(vid, cv2.VideoWriter_fourcc(*"FFV1"), 10, (W, H))
        if vw.isOpened():
            for pth in paths:
                vw.write(cv2.imread(pth))
            vw.release()
            run(["background", site, "--camera", "cam3", "--name", "video", vid])
            outv = cv2.imread(os.path.join(site, "backgrounds", "cam3", "video.png"))[:, :, ::-1]
            badv = (outv[good] != bg[good]).any(axis=1).sum()
            print("video (FFV1): %d pixels differ" % badv)
            if badv:
                fail("video median differs at %d pixels" % badv, SEED)
        else:
            print("note: no FFV1 writer in this OpenCV; video input not tested")
    print("OK")


main()

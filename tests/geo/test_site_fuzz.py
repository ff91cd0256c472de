#!/usr/bin/env python3
# test_site_fuzz.py -- robustness: 60 randomly damaged copies of the fixture (bytes flipped,
# inserted, deleted, files truncated; fixed seed, printed on failure). `roadside site check`
# must never crash (exit 0 or 1, no sanitizer report), every line but the summary must name a
# file of the site, and the summary must count the error and warning lines printed.
import os
import random
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import site_fixture as fx  # noqa: E402

FILES = ["site.json", "landmarks.geojson", "observations/north.csv", "observations/south.csv",
         "cameras/north.cameramodel", "cameras/south.cameramodel"]
TRIALS = 60


def damage(rng, path):
    with open(path, "rb") as f:
        data = bytearray(f.read())
    for _ in range(rng.randint(1, 4)):
        op = rng.choice(["flip", "insert", "delete", "truncate"])
        i = rng.randrange(max(len(data), 1))
        if op == "flip" and data:
            data[i] = rng.choice(b',."[]{}:-0123456789eE\n\r \x00\xff')
        elif op == "insert":
            data[i:i] = bytes(rng.choice(b',"[]{}0.-e\n') for _ in range(rng.randint(1, 3)))
        elif op == "delete":
            del data[i:i + rng.randint(1, 5)]
        else:
            del data[i:]
    with open(path, "wb") as f:
        f.write(bytes(data))


def main():
    rng = random.Random(fx.SEED)
    outcomes = {0: 0, 1: 0}
    for trial in range(TRIALS):
        with fx.TempSite() as site:
            victims = rng.sample(FILES, rng.randint(1, 2))
            for v in victims:
                damage(rng, os.path.join(site, v))
            rc, out, err = fx.run("site", "check", site)
        where = "trial %d (damaged %s)" % (trial, ", ".join(victims))
        if rc not in (0, 1):
            fx.fail("%s: exit status %d" % (where, rc), out, err)
        outcomes[rc] += 1
        lines = out.splitlines()
        m = re.match(r"^(\d+) errors?, (\d+) warnings?$", lines[-1] if lines else "")
        if not m:
            fx.fail("%s: no summary line" % where, out, err)
        body = lines[:-1]
        bad = [l for l in body if not l.startswith("SITE/")]
        if bad:
            fx.fail("%s: lines that name no site file: %s" % (where, bad[:3]), out, err)
        nwarn = sum(1 for l in body if ": warning: " in l)
        if (int(m.group(1)), int(m.group(2))) != (len(body) - nwarn, nwarn) or (rc == 1) != (int(m.group(1)) > 0):
            fx.fail("%s: summary does not match the lines or the exit status" % where, out, err)
    print("fuzz: %d damaged sites, %d rejected, %d accepted, no crash" % (TRIALS, outcomes[1], outcomes[0]))


if __name__ == "__main__":
    main()

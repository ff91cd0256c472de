#!/usr/bin/env python3
"""Issue 42: roadside pick with more than one writer, and under load.

  two_sessions  two servers on one site, one per camera (cam1, cam2), each adding a landmark with
                its pick, then saving -- one after the other, and then both at once: every landmark
                survives with an id of its own, each camera's pick still points at the position its
                session gave (not the other camera's landmark), the site passes `site check`.
                Before: the later save rewrote landmarks.geojson from its stale copy, both sessions
                named their landmark P1, and cam1's pick pointed at cam2's landmark.
  same_camera   two servers on one camera: the second save is refused (409) naming the file that
                changed, and the first session's picks are on disk
  strict_json   the API takes exactly application/json (not application/jsonx) and one JSON object
                with nothing after it
  slow_clients  64 connections opened and left silent (headers never finished), then a normal
                request: answered within 3 s (before: refused until the 64 gave up)
Oracles: Python's json and csv readers (each session's landmark recognised by the pick it carries;
the two landmarks' offset in metres from their lon/lat against the offset they were added at),
`roadside site check`."""
import csv
import json
import os
import socket
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rs_check import check, finish, run  # noqa: E402
import rs_pick_test as pt  # noqa: E402
from test_pick_api import request  # noqa: E402


def add_landmark(port, e, n, u, v):
    st, body = request(port, "POST", "/api/landmark", json.dumps({"e": e, "n": n, "u": u, "v": v}))
    check(st == 200, f"add landmark: {st} {body[:200]!r}")
    state = json.loads(body) if st == 200 else {"landmarks": []}
    # the landmark this session just added: the one picked at (u, v)
    ids = [l["id"] for l in state["landmarks"] if l["pick_px"] and abs(l["pick_px"][0] - u) < 1e-3
           and abs(l["pick_px"][1] - v) < 1e-3]
    return ids[0] if ids else None


def on_disk(site):
    """{id: ENU-free fingerprint (lon, lat)} of landmarks.geojson and {camera: {id: (u, v)}}."""
    fc = json.load(open(os.path.join(site, "landmarks.geojson")))
    ids = [f["properties"]["id"] for f in fc["features"]]
    pos = {f["properties"]["id"]: tuple(f["geometry"]["coordinates"][:2]) for f in fc["features"]}
    picks = {}
    for cam in ("cam1", "cam2"):
        rows = list(csv.DictReader(open(os.path.join(site, "observations", cam + ".csv"))))
        picks[cam] = {r["landmark"]: (float(r["u"]), float(r["v"])) for r in rows}
    return ids, pos, picks


def site_ok(site, what):
    p = run("site", "check", site)
    check(p.returncode == 0 and p.stdout.splitlines()[-1].startswith("0 errors"), f"{what}: site check exit {p.returncode}: {p.stdout[-300:]!r}")


def two_sessions(tmp, cam_a, cam_b):
    """A demo copy and two servers on it, each with a landmark added (12 m, 2 m apart) and picked."""
    site = pt.demo_copy(tmp)
    a = pt.Server(site, "--camera", cam_a)
    b = pt.Server(site, "--camera", cam_b)
    ida = add_landmark(a.port, 5.0, 6.0, 700.5, 800.25)
    idb = add_landmark(b.port, -7.0, 4.0, 300.75, 650.5)
    return site, a, b, ida, idb


def mode_two_sessions(tmp):
    site, a, b, ida, idb = two_sessions(tmp, "cam1", "cam2")
    n0 = len(on_disk(site)[0])
    try:
        # one after the other: A saves, then B (which read the site before A's save)
        print(f"session ids: cam1 {ida}, cam2 {idb}")
        st, body = request(a.port, "POST", "/api/save", "{}")
        check(st == 200, f"cam1 save: {st} {body[:300]!r}")
        st, body = request(b.port, "POST", "/api/save", "{}")
        check(st == 200, f"cam2 save (merged): {st} {body[:300]!r}")
        ids, pos, picks = on_disk(site)
        check(len(ids) == n0 + 2 and len(set(ids)) == len(ids), f"landmarks on disk: {len(ids)} (want {n0 + 2}), "
              f"unique {len(set(ids))}")
        pa = [k for k, uv in picks["cam1"].items() if abs(uv[0] - 700.5) < 1e-3 and abs(uv[1] - 800.25) < 1e-3]
        pb = [k for k, uv in picks["cam2"].items() if abs(uv[0] - 300.75) < 1e-3 and abs(uv[1] - 650.5) < 1e-3]
        check(len(pa) == 1 and len(pb) == 1 and pa[0] != pb[0] and pa[0] in pos and pb[0] in pos,
              f"each camera's new pick names its own landmark: cam1 {pa}, cam2 {pb}")
        if len(pa) == 1 and len(pb) == 1 and pa[0] in pos and pb[0] in pos:
            # A's landmark is 12 m east of B's: the picks point at landmarks that far apart
            (lo_a, la_a), (lo_b, la_b) = pos[pa[0]], pos[pb[0]]
            de = (lo_a - lo_b) * 111319.5 * 0.6677  # cos(48.137 deg)
            dn = (la_a - la_b) * 111195.0
            check(abs(de - 12.0) < 0.05 and abs(dn - 2.0) < 0.05,
                  f"cam1's landmark minus cam2's: ({de:.3f}, {dn:.3f}) m, want (12, 2)")
        site_ok(site, "after two sessions saved")

        # both at once, twice: each save either succeeds or is refused with a clear message (the
        # other holds the site); a refused one saved again; then every landmark is on disk
        for round in range(2):
            add_landmark(a.port, 10.0 + round, -3.0, 500.5 + round, 400.5)
            add_landmark(b.port, -10.0 - round, -3.0, 900.5 + round, 500.5)
            out = {}
            def save(name, port):
                out[name] = request(port, "POST", "/api/save", "{}")
            ts = [threading.Thread(target=save, args=(nm, s.port)) for nm, s in (("a", a), ("b", b))]
            for t in ts:
                t.start()
            for t in ts:
                t.join()
            for name, srv in (("a", a), ("b", b)):
                st, body = out[name]
                check(st == 200 or (st == 409 and b" is in use by " in body),
                      f"simultaneous save {name}: {st} {body[:300]!r}")
                if st != 200:
                    print(f"simultaneous save {name} refused as expected: {body[:160]!r}")
                    st, body = request(srv.port, "POST", "/api/save", "{}")
                    check(st == 200, f"save {name} again: {st} {body[:300]!r}")
        ids, pos, picks = on_disk(site)
        check(len(ids) == n0 + 6 and len(set(ids)) == len(ids), f"after the simultaneous saves: {len(ids)} "
              f"landmarks (want {n0 + 6}), {len(set(ids))} unique")
        for cam, uv in (("cam1", (500.5, 400.5)), ("cam1", (501.5, 400.5)), ("cam2", (900.5, 500.5)),
                        ("cam2", (901.5, 500.5))):
            check(any(abs(p[0] - uv[0]) < 1e-3 and abs(p[1] - uv[1]) < 1e-3 for p in picks[cam].values()),
                  f"{cam}'s pick at {uv} is on disk")
        site_ok(site, "after the simultaneous saves")
    finally:
        a.stop()
        b.stop()


def mode_same_camera(tmp):
    site, a, b, _, _ = two_sessions(tmp, "cam1", "cam1")
    try:
        st, body = request(a.port, "POST", "/api/save", "{}")
        check(st == 200, f"first save: {st} {body[:200]!r}")
        before = open(os.path.join(site, "observations", "cam1.csv")).read()
        st, body = request(b.port, "POST", "/api/save", "{}")
        check(st == 409 and b"cam1.csv changed on disk" in body, f"second save on cam1: {st} {body[:300]!r}")
        print("second session's save refused:", body[:200])
        check(open(os.path.join(site, "observations", "cam1.csv")).read() == before,
              "the refused save left cam1.csv as the first session saved it")
        site_ok(site, "after the refused save")
    finally:
        a.stop()
        b.stop()


def mode_strict_json(tmp):
    site = pt.demo_copy(tmp)
    srv = pt.Server(site, "--camera", "cam1")
    try:
        port = srv.port
        for ct, want in (("application/json", 404), ("application/json; charset=utf-8", 404),
                         ("Application/JSON", 404), ("application/jsonx", 415), ("application/json-seq", 415),
                         ("text/plain", 415)):
            st, body = request(port, "POST", "/api/undo", "{}", headers={"Content-Type": ct})
            check(st == want, f"Content-Type {ct!r}: {st} (want {want}) {body[:120]!r}")
        for body, want in ((b"{} ", 404), (b"{}\r\n", 404), (b"{}x", 400), (b"{}{}", 400), (b"{} []", 400),
                           (b"{}\x00", 400)):
            st, text = request(port, "POST", "/api/undo", body)
            check(st == want, f"body {body!r}: {st} (want {want}) {text[:120]!r}")
        st, text = request(port, "POST", "/api/pick", b'{"landmark": "L008", "u": 100, "v": 200} trailing')
        check(st == 400 and b"unexpected text after" in text, f"a pick with trailing text: {st} {text[:120]!r}")
    finally:
        srv.stop()


def mode_slow_clients(tmp):
    site = pt.demo_copy(tmp)
    srv = pt.Server(site, "--camera", "cam1")
    socks = []
    try:
        port = srv.port
        for k in range(64):
            s = socket.create_connection(("127.0.0.1", port), timeout=10)
            s.sendall(b"GET /api/state HTTP/1.1\r\nHost: 127.0.0.1:%d\r\n" % port)  # never finished
            socks.append(s)
        time.sleep(0.5)
        t0 = time.time()
        try:
            st, body = request(port, "GET", "/api/state", timeout=10)
        except OSError as e:
            st, body = None, str(e).encode()
        dt = time.time() - t0
        print(f"with 64 silent connections open: /api/state answered {st} in {dt:.2f} s")
        check(st == 200 and dt < 3.0, f"a normal request with 64 slow connections open: {st} after {dt:.2f} s "
              f"{body[:120]!r}")
        check(srv.alive(), "the server is still running")
    finally:
        for s in socks:
            s.close()
        srv.stop()


if __name__ == "__main__":
    mode = sys.argv[1]
    with tempfile.TemporaryDirectory() as tmp:
        {"two_sessions": mode_two_sessions, "same_camera": mode_same_camera, "strict_json": mode_strict_json,
         "slow_clients": mode_slow_clients}[mode](tmp)
    finish("test_pick_concurrent " + mode)

#!/usr/bin/env python3
"""roadside pick's server without a browser (http.client and raw sockets): what it refuses and
what it survives.

  origin_host   a foreign Host (DNS rebinding) is refused with 403 on GET and POST; a POST from
                another Origin, or with none, is refused with 403; the page's own Origin passes
  no_paths      no request names a file: paths in URLs and bodies ("../", absolute, a file field)
                are 404 or 400 and nothing outside the site changes (a sentinel file is untouched)
  fuzz          500 malformed requests (random bytes, truncated and huge bodies, bad JSON, wrong
                types, NaN, unknown endpoints) with a fixed seed: each answered 4xx or the
                connection closed, never 5xx; the server still answers /api/state afterwards
  save_kill     a save in a loop from a client while the server is killed with SIGKILL at random
                times (fixed seed): after each kill landmarks.geojson and observations/cam1.csv
                parse and are each either the old file or a new one the server wrote (never a
                mix); the site still loads (`roadside site check`)
Oracle: the HTTP status codes RFC 9110 defines, Python's json and csv readers, roadside site check.
"""
import csv
import hashlib
import http.client
import json
import os
import random
import signal
import socket
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rs_check import check, finish, run  # noqa: E402
import rs_pick_test as pt  # noqa: E402

SEED = 15


def request(port, method, path, body=None, headers=None, timeout=10):
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=timeout)
    h = {"Host": f"127.0.0.1:{port}"}
    if method == "POST":
        h.update({"Origin": f"http://127.0.0.1:{port}", "Content-Type": "application/json"})
    h.update(headers or {})
    h = {k: v for k, v in h.items() if v is not None}
    c.request(method, path, body=body, headers=h)
    r = c.getresponse()
    data = r.read()
    c.close()
    return r.status, data


def mode_origin_host(tmp):
    site = pt.demo_copy(tmp)
    srv = pt.Server(site, "--camera", "cam1")
    try:
        port = srv.port
        st, _ = request(port, "GET", "/api/state")
        check(st == 200, f"own Host: GET /api/state {st}")
        st, _ = request(port, "GET", "/", headers={"Host": "localhost:%d" % port})
        check(st == 200, f"Host localhost: GET / {st}")
        for host in ("evil.example", f"evil.example:{port}", "127.0.0.1", f"127.0.0.1:{port + 1}", ""):
            st, _ = request(port, "GET", "/api/state", headers={"Host": host})
            check(st in (400, 403), f"Host '{host}': GET answered {st}, expected 403")
            st, _ = request(port, "POST", "/api/undo", body="{}", headers={"Host": host})
            check(st in (400, 403), f"Host '{host}': POST answered {st}, expected 403")
        for origin in ("http://evil.example", f"http://127.0.0.1:{port + 1}", "null", None,
                       f"https://127.0.0.1:{port}"):
            st, _ = request(port, "POST", "/api/save", body="{}", headers={"Origin": origin})
            check(st == 403, f"Origin {origin}: POST /api/save answered {st}, expected 403")
        st, _ = request(port, "GET", "/api/state", headers={"Origin": "http://evil.example"})
        check(st == 403, f"a GET from another Origin answered {st}, expected 403")
        st, body = request(port, "POST", "/api/undo", body="{}")
        check(st == 404 and b"nothing to undo" in body, f"own Origin: POST /api/undo {st} {body[:80]}")
        st, _ = request(port, "POST", "/api/undo", body="{}", headers={"Content-Type": "text/plain"})
        check(st == 415, f"a text/plain POST (a form's) answered {st}, expected 415")
    finally:
        srv.stop()


def mode_no_paths(tmp):
    site = pt.demo_copy(tmp)
    sentinel = os.path.join(tmp, "sentinel.txt")
    open(sentinel, "w").write("untouched\n")
    before = {f: hashlib.sha256(open(os.path.join(dp, f), "rb").read()).hexdigest()
              for dp, _, fs in os.walk(site) for f in fs}
    srv = pt.Server(site, "--camera", "cam1")
    try:
        port = srv.port
        for path in ("/../sentinel.txt", "/..%2fsentinel.txt", "//etc/passwd", "/etc/passwd",
                     "/api/../../sentinel.txt", "/landmarks.geojson", "/site.json", "/api/state/../../x"):
            st, body = request(port, "GET", path)
            check(st == 404 and b"untouched" not in body and b"root:" not in body, f"GET {path}: {st}")
        for body in ({"path": sentinel}, {"file": "../sentinel.txt"}, {"out": "/tmp/x", "landmark": "L008"},
                     {"landmark": "../../sentinel.txt", "u": 1, "v": 1}):
            st, _ = request(port, "POST", "/api/save" if "landmark" not in body else "/api/pick", body=json.dumps(body))
            check(st in (200, 400, 404), f"POST {body}: {st}")
        check(open(sentinel).read() == "untouched\n", "the sentinel file outside the site changed")
        check(sorted(os.listdir(tmp)) == ["demo", "sentinel.txt"], f"files appeared next to the site: {os.listdir(tmp)}")
        after = {f for dp, _, fs in os.walk(site) for f in fs}
        check(after == set(before), f"the site's file names changed: {sorted(after ^ set(before))}")
    finally:
        srv.stop()


def raw(port, data, timeout=5):
    """Sends raw bytes; returns the status code answered, or None when the connection closed."""
    s = socket.create_connection(("127.0.0.1", port), timeout=timeout)
    got = b""
    try:
        s.sendall(data)
        s.shutdown(socket.SHUT_WR)
        got = b""
        while True:
            try:
                chunk = s.recv(65536)
            except (ConnectionResetError, socket.timeout):
                break
            if not chunk:
                break
            got += chunk
    except OSError:  # the server closed first (a huge body refused): an answer may have come
        try:
            got = s.recv(65536)
        except OSError:
            got = b""
    finally:
        s.close()
    if got.startswith(b"HTTP/1."):
        return int(got.split(b" ")[1])
    return None


def mode_fuzz(tmp):
    site = pt.demo_copy(tmp)
    srv = pt.Server(site, "--camera", "cam1")
    rng = random.Random(SEED)
    endpoints = ["/api/pick", "/api/move", "/api/delete", "/api/landmark", "/api/undo", "/api/save", "/api/x", "/"]
    bodies = [b"", b"{", b"[]", b"null", b"\"x\"", b"{\"landmark\": 5}", b"{\"landmark\": \"L008\", \"u\": \"1\", \"v\": 2}",
              b"{\"landmark\": \"L008\", \"u\": NaN, \"v\": 2}", b"{\"landmark\": \"L008\", \"u\": 1e308, \"v\": -1e308}",
              b"{\"e\": 1e9, \"n\": 0}", b"{\"e\": 0}", b"{\"landmark\": \"" + b"A" * 5000 + b"\"}",
              b"{\"landmark\": \"L008\", \"u\": 1, \"v\": 2, \"u\": 3}", b"\xff\xfe\x00{}", b"{\"a\":" * 2000]
    statuses = {}
    try:
        port = srv.port
        hdr = f"Host: 127.0.0.1:{port}\r\nOrigin: http://127.0.0.1:{port}\r\nContent-Type: application/json\r\n"
        for i in range(500):
            kind = rng.randrange(6)
            ep = rng.choice(endpoints)
            if kind == 0:  # random bytes, no HTTP at all
                data = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 400)))
            elif kind == 1:  # a malformed body
                b = rng.choice(bodies)
                data = f"POST {ep} HTTP/1.1\r\n{hdr}Content-Length: {len(b)}\r\n\r\n".encode() + b
            elif kind == 2:  # random bytes as the body
                b = bytes(rng.randrange(256) for _ in range(rng.randrange(0, 2000)))
                data = f"POST {ep} HTTP/1.1\r\n{hdr}Content-Length: {len(b)}\r\n\r\n".encode() + b
            elif kind == 3:  # a huge body, announced or chunked
                n = rng.choice([70000, 300000, 2000000])
                if rng.random() < 0.5:
                    data = f"POST {ep} HTTP/1.1\r\n{hdr}Content-Length: {n}\r\n\r\n".encode() + b"{" * min(n, 100000)
                else:
                    chunk = b"{" * 60000
                    data = f"POST {ep} HTTP/1.1\r\n{hdr}Transfer-Encoding: chunked\r\n\r\n".encode()
                    data += (b"%x\r\n" % len(chunk) + chunk + b"\r\n") * (n // 60000) + b"0\r\n\r\n"
            elif kind == 4:  # a lying Content-Length, truncated
                b = rng.choice(bodies)
                data = f"POST {ep} HTTP/1.1\r\n{hdr}Content-Length: {len(b) + 50}\r\n\r\n".encode() + b
            else:  # garbled request line or headers
                data = rng.choice([b"GET\r\n\r\n", b"POST /api/pick HTTP/9.9\r\n\r\n", b"GET / HTTP/1.1\r\nHost\r\n\r\n",
                                   b"GET /" + b"a" * 20000 + b" HTTP/1.1\r\n\r\n",
                                   f"DELETE /api/state HTTP/1.1\r\n{hdr}\r\n".encode()])
            st = raw(port, data, timeout=3)
            statuses[st] = statuses.get(st, 0) + 1
            if not check(st is None or 200 <= st < 500 or st == 505, f"fuzz {i} (kind {kind}, seed {SEED}): status {st}"):
                break
            if not check(srv.alive(), f"fuzz {i} (kind {kind}, seed {SEED}): the server died"):
                break
        st, body = request(port, "GET", "/api/state")
        check(st == 200 and json.loads(body)["camera"]["id"] == "cam1", "the server answers /api/state after the fuzzing")
        print("fuzz statuses:", dict(sorted(statuses.items(), key=lambda kv: str(kv[0]))))
    finally:
        srv.stop()


def mode_save_kill(tmp):
    site = pt.demo_copy(tmp)
    rng = random.Random(SEED)
    lm_path, obs_path = os.path.join(site, "landmarks.geojson"), os.path.join(site, "observations", "cam1.csv")
    digest = lambda p: hashlib.sha256(open(p, "rb").read()).hexdigest()
    seen = {lm_path: {digest(lm_path)}, obs_path: {digest(obs_path)}}
    kills = 0
    for rnd in range(8):
        srv = pt.Server(site, "--camera", "cam1")
        port = srv.port
        st, body = request(port, "GET", "/api/state")
        S = json.loads(body)
        picked = [l for l in S["landmarks"] if l["pick_px"]]
        # a save loop: move a pick a little, save, in a second process-free client loop
        deadline = time.time() + rng.uniform(0.05, 0.6)
        n = 0
        try:
            while time.time() < deadline:
                l = picked[n % len(picked)]
                request(port, "POST", "/api/pick", body=json.dumps(
                    {"landmark": l["id"], "u": l["pick_px"][0] + rng.uniform(-0.3, 0.3), "v": l["pick_px"][1]}))
                if rng.random() < 0.3:
                    request(port, "POST", "/api/landmark", body=json.dumps({"e": rng.uniform(-20, 20), "n": rng.uniform(-20, 20)}))
                # the save is sent, and the kill lands while it runs or just after
                c = http.client.HTTPConnection("127.0.0.1", port, timeout=5)
                c.request("POST", "/api/save", body="{}", headers={"Host": f"127.0.0.1:{port}", "Origin": f"http://127.0.0.1:{port}",
                                                                    "Content-Type": "application/json"})
                if time.time() + 0.01 > deadline:
                    time.sleep(rng.uniform(0, 0.004))
                    break
                c.getresponse().read()
                c.close()
                n += 1
                # every file the server completed is a possible "new" one
                seen[lm_path].add(digest(lm_path))
                seen[obs_path].add(digest(obs_path))
        except (ConnectionError, http.client.HTTPException, socket.timeout):
            pass
        os.kill(srv.p.pid, signal.SIGKILL)
        srv.p.wait()
        kills += 1
        # after the kill: each file parses, and is one the server wrote whole
        try:
            fc = json.load(open(lm_path))
            ok_lm = fc["type"] == "FeatureCollection" and all("id" in f["properties"] for f in fc["features"])
        except (ValueError, KeyError) as e:
            ok_lm = False
            print("landmarks.geojson:", e)
        check(ok_lm, f"round {rnd} (seed {SEED}): landmarks.geojson does not parse after the kill")
        rows = list(csv.reader(open(obs_path)))
        check(rows and rows[0][:3] == ["landmark", "u", "v"] and all(len(r) == len(rows[0]) for r in rows),
              f"round {rnd}: observations/cam1.csv is not whole after the kill")
        ids = {f["properties"]["id"] for f in fc["features"]} if ok_lm else set()
        check(all(r[0] in ids for r in rows[1:]), f"round {rnd}: an observation names a landmark the file lacks")
        leftovers = [f for f in os.listdir(site) + os.listdir(os.path.dirname(obs_path)) if ".tmp" in f or f.startswith(".")]
        seen[lm_path].add(digest(lm_path))
        seen[obs_path].add(digest(obs_path))
        r = run("site", "check", site)
        check(r.returncode == 0, f"round {rnd}: site check after the kill: {r.stdout[-300:]}{r.stderr[-300:]}")
        if leftovers:
            print(f"round {rnd}: temporary files left by the kill (not under the final names): {leftovers}")
    print(f"{kills} kills; {len(seen[lm_path])} versions of landmarks.geojson, {len(seen[obs_path])} of cam1.csv")


MODES = {"origin_host": mode_origin_host, "no_paths": mode_no_paths, "fuzz": mode_fuzz, "save_kill": mode_save_kill}

if __name__ == "__main__":
    mode = sys.argv[1]
    with tempfile.TemporaryDirectory() as tmp:
        MODES[mode](tmp)
    finish("pick_" + mode)

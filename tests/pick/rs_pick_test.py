"""What the pick tests share: starting `roadside pick` on a copy of the demo site, and driving
headless Chromium through the DevTools protocol over a pipe (--remote-debugging-pipe: JSON
messages separated by NUL bytes on file descriptors 3 and 4; no websocket, nothing from npm)."""
import json
import os
import re
import shutil
import subprocess
import time

SRC = os.environ.get("ROADSIDE_SOURCE_ROOT", ".")
ROADSIDE = os.environ["ROADSIDE"]


def demo_copy(tmp, empty_camera=None):
    """A copy of sites/demo in tmp; with empty_camera, that camera's observations are emptied."""
    site = os.path.join(tmp, "demo")
    shutil.copytree(os.path.join(SRC, "sites", "demo"), site)
    if empty_camera:
        with open(os.path.join(site, "observations", empty_camera + ".csv"), "w") as f:
            f.write("landmark,u,v,sigma_px\n")
    return site


class Server:
    """`roadside pick SITE ARGS...` in the background; .url, .port; stop() ends it (SIGTERM)."""

    def __init__(self, site, *args):
        self.p = subprocess.Popen([ROADSIDE, "pick", site, *args], stdout=subprocess.PIPE,
                                  stderr=subprocess.PIPE, text=True)
        self.url = None
        t0 = time.time()
        while time.time() - t0 < 60:
            line = self.p.stdout.readline()
            if not line:
                raise RuntimeError("roadside pick ended: " + self.p.stderr.read())
            m = re.match(r"^(http://127\.0\.0\.1:(\d+)/)$", line.strip())
            if m:
                self.url, self.port = m.group(1), int(m.group(2))
                break
        if not self.url:
            raise RuntimeError("roadside pick printed no URL")

    def alive(self):
        return self.p.poll() is None

    def stop(self):
        if self.p.poll() is None:
            self.p.terminate()
            try:
                self.p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.p.kill()
                self.p.wait()
        return self.p.returncode


class Browser:
    """Headless Chromium driven over --remote-debugging-pipe; one page (target) attached."""

    def __init__(self, tmp, width=1400, height=1000):
        r3, w3 = os.pipe()  # we write commands -> chromium reads fd 3
        r4, w4 = os.pipe()  # chromium writes fd 4 -> we read
        def fds():
            os.dup2(r3, 3)
            os.dup2(w4, 4)
        self.p = subprocess.Popen(
            ["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--remote-debugging-pipe",
             "--no-first-run", "--disable-background-networking", "--disable-component-update",
             "--disable-sync", "--user-data-dir=" + os.path.join(tmp, "chromium"),
             f"--window-size={width},{height}", "about:blank"],
            preexec_fn=fds, pass_fds=(3, 4), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        os.close(r3)
        os.close(w4)
        self.w, self.r = os.fdopen(w3, "wb"), os.fdopen(r4, "rb")
        self.buf = b""
        self.id = 0
        self.requests = []  # every URL the page asked for, once Network.enable is called
        self.session = None
        targets = self.call("Target.getTargets")["targetInfos"]
        page = next(t for t in targets if t["type"] == "page")
        self.session = self.call("Target.attachToTarget", targetId=page["targetId"], flatten=True,
                                 _root=True)["sessionId"]
        self.call("Page.enable")
        self.call("Runtime.enable")
        self.call("Emulation.setDeviceMetricsOverride", width=width, height=height, deviceScaleFactor=1,
                  mobile=False)

    def call(self, method, _root=False, **params):
        self.id += 1
        msg = {"id": self.id, "method": method, "params": params}
        if self.session and not _root:
            msg["sessionId"] = self.session
        self.w.write(json.dumps(msg).encode() + b"\0")
        self.w.flush()
        while True:
            while b"\0" not in self.buf:
                chunk = os.read(self.r.fileno(), 1 << 20)
                if not chunk:
                    raise RuntimeError("chromium closed the pipe")
                self.buf += chunk
            raw, self.buf = self.buf.split(b"\0", 1)
            m = json.loads(raw)
            if m.get("method") == "Network.requestWillBeSent":
                self.requests.append(m["params"]["request"]["url"])
            if m.get("id") == self.id:
                if "error" in m:
                    raise RuntimeError(f"{method}: {m['error']}")
                return m.get("result", {})

    def eval(self, expr):
        r = self.call("Runtime.evaluate", expression=expr, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in r:
            raise RuntimeError(f"{expr}: {r['exceptionDetails']}")
        return r["result"].get("value")

    def wait(self, expr, timeout=20):
        t0 = time.time()
        while time.time() - t0 < timeout:
            if self.eval(expr):
                return True
            time.sleep(0.05)
        return False

    def click(self, x, y):
        for t in ("mouseMoved", "mousePressed", "mouseReleased"):
            self.call("Input.dispatchMouseEvent", type=t, x=x, y=y, button="left" if t != "mouseMoved" else "none",
                      clickCount=1 if t != "mouseMoved" else 0)

    def wheel_zoom(self, view, a, b, steps):
        """Zooms `view` ('image' or 'map') in with the mouse wheel around the screen position of
        (a, b), as a surveyor does before a sub-pixel pick; returns that position afterwards."""
        for _ in range(steps):
            p = self.eval(f"window.rsPick.toScreen('{view}', {a}, {b})")
            self.call("Input.dispatchMouseEvent", type="mouseWheel", x=p["x"], y=p["y"], deltaX=0, deltaY=-100)
        return self.eval(f"window.rsPick.toScreen('{view}', {a}, {b})")

    def key(self, key, code=None):
        for t in ("keyDown", "keyUp"):
            self.call("Input.dispatchKeyEvent", type=t, key=key, code=code or key, text=key if t == "keyDown" and len(key) == 1 else "")

    def screenshot(self, path, clip=None, scale=1):
        import base64
        params = {"format": "png"}
        if clip:
            params["clip"] = dict(clip, scale=scale)
        data = self.call("Page.captureScreenshot", **params)["data"]
        with open(path, "wb") as f:
            f.write(base64.b64decode(data))

    def close(self):
        try:
            self.call("Browser.close", _root=True)
        except Exception:
            pass
        try:
            self.p.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.p.kill()
            self.p.wait()

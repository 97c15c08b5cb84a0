"""A minimal Chrome DevTools protocol client for headless Chromium (standard library only).

Chromium is started with --remote-debugging-pipe: it reads commands from file descriptor 3 and
writes replies and events to file descriptor 4, each message a JSON object followed by a NUL
byte. One page target is attached in "flatten" mode, so every page command carries its
sessionId. Console messages, uncaught exceptions and log entries of the page are collected in
`Browser.errors` / `Browser.console` while commands wait for their replies.

    with Browser() as b:
        b.navigate("file:///tmp/report/index.html")
        b.evaluate("document.title")
        png_bytes = b.screenshot(clip={"x": 0, "y": 0, "width": 800, "height": 600})
"""
import base64
import json
import os
import select
import subprocess
import tempfile
import time

CHROMIUM_FLAGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--enable-unsafe-swiftshader", "--remote-debugging-pipe", "--hide-scrollbars",
]


class CdpError(RuntimeError):
    pass


class Browser:
    def __init__(self, executable="chromium", width=1280, height=900, timeout_s=60.0):
        self.timeout_s = timeout_s
        self.profile = tempfile.TemporaryDirectory(prefix="lexdyn-chromium-")
        self.errors = []     # uncaught exceptions, console.error, log entries of level error
        self.console = []    # every console message: (type, text)
        self._next_id = 0
        self._buffer = b""
        self._events = []
        to_child_r, to_child_w = os.pipe()
        from_child_r, from_child_w = os.pipe()

        def child_fds():
            # fds 3 and 4 of the child: commands in, replies out. Copies first, so that dup2
            # cannot close an end we still need; a copy may itself land on 3 or 4 (dup2 is then
            # a no-op and the copy is close-on-exec), hence the explicit set_inheritable.
            a, b = os.dup(to_child_r), os.dup(from_child_w)
            if a != 3:
                os.dup2(a, 3)
            if b != 4:
                os.dup2(b, 4)
            os.set_inheritable(3, True)
            os.set_inheritable(4, True)

        args = [executable] + CHROMIUM_FLAGS + [f"--user-data-dir={self.profile.name}",
                                                 f"--window-size={width},{height}", "about:blank"]
        self.proc = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                     stderr=subprocess.DEVNULL, preexec_fn=child_fds, close_fds=False)
        os.close(to_child_r)
        os.close(from_child_w)
        self._w = to_child_w
        self._r = from_child_r
        target = self.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        self.page = self.call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        for domain in ("Page", "Runtime", "Log"):
            self.call(f"{domain}.enable", to_page=True)
        self.call("Emulation.setDeviceMetricsOverride",
                  {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False}, to_page=True)

    # -- transport ---------------------------------------------------------------------------
    def _send(self, msg):
        data = json.dumps(msg).encode() + b"\0"
        while data:
            n = os.write(self._w, data)
            data = data[n:]

    def _read_message(self, deadline):
        while b"\0" not in self._buffer:
            left = deadline - time.monotonic()
            if left <= 0:
                raise CdpError("timed out waiting for Chromium")
            ready, _, _ = select.select([self._r], [], [], left)
            if not ready:
                continue
            chunk = os.read(self._r, 1 << 20)
            if not chunk:
                raise CdpError(f"Chromium closed the pipe (exit code {self.proc.poll()})")
            self._buffer += chunk
        raw, self._buffer = self._buffer.split(b"\0", 1)
        return json.loads(raw)

    def _record_event(self, msg):
        method, p = msg.get("method"), msg.get("params", {})
        if method == "Runtime.exceptionThrown":
            d = p.get("exceptionDetails", {})
            text = d.get("exception", {}).get("description") or d.get("text", "")
            self.errors.append(f"uncaught exception: {text} ({d.get('url', '')}:{d.get('lineNumber', '?')})")
        elif method == "Runtime.consoleAPICalled":
            text = " ".join(str(a.get("value", a.get("description", ""))) for a in p.get("args", []))
            self.console.append((p.get("type"), text))
            if p.get("type") in ("error", "assert"):
                self.errors.append(f"console.{p.get('type')}: {text}")
        elif method == "Log.entryAdded":
            e = p.get("entry", {})
            self.console.append((f"log.{e.get('level')}", e.get("text", "")))
            if e.get("level") == "error":
                self.errors.append(f"log error ({e.get('source')}): {e.get('text')} {e.get('url', '')}")
        self._events.append(msg)

    def call(self, method, params=None, to_page=False, timeout_s=None):
        self._next_id += 1
        msg = {"id": self._next_id, "method": method, "params": params or {}}
        if to_page:
            msg["sessionId"] = self.page
        self._send(msg)
        deadline = time.monotonic() + (timeout_s or self.timeout_s)
        while True:
            reply = self._read_message(deadline)
            if reply.get("id") == self._next_id:
                if "error" in reply:
                    raise CdpError(f"{method}: {reply['error']}")
                return reply.get("result", {})
            if "method" in reply:
                self._record_event(reply)

    def wait_event(self, method, timeout_s=None):
        for i, e in enumerate(self._events):
            if e.get("method") == method:
                return self._events.pop(i)
        deadline = time.monotonic() + (timeout_s or self.timeout_s)
        while True:
            msg = self._read_message(deadline)
            if "method" in msg:
                self._record_event(msg)
                if msg["method"] == method:
                    self._events.remove(msg)
                    return msg

    # -- page --------------------------------------------------------------------------------
    def navigate(self, url):
        self._events = [e for e in self._events if e.get("method") != "Page.loadEventFired"]
        self.call("Page.navigate", {"url": url}, to_page=True)
        self.wait_event("Page.loadEventFired")

    def evaluate(self, expression, await_promise=False):
        r = self.call("Runtime.evaluate", {"expression": expression, "returnByValue": True,
                                           "awaitPromise": await_promise}, to_page=True)
        if "exceptionDetails" in r:
            d = r["exceptionDetails"]
            raise CdpError(f"evaluate({expression[:80]}...): {d.get('exception', {}).get('description', d.get('text'))}")
        return r.get("result", {}).get("value")

    def screenshot(self, clip=None):
        params = {"format": "png", "captureBeyondViewport": False}
        if clip:
            params["clip"] = dict(clip, scale=1)
        return base64.b64decode(self.call("Page.captureScreenshot", params, to_page=True)["data"])

    def close(self):
        try:
            if self.proc.poll() is None:
                try:
                    self.call("Browser.close", timeout_s=10)
                except (CdpError, OSError):
                    pass
                try:
                    self.proc.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    self.proc.kill()
                    self.proc.wait()
        finally:
            for fd in (self._w, self._r):
                try:
                    os.close(fd)
                except OSError:
                    pass
            self.profile.cleanup()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

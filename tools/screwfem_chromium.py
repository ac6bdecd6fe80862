"""Drives headless Chromium through the DevTools protocol: load a page, wait for it, read
console errors, evaluate JavaScript, take screenshots. Used by the viewer test
(tests/view/view_test.py) and by tools/screwfem_screenshot.py.

Needs Debian's chromium and python3-websocket (the DevTools protocol is a JSON-RPC over a
WebSocket). Chromium renders WebGL in software (SwiftShader), so no GPU is needed.
"""

import base64
import json
import os
import re
import shutil
import subprocess
import tempfile
import threading
import time
import urllib.request

CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome")


def find_chromium():
    """Path of a Chromium executable (SCREWFEM_CHROMIUM, else on PATH), or None."""
    env = os.environ.get("SCREWFEM_CHROMIUM")
    if env:
        return env if os.access(env, os.X_OK) else None
    for name in CHROMIUM_NAMES:
        path = shutil.which(name)
        if path:
            return path
    return None


class BrowserError(Exception):
    pass


class Chromium:
    """One headless Chromium with one page. Use as a context manager."""

    def __init__(self, width=1000, height=700, timeout=90.0):
        import websocket  # python3-websocket; imported here so find_chromium works without it

        self._websocket = websocket
        self.width, self.height, self.timeout = width, height, timeout
        exe = find_chromium()
        if not exe:
            raise BrowserError("chromium not found (Debian package chromium)")
        self._profile = tempfile.mkdtemp(prefix="screwfem-chromium-")
        args = [exe, "--headless=new", "--no-sandbox", "--enable-unsafe-swiftshader",
                "--use-angle=swiftshader", "--remote-debugging-port=0",
                "--remote-allow-origins=*", f"--user-data-dir={self._profile}",
                f"--window-size={width},{height}", "--hide-scrollbars", "--mute-audio",
                "--no-first-run", "--no-default-browser-check", "--disable-extensions",
                "--disable-background-networking", "--disable-sync", "about:blank"]
        env = dict(os.environ, DBUS_SESSION_BUS_ADDRESS="disabled:")
        self._proc = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.PIPE, env=env)
        self.stderr_lines = []
        endpoint = threading.Event()
        self._endpoint = None

        def drain():
            for raw in self._proc.stderr:
                line = raw.decode("utf-8", "replace").rstrip()
                self.stderr_lines.append(line)
                m = re.search(r"DevTools listening on (ws://\S+)", line)
                if m:
                    self._endpoint = m.group(1)
                    endpoint.set()
            endpoint.set()

        threading.Thread(target=drain, daemon=True).start()
        if not endpoint.wait(timeout) or not self._endpoint:
            self.close()
            raise BrowserError("chromium did not start its DevTools endpoint:\n" +
                               "\n".join(self.stderr_lines[-20:]))
        port = re.match(r"ws://[^:/]+:(\d+)/", self._endpoint).group(1)
        targets = json.load(urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=timeout))
        page = next((t for t in targets if t.get("type") == "page"), None)
        if page is None:
            self.close()
            raise BrowserError("chromium has no page target")
        self._ws = websocket.create_connection(page["webSocketDebuggerUrl"], timeout=timeout,
                                               suppress_origin=True)
        self._next_id = 0
        self.events = []  # DevTools events received so far (method, params)
        self.call("Runtime.enable")
        self.call("Log.enable")
        self.call("Page.enable")
        self.call("Emulation.setDeviceMetricsOverride",
                  width=width, height=height, deviceScaleFactor=1, mobile=False)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self):
        ws = getattr(self, "_ws", None)
        if ws is not None:
            try:
                ws.close()
            except Exception:  # noqa: BLE001 -- closing anyway
                pass
            self._ws = None
        if self._proc.poll() is None:
            self._proc.terminate()
            try:
                self._proc.wait(10)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
        shutil.rmtree(self._profile, ignore_errors=True)

    def call(self, method, **params):
        """Sends a DevTools command and returns its result (events on the way are kept)."""
        self._next_id += 1
        msg_id = self._next_id
        self._ws.send(json.dumps({"id": msg_id, "method": method, "params": params}))
        deadline = time.monotonic() + self.timeout
        while time.monotonic() < deadline:
            msg = json.loads(self._ws.recv())
            if msg.get("id") == msg_id:
                if "error" in msg:
                    raise BrowserError(f"{method}: {msg['error']}")
                return msg.get("result", {})
            if "method" in msg:
                self.events.append((msg["method"], msg.get("params", {})))
        raise BrowserError(f"{method}: no answer within {self.timeout} s")

    def evaluate(self, expression):
        """The value of a JavaScript expression (JSON-serialisable)."""
        r = self.call("Runtime.evaluate", expression=expression, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in r:
            raise BrowserError(f"{expression}: {r['exceptionDetails']}")
        return r.get("result", {}).get("value")

    def load(self, url, ready_expression="document.readyState === 'complete'", timeout=None):
        """Navigates to url and waits until ready_expression is true."""
        self.call("Page.navigate", url=url)
        deadline = time.monotonic() + (timeout or self.timeout)
        while time.monotonic() < deadline:
            try:
                if self.evaluate(ready_expression):
                    return
            except BrowserError:
                pass  # the old document may be gone while the new one loads
            time.sleep(0.05)
        raise BrowserError(f"{url}: not ready within {timeout or self.timeout} s")

    def screenshot(self):
        """PNG bytes of the page at the window size."""
        r = self.call("Page.captureScreenshot", format="png")
        return base64.b64decode(r["data"])

    def console_problems(self):
        """Console errors, uncaught exceptions and error log entries seen so far (text)."""
        out = []
        for method, p in self.events:
            if method == "Runtime.exceptionThrown":
                d = p.get("exceptionDetails", {})
                out.append("exception: " + (d.get("exception", {}).get("description") or d.get("text", "")))
            elif method == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
                out.append("console.error: " + " ".join(str(a.get("value", a.get("description", "")))
                                                         for a in p.get("args", [])))
            elif method == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
                out.append("log: " + p["entry"].get("text", ""))
        return out

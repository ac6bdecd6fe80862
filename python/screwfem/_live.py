"""Live view of a running Simulation in the browser viewer (``Simulation.view``).

``sim.view()`` starts a small server on 127.0.0.1 in a background thread: ``GET /`` is the
viewer page of ``screwfem view`` (tools/viewer) with the simulation's current state as its
first frame, and ``/ws`` a WebSocket over which every open page receives the frames the
simulation reaches as it steps. The frames are the ones ``screwfem run`` writes for ParaView
(io/vtk.h; ``Simulation._vtk_frame`` composes one in memory), turned into the page's data by the
same code as ``screwfem view`` (tools/screwfem_view.py: page_data, live_frame). Nothing is built
while no page is connected: the step hook then only checks that.

The page's Pause button pauses the simulation: the step hook (run after every accepted step)
waits while it is paused, until a page resumes, every page has gone, ``close()`` is called or
``pause_timeout`` seconds have passed; it polls every 0.1 s, so Ctrl-C still interrupts it.

Needs the ``websockets`` package (Debian: python3-websockets, 10.4) and the viewer's files:
$SCREWFEM_TOOLS_DIR, else screwfem/_viewer of a wheel, share/screwfem of the build tree or the
installation, or tools/ of the source tree; three.js from Debian's libjs-three
($SCREWFEM_THREE_DIR).
"""

import asyncio
import importlib.util
import json
import os
import threading
import time
import webbrowser

WS_PATH = "/ws"
WRITE_BUFFER_LIMIT = 8 << 20  # bytes queued for a page beyond which its in-between frames are dropped


def _tools_dir():
    here = os.path.dirname(os.path.abspath(__file__))
    env = os.environ.get("SCREWFEM_TOOLS_DIR")
    candidates = [env] if env else [
        os.path.join(here, "_viewer"),                         # a wheel (python/packaging)
        os.path.join(here, "..", "..", "share", "screwfem"),  # build tree: <build>/python/screwfem
        os.path.join(here, "..", ".."),                        # installed: share/screwfem/python/..
        os.path.join(here, "..", "..", "tools"),               # source tree: python/screwfem
    ]
    for c in candidates:
        if os.path.isfile(os.path.join(c, "screwfem_view.py")) and \
                os.path.isfile(os.path.join(c, "viewer", "viewer.js")):
            return os.path.abspath(c)
    raise RuntimeError("Simulation.view: the viewer's files (screwfem_view.py, viewer/) were not "
                       "found in " + ", ".join(os.path.abspath(c) for c in candidates) +
                       "; set SCREWFEM_TOOLS_DIR to the directory holding them")


_VIEW_MODULE = None


def _view_module():
    """tools/screwfem_view.py, loaded once (it imports screwfem_vtk from its directory)."""
    global _VIEW_MODULE
    if _VIEW_MODULE is None:
        path = os.path.join(_tools_dir(), "screwfem_view.py")
        spec = importlib.util.spec_from_file_location("screwfem_view", path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        _VIEW_MODULE = module
    return _VIEW_MODULE


class LiveView:
    """A running live view (Simulation.view): ``url``, ``port``, ``close()``; a context manager
    that closes it on leaving the block. Attributes for scripts and tests: ``clients`` (pages
    connected), ``paused``, ``frames_sent``."""

    def __init__(self, sim, port=0, open_browser=False, host="127.0.0.1", max_rate=30.0,
                 pause_timeout=None):
        try:
            import websockets
            import websockets.server  # noqa: F401
        except ImportError as e:
            raise ImportError("Simulation.view needs the Python package websockets (Debian: "
                              "python3-websockets)") from e
        if max_rate is not None and not (max_rate >= 0):
            raise ValueError("Simulation.view: max_rate must be None or >= 0 (frames per second)")
        if pause_timeout is not None and not (pause_timeout >= 0):
            raise ValueError("Simulation.view: pause_timeout must be None or >= 0 s")
        if not 0 <= int(port) <= 65535:
            raise ValueError("Simulation.view: port must be in 0 ... 65535 (0: a free one)")
        if sim._step_hook() is not None:
            raise RuntimeError("Simulation.view: the simulation has a live view already; close it")
        self._websockets = websockets
        self._sim = sim
        self._view = _view_module()
        self._max_rate = max_rate or 0.0
        self._pause_timeout = pause_timeout
        self._clients = set()
        self._paused = False
        self._resume = threading.Event()
        self._resume.set()
        self._closed = False
        self._last_push = -float("inf")
        self.frames_sent = 0
        self._layout = self._page_data()  # the frames' layout (the same for every page)
        self._loop = asyncio.new_event_loop()
        self._error = None
        started = threading.Event()
        self._thread = threading.Thread(target=self._serve, args=(host, int(port), started),
                                        name="screwfem-live-view", daemon=True)
        self._thread.start()
        started.wait(30)
        if self._error is not None or not hasattr(self, "port"):
            self._closed = True
            raise RuntimeError(f"Simulation.view: cannot serve on {host}:{port}: {self._error}")
        self.url = f"http://{host}:{self.port}/"
        sim._set_step_hook(self._after_step)
        if open_browser:
            webbrowser.open(self.url)

    # -- the page and its frames (the simulation's thread, or the server's for a page: the GIL
    # keeps the C++ state still meanwhile)

    def _frame(self, t):
        raw = self._sim._vtk_frame(t, 1.0)
        return self._view.screwfem_vtk.read_frame_bytes(raw, "live frame")

    def _page_data(self):
        sim, model = self._sim, self._sim.model
        joints = [{"index": i, "name": j.name, "type": j.type.name.lower(),
                   "drive": j.drive.name.lower()} for i, j in enumerate(model.joints)]
        summary = {"settings": {"gravity": [float(g) for g in model.gravity]},
                   "scene": {"name": sim.scene.name}, "status": "running"}
        t = sim.time
        return self._view.page_data([(t, self._frame(t))], 1, summary, {"joints": joints}, {},
                                    sim.scene.name or "screwfem simulation", None, [], live=True)

    def _page(self):
        data = self._page_data()
        data.pop("_live")
        data["live"] = {"path": WS_PATH}
        data["notes"] = [n for n in data["notes"] if "strain or stress" not in n]
        return self._view.render_html(data)

    def _after_step(self, t, last):
        if not self._clients:  # nobody watches: nothing is built
            return
        now = time.monotonic()
        if last or self._max_rate <= 0 or now - self._last_push >= 1.0 / self._max_rate:
            self._last_push = now
            message = json.dumps(self._view.live_frame(self._layout, t, self._frame(t)),
                                 separators=(",", ":"))
            self._loop.call_soon_threadsafe(self._broadcast, message, last)
            self.frames_sent += 1
        if self._paused:
            self._wait()

    def _wait(self):
        deadline = None if self._pause_timeout is None else time.monotonic() + self._pause_timeout
        while self._paused and not self._closed:
            wait = 0.1 if deadline is None else min(0.1, deadline - time.monotonic())
            if wait <= 0:
                break
            self._resume.wait(wait)

    # -- the server (its own thread and event loop)

    def _serve(self, host, port, started):
        asyncio.set_event_loop(self._loop)

        async def main():
            self._stop = self._loop.create_future()
            try:
                server = await self._websockets.serve(
                    self._handler, host, port, process_request=self._process_request,
                    max_size=1 << 16, ping_interval=20, ping_timeout=20)
            except OSError as e:
                self._error = e
                started.set()
                return
            self.port = server.sockets[0].getsockname()[1]
            started.set()
            await self._stop
            server.close()
            await server.wait_closed()

        try:
            self._loop.run_until_complete(main())
        except Exception as e:  # noqa: BLE001 -- reported by the constructor
            self._error = e
            started.set()
        finally:
            self._loop.close()

    async def _process_request(self, path, headers):
        from http import HTTPStatus
        if path == WS_PATH:
            return None  # the WebSocket handshake
        if path.split("?")[0] in ("/", "/index.html"):
            try:
                body = self._page()
            except Exception as e:  # noqa: BLE001 -- shown to the browser
                return (HTTPStatus.INTERNAL_SERVER_ERROR,
                        [("Content-Type", "text/plain; charset=utf-8")], str(e).encode())
            return (HTTPStatus.OK, [("Content-Type", "text/html; charset=utf-8"),
                                    ("Cache-Control", "no-store")], body)
        if path == "/favicon.ico":
            return (HTTPStatus.NO_CONTENT, [], b"")  # none, and no error in the console
        return (HTTPStatus.NOT_FOUND, [("Content-Type", "text/plain")], b"not found\n")

    async def _handler(self, ws, path=None):
        self._clients.add(ws)
        try:
            await ws.send(json.dumps({"paused": self._paused}))
            async for text in ws:
                try:
                    m = json.loads(text)
                except ValueError:
                    continue
                if isinstance(m, dict) and "pause" in m:
                    self._set_paused(bool(m["pause"]))
        except self._websockets.ConnectionClosed:
            pass
        finally:
            self._clients.discard(ws)
            if not self._clients and self._paused:
                self._set_paused(False)  # nobody is left to resume it

    def _set_paused(self, paused):
        self._paused = paused
        if paused:
            self._resume.clear()
        else:
            self._resume.set()
        self._websockets.broadcast(self._clients, json.dumps({"paused": paused}))

    def _broadcast(self, message, last):
        # A page that cannot keep up gets the last frame of every call, not those in between.
        ready = [ws for ws in self._clients if last or ws.transport is None or
                 ws.transport.get_write_buffer_size() < WRITE_BUFFER_LIMIT]
        self._websockets.broadcast(ready, message)

    # -- public

    @property
    def clients(self):
        """The number of pages connected."""
        return len(self._clients)

    @property
    def paused(self):
        """Whether a page has paused the simulation."""
        return self._paused

    def close(self):
        """Stops the server (pages see the connection end), releases a paused step and detaches
        from the simulation. Idempotent."""
        if self._closed:
            return
        self._closed = True
        self._paused = False
        self._resume.set()
        try:
            self._sim._set_step_hook(None)
        except Exception:  # noqa: BLE001 -- the simulation may be gone at exit
            pass
        if self._loop.is_running():
            self._loop.call_soon_threadsafe(
                lambda: self._stop.done() or self._stop.set_result(None))
        self._thread.join(10)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def __repr__(self):
        state = "closed" if self._closed else f"{self.clients} page(s)"
        return f"<screwfem.LiveView {self.url} {state}>"

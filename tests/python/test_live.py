"""Simulation.view (screwfem/_live.py) without a browser: the page it serves, the frames its
WebSocket sends (read with the websockets client), the pause and close, and the cost of
stepping with a view but no page; and Simulation._vtk_frame against the frame `screwfem run`
writes. The browser side is tests/view/live_test.py.

    PYTHONPATH=<build>/python /usr/bin/python3 -m unittest -v test_live   (from tests/python)
"""

import asyncio
import base64
import json
import os
import struct
import subprocess
import tempfile
import threading
import time
import unittest
import urllib.request

import screwfem as sf

SOURCE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
SCENE = os.path.join(SOURCE, "tests", "view", "true_size.yaml")

try:
    import websockets
except ImportError:
    websockets = None


def floats(b64):
    raw = base64.b64decode(b64)
    return struct.unpack(f"<{len(raw) // 4}f", raw)


class Client:
    """A WebSocket client of the live view in its own thread: the messages it receives."""

    def __init__(self, url):
        self.messages, self.ready, self.loop = [], threading.Event(), asyncio.new_event_loop()
        self.outbox = None
        def main():
            try:
                self.loop.run_until_complete(self.run(url))
            finally:
                self.loop.close()

        self.thread = threading.Thread(target=main, daemon=True)
        self.thread.start()
        assert self.ready.wait(10)

    async def run(self, url):
        self.outbox = asyncio.Queue()
        async with websockets.connect(url.replace("http://", "ws://") + "ws") as ws:
            self.ready.set()

            async def send():
                while True:
                    message = await self.outbox.get()
                    if message is None:
                        await ws.close()
                        return
                    await ws.send(message)
            sender = asyncio.ensure_future(send())
            try:
                async for text in ws:
                    self.messages.append(json.loads(text))
            except websockets.ConnectionClosed:
                pass
            sender.cancel()

    def send(self, message):
        self.loop.call_soon_threadsafe(self.outbox.put_nowait, json.dumps(message))

    def close(self):
        self.loop.call_soon_threadsafe(self.outbox.put_nowait, None)

    def frames(self):
        return [m for m in self.messages if "t" in m]

    def wait(self, predicate, timeout=10):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and not predicate():
            time.sleep(0.01)
        return predicate()


@unittest.skipIf(websockets is None, "python3-websockets is not installed")
class LiveView(unittest.TestCase):
    def setUp(self):
        self.sim = sf.Simulation(sf.load_scene(SCENE))
        self.sim.initialize()

    def test_page_frames_pause_and_close(self):
        sim = self.sim
        with sim.view(max_rate=0) as view:
            self.assertRegex(view.url, r"^http://127\.0\.0\.1:\d+/$")
            self.assertEqual(view.clients, 0)
            for _ in range(3):
                sim.step()
            self.assertEqual(view.frames_sent, 0)  # no page: nothing built
            page = urllib.request.urlopen(view.url, timeout=10).read().decode()
            self.assertIn('"live":{"path":"/ws"}', page)
            self.assertIn('"name":"True size: a 40 mm box, a 16 mm rod and a tendon"', page)
            self.assertIn("<title>True size", page)
            data = json.loads(page.split('<script id="run-data" type="application/json">')[1]
                              .split("</script>")[0].replace("<\\/", "</"))
            self.assertEqual(data["times"], [sim.time])
            with self.assertRaises(urllib.error.HTTPError):
                urllib.request.urlopen(view.url + "elsewhere", timeout=10)

            client = Client(view.url)
            self.assertTrue(client.wait(lambda: view.clients == 1))
            self.assertTrue(client.wait(lambda: client.messages[:1] == [{"paused": False}]))
            for _ in range(4):
                sim.step()
            self.assertTrue(client.wait(lambda: len(client.frames()) == 4))
            last = client.frames()[-1]
            self.assertEqual(last["t"], sim.time)
            # The moving points' positions of the page's layout: the rod's tip node among them,
            # as float32.
            rod_nodes = sim.rod_centerline("beam")
            x = floats(last["x"])
            self.assertEqual(len(x), 3 * len(data["moving"]))
            moved = [tuple(x[3 * k:3 * k + 3]) for k in range(len(data["moving"]))]
            tip = tuple(struct.unpack("<3f", struct.pack("<3f", *rod_nodes[-1])))
            self.assertIn(tip, moved)
            self.assertEqual(len(floats(last["q"])), 4 * len(data["turning"]))
            self.assertEqual(last["tension"], [1.0])  # the tendon pulls with 1 N

            # Paused by the page: a step waits until it resumes.
            client.send({"pause": True})
            self.assertTrue(client.wait(lambda: view.paused))
            self.assertTrue(client.wait(lambda: {"paused": True} in client.messages))
            done = threading.Event()
            worker = threading.Thread(target=lambda: (sim.step(), done.set()))
            worker.start()
            self.assertFalse(done.wait(0.5))
            client.send({"pause": False})
            self.assertTrue(done.wait(5))
            worker.join()
            # Paused again: close() releases the step.
            client.send({"pause": True})
            self.assertTrue(client.wait(lambda: view.paused))
            done.clear()
            worker = threading.Thread(target=lambda: (sim.step(), done.set()))
            worker.start()
            self.assertFalse(done.wait(0.3))
            view.close()
            self.assertTrue(done.wait(5))
            worker.join()
            client.thread.join(5)
            self.assertFalse(client.thread.is_alive())  # the server ended the connection
            self.assertEqual(len(client.frames()), 6)
        self.assertIsNone(sim._step_hook())
        view.close()  # idempotent

    def test_a_page_that_leaves_releases_the_pause(self):
        sim = self.sim
        with sim.view() as view:
            client = Client(view.url)
            client.send({"pause": True})
            self.assertTrue(client.wait(lambda: view.paused))
            client.close()  # the page goes away: nobody is left to resume
            self.assertTrue(client.wait(lambda: view.clients == 0 and not view.paused))
            start = time.perf_counter()
            sim.step()
            self.assertLess(time.perf_counter() - start, 1.0)

    def test_max_rate_keeps_the_last_step_of_a_call(self):
        sim = self.sim
        with sim.view(max_rate=1e-3) as view:  # one frame per 1000 s: only calls' last steps
            client = Client(view.url)
            self.assertTrue(client.wait(lambda: view.clients == 1))
            sim.simulate(until=0.02)  # 10 steps of 2 ms: the first (the rate allows one
            sim.step()                # frame) and the last, then the step's
            self.assertTrue(client.wait(lambda: len(client.frames()) == 3), client.frames())
            times = [m["t"] for m in client.frames()]
            self.assertAlmostEqual(times[0], 0.002, delta=1e-12)
            self.assertAlmostEqual(times[1], 0.02, delta=1e-12)
            self.assertEqual(times[2], sim.time)
            self.assertEqual(view.frames_sent, 3)

    def test_static_load_steps_are_frames(self):
        # tests/view/chamber.yaml: 4 load steps, a frame each with the load factor as its time.
        sim = sf.Simulation(sf.load_scene(os.path.join(SOURCE, "tests", "view", "chamber.yaml")))
        with sim.view(max_rate=0) as view:
            client = Client(view.url)
            self.assertTrue(client.wait(lambda: view.clients == 1))
            sim.solve_static()
            self.assertTrue(client.wait(lambda: len(client.frames()) == 4))
            self.assertEqual([m["t"] for m in client.frames()], [0.25, 0.5, 0.75, 1.0])

    def test_stepping_cost_without_a_page(self):
        sim = self.sim
        steps = 10

        def run():
            start = time.perf_counter()
            for _ in range(steps):
                sim.step(0.002)
            return (time.perf_counter() - start) / steps

        run()  # warm up
        plain, viewed = [], []
        for _ in range(4):  # interleaved, so that both see the same machine
            plain.append(run())
            with sim.view() as view:
                viewed.append(run())
                self.assertEqual(view.frames_sent, 0)
        plain, viewed = min(plain), min(viewed)
        print(f"\nstep without view {plain * 1e6:.0f} us, with a view and no page "
              f"{viewed * 1e6:.0f} us")
        self.assertLess(viewed, 1.5 * plain + 50e-6)

    def test_arguments(self):
        with self.assertRaisesRegex(ValueError, "max_rate"):
            self.sim.view(max_rate=-1)
        with self.assertRaisesRegex(ValueError, "pause_timeout"):
            self.sim.view(pause_timeout=-1)
        self.assertIsNone(self.sim._step_hook())

    def test_hook_errors_are_raised_by_the_step(self):
        sim = self.sim
        calls = []

        def hook(t, last):
            calls.append((t, last))
            if len(calls) == 2:
                raise KeyError("from the hook")

        sim._set_step_hook(hook)
        sim.step()
        with self.assertRaisesRegex(KeyError, "from the hook"):
            sim.step()
        sim._set_step_hook(None)
        self.assertEqual([last for _, last in calls], [True, True])


class VtkFrame(unittest.TestCase):
    def test_equals_the_first_frame_of_screwfem_run(self):
        cli = os.environ.get("SCREWFEM_CLI")
        if not cli:
            self.skipTest("SCREWFEM_CLI (the screwfem program) is not set")
        with tempfile.TemporaryDirectory() as tmp:
            subprocess.run([cli, "run", SCENE, "-o", tmp + "/run", "-q", "--set",
                            "analysis.end_time=0.002"], check=True)
            with open(os.path.join(tmp, "run", "vtk", "frame_00000.vtp"), "rb") as f:
                written = f.read()
        sim = sf.Simulation(sf.load_scene(SCENE))
        sim.initialize()
        self.assertEqual(sim._vtk_frame(sim.time), written)


if __name__ == "__main__":
    unittest.main()

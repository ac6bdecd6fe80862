"""The live view (Simulation.view), the load-factor slider of a static run and the chambers, in
headless Chromium.

    live_test.py --screwfem PATH/TO/screwfem --source REPO_ROOT --python BUILD/python [CLASS]

LiveView: tests/view/true_size.yaml stepped from Python with sim.view(max_rate=0) open in one
headless Chromium page (tools/screwfem_chromium.py):
  * with no page connected, stepping builds no frame (frames_sent stays 0);
  * the page served at view.url connects its WebSocket; 10 steps send it exactly 10 frames and
    the time it shows is the simulation's; its picture (the screen box of the mechanism's
    points, with a fixed orthographic camera) equals that of a page loaded afresh at that state;
  * the page's Pause button pauses the simulation: a step then does not return until the page
    resumes (its frame arrives), and a step paused again returns when view.close() is called;
    with pause_timeout a paused step returns after that time by itself.
StaticSlider: tests/view/chamber.yaml, a static run of 4 load steps, writes a frame per load
step with the load factor as its time (0.25 ... 1): the page labels its time the load factor
and moving the slider from its start to its end changes the frame shown (time, screen box and
pixels).
Chambers: the same scene without pressure (straight) seen from above: the rod (a section given by its
stiffness, drawn by visual_radius = 10 mm) covers 20 mm, the chamber (area 50 mm^2, 5 mm on the
-y side) is drawn in its colour on that side only, and hide=chambers removes it.
Exit status 77 (a skip for ctest) only when Chromium or python3-websockets is not installed.
"""

import argparse
import io
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import threading
import time
import unittest

ARGS = None
BACKGROUND = (245, 246, 248)  # the page's clear colour, 0xf5f6f8
CHAMBER_RGB = (30, 158, 60)   # 0x1e9e3c, the chambers' colour (lit: compared loosely)
READY = "['ready', 'error'].includes(document.body.dataset.state)"


def wait_for(predicate, timeout=20.0, step=0.02):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(step)
    return predicate()


class LiveView(unittest.TestCase):
    CAMERA = "view=front&ortho=1&target=0.1,0,0.05&span=0.4"

    @classmethod
    def setUpClass(cls):
        sys.path.insert(0, ARGS.python)
        sys.path.insert(0, os.path.join(ARGS.source, "tools"))
        import screwfem
        import screwfem_chromium

        scene = screwfem.load_scene(os.path.join(ARGS.source, "tests", "view", "true_size.yaml"))
        cls.sim = screwfem.Simulation(scene)
        cls.sim.initialize()
        # A small window: this test reads no pixels, and software WebGL's time goes with them.
        cls.browser = screwfem_chromium.Chromium(480, 360)

    @classmethod
    def tearDownClass(cls):
        cls.browser.close()

    def page(self):
        return self.browser.evaluate(
            "({state: document.body.dataset.state, live: document.body.dataset.live,"
            " received: Number(document.body.dataset.received), frames: Number(document.body.dataset.frames),"
            " time: Number(document.body.dataset.time), paused: document.body.dataset.paused,"
            " bbox: document.body.dataset.bbox, label: document.getElementById('time').textContent,"
            " errors: document.getElementById('errors').textContent})")

    def click_pause(self):
        self.browser.evaluate("document.getElementById('live-pause').click()")

    def test_frames_arrive_and_pause_blocks(self):
        sim = self.sim
        with sim.view(max_rate=0) as view:
            self.assertRegex(view.url, r"^http://127\.0\.0\.1:\d+/$")
            # No page: stepping builds nothing.
            t_start = time.perf_counter()
            for _ in range(5):
                sim.step()
            alone = time.perf_counter() - t_start
            self.assertEqual(view.frames_sent, 0)
            # The page connects and follows 10 steps.
            self.browser.load(view.url + "?" + self.CAMERA, READY)
            self.assertTrue(wait_for(lambda: view.clients == 1))
            self.assertTrue(wait_for(lambda: self.page()["live"] == "open"))
            start = self.page()
            self.assertEqual(start["errors"], "")
            self.assertEqual(start["received"], 0)
            t0 = sim.time
            self.assertAlmostEqual(start["time"], t0, places=5)
            for _ in range(10):
                sim.step()
            self.assertEqual(view.frames_sent, 10)
            after = wait_for(lambda: (lambda p: p if p["received"] == 10 and
                                      abs(p["time"] - sim.time) < 1e-6 else None)(self.page()))
            self.assertIsNotNone(after, self.page())
            self.assertEqual(after["frames"], 11)  # the page's first frame and 10 more
            self.assertGreater(after["time"], start["time"])
            self.assertIn(f"t = {sim.time:.3f} s", after["label"])
            # The same picture as a page loaded afresh at this state (its first frame).
            live_bbox = after["bbox"]
            print(f"5 steps without a page: {alone * 1e3:.1f} ms; live page at t = "
                  f"{after['time']:.4f} s, box {live_bbox}", file=sys.stderr)

            # Pause from the page: a step does not return until the page resumes.
            self.click_pause()
            self.assertTrue(wait_for(lambda: view.paused))
            self.assertTrue(wait_for(lambda: self.page()["paused"] == "1"))
            done = threading.Event()
            worker = threading.Thread(target=lambda: (sim.step(), done.set()))
            worker.start()
            self.assertFalse(done.wait(0.8), "the step returned while paused")
            # Its frame has arrived: the page shows the step it waits after.
            self.assertTrue(wait_for(lambda: self.page()["received"] == 11))
            self.click_pause()  # resume
            self.assertTrue(done.wait(10), "the step did not return after resuming")
            worker.join()
            self.assertFalse(view.paused)
            self.assertTrue(wait_for(lambda: self.page()["paused"] == "0"))
            # Paused again, close() releases the step.
            self.click_pause()
            self.assertTrue(wait_for(lambda: view.paused))
            done.clear()
            worker = threading.Thread(target=lambda: (sim.step(), done.set()))
            worker.start()
            self.assertFalse(done.wait(0.5))
            t_close = time.perf_counter()
            view.close()
            self.assertTrue(done.wait(5), "close() did not release the paused step")
            print(f"close() released the paused step in {time.perf_counter() - t_close:.2f} s",
                  file=sys.stderr)
            worker.join()
            self.assertTrue(wait_for(lambda: self.page()["live"] == "closed"))
        # Closed: no hook left, stepping goes on.
        self.assertIsNone(sim._step_hook())
        sim.step()

        # A fresh page at the same state as the live one showed (the state after the 10 steps
        # is gone now: compare a new live page with itself after one step instead).
        with sim.view(max_rate=0) as view:
            self.browser.load(view.url + "?" + self.CAMERA, READY)
            self.assertTrue(wait_for(lambda: self.page()["live"] == "open"))
            sim.step()
            live = wait_for(lambda: (lambda p: p if p["received"] == 1 else None)(self.page()))
            self.assertIsNotNone(live)
            wait_for(lambda: abs(self.page()["time"] - sim.time) < 1e-6)
            live = self.page()
            self.browser.load(view.url + "?" + self.CAMERA, READY)
            fresh = self.page()
            self.assertAlmostEqual(fresh["time"], live["time"], places=5)
            self.assertEqual(fresh["bbox"], live["bbox"])
        self.assertEqual(self.browser.console_problems(), [])
        self.assertNotEqual(live_bbox, "")

    def test_pause_timeout_and_no_second_view(self):
        sim = self.sim
        with sim.view(max_rate=0, pause_timeout=0.3) as view:
            with self.assertRaisesRegex(RuntimeError, "has a live view already"):
                sim.view()
            self.browser.load(view.url, READY)
            self.assertTrue(wait_for(lambda: self.page()["live"] == "open"))
            self.click_pause()
            self.assertTrue(wait_for(lambda: view.paused))
            start = time.perf_counter()
            sim.step()
            waited = time.perf_counter() - start
            self.assertGreaterEqual(waited, 0.25)
            self.assertLess(waited, 3.0)
            print(f"paused step with pause_timeout = 0.3 s returned after {waited:.2f} s",
                  file=sys.stderr)


def run_chamber_scene(tmp, overrides):
    outdir = os.path.join(tmp, "chamber")
    scene = os.path.join(ARGS.source, "tests", "view", "chamber.yaml")
    subprocess.run([ARGS.screwfem, "run", scene, "-o", outdir, "--quiet"] +
                   [a for o in overrides for a in ("--set", o)], check=True,
                   stdout=subprocess.DEVNULL)
    page = os.path.join(tmp, "chamber.html")
    view = subprocess.run([ARGS.screwfem, "view", outdir, "-o", page], capture_output=True,
                          text=True)
    assert view.returncode == 0, view.stderr
    return outdir, pathlib.Path(page).as_uri()


class PixelTest(unittest.TestCase):
    OVERRIDES = ()

    @classmethod
    def setUpClass(cls):
        sys.path.insert(0, os.path.join(ARGS.source, "tools"))
        import numpy as np
        from PIL import Image

        import screwfem_chromium

        cls.np, cls.Image = np, Image
        cls.tmp = tempfile.TemporaryDirectory(prefix="screwfem-live-test-")
        cls.outdir, cls.url = run_chamber_scene(cls.tmp.name, cls.OVERRIDES)
        cls.browser = screwfem_chromium.Chromium(800, 600)

    @classmethod
    def tearDownClass(cls):
        cls.browser.close()
        cls.tmp.cleanup()

    def pixels(self):
        png = self.browser.screenshot()
        return self.np.asarray(self.Image.open(io.BytesIO(png)).convert("RGB")).astype(int)

    def state(self):
        return self.browser.evaluate(
            "({state: document.body.dataset.state, time: Number(document.body.dataset.time),"
            " bbox: document.body.dataset.bbox, label: document.getElementById('time').textContent,"
            " errors: document.getElementById('errors').textContent})")


class StaticSlider(PixelTest):
    def test_slider_moves_through_the_load_steps(self):
        with open(os.path.join(self.outdir, "vtk", "motion.pvd")) as f:
            pvd = f.read()
        self.assertEqual(pvd.count("<DataSet"), 4)  # a frame per load step
        for lam in ('"0.25"', '"0.5"', '"0.75"', '"1"'):
            self.assertIn("timestep=" + lam, pvd)
        self.browser.load(self.url + "?bare=1&t=0", READY)
        start, start_png = self.state(), self.pixels()
        self.assertEqual(start["errors"], "")
        self.assertAlmostEqual(start["time"], 0.25)  # the first load step
        self.assertIn("\u03bb = 0.250", start["label"])
        self.assertIn("load factor", start["label"])
        self.browser.evaluate("(function () { var s = document.getElementById('slider');"
                              " s.value = 500; s.dispatchEvent(new Event('input')); })()")
        half = self.state()
        self.browser.evaluate("(function () { var s = document.getElementById('slider');"
                              " s.value = s.max; s.dispatchEvent(new Event('input')); })()")
        end, end_png = self.state(), self.pixels()
        self.assertAlmostEqual(half["time"], 0.625)  # between the 2nd and 3rd load steps
        self.assertAlmostEqual(end["time"], 1.0)
        self.assertIn("\u03bb = 1.000", end["label"])
        self.assertNotEqual(start["bbox"], half["bbox"])
        self.assertNotEqual(half["bbox"], end["bbox"])
        changed = (self.np.abs(start_png - end_png).sum(axis=2) > 24).mean()
        self.assertGreater(changed, 0.005)
        # The slider's end is the frame of ?t=1.
        self.browser.load(self.url + "?bare=1&t=1", READY)
        self.assertEqual(self.state()["bbox"], end["bbox"])


class Chambers(PixelTest):
    # Without pressure the rod stays straight along x at every load step.
    OVERRIDES = ("actuation.chamber.pressure.value=0",)
    WIDTH, SPAN, TARGET = 800, 0.16, (0.05, 0.0, 0.0)

    def screen(self, x, y):
        px = self.WIDTH / self.SPAN
        return (self.WIDTH / 2 + (x - self.TARGET[0]) * px, 300 - (y - self.TARGET[1]) * px)

    def test_chamber_is_drawn_inside_the_rod(self):
        camera = (f"bare=1&t=0&view=top&ortho=1&target={','.join(map(str, self.TARGET))}"
                  f"&span={self.SPAN}")
        self.browser.load(f"{self.url}?{camera}", READY)
        self.assertEqual(self.state()["errors"], "")
        shown = self.pixels()
        self.browser.load(f"{self.url}?{camera}&hide=chambers", READY)
        hidden = self.pixels()
        px = self.WIDTH / self.SPAN
        fg = self.np.abs(hidden - self.np.array(BACKGROUND)).sum(axis=2) > 24
        # The chamber's green over the rod's blue: green above red and blue (the rod's pixels
        # are bluer than green, the background grey).
        green = (shown[..., 1] > shown[..., 0] + 40) & (shown[..., 1] > shown[..., 2])
        for x in (0.03, 0.05, 0.07):
            col, row = (int(round(v)) for v in self.screen(x, 0.0))
            # The rod: 20 mm across (visual_radius 10 mm), without the chamber.
            column = fg[:, col]
            lo, hi = row, row
            while lo > 0 and column[lo - 1]:
                lo -= 1
            while hi + 1 < len(column) and column[hi + 1]:
                hi += 1
            self.assertAlmostEqual((hi - lo + 1) / px, 0.020, delta=0.002, msg=f"x = {x}")
            # The chamber: on the -y side (below the axis on the screen: rows > row), between
            # y = -9 and -1 mm, and nowhere on the +y side.
            below = green[int(row + 0.002 * px):int(row + 0.008 * px), col]
            above = green[int(row - 0.008 * px):int(row - 0.002 * px), col]
            self.assertGreater(below.mean(), 0.9, f"x = {x}")
            self.assertEqual(above.sum(), 0, f"x = {x}")
            print(f"x = {x}: rod {(hi - lo + 1)} px (expected {0.02 * px:.0f}), chamber rows "
                  f"{int(below.sum())} of {below.size}", file=sys.stderr)
        hidden_green = (hidden[..., 1] > hidden[..., 0] + 40) & (hidden[..., 1] > hidden[..., 2])
        self.assertEqual(int(hidden_green.sum()), 0)
        self.assertGreater(int(green.sum()), 1000)
        self.assertEqual(self.browser.console_problems(), [])


def main():
    global ARGS
    parser = argparse.ArgumentParser()
    parser.add_argument("--screwfem", required=True, help="the screwfem program")
    parser.add_argument("--source", required=True, help="repository root")
    parser.add_argument("--python", default="", help="the directory holding the screwfem "
                        "package (the build tree's python/; LiveView only)")
    ARGS, rest = parser.parse_known_args()
    sys.path.insert(0, os.path.join(ARGS.source, "tools"))
    import screwfem_chromium

    if screwfem_chromium.find_chromium() is None:
        print("SKIPPED: chromium is not installed (Debian package chromium; "
              "scripts/setup-deps.sh installs it)")
        return 77
    try:
        import websockets  # noqa: F401
    except ImportError:
        print("SKIPPED: python3-websockets is not installed (scripts/setup-deps.sh installs it)")
        return 77
    result = unittest.main(argv=[sys.argv[0]] + rest, exit=False, verbosity=2).result
    return 0 if result.wasSuccessful() else 1


if __name__ == "__main__":
    sys.exit(main())

"""The viewer draws the robot as it is: sizes, tendons and contact forces in headless Chromium.

    true_size_test.py --screwfem PATH/TO/screwfem --source REPO_ROOT

Runs tests/view/true_size.yaml for 0.1 s (a 40 mm box resting on a plane, a 16 mm rod with a
tendon 16 mm above its axis pulling with 1 N), writes its viewer page and looks at it from the
front with an orthographic camera of known span (URL: view=front, ortho=1, target, span), so
that a metre covers WIDTH / SPAN pixels:
  * the box covers 40 mm and the rod 16 mm of the picture, within 10 %;
  * the tendon is drawn above the rod in the colour of its tension (the top of the ramp: it
    pulls with the run's largest tension), and the box's contact forces as red arrows at its
    bottom corners, pointing up;
  * hiding the layers (hide=tendons,forces) removes those pixels.
And with plain headless Chromium (`chromium --headless --screenshot`, no DevTools), pages with
`?t=` and without any parameter are captured within a time limit (a paused page requests no
animation frames; a playing one still lets the screenshot happen).
Exit status 77 (a skip for ctest) only when no Chromium is installed.
"""

import argparse
import io
import os
import pathlib
import subprocess
import sys
import tempfile
import time
import unittest

ARGS = None
BACKGROUND = (245, 246, 248)  # the page's clear colour, 0xf5f6f8
WIDTH, HEIGHT = 800, 600
SPAN = 0.24                    # metres across the picture
TARGET = (0.08, 0.0, 0.03)     # the picture's centre (world)
PX = WIDTH / SPAN              # pixels per metre
TENDON_RGB = (122, 5, 3)       # the ramp's top, 0.48 0.02 0.01 (unlit)
ARROW_RGB = (227, 26, 28)      # 0xe31a1c (unlit)


def screen(x, z):
    """Pixel (column, row) of the world point (x, *, z) in the front view."""
    return (WIDTH / 2 + (x - TARGET[0]) * PX, HEIGHT / 2 - (z - TARGET[2]) * PX)


class TrueSize(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        sys.path.insert(0, os.path.join(ARGS.source, "tools"))
        import numpy as np
        from PIL import Image

        import screwfem_chromium

        cls.np, cls.Image, cls.chromium = np, Image, screwfem_chromium
        cls.tmp = tempfile.TemporaryDirectory(prefix="screwfem-true-size-")
        outdir = os.path.join(cls.tmp.name, "run")
        scene = os.path.join(ARGS.source, "tests", "view", "true_size.yaml")
        subprocess.run([ARGS.screwfem, "run", scene, "-o", outdir, "--quiet"], check=True,
                       stdout=subprocess.DEVNULL)
        cls.page = os.path.join(cls.tmp.name, "view.html")
        view = subprocess.run([ARGS.screwfem, "view", outdir, "-o", cls.page],
                              capture_output=True, text=True)
        assert view.returncode == 0, view.stderr
        cls.url = pathlib.Path(cls.page).as_uri()
        camera = (f"bare=1&t=0.1&view=front&ortho=1&target={','.join(map(str, TARGET))}"
                  f"&span={SPAN}&force_scale=0.1")
        ready = "['ready', 'error'].includes(document.body.dataset.state)"
        with screwfem_chromium.Chromium(WIDTH, HEIGHT) as browser:
            browser.load(f"{cls.url}?{camera}", ready)
            cls.errors = browser.evaluate("document.getElementById('errors').textContent")
            cls.projected = browser.evaluate("window.screwfemProject(0.02, 0, 0.04)")
            cls.shot = cls.pixels(browser.screenshot())
            browser.load(f"{cls.url}?{camera}&hide=tendons,forces", ready)
            cls.hidden = cls.pixels(browser.screenshot())
            cls.problems = browser.console_problems()

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    @classmethod
    def pixels(cls, png):
        return cls.np.asarray(cls.Image.open(io.BytesIO(png)).convert("RGB")).astype(int)

    def foreground(self, img):
        return self.np.abs(img - self.np.array(BACKGROUND)).sum(axis=2) > 24

    def run_through(self, line, at):
        """Length [px] of the run of foreground pixels in `line` that contains index `at`."""
        if not line[at]:
            return 0
        lo, hi = at, at
        while lo > 0 and line[lo - 1]:
            lo -= 1
        while hi + 1 < len(line) and line[hi + 1]:
            hi += 1
        return hi - lo + 1

    def near(self, img, rgb, tolerance=40):
        return self.np.abs(img - self.np.array(rgb)).max(axis=2) <= tolerance

    def test_page_loads_without_errors(self):
        self.assertEqual(self.problems, [])
        self.assertEqual(self.errors, "")
        # The page's camera is the one the URL asked for: the box's top corner lands where the
        # test computes it.
        x, y = screen(0.02, 0.04)
        self.assertAlmostEqual(self.projected[0], x, delta=0.5)
        self.assertAlmostEqual(self.projected[1], y, delta=0.5)

    def test_box_covers_40_mm(self):
        # Rows through the box's upper half (above the arrows at its bottom corners).
        mask = self.foreground(self.shot)
        cx, _ = screen(0.0, 0.0)
        for z in (0.026, 0.03, 0.035):
            _, row = screen(0.0, z)
            width = self.run_through(mask[int(round(row))], int(round(cx)))
            self.assertAlmostEqual(width / PX, 0.040, delta=0.004, msg=f"z = {z}: {width} px")
            print(f"box at z = {z} m: {width} px, expected {0.04 * PX:.1f}", file=sys.stderr)

    def test_rod_covers_16_mm(self):
        mask = self.foreground(self.hidden)  # without the tendon above it
        for x in (0.09, 0.12, 0.15):
            col, row = screen(x, 0.05)
            height = self.run_through(mask[:, int(round(col))], int(round(row)))
            self.assertAlmostEqual(height / PX, 0.016, delta=0.0016, msg=f"x = {x}: {height} px")
            print(f"rod at x = {x} m: {height} px, expected {0.016 * PX:.1f}", file=sys.stderr)

    def test_tendon_is_drawn_in_its_tension_colour(self):
        # The tendon runs 16 mm above the rod's axis: in a band of rows around z = 0.066.
        c0, _ = screen(0.08, 0)
        c1, _ = screen(0.16, 0)
        _, r0 = screen(0, 0.072)
        _, r1 = screen(0, 0.060)
        band = (slice(int(r0), int(r1)), slice(int(c0), int(c1)))
        drawn = self.near(self.shot[band], TENDON_RGB).sum()
        self.assertGreater(drawn, 0.5 * (c1 - c0))  # at least a pixel high along its length
        self.assertEqual(self.near(self.hidden[band], TENDON_RGB).sum(), 0)

    def test_contact_forces_are_arrows_up_from_the_bottom_corners(self):
        for corner in (-0.02, 0.02):
            c, _ = screen(corner, 0)
            _, top = screen(0, 0.018)
            _, bottom = screen(0, 0.0)
            region = (slice(int(top), int(bottom) + 1), slice(int(c) - 12, int(c) + 13))
            red = self.near(self.shot[region], ARROW_RGB)
            self.assertGreater(red.sum(), 100, f"corner x = {corner}")
            self.assertEqual(self.near(self.hidden[region], ARROW_RGB).sum(), 0)
            # Up: the head (widest rows) is at the top of the arrow.
            rows = self.np.nonzero(red.sum(axis=1))[0]
            widths = red.sum(axis=1)
            self.assertLess(self.np.argmax(widths), rows.mean())


class PlainHeadless(unittest.TestCase):
    """`chromium --headless --screenshot URL` for the URL forms: it must finish and show the
    mechanism."""

    @classmethod
    def setUpClass(cls):
        sys.path.insert(0, os.path.join(ARGS.source, "tools"))
        import numpy as np
        from PIL import Image

        import screwfem_chromium

        cls.np, cls.Image, cls.exe = np, Image, screwfem_chromium.find_chromium()
        cls.tmp = tempfile.TemporaryDirectory(prefix="screwfem-headless-")
        outdir = os.path.join(cls.tmp.name, "run")
        scene = os.path.join(ARGS.source, "tests", "view", "true_size.yaml")
        subprocess.run([ARGS.screwfem, "run", scene, "-o", outdir, "--quiet"], check=True,
                       stdout=subprocess.DEVNULL)
        cls.page = os.path.join(cls.tmp.name, "view.html")
        subprocess.run([ARGS.screwfem, "view", outdir, "-o", cls.page], check=True,
                       capture_output=True)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def capture(self, query, extra=()):
        png = os.path.join(self.tmp.name, "shot.png")
        if os.path.exists(png):
            os.remove(png)
        url = pathlib.Path(self.page).as_uri() + query
        start = time.monotonic()
        subprocess.run([self.exe, "--headless", "--no-sandbox", "--enable-unsafe-swiftshader",
                        "--use-angle=swiftshader", f"--screenshot={png}",
                        f"--window-size={WIDTH},{HEIGHT}", "--hide-scrollbars", *extra, url],
                       stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL, timeout=60,
                       env=dict(os.environ, DBUS_SESSION_BUS_ADDRESS="disabled:"))
        print(f"{query or '(no query)'} {' '.join(extra)}: {time.monotonic() - start:.1f} s",
              file=sys.stderr)
        self.assertTrue(os.path.isfile(png), query)
        with self.Image.open(png) as image:
            img = self.np.asarray(image.convert("RGB")).astype(int)
        blue = (img[..., 2] > img[..., 0] + 60)  # the rods
        self.assertGreater(blue.sum(), 200, query)

    def test_paused_at_a_time(self):
        self.capture("?t=0.05&bare=1")

    def test_playing_with_a_virtual_time_budget(self):
        self.capture("", ["--virtual-time-budget=1000"])


def main():
    global ARGS
    parser = argparse.ArgumentParser()
    parser.add_argument("--screwfem", required=True, help="the screwfem program")
    parser.add_argument("--source", required=True, help="repository root")
    ARGS, rest = parser.parse_known_args()
    sys.path.insert(0, os.path.join(ARGS.source, "tools"))
    import screwfem_chromium

    if screwfem_chromium.find_chromium() is None:
        print("SKIPPED: chromium is not installed (Debian package chromium; "
              "scripts/setup-deps.sh installs it)")
        return 77
    result = unittest.main(argv=[sys.argv[0]] + rest, exit=False, verbosity=2).result
    return 0 if result.wasSuccessful() else 1


if __name__ == "__main__":
    sys.exit(main())

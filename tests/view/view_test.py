"""The browser viewer (`screwfem view`, tools/screwfem_view.py) in headless Chromium.

    view_test.py --screwfem PATH/TO/screwfem --source REPO_ROOT

Runs the rigid GRM for 1 s (4 elements per soft body), writes its viewer page and loads it in
one headless Chromium through the DevTools protocol (tools/screwfem_chromium.py):
  * the page loads from file:// without console errors or exceptions and is self-contained
    (no script, style or image is fetched from elsewhere);
  * the mechanism is drawn: with ?bare=1 (no grid, axes or controls) the pixels that differ
    from the background are plentiful, lie inside the screen box the page reports for the
    mechanism's points, and include the rods' blue and the actuated joints' orange;
  * moving the time slider from 0 to the end changes the picture, and the picture at the end
    equals the one the URL hook ?t=END shows;
  * without ?t= the page plays: its time advances.
Exit status 77 (a skip for ctest) only when no Chromium is installed.
"""

import argparse
import io
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import unittest

ARGS = None
BACKGROUND = (245, 246, 248)  # the page's clear colour, 0xf5f6f8


def tools_dir():
    return os.path.join(ARGS.source, "tools")


class ViewerInChromium(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        sys.path.insert(0, tools_dir())
        import numpy as np
        from PIL import Image

        import screwfem_chromium

        cls.np, cls.Image = np, Image
        cls.tmp = tempfile.TemporaryDirectory(prefix="screwfem-view-test-")
        outdir = os.path.join(cls.tmp.name, "grm_rigid")
        scene = os.path.join(ARGS.source, "examples", "grm", "grm_rigid.yaml")
        subprocess.run([ARGS.screwfem, "run", scene, "-o", outdir, "--quiet",
                        "--set", "analysis.end_time=1", "--set", "defaults.elements=4"],
                       check=True, stdout=subprocess.DEVNULL)
        cls.page = os.path.join(cls.tmp.name, "grm rigid view.html")  # a space: URL quoting
        view = subprocess.run([ARGS.screwfem, "view", outdir, "-o", cls.page],
                              capture_output=True, text=True)
        assert view.returncode == 0, view.stderr
        cls.view_stderr = view.stderr
        cls.url = pathlib.Path(cls.page).as_uri()
        cls.browser = screwfem_chromium.Chromium(800, 600)
        cls.ready = "['ready', 'error'].includes(document.body.dataset.state)"

        def state():
            return cls.browser.evaluate(
                "({state: document.body.dataset.state, time: Number(document.body.dataset.time),"
                " bbox: (document.body.dataset.bbox || '').split(',').map(Number),"
                " errors: document.getElementById('errors').textContent})")

        cls.state = staticmethod(state)
        # t = 0, then the slider moved to its end, then the URL hook at the end time.
        cls.browser.load(cls.url + "?bare=1&t=0", cls.ready)
        cls.start = (state(), cls.browser.screenshot())
        cls.browser.evaluate("(function () { var s = document.getElementById('slider');"
                             " s.value = s.max; s.dispatchEvent(new Event('input')); })()")
        cls.slid = (state(), cls.browser.screenshot())
        cls.browser.load(cls.url + "?bare=1&t=1", cls.ready)
        cls.hooked = (state(), cls.browser.screenshot())
        # The full page, playing.
        cls.browser.load(cls.url, cls.ready)
        cls.browser.evaluate("document.getElementById('loop').checked = false")
        cls.playing_start = state()
        # Waits (at most 20 s, for a loaded machine) until the time has moved on.
        cls.browser.evaluate(
            "new Promise(function (done) { var t0 = document.body.dataset.time, n = 0;"
            " var id = setInterval(function () { if (document.body.dataset.time !== t0 || ++n > 400)"
            " { clearInterval(id); done(); } }, 50); })")
        cls.playing_later = state()
        cls.problems = cls.browser.console_problems()

    @classmethod
    def tearDownClass(cls):
        cls.browser.close()
        cls.tmp.cleanup()

    def pixels(self, png):
        return self.np.asarray(self.Image.open(io.BytesIO(png)).convert("RGB")).astype(int)

    def foreground(self, png):
        """Mask of the pixels that differ from the background."""
        img = self.pixels(png)
        return self.np.abs(img - self.np.array(BACKGROUND)).sum(axis=2) > 24, img

    def test_page_loads_without_errors(self):
        self.assertEqual(self.problems, [])
        for state in (self.start[0], self.slid[0], self.hooked[0], self.playing_start):
            self.assertEqual(state["state"], "ready", state["errors"])
            self.assertEqual(state["errors"], "")

    def test_page_is_self_contained(self):
        with open(self.page, encoding="utf-8") as f:
            html = f.read()
        self.assertNotRegex(html, r"<script[^>]*\bsrc=")
        self.assertNotRegex(html, r"<link[^>]*\bhref=")
        self.assertNotRegex(html, r"<img[^>]*\bsrc=")
        self.assertIn('"name":"GRM, case 1: rigid joints"', html)
        self.assertIn("no strain or stress", self.view_stderr)

    def test_mechanism_is_drawn_inside_its_screen_box(self):
        for state, png in (self.start, self.slid):
            mask, img = self.foreground(png)
            h, w = mask.shape
            self.assertEqual(tuple(img[2, 2]), BACKGROUND)
            self.assertGreater(mask.sum(), 0.01 * w * h)  # at least 1 % of the window
            x0, y0, x1, y1 = state["bbox"]
            # The page frames the whole motion: the mechanism is inside the window and spans
            # a good part of it.
            self.assertGreaterEqual(x0, 0)
            self.assertGreaterEqual(y0, 0)
            self.assertLessEqual(x1, w)
            self.assertLessEqual(y1, h)
            self.assertGreater(max((x1 - x0) / w, (y1 - y0) / h), 0.2)
            # Drawn pixels lie within the box of the projected points, widened by the tube,
            # box and sphere sizes (a few per cent of the window).
            m = int(0.04 * max(w, h))
            ys, xs = self.np.nonzero(mask)
            inside = (xs >= x0 - m) & (xs <= x1 + m) & (ys >= y0 - m) & (ys <= y1 + m)
            self.assertGreater(inside.mean(), 0.999)
            # Rods (blue tubes) and actuated joints (orange spheres) are among them.
            r, g, b = img[..., 0], img[..., 1], img[..., 2]
            self.assertGreater(((b > r + 40) & mask).sum(), 200)
            self.assertGreater(((r > b + 60) & (g > b) & mask).sum(), 30)

    def test_slider_changes_the_picture(self):
        self.assertAlmostEqual(self.start[0]["time"], 0.0)
        self.assertAlmostEqual(self.slid[0]["time"], 1.0)
        before, after = self.pixels(self.start[1]), self.pixels(self.slid[1])
        changed = (self.np.abs(before - after).sum(axis=2) > 24).mean()
        self.assertGreater(changed, 0.005)
        self.assertNotEqual(self.start[0]["bbox"], self.slid[0]["bbox"])

    def test_url_time_shows_the_same_picture_as_the_slider(self):
        self.assertAlmostEqual(self.hooked[0]["time"], 1.0)
        self.assertEqual(self.hooked[0]["bbox"], self.slid[0]["bbox"])
        a, b = self.pixels(self.hooked[1]), self.pixels(self.slid[1])
        self.assertLess((self.np.abs(a - b).sum(axis=2) > 24).mean(), 1e-3)

    def test_page_plays_without_a_time_parameter(self):
        # Without looping, the time advances until it stops at the end (1 s).
        later, start = self.playing_later["time"], self.playing_start["time"]
        self.assertTrue(later > start or later == 1.0, f"{start} -> {later}")


# Names that broke the page: '<!--<script>' in the data put the HTML tokenizer into its escaped
# script state, so that no later </script> ended the data element (a blank page).
HOSTILE_NAME = "<!--<script></script><b>&amp; \"q\" 'a' \u2028 $x$"


class HostileNames(unittest.TestCase):
    """A scene and a run folder named with HTML and script markup: the page works and shows
    the name as text."""

    def test_hostile_scene_name_is_text(self):
        import screwfem_chromium

        with tempfile.TemporaryDirectory(prefix="screwfem-view-names-") as tmp:
            outdir = os.path.join(tmp, "run <!--<script>")
            scene = os.path.join(ARGS.source, "tests", "data", "pendulum.yaml")
            subprocess.run([ARGS.screwfem, "run", scene, "-o", outdir, "--quiet",
                            "--set", "analysis.end_time=0.1", "--set", "name=" + HOSTILE_NAME],
                           check=True, stdout=subprocess.DEVNULL)
            page = os.path.join(tmp, "view.html")
            view = subprocess.run([ARGS.screwfem, "view", outdir, "-o", page],
                                  capture_output=True, text=True)
            self.assertEqual(view.returncode, 0, view.stderr)
            with open(page, encoding="utf-8") as f:
                text = f.read()
            data = text[text.index('<script id="run-data" type="application/json">'):]
            data = data[data.index(">") + 1:data.index("</script>")]
            self.assertNotIn("<", data)
            self.assertEqual(json.loads(data)["name"], HOSTILE_NAME)
            with screwfem_chromium.Chromium(400, 300) as browser:
                browser.load(pathlib.Path(page).as_uri() + "?bare=1&t=0",
                             "['ready', 'error'].includes(document.body.dataset.state)")
                got = browser.evaluate(
                    "({state: document.body.dataset.state, title: document.title,"
                    " name: JSON.parse(document.getElementById('run-data').textContent).name,"
                    " scripts: document.scripts.length,"
                    " errors: document.getElementById('errors').textContent})")
                problems = browser.console_problems()
            self.assertEqual(got["state"], "ready", got["errors"])
            self.assertEqual(got["title"], HOSTILE_NAME + " - screwfem viewer")
            self.assertEqual(got["name"], HOSTILE_NAME)
            self.assertEqual(got["scripts"], 5)
            self.assertEqual(problems, [])


def main():
    global ARGS
    parser = argparse.ArgumentParser()
    parser.add_argument("--screwfem", required=True, help="the screwfem program")
    parser.add_argument("--source", required=True, help="repository root")
    ARGS, rest = parser.parse_known_args()
    sys.path.insert(0, tools_dir())
    import screwfem_chromium

    if screwfem_chromium.find_chromium() is None:
        print("SKIPPED: chromium is not installed (Debian package chromium; "
              "scripts/setup-deps.sh installs it)")
        return 77
    result = unittest.main(argv=[sys.argv[0]] + rest, exit=False, verbosity=2).result
    return 0 if result.wasSuccessful() else 1


if __name__ == "__main__":
    sys.exit(main())

"""Takes a PNG screenshot of a viewer page (`screwfem view`) at a given time, with headless
Chromium (Debian packages chromium and python3-websocket).

    screwfem_screenshot.py VIEW.html -o FILE.png [--t 1.0] [--size 1200x800] [--query follow=P8]

Exit status: 0 on success, 1 when the page reports an error, 2 on bad input or no browser.
"""

import argparse
import os
import pathlib
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import screwfem_chromium  # noqa: E402


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("page", help="viewer HTML file")
    parser.add_argument("-o", "--output", required=True, help="PNG file to write")
    parser.add_argument("--t", type=float, default=None, help="time to show [s] (default: the start)")
    parser.add_argument("--size", default="1200x800", help="window size WIDTHxHEIGHT [px]")
    parser.add_argument("--query", default="", help="more URL parameters, e.g. bare=1&follow=P8")
    args = parser.parse_args(argv)
    if not os.path.isfile(args.page):
        print(f"error: {args.page} not found", file=sys.stderr)
        return 2
    try:
        width, height = (int(v) for v in args.size.lower().split("x"))
    except ValueError:
        print(f"error: --size {args.size}: expected WIDTHxHEIGHT", file=sys.stderr)
        return 2
    query = [f"t={args.t if args.t is not None else 0}"] + ([args.query] if args.query else [])
    url = pathlib.Path(os.path.abspath(args.page)).as_uri() + "?" + "&".join(query)
    try:
        with screwfem_chromium.Chromium(width, height) as browser:
            browser.load(url, "['ready', 'error'].includes(document.body.dataset.state)")
            problems = browser.console_problems()
            errors = browser.evaluate("document.getElementById('errors').textContent")
            png = browser.screenshot()
    except (screwfem_chromium.BrowserError, ImportError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    with open(args.output, "wb") as f:
        f.write(png)
    if problems or errors:
        print("error: the page reported:\n" + "\n".join(problems + [errors]), file=sys.stderr)
        return 1
    print(args.output)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

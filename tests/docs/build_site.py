"""Builds the documentation site (ctest docs_site) and checks it.

    /usr/bin/python3 tests/docs/build_site.py --source REPO --site DIR [--notebooks DIR]

runs Debian's `mkdocs build --strict` on REPO/mkdocs.yml into DIR. Strict mode fails on every
warning: a nav entry or a linked page or image that does not exist (MkDocs), a link to a
repository file outside docs/ that does not exist, or an anchor that names no heading of its
page (tools/mkdocs_hooks.py). Any other WARNING or ERROR line in MkDocs' log fails too. Then:
every page of the nav and every tutorial notebook has its HTML page; when the tutorial tests
have left executed notebooks in --notebooks (BUILD/tutorials/NAME/NAME.ipynb), every tutorial
page shows its figures (each <img> of an output exists in the site) and says it was executed.
Pages with formulas find MathJax in the site. Last, README.md's links (it is not part of the site): every relative target exists, and an
anchor into a docs page names a heading of that page.
"""

import argparse
import os
import pathlib
import re
import shutil
import subprocess
import sys
import time


def fail(message):
    print("docs_site: FAILED: " + message, flush=True)
    sys.exit(1)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--source", type=pathlib.Path, required=True)
    parser.add_argument("--site", type=pathlib.Path, required=True)
    parser.add_argument("--notebooks", type=pathlib.Path)
    args = parser.parse_args()
    source, site = args.source.resolve(), args.site.resolve()

    mkdocs = shutil.which("mkdocs") or "/usr/bin/mkdocs"
    if not os.path.exists(mkdocs):
        fail("mkdocs not found: install Debian's mkdocs (bash scripts/setup-deps.sh rest)")
    env = dict(os.environ)
    if args.notebooks:
        env["SCREWFEM_EXECUTED_NOTEBOOKS"] = str(args.notebooks.resolve())
    start = time.monotonic()
    run = subprocess.run([mkdocs, "build", "--strict", "--clean", "-f", str(source / "mkdocs.yml"),
                          "-d", str(site)], cwd=source, env=env, capture_output=True, text=True)
    seconds = time.monotonic() - start
    log = run.stdout + run.stderr
    print(log, end="")
    if run.returncode != 0:
        fail("mkdocs build --strict exited with status %d (the warnings are above)"
             % run.returncode)
    bad = [line for line in log.splitlines() if re.match(r"\s*(\x1b\[[0-9;]*m)?(WARNING|ERROR)", line)]
    if bad:
        fail("MkDocs logged warnings or errors:\n" + "\n".join(bad))

    # Every nav page was written.
    nav_pages = re.findall(r":\s*([\w./-]+\.md)\s*$", (source / "mkdocs.yml").read_text(), re.M)
    if not nav_pages:
        fail("no pages found in the nav of mkdocs.yml")
    for page in nav_pages:
        html = site / (page[:-3] + ".html")
        if page.endswith("README.md"):
            html = site / (page[: -len("README.md")] + "index.html")
        if not html.is_file():
            fail("nav page %s was not built (%s missing)" % (page, html))

    # The tutorials, with their figures when the tests executed them.
    notebooks = sorted((source / "docs" / "tutorials").glob("*.ipynb"))
    executed = 0
    for nb in notebooks:
        html = site / "tutorials" / (nb.stem + ".html")
        if not html.is_file():
            fail("tutorial %s has no page (%s)" % (nb.name, html))
        text = html.read_text(encoding="utf-8")
        copy = args.notebooks / nb.stem / nb.name if args.notebooks else None
        if copy is None or not copy.is_file() or copy.stat().st_mtime < nb.stat().st_mtime:
            continue
        executed += 1
        if "as the tests executed it" not in text:
            fail("%s: an executed copy exists (%s) but the page was built without it" % (nb.name, copy))
        images = re.findall(r'<img[^>]*src="([^"]+)"', text)
        outputs = [src for src in images if src.startswith(nb.stem + "_files/")]
        if not outputs:
            fail("%s: the executed tutorial's page shows no figure" % nb.name)
        for src in outputs:
            if not (html.parent / src).is_file():
                fail("%s: figure %s is missing from the site" % (nb.name, src))
    # Formulas: pages with math load MathJax from the site itself.
    with_math = [h for h in site.rglob("*.html") if 'class="arithmatex"' in h.read_text(encoding="utf-8")]
    if with_math and not (site / "js" / "mathjax" / "MathJax.js").is_file():
        fail("%d pages have formulas but the site has no js/mathjax/MathJax.js" % len(with_math))

    # README.md, the repository's front page, is not part of the site; its links are checked
    # here: every relative target exists, and an anchor into a docs page names an id of its page.
    readme = (source / "README.md").read_text(encoding="utf-8")
    readme_links = 0
    for target in re.findall(r"\]\(([^()\s]+)\)", re.sub(r"```.*?```", "", readme, flags=re.S)):
        if re.match(r"[a-z]+:", target):
            continue
        readme_links += 1
        path, _, anchor = target.partition("#")
        if path and not (source / path).exists():
            fail("README.md links to %s, which does not exist" % target)
        if anchor:
            if not path.startswith("docs/") or not path.endswith(".md"):
                fail("README.md: cannot check the anchor of %s" % target)
            page = site / (path[len("docs/"):-3] + ".html")
            if not re.search(r'\sid="%s"' % re.escape(anchor), page.read_text(encoding="utf-8")):
                fail("README.md links to %s: no heading '%s' on that page" % (target, anchor))
    print("docs_site: %d pages in the nav, %d tutorials (%d with their outputs), built in %.1f s "
          "into %s; README.md's %d links checked" % (len(nav_pages), len(notebooks), executed,
                                                    seconds, site, readme_links), flush=True)


if __name__ == "__main__":
    main()

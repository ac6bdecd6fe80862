"""MkDocs hooks of the documentation site (mkdocs.yml; Debian's mkdocs 1.4, no plugins).

1. Tutorials. Every docs/tutorials/NAME.ipynb becomes the page tutorials/NAME.md, converted
   with nbconvert's Markdown exporter when the site is built (nothing generated is committed).
   The notebooks are committed without outputs; the executed copies that the tests write
   (ctest tutorial_NAME: BUILD/tutorials/NAME/NAME.ipynb) are used when they exist and are
   newer than the notebook, so the pages show the outputs and figures. The build trees searched
   are $SCREWFEM_EXECUTED_NOTEBOOKS, else build/release/tutorials and build/main/tutorials. A
   page built without an executed copy says so. Links to NAME.ipynb from other pages point to
   the page. A notebook missing from the nav is a warning.
2. Links to repository files outside docs/ (`[gripper.yaml](../examples/gripper/gripper.yaml)`)
   stay valid in the repository view; in the site, where those files do not exist, they become
   code references (`examples/gripper/gripper.yaml`). A link whose file is missing from the
   repository is a warning.
3. Anchors. MkDocs 1.4 checks that a linked page exists, not the part after '#': every
   `page.md#anchor` and `#anchor` link must name a heading (or another id) of its target page.

4. Math. Pages write $...$ and $$...$$ (pymdownx.arithmatex in generic mode, mkdocs.yml); MathJax
   2 typesets them in the browser. The part of Debian's libjs-mathjax that its TeX-AMS_CHTML
   configuration loads (1.6 MB) is copied into the site's js/mathjax/, so the site works offline
   and from file://; js/mathjax-config.js tells MathJax to read arithmatex's delimiters only.

Warnings go through the `mkdocs` logger, so `mkdocs build --strict` fails on them
(tests/docs/build_site.py, ctest docs_site).
"""

import html
import logging
import os
import pathlib
import posixpath
import re
import shutil
import tempfile
import warnings
from urllib.parse import unquote, urlsplit

from mkdocs.structure.files import File

log = logging.getLogger("mkdocs.hooks.screwfem")

_generated = {}      # src_uri of a generated tutorial page -> notebook path (for messages)
_ids = {}            # page url -> set of element ids in its content
_links = []          # (page src_uri, page url, target url, fragment)
_tmp = None


def _repo_root(config):
    return pathlib.Path(config["config_file_path"]).resolve().parent


def _executed_copy(root, notebook):
    dirs = []
    if os.environ.get("SCREWFEM_EXECUTED_NOTEBOOKS"):
        dirs.append(pathlib.Path(os.environ["SCREWFEM_EXECUTED_NOTEBOOKS"]))
    dirs += [root / "build" / "release" / "tutorials", root / "build" / "main" / "tutorials"]
    for d in dirs:
        copy = d / notebook.stem / notebook.name
        if copy.is_file() and copy.stat().st_mtime >= notebook.stat().st_mtime:
            return copy
    return None


def _convert(notebook, source, outdir, name):
    from nbconvert import MarkdownExporter  # Debian's python3-nbconvert (jupyter-nbconvert)

    exporter = MarkdownExporter()
    with warnings.catch_warnings():  # nbformat's deprecation notice about nbconvert's own call
        warnings.simplefilter("ignore", DeprecationWarning)
        body, resources = exporter.from_filename(
            str(source), resources={"unique_key": name, "output_files_dir": name + "_files"})
    files = []
    for rel, data in (resources.get("outputs") or {}).items():
        path = outdir / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
        files.append(rel)
    return body, files


def on_files(files, config):
    global _tmp
    root = _repo_root(config)
    docs = pathlib.Path(config["docs_dir"])
    _generated.clear()
    _tmp = tempfile.TemporaryDirectory(prefix="screwfem-site-")
    src_dir = pathlib.Path(_tmp.name)
    for notebook in sorted((docs / "tutorials").glob("*.ipynb")):
        name = notebook.stem
        outdir = src_dir / "tutorials"
        outdir.mkdir(parents=True, exist_ok=True)
        executed = _executed_copy(root, notebook)
        body, outputs = _convert(notebook, executed or notebook, outdir, name)
        note = ("*This page is `docs/tutorials/%s`%s.*\n\n" % (
            notebook.name,
            ", as the tests executed it" if executed else
            ", shown without its outputs: they appear when the site is built after the tests "
            "have executed it (ctest `tutorial_%s`)" % name))
        (outdir / (name + ".md")).write_text(note + body, encoding="utf-8")
        uri = "tutorials/%s.md" % name
        files.append(File(uri, str(src_dir), config["site_dir"], config["use_directory_urls"]))
        _generated[uri] = notebook
        for rel in outputs:
            files.append(File("tutorials/" + rel, str(src_dir), config["site_dir"],
                              config["use_directory_urls"]))
    return files


def on_nav(nav, config, files):
    in_nav = {page.file.src_uri for page in nav.pages}
    for uri, notebook in _generated.items():
        if uri not in in_nav:
            log.warning("tutorial %s is not in the nav of mkdocs.yml (add '%s')",
                        notebook.name, uri)
    return nav


_FENCE = re.compile(r"^(```|~~~).*?^\1[ \t]*$", re.M | re.S)
_LINK = re.compile(r"(!?)\[((?:[^\[\]]|\[[^\]]*\])*)\]\(([^()\s]+)\)")


def _rewrite_links(text, page, config):
    root = _repo_root(config)
    docs = pathlib.Path(config["docs_dir"]).resolve()
    src_uri = page.file.src_uri
    if src_uri in _generated:  # a tutorial: resolve against the notebook's place in docs/
        base = docs / posixpath.dirname(src_uri)
    else:
        base = pathlib.Path(page.file.abs_src_path).parent

    def repl(m):
        bang, label, target = m.groups()
        parts = urlsplit(target)
        if parts.scheme or parts.netloc or not parts.path or target.startswith("/"):
            return m.group(0)
        path = unquote(parts.path)
        if path.endswith(".ipynb"):
            generated = posixpath.normpath(
                posixpath.join(posixpath.dirname(src_uri), path[:-len(".ipynb")] + ".md"))
            if generated in _generated:
                return "%s[%s](%s%s)" % (bang, label, path[:-len(".ipynb")] + ".md",
                                         "#" + parts.fragment if parts.fragment else "")
        resolved = pathlib.Path(os.path.normpath(base / path))
        try:
            resolved.relative_to(docs)
            return m.group(0)  # inside docs/: MkDocs checks it
        except ValueError:
            pass
        try:
            rel = resolved.relative_to(root).as_posix()
        except ValueError:
            log.warning("%s: link to '%s' leaves the repository", src_uri, target)
            return m.group(0)
        if not resolved.exists():
            log.warning("%s: link to '%s': no such file in the repository (%s)",
                        src_uri, target, rel)
            return m.group(0)
        if bang:
            log.warning("%s: image '%s' is outside docs/; put it in docs/figures", src_uri, target)
            return m.group(0)
        code = "`%s`" % rel
        return code if label.strip("`") == rel or label.strip("`") == path else \
            "%s (%s)" % (label, code)

    # Leave fenced code blocks and inline code alone.
    out, pos = [], 0
    for fence in _FENCE.finditer(text):
        out.append(_rewrite_spans(text[pos:fence.start()], repl))
        out.append(fence.group(0))
        pos = fence.end()
    out.append(_rewrite_spans(text[pos:], repl))
    return "".join(out)


def _rewrite_spans(text, repl):
    # Inline code is set aside (a link inside it is text), but a link whose label is code
    # ([`a.yaml`](a.yaml)) is still a link: the spans become placeholders while links are found.
    spans = []

    def hide(m):
        spans.append(m.group(0))
        return "\x00%d\x00" % (len(spans) - 1)

    def show(s):
        return re.sub("\x00([0-9]+)\x00", lambda m: spans[int(m.group(1))], s)

    hidden = re.sub(r"(`+)[^`].*?\1", hide, text, flags=re.S)
    return show(_LINK.sub(lambda m: repl(_Shown(m, show)), hidden))


class _Shown:
    """A link match with its label's code spans restored (what repl reads)."""

    def __init__(self, m, show):
        self._groups = tuple(show(g) for g in m.groups())
        self._all = show(m.group(0))

    def groups(self):
        return self._groups

    def group(self, i):
        return self._all if i == 0 else self._groups[i - 1]


def on_page_markdown(markdown, page, config, files):
    return _rewrite_links(markdown, page, config)


_ID = re.compile(r"""\sid=["']([^"']+)["']""")
_HREF = re.compile(r"""<a\s[^>]*?href=["']([^"']+)["']""")


def on_page_content(content, page, config, files):
    _ids[page.url] = {html.unescape(i) for i in _ID.findall(content)}
    for href in _HREF.findall(content):
        href = html.unescape(href)
        parts = urlsplit(href)
        if parts.scheme or parts.netloc or not parts.fragment:
            continue
        target = posixpath.normpath(posixpath.join(posixpath.dirname(page.url), parts.path)) \
            if parts.path else page.url
        _links.append((page.file.src_uri, page.url, target, unquote(parts.fragment)))
    return content


MATHJAX = pathlib.Path("/usr/share/javascript/mathjax")  # Debian's libjs-mathjax
_MATHJAX_PARTS = ["MathJax.js", "config/TeX-AMS_CHTML.js", "extensions", "jax/input/TeX", "jax/element",
                  "jax/output/CommonHTML", "fonts/HTML-CSS/TeX/woff", "localization/en"]
_MATHJAX_CONFIG = """// MathJax 2 (Debian's libjs-mathjax): typeset what pymdownx.arithmatex marked (tools/mkdocs_hooks.py).
window.MathJax = {
  tex2jax: {inlineMath: [["\\\\(", "\\\\)"]], displayMath: [["\\\\[", "\\\\]"]],
            processEscapes: false, ignoreClass: ".*", processClass: "arithmatex"},
  "HTML-CSS": {availableFonts: ["TeX"], imageFont: null},
  CommonHTML: {webFont: "TeX"},
  menuSettings: {zoom: "None"},
  showMathMenu: false
};
"""


def _copy_mathjax(site_dir):
    if not (MATHJAX / "MathJax.js").is_file():
        log.warning("MathJax not found in %s: install Debian's libjs-mathjax "
                    "(scripts/setup-deps.sh rest); the site's math stays as TeX", MATHJAX)
        return
    js = pathlib.Path(site_dir) / "js"
    js.mkdir(parents=True, exist_ok=True)
    (js / "mathjax-config.js").write_text(_MATHJAX_CONFIG, encoding="utf-8")
    for part in _MATHJAX_PARTS:
        src, dst = MATHJAX / part, js / "mathjax" / part
        if src.is_dir():
            shutil.copytree(src, dst, dirs_exist_ok=True)  # follows Debian's symlinks
        else:
            dst.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(src, dst)


def on_post_build(config):
    _copy_mathjax(config["site_dir"])
    for src, url, target, fragment in _links:
        if target not in _ids:
            continue  # not a page (a file): MkDocs checked the file itself
        if fragment not in _ids[target]:
            log.warning("%s: link to '%s#%s': no heading or id '%s' on that page",
                        src, target, fragment, fragment)
    _links.clear()
    _ids.clear()
    if _tmp is not None:
        _tmp.cleanup()

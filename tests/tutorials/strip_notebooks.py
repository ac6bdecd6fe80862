"""Checks, or makes, the tutorial notebooks stripped: committed without outputs.

    /usr/bin/python3 tests/tutorials/strip_notebooks.py [--check] [NOTEBOOK ...]

(default: every docs/tutorials/*.ipynb). A stripped notebook has no cell outputs, no execution
counts, no per-cell execution metadata (the timestamps nbconvert and Jupyter add), and its
notebook metadata holds only the kernelspec and the language name; it is written as Jupyter
writes it (JSON, indent 1, sorted keys, UTF-8, a final newline), so stripping a stripped
notebook changes nothing and a diff shows only what the text or code changed. Without
--check the notebooks are rewritten stripped; with --check (the ctest test tutorials_stripped)
the script lists those that are not and exits 1.

Only the standard library: `jupyter-nbconvert --clear-output` removes the outputs but keeps
the execution timestamps, so it is not enough.
"""

import argparse
import json
import pathlib
import sys

TUTORIALS = pathlib.Path(__file__).resolve().parents[2] / "docs" / "tutorials"
KEPT_METADATA = {"kernelspec", "language_info"}


def stripped(notebook):
    nb = json.loads(json.dumps(notebook))  # a copy
    nb["metadata"] = {k: v for k, v in nb.get("metadata", {}).items() if k in KEPT_METADATA}
    if "language_info" in nb["metadata"]:
        nb["metadata"]["language_info"] = {"name": nb["metadata"]["language_info"].get(
            "name", "python")}
    for cell in nb.get("cells", []):
        cell.get("metadata", {}).pop("execution", None)
        if cell.get("cell_type") == "code":
            cell["outputs"] = []
            cell["execution_count"] = None
    return nb


def text_of(notebook):
    return json.dumps(notebook, indent=1, sort_keys=True, ensure_ascii=False) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="only report; exit 1 if any is not")
    parser.add_argument("notebooks", nargs="*", type=pathlib.Path)
    args = parser.parse_args()
    paths = args.notebooks or sorted(TUTORIALS.glob("*.ipynb"))
    if not paths:
        print(f"strip_notebooks: no notebooks in {TUTORIALS}", file=sys.stderr)
        return 1
    dirty = []
    for path in paths:
        text = path.read_text(encoding="utf-8")
        clean = text_of(stripped(json.loads(text)))
        if clean != text:
            dirty.append(path)
            if not args.check:
                path.write_text(clean, encoding="utf-8")
    if args.check:
        for path in dirty:
            print(f"strip_notebooks: {path} has outputs or execution metadata; strip it with "
                  f"/usr/bin/python3 tests/tutorials/strip_notebooks.py {path}")
        print(f"strip_notebooks: {len(paths) - len(dirty)} of {len(paths)} notebooks stripped")
        return 1 if dirty else 0
    for path in dirty:
        print(f"strip_notebooks: stripped {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

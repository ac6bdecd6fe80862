#!/usr/bin/python3
"""The API reference pages, generated from the sources.

    PYTHONPATH=<build>/python /usr/bin/python3 tools/gen_api_docs.py [--check]

writes docs/api/python.md (every public name of the package `screwfem`: its signature and
docstring, the members of each class) and docs/api/cpp.md (every public header of
include/screwfem: its opening comment, then each declaration at namespace level with the
comment above it). With --check it writes nothing and exits 1 when a page differs from what
the sources give, or when a public Python name has no docstring (ctest `api_reference`): the
pages cannot fall behind the code.
"""

import argparse
import dataclasses
import inspect
import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
PYTHON_PAGE = ROOT / "docs" / "api" / "python.md"
CPP_PAGE = ROOT / "docs" / "api" / "cpp.md"

# Members pybind11 gives every enum or class: documented by Python, not by screwfem.
INHERITED = {"name", "value"}


# ---- Python ---------------------------------------------------------------------------------

def doc_of(obj):
    return inspect.cleandoc(getattr(obj, "__doc__", None) or "")


def split_signature(name, doc):
    """pybind11 puts 'name(args) -> result' on the docstring's first line: (signature, rest)."""
    lines = doc.split("\n")
    if lines and re.match(rf"{re.escape(name)}\(.*\)", lines[0].strip()):
        return lines[0].strip(), "\n".join(lines[1:]).strip()
    return None, doc


def signature_of(name, obj, doc):
    sig, rest = split_signature(name, doc)
    if sig is None and callable(obj) and not inspect.isclass(obj):
        try:
            sig = name + str(inspect.signature(obj))
        except (TypeError, ValueError):
            sig = None
        if sig:  # default values shown by their class, without the object's address
            sig = re.sub(r"<(?:[\w.]+\.)?(\w+) object at 0x[0-9a-f]+>", r"\1()", sig)
    return sig, rest


def is_enum(cls):
    return hasattr(cls, "__members__") and hasattr(cls, "__entries")


def class_members(cls):
    """(name, kind, signature, doc) of a class's own public members, in definition order. The
    fields of a dataclass are documented in its class docstring (an Attributes section)."""
    out = []
    fields = {f.name for f in dataclasses.fields(cls)} if dataclasses.is_dataclass(cls) else set()
    for member, value in vars(cls).items():
        if member.startswith("_") or member in fields or (is_enum(cls) and member in INHERITED):
            continue
        if is_enum(cls) and member in cls.__members__:
            continue  # values are listed with the enum
        if isinstance(value, property):
            out.append((member, "property", None, doc_of(value)))
            continue
        if isinstance(value, (staticmethod, classmethod)):
            value = value.__func__
        doc = doc_of(value)
        sig, rest = signature_of(member, value, doc)
        out.append((member, "method" if callable(value) else "attribute", sig, rest))
    return out


def python_page(package):
    missing = []
    parts = [
        "# Python API reference\n",
        "Generated from the docstrings by `tools/gen_api_docs.py` (ctest `api_reference` checks",
        "that it is up to date). The guide is [../python.md](../python.md).\n",
    ]
    names = sorted(package.__all__, key=str.lower)
    parts.append("Names: " + ", ".join(f"[`{n}`](#{n.lower()})" for n in names) + "\n")
    for name in names:
        obj = getattr(package, name)
        doc = doc_of(obj)
        parts.append(f"## {name}\n")
        if inspect.isclass(obj):
            sig, rest = split_signature(name, doc)
            if sig:
                parts.append(f"`{sig}`\n")
            if not rest:
                missing.append(name)
            parts.append((rest or "(undocumented)") + "\n")
            if is_enum(obj):
                for value_name, value in obj.__members__.items():
                    value_doc = doc_of(value) if doc_of(value) != doc_of(obj) else ""
                    parts.append(f"- `{value_name}`" + (f": {value_doc}" if value_doc else ""))
                parts.append("")
            for member, kind, msig, mdoc in class_members(obj):
                if not mdoc:
                    missing.append(f"{name}.{member}")
                head = f"`{msig}`" if msig else f"`{member}`"
                text = (mdoc or "(undocumented)").replace("\n", "\n  ")
                parts.append(f"- {head} ({kind}): {text}")
            parts.append("")
        else:
            sig, rest = signature_of(name, obj, doc)
            if not rest:
                missing.append(name)
            if sig:
                parts.append(f"`{sig}`\n")
            parts.append((rest or "(undocumented)") + "\n")
    return "\n".join(parts).rstrip() + "\n", missing


# ---- C++ ------------------------------------------------------------------------------------

DECLARATION = re.compile(
    r"^(template\s*<.*>\s*)?(inline\s+|constexpr\s+|\[\[nodiscard\]\]\s+)*"
    r"(struct|class|enum class|enum|using|[A-Za-z_][\w:<>,\s\*&]*?\s+[\*&]?[A-Za-z_]\w*\s*\()")


def header_entries(text):
    """The opening comment and [(declaration, comment)] at namespace level."""
    lines = text.split("\n")
    opening = []
    i = 0
    while i < len(lines) and lines[i].startswith("//"):
        opening.append(lines[i][3:] if lines[i].startswith("// ") else lines[i][2:])
        i += 1
    entries, comment, depth = [], [], 0
    while i < len(lines):
        line = lines[i]
        stripped = line.strip()
        at_top = depth == 0 and not line.startswith((" ", "\t"))
        if re.match(r"^namespace\b.*\{", stripped) or re.match(r"^\}\s*// namespace", stripped):
            comment = []
            i += 1
            continue  # namespaces do not nest declarations
        if at_top and stripped.startswith("//"):
            comment.append(stripped[2:].strip())
        elif at_top and stripped and not stripped.startswith(("#", "namespace", "}")) and \
                DECLARATION.match(stripped):
            decl = [stripped]
            j = i
            while not re.search(r"[;{]\s*(//.*)?$", lines[j].strip()) and j + 1 < len(lines):
                j += 1
                decl.append(lines[j].strip())
            head = " ".join(decl)
            head = re.sub(r"\)\s*(const\s*)?(override\s*)?\{.*\}$", r") \1", head)  # a body
            head = re.sub(r"\s*\{\s*(//.*)?$", "", head)  # an opening brace
            head = head.rstrip(";").strip()
            if comment:
                entries.append((head, " ".join(comment)))
            comment = []
            for k in range(i, j + 1):
                depth += lines[k].count("{") - lines[k].count("}")
            i = j
        else:
            if at_top and not stripped.startswith("//"):
                comment = []
            depth += line.count("{") - line.count("}")
            if depth < 0:
                depth = 0
        i += 1
    return opening, entries


def comment_markdown(lines):
    """Comment lines as Markdown: paragraphs (runs between empty lines) joined into one line,
    or fenced as code when a line of the run is indented (tables, formulas, code)."""
    out, run = [], []

    def flush():
        if not run:
            return
        if any(line.startswith("  ") for line in run):
            out.append("```\n" + "\n".join(run) + "\n```\n")
        else:
            out.append(" ".join(line.strip() for line in run) + "\n")
        run.clear()
    for line in lines:
        if line.strip():
            run.append(line)
        else:
            flush()
    flush()
    return "\n".join(out)


def cpp_page():
    include = ROOT / "include" / "screwfem"
    parts = [
        "# C++ API reference\n",
        "Generated from the public headers (`include/screwfem/`) by `tools/gen_api_docs.py`",
        "(ctest `api_reference` checks that it is up to date): each header's opening comment,",
        "then each declaration at namespace level with the comment above it. The headers are the",
        "full reference (members, arguments, units); the layers are described in",
        "[../architecture.md](../architecture.md).\n",
    ]
    for layer in sorted(p for p in include.iterdir() if p.is_dir()):
        parts.append(f"## {layer.name}\n")
        for header in sorted(layer.glob("*.h")):
            rel = header.relative_to(ROOT / "include")
            opening, entries = header_entries(header.read_text())
            parts.append(f"### `{rel}`\n")
            if opening:
                parts.append(comment_markdown(opening))
            for head, comment in entries:
                head = head.replace("|", "\\|")
                parts.append(f"- `{head}`: {comment}")
            if entries:
                parts.append("")
    return "\n".join(parts).rstrip() + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true",
                        help="compare with the pages on disk instead of writing them")
    args = parser.parse_args()
    import screwfem
    python_text, missing = python_page(screwfem)
    cpp_text = cpp_page()
    if not args.check:
        PYTHON_PAGE.parent.mkdir(parents=True, exist_ok=True)
        PYTHON_PAGE.write_text(python_text)
        CPP_PAGE.write_text(cpp_text)
        print(f"wrote {PYTHON_PAGE.relative_to(ROOT)} and {CPP_PAGE.relative_to(ROOT)}")
    status = 0
    if missing:
        print(f"gen_api_docs: {len(missing)} public Python names without a docstring: "
              + ", ".join(missing), file=sys.stderr)
        status = 1
    if args.check:
        for page, text in ((PYTHON_PAGE, python_text), (CPP_PAGE, cpp_text)):
            if not page.exists() or page.read_text() != text:
                print(f"gen_api_docs: {page.relative_to(ROOT)} is not what the sources give; "
                      "run tools/gen_api_docs.py to update it", file=sys.stderr)
                status = 1
    return status


if __name__ == "__main__":
    sys.exit(main())

"""Writes a self-contained HTML viewer of a screwfem run (`screwfem view` runs this script
with Debian's /usr/bin/python3).

    screwfem_view.py OUTDIR [-o FILE.html]      (default: OUTDIR/view.html)

The page plays the run in a browser, offline (it opens from file://): rods as tubes, rigid
bodies as boxes along their segments, joints as spheres, recorded points with trails, a ground
grid and axes; play/pause, speed, a time slider, orbit/pan/zoom and follow-a-body.

Where the geometry comes from: the run's ParaView frames (vtk/motion.pvd, vtk/frame_*.vtp),
read with tools/screwfem_vtk.py, which follows the VTK XML format (ASCII, inline base64 or
appended raw/base64 data, zlib- or LZMA-compressed), not the text screwfem writes today. The
frames carry every drawn point (rod nodes, body segment ends, joint frames) with its frame
axes, so the page can orient the tube cross-sections and the body boxes. points.csv adds the
recorded points (every output row, for the trails); summary.json the case name, status and
gravity (the up direction); joints.json the joint names, types and drives.

The rods are coloured by a scalar only if the frames carry one: the speed |v| from the
velocity array, and any other point array (a strain or a stress, for instance) per component.
Today's frames carry no strain or stress, and the page says so.

three.js r111 comes from Debian's libjs-three (/usr/share/javascript/three; another directory
with SCREWFEM_THREE_DIR) and is inlined with examples/js/controls/OrbitControls.js.
Standard library only. Exit status: 0 on success, 2 when an input is missing or malformed.
"""

import argparse
import base64
import csv
import json
import math
import os
import struct
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import screwfem_vtk  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_THREE_DIR = "/usr/share/javascript/three"
KNOWN_POINT_ARRAYS = {"frame_x", "frame_y", "frame_z", "velocity", "joint_id"}
MAX_RECORDED_ROWS = 4000  # recorded-point rows kept for the trails (every k-th row beyond)


class InputProblem(Exception):
    """A missing or malformed input: reported as 'error: ...' with exit status 2."""


def b64_floats(values):
    return base64.b64encode(struct.pack(f"<{len(values)}f", *values)).decode("ascii")


def read_json(path, required):
    if not os.path.isfile(path):
        if required:
            raise InputProblem(f"{path} not found (is {os.path.dirname(path) or '.'} a screwfem "
                               f"output directory? `screwfem run SCENE -o OUTDIR` writes it)")
        return None
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError) as e:
        raise InputProblem(f"{path}: cannot read: {e}") from e


def read_recorded_points(path):
    """{names, times, xyz} from points.csv (positions only), or None without recorded points."""
    if not os.path.isfile(path):
        return None
    with open(path, newline="") as f:
        reader = csv.reader(f)
        header = next(reader, None)
        if not header or header[0] != "t":
            raise InputProblem(f"{path}: the first line must be a header starting with 't'")
        names = [c[:-2] for c in header if c.endswith(".x") and c[:-2] + ".z" in header]
        if not names:
            return None
        cols = [[header.index(f"{n}.{a}") for a in "xyz"] for n in names]
        rows = []
        for line in reader:
            if len(line) != len(header):
                break  # a partial last line of a run still being written
            try:
                rows.append([float(line[0])] + [float(line[i]) for c in cols for i in c])
            except ValueError as e:
                raise InputProblem(f"{path}: line {len(rows) + 2}: {e}") from e
    if not rows:
        return None
    stride = max(1, math.ceil(len(rows) / MAX_RECORDED_ROWS))
    kept = rows[::stride]
    if kept[-1] is not rows[-1]:
        kept.append(rows[-1])
    return {"names": names, "times": [r[0] for r in kept],
            "xyz": b64_floats([v for r in kept for v in r[1:]])}


def build_data(outdir):
    summary = read_json(os.path.join(outdir, "summary.json"), required=True)
    joints_info = read_json(os.path.join(outdir, "joints.json"), required=False)
    try:
        collection = screwfem_vtk.read_collection(outdir)
    except screwfem_vtk.VtkError as e:
        raise InputProblem(str(e)) from e
    if not collection:
        raise InputProblem(f"{outdir} has no ParaView frames (vtk/motion.pvd or vtk/frame_*.vtp): "
                           f"the viewer draws them; run with outputs.vtk: true")
    frames = []
    for t, path in collection:
        try:
            frames.append((t, screwfem_vtk.read_frame(path)))
        except screwfem_vtk.VtkError as e:
            raise InputProblem(str(e)) from e

    # Topology from the first frame; every frame must have the same.
    first = frames[0][1]
    npoints = len(first["points"])
    for t, f in frames[1:]:
        if len(f["points"]) != npoints or f["cells"] != first["cells"]:
            raise InputProblem(f"the frame at t = {t} s has another topology than the first one")
    cd = first["cell_data"]
    ncell = len(first["cells"])
    rod_id = cd.get("rod_id", (1, [-1] * ncell))[1]
    body_id = cd.get("body_id", (1, [-1] * ncell))[1]
    joint_id = cd.get("joint_id", (1, [-1] * ncell))[1]
    rods, bodies, joints = {}, {}, []
    for i, cell in enumerate(first["cells"]):
        if rod_id[i] >= 0:
            rods[rod_id[i]] = cell
        elif body_id[i] >= 0:
            body = bodies.setdefault(body_id[i], {"segments": [], "vertex": None})
            if len(cell) >= 2:
                body["segments"].append(cell[:2])
            else:
                body["vertex"] = cell[0]
        elif joint_id[i] >= 0 and cell:
            joints.append({"index": joint_id[i], "point": cell[0]})

    # Joint names, types and drives from joints.json (written by screwfem run).
    described = {}
    if joints_info:
        for j in joints_info.get("joints", []):
            described[j.get("index")] = j
    for j in joints:
        d = described.get(j["index"], {})
        j["name"] = d.get("name", f"joint {j['index']}")
        j["type"] = d.get("type", "")
        j["drive"] = d.get("drive", "none")

    positions, axes = [], []
    has_axes = all(a in first["point_data"] for a in ("frame_x", "frame_y", "frame_z"))
    for _, f in frames:
        for p in f["points"]:
            positions.extend(p)
        if has_axes:
            pd = f["point_data"]
            for i in range(npoints):
                for a in ("frame_x", "frame_y", "frame_z"):
                    axes.extend(pd[a][1][3 * i:3 * i + 3])

    # Scalar fields to colour the rods by.
    fields, notes = [], []
    if "velocity" in first["point_data"]:
        values = []
        for _, f in frames:
            v = f["point_data"]["velocity"][1]
            values.extend(math.sqrt(v[3 * i] ** 2 + v[3 * i + 1] ** 2 + v[3 * i + 2] ** 2)
                          for i in range(npoints))
        fields.append({"name": "speed", "unit": "m/s", "values": b64_floats(values)})
    extra = sorted(n for n in first["point_data"] if n not in KNOWN_POINT_ARRAYS)
    for name in extra:
        ncomp = first["point_data"][name][0]
        for c in range(ncomp):
            values = []
            for _, f in frames:
                values.extend(f["point_data"][name][1][c::ncomp][:npoints])
            fields.append({"name": name if ncomp == 1 else f"{name}[{c}]", "unit": "",
                           "values": b64_floats(values)})
    if not any("strain" in n or "stress" in n for n in extra):
        notes.append("the outputs carry no strain or stress: rods are coloured by speed at most")

    gravity = summary.get("settings", {}).get("gravity") or [0.0, 0.0, -9.81]
    norm = math.sqrt(sum(g * g for g in gravity))
    up = [-g / norm for g in gravity] if norm > 0 else [0.0, 0.0, 1.0]
    scene = summary.get("scene", {})
    return {
        "format": "screwfem viewer data 1",
        "name": scene.get("name") or os.path.basename(os.path.normpath(outdir)),
        "source": scene.get("source", ""),
        "status": summary.get("status", ""),
        "message": summary.get("message", ""),
        "up": up,
        "times": [t for t, _ in frames],
        "npoints": npoints,
        "positions": b64_floats(positions),
        "axes": b64_floats(axes) if has_axes else None,
        "rods": [rods[k] for k in sorted(rods)],
        "bodies": [bodies[k] for k in sorted(bodies)],
        "joints": joints,
        "fields": fields,
        "recorded": read_recorded_points(os.path.join(outdir, "points.csv")),
        "notes": notes,
    }


def read_text(path, what):
    try:
        with open(path, encoding="utf-8") as f:
            return f.read()
    except OSError as e:
        raise InputProblem(f"cannot read {what} {path}: {e}") from e


def write_html(data, out_path):
    three_dir = os.environ.get("SCREWFEM_THREE_DIR") or DEFAULT_THREE_DIR
    three = read_text(os.path.join(three_dir, "three.min.js"),
                      "three.js (Debian package libjs-three; or set SCREWFEM_THREE_DIR)")
    orbit = read_text(os.path.join(three_dir, "examples", "js", "controls", "OrbitControls.js"),
                      "the three.js orbit controls (libjs-three)")
    template = read_text(os.path.join(HERE, "viewer", "viewer.html"), "the viewer template")
    viewer = read_text(os.path.join(HERE, "viewer", "viewer.js"), "the viewer script")
    # "</" inside a <script> element would end it early.
    data_json = json.dumps(data, separators=(",", ":")).replace("</", "<\\/")
    title = (data["name"].replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;"))
    parts = {"@@TITLE@@": title, "@@THREE_JS@@": three, "@@ORBIT_JS@@": orbit,
             "@@DATA_JSON@@": data_json, "@@VIEWER_JS@@": viewer}
    html, pos = [], 0
    while True:  # one pass: the inlined texts are not searched for markers
        hits = [(template.find(k, pos), k) for k in parts if template.find(k, pos) >= 0]
        if not hits:
            html.append(template[pos:])
            break
        at, key = min(hits)
        html.append(template[pos:at])
        html.append(parts[key].replace("</script", "<\\/script") if key != "@@TITLE@@" else parts[key])
        pos = at + len(key)
    os.makedirs(os.path.dirname(os.path.abspath(out_path)), exist_ok=True)
    tmp = out_path + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write("".join(html))
    os.replace(tmp, out_path)


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("outdir", help="run output directory (screwfem run -o)")
    parser.add_argument("-o", "--output", help="HTML file to write (default: OUTDIR/view.html)")
    args = parser.parse_args(argv)
    out_path = args.output or os.path.join(args.outdir, "view.html")
    try:
        if not os.path.isdir(args.outdir):
            raise InputProblem(f"{args.outdir} is not a directory")
        data = build_data(args.outdir)
        write_html(data, out_path)
    except InputProblem as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    for note in data["notes"]:
        print(f"note: {note}", file=sys.stderr)
    print(out_path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

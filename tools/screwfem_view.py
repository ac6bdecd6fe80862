"""Writes a self-contained HTML viewer of a screwfem run (`screwfem view` runs this script
with Debian's /usr/bin/python3).

    screwfem_view.py OUTDIR [-o FILE.html] [--max-frames N]     (default: OUTDIR/view.html)

The page plays the run in a browser at real rate, offline (it opens from file://), true to
size: rods as tubes of their section, rigid bodies as their contact shapes or else the box of
their inertia, obstacles, tendons and force elements coloured by tension, contact forces as
arrows, pressure chambers inside the rods, joints and joint frames, recorded points with
trails, a ground grid; every layer can
be switched off; play/pause, speed, a time slider, orbit/pan/zoom and follow-a-body
(tools/viewer/viewer.js lists the URL parameters).

Where it comes from: the run's ParaView frames (vtk/motion.pvd, vtk/frame_*.vtp), read with
tools/screwfem_vtk.py, which follows the VTK XML format (ASCII, inline base64 or appended
raw/base64 data, zlib- or LZMA-compressed), not the text screwfem writes today. The frames
carry every drawn point with its frame axes, the cells' kinds (include/screwfem/io/vtk.h),
the sizes (radius, half_size), tensions and contact forces. points.csv adds the recorded
points (every output row, for the trails); summary.json the case name, status and gravity
(the up direction); joints.json the joint names, types and drives; tendons.csv and forces.csv
the names of tendons and force elements.

Page size: the first frame's positions of every point, then per frame those of the drawn
points that move, orientations as quaternions of the points that have one (rod sections,
boxes, joints, planes), contact forces of the contact points that ever touch, as 16-bit
integers over each quantity's range (track); at most --max-frames frames (one in k beyond).
The size is printed on stderr.

The rods are coloured by a scalar only if the frames carry one: the speed |v| from the
velocity array, and any other point array (a strain or a stress, for instance) per component.
Today's frames carry no strain or stress, and the page says so.

The same code builds the page of a running Python simulation (Simulation.view,
python/screwfem/_live.py): page_data(..., live=True) for its first frame, live_frame for each
frame its WebSocket sends.

three.js r111 comes from Debian's libjs-three (/usr/share/javascript/three; another directory
with SCREWFEM_THREE_DIR) and is inlined with examples/js/controls/OrbitControls.js.
Standard library only. Exit status: 0 on success, 2 when an input is missing or malformed.
"""

import argparse
import base64
import csv
import html
import json
import math
import os
import struct
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import screwfem_vtk  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_THREE_DIR = "/usr/share/javascript/three"
KNOWN_POINT_ARRAYS = {"frame_x", "frame_y", "frame_z", "velocity", "joint_id", "contact_force",
                      "contact_state", "radius", "half_size"}
MAX_RECORDED_ROWS = 4000  # recorded-point rows kept for the trails (every k-th row beyond)
DEFAULT_MAX_FRAMES = 1500  # frames kept in the page (every k-th beyond; --max-frames)


class InputProblem(Exception):
    """A missing or malformed input: reported as 'error: ...' with exit status 2."""


def b64_floats(values):
    return base64.b64encode(struct.pack(f"<{len(values)}f", *values)).decode("ascii")


def track(values, components=1, zero=False):
    """Values that change from frame to frame, as 16-bit integers (the page's size): per
    component c, value = mid[c] + q * scale[c] with q in [-32767, 32767], so a component is
    resolved to 1/65534 of its range over the run (mid = 0 with `zero`: zero stays exact).
    The page decodes them (viewer.js, decode)."""
    mid, scale = [], []
    for c in range(components):
        column = values[c::components]
        a, b = (min(column), max(column)) if column else (0.0, 0.0)
        if zero:
            a, b = -max(abs(a), abs(b)), max(abs(a), abs(b))
        mid.append(0.5 * (a + b))
        scale.append((b - a) / 65534 if b > a else 1.0)
    q = [max(-32767, min(32767, round((v - mid[i % components]) / scale[i % components])))
         for i, v in enumerate(values)]
    return {"mid": mid, "scale": scale,
            "data": base64.b64encode(struct.pack(f"<{len(q)}h", *q)).decode("ascii")}


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
            "xyz": track([v for r in kept for v in r[1:]], 3)}


def csv_names(path, suffix):
    """The names of the columns NAME.suffix of a CSV header (tendons.csv, forces.csv), in order."""
    if not os.path.isfile(path):
        return []
    with open(path, newline="") as f:
        header = next(csv.reader(f), [])
    return [c[:-len(suffix)] for c in header if c.endswith(suffix)]


def quaternion(m):
    """(x, y, z, w) of the rotation whose columns are m[0], m[1], m[2] (frame_x, _y, _z)."""
    (xx, yx, zx), (xy, yy, zy), (xz, yz, zz) = m  # m[c][r]: column c, row r
    trace = xx + yy + zz
    if trace > 0:
        s = 0.5 / math.sqrt(trace + 1.0)
        return ((zy - yz) * s, (xz - zx) * s, (yx - xy) * s, 0.25 / s)
    if xx > yy and xx > zz:
        s = 2.0 * math.sqrt(max(1.0 + xx - yy - zz, 1e-300))
        return (0.25 * s, (xy + yx) / s, (xz + zx) / s, (zy - yz) / s)
    if yy > zz:
        s = 2.0 * math.sqrt(max(1.0 + yy - xx - zz, 1e-300))
        return ((xy + yx) / s, 0.25 * s, (yz + zy) / s, (xz - zx) / s)
    s = 2.0 * math.sqrt(max(1.0 + zz - xx - yy, 1e-300))
    return ((xz + zx) / s, (yz + zy) / s, 0.25 * s, (yx - xy) / s)


def kept_frames(collection, max_frames):
    """Every k-th frame (and the last) so that at most about max_frames remain."""
    if max_frames <= 0 or len(collection) <= max_frames:
        return collection
    stride = math.ceil(len(collection) / max_frames)
    kept = collection[::stride]
    if kept[-1] is not collection[-1]:
        kept.append(collection[-1])
    return kept


def actuator_names(path):
    """The actuator names of actuators.csv's header (its columns after t and load_factor)."""
    if not os.path.isfile(path):
        return []
    with open(path, newline="") as f:
        header = next(csv.reader(f), [])
    return [c for c in header if c not in ("t", "load_factor")]


def build_data(outdir, max_frames=DEFAULT_MAX_FRAMES):
    summary = read_json(os.path.join(outdir, "summary.json"), required=True)
    joints_info = read_json(os.path.join(outdir, "joints.json"), required=False)
    try:
        collection = screwfem_vtk.read_collection(outdir)
    except screwfem_vtk.VtkError as e:
        raise InputProblem(str(e)) from e
    if not collection:
        raise InputProblem(f"{outdir} has no ParaView frames (vtk/motion.pvd or vtk/frame_*.vtp): "
                           f"the viewer draws them; run with outputs.vtk: true")
    kept = kept_frames(collection, max_frames)
    frames = []
    for t, path in kept:
        try:
            frames.append((t, screwfem_vtk.read_frame(path)))
        except screwfem_vtk.VtkError as e:
            raise InputProblem(str(e)) from e
    notes = []
    if len(kept) < len(collection):
        notes.append(f"{len(kept)} of {len(collection)} frames kept (one in "
                     f"{math.ceil(len(collection) / max(max_frames, 1))}; --max-frames)")
    names = {"tendon": csv_names(os.path.join(outdir, "tendons.csv"), ".tension"),
             "force_element": csv_names(os.path.join(outdir, "forces.csv"), ".force"),
             "chamber": actuator_names(os.path.join(outdir, "actuators.csv"))}
    scene = summary.get("scene", {})
    return page_data(frames, len(collection), summary, joints_info, names,
                     scene.get("name") or os.path.basename(os.path.normpath(outdir)),
                     read_recorded_points(os.path.join(outdir, "points.csv")), notes)


def describe(first, joints_info, names):
    """What the cells of a frame are (the page's topology), from its first frame: rods, bodies,
    joints, contact shapes, tendon and force element lines, contact points, obstacles,
    chambers, and the points that carry a frame."""
    cd = first["cell_data"]
    ncell = len(first["cells"])
    item = cd.get("item_id", (1, [-1] * ncell))[1]
    body_of = cd.get("body_id", (1, [-1] * ncell))[1]
    joint_of = cd.get("joint_id", (1, [-1] * ncell))[1]
    rod_of = cd.get("rod_id", (1, [-1] * ncell))[1]
    rods, bodies, joints, shapes, lines, contacts, obstacles, chambers = \
        {}, {}, [], [], [], [], [], []
    oriented = set()

    def body(b):
        return bodies.setdefault(b, {"segments": [], "point": None, "box": None, "shapes": []})

    for i, (cell, kind) in enumerate(zip(first["cells"], first["kinds"])):
        if kind == "rod":
            rods[rod_of[i]] = cell
            oriented.update(cell)
        elif kind == "body":
            if len(cell) >= 2:
                body(body_of[i])["segments"].append(cell[:2])
            else:
                body(body_of[i])["point"] = cell[0]
        elif kind == "body_point":
            body(body_of[i])["point"] = cell[0]
        elif kind == "inertia_box":
            body(body_of[i])["box"] = cell[0]
            oriented.add(cell[0])
        elif kind in ("sphere", "capsule", "box", "cylinder"):
            body(body_of[i])["shapes"].append(len(shapes))
            shapes.append({"type": kind, "points": cell, "body": body_of[i]})
            if kind == "box":
                oriented.add(cell[0])
        elif kind in ("tendon", "force_element"):
            lines.append({"kind": kind, "points": cell, "item": item[i], "cell": i})
        elif kind in ("contact", "pair_contact"):
            contacts.append(cell[0])
        elif kind in ("plane", "obstacle_sphere", "obstacle_capsule", "obstacle_cylinder",
                      "obstacle_box"):
            obstacles.append({"type": kind.replace("obstacle_", ""), "points": cell})
            if kind in ("plane", "obstacle_box"):
                oriented.add(cell[0])
        elif kind == "joint" and cell and joint_of[i] >= 0:
            joints.append({"index": joint_of[i], "point": cell[0]})
            oriented.add(cell[0])
        elif kind == "chamber":
            chambers.append({"points": cell, "item": item[i], "rod": rod_of[i]})
            oriented.update(cell)

    # Names: joints from joints.json, tendons, force elements and chambers from their tables'
    # columns (or the model).
    described = {}
    if joints_info:
        for j in joints_info.get("joints", []):
            described[j.get("index")] = j
    for j in joints:
        d = described.get(j["index"], {})
        j["name"] = d.get("name", f"joint {j['index']}")
        j["type"] = d.get("type", "")
        j["drive"] = d.get("drive", "none")
    for line in lines:
        known = names.get(line["kind"], [])
        line["name"] = known[line["item"]] if 0 <= line["item"] < len(known) else \
            f"{line['kind'].replace('_', ' ')} {line['item'] + 1}"
    for c in chambers:
        known = names.get("chamber", [])
        c["name"] = known[c["item"]] if 0 <= c["item"] < len(known) else f"chamber {c['item'] + 1}"
    return {"rods": rods, "bodies": bodies, "joints": joints, "shapes": shapes, "lines": lines,
            "contacts": contacts, "obstacles": obstacles, "chambers": chambers,
            "oriented": oriented, "ncell": ncell}


def used_points(top, contacts):
    """The points the page draws."""
    used = set(contacts) | set(top["oriented"])
    for cells in (top["rods"].values(), [l["points"] for l in top["lines"]],
                  [s["points"] for s in top["shapes"]], [o["points"] for o in top["obstacles"]],
                  [c["points"] for c in top["chambers"]]):
        for cell in cells:
            used.update(cell)
    for b in top["bodies"].values():
        used.update(p for seg in b["segments"] for p in seg)
        used.update(p for p in (b["point"], b["box"]) if p is not None)
    return used


def frame_quats(f, oriented, previous):
    """(x, y, z, w) of every oriented point of frame f, each in the hemisphere of `previous`
    (the last frame's, or None)."""
    pd = f["point_data"]
    ax = [pd[a][1] for a in ("frame_x", "frame_y", "frame_z")]
    row = []
    for k, i in enumerate(oriented):
        q = quaternion([ax[c][3 * i:3 * i + 3] for c in range(3)])
        if previous and sum(a * b for a, b in zip(q, previous[k])) < 0:
            q = tuple(-v for v in q)
        row.append(q)
    return row


def field_list(pd):
    """The rods' colour fields a frame's point data gives: (name, unit, array, component);
    component -1: the speed |v| of the velocity array."""
    out = []
    if "velocity" in pd:
        out.append(("speed", "m/s", "velocity", -1))
    for name in sorted(n for n in pd if n not in KNOWN_POINT_ARRAYS):
        ncomp = pd[name][0]
        for c in range(ncomp):
            out.append((name if ncomp == 1 else f"{name}[{c}]", "", name, c))
    return out


def field_values(f, field, points):
    """The values of one colour field (field_list) at `points` of frame f."""
    _, _, name, c = field
    v = f["point_data"][name][1]
    if c < 0:
        return [math.sqrt(v[3 * i] ** 2 + v[3 * i + 1] ** 2 + v[3 * i + 2] ** 2) for i in points]
    ncomp = f["point_data"][name][0]
    return [v[ncomp * i + c] for i in points]


def frame_tensions(f, lines, ncell):
    values = f["cell_data"].get("tension", (1, [0.0] * ncell))[1]
    return [values[line["cell"]] for line in lines]


def frame_forces(f, contacts):
    v = f["point_data"]["contact_force"][1]
    return [x for i in contacts for x in v[3 * i:3 * i + 3]]


def frame_states(f, contacts):
    """(slip, deflection [m], share) of each drawn contact (the frames' contact_state)."""
    v = f["point_data"]["contact_state"][1]
    return [x for i in contacts for x in v[3 * i:3 * i + 3]]


def page_data(frames, frames_total, summary, joints_info, names, name, recorded, notes,
              live=False):
    """The page's data ('screwfem viewer data 2') from frames [(t, frame)]: tracks of the
    values that change over them. live: the page of Simulation.view, whose later frames come
    over its WebSocket (live_frame): every drawn point counts as moving, every oriented one as
    turning and every contact point as touching."""
    # Topology from the first frame; every frame must have the same.
    first = frames[0][1]
    npoints = len(first["points"])
    for t, f in frames[1:]:
        if len(f["points"]) != npoints or f["cells"] != first["cells"]:
            raise InputProblem(f"the frame at t = {t} s has another topology than the first one")
    pd = first["point_data"]
    top = describe(first, joints_info, names)
    rods, bodies, lines = top["rods"], top["bodies"], top["lines"]
    ncell = top["ncell"]

    # Contact points that never carry a force are left out (most pairs never touch).
    if "contact_force" in pd:
        def touching(i):
            return any(any(f["point_data"]["contact_force"][1][3 * i:3 * i + 3]) for _, f in frames)
        contacts = top["contacts"] if live else [i for i in top["contacts"] if touching(i)]
    else:
        contacts = []
    used = used_points(top, contacts)

    # Positions: the first frame's for every point, then per frame those of the drawn points
    # that move.
    points = [f["points"] for _, f in frames]
    static = {i for o in top["obstacles"] for i in o["points"]}
    if live:
        moving = [i for i in sorted(used) if i not in static]
    else:
        moving = [i for i in sorted(used) if any(p[i] != points[0][i] for p in points[1:])]
    has_axes = all(a in pd for a in ("frame_x", "frame_y", "frame_z"))
    oriented = sorted(top["oriented"]) if has_axes else []
    quats = []  # per frame, per oriented point, (x, y, z, w) in the hemisphere of the last one
    for _, f in frames:
        quats.append(frame_quats(f, oriented, quats[-1] if quats else None) if has_axes else [])
    if live:
        turning = list(range(len(oriented)))
    else:
        turning = [k for k in range(len(oriented)) if any(q[k] != quats[0][k] for q in quats[1:])]

    # Sizes (constant): radius and half sizes per point; zero in frames written before them.
    radius = pd.get("radius", (1, [0.0] * npoints))[1]
    half = pd.get("half_size", (3, [0.0] * 3 * npoints))[1]
    unsized = [k + 1 for k in sorted(rods) if not any(radius[i] > 0 for i in rods[k])]
    if unsized:
        notes.append("no section size for rod" + ("s " if len(unsized) > 1 else " ") +
                     ", ".join(str(k) for k in unsized) + " (a section given by its stiffness, "
                     "no contact_radius or visual_radius): drawn thin")

    # Per-frame values: tensions, contact forces, the rods' colour fields.
    tension = [v for _, f in frames for v in frame_tensions(f, lines, ncell)]
    forces = [v for _, f in frames for v in frame_forces(f, contacts)] \
        if "contact_force" in pd else []
    # Each contact's state (stick/slip, the anchor's deflection, the share of friction used).
    states = [v for _, f in frames for v in frame_states(f, contacts)] \
        if "contact_state" in pd and contacts else []
    field_points = sorted({i for k in rods for i in rods[k]})
    fields = []
    for field in field_list(pd):
        values = [v for _, f in frames for v in field_values(f, field, field_points)]
        fields.append({"name": field[0], "unit": field[1], "values": track(values)})
    extra = sorted(n for n in pd if n not in KNOWN_POINT_ARRAYS)
    if not any("strain" in n or "stress" in n for n in extra):
        notes.append("the outputs carry no strain or stress: rods are coloured by speed at most")

    gravity = summary.get("settings", {}).get("gravity") or [0.0, 0.0, -9.81]
    norm = math.sqrt(sum(g * g for g in gravity))
    up = [-g / norm for g in gravity] if norm > 0 else [0.0, 0.0, 1.0]
    scene = summary.get("scene", {})
    data = {
        "format": "screwfem viewer data 2",
        "name": name,
        "source": scene.get("source", ""),
        "static": summary.get("settings", {}).get("analysis") == "static",
        "status": summary.get("status", ""),
        "message": summary.get("message", ""),
        "up": up,
        "times": [t for t, _ in frames],
        "frames_total": frames_total,
        "npoints": npoints,
        "x0": b64_floats([v for p in points[0] for v in p]),
        "moving": moving,
        "positions": track([v for p in points for i in moving for v in p[i]], 3),
        "oriented": oriented,
        "q0": b64_floats([v for q in quats[0] for v in q]) if oriented else "",
        "turning": turning,
        "quats": track([v for row in quats for k in turning for v in row[k]], 4),
        "radius": b64_floats(radius),
        "half": b64_floats(half),
        "rods": [rods[k] for k in sorted(rods)],
        "bodies": [dict(bodies[k], index=k) for k in sorted(bodies)],
        "shapes": top["shapes"],
        "joints": top["joints"],
        "lines": [{k: v for k, v in line.items() if k != "cell"} for line in lines],
        "tension": track(tension, zero=True),
        "contacts": contacts,
        "forces": track(forces, 3, zero=True),
        "contact_states": track(states, 3, zero=True) if states else None,
        "obstacles": top["obstacles"],
        "chambers": top["chambers"],
        "field_points": field_points,
        "fields": fields,
        "recorded": recorded,
        "notes": notes,
    }
    if live:
        # What live_frame needs of the topology (not sent to the page).
        data["_live"] = {"lines": lines, "ncell": ncell, "quats": quats[-1],
                         "fields": field_list(pd), "has_contact": "contact_force" in pd}
    return data


def live_frame(data, t, f):
    """One frame of Simulation.view's WebSocket, for a page whose data is page_data(...,
    live=True): {'t', 'x' (moving points' positions), 'q' (turning points' quaternions),
    'tension', 'forces', 'fields'}, the arrays as base64 little-endian float32. Updates the
    hemisphere of the quaternions kept in data['_live']."""
    live = data["_live"]
    q = frame_quats(f, data["oriented"], live["quats"]) if data["oriented"] else []
    live["quats"] = q
    x = [v for i in data["moving"] for v in f["points"][i]]
    return {"t": t, "x": b64_floats(x), "q": b64_floats([v for row in q for v in row]),
            "tension": frame_tensions(f, live["lines"], live["ncell"]),
            "forces": b64_floats(frame_forces(f, data["contacts"])) if live["has_contact"] else "",
            "fields": [b64_floats(field_values(f, field, data["field_points"]))
                       for field in live["fields"]]}


def read_text(path, what):
    try:
        with open(path, encoding="utf-8") as f:
            return f.read()
    except OSError as e:
        raise InputProblem(f"cannot read {what} {path}: {e}") from e


def script_json(data):
    """The JSON text of `data` for a <script> element, safe for any strings in it: every "<",
    ">" and "&" (which JSON allows only inside strings) is written as a \\u escape, so that no
    "</script>", "<!--" or "<script" can end the element early or switch the HTML tokenizer into
    its escaped script states (a scene named '<!--<script>' swallowed the rest of the page),
    and U+2028 and U+2029 likewise. JSON.parse reads the same values back."""
    text = json.dumps(data, separators=(",", ":"), ensure_ascii=False)
    for c in "<>&\u2028\u2029":
        text = text.replace(c, "\\u%04x" % ord(c))
    return text


def write_html(data, out_path):
    text = render_html(data)
    os.makedirs(os.path.dirname(os.path.abspath(out_path)), exist_ok=True)
    tmp = out_path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(text)
    os.replace(tmp, out_path)
    return {"page": len(text), "library": render_html.library, "data": render_html.data}


def render_html(data):
    """The page's bytes (UTF-8): the template with three.js, the viewer and the data inlined."""
    three_dir = os.environ.get("SCREWFEM_THREE_DIR") or DEFAULT_THREE_DIR
    three = read_text(os.path.join(three_dir, "three.min.js"),
                      "three.js (Debian package libjs-three; or set SCREWFEM_THREE_DIR)")
    orbit = read_text(os.path.join(three_dir, "examples", "js", "controls", "OrbitControls.js"),
                      "the three.js orbit controls (libjs-three)")
    template = read_text(os.path.join(HERE, "viewer", "viewer.html"), "the viewer template")
    viewer = read_text(os.path.join(HERE, "viewer", "viewer.js"), "the viewer script")
    data_json = script_json(data)
    title = html.escape(data["name"], quote=True)
    parts = {"@@TITLE@@": title, "@@THREE_JS@@": three, "@@ORBIT_JS@@": orbit,
             "@@DATA_JSON@@": data_json, "@@VIEWER_JS@@": viewer}
    page, pos = [], 0
    while True:  # one pass: the inlined texts are not searched for markers
        hits = [(template.find(k, pos), k) for k in parts if template.find(k, pos) >= 0]
        if not hits:
            page.append(template[pos:])
            break
        at, key = min(hits)
        page.append(template[pos:at])
        page.append(parts[key].replace("</script", "<\\/script") if key != "@@TITLE@@" else parts[key])
        pos = at + len(key)
    render_html.library, render_html.data = len(three) + len(orbit), len(data_json)
    return "".join(page).encode("utf-8")


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("outdir", help="run output directory (screwfem run -o)")
    parser.add_argument("-o", "--output", help="HTML file to write (default: OUTDIR/view.html)")
    parser.add_argument("--max-frames", type=int, default=DEFAULT_MAX_FRAMES,
                        help=f"frames kept in the page, every k-th beyond (default "
                             f"{DEFAULT_MAX_FRAMES}; 0: all)")
    args = parser.parse_args(argv)
    out_path = args.output or os.path.join(args.outdir, "view.html")
    try:
        if not os.path.isdir(args.outdir):
            raise InputProblem(f"{args.outdir} is not a directory")
        data = build_data(args.outdir, args.max_frames)
        sizes = write_html(data, out_path)
    except InputProblem as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    for note in data["notes"]:
        print(f"note: {note}", file=sys.stderr)
    print(f"{out_path}: {sizes['page'] / 1e6:.2f} MB (three.js {sizes['library'] / 1e6:.2f} MB, "
          f"run data {sizes['data'] / 1e6:.2f} MB: {len(data['times'])} frames of "
          f"{data['npoints']} points)", file=sys.stderr)
    print(out_path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

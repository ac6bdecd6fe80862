"""Reads the ParaView files of a screwfem run (vtk/motion.pvd and vtk/frame_*.vtp).

Standard library only (no numpy), shared by screwfem_view.py and screwfem_plot.py.

The reader follows the VTK XML file format (the "VTK User's Guide", XML file formats) rather
than the exact text screwfem writes today, so that a change of encoding in the writer does not
break the viewer or the plots. A DataArray may be
  * format="ascii" (numbers as text),
  * format="binary" (base64 inside the element), or
  * format="appended" (an offset into <AppendedData encoding="raw"> or "base64"),
each with a UInt32 or UInt64 size header (header_type), little- or big-endian (byte_order),
and uncompressed or compressed in blocks by vtkZLibDataCompressor or vtkLZMADataCompressor.
Base64 data may encode the header and the data together or, as VTK itself writes them, as
separate base64 runs.
"""

import base64
import lzma
import os
import re
import struct
import xml.etree.ElementTree as ET
import zlib


class VtkError(Exception):
    """A missing, malformed or unsupported ParaView file (the message names the file)."""


_TYPES = {
    "Int8": "b", "UInt8": "B", "Int16": "h", "UInt16": "H", "Int32": "i", "UInt32": "I",
    "Int64": "q", "UInt64": "Q", "Float32": "f", "Float64": "d",
}
_DECOMPRESS = {
    "vtkZLibDataCompressor": zlib.decompress,
    "vtkLZMADataCompressor": lzma.decompress,
}


class _Format:
    """File-wide encoding settings from the <VTKFile> attributes."""

    def __init__(self, root, path):
        self.path = path
        self.endian = ">" if root.get("byte_order") == "BigEndian" else "<"
        header = root.get("header_type", "UInt32")
        if header not in ("UInt32", "UInt64"):
            raise VtkError(f"{path}: unsupported header_type {header}")
        self.header_code = _TYPES[header]
        self.header_size = struct.calcsize(self.header_code)
        compressor = root.get("compressor")
        if compressor and compressor not in _DECOMPRESS:
            raise VtkError(f"{path}: unsupported compressor {compressor} "
                           f"(supported: {', '.join(_DECOMPRESS)})")
        self.decompress = _DECOMPRESS.get(compressor) if compressor else None

    def ints(self, data, count):
        return struct.unpack(f"{self.endian}{count}{self.header_code}", data[:count * self.header_size])


def _b64(text):
    """Decodes base64 text that may hold several padded runs back to back."""
    runs = re.findall(r"[^=]+=*", text)
    return b"".join(base64.b64decode(run + "=" * (-len(run) % 4)) for run in runs)


class _Base64Stream:
    """Sequential base64 decoding that accepts one run or several padded runs back to back."""

    def __init__(self, text):
        self.text = re.sub(r"\s+", "", text)
        self.pos = 0

    def take(self, nbytes):
        """The next nbytes bytes, decoded from whole 4-character groups."""
        chars = 4 * ((nbytes + 2) // 3)
        chunk = self.text[self.pos:self.pos + chars]
        raw = _b64(chunk)
        # Either a padded run ends here (VTK encodes the header and the data separately), or
        # nbytes is a multiple of 3 and the groups line up with a joint encoding.
        if len(raw) >= nbytes and (chunk.endswith("=") or len(raw) == nbytes):
            self.pos += chars
            return raw[:nbytes]
        return None

    def rest(self):
        raw = _b64(self.text[self.pos:])
        self.pos = len(self.text)
        return raw


def _decode_binary_block(fmt, stream_or_bytes, name):
    """The data bytes of one binary array: header (+ compressed blocks) or header + raw data."""
    h = fmt.header_size
    if isinstance(stream_or_bytes, bytes):
        buf = stream_or_bytes
        if fmt.decompress is None:
            (n,) = fmt.ints(buf, 1)
            return buf[h:h + n]
        nblocks = fmt.ints(buf, 1)[0]
        header = fmt.ints(buf, 3 + nblocks)
        sizes = header[3:]
        pos = (3 + nblocks) * h
        out = []
        for size in sizes:
            out.append(fmt.decompress(buf[pos:pos + size]))
            pos += size
        return b"".join(out)

    # base64 text: try the header as a separate run first, else decode everything together
    stream = stream_or_bytes
    if fmt.decompress is None:
        head = stream.take(h)
        if head is not None:
            (n,) = fmt.ints(head, 1)
            data = stream.rest()
            if len(data) >= n:
                return data[:n]
        stream.pos = 0
        return _decode_binary_block(fmt, stream.rest(), name)
    first = stream.take(3 * h)
    if first is not None:
        nblocks = fmt.ints(first, 1)[0]
        stream.pos = 0
        header = stream.take((3 + nblocks) * h)
        if header is not None:
            sizes = fmt.ints(header, 3 + nblocks)[3:]
            data = stream.rest()
            if len(data) >= sum(sizes):
                out, pos = [], 0
                for size in sizes:
                    out.append(fmt.decompress(data[pos:pos + size]))
                    pos += size
                return b"".join(out)
    stream.pos = 0
    return _decode_binary_block(fmt, stream.rest(), name)


def _unpack(fmt, data, type_name, name):
    code = _TYPES.get(type_name)
    if code is None:
        raise VtkError(f"{fmt.path}: array {name}: unsupported type {type_name}")
    size = struct.calcsize(code)
    count = len(data) // size
    return list(struct.unpack(f"{fmt.endian}{count}{code}", data[:count * size]))


def _read_array(fmt, element, appended):
    """The values of one <DataArray> as a flat list of numbers."""
    type_name = element.get("type", "Float32")
    name = element.get("Name", "?")
    kind = element.get("format", "ascii")
    try:
        if kind == "ascii":
            convert = float if type_name.startswith("Float") else int
            return [convert(v) for v in (element.text or "").split()]
        if kind == "binary":
            data = _decode_binary_block(fmt, _Base64Stream(element.text or ""), name)
            return _unpack(fmt, data, type_name, name)
        if kind == "appended":
            if appended is None:
                raise VtkError(f"{fmt.path}: array {name} is appended but the file has no AppendedData")
            encoding, blob = appended
            offset = int(element.get("offset", "0"))
            if encoding == "raw":
                data = _decode_binary_block(fmt, blob[offset:], name)
            else:
                data = _decode_binary_block(fmt, _Base64Stream(blob[offset:].decode("ascii")), name)
            return _unpack(fmt, data, type_name, name)
    except (ValueError, struct.error, zlib.error, lzma.LZMAError, IndexError) as e:
        raise VtkError(f"{fmt.path}: array {name}: cannot decode ({kind}): {e}") from e
    raise VtkError(f"{fmt.path}: array {name}: unknown format {kind}")


def _parse(path):
    """(root element, appended data or None): the XML with any raw AppendedData cut out."""
    try:
        with open(path, "rb") as f:
            raw = f.read()
    except OSError as e:
        raise VtkError(f"cannot read {path}: {e}") from e
    return _parse_bytes(raw, path)


def _parse_bytes(raw, path):
    appended = None
    start = raw.find(b"<AppendedData")
    if start >= 0:
        tag_end = raw.find(b">", start)
        marker = raw.find(b"_", tag_end)
        # The data ends at the last closing tag (raw data may contain any byte).
        end = raw.rfind(b"</AppendedData>")
        if tag_end < 0 or marker < 0 or end < marker:
            raise VtkError(f"{path}: malformed AppendedData")
        tag = raw[start:tag_end + 1].decode("ascii", "replace")
        encoding = "raw" if 'encoding="raw"' in tag else "base64"
        blob = raw[marker + 1:end]
        if encoding == "base64":
            blob = blob.strip()
        appended = (encoding, blob)
        raw = raw[:start] + raw[end + len(b"</AppendedData>"):]
    try:
        return ET.fromstring(raw), appended
    except ET.ParseError as e:
        raise VtkError(f"{path}: not valid XML: {e}") from e


def read_collection(outdir):
    """[(time, path)] of the run's frames, sorted by time; None when the run has no vtk/.

    Uses vtk/motion.pvd; without it (a run stopped before writing it), the frame_*.vtp files
    themselves, with the time from each file's TimeValue field."""
    vtk_dir = os.path.join(outdir, "vtk")
    pvd = os.path.join(vtk_dir, "motion.pvd")
    if os.path.isfile(pvd):
        root, _ = _parse(pvd)
        frames = []
        for ds in root.iter("DataSet"):
            try:
                frames.append((float(ds.get("timestep")), os.path.join(vtk_dir, ds.get("file"))))
            except (TypeError, ValueError) as e:
                raise VtkError(f"{pvd}: a DataSet without a valid timestep and file") from e
        return sorted(frames)
    if not os.path.isdir(vtk_dir):
        return None
    files = sorted(f for f in os.listdir(vtk_dir) if re.fullmatch(r"frame_\d+\.vtp", f))
    frames = []
    for name in files:
        path = os.path.join(vtk_dir, name)
        frames.append((read_frame(path)["time"], path))
    return sorted(frames) or None


# The cell data `kind` of screwfem's frames (VtkCellKind, include/screwfem/io/vtk.h), by value.
KIND_NAMES = ("joint", "rod", "body", "body_point", "tendon", "force_element", "contact",
              "pair_contact", "sphere", "capsule", "box", "inertia_box", "plane",
              "obstacle_sphere", "obstacle_capsule", "chamber", "cylinder", "obstacle_cylinder",
              "obstacle_box")


def cell_kinds(cells, cell_data):
    """The kind name of every cell: from the `kind` cell array (KIND_NAMES), or, in frames
    written before it, 'rod', 'body' or 'joint' from the rod_id and body_id arrays."""
    if "kind" in cell_data:
        return [KIND_NAMES[k] if 0 <= k < len(KIND_NAMES) else "unknown"
                for k in cell_data["kind"][1]]
    rod = cell_data.get("rod_id", (1, [-1] * len(cells)))[1]
    body = cell_data.get("body_id", (1, [-1] * len(cells)))[1]
    return ["rod" if rod[i] >= 0 else "body" if body[i] >= 0 else "joint" for i in range(len(cells))]


class Frame(dict):
    """One .vtp frame: 'time' (or None), 'points' (list of (x, y, z)), 'point_data' and
    'cell_data' (name -> (components, flat values)), 'cells' (list of point-index lists, the
    vertices first, then the lines, as VTK orders them) and 'kinds' (per cell, cell_kinds)."""


def read_frame(path):
    if not os.path.isfile(path):
        raise VtkError(f"{path} not found (listed in motion.pvd but missing?)")
    return _frame(*_parse(path), path)


def read_frame_bytes(raw, name="frame"):
    """A frame from the bytes of a .vtp file (the live view's frames, Simulation._vtk_frame);
    `name` stands for the path in messages."""
    return _frame(*_parse_bytes(raw, name), name)


def _frame(root, appended, path):
    fmt = _Format(root, path)
    piece = root.find("PolyData/Piece")
    if piece is None:
        raise VtkError(f"{path}: not a PolyData file with a Piece")

    def arrays(parent):
        out = {}
        if parent is None:
            return out
        for a in parent.findall("DataArray"):
            out[a.get("Name")] = (int(a.get("NumberOfComponents", "1")), _read_array(fmt, a, appended))
        return out

    time = None
    for a in root.findall("PolyData/FieldData/DataArray"):
        if a.get("Name") == "TimeValue":
            values = _read_array(fmt, a, appended)
            time = float(values[0]) if values else None
    points_el = piece.find("Points/DataArray")
    if points_el is None:
        raise VtkError(f"{path}: no Points")
    flat = _read_array(fmt, points_el, appended)
    points = [tuple(flat[i:i + 3]) for i in range(0, len(flat) - 2, 3)]
    cells = []
    for tag in ("Verts", "Lines"):
        block = arrays(piece.find(tag))
        if not block:
            continue
        if "connectivity" not in block or "offsets" not in block:
            raise VtkError(f"{path}: {tag} without connectivity and offsets")
        connectivity, start = block["connectivity"][1], 0
        for end in block["offsets"][1]:
            cells.append([int(i) for i in connectivity[start:end]])
            start = end
    cell_data = arrays(piece.find("CellData"))
    kinds = cell_kinds(cells, cell_data)
    return Frame(time=time, points=points, point_data=arrays(piece.find("PointData")),
                 cell_data=cell_data, cells=cells, kinds=kinds)

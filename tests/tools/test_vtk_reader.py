"""tools/screwfem_vtk.py reads a .vtp frame the same whatever the VTK XML encoding: ASCII,
inline base64 (header and data as one run or as separate runs, as VTK writes them), appended
raw or base64 data, UInt32 or UInt64 headers, either byte order, zlib-compressed blocks.

    /usr/bin/python3 -m unittest -v test_vtk_reader      (from tests/tools; SCREWFEM_SOURCE_DIR)
"""

import base64
import os
import struct
import sys
import tempfile
import unittest
import zlib

sys.path.insert(0, os.path.join(os.environ.get("SCREWFEM_SOURCE_DIR", "../.."), "tools"))
import screwfem_vtk  # noqa: E402

CODES = {"Float64": "d", "Int64": "q", "Int32": "i"}

# One frame in screwfem's layout: a joint vertex, a 3-node rod polyline and a body segment.
POINTS = [0.0, 0.0, 0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, -1.0, 1e-9, 2.5, 3.5, 4.5]
VELOCITY = [float(i) * 0.25 for i in range(18)]
VERTS = ([0], [1])
LINES = ([1, 2, 3, 4, 5], [3, 5])
CELL_ROD = [-1, 0, -1]
CELL_BODY = [-1, -1, 2]
CELL_JOINT = [4, -1, -1]


class Writer:
    def __init__(self, fmt, header="UInt64", order="<", compress=False, joint_base64=False,
                 appended_encoding="raw"):
        self.fmt, self.header, self.order = fmt, header, order
        self.compress, self.joint = compress, joint_base64
        self.appended_encoding = appended_encoding
        self.blob = b""

    def block(self, data):
        """Header + data bytes (uncompressed), or the compressed block layout."""
        h = "Q" if self.header == "UInt64" else "I"
        if not self.compress:
            return [struct.pack(f"{self.order}{h}", len(data)), data]
        # two blocks, to exercise the block list
        half = max(1, len(data) // 2)
        raw_blocks = [data[:half], data[half:]] if len(data) > 1 else [data]
        comp = [zlib.compress(b) for b in raw_blocks]
        head = struct.pack(f"{self.order}{3 + len(comp)}{h}", len(comp), half,
                           len(raw_blocks[-1]), *[len(c) for c in comp])
        return [head, b"".join(comp)]

    def array(self, type_name, name, values, ncomp=1):
        attrs = f'type="{type_name}" Name="{name}"' + (f' NumberOfComponents="{ncomp}"' if ncomp > 1 else "")
        if self.fmt == "ascii":
            text = " ".join(repr(v) for v in values)
            return f'<DataArray {attrs} format="ascii">{text}</DataArray>\n'
        data = struct.pack(f"{self.order}{len(values)}{CODES[type_name]}", *values)
        parts = self.block(data)
        if self.fmt == "binary":
            if self.joint:
                text = base64.b64encode(b"".join(parts)).decode()
            else:
                text = "".join(base64.b64encode(p).decode() for p in parts)
            return f'<DataArray {attrs} format="binary">\n  {text}\n</DataArray>\n'
        offset = len(self.blob)
        if self.appended_encoding == "raw":
            self.blob += b"".join(parts)
        else:
            self.blob += b"".join(base64.b64encode(p) for p in parts)
        return f'<DataArray {attrs} format="appended" offset="{offset}"/>\n'

    def cells(self, tag, cells):
        conn, offsets = cells
        return (f"<{tag}>\n" + self.array("Int64", "connectivity", conn) +
                self.array("Int64", "offsets", offsets) + f"</{tag}>\n")

    def frame(self):
        order = "BigEndian" if self.order == ">" else "LittleEndian"
        comp = ' compressor="vtkZLibDataCompressor"' if self.compress else ""
        body = ("<PolyData>\n<FieldData>\n" + self.array("Float64", "TimeValue", [0.125]) +
                "</FieldData>\n"
                '<Piece NumberOfPoints="6" NumberOfVerts="1" NumberOfLines="2">\n'
                "<PointData>\n" + self.array("Float64", "velocity", VELOCITY, 3) + "</PointData>\n"
                "<CellData>\n" + self.array("Int32", "rod_id", CELL_ROD) +
                self.array("Int32", "body_id", CELL_BODY) + self.array("Int32", "joint_id", CELL_JOINT) +
                "</CellData>\n<Points>\n" + self.array("Float64", "position", POINTS, 3) + "</Points>\n" +
                self.cells("Verts", VERTS) + self.cells("Lines", LINES) + "</Piece>\n</PolyData>\n")
        head = (f'<?xml version="1.0"?>\n<VTKFile type="PolyData" version="1.0" byte_order="{order}" '
                f'header_type="{self.header}"{comp}>\n').encode()
        out = head + body.encode()
        if self.fmt == "appended":
            out += (f'<AppendedData encoding="{self.appended_encoding}">\n_').encode() + self.blob + \
                b"\n</AppendedData>\n"
        return out + b"</VTKFile>\n"


class ReadFrame(unittest.TestCase):
    def read(self, writer):
        with tempfile.NamedTemporaryFile(suffix=".vtp", delete=False) as f:
            f.write(writer.frame())
        try:
            return screwfem_vtk.read_frame(f.name)
        finally:
            os.unlink(f.name)

    def check(self, frame):
        self.assertEqual(frame["time"], 0.125)
        self.assertEqual([c for p in frame["points"] for c in p], POINTS)
        self.assertEqual(frame["point_data"]["velocity"], (3, VELOCITY))
        self.assertEqual(frame["cells"], [[0], [1, 2, 3], [4, 5]])
        self.assertEqual(frame["kinds"], ["joint", "rod", "body"])
        self.assertEqual(frame["cell_data"]["joint_id"][1], CELL_JOINT)

    def test_ascii(self):
        self.check(self.read(Writer("ascii")))

    def test_inline_base64_in_every_variant(self):
        for header in ("UInt32", "UInt64"):
            for order in ("<", ">"):
                for compress in (False, True):
                    for joint in (False, True):
                        with self.subTest(header=header, order=order, compress=compress, joint=joint):
                            self.check(self.read(Writer("binary", header, order, compress, joint)))

    def test_appended_raw_and_base64(self):
        for encoding in ("raw", "base64"):
            for header in ("UInt32", "UInt64"):
                for compress in (False, True):
                    with self.subTest(encoding=encoding, header=header, compress=compress):
                        self.check(self.read(Writer("appended", header, "<", compress,
                                                    appended_encoding=encoding)))

    def test_unsupported_compressor_is_named(self):
        data = Writer("ascii").frame().replace(b'header_type="UInt64"',
                                               b'header_type="UInt64" compressor="vtkLZ4DataCompressor"')
        with tempfile.NamedTemporaryFile(suffix=".vtp", delete=False) as f:
            f.write(data)
        try:
            with self.assertRaisesRegex(screwfem_vtk.VtkError, "vtkLZ4DataCompressor"):
                screwfem_vtk.read_frame(f.name)
        finally:
            os.unlink(f.name)


class ReadCollection(unittest.TestCase):
    def test_frames_without_pvd_are_found_with_their_times(self):
        with tempfile.TemporaryDirectory() as d:
            os.makedirs(os.path.join(d, "vtk"))
            for i in (1, 0):
                data = Writer("binary").frame()
                with open(os.path.join(d, "vtk", f"frame_{i:05d}.vtp"), "wb") as f:
                    f.write(data)
            frames = screwfem_vtk.read_collection(d)
            self.assertEqual([os.path.basename(p) for _, p in frames], ["frame_00000.vtp", "frame_00001.vtp"])
            self.assertEqual([t for t, _ in frames], [0.125, 0.125])

    def test_pvd_gives_times_and_files(self):
        with tempfile.TemporaryDirectory() as d:
            os.makedirs(os.path.join(d, "vtk"))
            with open(os.path.join(d, "vtk", "motion.pvd"), "w") as f:
                f.write('<?xml version="1.0"?>\n<VTKFile type="Collection"><Collection>\n'
                        '<DataSet timestep="0.5" file="frame_00001.vtp"/>\n'
                        '<DataSet timestep="0" file="frame_00000.vtp"/>\n</Collection></VTKFile>\n')
            frames = screwfem_vtk.read_collection(d)
            self.assertEqual([(t, os.path.basename(p)) for t, p in frames],
                             [(0.0, "frame_00000.vtp"), (0.5, "frame_00001.vtp")])
            self.assertIsNone(screwfem_vtk.read_collection(os.path.join(d, "vtk")))


if __name__ == "__main__":
    unittest.main()

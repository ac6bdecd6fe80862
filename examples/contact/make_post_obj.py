"""Writes post.obj, the mesh of examples/contact/mesh_wrap.yaml: a prism of 32 facets inscribed
in a cylinder of radius 0.05 m and length 0.4 m, axis along y, centred on the origin, faces
counter-clockwise seen from outside (quads on the side, polygons on the ends).

Run: /usr/bin/python3 examples/contact/make_post_obj.py (from the repository root)."""
import math
import pathlib

N, R, L = 32, 0.05, 0.4
lines = [f"# {N}-facet prism, radius {R} m, length {L} m, axis y (make_post_obj.py)"]
for y in (-L / 2, L / 2):
    for k in range(N):
        a = 2 * math.pi * k / N
        lines.append(f"v {R * math.cos(a):.17g} {y:.17g} {R * math.sin(a):.17g}")
for k in range(N):  # side quads; outward normal radial
    a, b = k + 1, (k + 1) % N + 1
    lines.append(f"f {a} {a + N} {b + N} {b}")
lines.append("f " + " ".join(str(k + 1) for k in range(N)))  # the end at -y, normal -y
lines.append("f " + " ".join(str(N + k + 1) for k in reversed(range(N))))  # the end at +y
pathlib.Path(__file__).with_name("post.obj").write_text("\n".join(lines) + "\n")

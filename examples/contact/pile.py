#!/usr/bin/env python3
"""Scenes of piles: k crossed layers of n rods (or rigid capsules, or rods and boxes mixed)
dropped onto a ground plane (docs/numerics.md, "Impacts and piles"; bench/pile_bench.cpp).

The default pile is the one of the contact-rich-scenes issue: straight rods of 2 m with 40
elements, radius 12 mm, EA 5e5 N, EI 100 N m^2, 0.45 kg/m, the lowest layer 0.3 m above the
ground, each next layer 4 radii higher and turned by 90 degrees, steps of 1/240 s. Every contact
setting is left at its default (stiffness, onset, damping and the spectral radius are chosen for
the scene's masses: summary.json states them), so that the scene shows what a user gets.

    pile.py --layers 2 --rods 10 --friction 1 -o pile.yaml
    screwfem run pile.yaml -o out/pile

The script writes YAML only (no screwfem import), so it also serves the benchmark and the
tests; `scene(...)` returns the text, `load(path, ...)` a screwfem.Scene.
"""

import argparse
import sys

ROD = {"length": 2.0, "elements": 40, "radius": 0.012, "EA": 5e5, "EI": 100.0, "mass": 0.45}


def rod_section(rod=ROD):
    """The rods' section given by stiffness and inertia per length (translation first)."""
    r, ea, ei, m = rod["radius"], rod["EA"], rod["EI"], rod["mass"]
    ga = ea / (2 * 1.3)  # nu = 0.3
    gj = ei / 1.3  # G J = E I / (1 + nu)
    i = m * r * r / 4  # rho I per length
    return ("{stiffness: [%g, %g, %g, %g, %g, %g], inertia: [%g, %g, %g, %g, %g, %g]}"
            % (ea, ga, ga, gj, ei, ei, m, m, m, 2 * i, i, i))


def scene(layers=2, rods=10, friction=0.0, kind="rods", end_time=2.0, step=1 / 240,
          bottom=0.3, spacing=None, rod=ROD, stop_at_rest=False):
    """The YAML text of a pile. kind: 'rods' (soft rods), 'capsules' (rigid capsules of the
    rods' size and mass) or 'mixed' (soft rods, every other layer a row of boxes)."""
    if kind not in ("rods", "capsules", "mixed"):
        raise ValueError("kind: expected rods, capsules or mixed, got %r" % kind)
    length, r = rod["length"], rod["radius"]
    spacing = spacing if spacing is not None else length / rods
    mass = rod["mass"] * length
    out = ["# A pile of %d layers of %d %s, friction %g (examples/contact/pile.py)"
           % (layers, rods, kind, friction),
           "name: \"Pile: %d x %d %s, mu = %g\"" % (layers, rods, kind, friction),
           "units: SI", "gravity: [0, 0, -9.81]", "",
           "sections:", "  cable: " + rod_section(rod), "", "bodies:"]
    for layer in range(layers):
        z = bottom + 4 * r * layer
        along_x = layer % 2 == 0
        for i in range(rods):
            c = (i - (rods - 1) / 2) * spacing
            a = [-length / 2, c, z] if along_x else [c, -length / 2, z]
            b = [length / 2, c, z] if along_x else [c, length / 2, z]
            name = "L%dR%d" % (layer, i)
            p = lambda v: "[%.6g, %.6g, %.6g]" % tuple(v)
            mid = [(a[k] + b[k]) / 2 for k in range(3)]
            if kind == "capsules" or (kind == "mixed" and layer % 2 == 1 and i % 2 == 1):
                if kind == "capsules":
                    iy = mass * (length * length / 12 + r * r / 4)
                    ix = mass * r * r / 2
                    inertia = [ix, iy, iy] if along_x else [iy, ix, iy]
                    shape = "{type: capsule, from: %s, to: %s, radius: %g}" % (
                        p(a), p(b), r)
                else:  # a box of the rod's footprint, as heavy as the rod
                    h = [length / 4, 2 * r, r] if along_x else [2 * r, length / 4, r]
                    inertia = [mass * (h[1] ** 2 + h[2] ** 2) / 3,
                               mass * (h[0] ** 2 + h[2] ** 2) / 3,
                               mass * (h[0] ** 2 + h[1] ** 2) / 3]
                    shape = "{type: box, center: %s, half_sizes: [%g, %g, %g]}" % (
                        p(mid), h[0], h[1], h[2])
                out.append("  %s: {type: rigid, at: %s, mass: %g, inertia: [%g, %g, %g], "
                           "free: true, shapes: [%s]}" % (name, p(mid), mass, *inertia, shape))
            else:
                out.append("  %s: {type: soft, from: %s, to: %s, section: cable, elements: %d, "
                           "free: true, contact_radius: %g}"
                           % (name, p(a), p(b), rod["elements"], r))
    out += ["", "contact:", "  friction: %g" % friction, "  obstacles:",
            "    ground: {type: plane, point: [0, 0, 0], normal: [0, 0, 1]}", ""]
    analysis = "analysis: {type: dynamic, end_time: %g, step: %.17g" % (end_time, step)
    if stop_at_rest:
        analysis += ", stop_at_rest: true"
    out += [analysis + "}", "outputs: {interval: %g}" % (1 / 30), ""]
    return "\n".join(out)


def load(path, **kwargs):
    """Writes the pile to `path` and loads it as a screwfem.Scene (needs the module)."""
    import screwfem
    with open(path, "w") as f:
        f.write(scene(**kwargs))
    return screwfem.load_scene(str(path))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--layers", type=int, default=2)
    ap.add_argument("--rods", type=int, default=10, help="rods per layer")
    ap.add_argument("--friction", type=float, default=0.0)
    ap.add_argument("--kind", default="rods", choices=("rods", "capsules", "mixed"))
    ap.add_argument("--end-time", type=float, default=2.0)
    ap.add_argument("--step", type=float, default=1 / 240)
    ap.add_argument("--stop-at-rest", action="store_true")
    ap.add_argument("-o", "--output", help="YAML file to write (default: standard output)")
    a = ap.parse_args(argv)
    if a.layers < 1 or a.rods < 1:
        ap.error("--layers and --rods must be at least 1")
    text = scene(a.layers, a.rods, a.friction, a.kind, a.end_time, a.step,
                 stop_at_rest=a.stop_at_rest)
    if a.output:
        with open(a.output, "w") as f:
            f.write(text)
    else:
        sys.stdout.write(text)


if __name__ == "__main__":
    main()

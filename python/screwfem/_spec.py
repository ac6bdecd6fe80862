"""The scene as data: ``SceneSpec``, the construction vocabulary of screwfem in Python.

A scene read from a file (``read_scene_spec``) and a scene built in code are the same kind of
object, compiled by the same compiler (C++ ``CompileScene``, include/screwfem/io/scene_spec.h)
into a ``Scene`` -- as MuJoCo's mjSpec is for MJCF. The classes mirror the C++ structs of
scene_spec.h field for field (the C++ names; each attribute's documentation gives the scene
file's key where it differs). Entities refer to each other by index, as in C++; the adders
(``SceneSpec.add_soft_body``, ``add_joint``, ...) take names, check every value and raise
``InputError`` (a ValueError) naming the entity and the field
("<python spec>: bodies.crank.mass: expected a positive number, got -1").

The objects are plain Python data: lists are Python lists, an entity returned by an adder is
the one in the spec (editing it edits the spec). ``SceneSpec.compile`` converts the whole spec
to C++ and checks it again, so an entity edited after it was added is checked too.

docs/python.md, "Building a scene in code", shows the API with the GRM of the method paper.
"""

import dataclasses
import inspect
import math
import numbers
import os
from dataclasses import dataclass, field
from typing import Any

from . import _screwfem as _m

SOURCE_NAME = "<python spec>"

_ZERO3 = (0.0, 0.0, 0.0)
_ZERO6 = (0.0,) * 6
_IDENTITY3 = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


def _f(default=dataclasses.MISSING, *, factory=dataclasses.MISSING, doc, scene=None):
    """A dataclass field with its documentation (and the scene file's key, where it differs)."""
    meta = {"doc": doc, "scene": scene}
    if factory is not dataclasses.MISSING:
        return field(default_factory=factory, metadata=meta)
    return field(default=default, metadata=meta)


def _documented(cls):
    """Appends the documentation of every attribute to the class docstring (help(BodySpec))."""
    lines = [inspect.cleandoc(cls.__doc__), "",
             "Attributes (C++ names; the scene file's key where it differs):"]
    for f in dataclasses.fields(cls):
        scene = f.metadata.get("scene")
        lines.append(f"    {f.name}" + (f"  [scene: {scene}]" if scene else ""))
        lines.append(f"        {f.metadata.get('doc', '')}")
    cls.__doc__ = "\n".join(lines)
    return cls


def _profile_factory(value):
    return lambda: _m.Profile.constant(value)


# ---- the entities (scene_spec.h) ----------------------------------------------------------------


@_documented
@dataclass(slots=True)
class BodySpec:
    """A body (C++ BodySpec; the scene's ``bodies:``): a rigid body at a node, or a soft body, a
    rod along a polyline. Made by SceneSpec.add_rigid_body and SceneSpec.add_soft_body."""

    name: str = _f("", doc="Unique among the bodies; not 'ground'.")
    rigid: bool = _f(True, doc="True: a rigid body; False: a soft body (a rod).",
                     scene="type: rigid | soft")
    free: bool = _f(False, doc="Floating on purpose: connected to nothing.")
    fixed: bool = _f(False, doc="Rigid bodies: welded to the ground.")
    origin: Any = _f(_ZERO3, doc="Rigid bodies: the origin of the body frame [m], world; the "
                     "frame is world-aligned in the reference configuration.",
                     scene="at, or the first point of between")
    com: Any = _f(_ZERO3, doc="Rigid bodies: the centre of mass [m], world.",
                  scene="com (default: the midpoint of between, or at)")
    mass: float = _f(0.0, doc="Rigid bodies: the mass [kg], > 0.")
    inertia: Any = _f(_IDENTITY3, doc="Rigid bodies: about the centre of mass, world-aligned "
                      "axes [kg m^2]: a 3x3 matrix, 9 numbers row by row or 3 principal "
                      "moments; symmetric positive definite.")
    has_initial_velocity: bool = _f(False, doc="Rigid bodies: initial_linear and "
                                    "initial_angular hold.", scene="initial_velocity given")
    initial_linear: Any = _f(_ZERO3, doc="Initial velocity of the centre of mass [m/s], world.",
                             scene="initial_velocity.linear")
    initial_angular: Any = _f(_ZERO3, doc="Initial angular velocity [rad/s], world.",
                              scene="initial_velocity.angular")
    path: list = _f(factory=list, doc="Soft bodies: the polyline, at least two points [m], "
                    "world.", scene="from and to, or path")
    elements: int = _f(8, doc="Soft bodies: elements per path segment, 1 ... 100000.",
                       scene="elements (default: defaults.elements)")
    section: Any = _f(factory=lambda: _m.Section(), doc="Soft bodies: the Section "
                      "(Section(stiffness, inertia), Section.circle, .rectangle, .tube).",
                      scene="section, a name of sections:")
    up: Any = _f((0.0, 0.0, 1.0), doc="Soft bodies: the section z axis is as close as possible "
                 "to this vector.", scene="up (default: defaults.up)")
    weld_start: int = _f(-1, doc="Soft bodies: an earlier soft body (index or name) whose node "
                         "at the first point is shared: a clamp without unknowns; -1: none.")
    weld_end: int = _f(-1, doc="The same at the last point.")
    contact_radius: float = _f(0.0, doc="Soft bodies, with contact: the capsule radius [m] "
                               "(add_soft_body takes the section's radius by default).")
    visual_radius: float = _f(0.0, doc="Soft bodies: the radius the rod is drawn with [m] (VTK "
                              "frames, viewer), for drawing only; 0: the section's own size.",
                              scene="visual_radius (of the body, else of its section)")
    shapes: list = _f(factory=list, doc="Rigid bodies, with contact: ContactShape objects in "
                      "the body frame [m] (add_rigid_body takes world points, as the scene).")
    contype: int = _f(1, doc="Contact group bitmask (MuJoCo's contype).")
    conaffinity: int = _f(1, doc="Contact group bitmask (MuJoCo's conaffinity).")


@_documented
@dataclass(slots=True)
class JointEntrySpec:
    """A joint between two bodies, or a body and the ground (C++ JointEntrySpec; the scene's
    ``joints:``). The builder's JointSpec holds its type, point, axes, springs and drive; the
    compiler finds the sides' nodes. Made by SceneSpec.add_joint."""

    body_a: int = _f(-1, doc="Side a: a body index (or name); -1: the ground.",
                     scene="between[0]")
    body_b: int = _f(-1, doc="Side b, which receives the reaction of reactions.csv.",
                     scene="between[1]")
    joint: Any = _f(factory=lambda: _m.JointSpec(), doc="The JointSpec: name, type, point "
                    "[m] (scene: at), axis, axis2, pitch, stiffness, damping, rest, drive, "
                    "drive_coordinate, drive_profile (scene: drive: {type, coordinate, "
                    "profile}), initial_coordinate (scene: initial_position), initial_rate "
                    "(scene: initial_velocity); node_a and node_b are the compiler's.")

    @property
    def name(self):
        """The joint's name (joint.name)."""
        return self.joint.name

    @name.setter
    def name(self, value):
        self.joint.name = value


@_documented
@dataclass(slots=True)
class LoadSpec:
    """An applied load (C++ LoadSpec; the scene's ``loads:``): at a point of a body, at an arc
    length of a soft body, or distributed along it. Made by SceneSpec.add_load."""

    name: str = _f("", doc="For messages (the model's loads have no names); may be empty.")
    body: int = _f(-1, doc="The body (index or name).")
    where: str = _f("at", doc="'at': at the point `at` (a rigid body's point, a soft body's "
                    "node); 's': at arc_length; 'distributed': per unit length over the rod.",
                    scene="at, s or distributed: true")
    at: Any = _f(_ZERO3, doc="[m], world.")
    arc_length: float = _f(0.0, doc="[m] from the rod's first point.", scene="s")
    frame: Any = _f(_m.LoadFrame.WORLD, doc="LoadFrame.WORLD (dead load) or BODY (follower); "
                    "or its name.")
    force: Any = _f(_ZERO3, doc="[N] (distributed: [N/m]).")
    moment: Any = _f(_ZERO3, doc="[N m] (distributed: [N m/m]).")
    profile: Any = _f(factory=_profile_factory(1.0), doc="Profile multiplying force and moment.")


@_documented
@dataclass(slots=True)
class BodyPointSpec:
    """A point of a body or of the ground: a tendon eyelet, a force element's end (C++
    BodyPointSpec; the scene's body points). The adders take the scene's form, a dict
    {'body': NAME, 'at': POINT} or {'body': SOFT, 's': S, 'offset': [x, y, z]}."""

    body: int = _f(-1, doc="A body (index or name); -1: the ground.")
    along_rod: bool = _f(False, doc="Soft bodies: the point is at arc_length (else at the "
                         "node at `at`).", scene="s given")
    at: Any = _f(_ZERO3, doc="[m], world (the ground's or a rigid body's point, or a rod node).")
    arc_length: float = _f(0.0, doc="[m].", scene="s")
    offset: Any = _f(_ZERO3, doc="Soft bodies: offset from the section's centre, section-frame "
                     "components [m] (x along the rod).")
    routed: bool = _f(False, doc="Tendon eyelets: this item stands for the eyelets of `route` "
                      "along the soft body `body`.", scene="route given")
    route: Any = _f(None, doc="A RodRoute (every, from_, to, offset, helix_radius, helix_pitch, "
                    "helix_phase) when routed; its rod is set from `body` when compiled.",
                    scene="route")


@_documented
@dataclass(slots=True)
class TendonSpec:
    """A tendon through eyelets (C++ TendonSpec; the scene's ``tendons:``), pulled by a tension
    or drawn by length. Made by SceneSpec.add_tendon."""

    name: str = _f("", doc="Unique among the tendons.")
    eyelets: list = _f(factory=list, doc="BodyPointSpec objects in routing order (>= 2).")
    tension: Any = _f(factory=_profile_factory(0.0), doc="Profile of the tension [N] >= 0.")
    by_length: bool = _f(False, doc="Drawn by length instead of tension.", scene="length given")
    length: Any = _f(factory=_profile_factory(0.0), doc="Profile of the route length [m] "
                     "(by_length).")


@_documented
@dataclass(slots=True)
class ForceSpec:
    """A spring-damper-actuator between two body points (C++ ForceSpec; the scene's
    ``forces:``). Made by SceneSpec.add_force."""

    name: str = _f("", doc="Unique among the force elements.")
    a: Any = _f(factory=BodyPointSpec, doc="One end (BodyPointSpec).")
    b: Any = _f(factory=BodyPointSpec, doc="The other end (BodyPointSpec).")
    stiffness: float = _f(0.0, doc="[N/m] >= 0.")
    damping: float = _f(0.0, doc="[N s/m] >= 0.")
    rest_length: float = _f(-1.0, doc="[m]; negative: the reference distance.")
    actuator: Any = _f(factory=_profile_factory(0.0), doc="Profile of the actuator force [N], "
                       "positive pulling the ends together.", scene="force")


@_documented
@dataclass(slots=True)
class ActuatorSpec:
    """Actuation of a soft body's rod over a range of its arc length (C++ ActuatorSpec; the
    scene's ``actuation:``). Made by SceneSpec.add_actuator."""

    name: str = _f("", doc="Unique among the actuators.")
    type: Any = _f(_m.ActuatorType.ACTIVE_STRESS, doc="ActuatorType (or its name): PRESSURE, "
                   "MUSCLE, REST_STRAIN, ACTIVE_STRESS.")
    body: int = _f(-1, doc="The soft body (index or name).", scene="rod")
    from_: float = _f(0.0, doc="Start of the range, arc length [m] (a node there with "
                      "conform_mesh; else it must be at one).", scene="from")
    to: float = _f(-1.0, doc="End of the range [m] (as from_); negative: the rod's end.")
    area: float = _f(0.0, doc="Chamber or muscle area [m^2].")
    offset: Any = _f(_ZERO3, doc="Centroid (0, r2, r3) in the section frame [m].",
                     scene="offset [r2, r3]")
    max_stress: float = _f(0.0, doc="Muscles: [Pa].")
    vector: Any = _f(_ZERO6, doc="REST_STRAIN: eps0 per unit profile value; ACTIVE_STRESS: "
                     "sigma_a [N, N, N, N m, N m, N m].")
    profile: Any = _f(factory=_profile_factory(1.0), doc="Profile: the pressure [Pa], the "
                      "activation [-] or the factor of `vector`.",
                      scene="pressure, activation or profile")


@_documented
@dataclass(slots=True)
class OutputPointSpec:
    """A recorded point (C++ OutputPointSpec; the scene's ``outputs.points``): a point of a body
    at `at`, or a point along a soft body at an arc length. Made by SceneSpec.add_output_point."""

    name: str = _f("", doc="Column prefix in points.csv (NAME.x, NAME.vx, ...).")
    body: int = _f(-1, doc="The body (index or name).", scene="body, or rod with s")
    along_rod: bool = _f(False, doc="At arc_length of a soft body.", scene="s given")
    at: Any = _f(_ZERO3, doc="[m], world.")
    arc_length: float = _f(0.0, doc="[m].", scene="s")


@_documented
@dataclass(slots=True)
class ContactSpec:
    """Contact (C++ ContactSpec; the scene's ``contact:``). Set by SceneSpec.set_contact,
    add_obstacle and exclude_contact."""

    present: bool = _f(False, doc="The scene has contact.", scene="a contact: section")
    settings: Any = _f(factory=lambda: _m.ContactSettings(), doc="ContactSettings (stiffness, "
                       "onset, damping_ratio, friction, slip_velocity, friction_law, "
                       "static_friction, tangential_stiffness, self, self_skip).")
    obstacles: list = _f(factory=list, doc="ContactObstacle objects.")
    exclude: list = _f(factory=list, doc="(body, obstacle) index pairs that never touch.")
    exclude_bodies: list = _f(factory=list, doc="(body, body) index pairs that never touch.",
                              scene="exclude: [[body, body]]")
    groups: list = _f(factory=list, doc="Contact material groups: (name, body indices, "
                      "obstacle indices) tuples.", scene="groups (and pairs naming a body or "
                      "obstacle)")
    pairs: list = _f(factory=list, doc="ContactMaterial objects: the law per pair of groups "
                     "(groups: indices into groups).")


@_documented
@dataclass(slots=True)
class OutputsSpec:
    """What a run records (C++ OutputsSpec; the scene's ``outputs:``). Set by
    SceneSpec.set_outputs and add_output_point."""

    points: list = _f(factory=list, doc="OutputPointSpec objects.")
    all_joints: bool = _f(True, doc="Every joint with coordinates.", scene="joints: all")
    joints: list = _f(factory=list, doc="Joint indices (or names) recorded when not all_joints.")
    interval: float = _f(-1.0, doc="[s] between rows; 0: every step; negative: the scene's "
                         "default, about 1000 rows.")
    vtk: bool = _f(True, doc="ParaView files under vtk/.")
    vtk_format: Any = _f(_m.VtkFormat.BINARY, doc="VtkFormat (or its name).")
    vtk_interval: float = _f(-1.0, doc="[s] between frames; 0: as interval; negative: the "
                             "default (interval when that is given, else about 100 frames).")
    rod_fields: bool = _f(False, doc="Write rod_fields.csv (strain and stress per element).")
    rod_fields_interval: float = _f(-1.0, doc="[s] between rod_fields rows; 0: every step; "
                                    "negative: at the rows of points.csv.",
                                    scene="rod_fields: true or the interval")
    max_rows: int = _f(1000000, doc="Most output times a run records (rows per table, "
                       "rod_fields times, ParaView frames); check and run refuse a scene "
                       "estimated above it.")
    reactions: bool = _f(True, doc="Write reactions.csv; False: neither written nor computed.")
    energy: bool = _f(True, doc="Write energy.csv; False: neither written nor computed.")


# ---- value checks of the adders ----------------------------------------------------------------


def _error(where, what):
    return _m.InputError(f"{SOURCE_NAME}: {where}: {what}")


def _is_number(x):
    return isinstance(x, numbers.Real) and not isinstance(x, bool)


def _number(x, where):
    if not _is_number(x):
        raise _error(where, f"expected a number, got {x!r}")
    v = float(x)
    if not math.isfinite(v):
        raise _error(where, f"expected a finite number, got {x!r}")
    return v


def _vector(x, n, where, form="[x, y, z]"):
    if isinstance(x, (str, bytes)) or not hasattr(x, "__len__"):
        raise _error(where, f"expected {form} ({n} numbers), got {x!r}")
    if len(x) != n:
        raise _error(where, f"expected {form} ({n} numbers), got {len(x)}")
    return tuple(_number(v, f"{where}[{i}]") for i, v in enumerate(x))


def _profile(x, where):
    if isinstance(x, _m.Profile):
        return x
    return _m.Profile.constant(_number(x, where))


def _enum(cls, value, where):
    if isinstance(value, cls):
        return value
    if isinstance(value, str) and value.upper() in cls.__members__:
        return cls.__members__[value.upper()]
    names = ", ".join(name.lower() for name in cls.__members__)
    raise _error(where, f"expected one of {names}, got {value!r}")


def _bool(x, where):
    if not isinstance(x, bool):
        raise _error(where, f"expected True or False, got {x!r}")
    return x


def _polyline_length(points):
    return sum(math.dist(a, b) for a, b in zip(points, points[1:]))


# ---- the scene ----------------------------------------------------------------------------------


@_documented
@dataclass(slots=True, repr=False, eq=False)
class SceneSpec:
    """A scene as plain data (C++ SceneSpec, include/screwfem/io/scene_spec.h): what a scene
    file says, before compilation. ``read_scene_spec`` reads one from a file; the adders build
    one in code; ``compile()`` makes the Scene that ``run_scene`` and ``Simulation`` take.

    Points, materials and sections are values (the adders accept the names of ``points`` where
    a point is expected); entities refer to each other by index (the adders take names)."""

    name: str = _f("", doc="The scene's title (Scene.name).")
    gravity: Any = _f(_ZERO3, doc="[m/s^2], world.")
    rod_inertia: Any = _f(_m.RodInertia.EXACT, doc="RodInertia (or its name).",
                          scene="analysis.rod_inertia")
    linear_solver: Any = _f(_m.LinearSolver.AUTO, doc="LinearSolver (or its name).",
                            scene="analysis.linear_solver")
    conform_mesh: bool = _f(True, doc="Nodes where eyelets, force-element ends, concentrated "
                            "rod loads and actuator ends fall between a rod's nodes (ModelBuilder."
                            "set_conform_mesh).", scene="defaults.conform_mesh")
    points: dict = _f(factory=dict, doc="Named points: name -> (x, y, z) [m], world "
                      "(Scene.named_points).")
    inputs: dict = _f(factory=dict, doc="Run-time inputs: name -> default value, in order "
                      "(Profile.input takes their index; see input()).")
    bodies: list = _f(factory=list, doc="BodySpec objects, in order (node and rod numbering "
                      "follows it).")
    joints: list = _f(factory=list, doc="JointEntrySpec objects.")
    loads: list = _f(factory=list, doc="LoadSpec objects.")
    tendons: list = _f(factory=list, doc="TendonSpec objects.")
    forces: list = _f(factory=list, doc="ForceSpec objects.")
    actuators: list = _f(factory=list, doc="ActuatorSpec objects.", scene="actuation")
    contact: Any = _f(factory=ContactSpec, doc="ContactSpec.")
    analysis: Any = _f(factory=lambda: _m.AnalysisSettings(), doc="AnalysisSettings (set_analysis "
                       "takes the scene's keys); analysis.statics.time is set by compile().")
    outputs: Any = _f(factory=OutputsSpec, doc="OutputsSpec.")

    def __repr__(self):
        counts = ", ".join(f"{len(getattr(self, k))} {k}" for k in (
            "bodies", "joints", "loads", "tendons", "forces", "actuators"))
        return f"<screwfem.SceneSpec {self.name!r}: {counts}>"

    # -- compiling and copying

    def compile(self, source_name=SOURCE_NAME):
        """The Scene of this spec (C++ CompileScene, the compiler of scene files). Every value is
        checked; messages read 'SOURCE_NAME: FIELD: what' with the entity's place as a scene file
        would give it ('bodies.arm.path[1]', 'joints.J1.between[0]')."""
        return _m._compile_spec(self, source_name)

    def copy(self):
        """A deep copy (through the C++ SceneSpec)."""
        return _m._copy_spec(self)

    # -- names

    def body_index(self, body, where="body", ground=False):
        """The index of a body given by name, index or BodySpec (-1 for 'ground' if allowed)."""
        if isinstance(body, BodySpec):
            for i, b in enumerate(self.bodies):
                if b is body:
                    return i
            raise _error(where, f"body {body.name!r} is not in this spec")
        if isinstance(body, str):
            if ground and body == "ground":
                return -1
            for i, b in enumerate(self.bodies):
                if b.name == body:
                    return i
            known = ", ".join(b.name for b in self.bodies) or "none"
            raise _error(where, f"undefined body {body!r} (known: {known})")
        if isinstance(body, int) and not isinstance(body, bool):
            if (ground and body == -1) or 0 <= body < len(self.bodies):
                return body
            raise _error(where, f"no body {body} (the spec has {len(self.bodies)})")
        raise _error(where, f"expected a body name, got {body!r}")

    def joint_index(self, joint, where="joint"):
        """The index of a joint given by name or index."""
        if isinstance(joint, str):
            for i, j in enumerate(self.joints):
                if j.joint.name == joint:
                    return i
            known = ", ".join(j.joint.name for j in self.joints) or "none"
            raise _error(where, f"undefined joint {joint!r} (known: {known})")
        if isinstance(joint, int) and not isinstance(joint, bool) and 0 <= joint < len(self.joints):
            return joint
        raise _error(where, f"expected a joint name, got {joint!r}")

    def point(self, p, where="point"):
        """A point: the name of one of `points`, or [x, y, z] [m] -> (x, y, z)."""
        if isinstance(p, str):
            if p not in self.points:
                known = ", ".join(self.points) or "none"
                raise _error(where, f"undefined point {p!r} (known: {known})")
            return tuple(float(v) for v in self.points[p])
        return _vector(p, 3, where)

    def _add(self, collection, entity, items=None):
        """Appends an entity, checks it as compile() would, removes it again on error."""
        items = getattr(self, collection) if items is None else items
        items.append(entity)
        try:
            _m._check_spec_entity(self, collection, len(items) - 1, SOURCE_NAME)
        except BaseException:
            items.pop()
            raise
        return entity

    @staticmethod
    def _name(name, collection, what):
        if not isinstance(name, str) or not name:
            raise _error(collection, f"a {what} needs a name (a non-empty string), got {name!r}")
        return f"{collection}.{name}"

    # -- points and inputs

    def add_point(self, name, p):
        """A named point [m] (the scene's ``points:``) that the adders accept by name; returns
        its coordinates."""
        where = self._name(name, "points", "point")
        if name in self.points:
            raise _error(where, "defined twice")
        self.points[name] = _vector(p, 3, where)
        return self.points[name]

    def add_input(self, name, default=0.0):
        """A run-time input (the scene's ``inputs:``); returns its index (Profile.input)."""
        where = self._name(name, "inputs", "input")
        if name in self.inputs:
            raise _error(where, "defined twice")
        self.inputs[name] = _number(default, where)
        return len(self.inputs) - 1

    def input(self, name, scale=1.0):
        """The profile scale x input `name` (the scene's {type: input, name, value})."""
        names = list(self.inputs)
        if name not in names:
            raise _error(f"inputs.{name}", f"unknown input (known: {', '.join(names) or 'none'})")
        return _m.Profile.input(names.index(name), _number(scale, f"inputs.{name}.scale"))

    # -- bodies

    def add_rigid_body(self, name, *, mass, inertia, at=None, between=None, com=None, fixed=False,
                       free=False, initial_velocity=None, shapes=(), contype=1, conaffinity=1):
        """A rigid body (the scene's ``type: rigid``); returns its BodySpec.

        at: its frame's origin (a point or a name of `points`), or between: two points (the
        frame at the first, the centre of mass at the midpoint by default); mass [kg] > 0;
        inertia [kg m^2] about the centre of mass (3 principal moments, 9 numbers or 3x3);
        com: the centre of mass, world; fixed: welded to the ground; free: floating;
        initial_velocity: {'linear': [m/s], 'angular': [rad/s]} (world); shapes: contact shapes
        as the scene writes them ({'type': 'sphere', 'center', 'radius'}, {'type': 'capsule',
        'from', 'to', 'radius'}, {'type': 'box', 'center', 'half_sizes'}; world points);
        contype, conaffinity: contact group bitmasks."""
        path = self._name(name, "bodies", "body")
        if (at is None) == (between is None):
            raise _error(path, "give either between (two points) or at (one point)")
        if between is not None:
            if isinstance(between, str) or len(between) != 2:
                raise _error(f"{path}.between", f"expected two points [A, B], got {between!r}")
            a = self.point(between[0], f"{path}.between[0]")
            c = self.point(between[1], f"{path}.between[1]")
            if a == c:
                raise _error(f"{path}.between", "the two points coincide (zero-length body; "
                             "use at)")
            origin, center = a, tuple(0.5 * (x + y) for x, y in zip(a, c))
        else:
            origin = center = self.point(at, f"{path}.at")
        if com is not None:
            center = self.point(com, f"{path}.com")
        body = BodySpec(name=name, rigid=True, fixed=fixed, free=free, origin=origin,
                        com=center, mass=mass, inertia=inertia, contype=contype,
                        conaffinity=conaffinity)
        if initial_velocity is not None:
            where = f"{path}.initial_velocity"
            if not isinstance(initial_velocity, dict) or set(initial_velocity) - {"linear",
                                                                                  "angular"}:
                raise _error(where, "expected {'linear': [vx, vy, vz], 'angular': [wx, wy, wz]}")
            body.has_initial_velocity = True
            body.initial_linear = _vector(initial_velocity.get("linear", _ZERO3), 3,
                                          f"{where}.linear")
            body.initial_angular = _vector(initial_velocity.get("angular", _ZERO3), 3,
                                           f"{where}.angular")
        body.shapes = [self._shape(s, origin, f"{path}.shapes[{i}]")
                       for i, s in enumerate(shapes)]
        return self._add("bodies", body)

    def _shape(self, s, origin, where):
        if isinstance(s, _m.ContactShape):
            return s
        if not isinstance(s, dict) or "type" not in s:
            raise _error(where, f"expected a shape {{'type': ..., ...}}, got {s!r}")
        kind = _enum(_m.ContactShapeType, s["type"], f"{where}.type")
        keys = {_m.ContactShapeType.SPHERE: {"center", "radius"},
                _m.ContactShapeType.CAPSULE: {"from", "to", "radius"},
                _m.ContactShapeType.BOX: {"center", "half_sizes"}}[kind]
        extra = set(s) - keys - {"type"}
        if extra:
            raise _error(f"{where}.{sorted(extra)[0]}", f"not used by {kind.name.lower()} shapes")
        missing = keys - set(s)
        if missing:
            raise _error(where, f"missing key {sorted(missing)[0]!r}")

        def local(key):
            p = self.point(s[key], f"{where}.{key}")
            return tuple(x - o for x, o in zip(p, origin))

        if kind == _m.ContactShapeType.CAPSULE:
            return _m.ContactShape(-1, kind, local("from"), local("to"),
                                   _number(s["radius"], f"{where}.radius"))
        if kind == _m.ContactShapeType.BOX:
            half = _vector(s["half_sizes"], 3, f"{where}.half_sizes")
            if min(half) <= 0:
                raise _error(f"{where}.half_sizes", "expected positive half sizes")
            return _m.ContactShape(-1, kind, local("center"), half, 0.0)
        return _m.ContactShape(-1, kind, local("center"), local("center"),
                               _number(s["radius"], f"{where}.radius"))

    def add_soft_body(self, name, *, section, path=None, from_=None, to=None, elements=8,
                      up=(0.0, 0.0, 1.0), weld_start=None, weld_end=None, free=False,
                      contact_radius=None, visual_radius=0.0, contype=1, conaffinity=1):
        """A soft body, a rod (the scene's ``type: soft``); returns its BodySpec.

        path: at least two points (or names of `points`), or from_ and to: one segment;
        section: a Section; elements: per path segment; up: the section z axis is as close as
        possible to it; weld_start, weld_end: an earlier soft body (name) whose node at the
        first (last) point is shared; free: floating; contact_radius [m]: the capsule radius
        with contact (default: the radius of Section.circle, .rectangle or .tube);
        visual_radius [m]: the radius the rod is drawn with (0: the section's own size)."""
        where = self._name(name, "bodies", "body")
        if path is not None and (from_ is not None or to is not None):
            raise _error(f"{where}.path", "give either from_ and to, or path, not both")
        if path is None:
            if from_ is None or to is None:
                raise _error(where, "missing path (or from_ and to)")
            points = [self.point(from_, f"{where}.from"), self.point(to, f"{where}.to")]
        else:
            if isinstance(path, str) or not hasattr(path, "__len__"):
                raise _error(f"{where}.path", f"expected a list of points, got {path!r}")
            points = [self.point(p, f"{where}.path[{i}]") for i, p in enumerate(path)]
        if not isinstance(section, _m.Section):
            raise _error(f"{where}.section", "expected a Section (Section(stiffness, inertia), "
                         f"Section.circle, .rectangle or .tube), got {section!r}")
        if contact_radius is None:
            contact_radius = getattr(section, "radius", 0.0)
        body = BodySpec(name=name, rigid=False, free=free, path=points, elements=elements,
                        section=section, up=_vector(up, 3, f"{where}.up"),
                        contact_radius=contact_radius, visual_radius=visual_radius,
                        contype=contype,
                        conaffinity=conaffinity)
        if weld_start is not None:
            body.weld_start = self.body_index(weld_start, f"{where}.weld_start")
        if weld_end is not None:
            body.weld_end = self.body_index(weld_end, f"{where}.weld_end")
        return self._add("bodies", body)

    # -- joints

    def _axis(self, axis, where):
        if isinstance(axis, dict):
            if set(axis) != {"from", "to"}:
                raise _error(where, "expected [x, y, z] or {'from': POINT, 'to': POINT}")
            return tuple(float(v) for v in _m._axis_between(
                self.point(axis["from"], f"{where}.from"), self.point(axis["to"], f"{where}.to"),
                where))
        return tuple(float(v) for v in _m._unit_axis(_vector(axis, 3, where), where))

    @staticmethod
    def _per_coordinate(value, k, where, non_negative):
        if isinstance(value, (str, bytes)) or not hasattr(value, "__len__"):
            values = (_number(value, where),) * k
        else:
            values = _vector(value, k, where, form="one value per coordinate")
        if non_negative and any(not v >= 0 for v in values):
            raise _error(where, "expected values >= 0")
        return values + (0.0,) * (6 - k)

    def add_joint(self, name, type, *, between, at, axis=None, axis2=None, pitch=None,
                  stiffness=None, damping=None, rest=None, drive=None, initial_position=None,
                  initial_velocity=None):
        """A joint (the scene's ``joints:``); returns its JointEntrySpec.

        type: a JointType or its name ('revolute', 'prismatic', 'fixed', ...); between: the two
        sides, body names or 'ground'; at: the joint point; axis: [x, y, z] (unit) or
        {'from': POINT, 'to': POINT}; axis2 (universal joints, orthogonal to axis); pitch
        [m/rad] (helical); stiffness [N/m or N m/rad], damping, rest: one value for every
        coordinate (spring) or one per coordinate; drive: {'type': 'prescribed' | 'force' |
        'series_elastic', 'profile': Profile or number, 'coordinate': 0}; initial_position,
        initial_velocity: one value per coordinate."""
        path = self._name(name, "joints", "joint")
        joint_type = type if isinstance(type, _m.JointType) else _enum(_m.JointType, type,
                                                                        f"{path}.type")
        info = _m._joint_type_info(joint_type)
        who = f"{info['name']} joints"
        if isinstance(between, str) or not hasattr(between, "__len__") or len(between) != 2:
            raise _error(f"{path}.between", "expected two sides [A, B] (ground or body names), "
                         f"got {between!r}")
        body_a = self.body_index(between[0], f"{path}.between[0]", ground=True)
        body_b = self.body_index(between[1], f"{path}.between[1]", ground=True)
        j = _m.JointSpec()
        j.name = name
        j.type = joint_type
        j.point = self.point(at, f"{path}.at")

        def not_used(key, value, by=who):
            if value is not None:
                raise _error(f"{path}.{key}", f"'{key}' is not used by {by}")

        if info["uses_axis"]:
            if axis is None:
                raise _error(path, "missing axis")
            j.axis = self._axis(axis, f"{path}.axis")
        else:
            not_used("axis", axis)
        if info["uses_axis2"]:
            if axis2 is None:
                raise _error(path, "missing axis2")
            j.axis2 = _m._second_axis(j.axis, self._axis(axis2, f"{path}.axis2"),
                                      f"{path}.axis2")
        else:
            not_used("axis2", axis2)
        if info["uses_pitch"]:
            if pitch is None:
                raise _error(path, "missing pitch")
            j.pitch = _number(pitch, f"{path}.pitch")
        else:
            not_used("pitch", pitch)
        self._joint_options(j, info, path, stiffness, damping, rest, drive, initial_position,
                            initial_velocity)
        return self._add("joints", JointEntrySpec(body_a=body_a, body_b=body_b, joint=j))

    def _joint_options(self, j, info, path, stiffness, damping, rest, drive, initial_position,
                       initial_velocity):
        """Sets the springs, drive and initial state of JointSpec j (add_joint, add_urdf)."""
        who = f"{info['name']} joints"

        def not_used(key, value, by=who):
            if value is not None:
                raise _error(f"{path}.{key}", f"'{key}' is not used by {by}")

        k, springs = info["dof"], info["springs"]
        if springs == 0:
            for key, value in (("stiffness", stiffness), ("damping", damping), ("rest", rest),
                               ("drive", drive)):
                not_used(key, value)
        if not info["global_coordinates"]:
            not_used("rest", rest, f"{who} (no global coordinates)")
            not_used("drive", drive, f"{who} (no global coordinates)")
            not_used("initial_position", initial_position)
        if k == 0:
            not_used("initial_velocity", initial_velocity)
        if stiffness is not None:
            j.stiffness = self._per_coordinate(stiffness, springs, f"{path}.stiffness", True)
        if damping is not None:
            j.damping = self._per_coordinate(damping, springs, f"{path}.damping", True)
        if rest is not None:
            j.rest = self._per_coordinate(rest, k, f"{path}.rest", False)
        if initial_position is not None:
            j.has_initial_coordinate = True
            j.initial_coordinate = self._per_coordinate(initial_position, k,
                                                        f"{path}.initial_position", False)
        if initial_velocity is not None:
            j.has_initial_rate = True
            j.initial_rate = self._per_coordinate(initial_velocity, k,
                                                  f"{path}.initial_velocity", False)
        if drive is not None:
            where = f"{path}.drive"
            if not isinstance(drive, dict) or "type" not in drive or "profile" not in drive or (
                    set(drive) - {"type", "profile", "coordinate"}):
                raise _error(where, "expected {'type': ..., 'profile': ..., 'coordinate': 0}")
            j.drive = _enum(_m.DriveKind, drive["type"], f"{where}.type")
            if j.drive == _m.DriveKind.NONE:
                raise _error(f"{where}.type", "a passive joint has no drive")
            coordinate = drive.get("coordinate", 0)
            if not isinstance(coordinate, int) or not 0 <= coordinate < k:
                raise _error(f"{where}.coordinate", f"expected an integer in [0, {k - 1}], got "
                             f"{coordinate!r}")
            j.drive_coordinate = coordinate
            j.drive_profile = _profile(drive["profile"], f"{where}.profile")
            if j.drive == _m.DriveKind.SERIES_ELASTIC and not j.stiffness[coordinate] > 0:
                raise _error(where, "a series_elastic drive needs a positive stiffness on "
                             f"coordinate {coordinate} (the spring it drives)")

    def add_urdf(self, name, urdf, *, at=(0.0, 0.0, 0.0), orientation=None, fixed_base=True,
                 contype=1, conaffinity=1, joints=None):
        """A URDF robot (the scene's ``robots:``; docs/urdf.md): the links of the file `urdf`
        become rigid bodies 'NAME/LINK' and its joints joints 'NAME/JOINT', appended in the
        file's order (C++ AppendUrdf, include/screwfem/io/urdf.h, as the scene reader does).
        Returns the list of the JointEntrySpec objects added.

        at: the root link's origin [m] (a point or a name of `points`); orientation: the root
        link's rotation, {'quaternion': [w, x, y, z]}, {'axis': [x, y, z], 'angle': rad} or
        {'rpy': [roll, pitch, yaw]} (default: the identity); fixed_base: the root link is welded
        to the ground (else it floats); contype, conaffinity: the links' contact bitmasks;
        joints: {URDF joint name: {'stiffness', 'damping', 'rest', 'drive',
        'initial_position', 'initial_velocity'}} as add_joint takes them.
        Raises InputError naming the URDF element (see docs/urdf.md, "Errors")."""
        path = self._name(name, "robots", "robot")
        base = self.point(at, f"{path}.base.at")
        fixed_base = _bool(fixed_base, f"{path}.fixed_base")
        groups = []
        for key, value in (("contype", contype), ("conaffinity", conaffinity)):
            if not isinstance(value, int) or isinstance(value, bool) or not 0 <= value <= 2**30:
                raise _error(f"{path}.{key}", f"expected an integer from 0 to 1073741824, got "
                             f"{value!r}")
            groups.append(value)
        rotation = _m._orientation(orientation or {}, f"{SOURCE_NAME}: {path}.base.orientation")
        try:
            part = _m._read_urdf(os.fspath(urdf), name, base, rotation, fixed_base, *groups)
        except _m.InputError as e:
            raise _error(f"{path}.urdf", str(e)) from None
        known = {b.name for b in self.bodies}
        for b in part.bodies:
            if b.name in known:
                raise _error(f"{path}", f"the spec already has a body {b.name!r}")
        known = {j.joint.name for j in self.joints}
        for j in part.joints:
            if j.joint.name in known:
                raise _error(f"{path}", f"the spec already has a joint {j.joint.name!r}")
        prefix = name + "/"
        options = dict(joints or {})
        by_name = {j.joint.name[len(prefix):]: j for j in part.joints}
        for joint_name, keys in options.items():
            where = f"{path}.joints.{joint_name}"
            if joint_name not in by_name:
                raise _error(where, f"the URDF has no joint {joint_name!r} (known: "
                             f"{', '.join(by_name) or 'none'})")
            allowed = {"stiffness", "damping", "rest", "drive", "initial_position",
                       "initial_velocity"}
            if not isinstance(keys, dict) or set(keys) - allowed:
                raise _error(where, f"expected a dict with keys from {sorted(allowed)}, got "
                             f"{keys!r}")
            entry = by_name[joint_name]
            info = _m._joint_type_info(entry.joint.type)
            args = {k: keys.get(k) for k in sorted(allowed)}
            self._joint_options(entry.joint, info, where, **args)
        offset = len(self.bodies)
        self.bodies.extend(part.bodies)
        for j in part.joints:
            j.body_a = j.body_a + offset if j.body_a >= 0 else -1
            j.body_b = j.body_b + offset if j.body_b >= 0 else -1
        self.joints.extend(part.joints)
        return list(part.joints)

    # -- loads, tendons, force elements, actuation

    def add_load(self, name="", *, body, at=None, s=None, distributed=False, force=None,
                 moment=None, frame="world", profile=1.0):
        """A load (the scene's ``loads:``); returns its LoadSpec.

        body: a body name; at: a point (a rigid body's point, or a soft body's node), or s: an
        arc length [m] of a soft body, or distributed=True: per unit length over a soft body;
        force [N], moment [N m] (per metre when distributed); frame: 'world' (dead load) or
        'body' (follower); profile: a Profile (or a number) multiplying them."""
        where = f"loads.{name}" if name else f"loads[{len(self.loads)}]"
        load = LoadSpec(name=name, body=self.body_index(body, f"{where}.body"))
        if force is None and moment is None:
            raise _error(where, "missing force (or moment)")
        if force is not None:
            load.force = _vector(force, 3, f"{where}.force")
        if moment is not None:
            load.moment = _vector(moment, 3, f"{where}.moment")
        if (at is not None) + (s is not None) + bool(distributed) != 1:
            raise _error(where, "give one of at, s or distributed=True")
        if at is not None:
            load.at = self.point(at, f"{where}.at")
        elif s is not None:
            load.where, load.arc_length = "s", _number(s, f"{where}.s")
        else:
            load.where = "distributed"
        load.frame = _enum(_m.LoadFrame, frame, f"{where}.frame")
        load.profile = _profile(profile, f"{where}.profile")
        return self._add("loads", load)

    def body_point(self, p, where="point"):
        """A BodyPointSpec from the scene's form: {'at': POINT} (the ground), {'body': NAME,
        'at': POINT} (a rigid body's point, a soft body's node), {'body': SOFT, 's': S,
        'offset': [x, y, z]} (the section at arc length S, offset in its frame [m])."""
        if isinstance(p, BodyPointSpec):
            return dataclasses.replace(p, body=self.body_index(p.body, f"{where}.body",
                                                               ground=True))
        if isinstance(p, dict) and "route" in p:
            return self._route(p, where)
        if not isinstance(p, dict) or set(p) - {"body", "at", "s", "offset"}:
            raise _error(where, f"expected {{'body': NAME, 'at': POINT}} or {{'body': NAME, "
                         f"'s': S, 'offset': [x, y, z]}}, got {p!r}")
        body = self.body_index(p.get("body", "ground"), f"{where}.body", ground=True)
        point = BodyPointSpec(body=body)
        if body < 0 or self.bodies[body].rigid:
            who = "the ground" if body < 0 else "rigid bodies"
            for key in ("s", "offset"):
                if key in p:
                    raise _error(f"{where}.{key}", f"'{key}' is not used by {who} (give the "
                                 "point itself as 'at')")
            if "at" not in p:
                raise _error(where, "missing key 'at'")
            point.at = self.point(p["at"], f"{where}.at")
            return point
        if ("at" in p) == ("s" in p):
            raise _error(where, "give either 'at' or 's' (the rod node the point is fixed to)")
        if "at" in p:
            point.at = self.point(p["at"], f"{where}.at")
        else:
            point.along_rod, point.arc_length = True, _number(p["s"], f"{where}.s")
        if "offset" in p:
            point.offset = _vector(p["offset"], 3, f"{where}.offset")
        return point

    def _route(self, p, where):
        """The scene's {'route': {'body': SOFT, 'every': K, 'from': S0, 'to': S1, 'offset':
        [x, y, z], 'helix': {'radius': R, 'pitch': P, 'phase': A}}} as a routed BodyPointSpec."""
        if set(p) != {"route"} or not isinstance(p["route"], dict):
            raise _error(where, f"expected {{'route': {{'body': NAME, ...}}}}, got {p!r}")
        r, rp = p["route"], f"{where}.route"
        unknown = set(r) - {"body", "every", "from", "to", "offset", "helix"}
        if unknown:
            raise _error(f"{rp}.{sorted(unknown)[0]}", "unknown key (expected body, every, from, "
                         "to, offset, helix)")
        if "body" not in r:
            raise _error(rp, "missing key 'body'")
        body = self.body_index(r["body"], f"{rp}.body")
        if self.bodies[body].rigid:
            raise _error(f"{rp}.body", "a route runs along a soft body")
        route = _m.RodRoute()
        if "every" in r:
            every = _number(r["every"], f"{rp}.every")
            if every != int(every) or every < 1:
                raise _error(f"{rp}.every", f"expected an integer of at least 1, got {every!r}")
            route.every = int(every)
        if "from" in r:
            route.from_ = _number(r["from"], f"{rp}.from")
        if "to" in r:
            route.to = _number(r["to"], f"{rp}.to")
        if "offset" in r:
            route.offset = _vector(r["offset"], 3, f"{rp}.offset")
        if "helix" in r:
            h, hp = r["helix"], f"{rp}.helix"
            if not isinstance(h, dict) or set(h) - {"radius", "pitch", "phase"} or \
                    not {"radius", "pitch"} <= set(h):
                raise _error(hp, f"expected {{'radius': R, 'pitch': P, 'phase': A}}, got {h!r}")
            route.helix_radius = _number(h["radius"], f"{hp}.radius")
            route.helix_pitch = _number(h["pitch"], f"{hp}.pitch")
            route.helix_phase = _number(h.get("phase", 0.0), f"{hp}.phase")
        return BodyPointSpec(body=body, routed=True, route=route)

    def add_tendon(self, name, *, eyelets, tension=None, length=None):
        """A tendon (the scene's ``tendons:``); returns its TendonSpec.

        eyelets: body points in routing order (dicts as body_point takes them, e.g. from
        route_offset or route_helical); tension: a Profile (or number) [N] >= 0, or length: a
        Profile [m] that draws the tendon by length."""
        where = self._name(name, "tendons", "tendon")
        if isinstance(eyelets, (str, dict)) or not hasattr(eyelets, "__len__"):
            raise _error(f"{where}.eyelets", f"expected a list of body points, got {eyelets!r}")
        tendon = TendonSpec(name=name, eyelets=[
            self.body_point(p, f"{where}.eyelets[{i}]") for i, p in enumerate(eyelets)])
        if (tension is None) == (length is None):
            raise _error(where, "give either tension or length (the tendon is drawn by one of "
                         "them)")
        if length is not None:
            tendon.by_length, tendon.length = True, _profile(length, f"{where}.length")
        else:
            tendon.tension = _profile(tension, f"{where}.tension")
        return self._add("tendons", tendon)

    def add_force(self, name, *, a, b, stiffness=None, damping=None, rest_length=None,
                  force=None):
        """A force element (the scene's ``forces:``): spring [N/m], damper [N s/m] and actuator
        force (a Profile [N], positive in tension) between the body points a and b; rest_length
        [m] (default: the reference distance). Returns its ForceSpec."""
        where = self._name(name, "forces", "force element")
        if stiffness is None and damping is None and force is None:
            raise _error(where, "missing stiffness (or damping, or force)")
        f = ForceSpec(name=name, a=self.body_point(a, f"{where}.a"),
                      b=self.body_point(b, f"{where}.b"))
        if stiffness is not None:
            f.stiffness = _number(stiffness, f"{where}.stiffness")
        if damping is not None:
            f.damping = _number(damping, f"{where}.damping")
        if rest_length is not None:
            f.rest_length = _number(rest_length, f"{where}.rest_length")
            if f.rest_length < 0:
                raise _error(f"{where}.rest_length", "expected a number >= 0")
        if force is not None:
            f.actuator = _profile(force, f"{where}.force")
        return self._add("forces", f)

    def add_actuator(self, name, *, type, rod, from_=None, to=None, area=None, offset=None,
                     pressure=None, max_stress=None, activation=None, vector=None,
                     profile=None):
        """Actuation of a soft body (the scene's ``actuation:``); returns its ActuatorSpec.

        type: 'pressure' (area [m^2], offset [r2, r3] [m], pressure [Pa]), 'muscle' (area,
        offset, max_stress [Pa], activation [-]), 'rest_strain' or 'active_stress' (vector: 6
        values, profile); rod: the soft body; from_, to: the range of arc length [m]."""
        where = self._name(name, "actuation", "actuator")
        a = ActuatorSpec(name=name, type=_enum(_m.ActuatorType, type, f"{where}.type"),
                         body=self.body_index(rod, f"{where}.rod"))
        if from_ is not None:
            a.from_ = _number(from_, f"{where}.from")
        if to is not None:
            a.to = _number(to, f"{where}.to")
        given = {k for k, v in (("area", area), ("offset", offset), ("pressure", pressure),
                                ("max_stress", max_stress), ("activation", activation),
                                ("vector", vector), ("profile", profile)) if v is not None}
        kind = a.type.name.lower()
        pressure_type, muscle = _m.ActuatorType.PRESSURE, _m.ActuatorType.MUSCLE
        if a.type in (pressure_type, muscle):
            allowed = {"area", "offset", "pressure"} if a.type == pressure_type else {
                "area", "offset", "max_stress", "activation"}
            value_key = "pressure" if a.type == pressure_type else "activation"
            required = allowed
        else:
            allowed, required, value_key = {"vector", "profile"}, {"vector"}, "profile"
        for key in sorted(given - allowed):
            raise _error(f"{where}.{key}", f"'{key}' is not used by type '{kind}'")
        for key in sorted(required - given):
            raise _error(where, f"missing key '{key}'")
        if area is not None:
            a.area = _number(area, f"{where}.area")
        if offset is not None:
            o = tuple(offset) if hasattr(offset, "__len__") else offset
            if not hasattr(o, "__len__") or len(o) not in (2, 3):
                raise _error(f"{where}.offset", "expected [r2, r3] (or [0, r2, r3]) in the "
                             f"section frame [m], got {offset!r}")
            o = _vector(o, len(o), f"{where}.offset", form="[r2, r3]")
            a.offset = (0.0,) + o if len(o) == 2 else o
        if max_stress is not None:
            a.max_stress = _number(max_stress, f"{where}.max_stress")
        if vector is not None:
            a.vector = _vector(vector, 6, f"{where}.vector", form="6 values")
        value = {"pressure": pressure, "activation": activation, "profile": profile}[value_key]
        if value is not None:
            a.profile = _profile(value, f"{where}.{value_key}")
        return self._add("actuators", a)

    # -- contact

    def set_contact(self, **settings):
        """Turns contact on (the scene's ``contact:``) with its settings: stiffness [N/m], onset
        [m], damping_ratio, friction, slip_velocity [m/s], friction_law ('stick' or 'smooth'),
        static_friction, tangential_stiffness [N/m], self (bool), self_skip [m]."""
        c = self.contact
        for key, value in settings.items():
            where = f"contact.{key}"
            if key == "self":
                c.settings.self = _bool(value, where)
            elif key == "friction_law":
                c.settings.friction_law = _enum(_m.FrictionLaw, value, where)
            elif key in ("stiffness", "onset", "damping_ratio", "friction", "slip_velocity",
                         "static_friction", "tangential_stiffness", "self_skip"):
                setattr(c.settings, key, _number(value, where))
            else:
                raise _error(where, "unknown key (stiffness, onset, damping_ratio, friction, "
                             "slip_velocity, friction_law, static_friction, "
                             "tangential_stiffness, self, self_skip)")
        c.present = True
        return c

    def add_obstacle(self, name, type, *, point=None, normal=None, center=None, from_=None,
                     to=None, radius=None, contype=1, conaffinity=1):
        """An obstacle fixed in the world (the scene's ``contact.obstacles``): 'plane' (point,
        normal), 'sphere' (center, radius) or 'capsule' (from_, to, radius); turns contact on.
        Returns its ContactObstacle."""
        where = self._name(name, "contact.obstacles", "obstacle")
        if any(o.name == name for o in self.contact.obstacles):
            raise _error(where, "defined twice")
        o = _m.ContactObstacle()
        o.name = name
        o.type = _enum(_m.ObstacleType, type, f"{where}.type")
        if o.type == _m.ObstacleType.PLANE:
            o.point = self.point(point, f"{where}.point")
            o.normal = self._axis(normal, f"{where}.normal")
        else:
            o.radius = _number(radius, f"{where}.radius")
            if o.type == _m.ObstacleType.SPHERE:
                o.point = self.point(center, f"{where}.center")
            else:
                o.point = self.point(from_, f"{where}.from")
                o.to = self.point(to, f"{where}.to")
        o.contype, o.conaffinity = contype, conaffinity
        self.contact.obstacles.append(o)
        self.contact.present = True
        return o

    def exclude_contact(self, body, other):
        """No contact between a body and an obstacle, or between two bodies (names)."""
        a = self.body_index(body, "contact.exclude[0]")
        names = [o.name for o in self.contact.obstacles]
        if other in names:
            self.contact.exclude.append((a, names.index(other)))
        else:
            b = self.body_index(other, "contact.exclude[1]")
            if a == b:
                raise _error("contact.exclude", "a body cannot be excluded from itself")
            self.contact.exclude_bodies.append((a, b))

    def add_contact_group(self, name, members):
        """A contact material group (the scene's ``contact.groups``): bodies and obstacles by
        name, each in one group at most; turns contact on. Returns its index."""
        where = self._name(name, "contact.groups", "contact group")
        c = self.contact
        if any(g[0] == name for g in c.groups):
            raise _error(where, "defined twice")
        obstacles = [o.name for o in c.obstacles]
        if name in obstacles or any(b.name == name for b in self.bodies):
            raise _error(where, "a contact group cannot take the name of a body or obstacle "
                         f"('{name}')")
        bodies, obs = [], []
        for i, member in enumerate(members):
            w = f"{where}[{i}]"
            if member in obstacles:
                index, kind = obstacles.index(member), obs
            else:
                index, kind = self.body_index(member, w), bodies
            for g in c.groups:
                if index in (g[2] if kind is obs else g[1]):
                    raise _error(w, f"'{member}' is in contact group '{g[0]}' already (each "
                                 "body or obstacle is in one group at most)")
            kind.append(index)
        c.groups.append((name, bodies, obs))
        c.present = True
        return len(c.groups) - 1

    def add_contact_pair(self, a, b, *, friction=None, static_friction=None, stiffness=None,
                         damping_ratio=None, tangential_stiffness=None, onset=None):
        """The contact law of a pair of groups (the scene's ``contact.pairs``): a and b are
        group names, or a body's or obstacle's name in no group (a group of its own);
        friction (mu_k), static_friction (mu_s >= mu_k), stiffness [N/m], damping_ratio,
        tangential_stiffness [N/m], onset [m] (the gap at which the pair's force starts), each
        defaulting to the scene's contact settings. Returns its
        ContactMaterial."""
        c = self.contact
        where = f"contact.pairs[{len(c.pairs)}]"
        obstacles = [o.name for o in c.obstacles]

        new_groups = []  # groups of their own, added only when the pair is valid

        def group(name, w):
            for i, g in enumerate(c.groups + new_groups):
                if g[0] == name:
                    return i
            if name in obstacles:
                index, slot = obstacles.index(name), 2
            else:
                index, slot = self.body_index(name, w), 1
            for g in c.groups:
                if index in g[slot]:
                    raise _error(w, f"'{name}' is in contact group '{g[0]}': name the group")
            new_groups.append((name, [index] if slot == 1 else [], [index] if slot == 2 else []))
            return len(c.groups) + len(new_groups) - 1

        m = _m.ContactMaterial()
        ga, gb = group(a, f"{where}.groups[0]"), group(b, f"{where}.groups[1]")
        for p in c.pairs:
            if sorted(p.groups) == sorted((ga, gb)):
                raise _error(f"{where}.groups", f"the pair [{a}, {b}] is given twice")
        m.groups = (ga, gb)
        for key, value in (("friction", friction), ("static_friction", static_friction),
                           ("stiffness", stiffness), ("damping_ratio", damping_ratio),
                           ("tangential_stiffness", tangential_stiffness), ("onset", onset)):
            if value is not None:
                v = _number(value, f"{where}.{key}")
                stiff = key in ("stiffness", "tangential_stiffness", "onset")
                if v < 0 or (v == 0 and stiff):
                    sign = "positive" if stiff else "non-negative"
                    raise _error(f"{where}.{key}", f"expected a {sign} number, got {value!r}")
                setattr(m, key, v)
        kinetic = m.friction if m.friction >= 0 else c.settings.friction
        if m.static_friction >= 0 and m.static_friction < kinetic:
            raise _error(f"{where}.static_friction", f"expected a value >= the pair's friction "
                         f"{kinetic:g} (mu_s >= mu_k)")
        c.groups.extend(new_groups)
        c.pairs.append(m)
        c.present = True
        return m

    # -- analysis and outputs

    def set_analysis(self, **keys):
        """Sets the analysis with the scene's ``analysis:`` keys (docs/scene-format.md): type
        ('dynamic' | 'static'), start_time, end_time [s], step [s] or 'auto' (with tolerance,
        min_step, max_step, initial_step), rho_inf, tolerances ({increment, constraint,
        residual}), max_iterations, max_halvings, load_steps, align_steps, static_preload,
        rod_inertia, linear_solver, newton, predictor, convergence, restart_at_breakpoints,
        perturbed_start, constraints, statics ({method, end_load_factor, max_steps, arc_length, arc_length_min,
        arc_length_max, desired_iterations, psi, rotation_weight, exact_tangent}), threads
        ('auto' or an integer from 1 to 256), line_search, stop_at_rest (a bool or {speed,
        angular_speed, hold})."""
        a, d, st = self.analysis, self.analysis.dynamic, self.analysis.statics
        auto = {}
        for key, value in keys.items():
            where = f"analysis.{key}"
            if key == "type":
                a.kind = _enum(_m.AnalysisKind, value, where)
            elif key in ("start_time", "end_time"):
                setattr(a, key, _number(value, where))
            elif key == "step":
                if value == "auto":
                    auto["step"] = True
                else:
                    a.step = _number(value, where)
            elif key == "rho_inf":
                if value == "auto":
                    d.rho_inf = _m.AUTO_RHO_INF
                    continue
                d.rho_inf = _number(value, where)
                if not 0 <= d.rho_inf <= 1:
                    raise _error(where, "expected a spectral radius in [0, 1] or 'auto'")
            elif key == "line_search":
                d.line_search = _bool(value, where)
            elif key == "stop_at_rest":
                self._set_stop_at_rest(value, where)
            elif key == "tolerances":
                if not isinstance(value, dict) or set(value) - {"increment", "constraint",
                                                                "residual"}:
                    raise _error(where, "expected {increment, constraint, residual}")
                for name, v in value.items():
                    x = _number(v, f"{where}.{name}")
                    setattr(d, f"{name}_tolerance", x)
                    setattr(st, f"{name}_tolerance", x)
            elif key in ("max_iterations", "max_halvings"):
                if not isinstance(value, int) or isinstance(value, bool):
                    raise _error(where, f"expected an integer, got {value!r}")
                setattr(d, key, value)
                setattr(st, key, value)
            elif key == "load_steps":
                st.load_steps = value
            elif key == "newton":
                d.newton_matrix = _enum(_m.NewtonMatrix, value, where)
            elif key == "predictor":
                d.predictor = _enum(_m.Predictor, value, where)
            elif key == "convergence":
                d.convergence = _enum(_m.ConvergenceTest, value, where)
            elif key == "constraints":
                d.constraints = _enum(_m.ConstraintFormulation, value, where)
            elif key in ("align_steps", "static_preload"):
                setattr(a, key, _bool(value, where))
            elif key in ("restart_at_breakpoints", "perturbed_start"):
                setattr(d, key, _bool(value, where))
            elif key == "rod_inertia":
                self.rod_inertia = _enum(_m.RodInertia, value, where)
            elif key == "linear_solver":
                self.linear_solver = _enum(_m.LinearSolver, value, where)
            elif key in ("tolerance", "min_step", "max_step", "initial_step"):
                auto[key] = value
            elif key == "statics":
                self._set_statics(value, where)
            elif key == "threads":
                if value != "auto" and (not isinstance(value, int) or isinstance(value, bool)
                                        or not 1 <= value <= 256):
                    raise _error(where, f"expected 'auto' or an integer from 1 to 256, got "
                                        f"{value!r}")
                a.threads = value
            else:
                raise _error(where, "unknown key (docs/scene-format.md, 'analysis')")
        if not a.end_time > a.start_time:
            raise _error("analysis.end_time", "expected end_time > start_time")
        if set(auto) - {"step"} and "step" not in auto:
            raise _error(f"analysis.{sorted(auto)[0]}", "applies only to step='auto'")
        if "step" in auto:
            self._set_step_control(auto)
        return a

    def _set_stop_at_rest(self, value, where):
        """analysis.stop_at_rest as the scene reads it: a bool or {speed, angular_speed, hold}."""
        c = self.analysis.stop_at_rest
        if isinstance(value, dict):
            for key, v in value.items():
                w = f"{where}.{key}"
                if key not in ("speed", "angular_speed", "hold"):
                    raise _error(w, "unknown key (expected speed, angular_speed or hold)")
                x = _number(v, w)
                if not (x > 0 if key != "hold" else x >= 0):
                    raise _error(w, f"expected a value {'>' if key != 'hold' else '>='} 0, "
                                    f"got {v!r}")
                setattr(c, key, x)
            c.enabled = True
        else:
            c.enabled = _bool(value, where)
        if c.enabled and self.analysis.kind == _m.AnalysisKind.STATIC:
            raise _error(where, "applies to dynamic analyses only")

    def _set_statics(self, value, where):
        st = self.analysis.statics
        if not isinstance(value, dict):
            raise _error(where, f"expected a dict, got {value!r}")
        for key, v in value.items():
            w = f"{where}.{key}"
            if key == "method":
                st.method = _enum(_m.StaticMethod, v, w)
            elif key == "exact_tangent":
                st.constraint_force_tangent = _bool(v, w)
            elif key in ("max_steps", "desired_iterations"):
                setattr(st, key, v)
            elif key in ("end_load_factor", "arc_length", "arc_length_min", "arc_length_max",
                         "psi", "rotation_weight"):
                setattr(st, key, _number(v, w))
            else:
                raise _error(w, "unknown key")

    def _set_step_control(self, auto):
        """step='auto' as the scene reads it: error-controlled steps."""
        a, d = self.analysis, self.analysis.dynamic
        a.adaptive_steps = True
        if "tolerance" not in auto:
            raise _error("analysis.step", "'auto' requires tolerance (a number, or {absolute, "
                         "relative})")
        tol = auto["tolerance"]
        if isinstance(tol, dict):
            if set(tol) - {"absolute", "relative"}:
                raise _error("analysis.tolerance", "expected {absolute, relative}")
            if "absolute" in tol:
                d.absolute_tolerance = _number(tol["absolute"], "analysis.tolerance.absolute")
            if "relative" in tol:
                d.relative_tolerance = _number(tol["relative"], "analysis.tolerance.relative")
        else:
            d.absolute_tolerance = d.relative_tolerance = _number(tol, "analysis.tolerance")
        if "min_step" in auto:
            d.min_step = _number(auto["min_step"], "analysis.min_step")
        if "max_step" in auto:
            d.max_step = _number(auto["max_step"], "analysis.max_step")
        a.step = min(max(1e-3 * (a.end_time - a.start_time), d.min_step), d.max_step)
        if "initial_step" in auto:
            a.step = _number(auto["initial_step"], "analysis.initial_step")
        d.initial_step = a.step

    def add_output_point(self, name, *, body, at=None, s=None):
        """A recorded point (the scene's ``outputs.points``): the point `at` of a body (a rigid
        body's point, a soft body's node), or the section of a soft body at arc length s [m].
        Returns its OutputPointSpec."""
        where = self._name(name, "outputs.points", "output point")
        p = OutputPointSpec(name=name, body=self.body_index(body, f"{where}.body"))
        if (at is None) == (s is None):
            raise _error(where, "give either at or s")
        if at is not None:
            p.at = self.point(at, f"{where}.at")
        else:
            p.along_rod, p.arc_length = True, _number(s, f"{where}.s")
        return self._add("outputs.points", p, self.outputs.points)

    def set_outputs(self, *, joints=None, interval=None, vtk=None, vtk_interval=None,
                    vtk_format=None, rod_fields=None, max_rows=None, reactions=None,
                    energy=None):
        """The scene's ``outputs:`` keys: joints ('all', 'none' or a list of joint names),
        interval [s] (0: every step), vtk (bool), vtk_interval [s], vtk_format ('binary' or
        'ascii'), rod_fields (True, False or the interval between its rows [s]), max_rows
        (the most output times a run records, a whole number from 1 to 1e9), reactions and
        energy (bool: write reactions.csv, energy.csv)."""
        o = self.outputs
        if joints is not None:
            if joints in ("all", "none"):
                o.all_joints, o.joints = joints == "all", []
            else:
                if isinstance(joints, str) or not hasattr(joints, "__len__"):
                    raise _error("outputs.joints", "expected 'all', 'none' or a list of joint "
                                 f"names, got {joints!r}")
                o.all_joints = False
                o.joints = [self.joint_index(j, f"outputs.joints[{i}]")
                            for i, j in enumerate(joints)]
        if interval is not None:
            o.interval = _number(interval, "outputs.interval")
        if vtk is not None:
            o.vtk = _bool(vtk, "outputs.vtk")
        if vtk_interval is not None:
            o.vtk_interval = _number(vtk_interval, "outputs.vtk_interval")
        if vtk_format is not None:
            o.vtk_format = _enum(_m.VtkFormat, vtk_format, "outputs.vtk_format")
        if rod_fields is not None:
            if isinstance(rod_fields, bool):
                o.rod_fields, o.rod_fields_interval = rod_fields, -1.0
            else:
                interval = _number(rod_fields, "outputs.rod_fields")
                if interval < 0.0:
                    raise _error("outputs.rod_fields", "expected true, false or an interval "
                                 f">= 0 s, got {rod_fields!r}")
                o.rod_fields, o.rod_fields_interval = True, interval
        if max_rows is not None:
            v = _number(max_rows, "outputs.max_rows")
            if v != math.floor(v) or not 1 <= v <= 1e9:
                raise _error("outputs.max_rows", "expected a whole number from 1 to "
                             f"1000000000, got {max_rows!r}")
            o.max_rows = int(v)
        if reactions is not None:
            o.reactions = _bool(reactions, "outputs.reactions")
        if energy is not None:
            o.energy = _bool(energy, "outputs.energy")
        return o


def read_scene_spec(path_or_text, overrides=(), source_name=None):
    """The SceneSpec a scene file gives (docs/scene-format.md), with overrides applied
    ('key.path=value', as load_scene): read, edit, then compile() -- MuJoCo's load-then-edit.

    path_or_text: a path (str or os.PathLike), or the scene's text (a str with a newline);
    source_name names the text in messages. Raises InputError 'FILE:LINE:COLUMN: FIELD: what'."""
    overrides = list(overrides)
    if isinstance(path_or_text, os.PathLike) or (
            isinstance(path_or_text, str) and "\n" not in path_or_text):
        return _m._load_scene_spec(os.fspath(path_or_text), overrides)
    return _m._read_scene_spec(path_or_text, source_name or "<text>", overrides)


def _body_name(body):
    if isinstance(body, BodySpec):
        return body.name
    if isinstance(body, str):
        return body
    raise _error("route", f"expected a body name or a BodySpec, got {body!r}")


def route_offset(body, s_values, offset):
    """Eyelets for SceneSpec.add_tendon: on a soft body at the arc lengths s_values [m], each
    offset by the same section-frame vector `offset` [m] ((x, y, z): x along the rod).
    body: a name or a BodySpec. Returns dicts {'body', 's', 'offset'} (the scene's form)."""
    name = _body_name(body)
    off = _vector(offset, 3, "route.offset")
    return [{"body": name, "s": _number(s, f"route.s[{i}]"), "offset": off}
            for i, s in enumerate(s_values)]


def route_helical(body, s_values, radius, turns, phase=0.0, length=None):
    """Eyelets on a helix around a soft body: at arc length s the offset is radius (0, cos t,
    sin t) in the section frame, t = phase + 2 pi turns s / L [rad]. L is `length`, or the
    length of the body's path (exact for a straight rod; pass length= for a path with corners,
    whose rod rounds them). radius [m]; turns: the helix's turns over L. Returns dicts
    {'body', 's', 'offset'} for SceneSpec.add_tendon."""
    name = _body_name(body)
    if length is None:
        if not isinstance(body, BodySpec):
            raise _error("route.length", "give length= (or pass the BodySpec)")
        length = _polyline_length([tuple(p) for p in body.path])
    length = _number(length, "route.length")
    if not length > 0:
        raise _error("route.length", "expected a positive length")
    r, n, p0 = (_number(radius, "route.radius"), _number(turns, "route.turns"),
                _number(phase, "route.phase"))
    out = []
    for i, s in enumerate(s_values):
        s = _number(s, f"route.s[{i}]")
        t = p0 + 2.0 * math.pi * n * s / length
        out.append({"body": name, "s": s, "offset": (0.0, r * math.cos(t), r * math.sin(t))})
    return out


__all__ = ["SceneSpec", "BodySpec", "JointEntrySpec", "LoadSpec", "BodyPointSpec", "TendonSpec",
           "ForceSpec", "ActuatorSpec", "OutputPointSpec", "ContactSpec", "OutputsSpec",
           "read_scene_spec", "route_offset", "route_helical"]

"""One typed, SymPy-free description of a compiled mechanism, built from its manifest (DESIGN.md §7).

The manifest is the JSON that :mod:`sewgen.derive.emit` compiles into every module (``sg_<name>_manifest``);
this module turns it once into frozen dataclasses that every run-time layer reads — the sweep API, results,
forces, loads, machine composition, reports and drawings — so no layer re-parses the JSON or repeats a name,
an offset or a size by hand.

Parts are found by name (``desc.point("needle_eye")``) or by role (``desc.role("feed_dog")``): a role is what a
declaration says a part *is* for the machine-level analyses (needle eye, thread eye, feed dog, throat plate,
stitch regulator, hook shaft, …), so those analyses never name a catalog mechanism or one of its parts.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from functools import cached_property

from sewgen.errors import RoleError

#: Per-point observables, in the order the motion kernel writes them (derive/kinematics.py point blocks).
POINT_FIELDS = ("x", "y", "vx", "vy", "ax", "ay")


@dataclass(frozen=True)
class Parameter:
    """A parameter: SI default, physical kind and SI unit, the unit it was declared in, docstring, role."""

    index: int
    name: str
    kind: str
    unit: str
    default: float
    display_unit: str
    doc: str
    positive: bool
    role: str | None = None
    minimum: float | None = None  # the physical range of its values (SI; None: open), e.g. a friction coefficient's
    maximum: float | None = None


@dataclass(frozen=True)
class Coordinate:
    """A generalised coordinate the loops solve for: a link angle (rad) or a slider travel (m)."""

    index: int
    name: str
    unit: str
    guess: float

    @property
    def kind(self) -> str:
        return "angle" if self.unit == "rad" else "length"


@dataclass(frozen=True)
class Input:
    """An input: index 0 is the shaft (angle = shaft angle), the others held inputs (a stitch regulator)."""

    index: int
    name: str
    kind: str
    unit: str
    default: float
    display_unit: str
    doc: str
    role: str | None = None

    @property
    def held(self) -> bool:
        return self.index > 0

    @property
    def quantity(self) -> str:
        """What the input sets: an angle (rad; its output is a torque) or a travel (m; a force)."""
        return "angle" if self.unit == "rad" else "length"

    @property
    def effort_unit(self) -> str:
        """The unit of the input's driving or holding effort: N·m for an angle, N for a travel."""
        return "N*m" if self.unit == "rad" else "N"


@dataclass(frozen=True)
class Branch:
    """The assembly sign of one closed-form dyad, named by its joint, and what +1 means."""

    index: int
    joint: str
    kind: str
    default: int
    meaning: str


@dataclass(frozen=True)
class Point:
    """A named point of a body; ``offset`` is the first of its six observables (x, y, vx, vy, ax, ay)."""

    name: str
    doc: str
    offset: int
    body: str | None = None
    role: str | None = None


@dataclass(frozen=True)
class Body:
    """A moving body: kind (driven, held, link, slider), its observables' offset (angle, ω, α, then the centre
    of mass's six), and the names of its mass parameters (None where the declaration has none)."""

    name: str
    kind: str
    doc: str
    offset: int
    mass: str | None = None
    com_u: str | None = None
    com_v: str | None = None
    inertia: str | None = None
    role: str | None = None
    com_z: int | None = None  # a spatial crank's: the offset of its centre of mass's z, z_d, z_dd (off the plane)


@dataclass(frozen=True)
class Reaction:
    """The force unknowns of one joint (or drive) in the force vector: ``columns`` from ``offset`` on.

    A revolute's (fx, fy) is the force on body ``b`` from body ``a``; a prismatic's (normal, couple) and a slot's
    or cam's normal force are on the ``b`` side; a drive's torque is what the frame (the shaft) puts on ``b``.
    """

    name: str
    kind: str
    a: str
    b: str
    columns: tuple
    offset: int
    grounded: bool
    input: str | None = None
    sense: float = 1  # d(relative angle)/d(input): ±1, or a speed ratio

    @property
    def is_drive(self) -> bool:
        """A drive (an input's torque or, for a travel input, its force), not a joint."""
        return self.input is not None


@dataclass(frozen=True)
class Joint:
    """A joint of the declaration: its kind, its two bodies, its reaction entry, its branch sign if any."""

    name: str
    kind: str
    a: str
    b: str
    reaction: str | None = None
    branch: dict | None = None


@dataclass(frozen=True)
class Anchor:
    """A drawing anchor (world x, y from the ``sg_<name>_anchors`` kernel): a joint's attachment on a body, a
    named point, a guide's origin or unit direction, a cam arc's centre, a centre of mass."""

    index: int
    name: str
    body: str
    kind: str
    joint: str | None = None


@dataclass(frozen=True)
class Arc:
    """One circular arc of a cam profile: its centre anchor and where its radius and normal sector are."""

    joint: str
    body: str
    center: int
    out: int


@dataclass(frozen=True)
class Load:
    """One load slot per position: a force component at a named point, or a torque on a body."""

    index: int
    name: str
    body: str
    component: str


@dataclass(frozen=True)
class Element:
    """A force element (spring, damper, torsion spring: sewgen.derive.elements) between two bodies, and the
    names of its force outputs (``<name>.force``, ``.length``, ``.energy`` …)."""

    name: str
    kind: str
    bodies: tuple
    outputs: tuple
    doc: str = ""


@dataclass(frozen=True)
class Output:
    """A derived force output (torque, power, shaking force, energies), its column in the force results."""

    name: str
    unit: str
    column: int


@dataclass(frozen=True)
class Description:
    """Everything the run time knows about one compiled mechanism."""

    name: str
    doc: str
    closed_form: bool
    default_speed: float
    sizes: dict
    params: tuple
    coords: tuple
    inputs: tuple
    branches: tuple
    points: tuple
    bodies: tuple
    reactions: tuple
    joints: tuple
    loads: tuple
    force_outputs: tuple
    force_rows: tuple
    observables: tuple  # (name, unit) per observable column
    anchors: tuple = ()
    arcs: tuple = ()
    roles: dict = field(default_factory=dict)  # role -> (kind, name)
    kernels: tuple = ()
    elements: tuple = ()  # force elements: springs, dampers, torsion springs

    # -- lookup by name --------------------------------------------------------------------------------------
    @cached_property
    def _by_name(self) -> dict:
        return {"param": {p.name: p for p in self.params}, "point": {p.name: p for p in self.points},
                "body": {b.name: b for b in self.bodies}, "input": {i.name: i for i in self.inputs},
                "coord": {c.name: c for c in self.coords}, "reaction": {r.name: r for r in self.reactions},
                "joint": {j.name: j for j in self.joints}, "element": {e.name: e for e in self.elements}}

    @cached_property
    def angle_columns(self) -> tuple[list, list]:
        """Columns of the angle results: angle coordinates in q, angles (unit rad) among the observables."""
        return ([c.index for c in self.coords if c.unit == "rad"],
                [k for k, (_name, unit) in enumerate(self.observables) if unit == "rad"])

    def _get(self, what: str, name: str):
        table = self._by_name[what]
        if name not in table:
            raise KeyError(f"{self.name} has no {what} {name!r}; {what}s: {', '.join(table) or 'none'}")
        return table[name]

    def param(self, name: str) -> Parameter:
        return self._get("param", name)

    def element(self, name: str) -> Element:
        return self._get("element", name)

    def point(self, name: str) -> Point:
        return self._get("point", name)

    def body(self, name: str) -> Body:
        return self._get("body", name)

    def input(self, name: str) -> Input:
        return self._get("input", name)

    def coord(self, name: str) -> Coordinate:
        return self._get("coord", name)

    def reaction(self, name: str) -> Reaction:
        return self._get("reaction", name)

    def has(self, what: str, name: str) -> bool:
        return name in self._by_name[what]

    # -- lookup by role -------------------------------------------------------------------------------------
    def has_role(self, role: str) -> bool:
        return role in self.roles

    def role(self, role: str):
        """The part (Point, Parameter, Input or Body) that plays ``role``; :class:`RoleError` if none does."""
        if role not in self.roles:
            raise RoleError(self.name, role, sorted(self.roles))
        kind, name = self.roles[role]
        return self._get(kind, name)

    def role_name(self, role: str, default=None):
        """The name of the part that plays ``role``, or ``default`` when no part does."""
        return self.roles[role][1] if role in self.roles else default

    # -- derived views --------------------------------------------------------------------------------------
    @property
    def held_inputs(self) -> tuple:
        return self.inputs[1:]

    @property
    def drives(self) -> tuple:
        return tuple(r for r in self.reactions if r.is_drive)

    @property
    def driven_bodies(self) -> tuple:
        """Bodies turned by the shaft (input 0), in declaration order: the cranks and cams on the shaft."""
        shaft = self.inputs[0].name
        return tuple(self.body(r.b) for r in self.drives if r.input == shaft)

    @property
    def force_joints(self) -> tuple:
        """Every reaction that is a joint force (the drives' torques are not)."""
        return tuple(r for r in self.reactions if not r.is_drive)

    def output_column(self, name: str) -> int:
        for o in self.force_outputs:
            if o.name == name:
                return o.column
        raise KeyError(f"{self.name} has no force output {name!r}")


def _mass_params(name: str, params: dict) -> dict:
    keys = {"mass": "mass", "com_u": "com_u", "com_v": "com_v", "inertia": "inertia"}
    return {k: (f"{name}.{v}" if f"{name}.{v}" in params else None) for k, v in keys.items()}


def describe(manifest: dict | str) -> Description:
    """The :class:`Description` of a manifest (the dict, or its JSON text)."""
    man = json.loads(manifest) if isinstance(manifest, str) else manifest
    params = tuple(Parameter(i, p["name"], p["kind"], p["unit"], float(p["default"]), p["display_unit"], p["doc"],
                             bool(p["positive"]), p.get("role"), p.get("minimum"), p.get("maximum"))
                   for i, p in enumerate(man["params"]))
    pnames = {p.name for p in params}
    coords = tuple(Coordinate(i, c["name"], c["unit"], float(c["guess"])) for i, c in enumerate(man["coords"]))
    inputs = tuple(Input(i, x["name"], x["kind"], x["unit"], float(x["default"]), x.get("display_unit", x["unit"]),
                         x.get("doc", ""), x.get("role")) for i, x in enumerate(man["inputs"]))
    branches = tuple(Branch(i, b["joint"], b["kind"], int(b["default"]), b.get("meaning", ""))
                     for i, b in enumerate(man["branches"]))
    points = tuple(Point(p["name"], p.get("doc", ""), int(p["offset"]), p.get("body"), p.get("role"))
                   for p in man["points"])
    observable = {o["name"]: k for k, o in enumerate(man["observables"])}
    bodies = tuple(Body(b["name"], b["kind"], b.get("doc", ""), int(b["offset"]), role=b.get("role"),
                        com_z=observable.get(f"{b['name']}.com.z"), **_mass_params(b["name"], pnames))
                   for b in man["bodies"])
    reactions = tuple(Reaction(r["name"], r["kind"], r["a"], r["b"], tuple(r["columns"]), int(r["offset"]),
                               bool(r["grounded"]), r.get("input"), r.get("sense", 1)) for r in man["reactions"])
    if "joints" in man:
        joints = tuple(Joint(j["name"], j["kind"], j["a"], j["b"], j.get("reaction"), j.get("branch"))
                       for j in man["joints"])
    else:  # an older manifest: the joints that carry a reaction
        joints = tuple(Joint(r.name, r.kind, r.a, r.b, r.name) for r in reactions if not r.is_drive)
    loads = tuple(Load(i, ld["name"], ld["body"], ld["component"]) for i, ld in enumerate(man["loads"]))
    nf = int(man["sizes"]["nf"])
    outputs = tuple(Output(o["name"], o["unit"], nf + k) for k, o in enumerate(man["force_outputs"]))
    anchors = tuple(Anchor(i, a["name"], a["body"], a["kind"], a.get("joint")) for i, a in enumerate(man.get("anchors", ())))
    arcs = tuple(Arc(a["joint"], a["body"], int(a["center"]), int(a["out"])) for a in man.get("arcs", ()))
    roles = {}
    for role, entry in (man.get("roles") or {}).items():
        roles[role] = (entry["kind"], entry["name"])
    return Description(
        name=man["name"], doc=man.get("doc", ""), closed_form=bool(man["closed_form"]),
        default_speed=float(man["default_speed"]), sizes=dict(man["sizes"]), params=params, coords=coords,
        inputs=inputs, branches=branches, points=points, bodies=bodies, reactions=reactions, joints=joints,
        loads=loads, force_outputs=outputs, force_rows=tuple(man["force_rows"]),
        observables=tuple((o["name"], o["unit"]) for o in man["observables"]), anchors=anchors, arcs=arcs,
        roles=roles, kernels=tuple(sorted(man.get("kernels", {}))),
        elements=tuple(Element(e["name"], e["kind"], tuple(e["bodies"]), tuple(e["outputs"]), e.get("doc", ""))
                       for e in man.get("elements", ())))

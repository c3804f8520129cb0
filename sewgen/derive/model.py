"""The modelling vocabulary: bodies, joints, points and parameters (DESIGN.md §3).

A mechanism is declared the way the seeds draw it, as bodies joined by joints; :mod:`derive.kinematics`
finds the loops. Nothing here is symbolic algebra beyond creating parameter symbols.

Body frames: a driven body has its origin at its pivot and its x axis along the crank; a slider has its
origin on its guide line at travel ``s`` and its x axis along the guide; a link's frame is wherever its
attachment points say (``link.at(u, v)`` in millimetres-or-whatever units the parameters carry).
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

import sympy as sp

from ..units import FRICTION_MAX, SI_UNITS, range_problem, to_si, unit_of
from .elements import ELEMENTS, ForceElement
from .joints import KINDS
from .vocabulary import (NAME, Arc, Attachment, Axis, Body, DeclarationError, Input, Joint, Line,  # noqa: F401
                         Param, SpatialPoint, check_bare)  # re-exported: declarations import the vocabulary from here


#: The range of a quantity that cannot be negative (a damper's coefficient, a spring's stiffness and free length, a
#: pin's radius): its minimum and maximum (SI; None: open).
_NOT_NEGATIVE = (0.0, None)
#: The unit a "give it with its unit" message suggests for each kind of parameter.
_EXAMPLE_UNITS = {"length": "mm", "angle": "deg", "mass": "g"}


@dataclass(eq=False)
class Mechanism:
    """A planar mechanism declaration. Create bodies, joints, points and parameters through its methods."""

    name: str
    doc: str = ""
    default_speed: str = "1000 rpm"  # shaft speed a run uses unless told otherwise
    params: list = field(default_factory=list)
    bodies: list = field(default_factory=list)
    joints: list = field(default_factory=list)
    points: list = field(default_factory=list)  # (name, Attachment, doc)
    inputs: list = field(default_factory=list)
    elements: list = field(default_factory=list)  # force elements (derive.elements): springs, dampers
    frictions: list = field(default_factory=list)  # Coulomb friction: (joint name, coefficient, pin radius)
    roles: dict = field(default_factory=dict)  # role -> (kind, name): what a part is for the machine analyses

    def __post_init__(self):
        if not NAME.match(self.name):
            raise DeclarationError(f"mechanism name {self.name!r} must be lower_snake_case")
        self.ground = Body(self, "ground", "ground", doc="the frame")
        self.bodies.append(self.ground)
        self.inputs.append(Input("shaft", "shaft", 0.0, "rad", "upper-shaft angle phi"))
        self._names: set = {"ground", "shaft"}

    # -- roles ---------------------------------------------------------------------------------------------
    def _role(self, role, kind: str, name: str) -> None:
        """Tag part ``name`` (a "point", "param", "input" or "body") with ``role`` (sewgen.roles); once per role."""
        if role is None:
            return
        if not isinstance(role, str) or not NAME.match(role):
            raise DeclarationError(f"{self.name}: role {role!r} of {kind} {name!r} must be lower_snake_case")
        if role in self.roles:
            other_kind, other = self.roles[role]
            raise DeclarationError(f"{self.name}: role {role!r} is given to both {other_kind} {other!r} and "
                                   f"{kind} {name!r}; a role names one part")
        self.roles[role] = (kind, name)

    def role_of(self, kind: str, name: str):
        """The role of part ``name`` of ``kind``, or None."""
        return next((r for r, (k, n) in self.roles.items() if k == kind and n == name), None)

    # -- parameters ------------------------------------------------------------------------------------
    def _claim(self, name: str, what: str) -> None:
        """Parameters have their own namespace; bodies, joints and points share one."""
        if not re.match(r"^[A-Za-z][A-Za-z0-9_.]*$", name):
            raise DeclarationError(f"{self.name}: {what} name {name!r} must be letters, digits and _")
        key = ("param:" if what == "parameter" else "") + name
        if key in self._names:
            raise DeclarationError(f"{self.name}: the {what} name {name!r} is declared twice")
        self._names.add(key)

    def param(self, name: str, kind: str, default: str, doc: str, positive: bool = False, role=None,
              bounds=(None, None)) -> sp.Symbol:
        """Declare a parameter of physical ``kind`` with a default such as "16.7 mm"; returns its symbol.

        The default carries its unit: a bare number is refused for every kind that has one (``length("crank",
        12)`` would be 12 m — a sewing machine's crank is 12 mm), a dimensionless one is a plain number.
        ``bounds`` (minimum, maximum; SI, None: open) is the physical range every value of it must lie in, checked
        here for the default and at run time for every value given (``sewgen.engine.arguments.parameter_problem``).
        """
        if not doc:
            raise DeclarationError(f"{self.name}: parameter {name!r} needs a docstring")
        if not isinstance(default, str) and SI_UNITS.get(kind):
            raise DeclarationError(f"{self.name}: default of {name!r} is a bare number {default!r}: give it with "
                                   f"its unit, e.g. \"{default} {_EXAMPLE_UNITS.get(kind, SI_UNITS[kind])}\" (a bare "
                                   f"number would be read as {default} {SI_UNITS[kind]})")
        value = to_si(default, kind, f"{self.name}.{name}")
        if positive and not value > 0:
            raise DeclarationError(f"{self.name}: default of {name!r} must be positive")
        problem = range_problem(value, *bounds, SI_UNITS[kind])
        if problem:
            raise DeclarationError(f"{self.name}: default of {name!r} {problem} ({doc})")
        self._claim(name, "parameter")
        self._role(role, "param", name)
        sym = sp.Symbol(f"p_{len(self.params)}", **({"positive": True} if positive else {"real": True}))
        unit = unit_of(default) if isinstance(default, str) else SI_UNITS[kind]
        self.params.append(Param(name, sym, kind, value, unit, doc, positive, *bounds))
        return sym

    def length(self, name: str, default: str, doc: str, signed: bool = False, role=None) -> sp.Symbol:
        """A length; positive unless ``signed`` (offsets, coordinates)."""
        return self.param(name, "length", default, doc, positive=not signed, role=role)

    def angle(self, name: str, default: str, doc: str, role=None) -> sp.Symbol:
        return self.param(name, "angle", default, doc, role=role)

    # -- bodies ----------------------------------------------------------------------------------------
    def _body(self, name: str, kind: str, doc: str, mass, com, inertia, role=None, **kw) -> Body:
        self._claim(name, "body")
        self._role(role, "body", name)
        body = Body(self, name, kind, doc=doc, **kw)
        body.mass = self._mass_prop(name, "mass", "mass", mass, f"mass of {name}")
        body.com = (
            self._mass_prop(name, "com_u", "length", com[0], f"centre of mass of {name}, local u"),
            self._mass_prop(name, "com_v", "length", com[1], f"centre of mass of {name}, local v"),
        )
        body.inertia = self._mass_prop(name, "inertia", "inertia", inertia, f"moment of inertia of {name} about its centre of mass")
        self.bodies.append(body)
        return body

    def _mass_prop(self, body: str, prop: str, kind: str, value, doc: str, bounds=(None, None)) -> sp.Expr:
        """A property of a part (mass, an element's stiffness …): a quantity string becomes parameter
        ``part.prop`` (its values within ``bounds``, see :meth:`param`); an expression is used as is (a number in
        it checked against ``bounds``)."""
        if isinstance(value, str):
            return self.param(f"{body}.{prop}", kind, value, doc, bounds=bounds)
        expr = sp.sympify(value)
        problem = range_problem(float(expr), *bounds, SI_UNITS[kind]) if expr.is_number else None
        if problem:
            raise DeclarationError(f"{self.name}: {body}.{prop} {problem} ({doc})")
        return expr

    def driven(self, name: str, pivot: Attachment, phase="0 deg", sense: int = 1, doc: str = "",
               mass="0 g", com=("0 mm", "0 mm"), inertia="0 kg*m**2", role=None, ratio=1) -> Body:
        """A body turned by the upper shaft about ``pivot``: its angle relative to the pivot's body is
        sense · ratio · phi + phase. ``pivot`` is a point of ground (an absolute drive: a crank on the shaft) or of
        a moving body declared before (a relative drive: a motor or gear train at that joint). ``ratio`` is the
        speed ratio (a rotary hook turns twice per stitch: 2), an exact number."""
        self._check_pivot(pivot, name)
        if sense not in (1, -1):
            raise DeclarationError(f"{self.name}: sense of {name!r} must be +1 or -1")
        ratio = self._ratio(ratio, name)
        ph = self.angle(f"{name}.phase", phase, f"phase of {name} relative to the shaft angle") if isinstance(phase, str) else sp.sympify(phase)
        return self._body(name, "driven", doc, mass, com, inertia, role=role, pivot=pivot, input_index=0, phase=ph,
                          sense=sense, ratio=ratio)

    def held(self, name: str, pivot: Attachment | None = None, default: str = "", doc: str = "",
             mass="0 g", com=("0 mm", "0 mm"), inertia="0 kg*m**2", role=None, guide: Line | None = None) -> Body:
        """A body set by a held input (a stitch regulator): an input that stays put in a run. With ``pivot`` the
        input is the body's angle relative to the pivot's body (``pivot`` as for :meth:`driven`; ``default`` an
        angle); with ``guide`` (a line of ground or of a moving body declared before) it is the body's travel
        along that line from the line's origin (a prismatic input: ``default`` a length, its holding force in N
        is the input's output). ``role`` tags the held input (e.g. "stitch_regulator")."""
        if (pivot is None) == (guide is None):
            raise DeclarationError(f"{self.name}: held body {name!r} needs either a pivot (an angle input) or a "
                                   "guide (a travel input)")
        quantity = "angle" if guide is None else "length"
        if guide is None:
            self._check_pivot(pivot, name)
        elif not isinstance(guide, Line) or guide.body not in self.bodies:
            raise DeclarationError(f"{self.name}: guide of {name!r} must be body.line(...) of ground or of a body "
                                   "declared before it")
        self._role(role, "input", name)
        self.inputs.append(Input(name, "held", to_si(default, quantity, f"{self.name}.{name}"), unit_of(default), doc,
                                 quantity))
        return self._body(name, "driven", doc, mass, com, inertia, pivot=pivot,
                          guide=guide, input_index=len(self.inputs) - 1)

    def spatial_crank(self, name: str, axis_point, axis, phase="0 deg", sense: int = 1, ratio=1, reference=None,
                      doc: str = "", mass="0 g", com=("0 mm", "0 mm"), inertia="0 kg*m**2", role=None,
                      planar: bool = False) -> Body:
        """A crank turned by the upper shaft about a fixed axis in space (seed 003's spatial four-bar: the crank
        of the needle or looper drive, whose shaft is not parallel to the rocker's).

        ``axis_point`` (x, y, z; the mechanism's plane is z = 0) is a point of the axis, ``axis`` its direction
        (three numbers, normalised here); the crank angle sense · ratio · phi + phase is measured about the axis
        from ``reference`` (three numbers; default: the machine's z axis, or x when the axis is along z) projected
        into the plane the crank turns in. Its points are ``crank.pin(radius, along)``. Its centre of mass lies in
        that plane, through the axis point: ``com`` = (u, v), u along the crank (towards ``pin(radius)``), v a
        quarter turn ahead about the axis (parameters ``<name>.com_u``, ``<name>.com_v``; default on the axis);
        ``inertia`` is about the line through the centre of mass parallel to the axis (about the axis itself:
        inertia + mass·(u² + v²)). In the force balance its rows are the in-plane components of its bearings'
        resultant (reaction ``<name>.pivot`` at the axis point's projection) and the moment about its own axis
        (the driving torque); its centre of mass's motion out of the plane is the observable ``<name>.com.z``.

        ``planar=True`` declares the planar equivalent instead (seed 003 computes its spatial four-bars so, eq. 1
        with α = 0): the crank's axis and the plane it turns in are turned, by the least rotation about the line
        through the axis point, until the axis is perpendicular to the mechanism's plane (z); the crank pin then
        moves in the plane, its radius, phase, sense and reference carried along (the reference e₁ and e₂ are
        rotated with the axis), and a rod to it becomes a plane binary link. An axis already along ±z is
        unchanged."""
        def coordinate(value, what):
            if isinstance(value, str):
                return sp.Float(to_si(value, "length", f"{self.name}.{name}.{what}"))
            return check_bare(self.name, name, sp.sympify(value), "length")

        try:
            point = tuple(coordinate(value, what) for value, what in zip(axis_point, "xyz"))
            direction = sp.Matrix([sp.Rational(str(c)) if not isinstance(c, sp.Expr) else c for c in axis])
            ref = sp.Matrix([sp.Rational(str(c)) for c in reference]) if reference is not None else None
        except DeclarationError:
            raise
        except (TypeError, ValueError, sp.SympifyError):
            raise DeclarationError(f"{self.name}: axis of {name!r}: a point (x, y, z) and a direction of three "
                                   "numbers") from None
        if len(point) != 3 or direction.shape != (3, 1) or direction.norm() == 0:
            raise DeclarationError(f"{self.name}: axis of {name!r}: a point (x, y, z) and a nonzero direction")
        a = direction / direction.norm()
        if ref is None:
            ref = sp.Matrix([0, 0, 1]) if abs(float(a[2])) < 0.9 else sp.Matrix([1, 0, 0])
        e1 = ref - ref.dot(a) * a
        if float(e1.norm()) < 1e-9:
            raise DeclarationError(f"{self.name}: reference of {name!r} is along its axis")
        e1 = sp.simplify(e1 / e1.norm())
        e2 = sp.simplify(a.cross(e1))
        if planar:  # the least rotation taking the axis a to z (Rodrigues), applied to a, e1 and e2
            z = sp.Matrix([0, 0, 1])
            k = a.cross(z)
            s_, c_ = k.norm(), a.dot(z)
            if float(s_) > 1e-12:
                k = k / s_
                kx = sp.Matrix([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
                rot = sp.eye(3) + s_ * kx + (1 - c_) * kx * kx
                a, e1, e2 = (sp.simplify(rot * v) for v in (a, e1, e2))
            point = (point[0], point[1], sp.S.Zero)
        body = self.driven(name, self.ground.at(point[0], point[1]), phase=phase, sense=sense, doc=doc, mass=mass,
                           com=com, inertia=inertia, role=role, ratio=ratio)
        body.axis = Axis(point, tuple(a), tuple(e1), tuple(e2))
        return body

    def _ratio(self, ratio, name: str) -> sp.Expr:
        """A speed ratio as an exact SymPy number (2, -1/2, 0.5 → 1/2); zero refused."""
        if isinstance(ratio, bool) or not isinstance(ratio, (int, float, str, sp.Rational)):
            raise DeclarationError(f"{self.name}: ratio of {name!r} must be a number, got {ratio!r}")
        try:
            value = sp.Rational(str(ratio)) if not isinstance(ratio, sp.Rational) else ratio
        except (TypeError, ValueError, sp.SympifyError):
            raise DeclarationError(f"{self.name}: ratio of {name!r} must be a number, got {ratio!r}") from None
        if value == 0:
            raise DeclarationError(f"{self.name}: ratio of {name!r} must not be zero")
        return value

    def link(self, name: str, doc: str = "", guess: str = "0 deg",
             mass="0 g", com=("0 mm", "0 mm"), inertia="0 kg*m**2", role=None) -> Body:
        """A free link; its absolute angle is a coordinate. ``guess`` starts Newton when no closed form exists."""
        return self._body(name, "link", doc, mass, com, inertia, role=role,
                          guess=to_si(guess, "angle", f"{self.name}.{name}.guess"))

    def slider(self, name: str, guide: Line, doc: str = "", guess: str = "0 mm",
               mass="0 g", com=("0 mm", "0 mm"), inertia="0 kg*m**2", role=None) -> Body:
        """A body travelling on ``guide`` (a line of ground or of a moving body); its travel is a coordinate."""
        if not isinstance(guide, Line):
            raise DeclarationError(f"{self.name}: guide of {name!r} must be body.line(...)")
        return self._body(name, "slider", doc, mass, com, inertia, role=role, guide=guide,
                          guess=to_si(guess, "length", f"{self.name}.{name}.guess"))

    def _check_pivot(self, att: Attachment, name: str) -> None:
        if not isinstance(att, Attachment) or att.body not in self.bodies:
            raise DeclarationError(f"{self.name}: pivot of {name!r} must be a point of ground or of a body "
                                   "declared before it (body.at(u, v))")

    # -- joints and points -----------------------------------------------------------------------------
    def _joint(self, kind: str, name: str, a, b, **options) -> Joint:
        """Declare a joint of ``kind`` (a key of :data:`derive.joints.KINDS`, which checks its sides)."""
        self._claim(name, "joint")
        KINDS[kind].check(self, name, a, b, **options)
        joint = Joint(name, kind, a, b, **options)
        self.joints.append(joint)
        return joint

    def revolute(self, a: Attachment, b: Attachment, name: str, branch: int = 1) -> Joint:
        """A pin joint between two bodies. ``branch`` (+1/-1) picks the assembly when this joint closes a dyad."""
        return self._joint("revolute", name, a, b, branch=branch)

    def prismatic(self, guide: Line, b: Attachment, name: str) -> Joint:
        """Point ``b`` slides on ``guide`` and body b keeps the guide body's angle (a closing slide)."""
        return self._joint("prismatic", name, guide, b)

    def slot(self, guide: Line, b: Attachment, name: str) -> Joint:
        """Pin ``b`` runs in the slot ``guide`` of another body; both turn freely (a roller in a slot: one
        equation, one normal force)."""
        return self._joint("slot", name, guide, b)

    def cam(self, cam: Body, face: Line, arcs, name: str) -> Joint:
        """A cam of circular ``arcs`` (cam frame) touching the flat ``face`` of a follower (seed 000 §一(四)5).

        The cam lies on the right of the face's direction; the face's normal n (its direction turned +90°)
        points away from the cam. While arc k is in contact, the contact is its equivalent lower pair: the
        arc's centre runs on the line parallel to the face at the arc's radius (a pin in a slot). The active
        arc is chosen at every evaluation by the direction of n in the cam's frame (the arcs' normal
        sectors), so position and velocity stay continuous across a switch of G1-joined arcs; acceleration
        jumps by what the change of curvature implies. A fork with two parallel faces on a cam of constant
        breadth needs one face: the opposite arcs are concentric, so both contacts share one line of action.
        """
        origin = Attachment(cam, sp.S.Zero, sp.S.Zero) if isinstance(cam, Body) else cam
        return self._joint("cam", name, origin, face, arcs=tuple(arcs))

    # -- force elements (derive.elements) ------------------------------------------------------------------
    def _element(self, kind: str, name: str, a=None, b=None, joint=None, values=None, doc: str = ""):
        self._claim(name, "force element")
        el = ForceElement(name, kind, a, b, joint, {}, doc)
        ELEMENTS[kind].check(self, el)
        for prop, (quantity, value, *bounds) in (values or {}).items():
            el.values[prop] = self._mass_prop(name, prop, quantity, value, f"{prop.replace('_', ' ')} of {name}",
                                              *bounds)
        self.elements.append(el)
        return el

    def spring(self, a: Attachment, b: Attachment, stiffness, free_length, preload="0 N", *, name: str,
               doc: str = ""):
        """A linear spring from point ``a`` to point ``b`` (any two bodies, ground included): tension
        preload + stiffness·(length − free_length), positive when it pulls the points together. Values are
        quantity strings ("1.2 N/mm", "30 mm", "2 N": parameters ``<name>.stiffness`` …) or expressions."""
        return self._element("spring", name, a, b, values={
            "stiffness": ("stiffness", stiffness, _NOT_NEGATIVE),
            "free_length": ("length", free_length, _NOT_NEGATIVE), "preload": ("force", preload)}, doc=doc)

    def damper(self, a: Attachment, b: Attachment, coefficient, *, name: str, doc: str = ""):
        """A linear viscous damper from ``a`` to ``b``: tension coefficient·(d length/dt)."""
        return self._element("damper", name, a, b, values={"coefficient": ("damping", coefficient, _NOT_NEGATIVE)},
                             doc=doc)

    def torsion_spring(self, joint: Joint, stiffness, free_angle="0 deg", preload="0 N*m", *, name: str,
                       doc: str = ""):
        """A torsion spring at revolute ``joint``: torque preload + stiffness·((θ_b − θ_a) − free_angle) acts on
        the joint's body b as −T and on its body a as +T; the deflection is the continuous relative rotation (a
        spring on a pin that turns right round winds a turn per turn; derive.elements.TorsionSpring.deflection)."""
        return self._element("torsion_spring", name, joint=joint, values={
            "stiffness": ("torsional_stiffness", stiffness, _NOT_NEGATIVE), "free_angle": ("angle", free_angle),
            "preload": ("torque", preload)}, doc=doc)

    def rod(self, crank_pin: SpatialPoint, b: Attachment, length, name: str, z="0 mm", branch: int = 1) -> Joint:
        """A rod with a ball joint at each end (seed 003's spatial four-bar ABCD): from a spatial crank's pin to
        point ``b`` of a planar body, lifted ``z`` out of the mechanism's plane; it keeps their distance at
        ``length``. A two-force member (massless: lump its mass on the crank and the rocker). Its reaction is
        its tension. ``branch`` picks the rocker's assembly (seed 003 eq. 1's δ₁) when the rod closes a dyad."""
        values = {"length": self._mass_prop(name, "length", "length", length, f"length of rod {name}"),
                  "z": b.body.expr(z, "length") if isinstance(b, Attachment) else sp.S.Zero}
        return self._joint("rod", name, crank_pin, b, branch=branch, values=values)

    def friction(self, joint, coefficient="0", pin_radius="0 mm") -> None:
        """Coulomb friction in ``joint`` (a Joint, or the name of one — also a body's implied ``<body>.pivot`` or
        ``<slider>.guide``): a pin's friction moment μ·r·|F| against the relative rotation, a slide's or slot's
        friction force μ·|N| against the sliding (derive.kinetostatics solves for it with the reactions).
        ``coefficient`` and ``pin_radius`` become parameters ``<joint>.friction`` and ``<joint>.pin_radius``; a
        coefficient of 0 (the seeds' assumption, the default) switches it off."""
        names = {j.name: j for j in self.joints + self.implied_joints()}
        name = joint.name if isinstance(joint, Joint) else joint
        if name not in names:
            raise DeclarationError(f"{self.name}: friction: no joint {name!r}; joints: {', '.join(sorted(names))}")
        kind = KINDS[names[name].kind]
        if not kind.has_friction:
            raise DeclarationError(f"{self.name}: friction in {name!r}: a {kind.name} joint has no friction model "
                                   f"(joints that have: {', '.join(k for k, v in KINDS.items() if v.has_friction)})")
        if any(f[0] == name for f in self.frictions):
            raise DeclarationError(f"{self.name}: friction in {name!r} is declared twice")
        mu = self._mass_prop(name, "friction", "dimensionless", coefficient, f"Coulomb friction coefficient of {name}",
                             (0.0, FRICTION_MAX))
        radius = (self._mass_prop(name, "pin_radius", "length", pin_radius, f"pin radius of {name} (friction arm)",
                                  _NOT_NEGATIVE) if kind.friction_unit == "N*m" else sp.S.Zero)
        self.frictions.append((name, mu, radius))

    def friction_off(self, pins: dict, slides=()) -> None:
        """Coulomb friction declared but off (coefficient 0, the seeds' assumption) in every pin of ``pins``
        (joint name -> pin radius, the friction arm) and every slide or slot of ``slides``: a model file turns it
        on by setting the parameter ``<joint>.friction`` (see :meth:`friction`)."""
        for joint, radius in pins.items():
            self.friction(joint, "0", radius)
        for joint in slides:
            self.friction(joint, "0")

    def point(self, name: str, at: Attachment, doc: str = "", role=None) -> None:
        """A named point whose position, velocity and acceleration are reported."""
        self._claim(name, "point")
        self._role(role, "point", name)
        self.points.append((name, at, doc))

    # -- queries ---------------------------------------------------------------------------------------
    def implied_joints(self) -> list[Joint]:
        """The joints the bodies imply, in body order: a driven body's pin ``<body>.pivot`` to ground (its pivot,
        its origin) and a slider's slide ``<body>.guide`` (its guide, its origin). The spanning tree satisfies
        them, so they close no loop; they carry reactions and are drawn like declared joints."""
        out = []
        for body in self.bodies:
            origin = Attachment(body, sp.S.Zero, sp.S.Zero)
            if body.kind == "driven" and body.guide is None:
                out.append(Joint(f"{body.name}.pivot", "revolute", body.pivot, origin))
            elif body.kind == "slider" or body.kind == "driven":  # a travel input slides on its guide
                out.append(Joint(f"{body.name}.guide", "prismatic", body.guide, origin))
        return out

    def body(self, name: str) -> Body:
        for b in self.bodies:
            if b.name == name:
                return b
        raise KeyError(name)


def constant_breadth_arcs(side, small_radius, centroid=(0, 0), orientation=sp.pi / 2) -> list[Arc]:
    """The six arcs of a constant-breadth cam built on an equilateral triangle (a rounded Reuleaux triangle).

    Vertices V_i at ``centroid`` + side/√3·(cos, sin)(orientation + 120°·i) in the cam frame. Around each
    vertex a small arc of ``small_radius`` (normals within ±30° of the vertex's direction) and, opposite, a
    large arc of side + small_radius centred on the same vertex. Breadth = side + 2·small_radius in every
    direction. A cam turning about a vertex (``centroid`` = −V_0) dwells 60°, rises 120°, dwells 60°, returns
    120° (the feed cam 送布凸轮 of seed 000 / seed 001).
    """
    side, r0 = sp.sympify(side), sp.sympify(small_radius)
    cu, cv = (sp.sympify(c) for c in centroid)
    arcs = []
    for i in range(3):
        a = sp.sympify(orientation) + 2 * sp.pi * i / 3
        vu, vv = cu + side / sp.sqrt(3) * sp.cos(a), cv + side / sp.sqrt(3) * sp.sin(a)
        arcs.append(Arc(vu, vv, r0, a - sp.pi / 6, a + sp.pi / 6))
        arcs.append(Arc(vu, vv, side + r0, a + sp.pi - sp.pi / 6, a + sp.pi + sp.pi / 6))
    return arcs

"""Joint kinds: one class per kind owns everything the derivation knows about it (DESIGN.md §3).

A kind gives

* its **declaration check** (what its two sides must be) — :meth:`JointKind.check`;
* its **closure equations** when it closes a loop (seed 000 §一(三): the complex-vector loop r·e^{iθ} as two
  scalar equations for a pin, the normal distance for a slide) — :meth:`JointKind.closure`;
* its **reaction unknowns** and the **force rows** they enter (seed 000 §二(三): per moving body, force x,
  force y, moment about G) — :attr:`JointKind.columns`, :meth:`JointKind.reaction`, :meth:`JointKind.rows`;
  the force it puts on the body (the frame's force on the parts, seed 000 §二(四)) and the outputs it adds
  — :meth:`JointKind.on_body`, :meth:`JointKind.outputs`;
* its part in the **closed-form dyads** (seed 001 §三: a pin is the R of RRR, RRP, RPR; a slider's guide the P)
  — :attr:`JointKind.dyad_letter`, and whether a free link hangs from it in the spanning tree;
* its **drawing anchors** — :meth:`JointKind.anchors`;
* any **run-time selection** the kernels must make before evaluating it (a cam's active arc)
  — :meth:`JointKind.prepare`, :meth:`JointKind.selection_c`.

Adding a kind means one class here, an entry in :data:`KINDS` and a declaring method in :mod:`.model`.
The "drive" kind is a reaction only (the driving or holding torque of a driven body), never declared.

Sign conventions (kept in the manifest and sewgen.engine.forces): a reaction is the force on the joint's body ``b``
from its body ``a``; a pin's in frame axes; a slide's or contact's along n = the guide (face) direction
turned +90°.
"""
from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from .drawing import Anchor, at_anchor, guide_anchors
from .vocabulary import Arc, Attachment, Body, DeclarationError, Joint, Line, SpatialPoint


@dataclass
class Reaction:
    """A joint as the force analysis sees it: body ``a`` acts on body ``b`` at ``b``'s point ``at``."""

    name: str
    kind: str  # a key of KINDS
    a: Body
    b: Body
    at: Attachment | None  # point of b where the force acts (None: a pure torque)
    at_a: Attachment | None = None  # revolute: the coinciding point of a (its own moment arm)
    guide_angle: sp.Expr = sp.S.Zero  # slides and contacts: world angle of the guide line (or face)
    sense: sp.Expr = sp.S.One  # drive: d(body's angle relative to its pivot's body)/d(input) = sense · ratio
    input_index: int = -1  # drive
    joint: Joint | None = None  # the declared joint, for kinds that need more than the fields above (a rod)

    @property
    def joint_kind(self) -> "JointKind":
        return KINDS[self.kind]

    @property
    def columns(self) -> list[str]:
        return list(self.joint_kind.columns)

    @property
    def grounded(self) -> bool:
        return not self.a.moving or not self.b.moving

    @property
    def normal(self) -> tuple:
        """Unit normal of a slide's or contact's force: the guide (or face) direction turned +90°."""
        return (-sp.sin(self.guide_angle), sp.cos(self.guide_angle))


@dataclass
class CamContact:
    """A cam joint as the kernels see it: the active arc's centre (u, v) and radius are the symbols
    ``ka[3j..3j+2]``, chosen at run time from the direction ``normal`` (cos, sin) of the follower face's
    normal in the cam frame; ``ka[3·ncam + j]`` is the active arc's index."""

    joint: Joint
    center: tuple
    radius: sp.Symbol
    index: sp.Symbol
    normal: tuple


def line_frame(kin, line: Line):
    """World point of a line, its world direction angle and unit normal (direction turned +90°)."""
    gx, gy = kin.world(Attachment(line.body, line.u, line.v))
    th = kin.pose[line.body][2] + line.angle
    return (gx, gy), th, (-sp.sin(th), sp.cos(th))


class JointKind:
    """The defaults: a kind that closes no loop, carries no reaction and draws nothing."""

    name = ""
    columns: tuple = ()  # reaction unknowns, in the order of the solution vector f
    dyad_letter: str | None = None  # "R": a pin that closed-form dyads are built of; None: Newton only
    places_links = False  # a free link may hang from it in the spanning tree

    def check(self, mech, name: str, a, b, **options) -> None:
        """Raise DeclarationError if ``a`` and ``b`` cannot be this kind's two sides."""

    def closure(self, kin, joint: Joint) -> list[tuple[str, sp.Expr]]:
        """(name, expression) of each loop-closure equation when ``joint`` is off the spanning tree."""
        return []

    def reaction(self, kin, joint: Joint) -> Reaction:
        raise NotImplementedError(self.name)

    def rows(self, kst, r: Reaction, body: Body, sign: int) -> list[tuple[int, int, sp.Expr]]:
        """Entries (row offset 0/1/2 = force x, force y, moment about G of ``body``; column offset in the
        reaction's unknowns; coefficient) that ``r`` adds to ``body``'s rows of A; ``sign`` is +1 on b, −1 on a."""
        return []

    def on_body(self, kst, r: Reaction, f: list) -> tuple:
        """(fx, fy, mz about the world origin) of the force on b from a, in the unknowns ``f`` of ``r``."""
        return (sp.S.Zero, sp.S.Zero, sp.S.Zero)

    def outputs(self, kst, r: Reaction, f: list) -> list[tuple[str, str, sp.Expr]]:
        """Results this reaction adds after the unknowns (name, unit, expression)."""
        return []

    def manifest(self, mech, r: Reaction) -> dict:
        """Extra fields of the reaction's manifest entry."""
        return {}

    def anchors(self, kin, joint: Joint) -> list[Anchor]:
        return []

    # -- Coulomb friction -----------------------------------------------------------------------------------
    has_friction = False
    friction_unit = ""

    def relative_rate(self, kst, r: Reaction) -> sp.Expr:
        """The relative motion friction opposes: b's rotation against a's (rad/s), or its sliding (m/s)."""
        raise NotImplementedError(self.name)

    def friction_magnitude(self, kst, r: Reaction, f: list, mu, radius) -> sp.Expr:
        """The friction moment or force on b from a (signed: against the relative motion) given the reaction."""
        raise NotImplementedError(self.name)

    def friction_loads(self, kst, r: Reaction, fr) -> list[tuple]:
        """(body, fx, fy, moment about its G) the friction ``fr`` puts on each of the joint's bodies."""
        raise NotImplementedError(self.name)

    def prepare(self, kin, joints: list) -> None:
        """Called once per mechanism with every joint of this kind, before the loops close."""

    def selection_c(self, kin, flavour, prepare) -> list[str]:
        """C lines that choose what this kind's joints need at run time, at the top of every kernel (``flavour``:
        scalar C or the SIMD twin's lanes, derive.kernels._Flavour)."""
        return []


class Revolute(JointKind):
    """A pin: point a of one body and point b of another coincide. Reaction (fx, fy) on b from a."""

    name, columns, dyad_letter, places_links = "revolute", ("fx", "fy"), "R", True

    def check(self, mech, name, a, b, branch=1, **options):
        for att in (a, b):
            if not isinstance(att, Attachment):
                raise DeclarationError(f"{mech.name}: joint {name!r} needs body.at(u, v) on both sides")
        if a.body is b.body:
            raise DeclarationError(f"{mech.name}: joint {name!r} joins {a.body.name!r} to itself")
        if branch not in (1, -1):
            raise DeclarationError(f"{mech.name}: branch of joint {name!r} must be +1 or -1")

    def closure(self, kin, joint):
        (ax, ay), (bx, by) = kin.world(joint.a), kin.world(joint.b)
        return [(f"{joint.name}.x", ax - bx), (f"{joint.name}.y", ay - by)]

    def reaction(self, kin, joint):
        return Reaction(joint.name, self.name, joint.a.body, joint.b.body, joint.b, joint.a)

    def rows(self, kst, r, body, sign):
        dx, dy = kst.own_arm(r.at if body is r.b else r.at_a)
        return [(0, 0, sign), (1, 1, sign), (2, 0, -sign * dy), (2, 1, sign * dx)]

    def on_body(self, kst, r, f):
        px, py = kst.kin.world(r.at)
        return (f[0], f[1], px * f[1] - py * f[0])

    def anchors(self, kin, joint):
        return [at_anchor(kin, joint.a, f"{joint.name}@{joint.a.body.name}", "joint", joint.name),
                at_anchor(kin, joint.b, f"{joint.name}@{joint.b.body.name}", "joint", joint.name)]

    has_friction, friction_unit = True, "N*m"

    def relative_rate(self, kst, r):
        """ω_b − ω_a."""
        return sum((s * kst.o(f"{body.name}.angle_d") for s, body in ((1, r.b), (-1, r.a)) if body.moving), sp.S.Zero)

    def friction_magnitude(self, kst, r, f, mu, radius):
        """−μ·r·|F|·sign(ω_b − ω_a): the pin's friction moment on b (the friction circle, radius μ·r)."""
        return -mu * radius * sp.sqrt(f[0] * f[0] + f[1] * f[1]) * sp.sign(self.relative_rate(kst, r))

    def friction_loads(self, kst, r, fr):
        return [(r.b, sp.S.Zero, sp.S.Zero, fr), (r.a, sp.S.Zero, sp.S.Zero, -fr)]


class _NormalForce(JointKind):
    """Slides and contacts: one normal force N along n at the point ``at`` (a prismatic adds a couple)."""

    couple = False

    def check(self, mech, name, a, b, **options):
        if not isinstance(a, Line) or not isinstance(b, Attachment) or a.body is b.body:
            raise DeclarationError(f"{mech.name}: {self.name} {name!r} needs a line of one body and a point of "
                                   "another")

    def reaction(self, kin, joint):
        return Reaction(joint.name, self.name, joint.a.body, joint.b.body, joint.b,
                        guide_angle=kin.pose[joint.a.body][2] + joint.a.angle)

    def rows(self, kst, r, body, sign):
        nx, ny = r.normal
        dx, dy = (kst.own_arm(r.at) if r.at.body is body else kst.arm(body, kst.kin.world(r.at)))
        out = [(0, 0, sign * nx), (1, 0, sign * ny), (2, 0, sign * (dx * ny - dy * nx))]
        return out + ([(2, 1, sign)] if self.couple else [])

    def on_body(self, kst, r, f):
        px, py = kst.kin.world(r.at)
        nx, ny = r.normal
        return (nx * f[0], ny * f[0], (px * ny - py * nx) * f[0] + (f[1] if self.couple else 0))

    def outputs(self, kst, r, f):
        """The normal force in frame components."""
        return [(f"{r.name}.fx", "N", r.normal[0] * f[0]), (f"{r.name}.fy", "N", r.normal[1] * f[0])]

    has_friction, friction_unit = True, "N"

    def _tangent(self, r):
        return (sp.cos(r.guide_angle), sp.sin(r.guide_angle))

    def relative_rate(self, kst, r):
        """The sliding speed along the guide: t · (v_b − v_a) at the contact point."""
        point = kst.kin.world(r.at)
        (vbx, vby), (vax, vay) = kst.velocity_at(r.b, point), kst.velocity_at(r.a, point)
        tx, ty = self._tangent(r)
        return tx * (vbx - vax) + ty * (vby - vay)

    def friction_magnitude(self, kst, r, f, mu, radius):
        """−μ·|N|·sign(sliding speed): the friction force on b along the guide."""
        return -mu * sp.Abs(f[0]) * sp.sign(self.relative_rate(kst, r))

    def friction_loads(self, kst, r, fr):
        tx, ty = self._tangent(r)
        point = kst.kin.world(r.at)
        out = []
        for body, s in ((r.b, 1), (r.a, -1)):
            if body.moving:
                dx, dy = kst.arm(body, point)
                out.append((body, s * fr * tx, s * fr * ty, s * fr * (dx * ty - dy * tx)))
        return out

    def anchors(self, kin, joint):
        """The guide line of body a, the pin or slider point of body b."""
        return guide_anchors(kin, joint.a, joint.name) + [
            at_anchor(kin, joint.b, f"{joint.name}@{joint.b.body.name}", "joint", joint.name)]


class Prismatic(_NormalForce):
    """A closing slide: point b stays on line a and body b keeps a's angle. Reaction: normal force, couple."""

    name, columns, couple = "prismatic", ("normal", "moment"), True

    def closure(self, kin, joint):
        (gx, gy), th, _n = line_frame(kin, joint.a)
        px, py = kin.world(joint.b)
        normal = -sp.sin(th) * (px - gx) + sp.cos(th) * (py - gy)
        return [(f"{joint.name}.normal", normal),
                (f"{joint.name}.angle", kin.pose[joint.b.body][2] - kin.pose[joint.a.body][2])]


class Slot(_NormalForce):
    """A pin in a slot: point b stays on line a, both turn freely. Reaction: the normal force."""

    name, columns = "slot", ("normal",)

    def closure(self, kin, joint):
        (fx, fy), _th, (nx, ny) = line_frame(kin, joint.a)
        px, py = kin.world(joint.b)
        return [(f"{joint.name}.normal", nx * (px - fx) + ny * (py - fy))]


class Cam(_NormalForce):
    """A cam of circular arcs touching a follower's flat face (seed 000 §一(四)5): while arc k touches, its
    centre runs on the line parallel to the face at the arc's radius (the equivalent pin in a slot); the
    active arc is chosen at run time by the face normal's direction in the cam frame (see model.Mechanism.cam).
    Side a is the cam's origin, side b the face. Reaction: the normal force through the arc's centre."""

    name, columns = "cam", ("normal",)
    has_friction = False  # a cam's contact rolls and slides at once: no Coulomb model here

    def check(self, mech, name, a, b, arcs=(), **options):
        cam = a.body if isinstance(a, Attachment) else None
        if cam is None or not cam.moving or not isinstance(b, Line) or b.body is cam:
            raise DeclarationError(f"{mech.name}: cam {name!r} needs a moving cam body and a face of another body")
        if cam.axis is not None:
            raise DeclarationError(f"{mech.name}: cam {name!r}: {cam.name!r} turns about an axis in space and carries "
                                   "pins only (crank.pin); a cam turns in the plane (driven)")
        if not arcs or not all(isinstance(x, Arc) for x in arcs):
            raise DeclarationError(f"{mech.name}: cam {name!r} needs a list of Arc")

    def prepare(self, kin, joints):
        """The contact of every cam: its active arc's symbols and the face normal in the cam frame."""
        kin.cams = []
        for k, joint in enumerate(joints):
            ka = [sp.Symbol(f"ka_{3 * k + i}", real=True) for i in range(3)]
            _f, th, _n = line_frame(kin, joint.b)
            rel = th + sp.pi / 2 - kin.pose[joint.a.body][2]
            kin.cams.append(CamContact(joint, (ka[0], ka[1]), ka[2], sp.Symbol(f"ka_{3 * len(joints) + k}", real=True),
                                       (sp.cos(rel), sp.sin(rel))))

    def _contact(self, kin, joint) -> CamContact:
        return next(c for c in kin.cams if c.joint is joint)

    def closure(self, kin, joint):
        cam = self._contact(kin, joint)
        (fx, fy), _th, (nx, ny) = line_frame(kin, joint.b)
        cx, cy = kin.world(Attachment(joint.a.body, *cam.center))
        return [(f"{joint.name}.normal", nx * (cx - fx) + ny * (cy - fy) + cam.radius)]

    def reaction(self, kin, joint):
        """On the follower (b) from the cam (a), along the face normal through the active arc's centre."""
        cam = self._contact(kin, joint)
        return Reaction(joint.name, self.name, joint.a.body, joint.b.body, Attachment(joint.a.body, *cam.center),
                        guide_angle=kin.pose[joint.b.body][2] + joint.b.angle)

    def anchors(self, kin, joint):
        """The follower's flat face (a guide line) and the cam's arc centres (radii and sectors: drawing.arcs)."""
        out = guide_anchors(kin, joint.b, joint.name)
        for k, arc in enumerate(joint.arcs):
            out.append(at_anchor(kin, Attachment(joint.a.body, arc.center_u, arc.center_v), f"{joint.name}.arc{k}",
                                 "arc_center", joint.name))
        return out

    #: How far (rad) the face normal is turned, in the sense it turns as the shaft angle grows, before the arc is
    #: chosen: a normal on a sector's edge to within rounding (a switch between two arcs) takes the arc it is
    #: turning into, whatever the last bits of the solved position (which depend on the sweep's other angles).
    #: The sectors' edges move by this much, 1e-12 rad: far below any cam's tolerance.
    SWITCH_NUDGE = 1e-12

    @staticmethod
    def normal_sense(kin, cam) -> int:
        """+1 or −1: the sense the face normal turns in the cam frame as the shaft angle grows (the opposite of the
        cam's own turning: the follower's face swings a little while the cam turns round, so the contact runs
        round the cam against its rotation); 0 where the cam's rate in the shaft angle is not a constant."""
        rate = sp.diff(kin.pose[cam.joint.a.body][2], kin.x[0]) if kin.x else sp.S.Zero
        return -int(sp.sign(rate)) if rate.is_number and rate != 0 else 0

    def selection_c(self, kin, flavour, prepare):
        """ka[3j..3j+2] = the active arc's centre and radius, ka[3·ncam + j] = its index: the arc whose normal
        sector [from, to) holds the face normal's direction e (cam frame) turned by :data:`SWITCH_NUDGE` in the
        sense it turns as the shaft angle grows (:meth:`normal_sense`), the first such arc in declaration order:
        at a switch between two arcs, the arc the contact is moving onto (every sweep through that angle then
        gives the limit from above, right-continuous in the shaft angle). The tests take sin(θ_e + δ − from) ≈
        sin(θ_e − from) + δ and sin(to − θ_e − δ) ≈ sin(to − θ_e) − δ, first order at an edge.
        ``flavour`` (derive.kernels._Flavour) prints scalar C, an if-chain, or the SIMD twin's lanes: the last
        arc in every lane, then each earlier arc selected over it where its sector holds that lane's e, so the
        first arc that holds it wins as in the chain (the same tests on the same values: the same arc)."""
        cams, pr = kin.cams, flavour.printer
        if not cams:
            return []
        lines = [f"{flavour.real} ka[{4 * len(cams)}];"]
        for j, cam in enumerate(cams):
            e0, e1 = (flavour.value(e) for e in prepare(cam.normal))
            block = [f"/* cam {cam.joint.name}: the arc whose normal sector holds e (turned as the shaft turns) */",
                     f"const {flavour.real} e0 = {e0}, e1 = {e1};"]
            nudge = self.normal_sense(kin, cam) * self.SWITCH_NUDGE
            shift = "" if nudge == 0 else f" + {nudge!r}" if nudge > 0 else f" - {-nudge!r}"
            back = "" if nudge == 0 else f" - {nudge!r}" if nudge > 0 else f" + {-nudge!r}"
            arcs = cam.joint.arcs
            picks = []
            for k, arc in enumerate(arcs):
                ca, sa, cb, sb, u, v, r = (pr.doprint(e) for e in prepare(
                    [sp.cos(arc.normal_from), sp.sin(arc.normal_from), sp.cos(arc.normal_to), sp.sin(arc.normal_to),
                     arc.center_u, arc.center_v, arc.radius]))
                values = [(3 * j, u), (3 * j + 1, v), (3 * j + 2, r), (3 * len(cams) + j, f"{k}.0")]
                picks.append(((f"({ca})*e1 - ({sa})*e0{shift}", f"e0*({sb}) - e1*({cb}){back}"), values))
            if flavour.vector:
                block += [f"ka[{i}] = sgv_set1({val});" for i, val in picks[-1][1]]
                for (a, b), values in reversed(picks[:-1]):
                    block += ["{", f"    const sg_vm in = ({a} >= sgv_set1(0.0)) & ({b} > sgv_set1(0.0));"]
                    block += [f"    ka[{i}] = sgv_select(in, sgv_set1({val}), ka[{i}]);" for i, val in values]
                    block.append("}")
            else:
                for k, ((a, b), values) in enumerate(picks):
                    test = f"{a} >= 0.0 && {b} > 0.0"
                    block.append("if (" + test + ") {" if k == 0 else
                                 ("} else if (" + test + ") {" if k < len(arcs) - 1 else "} else {"))
                    block += [f"    ka[{i}] = {val};" for i, val in values]
                block.append("}")
            lines += ["{"] + ["    " + line for line in block] + ["}"]
        return lines


class Rod(JointKind):
    """A rod with ball joints at both ends from a spatial crank's pin B (side a) to point C of a planar body
    (side b, lifted ``z`` out of the plane): |C − B| = length (seed 003 eq. 1's spatial four-bar). A two-force
    member: its reaction is the tension N, acting on C as −N·e and on B as +N·e, e = (C − B)/length.

    On the planar body the in-plane components enter its rows (its bearing takes the out-of-plane part, given as
    the output ``<name>.fz``); on the crank its x, y rows take the in-plane components and its moment row the
    moment about its own axis, ((B − A) × N·e)·axis. The dyad letter "S": a link pinned to a known point whose
    other point is at the rod's in-plane reach √(length² − Δz²) of B's projection closes in closed form as an
    RRR triangle (:mod:`derive.dyads`)."""

    name, columns, dyad_letter = "rod", ("tension",), "S"

    def check(self, mech, name, a, b, values=None, **options):
        if not isinstance(a, SpatialPoint) or not isinstance(b, Attachment) or b.body.axis is not None:
            raise DeclarationError(f"{mech.name}: rod {name!r} needs a spatial crank's pin (crank.pin(...)) and a "
                                   "point of a planar body")
        if options.get("branch", 1) not in (1, -1):
            raise DeclarationError(f"{mech.name}: branch of rod {name!r} must be +1 or -1")

    @staticmethod
    def ends(kin, joint):
        """B and C in the machine frame (x, y, z)."""
        return kin.world3(joint.a), kin.world3((joint.b, joint.values["z"]))

    def direction(self, kin, joint):
        """e = (C − B)/length."""
        b, c = self.ends(kin, joint)
        length = joint.values["length"]
        return tuple((c[k] - b[k]) / length for k in range(3))

    def closure(self, kin, joint):
        b, c = self.ends(kin, joint)
        length = joint.values["length"]
        return [(f"{joint.name}.length", sum((c[k] - b[k]) ** 2 for k in range(3)) - length ** 2)]

    def reaction(self, kin, joint):
        return Reaction(joint.name, self.name, joint.a.body, joint.b.body, joint.b, joint=joint)

    def rows(self, kst, r, body, sign):
        e = self.direction(kst.kin, r.joint)
        if body is r.b:  # −N·e at C
            dx, dy = kst.own_arm(r.at)
            return [(0, 0, -e[0]), (1, 0, -e[1]), (2, 0, -(dx * e[1] - dy * e[0]))]
        b, _c = self.ends(kst.kin, r.joint)  # +N·e at B on the crank: in-plane force, moment about its axis
        axis = body.axis
        arm = [b[k] - axis.point[k] for k in range(3)]
        moment = sum(axis.direction[k] * (arm[(k + 1) % 3] * e[(k + 2) % 3] - arm[(k + 2) % 3] * e[(k + 1) % 3])
                     for k in range(3))
        return [(0, 0, e[0]), (1, 0, e[1]), (2, 0, moment)]

    def outputs(self, kst, r, f):
        """The force on the planar body's pin C in machine axes (its z part goes to that body's bearing)."""
        return [(f"{r.name}.{axis}", "N", -f[0] * component)
                for axis, component in zip(("fx", "fy", "fz"), self.direction(kst.kin, r.joint))]

    def anchors(self, kin, joint):
        """B projected on the plane (on the crank) and C (on the planar body)."""
        b, _c = self.ends(kin, joint)
        return [Anchor(f"{joint.name}@{joint.a.body.name}", joint.a.body.name, "joint", joint.name, (b[0], b[1])),
                at_anchor(kin, joint.b, f"{joint.name}@{joint.b.body.name}", "joint", joint.name)]


class Drive(JointKind):
    """The torque that turns (or holds) a driven body, from the frame: a reaction, never declared."""

    name, columns = "drive", ("torque",)

    def rows(self, kst, r, body, sign):
        return [(2, 0, sign)]

    def on_body(self, kst, r, f):
        return (sp.S.Zero, sp.S.Zero, f[0])

    def manifest(self, mech, r):
        """Input torque = Σ sense · drive torque of the bodies that input turns."""
        rate = sp.sympify(r.sense)
        return {"input": mech.inputs[r.input_index].name, "sense": int(rate) if rate.is_Integer else float(rate)}


class LinearDrive(JointKind):
    """The force that holds a body at a travel input along its guide (a prismatic input), from the guide's
    body, at the body's origin on the guide: a reaction, never declared."""

    name, columns = "linear_drive", ("force",)

    def _along(self, r):
        return (sp.cos(r.guide_angle), sp.sin(r.guide_angle))

    def rows(self, kst, r, body, sign):
        tx, ty = self._along(r)
        dx, dy = (kst.own_arm(r.at) if r.at.body is body else kst.arm(body, kst.kin.world(r.at)))
        return [(0, 0, sign * tx), (1, 0, sign * ty), (2, 0, sign * (dx * ty - dy * tx))]

    def on_body(self, kst, r, f):
        px, py = kst.kin.world(r.at)
        tx, ty = self._along(r)
        return (tx * f[0], ty * f[0], (px * ty - py * tx) * f[0])

    def manifest(self, mech, r):
        """Input force = the drive force along the guide (sense 1: the input is the travel itself)."""
        return {"input": mech.inputs[r.input_index].name, "sense": 1}


#: Every joint kind by name: the only registry the derivation consults.
KINDS: dict[str, JointKind] = {k.name: k for k in (Revolute(), Prismatic(), Slot(), Cam(), Rod(), Drive(),
                                                   LinearDrive())}

#: The kinds a declaration may use (``Drive`` and ``LinearDrive`` are implied by driven and held bodies).
DECLARABLE = ("revolute", "prismatic", "slot", "cam", "rod")


def kind_of(joint: Joint) -> JointKind:
    return KINDS[joint.kind]

"""Force elements: springs, dampers and torsion springs, computed inside the compiled kinetostatics from the
positions and velocities of the points they join.

An element is not a constraint: it adds no unknown and no closure equation. It puts known forces on the bodies
it joins — into b of A f = b (seed 000 §二(三): the external forces on each body's right-hand side) — and adds
its own results (force, length, energy or power). One class per element kind, as :mod:`derive.joints` does for
joints; :data:`ELEMENTS` is the registry.

Conventions (stated in the manifest and in docs/explanation/conventions.md):

* a **spring** or **damper** between point ``a`` and point ``b``: its force is a *tension* (positive when it
  pulls the points together); spring F = preload + k·(L − L0), damper F = c·dL/dt;
* a **torsion spring** at a revolute between bodies a and b: deflection Δ = (θ_b − θ_a) − θ0, the continuous
  relative rotation (:meth:`TorsionSpring.deflection`: the inputs' turns wind it, a link's angle counts within half
  a turn of its declared guess); torque T = preload + k·Δ acts on b as −T and on a as +T;
* a spring's stored energy (preload·(L − L0) + k·(L − L0)²/2, and the torsional analogue) is part of the
  potential energy, and its rate the output ``elastic_power``; a damper's power on the mechanism
  (−c·(dL/dt)² ≤ 0) is part of ``load_power``, so the power balance drive + loads = d(E_kin + E_pot)/dt still
  closes;
* an element anchored to the frame acts on the moving parts *from the frame*: its force is part of the frame's
  force and moment on the parts (``frame_force_on_parts``), like a grounded joint's reaction.
"""
from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from .joints import KINDS, Revolute
from .vocabulary import Attachment, Body, DeclarationError, Joint


@dataclass(eq=False)
class ForceElement:
    """A declared element: its kind (a key of :data:`ELEMENTS`), the two points it joins (or the revolute it
    sits on) and its parameters (SymPy expressions, by what they are: stiffness, free_length, preload, …)."""

    name: str
    kind: str
    a: Attachment | None
    b: Attachment | None
    joint: Joint | None
    values: dict
    doc: str = ""

    @property
    def bodies(self) -> tuple:
        if self.joint is not None:
            return (self.joint.a.body, self.joint.b.body)
        return (self.a.body, self.b.body)


@dataclass(frozen=True)
class Applied:
    """A force (fx, fy, world axes) at point ``at`` of ``body`` and a couple ``torque`` on it."""

    body: Body
    fx: sp.Expr
    fy: sp.Expr
    at: Attachment | None
    torque: sp.Expr = sp.S.Zero


class ElementKind:
    name = ""

    def check(self, mech, el: ForceElement) -> None:
        """Raise DeclarationError when the element's sides are wrong for its kind."""

    def applied(self, kst, el: ForceElement) -> list[Applied]:
        """What the element puts on each of its two bodies (ground included)."""
        raise NotImplementedError

    def energy(self, kst, el: ForceElement) -> sp.Expr:
        """Stored energy (J): part of the potential energy."""
        return sp.S.Zero

    def energy_rate(self, kst, el: ForceElement) -> sp.Expr:
        """d(energy)/dt (W), from velocities: the run time's energy balance needs it without differencing."""
        return sp.S.Zero

    def power(self, kst, el: ForceElement) -> sp.Expr:
        """Power of the element's forces on the mechanism that no energy accounts for (W; a damper's ≤ 0)."""
        return sp.S.Zero

    def outputs(self, kst, el: ForceElement) -> list[tuple[str, str, sp.Expr]]:
        raise NotImplementedError


class _TwoPoint(ElementKind):
    """An element along the line between two points of two bodies."""

    def check(self, mech, el):
        if not isinstance(el.a, Attachment) or not isinstance(el.b, Attachment):
            raise DeclarationError(f"{mech.name}: {self.name} {el.name!r} needs body.at(u, v) at both ends")
        if el.a.body is el.b.body:
            raise DeclarationError(f"{mech.name}: {self.name} {el.name!r} joins {el.a.body.name!r} to itself")

    @staticmethod
    def geometry(kst, el):
        """Length L and unit vector e from a to b."""
        (ax, ay), (bx, by) = kst.kin.world(el.a), kst.kin.world(el.b)
        dx, dy = bx - ax, by - ay
        length = sp.sqrt(dx * dx + dy * dy)
        return length, (dx / length, dy / length)

    @staticmethod
    def rate(kst, el, e):
        """dL/dt = e · (v_b − v_a)."""
        (vax, vay), (vbx, vby) = kst.point_velocity(el.a), kst.point_velocity(el.b)
        return e[0] * (vbx - vax) + e[1] * (vby - vay)

    def tension(self, kst, el):
        raise NotImplementedError

    def pull(self, kst, el) -> tuple:
        """The force on a, towards b: F·e."""
        _length, e = self.geometry(kst, el)
        f = self.tension(kst, el)
        return (f * e[0], f * e[1])

    def applied(self, kst, el):
        """A tension F pulls a towards b (+F·e at a) and b towards a (−F·e at b)."""
        fx, fy = self.pull(kst, el)
        return [Applied(el.a.body, fx, fy, el.a), Applied(el.b.body, -fx, -fy, el.b)]


class Spring(_TwoPoint):
    """A linear spring: tension F = preload + k·(L − L0)."""

    name = "spring"

    def tension(self, kst, el):
        length, _e = self.geometry(kst, el)
        v = el.values
        return v["preload"] + v["stiffness"] * (length - v["free_length"])

    def energy(self, kst, el):
        length, _e = self.geometry(kst, el)
        v = el.values
        stretch = length - v["free_length"]
        return v["preload"] * stretch + v["stiffness"] * stretch * stretch / 2

    def pull(self, kst, el):
        """F·e = k·d + (preload − k·L0)·d/L, d = b − a: the linear part k·d needs no direction, so a spring whose
        ends meet (L = 0) pulls with k·d = 0 where its tension there, preload − k·L0, is zero (a zero-length
        spring, or one of zero stiffness and preload) — only a nonzero tension at L = 0 has no direction (a
        non-finite result at that angle). The division is by L + [preload − k·L0 = 0], which is L wherever the
        term counts."""
        (ax, ay), (bx, by) = kst.kin.world(el.a), kst.kin.world(el.b)
        length, _e = self.geometry(kst, el)
        v = el.values
        rest = v["preload"] - v["stiffness"] * v["free_length"]
        divisor = length + sp.Piecewise((1, sp.Eq(rest, 0)), (0, True))
        return tuple(v["stiffness"] * d + rest * d / divisor for d in (bx - ax, by - ay))

    def energy_rate(self, kst, el):
        """dV/dt = F·dL/dt = (F·e)·(v_b − v_a)."""
        fx, fy = self.pull(kst, el)
        (vax, vay), (vbx, vby) = kst.point_velocity(el.a), kst.point_velocity(el.b)
        return fx * (vbx - vax) + fy * (vby - vay)

    def outputs(self, kst, el):
        length, _e = self.geometry(kst, el)
        return [(f"{el.name}.force", "N", self.tension(kst, el)), (f"{el.name}.length", "m", length),
                (f"{el.name}.energy", "J", self.energy(kst, el))]


class Damper(_TwoPoint):
    """A linear viscous damper: tension F = c·dL/dt (it resists extension and compression alike)."""

    name = "damper"

    def tension(self, kst, el):
        _length, e = self.geometry(kst, el)
        return el.values["coefficient"] * self.rate(kst, el, e)

    def power(self, kst, el):
        _length, e = self.geometry(kst, el)
        rate = self.rate(kst, el, e)
        return -el.values["coefficient"] * rate * rate

    def outputs(self, kst, el):
        length, e = self.geometry(kst, el)
        return [(f"{el.name}.force", "N", self.tension(kst, el)), (f"{el.name}.length", "m", length),
                (f"{el.name}.rate", "m/s", self.rate(kst, el, e)), (f"{el.name}.power", "W", -self.power(kst, el))]


class TorsionSpring(ElementKind):
    """A torsion spring at a revolute: T = preload + k·Δ, Δ = (θ_b − θ_a) − θ0 the continuous relative rotation;
    −T on b, +T on a."""

    name = "torsion_spring"

    def check(self, mech, el):
        if not isinstance(el.joint, Joint) or not isinstance(KINDS[el.joint.kind], Revolute):
            raise DeclarationError(f"{mech.name}: torsion spring {el.name!r} needs a revolute joint "
                                   "(the value m.revolute(...) returns)")

    @staticmethod
    def deflection(kst, el):
        """Δ = (θ_b − θ_a) − θ0 as the spring winds, never wrapped at ±180°: a torsion spring on a joint that turns
        right round (a crank's pivot, its crank pin) winds a turn per turn. The relative angle is linear in the
        inputs and the link angles, θ_b − θ_a − θ0 = Σ c_k x_k + Σ s_i q_i + constants: the inputs' part is taken
        as the inputs are given (a shaft angle of 370° is a turn more than 10°); the links' part Σ s_i q_i within
        half a turn of its value at the links' declared guesses (a link rocks about where it is declared; the
        results read a link's angle only through its sine and cosine, so sweeps that count a link's turns
        differently agree)."""
        kin = kst.kin
        pose = kin.pose
        raw = sp.expand(pose[el.joint.b.body][2] - pose[el.joint.a.body][2] - el.values["free_angle"])
        turns = sum((sp.diff(raw, x) * x for x in kin.x), sp.S.Zero)
        links = sum((sp.diff(raw, q) * q for q in kin.q), sp.S.Zero)
        ref = links.subs({q: c.guess for q, c in zip(kin.q, kin.coords)})
        rest = sp.expand(raw - turns - links)  # phases, the free angle: no input, no coordinate (poses are linear)
        return turns + rest + ref + sp.atan2(sp.sin(links - ref), sp.cos(links - ref))

    def torque(self, kst, el):
        v = el.values
        return v["preload"] + v["stiffness"] * self.deflection(kst, el)

    def applied(self, kst, el):
        t = self.torque(kst, el)
        return [Applied(el.joint.a.body, sp.S.Zero, sp.S.Zero, None, t),
                Applied(el.joint.b.body, sp.S.Zero, sp.S.Zero, None, -t)]

    def energy_rate(self, kst, el):
        """dV/dt = T·(ω_b − ω_a)."""
        a, b = el.joint.a.body, el.joint.b.body
        rate = sum((s * kst.o(f"{body.name}.angle_d") for s, body in ((1, b), (-1, a)) if body.moving), sp.S.Zero)
        return self.torque(kst, el) * rate

    def energy(self, kst, el):
        d = self.deflection(kst, el)
        v = el.values
        return v["preload"] * d + v["stiffness"] * d * d / 2

    def outputs(self, kst, el):
        return [(f"{el.name}.torque", "N*m", self.torque(kst, el)),
                (f"{el.name}.deflection", "rad", self.deflection(kst, el)),
                (f"{el.name}.energy", "J", self.energy(kst, el))]


#: Every force-element kind by name.
ELEMENTS: dict[str, ElementKind] = {k.name: k for k in (Spring(), Damper(), TorsionSpring())}

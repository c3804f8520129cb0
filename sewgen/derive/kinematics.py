"""Symbolic kinematics of a declared mechanism (DESIGN.md §3, seed 000 §一(三)-(四)).

A spanning tree from ground places every body: a driven body turns about its pivot, a slider travels on
its guide, a link hangs from the first pin (breadth first) that joins it to a placed body. Each joint off
the tree closes a loop (the seeds' complex-vector loops r·e^{iθ} = the same two scalar equations):

    Φ(q, x) = 0,    Φ_q q' = −Φ_x x',    Φ_q q'' = γ = −Φ_x x'' − (∂(Φ_q q' + Φ_x x')/∂(q, x))·(q', x').

Unknowns q are absolute link angles (rad) and slider travels (m); inputs x are the shaft angle and held
inputs. Points and bodies get position, velocity and acceleration by the chain rule (seed 000 fig. 1-2).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import sympy as sp

from .joints import KINDS, CamContact, kind_of
from .vocabulary import Attachment, Body, DeclarationError, SpatialPoint

if TYPE_CHECKING:
    from .model import Mechanism


def rot(theta, u, v):
    """R(theta)·(u, v)."""
    c, s = sp.cos(theta), sp.sin(theta)
    return (c * u - s * v, s * u + c * v)


@dataclass
class Coordinate:
    name: str  # "<body>.angle" or "<body>.travel"
    kind: str  # "angle" or "length"
    body: Body
    guess: float


@dataclass
class Observable:
    name: str
    unit: str
    expr: sp.Expr


class Kinematics:
    """Φ, its Jacobians, γ and every observable of one mechanism, as SymPy expressions."""

    def __init__(self, mech: Mechanism):
        self.mech = mech
        self.coords: list[Coordinate] = []
        self.pose: dict = {}  # body -> (ox, oy, theta)
        self.tree_joint: dict = {}  # link body -> joint that places it
        self.x = [sp.Symbol(f"x_{k}", real=True) for k in range(len(mech.inputs))]
        self.xd = [sp.Symbol(f"xd_{k}", real=True) for k in range(len(mech.inputs))]
        self.xdd = [sp.Symbol(f"xdd_{k}", real=True) for k in range(len(mech.inputs))]
        self.p = [prm.symbol for prm in mech.params]
        self._place_bodies()
        n = len(self.coords)
        self.q = [sp.Symbol(f"q_{i}", real=True) for i in range(n)]
        self.qd = [sp.Symbol(f"qd_{i}", real=True) for i in range(n)]
        self.qdd = [sp.Symbol(f"qdd_{i}", real=True) for i in range(n)]
        self._close_loops()
        self._derive_motion()
        self._derive_observables()

    # -- tree --------------------------------------------------------------------------------------------
    def world(self, att: Attachment):
        ox, oy, th = self.pose[att.body]
        du, dv = rot(th, att.u, att.v)
        return (ox + du, oy + dv)

    def world3(self, point) -> tuple:
        """(x, y, z) of a point in the machine frame: a spatial crank's pin (axis point + along·axis + radius·(cos θ
        e1 + sin θ e2)), or a planar body's point lifted ``z`` out of the plane (given as (Attachment, z))."""
        if isinstance(point, SpatialPoint):
            axis, th = point.body.axis, self.pose[point.body][2]
            c, s = sp.cos(th), sp.sin(th)
            return tuple(axis.point[k] + point.along * axis.direction[k] + point.radius * (c * axis.e1[k] + s * axis.e2[k])
                         for k in range(3))
        att, z = point
        x, y = self.world(att)
        return (x, y, z)

    def com(self, body: Body) -> tuple:
        """(x, y, z) of ``body``'s centre of mass in the machine frame. A planar body's is its point (com_u, com_v)
        in the plane (z = 0); a spatial crank's lies in the plane it turns in through its axis point: com_u along
        the crank (where a pin at angle zero of the crank points), com_v a quarter turn ahead about its axis,
        G = axis point + com_u·(cos θ e1 + sin θ e2) + com_v·(−sin θ e1 + cos θ e2)."""
        u, v = body.com
        if body.axis is None:
            return (*self.world(Attachment(body, u, v)), sp.S.Zero)
        axis, th = body.axis, self.pose[body][2]
        c, s = sp.cos(th), sp.sin(th)
        return tuple(axis.point[k] + (u * c - v * s) * axis.e1[k] + (u * s + v * c) * axis.e2[k] for k in range(3))

    def _new_coord(self, body: Body, kind: str) -> sp.Symbol:
        suffix = "angle" if kind == "angle" else "travel"
        self.coords.append(Coordinate(f"{body.name}.{suffix}", kind, body, body.guess))
        return sp.Symbol(f"q_{len(self.coords) - 1}", real=True)

    def _place_bodies(self) -> None:
        mech = self.mech
        self.pose[mech.ground] = (sp.S.Zero, sp.S.Zero, sp.S.Zero)
        pending = [b for b in mech.bodies if b.kind != "ground"]
        while pending:
            known = set(self.pose)  # breadth first: only bodies placed in earlier rounds
            placed_now = []
            for body in pending:
                pose = self._try_place(body, known)
                if pose is not None:
                    placed_now.append((body, pose))
            if not placed_now:
                names = ", ".join(b.name for b in pending)
                raise DeclarationError(f"{mech.name}: cannot reach {names} from ground through joints or guides")
            for body, pose in placed_now:
                self.pose[body] = pose
                pending.remove(body)

    def _try_place(self, body: Body, known: set):
        if body.kind == "driven" and body.guide is not None:  # held at a travel along its guide
            g = body.guide
            if g.body not in known:
                return None
            s = self.x[body.input_index]
            bx, by = self.world(Attachment(g.body, g.u, g.v))
            th = self.pose[g.body][2] + g.angle
            return (bx + s * sp.cos(th), by + s * sp.sin(th), th)
        if body.kind == "driven":  # turns about its pivot relative to the pivot's body (ground: absolutely)
            parent = body.pivot.body
            if parent not in known:
                return None
            x = self.x[body.input_index]
            ox, oy = self.world(body.pivot)
            turn = body.sense * body.ratio * x + body.phase if body.input_index == 0 else x
            return (ox, oy, self.pose[parent][2] + turn)
        if body.kind == "slider":
            g = body.guide
            if g.body not in known:
                return None
            s = self._new_coord(body, "length")
            bx, by = self.world(Attachment(g.body, g.u, g.v))
            th = self.pose[g.body][2] + g.angle
            return (bx + s * sp.cos(th), by + s * sp.sin(th), th)
        for joint in self.mech.joints:  # link: first joint of a kind links hang from (a pin) to a placed body
            if not kind_of(joint).places_links:
                continue
            for mine, other in ((joint.a, joint.b), (joint.b, joint.a)):
                if mine.body is body and other.body in known:
                    th = self._new_coord(body, "angle")
                    wx, wy = self.world(other)
                    du, dv = rot(th, mine.u, mine.v)
                    self.tree_joint[body] = joint
                    return (wx - du, wy - dv, th)
        return None

    # -- loops ---------------------------------------------------------------------------------------------
    def _close_loops(self) -> None:
        """Every joint off the spanning tree closes a loop with its kind's equations (derive.joints)."""
        self.cams: list[CamContact] = []  # filled by the cam kind's prepare
        for name, kind in KINDS.items():
            kind.prepare(self, [j for j in self.mech.joints if j.kind == name])
        tree = set(self.tree_joint.values())
        self.closure: list[sp.Expr] = []
        self.closure_names: list[str] = []
        for joint in self.mech.joints:
            if joint in tree:
                continue
            for name, expr in kind_of(joint).closure(self, joint):
                self.closure_names.append(name)
                self.closure.append(expr)
        n, m = len(self.coords), len(self.closure)
        if n != m:
            raise DeclarationError(
                f"{self.mech.name}: {n} unknown coordinates but {m} loop-closure equations "
                f"({'under' if n > m else 'over'}-constrained; check the joints)")

    # -- derivatives ------------------------------------------------------------------------------------
    def dt(self, expr: sp.Expr) -> sp.Expr:
        """Total time derivative of an expression in q, x, q', x' (chain rule)."""
        out = sp.S.Zero
        for a, ad in zip(self.q + self.x + self.qd + self.xd, self.qd + self.xd + self.qdd + self.xdd):
            d = sp.diff(expr, a)
            if d != 0:
                out += d * ad
        return out

    def _derive_motion(self) -> None:
        phi = sp.Matrix(self.closure)
        self.jac_q = phi.jacobian(self.q) if self.q else sp.zeros(0, 0)
        self.jac_x = phi.jacobian(self.x) if self.closure else sp.zeros(0, len(self.x))  # a body with no loop
        self.vel_rhs = list(-(self.jac_x * sp.Matrix(self.xd))) if self.q else []
        vel = [sum((self.jac_q[i, j] * self.qd[j] for j in range(len(self.q))), sp.S.Zero)
               + sum((self.jac_x[i, k] * self.xd[k] for k in range(len(self.x))), sp.S.Zero)
               for i in range(len(self.closure))]
        # Φ_q q'' = −(d/dt of the velocity constraint with q'' = 0, x'' kept)
        zero_qdd = {s: 0 for s in self.qdd}
        self.gamma = [-self.dt(v).subs(zero_qdd) for v in vel]

    def _motion_of(self, name: str, pos, unit: str):
        vel = self.dt(pos)
        acc = self.dt(vel)
        rate = {"m": ("m/s", "m/s^2"), "rad": ("rad/s", "rad/s^2")}[unit]
        return [Observable(name, unit, pos), Observable(name + "_d", rate[0], vel),
                Observable(name + "_dd", rate[1], acc)]

    def _derive_observables(self) -> None:
        obs: list[Observable] = []
        for name, att, _doc in self.mech.points:
            px, py = self.world(att)
            obs += self._point_block(name, px, py)
        for body in self.mech.bodies:
            if not body.moving:
                continue
            th = self.pose[body][2]
            obs += self._motion_of(f"{body.name}.angle", th, "rad")
            gx, gy, _gz = self.com(body)
            obs += self._point_block(f"{body.name}.com", gx, gy)
        obs += [Observable(f"{c.joint.name}.arc", "", c.index) for c in self.cams]
        for body in self.spatial_bodies:  # a spatial crank's centre of mass moves out of the plane too
            obs += self._motion_of(f"{body.name}.com.z", self.com(body)[2], "m")
        self.observables = obs

    @property
    def spatial_bodies(self) -> list[Body]:
        """The bodies that turn about an axis in space (spatial cranks), in declaration order."""
        return [b for b in self.mech.bodies if b.axis is not None]

    def _point_block(self, name, px, py):
        """x, y, vx, vy, ax, ay of a point, in that order (the manifest's point layout)."""
        mx = self._motion_of(f"{name}.x", px, "m")
        my = self._motion_of(f"{name}.y", py, "m")
        return [mx[0], my[0], mx[1], my[1], mx[2], my[2]]

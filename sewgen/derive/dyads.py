"""Split a mechanism's loops into closed-form dyads (seed 001 §三, Makino's standard vector triangles).

A loop that splits into two-unknown triangles solves in closed form, with no first guess and with the
assembly branch an explicit sign (DESIGN.md §3). Four dyads cover the sewing-machine mechanisms:

* RRR (BV4): two links pinned together, each pinned to a known body — four-bars, the take-up lever;
* RRP: a link pinned to a slider on a known guide — the needle-bar crank-slider;
* RPR: a slider on a link pinned to a known body, the slider pinned to a known body — the oscillating
  guide bar of the hook drive (seed 000 fig. 1-2(c)).
* RRS: a link pinned to a known body whose other pin is held by a ball-jointed rod to a spatial crank's pin —
  seed 003 eq. 1's spatial four-bar, an RRR triangle whose second side is the rod's in-plane reach.

Each dyad lists the SymPy expressions of its known inputs (in earlier coordinates, inputs, parameters)
and of its coordinates in terms of the runtime solver's outputs (csrc/sg_runtime.h sg_dyad_*).
"""
from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from .joints import kind_of
from .kinematics import Kinematics, rot
from .vocabulary import Attachment, Body, Joint


@dataclass
class Dyad:
    kind: str  # "rrr", "rrp", "rpr", "rrs"
    joint: Joint  # the joint whose branch sign picks the assembly
    bodies: tuple
    inputs: dict  # C local name -> list of SymPy expressions (known when the dyad is reached)
    outputs: list  # (coordinate index, SymPy expression in the solver's output symbols)
    trig: list  # (angle coordinate index, cos, sin) in the solver's outputs: no trig call needed
    meaning: str


def _other(joint: Joint, body: Body) -> Attachment:
    return joint.b if joint.a.body is body else joint.a


def _mine(joint: Joint, body: Body) -> Attachment:
    return joint.a if joint.a.body is body else joint.b


def _angle(u, v):
    return sp.atan2(v, u)


def _rotation_between(a, b):
    """cos and sin of the rotation taking vector a onto vector b, for |a| = |b| (no trig call)."""
    n2 = a[0] ** 2 + a[1] ** 2
    return ((a[0] * b[0] + a[1] * b[1]) / n2, (a[0] * b[1] - a[1] * b[0]) / n2)


class _Split:
    def __init__(self, kin: Kinematics):
        self.kin = kin
        mech = kin.mech
        self.coord_of = {c.body: i for i, c in enumerate(kin.coords)}
        self.known_q: set = set()
        self.known_bodies = {b for b in mech.bodies if b.kind in ("ground", "driven")}
        self.used: set = set()
        self.dyads: list[Dyad] = []
        self.revolutes = [j for j in mech.joints if kind_of(j).dyad_letter == "R"]  # the pins dyads are made of
        self.rods = [j for j in mech.joints if kind_of(j).dyad_letter == "S"]  # ball-jointed rods to spatial cranks

    def is_known_point(self, att: Attachment) -> bool:
        if att.body not in self.known_bodies:
            return False
        ox, oy, th = self.kin.pose[att.body]
        needed = {s for e in (ox, oy, th) for s in e.free_symbols if s.name.startswith("q_")}
        return needed <= self.known_q

    def pins_to_known(self, body: Body, exclude: Joint):
        for j in self.revolutes:
            if j is exclude or j in self.used:
                continue
            if body in (j.a.body, j.b.body) and self.is_known_point(_other(j, body)):
                return j
        return None

    def solve(self) -> list[Dyad] | None:
        unknown = [b for b in self.kin.mech.bodies if b.kind in ("link", "slider")]
        while unknown:
            dyad = self.find_dyad(unknown)
            if dyad is None:
                return None
            self.dyads.append(dyad)
            for b in dyad.bodies:
                unknown.remove(b)
                self.known_bodies.add(b)
                self.known_q.add(self.kin.q[self.coord_of[b]])
        if any(j not in self.used for j in self.kin.mech.joints):
            return None  # a joint no dyad accounts for (an extra constraint): Newton checks it
        return self.dyads

    def find_dyad(self, unknown):
        for j in self.revolutes:
            if j in self.used or j.a.body not in unknown or j.b.body not in unknown:
                continue
            for b1, b2 in ((j.a.body, j.b.body), (j.b.body, j.a.body)):
                if b1.kind == "link" and b2.kind == "link":
                    ja, jb = self.pins_to_known(b1, j), self.pins_to_known(b2, j)
                    if ja and jb and ja is not jb:
                        return self.rrr(j, b1, b2, ja, jb)
                if b1.kind == "link" and b2.kind == "slider" and b2.guide.body in self.known_bodies \
                        and self.is_known_point(Attachment(b2.guide.body, 0, 0)):
                    ja = self.pins_to_known(b1, j)
                    if ja:
                        return self.rrp(j, b1, b2, ja)
        for j in self.rods:  # RRS: a link pinned to a known point, its rod's crank pin known (a spatial four-bar)
            b1 = j.b.body
            if j in self.used or b1 not in unknown or b1.kind != "link" or j.a.body not in self.known_bodies:
                continue
            ja = self.pins_to_known(b1, None)
            if ja:
                return self.rrs(j, b1, ja)
        for s in unknown:  # RPR: a slider whose guide is an unknown link
            if s.kind != "slider" or s.guide.body not in unknown or s.guide.body.kind != "link":
                continue
            bar = s.guide.body
            ja, jb = self.pins_to_known(bar, None), self.pins_to_known(s, None)
            if ja and jb and ja is not jb:
                return self.rpr(s, bar, ja, jb)
        return None

    def mark(self, *joints):
        self.used.update(joints)

    def rrr(self, j, b1, b2, ja, jb) -> Dyad:
        kin = self.kin
        P, Q = kin.world(_other(ja, b1)), kin.world(_other(jb, b2))
        a1, i1 = _mine(ja, b1), _mine(j, b1)
        a2, i2 = _mine(jb, b2), _mine(j, b2)
        v1 = (i1.u - a1.u, i1.v - a1.v)
        v2 = (i2.u - a2.u, i2.v - a2.v)
        Jx, Jy = sp.symbols("J_0 J_1", real=True)
        Px, Py, Qx, Qy = sp.symbols("P_0 P_1 Q_0 Q_1", real=True)
        self.mark(j, ja, jb)
        return Dyad("rrr", j, (b1, b2),
                    {"P": list(P), "Q": list(Q), "l": [sp.sqrt(v1[0] ** 2 + v1[1] ** 2),
                                                       sp.sqrt(v2[0] ** 2 + v2[1] ** 2)]},
                    [(self.coord_of[b1], _angle(Jx - Px, Jy - Py) - _angle(*v1)),
                     (self.coord_of[b2], _angle(Jx - Qx, Jy - Qy) - _angle(*v2))],
                    [(self.coord_of[b1], *_rotation_between(v1, (Jx - Px, Jy - Py))),
                     (self.coord_of[b2], *_rotation_between(v2, (Jx - Qx, Jy - Qy)))],
                    f"+1: joint {j.name} left of the line from {ja.name} to {jb.name}")

    def rrp(self, j, b1, s, ja) -> Dyad:
        kin = self.kin
        P = kin.world(_other(ja, b1))
        a1, i1 = _mine(ja, b1), _mine(j, b1)
        v1 = (i1.u - a1.u, i1.v - a1.v)
        g = s.guide
        gx, gy = kin.world(Attachment(g.body, g.u, g.v))
        th = kin.pose[g.body][2] + g.angle
        pin = _mine(j, s)
        du, dv = rot(th, pin.u, pin.v)
        Jx, Jy, ssym = sp.symbols("J_0 J_1 s", real=True)
        Px, Py = sp.symbols("P_0 P_1", real=True)
        self.mark(j, ja)
        return Dyad("rrp", j, (b1, s),
                    {"P": list(P), "l": [sp.sqrt(v1[0] ** 2 + v1[1] ** 2)],
                     "L0": [gx + du, gy + dv], "u": [sp.cos(th), sp.sin(th)]},
                    [(self.coord_of[b1], _angle(Jx - Px, Jy - Py) - _angle(*v1)), (self.coord_of[s], ssym)],
                    [(self.coord_of[b1], *_rotation_between(v1, (Jx - Px, Jy - Py)))],
                    f"+1: the larger travel of {s.name} at joint {j.name}")

    def rrs(self, j, b1, ja) -> Dyad:
        """Seed 003 eq. 1: the rocker's pin C lies on the circle of radius √(L² − (z_C − z_B)²) about B's
        projection and on the circle about its pivot: an RRR triangle with the rod's in-plane reach as one side
        (δ₁ = the branch: +1 puts C left of the line from the pivot to B's projection)."""
        kin = self.kin
        P = kin.world(_other(ja, b1))
        a1, i1 = _mine(ja, b1), j.b
        v1 = (i1.u - a1.u, i1.v - a1.v)
        B = kin.world3(j.a)
        reach = sp.sqrt(j.values["length"] ** 2 - (j.values["z"] - B[2]) ** 2)
        Jx, Jy = sp.symbols("J_0 J_1", real=True)
        Px, Py = sp.symbols("P_0 P_1", real=True)
        self.mark(j, ja)
        return Dyad("rrs", j, (b1,),
                    {"P": list(P), "Q": [B[0], B[1]], "l": [sp.sqrt(v1[0] ** 2 + v1[1] ** 2), reach]},
                    [(self.coord_of[b1], _angle(Jx - Px, Jy - Py) - _angle(*v1))],
                    [(self.coord_of[b1], *_rotation_between(v1, (Jx - Px, Jy - Py)))],
                    f"+1: pin {j.b.body.name} of rod {j.name} left of the line from {ja.name} to the crank pin's "
                    "projection (seed 003 eq. 1: δ₁)")

    def rpr(self, s, bar, ja, jb) -> Dyad:
        kin = self.kin
        P, Q = kin.world(_other(ja, bar)), kin.world(_other(jb, s))
        a = _mine(ja, bar)
        g = s.guide
        pin = _mine(jb, s)
        pu, pv = rot(g.angle, pin.u, pin.v)
        ssym, tsym = sp.symbols("s theta", real=True)
        D = sp.symbols("D_0 D_1", real=True)
        w = [sp.Symbol(f"w0_{k}", real=True) + ssym * sp.Symbol(f"u_{k}", real=True) for k in range(2)]
        self.mark(ja, jb)
        return Dyad("rpr", jb, (s, bar),
                    {"D": [Q[0] - P[0], Q[1] - P[1]], "w0": [g.u - a.u + pu, g.v - a.v + pv],
                     "u": [sp.cos(g.angle), sp.sin(g.angle)]},
                    [(self.coord_of[s], ssym), (self.coord_of[bar], tsym)],
                    [(self.coord_of[bar], *_rotation_between(w, D))],
                    f"+1: the larger travel of {s.name} on {bar.name}")


def split_into_dyads(kin: Kinematics) -> list[Dyad] | None:
    """The dyads that solve the mechanism in order, or None when its loops do not split so."""
    return _Split(kin).solve()

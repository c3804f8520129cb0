"""Adversarial campaigns against an independent high-precision reference (``python tools/fuzz.py``).

Every case is one sweep of one design, drawn at random or aimed at a place where float64 loses digits: a
four-bar touching its extended or folded toggle (a change point: the crank passes, the triangle flattens and
opens again), a dead centre approached from the side that assembles, a crank-slider's rod at right angles to its
guide, an oscillating guide whose slider pin passes micrometres to nanometres from the guide's pivot, a
Stephenson six-bar's second dyad at its toggle. The mechanisms: the catalog's needle bar, take-up, hook drive,
feed and the overlock's six mechanisms (with its planar and spatial cranks), and user mechanisms compiled once
and varied through ``params``: four-bars, crank-sliders, Stephenson six-bars, a spatial crank-rocker, a four-bar
with a spring and a relative drive. Each is swept at random shaft angles (a revolution, a few coarse angles, a
shuffled or repeated set, a cluster at the aimed angle), speed and shaft acceleration, on a random branch, by
the closed form where there is one and by Newton.

The reference is mpmath at 40 digits, nothing float64 in it:

* the classic families by plain complex-number geometry, dyad by dyad, velocities and accelerations from each
  dyad's exact 2 × 2 solve (nothing shared with the derivation or the C kernels, so a wrong model shows too);
* every mechanism, by its loop-closure equations (the declaration's, as sewgen.derive states them) solved by
  mpmath's Newton from the sweep's own position, velocities and accelerations by mpmath's LU, every observable
  evaluated exactly — a check of the numbers, not of the model (the classic families check that);
* the kinetostatic sweeps by the power balance: the driving power against d(KE + PE)/dt of the reference's
  motion, springs' stored energy included (with Coulomb friction on: not below it);
* the command line (``sewgen kinematics``): a design's CSV against the same reference, or exit status 2 with
  one line on stderr and nothing on stdout.

A result is compared position by position, each quantity relative to that position's own scale: positions to
the design's largest length, velocities to the largest speed of a point (a coordinate's rate times its
lever), accelerations to the largest acceleration or centripetal term. Outcomes, per sweep:

* ``verified``: every position the sweep accepts within WRONG (1e-6) of the reference;
* ``typed <Error>``: a :class:`~sewgen.errors.SewgenError` — for SingularPositionError, positions whose
  estimate (``Motion.error_estimate``, the sweep rerun with ``singular="flag"``) exceeded the tolerance;
  ``unjustified`` where the reference continues the requested branch with every triangle's margin above
  MARGIN (an assembly, convergence or branch error);
* ``silent wrong``: an accepted position off by more than WRONG (``silent flip`` where it is the other
  branch's); ``nan``; ``untyped``: any other exception.

The campaign passes when silent wrong, flips, NaN, untyped and unjustified are all 0 (exit status 1 otherwise).
It also reports how the estimate compares with the error it estimates: ``estimate exceeded`` counts accepted
positions whose error is above their estimate (and above 1e-13), ``overcautious`` refused positions whose error
is below a hundredth of the tolerance. The suite runs a short campaign (tests/test_property_adversarial.py).
"""
from __future__ import annotations

import argparse
import collections
import contextlib
import csv
import io
import math
import os
import sys
import tempfile
import time
from dataclasses import dataclass, field

import mpmath as mp
import numpy as np

MM = 1e-3
DPS = 40  # the reference's digits
MARGIN = 1e-3  # a toggle margin above this: the requested branch continues, no PositionError is justified
WRONG = 1e-6  # an accepted result off by more than this (relative to its position's scale) is wrong
EXCEEDED_FLOOR = 1e-13  # errors below this are rounding, whatever the estimate says
G = 9.80665


# -- exact complex kinematics (mpmath): z (position), v, a at one shaft angle ------------------------------------

@dataclass
class Pt:
    z: object
    v: object
    a: object


def _f(x) -> mp.mpf:
    """The double x exactly."""
    return mp.mpf(float(x))


def _fixed(z) -> Pt:
    return Pt(mp.mpc(_f(complex(z).real), _f(complex(z).imag)), mp.mpc(0), mp.mpc(0))


def _cross(a, b):
    return (mp.conj(a) * b).imag


def _solve2(A, B, C):
    """x, y with x A - y B = C (complex numbers as 2-vectors): Cramer's rule (infinite where A, B are parallel: an
    exact toggle, whose rates no sweep may report)."""
    det = _cross(A, B)
    if det == 0:
        return mp.inf, mp.inf
    return _cross(C, B) / det, -_cross(A, C) / det


def _on(p: Pt, w, omega, alpha) -> Pt:
    """The point p + w of a body turning at omega, alpha (w the world offset, already rotated)."""
    return Pt(p.z + w, p.v + 1j * omega * w, p.a + 1j * alpha * w - omega ** 2 * w)


def _crank(r, phi, w, al, phase=0.0) -> Pt:
    return _on(_fixed(0), _f(r) * mp.expj(_f(phi) + _f(phase)), _f(w), _f(al))


def rrr(P: Pt, Q: Pt, l1, l2, sigma):
    """Joint J at l1 from P and l2 from Q, left of P->Q for sigma = +1: (J, omega1, alpha1, omega2, alpha2,
    margin), margin = the sine of the angle at J (0 at a toggle); None where the triangle does not close."""
    l1, l2 = _f(l1), _f(l2)
    d = Q.z - P.z
    d2 = abs(d) ** 2
    a = (l1 ** 2 - l2 ** 2 + d2) / (2 * d2)
    h2 = l1 ** 2 / d2 - a ** 2
    if h2 < 0:
        return None
    J = P.z + a * d + sigma * 1j * mp.sqrt(h2) * d
    u1, u2 = J - P.z, J - Q.z
    w1, w2 = _solve2(1j * u1, 1j * u2, Q.v - P.v)
    al1, al2 = _solve2(1j * u1, 1j * u2, Q.a - P.a - w2 ** 2 * u2 + w1 ** 2 * u1)
    margin = abs(_cross(u1, u2)) / (abs(u1) * abs(u2))
    return Pt(J, P.v + 1j * w1 * u1, P.a + 1j * al1 * u1 - w1 ** 2 * u1), w1, al1, w2, al2, margin


def rrp(P: Pt, l, G0, u, sigma):
    """Pin J on the fixed line G0 + s u (|u| = 1) at l from P; sigma = +1 the larger s: (J, s, s', s'', omega,
    alpha, margin) or None."""
    l = _f(l)
    w = G0 - P.z
    b = (mp.conj(u) * w).real
    disc = b ** 2 - (abs(w) ** 2 - l ** 2)
    if disc < 0:
        return None
    s = -b + sigma * mp.sqrt(disc)
    J = G0 + s * u
    rel = J - P.z
    sd, om = _solve2(u, 1j * rel, P.v)
    sdd, al = _solve2(u, 1j * rel, P.a - om ** 2 * rel)
    return Pt(J, sd * u, sdd * u), s, sd, sdd, om, al, mp.sqrt(disc) / l


def _angle_coord(vec, omega, alpha, lever):
    return (mp.arg(vec), omega, alpha, _f(lever))


# -- the classic families' references: one position, exact ---------------------------------------------------------

@dataclass
class Ref:
    """A reference position: points (name -> Pt), coordinates (name -> (value, rate, acceleration, lever: what
    turns a rate into a speed; 1 for a travel)), the margin of its closest triangle."""

    points: dict
    coords: dict
    margin: object


def needle_reference(p, br, phi, w, al):
    B = _crank(p["crank"], phi, w, al, p.get("crank.phase", 0.0))
    res = rrp(B, p["rod"], mp.mpc(_f(p["offset"]), 0), mp.mpc(0, 1), br["C"])
    if res is None:
        return None
    C, s, sd, sdd, om, oal, margin = res
    eye = Pt(C.z - 1j * _f(p["eye_below_pin"]), C.v, C.a)
    tip = Pt(C.z - 1j * (_f(p["eye_below_pin"]) + _f(p["point_below_eye"])), C.v, C.a)
    return Ref({"crank_pin": B, "link_pin": C, "needle_eye": eye, "needle_point": tip},
               {"needle_bar.travel": (s, sd, sdd, mp.mpf(1)), "rod.angle": _angle_coord(C.z - B.z, om, oal, p["rod"])},
               margin)


def take_up_reference(p, br, phi, w, al):
    B = _crank(p["crank"], phi, w, al, p.get("crank.phase", 0.0))
    D = _fixed(complex(p["rocker_pivot_x"], p["rocker_pivot_y"]))
    res = rrr(B, D, p["lever_bc"], p["rocker"], br["C"])
    if res is None:
        return None
    C, w1, a1, w2, a2, margin = res
    bc, be, ce = _f(p["lever_bc"]), _f(p["lever_be"]), _f(p["lever_ce"])
    eu = (bc ** 2 + be ** 2 - ce ** 2) / (2 * bc)
    ev = mp.sqrt(max(be ** 2 - eu ** 2, 0))
    E = _on(B, (C.z - B.z) / bc * mp.mpc(eu, ev), w1, a1)
    return Ref({"crank_pin": B, "rocker_pin": C, "thread_eye": E},
               {"lever.angle": _angle_coord(C.z - B.z, w1, a1, p["lever_bc"]),
                "rocker.angle": _angle_coord(C.z - D.z, w2, a2, p["rocker"])}, margin)


def hook_reference(p, br, phi, w, al):
    B = _crank(p["crank"], phi, w, al, p.get("crank.phase", 0.0))
    O4 = _fixed(complex(p["rock_axis_x"], p["rock_axis_y"]))
    res = rrr(B, O4, p["big_rod"], p["rock_front_arm"], br["C"])
    if res is None:
        return None
    C, w1, a1, wr, ar, m1 = res
    E = _on(O4, (C.z - O4.z) / _f(p["rock_front_arm"]) * _f(p["rock_rear_arm"]) * mp.expj(_f(p["rock_rear_angle"])),
            wr, ar)
    O11 = _fixed(complex(p["lower_axis_x"], p["lower_axis_y"]))
    d = E.z - O11.z
    rho = abs(d)
    if rho == 0:
        return None
    e = d / rho
    rd = (mp.conj(e) * E.v).real
    psd = (mp.conj(e) * E.v).imag / rho
    rdd = (mp.conj(e) * E.a).real + rho * psd ** 2
    psdd = ((mp.conj(e) * E.a).imag - 2 * rd * psd) / rho
    sg = br["E"]
    psi = mp.arg(d) + (0 if sg > 0 else mp.pi)
    hook = _on(O11, _f(p["hook_radius"]) * mp.expj(psi + _f(p["hook_angle"])), psd, psdd)
    return Ref({"crank_pin": B, "rock_pin": C, "slider_pin": E, "hook_point": hook},
               {"rock_slider.travel": (sg * rho, sg * rd, sg * rdd, mp.mpf(1)),
                "lower_shaft.angle": (psi, psd, psdd, _f(p["hook_radius"])),
                "rock_shaft.angle": _angle_coord(C.z - O4.z, wr, ar, p["rock_front_arm"]),
                "big_rod.angle": _angle_coord(C.z - B.z, w1, a1, p["big_rod"])},
               min(m1, rho / _f(p["rock_rear_arm"])))


def four_bar_reference(p, br, phi, w, al):
    B = _crank(p["crank"], phi, w, al)
    D = _fixed(complex(p["ground_x"], p["ground_y"]))
    res = rrr(B, D, p["coupler"], p["rocker"], br["C"])
    if res is None:
        return None
    C, w1, a1, w2, a2, margin = res
    P = _on(B, (C.z - B.z) / _f(p["coupler"]) * mp.mpc(_f(p["point_u"]), _f(p["point_v"])), w1, a1)
    return Ref({"crank_pin": B, "coupler_pin": C, "coupler_point": P},
               {"coupler.angle": _angle_coord(C.z - B.z, w1, a1, p["coupler"]),
                "rocker.angle": _angle_coord(C.z - D.z, w2, a2, p["rocker"])}, margin)


def slider_reference(p, br, phi, w, al):
    B = _crank(p["crank"], phi, w, al)
    res = rrp(B, p["rod"], mp.mpc(_f(p["guide_x"]), _f(p["guide_y"])), mp.expj(_f(p["guide_angle"])), br["C"])
    if res is None:
        return None
    C, s, sd, sdd, om, oal, margin = res
    return Ref({"crank_pin": B, "block_pin": C},
               {"block.travel": (s, sd, sdd, mp.mpf(1)), "rod.angle": _angle_coord(C.z - B.z, om, oal, p["rod"])},
               margin)


def six_bar_reference(p, br, phi, w, al):
    four = four_bar_reference(p, br, phi, w, al)
    if four is None:
        return None
    E = four.points["coupler_point"]
    F = _fixed(complex(p["pivot_fx"], p["pivot_fy"]))
    res = rrr(E, F, p["link5"], p["link6"], br["G"])
    if res is None:
        return None
    Gp, w5, a5, w6, a6, m2 = res
    coords = dict(four.coords)
    coords["link5.angle"] = _angle_coord(Gp.z - E.z, w5, a5, p["link5"])
    coords["link6.angle"] = _angle_coord(Gp.z - F.z, w6, a6, p["link6"])
    return Ref({**four.points, "pin_g": Gp}, coords, min(four.margin, m2))


# -- every mechanism: its loop-closure equations solved by mpmath ---------------------------------------------------

class SymbolicReference:
    """A mechanism's kinematics from its declaration's equations (sewgen.derive.kinematics: Φ, Φ_q, Φ_x, γ and
    every observable as SymPy expressions) evaluated by mpmath: the position by Newton's method from the sweep's
    own position (so it checks accuracy, not the branch), q' and q'' by an exact LU, the observables exactly. The
    power balance reads the bodies' masses, centres of mass and inertias and the springs' geometry from it too."""

    def __init__(self, mechanism, declare):
        import sympy as sp

        from sewgen.derive.kinematics import Kinematics

        decl = declare()
        kin = Kinematics(decl)
        self.mechanism, self.kin = mechanism, kin
        self.param_names = [prm.name for prm in decl.params]
        self.nq, self.nx = len(kin.q), len(kin.x)
        args = kin.q + kin.x + kin.qd + kin.xd + kin.qdd + kin.xdd + kin.p
        fn = lambda exprs: sp.lambdify(args, exprs, "mpmath")  # noqa: E731
        self._phi = fn(list(kin.closure))
        self._jq = fn(kin.jac_q.tolist())
        self._rhs = fn(list(kin.vel_rhs))
        self._gamma = fn(list(kin.gamma))
        self.obs_names = [o.name for o in kin.observables]
        self._obs = fn([o.expr for o in kin.observables])
        if self.obs_names != [o["name"] for o in mechanism.manifest["observables"]]:
            raise RuntimeError(f"{mechanism.name}: the declaration's observables are not the compiled ones")
        self.angle_coord = [c.kind == "angle" for c in kin.coords]
        self.springs = []
        for el in decl.elements:
            if el.kind == "spring":
                ends = [kin.world(el.a), kin.world(el.b)]
                exprs = [e for pt in ends for e in pt] + [kin.dt(e) for pt in ends for e in pt]
                exprs += [el.values["stiffness"], el.values["free_length"], el.values["preload"]]
                self.springs.append(fn(exprs))
        self.bodies = [b.name for b in decl.bodies if b.moving]

    def solve(self, p: dict, q0, x, xd, xdd):
        """(q, q', q'', observables) at inputs x, x', x'' (lists, exact) from the float position q0, or None where
        Newton does not converge or Φ_q is singular."""
        pv = [_f(p[n]) for n in self.param_names]
        x, xd, xdd = [_f(v) for v in x], [_f(v) for v in xd], [_f(v) for v in xdd]
        q = [_f(v) for v in q0]
        zero = [mp.mpf(0)] * self.nq
        for _ in range(60):
            args = q + x + zero + xd + zero + xdd + pv
            r = mp.matrix(self._phi(*args))
            J = mp.matrix(self._jq(*args))
            try:
                dq = mp.lu_solve(J, r)
            except ZeroDivisionError:
                return None
            q = [qi - dqi for qi, dqi in zip(q, dq)]
            if mp.norm(dq, mp.inf) < mp.mpf(10) ** (-DPS + 6):
                break
        else:
            return None
        args = q + x + zero + xd + zero + xdd + pv
        J = mp.matrix(self._jq(*args))
        try:
            qd = list(mp.lu_solve(J, mp.matrix(self._rhs(*args))))
            args = q + x + qd + xd + zero + xdd + pv
            qdd = list(mp.lu_solve(J, mp.matrix(self._gamma(*args))))
        except ZeroDivisionError:
            return None
        args = q + x + qd + xd + qdd + xdd + pv
        return q, qd, qdd, list(self._obs(*args)), args

    def spring_power(self, args) -> tuple:
        """Σ tension · dL/dt of the springs (W) and its scale (Σ |.|)."""
        total = scale = mp.mpf(0)
        for f in self.springs:
            ax, ay, bx, by, vax, vay, vbx, vby, k, free, pre = f(*args)
            L = mp.sqrt((bx - ax) ** 2 + (by - ay) ** 2)
            rate = ((bx - ax) * (vbx - vax) + (by - ay) * (vby - vay)) / L
            tension = pre + k * (L - free)
            total += tension * rate
            scale += abs(tension * rate)
        return total, scale


# -- families: a mechanism, its designs, its reference ----------------------------------------------------------------

@dataclass
class Family:
    """A mechanism, how to draw a design of it (random, or aimed at a toggle), and its reference."""

    name: str
    mechanism: object
    draw: object  # rng -> Design
    reference: object = None  # classic: (params, branch, phi, omega, alpha) -> Ref or None
    symbolic: SymbolicReference | None = None
    closed_form: bool = True
    held: bool = False  # the feed: its "branch" is its held inputs, its reference its own continuation
    forces: bool = False  # a kinetostatic case (power balance) is drawn as well


@dataclass
class Design:
    params: dict
    branch: dict
    phi: np.ndarray | None = None  # angles chosen with the design (aimed at a toggle); else drawn
    held: dict = field(default_factory=dict)
    aim: str = "random"


# -- user mechanisms the campaign compiles once ---------------------------------------------------------------------

def declare_four_bar():
    from sewgen.derive.model import Mechanism as Declaration

    m = Declaration("fuzz_four_bar", "A four-bar with a coupler point (fuzz).")
    r, l2, l3 = m.length("crank", "10 mm", "AB"), m.length("coupler", "40 mm", "BC"), m.length("rocker", "30 mm", "DC")
    gx, gy = m.length("ground_x", "35 mm", "D x", signed=True), m.length("ground_y", "5 mm", "D y", signed=True)
    pu, pv = m.length("point_u", "20 mm", "P u", signed=True), m.length("point_v", "10 mm", "P v", signed=True)
    crank = m.driven("crank", pivot=m.ground.at(0, 0))
    coupler, rocker = m.link("coupler", guess="60 deg"), m.link("rocker", guess="100 deg")
    m.revolute(crank.at(r, 0), coupler.at(0, 0), name="B")
    m.revolute(m.ground.at(gx, gy), rocker.at(0, 0), name="D")
    m.revolute(coupler.at(l2, 0), rocker.at(l3, 0), name="C", branch=1)
    m.point("crank_pin", crank.at(r, 0))
    m.point("coupler_pin", rocker.at(l3, 0))
    m.point("coupler_point", coupler.at(pu, pv))
    return m


def declare_slider():
    from sewgen.derive.model import Mechanism as Declaration

    m = Declaration("fuzz_crank_slider", "A crank-slider on an inclined guide (fuzz).")
    r, l = m.length("crank", "12 mm", "AB"), m.length("rod", "45 mm", "BC")
    gx, gy = m.length("guide_x", "0 mm", "guide x", signed=True), m.length("guide_y", "3 mm", "guide y", signed=True)
    ga = m.angle("guide_angle", "10 deg", "guide direction")
    crank = m.driven("crank", pivot=m.ground.at(0, 0))
    rod = m.link("rod", guess="0 deg")
    block = m.slider("block", guide=m.ground.line(at=(gx, gy), angle=ga), guess="50 mm")
    m.revolute(crank.at(r, 0), rod.at(0, 0), name="B")
    m.revolute(rod.at(l, 0), block.at(0, 0), name="C", branch=1)
    m.point("crank_pin", crank.at(r, 0))
    m.point("block_pin", block.at(0, 0))
    return m


def declare_six_bar():
    from sewgen.derive.model import Mechanism as Declaration

    m = Declaration("fuzz_six_bar", "A Stephenson six-bar: a four-bar and a dyad on its coupler point (fuzz).")
    r, l2, l3 = m.length("crank", "10 mm", "AB"), m.length("coupler", "40 mm", "BC"), m.length("rocker", "30 mm", "DC")
    gx, gy = m.length("ground_x", "35 mm", "D x", signed=True), m.length("ground_y", "5 mm", "D y", signed=True)
    pu, pv = m.length("point_u", "20 mm", "E u", signed=True), m.length("point_v", "15 mm", "E v", signed=True)
    l5, l6 = m.length("link5", "45 mm", "EG"), m.length("link6", "40 mm", "FG")
    fx, fy = m.length("pivot_fx", "10 mm", "F x", signed=True), m.length("pivot_fy", "60 mm", "F y", signed=True)
    crank = m.driven("crank", pivot=m.ground.at(0, 0))
    coupler, rocker = m.link("coupler", guess="60 deg"), m.link("rocker", guess="100 deg")
    link5, link6 = m.link("link5", guess="0 deg"), m.link("link6", guess="-90 deg")
    m.revolute(crank.at(r, 0), coupler.at(0, 0), name="B")
    m.revolute(m.ground.at(gx, gy), rocker.at(0, 0), name="D")
    m.revolute(coupler.at(l2, 0), rocker.at(l3, 0), name="C", branch=1)
    m.revolute(coupler.at(pu, pv), link5.at(0, 0), name="E")
    m.revolute(m.ground.at(fx, fy), link6.at(0, 0), name="F")
    m.revolute(link5.at(l5, 0), link6.at(l6, 0), name="G", branch=1)
    m.point("crank_pin", crank.at(r, 0))
    m.point("coupler_pin", rocker.at(l3, 0))
    m.point("coupler_point", coupler.at(pu, pv))
    m.point("pin_g", link6.at(l6, 0))
    return m


def declare_spatial():
    """Seed 003's spatial crank-rocker (RSSR): a crank on a skew axis drives a rocker through a ball-jointed rod."""
    from sewgen.derive.model import Mechanism as Declaration

    m = Declaration("fuzz_rssr", "A spatial crank-rocker on a skew axis (fuzz).")
    crank = m.spatial_crank("crank", ("50 mm", "20 mm", "-30 mm"), (0, 1, 1), inertia="2e-6 kg*m**2")
    rocker = m.link("rocker", guess="60 deg", mass="25 g", com=("12 mm", "0 mm"), inertia="4e-6 kg*m**2")
    arm = m.length("arm", "30 mm", "rocker arm DC")
    m.revolute(m.ground.at(0, 0), rocker.at(0, 0), "D")
    m.rod(crank.pin("8 mm"), rocker.at(arm, 0), "60 mm", "rod", branch=1)
    m.point("C", rocker.at(arm, 0))
    return m


def declare_spring_drive():
    """A four-bar with masses, a spring from the frame to the coupler and a flywheel driven at twice the shaft's
    speed on the rocker (a relative drive): the power balance's springs and actuators."""
    from sewgen.derive.model import Mechanism as Declaration

    m = Declaration("fuzz_spring_drive", "A four-bar with a spring and a relative drive (fuzz).")
    r, l2, l3 = m.length("crank", "10 mm", "AB"), m.length("coupler", "40 mm", "BC"), m.length("rocker", "30 mm", "DC")
    gx, gy = m.length("ground_x", "35 mm", "D x", signed=True), m.length("ground_y", "5 mm", "D y", signed=True)
    crank = m.driven("crank", pivot=m.ground.at(0, 0), mass="20 g", com=("3 mm", "1 mm"), inertia="2e-6 kg*m**2")
    coupler = m.link("coupler", guess="60 deg", mass="30 g", com=("20 mm", "4 mm"), inertia="5e-6 kg*m**2")
    rocker = m.link("rocker", guess="100 deg", mass="25 g", com=("15 mm", "-2 mm"), inertia="3e-6 kg*m**2")
    m.driven("flywheel", pivot=rocker.at(l3 / 2, 0), ratio=2, mass="15 g", com=("2 mm", "0 mm"),
             inertia="1.5e-6 kg*m**2")
    m.revolute(crank.at(r, 0), coupler.at(0, 0), name="B")
    m.revolute(m.ground.at(gx, gy), rocker.at(0, 0), name="D")
    m.revolute(coupler.at(l2, 0), rocker.at(l3, 0), name="C", branch=1)
    m.spring(m.ground.at("0 mm", "40 mm"), coupler.at("25 mm", "0 mm"), "0.8 N/mm", "35 mm", "2 N", name="spring")
    m.friction("B", "0", "3 mm")
    m.friction("C", "0", "2 mm")
    m.point("coupler_pin", rocker.at(l3, 0))
    return m


# -- designs: random, and aimed at toggles ----------------------------------------------------------------------------

def _sign(rng) -> int:
    return int(rng.choice([1, -1]))


def _scaled(rng, base: dict, keys, spread=0.5) -> dict:
    out = dict(base)
    for k in keys:
        out[k] = base[k] * float(np.exp(rng.uniform(-spread, spread)))
    return out


def _signed(rng, base: dict, keys, span) -> dict:
    out = dict(base)
    for k in keys:
        out[k] = base[k] + float(rng.uniform(-span, span))
    return out


def _cluster(rng, at: float, side: int = 0) -> np.ndarray:
    """A few shaft angles within 1e-9 to 0.3 rad of ``at`` (on one side where ``side`` is ±1), sometimes at it."""
    n = int(rng.integers(2, 9))
    offs = 10.0 ** rng.uniform(-9, -0.5, n) * (side if side else rng.choice([1, -1], n))
    phi = at + offs
    if rng.random() < 0.3:
        phi = np.append(phi, at)
    return rng.permutation(phi) if rng.random() < 0.5 else np.sort(phi)


def _aim_rrr(rng, r, pivot: complex, l1: float, phase=0.0):
    """A toggle of the dyad of a crank pin (radius r) and a fixed pivot: (the second link's length, the angle, the
    side that assembles). A change point where the crank pin is farthest from or nearest to the pivot (the
    distance's extremum: the triangle flattens and opens again), else a dead centre at a random angle."""
    e = abs(pivot)
    toward = math.atan2(pivot.imag, pivot.real) - phase
    kind = rng.integers(3)
    if kind == 0 and r + e > l1:  # extended, at the farthest
        return r + e - l1, toward + math.pi, 0
    if kind == 1 and abs(e - r) < l1:  # folded, at the nearest
        return l1 - abs(e - r), toward, 0
    phi = float(rng.uniform(0, 2 * math.pi))
    d = abs(r * complex(math.cos(phi + phase), math.sin(phi + phase)) - pivot)
    grows = math.sin(phi + phase - toward) > 0  # d' > 0 past phi: the extended triangle opens below phi
    if d > l1:
        return d - l1, phi, -1 if grows else 1
    return l1 + d, phi, -1 if grows else 1  # never shorter than the distance: l2 - l1 = d, folded


def families(cache_dir=None) -> list[Family]:
    """Every family of the campaign (see the module docstring)."""
    import sewgen

    from sewgen.derive import catalog

    nb, tu, hd, fd = (sewgen.mechanism(n) for n in ("needle_bar", "take_up", "hook_drive", "feed"))
    fb = sewgen.load(declare_four_bar, cache_dir=cache_dir)
    cs = sewgen.load(declare_slider, cache_dir=cache_dir)
    sb = sewgen.load(declare_six_bar, cache_dir=cache_dir)
    rs = sewgen.load(declare_spatial, cache_dir=cache_dir)
    sd = sewgen.load(declare_spring_drive, cache_dir=cache_dir)

    def d_needle(rng):
        p = _scaled(rng, nb.defaults(), ["crank", "rod", "eye_below_pin"], 0.6)
        p = _signed(rng, p, ["offset"], 25 * MM)
        br = {"C": _sign(rng)}
        if rng.random() < 0.5:  # the rod at right angles to the guide: the crank pin farthest from it
            reach = p["crank"] + abs(p["offset"])
            toward = 0.0 if p["offset"] >= 0 else math.pi
            if rng.random() < 0.5:
                p["rod"] = reach
                return Design(p, br, _cluster(rng, math.pi - toward), aim="toggle")
            phi = float(rng.uniform(0, 2 * math.pi))
            p["rod"] = abs(p["crank"] * math.cos(phi) - p["offset"])
            if p["rod"] > 1e-4:
                return Design(p, br, _cluster(rng, phi), aim="dead centre")
        return Design(p, br)

    def d_take_up(rng):
        p = _scaled(rng, tu.defaults(), ["crank", "lever_bc", "rocker", "lever_be", "lever_ce"], 0.35)
        p = _signed(rng, p, ["rocker_pivot_x", "rocker_pivot_y"], 10 * MM)
        p["lever_be"] = max(p["lever_be"], abs(p["lever_bc"] - p["lever_ce"]) * 1.001)  # a triangle BCE
        p["lever_be"] = min(p["lever_be"], (p["lever_bc"] + p["lever_ce"]) * 0.999)
        br = {"C": _sign(rng)}
        if rng.random() < 0.5:
            l2, at, side = _aim_rrr(rng, p["crank"], complex(p["rocker_pivot_x"], p["rocker_pivot_y"]),
                                    p["lever_bc"], p.get("crank.phase", 0.0))
            p["rocker"] = l2
            return Design(p, br, _cluster(rng, at, side), aim="toggle")
        return Design(p, br)

    def d_hook(rng):
        p = _scaled(rng, hd.defaults(), ["crank", "big_rod", "rock_front_arm", "rock_rear_arm"], 0.3)
        p = _signed(rng, p, ["rock_axis_x", "lower_axis_x"], 10 * MM)
        p["rock_axis_y"] = -p["big_rod"] * float(rng.uniform(0.96, 1.03))
        p["lower_axis_y"] = p["rock_axis_y"] - float(rng.uniform(0.0, 1.3)) * p["rock_rear_arm"]
        p["rock_rear_angle"] = float(rng.uniform(-math.pi, math.pi)) if rng.random() < 0.3 else \
            -math.pi / 2 + float(rng.uniform(-1.0, 1.0))
        br = {"C": _sign(rng), "E": _sign(rng)}
        if rng.random() < 0.5:  # the slider pin passing a micrometre to a nanometre from the guide's pivot
            at = float(rng.uniform(0, 2 * math.pi))
            ref = hook_reference(p, br, at, 1.0, 0.0)
            if ref is not None:
                E = ref.points["slider_pin"]
                n = 1j * E.v / abs(E.v) if abs(E.v) > 0 else mp.mpc(1)
                O = E.z + _f(10.0 ** rng.uniform(-9.5, -3.5)) * n * _sign(rng)
                p["lower_axis_x"], p["lower_axis_y"] = float(O.real), float(O.imag)
                return Design(p, br, _cluster(rng, at), aim="guide pivot")
        return Design(p, br)

    def d_four_bar(rng):
        p = {k: float(rng.uniform(0.5, 80)) * MM for k in ("coupler", "rocker")}
        p["crank"] = float(rng.uniform(0.5, 25)) * MM
        p.update({k: float(rng.uniform(-60, 60)) * MM for k in ("ground_x", "ground_y", "point_u", "point_v")})
        br = {"C": _sign(rng)}
        if rng.random() < 0.5:
            l2, at, side = _aim_rrr(rng, p["crank"], complex(p["ground_x"], p["ground_y"]), p["coupler"])
            if l2 > 1e-4:
                p["rocker"] = l2
                return Design(p, br, _cluster(rng, at, side), aim="toggle")
        return Design(p, br)

    def d_slider(rng):
        p = {"crank": float(rng.uniform(0.5, 30)) * MM, "rod": float(rng.uniform(0.5, 90)) * MM,
             "guide_x": float(rng.uniform(-30, 30)) * MM, "guide_y": float(rng.uniform(-30, 30)) * MM,
             "guide_angle": float(rng.uniform(-math.pi, math.pi))}
        br = {"C": _sign(rng)}
        if rng.random() < 0.5:  # the rod at right angles to the guide
            u = complex(math.cos(p["guide_angle"]), math.sin(p["guide_angle"]))
            g0 = complex(p["guide_x"], p["guide_y"])
            h0 = ((-g0) / u).imag  # the crank axis' distance from the guide, signed
            at = math.atan2((u * 1j * math.copysign(1, h0)).imag, (u * 1j * math.copysign(1, h0)).real)
            if rng.random() < 0.5:
                p["rod"] = p["crank"] + abs(h0)
            else:
                at = float(rng.uniform(0, 2 * math.pi))
                p["rod"] = abs(((p["crank"] * complex(math.cos(at), math.sin(at)) - g0) / u).imag)
            if p["rod"] > 1e-4:
                return Design(p, br, _cluster(rng, at), aim="toggle")
        return Design(p, br)

    def d_six_bar(rng):
        d = d_four_bar(rng)
        p, br = d.params, {"C": d.branch["C"], "G": _sign(rng)}
        p.update({"link5": float(rng.uniform(5, 90)) * MM, "link6": float(rng.uniform(5, 90)) * MM,
                  "pivot_fx": float(rng.uniform(-60, 60)) * MM, "pivot_fy": float(rng.uniform(-60, 60)) * MM})
        if d.phi is None and rng.random() < 0.5:  # the second dyad at its toggle at a random angle
            at = float(rng.uniform(0, 2 * math.pi))
            ref = four_bar_reference(p, br, at, 1.0, 0.0)
            if ref is not None:
                dist = float(abs(ref.points["coupler_point"].z - mp.mpc(p["pivot_fx"], p["pivot_fy"])))
                p["link6"] = dist + p["link5"] if rng.random() < 0.5 else abs(dist - p["link5"])
                if p["link6"] > 1e-4:
                    return Design(p, br, _cluster(rng, at), aim="toggle")
        return Design(p, br, d.phi, aim=d.aim)

    def d_feed(rng):
        """Lengths and pivots varied, the long links sized to the varied pivots (a strap 15 % off its pivot
        distance cannot close: that is no design)."""
        p = _scaled(rng, fd.defaults(), ["cam_side", "cam_small_radius", "fork_q", "feed_arm_p", "feed_arm_r",
                                         "lift_arm", "lift_cam_eccentricity", "dog_u"], 0.2)
        p = _signed(rng, p, ["feed_shaft_x", "feed_shaft_y", "lift_shaft_x", "lift_shaft_y"], 8 * MM)
        p["lift_cam_angle"] += float(rng.uniform(-0.2, 0.2))
        p["lift_fork_angle"] += float(rng.uniform(-0.2, 0.2))
        p = _signed(rng, p, ["regulator_x"], 3 * MM)
        p["regulator_y"] = -p["fork_q"] + float(rng.uniform(-1.5, 1.5)) * MM  # the stitch pin near the slot
        wobble = (lambda: 1 + float(rng.uniform(-0.01, 0.01)))  # noqa: E731
        of = complex(p["feed_shaft_x"], p["feed_shaft_y"])
        ol = complex(p["lift_shaft_x"], p["lift_shaft_y"])
        p["fork_p"] = abs(of + p["feed_arm_p"]) * wobble()
        p["bar_slot_v"] = max((of + 1j * p["feed_arm_r"]).imag - (ol - p["lift_arm"]).imag, 0.5 * MM) * wobble()
        return Design(p, {}, held={"regulator": float(rng.uniform(-math.radians(50), math.radians(50)))})

    def varied(mech, spread=0.15, keep=()):
        """Random designs near a mechanism's defaults: positive lengths scaled by up to ±spread, signed ones moved
        by up to 2 % of the largest length, every branch sign and held input drawn."""
        desc = mech.description

        def draw(rng):
            p = dict(mech.defaults())
            big = max(abs(v) for prm, v in zip(desc.params, p.values()) if prm.kind == "length") or 1.0
            for prm in desc.params:
                if prm.kind != "length" or prm.name in keep or "." in prm.name:
                    continue
                if prm.positive:
                    p[prm.name] *= float(np.exp(rng.uniform(-spread, spread)))
                else:
                    p[prm.name] += float(rng.uniform(-0.02, 0.02)) * big
            br = {b: _sign(rng) if rng.random() < 0.3 else d for b, d in zip(mech.branch_names, (
                br.default for br in desc.branches))}
            held = {h.name: h.default + float(rng.uniform(-0.1, 0.1)) * (abs(h.default) or 1.0)
                    for h in desc.held_inputs}
            return Design(p, br, held=held)
        return draw

    def catalog_reference(name):
        return SymbolicReference(sewgen.mechanism(name), lambda: catalog.declare(name))

    symbolic = {name: catalog_reference(name) for name in ("needle_bar", "take_up", "hook_drive")}
    out = [Family("needle_bar", nb, d_needle, needle_reference, symbolic["needle_bar"], forces=True),
           Family("take_up", tu, d_take_up, take_up_reference, symbolic["take_up"], forces=True),
           Family("hook_drive", hd, d_hook, hook_reference, symbolic["hook_drive"], forces=True),
           Family("four_bar", fb, d_four_bar, four_bar_reference),
           Family("crank_slider", cs, d_slider, slider_reference),
           Family("six_bar", sb, d_six_bar, six_bar_reference),
           Family("feed", fd, d_feed, feed_reference, closed_form=False, held=True)]
    for name in ("overlock_feed", "overlock_knife", "overlock_loopers", "overlock_loopers_planar", "overlock_needle",
                 "overlock_needle_planar"):
        m = sewgen.mechanism(name)
        out.append(Family(name, m, varied(m), symbolic=catalog_reference(name), forces=True))
    out.append(Family("spatial_crank", rs, varied(rs, 0.1), symbolic=SymbolicReference(rs, declare_spatial),
                      forces=True))
    out.append(Family("spring_drive", sd, varied(sd, 0.2), symbolic=SymbolicReference(sd, declare_spring_drive),
                      forces=True))
    return out


# -- the feed: an independent solution (no closed form: a cam, a slot and a coupled fork loop) -----------------

def _feed_arcs(side, r0):
    """The constant-breadth cam's six arcs in its frame: (centre, radius, normal sector start) each, sectors 60°
    wide (sewgen.derive.model.constant_breadth_arcs, rewritten here)."""
    cen = complex(0.0, -side / math.sqrt(3))
    arcs = []
    for i in range(3):
        a = math.pi / 2 + 2 * math.pi * i / 3
        v = cen + side / math.sqrt(3) * complex(math.cos(a), math.sin(a))
        arcs += [(v, r0, a - math.pi / 6), (v, side + r0, a + math.pi - math.pi / 6)]
    return tuple(np.array(col) for col in zip(*arcs))  # centres, radii, sector starts


def _feed_fork(p, arcs, thc, P):
    """Fork angle for the feed rock shaft pin P: its face tangent to the active arc (the one whose normal sector
    holds the face normal), the fork pointing from the cam down to P; (angle, margin)."""
    b = p["cam_side"] + 2 * p["cam_small_radius"]
    c, r, start = arcs
    D = c * complex(math.cos(thc), math.sin(thc)) - P
    ratio = (r - b / 2) / np.abs(D)
    thf = np.angle(D) - math.pi + np.arcsin(np.clip(ratio, -1, 1))
    off = (thf - math.pi / 2 - thc - start) % (2 * math.pi)  # the face normal -i e^{i thf}, in the cam frame
    miss = np.maximum(0.0, np.minimum(off - math.pi / 3, 2 * math.pi - off))  # 0 inside the arc's sector
    k = int(np.argmin(miss))
    return float(thf[k]), float(1 - abs(ratio[k]))


def feed_positions(p, held, phi, start):
    """World points of the feed at shaft angles ``phi`` (sorted), continued from the assembly nearest ``start``
    (the feed rock shaft, lift rock shaft and feed bar angles at phi[0]: the feed has no declared branch, its
    assembly is the one the engine starts on): dict of complex arrays and the margin, or None, None where it
    does not assemble."""
    from scipy.optimize import brentq

    arcs = _feed_arcs(p["cam_side"], p["cam_small_radius"])
    Of, Ol, R0 = (complex(p[k + "_x"], p[k + "_y"]) for k in ("feed_shaft", "lift_shaft", "regulator"))
    ureg = complex(math.cos(held), math.sin(held))
    beta_prev, lift_sign, fork_sign, bar_sign = start[0], None, None, None
    out = {k: np.zeros(len(phi), complex) for k in ("feed_dog", "fork_top", "stitch_pin", "lift_roller")}
    margin = np.zeros(len(phi))

    def g(beta, thc):
        P = Of + p["feed_arm_p"] * complex(math.cos(beta), math.sin(beta))
        thf, m = _feed_fork(p, arcs, thc, P)
        Q = P + (p["fork_q"] - p["fork_p"]) * complex(math.cos(thf), math.sin(thf))
        return ((Q - R0) / ureg).imag, P, thf, Q, m

    for k, ph in enumerate(phi):
        thc = ph + p["feed_cam.phase"]
        f0 = g(beta_prev, thc)[0]
        roots = []
        for step in (0.25, 1.0, 4.0) if k else (1.0,):  # the nearest sign change, widening
            reach = 180.0 if k == 0 else 8 * step
            for sgn in (1, -1):
                a, fa = beta_prev, f0
                for j in range(1, int(reach / step) + 1):
                    b = beta_prev + sgn * math.radians(step * j)
                    fb = g(b, thc)[0]
                    if fa * fb <= 0:
                        roots.append(brentq(lambda t: g(t, thc)[0], min(a, b), max(a, b), xtol=1e-16, rtol=1e-15))
                        break
                    a, fa = b, fb
            if roots:
                break
        if not roots:
            return None, None
        beta = min(roots, key=lambda b: abs(b - beta_prev))
        beta_prev = beta
        _, P, thf, Q, m_fork = g(beta, thc)
        h = 1e-6
        slope = (g(beta + h, thc)[0] - g(beta - h, thc)[0]) / (2 * h) / p["feed_arm_p"]
        # the lift (seed 001's chain): hook crank B, big rod B-C, rock shaft O4-C (a triangle); the lift
        # cam D on the rock shaft runs in the lift crank's fork, a line through O_lift at lift_fork_angle from its
        # roller arm O_lift-L
        B = p["hook_crank"] * np.exp(1j * (ph + p["hook_crank.phase"]))
        O4 = complex(p["rock_axis_x"], p["rock_axis_y"])
        d = O4 - B
        l1, l2 = p["big_rod"], p["rock_front_arm"]
        a = 0.5 * (l1 ** 2 - l2 ** 2 + abs(d) ** 2) / abs(d) ** 2
        h2 = l1 ** 2 / abs(d) ** 2 - a ** 2
        if h2 < 0:
            return None, None
        cands = [B + a * d + sg * 1j * math.sqrt(h2) * d for sg in (1, -1)]
        if lift_sign is None:  # the assembly nearest the guesses at the first position (start[3]: rock shaft)
            lift_sign = min((1, -1), key=lambda sg: abs(_wrap(np.angle(cands[(1 - sg) // 2] - O4) - start[3])))
        C = cands[(1 - lift_sign) // 2]
        m_lift = abs(((C - B).conjugate() * (C - O4)).imag) / (l1 * l2)
        th_r = np.angle(C - O4)
        D = O4 + p["lift_cam_eccentricity"] * np.exp(1j * (th_r + p["lift_cam_angle"]))
        fork = np.angle(D - Ol)  # the fork's line through O_lift passes through D (either way along it)
        cand_l = [fork - p["lift_fork_angle"], fork + math.pi - p["lift_fork_angle"]]
        if fork_sign is None:
            fork_sign = min((0, 1), key=lambda j: abs(_wrap(cand_l[j] - start[1])))
        th_l = cand_l[fork_sign]
        L = Ol + p["lift_arm"] * np.exp(1j * th_l)
        Rb = Of + 1j * p["feed_arm_r"] * np.exp(1j * beta)
        rho, gam = abs(L - Rb), np.angle(L - Rb)
        ratio = p["bar_slot_v"] / rho
        if abs(ratio) > 1:
            return None, None
        cand_b = [gam + math.asin(ratio), gam + math.pi - math.asin(ratio)]
        if bar_sign is None:
            bar_sign = min((0, 1), key=lambda j: abs(_wrap(cand_b[j] - start[2])))
        thb = cand_b[bar_sign]
        out["feed_dog"][k] = Rb + p["dog_u"] * np.exp(1j * thb)
        out["fork_top"][k] = P - p["fork_p"] * np.exp(1j * thf)
        out["stitch_pin"][k] = Q
        out["lift_roller"][k] = L
        margin[k] = min(m_fork, m_lift, 1 - abs(ratio), min(abs(slope), 1.0))
    return out, margin


def _wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


def feed_reference(p, held, phi, w, al, start):
    """Positions at ``phi`` (any order), velocities and accelerations by Richardson-extrapolated differences of
    the continued solution (a cam: acceleration jumps where the active arc changes, so positions within two steps
    of a switch carry no rate reference): (points {name: (z, v, a) arrays}, margin, rates_ok mask, least margin).
    Float64 and differences: the feed's cam has no mpmath reference here; its tolerances are its own."""
    phi = np.asarray(phi, float)
    hs = (4e-3, 2e-3, 1e-3, -1e-3, -2e-3, -4e-3)
    path = np.arange(phi.min(), phi.max(), math.radians(1.0))  # continued along the sorted path, 1° apart
    grid = np.unique(np.concatenate([phi] + [phi + h for h in hs] + [path]))
    pts, margin = feed_positions(p, held, grid, start)
    if pts is None:
        return None
    idx = {v: i for i, v in enumerate(grid)}
    res, ok = {}, np.ones(len(phi), bool)
    for name, z in pts.items():
        def at(off):
            return np.array([z[idx[v + off]] for v in phi])
        d1 = lambda h: (at(h) - at(-h)) / (2 * h)  # noqa: E731
        d2 = lambda h: (at(h) - 2 * at(0.0) + at(-h)) / h ** 2  # noqa: E731
        v1 = (4 * d1(2e-3) - d1(4e-3)) / 3
        a1 = (4 * d2(2e-3) - d2(4e-3)) / 3
        a_half = (4 * d2(1e-3) - d2(2e-3)) / 3
        ok &= np.abs(a1 - a_half) <= 1e-6 * max(float(np.max(np.abs(a_half))), 1e-12)  # no arc switch nearby
        res[name] = (at(0.0), v1 * w, a1 * w ** 2 + v1 * al)
    return res, np.array([margin[idx[v]] for v in phi]), ok, float(np.min(margin))


FEED_TOL = (1e-9, 1e-7, 1e-5)  # positions, velocities, accelerations: brentq, then differences
#: The coordinates whose angles at the first position start the feed's continued reference.
FEED_START = ("feed_rock_shaft.angle", "lift_rock_shaft.angle", "feed_bar.angle", "rock_shaft.angle")


# -- comparing a sweep with the reference, position by position ------------------------------------------------------

def draw_angles(rng) -> np.ndarray:
    """A revolution, a few coarse angles, a shuffled revolution or one with repeats."""
    kind = rng.integers(4)
    start = float(rng.uniform(0, 2 * math.pi))
    if kind == 0:
        return start + np.radians(np.arange(0.0, 360.0, 10.0))
    if kind == 1:
        return np.sort(rng.uniform(0, 2 * math.pi, int(rng.integers(2, 9))))
    if kind == 2:
        return rng.permutation(start + np.radians(np.arange(0.0, 360.0, 20.0)))
    base = start + np.radians(np.arange(0.0, 360.0, 30.0))
    return rng.permutation(np.concatenate([base, base[rng.integers(0, len(base), 4)]]))


def _length_scale(mech, p) -> float:
    desc = mech.description
    return max(abs(p[prm.name]) for prm in desc.params if prm.kind == "length" and "." not in prm.name)


def _c(x) -> complex:
    return complex(x)


def _e(x) -> float:
    """An error as a float, infinite where it is not a number (a reference at an exact toggle)."""
    x = float(x)
    return math.inf if math.isnan(x) else x


class Errors:
    """Per position: the relative errors of positions, velocities and accelerations (inf where the reference has no
    position; 0 where the position was not compared)."""

    def __init__(self, n):
        self.pos = np.zeros(n)
        self.vel = np.zeros(n)
        self.acc = np.zeros(n)

    def worst(self, k) -> float:
        return max(self.pos[k], self.vel[k], self.acc[k])


def classic_errors(motion, refs, L: float, w: float, al: float, positions) -> Errors:
    """Each position's errors against a classic reference (a :class:`Ref` per position, None: no assembly)."""
    err = Errors(len(refs))
    pts = {name: motion.point(name) for name in refs[next(i for i, r in enumerate(refs) if r is not None)].points} \
        if any(r is not None for r in refs) else {}
    coords = {}
    for k in positions:
        ref = refs[k]
        if ref is None:
            err.pos[k] = err.vel[k] = err.acc[k] = math.inf
            continue
        V = max([abs(_c(pt.v)) for pt in ref.points.values()] +
                [abs(float(c[1])) * float(c[3]) for c in ref.coords.values()])
        A = max([abs(_c(pt.a)) for pt in ref.points.values()] +
                [abs(float(c[2])) * float(c[3]) for c in ref.coords.values()] +
                [float(c[1]) ** 2 * float(c[3]) for name, c in ref.coords.items() if name.endswith(".angle")])
        V = max(V, 1e-12 * L * max(abs(w), 1e-9))
        A = max(A, 1e-12 * L * max(w * w + abs(al), 1e-9))
        for name, pt in ref.points.items():
            got = pts[name]
            err.pos[k] = max(err.pos[k], _e(abs(complex(got.x[k], got.y[k]) - _c(pt.z)) / L))
            err.vel[k] = max(err.vel[k], _e(abs(complex(got.vx[k], got.vy[k]) - _c(pt.v)) / V))
            err.acc[k] = max(err.acc[k], _e(abs(complex(got.ax[k], got.ay[k]) - _c(pt.a)) / A))
        for name, (val, rate, acc, lever) in ref.coords.items():
            if name not in coords:
                coords[name] = motion.coord(name)
            c, lev = coords[name], float(lever)
            dv = float(c.value[k] - val)
            if name.endswith(".angle"):
                dv = _wrap(dv) * lev
            err.pos[k] = max(err.pos[k], _e(abs(dv) / L))
            err.vel[k] = max(err.vel[k], _e(abs(float(c.rate[k] - rate)) * lev / V))
            err.acc[k] = max(err.acc[k], _e(abs(float(c.accel[k] - acc)) * lev / A))
    return err


def _blocks(names):
    """The observables' point blocks (name -> index of .x: x, y, x_d, y_d, x_dd, y_dd) and angle blocks (name ->
    index of .angle: angle, angle_d, angle_dd)."""
    points, angles = {}, {}
    for i, n in enumerate(names):
        if n.endswith(".x") and names[i + 1: i + 6] == [n[:-2] + s for s in (".y", ".x_d", ".y_d", ".x_dd", ".y_dd")]:
            points[n[:-2]] = i
        elif n.endswith(".angle"):
            angles[n[:-6]] = i
    return points, angles


def symbolic_solutions(fam, motion, d: Design, positions):
    """The reference's solution at each position (None where mpmath's Newton finds none near the sweep's)."""
    mech, ref = fam.mechanism, fam.symbolic
    held = [d.held.get(h.name, h.default) for h in mech.description.held_inputs]
    out = {}
    with mp.workdps(DPS):
        for k in positions:
            out[k] = ref.solve(d.params, motion.q[k], [motion.phi[k]] + held,
                               [motion.omega[k]] + [0.0] * len(held), [motion.alpha[k]] + [0.0] * len(held))
    return out


def symbolic_errors(fam, motion, d: Design, sols, L: float) -> Errors:
    """Each position's errors against the mechanism's own equations solved exactly: every point and centre of mass,
    every body's angle (its rates relative to the position's fastest body)."""
    err = Errors(len(motion.phi))
    points, angles = _blocks(fam.symbolic.obs_names)
    w, al = float(np.max(np.abs(motion.omega))), float(np.max(np.abs(motion.alpha)))
    for k, sol in sols.items():
        if sol is None:
            err.pos[k] = err.vel[k] = err.acc[k] = math.inf
            continue
        obs = [float(v) for v in sol[3]]
        got = motion.obs[k]
        V = max([math.hypot(obs[i + 2], obs[i + 3]) for i in points.values()] + [1e-12 * L * max(w, 1e-9)])
        A = max([math.hypot(obs[i + 4], obs[i + 5]) for i in points.values()] +
                [1e-12 * L * max(w * w + al, 1e-9)])
        Om = max([abs(obs[i + 1]) for i in angles.values()] + [1e-12 * max(w, 1e-9)])
        Al = max([max(abs(obs[i + 2]), obs[i + 1] ** 2) for i in angles.values()] + [1e-12 * max(w * w + al, 1e-9)])
        for i in points.values():
            err.pos[k] = max(err.pos[k], math.hypot(got[i] - obs[i], got[i + 1] - obs[i + 1]) / L)
            err.vel[k] = max(err.vel[k], math.hypot(got[i + 2] - obs[i + 2], got[i + 3] - obs[i + 3]) / V)
            err.acc[k] = max(err.acc[k], math.hypot(got[i + 4] - obs[i + 4], got[i + 5] - obs[i + 5]) / A)
        for i in angles.values():
            err.pos[k] = max(err.pos[k], abs(_wrap(got[i] - obs[i])))
            err.vel[k] = max(err.vel[k], abs(got[i + 1] - obs[i + 1]) / Om)
            err.acc[k] = max(err.acc[k], abs(got[i + 2] - obs[i + 2]) / Al)
    return err


# -- one case -----------------------------------------------------------------------------------------------------

@dataclass
class Outcome:
    key: str
    detail: str = ""
    positions: int = 0  # positions compared
    refused: int = 0  # positions refused (their estimate above the tolerance)
    exceeded: int = 0  # accepted positions whose error is above their estimate
    overcautious: int = 0  # refused positions whose error is below a hundredth of the tolerance
    worst_ratio: float = 0.0  # the largest error / estimate of an accepted position
    worst: str = ""  # where


def _kwargs(fam, d: Design, w, al, newton):
    kw = dict(speed=w, accel=al, params=d.params, newton=newton)
    if fam.held:
        kw["held"] = d.held
    else:
        kw["branch"] = d.branch
        if d.held:
            kw["held"] = d.held
    return kw


def _typed(fam, d, phi, w, al, newton, exc) -> Outcome:
    import sewgen

    if isinstance(exc, sewgen.PositionError) and (fam.reference is not None or fam.held) and \
            _continues(fam, d, phi, w, al, newton):
        return Outcome(f"unjustified {type(exc).__name__}", str(exc))
    return Outcome(f"typed {type(exc).__name__}", str(exc))


def run_case(fam: Family, rng, newton: bool) -> Outcome:
    """One design of ``fam`` (random or aimed) through one path."""
    d = fam.draw(rng)
    phi = d.phi if d.phi is not None else draw_angles(rng)
    w = float(rng.choice([1.0, 100.0, float(rng.uniform(-300, 300))]))
    al = float(rng.choice([0.0, float(rng.uniform(-1e4, 1e4))]))
    return check_design(fam, d, phi, w, al, newton)


def check_design(fam: Family, d: Design, phi, w: float, al: float, newton: bool) -> Outcome:
    """The outcome of one design at shaft angles ``phi``, speed ``w``, shaft acceleration ``al``, by the closed form
    or Newton: the sweep with its singular positions kept and flagged (``singular="flag"``) compared position by
    position; where it flags any, the same sweep must raise SingularPositionError."""
    import sewgen
    from sewgen.engine.mechanism import SINGULAR_TOL

    mech = fam.mechanism
    phi = np.asarray(phi, float)
    kw = _kwargs(fam, d, w, al, newton)
    try:
        motion = mech.solve(phi, singular="flag", **kw)
    except sewgen.SewgenError as exc:
        return _typed(fam, d, phi, w, al, newton, exc)
    except Exception as exc:  # noqa: BLE001 -- counted, that is the point
        return Outcome(f"untyped {type(exc).__name__}", str(exc))
    if not all(np.isfinite(a).all() for a in (motion.q, motion.qd, motion.qdd, motion.obs)):
        return Outcome("nan")
    est, flagged = motion.error_estimate, motion.singular
    n = len(phi)
    L = _length_scale(mech, d.params)
    if fam.held:
        return _feed_outcome(fam, d, motion, phi, w, al)
    with mp.workdps(DPS):
        if fam.reference is not None:
            refs = [fam.reference(d.params, d.branch, float(ph), w, al) for ph in phi]
            err = classic_errors(motion, refs, L, w, al, range(n))
        else:
            err = symbolic_errors(fam, motion, d, symbolic_solutions(fam, motion, d, range(n)), L)
    out = Outcome("verified", positions=n, refused=int(flagged.sum()))
    wrong = [k for k in range(n) if not flagged[k] and err.worst(k) > WRONG]
    for k in range(n):
        rates = max(err.vel[k], err.acc[k])
        if flagged[k]:
            out.overcautious += int(rates < 1e-2 * SINGULAR_TOL)
        elif rates > max(est[k], EXCEEDED_FLOOR):
            out.exceeded += 1
            if rates / max(est[k], 1e-300) > out.worst_ratio:
                out.worst_ratio = rates / max(est[k], 1e-300)
                out.worst = (f"{fam.name} newton={newton} {d.aim}: position {k} (phi {phi[k]!r}), velocities "
                             f"{err.vel[k]:.3g}, accelerations {err.acc[k]:.3g}, estimate {est[k]:.3g}")
    if wrong:
        k = wrong[0]
        detail = (f"{fam.name} newton={newton} {d.aim}: position {k} (phi {phi[k]!r}) off by {err.worst(k):.3g} "
                  f"(positions {err.pos[k]:.3g}, velocities {err.vel[k]:.3g}, accelerations {err.acc[k]:.3g}), "
                  f"estimate {est[k]:.3g}")
        flip = fam.reference is not None and _flipped(fam, d, motion, phi, w, al, k, L)
        out.key, out.detail = ("silent flip" if flip else "silent wrong"), detail
        return out
    if flagged.any():
        try:
            mech.solve(phi, **kw)
        except sewgen.SingularPositionError as exc:
            out.key, out.detail = "typed SingularPositionError", str(exc)
        except Exception as exc:  # noqa: BLE001
            out.key, out.detail = f"untyped {type(exc).__name__} (flagged singular)", str(exc)
        else:
            out.key = "untyped: flagged singular but no error raised"
    return out


def _flipped(fam, d, motion, phi, w, al, k, L) -> bool:
    """Position k is another branch's (the same design with one or every branch sign turned)."""
    for j in d.branch:
        for alt in ({**d.branch, j: -d.branch[j]}, {i: -v for i, v in d.branch.items()}):
            with mp.workdps(DPS):
                ref = fam.reference(d.params, alt, float(phi[k]), w, al)
            if ref is not None and all(abs(complex(motion.point(nm).x[k], motion.point(nm).y[k]) - _c(pt.z)) <= 1e-7 * L
                                       for nm, pt in ref.points.items()):
                return True
    return False


def _continues(fam: Family, d: Design, phi, w, al, newton: bool) -> bool:
    """The reference assembles on the requested branch with every triangle's margin above MARGIN: at the
    requested angles (closed form), or all along the shaft-angle path between them in sorted order, 0.5° apart
    (Newton continues along it)."""
    phi = np.sort(np.asarray(phi, float))
    if fam.held:  # the feed's reference is continued along the path anyway, from the declared guesses
        names = fam.mechanism.coord_names
        guess = [c.guess for c in fam.mechanism.description.coords]
        ref = feed_reference(d.params, d.held["regulator"], phi, w, al, [guess[names.index(k)] for k in FEED_START])
        return ref is not None and ref[3] > MARGIN
    if newton and len(phi) > 1:
        steps = np.maximum(np.ceil(np.diff(phi) / math.radians(0.5)), 1).astype(int)
        phi = np.concatenate([np.linspace(a, b, k, endpoint=False) for a, b, k in zip(phi[:-1], phi[1:], steps)]
                             + [phi[-1:]])
    with mp.workdps(20):
        def margin(ph):
            ref = fam.reference(d.params, d.branch, float(ph), w, al)
            return 0.0 if ref is None else float(ref.margin)

        m = [margin(ph) for ph in phi]
        if not min(m) > MARGIN:
            return False
        if newton:  # a margin can dip between two samples (a guide's pin sweeping past its pivot): look closer there
            for a, b, ma, mb in zip(phi[:-1], phi[1:], m[:-1], m[1:]):
                if min(ma, mb) < 100 * MARGIN and not all(margin(t) > MARGIN for t in np.linspace(a, b, 41)[1:-1]):
                    return False
    return True


def _feed_outcome(fam, d, motion, phi, w, al) -> Outcome:
    """The feed against its own continued solution (float64, rates by differences: FEED_TOL)."""
    names = fam.mechanism.coord_names
    first = int(np.argmin(phi))
    start = [motion.q[first][names.index(k)] for k in FEED_START]
    ref = feed_reference(d.params, d.held["regulator"], phi, w, al, start)
    if ref is None:
        return Outcome("silent wrong", "the feed's reference does not assemble where the sweep did")
    pts, _margin, rated, _least = ref
    L = _length_scale(fam.mechanism, d.params)
    est = motion.error_estimate
    for name, (z, v, a) in pts.items():
        got = motion.point(name)
        V = max(float(np.max(np.abs(v))), 1e-3 * L * max(abs(w), 1e-9))
        A = max(float(np.max(np.abs(a))), 1e-3 * L * max(w * w + abs(al), 1e-9))
        for g, want, tol, mask, scale in (((got.x, got.y), z, FEED_TOL[0], slice(None), L),
                                          ((got.vx, got.vy), v, FEED_TOL[1], rated, V),
                                          ((got.ax, got.ay), a, FEED_TOL[2], rated, A)):
            off = np.abs(g[0] + 1j * g[1] - want) > (tol + 1e3 * est) * scale
            if np.any(off[mask] & ~motion.singular[mask]):
                return Outcome("silent wrong", f"feed: {name} off the reference")
    return Outcome("verified", positions=len(phi), refused=int(motion.singular.sum()))


# -- kinetostatics: the power balance ------------------------------------------------------------------------------

def check_forces(fam: Family, rng, newton: bool) -> Outcome:
    """A kinetostatic sweep of a random design (friction on in half of them, where the mechanism declares it): at
    every accepted position the driving power equals d(KE + PE)/dt of the reference's exact motion, the springs'
    stored energy included (with friction: is not below it, by at most WRONG of the balance's terms)."""
    import sewgen

    mech = fam.mechanism
    d = fam.draw(rng)
    phi = d.phi if d.phi is not None else draw_angles(rng)
    w = float(rng.choice([100.0, float(rng.uniform(-300, 300))]))
    al = float(rng.choice([0.0, float(rng.uniform(-1e4, 1e4))]))
    friction = rng.random() < 0.5 and any(n.endswith(".friction") for n in d.params)
    if friction:
        d.params = {**d.params, **{n: float(rng.uniform(0.02, 0.3)) for n in d.params if n.endswith(".friction")}}
    kw = _kwargs(fam, d, w, al, newton)
    try:
        fa = mech.kinetostatics(phi, singular="flag", **kw)
    except sewgen.SewgenError as exc:
        return Outcome(f"typed {type(exc).__name__}", str(exc))
    except Exception as exc:  # noqa: BLE001
        return Outcome(f"untyped {type(exc).__name__}", str(exc))
    motion = fa.motion
    if not np.all(np.isfinite(fa.frc)):
        return Outcome("nan")
    accepted = [k for k in range(len(phi)) if not motion.singular[k]]
    ref = fam.symbolic
    points, angles = _blocks(ref.obs_names)
    p = d.params
    pin = fa.input_power("shaft")
    out = Outcome("verified", positions=len(accepted), refused=len(phi) - len(accepted))
    with mp.workdps(DPS):
        sols = symbolic_solutions(fam, motion, d, accepted)
        for k in accepted:
            sol = sols[k]
            if sol is None:
                return Outcome("silent wrong", f"{fam.name}: no reference position near the sweep's at {phi[k]!r}")
            obs, args = sol[3], sol[4]
            rate, scale = ref.spring_power(args)
            for b in ref.bodies:
                m, inertia = _f(p[f"{b}.mass"]), _f(p[f"{b}.inertia"])
                i, j = points[f"{b}.com"], angles[b]
                terms = (m * (obs[i + 2] * obs[i + 4] + obs[i + 3] * obs[i + 5]), inertia * obs[j + 1] * obs[j + 2],
                         m * _f(G) * obs[i + 3])  # gravity along -y: -m g.v = m g v_y
                rate += sum(terms)
                scale += sum(abs(t) for t in terms)
            gap = float(_f(pin[k]) - rate)
            scale = float(scale) + abs(float(pin[k]))
            bad = gap < -WRONG * scale if friction else abs(gap) > WRONG * scale
            if bad:
                return Outcome("silent wrong", f"{fam.name} newton={newton} friction={friction}: power balance off by "
                                               f"{gap:.3g} W of {scale:.3g} at phi {phi[k]!r}")
    if motion.singular.any():
        out.key = "typed SingularPositionError"
    return out


# -- the command line -------------------------------------------------------------------------------------------------

CLI_FAMILIES = ("needle_bar", "take_up", "hook_drive")
#: Malformed options a run may end with: each must end it with exit status 2.
BAD_ARGS = (("--param", "crank=5"), ("--param", "no_such_param=1 mm"), ("--branch", "C=2"), ("--step", "0 deg"),
            ("--speed", "fast"), ("--param", "crank=nan mm"), ("--param", "crank=-1 mm"), ("--start", "1 mm"),
            ("--branch", "Z=1"))


def check_cli(fam: Family, rng) -> Outcome:
    """``sewgen kinematics`` on a random (or aimed) design of a catalog family: exit 0 and a CSV every row of which
    the reference verifies, or exit 2, one line on stderr and nothing on stdout; a malformed option exit 2."""
    from sewgen.cli.main import main

    mech = fam.mechanism
    d = fam.draw(rng)
    desc = mech.description
    step = float(rng.choice([1.0, 2.0, 5.0, 10.0, 15.0, 30.0]))
    start = float(rng.uniform(-180.0, 360.0))
    w = float(rng.uniform(1.0, 300.0))
    defaults = mech.defaults()
    bad = rng.random() < 0.2
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "out.csv")
        argv = ["kinematics", fam.name, "--step", f"{step!r} deg", "--start", f"{start!r} deg",
                "--speed", f"{w!r} rad/s", "--csv", path]
        for prm in desc.params:
            if d.params[prm.name] != defaults[prm.name]:
                argv += ["--param", f"{prm.name}={d.params[prm.name]!r} {prm.unit or '1'}"]
        for j, s in d.branch.items():
            argv += ["--branch", f"{j}={s:+d}"]
        if rng.random() < 0.3:
            argv.append("--newton")
        if bad:
            argv += list(BAD_ARGS[int(rng.integers(len(BAD_ARGS)))])
        so, se = io.StringIO(), io.StringIO()
        try:
            with contextlib.redirect_stdout(so), contextlib.redirect_stderr(se):
                rc = main(argv)
        except SystemExit as exc:
            rc = exc.code
        except Exception as exc:  # noqa: BLE001
            return Outcome(f"untyped cli {type(exc).__name__}", f"{argv}: {exc}")
        err_lines = [ln for ln in se.getvalue().splitlines() if ln.strip()]
        if rc == 2:
            if so.getvalue() or len(err_lines) != 1 or not err_lines[0].startswith("sewgen"):
                return Outcome("untyped cli output", f"{argv}: stdout {so.getvalue()[:80]!r}, stderr {se.getvalue()!r}")
            return Outcome("typed cli exit 2")
        if rc != 0 or bad:
            return Outcome(f"untyped cli exit {rc}", f"{argv}: {se.getvalue()!r}")
        with open(path, newline="") as fh:
            rows = list(csv.reader(fh))
    head, data = rows[0], np.array([[float(v) for v in r] for r in rows[1:]])
    col = {h.split(" [")[0]: data[:, i] for i, h in enumerate(head)}
    phi, L = col["phi"], _length_scale(mech, d.params)
    with mp.workdps(DPS):
        for k, ph in enumerate(phi):
            ref = fam.reference(d.params, d.branch, float(ph), w, 0.0)
            if ref is None:
                return Outcome("silent wrong", f"cli {fam.name}: a row where the reference does not assemble")
            for name, pt in ref.points.items():
                off = abs(complex(col[f"{name}.x"][k], col[f"{name}.y"][k]) - _c(pt.z)) / L
                V = max(abs(_c(q.v)) for q in ref.points.values())
                offv = abs(complex(col[f"{name}.x_d"][k], col[f"{name}.y_d"][k]) - _c(pt.v)) / max(V, 1e-300)
                if max(off, offv) > WRONG:
                    return Outcome("silent wrong", f"cli {fam.name} {argv}: {name} at row {k} off by "
                                                   f"{max(off, offv):.3g}")
    return Outcome("verified cli", positions=len(phi))


# -- campaigns ------------------------------------------------------------------------------------------------------

BAD = ("silent wrong", "silent flip", "nan")


def bad(counts) -> int:
    """Cases that fail the campaign: silent wrong results, flips, NaN, untyped and unjustified errors."""
    return sum(v for k, v in counts.items() if k in BAD or k.startswith(("untyped", "unjustified")))


def campaign(designs: int, seed: int = 0, cache_dir=None, out=sys.stdout, forces_every: int = 3,
             cli_every: int = 8) -> collections.Counter:
    """``designs`` designs, the families in turn: each swept by the closed form and by Newton (the feed by Newton);
    every ``forces_every``-th design of a family with masses a kinetostatic sweep too, every ``cli_every``-th of a
    catalog family a command line run. Returns the outcome counts (and ``sweeps``, ``positions``, the estimate's
    statistics, ``seconds``)."""
    rng = np.random.default_rng(seed)
    fams = families(cache_dir)
    counts = collections.Counter()
    by_family: dict = {}
    examples = {}
    worst = 0.0
    t0 = time.perf_counter()

    def add(fam, outcome: Outcome, what: str):
        nonlocal worst
        key = outcome.key
        counts[key] += 1
        counts["sweeps"] += 1
        counts["positions"] += outcome.positions
        counts["refused positions"] += outcome.refused
        counts["estimate exceeded"] += outcome.exceeded
        counts["overcautious"] += outcome.overcautious
        if outcome.worst_ratio > worst:
            worst = outcome.worst_ratio
            examples["worst error/estimate"] = outcome.worst
        by_family.setdefault(fam.name, collections.Counter())[key] += 1
        if key in BAD or key.startswith(("untyped", "unjustified")):
            examples.setdefault(key, f"{what}: {outcome.detail}")

    for k in range(designs):
        fam = fams[k % len(fams)]
        for newton in (False, True):
            if not fam.closed_form and not newton:
                continue  # Newton either way: one case
            sub = np.random.default_rng(rng.integers(2 ** 63))
            add(fam, run_case(fam, sub, newton), f"design {k} of {fam.name}, newton={newton}")
        turn = k // len(fams)
        if fam.forces and turn % forces_every == 0:
            sub = np.random.default_rng(rng.integers(2 ** 63))
            add(fam, check_forces(fam, sub, bool(sub.random() < 0.3)), f"forces of design {k} of {fam.name}")
        if fam.name in CLI_FAMILIES and turn % cli_every == 0:
            sub = np.random.default_rng(rng.integers(2 ** 63))
            add(fam, check_cli(fam, sub), f"cli run of design {k} of {fam.name}")
    counts["designs"] = designs
    counts["seconds"] = round(time.perf_counter() - t0, 1)
    counts["worst error/estimate"] = float(f"{worst:.3g}")
    for key, ex in examples.items():
        print(f"example of {key}: {ex}", file=out)
    for name, c in by_family.items():
        print(f"{name:<24} " + ", ".join(f"{k} {v}" for k, v in sorted(c.items())), file=out)
    return counts


STATS = ("designs", "sweeps", "positions", "refused positions", "estimate exceeded", "worst error/estimate",
         "overcautious")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python tools/fuzz.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("--designs", type=int, default=600, help="designs (each through closed form and Newton)")
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args(argv)
    counts = campaign(a.designs, a.seed)
    keys = [k for k in STATS] + sorted(k for k in counts if k.startswith("verified")) + sorted(
        k for k in counts if k.startswith("typed")) + sorted(
        k for k in counts if k not in STATS and k != "seconds" and not k.startswith(("verified", "typed")))
    width = max(len(k) for k in keys + list(BAD))
    for key in keys:
        print(f"{key:<{width}}  {counts[key]}")
    for key in BAD + ("untyped", "unjustified"):
        if not any(k.startswith(key) for k in counts):
            print(f"{key:<{width}}  0")
    print(f"{'seconds':<{width}}  {counts['seconds']}")
    return 1 if bad(counts) else 0


if __name__ == "__main__":
    sys.exit(main())

"""Adversarial campaigns: random designs against independent closed forms (``python tools/fuzz.py``).

Every design of a family (the catalog's needle bar, take-up and hook drive; user four-bars, crank-sliders and
Stephenson six-bars, compiled once and varied through ``params``) is swept at a random set of shaft angles —
a dense revolution, a few coarse angles, a shuffled or repeated set — on a random branch, at a random speed and
shaft acceleration, by the closed form where the mechanism has one and by Newton (``newton=True``). Each sweep
either matches the reference here (plain complex-number geometry, dyad by dyad: positions by the triangle,
velocities and accelerations from each dyad's 2 × 2 linear system; nothing shared with the derivation or the C
kernels) on the requested branch, or raises a typed error. Outcomes:

* ``matched``: every position, velocity and acceleration within 1e-9 of the reference (relative to the
  sweep's scale of that quantity), or within what the run's own error estimate admits;
* ``typed``: a :class:`~sewgen.errors.SewgenError` (counted by type) — ``unjustified`` among them when the
  reference continues the requested branch over the whole sweep with every triangle's margin above 1e-3;
* ``silent flip``: a result that is the *other* branch's at some position; ``mismatch``: neither branch's;
  ``nan``: a non-finite value in a result; ``untyped``: any other exception.

The campaign passes when flips, mismatches, NaN, untyped and unjustified errors are all 0 (exit status 1
otherwise). The property tests (tests/test_property_adversarial.py) run the same cases at a CI size.
"""
from __future__ import annotations

import argparse
import collections
import math
import sys
import time
from dataclasses import dataclass, field

import numpy as np

MM = 1e-3
MARGIN = 1e-3  # a toggle margin above this: the requested branch continues, no PositionError is justified
TOL = 1e-9


# -- complex-number kinematics: z (position), v, a over the sweep ----------------------------------------------

@dataclass
class Pt:
    z: np.ndarray
    v: np.ndarray
    a: np.ndarray


def _cross(a, b):
    return (np.conj(a) * b).imag


def _solve2(A, B, C):
    """x, y with x A - y B = C (complex 2-vectors as numbers): Cramer's rule."""
    det = _cross(A, B)
    return _cross(C, B) / det, -_cross(A, C) / det


def _on(p: Pt, w: np.ndarray, omega, alpha) -> Pt:
    """The point p + w of a body turning at omega, alpha (w the world offset, already rotated)."""
    return Pt(p.z + w, p.v + 1j * omega * w, p.a + 1j * alpha * w - omega ** 2 * w)


def _crank(r, phi, w, al, phase=0.0) -> tuple:
    th = phi + phase
    return _on(Pt(0 * phi + 0j, 0j * phi, 0j * phi), r * np.exp(1j * th), w, al), th


def _fixed(z, n) -> Pt:
    return Pt(np.full(n, complex(z)), np.zeros(n, complex), np.zeros(n, complex))


def rrr(P: Pt, Q: Pt, l1, l2, sigma):
    """Joint J at l1 from P and l2 from Q, left of P->Q for sigma = +1: (J, omega1, alpha1, omega2, alpha2,
    margin), margin = the triangle's height over its longest side (0 at a toggle); None where it cannot close."""
    d = Q.z - P.z
    d2 = np.abs(d) ** 2
    a = 0.5 * (l1 ** 2 - l2 ** 2 + d2) / d2
    h2 = l1 ** 2 / d2 - a ** 2
    if not np.all(h2 >= 0):
        return None
    J = P.z + a * d + sigma * 1j * np.sqrt(h2) * d
    u1, u2 = J - P.z, J - Q.z
    w1, w2 = _solve2(1j * u1, 1j * u2, Q.v - P.v)
    rhs = Q.a - P.a - w2 ** 2 * u2 + w1 ** 2 * u1
    al1, al2 = _solve2(1j * u1, 1j * u2, rhs)
    vJ = P.v + 1j * w1 * u1
    aJ = P.a + 1j * al1 * u1 - w1 ** 2 * u1
    margin = np.abs(_cross(u1, u2)) / (np.abs(u1) * np.abs(u2))  # sine of the angle at J: 0 at a toggle
    return Pt(J, vJ, aJ), w1, al1, w2, al2, margin


def rrp(P: Pt, l, G0: complex, u: complex, sigma):
    """Pin J on the fixed line G0 + s u (|u| = 1) at l from P; sigma = +1 the larger s: (J, s, omega, alpha,
    margin) or None."""
    w = G0 - P.z
    b = (np.conj(u) * w).real
    disc = b ** 2 - (np.abs(w) ** 2 - l ** 2)
    if not np.all(disc >= 0):
        return None
    s = -b + sigma * np.sqrt(disc)
    J = G0 + s * u
    rel = J - P.z
    sd, om = _solve2(u * np.ones_like(rel), 1j * rel, P.v)
    sdd, al = _solve2(u * np.ones_like(rel), 1j * rel, P.a - om ** 2 * rel)
    margin = np.sqrt(disc) / max(l, 1e-300)
    return Pt(J, sd * u, sdd * u), s, om, al, margin


# -- families ---------------------------------------------------------------------------------------------------

@dataclass
class Family:
    """A mechanism, how to draw a design of it, and its reference."""

    name: str
    mechanism: object
    draw: object  # rng -> (params dict SI, branch dict)
    reference: object  # (params, branch, phi, omega, alpha) -> (points, coords, margin) or None
    closed_form: bool = True
    held_name: str = ""  # the held input a design draws instead of branch signs (a mechanism without dyads)
    extra_guess: tuple = ()  # the coordinates whose guesses start its reference
    held: bool = False  # the "branch" a design draws is its held inputs (a mechanism without dyads)
    tol_rates: tuple = (TOL, TOL)  # velocities, accelerations (a reference by differences is less exact)
    rate_floor: float = 1e-9  # rates compared at least on this fraction of (length scale x speed (squared))


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


def needle_reference(p, br, phi, w, al):
    B, _ = _crank(p["crank"], phi, w, al, p.get("crank.phase", 0.0))
    res = rrp(B, p["rod"], complex(p["offset"], 0.0), 1j, br["C"])
    if res is None:
        return None
    C, s, om, ral, margin = res
    eye = Pt(C.z - 1j * p["eye_below_pin"], C.v, C.a)
    return {"crank_pin": B, "link_pin": C, "needle_eye": eye}, {"needle_bar.travel": (s, (C.v / 1j).real,
                                                                                     (C.a / 1j).real)}, margin


def take_up_reference(p, br, phi, w, al):
    n = len(phi)
    B, _ = _crank(p["crank"], phi, w, al, p.get("crank.phase", 0.0))
    D = _fixed(complex(p["rocker_pivot_x"], p["rocker_pivot_y"]), n)
    res = rrr(B, D, p["lever_bc"], p["rocker"], br["C"])
    if res is None:
        return None
    C, w1, a1, _w2, _a2, margin = res
    bc, be, ce = p["lever_bc"], p["lever_be"], p["lever_ce"]
    eu = (bc ** 2 + be ** 2 - ce ** 2) / (2 * bc)
    ev = math.sqrt(max(be ** 2 - eu ** 2, 0.0))
    E = _on(B, (C.z - B.z) / bc * complex(eu, ev), w1, a1)
    return {"crank_pin": B, "rocker_pin": C, "thread_eye": E}, {}, margin


def hook_reference(p, br, phi, w, al):
    n = len(phi)
    B, _ = _crank(p["crank"], phi, w, al, p.get("crank.phase", 0.0))
    O4 = _fixed(complex(p["rock_axis_x"], p["rock_axis_y"]), n)
    res = rrr(B, O4, p["big_rod"], p["rock_front_arm"], br["C"])
    if res is None:
        return None
    C, _w1, _a1, wr, ar, m1 = res
    E = _on(O4, (C.z - O4.z) / p["rock_front_arm"] * p["rock_rear_arm"] * np.exp(1j * p["rock_rear_angle"]), wr, ar)
    d = E.z - complex(p["lower_axis_x"], p["lower_axis_y"])
    rho = np.abs(d)
    if not np.all(rho > 0):
        return None
    e = d / rho
    rd = (np.conj(e) * E.v).real
    psd = (np.conj(e) * E.v).imag / rho
    rdd = (np.conj(e) * E.a).real + rho * psd ** 2
    psdd = ((np.conj(e) * E.a).imag - 2 * rd * psd) / rho
    sg = br["E"]
    psi = np.angle(d) + (0.0 if sg > 0 else math.pi)
    coords = {"rock_slider.travel": (sg * rho, sg * rd, sg * rdd), "lower_shaft.angle": (psi, psd, psdd)}
    margin = np.minimum(m1, rho / max(p["rock_rear_arm"], 1e-300))
    return {"crank_pin": B, "rock_pin": C, "slider_pin": E}, coords, margin


def four_bar_reference(p, br, phi, w, al):
    n = len(phi)
    B, _ = _crank(p["crank"], phi, w, al)
    D = _fixed(complex(p["ground_x"], p["ground_y"]), n)
    res = rrr(B, D, p["coupler"], p["rocker"], br["C"])
    if res is None:
        return None
    C, w1, a1, _, _, margin = res
    P = _on(B, (C.z - B.z) / p["coupler"] * complex(p["point_u"], p["point_v"]), w1, a1)
    return {"crank_pin": B, "coupler_pin": C, "coupler_point": P}, {}, margin


def slider_reference(p, br, phi, w, al):
    B, _ = _crank(p["crank"], phi, w, al)
    res = rrp(B, p["rod"], complex(p["guide_x"], p["guide_y"]), complex(math.cos(p["guide_angle"]),
                                                                        math.sin(p["guide_angle"])), br["C"])
    if res is None:
        return None
    C, s, _om, _al, margin = res
    return {"crank_pin": B, "block_pin": C}, {}, margin


def six_bar_reference(p, br, phi, w, al):
    n = len(phi)
    B, _ = _crank(p["crank"], phi, w, al)
    D = _fixed(complex(p["ground_x"], p["ground_y"]), n)
    res = rrr(B, D, p["coupler"], p["rocker"], br["C"])
    if res is None:
        return None
    C, w1, a1, _, _, m1 = res
    E = _on(B, (C.z - B.z) / p["coupler"] * complex(p["point_u"], p["point_v"]), w1, a1)
    F = _fixed(complex(p["pivot_fx"], p["pivot_fy"]), n)
    res2 = rrr(E, F, p["link5"], p["link6"], br["G"])
    if res2 is None:
        return None
    G, *_rest, m2 = res2
    return {"crank_pin": B, "coupler_pin": C, "coupler_point": E, "pin_g": G}, {}, np.minimum(m1, m2)


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
        m_lift = abs(_cross(C - B, C - O4)) / (l1 * l2)
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
    of a switch carry no rate reference): (points, {}, margin, rates_ok mask)."""
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
        res[name] = Pt(at(0.0), v1 * w, a1 * w ** 2 + v1 * al)
    return res, {}, np.array([margin[idx[v]] for v in phi]), ok, float(np.min(margin))


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


def families(cache_dir=None) -> list[Family]:
    """The catalog's needle bar, take-up and hook drive, and the user four-bar, crank-slider and six-bar."""
    import sewgen

    def sign(rng):
        return int(rng.choice([1, -1]))

    nb, tu, hd, fd = (sewgen.mechanism(n) for n in ("needle_bar", "take_up", "hook_drive", "feed"))
    fb = sewgen.load(declare_four_bar, cache_dir=cache_dir)
    cs = sewgen.load(declare_slider, cache_dir=cache_dir)
    sb = sewgen.load(declare_six_bar, cache_dir=cache_dir)

    def d_needle(rng):
        p = _scaled(rng, nb.defaults(), ["crank", "rod", "eye_below_pin"], 0.6)
        p = _signed(rng, p, ["offset"], 25 * MM)
        return p, {"C": sign(rng)}

    def d_take_up(rng):
        p = _scaled(rng, tu.defaults(), ["crank", "lever_bc", "rocker", "lever_be", "lever_ce"], 0.35)
        p = _signed(rng, p, ["rocker_pivot_x", "rocker_pivot_y"], 10 * MM)
        p["lever_be"] = max(p["lever_be"], abs(p["lever_bc"] - p["lever_ce"]) * 1.001)  # a triangle BCE
        p["lever_be"] = min(p["lever_be"], (p["lever_bc"] + p["lever_ce"]) * 0.999)
        return p, {"C": sign(rng)}

    def d_hook(rng):
        p = _scaled(rng, hd.defaults(), ["crank", "big_rod", "rock_front_arm", "rock_rear_arm"], 0.3)
        p = _signed(rng, p, ["rock_axis_x", "lower_axis_x"], 10 * MM)
        p["rock_axis_y"] = -p["big_rod"] * float(rng.uniform(0.96, 1.03))
        p["lower_axis_y"] = p["rock_axis_y"] - float(rng.uniform(0.0, 1.3)) * p["rock_rear_arm"]
        p["rock_rear_angle"] = float(rng.uniform(-math.pi, math.pi)) if rng.random() < 0.3 else \
            -math.pi / 2 + float(rng.uniform(-1.0, 1.0))
        return p, {"C": sign(rng), "E": sign(rng)}

    def d_four_bar(rng):
        p = {k: float(rng.uniform(0.5, 80)) * MM for k in ("coupler", "rocker")}
        p["crank"] = float(rng.uniform(0.5, 25)) * MM
        p.update({k: float(rng.uniform(-60, 60)) * MM for k in ("ground_x", "ground_y", "point_u", "point_v")})
        return p, {"C": sign(rng)}

    def d_slider(rng):
        p = {"crank": float(rng.uniform(0.5, 30)) * MM, "rod": float(rng.uniform(0.5, 90)) * MM,
             "guide_x": float(rng.uniform(-30, 30)) * MM, "guide_y": float(rng.uniform(-30, 30)) * MM,
             "guide_angle": float(rng.uniform(-math.pi, math.pi))}
        return p, {"C": sign(rng)}

    def d_six_bar(rng):
        p, br = d_four_bar(rng)
        p.update({"link5": float(rng.uniform(5, 90)) * MM, "link6": float(rng.uniform(5, 90)) * MM,
                  "pivot_fx": float(rng.uniform(-60, 60)) * MM, "pivot_fy": float(rng.uniform(-60, 60)) * MM})
        return p, {"C": br["C"], "G": sign(rng)}

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
        return p, {"regulator": float(rng.uniform(-math.radians(50), math.radians(50)))}

    return [Family("feed", fd, d_feed, feed_reference, closed_form=False, held_name="regulator",
                   extra_guess=("feed_rock_shaft.angle", "lift_rock_shaft.angle", "feed_bar.angle",
                                "rock_shaft.angle"), held=True,
                   tol_rates=(1e-7, 1e-5), rate_floor=1e-3),
            Family("needle_bar", nb, d_needle, needle_reference), Family("take_up", tu, d_take_up, take_up_reference),
            Family("hook_drive", hd, d_hook, hook_reference), Family("four_bar", fb, d_four_bar, four_bar_reference),
            Family("crank_slider", cs, d_slider, slider_reference), Family("six_bar", sb, d_six_bar, six_bar_reference)]


# -- one case ---------------------------------------------------------------------------------------------------

def draw_angles(rng) -> np.ndarray:
    """A dense revolution, a few coarse angles, a shuffled revolution or one with repeats."""
    kind = rng.integers(4)
    start = float(rng.uniform(0, 2 * math.pi))
    if kind == 0:
        return start + np.radians(np.arange(0.0, 360.0, 5.0))
    if kind == 1:
        return np.sort(rng.uniform(0, 2 * math.pi, int(rng.integers(2, 9))))
    if kind == 2:
        return rng.permutation(start + np.radians(np.arange(0.0, 360.0, 10.0)))
    base = start + np.radians(np.arange(0.0, 360.0, 15.0))
    return rng.permutation(np.concatenate([base, base[rng.integers(0, len(base), 6)]]))


def _close(got, want, scale, est, tol=TOL) -> np.ndarray:
    """|got - want| within tol x scale, plus what the run's own error estimate admits (1000 est: the estimate is
    of the order of the error, see csrc/sg_runtime.c)."""
    return np.abs(got - want) <= (tol + 1e3 * est) * scale


def _compare(motion, ref, scale_len, tol_rates=(TOL, TOL), rate_floor=1e-9) -> bool:
    points, coords = ref[0], ref[1]
    rated = ref[3] if len(ref) > 3 else np.ones(len(motion.phi), bool)  # positions with a rate reference
    est = motion.error_estimate
    w = float(np.max(np.abs(motion.omega)))
    al = float(np.max(np.abs(motion.alpha)))
    floors = (scale_len * 1e-9, rate_floor * scale_len * w, rate_floor * scale_len * (w * w + al))
    for name, pt in points.items():
        got = motion.point(name)
        for g, want, tol, mask, floor in (
                ((got.x, got.y), pt.z, TOL, slice(None), floors[0]),
                ((got.vx, got.vy), pt.v, tol_rates[0], rated, floors[1]),
                ((got.ax, got.ay), pt.a, tol_rates[1], rated, floors[2])):
            z = g[0] + 1j * g[1]
            scale = max(float(np.max(np.abs(want))), floor)
            if not np.all(_close(z, want, scale, est, tol)[mask]):
                return False
    for name, (val, rate, acc) in coords.items():
        c = motion.coord(name)
        if c.unit == "rad":
            dv = (c.value - val + math.pi) % (2 * math.pi) - math.pi
            if not np.all(np.abs(dv) <= TOL + 1e3 * est):
                return False
        elif not np.all(_close(c.value, val, max(float(np.max(np.abs(val))), scale_len), est)):
            return False
        for g, want in ((c.rate, rate), (c.accel, acc)):
            if not np.all(_close(g, want, max(float(np.max(np.abs(want))), 1e-12), est)):
                return False
    return True


def run_case(fam: Family, rng, newton: bool) -> str:
    """One random design of ``fam`` through one path: an outcome key (see the module docstring)."""
    p, br = fam.draw(rng)
    phi = draw_angles(rng)
    w = float(rng.choice([1.0, 100.0, float(rng.uniform(-300, 300))]))
    al = float(rng.choice([0.0, float(rng.uniform(-1e4, 1e4))]))
    return check_design(fam, p, br, phi, w, al, newton)


def _reference(fam: Family, p, br, phi, w, al, motion=None):
    if fam.held:  # no declared branch: the assembly the engine started on (else the declaration's guesses)
        names = fam.mechanism.coord_names
        if motion is not None:
            first = int(np.argmin(np.asarray(phi, float)))
            start = list(motion.q[first])
        else:
            start = [c.guess for c in fam.mechanism.description.coords]
        guesses = tuple(start[names.index(k)] for k in fam.extra_guess)
        return fam.reference(p, br[fam.held_name], np.asarray(phi, float), w, al, guesses)
    return fam.reference(p, br, np.asarray(phi, float), w, al)


def check_design(fam: Family, p: dict, br: dict, phi, w: float, al: float, newton: bool) -> str:
    """The outcome of one design (params ``p``, branch ``br`` -- held inputs for a family without dyads) at
    shaft angles ``phi``, speed ``w``, shaft acceleration ``al``, by the closed form or Newton."""
    import sewgen

    mech = fam.mechanism
    ref = None if fam.held else _reference(fam, p, br, phi, w, al)
    scale_len = max(abs(v) for k, v in p.items() if mech.description.params[mech.param_names.index(k)].kind ==
                    "length")
    try:
        if fam.held:
            motion = mech.solve(phi, speed=w, accel=al, params=p, held=br, newton=newton)
        else:
            motion = mech.solve(phi, speed=w, accel=al, params=p, branch=br, newton=newton)
    except sewgen.SewgenError as exc:
        if isinstance(exc, sewgen.PositionError) and _continues(fam, p, br, phi, w, al, newton):
            return f"unjustified {type(exc).__name__}"
        return f"typed {type(exc).__name__}"
    except Exception as exc:  # noqa: BLE001 -- counted, that is the point
        return f"untyped {type(exc).__name__}: {exc}"
    if not all(np.isfinite(a).all() for a in (motion.q, motion.qd, motion.qdd, motion.obs, motion.error_estimate)):
        return "nan"
    if fam.held:
        ref = _reference(fam, p, br, phi, w, al, motion)
    if ref is None:
        return "mismatch (the reference does not assemble)"
    if _compare(motion, ref, scale_len, fam.tol_rates, fam.rate_floor):
        return "matched"
    if fam.held:
        return "mismatch"
    flips = []
    for k in br:  # the same design with one or every branch sign turned
        for alt in ({**br, k: -br[k]}, {j: -v for j, v in br.items()}):
            alt_ref = fam.reference(p, alt, np.asarray(phi, float), w, al)
            if alt_ref is not None and _partly(motion, alt_ref, scale_len):
                flips.append(alt)
    return "silent flip" if flips else "mismatch"


def _continues(fam: Family, p, br, phi, w, al, newton: bool) -> bool:
    """The reference assembles on the requested branch with every triangle's margin above MARGIN: at the
    requested angles (closed form), or all along the shaft-angle path between them in sorted order, 0.5° apart
    (Newton continues along it)."""
    phi = np.sort(np.asarray(phi, float))
    if fam.held:  # the feed's reference is continued along the path anyway
        ref = _reference(fam, p, br, phi, w, al)
        return ref is not None and ref[4] > MARGIN
    if newton and len(phi) > 1:
        steps = np.maximum(np.ceil(np.diff(phi) / math.radians(0.5)), 1).astype(int)
        phi = np.concatenate([np.linspace(a, b, k, endpoint=False) for a, b, k in zip(phi[:-1], phi[1:], steps)]
                             + [phi[-1:]])
    ref = fam.reference(p, br, phi, w, al)
    return ref is not None and float(np.min(ref[2])) > MARGIN


def _partly(motion, ref, scale_len) -> bool:
    """Some position of ``motion`` is ``ref``'s (another branch)."""
    points = ref[0]
    ok = np.zeros(len(motion.phi), bool)
    for name, pt in points.items():
        got = motion.point(name)
        z = got.x + 1j * got.y
        ok |= np.abs(z - pt.z) <= 1e-7 * scale_len
    return bool(ok.any())


def campaign(designs: int, seed: int = 0, cache_dir=None, out=sys.stdout) -> collections.Counter:
    rng = np.random.default_rng(seed)
    fams = families(cache_dir)
    counts = collections.Counter()
    by_family: dict = {}
    examples = {}
    t0 = time.perf_counter()
    for k in range(designs):
        fam = fams[k % len(fams)]
        for newton in (False, True):
            sub = np.random.default_rng(rng.integers(2 ** 63))
            if not fam.closed_form and not newton:
                continue  # Newton either way: one case
            outcome = run_case(fam, sub, newton)
            key = outcome.split(":")[0]
            counts[key] += 1
            by_family.setdefault(fam.name, collections.Counter())[key] += 1
            if not (key == "matched" or key.startswith("typed")):
                examples.setdefault(key, (fam.name, newton, k, outcome))
    counts["designs"] = designs
    counts["cases"] = sum(v for k, v in counts.items() if k != "designs")
    counts["seconds"] = round(time.perf_counter() - t0, 1)
    for key, ex in examples.items():
        print(f"example of {key}: family {ex[0]}, newton={ex[1]}, design {ex[2]}: {ex[3]}", file=out)
    for name, c in by_family.items():
        print(f"{name:<13} " + ", ".join(f"{k} {v}" for k, v in sorted(c.items())), file=out)
    return counts


def bad(counts) -> int:
    return sum(v for k, v in counts.items()
               if k in ("silent flip", "mismatch", "nan") or k.startswith(("untyped", "unjustified", "mismatch")))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python tools/fuzz.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("--designs", type=int, default=600, help="random designs (each through closed form and Newton)")
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args(argv)
    counts = campaign(a.designs, a.seed)
    width = max(len(k) for k in counts)
    for key in ["designs", "cases", "matched"] + sorted(k for k in counts if k.startswith("typed")) + sorted(
            k for k in counts if k not in ("designs", "cases", "matched", "seconds") and not k.startswith("typed")):
        print(f"{key:<{width}}  {counts[key]}")
    for key in ("silent flip", "nan", "untyped"):
        if key not in counts:
            print(f"{key:<{width}}  0")
    print(f"{'seconds':<{width}}  {counts['seconds']}")
    return 1 if bad(counts) else 0


if __name__ == "__main__":
    sys.exit(main())

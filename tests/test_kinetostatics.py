"""Kinetostatics (Mechanism.kinetostatics, ForceAnalysis, force_matrix, Load) against independent references.

Written here without sewgen's force code: the energy rate Σ m v_G·a_G + I ω α − m g·v_G from the kinematic
results (power balance, also against a finite difference of the energy); Newton–Euler sums for the frame's
force and moment on the parts; the needle-bar crank-slider's closed form (slider, rod, crank in turn, from
analytic slider kinematics; point masses and a distributed rod); virtual work at rest (shaft and held inputs); a
Lagrange-multiplier formulation on absolute coordinates for the take-up four-bar; a change-point parallelogram for the
singular force matrix; load windows and the seed 000 thread force (2.94 N over 135°–155°); A f = b against numpy.
Besides the catalog, two user mechanisms: a four-bar whose frame pivot names the frame second, and a crank-slider
driven backwards (sense −1, phase) on the guide of a held body.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import sewgen
from sewgen.derive.model import Mechanism as Declaration
from sewgen.engine.loads import Load
from sewgen.engine.results import Motion

pytestmark = [pytest.mark.c, pytest.mark.derive]

G = 9.80665
W0 = 120.0  # rad/s
DEG = np.arange(0.0, 360.0, 2.0)  # integer degrees: window ends fall exactly on grid points
PHI = np.radians(DEG)
CATALOG = ["needle_bar", "take_up", "hook_drive"]
USER = ["kt_four_bar", "kt_slider"]
ALL = CATALOG + USER
CRANK = {"crank.phase": 0.3, "crank.mass": 0.02, "crank.com_u": 0.003, "crank.com_v": -0.001, "crank.inertia": 2e-6}
TILT = "-120 deg"  # gravity direction for the tilted cases


def declare_four_bar():
    """A user crank-rocker with a coupler point and masses on every body (parameters); pivot D names the frame
    second, so its reaction is the force on the frame."""
    m = Declaration("kt_four_bar", "A crank-rocker four-bar with masses, for the kinetostatics tests.")
    r = m.length("crank", "12 mm", "crank AB")
    b = m.length("coupler", "40 mm", "coupler BC")
    c = m.length("rocker", "30 mm", "rocker DC")
    dx = m.length("pivot_x", "35 mm", "pivot D, x", signed=True)
    dy = m.length("pivot_y", "5 mm", "pivot D, y", signed=True)
    crank = m.driven("crank", pivot=m.ground.at(0, 0), mass="15 g", com=("4 mm", "1 mm"), inertia="2e-6 kg*m**2")
    coupler = m.link("coupler", guess="60 deg", mass="10 g", com=("18 mm", "3 mm"), inertia="3e-6 kg*m**2")
    rocker = m.link("rocker", guess="100 deg", mass="8 g", com=("12 mm", "-2 mm"), inertia="1e-6 kg*m**2")
    m.revolute(crank.at(r, 0), coupler.at(0, 0), name="B")
    m.revolute(rocker.at(0, 0), m.ground.at(dx, dy), name="D")  # the frame second: D acts on the frame
    m.revolute(coupler.at(b, 0), rocker.at(c, 0), name="C", branch=1)
    m.point("tip", coupler.at(0.025, 0.008), "coupler point")
    return m


def declare_slider():
    """A user crank-slider: crank turned backwards (sense −1) with a phase, pivot off the origin; the guide is a
    line of a held regulator body (its holding torque is an input torque too)."""
    m = Declaration("kt_slider", "A crank-slider driven backwards on a held guide, for the kinetostatics tests.")
    r = m.length("crank", "12 mm", "crank AB")
    l = m.length("rod", "45 mm", "rod BC")
    crank = m.driven("crank", pivot=m.ground.at(0.001, 0.002), sense=-1, phase="20 deg", mass="10 g",
                     com=("3 mm", "1 mm"), inertia="1e-6 kg*m**2")
    reg = m.held("regulator", pivot=m.ground.at(0.04, 0.003), default="10 deg", doc="guide carrier", mass="50 g",
                 com=("5 mm", "2 mm"), inertia="5e-6 kg*m**2")
    rod = m.link("rod", mass="8 g", com=("20 mm", "1 mm"), inertia="2e-6 kg*m**2")
    block = m.slider("block", guide=reg.line(at=(0, 0), angle=math.pi), guess="5 mm", mass="30 g",
                     com=("2 mm", "3 mm"), inertia="1e-6 kg*m**2")
    m.revolute(crank.at(r, 0), rod.at(0, 0), name="B")
    m.revolute(rod.at(l, 0), block.at(0, 0), name="C")
    m.point("tip", rod.at(0.02, 0.003), "rod point")
    m.point("crank_pin", crank.at(r, 0), "crank pin B")
    return m


# Per mechanism: parameter overrides and loads (a force at a point, a torque on a body; windowed, one wrapping).
CASES = {
    "needle_bar": (CRANK, (Load("needle_eye", fx=0.5, fy=-3.0, window=("200 deg", "300 deg")),
                           Load("rod", torque=0.02, window=("350 deg", "20 deg")))),
    "take_up": (CRANK, (Load("thread_eye", fy=-2.94, window=("135 deg", "155 deg")),
                        Load("rocker", torque=-0.01), Load("crank_pin", fx=0.8, fy=0.3))),
    "hook_drive": (CRANK, (Load("slider_pin", fx=1.0, fy=2.0, window=("40 deg", "160 deg")),
                           Load("lower_shaft", torque=0.05, window=("300 deg", "30 deg")))),
    "kt_four_bar": ({"crank.phase": -0.2}, (Load("tip", fx=-1.5, fy=0.7, window=("330 deg", "90 deg")),
                                            Load("rocker", torque=0.03, window=("100 deg", "200 deg")))),
    "kt_slider": ({}, (Load("tip", fx=2.0, fy=-1.0, window=("250 deg", "10 deg")), Load("block", torque=0.02),
                       Load("crank_pin", fx=-0.5, fy=0.4, window=("0 deg", "180 deg")),
                       Load("regulator", torque=0.05))),
}


@pytest.fixture(scope="session")
def user(cache):
    return {"kt_four_bar": sewgen.load(declare_four_bar, cache_dir=cache),
            "kt_slider": sewgen.load(declare_slider, cache_dir=cache)}


@pytest.fixture
def four_bar(user):
    return user["kt_four_bar"]


@pytest.fixture(params=ALL)
def mech(request):
    return request.getfixturevalue("user")[request.param] if request.param in USER else sewgen.mechanism(request.param)


# -- independent helpers -------------------------------------------------------------------------------------

def cross(a, b):
    return a[0] * b[1] - a[1] * b[0]


def gravity(direction_deg=-90.0):
    return G * np.array([math.cos(math.radians(direction_deg)), math.sin(math.radians(direction_deg))])


def speeds(phi, varying):
    """ω(φ) = ω0(1 + 0.3 sin φ) with its consistent α = ω dω/dφ, or a constant ω0."""
    if not varying:
        return np.full_like(phi, W0), np.zeros_like(phi)
    w = W0 * (1 + 0.3 * np.sin(phi))
    return w, w * W0 * 0.3 * np.cos(phi)


def in_window(deg, window):
    """Window membership written from the spec: inclusive ends, wrapping through 360°."""
    if window is None:
        return np.ones(deg.shape, bool)
    a, b = (float(w.split()[0]) for w in window)
    return (deg >= a) & (deg <= b) if a <= b else (deg >= a) | (deg <= b)


def masses(mech, params):
    p = {**mech.defaults(), **params}
    return {b: (p[f"{b}.mass"], p[f"{b}.inertia"]) for b in mech.body_names}


def bodies(motion, mech, params):
    """(m, I, r_G, v_G, a_G, θ̇, θ̈) per moving body, from the kinematic results."""
    for name, (m, inertia) in masses(mech, params).items():
        b = motion.body(name)
        c = b.com
        yield m, inertia, np.array([c.x, c.y]), np.array([c.vx, c.vy]), np.array([c.ax, c.ay]), b.omega, b.alpha


def load_terms(motion, loads, deg):
    """Per load: (force (2, n), point (2, n) or None, torque (n), power (n)), window applied."""
    for ld in loads:
        on = in_window(deg, ld.window)
        if ld.at in motion.point_names:
            p = motion.point(ld.at)
            F = np.array([ld.fx * on, ld.fy * on])
            yield F, np.array([p.x, p.y]), 0.0 * on, F[0] * p.vx + F[1] * p.vy
        else:
            T = ld.torque * on
            yield np.zeros((2, len(deg))), None, T, T * motion.body(ld.at).omega


def energy(motion, mech, params, gv):
    """KE = Σ ½ m v_G² + ½ I ω², PE = −Σ m g·r_G."""
    ke = pe = 0.0
    for m, inertia, r, v, _a, w, _al in bodies(motion, mech, params):
        ke = ke + 0.5 * m * (v[0] ** 2 + v[1] ** 2) + 0.5 * inertia * w ** 2
        pe = pe - m * (gv[0] * r[0] + gv[1] * r[1])
    return ke, pe


def energy_rate(motion, mech, params, gv):
    """d(KE + PE)/dt = Σ m v_G·a_G + I ω α − m g·v_G."""
    return sum(m * (v[0] * a[0] + v[1] * a[1]) + inertia * w * al - m * (gv[0] * v[0] + gv[1] * v[1])
               for m, inertia, _r, v, a, w, al in bodies(motion, mech, params))


def assert_close(got, want, rtol, scale=None, what=""):
    """max |got − want| ≤ rtol · scale (default: the largest |want|)."""
    got, want = np.asarray(got, float), np.asarray(want, float)
    scale = float(np.max(np.abs(want))) if scale is None else scale
    err = float(np.max(np.abs(got - want)))
    assert err <= rtol * max(scale, 1e-300), f"{what}: error {err:.3g} > {rtol:g} × {scale:.3g}"


# -- 1. power balance -----------------------------------------------------------------------------------------

@pytest.mark.parametrize("varying", [False, True], ids=["constant_speed", "varying_speed"])
def test_power_balance_every_position(mech, varying):
    """Σ input power + Σ load power = d(KE+PE)/dt from the kinematics, at every position (tilted gravity, loads)."""
    params, loads = CASES[mech.name]
    w, al = speeds(PHI, varying)
    gv = gravity(-120.0)
    fa = mech.kinetostatics(PHI, w, al, loads=loads, gravity_direction=TILT, params=params)
    load_power = sum(t[3] for t in load_terms(fa.motion, loads, DEG))
    rate = energy_rate(fa.motion, mech, params, gv)
    scale = float(np.max(np.abs(rate)) + np.max(np.abs(load_power)))
    assert_close(fa.load_power, load_power, 1e-12, scale, "load power")
    assert_close(fa.input_power("shaft"), fa.torque("shaft") * w, 1e-14, scale, "power = torque × speed")
    inputs = sum(fa.input_power(i["name"]) for i in mech.manifest["inputs"])
    assert_close(inputs + load_power, rate, 1e-9, scale, "power balance")


def test_power_against_finite_difference_of_energy(mech):
    """Input power = ω dE/dφ, E = KE + PE from the kinematics on a fine grid (4th-order central differences)."""
    params = CASES[mech.name][0]
    phi = np.radians(np.arange(0.0, 360.0, 0.25))
    w, al = speeds(phi, True)
    gv = gravity(-120.0)
    fa = mech.kinetostatics(phi, w, al, gravity_direction=TILT, params=params)
    ke, pe = energy(fa.motion, mech, params, gv)
    assert_close(fa.kinetic_energy, ke, 1e-12, what="kinetic energy")
    assert_close(fa.potential_energy, pe, 1e-12, scale=float(np.max(np.abs(pe)) + np.max(ke)), what="potential")
    E, h = ke + pe, phi[1] - phi[0]
    dE = (-np.roll(E, -2) + 8 * np.roll(E, -1) - 8 * np.roll(E, 1) + np.roll(E, 2)) / (12 * h)
    assert_close(fa.input_power(), w * dE, 1e-5, what="power vs finite difference")


# -- 2. the frame's force and moment on the parts -------------------------------------------------------------

def test_frame_force_and_moment_on_parts(mech):
    """Frame's force on the parts = Σ m(a_G − g) − Σ F; its moment about O = Σ (r_G−O)×m(a_G−g) + Iα − Σ load
    moments about O."""
    params, loads = CASES[mech.name]
    w, al = speeds(PHI, True)
    gv, O = gravity(-120.0), np.array([0.013, -0.021])
    fa = mech.kinetostatics(PHI, w, al, loads=loads, gravity_direction=TILT, params=params,
                            moment_about=("13 mm", "-21 mm"))
    force, moment = np.zeros((2, len(PHI))), np.zeros(len(PHI))
    for m, inertia, r, _v, a, _w, alpha in bodies(fa.motion, mech, params):
        f = m * (a - gv[:, None])
        force += f
        moment += cross(r - O[:, None], f) + inertia * alpha
    for F, at, T, _p in load_terms(fa.motion, loads, DEG):
        force -= F
        moment -= T + (0.0 if at is None else cross(at - O[:, None], F))
    scale = float(np.max(np.abs(force)))
    assert_close(fa.frame_force_on_parts, force.T, 1e-10, scale, "frame force on parts")
    assert_close(fa.frame_moment_on_parts, moment, 1e-10, what="frame moment on parts")
    # the forces on the frame, joint by joint, sum to the frame's force on the parts with the sign turned
    on_frame = sum(np.array([fa.frame_force(j).fx, fa.frame_force(j).fy]) for j in fa.frame_joint_names)
    assert_close(-on_frame, force, 1e-10, scale, "Σ frame forces")


# -- 3. needle bar: closed-form crank-slider --------------------------------------------------------------------

def needle_bar_closed_form(phi, w, al, r, l, e, m_c, m_r, I_r, m_s, v_s, lumped):
    """Crank-slider with the guide x = e (vertical), C below B, crank mass m_c at its pin, rod centre of mass at
    its middle; slider centre of mass offset v_s across the guide (local v). Hand-derived, frame axes.

    Kinematics: r cos φ + l cos β = e, so β̇ = −rω sin φ/(l sin β),
    β̈ = −(rω² cos φ + rα sin φ + l β̇² cos β)/(l sin β), a_C = −rω² sin φ + rα cos φ − l β̇² sin β + l β̈ cos β (y).
    Slider (translates): F_C + N n + m_s g = m_s a_C, n = (−1, 0); moment about G_s: the couple is −v_s F_Cy.
    Rod, lumped (m_r/2 at B and at C on a massless bar pushing the C end with t·e):
    t sin β = (m_s + m_r/2)(a_C + g), N = t cos β, F_B = t e + (m_r/2)(a_B − g).
    Rod, distributed (I_r about its middle): F_B = m_r(a_G − g) + F_C and e × (F_B + F_C) = −2 I_r β̈ / l.
    Crank, moments about A: τ = B × F_B − m_c B × g + m_c r² α; pivot force = F_B + m_c(a_B − g).
    """
    c, s = np.cos(phi), np.sin(phi)
    cb = (e - r * c) / l
    sb = -np.sqrt(1 - cb ** 2)
    bd = -r * w * s / (l * sb)
    bdd = -(r * w ** 2 * c + r * al * s + l * bd ** 2 * cb) / (l * sb)
    e_rod = np.array([cb, sb])
    B = r * np.array([c, s])
    aB = np.array([-r * al * s - r * w ** 2 * c, r * al * c - r * w ** 2 * s])
    aC = -r * w ** 2 * s + r * al * c - l * bd ** 2 * sb + l * bdd * cb
    gv = np.array([0.0, -G])[:, None]
    FCy = m_s * (aC + G)
    if lumped:
        t = (m_s + m_r / 2) * (aC + G) / sb
        N = t * cb
        FB = t * e_rod + (m_r / 2) * (aB - gv)
    else:
        aG = aB + (l / 2) * np.array([-sb * bdd - cb * bd ** 2, cb * bdd - sb * bd ** 2])
        N = (cb * FCy + I_r * bdd / l + 0.5 * m_r * cross(e_rod, aG - gv)) / sb
        FB = m_r * (aG - gv) + np.array([N, FCy])
    tau = cross(B, FB) - m_c * cross(B, gv) + m_c * r ** 2 * al
    return {"travel": B[1] + l * sb, "B": FB, "C": np.array([N, FCy]), "normal": N, "moment": -v_s * FCy,
            "pivot": FB + m_c * (aB - gv), "torque": tau}


@pytest.mark.parametrize("offset", [0.0, 0.004], ids=["centred", "offset"])
@pytest.mark.parametrize("lumped", [True, False], ids=["point_masses", "distributed_rod"])
def test_needle_bar_closed_form(offset, lumped):
    """Pin forces B and C, guide normal force and couple, crank pivot and torque against the closed form."""
    nb = sewgen.mechanism("needle_bar")
    r, l, m_c, m_r, m_s, w, al = 0.0167, 0.05, 0.02, 0.012, 0.045, 150.0, 2000.0
    v_s = 0.0 if lumped else 0.0015
    I_r = m_r * l ** 2 / 4 if lumped else m_r * l ** 2 / 12  # two pin masses, or a uniform rod
    params = {"offset": offset, "crank.mass": m_c, "crank.com_u": r, "crank.com_v": 0.0, "crank.inertia": 0.0,
              "rod.mass": m_r, "rod.inertia": I_r, "needle_bar.mass": m_s, "needle_bar.com_u": -0.03,
              "needle_bar.com_v": v_s}
    fa = nb.kinetostatics(PHI, w, al, params=params)
    want = needle_bar_closed_form(PHI, w, al, r, l, offset, m_c, m_r, I_r, m_s, v_s, lumped)
    assert_close(fa.motion.coord("needle_bar.travel").value, want["travel"], 1e-12, what="travel")
    scale = float(np.max(np.abs(want["B"])))
    for name, key in (("B", "B"), ("C", "C"), ("crank.pivot", "pivot")):
        got = fa.reaction(name)
        assert_close(np.array([got.fx, got.fy]), want[key], 1e-9, scale, name)
    guide = fa.reaction("needle_bar.guide")
    assert_close(guide.normal, want["normal"], 1e-9, scale, "guide normal")
    assert_close(np.array([guide.fx, guide.fy]), [-want["normal"], 0 * PHI], 1e-9, scale, "guide force")
    assert_close(guide.moment, want["moment"], 1e-9, scale * l, "guide couple")
    assert_close(fa.torque("shaft"), want["torque"], 1e-9, what="crank torque")


# -- 4. virtual work at rest ------------------------------------------------------------------------------------

def test_static_torque_is_virtual_work(mech):
    """At rest under gravity, τ = −Σ m g·∂r_G/∂x for the shaft and every held input x, by central differences of
    the COM positions over x."""
    params = CASES[mech.name][0]
    phi, h = np.radians(np.arange(0.0, 360.0, 10.0)), 1e-5
    gv = gravity()

    def potential(phi, held=None):  # −Σ m g·r_G
        mo = mech.solve(phi, 1.0, params=params, held=held)
        return sum(-m * (gv[0] * mo.body(b).com.x + gv[1] * mo.body(b).com.y)
                   for b, (m, _i) in masses(mech, params).items())

    fa = mech.kinetostatics(phi, 0.0, 0.0, params=params)
    tau = (potential(phi + h) - potential(phi - h)) / (2 * h)
    assert np.max(np.abs(tau)) > 1e-4  # gravity does work here
    assert_close(fa.torque("shaft"), tau, 1e-7, what="static torque")
    assert_close(fa.kinetic_energy, 0 * phi, 0, 1.0, "kinetic energy at rest")
    for inp in mech.manifest["inputs"][1:]:
        x0, name = inp["default"], inp["name"]
        hold = (potential(phi, {name: x0 + h}) - potential(phi, {name: x0 - h})) / (2 * h)
        assert np.max(np.abs(hold)) > 1e-3
        assert_close(fa.torque(name), hold, 1e-7, what=f"holding torque {name}")
        assert_close(fa.input_power(name), 0 * phi, 0, 1.0, f"{name} power")


# -- 5. take-up four-bar against Lagrange multipliers -----------------------------------------------------------

def rot(th, u, v):
    c, s = np.cos(th), np.sin(th)
    return np.array([c * u - s * v, s * u + c * v])


def test_take_up_against_lagrange_multipliers():
    """Absolute coordinates (x, y, θ) per body; M q̈ − Φ_qᵀ μ = Q, Φ_q q̈ = γ solved together per position.

    Pins are written Φ = P_b − P_a (a = sewgen's first body), so μ is the force on b from a — sewgen's reaction;
    the driving constraint θ_crank − φ − phase = 0 has μ = the driving torque. Velocities: Φ_q q̇ = (0, …, ω).
    Only the lever and rocker angles are taken from sewgen (and checked to close the loop).
    """
    tu = sewgen.mechanism("take_up")
    params, loads = CASES["take_up"]
    w, al = speeds(PHI, True)
    gv = gravity(-120.0)
    fa = tu.kinetostatics(PHI, w, al, loads=loads, gravity_direction=TILT, params=params)
    p = {**tu.defaults(), **params}
    ab, bc, cd, be, ce = p["crank"], p["lever_bc"], p["rocker"], p["lever_be"], p["lever_ce"]
    D = np.array([p["rocker_pivot_x"], p["rocker_pivot_y"]])
    eu = (bc ** 2 + be ** 2 - ce ** 2) / (2 * bc)
    E = np.array([eu, math.sqrt(be ** 2 - eu ** 2)])  # thread eye in the lever frame (B origin, C on +u)
    com = [np.array([p["crank.com_u"], p["crank.com_v"]]), np.array([p["lever.com_u"], p["lever.com_v"]]),
           np.array([cd / 2, 0.0])]
    mass = [p["crank.mass"], p["lever.mass"], p["rocker.mass"]]
    inertia = [p["crank.inertia"], p["lever.inertia"], p["rocker.inertia"]]
    # (name, body a or None for ground, point of a (local, or world for ground), body b, point of b (local))
    pins = [("crank.pivot", None, np.zeros(2), 0, np.zeros(2)), ("B", 0, np.array([ab, 0.0]), 1, np.zeros(2)),
            ("D", None, D, 2, np.zeros(2)), ("C", 1, np.array([bc, 0.0]), 2, np.array([cd, 0.0]))]
    points = {"crank_pin": (0, np.array([ab, 0.0])), "thread_eye": (1, E), "rocker_pin": (2, np.array([cd, 0.0]))}
    index = {"crank": 0, "lever": 1, "rocker": 2}
    mu = np.zeros((len(PHI), 9))
    qdd = np.zeros((len(PHI), 9))
    lever, rocker = fa.motion.coord("lever.angle").value, fa.motion.coord("rocker.angle").value
    for k, phi in enumerate(PHI):
        th = np.array([phi + p["crank.phase"], lever[k], rocker[k]])
        B = rot(th[0], ab, 0.0)
        assert np.allclose(B + rot(th[1], bc, 0.0), D + rot(th[2], cd, 0.0), rtol=0, atol=1e-14)  # loop closes

        def arm(i, s):  # point s (local) of body i relative to its centre of mass, world axes
            return rot(th[i], *(s - com[i]))

        Jac, gam_terms = np.zeros((9, 9)), []
        for row, (_n, a, sa, b, sb) in enumerate(pins):
            for sign, i, s in ((1, b, sb), (-1, a, sa)):
                if i is None:
                    continue
                d = arm(i, s)
                Jac[2 * row:2 * row + 2, 3 * i:3 * i + 2] += sign * np.eye(2)
                Jac[2 * row:2 * row + 2, 3 * i + 2] += sign * np.array([-d[1], d[0]])
                gam_terms.append((row, sign, i, d))
        Jac[8, 2] = 1.0  # θ_crank − φ − phase = 0
        qd = np.linalg.solve(Jac, np.r_[np.zeros(8), w[k]])
        gamma = np.zeros(9)
        for row, sign, i, d in gam_terms:
            gamma[2 * row:2 * row + 2] += sign * d * qd[3 * i + 2] ** 2
        gamma[8] = al[k]
        Mq = np.diag([m for i in range(3) for m in (mass[i], mass[i], inertia[i])])
        Q = np.array([f for i in range(3) for f in (mass[i] * gv[0], mass[i] * gv[1], 0.0)])
        for ld in loads:
            if not in_window(DEG[k:k + 1], ld.window)[0]:
                continue
            if ld.at in points:
                i, s = points[ld.at]
                Q[3 * i:3 * i + 3] += [ld.fx, ld.fy, cross(arm(i, s), [ld.fx, ld.fy])]
            else:
                Q[3 * index[ld.at] + 2] += ld.torque
        sol = np.linalg.solve(np.block([[Mq, -Jac.T], [Jac, np.zeros((9, 9))]]), np.r_[Q, gamma])
        qdd[k], mu[k] = sol[:9], sol[9:]
    for i, name in enumerate(["crank", "lever", "rocker"]):
        b = fa.motion.body(name)
        assert_close(b.com.ax, qdd[:, 3 * i], 1e-9, what=f"{name} a_Gx")
        assert_close(b.alpha, qdd[:, 3 * i + 2], 1e-9, what=f"{name} alpha")
    scale = float(np.max(np.abs(mu[:, :8])))
    for row, (name, *_rest) in enumerate(pins):
        r = fa.reaction(name)
        assert_close(r.fx, mu[:, 2 * row], 1e-9, scale, f"{name}.fx")
        assert_close(r.fy, mu[:, 2 * row + 1], 1e-9, scale, f"{name}.fy")
    assert_close(fa.torque("shaft"), mu[:, 8], 1e-9, what="driving torque")


# -- 6. singular positions ----------------------------------------------------------------------------------------

# A parallelogram at its change point: at φ = 0 all four pins lie on the x axis (coupler and rocker collinear).
# Dimensions are powers of two (m) so that the toggle is exact in floating point.
PARALLELOGRAM = {"crank": 1 / 64, "coupler": 1 / 32, "rocker": 1 / 64, "pivot_x": 1 / 32, "pivot_y": 0.0}


@pytest.mark.parametrize("branch", [1, -1])
def test_change_point_raises_singular_position(four_bar, branch):
    """The sweep through the toggle at φ = 0 raises SingularPositionError naming 0°; without it, it solves."""
    deg = np.arange(-30.0, 31.0, 5.0)
    with pytest.raises(sewgen.SingularPositionError) as info:
        four_bar.kinetostatics(np.radians(deg), 10.0, params=PARALLELOGRAM, branch={"C": branch})
    err = info.value
    assert (err.mechanism, err.angle, err.index, err.count) == ("kt_four_bar", 0.0, 6, 1)
    assert "kt_four_bar" in str(err) and "shaft angle 0°" in str(err)
    fa = four_bar.kinetostatics(np.radians(deg[deg != 0]), 10.0, params=PARALLELOGRAM, branch={"C": branch})
    assert np.isfinite(fa.torque()).all()


def test_force_matrix_rank_drops_at_the_toggle(four_bar):
    """A(q) at the collinear configuration (coupler and rocker angles 0 at φ = 0) loses rank; nearby it is full."""
    near = four_bar.solve(np.radians([5.0]), 10.0, params=PARALLELOGRAM)
    nf = four_bar.manifest["sizes"]["nf"]
    A, _ = four_bar.force_matrix(near, 0, params=PARALLELOGRAM)
    assert np.linalg.matrix_rank(A) == nf
    q = np.zeros_like(near.q)  # coupler.angle = rocker.angle = 0: A, B, D, C on the x axis
    toggle = Motion(four_bar, np.zeros(1), near.omega, near.alpha, q, near.qd, near.qdd, near.obs)
    A0, _ = four_bar.force_matrix(toggle, 0, params=PARALLELOGRAM)
    assert np.linalg.matrix_rank(A0) == nf - 1


# -- 7. loads ---------------------------------------------------------------------------------------------------------

# full_turn: both ends inclusive, so (0°, 360°) is every angle (a span taken mod 360° would collapse it to 0° alone).
@pytest.mark.parametrize("window", [("350 deg", "20 deg"), ("135 deg", "155 deg"), ("0 deg", "360 deg"), None],
                         ids=["wrapping", "seed_000", "full_turn", "always"])
def test_load_window_inclusive_and_wrapping(window):
    """A load changes the frame's force on the parts by −F exactly where the window (ends included, wrapping) says."""
    tu = sewgen.mechanism("take_up")
    deg = np.arange(0.0, 360.0, 1.0)
    base = tu.kinetostatics(np.radians(deg))
    fa = tu.kinetostatics(np.radians(deg), loads=[Load("thread_eye", fx=0.4, fy=-2.94, window=window)])
    on = in_window(deg, window)
    if window == ("350 deg", "20 deg"):
        assert on[[350, 359, 0, 20]].all() and not on[[349, 21]].any()
    diff = fa.frame_force_on_parts - base.frame_force_on_parts
    assert_close(diff, -np.array([0.4 * on, -2.94 * on]).T, 1e-12, 3.0, "frame force on parts change")
    # radians give the same window
    if window is not None:
        rad = tuple(math.radians(float(w.split()[0])) for w in window)
        same = tu.kinetostatics(np.radians(deg), loads=[Load("thread_eye", fx=0.4, fy=-2.94, window=rad)])
        np.testing.assert_allclose(same.frame_force_on_parts, fa.frame_force_on_parts, rtol=0, atol=1e-12)


def test_seed_thread_force_changes_torque_by_its_virtual_power():
    """Seed 000: 2.94 N on the thread eye over 135°–155°; τ_with − τ_without = −F·v_E/ω, zero outside."""
    tu = sewgen.mechanism("take_up")
    deg = np.arange(0.0, 360.0, 1.0)
    w, al = speeds(np.radians(deg), True)
    load = Load("thread_eye", fx=0.0, fy=-2.94, window=("135 deg", "155 deg"), name="thread")
    base = tu.kinetostatics(np.radians(deg), w, al)
    fa = tu.kinetostatics(np.radians(deg), w, al, loads=[load])
    on = in_window(deg, load.window)
    power = -2.94 * fa.motion.point("thread_eye").vy * on
    assert on.sum() == 21 and np.all(np.abs(power[on]) > 1e-3)
    assert_close(fa.torque() - base.torque(), -power / w, 1e-12, what="torque change")
    assert_close(fa.load_powers()["thread"], power, 1e-14, what="load_powers")


def test_force_direction_and_body_torque():
    """Load.force(at, |F|, direction) is |F|(cos, sin); a body torque T changes the torque by −T ω_body/ω."""
    tu = sewgen.mechanism("take_up")
    f = Load.force("thread_eye", "2 N", "30 deg")
    assert (f.fx, f.fy) == pytest.approx((math.sqrt(3), 1.0), rel=1e-15)
    g = Load.force("thread_eye", 2.0, math.radians(210))
    assert (g.fx, g.fy) == pytest.approx((-math.sqrt(3), -1.0), rel=1e-15)
    w = np.full(len(PHI), W0)
    base = tu.kinetostatics(PHI, w)
    polar = tu.kinetostatics(PHI, w, loads=[f])
    cartesian = tu.kinetostatics(PHI, w, loads=[Load("thread_eye", fx=math.sqrt(3), fy=1.0)])
    assert_close(polar.torque(), cartesian.torque(), 1e-13, what="polar vs cartesian")
    fa = tu.kinetostatics(PHI, w, loads=[Load("lever", torque="0.1 N*m")])
    omega_lever = fa.motion.body("lever").omega
    assert_close(fa.torque() - base.torque(), -0.1 * omega_lever / w, 1e-12, what="body torque")
    assert_close(fa.load_powers()["lever"], 0.1 * omega_lever, 1e-14, what="body torque power")
    # a torque on the driven crank itself is taken off the driving torque one for one
    crank = tu.kinetostatics(PHI, w, loads=[Load("crank", torque=0.25)])
    assert_close(crank.torque() - base.torque(), np.full(len(PHI), -0.25), 1e-12, what="torque on the crank")


@pytest.mark.parametrize("load, label, says", [
    (Load("nowhere", fx=1.0), "load nowhere", "neither a point"),
    (Load("thread_eye", torque=0.1), "load thread_eye", "is a point"),
    (Load("lever", fx=1.0), "load lever", "is a body"),
    (Load("thread_eye", fx="3 mm", name="thread"), "load thread", "fx"),
    (Load("thread_eye", fy=1.0, window=("135 mm", "155 deg")), "load thread_eye", "window"),
])
def test_bad_loads_raise_parameter_error(load, label, says):
    """Unknown point, a torque on a point, a force on a body, a non-force unit: ParameterError naming the load."""
    with pytest.raises(sewgen.ParameterError) as info:
        sewgen.mechanism("take_up").kinetostatics(PHI[:3], loads=[load])
    assert (info.value.mechanism, info.value.parameter) == ("take_up", label)
    assert says in str(info.value)


# -- 8. the force matrix ----------------------------------------------------------------------------------------

def test_force_matrix_matches_solution(mech):
    """A f = b (f from the results in manifest column order) and f = numpy.linalg.solve(A, b), loads active."""
    params, loads = CASES[mech.name]
    w, al = speeds(PHI, True)
    gv = gravity(-120.0)
    fa = mech.kinetostatics(PHI, w, al, loads=loads, gravity_direction=TILT, params=params)
    slots = mech.manifest["loads"]
    checked = 0
    for k in range(0, len(PHI), 7):
        row = np.zeros(len(slots))
        for ld in loads:
            if in_window(DEG[k:k + 1], ld.window)[0]:
                for j, s in enumerate(slots):
                    if s["name"] == ld.at:
                        row[j] += {"fx": ld.fx, "fy": ld.fy, "torque": ld.torque}[s["component"]]
        checked += bool(row.any())
        A, b = mech.force_matrix(fa.motion, k, params=params, gravity=tuple(gv), load_row=row)
        f = []
        for r in mech.manifest["reactions"]:
            if r["kind"] == "drive":  # column: torque on the driven body; the shaft's is turned by its sense
                if r["b"] in mech.held_names:
                    f.append(fa.torque(r["b"])[k])
                else:
                    f.append(fa.motion.body(r["b"]).omega[k] / w[k] * fa.torque("shaft")[k])
                continue
            jr = fa.reaction(r["name"])
            f += [getattr(jr, c)[k] for c in r["columns"]]
        f = np.array(f)
        assert np.linalg.norm(A @ f - b, np.inf) <= 1e-12 * (np.linalg.norm(A, np.inf) * np.linalg.norm(f, np.inf)
                                                            + np.linalg.norm(b, np.inf))
        ref = np.linalg.solve(A, b)
        np.testing.assert_allclose(f, ref, rtol=1e-9, atol=1e-9 * np.max(np.abs(ref)))
    assert checked >= 3  # loads were active at several of the checked positions

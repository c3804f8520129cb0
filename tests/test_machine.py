"""The JB1-3 household machine, whole (sewgen.machine): power, bearings, torque, shaking, feed.

Every reference is computed here without sewgen's machine-level code (MachineAnalysis._shaft, energy_rate,
the shaking force and moments on the frame) and without its force code: energy rates from the kinematic
results and the group parameter vectors; the upper shaft's core point masses written out (m at radius r,
angle φ + β, rotating with the shaft); the shaft's bearing reactions from a 4 × 4 static balance solved with
numpy; a hand-worked machine (one needle-bar group at rest) by the lever rule and the crank-slider's statics;
the driving torque at rest by virtual work (finite differences of positions); the shaking force and the
weight on the frame from Newton's law over every moving part and, separately, from the frame's force on the
parts; the stitch length from a fine sweep of the feed dog.

Frame: x horizontal (feed direction +), y up, z along the upper shaft from the front bearing; SI units.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import sewgen
from sewgen.errors import ParameterError
from sewgen.machine import shaking
from sewgen.machine.feed import regulator_angle
from sewgen.machine.assembly import Group, Machine, Shaft, ShaftMass, load_machine

pytestmark = [pytest.mark.c]

MM = 1e-3
TWO_PI = 2.0 * math.pi
PHI = np.radians(np.arange(0.0, 360.0, 2.0))  # whole degrees: the load windows' ends fall on grid points
W0 = 1000.0 * TWO_PI / 60.0  # 1000 rpm


# -- helpers ------------------------------------------------------------------------------------------------
def assert_close(actual, expected, rel, what="", scale=None):
    """|actual − expected| <= rel · scale everywhere; scale defaults to max|expected|."""
    actual, expected = np.asarray(actual, dtype=float), np.asarray(expected, dtype=float)
    assert actual.shape == expected.shape, f"{what}: shape {actual.shape} != {expected.shape}"
    scale = max(float(np.max(np.abs(expected))), 1e-300) if scale is None else scale
    err = np.abs(actual - expected)
    worst = int(np.argmax(err))
    assert err.flat[worst] <= rel * scale, (
        f"{what}: max error {err.flat[worst]:.3e} at index {worst} (got {actual.flat[worst]!r}, "
        f"expected {expected.flat[worst]!r}, scale {scale:.3e}, rel {rel:g})")


def varying_speed(phi):
    """ω = ω0 (1 + 0.2 sin φ), α = dω/dt = ω dω/dφ."""
    w = W0 * (1.0 + 0.2 * np.sin(phi))
    return w, w * W0 * 0.2 * np.cos(phi)


def core_kinematics(phi, omega, alpha, sm):
    """Position, velocity, acceleration (n, 2) of a point mass m at radius r, angle φ + β on the shaft."""
    th = phi + sm.angle
    c, s = np.cos(th), np.sin(th)
    r = sm.radius
    pos = np.column_stack([r * c, r * s])
    vel = np.column_stack([-r * omega * s, r * omega * c])
    acc = np.column_stack([-r * omega**2 * c - r * alpha * s, -r * omega**2 * s + r * alpha * c])
    return pos, vel, acc


def group_values(a, g):
    """The group's parameters by name, from the vector its sweep ran with."""
    fa = a.groups[g.name]
    return fa, dict(zip(g.mechanism.param_names, fa.run_settings.params))


def moving_bodies(a, only=None):
    """(mass, inertia, BodyMotion) of every moving body of every group (or of group ``only``)."""
    for g in a.machine.groups if only is None else [only]:
        fa, vals = group_values(a, g)
        for body in fa.motion.body_names:
            yield vals[f"{body}.mass"], vals[f"{body}.inertia"], fa.motion.body(body)


def window_on(angles, window):
    """Inclusive window [start, end] (mod 2π) on the given shaft angles; always on without one."""
    if window is None:
        return np.ones(angles.shape, dtype=bool)
    start, end = window
    return (angles - start) % TWO_PI <= (end - start) % TWO_PI + 1e-9


def applied_loads(a):
    """(point motion or None, body motion or None, fx, fy, torque arrays) for every external load, each on
    over its window of the machine's shaft angle (seed 000: "relative to the upper-shaft angle")."""
    out = []
    for g in a.machine.groups:
        fa = a.groups[g.name]
        for ld in g.loads:
            on = window_on(a.phi, ld.window).astype(float)
            pt = fa.motion.point(ld.at) if ld.at in fa.motion.point_names else None
            bd = fa.motion.body(ld.at) if ld.at in fa.motion.body_names else None
            out.append((pt, bd, on * ld.fx, on * ld.fy, on * ld.torque))
    return out


def energy_rate(a):
    """d/dt (kinetic + potential energy) of every moving part, from the kinematic results alone (W)."""
    gx, gy = a.machine.gravity
    w, al = a.omega, a.alpha
    rate = a.machine.shaft.inertia * w * al
    for m, inertia, bm in moving_bodies(a):
        c = bm.com
        rate = rate + m * (c.vx * c.ax + c.vy * c.ay) + inertia * bm.omega * bm.alpha - m * (gx * c.vx + gy * c.vy)
    for sm in a.machine.shaft.masses:
        _, vel, _ = core_kinematics(a.phi, w, al, sm)
        rate = rate + sm.mass * sm.radius**2 * w * al - sm.mass * (gx * vel[:, 0] + gy * vel[:, 1])
    return rate


def load_power(a):
    p = np.zeros(len(a.phi))
    for pt, bd, fx, fy, tz in applied_loads(a):
        if pt is not None:
            p += fx * pt.vx + fy * pt.vy
        if bd is not None:
            p += tz * bd.omega
    return p


def core_torque(a):
    """Torque the shaft core needs: I α and the moment of its point masses' m(a − g) about the axis."""
    gx, gy = a.machine.gravity
    tau = a.machine.shaft.inertia * a.alpha
    for sm in a.machine.shaft.masses:
        th = a.phi + sm.angle
        tau = tau + sm.mass * sm.radius**2 * a.alpha - sm.mass * sm.radius * (np.cos(th) * gy - np.sin(th) * gx)
    return tau


def shaft_bearings(a, z0):
    """Frame-on-shaft bearing forces (front, rear), (n, 2) each, from ΣFx, ΣFy, ΣMx, ΣMy = 0 about (0, 0, z0)
    of the shaft assembly: crank forces on the core, the core masses' weight and d'Alembert forces."""
    sh, (gx, gy) = a.machine.shaft, a.machine.gravity
    n = len(a.phi)
    forces = []  # (z, (n, 2)) on the shaft core
    for g in a.machine.groups:
        fa = a.groups[g.name]
        for body, z in g.axial.items():
            f = fa.frame_force(f"{body}.pivot")
            forces.append((z, np.column_stack([f.fx, f.fy])))
    for sm in sh.masses:
        _, _, acc = core_kinematics(a.phi, a.omega, a.alpha, sm)
        forces.append((sm.z, sm.mass * (np.array([gx, gy])[None, :] - acc)))
    forces.append((sh.pulley, np.tile(np.asarray(sh.belt, dtype=float), (n, 1))))  # the belt's pull
    rhs = np.zeros((4, n))
    for z, f in forces:
        d = z - z0
        rhs[0] -= f[:, 0]
        rhs[1] -= f[:, 1]
        rhs[2] -= -d * f[:, 1]  # Mx = y Fz − z Fy = −z Fy
        rhs[3] -= d * f[:, 0]   # My = z Fx − x Fz = z Fx
    dA, dB = sh.front - z0, sh.rear - z0
    mat = np.array([[1.0, 0.0, 1.0, 0.0],
                    [0.0, 1.0, 0.0, 1.0],
                    [0.0, -dA, 0.0, -dB],
                    [dA, 0.0, dB, 0.0]])
    sol = np.linalg.solve(mat, rhs)  # rows: RAx, RAy, RBx, RBy
    return sol[:2].T, sol[2:].T


def shaft_pivots(g):
    return {f"{body}.pivot" for body in g.axial}


# -- fixtures -----------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def jb():
    return load_machine("jb1-3")


@pytest.fixture(scope="module")
def steady(jb):
    return jb.analyze(PHI)


@pytest.fixture(scope="module")
def unsteady(jb):
    w, al = varying_speed(PHI)
    return jb.analyze(PHI, speed=w, accel=al)


@pytest.fixture(scope="module")
def tilted(jb):
    """The machine on its side with its bearings moved (front 12 mm, rear 230 mm): gravity at −120°, so both
    components and the z − z_front lever arms count; varying speed."""
    g = 9.80665 * np.array([math.cos(math.radians(-120)), math.sin(math.radians(-120))])
    shaft = dataclasses.replace(jb.shaft, front=0.012, rear=0.230)
    w, al = varying_speed(PHI)
    return dataclasses.replace(jb, gravity=g, shaft=shaft).analyze(PHI, speed=w, accel=al)


@pytest.fixture(params=["steady", "unsteady", "tilted"])
def run(request):
    return request.getfixturevalue(request.param)


# -- 1. power balance -----------------------------------------------------------------------------------------
def test_the_analysis_runs_at_the_speed_it_was_given(steady, unsteady):
    assert_close(steady.omega, np.full(len(PHI), W0), 1e-15, "omega")
    assert_close(steady.alpha, np.zeros(len(PHI)), 0.0, "alpha", scale=1.0)
    w, al = varying_speed(PHI)
    assert_close(unsteady.omega, w, 1e-15, "omega")
    assert_close(unsteady.alpha, al, 1e-15, "alpha")
    for g in unsteady.machine.groups:  # every group swept at φ + phase with the same ω, α
        fa = unsteady.groups[g.name]
        assert_close(fa.phi, PHI + g.phase, 1e-15, g.name)
        assert_close(fa.motion.omega, w, 1e-15, g.name)


def test_power_balance_at_every_position(run):
    rate = energy_rate(run)
    drive = run.torque * run.omega
    loads = load_power(run)
    assert_close(run.load_power, loads, 1e-12, "load power")
    scale = max(np.abs(drive).max(), np.abs(rate).max())
    assert scale > 10.0  # W: a real machine at 1000 rpm, not an empty check
    assert_close(drive + loads, rate, 1e-9, "drive + loads vs dE/dt", scale=scale)
    assert run.power_balance_residual < 1e-9
    assert_close(run.energy_rate(), rate, 1e-12, "MachineAnalysis.energy_rate")


def test_power_balance_sees_the_core(unsteady):
    """The core's I α and its counterweight matter at the 1e-9 level: the check is not vacuous."""
    rate = energy_rate(unsteady)
    core = unsteady.machine.shaft.inertia * unsteady.omega * unsteady.alpha
    scale = np.abs(rate).max()
    assert np.abs(core).max() > 1e-4 * scale
    cw = [sm for sm in unsteady.machine.shaft.masses if sm.radius > 0]
    assert cw and cw[0].mass * cw[0].radius * 9.8 * W0 > 1e-5 * scale


# -- 2. bearings -----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("z0", [0.0, 0.0731, -0.25])
def test_bearings_from_a_static_balance_of_the_shaft(run, z0):
    front, rear = shaft_bearings(run, z0)
    scale = max(np.abs(front).max(), np.abs(rear).max())
    assert_close(run.bearing("front"), -front, 1e-9, "front bearing (load on the frame)", scale=scale)
    assert_close(run.bearing("rear"), -rear, 1e-9, "rear bearing (load on the frame)", scale=scale)


def test_bearing_names(steady):
    with pytest.raises(KeyError, match="front"):
        steady.bearing("middle")


def hand_machine(gravity=10.0):
    """One needle-bar group (massless rod, so it is a two-force member) on a shaft of 200 mm between bearings,
    crank and counterweight 20 mm in front of the front bearing, the core's 200 g midway; g = 10 m/s²."""
    nb = sewgen.mechanism("needle_bar")
    params = {"crank": 0.0167, "rod": 0.050, "offset": 0.0, "crank.phase": 0.0,
              "crank.mass": 0.030, "crank.com_u": 0.002, "crank.com_v": 0.0, "crank.inertia": 1e-6,
              "rod.mass": 0.0, "rod.inertia": 0.0, "needle_bar.mass": 0.050, "needle_bar.com_v": 0.0}
    group = Group("needle_bar", nb, 0.0, {"crank": -0.020}, params, {}, {}, [])
    shaft = Shaft(front=0.0, rear=0.200, inertia=1e-5,
                  masses=[ShaftMass("core", 0.200, 0.0, 0.0, 0.100),
                          ShaftMass("counterweight", 0.010, 0.010, math.pi, -0.020)])
    return Machine("hand", "", 0.0, math.radians(5.0), np.array([0.0, -gravity]), [group], shaft)


def test_bearings_by_the_lever_rule_at_rest():
    """Weights: crank 0.3 N + needle bar 0.5 N + counterweight 0.1 N at z = −20 mm, core 2 N at z = 100 mm.
    Front (z = 0): −(0.9 · 0.22 + 2 · 0.1)/0.2 = −1.99 N; rear (z = 200 mm): −(0.9 · (−0.02) + 2 · 0.1)/0.2
    = −0.91 N (down on the frame). The needle bar hangs below the shaft on the massless rod (C = B − (r cos φ,
    √(l² − r² cos² φ))): the rod, in tension W_bar l / √(l² − r² cos² φ), pulls the crank pin with
    H = −W_bar r cos φ / √(l² − r² cos² φ) sideways; the crank passes it to the shaft, split 1.1 H front,
    −0.1 H rear."""
    phi = np.radians(np.arange(0.0, 360.0, 15.0))
    a = hand_machine().analyze(phi, speed=0.0)
    r, l = 0.0167, 0.050
    root = np.sqrt(l**2 - (r * np.cos(phi))**2)
    assert_close(a.groups["needle_bar"].motion.point("link_pin").y, r * np.sin(phi) - root, 1e-12, "C below B")
    h = -0.5 * r * np.cos(phi) / root
    front, rear = a.bearing("front"), a.bearing("rear")
    assert_close(front[:, 1], np.full(len(phi), -1.99), 1e-12, "front y")
    assert_close(rear[:, 1], np.full(len(phi), -0.91), 1e-12, "rear y")
    assert_close(front[:, 0], 1.1 * h, 1e-12, "front x", scale=1.0)
    assert_close(rear[:, 0], -0.1 * h, 1e-12, "rear x", scale=1.0)
    # the holding torque: the rod's pull (H, −W_bar) at B, the crank's weight at c = 2 mm along it and the
    # counterweight opposite: τ = cos φ [W_bar r (1 − r sin φ / √(l² − r² cos² φ)) + W_crank c − W_cw r_cw]
    tau = np.cos(phi) * (0.5 * r * (1 - r * np.sin(phi) / root) + 0.3 * 0.002 - 0.1 * 0.010)
    assert_close(a.torque, tau, 1e-12, "holding torque")
    assert np.abs(a.shaking_force_on_frame).max() == 0.0  # at rest: no inertia
    assert_close(a.weight_on_frame[None, :], np.array([[0.0, -2.9]]), 1e-12, "weight on the frame")
    held = a.frame_force_on_parts + a.process_loads_on_parts()[0] + np.asarray(a.machine.shaft.belt)
    assert_close(held, np.tile([0.0, 2.9], (len(phi), 1)), 1e-12, "frame holds the weight")


# -- 3. driving torque ----------------------------------------------------------------------------------------
def test_torque_is_the_groups_plus_the_core(run):
    expected = sum(run.groups[g.name].torque("shaft") for g in run.machine.groups) + core_torque(run)
    assert_close(run.torque, expected, 1e-12, "machine torque")


def _static_potential(machine, phi):
    """Σ −m g·r_G over every moving part, the core's point masses included, at rest (J)."""
    a = machine.analyze(phi, speed=0.0)
    gx, gy = machine.gravity
    v = np.zeros(len(phi))
    for m, _inertia, bm in moving_bodies(a):
        v -= m * (gx * bm.com.x + gy * bm.com.y)
    for sm in machine.shaft.masses:
        pos, _, _ = core_kinematics(phi, 0.0, 0.0, sm)
        v -= sm.mass * (gx * pos[:, 0] + gy * pos[:, 1])
    return v


def test_torque_at_rest_by_virtual_work(jb):
    """At rest under gravity the driving torque holds the machine: τ = dV/dφ, V = −Σ m g·r_G."""
    quiet = dataclasses.replace(jb, groups=[dataclasses.replace(g, loads=[]) for g in jb.groups])
    phi = PHI + 0.0123  # off the grid of the cam's arc junctions
    tau = quiet.analyze(phi, speed=0.0).torque
    h = 1e-5
    dv = (_static_potential(quiet, phi + h) - _static_potential(quiet, phi - h)) / (2 * h)
    assert np.abs(tau).max() > 1e-3  # N·m: gravity alone, but not nothing
    assert_close(tau, dv, 1e-7, "torque at rest vs dV/dphi")  # central difference: ~1e-9 here


# -- 4. shaking force on the frame, weight on the frame, the frame's force on the parts -----------------------
def test_shaking_force_is_newtons_law_over_every_moving_part(run):
    g = run.machine.gravity
    total = np.zeros((len(run.phi), 2))
    for m, _inertia, bm in moving_bodies(run):
        total += m * (np.column_stack([bm.com.ax, bm.com.ay]) - g[None, :])
    for sm in run.machine.shaft.masses:
        _, _, acc = core_kinematics(run.phi, run.omega, run.alpha, sm)
        total += sm.mass * (acc - g[None, :])
    assert_close(-(run.shaking_force_on_frame + run.weight_on_frame), total, 1e-12, "inertia, weight on frame")
    for _pt, _bd, fx, fy, _tz in applied_loads(run):
        total -= np.column_stack([fx, fy])
    total -= np.asarray(run.machine.shaft.belt)[None, :]
    assert_close(run.frame_force_on_parts, total, 1e-12, "frame on the moving parts")


def test_frame_force_on_parts_is_what_the_frame_supplies(run):
    """Frame on the moving parts = −(what every non-shaft frame joint puts on the frame) − (bearing loads)."""
    total = -run.bearing("front") - run.bearing("rear")
    joints = 0
    for g in run.machine.groups:
        fa = run.groups[g.name]
        for name in fa.frame_joint_names:
            if name in shaft_pivots(g):
                continue
            f = fa.frame_force(name)
            total = total - np.column_stack([f.fx, f.fy])
            joints += 1
    assert joints == 8  # needle-bar guide; take-up D; hook O4, O11; feed regulator, O_feed, O_lift, O4 (B's copy)
    assert_close(run.frame_force_on_parts, total, 1e-11, "frame force on the parts vs frame joints")


def test_shaking_moment_about_a_point(run):
    """Shaking and weight moments on the frame = −Σ [r_G × m(a_G − g) + I α], from the kinematics and from the
    kernels' frame reactions; the moment of the frame's force on the parts also takes away the loads'."""
    o = np.array([0.013, -0.041])
    g = run.machine.gravity
    total = run.machine.shaft.inertia * run.alpha

    def cross(r, f):
        return (r[:, 0] - o[0]) * f[:, 1] - (r[:, 1] - o[1]) * f[:, 0]

    for m, inertia, bm in moving_bodies(run):
        r = np.column_stack([bm.com.x, bm.com.y])
        total = total + cross(r, m * (np.column_stack([bm.com.ax, bm.com.ay]) - g[None, :])) + inertia * bm.alpha
    for sm in run.machine.shaft.masses:
        pos, _, acc = core_kinematics(run.phi, run.omega, run.alpha, sm)
        total = total + cross(pos, sm.mass * (acc - g[None, :]))
    on_frame = run.shaking_moments_on_frame((*o, 0.0)) + shaking.weight_moments_on_frame(run, (*o, 0.0))
    assert_close(-on_frame[:, 2], total, 1e-11, "inertia and weight moment on the frame (kinematics)")
    kernels = run.inertia_and_weight_moments_on_frame((*o, 0.0))
    assert_close(-kernels[:, 2], total, 1e-11, "inertia and weight moment on the frame (frame reactions)")
    for pt, bd, fx, fy, tz in applied_loads(run):
        if pt is not None:
            total = total - cross(np.column_stack([pt.x, pt.y]), np.column_stack([fx, fy]))
        total = total - tz
    belt = np.tile(np.asarray(run.machine.shaft.belt, dtype=float), (len(run.phi), 1))
    total = total - cross(np.zeros_like(belt), belt)  # the belt pulls on the shaft axis
    assert_close(run.frame_moment_on_parts(about=tuple(o)), total, 1e-11, "moment of the frame's force on parts")


def test_shaking_moments_about_three_axes(run):
    """The moments on the frame about x and y: every group's moving parts act in the group's plane z (its
    driven bodies' mean z in the JB1-3 model) and each core mass at its own z; −M = Σ (r − O) × m(a_G − g) with
    forces in the x–y plane, so −Mx = −Σ (z − z_O) Fy and −My = Σ (z − z_O) Fx; the inertia part alone
    (the shaking moments on the frame) leaves out g."""
    o = np.array([0.013, -0.041, 0.052])
    g = run.machine.gravity
    mx, my = np.zeros(len(run.phi)), np.zeros(len(run.phi))
    for grp in run.machine.groups:
        z = np.mean(list(grp.axial.values()))
        for m, _inertia, bm in moving_bodies(run, grp):
            f = m * (np.column_stack([bm.com.ax, bm.com.ay]) - g[None, :])
            mx -= (z - o[2]) * f[:, 1]
            my += (z - o[2]) * f[:, 0]
    for sm in run.machine.shaft.masses:
        _, _, acc = core_kinematics(run.phi, run.omega, run.alpha, sm)
        f = sm.mass * (acc - g[None, :])
        mx -= (sm.z - o[2]) * f[:, 1]
        my += (sm.z - o[2]) * f[:, 0]
    got = -run.inertia_and_weight_moments_on_frame(about=tuple(o))
    assert got.shape == (len(run.phi), 3)
    assert np.abs(mx).max() > 0.1 and np.abs(my).max() > 0.1  # N·m: the groups' offsets do rock the base
    assert_close(got[:, 0], mx, 1e-11, "inertia and weight moment about x")
    assert_close(got[:, 1], my, 1e-11, "inertia and weight moment about y")
    weight = shaking.weight_moments_on_frame(run, tuple(o))
    shake = run.shaking_moments_on_frame(tuple(o))
    assert_close(-(shake + weight)[:, 0], mx, 1e-11, "shaking + weight moment about x")
    assert_close(-(shake + weight)[:, 1], my, 1e-11, "shaking + weight moment about y")


# -- load windows: the seed's angles are the machine's ------------------------------------------------------------
def test_load_windows_are_machine_shaft_angles(jb):
    """Seed 000 §二(二)1(1): the thread pull 2.94 N acts over 135°–155° 'relative to the upper-shaft angle'
    (相对于上轴转角), i.e. the machine's φ (needle top at 90°), as the model file's comment says. The take-up
    group runs at φ + 82°; its window must stay at machine φ = 135°–155°. The change in the frame's force on
    the parts when the load is removed shows where it acts."""
    phi = np.radians(np.arange(0.0, 360.0, 1.0))
    quiet = dataclasses.replace(jb, groups=[dataclasses.replace(g, loads=[]) if g.name == "take_up" else g
                                            for g in jb.groups])
    diff = jb.analyze(phi).frame_force_on_parts - quiet.analyze(phi).frame_force_on_parts  # −(thread pull) where on
    on_deg = np.flatnonzero(np.abs(diff[:, 1]) > 1.0)
    assert_close(diff[on_deg, 1], np.full(len(on_deg), 2.94), 1e-12, "thread pull")
    assert on_deg.tolist() == list(range(135, 156)), (
        f"thread pull acts at machine φ = {on_deg.min()}°–{on_deg.max()}°, the seed's window is 135°–155°")


# -- 5. feed and stitch length ------------------------------------------------------------------------------------
PHI_FINE = np.radians(np.arange(0.0, 360.0, 0.05))
STITCHES = [0.0, 1.0, 2.5, 4.0, -2.0, -4.0]  # mm


@pytest.fixture(scope="module")
def feed():
    return sewgen.mechanism("feed")


@pytest.fixture(scope="module")
def plate_y(feed):
    return float(feed.defaults()["plate_y"])


@pytest.fixture(scope="module")
def settings(feed):
    """stitch (mm) -> (regulator angle, motion on the fine sweep)."""
    out = {}
    for s in STITCHES:
        ang = regulator_angle(feed, s * MM)
        out[s] = ang, feed.solve(PHI_FINE, speed=1.0, held={"regulator": ang})
    return out


def measured_travel(motion, plate_y):
    """Feed-dog x travel between its rise through and its sink below the plate: linear interpolation of the
    plate crossings on the sweep. Returns (travel, rise angle, sink angle, height above the plate) in m, rad."""
    dog = motion.point("feed_dog")
    phi = motion.phi
    z, x = dog.y - plate_y, dog.x
    zn, xn = np.roll(z, -1), np.roll(x, -1)
    pn = np.roll(phi, -1)
    pn[-1] += TWO_PI
    up = np.flatnonzero((z < 0) & (zn >= 0))
    down = np.flatnonzero((z >= 0) & (zn < 0))
    assert len(up) == 1 and len(down) == 1, "the dog must rise through the plate once a turn"

    def crossing(i):
        t = z[i] / (z[i] - zn[i])
        return x[i] + t * (xn[i] - x[i]), phi[i] + t * (pn[i] - phi[i])

    (x0, rise), (x1, sink) = crossing(up[0]), crossing(down[0])
    return x1 - x0, rise, sink, z.max()


@pytest.mark.parametrize("stitch", STITCHES)
def test_dog_travel_above_the_plate_is_the_stitch(settings, plate_y, stitch):
    _ang, motion = settings[stitch]
    travel, rise, sink, height = measured_travel(motion, plate_y)
    assert abs(travel - stitch * MM) < 1e-9, f"travel {travel / MM:.9f} mm for a {stitch} mm stitch"
    assert 0.8 * MM <= height <= 1.3 * MM, f"dog {height / MM:.3f} mm above the plate"
    # the dog is up while the needle is out of the cloth (needle top at φ = 90°): rises before 90°, sinks
    # after it, and is up for less than half a turn
    assert rise < math.radians(90) < sink and sink - rise < math.pi


def test_regulator_direction_and_range(settings, feed, plate_y):
    angs = {s: a for s, (a, _m) in settings.items()}
    # zero stitch: the slot horizontal, up to second-order motions of the dog that do not cancel over its time
    # above the plate (φ ≈ 10°–179° since the lift comes from the rock shaft, seed 001's chain B → D)
    assert abs(angs[0.0]) < math.radians(1e-2)
    order = sorted(STITCHES)
    assert all(angs[p] < angs[q] for p, q in zip(order, order[1:])), "stitch grows with the regulator angle"
    assert 0 < angs[4.0] < math.radians(60.0)  # 4 mm is inside the regulator's ±60°
    for lim, sign in ((60.0, 1), (-60.0, -1)):
        m = feed.solve(PHI_FINE[::10], speed=1.0, held={"regulator": math.radians(lim)})
        assert sign * measured_travel(m, plate_y)[0] > 4.0 * MM


@pytest.mark.parametrize("stitch", [4.0, -3.0, 0.1, 4.5])
def test_regulator_angle_agrees_with_an_independent_brent_solve(feed, stitch):
    """sewgen.machine.feed solves the regulator without SciPy (a bracketing secant, for the analysis' start-up time):
    the same root as SciPy's Brent method to 1e-12 rad, and the stitch it gives is the one asked for."""
    from scipy.optimize import brentq

    from sewgen.machine.feed import stitch_length

    got = regulator_angle(feed, stitch * MM)
    ref = brentq(lambda a: stitch_length(feed, a).travel - stitch * MM, -math.radians(45), math.radians(45),
                 xtol=1e-15)
    assert abs(got - ref) < 1e-12
    assert abs(stitch_length(feed, got).travel - stitch * MM) < 1e-15


def test_too_long_a_stitch_is_refused(feed):
    with pytest.raises(ParameterError) as exc:
        regulator_angle(feed, 20.0 * MM)
    assert exc.value.parameter == "stitch" and "20 mm" in str(exc.value) and "feed" in str(exc.value)


def rock_pin(motion, p):
    """Feed-bar pin R on the feed rock shaft's upper arm: O + arm_r (−sin θ, cos θ)."""
    th = motion.body("feed_rock_shaft").angle
    return p["feed_shaft_x"] - p["feed_arm_r"] * np.sin(th), p["feed_shaft_y"] + p["feed_arm_r"] * np.cos(th)


@pytest.mark.parametrize("stitch", [2.0, 4.0])
def test_reverse_feed_mirrors_forward_feed(feed, plate_y, stitch):
    """Reversing the regulator (α → −α) reverses every first-order term of the feed rock shaft's swing, so the
    dog's path at −L is the path at +L with x reflected about its mid-x, up to terms that do not reverse:

    * x: the fork's tilt ψ from vertical shortens its height by fork_p (1 − cos ψ) whichever way the slot
      tilts, turning the rock shaft by that / feed_arm_p and moving R by arm_r/arm_p times it; the dog sits
      dog_u along the feed bar, whose tilt β moves it by dog_u (1 − cos β). Bound: the sum of the two.
    * y: the feed bar rests on the lift roller L: the dog's height over R is dog_u Δ / d with Δ = y_L + slot_v
      − y_R and d = x_L − x_R; reflecting R's x about its mid changes d from d to 2 d_mid − d, so the heights
      differ by at most dog_u max|Δ| (1/d_min − 1/d_max), plus R's arc sagitta arm_r (1 − cos θ_max).
    """
    p = feed.defaults()
    fwd = regulator_angle(feed, stitch * MM)
    rev = regulator_angle(feed, -stitch * MM)
    mf = feed.solve(PHI_FINE, speed=1.0, held={"regulator": fwd})
    mr = feed.solve(PHI_FINE, speed=1.0, held={"regulator": rev})
    assert abs(measured_travel(mr, plate_y)[0] + stitch * MM) < 1e-9
    df, dr = mf.point("feed_dog"), mr.point("feed_dog")
    mid_f, mid_r = (df.x.max() + df.x.min()) / 2, (dr.x.max() + dr.x.min()) / 2
    asym_x = np.abs((dr.x - mid_r) + (df.x - mid_f)).max()
    asym_y = np.abs(dr.y - df.y).max()

    psi = np.abs(mf.body("feed_fork").angle + math.pi / 2).max()
    beta = np.abs(mf.body("feed_bar").angle).max()
    bound_x = p["fork_p"] * (1 - math.cos(psi)) * p["feed_arm_r"] / p["feed_arm_p"] + p["dog_u"] * (1 - math.cos(beta))
    rx, ry = rock_pin(mf, p)
    lr = mf.point("lift_roller")
    d = lr.x - rx
    delta = lr.y + p["bar_slot_v"] - ry
    theta = np.abs(mf.body("feed_rock_shaft").angle).max()
    bound_y = p["dog_u"] * np.abs(delta).max() * (1 / d.min() - 1 / d.max()) + p["feed_arm_r"] * (1 - math.cos(theta))
    assert bound_x < 0.1 * MM and bound_y < 0.25 * stitch * MM / 2  # the bounds are small against the stitch
    assert asym_x <= bound_x, f"x asymmetry {asym_x / MM:.4f} mm > bound {bound_x / MM:.4f} mm"
    assert asym_y <= bound_y, f"y asymmetry {asym_y / MM:.4f} mm > bound {bound_y / MM:.4f} mm"
    # the regulator angles: opposite to first order. What is left comes from the even part e of the travel
    # L(α): with L(α(L)) = L, L(−α(L)) = 2 e − L, so α(−L) = −α(L) + ε with ε ≈ −2 e / L'(−α(L)); the
    # non-reversing x motion, at most bound_x at each crossing, bounds |e| by bound_x.
    def travel(ang):
        return measured_travel(feed.solve(PHI_FINE, speed=1.0, held={"regulator": ang}), plate_y)[0]

    e = (stitch * MM + travel(-fwd)) / 2
    k = (travel(-fwd + 1e-3) - travel(-fwd - 1e-3)) / 2e-3
    assert k > 0
    assert abs(fwd + rev) < 2 * bound_x / k
    assert abs((fwd + rev) - (-2 * e / k)) < 0.01 * abs(fwd + rev) + 1e-8


def test_the_machines_feed_is_set_for_its_stitch(jb, plate_y):
    """jb1-3.toml: stitch = "4 mm" → the machine's feed group holds the regulator where the dog travels 4 mm."""
    g = next(g for g in jb.groups if g.name == "feed")
    assert g.stitch == pytest.approx(4.0 * MM, rel=1e-15)
    m = g.mechanism.solve(PHI_FINE, speed=1.0, held=g.held, params=g.params or None)
    assert abs(measured_travel(m, plate_y)[0] - 4.0 * MM) < 1e-9

"""Kinematic invariants of every catalog mechanism: things that hold whatever the dimensions.

* the constraint Jacobian Phi_q that the C residual kernel returns is the derivative of its residual;
* every reported velocity and acceleration is the time derivative of the reported position (finite
  differences, at constant speed and with per-position speed and acceleration arrays);
* the compiled C agrees with a SymPy ``lambdify`` of the same symbolic expressions (derive.kinematics);
* the loop closes to 1e-13 m (1e-10 mm) at every position of a revolution, closed form and Newton;
* no assembly-branch flip over a revolution: closed form and Newton agree, angles are continuous and
  periodic, det(Phi_q) keeps its sign.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

import sewgen
from sewgen.derive.catalog import declare
from sewgen.derive.kinematics import Kinematics

pytestmark = [pytest.mark.c, pytest.mark.derive]

CATALOG = ("needle_bar", "take_up", "hook_drive")

# non-default parameters for the checks that should not only run at the defaults (all still assemble)
OVERRIDES = {
    "needle_bar": {"offset": "4 mm", "crank.phase": "10 deg", "rod": "47 mm"},
    "take_up": {"crank.phase": "-15 deg", "lever_ce": "24 mm", "rocker_pivot_x": "27 mm"},
    "hook_drive": {"crank.phase": "25 deg", "rock_rear_arm": "39.5 mm", "big_rod": "218.5 mm"},
}


def mech(name):
    return sewgen.mechanism(name)


def obs_columns(m):
    """name -> column of motion.obs, from the manifest."""
    return {o["name"]: k for k, o in enumerate(m.manifest["observables"])}


def derivative_triples(m):
    """(position column, velocity column, acceleration column) for every observable family."""
    cols = obs_columns(m)
    out = []
    for name, k in cols.items():
        if name.endswith("_d") or name.endswith("_dd"):
            continue
        out.append((name, k, cols[name + "_d"], cols[name + "_dd"]))
    return out


def angle_columns(m):
    cols = obs_columns(m)
    return {n for n in cols if n.endswith(".angle")}


def check(actual, expected, rel, what, scale=None):
    actual, expected = np.asarray(actual, float), np.asarray(expected, float)
    scale = max(float(np.max(np.abs(expected))) if scale is None else scale, 1e-300)
    err = np.abs(actual - expected)
    i = int(np.argmax(err))
    assert err.flat[i] <= rel * scale, (f"{what}: error {err.flat[i]:.3e} > {rel:g} * scale {scale:.3e} "
                                        f"at {i} (got {actual.flat[i]!r}, expected {expected.flat[i]!r})")


def wrap(d):
    return np.angle(np.exp(1j * d))


# ====================================================================================================
# Phi_q against central differences of the residual
# ====================================================================================================
@pytest.mark.parametrize("name", CATALOG)
def test_jacobian_matches_central_differences_of_residual(name):
    m = mech(name)
    params = OVERRIDES[name]
    phi = np.radians(np.arange(0.0, 360.0, 30.0) + 7.0)
    motion = m.solve(phi, params=params)
    rng = np.random.default_rng(1)
    nq = len(m.coord_names)
    h = 1e-6
    checked = 0
    for q0, ph in zip(motion.q, phi):
        # at the solution and away from it (the Jacobian of the residual holds everywhere)
        for q in (q0, q0 + rng.normal(scale=0.05, size=nq) * np.where(
                [c["unit"] == "rad" for c in m.manifest["coords"]], 1.0, 0.01)):
            r, jac = m.residual(q, ph, params=params)
            fd = np.empty((nq, nq))
            for j in range(nq):
                dq = np.zeros(nq)
                dq[j] = h
                rp, _ = m.residual(q + dq, ph, params=params)
                rm, _ = m.residual(q - dq, ph, params=params)
                fd[:, j] = (rp - rm) / (2 * h)
            assert np.max(np.abs(jac - fd)) <= 1e-8, (name, ph, jac, fd)
            checked += 1
        # the residual vanishes at the solver's solution
        assert np.max(np.abs(m.residual(q0, ph, params=params)[0])) <= 1e-13
    assert checked == 2 * len(phi)


# ====================================================================================================
# Velocities and accelerations against finite differences of positions
# ====================================================================================================
def stencil(center, h):
    """center - h, center, center + h interleaved (increasing, so the sweep stays continuous)."""
    return (center[:, None] + np.array([-h, 0.0, h])[None, :]).ravel()


def fd_checks(m, motion, n, dt_of_step, h, what):
    """Central differences over the three-point stencils of a sweep laid out by stencil()."""
    q = motion.q.reshape(n, 3, -1)
    qd = motion.qd.reshape(n, 3, -1)
    qdd = motion.qdd.reshape(n, 3, -1)
    obs = motion.obs.reshape(n, 3, -1)
    is_angle = np.array([c["unit"] == "rad" for c in m.manifest["coords"]])

    def diff(a, is_ang):
        d = a[:, 2] - a[:, 0]
        return np.where(is_ang, wrap(d), d) / (2 * h)

    # coordinates
    for i, cname in enumerate(m.coord_names):
        vel = diff(q[:, :, i], is_angle[i]) * dt_of_step
        check(qd[:, 1, i], vel, 1e-6, f"{what}: {cname} rate vs d/dt of position")
        acc = diff(qd[:, :, i], False) * dt_of_step
        check(qdd[:, 1, i], acc, 1e-6, f"{what}: {cname} accel vs d/dt of rate")
    # every point, body angle and centre of mass
    angles = angle_columns(m)
    for oname, kp, kv, ka in derivative_triples(m):
        ang = oname in angles
        vel = diff(obs[:, :, kp], ang) * dt_of_step
        check(obs[:, 1, kv], vel, 1e-6, f"{what}: {oname} velocity vs d/dt of position")
        acc = diff(obs[:, :, kv], False) * dt_of_step
        check(obs[:, 1, ka], acc, 1e-6, f"{what}: {oname} acceleration vs d/dt of velocity")


@pytest.mark.parametrize("name", CATALOG)
def test_rates_match_finite_differences_at_constant_speed(name):
    m = mech(name)
    omega = 1000 * 2 * math.pi / 60
    centers = np.radians(np.arange(0.0, 360.0, 7.5) + 0.37)
    h = 1e-4  # rad of shaft angle
    phi = stencil(centers, h)
    motion = m.solve(phi, omega, 0.0, params=OVERRIDES[name])
    # d/dt = omega d/dphi at constant speed
    fd_checks(m, motion, len(centers), omega, h, "constant speed")
    # second difference of positions straight to the accelerations
    # (angles are continuous within a stencil, so no wrapping is needed here)
    q = motion.q.reshape(len(centers), 3, -1)
    qdd = motion.qdd.reshape(len(centers), 3, -1)
    for i, cname in enumerate(m.coord_names):
        acc = (q[:, 2, i] - 2 * q[:, 1, i] + q[:, 0, i]) / h**2 * omega**2
        check(qdd[:, 1, i], acc, 1e-5, f"{cname} accel vs second difference of position")


@pytest.mark.parametrize("name", CATALOG)
def test_rates_match_time_differences_with_varying_speed(name):
    """phi(t) = w0 t + A sin(W t): speed w0 + A W cos(W t) and acceleration -A W^2 sin(W t) as
    per-position arrays; velocities and accelerations differenced in time."""
    m = mech(name)
    w0, A, W = 100.0, 0.2, 300.0
    period = 2 * math.pi / w0
    t_c = np.linspace(0.0, period, 41) + 1.3e-4  # a full revolution of the shaft
    h = 1e-6  # s
    t = stencil(t_c, h)
    phi = w0 * t + A * np.sin(W * t)
    omega = w0 + A * W * np.cos(W * t)
    alpha = -A * W**2 * np.sin(W * t)
    assert np.all(np.diff(phi) > 0) and np.ptp(phi) > 6.0
    motion = m.solve(phi, omega, alpha, params=OVERRIDES[name])
    fd_checks(m, motion, len(t_c), 1.0, h, "varying speed")


# ====================================================================================================
# Compiled C against SymPy lambdify of the same expressions
# ====================================================================================================
_KIN: dict = {}


def kinematics(name):
    if name not in _KIN:
        _KIN[name] = Kinematics(declare(name))
    return _KIN[name]


def lambdified(kin, exprs):
    args = [*kin.q, *kin.qd, *kin.qdd, *kin.x, *kin.xd, *kin.xdd, *kin.p]
    return sp.lambdify(args, exprs, modules="numpy")


def call(fn, motion, m, params, n):
    """Evaluate a lambdified list at every position; returns an array (n, len(list))."""
    p = m.param_vector(params)
    held = [i["default"] for i in m.manifest["inputs"][1:]]
    zeros = [np.zeros(n)] * len(held)
    args = ([motion.q[:, j] for j in range(motion.q.shape[1])]
            + [motion.qd[:, j] for j in range(motion.qd.shape[1])]
            + [motion.qdd[:, j] for j in range(motion.qdd.shape[1])]
            + [motion.phi] + [np.full(n, v) for v in held]
            + [motion.omega] + zeros + [motion.alpha] + zeros + list(p))
    out = fn(*args)
    return np.column_stack([np.broadcast_to(np.asarray(v, dtype=float), (n,)) for v in out])


@pytest.mark.parametrize("name", CATALOG)
def test_compiled_c_matches_sympy_lambdify(name):
    m = mech(name)
    kin = kinematics(name)
    params = OVERRIDES[name]
    # the compiled module and the derivation describe the same mechanism, in the same order
    assert [c.name for c in kin.coords] == m.coord_names
    assert [o.name for o in kin.observables] == [o["name"] for o in m.manifest["observables"]]
    assert [prm.name for prm in kin.mech.params] == m.param_names

    phi = np.radians(np.arange(0.0, 360.0, 3.0) + 0.11)
    n = len(phi)
    omega = 90.0 + 40.0 * np.cos(phi)
    alpha = 3000.0 * np.sin(2 * phi)
    motion = m.solve(phi, omega, alpha, params=params)

    obs = call(lambdified(kin, [o.expr for o in kin.observables]), motion, m, params, n)
    assert obs.shape == motion.obs.shape
    for k, o in enumerate(kin.observables):
        scale = max(float(np.max(np.abs(obs[:, k]))), 1e-3 if o.unit.startswith("m") else 1.0)
        check(motion.obs[:, k], obs[:, k], 1e-12, f"obs {o.name}", scale=scale)

    # the loop closes at the solver's q in the symbolic closure too
    closure = call(lambdified(kin, kin.closure), motion, m, params, n)
    assert np.max(np.abs(closure)) <= 1e-13
    # Phi_q from SymPy against the compiled residual kernel's Jacobian
    nq = len(kin.q)
    jac = call(lambdified(kin, list(kin.jac_q)), motion, m, params, n).reshape(n, nq, nq)
    for i in (0, n // 3, 2 * n // 3):
        _, cj = m.residual(motion.q[i], phi[i], params=params)
        check(cj, jac[i], 1e-12, f"Phi_q at position {i}")
    # the solver's rates satisfy the symbolic velocity and acceleration equations
    jx = call(lambdified(kin, list(kin.jac_x)), motion, m, params, n).reshape(n, nq, len(kin.x))
    gamma = call(lambdified(kin, kin.gamma), motion, m, params, n)
    xd = np.column_stack([omega] + [np.zeros(n)] * (len(kin.x) - 1))
    vel_res = np.einsum("nij,nj->ni", jac, motion.qd) + np.einsum("nij,nj->ni", jx, xd)
    acc_res = np.einsum("nij,nj->ni", jac, motion.qdd) - gamma
    assert np.max(np.abs(vel_res)) <= 1e-12 * max(np.max(np.abs(np.einsum("nij,nj->ni", jx, xd))), 1e-300)
    assert np.max(np.abs(acc_res)) <= 1e-12 * max(np.max(np.abs(gamma)), 1e-300)


# ====================================================================================================
# Loop closure over a full revolution
# ====================================================================================================
@pytest.mark.parametrize("newton", [False, True], ids=["closed_form", "newton"])
@pytest.mark.parametrize("name", CATALOG)
def test_loop_residual_below_1e_10_mm_over_a_revolution(name, newton):
    m = mech(name)
    phi = sewgen.shaft_angles(0.1)  # 3600 positions
    assert len(phi) == 3600
    motion = m.solve(phi, newton=newton)
    worst, where = 0.0, None
    for q, ph in zip(motion.q, phi):
        r = np.max(np.abs(m.residual(q, ph)[0]))
        if r > worst:
            worst, where = r, ph
    assert worst <= 1e-13, (f"{name} ({'newton' if newton else 'closed form'}): loop residual "
                            f"{worst:.3e} m > 1e-13 m at shaft angle {math.degrees(where):.1f} deg")


# ====================================================================================================
# No branch flip over a revolution
# ====================================================================================================
@pytest.mark.parametrize("name", CATALOG)
def test_no_branch_flip_over_a_revolution(name):
    m = mech(name)
    phi = sewgen.shaft_angles(0.1, turns=1.25)  # 4500 positions, a quarter turn past one revolution
    closed = m.solve(phi)
    newton = m.solve(phi, newton=True)
    per_turn = 3600
    is_angle = np.array([c["unit"] == "rad" for c in m.manifest["coords"]])
    # Newton (tracking the previous position) and the closed form (explicit branch signs) agree
    assert np.max(np.abs(closed.q - newton.q)) <= 1e-9
    assert np.max(np.abs(closed.obs - newton.obs) / np.maximum(np.max(np.abs(closed.obs), axis=0), 1e-3)) <= 1e-8
    cols = obs_columns(m)
    for motion, how in ((closed, "closed form"), (newton, "newton")):
        # continuous: a 0.1 deg step moves no angle by more than a few hundredths of a radian
        steps = np.abs(np.diff(motion.q[:, is_angle], axis=0))
        assert np.max(steps) < 0.05, f"{how}: an angle coordinate jumps by {np.max(steps):.3f} rad"
        for a in angle_columns(m):
            jump = np.max(np.abs(np.diff(motion.obs[:, cols[a]])))
            assert jump < 0.05, f"{how}: {a} jumps by {jump:.3f} rad"
        # periodic: after one revolution every link angle and travel is back (no net 2*pi, same branch)
        check(motion.q[per_turn:], motion.q[: len(phi) - per_turn], 1e-9, f"{how}: periodicity", scale=1.0)
        # det(Phi_q) keeps its sign: the path never crosses to the other assembly
        dets = np.array([np.linalg.det(m.residual(q, ph)[1]) for q, ph in zip(motion.q[::10], phi[::10])])
        assert np.all(np.sign(dets) == np.sign(dets[0])) and np.all(dets != 0), f"{how}: det(Phi_q) changes sign"

"""Machine.analyze through its call plan (sewgen.machine.plan): the same numbers as an assembly written here from
each group's own Mechanism.kinetostatics, a plan that follows every change made to the machine in place, and
results that never share memory with an earlier analysis."""
from __future__ import annotations

import math
import pickle
from dataclasses import replace

import numpy as np
import pytest

from sewgen.errors import InputError
from sewgen.machine.assembly import load_machine

pytestmark = [pytest.mark.c]


def _group_sweeps(m, phi, speed, accel):
    """Every group swept by its mechanism's public kinetostatics, as seed 000 composes the machine: at
    φ + phase, its loads' windows moved by the phase, the machine's gravity."""
    g_mag = math.hypot(*m.gravity)
    g_dir = math.atan2(m.gravity[1], m.gravity[0]) if g_mag else -math.pi / 2
    out = {}
    for g in m.groups:
        loads = [replace(ld, window=None if ld.window is None else (ld.window[0] + g.phase, ld.window[1] + g.phase))
                 for ld in g.loads]
        out[g.name] = g.mechanism.kinetostatics(phi + g.phase, speed=speed, accel=accel, loads=loads,
                                                gravity=g_mag, gravity_direction=g_dir, params=g.params or None,
                                                held=g.held or None, branch=g.branch or None)
    return out


def _shaft(m, phi, groups, speed, accel):
    """The upper shaft by d'Alembert (sewgen.machine's docstring), written out: the bearings' forces on the shaft
    and the driving torque, with the core's point masses at r (cos(φ + θ), sin(φ + θ))."""
    sh, gv = m.shaft, np.asarray(m.gravity, dtype=float)
    n = len(phi)
    force, moment = np.zeros((n, 2)), np.zeros((n, 2))  # Σ F and Σ (z − z_A) F of everything but the bearings
    torque = sh.inertia * accel + sum(fa.torque("shaft") for fa in groups.values())
    for g in m.groups:
        for body, z in g.axial.items():
            f = groups[g.name].frame_force(f"{body}.pivot")
            F = np.column_stack([f.fx, f.fy])
            force += F
            moment += (z - sh.front) * F
    belt = np.array(sh.belt, dtype=float)
    force += belt
    moment += (sh.pulley - sh.front) * belt
    for sm in sh.masses:
        ang = phi + sm.angle
        u = np.column_stack([np.cos(ang), np.sin(ang)])
        t = np.column_stack([-np.sin(ang), np.cos(ang)])
        pos = sm.radius * u
        acc = sm.radius * accel * t - sm.radius * speed ** 2 * u
        d = sm.mass * (gv - acc)
        force += d
        moment += (sm.z - sh.front) * d
        torque = torque - (pos[:, 0] * d[:, 1] - pos[:, 1] * d[:, 0])
    rear = -moment / (sh.rear - sh.front)
    return -rear - force, rear, torque


def _arrays(fa):
    mo = fa.motion
    out = {k: getattr(mo, k) for k in ("phi", "omega", "alpha", "q", "qd", "qdd", "obs", "error_estimate")}
    out["frc"] = fa.frc
    if fa.run_settings.loads is not None:
        out["loads"] = fa.run_settings.loads
    return out


def _same_bits(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


@pytest.mark.parametrize("name,accel,positions", [("jb1-3", 0.0, 72), ("jb1-3", 600.0, 72), ("jb1-3", 0.0, 3600),
                                                  ("51-a", 0.0, 72)])
def test_analysis_equals_an_assembly_of_the_groups(name, accel, positions):
    m = load_machine(name)
    phi = m.shaft_angles(2 * np.pi / positions)
    m.analyze(phi)  # the plan is made; the analysis below reuses it
    a = m.analyze(phi, accel=accel)
    ref = _group_sweeps(m, phi, m.speed, accel)
    for gname, fa in ref.items():  # every group's arrays, bit for bit
        got, want = _arrays(a.groups[gname]), _arrays(fa)
        assert got.keys() == want.keys()
        for key in want:
            assert _same_bits(got[key], want[key]), f"{gname}.{key}"
        s, r = a.groups[gname].run_settings, fa.run_settings
        assert all(_same_bits(getattr(s, k), getattr(r, k)) for k in ("params", "held", "branch", "gravity"))
        assert [(ld, cols) for ld, cols, _ in s.placed] == [(ld, cols) for ld, cols, _ in r.placed]
    if any(g.along for g in m.groups):  # its cranks turn about the shaft in the group's plane: the groups suffice
        return
    front, rear, torque = _shaft(m, phi, ref, m.speed, accel)
    scale = max(np.abs(front).max(), np.abs(rear).max())
    np.testing.assert_allclose(a.front, front, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(a.rear, rear, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(a.torque, torque, rtol=0, atol=1e-12 * np.abs(torque).max())
    assert np.abs(a.front).max() > 1.0 and np.abs(a.torque).max() > 0.01  # real loads, not zeros


def test_the_plan_and_the_general_path_agree_bit_for_bit():
    """Per-position speeds take the general path (every group through kinetostatics, the shaft through
    crank_loads): the same numbers as the planned path, to the bit."""
    m = load_machine("jb1-3")
    phi = m.shaft_angles()
    fast = m.analyze(phi)
    general = m.analyze(phi, speed=np.full(len(phi), m.speed))
    for arr in ("front", "rear", "torque", "bearing_friction", "frame_force_on_parts", "shaking_force_on_frame"):
        assert _same_bits(getattr(fast, arr), getattr(general, arr)), arr
    about = (0.01, 0.02, 0.03)
    assert _same_bits(fast.inertia_and_weight_moments_on_frame(about),
                      general.inertia_and_weight_moments_on_frame(about))
    assert _same_bits(fast.frame_moment_on_parts(about[:2]), general.frame_moment_on_parts(about[:2]))


def test_the_plan_follows_changes_made_in_place():
    """A machine changed in place (gravity, a group's parameters, its loads, the shaft's masses) analyses as a
    machine built with those values: no cached plan outlives what it was made from."""
    phi = np.radians(np.arange(0.0, 360.0, 10.0))
    m = load_machine("jb1-3")
    before = m.analyze(phi)
    m.gravity = np.zeros(2)
    fresh = load_machine("jb1-3")
    fresh.gravity = np.zeros(2)
    assert _same_bits(m.analyze(phi).front, fresh.analyze(phi, speed=np.full(len(phi), fresh.speed)).front)
    assert not np.allclose(m.analyze(phi).front, before.front)

    m = load_machine("jb1-3")
    m.analyze(phi)
    take_up = next(g for g in m.groups if g.name == "take_up")
    take_up.params["crank"] = 0.0115
    take_up.loads.clear()
    m.shaft.masses.pop()
    want = load_machine("jb1-3")
    want = replace(want, shaft=replace(want.shaft, masses=want.shaft.masses[:-1]),
                   groups=[replace(g, params={**g.params, "crank": 0.0115}, loads=[]) if g.name == "take_up" else g
                           for g in want.groups])
    got, ref = m.analyze(phi), want.analyze(phi, speed=np.full(len(phi), want.speed))
    for arr in ("front", "rear", "torque"):
        assert _same_bits(getattr(got, arr), getattr(ref, arr)), arr
    assert got.groups["take_up"].run_settings.loads is None
    assert got.groups["take_up"].run_settings.params[take_up.mechanism.param_names.index("crank")] == 0.0115


def test_every_analysis_owns_its_arrays():
    m = load_machine("jb1-3")
    phi = m.shaft_angles()
    a, b = m.analyze(phi), m.analyze(phi)
    mine = [a.phi, a.front, a.rear, a.torque] + [x for fa in a.groups.values() for x in _arrays(fa).values()]
    theirs = [b.phi, b.front, b.rear, b.torque] + [x for fa in b.groups.values() for x in _arrays(fa).values()]
    assert not any(np.shares_memory(x, y) for x in mine for y in theirs)
    assert not np.shares_memory(a.phi, phi)
    keep = b.groups["feed"].motion.q.copy()
    a.groups["feed"].motion.q[:] = 0.0  # a user's change to one result touches no other
    phi += 1.0  # nor does a change to the angles asked for
    assert _same_bits(b.groups["feed"].motion.q, keep) and _same_bits(b.phi, m.shaft_angles())
    c = m.analyze(m.shaft_angles())
    assert _same_bits(c.groups["feed"].motion.q, keep)


def test_a_machine_with_a_plan_pickles_and_copies():
    import copy

    m = load_machine("jb1-3")
    phi = m.shaft_angles()
    a = m.analyze(phi)
    for other in (pickle.loads(pickle.dumps(m)), copy.deepcopy(m)):
        assert _same_bits(other.analyze(phi).torque, a.torque)


def test_bad_angles_still_raise_located_errors():
    m = load_machine("jb1-3")
    m.analyze()
    with pytest.raises(InputError) as err:
        m.analyze(np.array([0.0, np.nan]))
    assert err.value.key == "groups.needle_bar" and "not finite at position 1" in str(err.value)

"""Relative drives and speed ratios: a driven or held body may turn about a pin on a moving
body, relative to it; a shaft-driven body may turn at a ratio of the shaft speed.

The references are written here: a two-link arm whose forearm is driven at the elbow (θ2 = θ1 + 2φ + 30°)
against the closed form of its tip, velocity and acceleration; with a force at the tip and massless links, the
shoulder and elbow actuator torques from the moments about the shoulder and the elbow, and the shaft torque by
virtual work (T ω + F·v = 0); a held elbow (the input is a relative angle) likewise.
"""
from __future__ import annotations

import numpy as np
import pytest

import sewgen
from sewgen.derive import DeclarationError
from sewgen.derive.model import Mechanism
from sewgen.engine.loads import Load

pytestmark = [pytest.mark.c, pytest.mark.derive]

MM = 1e-3
L1, L2, PHASE = 40 * MM, 25 * MM, np.radians(30)
F = np.array([3.0, -5.0])
W, A = 40.0, 15.0  # rad/s, rad/s²


def arm():
    m = Mechanism("elbow_arm", "two links: the shoulder on the shaft, the forearm driven at the elbow at twice it")
    upper = m.driven("upper", m.ground.at(0, 0))
    fore = m.driven("fore", upper.at("40 mm", 0), phase="30 deg", ratio=2)
    m.point("elbow", upper.at("40 mm", 0))
    m.point("tip", fore.at("25 mm", 0))
    return m


def held_arm():
    m = Mechanism("held_elbow_arm", "two links: the shoulder on the shaft, the elbow held at a set angle")
    upper = m.driven("upper", m.ground.at(0, 0))
    fore = m.held("fore", upper.at("40 mm", 0), "-50 deg", "elbow angle")
    m.point("tip", fore.at("25 mm", 0))
    return m


def _e(a):
    return np.column_stack([np.cos(a), np.sin(a)])


def _perp(a):
    return np.column_stack([-np.sin(a), np.cos(a)])


def test_an_arm_driven_at_its_elbow_moves_as_the_closed_form(cache):
    mech = sewgen.load(arm, cache_dir=cache)
    phi = np.radians(np.arange(0, 360, 7.5))
    motion = mech.solve(phi, speed=W, accel=A)
    t2 = 3 * phi + PHASE  # θ1 + 2φ + 30°
    tip = L1 * _e(phi) + L2 * _e(t2)
    vel = W * (L1 * _perp(phi) + 3 * L2 * _perp(t2))
    acc = A * (L1 * _perp(phi) + 3 * L2 * _perp(t2)) - W**2 * (L1 * _e(phi) + 9 * L2 * _e(t2))
    p = motion.point("tip")
    np.testing.assert_allclose(np.column_stack([p.x, p.y]), tip, atol=1e-15)
    np.testing.assert_allclose(np.column_stack([p.vx, p.vy]), vel, atol=1e-13)
    np.testing.assert_allclose(np.column_stack([p.ax, p.ay]), acc, atol=1e-11)
    np.testing.assert_allclose(np.cos(motion.body("fore").angle), np.cos(t2), atol=1e-14)
    np.testing.assert_allclose(motion.body("fore").omega, 3 * W, rtol=1e-14)


def test_actuator_torques_of_a_relative_drive_by_virtual_work(cache):
    mech = sewgen.load(arm, cache_dir=cache)
    phi = np.radians(np.arange(0, 360, 7.5))
    fa = mech.kinetostatics(phi, speed=W, gravity=0, loads=[Load("tip", fx=F[0], fy=F[1])])
    t2 = 3 * phi + PHASE
    tip, elbow = L1 * _e(phi) + L2 * _e(t2), L1 * _e(phi)
    cross = (lambda r: r[:, 0] * F[1] - r[:, 1] * F[0])  # noqa: E731
    shoulder, at_elbow = -cross(tip), -cross(tip - elbow)  # moments about the shoulder and about the elbow
    np.testing.assert_allclose(fa.drive_torque("upper"), shoulder, atol=1e-13)
    np.testing.assert_allclose(fa.drive_torque("fore"), at_elbow, atol=1e-13)
    dtip = L1 * _perp(phi) + 3 * L2 * _perp(t2)  # dP/dφ
    np.testing.assert_allclose(fa.torque("shaft"), -(dtip @ F), atol=1e-13)  # T ω + F·v = 0
    np.testing.assert_allclose(fa.torque("shaft"), shoulder + 2 * at_elbow, atol=1e-13)
    # the elbow actuator is inside the machine: the frame feels the shoulder only, and it balances the load
    np.testing.assert_allclose(fa.frame_force_on_parts, np.tile(-F, (len(phi), 1)), atol=1e-13)


def test_a_held_relative_input_holds_the_elbow(cache):
    mech = sewgen.load(held_arm, cache_dir=cache)
    phi = np.radians(np.arange(0, 360, 15.0))
    fa = mech.kinetostatics(phi, speed=W, gravity=0, loads=[Load("tip", fx=F[0], fy=F[1])],
                            held={"fore": np.radians(-20)})
    t2 = phi + np.radians(-20)
    tip = L1 * _e(phi) + L2 * _e(t2)
    p = fa.motion.point("tip")
    np.testing.assert_allclose(np.column_stack([p.x, p.y]), tip, atol=1e-15)
    r = tip - L1 * _e(phi)
    np.testing.assert_allclose(fa.torque("fore"), -(r[:, 0] * F[1] - r[:, 1] * F[0]), atol=1e-13)
    dtip = L1 * _perp(phi) + L2 * _perp(t2)
    np.testing.assert_allclose(fa.torque("shaft"), -(dtip @ F), atol=1e-13)


def test_a_pivot_on_an_undeclared_body_or_a_zero_ratio_is_refused():
    m = Mechanism("bad_drive")
    other = Mechanism("other")
    stray = other.link("stray")
    with pytest.raises(DeclarationError, match="pivot of 'k' must be a point of ground or of a body declared"):
        m.driven("k", stray.at(0, 0))
    with pytest.raises(DeclarationError, match="ratio of 'k' must not be zero"):
        m.driven("k", m.ground.at(0, 0), ratio=0)
    with pytest.raises(DeclarationError, match="ratio of 'k' must be a number"):
        m.driven("k", m.ground.at(0, 0), ratio="two")

"""The rates' error estimate against an exact reference written here (mpmath at 40 digits: the mechanism's closed
form, rates by mpmath's differentiation of it): near a change point and near an oscillating guide's pivot the
estimate is at least the error it estimates, and a position whose error it puts above the tolerance raises
SingularPositionError instead of returning wrong numbers (csrc/sg_runtime.h sg_rates_error, sg_dyad_*)."""
from __future__ import annotations

import math

import mpmath as mp
import numpy as np
import pytest

import sewgen

pytestmark = pytest.mark.c

DPS = 40


def _take_up_rocker(p):
    """The take-up's rocker angle as a function of the shaft angle: its crank pin B, the rocker pivot D and the
    triangle BCD (the law of cosines on |BD|), branch +1 (C left of B->D)."""
    r, dx, dy, l1, l2 = (mp.mpf(p[k]) for k in ("crank", "rocker_pivot_x", "rocker_pivot_y", "lever_bc", "rocker"))

    def rocker(t):
        B = r * mp.expj(t)
        d = mp.mpc(dx, dy) - B
        cos_b = (l1 ** 2 + abs(d) ** 2 - l2 ** 2) / (2 * l1 * abs(d))  # at B, between BD and BC
        C = B + l1 * d / abs(d) * mp.expj(mp.acos(cos_b))
        return mp.arg(C - mp.mpc(dx, dy))
    return rocker


def _rates(f, phi, w):
    """(f, f', f'') of f(shaft angle) at phi for a shaft turning at w (no shaft acceleration)."""
    with mp.workdps(DPS):
        t = mp.mpf(float(phi))
        return float(f(t)), float(mp.diff(f, t) * w), float(mp.diff(f, t, 2) * w * w)


@pytest.fixture(scope="module")
def change_point():
    """The take-up with its rocker made so long that the four-bar just reaches its extended toggle (|BD| = BC + CD
    where the crank pin is farthest from the rocker pivot): a change point, the triangle flattening and opening
    again as the crank passes."""
    tu = sewgen.mechanism("take_up")
    p = dict(tu.defaults())
    e = math.hypot(p["rocker_pivot_x"], p["rocker_pivot_y"])
    p["rocker"] = p["crank"] + e - p["lever_bc"]
    return tu, p, math.atan2(-p["rocker_pivot_y"], -p["rocker_pivot_x"])


@pytest.mark.parametrize("newton", [False, True])
def test_change_point_raises_where_the_accelerations_lose_their_digits(change_point, newton):
    tu, p, toggle = change_point
    w = tu.default_speed
    phi = toggle + math.radians(0.017)
    with pytest.raises(sewgen.SingularPositionError) as info:
        tu.solve(np.array([phi]), params=p, newton=newton)  # was: rocker acceleration -124.5 rad/s², exact -40.2
    assert "estimated relative error" in str(info.value)
    m = tu.solve(np.array([phi]), params=p, newton=newton, singular="flag")
    _, rate, acc = _rates(_take_up_rocker(p), phi, w)
    got = m.coord("rocker.angle").accel[0]
    rel = abs(got - acc) / max(abs(acc), rate * rate)  # against the rocker's own centripetal scale
    assert rel > 1e-5  # the float64 result is that wrong here ...
    assert m.error_estimate[0] >= rel  # ... and says so (was 3.8e-9)


@pytest.mark.parametrize("newton", [False, True])
def test_change_point_estimate_bounds_the_error_on_the_way_in(change_point, newton):
    """From 30° to 0.001° before the toggle: each position either raises (its estimate above 1e-8) or is right to
    within its estimate, velocities and accelerations alike."""
    tu, p, toggle = change_point
    w = tu.default_speed
    offsets = np.array([30.0, 10.0, 3.0, 1.0, 0.3, 0.1, 0.03, 0.01, 0.003, 0.001])
    phi = toggle + np.radians(offsets)
    m = tu.solve(phi, params=p, newton=newton, singular="flag")
    rocker = _take_up_rocker(p)
    accepted = 0
    for k, ph in enumerate(phi):
        _, rate, acc = _rates(rocker, ph, w)
        c = m.coord("rocker.angle")
        err_v = abs(c.rate[k] - rate) / max(abs(rate), 1e-300)
        err_a = abs(c.accel[k] - acc) / max(abs(acc), rate * rate)
        assert max(err_v, err_a) <= max(m.error_estimate[k], 1e-13), (offsets[k], err_v, err_a, m.error_estimate[k])
        accepted += not m.singular[k]
    assert 3 <= accepted < len(phi)  # far from it accepted, near it refused


def _hook_pin(p):
    """The hook drive's slider pin E and the lower shaft's angle as functions of the shaft angle: the crank-rocker's
    rocker angle by the law of cosines, the rear arm at its angle from the front arm, the lower shaft along E minus
    its axis (branches +1)."""
    g = {k: mp.mpf(v) for k, v in p.items()}

    def pin(t):
        B = g["crank"] * mp.expj(t)
        O4 = mp.mpc(g["rock_axis_x"], g["rock_axis_y"])
        d = B - O4
        cos_o = (g["rock_front_arm"] ** 2 + abs(d) ** 2 - g["big_rod"] ** 2) / (2 * g["rock_front_arm"] * abs(d))
        front = mp.arg(d) - mp.acos(cos_o)  # C right of O4->B: left of B->O4 (branch +1)
        return O4 + g["rock_rear_arm"] * mp.expj(front + g["rock_rear_angle"])

    def lower(t):
        return mp.arg(pin(t) - mp.mpc(g["lower_axis_x"], g["lower_axis_y"]))
    return pin, lower


def _hook_near_pivot(distance):
    """The hook drive with its lower shaft's axis ``distance`` beside the slider pin's path at 2 rad (its params)."""
    hd = sewgen.mechanism("hook_drive")
    p = dict(hd.defaults())
    pin, _ = _hook_pin(p)
    with mp.workdps(DPS):
        t = mp.mpf(2.0)
        E, v = pin(t), mp.diff(pin, t)
        axis = E + mp.mpf(distance) * 1j * v / abs(v)
    p["lower_axis_x"], p["lower_axis_y"] = float(axis.real), float(axis.imag)
    return hd, p


@pytest.mark.parametrize("newton", [False, True])
def test_guide_pin_a_nanometre_from_its_pivot_raises(newton):
    """The hook drive's lower shaft axis placed 1 nm beside the slider pin's path at 2 rad: the guide's angle is
    the pin's position error over 1 nm."""
    hd, p = _hook_near_pivot(1e-9)
    w = hd.default_speed
    phi = np.array([2.0])
    with pytest.raises(sewgen.SingularPositionError):
        hd.solve(phi, params=p, newton=newton)  # was: lower shaft 3.78e12 rad/s², exact 2.85e11; estimate 9e-13
    m = hd.solve(phi, params=p, newton=newton, singular="flag")
    _, lower = _hook_pin(p)
    _, rate, acc = _rates(lower, 2.0, w)
    c = m.coord("lower_shaft.angle")
    rel = max(abs(c.rate[0] - rate) / abs(rate), abs(c.accel[0] - acc) / max(abs(acc), rate * rate))
    assert rel > 1e-7
    assert m.error_estimate[0] >= rel


def test_guide_pin_near_its_pivot_is_right_where_accepted():
    """The pin passing 1 µm from the pivot, at shaft angles moving away from its closest approach: every position is
    right to within its estimate, and the farthest is accepted."""
    hd, p = _hook_near_pivot(1e-6)
    w = hd.default_speed
    phi = 2.0 + np.array([0.0, 1e-4, 1e-3, 1e-2, 0.1, 0.3])
    m = hd.solve(phi, params=p, singular="flag")
    _, lower = _hook_pin(p)
    c = m.coord("lower_shaft.angle")
    for k, ph in enumerate(phi):
        _, rate, acc = _rates(lower, ph, w)
        rel = max(abs(c.rate[k] - rate) / abs(rate), abs(c.accel[k] - acc) / max(abs(acc), rate * rate))
        assert rel <= max(m.error_estimate[k], 1e-13), (ph, rel, m.error_estimate[k])
    assert not m.singular[-1]

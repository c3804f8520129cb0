"""Every angle result is continuous over a sweep and starts in (−π, π].

A drag-link four-bar (the shortest link is the frame: both cranks turn fully) makes the follower's closed-form
angle (an atan2) pass ±180° every turn; over two turns it must come out as one continuous curve that gains 4π,
with the follower pin where that angle puts it (so only whole turns were added)."""
from __future__ import annotations

import numpy as np
import pytest

import sewgen
from sewgen.derive.model import Mechanism

pytestmark = [pytest.mark.derive, pytest.mark.c]


def drag_link():
    m = Mechanism("drag_link", "a double-crank four-bar: frame 10 mm, cranks 30 and 33 mm, coupler 35 mm")
    crank = m.driven("crank", m.ground.at(0, 0), phase="170 deg")
    coupler = m.link("coupler", guess="0 deg")
    follower = m.link("follower", guess="170 deg")
    m.revolute(crank.at("30 mm", 0), coupler.at(0, 0), "B")
    m.revolute(coupler.at("35 mm", 0), follower.at("33 mm", 0), "C")
    m.revolute(m.ground.at("10 mm", 0), follower.at(0, 0), "D")
    m.point("pin_c", follower.at("33 mm", 0))
    return m


@pytest.mark.parametrize("newton", [False, True])
def test_angles_are_continuous_and_start_in_the_principal_range(cache, newton):
    mech = sewgen.load(drag_link, cache_dir=cache)
    phi = np.radians(np.arange(0, 720, 5.0))
    motion = mech.solve(phi, speed=10.0, newton=newton)
    for body in ("crank", "coupler", "follower"):
        angle = motion.body(body).angle
        assert -np.pi < angle[0] <= np.pi, body
        assert np.abs(np.diff(angle)).max() < np.radians(30), body
    follower = motion.body("follower").angle
    assert abs(follower[-1] - follower[0]) > 3.5 * np.pi  # it turned (nearly) twice, one continuous curve
    assert np.degrees(motion.body("crank").angle[0]) == pytest.approx(170.0)
    c = motion.point("pin_c")  # the pin where the unwrapped angle says: only whole turns were added
    np.testing.assert_allclose(c.x, 0.010 + 0.033 * np.cos(follower), atol=1e-15)
    np.testing.assert_allclose(c.y, 0.033 * np.sin(follower), atol=1e-15)
    np.testing.assert_allclose(motion.coord("follower.angle").value, follower, atol=1e-15)


def _unwrapped(col):
    """One column as continuous_angles makes it (np.unwrap, then whole turns to bring the first into (−π, π]),
    where it jumps by more than π or starts out of range; else unchanged."""
    if not (np.abs(np.diff(col)) > np.pi).any() and -np.pi < col[0] <= np.pi:
        return col
    out = np.unwrap(col)
    return out - 2 * np.pi * np.ceil((out[0] - np.pi) / (2 * np.pi))


def test_the_c_continuity_pass_equals_numpy_column_by_column():
    """sg_make_continuous scans row columns two at a time (one SSE2 pass for two columns of the same stride) and
    a column of its own four steps at a time: on random angle columns where one of a pair jumps, the other not,
    one starts a turn away, one jumps by exactly π, its result equals np.unwrap's, column by column, to the bit."""
    mech = sewgen.mechanism("take_up")
    ffi, lib = mech.ffi, mech.lib
    rng = np.random.default_rng(5)
    n, nq, nobs = 203, 3, 8
    for trial in range(20):
        q = np.cumsum(rng.normal(0, 0.3, (n, nq)), axis=0)
        obs = np.cumsum(rng.normal(0, 0.3, (n, nobs)), axis=0)
        obs[:, 3] = np.angle(np.exp(1j * obs[:, 3]))  # wrapped: jumps of nearly 2π
        q[:, 0] = np.angle(np.exp(1j * q[:, 0]))
        q[50:, 2] += 2 * np.pi * (trial % 3)  # one jump of whole turns (or none)
        obs[:, 6] += 2 * np.pi * (trial % 2)  # a turn away from the start's range, no jump
        obs[100, 1] = obs[99, 1] + np.pi  # exactly π: not a jump (> π is)
        qcols, ocols = [0, 2], [1, 3, 5, 6, 7]
        want_q, want_o = q.copy(), obs.copy()
        for j in qcols:
            want_q[:, j] = _unwrapped(q[:, j])
        for j in ocols:
            want_o[:, j] = _unwrapped(obs[:, j])
        qc, oc = np.array(qcols, dtype=np.intc), np.array(ocols, dtype=np.intc)
        lib.sg_make_continuous(n, nq, nobs, ffi.from_buffer("double[]", q), ffi.from_buffer("double[]", obs),
                               len(qcols), ffi.from_buffer("int[]", qc), len(ocols), ffi.from_buffer("int[]", oc),
                               ffi.NULL)
        assert np.array_equal(q, want_q) and np.array_equal(obs, want_o), trial

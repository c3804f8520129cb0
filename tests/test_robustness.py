"""Trustworthy on any input: each defect the adversarial campaign found, as a regression test.

Branch identity on the Newton path (two dyads flipping together, coarse and unsorted angles), honest singular
positions (an error estimate, change points named), per-loop Newton tolerance, array sizes checked before C
reads them, typed API errors, results that own their arrays, derived dimensions that must be real, and the feed
designs whose intended assembly does not exist (another assembly mode, said so).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import sewgen
import fuzz

pytestmark = [pytest.mark.c, pytest.mark.derive]

PHI = sewgen.shaft_angles(5)
MM = 1e-3


@pytest.fixture(scope="module")
def four_bar(cache):
    return sewgen.load(fuzz.declare_four_bar, cache_dir=cache)


def _same_motion(a, b, rtol=1e-9):
    for x, y in ((a.obs, b.obs), (a.qd, b.qd), (a.qdd, b.qdd)):
        scale = np.maximum(np.abs(y).max(axis=0), 1e-9)
        assert np.all(np.abs(x - y) <= rtol * scale)


# -- branch identity -----------------------------------------------------------------------------------------

def test_hook_drive_newton_in_60_degree_steps_keeps_its_branch():
    hd = sewgen.mechanism("hook_drive")
    phi = np.radians(40 + 60 * np.arange(6))
    closed = hd.solve(phi)
    newton = hd.solve(phi, newton=True)
    _same_motion(newton, closed)  # was: positions 3-4 on branch C = -1, E = -1 (slider pin y -0.1528 vs -0.1866)


def test_feed_at_scattered_angles_is_the_dense_sweep():
    fd = sewgen.mechanism("feed")
    angles = [91.0, 35.0, 77.0, 352.0]
    dense = fd.solve(np.radians(np.arange(0.0, 360.0, 1.0)))
    few = fd.solve(np.radians(angles))
    rows = [int(a) for a in angles]
    np.testing.assert_allclose(few.point("feed_dog").y, dense.point("feed_dog").y[rows], rtol=0, atol=1e-12)
    # was: feed bar 104° off at 352°. Angles agree up to whole turns: each sweep's angles are continuous along
    # itself and start in (−180°, 180°] (sewgen.engine.mechanism.continuous_angles), a sparse one unwraps differently
    diff = few.q - dense.q[rows]
    angle = np.array([c.unit == "rad" for c in fd.description.coords])
    diff[:, angle] = (diff[:, angle] + np.pi) % (2 * np.pi) - np.pi
    np.testing.assert_allclose(diff, 0.0, rtol=0, atol=1e-10)


def test_unsorted_and_repeated_angles_are_solved_sorted_and_returned_in_order():
    fd = sewgen.mechanism("feed")
    perm = np.random.default_rng(11).permutation(len(PHI))
    sorted_run = fd.solve(PHI)
    shuffled = fd.solve(PHI[perm])  # was: BranchJumpError at 330°
    assert np.array_equal(shuffled.phi, PHI[perm])
    _same_motion(shuffled, sweep_rows(sorted_run, perm))
    rep = np.concatenate([PHI[:5], PHI[:5], PHI[3:1:-1]])
    again = fd.solve(rep)
    for k, ph in enumerate(rep):
        np.testing.assert_allclose(again.q[k], sorted_run.q[int(round(math.degrees(ph) / 5))], rtol=0, atol=1e-10)
    # the closed form too: the same angles, the same angles' rows
    hd = sewgen.mechanism("hook_drive")
    _same_motion(hd.solve(PHI[perm]), sweep_rows(hd.solve(PHI), perm))


def test_descending_newton_sweep_names_the_angle_newton_first_fails_at():
    """The feed's lift chain (hook crank, big rod, a rock arm shortened to 10 mm) does not close where the crank pin
    is farther from the rock shaft than rod + arm: 35° to 140° (the triangle, written here). Newton solves a
    descending sweep in ascending order, so it fails first at 35°, whichever way the caller gave the angles (was:
    315°, the first failing position in the caller's order, a failure that only followed the first)."""
    fd = sewgen.mechanism("feed")
    p = fd.defaults()
    phi = np.radians(np.arange(0.0, 360.0, 5.0))
    pin = p["hook_crank"] * np.exp(1j * (phi + p["hook_crank.phase"]))
    open_ = np.abs(complex(p["rock_axis_x"], p["rock_axis_y"]) - pin) > p["big_rod"] + 0.010
    first = phi[np.flatnonzero(open_)[0]]
    assert math.degrees(first) == pytest.approx(35.0)
    for order in (phi, phi[::-1], np.random.default_rng(5).permutation(phi)):
        with pytest.raises(sewgen.AssemblyError) as info:
            fd.solve(order, params={"rock_front_arm": 0.010})
        assert info.value.angle == first and order[info.value.index] == first
        assert "35°" in str(info.value)


def sweep_rows(motion, rows):
    class Rows:
        obs, qd, qdd = motion.obs[rows], motion.qd[rows], motion.qdd[rows]
    return Rows


def test_newton_follows_the_declared_branch_where_the_closed_form_starts_elsewhere(four_bar):
    """A four-bar whose declared branch does not close at the first angles: Newton must not take the other
    assembly there (its orientation signs come from the closed form where it assembles)."""
    p = {"crank": 20 * MM, "coupler": 30 * MM, "rocker": 25 * MM, "ground_x": 40 * MM, "ground_y": 0.0,
         "point_u": 10 * MM, "point_v": 5 * MM}
    for sigma in (1, -1):
        for newton in (False, True):
            with pytest.raises(sewgen.PositionError) as e:
                four_bar.solve(PHI, params=p, branch={"C": sigma}, newton=newton)
            assert type(e.value) in (sewgen.AssemblyError, sewgen.SingularPositionError, sewgen.ConvergenceError)
        ok = np.radians(np.arange(60.0, 120.0, 5.0))  # where it assembles: Newton = closed form, on the branch
        _same_motion(four_bar.solve(ok, params=p, branch={"C": sigma}, newton=True),
                     four_bar.solve(ok, params=p, branch={"C": sigma}))


# -- singular positions --------------------------------------------------------------------------------------

def test_near_dead_centre_needle_bar_is_singular_with_its_estimate():
    nb = sewgen.mechanism("needle_bar")
    r, e = 16.7 * MM, 10 * MM
    with pytest.raises(sewgen.SingularPositionError) as exc:
        nb.solve(PHI, params={"crank": r, "rod": r + e + 1e-15, "offset": e})  # was: velocity error 9e-3
    assert exc.value.angle == pytest.approx(math.pi) and exc.value.index == 36
    assert "estimated relative error" in str(exc.value) and "change point" in str(exc.value)
    flagged = nb.solve(PHI, params={"crank": r, "rod": r + e + 1e-15, "offset": e}, singular="flag")
    assert np.flatnonzero(flagged.singular).tolist() == [36] and flagged.error_estimate[36] > 1e-3
    assert np.all(np.isfinite(flagged.obs))
    well = nb.solve(PHI, params={"crank": r, "rod": r + e + 1e-4, "offset": e})
    assert well.error_estimate.max() < 1e-10 and not well.singular.any()


def test_four_bar_through_its_change_point_at_180_degrees(four_bar):
    p = {"crank": 10 * MM, "coupler": 25 * MM, "rocker": 20 * MM, "ground_x": 35 * MM, "ground_y": 0.0,
         "point_u": 10 * MM, "point_v": 0.0}  # coupler + rocker = ground + crank: the branches meet at 180°
    for newton in (False, True):
        with pytest.raises(sewgen.SingularPositionError) as exc:
            four_bar.solve(PHI, params=p, newton=newton)  # was: alpha -1.39e11 vs the true -2.41e11, no error
        assert exc.value.index == 36 and "change point" in str(exc.value)


def test_dead_centre_of_a_crank_that_cannot_turn(four_bar):
    """At the angle where |BD| reaches coupler + rocker and the loop closes on one side only: a dead centre
    (or, rounding the other way, no assembly), never a result."""
    r, g, big = 10 * MM, 35 * MM, 44 * MM
    p = {"crank": r, "coupler": 24 * MM, "rocker": 20 * MM, "ground_x": g, "ground_y": 0.0,
         "point_u": 10 * MM, "point_v": 0.0}
    phi0 = math.acos((r * r + g * g - big * big) / (2 * r * g))
    phi = np.concatenate([np.linspace(phi0 - 0.3, phi0, 7, endpoint=False), [phi0]])
    with pytest.raises((sewgen.SingularPositionError, sewgen.AssemblyError)) as exc:
        four_bar.solve(phi, params=p)
    assert exc.value.index == len(phi) - 1
    if isinstance(exc.value, sewgen.SingularPositionError):
        assert "dead centre" in str(exc.value)


# -- Newton's tolerance from each loop's own size ------------------------------------------------------------

@pytest.mark.parametrize("scale", [1e-3, 1e-6, 1e-9])
def test_newton_is_as_exact_as_the_closed_form_on_tiny_loops(four_bar, scale):
    p = {"crank": 10 * scale, "coupler": 40 * scale, "rocker": 30 * scale, "ground_x": 35 * scale,
         "ground_y": 5 * scale, "point_u": 20 * scale, "point_v": 10 * scale}
    closed = four_bar.solve(PHI, speed=1.0, params=p)
    newton = four_bar.solve(PHI, speed=1.0, params=p, newton=True)
    assert np.max(np.abs(newton.obs - closed.obs) / np.maximum(np.abs(closed.obs).max(axis=0), 1e-300)) < 1e-11


# -- sizes checked before C reads them -----------------------------------------------------------------------

def test_force_matrix_checks_every_size():
    fd, nb = sewgen.mechanism("feed"), sewgen.mechanism("needle_bar")
    motion = nb.solve(PHI)
    with pytest.raises(sewgen.InputError):
        fd.force_matrix(motion, 0)  # another mechanism's motion: read past its arrays (ASan, sg_feed.c:743)
    own = fd.solve(PHI)
    with pytest.raises(sewgen.ParameterError) as e:
        fd.force_matrix(own, 0, gravity=(0.0,))
    assert e.value.parameter == "gravity"
    with pytest.raises(sewgen.ParameterError) as e:
        fd.force_matrix(own, 0, load_row=[1.0])
    assert e.value.parameter == "load_row"
    with pytest.raises(sewgen.InputError):
        fd.force_matrix(own, len(PHI))
    with pytest.raises(sewgen.ParameterError):
        fd.force_matrix(own, 0, params=np.zeros(3))
    with pytest.raises(sewgen.ParameterError):
        fd.force_matrix(own, 0, held=np.zeros(5))
    a, b = fd.force_matrix(own, 3, gravity=(0.0, -9.8), load_row=np.zeros(len(fd.description.loads)))
    assert np.isfinite(a).all() and np.isfinite(b).all()
    with pytest.raises(sewgen.InputError):
        fd.residual(np.zeros(2), 0.0)


# -- API -----------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("kwargs, error, parameter", [
    (dict(max_iter=10 ** 12), sewgen.ParameterError, "max_iter"),
    (dict(max_iter=0), sewgen.ParameterError, "max_iter"),
    (dict(params=[1.0]), sewgen.ParameterError, "params"),
    (dict(held=[1.0]), sewgen.ParameterError, "held"),
    (dict(branch=1), sewgen.ParameterError, "branch"),
    (dict(guess=[0.0]), sewgen.ParameterError, "guess"),
    (dict(speed=True), sewgen.InputError, None),
    (dict(accel=np.ones(len(PHI), dtype=bool)), sewgen.InputError, None),
    (dict(singular="ignore"), sewgen.ParameterError, "singular"),
    (dict(newton="yes"), sewgen.ParameterError, "newton"),
])
def test_bad_arguments_are_typed_errors(kwargs, error, parameter):
    tu = sewgen.mechanism("take_up")
    with pytest.raises(error) as e:
        tu.solve(PHI, **kwargs)
    if parameter:
        assert e.value.parameter == parameter


def test_loads_boolean_angles_and_owned_arrays():
    tu = sewgen.mechanism("take_up")
    with pytest.raises(sewgen.ParameterError) as e:
        tu.kinetostatics(PHI, loads=sewgen.Load("thread_eye", fy=1.0))
    assert e.value.parameter == "loads"
    with pytest.raises(sewgen.InputError):
        tu.solve(PHI > 1.0)
    phi, speed = PHI.copy(), np.full(len(PHI), 50.0)
    m = tu.solve(phi, speed=speed)
    phi += 0.5
    speed *= 2
    assert m.phi[0] == 0.0 and m.omega[0] == 50.0  # the result owns its inputs


def test_take_up_thread_eye_triangle():
    tu = sewgen.mechanism("take_up")
    ok = tu.solve(PHI, params={"lever_be": "16 mm", "lever_ce": "22 mm", "lever_bc": "38 mm"})  # collinear
    eye, b = ok.point("thread_eye"), ok.point("crank_pin")
    c = ok.point("rocker_pin")
    t = 16 / 38  # E on BC, 16 mm from B
    np.testing.assert_allclose(eye.x, b.x + t * (c.x - b.x), rtol=0, atol=1e-12)
    with pytest.raises(sewgen.ParameterError) as e:
        tu.solve(PHI, params={"lever_be": "5 mm"})  # 5 + 22 < 38: no triangle
    assert e.value.parameter == "lever_be" and "lever_ce" in str(e.value)
    with pytest.raises(sewgen.ParameterError) as e:
        tu.solve(PHI, params={"lever_be": "5 mm", "lever_ce": "22 mm"})
    assert e.value.parameter == "lever_be, lever_ce"


# -- the intended assembly does not exist ----------------------------------------------------------------------

def test_feed_design_with_only_another_assembly_mode_says_so():
    """A feed design (found by a random search on the JB1-3 feed) reports 'cannot assemble' from
    140° on while an assembly exists there: the feed rock shaft turned over (another assembly mode). The error
    says so and where; started there, it solves."""
    fd = sewgen.mechanism("feed")
    p = {"cam_side": 6.429, "cam_small_radius": 8.25, "fork_q": 71.096, "feed_arm_p": 16.973, "feed_arm_r": 23.5,
         "lift_arm": 14.203, "dog_u": 16.372, "fork_p": 205.598, "bar_slot_v": 7.258, "regulator_x": -3.684,
         "regulator_y": -66.482, "feed_shaft_x": -20.565, "feed_shaft_y": -192.318}
    params = {k: f"{v} mm" for k, v in p.items()}
    held = {"regulator": 0.5009781279591697}
    with pytest.raises(sewgen.AssemblyError) as e:
        fd.solve(PHI, params=params, held=held)
    assert "another assembly mode" in str(e.value) and "feed_rock_shaft.angle" in str(e.value)
    other = fd.solve(np.radians([140.0]), params=params, held=held,
                     guess={"feed_rock_shaft.angle": "-133.9 deg", "rock_shaft.angle": "30.7 deg",
                            "feed_bar.angle": "104.3 deg"})
    assert np.all(np.abs(np.degrees(other.coord("feed_rock_shaft.angle").value)) > 120)

"""Bad input gets typed errors naming the mechanism and the parameter, position or shaft angle at fault.

Uses the compiled catalog (needle_bar: an offset crank-slider; take_up: a four-bar), so nothing compiles.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import sewgen

pytestmark = [pytest.mark.c]

PHI = sewgen.shaft_angles(5)  # 0°, 5°, ..., 355°

# A needle bar whose link is too short: the crank pin B = r (cos θ, sin θ) must reach the guide x = e with a
# link of length l, so the loop closes only where |r cos θ − e| <= l. With r = 16.7 mm, e = 10 mm and
# l = 20.2 mm it fails for cos θ < (e − l)/r, i.e. θ in (127.4°, 232.6°): 130° ... 230° on a 5° grid.
SHORT = {"crank": "16.7 mm", "rod": "20.2 mm", "offset": "10 mm"}
R, L, E = 0.0167, 0.0202, 0.010


def _reaches(theta):
    return np.abs(R * np.cos(theta) - E) <= L


def _first_failing(phi):
    bad = np.flatnonzero(~_reaches(np.asarray(phi)))
    assert bad.size, "test setup: the design should fail somewhere"
    return int(bad[0])


@pytest.fixture(scope="module")
def nb():
    return sewgen.mechanism("needle_bar")


@pytest.fixture(scope="module")
def tu():
    return sewgen.mechanism("take_up")


def _finite(motion):
    return all(np.isfinite(a).all() for a in (motion.phi, motion.omega, motion.alpha, motion.q, motion.qd,
                                               motion.qdd, motion.obs))


# -- parameters ------------------------------------------------------------------------------------------------

def test_unknown_parameter(nb):
    with pytest.raises(sewgen.ParameterError) as info:
        nb.solve(PHI, params={"crank_radius": "10 mm"})
    err = info.value
    assert err.mechanism == "needle_bar" and err.parameter == "crank_radius"
    assert "needle_bar" in str(err) and "crank_radius" in str(err)
    assert "crank" in str(err)  # the message lists the parameters there are


@pytest.mark.parametrize("value", [0, 0.0, -0.01, "-5 mm", "0 mm", -1e-300])
def test_non_positive_length(nb, value):
    with pytest.raises(sewgen.ParameterError) as info:
        nb.solve(PHI, params={"rod": value})
    assert info.value.parameter == "rod"
    assert "needle_bar" in str(info.value) and "'rod'" in str(info.value)
    assert "positive" in str(info.value)


def test_signed_length_may_be_negative(nb):
    m = nb.solve(PHI, params={"offset": "-3 mm"})
    assert _finite(m)


@pytest.mark.parametrize("value", ["5 kg", "3 s", "90 deg", "12 parsecs per fortnight", "5 mm mm", ""])
def test_wrong_or_unreadable_unit(nb, value):
    with pytest.raises(sewgen.ParameterError) as info:
        nb.solve(PHI, params={"crank": value})
    assert info.value.parameter == "crank"
    assert "needle_bar" in str(info.value) and "'crank'" in str(info.value)


@pytest.mark.parametrize("value", [float("nan"), float("inf"), -float("inf"), "nan mm", "inf mm"])
def test_non_finite_parameter(nb, value):
    with pytest.raises(sewgen.ParameterError) as info:
        nb.solve(PHI, params={"offset": value})
    assert info.value.parameter == "offset"


@pytest.mark.parametrize("value", [None, [0.01], True, {"mm": 1}])
def test_parameter_of_wrong_type(nb, value):
    with pytest.raises(sewgen.ParameterError) as info:
        nb.solve(PHI, params={"crank": value})
    assert info.value.parameter == "crank"


def test_negative_mass_and_inertia(nb):
    with pytest.raises(sewgen.ParameterError, match="rod.mass"):
        nb.solve(PHI, params={"rod.mass": "-1 g"})
    with pytest.raises(sewgen.ParameterError, match="needle_bar.inertia"):
        nb.solve(PHI, params={"needle_bar.inertia": -1e-6})
    with pytest.raises(sewgen.ParameterError, match="rod.mass"):
        nb.solve(PHI, params={"rod.mass": "5 mm"})


def test_units_are_converted(nb):
    a = nb.solve(PHI, params={"crank": "16.7 mm", "rod": "5 cm", "offset": "0.1 inch"})
    b = nb.solve(PHI, params={"crank": 0.0167, "rod": 0.05, "offset": 0.00254})
    np.testing.assert_allclose(a.obs, b.obs, rtol=1e-14, atol=1e-15)


def test_parameter_errors_are_value_errors(nb):
    with pytest.raises(ValueError):
        nb.solve(PHI, params={"crank": -1})
    with pytest.raises(sewgen.SewgenError):
        nb.solve(PHI, params={"nope": 1})


# -- branches, guesses, options --------------------------------------------------------------------------------

@pytest.mark.parametrize("value", [0, 2, -2, 0.5, "1", None, "+1"])
def test_bad_branch_value(nb, value):
    with pytest.raises(sewgen.ParameterError) as info:
        nb.solve(PHI, branch={"C": value})
    assert info.value.parameter == "C"
    assert "needle_bar" in str(info.value) and "branch" in str(info.value)


def test_unknown_branch_joint(nb):
    with pytest.raises(sewgen.ParameterError) as info:
        nb.solve(PHI, branch={"Z": 1})
    assert info.value.parameter == "Z"
    assert "needle_bar" in str(info.value) and "'Z'" in str(info.value)
    assert "C" in str(info.value).split("'Z'", 1)[1]  # names the joints that do have a branch


def test_branch_flip_gives_the_other_assembly(nb):
    lower = nb.solve(PHI, branch={"C": -1})
    upper = nb.solve(PHI, branch={"C": +1})
    assert _finite(lower) and _finite(upper)
    assert np.all(upper.point("link_pin").y > lower.point("link_pin").y)


def test_unknown_guess_coordinate_and_bad_max_iter(nb):
    with pytest.raises(sewgen.ParameterError) as info:
        nb.solve(PHI, guess={"rod.travel": 0.0}, newton=True)
    assert info.value.parameter == "rod.travel"
    with pytest.raises(sewgen.ParameterError) as info:
        nb.solve(PHI, guess={"rod.angle": "5 kg"}, newton=True)
    assert info.value.parameter == "rod.angle"
    with pytest.raises(sewgen.ParameterError, match="max_iter"):
        nb.solve(PHI, newton=True, max_iter=0)


# -- shaft angles, speeds, accelerations ------------------------------------------------------------------------

@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_shaft_angle(nb, bad):
    phi = PHI.copy()
    phi[17] = bad
    with pytest.raises(sewgen.InputError) as info:
        nb.solve(phi)
    msg = str(info.value)
    assert "needle_bar" in msg and "shaft angle" in msg and "position 17" in msg


def test_non_finite_shaft_angle_in_degrees(nb):
    with pytest.raises(sewgen.InputError, match="position 2"):
        nb.solve([0.0, 10.0, np.nan], degrees=True)


def test_degrees_given_as_radians_are_refused(nb):
    """np.arange(0, 360, 5) is 72 angles in degrees; as rad it would be 56 turns solved without a word."""
    with pytest.raises(sewgen.InputError, match="degrees=True") as info:
        nb.solve(np.arange(0, 360, 5))
    assert info.value.parameter == "phi" and info.value.mechanism == "needle_bar"
    with pytest.raises(sewgen.InputError, match="degrees=True"):
        nb.kinetostatics(np.arange(0, 720, 5))
    a = nb.solve(np.arange(0, 360, 5), degrees=True)  # the same angles, said to be degrees
    np.testing.assert_allclose(a.phi, PHI, rtol=1e-15)
    nb.solve(np.arange(0.0, 3.0, 0.01) * 2)  # rad in round numbers within two turns: rad
    nb.solve(np.linspace(0, 6 * np.pi, 50))  # three turns in rad: not round numbers


@pytest.mark.parametrize("phi", [[1e300], [0.0, 1e7], [-2e6, -2e6 + 0.1]])
def test_shaft_angles_too_large_for_their_steps(nb, phi):
    """Beyond 1e6 rad an angle's rounding is 1e-10 rad and more: at 1e300 rad the steps of a sweep vanish."""
    assert 1e300 + 0.1 == 1e300  # what would happen
    with pytest.raises(sewgen.InputError, match="beyond") as info:
        nb.solve(np.array(phi), newton=True)  # (newton=True: prepare's path, which checks the angles)
    assert info.value.parameter == "phi"


@pytest.mark.parametrize("gravity, words", [(-9.81, "at least 0"), ("1e308 m/s**2", "at most 100"),
                                            ("200 m/s**2", "at most 100")])
def test_gravity_is_a_magnitude_of_this_world(nb, gravity, words):
    """A negative magnitude turned the weight over; 1e308 m/s² made every force infinite."""
    with pytest.raises(sewgen.ParameterError, match=words) as info:
        nb.kinetostatics(PHI, gravity=gravity)
    assert info.value.parameter == "gravity"
    free = nb.kinetostatics(PHI, gravity=0)
    up = nb.kinetostatics(PHI, gravity=9.80665, gravity_direction="90 deg")
    down = nb.kinetostatics(PHI, gravity=9.80665)
    np.testing.assert_allclose(up.torque() - free.torque(), -(down.torque() - free.torque()), atol=1e-12)


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_speed(nb, bad):
    speed = np.full(len(PHI), 100.0)
    speed[40] = bad
    with pytest.raises(sewgen.InputError) as info:
        nb.solve(PHI, speed=speed)
    assert "needle_bar" in str(info.value) and "speed" in str(info.value) and "position 40" in str(info.value)
    with pytest.raises(sewgen.InputError, match="speed"):
        nb.solve(PHI, speed=bad)


def test_non_finite_acceleration(nb):
    accel = np.zeros(len(PHI))
    accel[3] = np.nan
    with pytest.raises(sewgen.InputError, match="position 3"):
        nb.solve(PHI, accel=accel)


@pytest.mark.parametrize("shape", [(8, 9), (72, 1), (1, 72), (2, 2, 18)])
def test_multi_dimensional_shaft_angles(nb, shape):
    with pytest.raises(sewgen.InputError) as info:
        nb.solve(PHI.reshape(shape))
    assert "needle_bar" in str(info.value) and "1-D" in str(info.value)


def test_complex_inputs(nb):
    with pytest.raises(sewgen.InputError, match="needle_bar"):
        nb.solve(PHI.astype(complex))
    with pytest.raises(sewgen.InputError, match="needle_bar"):
        nb.solve(PHI, speed=np.full(len(PHI), 100 + 0j))
    with pytest.raises(sewgen.InputError):
        nb.solve(PHI, speed=100 + 1j)


def test_non_numeric_inputs(nb):
    with pytest.raises(sewgen.InputError):
        nb.solve(np.array(["0", "1"]))
    with pytest.raises(sewgen.InputError):
        nb.solve(np.array([0.0, None], dtype=object))


@pytest.mark.parametrize("n", [0, 1, 71, 73, 144])
def test_speed_of_wrong_length(nb, n):
    with pytest.raises(sewgen.InputError) as info:
        nb.solve(PHI, speed=np.full(n, 100.0))
    assert "needle_bar" in str(info.value) and "speed" in str(info.value)
    assert "(72,)" in str(info.value)


def test_speed_of_wrong_shape_and_accel_of_wrong_length(nb):
    with pytest.raises(sewgen.InputError):
        nb.solve(PHI, speed=np.full((72, 1), 100.0))
    with pytest.raises(sewgen.InputError, match="acceleration"):
        nb.solve(PHI, accel=np.zeros(10))


def test_speed_with_wrong_unit(nb):
    with pytest.raises(sewgen.InputError, match="speed"):
        nb.solve(PHI, speed="100 kg")
    ok = nb.solve(PHI, speed="600 rpm")
    np.testing.assert_allclose(ok.omega, 20 * math.pi)


# -- conversions -------------------------------------------------------------------------------------------------

def _same(a, b):
    for x, y in ((a.phi, b.phi), (a.omega, b.omega), (a.alpha, b.alpha), (a.q, b.q), (a.qd, b.qd),
                 (a.qdd, b.qdd), (a.obs, b.obs)):
        assert np.array_equal(x, y)


def test_integer_arrays_are_converted(nb):
    deg = np.arange(0, 360, 10)  # int64
    rpm = np.full(deg.shape, 300, dtype=np.int32)
    a = nb.solve(deg, speed=rpm, accel=np.ones(deg.shape, dtype=np.int16), degrees=True)
    b = nb.solve(deg.astype(np.float64), speed=rpm.astype(np.float64), accel=np.ones(deg.shape), degrees=True)
    _same(a, b)
    np.testing.assert_allclose(a.phi, np.radians(deg.astype(float)))
    assert a.omega.dtype == np.float64
    c = nb.solve(list(deg), degrees=True)  # a plain list of ints
    np.testing.assert_array_equal(c.q, nb.solve(deg.astype(float), degrees=True).q)


def test_float32_arrays_are_converted(nb):
    phi32 = PHI.astype(np.float32)
    speed32 = np.linspace(50, 150, len(PHI)).astype(np.float32)
    a = nb.solve(phi32, speed=speed32)
    b = nb.solve(phi32.astype(np.float64), speed=speed32.astype(np.float64))
    _same(a, b)
    np.testing.assert_allclose(a.q, nb.solve(PHI, speed=speed32.astype(np.float64)).q, atol=1e-6)


def test_non_contiguous_arrays_are_converted(nb):
    wide = np.radians(np.arange(0, 720, 5.0))
    phi = wide[::2]  # a strided view
    assert not phi.flags["C_CONTIGUOUS"]
    speed = np.linspace(10, 200, 2 * len(phi))[::2]
    accel = np.stack([np.linspace(-5, 5, len(phi))] * 2, axis=1)[:, 1]
    assert not speed.flags["C_CONTIGUOUS"] and not accel.flags["C_CONTIGUOUS"]
    a = nb.solve(phi, speed=speed, accel=accel)
    b = nb.solve(np.ascontiguousarray(phi), speed=np.ascontiguousarray(speed), accel=np.ascontiguousarray(accel))
    _same(a, b)
    rev = nb.solve(PHI[::-1])  # negative stride
    np.testing.assert_array_equal(rev.q[::-1], nb.solve(PHI).q)


def test_scalar_and_list_inputs(nb):
    one = nb.solve(0.3)
    assert len(one) == 1 and one.q.shape == (1, 2)
    np.testing.assert_array_equal(one.q[0], nb.solve([0.1, 0.3]).q[1])
    empty = nb.solve(np.array([]))
    assert len(empty) == 0 and empty.obs.shape[0] == 0


def test_solve_does_not_modify_its_inputs(nb):
    phi = PHI.copy()
    speed = np.full(len(PHI), 100.0)
    nb.solve(phi, speed=speed, degrees=False)
    nb.solve(phi, speed=speed, degrees=True)
    np.testing.assert_array_equal(phi, PHI)
    np.testing.assert_array_equal(speed, 100.0)


# -- positions that cannot be solved ----------------------------------------------------------------------------

def test_design_setup_is_what_the_comment_says():
    assert _first_failing(PHI) == 26  # 130°
    assert _reaches(np.radians(125.0)) and not _reaches(np.radians(130.0))


@pytest.mark.parametrize("newton", [False, True])
def test_short_rod_fails_at_first_failing_angle(nb, newton):
    with pytest.raises(sewgen.AssemblyError) as info:
        nb.solve(PHI, params=SHORT, newton=newton)
    err = info.value
    i = _first_failing(PHI)
    assert isinstance(err, sewgen.PositionError)
    if not newton:
        assert type(err) is sewgen.AssemblyError
    assert err.mechanism == "needle_bar"
    assert err.index == i
    assert err.angle == PHI[i]
    assert f"{math.degrees(PHI[i]):.6g}°" in str(err)
    assert "130°" in str(err)
    assert "needle_bar" in str(err)
    if not newton:
        assert err.count == int(np.count_nonzero(~_reaches(PHI)))  # 130° ... 230°: 21 positions


@pytest.mark.parametrize("newton", [False, True])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_first_failing_angle_in_array_order(nb, newton, seed):
    """The error names the first failing shaft angle in the order given: any order in closed form; Newton
    continues from the previous positions, so it gets increasing (unevenly spaced) angles."""
    rng = np.random.default_rng(seed)
    phi = rng.uniform(-np.pi, 3 * np.pi, 50)
    phi = phi[np.abs(np.abs(R * np.cos(phi) - E) - L) > 1e-4]  # keep clear of the assembly limit itself
    if newton:
        phi = np.sort(phi)
    with pytest.raises(sewgen.AssemblyError) as info:
        nb.solve(phi, params=SHORT, newton=newton)
    i = _first_failing(phi)
    assert info.value.index == i
    assert info.value.angle == phi[i]
    assert f"{math.degrees(phi[i]):.6g}°" in str(info.value)


@pytest.mark.parametrize("newton", [False, True])
def test_failing_first_position(nb, newton):
    phi = np.radians([180.0, 0.0, 10.0])
    with pytest.raises(sewgen.AssemblyError) as info:
        nb.solve(phi, params=SHORT, newton=newton)
    assert info.value.index == 0 and info.value.angle == phi[0]
    assert "180°" in str(info.value)


def test_degrees_flag_reports_the_angle(nb):
    with pytest.raises(sewgen.AssemblyError) as info:
        nb.solve(np.arange(0.0, 360.0, 5.0), params=SHORT, degrees=True)
    assert info.value.angle == pytest.approx(math.radians(130))
    assert "130°" in str(info.value)


def test_short_rod_works_where_it_reaches(nb):
    phi = np.radians(np.arange(235.0, 490.0, 5.0))  # 235° ... 485° (= 125°): one arc, no gap for Newton to jump
    assert _reaches(phi).all()
    assert np.count_nonzero(_reaches(PHI)) == len(phi)  # every reachable position of the revolution
    for newton in (False, True):
        m = nb.solve(phi, params=SHORT, newton=newton)
        assert _finite(m)
        link = m.point("link_pin")
        np.testing.assert_allclose(link.x, E, atol=1e-15)  # C on the guide
        crank = m.point("crank_pin")
        np.testing.assert_allclose(np.hypot(link.x - crank.x, link.y - crank.y), L, rtol=0, atol=1e-13)


def test_impossible_take_up_triangle_is_a_typed_error_not_nan(tu):
    """lever_ce > lever_bc + lever_be: the eye's triangle cannot exist. Whatever the error, never NaN out."""
    with pytest.raises((sewgen.PositionError, sewgen.ParameterError)) as info:
        tu.solve(PHI, params={"lever_ce": "200 mm"})
    assert "take_up" in str(info.value)


def test_take_up_crank_too_long_fails_typed(tu):
    with pytest.raises(sewgen.PositionError) as info:
        tu.solve(PHI, params={"crank": "30 mm"})
    assert isinstance(info.value, sewgen.AssemblyError)
    assert 0 <= info.value.index < len(PHI)
    assert info.value.angle == PHI[info.value.index]
    assert "take_up" in str(info.value)


@pytest.mark.parametrize("name", ["needle_bar", "take_up", "hook_drive"])
@pytest.mark.parametrize("newton", [False, True])
def test_catalog_results_are_finite(name, newton):
    mech = sewgen.mechanism(name)
    m = mech.solve(sewgen.shaft_angles(2), speed="1500 rpm", accel=20.0, newton=newton)
    assert _finite(m)
    assert m.q.shape == (180, len(mech.coord_names))
    for col in m.table().values():
        assert np.isfinite(col).all()

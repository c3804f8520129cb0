"""Property-based tests over random dimensions: a user four-bar (compiled once, varied through
``solve(params=...)``) and the catalog needle bar (crank-slider with offset).

Every case either meets the invariants -- finite results, loop residual <= 1e-13 m at every position, the
assembly the branch sign asks for, rates that agree with finite differences, closed form and Newton agreeing
where both succeed -- or raises a sewgen.PositionError subclass (at a shaft angle where the geometry really
fails, checked analytically) or a sewgen.ParameterError. Never NaN, never another exception type.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, note, settings
from hypothesis import strategies as st

import sewgen
from sewgen.derive.model import Mechanism as Declaration

pytestmark = [pytest.mark.c, pytest.mark.derive]

PHI = sewgen.shaft_angles(5)
MM = 1e-3
RESIDUAL_MAX = 1e-13  # m
H = 1e-5  # rad, finite-difference step

#: derandomize: CI runs the same examples every time (a fresh clone has no example database). A failure that a
#: random search finds goes to the issues and, once fixed, into an @example here (open: crank 1.59375 mm,
#: coupler = rocker 62 mm, ground (1.125, 1.0) mm, branch +1 closes to 1.67e-13 m, above the 1e-13 m asserted).
SETTINGS = dict(deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)


def declare_four_bar():
    m = Declaration("prop_four_bar", "A four-bar for property tests: crank A-B, coupler B-C, rocker D-C.")
    r = m.length("crank", "10 mm", "crank AB")
    l2 = m.length("coupler", "40 mm", "coupler BC")
    l3 = m.length("rocker", "30 mm", "rocker DC")
    gx = m.length("ground_x", "35 mm", "rocker pivot D, x", signed=True)
    gy = m.length("ground_y", "5 mm", "rocker pivot D, y", signed=True)
    crank = m.driven("crank", pivot=m.ground.at(0, 0), doc="crank")
    coupler = m.link("coupler", doc="coupler", guess="60 deg")
    rocker = m.link("rocker", doc="rocker", guess="100 deg")
    m.revolute(crank.at(r, 0), coupler.at(0, 0), name="B")
    m.revolute(m.ground.at(gx, gy), rocker.at(0, 0), name="D")
    m.revolute(coupler.at(l2, 0), rocker.at(l3, 0), name="C", branch=1)
    m.point("crank_pin", crank.at(r, 0), "B")
    m.point("coupler_pin", rocker.at(l3, 0), "C")
    return m


@pytest.fixture(scope="session")
def four_bar(cache_dir):
    return sewgen.load(declare_four_bar, closed_form=True, cache_dir=cache_dir)


@pytest.fixture(scope="session")
def needle_bar():
    return sewgen.mechanism("needle_bar")


# -- helpers -------------------------------------------------------------------------------------------------

def event(what: str) -> None:
    """hypothesis.event inside a property test, nothing in a plain test."""
    from hypothesis import event as record
    from hypothesis.errors import InvalidArgument

    try:
        record(what)
    except InvalidArgument:
        pass


def _wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def _finite(m):
    return all(np.isfinite(a).all() for a in (m.q, m.qd, m.qdd, m.obs))


def _check_residuals(mech, motion, params):
    worst = 0.0
    for q, phi in zip(motion.q, motion.phi):
        r, jac = mech.residual(q, phi, params=params)
        assert np.isfinite(r).all() and np.isfinite(jac).all()
        worst = max(worst, float(np.max(np.abs(r))))
    assert worst <= RESIDUAL_MAX, f"loop residual {worst:.3g} m"


def _inv_norm(mech, q, phi, params):
    _, jac = mech.residual(q, phi, params=params)
    return float(np.linalg.norm(np.linalg.inv(jac), np.inf))


def _solve_or_none(mech, phi, **kw):
    """A solve that may legitimately fail (neighbours of a position near the assembly limit)."""
    try:
        return mech.solve(phi, **kw)
    except sewgen.PositionError:
        return None


def _check_rates(mech, params, good, branch=None):
    """q', q'' and point velocities at speed 1 rad/s against central differences, at well-conditioned
    positions ``good`` (boolean mask over PHI)."""
    phi = PHI[good]
    if not phi.size:
        return
    kw = dict(speed=1.0, accel=0.0, params=params, branch=branch)
    m0 = mech.solve(phi, **kw)
    mp, mm = _solve_or_none(mech, phi + H, **kw), _solve_or_none(mech, phi - H, **kw)
    if mp is None or mm is None:
        event("finite-difference neighbour failed: rates not checked")
        return
    fd_q = _wrap(mp.q - mm.q) / (2 * H)
    fd_qd = (mp.qd - mm.qd) / (2 * H)
    np.testing.assert_allclose(m0.qd, fd_q, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(m0.qdd, fd_qd, rtol=1e-5, atol=1e-5)
    for name in m0.point_names:
        a, p, n = m0.point(name), mp.point(name), mm.point(name)
        np.testing.assert_allclose(a.vx, (p.x - n.x) / (2 * H), rtol=1e-5, atol=1e-8)
        np.testing.assert_allclose(a.vy, (p.y - n.y) / (2 * H), rtol=1e-5, atol=1e-8)
        np.testing.assert_allclose(a.ay, (p.vy - n.vy) / (2 * H), rtol=1e-5, atol=1e-7)


def _check_agreement(mech, closed, newton, params):
    """Closed form and Newton: the same positions within what the Newton tolerance allows."""
    tol_newton = 1e-12 * mech.length_scale(mech.param_vector(params))
    for k in range(len(PHI)):
        allow = 1e-9 + 100 * tol_newton * _inv_norm(mech, closed.q[k], PHI[k], params)
        assert np.max(np.abs(_wrap(newton.q[k] - closed.q[k]))) <= allow, f"position {k}"
    scale = 1 + np.abs(closed.qd)
    assert np.all(np.abs(newton.qd - closed.qd) <= 1e-5 * scale)


# -- the four-bar --------------------------------------------------------------------------------------------

def _four_bar_geometry(p):
    B = p["crank"] * np.stack([np.cos(PHI), np.sin(PHI)], axis=-1)
    D = np.array([p["ground_x"], p["ground_y"]])
    d = np.hypot(*(D - B).T)
    return B, D, d


def _four_bar_case(mech, p, sigma):
    """Run one design through closed form and Newton and check whatever outcome it has."""
    params = dict(p)
    positive = [k for k in ("crank", "coupler", "rocker") if not p[k] > 0]
    try:
        closed = mech.solve(PHI, speed=1.0, params=params, branch={"C": sigma})
    except sewgen.ParameterError as exc:
        assert positive, f"unexpected ParameterError {exc}"
        assert exc.parameter in positive
        event("ParameterError")
        return "parameter"
    except sewgen.PositionError as exc:
        assert not positive
        _check_four_bar_failure(exc, p)
        if type(exc) is sewgen.AssemblyError:  # Newton cannot close a loop that cannot close
            with pytest.raises(sewgen.PositionError):
                mech.solve(PHI, speed=1.0, params=params, branch={"C": sigma}, newton=True)
        return "position"
    assert not positive
    event("assembles")
    l2, l3 = p["coupler"], p["rocker"]
    B, D, d = _four_bar_geometry(p)
    assert _finite(closed)
    assert np.all(d <= l2 + l3 + 1e-12) and np.all(d >= abs(l2 - l3) - 1e-12)
    _check_residuals(mech, closed, params)
    # the assembly the branch sign asks for: C left (sigma = +1) or right of the ray B -> D
    C = np.stack([closed.point("coupler_pin").x, closed.point("coupler_pin").y], axis=-1)
    cross = (D[0] - B[:, 0]) * (C[:, 1] - B[:, 1]) - (D[1] - B[:, 1]) * (C[:, 0] - B[:, 0])
    assert np.all(sigma * cross >= -1e-15)
    np.testing.assert_allclose(np.hypot(*(C - B).T), l2, rtol=0, atol=1e-13)
    np.testing.assert_allclose(np.hypot(*(C - D).T), l3, rtol=0, atol=1e-13)
    # rates by finite differences, where the transmission is not near a toggle
    q = dict(zip(closed.coord_names, closed.q.T))
    good = np.abs(np.sin(q["rocker.angle"] - q["coupler.angle"])) > 0.05
    _check_rates(mech, params, good, branch={"C": sigma})
    # Newton from the closed-form start, tracking the revolution
    try:
        newton = mech.solve(PHI, speed=1.0, params=params, branch={"C": sigma}, newton=True)
    except sewgen.PositionError as exc:
        event(f"Newton failed: {type(exc).__name__}")
        assert 0 <= exc.index < len(PHI) and exc.angle == PHI[exc.index]
        return "closed only"
    assert _finite(newton)
    _check_residuals(mech, newton, params)
    _check_agreement(mech, closed, newton, params)
    return "both"


def _check_four_bar_failure(exc, p):
    """A closed-form failure must be where the geometry says: no assembly, or a toggle."""
    assert 0 <= exc.index < len(PHI)
    assert exc.angle == PHI[exc.index]
    assert exc.mechanism == "prop_four_bar" and "prop_four_bar" in str(exc)
    l2, l3 = p["coupler"], p["rocker"]
    _, _, d = _four_bar_geometry(p)
    lo, hi = abs(l2 - l3), l2 + l3
    tol = 1e-12
    before = d[: exc.index]
    assert np.all(before <= hi + tol) and np.all(before >= lo - tol), "an earlier position assembles"
    di = d[exc.index]
    if type(exc) is sewgen.AssemblyError:
        event("AssemblyError")
        assert di > hi - tol or di < lo + tol
    elif type(exc) is sewgen.SingularPositionError:
        event("SingularPositionError")
        # near a toggle: the rates' estimate (docs/explanation/derivation.md) grows as the cube of the triangle BCD's
        # amplification, 1 / sin of its angle at C, near a change point, and the rounding the triangle amplifies as
        # its longest side over its shortest link; refused only where their product is above 20 (or B over D)
        cos_c = (l2 * l2 + l3 * l3 - di * di) / (2 * l2 * l3)
        sin_c = math.sqrt(max(0.0, 1.0 - cos_c * cos_c))
        assert sin_c * 20 < max(l2, l3, di) / min(l2, l3) or di < 1e-8
    else:
        raise AssertionError(f"closed form raised {type(exc).__name__}: {exc}")


length_mm = st.floats(min_value=0.5, max_value=80.0, allow_nan=False, allow_infinity=False)
coord_mm = st.floats(min_value=-60.0, max_value=60.0, allow_nan=False, allow_infinity=False)


@settings(max_examples=300, **SETTINGS)
@given(crank=st.floats(0.5, 25.0), coupler=length_mm, rocker=length_mm, gx=coord_mm, gy=coord_mm,
       sigma=st.sampled_from([1, -1]))
@example(crank=0.0, coupler=40.0, rocker=30.0, gx=35.0, gy=5.0, sigma=1)
@example(crank=10.0, coupler=-40.0, rocker=30.0, gx=35.0, gy=5.0, sigma=1)
@example(crank=10.0, coupler=20.0, rocker=20.0, gx=10.0, gy=0.0, sigma=1)  # pin B passes over pivot D
def test_four_bar_random_dimensions(four_bar, crank, coupler, rocker, gx, gy, sigma):
    p = {"crank": crank * MM, "coupler": coupler * MM, "rocker": rocker * MM, "ground_x": gx * MM,
         "ground_y": gy * MM}
    note(f"params {p}, branch {sigma}")
    _four_bar_case(four_bar, p, sigma)


non_positive_mm = st.one_of(st.just(0.0), st.just(-0.0), st.floats(-100.0, 0.0), st.just(-1e-300))


@settings(max_examples=40, **SETTINGS)
@given(which=st.sampled_from(["crank", "coupler", "rocker"]), bad=non_positive_mm, p=st.fixed_dictionaries(
    {"crank": length_mm, "coupler": length_mm, "rocker": length_mm, "ground_x": coord_mm, "ground_y": coord_mm}))
def test_four_bar_non_positive_length_is_a_parameter_error(four_bar, which, bad, p):
    p = {k: v * MM for k, v in p.items()}
    p[which] = bad * MM
    note(f"params {p}")
    assert _four_bar_case(four_bar, p, 1) == "parameter"


@st.composite
def crank_rockers(draw):
    """Grashof crank-rockers with margin: |B - D| stays inside (|l2 - l3|, l2 + l3) by at least ``margin``."""
    r = draw(st.floats(2.0, 15.0))
    g = draw(st.floats(r + 5.0, 50.0))
    psi = draw(st.floats(-np.pi, np.pi))
    dmin, dmax = g - r, g + r
    margin = 0.1 * dmin
    s = draw(st.floats(dmax + margin, dmax + margin + 30.0))
    delta = draw(st.floats(-(dmin - margin), dmin - margin))
    return {"crank": r * MM, "coupler": (s + delta) / 2 * MM, "rocker": (s - delta) / 2 * MM,
            "ground_x": g * np.cos(psi) * MM, "ground_y": g * np.sin(psi) * MM}


@settings(max_examples=60, **SETTINGS)
@given(p=crank_rockers(), sigma=st.sampled_from([1, -1]))
def test_four_bar_crank_rockers_always_solve(four_bar, p, sigma):
    """Designs that assemble with margin over the whole revolution: closed form and Newton both succeed."""
    note(f"params {p}, branch {sigma}")
    assert _four_bar_case(four_bar, p, sigma) == "both"


def test_four_bar_default_design(four_bar):
    assert four_bar.build_info["cached"] in (False, True)
    assert _four_bar_case(four_bar, four_bar.defaults(), 1) == "both"


# -- the needle bar ------------------------------------------------------------------------------------------

def _needle_case(mech, r, l, e, sigma):
    params = {"crank": r, "rod": l, "offset": e}
    bad = [k for k, v in (("crank", r), ("rod", l)) if not v > 0]
    reach = np.abs(r * np.cos(PHI) - e)  # the rod must span this horizontally
    try:
        closed = mech.solve(PHI, speed=1.0, params=params, branch={"C": sigma})
    except sewgen.ParameterError as exc:
        assert bad and exc.parameter in bad, f"unexpected {exc}"
        event("ParameterError")
        return "parameter"
    except sewgen.PositionError as exc:
        assert not bad
        assert 0 <= exc.index < len(PHI) and exc.angle == PHI[exc.index]
        assert "needle_bar" in str(exc)
        assert np.all(reach[: exc.index] <= l + 1e-12), "an earlier position assembles"
        if type(exc) is sewgen.AssemblyError:
            event("AssemblyError")
            assert reach[exc.index] > l - 1e-12
            with pytest.raises(sewgen.PositionError):
                mech.solve(PHI, speed=1.0, params=params, branch={"C": sigma}, newton=True)
        elif type(exc) is sewgen.SingularPositionError:
            event("SingularPositionError")
            assert abs(reach[exc.index] - l) < 1e-8
        else:
            raise AssertionError(f"closed form raised {type(exc).__name__}: {exc}")
        return "position"
    assert not bad
    event("assembles")
    assert _finite(closed)
    assert np.all(reach <= l + 1e-12)
    _check_residuals(mech, closed, params)
    # independent: C = (e, s) on the guide at distance l from B; sigma = +1 takes the larger travel
    root = np.sqrt(np.maximum(l**2 - (e - r * np.cos(PHI)) ** 2, 0.0))
    travel = r * np.sin(PHI) + sigma * root
    np.testing.assert_allclose(closed.coord("needle_bar.travel").value, travel, rtol=0, atol=1e-12)
    np.testing.assert_allclose(closed.point("link_pin").x, e, rtol=0, atol=1e-15)
    good = root > 0.05 * l
    _check_rates(mech, params, good, branch={"C": sigma})
    try:
        newton = mech.solve(PHI, speed=1.0, params=params, branch={"C": sigma}, newton=True)
    except sewgen.PositionError as exc:
        event(f"Newton failed: {type(exc).__name__}")
        assert 0 <= exc.index < len(PHI) and exc.angle == PHI[exc.index]
        return "closed only"
    assert _finite(newton)
    _check_residuals(mech, newton, params)
    _check_agreement(mech, closed, newton, params)
    return "both"


@settings(max_examples=300, **SETTINGS)
@given(r=st.floats(0.5, 40.0), l=st.floats(0.5, 100.0), e=st.floats(-40.0, 40.0), sigma=st.sampled_from([1, -1]))
@example(r=0.0, l=50.0, e=0.0, sigma=-1)
@example(r=16.7, l=0.0, e=0.0, sigma=-1)
@example(r=16.7, l=26.7, e=10.0, sigma=-1)  # rod = crank + offset: dead centre at 0°
def test_needle_bar_random_dimensions(needle_bar, r, l, e, sigma):
    note(f"crank {r} mm, rod {l} mm, offset {e} mm, branch {sigma}")
    _needle_case(needle_bar, r * MM, l * MM, e * MM, sigma)


@settings(max_examples=40, **SETTINGS)
@given(which=st.sampled_from(["crank", "rod"]), bad=non_positive_mm, r=st.floats(0.5, 40.0), l=st.floats(0.5, 100.0),
       e=st.floats(-40.0, 40.0))
def test_needle_bar_non_positive_length_is_a_parameter_error(needle_bar, which, bad, r, l, e):
    r, l = (bad, l) if which == "crank" else (r, bad)
    assert _needle_case(needle_bar, r * MM, l * MM, e * MM, -1) == "parameter"


@settings(max_examples=60, **SETTINGS)
@given(r=st.floats(1.0, 40.0), spare=st.floats(0.05, 1.0), e=st.floats(-40.0, 40.0),
       sigma=st.sampled_from([1, -1]))
def test_needle_bar_long_enough_rod_always_solves(needle_bar, r, spare, e, sigma):
    """rod >= (crank + |offset|) (1 + spare): assembles everywhere, closed form and Newton agree."""
    l = (r + abs(e)) * (1 + spare)
    note(f"crank {r} mm, rod {l} mm, offset {e} mm, branch {sigma}")
    assert _needle_case(needle_bar, r * MM, l * MM, e * MM, sigma) == "both"

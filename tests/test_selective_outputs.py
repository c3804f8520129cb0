"""Observables computed only when asked: a design sweep or ``solve(outputs=...)`` that keeps a
few columns runs the ``rates`` kernel (q', q'', the condition estimate) and the ``observe`` groups its columns
need, instead of the joint ``motion`` kernel, in every loop (generic, inlined scalar, SIMD). The selected columns must equal
the full sweep's exactly, with the same statuses and failing angles, on every catalog mechanism and on a user
mechanism; the kernels themselves are checked against the joint motion kernel at solved positions, bit for bit.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import sewgen
from sewgen import abi
from sewgen.engine.designs import Columns
from sewgen.engine.loader import catalog

pytestmark = [pytest.mark.c]

ROOT = Path(__file__).resolve().parents[1]
PHI = sewgen.shaft_angles(7.5)


def _table(mech):
    """Scaled lengths with a NaN, a design that cannot assemble and some that fail at some angles only."""
    lengths = [p for p in mech.description.params if p.kind == "length" and p.positive]
    factors = [1.0, 0.97, 1.04, float("nan"), 1.1, 40.0, 0.9, 1.25, 1.6, 1.0]
    table = {lengths[0].name: np.array([lengths[0].default * f for f in factors])}
    if len(lengths) > 1:
        table[lengths[1].name] = np.array([lengths[1].default * f for f in (1, 1, 0.98, 1, 1.03, 1, 1.01, 1, 1, 0.5)])
    return table


def _selections(mech):
    point, last_point = mech.point_names[0], mech.point_names[-1]
    body = mech.body_names[-1]
    return [(["coords"], None), ([f"points:{point}"], None), ([f"bodies:{body}"], None),
            ([f"points.{last_point}.y_dd", "coords"], None),
            ([], {f"points.{point}.a": "max", f"points.{last_point}.y": "min"}),
            ([f"bodies.{body}.angle"], {f"bodies.{body}.angle": "rms"})]


def _same(full, part):
    assert np.array_equal(part.status, full.status)
    assert np.array_equal(part.first_bad_angle, full.first_bad_angle)
    for key, arr in part.outputs.items():
        assert np.array_equal(arr, full.outputs[key], equal_nan=True), key
    for key in part.reductions:
        assert np.array_equal(part[key], full[key], equal_nan=True), key


def _check_mechanism(mech, newton, loop="auto"):
    table = _table(mech)
    everything = mech.sweep_designs(table, PHI, newton=newton, threads=1, loop=loop)  # the joint motion kernel
    cols = Columns(mech.description)
    n_failed = int((everything.status != 0).sum())
    assert 0 < n_failed < len(everything.status)
    for outputs, reduce in _selections(mech):
        part = mech.sweep_designs(table, PHI, newton=newton, threads=1, outputs=outputs, reduce=reduce, loop=loop)
        full = mech.sweep_designs(table, PHI, newton=newton, threads=1, outputs=["all"], reduce=reduce, loop=loop)
        _same(full, part)
        for key, arr in part.outputs.items():
            assert np.array_equal(arr, everything.outputs[key], equal_nan=True), key
        assert set(part.outputs) <= set(cols.names)


@pytest.mark.parametrize("name", catalog())
def test_selected_groups_equal_the_joint_kernel_to_the_bit(name):
    _check_mechanism(sewgen.mechanism(name), newton=True)


CLOSED = [n for n in catalog() if sewgen.mechanism(n).manifest.get("closed_form")]


@pytest.mark.parametrize("loop", ["auto", "scalar"])
@pytest.mark.parametrize("name", CLOSED)
def test_closed_form_loops_compute_only_the_selected_groups_to_the_bit(name, loop):
    """The inlined closed-form loops (four positions at a time in SIMD where it runs, and scalar) compute the
    rates and the wanted groups only, with the same values, statuses and failing angles as their full sweep."""
    mech = sewgen.mechanism(name)
    if loop == "auto" and mech.simd_width == 1:
        pytest.skip("no SIMD loop in this build or on this CPU")
    _check_mechanism(mech, newton=False, loop=loop)


def test_a_user_mechanism_selected_groups_equal_the_joint_kernel(tmp_path):
    path = ROOT / "examples" / "my_mechanism.py"
    _check_mechanism(sewgen.load(path, closed_form=False), newton=False)
    _check_mechanism(sewgen.load(path), newton=True)
    for loop in ("auto", "scalar"):
        _check_mechanism(sewgen.load(path), newton=False, loop=loop)


def _kernel(mech, kind):
    return getattr(mech.lib, f"sg_{mech.name}_{kind}")


@pytest.mark.parametrize("name", ["feed", "take_up", "overlock_loopers"])
def test_rates_and_observe_kernels_equal_motion_at_solved_positions(name):
    """At every solved position of a sweep (a cam's arcs switching within it for the feed), rates gives the motion
    kernel's q', q'' and cond, and the observe groups together its every observable, bit for bit."""
    mech = sewgen.mechanism(name)
    ffi = mech.ffi
    desc = mech.description
    sizes = desc.sizes
    nq, nobs, ngroup = sizes["nq"], sizes["nobs"], sizes["ngroup"]
    arcs = sum(o["name"].endswith(".arc") for o in mech.manifest["observables"])
    spatial = sum(o["name"].endswith(".com.z") for o in mech.manifest["observables"])  # a spatial crank's G: z
    assert ngroup == len(mech.manifest["points"]) + len(mech.manifest["bodies"]) + arcs + spatial
    sweep = mech.prepare(PHI, newton=True)
    sweep.run()
    assert (sweep.status == 0).all()
    c = np.empty(sizes["nc"])
    _kernel(mech, "constants")(ffi.from_buffer("double[]", mech.param_vector()), ffi.from_buffer("double[]", c))
    held = [i.default for i in desc.held_inputs]
    motion, rates, observe = (_kernel(mech, k) for k in ("motion", "rates", "observe"))
    seen = set()
    buf = lambda a: ffi.from_buffer("double[]", a)  # noqa: E731
    for i in range(len(PHI)):
        q = sweep.q[i].copy()
        cq = np.empty(2 * nq)
        for k in range(nq):
            cq[2 * k], cq[2 * k + 1] = (np.cos(q[k]), np.sin(q[k])) if mech.manifest["coords"][k]["unit"] == "rad" \
                else (1.0, 0.0)
        x = np.array([sweep.phi[i]] + held)
        cx = np.ravel([(np.cos(v), np.sin(v)) for v in x])
        xd = np.array([sweep.omega[i]] + [0.0] * len(held))
        xdd = np.array([sweep.alpha[i]] + [0.0] * len(held))
        ncond = abi.LIMIT["SG_NCOND"]  # the numbers a motion or rates kernel writes to cond
        qd1, qdd1, obs1, cond1 = np.empty(nq), np.empty(nq), np.empty(nobs), np.empty(ncond)
        qd2, qdd2, obs2, cond2 = np.empty(nq), np.empty(nq), np.full(nobs, np.nan), np.empty(ncond)
        args = (buf(q), buf(cq), buf(x), buf(cx), buf(xd), buf(xdd), buf(c))
        assert motion(*args, buf(qd1), buf(qdd1), buf(obs1), buf(cond1)) == 0
        assert rates(*args, buf(qd2), buf(qdd2), buf(cond2)) == 0
        assert np.array_equal(qd1, qd2) and np.array_equal(qdd1, qdd2) and np.array_equal(cond1, cond2)
        for g in range(ngroup):
            assert observe(*args, buf(qd2), buf(qdd2), g, buf(obs2)) == 0
        assert observe(*args, buf(qd2), buf(qdd2), ngroup, buf(obs2)) == 7  # SG_BAD_ARGUMENT
        assert np.array_equal(obs1, obs2)
        if arcs:
            seen.add(obs1[-1])
    if name == "feed":
        assert len(seen) >= 2  # more than one cam arc met: the groups read the run-time selection too


def test_polynomial_groups_need_not_be_computed_for_the_status():
    """A group whose observables are polynomials of finite values cannot fail where the rates did not; a
    division by a coordinate's function or a square root can, and such a group is computed in every sweep."""
    from sewgen.derive.kernels import _polynomial

    q, c = sp.Symbol("q_0", real=True), sp.Symbol("c_1", real=True)
    assert _polynomial(3 * q ** 2 + c * q - 1)
    assert not _polynomial(1 / (q + c))
    assert not _polynomial(sp.sqrt(q))
    assert not _polynomial(sp.atan2(q, c))
    assert not _polynomial(c ** -1)


def test_the_simd_loop_computes_angles_only_where_they_are_read():
    """group_angles: a body whose angle is a coordinate reads it (the SIMD loop then keeps the dyads' atan2);
    points, the crank (its angle is the shaft's) and the rates read only cos and sin. A selection of points alone
    skips the atan2 and still equals the full sweep (test_closed_form_loops_...), bodies and coords keep it."""
    tu = sewgen.mechanism("take_up")
    assert list(tu.point_names) + list(tu.body_names) == ["crank_pin", "rocker_pin", "thread_eye", "crank", "lever",
                                                          "rocker"]  # the groups, in order
    text = (ROOT / "generated" / "sg_take_up.c").read_text()
    flags = re.search(r"sg_take_up_group_angles\[7\] = \{ ([0-9, ]+) \}", text).group(1)
    assert flags == "0, 0, 0, 0, 1, 1, 0"
    crank = tu.defaults()["crank"] * np.array([1.0, 1.05])
    eye = tu.sweep_designs({"crank": crank}, PHI, outputs=["points:thread_eye"], threads=1)
    both = tu.sweep_designs({"crank": crank}, PHI, outputs=["points:thread_eye", "bodies:lever"], threads=1)
    for key, arr in eye.outputs.items():
        assert np.array_equal(arr, both.outputs[key])
    lever = both.outputs["bodies.lever.angle"]
    assert np.isfinite(lever).all() and np.ptp(lever[0]) > 0.1  # the lever swings: a real angle, not a skipped 0


def test_columns_stored_straight_take_a_scalar_lane_from_its_rows():
    """A selection's columns are stored by the SIMD loop straight to their arrays (sg_columns); a lane it does not
    vouch for is solved by the scalar step into rows and copied from them. A take-up crank 1e-8 inside its
    assembly limit (found here by bisection) has one position near the toggle whose estimated error (1e-7) is
    above the SIMD loop's acceptance (a quarter of 1e-8); 1e-12 inside, its triangle there is flatter than the SIMD
    margin and the whole block is scalar. With singular="flag" those positions are kept, and the columns must equal
    the full sweep's (rows, no direct columns) to the bit."""
    tu = sewgen.mechanism("take_up")
    phi = np.concatenate([sewgen.shaft_angles(1), [0.25, -3.0]])  # the last two: another order, a turn away
    c0 = tu.defaults()["crank"]
    lo, hi = 1.0, 3.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        try:
            tu.solve(phi, params={"crank": c0 * mid}, singular="flag")
            lo = mid
        except sewgen.errors.PositionError:
            hi = mid
    cols = Columns(tu.description)
    for inside in (1e-8, 1e-12):  # a lane refused for its error estimate; a block refused for a flat triangle
        params = {"crank": c0 * lo * (1 - inside)}
        full = tu.solve(phi, params=params, singular="flag")
        assert full.error_estimate.max() > 0.25e-8 and full.singular.sum() >= 1
        flat = np.hstack([full.q, full.qd, full.qdd, full.obs])
        for outputs in (["coords", "points:thread_eye"], ["all"], ["bodies.lever.angle", "points.thread_eye.y_dd"]):
            sel = tu.solve(phi, params=params, singular="flag", outputs=outputs)
            for name, arr in sel.columns.items():
                assert np.array_equal(arr, flat[:, cols.index[name]]), (inside, name)

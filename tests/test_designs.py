"""Batched designs: ``Mechanism.sweep_designs`` against one ``solve`` sweep per design.

The reference for every design is the engine's single sweep (``prepare`` + ``run``: the same arrays ``solve``
returns, or the status of every position where it would raise); the reductions are checked against NumPy on
those single sweeps. Catalog mechanisms and a user mechanism (closed form and Newton builds), with designs that
fail in the middle of a batch: a NaN parameter, a mechanism that does not assemble at all, one that fails at
some angles only, and branch signs per design.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import sewgen
from sewgen.engine.designs import Columns
from sewgen.errors import ParameterError
from sewgen.engine.loader import catalog

pytestmark = [pytest.mark.c, pytest.mark.derive]

ROOT = Path(__file__).resolve().parents[1]
PHI = sewgen.shaft_angles(7.5)


def _single(mech, phi, params, held=None, branch=None, speed=None, newton=False):
    """One sweep as solve() makes it: (status per position, flat columns (n, width)) or a ParameterError."""
    sweep = mech.prepare(phi, speed, params=params, held=held, branch=branch, newton=newton)
    sweep.run()
    flat = np.hstack([sweep.q, sweep.qd, sweep.qdd, sweep.obs])
    return sweep.status.copy(), flat


def _vary(mech, nd_extra=True):
    """A design table over the defaults: lengths scaled, a NaN in the middle, a design that cannot assemble,
    and for some a scale that fails at some angles only."""
    lengths = [p for p in mech.description.params if p.kind == "length" and p.positive]
    first = lengths[0]
    factors = [1.0, 0.97, 1.04, float("nan"), 1.1, 40.0, 0.9, 1.25, 1.6, 1.0]
    col = np.array([first.default * f for f in factors])
    table = {first.name: col}
    if len(lengths) > 1:
        second = lengths[1]
        table[second.name] = np.array([second.default * f for f in (1, 1, 0.98, 1, 1.03, 1, 1.01, 1, 1, 0.5)])
    return table


def _compare(mech, res, table, phi, held_rows=None, branch_rows=None, newton=False):
    cols = Columns(mech.description)
    nd = len(res)
    names = list(table)
    failing_in_middle = 0
    for d in range(nd):
        params = {k: float(v[d]) for k, v in table.items()}
        held = None if held_rows is None else held_rows[d]
        branch = None if branch_rows is None else branch_rows[d]
        if any(not math.isfinite(v) for v in params.values()):
            assert res.status[d] == 8 and res.first_bad_angle[d] == -1
            with pytest.raises(ParameterError) as exc:
                mech.solve(phi, params=params, held=held, branch=branch)
            assert str(exc.value) == res.error[d]
            assert np.isnan(res.outputs[cols.names[0]][d]).all()
            continue
        try:
            status, flat = _single(mech, phi, params, held, branch, newton=newton)
        except ParameterError as exc:  # a derived dimension that is not real: named as the single solve does
            assert res.status[d] == 8, (d, str(exc))
            assert exc.parameter.split(", ")[0] in res.error[d]
            continue
        bad = np.flatnonzero(status)
        if bad.size:
            assert res.status[d] == status[bad[0]], (mech.name, d, names)
            assert res.first_bad_angle[d] == bad[0]
            assert res.error[d] and res.error[d].startswith(mech.name)
            failing_in_middle += bool(bad[0] > 0)
            with pytest.raises(sewgen.errors.PositionError) as exc:
                mech.solve(phi, params=params, held=held, branch=branch, newton=newton)
            assert exc.value.index == bad[0] and res.error[d].split(":")[1] == str(exc.value).split(":")[1]
            for name in res.outputs:
                assert np.isnan(res.outputs[name][d]).all()
            continue
        assert res.status[d] == 0 and res.first_bad_angle[d] == -1 and res.error[d] is None, (mech.name, d)
        for name, arr in res.outputs.items():
            ref = flat[:, cols.index[name]]
            scale = max(np.abs(ref).max(), 1e-300)
            np.testing.assert_allclose(arr[d], ref, rtol=1e-13, atol=1e-13 * scale, err_msg=f"{mech.name} {name}")
    return failing_in_middle


@pytest.mark.parametrize("name", catalog())
def test_every_catalog_mechanism_batched_equals_single_sweeps(name):
    mech = sewgen.mechanism(name)
    table = _vary(mech)
    nd = len(next(iter(table.values())))
    branch_rows = None
    branch = None
    if mech.branch_names:  # flip the first dyad's sign on two designs
        j = mech.branch_names[0]
        default = mech.description.branches[0].default
        signs = np.full(nd, default)
        signs[[2, 6]] = -default
        branch = {j: signs}
        branch_rows = [{j: int(s)} for s in signs]
    held, held_rows = None, None
    if mech.held_names:
        h = mech.held_names[0]
        vals = np.radians(np.linspace(-20, 20, nd))
        held = {h: vals}
        held_rows = [{h: float(v)} for v in vals]
    res = mech.sweep_designs(table, PHI, held=held, branch=branch, threads=2, chunk=3)
    _compare(mech, res, table, PHI, held_rows, branch_rows)
    assert res.status[3] == 8 and res.status[0] == 0


def test_failures_in_the_middle_of_a_batch_leave_the_others_alone():
    tu = sewgen.mechanism("take_up")
    crank = tu.defaults()["crank"]
    rocker = tu.defaults()["rocker"]
    # a longer crank: the four-bar stops assembling over part of the turn only
    table = {"crank": np.array([crank, crank * 1.0, crank * 2.2, np.nan, crank * 0.9, crank * 40, crank]),
             "rocker": np.array([rocker] * 7)}
    res = tu.sweep_designs(table, PHI, threads=2, chunk=1)
    assert _compare(tu, res, table, PHI) >= 1  # at least one design fails at an angle after the first
    assert list(res.status[[0, 1, 4, 6]]) == [0, 0, 0, 0]
    assert res.status[3] == 8 and res.status[5] == 1 and res.first_bad_angle[5] == 0
    # the same design alone and among failing ones: bit for bit
    alone = tu.sweep_designs({"crank": [crank]}, PHI)
    for name, arr in alone.outputs.items():
        assert np.array_equal(arr[0], res.outputs[name][0])


def test_unsorted_and_repeated_angles_and_a_speed_per_position():
    tu = sewgen.mechanism("take_up")
    rng = np.random.default_rng(3)
    phi = rng.uniform(-4, 10, 40)
    phi[5] = phi[6]
    speed = rng.uniform(50, 300, 40)
    table = {"crank": tu.defaults()["crank"] * np.array([1.0, 1.05, 0.95])}
    res = tu.sweep_designs(table, phi, speed, outputs="all")
    for d in range(3):
        m = tu.solve(phi, speed, params={"crank": float(table["crank"][d])})
        np.testing.assert_allclose(res["bodies.lever.angle"][d], m.body("lever").angle, rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(res["coords.lever.angle_dd"][d], m.coord("lever.angle").accel, rtol=1e-13)
        np.testing.assert_allclose(res["points.thread_eye.y_dd"][d], m.point("thread_eye").ay, rtol=1e-13)


def test_reductions_equal_numpy_on_the_full_outputs():
    nb = sewgen.mechanism("needle_bar")
    names = [p for p in nb.param_names if nb.description.param(p).kind == "length"
             and nb.description.param(p).positive]
    rng = np.random.default_rng(7)
    table = {n: nb.defaults()[n] * rng.uniform(0.95, 1.05, 25) for n in names[:2]}
    eye = nb.description.role_name("needle_eye")
    red = {f"points.{eye}.y": ["min", "max", "mean", "rms", "absmax"], f"points.{eye}.a": "max",
           "bodies.rod.angle": ["min", "max"]}
    fused = nb.sweep_designs(table, PHI, reduce=red)
    assert fused.outputs == {}
    full = nb.sweep_designs(table, PHI, outputs="all", threads=1)
    y, ydd, xdd = (full[f"points.{eye}.{f}"] for f in ("y", "y_dd", "x_dd"))
    a = np.sqrt(xdd ** 2 + ydd ** 2)
    ang = full["bodies.rod.angle"]
    want = {f"points.{eye}.y:min": y.min(1), f"points.{eye}.y:max": y.max(1), f"points.{eye}.y:mean": y.mean(1),
            f"points.{eye}.y:rms": np.sqrt((y ** 2).mean(1)), f"points.{eye}.y:absmax": np.abs(y).max(1),
            f"points.{eye}.a:max": a.max(1), "bodies.rod.angle:min": ang.min(1), "bodies.rod.angle:max": ang.max(1)}
    for key, ref in want.items():
        np.testing.assert_allclose(fused[key], ref, rtol=1e-13, err_msg=key)
    assert np.array_equal(fused[f"points.{eye}.y:min.index"], y.argmin(1))
    assert np.array_equal(fused[f"points.{eye}.y:max.index"], y.argmax(1))
    assert np.array_equal(fused[f"points.{eye}.a:max.index"], a.argmax(1))
    assert f"points.{eye}.y:mean.index" not in fused.reductions


def test_input_forms_convert_once_per_column_and_agree():
    tu = sewgen.mechanism("take_up")
    mm = np.array([8.0, 8.5, 9.0])
    si = {"crank": mm / 1000}
    ref = tu.sweep_designs(si, PHI, outputs="points:thread_eye")
    forms = [{"crank [mm]": mm}, {"crank": [f"{v} mm" for v in mm]}, {"crank": np.array([f"{v} mm" for v in mm])},
             np.tile(tu.default_vectors["p"], (3, 1))]
    forms[-1][:, tu.param_names.index("crank")] = mm / 1000
    pint = pytest.importorskip("pint")
    forms.append({"crank": pint.UnitRegistry().Quantity(mm, "mm")})
    for form in forms:
        got = tu.sweep_designs(form, PHI, outputs="points:thread_eye")
        assert list(got.outputs) == list(ref.outputs)
        for name in ref.outputs:
            np.testing.assert_allclose(got[name], ref[name], rtol=1e-13, atol=0)  # 9 mm * 1e-3 vs 9e-3: an ulp
    # a scalar string applies to every design; a per-design held/branch array
    one = tu.sweep_designs({"crank": "8.5 mm", "rocker": si["crank"] * 0 + tu.defaults()["rocker"]}, PHI,
                           outputs=["points.thread_eye.y"])
    np.testing.assert_allclose(one["points.thread_eye.y"][1], ref["points.thread_eye.y"][1], rtol=1e-15)


def test_dataframe_in_and_out():
    pd = pytest.importorskip("pandas")
    tu = sewgen.mechanism("take_up")
    df = pd.DataFrame({"crank [mm]": [8.0, 9.0, float("nan"), 500.0], "rocker": [0.03, 0.031, 0.03, 0.03]})
    res = tu.sweep_designs(df, PHI, reduce={"points.thread_eye.a": "max", "points.thread_eye.y": ["min", "max"]})
    out = res.to_dataframe()
    assert len(out) == 4
    assert list(out["status"]) == list(res.status)
    assert "points.thread_eye.a:max [m/s^2]" in out.columns and "points.thread_eye.y:max.index" in out.columns
    assert out["crank [m]"].iloc[1] == pytest.approx(0.009, rel=1e-15)
    assert out["error"].iloc[0] is None and "crank" in out["error"].iloc[2]


def test_bad_arguments_are_typed_and_named():
    tu = sewgen.mechanism("take_up")
    with pytest.raises(ParameterError, match="'crankk'"):
        tu.sweep_designs({"crankk": [0.01]}, PHI)
    with pytest.raises(ParameterError, match="'rocker'.*designs"):
        tu.sweep_designs({"crank": [0.01, 0.02], "rocker": [0.03, 0.03, 0.03]}, PHI)
    with pytest.raises(ParameterError, match="'crank'"):
        tu.sweep_designs({"crank": ["8 kg"]}, PHI)
    with pytest.raises(ParameterError, match="outputs"):
        tu.sweep_designs({"crank": [0.01]}, PHI, outputs=["points:nowhere"])
    with pytest.raises(ParameterError, match="reduce"):
        tu.sweep_designs({"crank": [0.01]}, PHI, reduce={"points.thread_eye.y": "median"})
    with pytest.raises(ParameterError, match="'C'"):
        tu.sweep_designs({"crank": [0.01]}, PHI, branch={"C": [2]})
    with pytest.raises(ParameterError, match="designs"):
        tu.sweep_designs(np.zeros((2, 3)), PHI)


@pytest.fixture(scope="module")
def user_mechs(tmp_path_factory):
    path = ROOT / "examples" / "my_mechanism.py"
    return sewgen.load(path), sewgen.load(path, closed_form=False)


def test_a_user_mechanism_batched_equals_single_sweeps(user_mechs):
    for mech in user_mechs:
        table = _vary(mech)
        res = mech.sweep_designs(table, PHI, threads=2, chunk=2)
        _compare(mech, res, table, PHI)
        nd = len(res)
        assert (res.status == 0).sum() >= 3 and (res.status != 0).sum() >= 2


def test_threads_do_not_change_results():
    tu = sewgen.mechanism("take_up")
    table = {"crank": tu.defaults()["crank"] * np.linspace(0.8, 1.6, 101)}
    a = tu.sweep_designs(table, PHI, threads=1, reduce={"points.thread_eye.a": "max"}, outputs="coords")
    b = tu.sweep_designs(table, PHI, threads=2, chunk=7, reduce={"points.thread_eye.a": "max"}, outputs="coords")
    assert np.array_equal(a.status, b.status) and np.array_equal(a.first_bad_angle, b.first_bad_angle)
    for name in a.outputs:
        assert np.array_equal(a[name], b[name], equal_nan=True)
    assert np.array_equal(a["points.thread_eye.a:max"], b["points.thread_eye.a:max"], equal_nan=True)


@pytest.mark.parametrize("name", catalog())
def test_selected_outputs_equal_the_full_sweeps_columns_exactly(name):
    mech = sewgen.mechanism(name)
    cols = Columns(mech.description)
    rng = np.random.default_rng(11)
    phi = np.concatenate([PHI, rng.uniform(-7, 7, 9)])  # unsorted, beyond a turn: the angles made continuous
    full = mech.solve(phi)
    flat = np.hstack([full.q, full.qd, full.qdd, full.obs])
    point = mech.point_names[-1]
    body = mech.body_names[-1]
    for outputs in (["all"], ["coords"], [f"points:{point}"], [f"bodies:{body}", f"points.{point}.y_dd"],
                    [cols.names[-1], cols.names[0]]):
        sel = mech.solve(phi, outputs=outputs)
        for cname, arr in sel.columns.items():
            assert arr.flags.c_contiguous
            assert np.array_equal(arr, flat[:, cols.index[cname]]), (name, cname)
    sel = mech.solve(phi, outputs=[f"points:{point}"])
    assert np.array_equal(sel.point(point).ay, full.point(point).ay)
    again = mech.solve(phi, outputs=[f"points:{point}"], out=sel)  # out=: the same block, rewritten
    assert again.block is sel.block


def test_selected_outputs_raise_as_solve_does():
    tu = sewgen.mechanism("take_up")
    with pytest.raises(sewgen.errors.AssemblyError) as a:
        tu.solve(PHI, params={"crank": 0.05})
    with pytest.raises(sewgen.errors.AssemblyError) as b:
        tu.solve(PHI, params={"crank": 0.05}, outputs=["coords"])
    assert str(a.value) == str(b.value)
    with pytest.raises(ParameterError, match="outputs"):
        tu.solve(PHI, outputs=["nothing"])


@pytest.mark.parametrize("name", catalog())
def test_the_lean_selected_path_equals_the_general_one_to_the_bit(name):
    """solve(outputs=...)'s per-call path (cached selection, the thread's scratch) against the general one
    (held={} takes it): the same columns, bit for bit, in sorted, unsorted and shifted angles, with params=."""
    m = sewgen.mechanism(name)
    rng = np.random.default_rng(7)
    sels = (["coords", f"points:{m.point_names[0]}"], f"bodies:{m.body_names[-1]}", ("all",))
    for phi in (PHI, np.concatenate([PHI, rng.uniform(-9, 9, 11)]), PHI + 7.0, np.array([3.0])):
        for params in (None, {m.param_names[-1]: m.defaults()[m.param_names[-1]]}):
            for sel in sels:
                a = m.solve(phi, params=params, outputs=sel)
                b = m.solve(phi, params=params, outputs=sel, held={})
                assert list(a.keys()) == list(b.keys())
                assert np.array_equal(a.block, b.block) and np.array_equal(a.phi, b.phi), name
                assert np.array_equal(a.omega, b.omega) and np.array_equal(a.alpha, b.alpha)


@pytest.mark.parametrize("name", catalog())
def test_the_lean_solve_path_equals_the_general_one_to_the_bit(name):
    """solve()'s per-call fast path (one buffer, cached parameter vectors, the angles made continuous in C)
    against prepare() + the C call + continuous_angles in Python: the same arrays, bit for bit."""
    from sewgen.engine.mechanism import continuous_angles

    m = sewgen.mechanism(name)
    rng = np.random.default_rng(5)
    for phi in (PHI, np.concatenate([PHI, rng.uniform(-9, 9, 11)]), PHI + 7.0, np.array([3.0])):
        for params in (None, {m.param_names[-1]: m.defaults()[m.param_names[-1]]}):
            a = m.solve(phi, params=params)
            s = m.prepare(phi, params=params)
            s.bind()()
            continuous_angles(m.description, s.q, s.obs, s.order)
            for x, y in ((a.q, s.q), (a.qd, s.qd), (a.qdd, s.qdd), (a.obs, s.obs), (a.error_estimate, s.err),
                         (a.phi, s.phi), (a.omega, s.omega), (a.alpha, s.alpha)):
                assert np.array_equal(x, y), name
    with pytest.raises(sewgen.errors.InputError, match="position 1"):
        m.solve(np.array([0.1, np.nan, 0.3]))


@pytest.mark.parametrize("name", catalog())
def test_the_lean_kinetostatics_path_equals_the_general_one_to_the_bit(name):
    """kinetostatics() on the defaults (no loads, default gravity and moment point) takes solve()'s one-call lean
    path with forces: every array and the run settings equal the general path's (held={} forces it) bit for bit,
    and a failure still raises the general path's typed error."""
    m = sewgen.mechanism(name)
    rng = np.random.default_rng(6)
    for phi in (PHI, np.concatenate([PHI, rng.uniform(-9, 9, 11)]), np.array([3.0])):
        for params in (None, {m.param_names[-1]: m.defaults()[m.param_names[-1]]}):
            a = m.kinetostatics(phi, params=params)
            b = m.kinetostatics(phi, params=params, held={})
            assert "_lean" in vars(a.motion)  # the lean path ran
            for x, y in ((a.frc, b.frc), (a.motion.q, b.motion.q), (a.motion.qd, b.motion.qd),
                         (a.motion.qdd, b.motion.qdd), (a.motion.obs, b.motion.obs),
                         (a.motion.error_estimate, b.motion.error_estimate), (a.phi, b.phi)):
                assert np.array_equal(x, y), name
            sa, sb = a.run_settings, b.run_settings
            for x, y in ((sa.params, sb.params), (sa.held, sb.held), (sa.branch, sb.branch), (sa.gravity, sb.gravity)):
                assert np.array_equal(x, y), name
            assert sa.loads is None and sb.loads is None and sa.moment_about == sb.moment_about == (0.0, 0.0)
    with pytest.raises(sewgen.errors.InputError, match="position 1"):
        m.kinetostatics(np.array([0.1, np.nan, 0.3]))


def test_a_lean_motion_reads_pickles_and_copies_as_any_other():
    """solve()'s lean Motion makes its arrays at the first look (Motion.of_block): a strided phi, a pickle of a
    result not yet looked at, and a result read in any order give the general path's arrays."""
    import pickle

    m = sewgen.mechanism("take_up")
    phi = np.linspace(6.0, -1.0, 40)[::-2]  # strided, and ascending only after the reversal
    ref = m.prepare(phi)
    ref.bind()()
    from sewgen.engine.mechanism import continuous_angles

    continuous_angles(m.description, ref.q, ref.obs, ref.order)
    for look in ("pickle", "qdd", "error_estimate", "len"):
        a = m.solve(phi)
        assert "_lean" in vars(a)  # nothing made yet
        if look == "pickle":
            a = pickle.loads(pickle.dumps(a))
        elif look == "len":
            assert len(a) == len(phi)
        else:
            getattr(a, look)
        assert "_lean" not in vars(a)
        for x, y in ((a.q, ref.q), (a.qd, ref.qd), (a.qdd, ref.qdd), (a.obs, ref.obs), (a.error_estimate, ref.err),
                     (a.phi, ref.phi), (a.omega, ref.omega), (a.alpha, ref.alpha)):
            assert np.array_equal(x, y), look
        assert np.array_equal(a.point("thread_eye").y, ref.obs[:, m.description.point("thread_eye").offset + 1])
    with pytest.raises(AttributeError, match="no attribute 'nonsense'"):
        m.solve(phi).nonsense  # noqa: B018


def test_cached_parameter_vectors_still_check_every_call():
    tu = sewgen.mechanism("take_up")
    tu.solve(PHI, params={"crank.mass": 1})
    with pytest.raises(ParameterError, match="crank.mass"):
        tu.solve(PHI, params={"crank.mass": True})  # equal to 1, another type: not the cached vector
    with pytest.raises(ParameterError, match="crank"):
        tu.solve(PHI, params={"crank": -0.01})
    d = {"crank": 0.011}
    a = tu.solve(PHI, params=d)
    d["crank"] = 0.009
    b = tu.solve(PHI, params=d)
    assert not np.array_equal(a.obs, b.obs)
    np.testing.assert_array_equal(b.obs, tu.solve(PHI, params={"crank": 0.009}).obs)


def _paths_agree(mech, phi, **kw):
    a = mech.prepare(phi, **kw)
    b = mech.prepare(phi, **kw)
    a.use_loop("scalar")  # the inlined scalar loop (the SIMD one against it: tests/test_simd.py)
    b.use_loop("generic")
    for s in (a, b):
        s.phi[len(phi) // 3] = np.nan  # a NaN input reaches C (Python refuses it before; C says SG_NAN_INPUT)
        s.bind()()
    for x, y in ((a.q, b.q), (a.qd, b.qd), (a.qdd, b.qdd), (a.obs, b.obs), (a.err, b.err), (a.status, b.status)):
        assert np.array_equal(x, y), mech.name
    if a.forces:
        assert np.array_equal(a.frc, b.frc), mech.name
    return a.status


def varying_loads(mech):
    """A force at the first point over part of the turn and a torque on the first moving body: loads that change
    from position to position (the kinetostatic loops read a row of them per position)."""
    from sewgen.engine.loads import Load

    body = mech.description.bodies[0].name  # the description lists moving bodies only
    return [Load(mech.point_names[0], fx=3.0, fy=-2.0, window=(1.0, 2.5)), Load(body, torque=0.4)]


@pytest.mark.parametrize("name", catalog())
def test_the_inlined_sweep_equals_the_generic_loop_to_the_bit(name):
    """sg_<m>_sweep (the kernels inlined into one closed-form loop) against the runtime's generic loop (kernels
    through the descriptor, opt->generic): every output, error estimate and status, with failing positions, a
    NaN input, unsorted angles and singular positions kept or not."""
    mech = sewgen.mechanism(name)
    rng = np.random.default_rng(2)
    phi = np.concatenate([PHI, rng.uniform(-7, 7, 13)])
    statuses = [_paths_agree(mech, phi)]
    statuses.append(_paths_agree(mech, phi, singular="flag"))
    _paths_agree(mech, phi, forces=True)  # the inlined loop's kinetostatics, with loads and without
    _paths_agree(mech, phi, forces=True, loads=varying_loads(mech), singular="flag")
    lengths = [p for p in mech.description.params if p.kind == "length" and p.positive]
    for f in (1.3, 2.2, 40.0):
        try:
            statuses.append(_paths_agree(mech, phi, params={lengths[0].name: lengths[0].default * f}))
        except ParameterError:
            pass
    assert any(np.any(s == 4) for s in statuses)


def test_the_inlined_sweep_of_a_user_mechanism(user_mechs):
    closed, newton = user_mechs
    assert closed.closed_form and not newton.closed_form
    phi = np.concatenate([PHI, np.linspace(-3, 9, 17)])
    for mech in user_mechs:
        status = _paths_agree(mech, phi)
        assert (status == 4).sum() == 1
        _paths_agree(mech, phi, params={"crank": mech.defaults()["crank"] * 2.5})


def test_a_design_sweep_pickles_and_may_be_empty():
    import pickle

    tu = sewgen.mechanism("take_up")
    res = tu.sweep_designs({"crank": [0.01, np.nan, 0.05]}, PHI, reduce={"points.thread_eye.a": "max"},
                           outputs="coords")
    back = pickle.loads(pickle.dumps(res))
    assert list(back.status) == [0, 8, 1] and back.error == res.error
    np.testing.assert_array_equal(back["points.thread_eye.a:max"], res["points.thread_eye.a:max"])
    assert isinstance(res.exception(2), sewgen.errors.AssemblyError)
    assert np.isnan(res.first_bad_phi[0]) and res.first_bad_phi[2] == PHI[res.first_bad_angle[2]]
    empty = tu.sweep_designs({"crank": np.zeros(0)}, PHI, reduce={"points.thread_eye.a": "max"})
    assert len(empty) == 0 and empty["points.thread_eye.a:max"].shape == (0,)
    sel = tu.solve(PHI, outputs="points:thread_eye")
    assert list(pickle.loads(pickle.dumps(sel)).keys()) == list(sel.keys())


@pytest.mark.parametrize("name", [n for n in catalog() if sewgen.mechanism(n).manifest.get("closed_form")])
def test_a_batch_equals_its_designs_solved_alone_to_the_bit(name):
    """A batch of designs takes the shaft angles' cos and sin from one table for every design (the SIMD loop's
    own vector math, computed once): each design's columns equal its own solve() bit for bit."""
    m = sewgen.mechanism(name)
    length = next(p for p in m.description.params if p.kind == "length" and p.positive)
    values = length.default * np.array([1.0, 1.01, 0.995])
    res = m.sweep_designs({length.name: values}, PHI, threads=1)
    cols = Columns(m.description)
    assert (res.status == 0).all()
    for d, v in enumerate(values):
        alone = m.solve(PHI, params={length.name: float(v)})
        flat = np.hstack([alone.q, alone.qd, alone.qdd, alone.obs])
        for col, arr in res.outputs.items():
            assert np.array_equal(arr[d], flat[:, cols.index[col]]), (name, d, col)


def test_a_design_with_a_friction_coefficient_out_of_its_range_is_refused_alone():
    """A design table's parameter goes through the same range check as params= (a friction coefficient is in
    [0, 1]): the bad designs are named, the good one sweeps as solve() does."""
    nb = sewgen.mechanism("needle_bar")
    res = nb.sweep_designs({"B.friction": [0.1, 10.0, -0.2]}, PHI, reduce={"coords.needle_bar.travel": "max"})
    assert list(res.ok) == [True, False, False]
    for d in (1, 2):
        assert isinstance(res.exception(d), ParameterError) and "B.friction" in res.error[d]
    with pytest.raises(ParameterError, match="B.friction"):
        nb.solve(PHI, params={"B.friction": 10.0})

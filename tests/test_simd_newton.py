"""The SIMD Newton and SIMD finish of a mechanism Newton solves (csrc/sg_simd.h
SG_SIMD_NEWTON_BODY and SG_SIMD_FINISH_BODY) against the scalar loop.

Both loops solve fine sweeps in blocks of eight positions predicted from the same five newest states (csrc/
sg_runtime.c solve_block), coarse ones and whatever a block refuses step by step; the SIMD loop takes Newton's
usual course (one full step) SG_LANES positions at a time (8 with AVX-512, else 4) with the vector twins of the
residual and of Newton's LU, leaving any other course to the scalar newton(), then hands the solved positions to
the vector twins of the motion, rates, observe and forces kernels, which repeat the scalar kernels' operations
lane by lane (the cam's arc chosen by lane masks, Φ_q factored by its diagonal blocks in vectors): every value
must equal the scalar loop's to the bit, and every status too, with NaN inputs in the middle of a block, unsorted
and repeated angles, a short last block, designs that stop assembling at some angles, singular positions kept or
refused, loads, a few outputs selected.
A wrong lane, a wrong arc or a wrong pivot shows as a difference. The blocks' positions are then held to the
step-by-step continuation's (an independent path to the same solutions).
"""
from __future__ import annotations

import numpy as np
import pytest

import sewgen
from test_designs import varying_loads
from test_simd import _run_both  # (SIMD sweep, scalar sweep) of the same arguments, run

pytestmark = [pytest.mark.c]

RNG = np.random.default_rng(21)
#: a revolution at 0.1°, a few unsorted and repeated angles, a short last block (3615 = 4k + 3 = 8k' + 7)
PHI = np.concatenate([np.linspace(0.0, 2 * np.pi, 3600, endpoint=False), RNG.uniform(-7, 7, 13), [1.0, 1.0]])
FIELDS = ("q", "qd", "qdd", "obs", "err", "status")


@pytest.fixture(scope="module")
def feed():
    mech = sewgen.mechanism("feed")
    if mech.simd_width == 1:
        pytest.skip("feed: no SIMD finish on this build or CPU (Mechanism.simd_width == 1)")
    return mech


def _arc_column(feed):
    """The observable column of the feed cam's active arc (its number)."""
    arc = [k for k, o in enumerate(feed.manifest["observables"]) if o["name"].endswith(".arc")]
    assert len(arc) == 1
    return arc[0]


def _same(a, b, label, fields=FIELDS):
    for k in fields:
        np.testing.assert_array_equal(getattr(a, k), getattr(b, k), err_msg=f"{label}: {k}")


def test_a_newton_mechanism_has_the_simd_finish(feed):
    assert feed.simd_width in (4, 8)  # the catalog module's lanes: AVX2 or AVX-512
    assert feed.simd_width == sewgen.mechanism("take_up").simd_width  # the closed-form loops' too
    assert not feed.closed_form


@pytest.mark.parametrize("kw", [{}, {"singular": "flag"}], ids=["refuse", "flag"])
def test_kinematics_equal_the_scalar_loop_to_the_bit(feed, kw):
    a, b = _run_both(feed, PHI, nan_at=(5, 1802), **kw)
    _same(a, b, f"feed {kw}")
    assert (b.status[[5, 1802]] == 4).all()  # the NaN inputs reached C
    assert (b.status == 0).sum() == len(PHI) - 2
    # the cam's arc changes along the turn: every lane mask of the selection was exercised
    assert len(np.unique(b.obs[:3600, _arc_column(feed)])) == 6


@pytest.mark.parametrize("param, factor", [("feed_arm_p", 0.5), ("hook_crank", 1.5), ("rock_front_arm", 0.5)])
def test_designs_that_stop_assembling(feed, param, factor):
    """Positions that fail (no assembly, a branch jump) between ones that solve, in and out of blocks of four."""
    params = {param: feed.defaults()[param] * factor}
    a, b = _run_both(feed, PHI, params=params, singular="flag")
    _same(a, b, f"feed {param}×{factor}")
    assert 0 < (b.status != 0).sum() < len(PHI) - 100


def test_kinetostatics_equal_the_scalar_loop_to_the_bit(feed):
    for kw in ({}, {"loads": varying_loads(feed), "singular": "flag"}):
        a, b = _run_both(feed, PHI, nan_at=(9,), forces=True, **kw)
        _same(a, b, f"feed forces {kw}", FIELDS + ("frc",))
        assert b.status[9] == 4 and (b.status == 0).sum() == len(PHI) - 1
        assert np.abs(b.frc).max() > 0.0


def test_with_friction_the_whole_sweep_is_scalar(feed):
    frictions = [p.name for p in feed.description.params if p.name.endswith(".friction")]
    assert frictions
    a, b = _run_both(feed, PHI, forces=True, params={frictions[0]: 0.1})
    _same(a, b, "feed with friction", FIELDS + ("frc",))


def test_design_sweeps_with_a_few_outputs(feed):
    """Design sweeps that keep a point, a body or a reduction compute only their groups (kernels rates_v,
    observe_v in the SIMD finish): the same outputs, statuses and failing angles as the scalar loop, to the bit."""
    lengths = [p for p in feed.description.params if p.kind == "length" and p.positive]
    table = {lengths[0].name: np.array([lengths[0].default * f for f in (1.0, 0.97, float("nan"), 1.1, 40.0, 1.6)])}
    phi = sewgen.shaft_angles(2.5)
    for outputs, reduce in ((None, None), (["points:feed_dog"], None), (["bodies:rock_shaft", "coords"], None),
                            ([], {"points.feed_dog.a": "max", "points.feed_dog.y": "min"})):
        a, b = (feed.sweep_designs(table, phi, threads=1, outputs=outputs, reduce=reduce, loop=loop)
                for loop in ("auto", "scalar"))
        np.testing.assert_array_equal(a.status, b.status)
        np.testing.assert_array_equal(a.first_bad_angle, b.first_bad_angle)
        assert (b.status != 0).any() and (b.status == 0).any()
        for key, arr in b.outputs.items():
            np.testing.assert_array_equal(a.outputs[key], arr, err_msg=key)
        for key in b.reductions:
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)


def test_a_user_mechanism_solved_by_newton():
    """examples/my_mechanism.py without its closed form: Newton, and the SIMD finish of its twins."""
    from pathlib import Path

    mech = sewgen.load(Path(__file__).resolve().parents[1] / "examples" / "my_mechanism.py", closed_form=False)
    assert (mech.simd_width > 1) == (sewgen.mechanism("feed").simd_width > 1)  # a SIMD finish where the CPU runs one
    for kw in ({}, {"params": {"crank": mech.defaults()["crank"] * 2.5}, "singular": "flag"}):
        a, b = _run_both(mech, PHI, nan_at=(7,), **kw)
        _same(a, b, f"{mech.name} {kw}")
        assert b.status[7] == 4 and (b.status == 0).any()
    a, b = _run_both(mech, PHI, forces=True)
    _same(a, b, f"{mech.name} forces", FIELDS + ("frc",))


def test_blocks_agree_with_the_step_by_step_continuation(feed):
    """A revolution at 0.1° is solved in blocks of eight (each position predicted up to 0.8° ahead), one at 5° step
    by step (two positions would span 10°, beyond SG_BLOCK_SPAN): at their common angles both converge to the same
    positions, rates and forces. The tolerance is the conditioning's, not the blocks': before the blocks the two
    resolutions differed by up to 2.8e-11 of a coordinate's range (the rock shaft near its dead centre), and a
    solve that stopped short of rounding (Newton's tolerance, 1e-10 of each loop's size) or took another branch
    would differ far more."""
    fine, coarse = np.linspace(0.0, 2 * np.pi, 3600, endpoint=False), np.linspace(0.0, 2 * np.pi, 72, endpoint=False)
    a = feed.prepare(fine, forces=True).use_loop("scalar")
    b = feed.prepare(coarse, forces=True).use_loop("scalar")
    a.run()
    b.run()
    assert (a.status == 0).all() and (b.status == 0).all()
    # where a sample falls on a switch of the cam's arcs (q'' jumps there) the two may take either side of it
    arc = _arc_column(feed)
    same_arc = a.obs[::50, arc] == b.obs[:, arc]
    assert same_arc.sum() >= 66
    for k in ("q", "qd", "qdd", "obs", "frc"):
        x, y = getattr(a, k)[::50], getattr(b, k)
        if k not in ("q", "qd"):
            x, y = x[same_arc], y[same_arc]
        scale = np.maximum(np.abs(y).max(axis=0), 1e-300)
        assert (np.abs(x - y) / scale).max() < 1e-10, k
    # backwards along the turn: blocks in the other direction, the same solutions
    c = feed.prepare(fine[::-1].copy(), forces=True).use_loop("auto")
    c.run()
    assert (c.status == 0).all()
    np.testing.assert_allclose(c.q[::-1], a.q, rtol=0, atol=1e-10)

"""The SIMD closed-form loop (csrc/sg_simd.h) against the scalar loop.

Both loops run the same sweep through ``Sweep.use_loop``: every catalog mechanism with a closed form and a user
mechanism (examples/my_mechanism.py), with unsorted and repeated angles, NaN inputs in the middle of a block,
designs that fail to assemble at some angles or everywhere, singular positions kept or refused. Statuses must be
identical (so the first failing angle is too: the SIMD loop hands every position it does not vouch for to the
scalar step). Values agree to 1e-13 of each column's scale, or, at a position the runtime itself estimates less
accurate than that (near a toggle, where both paths' rounding is amplified alike), within twice that estimate.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

import sewgen
from sewgen.engine.build import compile_flags
from sewgen.errors import ParameterError
from sewgen.engine.loader import catalog, catalog_module
from sewgen.engine.mechanism import Mechanism

pytestmark = [pytest.mark.c, pytest.mark.derive]

ROOT = Path(__file__).resolve().parents[1]
RNG = np.random.default_rng(14)
#: a revolution at 0.1° (900 blocks of four, 450 of eight), a few unsorted and repeated angles, a short block tail
PHI = np.concatenate([np.linspace(0.0, 2 * np.pi, 3600, endpoint=False), RNG.uniform(-7, 7, 13), [1.0, 1.0]])

SIMD_CLOSED = [n for n in catalog() if sewgen.mechanism(n).closed_form]


def _run_both(mech, phi, nan_at=(), **kw):
    """(SIMD sweep, scalar sweep) of the same arguments, run; NaN written into phi at ``nan_at`` (C's own check)."""
    runs = []
    for loop in ("auto", "scalar"):
        s = mech.prepare(phi, **kw).use_loop(loop)
        for i in nan_at:
            s.phi[i] = np.nan
        s.run()
        runs.append(s)
    return runs


def _both(mech, phi, nan_at=(), **kw):
    """:func:`_run_both` and the scalar loop's sensitivity of every output to the shaft angle."""
    a, b = _run_both(mech, phi, nan_at, **kw)
    return a, b, _sensitivity(mech, b, kw)


def _sensitivity(mech, ref, kw, h=1e-6):
    """|d output / d phi| per position and column by one-sided differences of the scalar loop at phi ± h (the
    larger of the two; inf where neither neighbour solves: within h of where the mechanism stops assembling)."""
    flat = lambda s: np.hstack([s.q, s.qd, s.qdd, s.obs])
    base = flat(ref)
    sens = np.full_like(base, -np.inf)
    for step in (h, -h):
        s = mech.prepare(np.nan_to_num(ref.phi) + step, **kw).use_loop("scalar")
        s.run()
        good = (s.status == 0) & (ref.status == 0)
        sens[good] = np.maximum(sens[good], np.abs(flat(s)[good] - base[good]) / h)
    sens[~np.isfinite(sens)] = np.inf
    return sens


def _agree(a, b, sens, label, rtol=1e-13):
    """Equal statuses; every value within ``rtol`` of its column's scale plus what the position's own rounding
    makes of it: twice the runtime's error estimate of the rates, and the sensitivity to the shaft angle times
    16 ulp of it (libmvec's and glibc's sin, cos differ by an ulp or two, which a position near the end of its
    assembling range amplifies like any perturbation of the input)."""
    np.testing.assert_array_equal(a.status, b.status, err_msg=f"{label}: statuses")
    ok = b.status == 0
    x, y = np.hstack([a.q, a.qd, a.qdd, a.obs])[ok], np.hstack([b.q, b.qd, b.qdd, b.obs])[ok]
    if not y.size:
        return
    scale = np.maximum(np.abs(y).max(axis=0), 1e-300)
    tol = (rtol + 2.0 * b.err[ok])[:, None] * scale
    tol = tol + sens[ok] * (16 * np.finfo(float).eps * np.maximum(1.0, np.abs(b.phi[ok])))[:, None]
    bad = np.abs(x - y) > tol
    assert not bad.any(), (label, np.argwhere(bad)[:3], (np.abs(x - y) / scale).max())
    assert np.isinf(sens[ok]).any(axis=1).mean() < 0.02, label  # the sensitivity bounds almost every position
    flagged = (b.status == 0) | (b.status == 2)
    np.testing.assert_allclose(a.err[flagged], b.err[flagged], rtol=1e-9, atol=1e-300, err_msg=label)


def _needs_simd(mech):
    if mech.simd_width == 1:
        pytest.skip(f"{mech.name}: no SIMD loop on this build or CPU (Mechanism.simd_width == 1)")


@pytest.mark.parametrize("name", SIMD_CLOSED)
def test_simd_and_scalar_loops_agree(name):
    mech = sewgen.mechanism(name)
    _needs_simd(mech)
    statuses = []
    for kw in ({}, {"singular": "flag"}):
        a, b, sens = _both(mech, PHI, nan_at=(5, 1802), **kw)
        _agree(a, b, sens, f"{name} {kw}")
        statuses.append(b.status)
    lengths = [p for p in mech.description.params if p.kind == "length" and p.positive]
    for f in (1.3, 2.2, 40.0):
        try:
            a, b, sens = _both(mech, PHI, params={lengths[0].name: lengths[0].default * f}, singular="flag")
        except ParameterError:
            continue
        # ×40: a design that assembles over a few degrees only, every position near the end of its range, where
        # a dyad's discriminant is the small difference of large squares: both loops' rounding is amplified
        # beyond what the rates' estimate or the angle's ulp account for (needle bar: 8.7e-13 of the column)
        _agree(a, b, sens, f"{name} {lengths[0].name}×{f}", rtol=1e-13 if f < 10 else 1e-11)
        statuses.append(b.status)
    assert all((s[[5, 1802]] == 4).all() for s in statuses[:2])  # the NaN inputs reached C
    assert sum(int((s == 0).sum()) for s in statuses) > 2 * len(PHI)  # most positions did run in vectors


@pytest.mark.parametrize("name", SIMD_CLOSED)
def test_simd_kinetostatics_agree_with_the_scalar_loop(name):
    """The forces' SIMD twin (the frictionless solve, loads transposed in per block) against the scalar loop:
    statuses equal, reactions, torques, powers within 1e-13 of each column's scale plus twice the position's
    error estimate; with a friction coefficient on, the SIMD loop hands the whole sweep to the scalar one (equal
    to the bit)."""
    mech = sewgen.mechanism(name)
    _needs_simd(mech)
    from test_designs import varying_loads

    for kw in ({}, {"loads": varying_loads(mech), "singular": "flag"}):
        a, b = _run_both(mech, PHI, nan_at=(9,), forces=True, **kw)
        np.testing.assert_array_equal(a.status, b.status)
        ok = b.status == 0
        scale = np.maximum(np.abs(b.frc[ok]).max(axis=0), 1e-300)
        tol = (1e-13 + 2.0 * b.err[ok])[:, None] * scale
        assert (np.abs(a.frc[ok] - b.frc[ok]) <= tol).all(), (name, (np.abs(a.frc[ok] - b.frc[ok]) / scale).max())
        assert not np.array_equal(a.frc, b.frc)  # the vector forces did run
    frictions = [p.name for p in mech.description.params if p.name.endswith(".friction")]
    if frictions:
        runs = _run_both(mech, PHI, forces=True, params={frictions[0]: 0.1})
        for k in ("q", "qd", "qdd", "obs", "frc", "err", "status"):
            np.testing.assert_array_equal(getattr(runs[0], k), getattr(runs[1], k), err_msg=f"{name} {k}")


def test_most_positions_take_the_vector_path():
    """Not a fallback in disguise: on the take-up four-bar every clean block is vector, so its values differ from
    the scalar loop's by rounding somewhere (libmvec's sin/cos/atan2 are not glibc's scalar ones) and a value
    does not depend on which lane or block it lands in."""
    tu = sewgen.mechanism("take_up")
    _needs_simd(tu)
    a, b, _ = _both(tu, PHI)
    assert not np.array_equal(a.obs, b.obs)
    shifted = tu.prepare(PHI[1:]).use_loop("auto")  # every angle in another lane
    shifted.run()
    np.testing.assert_array_equal(shifted.obs[:3599], a.obs[1:3600])
    again = tu.prepare(PHI).use_loop("auto")
    again.run()
    np.testing.assert_array_equal(again.obs, a.obs)  # deterministic


def _avx2_catalog():
    """The catalog's AVX2 module where the loader runs its AVX-512 one (sewgen/engine/build.py catalog_levels), else
    skip: the tests above ran the AVX2 level already (or this build or CPU has only one level)."""
    if os.environ.get("SEWGEN_KERNELS"):  # CI's sanitized run: its catalog is one build of its own, named
        pytest.skip("SEWGEN_KERNELS names this run's catalog (sewgen._kernels is that build)")
    try:
        import sewgen._kernels_avx512 as wide
    except ImportError:
        pytest.skip("no AVX-512 catalog module in this build")
    import sewgen._kernels as narrow

    if wide.lib.sg_simd_width(wide.ffi.NULL) == 1 or narrow.lib.sg_simd_width(narrow.ffi.NULL) == 1:
        pytest.skip("this CPU runs one SIMD level only")
    assert catalog_module() is wide
    assert (narrow.lib.sg_simd_width(narrow.ffi.NULL), wide.lib.sg_simd_width(wide.ffi.NULL)) == (4, 8)
    return narrow


@pytest.mark.parametrize("name", SIMD_CLOSED)
def test_the_avx2_catalog_agrees_with_the_scalar_loop(name):
    """The catalog is built for AVX2 and for AVX-512, and an AVX-512 CPU runs the second: here the first's SIMD
    loops are held to the scalar loop as the test above holds the loaded module's, failing positions included."""
    narrow = _avx2_catalog()
    mech = Mechanism(narrow.ffi, narrow.lib, name)
    assert mech.simd_width == 4
    for kw in ({}, {"singular": "flag", "forces": True}):
        a, b, sens = _both(mech, PHI, nan_at=(5, 1802), **kw)
        _agree(a, b, sens, f"{name} avx2 {kw}")
        assert (b.status[[5, 1802]] == 4).all()


def test_the_avx2_newton_finish_equals_the_scalar_loop():
    """The AVX2 module's SIMD finish of the JB1-3 feed (four lanes, the short last block of three) equals its
    scalar loop to the bit, kinematics and forces, as tests/test_simd_newton.py holds the loaded module's."""
    narrow = _avx2_catalog()
    feed = Mechanism(narrow.ffi, narrow.lib, "feed")
    assert feed.simd_width == 4
    for kw in ({}, {"forces": True, "singular": "flag"}):
        a, b = _run_both(feed, PHI, nan_at=(5, 1802), **kw)
        for k in ("q", "qd", "qdd", "obs", "err", "status") + (("frc",) if kw else ()):
            np.testing.assert_array_equal(getattr(a, k), getattr(b, k), err_msg=f"feed avx2 {kw}: {k}")


def test_the_other_simd_level(monkeypatch):
    """A user's mechanism is built for one SIMD level, the building CPU's best (sewgen/engine/build.py: AVX-512 with 8
    lanes, else AVX2 with 4); where that is AVX-512, the same mechanism built for AVX2 (SEWGEN_SIMD=avx2, its own
    cache entry) runs four lanes and agrees with the scalar loop too, failing positions included; a bad
    SEWGEN_SIMD is a clear error."""
    if "-DSG_SIMD_LEVEL=512" not in compile_flags():
        pytest.skip("this build's SIMD level is AVX2 (or none): the tests above ran it")
    monkeypatch.setenv("SEWGEN_SIMD", "avx2")
    assert "-DSG_SIMD_LEVEL=256" in compile_flags()
    mech = sewgen.load(ROOT / "examples" / "my_mechanism.py")
    assert mech.simd_width == 4
    a, b, sens = _both(mech, PHI, nan_at=(7,))
    _agree(a, b, sens, mech.name + " avx2")
    a, b, sens = _both(mech, PHI, params={"crank": mech.defaults()["crank"] * 2.5}, singular="flag")
    _agree(a, b, sens, mech.name + " avx2 long crank")
    assert (b.status != 0).any() and (b.status == 0).any()
    monkeypatch.setenv("SEWGEN_SIMD", "avx-9000")
    with pytest.raises(ValueError, match="SEWGEN_SIMD='avx-9000'"):
        compile_flags()


def test_a_user_mechanism_in_simd():
    mech = sewgen.load(ROOT / "examples" / "my_mechanism.py")
    _needs_simd(mech)
    a, b, sens = _both(mech, PHI, nan_at=(7,))
    _agree(a, b, sens, mech.name)
    a, b, sens = _both(mech, PHI, params={"crank": mech.defaults()["crank"] * 2.5}, singular="flag")
    _agree(a, b, sens, mech.name + " long crank")
    assert (b.status != 0).any() and (b.status == 0).any()  # fails at some angles only


def test_bad_loop_names():
    feed = sewgen.mechanism("feed")  # Newton: its SIMD finish, tests/test_simd_newton.py
    with pytest.raises(ParameterError, match="loop"):
        feed.prepare(PHI[:4]).use_loop("vector")

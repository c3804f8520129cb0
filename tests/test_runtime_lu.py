"""The runtime's pivoted LU (csrc/sg_runtime.h) against numpy.linalg.solve, including matrices that need
row interchanges after the first column (the case a swap-as-you-go forward substitution gets wrong)."""
import numpy as np
import pytest

import sewgen

pytestmark = [pytest.mark.c, pytest.mark.derive]


@pytest.fixture(scope="module")
def lib():
    m = sewgen.mechanism("needle_bar")
    return m.ffi, m.lib


def _solve(ffi, lib, a, b):
    n = a.shape[0]
    lu, piv, x = np.ascontiguousarray(a, dtype=float).copy(), np.zeros(n, dtype=np.intc), b.astype(float).copy()
    sign = ffi.new("double *")
    st = lib.sg_lu_factor(n, ffi.cast("double *", ffi.from_buffer(lu)), ffi.cast("int *", ffi.from_buffer(piv)), sign)
    if st == 0:
        lib.sg_lu_solve(n, ffi.cast("double *", ffi.from_buffer(lu)), ffi.cast("int *", ffi.from_buffer(piv)),
                        ffi.cast("double *", ffi.from_buffer(x)))
    return st, x, sign[0]


@pytest.mark.parametrize("n", [2, 3, 4, 7, 12])
def test_lu_matches_numpy(lib, n):
    ffi, clib = lib
    rng = np.random.default_rng(n)
    for _ in range(100):
        a, b = rng.normal(size=(n, n)), rng.normal(size=n)
        st, x, sign = _solve(ffi, clib, a, b)
        assert st == 0
        np.testing.assert_allclose(x, np.linalg.solve(a, b), rtol=1e-9, atol=1e-9)
        assert sign == np.sign(np.linalg.det(a))


def test_lu_late_pivot():
    """Column 1 needs a swap of rows 1 and 2 after column 0 was eliminated with a swap of rows 0 and 2."""
    m = sewgen.mechanism("needle_bar")
    a = np.array([[1.0, 2.0, 3.0], [2.0, 4.0001, 1.0], [4.0, 1.0, 2.0]])
    b = np.array([1.0, -2.0, 0.5])
    st, x, _ = _solve(m.ffi, m.lib, a, b)
    assert st == 0
    np.testing.assert_allclose(a @ x, b, atol=1e-12)


def test_lu_singular_is_reported():
    m = sewgen.mechanism("needle_bar")
    a = np.array([[1.0, 2.0], [2.0, 4.0]])
    st, _, _ = _solve(m.ffi, m.lib, a, np.ones(2))
    assert st == 2  # SG_SINGULAR
    st, _, _ = _solve(m.ffi, m.lib, np.array([[np.nan, 0.0], [0.0, 1.0]]), np.ones(2))
    assert st == 2


def _factor_eq(ffi, lib, a, rs, b):
    """sg_factor_eq + sg_solve_eq on copies: (status, x, cond)."""
    n = a.shape[0]
    lu, piv, x = np.ascontiguousarray(a, dtype=float).copy(), np.zeros(n, dtype=np.intc), b.astype(float).copy()
    rs, cs, cond = np.ascontiguousarray(rs, dtype=float), np.zeros(2 * n), ffi.new("double *")  # cs: 2 n
    ptr = lambda arr, t="double *": ffi.cast(t, ffi.from_buffer(arr))  # noqa: E731
    st = lib.sg_factor_eq(n, ptr(lu), ptr(piv, "int *"), ptr(rs), ptr(cs), cond)
    if st == 0:
        lib.sg_solve_eq(n, ptr(lu), ptr(piv, "int *"), ptr(rs), ptr(cs), ptr(x))
    return st, x, cond[0]


def _equilibrated_cond(a, rs):
    """The inf-norm condition number of R A C, C scaling each column of R A to largest |entry| 1 (numpy)."""
    e = np.diag(rs) @ a
    e = e / np.abs(e).max(axis=0)
    return np.linalg.cond(e, np.inf)


@pytest.mark.parametrize("n", [2, 3, 4, 7])
def test_rates_factor_matches_numpy(lib, n):
    """The motion kernels' equilibrated factor: the solve is numpy's; the condition number is exact for n = 2
    (the closed-form inverse) and an upper bound for the general LU, never far above it."""
    ffi, clib = lib
    rng = np.random.default_rng(100 + n)
    for _ in range(200):
        a = rng.normal(size=(n, n)) * np.exp(rng.uniform(-3, 3, size=n))  # columns of unlike scales (rad, m)
        rs, b = np.exp(rng.uniform(-2, 2, size=n)), rng.normal(size=n)
        st, x, cond = _factor_eq(ffi, clib, a, rs, b)
        assert st == 0
        exact = _equilibrated_cond(a, rs)
        ref = np.linalg.solve(a, b)  # both backward stable: they agree normwise (a small component may not)
        assert np.abs(x - ref).max() <= 1e-13 * exact * np.abs(ref).max()
        if n == 2:
            assert cond == pytest.approx(exact, rel=1e-13)
        else:
            assert exact * (1 - 1e-12) <= cond <= 2.0 ** n * exact


@pytest.mark.parametrize("delta, status", [(2e-11, 0), (5e-12, 2), (0.0, 2)])
def test_rates_factor_singular_threshold(lib, delta, status):
    """The closed-form 2 x 2 and the general LU (the same block bordered to 3 x 3) draw the singular line at the
    same place: the equilibrated matrix's second pivot, |det E| = delta / (1 + delta), against 1e-11."""
    ffi, clib = lib
    a2 = np.array([[1.0, 1.0], [1.0, 1.0 + delta]])
    a3 = np.eye(3)
    a3[:2, :2] = a2
    for a in (a2, a3):
        st, _, _ = _factor_eq(ffi, clib, a, np.full(len(a), 3.0), np.ones(len(a)))
        assert st == status


def test_rates_factor_refuses_nan_and_unread_coordinate(lib):
    ffi, clib = lib
    for a in (np.array([[np.nan, 0.0], [0.0, 1.0]]), np.array([[1.0, 0.0], [2.0, 0.0]]),
              np.array([[np.inf, 1.0], [0.0, 1.0]])):
        st, _, _ = _factor_eq(ffi, clib, a, np.ones(2), np.ones(2))
        assert st == 2


@pytest.mark.parametrize("name", ["hook_drive", "overlock_loopers", "take_up"])
def test_a_mechanisms_own_newton_lu_equals_the_runtimes_to_the_bit(name):
    """Newton factors dΦ/dq with the mechanism's kernels 'lu_factor' and 'lu_solve' (nq a literal, the loops
    unrolled whole): the same pivots, factor, solution and singular verdicts as the runtime's sg_lu_factor /
    sg_lu_solve for any n, bit for bit — on random matrices, on ones with zeros below the diagonal, and on
    singular and nearly singular ones. (The feed's factors Φ_q by its blocks: the test below.)"""
    m = sewgen.mechanism(name)
    ffi, lib = m.ffi, m.lib
    own_f, own_s = getattr(lib, f"sg_{name}_lu_factor"), getattr(lib, f"sg_{name}_lu_solve")
    n = len(m.coord_names)
    rng = np.random.default_rng(n)
    cases = [rng.normal(size=(n, n)) for _ in range(40)]
    cases += [np.tril(rng.normal(size=(n, n))) + np.triu(rng.normal(size=(n, n)) * (rng.random((n, n)) < .3), 1)
              for _ in range(20)]
    rank_short = rng.normal(size=(n, n))
    rank_short[-1] = rank_short[0] * 2.0
    near = rng.normal(size=(n, n))
    near[-1] = near[0] * (1 + 1e-13)
    cases += [rank_short, near, np.zeros((n, n))]
    ptr = lambda t, a: ffi.cast(t, ffi.from_buffer(a))  # noqa: E731
    verdicts = set()
    for a in cases:
        b = rng.normal(size=n)
        lu1, piv1, x1 = a.copy(), np.zeros(n, dtype=np.intc), b.copy()
        lu2, piv2, x2 = a.copy(), np.zeros(n, dtype=np.intc), b.copy()
        st1 = lib.sg_lu_factor(n, ptr("double *", lu1), ptr("int *", piv1), ffi.NULL)
        st2 = own_f(ptr("double *", lu2), ptr("int *", piv2))
        assert st1 == st2
        verdicts.add(st1)
        if st1 == 0:
            assert np.array_equal(lu1, lu2) and np.array_equal(piv1, piv2)
            lib.sg_lu_solve(n, ptr("double *", lu1), ptr("int *", piv1), ptr("double *", x1))
            own_s(ptr("double *", lu2), ptr("int *", piv2), ptr("double *", x2))
            assert np.array_equal(x1, x2)
            np.testing.assert_allclose(a @ x1, b, atol=1e-8 * (1 + np.abs(a).sum(axis=1).max() * np.abs(x1).max()))
    assert verdicts == {0, 2}  # solved and singular cases both met


def test_the_feeds_newton_lu_by_blocks_solves_its_structure():
    """The feed's Newton factor works on Φ_q's diagonal blocks (sewgen/derive/blockfactor.py): on random matrices
    with Φ_q's structure (its structural zeros, from the residual kernel at a solved position) the solution is
    numpy's dense one (normwise); a block made singular, or a coupling-free block of zeros, is singular; a
    block pivot small against its column in all of Φ_q is singular, as in the dense factor."""
    m = sewgen.mechanism("feed")
    ffi, lib = m.ffi, m.lib
    n = len(m.coord_names)
    mo = m.solve(np.radians([10.0, 100.0, 250.0]))
    pattern = np.zeros((n, n), dtype=bool)
    for q, ph in zip(mo.q, np.radians([10.0, 100.0, 250.0])):
        pattern |= m.residual(q, ph)[1] != 0
    ptr = lambda t, a: ffi.cast(t, ffi.from_buffer(a))  # noqa: E731
    rng = np.random.default_rng(7)

    def factor_solve(a, b):
        lu, piv, x = a.copy(), np.zeros(n, dtype=np.intc), b.copy()
        st = lib.sg_feed_lu_factor(ptr("double *", lu), ptr("int *", piv))
        if st == 0:
            lib.sg_feed_lu_solve(ptr("double *", lu), ptr("int *", piv), ptr("double *", x))
        return st, x

    for _ in range(50):
        a = np.where(pattern, rng.normal(size=(n, n)) * np.exp(rng.uniform(-3, 3, size=n)), 0.0)
        b = rng.normal(size=n)
        st, x = factor_solve(a, b)
        assert st == 0
        ref = np.linalg.solve(a, b)
        assert np.abs(x - ref).max() <= 1e-12 * np.linalg.cond(a, np.inf) * np.abs(ref).max()
    a = np.where(pattern, rng.normal(size=(n, n)), 0.0)
    blk = m.manifest["blocks"][0]  # the cam and the stitch block's guide (3 x 3): rank 2
    r0, r1 = blk["rows"][0], blk["rows"][1]
    a[r1, blk["coords"]] = 2.0 * a[r0, blk["coords"]]
    assert factor_solve(a, rng.normal(size=n))[0] == 2
    singles = [b for b in m.manifest["blocks"] if len(b["rows"]) == 1]
    (r,), (c,) = singles[-1]["rows"], singles[-1]["coords"]
    a = np.where(pattern, rng.normal(size=(n, n)), 0.0)
    a[r, c] = 0.0  # a 1 x 1 block of zero
    assert factor_solve(a, rng.normal(size=n))[0] == 2
    (r,), (c,) = next((b["rows"], b["coords"]) for b in singles if pattern[:, b["coords"][0]].sum() > 1)
    a = np.where(pattern, rng.normal(size=(n, n)), 0.0)
    a[r, c] = 1e-13 * np.abs(a[:, c]).max()  # small against a later loop's entry in its column
    assert factor_solve(a, rng.normal(size=n))[0] == 2
    a[r, c] = 1e-9 * np.abs(a[:, c]).max()  # above the tolerance: solved
    assert factor_solve(a, rng.normal(size=n))[0] == 0

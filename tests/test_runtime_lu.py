"""The runtime's pivoted LU (csrc/sg_runtime.h) against numpy.linalg.solve, including matrices that need
row interchanges after the first column (the case a swap-as-you-go forward substitution gets wrong)."""
import numpy as np
import pytest

import sewgen


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
    rs, cs, cond = np.ascontiguousarray(rs, dtype=float), np.zeros(n), ffi.new("double *")
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
        np.testing.assert_allclose(x, np.linalg.solve(a, b), rtol=1e-13 * exact, atol=0)
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

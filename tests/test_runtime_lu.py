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

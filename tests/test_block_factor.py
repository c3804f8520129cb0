"""The rates of a mechanism Newton solves, factored by Φ_q's diagonal blocks (sewgen/derive/blockfactor.py).

The JB1-3 feed's Φ_q (7 × 7: its loops' blocks 3, 2, 1, 1) is factored block by block in its motion and rates
kernels. Checked here against independent computations: q' against numpy's dense solve of Φ_q q' = -Φ_x x'
(Φ_q from the residual kernel, Φ_x from central differences of the residual in the shaft angle), q'' against
central differences of q' along the shaft, and the kernel's condition estimate against numpy's exact
condition number of the same scaled matrix (it must bound it from above, and not by much).
"""
from __future__ import annotations

import numpy as np
import pytest

import sewgen
from sewgen import abi
from sewgen.derive.blockfactor import BlockFactor
from sewgen.engine.mechanism import _cos_sin_pairs

pytestmark = [pytest.mark.derive, pytest.mark.c]

FEED_CASES = [{}, {"regulator": "-30 deg"}, {"regulator": "5 deg"}]


def _rates_by_kernel(m, q, phi, omega, held):
    """The motion kernel's q', q'' and condition estimate at one solved position (held inputs by name)."""
    nq = len(q)
    x = np.concatenate([[phi], m.held_vector(held)])
    qd, qdd, cond = np.zeros(nq), np.zeros(nq), m.ffi.new("double[]", abi.LIMIT["SG_NCOND"])
    obs = np.zeros(m.description.sizes["nobs"])
    xd, xdd = np.zeros(len(x)), np.zeros(len(x))
    xd[0] = omega
    d = m._ptr
    st = getattr(m.lib, f"sg_{m.name}_motion")(
        d("double *", q), d("double *", _cos_sin_pairs(q)), d("double *", x), d("double *", _cos_sin_pairs(x)),
        d("double *", xd), d("double *", xdd), d("double *", m.constants()), d("double *", qd),
        d("double *", qdd), d("double *", obs), cond)
    return st, qd, qdd, cond[0]


def _scales(m, q, phi, held):
    """Each closure row's loop size (kernel 'scales'): the rows' scaling of the rates' factor."""
    x = np.concatenate([[phi], m.held_vector(held)])
    out = np.zeros(len(q))
    d = m._ptr
    getattr(m.lib, f"sg_{m.name}_scales")(d("double *", q), d("double *", _cos_sin_pairs(q)), d("double *", x),
                                          d("double *", _cos_sin_pairs(x)), d("double *", m.constants()),
                                          d("double *", out))
    return out


@pytest.mark.parametrize("held", FEED_CASES)
def test_feed_rates_by_blocks_match_a_dense_solve(held):
    m = sewgen.mechanism("feed")
    omega = 2 * np.pi * 1500 / 60
    phi = np.radians(np.arange(3.0, 360.0, 17.0))
    h = 1e-5
    stencil = np.sort(np.concatenate([phi - h, phi, phi + h]))
    mo = m.solve(stencil, speed=omega, held=held)
    ratios = []
    for k, ph in enumerate(phi):
        i = 3 * k + 1
        q = mo.q[i]
        st, qd, qdd, cond = _rates_by_kernel(m, q, ph, omega, held)
        assert st == 0
        # the sweep's rates (its cos, sin of q by the addition formulas, so not to the bit)
        np.testing.assert_allclose(qdd, mo.qdd[i], rtol=0, atol=1e-12 * np.abs(qdd).max())
        _, jac = m.residual(q, ph, held=held)
        r_plus, _ = m.residual(q, ph + 1e-6, held=held)
        r_minus, _ = m.residual(q, ph - 1e-6, held=held)
        phi_x = (r_plus - r_minus) / 2e-6
        ref = np.linalg.solve(jac, -phi_x * omega)
        assert np.abs(qd - ref).max() <= 1e-7 * np.abs(ref).max(), (ph, qd, ref)
        fd = (mo.qd[i + 1] - mo.qd[i - 1]) / (2 * h) * omega  # zero shaft acceleration: q'' = dq'/dphi omega
        assert np.abs(qdd - fd).max() <= 1e-6 * np.abs(fd).max(), (ph, qdd, fd)
        e = np.diag(1.0 / _scales(m, q, ph, held)) @ jac
        e = e / np.abs(e).max(axis=0)
        exact = np.linalg.cond(e, np.inf)
        ratios.append(cond / exact)
    assert min(ratios) >= 1 - 1e-12  # an upper bound ...
    assert max(ratios) <= 4.0, ratios  # ... and a tight one (measured: 1.0006 to 1.21)


class _Block:
    def __init__(self, rows, cols):
        self.rows, self.cols = rows, cols


def test_block_factor_applies_only_to_a_block_lower_triangular_structure():
    one = 1
    dense = [one] * 9
    blocks = [_Block([0], [0]), _Block([1, 2], [1, 2])]
    lower = [one, 0, 0, one, one, one, 0, one, one]  # row 0 reads q0 only; rows 1, 2 read q0..q2
    assert BlockFactor.of(3, lower, blocks) is not None
    assert BlockFactor.of(3, dense, blocks) is None  # row 0 reads a later block's coordinates
    assert BlockFactor.of(3, lower, [_Block([0, 1, 2], [0, 1, 2])]) is None  # one block: the dense factor

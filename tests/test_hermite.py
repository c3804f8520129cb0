"""sewgen.hermite, the one cubic Hermite implementation: a cubic is its own Hermite interpolant, so the crossings
and extremes of a sampled cubic (values and exact slopes) must be the cubic's own, known in closed form here."""
import math

import numpy as np
import pytest

from sewgen.hermite import Series, crossings, hermite, maximum, piece_root


def test_a_piece_of_a_cubic_is_the_cubic_and_its_root_is_exact():
    # p(t) = (t − r)(t² + 1) on [0, h]: one real root r
    h = 0.1
    r = np.array([1e-9, 0.0123456789, 0.05, 0.0999999])
    p = lambda t: (t - r) * (t * t + 1.0)  # noqa: E731
    dp = lambda t: (t * t + 1.0) + 2.0 * t * (t - r)  # noqa: E731
    t = np.linspace(0.0, h, 7)[:, None]
    assert np.allclose(hermite(p(0.0), p(h), dp(0.0), dp(h), h, t), p(t), rtol=0, atol=1e-15)
    assert piece_root(p(0.0), p(h), dp(0.0), dp(h), h) == pytest.approx(r, rel=0, abs=2e-17)
    # falling through zero as well
    assert piece_root(-p(0.0), -p(h), -dp(0.0), -dp(h), h) == pytest.approx(r, rel=0, abs=2e-17)


def test_crossings_and_maximum_of_a_sampled_periodic_quantity():
    # y = sin φ + 0.3 sin 2φ sampled every 5° with its exact slope: crossings by brute force on a 1e-7 grid
    phi = np.radians(np.arange(0.0, 360.0, 5.0))
    h = phi[1] - phi[0]
    y = np.sin(phi) + 0.3 * np.sin(2 * phi) - 0.2
    dy = np.cos(phi) + 0.6 * np.cos(2 * phi)
    rows, cols, t, sign = crossings(y[None], dy[None], h)
    found = np.sort((phi[cols] + t) % (2 * math.pi))
    # the exact crossings: refine with Newton on the true function
    exact = []
    for a in found:
        for _ in range(50):
            a -= (math.sin(a) + 0.3 * math.sin(2 * a) - 0.2) / (math.cos(a) + 0.6 * math.cos(2 * a))
        exact.append(a % (2 * math.pi))
    # a 5° step: Hermite is O(h⁴) accurate
    assert found == pytest.approx(sorted(exact), abs=2e-5)
    assert list(sign) == [1, -1] and list(rows) == [0, 0]
    top, i, tt = maximum(y[None], dy[None], h)
    fine = np.linspace(0, 2 * math.pi, 2_000_001)
    assert top[0] == pytest.approx((np.sin(fine) + 0.3 * np.sin(2 * fine) - 0.2).max(), abs=2e-6)
    # the Series view of the same samples agrees with the array functions
    s = Series(phi, y, dy)
    assert sorted(a for a, _ in s.crossings()) == pytest.approx(list(found), abs=1e-15)
    assert s.at(found[0]) == pytest.approx(0.0, abs=1e-15)


def test_the_maximum_of_a_cubic_between_samples_is_its_vertex():
    # y(t) = −(t − m)² (t + 1) near t = m: a maximum at m, between two samples
    h = 0.2
    m = 0.137
    f = lambda t: -(t - m) ** 2 * (t + 1.0)  # noqa: E731
    df = lambda t: -2 * (t - m) * (t + 1.0) - (t - m) ** 2  # noqa: E731
    ts = np.array([-0.2, 0.0, 0.2, 0.4])
    top, i, t = maximum(f(ts)[None], df(ts)[None], h)
    assert ts[i[0]] + t[0] == pytest.approx(m, abs=1e-15)
    assert top[0] == pytest.approx(0.0, abs=1e-17)

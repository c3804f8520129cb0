"""The 51-A overlock's needle mechanism (seed 003 fig. 1–2) against the seed's own formulas, written here.

Eq. (1): the rock shaft's angle φ₃ of the spatial four-bar, cos φ₃ = (f r_x − δ₁ r_y √(r_x² + r_y² − f²)) /
(r_x² + r_y²), with r = (B − D) in the lever's plane and f = (|B − D|² + l₃² − L²)/(2 l₃) for the arm DC.
Eq. (2): the needle stroke as a second-order expansion in the link's obliquity,

    S_L = √((l₄ + l₅)² − a²) + l₄ sin φ₃ − l₅ − a²/(2 l₅) + a l₄ cos φ₃ / l₅ − l₄²/(2 l₅) cos² φ₃,

which is √(l₅² − (a − l₄ cos φ₃)²) ≈ l₅ − (a − l₄ cos φ₃)²/(2 l₅) plus constants. The seed prints the last term
with cos φ₃; the expansion, and the test below, need cos² φ₃ (with cos φ₃ the stroke is off by about 1 mm).
sewgen's needle travel is exact; the expansion's error is bounded by its next term, (a − l₄ cos φ₃)⁴/(8 l₅³).
"""
from __future__ import annotations

import numpy as np
import pytest

import sewgen

pytestmark = [pytest.mark.c]

MM = 1e-3
R, H_A, ROD, L3, L4, L5, A = 7.4 * MM, 60 * MM, 60 * MM, 16 * MM, 28 * MM, 40 * MM, 28 * MM


@pytest.fixture(scope="module")
def needle():
    return sewgen.mechanism("overlock_needle")


def eccentric_pin(phi):
    """B: the main shaft along x through (l₃, −h_A, 0); angle from +z towards −y, phase 180°."""
    t = phi + np.pi
    return np.column_stack([np.full_like(phi, L3), -H_A - R * np.sin(t), R * np.cos(t)])


def rock_shaft_angle(phi, delta1=1):
    b = eccentric_pin(phi)
    rx, ry = b[:, 0], b[:, 1]
    f = (np.sum(b**2, axis=1) + L3**2 - ROD**2) / (2 * L3)
    root = np.sqrt(rx**2 + ry**2 - f**2)
    return np.arctan2(f * ry + delta1 * rx * root, f * rx - delta1 * ry * root)


def test_eq_1_rock_shaft_angle(needle):
    phi = np.radians(np.arange(0, 360, 2.5))
    motion = needle.solve(phi)
    ref = rock_shaft_angle(phi)
    got = motion.body("lever").angle
    np.testing.assert_allclose(np.cos(got), np.cos(ref), atol=1e-13)
    np.testing.assert_allclose(np.sin(got), np.sin(ref), atol=1e-13)
    assert np.degrees(got.max() - got.min()) == pytest.approx(2 * np.degrees(np.arcsin(R / L3)), abs=2.0)


def test_eq_2_needle_stroke_and_its_expansion_error(needle):
    phi = np.radians(np.arange(0, 360, 2.5))
    motion = needle.solve(phi, speed=3500 * np.pi / 30)
    p3 = motion.body("lever").angle
    travel = motion.coord("needle_bar.travel").value
    exact = L4 * np.sin(p3) + np.sqrt(L5**2 - (A - L4 * np.cos(p3)) ** 2)
    np.testing.assert_allclose(travel, exact, atol=1e-15)
    s_l = (np.sqrt((L4 + L5) ** 2 - A**2) + L4 * np.sin(p3) - L5 - A**2 / (2 * L5) + A * L4 * np.cos(p3) / L5
           - L4**2 / (2 * L5) * np.cos(p3) ** 2)
    offset = np.sqrt((L4 + L5) ** 2 - A**2) - 2 * L5  # S_L − travel, up to the expansion's error
    error = (s_l - offset) - travel
    bound = (A - L4 * np.cos(p3)) ** 4 / (8 * L5**3)
    assert np.all(np.abs(error) <= 1.05 * bound + 1e-15)
    assert np.abs(error).max() < 1e-6  # under a micrometre for these dimensions
    misprint = error + L4**2 / (2 * L5) * (np.cos(p3) ** 2 - np.cos(p3))  # the last term with cos φ₃ as printed
    assert np.abs(misprint).max() > 0.5 * MM
    stroke = motion.point("needle_eye").y.max() - motion.point("needle_eye").y.min()
    assert stroke == pytest.approx(25.9 * MM, abs=0.1 * MM)
    assert np.degrees(phi[np.argmax(motion.point("needle_eye").y)]) == pytest.approx(90.0)


def test_velocities_and_accelerations_against_finite_differences(needle):
    w = 3500 * np.pi / 30
    phi = np.radians(np.arange(0, 360, 5.0))
    h = 1e-5
    y = lambda p: needle.solve(p).point("needle_point").y  # noqa: E731
    m = needle.solve(phi, speed=w).point("needle_point")
    np.testing.assert_allclose(m.vy, w * (y(phi + h) - y(phi - h)) / (2 * h), atol=1e-6 * w * 0.02)
    np.testing.assert_allclose(m.ay, w**2 * (y(phi + h) - 2 * y(phi) + y(phi - h)) / h**2, atol=2e-3 * w**2 * 0.02)

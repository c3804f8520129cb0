"""The 51-A overlock's loopers (seed 003 fig. 3) against the seed's eqs. 1 and 4–6, written here.

Seed 003's axes D_X D_Y are the mirror image of sewgen's (its X against our x, Y up); it counts φ₃ as we do and
φ₅ in its mirrored axes (φ₅ = 180° − ours). With those readings eqs. 4–6 hold with γ = γ_ours + 90°,
β = β_ours − 180° and η = η_ours − β:

    eq. 4:  X_N₂ = −l₇ sin(φ₃ + γ),  Y_N₂ = −l₇ cos(φ₃ + γ);
    eq. 6:  X_N₁ = (L + l₆ cos(φ₅ − η)) cos β + l₆ sin(φ₅ − η) sin β,
            Y_N₁ = −(L + l₆ cos(φ₅ − η)) sin β + l₆ sin(φ₅ − η) cos β.

φ₃ comes from eq. 1 (the spatial four-bar ABCD), φ₅ from eq. 1 with α = 0 for the planar four-bar DEFG (the
seed's instruction), both written here, not read from sewgen.
"""
from __future__ import annotations

import numpy as np
import pytest

import sewgen

pytestmark = [pytest.mark.c]

MM = 1e-3
R, H_A, ROD, L3 = 6 * MM, 45 * MM, 45 * MM, 16 * MM
L7, GAMMA = 60 * MM, np.radians(100)
DE, DE_ANGLE, EF, GF = 20 * MM, np.radians(180), 40 * MM, 22 * MM
L, BETA, L6, ETA = 45 * MM, np.radians(140), 55 * MM, np.radians(-60)


def phi3(phi):
    """Eq. 1: the eccentric's pin B (main shaft along x through (l₃, −h_A, 0), angle from +z towards −y)."""
    b = np.column_stack([np.full_like(phi, L3), -H_A - R * np.sin(phi), R * np.cos(phi)])
    rx, ry = b[:, 0], b[:, 1]
    f = (np.sum(b**2, axis=1) + L3**2 - ROD**2) / (2 * L3)
    root = np.sqrt(rx**2 + ry**2 - f**2)
    return np.arctan2(f * ry + rx * root, f * rx - ry * root)


def phi5(p3):
    """Eq. 1 with α = 0 for DEFG: the lever GF's angle (ours) with F at |EF| from E and |GF| from G."""
    g = L * np.array([np.cos(BETA), np.sin(BETA)])
    e = DE * np.column_stack([np.cos(p3 + DE_ANGLE), np.sin(p3 + DE_ANGLE)])
    rx, ry = e[:, 0] - g[0], e[:, 1] - g[1]
    f = (rx**2 + ry**2 + GF**2 - EF**2) / (2 * GF)
    root = np.sqrt(rx**2 + ry**2 - f**2)
    # δ = −1: F right of the line G → E (the declaration's branch +1 at F reads from E's side)
    return np.arctan2(f * ry - rx * root, f * rx + ry * root)


@pytest.fixture(scope="module")
def loopers():
    return sewgen.mechanism("overlock_loopers")


def test_eq_1_and_the_planar_four_bar(loopers):
    phi = np.radians(np.arange(0, 360, 2.5))
    m = loopers.solve(phi)
    p3, p5 = phi3(phi), phi5(phi3(phi))
    for got, ref in ((m.body("rock_shaft").angle, p3), (m.body("lower_lever").angle, p5)):
        np.testing.assert_allclose(np.cos(got), np.cos(ref), atol=1e-12)
        np.testing.assert_allclose(np.sin(got), np.sin(ref), atol=1e-12)


def test_eqs_4_to_6_looper_tips(loopers):
    phi = np.radians(np.arange(0, 360, 2.5))
    m = loopers.solve(phi)
    p3 = phi3(phi)
    p5_seed = np.pi - phi5(p3)
    gamma, beta = GAMMA + np.pi / 2, BETA - np.pi
    eta = ETA - beta
    upper = np.column_stack([-L7 * np.sin(p3 + gamma), -L7 * np.cos(p3 + gamma)])
    u = p5_seed - eta
    lower = np.column_stack([(L + L6 * np.cos(u)) * np.cos(beta) + L6 * np.sin(u) * np.sin(beta),
                             -(L + L6 * np.cos(u)) * np.sin(beta) + L6 * np.sin(u) * np.cos(beta)])
    mirror = np.array([-1.0, 1.0])
    for name, ref in (("upper_looper_tip", upper), ("lower_looper_tip", lower)):
        p = m.point(name)
        np.testing.assert_allclose(np.column_stack([p.x, p.y]) * mirror, ref, atol=1e-14)


def test_looper_velocities_against_finite_differences(loopers):
    w = 3500 * np.pi / 30
    phi = np.radians(np.arange(0, 360, 5.0))
    h = 1e-5
    for name in ("upper_looper_tip", "lower_looper_tip"):
        pos = lambda p: np.column_stack([loopers.solve(p).point(name).x, loopers.solve(p).point(name).y])  # noqa: E731
        tip = loopers.solve(phi, speed=w).point(name)
        fd = w * (pos(phi + h) - pos(phi - h)) / (2 * h)
        np.testing.assert_allclose(np.column_stack([tip.vx, tip.vy]), fd, atol=1e-6 * np.abs(fd).max())
        fd2 = w**2 * (pos(phi + h) - 2 * pos(phi) + pos(phi - h)) / h**2
        np.testing.assert_allclose(np.column_stack([tip.ax, tip.ay]), fd2, atol=2e-3 * np.abs(fd2).max())

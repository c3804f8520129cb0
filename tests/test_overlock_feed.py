"""The 51-A overlock's feed (seed 003 fig. 5) against the seed's eqs. 3–14, written here.

Positions: eq. 3 (E on the rock shaft's arm, K on the lift eccentric, the base angle φ_b of KE... here of E→K),
eq. 4 (the triangle EFK's angles at E and K by the law of cosines) and eq. 5 (the links' directions from them).
Velocities: eqs. 8–13, the velocity plan v_E + v_FE = v_K + v_FK solved by Cramer's rule for v_FE and v_FK, with
eq. 12's erratum corrected (b₁ = ω₅ l₅ cos β_K − ω₃ l₃ cos β_E: the seed omits l₃, which gives a wrong v_F);
eq. 14, G's velocity from E and F on the rack. φ₃ and ω₃ come from the four-bar ABCD (eq. 1 with α = 0) in the
test, not from sewgen.
"""
from __future__ import annotations

import numpy as np
import pytest

import sewgen

pytestmark = [pytest.mark.c]

MM = 1e-3
R1, L2, D, CD, L3, L4, GF, L5, THETA, L6 = (1.6 * MM, 45 * MM, np.array([45 * MM, 16 * MM]), 18 * MM, 24 * MM,
                                            45 * MM, 10 * MM, 1.2 * MM, 0.0, 40 * MM)
W = 3500 * np.pi / 30
#: The stitch regulator (the adjustable-throw feed eccentric: e₁ − e₂·u(β), e₁ = e₂ = 2.5 mm) set so its throw
#: is R1 along the shaft angle: 2e·sin(β/2) = R1 at the angle β/2 − 90° + phase = 0.
BETA = 2 * np.arcsin(R1 / (2 * 2.5 * MM))
SETTING = dict(held={"stitch_eccentric": BETA}, params={"feed_eccentric.phase": np.pi / 2 - BETA / 2})


def _circle(p, rp, q, rq, sign):
    """Intersection of circle (p, rp) and (q, rq) left (sign +1) or right (−1) of p → q (arrays (n, 2))."""
    d = q - p
    dist = np.hypot(*d.T)
    a = (rp**2 - rq**2 + dist**2) / (2 * dist)
    h = np.sqrt(rp**2 - a**2)
    u = d / dist[:, None]
    return p + a[:, None] * u + sign * h[:, None] * np.column_stack([-u[:, 1], u[:, 0]])


def rock_angle(phi):
    """φ₃ of the arm DE: C at |BC| from B and |DC| from D (right of B → D), DE opposite DC."""
    b = R1 * np.column_stack([np.cos(phi), np.sin(phi)])
    c = _circle(b, L2, np.tile(D, (len(phi), 1)), CD, -1)
    return np.arctan2(D[1] - c[:, 1], D[0] - c[:, 0])  # DE points away from C


def positions(phi):
    p3 = rock_angle(phi)
    e = D + L3 * np.column_stack([np.cos(p3), np.sin(p3)])  # eq. 3
    p5 = phi + THETA
    k = L5 * np.column_stack([np.cos(p5), np.sin(p5)])  # eq. 3
    pb = np.arctan2(k[:, 1] - e[:, 1], k[:, 0] - e[:, 0])  # eq. 3: the base vector E → K
    lb = np.hypot(*(k - e).T)
    p4b = np.arccos((L4**2 + lb**2 - L6**2) / (2 * L4 * lb))  # eq. 4
    p6b = np.arccos((lb**2 + L6**2 - L4**2) / (2 * lb * L6))
    p4 = pb - p4b  # eq. 5, F on the side this machine assembles (the seed's sign reading: F right of E → K)
    f = e + L4 * np.column_stack([np.cos(p4), np.sin(p4)])
    p6 = np.arctan2(f[:, 1] - k[:, 1], f[:, 0] - k[:, 0])
    assert np.allclose(np.cos(p6), np.cos(pb + np.pi + p6b))  # K → F: the angle at K turned the other way
    return p3, p4, p5, p6, e, f


@pytest.fixture(scope="module")
def feed():
    return sewgen.mechanism("overlock_feed")


def test_eqs_3_to_5_positions(feed):
    phi = np.radians(np.arange(0, 360, 2.5))
    m = feed.solve(phi, **SETTING)
    _p3, p4, _p5, _p6, e, f = positions(phi)
    np.testing.assert_allclose(np.column_stack([m.point("rear_pin").x, m.point("rear_pin").y]), e, atol=1e-14)
    np.testing.assert_allclose(np.column_stack([m.point("tooth_f").x, m.point("tooth_f").y]), f, atol=1e-14)
    travel = m.point("tooth_f").x.max() - m.point("tooth_f").x.min()
    lift = m.point("tooth_f").y.max() - m.point("tooth_f").y.min()
    assert travel == pytest.approx(4.3 * MM, abs=0.1 * MM) and lift == pytest.approx(2.4 * MM, abs=0.1 * MM)
    top = np.degrees(phi[np.argmax(m.point("tooth_f").y)])
    fastest = np.degrees(phi[np.argmax(feed.solve(phi, speed=W, **SETTING).point("tooth_f").vx)])
    assert abs(top - 90) < 15 and abs(fastest - 90) < 15  # it feeds at the top, while the needle is up


def cramer(phi, printed_eq12=False):
    """Eqs. 8–13: v_F from the velocity plan, Cramer's rule; ω₃ by central differences of the four-bar."""
    h = 1e-6
    p3, p4, p5, p6, _e, _f = positions(phi)
    w3 = W * (rock_angle(phi + h) - rock_angle(phi - h)) / (2 * h)
    w5 = W
    b_e, b_k, b_fe, b_fk = p3 + np.pi / 2, p5 + np.pi / 2, p4 + np.pi / 2, p6 + np.pi / 2  # eq. 7
    l3 = 1.0 if printed_eq12 else L3
    b1 = w5 * L5 * np.cos(b_k) - w3 * l3 * np.cos(b_e)  # eq. 12 (corrected: ω₃·l₃)
    b2 = w5 * L5 * np.sin(b_k) - w3 * L3 * np.sin(b_e)
    a11, a12, a21, a22 = np.cos(b_fe), -np.cos(b_fk), np.sin(b_fe), -np.sin(b_fk)
    det = a11 * a22 - a12 * a21
    v_fe = (b1 * a22 - b2 * a12) / det
    v_e = w3 * L3
    vx = v_e * np.cos(b_e) + v_fe * np.cos(b_fe)  # eq. 13
    vy = v_e * np.sin(b_e) + v_fe * np.sin(b_fe)
    w4 = v_fe / L4  # eq. 12: ω₄
    return np.column_stack([vx, vy]), w4


def test_eqs_8_to_13_velocity_of_f_by_cramer(feed):
    phi = np.radians(np.arange(0, 360, 5.0))
    m = feed.solve(phi, speed=W, **SETTING)
    v, w4 = cramer(phi)
    got = np.column_stack([m.point("tooth_f").vx, m.point("tooth_f").vy])
    np.testing.assert_allclose(got, v, atol=1e-7 * np.abs(v).max())
    np.testing.assert_allclose(m.body("rack").omega, w4, atol=1e-7 * np.abs(w4).max())
    misprint, _ = cramer(phi, printed_eq12=True)
    assert np.abs(misprint - got).max() > 0.1 * np.abs(got).max()  # eq. 12 as printed is not the rack's speed


def test_eq_14_velocity_of_g(feed):
    phi = np.radians(np.arange(0, 360, 5.0))
    m = feed.solve(phi, speed=W, **SETTING)
    v_f, w4 = cramer(phi)
    _p3, p4, *_ = positions(phi)
    gf = -GF * np.column_stack([np.cos(p4), np.sin(p4)])  # G is GF behind F along the rack, towards E
    v_g = v_f + w4[:, None] * np.column_stack([-gf[:, 1], gf[:, 0]])  # v_G = v_F + v_GF
    got = np.column_stack([m.point("tooth_g").vx, m.point("tooth_g").vy])
    np.testing.assert_allclose(got, v_g, atol=1e-7 * np.abs(v_g).max())

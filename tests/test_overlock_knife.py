"""The 51-A overlock's knife: a crank-rocker from the main shaft rocks the upper knife against the fixed lower
knife. References written here: the lever angle by circle intersection, the edge's stroke and the cutting overlap
(the upper knife's edge below the lower knife's edge at the bottom of its stroke)."""
from __future__ import annotations

import numpy as np
import pytest

import sewgen

pytestmark = [pytest.mark.c]

MM = 1e-3
R, ROD, P, ARM, KNIFE, LOWER = 1.25 * MM, 40 * MM, np.array([-20 * MM, 40 * MM]), 20 * MM, 65 * MM, 36.5 * MM


def edge(phi):
    b = R * np.column_stack([np.cos(phi), np.sin(phi)])
    d = P - b
    dist = np.hypot(*d.T)
    a = (ROD**2 - ARM**2 + dist**2) / (2 * dist)
    h = np.sqrt(ROD**2 - a**2)
    u = d / dist[:, None]
    c = b + a[:, None] * u - h[:, None] * np.column_stack([-u[:, 1], u[:, 0]])  # C right of B → P
    ang = np.arctan2(c[:, 1] - P[1], c[:, 0] - P[0])
    return P + KNIFE * np.column_stack([np.cos(ang), np.sin(ang)])


def test_knife_edge_stroke_and_overlap():
    knife = sewgen.mechanism("overlock_knife")
    phi = np.radians(np.arange(0, 360, 0.5))
    m = knife.solve(phi)
    ref = edge(phi)
    np.testing.assert_allclose(np.column_stack([m.point("knife_edge").x, m.point("knife_edge").y]), ref, atol=1e-14)
    overlap = LOWER - ref[:, 1].min()
    assert overlap == pytest.approx(0.56 * MM, abs=0.02 * MM)
    assert ref[:, 1].max() - ref[:, 1].min() == pytest.approx(8.13 * MM, abs=0.02 * MM)
    assert knife.description.role("lower_knife_edge").name == "lower_edge"

"""Every angle result is continuous over a sweep and starts in (−π, π] (issue 12, item 5).

A drag-link four-bar (the shortest link is the frame: both cranks turn fully) makes the follower's closed-form
angle (an atan2) pass ±180° every turn; over two turns it must come out as one continuous curve that gains 4π,
with the follower pin where that angle puts it (so only whole turns were added)."""
from __future__ import annotations

import numpy as np
import pytest

import sewgen
from sewgen.derive.model import Mechanism


def drag_link():
    m = Mechanism("drag_link", "a double-crank four-bar: frame 10 mm, cranks 30 and 33 mm, coupler 35 mm")
    crank = m.driven("crank", m.ground.at(0, 0), phase="170 deg")
    coupler = m.link("coupler", guess="0 deg")
    follower = m.link("follower", guess="170 deg")
    m.revolute(crank.at("30 mm", 0), coupler.at(0, 0), "B")
    m.revolute(coupler.at("35 mm", 0), follower.at("33 mm", 0), "C")
    m.revolute(m.ground.at("10 mm", 0), follower.at(0, 0), "D")
    m.point("pin_c", follower.at("33 mm", 0))
    return m


@pytest.mark.parametrize("newton", [False, True])
def test_angles_are_continuous_and_start_in_the_principal_range(tmp_path_factory, newton):
    mech = sewgen.load(drag_link, cache_dir=tmp_path_factory.mktemp("angles"))
    phi = np.radians(np.arange(0, 720, 5.0))
    motion = mech.solve(phi, speed=10.0, newton=newton)
    for body in ("crank", "coupler", "follower"):
        angle = motion.body(body).angle
        assert -np.pi < angle[0] <= np.pi, body
        assert np.abs(np.diff(angle)).max() < np.radians(30), body
    follower = motion.body("follower").angle
    assert abs(follower[-1] - follower[0]) > 3.5 * np.pi  # it turned (nearly) twice, one continuous curve
    assert np.degrees(motion.body("crank").angle[0]) == pytest.approx(170.0)
    c = motion.point("pin_c")  # the pin where the unwrapped angle says: only whole turns were added
    np.testing.assert_allclose(c.x, 0.010 + 0.033 * np.cos(follower), atol=1e-15)
    np.testing.assert_allclose(c.y, 0.033 * np.sin(follower), atol=1e-15)
    np.testing.assert_allclose(motion.coord("follower.angle").value, follower, atol=1e-15)

"""Drawing anchors (sewgen.derive.drawing, kernel sg_<m>_anchors) and roles in declarations.

The anchors kernel evaluates, at one solved position, where every joint attachment, guide, cam arc, named point
and centre of mass of a mechanism is; the pictures of any mechanism are drawn from them. Checked here against
invariants that need no reference: the two attachments of every revolute coincide; a slot's or prismatic's pin
lies on its guide line; a cam touches its follower's face (one arc's centre lies its radius from the face line);
named points and centres of mass are the ones the motion kernel reports; guide directions are unit vectors.
"""
from __future__ import annotations

import numpy as np
import pytest

import sewgen
from sewgen.derive import DeclarationError
from sewgen.derive.model import Mechanism as Declaration

pytestmark = [pytest.mark.c, pytest.mark.derive]

PHI = np.radians(np.arange(0.0, 360.0, 15.0))


def anchors_at(m, motion, i):
    """{anchor name: (x, y)} and the arcs' (radius, from, to) at position i of ``motion``."""
    d = m.description
    q = np.ascontiguousarray(motion.q[i])
    x = np.concatenate([[motion.phi[i]], m.held_vector()]) if d.held_inputs else np.array([motion.phi[i]])
    out = m.anchors(q, x)
    pos = {a.name: out[2 * a.index:2 * a.index + 2] for a in d.anchors}
    base = 2 * len(d.anchors)
    arcs = [(a, out[base + 3 * a.out:base + 3 * a.out + 3]) for a in d.arcs]
    return pos, arcs


@pytest.mark.parametrize("name", ["needle_bar", "take_up", "hook_drive", "feed"])
def test_anchors_are_consistent_with_the_solved_motion(name):
    m = sewgen.mechanism(name)
    d = m.description
    motion = m.solve(PHI)
    kinds = {a.kind for a in d.anchors}
    assert {"joint", "point", "com"} <= kinds
    for i in range(len(PHI)):
        pos, arcs = anchors_at(m, motion, i)
        for j in d.joints:
            pins = [pos[a.name] for a in d.anchors if a.joint == j.name and a.kind == "joint"]
            if j.kind == "revolute":
                assert len(pins) == 2 and np.hypot(*(pins[0] - pins[1])) < 1e-12, (j.name, i)
            elif j.kind in ("prismatic", "slot"):
                origin = next(pos[a.name] for a in d.anchors if a.joint == j.name and a.kind == "guide")
                u = next(pos[a.name] for a in d.anchors if a.joint == j.name and a.kind == "guide_direction")
                assert abs(np.hypot(*u) - 1.0) < 1e-14
                off = pins[0] - origin
                assert abs(off[0] * u[1] - off[1] * u[0]) < 1e-12, (j.name, i)  # on the line
            elif j.kind == "cam":
                origin = next(pos[a.name] for a in d.anchors if a.joint == j.name and a.kind == "guide")
                u = next(pos[a.name] for a in d.anchors if a.joint == j.name and a.kind == "guide_direction")
                gaps = []
                for arc, (r, _f, _t) in arcs:
                    if arc.joint == j.name:
                        c = pos[d.anchors[arc.center].name] - origin
                        gaps.append(abs(abs(c[0] * u[1] - c[1] * u[0]) - r))
                assert min(gaps) < 1e-12, (j.name, i)  # some arc touches the face
        for p in d.points:
            pm = motion.point(p.name)
            assert np.hypot(pos[p.name][0] - pm.x[i], pos[p.name][1] - pm.y[i]) < 1e-13
        for b in d.bodies:
            com = motion.body(b.name).com
            assert np.hypot(pos[f"{b.name}.com"][0] - com.x[i], pos[f"{b.name}.com"][1] - com.y[i]) < 1e-13
        for a in d.anchors:  # ground anchors stay put
            if a.body == "ground" and a.kind == "joint":
                first, _ = anchors_at(m, motion, 0)
                assert np.allclose(pos[a.name], first[a.name], atol=1e-15, rtol=0)


def test_the_feed_cam_arcs_are_the_constant_breadth_cam():
    """Six arcs (derive.model.constant_breadth_arcs: a small and a large arc about each vertex of the
    triangle); each pair concentric with radii summing to the breadth, the same for the three vertices."""
    m = sewgen.mechanism("feed")
    motion = m.solve(PHI)
    pos, arcs = anchors_at(m, motion, 3)
    assert len(arcs) == 6
    radii = np.array([r for _, (r, _f, _t) in arcs])
    centres = [pos[m.description.anchors[a.center].name] for a, _ in arcs]
    breadths = {round(radii[k] + radii[k + 1], 12) for k in (0, 2, 4)}
    assert len(breadths) == 1
    for k in (0, 2, 4):
        assert np.hypot(*(centres[k] - centres[k + 1])) < 1e-13
    sides = [np.hypot(*(centres[k] - centres[(k + 2) % 6])) for k in (0, 2, 4)]  # the triangle is equilateral
    assert np.ptp(sides) < 1e-13 and abs(sides[0] - (radii[1] - radii[0])) < 1e-13


def test_catalog_roles():
    roles = {name: sewgen.mechanism(name).description.roles for name in sewgen.catalog()}
    assert roles["needle_bar"]["needle_eye"] == ("point", "needle_eye")
    assert roles["take_up"]["thread_eye"] == ("point", "thread_eye")
    assert roles["hook_drive"]["hook_shaft"] == ("body", "lower_shaft")
    assert roles["feed"]["feed_dog"] == ("point", "feed_dog")
    assert roles["feed"]["throat_plate"] == ("param", "plate_y")
    assert roles["feed"]["stitch_regulator"] == ("input", "regulator")
    d = sewgen.mechanism("feed").description
    assert d.role("throat_plate").role == "throat_plate" and d.point("feed_dog").role == "feed_dog"


def test_a_role_names_one_part():
    m = Declaration("two_eyes", "a role given twice")
    crank = m.driven("crank", pivot=m.ground.at(0, 0))
    m.point("a", crank.at("10 mm", 0), role="needle_eye")
    with pytest.raises(DeclarationError, match="needle_eye.*given to both point 'a' and point 'b'"):
        m.point("b", crank.at("5 mm", 0), role="needle_eye")
    with pytest.raises(DeclarationError, match="lower_snake_case"):
        m.length("r", "3 mm", "radius", role="Needle Eye")

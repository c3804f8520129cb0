"""The 51-A overlock machine (seed 003), whole: sewgen/models/51-a.toml.

Power balance of the whole machine, every group's velocities and accelerations against finite differences, the
stitch-formation rules on the built-in model and a phase moved by 30° failing the right rule, the stitch regulator
(the adjustable-throw feed eccentric) against a stitch length computed here, and the planar equivalents of the
spatial four-bars against the exact ones (seed 003: within ±2 %).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import sewgen
from sewgen.errors import ParameterError
from sewgen.machine.feed import regulator_angle, stitch_length
from sewgen.machine.assembly import load_machine
from sewgen.machine.timing import timing

pytestmark = [pytest.mark.c]

MM = 1e-3


@pytest.fixture(scope="module")
def machine():
    return load_machine("51-a")


@pytest.fixture(scope="module")
def analysis(machine):
    return machine.analyze()


def test_power_balance(analysis):
    assert analysis.power_balance_residual <= 1e-9
    assert np.abs(analysis.drive_power).max() > 10.0  # a real machine's power, not a trivial zero


@pytest.mark.parametrize("group", ["needle", "loopers", "feed", "knife"])
def test_velocities_and_accelerations_against_finite_differences(machine, group):
    """Every point and body of every group: v and a from the kinematics against central differences of the
    positions (and of the velocities) in the shaft angle, at constant speed."""
    g = next(gr for gr in machine.groups if gr.name == group)
    w, h = machine.speed, 1e-5
    phi = np.radians(np.arange(0.0, 360.0, 7.5)) + 0.01

    def solve(p):
        return g.mechanism.solve(p + g.phase, speed=w, params=g.params or None, held=g.held or None,
                                 branch=g.branch or None)

    m0, mp, mm = solve(phi), solve(phi + h), solve(phi - h)
    dt = h / w
    for name in m0.point_names:
        p0, pp, pm = m0.point(name), mp.point(name), mm.point(name)
        for c in "xy":
            v_fd = (getattr(pp, c) - getattr(pm, c)) / (2 * dt)
            a_fd = (getattr(pp, "v" + c) - getattr(pm, "v" + c)) / (2 * dt)
            scale_v = max(np.abs(getattr(p0, "v" + c)).max(), 1e-3)
            scale_a = max(np.abs(getattr(p0, "a" + c)).max(), 1.0)
            np.testing.assert_allclose(getattr(p0, "v" + c), v_fd, atol=1e-6 * scale_v, err_msg=f"{name}.v{c}")
            np.testing.assert_allclose(getattr(p0, "a" + c), a_fd, atol=1e-6 * scale_a, err_msg=f"{name}.a{c}")
    for name in m0.body_names:
        b0, bp, bm = m0.body(name), mp.body(name), mm.body(name)
        w_fd = np.angle(np.exp(1j * (bp.angle - bm.angle))) / (2 * dt)
        a_fd = (bp.omega - bm.omega) / (2 * dt)
        np.testing.assert_allclose(b0.omega, w_fd, atol=1e-6 * max(np.abs(b0.omega).max(), 1.0), err_msg=name)
        np.testing.assert_allclose(b0.alpha, a_fd, atol=1e-6 * max(np.abs(b0.alpha).max(), 1.0), err_msg=name)


def test_stitch_formation_rules_pass(machine):
    tm = timing(machine)
    assert tm.ok, tm.table()
    rules = {c.rule for c in tm.checks}
    assert {"lower_looper_at_needle_rise", "lower_looper_above_eye", "upper_takes_lower_thread",
            "needle_in_upper_triangle", "upper_above_material", "dog_sinks_before_needle_enters",
            "dog_rises_after_needle_leaves"} <= rules
    assert all(c.source for c in tm.checks)
    names = [e.name for e in tm.events]
    assert any("lower looper tip at the needle (forward pass" in n for n in names)
    assert any("upper looper tip rises past the lower looper" in n for n in names)
    # the loop pick-up: the lower looper passes the needle a few mm after BDC, just above the eye
    assert 2.5 <= tm.check("lower_looper_at_needle_rise").value <= 5.0
    rows = {p.row for p in tm.phases}
    assert {"needle", "lower looper", "upper looper", "feed dog"} <= rows


@pytest.mark.parametrize("group, shift, rule", [
    ("loopers", 30.0, "lower_looper_at_needle_rise"),  # the lower looper reaches the needle too early
    ("loopers", 30.0, "needle_in_upper_triangle"),  # the upper looper has left before the needle enters
    ("feed", 30.0, "dog_rises_after_needle_leaves"),  # the rack rises while the needle is still in
    ("feed", -30.0, "dog_sinks_before_needle_enters"),  # the rack still feeds as the needle enters
])
def test_phase_moved_by_30_deg_fails_the_right_rule(group, shift, rule):
    m = load_machine("51-a")
    g = next(gr for gr in m.groups if gr.name == group)
    g.phase += math.radians(shift)
    tm = timing(m)
    bad = {c.rule: c for c in tm.failed}
    assert rule in bad, tm.table()
    msg = bad[rule].message
    assert msg.startswith(f"{rule}:") and "φ = " in msg and "°" in msg and "outside" in msg


def test_knife_phase_does_not_touch_the_stitch_rules():
    m = load_machine("51-a")
    g = next(gr for gr in m.groups if gr.name == "knife")
    g.phase += math.radians(30.0)
    assert timing(m).ok


# -- the stitch regulator -----------------------------------------------------------------------------------------

def _stitch_here(feed, beta, params):
    """The teeth's travel above the throat plate at regulator angle β, computed here: the double eccentric
    (AB = e₁·u(φ + p) − e₂·u(φ + p + β)), the four-bar ABCD, the lift eccentric and the dyad EFK (circle
    intersections), F's height against the plate on a 0.01° grid, its x where it crosses."""
    v = dict(zip(feed.param_names, feed.param_vector(params)))
    phi = np.radians(np.arange(0.0, 360.0, 0.01))
    p = v["feed_eccentric.phase"]
    u = lambda a: np.column_stack([np.cos(a), np.sin(a)])  # noqa: E731
    b = v["feed_eccentric"] * u(phi + p) - v["stitch_eccentric"] * u(phi + p + beta)
    d = np.array([v["rock_shaft_x"], v["rock_shaft_y"]])

    def circles(p1, r1, p2, r2, sign):
        dd = p2 - p1
        dist = np.hypot(*dd.T)
        a = (r1**2 - r2**2 + dist**2) / (2 * dist)
        hh = np.sqrt(r1**2 - a**2)
        e = dd / dist[:, None]
        return p1 + a[:, None] * e + sign * hh[:, None] * np.column_stack([-e[:, 1], e[:, 0]])

    c = circles(b, v["strap"], np.tile(d, (len(phi), 1)), v["rock_arm"], -1)
    e = d + v["rack_arm"] * (d - c) / np.hypot(*(d - c).T)[:, None]
    k = v["lift_eccentric"] * u(phi + v["lift_angle"])
    f = circles(e, v["rack"], k, v["lift_link"], -1)
    z = f[:, 1] - v["plate_y"]
    up = np.flatnonzero((z < 0) & (np.roll(z, -1) >= 0))[0]
    down = np.flatnonzero((z >= 0) & (np.roll(z, -1) < 0))[0]

    def x_at(i):
        j = (i + 1) % len(z)
        t = z[i] / (z[i] - z[j])
        return f[i, 0] + t * (f[j, 0] - f[i, 0])

    return x_at(down) - x_at(up)


def test_regulator_sets_the_stitch(machine):
    g = next(gr for gr in machine.groups if gr.name == "feed")
    feed, params = g.mechanism, g.params
    reg = feed.description.role_name("stitch_regulator")
    beta = g.held[reg]  # the model file's stitch = "4 mm" solved by role
    assert stitch_length(feed, beta, params=params).travel == pytest.approx(4 * MM, abs=1e-9)
    for setting in (math.radians(15), beta, math.radians(45), math.radians(-20)):
        here = _stitch_here(feed, setting, params)
        got = stitch_length(feed, setting, params=params, step_deg=0.5).travel
        assert got == pytest.approx(here, abs=2e-6), setting
    assert 4.4 * MM < _stitch_here(feed, math.radians(45), params) < 4.7 * MM  # the longest: about 4.5 mm
    assert abs(stitch_length(feed, 0.0, params=params).travel) < 1e-9  # no throw: no feed
    for mm in (1.0, 2.5, 4.5):
        a = regulator_angle(feed, f"{mm} mm", params=params)
        assert _stitch_here(feed, a, params) == pytest.approx(mm * MM, abs=2e-6)
    with pytest.raises(ParameterError, match="beyond the regulator's range"):
        regulator_angle(feed, "6 mm", params=params)


# -- planar equivalents -----------------------------------------------------------------------------------------

#: Largest difference planar − spatial over a turn, relative to the spatial motion's range, by mechanism and
#: quantity (measured on the catalog's dimensions and on the 51-A's loopers; docs/explanation/seeds.md, seed 003).
PLANAR_CATALOG = {("overlock_needle", "rocker"): 0.0066, ("overlock_needle", "needle_eye"): 0.0065,
                  ("overlock_loopers", "rocker"): 0.0056, ("overlock_loopers", "upper_looper_tip"): 0.0058,
                  ("overlock_loopers", "lower_looper_tip"): 0.0087}


def _planar_differences(name, body, points, params=None):
    phi = np.radians(np.arange(0.0, 360.0, 0.5))
    s = sewgen.mechanism(name).solve(phi, params=params)
    p = sewgen.mechanism(f"{name}_planar").solve(phi, params=params)
    a1, a2 = np.unwrap(s.body(body).angle), np.unwrap(p.body(body).angle)
    out = {"rocker": float(np.abs(a1 - a2).max() / np.ptp(a1))}
    for q in points:
        ps, pp = s.point(q), p.point(q)
        out[q] = float(np.hypot(ps.x - pp.x, ps.y - pp.y).max() / max(np.ptp(ps.x), np.ptp(ps.y)))
    strokes = {q: (np.ptp(s.point(q).y), np.ptp(p.point(q).y)) for q in points}
    return out, strokes


def test_planar_equivalents_within_the_seeds_2_percent_on_the_catalog():
    for name, body, points in (("overlock_needle", "lever", ["needle_eye"]),
                               ("overlock_loopers", "rock_shaft", ["upper_looper_tip", "lower_looper_tip"])):
        diff, strokes = _planar_differences(name, body, points)
        for q, value in diff.items():
            assert value == pytest.approx(PLANAR_CATALOG[(name, q)], abs=2e-4), (name, q, value)
            assert value < 0.02  # seed 003: the planar equivalents agree within ±2 %
        if name == "overlock_needle":  # the stroke itself: its extremes are where the crank is in the plane
            s, p = strokes["needle_eye"]
            assert abs(p - s) / s < 1e-3


def test_planar_equivalent_of_the_51a_loopers_exceeds_2_percent(machine):
    """The 51-A's loopers have a short rod (23.3 mm on an 8 mm eccentric, the catalog's 45 on 6): the rod's
    sideways tilt is larger and the planar equivalent is off by 2.4-3.4 % — beyond the seed's ±2 %."""
    g = next(gr for gr in machine.groups if gr.name == "loopers")
    diff, _ = _planar_differences("overlock_loopers", "rock_shaft", ["upper_looper_tip", "lower_looper_tip"],
                                  params=g.params)
    assert 0.02 < max(diff.values()) < 0.04
    assert diff["rocker"] == pytest.approx(0.0265, abs=1e-3)


def test_planar_option_turns_the_crank_into_the_plane():
    d = sewgen.mechanism("overlock_needle_planar").description
    s = sewgen.mechanism("overlock_needle").description
    assert [p.name for p in d.params] == [p.name for p in s.params]


# -- the machine's layout ---------------------------------------------------------------------------------------

def test_groups_along_the_shaft(machine, analysis):
    along = {g.name for g in machine.groups if g.along}
    assert along == {"needle", "loopers"}
    # the needle's rock shaft D is placed so the eccentric's axis lies on the main shaft (y = 0)
    g = next(gr for gr in machine.groups if gr.name == "needle")
    x, y, z = g.to_machine(np.array([0.016]), np.array([-0.060]))
    assert abs(float(y[0])) < 1e-12 and float(z[0]) == pytest.approx(g.axial["eccentric"])
    # the bearings carry the rods' sideways push (machine x) from the groups along the shaft
    loads = {name: f for name, _z, f in analysis.crank_loads()}
    assert np.abs(loads["loopers.eccentric"][:, 0]).max() > 1.0
    # the throat plate, in the machine frame, is where the needle goes through
    tm = timing(machine)
    assert tm.values["plate"] == pytest.approx(0.0404)


def test_along_group_needs_its_origin(tmp_path):
    from sewgen.machine.assembly import ModelFileError

    text = (load_machine("51-a").source and open(load_machine("51-a").source, encoding="utf-8").read())
    bad = text.replace('origin = ["0 mm", "60 mm", "-28 mm"]', "", 1)
    assert bad != text
    path = tmp_path / "m.toml"
    path.write_text(bad, encoding="utf-8")
    with pytest.raises(ModelFileError, match="groups.needle.origin"):
        load_machine(path)
    wrong = text.replace('frame = "along"\norigin', 'frame = "sideways"\norigin', 1)
    assert wrong != text
    path.write_text(wrong, encoding="utf-8")
    with pytest.raises(ModelFileError, match="frame"):
        load_machine(path)


def test_summary_reports_knife_and_timing(analysis):
    from sewgen.report import outputs as report

    s = report.summary(analysis)
    knife = s["groups"]["knife"]["knife_edge"]
    assert knife["overlap_mm"] == pytest.approx(0.5626, abs=1e-3) and knife["stroke_mm"] == pytest.approx(8.125, abs=1e-3)
    assert s["groups"]["feed"]["stitch_mm"] == pytest.approx(4.0)
    assert all(c["ok"] for c in s["timing"]["checks"])


def test_the_rack_tilt_is_its_inclination_to_the_horizontal(machine, analysis):
    """The 51-A rack points back along −x (its angle near 180°): its tilt while feeding is its line's inclination,
    about −1° (falling toward the feed direction), not 178.5°–179.4°. Independent: the slope of the line through
    its two teeth F and G, from a 0.05° sweep, over the angles where tooth F stands above the plate."""
    from sewgen.report import outputs as report

    tilt = report.summary(analysis)["groups"]["feed"]["feed_dog"]["indices"]
    g = next(g for g in machine.groups if g.name == "feed")
    plate = dict(zip(g.mechanism.param_names, g.mechanism.param_vector(g.params or None)))["plate_y"]
    mo = machine.kinematics(np.radians(np.arange(0.0, 360.0, 0.05)))["feed"]
    f, t = mo.point("tooth_f"), mo.point("tooth_g")
    slope = np.degrees(np.arctan((f.y - t.y) / (f.x - t.x)))[f.y > plate]
    assert -2.0 < slope.min() < slope.max() < 0.0
    assert tilt["tilt_min_deg"] == pytest.approx(slope.min(), abs=0.01)
    assert tilt["tilt_max_deg"] == pytest.approx(slope.max(), abs=0.01)


@pytest.mark.parametrize("accel", [0.0, 500.0])
def test_shaking_moments_of_groups_along_the_shaft(accel):
    """The shaking and weight moments on the frame from the parts' kinematics (sewgen.machine.shaking, body by
    body in the machine frame) equal the ones from the groups' frame reactions with the process loads put back
    (MachineAnalysis.inertia_and_weight_moments_on_frame, the groups along the shaft placed by their origin), with
    gravity on and off."""
    from sewgen.machine import shaking

    m = load_machine("51-a")
    about = (0.01, 0.02, 0.03)
    for gravity in (np.zeros(2), np.array(m.gravity, dtype=float)):
        m.gravity = gravity
        a = m.analyze(accel=accel)
        kinematics = a.shaking_moments_on_frame(about) + shaking.weight_moments_on_frame(a, about)
        reactions = a.inertia_and_weight_moments_on_frame(about)
        np.testing.assert_allclose(kinematics, reactions, atol=1e-12 * np.abs(kinematics).max())
        assert np.abs(a.shaking_moments_on_frame(about)[:, 0]).max() > 1.0  # the needle and loopers rock it
        loads, _ = a.process_loads_on_parts()
        force = a.shaking_force_on_frame + a.weight_on_frame
        np.testing.assert_allclose(force, -(a.frame_force_on_parts + loads + np.asarray(m.shaft.belt)),
                                   atol=1e-12 * np.abs(force).max())


def test_an_eccentric_off_its_axis_loads_the_shaft_with_its_rotating_force():
    """The needle eccentric's centre of mass moved off the main shaft by (u, v) = (2, 1) mm: at constant speed the
    only change is the eccentric's own inertia, the rotating force m e ω² (e = |(u, v)|) perpendicular to the
    shaft — on the shaft's two bearings together and in the shaking force on the frame — and the machine's power
    balance still closes; the moments from the kinematics still equal those from the reactions."""
    from sewgen.machine import shaking

    m = load_machine("51-a")
    base = m.analyze()
    needle = next(g for g in m.groups if g.name == "needle")
    u, v = 2 * MM, 1 * MM
    mass = needle.mechanism.defaults()["eccentric.mass"]
    needle.params = {**needle.params, "eccentric.com_u": u, "eccentric.com_v": v}
    a = m.analyze()
    assert a.power_balance_residual <= 1e-9
    rotating = mass * math.hypot(u, v) * m.speed**2
    bearings = a.bearing("front") + a.bearing("rear") - base.bearing("front") - base.bearing("rear")
    np.testing.assert_allclose(np.hypot(bearings[:, 0], bearings[:, 1]), rotating, rtol=1e-9)
    shake = a.shaking_force_on_frame - base.shaking_force_on_frame
    np.testing.assert_allclose(shake, bearings, atol=1e-9 * rotating)
    about = (0.01, 0.02, 0.03)
    kinematics = a.shaking_moments_on_frame(about) + shaking.weight_moments_on_frame(a, about)
    np.testing.assert_allclose(kinematics, a.inertia_and_weight_moments_on_frame(about),
                               atol=1e-12 * np.abs(kinematics).max())

"""Stitch formation (sewgen.machine.timing, sewgen.machine.thread, sewgen.machine.shaking) on the built-in JB1-3.

The references are computed here without sewgen.machine.timing: event angles by bisection on the raw trajectories
(closed forms of the needle drive, or the compiled mechanisms solved at single shaft angles), the thread path's
length in closed form, the dynamic shaking force as −Σ m a_G over the parts' kinematics, the transmission
angle from the rod and rock-shaft angles.
"""
from __future__ import annotations

import dataclasses
import json
import math
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

import sewgen
from sewgen.machine import shaking
from sewgen.machine import timing as timing_module
from sewgen.machine.assembly import Group, Machine, Shaft, ShaftMass, load_machine
from sewgen.machine.modelfile import MODELS_DIR, ModelFileError
from sewgen.machine.thread import Guide, ThreadPath, eye_motion, guide_positions, path_length
from sewgen.machine.timing import timing

pytestmark = [pytest.mark.c]

ROOT = Path(__file__).resolve().parent.parent
MM = 1e-3
DEG = math.pi / 180.0
ANGLE = re.compile(r"φ = \d+\.\d+°")


@pytest.fixture(scope="module")
def jb():
    return load_machine("jb1-3")


@pytest.fixture(scope="module")
def tm(jb):
    return timing(jb)


def group(machine, name):
    return next(g for g in machine.groups if g.name == name)


def shifted(machine, name, deg):
    """``machine`` with group ``name``'s phase moved by ``deg``; the hook drive's crank also drives the feed's lift
    (seed 001's chain B → D), so moving the hook phase moves the feed's copy of it too."""
    d = math.radians(deg)
    groups = []
    for g in machine.groups:
        if g.name == name:
            g = dataclasses.replace(g, phase=g.phase + d)
        if name == "hook_drive" and g.name == "feed":
            g = dataclasses.replace(g, params=dict(g.params, **{"hook_crank.phase": g.params["hook_crank.phase"] + d}))
        groups.append(g)
    return dataclasses.replace(machine, groups=groups)


def bisect(f, a, b, tol=1e-12):
    """A root of f on [a, b] (f(a), f(b) of opposite signs), by bisection."""
    fa = f(a)
    assert fa * f(b) < 0, (a, b, fa, f(b))
    while b - a > tol:
        m = 0.5 * (a + b)
        fm = f(m)
        if (fm < 0) == (fa < 0):
            a, fa = m, fm
        else:
            b = m
    return 0.5 * (a + b)


def at(machine, name, point, phi, what="y"):
    """A point's coordinate or velocity component of group ``name`` at the machine's shaft angle ``phi`` (rad), the
    compiled mechanism solved at that one angle."""
    g = group(machine, name)
    m = g.mechanism.solve([phi + g.phase], speed=1.0, params=g.params or None, held=g.held or None)
    return float(getattr(m.point(point), what)[0])


def near(angle_deg, ref_rad, tol_deg=2e-4):
    d = (angle_deg - math.degrees(ref_rad) + 180.0) % 360.0 - 180.0
    return abs(d) <= tol_deg


# -- the built-in machine sews ----------------------------------------------------------------------------------
def test_the_jb1_3_passes_every_timing_rule(tm):
    assert [c.rule for c in tm.checks] == [
        "hook_at_needle_rise", "hook_above_eye", "hook_in_scarf", "shuttle_start_at_bdc",
        "loop_released_before_reversal", "dog_sinks_before_needle_enters", "dog_rises_after_needle_leaves",
        "take_up_rises_after_release", "stitch_set_before_needle_enters", "take_up_rise", "take_up_rises_over",
        "thread_slack"]
    assert tm.ok, [c.message for c in tm.failed]
    assert all(c.source for c in tm.checks)
    rise = tm.check("hook_at_needle_rise")
    assert 1.9 < rise.value < 2.1 and rise.unit == "mm" and (rise.lo, rise.hi) == (1.8, 2.5)
    assert tm.check("thread_slack").value > 5.0  # mm: a real margin, not a grazing pass


@pytest.mark.parametrize("deg", [40.0, -40.0])
def test_a_hook_phase_off_by_40_degrees_fails_the_hook_rules(jb, deg):
    bad = timing(shifted(jb, "hook_drive", deg))
    failed = {c.rule: c for c in bad.failed}
    assert "hook_at_needle_rise" in failed and "shuttle_start_at_bdc" in failed
    msg = failed["hook_at_needle_rise"].message
    assert msg.startswith("hook_at_needle_rise:") and "risen" in msg and "outside 1.8 – 2.5 mm" in msg
    assert len(ANGLE.findall(msg)) == 2  # the hook at the needle, the needle's bottom dead centre
    assert "φ = 270.00°" in msg
    assert not {"take_up_rise", "take_up_rises_over", "stitch_set_before_needle_enters"} & set(failed)
    # the hook drive alone moved (its lift copy left behind): the same hook rule fails
    alone = timing(dataclasses.replace(jb, groups=[dataclasses.replace(g, phase=g.phase + math.radians(deg))
                                                   if g.name == "hook_drive" else g for g in jb.groups]))
    assert "hook_at_needle_rise" in {c.rule for c in alone.failed}


@pytest.mark.parametrize("deg, rule", [(60.0, "take_up_rises_after_release"),
                                       (-60.0, "stitch_set_before_needle_enters")])
def test_a_take_up_phase_off_by_60_degrees_fails_a_take_up_rule(jb, deg, rule):
    bad = timing(shifted(jb, "take_up", deg))
    failed = {c.rule: c for c in bad.failed}
    assert rule in failed, [c.message for c in bad.failed]
    assert set(failed) <= {"take_up_rises_after_release", "stitch_set_before_needle_enters", "take_up_rise",
                           "take_up_rises_over", "thread_slack"}
    msg = failed[rule].message
    assert msg.startswith(f"{rule}:") and "take-up" in msg and len(ANGLE.findall(msg)) == 2
    top = bad.event("take-up top (stitch set)").deg
    assert f"φ = {top:.2f}°" in msg or f"φ = {bad.event('take-up bottom').deg:.2f}°" in msg
    for ok in ("hook_at_needle_rise", "hook_above_eye", "shuttle_start_at_bdc", "dog_sinks_before_needle_enters"):
        assert bad.check(ok).ok


# -- event angles against independent computations -------------------------------------------------------------
def test_needle_events_against_the_crank_slider_closed_form(jb, tm):
    """Needle point y = r sin φ − √(l² − (r cos φ − e)²) − h − tip (crank at φ, needle-bar axis at x = e),
    bisected at the cloth's top and the throat plate."""
    g = group(jb, "needle_bar")
    p = dict(zip(g.mechanism.param_names, g.mechanism.param_vector(g.params)))
    r, l, e, h, tip = p["crank"], p["rod"], p["offset"], p["eye_below_pin"], p["point_below_eye"]
    plate = -170.5 * MM
    cloth = plate + jb.stitch.cloth

    def y(phi):
        return r * math.sin(phi + g.phase) - math.sqrt(l**2 - (r * math.cos(phi + g.phase) - e) ** 2) - h - tip

    down = bisect(lambda f: y(f) - cloth, math.radians(100), math.radians(260))
    up = bisect(lambda f: y(f) - cloth, math.radians(280), math.radians(440))
    assert near(tm.event("needle point into the cloth").deg, down)
    assert near(tm.event("needle point out of the cloth").deg, up)
    assert near(tm.event("needle point through the throat plate").deg,
                bisect(lambda f: y(f) - plate, math.radians(100), math.radians(260)))
    assert near(tm.event("needle bottom dead centre").deg, math.radians(270.0))
    assert near(tm.event("needle top dead centre").deg, math.radians(90.0))
    lift = bisect(lambda f: y(f) - (y(1.5 * math.pi) + jb.stitch.loop_lift), math.radians(270), math.radians(360))
    assert near(tm.event("loop lift: needle risen 2 mm").deg, lift)


def test_hook_take_up_and_dog_events_from_single_angle_solves(jb, tm):
    """Bisection on quantities of the compiled mechanisms solved at one angle at a time: the hook point on the
    needle's centre line (x_hook − x_needle), the take-up eye's top and bottom (its vy), the dog at the plate."""
    x_needle = lambda f: at(jb, "needle_bar", "needle_point", f, "x")  # noqa: E731
    hook = bisect(lambda f: at(jb, "hook_drive", "hook_point", f, "x") - x_needle(f),
                  math.radians(280), math.radians(310))
    assert near(tm.event("hook point at the needle (forward pass, picks up the loop)").deg, hook)
    top = bisect(lambda f: at(jb, "take_up", "thread_eye", f, "vy"), math.radians(150), math.radians(200))
    bottom = bisect(lambda f: at(jb, "take_up", "thread_eye", f, "vy"), math.radians(30), math.radians(80))
    assert near(tm.event("take-up top (stitch set)").deg, top)
    assert near(tm.event("take-up bottom").deg, bottom)
    plate = -170.5 * MM
    rise = bisect(lambda f: at(jb, "feed", "feed_dog", f) - plate, math.radians(-20), math.radians(40))
    sink = bisect(lambda f: at(jb, "feed", "feed_dog", f) - plate, math.radians(150), math.radians(200))
    assert near(tm.event("feed dog rises above the plate").deg, rise)
    assert near(tm.event("feed dog sinks below the plate").deg, sink)
    # the shuttle's reversal: the lower shaft's angular velocity through zero
    g = group(jb, "hook_drive")

    def omega(f):
        return float(g.mechanism.solve([f + g.phase], speed=1.0, params=g.params).body("lower_shaft").omega[0])

    start = bisect(omega, math.radians(250), math.radians(290))
    assert near(tm.event("shuttle reverses: starts its forward stroke").deg, start)
    # the rule values from the same references
    y_n = lambda f: at(jb, "needle_bar", "needle_point", f)  # noqa: E731
    assert tm.check("hook_at_needle_rise").value == pytest.approx((y_n(hook) - y_n(1.5 * math.pi)) / MM, abs=1e-5)
    eye_top = at(jb, "needle_bar", "needle_eye", hook) + 0.6 * MM
    assert tm.check("hook_above_eye").value == pytest.approx((at(jb, "hook_drive", "hook_point", hook) - eye_top)
                                                             / MM, abs=1e-5)
    assert tm.check("take_up_rise").value == pytest.approx(math.degrees(top - bottom), abs=1e-4)


# -- the thread ---------------------------------------------------------------------------------------------------
def test_thread_length_through_two_fixed_guides_and_one_moving_eye():
    """L = |G1 − E| + |E − G2| with E the take-up's eye from the four-bar's closed form (seed 004's frame)."""
    tu = sewgen.mechanism("take_up")
    g = Group("take_up", tu, 0.0, {"crank": 0.0}, {}, {}, {}, [])
    m = Machine("T", "", 100.0, math.radians(5), np.array([0.0, -9.81]), [g],
                Shaft(0.0, 0.1, 1e-5, [ShaftMass("core", 0.1, 0.0, 0.0, 0.05)]))
    path = ThreadPath((Guide("discs", at=(-0.030, -0.005)), Guide("eye", point="thread_eye"),
                       Guide("guide", at=(0.020, -0.010))))
    phi = np.radians(np.arange(0.0, 360.0, 2.0))
    L = path_length(guide_positions(m, m.kinematics(phi), path, len(phi)))
    p = dict(zip(tu.param_names, tu.param_vector()))
    B = p["crank"] * np.exp(1j * phi)
    D = p["rocker_pivot_x"] + 1j * p["rocker_pivot_y"]
    d = D - B
    K = (p["lever_bc"] ** 2 - abs(d) ** 2 - p["rocker"] ** 2) / (2 * p["rocker"])
    cands = [D + p["rocker"] * np.exp(1j * (np.angle(d) + s * np.arccos(K / abs(d)))) for s in (1, -1)]
    left = (d.real * (cands[0] - B).imag - d.imag * (cands[0] - B).real) > 0  # branch +1: C left of B → D
    C = np.where(left, cands[0], cands[1])
    bc, be, ce = p["lever_bc"], p["lever_be"], p["lever_ce"]
    beta = math.acos((bc**2 + be**2 - ce**2) / (2 * bc * be))
    E = B + p["lever_be"] * np.exp(1j * (np.angle(C - B) + beta))
    ref = abs(E - (-0.030 - 0.005j)) + abs((0.020 - 0.010j) - E)
    np.testing.assert_allclose(L, ref, rtol=0, atol=1e-15)


def test_a_guide_on_the_needle_bar_moves_with_it(jb, tm):
    """The needle-bar thread guide: 45 mm up the bar from the needle eye, whatever the shaft angle."""
    names = [name for name, _ in tm.thread.guides]
    guide, eye = (dict(tm.thread.guides)[k] for k in ("needle-bar thread guide", "needle eye"))
    assert names[-1] == "needle eye"
    np.testing.assert_allclose(guide - eye, np.tile([0.0, 0.045], (len(eye), 1)), rtol=0, atol=1e-14)


def test_supply_demand_and_slack(tm):
    th = tm.thread
    k = int(np.argmin(np.abs(np.angle(np.exp(1j * (th.phi - th.set_at))))))
    assert th.slack[k] == pytest.approx(0.0, abs=1e-15)  # the stitch is set: the thread tight
    np.testing.assert_allclose(th.supply, th.length.max() - th.length, rtol=0, atol=1e-15)
    assert th.supply.min() == 0.0 and th.take_up_amount == pytest.approx(np.ptp(th.length))
    on = th.in_window()
    assert on.any() and th.min_slack == pytest.approx(th.slack[on].min())
    assert (th.slack[~on] >= -1e-12).all()  # outside the window, thread is drawn through the tension instead
    assert np.all(np.diff(th.drawn[np.roll(np.arange(len(th.phi)), -k)]) >= 0)  # drawn thread stays drawn
    assert 3.0 * MM < th.per_stitch < 12.0 * MM  # about a 4 mm stitch and the cloth's thickness
    assert th.parts["loop"].max() == pytest.approx(2 * 2 * 0.012, rel=0.02)  # two legs across the shuttle
    assert tm.check("thread_slack").value == pytest.approx(th.min_slack / MM)


def test_seed_004_eye_speed_and_acceleration_of_the_jack_a4_take_up():
    """The catalog take-up (seed 004's JACK A4, A = (0, 0), D = (26, −20) mm) at its 5000 r/min: |v| and |a| of
    the eye against central differences of its positions in time."""
    tu = sewgen.mechanism("take_up")
    h = math.radians(0.01)
    phi = np.radians(np.arange(0.0, 360.0, 1.0))
    w = 5000 * 2 * math.pi / 60
    m = tu.solve(phi, speed=w)
    spd, acc = eye_motion(m)
    assert m.omega[0] == pytest.approx(w)
    pts = [tu.solve(phi + k * h, speed=w).point("thread_eye") for k in (-1, 0, 1)]
    dt = h / w
    vx, vy = (pts[2].x - pts[0].x) / (2 * dt), (pts[2].y - pts[0].y) / (2 * dt)
    ax, ay = (pts[2].x - 2 * pts[1].x + pts[0].x) / dt**2, (pts[2].y - 2 * pts[1].y + pts[0].y) / dt**2
    np.testing.assert_allclose(spd, np.hypot(vx, vy), rtol=1e-6)
    np.testing.assert_allclose(acc, np.hypot(ax, ay), rtol=2e-4)
    assert 5.0 < spd.max() < 40.0 and acc.max() > 1e3  # m/s, m/s²: an industrial take-up's figures


# -- the design: hook drive, lift chain, ranges ------------------------------------------------------------------
def test_hook_drive_transmission_angle_swing_and_lift_copy(jb):
    phi = np.radians(np.arange(0.0, 360.0, 0.05))
    mo = jb.kinematics(phi)
    hd = mo["hook_drive"]
    rod, rock = hd.coord("big_rod.angle").value, hd.coord("rock_shaft.angle").value
    mu = np.degrees(np.abs(np.arcsin(np.sin(rod - rock))))  # big rod against the rock shaft's front arm
    assert mu.min() >= 40.0, mu.min()
    swing = np.degrees(np.ptp(np.unwrap(hd.coord("lower_shaft.angle").value)))
    assert 206.0 <= swing <= 210.0, swing
    # seed 001's lift chain B → D: the feed's copy of B moves the hook drive's rock shaft exactly
    np.testing.assert_allclose(mo["feed"].coord("rock_shaft.angle").value, rock, rtol=0, atol=1e-12)


def test_the_feed_keeps_its_stitch_and_dog_height(jb, tm):
    dog = tm.event("feed dog sinks below the plate").note
    height = float(re.search(r"([\d.]+) mm above", dog).group(1))
    assert 0.8 <= height <= 1.2  # Brother S-7000DD: 0.8 / 1.0 / 1.2 mm
    assert "cloth moved 4.00 mm" in tm.event("feed ends").note


# -- shaking force on the frame (inertia only), weight on the frame, the frame's force on the parts ------------
def test_shaking_force_on_the_frame_without_the_weight(jb):
    a = jb.analyze()
    total, mass = np.zeros((len(a.phi), 2)), 0.0
    for g in jb.groups:
        fa = a.groups[g.name]
        vals = dict(zip(g.mechanism.param_names, fa.run_settings.params))
        for body in fa.motion.body_names:
            m, c = vals[f"{body}.mass"], fa.motion.body(body).com
            total -= m * np.column_stack([c.ax, c.ay])
            mass += m
    for sm in jb.shaft.masses:
        th = a.phi + sm.angle
        total += sm.mass * sm.radius * a.omega[:, None] ** 2 * np.column_stack([np.cos(th), np.sin(th)])
        mass += sm.mass
    np.testing.assert_allclose(shaking.shaking_force_on_frame(a), total, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.shaking_force_on_frame, total, rtol=0, atol=1e-12)
    np.testing.assert_allclose(shaking.weight_on_frame(a), [0.0, -9.80665 * mass], rtol=1e-14)
    assert abs(a.shaking_force_on_frame.mean(axis=0)).max() < 0.05  # inertia only: no static part left


def test_shaking_and_weight_on_frame_are_the_frames_force_on_the_parts_turned_round(jb):
    """At every angle, from the kinematics (left) and from the compiled kernels' frame reactions (right):
    shaking force on the frame + weight on the frame = −(frame's force on the parts + process loads + belt pull),
    and the same for the moments about a point off every axis."""
    a = jb.analyze()
    loads, load_mz = a.process_loads_on_parts()
    assert np.abs(loads).max() > 1.0  # the process loads are on: the check is not empty
    belt = np.asarray(jb.shaft.belt, dtype=float)
    left = a.shaking_force_on_frame + a.weight_on_frame
    right = -(a.frame_force_on_parts + loads + belt)
    np.testing.assert_allclose(left, right, rtol=0, atol=1e-10 * np.abs(right).max())
    about = (0.013, -0.021, 0.05)
    moments = a.shaking_moments_on_frame(about) + shaking.weight_moments_on_frame(a, about)
    scale = np.abs(moments).max()
    np.testing.assert_allclose(moments, a.inertia_and_weight_moments_on_frame(about), rtol=0, atol=1e-10 * scale)
    ox, oy, _ = about
    force = loads + belt
    mz = -(a.frame_moment_on_parts((ox, oy)) + load_mz - (ox * force[:, 1] - oy * force[:, 0]))
    np.testing.assert_allclose(moments[:, 2], mz, rtol=0, atol=1e-10 * scale)
    # inertia only: the moments of the inertia forces average out over a turn; the weight's do not
    assert np.abs(a.shaking_moments_on_frame().mean(axis=0)).max() < 0.05
    assert np.abs(shaking.weight_moments_on_frame(a).mean(axis=0)).max() > 0.05


# -- outputs -------------------------------------------------------------------------------------------------------
def test_summary_json_and_timing_files(jb, tmp_path):
    from sewgen.report.outputs import write_report

    a = jb.analyze()
    files = write_report(a, tmp_path)
    s = json.loads((tmp_path / "summary.json").read_text())
    t = s["timing"]
    assert {"name", "angle_deg"} <= set(t["events"][0]) and len(t["events"]) == 18
    assert all({"rule", "value", "limit", "unit", "ok"} <= set(c) for c in t["checks"]) and all(
        c["ok"] for c in t["checks"])
    assert s["shaking_force_on_frame"]["acts_on"] == "frame" and s["weight_on_frame"]["acts_on"] == "frame"
    assert s["bearings"]["rear"]["acts_on"] == "frame"
    fine = jb.analyze(jb.shaft_angles(math.radians(0.05)))  # the peak between the samples
    assert s["shaking_force_on_frame"]["max"] == pytest.approx(np.hypot(*fine.shaking_force_on_frame.T).max(), rel=1e-5)
    assert (tmp_path / "timing.txt") in files and "12 of 12 rules pass" in (tmp_path / "timing.txt").read_text()
    header = (tmp_path / "machine.csv").read_text().splitlines()[0]
    assert "bearing_rear_on_frame.fx [N]" in header


def test_csv_and_summary_name_what_acts_on_what(jb, tmp_path):
    """machine.csv, a group's csv and summary.json carry the names of sewgen.machine.shaking's convention and
    none of the old ones."""
    from sewgen.report.outputs import CONVENTIONS, write_report

    a = jb.analyze()
    write_report(a, tmp_path)
    header = (tmp_path / "machine.csv").read_text().splitlines()[0].split(",")
    new = {f"shaking_force_on_frame.{c} [N]" for c in ("fx", "fy", "magnitude")}
    new |= {f"shaking_moments_on_frame.{c} [N*m]" for c in "xyz"}
    new |= {"frame_force_on_parts.fx [N]", "frame_force_on_parts.fy [N]"}
    assert new <= set(header)
    assert not [h for h in header if h.startswith(("shaking_on_frame", "frame_on_parts", "shaking."))]
    group = (tmp_path / f"{jb.groups[0].name}.csv").read_text().splitlines()[0].split(",")
    assert {"frame_force_on_parts.fx [N]", "frame_force_on_parts.fy [N]", "frame_moment_on_parts [N*m]"} <= set(group)
    assert not [h for h in group if h.startswith("shaking")]
    s = json.loads((tmp_path / "summary.json").read_text())
    assert {"shaking_force_on_frame", "shaking_moments_on_frame", "weight_on_frame"} <= set(s)
    assert set(s["shaking_moments_on_frame"]) == {"x", "y", "z"}
    old = {"shaking_force", "shaking_moment", "shaking_moments_about_origin", "weight_of_moving_parts"}
    assert not old & set(s) and not old & set(s["conventions"]) and not old & set(CONVENTIONS)
    assert {"shaking_force_on_frame", "shaking_moments_on_frame", "frame_force_on_parts"} <= set(s["conventions"])


def test_old_names_warn_and_keep_their_values(jb):
    a = jb.analyze()
    fa = a.groups[jb.groups[0].name]
    with pytest.warns(DeprecationWarning, match="frame_force_on_parts"):
        np.testing.assert_array_equal(a.frame_reaction, a.frame_force_on_parts)
    with pytest.warns(DeprecationWarning, match="shaking_force_on_frame"):
        old = a.shaking_force
    np.testing.assert_allclose(old, -(a.shaking_force_on_frame + a.weight_on_frame), atol=1e-9)
    with pytest.warns(DeprecationWarning, match="shaking_moments_on_frame"):
        np.testing.assert_array_equal(a.shaking_moments(), -a.inertia_and_weight_moments_on_frame())
    with pytest.warns(DeprecationWarning, match="frame_force_on_parts"):
        np.testing.assert_array_equal(fa.shaking_force, fa.frame_force_on_parts)
    with pytest.warns(DeprecationWarning, match="shaking_force_on_frame"):
        np.testing.assert_array_equal(shaking.shaking_force(a), a.shaking_force_on_frame)


def test_the_timing_command(tmp_path):
    def run(*args):
        return subprocess.run([sys.executable, "-m", "sewgen", "timing", *args], capture_output=True, text=True,
                              cwd=ROOT)

    ok = run("jb1-3")
    assert ok.returncode == 0 and "12 of 12 rules pass" in ok.stdout and "needle bottom dead centre" in ok.stdout
    text = (MODELS_DIR / "jb1-3.toml").read_text().replace('phase = "-2 deg"', 'phase = "38 deg"')
    (tmp_path / "late.toml").write_text(text)
    bad = run(str(tmp_path / "late.toml"), "--json")
    assert bad.returncode == 3  # done, and the machine fails a rule (1 is a bug of sewgen, 2 a mistake)
    assert "hook_at_needle_rise" in bad.stderr
    checks = {c["rule"]: c for c in json.loads(bad.stdout)["checks"]}
    assert checks["hook_at_needle_rise"]["ok"] is False


def test_model_file_stitch_errors_name_the_key(tmp_path):
    text = (MODELS_DIR / "jb1-3.toml").read_text()
    for old, new, key in (('rule = "take_up_rise"', 'rule = "take_up_rize"', "stitch.rules[9].rule"),
                          ('cloth = "1.5 mm"', 'cloth = "1.5 deg"', "stitch.cloth"),
                          ('min = "1.8 mm"', 'min = "1.8 deg"', "stitch.rules[0].min"),
                          ('at = ["-30 mm", "-5 mm"]', 'at = ["-30 mm"]', "thread.guides[0].at")):
        assert text.count(old) == 1, old
        p = tmp_path / "bad.toml"
        p.write_text(text.replace(old, new))
        with pytest.raises(ModelFileError) as exc:
            load_machine(p)
        assert exc.value.key == key, (exc.value.key, str(exc.value))


# -- the rules: one class each, found through the registry -------------------------------------------------------
UNIT = {"length": "mm", "angle": "deg"}  # a rule's kind (its min/max) -> the unit its checks show


def test_every_registered_rule_is_a_class_of_its_own():
    rules = timing_module.RULES
    assert len(rules) == 18
    for name, rule in rules.items():
        cls = type(rule)
        assert isinstance(rule, timing_module.TimingRule) and rule.name == name, name
        assert cls.measure is not timing_module.TimingRule.measure, f"{name}: measured nowhere"
        assert "__doc__" in vars(cls) and cls.__doc__.strip(), f"{name}: no docstring of its own (its source)"
        assert UNIT.get(rule.kind) == rule.unit and rule.text, name
        assert sum(type(r) is cls for r in rules.values()) == 1, f"{name}: its class registered twice"
    # the module's table of rules names the same rules, in the same order
    documented = re.findall(r"^``(\w+)``\s+(length|angle)\s", timing_module.__doc__, re.M)
    assert documented == [(n, r.kind) for n, r in rules.items()]


@pytest.mark.parametrize("path", sorted(MODELS_DIR.glob("*.toml")), ids=lambda p: p.stem)
def test_every_model_files_rule_is_registered(path):
    doc = tomllib.loads(path.read_text())
    names = [r["rule"] for r in doc.get("stitch", {}).get("rules", [])]
    assert names and set(names) <= set(timing_module.RULES), set(names) - set(timing_module.RULES)
    st = load_machine(path).stitch
    assert [r.kind for r in st.rules] == names


class NeedleHalfTurn(timing_module.TimingRule):
    """A rule for the test: the needle's fall, top dead centre to bottom dead centre (half a turn for a
    crank-driven needle bar)."""

    name = "needle_half_turn"
    kind, unit = "angle", "deg"
    text = "needle falls over half a turn"
    needs = ("tdc", "bdc")
    lacks = "the machine needs a needle_point"

    def measure(self, rule, tm, st, machine, ge):
        v = tm.values
        return timing_module.Measured((v["bdc"] - v["tdc"]) % (2 * math.pi), "the needle falls from its top to "
                                      "its bottom dead centre over")


def test_a_rule_registered_only_in_the_registry_is_read_and_checked(tmp_path, monkeypatch):
    """A rule class registered in RULES and nowhere else is read from a model file and checked in its place
    among the machine's rules; unregistered, the same file names it an unknown rule."""
    text = (MODELS_DIR / "jb1-3.toml").read_text()
    anchor = '[[stitch.rules]]\nrule = "take_up_rise"\n'
    assert text.count(anchor) == 1
    p = tmp_path / "half_turn.toml"
    p.write_text(text.replace(anchor, '[[stitch.rules]]\nrule = "needle_half_turn"\nmin = "175 deg"\n'
                                      'max = "3.2 rad"\nsource = "the test"\n' + anchor))
    with monkeypatch.context() as mp:
        mp.setitem(timing_module.RULES, NeedleHalfTurn.name, NeedleHalfTurn())
        m = load_machine(p)
        tm = timing(m)
        names = [c.rule for c in tm.checks]
        assert names[names.index("needle_half_turn") + 1] == "take_up_rise" and len(names) == 13
        c = tm.check("needle_half_turn")
        ref = math.degrees((tm.values["bdc"] - tm.values["tdc"]) % (2 * math.pi))
        assert c.value == pytest.approx(ref, abs=1e-9) and 170.0 < c.value < 190.0
        assert (c.lo, c.hi, c.unit, c.ok, c.source) == (175.0, pytest.approx(math.degrees(3.2)), "deg", True,
                                                       "the test")
        assert c.message.startswith("needle_half_turn: the needle falls from its top to its bottom dead centre "
                                    f"over: {c.value:.3f} deg, within 175 – ")
        assert "13 of 13 rules pass" in tm.table() and tm.as_dict()["checks"][names.index(c.rule)]["ok"] is True
        # a machine without the values it needs: it cannot be checked, and says what is missing
        bare = timing_module.RULES["needle_half_turn"].check(m.stitch.rules[names.index(c.rule)],
                                                            dataclasses.replace(tm, values={}), m.stitch, m, None)
        assert not bare.ok and bare.message == "needle_half_turn: cannot be checked: the machine needs a needle_point"
    assert "needle_half_turn" not in timing_module.RULES
    with pytest.raises(ModelFileError) as exc:
        load_machine(p)
    where = f"stitch.rules[{names.index('needle_half_turn')}].rule"
    assert exc.value.key == where and "unknown rule" in str(exc.value)

"""Peaks between the samples (sewgen.machine.peaks): the value and the angle of an extreme are the machine's own,
not the largest sample's.

Independent references: closed-form curves with a peak between the samples and with a jump; a 0.05° sweep of the
machine computed here, against the default 5° one; the figures' labels against summary.json.
"""
from __future__ import annotations

import math
import re

import numpy as np
import pytest

from sewgen.machine.assembly import load_machine
from sewgen.machine.peaks import AT_SWITCH, REFINED, SAMPLED, refine
from sewgen.report.outputs import summary

pytestmark = pytest.mark.c

FINE = math.radians(0.05)


@pytest.fixture(scope="module")
def jb():
    return load_machine("jb1-3")


@pytest.fixture(scope="module")
def jb_fine(jb):
    return jb.analyze(jb.shaft_angles(FINE))


# -- the search on closed forms ------------------------------------------------------------------------------------

def _curve(x):
    """Two narrow Gaussian peaks between 5° samples (heights 1 at 192.3°, 0.9 at 40.1°) and a dip at 300.7°."""
    d = lambda c: np.angle(np.exp(1j * (x - math.radians(c))))  # noqa: E731
    w = math.radians(2.0)
    return np.exp(-(d(192.3) / w) ** 2) + 0.9 * np.exp(-(d(40.1) / w) ** 2) - 0.5 * np.exp(-(d(300.7) / w) ** 2)


def test_a_peak_between_the_samples_is_found_with_its_angle():
    phi = np.radians(np.arange(0.0, 360.0, 5.0))
    sampled = _curve(phi)
    assert sampled.max() < 0.9  # the samples at 190° and 195° miss the peak by a quarter
    ext = refine(phi, {"f": sampled}, lambda x: ({"f": _curve(x)}, None))["f"]
    assert ext["max"].value == pytest.approx(1.0, abs=1e-8) and ext["max"].how == REFINED
    assert math.degrees(ext["max"].angle) == pytest.approx(192.3, abs=1e-3) and ext["max"].deg == 192.3
    assert ext["min"].value == pytest.approx(-0.5, abs=1e-8) and ext["min"].deg == 300.7


def test_a_peak_at_a_jump_is_the_larger_one_sided_value_at_the_switch():
    s = math.radians(101.3)  # a load switched off at 101.3°: the curve drops by 2 there

    def f(x):
        x = np.asarray(x) % (2 * math.pi)
        return np.cos(x - math.radians(130.0)) + 2.0 * (x <= s)  # rising to the switch

    def sig(x):
        return ((np.asarray(x) % (2 * math.pi)) <= s).astype(float)[:, None]

    phi = np.radians(np.arange(0.0, 360.0, 5.0))
    ext = refine(phi, {"f": f(phi)}, lambda x: ({"f": f(x)}, sig(x)), sig(phi))["f"]["max"]
    assert ext.how == AT_SWITCH and ext.deg == 101.3
    assert ext.value == pytest.approx(math.cos(s - math.radians(130.0)) + 2.0, abs=1e-6)  # the left limit


def test_an_analysis_that_cannot_be_solved_again_says_its_extremes_are_sampled():
    phi = np.radians(np.arange(0.0, 360.0, 5.0))
    ext = refine(phi, {"f": _curve(phi)}, lambda x: None)["f"]["max"]
    assert ext.how == SAMPLED and ext.value == _curve(phi).max()


# -- the machine -----------------------------------------------------------------------------------------------------

def test_the_rear_bearing_peak_at_the_default_step_is_the_fine_sweep_s(jb, jb_fine):
    s = summary(jb.analyze())  # the model's 5° step
    assert s["step_deg"] == 5.0
    fine = np.hypot(*jb_fine.bearing("rear").T)
    k = int(np.argmax(fine))
    rear = s["bearings"]["rear"]
    assert rear["max"] == pytest.approx(fine[k], rel=5e-3) and rear["max_how"] == "refined"
    assert abs(rear["max_at_deg"] - math.degrees(jb_fine.phi[k])) < 0.5
    torque = jb_fine.torque
    k = int(np.argmin(torque))
    assert s["drive_torque"]["min"] == pytest.approx(torque[k], rel=5e-3)
    assert abs(s["drive_torque"]["min_at_deg"] - math.degrees(jb_fine.phi[k])) < 0.5


def test_every_stated_extreme_of_the_summary_is_the_fine_sweep_s(jb, jb_fine):
    s = summary(jb.analyze())
    checks = {("bearings", "front"): np.hypot(*jb_fine.bearing("front").T),
              ("shaking_force_on_frame",): np.hypot(*jb_fine.shaking_force_on_frame.T),
              ("drive_torque",): jb_fine.torque}
    for g, fa in jb_fine.groups.items():
        for n in fa.reaction_names:
            checks[("groups", g, "joints", n)] = fa.reaction(n).magnitude
    for path, values in checks.items():
        stat = s
        for p in path:
            stat = stat[p]
        scale = np.ptp(values)
        assert stat["max"] == pytest.approx(values.max(), abs=5e-3 * scale), path
        assert stat["min"] == pytest.approx(values.min(), abs=5e-3 * scale), path


def test_an_analysis_at_per_position_speeds_states_its_extremes_are_the_samples(jb):
    """A speed that varies per position cannot be carried to other angles: the summary says its extremes are the
    sampled ones instead of presenting them as the machine's."""
    phi = jb.shaft_angles()
    w = jb.speed * (1.0 + 0.05 * np.sin(phi))
    a = jb.analyze(phi, speed=w, accel=jb.speed**2 * 0.05 * np.cos(phi))
    rear = summary(a)["bearings"]["rear"]
    assert rear["max_how"] == "sampled"
    assert rear["max"] == pytest.approx(np.hypot(*a.bearing("rear").T).max(), rel=1e-11)


def test_the_figures_label_the_summary_s_peaks(jb):
    matplotlib = pytest.importorskip("matplotlib")
    from sewgen.report.plots import draw_bearings_polar, new_figure

    assert matplotlib
    a = jb.analyze()
    s = summary(a)
    fig = new_figure((12.0, 6.6))
    draw_bearings_polar(fig, a.refined())  # the figures are drawn from the 1° analysis
    titles = [ax.get_title() for ax in fig.axes if ax.get_title()]
    for which, title in zip(("front", "rear"), titles):
        value, angle = re.search(r"peak (\S+) N at φ = (\S+)°", title).groups()
        stat = s["bearings"][which]
        assert value == f"{stat['max']:.3g}" and float(angle) == pytest.approx(stat["max_at_deg"], abs=0.051)


test_the_figures_label_the_summary_s_peaks = pytest.mark.plots(test_the_figures_label_the_summary_s_peaks)


def test_a_study_s_peak_loads_at_a_coarse_step_are_the_fine_sweep_s(jb, jb_fine):
    from sewgen.study import StudyOptions, run_designs

    df = run_designs(jb, ["groups.needle_bar.params.crank"], [[0.0167]], StudyOptions(step_deg=5.0))
    assert df["status"][0] == "ok"
    assert df["rear_bearing_peak [N]"][0] == pytest.approx(np.hypot(*jb_fine.bearing("rear").T).max(), rel=5e-3)
    assert df["drive_torque_peak [N*m]"][0] == pytest.approx(np.abs(jb_fine.torque).max(), rel=5e-3)


def test_a_feed_at_a_cam_arc_switch_is_the_same_in_every_sweep():
    """The JB1-3 feed cam switches arc at the group angle 300°: every sweep containing 300° must give there the
    value of the arc that starts at 300° (right-continuous in the shaft angle), the limit from above."""
    import sewgen

    feed = sewgen.mechanism("feed")
    right = feed.solve(np.radians([300.0 + 1e-7]), speed="1000 rpm").body("feed_rock_shaft").alpha[0]
    for phis in ([300.0], [0.0, 300.0], [295.0, 300.0], list(np.arange(0.0, 360.0, 5.0)),
                 list(np.arange(0.0, 360.0, 1.0))):
        got = feed.solve(np.radians(phis), speed="1000 rpm").body("feed_rock_shaft").alpha[phis.index(300.0)]
        assert got == pytest.approx(right, rel=1e-5), phis


@pytest.mark.cli
def test_the_mechanism_commands_print_the_peaks_between_the_samples(capsys):
    """``sewgen kinematics`` / ``forces`` at their default 5°: the take-up rocker pin's peak |a| and the least
    driving torque are a 0.01° sweep's (computed here; the 5° samples read 0.4 % and 0.6 % low)."""
    import sewgen
    from sewgen.cli.main import main

    m = sewgen.mechanism("take_up")
    phi = np.radians(np.arange(0.0, 360.0, 0.01))
    pin = m.solve(phi).point("rocker_pin")
    acc = np.hypot(pin.ax, pin.ay)
    torque = m.kinetostatics(phi).torque("shaft")
    assert main(["kinematics", "take_up"]) == 0
    out = capsys.readouterr().out
    value, angle = re.search(r"^rocker_pin .* (\S+) @ +(\S+)° *$", out, re.M).groups()
    assert float(value) == pytest.approx(acc.max(), rel=1e-5)
    assert float(angle) == pytest.approx(math.degrees(phi[np.argmax(acc)]), abs=0.02)
    assert main(["forces", "take_up"]) == 0
    out = capsys.readouterr().out
    value, angle = re.search(r"^torque shaft +min +(\S+) @ +(\S+)°", out, re.M).groups()
    assert float(value) == pytest.approx(torque.min(), rel=1e-5)
    assert float(angle) == pytest.approx(math.degrees(phi[np.argmin(torque)]), abs=0.02)

"""Whole-machine balancing: seed 000 part 2's three methods on counterweight planes of the upper shaft.

Independent references: seed 002's optimum through `sewgen balance needle-bar` (method 1 on a lone crank-slider);
the textbook primary balance of a crank-slider and its second order m_C r ω² (λ + λ³/4 + 15λ⁵/128) (method 2); a
least-squares solve written here from machines re-read with test masses (method 3, RMS); random feasible points
around the peak optimum; and `sewgen analyze` of the written model file.
"""
from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from sewgen.machine import machine_balance as mb
from sewgen.machine.assembly import load_machine
from sewgen.machine.modelfile import MODELS_DIR

pytestmark = [pytest.mark.c, pytest.mark.cli]

LONE = '''
[machine]
name = "lone crank-slider"
speed = "1000 rpm"
step = "0.1 deg"
gravity = "9.80665 m/s**2"

[shaft]
front_bearing = "0 mm"
rear_bearing = "200 mm"
mass = "0 g"
mass_z = "100 mm"
inertia = "1e-5 kg*m**2"

[[shaft.counterweights]]
name = "cw"
z = "-18 mm"
radius = "10 mm"
max_mass = "1 kg"
group = "needle_bar"

[groups.needle_bar]
mechanism = "needle_bar"
phase = "0 deg"
axial = { crank = "-18 mm" }
[groups.needle_bar.params]
crank = "16.7 mm"
rod = "50 mm"
offset = "0 mm"
"crank.mass" = "20 g"
"crank.com_u" = "16.7 mm"
"crank.com_v" = "0 mm"
"crank.inertia" = "0 kg*m**2"
"rod.mass" = "0 g"
"rod.inertia" = "0 kg*m**2"
"needle_bar.mass" = "60 g"
'''

PLANES = '''
[[shaft.counterweights]]
name = "front_cw"
z = "-30 mm"
radius = "12 mm"
max_mass = "{front}"
group = "needle_bar"

[[shaft.counterweights]]
name = "rear_cw"
z = "190 mm"
radius = "12 mm"
max_mass = "{rear}"
group = "hook_drive"
'''


@pytest.fixture(scope="module")
def lone(tmp_path_factory):
    path = tmp_path_factory.mktemp("lone") / "lone.toml"
    path.write_text(LONE)
    return load_machine(path)


def jb_text() -> str:
    """The built-in JB1-3 without its own counterweight planes (the tests set theirs)."""
    text = (MODELS_DIR / "jb1-3.toml").read_text()
    return text[:text.index("\n# Counterweight planes")] + "\n"


def jb_with_planes(folder, front="500 g", rear="500 g", extra=""):
    path = folder / "jb_planes.toml"
    path.write_text(jb_text() + PLANES.format(front=front, rear=rear) + extra)
    return path


def test_method_1_on_a_lone_crank_slider_is_seed_002(lone):
    out = subprocess.run([sys.executable, "-m", "sewgen", "balance", "needle-bar", "--crank", "16.7mm", "--rod",
                          "50mm", "--speed", "1000rpm", "--mass-b", "20g", "--mass-c", "60g", "--series", "exact",
                          "--points", "3600", "--json"], capture_output=True, text=True, check=True)
    seed002 = json.loads(out.stdout)
    report = mb.balance(lone, "separate")
    (cw,) = report.solution.counterweights
    assert cw.mr == pytest.approx(seed002["counterweight_mr"], rel=2e-5)
    assert math.degrees(cw.angle) % 360 == pytest.approx(180.0, abs=1e-3)  # opposite the crank
    assert report.as_dict()["after"]["shaking_force_on_frame_peak"] == pytest.approx(seed002["F1_after"], rel=1e-4)


def test_method_2_is_the_textbook_primary_balance(lone):
    report = mb.balance(lone, "harmonic", first_order="y")
    r, l, m_c, m_b = 0.0167, 0.050, 0.060, 0.020
    w, lam = lone.speed, r / l
    (cw,) = report.solution.counterweights
    assert cw.mr == pytest.approx((m_b + m_c) * r, rel=1e-9)  # the rotating and the whole reciprocating mass
    fy = report.after.shaking_force_on_frame[:, 1]
    c = np.fft.rfft(fy) / len(fy) * 2
    assert abs(c[1]) < 1e-9 * m_c * r * w**2  # the first order along the stroke vanishes
    second = m_c * r * w**2 * (lam + lam**3 / 4 + 15 * lam**5 / 128)
    assert abs(c[2]) == pytest.approx(second, rel=1e-4)  # = m_C r ω² λ to first order in λ
    assert abs(c[2]) == pytest.approx(m_c * r * w**2 * lam, rel=lam**2 / 3)
    before = mb.metrics(report.before)["shaking_force_on_frame_orders"]
    after = mb.metrics(report.after)["shaking_force_on_frame_orders"]
    assert after[1] == pytest.approx(before[1], rel=1e-9)  # counterweights do not touch the second order


def _bearing_rows(analysis):
    return np.concatenate([analysis.bearing("front").ravel(), analysis.bearing("rear").ravel()])


def test_method_3_rms_is_a_least_squares_solve(tmp_path):
    path = jb_with_planes(tmp_path)
    machine = load_machine(path)
    report = mb.balance(machine, "bearings", "rms")
    # independent: columns from machines re-read with a test mass (at α and α + 180°: the weight cancels), every 1°
    # (the balancing's documented step, finer than the model's 5°)
    phi = machine.shaft_angles(math.radians(1.0))
    base = _bearing_rows(machine.analyze(phi))
    cols = []
    for name, z in (("front", "-30 mm"), ("rear", "190 mm")):
        for angle in (0, 90):
            rows = []
            for a in (angle, angle + 180):
                mass = f'\n[[shaft.masses]]\nname = "t"\nmass = "10 g"\nradius = "10 mm"\nangle = "{a} deg"\nz = "{z}"\n'
                p = tmp_path / f"t_{name}_{a}.toml"
                p.write_text(path.read_text() + mass)
                rows.append(_bearing_rows(load_machine(p).analyze(phi)))
            cols.append((rows[0] - rows[1]) / 2 / 1e-4)  # per kg·m of m·r
    u, *_ = np.linalg.lstsq(np.column_stack(cols), -base, rcond=None)
    got = np.array([[c.mr * math.cos(c.angle), c.mr * math.sin(c.angle)] for c in report.solution.counterweights])
    np.testing.assert_allclose(got.ravel(), u, rtol=1e-5, atol=1e-9)
    assert report.as_dict()["after"]["bearing_rear_rms"] < report.as_dict()["before"]["bearing_rear_rms"]


def test_method_3_peak_optimum_beats_every_nearby_feasible_point(tmp_path):
    machine = load_machine(jb_with_planes(tmp_path, front="40 g", rear="40 g"))
    before = machine.analyze()
    planes = mb.planes_of(machine)
    model = mb.linear_model(before, planes)
    sol = mb.bearings(model, "peak")
    assert abs(sol.gap) < 1e-5 * sol.objective

    def peak(u):
        q = model.at(u)
        return max(np.hypot(*q["front"].T).max(), np.hypot(*q["rear"].T).max())

    u0 = np.array([[c.mr * math.cos(c.angle), c.mr * math.sin(c.angle)] for c in sol.counterweights]).ravel()
    assert peak(u0) == pytest.approx(sol.objective, rel=1e-5)  # the solve's tolerance, and the clip to the bounds
    rng = np.random.default_rng(7)
    for _ in range(400):
        u = u0 + rng.normal(scale=2e-5, size=u0.shape)
        u = u.reshape(-1, 2)
        for k, p in enumerate(planes):  # project back into the bounds
            n = np.hypot(*u[k])
            if n > p.max_mr:
                u[k] *= p.max_mr / n
        assert peak(u.ravel()) >= peak(u0) * (1 - 1e-5)


def test_the_cli_writes_a_model_that_analyses_to_the_reported_loads(tmp_path):
    path = jb_with_planes(tmp_path)
    res = subprocess.run([sys.executable, "-m", "sewgen", "balance", "machine", str(path), "--method", "bearings",
                          "--objective", "rms", "--out", str(tmp_path / "bal"), "--write-model",
                          str(tmp_path / "balanced.toml"), "--json", "--speeds", "600 rpm,1500 rpm"],
                         capture_output=True, text=True, cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    report = json.loads(res.stdout)
    assert set(report) >= {"method", "objective", "before", "after", "counterweights"}
    for k in ("bearing_front_peak", "bearing_rear_peak", "bearing_front_rms", "bearing_rear_rms",
              "shaking_force_on_frame_peak"):
        assert k in report["after"] and k in report["before"]
    assert [s["rpm"] for s in report["speeds"]] == pytest.approx([600, 1500])
    balanced = load_machine(tmp_path / "balanced.toml")
    analysed = balanced.analyze(balanced.shaft_angles(math.radians(0.05)))  # the peaks lie between 5° samples
    assert np.hypot(*analysed.bearing("front").T).max() == pytest.approx(report["after"]["bearing_front_peak"],
                                                                          rel=1e-4)
    assert np.hypot(*analysed.bearing("rear").T).max() == pytest.approx(report["after"]["bearing_rear_peak"],
                                                                         rel=1e-4)
    for name in ("balance.json", "bearings.csv", "speeds.csv", "balance.png"):
        assert (tmp_path / "bal" / name).stat().st_size > 200


def test_the_built_in_jb1_3_balances_by_every_method():
    machine = load_machine("jb1-3")
    assert [p.group for p in mb.planes_of(machine)] == ["needle_bar", "take_up", "hook_drive"]
    peak = (lambda m: max(m["bearing_front_peak"], m["bearing_rear_peak"]))  # noqa: E731
    for method in mb.METHODS:
        report = mb.balance(machine, method).as_dict()
        if method == "bearings":  # it minimises the larger bearing peak (and may shake more doing so)
            assert peak(report["after"]) < peak(report["before"]) - 1.0
        else:
            after, before = report["after"], report["before"]
            assert after["shaking_force_on_frame_peak"] < 0.8 * before["shaking_force_on_frame_peak"], method
        assert all(c["mass"] <= 0.060 + 1e-9 for c in report["counterweights"])


def _rms(v):
    return float(np.sqrt(np.mean(np.square(v))))


@pytest.mark.parametrize("method", mb.METHODS)
def test_the_reported_before_and_after_are_a_fine_re_analysis(method, tmp_path):
    """Every measure balancing reports, before and after, is the machine's own: a 0.1° analysis written here of
    the model and of the model file with the chosen counterweights gives it to 0.5 % (at the model's 5° the rear
    bearing's peak read 182 N for 190 N, and method 3's "improvement" was one of the samples only)."""
    machine = load_machine("jb1-3")
    report = mb.balance(machine, method)
    text = mb.model_text((MODELS_DIR / "jb1-3.toml").read_text(encoding="utf-8"), report.solution.counterweights)
    (tmp_path / "balanced.toml").write_text(text, encoding="utf-8")
    reported = report.as_dict()
    worst = {}
    for tag, m in (("before", machine), ("after", load_machine(tmp_path / "balanced.toml"))):
        a = m.analyze(m.shaft_angles(math.radians(0.1)))
        front, rear = np.hypot(*a.bearing("front").T), np.hypot(*a.bearing("rear").T)
        force = np.hypot(*a.shaking_force_on_frame.T)
        moments = a.shaking_moments_on_frame((0.0, 0.0, m.shaft.front))
        fine = {"bearing_front_peak": front.max(), "bearing_rear_peak": rear.max(), "bearing_front_rms": _rms(front),
                "bearing_rear_rms": _rms(rear), "shaking_force_on_frame_peak": force.max(),
                "shaking_force_on_frame_rms": _rms(force), "torque_peak": np.abs(a.torque).max(),
                "torque_rms": _rms(a.torque)}
        fine.update({f"shaking_moment_on_frame_{axis}_peak": np.abs(moments[:, k]).max()
                     for k, axis in enumerate("xyz")})
        for key, value in fine.items():
            assert reported[tag][key] == pytest.approx(value, rel=5e-3), (tag, key)
        worst[tag] = max(front.max(), rear.max())
    if method == "bearings":  # the larger bearing peak, which method 3 minimises, really falls
        assert worst["after"] < worst["before"] - 1.0


def test_bad_balancing_input_is_one_line_and_exit_2(tmp_path):
    no_planes = tmp_path / "no_planes.toml"
    no_planes.write_text(jb_text())
    res = subprocess.run([sys.executable, "-m", "sewgen", "balance", "machine", str(no_planes)],
                         capture_output=True, text=True)
    assert res.returncode == 2 and res.stdout == ""
    assert "no [[shaft.counterweights]] planes" in res.stderr and "Traceback" not in res.stderr
    path = jb_with_planes(tmp_path, front="1 g", rear="1 g")
    res = subprocess.run([sys.executable, "-m", "sewgen", "balance", "machine", str(path), "--method", "harmonic"],
                         capture_output=True, text=True)
    assert res.returncode == 2 and "needs more m·r than its planes allow" in res.stderr

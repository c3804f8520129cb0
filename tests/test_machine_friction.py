"""Coulomb friction in a whole machine: the catalog's joints and the upper shaft's bearings.

References written here: the bearing friction torque as the friction circle μ·r·(|R_A| + |R_B|) from the
bearing loads the analysis reports; the no-load torque against the mean friction power of the unloaded
machine over a turn (energy conservation: a periodic dE/dt averages to zero); the power balance with the
dissipation; the built-in model's commented friction values, uncommented, read and analysed.
"""
from __future__ import annotations

import json
import math
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest


from sewgen.machine.assembly import load_machine
from sewgen.machine.modelfile import ModelFileError, resolve
from sewgen.report.outputs import summary

pytestmark = [pytest.mark.c]

COMMENTED = re.compile(r'^# ("[\w.]+\.friction"|bearing_friction|journal_radius) = ', re.M)


@pytest.fixture(scope="module")
def model_with_friction(tmp_path_factory) -> Path:
    """The built-in JB1-3 model with its commented friction values switched on."""
    text = resolve("jb1-3").read_text(encoding="utf-8")
    on = COMMENTED.sub(r"\1 = ", text)
    assert len(COMMENTED.findall(text)) >= 20  # every group and the bearings
    path = tmp_path_factory.mktemp("friction") / "jb1-3-friction.toml"
    path.write_text(on, encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def ideal():
    return load_machine("jb1-3").analyze()


@pytest.fixture(scope="module")
def rough(model_with_friction):
    return load_machine(model_with_friction).analyze()


def test_friction_is_off_by_default(ideal):
    assert not np.any(ideal.friction_power)
    assert not np.any(ideal.bearing_friction)
    for fa in ideal.groups.values():
        assert fa.friction_joints  # declared in every catalog group ...
        for joint in fa.friction_joints:  # ... and zero
            assert not np.any(fa.friction(joint))
    s = summary(ideal)
    assert s["friction"]["on"] is False and s["friction"]["no_load_torque"]["value"] == 0.0


def test_power_balance_closes_with_friction(rough):
    assert rough.power_balance_residual < 1e-9
    assert np.all(rough.friction_power >= 0) and rough.friction_power.mean() > 1.0  # watts at 1000 rpm
    for fa in rough.groups.values():
        assert any(np.any(fa.friction(j)) for j in fa.friction_joints)


def test_bearing_friction_is_the_friction_circle(rough, model_with_friction):
    m = load_machine(model_with_friction)
    mu, r = m.shaft.friction, m.shaft.journal_radius
    assert (mu, r) == (0.04, 0.006)
    ra = np.hypot(*rough.bearing("front").T)
    rb = np.hypot(*rough.bearing("rear").T)
    np.testing.assert_allclose(rough.bearing_friction, mu * r * (ra + rb), rtol=1e-14)
    # the same machine with ideal bearings needs exactly that much less torque (the radial loads do not change)
    smooth = replace(m, shaft=replace(m.shaft, friction=0.0)).analyze()
    np.testing.assert_allclose(smooth.bearing("front"), rough.bearing("front"), rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(rough.torque - smooth.torque, mu * r * (ra + rb), rtol=1e-9, atol=1e-13)


def test_no_load_torque_is_the_mean_friction_power_over_the_speed(model_with_friction):
    m = load_machine(model_with_friction)
    # 1° samples at half degrees: the feed cam's arcs switch on whole degrees (at 300° the fork's acceleration
    # jumps, and a sample there takes either side by the last bit of its position: 4e-4 of this mean)
    phi = m.shaft_angles(math.radians(1.0)) + math.radians(0.5)
    a = m.analyze(phi)
    unloaded = replace(m, groups=[replace(g, loads=[]) for g in m.groups]).analyze(phi)
    # over a steady turn dE/dt averages to zero: mean drive power = mean dissipation. The sampled mean of dE/dt
    # is only second-order accurate here (friction turns with the sign of each joint's rate, the feed cam's
    # arcs switch with jumps in acceleration): these samples leave ~1e-6 of it
    expected = unloaded.friction_power.mean() / m.speed
    assert a.no_load_torque() == pytest.approx(expected, rel=3e-4)
    assert 0.02 < a.no_load_torque() < 0.5  # N*m: a household machine's no-load torque at 1000 rpm
    # with the loads on, the mean drive power pays the dissipation and the process loads' mean power
    assert np.mean(a.torque) * m.speed == pytest.approx(-np.mean(a.load_power), rel=3e-4)
    assert np.mean(a.torque) > a.no_load_torque()


def test_summary_reports_friction(rough, tmp_path):
    s = summary(rough)
    f = s["friction"]
    assert f["on"] is True and f["power"]["unit"] == "W" and f["no_load_torque"]["unit"] == "N*m"
    assert f["power"]["mean"] == pytest.approx(rough.friction_power.mean(), rel=1e-11)
    assert f["no_load_torque"]["value"] == pytest.approx(rough.no_load_torque(), rel=1e-11)
    assert f["no_load_torque"]["speed_rpm"] == pytest.approx(1000.0)
    json.dumps(s)


@pytest.mark.parametrize("keys, key", [
    ('bearing_friction = 0.04\n', "shaft.journal_radius"),
    ('bearing_friction = -0.1\njournal_radius = "6 mm"\n', "shaft.bearing_friction"),
])
def test_bearing_friction_errors_name_the_key(tmp_path, keys, key):
    text = resolve("jb1-3").read_text(encoding="utf-8")
    text = text.replace("[shaft]", "[shaft]\n" + keys, 1)
    path = tmp_path / "bad.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ModelFileError, match=re.escape(key)):
        load_machine(path)

"""Coulomb friction solved with the kinetostatics.

References written here: a massless crank-slider with friction only at its guide and a load on the slider,
solved by hand (the rod a two-force member: S = P / (e_x + μ·sign(P)·|e_y|·sign(v)), N = S·e_y, T = −B × S·e);
the dissipated power against the friction force times the sliding speed; with friction in the pins and masses,
the friction circle (moment = μ·r·|F|) and the power balance drive + loads (friction included) = dE/dt.
Coefficients outside [0, 1] refused where they are given; a slide that self-locks (μ·tan β > 1, β the rod's
angle to the guide, from the geometry) is a FrictionLockError, not a Newton failure.
"""
from __future__ import annotations

import numpy as np
import pytest

import sewgen
from sewgen.derive import DeclarationError
from sewgen.derive.model import Mechanism
from sewgen.engine.loads import Load

pytestmark = [pytest.mark.c, pytest.mark.derive]

R, L, P, MU, W = 0.012, 0.045, 30.0, 0.15, 50.0


def crank_slider(masses: bool):
    def declare():
        m = Mechanism("friction_slider" + ("_massive" if masses else ""), "a crank-slider with friction")
        mass = (lambda g, i: dict(mass=g, inertia=i)) if masses else (lambda g, i: {})  # noqa: E731
        crank = m.driven("crank", m.ground.at(0, 0), **mass("20 g", "1e-6 kg*m**2"))
        rod = m.link("rod", **mass("15 g", "3e-6 kg*m**2"))
        block = m.slider("block", m.ground.line(), guess="50 mm", **mass("40 g", "1e-6 kg*m**2"))
        b = m.revolute(crank.at("12 mm", 0), rod.at(0, 0), "B")
        c = m.revolute(rod.at("45 mm", 0), block.at(0, 0), "C")
        m.point("pin_c", block.at(0, 0))
        m.friction("block.guide", "0.15")
        if masses:
            m.friction(b, "0.1", "3 mm")
            m.friction(c, "0.1", "2 mm")
        return m
    return declare


def test_slider_friction_against_the_hand_solution(cache):
    mech = sewgen.load(crank_slider(False), cache_dir=cache)
    phi = np.radians(np.arange(2.5, 360, 5.0))  # no position at a dead centre (there the slider stops)
    fa = mech.kinetostatics(phi, speed=W, gravity=0, loads=[Load("pin_c", fx=P)])
    b = R * np.column_stack([np.cos(phi), np.sin(phi)])
    xc = R * np.cos(phi) + np.sqrt(L**2 - (R * np.sin(phi)) ** 2)
    c = np.column_stack([xc, np.zeros_like(xc)])
    e = (c - b) / L
    v = fa.motion.point("pin_c").vx
    s = P / (e[:, 0] + MU * np.sign(P) * np.abs(e[:, 1]) * np.sign(v))
    normal = s * e[:, 1]
    friction = -MU * np.abs(normal) * np.sign(v)
    torque = -(b[:, 0] * s * e[:, 1] - b[:, 1] * s * e[:, 0])
    np.testing.assert_allclose(fa.torque(), torque, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(fa._out("block.guide.friction"), friction, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(fa._out("block.guide.friction_power"), np.abs(friction * v), rtol=1e-10, atol=1e-12)
    assert np.all(fa._out("block.guide.friction_power") > 0)
    # without friction the same load needs less torque on average: friction only takes power
    free = mech.kinetostatics(phi, speed=W, gravity=0, loads=[Load("pin_c", fx=P)], params={"block.guide.friction": 0})
    assert np.mean(fa.input_power()) - np.mean(free.input_power()) == pytest.approx(
        np.mean(np.abs(friction * v)), rel=1e-9)


def test_pin_friction_circle_and_power_balance(cache):
    mech = sewgen.load(crank_slider(True), cache_dir=cache)
    phi = 2 * np.pi * np.arange(720) / 720 + 1e-3
    fa = mech.kinetostatics(phi, speed=W, loads=[Load("pin_c", fx=P)])
    for name, mu, radius in (("B", 0.1, 0.003), ("C", 0.1, 0.002)):
        r = fa.reaction(name)
        np.testing.assert_allclose(np.abs(fa._out(f"{name}.friction")), mu * radius * r.magnitude, rtol=1e-9)
    lost = sum(fa._out(f"{n}.friction_power") for n in ("B", "C", "block.guide"))
    assert lost.min() >= 0 and lost.max() > 0.05
    energy = fa.kinetic_energy + fa.potential_energy
    k = np.fft.rfftfreq(len(phi), d=1.0 / len(phi))
    rate = np.fft.irfft(1j * k * np.fft.rfft(energy), len(phi)) * W
    residual = fa.input_power() + fa.load_power - rate
    assert np.abs(residual).max() < 1e-8 * np.abs(fa.input_power()).max()


def test_friction_declarations_are_checked():
    m = Mechanism("bad_friction")
    crank = m.driven("crank", m.ground.at(0, 0))
    with pytest.raises(DeclarationError, match="friction: no joint 'X'"):
        m.friction("X", "0.1")
    for mu, words in (("-0.1", "at least 0"), ("5", "at most 1"), (-0.1, "at least 0"), (10, "at most 1")):
        with pytest.raises(DeclarationError, match=f"crank.pivot.friction.*{words}.*Coulomb friction coefficient"):
            m.friction("crank.pivot", mu, "4 mm")
    with pytest.raises(DeclarationError, match="pin_radius.*at least 0"):
        m.friction("crank.pivot", "0.1", "-4 mm")
    m = Mechanism("bad_friction")
    crank = m.driven("crank", m.ground.at(0, 0))
    m.friction("crank.pivot", "0.1", "4 mm")
    with pytest.raises(DeclarationError, match="declared twice"):
        m.friction("crank.pivot", "0.2", "4 mm")
    assert crank.name == "crank"


@pytest.mark.parametrize("params, words", [
    ({"block.guide.friction": -0.15}, "at least 0"),   # was accepted: the guide then drove the slider (−2.96 W)
    ({"block.guide.friction": 10.0}, "at most 1"),     # was 2.6e157 N·m or "Newton did not converge"
    ({"block.guide.friction": 1e6}, "at most 1"),
    ({"B.friction": -0.1}, "at least 0"),
    ({"B.pin_radius": -0.003}, "at least 0 m"),
])
def test_friction_coefficients_out_of_range_are_refused(cache, params, words):
    mech = sewgen.load(crank_slider(True), cache_dir=cache)
    name = next(iter(params))
    with pytest.raises(sewgen.ParameterError, match=words) as info:
        mech.kinetostatics(np.radians(np.arange(0, 360, 5.0)), speed=W, params=params)
    assert info.value.parameter == name and info.value.mechanism == mech.name


def test_a_self_locking_slide_is_a_friction_error(cache):
    """A massive slider driven by a massless rod at up to β = asin(r/l) to its guide: the friction the guide takes
    is μ|N| = μ tan β |S_x|, so the Coulomb balance iterated with the reactions grows by μ tan β a round. With
    r/l = 0.75 (tan β up to 1.13) μ = 1 locks it near β's largest; μ = 0.3 (gain ≤ 0.34) settles, and the friction
    is then the hand solution's of the massless case with the slider's inertia as its load."""
    r, l = 0.015, 0.020

    def declare():
        m = Mechanism("locking_slider", "a steep crank-slider, friction at its guide")
        crank = m.driven("crank", m.ground.at(0, 0))
        rod = m.link("rod")
        block = m.slider("block", m.ground.line(), guess="25 mm", mass="50 g")
        m.revolute(crank.at("15 mm", 0), rod.at(0, 0), "B")
        m.revolute(rod.at("20 mm", 0), block.at(0, 0), "C")
        m.point("pin_c", block.at(0, 0))
        m.friction("block.guide", "0.3")
        return m

    mech = sewgen.load(declare, cache_dir=cache)
    phi = np.radians(np.arange(2.5, 360, 5.0))
    assert 1.0 * np.tan(np.arcsin(r / l)) > 1.0 > 0.3 * np.tan(np.arcsin(r / l)) / 0.74
    with pytest.raises(sewgen.FrictionLockError) as info:
        mech.kinetostatics(phi, speed=W, gravity=0, params={"block.guide.friction": 1.0})
    assert not isinstance(info.value, sewgen.ConvergenceError) and "friction" in str(info.value)
    fa = mech.kinetostatics(phi, speed=W, gravity=0)
    b = r * np.column_stack([np.cos(phi), np.sin(phi)])
    xc = r * np.cos(phi) + np.sqrt(l**2 - (r * np.sin(phi)) ** 2)
    e = (np.column_stack([xc, np.zeros_like(xc)]) - b) / l
    v, a = fa.motion.point("pin_c").vx, fa.motion.point("pin_c").ax
    load = -0.050 * a  # the slider's inertia, its only load (d'Alembert)
    s = load / (e[:, 0] + 0.3 * np.sign(load) * np.abs(e[:, 1]) * np.sign(v))
    np.testing.assert_allclose(fa._out("block.guide.friction"), -0.3 * np.abs(s * e[:, 1]) * np.sign(v),
                               rtol=1e-9, atol=1e-12)

"""Coulomb friction solved with the kinetostatics.

References written here: a massless crank-slider with friction only at its guide and a load on the slider,
solved by hand (the rod a two-force member: S = P / (e_x + μ·sign(P)·|e_y|·sign(v)), N = S·e_y, T = −B × S·e);
the dissipated power against the friction force times the sliding speed; with friction in the pins and masses,
the friction circle (moment = μ·r·|F|) and the power balance drive + loads (friction included) = dE/dt.
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
    m.friction("crank.pivot", "0.1", "4 mm")
    with pytest.raises(DeclarationError, match="declared twice"):
        m.friction("crank.pivot", "0.2", "4 mm")
    assert crank.name == "crank"

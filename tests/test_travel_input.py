"""A held travel input (the relative travel of a prismatic as an input).

The mechanism: a crank whose radius is set by a block held at travel r along the crank's arm (an adjustable
eccentric, as a stitch regulator sets a feed stroke), a rod of length L to a piston on the vertical through
the shaft. Closed form written here: B = r (cos φ, sin φ), piston y = r sin φ + √(L² − r² cos² φ). Forces by
virtual work on the massless mechanism with a load F_y on the piston: shaft torque τ = −F_y ∂y/∂φ; the force
that holds the block at r (on it from the crank, along the arm) F_r = −F_y ∂y/∂r.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

import sewgen
from sewgen.derive.model import DeclarationError, Mechanism
from sewgen.errors import ParameterError
from sewgen.engine.loads import Load

pytestmark = [pytest.mark.c, pytest.mark.derive]

L = 0.04  # m
FY = -25.0  # N on the piston


def adjustable_crank() -> Mechanism:
    m = Mechanism("adjustable_crank", "a crank with its radius held by a block on its arm; rod; piston")
    length = m.length("rod", "40 mm", "rod")
    crank = m.driven("crank", pivot=m.ground.at(0, 0), doc="crank")
    block = m.held("radius", guide=crank.line(at=(0, 0), angle=0), default="10 mm",
                   doc="the block's travel along the crank arm: the crank radius", role="stitch_regulator")
    rod = m.link("rod", guess="80 deg")
    piston = m.slider("piston", guide=m.ground.line(at=(0, 0), angle=sp.pi / 2), guess="45 mm")
    m.revolute(block.at(0, 0), rod.at(0, 0), name="B")
    m.revolute(rod.at(length, 0), piston.at(0, 0), name="C")
    m.point("pin", piston.at(0, 0), "piston pin")
    m.point("eccentric", block.at(0, 0), "block centre B")
    return m


@pytest.fixture(scope="module")
def mech(cache):
    return sewgen.load(adjustable_crank(), cache_dir=cache)


def y_of(phi, r):
    return r * np.sin(phi) + np.sqrt(L**2 - (r * np.cos(phi)) ** 2)


PHI = np.radians(np.arange(0.0, 360.0, 7.5))


@pytest.mark.parametrize("r", [0.010, 0.014])
def test_positions_and_velocities_against_the_closed_form(mech, r):
    w = 50.0
    motion = mech.solve(PHI, speed=w, held={"radius": f"{r * 1e3} mm"})
    pin = motion.point("pin")
    np.testing.assert_allclose(pin.y, y_of(PHI, r), rtol=0, atol=1e-14)
    np.testing.assert_allclose(motion.point("eccentric").x, r * np.cos(PHI), atol=1e-15)
    dy = r * np.cos(PHI) + r * r * np.cos(PHI) * np.sin(PHI) / np.sqrt(L**2 - (r * np.cos(PHI)) ** 2)
    np.testing.assert_allclose(pin.vy, dy * w, rtol=1e-12, atol=1e-13)


def test_manifest_units(mech):
    inp = mech.description.input("radius")
    assert inp.unit == "m" and inp.quantity == "length" and inp.effort_unit == "N"
    assert inp.default == pytest.approx(0.010)
    assert mech.held_vector({"radius": "1.2 cm"}) == pytest.approx([0.012])
    with pytest.raises(ParameterError, match="radius"):
        mech.held_vector({"radius": "12 deg"})  # a travel, not an angle


def test_torque_and_holding_force_by_virtual_work(mech):
    r, h = 0.012, 1e-7
    fa = mech.kinetostatics(PHI, speed=0.0, gravity=0.0, loads=[Load("pin", fy=FY)], held={"radius": r})
    dy_dphi = r * np.cos(PHI) + r * r * np.cos(PHI) * np.sin(PHI) / np.sqrt(L**2 - (r * np.cos(PHI)) ** 2)
    dy_dr = (y_of(PHI, r + h) - y_of(PHI, r - h)) / (2 * h)
    np.testing.assert_allclose(fa.torque("shaft"), -FY * dy_dphi, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(fa.torque("radius"), -FY * dy_dr, rtol=1e-6, atol=1e-9)
    assert "radius.force [N]" in fa.table() and "radius.torque [N*m]" not in fa.table()
    np.testing.assert_array_equal(fa.input_power("radius"), 0.0)  # held: it does no work


def test_power_balance_with_masses(tmp_path):
    m = adjustable_crank()
    m.name = "adjustable_crank_massive"
    for body in m.bodies:
        if body.kind != "ground":
            body.mass, body.inertia = sp.Float(0.02), sp.Float(2e-6)
    mech = sewgen.load(m, cache_dir=tmp_path)
    phi = np.linspace(0, 2 * math.pi, 721)[:-1]
    w = 80.0
    fa = mech.kinetostatics(phi, speed=w, loads=[Load("pin", fy=FY)], held={"radius": "11 mm"})
    energy = fa.kinetic_energy + fa.potential_energy
    spectrum = np.fft.rfft(energy)
    k = np.fft.rfftfreq(len(phi), d=1.0 / len(phi))
    rate = np.fft.irfft(1j * k * spectrum, n=len(phi)) * w  # dE/dt = ω dE/dφ, spectrally
    residual = fa.input_power("shaft") + fa.load_power - rate
    assert np.abs(residual).max() < 1e-8 * np.abs(rate).max()


def test_declaration_errors():
    m = Mechanism("bad_held", "")
    crank = m.driven("crank", pivot=m.ground.at(0, 0))
    with pytest.raises(DeclarationError, match="either a pivot"):
        m.held("x", default="1 mm")
    with pytest.raises(DeclarationError, match="either a pivot"):
        m.held("x", pivot=m.ground.at(0, 0), guide=crank.line(at=(0, 0), angle=0), default="1 mm")
    with pytest.raises(Exception, match="x"):
        m.held("x", guide=crank.line(at=(0, 0), angle=0), default="10 deg")  # a travel needs a length


def test_batched_designs_read_a_travel_input_as_a_length(mech):
    """sweep_designs converts each held input by its own quantity, as solve() does: "14 mm" is a travel."""
    res = mech.sweep_designs(np.tile(mech.param_vector(), (2, 1)), PHI, 50.0, held={"radius": ["10 mm", "14 mm"]},
                             outputs=["points:pin"])
    assert res.ok.all()
    for k, r in enumerate((0.010, 0.014)):
        np.testing.assert_allclose(res.outputs["points.pin.y"][k], y_of(PHI, r), rtol=0, atol=1e-14)

"""Force elements inside the compiled kinetostatics: springs, dampers, torsion springs.

Independent references written here: a sprung and damped crank's driving torque by virtual work and its spring
and damper forces from the closed form of the length; a zero frame force on massless parts (what the frame puts
on the parts through the pivot and through the grounded spring cancels); a four-bar with masses, gravity and a
coupler-to-ground spring closing its power balance with the spring's energy (spectral derivative of the
energies); a torsion spring at a rocker's pivot against virtual work; a torsion spring on a crank pin that turns
right round, against k·Δ with Δ the continuous relative rotation written here (no jump at ±180°) and the drive by
virtual work; a spring whose ends meet; the machine-level power balance through a model file.
"""
from __future__ import annotations

import textwrap

import numpy as np
import pytest

import sewgen
from sewgen.derive import DeclarationError
from sewgen.errors import UnitError
from sewgen.derive.model import Mechanism
from sewgen.machine.assembly import load_machine

pytestmark = [pytest.mark.c, pytest.mark.derive]

MM = 1e-3
R, G = 20 * MM, np.array([60 * MM, 10 * MM])  # crank radius, spring anchor on the frame
K, L0, P0, C = 500.0, 30 * MM, 2.0, 3.0  # N/m, m, N, N·s/m
W = 50.0  # rad/s


def sprung_crank():
    m = Mechanism("sprung_crank", "a massless crank pulled towards a frame point by a spring and a damper")
    crank = m.driven("crank", m.ground.at(0, 0))
    m.spring(crank.at("20 mm", 0), m.ground.at("60 mm", "10 mm"), "500 N/m", "30 mm", "2 N", name="spring")
    m.damper(crank.at("20 mm", 0), m.ground.at("60 mm", "10 mm"), "3 N*s/m", name="damper")
    m.point("pin", crank.at("20 mm", 0))
    return m


FOUR_BAR = textwrap.dedent('''
    from sewgen.derive import Mechanism


    def declare():
        m = Mechanism("sprung_four_bar", "a crank-rocker with masses and a spring from the coupler to the frame")
        crank = m.driven("crank", m.ground.at(0, 0), mass="20 g", com=("4 mm", "0 mm"), inertia="1e-6 kg*m**2")
        coupler = m.link("coupler", guess="40 deg", mass="30 g", com=("20 mm", "5 mm"), inertia="5e-6 kg*m**2")
        rocker = m.link("rocker", guess="110 deg", mass="25 g", com=("15 mm", "0 mm"), inertia="3e-6 kg*m**2")
        m.revolute(crank.at("12 mm", 0), coupler.at(0, 0), "B")
        m.revolute(coupler.at("45 mm", 0), rocker.at("35 mm", 0), "C")
        d = m.revolute(m.ground.at("40 mm", "-10 mm"), rocker.at(0, 0), "D")
        m.spring(coupler.at("25 mm", "10 mm"), m.ground.at("10 mm", "50 mm"), "800 N/m", "35 mm", "1.5 N",
                 name="return_spring")
        m.torsion_spring(d, "0.05 N*m/rad", "100 deg", "0.01 N*m", name="rocker_spring")
        m.point("spring_end", coupler.at("25 mm", "10 mm"))
        return m
''')


@pytest.fixture(scope="module")
def crank(cache):
    return sewgen.load(sprung_crank, cache_dir=cache)


@pytest.fixture(scope="module")
def four_bar(cache, tmp_path_factory):
    folder = tmp_path_factory.mktemp("four_bar")
    (folder / "sprung_four_bar.py").write_text(FOUR_BAR)
    return sewgen.load(folder / "sprung_four_bar.py", cache_dir=cache), folder


def test_spring_and_damper_forces_and_the_driving_torque_by_virtual_work(crank):
    phi = np.radians(np.arange(0, 360, 5.0))
    fa = crank.kinetostatics(phi, speed=W, gravity=0)
    p = R * np.column_stack([np.cos(phi), np.sin(phi)])
    v = R * W * np.column_stack([-np.sin(phi), np.cos(phi)])
    d = p - G
    length = np.hypot(d[:, 0], d[:, 1])
    rate = np.sum(d * v, axis=1) / length
    spring = P0 + K * (length - L0)
    damper = C * rate
    s, dm = fa.element("spring"), fa.element("damper")
    np.testing.assert_allclose(s["length"], length, rtol=1e-13)
    np.testing.assert_allclose(s["force"], spring, rtol=1e-12)
    np.testing.assert_allclose(s["energy"], P0 * (length - L0) + K * (length - L0) ** 2 / 2, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(dm["force"], damper, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(dm["rate"], rate, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(dm["power"], C * rate**2, rtol=1e-12, atol=1e-15)
    # a massless crank: the drive's power goes into the spring and the damper, T ω = (F_s + F_d) dL/dt
    np.testing.assert_allclose(fa.torque(), (spring + damper) * rate / W, rtol=1e-11, atol=1e-13)
    np.testing.assert_allclose(fa.load_power, -C * rate**2, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(fa.elastic_power, spring * rate, rtol=1e-12, atol=1e-14)
    # massless parts, no gravity: the frame's pivot force and its spring-and-damper pull cancel
    assert np.abs(fa.frame_force_on_parts).max() < 1e-12
    assert np.abs(fa.frame_moment_on_parts).max() < 1e-14
    # the pivot carries what the elements pull: on the crank from the frame = −(F_s + F_d)·(G − P)/L
    e = -d / length[:, None]
    piv = fa.reaction("crank.pivot")
    np.testing.assert_allclose(piv.fx, -(spring + damper) * e[:, 0], rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(piv.fy, -(spring + damper) * e[:, 1], rtol=1e-11, atol=1e-12)
    assert {"spring.force [N]", "damper.power [W]"} <= set(fa.table())


def _spectral_rate(values, speed):
    """d/dt of a periodic sample over one revolution at constant speed, by the FFT (exact for smooth curves)."""
    n = len(values)
    k = np.fft.rfftfreq(n, d=1.0 / n)
    return np.fft.irfft(1j * k * np.fft.rfft(values), n) * speed


def test_the_power_balance_closes_with_the_springs_energy(four_bar):
    mech, _ = four_bar
    phi = 2 * np.pi * np.arange(720) / 720
    fa = mech.kinetostatics(phi, speed=W)
    energy = fa.kinetic_energy + fa.potential_energy
    residual = fa.input_power("shaft") + fa.load_power - _spectral_rate(energy, W)
    assert np.abs(residual).max() < 1e-8 * np.abs(fa.input_power("shaft")).max()
    # the springs' part of the potential energy changes at the rate elastic_power says
    stored = fa.element("return_spring")["energy"] + fa.element("rocker_spring")["energy"]
    np.testing.assert_allclose(_spectral_rate(stored, W), fa.elastic_power,
                               atol=1e-8 * np.abs(fa.elastic_power).max())


def test_torsion_spring_against_virtual_work(four_bar):
    mech, _ = four_bar
    phi = np.radians(np.arange(0, 360, 10.0))
    massless = {f"{b}.{p}": 0.0 for b in ("crank", "coupler", "rocker") for p in ("mass", "inertia")}
    massless.update({"return_spring.stiffness": 0.0, "return_spring.preload": 0.0})
    fa = mech.kinetostatics(phi, speed=W, gravity=0, params=massless)
    rocker = fa.motion.body("rocker")
    deflection = np.angle(np.exp(1j * (rocker.angle - np.radians(100))))  # in (−π, π]
    torque = 0.01 + 0.05 * deflection
    ts = fa.element("rocker_spring")
    np.testing.assert_allclose(ts["deflection"], deflection, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(ts["torque"], torque, rtol=1e-12)
    # the spring acts on the rocker (the joint's body b) as −T: the drive supplies T·ω_rocker
    np.testing.assert_allclose(fa.torque(), torque * rocker.omega / W, rtol=1e-10, atol=1e-14)


def wound_crank_slider():
    m = Mechanism("wound_crank_slider", "a massless crank-slider with a torsion spring on its crank pin")
    crank = m.driven("crank", m.ground.at(0, 0))
    rod = m.link("rod")
    bar = m.slider("bar", m.ground.line(at=(0, 0), angle=0), guess="50 mm")
    pin = m.revolute(crank.at("12 mm", 0), rod.at(0, 0), "B")
    m.revolute(rod.at("40 mm", 0), bar.at(0, 0), "C")
    m.torsion_spring(pin, "0.05 N*m/rad", "20 deg", "0.01 N*m", name="pin_spring")
    return m


def test_torsion_spring_on_a_turning_pin_winds_continuously(cache):
    """The pin B turns right round relative to the crank: the spring's deflection is the continuous relative
    rotation Δ = θ_rod − φ − θ0 (θ_rod within ±asin(r/l) of 0 here), so at adjacent degrees through ±180° its
    torque and the driving torque change by a little, and over two turns it winds two turns. Massless parts: the
    drive supplies the spring's power, T_drive ω = T (ω_rod − ω)."""
    mech = sewgen.load(wound_crank_slider, cache_dir=cache)
    for deg in (np.arange(170.0, 191.0, 1.0), np.arange(0.0, 720.0, 5.0)):
        phi = np.radians(deg)
        fa = mech.kinetostatics(phi, speed=W, gravity=0)
        rod = fa.motion.body("rod")
        assert np.abs(rod.angle).max() < np.arcsin(12 / 40) + 1e-12
        deflection = rod.angle - phi - np.radians(20)
        torque = 0.01 + 0.05 * deflection
        ts = fa.element("pin_spring")
        np.testing.assert_allclose(ts["deflection"], deflection, rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(ts["torque"], torque, rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(fa.torque(), torque * (rod.omega - W) / W, rtol=1e-10, atol=1e-14)
    assert np.abs(np.diff(ts["torque"])).max() < 0.05 * 0.2  # 5° steps turn B by < 0.2 rad: no jump of k·2π
    assert ts["deflection"][-1] < -4 * np.pi + 0.5  # two turns wound


def test_spring_whose_ends_meet(cache):
    """A spring from the crank pin to the frame point the pin passes at 0°: where its tension at zero length,
    preload − k·L0, is zero its force is k·d there (a zero-length spring; none at all with zero stiffness), so
    every result is finite and the massless drive supplies its power, T ω = k d·v."""
    def declare():
        m = Mechanism("meeting_spring", "a massless crank with a spring from its pin to a point on the pin's path")
        crank = m.driven("crank", m.ground.at(0, 0))
        m.spring(crank.at("20 mm", 0), m.ground.at("20 mm", 0), "0 N/m", "0 mm", name="s")
        return m

    mech = sewgen.load(declare, cache_dir=cache)
    phi = np.radians(np.arange(0, 360, 5.0))
    for k in (0.0, 500.0):
        fa = mech.kinetostatics(phi, speed=W, gravity=0, params={"s.stiffness": k})
        d = R * np.column_stack([1 - np.cos(phi), -np.sin(phi)])  # from the pin to the frame point
        v = R * W * np.column_stack([-np.sin(phi), np.cos(phi)])  # the pin's velocity
        np.testing.assert_allclose(fa.element("s")["force"], k * np.hypot(d[:, 0], d[:, 1]), atol=1e-12)
        np.testing.assert_allclose(fa.torque(), -k * np.sum(d * v, axis=1) / W, atol=1e-12)


def test_a_machine_with_springs_closes_its_power_balance(four_bar):
    _, folder = four_bar
    (folder / "sprung.toml").write_text(textwrap.dedent('''
        [machine]
        name = "sprung"
        speed = "600 rpm"
        step = "5 deg"

        [shaft]
        front_bearing = "0 mm"
        rear_bearing = "150 mm"
        mass = "100 g"
        mass_z = "75 mm"
        inertia = "1e-5 kg*m**2"

        [groups.drive]
        mechanism = "sprung_four_bar.py"
        phase = "0 deg"
        axial = { crank = "-20 mm" }
    '''))
    analysis = load_machine(folder / "sprung.toml").analyze()
    assert analysis.power_balance_residual < 1e-9
    assert np.abs(analysis.groups["drive"].elastic_power).max() > 0.01  # the springs matter here


def test_element_declarations_are_checked():
    m = Mechanism("bad_elements")
    crank = m.driven("crank", m.ground.at(0, 0))
    with pytest.raises(DeclarationError, match="spring 's' joins 'crank' to itself"):
        m.spring(crank.at(0, 0), crank.at(1, 0), "1 N/m", "1 mm", name="s")
    with pytest.raises(DeclarationError, match="torsion spring 't' needs a revolute joint"):
        m.torsion_spring(m.ground.line(), "1 N*m/rad", name="t")
    with pytest.raises(UnitError, match=r"wrong_unit\.stiffness: .1 N. is not a stiffness"):
        m.spring(crank.at(0, 0), m.ground.at(0, 0), "1 N", "1 mm", name="wrong_unit")
    # values no spring or damper has (each was accepted: a negative damper drives the mechanism)
    with pytest.raises(DeclarationError, match=r"d1\.coefficient.* at least 0"):
        m.damper(crank.at(0, 0), m.ground.at(0, 0), "-3 N*s/m", name="d1")
    with pytest.raises(DeclarationError, match=r"s1\.free_length.* at least 0"):
        m.spring(crank.at(0, 0), m.ground.at(0, 0), "1 N/m", "-1 mm", name="s1")
    with pytest.raises(DeclarationError, match=r"s2\.stiffness.* at least 0"):
        m.spring(crank.at(0, 0), m.ground.at(0, 0), -5.0, "1 mm", name="s2")


@pytest.mark.parametrize("params, words", [({"damper.coefficient": -3.0}, "at least 0 N*s/m"),
                                           ({"spring.free_length": -0.01}, "at least 0 m"),
                                           ({"spring.stiffness": -500.0}, "at least 0 N/m")])
def test_element_values_out_of_range_are_refused(crank, params, words):
    """A negative damper coefficient made the damper a motor (positive load power); a negative free length is no
    spring's. Each is refused naming the parameter, as params= gives it."""
    with pytest.raises(sewgen.ParameterError, match=words.replace("*", r"\*")) as info:
        crank.kinetostatics(np.radians(np.arange(0, 360, 5.0)), speed=W, params=params)
    assert info.value.parameter == next(iter(params))

"""The spatial crank–rocker (RSSR) of seed 003: a crank on an axis in space drives, through a
rod with ball joints at both ends, a rocker pinned in the mechanism's plane.

Independent references written here: the rocker angle by seed 003 eq. 1,

    cos φ3 = (f r_x − δ1 r_y √(r_x² + r_y² − f²)) / (r_x² + r_y²),

with r = (B − D) projected on the plane and f = (|B − D|² + ρ² − L²)/(2ρ) (ρ the rocker's arm, L the rod), for
perpendicular and skew axes (δ1 = +1 puts C left of the line from D to B's projection: the declaration's
branch +1); velocities and accelerations against central differences of that closed form; the rod tension and
the driving torque against a Newton–Euler solve of the rocker and the crank written here, and the power balance.
A crank whose centre of mass is off its axis: the power balance with energies written here (the centre of mass
turning with the crank in the plane it turns in), and a lone eccentric on the x axis against its rotating force
m e ω² and the weight's moment m g e cos ψ (Newton–Euler about a fixed axis).
"""
from __future__ import annotations

import numpy as np
import pytest

import sewgen
from sewgen.derive import DeclarationError
from sewgen.derive.model import Mechanism

pytestmark = [pytest.mark.c, pytest.mark.derive]

MM = 1e-3
A = np.array([50, 20, -30]) * MM  # crank axis point
R, RHO, L = 8 * MM, 30 * MM, 60 * MM  # crank radius, rocker arm, rod
W = 60.0  # rad/s
I1, M3, I3, COM3 = 2e-6, 0.025, 4e-6, 12 * MM  # crank inertia about its axis; rocker mass, inertia at G, G on DC


def declaration(direction, branch):
    def declare():
        name = "rssr_" + ("skew" if direction[1] else "square") + ("_up" if branch > 0 else "_down")
        m = Mechanism(name, "a spatial crank-rocker (seed 003's needle-drive four-bar ABCD)")
        crank = m.spatial_crank("crank", ("50 mm", "20 mm", "-30 mm"), direction, inertia=f"{I1} kg*m**2")
        rocker = m.link("rocker", guess="60 deg" if branch > 0 else "-60 deg", mass=f"{M3} kg",
                        com=(f"{COM3} m", 0), inertia=f"{I3} kg*m**2")
        m.revolute(m.ground.at(0, 0), rocker.at(0, 0), "D")
        m.rod(crank.pin("8 mm"), rocker.at("30 mm", 0), "60 mm", "rod", branch=branch)
        m.point("C", rocker.at("30 mm", 0))
        return m
    return declare


def axis_frame(direction):
    a = np.asarray(direction, float) / np.linalg.norm(direction)
    ref = np.array([0.0, 0.0, 1.0]) if abs(a[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    e1 = ref - ref.dot(a) * a
    e1 /= np.linalg.norm(e1)
    return a, e1, np.cross(a, e1)


def crank_pin(phi, direction):
    _, e1, e2 = axis_frame(direction)
    return A + R * (np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2)


def rocker_angle(phi, direction, delta1):
    """Seed 003 eq. 1 (D at the origin): the rocker's arm angle φ3."""
    b = crank_pin(phi, direction)
    rx, ry = b[:, 0], b[:, 1]
    f = (np.sum(b**2, axis=1) + RHO**2 - L**2) / (2 * RHO)
    root = np.sqrt(rx**2 + ry**2 - f**2)
    cos3 = (f * rx - delta1 * ry * root) / (rx**2 + ry**2)
    sin3 = (f * ry + delta1 * rx * root) / (rx**2 + ry**2)
    return np.arctan2(sin3, cos3)


CASES = [((1, 0, 0), 1), ((1, 0, 0), -1), ((1, 0.3, 0.4), 1)]


@pytest.mark.parametrize("direction, branch", CASES)
def test_rocker_follows_seed_003_eq_1(cache, direction, branch):
    mech = sewgen.load(declaration(direction, branch), cache_dir=cache)
    assert mech.description.closed_form
    phi = np.radians(np.arange(0, 360, 5.0))
    motion = mech.solve(phi, speed=W)
    ref = rocker_angle(phi, direction, branch)
    got = motion.body("rocker").angle
    np.testing.assert_allclose(np.cos(got), np.cos(ref), atol=1e-13)
    np.testing.assert_allclose(np.sin(got), np.sin(ref), atol=1e-13)
    # velocity and acceleration against central differences of eq. 1 (h = 1e-4 rad: errors ~ h² ~ 1e-8)
    h = 1e-4
    step = lambda d: np.unwrap(rocker_angle(phi + d, direction, branch) - ref) + ref  # noqa: E731
    d1 = (step(h) - step(-h)) / (2 * h)
    d2 = (step(h) - 2 * ref + step(-h)) / h**2
    rocker = motion.body("rocker")
    np.testing.assert_allclose(rocker.omega, W * d1, atol=1e-6 * W * np.abs(d1).max())
    np.testing.assert_allclose(rocker.alpha, W**2 * d2, atol=1e-5 * W**2 * np.abs(d2).max())
    # the rod keeps its length in space
    c = np.column_stack([motion.point("C").x, motion.point("C").y, np.zeros(len(phi))])
    np.testing.assert_allclose(np.linalg.norm(c - crank_pin(phi, direction), axis=1), L, rtol=1e-13)


@pytest.mark.parametrize("direction, branch", CASES)
def test_rod_force_and_torque_by_newton_euler(cache, direction, branch):
    mech = sewgen.load(declaration(direction, branch), cache_dir=cache)
    phi = np.radians(np.arange(0, 360, 5.0))
    g = 9.80665
    fa = mech.kinetostatics(phi, speed=W)
    rocker = fa.motion.body("rocker")
    psi, w3, a3 = rocker.angle, rocker.omega, rocker.alpha
    b = crank_pin(phi, direction)
    c = RHO * np.column_stack([np.cos(psi), np.sin(psi), np.zeros(len(phi))])
    e = (c - b) / L
    # rocker about D: (I3 + M3 COM3²) α3 = −M3 g COM3 cos ψ + (C × (−N e))_z  →  N
    lever = c[:, 0] * e[:, 1] - c[:, 1] * e[:, 0]
    tension = -((I3 + M3 * COM3**2) * a3 + M3 * g * COM3 * np.cos(psi)) / lever
    np.testing.assert_allclose(fa.frc[:, fa.mechanism.description.reaction("rod").offset], tension,
                               rtol=1e-9, atol=1e-9 * np.abs(tension).max())
    # crank about its axis at constant speed: T + ((B − A) × N e)·a = I1·0
    a, _, _ = axis_frame(direction)
    torque = -np.einsum("ij,j->i", np.cross(b - A, tension[:, None] * e), a)
    np.testing.assert_allclose(fa.torque("shaft"), torque, rtol=1e-9, atol=1e-9 * np.abs(torque).max())
    force_c = fa.reaction("rod")
    np.testing.assert_allclose(force_c.fx, -tension * e[:, 0], atol=1e-9 * np.abs(tension).max())
    # the power balance: T ω = d(E_kin + E_pot)/dt (spectral derivative over the revolution)
    phi = 2 * np.pi * np.arange(720) / 720
    fa = mech.kinetostatics(phi, speed=W)
    energy = fa.kinetic_energy + fa.potential_energy
    k = np.fft.rfftfreq(len(phi), d=1.0 / len(phi))
    rate = np.fft.irfft(1j * k * np.fft.rfft(energy), len(phi)) * W
    assert np.abs(fa.input_power("shaft") - rate).max() < 1e-8 * np.abs(rate).max()


def test_spatial_crank_declarations_are_checked():
    m = Mechanism("bad_rssr")
    crank = m.spatial_crank("crank", ("0 mm", "0 mm", "10 mm"), (1, 0, 0))
    rocker = m.link("rocker")
    with pytest.raises(DeclarationError, match="turns about an axis in space: its points are crank.pin"):
        crank.at(0, 0)
    with pytest.raises(DeclarationError, match="rocker' is a planar body"):
        rocker.pin("1 mm")
    with pytest.raises(DeclarationError, match="rod 'r' needs a spatial crank's pin"):
        m.rod(rocker.at(0, 0), rocker.at(1, 0), "10 mm", "r")
    with pytest.raises(DeclarationError, match="reference of 'c2' is along its axis"):
        m.spatial_crank("c2", (0, 0, 0), (0, 0, 1), reference=(0, 0, 2))


M1 = 0.030  # kg, the crank's mass where it has one
OFF = {"crank.com_u": 3 * MM, "crank.com_v": -2 * MM}  # its centre of mass off the axis, in its plane


def massive_crank(direction):
    def declare():
        m = Mechanism("rssr_massive", "a spatial crank-rocker whose crank has a mass (its centre of mass a parameter)")
        crank = m.spatial_crank("crank", ("50 mm", "20 mm", "-30 mm"), direction, mass=f"{M1} kg",
                                inertia=f"{I1} kg*m**2")
        rocker = m.link("rocker", guess="60 deg", mass=f"{M3} kg", com=(f"{COM3} m", 0), inertia=f"{I3} kg*m**2")
        m.revolute(m.ground.at(0, 0), rocker.at(0, 0), "D")
        m.rod(crank.pin("8 mm"), rocker.at("30 mm", 0), "60 mm", "rod")
        return m
    return declare


def test_crank_off_its_axis_closes_the_power_balance(cache):
    """T ω = d(E_kin + E_pot)/dt with the energies written here: the crank's centre of mass G at (u, v) in the
    plane it turns in (u along the crank, v a quarter turn ahead about the axis), E_kin = ½ (I + m |G − A|²) ω²,
    E_pot = −m g·G; the rocker's from its kinematics. Accelerating shaft, gravity on."""
    direction = (1, 0.3, 0.4)
    mech = sewgen.load(massive_crank(direction), cache_dir=cache)
    n = 720
    phi = 2 * np.pi * np.arange(n) / n
    w = W * (1 + 0.2 * np.sin(phi))
    alpha = w * W * 0.2 * np.cos(phi)  # ω dω/dφ: consistent with w(φ)
    g = np.array([0.0, -9.80665])
    fa = mech.kinetostatics(phi, speed=w, accel=alpha, params=OFF)
    _, e1, e2 = axis_frame(direction)
    u, v = OFF["crank.com_u"], OFF["crank.com_v"]
    c, s = np.cos(phi)[:, None], np.sin(phi)[:, None]
    centre = A + u * (c * e1 + s * e2) + v * (-s * e1 + c * e2)
    kinetic = 0.5 * (I1 + M1 * (u * u + v * v)) * w**2
    potential = -M1 * (centre[:, :2] @ g)
    rocker = fa.motion.body("rocker")
    kinetic = kinetic + 0.5 * M3 * (rocker.com.vx**2 + rocker.com.vy**2) + 0.5 * I3 * rocker.omega**2
    potential = potential - M3 * (g[0] * rocker.com.x + g[1] * rocker.com.y)
    np.testing.assert_allclose(fa.kinetic_energy, kinetic, rtol=1e-12)
    np.testing.assert_allclose(fa.potential_energy, potential, rtol=1e-12, atol=1e-15)
    # d/dt = ω d/dφ, the φ-derivative spectral (every term is periodic in φ)
    k = np.fft.rfftfreq(n, d=1.0 / n)
    rate = w * np.fft.irfft(1j * k * np.fft.rfft(kinetic + potential), n)
    power = fa.input_power("shaft")
    assert np.abs(power - rate).max() < 1e-9 * np.abs(power).max()


@pytest.mark.parametrize("accel, gravity", [(0.0, 0.0), (0.0, 9.80665), (400.0, 9.80665)])
def test_lone_eccentric_on_the_x_axis(cache, accel, gravity):
    """A lone eccentric of mass m, its centre of mass at e = |(u, v)| from the x axis, turning about x: written
    here by Newton–Euler about a fixed axis. Its centre is r = R_x(ψ)·(0, 0, e) from the axis (the crank's angle
    zero points along +z, the default reference; ψ = φ + atan2(v, u)); a_G = α x × r + ω x × (x × r) (at constant
    speed the rotating force m e ω²); the frame's force on it in the plane m (a_G − g); the torque about x
    (I + m e²) α − m ((r × g)·x) = (I + m e²) α − m g e cos ψ for g = −g y."""
    m, inertia, u, v = 0.04, 3e-6, 4 * MM, 3 * MM

    def declare():
        mech = Mechanism("lone_eccentric", "an eccentric alone on a shaft along x")
        mech.spatial_crank("crank", ("0 mm", "0 mm", "0 mm"), (1, 0, 0), mass=f"{m} kg", inertia=f"{inertia} kg*m**2")
        return mech

    mech = sewgen.load(declare, cache_dir=cache)
    phi = np.radians(np.arange(0, 360, 1.0))
    fa = mech.kinetostatics(phi, speed=W, accel=accel, gravity=gravity, params={"crank.com_u": u, "crank.com_v": v})
    e = np.hypot(u, v)
    psi = phi + np.arctan2(v, u)
    r = e * np.column_stack([np.zeros(len(phi)), -np.sin(psi), np.cos(psi)])  # R_x(ψ) (0, 0, e)
    x = np.array([1.0, 0.0, 0.0])
    acc = accel * np.cross(x, r) + W**2 * np.cross(x, np.cross(x, r))
    g = np.array([0.0, -gravity, 0.0])
    force = m * (acc - g)
    torque = (inertia + m * e * e) * accel - m * np.cross(r, g)[:, 0]
    if accel == 0.0:
        np.testing.assert_allclose(np.hypot(acc[:, 1], acc[:, 2]), e * W**2, rtol=1e-12)  # m e ω², rotating
        np.testing.assert_allclose(torque, -m * gravity * e * np.cos(psi), atol=1e-15)
    scale = m * e * W**2 + m * gravity
    np.testing.assert_allclose(fa.frame_force_on_parts[:, 0], force[:, 0], atol=1e-12 * scale)
    np.testing.assert_allclose(fa.frame_force_on_parts[:, 1], force[:, 1], atol=1e-12 * scale)
    np.testing.assert_allclose(fa.torque(), torque, atol=1e-12 * (scale * e + inertia * abs(accel)))
    com = fa.motion.body("crank").com
    np.testing.assert_allclose(np.column_stack([com.y, com.z]), r[:, 1:], atol=1e-15)
    np.testing.assert_allclose(np.column_stack([com.ay, com.az]), acc[:, 1:], atol=1e-12 * e * W**2)

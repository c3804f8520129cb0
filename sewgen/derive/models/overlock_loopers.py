"""51-A class overlock: the looper mechanism механизм петлителей (seed 003 fig. 3, eqs. 1, 4–6).

An eccentric on the main shaft 1 drives, through a ball-jointed rod, the looper rock shaft 3 (a spatial-planar
four-bar ABCD, φ₃ by eq. 1); rock shaft 3 carries the upper looper, whose tip N₂ is at l₇ from D at the
constructive angle γ (eq. 4), and drives through the planar four-bar DEFG the lever 5 of the lower looper, whose
tip N₁ is at l₆ from G at the angle η (eq. 5); G lies at L from D in the direction β (eq. 6).

Frame (the loopers' plane): origin on the rock-shaft axis D, x along the main shaft, y up; the main shaft's axis
runs parallel to x below D. Angles counter-clockwise from +x. Seed 003 writes eqs. 4–6 in its own axes (see
tests/test_overlock_loopers.py for the mapping).

Every dimension is an estimate (seed 003 prints none): the rock shaft swings about ±22°, the upper looper's tip
through about 45 mm of arc, the lower looper's lever about ±35°; masses of small steel levers and loopers.
"""
import sympy as sp

from sewgen.derive.model import Mechanism


def declare(planar: bool = False) -> Mechanism:
    """The mechanism; ``planar=True``: its planar equivalent (``overlock_loopers_planar``: the spatial four-bar's crank
    turned into the plane, as seed 003 computes it; Mechanism.spatial_crank)."""
    m = Mechanism("overlock_loopers_planar" if planar else "overlock_loopers", __doc__, default_speed="3500 rpm")
    r = m.length("eccentric", "6 mm", "eccentricity AB of the looper eccentric (estimate)")
    h_a = m.length("shaft_below", "45 mm", "main-shaft axis below the rock shaft D (estimate)")
    rod = m.length("rod", "45 mm", "ball-jointed rod BC (estimate)")
    l3 = m.length("arm", "16 mm", "rock-shaft arm DC, l₃ (estimate)")
    l7 = m.length("upper_looper", "60 mm", "upper looper DN₂, l₇ (estimate)")
    gamma = m.angle("upper_looper_angle", "100 deg", "its constructive angle γ from the arm DC (estimate)")
    de = m.length("drive_arm", "20 mm", "arm DE of the planar four-bar DEFG (estimate)")
    de_angle = m.angle("drive_arm_angle", "180 deg", "arm DE from the arm DC (estimate)")
    ef = m.length("coupler", "40 mm", "coupler EF (estimate)")
    gf = m.length("lever", "22 mm", "lower-looper lever GF (estimate)")
    big_l = m.length("pivot_distance", "45 mm", "DG, L (estimate)")
    beta = m.angle("pivot_direction", "140 deg", "direction of G from D, β (estimate)")
    l6 = m.length("lower_looper", "55 mm", "lower looper GN₁, l₆ (estimate)")
    eta = m.angle("lower_looper_angle", "-60 deg", "its constructive angle η from the lever GF (estimate)")

    crank = m.spatial_crank("eccentric", (l3, -h_a, 0), (1, 0, 0), doc="looper eccentric on the main shaft 1",
                            inertia="1.5e-6 kg*m**2", mass="25 g", planar=planar)
    rock = m.link("rock_shaft", doc="looper rock shaft 3 with the arm DC, the arm DE and the upper looper",
                  guess="0 deg", mass="45 g", com=("10 mm", "15 mm"), inertia="2.5e-5 kg*m**2")
    coupler = m.link("coupler", doc="coupler EF", guess="90 deg", mass="6 g", com=(ef / 2, 0),
                     inertia="8e-7 kg*m**2")
    lever = m.link("lower_lever", doc="lower-looper lever 5 with the lower looper", guess="0 deg",
                   mass="30 g", com=("15 mm", "0 mm"), inertia="1.2e-5 kg*m**2")
    m.revolute(m.ground.at(0, 0), rock.at(0, 0), "D")
    m.rod(crank.pin(r), rock.at(l3, 0), rod, "rod", branch=1)
    m.revolute(rock.at(de * sp.cos(de_angle), de * sp.sin(de_angle)), coupler.at(0, 0), "E")
    m.revolute(m.ground.at(big_l * sp.cos(beta), big_l * sp.sin(beta)), lever.at(0, 0), "G")
    m.revolute(coupler.at(ef, 0), lever.at(gf, 0), "F", branch=1)
    m.point("upper_looper_tip", rock.at(l7 * sp.cos(gamma), l7 * sp.sin(gamma)), "upper looper tip N₂",
            role="upper_looper_tip")
    m.point("lower_looper_tip", lever.at(l6 * sp.cos(eta), l6 * sp.sin(eta)), "lower looper tip N₁",
            role="lower_looper_tip")
    return m

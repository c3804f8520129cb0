"""51-A class overlock: the needle mechanism механизм иглы (seed 003 fig. 1–2, eqs. 1–2).

A spatial-planar four-bar: the main shaft 1 (below the bed, along the machine's x) carries an eccentric whose
pin B drives, through a rod with a ball joint at each end, the needle-lever rock shaft 3 (axis across the main
shaft, through D); its arm l₄ drives the needle bar through the link l₅ (the needle bar's axis at the offset a
from D). Seed 003 eq. (1) gives the rock shaft's angle φ₃ in closed form (δ₁ the assembly sign), eq. (2) the
needle stroke as a second-order expansion in the link's obliquity — here both are exact.

Frame (the needle lever's plane): origin on the rock-shaft axis D, x along the main shaft, y up, z along the rock
shaft. The main shaft's axis runs parallel to x through (l₃, −h_A, 0): the rod is nearly vertical and the lever
arm DC horizontal in mid stroke, so B's up-and-down throw rocks the shaft by about ±asin(r/l₃). The arm DC and
the needle lever DL are one bent lever (DL at ``lever_angle`` from DC). Crank angle zero points the eccentric
along +z (the mechanism's normal): φ = 90° puts B at its lowest, the needle at its highest (sign of the lever).

Every dimension is an estimate (seed 003 prints none; DOMAIN-NOTES: 51-A class, 3000–4000 r/min): a needle
stroke of about 25 mm, the rock shaft swinging about ±27°, masses of a small cast lever and a light needle bar.
"""
import sympy as sp

from sewgen.derive.model import Mechanism


def declare(planar: bool = False) -> Mechanism:
    """The mechanism; ``planar=True``: its planar equivalent (``overlock_needle_planar``: the spatial four-bar's crank
    turned into the plane, as seed 003 computes it; Mechanism.spatial_crank)."""
    m = Mechanism("overlock_needle_planar" if planar else "overlock_needle", __doc__, default_speed="3500 rpm")
    r = m.length("eccentric", "7.4 mm", "eccentricity AB of the needle eccentric on the main shaft (estimate)")
    h_a = m.length("shaft_below", "60 mm", "main-shaft axis below the rock shaft D (estimate)")
    rod = m.length("rod", "60 mm", "ball-jointed rod BC (estimate)")
    l3 = m.length("arm", "16 mm", "rock-shaft arm DC, l₃ (estimate)")
    l4 = m.length("lever", "28 mm", "needle lever DL, l₄ (estimate)")
    gamma = m.angle("lever_angle", "0 deg", "angle of the needle lever DL from the arm DC (estimate)")
    l5 = m.length("link", "40 mm", "needle-bar link LN, l₅ (estimate)")
    a = m.length("offset", "28 mm", "needle-bar axis from the rock shaft D, a (estimate)", signed=True)
    eye = m.length("eye_below_pin", "75 mm", "needle eye below the link pin N along the bar (estimate)")
    point = m.length("point_below_eye", "2 mm", "needle point below its eye (estimate)")
    m.length("eye_length", "1.0 mm", "length of the needle eye along the needle (estimate)", role="needle_eye_length")
    m.length("scarf_length", "3.5 mm", "needle scarf above the eye's top, where the lower looper's tip passes "
             "(estimate)", role="needle_scarf")

    crank = m.spatial_crank("eccentric", (l3, -h_a, 0), (1, 0, 0), phase="180 deg",
                            doc="needle eccentric on the main shaft 1",
                            inertia="2e-6 kg*m**2", mass="30 g", planar=planar)
    lever = m.link("lever", doc="needle-lever rock shaft 3 with its arm DC and lever DL", guess="0 deg",
                   mass="35 g", com=("8 mm", "0 mm"), inertia="6e-6 kg*m**2")
    link = m.link("link", doc="needle-bar link 5", guess="90 deg", mass="6 g", com=(l5 / 2, 0),
                  inertia="1e-6 kg*m**2")
    bar = m.slider("needle_bar", m.ground.line(at=(a, 0), angle=sp.pi / 2), doc="needle bar with its needle",
                   guess="40 mm", mass="25 g", com=("-30 mm", "0 mm"), inertia="8e-6 kg*m**2", role="needle_bar")
    m.revolute(m.ground.at(0, 0), lever.at(0, 0), "D")
    m.rod(crank.pin(r), lever.at(l3 * sp.cos(-gamma), l3 * sp.sin(-gamma)), rod, "rod", branch=1)
    m.revolute(lever.at(l4, 0), link.at(0, 0), "L")
    m.revolute(link.at(l5, 0), bar.at(0, 0), "N", branch=1)
    m.point("lever_pin", lever.at(l4, 0), "needle-lever pin L")
    m.point("needle_eye", bar.at(-eye, 0), "needle eye", role="needle_eye")
    m.point("needle_point", bar.at(-eye - point, 0), "needle point", role="needle_point")
    return m

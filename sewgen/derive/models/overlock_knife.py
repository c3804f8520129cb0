"""51-A class overlock: the knife механизм ножа (seed 003 names it; its drive is as on 51-A class machines).

The upper knife is clamped in a knife lever that an eccentric on the main shaft rocks through a rod (a
crank-rocker); it cuts against the fixed lower knife, whose edge is the parameter ``lower_edge``. The knife edge
point is the upper knife's cutting corner; the cutting overlap is how far it passes below the lower knife's edge
at the bottom of its stroke (about 0.5–1 mm on overlock machines; the analysis reports it).

Frame: the plane across the main shaft, origin on its axis, x the feed direction, y up. Every dimension is an
estimate: an edge stroke of about 8.1 mm, an overlap of about 0.56 mm.
"""
from sewgen.derive.model import Mechanism


def declare() -> Mechanism:
    m = Mechanism("overlock_knife", __doc__, default_speed="3500 rpm")
    r = m.length("eccentric", "1.25 mm", "knife eccentricity (estimate)")
    rod = m.length("rod", "40 mm", "knife rod (estimate)")
    px = m.length("lever_pivot_x", "-20 mm", "knife lever pivot, x (estimate)", signed=True)
    py = m.length("lever_pivot_y", "40 mm", "knife lever pivot, y (estimate)", signed=True)
    arm = m.length("lever_arm", "20 mm", "knife lever's arm to the rod (estimate)")
    knife = m.length("knife_arm", "65 mm", "knife lever's arm to the knife edge (estimate)")
    m.length("lower_edge", "36.5 mm", "height of the fixed lower knife's edge (estimate)", signed=True,
             role="lower_knife_edge")
    crank = m.driven("eccentric", m.ground.at(0, 0), doc="knife eccentric on the main shaft", mass="10 g",
                     com=("0.5 mm", "0 mm"), inertia="8e-7 kg*m**2")
    link = m.link("rod", doc="knife rod", guess="90 deg", mass="8 g", com=(rod / 2, 0), inertia="1.5e-6 kg*m**2")
    lever = m.link("knife_lever", doc="upper knife lever with the upper knife", guess="0 deg", mass="35 g",
                   com=("30 mm", "0 mm"), inertia="2e-5 kg*m**2")
    m.revolute(crank.at(r, 0), link.at(0, 0), "B")
    m.revolute(m.ground.at(px, py), lever.at(0, 0), "P")
    m.revolute(link.at(rod, 0), lever.at(arm, 0), "C", branch=-1)
    m.point("knife_edge", lever.at(knife, 0), "upper knife's cutting corner", role="knife_edge")
    return m

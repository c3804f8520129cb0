"""Needle-bar mechanism 刺布机构: upper-shaft crank → needle-bar link 小连杆 13 → needle bar 针杆 14.

A crank-slider with offset (seed 000 §一(一)1 and fig. 1-6; seed 002 fig. 1: A crank centre, B crank pin,
C needle-bar pin). Frame: origin on the upper-shaft axis A, x horizontal, y up; the needle bar slides on
the vertical line x = offset, its travel s measured upward from the shaft's horizontal (s = y of C).
Crank angle = shaft angle + phase, counter-clockwise from +x (the needle is highest near phi = 90°).

Dimensions: crank 16.7 mm is seed 002's industrial crank (its stroke 33.4 mm is within the 29–35 mm of
industrial and household machines). The link length, offset, masses and inertias are estimates (the
seeds' tables of them are not in the text we have).

The needle itself (stitch formation, sewgen.machine.timing): the eye (point ``needle_eye``, the eye's centre), the
point below it (point ``needle_point``: it enters and leaves the cloth), the eye's length (its top is where
the hook point's height is measured from) and the scarf above the eye (the hollow the hook point passes
through). A household 130/705 H (15x1) needle of size 80–90 is assumed: eye about 1.2 mm long, its centre
about 2.5 mm above the point, scarf about 4 mm long (estimates; no dimensioned drawing was reachable).
"""
import sympy as sp

from sewgen.derive.model import Mechanism


def declare() -> Mechanism:
    m = Mechanism("needle_bar", __doc__, default_speed="1000 rpm")
    r = m.length("crank", "16.7 mm", "crank radius AB (seed 002 §3)", role="needle_crank_radius")
    l = m.length("rod", "50 mm", "needle-bar link BC, pin to pin (estimate)", role="needle_rod_length")
    e = m.length("offset", "0 mm", "horizontal offset of the needle-bar axis from the shaft axis", signed=True,
                 role="needle_bar_offset")
    h = m.length("eye_below_pin", "62 mm", "needle eye below the link pin C along the bar (estimate)")
    tip = m.length("point_below_eye", "2.5 mm", "needle point below the eye's centre (estimate, 130/705 H size 80-90)")
    m.length("eye_length", "1.2 mm", "length of the needle eye along the needle (estimate)", role="needle_eye_length")
    m.length("scarf_length", "4 mm", "needle scarf above the eye's top, where the hook point passes (estimate)",
             role="needle_scarf")
    crank = m.driven("crank", pivot=m.ground.at(0, 0), doc="needle-bar crank on the upper shaft", role="needle_crank",
                     mass="0 g", com=("0 mm", "0 mm"), inertia="0 kg*m**2")
    rod = m.link("rod", doc="needle-bar link 小连杆 (part 13)", guess="-90 deg", role="needle_rod",
                 mass="12 g", com=(l / 2, 0), inertia="2.5e-6 kg*m**2")
    bar = m.slider("needle_bar", guide=m.ground.line(at=(e, 0), angle=sp.pi / 2),
                   doc="needle bar with clamp and needle 针杆组件 (part 14)", guess="-40 mm", role="needle_bar",
                   mass="45 g", com=("-30 mm", "0 mm"), inertia="1.5e-5 kg*m**2")
    m.revolute(crank.at(r, 0), rod.at(0, 0), name="B")
    m.revolute(rod.at(l, 0), bar.at(0, 0), name="C", branch=-1)
    m.point("crank_pin", crank.at(r, 0), "crank pin B")
    m.point("link_pin", bar.at(0, 0), "needle-bar link pin C")
    m.point("needle_eye", bar.at(-h, 0), "needle eye (its centre)", role="needle_eye")
    m.point("needle_point", bar.at(-h - tip, 0), "needle point", role="needle_point")
    # Coulomb friction, off (coefficient 0, as seed 000 assumes); pin radii are estimates (crank pin Ø6, link pin
    # Ø5). The crank's own pivot is the upper shaft's journal: its friction belongs to the machine's bearings.
    m.friction_off({"B": "3 mm", "C": "2.5 mm"}, slides=["needle_bar.guide"])
    return m

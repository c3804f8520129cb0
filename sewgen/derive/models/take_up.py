"""Thread take-up mechanism 挑线机构: upper-shaft crank AB → take-up lever 挑线杆 BCE (16) → rocker CD 挑线摇杆 (15).

A crank-rocker four-bar with the thread eye E on the coupler triangle BCE (seed 000 group 挑线; seed 004
§1.1, figs. 1-2). Frame as seed 004 with its (Z, X) taken as our (x, y): A at the origin, D = (26, −20) mm;
the crank angle runs from +x towards +y. E is placed from the triangle's sides by the law of cosines,
B→E at ∠CBE from B→C (seed 004 eq. for φBE, with φBC in place of the paper's misprinted φCD).
Seed 004 runs the crank at n = 5000 r/min.

The link lengths of seed 004's table 1 are not in the text: AB, BC, CD, BE, CE are estimates that make a
Grashof crank-rocker (10 + 38 ≤ 26 + 32.8) with the willow-leaf eye path the paper describes.
"""
import sympy as sp

from sewgen.derive.model import Mechanism


def declare() -> Mechanism:
    m = Mechanism("take_up", __doc__, default_speed="5000 rpm")
    dx = m.length("rocker_pivot_x", "26 mm", "D, horizontal (seed 004 §1.1.1)", signed=True)
    dy = m.length("rocker_pivot_y", "-20 mm", "D, vertical (seed 004 §1.1.1)", signed=True)
    ab = m.length("crank", "10 mm", "crank AB (estimate)")
    bc = m.length("lever_bc", "38 mm", "take-up lever B to C (estimate)")
    cd = m.length("rocker", "26 mm", "rocker CD (estimate)")
    be = m.length("lever_be", "58 mm", "take-up lever B to thread eye E (estimate)")
    ce = m.length("lever_ce", "22 mm", "take-up lever C to thread eye E (estimate)")
    eu = (bc**2 + be**2 - ce**2) / (2 * bc)  # E in the lever frame (B origin, C on +u)
    ev = sp.sqrt(be**2 - eu**2)
    crank = m.driven("crank", pivot=m.ground.at(0, 0), doc="take-up crank on the upper shaft")
    lever = m.link("lever", doc="take-up lever 挑线杆 (part 16)", guess="60 deg", role="take_up_lever",
                   mass="9 g", com=("24 mm", "2 mm"), inertia="3.0e-6 kg*m**2")
    rocker = m.link("rocker", doc="take-up rocker 挑线摇杆 (part 15)", guess="100 deg",
                    mass="4 g", com=(cd / 2, 0), inertia="3.0e-7 kg*m**2")
    m.revolute(crank.at(ab, 0), lever.at(0, 0), name="B")
    m.revolute(m.ground.at(dx, dy), rocker.at(0, 0), name="D")
    m.revolute(lever.at(bc, 0), rocker.at(cd, 0), name="C", branch=1)
    m.point("crank_pin", crank.at(ab, 0), "crank pin B")
    m.point("rocker_pin", rocker.at(cd, 0), "lever-rocker pin C")
    m.point("thread_eye", lever.at(eu, ev), "thread eye E of the take-up lever", role="thread_eye")
    # Coulomb friction, off (coefficient 0, as seed 000 assumes); pin radii are estimates (crank pin Ø6, lever
    # pin Ø4, rocker stud Ø5). The crank's pivot is the upper shaft's journal (the machine's bearings).
    m.friction_off({"B": "3 mm", "C": "2 mm", "D": "2.5 mm"})
    return m

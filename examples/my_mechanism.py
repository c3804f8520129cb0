"""A take-up lever of your own: a crank-rocker four-bar with the thread eye on the coupler (a user's
declaration, not in the catalog). Used by the README:

    sewgen kinematics --file examples/my_mechanism.py --units mm,deg
    sewgen forces --file examples/my_mechanism.py --load "thread_eye fy=-2.94N from=135deg to=155deg"

Crank AB on the upper shaft (A at the origin), coupler BC carrying the thread eye E, rocker DC pivoted on the
frame at D. Lengths are parameters (``--param crank="9 mm"``); every moving body has a mass, a centre of mass
(local u along the body from its first joint, v across) and a moment of inertia about that centre, so
``sewgen forces`` gives real joint reactions and driving torque.
"""
from sewgen.derive import Mechanism


def declare() -> Mechanism:
    m = Mechanism("my_take_up", "Crank-rocker take-up lever with the thread eye on the coupler.")
    r = m.length("crank", "8 mm", "crank AB")
    bc = m.length("coupler", "36 mm", "coupler B to C, pin to pin")
    cd = m.length("rocker", "22 mm", "rocker D to C")
    dx = m.length("pivot_x", "28 mm", "rocker pivot D, x", signed=True)
    dy = m.length("pivot_y", "-14 mm", "rocker pivot D, y", signed=True)
    eu = m.length("eye_u", "48 mm", "thread eye along B->C", signed=True)
    ev = m.length("eye_v", "6 mm", "thread eye across B->C", signed=True)

    crank = m.driven("crank", pivot=m.ground.at(0, 0), doc="crank on the upper shaft",
                     mass="12 g", com=("2 mm", "0 mm"), inertia="6e-7 kg*m**2")
    coupler = m.link("coupler", doc="take-up lever BCE", guess="10 deg",
                     mass="9 g", com=("24 mm", "2 mm"), inertia="2.2e-6 kg*m**2")
    rocker = m.link("rocker", doc="rocker DC", guess="60 deg",
                    mass="5 g", com=("11 mm", "0 mm"), inertia="3e-7 kg*m**2")

    m.revolute(crank.at(r, 0), coupler.at(0, 0), name="B")
    m.revolute(coupler.at(bc, 0), rocker.at(cd, 0), name="C")
    m.revolute(m.ground.at(dx, dy), rocker.at(0, 0), name="D")
    m.point("thread_eye", coupler.at(eu, ev), "thread eye", role="thread_eye")
    return m

"""Hook drive 钩线机构: hook crank 12 → big connecting rod 大连杆 9 → rock shaft 摆轴 4 → rock-shaft slider
摆轴滑块 10 in the slot of the lower-shaft arm 下轴 11 (an oscillating guide bar) → oscillating shuttle.

Two loops (seed 000 §一(一)3, fig. 1-1; fig. 1-2(c) is the guide-bar unit): the four-bar crank–rod–rock
shaft, then the guide bar whose slotted arm turns the lower shaft through a large swing. The rock shaft
and lower shaft run parallel to the upper shaft, so both loops project onto one plane: origin on the upper
shaft axis, x horizontal, y up. The lower-shaft slot passes through its axis (local u axis).

Dimensions are estimates sized to the household machine: the crank-rocker swings the rock shaft ±62° (its
pin under the upper shaft at mid-swing), and the guide bar, its axis 13.5 mm from the rock shaft's inside the
20 mm arm's circle, turns that into a shuttle swing of about 206° (household shuttles swing 206°–210°) with
the lower shaft's speed at most about 2.8 times the upper shaft's.
"""
import sympy as sp

from sewgen.derive.model import Mechanism


def declare() -> Mechanism:
    m = Mechanism("hook_drive", __doc__, default_speed="1000 rpm")
    r = m.length("crank", "12 mm", "hook crank radius on the upper shaft (estimate)")
    rod = m.length("big_rod", "170 mm", "big connecting rod, pin to pin (estimate)")
    ox = m.length("rock_axis_x", "-13.6 mm", "rock-shaft axis, horizontal (estimate)", signed=True)
    oy = m.length("rock_axis_y", "-170 mm", "rock-shaft axis, vertical (estimate)", signed=True)
    front = m.length("rock_front_arm", "13.6 mm", "rock-shaft arm driven by the big rod (estimate)")
    rear = m.length("rock_rear_arm", "20 mm", "rock-shaft arm carrying the slider pin (estimate)")
    rear_angle = m.angle("rock_rear_angle", "-90 deg", "rear arm direction relative to the front arm (estimate)")
    lx = m.length("lower_axis_x", "-13.6 mm", "lower-shaft axis, horizontal (estimate)", signed=True)
    ly = m.length("lower_axis_y", "-183.5 mm", "lower-shaft axis, vertical (estimate)", signed=True)
    crank = m.driven("crank", pivot=m.ground.at(0, 0), doc="hook crank 钩线曲柄 (part 12)")
    big_rod = m.link("big_rod", doc="big connecting rod 大连杆 (part 9)", guess="-90 deg",
                     mass="28 g", com=(rod / 2, 0), inertia="7.0e-5 kg*m**2")
    rock = m.link("rock_shaft", doc="rock shaft with its two arms 摆轴组件 (part 4)", guess="0 deg",
                  mass="60 g", com=("2 mm", "-2 mm"), inertia="8.0e-6 kg*m**2")
    lower = m.link("lower_shaft", doc="lower shaft with slotted arm and shuttle driver 下轴组件 (part 11)",
                   role="hook_shaft",
                   guess="-90 deg", mass="60 g", com=("0 mm", "0 mm"), inertia="6.0e-6 kg*m**2")
    slider = m.slider("rock_slider", guide=lower.line(at=(0, 0), angle=0),
                      doc="rock-shaft slider 摆轴滑块 (part 10)", guess="5 mm",
                      mass="3 g", com=("0 mm", "0 mm"), inertia="1.0e-8 kg*m**2")
    m.revolute(crank.at(r, 0), big_rod.at(0, 0), name="B")
    m.revolute(m.ground.at(ox, oy), rock.at(0, 0), name="O4")
    m.revolute(m.ground.at(lx, ly), lower.at(0, 0), name="O11")
    m.revolute(big_rod.at(rod, 0), rock.at(front, 0), name="C", branch=1)
    m.revolute(rock.at(rear * sp.cos(rear_angle), rear * sp.sin(rear_angle)), slider.at(0, 0), name="E", branch=1)
    m.point("crank_pin", crank.at(r, 0), "crank pin B")
    m.point("rock_pin", rock.at(front, 0), "big-rod pin C on the rock-shaft arm")
    m.point("slider_pin", slider.at(0, 0), "slider pin E on the rock-shaft rear arm")
    return m

"""Hook drive 钩线机构: hook crank 12 → big connecting rod 大连杆 9 → rock shaft 摆轴 4 → rock-shaft slider
摆轴滑块 10 in the slot of the lower-shaft arm 下轴 11 (an oscillating guide bar) → oscillating shuttle.

Two loops (seed 000 §一(一)3, fig. 1-1; fig. 1-2(c) is the guide-bar unit): the four-bar crank–rod–rock
shaft, then the guide bar whose slotted arm turns the lower shaft through a large swing. The rock shaft
and lower shaft run parallel to the upper shaft, so both loops project onto one plane: origin on the upper
shaft axis, x horizontal, y up. The lower-shaft slot passes through its axis (local u axis).

The shuttle's point 摆梭尖 (point ``hook_point``) is a point of the lower-shaft body at ``hook_radius`` from its
axis and ``hook_angle`` from the slot: the lower shaft's axis is under the needle (x = 0), so the hook point
crosses the needle's centre line at the top of its circle, moving across it (sewgen.machine.timing measures the
needle's rise from its bottom dead centre and the hook point's height above the needle eye there).

Dimensions are estimates sized to the household machine (seed 000's tables are not in the text); the
earlier estimate (crank 12, rod 170, rock arms 13.6 and 20 mm) swung the rock shaft ±62° with a minimum
transmission angle of 23.6°, at φ = 125° where the hook crank pin's load peaked:

* the crank-rocker (crank 16 mm, big rod 217.76 mm, front arm 21.02 mm, rock axis 217.45 mm below the upper
  shaft) swings the rock shaft 99.1° with a minimum transmission angle of 40.3° (big rod against the front
  arm). A crank-rocker's transmission angle falls below 40° once its rocker swings much more than 100°, so
  the rock swing cannot stay near the old 124°. Its ends — the shuttle's reversals — fall at crank angles of
  about 89° and 269°, so a group phase of −2° puts them at the needle's top and bottom dead centres (an
  oscillating shuttle starts from its end position with the needle at its lowest point);
* the guide bar (the lower-shaft axis under the needle, 32.4 mm from the rock shaft's, inside the 39.01 mm
  rear arm's circle; rear arm 57.63° from the front arm) turns the 99.1° into a shuttle swing of 206.7°
  (household shuttles swing 206°–210°). Its own transmission angle is 90° (the slot's force is normal to the
  slotted arm). The price of the smaller rock swing is a less uniform shuttle: the guide bar must multiply
  the swing 2.1 times, most of it at mid-stroke, so the lower shaft peaks at 4.5 times the upper shaft's speed
  (2.7 before) and its inertia, not the transmission, now sets the hook crank pin's peak load. These
  dimensions are the ones of least peak crank-pin load (167 N at 1000 r/min with the lower shaft's 6e-6
  kg·m²) among those with a transmission angle of at least 40.3°, a 206.5°–210° swing and reversals at 89° and
  269° (a local search over rod, rock axis, arms and rear-arm angle); a 35° design of the same kind would
  carry about 80 N, and without the lower shaft's inertia this one would carry 16 N (the old one 44 N);
* the shuttle (hook point) radius is 12 mm, its axis 20 mm below the throat plate: its point passes over the
  needle's centre line at the top of its circle. ``hook_angle`` (132.45°) puts it there when the needle has
  risen 2.0 mm from its bottom dead centre (JUKI service manuals: 2.0 ± 0.2 mm) at the JB1-3's phase, 1.6 mm
  above the top of the needle eye (service manuals: 1–2.5 mm).
"""
import sympy as sp

from sewgen.derive.model import Mechanism


def declare() -> Mechanism:
    m = Mechanism("hook_drive", __doc__, default_speed="1000 rpm")
    r = m.length("crank", "16 mm", "hook crank radius on the upper shaft (estimate)")
    rod = m.length("big_rod", "217.76 mm", "big connecting rod, pin to pin (estimate)")
    ox = m.length("rock_axis_x", "-17.9 mm", "rock-shaft axis, horizontal (estimate)", signed=True)
    oy = m.length("rock_axis_y", "-217.45 mm", "rock-shaft axis, vertical (estimate)", signed=True)
    front = m.length("rock_front_arm", "21.02 mm", "rock-shaft arm driven by the big rod (estimate)")
    rear = m.length("rock_rear_arm", "39.01 mm", "rock-shaft arm carrying the slider pin (estimate)")
    rear_angle = m.angle("rock_rear_angle", "57.63 deg", "rear arm direction relative to the front arm (estimate)")
    lx = m.length("lower_axis_x", "0 mm", "lower-shaft axis, horizontal: under the needle (estimate)", signed=True)
    ly = m.length("lower_axis_y", "-190.5 mm", "lower-shaft axis, vertical (estimate)", signed=True)
    hr = m.length("hook_radius", "12 mm", "shuttle point's radius about the lower-shaft axis (estimate)")
    ha = m.angle("hook_angle", "132.45 deg", "shuttle point's direction on the lower shaft from its slot "
                 "(set for a 2.0 mm loop lift)")
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
    m.point("hook_point", lower.at(hr * sp.cos(ha), hr * sp.sin(ha)), "shuttle point 摆梭尖", role="hook_point")
    # Coulomb friction, off (coefficient 0, as seed 000 assumes); radii are estimates (crank pin Ø6, rod pin Ø5,
    # rock-shaft journal Ø8, lower-shaft journal Ø10, slider pin Ø5). The crank's pivot is the upper shaft's
    # journal (the machine's bearings).
    m.friction_off({"B": "3 mm", "C": "2.5 mm", "O4": "4 mm", "O11": "5 mm", "E": "2.5 mm"},
                   slides=["rock_slider.guide"])
    return m

"""Feed mechanism 送布机构 of the JB household machine: feed cam → feed fork → feed rock shaft → feed bar, with
the stitch-length regulator 针距机构 and the feed lift 抬牙 (seed 000 §一(四), eqs. 1-1 to 1-5; seed 001 §二, the
sub-mechanisms D (lift), E (stitch length) and F (feed bar with the feed dog)).

A two-degree-of-freedom cam–linkage: the upper shaft turns the constant-breadth feed cam 送布凸轮 (six circular
arcs, a rounded Reuleaux triangle turning about a vertex: 60° dwell, 120° stroke, 60° dwell, 120° return)
inside the two flat faces of the feed fork 送布牙叉 (part 3), which hangs down the standing arm. The fork's
lower end P drives the feed rock shaft 送布轴 (part 2) through its rear arm; its middle Q carries the stitch
block 针距滑块 (part 8) in the slot of the stitch regulator 针距座, whose angle is the second input (held in a
run; its holding torque is an output). With the slot horizontal the fork only rocks about P: zero stitch;
tilted by ±α it makes the fork rise and fall, turning the feed rock shaft one way or the other: forward or
reverse feed. The feed rock shaft's upper arm carries the feed bar 牙架 (part 6) at R; the feed bar rests in
the lift rock shaft's 抬牙轴 (part 5) roller 抬牙滚柱 (part 7), a pin in a slot along the bar. The feed dog
送布牙 is a point of the feed bar.

The lift 抬牙 follows seed 001 §二's upper branch: upper shaft → B (the big-rod mechanism 大连杆机构: hook crank,
big rod 大连杆 9, rock shaft 摆轴 4 — the hook drive's own four-bar) → D (the lift cam mechanism 抬牙凸轮机构: a
lift cam on the rock shaft in the fork of the lift crank 抬牙曲柄) → the lift rock shaft. B is declared here a
second time, massless, with the hook drive's dimensions (its parameters must equal ``hook_drive``'s crank,
big_rod, rock_axis_x/_y and rock_front_arm and its phase the hook drive's): the two groups then move one rock
shaft alike, the hook drive's group carries B's masses, and the lift's reaction reaches the hook crank pin and
the rock-shaft bearing through this copy — kinetostatics is linear in the loads, so the groups' reactions add
up to the real ones. The lift cam is a circular cam (an eccentric of ``lift_cam_eccentricity`` on the rock
shaft) between the two parallel faces of the lift crank's fork: its equivalent lower pair, the eccentric's
centre as a pin in the fork's centre-line slot, is exact. The rock shaft swings about 96° once a turn with its
ends at the shuttle's reversals (needle top and bottom, φ ≈ 90° and 270°); the eccentric sits across the line
from the rock shaft to the lift shaft at mid-swing, so the lift crank turns one way over the whole swing and the
dog is highest when the needle is highest — above the plate while the needle is out of the cloth, below it
while the needle is in (seed 001 §五 2, "coordination of the feed dog with the other mechanisms").

The cam contact is replaced, arc by arc, by its equivalent lower pair (derive.model.Mechanism.cam), so the
loop closes in one set of equations (Newton, as seed 000 solves eqs. 1-5). Frame: origin on the upper-shaft
axis, x horizontal (feed direction positive), y up; the throat plate is at y = plate_y.

Every dimension here is an estimate (seed 000's tables 附表 and seed 001's 附表 1 are not in the text): sized so
the fork stroke is 6 mm, the maximum stitch 4 mm at a regulator angle near 40°, and the feed dog rises about
1 mm above the throat plate while the needle is out of the cloth (needle top at φ = 90°).
"""
import sympy as sp

from sewgen.derive.model import Mechanism, constant_breadth_arcs


def declare() -> Mechanism:
    m = Mechanism("feed", __doc__, default_speed="1000 rpm")
    side = m.length("cam_side", "6 mm", "feed cam: side of its Reuleaux triangle = fork stroke (estimate)")
    r0 = m.length("cam_small_radius", "8 mm", "feed cam: small arc radius; breadth = side + 2 radius (estimate)")
    tp = m.length("fork_p", "200 mm", "feed fork: cam centre line to rock-shaft pin P (estimate)")
    tq = m.length("fork_q", "60 mm", "feed fork: cam centre line to stitch-block pin Q (estimate)")
    rx = m.length("regulator_x", "0 mm", "stitch regulator pivot, x (estimate)", signed=True)
    ry = m.length("regulator_y", "-60 mm", "stitch regulator pivot, y (estimate)", signed=True)
    fx = m.length("feed_shaft_x", "-20 mm", "feed rock shaft axis, x (estimate)", signed=True)
    fy = m.length("feed_shaft_y", "-200 mm", "feed rock shaft axis, y (estimate)", signed=True)
    arm_p = m.length("feed_arm_p", "20 mm", "feed rock shaft: rear arm to the fork pin P (estimate)")
    arm_r = m.length("feed_arm_r", "29.3 mm", "feed rock shaft: upper arm to the feed-bar pin R (estimate)")
    lx = m.length("lift_shaft_x", "10 mm", "lift rock shaft axis, x (estimate)", signed=True)
    ly = m.length("lift_shaft_y", "-177.7 mm", "lift rock shaft axis, y (estimate)", signed=True)
    arm_l = m.length("lift_arm", "15 mm", "lift rock shaft: arm to the roller L (estimate)")
    # B: the hook drive's crank, big rod and rock shaft (hook_drive's parameters; massless here)
    b_crank = m.length("hook_crank", "16 mm", "B: hook crank radius (= hook_drive crank)")
    b_rod = m.length("big_rod", "217.76 mm", "B: big rod, pin to pin (= hook_drive big_rod)")
    b_ox = m.length("rock_axis_x", "-17.9 mm", "B: rock-shaft axis, x (= hook_drive rock_axis_x)", signed=True)
    b_oy = m.length("rock_axis_y", "-217.45 mm", "B: rock-shaft axis, y (= hook_drive rock_axis_y)", signed=True)
    b_arm = m.length("rock_front_arm", "21.02 mm", "B: rock-shaft arm driven by the big rod (= hook_drive's)")
    # D: the lift cam on the rock shaft, in the fork of the lift crank
    ecc = m.length("lift_cam_eccentricity", "3.9 mm", "D: lift cam (eccentric) centre from the rock-shaft axis "
                   "(estimate)")
    ecc_angle = m.angle("lift_cam_angle", "56.1 deg", "D: lift cam centre's direction on the rock shaft from its "
                        "front arm (estimate: across the line to the lift shaft at mid-swing)")
    fork_angle = m.angle("lift_fork_angle", "54.9 deg", "D: lift crank's fork centre line on the lift rock shaft, "
                         "from its roller arm (estimate)")
    dog_u = m.length("dog_u", "20 mm", "feed dog tip along the feed bar from R (estimate)")
    slot_v = m.length("bar_slot_v", "7 mm", "feed bar: its roller slot below the line R–feed dog (estimate)")
    m.length("plate_y", "-170.5 mm", "throat plate surface, y (estimate: the dog rises ~1 mm above it)", signed=True,
             role="throat_plate")

    cam = m.driven("feed_cam", pivot=m.ground.at(0, 0), phase="60 deg", role="feed_cam",
                   doc="feed cam 送布凸轮 on the upper shaft (constant breadth, six arcs)",
                   mass="30 g", com=("1.5 mm", "0 mm"), inertia="4.0e-6 kg*m**2")
    hook_crank = m.driven("hook_crank", pivot=m.ground.at(0, 0), phase="-2 deg",
                          doc="B: the hook crank 钩线曲柄 (part 12; its phase = the hook drive's group phase)")
    regulator = m.held("regulator", pivot=m.ground.at(rx, ry), default="40 deg", role="stitch_regulator",
                       doc="stitch regulator 针距座: slot angle from horizontal (0: no feed; >0 forward; <0 reverse)")
    fork = m.link("feed_fork", doc="feed fork 送布牙叉 (part 3), u down the fork from the cam centre line",
                  guess="-90 deg", mass="35 g", com=(tp / 2, 0), inertia="1.2e-4 kg*m**2")
    block = m.slider("stitch_block", guide=regulator.line(at=(0, 0), angle=0),
                     doc="stitch block 针距滑块 (part 8)", guess="0 mm", mass="4 g", inertia="1e-8 kg*m**2")
    feed_shaft = m.link("feed_rock_shaft", doc="feed rock shaft with its two arms 送布轴组件 (part 2)",
                        guess="0 deg", mass="40 g", com=("5 mm", "5 mm"), inertia="6.0e-6 kg*m**2")
    bar = m.link("feed_bar", doc="feed bar 牙架 (part 6) with the feed dog 送布牙", guess="0 deg", role="feed_bar",
                 mass="25 g", com=("15 mm", "-3 mm"), inertia="4.0e-6 kg*m**2")
    lift = m.link("lift_rock_shaft", doc="lift rock shaft with its arms and roller 抬牙轴组件 (parts 5, 7)",
                  guess="180 deg", mass="30 g", com=("0 mm", "0 mm"), inertia="3.0e-6 kg*m**2")
    big_rod = m.link("big_rod", doc="B: big rod 大连杆 (part 9); massless here, its mass is in the hook drive",
                     guess="-90 deg")
    rock = m.link("rock_shaft", doc="B: rock shaft 摆轴 (part 4) with the lift cam 抬牙凸轮 (D); massless here",
                  guess="0 deg")

    breadth = side + 2 * r0
    arcs = constant_breadth_arcs(side, r0, centroid=(0, -side / sp.sqrt(3)), orientation=sp.pi / 2)
    m.cam(cam, fork.line(at=(0, -breadth / 2), angle=sp.pi), arcs, name="cam")
    m.revolute(m.ground.at(fx, fy), feed_shaft.at(0, 0), name="O_feed")
    m.revolute(feed_shaft.at(arm_p, 0), fork.at(tp, 0), name="P")
    m.revolute(fork.at(tq, 0), block.at(0, 0), name="Q")
    m.revolute(feed_shaft.at(0, arm_r), bar.at(0, 0), name="R")
    m.revolute(m.ground.at(lx, ly), lift.at(0, 0), name="O_lift")
    m.revolute(hook_crank.at(b_crank, 0), big_rod.at(0, 0), name="B")
    m.revolute(m.ground.at(b_ox, b_oy), rock.at(0, 0), name="O4")
    m.revolute(big_rod.at(b_rod, 0), rock.at(b_arm, 0), name="C", branch=1)
    m.slot(lift.line(at=(0, 0), angle=fork_angle), rock.at(ecc * sp.cos(ecc_angle), ecc * sp.sin(ecc_angle)), name="D")
    m.slot(bar.line(at=(0, -slot_v), angle=0), lift.at(arm_l, 0), name="L")
    m.point("feed_dog", bar.at(dog_u, 0), "feed dog tip (on the line through R: lifting it does not move it sideways)",
            role="feed_dog")
    m.point("fork_top", fork.at(0, 0), "feed fork on the cam centre line")
    m.point("stitch_pin", fork.at(tq, 0), "fork pin Q in the stitch block")
    m.point("lift_roller", lift.at(arm_l, 0), "lift roller L in the feed bar")
    m.point("lift_cam", rock.at(ecc * sp.cos(ecc_angle), ecc * sp.sin(ecc_angle)), "D: lift cam centre, in the fork")
    # Coulomb friction, off (coefficient 0, as seed 000 assumes); radii are estimates (rock-shaft journals Ø8,
    # fork and block pins Ø5, feed-bar hinge Ø6). B, O4 and C are the hook drive's joints, counted there; the cam
    # on the fork has no Coulomb model (it rolls and slides at once); the held regulator does not turn.
    m.friction_off({"O_feed": "4 mm", "P": "2.5 mm", "Q": "2.5 mm", "R": "3 mm", "O_lift": "4 mm"},
                   slides=["stitch_block.guide", "D", "L"])
    return m

"""51-A class overlock: the material feed механизм продвижения материала (seed 003 fig. 5, eqs. 3–14).

Two eccentrics on the main shaft A, fixed to each other at the constructive angle θ: the feed eccentric AB
drives the rock shaft 3 through the planar four-bar ABCD (φ₃ by eq. 1 with α = 0), whose arm DE carries the rack's
rear pin E; the lift eccentric AK (radius l₅) lifts the rack's front through the link KF (l₆). The rack 4 — the
link EF (l₄) with its teeth at F and G — is the two-input group DEFKA's dyad (links 4 and 6 meeting at F): the
seed solves its velocities by Cramer's rule on the velocity plan (eqs. 8–13; eq. 12 needs ω₃·l₃) and G's by the
same plan (eq. 14).

Frame: the plane across the main shaft, origin on its axis A, x the feed direction, y up. The rock-shaft arm DE is
vertical in mid stroke, so E moves about horizontally (the stitch), K about vertically (the lift).

Every dimension is an estimate (seed 003 prints none): a rack travel of about 4.3 mm at the largest stitch, a
lift of about 2.4 mm, the rack's teeth about 40 mm above the shaft. θ = 0 puts the teeth at their highest when
they move forward fastest, at φ ≈ 90°, when the needle (overlock_needle) is at its highest: the rack feeds while
the needle is out of the material.

Stitch regulator (role ``stitch_regulator``): overlocks of this class set the stitch by the feed eccentric's throw
(a double, adjustable-throw eccentric: the inner eccentric is turned in the outer one and clamped — on later
machines by pressing a button and turning the hand wheel). Here the outer eccentric AB₀ (``feed_eccentric``, e₁,
fixed on the shaft at ``feed_eccentric.phase``) carries the inner one B₀B (``stitch_eccentric``, e₂ = e₁) turned
by the held angle β, its pin set back (−e₂ along its arm): AB = e₁ − e₂·(cos β, sin β) in the outer eccentric's
frame, a throw of 2e sin(β/2) at the angle β/2 − 90°. β = 0 gives no feed, β > 0 forward, β < 0 reverse (the
throw turned half a turn); the effective eccentric's phase moves by β/2 with the setting, so
``feed_eccentric.phase`` = 90° − β₀/2 puts it on the shaft angle at the design setting β₀ (the 4 mm stitch). At
the regulator's limit ±45° the throw is 2e sin 22.5° = 1.91 mm: a rack travel of about 5 mm.

The throat plate (role ``throat_plate``, ``plate_y``) is 1 mm below the teeth's highest point: the stitch is the
teeth's travel above it (sewgen.machine.feed).
"""
from sewgen.derive.model import Mechanism


def declare() -> Mechanism:
    m = Mechanism("overlock_feed", __doc__, default_speed="3500 rpm")
    e1 = m.length("feed_eccentric", "2.5 mm", "outer feed eccentric's eccentricity AB₀, e₁ (estimate)")
    e2 = m.length("stitch_eccentric", "2.5 mm", "inner (stitch) eccentric's eccentricity B₀B, e₂ (estimate)")
    l2 = m.length("strap", "45 mm", "feed eccentric strap BC (estimate)")
    dx = m.length("rock_shaft_x", "45 mm", "rock shaft D, x (estimate)", signed=True)
    dy = m.length("rock_shaft_y", "16 mm", "rock shaft D, y (estimate)", signed=True)
    cd = m.length("rock_arm", "18 mm", "rock-shaft arm DC, below D (estimate)")
    l3 = m.length("rack_arm", "24 mm", "rock-shaft arm DE, above D, l₃ (estimate)")
    l4 = m.length("rack", "45 mm", "rack EF between its rear pin E and front pin F, l₄ (estimate)")
    g_from_f = m.length("tooth_spacing", "10 mm", "tooth G behind tooth F along the rack (estimate)")
    l5 = m.length("lift_eccentric", "1.2 mm", "lift eccentricity AK, l₅ (estimate)")
    theta = m.angle("lift_angle", "0 deg", "constructive angle θ of the lift eccentric ahead of the feed one "
                    "(estimate)")
    l6 = m.length("lift_link", "40 mm", "lift link KF, l₆ (estimate)")
    m.length("plate_y", "40.2 mm", "throat plate surface above the main shaft, y (estimate: the teeth rise about 1 mm "
             "above it)", signed=True, role="throat_plate")

    feed = m.driven("feed_eccentric", m.ground.at(0, 0), phase="71.85 deg",
                    doc="outer feed eccentric AB₀ on the main shaft (phase: 90° − β₀/2, β₀ the 4 mm setting)",
                    mass="15 g", com=("0.8 mm", "0 mm"), inertia="2e-6 kg*m**2")
    stitch = m.held("stitch_eccentric", feed.at(e1, 0), default="36.3 deg", role="stitch_regulator",
                    doc="inner (stitch) eccentric B₀B: its angle β in the outer one sets the throw 2e·sin(β/2) "
                        "(0: no feed; > 0 forward; < 0 reverse)",
                    mass="8 g", com=("-0.8 mm", "0 mm"), inertia="6e-7 kg*m**2")
    lift = m.driven("lift_eccentric", m.ground.at(0, 0), phase=theta, doc="lift eccentric AK, θ ahead of AB",
                    mass="12 g", com=("0.4 mm", "0 mm"), inertia="1.5e-6 kg*m**2")
    strap = m.link("strap", doc="feed eccentric strap BC", guess="0 deg", mass="20 g", com=(l2 / 2, 0),
                   inertia="5e-6 kg*m**2")
    rock = m.link("rock_shaft", doc="feed rock shaft 3 with its arms DC (down) and DE (up)", guess="90 deg",
                  mass="30 g", com=("4 mm", "0 mm"), inertia="6e-6 kg*m**2")
    rack = m.link("rack", doc="feed rack 4 (the link EF with its teeth F and G)", guess="180 deg", mass="18 g",
                  com=(l4 / 2, "3 mm"), inertia="4e-6 kg*m**2")
    link = m.link("lift_link", doc="lift link 6 (KF)", guess="90 deg", mass="8 g", com=(l6 / 2, 0),
                  inertia="1.2e-6 kg*m**2")
    m.revolute(stitch.at(-e2, 0), strap.at(0, 0), "B")
    m.revolute(m.ground.at(dx, dy), rock.at(0, 0), "D")
    m.revolute(strap.at(l2, 0), rock.at(-cd, 0), "C", branch=-1)
    m.revolute(rock.at(l3, 0), rack.at(0, 0), "E")
    m.revolute(lift.at(l5, 0), link.at(0, 0), "K")
    m.revolute(rack.at(l4, 0), link.at(l6, 0), "F", branch=-1)
    m.point("rear_pin", rock.at(l3, 0), "rack's rear pin E")
    m.point("tooth_f", rack.at(l4, 0), "front tooth F", role="feed_dog")
    m.point("tooth_g", rack.at(l4 - g_from_f, 0), "tooth G behind F", role="rack_tooth")
    m.point("lift_pin", lift.at(l5, 0), "lift eccentric's centre K")
    return m

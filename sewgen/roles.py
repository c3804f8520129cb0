"""The role vocabulary: what a part *is* for the machine-level analyses (DESIGN.md §7).

A declaration tags a part with a role (``m.point("eye", bar.at(-h, 0), "needle eye", role=NEEDLE_EYE)``); the
analyses find parts through ``mechanism.description.role(...)`` and never by a catalog mechanism's or part's
name, so they work on any machine. A role is used at most once per mechanism. Other identifiers are allowed as
roles (a user's own analyses may define theirs); these are the ones sewgen's analyses read.
"""
from __future__ import annotations

# -- points -------------------------------------------------------------------------------------------------
NEEDLE_EYE = "needle_eye"        #: the needle's eye (stitch formation, needle-in-cloth windows)
NEEDLE_POINT = "needle_point"    #: the needle's point
THREAD_EYE = "thread_eye"        #: the take-up lever's thread eye (thread supply and demand)
FEED_DOG = "feed_dog"            #: the feed dog's tooth tip (stitch length, trajectory indices; seed 001 §五)
RACK_TOOTH = "rack_tooth"        #: another tooth of the feed dog or rack whose path is shown (seed 003's G)
HOOK_POINT = "hook_point"        #: the hook's or shuttle's point (loop pick-up timing)
LOOPER_TIP = "looper_tip"        #: a looper's tip (a machine with one looper)
LOWER_LOOPER_TIP = "lower_looper_tip"  #: the overlock's lower looper tip N₁ (seed 003 eqs. 5–6)
UPPER_LOOPER_TIP = "upper_looper_tip"  #: the overlock's upper looper tip N₂ (seed 003 eq. 4)
KNIFE_EDGE = "knife_edge"        #: the upper knife's edge (overlock, seed 003)

# -- parameters ----------------------------------------------------------------------------------------------
THROAT_PLATE = "throat_plate"    #: the throat plate's height in the mechanism's frame (m)
LOWER_KNIFE_EDGE = "lower_knife_edge"  #: the fixed lower knife's edge height (overlock; the cutting overlap)
NEEDLE_EYE_LENGTH = "needle_eye_length"  #: the needle eye's length along the needle (its top = eye + length/2)
NEEDLE_SCARF = "needle_scarf"    #: the needle scarf's length above the eye's top (where the hook point passes)

NEEDLE_CRANK_RADIUS = "needle_crank_radius"  #: the needle drive's crank radius (seed 002 l_AB)
NEEDLE_ROD_LENGTH = "needle_rod_length"      #: the needle-bar link's length, pin to pin (seed 002 l_BC)
NEEDLE_BAR_OFFSET = "needle_bar_offset"      #: the needle bar's guide offset from the shaft axis (seed 002 e)

# -- held inputs ----------------------------------------------------------------------------------------------
STITCH_REGULATOR = "stitch_regulator"  #: the held input that sets the stitch length (seed 000 针距机构)

# -- bodies ---------------------------------------------------------------------------------------------------
NEEDLE_BAR = "needle_bar"        #: the needle bar (slider) of a needle drive
NEEDLE_CRANK = "needle_crank"    #: the needle drive's crank on the upper shaft
NEEDLE_ROD = "needle_rod"        #: the needle-bar link (seed 000 小连杆)
TAKE_UP_LEVER = "take_up_lever"  #: the take-up lever carrying the thread eye
HOOK_SHAFT = "hook_shaft"        #: the lower (hook / shuttle) shaft
FEED_BAR = "feed_bar"            #: the feed bar carrying the feed dog
FEED_CAM = "feed_cam"            #: the feed cam on the upper shaft

#: The roles a crank-slider needle drive plays for seed 002's counterweight (sewgen.machine.balance).
NEEDLE_DRIVE = (NEEDLE_CRANK, NEEDLE_ROD, NEEDLE_BAR, NEEDLE_CRANK_RADIUS, NEEDLE_ROD_LENGTH, NEEDLE_BAR_OFFSET)

#: Every role above, for documentation and ``sewgen params``.
KNOWN = tuple(sorted(v for k, v in globals().items() if k.isupper() and isinstance(v, str)))

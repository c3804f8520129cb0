"""Stitch-formation timing: the events of one revolution and the machine's timing rules (``sewgen timing``).

A lockstitch forms when the mechanisms meet at the right shaft angles: the needle carries the thread through
the cloth and, rising from its bottom dead centre, leaves a loop; the hook (shuttle) point enters the loop at
the needle's centre line a little above the eye and carries it round the bobbin case; the take-up gives thread
while the loop is enlarged and cast off, then rises fast to set the stitch; the feed dog is below the throat
plate while the needle is in the cloth and moves the cloth while it is out. This module finds those events on
a fine kinematic sweep of the machine and checks the machine's rules (its model file's ``[[stitch.rules]]``,
each with its source).

Parts are found by role (sewgen.roles), never by a mechanism's name: the needle's ``needle_point`` and
``needle_eye`` (with ``needle_eye_length`` and ``needle_scarf``), the ``hook_point`` (a point of the hook or
shuttle body: its body's angle is the shuttle's), the take-up's ``thread_eye``, the ``feed_dog`` and the
``throat_plate``. A machine without some of them gets the events and rules the others allow.

Events are found to well below the sweep's step: between two sweep angles a quantity is the cubic Hermite
interpolant of its values and exact shaft-angle derivatives (v/ω, a/ω² from the kinematics at constant
speed; sewgen.hermite), and a crossing or an extreme is found on it to the last bit. Angles are the machine's shaft angle φ (needle top at
90° on the JB1-3), in [0°, 360°).

Rules (``rule`` in the model file; ``min``/``max`` with units; ``source`` names the manual, text or seed), each a
:class:`TimingRule` class in the rules section below, registered in :data:`RULES` by its decorator (a new rule
is its class there and its row here):

=====================================  ========  ================================================================
``hook_at_needle_rise``                length    the needle's rise from its bottom dead centre when the hook point
                                                 crosses the needle's centre line (forward pass)
``hook_above_eye``                     length    the hook point's height above the top of the needle eye then
``hook_in_scarf``                      length    the same height, at most the needle's scarf length (no limits in
                                                 the file: the needle's own ``needle_scarf``)
``shuttle_start_at_bdc``               angle     the shuttle's reversal that starts its forward stroke, minus the
                                                 needle's bottom dead centre
``loop_released_before_reversal``      angle     the shuttle's turn from the needle to its next reversal (at least
                                                 ``stitch.loop_release``: the loop must be cast off first)
``dog_sinks_before_needle_enters``     angle     the needle point entering the cloth minus the feed dog sinking
                                                 below the plate
``dog_rises_after_needle_leaves``      angle     the feed dog rising above the plate minus the needle point leaving
                                                 the cloth
``take_up_rises_after_release``        angle     the take-up eye's lowest point minus the loop's cast-off
``stitch_set_before_needle_enters``    angle     the needle point entering the cloth minus the take-up's top
``take_up_rise``                       angle     the take-up's rise, bottom to top (fast: about a quarter turn)
``take_up_rises_over``                 angle     how far the take-up's rise overlaps a window (``from``, ``to``) on
                                                 both sides: min(from − bottom, top − to)
``thread_slack``                       length    the least thread slack S − D + T while the hook carries the
                                                 loop (sewgen.machine.thread)
``lower_looper_at_needle_rise``        length    overlock: the needle's rise from BDC when the lower looper's tip
                                                 crosses the needle's centre line (forward pass: loop pick-up)
``lower_looper_above_eye``             length    the lower looper tip's height above the needle eye's top then
``lower_looper_passes_level``          length    the needle's height at the lower looper's return pass minus at
                                                 its forward pass (both passes meet the needle at one height)
``upper_takes_lower_thread``           length    how far the lower looper's tip stands beyond the needle's line
                                                 (the way it went) when the rising upper looper's tip passes its
                                                 height: the upper looper enters the lower looper's thread
``needle_in_upper_triangle``           length    how far the upper looper's tip stands beyond the needle's line
                                                 (the way it went) when the needle point enters the material: its
                                                 thread then runs across the needle's line, from the tip back over
                                                 the edge, and the needle enters the thread triangle
``upper_above_material``               length    the upper looper tip's height above the material then
=====================================  ========  ================================================================

Points of different groups are compared in the machine's frame (``Group.to_machine``: a group whose plane
contains the shaft, ``frame = "along"``, is placed by its origin). The looper rules measure across the needle in
the plane the lower looper moves in (the machine's x for a group across the shaft, z for one along it).

Angle differences are wrapped into (−180°, 180°], except ``take_up_rise`` and ``loop_released_before_reversal``
(a span). A rule whose parts the machine lacks cannot be checked: it fails, its value is NaN (null in
summary.json) and its message names the roles no group plays and the machine's groups.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from sewgen.errors import SewgenError
from sewgen.machine.feed import plate_height
from sewgen.machine.modelfile import Rule, Stitch
from sewgen.machine.parts import role_group, role_param
from sewgen.machine.thread import thread_control
from sewgen.hermite import Series  # the one cubic Hermite implementation (crossings, values between samples)
from sewgen.roles import (FEED_DOG, HOOK_POINT, LOWER_LOOPER_TIP, NEEDLE_EYE, NEEDLE_EYE_LENGTH, NEEDLE_POINT,
    NEEDLE_SCARF, THREAD_EYE, THROAT_PLATE, UPPER_LOOPER_TIP)

TWO_PI = 2.0 * math.pi
STEP_DEG = 0.25  # the timing sweep's step (1440 positions a turn)


class TimingError(SewgenError):
    """A machine whose timing cannot be worked out (a part that never crosses where it must)."""


# -- the rules ---------------------------------------------------------------------------------------------------

_SCALE = {"length": 1e3, "angle": 180.0 / math.pi}  # SI -> the unit shown

#: rule name -> the rule (a TimingRule), in the order of the table above; a class decorated with @_rule is one
RULES: dict = {}


class Measured(NamedTuple):
    """A rule's value (SI) and how it was measured: the message's middle, naming the angles it was read at."""

    value: float
    how: str


class TimingRule:
    """One kind of timing rule, measured on a machine's :class:`Timing`. ``name`` is the model file's ``rule``,
    ``kind`` the kind of its value (a key of ``_SCALE``: its ``min``/``max`` are read in it), ``unit`` the unit
    shown, ``text`` what it measures. ``needs`` names the :attr:`Timing.values` it reads, ``roles`` the parts
    (sewgen.roles) those come from and ``lacks`` what a machine without one of them lacks; ``window`` rules take
    ``from``/``to``; ``own_limits`` rules need no ``min``/``max`` in the file (:meth:`limits` gives them).

    A rule measures (:meth:`measure`); :meth:`check` does the rest, the same for every rule."""

    name = ""
    kind = "length"
    unit = "mm"
    text = ""
    needs: tuple = ()
    roles: tuple = ()
    lacks = ""
    window = False
    own_limits = False

    def measure(self, rule: Rule, tm: Timing, st: Stitch, machine, ge) -> Measured | str:
        """The value and how it was measured, or why it cannot be (what the machine lacks, a str). ``rule`` is the
        model file's entry, ``st`` the machine's stitch, ``ge`` the needle eye's group (None without one)."""
        raise NotImplementedError(self.name)

    def limits(self, rule: Rule, st: Stitch, ge) -> tuple:
        """(lower, upper) limits in SI, None where open: the model file's."""
        return rule.lo, rule.hi

    def missing(self, machine) -> str:
        """Why the rule cannot be measured on ``machine``: the roles it needs that no group plays, named with the
        machine's groups; else :attr:`lacks`."""
        absent = [r for r in self.roles if not any(g.mechanism.description.has_role(r) for g in machine.groups)]
        if not absent:
            return self.lacks
        return (f"no group has a part with the role{'s' if len(absent) > 1 else ''} {', '.join(absent)} (groups: "
                f"{', '.join(g.name for g in machine.groups)}); {self.lacks}")

    def check(self, rule: Rule, tm: Timing, st: Stitch, machine, ge) -> Check:
        """The rule measured on ``tm`` against its limits: value and limits in the unit shown, pass or fail."""
        scale = _SCALE[self.kind]

        def shown(x):  # SI back to the unit shown, without the conversion's last-digit noise
            return None if x is None else float(f"{x * scale:.12g}")

        got = self.missing(machine) if any(tm.values.get(k) is None for k in self.needs) else \
            self.measure(rule, tm, st, machine, ge)
        if isinstance(got, str):
            return Check(rule.kind, math.nan, shown(rule.lo), shown(rule.hi), self.unit, False,
                         f"{rule.kind}: cannot be checked: {got}", rule.source)
        lo, hi = (shown(x) for x in self.limits(rule, st, ge))
        val = float(got.value * scale)
        ok = bool((lo is None or val >= lo - 1e-9) and (hi is None or val <= hi + 1e-9))
        limit = Check(rule.kind, val, lo, hi, self.unit, ok, "", rule.source).limit
        msg = f"{rule.kind}: {got.how}: {val:.3f} {self.unit}, {'within' if ok else 'outside'} {limit}"
        return Check(rule.kind, val, lo, hi, self.unit, ok, msg, rule.source)


def _rule(cls):
    """Class decorator: registers one instance of the rule class ``cls`` in :data:`RULES` under its name."""
    if cls.name in RULES:
        raise ValueError(f"timing rule {cls.name!r} registered twice")
    RULES[cls.name] = cls()
    return cls


def _deg(a) -> str:
    return f"{math.degrees(a) % 360.0:.2f}°"


class _AngleRule(TimingRule):
    """A rule whose value is a shaft angle (deg shown)."""

    kind = "angle"
    unit = "deg"


class _TakerAtNeedle(TimingRule):
    """A loop taker (``role``: the hook point, a looper's tip) meeting the needle's centre line at event ``event``
    of the sweep (its forward pass); ``taker`` names it in the message."""

    role = ""
    event = ""
    taker = ""

    @property
    def needs(self):
        return (self.event, "bdc")

    def measure(self, rule, tm, st, machine, ge):
        return self.measured(*_taker_at_needle(tm, machine, ge, tm.values, self.event, self.role), tm.values, ge)

    def measured(self, a, rise, height, v, ge) -> Measured | str:
        """The rule's value from the taker's angle ``a`` at the needle, the needle's rise from BDC then and the
        taker's height above the needle eye's top then (None without a needle eye)."""
        raise NotImplementedError(self.name)


class _NeedleRiseAtTaker(_TakerAtNeedle):
    """The needle's rise from its bottom dead centre when the taker reaches the needle's centre line."""

    def measured(self, a, rise, height, v, ge):
        return Measured(rise, f"{self.taker} reaches the needle's centre line at φ = {_deg(a)}, when the needle has "
                              f"risen this far from its bottom dead centre (φ = {_deg(v['bdc'])})")


class _TakerAboveEye(_TakerAtNeedle):
    """The taker's height above the top of the needle eye when it reaches the needle's centre line; ``at`` and
    ``who`` name it in the message."""

    at = ""
    who = ""

    def measured(self, a, rise, height, v, ge):
        if height is None:
            return "the machine needs a needle_eye"
        return Measured(height, f"at φ = {_deg(a)} ({self.at}) {self.who} is this far above the top of the needle "
                                f"eye")


@_rule
class HookAtNeedleRise(_NeedleRiseAtTaker):
    """Service manuals: the hook point at the needle's centre line when the needle bar has risen about 2 mm from
    its bottom dead centre (JUKI LU-2210N-7, TL-2010Q, LH-4128; DOMAIN-NOTES)."""

    name = "hook_at_needle_rise"
    text = "needle rise from BDC when the hook point reaches the needle"
    role, event, taker = HOOK_POINT, "hook_fwd", "the hook point"
    roles = (NEEDLE_POINT, HOOK_POINT)
    lacks = "the machine needs a needle_point and a hook_point"


@_rule
class HookAboveEye(_TakerAboveEye):
    """Service manuals: the hook point about 1-2.5 mm above the top of the needle eye as it reaches the needle
    (typical adjustment; DOMAIN-NOTES)."""

    name = "hook_above_eye"
    text = "hook point above the needle eye's top at the needle"
    role, event, at, who = HOOK_POINT, "hook_fwd", "hook point at the needle", "the hook point"
    roles = (NEEDLE_POINT, HOOK_POINT)
    lacks = "the machine needs a needle_point and a hook_point"


@_rule
class HookInScarf(_TakerAtNeedle):
    """The hook point passes the needle in its scarf: its height above the needle eye's top between 0 and the
    needle's ``needle_scarf`` (the limits are the needle's, none in the model file)."""

    name = "hook_in_scarf"
    text = "hook point within the needle's scarf"
    role, event = HOOK_POINT, "hook_fwd"
    roles = (NEEDLE_POINT, HOOK_POINT)
    lacks = "the machine needs a needle_point and a hook_point"
    own_limits = True

    def measured(self, a, rise, height, v, ge):
        if height is None:
            return "the machine needs a needle_eye"
        if not ge.mechanism.description.has_role(NEEDLE_SCARF):
            return "the needle declares no needle_scarf"
        return Measured(height, f"at φ = {_deg(a)} the hook point passes this far above the needle eye's top, in "
                                f"the needle's {role_param(ge, NEEDLE_SCARF) * 1e3:g} mm scarf")

    def limits(self, rule, st, ge):
        return 0.0, role_param(ge, NEEDLE_SCARF)


@_rule
class ShuttleStartAtBdc(_AngleRule):
    """The household oscillating shuttle starts its forward stroke from its end position with the needle at its
    lowest point and meets the needle as it rises (repair guides; DOMAIN-NOTES): the reversal before the forward
    pass minus the needle's bottom dead centre."""

    name = "shuttle_start_at_bdc"
    text = "shuttle starts its forward stroke at the needle's BDC"
    needs = ("shuttle_start", "bdc")
    roles = (NEEDLE_POINT, HOOK_POINT)
    lacks = "the machine needs a needle_point and a hook_point on a shuttle"

    def measure(self, rule, tm, st, machine, ge):
        v = tm.values
        return Measured(_wrap(v["shuttle_start"] - v["bdc"]),
                        f"the shuttle starts its forward stroke at φ = {_deg(v['shuttle_start'])}, the needle is at "
                        f"its bottom dead centre at φ = {_deg(v['bdc'])}")


@_rule
class LoopReleasedBeforeReversal(_AngleRule):
    """The shuttle carries the loop round the bobbin case to its cast-off (``stitch.loop_release`` past the
    needle) before it turns back: its turn from the needle to its next reversal, at least the loop release when
    the file gives no ``min``."""

    name = "loop_released_before_reversal"
    text = "shuttle turns past the loop release before it reverses"
    needs = ("hook_turn", "hook_fwd", "shuttle_back")
    roles = (NEEDLE_POINT, HOOK_POINT)
    lacks = "the machine needs a needle_point and a hook_point on a shuttle"

    def measure(self, rule, tm, st, machine, ge):
        v = tm.values
        return Measured(v["hook_turn"], f"the shuttle turns this far from the needle (φ = {_deg(v['hook_fwd'])}) to "
                                        f"its reversal (φ = {_deg(v['shuttle_back'])}); the loop is cast off "
                                        f"{math.degrees(st.loop_release):g}° past the needle")

    def limits(self, rule, st, ge):
        return (st.loop_release if rule.lo is None else rule.lo), rule.hi


@_rule
class DogSinksBeforeNeedleEnters(_AngleRule):
    """Repair guides: the feed dog sinks below the throat plate about when the needle point reaches the cloth
    (DOMAIN-NOTES; seed 001's sink lead): the needle entering the cloth minus the dog sinking."""

    name = "dog_sinks_before_needle_enters"
    text = "feed dog below the plate before the needle enters"
    needs = ("needle_in_cloth", "dog_down")
    roles = (NEEDLE_POINT, FEED_DOG, THROAT_PLATE)
    lacks = "the machine needs a needle_point, a feed_dog and a throat_plate"

    def measure(self, rule, tm, st, machine, ge):
        v = tm.values
        return Measured(_wrap(v["needle_in_cloth"] - v["dog_down"]),
                        f"the feed dog sinks below the plate at φ = {_deg(v['dog_down'])}, the needle point enters "
                        f"the cloth at φ = {_deg(v['needle_in_cloth'])}")


@_rule
class DogRisesAfterNeedleLeaves(_AngleRule):
    """Repair guides: the feed dog rises above the plate after the needle has left the cloth (DOMAIN-NOTES;
    seed 001's rise lag): the dog rising minus the needle point leaving the cloth."""

    name = "dog_rises_after_needle_leaves"
    text = "feed dog above the plate after the needle leaves"
    needs = ("needle_out_cloth", "dog_up")
    roles = (NEEDLE_POINT, FEED_DOG, THROAT_PLATE)
    lacks = "the machine needs a needle_point, a feed_dog and a throat_plate"

    def measure(self, rule, tm, st, machine, ge):
        v = tm.values
        return Measured(_wrap(v["dog_up"] - v["needle_out_cloth"]),
                        f"the needle point leaves the cloth at φ = {_deg(v['needle_out_cloth'])}, the feed dog "
                        f"rises above the plate at φ = {_deg(v['dog_up'])}")


@_rule
class TakeUpRisesAfterRelease(_AngleRule):
    """The link take-up descends, giving thread, while the loop is enlarged and cast off, and rises after it is
    released (Singer US 462 398; lockstitch texts): the take-up's lowest point minus the loop's cast-off."""

    name = "take_up_rises_after_release"
    text = "take-up gives thread until the loop is cast off"
    needs = ("take_up_bottom", "release")
    roles = (THREAD_EYE, NEEDLE_POINT, HOOK_POINT)
    lacks = "the machine needs a thread_eye, a needle_point and a hook_point"

    def measure(self, rule, tm, st, machine, ge):
        v = tm.values
        return Measured(_wrap(v["take_up_bottom"] - v["release"]),
                        f"the loop is cast off at φ = {_deg(v['release'])}, the take-up is lowest (starts to rise) "
                        f"at φ = {_deg(v['take_up_bottom'])}")


@_rule
class StitchSetBeforeNeedleEnters(_AngleRule):
    """The take-up sets the stitch before the needle comes down again (lockstitch texts; seed 001 times the
    needle against the take-up's top): the needle point entering the cloth minus the take-up's top."""

    name = "stitch_set_before_needle_enters"
    text = "take-up sets the stitch before the needle enters"
    needs = ("take_up_top", "needle_in_cloth")
    roles = (THREAD_EYE, NEEDLE_POINT, THROAT_PLATE)
    lacks = "the machine needs a thread_eye, a needle_point and a throat_plate"

    def measure(self, rule, tm, st, machine, ge):
        v = tm.values
        return Measured(_wrap(v["needle_in_cloth"] - v["take_up_top"]),
                        f"the take-up is at its top (stitch set) at φ = {_deg(v['take_up_top'])}, the needle point "
                        f"enters the cloth at φ = {_deg(v['needle_in_cloth'])}")


@_rule
class TakeUpRise(_AngleRule):
    """The link take-up descends slowly over about three quarters of a turn and rises fast over about a quarter
    (Singer US 462 398; DOMAIN-NOTES): its rise, bottom to top (a span, not wrapped)."""

    name = "take_up_rise"
    text = "take-up rises fast"
    needs = ("take_up_top", "take_up_bottom")
    roles = (THREAD_EYE,)
    lacks = "the machine needs a thread_eye"

    def measure(self, rule, tm, st, machine, ge):
        v = tm.values
        return Measured((v["take_up_top"] - v["take_up_bottom"]) % TWO_PI,
                        f"the take-up rises from φ = {_deg(v['take_up_bottom'])} to φ = {_deg(v['take_up_top'])}")


@_rule
class TakeUpRisesOver(_AngleRule):
    """The take-up rises over the whole stitch-setting window (``from``, ``to`` in the model file): how far its
    rise overlaps the window on both sides, min(from − bottom, top − to)."""

    name = "take_up_rises_over"
    text = "take-up rising over the stitch-setting window"
    needs = ("take_up_top", "take_up_bottom")
    roles = (THREAD_EYE,)
    lacks = "the machine needs a thread_eye"
    window = True

    def measure(self, rule, tm, st, machine, ge):
        v = tm.values
        f, t = rule.window
        b, top = v["take_up_bottom"], v["take_up_top"]
        span = (top - b) % TWO_PI
        m1 = (f - b) % TWO_PI
        m2 = span - ((t - b) % TWO_PI)
        return Measured(min(m1 if m1 <= span else m1 - TWO_PI, m2),
                        f"the take-up rises from φ = {_deg(b)} to φ = {_deg(top)}; the window is "
                        f"φ = {_deg(f)} – {_deg(t)}")


@_rule
class ThreadSlack(TimingRule):
    """The take-up supplies the thread each stitch needs, and the loop must not pull thread through the tension
    while the hook carries it (seed 004): the least slack S − D + T then (sewgen.machine.thread)."""

    name = "thread_slack"
    text = "thread slack while the hook carries the loop"

    def measure(self, rule, tm, st, machine, ge):
        th = tm.thread
        if th is None:
            return "the machine declares no thread path ([[thread.guides]])"
        return Measured(th.min_slack, f"the least slack S − D + T while the hook carries the loop "
                                      f"(φ = {_deg(th.window[0])} – {_deg(th.window[1])}) is at "
                                      f"φ = {_deg(th.min_slack_at)}")


@_rule
class LowerLooperAtNeedleRise(_NeedleRiseAtTaker):
    """Overlock: the lower looper's tip takes the needle loop from behind the needle as the needle rises from its
    bottom dead centre (JUKI MO-104D engineer's manual, 'loop lift'; Janome MyLock 213D service manual)."""

    name = "lower_looper_at_needle_rise"
    text = "needle rise from BDC when the lower looper reaches the needle"
    role, event, taker = LOWER_LOOPER_TIP, "lower_fwd", "the lower looper's tip"
    roles = (NEEDLE_POINT, LOWER_LOOPER_TIP)
    lacks = "the machine needs a needle_point and a lower_looper_tip"


@_rule
class LowerLooperAboveEye(_TakerAboveEye):
    """Overlock: the lower looper's tip passes just above the needle eye's top, as a hook's point does
    (DOMAIN-NOTES; JUKI LU-2210N-7)."""

    name = "lower_looper_above_eye"
    text = "lower looper tip above the needle eye's top at the needle"
    role, event, at, who = LOWER_LOOPER_TIP, "lower_fwd", "lower looper tip at the needle", "the tip"
    roles = (NEEDLE_POINT, LOWER_LOOPER_TIP)
    lacks = "the machine needs a needle_point and a lower_looper_tip"


@_rule
class LowerLooperPassesLevel(TimingRule):
    """Overlock: the lower looper's blade point meets the needle at one height going and coming back (JUKI
    MO-104D engineer's manual): the needle's height at the return pass minus at the forward pass."""

    name = "lower_looper_passes_level"
    text = "needle height at the lower looper's return minus forward pass"
    needs = ("lower_ret", "lower_fwd")
    roles = (NEEDLE_POINT, LOWER_LOOPER_TIP)
    lacks = "the lower looper must pass the needle forward and back"

    def measure(self, rule, tm, st, machine, ge):
        v = tm.values
        return Measured(v["needle_at_lower_ret"] - v["needle_at_lower_fwd"],
                        f"the lower looper's tip passes the needle forward at φ = {_deg(v['lower_fwd'])} and back "
                        f"at φ = {_deg(v['lower_ret'])}; the needle's height then differs by")


@_rule
class UpperTakesLowerThread(TimingRule):
    """Overlock (ISO 4915 stitch types 504/505): the rising upper looper passes behind the lower looper, between
    its blade and its thread, while the lower looper stands beyond the needle: how far the lower looper's tip
    stands beyond the needle's line (the way it went) when the upper looper's tip rises past its height."""

    name = "upper_takes_lower_thread"
    text = "lower looper beyond the needle as the upper looper passes it"
    needs = ("upper_meets_lower",)
    roles = (NEEDLE_POINT, LOWER_LOOPER_TIP, UPPER_LOOPER_TIP)
    lacks = "the machine needs an upper_looper_tip that rises past the lower_looper_tip"

    def measure(self, rule, tm, st, machine, ge):
        v = tm.values
        return Measured(v["lower_beyond_at_meet"],
                        f"the upper looper's tip rises past the lower looper's at φ = {_deg(v['upper_meets_lower'])} "
                        f"(the lower looper at its far end at φ = {_deg(v['lower_far'])}); the lower tip is this far "
                        f"beyond the needle")


@_rule
class NeedleInUpperTriangle(TimingRule):
    """Overlock (ISO 4915 stitch types 504/505): the needle, coming down, enters the triangle of the upper
    looper's thread, held beyond the needle over the material's edge: how far the upper looper's tip stands
    beyond the needle's line (the way it went) when the needle point enters the material."""

    name = "needle_in_upper_triangle"
    text = "upper looper beyond the needle as the needle enters"
    needs = ("needle_at_upper", "upper_top")
    roles = (NEEDLE_POINT, LOWER_LOOPER_TIP, UPPER_LOOPER_TIP, THROAT_PLATE)
    lacks = "the machine needs an upper_looper_tip, a needle_point and a throat_plate"

    def measure(self, rule, tm, st, machine, ge):
        v = tm.values
        return Measured(v["upper_beyond_at_needle"],
                        f"the needle point enters the material at φ = {_deg(v['needle_at_upper'])} (the upper looper "
                        f"at its top at φ = {_deg(v['upper_top'])}, its tip "
                        f"{v['upper_above_cloth_at_needle'] * 1e3:.2f} mm above the material then); the tip is this "
                        f"far beyond the needle")


@_rule
class UpperAboveMaterial(TimingRule):
    """Overlock (ISO 4915 stitch types 504/505): the upper looper holds its thread above the material when the
    needle enters it: its tip's height above the material then."""

    name = "upper_above_material"
    text = "upper looper tip above the material as the needle enters"
    needs = ("needle_at_upper", "upper_top")
    roles = (NEEDLE_POINT, LOWER_LOOPER_TIP, UPPER_LOOPER_TIP, THROAT_PLATE)
    lacks = "the machine needs an upper_looper_tip, a needle_point and a throat_plate"

    def measure(self, rule, tm, st, machine, ge):
        v = tm.values
        return Measured(v["upper_above_cloth_at_needle"],
                        f"the needle point enters the material at φ = {_deg(v['needle_at_upper'])}; the upper "
                        f"looper's tip (at its top at φ = {_deg(v['upper_top'])}) is this far above the material")


# -- results ---------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Event:
    """A stitch-formation event: what happens, the machine's shaft angle (rad, in [0, 2π)), the mechanism
    part it concerns (``role``) and a note (a value at that moment)."""

    name: str
    angle: float
    role: str = ""
    note: str = ""

    @property
    def deg(self) -> float:
        return math.degrees(self.angle) % 360.0


@dataclass(frozen=True)
class Check:
    """One rule checked: its value and limits in the unit shown (mm, deg), pass or fail, a message naming the
    rule and the angles it was measured at, the rule's source."""

    rule: str
    value: float
    lo: float | None
    hi: float | None
    unit: str
    ok: bool
    message: str
    source: str = ""

    @property
    def limit(self) -> str:
        if self.lo is not None and self.hi is not None:
            return f"{self.lo:g} – {self.hi:g} {self.unit}"
        return f"≥ {self.lo:g} {self.unit}" if self.lo is not None else f"≤ {self.hi:g} {self.unit}"

    @property
    def margin(self) -> float:
        """The distance to the nearer limit, positive inside (the unit shown)."""
        m = math.inf
        if self.lo is not None:
            m = min(m, self.value - self.lo)
        if self.hi is not None:
            m = min(m, self.hi - self.value)
        return m


@dataclass(frozen=True)
class Phase:
    """A bar of the cycle diagram: mechanism row, what it does, from and to (rad, wrapping through 360°)."""

    row: str
    name: str
    start: float
    end: float
    style: str = "main"  # "main" (the row's phases), "inner" (a narrower bar inside: e.g. the feed stroke)


@dataclass
class Timing:
    """Events, phases and rule checks of one machine over one revolution (see the module docstring)."""

    machine: object
    phi: np.ndarray
    speed: float
    events: list
    checks: list
    phases: list
    thread: object = None  # sewgen.machine.thread.ThreadControl, when the machine declares a thread path
    values: dict = field(default_factory=dict)  # named angles (rad) and lengths (m) the rules used
    motions: dict = field(default_factory=dict, repr=False)  # group -> Motion of the timing sweep

    @property
    def failed(self) -> list:
        return [c for c in self.checks if not c.ok]

    @property
    def ok(self) -> bool:
        return not self.failed

    def event(self, name: str) -> Event:
        for e in self.events:
            if e.name == name:
                return e
        raise KeyError(f"no event {name!r}; events: {', '.join(e.name for e in self.events)}")

    def check(self, rule: str) -> Check:
        for c in self.checks:
            if c.rule == rule:
                return c
        raise KeyError(f"no check of rule {rule!r}; checked: {', '.join(c.rule for c in self.checks)}")

    def as_dict(self) -> dict:
        """summary.json's ``timing``: events (name, angle_deg) and checks (rule, value, limit, unit, ok); the value
        of a rule that cannot be checked (a part missing: its message says which) is None."""
        out = {"events": [{"name": e.name, "angle_deg": round(float(e.deg), 3), "note": e.note} for e in self.events],
               "checks": [{"rule": c.rule, "value": round(c.value, 4) if math.isfinite(c.value) else None,
                           "limit": [c.lo, c.hi], "unit": c.unit, "ok": c.ok, "message": c.message,
                           "source": c.source} for c in self.checks]}
        if self.thread is not None:
            out["thread"] = self.thread.as_dict()
        return out

    def table(self) -> str:
        """The event table and the rule checks as text (``sewgen timing``)."""
        lines = [f"{self.machine.name}: stitch-formation timing at {self.speed * 30 / math.pi:.0f} rpm "
                 f"(shaft angle φ; events to 0.01°)", "", f"{'φ (deg)':>8s}  event"]
        for e in sorted(self.events, key=lambda e: e.deg):
            lines.append(f"{e.deg:8.2f}  {e.name}" + (f"  ({e.note})" if e.note else ""))
        lines += ["", f"{'rule':34s} {'value':>10s} {'limit':>16s}  {'margin':>8s}  result"]
        for c in self.checks:
            lines.append(f"{c.rule:34s} {c.value:10.3f} {c.limit:>16s}  {c.margin:8.3f}  "
                         f"{'pass' if c.ok else 'FAIL'}")
        if self.thread is not None:
            lines += [""] + self.thread.lines()
        bad = self.failed
        lines += ["", f"{len(self.checks) - len(bad)} of {len(self.checks)} rules pass"]
        lines += [f"FAIL {c.message}" for c in bad]
        return "\n".join(lines)


# -- interpolation on a sweep -----------------------------------------------------------------------------------

def _deriv(phi, y, dy, d2y):
    """(Series of y, Series of dy/dφ) from values and their first and second shaft-angle derivatives."""
    return Series(phi, y, dy), Series(phi, dy, d2y)


def _wrap(a: float) -> float:
    """An angle difference (rad) in (−π, π]."""
    return -((-a + math.pi) % TWO_PI - math.pi)


def _after(angles: list, start: float) -> list:
    """``angles`` (rad) ordered by how far they come after ``start`` going round."""
    return sorted(angles, key=lambda a: (a - start) % TWO_PI)


def _first_after(found: list, start: float, sign: int | None = None):
    cands = [a for a, s in found if sign is None or s == sign]
    return _after(cands, start)[0] if cands else None


# -- the analysis ------------------------------------------------------------------------------------------------

def plate_level(machine):
    """The throat plate's height (m) from the first group with a ``throat_plate`` role, or None."""
    for g in machine.groups:
        if g.mechanism.description.has_role(THROAT_PLATE):
            return float(_to_machine(g, 0.0, plate_height(g.mechanism, g.params or None))[1])
    return None


def _to_machine(g, x, y):
    """(X, Y, Z) of a group's point in the machine frame (groups without a placement: their own x, y)."""
    place = getattr(g, "to_machine", None)
    return place(x, y) if place is not None else (x, y, 0.0 * np.asarray(x))


class _Point:
    """A role point's position and its shaft-angle derivatives in the machine frame (``group``'s placement), as
    Series: x, y, and z (along the shaft)."""

    def __init__(self, phi, motion, name, w, group=None):
        p = motion.point(name)
        zero = 0.0 * p.x
        if group is None or not hasattr(group, "to_machine"):
            pos, vel, acc = (p.x, p.y, zero), (p.vx, p.vy, zero), (p.ax, p.ay, zero)
        else:  # positions placed, velocities and accelerations turned
            pos = group.to_machine(p.x, p.y)
            vel, acc = group.force_to_machine(p.vx, p.vy, zero), group.force_to_machine(p.ax, p.ay, zero)
        (self.x, self.dx), (self.y, self.dy), (self.z, self.dz) = (
            _deriv(phi, c + zero, v / w, a / w**2) for c, v, a in zip(pos, vel, acc))
        self.raw = p

    def lateral(self, g):
        """(Series, its derivative) across the needle in group ``g``'s plane: z for an "along" group, else x."""
        return (self.z, self.dz) if getattr(g, "along", False) else (self.x, self.dx)


def timing(machine, speed: float | None = None, step_deg: float = STEP_DEG, motions: dict | None = None) -> Timing:
    """Events, phases and rule checks of ``machine`` (a sewgen.machine.Machine) on a sweep of ``step_deg`` at
    constant ``speed`` (rad/s; default the machine's). ``motions`` (group -> Motion on that sweep) reuses a
    sweep already made."""
    w = float(machine.speed if speed is None else speed)
    n = int(round(360.0 / step_deg))
    phi = TWO_PI * np.arange(n) / n
    if motions is None:
        motions = machine.kinematics(phi, speed=w)
    st = getattr(machine, "stitch", None) or Stitch()
    events, phases, values = [], [], {}
    ev = (lambda name, angle, role="", note="": events.append(Event(name, angle % TWO_PI, role, note)))  # noqa: E731

    # needle ----------------------------------------------------------------------------------------------------
    gn, npt = role_group(machine, NEEDLE_POINT)
    ge, _ = role_group(machine, NEEDLE_EYE)
    plate = plate_level(machine)
    needle = None
    if gn is not None:
        needle = _Point(phi, motions[gn.name], npt, w, gn)
        top = [a for a, s in needle.dy.crossings() if s == -1]
        bdc = [a for a, s in needle.dy.crossings() if s == 1]
        if len(top) != 1 or len(bdc) != 1:
            raise TimingError(f"{machine.name}: the needle point must rise and fall once a turn "
                              f"({len(top)} tops, {len(bdc)} bottoms)")
        values["tdc"], values["bdc"] = top[0], bdc[0]
        ev("needle top dead centre", top[0], NEEDLE_POINT, f"point {needle.y.at(top[0]) * 1e3:.2f} mm")
        ev("needle bottom dead centre", bdc[0], NEEDLE_POINT, f"point {needle.y.at(bdc[0]) * 1e3:.2f} mm")
        y_bdc = needle.y.at(bdc[0])
        lift = _first_after(needle.y.crossings(y_bdc + st.loop_lift), bdc[0], 1)
        if lift is not None:  # (a loop lift beyond the stroke never comes)
            values["loop_lift"] = lift
            ev(f"loop lift: needle risen {st.loop_lift * 1e3:g} mm", lift, NEEDLE_POINT)
        if plate is not None:
            cloth = plate + st.cloth
            values["cloth_top"], values["plate"] = cloth, plate
            for level, what in ((cloth, "cloth"), (plate, "throat plate")):
                cr = needle.y.crossings(level)
                down, up = _first_after(cr, top[0], -1), _first_after(cr, bdc[0], 1)
                if down is None or up is None:
                    raise TimingError(f"{machine.name}: the needle point never goes below the {what}")
                key = "cloth" if what == "cloth" else "plate"
                values[f"needle_in_{key}"], values[f"needle_out_{key}"] = down, up
                ev(f"needle point into the {what}" if key == "cloth" else "needle point through the throat plate",
                   down, NEEDLE_POINT)
                ev(f"needle point out of the {what}" if key == "cloth" else "needle point back up through the plate",
                   up, NEEDLE_POINT)
            phases.append(Phase("needle", "point in the cloth", values["needle_in_cloth"],
                                values["needle_out_cloth"]))
            phases.append(Phase("needle", "point above the cloth", values["needle_out_cloth"],
                                values["needle_in_cloth"]))
        phases.append(Phase("needle", "rising", bdc[0], top[0], "inner"))

    # hook / shuttle --------------------------------------------------------------------------------------------
    gh, hpt = role_group(machine, HOOK_POINT)
    hook = None
    if gh is not None and needle is not None:
        hook = _Point(phi, motions[gh.name], hpt, w, gh)
        body = gh.mechanism.description.point(hpt).body
        bm = motions[gh.name].body(body)
        theta = np.unwrap(bm.angle)
        ang, dang = _deriv(phi, theta, bm.omega / w, bm.alpha / w**2)
        rel = Series(phi, hook.x.y - needle.x.y, hook.x.dy - needle.x.dy)
        # crossings of the needle's centre line within the needle's reach (not the far side of a rotary hook)
        near = [(a, s) for a, s in rel.crossings() if abs(hook.y.at(a) - needle.y.at(a)) < 0.03]
        fwd = _first_after(near, values["bdc"])
        if fwd is None:
            raise TimingError(f"{machine.name}: the hook point never crosses the needle's centre line")
        fsign = next(s for a, s in near if a == fwd)
        ret = _first_after([(a, s) for a, s in near if s != fsign], fwd)
        revs = [a for a, s in dang.crossings()]
        if len(revs) < 2:
            raise TimingError(f"{machine.name}: the hook ({body}) turns round without reversing: not a shuttle")
        start = _after(revs, fwd)[-1]  # the reversal before the forward pass
        back = _after(revs, fwd)[0]  # the next one after it
        values.update(hook_fwd=fwd, shuttle_start=start, shuttle_back=back)
        if ret is not None:
            values["hook_ret"] = ret
        turn = abs(ang.at(back) - ang.at(fwd))
        values["hook_turn"] = turn
        speed_ratio = dang.at(fwd)
        ev("shuttle reverses: starts its forward stroke", start, HOOK_POINT)
        ev("hook point at the needle (forward pass, picks up the loop)", fwd, HOOK_POINT,
           f"hook {abs(speed_ratio):.2f} × shaft speed")
        ev("shuttle reverses: starts its return", back, HOOK_POINT, f"{math.degrees(turn):.1f}° past the needle")
        if ret is not None:
            ev("hook point at the needle (return pass)", ret, HOOK_POINT)
        release = None
        if turn >= st.loop_release:
            a0 = ang.at(fwd)
            cr = Series(phi, np.abs(theta - a0) - st.loop_release, np.sign(theta - a0) * bm.omega / w).crossings()
            release = _first_after([(a, s) for a, s in cr if s == 1], fwd)
        values["release"] = release if release is not None else back
        ev(f"loop cast off: shuttle {math.degrees(st.loop_release):.0f}° past the needle" if release is not None
           else "loop cast off (not reached before the shuttle reverses)", values["release"], HOOK_POINT)
        phases.append(Phase("shuttle", "forward stroke", start, back))
        phases.append(Phase("shuttle", "return stroke", back, start))
        phases.append(Phase("shuttle", "carries the loop", fwd, values["release"], "inner"))

    # take-up ----------------------------------------------------------------------------------------------------
    gt, tpt = role_group(machine, THREAD_EYE)
    if gt is not None:
        te = _Point(phi, motions[gt.name], tpt, w, gt)
        hi = [a for a, s in te.dy.crossings() if s == -1]
        lo = [a for a, s in te.dy.crossings() if s == 1]
        k_hi = max(hi, key=te.y.at) if hi else None
        k_lo = min(lo, key=te.y.at) if lo else None
        if k_hi is None or k_lo is None:
            raise TimingError(f"{machine.name}: the take-up's thread eye must rise and fall")
        values["take_up_top"], values["take_up_bottom"] = k_hi, k_lo
        stroke = te.y.at(k_hi) - te.y.at(k_lo)
        ev("take-up top (stitch set)", k_hi, THREAD_EYE, f"eye {te.y.at(k_hi) * 1e3:.2f} mm")
        ev("take-up bottom", k_lo, THREAD_EYE, f"{stroke * 1e3:.2f} mm below its top")
        phases.append(Phase("take-up", "descends: gives thread", k_hi, k_lo))
        phases.append(Phase("take-up", "rises: takes up, sets the stitch", k_lo, k_hi))

    # feed dog ----------------------------------------------------------------------------------------------------
    gf, fpt = role_group(machine, FEED_DOG)
    if gf is not None and plate is not None:
        dog = _Point(phi, motions[gf.name], fpt, w, gf)
        cr = dog.y.crossings(plate)
        up, down = [a for a, s in cr if s == 1], [a for a, s in cr if s == -1]
        if len(up) != 1 or len(down) != 1:
            raise TimingError(f"{machine.name}: the feed dog must rise above the plate once a turn "
                              f"(rises {len(up)}, sinks {len(down)})")
        values["dog_up"], values["dog_down"] = up[0], down[0]
        ev("feed dog rises above the plate", up[0], FEED_DOG)
        ev("feed dog sinks below the plate", down[0], FEED_DOG,
           f"{(dog.y.y.max() - plate) * 1e3:.2f} mm above it at most")
        phases.append(Phase("feed dog", "above the plate", up[0], down[0]))
        phases.append(Phase("feed dog", "below the plate", down[0], up[0]))
        travel = dog.x.at(down[0]) - dog.x.at(up[0])
        x, span = dog.x.y, float(np.ptp(dog.x.y))
        if span > 1e-6:
            sign = 1 if travel >= 0 else -1
            a = dog.x.crossings(x.min() + 0.01 * span if sign > 0 else x.max() - 0.01 * span)
            b = dog.x.crossings(x.max() - 0.01 * span if sign > 0 else x.min() + 0.01 * span)
            s0, s1 = _first_after(a, up[0] - math.pi, sign), None  # the stroke round the dog's time up
            if s0 is not None:
                s1 = _first_after(b, s0, sign)
            if s0 is not None and s1 is not None:
                values["feed_start"], values["feed_end"] = s0, s1
                ev("feed starts (dog leaves its rearmost position)", s0, FEED_DOG)
                ev("feed ends", s1, FEED_DOG, f"cloth moved {abs(travel) * 1e3:.2f} mm")
                phases.append(Phase("feed dog", "feed stroke", s0, s1, "inner"))

    # overlock loopers ---------------------------------------------------------------------------------------------
    gl, lpt = role_group(machine, LOWER_LOOPER_TIP)
    gu, upt = role_group(machine, UPPER_LOOPER_TIP)
    if gl is not None and needle is not None:
        _loopers(machine, phi, w, motions, needle, gl, lpt, gu, upt, values, ev, phases, ge)

    tm = Timing(machine, phi, w, events, [], phases, None, values, motions)
    thread_cfg = getattr(machine, "thread", None)
    if thread_cfg is not None and needle is not None:

        tm.thread = thread_control(machine, motions, tm, thread_cfg, st)
    tm.checks = [RULES[r.kind].check(r, tm, st, machine, ge) for r in st.rules]
    return tm


def _loopers(machine, phi, w, motions, needle, gl, lpt, gu, upt, values, ev, phases, ge):
    """The overlock's looper events (ISO 504/505): the lower looper's tip passes behind the needle as the needle
    rises from BDC (it takes the needle loop), reaches its far end, where the rising upper looper passes it and
    enters its thread; the upper looper's tip reaches over beyond the needle, and the descending needle enters
    its thread triangle; the lower looper returns past the needle."""
    low = _Point(phi, motions[gl.name], lpt, w, gl)
    lat, dlat = low.lateral(gl)
    nlat, _ = needle.lateral(gl)
    rel = Series(phi, lat.y - nlat.y, lat.dy - nlat.dy)
    near = [(a, s) for a, s in rel.crossings() if abs(low.y.at(a) - needle.y.at(a)) < 0.03]
    fwd = _first_after(near, values["bdc"])
    if fwd is None:
        raise TimingError(f"{machine.name}: the lower looper's tip never crosses the needle's centre line")
    fsign = next(s for a, s in near if a == fwd)
    ret = _first_after([(a, s) for a, s in near if s != fsign], fwd)
    ends = [(a, s) for a, s in dlat.crossings()]
    far = _first_after(ends, fwd)  # the reversal at its far end
    values.update(lower_fwd=fwd, lower_far=far, lower_sign=fsign)
    y_fwd = needle.y.at(fwd)
    ev("lower looper tip at the needle (forward pass, takes the needle loop)", fwd, LOWER_LOOPER_TIP,
       f"needle risen {(y_fwd - needle.y.at(values['bdc'])) * 1e3:.2f} mm")
    if far is not None:
        ev("lower looper at its far end", far, LOWER_LOOPER_TIP,
           f"tip {abs(lat.at(far) - nlat.at(far)) * 1e3:.2f} mm beyond the needle")
    if ret is not None:
        values["lower_ret"] = ret
        values["needle_at_lower_fwd"], values["needle_at_lower_ret"] = y_fwd, needle.y.at(ret)
        ev("lower looper tip at the needle (return pass)", ret, LOWER_LOOPER_TIP)
        phases.append(Phase("lower looper", "beyond the needle", fwd, ret))
        phases.append(Phase("lower looper", "returning, behind", ret, fwd))
    near_end = _first_after(ends, ret if ret is not None else fwd)
    if far is not None and near_end is not None:
        phases.append(Phase("lower looper", "forward stroke", near_end, far, "inner"))
    if gu is None:
        return
    up = _Point(phi, motions[gu.name], upt, w, gu)
    ulat, _ = up.lateral(gl)
    # the upper looper's tip rising through the lower looper tip's height: it enters the lower looper's thread
    cross = Series(phi, up.y.y - low.y.y, up.y.dy - low.y.dy).crossings()
    meet = _first_after([(a, s) for a, s in cross if s == 1], fwd)
    if meet is not None:
        values["upper_meets_lower"] = meet
        values["lower_beyond_at_meet"] = fsign * (lat.at(meet) - nlat.at(meet))
        ev("upper looper tip rises past the lower looper (takes its thread)", meet, UPPER_LOOPER_TIP,
           f"lower looper tip {values['lower_beyond_at_meet'] * 1e3:.2f} mm beyond the needle")
    tops = [a for a, s in up.dy.crossings() if s == -1]
    bots = [a for a, s in up.dy.crossings() if s == 1]
    if tops and bots:
        top, bot = max(tops, key=up.y.at), min(bots, key=up.y.at)
        values["upper_top"], values["upper_bottom"] = top, bot
        ev("upper looper at its top", top, UPPER_LOOPER_TIP, f"tip {up.y.at(top) * 1e3:.2f} mm")
        ev("upper looper at its bottom", bot, UPPER_LOOPER_TIP, f"tip {up.y.at(bot) * 1e3:.2f} mm")
        phases.append(Phase("upper looper", "rising", bot, top))
        phases.append(Phase("upper looper", "falling", top, bot))
        # its way over the needle: the sign of its lateral motion while it rises
        usign = 1 if ulat.at(top) - ulat.at(bot) > 0 else -1
        values["upper_sign"] = usign
        beyond = Series(phi, usign * (ulat.y - nlat.y), usign * (ulat.dy - nlat.dy))
        over = [(a, s) for a, s in beyond.crossings()]
        on, off = _first_after(over, bot, 1), None
        if on is not None:
            off = _first_after(over, on, -1)
        if on is not None and off is not None:
            phases.append(Phase("upper looper", "beyond the needle", on, off, "inner"))
        # the needle point entering the material: the upper looper's thread must lie across its line, from the
        # tip beyond the needle back over the material's edge (the needle enters the thread triangle)
        enter = values.get("needle_in_cloth")
        if enter is not None:
            values["needle_at_upper"] = enter
            values["upper_beyond_at_needle"] = usign * (ulat.at(enter) - nlat.at(enter))
            values["upper_above_cloth_at_needle"] = up.y.at(enter) - values["cloth_top"]


# -- the taker at the needle ------------------------------------------------------------------------------------

def _taker_at_needle(tm: Timing, machine, ge, v: dict, event: str, taker_role: str):
    """Where a loop taker (hook point, looper tip: ``taker_role``) meets the needle's centre line, at event
    ``event`` of ``v``: (its angle, the needle point's rise from bottom dead centre then, the taker's height
    above the needle eye's top then — None without a needle_eye group ``ge``)."""
    a = v[event]
    gn, npt = role_group(machine, NEEDLE_POINT)
    gt, tpt = role_group(machine, taker_role)
    rise = _interp_point(tm, gn, npt, a)[1] - _interp_point(tm, gn, npt, v["bdc"])[1]
    if ge is None:
        return a, rise, None
    _, eye = role_group(machine, NEEDLE_EYE)
    d = ge.mechanism.description
    half = 0.5 * role_param(ge, NEEDLE_EYE_LENGTH) if d.has_role(NEEDLE_EYE_LENGTH) else 0.0
    return a, rise, _interp_point(tm, gt, tpt, a)[1] - (_interp_point(tm, ge, eye, a)[1] + half)


def _interp_point(tm: Timing, g, name, angle):
    """(x, y) of point ``name`` of group ``g`` at shaft angle ``angle``, Hermite-interpolated on tm's sweep."""
    p = _Point(tm.phi, tm.motions[g.name], name, tm.speed, g)
    return p.x.at(angle), p.y.at(angle)


__all__ = ["Check", "Event", "Measured", "Phase", "RULES", "Rule", "Stitch", "Timing", "TimingError", "TimingRule",
           "timing"]

"""Stitch length of the feed mechanism: feed-dog travel above the throat plate, and the regulator angle for it.

The stitch length is the feed dog's horizontal travel while it is above the throat plate (seed 001 §五 3, the
feed-dog trajectory indices): the cloth moves only while the dog's teeth stand above the plate. The plate
crossings are found on a sweep by cubic Hermite interpolation in the shaft angle (positions and their exact
shaft-angle derivatives v/ω from the kinematics; the same pieces and root finder as the study indices and the
timing, :mod:`sewgen.hermite`), so the travel is accurate far below the sweep's step.

No SciPy here: this module runs when a machine with a feed loads (its stitch regulator is solved for the
model's stitch), and ``import scipy.optimize`` alone took 0.4–0.7 s of a 0.6 s ``sewgen analyze --no-plots``
(SciPy 1.17). The regulator's one scalar equation is solved by :func:`_root`, a bracketing secant.

Parts are found by role, so any feed mechanism works: the point with role ``feed_dog``, the parameter with role
``throat_plate`` (its height) and the held input with role ``stitch_regulator``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sewgen.errors import ParameterError
from sewgen.hermite import at, crossings
from sewgen.roles import FEED_DOG, STITCH_REGULATOR, THROAT_PLATE
from sewgen.units import UnitError, to_si


@dataclass(frozen=True)
class DogTravel:
    """Feed-dog travel above the plate (m; + forward) between the shaft angles where it rises and sinks (rad)."""

    travel: float
    rise: float
    sink: float
    height: float  # highest point above the plate (m)


def has_feed(mech) -> bool:
    """Whether ``mech`` declares a feed dog, a throat plate and a stitch regulator (by role)."""
    d = mech.description
    return all(d.has_role(r) for r in (FEED_DOG, THROAT_PLATE, STITCH_REGULATOR))


def plate_height(mech, params: dict | None = None) -> float:
    """The throat plate's height (m) in ``mech``'s frame: its ``throat_plate`` parameter with ``params``."""
    return float(mech.param_vector(params)[mech.description.role(THROAT_PLATE).index])


def dog_travel(motion, plate: float, point: str | None = None) -> DogTravel:
    """The travel of ``point`` (default: the mechanism's ``feed_dog``) above the plate height ``plate`` (m) over
    one revolution of ``motion`` (equal steps, one turn). The crossings are interpolated with the exact slopes
    v/ω; a sweep at rest (ω = 0) falls back on central differences."""
    point = point or motion.mechanism.description.role(FEED_DOG).name
    pt = motion.point(point)
    phi, w = motion.phi, motion.omega
    h = float(phi[1] - phi[0]) if len(phi) > 1 else 0.0
    if not h > 0 or not np.allclose(np.diff(phi), h) or abs(len(phi) * h - 2 * math.pi) > 1e-9:
        raise ParameterError(motion.mechanism.name, "shaft angles", "need one revolution in equal steps")
    z = pt.y - plate
    if np.all(w != 0):  # exact slopes d/dφ = v / ω
        dz, dx = pt.vy / w, pt.vx / w
    else:  # at rest (a static analysis) the velocities say nothing: periodic central differences
        dz = (np.roll(z, -1) - np.roll(z, 1)) / (2 * h)
        dx = (np.roll(pt.x, -1) - np.roll(pt.x, 1)) / (2 * h)
    _rows, steps, t, sign = crossings(z[None, :], dz[None, :], h)
    up, down = np.flatnonzero(sign > 0), np.flatnonzero(sign < 0)
    if len(up) != 1 or len(down) != 1:
        raise ParameterError(motion.mechanism.name, point,
                             f"must rise above the plate once a revolution (rises {len(up)}, sinks {len(down)})")
    k = np.array([up[0], down[0]])
    x0, x1 = at(pt.x[None, :], dx[None, :], h, np.zeros(2, int), steps[k], t[k])
    rise, sink = phi[steps[k]] + t[k]
    return DogTravel(float(x1 - x0), float(rise % (2 * math.pi)), float(sink % (2 * math.pi)), float(z.max()))


def stitch_length(mech, regulator, *, params: dict | None = None, step_deg: float = 1.0) -> DogTravel:
    """Dog travel above the plate at stitch-regulator setting ``regulator`` (rad or "30 deg")."""
    phi = np.radians(np.arange(0.0, 360.0, step_deg))
    held = {mech.description.role(STITCH_REGULATOR).name: regulator}
    motion = mech.solve(phi, speed=1.0, params=params, held=held)
    return dog_travel(motion, plate_height(mech, params))


#: The stitch regulator's working range (deg either side of zero) unless a caller states another: the catalog
#: feed's largest stitch, 4 mm (seed 000 §一(二)5), needs about 33°; beyond ±45° the regulator slot runs out.
REGULATOR_LIMIT_DEG = 45.0


def regulator_angle(mech, length, *, params: dict | None = None, limit_deg: float = REGULATOR_LIMIT_DEG,
                    step_deg: float = 1.0) -> float:
    """The stitch-regulator angle (rad) whose stitch is ``length`` (m or "4 mm"; negative: reverse feed), by
    a bracketing secant (:func:`_root`) within the regulator's range ±``limit_deg``. A stitch the regulator cannot
    reach within that range is a :class:`~sewgen.errors.ParameterError` naming the longest stitch it can."""
    try:
        length = to_si(length, "length", "stitch")
    except UnitError as exc:
        raise ParameterError(mech.name, "stitch", exc.problem) from None
    if not (isinstance(limit_deg, (int, float)) and 0 < limit_deg < 90):
        raise ParameterError(mech.name, "limit_deg", f"must be between 0 and 90 degrees, got {limit_deg!r}")
    f = (lambda a: stitch_length(mech, a, params=params, step_deg=step_deg).travel - length)
    lo, hi = -math.radians(limit_deg), math.radians(limit_deg)
    f_lo, f_hi = f(lo), f(hi)
    if not min(f_lo, f_hi) <= 0.0 <= max(f_lo, f_hi):
        reach = f_hi + length if length > 0 else f_lo + length
        raise ParameterError(mech.name, "stitch", f"{length * 1e3:.3g} mm is beyond the regulator's range "
                             f"(±{limit_deg:g}°: at most {abs(reach) * 1e3:.3g} mm "
                             f"{'forward' if length > 0 else 'reverse'})")
    return _root(f, lo, hi, f_lo, f_hi)


def _root(f, a, b, fa, fb, xtol: float = 1e-13, maxiter: int = 200) -> float:
    """A root of the continuous ``f`` between ``a`` and ``b`` (``fa``, ``fb``: f there, of opposite signs or
    zero), to ``xtol`` (rad here: 1e-13, below the 1e-12 the regulator was solved to with SciPy's ``brentq``).

    Regula falsi with the Anderson–Björck weighting (Anderson & Björck 1973, BIT 13: when the new point falls on
    the same side as the last one, the far end's value is scaled by 1 − f_new/f_last, or halved if that is not
    positive), so neither end sticks: superlinear on a smooth f such as the stitch against the regulator angle
    (about 8 evaluations from ±45°). The bracket always holds the root; a step that would leave it, or a
    bracket that fails to halve in three steps, falls back on bisection."""
    if fa == 0.0:
        return float(a)
    if fb == 0.0:
        return float(b)
    ref, steps = abs(b - a), 0  # the bracket's width three steps ago
    for _ in range(maxiter):
        c = b - fb * (b - a) / (fb - fa)  # the secant through the two ends
        steps += 1
        if steps > 3:
            slow, ref, steps = abs(b - a) > 0.5 * ref, abs(b - a), 0
        else:
            slow = False
        if slow or not min(a, b) < c < max(a, b):
            c = 0.5 * (a + b)
        fc = f(c)
        if fc == 0.0:
            return float(c)
        if (fc < 0.0) != (fb < 0.0):  # the root is between c and b: b becomes the far end
            a, fa = b, fb
        else:  # same side as b: keep a, its value weighted (Anderson-Björck)
            m = 1.0 - fc / fb
            fa *= m if m > 0.0 else 0.5
        b, fb = c, fc
        if abs(b - a) <= xtol:
            break
    return float(b)

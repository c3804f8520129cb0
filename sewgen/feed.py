"""Stitch length of the feed mechanism: feed-dog travel above the throat plate, and the regulator angle for it.

The stitch length is the feed dog's horizontal travel while it is above the throat plate (seed 001 §五 3, the
feed-dog trajectory indices): the cloth moves only while the dog's teeth stand above the plate. The plate
crossings are found on a sweep by cubic Hermite interpolation in the shaft angle (positions and their exact
shaft-angle derivatives v/ω from the kinematics), so the travel is accurate far below the sweep's step.

Parts are found by role, so any feed mechanism works: the point with role ``feed_dog``, the parameter with role
``throat_plate`` (its height) and the held input with role ``stitch_regulator``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .errors import ParameterError
from .hermite import hermite
from .roles import FEED_DOG, STITCH_REGULATOR, THROAT_PLATE
from .units import UnitError, to_si


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
    from scipy.optimize import brentq

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
    up = np.flatnonzero((z < 0) & (np.roll(z, -1) >= 0))
    down = np.flatnonzero((z >= 0) & (np.roll(z, -1) < 0))
    if len(up) != 1 or len(down) != 1:
        raise ParameterError(motion.mechanism.name, point,
                             f"must rise above the plate once a revolution (rises {len(up)}, sinks {len(down)})")

    def crossing(i):
        j = (i + 1) % len(phi)
        t = brentq(lambda t: hermite(z[i], z[j], dz[i], dz[j], h, t), 0.0, h, xtol=1e-15)
        return phi[i] + t, hermite(pt.x[i], pt.x[j], dx[i], dx[j], h, t)

    (rise, x0), (sink, x1) = crossing(int(up[0])), crossing(int(down[0]))
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
    Brent's method within the regulator's range ±``limit_deg``. A stitch the regulator cannot reach within
    that range is a :class:`~sewgen.errors.ParameterError` naming the longest stitch it can."""
    from scipy.optimize import brentq

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
    return brentq(f, lo, hi, xtol=1e-12)

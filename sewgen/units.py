"""Quantities with explicit units -> SI floats (DESIGN.md §5).

Model files and declarations state units ("16.7 mm", "105 g", "1000 rpm", "90 deg"); everything inside
sewgen is SI. This module is the one place that talks to the units library (pint). It is a leaf: the run-time
package and the derivation (:mod:`sewgen.derive`) both read it, and it imports nothing of either.

pint is imported and its registry built on the first quantity string, never at import: a sweep given SI
numbers never pays for it. The registry's parsed definitions are cached on disk (pint's own cache, under the
sewgen cache folder), which makes a later process's build several times faster.
"""
from __future__ import annotations

import functools
import math
import re
import threading

import numpy as np

from sewgen.errors import UnitError  # errors is a leaf too; re-exported here, where quantities are read

#: Physical kinds a parameter can have, with the SI unit its value is stored in.
SI_UNITS = {
    "length": "m",
    "angle": "rad",
    "mass": "kg",
    "inertia": "kg*m**2",
    "speed": "rad/s",
    "angular_acceleration": "rad/s**2",
    "acceleration": "m/s**2",
    "force": "N",
    "torque": "N*m",
    "stiffness": "N/m",
    "damping": "N*s/m",
    "torsional_stiffness": "N*m/rad",
    "mass_length": "kg*m",
    "density": "kg/m**3",
    "dimensionless": "",
}


#: Kinds whose text must name an angle unit: pint takes rad as dimensionless, so "100 Hz" would pass as
#: 100 rad/s where its writer most likely meant 100 revolutions per second.
_ANGULAR = ("speed", "angular_acceleration")



def _cache_folder():
    """pint's definition cache: ``$SEWGEN_CACHE/pint`` (default ``~/.cache/sewgen/pint``), or None if unusable."""
    import os
    from pathlib import Path

    folder = Path(os.environ.get("SEWGEN_CACHE", Path.home() / ".cache" / "sewgen")) / "pint"
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    return folder if os.access(folder, os.W_OK) else None


_REGISTRY = None
_REGISTRY_LOCK = threading.Lock()


def registry():
    """The one pint registry, built on first use, once even when several threads ask at the same time."""
    global _REGISTRY
    with _REGISTRY_LOCK:
        if _REGISTRY is None:
            import pint

            folder = _cache_folder()
            reg = None
            if folder is not None:
                try:
                    reg = pint.UnitRegistry(cache_folder=folder)
                except Exception:  # a damaged or foreign cache must not stop unit parsing: build without it
                    reg = None
            _REGISTRY = reg if reg is not None else pint.UnitRegistry()
        return _REGISTRY


#: A typical quantity of each kind, for messages ("give an angle with its unit, e.g. 5 deg").
EXAMPLES = {
    "length": "16.7 mm", "angle": "5 deg", "mass": "35 g", "inertia": "2e-6 kg*m**2", "speed": "1000 rpm",
    "angular_acceleration": "100 rad/s**2", "acceleration": "9.81 m/s**2", "force": "2.94 N", "torque": "0.5 N*m",
    "mass_length": "500 g*mm", "density": "7850 kg/m**3", "dimensionless": "0.5", "stiffness": "1.2 N/mm",
    "damping": "3 N*s/m", "torsional_stiffness": "0.05 N*m/rad",
}
#: The units a message suggests for each kind.
UNIT_HINTS = {
    "length": "mm or m", "angle": "deg or rad", "mass": "g or kg", "inertia": "kg*m**2", "speed": "rpm or rad/s",
    "angular_acceleration": "rad/s**2", "acceleration": "m/s**2", "force": "N", "torque": "N*m",
    "mass_length": "g*mm or kg*m", "density": "kg/m**3", "dimensionless": "no unit", "stiffness": "N/mm or N/m",
    "damping": "N*s/m", "torsional_stiffness": "N*m/rad or N*mm/deg",
}

#: The units declarations and model files use most, with their factor to SI and their kind: read without pint
#: (the derivation of the catalog needs no units library; pint's factors, so the values are pint's to the bit).
#: Any other unit, or one of these for another kind, goes through pint.
_COMMON = {
    "mm": (1e-3, "length"), "m": (1.0, "length"), "deg": (math.pi / 180, "angle"), "rad": (1.0, "angle"),
    "g": (1e-3, "mass"), "kg": (1.0, "mass"), "kg*m**2": (1.0, "inertia"), "N": (1.0, "force"),
    "N*m": (1.0, "torque"), "rpm": (2 * math.pi / 60, "speed"), "rad/s": (1.0, "speed"),
    "m/s**2": (1.0, "acceleration"),
}

#: Unit names read here otherwise than the units library would: "gr" is a grain to pint (64.8 mg) and a gram to
#: many a reader (a mass of "35 gr" meant 35 g would be 2.27 g): refused, saying which to write.
_AMBIGUOUS = {"gr": 'is ambiguous: pint reads it as grains (1 gr = 64.8 mg), many write it for grams: write "g" for '
                    'grams or "grain" for grains'}
#: The shaft-speed spellings of the trade: r/min (the SI brochure's, the README's), r/s, rev/min, rev/s.
_REVOLUTION = re.compile(r"(?<![A-Za-z_])(?:r|rev)(?![A-Za-z_0-9])")

#: The number a quantity string starts with: digits with a decimal point, an optional exponent; no thousands
#: separators, no decimal comma, no other digits than 0-9.
_NUMBER = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")


def _article(kind: str) -> str:
    return f"{'an' if kind[0] in 'aeiou' else 'a'} {kind.replace('_', ' ')}"


def to_si(value, kind: str, what: str = "value") -> float:
    """Convert ``value`` (a number taken as SI, or a string such as ``"16.7 mm"``) to an SI float.

    ``kind`` is a key of :data:`SI_UNITS`; ``what`` names the parameter or option in the error. A string must be
    a number (decimal point, optional exponent) followed by its unit: "1,5 mm", "mm", "" and a bare "5" (for a
    kind with a unit) are refused naming the value, never guessed.
    """
    if kind not in SI_UNITS:
        raise UnitError(what, f"unknown kind {kind!r}")
    if isinstance(value, (bool, np.bool_)):
        raise UnitError(what, f"expected {_article(kind)} ({SI_UNITS[kind] or 'no unit'}), got {value!r}")
    if isinstance(value, (int, float, np.integer, np.floating)):
        out = float(value)
    elif isinstance(value, str):
        out, problem = _parse(value.strip(), kind)
        if problem:
            raise UnitError(what, problem.format(value=_show(value)))
    else:
        raise UnitError(what, f"expected a number or a quantity string, got {type(value).__name__}")
    if not math.isfinite(out):
        raise UnitError(what, f"{_show(value) if isinstance(value, str) else value!r} is not finite")
    return out


def _show(text: str) -> str:
    """A value as it appears in a message: in double quotes (so that "" and "1,5 mm" stay visible)."""
    return '"' + text.replace('"', '\\"') + '"'


@functools.lru_cache(maxsize=4096)
def _parse(text: str, kind: str) -> tuple[float, str]:
    """(SI value, "") or (nan, problem text with a {value} slot): pint is slow, so each text is read once."""
    example = EXAMPLES[kind]
    m = _NUMBER.match(text)
    if not text:
        return math.nan, f"empty: expected {_article(kind)} with its unit, e.g. {_show(example)}"
    if m is None:
        return math.nan, (f"{{value}} does not start with a number: expected {_article(kind)} with its unit, "
                          f"e.g. {_show(example)}")
    number, unit = m.group(0), text[m.end():].strip()
    if unit[:1] in (",", "_", "'") or (unit[:1].isdigit()) or "," in unit:
        return math.nan, (f"cannot read {{value}}: write the number with a decimal point and no thousands "
                          f"separators, e.g. {_show(example)}")
    magnitude = float(number)
    target = SI_UNITS[kind]
    if not unit:
        if kind == "dimensionless":
            return magnitude, ""
        return math.nan, (f"{{value}} has no unit: expected {_article(kind)} in {UNIT_HINTS[kind]}, "
                          f"e.g. {_show(example)}")
    if not math.isfinite(magnitude):
        return math.nan, "{value} is not finite"
    common = _COMMON.get(unit)
    if common is not None and common[1] == kind:  # the units declarations and model files use: no pint needed
        return magnitude * common[0], ""
    for token in re.findall(r"[A-Za-z_]+", unit):
        if token in _AMBIGUOUS:
            return math.nan, f"cannot read {{value}}: {_show(token)} {_AMBIGUOUS[token]}"
    unit = _REVOLUTION.sub("revolution", unit)  # "r/min" is rpm: pint knows no "r"
    ureg = registry()
    try:
        q = ureg.Quantity(magnitude, unit)
    except Exception:  # pint raises several unrelated types for unreadable text
        return math.nan, f"cannot read {{value}}: {_show(unit)} is not a unit (e.g. {_show(example)})"
    try:
        if kind == "angle" and q.dimensionless:
            value = float(q.to("radian").magnitude)
        else:
            value = float(q.to(target or "dimensionless").magnitude)
    except Exception:
        return math.nan, f"{{value}} is not {_article(kind)} (expected {UNIT_HINTS[kind]}, e.g. {_show(example)})"
    if kind in _ANGULAR and "radian" not in q.to_root_units().units._units:
        hint = "rad/s, rpm, deg/s or revolution/s" if kind == "speed" else "rad/s**2 or deg/s**2"
        return math.nan, f"{{value}} names no angle unit (Hz or 1/min would be read as rad/s): write {hint}"
    if kind == "angle" and "radian" not in q.to_root_units().units._units and unit not in ("rad", "radian"):
        return math.nan, f"{{value}} is not an angle (expected {UNIT_HINTS[kind]}, e.g. {_show(example)})"
    return value, ""


def unit_of(text: str) -> str:
    """The unit part of a quantity string ("16.7 mm" -> "mm"); "" for a bare number."""
    parts = text.strip().split(None, 1)
    return parts[1] if len(parts) == 2 else ""


# -- physical limits ------------------------------------------------------------------------------------------------

#: The largest Coulomb friction coefficient a joint or bearing may be given. Oiled pins and slides run at about
#: 0.05-0.15, dry steel on steel at 0.6-0.8 (engineering handbooks' tables of friction coefficients); 1 covers every
#: pair in a sewing machine. Far above it a pin's friction moment μ·r·|F| outgrows what drives the pin (the
#: joint self-locks) and the Coulomb balance the kernels iterate has no solution: refused, never iterated.
FRICTION_MAX = 1.0

#: The largest gravity a run may be given (m/s²): 10 g, beyond any machine's standing on Earth (9.80665). A larger
#: value is a slip of the units (or an overflow: 1e308 m/s² times a mass is infinite), refused with its name.
GRAVITY_MAX = 100.0


def range_problem(value: float, minimum=None, maximum=None, unit: str = "") -> str | None:
    """What is wrong with ``value`` (SI) against a physical range [``minimum``, ``maximum``] (None: open), or None."""
    shown = f"{value!r}{' ' + unit if unit else ''}"
    if minimum is not None and not value >= minimum:
        return f"must be at least {minimum:g}{' ' + unit if unit else ''}, got {shown}"
    if maximum is not None and not value <= maximum:
        return f"must be at most {maximum:g}{' ' + unit if unit else ''}, got {shown}"
    return None


# -- sweeps of one revolution ------------------------------------------------------------------------------------

#: The largest shaft angle a sweep may ask for (rad; about 160 000 turns): an angle's rounding there is 1e-10 rad.
#: Beyond it the steps of a sweep drown in the angle's own rounding ("1e300 deg" + 5° is 1e300 deg): refused.
MAX_SHAFT_ANGLE = 1e6

#: The most positions a sweep of one revolution may have (a step of at least 0.0036°): a larger sweep would need
#: gigabytes for its results and is refused with a message instead of running out of memory.
MAX_POSITIONS = 100_000


def steps_per_turn(step: float) -> tuple[int | None, str]:
    """(n, "") when ``step`` (rad) divides one revolution into n equal steps, 4 ≤ n ≤ :data:`MAX_POSITIONS`;
    else (None, what is wrong, suggesting steps that do). A step that does not divide 360° is refused, never
    rounded: the sweep is exactly the step asked for, or nothing."""
    if not (isinstance(step, (int, float)) and math.isfinite(step) and step > 0):
        return None, f"must be a positive angle, got {math.degrees(step) if isinstance(step, float) else step!r}°"
    deg = math.degrees(step)
    ratio = 360.0 / deg
    if ratio > MAX_POSITIONS + 0.5:
        return None, (f"{deg:g}° gives {ratio:.4g} positions a revolution; at most {MAX_POSITIONS:,} are allowed "
                      f"(a step of at least {360.0 / MAX_POSITIONS:g} deg)")
    n = round(ratio)
    if n < 4:
        return None, f"{deg:g}° gives fewer than 4 positions a revolution (at most 90 deg)"
    if abs(n * deg - 360.0) > 1e-9 * 360.0:
        return None, f"{deg:g}° does not divide 360° into equal steps ({ratio:.4g} steps): use {_divisors(deg)}"
    return n, ""


def _divisors(deg: float) -> str:
    """The steps nearest ``deg`` (below and above) that divide 360° and are whole hundredths of a degree."""
    hundredths = [d for d in range(1, 9001) if 36000 % d == 0 and 36000 // d >= 4]
    below = [d for d in hundredths if d < deg * 100]
    above = [d for d in hundredths if d > deg * 100]
    picks = ([below[-1]] if below else []) + ([above[0]] if above else [])
    return " or ".join(f"{d / 100:g} deg ({36000 // d} positions)" for d in picks)


# -- display units -------------------------------------------------------------------------------------------------

#: Kinds a display unit can be chosen for (``--units mm,deg``); every other column unit is built from them.
DISPLAY_KINDS = ("length", "angle", "mass", "force", "torque")
#: The SI units of sewgen's table columns, as (base kind, power) pairs and a power of the second.
_COLUMN_UNITS = {
    "m": ((("length", 1),), 0), "m/s": ((("length", 1),), -1), "m/s^2": ((("length", 1),), -2),
    "m/s**2": ((("length", 1),), -2), "rad": ((("angle", 1),), 0), "rad/s": ((("angle", 1),), -1),
    "rad/s^2": ((("angle", 1),), -2), "rad/s**2": ((("angle", 1),), -2), "N": ((("force", 1),), 0),
    "N*m": ((("torque", 1),), 0), "kg": ((("mass", 1),), 0), "kg*m**2": ((("mass", 1), ("length", 2)), 0),
    "kg*m": ((("mass", 1), ("length", 1)), 0),
}
HEADER = re.compile(r"^(?P<name>.*) \[(?P<unit>[^\]]*)\]$")


class DisplayUnits:
    """The units tables and terminal output are shown in: SI (m, rad, kg, N, N*m) unless chosen per kind.

    ``DisplayUnits.parse("mm,deg")`` shows lengths in mm and angles in deg, and so velocities in mm/s,
    accelerations in mm/s^2, angular velocities in deg/s. Columns named ``"name [unit]"`` with an SI unit of
    sewgen's tables are converted by :meth:`table`; their header names the unit shown.
    """

    def __init__(self, units: dict | None = None):
        self.units = {k: SI_UNITS[k] for k in DISPLAY_KINDS}
        self.factors = {k: 1.0 for k in DISPLAY_KINDS}
        for kind, text in (units or {}).items():
            q = registry().Quantity(1.0, text)
            self.units[kind] = text
            self.factors[kind] = 1.0 / float(q.to(SI_UNITS[kind] if kind != "angle" else "radian").magnitude)

    @classmethod
    def parse(cls, text: str | None, what: str = "--units") -> "DisplayUnits":
        """``"mm,deg"`` (a unit for any of length, angle, mass, force, torque; "si" for SI); None: SI."""
        if text is None or text.strip().lower() == "si":
            return cls()
        chosen = {}
        for item in (t.strip() for t in text.split(",")):
            if not item:
                raise UnitError(what, f"{_show(text)}: an empty unit; give units separated by commas, e.g. "
                                      f'"mm,deg"')
            kind = _display_kind(item)
            if kind is None:
                raise UnitError(what, f"{_show(item)} is not a unit of {', '.join(DISPLAY_KINDS[:-1])} or "
                                      f"{DISPLAY_KINDS[-1]} (e.g. \"mm,deg\")")
            if kind in chosen:
                raise UnitError(what, f"two units for {kind}: {chosen[kind]} and {item}")
            chosen[kind] = item
        return cls(chosen)

    @property
    def si(self) -> bool:
        return all(f == 1.0 for f in self.factors.values())

    def of(self, si_unit: str) -> tuple[str, float]:
        """(unit shown, factor SI -> shown) for a column's SI unit; (si_unit, 1) for units not converted."""
        spec = _COLUMN_UNITS.get(si_unit)
        if spec is None:
            return si_unit, 1.0
        parts, time = spec
        if all(self.factors[k] == 1.0 for k, _ in parts):
            return si_unit, 1.0
        factor, names = 1.0, []
        for kind, power in parts:
            factor *= self.factors[kind] ** power
            names.append(self.units[kind] + (f"^{power}" if power != 1 else ""))
        unit = "*".join(names) + ({0: "", -1: "/s", -2: "/s^2"}[time])
        return unit, factor

    def convert(self, values, si_unit: str):
        """``values`` (SI, in ``si_unit``) in the unit shown: (values, unit)."""
        unit, factor = self.of(si_unit)
        return (values if factor == 1.0 else np.asarray(values) * factor), unit

    def table(self, cols: dict) -> dict:
        """Columns ``"name [SI unit]"`` -> ``"name [unit shown]"`` with their values converted."""
        if self.si:
            return cols
        out = {}
        for header, values in cols.items():
            m = HEADER.match(header)
            if m is None:
                out[header] = values
                continue
            unit, factor = self.of(m.group("unit"))
            out[f"{m.group('name')} [{unit}]"] = values if factor == 1.0 else np.asarray(values) * factor
        return out

    def describe(self) -> dict:
        """{kind: unit} of every display kind (what a summary states)."""
        return dict(self.units)


def _display_kind(text: str):
    """The kind (of :data:`DISPLAY_KINDS`) a unit text measures, or None."""
    if _NUMBER.match(text) or any(c in text for c in ",[]"):
        return None
    try:
        q = registry().Quantity(1.0, text)
    except Exception:
        return None
    for kind in DISPLAY_KINDS:
        try:
            if kind == "angle":
                if q.dimensionless and "radian" in q.to_root_units().units._units:
                    return kind
                continue
            q.to(SI_UNITS[kind])
            return kind
        except Exception:
            continue
    return None

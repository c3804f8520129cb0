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
import threading

import numpy as np

from .errors import UnitError  # errors is a leaf too; re-exported here, where quantities are read

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


def to_si(value, kind: str, what: str = "value") -> float:
    """Convert ``value`` (a number taken as SI, or a string such as ``"16.7 mm"``) to an SI float.

    ``kind`` is a key of :data:`SI_UNITS`; ``what`` names the parameter or option in the error.
    """
    if kind not in SI_UNITS:
        raise UnitError(what, f"unknown kind {kind!r}")
    if isinstance(value, (bool, np.bool_)):
        raise UnitError(what, f"expected a {kind} ({SI_UNITS[kind] or 'no unit'}), got {value!r}")
    if isinstance(value, (int, float, np.integer, np.floating)):
        out = float(value)
    elif isinstance(value, str):
        out, problem = _parse(value.strip(), kind)
        if problem:
            raise UnitError(what, f"{problem.format(value=repr(value))}")
    else:
        raise UnitError(what, f"expected a number or a quantity string, got {type(value).__name__}")
    if not math.isfinite(out):
        raise UnitError(what, f"{value!r} is not finite")
    return out


@functools.lru_cache(maxsize=4096)
def _parse(text: str, kind: str) -> tuple[float, str]:
    """(SI value, "") or (nan, problem text with a {value} slot): pint is slow, so each text is read once."""
    ureg = registry()
    try:
        q = ureg.Quantity(text)
    except Exception as exc:  # pint raises several unrelated types for unreadable text
        return math.nan, f"cannot read {{value}} as a quantity ({str(exc).replace('{', '{{').replace('}', '}}')})"
    target = SI_UNITS[kind]
    try:
        if kind == "angle" and q.dimensionless and not isinstance(q.magnitude, str):
            value = float(q.to("radian").magnitude)
        else:
            value = float(q.to(target or "dimensionless").magnitude)
    except Exception:
        article = "an" if kind[0] in "aeiou" else "a"
        return math.nan, f"{{value}} is not {article} {kind} (expected a unit convertible to {target or 'no unit'})"
    if kind in _ANGULAR and "radian" not in q.to_root_units().units._units:
        hint = "rad/s, rpm, deg/s or revolution/s" if kind == "speed" else "rad/s**2 or deg/s**2"
        return math.nan, f"{{value}} names no angle unit (Hz or 1/min would be read as rad/s): write {hint}"
    return value, ""


def unit_of(text: str) -> str:
    """The unit part of a quantity string ("16.7 mm" -> "mm"); "" for a bare number."""
    parts = text.strip().split(None, 1)
    return parts[1] if len(parts) == 2 else ""

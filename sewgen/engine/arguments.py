"""The engine's arguments: checked, converted to SI and handed to C (every entry point reads them so).

``pointer`` is how an array reaches C; ``si``, ``vector`` and ``mapping`` check a user's value and name the
mechanism and the parameter when it is wrong.
"""
from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from sewgen import abi
from sewgen.errors import InputError, ParameterError
from sewgen.units import GRAVITY_MAX, MAX_SHAFT_ANGLE, UnitError, range_problem, to_si

#: Parameter kinds that must not be negative.
NONNEGATIVE = {"mass", "inertia"}
#: Newton iterations per position unless the caller says otherwise.
DEFAULT_MAX_ITER = 50


def pointer(ffi, ctype: str, arr: np.ndarray):
    """``arr`` as a C array argument ("double *" -> double[]). The typed from_buffer keeps ``arr`` alive for as
    long as the cdata lives (a cast pointer would not: a temporary array could be freed before the call)."""
    return ffi.from_buffer(ctype.replace(" *", "[]"), arr) if arr.size else ffi.NULL


def vector(mechanism: str, what: str, value, n: int) -> np.ndarray:
    """``value`` as a C-ready float64 vector of exactly ``n`` finite entries (C reads n, whatever it is given)."""
    try:
        arr = np.ascontiguousarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError(mechanism, what, f"must be {n} numbers, got {value!r}") from None
    if arr.shape != (n,):
        raise ParameterError(mechanism, what, f"must have {n} entries, got shape {arr.shape}")
    if not np.isfinite(arr).all():
        raise ParameterError(mechanism, what, "must be finite")
    return arr


def parameter_problem(spec, value: float) -> str | None:
    """What is wrong with ``value`` (SI, finite) for the parameter ``spec`` (a description.Parameter), or None:
    positive where it is declared so, not negative for a mass or an inertia, within its physical range (a friction
    coefficient's [0, 1], a damper's or a spring's [0, ∞): the declaration's ``minimum`` and ``maximum``). The one
    check of a parameter's value, whichever way it comes (params=, a model file, a design table)."""
    if spec.positive and not value > 0:
        return f"must be positive, got {value!r} {spec.unit}"
    if spec.kind in NONNEGATIVE and value < 0:
        return f"must not be negative, got {value!r} {spec.unit}"
    problem = range_problem(value, spec.minimum, spec.maximum, spec.unit)
    return None if problem is None else f"{problem} ({spec.doc})"


def check_gravity(mechanism: str, g: float) -> float:
    """``g`` (m/s², finite): the magnitude of gravity (its direction is ``gravity_direction``), from 0 (off) to
    :data:`sewgen.units.GRAVITY_MAX`; a negative or larger one is a ParameterError naming ``gravity``."""
    problem = range_problem(g, 0.0, GRAVITY_MAX, "m/s**2")
    if problem:
        raise ParameterError(mechanism, "gravity", f"{problem} (a magnitude: standing on Earth 9.80665 m/s**2, 0 "
                                                   "switches it off; its direction is gravity_direction)")
    return g


#: Shaft angles in rad beyond this (two turns) whose every value is a whole hundredth are taken for degrees.
DEGREES_LIKE = 4 * math.pi


def check_shaft_angles(mechanism: str, phi: np.ndarray, degrees: bool) -> np.ndarray:
    """``phi``: a sweep's shaft angles in rad (converted already where ``degrees``), finite. Refused, naming them:

    * any angle beyond ±:data:`sewgen.units.MAX_SHAFT_ANGLE` (its rounding would swallow the steps of the sweep);
    * angles given as rad (``degrees`` False) that look like degrees: more than two turns out (|φ| > 4π) and every
      one a whole hundredth (``np.arange(0, 360, 5)``). A sweep in rad is a few turns at most and its angles are
      not round numbers; a true sweep of many turns in whole hundredths of a radian goes as degrees
      (``np.degrees(phi)``, ``degrees=True``).

    Cheap: one pass for the largest |φ|, a second only when it is beyond two turns. Returns ``phi``."""
    top = float(np.abs(phi).max()) if phi.size else 0.0
    if top > MAX_SHAFT_ANGLE:
        raise InputError(mechanism, f"shaft angle {top:g} rad is beyond ±{MAX_SHAFT_ANGLE:g} rad (about "
                                    f"{MAX_SHAFT_ANGLE / (2 * math.pi):.0f} turns): its rounding would swallow the "
                                    "sweep's steps", parameter="phi")
    if not degrees and top > DEGREES_LIKE:
        hundredths = phi * 100.0
        if (np.abs(hundredths - np.rint(hundredths)) <= 1e-9 * np.maximum(1.0, np.abs(hundredths))).all():
            raise InputError(mechanism, f"shaft angles up to {top:g} rad ({top / (2 * math.pi):.3g} turns), all of "
                                        "them round numbers, look like degrees: pass degrees=True (or the angles in "
                                        "rad, e.g. np.radians(...))", parameter="phi")
    return phi


def mapping(mechanism: str, what: str, value) -> Mapping:
    """A by-name argument (params, held, branch, guess): a mapping, or None for none."""
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise ParameterError(mechanism, what, f"must be a dict of names to values, got {type(value).__name__}")
    return value


def si(mechanism: str, value, kind: str, name: str) -> float:
    """to_si with its error retyped as a ParameterError naming the mechanism and ``name``."""
    try:
        return to_si(value, kind, name)
    except UnitError as exc:
        raise ParameterError(mechanism, name, exc.problem) from None


#: Each sg_request field's C type (sewgen.abi.REQUEST), for the arrays handed to it.
_REQUEST_TYPES = {name: ctype.replace("const ", "") for ctype, name, _ in abi.REQUEST}


def request(ffi, **fields):
    """One ``sg_request`` (:data:`sewgen.abi.REQUEST`) with ``fields``: numpy arrays (C-contiguous, of the field's
    type), cffi pointers or numbers; the others 0 (NULL). Returns (the struct, the buffers its pointers point
    into): keep both for as long as C may read the struct (the struct itself holds no reference)."""
    keep = []
    init = {}
    for name, value in fields.items():
        if isinstance(value, np.ndarray):
            value = pointer(ffi, _REQUEST_TYPES[name], value)
            keep.append(value)
        init[name] = value
    return ffi.new("sg_request *", init), keep

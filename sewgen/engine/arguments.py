"""The engine's arguments: checked, converted to SI and handed to C (every entry point reads them so).

``pointer`` is how an array reaches C; ``si``, ``vector`` and ``mapping`` check a user's value and name the
mechanism and the parameter when it is wrong.
"""
from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from sewgen import abi
from sewgen.errors import ParameterError
from sewgen.units import UnitError, range_problem, to_si

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

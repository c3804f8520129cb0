"""External loads on a mechanism: a force at a named point or a torque on a body, over a shaft-angle window.

Seed 000 §二(二)1 gives the examples: the take-up thread force 2.94 N over φ = 135°–155° (JB1-3), and the
presser-foot force 14.7 N (vertical) with the feed resistance 7.35 N (horizontal) on the feed dog over
90°–175°. Forces are in the mechanism's frame axes (x, y); a window is inclusive at both ends and may wrap
through 360° (e.g. 350°–20°).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sewgen.units import UnitError, to_si

from sewgen.errors import ParameterError

_WINDOW_TOL = 1e-9  # rad: a window's ends are inclusive despite rounding in the shaft angles


@dataclass(frozen=True)
class Load:
    """A force (``fx``, ``fy``, N) at named point ``at``, or a ``torque`` (N·m) on moving body ``at``.

    Values are SI numbers or quantity strings ("2.94 N"); ``window`` = (start, end) shaft angles (rad or
    strings such as "135 deg"), None for always on.
    """

    at: str
    fx: float | str = 0.0
    fy: float | str = 0.0
    torque: float | str = 0.0
    window: tuple | None = None
    name: str = ""

    @classmethod
    def force(cls, at: str, magnitude, direction, window=None, name: str = "") -> "Load":
        """A force of ``magnitude`` along ``direction`` (angle from +x, counter-clockwise)."""
        mag = to_si(magnitude, "force", f"load at {at}: magnitude")
        ang = to_si(direction, "angle", f"load at {at}: direction")
        return cls(at, mag * math.cos(ang), mag * math.sin(ang), 0.0, window, name)

    @property
    def label(self) -> str:
        return self.name or self.at


def window_mask(phi: np.ndarray, window) -> np.ndarray:
    """True where the shaft angle lies in [start, end] (mod 360°, inclusive); all True without a window."""
    if window is None:
        return np.ones(phi.shape, dtype=bool)
    start, end = window
    if abs(end - start) >= 2 * math.pi - _WINDOW_TOL:  # a whole turn (or more): always on
        return np.ones(phi.shape, dtype=bool)
    span = (end - start) % (2 * math.pi)
    return (phi - start) % (2 * math.pi) <= span + _WINDOW_TOL


def load_matrix(mech, loads, phi: np.ndarray, degrees: bool = False) -> tuple[np.ndarray | None, list[tuple]]:
    """The (n, nload) load array the C sweep reads, and (load, slot indices, mask) per load.

    Slots (the description's ``loads``): fx, fy per named point of a moving body, torque per moving body. Window
    ends given as bare numbers are radians, or degrees when ``degrees`` (as the sweep's shaft angles).
    """
    if not loads:
        return None, []
    return place_loads(load_layout(mech, loads, degrees), phi, len(mech.description.loads))


class LoadLayout(list):
    """:func:`load_layout`'s list, (load, [(slot, SI value)], window in rad or None) per load, with the C arrays
    sg_place_loads reads (csrc/sg_runtime.c: each window's start, NaN for always on, and its span plus the
    tolerance; the slots and values, zeros left out) and the mechanism's C module."""

    def __init__(self, mech, entries):
        super().__init__(entries)
        win, ncol, col, val = [], [], [], []
        for _load, cols, window in entries:
            if window is None or abs(window[1] - window[0]) >= 2 * math.pi - _WINDOW_TOL:  # a whole turn or more
                win += [math.nan, math.inf]
            else:
                win += [window[0], (window[1] - window[0]) % (2 * math.pi) + _WINDOW_TOL]
            kept = [(k, value) for k, value in cols if value != 0.0]  # x + 0 is x: no -0.0 made +0.0
            ncol.append(len(kept))
            col += [k for k, _ in kept]
            val += [value for _, value in kept]
        ffi = mech.ffi
        self.c = (mech.lib.sg_place_loads, ffi, len(entries)) + tuple(
            ffi.from_buffer(t, a) for t, a in (("double[]", np.array(win, dtype=float)),
                                               ("int[]", np.array(ncol, dtype=np.intc)),
                                               ("int[]", np.array(col, dtype=np.intc)),
                                               ("double[]", np.array(val, dtype=float))))


def load_layout(mech, loads, degrees: bool = False) -> LoadLayout:
    """Every load checked and converted once: (load, [(slot, SI value)], window in rad or None) per load, in
    order. What depends on the shaft angles (the windows' masks) is :func:`place_loads`'s."""
    slots = mech.description.loads
    index = {(s.name, s.component): s.index for s in slots}
    layout = []
    for load in loads:
        if not isinstance(load, Load):
            raise ParameterError(mech.name, "loads", f"expected sewgen.Load entries, got {type(load).__name__}")
        what = f"load {load.label}"
        try:
            fx, fy = to_si(load.fx, "force", f"{what}: fx"), to_si(load.fy, "force", f"{what}: fy")
            tz = to_si(load.torque, "torque", f"{what}: torque")
            if load.window is not None and len(load.window) != 2:
                raise ValueError(f"{what}: window must be (start, end), got {load.window!r}")
            window = None if load.window is None else tuple(
                math.radians(w) if degrees and not isinstance(w, str) else to_si(w, "angle", f"{what}: window")
                for w in load.window)
        except (UnitError, TypeError, ValueError) as exc:
            raise ParameterError(mech.name, what, str(exc)) from None
        is_point = (load.at, "fx") in index
        is_body = (load.at, "torque") in index
        if not (is_point or is_body):
            points = sorted({s.name for s in slots if s.component != "torque"})
            bodies = sorted({s.name for s in slots if s.component == "torque"})
            raise ParameterError(mech.name, what, f"{load.at!r} is neither a point of a moving body "
                                 f"({', '.join(points) or 'none'}) nor a moving body ({', '.join(bodies)})")
        if is_point and not is_body and tz != 0.0:
            raise ParameterError(mech.name, what, f"{load.at!r} is a point: give a force, not a torque")
        if is_body and not is_point and (fx != 0.0 or fy != 0.0):
            raise ParameterError(mech.name, what, f"{load.at!r} is a body: give a torque, or put the force at "
                                 "a named point")
        cols = [(k, value) for k, value in ((index.get((load.at, comp)), value)
                                            for comp, value in (("fx", fx), ("fy", fy), ("torque", tz)))
                if k is not None]
        layout.append((load, cols, window))
    return LoadLayout(mech, layout)


def place_loads(layout: LoadLayout, phi: np.ndarray, nload: int, out: np.ndarray | None = None):
    """The (n, nload) load array of a :func:`load_layout` at shaft angles ``phi`` (into ``out``, C-contiguous, if
    given), and (load, slot indices, mask) per load: each load's SI values added where its window holds the
    angle (:func:`window_mask`'s test), in one C call (sg_place_loads)."""
    n = phi.shape[0]
    if out is None:
        out = np.empty((n, nload))
    fn, ffi, nl, win, ncol, col, val = layout.c
    masks = np.empty((nl, n), dtype=bool)
    d = ffi.from_buffer
    fn(n, d("double[]", np.ascontiguousarray(phi, dtype=float)), nload, nl, win, ncol, col, val,
       d("double[]", out), d("unsigned char[]", masks))
    return out, [(load, list(cols), masks[k]) for k, (load, cols, _window) in enumerate(layout)]

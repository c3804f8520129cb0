"""Peaks of per-angle quantities of a machine, true between the samples: the value and its shaft angle.

A sweep samples the machine every step (seed 000's 72 positions: 5°); a peak narrower than a few steps falls
between two samples, and the largest sample can miss it by much (JB1-3's rear bearing: 182 N at 355° sampled,
190 N at 192° the true peak). The machine itself is exact and cheap to solve at any angle, so a peak is refined
by solving it again, not by interpolating the samples:

1. **candidates**: every sampled local extreme within :data:`BAND` of the sampled range from the sampled
   extreme (at most :data:`MAX_CANDIDATES`, the largest), and every sample next to a switch (below) whose
   neighbourhood reaches that band, each bracketed by its two neighbouring samples (round the turn for a whole
   revolution; at a sweep's end by its one neighbour);
2. **zoom**: every bracket of every quantity at once — one machine analysis a round — gets :data:`POINTS` equally
   spaced angles inside; the best of the bracket's known points (its ends, the best so far and the new ones) and
   its two neighbours become the next bracket, which shrinks by (POINTS + 1)/2 a round until it is narrower than
   :data:`ANGLE_TOL`. This is a direct search on the exact machine (a grid form of golden-section search: each
   round one batched C call for every bracket of every quantity, where a scalar Brent search would make one call
   per point per bracket); the value reported is the machine's own value at the angle reported, never an
   interpolation;
3. **switches**: between cam-arc switches and the edges of the load windows the machine is smooth; across
   one the accelerations (and so every force) jump. The zoom then closes on the switch from the side whose limit
   is larger, and the peak is reported as that one-sided limit at the switch (``how`` = :data:`AT_SWITCH`), the
   switch being where the final bracket's ends differ in their active arcs or load windows.

``how`` says how every extreme was obtained: :data:`REFINED`, :data:`AT_SWITCH`, or :data:`SAMPLED` where the
analysis cannot be solved again at other angles (per-position speeds, angles not in increasing order, a position
between the samples that cannot be solved): then it is the extreme sample.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sewgen.engine.loads import window_mask
from sewgen.errors import SewgenError
from sewgen.machine.cams import arc_columns

TWO_PI = 2.0 * math.pi
#: Width (rad) the final bracket of a refined extreme is narrower than: its angle is known to half of it.
ANGLE_TOL = math.radians(1e-3)
#: New angles inside each bracket per round (the bracket shrinks by (POINTS + 1) / 2 a round).
POINTS = 8
#: Sampled local extremes refined: those within BAND × (sampled range) of the sampled extreme ...
BAND = 0.5
#: ... the largest MAX_CANDIDATES of them.
MAX_CANDIDATES = 8
#: A bound on the rounds (a bracket of a whole turn needs 9 to reach ANGLE_TOL).
MAX_ROUNDS = 40
#: A quantity whose values at the final bracket's ends differ by more than JUMP × its sampled range, a switch
#: between them, jumps (or turns) there: its extreme is at the switch. A smooth extreme differs by
#: ~ f″ (ANGLE_TOL / 2)², far less.
JUMP = 1e-6

REFINED = "refined"
AT_SWITCH = "at a switch"
SAMPLED = "sampled"
SENSES = ("max", "min")


@dataclass(frozen=True)
class Extreme:
    """A quantity's largest (or least) value over a sweep and the machine shaft angle (rad) where it occurs;
    ``how``: :data:`REFINED`, :data:`AT_SWITCH` (a one-sided limit at a cam-arc switch or a load window's edge)
    or :data:`SAMPLED` (see the module)."""

    value: float
    angle: float
    how: str

    @property
    def deg(self) -> float:
        """The angle in degrees within [0, 360), to 0.01° (a refined angle is known to ANGLE_TOL / 2)."""
        return round(math.degrees(self.angle) % 360.0, 2) % 360.0


def _whole_turn(phi: np.ndarray) -> bool:
    n = len(phi)
    if n < 3:
        return False
    h = TWO_PI / n
    return bool(np.allclose(np.diff(phi), h, rtol=0.0, atol=1e-9 * h))


def _candidates(s: np.ndarray, periodic: bool, switch: np.ndarray) -> np.ndarray:
    """Indices of the samples of ``s`` whose neighbourhoods are worth refining (module: 1.): the sampled local
    maxima, the largest first (at most :data:`MAX_CANDIDATES`), and every sample next to a switch
    (``switch``: the samples whose signature differs from a neighbour's), where a one-sided limit may exceed
    every sample; both within :data:`BAND` of the sampled range from the sampled maximum."""
    n = len(s)
    if periodic:
        left, right = np.roll(s, 1), np.roll(s, -1)
    else:
        left = np.concatenate([[-np.inf], s[:-1]])
        right = np.concatenate([s[1:], [-np.inf]])
    top, low = float(s.max()), float(s.min())
    level = top - BAND * (top - low)
    idx = np.flatnonzero((s >= left) & (s >= right) & (s >= level))
    idx = idx[np.argsort(-s[idx], kind="stable")][:MAX_CANDIDATES]
    near = np.flatnonzero(switch & (np.maximum(np.maximum(left, right), s) >= level))
    return np.concatenate([idx, np.setdiff1d(near, idx)]) if n else idx


def refine(phi, values: dict, evaluate, signature=None, senses=SENSES, tol: float = ANGLE_TOL) -> dict:
    """name -> sense ("max"/"min") -> :class:`Extreme` of every quantity of ``values`` (name -> (n,) samples at
    the shaft angles ``phi``, rad), refined as the module says.

    ``evaluate(angles)`` -> (name -> values at ``angles``, (m, c) signature or None) solves the machine at
    other angles (None: it cannot; it may raise SewgenError: the extremes are then the sampled ones);
    ``signature`` (n, c): what switches at a discontinuity (active arcs, load windows) at the samples."""
    phi = np.asarray(phi, dtype=float)
    names = list(values)
    vals = {k: np.asarray(values[k], dtype=float) for k in names}
    n = len(phi)
    sampled = {k: {sense: _sampled(phi, vals[k], sense) for sense in senses} for k in names}
    if evaluate is None or n < 2 or not np.all(np.diff(phi) > 0.0) or not all(
            np.isfinite(v).all() for v in vals.values()):
        return sampled
    periodic = _whole_turn(phi)
    sig = np.zeros((n, 0)) if signature is None else np.asarray(signature, dtype=float).reshape(n, -1)
    prev, nxt = (np.roll(sig, 1, axis=0), np.roll(sig, -1, axis=0)) if periodic else (
        np.concatenate([sig[:1], sig[:-1]]), np.concatenate([sig[1:], sig[-1:]]))
    switch = np.any((sig != prev) | (sig != nxt), axis=1) if sig.shape[1] else np.zeros(n, bool)
    # the brackets: quantity index, sign (+1 max, −1 min), ends, their values (signed) and signatures, best point
    q, sign, lo, hi, vlo, vhi, slo, shi, ba, bv, sb = ([] for _ in range(11))
    for j, k in enumerate(names):
        for sense in senses:
            sg = 1.0 if sense == "max" else -1.0
            s = sg * vals[k]
            for i in _candidates(s, periodic, switch):
                if periodic:
                    il, ir = (i - 1) % n, (i + 1) % n
                    a0 = phi[i] - (phi[i] - phi[il]) % TWO_PI
                    a1 = phi[i] + (phi[ir] - phi[i]) % TWO_PI
                else:
                    il, ir = max(i - 1, 0), min(i + 1, n - 1)
                    a0, a1 = phi[il], phi[ir]
                ib = max((il, i, ir), key=lambda m: s[m])  # the best sample of the bracket
                q.append(j), sign.append(sg), lo.append(a0), hi.append(a1), vlo.append(s[il]), vhi.append(s[ir])
                slo.append(sig[il]), shi.append(sig[ir]), bv.append(s[ib]), sb.append(sig[ib])
                ba.append(a0 if ib == il and ib != i else a1 if ib == ir and ib != i else phi[i])
    q, sign = np.array(q), np.array(sign)
    lo, hi, vlo, vhi, ba, bv = (np.array(x, dtype=float) for x in (lo, hi, vlo, vhi, ba, bv))
    c = sig.shape[1]
    slo, shi, sb = (np.array(x, dtype=float).reshape(len(q), c) for x in (slo, shi, sb))
    frac = np.arange(1, POINTS + 1) / (POINTS + 1)
    for _ in range(MAX_ROUNDS):
        act = np.flatnonzero(hi - lo > tol)
        if not len(act):
            break
        t = lo[act, None] + (hi - lo)[act, None] * frac[None, :]  # (Ka, POINTS)
        flat = t.ravel()
        order = np.argsort(flat, kind="stable")
        try:
            got = evaluate(flat[order])
        except SewgenError:
            return sampled
        if got is None:
            return sampled
        out, psig = got
        back = np.empty_like(order)
        back[order] = np.arange(len(order))
        table = np.stack([np.asarray(out[k], dtype=float)[back] for k in names])  # (Q, Ka·POINTS)
        ka = len(act)
        tv = sign[act, None] * table[q[act][:, None], np.arange(ka * POINTS).reshape(ka, POINTS)]
        tv = np.where(np.isfinite(tv), tv, -np.inf)
        ts = (np.zeros((ka * POINTS, 0)) if psig is None or c == 0
              else np.asarray(psig, dtype=float).reshape(len(order), -1)[back]).reshape(ka, POINTS, c)
        # the bracket's known points in angle order: its ends, the best so far, the new ones
        ga = np.column_stack([lo[act], ba[act], hi[act], t])
        gv = np.column_stack([vlo[act], bv[act], vhi[act], tv])
        gs = np.concatenate([slo[act, None], sb[act, None], shi[act, None], ts], axis=1)
        o = np.argsort(ga, axis=1, kind="stable")
        ga, gv = np.take_along_axis(ga, o, 1), np.take_along_axis(gv, o, 1)
        gs = np.take_along_axis(gs, o[:, :, None], 1)
        best = np.argmax(gv, axis=1)
        rows = np.arange(ka)
        # its neighbours: the nearest known points at other angles (a new point may fall on the best one)
        at = ga[rows, best][:, None]
        below, above = (ga < at).sum(axis=1), (ga > at).sum(axis=1)
        left = np.where(below > 0, below - 1, best)
        right = np.where(above > 0, ga.shape[1] - above, best)
        lo[act], vlo[act], slo[act] = ga[rows, left], gv[rows, left], gs[rows, left]
        hi[act], vhi[act], shi[act] = ga[rows, right], gv[rows, right], gs[rows, right]
        ba[act], bv[act], sb[act] = ga[rows, best], gv[rows, best], gs[rows, best]
    # at a switch: one lies in the final bracket and the quantity jumps (or turns) across it
    scale = np.array([np.ptp(vals[names[j]]) for j in q]) if len(q) else np.zeros(0)
    switched = ((np.any(slo != shi, axis=1) if c else np.zeros(len(q), bool))
                & (np.abs(vhi - vlo) > JUMP * scale))
    result = {}
    for j, k in enumerate(names):
        result[k] = {}
        for sense in senses:
            sg = 1.0 if sense == "max" else -1.0
            mine = np.flatnonzero((q == j) & (sign == sg))
            b = mine[int(np.argmax(bv[mine]))]
            result[k][sense] = Extreme(float(sg * bv[b]), float(ba[b] % TWO_PI), AT_SWITCH if switched[b] else REFINED)
    return result


def _sampled(phi, v, sense) -> Extreme:
    i = int(np.argmax(v) if sense == "max" else np.argmin(v))
    return Extreme(float(v[i]), float(phi[i] % TWO_PI), SAMPLED)


# -- a machine analysis ------------------------------------------------------------------------------------------

def _scalar(value):
    """A run's speed or acceleration as one value (a constant array's), or None where it varies per position."""
    if isinstance(value, str) or np.ndim(value) == 0:
        return value
    arr = np.asarray(value, dtype=float).ravel()
    return float(arr[0]) if len(arr) and np.all(arr == arr[0]) else None


def mechanism_signature(mech, obs, angles, loads=()) -> np.ndarray:
    """(n, c) at ``angles`` (rad) of one mechanism: every cam contact's active arc (from its observables ``obs``,
    (n, nobs)) and every load window's state (on, off) — what changes at a discontinuity of its accelerations and
    forces."""
    cols = [obs[:, k] for k in arc_columns(mech).values()]
    cols += [window_mask(np.asarray(angles, dtype=float), ld.window).astype(float) for ld in loads
             if ld.window is not None]
    return np.column_stack(cols) if cols else np.zeros((len(angles), 0))


def signature(a) -> np.ndarray:
    """(n, c) at the machine analysis' angles: :func:`mechanism_signature` of every group (its load windows in the
    machine's angle), side by side."""
    parts = [mechanism_signature(g.mechanism, a.groups[g.name].motion.obs, a.phi, g.loads) for g in a.machine.groups]
    return np.column_stack(parts) if parts else np.zeros((len(a.phi), 0))


def analysis_at(a, angles):
    """The machine analysis ``a`` again at the shaft angles ``angles`` (rad): its machine at its speed and
    acceleration; None where those vary per position (they cannot be carried to other angles)."""
    speed, accel = _scalar(a.run["speed"]), _scalar(a.run["accel"])
    if speed is None or accel is None:
        return None
    with np.errstate(all="ignore"):  # a non-finite result is the analysis' typed error
        return a.machine.analyze(np.ascontiguousarray(angles, dtype=float), speed=speed, accel=accel)


def extremes_of(result, phi, quantities: dict, solve, signature_of=None, senses=SENSES) -> dict:
    """name -> sense -> :class:`Extreme` of every quantity of ``quantities`` (name -> function of a result giving
    its (n,) values) over ``result``, a sweep at the shaft angles ``phi``: ``solve(angles)`` gives the same kind of
    result at other angles (None: it cannot), ``signature_of(result, angles)`` its switches (:func:`refine`)."""
    values = {k: f(result) for k, f in quantities.items()}

    def evaluate(angles):
        r = solve(angles)
        if r is None:
            return None
        with np.errstate(all="ignore"):
            return {k: f(r) for k, f in quantities.items()}, (None if signature_of is None
                                                               else signature_of(r, angles))

    with np.errstate(all="ignore"):
        return refine(phi, values, evaluate, None if signature_of is None else signature_of(result, phi), senses)


def extremes(a, quantities: dict, senses=SENSES) -> dict:
    """name -> sense -> :class:`Extreme` of every quantity of ``quantities`` (name -> function of a
    :class:`sewgen.machine.MachineAnalysis` giving its (n,) values) over the machine analysis ``a``, each refined
    between the samples by solving ``a``'s machine again at its speed and acceleration (module docstring)."""
    return extremes_of(a, a.phi, quantities, lambda angles: analysis_at(a, angles), lambda b, _angles: signature(b),
                       senses)


__all__ = ["ANGLE_TOL", "AT_SWITCH", "Extreme", "REFINED", "SAMPLED", "analysis_at", "extremes", "extremes_of",
           "mechanism_signature", "refine", "signature"]

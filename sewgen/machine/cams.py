"""Arc switches of cam contacts: where the active arc changes and the acceleration jump it implies.

A cam of circular arcs joined with a common tangent (G1) keeps the follower's position and velocity
continuous when the contact passes from one arc to the next; the curvature changes there, so the
acceleration jumps (seed 000 §一(四)5: the contact's complex vectors a₁e^{iθ}, re^{iθ} change "by the
geometric condition" at each transition point). This module finds each switch in a sweep, brackets its shaft
angle by bisection, and evaluates the one-sided accelerations there.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ArcSwitch:
    """One switch: shaft angle (rad, the group's own), cam joint, arcs before/after, and for every named point
    the acceleration just after minus just before (m/s², frame x and y)."""

    angle: float
    cam: str
    from_arc: int
    to_arc: int
    jumps: dict

    def as_dict(self) -> dict:
        return {"angle_deg": math.degrees(self.angle) % 360.0, "cam": self.cam, "from_arc": self.from_arc,
                "to_arc": self.to_arc,
                "acceleration_jump": {k: {"ax": v[0], "ay": v[1], "magnitude": math.hypot(*v)}
                                      for k, v in self.jumps.items()}}


def arc_columns(mech) -> dict:
    return {name[:-len(".arc")]: k for k, (name, _) in enumerate(mech.description.observables)
            if name.endswith(".arc")}


def arc_switches(mech, motion, *, params=None, held=None, tol: float = 1e-10, side: float = 1e-7) -> list[ArcSwitch]:
    """Every arc switch between consecutive positions of ``motion`` (a sweep of ``mech`` at constant speed).

    ``params`` and ``held`` must be the sweep's. The switch angle is bracketed to ``tol`` rad; the one-sided
    accelerations are taken ``side`` rad either side of it (their difference is the jump to O(side)).
    """
    cols = arc_columns(mech)
    if not cols:
        return []
    out = []
    n = len(motion.phi)
    w = float(motion.omega[0])
    names = mech.coord_names

    def state(phi, q_start):
        guess = dict(zip(names, q_start))
        return mech.solve([phi], speed=w, params=params, held=held, guess=guess, newton=True)

    for cam, k in cols.items():
        arc = motion.obs[:, k]
        for i in np.flatnonzero(arc != np.roll(arc, -1)):
            j = (i + 1) % n
            lo, hi = float(motion.phi[i]), float(motion.phi[j])
            if hi < lo:
                hi += 2 * math.pi
            q_lo = motion.q[i]
            while hi - lo > tol:
                mid = 0.5 * (lo + hi)
                s = state(mid, q_lo)
                if s.obs[0, k] == arc[i]:
                    lo, q_lo = mid, s.q[0]
                else:
                    hi = mid
            before, after = state(lo - side, q_lo), state(hi + side, q_lo)
            jumps = {p: (float(after.point(p).ax[0] - before.point(p).ax[0]),
                         float(after.point(p).ay[0] - before.point(p).ay[0])) for p in mech.point_names}
            out.append(ArcSwitch(0.5 * (lo + hi), cam, int(arc[i]), int(arc[j]), jumps))
    return out

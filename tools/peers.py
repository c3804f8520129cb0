"""Peers of the benchmark: the take_up four-bar as other tools compute it, each checked against
sewgen before ``python tools/bench.py --peers`` times it.

* :func:`take_up_kernel` — the closed form a numba user writes: one loop over the shaft angles filling every
  output sewgen's ``solve()`` gives, in :mod:`sewgen.engine.designs`' column names (:data:`COLUMNS`). With numba
  installed, :func:`numba_kernel` compiles it (``peer:numba``); without numba the same function runs as plain
  Python, which is how the tests check it.
* :func:`pylinkage_take_up` — the same mechanism built from pylinkage's components (a crank, an RRR dyad and a
  fixed dyad for the eye), swept by its numba solver with velocities and accelerations (``peer:pylinkage``):
  the three points' positions, velocities and accelerations.

Only the benchmark imports this module; neither numba nor pylinkage is a dependency of sewgen.
"""
from __future__ import annotations

import math

import numpy as np

#: The parameters the kernels read, in this order (take_up's names, SI).
PARAMS = ("crank.phase", "crank", "lever_bc", "rocker", "rocker_pivot_x", "rocker_pivot_y", "lever_be", "lever_ce",
          "crank.com_u", "crank.com_v", "lever.com_u", "lever.com_v")

#: The kernel's output columns, in order: sewgen's own names (:class:`sewgen.engine.designs.Columns`).
COLUMNS = tuple(
    ["coords.rocker.angle", "coords.lever.angle", "coords.rocker.angle_d", "coords.lever.angle_d",
     "coords.rocker.angle_dd", "coords.lever.angle_dd"]
    + [f"points.{p}.{c}" for p in ("crank_pin", "rocker_pin", "thread_eye")
       for c in ("x", "y", "x_d", "y_d", "x_dd", "y_dd")]
    + [f"bodies.{b}.{c}" for b in ("crank", "lever", "rocker")
       for c in ("angle", "angle_d", "angle_dd", "com.x", "com.y", "com.x_d", "com.y_d", "com.x_dd", "com.y_dd")])


def parameter_vector(p: dict) -> np.ndarray:
    """take_up's parameters (``Mechanism.defaults()``, SI) in :data:`PARAMS` order."""
    return np.array([float(p[k]) for k in PARAMS])


def _point(out, i, k, ox, oy, vx, vy, ax, ay, th, w, al, u, v):
    """A point (u, v) of a body (its frame at (ox, oy), angle th, rates w, al) into out[i, k:k + 6]."""
    ct, st = math.cos(th), math.sin(th)
    ex, ey = u * ct - v * st, u * st + v * ct
    out[i, k] = ox + ex
    out[i, k + 1] = oy + ey
    out[i, k + 2] = vx - w * ey
    out[i, k + 3] = vy + w * ex
    out[i, k + 4] = ax - al * ey - w * w * ex
    out[i, k + 5] = ay + al * ex - w * w * ey


def _kernel(phi, omega, alpha, prm, out, point):
    """Every output of the take_up four-bar at each shaft angle (crank AB, lever BC with the eye E, rocker DC;
    branch +1: C left of B→D), one position at a time: the dyad's closed form (Makino's vector triangle, seed
    001 §三), its rates from the velocity and acceleration loop equations, then each point of a body."""
    phase, ab, bc, cd, pdx, pdy, be, ce = prm[0], prm[1], prm[2], prm[3], prm[4], prm[5], prm[6], prm[7]
    eu = (bc * bc + be * be - ce * ce) / (2 * bc)
    ev = math.sqrt(be * be - eu * eu)
    for i in range(phi.shape[0]):
        th1 = phi[i] + phase
        c1, s1 = math.cos(th1), math.sin(th1)
        bx, by = ab * c1, ab * s1
        vbx, vby = -ab * omega * s1, ab * omega * c1
        abx, aby = -ab * (omega * omega * c1 + alpha * s1), ab * (alpha * c1 - omega * omega * s1)
        dx, dy = pdx - bx, pdy - by
        d2 = dx * dx + dy * dy
        a = 0.5 * (bc * bc - cd * cd + d2) / d2
        h = math.sqrt(bc * bc / d2 - a * a)
        cx, cy = bx + a * dx - h * dy, by + a * dy + h * dx
        r2x, r2y, r3x, r3y = cx - bx, cy - by, cx - pdx, cy - pdy
        cr = r2x * r3y - r2y * r3x
        w2 = -(vbx * r3x + vby * r3y) / cr
        w3 = -(vbx * r2x + vby * r2y) / cr
        rx = abx - w2 * w2 * r2x + w3 * w3 * r3x
        ry = aby - w2 * w2 * r2y + w3 * w3 * r3y
        a2 = -(rx * r3x + ry * r3y) / cr
        a3 = -(rx * r2x + ry * r2y) / cr
        th2, th3 = math.atan2(r2y, r2x), math.atan2(r3y, r3x)
        out[i, 0], out[i, 1], out[i, 2], out[i, 3], out[i, 4], out[i, 5] = th3, th2, w3, w2, a3, a2
        point(out, i, 6, bx, by, vbx, vby, abx, aby, th2, w2, a2, 0.0, 0.0)
        point(out, i, 12, bx, by, vbx, vby, abx, aby, th2, w2, a2, bc, 0.0)
        point(out, i, 18, bx, by, vbx, vby, abx, aby, th2, w2, a2, eu, ev)
        out[i, 24], out[i, 25], out[i, 26] = th1, omega, alpha
        point(out, i, 27, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, th1, omega, alpha, prm[8], prm[9])
        out[i, 33], out[i, 34], out[i, 35] = th2, w2, a2
        point(out, i, 36, bx, by, vbx, vby, abx, aby, th2, w2, a2, prm[10], prm[11])
        out[i, 42], out[i, 43], out[i, 44] = th3, w3, a3
        point(out, i, 45, pdx, pdy, 0.0, 0.0, 0.0, 0.0, th3, w3, a3, 0.5 * cd, 0.0)


def take_up_kernel(phi, omega: float, alpha: float, prm: np.ndarray, out: np.ndarray) -> None:
    """:func:`_kernel` as plain Python: out (n, len(COLUMNS)) gets every output at the angles phi."""
    _kernel(phi, omega, alpha, prm, out, _point)


def numba_kernel():
    """:func:`take_up_kernel` compiled by numba (``njit``, no fastmath: IEEE as sewgen's C), or None where numba
    is not installed."""
    try:
        import numba
    except ImportError:
        return None
    point = numba.njit(_point)
    kernel = numba.njit(_kernel)
    return lambda phi, omega, alpha, prm, out: kernel(phi, omega, alpha, prm, out, point)


def pylinkage_take_up(p: dict, n: int, omega: float, q_first: tuple):
    """The take_up four-bar in pylinkage (when installed; else None): a crank from the shaft phase, an RRR dyad
    for the rocker pin C started at sewgen's first C (q_first: its x, y; pylinkage keeps the branch nearest the
    last position) and a fixed dyad for the thread eye E. Returns run: run() sweeps one revolution in n equal
    steps with pylinkage's numba solver and gives (positions, velocities, accelerations) of B, C and E, each
    (n, 3, 2)."""
    try:
        import pylinkage as pl
    except ImportError:
        return None
    ab, bc, cd, be, ce = p["crank"], p["lever_bc"], p["rocker"], p["lever_be"], p["lever_ce"]
    step = 2 * math.pi / n
    origin = pl.Ground(0.0, 0.0, name="A")
    pivot = pl.Ground(p["rocker_pivot_x"], p["rocker_pivot_y"], name="D")
    crank = pl.Crank(anchor=origin, radius=ab, angular_velocity=step, initial_angle=p["crank.phase"] - step,
                     name="B")
    rocker_pin = pl.RRRDyad(crank.output, pivot, distance1=bc, distance2=cd, x=q_first[0], y=q_first[1], name="C")
    eu = (bc * bc + be * be - ce * ce) / (2 * bc)
    eye = pl.FixedDyad(crank.output, rocker_pin, distance=be, angle=math.atan2(math.sqrt(be * be - eu * eu), eu),
                       name="E")
    linkage = pl.Linkage([origin, pivot, crank, rocker_pin, eye], name="take_up")
    linkage.set_input_velocity(crank, omega=omega)
    parts = [linkage.components.index(c) for c in (crank, rocker_pin, eye)]

    def run():
        pos, vel, acc = linkage.step_fast_with_kinematics(iterations=n)
        return pos[:, parts], vel[:, parts], acc[:, parts]

    return run

"""The machine's shaking force and moments as the moving parts put them on the frame, without their weight.

:class:`sewgen.machine.MachineAnalysis` keeps the frame's reactions *on the parts*: ``shaking_force`` is
Σ m a_G − Σ m g (process loads internal), so it holds the parts' static weight — the frame holding them up —
besides the inertia forces. What shakes the base is the inertia alone, acting *on the frame*:

    F = −Σ m a_G,        M = −Σ [(r_G − O) × m a_G + I_G α]   (the drive torque counted as frame),

summed over every moving part of every group (each group's parts in its plane z, for the moments about x and
y) and the upper shaft's core masses. The weight of the moving parts, W = Σ m g, is constant and acts on the
frame besides (its moment about O moves with the centres of mass); :func:`weight` gives it apart. Then
F + W = −(the frame's force on the parts with the process loads put back), which the tests check.
"""
from __future__ import annotations

import numpy as np


def moving_mass(a) -> float:
    """Σ m of every moving part (kg): the groups' bodies and the shaft core's masses."""
    return sum(b.mass for b in a.moving_bodies()) + sum(sm.mass for sm in a.machine.shaft.masses)


def weight(a) -> np.ndarray:
    """(2,) the moving parts' weight, the force it puts on the frame (N): Σ m g, constant."""
    return moving_mass(a) * np.asarray(a.machine.gravity, dtype=float)


def _placed(b):
    """Moving body ``b``'s (sewgen.machine.MovingBody) centre of mass (X, Y, Z), its acceleration (AX, AY, AZ) and
    its rotation axis (3,) in the machine frame: a group across the shaft is its plane at z = ``Group.z``; one
    along it (``frame = "along"``) has its x along the machine's z and turns about the machine's −x
    (sewgen.machine.Group.to_machine), but for its cranks, which turn about the shaft."""
    g, c = b.group, b.motion.com
    zero = 0.0 * c.x
    pos = tuple(v + zero for v in g.to_machine(c.x, c.y))
    acc = tuple(v + zero for v in g.force_to_machine(c.ax, c.ay, zero))
    axis = (0.0, 0.0, 1.0) if g.along and b.driven else tuple(float(v) for v in g.force_to_machine(0.0, 0.0, 1.0))
    return pos, acc, axis


def shaking_force(a) -> np.ndarray:
    """(n, 2) the dynamic shaking force on the frame, −Σ m a_G over every moving part (N); no weight. The parts
    of a group along the shaft move partly along it (z): that component is not in the plane x–y."""
    out = np.zeros((len(a.phi), 2))
    for b in a.moving_bodies():
        _pos, acc, _axis = _placed(b)
        out[:, 0] -= b.mass * acc[0]
        out[:, 1] -= b.mass * acc[1]
    for sm, _pos, _vel, acc in a.core:
        out -= sm.mass * acc
    return out


def shaking_moments(a, about=(0.0, 0.0, 0.0)) -> np.ndarray:
    """(n, 3) the dynamic shaking moment on the frame about the point ``about`` (x, y, z; m), about the x, y and
    z axes (N m): −Σ (r − O) × m a_G − Σ I α (each about its body's axis: z for a group across the shaft, −x
    for one along it), the shaft core's included; each group's parts placed in the machine frame (a group across
    the shaft in its plane z = ``Group.z``), each core mass at its own z; no weight."""
    ox, oy, oz = about
    out = np.zeros((len(a.phi), 3))
    out[:, 2] -= a.machine.shaft.inertia * a.alpha
    for b in a.moving_bodies():
        (x, y, z), (ax, ay, az), axis = _placed(b)
        fx, fy, fz = -b.mass * ax, -b.mass * ay, -b.mass * az
        spin = b.inertia * b.motion.alpha
        out[:, 0] += (y - oy) * fz - (z - oz) * fy - spin * axis[0]
        out[:, 1] += (z - oz) * fx - (x - ox) * fz - spin * axis[1]
        out[:, 2] += (x - ox) * fy - (y - oy) * fx - spin * axis[2]
    for sm, pos, _vel, acc in a.core:
        fx, fy = -sm.mass * acc[:, 0], -sm.mass * acc[:, 1]
        out[:, 0] -= (sm.z - oz) * fy
        out[:, 1] += (sm.z - oz) * fx
        out[:, 2] += (pos[:, 0] - ox) * fy - (pos[:, 1] - oy) * fx
    return out


__all__ = ["moving_mass", "shaking_force", "shaking_moments", "weight"]

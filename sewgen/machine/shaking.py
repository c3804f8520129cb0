"""The shaking force and moments on the frame, the moving parts' weight on the frame: the sign convention.

Every force here says what acts on what. Over every moving part (each group's bodies, placed in the machine
frame — a group across the shaft in its plane z = ``Group.z`` — and the upper shaft's core masses):

* the **shaking force and moments on the frame**, the moving parts' inertia alone, acting on the frame:

      F_shake = −Σ m a_G,        M_shake = −Σ [(r_G − O) × m a_G + I_G α]   (the drive torque counted as frame);

* the **moving parts' weight on the frame**, W = Σ m g (constant), and its moment Σ (r_G − O) × m g (it moves
  with the centres of mass);
* the **frame's force on the moving parts**, R = Σ m a_G − Σ m g − Σ loads − belt pull (drives counted as
  frame): what the frame's joints and bearings put on the parts (:attr:`MachineAnalysis.frame_force_on_parts`,
  for one group :attr:`ForceAnalysis.frame_force_on_parts`). The process loads (thread, presser foot, cloth)
  and the belt's pull react inside the machine, so

      F_shake + W = −(R + Σ loads + belt pull),

  which the tests check at every angle (the left side from the kinematics here, the right from the compiled
  kernels' frame reactions).

The functions below take a :class:`sewgen.machine.MachineAnalysis`; its properties of the same names call them.
"""
from __future__ import annotations

import warnings

import numpy as np


def moving_mass(a) -> float:
    """Σ m of every moving part (kg): the groups' bodies and the shaft core's masses."""
    return sum(b.mass for b in a.moving_bodies()) + sum(sm.mass for sm in a.machine.shaft.masses)


def weight_on_frame(a) -> np.ndarray:
    """(2,) the moving parts' weight on the frame, W = Σ m g (N), constant."""
    return moving_mass(a) * np.asarray(a.machine.gravity, dtype=float)


def _placed(b):
    """Moving body ``b``'s (sewgen.machine.MovingBody) centre of mass (X, Y, Z), its acceleration (AX, AY, AZ) and
    its rotation axis (3,) in the machine frame: a group across the shaft is its plane at z = ``Group.z``; one
    along it (``frame = "along"``) has its x along the machine's z and turns about the machine's −x
    (sewgen.machine.Group.to_machine), but for its cranks, which turn about the shaft."""
    g, c = b.group, b.motion.com
    zero = 0.0 * c.x
    z, az = (zero, zero) if c.z is None else (c.z, c.az)  # a spatial crank's centre of mass leaves the plane
    pos = tuple(v + zero for v in g.to_machine(c.x, c.y, z))
    acc = tuple(v + zero for v in g.force_to_machine(c.ax, c.ay, az))
    axis = (0.0, 0.0, 1.0) if g.along and b.driven else tuple(float(v) for v in g.force_to_machine(0.0, 0.0, 1.0))
    return pos, acc, axis


def shaking_force_on_frame(a, group=None) -> np.ndarray:
    """(n, 2) the shaking force on the frame, F_shake = −Σ m a_G (N; the module's convention): inertia only, no
    weight. With ``group`` (a :class:`sewgen.machine.Group`), that group's moving parts alone (no shaft core).
    The parts of a group along the shaft move partly along it (z): that component is not in the plane x–y."""
    out = np.zeros((len(a.phi), 2))
    for b in a.moving_bodies(group):
        _pos, acc, _axis = _placed(b)
        out[:, 0] -= b.mass * acc[0]
        out[:, 1] -= b.mass * acc[1]
    if group is None:
        for sm, _pos, _vel, acc in a.core:
            out -= sm.mass * acc
    return out


def add_moment(out, r, f, about) -> None:
    """out (n, 3) += (r − O) × f: the moment about the point ``about`` (x, y, z) of a force f = (fx, fy, fz)
    acting at r = (x, y, z) (each an array of n or a number)."""
    dx, dy, dz = (r[k] - about[k] for k in range(3))
    fx, fy, fz = f
    out[:, 0] += dy * fz - dz * fy
    out[:, 1] += dz * fx - dx * fz
    out[:, 2] += dx * fy - dy * fx


def shaking_moments_on_frame(a, about=(0.0, 0.0, 0.0)) -> np.ndarray:
    """(n, 3) the shaking moments on the frame about the point ``about`` (x, y, z; m), about the x, y and z axes
    (N m): M_shake = −Σ (r − O) × m a_G − Σ I α (the module's convention; each I α about its body's axis: z for a
    group across the shaft, −x for one along it), the shaft core's included, each core mass at its own z; inertia
    only, no weight."""
    out = np.zeros((len(a.phi), 3))
    out[:, 2] -= a.machine.shaft.inertia * a.alpha
    for b in a.moving_bodies():
        pos, (ax, ay, az), axis = _placed(b)
        add_moment(out, pos, (-b.mass * ax, -b.mass * ay, -b.mass * az), about)
        spin = b.inertia * b.motion.alpha
        for k in range(3):
            out[:, k] -= spin * axis[k]
    for sm, pos, _vel, acc in a.core:
        add_moment(out, (pos[:, 0], pos[:, 1], sm.z), (-sm.mass * acc[:, 0], -sm.mass * acc[:, 1], 0.0), about)
    return out


def weight_moments_on_frame(a, about=(0.0, 0.0, 0.0)) -> np.ndarray:
    """(n, 3) the moments of the moving parts' weight on the frame about the point ``about`` (x, y, z; m), about
    the x, y and z axes (N m): Σ (r_G − O) × m g (the module's convention), the shaft core's masses included."""
    gx, gy = (float(v) for v in a.machine.gravity)
    out = np.zeros((len(a.phi), 3))
    for b in a.moving_bodies():
        pos, _acc, _axis = _placed(b)
        add_moment(out, pos, (b.mass * gx, b.mass * gy, 0.0), about)
    for sm, pos, _vel, _acc in a.core:
        add_moment(out, (pos[:, 0], pos[:, 1], sm.z), (sm.mass * gx, sm.mass * gy, 0.0), about)
    return out


def _deprecated(old: str, new: str) -> None:
    warnings.warn(f"sewgen.machine.shaking.{old} is deprecated; use {new}", DeprecationWarning, stacklevel=3)


def shaking_force(a) -> np.ndarray:
    """Deprecated name of :func:`shaking_force_on_frame`."""
    _deprecated("shaking_force", "shaking_force_on_frame")
    return shaking_force_on_frame(a)


def shaking_moments(a, about=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Deprecated name of :func:`shaking_moments_on_frame`."""
    _deprecated("shaking_moments", "shaking_moments_on_frame")
    return shaking_moments_on_frame(a, about)


def weight(a) -> np.ndarray:
    """Deprecated name of :func:`weight_on_frame`."""
    _deprecated("weight", "weight_on_frame")
    return weight_on_frame(a)


__all__ = ["moving_mass", "shaking_force_on_frame", "shaking_moments_on_frame", "weight_moments_on_frame",
           "weight_on_frame"]

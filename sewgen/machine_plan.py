"""The call plan of a machine analysis: what :meth:`sewgen.machine.Machine.analyze` needs that depends on the
machine alone, made once per machine state, and the lean per-call path that uses it (issue 14: the JB1-3
machine at 72 positions in < 0.3 ms).

A plan holds, per group, the C-ready vectors of its run (SI parameters, held inputs, branches, gravity, Newton
options: harvested from one :meth:`Mechanism.prepare` of the group, so every conversion and check is the
engine's own), its loads converted once (:func:`sewgen.loads.load_layout`), the C function and descriptor of
its sweep, and for the shaft the bearing positions, the belt, the crank-pin force columns of the groups across
the shaft. Per call only what depends on the shaft angles is computed: each group's arrays in one fresh block
(inputs, outputs, loads; never shared with an earlier result), the load windows' masks, one C call, the angles
made continuous in C.

Machines are plain (mutable) dataclasses and callers do change them in place (``m.gravity = ...``), so a plan
carries the :func:`machine_state` it was made from and is rebuilt whenever the machine's state differs: a
cached plan never outlives what it was computed from. Machines made with other parameters (``replace``, a
design study's variants) are other objects with their own plans.

Anything this path does not handle (per-position speeds, quantity strings, a position that fails) returns
None, and ``analyze`` takes the general path, which gives the same results and raises the typed errors.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from .forces import ForceAnalysis, RunSettings
from .loads import load_layout, place_loads
from .mechanism import SINGULAR_TOL
from .results import Motion

_SCALAR = (float, int, np.float64)


def machine_state(machine) -> tuple:
    """Everything of ``machine`` an analysis plan is computed from, by value (dicts and lists copied): equal
    states give equal plans."""
    sh = machine.shaft
    gv = machine.gravity
    groups = tuple((g, g.mechanism, g.phase, dict(g.params), dict(g.held), dict(g.branch), tuple(g.loads),
                    dict(g.axial), g.frame, g.origin, g.plane) for g in machine.groups)
    return (tuple(np.asarray(gv, dtype=float).tolist()), sh, sh.front, sh.rear, sh.inertia, tuple(sh.masses),
            sh.pulley, sh.belt, sh.friction, sh.journal_radius, groups)


def gravity_polar(gravity) -> tuple[float, float]:
    """(magnitude, direction) of the machine's gravity vector, as each group's sweep is given it."""
    g_mag = float(np.hypot(*gravity))
    g_dir = math.atan2(gravity[1], gravity[0]) if g_mag else -math.pi / 2
    return g_mag, g_dir


class GroupCall:
    """One group's kinetostatic sweep with everything but the shaft angles fixed: :meth:`run` is
    ``mechanism.kinetostatics(phi + phase, speed, accel, loads=..., gravity=..., params=..., held=...,
    branch=...)`` (the same arrays, bit for bit) without the per-call conversions."""

    __slots__ = ("group", "mech", "phase", "loads", "settings", "nq", "nobs", "nfo", "nload", "width", "call",
                 "angle", "keep", "torque_column")

    def __init__(self, g, g_mag: float, g_dir: float):
        mech = g.mechanism
        self.group, self.mech, self.phase = g, mech, g.phase
        loads = [replace(ld, window=None if ld.window is None else tuple(w + g.phase for w in ld.window))
                 for ld in g.loads]  # Group.sweep_loads: the windows in the group's own shaft angle
        # One prepare() of the group: the engine's own conversions and checks of params, held, branch, gravity
        probe = mech.prepare(np.zeros(1), None, 0.0, params=g.params or None, held=g.held or None,
                             branch=g.branch or None, forces=True, loads=loads, gravity=g_mag,
                             gravity_direction=g_dir)
        s = probe.settings
        for arr in (probe.params, probe.held, probe.branch, s.gravity):
            arr.flags.writeable = False  # shared by every result of this plan, like the mechanism's defaults
        self.loads = load_layout(mech, loads) if loads else None
        self.settings = (probe.params, probe.held, probe.branch, s.gravity, s.moment_about)
        sizes = mech.description.sizes
        self.nq, self.nobs, self.nfo = sizes["nq"], sizes["nobs"], sizes["nfo"]
        self.nload = sizes["nload"] if loads else 0
        self.torque_column = mech.description.output_column("shaft.torque")  # ForceAnalysis.torque("shaft")
        self.width = 4 + 3 * self.nq + self.nobs + self.nfo + self.nload  # doubles per position in the block
        ffi, d = mech.ffi, mech._ptr
        self.keep = (probe.params, probe.held, probe.branch, probe.guess, s.gravity)  # alive with the pointers
        self.call = (mech.lib.sg_sweep_forces, mech._descriptor, d("double *", probe.held),
                     d("double *", probe.params), d("int *", probe.branch), d("double *", probe.guess),
                     probe.options, d("double *", s.gravity), ffi)
        _angle, nqa, qa_p, noa, oa_p = mech._angle
        self.angle = (nqa, qa_p, noa, oa_p) if (nqa or noa) else None

    def run(self, rows, k: int, status, blk, o: int, sort: bool):
        """The group's ForceAnalysis over its rows ``k`` of ``rows`` (phi, omega, alpha, err: (4, groups, n), the
        head of the analysis' block ``blk``), ``status`` and its own region of ``blk`` from offset ``o`` (q,
        qd, qdd, obs, frc, loads), or None where a position fails (the general path then raises its typed
        error). ``sort``: the angles are not in non-decreasing order."""
        phi_g, omega, alpha, err = rows[:, k]
        ng, n = rows.shape[1], rows.shape[2]
        nq, nobs, nfo, nload = self.nq, self.nobs, self.nfo, self.nload
        nn = n * nq
        q, qd, qdd = blk[o:o + 3 * nn].reshape(3, n, nq)
        o2 = o + 3 * nn
        obs = blk[o2:o2 + n * nobs].reshape(n, nobs)
        o3 = o2 + n * nobs
        frc = blk[o3:o3 + n * nfo].reshape(n, nfo)
        o4 = o3 + n * nfo
        fn, desc, held_p, p_p, branch_p, guess_p, opt, gv_p, ffi = self.call
        base = ffi.from_buffer("double[]", blk)
        head = base + k * n  # phi; omega, alpha, err each ng * n further
        ld, placed = None, []
        loads_p = ffi.NULL
        if self.loads is not None:
            ld, placed = place_loads(self.loads, phi_g, nload, blk[o4:o4 + n * nload].reshape(n, nload))
            ld.flags.writeable = False
            loads_p = base + o4
        order, order_p = None, ffi.NULL
        if sort:
            order = np.argsort(phi_g, kind="stable").astype(np.uintp)
            order_p = ffi.from_buffer("size_t[]", order)
        qp, op = base + o, base + o2
        step = ng * n
        if fn(desc, n, head, head + step, head + 2 * step, held_p, p_p, branch_p, guess_p, opt, order_p, gv_p,
              loads_p, qp, qp + nn, qp + 2 * nn, op, head + 3 * step, base + o3, ffi.from_buffer("int[]", status)):
            return None
        if self.angle is not None:
            nqa, qa_p, noa, oa_p = self.angle
            self.mech.lib.sg_make_continuous(n, nq, nobs, qp, op, nqa, qa_p, noa, oa_p, order_p)
        p, held, branch, gv, about = self.settings
        settings = RunSettings(p, held, branch, gv, ld, about, tuple(placed))
        motion = Motion(self.mech, phi_g, omega, alpha, q, qd, qdd, obs, err, SINGULAR_TOL)
        return ForceAnalysis(self.mech, motion, frc, settings)

    def size(self, n: int) -> int:
        """Doubles of the group's own region of an analysis' block at ``n`` positions."""
        return (3 * self.nq + self.nobs + self.nfo + self.nload) * n

    def frc_offset(self, n: int) -> int:
        """Offset of ``frc`` in the group's region."""
        return (3 * self.nq + self.nobs) * n


class ShaftPlan:
    """The upper shaft's fixed data: bearings, belt, core masses, and per group across the shaft the columns of
    its cranks' pivot forces on the frame (``frame_force(<crank>.pivot)``) with their sign and axial z."""

    __slots__ = ("zA", "zB", "belt", "pulley_belt", "cranks", "along", "ncore", "weights", "axis_force",
                 "axis_moment")

    def __init__(self, machine):
        sh = machine.shaft
        self.zA, self.zB = sh.front, sh.rear
        self.belt = np.asarray(sh.belt, dtype=float)[None, :]
        self.pulley_belt = (sh.pulley - sh.front) * self.belt
        self.cranks = []  # (group name, label, z, column x, column y, sign) of every crank across the shaft
        self.along = any(g.along for g in machine.groups)
        for g in machine.groups:
            desc = g.mechanism.description
            for body, z in g.axial.items():
                name = f"{body}.pivot"
                r = desc.reaction(name)
                if r.kind == "revolute":
                    cx, cy = r.offset, r.offset + 1
                else:
                    cx, cy = desc.output_column(f"{name}.fx"), desc.output_column(f"{name}.fy")
                self.cranks.append((g.name, f"{g.name}.{body}", z, cx, cy, -1.0 if r.a == "ground" else 1.0,
                                    g.along))
        self.ncore = len(sh.masses)
        # a core mass on the axis (r = 0) is at rest: its d'Alembert force m (g − 0) and the terms 0·f of its
        # moment r × m (a − g) are constants (the same operations as sewgen.machine's _shaft on arrays of zeros)
        gv = np.asarray(machine.gravity)[None, :]
        self.axis_force = [sm.mass * (gv - 0.0) for sm in sh.masses]
        self.axis_moment = []
        for sm in sh.masses:
            f = sm.mass * (np.zeros((1, 2)) - gv)
            self.axis_moment.append((0.0 * f[0, 1], 0.0 * f[0, 0]))
        # arms about the front bearing of the stacked forces: the zero row, the cranks, the belt, the core masses
        self.weights = np.array([1.0] + [c[2] - sh.front for c in self.cranks] + [sh.pulley - sh.front]
                                + [sm.z - sh.front for sm in sh.masses])[:, None, None]


class Plan:
    """A machine's analysis plan (see the module docstring)."""

    __slots__ = ("state", "gravity", "groups", "shaft", "_layouts", "sorted")

    def __init__(self, machine, state):
        self.state = state
        self.gravity = gravity_polar(machine.gravity)
        self.groups = [GroupCall(g, *self.gravity) for g in machine.groups]
        self.shaft = ShaftPlan(machine)
        self._layouts = {}
        first = self.groups[0].mech
        self.sorted = (first.lib.sg_sorted, first.ffi)  # the runtime's test of ascending angles

    def layout(self, n: int):
        """(group offsets in the block, block size, flat indices (k, n, 2) of the crank forces' columns in the
        block, (k, 1, 1) their signs) at ``n`` positions; made once per ``n``."""
        got = self._layouts.get(n)
        if got is None:
            ng = len(self.groups)
            offsets, o = [], 4 * ng * n
            for call in self.groups:
                offsets.append(o)
                o += call.size(n)
            index = {call.group.name: (off + call.frc_offset(n), call.nfo) for call, off in zip(self.groups, offsets)}
            rows = np.arange(n)[:, None]
            idx = np.array([index[gname][0] + rows * index[gname][1] + np.array([cx, cy])
                            for gname, _label, _z, cx, cy, _sign, _along in self.shaft.cranks], dtype=np.intp)
            sign = np.array([c[5] for c in self.shaft.cranks], dtype=float)[:, None, None]
            torque = np.array([off + call.frc_offset(n) + np.arange(n) * call.nfo + call.torque_column
                               for call, off in zip(self.groups, offsets)], dtype=np.intp)
            got = (offsets, o, idx.reshape(len(self.shaft.cranks), n, 2), sign, torque.reshape(ng, n))
            if len(self._layouts) >= 8:
                self._layouts.clear()
            self._layouts[n] = got
        return got

    def run(self, phi: np.ndarray, w: float, accel: float, progress=None):
        """(group name -> ForceAnalysis, the crank forces stacked for the shaft or None) at machine shaft angles
        ``phi``, in one fresh block; None where anything fails."""
        n, ng = phi.shape[0], len(self.groups)
        offsets, size, idx, sign, torque = self.layout(n)
        blk = np.empty(size)
        rows = blk[:4 * ng * n].reshape(4, ng, n)
        phis, omegas, alphas = rows[0], rows[1], rows[2]
        for k, call in enumerate(self.groups):
            np.add(phi, call.phase, out=phis[k])
        sorted_, ffi = self.sorted
        sort = n > 1 and not (sorted_(n, ffi.from_buffer("double[]", phi)) if phi.flags.c_contiguous
                              else (phi[1:] >= phi[:-1]).all())
        omegas.fill(w)
        alphas.fill(accel)
        status = np.zeros((ng, n), dtype=np.intc)
        out = {}
        for k, call in enumerate(self.groups):
            if progress:
                progress(f"{call.group.name}: {n} positions", k, ng)
            fa = call.run(rows, k, status[k], blk, offsets[k], sort)
            if fa is None:
                return None
            out[call.group.name] = fa
        stack = torques = None
        if not self.shaft.along:  # the crank forces, sign applied, after a zero row (sewgen.machine: _shaft)
            stack = np.empty((1 + len(idx) + 1 + self.shaft.ncore, n, 2))
            stack[0] = 0.0
            np.multiply(blk[idx], sign, out=stack[1:1 + len(idx)])
            torques = np.empty((ng + 3, n))  # 0, the groups' shaft torques, the core's, the bearings' friction
            torques[0] = 0.0
            torques[1:ng + 1] = blk[torque]
        return out, stack, torques


def plan_of(machine) -> Plan:
    """``machine``'s plan for its current state: the cached one while the state is unchanged, else a new one."""
    state = machine_state(machine)
    plan = machine.__dict__.get("_plan")
    if plan is None or plan.state != state:
        plan = Plan(machine, state)
        machine.__dict__["_plan"] = plan
    return plan


def scalar(value) -> float | None:
    """A finite real scalar (not a bool, not a string) as a float, else None."""
    if type(value) in _SCALAR:
        v = float(value)
        if math.isfinite(v):
            return v
    return None

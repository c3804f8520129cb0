"""The call plan of a machine analysis: what :meth:`sewgen.machine.Machine.analyze` needs that depends on the
machine alone, made once per machine state, and the lean per-call path that uses it (so that a small analysis,
the JB1-3 machine at 72 positions, pays no conversion or check twice).

A plan holds, per group, the C-ready vectors of its run (SI parameters, held inputs, branches, gravity, Newton
options: harvested from one :meth:`Mechanism.prepare` of the group, so every conversion and check is the
engine's own), its loads converted once (:func:`sewgen.engine.loads.load_layout`), the C function and descriptor of
its sweep, and for the shaft its constants (:class:`ShaftCall`) and the crank-pin force columns of the groups
across the shaft. Per call only what depends on the shaft angles is computed: each group's arrays in one fresh
block (inputs, outputs, loads; never shared with an earlier result), its loads placed (one C call), its sweep
(one C call), its angles made continuous (one C call), and then the shaft's bearings and torque (one C call,
sg_shaft, which the general path calls too).

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

from sewgen.engine.forces import ForceAnalysis, RunSettings
from sewgen.engine.loads import load_layout, place_loads
from sewgen.engine.mechanism import SINGULAR_TOL
from sewgen.engine.results import Motion

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
                 "angle", "keep", "torque_column", "fixed")

    def __init__(self, g, g_mag: float, g_dir: float):
        mech = g.mechanism
        self.group, self.mech, self.phase = g, mech, g.phase
        loads = [replace(ld, window=None if ld.window is None else tuple(w + g.phase for w in ld.window))
                 for ld in g.loads]  # Group.sweep_loads: the windows in the group's own shaft angle
        # One prepare() of the group: the engine's own conversions and checks of params, held, branch, gravity
        probe = mech.prepare(np.zeros(1), None, 0.0, params=g.params or None, held=g.held or None,
                             branch=g.branch or None, forces=True, loads=loads, gravity=g_mag,
                             gravity_direction=g_dir, layout="arrays")
        s = probe.settings
        for arr in (probe.params, probe.held, probe.branch, s.gravity):
            arr.flags.writeable = False  # shared by every result of this plan, like the mechanism's defaults
        self.loads = load_layout(mech, loads) if loads else None
        self.settings = (probe.params, probe.held, probe.branch, s.gravity, s.moment_about)
        # without loads the run's settings are the same every call: one frozen object of read-only arrays
        self.fixed = None if loads else RunSettings(*self.settings[:4], None, s.moment_about, ())
        sizes = mech.description.sizes
        self.nq, self.nobs, self.nfo = sizes["nq"], sizes["nobs"], sizes["nfo"]
        self.nload = sizes["nload"] if loads else 0
        self.torque_column = mech.description.output_column("shaft.torque")  # ForceAnalysis.torque("shaft")
        self.width = 4 + 3 * self.nq + self.nobs + self.nfo + self.nload  # doubles per position in the block
        # the group's sg_request: what every run shares, set once (self.keep: the buffers its pointers point
        # into); run() copies it and fills in the positions' arrays
        req, self.keep = probe.request()
        c = mech.in_c
        self.call = (mech.lib.sg_sweep, c.descriptor, req, mech.ffi)
        self.angle = (c.nqa, c.qcols, c.noa, c.ocols) if (c.nqa or c.noa) else None

    def run(self, phi, w: float, accel: float, blk, base, o: int, status, sort: bool):
        """The group's ForceAnalysis at machine shaft angles ``phi`` (``sort``: they do not ascend) in its region
        of the analysis' block ``blk`` from offset ``o`` (``base``: the block's C pointer), laid out as
        sg_solve_lean's (phi + phase, omega, alpha, err, then q, qd, qdd, obs by rows; see
        :meth:`Motion.of_block`) and followed by frc and the loads; or None where a position fails (the general
        path then raises its typed error). ``status``: the positions' C statuses (scratch)."""
        n, nq, nobs, nfo = phi.shape[0], self.nq, self.nobs, self.nfo
        nn = n * nq
        ph = blk[o:o + 3 * n]
        np.add(phi, self.phase, out=ph[:n])
        ph[n:2 * n] = w
        ph[2 * n:] = accel
        o2 = o + 4 * n + 3 * nn  # obs
        o3 = o2 + n * nobs  # frc
        fn, desc, template, ffi = self.call
        head = base + o
        loads_p, settings = ffi.NULL, self.fixed
        if self.loads is not None:
            o4 = o3 + n * nfo
            ld, placed = place_loads(self.loads, ph[:n], self.nload, blk[o4:o4 + n * self.nload].reshape(n, -1))
            ld.flags.writeable = False
            loads_p = base + o4
            p, held, branch, gv, about = self.settings
            settings = RunSettings(p, held, branch, gv, ld, about, tuple(placed))
        order_p = ffi.NULL
        if sort:
            order = np.argsort(ph[:n], kind="stable").astype(np.uintp)
            order_p = ffi.from_buffer("size_t[]", order)
        qp = head + 4 * n
        req = ffi.new("sg_request *", template[0])  # a copy: one plan may run in several threads at once
        req.n, req.phi, req.omega, req.alpha, req.order, req.loads = n, head, head + n, head + 2 * n, order_p, loads_p
        req.q, req.qd, req.qdd, req.obs, req.err, req.frc = qp, qp + nn, qp + 2 * nn, base + o2, head + 3 * n, base + o3
        req.status = status
        if fn(desc, req):
            return None
        if self.angle is not None:
            nqa, qa_p, noa, oa_p = self.angle
            self.mech.lib.sg_make_continuous(n, nq, nobs, qp, base + o2, nqa, qa_p, noa, oa_p, order_p)
        motion = Motion.of_block(self.mech, blk[o:o3], n, nq, nobs, SINGULAR_TOL)
        return ForceAnalysis(self.mech, motion, blk[o3:o3 + n * nfo].reshape(n, nfo), settings)

    def size(self, n: int) -> int:
        """Doubles of the group's own region of an analysis' block at ``n`` positions."""
        return self.width * n

    def frc_offset(self, n: int) -> int:
        """Offset of ``frc`` in the group's region."""
        return (4 + 3 * self.nq + self.nobs) * n


class ShaftCall:
    """The upper shaft's constants as sg_shaft (csrc/sg_runtime.c) reads them: the core masses (mass, radius, cos
    and sin of the angle, arm about the front bearing), the belt and its arm, gravity, the core's inertia, the
    bearings' span and friction radius. The planned and the general analysis both run :meth:`run`, so they
    agree to the bit."""

    __slots__ = ("masses", "core", "belt", "belt_arm", "gravity", "inertia", "span", "mu_r", "front", "fn", "ffi",
                 "_p")

    def __init__(self, machine):
        sh = machine.shaft
        self.masses, self.front = tuple(sh.masses), sh.front
        self.core = np.array([(sm.mass, sm.radius, math.cos(sm.angle), math.sin(sm.angle), sm.z - sh.front)
                              for sm in sh.masses], dtype=float).reshape(len(sh.masses), 5)
        self.belt = np.array(sh.belt, dtype=float)
        self.belt_arm = float(sh.pulley - sh.front)
        self.gravity = np.array(machine.gravity, dtype=float)
        self.inertia, self.span = float(sh.inertia), float(sh.rear - sh.front)
        self.mu_r = float(sh.friction * sh.journal_radius)
        mech = machine.groups[0].mechanism
        self.fn, self.ffi = mech.lib.sg_shaft, mech.ffi
        self._p = tuple(self.ffi.from_buffer("double[]", a) for a in (self.belt, self.core, self.gravity))

    def run(self, phi, omega, alpha, src, forces, torques):
        """(front (n, 2), rear (n, 2), torque (n,), the bearings' friction torque (n,), [(mass, position,
        velocity, acceleration)] of the core, all finite) at ``phi`` with ``omega``, ``alpha`` ((n,) each,
        contiguous), the forces on the core and the groups' shaft torques read from ``src`` at ``forces`` and
        ``torques``: :meth:`layout`'s."""
        n, d = phi.shape[0], self.ffi.from_buffer
        ncore = len(self.masses)
        out = np.empty(n * (6 + 6 * ncore))
        nf, f_off, f_step, f_sign, f_arm = forces
        nt, t_off, t_step = torques
        belt_p, core_p, g_p = self._p
        finite = self.fn(n, d("double[]", phi), d("double[]", omega), d("double[]", alpha), d("double[]", src), nf,
                         f_off, f_step, f_sign, f_arm, nt, t_off, t_step, belt_p, self.belt_arm, ncore, core_p, g_p,
                         self.inertia, self.span, self.mu_r, d("double[]", out))
        kin = out[6 * n:].reshape(ncore, 3, n, 2)
        core = [(sm, kin[k, 0], kin[k, 1], kin[k, 2]) for k, sm in enumerate(self.masses)]
        return out[:2 * n].reshape(n, 2), out[2 * n:4 * n].reshape(n, 2), out[4 * n:5 * n], out[5 * n:6 * n], core, \
            bool(finite)

    def layout(self, columns, steps, signs, arms, torque_offsets, torque_steps):
        """(forces, torques) as :meth:`run` reads them: the count and C arrays of the cranks' x and y columns'
        offsets, their steps, signs and arms, then of the torques' offsets and steps."""
        d = self.ffi.from_buffer
        forces = (len(steps), d("size_t[]", np.asarray(columns, dtype=np.uintp).reshape(-1)),
                  d("size_t[]", np.asarray(steps, dtype=np.uintp)), d("double[]", np.asarray(signs, dtype=float)),
                  d("double[]", np.asarray(arms, dtype=float)))
        return forces, (len(torque_steps), d("size_t[]", np.asarray(torque_offsets, dtype=np.uintp)),
                        d("size_t[]", np.asarray(torque_steps, dtype=np.uintp)))


class ShaftPlan:
    """The upper shaft's fixed data: its :class:`ShaftCall`, and per group across the shaft the columns of its
    cranks' pivot forces on the frame (``frame_force(<crank>.pivot)``) with their sign and arm about the front
    bearing."""

    __slots__ = ("call", "cranks", "along")

    def __init__(self, machine):
        self.call = ShaftCall(machine)
        self.cranks = []  # (group name, column x, column y, sign, arm z - z_A) of every crank across the shaft
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
                self.cranks.append((g.name, cx, cy, -1.0 if r.a == "ground" else 1.0, z - self.call.front))


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
        """(group offsets in the block, block size, the shaft's (forces, torques) in the block for
        :meth:`ShaftCall.run`) at ``n`` positions; made once per ``n``."""
        got = self._layouts.get(n)
        if got is None:
            ng = len(self.groups)
            offsets, o = [], 0
            for call in self.groups:
                offsets.append(o)
                o += call.size(n)
            frc = {call.group.name: (off + call.frc_offset(n), call.nfo) for call, off in zip(self.groups, offsets)}
            cranks = [(frc[g][0] + cx, frc[g][0] + cy, frc[g][1], sign, arm)
                      for g, cx, cy, sign, arm in self.shaft.cranks]
            shaft = self.shaft.call.layout([c[:2] for c in cranks], [c[2] for c in cranks], [c[3] for c in cranks],
                                           [c[4] for c in cranks],
                                           [off + call.frc_offset(n) + call.torque_column
                                            for call, off in zip(self.groups, offsets)],
                                           [call.nfo for call in self.groups])
            got = (offsets, o, shaft)
            if len(self._layouts) >= 8:
                self._layouts.clear()
            self._layouts[n] = got
        return got

    def run(self, phi: np.ndarray, w: float, accel: float, progress=None):
        """(group name -> ForceAnalysis, the shaft's results of :meth:`ShaftCall.run` or None) at machine shaft
        angles ``phi`` (contiguous), in one fresh block; None where anything fails."""
        n, ng = phi.shape[0], len(self.groups)
        offsets, size, shaft = self.layout(n)
        blk = np.empty(size)
        sorted_, ffi = self.sorted
        sort = n > 1 and not sorted_(n, ffi.from_buffer("double[]", phi))
        base = ffi.from_buffer("double[]", blk)
        status = ffi.new("int[]", n)
        out = {}
        for k, call in enumerate(self.groups):
            if progress:
                progress(f"{call.group.name}: {n} positions", k, ng)
            fa = call.run(phi, w, accel, blk, base, offsets[k], status, sort)
            if fa is None:
                return None
            out[call.group.name] = fa
        if self.shaft.along:  # its cranks' forces need the groups' frames (sewgen.machine: crank_loads)
            return out, None
        o = offsets[0]
        return out, self.shaft.call.run(phi, blk[o + n:o + 2 * n], blk[o + 2 * n:o + 3 * n], blk, *shaft)


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

"""A whole machine: mechanism groups on one upper shaft, the shaft as a 3D body on two bearings (seed 000).

Seed 000 splits the JB machine into four groups driven by the upper shaft 上轴组件 1 — needle bar, take-up,
hook drive, feed (§一(一)) — analyses each as a plane mechanism (§二(三)) and the upper shaft in space
(§二(二)1(6), §四): the crank-pin forces of every group act on the shaft at their axial positions, with the
shaft's own unbalance and counterweights; the front and rear bearings 上轴前/后支承 carry them, the belt
pulley supplies the torque.

Here each group is a compiled mechanism swept at φ + phase (φ the machine's shaft angle, needle top at 90°).
The shaft assembly is the shaft with every driven body of every group rigidly on it: a crank's own mass is in
its group, so what the shaft core takes from crank i is the force its pivot puts on the "frame",
``frame_force(<crank>.pivot)``, at the crank's axial position z_i, and the group's driving torque. The core's
own masses (its unbalance, counterweights) are point masses (m, r, angle, z). With bearing A at z_A and B at
z_B, per frame axis c ∈ {x, y} (d'Alembert; the plane forces have no axial component):

    R_B,c = −[Σ_i (z_i − z_A) F_i,c + Σ_k (z_k − z_A) m_k (g_c − a_k,c) + (z_P − z_A) P_c] / (z_B − z_A)
    R_A,c = −R_B,c − Σ_i F_i,c − Σ_k m_k (g_c − a_k,c) − P_c

with P the belt's pull on the pulley at z_P (T1 + T2 along the belt: constant, it does no work).

R = frame on shaft; the bearing loads on the frame are −R. Driving torque at the pulley = Σ group shaft
torques + I_core·α + Σ_k (r_k × m_k (a_k − g))_z. The frame's force on the moving parts (drives counted as
frame, as for a group) is the groups' plus the core's. The shaking force and moments on the frame (inertia
only), the parts' weight on the frame and the frame's force on the parts follow the sign convention stated once
in :mod:`sewgen.machine.shaking`.
"""
from __future__ import annotations

import copy
import math
import warnings
from dataclasses import dataclass, replace
from pathlib import Path
from typing import NamedTuple

import numpy as np

from sewgen.engine.loader import catalog, load
from sewgen.engine.loader import mechanism as catalog_mechanism
from sewgen.errors import BuildError, NonFiniteOutputError, ParameterError, SewgenError
from sewgen.machine import shaking
from sewgen.machine.tables import group_table, machine_table
from sewgen.machine.feed import regulator_angle
from sewgen.engine.loads import load_matrix
from sewgen.machine.plan import ShaftCall, gravity_polar, plan_of, scalar
from sewgen.machine.modelfile import (Declared, GroupSpec, Model, ModelFileError, Shaft, ShaftMass,
    declaration_problem, read_model, read_settings, resolve)
from sewgen.machine.thread import find_point
from sewgen.machine.timing import RULES
from sewgen.roles import STITCH_REGULATOR
from sewgen.units import UnitError, steps_per_turn, to_si


def _deprecated(old: str, new: str) -> None:
    warnings.warn(f"MachineAnalysis.{old} is deprecated; use {new}", DeprecationWarning, stacklevel=3)


@dataclass
class Group:
    """One mechanism group on the upper shaft."""

    name: str
    mechanism: object  # sewgen.Mechanism
    phase: float  # rad: group shaft angle = machine shaft angle + phase
    axial: dict  # driven body -> z on the upper shaft (m)
    params: dict  # SI overrides
    held: dict  # SI held inputs (after converting a stitch length)
    branch: dict
    loads: list  # windows in the machine's shaft angle (seed 000: "relative to the upper-shaft angle")
    stitch: float | None = None  # m, feed groups: the stitch the regulator was set for
    plane: float | None = None  # z of the group's plane (m); None: the mean z of its driven bodies
    frame: str = "across"  # "across": the group's plane is across the shaft (its x, y = the machine's x, y);
    #                       "along": its plane contains the shaft (its x = the machine's z, y = y, z = −x)
    origin: tuple = (0.0, 0.0, 0.0)  # "along": the group's origin in the machine frame (m)

    @property
    def along(self) -> bool:
        return self.frame == "along"

    def to_machine(self, x, y, z=0.0):
        """(X, Y, Z) in the machine frame of the point (x, y, z) of the group's frame, z = 0 its plane (arrays or
        numbers, m)."""
        if not self.along:
            return x, y, self.z + z + 0.0 * np.asarray(x)
        ox, oy, oz = self.origin
        return ox - z + 0.0 * np.asarray(x), oy + y, oz + x

    def force_to_machine(self, fx, fy, fz=0.0):
        """A force (or any vector) of the group's frame in the machine frame: (X, Y, Z) components."""
        if not self.along:
            return fx, fy, fz
        return -fz, fy, fx

    @property
    def z(self) -> float:
        """z of the plane the group's forces act in (m): ``plane`` if the model gives it, else the mean axial
        position of its driven bodies (seed 000 analyses each group as a plane mechanism, §二(三))."""
        if self.along:
            return float(self.origin[0])  # its plane is x = origin x (its own z = 0)
        return self.plane if self.plane is not None else float(np.mean(list(self.axial.values())))

    @property
    def sweep_loads(self) -> list:
        """The loads with their windows moved into the group's own shaft angle (machine angle + phase)."""
        return [replace(ld, window=None if ld.window is None else tuple(w + self.phase for w in ld.window))
                for ld in self.loads]


class MovingBody(NamedTuple):
    """A moving body of a group in an analysis: its mass and inertia (SI, the run's values), its motion, and
    whether an input turns it (a crank; a spatial crank of a group along the shaft turns about the shaft)."""

    group: "Group"
    name: str
    mass: float
    inertia: float
    motion: object  # sewgen.engine.results.BodyMotion
    driven: bool


@dataclass
class Machine:
    name: str
    doc: str
    speed: float  # rad/s
    step: float  # rad
    gravity: np.ndarray  # (gx, gy), m/s²
    groups: list
    shaft: Shaft
    source: str = ""
    stitch: object = None  # sewgen.machine.modelfile.Stitch: cloth, loop lift and release, timing rules ([stitch])
    thread: object = None  # sewgen.machine.modelfile.ThreadPath: the needle thread's guides ([thread])
    allow_outside_code: bool = False  # loaded with declaration files outside the model's folder allowed

    def shaft_angles(self, step: float | None = None) -> np.ndarray:
        """One revolution every ``step`` (rad; default the model's): a step must divide 360° into 4 to
        :data:`sewgen.units.MAX_POSITIONS` equal steps (it is never rounded to one that does)."""
        h = self.step if step is None else step
        n, problem = steps_per_turn(h)
        if n is None:
            raise ParameterError(self.name, "step", problem)
        return (2 * math.pi / n) * np.arange(n)

    def analyze(self, phi=None, speed=None, accel=0.0, progress=None) -> "MachineAnalysis":
        """Kinematics, kinetostatics and the upper-shaft bearings at machine shaft angles ``phi`` (rad).

        A group that cannot be solved raises its typed error (AssemblyError, SingularPositionError, ...) with
        the model file (``file``) and the group's key (``key``, e.g. ``groups.take_up``) added to its fields and
        its message.

        Repeated analyses of one machine reuse its call plan (:mod:`sewgen.machine.plan`: everything that
        depends on the machine alone, converted once, rebuilt when the machine is changed in place); every
        analysis returns new arrays."""
        fast = self._planned_analysis(phi, speed, accel, progress)
        if fast is not None:
            return fast
        phi = self.shaft_angles() if phi is None else np.asarray(phi, dtype=float)
        w = self.speed if speed is None else speed
        if isinstance(w, str):
            try:
                w = to_si(w, "speed", "speed")
            except UnitError as exc:
                raise ParameterError(self.name, "speed", exc.problem) from None
        g_mag, g_dir = gravity_polar(self.gravity)
        out = {}
        for k, g in enumerate(self.groups):
            if progress:
                progress(f"{g.name}: {len(phi)} positions", k, len(self.groups))
            try:
                out[g.name] = g.mechanism.kinetostatics(
                    phi + g.phase, speed=w, accel=accel, loads=g.sweep_loads, gravity=g_mag, gravity_direction=g_dir,
                    params=g.params or None, held=g.held or None, branch=g.branch or None)
            except SewgenError as exc:
                raise located(exc, self.source, f"groups.{g.name}") from None
        analysis = MachineAnalysis(self, phi, out)
        analysis.run = {"speed": w, "accel": accel}
        return analysis

    def _planned_analysis(self, phi, speed, accel, progress):
        """analyze() through the machine's call plan, or None where the general path must run (per-position or
        string speeds, a non-finite or non-1-D phi, a position that fails: that path raises the typed error)."""
        if phi is None:
            phi = self.shaft_angles()
        elif type(phi) is not np.ndarray or phi.dtype != np.float64 or phi.ndim != 1:
            return None
        if not phi.shape[0] or not np.isfinite(phi).all():
            return None
        w, al = scalar(self.speed if speed is None else speed), scalar(accel)
        if w is None or al is None:
            return None
        try:
            plan = plan_of(self)
        except (SewgenError, KeyError):  # the general path raises it, located
            return None
        phi = phi.copy()  # the analysis owns its angles
        out = plan.run(phi, w, al, progress)
        if out is None:
            return None
        groups, shaft = out
        analysis = MachineAnalysis(self, phi, groups, shaft)
        analysis.run = {"speed": self.speed if speed is None else speed, "accel": accel}
        return analysis

    def __getstate__(self):
        state = dict(self.__dict__)
        state.pop("_plan", None)  # compiled pointers: made again where it is used
        return state

    def kinematics(self, phi, speed=None) -> dict:
        """Group name -> Motion at machine shaft angles ``phi`` (rad), constant ``speed`` (sewgen.machine.timing)."""
        w = self.speed if speed is None else speed
        return {g.name: g.mechanism.solve(np.asarray(phi, dtype=float) + g.phase, speed=w, params=g.params or None,
                                          held=g.held or None, branch=g.branch or None) for g in self.groups}


class MachineAnalysis:
    """Every group's results and the machine-level ones, indexed by the machine's shaft angle."""

    def __init__(self, machine: Machine, phi: np.ndarray, groups: dict, shaft=None):
        self.machine, self.phi, self.groups = machine, phi, groups
        first = next(iter(groups.values()))
        self.omega, self.alpha = first.motion.omega, first.motion.alpha
        self.run = {"speed": self.omega, "accel": self.alpha}  # what analyze() was given
        with np.errstate(over="ignore", invalid="ignore"):  # an overflow is reported as a typed error
            self._shaft(shaft)

    def refined(self, step: float = math.radians(1.0)) -> "MachineAnalysis":
        """The same analysis (speed, acceleration) every ``step`` (rad) over one revolution, when this one is a
        whole revolution in coarser steps; else this one. Curves are drawn from it (a 5° polyline looks
        jagged), while tables keep the step that was asked for."""
        phi = self.phi
        n = len(phi)
        whole = n > 2 and np.allclose(np.diff(phi), 2 * math.pi / n) and abs(phi[0]) < 1e-12
        if not whole or 2 * math.pi / n <= step * (1 + 1e-9):
            return self
        run = self.run
        speed, accel = run["speed"], run["accel"]
        if np.ndim(speed) or np.ndim(accel):  # per-position speeds cannot be resampled
            return self
        return self.machine.analyze(self.machine.shaft_angles(step), speed=speed, accel=accel)

    def crank_loads(self):
        """(name, z, (n, 2) force on the shaft core) for every driven body on the shaft. A group whose plane
        contains the shaft (``frame = "along"``: its cranks are spatial cranks turning about its x axis) puts its
        pivot's in-plane force (x: along the shaft, a thrust the radial bearings do not take; y) and the
        out-of-plane force of the rods on its cranks (seed 003's ball-jointed rods, ``<rod>.fz``) on the shaft."""
        return [load for g in self.machine.groups for load in self._crank_loads(g)]

    def _crank_loads(self, g):
        fa = self.groups[g.name]
        out = []
        inertia = {b.name: b.mass * b.motion.com.az for b in self.moving_bodies(g) if b.motion.com.az is not None}
        for body, z in g.axial.items():
            fx, fy = _xy(fa.frame_force(f"{body}.pivot"))
            if g.along:  # the crank on the core out of the plane: its rods' pull and its own inertia, −m a_z
                fz = -sum((fa.output(f"{r.name}.fz") for r in g.mechanism.description.force_joints
                           if r.kind == "rod" and r.a == body), np.zeros(len(self.phi))) - inertia.get(body, 0.0)
                fx, fy, _ = g.force_to_machine(fx, fy, fz)
            out.append((f"{g.name}.{body}", z, np.column_stack([fx, fy])))
        return out

    def _group_force(self, g, force):
        """A group's (n, 2) in-plane force in the machine's x, y (an "along" group's x is axial: dropped)."""
        if not g.along:
            return force
        x, y, _ = g.force_to_machine(force[:, 0], force[:, 1])
        return np.column_stack([np.zeros(len(y)) + x, y])

    def _off_plane(self, g):
        """Per body of group ``g`` whose centre of mass leaves the group's plane (a spatial crank's turning about
        its axis): the frame's force on it m (a_G − g) and its centre of mass, both in the machine frame, as they are
        (F, P) and as the group's plane forces count them, in the plane (F₀, P₀) — the part the plane leaves out
        is the difference."""
        gx, gy = (0.0, float(self.machine.gravity[1])) if g.along else (float(v) for v in self.machine.gravity)
        for b in self.moving_bodies(g):
            c = b.motion.com
            if c.z is None:
                continue
            fx, fy = b.mass * (c.ax - gx), b.mass * (c.ay - gy)
            yield (g.force_to_machine(fx, fy, b.mass * c.az), g.to_machine(c.x, c.y, c.z),
                   g.force_to_machine(fx, fy), g.to_machine(c.x, c.y))

    def _off_plane_moment(self, g, about=(0.0, 0.0, 0.0)) -> np.ndarray:
        """(n, 3) the moment about ``about`` of the frame's forces on ``g``'s bodies that its plane leaves out
        (:meth:`_off_plane`): Σ (P − O) × F − (P₀ − O) × F₀."""
        out = np.zeros((len(self.phi), 3))
        for force, at, plane_force, plane_at in self._off_plane(g):
            shaking.add_moment(out, at, force, about)
            shaking.add_moment(out, plane_at, tuple(-np.asarray(f) for f in plane_force), about)
        return out

    def _group_moment_z(self, g, force, moment):
        """The z moment about the machine's origin of a group's force (n, 2) and its moment about the group's
        origin (n,), both in the group's frame."""
        if not g.along:
            return moment
        return g.origin[0] * force[:, 1]  # its own moment is about −x

    def _along_moments(self, g):
        """((n,) moment about its own z axis through its origin, (n,) about the machine's z) of the frame's
        reactions on the parts of a group along the shaft, its process loads internal, from the kinematics:
        Σ m (x (a_y − g_y) − y (a_x − g_x)) + I α over its bodies (its spatial cranks' I α is about the machine's
        z). The group's own balance cannot give them: its spatial cranks have no moment row about its z, their
        bearings carry that moment (and its rocker bearings the one about the machine's z)."""
        gx, gy = 0.0, float(self.machine.gravity[1])  # gravity in the group's plane (the machine's x is its −z)
        own, about_z = np.zeros(len(self.phi)), np.zeros(len(self.phi))
        for b in self.moving_bodies(g):
            c, spin = b.motion.com, b.inertia * b.motion.alpha
            own = own + b.mass * (c.x * (c.ay - gy) - c.y * (c.ax - gx))
            if b.driven:
                about_z = about_z + spin
            else:
                own = own + spin
        return own, about_z

    def _shaft(self, shaft=None):
        """The bearings' forces on the shaft (``front``, ``rear``), the driving ``torque``, the bearings' friction
        torque and the core masses' motion (``core``: (mass, position, velocity, acceleration) each), by
        d'Alembert in one C call (csrc/sg_runtime.c: sg_shaft). ``shaft``: its results from the machine's plan,
        else the cranks' forces and the groups' shaft torques are gathered here (crank_loads: any machine)."""
        if shaft is None:
            call = ShaftCall(self.machine)
            n = len(self.phi)
            loads = self.crank_loads()
            torques = [fa.torque("shaft") for fa in self.groups.values()]
            src = np.concatenate([np.ravel(F) for _, _, F in loads] + [np.ravel(t) for t in torques], dtype=float)
            forces, tq = call.layout([(2 * n * j, 2 * n * j + 1) for j in range(len(loads))], [2] * len(loads),
                                     [1.0] * len(loads), [z - call.front for _, z, _ in loads],
                                     [2 * n * len(loads) + n * k for k in range(len(torques))], [1] * len(torques))
            rates = [np.ascontiguousarray(np.broadcast_to(np.asarray(v, dtype=float), (n,)))
                     for v in (self.omega, self.alpha)]
            shaft = call.run(np.ascontiguousarray(self.phi, dtype=float), *rates, src, forces, tq)
        self.front, self.rear, self.torque, self.bearing_friction, self.core, finite = shaft
        if finite:
            return
        for what, values in (("shaft.front_bearing", self.front), ("shaft.rear_bearing", self.rear),
                             ("shaft", self.torque)):
            if not np.isfinite(values).all():
                raise NonFiniteOutputError(f"{what}: the {'driving torque' if what == 'shaft' else 'bearing load'}",
                                           values[~np.isfinite(values)].flat[0], self.machine.source or None)

    # -- tables ----------------------------------------------------------------------------------------------
    def to_dataframe(self, group: str | None = None):
        """The machine's table (bearings, torques, shaking force and moments, powers; the report's machine.csv)
        as a pandas DataFrame indexed by the machine's shaft angle ``phi [deg]``; with ``group``, that group's
        kinematics and forces (its <group>.csv)."""
        from sewgen.engine.frames import dataframe

        if group is not None:
            if group not in self.groups:
                raise KeyError(f"{self.machine.name} has no group {group!r}; groups: {', '.join(self.groups)}")
            cols = group_table(self.groups[group], self.phi)
        else:
            cols = machine_table(self)
        return dataframe({k: v for k, v in cols.items() if k != "phi [deg]"}, np.degrees(self.phi))

    def to_xarray(self):
        """The machine's table as an xarray Dataset over ``phi`` (deg) (xarray is optional)."""
        from sewgen.engine.frames import dataset
        return dataset({k: v for k, v in machine_table(self).items() if k != "phi [deg]"}, np.degrees(self.phi),
                       {"machine": self.machine.name})

    def __repr__(self) -> str:
        from sewgen.engine.frames import angle_span, speed_text

        return (f"<MachineAnalysis of {self.machine.name}: {angle_span(self.phi)} at {speed_text(self.omega)}; "
                f"groups {', '.join(self.groups)}>")

    # -- results ---------------------------------------------------------------------------------------------
    def bearing(self, which: str) -> np.ndarray:
        """(n, 2) load the shaft puts on the frame at bearing "front" or "rear" (N)."""
        if which not in ("front", "rear"):
            raise KeyError(f"bearings are 'front' and 'rear', not {which!r}")
        return -(self.front if which == "front" else self.rear)

    @property
    def drive_power(self) -> np.ndarray:
        return self.torque * self.omega

    @property
    def frame_force_on_parts(self) -> np.ndarray:
        """(n, 2) the frame's force on all moving parts, R = Σ m a_G − Σ m g − Σ loads − belt pull, the shaft core
        included (N; :mod:`sewgen.machine.shaking`): the sum of every group's frame-joint reactions (the shaft's
        pivots excepted) and of the bearings' (seed 000's base-support reactions 机座支承反力)."""
        gv = self.machine.gravity
        out = sum(self._group_force(g, self.groups[g.name].frame_force_on_parts) for g in self.machine.groups)
        for g in self.machine.groups:  # the part of a spatial crank's force that leaves the group's plane
            for force, _at, plane_force, _plane_at in self._off_plane(g):
                out = out + np.column_stack([force[k] - plane_force[k] + 0.0 * self.phi for k in range(2)])
        for sm, _pos, _vel, acc in self.core:
            out = out + sm.mass * (acc - gv[None, :])
        return out - np.asarray(self.machine.shaft.belt, dtype=float)[None, :]

    def frame_moment_on_parts(self, about=(0.0, 0.0)) -> np.ndarray:
        """(n,) the moment about z through ``about`` (x, y; m) of the frame's force on the moving parts, the drive
        counted as frame (N m)."""
        ox, oy = about
        gv = self.machine.gravity
        out = self.machine.shaft.inertia * self.alpha
        for g in self.machine.groups:
            fa = self.groups[g.name]
            sf = fa.frame_force_on_parts
            own = fa.frame_moment_on_parts + fa.moment_about[0] * sf[:, 1] - fa.moment_about[1] * sf[:, 0]
            out = out + self._group_moment_z(g, sf, own) + self._off_plane_moment(g)[:, 2]
            if g.along:  # its cranks turn about the machine's z
                out = out + self._along_moments(g)[1]
        for sm, pos, _vel, acc in self.core:
            f = sm.mass * (acc - gv[None, :])
            out = out + pos[:, 0] * f[:, 1] - pos[:, 1] * f[:, 0]
        sf = self.frame_force_on_parts
        return out - (ox * sf[:, 1] - oy * sf[:, 0])

    def _group_loads(self, g: Group):
        """(n, 2) resultant of one group's external loads and their moment about the origin (n,)."""
        force, moment = np.zeros((len(self.phi), 2)), np.zeros(len(self.phi))
        fa = self.groups[g.name]
        ld = fa.run_settings.loads
        if ld is None:
            return force, moment
        for slot in g.mechanism.description.loads:
            k = slot.index
            if slot.component == "torque":
                moment += ld[:, k]
                continue
            pt = fa.motion.point(slot.name)
            if slot.component == "fx":
                force[:, 0] += ld[:, k]
                moment -= pt.y * ld[:, k]
            else:
                force[:, 1] += ld[:, k]
                moment += pt.x * ld[:, k]
        return force, moment

    def process_loads_on_parts(self):
        """((n, 2), (n,)) the resultant of the process loads (every group's external loads: thread, presser foot,
        cloth) on the moving parts and its moment about z through the origin (N, N m); the belt's pull apart."""
        force, moment = np.zeros((len(self.phi), 2)), np.zeros(len(self.phi))
        for g in self.machine.groups:
            f, m = self._group_loads(g)
            force, moment = force + self._group_force(g, f), moment + self._group_moment_z(g, f, m)
        return force, moment

    @property
    def shaking_force_on_frame(self) -> np.ndarray:
        """(n, 2) the shaking force on the frame, −Σ m a_G (N): inertia only
        (:func:`sewgen.machine.shaking.shaking_force_on_frame`)."""
        return shaking.shaking_force_on_frame(self)

    def shaking_moments_on_frame(self, about=(0.0, 0.0, 0.0)) -> np.ndarray:
        """(n, 3) the shaking moments on the frame about the point ``about`` (x, y, z; m), about the x, y and z
        axes (N m): inertia only (:func:`sewgen.machine.shaking.shaking_moments_on_frame`)."""
        return shaking.shaking_moments_on_frame(self, about)

    @property
    def weight_on_frame(self) -> np.ndarray:
        """(2,) the moving parts' weight on the frame, Σ m g (N) (:func:`sewgen.machine.shaking.weight_on_frame`)."""
        return shaking.weight_on_frame(self)

    def inertia_and_weight_moments_on_frame(self, about=(0.0, 0.0, 0.0)) -> np.ndarray:
        """(n, 3) the shaking moments plus the weight's moments on the frame about ``about`` (x, y, z; m), about
        the x, y and z axes (N m), from the frame's force on the parts with the process loads and the belt pull
        put back (the compiled kernels' reactions): −Σ [(r_G − O) × m (a_G − g) + I α]. It equals
        :meth:`shaking_moments_on_frame` + :func:`sewgen.machine.shaking.weight_moments_on_frame` from the
        kinematics, which the tests check. Each group's force acts in its plane z = ``Group.z`` and each core mass
        at its own z, so the groups' axial offsets rock the base about x and y (seed 000 §二(二)1(6) treats the
        upper shaft in space for this reason)."""
        ox, oy, oz = about
        gv = self.machine.gravity
        out = np.zeros((len(self.phi), 3))
        force, moment = self.process_loads_on_parts()
        force = force + np.asarray(self.machine.shaft.belt)[None, :]  # the belt pulls on the shaft axis
        out[:, 2] = self.frame_moment_on_parts((ox, oy)) + moment - (ox * force[:, 1] - oy * force[:, 0])
        for g in self.machine.groups:
            fa = self.groups[g.name]
            lf, _lm = self._group_loads(g)
            force = fa.frame_force_on_parts + lf
            out[:, :2] += self._off_plane_moment(g, about)[:, :2]
            if g.along:  # F = (0, fy, fx) at the group's origin with its own moment M about −x: (o − O) × F − M x
                own = self._along_moments(g)[0]
                dx, dy, dz = g.origin[0] - ox, g.origin[1] - oy, g.origin[2] - oz
                out[:, 0] += dy * force[:, 0] - dz * force[:, 1] - own
                out[:, 1] -= dx * force[:, 0]
                continue
            out[:, 0] -= (g.z - oz) * force[:, 1]
            out[:, 1] += (g.z - oz) * force[:, 0]
        for sm, _pos, _vel, acc in self.core:
            force = sm.mass * (acc - gv[None, :])
            out[:, 0] -= (sm.z - oz) * force[:, 1]
            out[:, 1] += (sm.z - oz) * force[:, 0]
        return -out

    # -- deprecated names (one release) ----------------------------------------------------------------------
    @property
    def frame_reaction(self) -> np.ndarray:
        """Deprecated name of :attr:`frame_force_on_parts`."""
        _deprecated("frame_reaction", "frame_force_on_parts")
        return self.frame_force_on_parts

    def frame_moment(self, about=(0.0, 0.0)) -> np.ndarray:
        """Deprecated name of :meth:`frame_moment_on_parts`."""
        _deprecated("frame_moment", "frame_moment_on_parts")
        return self.frame_moment_on_parts(about)

    @property
    def shaking_force(self) -> np.ndarray:
        """Deprecated: Σ m a_G − Σ m g, the frame's force on the parts with the process loads and the belt pull
        put back, i.e. −(:attr:`shaking_force_on_frame` + :attr:`weight_on_frame`); not a shaking force."""
        _deprecated("shaking_force", "shaking_force_on_frame (inertia only, on the frame) or frame_force_on_parts")
        return self.frame_force_on_parts + self.process_loads_on_parts()[0] + np.asarray(self.machine.shaft.belt)

    def shaking_moment(self, about=(0.0, 0.0)) -> np.ndarray:
        """Deprecated: −(the z column of :meth:`inertia_and_weight_moments_on_frame`), about ``about`` (x, y)."""
        _deprecated("shaking_moment", "shaking_moments_on_frame")
        return -self.inertia_and_weight_moments_on_frame((about[0], about[1], 0.0))[:, 2]

    def shaking_moments(self, about=(0.0, 0.0, 0.0)) -> np.ndarray:
        """Deprecated: −:meth:`inertia_and_weight_moments_on_frame` (the weight included, on the parts)."""
        _deprecated("shaking_moments", "shaking_moments_on_frame")
        return -self.inertia_and_weight_moments_on_frame(about)

    def moving_bodies(self, group: Group | None = None):
        """A :class:`MovingBody` for every moving body of every group (or of ``group``), with the run's parameter
        values; a mass or inertia declared as an expression (not a parameter) is a ParameterError naming it."""
        for g in self.machine.groups if group is None else [group]:
            fa = self.groups[g.name]
            values = dict(zip(g.mechanism.param_names, fa.run_settings.params))
            driven = {b.name for b in g.mechanism.description.driven_bodies}
            for body in g.mechanism.description.bodies:
                if body.mass is None or body.inertia is None:
                    raise ParameterError(g.mechanism.name, f"{body.name}.mass", "the machine's energy and shaking "
                                         "need mass and inertia as parameters, not expressions")
                yield MovingBody(g, body.name, values[body.mass], values[body.inertia], fa.motion.body(body.name),
                                 body.name in driven)

    def energy_rate(self) -> np.ndarray:
        """d/dt(kinetic + potential energy) of every moving part, from the kinematics alone, plus the rate at which
        the springs store energy (W)."""
        gv = self.machine.gravity
        rate = self.machine.shaft.inertia * self.omega * self.alpha
        for b in self.moving_bodies():
            com, bm = b.motion.com, b.motion
            rate = rate + b.mass * (com.vx * com.ax + com.vy * com.ay - gv[0] * com.vx - gv[1] * com.vy)
            if com.vz is not None:  # a spatial crank's centre of mass leaves the plane
                rate = rate + b.mass * com.vz * com.az
            rate = rate + b.inertia * bm.omega * bm.alpha
        for fa in self.groups.values():
            rate = rate + fa.elastic_power  # the springs' stored energy
        for sm, _pos, vel, acc in self.core:
            rate = rate + sm.mass * np.sum(vel * (acc - gv[None, :]), axis=1)
        return rate

    @property
    def load_power(self) -> np.ndarray:
        """Power of the process loads, dampers and friction (W): the groups' and the shaft bearings' friction."""
        return sum(fa.load_power for fa in self.groups.values()) - self.bearing_friction * self.omega

    @property
    def friction_power(self) -> np.ndarray:
        """Power dissipated by Coulomb friction (W, ≥ 0): every group's joints and the upper shaft's bearings."""
        return sum(fa.friction_power for fa in self.groups.values()) + self.bearing_friction * self.omega

    def no_load_torque(self) -> float:
        """Mean driving torque over a turn with the process loads (thread, presser foot, cloth) taken off: at
        constant speed the inertia and gravity terms average out, so it is the torque the joints' and bearings'
        friction costs — seed 000's "no-load driving torque at rated speed" (空载驱动力矩, at the analysis'
        speed). Zero without friction. Needs an analysis of a whole turn at constant speed."""
        m = self.machine
        if not any(g.loads for g in m.groups):
            return float(np.mean(self.torque))
        unloaded = replace(m, groups=[replace(g, loads=[]) for g in m.groups])
        return float(np.mean(unloaded.analyze(self.phi, speed=self.run["speed"], accel=self.run["accel"]).torque))

    @property
    def power_balance_residual(self) -> float:
        """max |P_drive + P_loads − dE/dt| over the sweep, relative to the largest |P_drive|, |dE/dt|."""
        rate = self.energy_rate()
        res = self.drive_power + self.load_power - rate
        scale = max(np.abs(self.drive_power).max(), np.abs(rate).max(), 1e-300)
        return float(np.abs(res).max() / scale)


def _xy(r) -> tuple:
    return (r.fx, r.fy)


# -- model files ---------------------------------------------------------------------------------------------

def load_machine(name_or_path, doc: dict | None = None, *, allow_outside_code: bool = False) -> Machine:
    """A machine from a model file (or a built-in model such as "jb1-3"), checked and converted to SI. ``doc``:
    the file's parsed TOML, changed (a design study's variant, sewgen.study.machine_designs); relative paths in
    it still resolve beside the file.

    A model file is code where a group's ``mechanism`` names a declaration file (a .py file whose ``declare()``
    runs when the machine is loaded): only files in the model file's folder or below are run, unless
    ``allow_outside_code`` (the command line's ``--allow-outside-code``) allows any path.

    The file is read by :func:`sewgen.machine.modelfile.read_model` (every table, its schema in
    sewgen.machine.modelfile.schema); here each group's mechanism is loaded, its tables are read against what
    it declares, and what only the compiled mechanism can check is checked: its parameter values, the stitch
    regulator's setting, the points and bodies its loads act on. So a problem the file alone shows is reported
    before any mechanism is loaded (a declaration file compiled)."""
    model = read_model(resolve(name_or_path), doc, rules=RULES)
    groups = []
    for spec in model.groups:
        try:
            groups.append(_group(model, spec, allow_outside_code))
        except ModelFileError:
            raise
        except SewgenError as exc:  # the group's geometry: cannot assemble at the stitch's setting, ...
            raise located(exc, model.path, spec.key) from None
    machine = Machine(model.name, model.description, model.speed, model.step, model.gravity, groups, model.shaft,
                      str(model.path), model.stitch, model.thread, allow_outside_code)
    for i, guide in enumerate(model.thread.guides if model.thread is not None else ()):
        if guide.point is not None:  # a moving guide names a point some group has
            try:
                find_point(machine, guide.point)
            except KeyError as exc:
                raise ModelFileError(model.path, f"thread.guides[{i}].point", exc.args[0]) from None
    return machine


def located(exc: SewgenError, path, key: str) -> SewgenError:
    """``exc`` (same type, same fields) with the model file and key added: its message starts "file: key: "."""
    if not path:
        return exc
    out = copy.copy(exc)
    out.args = (f"{path}: {key}: {exc}",) + tuple(exc.args[1:])
    out.file, out.key = str(path), key
    return out


def _group(model: Model, spec: GroupSpec, allow_outside_code: bool) -> Group:
    """A group of the model file: its mechanism loaded, its tables read against the mechanism's declaration, its
    parameter values, stitch regulator and loads checked by the compiled mechanism."""
    key = spec.key
    mech = _group_mechanism(model.path, f"{key}.mechanism", spec.mechanism, allow_outside_code)
    desc = mech.description
    declared = Declared(mech.name, {p.name: p.kind for p in desc.params}, tuple(mech.held_names),
                        tuple(mech.branch_names), tuple(b.name for b in desc.driven_bodies))
    settings = read_settings(model.path, spec, declared)
    params, held = settings.params, settings.held
    try:
        mech.param_vector(params)
    except ParameterError as exc:
        raise ModelFileError(model.path, f"{key}.params.{exc.parameter}", exc.problem) from None
    loads = list(spec.loads)
    group = Group(spec.name, mech, spec.phase, settings.axial, params, held, settings.branch, loads, spec.stitch,
                  spec.plane, spec.frame, spec.origin)
    if group.stitch is not None:
        regulator = desc.role_name(STITCH_REGULATOR)
        if regulator is None:
            raise ModelFileError(model.path, f"{key}.stitch",
                                 f"{mech.name} has no held input with the role {STITCH_REGULATOR!r}")
        if regulator in held:
            raise ModelFileError(model.path, f"{key}.stitch", f"give the stitch length or held.{regulator}, not both")
        try:
            group.held[regulator] = regulator_angle(mech, group.stitch, params=params or None)
        except ParameterError as exc:
            raise ModelFileError(model.path, f"{key}.stitch", exc.problem) from None
    try:  # every load names a point or body of the mechanism
        load_matrix(mech, loads, np.zeros(1))
    except ParameterError as exc:
        raise ModelFileError(model.path, f"{key}.loads", f"{exc.parameter}: {exc.problem}") from None
    return group


def _group_mechanism(model_path: Path, key: str, text: str, allow_outside_code: bool = False):
    """A group's mechanism: a catalog name, or a declaration file (.py with ``declare()``) relative to the model
    file, derived and compiled on first use and then loaded from the cache (:func:`sewgen.load`). Loading a
    declaration file runs its code: one outside the model file's folder (an absolute path, ``..``, ``~``, a link
    out of it) is refused unless ``allow_outside_code``."""
    if text in catalog():
        return catalog_mechanism(text)
    path = Path(text).expanduser()
    if not path.is_absolute():
        path = model_path.parent / path
    if path.suffix != ".py":
        raise ModelFileError(model_path, key, f"{text!r} is neither a catalog mechanism ({', '.join(catalog())}) "
                                              "nor a declaration file (.py with a declare() function)")
    try:
        folder = model_path.parent.resolve()
        outside = not path.resolve().is_relative_to(folder)
        found = path.is_file()
    except OSError as exc:  # a name too long, a loop of links
        raise ModelFileError(model_path, key, f"cannot read {path}: {exc.strerror or exc}") from None
    if outside and not allow_outside_code:
        raise ModelFileError(model_path, key, f"{text!r} is outside the model file's folder {folder}: a declaration "
                                              "file is Python code that loading the model runs, so only files in "
                                              "that folder or below are run; allow others with "
                                              "--allow-outside-code (load_machine(..., allow_outside_code=True))")
    if not found:
        raise ModelFileError(model_path, key, f"no declaration file {path}")
    try:
        return load(path)
    except BuildError as exc:
        raise ModelFileError(model_path, key, exc.problem) from None
    except Exception as exc:  # a syntax error in the declaration, or its declare() raised
        problem = declaration_problem(exc, path)
        if problem is None:
            raise
        raise ModelFileError(model_path, key, problem) from None


__all__ = ["Group", "Machine", "MachineAnalysis", "ModelFileError", "Shaft", "ShaftMass", "load_machine"]

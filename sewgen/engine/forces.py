"""Named results of a kinetostatic sweep: joint reactions, driving torques, the frame's force on the parts, energy.

Conventions (derive/kinetostatics.py): a revolute's reaction is the force on the joint's second body (b) from
its first (a), in the frame's x, y axes; a prismatic's is the normal force along the guide's normal (guide
direction turned +90°) and the couple, both on the slider side. Driven bodies are pinned to the frame at
``<body>.pivot``; a slider's own guide is ``<slider>.guide``. :attr:`ForceAnalysis.frame_force_on_parts` and
:attr:`ForceAnalysis.frame_moment_on_parts` are the resultant of the frame's reactions on the moving parts —
Σ m·a_G − Σ m·g − Σ loads — with the drives counted as part of the frame (seed 000 analyses the machine's
shaking through these base reactions); the force the mechanism puts on the frame is their negative, per joint
in :meth:`ForceAnalysis.frame_force`. A machine's shaking force on the frame (inertia only) is
:mod:`sewgen.machine.shaking`'s.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from sewgen.engine.results import write_csv


@dataclass(frozen=True)
class RunSettings:
    """What a kinetostatic sweep ran with, as the C runtime read it (the arrays are read-only).

    ``params`` (np,) SI parameter vector; ``held`` held inputs (rad); ``branch`` assembly signs; ``gravity`` the
    vector (gx, gy) in m/s²; ``loads`` the (n, nload) load-slot array of :func:`sewgen.engine.loads.load_matrix` or None
    without loads; ``moment_about`` the point (x, y; m) of the frame's moment on the parts; ``placed`` the loads
    with their slots and windows, (load, [(slot, value)], mask) each. Analyses that need a run's parameters or
    loads (the machine's energy check, its process loads) read them here.
    """

    params: np.ndarray
    held: np.ndarray
    branch: np.ndarray
    gravity: np.ndarray
    loads: np.ndarray | None
    moment_about: tuple
    placed: tuple = ()


@dataclass(frozen=True)
class JointReaction:
    """A joint force over the sweep: frame components (N), magnitude (N), direction (rad from +x).

    For a prismatic joint also the normal force (N) and the couple (N·m); for a slot or a cam the normal force
    (couple None); for a revolute both are None.
    """

    fx: np.ndarray
    fy: np.ndarray
    normal: np.ndarray | None = None
    moment: np.ndarray | None = None

    @property
    def magnitude(self) -> np.ndarray:
        return np.hypot(self.fx, self.fy)

    @property
    def direction(self) -> np.ndarray:
        return np.arctan2(self.fy, self.fx)


class ForceAnalysis:
    """Kinematics and kinetostatics of one mechanism over a sweep (SI units throughout)."""

    def __init__(self, mechanism, motion, frc: np.ndarray, settings: RunSettings):
        self.mechanism, self.motion, self.frc = mechanism, motion, frc
        self.run_settings = settings

    def __len__(self) -> int:
        return len(self.phi)

    @property
    def phi(self) -> np.ndarray:
        return self.motion.phi

    @property
    def gravity(self) -> np.ndarray:
        """The gravity vector (gx, gy) of the run, m/s²."""
        return self.run_settings.gravity

    @property
    def moment_about(self) -> tuple:
        """The point (x, y; m) :attr:`frame_moment_on_parts` is taken about."""
        return self.run_settings.moment_about

    @property
    def _run(self) -> dict:
        """Deprecated dict view of :attr:`run_settings` (``p``, ``held``, ``loads``), kept for callers not yet
        moved to the public name."""
        s = self.run_settings
        return {"p": s.params, "held": s.held, "loads": s.loads}

    @property
    def reaction_names(self) -> list[str]:
        """Every joint that carries a force (driving torques are under :meth:`torque`)."""
        return [r.name for r in self.mechanism.description.force_joints]

    @property
    def frame_joint_names(self) -> list[str]:
        return [r.name for r in self.mechanism.description.force_joints if r.grounded]

    def _out(self, name: str) -> np.ndarray:
        return self.frc[:, self.mechanism.description.output_column(name)]

    def output(self, name: str) -> np.ndarray:
        """Any named force output over the sweep (``Description.force_outputs``: e.g. a rod's ``<rod>.fz``, a
        joint's ``<joint>.friction``), in SI."""
        return self._out(name)

    def _joint(self, name: str):
        desc = self.mechanism.description
        return desc.reaction(name) if desc.has("reaction", name) else None

    def reaction(self, name: str) -> JointReaction:
        """The force on the joint's second body from its first (see the module docstring)."""
        r = self._joint(name)
        if r is None or r.is_drive:
            raise KeyError(f"{self.mechanism.name} has no joint {name!r}; joints: {', '.join(self.reaction_names)}")
        k = r.offset
        if r.kind == "revolute":
            return JointReaction(self.frc[:, k], self.frc[:, k + 1])
        couple = self.frc[:, k + 1] if r.kind == "prismatic" else None  # slot and cam: a normal force only
        return JointReaction(self._out(f"{name}.fx"), self._out(f"{name}.fy"), self.frc[:, k], couple)

    def frame_force(self, name: str) -> JointReaction:
        """The force joint ``name`` puts on the frame (it must join a body to ground)."""
        r = self._joint(name)
        if r is None or not r.grounded or r.is_drive:
            raise KeyError(f"{self.mechanism.name}: {name!r} is not a frame joint; frame joints: "
                           f"{', '.join(self.frame_joint_names)}")
        on_b = self.reaction(name)
        sign = -1.0 if r.a == "ground" else 1.0  # the frame is a: it gets −f; the frame is b: it gets f
        scale = (lambda v: None if v is None else sign * v)
        return JointReaction(sign * on_b.fx, sign * on_b.fy, scale(on_b.normal), scale(on_b.moment))

    def torque(self, input_name: str = "shaft") -> np.ndarray:
        """Driving torque of an input (N·m): the shaft's, or a held input's holding torque; a travel input's
        holding force (N) along its guide."""
        desc = self.mechanism.description
        if not desc.has("input", input_name):
            raise KeyError(f"{self.mechanism.name} has no input {input_name!r}; inputs: "
                           f"{', '.join(i.name for i in desc.inputs)}")
        return self._out(f"{input_name}.torque")

    def drive_torque(self, body: str) -> np.ndarray:
        """The torque that turns (or holds) driven body ``body`` at its pivot, on it from its pivot's body (N·m):
        one actuator's share; an input's torque is Σ ratio · these over the bodies it drives."""
        r = self._joint(f"{body}.drive")
        if r is None:
            raise KeyError(f"{self.mechanism.name} has no driven body {body!r}")
        return self.frc[:, r.offset]

    def input_power(self, input_name: str = "shaft") -> np.ndarray:
        """Power the input delivers (W) = torque × input speed (zero for held inputs)."""
        self.torque(input_name)
        return self._out(f"{input_name}.power")

    @property
    def frame_force_on_parts(self) -> np.ndarray:
        """(n, 2) the frame's force on the moving parts, the resultant of its reactions = Σ m a_G − Σ m g − Σ loads
        (N), the drives counted as frame."""
        return np.column_stack([self._out("frame_force_on_parts.fx"), self._out("frame_force_on_parts.fy")])

    @property
    def frame_moment_on_parts(self) -> np.ndarray:
        """(n,) the moment of the frame's force on the moving parts (drives included) about ``moment_about``
        (N·m)."""
        ox, oy = self.moment_about
        fx, fy = self._out("frame_force_on_parts.fx"), self._out("frame_force_on_parts.fy")
        return self._out("frame_moment_on_parts") - (ox * fy - oy * fx)

    @property
    def shaking_force(self) -> np.ndarray:
        """Deprecated name of :attr:`frame_force_on_parts` (the frame's force on the parts, not a shaking force)."""
        warnings.warn("ForceAnalysis.shaking_force is deprecated; use frame_force_on_parts", DeprecationWarning,
                      stacklevel=2)
        return self.frame_force_on_parts

    @property
    def shaking_moment(self) -> np.ndarray:
        """Deprecated name of :attr:`frame_moment_on_parts`."""
        warnings.warn("ForceAnalysis.shaking_moment is deprecated; use frame_moment_on_parts", DeprecationWarning,
                      stacklevel=2)
        return self.frame_moment_on_parts

    @property
    def kinetic_energy(self) -> np.ndarray:
        return self._out("kinetic_energy")

    @property
    def potential_energy(self) -> np.ndarray:
        """Gravitational potential energy, zero at the frame's origin, plus the energy the springs store (J)."""
        return self._out("potential_energy")

    @property
    def elastic_power(self) -> np.ndarray:
        """d/dt of the energy the springs store (W); zero without springs."""
        return self._out("elastic_power")

    @property
    def load_power(self) -> np.ndarray:
        """Total power of the external loads, the dampers and the joints' friction (the last two ≤ 0) (W)."""
        return self._out("load_power")

    @property
    def friction_joints(self) -> list[str]:
        """The joints declaring Coulomb friction (``m.friction``; coefficient 0 switches it off)."""
        tail = ".friction_power"
        return [o.name[:-len(tail)] for o in self.mechanism.description.force_outputs if o.name.endswith(tail)]

    def friction(self, joint: str) -> np.ndarray:
        """Joint ``joint``'s friction moment (N·m, a pin) or force (N, a slide or slot), against the motion."""
        if joint not in self.friction_joints:
            raise KeyError(f"{self.mechanism.name}: no friction declared in {joint!r}; joints with friction: "
                           f"{', '.join(self.friction_joints) or 'none'}")
        return self._out(f"{joint}.friction")

    @property
    def friction_power(self) -> np.ndarray:
        """Power the joints' Coulomb friction dissipates (W, ≥ 0); part of :attr:`load_power` (with a minus)."""
        out = np.zeros(len(self))
        for joint in self.friction_joints:
            out = out + self._out(f"{joint}.friction_power")
        return out

    def load_powers(self) -> dict[str, np.ndarray]:
        """Power of each external load (W), by its label."""
        out = {}
        slots = self.mechanism.description.loads
        for load, cols, mask in self.run_settings.placed:
            p = np.zeros(len(self))
            for k, value in cols:
                s = slots[k]
                rate = (self.motion.body(s.body).omega if s.component == "torque"
                        else getattr(self.motion.point(s.name), "v" + s.component[1]))
                p += np.where(mask, value, 0.0) * rate
            out[load.label] = out.get(load.label, 0.0) + p
        return out

    def element(self, name: str) -> dict[str, np.ndarray]:
        """The results of force element ``name`` over the sweep, by quantity: a spring's ``force`` (tension, N),
        ``length`` (m) and ``energy`` (J); a damper's ``force``, ``length``, ``rate`` (m/s) and ``power``
        (dissipated, W); a torsion spring's ``torque`` (N·m, on the joint's body a), ``deflection`` (rad) and
        ``energy`` (sewgen.derive.elements)."""
        el = self.mechanism.description.element(name)
        return {out[len(name) + 1:]: self._out(out) for out in el.outputs}

    def force_matrix(self, index: int = 0):
        """A and b of A f = b at position ``index``, with this run's parameters, held inputs, gravity and loads."""
        s = self.run_settings
        return self.mechanism.force_matrix(self.motion, index, params=s.params, held=s.held, gravity=s.gravity,
                                           load_row=None if s.loads is None else s.loads[index])

    def table(self) -> dict[str, np.ndarray]:
        """Every force result as a column named ``"<name> [unit]"``, shaft angle first."""
        cols = {"phi [rad]": self.phi}
        for name in self.reaction_names:
            r = self.reaction(name)
            cols[f"{name}.fx [N]"], cols[f"{name}.fy [N]"] = r.fx, r.fy
            cols[f"{name}.magnitude [N]"] = r.magnitude
            cols[f"{name}.direction [rad]"] = r.direction
            if r.normal is not None:
                cols[f"{name}.normal [N]"] = r.normal
            if r.moment is not None:
                cols[f"{name}.moment [N*m]"] = r.moment
        for name in self.frame_joint_names:
            r = self.frame_force(name)
            cols[f"frame@{name}.fx [N]"], cols[f"frame@{name}.fy [N]"] = r.fx, r.fy
        for inp in self.mechanism.description.inputs:
            cols[f"{inp.name}.{'torque' if inp.quantity == 'angle' else 'force'} [{inp.effort_unit}]"] = \
                self.torque(inp.name)
            cols[f"{inp.name}.power [W]"] = self.input_power(inp.name)
        sf = self.frame_force_on_parts
        cols["frame_force_on_parts.fx [N]"], cols["frame_force_on_parts.fy [N]"] = sf[:, 0], sf[:, 1]
        cols["frame_moment_on_parts [N*m]"] = self.frame_moment_on_parts
        cols["kinetic_energy [J]"] = self.kinetic_energy
        cols["potential_energy [J]"] = self.potential_energy
        cols["load_power [W]"] = self.load_power
        units = {o.name: o.unit for o in self.mechanism.description.force_outputs}
        for joint in self.friction_joints:  # only where friction is on in this run
            if np.any(self._out(f"{joint}.friction") != 0.0):
                for out in (f"{joint}.friction", f"{joint}.friction_power"):
                    cols[f"{out} [{units[out]}]"] = self._out(out)
        for el in self.mechanism.description.elements:
            for out in el.outputs:
                cols[f"{out} [{units[out]}]"] = self._out(out)
        return cols

    def to_csv(self, path) -> None:
        write_csv(path, self.table())

    def _all_columns(self) -> dict:
        cols = dict(self.motion.table())
        cols.update({k: v for k, v in self.table().items() if not k.startswith("phi ")})
        return cols

    def to_dataframe(self, kinematics: bool = True):
        """Every force result (and, with ``kinematics``, every kinematic one) as a pandas DataFrame, one row per
        shaft angle (index ``phi [deg]``), columns ``"<name> [unit]"``."""
        from sewgen.engine.frames import dataframe

        return dataframe(self._all_columns() if kinematics else self.table(), np.degrees(self.phi))

    def to_xarray(self):
        """Kinematics and forces as an xarray Dataset over ``phi`` (deg) (xarray is optional)."""
        from sewgen.engine.frames import dataset

        return dataset(self._all_columns(), np.degrees(self.phi), {"mechanism": self.mechanism.name})

    def __repr__(self) -> str:
        from sewgen.engine.frames import angle_span, speed_text

        return (f"<ForceAnalysis of {self.mechanism.name}: {angle_span(self.phi)} at "
                f"{speed_text(self.motion.omega)}; joints {', '.join(self.reaction_names) or 'none'}; inputs "
                f"{', '.join(i.name for i in self.mechanism.description.inputs)}>")

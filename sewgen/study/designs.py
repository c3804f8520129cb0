"""Design tables and the one seam where designs are evaluated.

A *design table* gives one parameter set per row: a pandas DataFrame (columns named by parameter), a mapping
name -> array, or an ndarray in ``param_names`` order; every value in SI. :func:`design_matrix` turns any of
them into the (D, n_params) matrix a mechanism's sweep reads, the parameters a table leaves out at their base
values.

:func:`sweep_group_designs` is the single place where a study evaluates many designs of one mechanism: the
kinematics through the sweep engine's batched C calls (``Mechanism.sweep_designs``), the kinetostatics by a loop
over :meth:`Mechanism.kinetostatics` (no batched form yet), each design's typed error caught into its status;
everything downstream reads the stacked (designs × angles × …) arrays.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from sewgen.errors import InputError, ParameterError, SewgenError
from sewgen.engine.results import Motion
from sewgen.engine.forces import ForceAnalysis
from sewgen.units import to_si
from sewgen.engine.designs import output_columns


def design_matrix(mech, designs, base: dict | None = None) -> np.ndarray:
    """The (D, n_params) SI matrix of ``designs`` for ``mech``: a DataFrame or mapping (columns by parameter name;
    the others at ``base``'s or the declaration's values) or an ndarray of shape (D, n_params) in
    ``mech.param_names`` order. An unknown column is a ParameterError naming it."""
    names = mech.param_names
    p0 = mech.param_vector(base)
    if isinstance(designs, np.ndarray) or (not isinstance(designs, Mapping) and not hasattr(designs, "columns")):
        arr = np.asarray(designs, dtype=float)
        if arr.ndim != 2 or arr.shape[1] != len(names):
            raise InputError(mech.name, f"a design array must have shape (designs, {len(names)}) in param_names "
                                        f"order, got {arr.shape}")
        return np.ascontiguousarray(arr)
    cols = list(designs.columns) if hasattr(designs, "columns") else list(designs)
    index = {n: k for k, n in enumerate(names)}
    lengths = {len(np.asarray(designs[c])) for c in cols}
    if len(lengths) > 1:
        raise InputError(mech.name, f"design columns of unequal lengths: {sorted(lengths)}")
    d = lengths.pop() if lengths else 0
    out = np.tile(p0, (d, 1))
    for c in cols:
        if c not in index:
            raise ParameterError(mech.name, str(c), f"not a parameter of {mech.name}; it has: {', '.join(names)}")
        out[:, index[c]] = np.asarray(designs[c], dtype=float)
    return out


@dataclass
class GroupSweep:
    """Many designs of one mechanism over the same shaft angles: ``status`` ("ok" or the error's type name) and
    ``error`` (None or the message) per design; ``q``, ``qd``, ``qdd`` (D, N, nq), ``obs`` (D, N, nobs) and,
    for a kinetostatic sweep, ``frc`` (D, N, nfo) — NaN rows for a failed design."""

    mechanism: object
    params: np.ndarray
    phi: np.ndarray
    omega: float
    status: np.ndarray
    error: list
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    obs: np.ndarray
    frc: np.ndarray | None = None
    settings: list | None = None  # per design: the ForceAnalysis run settings (kinetostatic sweeps)
    kept: tuple | None = None  # a sweep of some observables only: their indices (``obs``'s last axis); q… None

    def observable(self, k: int) -> np.ndarray:
        """Observable ``k`` (its index in the mechanism's observables) of every design: (D, N)."""
        if self.kept is None:
            return self.obs[:, :, k]
        try:
            return self.obs[:, :, self.kept.index(k)]
        except ValueError:
            raise KeyError(f"observable {k} of {self.mechanism.name} was not kept by this sweep") from None

    @property
    def ok(self) -> np.ndarray:
        return self.status == "ok"

    def __len__(self) -> int:
        return len(self.status)

    def motion(self, k: int):
        """Design ``k`` as a :class:`sewgen.Motion`."""
        if self.kept is not None:
            raise ValueError("a sweep of some observables only has no Motion: sweep with every output")
        n = len(self.phi)
        return Motion(self.mechanism, self.phi, np.full(n, self.omega), np.zeros(n), self.q[k], self.qd[k],
                      self.qdd[k], self.obs[k])

    def analysis(self, k: int):
        """Design ``k`` as a :class:`sewgen.ForceAnalysis` (a kinetostatic sweep)."""
        return ForceAnalysis(self.mechanism, self.motion(k), self.frc[k], self.settings[k])

    def to_dataframe(self):
        """One row per design: its parameters (SI, by name), ``status`` and ``error``."""
        from sewgen.engine.frames import pandas

        df = pandas().DataFrame(self.params, columns=self.mechanism.param_names)
        df["status"], df["error"] = self.status, self.error
        return df


def sweep_group_designs(mech, designs, phi, speed=None, *, base: dict | None = None, held: dict | None = None,
                        branch: dict | None = None, forces: bool = False, loads=(), gravity="9.80665 m/s**2",
                        gravity_direction="-90 deg", threads: int | None = None, observables=None) -> GroupSweep:
    """Every design of ``designs`` (see :func:`design_matrix`) swept at shaft angles ``phi`` (rad, the
    mechanism's own) and constant ``speed``; with ``forces``, the kinetostatics (``loads``, ``gravity`` as in
    :meth:`Mechanism.kinetostatics`). A design that cannot be solved (cannot assemble, a singular position, a
    parameter out of range …) gets its error's type in ``status`` and its message in ``error``; the others are
    unaffected. ``observables`` (kinematic sweeps): the indices of the only observables to keep (``obs`` then
    holds them in that order, ``q``, ``qd``, ``qdd`` are None; :meth:`GroupSweep.observable` reads them) —
    the C sweep writes less, the same values bit for bit.

    Kinematic sweeps go through :meth:`Mechanism.sweep_designs` (chunks of designs in batched C calls on every
    core, the GIL released); kinetostatic ones loop over :meth:`Mechanism.kinetostatics` (the batched call has no
    forces yet)."""
    P = design_matrix(mech, designs, base)
    phi = np.asarray(phi, dtype=float)
    d, n = P.shape[0], len(phi)
    sizes = mech.description.sizes
    omega = _omega(mech, speed)
    if not forces:
        return _batched(mech, P, phi, omega, held, branch, threads, observables)
    nan = np.nan
    q, qd, qdd = (np.full((d, n, sizes["nq"]), nan) for _ in range(3))
    obs = np.full((d, n, sizes["nobs"]), nan)
    frc = np.full((d, n, sizes["nfo"]), nan)
    status = np.full(d, "ok", dtype=object)
    error: list = [None] * d
    settings: list = [None] * d
    names = mech.param_names
    for k in range(d):
        try:
            fa = mech.kinetostatics(phi, speed=omega, params=dict(zip(names, P[k])), held=held, branch=branch,
                                    loads=loads, gravity=gravity, gravity_direction=gravity_direction)
        except SewgenError as exc:
            status[k], error[k] = type(exc).__name__, str(exc)
            continue
        mo = fa.motion
        q[k], qd[k], qdd[k], obs[k], frc[k], settings[k] = mo.q, mo.qd, mo.qdd, mo.obs, fa.frc, fa.run_settings
    return GroupSweep(mech, P, phi, omega, status, error, q, qd, qdd, obs, frc, settings)


def _omega(mech, speed) -> float:
    """The sweep's constant shaft speed (rad/s): ``speed`` (a number or "1000 rpm"), or the mechanism's default."""
    w = mech.default_speed if speed is None else speed
    if isinstance(w, str):
        w = to_si(w, "speed", "speed")
    return float(w)


def _batched(mech, P, phi, omega: float, held, branch, threads=None, observables=None) -> GroupSweep:
    """The kinematic sweep of every design at speed ``omega`` (rad/s) in batched C calls
    (``Mechanism.sweep_designs``), as the stacked arrays of :class:`GroupSweep` (views of the sweep's block, no
    copy); a failed design's rows are NaN, its error's type and message kept. ``observables``: see
    :func:`sweep_group_designs`."""
    nq = mech.description.sizes["nq"]
    if observables is None:
        outputs = ["all"]
    else:
        names = output_columns(mech).names
        observables = tuple(int(k) for k in observables)
        outputs = [names[3 * nq + k] for k in observables]
    res = mech.sweep_designs(P, phi, omega, held=held, branch=branch, outputs=outputs, threads=threads)
    status = np.full(len(P), "ok", dtype=object)
    error: list = [None] * len(P)
    for k in np.flatnonzero(~res.ok):
        exc = res.exception(int(k))
        status[k], error[k] = type(exc).__name__, str(exc)
    full = res.stacked()  # (D, N, columns): the outputs in the order asked
    if observables is not None:
        return GroupSweep(mech, P, phi, omega, status, error, None, None, None, full, None, None, observables)
    return GroupSweep(mech, P, phi, omega, status, error, full[..., :nq], full[..., nq:2 * nq],
                      full[..., 2 * nq:3 * nq], full[..., 3 * nq:], None, None)


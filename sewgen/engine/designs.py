"""Many designs of one mechanism over the same shaft angles in one C call per chunk.

:meth:`sewgen.Mechanism.sweep_designs` is the entry: a table of designs (rows) by parameters (columns) is
converted to SI once per column, checked column-wise (a design out of range is skipped, named, and the others
run), and swept by ``sg_sweep_designs`` (csrc/sg_runtime.c): each design its own sweep exactly as
:meth:`~sewgen.Mechanism.solve` makes it (its own continuation, tolerance and per-position status), with only
the asked outputs written and optional per-design reductions fused into the same pass, so that nothing per
position need be kept. Chunks of designs run on a thread pool (cffi releases the GIL during the C call).

**Column names.** Every per-position result has a flat name: ``coords.<coordinate>`` (rad or m), with ``_d``
and ``_dd`` for its first and second time derivatives; ``points.<point>.<field>`` (``x``, ``y``, ``x_d``, ``y_d``,
``x_dd``, ``y_dd``); ``bodies.<body>.<field>`` (``angle``, ``angle_d``, ``angle_dd``, ``com.x`` … ``com.y_dd``);
``obs.<observable>`` for any other observable. For reductions a point (and a body's centre of mass) also has
its speed ``points.<point>.v`` = |(x_d, y_d)| and the magnitude of its acceleration ``points.<point>.a`` =
|(x_dd, y_dd)|. A reduction is named ``<column>:<kind>`` (kinds: ``min``, ``max``, ``absmax``, ``rms``,
``mean``); ``min``, ``max`` and ``absmax`` also give ``<column>:<kind>.index``, the first position of the
extremum in the caller's angle order. :meth:`DesignSweep.to_dataframe` adds the SI unit in brackets:
``points.thread_eye.y:max [m]``, ``points.thread_eye.a:max [m/s^2]``, ``points.thread_eye.a:max.index``.
"""
from __future__ import annotations

import math
import os
import re
import threading
from collections.abc import Mapping
from functools import partial
from functools import cached_property

import numpy as np

from sewgen import abi
from sewgen.errors import InputError, ParameterError
from sewgen.engine.arguments import DEFAULT_MAX_ITER, NONNEGATIVE, parameter_problem, pointer, request, si
from sewgen.engine.results import Selection
from sewgen.units import UnitError, to_si

#: Reduction kinds, in the C runtime's numbering (sewgen.abi.REDUCTIONS).
REDUCTIONS = tuple(name for _, name in abi.REDUCTIONS)
_EXTREMA = ("min", "max", "absmax")
_BAD_DESIGN = next(code for name, code, _, _ in abi.STATUS if name == "SG_BAD_DESIGN")
_UNIT_SUFFIX = re.compile(r"^(.*\S)\s*\[([^\]]+)\]$")


class Columns:
    """The flat per-position columns of a mechanism (q, qd, qdd, obs), their names and SI units, and the norms
    of point velocity and acceleration pairs (for reductions). Built once per mechanism."""

    def __init__(self, desc):
        nq = len(desc.coords)
        names, units = [], []
        for suffix, rate in (("", ""), ("_d", "/s"), ("_dd", "/s^2")):
            for c in desc.coords:
                names.append(f"coords.{c.name}{suffix}")
                units.append(c.unit + rate)
        owner = {}
        for p in desc.points:
            for k in range(6):
                owner[p.offset + k] = "points"
        for b in desc.bodies:
            for k in range(9):
                owner[b.offset + k] = "bodies"
        for k, (name, unit) in enumerate(desc.observables):
            names.append(f"{owner.get(k, 'obs')}.{name}")
            units.append(unit)
        self.names, self.units = names, units
        self.index = {n: k for k, n in enumerate(names)}
        self.width = len(names)
        groups = {"coords": list(range(3 * nq)), "points": [], "bodies": []}
        members = {}
        for c in desc.coords:
            members[f"coords:{c.name}"] = [c.index, nq + c.index, 2 * nq + c.index]
        norms = {}
        for p in desc.points:
            cols = [3 * nq + p.offset + k for k in range(6)]
            members[f"points:{p.name}"] = cols
            groups["points"] += cols
            norms[f"points.{p.name}.v"] = (cols[2], cols[3], units[cols[2]])
            norms[f"points.{p.name}.a"] = (cols[4], cols[5], units[cols[4]])
        for b in desc.bodies:
            cols = [3 * nq + b.offset + k for k in range(9)]
            members[f"bodies:{b.name}"] = cols
            groups["bodies"] += cols
            norms[f"bodies.{b.name}.com.v"] = (cols[5], cols[6], units[cols[5]])
            norms[f"bodies.{b.name}.com.a"] = (cols[7], cols[8], units[cols[7]])
        groups["all"] = list(range(self.width))
        self.groups, self.members, self.norms = groups, members, norms
        qa, oa = desc.angle_columns
        self.angle_cols = np.array(list(qa) + [3 * nq + k for k in oa], dtype=np.intc)

    def angles_among(self, columns) -> np.ndarray:
        """The angle columns among ``columns`` (flat indices): the only ones whose 2π jumps a design sweep that
        writes or reduces just ``columns`` must take out (C does it per design, a pass over every position)."""
        wanted = {int(c) for c in columns}
        return np.array([c for c in self.angle_cols if int(c) in wanted], dtype=np.intc)

    def unit(self, name: str) -> str:
        if name in self.norms:
            return self.norms[name][2]
        return self.units[self.index[name]]

    def select(self, mech: str, outputs) -> list[int]:
        """Flat columns of an ``outputs`` selection, in order, each once."""
        if isinstance(outputs, str):
            outputs = [outputs]
        out: list[int] = []
        for sel in outputs:
            if not isinstance(sel, str):
                raise ParameterError(mech, "outputs", f"must be names (str), got {sel!r}")
            cols = self.groups.get(sel) or self.members.get(sel)
            if cols is None and sel in self.index:
                cols = [self.index[sel]]
            if cols is None:
                raise ParameterError(mech, "outputs", f"no output {sel!r}; give 'all', 'coords', 'points', "
                                                      f"'bodies', 'coords:<name>', 'points:<name>', "
                                                      f"'bodies:<name>' or a column such as {self.names[0]!r} "
                                                      f"(columns: {', '.join(self.names)})")
            out += [c for c in cols if c not in out]
        return out

    def reductions(self, mech: str, spec) -> list[tuple[str, str, int, int]]:
        """(column name, kind, column, second column or -1) of a ``reduce`` argument: a mapping column -> kind or
        kinds, or a list of ``"column:kind"`` strings."""
        if spec is None:
            return []
        if isinstance(spec, str):
            spec = [spec]
        pairs = []
        if isinstance(spec, Mapping):
            for col, kinds in spec.items():
                for kind in ([kinds] if isinstance(kinds, str) else list(kinds)):
                    pairs.append((col, kind))
        else:
            for item in spec:
                if not isinstance(item, str) or ":" not in item:
                    raise ParameterError(mech, "reduce", f"entries must be 'column:kind' strings, got {item!r}")
                col, kind = item.rsplit(":", 1)
                pairs.append((col, kind))
        out = []
        for col, kind in pairs:
            if kind not in REDUCTIONS:
                raise ParameterError(mech, "reduce", f"unknown reduction {kind!r} of {col!r}; kinds: "
                                                     f"{', '.join(REDUCTIONS)}")
            if col in self.norms:
                a, b, _ = self.norms[col]
            elif col in self.index:
                a, b = self.index[col], -1
            else:
                raise ParameterError(mech, "reduce", f"no column {col!r} to reduce; columns: "
                                                     f"{', '.join(self.names + list(self.norms))}")
            if (col, kind) not in [(c, k) for c, k, _, _ in out]:
                out.append((col, kind, a, b))
        return out


class DesignSweep:
    """The result of :meth:`sewgen.Mechanism.sweep_designs` (SI throughout).

    ``status`` (n_designs, int): 0 for a design swept at every angle, else the status code of its first failing
    angle (:data:`sewgen.abi.STATUS`; 8, ``SG_BAD_DESIGN``, for parameters out of range); ``first_bad_angle``
    (int64): the index into ``phi`` of that first failing angle, -1 where none failed (or the design was not
    swept); ``error``: per design the message of the typed error a single :meth:`~sewgen.Mechanism.solve` of it
    raises (without the extra diagnosis ``solve`` adds), or None; :meth:`exception` the error itself.
    ``outputs``: column name -> (n_designs, n_angles) array (each contiguous); ``reductions``: ``"<column>:<kind>"``
    -> (n_designs,) and ``"<column>:<kind>.index"`` -> (n_designs,) int64. A failed design's outputs and
    reductions are NaN (indices -1). ``result[name]`` reads either. Column naming: :mod:`sewgen.engine.designs`.
    """

    def __init__(self, mechanism, phi, params, held, branch, status, first_bad, nbad, last_bad, outputs,
                 reductions, problems, columns, block=None):
        self.mechanism = mechanism
        self.phi = phi
        self.params, self.held, self.branch = params, held, branch
        self.status, self.first_bad_angle = status, first_bad
        self._nbad, self._last_bad = nbad, last_bad
        self.outputs, self.reductions = outputs, reductions
        self._problems = problems  # design -> ParameterError found by Python's checks
        self._columns = columns
        self._block = block  # (outputs, designs, angles): the one array ``outputs`` are slices of

    def stacked(self) -> np.ndarray:
        """Every output as one (designs, angles, outputs) array, in the order of ``outputs``: a view of the block
        the C sweep wrote, no copy."""
        if self._block is None:
            return np.stack(list(self.outputs.values()), axis=-1)
        return np.moveaxis(self._block, 0, -1)

    def __len__(self) -> int:
        return len(self.status)

    @property
    def column_names(self) -> list[str]:
        """Every per-position column of the mechanism in its layout order: q, q', q'', then the observables."""
        return list(self._columns.names)

    def __getitem__(self, name: str) -> np.ndarray:
        if name in self.outputs:
            return self.outputs[name]
        if name in self.reductions:
            return self.reductions[name]
        raise KeyError(f"{name!r} is neither an output nor a reduction of this sweep; outputs: "
                       f"{', '.join(self.outputs) or 'none'}; reductions: {', '.join(self.reductions) or 'none'}")

    @property
    def ok(self) -> np.ndarray:
        """Designs swept at every angle."""
        return self.status == 0

    @property
    def first_bad_phi(self) -> np.ndarray:
        """The shaft angle (rad) of each design's first failing position; NaN where none failed."""
        idx = self.first_bad_angle
        return np.where(idx >= 0, self.phi[np.clip(idx, 0, None)], np.nan)

    def exception(self, design: int):
        """The typed error of design ``design`` (what a single solve of it raises), or None."""
        code = int(self.status[design])
        if code == 0:
            return None
        mech = self.mechanism
        if design in self._problems:
            return self._problems[design]
        if code == _BAD_DESIGN:
            try:
                mech.check_constants(self.params[design])
            except ParameterError as exc:
                return exc
            return ParameterError(mech.name, "params", "a parameter, held input or branch sign is out of range")
        cls = abi.error_for(code)
        i, last = int(self.first_bad_angle[design]), int(self._last_bad[design])
        if cls is None:
            return InputError(mech.name, f"runtime refused the design ({abi.status_name(code)})")
        return cls(mech.name, float(self.phi[i]), i, int(self._nbad[design]), float(self.phi[last]))

    @cached_property
    def error(self) -> list:
        """Per design: the message of its typed error, or None."""
        out: list = [None] * len(self.status)
        for d in np.flatnonzero(self.status):
            out[int(d)] = str(self.exception(int(d)))
        return out

    def to_dataframe(self):
        """One row per design (pandas): the design's parameters (``<name> [unit]``, SI), ``status``, ``error``,
        ``first_bad_angle`` (index), then every reduction as ``<column>:<kind> [unit]`` (its extremum's position
        as ``<column>:<kind>.index``)."""
        import pandas as pd

        desc = self.mechanism.description
        cols = {}
        for spec in desc.params:
            cols[f"{spec.name} [{spec.unit}]"] = self.params[:, spec.index]
        for k, spec in enumerate(desc.held_inputs):
            cols[f"{spec.name} [{spec.unit}]"] = self.held[:, k]
        for k, b in enumerate(desc.branches):
            cols[f"branch.{b.joint}"] = self.branch[:, k]
        cols["status"] = self.status
        cols["error"] = pd.Series(self.error, dtype=object)  # None where it swept (pandas 3 would make it NaN)
        cols["first_bad_angle"] = self.first_bad_angle
        for name, arr in self.reductions.items():
            if name.endswith(".index"):
                cols[name] = arr
            else:
                col = name.rsplit(":", 1)[0]
                cols[f"{name} [{self._columns.unit(col)}]"] = arr
        return pd.DataFrame(cols)


# -- input conversion ---------------------------------------------------------------------------------------
def _column_values(mech: str, name: str, value, kind: str, unit: str | None):
    """One column of a design table as float64 SI: a number or an array (SI, or in ``unit`` when the column's
    name carried one: one factor for the column), a quantity string (all designs), an array of quantity
    strings (each distinct text read once), or a pint Quantity (one factor for the column)."""
    def factor(u: str) -> float:
        return si(mech, f"1 {u}", kind, name)

    if hasattr(value, "magnitude") and hasattr(value, "units"):  # a pint Quantity
        return np.asarray(value.magnitude, dtype=np.float64) * factor(f"{value.units:~}" if str(value.units)
                                                                       else "")
    if isinstance(value, str):
        return np.float64(si(mech, value, kind, name))
    arr = np.asarray(value.to_numpy() if hasattr(value, "to_numpy") else value)
    if arr.dtype.kind in "OUS":  # quantity strings (or numbers among them)
        flat = arr.ravel()
        seen: dict = {}
        out = np.empty(flat.shape, dtype=np.float64)
        for k, v in enumerate(flat):
            key = v if isinstance(v, str) else None
            if key is not None and key in seen:
                out[k] = seen[key]
                continue
            if isinstance(v, (float, int, np.floating, np.integer)) and not isinstance(v, (bool, np.bool_)) \
                    and unit is None:
                out[k] = float(v)
                continue
            try:
                val = to_si(v if unit is None or isinstance(v, str) else f"{v} {unit}", kind, name)
            except UnitError as exc:
                raise ParameterError(mech, name, f"design {k}: {exc.problem}") from None
            if key is not None:
                seen[key] = val
            out[k] = val
        return out.reshape(arr.shape)
    if arr.dtype.kind not in "iuf":
        raise ParameterError(mech, name, f"must be real numbers or quantity strings, got dtype {arr.dtype}")
    arr = arr.astype(np.float64)
    return arr * factor(unit) if unit is not None else arr


def _table(mech, designs) -> tuple[int, dict]:
    """(n_designs, {parameter name: SI column or scalar}) of a design table."""
    name = mech.name
    known = {p.name: p for p in mech.description.params}
    if isinstance(designs, np.ndarray) or (isinstance(designs, (list, tuple)) and designs
                                           and not isinstance(designs[0], str)):
        arr = np.asarray(designs)
        if arr.dtype.kind not in "iuf" or arr.ndim != 2 or arr.shape[1] != len(known):
            raise ParameterError(name, "designs", f"an array of designs must be real numbers of shape (n_designs, "
                                                  f"{len(known)}) in param_names order (SI), got "
                                                  f"{arr.dtype} {arr.shape}")
        arr = np.asarray(arr, dtype=np.float64)
        return arr.shape[0], {p: arr[:, k] for k, p in enumerate(known)}
    if hasattr(designs, "columns") and hasattr(designs, "__getitem__"):  # a pandas DataFrame
        items = [(str(c), designs[c]) for c in designs.columns]
    elif isinstance(designs, Mapping):
        items = list(designs.items())
    else:
        raise ParameterError(name, "designs", f"must be a DataFrame, a mapping of parameter names to values or an "
                                              f"(n_designs, n_parameters) array, got {type(designs).__name__}")
    cols, n = {}, None
    held, branches = set(mech.held_names), set(mech.branch_names)
    for key, value in items:
        key = str(key)
        unit = None
        if key not in known:
            m = _UNIT_SUFFIX.match(key)
            if m and m.group(1) in known:
                key, unit = m.group(1), m.group(2).strip()
        if key not in known:
            hint = (" (a held input: pass held=)" if key in held else " (a branch: pass branch=)" if key in branches
                    else f"; parameters are: {', '.join(known)}")
            raise ParameterError(name, key, f"is not a parameter{hint}")
        if key in cols:
            raise ParameterError(name, key, "given twice")
        v = _column_values(name, key, value, known[key].kind, unit)
        v = np.asarray(v, dtype=np.float64)
        if v.ndim > 1:
            raise ParameterError(name, key, f"a design column must be 1-D, got shape {v.shape}")
        if v.ndim == 1:
            if n is not None and v.shape[0] != n:
                raise ParameterError(name, key, f"has {v.shape[0]} designs, another column {n}")
            n = v.shape[0]
        cols[key] = v
    return (1 if n is None else n), cols


def _per_design(mech, what: str, given, names: list[str], defaults: list, nd: int, kind: str) -> np.ndarray:
    """held inputs (kind "held": each an angle or a travel, as its input says) or branch signs (kind "sign")
    per design: (nd, len(names))."""
    quantities = {i.name: i.quantity for i in mech.description.held_inputs}
    dtype = np.intc if kind == "sign" else np.float64
    out = np.empty((nd, len(names)), dtype=dtype)
    out[:] = np.asarray(defaults, dtype=dtype) if names else 0
    if given is None:
        return out
    if isinstance(given, np.ndarray):
        if given.shape != (nd, len(names)):
            raise ParameterError(mech.name, what, f"an array must have shape ({nd}, {len(names)}), got {given.shape}")
        if kind == "sign":
            if given.dtype.kind not in "iuf" or not np.isin(given, (1, -1)).all():
                raise ParameterError(mech.name, what, "branch signs must be +1 or -1")
        out[:] = given
        return out
    if not isinstance(given, Mapping):
        raise ParameterError(mech.name, what, f"must be a dict of names to values (scalars or one per design) or an "
                                              f"({nd}, {len(names)}) array, got {type(given).__name__}")
    for key, value in given.items():
        if key not in names:
            label = "held input" if kind == "held" else "branch joint"
            raise ParameterError(mech.name, key, f"is not a {label}; {label}s are: {', '.join(names) or 'none'}")
        k = names.index(key)
        if kind == "sign":
            v = np.asarray(value)
            if v.dtype.kind not in "iu" and not (v.dtype.kind == "f" and np.all(v == np.round(v))) \
                    or v.dtype == bool or not np.isin(v, (1, -1)).all():
                raise ParameterError(mech.name, key, f"branch must be +1 or -1 (per design), got {value!r}")
        else:
            v = _column_values(mech.name, key, value, kind if kind != "held" else quantities[key], None)
        v = np.asarray(v)
        if v.ndim == 1 and v.shape[0] != nd:
            raise ParameterError(mech.name, key, f"has {v.shape[0]} values for {nd} designs")
        if v.ndim > 1:
            raise ParameterError(mech.name, key, f"must be a scalar or one value per design, got shape {v.shape}")
        out[:, k] = v
    return out


def _check_columns(mech, p: np.ndarray, held: np.ndarray) -> dict:
    """Per-design checks, column by column (vectorised): design -> the ParameterError a single solve raises."""
    problems: dict = {}
    for spec in mech.description.params:
        col = p[:, spec.index]
        bad = ~np.isfinite(col)
        if spec.positive:
            bad |= ~(col > 0)
        if spec.kind in NONNEGATIVE:
            bad |= col < 0
        if spec.minimum is not None:
            bad |= col < spec.minimum
        if spec.maximum is not None:
            bad |= col > spec.maximum
        for d in np.flatnonzero(bad):  # the message: the one check of a parameter's value (parameter_problem)
            d = int(d)
            if d in problems:
                continue
            v = float(col[d])
            msg = f"{v!r} is not finite" if not math.isfinite(v) else parameter_problem(spec, v)
            problems[d] = ParameterError(mech.name, spec.name, msg)
    for k, spec in enumerate(mech.description.held_inputs):
        for d in np.flatnonzero(~np.isfinite(held[:, k])):
            problems.setdefault(int(d), ParameterError(mech.name, spec.name, f"{float(held[d, k])!r} is not finite"))
    return problems


_local = threading.local()


def _work(n: int, width: int) -> tuple:
    """This thread's scratch of sg_sweep_designs (one design's sweep: n rows of width + 3 doubles, n statuses),
    kept between calls: fresh memory of this size would cost its page faults on every call, as much as a short
    sweep itself. Never handed out: every result is copied from it."""
    work = getattr(_local, "work", None)
    if work is None or work[0].shape[0] < n * (width + 3) or work[1].shape[0] < n:
        work = (np.empty(max(n * (width + 3), 1)), np.empty(max(n, 1), dtype=np.intc))
        _local.work = work
    return work


def sweep_designs(mech, designs, phi, speed=None, accel=0.0, *, outputs=None, reduce=None, held=None, branch=None,
                  threads=None, degrees=False, newton=False, max_iter=None, chunk=None, loop="auto") -> DesignSweep:
    """:meth:`sewgen.Mechanism.sweep_designs` (its documentation)."""
    name = mech.name
    desc = mech.description
    sizes = desc.sizes
    nq, nobs, npar = sizes["nq"], sizes["nobs"], sizes["np"]
    # the shaft angles, speed and acceleration: as prepare() checks them (one sweep's worth, shared)
    base = mech.prepare(phi, speed, accel, degrees=degrees, newton=newton,
                        max_iter=DEFAULT_MAX_ITER if max_iter is None else max_iter, layout="arrays").use_loop(loop)
    n = base.n
    nd, given = _table(mech, designs)
    p = np.empty((nd, npar))
    p[:] = mech.default_vectors["p"]
    for key, v in given.items():
        p[:, desc.param(key).index] = v
    h = _per_design(mech, "held", held, mech.held_names, [i.default for i in desc.held_inputs], nd, "held")
    b = _per_design(mech, "branch", branch, mech.branch_names, [x.default for x in desc.branches], nd, "sign")
    problems = _check_columns(mech, p, h)
    cols = output_columns(mech)
    if outputs is None:
        outputs = [] if reduce is not None else ["all"]
    sel = cols.select(name, outputs)
    reds = cols.reductions(name, reduce)
    if threads is None:
        threads = min(os.cpu_count() or 1, 8)
    if not isinstance(threads, (int, np.integer)) or isinstance(threads, bool) or threads < 1:
        raise ParameterError(name, "threads", f"must be a positive integer, got {threads!r}")
    status = np.zeros(nd, dtype=np.intc)
    for d in problems:
        status[d] = _BAD_DESIGN
    first = np.full(nd, -1, dtype=np.int64)
    nbad = np.zeros(nd, dtype=np.int64)
    last = np.full(nd, -1, dtype=np.int64)
    out = np.empty((len(sel), nd, n))
    red_val = np.empty((len(reds), nd))
    red_idx = np.empty((len(reds), nd), dtype=np.int64)
    sel_c = np.array(sel, dtype=np.intc)
    red_c = np.array([(REDUCTIONS.index(k), a, bb) for _, k, a, bb in reds], dtype=np.intc).reshape(-1)
    ncheck = len(mech.manifest.get("constants") or [])
    ffi, lib = mech.ffi, mech.lib
    width = 3 * nq + nobs
    ptr = partial(pointer, ffi)

    shared = (ptr("double *", base.phi), ptr("double *", base.omega), ptr("double *", base.alpha))
    guess, opt = ptr("double *", base.guess), base.options
    order = ffi.NULL if base.order is None else ptr("size_t *", base.order)
    angle_c = cols.angles_among(list(sel) + [c for _, _, a, bb in reds for c in (a, bb) if c >= 0])
    angle_p = ptr("int *", angle_c)
    sel_p, red_p = ptr("int *", sel_c), ptr("int *", red_c)
    bases = {"p": ptr("double *", p), "h": ptr("double *", h), "b": ptr("int *", b), "out": ptr("double *", out),
             "rv": ptr("double *", red_val), "ri": ptr("long long *", red_idx), "st": ptr("int *", status),
             "first": ptr("long long *", first), "nbad": ptr("long long *", nbad), "last": ptr("long long *", last)}

    def offset(key, k):
        base_ptr = bases[key]
        return base_ptr if base_ptr == ffi.NULL else base_ptr + k

    def run(span):
        d0, d1 = span
        work = _work(n, width)
        req, keep = request(
            ffi, n=n, phi=shared[0], omega=shared[1], alpha=shared[2], held=offset("h", d0 * (len(desc.inputs) - 1)),
            p=offset("p", d0 * npar), branch=offset("b", d0 * len(desc.branches)), q_guess=guess, opt=opt,
            order=order, nd=d1 - d0, ncheck=ncheck, nangle=len(angle_c), angle_cols=angle_p, nsel=len(sel),
            sel=sel_p, out=offset("out", d0 * n), out_stride=nd * n, nred=len(reds), red=red_p,
            red_val=offset("rv", d0), red_idx=offset("ri", d0), red_stride=nd, work=work[0], work_status=work[1],
            design_status=offset("st", d0), first_bad=offset("first", d0), nbad=offset("nbad", d0),
            last_bad=offset("last", d0))
        lib.sg_sweep_designs(mech.in_c.descriptor, req)

    if chunk is None:
        chunk = max(1, min(4096, -(-nd // (8 * threads))))
    spans = [(d0, min(nd, d0 + chunk)) for d0 in range(0, nd, chunk)]
    if threads == 1 or len(spans) == 1:
        for s in spans:
            run(s)
    else:
        # imported here: concurrent.futures (and the logging it loads) would cost every `import sewgen` 4 ms
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(max_workers=threads) as pool:
            list(pool.map(run, spans))
    outs = {cols.names[c]: out[k] for k, c in enumerate(sel)}
    red = {}
    for k, (col, kind, _, _) in enumerate(reds):
        red[f"{col}:{kind}"] = red_val[k]
        if kind in _EXTREMA:
            red[f"{col}:{kind}.index"] = red_idx[k]
    return DesignSweep(mech, base.phi, p, h, b, status, first, nbad, last, outs, red, problems, cols, out)


_COLUMNS: dict = {}
_COLUMNS_LOCK = threading.Lock()


def output_columns(mech) -> Columns:
    key = mech.reference.digest
    cols = _COLUMNS.get(key)
    if cols is None:
        with _COLUMNS_LOCK:
            cols = _COLUMNS.setdefault(key, Columns(mech.description))
    return cols


def _one_design(ffi, n: int, width: int) -> tuple:
    """This thread's scratch of a one-design sg_sweep_designs call (:func:`_work`, a status and a first failing
    position) with its C pointers, made again only when the scratch grows or the module differs."""
    work, work_st = _work(n, width)
    one = getattr(_local, "one", None)
    if one is None or one[0] is not ffi or one[1] is not work:
        status, first = np.zeros(1, dtype=np.intc), np.full(1, -1, dtype=np.int64)
        one = (ffi, work, status, ffi.from_buffer("int[]", status), ffi.from_buffer("long long[]", first),
               ffi.from_buffer("double[]", work), ffi.from_buffer("int[]", work_st), first)
        _local.one = one
    return one[2:7]


#: solve(outputs=...)'s parsed selections, by (mechanism digest, outputs): a cache, not state (a hit gives what a
#: miss computes).
_SELECTIONS: dict = {}


def _selection(mech, outputs) -> tuple:
    """(count, C pointer of the flat columns, count, C pointer of the angle columns among them, their names, the
    flat columns' count, the columns, the angle columns) of ``outputs``, parsed once per (mechanism, outputs)
    where ``outputs`` is hashable; a bad name raises its ParameterError."""
    try:
        key = (mech.reference.digest, tuple(outputs) if isinstance(outputs, (list, tuple)) else (outputs,))
        plan = _SELECTIONS.get(key)
    except TypeError:
        key, plan = None, None
    if plan is None:
        cols = output_columns(mech)
        sel = np.array(cols.select(mech.name, outputs), dtype=np.intc)
        angle = np.array(cols.angles_among(list(sel)), dtype=np.intc)
        plan = (len(sel), pointer(mech.ffi, "int *", sel), len(angle), pointer(mech.ffi, "int *", angle),
                [cols.names[c] for c in sel], len(cols.names), sel, angle)
        if key is not None:
            if len(_SELECTIONS) >= 256:
                _SELECTIONS.clear()
            _SELECTIONS[key] = plan
    return plan


class SelectedSweep:
    """``Mechanism.solve(..., outputs=...)`` prepared (:meth:`~sewgen.Mechanism.prepare` with ``outputs``): one
    sweep writing only the selected columns, each contiguous, into ``block`` (a
    :class:`~sewgen.engine.results.Selection` is the result); the same values as the full sweep's columns, bit
    for bit. ``base`` is the prepared full sweep of the same arguments (its checked inputs; a lean one's angles
    and speed are laid out here), which also diagnoses a failure: :meth:`check` runs it and raises its error."""

    def __init__(self, mech, base, outputs, out=None):
        self.mechanism, self.base, self.n = mech, base, base.n
        self.plan = _selection(mech, outputs)
        n, nsel = base.n, self.plan[0]
        block = getattr(out, "block", out)
        inputs = () if base.one_block else (base.phi, base.omega, base.alpha)  # a lean base's: laid out in run()
        if not (isinstance(block, np.ndarray) and block.shape == (nsel, n) and block.dtype == np.float64
                and block.flags.c_contiguous and block.flags.writeable
                and not any(np.may_share_memory(block, x) for x in inputs)):
            block = np.empty((nsel, n))
        self.block = block
        self.failed = 0
        self.inputs = None

    def run(self) -> int:
        """One C call (sg_sweep_designs with one design); returns 1 where the sweep failed, else 0."""
        mech, base, n = self.mechanism, self.base, self.n
        nsel, sel_p, nangle, angle_p, _names, width = self.plan[:6]
        ffi, lib, c = mech.ffi, mech.lib, mech.in_c
        if base.one_block:  # the angles, the one speed, no acceleration: one buffer
            inputs = np.empty(3 * n)
            phi_v, omega, alpha = inputs[:n], inputs[n:2 * n], inputs[2 * n:]
            phi_v[:] = base.phi
            omega.fill(base.speed)
            alpha.fill(0.0)
            phi_p = ffi.from_buffer("double[]", inputs)
            omega_p, alpha_p = phi_p + n, phi_p + 2 * n
            order_p = ffi.NULL
            if n > 1 and not lib.sg_sorted(n, phi_p):
                order_p = ffi.from_buffer("size_t[]", np.argsort(phi_v, kind="stable").astype(np.uintp))
            held, branch, guess, p = c.held, c.branch, c.guess, base.params_c
        else:
            phi_v, omega, alpha = base.phi, base.omega, base.alpha
            phi_p, omega_p, alpha_p = phi_v, omega, alpha
            order_p = ffi.NULL if base.order is None else base.order
            held, branch, guess, p = base.held, base.branch, base.guess, base.params
        status, status_p, first_p, work_p, work_st_p = _one_design(ffi, n, width)
        status[0] = 0
        req, keep = request(ffi, n=n, phi=phi_p, omega=omega_p, alpha=alpha_p, held=held, p=p, branch=branch,
                            q_guess=guess, opt=base.options, order=order_p, nd=1, nangle=nangle,
                            angle_cols=angle_p, nsel=nsel, sel=sel_p, out=self.block, out_stride=n, work=work_p,
                            work_status=work_st_p, design_status=status_p, first_bad=first_p)
        lib.sg_sweep_designs(c.descriptor, req)
        self.inputs = (phi_v, omega, alpha)
        self.failed = int(status[0])
        return int(self.failed != 0)

    def check(self) -> None:
        """Raise the error :meth:`~sewgen.Mechanism.solve` raises where the sweep failed: the full sweep of the
        same arguments names the failure with its diagnosis."""
        if not self.failed:
            return
        self.base.run()
        self.base.check()
        raise InputError(self.mechanism.name, f"runtime refused the sweep ({abi.status_name(self.failed)})")

    def result(self) -> Selection:
        """Run, check, and the :class:`~sewgen.engine.results.Selection` of the selected columns."""
        self.run()
        self.check()
        return Selection(self.mechanism, *self.inputs, self.block, self.plan[4])

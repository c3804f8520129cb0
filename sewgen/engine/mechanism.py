"""A compiled mechanism behind a thin Python API: one C call per sweep.

Names, units, sizes and defaults come from the mechanism's :class:`~sewgen.engine.description.Description` (built once
from the manifest compiled into the module); nothing here repeats them by hand. Inputs are checked and converted
before C sees them; a failing position raises the typed error of its status, naming the mechanism and the first
failing shaft angle.

A :class:`Mechanism` is immutable once built and holds no state that a call changes: every sweep gets its own
arrays (or the caller's, through ``out=``), and what is shared — the default parameter vector, the Newton options
of the defaults — is made once in ``__init__`` and read-only. cffi releases the GIL during the C call, so several
threads may sweep one Mechanism at once. A Mechanism pickles as a :class:`Reference` (a catalog name, or the
cache entry of a user build with the generated sources to rebuild it), never as compiled code.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import threading
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from sewgen import abi
from sewgen.engine import designs as many_designs
from sewgen.engine.arguments import (DEFAULT_MAX_ITER, DEGREES_LIKE, check_gravity, check_shaft_angles, mapping,
                                     parameter_problem, pointer, request, si, vector)
from sewgen.engine.description import describe
from sewgen.errors import AssemblyError, InputError, ParameterError, SingularPositionError
from sewgen.engine.forces import ForceAnalysis, RunSettings
from sewgen.engine.loads import Load, load_matrix
from sewgen.engine.results import Motion
from sewgen.units import UnitError, to_si

_SIZE_MAX = (1 << (8 * np.dtype(np.uintp).itemsize)) - 1  # sg_solve_lean's "not ascending" (size_t is uintp)
#: kinetostatics()' defaults: gravity, its direction (−y, the catalog's "down"), the shaking moment's point.
_GRAVITY, _DOWN, _ORIGIN = "9.80665 m/s**2", "-90 deg", (0.0, 0.0)
_MAX_ITER_LIMIT = 100_000  # Newton iterations per position: more is a hang, not a solve
#: Newton's relative tolerance: every closure equation's residual below this times its own loop size.
NEWTON_RTOL = 1e-13
#: Largest estimated relative error of a position's velocities and accelerations (the amplification of the
#: velocity and acceleration solves, with the position's own error: csrc/sg_runtime.h sg_rates_error): above it the
#: position is singular.
SINGULAR_TOL = 1e-8
_SINGULAR_MODES = ("raise", "flag")


@dataclass(frozen=True)
class Reference:
    """How to find a compiled mechanism again, in this or another process: what a pickled Mechanism holds.

    ``kind`` "catalog": the built-in module's mechanism ``name``. ``kind`` "user": cffi module ``module`` in the
    cache entry ``folder``, built from generated files whose hash is ``key``; ``sources`` (the generated files,
    zlib-compressed JSON) rebuild it where that entry is gone (another machine, a cleared cache), so no SymPy
    and no declaration file are needed to unpickle. ``digest`` (sha256 of the manifest) is checked when the
    reference is resolved: a result never meets another mechanism than the one that made it.
    ``declaration`` is the declaration file a user mechanism came from, if any (for messages only).
    """

    kind: str
    name: str
    digest: str = ""
    module: str = ""
    folder: str = ""
    key: str = ""
    declaration: str = ""
    sources: bytes = dataclasses.field(default=b"", repr=False)


#: Who finds the Mechanism a :class:`Reference` names: :func:`sewgen.engine.loader.resolve`, registered when the
#: loader is imported (``import sewgen`` imports it, and unpickling imports the package before this module).
RESOLVERS: list = []


def resolve_reference(ref: Reference) -> Mechanism:
    """The Mechanism ``ref`` names, in this process (what unpickling a Mechanism calls)."""
    return RESOLVERS[-1](ref)


@dataclass(frozen=True)
class CDefaults:
    """What every call of one mechanism into C shares, made once when it loads: its descriptor, the C pointers of
    its default parameter, held-input, branch and guess vectors and of its default options (closed form where
    there is one, singular positions refused), and the angle columns a sweep makes continuous (counts and C
    pointers). The engine's design sweeps and the machine plan read these instead of converting again."""

    descriptor: object
    params: object
    held: object
    branch: object
    guess: object
    options: object
    nqa: int
    qcols: object
    noa: int
    ocols: object


class Mechanism:
    """One mechanism of a compiled module (the catalog's or a user's). Immutable and safe to share between
    threads; pickles by reference (see the module docstring)."""

    def __init__(self, ffi, lib, name: str, build_info: dict | None = None, reference: Reference | None = None):
        text = ffi.string(getattr(lib, f"sg_{name}_manifest")()).decode()
        manifest = json.loads(text)
        desc = describe(manifest)
        desc.has("point", "")  # build its name tables now, before threads share it
        digest = hashlib.sha256(text.encode()).hexdigest()
        ref = Reference("catalog", name) if reference is None else reference
        p = self._check_params(desc, {q.name: q.default for q in desc.params})
        defaults = {  # C only reads these: shared by every call, so read-only
            "p": p,
            "held": np.array([i.default for i in desc.held_inputs], dtype=np.float64),
            "branch": np.array([b.default for b in desc.branches], dtype=np.intc),
            "guess": np.array([c.guess for c in desc.coords], dtype=np.float64),
        }
        for arr in defaults.values():
            arr.flags.writeable = False
        fields = dict(
            ffi=ffi, lib=lib, name=name, description=desc, _manifest=manifest,
            build_info=MappingProxyType(dict(build_info or {})),
            reference=dataclasses.replace(ref, digest=digest), default_vectors=MappingProxyType(defaults),
            _default_options=MappingProxyType({(newton, keep): self._new_options(ffi, DEFAULT_MAX_ITER, newton, keep)
                                               for newton in (False, True) for keep in (False, True)}))
        qa, oa = (np.array(cols, dtype=np.intc) for cols in desc.angle_columns)
        vec = {k: pointer(ffi, "int *" if k == "branch" else "double *", v) for k, v in defaults.items()}
        fields["in_c"] = CDefaults(getattr(lib, f"sg_{name}")(), vec["p"], vec["held"], vec["branch"], vec["guess"],
                                   fields["_default_options"][(False, False)], len(qa), pointer(ffi, "int *", qa),
                                   len(oa), pointer(ffi, "int *", oa))
        # The per-call cost of solve(): one sg_request per thread for the lean path, the converted parameter
        # vectors of recent params= dicts, kinetostatics()' default settings. Caches, not state: a hit gives what a
        # miss computes.
        sizes = desc.sizes
        w = 4 + 3 * sizes["nq"] + sizes["nobs"]  # doubles a position of sg_solve_lean's block: kinematics, forces
        fields["lean_widths"] = (w, w + sizes["nfo"])
        fields["_lean_requests"] = threading.local()
        fields["_lean_forces_base"] = []
        fields["_pcache"] = {}
        for key, value in fields.items():
            object.__setattr__(self, key, value)
        self.check_constants(p)  # a declaration whose defaults give no real dimension

    def __setattr__(self, key, value):
        raise AttributeError(f"sewgen.Mechanism is immutable (cannot set {key!r})")

    def __reduce__(self):
        return resolve_reference, (self.reference,)

    def __repr__(self) -> str:
        d = self.description
        return f"<sewgen.Mechanism {self.name}: {len(d.coords)} coordinates, {len(d.params)} parameters>"

    # -- what the mechanism is (all from the description) --------------------------------------------------
    @property
    def manifest(self) -> dict:
        """The compiled manifest (JSON as a dict), for compatibility: read it, never change it. The engine reads
        :attr:`description` only."""
        return self._manifest

    @property
    def doc(self) -> str:
        return self.description.doc

    @property
    def closed_form(self) -> bool:
        return self.description.closed_form

    @property
    def simd_width(self) -> int:
        """Shaft positions per SIMD block of this mechanism's sweeps here (csrc/sg_simd.h; a Newton sweep's
        rates, observables and forces): 8 where its module is built for AVX-512 and the CPU has it (F, VL, DQ),
        4 where it is built for AVX2 and the CPU has AVX2 and FMA, 1 where the scalar loop runs. The catalog is
        built for both and the loader takes the AVX-512 module where the CPU runs it; a user's mechanism is built
        for the running CPU's best (sewgen/engine/build.py; ``SEWGEN_SIMD=avx2`` at build time: AVX2 only). Results
        agree to rounding either way (:meth:`Sweep.use_loop`)."""
        return int(self.lib.sg_simd_width(self.in_c.descriptor))

    @property
    def default_speed(self) -> float:
        return self.description.default_speed

    @property
    def param_names(self) -> list[str]:
        return [p.name for p in self.description.params]

    @property
    def coord_names(self) -> list[str]:
        return [c.name for c in self.description.coords]

    @property
    def held_names(self) -> list[str]:
        return [i.name for i in self.description.held_inputs]

    @property
    def branch_names(self) -> list[str]:
        return [b.joint for b in self.description.branches]

    @property
    def point_names(self) -> list[str]:
        return [p.name for p in self.description.points]

    @property
    def body_names(self) -> list[str]:
        return [b.name for b in self.description.bodies]

    def defaults(self) -> dict[str, float]:
        """Every parameter's default, SI."""
        return {p.name: p.default for p in self.description.params}

    def describe_params(self) -> list[dict]:
        """Name, kind, SI unit, default, declared unit, docstring and role of every parameter."""
        return [dataclasses.asdict(p) for p in self.description.params]

    # -- input conversion ----------------------------------------------------------------------------------
    def param_vector(self, params: dict | None = None) -> np.ndarray:
        """Defaults overridden by ``params`` (SI numbers or quantity strings), checked, as a C-ready vector."""
        values = self.defaults()
        given = mapping(self.name, "params", params)
        for key, val in given.items():
            if key not in values:
                raise ParameterError(self.name, key, f"unknown; parameters are: {', '.join(values)}")
            values[key] = val
        p = self._check_params(self.description, values)
        self.check_constants(p, given)
        return p

    def check_constants(self, p: np.ndarray, given=()) -> None:
        """Every dimension derived from the parameters (the hoisted constants: a triangle's height from its sides,
        ...) must be real: a non-finite one is a ParameterError naming the parameters it is made of (those the
        caller gave first)."""
        which = self.manifest.get("constants")
        if not which:
            return
        c = self._constants(p)
        bad = np.flatnonzero(~np.isfinite(c[:len(which)]))
        if not bad.size:
            return
        names = [self.description.params[i].name for i in which[int(bad[0])]]
        named = [n for n in names if n in given] or names
        raise ParameterError(self.name, ", ".join(named),
                             f"no real value for a dimension derived from {', '.join(names)} (sides that make no "
                             f"triangle, a zero length under a division, ...)")

    @staticmethod
    def _check_params(desc, values: dict) -> np.ndarray:
        out = np.empty(len(desc.params))
        for spec in desc.params:
            v = si(desc.name, values[spec.name], spec.kind, spec.name)
            problem = parameter_problem(spec, v)
            if problem:
                raise ParameterError(desc.name, spec.name, problem)
            out[spec.index] = v
        return out

    def _named_vector(self, what: str, names: list[str], defaults: list, given: dict, kind) -> list:
        """``kind``: the units kind of every entry, "sign", or a list of kinds, one per name."""
        vals = dict(zip(names, defaults))
        arg = {"held input": "held", "branch joint": "branch"}.get(what, what)
        for key, v in mapping(self.name, arg, given).items():
            if key not in vals:
                known = ", ".join(names) or "none"
                raise ParameterError(self.name, key, f"is not a {what}; {what}s are: {known}")
            vals[key] = v
        out = []
        kinds = kind if isinstance(kind, list) else [kind] * len(names)
        for key, kind in zip(names, kinds):
            v = vals[key]
            if kind == "sign":
                if isinstance(v, (bool, np.bool_)) or v not in (1, -1):
                    raise ParameterError(self.name, key, f"branch must be +1 or -1, got {v!r}")
                out.append(int(v))
            else:
                out.append(si(self.name, v, kind, key))
        return out

    def held_vector(self, held: dict | None = None) -> np.ndarray:
        """Held inputs (rad, or m for a travel; numbers or quantity strings by name) over their defaults, as a
        C-ready vector."""
        if held is None:
            return self.default_vectors["held"].copy()
        inputs = self.description.held_inputs
        return np.array(self._named_vector("held input", self.held_names, [i.default for i in inputs], held,
                                           [i.quantity for i in inputs]), dtype=np.float64)

    def _branch_vector(self, branch: dict) -> np.ndarray:
        return np.array(self._named_vector("branch joint", self.branch_names,
                                           [b.default for b in self.description.branches], branch, "sign"),
                        dtype=np.intc)

    def _guess_vector(self, guess: dict) -> np.ndarray:
        """Newton's start per coordinate (rad or m, or quantity strings): the declaration's unless overridden."""
        names = self.coord_names
        guess = mapping(self.name, "guess", guess)
        unknown = sorted(set(guess) - set(names))
        if unknown:
            raise ParameterError(self.name, unknown[0], f"is not a coordinate; coordinates are: {', '.join(names)}")
        return np.array([si(self.name, guess.get(c.name, c.guess), c.kind, c.name) for c in self.description.coords],
                        dtype=np.float64)

    def _series(self, what: str, value, n: int, kind: str) -> np.ndarray:
        """A per-position array (scalar broadcast) of float64, finite, 1-D, length n."""
        if isinstance(value, str):
            try:
                value = to_si(value, kind, what)
            except UnitError as exc:
                raise InputError(self.name, str(exc)) from None
        if type(value) in (float, int) and math.isfinite(value):  # the common scalar, fast
            return np.full(n, float(value))
        try:
            arr = np.asarray(value)
        except (ValueError, TypeError) as exc:  # ragged nesting and the like
            raise InputError(self.name, f"{what} must be real numbers: {exc}") from None
        if np.iscomplexobj(arr) or arr.dtype.kind not in "iuf":  # booleans are not angles or speeds
            raise InputError(self.name, f"{what} must be real numbers, got dtype {arr.dtype}")
        # always a copy: a result owns its inputs (a caller's later phi += 0.5 changes no result)
        arr = np.full(n, float(arr)) if arr.ndim == 0 else np.array(arr, dtype=np.float64, order="C", copy=True)
        if arr.ndim != 1 or arr.shape[0] != n:
            raise InputError(self.name, f"{what} must be a scalar or have shape ({n},), got {arr.shape}")
        if not np.isfinite(arr).all():
            bad = np.flatnonzero(~np.isfinite(arr))
            raise InputError(self.name, f"{what} is not finite at position {bad[0]} ({arr[bad[0]]!r})")
        return arr

    def length_scale(self, p: np.ndarray) -> float:
        """The largest length parameter (m), 1 mm at least (for checks; Newton's tolerance is per loop now)."""
        return _length_scale(self.description, p)

    @staticmethod
    def _new_options(ffi, max_iter: int, newton: bool, keep_singular: bool):
        return ffi.new("sg_options *", {"tol": NEWTON_RTOL, "max_iter": max_iter, "newton_only": 1 if newton else 0,
                                        "singular_tol": SINGULAR_TOL, "keep_singular": 1 if keep_singular else 0})

    # -- sweeps --------------------------------------------------------------------------------------------
    def prepare(self, phi, speed=None, accel=0.0, *, params: dict | None = None, held: dict | None = None,
                branch: dict | None = None, guess: dict | None = None, degrees: bool = False,
                newton: bool = False, max_iter: int = DEFAULT_MAX_ITER, forces: bool = False, loads=(),
                gravity=_GRAVITY, gravity_direction=_DOWN, moment_about=_ORIGIN, out=None,
                singular: str = "raise", outputs=None, layout: str = "auto") -> "Sweep":
        """Every argument of a sweep checked and converted into a prepared call: the one place the engine checks
        a sweep's arguments. :meth:`solve` and :meth:`kinetostatics` are ``prepare(...).result()``; call it
        yourself to time or repeat the bare C call (:meth:`Sweep.bind`, the benchmark) or to read the arrays C
        wrote. ``forces=True`` prepares the kinetostatic sweep (``loads``, ``gravity``, ``gravity_direction``,
        ``moment_about`` as in :meth:`kinetostatics`); ``outputs`` the sweep of a few columns
        (a :class:`~sewgen.engine.designs.SelectedSweep`, as :meth:`solve`'s ``outputs``); ``out`` as in
        :meth:`solve`.

        A sweep on the declaration's defaults but ``params`` (a 1-D float64 ``phi``, one number for ``speed``,
        no acceleration, the default gravity and no loads) is a :class:`LeanSweep`: every array in one buffer
        and one C call that fills the inputs, sweeps and makes the angles continuous; any other a
        :class:`Sweep` of separate arrays. Both run, check and give their results the same way. ``layout="arrays"``
        asks for separate arrays whatever the arguments (a caller that hands :meth:`Sweep.request` to sg_sweep
        itself: the machine plan)."""
        if layout not in ("auto", "arrays"):
            raise ParameterError(self.name, "layout", f"is {layout!r}; use 'auto' or 'arrays'")
        lean = (layout == "auto" and held is None and branch is None and guess is None and out is None and degrees is False
                and newton is False and max_iter == DEFAULT_MAX_ITER and singular == "raise"
                and type(phi) is np.ndarray and (speed is None or type(speed) in (float, int))
                and type(accel) in (float, int) and accel == 0
                and (forces is False or (moment_about is _ORIGIN and type(loads) in (tuple, list) and not loads
                                         and type(gravity) is str and gravity == _GRAVITY
                                         and type(gravity_direction) is str and gravity_direction == _DOWN)))
        base = LeanSweep.of(self, phi, speed, params, forces is True) if lean else None
        if base is None:
            base = self._prepare_arrays(phi, speed, accel, params=params, held=held, branch=branch, guess=guess,
                                        degrees=degrees, newton=newton, max_iter=max_iter, forces=forces,
                                        loads=loads, gravity=gravity, gravity_direction=gravity_direction,
                                        moment_about=moment_about, out=None if outputs is not None else out,
                                        singular=singular)
        if outputs is None:
            return base
        if forces:
            raise ParameterError(self.name, "outputs", "selects kinematic outputs: not with forces=True")
        return many_designs.SelectedSweep(self, base, outputs, out)

    def _prepare_arrays(self, phi, speed=None, accel=0.0, *, params=None, held=None, branch=None, guess=None,
                        degrees=False, newton=False, max_iter=DEFAULT_MAX_ITER, forces=False, loads=(),
                        gravity=_GRAVITY, gravity_direction=_DOWN, moment_about=_ORIGIN, out=None,
                        singular="raise") -> "Sweep":
        """:meth:`prepare` of any arguments: every check and conversion, separate arrays (a :class:`Sweep`)."""
        phi_arr = np.asarray(phi)
        if phi_arr.ndim == 0:
            phi_arr = phi_arr.reshape(1)
        if phi_arr.ndim != 1:
            raise InputError(self.name, f"shaft angles must be a 1-D array, got shape {phi_arr.shape}")
        n = phi_arr.shape[0]
        phi_v = self._series("shaft angle", phi_arr, n, "angle")
        if degrees:
            phi_v = np.radians(phi_v)
        check_shaft_angles(self.name, phi_v, degrees)  # the angles' own checks (sewgen.engine.arguments)
        omega = self._series("speed", self.default_speed if speed is None else speed, n, "speed")
        alpha = self._series("angular acceleration", accel, n, "angular_acceleration")
        if not isinstance(max_iter, (int, np.integer)) or isinstance(max_iter, (bool, np.bool_)) \
                or not 1 <= max_iter <= _MAX_ITER_LIMIT:
            raise ParameterError(self.name, "max_iter", f"must be an integer from 1 to {_MAX_ITER_LIMIT}, got "
                                                        f"{max_iter!r}")
        max_iter = int(max_iter)
        if not isinstance(newton, (bool, np.bool_)):
            raise ParameterError(self.name, "newton", f"must be True or False, got {newton!r}")
        if singular not in _SINGULAR_MODES:
            raise ParameterError(self.name, "singular", f"must be 'raise' or 'flag', got {singular!r}")
        keep = singular == "flag"
        dflt = self.default_vectors
        if params is None:
            p = dflt["p"]
        elif (hit := self.params_in_c(params)) is not None:  # converted and checked once per distinct dict
            p = hit[0]
        else:
            p = self.param_vector(params)
            p.flags.writeable = False  # it becomes part of the result's run settings
        if max_iter == DEFAULT_MAX_ITER:
            opt = self._default_options[(bool(newton), keep)]
        else:
            opt = self._new_options(self.ffi, max_iter, bool(newton), keep)
        held_v = dflt["held"] if held is None else _readonly(self.held_vector(held))
        branch_v = dflt["branch"] if branch is None else self._branch_vector(branch)
        guess_v = dflt["guess"] if guess is None else self._guess_vector(guess)
        sizes = self.description.sizes
        inputs = (phi_v, omega, alpha)
        arrays = {"q": (n, sizes["nq"]), "qd": (n, sizes["nq"]), "qdd": (n, sizes["nq"]), "obs": (n, sizes["nobs"])}
        settings = None
        if forces:
            arrays["frc"] = (n, sizes["nfo"])
            g = check_gravity(self.name, si(self.name, gravity, "acceleration", "gravity"))
            g_dir = si(self.name, gravity_direction, "angle", "gravity_direction")
            gx, gy = g * math.cos(g_dir), g * math.sin(g_dir)
            tiny = 1e-15 * abs(g)  # -90 deg is exactly -y, not (6e-16, -g)
            gv = _readonly(np.array([0.0 if abs(gx) < tiny else gx, 0.0 if abs(gy) < tiny else gy]))
            if not (isinstance(moment_about, (tuple, list)) and len(moment_about) == 2):
                raise ParameterError(self.name, "moment_about", f"must be a point (x, y), got {moment_about!r}")
            about = tuple(si(self.name, v, "length", "moment_about") for v in moment_about)
            if isinstance(loads, (Load, str, bytes, Mapping)) or not isinstance(loads, (list, tuple)):
                raise ParameterError(self.name, "loads", f"must be a list or tuple of sewgen.Load, got "
                                                         f"{type(loads).__name__} (a single load: loads=[load])")
            ld, placed = load_matrix(self, loads, phi_v, degrees)
            if ld is not None:
                ld.flags.writeable = False
            settings = RunSettings(p, held_v, branch_v, gv, ld, about, tuple(placed))
        reuse = _out_arrays(out)
        outputs = {}
        for key, shape in arrays.items():
            arr = reuse.get(key)
            if not _reusable(arr, shape, inputs):
                arr = np.empty(shape)  # C writes every row
            outputs[key] = arr
        order = None  # Newton continues along the shaft angle: unsorted or repeated angles are solved sorted
        if n > 1 and not (phi_v[1:] >= phi_v[:-1]).all():
            order = np.argsort(phi_v, kind="stable").astype(np.uintp)
        return Sweep(self, n, phi_v, omega, alpha, p, held_v, branch_v, guess_v, opt, outputs,
                     np.zeros(n, dtype=np.intc), settings, order, np.empty(n), keep)

    def solve(self, phi, speed=None, accel=0.0, *, params: dict | None = None, held: dict | None = None,
              branch: dict | None = None, guess: dict | None = None, degrees: bool = False,
              newton: bool = False, max_iter: int = DEFAULT_MAX_ITER, out=None, singular: str = "raise",
              outputs=None) -> Motion:
        """Positions, velocities and accelerations of every coordinate, point and body at shaft angles ``phi``.

        ``phi`` in rad (or degrees with ``degrees=True``); ``speed`` (rad/s, default the mechanism's
        default speed) and ``accel`` (rad/s²) are scalars or per-position arrays, numbers in SI or quantity
        strings ("1000 rpm"). ``params``, ``held`` (held inputs), ``branch`` (joint -> ±1) and ``guess``
        (coordinate -> Newton start) override the declaration's defaults by name. ``newton=True`` solves by
        Newton even where a closed form exists. Raises a :class:`~sewgen.errors.PositionError` subclass at
        the first shaft angle that fails.

        The angles may come in any order, repeated or not: they are solved in sorted order (Newton continues
        along the shaft angle, in steps of at most 0.2 rad, checking every closing loop's orientation sign) and
        returned in the caller's order. A position whose velocities and accelerations would carry an estimated
        relative error above 1e-8 (near a toggle, dead centre or change point) raises
        :class:`~sewgen.errors.SingularPositionError`; ``singular="flag"`` keeps it instead, with
        ``Motion.error_estimate`` and ``Motion.singular`` saying which (docs/explanation/runtime.md, "Robustness").

        ``out``: a previous result (:class:`Motion` or :class:`ForceAnalysis`) or a dict of arrays (``q``, ``qd``,
        ``qdd``, ``obs``) to write into instead of fresh arrays — in a loop of equal sweeps this spares the
        allocation and the page faults of new memory, which on large sweeps cost as much as the sweep. Arrays
        of another shape (or not C-contiguous float64, or overlapping an input) are not used. The result given
        as ``out`` is consumed: its arrays now hold this sweep, so use only the returned one. Without ``out``
        every call returns new arrays and no earlier result is ever touched.

        ``outputs``: only these results, each a contiguous array (a :class:`~sewgen.engine.results.Selection`, by column
        name): ``"coords"``, ``"points"``, ``"bodies"``, ``"points:<name>"``, ``"bodies:<name>"``,
        ``"coords:<name>"`` or single columns such as ``"points.thread_eye.y_dd"`` (names:
        :mod:`sewgen.engine.designs`); the values are those of the full sweep's columns, bit for bit. ``out`` may then be a previous Selection
        of the same columns and length.
        """
        return self.prepare(phi, speed, accel, params=params, held=held, branch=branch, guess=guess,
                            degrees=degrees, newton=newton, max_iter=max_iter, out=out, singular=singular,
                            outputs=outputs).result()

    def params_in_c(self, params):
        """(vector, C pointer) of a params= dict, converted and checked once and then cached by its items (with
        their types: 1 and True are different keys); None where the items are not hashable."""
        if params is None:
            return self.default_vectors["p"], self.in_c.params
        if type(params) is not dict:
            return None
        try:
            key = tuple((k, type(v), v) for k, v in params.items())
            hit = self._pcache.get(key)
        except TypeError:
            return None
        if hit is None:
            p = self.param_vector(params)  # every check, the typed errors
            p.flags.writeable = False
            hit = (p, pointer(self.ffi, "double *", p))
            if len(self._pcache) >= 256:
                self._pcache.clear()
            self._pcache[key] = hit
        return hit

    def _lean_forces(self, p):
        """(RunSettings of a kinetostatics() on the defaults but the parameter vector ``p``, C pointer of its
        gravity vector): the default gravity and moment point converted once, by prepare() itself; the settings
        cached by the vector's identity (each keeps its vector alive, so an id is never reused while cached)."""
        if not self._lean_forces_base:
            base = self._prepare_arrays(np.zeros(1), forces=True).settings
            self._lean_forces_base.append((base, pointer(self.ffi, "double *", base.gravity), {}))
        base, gravity_p, by_params = self._lean_forces_base[0]
        settings = by_params.get(id(p))
        if settings is None:
            if len(by_params) >= 256:
                by_params.clear()
            settings = by_params[id(p)] = dataclasses.replace(base, params=p)
        return settings, gravity_p

    def _continuous(self, n: int, q: np.ndarray, obs: np.ndarray, order) -> None:
        """continuous_angles(self.description, q, obs, order), in C."""
        c = self.in_c
        if not (c.nqa or c.noa) or not n:
            return
        ffi = self.ffi
        self.lib.sg_make_continuous(n, q.shape[1], obs.shape[1], pointer(ffi, "double *", q),
                                    pointer(ffi, "double *", obs), c.nqa, c.qcols, c.noa, c.ocols,
                                    ffi.NULL if order is None else pointer(ffi, "size_t *", order))

    def kinetostatics(self, phi, speed=None, accel=0.0, *, loads=(), gravity=_GRAVITY,
                      gravity_direction=_DOWN, moment_about=_ORIGIN, params: dict | None = None,
                      held: dict | None = None, branch: dict | None = None, guess: dict | None = None,
                      degrees: bool = False, newton: bool = False, max_iter: int = DEFAULT_MAX_ITER,
                      out=None, singular: str = "raise") -> ForceAnalysis:
        """Kinematics and every force at shaft angles ``phi``, in one C call (seed 000 §二(三)).

        Joint reactions, driving (and holding) torques, the shaking force and moment, kinetic and potential
        energy and the power of every source. ``loads`` is a sequence of :class:`~sewgen.engine.loads.Load`;
        ``gravity`` (magnitude, 0 to switch it off) acts along ``gravity_direction`` in the mechanism's plane
        (default −90°: −y, the catalog's "down"); ``moment_about`` is the point (x, y; m or strings) the
        shaking moment is taken about. The other arguments are :meth:`solve`'s; ``out`` may also hold ``frc``
        (a previous :class:`ForceAnalysis` gives all five arrays). A singular force matrix (a toggle position)
        raises :class:`~sewgen.errors.SingularPositionError` naming the shaft angle.
        """
        return self.prepare(phi, speed, accel, params=params, held=held, branch=branch, guess=guess,
                            degrees=degrees, newton=newton, max_iter=max_iter, forces=True, loads=loads,
                            gravity=gravity, gravity_direction=gravity_direction, moment_about=moment_about,
                            out=out, singular=singular).result()

    def sweep_designs(self, designs, phi, speed=None, *, outputs=None, reduce=None, held=None, branch=None,
                      threads=None, accel=0.0, degrees: bool = False, newton: bool = False,
                      max_iter: int = DEFAULT_MAX_ITER, chunk: int | None = None, loop: str = "auto"):
        """Many designs over the same shaft angles, each swept as :meth:`solve` sweeps it (its own continuation,
        tolerance and per-position status), in C calls over chunks of designs on ``threads`` threads (default:
        every core; the GIL is released). Returns a :class:`sewgen.engine.designs.DesignSweep`.

        ``designs``: a pandas DataFrame or a mapping parameter name -> values (one per design, or one for all):
        SI numbers, quantity strings, or a pint Quantity; a column named ``"crank [mm]"`` is in that unit. Units
        are converted once per column, never per row. Or an (n_designs, n_parameters) array, SI, in
        :attr:`param_names` order. Parameters not given take their defaults. ``held`` and ``branch``: by name,
        a scalar or one value per design each (or an (n_designs, n) array). ``phi``, ``speed``, ``accel``,
        ``degrees``, ``newton``, ``max_iter``: as :meth:`solve`, shared by every design; ``loop``: which
        closed-form loop runs, as :meth:`Sweep.use_loop` (``"auto"``, ``"scalar"``, ``"generic"``).

        ``outputs``: which per-position results to keep, ``"all"``, ``"coords"``, ``"points"``, ``"bodies"``,
        ``"points:<name>"``, ``"bodies:<name>"``, ``"coords:<name>"`` or single columns
        (``"points.thread_eye.y_dd"``); default all unless ``reduce`` is given (then none). ``reduce``: per-design
        reductions fused into the sweep, ``{"points.thread_eye.a": "max", "coords.lever.angle": ["min",
        "max"]}`` or ``["points.thread_eye.y:max", ...]`` (kinds min, max, absmax, rms, mean; a point's
        ``.v``/``.a`` is the magnitude of its velocity/acceleration). Column naming: :mod:`sewgen.engine.designs`.

        A design that fails (parameters out of range, a position that does not assemble, a singular position, …)
        gets its status, first failing angle and error message; the others are unaffected. Bad arguments (an
        unknown column, a wrong length, an unknown output) raise a :class:`~sewgen.errors.ParameterError`
        naming them."""
        return many_designs.sweep_designs(self, designs, phi, speed, accel, outputs=outputs, reduce=reduce, held=held,
                             branch=branch, threads=threads, degrees=degrees, newton=newton, max_iter=max_iter,
                             chunk=chunk, loop=loop)

    # -- single-position kernels (checks and inspection) -----------------------------------------------------
    def _ptr(self, ctype: str, arr: np.ndarray):
        return pointer(self.ffi, ctype, arr)

    def constants(self, params: dict | None = None) -> np.ndarray:
        """The parameter-only constants the kernels read (sg_<name>_constants)."""
        return self._constants(self.param_vector(params))

    def _constants(self, p: np.ndarray) -> np.ndarray:
        p = vector(self.name, "params", p, len(self.description.params))
        c = np.zeros(max(self.description.sizes["nc"], 1))
        getattr(self.lib, f"sg_{self.name}_constants")(self._ptr("double *", np.ascontiguousarray(p, dtype=float)),
                                                         self._ptr("double *", c))
        return c

    def residual(self, q, phi: float, params: dict | None = None, held: dict | None = None):
        """Φ(q, x) and Φ_q at one position (for checks): arrays of shape (nq,) and (nq, nq)."""
        nq = len(self.description.coords)
        qv = np.ascontiguousarray(q, dtype=np.float64)
        if qv.shape != (nq,):
            raise InputError(self.name, f"residual needs q of shape ({nq},), got {qv.shape}")
        x = np.concatenate([[float(phi)], self.held_vector(held)])
        r, jac = np.zeros(nq), np.zeros((nq, nq))
        d = self._ptr
        getattr(self.lib, f"sg_{self.name}_residual")(
            d("double *", qv), d("double *", _cos_sin_pairs(qv)), d("double *", x), d("double *", _cos_sin_pairs(x)),
            d("double *", self.constants(params)), d("double *", r), d("double *", jac))
        return r, jac

    def anchors(self, q, x, params=None, constants: np.ndarray | None = None) -> np.ndarray:
        """The drawing anchors at one position (sg_<name>_anchors): world x, y of every anchor of the description
        (``description.anchors``; a "guide_direction" pair is a unit vector), then radius, world normal_from and
        normal_to of every cam arc (``description.arcs``). ``q`` the coordinates of a solved position, ``x`` its
        inputs (shaft angle, then held inputs); ``params`` by name or as the run's vector, or ``constants``
        already computed (drawing many frames of one run)."""
        d = self.description
        nq, nx = len(d.coords), len(d.inputs)
        qv = np.ascontiguousarray(q, dtype=np.float64)
        xv = np.ascontiguousarray(x, dtype=np.float64)
        if qv.shape != (nq,) or xv.shape != (nx,):
            raise InputError(self.name, f"anchors need q of shape ({nq},) and x of shape ({nx},), got {qv.shape} "
                                        f"and {xv.shape}")
        if constants is None:
            p = params if isinstance(params, np.ndarray) else self.param_vector(params)
            constants = self._constants(p)
        out = np.zeros(max(d.sizes["nanchor_out"], 1))
        dp = self._ptr
        getattr(self.lib, f"sg_{self.name}_anchors")(
            dp("double *", qv), dp("double *", _cos_sin_pairs(qv)), dp("double *", xv), dp("double *", _cos_sin_pairs(xv)),
            dp("double *", np.ascontiguousarray(constants, dtype=np.float64)), dp("double *", out))
        return out[:d.sizes["nanchor_out"]]

    def force_matrix(self, motion: Motion, index: int = 0, *, params=None, held=None,
                     gravity=(0.0, -9.80665), load_row=None):
        """A and b of A f = b at position ``index`` of a solved ``motion`` (for inspection and checks).

        ``params`` and ``held`` must be those of the run: dicts by name (over the defaults), or the C-ready
        vectors of a run (:attr:`ForceAnalysis.run_settings` ``.params``, ``.held``); ``gravity`` is the vector
        (gx, gy) in m/s²; ``load_row`` the load slots (description ``loads``) or zeros.
        :meth:`ForceAnalysis.force_matrix` passes a run's own settings. Rows: the manifest's "force_rows";
        columns: the reactions' columns in order.
        """
        p, hv = self._run_vectors(params, held)
        sizes = self.description.sizes
        nf = sizes["nf"]
        if not isinstance(motion, Motion) or motion.mechanism.reference.digest != self.reference.digest:
            got = getattr(getattr(motion, "mechanism", None), "name", type(motion).__name__)
            raise InputError(self.name, f"force_matrix needs a Motion of {self.name}, got one of {got}")
        n = len(motion.phi)
        if not isinstance(index, (int, np.integer)) or isinstance(index, bool) or not -n <= index < n:
            raise InputError(self.name, f"position index {index!r} out of range for a sweep of {n}")
        q = np.ascontiguousarray(motion.q[index], dtype=np.float64)
        x = np.concatenate([[float(motion.phi[index])], hv]).astype(np.float64)
        obs = np.ascontiguousarray(motion.obs[index], dtype=np.float64)
        gv = vector(self.name, "gravity", gravity, 2)
        nload = sizes["nload"]
        ld = np.zeros(max(nload, 1)) if load_row is None else vector(self.name, "load_row", load_row, nload)
        if q.shape != (sizes["nq"],) or obs.shape != (sizes["nobs"],):
            raise InputError(self.name, "the motion's arrays do not have this mechanism's sizes")
        A, b = np.zeros((nf, nf)), np.zeros(nf)
        d = self._ptr
        getattr(self.lib, f"sg_{self.name}_force_matrix")(
            d("double *", q), d("double *", _cos_sin_pairs(q)), d("double *", x), d("double *", _cos_sin_pairs(x)),
            d("double *", self._constants(p)), d("double *", obs), d("double *", gv), d("double *", ld),
            d("double *", A), d("double *", b))
        return A, b

    def _run_vectors(self, params, held):
        """A run's parameter and held-input vectors: by name (dicts over the defaults) or C-ready arrays of the
        right length."""
        if isinstance(params, np.ndarray):
            p = vector(self.name, "params", params, len(self.description.params))
        else:
            p = self.param_vector(params)
        if isinstance(held, np.ndarray):
            hv = vector(self.name, "held", held, len(self.description.held_inputs))
        else:
            hv = self.held_vector(held)
        return p, hv


class Sweep:
    """One sweep of a mechanism, checked and converted: the C-ready arrays the runtime reads (``phi``, ``omega``,
    ``alpha``, ``params``, ``held``, ``branch``, ``guess``, ``options``, ``order``; with forces
    ``settings.gravity`` and ``settings.loads``) and writes (``q``, ``qd``, ``qdd``, ``obs``, ``frc``, ``err``,
    ``status``).

    Made by :meth:`Mechanism.prepare`. :meth:`run` calls C once; :meth:`bind` gives that call as a bare
    zero-argument function (its pointers made once), which is what a benchmark times. Running again overwrites
    this sweep's own output arrays, so a Sweep belongs to one thread; the results it makes share its arrays.
    ``order`` (None when the angles are already non-decreasing) is the permutation C solves the positions in.
    """

    #: False: separate arrays (a :class:`LeanSweep` is the one-block layout).
    one_block = False

    def __init__(self, mechanism: Mechanism, n, phi, omega, alpha, params, held, branch, guess, options,
                 outputs: dict, status, settings: RunSettings | None, order=None, err=None, keep_singular=False):
        self.mechanism, self.n = mechanism, n
        self.phi, self.omega, self.alpha = phi, omega, alpha
        self.params, self.held, self.branch, self.guess, self.options = params, held, branch, guess, options
        self.q, self.qd, self.qdd, self.obs = outputs["q"], outputs["qd"], outputs["qdd"], outputs["obs"]
        self.frc = outputs.get("frc")
        self.status = status
        self.settings = settings
        self.order = order
        self.err = np.empty(n) if err is None else err
        self.keep_singular = keep_singular
        _check_sizes(self)

    @property
    def forces(self) -> bool:
        return self.settings is not None

    #: Closed-form loops :meth:`use_loop` chooses between (csrc/sg_runtime.c sweep): the options it sets.
    LOOPS = {"auto": {"scalar": 0, "generic": 0}, "scalar": {"scalar": 1, "generic": 0},
             "generic": {"scalar": 0, "generic": 1}}

    def use_loop(self, loop: str) -> "Sweep":
        """Which closed-form loop runs (kinematics and kinetostatics): ``"auto"`` (the default: 8 or 4 positions
        at a time in SIMD where the module and the CPU have it, :attr:`Mechanism.simd_width`), ``"scalar"`` (the
        scalar inlined loop, which does not depend on the CPU's vector units) or ``"generic"`` (the same scalar
        loop, csrc/sg_runtime.h sg_closed_sweep, with the kernels called through the descriptor: equal to the
        inlined one to the bit). SIMD and scalar agree to rounding with the same statuses (tests).
        Every other option stays as it was (the fields of :data:`sewgen.abi.OPTIONS`)."""
        if loop not in self.LOOPS:
            raise ParameterError(self.mechanism.name, "loop", f"is {loop!r}; use one of {', '.join(self.LOOPS)}")
        fields = {name: getattr(self.options, name) for _, name, _ in abi.OPTIONS}
        self.options = self.mechanism.ffi.new("sg_options *", {**fields, **self.LOOPS[loop]})
        return self

    def request(self):
        """This sweep as the one ``sg_request`` C reads (:data:`sewgen.abi.REQUEST`), with the buffers its pointers
        point into (keep both while C may read it)."""
        fields = dict(n=self.n, phi=self.phi, omega=self.omega, alpha=self.alpha, held=self.held, p=self.params,
                      branch=self.branch, q_guess=self.guess, opt=self.options, q=self.q, qd=self.qd, qdd=self.qdd,
                      obs=self.obs, err=self.err, status=self.status)
        if self.order is not None:
            fields["order"] = self.order
        if self.forces:
            fields.update(gv=self.settings.gravity, frc=self.frc)
            if self.settings.loads is not None:
                fields["loads"] = self.settings.loads
        return request(self.mechanism.ffi, **fields)

    def bind(self):
        """The C call of this sweep as a function of no arguments (its request made once); it returns how many
        positions failed."""
        req, keep = self.request()
        fn, desc = self.mechanism.lib.sg_sweep, self.mechanism.in_c.descriptor

        def call(_keep=keep) -> int:
            return fn(desc, req)

        return call

    def run(self) -> int:
        """Run the sweep in C (the GIL released), then make every angle continuous over the sweep; returns the
        number of positions whose status is not SG_OK."""
        failed = self.bind()()
        self.mechanism._continuous(self.n, self.q, self.obs, self.order)  # continuous_angles, in C
        return failed

    def check(self) -> None:
        """Raise the typed error of the first failing position (naming its shaft angle), if any failed: the first in
        the caller's order where each position is solved on its own (the closed form), the first Newton met where it
        continues from one position to the next (in ``order``, the sorted angles: a position after a failure may
        fail only for it)."""
        status = self.status
        bad = np.flatnonzero(status)
        if not bad.size:
            return
        if self.order is not None and (self.options.newton_only or not self.mechanism.closed_form):
            bad = self.order[status[self.order] != 0].astype(np.intp)  # in the order Newton solved them
        i = int(bad[0])
        code = int(status[i])
        cls = abi.error_for(code)
        name = self.mechanism.name
        if cls is None:  # SG_NAN_INPUT / SG_BAD_ARGUMENT: Python checks first, so this is a bug
            raise InputError(name, f"runtime refused the sweep ({abi.status_name(code)}) at position {i}")
        same = bad[status[bad] == code]
        detail = None
        if cls is SingularPositionError:
            detail = _singular_detail(self, i)
        elif issubclass(cls, AssemblyError) and not self.mechanism.closed_form:  # no declared branch: which?
            detail = _assembly_detail(self, i)
        raise cls(name, float(self.phi[i]), i, int(same.size), float(self.phi[same[-1]]), detail=detail)

    def motion(self) -> Motion:
        return Motion(self.mechanism, self.phi, self.omega, self.alpha, self.q, self.qd, self.qdd, self.obs,
                      self.err, SINGULAR_TOL)

    def analysis(self) -> ForceAnalysis:
        if not self.forces:
            raise ValueError("this sweep was prepared without forces (prepare(..., forces=True))")
        return ForceAnalysis(self.mechanism, self.motion(), self.frc, self.settings)

    def result(self):
        """Run, check, and the result: a :class:`ForceAnalysis` of a force sweep, else a :class:`Motion` (what
        :meth:`Mechanism.solve` and :meth:`Mechanism.kinetostatics` return)."""
        self.run()
        self.check()
        return self.analysis() if self.forces else self.motion()


#: The arrays of a :class:`LeanSweep` that are views of its block (made at the first look after a run).
_LEAN_VIEWS = frozenset(("phi", "omega", "alpha", "err", "q", "qd", "qdd", "obs", "frc", "status"))


class LeanSweep(Sweep):
    """A :class:`Sweep` on the declaration's defaults but the parameters (made by :meth:`Mechanism.prepare` where
    the arguments allow it): one buffer ``blk`` in sg_solve_lean's layout (csrc/sg_runtime.c: phi, omega, alpha,
    the error estimate, q, qd, qdd, obs by rows, then frc, then the statuses) and one C call that fills the
    inputs, sweeps (in sorted order where the angles do not ascend) and makes the angles continuous. Its arrays
    (``q``, ``status``, …) are views of the block of the last run, made at the first look; a run writes a new
    block (a bound call, :meth:`bind`, the same one), so earlier results stay as they were. A failed run is
    diagnosed by the general sweep of the same arguments (:meth:`check`). ``speed``: the one shaft speed (rad/s);
    ``params_c``: the C pointer of ``params``. The per-call cost of a short :meth:`Mechanism.solve` is this
    class's: it sets only what a run reads, the rest (defaults, views) is made at the first look."""

    one_block = True

    def __init__(self, mechanism: Mechanism, phi: np.ndarray, speed: float, params, params_c, settings, gravity_c,
                 user_params, width: int):
        self.__dict__ = {"mechanism": mechanism, "n": phi.shape[0], "phi_in": phi, "speed": speed, "params": params,
                         "params_c": params_c, "settings": settings, "gravity_c": gravity_c,
                         "user_params": user_params, "width": width, "blk": None, "failed": 0}

    @classmethod
    def of(cls, mechanism: Mechanism, phi: np.ndarray, speed, params, forces: bool) -> "LeanSweep | None":
        """The lean sweep of these arguments, None where they need the general one (a ``phi`` not 1-D float64 or
        empty, a speed not finite, parameters whose dict cannot be cached): :meth:`Mechanism.prepare` then makes a
        :class:`Sweep`, which checks them and names what is wrong. The angles are read when the sweep runs (its
        ``phi``, at the first look, is its own copy of them, which a run then reads)."""
        if phi.ndim != 1 or phi.dtype != np.float64 or not phi.shape[0]:
            return None  # a non-finite angle: SG_NAN_INPUT from C, diagnosed by the general sweep
        spd = mechanism.description.default_speed if speed is None else float(speed)
        if not math.isfinite(spd):
            return None
        got = mechanism.params_in_c(params)
        if got is None:
            return None
        if (abs(phi[0]) > DEGREES_LIKE or abs(phi[-1]) > DEGREES_LIKE) and np.isfinite(phi).all():
            check_shaft_angles(mechanism.name, phi, False)  # ascending angles' extremes are the ends (unsorted
            # ones: run() checks them all; a non-finite one: the sweep fails and check() names it)
        widths = mechanism.lean_widths
        if not phi.flags.c_contiguous:
            phi = np.ascontiguousarray(phi)
        if not forces:
            return cls(mechanism, phi, spd, got[0], got[1], None, mechanism.ffi.NULL, params, widths[0])
        settings, gravity_c = mechanism._lean_forces(got[0])
        return cls(mechanism, phi, spd, got[0], got[1], settings, gravity_c, params, widths[1])

    def __getattr__(self, name):
        """The block's arrays (after a run) and the defaults this sweep runs with, at the first look."""
        d = self.__dict__
        if name in _LEAN_VIEWS and d.get("blk") is not None:
            self._views()
            return d[name]
        if name == "phi" and "phi_in" in d:  # before a run: the sweep's own copy, which the run reads
            d["phi"] = d["phi_in"] = np.array(d["phi_in"], order="C")
            return d["phi"]
        if name in _LEAN_DEFAULTS and "mechanism" in d:
            value = d[name] = _LEAN_DEFAULTS[name](d["mechanism"])
            return value
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    def _views(self) -> None:
        """The block's arrays as attributes (views of the last run's block)."""
        m, n, blk = self.mechanism, self.n, self.blk
        sizes = m.description.sizes
        nq, nobs, nfo = sizes["nq"], sizes["nobs"], sizes["nfo"]
        o = 4 * n + 3 * n * nq
        rows, rates = blk[:4 * n].reshape(4, n), blk[4 * n:o].reshape(3, n, nq)
        tail = o + n * nobs
        frc = blk[tail:tail + n * nfo].reshape(n, nfo) if self.forces else None
        if self.forces:
            tail += n * nfo
        self.__dict__.update(phi=rows[0], omega=rows[1], alpha=rows[2], err=rows[3], q=rates[0], qd=rates[1],
                             qdd=rates[2], obs=blk[o:o + n * nobs].reshape(n, nobs), frc=frc,
                             status=blk[tail:].view(np.intc)[:n])

    def _call(self, order) -> tuple:
        """(sg_solve_lean, descriptor, request, what its pointers point into) on a new block (the last run's views
        dropped), solving in ``order`` (None: as given)."""
        d = self.__dict__
        m, n = d["mechanism"], d["n"]
        ffi, c = m.ffi, m.in_c
        if "q" in d:  # the last run's views
            for name in _LEAN_VIEWS:
                d.pop(name, None)
            d["phi"] = d["phi_in"]  # the sweep's angles until the block holds them
        blk = d["blk"] = np.empty(d["width"] * n + (n + 1) // 2)  # the statuses (C int) at the tail
        d["order"] = order
        req = getattr(m._lean_requests, "r", None)
        if req is None:  # what every lean call of this mechanism shares, set once per thread
            req = m._lean_requests.r = ffi.new("sg_request *", dict(
                held=c.held, branch=c.branch, q_guess=c.guess, nqa=c.nqa, qcols=c.qcols, noa=c.noa, ocols=c.ocols))
        phi_p, blk_p = ffi.from_buffer("double[]", d["phi_in"]), ffi.from_buffer("double[]", blk)
        order_p = ffi.NULL if order is None else ffi.from_buffer("size_t[]", order)
        req.n, req.phi, req.speed, req.p, req.gv, req.blk = n, phi_p, d["speed"], d["params_c"], d["gravity_c"], blk_p
        req.opt, req.order = d["options"] if "options" in d else c.options, order_p
        return m.lib.sg_solve_lean, c.descriptor, req, (phi_p, blk_p, order_p)

    def request(self):
        """This sweep as the ``sg_request`` sg_solve_lean reads (the mechanism's per-thread one, set for this sweep
        and a new block), with the buffers its pointers point into."""
        return self._call(self.__dict__.get("order"))[2:]

    def bind(self):
        """The C call of this sweep on one block (made here) as a function of no arguments; it returns how many
        positions failed. The angles are sorted first where they do not ascend."""
        phi = self.phi_in
        order = None
        if self.n > 1 and not (phi[1:] >= phi[:-1]).all():
            order = np.argsort(phi, kind="stable").astype(np.uintp)
        fn, desc, req, keep = self._call(order)

        def call(_keep=keep) -> int:
            return fn(desc, req)

        return call

    def run(self) -> int:
        """Run the sweep in C (the GIL released) on a new block; returns the number of failed positions."""
        fn, desc, req, keep = self._call(None)
        failed = fn(desc, req)
        if failed == _SIZE_MAX:  # not ascending: solved in sorted order, returned in the caller's
            if np.isfinite(self.phi_in).all():  # (a non-finite one: the sweep fails, check() names it)
                check_shaft_angles(self.mechanism.name, self.phi_in, False)  # of() looked at the ends only
            fn, desc, req, keep = self._call(np.argsort(self.phi_in, kind="stable").astype(np.uintp))
            failed = fn(desc, req)
        self.__dict__["failed"] = failed
        return failed

    def check(self) -> None:
        """Raise the typed error of the first failing position: the general sweep of the same arguments names it
        with its diagnosis (a non-finite angle, the failing shaft angle, …)."""
        if not self.failed:
            return
        m = self.mechanism
        full = m._prepare_arrays(self.phi_in, self.speed, params=self.user_params, forces=self.forces)
        full.run()
        full.check()
        raise InputError(m.name, f"runtime refused the sweep ({abi.status_name(int(self.status[self.status != 0][0]))})")

    def motion(self) -> Motion:
        sizes = self.mechanism.description.sizes
        return Motion.of_block(self.mechanism, self.blk, self.n, sizes["nq"], sizes["nobs"], SINGULAR_TOL)

    def analysis(self) -> ForceAnalysis:
        if not self.forces:
            raise ValueError("this sweep was prepared without forces (prepare(..., forces=True))")
        n, sizes = self.n, self.mechanism.description.sizes
        o = (4 + 3 * sizes["nq"] + sizes["nobs"]) * n
        return ForceAnalysis(self.mechanism, self.motion(), self.blk[o:o + n * sizes["nfo"]].reshape(n, sizes["nfo"]),
                             self.settings)

    def result(self):
        fn, desc, req, keep = self._call(None)
        failed = fn(desc, req)
        if failed:  # unsorted angles (run() solves them sorted), or a failure (check() names it)
            if failed == _SIZE_MAX:
                failed = self.run()
            else:
                self.__dict__["failed"] = failed
            self.check()
        if self.settings is not None:
            return self.analysis()
        m, blk = self.mechanism, self.blk
        return Motion.of_block(m, blk, self.n, m.description.sizes["nq"], m.description.sizes["nobs"], SINGULAR_TOL)


#: What a :class:`LeanSweep` runs with but sets only at the first look: the mechanism's defaults.
_LEAN_DEFAULTS = {"held": lambda m: m.default_vectors["held"], "branch": lambda m: m.default_vectors["branch"],
                  "guess": lambda m: m.default_vectors["guess"], "options": lambda m: m.in_c.options,
                  "order": lambda m: None, "keep_singular": lambda m: False}


def continuous_angles(desc, q: np.ndarray, obs: np.ndarray, order=None) -> None:
    """Every angle result (angle coordinates, body angles) continuous along the sweep, in place: no 2π jumps
    (a closed-form dyad's atan2 wraps at ±180°), the first position in (−π, π]. Along the
    shaft angles in sorted order (``order``, the permutation the sweep was solved in; None: as given). Only
    angles change, by whole turns, so every sine and cosine — and every result computed from them — stays the
    same; sweeps that start elsewhere or sample sparsely may differ from each other by whole turns."""
    qa, oa = desc.angle_columns
    idx = slice(None) if order is None else np.asarray(order, dtype=np.intp)
    for arr, cols in ((q, qa), (obs, oa)):
        if not cols or arr.ndim != 2 or not len(arr):
            continue
        block = arr[idx][:, cols]
        first = block[0]
        if not (np.abs(np.diff(block, axis=0)) > np.pi).any() and ((first > -np.pi) & (first <= np.pi)).all():
            continue  # already continuous and in range: the common case costs one pass
        block = np.unwrap(block, axis=0)
        block -= 2 * np.pi * np.ceil((block[:1] - np.pi) / (2 * np.pi))
        sub = arr[idx]
        sub[:, cols] = block
        arr[idx] = sub


def _check_sizes(sweep: Sweep) -> None:
    """Every array C reads or writes has the length the mechanism's description says (the C side reads no
    sizes: a wrong one would be read or written past its end)."""
    m, n, sizes = sweep.mechanism, sweep.n, sweep.mechanism.description.sizes
    nq, nx, nobs = sizes["nq"], sizes["nx"], sizes["nobs"]
    want = {"phi": (sweep.phi, (n,)), "omega": (sweep.omega, (n,)), "alpha": (sweep.alpha, (n,)),
            "params": (sweep.params, (sizes["np"],)), "held": (sweep.held, (nx - 1,)),
            "guess": (sweep.guess, (nq,)), "q": (sweep.q, (n, nq)), "qd": (sweep.qd, (n, nq)),
            "qdd": (sweep.qdd, (n, nq)), "obs": (sweep.obs, (n, nobs)), "err": (sweep.err, (n,))}
    for key, (arr, shape) in want.items():
        if not (isinstance(arr, np.ndarray) and arr.shape == shape and arr.dtype == np.float64
                and arr.flags.c_contiguous):
            raise InputError(m.name, f"sweep array {key} must be C-contiguous float64 of shape {shape}")
    if not (sweep.branch.shape == (sizes["nbranch"],) and sweep.branch.dtype == np.intc):
        raise InputError(m.name, f"sweep array branch must be int of shape ({sizes['nbranch']},)")
    if not (sweep.status.shape == (n,) and sweep.status.dtype == np.intc):
        raise InputError(m.name, f"sweep array status must be int of shape ({n},)")
    if sweep.order is not None and not (sweep.order.shape == (n,) and sweep.order.dtype == np.uintp):
        raise InputError(m.name, f"sweep order must be a permutation of shape ({n},)")
    if sweep.forces:
        s = sweep.settings
        if not (s.gravity.shape == (2,) and (s.loads is None or s.loads.shape == (n, sizes["nload"]))
                and isinstance(sweep.frc, np.ndarray) and sweep.frc.shape == (n, sizes["nfo"])):
            raise InputError(m.name, "force sweep arrays (gravity, loads, frc) of the wrong shape")


def _singular_detail(sweep: Sweep, i: int) -> str:
    """What makes position ``i`` singular: the estimated error of its rates, or a singular force matrix; and
    whether it is a change point (the loop assembles on both sides: two branches meet) or a dead centre."""
    est = float(sweep.err[i])
    if est <= SINGULAR_TOL:
        return "the force matrix is singular there"
    why = ("the velocity solve is singular" if not math.isfinite(est) else
           f"the velocities and accelerations would carry an estimated relative error of {est:.2g} (above "
           f"{SINGULAR_TOL:g})")
    kind = _change_point(sweep, i)
    return f"{why}; {kind}" if kind else why


def _assembly_detail(sweep: Sweep, i: int) -> str:
    """Newton found no assembly at position ``i`` (from the declared guesses, or continuing from the previous
    position): is there one in another assembly mode? A damped least-squares search (Levenberg–Marquardt on the
    loop residual) from the guesses and from starts with the angle coordinates turned, each candidate confirmed
    by the engine itself (a one-position sweep started there)."""
    m = sweep.mechanism
    d = m.description
    nq = len(d.coords)
    phi = float(sweep.phi[i])
    c = m._constants(sweep.params)
    x = np.concatenate([[phi], sweep.held])
    cx = _cos_sin_pairs(x)
    fn = getattr(m.lib, f"sg_{m.name}_residual")
    r, jac = np.zeros(nq), np.zeros((nq, nq))
    ptr = m._ptr

    def resid(q):
        fn(ptr("double *", q), ptr("double *", _cos_sin_pairs(q)), ptr("double *", x), ptr("double *", cx),
           ptr("double *", c), ptr("double *", r), ptr("double *", jac))
        return r.copy(), jac.copy()

    angle = np.array([co.unit == "rad" for co in d.coords])
    guess = np.array(sweep.guess, dtype=float)
    starts = [guess.copy()]
    for k in np.flatnonzero(angle):
        for turn in (math.pi / 2, -math.pi / 2, math.pi):
            s = guess.copy()
            s[k] += turn
            starts.append(s)
    found = []
    for q in starts[:25]:
        q = q.copy()
        mu = 1e-3
        res, jac_q = resid(q)
        cost = float(res @ res)
        for _ in range(200):
            if not np.isfinite(cost):
                break
            jtj, g = jac_q.T @ jac_q, jac_q.T @ res
            try:
                step = np.linalg.solve(jtj + mu * np.diag(np.diag(jtj) + 1e-30), -g)
            except np.linalg.LinAlgError:
                break
            trial = q + step
            r2, j2 = resid(trial)
            c2 = float(r2 @ r2)
            if c2 < cost:
                q, res, jac_q, cost, mu = trial, r2, j2, c2, max(mu / 3, 1e-12)
                if math.sqrt(cost) < 1e-14:
                    break
            else:
                mu *= 4
                if mu > 1e12:
                    break
        if math.sqrt(cost) < 1e-11 * m.length_scale(sweep.params):
            found.append(q)
    for q in found:  # confirmed by the engine: a sweep of this one position started there
        probe = m.prepare([phi], 0.0)
        probe.params, probe.held, probe.branch = sweep.params, sweep.held, sweep.branch
        probe.guess = _readonly(np.ascontiguousarray(q))
        probe.options = m._default_options[(True, True)]
        probe.run()
        if int(probe.status[0]) == 0:
            q = probe.q[0]
            moved = [f"{co.name} {math.degrees(q[k]):.4g}° (guess {math.degrees(guess[k]):.4g}°)"
                     for k, co in enumerate(d.coords) if angle[k]
                     and abs((q[k] - guess[k] + math.pi) % (2 * math.pi) - math.pi) > math.radians(20)]
            where = ("another assembly mode" if moved else "a mode near the guesses that Newton did not reach "
                     "from the previous position (the followed assembly ends here)")
            return (f"an assembly exists at this angle in {where}" + (f": {', '.join(moved)}" if moved else "")
                    + "; pass guess= to start there")
    return f"no assembly found at this angle by a least-squares search from {min(len(starts), 25)} starts either"


def _change_point(sweep: Sweep, i: int) -> str:
    """Probe the shaft angle on both sides of position ``i``: a change point if the loop closes on both (its
    assembly branches meet there), a dead centre if on one side only."""
    m, phi = sweep.mechanism, float(sweep.phi[i])
    sides = []
    for delta in (-1e-3, 1e-3):
        probe = m.prepare([phi + delta], 0.0)
        probe.params, probe.held, probe.branch, probe.guess = sweep.params, sweep.held, sweep.branch, sweep.guess
        probe.options = m._default_options[(bool(sweep.options.newton_only), True)]
        probe.run()
        sides.append(int(probe.status[0]) == 0)
    if all(sides):
        return ("a change point: the loop closes on both sides and two assembly branches meet here (past it the "
                "declared branch may follow the other circuit)")
    if any(sides):
        return "a dead centre: the loop closes on one side only"
    return ""


def _length_scale(desc, p) -> float:
    lengths = [abs(p[s.index]) for s in desc.params if s.kind == "length"]
    return max(lengths + [1e-3])


def _readonly(arr: np.ndarray) -> np.ndarray:
    arr.flags.writeable = False
    return arr


def _out_arrays(out) -> dict:
    """The arrays an ``out=`` argument offers, by name (q, qd, qdd, obs, frc)."""
    if out is None:
        return {}
    if isinstance(out, dict):
        return out
    if isinstance(out, ForceAnalysis):
        return {"q": out.motion.q, "qd": out.motion.qd, "qdd": out.motion.qdd, "obs": out.motion.obs, "frc": out.frc}
    if isinstance(out, Motion):
        return {"q": out.q, "qd": out.qd, "qdd": out.qdd, "obs": out.obs}
    raise TypeError(f"out must be a Motion, a ForceAnalysis or a dict of arrays, got {type(out).__name__}")


def _reusable(arr, shape: tuple, inputs) -> bool:
    """An out= array C may write: the right shape, float64, C-contiguous, writeable, no overlap with an input."""
    return (isinstance(arr, np.ndarray) and arr.shape == shape and arr.dtype == np.float64
            and arr.flags.c_contiguous and arr.flags.writeable
            and not any(np.may_share_memory(arr, x) for x in inputs))


def _cos_sin_pairs(v: np.ndarray) -> np.ndarray:
    """cos v0, sin v0, cos v1, ...: the cq/cx layout the kernels read."""
    return np.column_stack([np.cos(v), np.sin(v)]).ravel()


def shaft_angles(step_deg: float = 5.0, start_deg: float = 0.0, turns: float = 1.0) -> np.ndarray:
    """Shaft angles (rad) from ``start_deg`` over ``turns`` revolutions every ``step_deg`` (seed 000: 72 at 5°)."""
    if not step_deg > 0 or not turns > 0:
        raise ValueError("step_deg and turns must be positive")
    n = int(round(360.0 * turns / step_deg))
    return np.radians(start_deg + step_deg * np.arange(n))

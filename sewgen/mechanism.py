"""A compiled mechanism behind a thin Python API: one C call per sweep.

Names, units, sizes and defaults come from the mechanism's :class:`~sewgen.description.Description` (built once
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
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from . import abi
from .description import describe
from .errors import InputError, ParameterError
from .forces import ForceAnalysis, RunSettings
from .loads import load_matrix
from .results import Motion
from .units import UnitError, to_si

_NONNEGATIVE = {"mass", "inertia"}
_DEFAULT_MAX_ITER = 50


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
            _descriptor=getattr(lib, f"sg_{name}")(), build_info=MappingProxyType(dict(build_info or {})),
            reference=dataclasses.replace(ref, digest=digest), _defaults=MappingProxyType(defaults),
            _default_options=MappingProxyType({newton: self._new_options(ffi, desc, p, _DEFAULT_MAX_ITER, newton)
                                               for newton in (False, True)}))
        for key, value in fields.items():
            object.__setattr__(self, key, value)

    def __setattr__(self, key, value):
        raise AttributeError(f"sewgen.Mechanism is immutable (cannot set {key!r})")

    def __reduce__(self):
        from .loader import resolve

        return resolve, (self.reference,)

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
        for key, val in (params or {}).items():
            if key not in values:
                raise ParameterError(self.name, key, f"unknown; parameters are: {', '.join(values)}")
            values[key] = val
        return self._check_params(self.description, values)

    @staticmethod
    def _check_params(desc, values: dict) -> np.ndarray:
        out = np.empty(len(desc.params))
        for spec in desc.params:
            v = _si(desc.name, values[spec.name], spec.kind, spec.name)
            if spec.positive and not v > 0:
                raise ParameterError(desc.name, spec.name, f"must be positive, got {v!r} {spec.unit}")
            if spec.kind in _NONNEGATIVE and v < 0:
                raise ParameterError(desc.name, spec.name, f"must not be negative, got {v!r} {spec.unit}")
            out[spec.index] = v
        return out

    def _named_vector(self, what: str, names: list[str], defaults: list, given: dict, kind: str) -> list:
        vals = dict(zip(names, defaults))
        for key, v in given.items():
            if key not in vals:
                known = ", ".join(names) or "none"
                raise ParameterError(self.name, key, f"is not a {what}; {what}s are: {known}")
            vals[key] = v
        out = []
        for key in names:
            v = vals[key]
            if kind == "sign":
                if isinstance(v, (bool, np.bool_)) or v not in (1, -1):
                    raise ParameterError(self.name, key, f"branch must be +1 or -1, got {v!r}")
                out.append(int(v))
            else:
                out.append(_si(self.name, v, kind, key))
        return out

    def held_vector(self, held: dict | None = None) -> np.ndarray:
        """Held inputs (rad; numbers or quantity strings by name) over their defaults, as a C-ready vector."""
        if held is None:
            return self._defaults["held"].copy()
        return np.array(self._named_vector("held input", self.held_names,
                                           [i.default for i in self.description.held_inputs], held, "angle"),
                        dtype=np.float64)

    def _branch_vector(self, branch: dict) -> np.ndarray:
        return np.array(self._named_vector("branch joint", self.branch_names,
                                           [b.default for b in self.description.branches], branch, "sign"),
                        dtype=np.intc)

    def _guess_vector(self, guess: dict) -> np.ndarray:
        """Newton's start per coordinate (rad or m, or quantity strings): the declaration's unless overridden."""
        names = self.coord_names
        unknown = sorted(set(guess) - set(names))
        if unknown:
            raise ParameterError(self.name, unknown[0], f"is not a coordinate; coordinates are: {', '.join(names)}")
        return np.array([_si(self.name, guess.get(c.name, c.guess), c.kind, c.name) for c in self.description.coords],
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
        arr = np.asarray(value)
        if np.iscomplexobj(arr) or arr.dtype.kind not in "biuf":
            raise InputError(self.name, f"{what} must be real numbers, got dtype {arr.dtype}")
        arr = np.full(n, float(arr)) if arr.ndim == 0 else np.ascontiguousarray(arr, dtype=np.float64)
        if arr.ndim != 1 or arr.shape[0] != n:
            raise InputError(self.name, f"{what} must be a scalar or have shape ({n},), got {arr.shape}")
        if not np.isfinite(arr).all():
            bad = np.flatnonzero(~np.isfinite(arr))
            raise InputError(self.name, f"{what} is not finite at position {bad[0]} ({arr[bad[0]]!r})")
        return arr

    def length_scale(self, p: np.ndarray) -> float:
        """The largest length parameter (m): sets the loop-residual tolerance."""
        return _length_scale(self.description, p)

    @staticmethod
    def _new_options(ffi, desc, p: np.ndarray, max_iter: int, newton: bool):
        return ffi.new("sg_options *", {"tol": 1e-13 * _length_scale(desc, p), "max_iter": max_iter,
                                        "newton_only": 1 if newton else 0})

    # -- sweeps --------------------------------------------------------------------------------------------
    def prepare(self, phi, speed=None, accel=0.0, *, params: dict | None = None, held: dict | None = None,
                branch: dict | None = None, guess: dict | None = None, degrees: bool = False,
                newton: bool = False, max_iter: int = _DEFAULT_MAX_ITER, forces: bool = False, loads=(),
                gravity="9.80665 m/s**2", gravity_direction="-90 deg", moment_about=(0.0, 0.0), out=None) -> "Sweep":
        """Every argument of a sweep checked and converted into a :class:`Sweep`: the arrays the C runtime
        reads and writes, ready to run. :meth:`solve` and :meth:`kinetostatics` are ``prepare`` + ``run`` +
        result; call it yourself to time or repeat the bare C call on exactly those arrays (sewgen.bench).
        ``forces=True`` prepares the kinetostatic sweep (``loads``, ``gravity``, ``gravity_direction``,
        ``moment_about`` as in :meth:`kinetostatics`). ``out`` as in :meth:`solve`."""
        phi_arr = np.asarray(phi)
        if phi_arr.ndim == 0:
            phi_arr = phi_arr.reshape(1)
        if phi_arr.ndim != 1:
            raise InputError(self.name, f"shaft angles must be a 1-D array, got shape {phi_arr.shape}")
        n = phi_arr.shape[0]
        phi_v = self._series("shaft angle", phi_arr, n, "angle")
        if degrees:
            phi_v = np.radians(phi_v)
        omega = self._series("speed", self.default_speed if speed is None else speed, n, "speed")
        alpha = self._series("angular acceleration", accel, n, "angular_acceleration")
        if not isinstance(max_iter, int) or isinstance(max_iter, bool) or max_iter < 1:
            raise ParameterError(self.name, "max_iter", f"must be a positive integer, got {max_iter!r}")
        dflt = self._defaults
        if params is None:
            p = dflt["p"]
        else:
            p = self.param_vector(params)
            p.flags.writeable = False  # it becomes part of the result's run settings
        if params is None and max_iter == _DEFAULT_MAX_ITER:
            opt = self._default_options[bool(newton)]
        else:
            opt = self._new_options(self.ffi, self.description, p, max_iter, bool(newton))
        held_v = dflt["held"] if held is None else _readonly(self.held_vector(held))
        branch_v = dflt["branch"] if branch is None else self._branch_vector(branch)
        guess_v = dflt["guess"] if guess is None else self._guess_vector(guess)
        sizes = self.description.sizes
        inputs = (phi_v, omega, alpha)
        arrays = {"q": (n, sizes["nq"]), "qd": (n, sizes["nq"]), "qdd": (n, sizes["nq"]), "obs": (n, sizes["nobs"])}
        settings = None
        if forces:
            arrays["frc"] = (n, sizes["nfo"])
            g = _si(self.name, gravity, "acceleration", "gravity")
            g_dir = _si(self.name, gravity_direction, "angle", "gravity_direction")
            gx, gy = g * math.cos(g_dir), g * math.sin(g_dir)
            tiny = 1e-15 * abs(g)  # -90 deg is exactly -y, not (6e-16, -g)
            gv = _readonly(np.array([0.0 if abs(gx) < tiny else gx, 0.0 if abs(gy) < tiny else gy]))
            if not (isinstance(moment_about, (tuple, list)) and len(moment_about) == 2):
                raise ParameterError(self.name, "moment_about", f"must be a point (x, y), got {moment_about!r}")
            about = tuple(_si(self.name, v, "length", "moment_about") for v in moment_about)
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
        return Sweep(self, n, phi_v, omega, alpha, p, held_v, branch_v, guess_v, opt, outputs,
                     np.zeros(n, dtype=np.intc), settings)

    def solve(self, phi, speed=None, accel=0.0, *, params: dict | None = None, held: dict | None = None,
              branch: dict | None = None, guess: dict | None = None, degrees: bool = False,
              newton: bool = False, max_iter: int = _DEFAULT_MAX_ITER, out=None) -> Motion:
        """Positions, velocities and accelerations of every coordinate, point and body at shaft angles ``phi``.

        ``phi`` in rad (or degrees with ``degrees=True``); ``speed`` (rad/s, default the mechanism's
        default speed) and ``accel`` (rad/s²) are scalars or per-position arrays, numbers in SI or quantity
        strings ("1000 rpm"). ``params``, ``held`` (held inputs), ``branch`` (joint -> ±1) and ``guess``
        (coordinate -> Newton start) override the declaration's defaults by name. ``newton=True`` solves by
        Newton even where a closed form exists. Raises a :class:`~sewgen.errors.PositionError` subclass at
        the first shaft angle that fails.

        ``out``: a previous result (:class:`Motion` or :class:`ForceAnalysis`) or a dict of arrays (``q``, ``qd``,
        ``qdd``, ``obs``) to write into instead of fresh arrays — in a loop of equal sweeps this spares the
        allocation and the page faults of new memory, which on large sweeps cost as much as the sweep. Arrays
        of another shape (or not C-contiguous float64, or overlapping an input) are not used. The result given
        as ``out`` is consumed: its arrays now hold this sweep, so use only the returned one. Without ``out``
        every call returns new arrays and no earlier result is ever touched.
        """
        sweep = self.prepare(phi, speed, accel, params=params, held=held, branch=branch, guess=guess,
                             degrees=degrees, newton=newton, max_iter=max_iter, out=out)
        sweep.run()
        sweep.check()
        return sweep.motion()

    def kinetostatics(self, phi, speed=None, accel=0.0, *, loads=(), gravity="9.80665 m/s**2",
                      gravity_direction="-90 deg", moment_about=(0.0, 0.0), params: dict | None = None,
                      held: dict | None = None, branch: dict | None = None, guess: dict | None = None,
                      degrees: bool = False, newton: bool = False, max_iter: int = _DEFAULT_MAX_ITER,
                      out=None) -> ForceAnalysis:
        """Kinematics and every force at shaft angles ``phi``, in one C call (seed 000 §二(三)).

        Joint reactions, driving (and holding) torques, the shaking force and moment, kinetic and potential
        energy and the power of every source. ``loads`` is a sequence of :class:`~sewgen.loads.Load`;
        ``gravity`` (magnitude, 0 to switch it off) acts along ``gravity_direction`` in the mechanism's plane
        (default −90°: −y, the catalog's "down"); ``moment_about`` is the point (x, y; m or strings) the
        shaking moment is taken about. The other arguments are :meth:`solve`'s; ``out`` may also hold ``frc``
        (a previous :class:`ForceAnalysis` gives all five arrays). A singular force matrix (a toggle position)
        raises :class:`~sewgen.errors.SingularPositionError` naming the shaft angle.
        """
        sweep = self.prepare(phi, speed, accel, params=params, held=held, branch=branch, guess=guess,
                             degrees=degrees, newton=newton, max_iter=max_iter, forces=True, loads=loads,
                             gravity=gravity, gravity_direction=gravity_direction, moment_about=moment_about,
                             out=out)
        sweep.run()
        sweep.check()
        return sweep.analysis()

    # -- single-position kernels (checks and inspection) -----------------------------------------------------
    def _ptr(self, ctype: str, arr: np.ndarray):
        return _ptr(self.ffi, ctype, arr)

    def constants(self, params: dict | None = None) -> np.ndarray:
        """The parameter-only constants the kernels read (sg_<name>_constants)."""
        return self._constants(self.param_vector(params))

    def _constants(self, p: np.ndarray) -> np.ndarray:
        c = np.zeros(max(self.description.sizes["nc"], 1))
        getattr(self.lib, f"sg_{self.name}_constants")(self._ptr("double *", np.ascontiguousarray(p, dtype=float)),
                                                         self._ptr("double *", c))
        return c

    def residual(self, q, phi: float, params: dict | None = None, held: dict | None = None):
        """Φ(q, x) and Φ_q at one position (for checks): arrays of shape (nq,) and (nq, nq)."""
        nq = len(self.description.coords)
        qv = np.ascontiguousarray(q, dtype=np.float64).reshape(nq)
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
        p = params if isinstance(params, np.ndarray) else self.param_vector(params)
        hv = held if isinstance(held, np.ndarray) else self.held_vector(held)
        sizes = self.description.sizes
        nf = sizes["nf"]
        q = np.ascontiguousarray(motion.q[index], dtype=np.float64)
        x = np.concatenate([[float(motion.phi[index])], hv]).astype(np.float64)
        obs = np.ascontiguousarray(motion.obs[index], dtype=np.float64)
        ld = np.zeros(max(sizes["nload"], 1)) if load_row is None else np.ascontiguousarray(load_row, dtype=np.float64)
        A, b = np.zeros((nf, nf)), np.zeros(nf)
        d = self._ptr
        getattr(self.lib, f"sg_{self.name}_force_matrix")(
            d("double *", q), d("double *", _cos_sin_pairs(q)), d("double *", x), d("double *", _cos_sin_pairs(x)),
            d("double *", self._constants(p)), d("double *", obs),
            d("double *", np.ascontiguousarray(gravity, dtype=np.float64)), d("double *", ld),
            d("double *", A), d("double *", b))
        return A, b


class Sweep:
    """One sweep of a mechanism, checked and converted: the C-ready arrays the runtime reads (``phi``, ``omega``,
    ``alpha``, ``params``, ``held``, ``branch``, ``guess``, ``options``; with forces ``settings.gravity`` and
    ``settings.loads``) and writes (``q``, ``qd``, ``qdd``, ``obs``, ``frc``, ``status``).

    Made by :meth:`Mechanism.prepare`. :meth:`run` calls C once; :meth:`bind` gives that call as a bare
    zero-argument function (its pointers made once), which is what a benchmark times. Running again overwrites
    this sweep's own output arrays, so a Sweep belongs to one thread; the results it makes share its arrays.
    """

    def __init__(self, mechanism: Mechanism, n, phi, omega, alpha, params, held, branch, guess, options,
                 outputs: dict, status, settings: RunSettings | None):
        self.mechanism, self.n = mechanism, n
        self.phi, self.omega, self.alpha = phi, omega, alpha
        self.params, self.held, self.branch, self.guess, self.options = params, held, branch, guess, options
        self.q, self.qd, self.qdd, self.obs = outputs["q"], outputs["qd"], outputs["qdd"], outputs["obs"]
        self.frc = outputs.get("frc")
        self.status = status
        self.settings = settings

    @property
    def forces(self) -> bool:
        return self.settings is not None

    def bind(self):
        """The C call of this sweep as a function of no arguments; it returns how many positions failed."""
        m, ffi = self.mechanism, self.mechanism.ffi
        d = (lambda ctype, arr: _ptr(ffi, ctype, arr))
        head = (m._descriptor, self.n, d("double *", self.phi), d("double *", self.omega), d("double *", self.alpha),
                d("double *", self.held), d("double *", self.params), d("int *", self.branch),
                d("double *", self.guess), self.options)
        tail = (d("double *", self.q), d("double *", self.qd), d("double *", self.qdd), d("double *", self.obs))
        if self.forces:
            s = self.settings
            loads = ffi.NULL if s.loads is None else d("double *", s.loads)
            args = head + (d("double *", s.gravity), loads) + tail + (d("double *", self.frc),
                                                                      d("int *", self.status))
            fn = m.lib.sg_sweep_forces
        else:
            args, fn = head + tail + (d("int *", self.status),), m.lib.sg_sweep

        def call() -> int:
            return fn(*args)

        return call

    def run(self) -> int:
        """Run the sweep in C (the GIL released), then make every angle continuous over the sweep; returns the
        number of positions whose status is not SG_OK."""
        failed = self.bind()()
        continuous_angles(self.mechanism.description, self.q, self.obs)
        return failed

    def check(self) -> None:
        """Raise the typed error of the first failing position (naming its shaft angle), if any failed."""
        status = self.status
        bad = np.flatnonzero(status)
        if not bad.size:
            return
        i = int(bad[0])
        code = int(status[i])
        cls = abi.error_for(code)
        name = self.mechanism.name
        if cls is None:  # SG_NAN_INPUT / SG_BAD_ARGUMENT: Python checks first, so this is a bug
            raise InputError(name, f"runtime refused the sweep ({abi.status_name(code)}) at position {i}")
        same = bad[status[bad] == code]
        raise cls(name, float(self.phi[i]), i, int(same.size), float(self.phi[same[-1]]))

    def motion(self) -> Motion:
        return Motion(self.mechanism, self.phi, self.omega, self.alpha, self.q, self.qd, self.qdd, self.obs)

    def analysis(self) -> ForceAnalysis:
        if not self.forces:
            raise ValueError("this sweep was prepared without forces (prepare(..., forces=True))")
        return ForceAnalysis(self.mechanism, self.motion(), self.frc, self.settings)


def continuous_angles(desc, q: np.ndarray, obs: np.ndarray) -> None:
    """Every angle result (angle coordinates, body angles) continuous along the sweep, in place: no 2π jumps
    (a closed-form dyad's atan2 wraps at ±180°), the first position in (−π, π] (issue 12, item 5). Only angles
    change, by whole turns, so every sine and cosine — and every result computed from them — stays the same."""
    qa, oa = desc.angle_columns
    for arr, cols in ((q, qa), (obs, oa)):
        if cols and arr.ndim == 2 and len(arr):
            block = np.unwrap(arr[:, cols], axis=0)
            block -= 2 * np.pi * np.ceil((block[:1] - np.pi) / (2 * np.pi))
            arr[:, cols] = block


def _si(mechanism: str, value, kind: str, name: str) -> float:
    """to_si with its error retyped as a ParameterError naming the mechanism and ``name``."""
    try:
        return to_si(value, kind, name)
    except UnitError as exc:
        raise ParameterError(mechanism, name, exc.problem) from None


def _length_scale(desc, p) -> float:
    lengths = [abs(p[s.index]) for s in desc.params if s.kind == "length"]
    return max(lengths + [1e-3])


def _readonly(arr: np.ndarray) -> np.ndarray:
    arr.flags.writeable = False
    return arr


def _ptr(ffi, ctype: str, arr: np.ndarray):
    """``arr`` as a C array argument ("double *" -> double[]). The typed from_buffer keeps ``arr`` alive for as
    long as the cdata lives (a cast pointer would not: a temporary array could be freed before the call)."""
    return ffi.from_buffer(ctype.replace(" *", "[]"), arr) if arr.size else ffi.NULL


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

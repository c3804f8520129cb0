"""A compiled mechanism behind a thin Python API: parameters from the manifest, one C call per sweep.

Names, units, sizes and defaults come from the manifest compiled into the module (derive/emit.py); nothing
here repeats them by hand. Inputs are checked and converted before C sees them; a failing position raises
the typed error of its status, naming the mechanism and the first failing shaft angle.
"""
from __future__ import annotations

import json
import math
import sys

import numpy as np

from .units import UnitError, to_si

from . import abi
from .description import describe
from .errors import InputError, ParameterError
from .forces import ForceAnalysis
from .loads import load_matrix
from .results import Motion

_NONNEGATIVE = {"mass", "inertia"}


class Mechanism:
    """One mechanism of a compiled module (the catalog's or a user's)."""

    def __init__(self, ffi, lib, name: str, build_info: dict | None = None):
        self.ffi, self.lib, self.name = ffi, lib, name
        self.manifest = json.loads(ffi.string(getattr(lib, f"sg_{name}_manifest")()).decode())
        self.description = describe(self.manifest)
        self._descriptor = getattr(lib, f"sg_{name}")()
        self.build_info = build_info or {}
        man = self.manifest
        self.param_names = [p["name"] for p in man["params"]]
        self.coord_names = [c["name"] for c in man["coords"]]
        self.held_names = [i["name"] for i in man["inputs"][1:]]
        self.branch_names = [b["joint"] for b in man["branches"]]
        self.point_names = [p["name"] for p in man["points"]]
        self.body_names = [b["name"] for b in man["bodies"]]
        self.closed_form = bool(man["closed_form"])
        self.default_speed = float(man["default_speed"])
        nf = man["sizes"]["nf"]
        self.layout = {  # name -> place in the result arrays, shared by every Motion and ForceAnalysis
            "points": {p["name"]: p["offset"] for p in man["points"]},
            "bodies": {b["name"]: b["offset"] for b in man["bodies"]},
            "coords": {c["name"]: (i, c["unit"]) for i, c in enumerate(man["coords"])},
            "reactions": {r["name"]: r for r in man["reactions"]},
            "force_outputs": {o["name"]: nf + k for k, o in enumerate(man["force_outputs"])},
            "inputs": [i["name"] for i in man["inputs"]],
        }
        self._defaults = None
        self._options: dict = {}
        self._outputs: dict = {}

    def __repr__(self) -> str:
        return f"<sewgen.Mechanism {self.name}: {len(self.coord_names)} coordinates, {len(self.param_names)} parameters>"

    @property
    def doc(self) -> str:
        return self.manifest["doc"]

    def defaults(self) -> dict[str, float]:
        """Every parameter's default, SI."""
        return {p["name"]: p["default"] for p in self.manifest["params"]}

    def describe_params(self) -> list[dict]:
        """Name, kind, SI unit, default, declared unit and docstring of every parameter."""
        return [dict(p) for p in self.manifest["params"]]

    # -- input conversion ----------------------------------------------------------------------------------
    def param_vector(self, params: dict | None = None) -> np.ndarray:
        """Defaults overridden by ``params`` (SI numbers or quantity strings), checked, as a C-ready vector."""
        values = self.defaults()
        for key, val in (params or {}).items():
            if key not in values:
                raise ParameterError(self.name, key, f"unknown; parameters are: {', '.join(values)}")
            values[key] = val
        out = np.empty(len(self.param_names))
        for i, spec in enumerate(self.manifest["params"]):
            name, kind = spec["name"], spec["kind"]
            v = self._si(values[name], kind, name)
            if spec["positive"] and not v > 0:
                raise ParameterError(self.name, name, f"must be positive, got {v!r} {spec['unit']}")
            if kind in _NONNEGATIVE and v < 0:
                raise ParameterError(self.name, name, f"must not be negative, got {v!r} {spec['unit']}")
            out[i] = v
        return out

    def _named_vector(self, what: str, names: list[str], defaults: list, given: dict | None, kind: str):
        vals = dict(zip(names, defaults))
        for key, v in (given or {}).items():
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
                out.append(self._si(v, kind, key))
        return out

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

    # -- kernels -------------------------------------------------------------------------------------------
    def _ptr(self, ctype: str, arr: np.ndarray):
        """``arr`` as a C array argument ("double *" -> double[]). The typed from_buffer keeps ``arr`` alive for
        as long as the cdata lives (a cast pointer would not: a temporary array could be freed before the call)."""
        return self.ffi.from_buffer(ctype.replace(" *", "[]"), arr) if arr.size else self.ffi.NULL

    def constants(self, params: dict | None = None) -> np.ndarray:
        """The parameter-only constants the kernels read (sg_<name>_constants)."""
        return self._constants(self.param_vector(params))

    def _constants(self, p: np.ndarray) -> np.ndarray:
        c = np.zeros(max(self.manifest["sizes"]["nc"], 1))
        getattr(self.lib, f"sg_{self.name}_constants")(self._ptr("double *", np.ascontiguousarray(p, dtype=float)),
                                                         self._ptr("double *", c))
        return c

    def residual(self, q, phi: float, params: dict | None = None, held: dict | None = None):
        """Φ(q, x) and Φ_q at one position (for checks): arrays of shape (nq,) and (nq, nq)."""
        nq = len(self.coord_names)
        qv = np.ascontiguousarray(q, dtype=np.float64).reshape(nq)
        x = np.array([float(phi)] + self._held(held), dtype=np.float64)
        cq, cx = _cos_sin_pairs(qv), _cos_sin_pairs(x)
        r, jac = np.zeros(nq), np.zeros((nq, nq))
        d = self._ptr
        getattr(self.lib, f"sg_{self.name}_residual")(
            d("double *", qv), d("double *", cq), d("double *", x), d("double *", cx),
            d("double *", self.constants(params)), d("double *", r), d("double *", jac))
        return r, jac

    def _held(self, held):
        defaults = [i["default"] for i in self.manifest["inputs"][1:]]
        return self._named_vector("held input", self.held_names, defaults, held, "angle")

    def _branches(self, branch):
        return self._named_vector("branch joint", self.branch_names,
                                  [b["default"] for b in self.manifest["branches"]], branch, "sign")

    def _guess(self, guess):
        """Newton's start per coordinate (rad or m, or quantity strings): the manifest's unless overridden."""
        given = dict(guess or {})
        unknown = sorted(set(given) - set(self.coord_names))
        if unknown:
            raise ParameterError(self.name, unknown[0],
                                 f"is not a coordinate; coordinates are: {', '.join(self.coord_names)}")
        return [self._si(given.get(c["name"], c["guess"]), "angle" if c["unit"] == "rad" else "length", c["name"])
                for c in self.manifest["coords"]]

    def _si(self, value, kind: str, name: str) -> float:
        """to_si with its error retyped as a ParameterError naming this mechanism and ``name``."""
        try:
            return to_si(value, kind, name)
        except UnitError as exc:
            raise ParameterError(self.name, name, exc.problem) from None

    def length_scale(self, p: np.ndarray) -> float:
        """The largest length parameter (m): sets the loop-residual tolerance."""
        lengths = [abs(v) for v, s in zip(p, self.manifest["params"]) if s["kind"] == "length"]
        return max(lengths + [1e-3])

    def _sweep_inputs(self, phi, speed, accel, params, held, branch, guess, degrees, newton, max_iter) -> dict:
        """Every sweep argument checked and converted to the C-ready arrays sg_sweep takes."""
        phi_arr = np.asarray(phi)
        if phi_arr.ndim == 0:
            phi_arr = phi_arr.reshape(1)
        n = phi_arr.shape[0] if phi_arr.ndim == 1 else -1
        if n < 0:
            raise InputError(self.name, f"shaft angles must be a 1-D array, got shape {phi_arr.shape}")
        phi_v = self._series("shaft angle", phi_arr, n, "angle")
        if degrees:
            phi_v = np.radians(phi_v)
        omega = self._series("speed", self.default_speed if speed is None else speed, n, "speed")
        alpha = self._series("angular acceleration", accel, n, "angular_acceleration")
        if not isinstance(max_iter, int) or isinstance(max_iter, bool) or max_iter < 1:
            raise ParameterError(self.name, "max_iter", f"must be a positive integer, got {max_iter!r}")
        if self._defaults is None:  # the conversions of the defaults, once (read-only: C only reads them)
            self._defaults = {"p": self.param_vector(None), "held": np.array(self._held(None), dtype=np.float64),
                              "branch": np.array(self._branches(None), dtype=np.intc),
                              "guess": np.array(self._guess(None), dtype=np.float64)}
            for arr in self._defaults.values():
                arr.flags.writeable = False
        dflt = self._defaults
        p = dflt["p"] if params is None else self.param_vector(params)
        nq, nobs = len(self.coord_names), len(self.manifest["observables"])
        key = (max_iter, bool(newton))
        opt = self._options.get(key) if params is None else None
        if opt is None:  # Newton's options; those of the default parameters are made once
            opt = self.ffi.new("sg_options *", {"tol": 1e-13 * self.length_scale(p), "max_iter": max_iter,
                                               "newton_only": 1 if newton else 0})
            if params is None:
                self._options[key] = opt
        return {"n": n, "phi": phi_v, "omega": omega, "alpha": alpha, "p": p,
                "held": dflt["held"] if held is None else np.array(self._held(held), dtype=np.float64),
                "branch": dflt["branch"] if branch is None else np.array(self._branches(branch), dtype=np.intc),
                "guess": dflt["guess"] if guess is None else np.array(self._guess(guess), dtype=np.float64),
                "opt": opt,
                "q": self._output("q", (n, nq)), "qd": self._output("qd", (n, nq)),  # C writes every row
                "qdd": self._output("qdd", (n, nq)), "obs": self._output("obs", (n, nobs)),
                "status": np.zeros(n, dtype=np.intc)}

    def _output(self, name: str, shape: tuple) -> np.ndarray:
        """An output array for C to fill: the previous call's, if nothing outside this cache still holds it
        (no result, view or copy of it is alive), else a new one. Reusing the memory spares the page faults
        of fresh pages, which cost as much as the sweep itself on large sweeps."""
        arr = self._outputs.get(name)
        if arr is not None and arr.shape == shape and sys.getrefcount(arr) == 3:  # the dict, `arr`, the argument
            return arr
        arr = np.empty(shape)
        self._outputs[name] = arr
        return arr

    def _motion(self, a: dict) -> Motion:
        return Motion(self, a["phi"], a["omega"], a["alpha"], a["q"], a["qd"], a["qdd"], a["obs"])

    def solve(self, phi, speed=None, accel=0.0, *, params: dict | None = None, held: dict | None = None,
              branch: dict | None = None, guess: dict | None = None, degrees: bool = False,
              newton: bool = False, max_iter: int = 50) -> Motion:
        """Positions, velocities and accelerations of every coordinate, point and body at shaft angles ``phi``.

        ``phi`` in rad (or degrees with ``degrees=True``); ``speed`` (rad/s, default the mechanism's
        default speed) and ``accel`` (rad/s²) are scalars or per-position arrays, numbers in SI or quantity
        strings ("1000 rpm"). ``params``, ``held`` (held inputs), ``branch`` (joint -> ±1) and ``guess``
        (coordinate -> Newton start) override the manifest's defaults by name. ``newton=True`` solves by
        Newton even where a closed form exists. Raises a :class:`~sewgen.errors.PositionError` subclass at
        the first shaft angle that fails.
        """
        a = self._sweep_inputs(phi, speed, accel, params, held, branch, guess, degrees, newton, max_iter)
        d = self._ptr
        self.lib.sg_sweep(self._descriptor, a["n"], d("double *", a["phi"]), d("double *", a["omega"]),
                          d("double *", a["alpha"]), d("double *", a["held"]), d("double *", a["p"]),
                          d("int *", a["branch"]), d("double *", a["guess"]), a["opt"], d("double *", a["q"]),
                          d("double *", a["qd"]), d("double *", a["qdd"]), d("double *", a["obs"]),
                          d("int *", a["status"]))
        self._raise_for(a["status"], a["phi"])
        return self._motion(a)

    def kinetostatics(self, phi, speed=None, accel=0.0, *, loads=(), gravity="9.80665 m/s**2",
                      gravity_direction="-90 deg", moment_about=(0.0, 0.0), params: dict | None = None,
                      held: dict | None = None, branch: dict | None = None, guess: dict | None = None,
                      degrees: bool = False, newton: bool = False, max_iter: int = 50) -> ForceAnalysis:
        """Kinematics and every force at shaft angles ``phi``, in one C call (seed 000 §二(三)).

        Joint reactions, driving (and holding) torques, the shaking force and moment, kinetic and potential
        energy and the power of every source. ``loads`` is a sequence of :class:`~sewgen.loads.Load`;
        ``gravity`` (magnitude, 0 to switch it off) acts along ``gravity_direction`` in the mechanism's plane
        (default −90°: −y, the catalog's "down"); ``moment_about`` is the point (x, y; m or strings) the
        shaking moment is taken about. The other arguments are :meth:`solve`'s. A singular force matrix (a
        toggle position) raises :class:`~sewgen.errors.SingularPositionError` naming the shaft angle.
        """
        a = self._sweep_inputs(phi, speed, accel, params, held, branch, guess, degrees, newton, max_iter)
        g = self._si(gravity, "acceleration", "gravity")
        g_dir = self._si(gravity_direction, "angle", "gravity_direction")
        gx, gy = g * math.cos(g_dir), g * math.sin(g_dir)
        tiny = 1e-15 * abs(g)  # -90 deg is exactly -y, not (6e-16, -g)
        gv = np.array([0.0 if abs(gx) < tiny else gx, 0.0 if abs(gy) < tiny else gy])
        if not (isinstance(moment_about, (tuple, list)) and len(moment_about) == 2):
            raise ParameterError(self.name, "moment_about", f"must be a point (x, y), got {moment_about!r}")
        about = tuple(self._si(v, "length", "moment_about") for v in moment_about)
        ld, placed = load_matrix(self, loads, a["phi"], degrees)
        frc = self._output("frc", (a["n"], self.manifest["sizes"]["nfo"]))
        d = self._ptr
        self.lib.sg_sweep_forces(
            self._descriptor, a["n"], d("double *", a["phi"]), d("double *", a["omega"]),
            d("double *", a["alpha"]), d("double *", a["held"]), d("double *", a["p"]), d("int *", a["branch"]),
            d("double *", a["guess"]), a["opt"], d("double *", gv),
            self.ffi.NULL if ld is None else d("double *", ld), d("double *", a["q"]), d("double *", a["qd"]),
            d("double *", a["qdd"]), d("double *", a["obs"]), d("double *", frc), d("int *", a["status"]))
        self._raise_for(a["status"], a["phi"])
        run = {"p": a["p"], "held": a["held"], "loads": ld}
        return ForceAnalysis(self, self._motion(a), frc, placed, gv, about, run)

    def force_matrix(self, motion: Motion, index: int = 0, *, params: dict | None = None,
                     held: dict | None = None, gravity=(0.0, -9.80665), load_row=None):
        """A and b of A f = b at position ``index`` of a solved ``motion`` (for inspection and checks).

        ``params`` and ``held`` must be those of the run; ``gravity`` is the vector (gx, gy) in m/s²;
        ``load_row`` the load slots (manifest "loads") or zeros. :meth:`ForceAnalysis.force_matrix` reuses a
        run's own settings. Rows: the manifest's "force_rows"; columns: the reactions' columns in order.
        """
        return self._force_matrix(motion, index, self.param_vector(params), np.array(self._held(held)),
                                  np.asarray(gravity, dtype=float), load_row)

    def _force_matrix(self, motion: Motion, index: int, p: np.ndarray, held: np.ndarray, gv: np.ndarray, load_row):
        nf = self.manifest["sizes"]["nf"]
        q = np.ascontiguousarray(motion.q[index], dtype=np.float64)
        x = np.concatenate([[float(motion.phi[index])], held]).astype(np.float64)
        obs = np.ascontiguousarray(motion.obs[index], dtype=np.float64)
        ld = np.zeros(max(self.manifest["sizes"]["nload"], 1)) if load_row is None else \
            np.ascontiguousarray(load_row, dtype=np.float64)
        A, b = np.zeros((nf, nf)), np.zeros(nf)
        d = self._ptr
        getattr(self.lib, f"sg_{self.name}_force_matrix")(
            d("double *", q), d("double *", _cos_sin_pairs(q)), d("double *", x), d("double *", _cos_sin_pairs(x)),
            d("double *", self._constants(p)),
            d("double *", obs), d("double *", np.ascontiguousarray(gv, dtype=np.float64)), d("double *", ld),
            d("double *", A), d("double *", b))
        return A, b

    def _raise_for(self, status: np.ndarray, phi: np.ndarray) -> None:
        bad = np.flatnonzero(status)
        if not bad.size:
            return
        i = int(bad[0])
        code = int(status[i])
        cls = abi.error_for(code)
        if cls is None:  # SG_NAN_INPUT / SG_BAD_ARGUMENT: Python checks first, so this is a bug
            raise InputError(self.name, f"runtime refused the sweep ({abi.status_name(code)}) at position {i}")
        same = bad[status[bad] == code]
        raise cls(self.name, float(phi[i]), i, int(same.size), float(phi[same[-1]]))


def _cos_sin_pairs(v: np.ndarray) -> np.ndarray:
    """cos v0, sin v0, cos v1, ...: the cq/cx layout the kernels read."""
    return np.column_stack([np.cos(v), np.sin(v)]).ravel()


def shaft_angles(step_deg: float = 5.0, start_deg: float = 0.0, turns: float = 1.0) -> np.ndarray:
    """Shaft angles (rad) from ``start_deg`` over ``turns`` revolutions every ``step_deg`` (seed 000: 72 at 5°)."""
    if not step_deg > 0 or not turns > 0:
        raise ValueError("step_deg and turns must be positive")
    n = int(round(360.0 * turns / step_deg))
    return np.radians(start_deg + step_deg * np.arange(n))

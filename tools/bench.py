"""Benchmarks: compiled sweeps against a SymPy-lambdify + SciPy baseline of the same equations.

    python tools/bench.py                      # every catalog mechanism, table on stdout
    python tools/bench.py --json               # the same as a JSON list
    python tools/bench.py --mechanism take_up  # one mechanism (repeatable; "catalog" = the derive line)

Each row is one (mechanism, kernel) entry of the registry below. The "kinematics" kernel times
``Mechanism.solve`` over one sweep of N shaft angles (positions, velocities, accelerations of every
coordinate, point and body; the thin Python API included), best of several repeats after a warm-up, and
the same sweep through ``sg_sweep`` alone (raw C). The baseline evaluates the same Kinematics expressions
(derive.kinematics) through ``sympy.lambdify(modules="numpy")``, one position at a time: scipy.optimize.root
on the loop closure from the previous position's solution, numpy.linalg.solve for q' and q'', then every
observable. Its results are checked against the compiled sweep at the same angles, so the ratio compares
like with like. The "derive" line times derive.emit.generate for the whole catalog, in-process.

The "kinetostatics" kernel times ``Mechanism.kinetostatics`` (kinematics plus every force: joint reactions,
driving torques, the frame's force and moment on the parts, energies and powers; default gravity, no loads) over
the same sweep, and the same call through ``sg_sweep`` alone (raw C, forces on). Its baseline is the kinematics baseline
above plus, per position, the force balance A f = b of derive.kinetostatics solved by numpy.linalg.solve.
A and b are lambdified as derive writes them, with the placeholder symbols of the kinematic observables,
and are fed the observables the kinematics baseline has just evaluated at that position: that is how the
compiled kernel builds them too (from the motion kernel's observables), so these are the same matrices,
not a re-expansion of the kinematics inside A and b (``Kinetostatics.explicit``). Gravity (0, -9.80665)
m/s², loads zero. The baseline solves the unknowns f only (joint reactions and drive torques, nf per
position); the compiled sweep also derives the other force outputs from f. q, q', q'', the observables and
f are checked against the compiled sweep at the same angles.

Extension point: add a kernel that runs for every catalog mechanism with :func:`register_kernel`, or a
single entry such as a whole machine ("jb1-3") with :func:`register_entry`. Either function returns
``(positions_per_s, baseline_positions_per_s or None, extra dict)``; put ``extra["agree"] = False`` in when
a cross-check fails (the run then exits with status 1).
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

import sewgen
from sewgen.engine.mechanism import continuous_angles

# -- configuration and registry -----------------------------------------------------------------------------


@dataclass
class Config:
    positions: int = 3600  # shaft angles in the timed sweep (one revolution)
    baseline_positions: int = 200  # positions of the lambdify + scipy baseline
    repeats: int = 7  # timed repeats; the best counts
    baseline_repeats: int = 5
    min_time: float = 0.05  # s: one timed repeat loops the call until it lasts at least this long
    # Agreement of baseline and compiled results, relative to each column's scale. scipy's root ("hybr",
    # default xtol 1.49e-8) leaves relative errors up to ~1e-8 in the baseline itself (hook_drive: 9e-9).
    rtol: float = 1e-7
    study_designs: int = 100_000  # designs of the "study" entries (the JB1-3 feed group's tolerance study)
    baseline_angles: str = "spread"  # "spread": every k-th sweep angle; "contiguous": the first ones

    def sweep_angles(self) -> np.ndarray:
        """One revolution in ``positions`` equal steps (0.1° for the default 3600), rad."""
        return 2.0 * np.pi * np.arange(self.positions) / self.positions

    def baseline_rows(self) -> np.ndarray:
        """Indices into the sweep of the angles the baseline solves (a subset of the timed sweep)."""
        m = min(self.baseline_positions, self.positions)
        if self.baseline_angles == "contiguous":
            return np.arange(m)
        return np.arange(m) * (self.positions // m)


Result = tuple  # (positions_per_s, baseline_positions_per_s | None, extra: dict)
KernelFn = Callable[[str, Config], Result]  # (catalog mechanism name, config) -> Result


@dataclass
class Entry:
    mechanism: str
    kernel: str
    run: Callable[[Config], Result]


class NotApplicable(Exception):
    """Raise from a kernel function when the kernel does not apply to that mechanism (row skipped)."""


#: Kernels timed for every catalog mechanism: name -> function(mechanism name, config).
KERNELS: dict[str, KernelFn] = {}
#: Entries that are not "every catalog mechanism" (a whole machine such as "jb1-3", user mechanisms).
EXTRA_ENTRIES: list[Entry] = []


def register_kernel(name: str):
    """Decorator: time ``fn(mechanism_name, config)`` for every catalog mechanism as kernel ``name``."""
    def deco(fn: KernelFn) -> KernelFn:
        KERNELS[name] = fn
        return fn
    return deco


def register_entry(mechanism: str, kernel: str, fn: Callable[[Config], Result]) -> None:
    """One extra row: ``fn(config)`` timed as (mechanism, kernel)."""
    EXTRA_ENTRIES.append(Entry(mechanism, kernel, fn))


def entries(selected: list[str] | None = None) -> list[Entry]:
    """Every registered row (catalog × KERNELS, then EXTRA_ENTRIES), restricted to ``selected`` names."""
    out = [Entry(name, kernel, (lambda cfg, f=fn, n=name: f(n, cfg)))
           for name in sewgen.catalog() for kernel, fn in KERNELS.items()]
    out += EXTRA_ENTRIES
    return [e for e in out if selected is None or e.mechanism in selected]


# -- timing -------------------------------------------------------------------------------------------------


def best_time(fn: Callable[[], object], repeats: int, min_time: float) -> float:
    """Seconds per call of ``fn``: warm up, loop enough calls that a repeat lasts ``min_time``, best repeat."""
    fn()
    loops = 1
    while True:
        t0 = time.perf_counter()
        for _ in range(loops):
            fn()
        dt = time.perf_counter() - t0
        if dt >= min_time:
            break
        loops = max(loops * 2, int(loops * min_time / max(dt, 1e-9) * 1.2))
    best = dt / loops
    for _ in range(repeats - 1):
        t0 = time.perf_counter()
        for _ in range(loops):
            fn()
        best = min(best, (time.perf_counter() - t0) / loops)
    return best


# -- the compiled sweep -------------------------------------------------------------------------------------


def raw_sweep(m: sewgen.Mechanism, phi: np.ndarray, loop: str = "auto", **forces):
    """The bare C call of ``m.solve(phi)`` (or, with ``forces=True`` and kinetostatics()'s force arguments, of
    ``m.kinetostatics(phi, ...)``) on its own arrays: :meth:`Mechanism.prepare` converts every argument exactly
    as solve() does, :meth:`Sweep.bind` makes the pointers once; ``loop``: :meth:`Sweep.use_loop`'s (the SIMD
    loop where it runs by default). Returns (call, sweep): time ``call``, read the results (``sweep.q``,
    ``.obs``, ``.frc``, ``.status``) from ``sweep``."""
    sweep = m.prepare(phi, layout="arrays", **forces).use_loop(loop)  # sg_sweep on separate arrays
    return sweep.bind(), sweep


def loop_rates(m: sewgen.Mechanism, phi: np.ndarray, cfg, **forces) -> dict:
    """Positions/s of the bare C call through the scalar inlined loop and the generic loop, in the same run as
    the default (SIMD where it runs) one, and the SIMD width: the extra fields of a kernel's row."""
    out = {"simd_width": m.simd_width}
    for loop in ("scalar", "generic"):
        call, _ = raw_sweep(m, phi, loop, **forces)
        out[f"raw_c_{loop}_loop_positions_per_s"] = len(phi) / best_time(call, cfg.repeats, cfg.min_time)
    return out


# -- the lambdify + scipy baseline --------------------------------------------------------------------------


class Baseline:
    """The Kinematics expressions of one catalog mechanism through sympy.lambdify, solved per position.

    With ``forces=True`` also the force balance A f = b of derive.kinetostatics, lambdified in the observable
    placeholders (see the module docstring); :meth:`run` then solves it at every position when given gravity.
    """

    def __init__(self, name: str, forces: bool = False):
        import sympy as sp

        from sewgen.derive.catalog import declare
        from sewgen.derive.kinematics import Kinematics

        t0 = time.perf_counter()
        kin = Kinematics(declare(name))
        t1 = time.perf_counter()

        def lam(args, expr):
            return sp.lambdify(args, expr, modules="numpy")

        q, qd, qdd, x, xd, xdd, p = kin.q, kin.qd, kin.qdd, kin.x, kin.xd, kin.xdd, kin.p
        ka = [sp.Symbol(f"ka_{k}", real=True) for k in range(4 * len(kin.cams))]  # active cam arcs
        self.closure = lam([q, x, p, ka], kin.closure)
        self.jac_q = lam([q, x, p, ka], kin.jac_q)
        self.vel_rhs = lam([q, x, xd, p, ka], kin.vel_rhs)
        self.gamma = lam([q, qd, x, xd, xdd, p, ka], kin.gamma)
        self.observables = lam([q, qd, qdd, x, xd, xdd, p, ka], [o.expr for o in kin.observables])
        self.cam_normals = [lam([q, x, p], list(c.normal)) for c in kin.cams]
        self.cam_arcs = [[lam([p], [sp.cos(a.normal_from), sp.sin(a.normal_from), sp.cos(a.normal_to),
                                    sp.sin(a.normal_to), a.center_u, a.center_v, a.radius])
                          for a in c.joint.arcs] for c in kin.cams]
        self.kin = kin
        self.kst = None
        if forces:
            from sewgen.derive.kinetostatics import Kinetostatics

            kst = Kinetostatics(kin)
            fargs = [q, x, p, kst.obs, kst.gravity, kst.loads, ka]
            # b without friction: the catalog declares it with coefficient 0 (the kernel skips it then)
            frictionless = kst.b.xreplace({fr: 0 for _r, fr, _u in kst.frictions})
            self.force_A, self.force_b = lam(fargs, kst.A), lam(fargs, frictionless)
            self.kst = kst
        self.derive_s, self.lambdify_s = t1 - t0, time.perf_counter() - t1

    def arcs(self, q, x, p) -> list:
        """ka: centre, radius of each cam's active arc (the sector holding the face normal), then the indices."""
        n = len(self.cam_normals)
        ka = [0.0] * (4 * n)
        for j, (normal, arcs) in enumerate(zip(self.cam_normals, self.cam_arcs)):
            e0, e1 = normal(q, x, p)
            for k, arc in enumerate(arcs):
                ca, sa, cb, sb, u, v, r = arc(p)
                if (ca * e1 - sa * e0 >= 0.0 and e0 * sb - e1 * cb > 0.0) or k == len(arcs) - 1:
                    ka[3 * j: 3 * j + 3], ka[3 * n + j] = [u, v, r], float(k)
                    break
        return ka

    def run(self, phi, omega, accel, held, p, q_start, gravity=None):
        """Positions, velocities, accelerations and observables at each angle of ``phi`` (sequentially).

        Returns (Q, QD, QDD, OBS, root evaluations per position), and, when ``gravity`` (gx, gy) is given
        (needs ``forces=True``), the force unknowns F (n × nf; loads zero) as a sixth element.
        """
        from scipy.optimize import root

        n, nq, nobs = len(phi), len(self.kin.q), len(self.kin.observables)
        forces = gravity is not None
        if forces:
            if self.kst is None:
                raise RuntimeError("baseline: built without forces=True")
            F = np.zeros((n, len(self.kst.f)))
            force_A, force_b, loads = self.force_A, self.force_b, [0.0] * len(self.kst.loads)
            gravity = list(gravity)
        Q, QD, QDD, OBS = np.zeros((n, nq)), np.zeros((n, nq)), np.zeros((n, nq)), np.zeros((n, nobs))
        closure, jac_q, vel_rhs, gamma, observables = (self.closure, self.jac_q, self.vel_rhs, self.gamma,
                                                        self.observables)
        held = list(held)
        xd = [omega] + [0.0] * len(held)
        xdd = [accel] + [0.0] * len(held)
        q = np.array(q_start, dtype=np.float64)
        nfev = 0
        for i in range(n):
            x = [phi[i]] + held
            arcs = self.arcs
            sol = root(lambda qq: np.asarray(closure(qq, x, p, arcs(qq, x, p)), dtype=np.float64), q,
                       jac=lambda qq: np.asarray(jac_q(qq, x, p, arcs(qq, x, p)), dtype=np.float64))
            if not sol.success:
                raise RuntimeError(f"baseline: scipy.optimize.root failed at position {i}: {sol.message}")
            nfev += sol.nfev
            q = sol.x
            ka = arcs(q, x, p)
            J = np.asarray(jac_q(q, x, p, ka), dtype=np.float64)
            qd = np.linalg.solve(J, np.asarray(vel_rhs(q, x, xd, p, ka), dtype=np.float64))
            qdd = np.linalg.solve(J, np.asarray(gamma(q, qd, x, xd, xdd, p, ka), dtype=np.float64))
            Q[i], QD[i], QDD[i] = q, qd, qdd
            OBS[i] = np.asarray(observables(q, qd, qdd, x, xd, xdd, p, ka), dtype=np.float64)
            if forces:
                o = OBS[i]
                A = np.asarray(force_A(q, x, p, o, gravity, loads, ka), dtype=np.float64)
                b = np.asarray(force_b(q, x, p, o, gravity, loads, ka), dtype=np.float64)
                F[i] = np.linalg.solve(A, b).ravel()
        if forces:
            return Q, QD, QDD, OBS, nfev / max(n, 1), F
        return Q, QD, QDD, OBS, nfev / max(n, 1)


def compare(m: sewgen.Mechanism, base: tuple, ref: tuple, rtol: float) -> dict:
    """Largest difference of baseline and compiled results, relative to each column's scale.

    ``base`` and ``ref`` are (q, q', q'', observables) and optionally the force unknowns f as a fifth part
    (columns of the manifest's "reactions"; N, or N·m for couples and torques). A column's scale is its
    largest magnitude over the compared positions, floored at 1e-6 of the largest magnitude among columns
    of the same unit (so an identically zero column is judged against its unit).
    """
    desc = m.description
    coord_units = [c.unit for c in desc.coords]
    parts = {  # part -> (units, labels) of its columns, in the order of base and ref
        "q": (coord_units, m.coord_names),
        "qd": ([u + "/s" for u in coord_units], [c + "_d" for c in m.coord_names]),
        "qdd": ([u + "/s^2" for u in coord_units], [c + "_dd" for c in m.coord_names]),
        "obs": ([u for _, u in desc.observables], [n for n, _ in desc.observables]),
    }
    if len(base) > 4:
        cols = [(r.name, c) for r in desc.reactions for c in r.columns]
        parts["f"] = (["N*m" if c in ("moment", "torque") else "N" for _, c in cols],
                      [f"{r}.{c}" for r, c in cols])
    units = [u for us, _ in parts.values() for u in us]
    labels = [lb for _, lbs in parts.values() for lb in lbs]
    b_all, r_all = np.hstack(base), np.hstack(ref)
    colmax = np.max(np.abs(r_all), axis=0)
    scale = colmax.copy()
    for u in set(units):
        idx = [k for k, uu in enumerate(units) if uu == u]
        scale[idx] = np.maximum(colmax[idx], 1e-6 * colmax[idx].max())
    scale[scale == 0] = 1.0
    rel = np.max(np.abs(b_all - r_all), axis=0) / scale
    out = {"max_rel_diff": float(rel.max()), "worst": labels[int(rel.argmax())], "agree": bool(rel.max() <= rtol)}
    start = 0
    for part, (us, _) in parts.items():
        k = len(us)
        out[f"max_rel_diff_{part}"] = float(rel[start:start + k].max()) if k else 0.0
        start += k
    return out


# -- kernels ------------------------------------------------------------------------------------------------


@register_kernel("kinematics")
def kinematics(name: str, cfg: Config) -> Result:
    """solve() over the sweep; raw sg_sweep; the lambdify + scipy baseline on a subset, cross-checked."""
    m = sewgen.mechanism(name)
    phi = cfg.sweep_angles()
    n = len(phi)
    t_solve = best_time(lambda: m.solve(phi), cfg.repeats, cfg.min_time)
    t_overhead = best_time(lambda: m.solve(phi[:1]), cfg.repeats, cfg.min_time)
    one, params = phi[:1], {m.param_names[0]: m.defaults()[m.param_names[0]]}
    t_overhead_params = best_time(lambda: m.solve(one, params=params), cfg.repeats, cfg.min_time)
    zero = np.zeros(1)  # an array accel: the general path (prepare, run, check), which the lean path skips
    t_general = best_time(lambda: m.solve(one, accel=zero), cfg.repeats, cfg.min_time)
    raw, sw = raw_sweep(m, phi)
    t_raw = best_time(raw, cfg.repeats, cfg.min_time)
    loops = loop_rates(m, phi, cfg)
    motion = m.solve(phi)
    continuous_angles(m.description, sw.q, sw.obs, sw.order)  # what solve() adds after the C call
    if np.any(sw.status) or not np.array_equal(sw.obs, motion.obs):
        raise RuntimeError(f"{name}: the raw sg_sweep call disagrees with solve()")

    rows = cfg.baseline_rows()
    bl = Baseline(name)
    p = m.param_vector()
    if len(bl.kin.p) != len(p):
        raise RuntimeError(f"{name}: {len(bl.kin.p)} symbolic parameters but {len(p)} compiled ones")
    held = [i.default for i in m.description.held_inputs]
    args = (phi[rows], float(m.default_speed), 0.0, held, p, motion.q[rows[0]])
    out = bl.run(*args)  # warm-up, and the results to check
    t_base = min(_timed(bl.run, args) for _ in range(cfg.baseline_repeats))
    check = compare(m, out[:4], (motion.q[rows], motion.qd[rows], motion.qdd[rows], motion.obs[rows]), cfg.rtol)

    extra = {
        "raw_c_positions_per_s": n / t_raw,
        "solve_seconds": t_solve,
        "solve_overhead_seconds": t_overhead,
        "solve_overhead_params_seconds": t_overhead_params,
        "solve_overhead_general_path_seconds": t_general,
        **loops,
        "baseline_step_deg": float(np.degrees(phi[rows[1]] - phi[rows[0]])) if len(rows) > 1 else None,
        "baseline_nfev_per_position": out[4],
        "baseline_setup_seconds": bl.derive_s + bl.lambdify_s,
        "nq": len(m.coord_names),
        "nobs": m.description.sizes["nobs"],
        **check,
    }
    return n / t_solve, len(rows) / t_base, extra


#: Gravity of the kinetostatics baseline, m/s² (the compiled side uses kinetostatics()'s default, "-y").
GRAVITY = (0.0, -9.80665)


@register_kernel("kinetostatics")
def kinetostatics(name: str, cfg: Config) -> Result:
    """kinetostatics() over the sweep; raw sg_sweep with forces; kinematics + A f = b baseline on a subset, checked."""
    m = sewgen.mechanism(name)
    phi = cfg.sweep_angles()
    n = len(phi)
    nf = m.description.sizes["nf"]
    t_kst = best_time(lambda: m.kinetostatics(phi), cfg.repeats, cfg.min_time)
    t_overhead = best_time(lambda: m.kinetostatics(phi[:1]), cfg.repeats, cfg.min_time)
    fa = m.kinetostatics(phi)
    raw, sw = raw_sweep(m, phi, forces=True)  # kinetostatics()'s own defaults, so results are equal
    t_raw = best_time(raw, cfg.repeats, cfg.min_time)
    loops = loop_rates(m, phi, cfg, forces=True)
    mo = fa.motion
    continuous_angles(m.description, sw.q, sw.obs, sw.order)  # what kinetostatics() adds after the C call
    if np.any(sw.status) or not all(np.array_equal(a, b) for a, b in (
            (sw.q, mo.q), (sw.qd, mo.qd), (sw.qdd, mo.qdd), (sw.obs, mo.obs), (sw.frc, fa.frc))):
        raise RuntimeError(f"{name}: the raw sg_sweep call (forces) disagrees with kinetostatics()")

    rows = cfg.baseline_rows()
    bl = Baseline(name, forces=True)
    p = m.param_vector()
    if len(bl.kin.p) != len(p):
        raise RuntimeError(f"{name}: {len(bl.kin.p)} symbolic parameters but {len(p)} compiled ones")
    unknowns = [f"{r.name}.{c}" for r in m.description.reactions for c in r.columns]
    if bl.kst.unknown_names != unknowns or len(unknowns) != nf:
        raise RuntimeError(f"{name}: symbolic force unknowns {bl.kst.unknown_names} are not the compiled "
                           f"reactions' columns {unknowns}")
    held = [i.default for i in m.description.held_inputs]
    args = (phi[rows], float(m.default_speed), 0.0, held, p, mo.q[rows[0]], GRAVITY)
    out = bl.run(*args)  # warm-up, and the results to check
    t_base = min(_timed(bl.run, args) for _ in range(cfg.baseline_repeats))
    ref = (mo.q[rows], mo.qd[rows], mo.qdd[rows], mo.obs[rows], fa.frc[rows, :nf])
    check = compare(m, out[:4] + (out[5],), ref, cfg.rtol)

    extra = {
        "raw_c_positions_per_s": n / t_raw,
        "kinetostatics_seconds": t_kst,
        "kinetostatics_overhead_seconds": t_overhead,
        **loops,
        "baseline_step_deg": float(np.degrees(phi[rows[1]] - phi[rows[0]])) if len(rows) > 1 else None,
        "baseline_nfev_per_position": out[4],
        "baseline_setup_seconds": bl.derive_s + bl.lambdify_s,
        "baseline_gravity": list(GRAVITY),
        "compiled_gravity": [float(g) for g in fa.gravity],
        "nq": len(m.coord_names),
        "nobs": m.description.sizes["nobs"],
        "nf": nf,
        "nfo": m.description.sizes["nfo"],
        **check,
    }
    return n / t_kst, len(rows) / t_base, extra


def _timed(fn, args) -> float:
    t0 = time.perf_counter()
    fn(*args)
    return time.perf_counter() - t0


def derive_catalog() -> dict:
    """Seconds of derive.emit.generate for every catalog declaration, in-process, SymPy's cache cleared."""
    from sympy.core.cache import clear_cache

    from sewgen.derive.catalog import CATALOG, declare
    from sewgen.derive.emit import generate

    clear_cache()
    each = {}
    t0 = time.perf_counter()
    for name in CATALOG:
        t = time.perf_counter()
        generate(declare(name))
        each[name] = time.perf_counter() - t
    return {"derive_seconds": time.perf_counter() - t0, "per_mechanism_seconds": each}


# -- driver -------------------------------------------------------------------------------------------------


def run(cfg: Config, selected: list[str] | None = None) -> list[dict]:
    """Every selected row as a dict (the --json objects), the derive line last."""
    rows: list[dict] = []
    derive_row = None
    if selected is None or "catalog" in selected:  # first, before the baselines warm SymPy up
        d = derive_catalog()
        derive_row = {"mechanism": "catalog", "kernel": "derive", "derive_seconds": d["derive_seconds"],
                      "positions_per_s": None, "baseline_positions_per_s": None, "speedup": None,
                      "positions": None, "baseline_positions": None,
                      "extra": {"per_mechanism_seconds": d["per_mechanism_seconds"]}}
    for e in entries(selected):
        try:
            pps, bpps, extra = e.run(cfg)
        except NotApplicable:
            continue
        rows.append({"mechanism": e.mechanism, "kernel": e.kernel, "positions_per_s": pps,
                     "baseline_positions_per_s": bpps, "speedup": pps / bpps if bpps else None,
                     "positions": cfg.positions,
                     "baseline_positions": len(cfg.baseline_rows()) if bpps else None, "extra": extra})
    if derive_row is not None:
        rows.append(derive_row)
    return rows


def _si(v: float | None) -> str:
    if v is None:
        return "-"
    for div, suffix in ((1e9, " G"), (1e6, " M"), (1e3, " k")):
        if abs(v) >= div:
            return f"{v / div:.3g}{suffix}"
    return f"{v:.3g}"


def table(rows: list[dict]) -> str:
    head = ("mechanism", "kernel", "positions/s", "raw C pos/s", "baseline pos/s", "speed-up", "check")
    lines = [head]
    for r in rows:
        x = r.get("extra", {})
        if r["kernel"] == "derive":
            lines.append((r["mechanism"], "derive", f"{r['derive_seconds']:.2f} s", "-", "-", "-", "-"))
            continue
        if r["kernel"] == "study":  # a design study: wall time, the 10 s target, the 2-worker speed-up
            check = f"{'ok' if x['meets_target'] else 'MISSES'} < {x['target_s']:.0f} s"
            if "speedup_vs_1_worker" in x:
                check += (f"; {x['speedup_vs_1_worker']:.2f}x of 1 worker "
                          f"({'ok' if x['speedup_vs_1_worker'] >= x['target_speedup'] else 'MISSES'} >= 1.7x)")
            if "agree" in x:
                check += "; = in-process" if x["agree"] else "; DIFFERS from in-process"
            if "dask_overhead_s" in x:
                check += (f"; Dask overhead {x['dask_overhead_s']:+.2f} s ({x['dask_overhead_per_task_ms']:+.0f} ms "
                          f"a task) over 1 thread in-process")
            if "cluster_start_s" in x:
                check += f"; start {x['cluster_start_s']:.1f} s + warm {x['worker_warm_s']:.2f} s apart"
            lines.append((r["mechanism"], r["kernel"], f"{x['seconds']:.1f} s", "-", "-",
                          f"{x['designs_per_s']:.0f} designs/s", check))
            continue
        if "ms_per_analysis" in x:  # a whole machine through the API: ms an analysis against the issue's target
            lines.append((r["mechanism"], r["kernel"], _si(r["positions_per_s"]), "-", "-", "-",
                          f"{'ok' if x['meets_target'] else 'MISSES'} {x['ms_per_analysis']:.3g} ms "
                          f"< {x['target_ms']:.3g} ms"))
            continue
        if "wall_ms" in x:  # a whole command's wall time: ms in the first column, the target in the last
            lines.append((r["mechanism"], r["kernel"], f"{x['wall_ms']:.0f} ms", "-", "-", "-",
                          f"{'ok' if x['meets_target'] else 'MISSES'} < {x['target_ms']:.0f} ms"))
            continue
        if "ratio" in x:  # a row timed against a peer in the same run
            check = (f"{'ok' if x['ratio'] >= x['target_ratio'] else 'MISSES'} {x['ratio']:.2f}x of "
                     f"{_si(x['peer_positions_per_s'])} {x.get('peer', 'without')} (>= {x['target_ratio']:.2f}x)")
        else:
            check = "-" if "agree" not in x else (f"ok {x['max_rel_diff']:.0e}" if x["agree"] else
                                                  f"MISMATCH {x['max_rel_diff']:.1e} ({x['worst']})")
            if "sewgen_over_peer" in x:  # a peer: sewgen's rate on the same outputs over the peer's, same run
                check += f"; sewgen {x['sewgen_over_peer']:.2f}x this"
            if "target_selected_positions_per_s" in x:  # coordinates and one point, against the target rate
                sel, want = x["sewgen_selected_positions_per_s"], x["target_selected_positions_per_s"]
                check += (f"; coords + thread eye {_si(sel)}/s ({'ok' if sel >= want else 'MISSES'} "
                          f">= {_si(want)})")
        lines.append((r["mechanism"], r["kernel"], _si(r["positions_per_s"]),
                       _si(x.get("raw_c_positions_per_s")), _si(r["baseline_positions_per_s"]),
                       "-" if r["speedup"] is None else f"{r['speedup']:.0f}x", check))
    widths = [max(len(row[k]) for row in lines) for k in range(len(head))]
    fmt = lambda row: "  ".join(c.ljust(w) if k < 2 or k == 6 else c.rjust(w)  # noqa: E731
                                for k, (c, w) in enumerate(zip(row, widths))).rstrip()
    out = [fmt(lines[0]), fmt(tuple("-" * w for w in widths))] + [fmt(r) for r in lines[1:]]
    return "\n".join(out)


def _machine_entry(positions: int, target_ms: float):
    """The whole JB1-3 machine through the Python API: four group sweeps (kinematics + forces) and the shaft."""

    def run(cfg: Config) -> Result:
        from sewgen.machine.assembly import load_machine

        machine = load_machine("jb1-3")
        phi = machine.shaft_angles(2 * np.pi / positions)
        machine.analyze(phi)  # warm-up
        t = best_time(lambda: machine.analyze(phi), cfg.repeats, cfg.min_time)
        return positions / t, None, {"ms_per_analysis": t * 1e3, "target_ms": target_ms,
                                     "meets_target": t * 1e3 < target_ms, "positions": positions}

    return run


register_entry("jb1-3", "machine@72", _machine_entry(72, 0.3))  # the target: < 0.3 ms
register_entry("jb1-3", "machine@3600", _machine_entry(3600, 3.0))  # the target: < 3 ms


def _wall_entry(args: list[str], target_ms: float, repeats: int | None = None):
    """Wall time of a fresh ``python ...`` process (start-up included), best of the repeats, in a scratch folder:
    what a user waits for. ``extra.wall_ms`` is the best time; no positions, no baseline."""

    def run(cfg: Config) -> Result:
        import subprocess
        import tempfile

        best = math.inf
        with tempfile.TemporaryDirectory() as tmp:
            for _ in range(repeats or cfg.repeats):
                t0 = time.perf_counter()
                subprocess.run([sys.executable, *args], cwd=tmp, check=True, capture_output=True)
                best = min(best, time.perf_counter() - t0)
        return None, None, {"wall_ms": best * 1e3, "target_ms": target_ms, "meets_target": best * 1e3 < target_ms}

    return run


def _four_bar(spring: bool):
    """A crank-rocker with masses (a user mechanism, compiled once into the cache), with or without a spring from
    its coupler to the frame: the force-element rows of the benchmark."""
    from sewgen.derive.model import Mechanism

    def declare():
        m = Mechanism("bench_sprung_four_bar" if spring else "bench_four_bar", "a crank-rocker with masses")
        crank = m.driven("crank", m.ground.at(0, 0), mass="20 g", com=("4 mm", "0 mm"), inertia="1e-6 kg*m**2")
        coupler = m.link("coupler", guess="40 deg", mass="30 g", com=("20 mm", "5 mm"), inertia="5e-6 kg*m**2")
        rocker = m.link("rocker", guess="110 deg", mass="25 g", com=("15 mm", "0 mm"), inertia="3e-6 kg*m**2")
        m.revolute(crank.at("12 mm", 0), coupler.at(0, 0), "B")
        m.revolute(coupler.at("45 mm", 0), rocker.at("35 mm", 0), "C")
        m.revolute(m.ground.at("40 mm", "-10 mm"), rocker.at(0, 0), "D")
        if spring:
            m.spring(coupler.at("25 mm", "10 mm"), m.ground.at("10 mm", "50 mm"), "800 N/m", "35 mm", "1.5 N",
                     name="return_spring")
        return m

    return sewgen.load(declare)


def _spring_entry(cfg: Config) -> Result:
    """Kinetostatics of the four-bar with one spring against the same four-bar without it, in the same run."""
    phi = cfg.sweep_angles()
    rates = []
    for spring in (True, False):
        call, _ = raw_sweep(_four_bar(spring), phi, forces=True)
        rates.append(cfg.positions / best_time(call, cfg.repeats, cfg.min_time))
    return rates[0], None, {"raw_c_positions_per_s": rates[0], "peer_positions_per_s": rates[1],
                            "ratio": rates[0] / rates[1], "target_ratio": 0.9}


register_entry("four_bar", "kinetostatics+spring", _spring_entry)


def _rssr():
    """A spatial crank-rocker (seed 003's needle-drive four-bar, axes perpendicular) with the four-bar's rocker."""
    from sewgen.derive.model import Mechanism

    def declare():
        m = Mechanism("bench_rssr", "a spatial crank-rocker")
        crank = m.spatial_crank("crank", ("50 mm", "20 mm", "-30 mm"), (1, 0, 0), inertia="2e-6 kg*m**2")
        rocker = m.link("rocker", guess="90 deg", mass="25 g", com=("15 mm", "0 mm"), inertia="3e-6 kg*m**2")
        m.revolute(m.ground.at(0, 0), rocker.at(0, 0), "D")
        m.rod(crank.pin("8 mm"), rocker.at("30 mm", 0), "60 mm", "rod")
        return m

    return sewgen.load(declare)


def _rssr_entry(cfg: Config) -> Result:
    """Kinematics of the spatial crank-rocker against the planar four-bar's, in the same run."""
    phi = cfg.sweep_angles()
    rates = []
    for mech in (_rssr(), _four_bar(False)):
        call, _ = raw_sweep(mech, phi)
        rates.append(cfg.positions / best_time(call, cfg.repeats, cfg.min_time))
    return rates[0], None, {"raw_c_positions_per_s": rates[0], "peer_positions_per_s": rates[1],
                            "ratio": rates[0] / rates[1], "target_ratio": 1.0, "peer": "the planar four-bar"}


register_entry("rssr", "kinematics", _rssr_entry)


def _balance_entry(objective: str):
    """Method 3 (bearings) on the JB1-3 at 72 positions with two counterweight planes: the group sweeps once,
    the affine model, the convex solve. Wall time of one balancing after a warm-up (CVXPY imported)."""

    def run(cfg: Config) -> Result:
        import tempfile
        from pathlib import Path

        from sewgen.machine import machine_balance as mb
        from sewgen.machine.assembly import load_machine
        from sewgen.machine.modelfile import MODELS_DIR

        planes = "".join(f'\n[[shaft.counterweights]]\nname = "{n}"\nz = "{z}"\nradius = "12 mm"\n'
                         f'max_mass = "60 g"\n' for n, z in (("front_cw", "-30 mm"), ("rear_cw", "190 mm")))
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "jb.toml"
            path.write_text((MODELS_DIR / "jb1-3.toml").read_text() + planes)
            machine = load_machine(path)

            def once():
                before = machine.analyze()
                t0 = time.perf_counter()
                model = mb.linear_model(before, mb.planes_of(machine))
                t1 = time.perf_counter()
                mb.bearings(model, objective)
                return t1 - t0, time.perf_counter() - t1

            once()
            best = min((time.perf_counter(), once(), time.perf_counter()) for _ in range(3))
            wall = best[2] - best[0]
        return None, None, {"wall_ms": wall * 1e3, "target_ms": 500.0, "meets_target": wall < 0.5,
                            "model_ms": best[1][0] * 1e3, "solver_ms": best[1][1] * 1e3}

    return run


#: The tolerance study the "study" entries time: every feed-group length of the JB1-3 at ±0.02 mm (normal, 3σ),
#: every feed-dog index per design (sewgen.study), on the model's own 5° sweep; no loads.
STUDY_TOLERANCES = {f"groups.feed.params.{k}": "±0.02mm" for k in ("feed_arm_r", "feed_arm_p", "lift_arm", "fork_p",
                                                                  "fork_q", "dog_u", "bar_slot_v", "cam_side")}
STUDY_TARGET_S = 10.0
_STUDY: dict = {}


#: rounds of the study runs (alternating the configurations, the best of each counts: the machine is shared)
STUDY_ROUNDS = 2
#: the study's runs: in-process (sweeps on every core, chunks on a thread a core), in-process on one thread
#: (the 1-worker run's work without Dask: their difference is the Dask overhead), LocalClusters of 1 and 2 workers
STUDY_RUNS = ("in-process", "in-process (1 thread)", "dask local:1", "dask local:2")


def _warm_worker(machine, options) -> float:
    """On a worker: import the study's modules (pandas among them), load the mechanisms and compute the nominal
    baseline a study's chunks reuse, by evaluating the nominal design once (s taken)."""
    from dataclasses import replace

    import numpy as np

    from sewgen.study.evaluate import evaluate_chunk
    from sewgen.study.run import linked_keys

    t0 = time.perf_counter()
    keys, _ = linked_keys(machine, list(STUDY_TOLERANCES))
    evaluate_chunk(machine, keys, np.array([[k.nominal for k in keys]]), replace(options, threads=1))
    return time.perf_counter() - t0


def _study_runs(cfg: Config) -> dict:
    """The same 10⁵-design tolerance study in-process (every core; one thread), on a 1-worker and on a
    2-worker LocalCluster, in :data:`STUDY_ROUNDS` alternating rounds (the best of each counts); each
    cluster's start-up and its workers' warm-up (loading the mechanisms, the nominal baseline) timed apart.
    The results are checked equal bit for bit."""
    key = cfg.study_designs
    if key in _STUDY:
        return _STUDY[key]
    import os

    import pandas as pd

    from sewgen.machine.assembly import load_machine
    from sewgen.study import StudyOptions, tolerance
    from sewgen.study.run import dask_chunk, dask_client

    machine = load_machine("jb1-3")
    opts = StudyOptions(step_deg=5.0, loads=False)
    one = StudyOptions(step_deg=5.0, loads=False, threads=1)
    tolerance(machine, STUDY_TOLERANCES, 10, seed=0, options=opts)  # warm-up (the nominal baseline)
    tolerance(machine, STUDY_TOLERANCES, 10, seed=0, options=one)
    out = {name: {"runs": []} for name in STUDY_RUNS}
    ref = None

    def same(res):
        try:
            pd.testing.assert_frame_equal(ref.table, res.table, check_exact=True)
            return True
        except AssertionError:
            return False

    for _ in range(STUDY_ROUNDS):
        for name, o in (("in-process", opts), ("in-process (1 thread)", one)):
            t0 = time.perf_counter()
            res = tolerance(machine, STUDY_TOLERANCES, cfg.study_designs, seed=0, options=o)
            out[name]["runs"].append(time.perf_counter() - t0)
            if ref is None:
                ref = res
            out[name]["same_as_in_process"] = out[name].get("same_as_in_process", True) and same(res)
        for n in (1, 2):
            name = f"dask local:{n}"
            t0 = time.perf_counter()
            client, _ = dask_client(f"local:{n}")
            start = time.perf_counter() - t0
            try:
                t0 = time.perf_counter()
                warm = client.run(_warm_worker, machine, opts)
                warm_s = time.perf_counter() - t0
                t0 = time.perf_counter()
                res = tolerance(machine, STUDY_TOLERANCES, cfg.study_designs, seed=0, options=opts, dask=client)
                secs = time.perf_counter() - t0
            finally:
                cluster = client.cluster
                client.close()
                cluster.close()
            r = out[name]
            r["runs"].append(secs)
            r.setdefault("cluster_start_s", []).append(start)
            r.setdefault("worker_warm_s", []).append(warm_s)
            r["worker_baseline_s"] = max(warm.values())
            r["same_as_in_process"] = r.get("same_as_in_process", True) and same(res)
    for name in STUDY_RUNS:
        r = out[name]
        r["seconds"] = min(r["runs"])
        for k in ("cluster_start_s", "worker_warm_s"):
            if k in r:
                r[k] = min(r[k])
    n = cfg.study_designs + 1  # the nominal design leads the table
    tasks = -(-n // dask_chunk(n, 1))
    overhead = out["dask local:1"]["seconds"] - out["in-process (1 thread)"]["seconds"]
    out["dask_overhead"] = {"seconds": overhead, "per_task_ms": overhead / tasks * 1e3, "tasks": tasks,
                            "fraction": overhead / out["in-process (1 thread)"]["seconds"]}
    out["failing"] = int(len(ref.failures))
    out["load_average"] = os.getloadavg()
    _STUDY[key] = out
    return out


def _study_entry(which: str):
    def run(cfg: Config) -> Result:
        r = _study_runs(cfg)
        secs = r[which]["seconds"]
        extra = {"designs": cfg.study_designs, "seconds": secs, "designs_per_s": cfg.study_designs / secs,
                 "runs_s": r[which]["runs"], "step_deg": 5.0, "target_s": STUDY_TARGET_S,
                 "meets_target": secs < STUDY_TARGET_S, "wall_ms": secs * 1e3, "target_ms": STUDY_TARGET_S * 1e3,
                 "failing_designs": r["failing"], "load_average_after": r["load_average"]}
        if which != "in-process":
            same = r[which]["same_as_in_process"]
            extra.update(agree=same, max_rel_diff=0.0 if same else math.inf, worst="table")
        if which.startswith("dask"):
            extra.update(cluster_start_s=r[which]["cluster_start_s"], worker_warm_s=r[which]["worker_warm_s"],
                         worker_baseline_s=r[which]["worker_baseline_s"])
        if which.endswith(":1"):
            ov = r["dask_overhead"]
            extra.update(dask_overhead_s=ov["seconds"], dask_overhead_per_task_ms=ov["per_task_ms"],
                         dask_overhead_fraction=ov["fraction"], dask_tasks=ov["tasks"])
        if which.endswith(":2"):
            extra["speedup_vs_1_worker"] = r["dask local:1"]["seconds"] / secs
            extra["target_speedup"] = 1.7
        return cfg.study_designs / secs, None, extra

    return run


for _which in STUDY_RUNS:
    register_entry(f"jb1-3 feed tolerance ({_which})", "study", _study_entry(_which))

register_entry("jb1-3", "balance bearings peak", _balance_entry("peak"))
register_entry("jb1-3", "balance bearings rms", _balance_entry("rms"))
register_entry("cli", "import sewgen", _wall_entry(["-c", "import sewgen"], 300.0))
register_entry("cli", "analyze --no-plots", _wall_entry(["-m", "sewgen", "analyze", "jb1-3", "--out", "out",
                                                         "--no-plots"], 1000.0))
register_entry("cli", "analyze", _wall_entry(["-m", "sewgen", "analyze", "jb1-3", "--out", "out"], 4000.0, 3))
register_entry("cli", "timing", _wall_entry(["-m", "sewgen", "timing", "jb1-3"], 1000.0))



# -- peers and batched designs --------------------------------------------------------------------------------


def take_up_numpy(phi, omega, alpha, p: dict) -> dict:
    """The take_up four-bar in closed form with NumPy, vectorised over the shaft angles: every output sewgen's
    solve() gives (2 coordinates with their rates, 3 points and 3 bodies with their centres of mass), named as
    :mod:`sewgen.engine.designs` names them. The peer a user could write in thirty lines (crank AB, lever BC with the
    eye E, rocker DC; the branch +1: C left of B→D)."""
    th1 = phi + p["crank.phase"]
    c1, s1 = np.cos(th1), np.sin(th1)
    ab, bc, cd = p["crank"], p["lever_bc"], p["rocker"]
    bx, by = ab * c1, ab * s1
    vbx, vby = -ab * omega * s1, ab * omega * c1
    abx, aby = -ab * (omega ** 2 * c1 + alpha * s1), ab * (alpha * c1 - omega ** 2 * s1)
    dx, dy = p["rocker_pivot_x"] - bx, p["rocker_pivot_y"] - by
    d2 = dx * dx + dy * dy
    a = 0.5 * (bc * bc - cd * cd + d2) / d2
    h = np.sqrt(bc * bc / d2 - a * a)
    cx, cy = bx + a * dx - h * dy, by + a * dy + h * dx
    r2x, r2y = cx - bx, cy - by
    r3x, r3y = cx - p["rocker_pivot_x"], cy - p["rocker_pivot_y"]
    cr = r2x * r3y - r2y * r3x
    w2 = -(vbx * r3x + vby * r3y) / cr
    w3 = -(vbx * r2x + vby * r2y) / cr
    rx = abx - w2 ** 2 * r2x + w3 ** 2 * r3x
    ry = aby - w2 ** 2 * r2y + w3 ** 2 * r3y
    a2 = -(rx * r3x + ry * r3y) / cr
    a3 = -(rx * r2x + ry * r2y) / cr
    th2, th3 = np.arctan2(r2y, r2x), np.arctan2(r3y, r3x)
    out = {"coords.rocker.angle": th3, "coords.lever.angle": th2, "coords.rocker.angle_d": w3,
           "coords.lever.angle_d": w2, "coords.rocker.angle_dd": a3, "coords.lever.angle_dd": a2}

    def point(name, ox, oy, vx, vy, ax, ay, th, w, al, u, v):  # (u, v) in the body frame from (ox, oy)
        ct, st = np.cos(th), np.sin(th)
        ex, ey = u * ct - v * st, u * st + v * ct
        out.update({f"{name}.x": ox + ex, f"{name}.y": oy + ey, f"{name}.x_d": vx - w * ey,
                    f"{name}.y_d": vy + w * ex, f"{name}.x_dd": ax - al * ey - w * w * ex,
                    f"{name}.y_dd": ay + al * ex - w * w * ey})

    z = np.zeros_like(phi)
    bce, bee, cee = p["lever_bc"], p["lever_be"], p["lever_ce"]
    eu = (bce ** 2 + bee ** 2 - cee ** 2) / (2 * bce)
    ev = np.sqrt(bee ** 2 - eu ** 2)
    point("points.crank_pin", bx, by, vbx, vby, abx, aby, th2, w2, a2, 0.0, 0.0)
    point("points.rocker_pin", bx, by, vbx, vby, abx, aby, th2, w2, a2, bc, 0.0)
    point("points.thread_eye", bx, by, vbx, vby, abx, aby, th2, w2, a2, eu, ev)
    pdx, pdy = p["rocker_pivot_x"], p["rocker_pivot_y"]
    for body, (ox, oy, vx, vy, ax, ay), th, w, al in (
            ("crank", (z, z, z, z, z, z), th1, omega + z, alpha + z),
            ("lever", (bx, by, vbx, vby, abx, aby), th2, w2, a2),
            ("rocker", (pdx + z, pdy + z, z, z, z, z), th3, w3, a3)):
        out.update({f"bodies.{body}.angle": th, f"bodies.{body}.angle_d": w, f"bodies.{body}.angle_dd": al})
        com = (p[f"{body}.com_u"], p[f"{body}.com_v"]) if f"{body}.com_u" in p else (cd / 2, 0.0)  # rocker: CD/2
        point(f"bodies.{body}.com", ox, oy, vx, vy, ax, ay, th, w, al, *com)
    return out


def _peer_check(m, peer: dict, phi) -> float:
    """The largest difference of a peer's outputs from sewgen's full sweep at the same angles, relative to each
    column's scale (angles compared modulo whole turns)."""
    from sewgen.engine.designs import Columns

    motion = m.solve(phi)
    flat = np.hstack([motion.q, motion.qd, motion.qdd, motion.obs])
    cols = Columns(m.description)
    if set(peer) != set(cols.names):
        raise RuntimeError(f"the peer gives {sorted(set(cols.names) ^ set(peer))} differently from sewgen")
    worst = 0.0
    for name in cols.names:
        ref, got = flat[:, cols.index[name]], np.asarray(peer[name], dtype=float)
        diff = got - ref
        if cols.unit(name) == "rad":
            diff = (diff + np.pi) % (2 * np.pi) - np.pi
        worst = max(worst, float(np.abs(diff).max() / max(np.abs(ref).max(), 1e-12)))
    return worst


def _peer_numpy_entry(cfg: Config) -> Result:
    """take_up kinematics, all outputs: the NumPy closed form (checked against sewgen, then timed) against
    sewgen's solve() (all outputs; coordinates and the thread eye only) in the same run."""
    m = sewgen.mechanism("take_up")
    phi = cfg.sweep_angles()
    omega = float(m.default_speed)
    p = m.defaults()
    err = _peer_check(m, take_up_numpy(phi, omega, 0.0, p), phi)
    t_peer = best_time(lambda: take_up_numpy(phi, omega, 0.0, p), cfg.repeats, cfg.min_time)
    t_all = best_time(lambda: m.solve(phi), cfg.repeats, cfg.min_time)
    t_sel = best_time(lambda: m.solve(phi, outputs=["coords", "points:thread_eye"]), cfg.repeats, cfg.min_time)
    n = len(phi)
    return n / t_peer, None, {"agree": err < 1e-12, "max_rel_diff": err, "worst": "-",
                              "sewgen_solve_positions_per_s": n / t_all,
                              "sewgen_over_peer": t_peer / t_all,
                              "sewgen_selected_positions_per_s": n / t_sel,
                              "target_selected_positions_per_s": 40e6,
                              "target_sewgen_over_peer": 2.0}


def _peer_numba_entry(cfg: Config) -> Result:
    """take_up kinematics, all outputs: the closed form as one numba loop (peers, checked against sewgen,
    compiled by the warm-up call, then timed) against sewgen's solve() in the same run."""
    import peers

    m = sewgen.mechanism("take_up")
    phi = cfg.sweep_angles()
    omega = float(m.default_speed)
    prm = peers.parameter_vector(m.defaults())
    kernel = peers.numba_kernel()
    out = np.empty((len(phi), len(peers.COLUMNS)))
    kernel(phi, omega, 0.0, prm, out)
    err = _peer_check(m, dict(zip(peers.COLUMNS, out.T)), phi)
    t_peer = best_time(lambda: kernel(phi, omega, 0.0, prm, out), cfg.repeats, cfg.min_time)
    t_all = best_time(lambda: m.solve(phi), cfg.repeats, cfg.min_time)
    n = len(phi)
    return n / t_peer, None, {"agree": err < 1e-12, "max_rel_diff": err, "worst": "-",
                              "sewgen_solve_positions_per_s": n / t_all, "sewgen_over_peer": t_peer / t_all}


def _peer_pylinkage_entry(cfg: Config) -> Result:
    """take_up's three points (crank pin, rocker pin, thread eye: position, velocity, acceleration) over one
    revolution by pylinkage's numba solver (peers), checked against sewgen (relative to each column's
    largest value), then timed against sewgen's solve(outputs=["points"]) — the same 18 columns — in the same
    run. pylinkage sweeps equal steps of one revolution only, so both take n = --positions such steps."""
    import peers

    m = sewgen.mechanism("take_up")
    n = cfg.positions
    phi = 2 * np.pi * np.arange(n) / n
    omega = float(m.default_speed)
    ref = m.solve(phi)
    first = ref.point("rocker_pin")
    run = peers.pylinkage_take_up(m.defaults(), n, omega, (float(first.x[0]), float(first.y[0])))
    pos, vel, acc = run()
    err = 0.0
    for j, name in enumerate(("crank_pin", "rocker_pin", "thread_eye")):
        pt = ref.point(name)
        for got, want in ((pos[:, j, 0], pt.x), (pos[:, j, 1], pt.y), (vel[:, j, 0], pt.vx), (vel[:, j, 1], pt.vy),
                          (acc[:, j, 0], pt.ax), (acc[:, j, 1], pt.ay)):
            err = max(err, float(np.abs(got - want).max() / max(np.abs(want).max(), 1e-12)))
    t_peer = best_time(run, cfg.repeats, cfg.min_time)
    t_sel = best_time(lambda: m.solve(phi, outputs=["points"]), cfg.repeats, cfg.min_time)
    return n / t_peer, None, {"agree": err < 1e-9, "max_rel_diff": err, "worst": "-",
                              "sewgen_selected_positions_per_s": n / t_sel, "sewgen_over_peer": t_peer / t_sel}


def _designs_entry(cfg: Config) -> Result:
    """10⁵ take_up designs (the crank length varied) × 72 angles with the peak thread-eye acceleration per design,
    sweep_designs on every core and on one; the baseline: solve() per design (on 2000 of them) in the same run;
    ``projected_1e6_designs_s`` is the time of 10⁶ at the measured rate (target < 2 s on two cores)."""
    import os

    m = sewgen.mechanism("take_up")
    phi = sewgen.shaft_angles(5)
    nd = 100_000
    crank = m.defaults()["crank"] * np.linspace(0.9, 1.1, nd)
    red = {"points.thread_eye.a": "max"}
    threads = os.cpu_count() or 1
    run = lambda th: m.sweep_designs({"crank": crank}, phi, reduce=red, threads=th)  # noqa: E731
    res = run(threads)
    nb = 2000
    ref = np.array([np.hypot(mo.point("thread_eye").ax, mo.point("thread_eye").ay).max()
                    for mo in (m.solve(phi, params={"crank": float(c)}) for c in crank[:nb])])
    err = float(np.abs(res["points.thread_eye.a:max"][:nb] / ref - 1).max())
    t_all = min(_timed(run, (threads,)) for _ in range(3))
    t_one = min(_timed(run, (1,)) for _ in range(2))
    t_base = min(_timed(lambda: [m.solve(phi, params={"crank": float(c)}) for c in crank[:nb]], ()) for _ in
                 range(2)) / nb * nd
    pos = nd * len(phi)
    return pos / t_all, pos / t_base, {
        "agree": err < 1e-13, "max_rel_diff": err, "worst": "points.thread_eye.a:max",
        "designs": nd, "angles": len(phi), "threads": threads, "us_per_design": t_all / nd * 1e6,
        "us_per_design_one_thread": t_one / nd * 1e6, "thread_speedup": t_one / t_all,
        "projected_1e6_designs_s": t_all * 1e6 / nd, "target_1e6_designs_s": 2.0,
        "meets_target": t_all * 1e6 / nd < 2.0}


register_entry("take_up", "designs", _designs_entry)


def _feed_designs_entry(cfg: Config) -> Result:
    """5000 JB1-3 feed designs (every parameter scaled by 1 + 1e-4 noise) × 72 angles (5°), a Newton mechanism,
    keeping the feed dog's x and y only (so the rates kernel and the feed dog's group of
    observables run, not the joint motion kernel), on one thread; the baseline: the same designs with every column
    (the joint kernel) in the same run, checked equal to the bit on the kept columns."""
    m = sewgen.mechanism("feed")
    phi = sewgen.shaft_angles(5)
    nd = 5000
    p0 = m.param_vector()
    P = np.tile(p0, (nd, 1)) * (1 + 1e-4 * np.random.default_rng(0).standard_normal((nd, p0.size)))
    dog = m.description.role("feed_dog").name
    kept = [f"points.{dog}.x", f"points.{dog}.y"]
    run = lambda outputs: m.sweep_designs(P, phi, outputs=outputs, threads=1, chunk=1000)  # noqa: E731
    sel, full = run(kept), run(["all"])
    agree = all(np.array_equal(sel[k], full[k], equal_nan=True) for k in kept) and np.array_equal(sel.status,
                                                                                                  full.status)
    t_sel = min(_timed(run, (kept,)) for _ in range(3))
    t_full = min(_timed(run, (["all"],)) for _ in range(2))
    pos = nd * len(phi)
    return pos / t_sel, pos / t_full, {
        "agree": agree, "max_rel_diff": 0.0 if agree else math.inf, "worst": kept[0], "designs": nd,
        "angles": len(phi), "threads": 1, "us_per_design": t_sel / nd * 1e6,
        "us_per_design_all_columns": t_full / nd * 1e6, "failing_designs": int((sel.status != 0).sum())}


register_entry("feed", "designs (feed dog x, y)", _feed_designs_entry)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python tools/bench.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("--positions", type=int, default=Config.positions,
                    help="shaft angles in the timed sweep, one revolution (default %(default)s: 0.1°)")
    ap.add_argument("--baseline-positions", type=int, default=Config.baseline_positions,
                    help="positions the lambdify + scipy baseline solves (default %(default)s)")
    ap.add_argument("--baseline-angles", choices=("spread", "contiguous"), default=Config.baseline_angles,
                    help="baseline angles: every k-th sweep angle over the revolution (default) or the "
                         "first ones at the sweep's own step")
    ap.add_argument("--repeats", type=int, default=Config.repeats, help="timed repeats, best counts")
    ap.add_argument("--rtol", type=float, default=Config.rtol,
                    help="baseline/compiled agreement, relative to each column's scale (default %(default)g)")
    ap.add_argument("--mechanism", action="append", metavar="NAME",
                    help="restrict to this mechanism (repeatable); 'catalog' selects the derive line")
    ap.add_argument("--study-designs", type=int, default=Config.study_designs,
                    help="designs of the 'study' entries (default %(default)s)")
    ap.add_argument("--json", action="store_true", help="print a JSON list instead of the table")
    ap.add_argument("--peers", action="store_true",
                    help="also time the peers of take_up's kinematics (a NumPy closed form; numba, pylinkage "
                         "when installed: pip install -e '.[peers]'), each checked against sewgen first: kernel "
                         "\"peer:<name>\"")
    args = ap.parse_args(argv)
    if args.positions < 1 or args.baseline_positions < 1 or args.repeats < 1:
        ap.error("--positions, --baseline-positions and --repeats must be positive")
    known = set(sewgen.catalog()) | {e.mechanism for e in EXTRA_ENTRIES} | {"catalog"}
    for name in args.mechanism or []:
        if name not in known:
            ap.error(f"unknown mechanism {name!r}; known: {', '.join(sorted(known))}")
    cfg = Config(positions=args.positions, baseline_positions=args.baseline_positions,
                 repeats=args.repeats, baseline_angles=args.baseline_angles, rtol=args.rtol,
                 study_designs=args.study_designs)
    if args.peers:
        import importlib.util

        register_entry("take_up", "peer:numpy", _peer_numpy_entry)
        for peer, entry in (("numba", _peer_numba_entry), ("pylinkage", _peer_pylinkage_entry)):
            if importlib.util.find_spec(peer) is not None:
                register_entry("take_up", f"peer:{peer}", entry)
            else:
                print(f"bench: {peer} is not installed: no peer:{peer} row", file=sys.stderr)
    t0 = time.perf_counter()
    rows = run(cfg, args.mechanism)
    if args.json:
        print(json.dumps(rows, indent=1))
    else:
        print(table(rows))
        print(f"\n{cfg.positions} positions per sweep (one revolution), best of {cfg.repeats}; baseline "
              f"{len(cfg.baseline_rows())} positions, best of {cfg.baseline_repeats}; "
              f"{time.perf_counter() - t0:.1f} s in all")
    bad = [r for r in rows if r.get("extra", {}).get("agree") is False]
    for r in bad:
        x = r["extra"]
        print(f"bench: {r['mechanism']} {r['kernel']}: baseline and compiled results differ by "
              f"{x['max_rel_diff']:.3g} (relative, worst {x['worst']}; tolerance {cfg.rtol:g})", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

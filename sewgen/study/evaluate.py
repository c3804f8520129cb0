"""Evaluate machine designs: per design the feed-dog indices, the needle stroke, the hook timing, the take-up
amount, the timing rules and the machine's peak loads, as one row of a pandas DataFrame.

Each group's designs are swept in one call of the seam (:func:`sewgen.study.designs.sweep_group_designs`);
the groups a design set does not vary are swept once (the nominal machine) and broadcast. Everything after the
sweep is computed on (designs × angles) arrays — the feed-dog indices (sewgen.machine.feed_indices), the needle
stroke — except what needs the whole machine per design: the stitch timing (sewgen.machine.timing, on the study's own
sweep; only when a group other than the feed varies: otherwise the nominal timing holds, and the two feed rules
are re-checked from each design's rise lag and sink lead) and the peak loads (sewgen.machine.MachineAnalysis; each
refined between the samples by solving the design's machine again around it, sewgen.machine.peaks).
A design set with a key other than a mechanism parameter reloads the model per design (the loader's checks).
"""
from __future__ import annotations

import hashlib
import math
import pickle
from dataclasses import dataclass

import numpy as np

from sewgen.errors import ParameterError, SewgenError
from sewgen.hermite import maximum
from sewgen.machine import feed_indices as fi
from sewgen.machine.assembly import MachineAnalysis
from sewgen.machine.cams import arc_switches
from sewgen.machine.peaks import extremes
from sewgen.machine.timing import timing
from sewgen.roles import FEED_DOG, NEEDLE_POINT, THROAT_PLATE
from sewgen.study.designs import sweep_group_designs
from sewgen.study.machine_designs import MachineDesigns, with_params

TWO_PI = 2.0 * math.pi

NEEDLE_STROKE = "needle_stroke [mm]"
HOOK_RISE = "hook_at_needle_rise [mm]"
HOOK_MARGIN = "hook_timing_margin [mm]"
TAKE_UP = "take_up_amount [mm]"
FAILURES = "timing_failures"
FAILED = "failed_rules"
LOADS = ("front_bearing_peak [N]", "rear_bearing_peak [N]", "drive_torque_peak [N*m]",
         "shaking_force_on_frame_peak [N]")
#: rules re-checked per design from the feed-dog indices when only feed groups vary
FEED_RULES = {"dog_sinks_before_needle_enters": "sink_lead", "dog_rises_after_needle_leaves": "rise_lag"}


@dataclass(frozen=True)
class StudyOptions:
    """``step_deg``: the sweep's step (must divide 360°); ``speed`` (rad/s; None: the machine's); ``loads``:
    the kinetostatics and the machine's peak loads per design; ``tooth_depth`` (m) for the effective travel;
    ``threads``: threads of each batched sweep (None: every core; a Dask worker runs with 1, its cluster being
    the parallelism). The results do not depend on it. ``exact_jumps``: each design's cam-arc acceleration
    jumps by sewgen.machine.cams.arc_switches (the switch bracketed and solved at its own angle, as summary.json; 5–30
    ms a design) instead of extrapolated from the sweep (sewgen.machine.feed_indices.arc_jumps, O(h³))."""

    step_deg: float = 1.0
    speed: float | None = None
    loads: bool = True
    tooth_depth: float = fi.TOOTH_DEPTH
    threads: int | None = None
    exact_jumps: bool = False

    def phi(self) -> np.ndarray:
        n = int(round(360.0 / self.step_deg))
        return TWO_PI * np.arange(n) / n


def _role_group(machine, role):
    for g in machine.groups:
        d = g.mechanism.description
        if d.has_role(role) and d.roles[role][0] == "point":
            return g
    return None


def feed_groups(machine) -> list:
    return [g for g in machine.groups if g.mechanism.description.has_role(FEED_DOG)
            and g.mechanism.description.has_role(THROAT_PLATE)]


def quantity_columns(machine, options: StudyOptions) -> list[str]:
    """The columns a study of ``machine`` reports, besides its design keys, ``status`` and ``error``."""
    cols = []
    fg = feed_groups(machine)
    for g in fg:
        pre = "" if len(fg) == 1 else f"{g.name}."
        cols += [pre + fi.column(k) for k in fi.INDICES]
    if _role_group(machine, NEEDLE_POINT) is not None:
        cols.append(NEEDLE_STROKE)
    if machine.stitch is not None:
        cols += [HOOK_RISE, HOOK_MARGIN, TAKE_UP, FAILURES, FAILED]
    if options.loads:
        cols += list(LOADS)
    return cols


def angle_periods(machine, options: StudyOptions) -> dict:
    """Column -> period (in the column's unit, deg) of every quantity column that is an angle known only modulo a
    period (sewgen.machine.feed_indices.PERIODS): a study compares such values continuously across the period
    (:func:`around`)."""
    out = {}
    fg = feed_groups(machine)
    for g in fg:
        pre = "" if len(fg) == 1 else f"{g.name}."
        out.update({pre + fi.column(k): period * fi.INDICES[k][1] for k, period in fi.PERIODS.items()})
    return {c: p for c, p in out.items() if c in quantity_columns(machine, options)}


def around(values, centre, period: float):
    """Angles ``values`` moved by whole periods to within half a period of ``centre`` (−period/2 ≤ v − centre <
    period/2): 359.9° about 10° is −0.1°."""
    v = np.asarray(values, dtype=float)
    return centre + (v - centre + 0.5 * period) % period - 0.5 * period


def continuous(values, centre, period: float) -> np.ndarray:
    """A sequence of angles (an influence sweep's, in order) made continuous: unwrapped across the period
    wherever consecutive finite values jump by more than half of it, then moved by whole periods so the value
    nearest ``centre`` (the nominal) lies within half a period of it (NaNs stay)."""
    v = np.asarray(values, dtype=float).copy()
    ok = np.flatnonzero(np.isfinite(v))
    if not len(ok):
        return v
    u = np.unwrap(v[ok], period=period)
    i = int(np.argmin(np.abs(around(u, centre, period) - centre))) if math.isfinite(centre) else 0
    v[ok] = u + (float(around(u[i], centre, period)) - u[i] if math.isfinite(centre) else 0.0)
    return v


def _speed(machine, options):
    return float(machine.speed if options.speed is None else options.speed)


def _sweep(machine, g, P, phi, w, options, observables=None):
    gv = machine.gravity
    mag = float(np.hypot(*gv))
    direction = math.atan2(gv[1], gv[0]) if mag else -math.pi / 2
    return sweep_group_designs(g.mechanism, P, phi + g.phase, w, held=g.held or None, branch=g.branch or None,
                               forces=options.loads, loads=g.sweep_loads, gravity=mag, gravity_direction=direction,
                               threads=options.threads, observables=None if options.loads else observables)


def _needle_observables(g) -> tuple:
    off = g.mechanism.description.role(NEEDLE_POINT).offset
    return off + 1, off + 3  # y, vy


def _kept_observables(machine, g) -> tuple:
    """The only observables of group ``g`` a study reads when nothing needs its whole motion (no per-design
    timing, no loads): the feed dog's (feed groups) and the needle point's height and speed."""
    kept = []
    if g in feed_groups(machine):
        kept += [k for k in fi.feed_observables(g.mechanism) if k is not None]
    if _role_group(machine, NEEDLE_POINT) is g:
        kept += [k for k in _needle_observables(g) if k not in kept]
    return tuple(kept)


def _needle_stroke(g, sweep, w, h):
    iy, ivy = _needle_observables(g)
    y, dy = sweep.observable(iy), sweep.observable(ivy) / w
    hi, _, _ = maximum(y, dy, h)
    lo, _, _ = maximum(-y, -dy, h)
    return hi + lo


def _exact_jumps(g, sweep, status, error, estimate):
    """Per design of ``sweep`` (feed group ``g``): the largest |horizontal acceleration jump| of the feed dog at
    a cam-arc switch, each switch bracketed and solved at its own shaft angle (sewgen.machine.cams.arc_switches, as
    summary.json's); ``estimate`` where a design failed (its value is NaN then anyway). A switch that cannot be
    solved fails its design (``status``/``error`` updated), the others unaffected."""
    mech = g.mechanism
    dog = mech.description.role(FEED_DOG).name
    out = np.array(estimate, dtype=float)
    for k in np.flatnonzero(status == "ok"):
        try:
            switches = arc_switches(mech, sweep.motion(int(k)),
                                    params=dict(zip(mech.param_names, sweep.params[k])), held=g.held or None)
        except SewgenError as exc:
            status[k], error[k] = type(exc).__name__, f"groups.{g.name}: cam-arc switch: {exc}"
            continue
        out[k] = max((abs(s.jumps[dog][0]) for s in switches), default=0.0)
    return out


def _timing_values(tm, machine):
    """hook_at_needle_rise value and margin (mm), take-up amount (mm), failed rules."""
    out = {HOOK_RISE: math.nan, HOOK_MARGIN: math.nan, TAKE_UP: math.nan}
    for c in tm.checks:
        if c.rule == "hook_at_needle_rise":
            out[HOOK_RISE], out[HOOK_MARGIN] = c.value, c.margin
    if tm.thread is not None:
        out[TAKE_UP] = tm.thread.take_up_amount * 1e3
    failed = [c.rule for c in tm.checks if not c.ok]
    out[FAILURES], out[FAILED] = len(failed), ";".join(failed)
    out["needle_in_cloth"] = tm.values.get("needle_in_cloth", math.nan)
    out["needle_out_cloth"] = tm.values.get("needle_out_cloth", math.nan)
    return out


#: the peak loads: column -> the quantity (a function of a machine analysis) whose largest value it is
PEAK_LOADS = {LOADS[0]: lambda a: np.hypot(*a.bearing("front").T), LOADS[1]: lambda a: np.hypot(*a.bearing("rear").T),
              LOADS[2]: lambda a: np.abs(a.torque), LOADS[3]: lambda a: np.hypot(*a.shaking_force_on_frame.T)}


def _peaks(a):
    """The design's peak loads, each refined between the sweep's samples (sewgen.machine.peaks: its machine solved
    again around each sampled peak), as summary.json's."""
    return {c: e["max"].value for c, e in extremes(a, PEAK_LOADS, ("max",)).items()}


_BASELINES: dict = {}


def _baseline(machine, options):
    """The nominal machine's sweeps (one design per group) and timing on the study's sweep, cached per process
    by the machine's pickle and the options."""
    key = (hashlib.sha1(pickle.dumps(machine)).hexdigest(), options)
    b = _BASELINES.get(key)
    if b is None:
        b = _evaluate_fast(machine, MachineDesigns(machine, [], np.zeros((1, 0))), options, None, nominal=True)
        if len(_BASELINES) > 8:
            _BASELINES.clear()
        _BASELINES[key] = b
    return b


def _evaluate_fast(machine, designs: MachineDesigns, options, base, nominal=False):
    """Columns (name -> (D,) array or list) for designs that change mechanism parameters only."""
    phi = options.phi()
    h = float(phi[1] - phi[0])
    w = _speed(machine, options)
    d = len(designs)
    varied = set(designs.varied_groups)
    sweeps, status, error = {}, np.full(d, "ok", dtype=object), [None] * d
    fnames = {g.name for g in feed_groups(machine)}
    per_design_timing = machine.stitch is not None and (nominal or bool(varied - fnames))
    # something reads each design's whole motion
    whole = nominal or per_design_timing or options.loads or options.exact_jumps
    for g in machine.groups:
        if nominal or g.name in varied:
            s = _sweep(machine, g, designs.group_matrix(g), phi, w, options,
                       None if whole else _kept_observables(machine, g))
            for k in np.flatnonzero(~s.ok):
                if error[k] is None:
                    status[k], error[k] = s.status[k], f"groups.{g.name}: {s.error[k]}"
        else:
            s = base["sweeps"][g.name]
        sweeps[g.name] = s
    cols: dict = {}
    fgroups = feed_groups(machine)
    rows = [None] * d
    if machine.stitch is not None:
        tcols = (HOOK_RISE, HOOK_MARGIN, TAKE_UP, FAILURES, FAILED, "needle_in_cloth", "needle_out_cloth")
        if per_design_timing:
            for k in range(d):
                if status[k] != "ok":
                    continue
                mk = with_params(machine, designs.param_changes(k))
                motions = {g.name: sweeps[g.name].motion(k if g.name in varied or nominal else 0)
                           for g in machine.groups}
                try:
                    rows[k] = _timing_values(timing(mk, w, options.step_deg, motions), mk)
                except SewgenError as exc:
                    status[k], error[k] = type(exc).__name__, str(exc)
            for c in tcols:
                vals = [r[c] if r is not None else (math.nan if c != FAILED else "") for r in rows]
                cols[c] = np.array(vals, dtype=object if c == FAILED else float)
        else:
            nom = base["timing"]
            for c in tcols:
                cols[c] = np.array([nom[c]] * d, dtype=object if c == FAILED else float)
    # feed-dog indices, vectorised
    ixs = {}  # group -> its indices over the designs
    for g in fgroups:
        pre = "" if len(fgroups) == 1 else f"{g.name}."
        if g.name in varied or nominal or per_design_timing:
            s = sweeps[g.name]
            own = g.name in varied or nominal
            rows_g = np.arange(d) if own else np.zeros(d, dtype=int)
            x, y, vx, vy, ax, tilt, arc = fi.group_arrays(
                g.mechanism, s.observable if own else (lambda k, s=s: s.observable(k)[rows_g]))
            plate = s.params[rows_g, g.mechanism.description.role(THROAT_PLATE).index]
            n_in = cols.get("needle_in_cloth", np.full(d, np.nan))
            n_out = cols.get("needle_out_cloth", np.full(d, np.nan))
            ix = fi.feed_indices(phi, x, y, vx, vy, ax, w, plate, needle_in=n_in, needle_out=n_out,
                                 tooth_depth=options.tooth_depth, tilt=tilt, arc=arc)
            for k, e in enumerate(ix["error"]):
                if e is not None and status[k] == "ok":
                    status[k], error[k] = "FeedDogError", f"groups.{g.name}: {e}"
            if options.exact_jumps:  # the group's own designs solved; the nominal's (exact) broadcast
                ix["accel_jump"] = (_exact_jumps(g, s, status, error, ix["accel_jump"]) if own else
                                    np.repeat(base["indices"][g.name]["accel_jump"], d))
        else:
            ix = {name: np.repeat(base["indices"][g.name][name], d) for name in fi.INDICES}
        for name, (unit, factor, _) in fi.INDICES.items():
            v = np.asarray(ix[name], float) * factor
            cols[pre + fi.column(name)] = v
        ixs[g.name] = ix
    # the feed rules from the indices, when the nominal timing holds otherwise
    if machine.stitch is not None and not per_design_timing and fgroups:
        ix = ixs[fgroups[0].name]
        failed = [list(filter(None, str(f).split(";"))) for f in cols[FAILED]]
        for rule in machine.stitch.rules:
            if rule.kind not in FEED_RULES:
                continue
            val = np.degrees(np.asarray(ix[FEED_RULES[rule.kind]], float))
            lo = None if rule.lo is None else float(f"{math.degrees(rule.lo):.12g}")
            hi = None if rule.hi is None else float(f"{math.degrees(rule.hi):.12g}")
            ok = np.ones(d, bool)
            if lo is not None:
                ok &= val >= lo - 1e-9
            if hi is not None:
                ok &= val <= hi + 1e-9
            for k in range(d):
                if status[k] != "ok":
                    failed[k] = []
                    continue
                has = rule.kind in failed[k]
                if not ok[k] and not has:
                    failed[k].append(rule.kind)
                elif ok[k] and has:
                    failed[k].remove(rule.kind)
        order = [r.kind for r in machine.stitch.rules]
        failed = [sorted(f, key=order.index) for f in failed]
        cols[FAILURES] = np.array([len(f) for f in failed], dtype=float)
        cols[FAILED] = np.array([";".join(f) for f in failed], dtype=object)
    gn = _role_group(machine, NEEDLE_POINT)
    if gn is not None:
        if gn.name in varied or nominal:
            cols[NEEDLE_STROKE] = _needle_stroke(gn, sweeps[gn.name], w, h) * 1e3
        else:
            cols[NEEDLE_STROKE] = np.repeat(base["stroke"], d)
    if options.loads:
        peaks = {c: np.full(d, np.nan) for c in LOADS}
        for k in range(d):
            if status[k] != "ok":
                continue
            if not (nominal or varied) and base is not None:
                pk = base["peaks"]
            else:
                mk = with_params(machine, designs.param_changes(k)) if varied else machine
                fas = {g.name: sweeps[g.name].analysis(k if (g.name in varied or nominal) else 0)
                       for g in machine.groups}
                try:
                    pk = _peaks(MachineAnalysis(mk, phi, fas))
                except SewgenError as exc:
                    status[k], error[k] = type(exc).__name__, str(exc)
                    continue
            for c in LOADS:
                peaks[c][k] = pk[c]
        cols.update(peaks)
    for c in list(cols):
        if c in ("needle_in_cloth", "needle_out_cloth"):
            del cols[c]
    bad = status != "ok"
    for c, v in cols.items():
        if v.dtype != object:
            v[bad] = np.nan
    out = {"status": status, "error": error, "cols": cols}
    if nominal:
        if status[0] != "ok":
            raise ParameterError(machine.name, "nominal design", error[0])
        out["sweeps"] = sweeps
        out["timing"] = {c: cols[c][0] for c in (HOOK_RISE, HOOK_MARGIN, TAKE_UP, FAILURES, FAILED)
                         if c in cols}
        if machine.stitch is not None:
            out["timing"]["needle_in_cloth"] = rows[0]["needle_in_cloth"]
            out["timing"]["needle_out_cloth"] = rows[0]["needle_out_cloth"]
        out["indices"] = {g.name: {k: v[0] for k, v in ixs[g.name].items() if k != "error"} for g in fgroups}
        out["stroke"] = cols.get(NEEDLE_STROKE, [np.nan])[0]
        if options.loads:
            out["peaks"] = {c: cols[c][0] for c in LOADS}
    return out


def evaluate_chunk(machine, keys, values, options: StudyOptions):
    """One chunk of designs (``keys``: DesignKey list, ``values`` (D, k) SI) -> a DataFrame: the keys in their
    display units, ``status``, ``error`` and every quantity (:func:`quantity_columns`). A top-level function:
    it runs on a Dask worker as it runs here."""
    from sewgen.engine.frames import pandas

    pd = pandas()
    designs = MachineDesigns(machine, keys, values)
    d = len(designs)
    names = quantity_columns(machine, options)
    if designs.model_keys:  # reload the model per design
        status, error = np.full(d, "ok", dtype=object), [None] * d
        cols = {c: np.full(d, np.nan, dtype=object if c == FAILED else float) for c in names}
        for k in range(d):
            try:
                mk = designs.machine_for(k)
                r = _evaluate_fast(mk, MachineDesigns(mk, [], np.zeros((1, 0))), options, None, nominal=True)
            except SewgenError as exc:
                status[k], error[k] = type(exc).__name__, str(exc)
                continue
            for c in names:
                if c in r["cols"]:
                    cols[c][k] = r["cols"][c][0]
    else:
        base = _baseline(machine, options)
        r = _evaluate_fast(machine, designs, options, base)
        status, error, cols = r["status"], r["error"], r["cols"]
    df = designs.table()
    df["status"] = status
    df["error"] = pd.Series(error, dtype=object)
    for c in names:
        df[c] = cols[c]
    if FAILED in df:
        df[FAILED] = df[FAILED].fillna("").astype(object)
    return df

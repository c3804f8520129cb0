"""The analysis report of a machine: CSV tables per group and for the machine, and summary.json.

summary.json holds, for every quantity a designer checks (bearing loads, driving torque, the shaking force on the
frame and its moments about the x, y and z axes, every joint reaction), the peak and the RMS over the revolution with
the shaft angles where they occur; the whole machine's relative power-balance residual
(``power_balance_residual_relative``); the feed setting (stitch, regulator angle, dog travel and height above
the plate) and the cam arc switches with the acceleration jump each implies; for a machine with a ``[stitch]``
table, its stitch-formation timing (events, rule checks, thread control: sewgen.machine.timing, written out as
timing.txt too); the units of every entry and the sign conventions (``units``, ``conventions``). Numbers are
rounded to 12 significant digits (float noise such as 999.9999999999999 rpm or 255.00000000000003° is not a
result), and a non-finite number is never written: it raises :class:`NonFiniteOutputError` naming the entry.

Every force says on which body it acts, in its name and in ``acts_on``: the bearing loads, the shaking force and
moments (inertia only, −Σ m a_G) and the moving parts' weight act on the frame (``*_on_frame``); machine.csv's
``frame_force_on_parts`` is the frame's force on the moving parts (the sign convention: sewgen.machine.shaking);
a joint's reaction is on its second body from its first (group tables).

A report is written as a whole (sewgen.files.staged_folder): into a temporary folder, moved into place only when
complete, replacing the previous run's files; a run that fails leaves the folder as it was.
"""
from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

from sewgen.engine.results import write_csv
from sewgen.errors import NonFiniteOutputError
from sewgen.files import staged_folder, write_text
from sewgen.machine import shaking
from sewgen.machine.cams import arc_switches
from sewgen.machine.feed import dog_travel, has_feed, plate_height
from sewgen.machine.feed_indices import machine_indices
from sewgen.machine.modelfile import is_builtin
from sewgen.machine.parts import role_param
from sewgen.machine.peaks import ANGLE_TOL, extremes
from sewgen.machine.tables import angle_deg, group_table, machine_table
from sewgen.machine.timing import timing
from sewgen.roles import FEED_DOG, KNIFE_EDGE, LOWER_KNIFE_EDGE, STITCH_REGULATOR
from sewgen.units import DisplayUnits

#: What the numbers of summary.json mean: frame, angles, signs (the same words as
#: docs/explanation/conventions.md).
CONVENTIONS = {
    "frame": "x horizontal across the upper shaft (+ = the feed direction), y up, origin on the upper-shaft axis; "
             "z along the upper shaft from the front bearing towards the hand wheel; a group with frame = \"along\" "
             "(its plane contains the shaft) has its own x along z and its points placed by its origin; the "
             "group tables (<group>.csv) stay in each group's own plane",
    "shaft_angle": "φ, the machine's upper-shaft angle in degrees, 0 ≤ φ < 360, increasing counter-clockwise in the "
                   "x-y plane (from +x towards +y); the model's zero has the needle at its top at φ = 90°; a "
                   "group's own angle is φ + phase_deg; *_at_deg and *_deg entries are shaft angles",
    "bearings": "magnitude of the load the upper shaft puts on the frame at each bearing",
    "drive_torque": "torque the pulley puts on the upper shaft about +z, positive in the sense of rotation; "
                    "it includes the Coulomb friction the model file switches on (joints' <joint>.friction, "
                    "shaft.bearing_friction); none by default (ideal joints, the seeds' assumption)",
    "friction": "power dissipated by Coulomb friction (≥ 0); no_load_torque: the mean driving torque over a turn "
                "at the analysis' speed with the process loads off (seed 000's no-load driving torque)",
    "joints": "magnitude of a joint's reaction: the force on the joint's second body from its first",
    "shaking_force_on_frame": "magnitude of the force the moving parts put on the frame by their inertia, "
                              "−Σ m·a_G: inertia only, the parts' weight apart (weight_on_frame, Σ m·g); process "
                              "loads (thread, presser foot, cloth) react inside the machine and are left out",
    "shaking_moments_on_frame": "of the same inertia forces on the frame, −Σ [(r_G − O) × m·a_G + I·α], about the "
                                "x, y and z axes through the origin",
    "frame_force_on_parts": "machine.csv: the frame's force on the moving parts through its joints and bearings, "
                            "Σ m·a_G − Σ m·g − Σ loads − belt pull; shaking_force_on_frame + weight_on_frame = "
                            "−(frame_force_on_parts + Σ loads + belt pull)",
    "extremes": f"max, min and their *_at_deg are the machine's own values between the samples, not the "
                f"largest sample: every sampled local extreme near the largest is bracketed by its neighbours and "
                f"the machine solved again inside until the bracket is narrower than {math.degrees(ANGLE_TOL):g}°; "
                f"*_at_deg to 0.01°; *_how: \"refined\", \"at a switch\" (the one-sided limit at a cam-arc switch "
                f"or a load window's edge, where the forces jump) or \"sampled\" (an analysis that cannot be solved "
                f"again at other angles); rms: over the samples",
    "power_balance_residual_relative": "max over the revolution of |P_drive + P_loads − dE/dt| divided by the "
                                       "largest |P_drive| or |dE/dt| (E: kinetic + potential energy): 0 for an "
                                       "exact analysis",
}
#: Units of summary.json's entries (every statistic also carries its own "unit").
UNITS = {"angles": "deg", "speed_rpm": "rpm (revolutions per minute)", "forces": "N", "torques": "N*m",
         "moments": "N*m", "powers": "W", "lengths": "mm (keys ending in _mm)",
         "power_balance_residual_relative": "1 (a ratio)"}
#: Significant digits kept in summary.json.
DIGITS = 12


def _clean(value, key: str = "summary", file: str | None = None):
    """``value`` (nested dicts, lists, numbers) with every float rounded to :data:`DIGITS` significant digits and
    -0.0 made 0.0; a non-finite number raises :class:`NonFiniteOutputError` naming its key."""
    if isinstance(value, dict):
        return {k: _clean(v, f"{key}.{k}", file) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v, f"{key}[{i}]", file) for i, v in enumerate(value)]
    if isinstance(value, (bool, np.bool_)) or value is None or isinstance(value, str):
        return value
    if isinstance(value, (int, np.integer)):
        return int(value)
    v = float(value)
    if not math.isfinite(v):
        raise NonFiniteOutputError(key, v, file)
    v = float(f"{v:.{DIGITS}g}")
    if v == 0.0:
        return 0.0
    if "deg" in key.rsplit(".", 1)[-1] and abs(v - 360.0) < 1e-9:  # an angle in [0, 360)
        return 0.0
    return v


def _check_columns(cols: dict, table: str, file: str | None) -> dict:
    for name, values in cols.items():
        arr = np.asarray(values)
        if arr.dtype.kind == "f" and not np.isfinite(arr).all():
            bad = arr[~np.isfinite(arr)][0]
            raise NonFiniteOutputError(f"{table}: {name}", bad, file)
    return cols


def _rms(values: np.ndarray) -> float:
    """RMS without overflow: large values are scaled before squaring."""
    scale = float(np.max(np.abs(values))) if len(values) else 0.0
    if not math.isfinite(scale) or scale == 0.0:
        return scale
    return scale * float(np.sqrt(np.mean(np.square(values / scale))))


def _stat(values: np.ndarray, ext: dict, unit: str) -> dict:
    """Largest and least value with their shaft angles and how they were found (``ext``: sense -> Extreme,
    sewgen.machine.peaks), and the RMS over the samples."""
    hi, lo = ext["max"], ext["min"]
    return {"unit": unit, "max": hi.value, "max_at_deg": hi.deg, "max_how": hi.how, "min": lo.value,
            "min_at_deg": lo.deg, "min_how": lo.how, "rms": _rms(values)}


class _Stats:
    """The quantities summary.json states, gathered first (key -> function of an analysis, unit), their extremes
    refined together in one search (sewgen.machine.peaks.extremes), then read back by key."""

    def __init__(self, a):
        self.a, self.quantities, self.units, self.ext = a, {}, {}, None

    def add(self, key: str, quantity, unit: str) -> None:
        self.quantities[key], self.units[key] = quantity, unit

    def __call__(self, key: str) -> dict:
        if self.ext is None:
            self.ext = extremes(self.a, self.quantities)
        return _stat(np.asarray(self.quantities[key](self.a), dtype=float), self.ext[key], self.units[key])


def model_path(source: str, start=None) -> str:
    """The model file as summary.json names it: ``<sewgen>/models/NAME.toml`` for a built-in model, else the
    path relative to ``start`` (default: the working directory)."""
    if not source:
        return ""
    if is_builtin(source):
        return f"<sewgen>/models/{Path(source).name}"
    try:
        return Path(os.path.relpath(Path(source).resolve(), Path(start or os.getcwd()).resolve())).as_posix()
    except ValueError:  # another drive (Windows)
        return Path(source).as_posix()


def summary(a, switches: dict | None = None, timing=None) -> dict:
    """Peaks, RMS and where they occur; the power-balance residual; feed setting; cam arc switches; the
    stitch-formation timing; units and conventions. Every peak is the machine's own value refined between the
    samples (sewgen.machine.peaks; ``*_how`` says how). Numbers rounded to :data:`DIGITS` significant digits; a
    non-finite one raises :class:`NonFiniteOutputError`."""
    phi, m = a.phi, a.machine
    weight = shaking.weight_on_frame(a)
    st = _Stats(a)
    for w in ("front", "rear"):
        st.add(f"bearings.{w}", lambda b, w=w: np.hypot(*b.bearing(w).T), "N")
    st.add("drive_torque", lambda b: b.torque, "N*m")
    st.add("drive_power", lambda b: b.drive_power, "W")
    st.add("friction.power", lambda b: b.friction_power, "W")
    st.add("shaking_force_on_frame", lambda b: np.hypot(*shaking.shaking_force_on_frame(b).T), "N")
    for k, axis in enumerate("xyz"):
        st.add(f"shaking_moments_on_frame.{axis}", lambda b, k=k: shaking.shaking_moments_on_frame(b)[:, k], "N*m")
    for g in m.groups:
        st.add(f"{g.name}.torque", lambda b, g=g.name: b.groups[g].torque("shaft"), "N*m")
        for n in a.groups[g.name].reaction_names:
            st.add(f"{g.name}.joints.{n}", lambda b, g=g.name, n=n: b.groups[g].reaction(n).magnitude, "N")
        regulator = g.mechanism.description.role_name(STITCH_REGULATOR)
        if regulator is not None:
            st.add(f"{g.name}.holding", lambda b, g=g.name, r=regulator: b.groups[g].torque(r),
                   g.mechanism.description.input(regulator).effort_unit)
    out = {
        "machine": m.name,
        "model_file": model_path(m.source),
        "speed_rpm": float(a.omega[0] * 60 / (2 * math.pi)),
        "positions": int(len(phi)),
        "step_deg": 360.0 / len(phi),
        "power_balance_residual_relative": a.power_balance_residual,
        "bearings": {w: dict(st(f"bearings.{w}"), acts_on="frame") for w in ("front", "rear")},
        "drive_torque": st("drive_torque"),
        "drive_power": st("drive_power"),
        "friction": friction_summary(a, st("friction.power")),
        "shaking_force_on_frame": dict(st("shaking_force_on_frame"), acts_on="frame",
                                       what="-sum(m a_G): inertia only, the weight apart"),
        "weight_on_frame": {"unit": "N", "acts_on": "frame", "fx": float(weight[0]), "fy": float(weight[1]),
                            "magnitude": float(np.hypot(*weight))},
        "shaking_moments_on_frame": {axis: dict(st(f"shaking_moments_on_frame.{axis}"), acts_on="frame",
                                                about="origin") for axis in "xyz"},
        "groups": {},
    }
    if m.stitch is not None:
        timing = timing or timing_of(a)
    indices = machine_indices(m, timing, switches=switches)  # seed 001 §五.3, on the timing sweep
    for g in m.groups:
        fa = a.groups[g.name]
        entry = {"mechanism": g.mechanism.name, "phase_deg": math.degrees(g.phase),
                 "torque": st(f"{g.name}.torque"),
                 "joints": {n: st(f"{g.name}.joints.{n}") for n in fa.reaction_names}}
        regulator = g.mechanism.description.role_name(STITCH_REGULATOR)
        if regulator is not None:
            inp = g.mechanism.description.input(regulator)
            setting = g.held.get(regulator, inp.default)
            if inp.quantity == "angle":
                entry["regulator_deg"] = math.degrees(setting)
                entry["holding_torque"] = st(f"{g.name}.holding")
            else:  # a regulator set by a travel
                entry["regulator_mm"] = setting * 1e3
                entry["holding_force"] = st(f"{g.name}.holding")
        if g.stitch is not None:
            entry["stitch_mm"] = g.stitch * 1e3
        if has_feed(g.mechanism):
            t = dog_travel(fa.motion, plate_height(g.mechanism, g.params or None))
            entry[FEED_DOG] = {"travel_above_plate_mm": t.travel * 1e3, "height_above_plate_mm": t.height * 1e3,
                               "rises_at_deg": float(angle_deg(t.rise - g.phase)),
                               "sinks_at_deg": float(angle_deg(t.sink - g.phase))}
        if g.name in indices:
            entry.setdefault(FEED_DOG, {})["indices"] = indices[g.name]
        d = g.mechanism.description
        if d.has_role(KNIFE_EDGE) and d.has_role(LOWER_KNIFE_EDGE):  # overlock knife: stroke and cutting overlap
            ky = fa.motion.point(d.role_name(KNIFE_EDGE)).y
            lower = role_param(g, LOWER_KNIFE_EDGE)
            k = int(np.argmin(ky))
            entry[KNIFE_EDGE] = {"stroke_mm": float(np.ptp(ky)) * 1e3, "overlap_mm": (lower - float(ky[k])) * 1e3,
                                 "lowest_at_deg": float(angle_deg(phi[k]))}
        if switches and switches.get(g.name):
            entry["cam_arc_switches"] = [dict(s.as_dict(), angle_deg=float(angle_deg(s.angle - g.phase)))
                                         for s in switches[g.name]]
        out["groups"][g.name] = entry
    if m.stitch is not None:  # stitch-formation timing and thread control (sewgen.machine.timing)
        out["timing"] = timing.as_dict()
    out["units"] = UNITS
    out["conventions"] = CONVENTIONS
    return _clean(out, "summary", m.source or None)


def friction_summary(a, power_stat: dict) -> dict:
    """Whether friction is on, its dissipated power (``power_stat``: its statistics, :func:`_stat`), the mean
    driving torque and the no-load torque."""
    power = a.friction_power
    on = bool(np.any(power != 0.0))
    return {"on": on, "power": dict(power_stat, mean=float(np.mean(power))),
            "mean_drive_torque": {"value": float(np.mean(a.torque)), "unit": "N*m"},
            "no_load_torque": {"value": a.no_load_torque() if on else 0.0, "unit": "N*m",
                               "speed_rpm": float(np.mean(a.omega) * 60 / (2 * math.pi))}}


def timing_of(a):
    """The stitch-formation timing (sewgen.machine.timing.Timing) of analysis ``a``'s machine at the analysis' speed."""
    return timing(a.machine, speed=float(a.omega[0]) or None)  # at rest: the events are positions; eye speeds
    # at the model's speed


def cam_switches(a) -> dict:
    """Arc switches of every group with a cam, at the analysis' speed."""
    out = {}
    for g in a.machine.groups:
        fa = a.groups[g.name]
        if any(name.endswith(".arc") for name, _ in g.mechanism.description.observables):
            out[g.name] = arc_switches(g.mechanism, fa.motion, params=g.params or None, held=g.held or None)
    return out


def write_tables(a, folder, progress=None, units: DisplayUnits | None = None) -> list[Path]:
    """machine.csv, <group>.csv for every group and summary.json into ``folder`` (which must exist), the tables
    in ``units`` (default SI; headers name the unit of every column). Everything is computed and checked
    before the first file is written."""
    folder = Path(folder)
    units = units or DisplayUnits()
    if progress:
        progress("tables", 0, 1)
    source = a.machine.source or None
    tables = {"machine.csv": _check_columns(units.table(machine_table(a)), "machine.csv", source)}
    for name, fa in a.groups.items():
        tables[f"{name}.csv"] = _check_columns(units.table(group_table(fa, a.phi)), f"{name}.csv", source)
    tm = timing_of(a) if a.machine.stitch is not None else None
    text = json.dumps(summary(a, cam_switches(a), tm), indent=2, ensure_ascii=False, allow_nan=False)
    paths = [write_csv(folder / name, cols) for name, cols in tables.items()]
    if tm is not None:
        paths.append(write_text(folder / "timing.txt", tm.table() + "\n"))
    paths.append(write_text(folder / "summary.json", text + "\n"))  # last: the report is complete
    return paths


def write_report(a, folder, progress=None, units: DisplayUnits | None = None) -> list[Path]:
    """machine.csv, <group>.csv for every group and summary.json into ``folder``, moved into place only when all
    are written, replacing the previous run's files (sewgen.files.staged_folder). Returns the paths in
    ``folder``."""
    folder = Path(folder)
    with staged_folder(folder, "folder") as tmp:
        written = write_tables(a, tmp, progress, units)
    return [folder / p.name for p in written]

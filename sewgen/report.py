"""The analysis report of a machine: CSV tables per group and for the machine, and summary.json.

summary.json holds, for every quantity a designer checks (bearing loads, driving torque, shaking force, the
shaking moment about the x, y and z axes, every joint reaction), the peak and the RMS over the revolution with
the shaft angles where they occur; the whole machine's power-balance residual (``power_balance_residual``); the feed setting (stitch,
regulator angle, dog travel and height above the plate) and the cam arc switches with the acceleration
jump each implies; and, for a machine with a ``[stitch]`` table, its stitch-formation timing (events, rule
checks, thread control: sewgen.timing, written out as timing.txt too).

Every force says on which body it acts: the bearing loads and the shaking force and moments act on the frame
(``acts_on``; the shaking ones are dynamic, −Σ m a_G, with the moving parts' weight reported apart, sewgen.shaking);
``frame_on_parts`` is the frame's reaction on the moving parts; a joint's reaction is on its second body from
its first (group tables).
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from .cams import arc_switches
from .feed import dog_travel, has_feed, plate_height
from . import shaking
from .roles import FEED_DOG, STITCH_REGULATOR
from .results import write_csv


def _deg(phi) -> np.ndarray:
    return np.degrees(phi) % 360.0


def machine_table(a) -> dict:
    """Machine-level columns: bearings, torques, shaking force and moment, powers."""
    cols = {"phi [deg]": _deg(a.phi)}
    for which in ("front", "rear"):
        b = a.bearing(which)
        cols[f"bearing_{which}_on_frame.fx [N]"], cols[f"bearing_{which}_on_frame.fy [N]"] = b[:, 0], b[:, 1]
        cols[f"bearing_{which}_on_frame.magnitude [N]"] = np.hypot(b[:, 0], b[:, 1])
    cols["drive_torque [N*m]"] = a.torque
    for name, fa in a.groups.items():
        cols[f"{name}.torque [N*m]"] = fa.torque("shaft")
    sf = shaking.shaking_force(a)  # dynamic, on the frame; the weight apart (summary.json)
    cols["shaking_on_frame.fx [N]"], cols["shaking_on_frame.fy [N]"] = sf[:, 0], sf[:, 1]
    cols["shaking_on_frame.magnitude [N]"] = np.hypot(sf[:, 0], sf[:, 1])
    moments = shaking.shaking_moments(a)
    for k, axis in enumerate("xyz"):
        cols[f"shaking_on_frame.moment_{axis} [N*m]"] = moments[:, k]
    fr = a.frame_reaction
    cols["frame_on_parts.fx [N]"], cols["frame_on_parts.fy [N]"] = fr[:, 0], fr[:, 1]
    cols["drive_power [W]"] = a.drive_power
    cols["load_power [W]"] = a.load_power
    cols["energy_rate [W]"] = a.energy_rate()
    return cols


def group_table(fa, phi) -> dict:
    """Kinematics and forces of one group, one row per machine shaft angle ``phi``."""
    cols = {"phi [deg]": _deg(phi), "group_phi [deg]": _deg(fa.phi)}
    cols.update({k: v for k, v in fa.motion.table().items() if not k.startswith("phi ")})
    cols.update({k: v for k, v in fa.table().items() if not k.startswith("phi ")})
    return cols


def _stat(values: np.ndarray, phi: np.ndarray, unit: str) -> dict:
    i, j = int(np.argmax(values)), int(np.argmin(values))
    return {"unit": unit, "max": float(values[i]), "max_at_deg": float(_deg(phi[i])), "min": float(values[j]),
            "min_at_deg": float(_deg(phi[j])), "rms": float(np.sqrt(np.mean(np.square(values))))}


def summary(a, switches: dict | None = None, timing=None) -> dict:
    """Peaks, RMS and where they occur; the power-balance residual; feed setting; cam arc switches."""
    phi, m = a.phi, a.machine
    weight, moments = shaking.weight(a), shaking.shaking_moments(a)
    out = {
        "machine": m.name,
        "model_file": m.source,
        "speed_rpm": float(a.omega[0] * 60 / (2 * math.pi)),
        "positions": int(len(phi)),
        "power_balance_residual": a.power_balance_residual,
        "bearings": {w: dict(_stat(np.hypot(*a.bearing(w).T), phi, "N"), acts_on="frame") for w in ("front", "rear")},
        "drive_torque": _stat(a.torque, phi, "N*m"),
        "drive_power": _stat(a.drive_power, phi, "W"),
        "shaking_force": dict(_stat(np.hypot(*shaking.shaking_force(a).T), phi, "N"), acts_on="frame",
                              what="-sum(m a_G): dynamic, the weight apart"),
        "weight_of_moving_parts": {"unit": "N", "acts_on": "frame", "fx": float(weight[0]), "fy": float(weight[1]),
                                   "magnitude": float(np.hypot(*weight))},
        "shaking_moment": dict(_stat(moments[:, 2], phi, "N*m"), acts_on="frame"),
        "shaking_moments_about_origin": {axis: dict(_stat(v, phi, "N*m"), acts_on="frame")
                                         for axis, v in zip("xyz", moments.T)},
        "groups": {},
    }
    for g in m.groups:
        fa = a.groups[g.name]
        entry = {"mechanism": g.mechanism.name, "phase_deg": math.degrees(g.phase),
                 "torque": _stat(fa.torque("shaft"), phi, "N*m"),
                 "joints": {n: _stat(fa.reaction(n).magnitude, phi, "N") for n in fa.reaction_names}}
        regulator = g.mechanism.description.role_name(STITCH_REGULATOR)
        if regulator is not None:
            setting = g.held.get(regulator, g.mechanism.description.input(regulator).default)
            entry["regulator_deg"] = math.degrees(setting)
            entry["holding_torque"] = _stat(fa.torque(regulator), phi, "N*m")
        if g.stitch is not None:
            entry["stitch_mm"] = g.stitch * 1e3
        if has_feed(g.mechanism):
            t = dog_travel(fa.motion, plate_height(g.mechanism, g.params or None))
            entry[FEED_DOG] = {"travel_above_plate_mm": t.travel * 1e3, "height_above_plate_mm": t.height * 1e3,
                                 "rises_at_deg": float(_deg(t.rise - g.phase)),
                                 "sinks_at_deg": float(_deg(t.sink - g.phase))}
        if switches and switches.get(g.name):
            entry["cam_arc_switches"] = [dict(s.as_dict(), angle_deg=float(_deg(s.angle - g.phase)))
                                         for s in switches[g.name]]
        out["groups"][g.name] = entry
    if m.stitch is not None:  # stitch-formation timing and thread control (sewgen.timing)
        out["timing"] = (timing or timing_of(a)).as_dict()
    return out


def timing_of(a):
    """The stitch-formation timing (sewgen.timing.Timing) of analysis ``a``'s machine at the analysis' speed."""
    from .timing import timing

    return timing(a.machine, speed=float(a.omega[0]))


def cam_switches(a) -> dict:
    """Arc switches of every group with a cam, at the analysis' speed."""
    out = {}
    for g in a.machine.groups:
        fa = a.groups[g.name]
        if any(name.endswith(".arc") for name, _ in g.mechanism.description.observables):
            out[g.name] = arc_switches(g.mechanism, fa.motion, params=g.params or None, held=g.held or None)
    return out


def write_report(a, folder, progress=None) -> list[Path]:
    """machine.csv, <group>.csv for every group and summary.json into ``folder``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    if progress:
        progress("tables", 0, 1)
    paths = [write_csv(folder / "machine.csv", machine_table(a))]
    for name, fa in a.groups.items():
        paths.append(write_csv(folder / f"{name}.csv", group_table(fa, a.phi)))
    tm = timing_of(a) if a.machine.stitch is not None else None
    text = json.dumps(summary(a, cam_switches(a), tm), indent=2, ensure_ascii=False)
    (folder / "summary.json").write_text(text + "\n", encoding="utf-8")
    paths.append(folder / "summary.json")
    if tm is not None:
        (folder / "timing.txt").write_text(tm.table() + "\n", encoding="utf-8")
        paths.append(folder / "timing.txt")
    return paths

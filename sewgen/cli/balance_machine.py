"""``sewgen balance machine MODEL``: whole-machine balancing by seed 000's three methods
(sewgen.machine.machine_balance).

Writes into ``--out`` the before/after evaluation (balance.json, bearings.csv, speeds.csv), the bearing-load
hodographs and the hodograph of the shaking force on the frame before and after (balance.png), and with
``--write-model`` the model file with the counterweights added (analysable as it is: ``sewgen analyze
balanced.toml``).
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from sewgen.cli.common import Console, UsageError, outside_code_option
from sewgen.engine.results import write_csv
from sewgen.files import check_file, check_folder, staged_folder, write_text
from sewgen.units import UnitError, to_si

SPEEDS_HELP = "speeds to evaluate at, e.g. \"600 rpm,900 rpm,1200 rpm,1500 rpm\" (default: 60 %%, 100 %%, 150 %% of rated)"


def add_arguments(p) -> None:
    """The machine-balancing options (the ``balance`` command's target ``machine``)."""
    g = p.add_argument_group("balance machine MODEL (seed 000 part 2: whole-machine balancing)")
    g.add_argument("--method", choices=["separate", "harmonic", "bearings"], default="bearings",
                   help="separate: each group by itself (seed 002's objective); harmonic: cancel the first order "
                   "of the shaking force and moments on the frame; bearings: minimise the bearing loads (default)")
    g.add_argument("--objective", choices=["peak", "rms"], default="peak", help="bearings: peak or RMS (default peak)")
    g.add_argument("--shaking-weight", default="0", metavar="W",
                   help="bearings: add W × the peak (or RMS) of the shaking force on the frame to the objective "
                        "(default 0)")
    g.add_argument("--first-order", choices=["forward", "x", "y"], default="forward",
                   help="harmonic: cancel the forward-rotating first order (default), or the first order along x or "
                   "y completely (primary balance along a line of stroke)")
    g.add_argument("--out", metavar="DIR", help="write balance.json, bearings.csv, speeds.csv and balance.png here "
                                                "(written whole, replacing the run that wrote DIR before)")
    g.add_argument("--write-model", metavar="FILE", help="write the model file with the counterweights added "
                                                         "(written whole; it may be the model file itself)")
    g.add_argument("--speeds", metavar="LIST", help=SPEEDS_HELP)
    outside_code_option(g)


def _speeds(text, rated: float) -> list[float]:
    """rpm values from "600 rpm,900 rpm" (each with its unit), or 60/100/150 % of the rated speed."""
    if not text:
        rpm = rated * 60 / (2 * math.pi)
        return [round(0.6 * rpm), round(rpm), round(1.5 * rpm)]
    out = []
    for item in text.split(","):
        try:
            w = to_si(item.strip(), "speed", "--speeds")
        except UnitError as exc:
            raise UsageError("--speeds", exc.problem) from None
        if not w > 0:
            raise UsageError("--speeds", f"{item.strip()!r} must be positive")
        out.append(w * 60 / (2 * math.pi))
    return out


def run(args, con: Console) -> int:
    from sewgen.machine import machine_balance as mb
    from sewgen.machine.assembly import load_machine

    if not args.model:
        raise UsageError("", "name the model file: sewgen balance machine MODEL")
    try:
        weight = float(args.shaking_weight)
    except ValueError:
        raise UsageError("--shaking-weight", f"a number, got {args.shaking_weight!r}") from None
    if not (math.isfinite(weight) and weight >= 0):
        raise UsageError("--shaking-weight", f"must be a number >= 0, got {args.shaking_weight!r}")
    if args.out:
        check_folder(args.out, "--out")
    if args.write_model:
        check_file(args.write_model, "--write-model")
    machine = load_machine(args.model, allow_outside_code=args.allow_outside_code)
    speeds = _speeds(args.speeds, machine.speed)
    report = mb.balance(machine, args.method, args.objective, weight, speeds_rpm=speeds,
                        first_order=args.first_order)
    result = report.as_dict()
    result["model"] = str(args.model)
    text = None
    if args.write_model:
        text = mb.model_text(Path(machine.source).read_text(encoding="utf-8"), report.solution.counterweights,
                             machine.source)
        result["written_model"] = str(args.write_model)
    if args.out:  # the folder first, the model file last: a model file written means every output was
        _write(Path(args.out), report, result)
    if text is not None:
        write_text(args.write_model, text, "--write-model")
    if args.json:
        con.say(json.dumps(result, indent=2))
    else:
        _print(result, con)
    return 0


def _print(r: dict, con: Console) -> None:
    head = f"{r['method']}" + (f" ({r['objective']})" if r["objective"] else "")
    con.say(f"balance by {head}: solver {r['solver']['status']}"
            + (f", gap {abs(r['solver']['gap']):.1e}" if r["solver"]["gap"] is not None else ""))
    for c in r["counterweights"]:
        con.say(f"  {c['name']}: m·r {c['mr'] * 1e6:.0f} g·mm at {math.degrees(c['angle']):.1f}° from the crank, "
                f"{c['mass'] * 1e3:.1f} g at {c['radius'] * 1e3:.1f} mm, z {c['z'] * 1e3:.1f} mm")
    rows = [("front bearing peak [N]", "bearing_front_peak"), ("rear bearing peak [N]", "bearing_rear_peak"),
            ("front bearing RMS [N]", "bearing_front_rms"), ("rear bearing RMS [N]", "bearing_rear_rms"),
            ("shaking force on frame peak [N]", "shaking_force_on_frame_peak"),
            ("shaking moment on frame x peak [N*m]", "shaking_moment_on_frame_x_peak"),
            ("shaking moment on frame y peak [N*m]", "shaking_moment_on_frame_y_peak"),
            ("driving torque peak [N*m]", "torque_peak")]
    con.say(f"  {'':42s} {'before':>10s} {'after':>10s}   (every {r['before']['step_deg']:g}°; peaks refined "
            "between the positions, at φ before -> after)")
    for label, key in rows:
        line = f"  {label:42s} {r['before'][key]:10.3f} {r['after'][key]:10.3f}"
        if key in r["before"]["peak_at_deg"]:
            line += f"   {_at(r['before'], key)} -> {_at(r['after'], key)}"
        con.say(line)
    for name, key in (("shaking force on frame orders 1-3 [N]", "shaking_force_on_frame_orders"),):
        b = ", ".join(f"{v:.2f}" for v in r["before"][key])
        a = ", ".join(f"{v:.2f}" for v in r["after"][key])
        con.say(f"  {name}: {b} -> {a}")


def _at(m: dict, key: str) -> str:
    how = m["peak_how"][key]
    return f"{m['peak_at_deg'][key]:.2f}°" + ("" if how == "refined" else f" ({how})")


def _write(folder: Path, report, result: dict) -> None:
    """balance.json, bearings.csv, speeds.csv and balance.png into ``folder``, written whole
    (sewgen.files.staged_folder)."""
    with staged_folder(folder, "--out") as tmp:
        _write_files(tmp, report, result)


def _write_files(folder: Path, report, result: dict) -> None:
    write_text(folder / "balance.json", json.dumps(result, indent=2) + "\n")
    cols = {"phi [deg]": np.degrees(report.before.phi)}
    for tag, a in (("before", report.before), ("after", report.after)):
        for which in ("front", "rear"):
            load = a.bearing(which)
            cols[f"{which}_{tag}.fx [N]"], cols[f"{which}_{tag}.fy [N]"] = load[:, 0], load[:, 1]
            cols[f"{which}_{tag}.magnitude [N]"] = np.hypot(*load.T)
    write_csv(folder / "bearings.csv", cols)
    keys = ("bearing_front_peak", "bearing_rear_peak", "bearing_front_rms", "bearing_rear_rms",
            "shaking_force_on_frame_peak")
    speed_cols = {"speed [rpm]": np.array([s["rpm"] for s in result["speeds"]], dtype=float)}
    for tag in ("before", "after"):
        for k in keys:
            speed_cols[f"{k}_{tag} [N]"] = np.array([s[tag][k] for s in result["speeds"]])
    write_csv(folder / "speeds.csv", speed_cols)
    _plot(folder / "balance.png", report, result)


def _plot(path: Path, report, result: dict) -> None:
    """Hodographs of the front and rear bearing loads and of the shaking force on the frame, before and after; the
    peaks the legends state are the report's (refined between the samples)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from sewgen.report.plots.common import save

    fig, axes = plt.subplots(1, 3, figsize=(15, 5.4))
    for ax, (title, get, key) in zip(axes, (
            ("front bearing load (shaft on frame)", lambda a: a.bearing("front"), "bearing_front_peak"),
            ("rear bearing load (shaft on frame)", lambda a: a.bearing("rear"), "bearing_rear_peak"),
            ("shaking force on the frame, −Σ m a_G", lambda a: a.shaking_force_on_frame,
             "shaking_force_on_frame_peak"))):
        for tag, a, style in (("before", report.before, dict(color="0.55", ls="--")),
                              ("after", report.after, dict(color="C3"))):
            v = get(a)
            v = np.vstack([v, v[:1]])
            ax.plot(v[:, 0], v[:, 1], label=f"{tag}: peak {result[tag][key]:.1f} N at φ = "
                    f"{result[tag]['peak_at_deg'][key]:.1f}°", lw=1.6, **style)
        ax.plot([0], [0], marker="+", color="k", ms=10)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("x (N)")
        ax.set_ylabel("y (N)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
    name = report.before.machine.name
    method = report.method + (f", {report.objective}" if report.objective else "")
    fig.suptitle(f"{name}: balancing by {method} — load vectors over one revolution "
                 f"at {report.before.machine.speed * 60 / (2 * math.pi):.0f} rpm", fontsize=12)
    fig.tight_layout()
    try:
        save(fig, path, dpi=110)
    finally:
        plt.close(fig)

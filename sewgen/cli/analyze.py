"""``sewgen analyze``: a whole machine from its model file, written whole into an output folder (tables,
summary.json, timing.txt, plots, the GIF), and its verdict on the timing rules (exit status 3 where one fails)."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from sewgen.cli.common import RULES_FAIL, Console, UsageError, display_units, quantity
from sewgen.files import check_folder, staged_folder
from sewgen.machine.assembly import load_machine
from sewgen.report.outputs import write_tables
from sewgen.units import steps_per_turn


def cmd_analyze(args, con: Console) -> int:
    units = display_units(args)
    step = quantity(args.step, "angle", "--step")
    if step is not None and steps_per_turn(step)[0] is None:
        raise UsageError("--step", steps_per_turn(step)[1])
    speed = quantity(args.speed, "speed", "--speed", "positive")
    if args.out is not None:  # before the model is loaded (a declaration file compiled)
        check_folder(args.out, "--out")
    machine = load_machine(args.model, allow_outside_code=args.allow_outside_code)
    out = Path(args.out) if args.out is not None else Path(machine.name.lower())
    if args.out is None:
        check_folder(out, "--out")
    phi = machine.shaft_angles(step)
    w = machine.speed if speed is None else speed
    head = (f"{machine.name}: {len(phi)} positions every {360 / len(phi):g}° at {w * 30 / math.pi:.6g} rpm"
            + (" (the model's speed; --speed to change)" if speed is None else ""))
    con.note(f"{head} -> {out}/")
    with np.errstate(all="ignore"):  # non-finite results are refused by name, not warned about
        analysis = machine.analyze(phi, speed=speed, progress=con.progress)
    with np.errstate(all="ignore"), staged_folder(out, "--out") as tmp:
        plots = None
        if not args.no_plots:  # the plotting child is forked first: it draws while the tables are written here
            import gc

            from sewgen.report.plots import import_drawing, start_all

            import_drawing()
            if args.process_ends:
                # what is alive now (the modules, matplotlib's among them, and the analysis) lives until the
                # process ends with this command, so the collector skips it from here on — in the collections
                # that drawing triggers (in both processes) and in the one at exit.
                # Not when called in-process (main(argv)): garbage waiting for a collection would stay for good.
                gc.freeze()
            plots = start_all(analysis, tmp, progress=con.progress, gif=not args.no_gif, curves=analysis.refined())
        try:
            files = write_tables(analysis, tmp, progress=con.progress, units=units)
            if plots is not None:
                files += plots.finish()
        finally:
            if plots is not None:
                plots.cancel()
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    con.say(head)
    torque, bearings = summary["drive_torque"], summary["bearings"]
    con.say(f"power balance residual (relative) {summary['power_balance_residual_relative']:.3g}; "
            f"drive torque {_at(torque, 'min')} .. {_at(torque, 'max')} (RMS {torque['rms']:.4g} N*m, "
            f"{_friction_words(summary['friction'])}); bearings' peaks front {_at(bearings['front'], 'max')}, "
            f"rear {_at(bearings['rear'], 'max')}; shaking force on the frame peak "
            f"{_at(summary['shaking_force_on_frame'], 'max')} ({_how_words(summary)})")
    for f in files:
        con.say(f"wrote {out / Path(f).name}")
    return verdict(machine.name, summary.get("timing"), con)


def verdict(name: str, timing: dict | None, con: Console) -> int:
    """The machine's verdict on its timing rules (summary.json's ``timing``): how many pass on stdout, each
    failing rule with its message on stderr; the exit status (:data:`RULES_FAIL` where one fails)."""
    if not timing or not timing["checks"]:
        return 0
    checks = timing["checks"]
    failed = [c for c in checks if not c["ok"]]
    con.say(f"timing: {len(checks) - len(failed)} of {len(checks)} rules pass"
            + (f"; failing: {', '.join(c['rule'] for c in failed)} (timing.txt)" if failed else ""))
    for c in failed:
        con.warn(f"{name} fails the timing rule {c['message']}")
    return RULES_FAIL if failed else 0


def _at(stat: dict, sense: str) -> str:
    """"190.1 N at φ = 192.12°" from a summary.json statistic; a peak at a switch or sampled says so."""
    how = stat[f"{sense}_how"]
    note = "" if how == "refined" else f" ({how})"
    return f"{stat[sense]:.4g} {stat['unit']} at φ = {stat[f'{sense}_at_deg']:.2f}°{note}"


def _how_words(summary: dict) -> str:
    hows = {s[f"{k}_how"] for s in (summary["drive_torque"], summary["bearings"]["front"],
                                     summary["bearings"]["rear"], summary["shaking_force_on_frame"])
            for k in ("max", "min")}
    return ("extremes sampled: the analysis cannot be solved between its positions" if hows == {"sampled"}
            else "extremes refined between the positions")


def _friction_words(friction: dict) -> str:
    if not friction["on"]:
        return "friction left out"
    return (f"friction {friction['power']['mean']:.4g} W mean, no-load torque "
            f"{friction['no_load_torque']['value']:.4g} N*m")

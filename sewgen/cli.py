"""The ``sewgen`` command: list the catalog, show parameters, run a kinematic sweep to a table and CSV."""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from . import balance_cli, catalog, load, mechanism
from .errors import SewgenError
from .loads import Load
from .mechanism import Mechanism
from .units import UnitError, to_si


def _pairs(items: list[str], what: str) -> dict:
    out = {}
    for item in items or []:
        key, sep, val = item.partition("=")
        if not sep or not key:
            raise SystemExit(f"sewgen: {what} {item!r} must be NAME=VALUE")
        out[key.strip()] = val.strip()
    return out


def _mechanism(args) -> Mechanism:
    if args.file and args.name:
        raise SewgenError(f"give a catalog mechanism ({args.name!r}) or --file, not both")
    if args.file:
        return load(Path(args.file))
    if not args.name:
        raise SewgenError(f"name a catalog mechanism ({', '.join(catalog())}) or give --file my_mechanism.py")
    return mechanism(args.name)


def cmd_list(args) -> int:
    for name in catalog():
        m = mechanism(name)
        title = m.doc.splitlines()[0] if m.doc else ""
        print(f"{name:12s} {title}")
        print(f"{'':12s} coordinates: {', '.join(m.coord_names)}; points: {', '.join(m.point_names)}")
    return 0


def cmd_params(args) -> int:
    m = _mechanism(args)
    print(f"{m.name}: {len(m.param_names)} parameters (SI default, declared unit)")
    d = m.description
    for p in d.params:
        role = f"  (role {p.role})" if p.role else ""
        print(f"  {p.name:24s} {p.default:>12.6g} {p.unit:8s} [{p.display_unit}]  {p.doc}{role}")
    for i in d.held_inputs:
        role = f"  (role {i.role})" if i.role else ""
        print(f"  held {i.name:19s} {i.default:>12.6g} {i.unit:8s} [{i.display_unit}]  {i.doc}{role}")
    for b in d.branches:
        print(f"  branch {b.joint:17s} default {b.default:+d}  {b.meaning}")
    if d.roles:
        print("  roles: " + ", ".join(f"{role} = {kind} {name}" for role, (kind, name) in sorted(d.roles.items())))
    return 0


def _extreme(values: np.ndarray, phi: np.ndarray, fn) -> str:
    i = int(fn(values))
    return f"{values[i]:12.6g} @ {math.degrees(phi[i]):6.1f}°"


def cmd_kinematics(args) -> int:
    m = _mechanism(args)
    phi = _sweep_angles(args)
    n, step = len(phi), 360.0 / len(phi)
    motion = m.solve(phi, speed=args.speed, params=_pairs(args.param, "--param"),
                     branch={k: int(v) for k, v in _pairs(args.branch, "--branch").items()}, newton=args.newton)
    print(f"{m.name}: {n} positions every {step:g}°, speed {motion.omega[0]:.6g} rad/s")
    print(f"{'point':16s} {'x range (m)':>22s} {'y range (m)':>22s} {'peak |v| (m/s)':>26s} {'peak |a| (m/s²)':>26s}")
    for name in motion.point_names:
        pt = motion.point(name)
        speed, acc = np.hypot(pt.vx, pt.vy), np.hypot(pt.ax, pt.ay)
        print(f"{name:16s} {pt.x.min():10.5f} {pt.x.max():10.5f}  {pt.y.min():10.5f} {pt.y.max():10.5f} "
              f"{_extreme(speed, phi, np.argmax)} {_extreme(acc, phi, np.argmax)}")
    for name in motion.coord_names:
        c = motion.coord(name)
        print(f"{name:24s} [{c.unit}] min {_extreme(c.value, phi, np.argmin)}  max {_extreme(c.value, phi, np.argmax)}")
    if args.csv:
        motion.to_csv(args.csv)
        print(f"wrote {args.csv}")
    return 0


def _load(text: str) -> Load:
    """ "AT fx=.. fy=.. torque=.. from=.. to=.." -> Load (quantities with units)."""
    at, *pairs = text.split()
    kw, window = {}, {}
    for item in pairs:
        key, sep, val = item.partition("=")
        if not sep or key not in ("fx", "fy", "torque", "from", "to"):
            raise SystemExit(f"sewgen: --load {text!r}: expected AT fx=.. fy=.. torque=.. from=.. to=.., got {item!r}")
        (window if key in ("from", "to") else kw)[key] = val
    if len(window) == 1:
        raise SystemExit(f"sewgen: --load {text!r}: give both from= and to= for a window")
    return Load(at, window=(window["from"], window["to"]) if window else None, **kw)


def _option(text: str | None, kind: str, option: str) -> float | None:
    """A command-line quantity in SI (None when not given); a bad unit ends the command naming the option."""
    if text is None:
        return None
    try:
        return to_si(text, kind, option)
    except UnitError as exc:
        raise SystemExit(f"sewgen: {exc}") from None


def _sweep_angles(args) -> np.ndarray:
    step = math.degrees(_option(args.step, "angle", "--step"))
    start = math.degrees(_option(args.start, "angle", "--start"))
    if not step > 0:
        raise SystemExit("sewgen: --step must be positive")
    return np.radians(start + step * np.arange(int(round(360.0 / step))))


def _number_or_quantity(text: str):
    """A bare number on the command line is SI (like a number in the API); anything else keeps its unit."""
    try:
        return float(text)
    except ValueError:
        return text


def _rms(v: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(v))))


def cmd_forces(args) -> int:
    m = _mechanism(args)
    phi = _sweep_angles(args)
    fa = m.kinetostatics(phi, speed=args.speed, params=_pairs(args.param, "--param"),
                         branch={k: int(v) for k, v in _pairs(args.branch, "--branch").items()}, newton=args.newton,
                         loads=[_load(t) for t in args.load or []], gravity=_number_or_quantity(args.gravity))
    print(f"{m.name}: {len(phi)} positions, speed {fa.motion.omega[0]:.6g} rad/s, gravity {args.gravity}")
    print(f"{'joint':22s} {'peak |F| (N)':>26s} {'RMS |F| (N)':>12s}")
    for name in fa.reaction_names:
        mag = fa.reaction(name).magnitude
        print(f"{name:22s} {_extreme(mag, phi, np.argmax)} {_rms(mag):12.6g}")
    for name in [i.name for i in m.description.inputs]:
        tau = fa.torque(name)
        print(f"torque {name:15s} min {_extreme(tau, phi, np.argmin)}  max {_extreme(tau, phi, np.argmax)}"
              f"  RMS {_rms(tau):.6g} N*m")
    shake = np.hypot(*fa.shaking_force.T)
    print(f"{'shaking force':22s} {_extreme(shake, phi, np.argmax)} {_rms(shake):12.6g}")
    moment = np.abs(fa.shaking_moment)
    print(f"{'shaking moment (N*m)':22s} {_extreme(moment, phi, np.argmax)} {_rms(moment):12.6g}")
    if args.csv:
        fa.to_csv(args.csv)
        print(f"wrote {args.csv}")
    return 0


def _progress(message: str, done: int, total: int) -> None:
    print(f"  [{done + 1}/{total}] {message}", file=sys.stderr, flush=True)


def cmd_analyze(args) -> int:
    from .machine import load_machine
    from .report import write_report

    machine = load_machine(args.model)
    phi = machine.shaft_angles(_option(args.step, "angle", "--step"))
    speed = _option(args.speed, "speed", "--speed")
    out = Path(args.out or machine.name.lower())
    print(f"{machine.name}: {len(phi)} positions at {(speed or machine.speed) * 30 / math.pi:.6g} rpm "
          f"-> {out}/", file=sys.stderr)
    analysis = machine.analyze(phi, speed=speed, progress=_progress)
    files = write_report(analysis, out, progress=_progress)
    if not args.no_plots:
        from .plots import write_all

        files += write_all(analysis, out, progress=_progress, gif=not args.no_gif)
    summary = json.loads((out / "summary.json").read_text())
    print(f"power balance residual {summary['power_balance_residual']:.3g}; "
          f"drive torque {summary['drive_torque']['min']:.4g} .. {summary['drive_torque']['max']:.4g} N*m "
          f"(RMS {summary['drive_torque']['rms']:.4g}); bearings front {summary['bearings']['front']['max']:.4g} N, "
          f"rear {summary['bearings']['rear']['max']:.4g} N peak; shaking force {summary['shaking_force']['max']:.4g} N peak")
    for f in files:
        print(f"wrote {f}")
    return 0


def cmd_timing(args) -> int:
    """Stitch-formation timing of a machine: the event table and every rule's margin (exit 1 if one fails)."""
    from .machine import load_machine
    from .timing import timing

    machine = load_machine(args.model)
    tm = timing(machine, speed=_option(args.speed, "speed", "--speed"))
    print(json.dumps(tm.as_dict(), indent=2, ensure_ascii=False) if args.json else tm.table())
    if args.plots:
        from .plots.cycle import write_timing_plots

        for path in write_timing_plots(tm, Path(args.plots)):
            print(f"wrote {path}", file=sys.stderr)
    return 0 if tm.ok else 1


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="sewgen", description="Sewing-machine mechanism analysis.")
    sub = ap.add_subparsers(dest="command", required=True)
    sub.add_parser("list", help="the built-in mechanisms").set_defaults(fn=cmd_list)
    for name, fn, text in (("params", cmd_params, "a mechanism's parameters"),
                           ("kinematics", cmd_kinematics, "positions, velocities, accelerations over a revolution"),
                           ("forces", cmd_forces, "joint reactions, driving torque, shaking force over a revolution")):
        p = sub.add_parser(name, help=text)
        p.add_argument("name", nargs="?", help="a catalog mechanism (sewgen list), or give --file")
        p.add_argument("--file", help="a user mechanism: a .py file with declare()")
        p.set_defaults(fn=fn)
        if name in ("kinematics", "forces"):
            p.add_argument("--speed", default=None, help='shaft speed, e.g. "1000 rpm" (default: the model\'s)')
            p.add_argument("--step", default="5 deg", help="shaft-angle step (default 5 deg: 72 positions)")
            p.add_argument("--start", default="0 deg", help="first shaft angle")
            p.add_argument("--param", action="append", help="NAME=VALUE with unit, e.g. crank='16.7 mm'")
            p.add_argument("--branch", action="append", help="JOINT=+1|-1 assembly branch")
            p.add_argument("--newton", action="store_true", help="solve by Newton even where a closed form exists")
            p.add_argument("--csv", help="write every result column to this CSV file")
        if name == "forces":
            p.add_argument("--gravity", default="9.80665 m/s**2", help="gravity along -y (0 to switch it off)")
            p.add_argument("--load", action="append",
                           help='external load "AT fx=.. fy=.. torque=.. from=.. to=..", e.g. '
                                '"thread_eye fy=-2.94N from=135deg to=155deg"')
    balance_cli.add_parser(sub)
    p = sub.add_parser("analyze", help="a whole machine: kinematics, forces, shaft bearings; tables, plots, GIF")
    p.add_argument("model", help='a built-in machine ("jb1-3") or a model file (.toml)')
    p.add_argument("--out", help="output folder (default: the machine's name)")
    p.add_argument("--step", help='shaft-angle step, e.g. "1 deg" (default: the model\'s)')
    p.add_argument("--speed", help='upper-shaft speed, e.g. "1500 rpm" (default: the model\'s)')
    p.add_argument("--no-plots", action="store_true", help="tables and summary.json only")
    p.add_argument("--no-gif", action="store_true", help="no animation")
    p.set_defaults(fn=cmd_analyze)
    p = sub.add_parser("timing", help="stitch-formation timing: events, rule margins (exit 1 if a rule fails)")
    p.add_argument("model", help='a built-in machine ("jb1-3") or a model file (.toml)')
    p.add_argument("--speed", help='upper-shaft speed for the take-up eye\'s speed, e.g. "1500 rpm"')
    p.add_argument("--json", action="store_true", help="the events and checks as JSON (summary.json's timing)")
    p.add_argument("--plots", metavar="DIR", help="also write the cycle diagram and the thread curves into DIR")
    p.set_defaults(fn=cmd_timing)
    return ap


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.fn(args)
    except (SewgenError, KeyError) as exc:
        print(f"sewgen: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # `sewgen ... | head`: the reader has gone, nothing more to say
        sys.stderr.close()
        return 0


if __name__ == "__main__":
    sys.exit(main())

"""The ``sewgen`` command: list the catalog, show parameters, sweep a mechanism to a table and CSV, analyse a
whole machine, balance the needle bar.

The contract (tests/test_cli_contract.py): every quantity option carries its unit ("5 deg", "1000 rpm", "16.7
mm"; a bare number is refused naming the option and the unit expected); a user mistake — an option, a file, a
value — ends the command with exit status 2, one line on stderr that names the culprit, and nothing on stdout;
output files are checked before the work and written whole (a temporary file or folder beside the target,
renamed into place), before anything is printed. Tables and terminal output are SI unless ``--units`` says
otherwise (``--units mm,deg``); every header names its unit.
"""
from __future__ import annotations

import argparse
import difflib
import json
import math
import os
import sys
from pathlib import Path

import numpy as np

from sewgen.cli import balance as balance_cli
from sewgen.cli.common import USAGE, Console, UsageError, quantity
from sewgen.engine.loader import catalog, load, mechanism
from sewgen.errors import SewgenError
from sewgen.version import version
from sewgen.machine.modelfile import declaration_problem
from sewgen.units import DisplayUnits, UnitError, steps_per_turn
from sewgen.engine.loads import Load

class _Parser(argparse.ArgumentParser):
    """argparse with its usage errors on one line (no usage block), exit status 2."""

    def error(self, message):
        self.exit(USAGE, f"{self.prog}: {message} (see {self.prog} --help)\n")


class _Version(argparse.Action):
    """``--version``: the version is looked up only when asked for (package metadata costs start-up time)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        print(f"sewgen {version()}")
        parser.exit()


# -- arguments -------------------------------------------------------------------------------------------------

def _units(args) -> DisplayUnits:
    try:
        return DisplayUnits.parse(getattr(args, "units", None), "--units")
    except UnitError as exc:
        raise UsageError("--units", exc.problem) from None


def catalog_name(text: str) -> str:
    """The catalog's spelling of a mechanism name: "take-up" and "take_up" both give "take_up"."""

    names = catalog()
    for cand in (text, text.replace("-", "_")):
        if cand in names:
            return cand
    close = difflib.get_close_matches(text.replace("-", "_"), names, n=1)
    hint = f" (did you mean {close[0]}?)" if close else ""
    raise UsageError("", f"no built-in mechanism {text}{hint}; the catalog has: {', '.join(names)}")


def _user_file(text: str):
    """A user's declaration file (--file), loaded; a missing file, a syntax error or an exception inside its
    ``declare()`` is one line naming the file and the line."""

    path = Path(text)
    if path.is_dir():
        raise UsageError("--file", f"{path} is a folder, not a declaration file (.py with a declare())")
    if not path.is_file():
        raise UsageError("--file", f"no such file {path}")
    if path.suffix != ".py":
        raise UsageError("--file", f"{path} is not a Python file (.py with a declare())")
    try:
        return load(path)
    except SewgenError:
        raise
    except Exception as exc:  # SyntaxError (a file that is not UTF-8 too), or raised by the file's declare()
        problem = declaration_problem(exc, path)
        if problem is None:  # not raised through the user's file: a bug of sewgen, with its traceback
            raise
        raise UsageError("--file", problem) from None


def _mechanism(args):

    if args.file and args.name:
        raise UsageError("--file", f"give a catalog mechanism ({args.name}) or --file, not both")
    if args.file:
        return _user_file(args.file)
    if not args.name:
        raise UsageError("", f"name a mechanism: one of {', '.join(catalog())} (sewgen list), or --file "
                             "my_mechanism.py")
    return mechanism(catalog_name(args.name))


def _pairs(items: list[str] | None, option: str, example: str) -> list[tuple[str, str]]:
    out = []
    for item in items or []:
        key, sep, val = item.partition("=")
        if not sep or not key.strip() or not val.strip():
            raise UsageError(option, f'"{item}" must be NAME=VALUE, e.g. {example}')
        out.append((key.strip(), val.strip()))
    return out


def _params(m, items) -> dict:
    """--param NAME=VALUE pairs, each VALUE a quantity of the parameter's kind (SI dict)."""
    specs = {p.name: p for p in m.description.params}
    out = {}
    for key, val in _pairs(items, "--param", 'crank="16.7 mm"'):
        if key not in specs:
            raise UsageError("--param", f"{m.name} has no parameter {key}; its parameters: {', '.join(specs)}")
        out[key] = quantity(val, specs[key].kind, f"--param {key}")
    return out


def _branches(m, items) -> dict:
    out = {}
    for key, val in _pairs(items, "--branch", "C=-1"):
        if key not in m.branch_names:
            raise UsageError("--branch", f"{m.name} has no branch joint {key}; its branch joints: "
                                         f"{', '.join(m.branch_names) or 'none'}")
        if val not in ("1", "+1", "-1"):
            raise UsageError("--branch", f"{key}={val}: a branch is +1 or -1")
        out[key] = int(val)
    return out


def _sweep(args) -> tuple[np.ndarray, float, float]:
    """(shaft angles, step in deg, start in deg) from --step and --start: the step must divide 360°."""
    step = quantity(args.step, "angle", "--step")
    n, problem = steps_per_turn(step)
    if n is None:
        raise UsageError("--step", problem)
    start = quantity(args.start, "angle", "--start")
    return start + (2 * math.pi / n) * np.arange(n), 360.0 / n, math.degrees(start)


def _speed(args, default: float, whose: str) -> tuple[float | None, str]:
    """(speed given or None, the words stating the speed used)."""
    speed = quantity(args.speed, "speed", "--speed", "positive")
    used = default if speed is None else speed
    words = f"{used * 30 / math.pi:.6g} rpm"
    return speed, words + ("" if speed is not None else f" ({whose} default; --speed to change)")


def _check_file(text: str | None, option: str) -> Path | None:
    """An output file's path, checked before any work: not a folder, in an existing folder."""
    if text is None:
        return None
    path = Path(text)
    if not text.strip():
        raise UsageError(option, "an empty file name")
    if path.is_dir():
        raise UsageError(option, f"{path} is a folder: give a file name, e.g. {path / 'results.csv'}")
    parent = path.absolute().parent
    if not parent.is_dir():
        raise UsageError(option, f"cannot write {path}: no folder {parent}")
    return path


def _write_table(path: Path, cols: dict, option: str) -> None:
    from sewgen.report.outputs import write_csv

    try:
        write_csv(path, cols)
    except OSError as exc:
        raise UsageError(option, f"cannot write {path}: {exc.strerror or exc}") from None


def _extreme(values: np.ndarray, phi: np.ndarray, fn) -> str:
    i = int(fn(values))
    return f"{values[i]:12.6g} @ {math.degrees(phi[i]) % 360.0:6.1f}°"


def _rms(v: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(v))))


# -- commands --------------------------------------------------------------------------------------------------

def cmd_list(args, con: Console) -> int:

    for name in catalog():
        m = mechanism(name)
        title = m.doc.splitlines()[0] if m.doc else ""
        con.say(f"{name:12s} {title}")
        con.say(f"{'':12s} coordinates: {', '.join(m.coord_names)}; points: {', '.join(m.point_names)}")
    return 0


def cmd_params(args, con: Console) -> int:
    units = _units(args)
    m = _mechanism(args)
    d = m.description
    con.say(f"{m.name}: {len(d.params)} parameters (default, unit; declared in)")
    for p in d.params:
        (value,), unit = units.convert([p.default], p.unit)
        role = f"  (role {p.role})" if p.role else ""
        con.say(f"  {p.name:24s} {value:>12.6g} {unit:9s} {p.display_unit:8s} {p.doc}{role}")
    for i in d.held_inputs:
        (value,), unit = units.convert([i.default], i.unit)
        role = f"  (role {i.role})" if i.role else ""
        con.say(f"  held {i.name:19s} {value:>12.6g} {unit:9s} {i.display_unit:8s} {i.doc}{role}")
    for b in d.branches:
        con.say(f"  branch {b.joint:17s} default {b.default:+d}  {b.meaning}")
    con.say(f"  default speed {m.default_speed * 30 / math.pi:.6g} rpm")
    if d.roles:
        con.say("  roles: " + ", ".join(f"{role} = {kind} {name}" for role, (kind, name) in sorted(d.roles.items())))
    return 0


def cmd_kinematics(args, con: Console) -> int:
    units = _units(args)
    csv = _check_file(args.csv, "--csv")
    phi, step, start = _sweep(args)
    m = _mechanism(args)
    speed, speed_words = _speed(args, m.default_speed, "the mechanism's")
    motion = m.solve(phi, speed=speed, params=_params(m, args.param), branch=_branches(m, args.branch),
                     newton=args.newton)
    if csv:
        _write_table(csv, units.table(motion.table()), "--csv")
    L, V, A = (units.of(u)[0] for u in ("m", "m/s", "m/s^2"))
    lines = [f"{m.name}: {len(phi)} positions every {step:g}° from {start:g}°, speed {speed_words}",
             f"{'point':16s} {f'x range ({L})':>22s} {f'y range ({L})':>22s} {f'peak |v| ({V})':>26s} "
             f"{f'peak |a| ({A})':>26s}"]
    for name in motion.point_names:
        pt = motion.point(name)
        x, _ = units.convert(pt.x, "m")
        y, _ = units.convert(pt.y, "m")
        v, _ = units.convert(np.hypot(pt.vx, pt.vy), "m/s")
        a, _ = units.convert(np.hypot(pt.ax, pt.ay), "m/s^2")
        lines.append(f"{name:16s} {x.min():10.5g} {x.max():10.5g}  {y.min():10.5g} {y.max():10.5g} "
                     f"{_extreme(v, phi, np.argmax)} {_extreme(a, phi, np.argmax)}")
    for name in motion.coord_names:
        c = motion.coord(name)
        value, unit = units.convert(c.value, c.unit)
        lines.append(f"{name:24s} [{unit}] min {_extreme(value, phi, np.argmin)}  "
                     f"max {_extreme(value, phi, np.argmax)}")
    if csv:
        lines.append(f"wrote {csv}")
    for line in lines:
        con.say(line)
    return 0


def _load(text: str, m):
    """ "AT fx=.. fy=.. torque=.. from=.. to=.." -> Load (quantities with units)."""
    fields = text.split()
    if not fields or "=" in fields[0]:
        raise UsageError("--load", f'"{text}": expected AT fx=.. fy=.. torque=.. from=.. to=.., e.g. '
                                   f'"POINT fy=-2.94N from=135deg to=155deg"')
    at, *pairs = fields
    kw, window = {}, {}
    kinds = {"fx": "force", "fy": "force", "torque": "torque", "from": "angle", "to": "angle"}
    for item in pairs:
        key, sep, val = item.partition("=")
        if not sep or key not in kinds:
            raise UsageError("--load", f'"{text}": expected AT fx=.. fy=.. torque=.. from=.. to=.., got {item}')
        if key in kw or key in window:
            raise UsageError("--load", f'"{text}": {key} given twice')
        value = quantity(val, kinds[key], f"--load {key}")
        (window if key in ("from", "to") else kw)[key] = value
    if len(window) == 1:
        raise UsageError("--load", f'"{text}": give both from= and to= for a window')
    return Load(at, window=(window["from"], window["to"]) if window else None, **kw)


def _all_masses_zero(m, params: dict) -> bool:
    d = m.description
    p = m.param_vector(params or None)
    index = {q.name: q.index for q in d.params}
    masses = [p[index[b.mass]] for b in d.bodies if b.mass in index]
    return bool(masses) and all(v == 0.0 for v in masses)


def cmd_forces(args, con: Console) -> int:
    units = _units(args)
    csv = _check_file(args.csv, "--csv")
    phi, step, start = _sweep(args)
    gravity = quantity(args.gravity, "acceleration", "--gravity")
    if gravity < 0:
        raise UsageError("--gravity", f'must not be negative, got "{args.gravity}" (it acts along -y)')
    m = _mechanism(args)
    speed, speed_words = _speed(args, m.default_speed, "the mechanism's")
    params = _params(m, args.param)
    loads = [_load(t, m) for t in args.load or []]
    fa = m.kinetostatics(phi, speed=speed, params=params or None, branch=_branches(m, args.branch),
                         newton=args.newton, loads=loads, gravity=gravity)
    if _all_masses_zero(m, params):
        con.warn(f"{m.name}: every body's mass is zero, so there are no inertia or gravity forces: the reactions "
                 "come from the loads alone (give masses with --param BODY.mass=\"35 g\")")
    if csv:
        _write_table(csv, units.table(fa.table()), "--csv")
    F, T = units.of("N")[0], units.of("N*m")[0]
    lines = [f"{m.name}: {len(phi)} positions every {step:g}° from {start:g}°, speed {speed_words}, gravity "
             f"{gravity:g} m/s^2 along -y",
             f"{'joint':22s} {f'peak |F| ({F}) @ φ':>26s} {f'RMS |F| ({F})':>12s}"]
    for name in fa.reaction_names:
        mag, _ = units.convert(fa.reaction(name).magnitude, "N")
        lines.append(f"{name:22s} {_extreme(mag, phi, np.argmax)} {_rms(mag):12.6g}")
    for name in [i.name for i in m.description.inputs]:
        tau, _ = units.convert(fa.torque(name), "N*m")
        lines.append(f"torque {name:15s} min {_extreme(tau, phi, np.argmin)}  max {_extreme(tau, phi, np.argmax)}"
                     f"  RMS {_rms(tau):.6g} {T}")
    on_parts, _ = units.convert(np.hypot(*fa.frame_force_on_parts.T), "N")
    lines.append(f"{f'frame on parts ({F})':22s} {_extreme(on_parts, phi, np.argmax)} {_rms(on_parts):12.6g}")
    moment, _ = units.convert(np.abs(fa.frame_moment_on_parts), "N*m")
    lines.append(f"{f'frame moment ({T})':22s} {_extreme(moment, phi, np.argmax)} {_rms(moment):12.6g}")
    if csv:
        lines.append(f"wrote {csv}")
    for line in lines:
        con.say(line)
    return 0


def cmd_analyze(args, con: Console) -> int:
    from sewgen.machine.assembly import load_machine
    from sewgen.report.outputs import check_output_folder, staged_folder, write_tables

    units = _units(args)
    step = quantity(args.step, "angle", "--step")
    if step is not None and steps_per_turn(step)[0] is None:
        raise UsageError("--step", steps_per_turn(step)[1])
    speed = quantity(args.speed, "speed", "--speed", "positive")
    if args.out is not None and not args.out.strip():
        raise UsageError("--out", "an empty folder name")
    machine = load_machine(args.model)
    out = check_output_folder(Path(args.out) if args.out is not None else Path(machine.name.lower()), "--out")
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
    con.say(f"power balance residual (relative) {summary['power_balance_residual_relative']:.3g}; "
            f"drive torque {summary['drive_torque']['min']:.4g} .. {summary['drive_torque']['max']:.4g} N*m "
            f"(RMS {summary['drive_torque']['rms']:.4g}, {_friction_words(summary['friction'])}); bearings front "
            f"{summary['bearings']['front']['max']:.4g} N, rear {summary['bearings']['rear']['max']:.4g} N peak; "
            f"shaking force on the frame {summary['shaking_force_on_frame']['max']:.4g} N peak")
    for f in files:
        con.say(f"wrote {out / Path(f).name}")
    return 0


def _friction_words(friction: dict) -> str:
    if not friction["on"]:
        return "friction left out"
    return (f"friction {friction['power']['mean']:.4g} W mean, no-load torque "
            f"{friction['no_load_torque']['value']:.4g} N*m")


def cmd_timing(args, con: Console) -> int:
    """Stitch-formation timing of a machine: the event table and every rule's margin (exit 1 if one fails)."""
    from sewgen.machine.assembly import load_machine
    from sewgen.report.outputs import check_output_folder
    from sewgen.machine.timing import timing

    speed = quantity(args.speed, "speed", "--speed", "positive")
    plots = check_output_folder(Path(args.plots), "--plots") if args.plots else None
    machine = load_machine(args.model)
    tm = timing(machine, speed=speed)
    con.say(json.dumps(tm.as_dict(), indent=2, ensure_ascii=False) if args.json else tm.table())
    if plots is not None:
        from sewgen.report.plots.cycle import write_timing_plots

        for path in write_timing_plots(tm, plots):
            con.note(f"wrote {path}")
    return 0 if tm.ok else 1


# -- the parser ------------------------------------------------------------------------------------------------

QUIET_HELP = "print nothing but errors and warnings (files are still written)"
UNITS_HELP = ('units of tables and terminal output, e.g. "mm,deg" (a unit for any of length, angle, mass, force, '
              "torque; velocities and accelerations follow; default SI: m, rad, kg, N, N*m)")


def _common(p) -> None:
    p.add_argument("-q", "--quiet", action="store_true", default=argparse.SUPPRESS, help=QUIET_HELP)


def build_parser() -> argparse.ArgumentParser:
    ap = _Parser(prog="sewgen", description="Sewing-machine mechanism analysis. Quantities carry their units "
                 '("5 deg", "1000 rpm", "16.7 mm"); results are SI unless --units says otherwise.')
    ap.add_argument("--version", action=_Version, help="print the version and exit")
    ap.add_argument("-q", "--quiet", action="store_true", help=QUIET_HELP)
    sub = ap.add_subparsers(dest="command", required=True, metavar="COMMAND")
    p = sub.add_parser("list", help="the built-in mechanisms")
    _common(p)
    p.set_defaults(fn=cmd_list)
    for name, fn, text in (("params", cmd_params, "a mechanism's parameters"),
                           ("kinematics", cmd_kinematics, "positions, velocities, accelerations over a revolution"),
                           ("forces", cmd_forces,
                            "joint reactions, driving torque, the frame's force on the parts over a revolution")):
        p = sub.add_parser(name, help=text, description=text[:1].upper() + text[1:] + ".")
        p.add_argument("name", nargs="?", help="a catalog mechanism (sewgen list; take_up or take-up), or give --file")
        p.add_argument("--file", help="a mechanism of your own: a .py file with declare()")
        p.add_argument("--units", help=UNITS_HELP)
        _common(p)
        p.set_defaults(fn=fn)
        if name in ("kinematics", "forces"):
            p.add_argument("--speed", help='shaft speed, e.g. "1000 rpm" (default: the mechanism\'s, stated in '
                                           "the output)")
            p.add_argument("--step", default="5 deg", help='shaft-angle step dividing 360°, e.g. "1 deg" (default '
                                                           '"5 deg": 72 positions; at least 0.0036 deg)')
            p.add_argument("--start", default="0 deg", help='first shaft angle, e.g. "90 deg" (default "0 deg")')
            p.add_argument("--param", action="append", metavar="NAME=VALUE",
                           help='a parameter with its unit, e.g. crank="16.7 mm" (repeatable)')
            p.add_argument("--branch", action="append", metavar="JOINT=±1", help="assembly branch, e.g. C=-1")
            p.add_argument("--newton", action="store_true", help="solve by Newton even where a closed form exists")
            p.add_argument("--csv", metavar="FILE", help="write every result column to this CSV file (headers name "
                                                         "the unit of each column)")
        if name == "forces":
            p.add_argument("--gravity", default="9.80665 m/s**2",
                           help='gravity along -y, e.g. "9.81 m/s**2" ("0 m/s**2" to switch it off)')
            p.add_argument("--load", action="append", metavar="LOAD",
                           help='external load "AT fx=.. fy=.. torque=.. from=.. to=..", e.g. '
                                '"thread_eye fy=-2.94N from=135deg to=155deg" (repeatable)')
    balance_cli.add_parser(sub, _common)
    p = sub.add_parser("analyze", help="a whole machine: kinematics, forces, shaft bearings; tables, plots, GIF",
                       description="Analyse a whole machine: tables (CSV), summary.json, plots and a GIF.")
    p.add_argument("model", help='a built-in machine ("jb1-3") or a model file (.toml)')
    p.add_argument("--out", metavar="FOLDER", help="output folder (default: the machine's name in lower case); "
                                                   "written whole or not at all")
    p.add_argument("--step", help='shaft-angle step dividing 360°, e.g. "1 deg" (default: the model\'s)')
    p.add_argument("--speed", help='upper-shaft speed, e.g. "1500 rpm" (default: the model\'s)')
    p.add_argument("--units", help=UNITS_HELP + "; summary.json stays SI with its units stated")
    p.add_argument("--no-plots", action="store_true", help="tables and summary.json only")
    p.add_argument("--no-gif", action="store_true", help="no animation")
    _common(p)
    p.set_defaults(fn=cmd_analyze)
    from sewgen.cli import study as study_cli

    study_cli.add_parser(sub, _common)
    p = sub.add_parser("timing", help="stitch-formation timing: events, rule margins (exit 1 if a rule fails)")
    p.add_argument("model", help='a built-in machine ("jb1-3") or a model file (.toml)')
    p.add_argument("--speed", help='upper-shaft speed for the take-up eye\'s speed, e.g. "1500 rpm"')
    p.add_argument("--json", action="store_true", help="the events and checks as JSON (summary.json's timing)")
    p.add_argument("--plots", metavar="DIR", help="also write the cycle diagram and the thread curves into DIR")
    _common(p)
    p.set_defaults(fn=cmd_timing)
    return ap


def _one_line(text: str) -> str:
    return " ".join(part.strip() for part in str(text).splitlines() if part.strip())


#: Options whose value may start with "-" ("-10%..+10%"): joined to their option before argparse sees them.
DASH_VALUES = ("--range",)


def _join_dash_values(argv: list) -> list:
    out, i = [], 0
    while i < len(argv):
        a = argv[i]
        if a in DASH_VALUES and i + 1 < len(argv) and str(argv[i + 1]).startswith("-"):
            out.append(f"{a}={argv[i + 1]}")
            i += 2
            continue
        out.append(a)
        i += 1
    return out


def main(argv=None) -> int:
    """Run the command ``argv`` (None: this process's own command line, ``sys.argv[1:]``); returns the exit
    status."""
    args = build_parser().parse_args(_join_dash_values(list(sys.argv[1:] if argv is None else argv)))
    args.process_ends = argv is None  # the process's own command line: it ends when the command does
    con = Console(quiet=getattr(args, "quiet", False))
    try:
        return args.fn(args, con)
    except SewgenError as exc:
        print(f"sewgen: {_one_line(exc)}", file=sys.stderr)
        return USAGE
    except KeyError as exc:  # a name not found (str(KeyError) would quote the message)
        text = exc.args[0] if exc.args and isinstance(exc.args[0], str) else str(exc)
        print(f"sewgen: {_one_line(text)}", file=sys.stderr)
        return USAGE
    except MemoryError:
        print("sewgen: out of memory: use a coarser --step (or fewer --points)", file=sys.stderr)
        return USAGE
    except KeyboardInterrupt:
        print("sewgen: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # `sewgen ... | head`: the reader has gone, nothing more to say
        try:
            sys.stdout = open(os.devnull, "w")
        except OSError:
            pass
        return 0


if __name__ == "__main__":
    sys.exit(main())

"""What every ``sewgen`` command shares: the exit status of a user mistake, its error, the console and
command-line quantities (a value with its unit, in SI)."""
from __future__ import annotations

import csv
import difflib
import math
import sys
from pathlib import Path

import numpy as np

from sewgen.files import check_file as checked_file
from sewgen.engine.loader import catalog, load, mechanism
from sewgen.engine.results import write_csv
from sewgen.errors import SewgenError
from sewgen.machine.modelfile import declaration_problem
from sewgen.units import MAX_SHAFT_ANGLE, DisplayUnits, UnitError, steps_per_turn, to_si

#: Exit status of a user mistake (a bad option, file or value: a typed error of sewgen.errors), as argparse uses
#: for usage errors.
USAGE = 2
#: Exit status of a command that did its work on a machine that fails a timing rule (``analyze``, ``timing``).
RULES_FAIL = 3
#: Exit status of a bug of sewgen (an exception that is not a typed error): its traceback is printed.
BUG = 1


class UsageError(SewgenError, ValueError):
    """A command-line mistake: ``parameter`` names the option (or argument) at fault."""

    def __init__(self, option: str, problem: str):
        super().__init__(f"{option}: {problem}" if option else problem, problem=problem, parameter=option)


class Console:
    """Where the command's words go: results on stdout (silenced by ``--quiet``); progress on stderr when it is a
    terminal (never into a log or a pipe, where a failing run must leave its one-line error alone); warnings on
    stderr always."""

    def __init__(self, quiet: bool = False, progress: bool | None = None):
        self.quiet = quiet
        if progress is None:
            try:
                progress = sys.stderr.isatty()
            except (AttributeError, ValueError):
                progress = False
        self.show_progress = progress and not quiet

    def say(self, text: str = "") -> None:
        if not self.quiet:
            print(text)

    def note(self, text: str) -> None:
        if self.show_progress:
            print(text, file=sys.stderr, flush=True)

    def warn(self, text: str) -> None:
        print(f"sewgen: warning: {text}", file=sys.stderr, flush=True)

    def progress(self, message: str, done: int, total: int) -> None:
        self.note(f"  [{done + 1}/{total}] {message}")


def quantity(text: str | None, kind: str, option: str, sign: str = ""):
    """A command-line quantity in SI (None when not given); a bad one is a UsageError naming the option."""
    if text is None:
        return None
    try:
        value = to_si(text, kind, option)
    except UnitError as exc:
        raise UsageError(option, exc.problem) from None
    if sign == "positive" and not value > 0:
        raise UsageError(option, f'must be positive, got "{text}"')
    return value


# -- arguments of several commands ---------------------------------------------------------------------------

def outside_code_option(p) -> None:
    """``--allow-outside-code`` of the commands that load a machine's model file."""
    p.add_argument("--allow-outside-code", action="store_true",
                   help="let the model file's groups name declaration files (mechanism = \"....py\": Python code "
                        "that loading the model runs) outside the model file's folder; without it only files in "
                        "that folder or below are run")


def display_units(args) -> DisplayUnits:
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


def user_file(text: str):
    """A user's declaration file (--file), loaded; a missing file, a syntax error or an exception inside its
    ``declare()`` is one line naming the file and the line."""

    path = Path(text)
    try:
        folder, found = path.is_dir(), path.is_file()
    except OSError as exc:  # a name too long for the file system, a loop of links
        raise UsageError("--file", f"cannot read {path}: {exc.strerror or exc}") from None
    if folder:
        raise UsageError("--file", f"{path} is a folder, not a declaration file (.py with a declare())")
    if not found:
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


def mechanism_of(args):

    if args.file and args.name:
        raise UsageError("--file", f"give a catalog mechanism ({args.name}) or --file, not both")
    if args.file:
        return user_file(args.file)
    if not args.name:
        raise UsageError("", f"name a mechanism: one of {', '.join(catalog())} (sewgen list), or --file "
                             "my_mechanism.py")
    return mechanism(catalog_name(args.name))


def pairs(items: list[str] | None, option: str, example: str) -> list[tuple[str, str]]:
    out = []
    for item in items or []:
        key, sep, val = item.partition("=")
        if not sep or not key.strip() or not val.strip():
            raise UsageError(option, f'"{item}" must be NAME=VALUE, e.g. {example}')
        out.append((key.strip(), val.strip()))
    return out


def params_of(m, items) -> dict:
    """--param NAME=VALUE pairs, each VALUE a quantity of the parameter's kind (SI dict)."""
    specs = {p.name: p for p in m.description.params}
    out = {}
    for key, val in pairs(items, "--param", 'crank="16.7 mm"'):
        if key not in specs:
            raise UsageError("--param", f"{m.name} has no parameter {key}; its parameters: {', '.join(specs)}")
        out[key] = quantity(val, specs[key].kind, f"--param {key}")
    return out


def branches_of(m, items) -> dict:
    out = {}
    for key, val in pairs(items, "--branch", "C=-1"):
        if key not in m.branch_names:
            raise UsageError("--branch", f"{m.name} has no branch joint {key}; its branch joints: "
                                         f"{', '.join(m.branch_names) or 'none'}")
        if val not in ("1", "+1", "-1"):
            raise UsageError("--branch", f"{key}={val}: a branch is +1 or -1")
        out[key] = int(val)
    return out


def sweep_of(args) -> tuple[np.ndarray, float, float]:
    """(shaft angles, step in deg, start in deg) from --step and --start: the step must divide 360°."""
    step = quantity(args.step, "angle", "--step")
    n, problem = steps_per_turn(step)
    if n is None:
        raise UsageError("--step", problem)
    start = quantity(args.start, "angle", "--start")
    if abs(start) > MAX_SHAFT_ANGLE:
        raise UsageError("--start", f'"{args.start}" is beyond ±{math.degrees(MAX_SHAFT_ANGLE):.6g} deg: the '
                                    f"{360.0 / n:g}° steps would drown in its rounding (give an angle within a turn)")
    return start + (2 * math.pi / n) * np.arange(n), 360.0 / n, math.degrees(start)


def speed_of(args, default: float, whose: str) -> tuple[float | None, str]:
    """(speed given or None, the words stating the speed used)."""
    speed = quantity(args.speed, "speed", "--speed", "positive")
    used = default if speed is None else speed
    words = f"{used * 30 / math.pi:.6g} rpm"
    return speed, words + ("" if speed is not None else f" ({whose} default; --speed to change)")


#: ``--csv -``: the table goes to standard output, alone (the command's text report is then not printed).
STDOUT = "-"


def check_file(text: str | None, option: str) -> Path | str | None:
    """An output table's target, checked before any work: None (not given), :data:`STDOUT` for "-", else the
    file (sewgen.files.check_file: a regular file or none yet, in an existing folder, outside sewgen's package)."""
    if text is None or text == STDOUT:
        return text
    checked_file(text, option)
    return Path(text)


def write_table(target: Path | str, cols: dict, option: str) -> None:
    """``cols`` as CSV to ``target``: a file, written whole (sewgen.engine.results.write_csv), or standard output
    (:data:`STDOUT`)."""
    if target == STDOUT:
        w = csv.writer(sys.stdout, lineterminator="\n")
        w.writerow(cols)
        w.writerows(zip(*(np.asarray(c).tolist() for c in cols.values())))
        sys.stdout.flush()
    else:
        write_csv(target, cols, option)


def extreme(values: np.ndarray, phi: np.ndarray, fn) -> str:
    i = int(fn(values))
    return f"{values[i]:12.6g} @ {math.degrees(phi[i]) % 360.0:6.1f}°"


def rms(v: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(v))))

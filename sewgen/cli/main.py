"""The ``sewgen`` command: list the catalog, show parameters, sweep a mechanism to a table and CSV, analyse a
whole machine, balance the needle bar.

The contract (tests/test_cli_contract.py): every quantity option carries its unit ("5 deg", "1000 rpm", "16.7
mm"; a bare number is refused naming the option and the unit expected); a user mistake — an option, a file, a
value: a typed error of sewgen.errors — ends the command with exit status 2, one line on stderr that names the
culprit, and nothing on stdout; an analysis or timing of a machine that fails a timing rule ends with exit status 3,
the failing rules named on stderr; any other exception is a bug of sewgen: its traceback and exit status 1
(``--debug`` shows the traceback of a mistake too). Output files are checked before the work and written whole
(sewgen.files: a temporary file or folder beside the target, renamed into place), before anything is printed.
Tables and terminal output are SI unless ``--units`` says otherwise (``--units mm,deg``); every header names its
unit.
"""
from __future__ import annotations

import argparse
import importlib
import os
import sys
import traceback

from sewgen.cli import balance as balance_cli
from sewgen.cli.common import BUG, RULES_FAIL, USAGE, Console, outside_code_option
from sewgen.errors import SewgenError
from sewgen.version import version


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


# -- the parser ------------------------------------------------------------------------------------------------

QUIET_HELP = "print nothing but errors and warnings (files are still written)"
UNITS_HELP = ('units of tables and terminal output, e.g. "mm,deg" (a unit for any of length, angle, mass, force, '
              "torque; velocities and accelerations follow; default SI: m, rad, kg, N, N*m)")


DEBUG_HELP = "on a mistake, show where it was raised (a traceback) as well as its one line"


def _common(p) -> None:
    p.add_argument("-q", "--quiet", action="store_true", default=argparse.SUPPRESS, help=QUIET_HELP)
    p.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=DEBUG_HELP)


def _command(module: str, function: str):
    """The command ``function`` of ``sewgen.cli.<module>``, imported when it runs: ``sewgen list`` loads no
    machine layer, and ``--help`` or a usage mistake none of the commands."""
    def run(args, con: Console) -> int:
        return getattr(importlib.import_module(f"sewgen.cli.{module}"), function)(args, con)

    return run


def build_parser() -> argparse.ArgumentParser:
    ap = _Parser(prog="sewgen", description="Sewing-machine mechanism analysis. Quantities carry their units "
                 '("5 deg", "1000 rpm", "16.7 mm"); results are SI unless --units says otherwise.')
    ap.add_argument("--version", action=_Version, help="print the version and exit")
    ap.add_argument("-q", "--quiet", action="store_true", help=QUIET_HELP)
    ap.add_argument("--debug", action="store_true", help=DEBUG_HELP)
    sub = ap.add_subparsers(dest="command", required=True, metavar="COMMAND")
    p = sub.add_parser("list", help="the built-in mechanisms")
    _common(p)
    p.set_defaults(fn=_command("mechanism", "cmd_list"))
    for name, text in (("params", "a mechanism's parameters"),
                       ("kinematics", "positions, velocities, accelerations over a revolution"),
                       ("forces", "joint reactions, driving torque, the frame's force on the parts over a revolution")):
        p = sub.add_parser(name, help=text, description=text[:1].upper() + text[1:] + ".")
        p.add_argument("name", nargs="?", help="a catalog mechanism (sewgen list; take_up or take-up), or give --file")
        p.add_argument("--file", help="a mechanism of your own: a .py file with declare()")
        p.add_argument("--units", help=UNITS_HELP)
        _common(p)
        p.set_defaults(fn=_command("mechanism", f"cmd_{name}"))
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
                                                         "the unit of each column); - writes the table to standard "
                                                         "output instead of the text report")
        if name == "forces":
            p.add_argument("--gravity", default="9.80665 m/s**2",
                           help='gravity along -y, e.g. "9.81 m/s**2" ("0 m/s**2" to switch it off)')
            p.add_argument("--load", action="append", metavar="LOAD",
                           help='external load "AT fx=.. fy=.. torque=.. from=.. to=..", e.g. '
                                '"thread_eye fy=-2.94N from=135deg to=155deg" (repeatable)')
    balance_cli.add_parser(sub, _common)
    p = sub.add_parser("analyze", help="a whole machine: kinematics, forces, shaft bearings; tables, plots, GIF "
                                       "(exit 3 if a timing rule fails)",
                       description="Analyse a whole machine: tables (CSV), summary.json, plots and a GIF; the verdict "
                                   "on its timing rules (exit status 3 if one fails).")
    p.add_argument("model", help='a built-in machine ("jb1-3") or a model file (.toml)')
    p.add_argument("--out", metavar="FOLDER", help="output folder (default: the machine's name in lower case); "
                                                   "written whole or not at all, replacing the files of the run "
                                                   "that wrote it before")
    p.add_argument("--step", help='shaft-angle step dividing 360°, e.g. "1 deg" (default: the model\'s)')
    p.add_argument("--speed", help='upper-shaft speed, e.g. "1500 rpm" (default: the model\'s)')
    p.add_argument("--units", help=UNITS_HELP + "; summary.json stays SI with its units stated")
    p.add_argument("--no-plots", action="store_true", help="tables and summary.json only")
    p.add_argument("--no-gif", action="store_true", help="no animation")
    outside_code_option(p)
    _common(p)
    p.set_defaults(fn=_command("analyze", "cmd_analyze"))
    from sewgen.cli import study as study_cli

    study_cli.add_parser(sub, _common)
    p = sub.add_parser("timing", help="stitch-formation timing: events, rule margins (exit 3 if a rule fails)")
    p.add_argument("model", help='a built-in machine ("jb1-3") or a model file (.toml)')
    p.add_argument("--speed", help='upper-shaft speed for the take-up eye\'s speed, e.g. "1500 rpm"')
    p.add_argument("--json", action="store_true", help="the events and checks as JSON (summary.json's timing)")
    p.add_argument("--plots", metavar="DIR", help="also write the cycle diagram and the thread curves into DIR "
                                                  "(written whole, replacing the run that wrote DIR before)")
    outside_code_option(p)
    _common(p)
    p.set_defaults(fn=_command("timing", "cmd_timing"))
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
    status: 0 done, :data:`USAGE` (2) a user's mistake (a typed error of sewgen.errors: one line on stderr),
    :data:`RULES_FAIL` (3) done but the machine fails a timing rule, 1 a bug of sewgen (its traceback on
    stderr), 130 interrupted."""
    args = build_parser().parse_args(_join_dash_values(list(sys.argv[1:] if argv is None else argv)))
    args.process_ends = argv is None  # the process's own command line: it ends when the command does
    debug = getattr(args, "debug", False)
    con = Console(quiet=getattr(args, "quiet", False))
    try:
        return args.fn(args, con)
    except SewgenError as exc:
        if debug:
            traceback.print_exc()
        print(f"sewgen: {_one_line(exc)}", file=sys.stderr)
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
    except Exception:  # not a user's mistake: a bug of sewgen, shown whole
        traceback.print_exc()
        print(f"sewgen: internal error (a bug of sewgen {version()}, not a mistake of yours): please report it "
              "with the traceback above", file=sys.stderr)
        return BUG


if __name__ == "__main__":
    sys.exit(main())

"""What every ``sewgen`` command shares: the exit status of a user mistake, its error, the console and
command-line quantities (a value with its unit, in SI)."""
from __future__ import annotations

import sys

from sewgen.errors import SewgenError
from sewgen.units import UnitError, to_si

#: Exit status of a user mistake (a bad option, file or value), as argparse uses for usage errors.
USAGE = 2


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

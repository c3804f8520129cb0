"""Typed errors: every one names the mechanism and the parameter, option, file, key or shaft angle at fault.

Each error keeps its parts as attributes — ``mechanism``, ``parameter``, ``file``, ``key``, ``angle`` (rad),
``index`` (position in the sweep) and ``problem`` (what is wrong, without the naming prefix) — so code that
re-raises an error in another context (a model file's key, a CLI option) reads ``problem`` and never splits
the message text. Attributes an error does not concern are None.
"""
from __future__ import annotations

import math


class SewgenError(Exception):
    """Base of every error sewgen raises on purpose."""

    mechanism: str | None = None
    parameter: str | None = None
    file: str | None = None
    key: str | None = None
    angle: float | None = None
    index: int | None = None

    def __init__(self, message: str, *, problem: str | None = None, **fields):
        for name, value in fields.items():
            setattr(self, name, value)
        self.problem = message if problem is None else problem
        super().__init__(message)

    def __reduce__(self):  # pickles (across processes, Dask) with its fields, whatever the subclass's signature
        return _rebuild, (type(self), self.args, self.__dict__)


def _rebuild(cls, args, state):
    err = cls.__new__(cls)
    Exception.__init__(err, *args)
    err.__dict__.update(state)
    return err


class UnitError(SewgenError, ValueError):
    """A quantity whose text cannot be read, or whose unit is not of the expected kind. ``parameter`` names
    the parameter or option it was given for."""

    def __init__(self, what: str, problem: str):
        super().__init__(f"{what}: {problem}", problem=problem, parameter=what)


class ParameterError(SewgenError, ValueError):
    """A parameter, input or option value that a mechanism cannot take."""

    def __init__(self, mechanism: str, parameter: str, message: str):
        super().__init__(f"{mechanism}: parameter {parameter!r}: {message}", problem=message, mechanism=mechanism,
                         parameter=parameter)


class RoleError(SewgenError, KeyError):
    """A machine-level analysis asked a mechanism for a part by a role that no part of it plays."""

    def __init__(self, mechanism: str, role: str, known: list):
        self.role = role
        problem = f"no part plays the role {role!r}; roles: {', '.join(known) or 'none'}"
        super().__init__(f"{mechanism}: {problem}", problem=problem, mechanism=mechanism)

    def __str__(self) -> str:  # KeyError would quote the message
        return self.args[0]


class InputError(SewgenError, ValueError):
    """Shaft angles, speeds or accelerations of the wrong shape, type or value."""

    def __init__(self, mechanism: str, message: str, parameter: str | None = None):
        super().__init__(f"{mechanism}: {message}", problem=message, mechanism=mechanism, parameter=parameter)


class BuildError(SewgenError):
    """A user mechanism that failed to derive or compile (``file``: its declaration file, if any)."""

    def __init__(self, message: str, *, mechanism: str | None = None, file: str | None = None):
        super().__init__(message, mechanism=mechanism, file=file)


class PositionError(SewgenError):
    """A shaft angle at which the mechanism cannot be solved. ``angle`` is the first such angle (rad),
    ``index`` its position in the sweep, ``count`` how many positions failed so."""

    what = "cannot be solved"

    def __init__(self, mechanism: str, angle: float, index: int, count: int, last_angle: float,
                 detail: str | None = None):
        span = "" if count == 1 else f" (first of {count} failing positions, up to {math.degrees(last_angle):.6g}°)"
        problem = f"{self.what} at shaft angle {math.degrees(angle):.6g}° (position {index}){span}"
        if detail:
            problem += f": {detail}"
        super().__init__(f"{mechanism}: {problem}", problem=problem, mechanism=mechanism, angle=angle, index=index,
                         count=count, last_angle=last_angle, detail=detail)


class AssemblyError(PositionError):
    what = "cannot assemble (the loop does not close)"


class ConvergenceError(AssemblyError):
    what = "Newton did not converge (no assembly near the previous position)"


class SingularPositionError(PositionError):
    what = "singular position (a toggle, dead centre or change point)"


class BranchJumpError(PositionError):
    what = "the solution jumped to another assembly branch"


class NonFiniteResultError(PositionError):
    what = "a result came out non-finite"


class FrictionLockError(PositionError):
    what = ("Coulomb friction did not settle (its loads feed back through the reactions about as strongly as they "
            "act, or more: a joint at or near self-locking; lower the <joint>.friction coefficients)")


class NonFiniteOutputError(SewgenError, ValueError):
    """A result that came out infinite or NaN (an absurd mass or speed in a model file overflows): never written.
    ``key`` names the entry or column, ``file`` the model file."""

    def __init__(self, key: str, value, file: str | None = None):
        problem = f"{key} came out {value} (not finite): check the model's masses, inertias and speed"
        super().__init__(f"{file}: {problem}" if file else problem, problem=problem, key=key, file=file)


class OutputPathError(SewgenError, ValueError):
    """An output file or folder that cannot be written (sewgen.files): ``file`` is the path, ``parameter`` the
    command-line option or argument that named it (None from the API), ``problem`` what is wrong — not a folder,
    not a regular file, inside sewgen's installed package, a full or read-only disk, a name too long."""

    def __init__(self, option: str, problem: str, file: str | None = None):
        super().__init__(f"{option}: {problem}" if option else problem, problem=problem, parameter=option or None,
                         file=file)

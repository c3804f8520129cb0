"""What the C runtime and Python must agree on, stated once (DESIGN.md §4, §7).

The per-position status codes of the sweeps are listed here with the typed error each becomes;
:mod:`sewgen.derive.emit` writes them into ``generated/sg_abi.h`` for the C runtime, and
:mod:`sewgen.mechanism` maps a failing position's code to its error through :func:`error_for`. Neither side
keeps a copy by hand.
"""
from __future__ import annotations

from . import errors


#: (C enumerator, code, error class or None, meaning), in code order.
STATUS = (
    ("SG_OK", 0, None, "solved"),
    ("SG_CANNOT_ASSEMBLE", 1, errors.AssemblyError,
     "the loop does not close at this input (a dyad's circles do not meet)"),
    ("SG_SINGULAR", 2, errors.SingularPositionError,
     "the constraint Jacobian or a force block is singular here (toggle / dead-centre position)"),
    ("SG_BRANCH_JUMP", 3, errors.BranchJumpError,
     "Newton landed on another assembly branch than the previous position"),
    ("SG_NAN_INPUT", 4, None, "a shaft angle, speed or acceleration is not finite (Python checks first)"),
    ("SG_NO_CONVERGENCE", 5, errors.ConvergenceError, "Newton ran out of iterations"),
    ("SG_NONFINITE", 6, errors.NonFiniteResultError,
     "a result came out non-finite (the motion kernel tests every output)"),
    ("SG_BAD_ARGUMENT", 7, None, "sizes or options out of range: nothing was computed"),
)

_ERRORS = {code: cls for _, code, cls, _ in STATUS}
_NAMES = {code: name for name, code, _, _ in STATUS}


def error_for(code: int):
    """The :class:`~sewgen.errors.PositionError` subclass of a status code; None for codes Python prevents."""
    return _ERRORS.get(code)


def status_name(code: int) -> str:
    return _NAMES.get(code, f"unknown status {code}")

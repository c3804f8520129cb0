"""Typed errors: every one names the mechanism and the parameter, option or shaft angle at fault."""
from __future__ import annotations

import math


class SewgenError(Exception):
    """Base of every error sewgen raises on purpose."""


class ParameterError(SewgenError, ValueError):
    """A parameter, input or option value that a mechanism cannot take."""

    def __init__(self, mechanism: str, parameter: str, message: str):
        self.mechanism, self.parameter = mechanism, parameter
        super().__init__(f"{mechanism}: parameter {parameter!r}: {message}")


class InputError(SewgenError, ValueError):
    """Shaft angles, speeds or accelerations of the wrong shape, type or value."""

    def __init__(self, mechanism: str, message: str):
        self.mechanism = mechanism
        super().__init__(f"{mechanism}: {message}")


class BuildError(SewgenError):
    """A user mechanism that failed to derive or compile."""


class PositionError(SewgenError):
    """A shaft angle at which the mechanism cannot be solved. ``angle`` is the first such angle (rad)."""

    what = "cannot be solved"

    def __init__(self, mechanism: str, angle: float, index: int, count: int, last_angle: float):
        self.mechanism, self.angle, self.index, self.count = mechanism, angle, index, count
        span = "" if count == 1 else f" (first of {count} failing positions, up to {math.degrees(last_angle):.6g}°)"
        super().__init__(f"{mechanism}: {self.what} at shaft angle {math.degrees(angle):.6g}°"
                         f" (position {index}){span}")


class AssemblyError(PositionError):
    what = "cannot assemble (the loop does not close)"


class ConvergenceError(AssemblyError):
    what = "Newton did not converge (no assembly near the previous position)"


class SingularPositionError(PositionError):
    what = "singular position (toggle or dead centre: the constraint Jacobian or the force matrix is singular)"


class BranchJumpError(PositionError):
    what = "the solution jumped to another assembly branch"


class NonFiniteResultError(PositionError):
    what = "a result came out non-finite"


#: Runtime status code (csrc/sg_runtime.h enum sg_status) -> error class.
STATUS_ERRORS = {
    1: AssemblyError,
    2: SingularPositionError,
    3: BranchJumpError,
    5: ConvergenceError,
    6: NonFiniteResultError,
}

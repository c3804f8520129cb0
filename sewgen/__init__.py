"""sewgen: sewing-machine mechanism analysis through derived, compiled kinematics.

    >>> import sewgen
    >>> nb = sewgen.mechanism("needle_bar")
    >>> motion = nb.solve(sewgen.shaft_angles(5), speed="1000 rpm")
    >>> motion.point("needle_eye").y      # m, at 72 shaft angles
"""
from sewgen.errors import (AssemblyError, BranchJumpError, BuildError, ConvergenceError, FrictionLockError, InputError,
    ParameterError, PositionError, SewgenError, SingularPositionError)
from sewgen.engine.forces import ForceAnalysis, JointReaction, RunSettings
from sewgen.engine.loads import Load
from sewgen.engine.loader import catalog, load, mechanism
from sewgen.engine.mechanism import Mechanism, Reference, Sweep, shaft_angles
from sewgen.engine.results import Motion
from sewgen.version import version

__all__ = ["AssemblyError", "BranchJumpError", "BuildError", "ConvergenceError", "ForceAnalysis", "FrictionLockError",
           "InputError", "JointReaction", "Load", "Mechanism", "Motion", "ParameterError", "PositionError",
           "Reference", "RunSettings", "SewgenError", "SingularPositionError", "Sweep", "catalog", "load", "mechanism",
           "shaft_angles"]


def __getattr__(name: str):
    """``sewgen.__version__``, looked up on first use (package metadata costs start-up time)."""
    if name == "__version__":
        value = version()
        globals()["__version__"] = value
        return value
    raise AttributeError(f"module 'sewgen' has no attribute {name!r}")

"""sewgen: sewing-machine mechanism analysis through derived, compiled kinematics.

    >>> import sewgen
    >>> nb = sewgen.mechanism("needle_bar")
    >>> motion = nb.solve(sewgen.shaft_angles(5), speed="1000 rpm")
    >>> motion.point("needle_eye").y      # m, at 72 shaft angles
"""
import threading

from sewgen.errors import (AssemblyError, BranchJumpError, BuildError, ConvergenceError, InputError, ParameterError,
    PositionError, SewgenError, SingularPositionError)
from sewgen.engine.forces import ForceAnalysis, JointReaction, RunSettings
from sewgen.engine.loads import Load
from sewgen.engine.mechanism import Mechanism, Reference, Sweep, shaft_angles
from sewgen.engine.results import Motion

__all__ = ["AssemblyError", "BranchJumpError", "BuildError", "ConvergenceError", "ForceAnalysis", "InputError",
           "JointReaction", "Load", "Mechanism", "Motion", "ParameterError", "PositionError", "Reference",
           "RunSettings", "SewgenError", "SingularPositionError", "Sweep", "catalog", "load", "mechanism",
           "shaft_angles"]


def __getattr__(name: str):
    """``sewgen.__version__``, looked up on first use (package metadata costs start-up time)."""
    if name == "__version__":
        value = _version()
        globals()["__version__"] = value
        return value
    raise AttributeError(f"module 'sewgen' has no attribute {name!r}")


def _version() -> str:
    """The installed distribution's version (package metadata); else, in a checkout, pyproject.toml's."""
    from importlib import metadata

    try:
        return metadata.version("sewgen")
    except metadata.PackageNotFoundError:
        pass
    try:
        import tomllib
        from pathlib import Path

        text = (Path(__file__).resolve().parent.parent / "pyproject.toml").read_text(encoding="utf-8")
        return str(tomllib.loads(text)["project"]["version"])
    except (OSError, KeyError, ValueError):
        return "0+unknown"


_cache: dict = {}
_cache_lock = threading.Lock()  # one Mechanism per catalog name, even when threads ask at once


def catalog() -> list[str]:
    """Names of the built-in mechanisms."""
    from sewgen.engine.loader import catalog_names

    return catalog_names()


def mechanism(name: str) -> Mechanism:
    """A built-in mechanism by name (see :func:`catalog`)."""
    from sewgen.engine.loader import catalog_module, catalog_names

    mech = _cache.get(name)
    if mech is None:
        with _cache_lock:
            if name not in _cache:
                names = catalog_names()
                if name not in names:
                    raise KeyError(f"no built-in mechanism {name!r}; the catalog has: {', '.join(names)}")
                mod = catalog_module()
                _cache[name] = Mechanism(mod.ffi, mod.lib, name)
            mech = _cache[name]
    return mech


def load(source, *, closed_form: bool = True, cache_dir=None) -> Mechanism:
    """A mechanism declared outside the catalog: a derive.Mechanism, a function returning one, or a .py file
    with ``declare()``. Derived and compiled on first use, then loaded from the cache."""
    from sewgen.engine.loader import load_user

    return load_user(source, closed_form=closed_form, cache_dir=cache_dir)

"""sewgen's version: the installed distribution's, or in a checkout pyproject.toml's (a leaf)."""
from __future__ import annotations

from pathlib import Path


def version() -> str:
    """The installed distribution's version (package metadata); else, in a checkout, pyproject.toml's. Its
    imports wait for the first call: package metadata costs start-up time."""
    from importlib import metadata

    try:
        return metadata.version("sewgen")
    except metadata.PackageNotFoundError:
        pass
    try:
        import tomllib

        text = (Path(__file__).resolve().parent.parent / "pyproject.toml").read_text(encoding="utf-8")
        return str(tomllib.loads(text)["project"]["version"])
    except (ImportError, OSError, KeyError, ValueError):
        return "0+unknown"

"""What every test file shares: the markers, and one build cache for the whole run.

One build cache: a user mechanism (and the runtime object every user build links) is compiled once per run,
whichever test file or ``sewgen`` subprocess asks first; the cache is lock-safe, so pytest-xdist's workers
share it too. The controller makes it and exports it as ``SEWGEN_CACHE`` before the workers start (they and
every subprocess inherit it); ``SEWGEN_TEST_CACHE=DIR`` keeps it between runs instead (a build's key hashes
everything it depends on, so a kept cache is never stale). Tests of the cache's own behaviour (first build,
rebuild, a broken entry) use a folder of their own.

Markers (pyproject.toml): ``derive`` (runs the SymPy derivation), ``c`` (executes compiled C: CI runs these
again against a sanitized build), ``cli`` (runs the ``sewgen`` command in a subprocess), ``plots`` (draws
figures), ``slow`` (more than about ten seconds on one core).
"""
from __future__ import annotations

import os
import shutil
import sys
import tempfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
#: bench, peers and fuzz live in tools/, outside the installed package.
sys.path.insert(0, str(ROOT / "tools"))

_OWNED: list[Path] = []  # a cache this process made, removed at the end


def pytest_configure(config):
    if hasattr(config, "workerinput"):  # an xdist worker: the controller exported SEWGEN_CACHE already
        return
    kept = os.environ.get("SEWGEN_TEST_CACHE")
    if kept:
        folder = Path(kept).resolve()
        folder.mkdir(parents=True, exist_ok=True)
    else:
        folder = Path(tempfile.mkdtemp(prefix="sewgen-test-cache-"))
        _OWNED.append(folder)
    os.environ["SEWGEN_CACHE"] = str(folder)


def pytest_unconfigure(config):
    while _OWNED:
        shutil.rmtree(_OWNED.pop(), ignore_errors=True)


@pytest.fixture(scope="session")
def cache() -> Path:
    """The run's one build cache (``SEWGEN_CACHE``)."""
    return Path(os.environ["SEWGEN_CACHE"])


@pytest.fixture(scope="session")
def cache_dir(cache) -> Path:
    return cache

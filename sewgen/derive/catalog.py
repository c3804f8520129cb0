"""The built-in mechanisms, in the order they are generated."""
from __future__ import annotations

import importlib

CATALOG = ("needle_bar", "take_up", "hook_drive", "feed", "overlock_needle", "overlock_loopers", "overlock_feed",
           "overlock_knife")


def declare(name: str):
    """The declaration of a catalog mechanism by name."""
    if name not in CATALOG:
        raise KeyError(f"no catalog mechanism {name!r}; known: {', '.join(CATALOG)}")
    return importlib.import_module(f"sewgen.derive.models.{name}").declare()

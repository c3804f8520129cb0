"""The built-in mechanisms, in the order they are generated."""
from __future__ import annotations

import importlib

CATALOG = ("needle_bar", "take_up", "hook_drive", "feed", "overlock_needle", "overlock_loopers", "overlock_feed",
           "overlock_knife", "overlock_needle_planar", "overlock_loopers_planar")
#: Planar equivalents: name -> (module, keyword arguments of its declare())
VARIANTS = {"overlock_needle_planar": ("overlock_needle", {"planar": True}),
            "overlock_loopers_planar": ("overlock_loopers", {"planar": True})}


def declare(name: str):
    """The declaration of a catalog mechanism by name."""
    if name not in CATALOG:
        raise KeyError(f"no catalog mechanism {name!r}; known: {', '.join(CATALOG)}")
    module, kwargs = VARIANTS.get(name, (name, {}))
    return importlib.import_module(f"sewgen.derive.models.{module}").declare(**kwargs)

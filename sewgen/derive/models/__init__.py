"""The catalog's mechanism declarations, one module each, each with ``declare() -> Mechanism``."""

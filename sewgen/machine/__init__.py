"""Whole machines: groups of mechanisms on one upper shaft, read from a model file.

Reads the engine and the leaves. ``assembly`` (the machine, its analysis), ``plan`` (one prepared engine
call per group), ``modelfile`` (the model file end to end: its reader, every schema table, the file read into
typed data), ``tables`` (the machine's and a group's columns), ``shaking`` (the shaking force and moments on
the frame: the sign convention), ``feed``, ``feed_indices``, ``cams``, ``timing``, ``thread``, ``peaks`` (a
quantity's peaks refined between the samples), ``balance`` (seed 002's needle bar) and ``machine_balance`` (seed
000's three methods).
"""
__all__ = ["Machine", "MachineAnalysis", "load_machine"]


def __getattr__(name: str):
    """``sewgen.machine.load_machine``, ``Machine``, ``MachineAnalysis``: the assembly's, imported on first use,
    so that a module of this package (the model-file reader, say) loads without the whole machine layer."""
    if name in __all__:
        from sewgen.machine import assembly

        return getattr(assembly, name)
    raise AttributeError(f"module 'sewgen.machine' has no attribute {name!r}")

"""Whole machines: groups of mechanisms on one upper shaft, read from a model file.

Reads the engine and the leaves. ``assembly`` (the machine, its analysis), ``plan`` (one prepared engine
call per group), ``modelfile`` (the model file end to end: its reader, every schema table, the file read into
typed data), ``tables`` (the machine's and a group's columns), ``shaking`` (the shaking force and moments on
the frame: the sign convention), ``feed``, ``feed_indices``, ``cams``, ``timing``, ``thread``, ``balance``
(seed 002's needle bar) and ``machine_balance`` (seed 000's three methods).
"""
from sewgen.machine.assembly import Machine, MachineAnalysis, load_machine

__all__ = ["Machine", "MachineAnalysis", "load_machine"]

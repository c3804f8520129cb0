"""Design studies at scale (seed 001 §六): design tables, machine-level design sets, parameter influence,
tolerance Monte Carlo, in-process or on Dask. pandas is imported on first use.

    >>> from sewgen.machine import load_machine
    >>> from sewgen.study import influence, tolerance
    >>> jb = load_machine("jb1-3")
    >>> r = influence(jb, ["groups.needle_bar.params.crank"], "-10%..+10%", 5)
    >>> r.sensitivity("groups.needle_bar.params.crank", "needle_stroke [mm]")   # 2.0 (crank-slider)
"""
from sewgen.study.designs import GroupSweep, design_matrix, sweep_group_designs
from sewgen.study.evaluate import StudyOptions, evaluate_chunk, quantity_columns
from sewgen.study.machine_designs import DesignKey, MachineDesigns, parse_key
from sewgen.study.run import InfluenceResult, StudyError, ToleranceResult, influence, run_designs, tolerance

__all__ = ["DesignKey", "GroupSweep", "InfluenceResult", "MachineDesigns", "StudyError", "StudyOptions",
           "ToleranceResult", "design_matrix", "evaluate_chunk", "influence", "parse_key", "quantity_columns",
           "run_designs", "sweep_group_designs", "tolerance"]

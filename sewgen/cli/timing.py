"""``sewgen timing``: the stitch-formation events of a revolution and every timing rule's margin (exit status 1
where one fails)."""
from __future__ import annotations

import json
from pathlib import Path

from sewgen.cli.common import Console, quantity
from sewgen.machine.assembly import load_machine
from sewgen.machine.timing import timing
from sewgen.report.outputs import check_output_folder


def cmd_timing(args, con: Console) -> int:
    """Stitch-formation timing of a machine: the event table and every rule's margin (exit 1 if one fails)."""
    speed = quantity(args.speed, "speed", "--speed", "positive")
    plots = check_output_folder(Path(args.plots), "--plots") if args.plots else None
    machine = load_machine(args.model)
    tm = timing(machine, speed=speed)
    con.say(json.dumps(tm.as_dict(), indent=2, ensure_ascii=False) if args.json else tm.table())
    if plots is not None:
        from sewgen.report.plots.cycle import write_timing_plots

        for path in write_timing_plots(tm, plots):
            con.note(f"wrote {path}")
    return 0 if tm.ok else 1

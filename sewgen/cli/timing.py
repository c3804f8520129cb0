"""``sewgen timing``: the stitch-formation events of a revolution and every timing rule's margin (exit status 3
where one fails)."""
from __future__ import annotations

import json

from sewgen.cli.common import RULES_FAIL, Console, quantity
from sewgen.files import check_folder, staged_folder
from sewgen.machine.assembly import load_machine
from sewgen.machine.timing import timing


def cmd_timing(args, con: Console) -> int:
    """Stitch-formation timing of a machine: the event table and every rule's margin (exit 3 if one fails)."""
    speed = quantity(args.speed, "speed", "--speed", "positive")
    if args.plots is not None:
        check_folder(args.plots, "--plots")
    machine = load_machine(args.model, allow_outside_code=args.allow_outside_code)
    tm = timing(machine, speed=speed)
    if args.plots is not None:
        from sewgen.report.plots.cycle import write_timing_plots

        with staged_folder(args.plots, "--plots") as tmp:
            written = write_timing_plots(tm, tmp)
    con.say(json.dumps(tm.as_dict(), indent=2, ensure_ascii=False) if args.json else tm.table())
    if args.plots is not None:
        for path in written:
            con.note(f"wrote {args.plots}/{path.name}")
    if not tm.ok:
        con.warn(f"{machine.name} fails {len(tm.failed)} of {len(tm.checks)} timing rules: "
                 f"{', '.join(c.rule for c in tm.failed)}")
    return 0 if tm.ok else RULES_FAIL

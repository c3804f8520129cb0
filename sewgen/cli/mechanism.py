"""``sewgen list``, ``sewgen params``, ``sewgen kinematics`` and ``sewgen forces``: one mechanism (the
catalog's or a declaration file) listed, described, swept to a table and a CSV."""
from __future__ import annotations

import math

import numpy as np

from sewgen.cli.common import (
    Console,
    UsageError,
    branches_of,
    check_file,
    display_units,
    extreme,
    mechanism_of,
    params_of,
    quantity,
    rms,
    speed_of,
    sweep_of,
    write_table,
)
from sewgen.engine.loader import catalog, mechanism
from sewgen.engine.loads import Load
from sewgen.units import GRAVITY_MAX, range_problem


def cmd_list(args, con: Console) -> int:

    for name in catalog():
        m = mechanism(name)
        title = m.doc.splitlines()[0] if m.doc else ""
        con.say(f"{name:12s} {title}")
        con.say(f"{'':12s} coordinates: {', '.join(m.coord_names)}; points: {', '.join(m.point_names)}")
    return 0


def cmd_params(args, con: Console) -> int:
    units = display_units(args)
    m = mechanism_of(args)
    d = m.description
    con.say(f"{m.name}: {len(d.params)} parameters (default, unit; declared in)")
    for p in d.params:
        (value,), unit = units.convert([p.default], p.unit)
        role = f"  (role {p.role})" if p.role else ""
        con.say(f"  {p.name:24s} {value:>12.6g} {unit:9s} {p.display_unit:8s} {p.doc}{role}")
    for i in d.held_inputs:
        (value,), unit = units.convert([i.default], i.unit)
        role = f"  (role {i.role})" if i.role else ""
        con.say(f"  held {i.name:19s} {value:>12.6g} {unit:9s} {i.display_unit:8s} {i.doc}{role}")
    for b in d.branches:
        con.say(f"  branch {b.joint:17s} default {b.default:+d}  {b.meaning}")
    con.say(f"  default speed {m.default_speed * 30 / math.pi:.6g} rpm")
    if d.roles:
        con.say("  roles: " + ", ".join(f"{role} = {kind} {name}" for role, (kind, name) in sorted(d.roles.items())))
    return 0


def cmd_kinematics(args, con: Console) -> int:
    units = display_units(args)
    csv = check_file(args.csv, "--csv")
    phi, step, start = sweep_of(args)
    m = mechanism_of(args)
    speed, speed_words = speed_of(args, m.default_speed, "the mechanism's")
    motion = m.solve(phi, speed=speed, params=params_of(m, args.param), branch=branches_of(m, args.branch),
                     newton=args.newton)
    if csv:
        write_table(csv, units.table(motion.table()), "--csv")
    L, V, A = (units.of(u)[0] for u in ("m", "m/s", "m/s^2"))
    lines = [f"{m.name}: {len(phi)} positions every {step:g}° from {start:g}°, speed {speed_words}",
             f"{'point':16s} {f'x range ({L})':>22s} {f'y range ({L})':>22s} {f'peak |v| ({V})':>26s} "
             f"{f'peak |a| ({A})':>26s}"]
    for name in motion.point_names:
        pt = motion.point(name)
        x, _ = units.convert(pt.x, "m")
        y, _ = units.convert(pt.y, "m")
        v, _ = units.convert(np.hypot(pt.vx, pt.vy), "m/s")
        a, _ = units.convert(np.hypot(pt.ax, pt.ay), "m/s^2")
        lines.append(f"{name:16s} {x.min():10.5g} {x.max():10.5g}  {y.min():10.5g} {y.max():10.5g} "
                     f"{extreme(v, phi, np.argmax)} {extreme(a, phi, np.argmax)}")
    for name in motion.coord_names:
        c = motion.coord(name)
        value, unit = units.convert(c.value, c.unit)
        lines.append(f"{name:24s} [{unit}] min {extreme(value, phi, np.argmin)}  "
                     f"max {extreme(value, phi, np.argmax)}")
    if csv:
        lines.append(f"wrote {csv}")
    for line in lines:
        con.say(line)
    return 0


def _load(text: str, m):
    """ "AT fx=.. fy=.. torque=.. from=.. to=.." -> Load (quantities with units)."""
    fields = text.split()
    if not fields or "=" in fields[0]:
        raise UsageError("--load", f'"{text}": expected AT fx=.. fy=.. torque=.. from=.. to=.., e.g. '
                                   f'"POINT fy=-2.94N from=135deg to=155deg"')
    at, *pairs = fields
    kw, window = {}, {}
    kinds = {"fx": "force", "fy": "force", "torque": "torque", "from": "angle", "to": "angle"}
    for item in pairs:
        key, sep, val = item.partition("=")
        if not sep or key not in kinds:
            raise UsageError("--load", f'"{text}": expected AT fx=.. fy=.. torque=.. from=.. to=.., got {item}')
        if key in kw or key in window:
            raise UsageError("--load", f'"{text}": {key} given twice')
        value = quantity(val, kinds[key], f"--load {key}")
        (window if key in ("from", "to") else kw)[key] = value
    if len(window) == 1:
        raise UsageError("--load", f'"{text}": give both from= and to= for a window')
    return Load(at, window=(window["from"], window["to"]) if window else None, **kw)


def _all_masses_zero(m, params: dict) -> bool:
    d = m.description
    p = m.param_vector(params or None)
    index = {q.name: q.index for q in d.params}
    masses = [p[index[b.mass]] for b in d.bodies if b.mass in index]
    return bool(masses) and all(v == 0.0 for v in masses)


def cmd_forces(args, con: Console) -> int:
    units = display_units(args)
    csv = check_file(args.csv, "--csv")
    phi, step, start = sweep_of(args)
    gravity = quantity(args.gravity, "acceleration", "--gravity")
    problem = range_problem(gravity, 0.0, GRAVITY_MAX, "m/s**2")
    if problem:
        raise UsageError("--gravity", f"{problem} (a magnitude: it acts along -y; 9.80665 m/s**2 on Earth)")
    m = mechanism_of(args)
    speed, speed_words = speed_of(args, m.default_speed, "the mechanism's")
    params = params_of(m, args.param)
    loads = [_load(t, m) for t in args.load or []]
    fa = m.kinetostatics(phi, speed=speed, params=params or None, branch=branches_of(m, args.branch),
                         newton=args.newton, loads=loads, gravity=gravity)
    if _all_masses_zero(m, params):
        con.warn(f"{m.name}: every body's mass is zero, so there are no inertia or gravity forces: the reactions "
                 "come from the loads alone (give masses with --param BODY.mass=\"35 g\")")
    if csv:
        write_table(csv, units.table(fa.table()), "--csv")
    F, T = units.of("N")[0], units.of("N*m")[0]
    lines = [f"{m.name}: {len(phi)} positions every {step:g}° from {start:g}°, speed {speed_words}, gravity "
             f"{gravity:g} m/s^2 along -y",
             f"{'joint':22s} {f'peak |F| ({F}) @ φ':>26s} {f'RMS |F| ({F})':>12s}"]
    for name in fa.reaction_names:
        mag, _ = units.convert(fa.reaction(name).magnitude, "N")
        lines.append(f"{name:22s} {extreme(mag, phi, np.argmax)} {rms(mag):12.6g}")
    for name in [i.name for i in m.description.inputs]:
        tau, _ = units.convert(fa.torque(name), "N*m")
        lines.append(f"torque {name:15s} min {extreme(tau, phi, np.argmin)}  max {extreme(tau, phi, np.argmax)}"
                     f"  RMS {rms(tau):.6g} {T}")
    on_parts, _ = units.convert(np.hypot(*fa.frame_force_on_parts.T), "N")
    lines.append(f"{f'frame on parts ({F})':22s} {extreme(on_parts, phi, np.argmax)} {rms(on_parts):12.6g}")
    moment, _ = units.convert(np.abs(fa.frame_moment_on_parts), "N*m")
    lines.append(f"{f'frame moment ({T})':22s} {extreme(moment, phi, np.argmax)} {rms(moment):12.6g}")
    if csv:
        lines.append(f"wrote {csv}")
    for line in lines:
        con.say(line)
    return 0

"""``sewgen list``, ``sewgen params``, ``sewgen kinematics`` and ``sewgen forces``: one mechanism (the
catalog's or a declaration file) listed, described, swept to a table and a CSV."""
from __future__ import annotations

import math

import numpy as np

from sewgen.cli.common import (
    STDOUT,
    Console,
    UsageError,
    branches_of,
    check_file,
    display_units,
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
from sewgen.machine.peaks import REFINED, extremes_of, mechanism_signature
from sewgen.units import GRAVITY_MAX, range_problem

REFINED_NOTE = "peaks and extremes refined between the positions (the mechanism solved again around each)"


def _extreme(ext, units, unit: str) -> str:
    """"     190.055 @ 192.12°" (an extreme found at a switch or on the samples only says so: * / ~)."""
    (value,), _ = units.convert(np.array([ext.value]), unit)
    mark = " " if ext.how == REFINED else ("*" if ext.how == "at a switch" else "~")
    return f"{value:12.6g} @ {ext.deg:6.2f}°{mark}"


def _note(found: dict) -> str:
    hows = {e.how for senses in found.values() for e in senses.values()}
    return REFINED_NOTE + ("; * at a cam-arc switch or a load window's edge (the one-sided value)"
                           if "at a switch" in hows else "") + ("; ~ sampled" if "sampled" in hows else "")


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
    settings = dict(speed=speed, params=params_of(m, args.param), branch=branches_of(m, args.branch),
                    newton=args.newton)
    motion = m.solve(phi, **settings)
    if csv:
        write_table(csv, units.table(motion.table()), "--csv")
    quantities = {}
    for name in motion.point_names:
        quantities[f"v.{name}"] = lambda r, name=name: np.hypot(r.point(name).vx, r.point(name).vy)
        quantities[f"a.{name}"] = lambda r, name=name: np.hypot(r.point(name).ax, r.point(name).ay)
    for name in motion.coord_names:
        quantities[f"q.{name}"] = lambda r, name=name: r.coord(name).value
    found = extremes_of(motion, phi, quantities, lambda angles: m.solve(angles, **settings),
                        lambda r, angles: mechanism_signature(m, r.obs, angles))
    L, V, A = (units.of(u)[0] for u in ("m", "m/s", "m/s^2"))
    lines = [f"{m.name}: {len(phi)} positions every {step:g}° from {start:g}°, speed {speed_words}; {_note(found)}",
             f"{'point':16s} {f'x range ({L})':>22s} {f'y range ({L})':>22s} {f'peak |v| ({V})':>26s} "
             f"{f'peak |a| ({A})':>26s}"]
    for name in motion.point_names:
        pt = motion.point(name)
        x, _ = units.convert(pt.x, "m")
        y, _ = units.convert(pt.y, "m")
        lines.append(f"{name:16s} {x.min():10.5g} {x.max():10.5g}  {y.min():10.5g} {y.max():10.5g} "
                     f"{_extreme(found[f'v.{name}']['max'], units, 'm/s')} "
                     f"{_extreme(found[f'a.{name}']['max'], units, 'm/s^2')}")
    for name in motion.coord_names:
        c = motion.coord(name)
        _, unit = units.convert(c.value[:1], c.unit)
        ext = found[f"q.{name}"]
        lines.append(f"{name:24s} [{unit}] min {_extreme(ext['min'], units, c.unit)}  "
                     f"max {_extreme(ext['max'], units, c.unit)}")
    _report(lines, csv, con)
    return 0


def _report(lines: list, csv, con: Console) -> None:
    """The text report, unless the table went to standard output (``--csv -``: the table alone there)."""
    if csv == STDOUT:
        return
    if csv:
        lines.append(f"wrote {csv}")
    for line in lines:
        con.say(line)


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
    settings = dict(speed=speed, params=params or None, branch=branches_of(m, args.branch), newton=args.newton,
                    loads=loads, gravity=gravity)
    fa = m.kinetostatics(phi, **settings)
    if _all_masses_zero(m, params):
        con.warn(f"{m.name}: every body's mass is zero, so there are no inertia or gravity forces: the reactions "
                 "come from the loads alone (give masses with --param BODY.mass=\"35 g\")")
    if csv:
        write_table(csv, units.table(fa.table()), "--csv")
    inputs = [i.name for i in m.description.inputs]
    quantities = {f"joint.{n}": (lambda r, n=n: r.reaction(n).magnitude) for n in fa.reaction_names}
    quantities.update({f"torque.{n}": (lambda r, n=n: r.torque(n)) for n in inputs})
    quantities["on_parts"] = lambda r: np.hypot(*r.frame_force_on_parts.T)
    quantities["moment"] = lambda r: np.abs(r.frame_moment_on_parts)
    found = extremes_of(fa, phi, quantities, lambda angles: m.kinetostatics(angles, **settings),
                        lambda r, angles: mechanism_signature(m, r.motion.obs, angles, loads))
    F, T = units.of("N")[0], units.of("N*m")[0]
    lines = [f"{m.name}: {len(phi)} positions every {step:g}° from {start:g}°, speed {speed_words}, gravity "
             f"{gravity:g} m/s^2 along -y; {_note(found)}",
             f"{'joint':22s} {f'peak |F| ({F}) @ φ':>27s} {f'RMS |F| ({F})':>12s}"]
    for name in fa.reaction_names:
        mag, _ = units.convert(fa.reaction(name).magnitude, "N")
        lines.append(f"{name:22s} {_extreme(found[f'joint.{name}']['max'], units, 'N')} {rms(mag):12.6g}")
    for name in inputs:
        tau, _ = units.convert(fa.torque(name), "N*m")
        ext = found[f"torque.{name}"]
        lines.append(f"torque {name:15s} min {_extreme(ext['min'], units, 'N*m')}  "
                     f"max {_extreme(ext['max'], units, 'N*m')}  RMS {rms(tau):.6g} {T}")
    on_parts, _ = units.convert(np.hypot(*fa.frame_force_on_parts.T), "N")
    lines.append(f"{f'frame on parts ({F})':22s} {_extreme(found['on_parts']['max'], units, 'N')} "
                 f"{rms(on_parts):12.6g}")
    moment, _ = units.convert(np.abs(fa.frame_moment_on_parts), "N*m")
    lines.append(f"{f'frame moment ({T})':22s} {_extreme(found['moment']['max'], units, 'N*m')} {rms(moment):12.6g}")
    _report(lines, csv, con)
    return 0

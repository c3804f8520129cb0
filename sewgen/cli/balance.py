"""``sewgen balance needle_bar``: the optimum partial-balancing counterweight of seed 002 (see balance.py).

The target is the needle drive, named as the catalog names it (``needle-bar`` is accepted too). A mistake is one
line naming the option or the model file's key (exit status 2, nothing on stdout); the plot is written before
the table is printed.
"""
from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from sewgen.cli.common import Console
from sewgen.errors import SewgenError
from sewgen.files import check_file
from sewgen.machine.modelfile import ModelFileError, load_toml
from sewgen.units import MAX_POSITIONS, UnitError, to_si


class _Balance:
    """sewgen.machine.balance, imported on first use: it brings SciPy, which no other command should wait for."""

    def __getattr__(self, name):
        from sewgen.machine import balance

        return getattr(balance, name)


bal = _Balance()
#: Formats --plot may write (by extension); a name without an extension gets .png.
PLOT_FORMATS = (".png", ".pdf", ".svg")

#: Model fields that carry a unit: name -> (kind, help).
QUANTITIES = {
    "crank": ("length", "crank radius l_AB, e.g. 16.7mm (required)"),
    "rod": ("length", "needle-bar link l_BC, pin to pin (required)"),
    "speed": ("speed", "upper-shaft speed, e.g. 6000rpm (required)"),
    "offset": ("length", "needle-bar axis offset from the shaft axis (default 0 mm)"),
    "mass_b": ("mass", "mass lumped at the crank pin B (rotating)"),
    "mass_c": ("mass", "mass lumped at the link pin C (reciprocating)"),
    "crank_mass": ("mass", "the crank's own mass (substituted onto A and B)"),
    "crank_com": ("length", "the crank's centre of mass, from A along AB (signed)"),
    "rod_mass": ("mass", "the link's own mass (substituted onto B and C)"),
    "rod_com": ("length", "the link's centre of mass, from B along BC (default mid-link)"),
    "bar_mass": ("mass", "the needle bar's own mass (with clamp and needle; reciprocating)"),
}
SECTOR = {
    "sector_thickness": ("length", None, "size a sector counterweight of this thickness (annular sector plate)"),
    "sector_inner": ("length", "0 mm", "its inner radius"),
    "sector_angle": ("angle", "180 deg", "its full angle"),
    "density": ("density", "7850 kg/m**3", "its density (default steel)"),
}
SETTINGS = ("weights", "series", "points")
EXAMPLE = """example:
  sewgen balance needle_bar --crank 16.7mm --rod 53mm --mass-b 39.3g --mass-c 105.29g --speed 6000rpm

model file (TOML; quantities are strings with units, options override it):
  crank = "16.7 mm"
  rod = "53 mm"
  speed = "6000 rpm"
  mass_b = "39.3 g"
  mass_c = "105.3 g"
  weights = [0.1, 0.9]
  series = "two-term"
"""


def _opt(name: str) -> str:
    return "--" + name.replace("_", "-")


def add_parser(subparsers, common=None) -> None:
    """Register ``balance`` with the ``sewgen`` command's subparsers (``common(p)`` adds the shared options)."""
    p = subparsers.add_parser("balance", help="optimum partial-balancing counterweight (seed 002)",
                              description="Partial balancing of the needle-bar crank-slider by a counterweight on "
                              "the crank: optimum K, residual inertia force before (K = 0) and after.",
                              epilog=EXAMPLE, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("target", metavar="TARGET", help="needle-bar (or needle_bar): the needle drive's counterweight "
                   "(seed 002); machine: a whole machine by seed 000's three methods (give its MODEL)")
    p.add_argument("machine_model", nargs="?", metavar="MODEL", help="machine: its model file or built-in name")
    p.add_argument("--model", metavar="FILE", help="a TOML model file (keys as the options, with underscores)")
    for name, (_, text) in QUANTITIES.items():
        p.add_argument(_opt(name), dest=name, metavar="Q", help=text)
    for name, (_, default, text) in SECTOR.items():
        p.add_argument(_opt(name), dest=name, metavar="Q", help=text + (f" (default {default})" if default else ""))
    p.add_argument("--weights", help="w1,w2 of the objective w1·F1 + w2·F2, summing to 1 (default 0.1,0.9)")
    p.add_argument("--series", help="slider acceleration: two-term (the paper's, default) or exact (compiled)")
    p.add_argument("--points", help=f"shaft positions per revolution (default 3600, at most {MAX_POSITIONS:,})")
    p.add_argument("--json", action="store_true", help="print the result as JSON (SI: N, kg·m, kg, m)")
    p.add_argument("--plot", default=None, metavar="FILE",
                   help="picture of F(φ) before/after and of F1, F2, objective over K: .png (default "
                        "<mechanism>_balance.png), .pdf or .svg")
    p.add_argument("--no-plot", action="store_true", help="write no plot")
    from sewgen.cli.balance_machine import add_arguments

    add_arguments(p)
    if common is not None:
        common(p)
    p.set_defaults(fn=cmd_balance)


class BalanceInputError(SewgenError, ValueError):
    """A bad option or model-file value of ``sewgen balance`` (the message names it)."""


def _fail(message: str):
    raise BalanceInputError(message)


def target_name(text: str) -> str:
    """The catalog's name of the needle drive, if ``text`` names it (either spelling); else a one-line error."""
    drive = bal.needle_drive().mechanism.name
    if text.replace("-", "_") != drive:
        _fail(f"balance: no such mechanism {text}: the one mechanism to balance is {drive} (the needle drive)")
    return drive


def _plot_path(text: str | None, drive: str) -> Path:
    """--plot's file, checked before any work: a picture format, a regular file or none yet in an existing folder
    (sewgen.files.check_file)."""
    path = Path(text if text is not None else f"{drive}_balance.png")
    if text is not None and not text.strip():
        _fail("--plot: an empty file name")
    check_file(path, "--plot")  # a folder, a FIFO, "-", inside sewgen: refused as named
    if path.suffix == "":
        path = path.with_name(path.name + ".png")
    if path.suffix.lower() not in PLOT_FORMATS:
        _fail(f"--plot: {path}: cannot write a {path.suffix} picture; use {', '.join(PLOT_FORMATS)}")
    check_file(path, "--plot")
    return path


def _inputs(args) -> tuple[dict, dict]:
    """Raw values by field name (file first, options override) and the label naming each in errors."""
    raw, label = {}, {}
    if args.model:
        try:
            data = load_toml(args.model)
        except ModelFileError as exc:
            _fail(f"--model {exc}")
        for key, value in data.items():
            name = key.replace("-", "_")
            if name not in QUANTITIES and name not in SECTOR and name not in SETTINGS:
                _fail(f"{args.model}: unknown key {key!r}; keys are: {', '.join([*QUANTITIES, *SECTOR, *SETTINGS])}")
            if (name in QUANTITIES or name in SECTOR) and not isinstance(value, str):
                _fail(f"{args.model}: {key} = {value!r} needs a unit, e.g. \"16.7 mm\"")
            raw[name], label[name] = value, f"{args.model}: {key}"
    for name in (*QUANTITIES, *SECTOR, *SETTINGS):
        if getattr(args, name) is not None:
            raw[name], label[name] = getattr(args, name), _opt(name)
    return raw, label


def _quantity(raw, label, name, kind):
    try:
        value = to_si(raw[name], kind, label[name])
    except UnitError as exc:
        _fail(str(exc))
    if kind == "mass" and not value > 0:
        _fail(f"{label[name]}: a mass must be positive, got {raw[name]!r}")
    return value


def _settings(raw, label):
    weights = raw.get("weights", bal.DEFAULT_WEIGHTS)
    if isinstance(weights, str):
        weights = weights.split(",")
    try:
        weights = bal.check_weights(weights)
    except bal.BalanceError as exc:
        _fail(f"{label.get('weights', '--weights')}: {exc.problem}")
    series = raw.get("series", "two-term")
    if series not in bal.SERIES:
        _fail(f"{label['series']}: must be one of {', '.join(bal.SERIES)}, got {series!r}")
    value = raw.get("points", 3600)
    try:
        points = int(value) if isinstance(value, int) or str(value).strip().isdigit() else 0
    except (TypeError, ValueError):
        points = 0
    if isinstance(value, bool) or points < 8:
        _fail(f"{label['points']}: need a whole number of at least 8, got {value}")
    if points > MAX_POSITIONS:
        _fail(f"{label['points']}: {points:,} positions a revolution; at most {MAX_POSITIONS:,} are allowed")
    return weights, series, points


def build(args):
    """(model, weights, series, points, sector settings or None) from the file and options; exits on bad input."""
    raw, label = _inputs(args)
    for name in ("crank", "rod", "speed"):
        if name not in raw:
            _fail(f"{_opt(name)} is required (or {name} in a --model file)")
    values = {name: _quantity(raw, label, name, kind) for name, (kind, _) in QUANTITIES.items() if name in raw}
    try:
        model = bal.NeedleBarModel(**values)
    except bal.BalanceError as exc:
        _fail(f"{label.get(exc.name, _opt(exc.name))}: {exc.problem}")
    sector = None
    if "sector_thickness" in raw:
        for name, (_, default, _) in SECTOR.items():
            raw.setdefault(name, default)
            label.setdefault(name, _opt(name))
        sector = {name: _quantity(raw, label, name, kind) for name, (kind, _, _) in SECTOR.items()}
    return (model, *_settings(raw, label), sector)


def _size_sector(mr, s):
    if not mr > 0:
        _fail(f"--sector-thickness: the optimum counterweight m·r = {mr:g} kg·m is not positive: nothing to size")
    try:
        outer = bal.sector_outer_radius(mr, s["sector_inner"], s["sector_thickness"], s["sector_angle"],
                                        s["density"])
    except bal.BalanceError as exc:
        name = exc.name if exc.name == "density" else "sector_" + exc.name
        _fail(f"{_opt(name)}: {exc.problem}")
    mass, centroid = bal.sector(outer, s["sector_inner"], s["sector_thickness"], s["sector_angle"], s["density"])
    return {"sector_outer_radius": outer, "sector_mass": mass, "sector_centroid": centroid}


def plot(path, model, res, curve, series, n=720):
    """F(φ) before and after, and F1, F2, objective over K (the paper's figs. 3 and 4), to a PNG."""
    from matplotlib.figure import Figure

    from sewgen.report.plots.common import save

    phi = np.append(bal.revolution(n), 2 * math.pi)
    fig = Figure(figsize=(11, 4.2), layout="constrained")
    ax1, ax2 = fig.subplots(1, 2)
    for K, style, name in ((0.0, "C3", "before, K = 0"), (res.K, "C0", f"after, K = {res.K:.3f}")):
        force = bal.residual_magnitude(model, K, bal.shaft_angle(phi), series)
        ax1.plot(np.degrees(phi), force, style, label=f"{name}: max {force.max():.1f} N")
        ax1.axhline(force[:-1].mean(), color=style, ls=":", lw=1, label=f"mean {force[:-1].mean():.1f} N")
    ax1.set(xlabel="φ (deg) from lower dead centre (= shaft angle + 90°)", ylabel="residual inertia force |F| (N)",
            title="Residual inertia force over a revolution", xlim=(0, 360), xticks=range(0, 361, 45))
    ax1.legend()
    ax1.grid(alpha=0.3)
    for col, style, name in ((1, "C3", "F1 = max |F|"), (2, "C2", "F2 = mean |F|"), (3, "C0", "objective")):
        ax2.plot(curve[:, 0], curve[:, col], style, label=name)
    ax2.axvline(res.K, color="0.5", ls="--", lw=1)
    ax2.plot([res.K], [res.objective_after], "ko", label=f"optimum K = {res.K:.3f}")
    ax2.set(xlabel="balance coefficient K", ylabel="N", title=f"Objective {res.weights[0]:g}·F1 + "
            f"{res.weights[1]:g}·F2 over K", xlim=(0, 1))
    ax2.legend()
    ax2.grid(alpha=0.3)
    fig.suptitle(f"needle bar: crank {model.crank * 1e3:g} mm, rod {model.rod * 1e3:g} mm, "
                 f"{model.speed * 30 / math.pi:g} rpm, m_B {res.mass_B * 1e3:.4g} g, m_C {res.mass_C * 1e3:.4g} g, "
                 f"{series}")
    save(fig, path, "--plot", dpi=110)


def _table(model, res, series, sector, plot_path) -> str:
    def row(name, before, after):
        return f"  {name:20s} {before:17.4f} {after:17.4f} {100 * (after / before - 1):+9.1f} %"

    mr_b = res.mass_B * model.crank
    lines = [f"needle bar: crank {model.crank * 1e3:g} mm, rod {model.rod * 1e3:g} mm (λ = {model.lam:.4f}), "
             f"offset {model.offset * 1e3:g} mm, {model.speed * 30 / math.pi:g} rpm, slider acceleration {series}",
             f"substituted masses: m_B = {res.mass_B * 1e3:.4f} g (rotating, fully balanced), "
             f"m_C = {res.mass_C * 1e3:.4f} g (reciprocating)",
             f"optimum K = {res.K:.4f} for {res.weights[0]:g}·F1 + {res.weights[1]:g}·F2",
             f"  {'':20s} {'before (K = 0)':>17s} {f'after (K = {res.K:.3f})':>17s} {'change':>11s}",
             row("F1 = max |F| (N)", res.F1_before, res.F1_after),
             row("F2 = mean |F| (N)", res.F2_before, res.F2_after),
             row("objective (N)", res.objective_before, res.objective_after),
             f"counterweight m·r = {res.counterweight_mr * 1e6:.2f} g·mm "
             f"(m_B·l_AB {mr_b * 1e6:.2f} + K·m_C·l_AB {(res.counterweight_mr - mr_b) * 1e6:.2f})"]
    if sector:
        lines.append(f"sector counterweight: outer radius R = {sector['sector_outer_radius'] * 1e3:.4f} mm, "
                     f"centroid r = {sector['sector_centroid'] * 1e3:.4f} mm, m = {sector['sector_mass'] * 1e3:.4f} g")
    if plot_path:
        lines.append(f"plot: {plot_path}")
    return "\n".join(lines)


def cmd_balance(args, con=None) -> int:
    if args.target == "machine":
        from sewgen.cli.balance_machine import run

        args.model = args.machine_model
        return run(args, con if con is not None else Console())
    drive = target_name(args.target)
    if args.machine_model:
        _fail(f"balance {args.target}: takes no model file argument ({args.machine_model!r}); use --model FILE")
    plot_path = None if (args.no_plot or args.json) else _plot_path(args.plot, drive)
    model, weights, series, points, sector_in = build(args)
    res = bal.optimise(model, weights, series, points)
    sector = _size_sector(res.counterweight_mr, sector_in) if sector_in else None
    say = con.say if con is not None else print
    if args.json:
        out = {**res.as_dict(), "weights": list(res.weights), "lambda": model.lam, "omega": model.speed,
               "points": points, **(sector or {})}
        say(json.dumps(out, indent=2))
        return 0
    if plot_path is not None:
        curve = bal.objective_curve(model, np.linspace(0, 1, 101), weights, series, min(points, 1440))
        try:
            plot(plot_path, model, res, curve, series)
        except ImportError:
            _fail("--plot needs matplotlib (pip install matplotlib), or give --no-plot")
        except ValueError as exc:  # (a disk's error is an OutputPathError, naming --plot and the file)
            _fail(f"--plot: cannot write {plot_path}: {exc}")
    say(_table(model, res, series, sector, plot_path))
    return 0

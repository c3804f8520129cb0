"""``sewgen study influence`` and ``sewgen study tolerance``: design studies of a machine (seed 001 §六).

The output folder is written whole or not at all (sewgen.files.staged_folder): CSV tables whose headers name
their units, PNG plots, and study.json (the settings, the finite-difference scheme, the counts). Progress goes
to stderr as a bar when it is a terminal; a mistake (a key the model lacks, a bad range or tolerance, an
unreachable scheduler) is one line on stderr, exit status 2 and nothing on stdout.
"""
from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np

from sewgen.cli.common import Console, UsageError, outside_code_option, quantity
from sewgen.files import check_folder, replacing, staged_folder, write_text
from sewgen.units import steps_per_turn

#: Relative spread below which a quantity's samples count as one value (float rounding between designs, as
#: summary.json's 12 significant digits): its histogram is a line of text, not bins narrower than the rounding.
NOISE = 1e-12


def _options(args, loads: bool):
    from sewgen.study.evaluate import StudyOptions

    step = quantity(args.step, "angle", "--step")
    n, problem = steps_per_turn(step)
    if n is None:
        raise UsageError("--step", problem)
    speed = quantity(args.speed, "speed", "--speed", "positive")
    return StudyOptions(step_deg=360.0 / n, speed=speed, loads=loads, exact_jumps=args.exact_jumps)


def _chunk(args):
    if args.chunk is None:
        return None
    if args.chunk < 1:
        raise UsageError("--chunk", f"must be at least 1, got {args.chunk}")
    return args.chunk


def _safe(key: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", key)


def _grid(n):
    cols = min(4, n)
    return max(1, math.ceil(n / cols)), cols


def influence_plots(res, folder) -> list[Path]:
    """One PNG per varied key: every numeric quantity against the key's value, the nominal marked; an angle
    continuous across 0°/360° (InfluenceResult.curve)."""
    from sewgen.report.plots.common import new_figure, save

    out = []
    t = res.table
    quantities = [c for c in t.columns[t.columns.get_loc("error") + 1:] if t[c].dtype != object]
    for k in res.keys:
        nr, nc = _grid(len(quantities))
        fig = new_figure((3.2 * nc, 2.4 * nr))
        axes = fig.subplots(nr, nc, squeeze=False)
        for ax, q in zip(axes.flat, quantities):
            ax.plot(*res.curve(k.key, q), "o-", ms=3)
            ax.axvline(k.nominal * k.factor, color="0.6", lw=0.8, ls="--")
            ax.set_title(q, fontsize=8)
            ax.tick_params(labelsize=7)
            ax.ticklabel_format(axis="y", useOffset=False)  # read the values themselves, not "+1.9e2"
            ax.set_xlabel(k.column, fontsize=7)
        for ax in list(axes.flat)[len(quantities):]:
            ax.set_visible(False)
        fig.suptitle(f"{res.machine}: influence of {k.key} (others at nominal)", fontsize=10)
        fig.subplots_adjust(hspace=0.7, wspace=0.35, left=0.06, right=0.98, top=0.93, bottom=0.06)
        out.append(save(fig, Path(folder) / f"influence_{_safe(k.key)}.png"))
    return out


def tolerance_plots(res, folder) -> list[Path]:
    """histograms.png: a histogram per numeric quantity, the nominal marked; an angle (``res.periods``) within half
    its period of the nominal (sewgen.study.evaluate.around), as the percentiles take it; a quantity whose samples
    differ by no more than float rounding (:data:`NOISE`) is stated as one value instead."""
    from sewgen.report.plots.common import new_figure, save
    from sewgen.study.evaluate import around

    ok = res.table[res.table["status"] == "ok"]
    stats = res.stats
    quantities = [q for q in stats["quantity"] if q in ok and ok[q].dtype != object]
    nr, nc = _grid(len(quantities))
    fig = new_figure((3.2 * nc, 2.4 * nr))
    axes = fig.subplots(nr, nc, squeeze=False)
    for ax, q in zip(axes.flat, quantities):
        v = ok[q].to_numpy(dtype=float)
        v = v[np.isfinite(v)]
        if q in res.periods:
            v = around(v, float(res.nominal[q]), res.periods[q])
        ax.set_title(q, fontsize=8)
        ax.tick_params(labelsize=7)
        if len(v) and np.ptp(v) > NOISE * np.max(np.abs(v)):
            ax.hist(v, bins=min(50, max(5, len(v) // 20)), color="tab:blue", alpha=0.8)
            ax.axvline(float(res.nominal[q]), color="k", lw=0.8, ls="--")
            ax.ticklabel_format(axis="x", useOffset=False)
            ax.locator_params(axis="x", nbins=4)  # long values: few ticks, no overlap
        else:  # no spread beyond rounding: say so instead of an empty histogram
            ax.text(0.5, 0.5, f"every sample: {np.median(v):.6g}" if len(v) else "no finite value", ha="center",
                    va="center", fontsize=9, transform=ax.transAxes)
            ax.set_xticks([])
            ax.set_yticks([])
    for ax in list(axes.flat)[len(quantities):]:
        ax.set_visible(False)
    fig.suptitle(f"{res.machine}: {len(res.table)} samples ({res.distribution}); dashed: nominal", fontsize=10)
    fig.subplots_adjust(hspace=0.6, wspace=0.35, left=0.06, right=0.98, top=0.93, bottom=0.05)
    return [save(fig, Path(folder) / "histograms.png")]


def _write_json(path, data):
    return write_text(path, json.dumps(data, indent=2, ensure_ascii=False, allow_nan=False, default=str) + "\n")


def _write_csv(frame, path, **kw) -> Path:
    """A pandas table as the CSV file ``path``, written whole (sewgen.files.replacing)."""
    with replacing(path, text=True, newline="") as fh:
        frame.to_csv(fh, **kw)
    return Path(path)


def cmd_influence(args, con: Console) -> int:
    from sewgen.machine.assembly import load_machine
    from sewgen.report.outputs import model_path
    from sewgen.study.run import FD_SCHEME, influence

    options = _options(args, loads=not args.no_loads)
    check_folder(args.out, "--out")
    out = Path(args.out)
    if not args.param:
        raise UsageError("--param", "name at least one model-file key, e.g. groups.GROUP.params.NAME")
    machine = load_machine(args.model, allow_outside_code=args.allow_outside_code)
    res = influence(machine, args.param, args.range, args.steps, options,
                    chunk_size=_chunk(args), dask=args.dask, progress=con.show_progress)
    with staged_folder(out, "--out") as tmp:
        files = [_write_csv(res.table, tmp / "influence.csv", index=False),
                 _write_csv(res.sensitivities, tmp / "sensitivities.csv", index=False)]
        if not args.no_plots:
            files += influence_plots(res, tmp)
        bad = res.table[res.table["status"] != "ok"]
        files.append(_write_json(tmp / "study.json", {
            "study": "influence", "machine": machine.name, "model_file": model_path(machine.source),
            "parameters": [{"key": k.key, "unit": k.unit, "nominal": k.nominal * k.factor} for k in res.keys],
            "ranges": res.ranges, "steps": args.steps, "sensitivity_scheme": FD_SCHEME,
            "step_deg": options.step_deg, "exact_jumps": options.exact_jumps, "speed_rad_s": options.speed or machine.speed,
            "designs": int(len(res.table)), "failed_designs": int(len(bad))}))
    con.say(f"{machine.name}: influence of {', '.join(k.key for k in res.keys)}: {len(res.table)} designs, "
            f"{len(bad)} failed; sensitivities by {FD_SCHEME}")
    for k in res.keys:
        for q in ("needle_stroke [mm]", "feed_travel [mm]", "hook_timing_margin [mm]", "take_up_amount [mm]"):
            try:
                s = res.sensitivity(k.key, q)
            except KeyError:
                continue
            con.say(f"  d {q} / d {k.column}: {s:.6g}")
    for f in files:
        con.say(f"wrote {out / Path(f).name}")
    return 0


def _tolerances(items) -> dict:
    out = {}
    for item in items or []:
        key, sep, val = item.partition("=")
        if not sep or not key.strip() or not val.strip():
            raise UsageError("--tolerance", f'"{item}" must be KEY=±TOL, e.g. groups.GROUP.params.NAME=±0.02mm')
        if key.strip() in out:
            raise UsageError("--tolerance", f"{key.strip()} given twice")
        out[key.strip()] = val.strip()
    if not out:
        raise UsageError("--tolerance", "give at least one KEY=±TOL, e.g. groups.GROUP.params.NAME=±0.02mm")
    return out


def cmd_tolerance(args, con: Console) -> int:
    from sewgen.machine.assembly import load_machine
    from sewgen.report.outputs import model_path
    from sewgen.study.run import PERCENTILES, tolerance

    options = _options(args, loads=args.loads)
    check_folder(args.out, "--out")
    out = Path(args.out)
    tols = _tolerances(args.tolerance)
    if args.samples < 1:
        raise UsageError("--samples", f"must be at least 1, got {args.samples}")
    machine = load_machine(args.model, allow_outside_code=args.allow_outside_code)
    res = tolerance(machine, tols, args.samples, args.seed, args.distribution, options, chunk_size=_chunk(args),
                    dask=args.dask, progress=con.show_progress)
    fails = res.failures
    with staged_folder(out, "--out") as tmp:
        files = [_write_csv(res.table, tmp / "samples.csv", index_label="sample"),
                 _write_csv(res.stats, tmp / "percentiles.csv", index=False),
                 _write_csv(fails, tmp / "failures.csv", index_label="sample")]
        if not args.no_plots:
            files += tolerance_plots(res, tmp)
        files.append(_write_json(tmp / "study.json", {
            "study": "tolerance", "machine": machine.name, "model_file": model_path(machine.source),
            "tolerances": [{"key": k.key, "unit": k.unit, "nominal": k.nominal * k.factor, "tolerance": t * k.factor}
                           for k, t in zip(res.keys, res.tolerances)],
            "distribution": res.distribution + (": tolerance = 3 sigma, clipped at 3 sigma"
                                                if res.distribution == "normal" else ": within ± the tolerance"),
            "samples": int(len(res.table)), "seed": args.seed, "percentiles": list(PERCENTILES),
            "failing_designs": int(len(fails)), "step_deg": options.step_deg,
            "exact_jumps": options.exact_jumps}))
    con.say(f"{machine.name}: {len(res.table)} samples ({res.distribution}, seed {args.seed}) of "
            f"{', '.join(k.key for k in res.keys)}; {len(fails)} fail a timing rule or cannot be evaluated")
    st = res.stats.set_index("quantity")
    for q in st.index:
        if "p2.5" in st and not math.isnan(st.loc[q, "p2.5"]):
            con.say(f"  {q:32s} nominal {st.loc[q, 'nominal']:.6g}  p2.5 {st.loc[q, 'p2.5']:.6g}  "
                    f"p97.5 {st.loc[q, 'p97.5']:.6g}  std {st.loc[q, 'std']:.3g}")
    for f in files:
        con.say(f"wrote {out / Path(f).name}")
    return 0


def _study_common(p, common):
    p.add_argument("model", help='a built-in machine ("jb1-3") or a model file (.toml)')
    p.add_argument("--out", required=True, metavar="DIR", help="output folder, written whole or not at all")
    p.add_argument("--step", default="1 deg", help='shaft-angle step of each design\'s sweep (default "1 deg")')
    p.add_argument("--speed", help='upper-shaft speed, e.g. "1500 rpm" (default: the model\'s)')
    p.add_argument("--dask", metavar="SPEC", help="run on Dask: local[:N] (a LocalCluster of N worker processes) "
                                                   "or tcp://host:port (a running scheduler)")
    p.add_argument("--chunk", type=int, metavar="N", help="designs per evaluation call / Dask task")
    p.add_argument("--no-plots", action="store_true", help="tables and study.json only")
    p.add_argument("--exact-jumps", action="store_true",
                   help="the cam-arc acceleration jumps solved at each design's own switch angles (as summary.json; "
                        "5-30 ms a design) instead of extrapolated from the sweep's samples")
    outside_code_option(p)
    common(p)


def add_parser(sub, common) -> None:
    p = sub.add_parser("study", help="design studies: parameter influence, tolerance Monte Carlo (seed 001 §六)",
                       description="Design studies of a machine: how model-file values change the feed-dog "
                                   "indices, the needle stroke, the hook timing, the take-up amount and the loads.")
    ss = p.add_subparsers(dest="study", required=True, metavar="STUDY")
    q = ss.add_parser("influence", help="each parameter moved over a range, the others at nominal; sensitivities")
    _study_common(q, common)
    q.add_argument("--param", action="append", metavar="KEY",
                   help="a model-file key, groups.GROUP.params.NAME, groups.GROUP.phase, shaft.rear_bearing …; "
                        "KEY,KEY2,... moves KEY2... by the same offset (repeatable)")
    q.add_argument("--range", action="append", metavar="LO..HI",
                   help='"-10%%..+10%%" of the nominal (default) or "15 mm..18 mm"; an angle takes an absolute '
                        'range (default: the nominal ± 10 deg), a percentage of it is refused; one for all or one '
                        'per --param')
    q.add_argument("--steps", type=int, default=11, help="values per parameter (default 11)")
    q.add_argument("--no-loads", action="store_true", help="leave out the kinetostatics and the peak loads")
    q.set_defaults(fn=cmd_influence)
    t = ss.add_parser("tolerance", help="Monte Carlo of tolerances: histograms, percentiles, failing designs")
    _study_common(t, common)
    t.add_argument("--tolerance", action="append", metavar="KEY=±TOL",
                   help="e.g. groups.GROUP.params.NAME=±0.02mm or ...=±1%% (repeatable)")
    t.add_argument("--samples", type=int, default=1000, help="Monte Carlo samples (default 1000)")
    t.add_argument("--seed", type=int, default=0, help="random seed, a whole number ≥ 0 (default 0)")
    t.add_argument("--distribution", choices=("normal", "uniform"), default="normal",
                   help="normal: the tolerance is 3σ (default); uniform: within ± the tolerance")
    t.add_argument("--loads", action="store_true", help="also the kinetostatics and the peak loads per sample")
    t.set_defaults(fn=cmd_tolerance)

"""Design studies of a machine (seed 001 §六): parameter influence and tolerance Monte Carlo, in-process or on
Dask.

:func:`run_designs` is the engine: the design table is split into chunks of ``chunk_size`` rows; each chunk is
one :func:`sewgen.study.evaluate.evaluate_chunk` call — in this process, or one task on a Dask worker
(``dask="local"``, ``"local:4"`` for a LocalCluster of 4 worker processes on this machine, or a scheduler's
address ``"tcp://host:8786"``, or a ``distributed.Client``). The chunks are gathered in order into one DataFrame.
Each design is evaluated independently of the chunk it falls in (its own sweep, every index per row), so the
result is the same bit for bit with or without Dask, whatever the chunks (Dask's are larger: :func:`dask_chunk`).
"""
from __future__ import annotations

import math
import re
import sys
from dataclasses import dataclass, field, replace

import numpy as np

from sewgen.errors import SewgenError
from sewgen.study.evaluate import (FAILED, FAILURES, StudyOptions, angle_periods, around, continuous, evaluate_chunk,
                                   quantity_columns)
from sewgen.study.machine_designs import DesignKey, MachineDesigns, parse_keys
from sewgen.units import to_si

#: designs per chunk (one batched evaluation call each): parameter-only designs / designs that reload the model
CHUNK = 1000  # the batched sweep amortises its calls and threads over a chunk (100: 1.4x slower, 5000: slower again)
CHUNK_RELOAD = 4
#: Dask tasks: fewer, larger chunks (the scheduler and client spend ≈ 20 ms of CPU a task, on the workers'
#: cores), at least 6 a worker so the last ones balance: between CHUNK and DASK_CHUNK_MAX designs
DASK_CHUNK_MAX = 4000


def dask_chunk(designs: int, workers: int) -> int:
    """Designs per Dask task for ``designs`` designs on ``workers`` workers (parameter-only designs)."""
    return int(min(DASK_CHUNK_MAX, max(CHUNK, -(-designs // (6 * workers)))))


class StudyError(SewgenError, ValueError):
    """A study's option or setting that cannot work (``parameter`` names it)."""

    def __init__(self, option: str, problem: str):
        super().__init__(f"{option}: {problem}", problem=problem, parameter=option)


def linked_keys(machine, specs) -> tuple[list, list]:
    """Keys that move together: ``"groups.hook_drive.phase,groups.feed.params.hook_crank.phase"`` varies the
    first and moves the others by the same offset from their own nominals (a model's coupling, such as a
    crank one group copies from another, stays as the model has it). Returns (the first keys, the followers of
    each)."""
    firsts, followers = [], []
    for spec in specs:
        parts = [p.strip() for p in str(spec).split(",")] if not isinstance(spec, DesignKey) else [spec]
        if any(p == "" for p in parts):
            raise StudyError("--param", f'"{spec}": an empty key in a linked set (KEY,KEY,...)')
        ks = parse_keys(machine, parts)
        for k in ks[1:]:
            if k.kind != ks[0].kind:
                raise StudyError("--param", f"{k.key} ({k.kind}) cannot move with {ks[0].key} ({ks[0].kind})")
        firsts.append(ks[0])
        followers.append(ks[1:])
    return firsts, followers


def _expand(firsts, followers, values):
    """The design values of the first keys (D, k) with the followers' columns appended: (keys, values)."""
    keys, cols = list(firsts), [values[:, j] for j in range(len(firsts))]
    for j, fol in enumerate(followers):
        for k in fol:
            keys.append(k)
            cols.append(k.nominal + (values[:, j] - firsts[j].nominal))
    return keys, np.column_stack(cols) if cols else values


def _progress(total: int, desc: str, enabled):
    if enabled is False or enabled is None:
        return None
    try:
        from tqdm import tqdm
    except ImportError:  # pragma: no cover
        return None
    return tqdm(total=total, desc=desc, unit="design", file=sys.stderr, leave=False, dynamic_ncols=True)


def dask_client(spec):
    """A ``distributed.Client`` for ``spec``: "local" / "local:N" (a LocalCluster of N worker processes, one
    thread each), an address "tcp://host:port", or a Client (returned as is). Returns (client, close)."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise StudyError("--dask", "needs dask.distributed: pip install 'sewgen[dask]'") from None
    if isinstance(spec, Client):
        return spec, False
    text = str(spec).strip()
    m = re.fullmatch(r"local(?::(\d+))?", text)
    if m:
        n = int(m.group(1)) if m.group(1) else None
        if n is not None and n < 1:
            raise StudyError("--dask", f"local:N needs N >= 1 workers, got {n}")
        import dask

        # Dask's nanny starts workers with MALLOC_TRIM_THRESHOLD_=65536, which turns glibc's adaptive mmap
        # threshold off: every NumPy temporary above 128 KiB is then mapped and unmapped afresh (twice the page
        # faults, and markedly more CPU for a study's chunk). A study's workers run without it.
        with dask.config.set({"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}):
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0")
        return Client(cluster), True
    if re.fullmatch(r"(tcp|tls|inproc|ws|wss)://\S+", text):
        try:
            return Client(text, timeout="10s"), True
        except OSError as exc:
            raise StudyError("--dask", f"cannot reach the scheduler at {text}: {exc}") from None
    raise StudyError("--dask", f'"{text}" is neither local, local:N nor a scheduler address tcp://host:port')


def design_columns(machine, table) -> tuple[list, np.ndarray]:
    """(keys, SI values) of a design table whose columns are model-file keys, in SI (``groups.feed.params.x``)
    or with a unit (``groups.feed.params.x [mm]``, as the study tables name them): a DataFrame or a mapping."""
    keys, cols = [], []
    names = list(table.columns) if hasattr(table, "columns") else list(table)
    for name in names:
        m = re.fullmatch(r"(?P<key>.*?)\s*\[(?P<unit>[^\]]*)\]", str(name))
        key = parse_keys(machine, [m["key"] if m else str(name)])[0]
        factor = 1.0
        if m and m["unit"].strip():
            try:
                factor = to_si(f"1 {m['unit'].strip()}", key.kind, str(name))
            except SewgenError as exc:
                raise StudyError(str(name), exc.problem) from None
        keys.append(key)
        cols.append(np.asarray(table[name], dtype=float) * factor)
    return keys, (np.column_stack(cols) if cols else np.zeros((0, 0)))


def _in_process(machine, keys, chunks, options, bar) -> list:
    """Every chunk evaluated in this process, in order. With ``options.threads`` None (every core) and more
    than one chunk, the chunks run on a pool of one thread a core, each chunk's sweep on one thread: the
    C sweep and NumPy (both releasing the GIL) of different chunks overlap instead of the NumPy part running
    alone while the cores wait. Each chunk is evaluated as it would be alone, so the result is the same."""
    import os
    from concurrent.futures import ThreadPoolExecutor

    workers = min(os.cpu_count() or 1, len(chunks)) if options.threads is None else 1
    if workers <= 1:
        parts = []
        for c in chunks:
            parts.append(evaluate_chunk(machine, keys, c, options))
            if bar is not None:
                bar.update(len(c))
        return parts
    one = replace(options, threads=1)
    parts = [evaluate_chunk(machine, keys, chunks[0], one)]  # the nominal baseline, once, before the pool
    if bar is not None:
        bar.update(len(chunks[0]))

    def run(c):
        df = evaluate_chunk(machine, keys, c, one)
        if bar is not None:
            bar.update(len(c))
        return df

    with ThreadPoolExecutor(max_workers=workers) as pool:
        parts += list(pool.map(run, chunks[1:]))
    return parts


def evaluate_pieces(machine, keys, values, options):
    """A Dask task's designs evaluated in pieces of :data:`CHUNK` (:func:`evaluate_chunk` each, the results
    joined): a task is larger than a chunk (fewer tasks, less scheduler work), but the chunk's arrays are the
    size that keeps a core's caches warm. Each design is evaluated as it would be alone: the same table."""
    from sewgen.engine.frames import pandas

    if len(values) <= CHUNK:
        return evaluate_chunk(machine, keys, values, options)
    parts = [evaluate_chunk(machine, keys, values[a:a + CHUNK], options) for a in range(0, len(values), CHUNK)]
    return pandas().concat(parts, ignore_index=True)


def run_designs(machine, keys, values=None, options: StudyOptions | None = None, *, chunk_size: int | None = None,
                dask=None, progress=None):
    """Every design of ``machine`` evaluated: ``keys`` (model-file keys) × ``values`` ((D, k), SI), or ``keys``
    a design table (a DataFrame or mapping whose columns are keys, SI or with a unit: ``"<key> [mm]"``) and no
    ``values``. Returns a DataFrame with the keys (display units), ``status``, ``error`` and every quantity, one
    row per design in the table's order."""
    from sewgen.engine.frames import pandas

    pd = pandas()
    options = options or StudyOptions()
    if values is None:
        keys, values = design_columns(machine, keys)
    keys = parse_keys(machine, keys)
    values = np.asarray(values, dtype=float)
    MachineDesigns(machine, keys, values[:0])  # the keys checked before any work
    d = len(values)
    reload = any(k.group is None for k in keys)

    def cut(size):
        bounds = list(range(0, d, size)) + [d]
        return [values[a:b] for a, b in zip(bounds[:-1], bounds[1:])]

    bar = _progress(d, f"{machine.name}: {d} designs", progress)
    parts = []
    try:
        if dask is None:
            chunks = cut(chunk_size or (CHUNK_RELOAD if reload else CHUNK))
            parts = _in_process(machine, keys, chunks, options, bar)
        else:
            from distributed import as_completed

            client, close = dask_client(dask)
            try:
                size = chunk_size
                if size is None:
                    workers = max(1, len(client.scheduler_info().get("workers", {})))
                    size = CHUNK_RELOAD if reload else dask_chunk(d, workers)
                chunks = cut(size)
                mref = client.scatter(machine, broadcast=True)
                # one thread per task: the workers are the parallelism (threads in each would oversubscribe)
                on_worker = replace(options, threads=1)
                futures = [client.submit(evaluate_pieces, mref, keys, c, on_worker, pure=False) for c in chunks]
                where = {f.key: k for k, f in enumerate(futures)}
                parts = [None] * len(futures)
                # each result fetched as its task ends (overlapping the transfers with the other tasks' work),
                # placed by its chunk's index; a task's error raises here
                for f, df in as_completed(futures, with_results=True, raise_errors=True):
                    k = where[f.key]
                    parts[k] = df
                    if bar is not None:
                        bar.update(len(chunks[k]))
            finally:
                if close:
                    cluster = getattr(client, "cluster", None)
                    client.close()
                    if cluster is not None:
                        cluster.close()
    finally:
        if bar is not None:
            bar.close()
    if not parts:
        return evaluate_chunk(machine, keys, values[:0], options)
    return pd.concat(parts, ignore_index=True)


# -- influence ------------------------------------------------------------------------------------------------

#: The finite-difference scheme of the sensitivities (docs/how-to/design-studies.md, "Influence").
FD_SCHEME = "central difference (f(x+δ) − f(x−δ)) / 2δ at the nominal, δ = 1e-4 × |nominal| (1e-4 × the range if the nominal is 0)"
FD_RELATIVE = 1e-4


#: The default range of an influence study: ±10 % of the nominal, or for an angle (a phase, a regulator setting)
#: the nominal ± :data:`ANGLE_SPAN_DEG`: a percentage of an angle means nothing (10 % of a −2° phase is 0.2°, of a
#: 40° setting 4°), and of a full turn (36°) it would move a timing far past any adjustment.
DEFAULT_RANGE = "-10%..+10%"
ANGLE_SPAN_DEG = 10.0


def default_range(key: DesignKey) -> str:
    """The range an influence study moves ``key`` over when none is given (:data:`DEFAULT_RANGE`)."""
    if key.kind != "angle":
        return DEFAULT_RANGE
    nominal = math.degrees(key.nominal)
    return f"{nominal - ANGLE_SPAN_DEG:.12g} deg..{nominal + ANGLE_SPAN_DEG:.12g} deg"


def _no_percent_of_angle(key: DesignKey, text: str, option: str, example: str) -> None:
    if key.kind == "angle":
        raise StudyError(option, f'{key.key}: "{text}" is a percentage of an angle, which means nothing (of a '
                                 f"{math.degrees(key.nominal):.6g}° nominal); give the angle with its unit, e.g. "
                                 f'"{example}"')


def parse_range(key: DesignKey, text: str, option: str = "--range") -> tuple[float, float]:
    """"-10%..+10%" (relative to the nominal) or "15 mm..18 mm" (absolute) -> (lo, hi) in SI. An angle takes an
    absolute range only ("-12 deg..8 deg"): a percentage of it is refused (:data:`DEFAULT_RANGE`)."""
    lo_t, sep, hi_t = str(text).partition("..")
    if not sep or not lo_t.strip() or not hi_t.strip():
        raise StudyError(option, f'"{text}" must be LO..HI, e.g. "-10%..+10%" or "15 mm..18 mm"')
    ends = []
    for t in (lo_t.strip(), hi_t.strip()):
        if t.endswith("%"):
            _no_percent_of_angle(key, text, option, default_range(key))
            try:
                frac = float(t[:-1]) / 100.0
            except ValueError:
                raise StudyError(option, f'"{t}" is not a percentage') from None
            if key.nominal == 0.0:
                raise StudyError(option, f"{key.key} is 0 in the model: give an absolute range with units")
            ends.append(key.nominal * (1.0 + frac))
        else:
            try:
                ends.append(key.parse(t, option))
            except SewgenError as exc:
                raise StudyError(option, f"{key.key}: {exc.problem}") from None
    lo, hi = min(ends), max(ends)
    if not hi > lo:
        raise StudyError(option, f'"{text}" is an empty range')
    return lo, hi


@dataclass
class InfluenceResult:
    """``table``: one row per design (the column ``varied`` names the key moved; the others at nominal);
    ``sensitivities``: one row per (key, quantity) with d quantity / d key in display units, by :data:`FD_SCHEME`;
    ``periods``: column -> period (deg) of the quantities that are angles (drawn continuous across it);
    ``ranges``: the range each key was moved over, as given or its default (:func:`default_range`)."""

    machine: str
    keys: list
    table: object
    sensitivities: object
    nominal: object
    scheme: str = FD_SCHEME
    periods: dict = field(default_factory=dict)
    ranges: list = field(default_factory=list)

    def curve(self, key: str, quantity: str) -> tuple:
        """(values of ``key``, of ``quantity``) over the designs that varied ``key``, in the key's order, in the
        table's units; an angle (:attr:`periods`) continuous across its period (:func:`continuous`), as the
        influence plots draw it."""
        k = next((k for k in self.keys if k.key == key), None)
        if k is None:
            raise KeyError(f"{key!r} was not varied; varied: {', '.join(k.key for k in self.keys)}")
        rows = self.table[self.table["varied"] == key].sort_values(k.column)
        y = rows[quantity].to_numpy(dtype=float)
        if quantity in self.periods:
            y = continuous(y, float(self.nominal[quantity]), self.periods[quantity])
        return rows[k.column].to_numpy(dtype=float), y

    def sensitivity(self, key: str, quantity: str) -> float:
        s = self.sensitivities
        row = s[(s["parameter"] == key) & (s["quantity"] == quantity)]
        if row.empty:
            raise KeyError(f"no sensitivity of {quantity!r} to {key!r}")
        return float(row["sensitivity"].iloc[0])

    def to_dataframe(self):
        return self.table

    def __repr__(self) -> str:
        return (f"<InfluenceResult {self.machine}: {len(self.table)} designs over "
                f"{', '.join(k.key for k in self.keys)}; sensitivities by {self.scheme.split(' at')[0]}>")


def influence(machine, params, ranges=None, steps: int = 11, options: StudyOptions | None = None, **run):
    """Seed 001 §六: each key of ``params`` moved alone over its range (``ranges``: one per key, or one for
    all; None: each key's :func:`default_range`) in ``steps`` equal steps, the others at nominal; plus the
    nominal ± δ for the sensitivities."""
    from sewgen.engine.frames import pandas

    pd = pandas()
    options = options or StudyOptions()
    keys, followers = linked_keys(machine, params)
    if not ranges:
        ranges = [default_range(k) for k in keys]
    if isinstance(ranges, str):
        ranges = [ranges]
    if len(ranges) == 1:
        ranges = list(ranges) * len(keys)
    if len(ranges) != len(keys):
        raise StudyError("--range", f"give one range for all parameters or one per parameter ({len(keys)}), "
                                    f"got {len(ranges)}")
    if not (isinstance(steps, int) and steps >= 2):
        raise StudyError("--steps", f"must be an integer of at least 2, got {steps!r}")
    nominal = np.array([k.nominal for k in keys])
    rows, varied, role = [nominal.copy()], [""], ["nominal"]
    deltas = []
    for j, (k, r) in enumerate(zip(keys, ranges)):
        lo, hi = parse_range(k, r)
        for v in np.linspace(lo, hi, steps):
            row = nominal.copy()
            row[j] = v
            rows.append(row)
            varied.append(k.key)
            role.append("range")
        delta = FD_RELATIVE * (abs(k.nominal) if k.nominal != 0 else (hi - lo))
        deltas.append(delta)
        for sgn in (1.0, -1.0):
            row = nominal.copy()
            row[j] = k.nominal + sgn * delta
            rows.append(row)
            varied.append(k.key)
            role.append("fd+" if sgn > 0 else "fd-")
    df = run_designs(machine, *_expand(keys, followers, np.array(rows)), options, **run)
    df.insert(0, "varied", varied)
    df.insert(1, "role", role)
    quantities = [c for c in quantity_columns(machine, options) if c != FAILED]
    periods = angle_periods(machine, options)
    sens = []
    for j, k in enumerate(keys):
        plus = df[(df["varied"] == k.key) & (df["role"] == "fd+")].iloc[0]
        minus = df[(df["varied"] == k.key) & (df["role"] == "fd-")].iloc[0]
        step = 2 * deltas[j] * k.factor
        for q in quantities:
            try:
                hi, lo = float(plus[q]), float(minus[q])
            except (TypeError, ValueError):
                hi = lo = math.nan
            if q in periods:  # an angle: its change, not the wrap of its value (359.9° after 0.1°)
                hi = float(around(hi, lo, periods[q]))
            value = (hi - lo) / step
            qunit = q[q.rfind("[") + 1:-1] if q.endswith("]") else "1"
            sens.append({"parameter": k.key, "quantity": q,
                         "sensitivity": value, "unit": f"{qunit}/{k.unit or '1'}",
                         "step": deltas[j] * k.factor, "step_unit": k.unit})
    table = df[df["role"] != "fd+"]
    table = table[table["role"] != "fd-"].reset_index(drop=True)
    return InfluenceResult(machine.name, keys, table, pd.DataFrame(sens), df.iloc[0], periods=periods,
                           ranges=list(ranges))


# -- tolerance ------------------------------------------------------------------------------------------------

def parse_tolerance(key: DesignKey, text: str, option: str = "--tolerance") -> float:
    """"±0.02mm", "+-0.02 mm", "+/-0.02 mm", "±1%" -> the half-width in SI (≥ 0). The ± is required: "0.02 mm"
    alone could be a half-width, a full width or a one-sided limit, so it is refused naming the key. An angle's
    tolerance is an angle ("±0.5 deg"): a percentage of it is refused, as in :func:`parse_range`."""
    t = str(text).strip()
    for pre in ("±", "+-", "+/-"):
        if t.startswith(pre):
            t = t[len(pre):].strip()
            break
    else:
        raise StudyError(option, f'{key.key}: "{text}" has no ±: write the tolerance as a half-width, e.g. '
                                 f'"±{t}" (or "+-{t}", "±1%")')
    if t.endswith("%"):
        _no_percent_of_angle(key, text, option, "±0.5 deg")
        try:
            return abs(key.nominal) * float(t[:-1]) / 100.0
        except ValueError:
            raise StudyError(option, f'{key.key}: "{text}" is not a percentage') from None
    try:
        v = key.parse(t, option)
    except SewgenError as exc:
        raise StudyError(option, f"{key.key}: {exc.problem}") from None
    if v < 0:
        raise StudyError(option, f'{key.key}: a tolerance is a half-width ≥ 0, got "{text}"')
    return v


#: Percentiles reported (the ±3σ band of a normal distribution, 95 %, the median)
PERCENTILES = (0.135, 2.5, 50.0, 97.5, 99.865)


@dataclass
class ToleranceResult:
    machine: str
    keys: list
    tolerances: list  # SI half-widths
    distribution: str
    seed: int | None
    table: object
    nominal: object
    stats: object = field(default=None)
    periods: dict = field(default_factory=dict)  # column -> period (deg) of the angle quantities

    @property
    def failures(self):
        """The designs that fail a timing rule (or cannot be evaluated)."""
        t = self.table
        bad = t["status"] != "ok"
        if FAILURES in t:
            bad |= t[FAILURES].fillna(0) > 0
        return t[bad]

    def to_dataframe(self):
        return self.table

    def __repr__(self) -> str:
        return (f"<ToleranceResult {self.machine}: {len(self.table)} samples ({self.distribution}, seed "
                f"{self.seed}) of {', '.join(k.key for k in self.keys)}; {len(self.failures)} failing>")


def tolerance(machine, tolerances: dict, samples: int = 1000, seed: int | None = 0, distribution: str = "normal",
              options: StudyOptions | None = None, **run):
    """Monte Carlo: every key of ``tolerances`` (key -> "±0.02 mm") drawn independently round its nominal —
    ``normal``: the tolerance is 3σ (clipped at ±3σ); ``uniform``: anywhere within ± the tolerance."""
    options = options or StudyOptions(loads=False)
    specs = list(tolerances)
    keys, followers = linked_keys(machine, specs)
    tol = np.array([parse_tolerance(k, tolerances[spec]) for k, spec in zip(keys, specs)])
    if not (isinstance(samples, (int, np.integer)) and samples >= 1):
        raise StudyError("--samples", f"must be a positive integer, got {samples!r}")
    if distribution not in ("normal", "uniform"):
        raise StudyError("--distribution", f"normal or uniform, not {distribution!r}")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0):
        raise StudyError("--seed", f"a seed is a whole number ≥ 0 (or None: a fresh one), got {seed!r}")
    rng = np.random.default_rng(seed)
    if distribution == "normal":
        u = np.clip(rng.standard_normal((samples, len(keys))) / 3.0, -1.0, 1.0)
    else:
        u = rng.uniform(-1.0, 1.0, (samples, len(keys)))
    nominal = np.array([k.nominal for k in keys])
    values = nominal[None, :] + u * tol[None, :]
    df = run_designs(machine, *_expand(keys, followers, np.vstack([nominal[None, :], values])), options, **run)
    nom, table = df.iloc[0], df.iloc[1:].reset_index(drop=True)
    res = ToleranceResult(machine.name, keys, list(tol), distribution, seed, table, nom,
                          periods=angle_periods(machine, options))
    res.stats = statistics(res, quantity_columns(machine, options))
    return res


def statistics(res: ToleranceResult, quantities):
    """Per quantity: the nominal, mean, std, min, max, spread and :data:`PERCENTILES` of the designs that could be
    evaluated; an angle (``res.periods``) taken within half its period of the nominal (:func:`around`), so a
    spread across 0°/360° is the spread, not a turn."""
    from sewgen.engine.frames import pandas

    pd = pandas()
    ok = res.table[res.table["status"] == "ok"]
    rows = []
    for q in quantities:
        if q in (FAILED,):
            continue
        v = ok[q].to_numpy(dtype=float)
        v = v[np.isfinite(v)]
        nominal = float(res.nominal[q]) if res.nominal[q] is not None else math.nan
        if q in res.periods and math.isfinite(nominal):
            v = around(v, nominal, res.periods[q])
        row = {"quantity": q, "nominal": nominal, "samples": int(len(v))}
        if len(v):
            dv = v - v[0]  # shift-invariant: identical samples give exactly 0
            row.update(mean=float(v[0] + dv.mean()), std=float(dv.std()), min=float(v.min()), max=float(v.max()),
                       spread=float(v.max() - v.min()))
            for p, val in zip(PERCENTILES, np.percentile(v, PERCENTILES)):
                row[f"p{p:g}"] = float(val)
        rows.append(row)
    return pd.DataFrame(rows)

"""The stitch-formation cycle diagram: the bar chart of one revolution a designer draws (sewgen.machine.timing).

One row per mechanism (needle, shuttle, take-up, feed dog), its phases as bars against the shaft angle φ
(a darker and a lighter tone for the two halves of its motion, a narrow bar inside for what it does then:
the needle rising, the hook carrying the loop, the feed stroke), the events as numbered markers on their row
and listed with their angles beside the chart, and the needle point's time in the cloth shaded across all rows
(the feed dog must be below the plate there). A footer lists every timing rule with its value and margin.
"""
from __future__ import annotations

import math

import numpy as np

from sewgen.roles import FEED_DOG, HOOK_POINT, LOWER_LOOPER_TIP, NEEDLE_EYE, NEEDLE_POINT, THREAD_EYE, UPPER_LOOPER_TIP
from sewgen.report.plots.common import DPI, new_figure, save, suptitle
from sewgen.machine.timing import timing
from sewgen.report.plots.thread import draw_thread_timing, thread_size

ROWS = ("needle", "shuttle", "lower looper", "upper looper", "take-up", "feed dog")
#: row -> (dark, light, inner) colours
TONES = {"needle": ("#4a6fa5", "#b9cbe4", "#1f3b66"), "shuttle": ("#d08a2e", "#f2d3a6", "#7a4a0c"),
         "take-up": ("#3f9a5a", "#bfe3c8", "#195c2c"), "feed dog": ("#b54848", "#efc0c0", "#6b1515"),
         "lower looper": ("#d08a2e", "#f2d3a6", "#7a4a0c"), "upper looper": ("#8a5fb0", "#d9c6ea", "#4a2a6b")}
_ROLE_ROW = {NEEDLE_POINT: "needle", NEEDLE_EYE: "needle", HOOK_POINT: "shuttle", THREAD_EYE: "take-up",
             FEED_DOG: "feed dog", LOWER_LOOPER_TIP: "lower looper", UPPER_LOOPER_TIP: "upper looper"}


def _spans(start, end):
    """[(left, width)] in degrees of the arc from ``start`` to ``end`` (rad) going forward, split at 360°."""
    a, b = math.degrees(start) % 360.0, math.degrees(end) % 360.0
    if b >= a:
        return [(a, b - a)]
    return [(a, 360.0 - a), (0.0, b)]


_LINE = 0.135  # inches per line of the monospaced footer


def _foot(rules: int):
    return _LINE * (rules + 1) + 0.45 if rules else 0.2


def cycle_size(what):
    """The figure's size (inches) for a Timing, or for a Machine (before its timing is worked out: every row)."""
    if hasattr(what, "phases"):
        rows = len([r for r in ROWS if any(p.row == r for p in what.phases)])
        rules = len(what.checks)
    else:
        rows, rules = len(ROWS), len(what.stitch.rules) if getattr(what, "stitch", None) else 0
    return (15.0, round(1.75 + 1.05 * max(rows, 1) + _foot(rules), 2))


def draw_cycle_timing(fig, tm):
    """The cycle diagram of ``tm`` (sewgen.machine.timing.Timing) on ``fig``; returns the rows drawn."""
    rows = [r for r in ROWS if any(p.row == r for p in tm.phases)] or list(ROWS)
    W, H = fig.get_size_inches()
    foot = _foot(len(tm.checks))
    left = 0.35 + 0.085 * max(len(r) for r in rows)  # inches: room for the longest row label
    ax = fig.add_axes([left / W, (foot + 0.55) / H, (W - 4.4 - left) / W, (H - foot - 1.3) / H])
    per_deg = (W - 4.4 - left) * 72.0 / 360.0  # points per degree of shaft angle
    n = len(rows)
    y_of = {r: n - 1 - k for k, r in enumerate(rows)}
    if "needle_in_cloth" in tm.values and "needle_out_cloth" in tm.values:
        spans = _spans(tm.values["needle_in_cloth"], tm.values["needle_out_cloth"])
        for k, (left, width) in enumerate(spans):
            ax.axvspan(left, left + width, color="0.85", zorder=0, label="needle point in the cloth" if k == 0 else None)
    for r in rows:
        y = y_of[r]
        dark, light, inner = TONES[r]
        mains = [p for p in tm.phases if p.row == r and p.style == "main"]
        for k, p in enumerate(mains):
            for left, width in _spans(p.start, p.end):
                ax.broken_barh([(left, width)], (y - 0.32, 0.64), facecolors=(dark, light)[k % 2], edgecolor="w",
                               lw=0.8, zorder=2)
            _label(ax, p, y + 0.18, "w" if k % 2 == 0 else "0.15", 7.5, per_deg)
        for p in (p for p in tm.phases if p.row == r and p.style == "inner"):
            for left, width in _spans(p.start, p.end):
                ax.broken_barh([(left, width)], (y - 0.3, 0.2), facecolors=inner, edgecolor="none", zorder=3,
                               alpha=0.9)
            _label(ax, p, y - 0.2, "w", 6.8, per_deg)
    events = sorted(tm.events, key=lambda e: e.deg)
    last = {}  # row -> (angle, stagger) of the last number placed: close events are numbered one above the other
    for k, e in enumerate(events, 1):
        r = _ROLE_ROW.get(e.role)
        if r not in y_of:
            continue
        y = y_of[r]
        prev = last.get(r)
        lift = prev[1] + 1 if prev is not None and (e.deg - prev[0]) * per_deg < 11 else 0
        last[r] = (e.deg, lift)
        ax.plot([e.deg], [y + 0.42], "v", color="k", ms=5, zorder=5)
        ax.annotate(str(k), (e.deg, y + 0.42), xytext=(0, 4 + 8 * lift), textcoords="offset points", ha="center",
                    va="bottom", fontsize=7, zorder=6)
        ax.plot([e.deg, e.deg], [y - 0.34, y + 0.36], color="k", lw=0.6, zorder=4)
    for key, text in (("bdc", "needle BDC"), ("tdc", "needle TDC")):
        if key in tm.values:
            ax.axvline(math.degrees(tm.values[key]) % 360, color="k", lw=0.8, ls=":", zorder=1)
            ax.text(math.degrees(tm.values[key]) % 360, -0.56, f" {text}", fontsize=7, ha="left", va="bottom",
                    color="0.3")
    ax.set_xlim(0, 360)
    ax.set_xticks(np.arange(0, 361, 30))
    ax.set_ylim(-0.6, n - 0.3)
    ax.set_yticks([y_of[r] for r in rows])
    ax.set_yticklabels(rows, fontsize=10)
    ax.set_xlabel("shaft angle φ (deg)")
    ax.grid(axis="x", alpha=0.35)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.0), fontsize=8, frameon=False)
    # the numbered events, beside the chart
    lines = [f"{k:2d}  {e.deg:7.2f}°  {e.name}" for k, e in enumerate(events, 1)]
    fig.text((W - 4.25) / W, 1 - 0.75 / H, "events (φ)\n" + "\n".join(_wrap(l, 52) for l in lines),
             ha="left", va="top", fontsize=6.6, family="monospace")
    # the rules, below
    rule_lines = [f"{'pass' if c.ok else 'FAIL'}  {c.rule:33s} {c.value:9.3f} {c.unit:3s}  limit {c.limit:15s} "
                  f"margin {c.margin:8.3f}" for c in tm.checks]
    if rule_lines:
        fig.text(0.9 / W, (foot - 0.05) / H, "timing rules\n" + "\n".join(rule_lines), ha="left", va="top",
                 fontsize=7.2, family="monospace",
                 color="k" if tm.ok else "darkred")
    bad = len(tm.failed)
    verdict = "all rules pass" if not bad else f"{bad} rule{'s' * (bad > 1)} FAIL"
    suptitle(fig, f"{tm.machine.name}: stitch-formation cycle diagram at {tm.speed * 30 / math.pi:.0f} rpm — "
                  f"{verdict}")
    return rows


def _wrap(line, width):
    if len(line) <= width:
        return line
    cut = line.rfind(" ", 0, width)
    return line[:cut] + "\n" + " " * 14 + line[cut + 1:]


def _label(ax, p, y, color, size, per_deg):
    """The phase's name inside its longest bar, if it fits (``per_deg``: points per degree)."""
    left, width = max(_spans(p.start, p.end), key=lambda s: s[1])
    if width * per_deg > 0.6 * size * len(p.name) + 6:
        ax.text(left + width / 2, y, p.name, ha="center", va="center", fontsize=size, color=color, zorder=6)


def draw_cycle(fig, a):
    """The stitch-formation cycle diagram of analysis ``a``'s machine (its timing at the analysis' speed)."""
    return draw_cycle_timing(fig, timing(a.machine, speed=float(a.omega[0])))


def write_timing_plots(tm, folder) -> list:
    """cycle_diagram.png and, with a thread path, thread_control.png of ``tm`` into ``folder`` (which must exist);
    returns the paths."""
    from pathlib import Path

    folder = Path(folder)
    fig = new_figure(cycle_size(tm))
    draw_cycle_timing(fig, tm)
    out = [save(fig, folder / "cycle_diagram.png", dpi=DPI)]
    if tm.thread is not None:
        fig = new_figure(thread_size(tm))
        draw_thread_timing(fig, tm)
        out.append(save(fig, folder / "thread_control.png", dpi=DPI))
    return out

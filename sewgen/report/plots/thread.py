"""Thread control curves (sewgen.machine.thread): the take-up's supply S = L_max − L, the stitch's demand D and the
slack S − D against the shaft angle, the demand's parts, where the hook carries the loop; and the take-up eye's speed
and acceleration (seed 004's figure-3 quantities)."""
from __future__ import annotations

import math

import numpy as np

from sewgen.report.plots.common import place, suptitle
from sewgen.machine.timing import timing

MM = 1e3


def thread_size(_=None):
    return (13.0, 8.4)


def _closed(phi, y):
    d = np.degrees(phi)
    return np.append(d, 360.0), np.append(y, y[0])


def _shade_window(ax, th, label=None):
    a, b = (math.degrees(v) % 360.0 for v in th.window)
    spans = [(a, b)] if b >= a else [(a, 360.0), (0.0, b)]
    for k, (lo, hi) in enumerate(spans):
        ax.axvspan(lo, hi, color="tab:orange", alpha=0.13, lw=0, label=label if k == 0 else None)


def draw_thread_timing(fig, tm):
    """Supply, demand, slack; eye speed and acceleration, for ``tm`` (sewgen.machine.timing.Timing with a thread)."""
    th = tm.thread
    axes = place(fig, 2, 1, left=0.9, right=0.9, top=0.75, bottom=1.45, hspace=0.75, sharex=True,
                 height_ratios=(1.6, 1.0))
    ax, bx = axes[0, 0], axes[1, 0]
    phi = th.phi
    _shade_window(ax, th, "hook carries the loop (slack rule applies)")
    ax.plot(*_closed(phi, th.supply * MM), color="tab:green", lw=2,
            label="supply S = L_max − L (take-up, needle-bar guide)")
    ax.plot(*_closed(phi, th.demand * MM), color="tab:red", lw=2, label="demand D (needle + loop + stitch)")
    slack = th.slack * MM
    ax.plot(*_closed(phi, slack), color="k", lw=1.6, label="slack S − D + T")
    ax.plot(*_closed(phi, th.drawn * MM), color="0.45", lw=1.2, ls="--", label="T: drawn through the tension")
    for name, style in (("needle", (0, (4, 2))), ("loop", (0, (1, 1.5))), ("stitch", (0, (6, 2, 1, 2)))):
        ax.plot(*_closed(phi, th.parts[name] * MM), color="tab:red", lw=0.9, ls=style, alpha=0.8,
                label=f"demand: {name}")
    ax.axhline(0, color="0.4", lw=0.7)
    k = int(np.argmin(np.abs(np.angle(np.exp(1j * (phi - th.min_slack_at))))))
    ax.plot([math.degrees(th.min_slack_at) % 360], [th.min_slack * MM], "o", mfc="none", mec="k", ms=8)
    ax.annotate(f"least slack {th.min_slack * MM:.2f} mm\nat φ = {math.degrees(th.min_slack_at) % 360:.1f}°",
                (math.degrees(th.min_slack_at) % 360, slack[k]), xytext=(12, -28), textcoords="offset points",
                fontsize=8, arrowprops=dict(arrowstyle="-", color="0.3", lw=0.7))
    top = ax.get_ylim()[1]
    for when, text, c in ((th.set_at, "stitch set\n(take-up top)", "tab:green"),
                          (th.window[0], "hook takes\nthe loop", "tab:orange"),
                          (th.window[1], "loop\ncast off", "tab:orange")):
        ax.axvline(math.degrees(when) % 360, color=c, lw=0.9, ls="--")
        ax.text(math.degrees(when) % 360, top, " " + text.replace("\n", "\n "), fontsize=7.5, va="top", ha="left",
                color=c)
    ax.set_ylabel("thread (mm)")
    ax.grid(alpha=0.3)
    ax.set_title(f"thread path {th.length.min() * MM:.1f} – {th.length.max() * MM:.1f} mm through "
                 f"{len(th.guides)} guides; take-up amount per stitch {th.take_up_amount * MM:.1f} mm; "
                 f"drawn through the tension per stitch {th.per_stitch * MM:.1f} mm", fontsize=9.5, y=1.0)
    fig.legend(*ax.get_legend_handles_labels(), loc="lower center", ncol=3, fontsize=7.8, frameon=True,
               bbox_to_anchor=(0.5, 0.05 / fig.get_size_inches()[1]))
    d, v = _closed(phi, th.eye_speed)
    bx.plot(d, v, color="tab:blue", lw=1.6, label="take-up eye speed |v|")
    bx.set_ylabel("speed (m/s)", color="tab:blue")
    cx = bx.twinx()
    d, acc = _closed(phi, th.eye_accel)
    cx.plot(d, acc, color="tab:purple", lw=1.3, ls="--", label="take-up eye acceleration |a|")
    cx.set_ylabel("acceleration (m/s²)", color="tab:purple")
    i, j = int(np.argmax(th.eye_speed)), int(np.argmax(th.eye_accel))
    bx.set_title(f"take-up eye at {th.speed * 30 / math.pi:.0f} rpm: peak speed {th.eye_speed[i]:.2f} m/s at "
                 f"φ = {math.degrees(phi[i]) % 360:.0f}°, peak acceleration {th.eye_accel[j]:.0f} m/s² at "
                 f"φ = {math.degrees(phi[j]) % 360:.0f}° (seed 004 fig. 3 quantities)", fontsize=9.5, y=1.0)
    bx.grid(alpha=0.3)
    bx.set_xlim(0, 360)
    bx.set_xticks(np.arange(0, 361, 30))
    bx.set_xlabel("shaft angle φ (deg)")
    h1, l1 = bx.get_legend_handles_labels()
    h2, l2 = cx.get_legend_handles_labels()
    bx.legend(h1 + h2, l1 + l2, loc="upper right", fontsize=7.5)
    suptitle(fig, f"{tm.machine.name}: thread control — supply, demand and slack of the needle thread")


def draw_thread(fig, a):
    """Thread control of analysis ``a``'s machine (its timing at the analysis' speed)."""
    draw_thread_timing(fig, timing(a.machine, speed=float(a.omega[0])))

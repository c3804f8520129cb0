"""Forces: polar diagrams of the upper-shaft bearing loads and of each group's three most loaded joints, the
driving torque, and the shaking force and moments (about z, and the base's rocking about x and y)."""
from __future__ import annotations

import math

import numpy as np

from sewgen.machine.peaks import analysis_at, extremes
from sewgen.report.plots.common import angle_axis, angle_labels, closed, color, deg, place, shade_loads, suptitle, title

MAIN_JOINTS = 3  # joints per group in the joint-reaction figure: the most loaded ones
_QUIET = np.arange(22.5, 360, 45)


def _rings(top: float) -> np.ndarray:
    """Two to four evenly spaced rings (a step of 1, 2, 2.5 or 5 times a power of ten): the outermost the
    smallest that reaches ``top``, then the fewest rings."""
    top = max(top, 1e-12)
    best = None
    e0 = int(math.floor(math.log10(top)))
    for e in range(e0 + 1, e0 - 3, -1):  # fewer rings first when two reach as far
        for m in (5.0, 2.5, 2.0, 1.0):
            step = m * 10.0**e
            k = math.ceil(top / step - 1e-9)
            if 2 <= k <= 4 and (best is None or k * step < best[0] * best[1] - 1e-12):
                best = (k, step)
    k, step = best
    return step * np.arange(1, k + 1)


def _peak_of(a, quantity, sense="max"):
    """(Extreme, the analysis at its angle or None) of ``quantity`` (a function of an analysis): the peak
    refined between the samples as summary.json's (sewgen.machine.peaks), so figure and summary agree."""
    ext = extremes(a, {"q": quantity}, (sense,))["q"][sense]
    return ext, analysis_at(a, np.array([ext.angle]))


def _polar(ax, a, vector, c, text, step=90.0):
    """Hodograph of a force as a polar diagram: the force vector's tip (``vector(analysis)``: (n, 2)), so its
    direction is the polar angle and its magnitude (N) the radius, on equal-aspect axes with a drawn polar grid
    (rings with their magnitudes, spokes every 45° with their directions); shaft-angle labels on the curve; the
    peak refined between the samples, marked."""
    from matplotlib.collections import LineCollection

    f = vector(a)
    fx, fy = f[:, 0], f[:, 1]
    mag = np.hypot(fx, fy)
    ext, there = _peak_of(a, lambda b: np.hypot(*vector(b).T))
    tip = vector(there)[0] if there is not None else f[int(np.argmax(mag))]
    rings = _rings(max(mag.max(), ext.value))
    R = rings[-1]
    t = np.linspace(0, 2 * np.pi, 121)
    grid = [np.column_stack([r * np.cos(t), r * np.sin(t)]) for r in rings]
    spokes = np.radians(np.arange(0, 360, 45))
    grid += [np.array([[0, 0], [R * math.cos(s), R * math.sin(s)]]) for s in spokes]
    ax.add_collection(LineCollection(grid[:-len(spokes)], colors="0.45", linewidths=[0.5] * (len(rings) - 1) + [1.0]))
    ax.add_collection(LineCollection(grid[-len(spokes):], colors="0.7", linewidths=0.5))
    for s in spokes:
        ax.text(1.1 * R * math.cos(s), 1.1 * R * math.sin(s), f"{math.degrees(s):.0f}°", ha="center", va="center",
                fontsize=6.5, color="0.3")
    quiet = np.radians(_QUIET)  # the magnitudes where the curve is least in the way
    ang = np.arctan2(fy, fx)
    crowd = [np.max(mag * (np.abs(np.angle(np.exp(1j * (ang - q)))) < math.radians(30)), initial=0) for q in quiet]
    q = quiet[int(np.argmin(crowd))]
    for r in rings:
        ax.text(r * math.cos(q), r * math.sin(q), f"{r:g} N", ha="center", va="center", fontsize=6.5, color="0.25",
                bbox=dict(fc="w", ec="none", pad=0.5, alpha=0.8))
    ax.plot(closed(a, fx), closed(a, fy), color=c, lw=1.5)
    ax.plot([0], [0], "k+", ms=6)
    ax.plot([tip[0]], [tip[1]], "o", ms=6, mfc="none", mec="k")
    ax.set_title(f"{text}\npeak {ext.value:.3g} N at φ = {ext.deg:.1f}°, "
                 f"mean {mag.mean():.3g} N", fontsize=8.5, y=1.0, pad=4)
    ax.set(xlim=(-1.2 * R, 1.2 * R), ylim=(-1.2 * R, 1.2 * R))
    ax.set_aspect("equal", adjustable="box")
    ax.set_autoscale_on(False)
    ax.set_axis_off()
    angle_labels(ax, a, fx, fy, size=6, step=step)  # after the limits: overlapping labels are left out


def draw_bearings_polar(fig, a):
    axes = place(fig, 1, 2, left=0.4, right=0.4, top=1.1, bottom=0.2, wspace=0.8)[0]
    for ax, which, c in zip(axes, ("front", "rear"), ("k", "0.35")):
        _polar(ax, a, lambda b, which=which: b.bearing(which), c, f"{which} upper-shaft bearing: load on the frame",
               step=45.0)
    suptitle(fig, title(a, "upper-shaft bearing loads (polar: direction of the force, magnitude in N; labels: "
                           "shaft angle φ)"), size=11)


def _reaction(a, group: str, joint: str) -> np.ndarray:
    r = a.groups[group].reaction(joint)
    return np.column_stack([r.fx, r.fy])


def main_joints(fa, k: int = MAIN_JOINTS) -> list:
    """A group's ``k`` most loaded joints (by peak reaction magnitude), most loaded first."""
    return sorted(fa.reaction_names, key=lambda n: -fa.reaction(n).magnitude.max())[:k]


def joints_size(a):
    return (12.0, 0.7 + 3.7 * len(a.machine.groups))


def draw_joint_reactions_polar(fig, a):
    rows = [(g, a.groups[g.name]) for g in a.machine.groups]
    ncol = max([len(main_joints(fa)) for _, fa in rows] + [1])
    axes = place(fig, len(rows), ncol, left=0.3, right=0.3, top=0.95, bottom=0.15, wspace=0.7, hspace=0.75)
    for r, (g, fa) in enumerate(rows):
        d = g.mechanism.description
        names = main_joints(fa)
        for cc in range(ncol):
            if cc >= len(names):
                axes[r, cc].set_visible(False)
                continue
            j = d.reaction(names[cc])
            _polar(axes[r, cc], a, lambda b, g=g.name, n=names[cc]: _reaction(b, g, n), color(a, g),
                   f"{g.name} {names[cc]}: on {j.b} (from {j.a})")
    suptitle(fig, title(a, "the three most loaded joints of each group, the force on the part named (polar: "
                           "direction, magnitude in N; labels: shaft angle φ)"), size=11)


# -- driving torque --------------------------------------------------------------------------------------------

def _stats(t):
    return f"mean {round(t.mean(), 4) + 0.0:+.4f}, RMS {np.sqrt(np.mean(t**2)):.4f} N·m"


def draw_torque(fig, a):
    ax = place(fig, 1, 1, left=0.9, right=0.3, top=0.85, bottom=0.6 + 0.25 * (len(a.machine.groups) // 2 + 3))[0, 0]
    d, t = deg(a), a.torque
    shade_loads(ax, a)
    groups = 0.0
    for g in a.machine.groups:
        tg = a.groups[g.name].torque("shaft")
        groups = groups + tg
        ax.plot(d, closed(a, tg), color=color(a, g), lw=1.2, label=f"{g.name}: {_stats(tg)}")
    core = t - groups
    friction = bool(np.any(a.friction_power))
    bearings = ", bearing friction" if np.any(a.bearing_friction) else ""
    ax.plot(d, closed(a, core), color="0.55", lw=1, ls=":",
            label=f"shaft core, counterweights{bearings}: {_stats(core)}")
    ax.plot(d, closed(a, t), color="k", lw=2.2, label=f"total at the pulley: {_stats(t)}")
    rms = np.sqrt(np.mean(t**2))
    ax.axhline(t.mean(), color="k", lw=0.8, ls="--", label="total: mean (dashed), ±RMS (dash-dot)")
    for s in (rms, -rms):
        ax.axhline(s, color="k", lw=0.6, ls="-.", alpha=0.6)
    ax.axhline(0, color="0.5", lw=0.6)
    angle_axis(ax)
    ax.set_ylabel("driving torque on the shaft (N·m)")
    ext = extremes(a, {"t": lambda b: b.torque})["t"]
    hi, lo = ext["max"], ext["min"]
    ax.set_title(f"total: mean {t.mean():.4f} N·m, RMS {rms:.4f} N·m, max {hi.value:.3f} N·m at φ = "
                 f"{hi.deg:.1f}°, min {lo.value:.3f} N·m at φ = {lo.deg:.1f}°", fontsize=9, y=1.0)
    fig.legend(*ax.get_legend_handles_labels(), loc="lower center", ncol=2, fontsize=8,
               bbox_to_anchor=(0.5, 0.04 / fig.get_size_inches()[1]))
    note = (f"with Coulomb friction: {np.mean(a.friction_power):.3g} W dissipated on average" if friction
            else "ideal joints: friction is left out")
    ax.text(0.995, 0.015, note, transform=ax.transAxes, ha="right", va="bottom",
            fontsize=8, color="0.25", bbox=dict(fc="w", ec="0.7", alpha=0.85))
    suptitle(fig, title(a, "driving torque on the upper shaft (the pulley's, and each group's share; "
                           + ("friction included)" if friction else "friction left out)")))


# -- shaking force and moments ---------------------------------------------------------------------------------

def draw_shaking(fig, a):
    """The shaking force and moments on the frame: the moving parts' inertia alone (−Σ m a_G, process loads
    internal), their weight on the frame apart (the convention of sewgen.machine.shaking)."""
    from matplotlib.gridspec import GridSpec

    W, H = fig.get_size_inches()
    gs = GridSpec(2, 2, figure=fig, left=0.8 / W, right=1 - 0.3 / W, top=1 - 0.75 / H, bottom=1.25 / H,
                  wspace=0.28, hspace=0.55, width_ratios=(1, 1.25))
    ax1 = fig.add_subplot(gs[:, 0])
    ax2, ax3 = fig.add_subplot(gs[0, 1]), fig.add_subplot(gs[1, 1])
    f = a.shaking_force_on_frame
    wgt = a.weight_on_frame
    ax1.plot(closed(a, f[:, 0]), closed(a, f[:, 1]), color="tab:purple", lw=1.5,
             label="shaking force on the frame, −Σ m a_G")
    angle_labels(ax1, a, f[:, 0], f[:, 1])
    ax1.plot([0], [0], "k+", ms=10, label="origin (no force)")
    m = f.mean(axis=0)
    ax1.plot(*m, "kx", ms=7, label=f"mean ({m[0]:.2f}, {m[1]:.2f}) N")
    ext, there = _peak_of(a, lambda b: np.hypot(*b.shaking_force_on_frame.T))
    tip = there.shaking_force_on_frame[0] if there is not None else f[int(np.argmax(np.hypot(*f.T)))]
    ax1.plot(*tip, "o", ms=7, mfc="none", mec="k", label=f"peak {ext.value:.3g} N at φ = {ext.deg:.1f}°")
    ax1.annotate("", xy=tuple(wgt), xytext=(0, 0), arrowprops=dict(arrowstyle="-|>", color="0.35", lw=1.6))
    ax1.plot([], [], color="0.35", lw=1.6,
             label=f"weight on the frame, Σ m g: {np.hypot(*wgt):.2f} N, static, acts besides")
    ax1.set_aspect("equal", adjustable="datalim")
    ax1.margins(0.12)
    angle_labels(ax1, a, f[:, 0], f[:, 1])
    ax1.set_autoscale_on(False)
    ax1.grid(alpha=0.3)
    ax1.set(xlabel="Fx (N)", ylabel="Fy (N)")
    ax1.set_title("shaking force on the frame, −Σ m a_G (inertia only)", y=1.0)
    ax1.legend(fontsize=7.5, loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=2)

    moments = a.shaking_moments_on_frame()
    d = deg(a)
    for ax, cols, text in ((ax2, (2,), "about the upper-shaft axis z"),
                           (ax3, (0, 1), "about x and y: the base rocks (groups at their axial positions)")):
        shade_loads(ax, a, labels=ax is ax2)
        for c, style in zip(cols, ("-", "--")):
            mo = moments[:, c]
            axis = "xyz"[c]
            ext, there = _peak_of(a, lambda b, c=c: np.abs(b.shaking_moments_on_frame()[:, c]))
            kk = int(np.argmax(np.abs(mo)))
            at = there.shaking_moments_on_frame()[0, c] if there is not None else mo[kk]
            ax.plot(d, closed(a, mo), color=("tab:purple", "tab:cyan", "0.15")[c], lw=1.5, ls=style,
                    label=f"M{axis}: peak |M| {ext.value:.3f} N·m at φ = {ext.deg:.1f}°, mean {mo.mean():+.3f}")
            ax.plot(ext.deg, at, "o", mfc="none", mec="k")
        ax.axhline(0, color="0.5", lw=0.6)
        angle_axis(ax, label=ax is ax3)
        ax.set_ylabel("moment (N·m)")
        ax.set_title(f"shaking moment on the frame {text}", fontsize=9.5, y=1.0)
        ax.legend(fontsize=7, loc="best", framealpha=0.85)
    suptitle(fig, title(a, "shaking force and moments on the frame (inertia only, −Σ m a_G; the weight on the frame "
                           "apart), about the frame origin; labels: shaft angle φ"))

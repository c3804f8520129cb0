"""Pictures of a whole-machine analysis for ``sewgen analyze MACHINE --out DIR``.

One function per figure, ``name(analysis, path) -> Path``, taking a :class:`sewgen.machine.MachineAnalysis`
and writing one PNG; beside each a ``draw_<name>(fig, analysis)`` that draws onto a given figure (for tests
and notebooks). :func:`machine_gif` animates the four linkages over the sweep; :func:`write_all` writes
everything. Figures are ``matplotlib.figure.Figure`` objects on the Agg canvas: nothing here touches pyplot
or a caller's backend. Lengths are drawn in mm; abscissae are the machine's shaft angle φ (seed 000: needle
top at 90°). Groups are found by their catalog mechanism (needle_bar, take_up, hook_drive, feed), whatever
the model file calls them; a figure leaves out what a machine does not have.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

MM = 1e3  # m -> mm
DPI = 100
SIZES = {  # inches; a PNG is SIZES[name] * DPI pixels
    "trajectories.png": (13.0, 5.2),
    "motion.png": (13.0, 13.0),
    "bearings_polar.png": (12.0, 6.0),
    "joint_reactions_polar.png": (12.0, 15.0),
    "torque.png": (11.0, 5.5),
    "shaking.png": (13.0, 5.5),
    "feed_dog_stitches.png": (11.0, 6.0),
}
GIF_SIZE, GIF_DPI, GIF_FPS, GIF_COLORS = (8.0, 5.6), 80, 10, 64
COLORS = {"needle_bar": "tab:blue", "take_up": "tab:orange", "hook_drive": "tab:green", "feed": "tab:red"}
MAIN_JOINTS = {  # the joints whose reactions a designer looks at first, per catalog mechanism
    "needle_bar": ("crank.pivot", "B", "C"),
    "take_up": ("B", "C", "D"),
    "hook_drive": ("B", "O4", "E"),
    "feed": ("cam", "L", "O_lift"),
}


# -- shared helpers --------------------------------------------------------------------------------------------

def new_figure(size, dpi=DPI):
    """A figure on its own Agg canvas (no pyplot, no global backend change), constrained layout."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, dpi=dpi, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _render(draw, analysis, path, name):
    fig = new_figure(SIZES[name])
    draw(fig, analysis)
    fig.savefig(path, dpi=DPI)
    return Path(path)


def _find(a, mechanism):
    """(group, ForceAnalysis) of the first group running catalog ``mechanism``, or (None, None)."""
    for g in a.machine.groups:
        if g.mechanism.name == mechanism:
            return g, a.groups[g.name]
    return None, None


def _params(g) -> dict:
    return dict(zip(g.mechanism.param_names, g.mechanism.param_vector(g.params or None)))


def _plate_y(a):
    """Throat-plate height (m) from the feed group, or None."""
    g, _ = _find(a, "feed")
    return None if g is None else float(_params(g)["plate_y"])


def _full_turn(phi) -> bool:
    h = np.diff(phi)
    return len(phi) > 2 and np.allclose(h, h[0]) and abs(len(phi) * h[0] - 2 * math.pi) < 1e-6


def _closed(a, y):
    """``y`` with its first value repeated at the end when the sweep is one whole turn (closed curves)."""
    y = np.asarray(y)
    return np.concatenate([y, y[:1]]) if _full_turn(a.phi) else y


def _deg(a):
    """Shaft angles in degrees, closed to 360° like :func:`_closed`."""
    d = np.degrees(a.phi)
    return np.append(d, d[0] + 360.0) if _full_turn(a.phi) else d


def _title(a, what: str) -> str:
    return f"{a.machine.name}: {what} at {a.omega[0] * 30 / math.pi:.0f} rpm"


def _angle_axis(ax, label=True):
    ax.set_xlim(0, 360)
    ax.set_xticks(np.arange(0, 361, 45))
    ax.grid(alpha=0.3)
    if label:
        ax.set_xlabel("shaft angle φ (deg)")


def _shade(ax, a, mask, color, label=None):
    """Shade the shaft angles where ``mask`` holds (full height of the axes)."""
    ax.fill_between(_deg(a), 0, 1, where=_closed(a, mask), color=color, alpha=0.12, lw=0,
                    transform=ax.get_xaxis_transform(), label=label)


def _angle_labels(ax, a, x, y, *, at=None, step=45.0, color="0.2", size=7):
    """Dots and "φ°" labels at every ``step`` degrees of shaft angle on a path x, y (equal-aspect data units);
    each label is pushed off the path along its normal, away from the path's centre. ``at`` gives other
    data coordinates to annotate (a polar axes' θ, r) with x, y used for the directions."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    deg = np.degrees(a.phi)
    idx = np.flatnonzero(np.abs(deg - step * np.round(deg / step)) < 1e-6)
    tx, ty = np.roll(x, -1) - np.roll(x, 1), np.roll(y, -1) - np.roll(y, 1)
    cx, cy = x.mean(), y.mean()
    size_ = max(np.ptp(x), np.ptp(y), 1e-300)
    for i in idx:
        nx, ny = ty[i], -tx[i]  # right-hand normal of the direction of travel
        ox, oy = x[i] - cx, y[i] - cy
        if math.hypot(nx, ny) < 1e-3 * size_:  # at rest: straight out from the centre
            nx, ny = ox, oy
        elif nx * ox + ny * oy < -1e-9 * size_**2:
            nx, ny = -nx, -ny
        r = math.hypot(nx, ny) or 1.0
        nx, ny = nx / r, ny / r
        px, py = (x[i], y[i]) if at is None else (at[0][i], at[1][i])
        ax.plot([px], [py], "o", ms=2.5, color=color)
        ha = "center" if abs(nx) < 0.4 else ("left" if nx > 0 else "right")  # the text starts next to the dot
        va = "center" if abs(ny) < 0.4 else ("bottom" if ny > 0 else "top")
        ax.annotate(f"{deg[i] % 360:.0f}°", (px, py), xytext=(5 * nx, 5 * ny), textcoords="offset points",
                    ha=ha, va=va, fontsize=size, color=color)


def _xy(fa, point):
    p = fa.motion.point(point)
    return p.x * MM, p.y * MM


def _inertia_force(a, g):
    """Σ m (a_G − g) over a group's moving bodies (n, 2) N: its shaking force without the external loads.
    None when a body's mass is not a plain parameter."""
    fa, p = a.groups[g.name], _params(g)
    out = np.zeros((len(a.phi), 2))
    for body in fa.motion.body_names:
        if f"{body}.mass" not in p:
            return None
        com = fa.motion.body(body).com
        out += p[f"{body}.mass"] * (np.column_stack([com.ax, com.ay]) - a.machine.gravity)
    return out


def _shade_loads(ax, a):
    """Shade the shaft angles where each group's external forces act, read from its results (Σ m (a_G − g) −
    shaking force), so the shading shows where the analysis applied them."""
    for g in a.machine.groups:
        f = _inertia_force(a, g)
        if f is not None:
            mask = np.hypot(*(f - a.groups[g.name].shaking_force).T) > 1e-9 * max(1.0, np.abs(f).max())
            if mask.any():
                _shade(ax, a, mask, COLORS.get(g.mechanism.name, "0.5"), f"external loads on {g.name} act")


# -- 1. trajectories -------------------------------------------------------------------------------------------

def draw_trajectories(fig, a):
    """Needle eye, take-up thread eye and feed dog paths (mm), with the throat plate; returns {point: (x, y)}."""
    plate = _plate_y(a)
    items = [(m, p, t) for m, p, t in (("needle_bar", "needle_eye", "needle eye"),
                                        ("take_up", "thread_eye", "take-up thread eye"),
                                        ("feed", "feed_dog", "feed dog"))
             if _find(a, m)[1] is not None]
    axes = fig.subplots(1, len(items), squeeze=False)[0]
    data = {}
    for ax, (mech, point, text) in zip(axes, items):
        _, fa = _find(a, mech)
        x, y = _xy(fa, point)
        data[point] = (x, y)
        ax.plot(_closed(a, x), _closed(a, y), color=COLORS[mech], lw=1.5, label=f"{text} path", gid=point)
        _angle_labels(ax, a, x, y)
        if plate is not None and mech in ("needle_bar", "feed"):
            ax.axhline(plate * MM, color="k", lw=1, ls="--", label=f"throat plate, y = {plate * MM:g} mm")
        if mech == "feed" and plate is not None:
            above = y > plate * MM
            ax.plot(np.where(above, x, np.nan), np.where(above, y, np.nan), color="k", lw=3, alpha=0.35,
                    label="above the plate (feeding)")
            _feed_note(ax, fa, plate)
        ax.set_aspect("equal", adjustable="datalim")
        ax.margins(0.25)
        ax.set(xlabel="x (mm)", ylabel="y (mm)", title=text)
        ax.grid(alpha=0.3)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), fontsize=8)
    fig.suptitle(_title(a, "paths (labels: shaft angle φ)"))
    return data


def _feed_note(ax, fa, plate):
    from .errors import ParameterError
    from .feed import dog_travel

    try:
        t = dog_travel(fa.motion, plate)
    except (ParameterError, ValueError):  # not a whole turn, or the dog never clears the plate: no note
        return
    ax.text(0.02, 0.98, f"feed above the plate {t.travel * MM:.2f} mm\nφ {math.degrees(t.rise):.0f}°"
            f" – {math.degrees(t.sink):.0f}°, {t.height * MM:.2f} mm high",
            transform=ax.transAxes, va="top", fontsize=8, bbox=dict(fc="w", ec="0.7", alpha=0.85))


def trajectories(analysis, path):
    return _render(draw_trajectories, analysis, path, "trajectories.png")


#: Stitch lengths (mm) of the feed-dog family: zero to the household maximum, and reverse feed.
STITCHES_MM = (0.0, 1.0, 2.0, 3.0, 4.0, -2.0, -4.0)


def draw_feed_dog_stitches(fig, a):
    """Feed-dog paths (mm) for stitch lengths 0 to 4 mm and reverse, the regulator set for each (seed 001 §五);
    returns {stitch mm: (x, y)}. Empty without a feed group."""
    from .feed import regulator_angle

    g, fa = _find(a, "feed")
    ax = fig.subplots()
    data = {}
    if g is None:
        ax.set_axis_off()
        return data
    plate = _plate_y(a)
    mech, params = g.mechanism, g.params or None
    from matplotlib import colormaps

    cmap = colormaps["coolwarm"]
    for k, mm in enumerate(STITCHES_MM):
        reg = regulator_angle(mech, mm * 1e-3, params=params)
        mo = mech.solve(fa.phi, speed=fa.motion.omega, params=params, held={"regulator": reg})
        x, y = mo.point("feed_dog").x * MM, mo.point("feed_dog").y * MM
        data[mm] = (x, y)
        ax.plot(_closed(a, x), _closed(a, y), lw=1.4, color=cmap(0.5 + mm / 9.0),
                label=f"{mm:+.0f} mm (regulator {math.degrees(reg):+.1f}°)")
    if plate is not None:
        ax.axhline(plate * MM, color="k", lw=1, ls="--", label=f"throat plate, y = {plate * MM:g} mm")
    ax.set_aspect("equal", adjustable="datalim")
    ax.margins(0.1)
    ax.grid(alpha=0.3)
    ax.set(xlabel="x (mm, + = forward feed)", ylabel="y (mm)")
    ax.legend(fontsize=8, loc="center left", bbox_to_anchor=(1.02, 0.5))
    fig.suptitle(_title(a, "feed-dog paths for stitch lengths 0 to 4 mm and reverse"))
    return data


def feed_dog_stitches(analysis, path):
    return _render(draw_feed_dog_stitches, analysis, path, "feed_dog_stitches.png")


# -- 2. motion against shaft angle -----------------------------------------------------------------------------

def _motion_rows(a):
    """(title, mechanism, units, displacement, velocity, acceleration) for each quantity present."""
    rows = []
    _, fa = _find(a, "needle_bar")
    if fa is not None:
        p = fa.motion.point("needle_eye")
        rows.append(("needle eye y (needle-bar travel)", "needle_bar", ("mm", "m/s", "m/s²"), p.y * MM, p.vy, p.ay))
    _, fa = _find(a, "take_up")
    if fa is not None:
        p = fa.motion.point("thread_eye")
        rows.append(("take-up thread eye y", "take_up", ("mm", "m/s", "m/s²"), p.y * MM, p.vy, p.ay))
    _, fa = _find(a, "feed")
    if fa is not None:
        p = fa.motion.point("feed_dog")
        rows.append(("feed dog x (feed)", "feed", ("mm", "m/s", "m/s²"), p.x * MM, p.vx, p.ax))
        rows.append(("feed dog y (lift)", "feed", ("mm", "m/s", "m/s²"), p.y * MM, p.vy, p.ay))
    _, fa = _find(a, "hook_drive")
    if fa is not None:
        b = fa.motion.body("lower_shaft")
        rows.append(("shuttle (lower shaft) angle", "hook_drive", ("deg", "deg/s", "deg/s²"),
                     np.degrees(np.unwrap(b.angle)), np.degrees(b.omega), np.degrees(b.alpha)))
    return rows


def draw_motion(fig, a):
    rows = _motion_rows(a)
    axes = fig.subplots(len(rows), 3, sharex=True, squeeze=False)
    plate = _plate_y(a)
    masks = []
    _, nb = _find(a, "needle_bar")
    _, fd = _find(a, "feed")
    if plate is not None and nb is not None:
        masks.append((nb.motion.point("needle_eye").y < plate, "0.3", "needle eye below the plate"))
    if plate is not None and fd is not None:
        masks.append((fd.motion.point("feed_dog").y > plate, "tab:red", "feed dog above the plate"))
    d = _deg(a)
    for r, (text, mech, units, *series) in enumerate(rows):
        for c, (values, unit, kind) in enumerate(zip(series, units, ("displacement", "velocity", "acceleration"))):
            ax = axes[r, c]
            ax.plot(d, _closed(a, values), color=COLORS[mech], lw=1.5)
            for mask, color, label in masks:
                _shade(ax, a, mask, color, label)
            if c == 0 and plate is not None and text.startswith(("needle eye", "feed dog y")):
                ax.axhline(plate * MM, color="k", lw=1, ls="--", label="throat plate")
            if c > 0:
                ax.axhline(0, color="0.5", lw=0.6)
            ax.set_ylabel(f"{kind} ({unit})")
            ax.set_title(text, fontsize=9)
            ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 4))
            _angle_axis(ax, label=r == len(rows) - 1)
    if masks:
        handles, labels = axes[0, 0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="outside lower center", ncol=len(labels), fontsize=9)
    fig.suptitle(_title(a, "displacement, velocity and acceleration against the shaft angle"))


def motion(analysis, path):
    return _render(draw_motion, analysis, path, "motion.png")


# -- 3. polar diagrams of bearing loads and joint reactions ----------------------------------------------------

def _polar(ax, a, fx, fy, color, title):
    """Hodograph of a force on polar axes: θ = its direction, r = its magnitude (N); shaft-angle labels."""
    from matplotlib.ticker import MaxNLocator

    mag, ang = np.hypot(fx, fy), np.arctan2(fy, fx)
    ax.plot(_closed(a, ang), _closed(a, mag), color=color, lw=1.5)
    ax.plot([0], [0], "k+", ms=6)
    _angle_labels(ax, a, fx, fy, at=(ang, mag), size=6)
    k = int(np.argmax(mag))
    ax.plot([ang[k]], [mag[k]], "o", ms=6, mfc="none", mec="k")
    ax.set_title(f"{title}\npeak {mag[k]:.3g} N at φ = {math.degrees(a.phi[k]) % 360:.0f}°, "
                 f"mean {mag.mean():.3g} N", fontsize=9)
    quiet = np.arange(22.5, 360, 45)  # put the magnitude labels where the curve is least in the way
    crowd = [np.max(mag * (np.abs(np.angle(np.exp(1j * (ang - math.radians(c))))) < math.radians(30)), initial=0)
             for c in quiet]
    ax.set_rlabel_position(quiet[int(np.argmin(crowd))])
    ax.yaxis.set_major_locator(MaxNLocator(4))
    ax.yaxis.set_major_formatter(lambda v, _pos: f"{v:g} N")
    ax.tick_params(labelsize=7)
    ax.set_xticks(np.radians(np.arange(0, 360, 45)))


def draw_bearings_polar(fig, a):
    axes = fig.subplots(1, 2, subplot_kw={"projection": "polar"})
    for ax, which, color in zip(axes, ("front", "rear"), ("tab:purple", "tab:brown")):
        f = a.bearing(which)
        _polar(ax, a, f[:, 0], f[:, 1], color, f"{which} upper-shaft bearing: load on the frame")
    fig.suptitle(_title(a, "upper-shaft bearing loads (polar: direction of the force, magnitude in N; "
                           "labels: shaft angle φ)"), fontsize=11)


def bearings_polar(analysis, path):
    return _render(draw_bearings_polar, analysis, path, "bearings_polar.png")


def _main_joints(g, fa):
    names = [n for n in MAIN_JOINTS.get(g.mechanism.name, ()) if n in fa.reaction_names]
    if not names:  # a mechanism we do not know: its three most loaded joints
        names = sorted(fa.reaction_names, key=lambda n: -fa.reaction(n).magnitude.max())[:3]
    return names


def draw_joint_reactions_polar(fig, a):
    rows = [(g, a.groups[g.name]) for g in a.machine.groups]
    ncol = max(len(_main_joints(g, fa)) for g, fa in rows)
    axes = fig.subplots(len(rows), ncol, subplot_kw={"projection": "polar"}, squeeze=False)
    for r, (g, fa) in enumerate(rows):
        joints = {j["name"]: j for j in g.mechanism.manifest["reactions"]}
        names = _main_joints(g, fa)
        for c in range(ncol):
            if c >= len(names):
                axes[r, c].set_visible(False)
                continue
            f, j = fa.reaction(names[c]), joints[names[c]]
            _polar(axes[r, c], a, f.fx, f.fy, COLORS.get(g.mechanism.name, "k"),
                   f"{g.name} {names[c]}: on {j['b']} from {j['a']}")
    fig.suptitle(_title(a, "main joint reactions (polar: direction, magnitude in N; labels: shaft angle φ)"),
                 fontsize=11)


def joint_reactions_polar(analysis, path):
    return _render(draw_joint_reactions_polar, analysis, path, "joint_reactions_polar.png")


# -- 4. driving torque -----------------------------------------------------------------------------------------

def _stats(t):
    return f"mean {round(t.mean(), 4) + 0.0:+.4f}, RMS {np.sqrt(np.mean(t**2)):.4f} N·m"


def draw_torque(fig, a):
    ax = fig.subplots()
    d, t = _deg(a), a.torque
    _shade_loads(ax, a)
    groups = 0.0
    for g in a.machine.groups:
        tg = a.groups[g.name].torque("shaft")
        groups = groups + tg
        ax.plot(d, _closed(a, tg), color=COLORS.get(g.mechanism.name), lw=1.2, label=f"{g.name}: {_stats(tg)}")
    core = t - groups
    ax.plot(d, _closed(a, core), color="0.55", lw=1, ls=":", label=f"shaft core, counterweights: {_stats(core)}")
    ax.plot(d, _closed(a, t), color="k", lw=2.2, label=f"total at the pulley: {_stats(t)}")
    rms = np.sqrt(np.mean(t**2))
    ax.axhline(t.mean(), color="k", lw=0.8, ls="--", label="total: mean (dashed), ±RMS (dash-dot)")
    for s in (rms, -rms):
        ax.axhline(s, color="k", lw=0.6, ls="-.", alpha=0.6)
    ax.axhline(0, color="0.5", lw=0.6)
    _angle_axis(ax)
    ax.set_ylabel("driving torque (N·m)")
    kmin, kmax = int(np.argmin(t)), int(np.argmax(t))
    ax.set_title(f"total: mean {t.mean():.4f} N·m, RMS {rms:.4f} N·m, max {t[kmax]:.3f} N·m at φ = "
                 f"{np.degrees(a.phi[kmax]) % 360:.0f}°, min {t[kmin]:.3f} N·m at φ = "
                 f"{np.degrees(a.phi[kmin]) % 360:.0f}°", fontsize=9)
    fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center", ncol=2, fontsize=8)
    fig.suptitle(_title(a, "driving torque of the upper shaft"))


def torque(analysis, path):
    return _render(draw_torque, analysis, path, "torque.png")


# -- 5. shaking force and moment -------------------------------------------------------------------------------

def draw_shaking(fig, a):
    ax1, ax2 = fig.subplots(1, 2)
    f = a.shaking_force
    ax1.plot(_closed(a, f[:, 0]), _closed(a, f[:, 1]), color="tab:purple", lw=1.5, label="shaking force hodograph")
    _angle_labels(ax1, a, f[:, 0], f[:, 1])
    ax1.plot([0], [0], "k+", ms=10, label="origin (no force)")
    m = f.mean(axis=0)
    ax1.plot(*m, "kx", ms=7, label=f"mean ({m[0]:.2f}, {m[1]:.2f}) N: the parts' weight")
    k = int(np.argmax(np.hypot(*f.T)))
    ax1.plot(*f[k], "o", ms=7, mfc="none", mec="k",
             label=f"peak {np.hypot(*f[k]):.3g} N at φ = {np.degrees(a.phi[k]) % 360:.0f}°")
    ax1.set_aspect("equal", adjustable="datalim")
    ax1.margins(0.12)
    ax1.grid(alpha=0.3)
    ax1.set(xlabel="Fx (N)", ylabel="Fy (N)", title="shaking force on the base (process loads internal)")
    ax1.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2)
    mo = a.shaking_moment()
    _shade_loads(ax2, a)
    ax2.plot(_deg(a), _closed(a, mo), color="tab:purple", lw=1.5)
    ax2.axhline(0, color="0.5", lw=0.6)
    ax2.axhline(mo.mean(), color="k", lw=0.8, ls="--", label=f"mean {mo.mean():.3f} N·m")
    k = int(np.argmax(np.abs(mo)))
    ax2.plot(np.degrees(a.phi[k]) % 360, mo[k], "o", mfc="none", mec="k",
             label=f"peak |M| {abs(mo[k]):.3f} N·m at φ = {np.degrees(a.phi[k]) % 360:.0f}°")
    _angle_axis(ax2)
    ax2.set(ylabel="shaking moment (N·m)", title="shaking moment about the upper-shaft axis")
    ax2.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2)
    fig.suptitle(_title(a, "shaking force and moment (labels: shaft angle φ)"))


def shaking(analysis, path):
    return _render(draw_shaking, analysis, path, "shaking.png")


# -- 6. the linkages and their animation ------------------------------------------------------------------------

@dataclass
class Linkage:
    """One group drawn as a plane linkage, in mm: points (n, 2) by name (fixed ones repeated), polylines through
    named points, ground pivots, circles (centre point, radius), closed outlines (n, k, 2), fixed lines
    ((2, 2): guides, the throat plate) and marked points (needle eye, thread eye, ...) whose paths are traced."""

    mechanism: str
    points: dict
    links: list
    pivots: list = field(default_factory=list)
    circles: list = field(default_factory=list)
    outlines: list = field(default_factory=list)
    fixed: list = field(default_factory=list)
    marks: list = field(default_factory=list)


def _rot(t, u, v):
    """A body-frame offset (u, v) (m) turned by the body angle t (n,): (n, 2)."""
    c, s = np.cos(t), np.sin(t)
    return np.column_stack([u * c - v * s, u * s + v * c])


def _points(fa, **fixed):
    """Every named point of a group (n, 2) (m), and fixed points given as name=(x, y)."""
    pts = {n: np.column_stack([fa.motion.point(n).x, fa.motion.point(n).y]) for n in fa.motion.point_names}
    pts.update({n: np.tile(np.asarray(xy, float), (len(fa.phi), 1)) for n, xy in fixed.items()})
    return pts


def _needle_bar(fa, p):
    pts = _points(fa, A=(0, 0))
    e, top, bottom = p["offset"], pts["link_pin"][:, 1].max() + 0.01, pts["needle_eye"][:, 1].min() - 0.004
    return dict(points=pts, links=[("A", "crank_pin", "link_pin", "needle_eye")], pivots=["A"],
                circles=[("A", p["crank"])], fixed=[((e, top), (e, bottom))], marks=["needle_eye"])


def _take_up(fa, p):
    pts = _points(fa, A=(0, 0), D=(p["rocker_pivot_x"], p["rocker_pivot_y"]))
    return dict(points=pts, links=[("A", "crank_pin"), ("crank_pin", "rocker_pin", "thread_eye", "crank_pin"),
                                   ("D", "rocker_pin")],
                pivots=["A", "D"], circles=[("A", p["crank"])], marks=["thread_eye"])


def _hook_drive(fa, p):
    pts = _points(fa, A=(0, 0), O4=(p["rock_axis_x"], p["rock_axis_y"]), O11=(p["lower_axis_x"], p["lower_axis_y"]))
    lower, travel = fa.motion.body("lower_shaft").angle, fa.motion.coord("rock_slider.travel").value
    pts["arm0"] = pts["O11"] + _rot(lower, min(travel.min(), 0.0) - 0.004, 0)  # the slotted arm of the lower
    pts["arm1"] = pts["O11"] + _rot(lower, travel.max() + 0.004, 0)  # shaft: its end traces the shuttle swing
    return dict(points=pts, links=[("A", "crank_pin"), ("crank_pin", "rock_pin"), ("rock_pin", "O4", "slider_pin"),
                                   ("arm0", "arm1")],
                pivots=["A", "O4", "O11"], circles=[("A", p["crank"])], marks=["arm1"])


def _cam_outline(p, angle, k=10):
    """The feed cam in the frame, (n, 6k, 2) m: the six arcs of derive.model.constant_breadth_arcs as
    derive/models/feed.py places them (centroid (0, -side/√3), a vertex on the shaft), by normal direction."""
    from .derive.model import constant_breadth_arcs

    s, r0 = p["cam_side"], p["cam_small_radius"]
    t, u, v = [], [], []
    for arc in constant_breadth_arcs(s, r0, centroid=(0, -s / math.sqrt(3)), orientation=math.pi / 2):
        th = np.linspace(float(arc.normal_from), float(arc.normal_to), k)
        t.append(th % (2 * math.pi))
        u.append(float(arc.center_u) + float(arc.radius) * np.cos(th))
        v.append(float(arc.center_v) + float(arc.radius) * np.sin(th))
    order = np.argsort(np.concatenate(t), kind="stable")
    u, v = np.concatenate(u)[order], np.concatenate(v)[order]
    c, sn = np.cos(angle)[:, None], np.sin(angle)[:, None]
    return np.stack([u * c - v * sn, u * sn + v * c], axis=-1)


def _feed(fa, p):
    ang = lambda body: fa.motion.body(body).angle  # noqa: E731
    tf, tr, tb, tl, tg = (ang(b) for b in ("feed_fork", "feed_rock_shaft", "feed_bar", "lift_rock_shaft", "regulator"))
    pts = _points(fa, O=(0, 0), O_feed=(p["feed_shaft_x"], p["feed_shaft_y"]),
                  O_lift=(p["lift_shaft_x"], p["lift_shaft_y"]), O_reg=(p["regulator_x"], p["regulator_y"]))
    top, h = pts["fork_top"], (p["cam_side"] + 2 * p["cam_small_radius"]) / 2  # fork faces at ±breadth/2
    slot = _rot(tb, 0, -p["bar_slot_v"])
    pts.update(fork_a=top + _rot(tf, -h, -h), fork_b=top + _rot(tf, h, -h), fork_c=top + _rot(tf, h, h),
               fork_d=top + _rot(tf, -h, h), fork_stem=top + _rot(tf, h, 0), P=top + _rot(tf, p["fork_p"], 0),
               R=pts["O_feed"] + _rot(tr, 0, p["feed_arm_r"]), T=pts["O_lift"] + _rot(tl, -p["lift_drive_arm"], 0),
               S=_rot(ang("lift_eccentric"), p["lift_eccentricity"], 0),
               reg_a=pts["O_reg"] + _rot(tg, -0.008, 0), reg_b=pts["O_reg"] + _rot(tg, 0.008, 0))
    pts.update(slot_a=pts["R"] + slot, slot_b=pts["feed_dog"] + slot)
    plate = p["plate_y"]
    return dict(points=pts, links=[("fork_a", "fork_b", "fork_c", "fork_d"), ("fork_stem", "stitch_pin", "P"),
                                   ("P", "O_feed", "R"), ("R", "feed_dog"), ("slot_a", "slot_b"),
                                   ("lift_roller", "O_lift", "T"), ("S", "T"), ("reg_a", "reg_b")],
                pivots=["O", "O_feed", "O_lift", "O_reg"], outlines=[_cam_outline(p, ang("feed_cam"))],
                fixed=[((-0.025, plate), (0.025, plate))], marks=["feed_dog"])


_LINKAGES = {"needle_bar": _needle_bar, "take_up": _take_up, "hook_drive": _hook_drive, "feed": _feed}


def linkage(g, fa) -> Linkage:
    """How to draw group ``g`` (its ForceAnalysis or Motion holder ``fa``) as line segments, in mm."""
    build = _LINKAGES.get(g.mechanism.name)
    spec = (build(fa, _params(g)) if build else
            dict(points=_points(fa), links=[], marks=list(fa.motion.point_names)))  # unknown: its points only
    return Linkage(g.mechanism.name, {k: v * MM for k, v in spec["points"].items()}, spec["links"],
                   spec.get("pivots", []), [(c, r * MM) for c, r in spec.get("circles", [])],
                   [o * MM for o in spec.get("outlines", [])], [np.asarray(f) * MM for f in spec.get("fixed", [])],
                   spec.get("marks", []))


def _draw_linkage(ax, lk, lw, z):
    """Draw a linkage's fixed parts (guides, circles, traced paths, pivots) and its moving parts at position 0;
    returns (moving artists, move(i)), move(i) putting them at position i. ``z``: z-order of the links."""
    from matplotlib.patches import Circle

    color, P = COLORS.get(lk.mechanism, "k"), lk.points
    for f in lk.fixed:
        ax.plot(f[:, 0], f[:, 1], color="0.35", lw=0.9, ls="--", zorder=1)
    for c, r in lk.circles:
        ax.add_patch(Circle(P[c][0], r, fill=False, ec=color, lw=0.7, ls=":", zorder=1))
    for m in lk.marks:
        ax.plot(np.append(P[m][:, 0], P[m][0, 0]), np.append(P[m][:, 1], P[m][0, 1]), color=color, lw=0.6, alpha=0.5)
    if lk.pivots:
        ax.plot(*np.array([P[k][0] for k in lk.pivots]).T, "o", ms=5.5, mfc="0.8", mec="k", mew=0.8, zorder=z + 1)
    # the moving parts are drawn without antialiasing: fewer colours, half the GIF's size
    chains = [ax.plot([], [], "-o", color=color, lw=lw, ms=2.5, mfc="w", zorder=z, antialiased=False)[0]
              for _ in lk.links]
    shapes = [ax.plot([], [], color=color, lw=lw * 0.7, zorder=z - 0.5, antialiased=False)[0] for _ in lk.outlines]
    marks = ax.plot([], [], "o", ms=4.5, color=color, mec="k", mew=0.6, zorder=z + 2, antialiased=False)[0]

    def move(i):
        for line, ch in zip(chains, lk.links):
            line.set_data(*np.array([P[k][i] for k in ch]).T)
        for line, o in zip(shapes, lk.outlines):
            line.set_data(*np.vstack([o[i], o[i][:1]]).T)
        marks.set_data(*np.array([P[m][i] for m in lk.marks]).reshape(-1, 2).T)

    move(0)
    return [*shapes, *chains, marks], move


def _extent(links, margin=8.0):
    """(x0, x1, y0, y1) mm around every point and circle of the linkages."""
    xy = np.concatenate([v.reshape(-1, 2) for lk in links for v in (*lk.points.values(), *lk.outlines)])
    lo, hi = xy.min(axis=0) - margin, xy.max(axis=0) + margin
    for lk in links:
        for c, r in lk.circles:
            lo, hi = np.minimum(lo, lk.points[c][0] - r - 2), np.maximum(hi, lk.points[c][0] + r + 2)
    return lo[0], hi[0], lo[1], hi[1]


def _status(a, plate, i):
    """What the stitch-forming parts are doing at position i (needle in the cloth, feed dog up)."""
    words = []
    _, nb = _find(a, "needle_bar")
    _, fd = _find(a, "feed")
    if plate is not None and nb is not None:
        words.append(f"needle {'below' if nb.motion.point('needle_eye').y[i] < plate else 'above'} the plate")
    if plate is not None and fd is not None:
        words.append(f"feed dog {'up' if fd.motion.point('feed_dog').y[i] > plate else 'down'}")
    return ", ".join(words)


def _gif_writer(fps):
    """A PillowWriter that takes each frame from the canvas as it stands (blitted: no full redraw per frame) and
    maps every frame onto the first frame's palette (no dithering; Pillow then writes only the pixels that
    changed): a fast, small GIF."""
    from matplotlib.animation import PillowWriter
    from PIL import Image

    class CanvasGifWriter(PillowWriter):
        def grab_frame(self, **savefig_kwargs):
            canvas = self.fig.canvas
            im = Image.frombuffer("RGBA", canvas.get_width_height(), canvas.buffer_rgba(), "raw", "RGBA", 0, 1)
            im = im.convert("RGB")
            if not self._frames:
                self._palette = im.quantize(GIF_COLORS, method=Image.Quantize.MEDIANCUT)
            self._frames.append(im.quantize(palette=self._palette, dither=Image.Dither.NONE))

    return CanvasGifWriter(fps=fps)


def machine_gif(analysis, path, progress=None):
    """All groups in the x–y plane over the sweep, one frame per shaft angle: the whole machine and, when the
    machine has a throat plate, a close-up of the stitch-forming zone. ``progress(message, frame, frames)``
    is called every 8 frames."""
    from matplotlib.lines import Line2D

    a, n = analysis, len(analysis.phi)
    links = [linkage(g, a.groups[g.name]) for g in a.machine.groups]
    plate = _plate_y(a)
    x0, x1, y0, y1 = _extent(links)
    fig = new_figure(GIF_SIZE, GIF_DPI)
    views = [(x0, x1, y0, y1)]
    if plate is not None:  # the stitch-forming zone: 60 mm around the throat plate under the needle
        views.append((-32.0, 32.0, plate * MM - 38.0, plate * MM + 26.0))
    axes = fig.subplots(1, len(views), squeeze=False,
                        width_ratios=[(v[1] - v[0]) / (v[3] - v[2]) for v in views])[0]
    moving, moves = [], []
    for ax, (vx0, vx1, vy0, vy1), lw in zip(axes, views, (1.3, 2.0)):
        for lk in links:  # the needle on top: in the plane it runs along the feed fork
            artists, move = _draw_linkage(ax, lk, lw, z=6 if lk.mechanism == "needle_bar" else 3)
            moving += artists
            moves.append(move)
        ax.set(xlim=(vx0, vx1), ylim=(vy0, vy1), xlabel="x (mm)")
        ax.set_aspect("equal", adjustable="box")
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.25)
    axes[0].set_ylabel("y (mm)")
    axes[0].set_title("whole machine", fontsize=9)
    if len(views) > 1:
        axes[1].set_title("stitch-forming zone (throat plate dashed)", fontsize=9)
    handles = [Line2D([], [], color=COLORS.get(g.mechanism.name, "k"), lw=2, label=g.name) for g in a.machine.groups]
    axes[-1].legend(handles=handles, loc="lower right", fontsize=7, framealpha=0.9)
    readout = lambda i: (f"{a.machine.name}  φ = {math.degrees(a.phi[i]) % 360:5.1f}°  "  # noqa: E731
                         f"{_status(a, plate, i)}")
    title = fig.suptitle(readout(0), fontsize=10)
    moving.append(title)
    for art in moving:
        art.set_animated(True)
    fig.canvas.draw()  # layout and the fixed parts, once
    fig.set_layout_engine("none")
    background = fig.canvas.copy_from_bbox(fig.bbox)
    writer = _gif_writer(GIF_FPS)
    with writer.saving(fig, path, GIF_DPI):
        for i in range(n):
            if progress and i % 8 == 0:
                progress(f"{Path(path).name}: frame {i + 1}/{n}", i, n)
            fig.canvas.restore_region(background)
            for move in moves:
                move(i)
            title.set_text(readout(i))
            for art in moving:
                fig.draw_artist(art)
            writer.grab_frame()
    return Path(path)


# -- everything ------------------------------------------------------------------------------------------------

FIGURES = (("trajectories.png", trajectories), ("feed_dog_stitches.png", feed_dog_stitches), ("motion.png", motion),
           ("bearings_polar.png", bearings_polar), ("joint_reactions_polar.png", joint_reactions_polar),
           ("torque.png", torque), ("shaking.png", shaking))
GIF = "machine.gif"


def write_all(analysis, folder, progress=None, gif: bool = True) -> list[Path]:
    """Every figure (and the GIF unless ``gif=False``) into ``folder``; returns the paths written.
    ``progress(message, done, total)`` is called before each file (done = files finished, total = files) and
    every 8 frames of the GIF (done stays at the GIF's index)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    total = len(FIGURES) + bool(gif)
    report = progress or (lambda message, done, total: None)
    out = []
    for k, (name, make) in enumerate(FIGURES):
        report(name, k, total)
        out.append(make(analysis, folder / name))
    if gif:
        out.append(machine_gif(analysis, folder / GIF, lambda message, i, n: report(message, len(FIGURES), total)))
    return out


__all__ = ["DPI", "FIGURES", "GIF", "SIZES", "Linkage", "bearings_polar", "draw_bearings_polar",
           "draw_feed_dog_stitches", "feed_dog_stitches",
           "draw_joint_reactions_polar", "draw_motion", "draw_shaking", "draw_torque", "draw_trajectories",
           "joint_reactions_polar", "linkage", "machine_gif", "motion", "new_figure", "shaking", "torque",
           "trajectories", "write_all"]

"""What every figure shares: the Agg figure and its fixed layout, shaft-angle axes, group colours, and the parts
a machine's pictures look up by role (never by a catalog name)."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from sewgen.files import replacing
from sewgen.machine.feed import has_feed, plate_height
from sewgen.roles import (FEED_DOG, HOOK_POINT, KNIFE_EDGE, LOWER_LOOPER_TIP, NEEDLE_EYE, NEEDLE_POINT, RACK_TOOTH,
    THROAT_PLATE, UPPER_LOOPER_TIP)

MM = 1e3  # m -> mm
DPI = 100
#: Group colours, by the group's place in the machine (the first group blue, the second orange, ...).
PALETTE = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown", "tab:pink", "tab:olive",
           "tab:cyan", "tab:gray")
#: Point roles that work at the throat plate: the plate is drawn beside them.
AT_THE_PLATE = (NEEDLE_EYE, NEEDLE_POINT, HOOK_POINT, FEED_DOG, RACK_TOOTH, LOWER_LOOPER_TIP, UPPER_LOOPER_TIP,
                KNIFE_EDGE)


# -- figures ---------------------------------------------------------------------------------------------------

def import_drawing() -> None:
    """Import what drawing a figure needs (matplotlib's figure, axes and Agg canvas: ~0.5 s): done before the
    plotting child is forked, the child shares it instead of paying it again (sewgen.report.plots.start_all)."""
    import matplotlib.figure  # noqa: F401

    from sewgen.report.plots import canvas  # noqa: F401


def new_figure(size, dpi=DPI):
    """A figure on its own Agg canvas (no pyplot, no global backend change; :mod:`.canvas`). No layout engine:
    the figures place their axes once (:func:`place`), so drawing never re-runs a layout."""
    from matplotlib.figure import Figure

    from sewgen.report.plots.canvas import TextCacheCanvas

    fig = Figure(figsize=size, dpi=dpi)
    TextCacheCanvas(fig)  # Agg, its plain text drawn from cached whole-string bitmaps (sewgen.report.plots.canvas)
    return fig


def place(fig, nrows, ncols, *, left=0.8, right=0.25, top=0.6, bottom=0.6, wspace=0.7, hspace=0.7, **kw):
    """A grid of axes with margins and gaps in inches (fast: no constrained layout); ``kw`` go to
    ``fig.subplots`` (``subplot_kw``, ``width_ratios``, ``sharex``, ...). Returns the (nrows, ncols) array."""
    w, h = fig.get_size_inches()
    aw = (w - left - right - wspace * (ncols - 1)) / ncols
    ah = (h - top - bottom - hspace * (nrows - 1)) / nrows
    gs = dict(left=left / w, right=1 - right / w, top=1 - top / h, bottom=bottom / h,
              wspace=wspace / max(aw, 1e-3), hspace=hspace / max(ah, 1e-3))
    return fig.subplots(nrows, ncols, squeeze=False, gridspec_kw=gs, **kw)


def save(fig, path, option: str | None = None, **kw) -> Path:
    """``fig`` as the picture ``path`` (its format from the suffix: png, pdf, svg), written whole or not at all
    (sewgen.files.replacing; ``option``: the command-line option naming it, for its errors); ``kw`` go to
    ``savefig``. A PNG is compressed with zlib's fastest level: ~30 % less time, ~10 % more bytes."""
    fmt = Path(path).suffix[1:].lower() or "png"
    if fmt == "png":
        kw.setdefault("pil_kwargs", {"compress_level": 1})
    with replacing(path, option) as fh:
        fig.savefig(fh, format=fmt, **kw)
    return Path(path)


def render(draw, analysis, path, size):
    """Draw ``draw(fig, analysis)`` on a new figure of ``size`` (inches) and write it as a PNG."""
    fig = new_figure(size)
    draw(fig, analysis)
    return save(fig, path, dpi=DPI)


def title(a, what: str) -> str:
    return f"{a.machine.name}: {what} at {a.omega[0] * 30 / math.pi:.0f} rpm"


def suptitle(fig, text, size=12):
    """A figure title in one line: its font shrinks (to 8 pt at least) to fit a narrow figure's width."""
    width_in, height_in = fig.get_size_inches()
    fit = 0.96 * width_in * 72 / (0.55 * max(len(text), 1))  # DejaVu Sans: a character is about 0.55 em wide
    fig.text(0.5, 1 - 0.12 / height_in, text, ha="center", va="top", fontsize=max(min(size, fit), 8))


# -- shaft angles ----------------------------------------------------------------------------------------------

def full_turn(phi) -> bool:
    h = np.diff(phi)
    return len(phi) > 2 and np.allclose(h, h[0]) and abs(len(phi) * h[0] - 2 * math.pi) < 1e-6


def closed(a, y):
    """``y`` with its first value repeated at the end when the sweep is one whole turn (closed curves)."""
    y = np.asarray(y)
    return np.concatenate([y, y[:1]]) if full_turn(a.phi) else y


def deg(a):
    """Shaft angles in degrees, closed to 360° like :func:`closed`."""
    d = np.degrees(a.phi)
    return np.append(d, d[0] + 360.0) if full_turn(a.phi) else d


def angle_axis(ax, label=True, step=45):
    """A shaft-angle abscissa 0–360° with a tick every ``step`` degrees and a light grid."""
    ax.set_xlim(0, 360)
    ax.set_xticks(np.arange(0, 361, step))
    ax.grid(alpha=0.3)
    if label:
        ax.set_xlabel("shaft angle φ (deg)")


def angle_grid(ax, bottom: bool, step=90):
    """A shaft-angle abscissa 0–360° for one of a column of panels: grid lines every ``step`` degrees, ticks and
    their labels only on the ``bottom`` panel (a tick costs matplotlib about a millisecond to build: on the
    motion figure's 24 panels the hidden x ticks of all but the bottom row were a fifth of its time)."""
    from matplotlib import rcParams
    from matplotlib.ticker import NullLocator

    ax.set_xlim(0, 360)
    grid = np.arange(0, 361, step)
    if bottom:
        ax.set_xticks(grid)
        ax.set_xlabel("shaft angle φ (deg)")
    else:
        ax.xaxis.set_major_locator(NullLocator())
    ax.grid(axis="y", alpha=0.3)
    ax.vlines(grid[1:-1], 0, 1, transform=ax.get_xaxis_transform(), colors=rcParams["grid.color"],
              linewidths=rcParams["grid.linewidth"], alpha=0.3, zorder=0.5)  # the x grid, as ax.grid draws it


def runs(mask) -> list[tuple[int, int]]:
    """(first, last) indices of every run of True in ``mask``."""
    m = np.concatenate([[False], np.asarray(mask, bool), [False]])
    edges = np.flatnonzero(m[1:] != m[:-1])
    return [(int(i), int(j) - 1) for i, j in zip(edges[::2], edges[1::2])]


def shade(ax, a, mask, color, label=None):
    """Shade the shaft angles where ``mask`` holds (full height of the axes): one rectangle per run of samples
    where it holds, from the run's first sample to its last (what ``fill_between(where=mask)`` draws), as one
    collection added without autoscaling (fill_between re-scales the axes and, through them, every axes sharing
    x: a third of the motion figure's time)."""
    from matplotlib.collections import PolyCollection

    x = deg(a)
    verts = [[(x[i], 0.0), (x[j], 0.0), (x[j], 1.0), (x[i], 1.0)] for i, j in runs(closed(a, mask))]
    pc = PolyCollection(verts, facecolors=color, edgecolors="none", alpha=0.12, linewidths=0,
                        transform=ax.get_xaxis_transform(), label=label)
    ax.add_collection(pc, autolim=False)
    return pc


def angle_labels(ax, a, x, y, *, at=None, step=45.0, color="0.2", size=7):
    """Dots and "φ°" labels at every ``step`` degrees of shaft angle on a path x, y (equal-aspect data units);
    each label is pushed off the path along its normal, away from the path's centre. ``at`` gives other
    data coordinates to annotate (a polar axes' θ, r) with x, y used for the directions. A label that would
    overlap one already placed is left out with its dot (labels at multiples of 90° are placed first), so
    labels never pile up where a path passes one spot at several angles. Call it after the axes' limits are
    final (set, or autoscaled with the path plotted). One Line2D holds the dots; the labels are plain texts.
    Returns the shaft angles (deg) labelled."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    d = np.degrees(a.phi)
    idx = np.flatnonzero(np.abs(d - step * np.round(d / step)) < 1e-6)
    if not len(idx):
        return []
    tx, ty = np.roll(x, -1) - np.roll(x, 1), np.roll(y, -1) - np.roll(y, 1)
    cx, cy = x.mean(), y.mean()
    size_ = max(np.ptp(x), np.ptp(y), 1e-300)
    px, py = (x, y) if at is None else (np.asarray(at[0]), np.asarray(at[1]))
    ax.autoscale_view()
    ax.apply_aspect()
    to_px = ax.transData.transform
    scale = ax.figure.dpi / 72.0  # points -> pixels
    order = sorted(idx, key=lambda i: (round(d[i] % 90.0, 6) != 0.0, d[i] % 360.0))
    boxes, kept = [], []
    for i in order:
        nx, ny = ty[i], -tx[i]  # right-hand normal of the direction of travel
        ox, oy = x[i] - cx, y[i] - cy
        if math.hypot(nx, ny) < 1e-3 * size_:  # at rest: straight out from the centre
            nx, ny = ox, oy
        elif nx * ox + ny * oy < -1e-9 * size_**2:
            nx, ny = -nx, -ny
        r = math.hypot(nx, ny) or 1.0
        nx, ny = nx / r, ny / r
        ha = "center" if abs(nx) < 0.4 else ("left" if nx > 0 else "right")  # the text starts next to the dot
        va = "center" if abs(ny) < 0.4 else ("bottom" if ny > 0 else "top")
        text = f"{d[i] % 360:.0f}°"
        w, h = 0.62 * size * len(text) * scale, 1.15 * size * scale
        bx, by = to_px((px[i], py[i])) + 5 * scale * np.array([nx, ny])
        left = bx - {"left": 0.0, "center": w / 2, "right": w}[ha]
        bottom = by - {"bottom": 0.0, "center": h / 2, "top": h}[va]
        box = (left - 1, bottom - 1, left + w + 1, bottom + h + 1)
        if any(box[0] < o[2] and o[0] < box[2] and box[1] < o[3] and o[1] < box[3] for o in boxes):
            continue
        boxes.append(box)
        kept.append(i)
        ax.annotate(text, (px[i], py[i]), xytext=(5 * nx, 5 * ny), textcoords="offset points",
                    ha=ha, va=va, fontsize=size, color=color)
    kept.sort()
    ax.plot(px[kept], py[kept], "o", ms=2.5, color=color)
    return [float(d[i] % 360) for i in kept]


# -- groups, roles ---------------------------------------------------------------------------------------------

def color(a, g) -> str:
    """The colour of group ``g`` (a Group or its name): by its place in the machine."""
    name = getattr(g, "name", g)
    k = next(i for i, gr in enumerate(a.machine.groups) if gr.name == name)
    return PALETTE[k % len(PALETTE)]


def plate(a):
    """(group, height in m) of the first group with a ``throat_plate`` role, or None. The groups share the
    machine's frame (x, y), so one plate serves every group."""
    for g in a.machine.groups:
        if g.mechanism.description.has_role(THROAT_PLATE):
            return g, plate_height(g.mechanism, g.params or None)
    return None


def throat_plate_height(a):
    """The throat plate's height (m) in the machine frame, or None."""
    p = plate(a)
    return None if p is None else float(p[1]) + offset(p[0])[1]


def offset(g) -> tuple:
    """(horizontal, vertical) shift (m) from group ``g``'s plane coordinates to the drawing's: zero for a group
    across the shaft (its x, y are the machine's); for a group whose plane contains the shaft (``frame =
    "along"``) its origin's (z, y), so it is drawn in the machine's z–y plane (x along the shaft is z)."""
    if not getattr(g, "along", False):
        return (0.0, 0.0)
    return (float(g.origin[2]), float(g.origin[1]))


def axis_name(g) -> str:
    """The drawing's horizontal axis for group ``g``: "x", or "z" for a group along the shaft."""
    return "z" if getattr(g, "along", False) else "x"


def role_points(g) -> list:
    """(point name, role) of every role-tagged point of group ``g``, in declaration order."""
    return [(p.name, p.role) for p in g.mechanism.description.points if p.role]


def role_point(a, role):
    """(group, point name) of the first group with a point of ``role``, or (None, None)."""
    for g in a.machine.groups:
        name = g.mechanism.description.role_name(role)
        if name is not None and g.mechanism.description.has("point", name):
            return g, name
    return None, None


def feed_groups(a) -> list:
    """The groups that declare a feed dog, a throat plate and a stitch regulator (sewgen.machine.feed.has_feed)."""
    return [g for g in a.machine.groups if has_feed(g.mechanism)]


def pretty(name: str) -> str:
    """A role or part name as words: "needle_eye" -> "needle eye"."""
    return name.replace("_", " ")


def run_of(fa) -> tuple:
    """(parameter vector, held inputs, load array or None) that a group's sweep ``fa`` ran with; Nones for what
    it does not know (a plain Motion)."""
    s = getattr(fa, "run_settings", None)
    return (None, None, None) if s is None else (s.params, s.held, s.loads)


def load_mask(fa):
    """(n,) where the group's external loads act (any load slot non-zero), or None without loads."""
    ld = run_of(fa)[2]
    if ld is None:
        return None
    mask = np.any(np.asarray(ld) != 0.0, axis=1)
    return mask if mask.any() else None


def shade_loads(ax, a, labels=True):
    """Shade the shaft angles where each group's external forces act, read from the load array its sweep used."""
    for g in a.machine.groups:
        mask = load_mask(a.groups[g.name])
        if mask is not None:
            shade(ax, a, mask, color(a, g), f"external loads on {g.name} act" if labels else None)

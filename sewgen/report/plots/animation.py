"""The machine drawn over a revolution: one panel per group, each in its own equal-aspect view (groups at
different axial positions never pile up into one knot), and, when the machine has a throat plate, a close-up
of the stitch-forming zone: the bodies that carry the needle, the hook point and the feed dog (the roles of
common.AT_THE_PLATE), their paths and the plate.
A readout says, by role, whether the needle is below the plate and the feed dog up.

The GIF is blitted: the fixed parts are drawn once, every frame redraws only the moving collections onto a
saved background, and each frame is mapped onto the first frame's palette (no dithering), so Pillow writes only
the pixels that change.
"""
from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np

from sewgen.files import replacing
from sewgen.roles import FEED_DOG, NEEDLE_EYE, NEEDLE_POINT
from sewgen.report.plots.common import (AT_THE_PLATE, axis_name, color, new_figure, offset, role_point,
    throat_plate_height)
from sewgen.report.plots.drawing import PanelArtists, Part
from sewgen.report.plots.geometry import linkage

GIF_WIDTH, GIF_MAX_HEIGHT, GIF_DPI, GIF_FPS, GIF_COLORS = 12.0, 8.0, 80, 10, 64
_ROW_MAX = 4.5  # inches: the tallest a row of panels gets
_MIN_WIDTH = 6.0  # inches: room for the readout
#: Inches round each panel: left (y tick labels and label), bottom (x ones), top (the panel's title).
_PAD = dict(left=0.62, bottom=0.48, top=0.3, right=0.08)
_HEADER = 0.4  # inches: the readout line at the top of the figure


def _views(a, links):
    """[(title, linkage index or None for the close-up, (x0, x1, y0, y1) mm)] of the panels."""
    views = []
    for k, (g, lk) in enumerate(zip(a.machine.groups, links)):
        x0, x1, y0, y1 = lk.extent(0.0)
        text = g.name if g.name == g.mechanism.name else f"{g.name} ({g.mechanism.name})"
        views.append((text, k, lk.extent(0.06 * max(x1 - x0, y1 - y0))))
    zone = _zone(a, links)
    if zone is not None:
        views.append(("stitch-forming zone", None, zone))
    return views


def _zone_parts(a, links):
    """(linkage index, bodies, marks) of the parts that work at the throat plate (needle eye, feed dog)."""
    out = []
    gn, _ = role_point(a, NEEDLE_POINT)
    for k, lk in enumerate(links):
        marks = [lk.roles[r] for r in AT_THE_PLATE if r in lk.roles]
        if not marks or (gn is not None and axis_name(a.machine.groups[k]) != axis_name(gn)):
            continue  # only the parts drawn in the needle's plane (a group across the shaft, beside one along it)
        bodies = {b for m in marks for b in _bodies_of(a.machine.groups[k].mechanism, m)}
        out.append((k, bodies, marks))
    return out


def _bodies_of(mech, point):
    """The body a named point belongs to (from its anchor), as a one-element list (empty if unknown)."""
    d = mech.description
    body = d.point(point).body or next((an.body for an in d.anchors if an.kind == "point" and an.name == point), None)
    return [body] if body else []


def _zone(a, links):
    """(x0, x1, y0, y1) mm of the stitch-forming zone round the throat plate, or None without a plate."""
    plate = throat_plate_height(a)
    parts = _zone_parts(a, links)
    if plate is None or not parts:
        return None
    xy = np.concatenate([links[k].points[m] for k, _b, marks in parts for m in marks])
    x0, x1 = xy[:, 0].min(), xy[:, 0].max()
    y0, y1 = min(xy[:, 1].min(), plate * 1e3), max(xy[:, 1].max(), plate * 1e3)
    h = (y1 - y0) + 16.0
    w = max(x1 - x0 + 24.0, 0.75 * h)
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    return cx - w / 2, cx + w / 2, cy - h / 2, cy + h / 2


def _arrangements(n, aspects):
    """Candidate arrangements of n panels: (kind, [[panel, ...], ...]) — rows of panels side by side in their
    order, or columns of stacked panels in their order or from the tallest to the widest (tall mechanisms get a
    column each, wide ones share one)."""
    orders = [list(range(n)), sorted(range(n), key=lambda i: aspects[i])]
    for kind, order in (("rows", orders[0]), ("columns", orders[0]), ("columns", orders[1])):
        for k in range(1, min(n, 6 if kind == "columns" else 3) + 1):
            for cuts in itertools.combinations(range(1, n), k - 1):
                bounds = (0, *cuts, n)
                yield kind, [order[bounds[r]:bounds[r + 1]] for r in range(k)]


def _layout(aspects, W, H_max):
    """(width, height, boxes) for panels of data aspect w/h on a figure at most ``W`` inches wide and ``H_max``
    high: of :func:`_arrangements`, the one with the largest product of the panels' areas (every panel gets a
    fair share); boxes (left, bottom, width, height) in inches, the figure as large as the panels need."""
    n = len(aspects)
    padw, padh = _PAD["left"] + _PAD["right"], _PAD["top"] + _PAD["bottom"]
    room_h = H_max - _HEADER
    best, best_score = None, -math.inf
    for kind, lines in _arrangements(n, aspects):
        if kind == "rows":  # each row as high as its panels fit across W (at most _ROW_MAX)
            sizes = [min(_ROW_MAX, (W - padw * len(g)) / sum(aspects[i] for i in g)) for g in lines]
            used = sum(sizes) + padh * len(lines)
            scale = min(1.0, (room_h - padh * len(lines)) / max(sum(sizes), 1e-9))
        else:  # each column as wide as its stacked panels fit down the room
            sizes = [(room_h - padh * len(g)) / sum(1 / aspects[i] for i in g) for g in lines]
            scale = min(1.0, (W - padw * len(lines)) / max(sum(sizes), 1e-9))
        sizes = [s * scale for s in sizes]
        if min(sizes) <= 0:
            continue
        heights = {i: (s if kind == "rows" else s / aspects[i]) for g, s in zip(lines, sizes) for i in g}
        score = sum(math.log(aspects[i] * h * h) for i, h in heights.items())
        if score > best_score + 1e-9:
            best, best_score = (kind, lines, sizes, heights), score
    kind, lines, sizes, heights = best
    boxes = [None] * n
    if kind == "rows":
        W = max(min(W, max(sum(aspects[i] * h + padw for i in g) for g, h in zip(lines, sizes))), _MIN_WIDTH)
    else:
        W = max(min(W, sum(s + padw for s in sizes)), _MIN_WIDTH)
    if kind == "rows":
        H = _HEADER + sum(s + padh for s in sizes)
        y = H - _HEADER
        for g, h in zip(lines, sizes):
            y -= h + padh
            widths = [aspects[i] * h + padw for i in g]
            x = (W - sum(widths)) / 2
            for i, w in zip(g, widths):
                boxes[i] = (x + _PAD["left"], y + _PAD["bottom"], w - padw, h)
                x += w
    else:
        H = _HEADER + max(sum(heights[i] + padh for i in g) for g in lines)
        x = (W - sum(s + padw for s in sizes)) / 2
        for g, w in zip(lines, sizes):
            col_h = sum(heights[i] + padh for i in g)
            y = H - _HEADER - (H - _HEADER - col_h) / 2
            for i in g:
                y -= heights[i] + padh
                boxes[i] = (x + _PAD["left"], y + _PAD["bottom"], w, heights[i])
            x += w + padw
    return W, H, boxes


def machine_linkages(a) -> list:
    """The drawing of every group of analysis ``a`` (:func:`~sewgen.report.plots.geometry.linkage`), in group order."""
    return [_shifted(linkage(g, a.groups[g.name]), offset(g)) for g in a.machine.groups]


def _shifted(lk, shift):
    """Linkage ``lk`` moved by ``shift`` (m; :func:`~sewgen.report.plots.common.offset`): a group along the shaft is
    drawn in the machine's z–y plane, where the groups working at the needle meet."""
    dx, dy = shift[0] * 1e3, shift[1] * 1e3
    if dx == 0.0 and dy == 0.0:
        return lk
    d = np.array([dx, dy])
    lk.bodies = {k: v + d for k, v in lk.bodies.items()}
    lk.joints = {k: {b: v + d for b, v in on.items()} for k, on in lk.joints.items()}
    lk.pins = None if lk.pins is None else lk.pins + d
    lk.pivots = None if lk.pivots is None else lk.pivots + d
    lk.circles = [(np.asarray(c) + d, r) for c, r in lk.circles]
    for gd in lk.guides:
        gd.ends = gd.ends + d
    for sl in lk.sliders:
        sl.center = sl.center + d
    lk.cams = {k: v + d for k, v in lk.cams.items()}
    lk.rods = [(a, b, v + d) for a, b, v in lk.rods]
    lk.points = {k: v + d for k, v in lk.points.items()}
    return lk


class MachineView:
    """The panels of a machine on a new figure ``width`` inches wide (as high as the panels need, at most
    ``max_height``), drawn at position ``index``; :meth:`update` moves them to another. ``animated``: the moving
    parts are left out of a plain draw (for blitting)."""

    def __init__(self, a, *, width=GIF_WIDTH, max_height=GIF_MAX_HEIGHT, dpi=GIF_DPI, index=0, animated=False,
                 links=None):
        self.a = a
        self.links = machine_linkages(a) if links is None else links
        self.plate = throat_plate_height(a)
        views = _views(a, self.links)
        W, H, boxes = _layout([(v[2][1] - v[2][0]) / (v[2][3] - v[2][2]) for v in views], width, max_height)
        W, H = (math.ceil(v * dpi / 2) * 2 / dpi for v in (W, H))  # even numbers of pixels
        self.fig = fig = new_figure((W, H), dpi)
        self.axes, self.panels = [], []
        zone_parts = _zone_parts(a, self.links)
        groups = a.machine.groups
        for (text, k, (x0, x1, y0, y1)), (l, b, w, h) in zip(views, boxes):
            ax = fig.add_axes((l / W, b / H, w / W, h / H))
            self.axes.append(ax)
            if k is None:
                parts = [Part(self.links[j], color(a, groups[j]), bodies, marks) for j, bodies, marks in zone_parts]
                self.panels.append(PanelArtists(ax, parts, lw=1.8, animated=animated))
                ax.set_title(text, fontsize=8, y=1.0)
            else:
                self.panels.append(PanelArtists(ax, [Part(self.links[k], color(a, groups[k]))], lw=1.2,
                                                animated=animated))
                ax.set_title(text, fontsize=8, color=color(a, groups[k]), y=1.0)
            if self.plate is not None and y0 < self.plate * 1e3 < y1:
                ax.axhline(self.plate * 1e3, color="k", lw=0.8, ls=(0, (6, 3)), zorder=1)
                if k is None:
                    ax.text(x1, self.plate * 1e3, "throat plate ", ha="right", va="bottom", fontsize=7)
            ax.set(xlim=(x0, x1), ylim=(y0, y1))
            ax.set_aspect("equal", adjustable="box")
            names = sorted({axis_name(groups[j]) for j, _b, _m in zone_parts} if k is None else {axis_name(groups[k])})
            ax.set_xlabel(f"{' or '.join(names)} (mm)", fontsize=7, labelpad=1)
            ax.set_ylabel("y (mm)", fontsize=7, labelpad=1)
            ax.tick_params(labelsize=6, pad=1.5, length=2)
            ax.grid(alpha=0.25, lw=0.5)
        x = 0.08 + 0.11 * len(a.machine.name) + 0.2  # inches: the name, the shaft angle, the status
        top = 1 - 0.1 / H
        fig.text(0.08 / W, top, a.machine.name, ha="left", va="top", fontsize=10, weight="bold")
        self.angle = fig.text(x / W, top, "", ha="left", va="top", fontsize=10, animated=animated)
        self.status = fig.text((x + 1.1) / W, top, "", ha="left", va="top", fontsize=10, animated=animated)
        self.boxes = {"angle": (x - 0.02, H - _HEADER, x + 1.08, H), "status": (x + 1.08, H - _HEADER, W, H)}
        self.update(index)

    @property
    def artists(self):
        return [art for p in self.panels for art in p.artists] + [self.angle, self.status]

    def update(self, i: int):
        for p in self.panels:
            p.update(i)
        self.angle.set_text(f"φ = {math.degrees(self.a.phi[i]) % 360:5.1f}°")
        self.status.set_text(status(self.a, i))
        return self.artists


def status(a, i: int) -> str:
    """What the stitch-forming parts are doing at position i, by role: needle below/above the plate, feed dog
    up/down; empty without a throat plate."""
    plate = throat_plate_height(a)
    if plate is None:
        return ""
    words = []
    for role, yes, no in ((NEEDLE_EYE, "needle in the cloth", "needle out"),
                          (FEED_DOG, "feed dog up (feeding)", "feed dog down")):
        g, name = role_point(a, role)
        if g is not None:
            below = a.groups[g.name].motion.point(name).y[i] + offset(g)[1] < plate
            words.append((yes if below else no) if role == NEEDLE_EYE else (no if below else yes))
    return ", ".join(words)


def draw_machine(a, index: int = 0, **kw) -> MachineView:
    """The machine at position ``index`` on a new figure (a static picture: ``view.fig``); returns the view
    (``view.update(i)`` moves it)."""
    return MachineView(a, index=index, **kw)


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

        def finish(self):  # the GIF written whole or not at all (sewgen.files.replacing)
            with replacing(self.outfile) as fh:
                self._frames[0].save(fh, format="GIF", save_all=True, append_images=self._frames[1:],
                                     duration=int(1000 / self.fps), loop=0)

    return CanvasGifWriter(fps=fps)


def machine_gif(analysis, path, progress=None, links=None):
    """The machine over the sweep, one frame per shaft angle (see the module). ``progress(message, frame,
    frames)`` is called every 8 frames; ``links``: the groups' drawings if already built."""
    a, n = analysis, len(analysis.phi)
    from matplotlib.transforms import Bbox

    view = MachineView(a, animated=True, links=links)
    fig, canvas = view.fig, view.fig.canvas
    canvas.draw()  # the fixed parts, once
    # the backgrounds of the panels and of the two readouts; a frame restores and redraws each panel and the
    # shaft angle, and the status only when it changes (the canvas keeps the rest from the frame before)
    panels = [(canvas.copy_from_bbox(ax.bbox), p.artists) for ax, p in zip(view.axes, view.panels)]
    readouts = {k: canvas.copy_from_bbox(Bbox.from_extents(*v).transformed(fig.dpi_scale_trans))
                for k, v in view.boxes.items()}
    shown = None
    writer = _gif_writer(GIF_FPS)
    with writer.saving(fig, path, GIF_DPI):
        for i in range(n):
            if progress and i % 8 == 0:
                progress(f"{Path(path).name}: frame {i + 1}/{n}", i, n)
            view.update(i)
            for region, artists in panels:
                canvas.restore_region(region)
                for art in artists:
                    fig.draw_artist(art)
            canvas.restore_region(readouts["angle"])
            fig.draw_artist(view.angle)
            if view.status.get_text() != shown:
                shown = view.status.get_text()
                canvas.restore_region(readouts["status"])
                fig.draw_artist(view.status)
            writer.grab_frame()
    return Path(path)

"""Linkages on axes: the fixed parts drawn once, the moving parts as three collections updated per position.

:class:`PanelArtists` puts one or more :class:`~sewgen.report.plots.geometry.Linkage` on an axes: ground pivots
(hatched pivot symbols), fixed guides (dashed), crank circles (dotted) and the paths of the named points are
drawn once; the moving parts of all of them are three artists — cams, bodies (translucent polygons) and slider
blocks; bars and moving guides; pins and point markers — whose data ``update(i)`` sets to position i, so a
blitted animation redraws three artists per panel and frame.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

_GROUND_MARKER = None


def ground_marker():
    """A pivot-on-ground marker: a triangle under the pin, a base line and hatching below it."""
    global _GROUND_MARKER
    if _GROUND_MARKER is None:
        from matplotlib.path import Path as MPath

        verts = [(0, 0), (-0.55, -1.0), (0.55, -1.0), (0, 0)]
        codes = [MPath.MOVETO, MPath.LINETO, MPath.LINETO, MPath.CLOSEPOLY]
        verts += [(-0.9, -1.0), (0.9, -1.0)]
        codes += [MPath.MOVETO, MPath.LINETO]
        for k in range(7):
            x = -0.75 + 0.27 * k
            verts += [(x, -1.0), (x - 0.3, -1.35)]
            codes += [MPath.MOVETO, MPath.LINETO]
        _GROUND_MARKER = MPath(verts, codes)
    return _GROUND_MARKER


def lighter(color, k=0.55):
    """``color`` mixed with white (k = 0: itself, 1: white), as an RGB tuple."""
    from matplotlib.colors import to_rgb

    r, g, b = to_rgb(color)
    return (r + (1 - r) * k, g + (1 - g) * k, b + (1 - b) * k)


@dataclass
class Part:
    """What of a linkage a panel draws: ``bodies`` (None: all, with its ground parts) and ``marks`` (None: the
    linkage's marks), in ``color``."""

    lk: object
    color: str
    bodies: set | None = None
    marks: list | None = None


class PanelArtists:
    """The parts on ``ax``; ``lw`` the line width of outlines (bars are 1.6 times it). With ``animated`` the
    moving artists are left out of a plain draw (blitting) and drawn without antialiasing (fewer colours: a
    smaller GIF)."""

    def __init__(self, ax, parts, *, lw=1.4, animated=True, paths=True, z=3.0):
        from matplotlib.collections import LineCollection, PathCollection, PolyCollection
        from matplotlib.transforms import IdentityTransform

        self.parts = parts
        aa = not animated
        polys, poly_fc, poly_ec = [], [], []  # (getter, ...) per polygon, drawn in this order: cams, bodies
        lines, line_c, line_w, line_s = [], [], [], []
        blocks, block_fc, block_ec = [], [], []
        pins, pin_ec = [], []
        marks, mark_fc, mark_sz = [], [], []
        for part in parts:
            lk, color = part.lk, part.color
            keep = (lambda b: True) if part.bodies is None else (lambda b, s=part.bodies: b in s)
            light = lighter(color)
            for b, prof in lk.cams.items():
                if keep(b):
                    polys.append(prof)
                    poly_fc.append((*light, 0.85))
                    poly_ec.append(color)
            for b, ol in lk.bodies.items():
                if keep(b) and ol.shape[1] >= 3:
                    polys.append(ol)
                    poly_fc.append((*light, 0.4))
                    poly_ec.append(color)
            for b, ol in lk.bodies.items():
                if keep(b) and ol.shape[1] == 2:
                    lines.append(ol)
                    line_c.append(color)
                    line_w.append(lw * 1.6)
                    line_s.append("solid")
            for ba, bb, ends in lk.rods:
                if keep(ba) or keep(bb):
                    lines.append(ends)
                    line_c.append(color)
                    line_w.append(lw)
                    line_s.append("solid")
            for gd in lk.guides:
                if not gd.fixed and keep(gd.body):
                    lines.append(gd.ends)
                    line_c.append("0.25")
                    line_w.append(0.8)
                    line_s.append((0, (4, 2)))
            for s in lk.sliders:
                if keep(s.body):
                    blocks.append(s.corners())
                    block_fc.append(light)
                    block_ec.append(color)
            if part.bodies is None and lk.pins is not None:
                for k in range(lk.pins.shape[1]):
                    pins.append(lk.pins[:, k])
                    pin_ec.append(color)
            roles = set(lk.roles.values())
            for m in (lk.marks if part.marks is None else part.marks):
                marks.append(lk.points[m])
                mark_fc.append(color)
                mark_sz.append(40.0 if m in roles else 20.0)
            # -- fixed parts, drawn once
            if part.bodies is None:
                for gd in lk.guides:
                    if gd.fixed:
                        ax.plot(*gd.ends[0].T, color="0.3", lw=0.9, ls=(0, (5, 3)), zorder=z - 2)
                t = np.linspace(0, 2 * np.pi, 73)
                for c, r in lk.circles:
                    ax.plot(c[0] + r * np.cos(t), c[1] + r * np.sin(t), color=color, lw=0.7, ls=":", zorder=z - 2)
                if lk.pivots is not None and len(lk.pivots):
                    ax.plot(*lk.pivots.T, ls="none", marker=ground_marker(), ms=13, mfc="0.85", mec="0.3", mew=0.7,
                            zorder=z - 1)
                    ax.plot(*lk.pivots.T, "o", ms=4.5, mfc="0.55", mec="k", mew=0.8, zorder=z + 2)
            if paths:
                for m in (lk.marks if part.marks is None else part.marks):
                    p = lk.points[m]
                    ax.plot(np.append(p[:, 0], p[0, 0]), np.append(p[:, 1], p[0, 1]), color=color, lw=0.7,
                            alpha=0.6, zorder=z - 1)
        self._polys = polys + blocks  # the blocks over the bodies; a bar through a block is its rod in a bush
        self._lines = lines
        dots = pins + marks  # the pins, then the named points over them
        self._dots = np.stack(dots, axis=1) if dots else None  # (n, k, 2)
        self.artists = []
        if self._polys:
            self.poly_art = PolyCollection([], facecolors=poly_fc + [(*c, 1.0) for c in block_fc],
                                           edgecolors=poly_ec + block_ec, linewidths=lw * 0.7, zorder=z - 0.5,
                                           antialiased=aa)
            self.artists.append(self.poly_art)
        if lines:
            self.line_art = LineCollection([], colors=line_c, linewidths=line_w, linestyles=line_s, zorder=z,
                                           antialiased=aa, capstyle="round")
            self.artists.append(self.line_art)
        for art in self.artists:
            ax.add_collection(art, autolim=False)
        if self._dots is not None:
            self.dot_art = PathCollection([_circle()], sizes=[12.0] * len(pins) + mark_sz,
                                          facecolors=["w"] * len(pins) + mark_fc,
                                          edgecolors=pin_ec + ["k"] * len(marks), linewidths=0.8,
                                          offsets=self._dots[0], offset_transform=ax.transData,
                                          transform=IdentityTransform(), zorder=z + 1, antialiased=aa)
            ax.add_collection(self.dot_art, autolim=False)
            self.artists.append(self.dot_art)
        if animated:
            for art in self.artists:
                art.set_animated(True)
        self.update(0)

    def update(self, i: int):
        if self._polys:
            self.poly_art.set_verts([p[i] for p in self._polys])
        if self._lines:
            self.line_art.set_segments([s[i] for s in self._lines])
        if self._dots is not None:
            self.dot_art.set_offsets(self._dots[i])
        return self.artists


def _circle():
    """The path of marker "o" (radius 0.5: a size s in points² gives a diameter of √s points)."""
    from matplotlib.markers import MarkerStyle

    m = MarkerStyle("o")
    return m.get_path().transformed(m.get_transform())

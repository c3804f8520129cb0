"""Paths of points in the machine's plane: every role-tagged point (needle eye, thread eye, feed dog, ...), or
every named point of a group without roles; and the feed-dog paths for a range of stitch lengths, for each group
that has a feed (a feed dog, a throat plate and a stitch regulator by role)."""
from __future__ import annotations

import math

import numpy as np

from ..errors import ParameterError
from ..feed import dog_travel, has_feed, plate_height, regulator_angle
from ..roles import FEED_DOG, STITCH_REGULATOR
from .common import (AT_THE_PLATE, MM, angle_labels, closed, color, feed_groups, place, pretty, role_points, suptitle,
                     throat_plate_height, title)

#: Stitch lengths (mm) of the feed-dog family: zero to the household maximum, and reverse feed.
STITCHES_MM = (0.0, 1.0, 2.0, 3.0, 4.0, -2.0, -4.0)
_NCOL = 3


def path_panels(a) -> list:
    """[(group, [(point, role or None), ...])]: one panel per role-tagged point; a group without any role (a
    user's mechanism that tags nothing) gets one panel with all its named points."""
    out = []
    for g in a.machine.groups:
        d = g.mechanism.description
        tagged = role_points(g)
        if tagged:
            out += [(g, [pr]) for pr in tagged]
        elif not d.roles and d.points:
            out.append((g, [(p.name, None) for p in g.mechanism.description.points]))
    return out


def trajectories_size(a):
    n = max(len(path_panels(a)), 1)
    rows, cols = math.ceil(n / _NCOL), min(n, _NCOL)
    return (max(1.1 + 3.95 * cols, 6.0), 0.75 + 4.75 * rows)


def draw_trajectories(fig, a):
    """Paths (mm) of the role-tagged points (a group without roles: all its points), the throat plate beside the
    points that work at it; returns {"group.point": (x, y)}."""
    panels = path_panels(a)
    n = max(len(panels), 1)
    rows, cols = math.ceil(n / _NCOL), min(n, _NCOL)
    axes = place(fig, rows, cols, left=0.8, right=0.3, top=0.55, bottom=0.65, wspace=0.85, hspace=1.0).ravel()
    plate = throat_plate_height(a)
    data = {}
    for ax in axes[len(panels):]:
        ax.set_visible(False)
    for ax, (g, pts) in zip(axes, panels):
        fa, c = a.groups[g.name], color(a, g)
        styles = ("-", "--", "-.", ":")
        for k, (name, role) in enumerate(pts):
            p = fa.motion.point(name)
            x, y = p.x * MM, p.y * MM
            data[f"{g.name}.{name}"] = (x, y)
            ax.plot(closed(a, x), closed(a, y), color=c, lw=1.5, ls=styles[k % 4], label=f"{pretty(name)} path",
                    gid=f"{g.name}.{name}")
            angle_labels(ax, a, x, y, size=6.5)
        roles = {role for _, role in pts}
        if plate is not None and roles & set(AT_THE_PLATE):
            ax.axhline(plate * MM, color="k", lw=1, ls="--", label=f"throat plate, y = {plate * MM:g} mm")
        if plate is not None and FEED_DOG in roles:
            name = next(nm for nm, r in pts if r == FEED_DOG)
            x, y = data[f"{g.name}.{name}"]
            above = y > plate * MM
            ax.plot(np.where(above, x, np.nan), np.where(above, y, np.nan), color="k", lw=3, alpha=0.3,
                    label="above the plate (feeding)")
            if has_feed(g.mechanism):
                _feed_note(ax, g, fa, plate)
        ax.set_aspect("equal", adjustable="datalim")
        ax.margins(0.2)
        head = pretty(pts[0][1]) if len(pts) == 1 and pts[0][1] else "named points"
        ax.set_title(f"{g.name}: {head}", fontsize=10, color=c, y=1.0)
        ax.set(xlabel="x (mm)", ylabel="y (mm)")
        ax.grid(alpha=0.3)
        ax.legend(loc="best", fontsize=7, framealpha=0.8)
    suptitle(fig, title(a, "paths in the machine's plane (labels: shaft angle φ)"))
    return data


def _feed_note(ax, g, fa, plate):
    try:
        t = dog_travel(fa.motion, plate)
    except (ParameterError, ValueError):  # not a whole turn, or the dog never clears the plate: no note
        return
    rise, sink = (math.degrees(v - g.phase) % 360 for v in (t.rise, t.sink))  # in the machine's shaft angle
    ax.text(0.02, 0.02, f"feed above the plate {t.travel * MM:.2f} mm\nφ {rise:.0f}° – {sink:.0f}°, "
            f"{t.height * MM:.2f} mm high",
            transform=ax.transAxes, va="bottom", fontsize=7, bbox=dict(fc="w", ec="0.7", alpha=0.85))


def stitches_size(a):
    return (11.0, 0.6 + 5.6 * max(len(feed_groups(a)), 1))


def draw_feed_dog_stitches(fig, a):
    """Feed-dog paths (mm) for stitch lengths 0 to 4 mm and reverse, the stitch regulator set for each (seed 001
    §五), one panel per group with a feed; returns {stitch mm: (x, y)} of the first such group (empty without)."""
    from matplotlib import colormaps

    groups = feed_groups(a)
    axes = place(fig, max(len(groups), 1), 1, left=0.9, right=3.4, top=0.85, bottom=0.6, hspace=0.9).ravel()
    out = {}
    if not groups:
        axes[0].set_axis_off()
        axes[0].text(0.5, 0.5, "no group with a feed dog, a throat plate and a stitch regulator", ha="center",
                     transform=axes[0].transAxes)
        return out
    cmap = colormaps["coolwarm"]
    for ax, g in zip(axes, groups):
        mech, params, fa = g.mechanism, g.params or None, a.groups[g.name]
        d = mech.description
        dog, reg = d.role_name(FEED_DOG), d.role_name(STITCH_REGULATOR)
        plate = plate_height(mech, params)
        data = {}
        for mm in STITCHES_MM:
            angle = regulator_angle(mech, mm * 1e-3, params=params)
            mo = mech.solve(fa.motion.phi, speed=fa.motion.omega, params=params, held={reg: angle})
            x, y = mo.point(dog).x * MM, mo.point(dog).y * MM
            data[mm] = (x, y)
            ax.plot(closed(a, x), closed(a, y), lw=1.4, color=cmap(0.5 + mm / 9.0),
                    label=f"{mm:+.0f} mm ({pretty(reg)} {math.degrees(angle):+.1f}°)")
        ax.axhline(plate * MM, color="k", lw=1, ls="--", label=f"throat plate, y = {plate * MM:g} mm")
        ax.set_aspect("equal", adjustable="datalim")
        ax.margins(0.1)
        ax.grid(alpha=0.3)
        ax.set(xlabel="x (mm, + = forward feed)", ylabel="y (mm)")
        ax.set_title(f"{g.name}: {pretty(dog)}", y=1.0)
        ax.legend(fontsize=8, loc="center left", bbox_to_anchor=(1.02, 0.5), title="stitch length")
        out = out or data
    suptitle(fig, title(a, "feed-dog paths for stitch lengths 0 to 4 mm and reverse"))
    return out

"""Displacement, velocity and acceleration against the shaft angle, for the parts found by role: the needle eye's
and the thread eye's height, the feed dog's feed and lift, the hook shaft's angle; any other role-tagged point
(x and y); and, for a group without roles, every named point (x and y)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sewgen.roles import FEED_DOG, HOOK_SHAFT, NEEDLE_EYE, RACK_TOOTH, THREAD_EYE
from sewgen.report.plots.common import (MM, angle_grid, axis_name, closed, color, deg, offset, place, pretty,
    role_point, shade, suptitle, throat_plate_height, title)

#: What the motion figure shows of a role-tagged point: [(component, title)], by role.
POINT_ROLES = {
    NEEDLE_EYE: [("y", "needle eye y (needle-bar travel)")],
    THREAD_EYE: [("y", "thread eye y (take-up)")],
    FEED_DOG: [("x", "feed dog x (feed)"), ("y", "feed dog y (lift)")],
    RACK_TOOTH: [("x", "rack tooth x (feed)"), ("y", "rack tooth y (lift)")],
}
#: Body roles whose angle the motion figure shows.
ANGLE_ROLES = {HOOK_SHAFT: "hook shaft angle"}
LINEAR, ANGULAR = ("mm", "m/s", "m/s²"), ("deg", "deg/s", "deg/s²")


@dataclass
class Row:
    """One row of the motion figure: a title, the group, units and one or more (label, x, v, a) series."""

    title: str
    group: object
    units: tuple
    series: list
    role: str | None = None
    component: str | None = None


def _point_series(p, comp, g=None):
    """(position mm, velocity, acceleration) of a point's component, positions in the drawing's frame (a group
    along the shaft: its x is the machine's z, shifted by its origin; sewgen.report.plots.common.offset)."""
    dx, dy = offset(g) if g is not None else (0.0, 0.0)
    return ((p.x + dx) * MM, p.vx, p.ax) if comp == "x" else ((p.y + dy) * MM, p.vy, p.ay)


def motion_rows(a) -> list:
    """The rows, group by group: role-tagged points and bodies first; a group without any, all its points."""
    rows = []
    for g in a.machine.groups:
        d, mo = g.mechanism.description, a.groups[g.name].motion
        mine = []
        for pt in d.points:
            if not pt.role:
                continue
            p = mo.point(pt.name)
            for comp, text in POINT_ROLES.get(pt.role, [("x", f"{pretty(pt.role)} x"), ("y", f"{pretty(pt.role)} y")]):
                if np.ptp(getattr(p, comp)) < 1e-9:  # a component that never moves (a needle's sideways): no row
                    continue
                if comp == "x" and axis_name(g) != "x":  # a group along the shaft: its x is the machine's z
                    text = text[:-1] + axis_name(g) if text.endswith(" x") else text
                mine.append(Row(f"{g.name}: {text}", g, LINEAR, [(comp, *_point_series(p, comp, g))], pt.role,
                                comp))
        for b in d.bodies:
            if b.role in ANGLE_ROLES:
                bm = mo.body(b.name)
                mine.append(Row(f"{g.name}: {ANGLE_ROLES[b.role]} ({b.name})", g, ANGULAR,
                                [("angle", np.degrees(np.unwrap(bm.angle)), np.degrees(bm.omega),
                                  np.degrees(bm.alpha))], b.role))
        if not mine:
            for pt in d.points:
                p = mo.point(pt.name)
                mine.append(Row(f"{g.name}: {pretty(pt.name)} x, y", g, LINEAR,
                                [(c, *_point_series(p, c)) for c in "xy"]))
        rows += mine
    return rows


def _masks(a):
    """[(mask, colour, text)]: where the needle eye is below the throat plate and the feed dog above it."""
    plate = throat_plate_height(a)
    out = []
    if plate is not None:
        for role, c, text, below in ((NEEDLE_EYE, "0.3", "needle eye below the plate", True),
                                     (FEED_DOG, "tab:red", "feed dog above the plate", False)):
            g, name = role_point(a, role)
            if g is not None:
                y = a.groups[g.name].motion.point(name).y + offset(g)[1]
                out.append(((y < plate) if below else (y > plate), c, text))
    return out


def _bottom(a):
    return 0.75 + (0.4 if _masks(a) else 0.0)  # inches: the x labels, and the legend of the shading


def motion_size(a):
    return (13.0, 0.55 + _bottom(a) + 2.45 * max(len(motion_rows(a)), 1))


_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def scale_of(values) -> tuple[float, str]:
    """(factor, prefix) that keeps an axis's tick labels short without an offset text ("1e4" in a corner): values
    of 10⁴ and more are shown in 10³, 10⁶, ... of their unit, the power in the axis label."""
    top = float(np.max(np.abs(values))) if len(values) else 0.0
    if not np.isfinite(top) or top < 1e4:
        return 1.0, ""
    e = 3 * int(np.floor(np.log10(top) / 3))
    return 10.0 ** -e, f"10{str(e).translate(_SUPERSCRIPT)} "


def draw_motion(fig, a):
    from matplotlib.ticker import MaxNLocator

    rows = motion_rows(a)
    n = max(len(rows), 1)
    axes = place(fig, n, 3, left=0.85, right=0.3, top=0.55, bottom=_bottom(a), wspace=0.85, hspace=0.5)
    plate = throat_plate_height(a)
    masks = _masks(a)
    d = deg(a)
    for r, row in enumerate(rows):
        c = color(a, row.group)
        for k, kind in enumerate(("displacement", "velocity", "acceleration")):
            ax = axes[r, k]
            factor, prefix = scale_of(np.concatenate([values[k] for _, *values in row.series]))
            if k == 0:
                factor, prefix = 1.0, ""  # positions keep their unit (mm, deg)
            for s, (label, *values) in enumerate(row.series):
                ax.plot(d, closed(a, factor * values[k]), color=c, lw=1.4, ls=("-", "--")[s % 2],
                        label=label if len(row.series) > 1 else None)
            for mask, mc, text in masks:
                shade(ax, a, mask, mc, text if r == 0 and k == 0 else None)
            if k == 0 and plate is not None and row.component == "y" and row.role in (NEEDLE_EYE, FEED_DOG):
                ax.axhline(plate * MM, color="k", lw=1, ls="--", label="throat plate")
            if k > 0:
                ax.axhline(0, color="0.5", lw=0.6)
            if len(row.series) > 1 and k == 0:
                ax.legend(fontsize=7, loc="best")
            ax.set_ylabel(f"{kind} ({prefix}{row.units[k]})", fontsize=9)
            ax.set_title(row.title, fontsize=9, color=c, y=1.0)
            ax.yaxis.set_major_locator(MaxNLocator(5, steps=[1, 2, 2.5, 5, 10]))
            ax.ticklabel_format(axis="y", style="plain", useOffset=False)  # no "1e4" offsets: the power is in the label
            ax.tick_params(labelsize=8)
            angle_grid(ax, bottom=r == n - 1, step=90)
    handles, labels = [], []
    for ax in axes.ravel():
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if lab in ("throat plate",) or any(lab == m[2] for m in masks):
                if lab not in labels:
                    handles.append(h)
                    labels.append(lab)
    if labels:
        fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=9, frameon=True,
                   bbox_to_anchor=(0.5, 0.05 / fig.get_size_inches()[1]))
    suptitle(fig, title(a, "displacement, velocity and acceleration against the shaft angle"))
    return rows

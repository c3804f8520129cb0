"""Paths of points in the machine's plane: every role-tagged point (needle eye, thread eye, feed dog, ...), or
every named point of a group without roles; and the feed-dog paths for a range of stitch lengths, for each group
that has a feed (a feed dog, a throat plate and a stitch regulator by role)."""
from __future__ import annotations

import math

import numpy as np

from sewgen.errors import ParameterError
from sewgen.machine.feed import dog_travel, has_feed, plate_height, regulator_angle
from sewgen.roles import FEED_DOG, STITCH_REGULATOR
from sewgen.report.plots.common import (AT_THE_PLATE, DPI, MM, angle_labels, axis_name, closed, color, feed_groups,
    offset, place, pretty, role_point, role_points, suptitle, throat_plate_height, title)
from sewgen.roles import HOOK_POINT, KNIFE_EDGE, LOWER_KNIFE_EDGE, LOWER_LOOPER_TIP, NEEDLE_POINT, UPPER_LOOPER_TIP
from sewgen.machine.parts import role_param

#: Points that work at the needle: their panels show the needle's centre line (when drawn in the same plane).
AT_THE_NEEDLE = (HOOK_POINT, LOWER_LOOPER_TIP, UPPER_LOOPER_TIP)

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


#: Width (in) of a trajectory panel's axes for a path as wide as it is high; a narrower path (the needle eye's
#: straight stroke) gets a narrower panel, down to :data:`_MIN_RATIO` of it, so no panel is mostly empty.
_PANEL_W, _GAP, _MIN_RATIO = 3.1, 0.85, 0.42


def _column_ratios(a) -> list:
    """Width of each column of trajectory panels, relative to :data:`_PANEL_W`: the widest path's width over
    its height (at least :data:`_MIN_RATIO`, at most 1)."""
    panels = path_panels(a)
    n = max(len(panels), 1)
    cols = min(n, _NCOL)
    ratios = [_MIN_RATIO] * cols
    for k, (g, pts) in enumerate(panels):
        fa = a.groups[g.name]
        xs = np.concatenate([fa.motion.point(name).x for name, _ in pts])
        ys = np.concatenate([fa.motion.point(name).y for name, _ in pts])
        aspect = (np.ptp(xs) + 0.2 * np.ptp(ys)) / max(np.ptp(ys), 1e-12)
        ratios[k % cols] = max(ratios[k % cols], min(1.0, 1.4 * aspect))
    return ratios if panels else [1.0]


def trajectories_size(a):
    n = max(len(path_panels(a)), 1)
    rows = math.ceil(n / _NCOL)
    ratios = _column_ratios(a)
    width = max(1.1 + _PANEL_W * sum(ratios) + _GAP * (len(ratios) - 1), 6.0)
    return (round(width * DPI) / DPI, 0.9 + 5.35 * rows)  # whole pixels: the PNG is exactly this size


def draw_trajectories(fig, a):
    """Paths (mm) of the role-tagged points (a group without roles: all its points), the throat plate beside the
    points that work at it; returns {"group.point": (x, y)}. A panel is as wide as its paths need (the needle
    eye's straight stroke gets a narrow one)."""
    panels = path_panels(a)
    n = max(len(panels), 1)
    rows, cols = math.ceil(n / _NCOL), min(n, _NCOL)
    ratios = _column_ratios(a)
    axes = place(fig, rows, cols, left=0.8, right=0.3, top=0.55, bottom=1.2, wspace=_GAP, hspace=1.6,
                 width_ratios=ratios).ravel()
    plate = throat_plate_height(a)
    data = {}
    for ax in axes[len(panels):]:
        ax.set_visible(False)
    for ax, (g, pts) in zip(axes, panels):
        fa, c = a.groups[g.name], color(a, g)
        styles = ("-", "--", "-.", ":")
        dx, dy = offset(g)
        for k, (name, role) in enumerate(pts):
            p = fa.motion.point(name)
            x, y = (p.x + dx) * MM, (p.y + dy) * MM
            data[f"{g.name}.{name}"] = (x, y)
            ax.plot(closed(a, x), closed(a, y), color=c, lw=1.5, ls=styles[k % 4],
                    label=f"{pretty(name)} path" if len(pts) > 1 else None, gid=f"{g.name}.{name}")
        roles = {role for _, role in pts}
        gn, npt = role_point(a, NEEDLE_POINT)
        if gn is not None and roles & set(AT_THE_NEEDLE) and axis_name(gn) == axis_name(g):
            p = a.groups[gn.name].motion.point(npt)
            line = float(np.mean(p.x + offset(gn)[0])) * MM
            ax.axvline(line, color="0.4", lw=1, ls=":", label=f"needle's centre line, {axis_name(g)} = {line:.4g} mm")
        if plate is not None and roles & set(AT_THE_PLATE + AT_THE_NEEDLE):
            ax.axhline(plate * MM, color="k", lw=1, ls="--", label=f"throat plate, y = {plate * MM:g} mm")
        d = g.mechanism.description
        if KNIFE_EDGE in roles and d.has_role(LOWER_KNIFE_EDGE):  # the fixed knife the edge cuts against
            lower = (role_param(g, LOWER_KNIFE_EDGE) + dy) * MM
            ax.axhline(lower, color="tab:red", lw=1, ls="-.", label=f"lower knife's edge, y = {lower:.4g} mm")
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
        for name, _ in pts:  # after the limits: labels that would overlap are left out
            angle_labels(ax, a, *data[f"{g.name}.{name}"], size=6.5)
        ax.set_autoscale_on(False)
        head = pretty(pts[0][1]) if len(pts) == 1 and pts[0][1] else "named points"
        if len(pts) == 1 and pts[0][1] and pts[0][0] != pts[0][1]:  # the point's own name too (seed 003's F, G)
            head += f" ({pts[0][0]})"
        ax.set_title(f"{g.name}: {head}", fontsize=10, color=c, y=1.0)
        ax.set(xlabel=f"{axis_name(g)} (mm{', along the main shaft' if axis_name(g) == 'z' else ''})", ylabel="y (mm)")
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[1]:  # below the axes: never over a path or its labels
            ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), fontsize=7, framealpha=0.8)
    planes = sorted({axis_name(g) for g, _ in panels})
    where = "paths in the machine's plane" if planes == ["x"] else "paths in the machine's x–y and z–y planes"
    suptitle(fig, title(a, f"{where} (labels: shaft angle φ)"))
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
    return (13.0, 0.6 + 6.0 * max(len(feed_groups(a)), 1))


def _arrows(ax, x, y, color, count=2):
    """Arrowheads along a closed path in its direction of travel: at its highest and lowest points (more with
    ``count`` > 2, evenly between)."""
    n = len(x)
    if n < 4:
        return
    picks = [int(np.argmax(y)), int(np.argmin(y))]
    picks += [int(k * n / count) for k in range(2, count)]
    step = max(1, n // 90)  # a few degrees of travel
    for i in picks:
        j = (i + step) % n
        if math.hypot(x[j] - x[i], y[j] - y[i]) < 1e-9:
            continue
        ax.annotate("", xy=(x[j], y[j]), xytext=(x[i], y[i]),
                    arrowprops=dict(arrowstyle="-|>", color=color, lw=1.2, mutation_scale=13, shrinkA=0, shrinkB=0))


def draw_feed_dog_stitches(fig, a):
    """Feed-dog paths (mm) for stitch lengths 0 to 4 mm and reverse, the stitch regulator set for each (seed 001
    §五): for each group with a feed, forward feed in one panel and reverse feed beside it, the same scale, with
    arrows in the dog's direction of travel; returns {stitch mm: (x, y)} of the first such group (empty without)."""
    from matplotlib import colormaps

    groups = feed_groups(a)
    axes = place(fig, max(len(groups), 1), 2, left=0.9, right=0.3, top=0.85, bottom=1.9, wspace=0.9,
                 hspace=2.2)
    out = {}
    if not groups:
        for ax in axes.ravel():
            ax.set_axis_off()
        axes[0, 0].text(0.5, 0.5, "no group with a feed dog, a throat plate and a stitch regulator", ha="center",
                        transform=axes[0, 0].transAxes)
        return out
    cmap = colormaps["coolwarm"]
    forward = [mm for mm in STITCHES_MM if mm >= 0]
    reverse = [0.0] + [mm for mm in STITCHES_MM if mm < 0]
    for row, g in zip(axes, groups):
        mech, params, fa = g.mechanism, g.params or None, a.groups[g.name]
        d = mech.description
        dog, reg = d.role_name(FEED_DOG), d.role_name(STITCH_REGULATOR)
        plate = plate_height(mech, params)
        data, beyond = {}, []
        for mm in STITCHES_MM:
            try:
                angle = regulator_angle(mech, mm * 1e-3, params=params)
            except ParameterError:  # beyond this regulator's range: said under the panel
                beyond.append(mm)
                continue
            mo = mech.solve(fa.motion.phi, speed=fa.motion.omega, params=params, held={reg: angle})
            data[mm] = (mo.point(dog).x * MM, mo.point(dog).y * MM, angle)
        for ax, family, text in ((row[0], forward, "forward stitches"), (row[1], reverse, "reverse stitches")):
            if any(mm in beyond for mm in family):
                ax.text(0.02, 0.02, "beyond the regulator's range: " + ", ".join(f"{mm:+.0f} mm" for mm in family
                                                                                  if mm in beyond),
                        transform=ax.transAxes, fontsize=8, color="0.3")
            for mm in family:
                if mm not in data:
                    continue
                x, y, angle = data[mm]
                c = cmap(0.5 + mm / 9.0) if mm else "0.55"
                ax.plot(closed(a, x), closed(a, y), lw=1.5, color=c,
                        label=f"{mm:+.0f} mm ({pretty(reg)} {round(math.degrees(angle), 1) + 0.0:+.1f}°)")
                if mm:
                    _arrows(ax, x, y, c)
            ax.axhline(plate * MM, color="k", lw=1, ls="--", label=f"throat plate, y = {plate * MM:g} mm")
            xs = np.concatenate([v[0] for v in data.values()])  # both panels on one scale
            ys = np.concatenate([v[1] for v in data.values()] + [[plate * MM]])
            pad = 0.08 * max(np.ptp(xs), np.ptp(ys))
            ax.set(xlim=(xs.min() - pad, xs.max() + pad), ylim=(ys.min() - pad, ys.max() + pad))
            ax.set_aspect("equal", adjustable="box")
            ax.grid(alpha=0.3)
            ax.set(xlabel="x (mm, + = forward feed)", ylabel="y (mm)")
            ax.set_title(f"{g.name}: {pretty(dog)}, {text} (arrows: direction of travel)", y=1.0, fontsize=10)
            ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2,
                      title="stitch length", title_fontsize=8)
        out = out or {mm: (x, y) for mm, (x, y, _) in data.items()}
    suptitle(fig, title(a, "feed-dog paths for stitch lengths 0 to 4 mm and reverse"))
    return out

"""Pictures of a whole-machine analysis for ``sewgen analyze MACHINE --out DIR``, drawn from the mechanisms'
descriptions and roles — never from a catalog name — so a machine of the user's own gets the same pictures.

One function per figure, ``name(analysis, path) -> Path``, taking a :class:`sewgen.machine.MachineAnalysis`
and writing one PNG; beside each a ``draw_<name>(fig, analysis)`` that draws onto a given figure (for tests
and notebooks; :func:`figure_size` gives the size the PNG uses). :func:`machine_gif` animates the machine over
the sweep and :func:`draw_machine` draws one position of it; :func:`write_all` writes everything. Figures are
``matplotlib.figure.Figure`` objects on the Agg canvas: nothing here touches pyplot or a caller's backend.
Lengths are drawn in mm; abscissae are the machine's shaft angle φ.

Modules, one job each: :mod:`.canvas` (the Agg canvas, its plain text drawn from cached whole-string bitmaps),
:mod:`.common` (figures, shaft-angle axes, group colours, role look-ups),
:mod:`.geometry` (a mechanism's drawing from its description and the anchors kernel), :mod:`.drawing` (linkages
on axes), :mod:`.animation` (the machine's panels and the GIF), :mod:`.background` (a forked process that writes the
GIF and shares the PNGs), :mod:`.paths` (trajectories, feed-dog stitch
family), :mod:`.curves` (motion against the shaft angle), :mod:`.reactions` (bearing and joint polars, torque,
shaking force and moments), :mod:`.cycle` (the stitch-formation cycle diagram) and :mod:`.thread` (the thread's
supply, demand and slack) for a machine with a ``[stitch]`` table.
"""
from __future__ import annotations

import math
from pathlib import Path

from sewgen.report.plots.animation import (GIF_DPI, GIF_FPS, GIF_WIDTH, MachineView, draw_machine, machine_gif,
    machine_linkages)
from sewgen.report.plots.background import can_fork, start_shared
from sewgen.report.plots.common import (DPI, PALETTE, feed_groups, import_drawing, new_figure, render,
    throat_plate_height)
from sewgen.report.plots.curves import draw_motion, motion_rows, motion_size
from sewgen.report.plots.cycle import cycle_size, draw_cycle, draw_cycle_timing, write_timing_plots
from sewgen.report.plots.geometry import Linkage, linkage, linkage_of
from sewgen.report.plots.paths import (STITCHES_MM, draw_feed_dog_stitches, draw_trajectories, path_panels,
    stitches_size, trajectories_size)
from sewgen.report.plots.reactions import (draw_bearings_polar, draw_joint_reactions_polar, draw_shaking, draw_torque,
    joints_size, main_joints)
from sewgen.report.plots.thread import draw_thread, draw_thread_timing, thread_size

#: Sizes (inches) of the figures whose size does not depend on the machine; :func:`figure_size` gives all.
SIZES = {"bearings_polar.png": (12.0, 6.6), "torque.png": (11.0, 6.2), "shaking.png": (13.0, 7.0)}
_SIZED = {"trajectories.png": trajectories_size, "feed_dog_stitches.png": stitches_size, "motion.png": motion_size,
          "joint_reactions_polar.png": joints_size,
          "cycle_diagram.png": lambda a: cycle_size(a.machine),
          "thread_control.png": lambda a: thread_size(a.machine)}


def figure_size(name: str, analysis) -> tuple:
    """The size (inches) of figure ``name`` for ``analysis``: a PNG is this times :data:`DPI` pixels."""
    return _SIZED[name](analysis) if name in _SIZED else SIZES[name]


def _png(name, draw):
    def make(analysis, path):
        return render(draw, analysis, path, figure_size(name, analysis))

    make.__name__ = Path(name).stem
    make.__doc__ = f"Write {name}: {draw.__doc__.splitlines()[0] if draw.__doc__ else ''}"
    return make


trajectories = _png("trajectories.png", draw_trajectories)
feed_dog_stitches = _png("feed_dog_stitches.png", draw_feed_dog_stitches)
motion = _png("motion.png", draw_motion)
bearings_polar = _png("bearings_polar.png", draw_bearings_polar)
joint_reactions_polar = _png("joint_reactions_polar.png", draw_joint_reactions_polar)
torque = _png("torque.png", draw_torque)
shaking = _png("shaking.png", draw_shaking)
cycle_diagram = _png("cycle_diagram.png", draw_cycle)
thread_control = _png("thread_control.png", draw_thread)

FIGURES = (("trajectories.png", trajectories), ("feed_dog_stitches.png", feed_dog_stitches), ("motion.png", motion),
           ("bearings_polar.png", bearings_polar), ("joint_reactions_polar.png", joint_reactions_polar),
           ("torque.png", torque), ("shaking.png", shaking), ("cycle_diagram.png", cycle_diagram),
           ("thread_control.png", thread_control))
GIF = "machine.gif"
#: Figures drawn only for some machines: figure -> whether ``analysis`` has what it shows.
APPLIES = {"feed_dog_stitches.png": lambda analysis: bool(feed_groups(analysis)),
           "cycle_diagram.png": lambda analysis: getattr(analysis.machine, "stitch", None) is not None,
           "thread_control.png": lambda analysis: getattr(analysis.machine, "stitch", None) is not None
           and getattr(analysis.machine, "thread", None) is not None}


def figures_for(analysis) -> list[tuple]:
    """The (name, writer) pairs of :data:`FIGURES` that apply to ``analysis`` (no feed-dog figure without a feed)."""
    return [(name, make) for name, make in FIGURES if APPLIES.get(name, lambda a: True)(analysis)]


class PendingPlots:
    """Figures and GIF being written (:func:`start_all`): :meth:`finish` draws this process's share and returns
    the paths once every file is written; :meth:`cancel` stops the forked child (after an error elsewhere)."""

    def __init__(self, run, paths, figures, total, report):
        self._run, self.paths, self._figures, self._total, self._report = run, paths, figures, total, report
        self._done = 0

    def finish(self) -> list[Path]:
        figures, total, report = self._figures, self._total, self._report

        def on_start(k):
            report(figures[k][0], self._done, total)

        def on_written(k):
            self._done += 1

        def on_progress(message, i, n):
            report(message, min(self._done, total - 1), total)

        self._run.finish(on_start=on_start, on_written=on_written, on_progress=on_progress)
        return list(self.paths)

    def cancel(self) -> None:
        self._run.cancel()


def start_all(analysis, folder, progress=None, gif: bool = True, parallel: bool | None = None,
              curves=None) -> PendingPlots:
    """Start writing every figure (and the GIF unless ``gif=False``) into ``folder``; returns a
    :class:`PendingPlots` whose ``finish()`` completes them. Where that is safe
    (:func:`~sewgen.report.plots.background.can_fork`; ``parallel=False``: never) a process forked here writes the GIF
    and then shares the figures with this one (:func:`~sewgen.report.plots.background.start_shared`), so the caller
    can write its tables in the meantime. Arguments as :func:`write_all`."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    if curves is None:
        refine = getattr(analysis, "refined", None)
        curves = refine() if refine is not None else analysis
    figures = figures_for(analysis)
    paths = [folder / name for name, _ in figures] + ([folder / GIF] if gif else [])
    figures = _big_ends_first(figures, curves)
    total = len(figures) + bool(gif)
    report = progress or (lambda message, done, total: None)
    links = machine_linkages(analysis) if gif else None  # built here: the geometry's errors raise here
    jobs = [lambda _progress, make=make, name=name: make(curves, folder / name) for name, make in figures]
    first = (lambda progress: machine_gif(analysis, folder / GIF, progress, links=links)) if gif else None
    parallel = can_fork() if parallel is None else parallel
    import_drawing()  # before the fork: the child inherits the imports and the strings kept on disk
    from sewgen.report.plots import canvas

    canvas.load()
    run = start_shared(jobs, first, parallel=parallel, after=canvas.save)
    return PendingPlots(run, paths, figures, total, report)


def _big_ends_first(figures, analysis) -> list:
    """``figures`` ordered for two processes taking them from the two ends (sewgen.report.plots.background): the
    costliest at the ends, the cheapest in the middle where the two meet, so neither waits long for the other's
    last figure. A figure's cost is estimated by its area (its axes, texts and pixels grow with it: on JB1-3
    the motion figure, the largest, takes three times the torque figure's time)."""
    ranked = sorted(figures, key=lambda f: -math.prod(figure_size(f[0], analysis)))
    front, back = ranked[0::2], ranked[1::2]
    return front + back[::-1]


def write_all(analysis, folder, progress=None, gif: bool = True, parallel: bool | None = None,
              curves=None) -> list[Path]:
    """Every figure (and the GIF unless ``gif=False``) into ``folder``; returns the paths written.
    ``progress(message, done, total)`` is called before each figure (done = files finished so far, total =
    files) and every 8 frames of the GIF. Where that is safe (:func:`~sewgen.report.plots.background.can_fork`;
    ``parallel=False``: never) a forked process writes the GIF and then shares the figures with this one
    (:func:`~sewgen.report.plots.background.start_shared`), so two figures may be in progress at once.

    The figures are drawn from ``curves`` (default: ``analysis.refined()``, the same analysis every 1° when it
    was run in coarser steps, so no curve is a jagged polyline); the GIF has one frame per position of
    ``analysis``."""
    return start_all(analysis, folder, progress, gif, parallel, curves).finish()


__all__ = ["DPI", "FIGURES", "GIF", "GIF_DPI", "GIF_FPS", "GIF_WIDTH", "PALETTE", "SIZES", "STITCHES_MM",
           "APPLIES", "Linkage", "MachineView", "PendingPlots", "start_all", "bearings_polar", "can_fork",
           "draw_bearings_polar",
           "draw_feed_dog_stitches", "draw_joint_reactions_polar", "draw_machine", "draw_motion", "draw_shaking",
           "draw_torque", "draw_trajectories", "feed_dog_stitches", "figure_size", "figures_for", "joint_reactions_polar", "linkage",
           "linkage_of", "machine_gif", "machine_linkages", "main_joints", "motion", "motion_rows", "new_figure",
           "path_panels", "shaking", "throat_plate_height", "torque", "trajectories", "write_all",
           "cycle_diagram", "thread_control", "cycle_size", "thread_size", "draw_cycle", "draw_cycle_timing",
           "draw_thread", "draw_thread_timing", "write_timing_plots"]

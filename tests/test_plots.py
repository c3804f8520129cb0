"""sewgen.report.plots: every file written and readable, what is drawn is the analysis, and the drawing comes from the
mechanism's description (anchors and roles), so a user's mechanism and machine get the same pictures.

On the built-in JB1-3: the files, the GIF's frames, the needle-eye path, rigid bodies, revolute anchors that
coincide, sliders on their guides, the feed cam touching both faces of its fork, the stitch family. On a user's
offset crank-slider (declared here, compiled into a temporary cache): the same checks of the generic drawing,
and a one-group machine of it gets every PNG and a GIF of one frame per position. And no plotting module names
a catalog mechanism or one of its parts.
"""
from __future__ import annotations

import math
import os
import re
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import sewgen
from sewgen.report import plots
from sewgen.machine.feed import has_feed
from sewgen.machine.assembly import Group, Machine, MachineAnalysis, Shaft, ShaftMass, load_machine
from sewgen.report.plots import animation
from sewgen.roles import FEED_DOG, HOOK_POINT, NEEDLE_EYE

pytestmark = [pytest.mark.c, pytest.mark.plots, pytest.mark.derive]

ROOT = Path(__file__).resolve().parent.parent
TOL = 1e-9  # mm: anchors that a solved loop makes coincide


@pytest.fixture(scope="module")
def analysis():
    return load_machine("jb1-3").analyze()  # 72 positions, 5° apart


@pytest.fixture(scope="module")
def written(analysis, tmp_path_factory):
    calls = []
    files = plots.write_all(analysis, tmp_path_factory.mktemp("plots"), progress=lambda *c: calls.append(c))
    return files, calls


def _role_group(a, role):
    g = next(g for g in a.machine.groups if g.mechanism.description.has_role(role))
    return g, g.mechanism.description.role_name(role)


def test_write_all_writes_every_file(written, analysis):
    files, calls = written
    names = [f.name for f in files]
    assert names == [name for name, _ in plots.FIGURES] + [plots.GIF]
    for f in files:
        assert f.is_file() and f.stat().st_size > 20_000, f
    for name, _ in plots.FIGURES:
        with Image.open(files[names.index(name)]) as im:
            im.verify()
        with Image.open(files[names.index(name)]) as im:
            assert im.format == "PNG"
            assert im.size == tuple(round(s * plots.DPI) for s in plots.figure_size(name, analysis))
    # progress: once before each figure, during the GIF every 8 frames; done counts the files finished so far
    # (the GIF and the figures are shared by two processes, so their reports interleave)
    total = len(files)
    assert all(c[2] == total for c in calls)
    figure_calls = [c[0] for c in calls if not c[0].startswith(plots.GIF)]
    assert sorted(figure_calls) == sorted(name for name, _ in plots.FIGURES)
    gif_calls = [c for c in calls if c[0].startswith(plots.GIF)]
    assert len(gif_calls) == 9 and all(0 <= c[1] < total for c in gif_calls)
    dones = [c[1] for c in calls]
    assert dones == sorted(dones) and dones[0] == 0 and dones[-1] < total


def test_gif_has_one_frame_per_shaft_angle(written, analysis):
    files, _ = written
    with Image.open(files[-1]) as im:
        assert im.format == "GIF"
        assert im.n_frames == len(analysis.phi) == 72
        assert im.size[0] <= round(plots.GIF_WIDTH * plots.GIF_DPI)
        assert im.info["duration"] == 1000 // plots.GIF_FPS
        frames = []
        for k in (0, 18):
            im.seek(k)
            frames.append(np.asarray(im.convert("RGB")))
    assert (frames[0] != frames[1]).any(axis=-1).mean() > 0.005  # the mechanisms move
    assert files[-1].stat().st_size < 900_000


def test_machine_view_has_a_panel_per_group_and_the_stitch_zone(analysis):
    """Groups never share a panel (no knot of linkages at different axial positions); with a throat plate the
    stitch-forming zone is one more panel holding the needle's, the hook point's and the feed dog's bodies; the
    readout says by role what they do."""
    view = plots.draw_machine(analysis, index=0)
    groups = analysis.machine.groups
    assert len(view.axes) == len(groups) + 1
    boxes = [ax.get_position() for ax in view.axes]
    for i in range(len(boxes)):
        for j in range(i):
            assert not boxes[i].overlaps(boxes[j]) or boxes[i].x1 <= boxes[j].x0 or boxes[j].x1 <= boxes[i].x0
    for ax in view.axes:  # equal aspect: a millimetre is as long across as up
        (x0, y0), (x1, y1) = ax.transData.transform([(0, 0), (10, 10)])
        assert abs((x1 - x0) - (y1 - y0)) < 0.02 * abs(x1 - x0)
    zone = view.panels[-1].parts
    assert {p.lk.group for p in zone} == {_role_group(analysis, r)[0].name for r in (NEEDLE_EYE, HOOK_POINT, FEED_DOG)}
    g, eye = _role_group(analysis, NEEDLE_EYE)
    plate = plots.throat_plate_height(analysis)
    y = analysis.groups[g.name].motion.point(eye).y
    low, high = int(np.argmin(y)), int(np.argmax(y))
    assert y[low] < plate < y[high]
    assert "needle in the cloth" in animation.status(analysis, low)
    assert "needle out" in animation.status(analysis, high)


def test_trajectory_figure_draws_the_needle_eye_path(analysis):
    fig = plots.new_figure(plots.figure_size("trajectories.png", analysis))
    data = plots.draw_trajectories(fig, analysis)
    g, eye_name = _role_group(analysis, NEEDLE_EYE)
    key = f"{g.name}.{eye_name}"
    line = next(ln for ax in fig.axes for ln in ax.get_lines() if ln.get_gid() == key)
    eye = analysis.groups[g.name].motion.point(eye_name)
    x, y = line.get_xdata(), line.get_ydata()
    assert len(y) == len(analysis.phi) + 1  # a closed path: the first point repeated
    np.testing.assert_allclose(x[:-1], eye.x * 1e3)
    np.testing.assert_allclose(y[:-1], eye.y * 1e3)
    assert (x[-1], y[-1]) == (x[0], y[0])
    np.testing.assert_allclose(data[key][1], eye.y * 1e3)
    # and it is the needle eye of a 16.7 mm crank: 33.4 mm stroke on the line x = offset = 0, top at 90°
    assert np.ptp(y) == pytest.approx(33.4, abs=1e-9)
    assert np.abs(x).max() < 1e-9
    assert math.degrees(analysis.phi[int(np.argmax(y[:-1]))]) == pytest.approx(90.0)


def _check_drawing(mech, lk, motion):
    """The generic drawing of ``mech`` is its kinematics: revolute anchors coincide, bodies are rigid, the named
    points are the motion's, slider blocks sit on their guides and move along them."""
    d = mech.description
    revolutes = [j.name for j in d.joints if j.kind == "revolute"]
    assert revolutes
    for name in revolutes:
        sides = list(lk.joints[name].values())
        assert len(sides) == 2, name
        np.testing.assert_allclose(sides[0], sides[1], atol=TOL, rtol=0, err_msg=name)
    for body, outline in lk.bodies.items():  # every pair of vertices keeps its distance
        dist = np.hypot(*(outline[:, :, None, :] - outline[:, None, :, :]).transpose(3, 0, 1, 2))
        np.testing.assert_allclose(dist, np.broadcast_to(dist[:1], dist.shape), atol=1e-9, err_msg=body)
    for name in d.points:
        p = motion.point(name.name)
        np.testing.assert_allclose(lk.points[name.name], np.column_stack([p.x, p.y]) * 1e3, atol=1e-12)
    for s in lk.sliders:
        guide = next(gd for gd in lk.guides if gd.joint == s.joint)
        a, b = guide.ends[:, 0], guide.ends[:, 1]
        u = (b - a) / np.hypot(*(b - a).T)[:, None]
        rel = s.center - a
        np.testing.assert_allclose(u[:, 0] * rel[:, 1] - u[:, 1] * rel[:, 0], 0.0, atol=TOL)  # on the line
        along = np.einsum("nc,nc->n", rel, u)
        assert (along > 0).all() and (along < np.hypot(*(b - a).T)).all()  # within the drawn travel
        np.testing.assert_allclose(np.abs(np.einsum("nc,nc->n", s.direction, u)), 1.0, atol=1e-12)
        corners = s.corners()
        np.testing.assert_allclose(corners.mean(axis=1), s.center, atol=TOL)


def test_catalog_linkages_are_their_kinematics(analysis):
    """Every JB1-3 group drawn from its anchors: the generic checks, and the feed cam between both faces of its
    fork (the declared face and the yoke's other face, constant breadth apart)."""
    cams = 0
    for g in analysis.machine.groups:
        fa = analysis.groups[g.name]
        lk = plots.linkage(g, fa)
        assert lk.bodies, g.name
        _check_drawing(g.mechanism, lk, fa.motion)
        for body, prof in lk.cams.items():
            faces = [gd for gd in lk.guides if gd.kind == "face"]
            assert len(faces) == 2
            for gd in faces:
                a, b = gd.ends[:, 0], gd.ends[:, 1]
                u = (b - a) / np.hypot(*(b - a).T)[:, None]
                across = (prof[..., 1] - a[:, None, 1]) * u[:, None, 0] - (prof[..., 0] - a[:, None, 0]) * u[:, None, 1]
                touch = np.where(np.abs(across.max(axis=1)) < np.abs(across.min(axis=1)), across.max(axis=1),
                                 across.min(axis=1))
                np.testing.assert_allclose(touch, 0.0, atol=0.03)  # the arcs are drawn with 12 points each
            cams += 1
    assert cams == 1


def test_stitch_family_travels_the_stitch_above_the_plate(analysis):
    """The feed-dog family: each plotted path moves the dog by its stitch while above the throat plate (plate
    crossings by linear interpolation on the 5° sweep, so to ~0.05 mm), zero stitch hardly moves it, and the
    reverse paths span the same width as the forward ones."""
    fig = plots.new_figure(plots.figure_size("feed_dog_stitches.png", analysis))
    data = plots.draw_feed_dog_stitches(fig, analysis)
    plate = plots.throat_plate_height(analysis) * 1e3
    assert set(data) == set(plots.STITCHES_MM)
    for mm, (x, y) in data.items():
        z = y - plate
        up = int(np.flatnonzero((z < 0) & (np.roll(z, -1) >= 0))[0])
        down = int(np.flatnonzero((z >= 0) & (np.roll(z, -1) < 0))[0])

        def cross(i):
            j = (i + 1) % len(z)
            t = z[i] / (z[i] - z[j])
            return x[i] + t * (x[j] - x[i])

        assert abs(cross(down) - cross(up) - mm) < 0.05, (mm, cross(down) - cross(up))
    assert np.ptp(data[0.0][0]) < 0.05
    assert abs(np.ptp(data[4.0][0]) - np.ptp(data[-4.0][0])) < 0.1


def test_main_joints_are_the_most_loaded(analysis):
    for g in analysis.machine.groups:
        fa = analysis.groups[g.name]
        names = plots.main_joints(fa)
        peaks = {n: fa.reaction(n).magnitude.max() for n in fa.reaction_names}
        assert len(names) == min(3, len(peaks))
        assert [peaks[n] for n in names] == sorted(peaks.values(), reverse=True)[:len(names)]


# -- a user's mechanism and machine ----------------------------------------------------------------------------

def declare_offset_slider():
    """An offset crank-slider on a tilted guide with a point off the slider's axis, and masses."""
    import sympy as sp

    from sewgen.derive.model import Mechanism

    m = Mechanism("plot_offset_slider", "offset crank-slider on a tilted guide (a user's mechanism, for plots)")
    r = m.length("crank", "12 mm", "crank radius")
    rod = m.length("rod", "45 mm", "connecting rod, pin to pin")
    e = m.length("offset", "7 mm", "guide offset from the crank axis", signed=True)
    crank = m.driven("crank", pivot=m.ground.at(0, 0), doc="crank", mass="20 g", com=("3 mm", "0 mm"),
                     inertia="1e-6 kg*m**2")
    link = m.link("link", doc="connecting rod", guess="-80 deg", mass="10 g", com=(rod / 2, 0),
                  inertia="2e-6 kg*m**2")
    block = m.slider("block", guide=m.ground.line(at=(e, 0), angle=-sp.pi * 100 / 180), doc="slider",
                     guess="40 mm", mass="30 g", com=("5 mm", "0 mm"), inertia="1e-6 kg*m**2")
    m.revolute(crank.at(r, 0), link.at(0, 0), name="pin")
    m.revolute(link.at(rod, 0), block.at(0, 0), name="wrist")
    m.point("tool", block.at("20 mm", "4 mm"), "the tool on the slider")
    return m


@pytest.fixture(scope="module")
def user_mech(cache):
    return sewgen.load(declare_offset_slider, cache_dir=cache)


def test_user_mechanism_drawn_from_its_description(user_mech):
    phi = sewgen.shaft_angles(5)
    motion = user_mech.solve(phi, speed=100.0)
    lk = plots.linkage_of(user_mech, motion)
    _check_drawing(user_mech, lk, motion)
    assert set(lk.bodies) == {"crank", "link", "block"}  # a bar for each, the block reaching to its tool
    assert [s.body for s in lk.sliders] == ["block"] and [gd.fixed for gd in lk.guides] == [True]
    assert lk.pivots.shape == (1, 2) and len(lk.circles) == 1 and lk.circles[0][1] == pytest.approx(12.0)
    assert lk.marks == ["tool"]
    np.testing.assert_allclose(lk.circles[0][0], [0.0, 0.0], atol=1e-12)


def user_machine(mech):
    group = Group("slider", mech, 0.3, {"crank": 0.01}, {}, {}, {}, [])
    shaft = Shaft(front=0.0, rear=0.1, inertia=1e-5, masses=[ShaftMass("core", 0.1, 0.0, 0.0, 0.05)])
    return Machine("User-1", "", 2 * math.pi * 10, math.radians(10.0), np.array([0.0, -9.81]), [group], shaft)


def test_user_machine_gets_every_picture(user_mech, tmp_path):
    a = user_machine(user_mech).analyze()
    assert isinstance(a, MachineAnalysis) and len(a.phi) == 36
    assert not has_feed(user_mech) and plots.throat_plate_height(a) is None
    files = plots.write_all(a, tmp_path)
    assert [f.name for f in files] == [name for name, _ in plots.figures_for(a)] + [plots.GIF]
    # no feed and no [stitch] table: every figure but the feed-dog family, the cycle diagram and the thread curves
    assert {name for name, _ in plots.FIGURES} - {f.name for f in files} == {
        "feed_dog_stitches.png", "cycle_diagram.png", "thread_control.png"}
    for f in files[:-1]:
        with Image.open(f) as im:
            assert im.format == "PNG" and im.size == tuple(round(s * plots.DPI) for s in
                                                           plots.figure_size(f.name, a))
        assert f.stat().st_size > 10_000, f
    with Image.open(files[-1]) as im:
        assert im.n_frames == len(a.phi)
    assert plots.path_panels(a)[0][1] == [("tool", None)]  # no roles: every named point
    assert [r.title for r in plots.motion_rows(a)] == ["slider: tool x, y"]
    view = plots.draw_machine(a)
    assert len(view.axes) == 1  # no throat plate: no stitch-forming zone


# -- nothing in the plots names the catalog ----------------------------------------------------------------------

#: Catalog mechanisms and parts the pictures once found by name. Identifiers that are no English word must not
#: appear at all; "feed" and "regulator" (words of the prose, and of sewgen.machine.feed.regulator_angle) must not
#: appear as names in a string: "feed", 'regulator', "x.regulator", "regulator.angle".
NAMES = ("needle_bar", "take_up", "hook_drive", "plate_y", "lower_shaft")
WORDS = ("feed", "regulator")


def test_plots_name_no_catalog_mechanism_or_part():
    sources = sorted((ROOT / "sewgen" / "report" / "plots").glob("*.py"))
    assert sources
    for path in sources:
        text = path.read_text()
        for word in NAMES:
            assert not re.search(rf"\b{word}\b", text), f"{path.relative_to(ROOT)} names {word}"
        code = re.sub(r'"""(?:.|\n)*?"""', "", text)
        code = re.sub(r"#.*", "", code)
        for word in WORDS:
            assert not re.search(rf"""["'.]{word}["'.]""", code), f"{path.relative_to(ROOT)} names {word!r}"


def _jobs(folder, n, fail_in_child=(), fail_always=()):
    """Jobs that each append their index to a log (a file: the child's writes must reach the parent)."""
    parent = os.getpid()
    log = folder / "log"

    def job(k):
        def run(_progress):
            if k in fail_always or (k in fail_in_child and os.getpid() != parent):
                raise ValueError(f"job {k}")
            with open(log, "a") as f:
                f.write(f"{k}\n")
        return run
    return [job(k) for k in range(n)], job(-1), log


@pytest.mark.skipif(not plots.can_fork(), reason="needs fork and two CPUs")
@pytest.mark.parametrize("fail_in_child", [(), (-1,), (5, 4), tuple(range(-1, 6))])
def test_shared_jobs_run_each_job_once_even_when_the_child_fails(tmp_path, fail_in_child):
    from sewgen.report.plots.background import run_shared

    jobs, first, log = _jobs(tmp_path, 6, fail_in_child)
    started, written = [], []
    run_shared(jobs, first, parallel=True, on_start=started.append, on_written=written.append,
               on_progress=lambda *a: None)
    assert sorted(int(x) for x in log.read_text().split()) == list(range(-1, 6))
    assert sorted(written) == list(range(-1, 6))
    assert sorted(set(started)) == list(range(6))


@pytest.mark.skipif(not plots.can_fork(), reason="needs fork and two CPUs")
def test_shared_jobs_raise_the_failure_here(tmp_path):
    from sewgen.report.plots.background import run_shared

    jobs, first, _ = _jobs(tmp_path, 4, fail_always=(3,))
    with pytest.raises(ValueError, match="job 3"):
        run_shared(jobs, first, parallel=True, on_start=lambda k: None, on_written=lambda k: None,
                   on_progress=lambda *a: None)


@pytest.mark.skipif(not plots.can_fork(), reason="needs fork and two CPUs")
def test_a_started_run_works_while_the_caller_does_and_cancels_cleanly(tmp_path):
    """sewgen analyze forks the plotting child before writing its tables (start_shared), then finishes the
    figures; after an error in the tables it cancels the child."""
    import multiprocessing
    import time

    from sewgen.report.plots.background import start_shared

    jobs, first, log = _jobs(tmp_path, 5)
    run = start_shared(jobs, first, parallel=True)
    deadline = time.monotonic() + 30
    while not log.exists() and time.monotonic() < deadline:  # the child works before finish() is called
        time.sleep(0.01)
    assert log.exists()
    written = []
    run.finish(on_start=lambda k: None, on_written=written.append, on_progress=lambda *a: None)
    assert sorted(int(x) for x in log.read_text().split()) == list(range(-1, 5))
    assert sorted(written) == list(range(-1, 5))

    slow = [lambda _p: time.sleep(30)] * 2
    run = start_shared(slow, slow[0], parallel=True)
    proc = run.child._proc
    t0 = time.monotonic()
    run.cancel()
    run.cancel()  # twice: a no-op
    assert time.monotonic() - t0 < 10 and not proc.is_alive() and proc not in multiprocessing.active_children()


def test_figures_are_scheduled_costliest_at_both_ends(analysis):
    """The two processes take figures from the two ends of the list: the largest (by area) come first at each
    end and the smallest meet in the middle."""
    import math

    from sewgen.report.plots import _big_ends_first

    order = _big_ends_first(plots.figures_for(analysis), analysis)
    assert sorted(n for n, _ in order) == sorted(n for n, _ in plots.figures_for(analysis))
    area = [math.prod(plots.figure_size(n, analysis)) for n, _ in order]
    k = area.index(min(area))
    assert area[:k + 1] == sorted(area[:k + 1], reverse=True) and area[k:] == sorted(area[k:])
    assert max(area[0], area[-1]) == max(area)


def _ink_box(canvas_cls, text_kw):
    """(x0, x1, y0, y1) pixel box of the ink of one text drawn alone on ``canvas_cls``."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(4, 2), dpi=100)
    canvas_cls(fig)
    fig.text(0.31, 0.43, **text_kw)
    fig.canvas.draw()
    ink = np.asarray(fig.canvas.buffer_rgba())[..., 0] < 250
    ys, xs = np.nonzero(ink)
    return xs.min(), xs.max(), ys.min(), ys.max()


@pytest.mark.parametrize("kw", [dict(s="shaft angle φ (deg)", fontsize=10),
                                dict(s="−180", fontsize=8, ha="right", va="center"),
                                dict(s="displacement (mm)", fontsize=9, rotation=90, va="bottom"),
                                dict(s="gyp 10³ deg/s²", fontsize=12, color="tab:red", alpha=0.5),
                                dict(s=" 1    9.95°  feed dog rises", fontsize=7, family="monospace")])
def test_cached_text_lands_where_matplotlib_draws_it(kw):
    """sewgen.report.plots.canvas draws plain text from whole-string bitmaps (speed); its ink covers the box
    matplotlib's own renderer inks, to a pixel, at 0° and 90°."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from sewgen.report.plots.canvas import TextCacheCanvas

    kw = dict(kw)
    s = kw.pop("s")
    ref = _ink_box(FigureCanvasAgg, dict(s=s, **kw))
    got = _ink_box(TextCacheCanvas, dict(s=s, **kw))
    got_again = _ink_box(TextCacheCanvas, dict(s=s, **kw))  # from the cache
    assert got == got_again
    assert all(abs(g - r) <= 1 for g, r in zip(got, ref)), (got, ref)


def test_cached_text_falls_back_on_matplotlib_where_its_internals_differ(monkeypatch):
    """A matplotlib whose renderer lacks what the text cache uses (its whole-string bitmap raises
    AttributeError) still gets every string drawn, by matplotlib itself, exactly where it draws it."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from sewgen.report.plots import canvas

    def missing(self, s, prop, antialiased):
        raise AttributeError("'RendererAgg' object has no attribute '_prepare_font'")

    kw = dict(s="a string not drawn before 12", fontsize=10)
    ref = _ink_box(FigureCanvasAgg, kw)
    monkeypatch.setattr(canvas, "_unsupported", False)
    monkeypatch.setattr(canvas.TextCacheRenderer, "_bitmap", missing)
    assert _ink_box(canvas.TextCacheCanvas, kw) == ref
    assert canvas._unsupported


@pytest.mark.skipif(not plots.can_fork(), reason="needs fork and two CPUs")
def test_shared_runs_call_after_in_each_process_the_child_first(tmp_path):
    """``after`` (the text cache's save) runs once in the child, once its share is done, and then once here."""
    from sewgen.report.plots.background import run_shared

    jobs, first, _ = _jobs(tmp_path, 4)
    log = tmp_path / "after"

    def after():
        with open(log, "a") as f:
            f.write(f"{os.getpid()}\n")

    run_shared(jobs, first, parallel=True, on_start=lambda k: None, on_written=lambda k: None,
               on_progress=lambda *a: None, after=after)
    pids = [int(x) for x in log.read_text().split()]
    assert len(pids) == 2 and pids[1] == os.getpid() and pids[0] != os.getpid()


def test_text_cache_is_kept_on_disk_between_runs(tmp_path, monkeypatch):
    """The whole-string bitmaps and measures go to $SEWGEN_CACHE/text (canvas.save) and come back in another
    run (canvas.load) under keys that do not depend on the process; a string drawn from the loaded cache lands
    where matplotlib draws it. A damaged file is an empty cache, not an error."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from sewgen.report.plots import canvas

    monkeypatch.setenv("SEWGEN_CACHE", str(tmp_path))
    monkeypatch.setattr(canvas, "_bitmaps", {})
    monkeypatch.setattr(canvas, "_extents", {})
    monkeypatch.setattr(canvas, "_loaded", (0, 0))
    kw = dict(s="a string kept between runs 417", fontsize=11, weight="bold")
    drawn = _ink_box(canvas.TextCacheCanvas, kw)
    assert any(key[0] == kw["s"] for key in canvas._bitmaps)
    canvas.save()
    path = canvas._cache_file()
    assert path.parent == tmp_path / "text" and path.is_file()
    # keys name the font file (never a per-process hash), so another process finds them
    key = next(key for key in canvas._bitmaps if key[0] == kw["s"])
    assert key[1].endswith(".ttf") and "Bold" in key[1]

    monkeypatch.setattr(canvas, "_bitmaps", {})
    monkeypatch.setattr(canvas, "_extents", {})
    canvas.load()
    assert key in canvas._bitmaps and len(canvas._extents) >= 1

    def no_rendering(self, *a, **k):
        raise AssertionError("rendered again although loaded from disk")

    monkeypatch.setattr(canvas.RendererAgg, "_prepare_font", no_rendering)
    assert _ink_box(canvas.TextCacheCanvas, kw) == drawn
    monkeypatch.undo()
    monkeypatch.setenv("SEWGEN_CACHE", str(tmp_path))
    ref = _ink_box(FigureCanvasAgg, kw)
    assert all(abs(g - r) <= 1 for g, r in zip(drawn, ref)), (drawn, ref)

    path.write_bytes(b"not a pickle")
    monkeypatch.setattr(canvas, "_bitmaps", {})
    monkeypatch.setattr(canvas, "_extents", {})
    canvas.load()
    assert canvas._bitmaps == {} and canvas._extents == {}


def test_text_cache_on_disk_stays_within_its_size(tmp_path, monkeypatch):
    """Runs meeting ever new strings (tick labels of other machines) never grow the file past CACHE_SIZE: a full
    file starts again from the strings of the process that saves."""
    import pickle

    from sewgen.report.plots import canvas

    monkeypatch.setenv("SEWGEN_CACHE", str(tmp_path))
    monkeypatch.setattr(canvas, "CACHE_SIZE", 6)
    for run in range(4):
        monkeypatch.setattr(canvas, "_bitmaps", {})
        monkeypatch.setattr(canvas, "_extents", {})
        monkeypatch.setattr(canvas, "_loaded", (0, 0))
        canvas.load()
        for k in range(2):
            _ink_box(canvas.TextCacheCanvas, dict(s=f"run {run} string {k}", fontsize=9))
        canvas.save()
        bitmaps, extents = pickle.loads(canvas._cache_file().read_bytes())
        assert len(bitmaps) <= 6 and len(extents) <= 6
        assert {f"run {run} string {k}" for k in range(2)} <= {key[0] for key in bitmaps}

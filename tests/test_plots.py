"""sewgen.plots on the built-in JB1-3 machine: every file written and readable, and what is drawn is the analysis."""
from __future__ import annotations

import math

import numpy as np
import pytest
from PIL import Image

from sewgen import plots
from sewgen.machine import load_machine


@pytest.fixture(scope="module")
def analysis():
    return load_machine("jb1-3").analyze()  # 72 positions, 5° apart


@pytest.fixture(scope="module")
def written(analysis, tmp_path_factory):
    calls = []
    files = plots.write_all(analysis, tmp_path_factory.mktemp("plots"), progress=lambda *c: calls.append(c))
    return files, calls


def test_write_all_writes_every_file(written):
    files, calls = written
    names = [f.name for f in files]
    assert names == [name for name, _ in plots.FIGURES] + [plots.GIF]
    for f in files:
        assert f.is_file() and f.stat().st_size > 0, f
    for name, _ in plots.FIGURES:
        with Image.open(files[names.index(name)]) as im:
            im.verify()
        with Image.open(files[names.index(name)]) as im:
            assert im.format == "PNG"
            assert im.size == tuple(round(s * plots.DPI) for s in plots.SIZES[name])
    # progress: once before each file, during the GIF every 8 frames; done counts files
    total = len(files)
    assert all(c[2] == total for c in calls)
    assert [c[0] for c in calls[:len(plots.FIGURES)]] == [name for name, _ in plots.FIGURES]
    gif_calls = [c for c in calls if c[0].startswith(plots.GIF)]
    assert len(gif_calls) == 9 and all(c[1] == total - 1 for c in gif_calls)


def test_gif_has_one_frame_per_shaft_angle(written, analysis):
    files, _ = written
    with Image.open(files[-1]) as im:
        assert im.format == "GIF"
        assert im.n_frames == len(analysis.phi) == 72
        assert im.size == tuple(round(s * plots.GIF_DPI) for s in plots.GIF_SIZE)
        assert im.info["duration"] == 1000 // plots.GIF_FPS
        frames = []
        for k in (0, 18):
            im.seek(k)
            frames.append(np.asarray(im.convert("RGB")))
    assert (frames[0] != frames[1]).any(axis=-1).mean() > 0.005  # the mechanisms move
    assert files[-1].stat().st_size < 600_000


def test_trajectory_figure_draws_the_needle_eye_path(analysis):
    fig = plots.new_figure(plots.SIZES["trajectories.png"])
    data = plots.draw_trajectories(fig, analysis)
    line = next(ln for ax in fig.axes for ln in ax.get_lines() if ln.get_gid() == "needle_eye")
    eye = analysis.groups["needle_bar"].motion.point("needle_eye")
    x, y = line.get_xdata(), line.get_ydata()
    assert len(y) == len(analysis.phi) + 1  # a closed path: the first point repeated
    np.testing.assert_allclose(x[:-1], eye.x * 1e3)
    np.testing.assert_allclose(y[:-1], eye.y * 1e3)
    assert (x[-1], y[-1]) == (x[0], y[0])
    np.testing.assert_allclose(data["needle_eye"][1], eye.y * 1e3)
    # and it is the needle eye of a 16.7 mm crank: 33.4 mm stroke on the line x = offset = 0, top at 90°
    assert np.ptp(y) == pytest.approx(33.4, abs=1e-9)
    assert np.abs(x).max() < 1e-9
    assert math.degrees(analysis.phi[int(np.argmax(y[:-1]))]) == pytest.approx(90.0)


def test_linkages_drawn_with_rigid_links(analysis):
    """The GIF's segments between points of one body keep the body's dimensions (mm) at every shaft angle."""
    m = analysis.machine
    drawn = {g.mechanism.name: plots.linkage(g, analysis.groups[g.name]) for g in m.groups}

    def length(lk, p, q):
        return np.hypot(*(lk.points[p] - lk.points[q]).T)

    rigid = [("needle_bar", "crank_pin", "link_pin", 50.0), ("needle_bar", "A", "crank_pin", 16.7),
             ("take_up", "crank_pin", "rocker_pin", 38.0), ("take_up", "crank_pin", "thread_eye", 58.0),
             ("take_up", "rocker_pin", "thread_eye", 22.0), ("take_up", "D", "rocker_pin", 26.0),
             ("hook_drive", "crank_pin", "rock_pin", 170.0), ("hook_drive", "O4", "slider_pin", 20.0),
             ("feed", "P", "O_feed", 20.0), ("feed", "O_feed", "R", 29.3), ("feed", "S", "T", 180.2),
             ("feed", "R", "feed_dog", 20.0), ("feed", "fork_top", "P", 200.0)]
    for mech, p, q, mm in rigid:
        np.testing.assert_allclose(length(drawn[mech], p, q), mm, atol=1e-9, err_msg=f"{mech} {p}-{q}")
    hook = drawn["hook_drive"]  # the slider pin lies on the lower shaft's slotted arm
    arm = hook.points["arm1"] - hook.points["arm0"]
    rel = hook.points["slider_pin"] - hook.points["arm0"]
    np.testing.assert_allclose(arm[:, 0] * rel[:, 1] - arm[:, 1] * rel[:, 0], 0.0, atol=1e-9)
    cam = drawn["feed"].outlines[0]  # the fork's faces touch the cam, breadth 6 + 2·8 mm apart
    fork = drawn["feed"].points
    normal = fork["fork_d"] - fork["fork_a"]
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    reach = np.einsum("nkc,nc->nk", cam - fork["fork_top"][:, None, :], normal)
    np.testing.assert_allclose(reach.max(axis=1), 11.0, atol=0.03)  # arcs drawn with 10 points
    np.testing.assert_allclose(reach.min(axis=1), -11.0, atol=0.03)


def test_stitch_family_travels_the_stitch_above_the_plate(analysis):
    """The feed-dog family: each plotted path moves the dog by its stitch while above the throat plate (plate
    crossings by linear interpolation on the 5° sweep, so to ~0.05 mm), zero stitch hardly moves it, and the
    reverse paths span the same width as the forward ones."""
    fig = plots.new_figure(plots.SIZES["feed_dog_stitches.png"])
    data = plots.draw_feed_dog_stitches(fig, analysis)
    plate = plots._plate_y(analysis) * 1e3
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

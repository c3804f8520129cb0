"""The benchmark's peers compute what sewgen computes: the closed-form loop a numba user writes
(peers.take_up_kernel, run here as plain Python, and compiled where numba is installed), the NumPy closed
form of the bench, and pylinkage's components where pylinkage is installed — every output against sewgen's
solve() over more than a turn, at another crank length, speed and a shaft acceleration."""
from __future__ import annotations

import numpy as np
import pytest

import sewgen
import peers
from bench import take_up_numpy
from sewgen.engine.designs import Columns

pytestmark = [pytest.mark.c]

PHI = np.linspace(-1.0, 8.0, 181)  # more than a turn: sewgen's angles continuous, the peers' within ±π
SPEED, ACCEL = 140.0, 35.0


def _sewgen(params):
    m = sewgen.mechanism("take_up")
    mo = m.solve(PHI, SPEED, ACCEL, params=params)
    cols = Columns(m.description)
    flat = np.hstack([mo.q, mo.qd, mo.qdd, mo.obs])
    return m, {name: flat[:, cols.index[name]] for name in cols.names}


def _worst(ref: dict, got: dict) -> float:
    """The largest difference over every column, relative to the column's largest value (angles modulo 2π)."""
    assert set(got) == set(ref)
    worst = 0.0
    for name, want in ref.items():
        diff = np.asarray(got[name]) - want
        if name.endswith(".angle"):
            diff = (diff + np.pi) % (2 * np.pi) - np.pi
        worst = max(worst, float(np.abs(diff).max() / max(np.abs(want).max(), 1e-12)))
    return worst


@pytest.fixture(scope="module")
def reference():
    m = sewgen.mechanism("take_up")
    params = {"crank": 1.04 * m.defaults()["crank"]}
    m, ref = _sewgen(params)
    p = dict(m.defaults(), **params)
    return p, ref


def test_the_loop_peer_gives_every_output_as_sewgen(reference):
    p, ref = reference
    out = np.empty((PHI.size, len(peers.COLUMNS)))
    peers.take_up_kernel(PHI, SPEED, ACCEL, peers.parameter_vector(p), out)
    assert _worst(ref, dict(zip(peers.COLUMNS, out.T))) < 1e-12
    assert set(peers.COLUMNS) == set(Columns(sewgen.mechanism("take_up").description).names)


def test_the_numpy_peer_gives_every_output_as_sewgen(reference):
    p, ref = reference
    assert _worst(ref, take_up_numpy(PHI, SPEED, ACCEL, p)) < 1e-12


def test_the_numba_peer_equals_its_plain_python():
    kernel = peers.numba_kernel()
    if kernel is None:
        pytest.skip("numba is not installed (pip install -e '.[peers]')")
    m = sewgen.mechanism("take_up")
    prm = peers.parameter_vector(m.defaults())
    a, b = np.empty((PHI.size, len(peers.COLUMNS))), np.empty((PHI.size, len(peers.COLUMNS)))
    kernel(PHI, SPEED, ACCEL, prm, a)
    peers.take_up_kernel(PHI, SPEED, ACCEL, prm, b)
    assert (np.abs(a - b) <= 1e-13 * np.abs(b).max(axis=0)).all()


def test_the_pylinkage_peer_gives_the_three_points_as_sewgen():
    pytest.importorskip("pylinkage", reason="pylinkage is not installed (pip install -e '.[peers]')")
    m = sewgen.mechanism("take_up")
    n = 720
    phi = 2 * np.pi * np.arange(n) / n
    mo = m.solve(phi, SPEED)
    c = mo.point("rocker_pin")
    run = peers.pylinkage_take_up(m.defaults(), n, SPEED, (float(c.x[0]), float(c.y[0])))
    pos, vel, acc = run()
    for j, name in enumerate(("crank_pin", "rocker_pin", "thread_eye")):
        pt = mo.point(name)
        for got, want in ((pos[:, j, 0], pt.x), (pos[:, j, 1], pt.y), (vel[:, j, 0], pt.vx), (vel[:, j, 1], pt.vy),
                          (acc[:, j, 0], pt.ax), (acc[:, j, 1], pt.ay)):
            assert np.abs(got - want).max() < 1e-9 * np.abs(want).max(), name

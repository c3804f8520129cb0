"""The feed-dog trajectory indices (seed 001 §五.3, sewgen.machine.feed_indices) against an independent computation from
a dense trajectory: 0.01° samples, linear interpolation of the crossings, trapezoids for the integrals."""
import math

import numpy as np
import pytest

from sewgen.machine.feed_indices import TOOTH_DEPTH, feed_indices, group_arrays
from sewgen.machine.assembly import load_machine
from sewgen.roles import FEED_DOG, THROAT_PLATE
from sewgen.machine.timing import timing

pytestmark = [pytest.mark.c]


@pytest.fixture(scope="module")
def jb():
    m = load_machine("jb1-3")
    return m, timing(m)


def _group(m):
    return next(g for g in m.groups if g.mechanism.description.has_role(FEED_DOG))


def _params(g, plate_shift):
    p = g.mechanism.param_vector(g.params or None).copy()
    p[g.mechanism.description.role(THROAT_PLATE).index] += plate_shift
    return dict(zip(g.mechanism.param_names, p))


def _crossings(z, x, phi):
    """Linear-interpolated (angle, x, sign) of every sign change of z on a dense periodic sweep."""
    out = []
    n = len(z)
    for i in range(n):
        j = (i + 1) % n
        if (z[i] < 0) != (z[j] < 0):
            f = z[i] / (z[i] - z[j])
            out.append((phi[i] + f * (phi[1] - phi[0]), x[i] + f * (x[j] - x[i]), 1 if z[i] < 0 else -1))
    return out


def _dense(g, phi, w, plate_shift):
    mo = g.mechanism.solve(phi + g.phase, speed=w, params=_params(g, plate_shift), held=g.held or None)
    dog = mo.point(g.mechanism.description.role(FEED_DOG).name)
    plate = g.mechanism.param_vector(_params(g, plate_shift))[g.mechanism.description.role(THROAT_PLATE).index]
    return mo, dog, plate


def _wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


@pytest.mark.parametrize("plate_shift", [0.0, -0.6e-3])  # the catalog's plate; 0.6 mm lower: the dog overlaps
def test_every_index_against_a_dense_trajectory(jb, plate_shift):
    m, tm = jb
    g = _group(m)
    w = m.speed
    n_in, n_out = tm.values["needle_in_cloth"], tm.values["needle_out_cloth"]
    # the indices on a 1° sweep, two designs in one call (the catalog's and the shifted plate)
    phi = np.radians(np.arange(0.0, 360.0, 1.0))
    obs, plates = [], []
    for shift in (0.0, plate_shift):
        mo, _, plate = _dense(g, phi, w, shift)
        obs.append(mo.obs)
        plates.append(plate)
    x, y, vx, vy, ax, tilt, arc = group_arrays(g.mechanism, np.stack(obs))
    ix = feed_indices(phi, x, y, vx, vy, ax, w, np.array(plates), needle_in=n_in, needle_out=n_out, tilt=tilt,
                      arc=arc)
    assert ix["error"] == [None, None]
    k = 1

    # the dense reference, written out here
    phd = np.radians(np.arange(0.0, 360.0, 0.01))
    mo, dog, plate = _dense(g, phd, w, plate_shift)
    z = dog.y - plate
    cr = _crossings(z, dog.x, phd)
    assert [s for _, _, s in cr].count(1) == 1 and [s for _, _, s in cr].count(-1) == 1
    (rise, x_r, _), = [c for c in cr if c[2] == 1]
    (sink, x_s, _), = [c for c in cr if c[2] == -1]
    travel = x_s - x_r
    teeth = _crossings(z - TOOTH_DEPTH, dog.x, phd)
    effective = sum(-s * xc for _, xc, s in teeth)
    height = z.max()
    span = (sink - rise) % (2 * math.pi)
    inside = (phd - rise) % (2 * math.pi) <= span
    zp = np.maximum(z, 0.0)
    area = np.sum(0.5 * (zp + np.roll(zp, -1)) * (np.roll(dog.x, -1) - dog.x))
    fullness = abs(area) / (abs(travel) * height)
    uniformity = np.abs(dog.vx[inside]).max() / np.abs(dog.vx[inside]).mean()
    peak_accel = np.abs(dog.ax[inside]).max()
    a_arc = mo.obs[:, [k for k, (nm, _) in enumerate(g.mechanism.description.observables) if nm.endswith(".arc")][0]]
    jumps = np.abs(np.roll(dog.ax, -1) - dog.ax)[a_arc != np.roll(a_arc, -1)]
    body = mo.body(g.mechanism.description.role("feed_bar").name).angle[inside]
    sink_lead, rise_lag = _wrap(n_in - sink), _wrap(rise - n_out)

    def x_at(a):
        return np.interp((a - phd[0]) % (2 * math.pi), phd, dog.x, period=2 * math.pi)

    overlap = (abs(x_s - x_at(n_in)) if sink_lead < 0 else 0.0) + (abs(x_at(n_out) - x_r) if rise_lag < 0 else 0.0)

    def close(name, ref, tol):
        assert ix[name][k] == pytest.approx(ref, abs=tol), name

    close("travel", travel, 1e-7)
    close("effective_travel", effective, 1e-7)
    close("height", height, 1e-8)
    close("rise_at", rise % (2 * math.pi), 1e-5)
    close("sink_at", sink % (2 * math.pi), 1e-5)
    close("sink_lead", sink_lead, 1e-5)
    close("rise_lag", rise_lag, 1e-5)
    close("overlap_travel", overlap, 1e-7)
    close("fullness", fullness, 1e-4)
    close("speed_uniformity", uniformity, 1e-3 * uniformity)
    close("peak_accel", peak_accel, 2e-3 * peak_accel)
    close("accel_jump", jumps.max(), 0.03 * jumps.max())
    close("tilt_min", body.min(), 1e-5)
    close("tilt_max", body.max(), 1e-5)
    if plate_shift:
        assert ix["overlap_travel"][k] > 1e-5 and (ix["sink_lead"][k] < 0 or ix["rise_lag"][k] < 0)
    else:
        assert ix["overlap_travel"][k] == 0.0


def test_a_dog_that_never_sinks_is_named_and_the_others_unaffected(jb):
    m, tm = jb
    g = _group(m)
    phi = np.radians(np.arange(0.0, 360.0, 1.0))
    obs, plates = [], []
    for shift in (0.0, -0.02, 0.0):  # plate 20 mm lower: the dog is always above it
        mo, _, plate = _dense(g, phi, m.speed, shift)
        obs.append(mo.obs)
        plates.append(plate)
    x, y, vx, vy, ax, tilt, arc = group_arrays(g.mechanism, np.stack(obs))
    ix = feed_indices(phi, x, y, vx, vy, ax, m.speed, np.array(plates))
    assert ix["error"][0] is None and ix["error"][2] is None
    assert "rise above the plate once a turn" in ix["error"][1]
    assert math.isnan(ix["travel"][1]) and ix["travel"][0] == ix["travel"][2]


def test_summary_has_the_indices(jb, tmp_path):
    from sewgen.report.outputs import summary

    m, tm = jb
    entry = summary(m.analyze(), None, tm)["groups"][_group(m).name][FEED_DOG]["indices"]
    assert entry["travel_mm"] == pytest.approx(4.0, abs=1e-4)
    assert entry["rise_lag_deg"] == pytest.approx(tm.check("dog_rises_after_needle_leaves").value, abs=1e-3)
    assert entry["sink_lead_deg"] == pytest.approx(tm.check("dog_sinks_before_needle_enters").value, abs=1e-3)


@pytest.mark.parametrize("step, rel", [(5.0, 1.5e-3), (1.0, 2e-5)])
def test_the_arc_jumps_against_each_switch_solved_at_its_own_angle(jb, step, rel):
    """feed_indices.arc_jumps extrapolates each side's acceleration to where the sides' velocities meet; the
    reference brackets every switch and solves both sides at it (sewgen.machine.cams.arc_switches, summary.json's)."""
    from sewgen.machine.cams import arc_switches
    from sewgen.machine.feed_indices import arc_jumps

    m, _ = jb
    g = _group(m)
    phi = np.radians(np.arange(0.0, 360.0, step))
    mo, dog, _ = _dense(g, phi, m.speed, 0.0)
    exact = arc_switches(g.mechanism, mo, params=_params(g, 0.0), held=g.held or None)
    x, y, vx, vy, ax, tilt, arc = group_arrays(g.mechanism, mo.obs)
    rows, i, jumps = arc_jumps(arc, vx, ax / m.speed, phi[1] - phi[0])
    assert len(exact) == len(jumps) == 6
    name = g.mechanism.description.role(FEED_DOG).name
    ref = {round(math.degrees(s.angle) / step - 0.5) % len(phi): s.jumps[name][0] for s in exact}
    for k, jmp in zip(i, jumps * m.speed):
        want = ref.get(int(k), ref.get(int(k) - 1, ref.get(int(k) + 1)))
        assert jmp == pytest.approx(want, rel=rel)

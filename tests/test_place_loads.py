"""The loads' slots at the shaft angles (sewgen.engine.loads.place_loads, one C call: sg_place_loads) against the
definition written here with numpy: each load's SI value added to its slots wherever its window holds the angle,
(φ − start) mod 2π ≤ span + 1e-9 with the ends inclusive and windows wrapping through 360°, always on without a
window or with a whole turn. Equal to the bit, masks included."""
from __future__ import annotations

import math

import numpy as np
import pytest

import sewgen
from sewgen import Load
from sewgen.engine.loads import load_layout, place_loads, window_mask

pytestmark = [pytest.mark.c]


def _by_numpy(layout, phi, nload):
    out, masks = np.zeros((len(phi), nload)), []
    for _load, cols, window in layout:
        mask = window_mask(phi, window)
        for k, value in cols:
            if value != 0.0:
                out[mask, k] += value
        masks.append(mask)
    return out, masks


LOADS = [
    Load("thread_eye", fx=1.5, fy=-2.94, window=("135 deg", "155 deg"), name="thread"),
    Load("thread_eye", fy=0.25, window=("350 deg", "20 deg")),          # wraps through 360°, same slot again
    Load("crank_pin", fx=-0.0, fy=3.0),                                 # always on; a -0.0 left out
    Load("lever", torque=0.125, window=(0.0, 2 * math.pi)),             # a whole turn
    Load("rocker_pin", fx=2.0, window=(math.radians(90.0), math.radians(90.0))),  # one angle, both ends
    Load("rocker", torque=-1.0, window=("-30 deg", "30 deg")),
]


@pytest.mark.parametrize("phi", [
    np.linspace(0.0, 2 * math.pi, 73),                       # ends of windows hit exactly
    np.linspace(-4 * math.pi, 4 * math.pi, 1001),            # several turns, negative angles
    np.array([math.radians(135.0), math.radians(155.0) + 5e-10, math.radians(155.0) + 2e-9, np.nan, -0.0]),
    np.linspace(0.0, 1.0, 9)[::-2],                          # strided, descending
])
def test_the_c_placement_equals_the_numpy_definition_bit_for_bit(phi):
    mech = sewgen.mechanism("take_up")
    nload = len(mech.description.loads)
    layout = load_layout(mech, LOADS)
    got, placed = place_loads(layout, phi, nload)
    want, masks = _by_numpy(layout, phi, nload)
    assert got.tobytes() == want.tobytes()
    assert [(ld, cols) for ld, cols, _ in placed] == [(ld, cols) for ld, cols, _ in layout]
    for (_ld, _cols, mask), ref in zip(placed, masks):
        assert mask.dtype == bool and np.array_equal(mask, ref)
    # real placements, not zeros: the thread load is on over 135°–155° only
    if len(phi) == 73:
        on = got[:, 5] != 0.0
        assert on.sum() > 3 and np.all(got[np.isclose(np.degrees(phi), 145.0), 5] == -2.94)


def test_into_a_given_array_every_slot_is_overwritten():
    mech = sewgen.mechanism("take_up")
    nload = len(mech.description.loads)
    phi = np.linspace(0.0, 2 * math.pi, 36, endpoint=False)
    out = np.full((len(phi), nload), np.nan)
    got, _ = place_loads(load_layout(mech, LOADS), phi, nload, out)
    assert got is out
    assert got.tobytes() == _by_numpy(load_layout(mech, LOADS), phi, nload)[0].tobytes()

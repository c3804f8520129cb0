"""User mechanisms of every size a designer declares build: a corpus of 1 to 4 closing loops and up to 9 moving
bodies (a crank driving four-bar loops in series, the last one a slider-crank, a spring on the crank pin), closed
form and Newton, compiled with the module's own flags at -O2 and at -O3.

GCC's "may be used uninitialized" analysis follows the sweeps' deep inlining only as far as its optimisation level
and inlining budget take it; it once failed the build of a closed-form 7-body, 3-loop mechanism with a spring
(a false positive: every kernel's SG_OK return writes all its outputs). Here every size compiles, and the largest
one, loaded and swept, keeps the power balance (input power = ω dE/dφ of the kinematics' energies).
"""
from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest

import sewgen
from sewgen.derive import generate, render_files
from sewgen.derive.model import Mechanism as Declaration
from sewgen.engine import build

pytestmark = [pytest.mark.derive, pytest.mark.slow]

GCC = shutil.which("gcc")
#: Every coupler's and rocker's mass, centre of mass and moment of inertia (a 30 mm steel link, about).
INERTIA = {"mass": "20 g", "com": ("15 mm", "0 mm"), "inertia": "2e-6 kg*m**2"}


def chain(loops: int) -> Declaration:
    """A crank driving ``loops`` loops in series: each a coupler from the last body's pin to a rocker pivoted on
    the frame (an RRR dyad), the last one a coupler to a slider on a horizontal guide (RRP) where ``loops`` > 1;
    1 + 2 * loops moving bodies, a spring from the crank pin to the frame."""
    m = Declaration(f"chain{loops}", f"{loops} loops in series on one crank, a spring on the crank pin")
    r = m.length("crank", "10 mm", "crank")
    crank = m.driven("crank", pivot=m.ground.at(0, 0), doc="crank")
    prev, pin = crank, (r, 0)
    for i in range(loops):
        lc = m.length(f"coupler{i}", "40 mm", f"coupler {i}")
        coupler = m.link(f"coupler{i}", guess="20 deg", **INERTIA)
        m.revolute(prev.at(*pin), coupler.at(0, 0), name=f"A{i}")
        if i == loops - 1 and loops > 1:  # the last loop: a slider-crank
            gy = m.length("guide_y", "-5 mm", "guide line's height", signed=True)
            slider = m.slider("slider", m.ground.line((0, gy), "0 deg"), guess=f"{40 * i + 45} mm", mass="30 g")
            m.revolute(coupler.at(lc, 0), slider.at(0, 0), name=f"B{i}")
            m.point("slider_pin", slider.at(0, 0))
            break
        lr = m.length(f"rocker{i}", "30 mm", f"rocker {i}")
        px = m.length(f"pivot{i}_x", f"{35 + 40 * i} mm", f"rocker {i} pivot, x", signed=True)
        py = m.length(f"pivot{i}_y", "5 mm", f"rocker {i} pivot, y", signed=True)
        rocker = m.link(f"rocker{i}", guess="100 deg", **INERTIA)
        m.revolute(m.ground.at(px, py), rocker.at(0, 0), name=f"O{i}")
        m.revolute(coupler.at(lc, 0), rocker.at(lr, 0), name=f"B{i}")
        au = m.length(f"arm{i}_u", "-10 mm", f"rocker {i} arm pin, u", signed=True)
        av = m.length(f"arm{i}_v", "8 mm", f"rocker {i} arm pin, v", signed=True)
        m.point(f"rocker{i}_pin", rocker.at(lr, 0))
        prev, pin = rocker, (au, av)
    ax = m.length("anchor_x", "0 mm", "spring anchor, x", signed=True)
    ay = m.length("anchor_y", "60 mm", "spring anchor, y", signed=True)
    m.spring(crank.at(r, 0), m.ground.at(ax, ay), "500 N/m", "40 mm", name="spring")
    return m


@pytest.mark.skipif(GCC is None, reason="gcc not installed")
@pytest.mark.parametrize("closed_form", [True, False], ids=["closed", "newton"])
@pytest.mark.parametrize("loops", [1, 2, 3, 4])
def test_every_size_compiles_with_the_module_flags(loops, closed_form, tmp_path):
    files = render_files([generate(chain(loops), closed_form=closed_form)])
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    for level in ("-O2", "-O3"):
        flags = [*build.compile_flags(), level]  # the module's flags (warnings as errors), the level last
        cmd = [GCC, *flags, f"-I{build.runtime_dir()}", f"-I{tmp_path}", "-c", str(tmp_path / f"sg_chain{loops}.c"),
               "-o", str(tmp_path / f"chain{level}.o")]
        res = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        assert res.returncode == 0, f"{' '.join(cmd)}\n{res.stderr[-4000:]}"


@pytest.mark.c
def test_the_largest_sweeps_and_keeps_the_power_balance(tmp_path):
    closed = sewgen.load(lambda: chain(4), closed_form=True, cache_dir=tmp_path)
    newton = sewgen.load(lambda: chain(4), closed_form=False, cache_dir=tmp_path)
    assert len(closed.description.coords) == 8  # 8 moving bodies' coordinates beyond the crank
    phi = np.radians(np.arange(0.0, 360.0, 0.25))
    w = 40.0
    fa = closed.kinetostatics(phi, w)
    np.testing.assert_allclose(newton.solve(phi, w).q, fa.motion.q, rtol=0, atol=1e-9)
    E, h = fa.kinetic_energy + fa.potential_energy, phi[1] - phi[0]
    dE = (-np.roll(E, -2) + 8 * np.roll(E, -1) - 8 * np.roll(E, 1) + np.roll(E, 2)) / (12 * h)
    scale = float(np.max(np.abs(fa.input_power())))
    assert scale > 0.1  # the spring and the links' inertia load the crank
    np.testing.assert_allclose(fa.input_power(), w * dE, rtol=0, atol=1e-5 * scale)

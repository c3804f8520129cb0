"""A machine of the user's own: a Stephenson six-bar needle drive declared in a file beside the model file.

The mechanism is not in the catalog: an upper-shaft crank AB drives a crank-rocker four-bar ABCD whose ternary
coupler BCE carries the pin E of a rod EF; the rod drives the needle bar (a slider on the vertical guide
x = e) at F; the needle eye is on the bar, tagged with the role ``needle_eye``. Ground (A, D, the guide) and the
coupler (B, C, E) are the two ternary links and are not joined to each other: a Stephenson chain. Every body
has mass and inertia.

The test writes the declaration file and a model file whose group points at it, runs ``sewgen analyze`` on
it as a user would (a subprocess, its own cache folder), and checks that the tables and summary.json (power
balance closed to 1e-9) are written, and that the needle-eye stroke and the peak driving
torque at rest-free speed agree with an independent computation written here: circle intersections for
the four-bar and the rod, velocities and accelerations by central differences in the shaft angle, and the
driving torque from the power balance T·ω = Σ m a_G·v_G + I α ω (no gravity, constant speed).
"""
from __future__ import annotations

import csv
import json
import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

pytestmark = [pytest.mark.c, pytest.mark.derive, pytest.mark.cli, pytest.mark.plots]

MM = 1e-3

DECLARATION = textwrap.dedent('''
    """Stephenson six-bar needle drive (a user's declaration, not in the catalog)."""
    import sympy as sp

    from sewgen.derive import Mechanism


    def declare():
        m = Mechanism("stephenson_needle", __doc__)
        r = m.length("crank", "8 mm", "crank AB")
        bc = m.length("coupler_bc", "40 mm", "coupler B to C")
        eu = m.length("coupler_eu", "20 mm", "pin E on the coupler, along B->C", signed=True)
        ev = m.length("coupler_ev", "-15 mm", "pin E on the coupler, across B->C", signed=True)
        cd = m.length("rocker", "30 mm", "rocker DC")
        dx = m.length("rocker_pivot_x", "30 mm", "pivot D, x", signed=True)
        dy = m.length("rocker_pivot_y", "25 mm", "pivot D, y", signed=True)
        ef = m.length("rod", "45 mm", "rod EF")
        e = m.length("guide_x", "5 mm", "needle-bar guide line x = e", signed=True)
        h = m.length("eye_below_pin", "60 mm", "needle eye below F")
        crank = m.driven("crank", pivot=m.ground.at(0, 0), doc="crank on the upper shaft",
                         mass="20 g", com=("3 mm", "0 mm"), inertia="1e-6 kg*m**2")
        coupler = m.link("coupler", doc="ternary coupler BCE", guess="60 deg",
                         mass="15 g", com=("20 mm", "-5 mm"), inertia="3e-6 kg*m**2")
        rocker = m.link("rocker", doc="rocker DC", guess="-100 deg",
                        mass="10 g", com=("15 mm", "0 mm"), inertia="1e-6 kg*m**2")
        rod = m.link("rod", doc="rod EF", guess="-90 deg",
                     mass="8 g", com=("22 mm", "0 mm"), inertia="1.5e-6 kg*m**2")
        bar = m.slider("bar", guide=m.ground.line(at=(e, 0), angle=sp.pi / 2), doc="needle bar", guess="-50 mm",
                       mass="40 g", com=("-30 mm", "0 mm"), inertia="1e-5 kg*m**2")
        m.revolute(crank.at(r, 0), coupler.at(0, 0), name="B")
        m.revolute(coupler.at(bc, 0), rocker.at(cd, 0), name="C")
        m.revolute(m.ground.at(dx, dy), rocker.at(0, 0), name="D")
        m.revolute(coupler.at(eu, ev), rod.at(0, 0), name="E")
        m.revolute(rod.at(ef, 0), bar.at(0, 0), name="F", branch=-1)
        m.point("pin_e", coupler.at(eu, ev), "coupler pin E")
        m.point("needle_eye", bar.at(-h, 0), "needle eye", role="needle_eye")
        return m
''')

MODEL = textwrap.dedent('''
    [machine]
    name = "Stephenson-1"
    description = "a user's needle drive"
    speed = "1200 rpm"
    step = "5 deg"
    gravity = "0 m/s**2"

    [shaft]
    front_bearing = "0 mm"
    rear_bearing = "200 mm"
    mass = "200 g"
    mass_z = "100 mm"
    inertia = "2e-5 kg*m**2"

    [groups.needle]
    mechanism = "stephenson_needle.py"
    phase = "0 deg"
    axial = { crank = "-15 mm" }
''')


def _intersect(p, r1, q, r2, sign):
    """The intersection of circles (p, r1) and (q, r2) on the side ``sign`` of the line p -> q (arrays (n, 2))."""
    d = q - p
    dist = np.hypot(d[:, 0], d[:, 1])
    a = (r1**2 - r2**2 + dist**2) / (2 * dist)
    h = np.sqrt(r1**2 - a**2)
    u = d / dist[:, None]
    perp = np.column_stack([-u[:, 1], u[:, 0]])
    return p + a[:, None] * u + sign * h[:, None] * perp


def reference(phi):
    """Needle-eye height (m) and the joints, by circle intersections, written out independently of sewgen."""
    n = len(phi)
    A, D = np.zeros((n, 2)), np.tile([30 * MM, 25 * MM], (n, 1))
    B = 8 * MM * np.column_stack([np.cos(phi), np.sin(phi)])
    # C: |BC| = 40, |DC| = 30; the assembly the declaration's guesses start from (coupler up, rocker down)
    C = _intersect(B, 40 * MM, D, 30 * MM, +1.0)
    ub = (C - B) / (40 * MM)
    vb = np.column_stack([-ub[:, 1], ub[:, 0]])
    E = B + 20 * MM * ub - 15 * MM * vb
    # F on x = 5 mm at |EF| = 45 mm, below E (branch -1 of the declaration)
    dxe = 5 * MM - E[:, 0]
    F = np.column_stack([np.full(n, 5 * MM), E[:, 1] - np.sqrt((45 * MM) ** 2 - dxe**2)])
    return F[:, 1] - 60 * MM, {"A": A, "B": B, "C": C, "D": D, "E": E, "F": F}


@pytest.fixture(scope="module")
def analysed(tmp_path_factory):
    root = tmp_path_factory.mktemp("user_machine")
    (root / "stephenson_needle.py").write_text(DECLARATION)
    (root / "my_machine.toml").write_text(MODEL)
    env = dict(os.environ, SEWGEN_CACHE=str(root / "cache"))
    res = subprocess.run([sys.executable, "-m", "sewgen", "analyze", "my_machine.toml", "--out", "results"],
                         cwd=root, env=env, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    return root / "results", res


def test_the_user_machine_writes_its_tables_and_summary(analysed):
    out, _ = analysed
    for name in ("machine.csv", "needle.csv", "summary.json"):
        assert (out / name).stat().st_size > 100, name
    header = (out / "needle.csv").read_text().splitlines()[0].split(",")
    assert {"needle_eye.y [m]", "pin_e.x [m]", "F.fx [N]", "bar.travel [m]", "shaft.torque [N*m]"} <= set(header)


def test_the_user_machine_gets_every_picture(analysed):
    """Pictures are drawn from the description: the user's six-bar gets the catalog's figures (no feed figure:
    it has no feed dog), each a real image with the PNG or GIF signature and many frames in the GIF."""
    out, _ = analysed
    pngs = {p.name for p in out.glob("*.png")}
    assert pngs == {"trajectories.png", "motion.png", "torque.png", "shaking.png", "bearings_polar.png",
                    "joint_reactions_polar.png"}
    for name in pngs:
        data = (out / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000, name
    gif = (out / "machine.gif").read_bytes()
    assert gif[:6] in (b"GIF87a", b"GIF89a")
    assert gif.count(b"\x21\xf9\x04") >= 36  # one graphic-control extension per frame


def test_the_power_balance_closes(analysed):
    out, _ = analysed
    summary = json.loads((out / "summary.json").read_text())
    assert summary["power_balance_residual_relative"] <= 1e-9
    assert summary["positions"] == 72
    assert summary["groups"]["needle"]["mechanism"] == "stephenson_needle"
    assert set(summary["shaking_moments_on_frame"]) == {"x", "y", "z"}


def _column(path, name):
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    k = rows[0].index(name)
    return np.array([float(r[k]) for r in rows[1:]])


def test_the_needle_eye_and_torque_match_an_independent_solution(analysed):
    out, _ = analysed
    phi = np.radians(_column(out / "needle.csv", "phi [deg]"))
    eye = _column(out / "needle.csv", "needle_eye.y [m]")
    ref, _ = reference(phi)
    assert np.max(np.abs(eye - ref)) < 1e-12
    # the driving torque at constant speed without gravity: T ω = dE_kin/dt, E_kin from central differences of
    # the reference positions (every body's centre of mass and angle), written out here
    w = 1200 * 2 * math.pi / 60
    h = 1e-4
    def kinetic(p):
        _, J = reference(p)
        def com(a, b, u, v):  # centre of mass at (u, v) in the frame with origin a and x along a -> b
            ux = (b - a) / np.hypot(*(b - a).T)[:, None]
            return a + u * ux + v * np.column_stack([-ux[:, 1], ux[:, 0]])
        def angle(a, b):
            return np.unwrap(np.arctan2(b[:, 1] - a[:, 1], b[:, 0] - a[:, 0]))
        bodies = [  # (mass, inertia, com, angle)
            (0.020, 1e-6, com(J["A"], J["B"], 3 * MM, 0.0), angle(J["A"], J["B"])),
            (0.015, 3e-6, com(J["B"], J["C"], 20 * MM, -5 * MM), angle(J["B"], J["C"])),
            (0.010, 1e-6, com(J["D"], J["C"], 15 * MM, 0.0), angle(J["D"], J["C"])),
            (0.008, 1.5e-6, com(J["E"], J["F"], 22 * MM, 0.0), angle(J["E"], J["F"])),
            (0.040, 1e-5, J["F"] + np.array([0.0, -30 * MM]), np.zeros(len(p))),
        ]
        return bodies
    lo, mid, hi = kinetic(phi - h), kinetic(phi), kinetic(phi + h)
    torque = np.zeros(len(phi))
    for (m, inertia, c0, a0), (_, _, c1, a1), (_, _, c2, a2) in zip(lo, mid, hi):
        v = (c2 - c0) / (2 * h) * w
        acc = (c2 - 2 * c1 + c0) / h**2 * w * w
        om = (a2 - a0) / (2 * h) * w
        al = (a2 - 2 * a1 + a0) / h**2 * w * w
        torque += (m * np.sum(acc * v, axis=1) + inertia * al * om) / w
    group_torque = _column(out / "needle.csv", "shaft.torque [N*m]")
    assert np.max(np.abs(group_torque - torque)) < 1e-5 * np.max(np.abs(torque))


def test_a_built_declaration_loads_without_the_derivation(analysed):
    """The second run finds the declaration's build through the cache's index: no SymPy, no jinja2."""
    out, _ = analysed
    root = out.parent
    code = ("import sys\n"
            "from sewgen.machine import load_machine\n"
            "a = load_machine('my_machine.toml').analyze()\n"
            "print(a.groups['needle'].mechanism.build_info['cached'],\n"
            "      sorted(k for k in ('sympy', 'jinja2', 'sewgen.derive') if k in sys.modules))\n")
    env = dict(os.environ, SEWGEN_CACHE=str(root / "cache"))
    res = subprocess.run([sys.executable, "-c", code], cwd=root, env=env, capture_output=True, text=True,
                         timeout=300)
    assert res.returncode == 0, res.stderr
    assert res.stdout.split() == ["True", "[]"]
    # an edited declaration is derived and built again
    decl = root / "stephenson_needle.py"
    decl.write_text(decl.read_text().replace('"45 mm", "rod EF"', '"46 mm", "rod EF"'))
    res = subprocess.run([sys.executable, "-c", code], cwd=root, env=env, capture_output=True, text=True,
                         timeout=600)
    assert res.returncode == 0, res.stderr
    assert res.stdout.split()[0] == "False" and "sympy" in res.stdout


# -- a model file is code: only its own folder's declaration files run --------------------------------------------

RUNS = textwrap.dedent('''
    from pathlib import Path

    Path(__file__).resolve().with_name("ran.txt").write_text("the declaration ran")


    def declare():
        raise RuntimeError("declared")
''')


@pytest.mark.parametrize("where", ["parent", "absolute", "home", "link"])
def test_a_model_file_runs_no_code_outside_its_folder_unless_allowed(where, tmp_path, monkeypatch, capsys):
    """A declaration file named by a group runs when the machine is loaded: one outside the model file's folder
    (``..``, an absolute path, ``~``, a link out of the folder) is refused before any of its code runs, naming the
    key and the option that allows it; with the option it runs (here its declare() raises, named by file and
    line)."""
    from sewgen.cli.main import main
    from sewgen.machine import load_machine
    from sewgen.machine.modelfile import ModelFileError

    (tmp_path / "code.py").write_text(RUNS)
    (tmp_path / "models").mkdir()
    monkeypatch.setenv("HOME", str(tmp_path))
    if where == "link":
        os.symlink(tmp_path / "code.py", tmp_path / "models" / "link.py")
    text = {"parent": "../code.py", "absolute": str(tmp_path / "code.py"), "home": "~/code.py", "link": "link.py"}
    model = tmp_path / "models" / "m.toml"
    model.write_text(MODEL.replace('mechanism = "stephenson_needle.py"', f'mechanism = "{text[where]}"'))
    with pytest.raises(ModelFileError) as exc:
        load_machine(model)
    assert exc.value.key == "groups.needle.mechanism" and "--allow-outside-code" in exc.value.problem
    assert not (tmp_path / "ran.txt").exists()
    monkeypatch.chdir(tmp_path)
    assert main(["analyze", "models/m.toml", "--no-plots"]) == 2
    err = capsys.readouterr().err
    assert "groups.needle.mechanism" in err and "outside the model file's folder" in err
    assert not (tmp_path / "ran.txt").exists()
    assert main(["analyze", "models/m.toml", "--no-plots", "--allow-outside-code"]) == 2
    err = capsys.readouterr().err
    assert ".py:8: RuntimeError: declared" in err and len(err.splitlines()) == 1
    assert (tmp_path / "ran.txt").read_text() == "the declaration ran"

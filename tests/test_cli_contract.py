"""The command line's contract with a new user: docs that run, strict quantity strings, model files.

* The README's quick start works twice in one folder, and then the built-in name still finds the built-in model.
* Every ``sewgen ...`` command line of the code blocks of README.md and docs/**/*.md runs (extracted from them,
  not copied here); so does every ```python block; the numbers the docs quote for the balancing command are the
  ones it prints. ```text, ```toml and other blocks are illustrations: they are not run.
* Every user mistake — a bare number, a unit-less or garbled quantity, an impossible step, an output path that
  cannot be written, a broken declaration or model file — exits 2 with exactly one line on stderr naming the
  culprit, nothing on stdout and no traceback.
* Conventions: ``--version``, ``--quiet``, ``--units``, one spelling of names, the speed used in the header,
  clean summary numbers with their units and conventions, a warning when every mass is zero.

Commands run as a user runs them: ``python -m sewgen`` in a fresh temporary folder with its own build cache.
"""
from __future__ import annotations

import csv
import json
import math
import os
import re
import shlex
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import sewgen

pytestmark = [pytest.mark.c, pytest.mark.cli, pytest.mark.plots, pytest.mark.derive]

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text(encoding="utf-8")
DOCS = [README] + [p.read_text(encoding="utf-8") for p in sorted((ROOT / "docs").rglob("*.md"))]
MODEL = (ROOT / "sewgen" / "models" / "jb1-3.toml").read_text(encoding="utf-8")


# -- running the command -----------------------------------------------------------------------------------------

def sewgen_run(args, cwd, cache, timeout=600, env=None):
    """``sewgen ARGS`` as a user runs it (python -m sewgen), in ``cwd`` with its own build cache."""
    full_env = dict(os.environ, SEWGEN_CACHE=str(cache), **(env or {}))
    full_env.pop("MPLBACKEND", None)
    return subprocess.run([sys.executable, "-m", "sewgen", *args], cwd=cwd, env=full_env, capture_output=True,
                          text=True, timeout=timeout)


def ok(res):
    assert res.returncode == 0, f"exit {res.returncode}\n{res.stderr}"
    assert "Traceback" not in res.stderr, res.stderr
    return res


def refused(res, *culprits):
    """Exit 2, nothing on stdout, exactly one line on stderr naming every culprit, no traceback, no wrapping
    quotes around the message."""
    lines = res.stderr.splitlines()
    assert res.returncode == 2, f"exit {res.returncode}\nstdout: {res.stdout}\nstderr: {res.stderr}"
    assert res.stdout == "", res.stdout
    assert len(lines) == 1, res.stderr
    assert "Traceback" not in res.stderr
    line = lines[0]
    assert line.startswith("sewgen"), line
    assert not re.match(r"sewgen[^:]*: [\"']", line), f"message wrapped in quotes: {line}"
    for c in culprits:
        assert str(c) in line, f"{c!r} not named in: {line}"
    return line


# -- the README and the docs ---------------------------------------------------------------------------------------

SHELL = ("", "bash", "sh", "shell", "console")  # blocks whose ``sewgen ...`` lines run; ```text etc. illustrate


def _blocks(lang: str | tuple | None = None) -> list[str]:
    """The fenced code blocks of README.md, then of docs/**/*.md (of language ``lang`` or one of a tuple of them,
    or every one)."""
    out = []
    for text in DOCS:
        for m in re.finditer(r"^```([A-Za-z]*)\n(.*?)^```", text, re.S | re.M):
            if lang is None or m.group(1) == lang or (isinstance(lang, tuple) and m.group(1) in lang):
                out.append(m.group(2))
    return out


def _commands(block: str) -> list[list[str]]:
    """Every ``sewgen ...`` command in a block (continuation lines joined, comments dropped, ``a && sewgen ..``
    split), as argv lists without the leading ``sewgen``."""
    out = []
    for line in block.replace("\\\n", " ").splitlines():
        for part in line.split("&&"):
            part = part.strip()
            if re.match(r"sewgen\s", part):
                argv = shlex.split(part, comments=True)
                out.append(argv[1:])
    return out


QUICK_START = _blocks("bash")[0]  # README's first bash block
QUICK = _commands(QUICK_START)
COMMANDS = []  # each command once, in the order the README and then the docs show it
for _argv in (argv for block in _blocks(SHELL) for argv in _commands(block)):
    if _argv not in QUICK and _argv not in COMMANDS:
        COMMANDS.append(_argv)


def test_the_readme_has_two_quick_start_commands_and_command_examples():
    lines = [ln for ln in QUICK_START.splitlines() if ln.strip()]
    assert len(lines) == 2, lines
    assert QUICK == [["analyze", "jb1-3", "--out", "jb1-3"]]
    assert len(COMMANDS) >= 10
    assert any(argv[:1] == ["balance"] for argv in COMMANDS)
    assert any("--file" in argv for argv in COMMANDS)


@pytest.fixture(scope="module")
def quick_start(tmp_path_factory, cache):
    """The quick start's command twice in one fresh folder, then plain ``sewgen analyze jb1-3 --no-plots``
    there: (folder, the runs, {file: size} of ./jb1-3 after the second run)."""
    folder = tmp_path_factory.mktemp("quick_start")
    runs = [ok(sewgen_run(QUICK[0], folder, cache)) for _ in range(2)]
    second = {p.name: p.stat().st_size for p in (folder / "jb1-3").iterdir()}
    runs.append(ok(sewgen_run(["analyze", "jb1-3", "--no-plots", "--quiet"], folder, cache)))
    return folder, runs, second


def test_quick_start_works_twice_in_one_folder(quick_start):
    folder, runs, second = quick_start
    for name in ("machine.csv", "summary.json", "trajectories.png", "motion.png", "machine.gif"):
        assert second[name] > 1000, name
    assert "1000 rpm" in runs[0].stdout and "wrote jb1-3/summary.json" in runs[0].stdout
    assert "timing: 12 of 12 rules pass" in runs[0].stdout  # the verdict, exit status 0
    assert runs[1].stdout == runs[0].stdout
    assert runs[2].stdout == ""  # --quiet
    assert sorted(p.name for p in folder.iterdir()) == ["jb1-3"]  # nothing half-written left beside it
    # the third run (no plots) replaced the second's set: its tables, no picture of the run before
    wrote = {name for name in second if not name.endswith((".png", ".gif"))}
    assert {p.name for p in (folder / "jb1-3").iterdir()} == wrote


def test_summary_numbers_are_clean_and_say_what_they_mean(quick_start):
    folder, _, _ = quick_start
    s = json.loads((folder / "jb1-3" / "summary.json").read_text(encoding="utf-8"))
    assert s["speed_rpm"] == 1000.0 and s["positions"] == 72 and s["step_deg"] == 5.0
    assert s["model_file"] == "<sewgen>/models/jb1-3.toml"
    assert "power_balance_residual" not in s and 0 <= s["power_balance_residual_relative"] < 1e-9
    assert "relative" in s["conventions"]["power_balance_residual_relative"] or \
        "divided" in s["conventions"]["power_balance_residual_relative"]
    for key in ("frame", "shaft_angle", "bearings", "drive_torque", "joints", "shaking_force_on_frame",
                "shaking_moments_on_frame", "frame_force_on_parts"):
        assert s["conventions"][key], key
    assert "friction" in s["conventions"]["drive_torque"]
    assert s["units"]["angles"] == "deg"

    def walk(node, key=""):
        if isinstance(node, dict):
            for k, v in node.items():
                yield from walk(v, k)
        elif isinstance(node, list):
            for v in node:
                yield from walk(v, key)
        else:
            yield key, node

    angles = [v for k, v in walk(s) if k in ("max_at_deg", "min_at_deg")]  # refined between the samples
    assert len(angles) > 50 and any(v % 5 != 0 for v in angles)
    for v in angles:  # to 0.01°, in [0, 360)
        assert v == round(v, 2) and 0 <= v < 360, v
    assert {v for k, v in walk(s) if k in ("max_how", "min_how")} <= {"refined", "at a switch"}
    for k, v in walk(s):
        if isinstance(v, float):
            assert math.isfinite(v) and float(f"{v:.12g}") == v, (k, v)
    assert s["groups"]["take_up"]["phase_deg"] == -58.0  # the model file's take-up phase, exactly


def test_analyze_states_the_speed_and_the_relative_residual(quick_start):
    _, runs, _ = quick_start
    head = runs[0].stdout.splitlines()[0]
    assert head.startswith("JB1-3: 72 positions every 5° at 1000 rpm")
    assert "residual (relative)" in runs[0].stdout and "friction left out" in runs[0].stdout


@pytest.fixture(scope="module")
def readme_folder(tmp_path_factory):
    """A fresh folder with the README's example files (examples/)."""
    folder = tmp_path_factory.mktemp("readme")
    shutil.copytree(ROOT / "examples", folder / "examples")
    return folder


@pytest.mark.parametrize("argv", COMMANDS, ids=[" ".join(a)[:60] for a in COMMANDS])
def test_every_readme_command_runs(argv, readme_folder, cache):
    res = ok(sewgen_run(argv, readme_folder, cache))
    if "--help" not in argv and "--version" not in argv and "--quiet" not in argv:
        assert res.stdout.strip(), argv
    csv_arg = argv[argv.index("--csv") + 1] if "--csv" in argv else None
    if csv_arg:
        assert (readme_folder / csv_arg).stat().st_size > 1000


@pytest.mark.parametrize("k", range(len(_blocks("python"))))
def test_every_readme_python_example_runs(k, readme_folder, cache):
    code = _blocks("python")[k]
    res = subprocess.run([sys.executable, "-c", code], cwd=readme_folder, capture_output=True, text=True,
                         env=dict(os.environ, SEWGEN_CACHE=str(cache)), timeout=600)
    assert res.returncode == 0, f"python block {k} of README.md and docs/:\n{code}\n{res.stderr}"


def test_the_readme_quotes_what_the_balance_command_prints(readme_folder, cache):
    m = re.search(r"the second command above prints K = ([0-9.]+), ([0-9.]+) N\s+peak and objective ([0-9.]+)",
                  "\n".join(DOCS))
    assert m, "the docs' balancing numbers (docs/how-to/balancing.md)"
    argv = [a for a in COMMANDS if a[:1] == ["balance"] and "--plot" in a][0]
    out = ok(sewgen_run(argv, readme_folder, cache)).stdout
    K, F1, obj = m.groups()
    assert f"optimum K = {K}" in out
    assert re.search(rf"F1 = max \|F\| \(N\)\s+\S+\s+{re.escape(F1)}", out), out
    assert re.search(rf"objective \(N\)\s+\S+\s+{re.escape(obj)}", out), out


# -- conventions ---------------------------------------------------------------------------------------------------

def test_version(tmp_path, cache):
    res = ok(sewgen_run(["--version"], tmp_path, cache))
    assert res.stdout.strip() == f"sewgen {sewgen.__version__}"
    assert re.fullmatch(r"\d+(\.\d+)*\S*", sewgen.__version__)


def test_quiet_prints_nothing_but_writes(tmp_path, cache):
    res = ok(sewgen_run(["kinematics", "take_up", "--csv", "t.csv", "--quiet"], tmp_path, cache))
    assert res.stdout == "" and res.stderr == ""
    assert (tmp_path / "t.csv").stat().st_size > 1000
    assert ok(sewgen_run(["--quiet", "list"], tmp_path, cache)).stdout == ""


def test_both_spellings_name_one_mechanism(tmp_path, cache):
    a = ok(sewgen_run(["kinematics", "take-up"], tmp_path, cache)).stdout
    b = ok(sewgen_run(["kinematics", "take_up"], tmp_path, cache)).stdout
    assert a == b and a.startswith("take_up: ")
    for spelling in ("needle-bar", "needle_bar"):
        ok(sewgen_run(["balance", spelling, "--crank", "16.7 mm", "--rod", "53 mm", "--speed", "6000 rpm",
                       "--mass-b", "39.3 g", "--mass-c", "105.29 g", "--json"], tmp_path, cache))


@pytest.mark.parametrize("argv, words", [
    (["kinematics", "take_up"], "speed 5000 rpm (the mechanism's default"),
    (["kinematics", "needle_bar"], "speed 1000 rpm (the mechanism's default"),
    (["kinematics", "take_up", "--speed", "1200 rpm"], "speed 1200 rpm"),
    (["forces", "take_up"], "speed 5000 rpm (the mechanism's default"),
])
def test_the_header_states_the_speed_used(argv, words, tmp_path, cache):
    head = ok(sewgen_run(argv, tmp_path, cache)).stdout.splitlines()[0]
    assert words in head, head


def test_units_option_converts_tables_and_names_the_units(tmp_path, cache):
    ok(sewgen_run(["kinematics", "take_up", "--csv", "si.csv"], tmp_path, cache))
    res = ok(sewgen_run(["kinematics", "take_up", "--csv", "mm.csv", "--units", "mm,deg"], tmp_path, cache))
    assert "(mm)" in res.stdout and "[deg]" in res.stdout and "(m)" not in res.stdout

    def read(name):
        with open(tmp_path / name, newline="") as fh:
            rows = list(csv.reader(fh))
        return rows[0], np.array(rows[1:], dtype=float)

    h_si, v_si = read("si.csv")
    h_mm, v_mm = read("mm.csv")
    assert "thread_eye.x [m]" in h_si and "thread_eye.x [mm]" in h_mm
    assert "thread_eye.x_d [mm/s]" in h_mm and "rocker.angle [deg]" in h_mm and "phi [deg]" in h_mm
    np.testing.assert_allclose(v_mm[:, h_mm.index("thread_eye.x [mm]")], 1e3 * v_si[:, h_si.index("thread_eye.x [m]")])
    np.testing.assert_allclose(v_mm[:, h_mm.index("rocker.angle [deg]")],
                               np.degrees(v_si[:, h_si.index("rocker.angle [rad]")]))
    params = ok(sewgen_run(["params", "needle_bar", "--units", "mm,deg"], tmp_path, cache)).stdout
    assert re.search(r"\bcrank\s+16\.7 mm", params) or re.search(r"\bcrank\s+\S+ mm", params)


def test_analyze_tables_in_display_units(tmp_path, cache):
    ok(sewgen_run(["analyze", "jb1-3", "--no-plots", "--units", "mm,deg", "--out", "r", "-q"], tmp_path, cache))
    with open(tmp_path / "r" / "needle_bar.csv", newline="") as fh:
        header = next(csv.reader(fh))
    assert "needle_eye.y [mm]" in header and "needle_eye.y_dd [mm/s^2]" in header
    assert not any(h.endswith("[m]") for h in header)


ZERO_MASS = textwrap.dedent('''
    from sewgen.derive import Mechanism

    def declare():
        m = Mechanism("massless_slider", "an offset crank-slider without masses")
        r = m.length("crank", "12 mm", "crank radius")
        l = m.length("rod", "45 mm", "rod length")
        crank = m.driven("crank", pivot=m.ground.at(0, 0))
        rod = m.link("rod")
        block = m.slider("block", guide=m.ground.line(at=(0, 0), angle=0))
        m.revolute(crank.at(r, 0), rod.at(0, 0), name="B")
        m.revolute(rod.at(l, 0), block.at(0, 0), name="C")
        m.point("tip", block.at("10 mm", 0))
        return m
''')


def test_forces_warns_when_every_mass_is_zero(tmp_path, cache):
    (tmp_path / "massless.py").write_text(ZERO_MASS)
    res = ok(sewgen_run(["forces", "--file", "massless.py"], tmp_path, cache))
    warnings = [ln for ln in res.stderr.splitlines() if "warning" in ln]
    assert len(warnings) == 1 and "mass is zero" in warnings[0]
    res = ok(sewgen_run(["forces", "--file", "examples/my_mechanism.py"], ROOT, cache))
    assert "warning" not in res.stderr


# -- mistakes: exit 2, one line naming the culprit ----------------------------------------------------------------

BALANCE = ["balance", "needle_bar", "--crank", "16.7mm", "--rod", "53mm", "--mass-b", "39.3g", "--mass-c",
           "105.29g", "--speed", "6000rpm"]
BAD = [
    # bare numbers are refused for every quantity option, in every command
    (["kinematics", "take_up", "--step", "5"], ["--step", "deg"]),
    (["kinematics", "take_up", "--start", "90"], ["--start", "deg"]),
    (["forces", "take_up", "--step", "5"], ["--step"]),
    (["analyze", "jb1-3", "--step", "5", "--no-plots"], ["--step", "deg"]),
    (["kinematics", "take_up", "--speed", "1000"], ["--speed", "rpm"]),
    (["analyze", "jb1-3", "--speed", "1000", "--no-plots"], ["--speed", "rpm"]),
    (["forces", "take_up", "--gravity", "9.81"], ["--gravity", "m/s**2"]),
    (["kinematics", "take_up", "--param", "crank=5"], ["--param crank", "mm"]),
    (BALANCE + ["--rod", "53"], ["--rod"]),
    # impossible values
    (["analyze", "jb1-3", "--step", "0 deg", "--no-plots"], ["--step", "positive"]),
    (["kinematics", "take_up", "--step", "-5 deg"], ["--step", "positive"]),
    (["analyze", "jb1-3", "--speed", "0 rpm", "--no-plots"], ["--speed", "positive"]),
    (["kinematics", "take_up", "--speed", "-100 rpm"], ["--speed", "positive"]),
    (["kinematics", "take_up", "--step", "7 deg"], ["--step", "7", "6 deg", "7.2 deg"]),
    (["analyze", "jb1-3", "--step", "7 deg", "--no-plots"], ["--step", "7", "6 deg", "7.2 deg"]),
    (["kinematics", "take_up", "--step", "1e-6 deg"], ["--step", "100,000"]),
    (["analyze", "jb1-3", "--step", "1e-6 deg", "--no-plots"], ["--step", "100,000"]),
    (BALANCE + ["--points", "1000000000"], ["--points", "100,000"]),
    (BALANCE + ["--points", "many"], ["--points"]),
    (["kinematics", "needle_bar", "--branch", "C=1.0"], ["--branch", "C=1.0"]),
    (["kinematics", "needle_bar", "--branch", "C=x"], ["--branch", "C=x"]),
    (["kinematics", "needle_bar", "--branch", "Z=1"], ["--branch", "Z"]),
    (["kinematics", "needle_bar", "--param", "nothing=1 mm"], ["--param", "nothing"]),
    (["kinematics", "needle_bar", "--param", "crank"], ["--param", "crank"]),
    (["forces", "needle_bar", "--load", ""], ["--load"]),
    (["forces", "needle_bar", "--load", "needle_eye fy=-3"], ["--load fy", "N"]),
    (["forces", "needle_bar", "--load", "needle_eye fy=-3N from=10deg"], ["--load", "to="]),
    (["forces", "needle_bar", "--load", "nowhere fy=-3N"], ["nowhere"]),
    (["kinematics", "take_up", "--units", "rpm"], ["--units", "rpm"]),
    (["forces", "take_up", "--gravity", "1e308 m/s**2"], ["--gravity", "at most 100 m/s**2"]),  # printed inf
    (["kinematics", "take_up", "--start", "1e300 deg"], ["--start", "1e300 deg"]),  # was 72 positions in one
    (["forces", "needle_bar", "--param", "crank.mass=35 gr"], ["--param crank.mass", '"gr"']),  # was 2.27 g
    (["kinematics", "take_up", "--units", "mm,mm"], ["--units"]),
    # strict quantity strings
    (["kinematics", "take_up", "--param", "crank=1,5 mm"], ["--param crank", "1,5 mm"]),
    (["kinematics", "take_up", "--param", "crank=16,7 mm"], ["--param crank", "16,7 mm"]),
    (["kinematics", "take_up", "--param", "crank=mm"], ["--param crank", '"mm"']),
    (["kinematics", "take_up", "--param", "crank=🧵 mm"], ["--param crank", "🧵 mm"]),
    (["kinematics", "take_up", "--speed", ""], ["--speed", "empty"]),
    (["kinematics", "take_up", "--speed", "1,000 rpm"], ["--speed", "1,000 rpm"]),
    (BALANCE + ["--crank", "1,5 mm"], ["--crank", "1,5 mm"]),
    # names
    (["params"], ["name a mechanism", "take_up"]),
    (["kinematics"], ["name a mechanism"]),
    (["forces"], ["name a mechanism"]),
    (["kinematics", "needle_bars"], ["needle_bars", "needle_bar"]),
    (["kinematics", "take_up", "--file", "examples/my_mechanism.py"], ["--file", "not both"]),
    (["balance", "hook_drive", "--crank", "16.7mm"], ["hook_drive", "needle_bar"]),
    (["analyze", "jb9-9", "--no-plots"], ["jb9-9", "jb1-3"]),
    (["analyze", "nowhere.toml", "--no-plots"], ["nowhere.toml", "no such model file"]),
    (["kinematics", "--file", "nowhere.py"], ["--file", "nowhere.py"]),
    (["frobnicate"], ["frobnicate"]),
    (["kinematics", "take_up", "--stpe", "5 deg"], ["--stpe"]),
    # output paths
    (["analyze", "jb1-3", "--out", "a_file", "--no-plots"], ["--out", "a_file"]),
    (["analyze", "jb1-3", "--out", "no/such/folder/out", "--no-plots"], ["--out", "no/such/folder"]),
    (["kinematics", "take_up", "--csv", "/nonexistent/dir/x.csv"], ["--csv", "/nonexistent/dir"]),
    (["kinematics", "take_up", "--csv", "a_folder"], ["--csv", "a_folder", "folder"]),
    (["forces", "take_up", "--csv", "a_folder"], ["--csv", "a_folder"]),
    (BALANCE + ["--plot", "x.txt"], ["--plot", ".txt"]),
    (BALANCE + ["--plot", "a_folder"], ["--plot", "a_folder", "folder"]),
    (BALANCE + ["--plot", "no/such/folder/nb.png"], ["--plot", "no/such/folder"]),
    (BALANCE + ["--plot", "-"], ["--plot", "standard output"]),
    (["analyze", "jb1-3", "--out", "-", "--no-plots"], ["--out", "standard output"]),
    # names the file system cannot take (ENAMETOOLONG), and a folder that is not there
    (["kinematics", "take_up", "--csv", "c" * 300 + ".csv"], ["--csv", "File name too long"]),
    (["analyze", "jb1-3", "--out", "o" * 300, "--no-plots"], ["--out", "File name too long"]),
    (["analyze", "m" * 300, "--no-plots"], ["m" * 300, "too long"]),
    (["analyze", "m" * 300 + ".toml", "--no-plots"], ["too long"]),
    (["kinematics", "--file", "d" * 300 + ".py"], ["--file", "too long"]),
    (["balance", "machine", "jb1-3", "--write-model", "nodir/b.toml"], ["--write-model", "nodir"]),
    (["balance", "machine", "jb1-3", "--write-model", "w" * 300 + ".toml"], ["--write-model", "too long"]),
    (["study", "tolerance", "jb1-3", "--tolerance", "groups.needle_bar.params.rod=±0.02mm", "--samples", "2",
      "--seed", "-1", "--out", "st", "--no-plots"], ["--seed", "-1"]),
]
if Path("/proc").is_dir() and sys.platform.startswith("linux"):
    BAD.append((["kinematics", "take_up", "--csv", "/proc/x.csv"], ["--csv", "/proc/x.csv"]))


def _concurrently(jobs: dict) -> dict:
    """{key: CompletedProcess} of ``jobs`` ({key: zero-argument callable}), run a few at a time (each is a fresh
    process: the wall time is start-up, not work)."""
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(max_workers=max(2, min(8, 2 * (os.cpu_count() or 1)))) as pool:
        futures = {key: pool.submit(job) for key, job in jobs.items()}
        return {key: f.result() for key, f in futures.items()}


@pytest.fixture(scope="module")
def mistakes(tmp_path_factory, cache):
    """Every command of BAD run once in one folder: (folder, names before, {index: result})."""
    folder = tmp_path_factory.mktemp("mistakes")
    (folder / "a_file").write_text("not a folder\n")
    (folder / "a_folder").mkdir()
    shutil.copytree(ROOT / "examples", folder / "examples")
    before = sorted(p.name for p in folder.iterdir())
    results = _concurrently({k: (lambda argv=argv: sewgen_run(argv, folder, cache)) for k, (argv, _) in
                             enumerate(BAD)})
    return folder, before, results


@pytest.mark.parametrize("k", range(len(BAD)), ids=[" ".join(a)[:70] for a, _ in BAD])
def test_a_mistake_is_one_line_naming_it(k, mistakes):
    _, _, results = mistakes
    refused(results[k], *BAD[k][1])


def test_mistakes_write_nothing(mistakes):
    folder, before, _ = mistakes
    assert sorted(p.name for p in folder.iterdir()) == before  # nothing written, nothing half-written
    assert sorted(p.name for p in (folder / "a_folder").iterdir()) == []


def test_balance_plot_without_an_extension_is_a_png(tmp_path, cache):
    res = ok(sewgen_run(BALANCE + ["--plot", "nb"], tmp_path, cache))
    assert (tmp_path / "nb.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "plot: nb.png" in res.stdout


def test_a_syntax_error_in_a_declaration_names_file_and_line(tmp_path, cache):
    (tmp_path / "broken.py").write_text("from sewgen.derive import Mechanism\n\ndef declare(:\n    pass\n")
    line = refused(sewgen_run(["kinematics", "--file", "broken.py"], tmp_path, cache), "--file", "broken.py:3")
    assert "syntax" in line
    (tmp_path / "raises.py").write_text("def declare():\n    return 1 / 0\n")
    refused(sewgen_run(["kinematics", "--file", "raises.py"], tmp_path, cache), "raises.py:2", "ZeroDivisionError")
    (tmp_path / "latin1.py").write_bytes(b"# caf\xe9\ndef declare():\n    pass\n")
    refused(sewgen_run(["kinematics", "--file", "latin1.py"], tmp_path, cache), "latin1.py")


# -- model files ---------------------------------------------------------------------------------------------------

def _edit(old: str, new: str, text: str = MODEL) -> str:
    assert text.count(old) == 1, old
    return text.replace(old, new)


BAD_MODELS = [
    ("group_machine", _edit("[groups.needle_bar]", "[groups.machine]").replace("groups.needle_bar.", "groups.machine."),
     ["groups.machine", "reserved"]),
    ("group_summary", _edit("[groups.take_up]", "[groups.summary]").replace("groups.take_up.", "groups.summary."),
     ["groups.summary", "reserved"]),
    ("group_not_identifier",
     _edit("[groups.feed]", '[groups."feed dog"]').replace("groups.feed.", 'groups."feed dog".'),
     ["groups.feed dog", "identifier"]),
    ("name_escapes", _edit('name = "JB1-3"', 'name = "../ESCAPED"'), ["machine.name", "../ESCAPED"]),
    ("name_path", _edit('name = "JB1-3"', 'name = "a/b"'), ["machine.name"]),
    ("negative_shaft_mass", _edit('mass = "250 g"', 'mass = "-250 g"'), ["shaft.mass", "negative"]),
    ("negative_shaft_inertia", _edit('inertia = "2.0e-5 kg*m**2"', 'inertia = "-2.0e-5 kg*m**2"'),
     ["shaft.inertia", "negative"]),
    ("negative_counterweight", _edit('mass = "20 g"', 'mass = "-20 g"'), ["shaft.masses[0].mass", "negative"]),
    ("negative_group_mass", _edit('"crank.mass" = "35 g"', '"crank.mass" = "-35 g"'),
     ["groups.needle_bar.params.crank.mass", "negative"]),
    ("speed_zero", _edit('speed = "1000 rpm"', 'speed = "0 rpm"'), ["machine.speed", "positive"]),
    ("comma", _edit('rod = "50 mm"', 'rod = "5,0 mm"'), ["groups.needle_bar.params.rod", "5,0 mm"]),
    ("unit_only", _edit('rod = "50 mm"', 'rod = "mm"'), ["groups.needle_bar.params.rod"]),
    ("bare_number", _edit('rod = "50 mm"', 'rod = "50"'), ["groups.needle_bar.params.rod", "no unit"]),
    ("huge_mass", _edit('mass = "20 g"', 'mass = "1e307 kg"'), ["not finite"]),
    ("cannot_assemble", _edit('rod = "50 mm"', 'rod = "10 mm"'), ["groups.needle_bar"]),
    ("step", _edit('step = "5 deg"', 'step = "7 deg"'), ["machine.step", "7"]),
    ("nested", MODEL + "\nnested = " + "[" * 2000 + "]" * 2000 + "\n", ["nested too deeply"]),
    ("guide_point", _edit('point = "thread_eye"', 'point = "nowhere"'), ["thread.guides[1].point", "nowhere"]),
    ("group_Machine", _edit("[groups.needle_bar]", "[groups.Machine]").replace("groups.needle_bar.", "groups.Machine."),
     ["groups.Machine", "reserved"]),
]


@pytest.fixture(scope="module")
def bad_models(tmp_path_factory, cache):
    """Every model of BAD_MODELS analysed in a folder of its own: {name: (folder, result)}."""
    folders = {}
    for name, text, _ in BAD_MODELS:
        folders[name] = tmp_path_factory.mktemp(f"model_{name}")
        (folders[name] / f"{name}.toml").write_text(text, encoding="utf-8")
    results = _concurrently({name: (lambda name=name: sewgen_run(["analyze", f"{name}.toml", "--out", "out",
                                                                   "--no-gif"], folders[name], cache))
                             for name in folders})
    return {name: (folders[name], results[name]) for name in folders}


@pytest.mark.parametrize("name, culprits", [(b[0], b[2]) for b in BAD_MODELS], ids=[b[0] for b in BAD_MODELS])
def test_a_bad_model_file_is_one_line_naming_file_and_key(name, culprits, bad_models):
    folder, res = bad_models[name]
    refused(res, f"{name}.toml", *culprits)
    assert sorted(p.name for p in folder.iterdir()) == [f"{name}.toml"]  # no output, not even half of one
    assert not (folder.parent / "ESCAPED").exists()


def test_a_model_file_that_is_not_utf8(tmp_path, cache):
    (tmp_path / "latin1.toml").write_bytes(MODEL.replace("JB1-3 household", "JB1-3 m\u00e9nage").encode("latin-1",
                                                                                                   "replace"))
    refused(sewgen_run(["analyze", "latin1.toml", "--no-plots"], tmp_path, cache), "latin1.toml", "UTF-8")


def test_a_failed_run_leaves_a_previous_result_untouched(tmp_path, cache):
    ok(sewgen_run(["analyze", "jb1-3", "--no-plots", "--out", "res", "-q"], tmp_path, cache))
    before = {p.name: p.read_bytes() for p in (tmp_path / "res").iterdir()}
    (tmp_path / "bad.toml").write_text(_edit('rod = "50 mm"', 'rod = "10 mm"'), encoding="utf-8")
    refused(sewgen_run(["analyze", "bad.toml", "--no-plots", "--out", "res"], tmp_path, cache), "bad.toml")
    assert {p.name: p.read_bytes() for p in (tmp_path / "res").iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml", "res"]


def test_a_user_model_file_is_named_relative(tmp_path, cache):
    (tmp_path / "models").mkdir()
    (tmp_path / "models" / "mine.toml").write_text(MODEL, encoding="utf-8")
    ok(sewgen_run(["analyze", "models/mine.toml", "--no-plots", "--out", "res", "-q"], tmp_path, cache))
    s = json.loads((tmp_path / "res" / "summary.json").read_text(encoding="utf-8"))
    assert s["model_file"] == "models/mine.toml"
    ok(sewgen_run(["analyze", str(tmp_path / "models" / "mine.toml"), "--no-plots", "--out", "res", "-q"],
                  tmp_path / "models", cache))
    s = json.loads((tmp_path / "models" / "res" / "summary.json").read_text(encoding="utf-8"))
    assert s["model_file"] == "mine.toml"
    assert "Infinity" not in (tmp_path / "res" / "summary.json").read_text(encoding="utf-8")


# -- the same contract from Python ---------------------------------------------------------------------------------

def test_regulator_angle_takes_a_quantity_and_refuses_a_stitch_out_of_range():
    from sewgen.errors import ParameterError
    from sewgen.machine.feed import regulator_angle

    feed = sewgen.mechanism(next(n for n in sewgen.catalog() if sewgen.mechanism(n).description.has_role(
        "stitch_regulator")))
    assert regulator_angle(feed, "4 mm") == pytest.approx(regulator_angle(feed, 0.004), abs=1e-12)
    with pytest.raises(ParameterError) as exc:
        regulator_angle(feed, "10 mm")
    assert exc.value.parameter == "stitch" and "10 mm" in str(exc.value) and "range" in str(exc.value)
    with pytest.raises(ParameterError):
        regulator_angle(feed, "1,5 mm")


def test_main_in_process_returns_2_for_a_mistake(capsys):
    from sewgen.cli.main import main

    assert main(["kinematics", "take_up", "--step", "5"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "--step" in err


def test_a_broken_group_declaration_names_model_key_file_and_line(tmp_path, cache):
    (tmp_path / "mine.py").write_text("def declare(:\n    pass\n")
    (tmp_path / "m.toml").write_text(_edit('mechanism = "needle_bar"', 'mechanism = "mine.py"'), encoding="utf-8")
    refused(sewgen_run(["analyze", "m.toml", "--no-plots"], tmp_path, cache), "m.toml",
            "groups.needle_bar.mechanism", "mine.py:1", "syntax error")


# -- exit statuses: a mistake 2, a machine failing its rules 3, a bug of sewgen 1 ----------------------------------

def test_a_bug_of_sewgen_is_a_traceback_and_exit_1_never_a_users_one_line(monkeypatch, capsys):
    """Only sewgen's typed errors are a user's mistake: a KeyError inside sewgen (a bug) keeps its traceback."""
    from sewgen.cli import mechanism as cli_mechanism
    from sewgen.cli.main import main

    def buggy(args, con):
        return {}["nowhere"]

    monkeypatch.setattr(cli_mechanism, "cmd_list", buggy)
    assert main(["list"]) == 1
    out, err = capsys.readouterr()
    assert out == "" and "Traceback" in err and "KeyError: 'nowhere'" in err and "in buggy" in err
    assert err.splitlines()[-1].startswith("sewgen: internal error") and "report" in err.splitlines()[-1]


def test_debug_shows_where_a_mistake_was_raised(capsys):
    from sewgen.cli.main import main

    assert main(["--debug", "kinematics", "take_up", "--step", "5"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and "Traceback" in err and "UsageError" in err
    assert err.splitlines()[-1].startswith("sewgen: --step: ")
    assert main(["kinematics", "take_up", "--step", "5", "--debug"]) == 2
    assert "Traceback" in capsys.readouterr().err


def test_analyze_says_its_verdict_and_exits_3_when_a_rule_fails(tmp_path, cache):
    """The hook drive turned 40° late (the hook meets the needle far from the 1.8-2.5 mm rise its rule asks):
    the analysis is written, stdout counts the rules that pass, stderr names each failing one, exit status 3."""
    (tmp_path / "late.toml").write_text(_edit('phase = "-2 deg"', 'phase = "38 deg"'), encoding="utf-8")
    res = sewgen_run(["analyze", "late.toml", "--no-plots", "--out", "late"], tmp_path, cache)
    assert res.returncode == 3 and "Traceback" not in res.stderr, res.stderr
    summary = json.loads((tmp_path / "late" / "summary.json").read_text(encoding="utf-8"))
    failed = [c for c in summary["timing"]["checks"] if not c["ok"]]
    assert failed and "hook_at_needle_rise" in [c["rule"] for c in failed]
    hook = next(c for c in failed if c["rule"] == "hook_at_needle_rise")
    assert not 1.8 <= hook["value"] <= 2.5
    n = len(summary["timing"]["checks"])
    assert f"timing: {n - len(failed)} of {n} rules pass; failing: " in res.stdout
    warnings = [ln for ln in res.stderr.splitlines() if ln.startswith("sewgen: warning: JB1-3 fails the timing rule")]
    assert len(warnings) == len(failed) and "hook_at_needle_rise" in res.stderr


def test_a_rule_whose_parts_are_missing_names_them(tmp_path, cache):
    """JB1-3 without its feed group: the dog rules and the stitch-setting rule cannot be checked — they fail, each
    naming the roles no group plays (feed_dog, throat_plate) and the machine's groups; no NaN anywhere."""
    start = MODEL.index("[groups.feed]")
    end = MODEL.index("[[shaft.counterweights]]")
    text = MODEL[:start] + MODEL[end:]
    (tmp_path / "nofeed.toml").write_text(text, encoding="utf-8")
    res = sewgen_run(["analyze", "nofeed.toml", "--no-plots", "--out", "nofeed"], tmp_path, cache)
    assert res.returncode == 3, res.stderr
    checks = {c["rule"]: c for c in json.loads((tmp_path / "nofeed" / "summary.json").read_text())["timing"]["checks"]}
    for rule, roles in (("dog_sinks_before_needle_enters", "feed_dog, throat_plate"),
                        ("dog_rises_after_needle_leaves", "feed_dog, throat_plate"),
                        ("stitch_set_before_needle_enters", "throat_plate")):
        assert checks[rule]["ok"] is False and checks[rule]["value"] is None
        assert f"no group has a part with the role{'s' if ',' in roles else ''} {roles} (groups: needle_bar, " \
               f"take_up, hook_drive)" in checks[rule]["message"]
    assert sum(not c["ok"] for c in checks.values()) == 3
    assert "nan" not in res.stderr.lower() and "timing: 9 of 12 rules pass" in res.stdout

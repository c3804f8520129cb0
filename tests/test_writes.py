"""Writes that never destroy or mix files (sewgen.files): a full or read-only disk, a target that is not a regular
file, sewgen's own package, a folder rewritten by a second run.

A full disk is simulated by the file objects Python opens for writing in the test's folder: each write puts half
of its data on the disk and then fails with ENOSPC, as the kernel does when the disk fills up; a read-only file
system fails the opening itself (EROFS). Whatever the writer, the file that was there must be there unchanged,
the user gets one typed line naming the file (exit status 2) and nothing half-written is left beside it.
"""
from __future__ import annotations

import builtins
import errno
import io
import json
import os
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import sewgen
from sewgen.cli.main import main
from sewgen.machine.modelfile import MODELS_DIR

pytestmark = pytest.mark.c

JB = (MODELS_DIR / "jb1-3.toml").read_text(encoding="utf-8")


class _FullDisk:
    """A file open for writing on a disk that fills up: every write stores half its data, then raises ENOSPC."""

    def __init__(self, fh):
        self._fh = fh

    def write(self, data):
        self._fh.write(data[: len(data) // 2])
        self._fh.flush()
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    def writelines(self, lines):
        for line in lines:
            self.write(line)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._fh.close()

    def __iter__(self):
        return iter(self._fh)

    def __getattr__(self, name):
        return getattr(self._fh, name)


def _where(file) -> Path | None:
    if isinstance(file, int):
        try:
            return Path(os.readlink(f"/proc/self/fd/{file}"))
        except OSError:
            return None
    try:
        return Path(os.path.realpath(os.fspath(file)))
    except TypeError:
        return None


def broken_disk(monkeypatch, folder: Path, how: str) -> None:
    """Files opened for writing under ``folder`` from now on: ``how`` = "full" (writes fail with ENOSPC after
    half their data) or "read-only" (opening fails with EROFS)."""
    real_open = io.open
    folder = Path(os.path.realpath(folder))

    def fake_open(file, mode="r", *args, **kwargs):
        path = _where(file)
        writing = any(c in mode for c in "wax+")
        if not (writing and path is not None and path.is_relative_to(folder)):
            return real_open(file, mode, *args, **kwargs)
        if how == "read-only":
            if isinstance(file, int):
                os.close(file)
            raise OSError(errno.EROFS, os.strerror(errno.EROFS), str(path))
        return _FullDisk(real_open(file, mode, *args, **kwargs))

    monkeypatch.setattr(io, "open", fake_open)
    monkeypatch.setattr(builtins, "open", fake_open)


def snapshot(folder: Path) -> dict:
    """Every entry under ``folder``: name -> bytes of a regular file, "link -> target", or its kind."""
    out = {}
    for p in sorted(folder.rglob("*")):
        key = str(p.relative_to(folder))
        if p.is_symlink():
            out[key] = f"link -> {os.readlink(p)}"
        elif p.is_file():
            out[key] = p.read_bytes()
        else:
            out[key] = stat.filemode(p.lstat().st_mode)
    return out


def one_line(capsys, *culprits) -> str:
    out, err = capsys.readouterr()
    assert out == "", out
    lines = err.splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    for c in culprits:
        assert c in lines[0], (c, lines[0])
    return lines[0]


# -- one file: the model file balancing writes, a table, the API -----------------------------------------------

@pytest.mark.parametrize("how, words", [("full", "No space left on device"), ("read-only", "Read-only file system")])
def test_write_model_over_itself_on_a_broken_disk_keeps_the_model(how, words, tmp_path, monkeypatch, capsys):
    (tmp_path / "my.toml").write_text(JB, encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    before = snapshot(tmp_path)
    broken_disk(monkeypatch, tmp_path, how)
    assert main(["balance", "machine", "my.toml", "--write-model", "my.toml", "--method", "separate"]) == 2
    one_line(capsys, "--write-model", "my.toml", words)
    assert snapshot(tmp_path) == before  # the model whole, nothing half-written beside it


def test_balance_out_on_a_full_disk_keeps_the_previous_results(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["balance", "machine", "jb1-3", "--method", "separate", "--out", "bal", "-q"]) == 0
    written = snapshot(tmp_path / "bal")
    assert {"balance.json", "bearings.csv", "speeds.csv", "balance.png"} <= set(written)
    counterweights = json.loads(written["balance.json"])["counterweights"]
    assert len(counterweights) == 3
    capsys.readouterr()
    broken_disk(monkeypatch, tmp_path, "full")
    assert main(["balance", "machine", "jb1-3", "--method", "harmonic", "--out", "bal"]) == 2
    one_line(capsys, "--out", "No space left on device")
    assert snapshot(tmp_path / "bal") == written
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bal"]


def test_a_table_on_a_full_disk_is_a_typed_error_and_the_old_file_stays(tmp_path, monkeypatch):
    from sewgen.errors import OutputPathError

    motion = sewgen.mechanism("needle_bar").solve(sewgen.shaft_angles(30))
    motion.to_csv(tmp_path / "nb.csv")
    before = snapshot(tmp_path)
    rows = (tmp_path / "nb.csv").read_text().splitlines()
    assert len(rows) == 1 + 12  # header and 12 positions
    broken_disk(monkeypatch, tmp_path, "full")
    with pytest.raises(OutputPathError) as exc:
        sewgen.mechanism("needle_bar").solve(sewgen.shaft_angles(5)).to_csv(tmp_path / "nb.csv")
    assert exc.value.file == str(tmp_path / "nb.csv") and "No space left on device" in exc.value.problem
    assert snapshot(tmp_path) == before


def test_write_model_never_rewrites_the_built_in_model(capsys):
    builtin = MODELS_DIR / "jb1-3.toml"
    before = builtin.read_bytes()
    assert main(["balance", "machine", "jb1-3", "--write-model", str(builtin)]) == 2
    one_line(capsys, "--write-model", str(builtin), "installed package")
    assert builtin.read_bytes() == before


def test_nothing_is_written_inside_the_package():
    from sewgen.errors import OutputPathError
    from sewgen.files import PACKAGE_DIR, write_text

    assert PACKAGE_DIR == Path(sewgen.__file__).resolve().parent
    for target in (MODELS_DIR / "jb1-3.toml", MODELS_DIR / "new.toml", PACKAGE_DIR / "x.txt"):
        existed = target.read_bytes() if target.exists() else None
        with pytest.raises(OutputPathError) as exc:
            write_text(target, "nothing")
        assert str(target) in str(exc.value) and "installed package" in exc.value.problem
        assert (target.read_bytes() if target.exists() else None) == existed


def test_balancing_a_balanced_model_again_is_refused_not_doubled(tmp_path, monkeypatch, capsys):
    """The counterweights written into a model sit on its planes: a second run would add a second counterweight
    on each plane (more than its max_mass), so it is refused and the model stays as the first run wrote it."""
    (tmp_path / "my.toml").write_text(JB, encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    assert main(["balance", "machine", "my.toml", "--write-model", "my.toml", "--method", "separate", "-q"]) == 0
    once = (tmp_path / "my.toml").read_text(encoding="utf-8")
    assert once.startswith(JB.rstrip("\n")) and once.count("[[shaft.masses]]") == JB.count("[[shaft.masses]]") + 3
    capsys.readouterr()
    assert main(["balance", "machine", "my.toml", "--write-model", "my.toml", "--method", "separate"]) == 2
    one_line(capsys, "my.toml", "needle_crank_cw", "shaft.masses")
    assert (tmp_path / "my.toml").read_text(encoding="utf-8") == once


def test_balance_machine_is_quiet_when_asked(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["balance", "machine", "jb1-3", "--method", "separate", "--quiet"]) == 0
    assert capsys.readouterr() == ("", "")
    assert main(["balance", "machine", "jb1-3", "--method", "separate"]) == 0
    assert "needle_crank_cw" in capsys.readouterr().out


# -- targets that are not regular files ---------------------------------------------------------------------------

def test_a_fifo_is_refused_and_stays_a_fifo(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    os.mkfifo("pipe.csv")
    assert main(["kinematics", "take_up", "--csv", "pipe.csv"]) == 2
    one_line(capsys, "--csv", "pipe.csv", "FIFO")
    assert stat.S_ISFIFO(os.lstat("pipe.csv").st_mode) and sorted(os.listdir()) == ["pipe.csv"]


def test_devices_and_folders_are_refused_before_any_work():
    from sewgen.errors import OutputPathError
    from sewgen.files import check_file

    for target, words in (("/dev/null", "device"), (os.getcwd(), "folder")):
        with pytest.raises(OutputPathError) as exc:
            check_file(target, "--csv")
        assert exc.value.parameter == "--csv" and words in exc.value.problem


def test_a_symlink_is_written_through_and_stays_a_link(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "runs").mkdir()
    (tmp_path / "runs" / "t.csv").write_text("old\n")
    os.symlink("runs/t.csv", "latest.csv")
    assert main(["kinematics", "take_up", "--csv", "latest.csv", "--step", "30 deg", "-q"]) == 0
    assert os.readlink("latest.csv") == "runs/t.csv"  # the link kept, the file it names replaced
    rows = (tmp_path / "runs" / "t.csv").read_text().splitlines()
    assert len(rows) == 1 + 12 and rows[0].startswith("phi [rad],")


def test_csv_dash_is_the_table_on_stdout_alone(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["kinematics", "needle_bar", "--step", "30 deg", "--csv", "-"]) == 0
    out, err = capsys.readouterr()
    assert err == "" and os.listdir() == []  # no file named "-"
    rows = [r.split(",") for r in out.splitlines()]
    assert len(rows) == 1 + 12
    header, values = rows[0], np.array(rows[1:], dtype=float)
    # the needle eye's height from the offset crank-slider's closed form (the bar below the crank, branch C = -1):
    # y = r sin(phi) - sqrt(l^2 - (e - r cos(phi))^2) - h
    nb = sewgen.mechanism("needle_bar")
    p = dict(zip(nb.param_names, nb.param_vector()))
    phi = values[:, header.index("phi [rad]")]
    y = values[:, header.index("needle_eye.y [m]")]
    r, rod, e, h = p["crank"], p["rod"], p["offset"], p["eye_below_pin"]
    np.testing.assert_allclose(y, r * np.sin(phi) - np.sqrt(rod**2 - (e - r * np.cos(phi)) ** 2) - h, atol=1e-12)


# -- folders: one run each --------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def jb_runs():
    """JB1-3 analysed at 1000 and at 1500 rpm (12 positions)."""
    from sewgen.machine import load_machine

    jb = load_machine("jb1-3")
    phi = jb.shaft_angles(np.radians(30))
    return jb.analyze(phi), jb.analyze(phi, speed=1500 * np.pi / 30)


def test_a_failure_while_files_move_in_leaves_the_old_run_whole(tmp_path, jb_runs, monkeypatch):
    """The third rename into the folder fails (EIO): the files already moved go back, the folder is the old run's."""
    from sewgen.errors import OutputPathError
    from sewgen.report.outputs import write_report

    slow, fast = jb_runs
    write_report(slow, tmp_path / "r")
    before = snapshot(tmp_path)
    folder = Path(os.path.realpath(tmp_path / "r"))
    real_replace, into = os.replace, []

    def failing_replace(src, dst, **kw):
        if Path(dst).parent == folder:
            into.append(Path(dst).name)
            if len(into) == 3:
                raise OSError(errno.EIO, os.strerror(errno.EIO))
        return real_replace(src, dst, **kw)

    monkeypatch.setattr(os, "replace", failing_replace)
    with pytest.raises(OutputPathError) as exc:
        write_report(fast, tmp_path / "r")
    assert "Input/output error" in exc.value.problem and len(into) >= 3  # (and the moves back)
    assert snapshot(tmp_path) == before
    speed = json.loads((tmp_path / "r" / "summary.json").read_text())["speed_rpm"]
    assert speed == 1000.0


def test_a_second_run_replaces_the_first_runs_set(tmp_path, jb_runs):
    """Files of the run before that this run does not write are removed; files sewgen did not write stay."""
    from sewgen.files import staged_folder
    from sewgen.report.outputs import write_report

    slow, fast = jb_runs
    with staged_folder(tmp_path / "r") as tmp:
        (tmp / "trajectories.png").write_bytes(b"\x89PNG picture of the first run")
        (tmp / "summary.json").write_text("{}")
    (tmp_path / "r" / "notes.txt").write_text("mine")
    write_report(fast, tmp_path / "r")
    names = sorted(p.name for p in (tmp_path / "r").iterdir())
    groups = [g.name for g in fast.machine.groups]
    assert names == sorted([".sewgen-run.json", "machine.csv", "notes.txt", "summary.json", "timing.txt",
                            *(f"{g}.csv" for g in groups)])
    assert json.loads((tmp_path / "r" / "summary.json").read_text())["speed_rpm"] == 1500.0
    assert (tmp_path / "r" / "notes.txt").read_text() == "mine"


@pytest.mark.cli
@pytest.mark.plots
def test_analyze_again_without_plots_leaves_no_picture_of_the_first_run(tmp_path):
    def run(*args):
        return subprocess.run([sys.executable, "-m", "sewgen", "analyze", "jb1-3", "--out", "r", "--step",
                               "10 deg", *args], cwd=tmp_path, capture_output=True, text=True, timeout=600)

    first = run("--no-gif", "-q")
    assert first.returncode == 0, first.stderr
    assert (tmp_path / "r" / "trajectories.png").stat().st_size > 1000
    second = run("--no-plots", "--speed", "1500 rpm", "-q")
    assert second.returncode == 0, second.stderr
    names = {p.name for p in (tmp_path / "r").iterdir()}
    assert not any(n.endswith((".png", ".gif")) for n in names), names
    assert json.loads((tmp_path / "r" / "summary.json").read_text())["speed_rpm"] == 1500.0

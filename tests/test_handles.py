"""Handles: Mechanism, Motion, ForceAnalysis, Machine and MachineAnalysis pickle and
cross processes bit for bit; one Mechanism is swept from many threads at once; ``out=`` reuses a result's
arrays and nothing else; the user-mechanism cache survives two processes building at once and a corrupted
shared object.

Whatever loads a cache entry that this test then corrupts runs in its own process (tests/handles_worker.py):
truncating a shared object that a process has mapped would crash that process, which must not be pytest.
"""
from __future__ import annotations

import concurrent.futures as cf
import dataclasses
import json
import multiprocessing
import os
import pickle
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import sewgen
from sewgen.engine.loader import resolve
from sewgen.machine.assembly import load_machine

pytestmark = [pytest.mark.c, pytest.mark.derive, pytest.mark.cli, pytest.mark.slow]

HERE = Path(__file__).resolve().parent
WORKER = HERE / "handles_worker.py"

FOUR_BAR_SOURCE = textwrap.dedent('''
    from sewgen.derive.model import Mechanism


    def declare():
        m = Mechanism("handles_four_bar", "crank-rocker with a coupler point (tests/test_handles.py)")
        r = m.length("crank", "12 mm", "crank AB")
        l2 = m.length("coupler", "45 mm", "coupler BC")
        l3 = m.length("rocker", "35 mm", "rocker DC")
        dx = m.length("pivot_x", "40 mm", "pivot D, x", signed=True)
        dy = m.length("pivot_y", "-8 mm", "pivot D, y", signed=True)
        pu = m.length("point_u", "20 mm", "coupler point P, u", signed=True)
        pv = m.length("point_v", "12 mm", "coupler point P, v", signed=True)
        crank = m.driven("crank", pivot=m.ground.at(0, 0), doc="input crank")
        coupler = m.link("coupler", doc="coupler BC", guess="30 deg")
        rocker = m.link("rocker", doc="rocker DC", guess="100 deg")
        m.revolute(crank.at(r, 0), coupler.at(0, 0), name="B")
        m.revolute(m.ground.at(dx, dy), rocker.at(0, 0), name="D")
        m.revolute(coupler.at(l2, 0), rocker.at(l3, 0), name="C")
        m.point("crank_pin", crank.at(r, 0), "B")
        m.point("coupler_point", coupler.at(pu, pv), "P")
        return m
''')

PHI = sewgen.shaft_angles(5)


def _arrays(result) -> list[np.ndarray]:
    """Every array of a Motion or ForceAnalysis."""
    if isinstance(result, sewgen.ForceAnalysis):
        return _arrays(result.motion) + [result.frc]
    return [result.phi, result.omega, result.alpha, result.q, result.qd, result.qdd, result.obs]


def _same(a, b) -> bool:
    xs, ys = _arrays(a), _arrays(b)
    return len(xs) == len(ys) and all(x.dtype == y.dtype and np.array_equal(x, y) for x, y in zip(xs, ys))


def _same_parts(a, b) -> bool:
    """Equal dataclass results (PointMotion, BodyMotion, JointReaction, ...), arrays bit for bit."""
    if dataclasses.is_dataclass(a):
        return type(a) is type(b) and all(_same_parts(getattr(a, f.name), getattr(b, f.name))
                                          for f in dataclasses.fields(a))
    if isinstance(a, np.ndarray):
        return isinstance(b, np.ndarray) and a.dtype == b.dtype and np.array_equal(a, b)
    return a == b


@pytest.fixture(scope="module")
def declaration(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("handles_decl") / "handles_four_bar.py"
    path.write_text(FOUR_BAR_SOURCE)
    return path


@pytest.fixture(scope="module")
def user(declaration, tmp_path_factory):
    return sewgen.load(declaration, cache_dir=tmp_path_factory.mktemp("handles_cache"))


# -- pickling ------------------------------------------------------------------------------------------------

def test_catalog_mechanism_pickles_as_a_reference():
    tu = sewgen.mechanism("take_up")
    blob = pickle.dumps(tu)
    assert len(blob) < 1000  # a name and a digest, not compiled code
    back = pickle.loads(blob)
    assert back is tu
    assert _same(back.solve(PHI, params={"crank": "13 mm"}), tu.solve(PHI, params={"crank": "13 mm"}))
    with pytest.raises(AttributeError, match="immutable"):
        tu.name = "other"


def test_a_changed_catalog_is_refused():
    ref = dataclasses.replace(sewgen.mechanism("take_up").reference, digest="0" * 64)
    with pytest.raises(sewgen.BuildError) as e:
        resolve(ref)
    assert e.value.mechanism == "take_up"


def test_motion_and_force_analysis_pickle_bit_identical():
    tu = sewgen.mechanism("take_up")
    thread = sewgen.Load.force("thread_eye", "2.94 N", "-60 deg", window=("135 deg", "155 deg"), name="thread")
    fa = tu.kinetostatics(PHI, speed="1000 rpm", loads=[thread], params={"crank": "13 mm"},
                          moment_about=("5 mm", "-3 mm"))
    back = pickle.loads(pickle.dumps(fa))
    assert _same(back, fa) and back.mechanism is tu
    s, t = fa.run_settings, back.run_settings
    for x, y in ((s.params, t.params), (s.held, t.held), (s.gravity, t.gravity), (s.loads, t.loads)):
        assert np.array_equal(x, y)
    assert t.moment_about == s.moment_about and [p[0] for p in t.placed] == [thread]
    assert np.array_equal(back.frame_moment_on_parts, fa.frame_moment_on_parts)
    assert np.array_equal(back.load_powers()["thread"], fa.load_powers()["thread"])
    for i in (0, 30):
        assert all(np.array_equal(x, y) for x, y in zip(back.force_matrix(i), fa.force_matrix(i)))
    motion = pickle.loads(pickle.dumps(fa.motion))
    assert _same(motion, fa.motion)
    for part in (fa.reaction("B"), fa.frame_force("D"), fa.motion.point("thread_eye"), fa.motion.body("rocker"),
                 fa.motion.coord("rocker.angle")):
        assert _same_parts(pickle.loads(pickle.dumps(part)), part)


def test_user_mechanism_pickles_and_solves_identically(user):
    back = pickle.loads(pickle.dumps(user))
    assert back is user  # resolved in-process to the loaded mechanism
    assert back.reference.kind == "user" and back.reference.declaration.endswith("handles_four_bar.py")
    fa = user.kinetostatics(PHI, params={"crank": "10 mm"})
    again = pickle.loads(pickle.dumps(fa))
    assert _same(again, fa)
    assert np.array_equal(again.torque(), back.kinetostatics(PHI, params={"crank": "10 mm"}).torque())


def test_unpickled_user_mechanism_rebuilds_where_its_cache_is_gone(user, tmp_path):
    """Another process, an empty cache and no declaration file: the reference's generated sources rebuild it."""
    ref = dataclasses.replace(user.reference, folder=str(tmp_path / "gone" / user.reference.module))
    blob = tmp_path / "mech.pickle"
    blob.write_bytes(pickle.dumps(_Rebound(ref)))  # what pickling the mechanism gives, but for the folder
    cache = tmp_path / "fresh_cache"
    out = _worker("unpickle", blob, cache)
    assert out["cached"] is False and out["path"].startswith(str(cache))
    fa = user.kinetostatics(np.radians(np.arange(0.0, 360.0, 10.0)))
    assert out["obs"] == fa.motion.obs.tobytes().hex() and out["frc"] == fa.frc.tobytes().hex()


@dataclasses.dataclass
class _Rebound:
    """Pickles as the Mechanism a (changed) reference names."""

    ref: object

    def __reduce__(self):
        return resolve, (self.ref,)


def test_machine_and_its_analysis_pickle():
    machine = load_machine("jb1-3")
    a = machine.analyze()
    m2 = pickle.loads(pickle.dumps(machine))
    assert [g.mechanism for g in m2.groups] == [g.mechanism for g in machine.groups]
    a2 = pickle.loads(pickle.dumps(a))
    for which in ("front", "rear"):
        assert np.array_equal(a2.bearing(which), a.bearing(which))
    assert np.array_equal(a2.torque, a.torque)
    assert np.array_equal(a2.shaking_moments_on_frame(), a.shaking_moments_on_frame())
    assert np.array_equal(a2.frame_force_on_parts, a.frame_force_on_parts)
    assert all(_same(a2.groups[k], a.groups[k]) for k in a.groups)
    again = m2.analyze()  # the unpickled machine runs and agrees bit for bit
    assert np.array_equal(again.torque, a.torque) and np.array_equal(again.bearing("rear"), a.bearing("rear"))


# -- processes and threads -------------------------------------------------------------------------------------

def test_results_cross_a_process_pool(user):
    """Bound methods of Mechanism and Machine pickle by reference: the workers solve, results come back."""
    tu = sewgen.mechanism("take_up")
    machine = load_machine("jb1-3")
    with cf.ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn")) as pool:
        motion = pool.submit(tu.solve, PHI, params={"crank": "11 mm"})
        forces = pool.submit(user.kinetostatics, PHI, params={"crank": "11 mm"})
        echoed = pool.submit(pickle.loads, pickle.dumps(tu.kinetostatics(PHI)))
        analysis = pool.submit(machine.analyze)
        motion, forces, echoed, analysis = (f.result(timeout=120) for f in (motion, forces, echoed, analysis))
    assert motion.mechanism is tu and _same(motion, tu.solve(PHI, params={"crank": "11 mm"}))
    assert forces.mechanism is user and _same(forces, user.kinetostatics(PHI, params={"crank": "11 mm"}))
    assert _same(echoed, tu.kinetostatics(PHI))
    local = machine.analyze()
    assert np.array_equal(analysis.torque, local.torque) and np.array_equal(analysis.bearing("front"),
                                                                            local.bearing("front"))


def test_threads_sweeping_one_mechanism_agree_with_serial():
    tu = sewgen.mechanism("take_up")
    phi = np.radians(np.arange(3600) / 10.0)
    cranks = [f"{c} mm" for c in (10.5, 11.0, 11.5, 12.0, 12.5, 13.0, 13.5, 14.0)]

    def run(crank):
        return tu.kinetostatics(phi, params={"crank": crank}), tu.solve(phi, speed=40.0, params={"crank": crank})

    serial = [run(c) for c in cranks]
    with cf.ThreadPoolExecutor(8) as pool:
        for _ in range(3):
            parallel = list(pool.map(run, cranks * 2))
            for (fa, mo), (sfa, smo) in zip(parallel, serial * 2):
                assert _same(fa, sfa) and _same(mo, smo)
    assert not _same(serial[0][0], serial[1][0])  # the threads really ran different designs


# -- out= ------------------------------------------------------------------------------------------------------

def test_out_reuses_the_given_result_and_nothing_else():
    tu = sewgen.mechanism("take_up")
    first = tu.kinetostatics(PHI)
    kept = [x.copy() for x in _arrays(first)]
    eye_x = tu.kinetostatics(PHI + 0.3).motion.point("thread_eye").x  # a view of a dropped result
    eye_x_values = eye_x.copy()
    scratch = tu.kinetostatics(PHI + 0.1)
    for shift in (0.2, 0.4):
        fresh = tu.kinetostatics(PHI + shift)
        reused = tu.kinetostatics(PHI + shift, out=scratch)
        assert reused.frc is scratch.frc and reused.motion.obs is scratch.motion.obs  # written in place
        assert _same(reused, fresh)
        scratch = reused
        tu.solve(PHI - shift)
    assert all(np.array_equal(x, y) for x, y in zip(_arrays(first), kept))  # never passed as out: untouched
    assert np.array_equal(eye_x, eye_x_values)
    # a Motion or a dict may serve; arrays of another shape are not used
    motion = tu.solve(PHI)
    again = tu.solve(PHI + 0.5, out=motion)
    assert again.q is motion.q and _same(again, tu.solve(PHI + 0.5))
    arrays = {"q": np.empty((len(PHI), 2)), "obs": np.empty((3, 3))}
    m3 = tu.solve(PHI, out=arrays)
    assert m3.q is arrays["q"] and m3.obs is not arrays["obs"] and _same(m3, tu.solve(PHI))
    with pytest.raises(TypeError):
        tu.solve(PHI, out=[1, 2])


def test_prepared_sweep_is_the_solve_call():
    """bench times Sweep.bind(): the same arrays solve() passes, the same results."""
    fb = sewgen.mechanism("hook_drive")
    sweep = fb.prepare(PHI, forces=True)
    call = sweep.bind()
    assert call() == 0 and call() == 0
    sweep.check()
    assert _same(sweep.analysis(), fb.kinetostatics(PHI))
    assert not sweep.params.flags.writeable  # shared defaults are read-only


# -- the build cache -------------------------------------------------------------------------------------------

def _worker(command: str, arg, cache: Path, env: dict | None = None, check: bool = True):
    run_env = dict(os.environ, SEWGEN_CACHE=str(cache), **(env or {}))
    res = subprocess.run([sys.executable, str(WORKER), command, str(arg)], capture_output=True, text=True,
                         env=run_env, cwd=HERE, timeout=300)
    if not check:
        return res
    assert res.returncode == 0, res.stderr[-3000:]
    return json.loads(res.stdout.strip().splitlines()[-1])


def _start(command: str, arg, cache: Path, env: dict) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, str(WORKER), command, str(arg)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=dict(os.environ, SEWGEN_CACHE=str(cache), **env),
                            cwd=HERE)


def test_two_processes_build_one_new_mechanism_at_once(declaration, tmp_path):
    cache = tmp_path / "cache"
    go = tmp_path / "go"
    procs = [_start("load", declaration, cache, {"HANDLES_GO": str(go)}) for _ in range(2)]
    go.write_text("")
    outs = []
    for p in procs:
        stdout, stderr = p.communicate(timeout=300)
        assert p.returncode == 0, stderr[-3000:]
        outs.append(json.loads(stdout.strip().splitlines()[-1]))
    assert outs[0]["path"] == outs[1]["path"]
    assert sorted(o["cached"] for o in outs) == [False, True]  # built once: the other waited on the lock
    assert outs[0]["obs"] == outs[1]["obs"] and outs[0]["frc"] == outs[1]["frc"]
    entries = [p.name for p in cache.iterdir() if p.is_dir()]
    assert len([e for e in entries if e.startswith("_sg_user_")]) == 1
    assert not [e for e in entries if e.startswith(".")]  # no temporary build folder left behind


def test_a_corrupted_cached_module_is_rebuilt(declaration, tmp_path):
    cache = tmp_path / "cache"
    first = _worker("load", declaration, cache)
    so = Path(first["path"])
    size = so.stat().st_size
    with open(so, "r+b") as fh:  # a partial copy: the marker's hash no longer matches
        fh.truncate(size // 2)
    second = _worker("load", declaration, cache)
    assert second["cached"] is False and second["path"] == first["path"] and so.stat().st_size == size
    assert second["obs"] == first["obs"] and second["frc"] == first["frc"]
    # a marker that vouches for a file the loader rejects (no ELF header): the import fails, the entry is
    # rebuilt once. (A truncated file with a forged hash could crash the dynamic loader itself: the hash is the
    # defence, and the marker is written only after the complete file is in place.)
    marker = so.parent / "BUILT.json"
    with open(so, "r+b") as fh:
        fh.write(b"not an ELF file")
    info = json.loads(marker.read_text())
    info["sha256"] = __import__("hashlib").sha256(so.read_bytes()).hexdigest()
    marker.write_text(json.dumps(info))
    third = _worker("load", declaration, cache)
    assert third["cached"] is False and third["obs"] == first["obs"]
    # a build folder without its marker (a build that died before the end) is not taken as built
    marker.unlink()
    fourth = _worker("load", declaration, cache)
    assert fourth["cached"] is False and fourth["obs"] == first["obs"]
    assert _worker("load", declaration, cache)["cached"] is True


def test_a_module_that_will_not_import_is_a_build_error(user, declaration, monkeypatch):
    """Rebuilt once, then reported with the mechanism and the path (here every import is made to fail)."""
    import sewgen.engine.loader as loader

    calls = []

    def refuse(module, path):
        calls.append(path)
        raise ImportError("refused by the test")

    monkeypatch.setattr(loader, "_import_path", refuse)
    with pytest.raises(sewgen.BuildError) as e:
        sewgen.load(declaration, cache_dir=Path(user.reference.folder).parent)
    assert e.value.mechanism == "handles_four_bar" and e.value.file == user.build_info["path"]
    assert "refused by the test" in str(e.value) and len(calls) == 2  # the cached module, then the rebuilt one


def _race(cache: str, spec: str, prebuilt: str, barrier, queue) -> None:
    """One process of a race (forked: sewgen is already imported): load the generated files of ``spec`` through
    the cache ``cache`` when every process of the trial is ready, solve, report to ``queue``."""
    from handles_worker import PHI as angles, fake_compiler
    from sewgen.engine.loader import _load_built

    try:
        if prebuilt:
            fake_compiler(prebuilt)
        data = json.loads(Path(spec).read_text())
        barrier.wait(timeout=120)
        mech = _load_built(Path(cache), data["name"], data["files"])
        queue.put({"path": mech.build_info["path"], "cached": mech.build_info["cached"],
                   "obs": mech.solve(angles, speed=100.0).obs.tobytes().hex()})
    except BaseException as exc:  # reported, not lost with the process
        queue.put({"error": f"{type(exc).__name__}: {exc}"})


def test_processes_loading_one_new_mechanism_at_once_all_succeed(declaration, tmp_path):
    """Two and four processes load the same new user mechanism at once, 20 trials each, every
    trial in an empty cache: every process succeeds (no crash, no error), one entry is built, all load the same
    module and agree bit for bit. Affordable in CI: the derivation is done once here, the processes are forked
    from this one (no interpreter start) and start loading together (a barrier); the first trial compiles for
    real, the others replace the compiler by a copy of that module written in pieces after a random delay
    (handles_worker.fake_compiler) -- the race under test is the cache's: its lock, temporary folder, rename and
    marker. (Two interpreters compiling for real at once: test_two_processes_build_one_new_mechanism_at_once.)"""
    from sewgen.derive import generate, render_files
    from sewgen.engine.loader import _declaration

    spec = tmp_path / "files.json"
    spec.write_text(json.dumps({"name": "handles_four_bar",
                                "files": render_files([generate(_declaration(declaration))])}))
    import handles_worker  # noqa: F401  (imported before the forks: each child starts ready)
    import sewgen.engine.build

    ctx = multiprocessing.get_context("fork")
    prebuilt = ""
    for procs, trials in ((2, 20), (4, 20)):
        for trial in range(trials):
            cache = tmp_path / f"cache_{procs}_{trial}"
            barrier, queue = ctx.Barrier(procs), ctx.Queue()
            running = [ctx.Process(target=_race, args=(str(cache), str(spec), prebuilt, barrier, queue))
                       for _ in range(procs)]
            for p in running:
                p.start()
            outs = [queue.get(timeout=300) for _ in running]
            for p in running:
                p.join(timeout=60)
                assert p.exitcode == 0, f"{procs} processes, trial {trial}: exit code {p.exitcode}"
            assert not [o for o in outs if "error" in o], f"{procs} processes, trial {trial}: {outs}"
            assert len({o["path"] for o in outs}) == 1
            assert sorted(o["cached"] for o in outs) == [False] + [True] * (procs - 1)
            assert len({o["obs"] for o in outs}) == 1
            entries = [e.name for e in cache.iterdir() if e.is_dir()]
            assert len([e for e in entries if e.startswith("_sg_user_")]) == 1
            assert not [e for e in entries if e.startswith(".")]
            if not prebuilt:
                (tmp_path / "prebuilt").mkdir()
                prebuilt = str(tmp_path / "prebuilt" / Path(outs[0]["path"]).name)
                shutil.copy2(outs[0]["path"], prebuilt)

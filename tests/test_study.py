"""Design studies (sewgen.study): design tables, machine-level design keys, influence, tolerance, Dask."""
import json
import math

import numpy as np
import pandas as pd
import pytest

import sewgen
from sewgen.cli.main import main
from sewgen.errors import ParameterError
from sewgen.machine.assembly import load_machine
from sewgen.roles import FEED_DOG
from sewgen.study import (MachineDesigns, StudyOptions, influence, parse_key, run_designs, sweep_group_designs,
                          tolerance)

pytestmark = [pytest.mark.c, pytest.mark.plots]

PHI = sewgen.shaft_angles(10)


@pytest.fixture(scope="module")
def jb():
    return load_machine("jb1-3")


# -- design tables ------------------------------------------------------------------------------------------------

def test_a_dataframe_design_table_gives_the_array_s_results():
    nb = sewgen.mechanism("needle_bar")
    base = nb.param_vector()
    P = np.tile(base, (3, 1))
    P[:, nb.param_names.index("crank")] = [0.015, 0.0167, 0.018]
    P[:, nb.param_names.index("rod")] = [0.045, 0.05, 0.055]
    by_array = sweep_group_designs(nb, P, PHI, "1000 rpm")
    by_frame = sweep_group_designs(nb, pd.DataFrame(P, columns=nb.param_names), PHI, "1000 rpm")
    by_columns = sweep_group_designs(nb, pd.DataFrame({"crank": P[:, 0], "rod": P[:, 1]}), PHI, "1000 rpm")
    by_mapping = sweep_group_designs(nb, {"crank": P[:, 0], "rod": P[:, 1]}, PHI, "1000 rpm")
    for other in (by_frame, by_columns, by_mapping):
        assert np.array_equal(other.params, by_array.params)
        assert np.array_equal(other.obs, by_array.obs) and np.array_equal(other.q, by_array.q)
        assert list(other.status) == ["ok"] * 3
    # and each design as a plain solve
    for k in range(3):
        mo = nb.solve(PHI, speed="1000 rpm", params=dict(zip(nb.param_names, P[k])))
        assert np.array_equal(mo.obs, by_array.obs[k])


def test_a_design_that_cannot_assemble_is_reported_and_the_others_unaffected():
    nb = sewgen.mechanism("needle_bar")
    designs = pd.DataFrame({"crank": [0.0167, 0.0167, 0.015], "rod": [0.05, 0.005, 0.05]})  # rod < crank
    s = sweep_group_designs(nb, designs, PHI, "1000 rpm", forces=True)
    assert list(s.status) == ["ok", "AssemblyError", "ok"]
    assert s.error[0] is None and s.error[2] is None and "assemble" in s.error[1]
    assert np.isnan(s.obs[1]).all() and np.isnan(s.frc[1]).all()
    for k in (0, 2):
        fa = nb.kinetostatics(PHI, speed="1000 rpm", params=designs.iloc[k].to_dict())
        assert np.array_equal(fa.frc, s.frc[k]) and np.array_equal(fa.motion.obs, s.obs[k])
    df = s.to_dataframe()
    assert list(df["status"]) == ["ok", "AssemblyError", "ok"] and df["error"][1] == s.error[1]


def test_the_batched_kinematic_seam_is_the_per_design_solve_bit_for_bit(jb):
    """Kinematic sweeps go through Mechanism.sweep_designs (batched C calls): each design's arrays equal its own
    solve() exactly, on a closed-form mechanism and on a Newton one (the JB1-3 feed at its stitch setting), and
    a design that cannot assemble keeps its error's type while the others are unaffected."""
    nb = sewgen.mechanism("needle_bar")
    designs = {"crank": [0.0167, 0.0167, 0.015, 0.018], "rod": [0.05, 0.005, 0.05, 0.06]}  # design 1: rod < crank
    s = sweep_group_designs(nb, designs, PHI, "1000 rpm")
    assert list(s.status) == ["ok", "AssemblyError", "ok", "ok"] and "assemble" in s.error[1]
    assert np.isnan(s.obs[1]).all()
    for k in (0, 2, 3):
        mo = nb.solve(PHI, speed="1000 rpm", params={n: v[k] for n, v in designs.items()})
        for got, want in ((s.q[k], mo.q), (s.qd[k], mo.qd), (s.qdd[k], mo.qdd), (s.obs[k], mo.obs)):
            assert np.array_equal(got, want)
    feed = next(g for g in jb.groups if g.name == "feed")
    mech = feed.mechanism
    P = np.tile(mech.param_vector(feed.params or None), (5, 1))
    P[:, mech.param_names.index("feed_arm_r")] *= np.linspace(0.98, 1.02, 5)
    s = sweep_group_designs(mech, P, PHI, None, held=feed.held or None)
    assert list(s.status) == ["ok"] * 5
    for k in range(5):
        mo = mech.solve(PHI, params=dict(zip(mech.param_names, P[k])), held=feed.held or None)
        assert np.array_equal(s.obs[k], mo.obs) and np.array_equal(s.q[k], mo.q)


def test_an_unknown_design_column_is_named():
    nb = sewgen.mechanism("needle_bar")
    with pytest.raises(ParameterError, match="crnak"):
        sweep_group_designs(nb, {"crnak": [0.01]}, PHI)


# -- machine-level design keys ---------------------------------------------------------------------------------

def test_model_file_keys_with_their_units(jb):
    k = parse_key(jb, "groups.feed.params.feed_arm_r")
    assert (k.kind, k.unit, k.group, k.param) == ("length", "mm", "feed", "feed_arm_r")
    assert k.column == "groups.feed.params.feed_arm_r [mm]"
    k = parse_key(jb, "groups.hook_drive.phase")
    assert (k.kind, k.unit, k.group) == ("angle", "deg", None) and k.nominal == pytest.approx(math.radians(-2))
    assert parse_key(jb, "shaft.masses[0].mass").nominal == pytest.approx(0.020)
    for bad, word in (("groups.fed.params.x", "no group 'fed'"), ("groups.feed.params.nope", "no parameter"),
                      ("shaft.nothing", "shaft.nothing"), ("groups.feed.mechanism", "not a quantity")):
        with pytest.raises(ParameterError, match=word) as info:
            parse_key(jb, bad)
        assert info.value.parameter == bad


def test_a_model_key_reloads_the_machine_and_a_refused_design_names_the_key(jb):
    md = MachineDesigns(jb, ["groups.hook_drive.phase", "shaft.rear_bearing"], [[-0.1, 0.2], [-0.1, -1.0]])
    m0 = md.machine_for(0)
    assert next(g for g in m0.groups if g.name == "hook_drive").phase == -0.1 and m0.shaft.rear == 0.2
    df = run_designs(jb, md.keys, md.values, StudyOptions(step_deg=5.0))
    assert df["status"][0] == "ok"
    assert df["status"][1] == "ModelFileError" and "shaft.rear_bearing" in df["error"][1]
    assert df.columns[:2].tolist() == ["groups.hook_drive.phase [deg]", "shaft.rear_bearing [mm]"]


def test_a_machine_design_table_by_column_names_with_units(jb):
    opts = StudyOptions(step_deg=5.0, loads=False)
    a = run_designs(jb, ["groups.feed.params.feed_arm_r"], [[0.0293], [0.0295]], opts)
    b = run_designs(jb, pd.DataFrame({"groups.feed.params.feed_arm_r [mm]": [29.3, 29.5]}), options=opts)
    c = run_designs(jb, {"groups.feed.params.feed_arm_r": [0.0293, 0.0295]}, options=opts)
    pd.testing.assert_frame_equal(a, c, check_exact=True)
    pd.testing.assert_frame_equal(a.drop(columns=a.columns[0]), b.drop(columns=b.columns[0]), check_exact=False,
                                  rtol=1e-12)
    assert b.columns[0] == "groups.feed.params.feed_arm_r [mm]"


# -- studies ------------------------------------------------------------------------------------------------------

def test_influence_needle_stroke_to_crank_radius_is_two(jb):
    r = influence(jb, ["groups.needle_bar.params.crank"], "-10%..+10%", 3, StudyOptions(loads=False))
    assert r.sensitivity("groups.needle_bar.params.crank", "needle_stroke [mm]") == pytest.approx(2.0, abs=1e-6)
    crank = r.table["groups.needle_bar.params.crank [mm]"]
    assert np.allclose(r.table["needle_stroke [mm]"], 2 * crank, rtol=0, atol=1e-9)
    assert "central difference" in r.scheme


def test_linked_keys_move_together(jb):
    spec = "groups.hook_drive.phase,groups.feed.params.hook_crank.phase"
    r = influence(jb, [spec], "-4 deg..0 deg", 3, StudyOptions(step_deg=5.0, loads=False))
    a, b = r.table["groups.hook_drive.phase [deg]"], r.table["groups.feed.params.hook_crank.phase [deg]"]
    assert np.allclose(a, b, atol=1e-12) and sorted(np.round(a, 9).unique()) == [-4.0, -2.0, 0.0]
    assert set(r.table["varied"]) == {"", "groups.hook_drive.phase"}
    t = tolerance(jb, {spec: "±1 deg"}, 6, seed=0, options=StudyOptions(step_deg=5.0, loads=False))
    assert np.allclose(t.table["groups.hook_drive.phase [deg]"], t.table["groups.feed.params.hook_crank.phase [deg]"])
    with pytest.raises(Exception, match="cannot move with"):
        influence(jb, ["groups.hook_drive.phase,groups.feed.params.feed_arm_r"], "-1%..1%", 2)


def test_tolerance_with_zero_tolerance_has_zero_spread(jb):
    r = tolerance(jb, {"groups.feed.params.feed_arm_r": "±0 mm", "groups.needle_bar.params.crank": "+-0 mm"}, 12,
                  seed=5)
    assert (r.table["status"] == "ok").all()
    for q in r.stats["quantity"]:
        v = r.table[q].to_numpy(dtype=float)
        assert np.all(v == v[0]) and (np.isnan(v[0]) or v[0] == r.nominal[q]), q
    assert (r.stats["spread"] == 0).all() and (r.stats["std"] == 0).all()


def test_tolerance_counts_the_designs_that_fail_a_timing_rule(jb):
    r = tolerance(jb, {"groups.feed.params.feed_arm_r": "±3 mm"}, 40, seed=1, distribution="uniform")
    fails = r.failures
    assert 0 < len(fails) < 40
    assert all(("dog_" in f) or s != "ok" for f, s in zip(fails["failed_rules"], fails["status"]))


def test_a_study_on_a_two_worker_local_cluster_is_the_in_process_result(jb):
    pytest.importorskip("distributed")
    tol = {"groups.feed.params.feed_arm_r": "±0.05mm", "groups.needle_bar.params.crank": "±0.05mm"}
    opts = StudyOptions(step_deg=2.0, loads=True)
    here = tolerance(jb, tol, 12, seed=2, options=opts, chunk_size=3)
    there = tolerance(jb, tol, 12, seed=2, options=opts, chunk_size=3, dask="local:2")
    pd.testing.assert_frame_equal(here.table, there.table, check_exact=True)
    assert (here.table["status"] == "ok").all()


def test_the_chunking_does_not_change_a_bit(jb):
    """Each design is evaluated independently of its chunk: any chunk size (and Dask's larger default ones)
    gives the same table exactly."""
    from sewgen.study.run import dask_chunk

    tol = {"groups.feed.params.feed_arm_r": "±0.05mm", "groups.feed.params.lift_arm": "±0.05mm"}
    opts = StudyOptions(step_deg=5.0, loads=False)
    tables = [tolerance(jb, tol, 11, seed=4, options=opts, chunk_size=c).table for c in (12, 5, 1)]
    for t in tables[1:]:
        pd.testing.assert_frame_equal(tables[0], t, check_exact=True)
    assert dask_chunk(100_000, 2) == 4000 and dask_chunk(10_000, 2) == 1000 and dask_chunk(30_000, 2) == 2500


def test_a_dask_task_evaluates_its_designs_in_pieces_to_the_same_table(jb, monkeypatch):
    """A Dask task larger than a chunk runs its designs in pieces of CHUNK (cache-sized arrays): the same table
    as the whole task at once, bit for bit, with a failing design in the middle of a piece."""
    from sewgen.study import run as study_run
    from sewgen.study.evaluate import evaluate_chunk
    from sewgen.study.run import evaluate_pieces, linked_keys

    keys, _ = linked_keys(jb, ["groups.feed.params.feed_arm_r"])
    values = np.linspace(0.0290, 0.0298, 11)[:, None]
    values[4, 0] = 0.05  # the dog never sinks below the plate: a failing design
    opts = StudyOptions(step_deg=5.0, loads=False)
    monkeypatch.setattr(study_run, "CHUNK", 3)
    pieces = evaluate_pieces(jb, keys, values, opts)
    whole = evaluate_chunk(jb, keys, values, opts)
    pd.testing.assert_frame_equal(pieces, whole, check_exact=True)
    assert (pieces["status"] != "ok").sum() == 1 and pieces["status"][4] != "ok"


def test_a_study_on_a_running_scheduler_by_its_address(jb):
    distributed = pytest.importorskip("distributed")
    from sewgen.study.run import StudyError, dask_client

    designs = [[0.0293], [0.0294], [0.05]]  # the last: the dog never sinks below the plate
    opts = StudyOptions(step_deg=5.0, loads=False)
    here = run_designs(jb, ["groups.feed.params.feed_arm_r"], designs, opts, chunk_size=1)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as c:
        there = run_designs(jb, ["groups.feed.params.feed_arm_r"], designs, opts, chunk_size=1,
                            dask=c.scheduler_address)
    pd.testing.assert_frame_equal(here, there, check_exact=True)
    assert list(there["status"]) == ["ok", "ok", "FeedDogError"]
    for bad in ("local:0", "nowhere", "local:two"):
        with pytest.raises(StudyError, match="--dask"):
            dask_client(bad)


# -- angles ---------------------------------------------------------------------------------------------------------

def test_an_angle_moves_over_an_absolute_range_never_a_percentage_of_it(jb):
    """10 % of the hook drive's −2° phase is 0.2°: meaningless. An angle's range is absolute, by default its
    nominal ± 10°; a percentage of an angle (a range or a tolerance) is refused, naming the key."""
    from sewgen.study.run import StudyError

    opts = StudyOptions(step_deg=5.0, loads=False)
    with pytest.raises(StudyError, match="percentage of an angle") as err:
        influence(jb, ["groups.hook_drive.phase"], "-10%..+10%", 3, opts)
    assert err.value.parameter == "--range" and "groups.hook_drive.phase" in str(err.value)
    with pytest.raises(StudyError, match="percentage of an angle"):
        tolerance(jb, {"groups.hook_drive.phase": "±1%"}, 2, options=opts)
    r = influence(jb, ["groups.hook_drive.phase"], None, 3, opts)
    ranged = r.table[r.table["varied"] == "groups.hook_drive.phase"]["groups.hook_drive.phase [deg]"]
    assert sorted(ranged) == pytest.approx([-12.0, -2.0, 8.0])
    assert r.ranges == ["-12 deg..8 deg"]


@pytest.fixture(scope="module")
def feed_rising_at_0():
    """JB1-3 with its feed group's phase set so that the dog rises 0.0002° after φ = 0 (its events move by
    −phase: the group turns at φ + phase)."""
    from sewgen.machine.modelfile import MODELS_DIR, load_toml

    r = run_designs(load_machine("jb1-3"), ["groups.feed.phase"], [[0.0]], StudyOptions(step_deg=5.0, loads=False))
    rise0 = float(r["feed_rise_at [deg]"][0])
    doc = load_toml(MODELS_DIR / "jb1-3.toml")
    phase = rise0 - 0.0002
    doc["groups"]["feed"]["phase"] = f"{phase!r} deg"
    return load_machine(MODELS_DIR / "jb1-3.toml", doc), phase


def test_an_angle_across_0_deg_is_continuous_in_sensitivities_curves_and_percentiles(feed_rising_at_0):
    """The rise angle moves by −1° per degree of the feed's phase (closed form): its sensitivity is −1 though its
    value wraps from 359.999° to 0.001° between the two difference points, the influence curve is the line of slope
    −1, and a tolerance's spread of it is the phase's spread, not a turn."""
    machine, phase = feed_rising_at_0
    opts = StudyOptions(step_deg=5.0, loads=False)
    rise = "feed_rise_at [deg]"
    r = influence(machine, ["groups.feed.phase"], [f"{phase - 4} deg..{phase + 4} deg"], 5, opts)
    assert r.sensitivity("groups.feed.phase", rise) == pytest.approx(-1.0, abs=1e-6)
    x, y = r.curve("groups.feed.phase", rise)
    assert (r.table[rise] > 350).any() and (r.table[rise] < 10).any()  # the table keeps [0°, 360°)
    assert y == pytest.approx(0.0002 - (x - phase), abs=1e-4)  # the rise found between 5° samples
    t = tolerance(machine, {"groups.feed.phase": "±2 deg"}, 24, seed=3, distribution="uniform", options=opts)
    st = t.stats.set_index("quantity")
    shift = t.table["groups.feed.phase [deg]"].to_numpy() - phase
    assert st.loc[rise, "spread"] == pytest.approx(np.ptp(shift), abs=1e-4)
    assert st.loc[rise, "std"] == pytest.approx(np.std(shift), abs=1e-4)
    assert st.loc[rise, "min"] == pytest.approx(0.0002 - shift.max(), abs=1e-4)


# -- the command --------------------------------------------------------------------------------------------------

def test_study_influence_command_writes_tables_with_units(tmp_path, capsys):
    out = tmp_path / "inf"
    rc = main(["study", "influence", "jb1-3", "--param", "groups.needle_bar.params.crank", "--range", "-5%..+5%",
               "--steps", "3", "--step", "5 deg", "--no-plots", "--out", str(out)])
    assert rc == 0
    table = pd.read_csv(out / "influence.csv")
    assert "needle_stroke [mm]" in table and "groups.needle_bar.params.crank [mm]" in table
    sens = pd.read_csv(out / "sensitivities.csv")
    row = sens[(sens["quantity"] == "needle_stroke [mm]")]
    assert float(row["sensitivity"].iloc[0]) == pytest.approx(2.0, abs=1e-6)
    assert json.loads((out / "study.json").read_text())["study"] == "influence"
    assert "wrote" in capsys.readouterr().out


def test_study_tolerance_command_with_exact_jumps(tmp_path, capsys):
    """--exact-jumps: the feed's acceleration jump of the nominal design is summary.json's exact one."""
    from sewgen.machine import feed_indices as fi
    from sewgen.machine.cams import arc_switches

    out = tmp_path / "tol"
    rc = main(["study", "tolerance", "jb1-3", "--tolerance", "groups.feed.params.lift_arm=±0.0mm", "--samples", "2",
               "--step", "5 deg", "--exact-jumps", "--no-plots", "--out", str(out)])
    assert rc == 0
    assert json.loads((out / "study.json").read_text())["exact_jumps"] is True
    jb = load_machine("jb1-3")
    feed = next(g for g in jb.groups if g.name == "feed")
    mech = feed.mechanism
    mo = mech.solve(np.radians(np.arange(0.0, 360.0, 5.0)) + feed.phase, speed=jb.speed,
                    params=feed.params or None, held=feed.held or None)
    dog = mech.description.role(FEED_DOG).name
    want = max(abs(s.jumps[dog][0]) for s in arc_switches(mech, mo, params=feed.params or None,
                                                         held=feed.held or None))
    samples = pd.read_csv(out / "samples.csv")
    assert samples[fi.column("accel_jump")].to_numpy() == pytest.approx([want, want], rel=1e-9)


@pytest.mark.parametrize("argv, word", [
    (["study", "influence", "jb1-3", "--param", "groups.feed.params.nope"], "groups.feed.params.nope"),
    (["study", "influence", "jb1-3", "--param", "groups.feed.params.feed_arm_r", "--range", "5%"], "--range"),
    (["study", "tolerance", "jb1-3", "--tolerance", "groups.feed.params.feed_arm_r=±0.02 deg"], "--tolerance"),
    (["study", "influence", "jb1-3", "--param", "groups.hook_drive.phase", "--range", "-10%..+10%"],
     "percentage of an angle"),
    (["study", "tolerance", "jb1-3", "--tolerance", "groups.hook_drive.phase=±1%"], "percentage of an angle"),
    # a half-width, a full width or a one-sided limit? was read as ±0.02 mm
    (["study", "tolerance", "jb1-3", "--tolerance", "groups.feed.params.feed_arm_r=0.02mm"],
     "groups.feed.params.feed_arm_r"),
    (["study", "tolerance", "jb1-3", "--tolerance", "groups.feed.params.feed_arm_r=±0.02mm", "--dask", "nowhere"],
     "--dask"),
    (["study", "tolerance", "jb1-3", "--tolerance", "groups.feed.params.feed_arm_r=±0.02mm", "--seed", "-1"],
     "--seed"),
])
def test_study_mistakes_exit_2_with_one_line_and_nothing_on_stdout(tmp_path, capsys, argv, word):
    rc = main(argv + ["--out", str(tmp_path / "x"), "--samples" if argv[1] == "tolerance" else "--steps", "2"])
    cap = capsys.readouterr()
    assert rc == 2 and cap.out == ""
    assert word in cap.err and len(cap.err.strip().splitlines()) == 1
    assert not (tmp_path / "x").exists()


def test_a_negative_seed_is_a_typed_error_naming_it(jb):
    from sewgen.study.run import StudyError

    with pytest.raises(StudyError) as exc:
        tolerance(jb, {"groups.feed.params.feed_arm_r": "±0.02 mm"}, 2, seed=-1)
    assert exc.value.parameter == "--seed" and "-1" in exc.value.problem


def test_a_histogram_of_samples_one_rounding_apart_states_the_one_value(tmp_path):
    """Samples that differ by float rounding only — here one ulp of 16.7 — leave no room for bins (numpy cannot
    cut 3.6e-15 into five finite bins above 16.7: "Too many bins"); the panel states the value instead, and the
    histograms of the quantities that do spread are drawn as before."""
    from types import SimpleNamespace

    from sewgen.cli.study import tolerance_plots

    noisy = np.where(np.arange(100) % 2 == 0, 16.7, np.nextafter(16.7, 17.0))
    assert np.ptp(noisy) == np.spacing(16.7) > 0
    with pytest.raises(ValueError, match="Too many bins"):
        np.histogram(noisy, bins=5)
    quantities = ["needle_stroke [mm]", "take_up_amount [mm]"]
    table = pd.DataFrame({"status": ["ok"] * 100, quantities[0]: noisy, quantities[1]: np.linspace(90.0, 92.0, 100)})
    res = SimpleNamespace(table=table, periods={}, stats=pd.DataFrame({"quantity": quantities}), machine="JB1-3",
                          nominal=pd.Series({quantities[0]: 16.7, quantities[1]: 91.0}), distribution="normal")
    (path,) = tolerance_plots(res, tmp_path)
    assert path == tmp_path / "histograms.png" and path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_study_reading_only_the_feed_sweeps_only_its_observables_bit_for_bit(jb):
    """A feed-only study without loads sweeps just the observables it reads: the same values as the whole
    sweep, bit for bit; with exact_jumps the jump is summary.json's (each switch solved at its own angle)."""
    from sewgen.machine import feed_indices as fi
    from sewgen.machine.cams import arc_switches

    feed = next(g for g in jb.groups if g.name == "feed")
    mech = feed.mechanism
    P = np.tile(mech.param_vector(feed.params or None), (3, 1))
    P[:, mech.param_names.index("lift_arm")] *= [0.99, 1.0, 1.01]
    kept = tuple(k for k in fi.feed_observables(mech) if k is not None)
    whole = sweep_group_designs(mech, P, PHI, None, held=feed.held or None)
    some = sweep_group_designs(mech, P, PHI, None, held=feed.held or None, observables=kept)
    assert some.q is None and some.obs.shape == (3, len(PHI), len(kept))
    for k in kept:
        assert np.array_equal(some.observable(k), whole.obs[:, :, k])
    opts = StudyOptions(step_deg=5.0, loads=False, exact_jumps=True)
    r = run_designs(jb, ["groups.feed.params.lift_arm"], P[:, [mech.param_names.index("lift_arm")]], opts)
    dog = mech.description.role(FEED_DOG).name
    for k in range(3):
        mo = mech.solve(np.radians(np.arange(0.0, 360.0, 5.0)) + feed.phase, speed=jb.speed,
                        params=dict(zip(mech.param_names, P[k])), held=feed.held or None)
        want = max(abs(s.jumps[dog][0]) for s in arc_switches(mech, mo, params=dict(zip(mech.param_names, P[k])),
                                                             held=feed.held or None))
        assert r["feed_accel_jump [m/s^2]"][k] == pytest.approx(want, rel=1e-9)
    # a study that leaves the feed at nominal broadcasts the nominal's exact jump
    other = run_designs(jb, ["groups.needle_bar.params.crank"], [[0.0167], [0.0168]], opts)
    assert other["feed_accel_jump [m/s^2]"].tolist() == [r["feed_accel_jump [m/s^2]"][1]] * 2
    est = run_designs(jb, ["groups.feed.params.lift_arm"], P[:, [mech.param_names.index("lift_arm")]],
                      StudyOptions(step_deg=5.0, loads=False))
    assert np.allclose(est["feed_accel_jump [m/s^2]"], r["feed_accel_jump [m/s^2]"], rtol=1.5e-3)

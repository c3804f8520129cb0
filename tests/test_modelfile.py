"""Machine model files (sewgen.machine.load_machine, sewgen.machine.modelfile): the built-in JB1-3, round trips, errors.

The reference numbers are the model file's own text converted by hand (1000 rpm = 1000 · 2π/60 rad/s, 82° =
82 π/180 rad, ...). Every bad input must raise ModelFileError naming the file, the dotted key and the unit
expected (DESIGN.md §5; sewgen/machine/modelfile.py's docstring).
"""
from __future__ import annotations

import json
import math
import re
import tomllib

import numpy as np
import pytest

from sewgen.machine.feed import regulator_angle
from sewgen.engine.loads import Load
from sewgen.machine.assembly import load_machine
from sewgen.machine.modelfile import MODELS_DIR, ModelFileError

pytestmark = [pytest.mark.c]

MM = 1e-3
BUILTIN = MODELS_DIR / "jb1-3.toml"
TEXT = BUILTIN.read_text(encoding="utf-8")


def edit(old: str, new: str, text: str = TEXT) -> str:
    """``text`` with ``old`` (which must occur exactly once) replaced by ``new``."""
    assert text.count(old) == 1, f"{old!r} occurs {text.count(old)} times in the model text"
    return text.replace(old, new)


def write(tmp_path, text: str, name: str = "machine.toml"):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def numbers(m):
    """Everything a machine is made of, as plain comparable values."""
    return {
        "name": m.name, "doc": m.doc, "speed": m.speed, "step": m.step, "gravity": tuple(m.gravity),
        "shaft": (m.shaft.front, m.shaft.rear, m.shaft.inertia, m.shaft.pulley,
                  [(s.name, s.mass, s.radius, s.angle, s.z) for s in m.shaft.masses]),
        "groups": [(g.name, g.mechanism.name, g.phase, dict(g.axial), dict(g.params), dict(g.held), dict(g.branch),
                    list(g.loads), g.stitch) for g in m.groups],
    }


def close(a, b, rel=1e-12):
    """Nested equality with floats to ``rel``."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(close(a[k], b[k], rel) for k in a)
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(close(x, y, rel) for x, y in zip(a, b))
    if isinstance(a, Load):
        return close((a.at, a.fx, a.fy, a.torque, a.window, a.name), (b.at, b.fx, b.fy, b.torque, b.window, b.name))
    if isinstance(a, (float, np.floating)) and not isinstance(a, bool):
        return math.isclose(a, b, rel_tol=rel, abs_tol=1e-300)
    return a == b


def dump_toml(doc: dict) -> str:
    """A minimal TOML writer (strings, numbers, booleans, tables, arrays of tables; every key quoted)."""
    lines = []

    def key(k):
        return json.dumps(k)

    def value(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, (int, float)):
            return repr(v)
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, list) and not any(isinstance(x, dict) for x in v):
            return "[" + ", ".join(value(x) for x in v) + "]"
        raise TypeError(type(v))

    def tables(v):
        return isinstance(v, list) and v and all(isinstance(x, dict) for x in v)

    def table(path, t):
        scalars = {k: v for k, v in t.items() if not isinstance(v, dict) and not tables(v)}
        if path:
            lines.append("[" + ".".join(key(p) for p in path) + "]")
        lines.extend(f"{key(k)} = {value(v)}" for k, v in scalars.items())
        lines.append("")
        for k, v in t.items():
            if isinstance(v, dict):
                table(path + [k], v)
            elif tables(v):
                for item in v:
                    lines.append("[[" + ".".join(key(p) for p in path + [k]) + "]]")
                    lines.extend(f"{key(a)} = {value(b)}" for a, b in item.items())
                    lines.append("")

    table([], doc)
    return "\n".join(lines)


@pytest.fixture(scope="module")
def jb():
    return load_machine("jb1-3")


# -- the built-in model -----------------------------------------------------------------------------------------
def test_builtin_jb1_3_numbers(jb):
    assert jb.name == "JB1-3" and jb.source == str(BUILTIN)
    assert jb.speed == pytest.approx(1000 * 2 * math.pi / 60, rel=1e-15)
    assert jb.step == pytest.approx(math.radians(5), rel=1e-15)
    assert len(jb.shaft_angles()) == 72
    assert np.array_equal(jb.gravity, [0.0, -9.80665])  # −90° is exactly −y
    sh = jb.shaft
    assert (sh.front, sh.rear, sh.pulley) == pytest.approx((0.0, 0.215, 0.245), rel=1e-15)
    assert sh.inertia == pytest.approx(2.0e-5, rel=1e-15)
    assert [(s.name, s.mass, s.radius, s.angle, s.z) for s in sh.masses] == [
        ("core", pytest.approx(0.250), 0.0, 0.0, pytest.approx(0.105)),
        ("needle_counterweight", pytest.approx(0.020), pytest.approx(0.010), pytest.approx(math.pi),
         pytest.approx(-0.018))]
    groups = {g.name: g for g in jb.groups}
    assert list(groups) == ["needle_bar", "take_up", "hook_drive", "feed"]
    assert {n: g.mechanism.name for n, g in groups.items()} == {n: n for n in groups}
    assert {n: math.degrees(g.phase) for n, g in groups.items()} == pytest.approx(
        {"needle_bar": 0.0, "take_up": -58.0, "hook_drive": -2.0, "feed": 0.0}, abs=1e-12)
    assert {n: g.axial for n, g in groups.items()} == {
        "needle_bar": {"crank": pytest.approx(-0.018)}, "take_up": {"crank": pytest.approx(-0.008)},
        "hook_drive": {"crank": pytest.approx(0.200)},
        "feed": {"feed_cam": pytest.approx(0.175), "hook_crank": pytest.approx(0.200)}}
    nb = groups["needle_bar"].params
    assert nb["crank"] == pytest.approx(0.0167) and nb["crank.mass"] == pytest.approx(0.035)
    assert nb["crank.inertia"] == pytest.approx(3.0e-6) and nb["needle_bar.com_u"] == pytest.approx(-0.040)
    tu = groups["take_up"].loads
    assert len(tu) == 1 and tu[0].at == "thread_eye" and tu[0].name == "thread_pull"
    assert (tu[0].fx, tu[0].fy) == (0.0, pytest.approx(-2.94))
    assert tu[0].window == pytest.approx((math.radians(135), math.radians(155)))
    fd = groups["feed"]
    assert fd.stitch == pytest.approx(0.004)
    assert (fd.loads[0].fx, fd.loads[0].fy) == (pytest.approx(-7.35), pytest.approx(-14.7))
    # the stitch is turned into the regulator angle that makes it, nothing else held
    assert list(fd.held) == ["regulator"]
    assert fd.held["regulator"] == pytest.approx(regulator_angle(fd.mechanism, 0.004), abs=1e-10)
    assert 0.0 < fd.held["regulator"] < math.radians(60)


def test_builtin_by_path_is_the_builtin_by_name(jb):
    assert close(numbers(load_machine(BUILTIN)), numbers(jb))
    assert close(numbers(load_machine(str(BUILTIN))), numbers(jb))


def test_a_copy_round_trips(tmp_path, jb):
    copy = load_machine(write(tmp_path, TEXT, "copy.toml"))
    assert copy.source == str(tmp_path / "copy.toml")
    assert close(numbers(copy), numbers(jb), rel=0.0)
    phi = np.radians([0.0, 47.0, 90.0, 135.0, 180.0, 222.0])  # the feed tracks its Newton loop in steps ≤ 60°
    a, b = copy.analyze(phi), jb.analyze(phi)
    assert np.array_equal(a.torque, b.torque) and np.array_equal(a.bearing("rear"), b.bearing("rear"))


def test_a_rewritten_copy_round_trips(tmp_path, jb):
    """Parsed, written out again by another writer (every key quoted, inline tables as tables), re-read."""
    doc = tomllib.loads(TEXT)
    text = dump_toml(doc)
    assert tomllib.loads(text) == doc
    assert close(numbers(load_machine(write(tmp_path, text, "rewritten.toml"))), numbers(jb), rel=0.0)


def test_other_units_same_machine(tmp_path, jb):
    """The same machine in other units: 6000 deg/s = 1000 rpm, 0.215 m, 0.25 kg, 1.0 m/s**2 · 9.80665, ..."""
    text = TEXT
    for old, new in [('speed = "1000 rpm"', 'speed = "6000 deg/s"'),
                     ('step = "5 deg"', f'step = "{math.radians(5)!r} rad"'),
                     ('rear_bearing = "215 mm"', 'rear_bearing = "0.215 m"'),
                     ('mass = "250 g"', 'mass = "0.25 kg"'),
                     ('inertia = "2.0e-5 kg*m**2"', 'inertia = "200 g*cm**2"'),
                     ('gravity = "9.80665 m/s**2"', 'gravity = "980.665 cm/s**2"'),
                     ('phase = "-58 deg"', f'phase = "{math.radians(-58)!r} rad"'),
                     ('crank = "16.7 mm"', 'crank = "1.67 cm"'),
                     ('fy = "-2.94 N"', 'fy = "-294000 dyn"'),
                     ('stitch = "4 mm"', 'stitch = "0.4 cm"')]:
        text = edit(old, new, text)
    assert close(numbers(load_machine(write(tmp_path, text))), numbers(jb), rel=1e-12)


# -- bad input ------------------------------------------------------------------------------------------------------
UNIT = {  # the unit text an error must show, per kind
    "length": r"(?<![A-Za-z])(m|mm)(?![A-Za-z])",
    "angle": r"\b(deg|rad|degrees?)\b",
    "speed": r"rad/s|rpm",
    "mass": r"(?<![A-Za-z])(kg|g)(?![A-Za-z])",
    "inertia": re.escape("kg*m**2"),
    "acceleration": re.escape("m/s**2"),
    "force": r"(?<![A-Za-z])N(?![A-Za-z])",
}


def check(tmp_path, text, key, must=(), unit=None, name="bad.toml"):
    path = write(tmp_path, text, name)
    with pytest.raises(ModelFileError) as exc:
        load_machine(path)
    err = exc.value
    msg = str(err)
    assert isinstance(err, ValueError)
    assert err.path == str(path) and str(path) in msg, msg
    assert err.key == key and f": {key}: " in msg, msg
    for text_ in must:
        assert text_ in msg, f"{text_!r} not in {msg!r}"
    if unit is not None:
        tail = msg.split(f": {key}: ", 1)[1]
        assert re.search(UNIT[unit], tail), f"no {unit} unit in {msg!r}"
    return msg


UNKNOWN = [
    ("top level", edit("[machine]\n", 'colour = "red"\n\n[machine]\n'), "colour",
     ["unknown key", "machine, shaft, groups, stitch, thread"]),
    ("machine", edit('step = "5 deg"', 'step = "5 deg"\nspeeed = "1000 rpm"'), "machine.speeed",
     ["unknown key", "speed"]),
    ("shaft", edit('pulley = "245 mm"', 'pulley = "245 mm"\npully = "245 mm"'), "shaft.pully", ["unknown key"]),
    ("group", edit('phase = "-58 deg"', 'phase = "-58 deg"\nphaze = "1 deg"'), "groups.take_up.phaze",
     ["unknown key", "phase"]),
    ("param", edit('"crank.mass" = "10 g"', '"crank.mass" = "10 g"\ncranck = "16 mm"'), "groups.take_up.params.cranck",
     ["take_up has no such parameter", "lever_bc"]),
    ("shaft mass", edit('z = "-18 mm"', 'z = "-18 mm"\nradious = "1 mm"'), "shaft.masses[0].radious", ["unknown key"]),
    ("load", edit('at = "thread_eye"', 'at = "thread_eye"\nfz = "1 N"'), "groups.take_up.loads[0].fz", ["unknown key"]),
    ("axial body", edit('axial = { crank = "-8 mm" }', 'axial = { crank = "-8 mm", rocker = "1 mm" }'),
     "groups.take_up.axial.rocker", ["not a body the shaft drives", "crank"]),
    ("held input", edit('phase = "-58 deg"', 'phase = "-58 deg"\nheld = { regulator = "1 deg" }'),
     "groups.take_up.held.regulator", ["no such held input"]),
]


@pytest.mark.parametrize("text, key, must", [c[1:] for c in UNKNOWN], ids=[c[0] for c in UNKNOWN])
def test_unknown_key(tmp_path, text, key, must):
    check(tmp_path, text, key, must)


MISSING = [
    ("machine.speed", edit('speed = "1000 rpm"              # seed', "# seed"), "machine.speed", "speed"),
    ("machine.step", edit('step = "5 deg"  ', "# "), "machine.step", "angle"),
    ("shaft.front_bearing", edit('front_bearing = "0 mm"\n', ""), "shaft.front_bearing", "length"),
    ("group phase", edit('phase = "-58 deg"\n', "\n"), "groups.take_up.phase", "angle"),
    ("axial position", edit('axial = { feed_cam = "175 mm", hook_crank = "200 mm" }',
                            'axial = { feed_cam = "175 mm" }'), "groups.feed.axial.hook_crank", "length"),
]


@pytest.mark.parametrize("text, key, unit", [c[1:] for c in MISSING], ids=[c[0] for c in MISSING])
def test_missing_key_names_the_unit(tmp_path, text, key, unit):
    check(tmp_path, text, key, ["missing"], unit)


WRONG_UNIT = [
    ("length in g", edit('rod = "50 mm"', 'rod = "50 g"'), "groups.needle_bar.params.rod", "length"),
    ("speed in mm", edit('speed = "1000 rpm"', 'speed = "1000 mm"'), "machine.speed", "speed"),
    ("gravity in N", edit('gravity = "9.80665 m/s**2"', 'gravity = "9.80665 N"'), "machine.gravity", "acceleration"),
    ("inertia in kg*m", edit('"crank.inertia" = "5.0e-7 kg*m**2"', '"crank.inertia" = "5.0e-7 kg*m"'),
     "groups.take_up.params.crank.inertia", "inertia"),
    ("counterweight radius in g", edit('radius = "10 mm"', 'radius = "10 g"'), "shaft.masses[0].radius", "length"),
    ("load in N*m", edit('fy = "-2.94 N"', 'fy = "-2.94 N*m"'), "groups.take_up.loads[0].fy", "force"),
    ("stitch in deg", edit('stitch = "4 mm"', 'stitch = "4 deg"'), "groups.feed.stitch", "length"),
    ("phase in mm", edit('phase = "-2 deg"', 'phase = "-2 mm"'), "groups.hook_drive.phase", "angle"),
    ("bare length", edit('rear_bearing = "215 mm"', "rear_bearing = 215"), "shaft.rear_bearing", "length"),
    ("bare speed", edit('speed = "1000 rpm"', "speed = 1000"), "machine.speed", "speed"),
    ("bare param", edit('rod = "50 mm"', "rod = 0.05"), "groups.needle_bar.params.rod", "length"),
]


@pytest.mark.parametrize("text, key, unit", [c[1:] for c in WRONG_UNIT], ids=[c[0] for c in WRONG_UNIT])
def test_wrong_unit_names_the_expected_unit(tmp_path, text, key, unit):
    check(tmp_path, text, key, (), unit)


def test_bare_number_message(tmp_path):
    msg = check(tmp_path, edit('rear_bearing = "215 mm"', "rear_bearing = 215"), "shaft.rear_bearing",
                ["quantity string with its unit", "215"])
    assert "expected m)" in msg


def test_unknown_mechanism(tmp_path):
    check(tmp_path, edit('mechanism = "take_up"', 'mechanism = "take_upp"'), "groups.take_up.mechanism",
          ["take_upp", "needle_bar", "hook_drive", "feed"])


@pytest.mark.parametrize("branch", ["{ C = 2 }", "{ C = 0 }", "{ C = true }", '{ C = "1" }', "{ X = 1 }"])
def test_bad_branch(tmp_path, branch):
    joint = branch.split()[1]
    check(tmp_path, edit('phase = "-58 deg"', f'phase = "-58 deg"\nbranch = {branch}'),
          f"groups.take_up.branch.{joint}", ["1 or -1", "(C)"])


def test_good_branch_is_taken(tmp_path):
    m = load_machine(write(tmp_path, edit('phase = "-58 deg"', 'phase = "-58 deg"\nbranch = { C = -1 }')))
    assert next(g for g in m.groups if g.name == "take_up").branch == {"C": -1}


def test_load_at_an_unknown_point(tmp_path):
    msg = check_prefix(tmp_path, edit('at = "thread_eye"', 'at = "thread_eyes"'), "groups.take_up.loads")
    assert "thread_eyes" in msg and "thread_eye" in msg.replace("thread_eyes", "")  # names the known points


def check_prefix(tmp_path, text, prefix):
    """As check(), but the key need only start with ``prefix`` (the load's index may or may not be named)."""
    path = write(tmp_path, text, "bad.toml")
    with pytest.raises(ModelFileError) as exc:
        load_machine(path)
    assert exc.value.path == str(path) and str(path) in str(exc.value)
    assert exc.value.key.startswith(prefix) and exc.value.key in str(exc.value)
    return str(exc.value)


def test_window_with_only_from(tmp_path):
    check(tmp_path, edit('to = "155 deg"\n\n[groups.hook_drive]', "\n[groups.hook_drive]"), "groups.take_up.loads[0]",
          ["'from'", "'to'"])


def test_window_with_only_to(tmp_path):
    check(tmp_path, edit('from = "90 deg"\n', ""), "groups.feed.loads[0]", ["'from'", "'to'"])


@pytest.mark.parametrize("rear", ["-10 mm", "0 mm"])
def test_rear_bearing_must_be_behind_the_front(tmp_path, rear):
    check(tmp_path, edit('rear_bearing = "215 mm"', f'rear_bearing = "{rear}"'), "shaft.rear_bearing",
          ["behind the front bearing"])


def test_too_long_a_stitch(tmp_path):
    check(tmp_path, edit('stitch = "4 mm"', 'stitch = "20 mm"'), "groups.feed.stitch", ["20 mm", "range"])


def test_stitch_and_held_regulator_both(tmp_path):
    check(tmp_path, edit('stitch = "4 mm"', 'stitch = "4 mm"\nheld = { regulator = "10 deg" }'),
          "groups.feed.stitch", ["not both"])


def test_bad_parameter_value(tmp_path):
    check(tmp_path, edit('"crank.mass" = "10 g"', '"crank.mass" = "-10 g"'), "groups.take_up.params.crank.mass",
          ["negative"], "mass")


def test_a_step_that_does_not_divide_a_turn(tmp_path):
    """A bad step is a model-file error like any other: it names the file and machine.step."""
    check(tmp_path, edit('step = "5 deg"', 'step = "7 deg"'), "machine.step", ["7"], "angle")


def test_invalid_toml(tmp_path):
    path = write(tmp_path, edit('speed = "1000 rpm"', 'speed = "1000 rpm'), "syntax.toml")
    with pytest.raises(ModelFileError) as exc:
        load_machine(path)
    msg = str(exc.value)
    assert exc.value.path == str(path) and str(path) in msg and "not valid TOML" in msg
    line = 1 + TEXT.splitlines().index(next(ln for ln in TEXT.splitlines() if ln.startswith("speed = ")))
    assert f"line {line}" in msg  # the speed line


def test_group_names_that_differ_only_in_case_are_refused(tmp_path):
    """Group names name the tables (<group>.csv): two that differ only in case would be one file on a
    case-insensitive file system (Windows, macOS), and a reserved name in another case is the machine's own."""
    doc = tomllib.loads(TEXT)
    doc["groups"]["Needle_Bar"] = doc["groups"]["needle_bar"]
    msg = check(tmp_path, dump_toml(doc), "groups.Needle_Bar", ["groups.needle_bar", "Needle_Bar.csv", "case"])
    assert "needle_bar.csv" in msg
    check(tmp_path, edit("[groups.take_up]", "[groups.SUMMARY]").replace("groups.take_up.", "groups.SUMMARY."),
          "groups.SUMMARY", ["reserved"])


def test_nesting_too_deep_to_read_is_a_model_file_error(tmp_path):
    for nested in ("[" * 5000 + "]" * 5000, "{a = " * 5000 + "1" + "}" * 5000):
        path = write(tmp_path, TEXT + f"\ndeep = {nested}\n", "deep.toml")
        with pytest.raises(ModelFileError) as exc:
            load_machine(path)
        assert exc.value.path == str(path) and "nested too deeply" in exc.value.problem


def test_a_name_too_long_for_the_file_system_is_a_model_file_error(tmp_path):
    for name in ("m" * 300, "m" * 300 + ".toml", str(tmp_path / ("m" * 300 + ".toml"))):
        with pytest.raises(ModelFileError) as exc:
            load_machine(name)
        assert "File name too long" in exc.value.problem


def test_a_thread_guide_at_no_point_names_its_key(tmp_path):
    check(tmp_path, edit('point = "thread_eye"', 'point = "nowhere"'), "thread.guides[1].point", ["nowhere"])


def test_missing_file(tmp_path):
    path = tmp_path / "nowhere.toml"
    with pytest.raises(ModelFileError) as exc:
        load_machine(path)
    assert exc.value.path == str(path) and str(path) in str(exc.value) and "no such model file" in str(exc.value)


def test_unknown_builtin():
    with pytest.raises(ModelFileError) as exc:
        load_machine("jb9-9")
    assert "jb9-9" in str(exc.value) and "jb1-3" in str(exc.value)


def test_a_table_where_a_quantity_belongs(tmp_path):
    check(tmp_path, edit('rod = "50 mm"', 'rod = { length = "50 mm" }'), "groups.needle_bar.params.rod", (), "length")


def test_a_results_folder_named_like_a_builtin_model_does_not_shadow_it(tmp_path, monkeypatch):
    """`sewgen analyze jb1-3` writes ./jb1-3/; run again in the same folder, it must still find the model."""
    from sewgen.machine.modelfile import MODELS_DIR, resolve

    monkeypatch.chdir(tmp_path)
    (tmp_path / "jb1-3").mkdir()
    assert resolve("jb1-3") == MODELS_DIR / "jb1-3.toml"


# -- names, signs, encodings, geometry -----------------------------------------------------------------------------

@pytest.mark.parametrize("old, new, key, must", [
    ("[groups.needle_bar]", "[groups.machine]", "groups.machine", ["reserved"]),
    ("[groups.take_up]", "[groups.summary]", "groups.summary", ["reserved"]),
    ("[groups.hook_drive]", '[groups."hook drive"]', "groups.hook drive", ["identifier"]),
    ("[groups.hook_drive]", '[groups."2nd"]', "groups.2nd", ["identifier"]),
    ("[groups.hook_drive]", '[groups."../x"]', "groups.../x", ["identifier"]),
])
def test_group_names_are_identifiers_and_not_reserved(tmp_path, old, new, key, must):
    stem = old[1:-1] + "."
    text = edit(old, new).replace(stem, new[1:-1] + ".")
    check(tmp_path, text, key, must)


@pytest.mark.parametrize("name", ["../ESCAPED", "a/b", "a\\\\b", "..", ".hidden", " JB", ""])
def test_the_machine_name_is_never_a_path(tmp_path, name):
    check(tmp_path, edit('name = "JB1-3"', f'name = "{name}"'), "machine.name", ["plain name"])


@pytest.mark.parametrize("old, new, key", [
    ('mass = "250 g"', 'mass = "-250 g"', "shaft.mass"),
    ('inertia = "2.0e-5 kg*m**2"', 'inertia = "-2.0e-5 kg*m**2"', "shaft.inertia"),
    ('mass = "20 g"', 'mass = "-20 g"', "shaft.masses[0].mass"),
    ('radius = "10 mm"', 'radius = "-10 mm"', "shaft.masses[0].radius"),
    ('belt_pull = "30 N"', 'belt_pull = "-30 N"', "shaft.belt_pull"),
    ('"crank.mass" = "35 g"', '"crank.mass" = "-35 g"', "groups.needle_bar.params.crank.mass"),
    ('"crank.inertia" = "3.0e-6 kg*m**2"', '"crank.inertia" = "-3.0e-6 kg*m**2"',
     "groups.needle_bar.params.crank.inertia"),
])
def test_masses_and_inertias_are_not_negative(tmp_path, old, new, key):
    check(tmp_path, edit(old, new), key, ["negative"])


@pytest.mark.parametrize("old, new, key, words", [
    ('gravity = "9.80665 m/s**2"', 'gravity = "-9.81 m/s**2"', "machine.gravity", ["negative"]),
    ('gravity = "9.80665 m/s**2"', 'gravity = "1e308 m/s**2"', "machine.gravity", ["at most 100 m/s**2"]),
    ('# bearing_friction = 0.04\n# journal_radius = "6 mm"', 'bearing_friction = 4\njournal_radius = "6 mm"',
     "shaft.bearing_friction", ["at most 1"]),
    ('cloth = "1.5 mm"', 'cloth = "-1.5 mm"', "stitch.cloth", ["negative"]),
    ('min = "1.8 mm"\nmax = "2.5 mm"', 'min = "2.5 mm"\nmax = "1.8 mm"', "stitch.rules[0].min", ["above max"]),
])
def test_physical_ranges_in_a_model_file(tmp_path, old, new, key, words):
    """Values no machine can have, each refused naming its key (each was accepted: a negative gravity turned the
    weight over, a rule with min > max failed whatever the machine did)."""
    check(tmp_path, edit(old, new), key, words)


@pytest.mark.parametrize("param, value, words", [("B.friction", "-0.08", "at least 0"),
                                                 ("B.friction", "10", "at most 1"),
                                                 ("needle_bar.guide.friction", "1e6", "at most 1")])
def test_friction_coefficients_of_a_group(tmp_path, param, value, words):
    text = edit('# "B.friction" = 0.08\n# "C.friction" = 0.08\n# "needle_bar.guide.friction" = 0.10',
                f'"{param}" = {value}')
    check(tmp_path, text, f"groups.needle_bar.params.{param}", [words, "Coulomb friction coefficient"])


@pytest.mark.parametrize("old, new", [('speed = "1000 rpm"', 'speed = "0 rpm"'),
                                      ('speed = "1000 rpm"', 'speed = "-1000 rpm"'),
                                      ('step = "5 deg"', 'step = "0 deg"')])
def test_speed_and_step_are_positive(tmp_path, old, new):
    check(tmp_path, edit(old, new), f"machine.{old.split()[0]}", ["positive"])


@pytest.mark.parametrize("value", ["1,5 mm", "16,7 mm", "mm", "🧵 mm", "", "50"])
def test_strict_quantities_in_a_model_file(tmp_path, value):
    msg = check(tmp_path, edit('rod = "50 mm"', f'rod = "{value}"'), "groups.needle_bar.params.rod")
    assert f'"{value}"' in msg or "empty" in msg


def test_a_file_that_is_not_utf8(tmp_path):
    path = tmp_path / "latin1.toml"
    path.write_bytes(TEXT.replace("household", "m\u00e9nage").encode("latin-1", "replace"))
    with pytest.raises(ModelFileError) as exc:
        load_machine(path)
    assert exc.value.file == str(path) and "UTF-8" in str(exc.value) and "line" in str(exc.value)


def test_a_folder_is_not_a_model(tmp_path, monkeypatch):
    from sewgen.machine.modelfile import resolve

    monkeypatch.chdir(tmp_path)
    (tmp_path / "mine.toml").mkdir()
    with pytest.raises(ModelFileError) as exc:
        load_machine("mine.toml")
    assert "folder" in str(exc.value)
    (tmp_path / "jb1-3.toml").write_text(TEXT.replace('name = "JB1-3"', 'name = "Local"'), encoding="utf-8")
    assert load_machine("jb1-3.toml").name == "Local"  # a .toml path is that file
    assert resolve("jb1-3") == MODELS_DIR / "jb1-3.toml"  # the built-in name is the built-in
    (tmp_path / "plain").write_text(TEXT, encoding="utf-8")
    assert resolve("plain").name == "plain"  # any other existing file: that file


def test_a_group_that_cannot_assemble_names_file_and_group(tmp_path):
    from sewgen.errors import AssemblyError

    path = write(tmp_path, edit('rod = "50 mm"', 'rod = "10 mm"'))
    m = load_machine(path)
    with pytest.raises(AssemblyError) as exc:
        m.analyze()
    err = exc.value
    assert err.file == str(path) and err.key == "groups.needle_bar" and err.mechanism == "needle_bar"
    assert str(err).startswith(f"{path}: groups.needle_bar: needle_bar: cannot assemble")
    assert err.angle is not None


def test_a_stitch_the_regulator_cannot_reach_names_the_key(tmp_path):
    check(tmp_path, edit('stitch = "4 mm"', 'stitch = "10 mm"'), "groups.feed.stitch", ["10 mm", "range"])


def test_non_finite_results_are_a_typed_error_and_never_written(tmp_path):
    from sewgen.errors import NonFiniteOutputError
    from sewgen.report.outputs import write_report

    path = write(tmp_path, edit('mass = "20 g"', 'mass = "1e307 kg"'))
    with np.errstate(all="ignore"), pytest.raises(NonFiniteOutputError) as exc:
        write_report(load_machine(path).analyze(), tmp_path / "out")
    assert exc.value.file == str(path) and "shaft" in str(exc.value)
    assert not (tmp_path / "out").exists() and sorted(p.name for p in tmp_path.iterdir()) == ["machine.toml"]


def test_a_report_is_written_whole_or_not_at_all(tmp_path, jb, monkeypatch):
    from sewgen.errors import OutputPathError
    from sewgen.report import outputs as report

    a = jb.analyze()
    files = report.write_report(a, tmp_path / "r")
    assert [f.name for f in files][-1] == "summary.json" and all(f.is_file() for f in files)
    before = {f.name: f.read_bytes() for f in (tmp_path / "r").iterdir()}

    def broken(a_, folder, progress=None, units=None):
        (folder / "machine.csv").write_text("half")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(report, "write_tables", broken)
    with pytest.raises(OutputPathError):
        report.write_report(a, tmp_path / "r")
    assert {f.name: f.read_bytes() for f in (tmp_path / "r").iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r"]


def test_summary_is_clean_json(jb):
    from sewgen.report.outputs import summary

    s = summary(jb.analyze())
    text = json.dumps(s, allow_nan=False)
    assert "Infinity" not in text and "NaN" not in text
    assert s["speed_rpm"] == 1000.0 and s["model_file"] == "<sewgen>/models/jb1-3.toml"
    sampled = jb.analyze().torque  # the peak is refined between the 5° samples: never below the largest one
    assert s["drive_torque"]["max"] >= sampled.max() and s["drive_torque"]["max_how"] == "refined"
    assert s["drive_torque"]["max_at_deg"] == round(s["drive_torque"]["max_at_deg"], 2)
    assert set(s["conventions"]) >= {"frame", "shaft_angle", "drive_torque", "power_balance_residual_relative"}


def test_a_summary_at_rest(jb):
    """A static analysis (speed 0) is an analysis: the feed's travel from central differences, no NaN."""
    from sewgen.report.outputs import summary

    s = summary(jb.analyze(speed=0.0))
    assert s["speed_rpm"] == 0.0
    assert s["groups"]["feed"]["feed_dog"]["travel_above_plate_mm"] == pytest.approx(4.0, abs=1e-3)  # differences

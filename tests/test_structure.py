"""The run time's structure (issue "Any machine"): no SymPy, jinja2 or SciPy behind ``import sewgen`` and a
catalog sweep; errors carry their fields as attributes and pickle; the description is the manifest's; the
status codes C and Python share come from one table; no run-time module outside the catalog declarations
names a catalog mechanism or one of its parts.
"""
from __future__ import annotations

import json
import pickle
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import sewgen
from sewgen import abi
from sewgen.errors import AssemblyError, InputError, ParameterError, PositionError, SewgenError, UnitError
from sewgen.machine.modelfile import ModelFileError

pytestmark = [pytest.mark.c]

ROOT = Path(__file__).resolve().parent.parent


def test_import_and_a_catalog_sweep_load_no_derivation_and_no_scipy():
    """SI numbers in, nothing but numpy and cffi needed (pint, which imports SciPy, comes with the first
    quantity string)."""
    code = ("import sys, sewgen\n"
            "m = sewgen.mechanism('feed')\n"
            "m.solve(sewgen.shaft_angles(5), speed=104.7)\n"
            "print(sorted(k for k in ('sympy', 'jinja2', 'scipy', 'pint', 'cvxpy', 'sewgen.derive') if k in sys.modules))\n"
            "m.kinetostatics(sewgen.shaft_angles(5), speed='1000 rpm')\n"
            "print(sorted(k for k in ('sympy', 'jinja2', 'sewgen.derive') if k in sys.modules))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    assert out.stdout.split() == ["[]", "[]"]


def test_a_machine_analysis_loads_no_derivation():
    code = ("import sys\n"
            "from sewgen.machine import load_machine\n"
            "from sewgen.report.outputs import summary\n"
            "a = load_machine('jb1-3').analyze()\n"
            "summary(a)\n"
            "print(sorted(k for k in ('sympy', 'jinja2', 'sewgen.derive') if k in sys.modules))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    assert out.stdout.strip() == "[]"


def test_analyze_without_plots_loads_no_scipy(tmp_path):
    """``sewgen analyze jb1-3 --no-plots``: the stitch regulator's solve and the dog's plate crossings need no
    SciPy (its import cost 0.4–0.7 s of the command; sewgen.machine.feed)."""
    code = ("import sys\n"
            "from sewgen.cli.main import main\n"
            f"assert main(['analyze', 'jb1-3', '--out', {str(tmp_path / 'out')!r}, '--no-plots']) == 0\n"
            "print(sorted(k for k in ('scipy', 'sympy', 'jinja2', 'matplotlib') if k in sys.modules),\n"
            "      file=sys.stderr)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    assert out.stderr.strip().splitlines()[-1] == "[]"


def test_errors_carry_their_fields():
    nb = sewgen.mechanism("needle_bar")
    with pytest.raises(ParameterError) as e:
        nb.solve([0.0], params={"crank": "3 kg"})
    assert (e.value.mechanism, e.value.parameter) == ("needle_bar", "crank")
    assert "mass" not in e.value.problem and "length" in e.value.problem and "needle_bar" not in e.value.problem
    with pytest.raises(AssemblyError) as e:
        nb.solve(np.radians([0.0, 180.0]), params={"crank": "16.7 mm", "rod": "20.2 mm", "offset": "10 mm"})
    assert isinstance(e.value, PositionError)
    assert (e.value.mechanism, e.value.index) == ("needle_bar", 1)
    assert e.value.angle == pytest.approx(np.pi)
    with pytest.raises(InputError) as e:
        nb.solve([0.0, float("nan")])
    assert e.value.mechanism == "needle_bar"
    with pytest.raises(UnitError) as e:
        sewgen.units.to_si("3 furlongs per fortnight", "speed", "speed")
    assert e.value.parameter == "speed" and isinstance(e.value, SewgenError)


def test_model_file_errors_name_file_and_key(tmp_path):
    from sewgen.machine.assembly import load_machine

    text = (ROOT / "sewgen" / "models" / "jb1-3.toml").read_text().replace('rod = "50 mm"', 'rod = "50 g"')
    path = tmp_path / "m.toml"
    path.write_text(text)
    with pytest.raises(ModelFileError) as e:
        load_machine(path)
    assert e.value.file == str(path) and e.value.key == "groups.needle_bar.params.rod"
    assert "length" in e.value.problem


@pytest.mark.parametrize("err", [
    ParameterError("m", "p", "must be positive"),
    AssemblyError("m", 1.25, 3, 2, 1.5),
    UnitError("speed", "names no angle unit"),
    ModelFileError("x.toml", "machine.speed", "missing"),
])
def test_errors_pickle_with_their_fields(err):
    back = pickle.loads(pickle.dumps(err))
    assert type(back) is type(err) and str(back) == str(err) and vars(back) == vars(err)


def test_status_codes_are_one_table():
    codes = [code for _, code, _, _ in abi.STATUS]
    assert codes == list(range(len(codes)))
    header = (ROOT / "generated" / "sg_abi.h")
    if header.exists():  # the C side is written from the same table
        text = header.read_text()
        for name, code, _, _ in abi.STATUS:
            assert re.search(rf"\b{name} = {code}\b", text), name
    assert abi.error_for(1) is AssemblyError and abi.error_for(0) is None


def test_description_is_the_manifest():
    for name in sewgen.catalog():
        m = sewgen.mechanism(name)
        d, man = m.description, m.manifest
        assert [p.name for p in d.params] == [p["name"] for p in man["params"]]
        assert [b.offset for b in d.bodies] == [b["offset"] for b in man["bodies"]]
        assert [(r.name, r.offset, r.columns) for r in d.reactions] == \
            [(r["name"], r["offset"], tuple(r["columns"])) for r in man["reactions"]]
        assert d.sizes == man["sizes"]
        for role, (kind, part) in d.roles.items():
            assert d.role(role).name == part


#: The catalog's mechanisms and its distinctive part names (bodies, points, parameters, held inputs).
CATALOG_WORDS = ("needle_bar", "take_up", "hook_drive", "feed", "plate_y", "lower_shaft", "regulator", "feed_cam",
                 "feed_fork", "feed_bar", "feed_dog", "needle_eye", "thread_eye", "link_pin", "crank_pin",
                 "rock_slider", "lift_rock_shaft", "feed_rock_shaft", "stitch_block", "hook_point", "needle_point")
#: Modules that may name catalog parts: the catalog declarations (sewgen/derive/models), the derivation's
#: catalog list, the benchmark's catalog table (it times every catalog mechanism by name) and its peers (other
#: tools' take_up four-bar, output by output under sewgen's column names), the adversarial campaign (its
#: independent references are written for the catalog's mechanisms by name), and the role vocabulary (whose roles
#: share words with the catalog's part names).
ALLOWED = {"derive/catalog.py", "bench.py", "peers.py", "fuzz.py", "roles.py"}


def test_no_runtime_module_names_a_catalog_part():
    offenders = []
    for path in sorted((ROOT / "sewgen").rglob("*.py")):
        rel = path.relative_to(ROOT / "sewgen").as_posix()
        if rel.startswith("derive/models/") or rel in ALLOWED:
            continue
        text = path.read_text()
        code = re.sub(r'"""(?:.|\n)*?"""', "", text)  # docstrings may cite the seeds' parts
        code = re.sub(r"#.*", "", code)
        for word in CATALOG_WORDS:  # as a name in a string: "feed_dog", 'needle_bar.travel', f"{x}.regulator"
            if re.search(rf"""["'.]{word}\b(?![(])""", code) and re.search(rf"""\b{word}["'.]""", code):
                offenders.append(f"{rel}: {word}")
    assert not offenders, offenders


def test_every_package_is_installed():
    """A non-editable `pip install .` installs exactly the packages pyproject.toml lists: every folder of
    sewgen/ with an __init__.py must be among them (sewgen.study was missing once: the README's quick start
    failed on a fresh machine while the editable test install passed)."""
    import tomllib

    root = Path(__file__).resolve().parent.parent
    listed = set(tomllib.loads((root / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["setuptools"]["packages"])
    found = {".".join(p.parent.relative_to(root).parts) for p in (root / "sewgen").rglob("__init__.py")}
    assert found <= listed, f"not installed: {sorted(found - listed)}"

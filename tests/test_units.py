"""sewgen.units: strict quantity strings, sweeps of one revolution, display units."""
from __future__ import annotations

import math

import numpy as np
import pytest

from sewgen.errors import UnitError
from sewgen.units import MAX_POSITIONS, DisplayUnits, steps_per_turn, to_si


@pytest.mark.parametrize("text, kind, si", [
    ("16.7 mm", "length", 0.0167), ("16.7mm", "length", 0.0167), (" 16.7 mm ", "length", 0.0167),
    (".5 mm", "length", 0.0005), ("5. mm", "length", 0.005), ("-2.94 N", "force", -2.94), ("+3 deg", "angle",
                                                                                             math.radians(3)),
    ("1e-3 m", "length", 1e-3), ("2.0E+1 mm", "length", 0.02), ("1000 rpm", "speed", 1000 * math.pi / 30),
    ("90°", "angle", math.pi / 2), ("2.0e-5 kg*m**2", "inertia", 2e-5), ("9.81 m/s^2", "acceleration", 9.81),
    ("0.5", "dimensionless", 0.5), ("1e300 kg", "mass", 1e300),
    ("1000 r/min", "speed", 1000 * 2 * math.pi / 60), ("1000 rev/min", "speed", 1000 * 2 * math.pi / 60),
    ("10 r/s", "speed", 20 * math.pi), ("35 grain", "mass", 35 * 64.79891e-6),
])
def test_good_quantities(text, kind, si):
    assert to_si(text, kind, "x") == pytest.approx(si, rel=1e-15)


@pytest.mark.parametrize("text, kind, words", [
    ("1,5 mm", "length", ["1,5 mm", "decimal point"]),        # was read as 15 mm
    ("16,7 mm", "length", ["16,7 mm", "decimal point"]),      # was read as 167 mm
    ("1,000 rpm", "speed", ["1,000 rpm", "thousands"]),
    ("1_000 mm", "length", ["1_000 mm"]),
    ("mm", "length", ['"mm"', "number"]),                       # was read as 1 mm
    ("🧵 mm", "length", ["🧵 mm", "number"]),                   # was read as 1 mm
    ("", "length", ["empty"]),
    ("   ", "length", ["empty"]),
    ("5", "angle", ['"5"', "no unit", "deg"]),                  # was read as 5 rad
    ("5", "length", ['"5"', "no unit", "mm"]),
    ("5 mm 3", "length", ["5 mm 3"]),
    ("5 furlongs", "angle", ["5 furlongs"]),
    ("5 m", "angle", ["not an angle"]),
    ("5 percent", "angle", ["not an angle"]),
    ("100 Hz", "speed", ["angle unit"]),
    ("inf mm", "length", ["inf mm"]),
    ("nan mm", "length", ["nan mm"]),
    ("1e999 mm", "length", ["not finite"]),
    ("٣ mm", "length", ["number"]),                             # digits other than 0-9
    ("35 gr", "mass", ['"gr"', "grains", '"g"', '"grain"']),   # was read as 35 grains, 2.27 g
    ("2 gr*mm", "mass_length", ['"gr"', "ambiguous"]),
])
def test_bad_quantities_name_the_value(text, kind, words):
    with pytest.raises(UnitError) as exc:
        to_si(text, kind, "--opt")
    msg = str(exc.value)
    assert exc.value.parameter == "--opt" and msg.startswith("--opt: ")
    for w in words:
        assert w in msg, msg


def test_numbers_are_si_and_booleans_are_refused():
    assert to_si(0.0167, "length") == 0.0167 and to_si(np.float32(2.0), "mass") == 2.0
    for bad in (True, None, [1.0], float("inf")):
        with pytest.raises(UnitError):
            to_si(bad, "length", "x")


@pytest.mark.parametrize("deg, n", [(5, 72), (1, 360), (0.5, 720), (7.2, 50), (90, 4), (0.0036, MAX_POSITIONS)])
def test_steps_that_divide_a_turn(deg, n):
    assert steps_per_turn(math.radians(deg)) == (n, "")


@pytest.mark.parametrize("deg, words", [
    (7, ["does not divide", "6 deg", "7.2 deg"]), (0, ["positive"]), (-5, ["positive"]), (100, ["divide"]),
    (1e-6, ["100,000", "0.0036"]), (0.0035, ["100,000"]), (120, ["fewer than 4"]), (float("nan"), ["positive"]),
])
def test_steps_refused(deg, words):
    n, problem = steps_per_turn(math.radians(deg))
    assert n is None
    for w in words:
        assert w in problem, problem


def test_display_units():
    si = DisplayUnits.parse(None)
    assert si.si and si.of("m/s") == ("m/s", 1.0)
    d = DisplayUnits.parse("mm, deg")
    assert d.of("m") == ("mm", 1000.0) and d.of("m/s^2") == ("mm/s^2", 1000.0)
    unit, f = d.of("rad/s")
    assert unit == "deg/s" and f == pytest.approx(180 / math.pi)
    assert d.of("N") == ("N", 1.0) and d.of("J") == ("J", 1.0)
    cols = d.table({"phi [rad]": np.array([math.pi]), "eye.x [m]": np.array([0.01]), "e [J]": np.array([2.0]),
                    "note": np.array([1.0])})
    assert list(cols) == ["phi [deg]", "eye.x [mm]", "e [J]", "note"]
    assert cols["phi [deg]"][0] == pytest.approx(180.0) and cols["eye.x [mm]"][0] == pytest.approx(10.0)
    g = DisplayUnits.parse("cm,g,N*mm")
    assert g.of("m") == ("cm", 100.0) and g.of("kg") == ("g", 1000.0) and g.of("N*m") == ("N*mm", 1000.0)


@pytest.mark.parametrize("text, words", [("rpm", ["rpm"]), ("mm,mm", ["two units"]), ("mm,,deg", ["empty"]),
                                         ("5 mm", ["5 mm"]), ("furlong,parsec", ["two units for length"])])
def test_display_units_refused(text, words):
    with pytest.raises(UnitError) as exc:
        DisplayUnits.parse(text, "--units")
    assert exc.value.parameter == "--units"
    for w in words:
        assert w in str(exc.value)

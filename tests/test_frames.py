"""Results as tables: to_dataframe() / to_xarray() on Motion, ForceAnalysis, MachineAnalysis; readable reprs;
pandas imported on first use only."""
import subprocess
import sys

import numpy as np
import pytest

import sewgen
from sewgen.machine.assembly import load_machine

pytestmark = [pytest.mark.c]


def test_import_sewgen_does_not_import_pandas():
    code = "import sewgen, sewgen.cli.main, sewgen.study, sys; print('pandas' in sys.modules, 'dask' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["False", "False"]


def test_motion_and_force_analysis_as_dataframes():
    nb = sewgen.mechanism("needle_bar")
    phi = sewgen.shaft_angles(5)
    mo = nb.solve(phi, speed="1000 rpm")
    df = mo.to_dataframe()
    assert df.shape == (72, len(mo.table())) and df.index.name == "phi [deg]"
    assert np.array_equal(df["needle_eye.y [m]"].to_numpy(), mo.point("needle_eye").y)
    assert np.allclose(df.index.to_numpy(), np.degrees(phi))
    fa = nb.kinetostatics(phi, speed="1000 rpm")
    fdf = fa.to_dataframe()
    assert "needle_eye.y [m]" in fdf and "shaft.torque [N*m]" in fdf
    assert np.array_equal(fdf["shaft.torque [N*m]"].to_numpy(), fa.torque("shaft"))
    assert "needle_eye.y [m]" not in fa.to_dataframe(kinematics=False)
    assert repr(mo).startswith("<Motion of needle_bar: 72 positions, φ 0°–355° at 1000 rpm")
    assert repr(fa).startswith("<ForceAnalysis of needle_bar: 72 positions")


def test_machine_analysis_as_dataframes_and_xarray():
    a = load_machine("jb1-3").analyze()
    df = a.to_dataframe()
    assert df.index.name == "phi [deg]" and len(df) == 72
    assert np.array_equal(df["drive_torque [N*m]"].to_numpy(), a.torque)
    g = a.to_dataframe("feed")
    assert "feed_dog.y [m]" in g
    with pytest.raises(KeyError, match="no group"):
        a.to_dataframe("nope")
    assert repr(a).startswith("<MachineAnalysis of JB1-3: 72 positions")
    pytest.importorskip("xarray")
    ds = a.to_xarray()
    assert ds["drive_torque"].attrs["units"] == "N*m" and ds.sizes["phi"] == 72
    mo = a.groups["feed"].motion.to_xarray()
    assert mo["feed_dog.y"].attrs["units"] == "m"

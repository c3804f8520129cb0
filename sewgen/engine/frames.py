"""Results as the tables a notebook user expects: pandas DataFrames (and xarray Datasets) built from the
``"<name> [unit]"`` column dicts every result already has. pandas and xarray are imported here, on first use,
so ``import sewgen`` stays light."""
from __future__ import annotations

import numpy as np

from sewgen.units import HEADER  # "<name> [unit]"


def pandas():
    import pandas as pd

    return pd


def dataframe(cols: dict, phi_deg, index_name: str = "phi [deg]"):
    """A DataFrame of ``cols`` (name -> array), indexed by the shaft angle in degrees."""
    pd = pandas()
    df = pd.DataFrame({k: np.asarray(v) for k, v in cols.items()})
    df.index = pd.Index(np.asarray(phi_deg, float), name=index_name)
    return df


def dataset(cols: dict, phi_deg, attrs: dict | None = None):
    """An xarray Dataset over the shaft angle ``phi`` (deg): one variable per column, its unit in ``attrs``.
    xarray is optional: without it an ImportError says how to get it."""
    try:
        import xarray as xr
    except ImportError:  # pragma: no cover - depends on the environment
        raise ImportError("to_xarray() needs xarray: pip install xarray") from None
    data = {}
    for k, v in cols.items():
        m = HEADER.match(k)
        name, unit = (m["name"], m["unit"]) if m else (k, "")
        if name in ("phi",):
            continue
        data[name] = xr.Variable(("phi",), np.asarray(v), attrs={"units": unit})
    return xr.Dataset(data, coords={"phi": ("phi", np.asarray(phi_deg, float), {"units": "deg"})},
                      attrs=attrs or {})


def angle_span(phi) -> str:
    """"72 positions, 0°–355°" for a repr."""
    phi = np.asarray(phi)
    if not len(phi):
        return "no positions"
    d = np.degrees(phi)
    return f"{len(phi)} position{'s' if len(phi) != 1 else ''}, φ {d.min():g}°–{d.max():g}°"


def speed_text(omega) -> str:
    w = np.asarray(omega)
    if not len(w):
        return ""
    if np.all(w == w[0]):
        return f"{float(w[0]) * 30 / np.pi:.6g} rpm"
    return f"{float(w.min()) * 30 / np.pi:.6g}–{float(w.max()) * 30 / np.pi:.6g} rpm"

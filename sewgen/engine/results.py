"""Named results of a sweep: every coordinate, point and body with position, velocity and acceleration."""
from __future__ import annotations

import csv
from dataclasses import dataclass, replace

import numpy as np

from sewgen.files import replacing


#: The arrays of a :class:`Motion` (those :meth:`Motion.of_block` makes as views at the first look).
_BLOCK_ARRAYS = frozenset({"phi", "omega", "alpha", "error_estimate", "q", "qd", "qdd", "obs"})


@dataclass(frozen=True)
class PointMotion:
    """A point's path: position (m), velocity (m/s), acceleration (m/s²), one entry per shaft angle. ``z``,
    ``vz``, ``az``: out of the mechanism's plane, for a spatial crank's centre of mass (None for every point that
    stays in the plane, z = 0)."""

    x: np.ndarray
    y: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    ax: np.ndarray
    ay: np.ndarray
    z: np.ndarray | None = None
    vz: np.ndarray | None = None
    az: np.ndarray | None = None


@dataclass(frozen=True)
class BodyMotion:
    """A body's angle (rad), angular velocity (rad/s) and acceleration (rad/s²), and its centre of mass."""

    angle: np.ndarray
    omega: np.ndarray
    alpha: np.ndarray
    com: PointMotion


@dataclass(frozen=True)
class CoordinateMotion:
    """A coordinate (link angle in rad or slider travel in m) and its first and second time derivatives."""

    value: np.ndarray
    rate: np.ndarray
    accel: np.ndarray
    unit: str


class Motion:
    """The kinematics of one mechanism over a sweep of shaft angles (SI units throughout).

    ``error_estimate`` (per position): the estimated relative error of the velocities and accelerations (each
    relative to the position's own scale of its kind: the largest rate times its lever, the largest acceleration
    or centripetal term), from the amplification of their solves and the position's own accuracy
    (csrc/sg_runtime.h sg_rates_error; docs/explanation/derivation.md, "Singular positions"); ``singular`` flags
    the positions above ``singular_tol`` (kept only by ``solve(..., singular="flag")``).

    Plain arrays plus the mechanism (which pickles by reference), so a Motion pickles, crosses processes and
    compares bit for bit; every named view reads the mechanism's description for its column.
    """

    def __init__(self, mechanism, phi, omega, alpha, q, qd, qdd, obs, error_estimate=None, singular_tol=1e-8):
        self.mechanism = mechanism
        self.phi, self.omega, self.alpha = phi, omega, alpha
        self.q, self.qd, self.qdd, self.obs = q, qd, qdd, obs
        self.error_estimate = np.zeros(len(phi)) if error_estimate is None else error_estimate
        self.singular_tol = singular_tol

    @classmethod
    def of_block(cls, mechanism, blk: np.ndarray, n: int, nq: int, nobs: int, singular_tol: float) -> "Motion":
        """A Motion over one buffer in sg_solve_lean's layout (csrc/sg_runtime.c: phi, omega, alpha, the error
        estimate, then q, qd, qdd and obs by rows), its arrays made as views at the first look at any of them:
        a solve() whose result is read in part, or not at once, does not pay for eight views."""
        self = object.__new__(cls)
        self.__dict__.update(mechanism=mechanism, singular_tol=singular_tol, _lean=(blk, n, nq, nobs))
        return self

    def __getattr__(self, name):
        """The arrays of a Motion made by :meth:`of_block`, at the first look (only attributes not yet set come
        here)."""
        state = self.__dict__
        layout = state.get("_lean") if name in _BLOCK_ARRAYS else None
        if layout is None:
            if name in _BLOCK_ARRAYS and name in state:  # made by another thread since this one looked
                return state[name]
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        blk, n, nq, nobs = layout
        o = 4 * n + 3 * n * nq
        rows, rates = blk[:4 * n].reshape(4, n), blk[4 * n:o].reshape(3, n, nq)  # each C-contiguous
        state.update(phi=rows[0], omega=rows[1], alpha=rows[2], error_estimate=rows[3], q=rates[0],
                     qd=rates[1], qdd=rates[2], obs=blk[o:o + n * nobs].reshape(n, nobs))
        state.pop("_lean", None)
        return state[name]

    def __getstate__(self):
        if "_lean" in self.__dict__:
            self.phi  # noqa: B018 -- the views, so that a pickle holds the arrays
        return self.__dict__

    @property
    def singular(self) -> np.ndarray:
        """Positions whose velocities and accelerations carry an estimated relative error above
        ``singular_tol`` (only a ``solve(..., singular="flag")`` keeps such positions; otherwise they raise)."""
        return self.error_estimate > self.singular_tol

    def __setstate__(self, state):  # results pickled before the error estimate existed
        state.setdefault("error_estimate", np.zeros(len(state["phi"])))
        state.setdefault("singular_tol", 1e-8)
        self.__dict__.update(state)

    def __len__(self) -> int:
        return len(self.phi)

    @property
    def point_names(self) -> list[str]:
        return [p.name for p in self.mechanism.description.points]

    @property
    def body_names(self) -> list[str]:
        return [b.name for b in self.mechanism.description.bodies]

    @property
    def coord_names(self) -> list[str]:
        return [c.name for c in self.mechanism.description.coords]

    def _block(self, off: int) -> PointMotion:
        return PointMotion(*(self.obs[:, off + k] for k in range(6)))

    def point(self, name: str) -> PointMotion:
        desc = self.mechanism.description
        if not desc.has("point", name):
            raise KeyError(f"{self.mechanism.name} has no point {name!r}; points: {', '.join(self.point_names)}")
        return self._block(desc.point(name).offset)

    def body(self, name: str) -> BodyMotion:
        desc = self.mechanism.description
        if not desc.has("body", name):
            raise KeyError(f"{self.mechanism.name} has no moving body {name!r}; bodies: {', '.join(self.body_names)}")
        body = desc.body(name)
        off, com = body.offset, self._block(body.offset + 3)
        if body.com_z is not None:  # a spatial crank's centre of mass leaves the plane
            com = replace(com, **{k: self.obs[:, body.com_z + i] for i, k in enumerate(("z", "vz", "az"))})
        return BodyMotion(self.obs[:, off], self.obs[:, off + 1], self.obs[:, off + 2], com)

    def coord(self, name: str) -> CoordinateMotion:
        desc = self.mechanism.description
        if not desc.has("coord", name):
            raise KeyError(f"{self.mechanism.name} has no coordinate {name!r}; coordinates: "
                           f"{', '.join(self.coord_names)}")
        c = desc.coord(name)
        return CoordinateMotion(self.q[:, c.index], self.qd[:, c.index], self.qdd[:, c.index], c.unit)

    def table(self) -> dict[str, np.ndarray]:
        """Every result as a column named ``"<name> [unit]"``, shaft angle first."""
        cols = {"phi [rad]": self.phi, "omega [rad/s]": self.omega, "alpha [rad/s^2]": self.alpha}
        desc = self.mechanism.description
        for c in desc.coords:
            rate = "m/s" if c.unit == "m" else "rad/s"
            cols[f"{c.name} [{c.unit}]"] = self.q[:, c.index]
            cols[f"{c.name}_d [{rate}]"] = self.qd[:, c.index]
            cols[f"{c.name}_dd [{rate}^2]"] = self.qdd[:, c.index]
        for k, (name, unit) in enumerate(desc.observables):
            cols[f"{name} [{unit}]"] = self.obs[:, k]
        return cols

    def to_csv(self, path) -> None:
        write_csv(path, self.table())

    def to_dataframe(self):
        """Every result of :meth:`table` as a pandas DataFrame, one row per shaft angle (index ``phi [deg]``)."""
        from sewgen.engine.frames import dataframe

        return dataframe(self.table(), np.degrees(self.phi))

    def to_xarray(self):
        """The same as an xarray Dataset over ``phi`` (deg), one variable per output with its unit (xarray is
        optional)."""
        from sewgen.engine.frames import dataset

        return dataset(self.table(), np.degrees(self.phi), {"mechanism": self.mechanism.name})

    def __repr__(self) -> str:
        from sewgen.engine.frames import angle_span, speed_text

        return (f"<Motion of {self.mechanism.name}: {angle_span(self.phi)} at {speed_text(self.omega)}; "
                f"{len(self.coord_names)} coordinates, points {', '.join(self.point_names) or 'none'}; "
                f"bodies {', '.join(self.body_names) or 'none'}>")


def write_csv(path, cols: dict, option: str | None = None):
    """Columns (name -> array, equal lengths) as a CSV file with a header row, written whole or not at all
    (sewgen.files.replacing: a reader sees the old file or the whole new one); returns ``path``. ``option``: the
    command-line option naming the file, for its errors."""
    with replacing(path, option, text=True, newline="") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        w.writerows(zip(*(np.asarray(c).tolist() for c in cols.values())))
    return path


class Selection:
    """Selected outputs of a sweep (``solve(..., outputs=[...])``): each named column a contiguous array over the
    shaft angles (structure of arrays; names as :mod:`sewgen.engine.designs` gives them: ``coords.<name>``,
    ``coords.<name>_d``, ``points.<point>.x`` …). ``point``, ``body`` and ``coord`` work when all their columns
    were selected. ``block`` is the (n_columns, n) array they are rows of (``out=`` reuses it)."""

    def __init__(self, mechanism, phi, omega, alpha, block, names):
        self.mechanism = mechanism
        self.phi, self.omega, self.alpha = phi, omega, alpha
        self.block = block
        self._names = names

    @property
    def columns(self) -> dict:
        """Column name -> its row of ``block`` (made at the first look: a sweep's result costs no views)."""
        cols = self.__dict__.get("_columns") or self.__dict__.get("columns")  # the latter: pickled before
        if cols is None:
            cols = self.__dict__["_columns"] = {name: self.block[k] for k, name in enumerate(self._names)}
        return cols

    def __len__(self) -> int:
        return len(self.phi)

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.columns[name]
        except KeyError:
            raise KeyError(f"{name!r} was not selected; selected: {', '.join(self.columns)}") from None

    def __contains__(self, name: str) -> bool:
        return name in self.columns

    def keys(self):
        return self.columns.keys()

    def point(self, name: str) -> PointMotion:
        return PointMotion(*(self[f"points.{name}.{f}"] for f in ("x", "y", "x_d", "y_d", "x_dd", "y_dd")))

    def body(self, name: str) -> BodyMotion:
        b = f"bodies.{name}"
        com = PointMotion(*(self[f"{b}.com.{f}"] for f in ("x", "y", "x_d", "y_d", "x_dd", "y_dd")),
                          *(self.columns.get(f"obs.{name}.com.{f}") for f in ("z", "z_d", "z_dd")))
        return BodyMotion(self[f"{b}.angle"], self[f"{b}.angle_d"], self[f"{b}.angle_dd"], com)

    def coord(self, name: str) -> CoordinateMotion:
        c = self.mechanism.description.coord(name)
        return CoordinateMotion(self[f"coords.{name}"], self[f"coords.{name}_d"], self[f"coords.{name}_dd"], c.unit)

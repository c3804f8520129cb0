"""Named results of a sweep: every coordinate, point and body with position, velocity and acceleration."""
from __future__ import annotations

import csv
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PointMotion:
    """A point's path: position (m), velocity (m/s), acceleration (m/s²), one entry per shaft angle."""

    x: np.ndarray
    y: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    ax: np.ndarray
    ay: np.ndarray


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
    """The kinematics of one mechanism over a sweep of shaft angles (SI units throughout)."""

    def __init__(self, mechanism, phi, omega, alpha, q, qd, qdd, obs):
        self.mechanism = mechanism
        self.phi, self.omega, self.alpha = phi, omega, alpha
        self.q, self.qd, self.qdd, self.obs = q, qd, qdd, obs
        lay = mechanism.layout
        self._points, self._bodies, self._coords = lay["points"], lay["bodies"], lay["coords"]

    def __len__(self) -> int:
        return len(self.phi)

    @property
    def point_names(self) -> list[str]:
        return list(self._points)

    @property
    def body_names(self) -> list[str]:
        return list(self._bodies)

    @property
    def coord_names(self) -> list[str]:
        return list(self._coords)

    def _block(self, off: int) -> PointMotion:
        return PointMotion(*(self.obs[:, off + k] for k in range(6)))

    def point(self, name: str) -> PointMotion:
        if name not in self._points:
            raise KeyError(f"{self.mechanism.name} has no point {name!r}; points: {', '.join(self._points)}")
        return self._block(self._points[name])

    def body(self, name: str) -> BodyMotion:
        if name not in self._bodies:
            raise KeyError(f"{self.mechanism.name} has no moving body {name!r}; bodies: {', '.join(self._bodies)}")
        off = self._bodies[name]
        return BodyMotion(self.obs[:, off], self.obs[:, off + 1], self.obs[:, off + 2], self._block(off + 3))

    def coord(self, name: str) -> CoordinateMotion:
        if name not in self._coords:
            raise KeyError(f"{self.mechanism.name} has no coordinate {name!r}; coordinates: {', '.join(self._coords)}")
        i, unit = self._coords[name]
        return CoordinateMotion(self.q[:, i], self.qd[:, i], self.qdd[:, i], unit)

    def table(self) -> dict[str, np.ndarray]:
        """Every result as a column named ``"<name> [unit]"``, shaft angle first."""
        cols = {"phi [rad]": self.phi, "omega [rad/s]": self.omega, "alpha [rad/s^2]": self.alpha}
        for name, (i, unit) in self._coords.items():
            rate = "m/s" if unit == "m" else "rad/s"
            cols[f"{name} [{unit}]"] = self.q[:, i]
            cols[f"{name}_d [{rate}]"] = self.qd[:, i]
            cols[f"{name}_dd [{rate}^2]"] = self.qdd[:, i]
        for k, o in enumerate(self.mechanism.manifest["observables"]):
            cols[f"{o['name']} [{o['unit']}]"] = self.obs[:, k]
        return cols

    def to_csv(self, path) -> None:
        write_csv(path, self.table())


def write_csv(path, cols: dict):
    """Columns (name -> array, equal lengths) as a CSV file with a header row; returns ``path``."""
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        w.writerows(zip(*(np.asarray(c).tolist() for c in cols.values())))
    return path

"""The modelling vocabulary's parts: parameters, bodies and their attachment points, lines, arcs, joints,
inputs, and the error a bad declaration raises (DESIGN.md §3). The joint kinds, the force elements and the
drawing build on these; :class:`derive.model.Mechanism` declares a mechanism with them.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import sympy as sp

if TYPE_CHECKING:
    from .model import Mechanism

from ..units import SI_UNITS, UnitError, to_si

#: A declared name: lower_snake_case.
NAME = re.compile(r"^[a-z][a-z0-9_]*$")


class DeclarationError(ValueError):
    """A mechanism declaration that cannot be derived (names the mechanism and the part)."""


#: The largest bare number (SI, no unit) a declaration's coordinate may be, by kind: a sewing machine has no part
#: a metre long and no fixed angle beyond a turn, so a bare 12 where a length goes (12 m) or 90 where an angle goes
#: (90 rad) is a number meant in mm or deg: refused, naming it, before anything is derived or compiled.
BARE_LIMIT = {"length": 1.0, "angle": 2 * math.pi}


def check_bare(mech: str, owner: str, expr: sp.Expr, kind: str) -> sp.Expr:
    """``expr`` (a coordinate of ``owner`` given without a unit) if it is not a number beyond :data:`BARE_LIMIT`."""
    limit = BARE_LIMIT.get(kind)
    if limit is not None and expr.is_number and expr.is_real and abs(float(expr)) > limit:
        unit = SI_UNITS[kind]
        raise DeclarationError(f"{mech}: a coordinate of {owner!r} is the bare number {float(expr):g}, read as "
                               f"{float(expr):g} {unit}: give it with its unit (e.g. \"{float(expr):g} "
                               f"{'mm' if kind == 'length' else 'deg'}\")")
    return expr


@dataclass(frozen=True)
class Param:
    """A named parameter: symbol, physical kind, SI default, the unit it was declared in, docstring, and the
    physical range its values must lie in (``minimum``, ``maximum``, SI; None: open)."""

    name: str
    symbol: sp.Symbol
    kind: str
    default: float
    display_unit: str
    doc: str
    positive: bool
    minimum: float | None = None
    maximum: float | None = None

    @property
    def unit(self) -> str:
        return SI_UNITS[self.kind]


@dataclass(frozen=True)
class Attachment:
    """A point fixed in a body, at local coordinates (u, v) of the body frame."""

    body: "Body"
    u: sp.Expr
    v: sp.Expr


@dataclass(frozen=True)
class Line:
    """A line fixed in a body: through local point (u, v), at local angle ``angle``."""

    body: "Body"
    u: sp.Expr
    v: sp.Expr
    angle: sp.Expr


@dataclass(frozen=True)
class Axis:
    """A fixed axis in the machine frame (x, y in the mechanism's plane, z out of it): a point on it, its unit
    direction, and the unit vectors e1 (angle zero) and e2 = direction × e1 of the plane it turns in."""

    point: tuple
    direction: tuple
    e1: tuple
    e2: tuple


@dataclass(frozen=True)
class SpatialPoint:
    """A point of a spatial crank: at ``radius`` from its axis in the plane it turns in, ``along`` the axis from
    the axis point (seed 003's crank pin B of the spatial four-bar)."""

    body: "Body"
    radius: sp.Expr
    along: sp.Expr


@dataclass(eq=False)
class Body:
    """A rigid body. ``kind`` is ground, driven (angle = input), link (free angle) or slider (travel)."""

    mech: "Mechanism"
    name: str
    kind: str
    doc: str = ""
    pivot: Attachment | None = None  # driven: its pivot (None: a held travel on ``guide``)
    input_index: int = -1  # driven: which input drives it
    phase: sp.Expr = sp.S.Zero  # driven: angle = pivot body's angle + sense * ratio * input + phase
    sense: int = 1
    ratio: sp.Expr = sp.S.One
    guide: Line | None = None  # slider, or a driven body held at a travel: the line it travels on
    guess: float = 0.0  # link angle (rad) or slider travel (m) to start Newton from
    axis: Axis | None = None  # spatial crank: the axis it turns about (its angle is measured from e1 to e2)
    mass: sp.Expr = sp.S.Zero
    com: tuple = (sp.S.Zero, sp.S.Zero)
    inertia: sp.Expr = sp.S.Zero

    def at(self, u, v) -> Attachment:
        """The point (u, v) of this body's frame: symbols, numbers (m) or quantity strings ("25 mm")."""
        if self.axis is not None:
            raise DeclarationError(f"{self.mech.name}: {self.name!r} turns about an axis in space: its points are "
                                   f"{self.name}.pin(radius, along), not .at(u, v)")
        return Attachment(self, self.expr(u, "length"), self.expr(v, "length"))

    def pin(self, radius, along="0 mm") -> SpatialPoint:
        """A spatial crank's point at ``radius`` from its axis, ``along`` the axis from its axis point."""
        if self.axis is None:
            raise DeclarationError(f"{self.mech.name}: {self.name!r} is a planar body: its points are .at(u, v)")
        return SpatialPoint(self, self.expr(radius, "length"), self.expr(along, "length"))

    def line(self, at=(0, 0), angle=0) -> Line:
        """The line through (u, v) of this body's frame at ``angle`` (rad, a symbol or "30 deg")."""
        return Line(self, self.expr(at[0], "length"), self.expr(at[1], "length"), self.expr(angle, "angle"))

    def expr(self, value, kind: str) -> sp.Expr:
        """A ``kind`` (length, angle) of this body's declaration as a SymPy expression: an SI number, a quantity
        string (\"16.7 mm\") or a parameter's symbol."""
        if isinstance(value, str):
            try:
                return sp.Float(to_si(value, kind, f"{self.mech.name}.{self.name}"))
            except UnitError as exc:
                raise DeclarationError(str(exc)) from None
        try:
            expr = sp.sympify(value, strict=True)
        except (sp.SympifyError, TypeError):
            raise DeclarationError(f"{self.mech.name}: a coordinate of {self.name!r} must be a number, a "
                                   f"parameter symbol or a quantity string, got {value!r}") from None
        return check_bare(self.mech.name, self.name, expr, kind)

    @property
    def moving(self) -> bool:
        return self.kind != "ground"

    def __repr__(self) -> str:
        return f"<{self.kind} {self.name}>"


@dataclass(frozen=True)
class Arc:
    """One circular arc of a cam profile, in the cam's frame: centre (u, v), radius, and the sector of outward
    normal directions [normal_from, normal_to] (rad, counter-clockwise, width < 180°) over which it is the
    profile's extreme point — i.e. where a flat face touching the cam touches this arc."""

    center_u: sp.Expr
    center_v: sp.Expr
    radius: sp.Expr
    normal_from: sp.Expr
    normal_to: sp.Expr


@dataclass(eq=False)
class Joint:
    """A joint of ``kind`` (a key of :data:`derive.joints.KINDS`, whose class says what it constrains and
    carries) between side ``a`` and side ``b``, each a point (:class:`Attachment`) or a line of a body."""

    name: str
    kind: str
    a: Attachment | Line
    b: Attachment | Line
    branch: int = 1
    arcs: tuple = ()
    values: dict = field(default_factory=dict)  # a kind's own values (a rod's length, its planar end's z)


@dataclass(frozen=True)
class Input:
    """A driving input: the shaft angle (index 0) or a held input such as a stitch regulator."""

    name: str
    kind: str  # "shaft" or "held"
    default: float  # held inputs: SI default value (rad, or m for a travel)
    display_unit: str
    doc: str
    quantity: str = "angle"  # what it sets: a relative angle ("angle", rad) or a relative travel ("length", m)

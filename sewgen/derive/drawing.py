"""Drawing anchors: where every body's joints, guides, cam arcs, named points and centre of mass are, in the
world, as expressions of the coordinates, inputs and parameters (DESIGN.md §7, "pictures of any mechanism").

The run time draws any mechanism from these alone — each body as the outline through its joint anchors, a
slider as a block on its guide, a cam as its arcs, ground anchors as pivots — so a user's mechanism gets the same
pictures as the catalog. Each joint kind gives its own anchors (:mod:`derive.joints`) with the helpers here;
:func:`anchors` walks the declaration. The kernel that evaluates them is ``sg_<m>_anchors`` (:meth:`KernelSet.anchors`); its output is
laid out in the manifest's "anchors" (x, y per anchor; a "guide_direction" pair is a unit vector) and "arcs"
(radius, world normal_from, world normal_to per cam arc, after the anchors).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import sympy as sp

from .vocabulary import Attachment, Line

if TYPE_CHECKING:  # the joint kinds import this module, and kinematics imports the joint kinds
    from .kinematics import Kinematics


@dataclass(frozen=True)
class Anchor:
    name: str
    body: str
    kind: str  # joint | point | guide | guide_direction | arc_center | com
    joint: str | None
    xy: tuple  # two SymPy expressions


@dataclass(frozen=True)
class ArcAnchor:
    joint: str
    body: str
    center: int  # index of its arc_center anchor
    radius: sp.Expr
    normal_from: sp.Expr  # world angles
    normal_to: sp.Expr


def at_anchor(kin: Kinematics, att: Attachment, name: str, kind: str, joint: str | None) -> Anchor:
    """The anchor of a point fixed in a body."""
    return Anchor(name, att.body.name, kind, joint, kin.world(att))


def guide_anchors(kin: Kinematics, line: Line, joint: str) -> list[Anchor]:
    """A guide line's origin and its world unit direction."""
    th = kin.pose[line.body][2] + line.angle
    origin = at_anchor(kin, Attachment(line.body, line.u, line.v), f"{joint}@{line.body.name}", "guide", joint)
    return [origin, Anchor(f"{joint}.direction", line.body.name, "guide_direction", joint, (sp.cos(th), sp.sin(th)))]


def anchors(kin: Kinematics, kind_of) -> tuple[list[Anchor], list[ArcAnchor]]:
    """Every anchor of the mechanism (the joints its bodies imply, every declared joint — each kind's own
    anchors, :meth:`derive.joints.JointKind.anchors`, found by ``kind_of``: the joint kinds draw themselves with
    this module's helpers — named points, centres of mass) and every cam arc."""

    mech = kin.mech
    out: list[Anchor] = []
    for j in mech.implied_joints() + mech.joints:
        out += kind_of(j).anchors(kin, j)
    for name, att, _doc in mech.points:
        out.append(at_anchor(kin, att, name, "point", None))
    for body in mech.bodies:
        if body.moving:
            out.append(Anchor(f"{body.name}.com", body.name, "com", None, kin.com(body)[:2]))
    arcs = []
    index = {a.name: k for k, a in enumerate(out)}
    for j in mech.joints:
        turn = kin.pose[j.a.body][2]
        for k, arc in enumerate(j.arcs):
            arcs.append(ArcAnchor(j.name, j.a.body.name, index[f"{j.name}.arc{k}"], arc.radius,
                                  turn + arc.normal_from, turn + arc.normal_to))
    return out, arcs


def manifest(anchor_list: list[Anchor], arc_list: list[ArcAnchor]) -> dict:
    """The manifest's "anchors" and "arcs" entries (see the module docstring)."""
    return {"anchors": [{"name": a.name, "body": a.body, "kind": a.kind, "joint": a.joint} for a in anchor_list],
            "arcs": [{"joint": a.joint, "body": a.body, "center": a.center, "out": k} for k, a in enumerate(arc_list)]}


def outputs(anchor_list: list[Anchor], arc_list: list[ArcAnchor]) -> list:
    """The kernel's outputs in order: x, y of every anchor, then radius, normal_from, normal_to of every arc."""
    out = [e for a in anchor_list for e in a.xy]
    for a in arc_list:
        out += [a.radius, a.normal_from, a.normal_to]
    return out

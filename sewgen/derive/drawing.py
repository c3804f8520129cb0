"""Drawing anchors: where every body's joints, guides, cam arcs, named points and centre of mass are, in the
world, as expressions of the coordinates, inputs and parameters (DESIGN.md §7, "pictures of any mechanism").

The run time draws any mechanism from these alone — each body as the outline through its joint anchors, a
slider as a block on its guide, a cam as its arcs, ground anchors as pivots — so a user's mechanism gets the same
pictures as the catalog. One function per joint kind gives that kind's anchors; :func:`anchors` walks the
declaration. The kernel that evaluates them is ``sg_<m>_anchors`` (:meth:`KernelSet.anchors`); its output is
laid out in the manifest's "anchors" (x, y per anchor; a "guide_direction" pair is a unit vector) and "arcs"
(radius, world normal_from, world normal_to per cam arc, after the anchors).
"""
from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from .kinematics import Kinematics
from .model import Attachment, Joint, Line


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


def _at(kin: Kinematics, att: Attachment, name: str, kind: str, joint: str | None) -> Anchor:
    return Anchor(name, att.body.name, kind, joint, kin.world(att))


def _guide(kin: Kinematics, line: Line, joint: str) -> list[Anchor]:
    """A guide line's origin and its world unit direction."""
    th = kin.pose[line.body][2] + line.angle
    origin = _at(kin, Attachment(line.body, line.u, line.v), f"{joint}@{line.body.name}", "guide", joint)
    return [origin, Anchor(f"{joint}.direction", line.body.name, "guide_direction", joint, (sp.cos(th), sp.sin(th)))]


def _revolute(kin: Kinematics, j: Joint) -> list[Anchor]:
    return [_at(kin, j.a, f"{j.name}@{j.a.body.name}", "joint", j.name),
            _at(kin, j.b, f"{j.name}@{j.b.body.name}", "joint", j.name)]


def _slide(kin: Kinematics, j: Joint) -> list[Anchor]:
    """Prismatic and slot: the guide line of body a, the pin or slider point of body b."""
    return _guide(kin, j.a, j.name) + [_at(kin, j.b, f"{j.name}@{j.b.body.name}", "joint", j.name)]


def _cam(kin: Kinematics, j: Joint) -> list[Anchor]:
    """The follower's flat face (a guide line) and the cam's arc centres (their radii and sectors: :func:`arcs`)."""
    cam = j.a.body
    out = _guide(kin, j.b, j.name)
    for k, arc in enumerate(j.arcs):
        out.append(_at(kin, Attachment(cam, arc.center_u, arc.center_v), f"{j.name}.arc{k}", "arc_center", j.name))
    return out


#: Joint kind -> its anchors.
JOINT_ANCHORS = {"revolute": _revolute, "prismatic": _slide, "slot": _slide, "cam": _cam}


def anchors(kin: Kinematics) -> tuple[list[Anchor], list[ArcAnchor]]:
    """Every anchor of the mechanism (pivots and guides of driven bodies and sliders, every joint, named points,
    centres of mass) and every cam arc."""
    mech = kin.mech
    out: list[Anchor] = []
    for body in mech.bodies:
        if body.kind == "driven":  # the pivot on ground and the body's own origin
            name = f"{body.name}.pivot"
            out += [_at(kin, body.pivot, f"{name}@ground", "joint", name),
                    _at(kin, Attachment(body, sp.S.Zero, sp.S.Zero), f"{name}@{body.name}", "joint", name)]
        elif body.kind == "slider":
            name = f"{body.name}.guide"
            out += _guide(kin, body.guide, name)
            out.append(_at(kin, Attachment(body, sp.S.Zero, sp.S.Zero), f"{name}@{body.name}", "joint", name))
    for j in mech.joints:
        out += JOINT_ANCHORS[j.kind](kin, j)
    for name, att, _doc in mech.points:
        out.append(_at(kin, att, name, "point", None))
    for body in mech.bodies:
        if body.moving:
            out.append(_at(kin, Attachment(body, *body.com), f"{body.name}.com", "com", None))
    arcs = []
    index = {a.name: k for k, a in enumerate(out)}
    for j in mech.joints:
        if j.kind != "cam":
            continue
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

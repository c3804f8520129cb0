"""One place per joint kind: every joint kind's closure equations, reaction unknowns, force
rows, dyad part and drawing live in its class in sewgen.derive.joints; the rest of the derivation asks the
registry. A kind registered there and nowhere else must flow through kinematics, kinetostatics and drawing."""
from __future__ import annotations

import re
from pathlib import Path

import pytest
import sympy as sp

from sewgen.derive import drawing, joints
from sewgen.derive.kinematics import Kinematics
from sewgen.derive.kinetostatics import Kinetostatics
from sewgen.derive.model import Mechanism

pytestmark = [pytest.mark.derive]

DERIVE = Path(joints.__file__).parent


def test_only_the_joint_kinds_and_the_declaring_methods_name_a_joint_kind():
    names = "|".join(joints.DECLARABLE)
    offenders = []
    for path in sorted(DERIVE.glob("*.py")):
        if path.name in ("joints.py", "model.py"):
            continue
        code = re.sub(r'"""(?:.|\n)*?"""', "", path.read_text())
        code = re.sub(r"#.*", "", code)
        offenders += [f"{path.name}: {m}" for m in re.findall(rf"""["']({names})["']""", code)]
    assert not offenders, offenders


def test_every_kind_fills_only_its_own_unknowns():
    for name, kind in joints.KINDS.items():
        assert kind.name == name
        assert len(kind.columns) >= 1
    mech = _slider_crank_in_a_slot("slot")
    kst = Kinetostatics(Kinematics(mech))
    for r in kst.reactions:
        for body in (r.a, r.b):
            if body.moving:
                for row, column, _ in r.joint_kind.rows(kst, r, body, 1):
                    assert 0 <= row < 3 and 0 <= column < len(r.columns), (r.name, row, column)


def _slider_crank_in_a_slot(kind: str) -> Mechanism:
    """A crank whose pin runs in the slot of a rocker (an oscillating slotted lever: Whitworth's quick return),
    the slot joint declared through ``kind``."""
    m = Mechanism("quick_return")
    crank = m.driven("crank", m.ground.at(0, 0), mass="20 g", com=("5 mm", "0 mm"), inertia="1e-6 kg*m**2")
    rocker = m.link("rocker", guess="60 deg", mass="40 g", com=("30 mm", "0 mm"), inertia="2e-5 kg*m**2")
    m.revolute(m.ground.at(0, "-40 mm"), rocker.at(0, 0), "O")
    m._joint(kind, "slot_pin", rocker.line(), crank.at("15 mm", 0))
    m.point("tip", rocker.at("70 mm", 0))
    return m


def test_a_kind_registered_in_one_place_flows_through_the_derivation(monkeypatch):
    """A copy of the slot registered under a new name and nowhere else gives the same closure, force balance,
    outputs and anchors as the slot itself (names aside)."""

    class Groove(joints.Slot):
        name = "groove"

    monkeypatch.setitem(joints.KINDS, "groove", Groove())
    derived = {}
    for kind in ("slot", "groove"):
        kin = Kinematics(_slider_crank_in_a_slot(kind))
        kst = Kinetostatics(kin)
        anchor_list, _ = drawing.anchors(kin, joints.kind_of)
        derived[kind] = (kin.closure, kst.A, kst.b, [e for _, _, e in kst.outputs], [a.xy for a in anchor_list],
                         [r.kind for r in kst.reactions])
    slot, groove = derived["slot"], derived["groove"]
    assert slot[5].count("slot") == 1 and groove[5].count("groove") == 1
    for a, b in zip(slot[:5], groove[:5]):
        assert sp.simplify(sp.Matrix(a) - sp.Matrix(b)) == sp.zeros(*sp.Matrix(a).shape)


def test_a_declaration_check_belongs_to_its_kind():
    m = Mechanism("bad")
    crank = m.driven("crank", m.ground.at(0, 0))
    with pytest.raises(joints.DeclarationError, match="slot 'S' needs a line of one body and a point of another"):
        m.slot(crank.at(0, 0), m.ground.at(0, 0), "S")
    with pytest.raises(joints.DeclarationError, match="branch of joint 'P' must be"):
        m.revolute(crank.at(0, 0), m.ground.at(0, 0), "P", branch=2)

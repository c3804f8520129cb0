"""A model file read into plain typed data, checked and in SI: what the machine layer builds a machine from.

:func:`read_model` reads the whole file (every table of :mod:`.schema`) in one pass into a :class:`Model`: the
``[machine]`` values, the :class:`Shaft` with its :class:`ShaftMass` list, one :class:`GroupSpec` per group,
the :class:`Stitch` with its :class:`Rule` list and the :class:`ThreadPath` of :class:`Guide` points.

What needs a group's mechanism is read when the mechanism is known: :func:`read_settings` reads the group's
``params``, ``held``, ``branch`` and ``axial`` tables against what the mechanism declares (a
:class:`Declared`, given by the caller that loaded it). :func:`read_counterweights` reads the counterweight
planes (``[[shaft.counterweights]]``) when a machine is balanced.

Every problem is a :class:`~sewgen.machine.modelfile.reader.ModelFileError` naming the file and the dotted key.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from sewgen.engine.loads import Load
from sewgen.machine.modelfile.reader import Reader, load_toml
from sewgen.machine.modelfile.schema import (COUNTERWEIGHT, GROUP, GUIDE, LOAD, MACHINE, MODEL, RULE, SHAFT,
    SHAFT_MASS, STITCH, THREAD)
from sewgen.units import steps_per_turn

#: Names a group may not take: its table would overwrite the machine's (machine.csv, summary.json).
RESERVED_GROUP_NAMES = ("machine", "summary")
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
GRAVITY = 9.80665  # m/s², standard gravity: ``machine.gravity``'s default
DOWN = -math.pi / 2  # −y: the default of ``machine.gravity_direction`` and ``shaft.belt_direction``


# -- the shaft ---------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class ShaftMass:
    """A point mass on the upper shaft: m (kg) at radius r (m), angle (rad, from the shaft angle φ), axial z (m)."""

    name: str
    mass: float
    radius: float
    angle: float
    z: float


@dataclass
class Shaft:
    """The upper shaft's core on its two bearings (seed 000 §二(二)1(6)): ``[shaft]`` in SI."""

    front: float  # z of the front bearing A (m)
    rear: float  # z of the rear bearing B (m)
    inertia: float  # of the core about its axis (kg m²)
    masses: list = field(default_factory=list)  # ShaftMass: the core's mass, unbalance, counterweights
    pulley: float = 0.0  # z of the pulley (m), where the drive torque enters
    belt: tuple = (0.0, 0.0)  # the belt's pull on the pulley (N, frame x, y): T1 + T2 along the belt
    friction: float = 0.0  # Coulomb coefficient of the two bearings (0: ideal, the seeds' assumption)
    journal_radius: float = 0.0  # m, the journals' radius: the friction moment's arm


@dataclass(frozen=True)
class Plane:
    """Where a counterweight may go: axial ``z`` (m), its centre of mass at ``radius`` (m), at most ``max_mass``
    (kg) — so |m·r| ≤ max_mass · radius; ``group`` ties the plane to a group for method 1."""

    name: str
    z: float
    radius: float
    max_mass: float
    group: str | None = None

    @property
    def max_mr(self) -> float:
        return self.max_mass * self.radius


# -- a group -----------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class GroupSpec:
    """``[groups.<name>]`` read as far as the file alone allows, in SI. ``mechanism`` is the text of the file (a
    catalog name or a declaration file's path); ``table`` keeps the group's ``params``, ``held``, ``branch`` and
    ``axial`` tables as the file gives them, for :func:`read_settings`."""

    name: str
    key: str  # "groups.<name>"
    mechanism: str
    phase: float  # rad: group shaft angle = machine shaft angle + phase
    loads: tuple  # sewgen.engine.loads.Load, windows in the machine's shaft angle (rad)
    stitch: float | None  # m: the stitch the regulator is set for (feed groups)
    plane: float | None  # z of the group's plane (m); None: the mean z of its driven bodies
    frame: str  # "across" or "along"
    origin: tuple  # "along": the group's origin in the machine frame (m); else (0, 0, 0)
    table: dict  # the group's table as read: params, held, branch, axial (not converted)


@dataclass(frozen=True)
class Declared:
    """What a group's mechanism declares that its model-file table may set: the mechanism's ``name``, its
    parameters (name -> kind of quantity), held inputs, branch joints and the bodies the shaft drives."""

    name: str
    params: dict
    held: tuple
    branch: tuple
    driven: tuple


@dataclass(frozen=True)
class Settings:
    """A group's ``params``, ``held``, ``axial`` (SI) and ``branch`` (±1) tables, checked against its mechanism."""

    params: dict
    held: dict
    branch: dict
    axial: dict


# -- stitch formation and the thread -------------------------------------------------------------------------

@dataclass(frozen=True)
class Rule:
    """One timing rule of a machine: ``kind`` (a rule's name in sewgen.machine.timing.RULES), limits in SI (None:
    open), its source, and a window (rad, ``take_up_rises_over``)."""

    kind: str
    lo: float | None = None
    hi: float | None = None
    source: str = ""
    window: tuple | None = None


@dataclass(frozen=True)
class Stitch:
    """What stitch formation needs beyond the mechanisms: the cloth's thickness on the plate (m), the loop
    lift (the needle's rise from BDC at which the loop stands, m), how far the shuttle carries the loop past
    the needle before casting it off (rad), and the machine's rules."""

    cloth: float = 0.0015
    loop_lift: float = 0.002
    loop_release: float = math.pi
    rules: tuple = ()


@dataclass(frozen=True)
class Guide:
    """A point of the thread path: on the frame (``at``, m) or a moving point (``point``: a role or
    "group.point") with an ``offset`` (m) along its body's own axes."""

    name: str
    at: tuple | None = None
    point: str | None = None
    offset: tuple = (0.0, 0.0)


@dataclass(frozen=True)
class ThreadPath:
    """The needle thread's guides, from the tension discs to the needle eye."""

    guides: tuple


# -- the whole file ------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Model:
    """A model file read: ``[machine]`` (``speed`` rad/s, ``step`` rad, ``gravity`` (gx, gy) m/s²), the shaft,
    the groups in the file's order, and the stitch and thread (None where the file has none)."""

    path: Path
    name: str
    description: str
    speed: float
    step: float
    gravity: np.ndarray
    shaft: Shaft
    groups: tuple
    stitch: Stitch | None
    thread: ThreadPath | None


def read_model(path, doc: dict | None = None, *, rules: dict) -> Model:
    """The model file ``path`` read and checked (``doc``: its parsed TOML, changed, instead of the file's).
    ``rules``: the timing rules by name (sewgen.machine.timing.RULES), each with the ``kind`` of its value, and
    whether it takes a ``window`` or has ``own_limits``."""
    rd = Reader(path)
    doc = rd.table(load_toml(path) if doc is None else doc, "")
    rd.check_keys(doc, "", MODEL)
    mach = rd.read(rd.table(doc["machine"], "machine"), "machine", MACHINE)
    _check_name(rd, mach["name"])
    shaft = _shaft(rd, rd.read(rd.table(doc["shaft"], "shaft"), "shaft", SHAFT))
    groups, folded = [], {}
    for name, g in rd.table(doc["groups"], "groups").items():
        _check_group_name(rd, name)
        other = folded.setdefault(name.casefold(), name)
        if other != name:
            rd.fail(f"groups.{name}", f"differs from groups.{other} only in case: their tables ({name}.csv, "
                                      f"{other}.csv) would be one file on a case-insensitive file system "
                                      "(Windows, macOS); rename one of them")
        groups.append(_group(rd, name, rd.table(g, f"groups.{name}")))
    if not groups:
        rd.fail("groups", "a machine needs at least one group")
    g_mag = mach.get("gravity", GRAVITY)
    g_dir = mach.get("gravity_direction", DOWN)
    gv = np.array([g_mag * math.cos(g_dir), g_mag * math.sin(g_dir)])
    gv[np.abs(gv) < 1e-15 * max(g_mag, 1e-300)] = 0.0
    stitch = _stitch(rd, doc["stitch"], rules) if "stitch" in doc else None
    thread = _thread(rd, doc["thread"]) if "thread" in doc else None
    n, problem = steps_per_turn(mach["step"])
    if n is None:
        rd.fail("machine.step", problem + " (an angle in deg or rad)")
    return Model(rd.path, mach["name"], mach.get("description", ""), mach["speed"], mach["step"], gv, shaft,
                 tuple(groups), stitch, thread)


def _check_name(rd: Reader, name: str) -> None:
    """The machine's name is the default output folder: a plain name, never a path."""
    bad = ("/" in name or "\\" in name or ".." in name or not name.strip() or name != name.strip()
           or name.startswith(".") or any(ord(c) < 32 or ord(c) == 127 for c in name))
    if bad:
        rd.fail("machine.name", f"must be a plain name (it names the default output folder): no /, \\, .., "
                                f"leading dot, control characters or surrounding spaces; got {name!r}")


def _shaft(rd: Reader, s: dict) -> Shaft:
    """``[shaft]`` (read against SHAFT) with its ``[[shaft.masses]]``: the core's own mass is the first."""
    masses = [ShaftMass("core", s["mass"], 0.0, 0.0, s["mass_z"])]
    for i, item in enumerate(s.get("masses", [])):
        key = f"shaft.masses[{i}]"
        sm = rd.read(rd.table(item, key), key, SHAFT_MASS)
        masses.append(ShaftMass(sm["name"], sm["mass"], sm["radius"], sm["angle"], sm["z"]))
    pull, pull_dir = s.get("belt_pull", 0.0), s.get("belt_direction", DOWN)
    shaft = Shaft(s["front_bearing"], s["rear_bearing"], s["inertia"], masses, s.get("pulley", s["rear_bearing"]),
                  (pull * math.cos(pull_dir), pull * math.sin(pull_dir)),
                  s.get("bearing_friction", 0.0), s.get("journal_radius", 0.0))
    if shaft.friction and not shaft.journal_radius:
        rd.fail("shaft.journal_radius", "bearing friction needs the journals' radius (its arm), e.g. \"6 mm\"")
    if not shaft.rear > shaft.front:
        rd.fail("shaft.rear_bearing", "must lie behind the front bearing (larger z)")
    return shaft


def _check_group_name(rd: Reader, name: str) -> None:
    """A group's name names its table (``<group>.csv``) and its entries in summary.json: an identifier, not a
    reserved name in any case (``Machine.csv`` is ``machine.csv`` on a case-insensitive file system)."""
    if not _IDENTIFIER.fullmatch(name):
        rd.fail(f"groups.{name}", "a group name must be an identifier (letters, digits and _, not starting with a "
                                  "digit)")
    if name.casefold() in RESERVED_GROUP_NAMES:
        rd.fail(f"groups.{name}", f"{name!r} is reserved (the machine's own outputs: "
                                  f"{', '.join(RESERVED_GROUP_NAMES)}); rename the group")


def _group(rd: Reader, name: str, data: dict) -> GroupSpec:
    """``[groups.<name>]`` read against GROUP: its loads, frame, origin and plane checked."""
    key = f"groups.{name}"
    g = rd.read(data, key, GROUP)
    loads = []
    for i, item in enumerate(g.get("loads", [])):
        lk = f"{key}.loads[{i}]"
        ld = rd.read(rd.table(item, lk), lk, LOAD)
        if ("from" in ld) != ("to" in ld):
            rd.fail(lk, "give both 'from' and 'to' for a window, or neither")
        loads.append(Load(ld["at"], ld.get("fx", 0.0), ld.get("fy", 0.0), ld.get("torque", 0.0),
                          (ld["from"], ld["to"]) if "from" in ld else None, ld.get("name", "")))
    frame = g.get("frame", "across")
    if frame not in ("across", "along"):
        rd.fail(f"{key}.frame", f"must be \"across\" or \"along\", got {frame!r}")
    if ("origin" in g) != (frame == "along"):
        rd.fail(f"{key}.origin", "give the origin (the group's origin in the machine frame, [x, y, z]) for a group "
                                 "with frame = \"along\", and only there")
    origin = (0.0, 0.0, 0.0)
    if "origin" in g:
        if not isinstance(g["origin"], list) or len(g["origin"]) != 3:
            rd.fail(f"{key}.origin", "must be three lengths [x, y, z]")
        origin = tuple(rd.quantity(v, "length", f"{key}.origin[{i}]") for i, v in enumerate(g["origin"]))
    if frame == "along" and "plane" in g:
        rd.fail(f"{key}.plane", "an \"along\" group's plane is x = origin x: give the origin, not the plane")
    table = {k: g.get(k, {}) for k in ("params", "held", "branch", "axial")}
    return GroupSpec(name, key, g["mechanism"], g["phase"], tuple(loads), g.get("stitch"), g.get("plane"), frame,
                     origin, table)


def read_settings(path, spec: GroupSpec, declared: Declared) -> Settings:
    """A group's ``params``, ``held``, ``branch`` and ``axial`` tables read against what its mechanism declares:
    every name one the mechanism has, every quantity in its kind, every driven body placed on the shaft."""
    rd, key, mech = Reader(path), spec.key, declared.name
    kinds = declared.params
    params = {}
    for pname, value in spec.table["params"].items():
        if pname not in kinds:
            rd.fail(f"{key}.params.{pname}", f"{mech} has no such parameter; it has: {', '.join(kinds)}")
        params[pname] = rd.quantity(value, kinds[pname], f"{key}.params.{pname}")
    held = {}
    for hname, value in spec.table["held"].items():
        if hname not in declared.held:
            rd.fail(f"{key}.held.{hname}", f"{mech} has no such held input; it has: "
                    f"{', '.join(declared.held) or 'none'}")
        held[hname] = rd.quantity(value, "angle", f"{key}.held.{hname}")
    branch = {}
    for bname, value in spec.table["branch"].items():
        if bname not in declared.branch or value not in (1, -1) or isinstance(value, bool):
            rd.fail(f"{key}.branch.{bname}", f"must be a branch joint of {mech} "
                    f"({', '.join(declared.branch) or 'none'}) set to 1 or -1")
        branch[bname] = value
    axial = {}
    for bname, value in spec.table["axial"].items():
        if bname not in declared.driven:
            rd.fail(f"{key}.axial.{bname}", f"not a body the shaft drives; {mech}'s are: {', '.join(declared.driven)}")
        axial[bname] = rd.quantity(value, "length", f"{key}.axial.{bname}")
    for bname in declared.driven:
        if bname not in axial:
            rd.fail(f"{key}.axial.{bname}", "missing (z of this driven body on the upper shaft: a length in m, "
                                            "e.g. \"20 mm\")")
    return Settings(params, held, branch, axial)


def _stitch(rd: Reader, data, rules: dict) -> Stitch:
    """``[stitch]`` with its ``[[stitch.rules]]``, each read in its rule's kind of value."""
    s = rd.read(rd.table(data, "stitch"), "stitch", STITCH)
    windowed = ", ".join(n for n, r in rules.items() if r.window)
    out = []
    for i, item in enumerate(s.get("rules", [])):
        key = f"stitch.rules[{i}]"
        item = rd.table(item, key)
        kind = item.get("rule")
        if kind not in rules:
            rd.fail(f"{key}.rule", f"unknown rule {kind!r}; rules: {', '.join(rules)}")
        kr = rules[kind]
        unit_kind = kr.kind
        schema = {**RULE, "min": replace(RULE["min"], kind=unit_kind), "max": replace(RULE["max"], kind=unit_kind)}
        r = rd.read(item, key, schema)
        if ("from" in r) != ("to" in r) or kr.window != ("from" in r):
            rd.fail(key, f"give 'from' and 'to' (a window of shaft angles) for {windowed}, and only there")
        if not kr.own_limits and "min" not in r and "max" not in r:
            rd.fail(key, f"give 'min' or 'max' (a {unit_kind} with its unit)")
        if "min" in r and "max" in r and r["min"] > r["max"]:
            rd.fail(f"{key}.min", f"{item['min']!r} is above max {item['max']!r}: no value could pass the rule")
        out.append(Rule(kind, r.get("min"), r.get("max"), r["source"], (r["from"], r["to"]) if "from" in r else None))
    return Stitch(s.get("cloth", Stitch.cloth), s.get("loop_lift", Stitch.loop_lift),
                  s.get("loop_release", Stitch.loop_release), tuple(out))


def _thread(rd: Reader, data) -> ThreadPath:
    """``[thread]``: ``[[thread.guides]]`` from the tension discs to the needle eye."""
    t = rd.read(rd.table(data, "thread"), "thread", THREAD)
    guides = []
    for i, item in enumerate(t["guides"]):
        key = f"thread.guides[{i}]"
        g = rd.read(rd.table(item, key), key, GUIDE)
        if ("at" in g) == ("point" in g):
            rd.fail(key, "give 'at' (a point on the frame) or 'point' (a moving point), one of them")

        def pair(name):
            v = g[name]
            if not isinstance(v, list) or len(v) != 2:
                rd.fail(f"{key}.{name}", "must be two lengths with units, e.g. [\"-20 mm\", \"35 mm\"]")
            return tuple(rd.quantity(x, "length", f"{key}.{name}[{k}]") for k, x in enumerate(v))

        if "at" in g:
            if "offset" in g:
                rd.fail(f"{key}.offset", "an offset belongs to a moving point")
            guides.append(Guide(g["name"], at=pair("at")))
        else:
            guides.append(Guide(g["name"], point=g["point"], offset=pair("offset") if "offset" in g else (0.0, 0.0)))
    if len(guides) < 2:
        rd.fail("thread.guides", "a thread path needs at least two guides")
    return ThreadPath(tuple(guides))


def read_counterweights(path, groups) -> list[Plane]:
    """The counterweight planes of the model file ``path`` (``[[shaft.counterweights]]``); ``groups``: the
    machine's group names, the ones a plane may be tied to."""
    rd = Reader(path)
    doc = load_toml(path)
    items = doc.get("shaft", {}).get("counterweights", [])
    if not isinstance(items, list):
        rd.fail("shaft.counterweights", "must be an array of tables ([[shaft.counterweights]])")
    out = []
    groups = set(groups)
    for i, item in enumerate(items):
        key = f"shaft.counterweights[{i}]"
        p = rd.read(rd.table(item, key), key, COUNTERWEIGHT)
        if not p["radius"] > 0 or not p["max_mass"] >= 0:
            rd.fail(key, "radius must be positive and max_mass not negative")
        if p.get("group") is not None and p["group"] not in groups:
            rd.fail(f"{key}.group", f"no group {p['group']!r}; groups: {', '.join(sorted(groups))}")
        out.append(Plane(p["name"], p["z"], p["radius"], p["max_mass"], p.get("group")))
    if len({p.name for p in out}) != len(out):
        rd.fail("shaft.counterweights", "counterweight names must differ")
    return out


__all__ = ["Declared", "Guide", "GroupSpec", "Model", "Plane", "RESERVED_GROUP_NAMES", "Rule", "Settings", "Shaft",
           "ShaftMass", "Stitch", "ThreadPath", "read_counterweights", "read_model", "read_settings"]

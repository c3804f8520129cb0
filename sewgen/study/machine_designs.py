"""Machine-level design sets: any model-file key varied per design, applied to a loaded machine.

A key is the dotted path of a value in the machine's model file, e.g. ``groups.feed.params.feed_arm_r`` (a
group's mechanism parameter: the rest after ``params.`` is the parameter's name, dots and all, e.g.
``groups.feed.params.hook_crank.phase``), ``groups.hook_drive.phase``, ``groups.feed.held.regulator``,
``groups.needle_bar.axial.crank``, ``shaft.rear_bearing``, ``stitch.cloth``. Each key has a kind of quantity
(length, angle, mass …: its schema's, or the mechanism parameter's), its nominal value (the model's, SI) and a
display unit (mm, deg, g; otherwise SI) that names its table column, e.g. ``groups.feed.params.feed_arm_r [mm]``.

Applying a design: a mechanism parameter changes that group's parameter vector only (a batched sweep of the
group); any other key rewrites the model file's value (in SI) and loads the machine again — every check of the
loader applies, and a design it refuses is reported with the loader's error. The stitch regulator stays at the
nominal machine's setting when a parameter changes (the stitch is then an output, the feed-dog travel); vary
``groups.<feed>.stitch`` to set the stitch itself.
"""
from __future__ import annotations

import copy
import math
import re
from dataclasses import dataclass, replace

import numpy as np

from sewgen.errors import ParameterError, SewgenError
from sewgen.machine.modelfile import load_toml
from sewgen.machine.modelfile.schema import COUNTERWEIGHT, GROUP, LOAD, MACHINE, SHAFT, SHAFT_MASS, STITCH
from sewgen.units import SI_UNITS, UnitError, to_si

#: kind -> (display unit, factor from SI)
DISPLAY = {"length": ("mm", 1e3), "angle": ("deg", 180.0 / math.pi), "mass": ("g", 1e3)}
_INDEXED = re.compile(r"^(?P<name>[^\[\]]+)\[(?P<i>\d+)\]$")


@dataclass(frozen=True)
class DesignKey:
    """One varied model-file key: its kind of quantity, nominal value (SI) and, for a mechanism parameter, the
    group and the parameter's name."""

    key: str
    kind: str
    nominal: float
    group: str | None = None
    param: str | None = None

    @property
    def unit(self) -> str:
        return DISPLAY.get(self.kind, (SI_UNITS.get(self.kind, ""), 1.0))[0]

    @property
    def factor(self) -> float:
        return DISPLAY.get(self.kind, ("", 1.0))[1]

    @property
    def column(self) -> str:
        return f"{self.key} [{self.unit}]" if self.unit else self.key

    def parse(self, text: str, what: str) -> float:
        """A quantity of this key's kind, SI (``"0.02 mm"``, ``"1 deg"``)."""
        try:
            return to_si(text, self.kind, what)
        except UnitError as exc:
            raise ParameterError(self.key, what, exc.problem) from None


def _schema_kind(parts: list[str]) -> str | None:
    """The kind of the value at a model-file key (its schema's, sewgen.machine.modelfile.schema), or None where
    the schema does not say (a rule's limits: the rule's own kind, found from the value)."""
    head = parts[0]
    if head == "machine" and len(parts) == 2 and parts[1] in MACHINE:
        return MACHINE[parts[1]].kind
    if head == "shaft":
        if len(parts) == 2 and parts[1] in SHAFT:
            return SHAFT[parts[1]].kind
        if len(parts) == 3 and parts[1].startswith("masses[") and parts[2] in SHAFT_MASS:
            return SHAFT_MASS[parts[2]].kind
        if len(parts) == 3 and parts[1].startswith("counterweights[") and parts[2] in COUNTERWEIGHT:
            return COUNTERWEIGHT[parts[2]].kind
    if head == "groups" and len(parts) >= 3:
        if len(parts) == 3 and parts[2] in GROUP:
            return GROUP[parts[2]].kind
        if len(parts) == 4 and parts[2] == "held":
            return "angle"
        if len(parts) == 4 and parts[2] == "axial":
            return "length"
        if len(parts) == 4 and parts[2].startswith("loads[") and parts[3] in LOAD:
            return LOAD[parts[3]].kind
    if head == "stitch" and len(parts) == 2 and parts[1] in STITCH:
        return STITCH[parts[1]].kind
    if head == "stitch" and len(parts) == 3 and parts[1].startswith("rules["):
        return None  # min/max: the rule's own kind, found from the value
    return None


def _walk(doc, parts: list[str], key: str, machine_name: str):
    """(container, last part) of ``key`` in the model document."""
    node = doc
    for k, part in enumerate(parts):
        m = _INDEXED.match(part)
        name, idx = (m["name"], int(m["i"])) if m else (part, None)
        last = k == len(parts) - 1
        if not isinstance(node, dict) or name not in node:
            have = ", ".join(node) if isinstance(node, dict) else "nothing"
            raise ParameterError(machine_name, key, f"no {'.'.join(parts[:k + 1])!r} in the model file (there: {have})")
        if idx is not None:
            seq = node[name]
            if not isinstance(seq, list) or idx >= len(seq):
                raise ParameterError(machine_name, key, f"{'.'.join(parts[:k + 1])} is not an item of a list")
            if last:
                return seq, idx
            node = seq[idx]
        else:
            if last:
                return node, name
            node = node[name]
    raise ParameterError(machine_name, key, "an empty key")


def parse_key(machine, key: str, doc: dict | None = None) -> DesignKey:
    """The :class:`DesignKey` of ``key`` on ``machine`` (a loaded sewgen.machine.Machine): a key the model file
    does not have, or a value that is no quantity, is a ParameterError naming the key."""
    if not isinstance(key, str) or not key.strip():
        raise ParameterError(machine.name, str(key), "a design key must be a dotted model-file key, e.g. "
                                                     "groups.GROUP.params.NAME")
    key = key.strip()
    m = re.match(r"^groups\.(?P<g>[^.]+)\.params\.(?P<p>.+)$", key)
    if m:
        groups = {g.name: g for g in machine.groups}
        g = groups.get(m["g"])
        if g is None:
            raise ParameterError(machine.name, key, f"no group {m['g']!r}; groups: {', '.join(groups)}")
        desc = g.mechanism.description
        names = g.mechanism.param_names
        if m["p"] not in names:
            raise ParameterError(machine.name, key, f"{g.mechanism.name} has no parameter {m['p']!r}; it has: "
                                                    f"{', '.join(names)}")
        kind = next(p.kind for p in desc.params if p.name == m["p"])
        nominal = float(g.mechanism.param_vector(g.params or None)[names.index(m["p"])])
        return DesignKey(key, kind, nominal, g.name, m["p"])
    if doc is None:
        doc = model_doc(machine)
    parts = key.split(".")
    container, last = _walk(doc, parts, key, machine.name)
    value = container[last]
    kind = _schema_kind(parts)
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        raise ParameterError(machine.name, key, f"is not a quantity (got {type(value).__name__}): a design varies "
                                                "numbers with units")
    if kind is not None and kind not in SI_UNITS:
        raise ParameterError(machine.name, key, f"is a {kind} value, not a quantity: a design varies numbers with "
                                                "units")
    kinds = [kind] if kind else [k for k in SI_UNITS if k != "dimensionless"] + ["dimensionless"]
    for k in kinds:
        try:
            return DesignKey(key, k, float(to_si(value, k, key)))
        except UnitError as exc:
            problem = exc.problem
    raise ParameterError(machine.name, key, f"is not a quantity: {problem}")


def model_doc(machine) -> dict:
    """The machine's model file as parsed TOML."""
    if not machine.source:
        raise ParameterError(machine.name, "model file", "the machine was not loaded from a model file")
    return load_toml(machine.source)


def with_params(machine, changes: dict):
    """A copy of ``machine`` whose groups have the parameter changes ``{group: {param: SI value}}`` (held inputs,
    the stitch regulator among them, unchanged)."""
    groups = []
    for g in machine.groups:
        if g.name in changes:
            g = replace(g, params={**g.params, **changes[g.name]})
        groups.append(g)
    return replace(machine, groups=groups)


def parse_keys(machine, keys) -> list[DesignKey]:
    """Each of ``keys`` (model-file keys, or DesignKeys already parsed) as a :class:`DesignKey` of ``machine``;
    the model file is read once, and only when a key is not a mechanism parameter."""
    doc = None
    out = []
    for k in keys:
        if isinstance(k, DesignKey):
            out.append(k)
            continue
        if doc is None and not re.match(r"^groups\.[^.]+\.params\.", str(k).strip()):
            doc = model_doc(machine)
        out.append(parse_key(machine, k, doc))
    return out


class MachineDesigns:
    """D designs of ``machine``: ``keys`` (model-file keys) and ``values`` (D, len(keys)) in SI."""

    def __init__(self, machine, keys, values):
        self.machine = machine
        parsed = parse_keys(machine, keys)
        seen = set()
        for k in parsed:
            if k.key in seen:
                raise ParameterError(machine.name, k.key, "given twice")
            seen.add(k.key)
        self.keys = parsed
        v = np.asarray(values, dtype=float)
        if v.ndim != 2 or v.shape[1] != len(parsed):
            raise ParameterError(machine.name, "designs", f"need a (designs, {len(parsed)}) table of values, got "
                                                          f"shape {v.shape}")
        self.values = v
        self._doc = None  # the model file's parsed TOML, read on the first design that needs it

    def __len__(self) -> int:
        return len(self.values)

    @property
    def model_keys(self) -> list:
        """The keys that need the model file reloaded (not a group's mechanism parameter)."""
        return [k for k in self.keys if k.group is None]

    @property
    def varied_groups(self) -> list[str]:
        return sorted({k.group for k in self.keys if k.group is not None})

    def group_matrix(self, group) -> np.ndarray:
        """(D, n_params) parameter matrix of ``group`` (a Group) for every design."""
        mech = group.mechanism
        P = np.tile(mech.param_vector(group.params or None), (len(self), 1))
        names = mech.param_names
        for j, k in enumerate(self.keys):
            if k.group == group.name:
                P[:, names.index(k.param)] = self.values[:, j]
        return P

    def param_changes(self, i: int) -> dict:
        out: dict = {}
        for j, k in enumerate(self.keys):
            if k.group is not None:
                out.setdefault(k.group, {})[k.param] = float(self.values[i, j])
        return out

    def machine_for(self, i: int):
        """Design ``i`` as a Machine (a SewgenError if the loader refuses it)."""
        m = self.machine
        if self.model_keys:
            from sewgen.machine.assembly import load_machine

            if self._doc is None:
                self._doc = model_doc(m)
            doc = copy.deepcopy(self._doc)
            for j, k in enumerate(self.keys):
                if k.group is None:
                    container, last = _walk(doc, k.key.split("."), k.key, m.name)
                    unit = SI_UNITS.get(k.kind, "")
                    v = float(self.values[i, j])
                    container[last] = f"{v!r} {unit}".strip() if unit else v
            m = load_machine(m.source, doc=doc, allow_outside_code=m.allow_outside_code)
        return with_params(m, self.param_changes(i))

    def table(self):
        """The designs as a DataFrame, one column per key in its display unit (``<key> [mm]``)."""
        from sewgen.engine.frames import pandas

        return pandas().DataFrame({k.column: self.values[:, j] * k.factor for j, k in enumerate(self.keys)})


__all__ = ["DISPLAY", "DesignKey", "MachineDesigns", "SewgenError", "model_doc", "parse_key", "with_params"]

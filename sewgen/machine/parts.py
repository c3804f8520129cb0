"""A machine's parts by role (never by a catalog name): the group that carries a role, and a role's parameter.

Timing, thread, the report and the plots ask for ``needle_eye``, ``hook_point``, ``thread_eye``, ``feed_dog``
and the rest here, whatever mechanisms the machine's model file names.
"""
from __future__ import annotations


def role_group(machine, role: str, kind: str = "point"):
    """(the first group whose mechanism has ``role`` as a ``kind`` — point, body, parameter, input —, the part's
    name in that mechanism), or (None, None) where no group has it."""
    for g in machine.groups:
        d = g.mechanism.description
        if d.has_role(role) and d.roles[role][0] == kind:
            return g, d.roles[role][1]
    return None, None


def role_param(group, role: str) -> float:
    """The value (SI) of the parameter tagged ``role`` in ``group``'s mechanism, with the group's settings."""
    d = group.mechanism.description
    return float(group.mechanism.param_vector(group.params or None)[d.role(role).index])

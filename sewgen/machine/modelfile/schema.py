"""Every table of a machine model file: its keys, their kinds and units, which are required, what they mean.

A table is a dict key -> :class:`~sewgen.machine.modelfile.reader.Field`, in the order the file's keys are
listed in an "unknown key; allowed here: ..." message. A required key's ``doc`` is part of its "missing ..."
message; keys without one are explained in the comments here. Quantities are read in SI (lengths in m, angles
in rad, ...); the defaults named here are applied by :mod:`sewgen.machine.modelfile.sections`.

=====================================  ===================================================================
``MODEL``                              the top level: ``[machine]``, ``[shaft]``, ``[groups.*]``,
                                       ``[stitch]``, ``[thread]``
``MACHINE``                            ``[machine]``: name, speed, angle step, gravity
``SHAFT``                              ``[shaft]``: the upper shaft on its two bearings (seed 000 §二(二))
``SHAFT_MASS``                         ``[[shaft.masses]]``: a point mass on the shaft (unbalance, counterweight)
``COUNTERWEIGHT``                      ``[[shaft.counterweights]]``: where ``sewgen balance machine`` may put one
``GROUP``                              ``[groups.<name>]``: one mechanism group on the shaft (seed 000 §一(一))
``LOAD``                               ``[[groups.<name>.loads]]``: a process load on a group
``STITCH``                             ``[stitch]``: stitch formation (sewgen.machine.timing)
``RULE``                               ``[[stitch.rules]]``: one timing rule
``THREAD``                             ``[thread]``: the needle thread's path (sewgen.machine.thread)
``GUIDE``                              ``[[thread.guides]]``: one point of that path
=====================================  ===================================================================

A group's ``params``, ``held``, ``branch`` and ``axial`` tables have no schema here: their keys are the ones its
mechanism declares (its parameters with their kinds, held inputs, branch joints, driven bodies), checked when
the mechanism is known (:func:`sewgen.machine.modelfile.sections.read_settings`).
"""
from __future__ import annotations

from sewgen.machine.modelfile.reader import Field
from sewgen.units import FRICTION_MAX, GRAVITY_MAX

#: The top level of a model file. ``machine``, ``shaft`` and ``groups`` are required tables; ``stitch`` and
#: ``thread`` are optional (a machine without them is analysed, not timed).
MODEL = {
    "machine": Field("table"),
    "shaft": Field("table"),
    "groups": Field("table"),
    "stitch": Field("table", False),
    "thread": Field("table", False),
}

#: ``[machine]``. ``name`` names the default output folder (a plain name, never a path). ``gravity`` defaults to
#: 9.80665 m/s² and ``gravity_direction`` to −90° (−y, the machine standing upright).
MACHINE = {
    "name": Field("text", doc="the machine's name"),
    "description": Field("text", False, "what the machine is (shown in reports)"),
    "speed": Field("speed", doc="upper-shaft speed, e.g. \"1000 rpm\"", sign="positive"),
    "step": Field("angle", doc="shaft-angle step, e.g. \"5 deg\" (72 positions)", sign="positive"),
    "gravity": Field("acceleration", False, "magnitude of gravity (default 9.80665 m/s²)", sign="nonnegative",
                     maximum=GRAVITY_MAX),
    "gravity_direction": Field("angle", False, "direction of gravity in the frame, from +x (default −90°: −y)"),
}

#: ``[shaft]``: the upper shaft 上轴组件 1 of seed 000 as a body on its front and rear bearings (z along the
#: shaft, from the front bearing towards the hand wheel). ``pulley`` defaults to the rear bearing's z,
#: ``belt_pull`` to 0 and ``belt_direction`` to −90°; friction is off unless ``bearing_friction`` is given (the
#: seeds' ideal bearings), and then needs ``journal_radius``. ``masses`` is ``[[shaft.masses]]``
#: (:data:`SHAFT_MASS`), ``counterweights`` ``[[shaft.counterweights]]`` (:data:`COUNTERWEIGHT`).
SHAFT = {
    "front_bearing": Field("length", doc="z of the front bearing"),
    "rear_bearing": Field("length", doc="z of the rear bearing"),
    "pulley": Field("length", False, "z of the pulley, where the drive torque enters (default: the rear bearing)"),
    "inertia": Field("inertia", doc="moment of inertia of the shaft core about its axis", sign="nonnegative"),
    "mass": Field("mass", doc="mass of the shaft core", sign="nonnegative"),
    "mass_z": Field("length", doc="z of the core's centre of mass"),
    "masses": Field("list", False, "point masses on the core: unbalance, counterweights, [[shaft.masses]]"),
    "counterweights": Field("list", False, "planes where `sewgen balance machine` may put counterweights"),
    "belt_pull": Field("force", False, "the belt's radial pull on the pulley, T1 + T2", sign="nonnegative"),
    "belt_direction": Field("angle", False, "direction of the belt pull in the frame (from +x)"),
    "bearing_friction": Field("dimensionless", False, "Coulomb friction coefficient of the front and rear "
                              "bearings (default 0: ideal)", sign="nonnegative", maximum=FRICTION_MAX),
    "journal_radius": Field("length", False, "radius of the shaft's journals in the bearings (friction arm)",
                            sign="nonnegative"),
}

#: ``[[shaft.masses]]``: a point mass on the shaft core, all keys required: its ``name``, ``mass``, the ``radius``
#: of its centre of mass, its ``angle`` from the shaft angle φ (the needle-bar crank's direction on the JB1-3)
#: and its axial position ``z``.
SHAFT_MASS = {
    "name": Field("text"),
    "mass": Field("mass", sign="nonnegative"),
    "radius": Field("length", sign="nonnegative"),
    "angle": Field("angle"),
    "z": Field("length"),
}

#: ``[[shaft.counterweights]]``: a plane where ``sewgen balance machine`` may put a counterweight (seed 000
#: part 2's balancing methods), read when balancing (the analysis does not look at it).
COUNTERWEIGHT = {
    "name": Field("text", doc="the counterweight's name"),
    "z": Field("length", doc="axial position on the upper shaft"),
    "radius": Field("length", doc="radius of the counterweight's centre of mass"),
    "max_mass": Field("mass", doc="the most mass the space there allows"),
    "group": Field("text", False, "the group this plane balances by itself (method separate)"),
}

#: ``[groups.<name>]``: one mechanism group on the upper shaft, swept at φ + ``phase`` (seed 000 analyses each
#: group as a plane mechanism, §二(三)). Its name must be an identifier, not a reserved one and not another
#: group's name in another case (it names the group's table, ``<name>.csv``). ``params`` (SI overrides of the
#: mechanism's parameters, each in its own kind), ``held`` (held inputs, angles), ``branch`` (branch joints set
#: to 1 or −1) and ``axial`` (z of every driven body) are checked against the mechanism's declaration.
#: ``frame`` defaults to "across"; ``origin`` is given exactly for "along" groups; ``loads`` is
#: ``[[groups.<name>.loads]]`` (:data:`LOAD`).
GROUP = {
    "mechanism": Field("text", doc="a catalog mechanism's name, or the path of a declaration file (.py with a "
                               "declare()), relative to the model file: Python code that loading the model "
                               "runs, so only in the model file's folder or below unless allowed "
                               "(--allow-outside-code)"),
    "description": Field("text", False, "what the group is"),
    "phase": Field("angle", doc="group shaft angle minus machine shaft angle"),
    "axial": Field("table", doc="z on the upper shaft of every driven body, e.g. { crank = \"-20 mm\" }"),
    "params": Field("table", False, "the mechanism's parameters, each with its unit"),
    "held": Field("table", False, "the mechanism's held inputs (angles)"),
    "stitch": Field("length", False, "stitch length the stitch regulator is set for (feed groups)"),
    "plane": Field("length", False, "z of the group's plane on the machine (default: mean z of its driven bodies)"),
    "frame": Field("text", False, "\"across\" (default: the group's plane is across the shaft) or \"along\" (its "
                   "plane contains the shaft: its x along the shaft, y up; its cranks are spatial cranks about x)"),
    "origin": Field("list", False, "\"along\" groups: the group's origin in the machine frame, [x, y, z] lengths"),
    "branch": Field("table", False, "the mechanism's branch joints, each 1 or -1"),
    "loads": Field("list", False, "process loads, [[groups.<name>.loads]]"),
}

#: ``[[groups.<name>.loads]]``: a process load (thread, presser foot, cloth) on the group's point or body ``at``
#: (required): forces ``fx``, ``fy`` and a ``torque`` (each 0 by default), acting while the machine's shaft angle
#: is in [``from``, ``to``] (both or neither: always; seed 000 gives its windows "relative to the upper-shaft
#: angle").
LOAD = {
    "at": Field("text"),
    "fx": Field("force", False),
    "fy": Field("force", False),
    "torque": Field("torque", False),
    "from": Field("angle", False),
    "to": Field("angle", False),
    "name": Field("text", False),
}

#: ``[stitch]``: what stitch formation needs beyond the mechanisms (defaults in
#: :class:`sewgen.machine.modelfile.sections.Stitch`) and the rules, ``[[stitch.rules]]`` (:data:`RULE`).
STITCH = {
    "cloth": Field("length", False, "cloth thickness on the throat plate", sign="nonnegative"),
    "loop_lift": Field("length", False, "the needle's rise from BDC at which the loop forms", sign="nonnegative"),
    "loop_release": Field("angle", False, "shuttle turn past the needle at which the loop is cast off"),
    "rules": Field("list", False, "the timing rules, [[stitch.rules]]"),
}

#: ``[[stitch.rules]]``: one timing rule, a rule of :data:`sewgen.machine.timing.RULES`. ``min`` and ``max`` have
#: no kind here: they are read in the rule's own kind of value (a length or an angle); at least one is needed
#: unless the rule has its own limits. ``from`` and ``to`` are given exactly for the rules that take a window.
RULE = {
    "rule": Field("text", True, "the rule's name (sewgen.machine.timing.RULES)"),
    "min": Field("", False, "lower limit"),
    "max": Field("", False, "upper limit"),
    "from": Field("angle", False, "window start (the rules with a window)"),
    "to": Field("angle", False, "window end (the rules with a window)"),
    "source": Field("text", True, "where the rule comes from (manual, textbook, seed)"),
}

#: ``[thread]``: the needle thread's path from the tension discs to the needle eye (seed 004's purpose).
THREAD = {
    "guides": Field("list", True, "the thread path, [[thread.guides]]"),
}

#: ``[[thread.guides]]``: one point of the thread path, ``at`` a point on the frame or ``point`` a moving one (one
#: of them), with an ``offset`` along the moving point's body axes (moving points only; default none).
GUIDE = {
    "name": Field("text", True, "what the guide is (tension discs, take-up eye, ...)"),
    "at": Field("list", False, "a point on the frame: [\"x\", \"y\"] with units"),
    "point": Field("text", False, "a moving point: a role (\"thread_eye\") or \"group.point\""),
    "offset": Field("list", False, "[\"u\", \"v\"] along the moving point's body axes"),
}

__all__ = ["COUNTERWEIGHT", "GROUP", "GUIDE", "LOAD", "MACHINE", "MODEL", "RULE", "SHAFT", "SHAFT_MASS", "STITCH",
           "THREAD"]

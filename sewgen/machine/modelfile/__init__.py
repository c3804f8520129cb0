"""Machine model files: TOML with explicit units, checked against a schema (DESIGN.md §5), read end to end here.

Every quantity is a string with its unit ("16.7 mm", "105 g", "1000 rpm"); a bare number is refused for
anything that has a unit. An unknown key, a missing key or a unit of the wrong kind raises
:class:`ModelFileError` naming the file, the key (dotted, e.g. ``groups.feed.params.cam_side``) and the unit
expected. Group parameters, held inputs, branches and load points are checked against the mechanism's own
manifest, so a model file can set anything a mechanism declares and nothing else. A file that is not UTF-8 text
or not TOML is a ModelFileError too, naming the file (and the line).

``reader``    the reader: :class:`ModelFileError`, :class:`Field`, :class:`Reader`, :func:`load_toml`,
              :func:`resolve` (a built-in model's name or a path), :func:`declaration_problem`
``schema``    every table of the file (``MACHINE``, ``SHAFT``, ``GROUP``, ``STITCH``, ``THREAD``, ...)
``sections``  the file read into typed data in SI: :func:`read_model` -> :class:`Model` (the shaft, a
              :class:`GroupSpec` per group, the :class:`Stitch`, the :class:`ThreadPath`);
              :func:`read_settings` (a group's tables against its mechanism); :func:`read_counterweights`

The machine layer (sewgen.machine.assembly, timing, thread, machine_balance) builds on this data and never reads
the file itself; this package imports only the leaves and the engine.
"""
from sewgen.machine.modelfile import schema
from sewgen.machine.modelfile.reader import (MODELS_DIR, Field, ModelFileError, Reader, builtin_models,
    declaration_problem, is_builtin, load_toml, resolve)
from sewgen.machine.modelfile.sections import (RESERVED_GROUP_NAMES, Declared, GroupSpec, Guide, Model, Plane, Rule,
    Settings, Shaft, ShaftMass, Stitch, ThreadPath, read_counterweights, read_model, read_settings)

__all__ = ["Declared", "Field", "GroupSpec", "Guide", "MODELS_DIR", "Model", "ModelFileError", "Plane",
           "RESERVED_GROUP_NAMES", "Reader", "Rule", "Settings", "Shaft", "ShaftMass", "Stitch", "ThreadPath",
           "builtin_models", "declaration_problem", "is_builtin", "load_toml", "read_counterweights", "read_model",
           "read_settings", "resolve", "schema"]

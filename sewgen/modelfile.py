"""Machine model files: TOML with explicit units, checked against a schema (DESIGN.md §5).

Every quantity is a string with its unit ("16.7 mm", "105 g", "1000 rpm"); a bare number is refused for
anything that has a unit. An unknown key, a missing key or a unit of the wrong kind raises
:class:`ModelFileError` naming the file, the key (dotted, e.g. ``groups.feed.params.cam_side``) and the unit
expected. Group parameters, held inputs, branches and load points are checked against the mechanism's own
manifest, so a model file can set anything a mechanism declares and nothing else.
"""
from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path

from .units import SI_UNITS, UnitError, to_si

from .errors import SewgenError

#: Built-in machine models, shipped beside this module.
MODELS_DIR = Path(__file__).parent / "models"


class ModelFileError(SewgenError, ValueError):
    """A model file that cannot be read: names the file (``file``, also ``path``), the dotted key and what was
    expected (``problem``)."""

    def __init__(self, path, key: str, message: str):
        self.path = str(path)
        super().__init__(f"{path}: {key}: {message}" if key else f"{path}: {message}", problem=message,
                         file=str(path), key=key)


@dataclass(frozen=True)
class Field:
    kind: str  # a units kind, "text", "int", "table" or "list"
    required: bool = True
    doc: str = ""


def _unit(kind: str) -> str:
    return SI_UNITS[kind] or "no unit"


class Reader:
    """Walks a parsed TOML document against a schema, converting quantities to SI."""

    def __init__(self, path):
        self.path = Path(path)

    def fail(self, key: str, message: str):
        raise ModelFileError(self.path, key, message)

    def table(self, data, key: str) -> dict:
        if not isinstance(data, dict):
            self.fail(key, f"must be a table, got {type(data).__name__}")
        return data

    def check_keys(self, data: dict, key: str, schema: dict) -> None:
        for k in data:
            if k not in schema:
                self.fail(f"{key}.{k}" if key else k, f"unknown key; allowed here: {', '.join(schema)}")
        for k, f in schema.items():
            if f.required and k not in data:
                what = f"a quantity in {_unit(f.kind)}" if f.kind in SI_UNITS else f"a {f.kind}"
                self.fail(f"{key}.{k}" if key else k, f"missing ({f.doc}: {what})" if f.doc else f"missing ({what})")

    def quantity(self, value, kind: str, key: str) -> float:
        if kind == "dimensionless" and isinstance(value, (int, float)) and not isinstance(value, bool):
            return float(value)
        if not isinstance(value, str):
            self.fail(key, f"must be a quantity string with its unit, e.g. \"12 {_hint(kind)}\" "
                           f"(expected {_unit(kind)}), got {value!r}")
        try:
            return to_si(value, kind, key)
        except UnitError as exc:
            self.fail(key, exc.problem)

    def read(self, data: dict, key: str, schema: dict) -> dict:
        """Check ``data`` against ``schema`` and convert: quantities to SI floats, the rest as they are."""
        self.check_keys(data, key, schema)
        out = {}
        for k, f in schema.items():
            if k not in data:
                continue
            v, full = data[k], f"{key}.{k}" if key else k
            if f.kind in SI_UNITS:
                out[k] = self.quantity(v, f.kind, full)
            elif f.kind == "text":
                if not isinstance(v, str):
                    self.fail(full, f"must be text, got {v!r}")
                out[k] = v
            elif f.kind == "int":
                if not isinstance(v, int) or isinstance(v, bool) or v < 1:
                    self.fail(full, f"must be a positive integer, got {v!r}")
                out[k] = v
            elif f.kind == "table":
                out[k] = self.table(v, full)
            elif f.kind == "list":
                if not isinstance(v, list):
                    self.fail(full, f"must be a list of tables ([[{full}]]), got {type(v).__name__}")
                out[k] = v
        return out


def _hint(kind: str) -> str:
    return {"length": "mm", "angle": "deg", "mass": "g", "inertia": "kg*m**2", "speed": "rpm", "force": "N",
            "torque": "N*m", "acceleration": "m/s**2", "mass_length": "g*mm"}.get(kind, _unit(kind))


def load_toml(path) -> dict:
    """Parse a TOML file; a syntax error names the file and the line."""
    p = Path(path)
    if not p.is_file():
        raise ModelFileError(p, "", "no such model file")
    try:
        return tomllib.loads(p.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ModelFileError(p, "", f"not valid TOML: {exc}") from None


def resolve(name_or_path) -> Path:
    """A built-in model by name ("jb1-3") or a path to a .toml file. A folder is never a model: ``sewgen analyze
    jb1-3`` writes its results into ./jb1-3, and the next run must still find the built-in model."""
    p = Path(name_or_path)
    if p.suffix == ".toml" or p.is_file():
        return p
    builtin = MODELS_DIR / f"{name_or_path}.toml"
    if builtin.is_file():
        return builtin
    known = ", ".join(sorted(q.stem for q in MODELS_DIR.glob("*.toml")))
    raise ModelFileError(p, "", f"neither a model file nor a built-in model (built in: {known})")

"""The model file's reader: TOML parsed, walked against a schema table (:mod:`.schema`), quantities to SI.

Every quantity is a string with its unit ("16.7 mm", "105 g", "1000 rpm"); a bare number is refused for
anything that has a unit. An unknown key, a missing key or a unit of the wrong kind raises
:class:`ModelFileError` naming the file, the key (dotted, e.g. ``groups.feed.params.cam_side``) and the unit
expected. A file that is not UTF-8 text or not TOML is a ModelFileError too, naming the file (and the line).
"""
from __future__ import annotations

import tomllib
import traceback
from dataclasses import dataclass
from pathlib import Path

from sewgen.errors import SewgenError
from sewgen.units import EXAMPLES, SI_UNITS, UnitError, range_problem, to_si

#: Built-in machine models: sewgen/models (this file is sewgen/machine/modelfile/reader.py).
MODELS_DIR = Path(__file__).resolve().parents[2] / "models"


class ModelFileError(SewgenError, ValueError):
    """A model file that cannot be read: names the file (``file``, also ``path``), the dotted key and what was
    expected (``problem``)."""

    def __init__(self, path, key: str, message: str):
        self.path = str(path)
        super().__init__(f"{path}: {key}: {message}" if key else f"{path}: {message}", problem=message,
                         file=str(path), key=key)


@dataclass(frozen=True)
class Field:
    """One key of a schema table: its kind, whether the file must give it, what it means (``doc``: shown in the
    "missing" message of a required key) and, for a quantity, its sign and the largest value it may have."""

    kind: str  # a units kind, "text", "int", "table" or "list"
    required: bool = True
    doc: str = ""
    sign: str = ""  # quantities: "positive" (> 0), "nonnegative" (>= 0) or "" (any finite value)
    maximum: float | None = None  # quantities: the largest physical value (SI), e.g. a friction coefficient's 1


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
            self.fail(key, f"must be a quantity string with its unit, e.g. \"{EXAMPLES.get(kind, '1')}\" "
                           f"(expected {_unit(kind)}), got {value!r}")
        try:
            return to_si(value, kind, key)
        except UnitError as exc:
            self.fail(key, exc.problem)

    def signed(self, value: float, sign: str, key: str, text) -> float:
        """``value`` checked against ``sign`` ("positive", "nonnegative" or "")."""
        if sign == "positive" and not value > 0:
            self.fail(key, f"must be positive, got {text!r}")
        if sign == "nonnegative" and value < 0:
            self.fail(key, f"must not be negative, got {text!r}")
        return value

    def read(self, data: dict, key: str, schema: dict) -> dict:
        """Check ``data`` against ``schema`` and convert: quantities to SI floats, the rest as they are."""
        self.check_keys(data, key, schema)
        out = {}
        for k, f in schema.items():
            if k not in data:
                continue
            v, full = data[k], f"{key}.{k}" if key else k
            if f.kind in SI_UNITS:
                out[k] = self.signed(self.quantity(v, f.kind, full), f.sign, full, v)
                problem = range_problem(out[k], None, f.maximum, SI_UNITS[f.kind])
                if problem:
                    self.fail(full, f"{problem} ({f.doc})" if f.doc else problem)
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


def load_toml(path) -> dict:
    """Parse a TOML file; a missing file, a folder, a name the file system cannot take, unreadable bytes (not
    UTF-8), a syntax error or nesting too deep to read names the file (and, for a syntax error, the line)."""
    p = Path(path)
    try:
        if p.is_dir():
            raise ModelFileError(p, "", "is a folder, not a model file")
        if not p.is_file():
            raise ModelFileError(p, "", "no such model file")
        data = p.read_bytes()
    except OSError as exc:  # a name too long, no permission, a loop of links
        raise ModelFileError(p, "", f"cannot be read ({exc.strerror or exc})") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise ModelFileError(p, "", f"not UTF-8 text (byte 0x{data[exc.start]:02x} on line {line}): save the file "
                                    "as UTF-8") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ModelFileError(p, "", f"not valid TOML: {exc}") from None
    except RecursionError:  # tomllib reads nested arrays and inline tables recursively
        raise ModelFileError(p, "", "arrays or inline tables nested too deeply to read (no model file nests more "
                                    "than a few levels)") from None


def builtin_models() -> list[str]:
    """Names of the built-in machine models ("jb1-3", ...)."""
    return sorted(q.stem for q in MODELS_DIR.glob("*.toml"))


def resolve(name_or_path) -> Path:
    """The model file a name or path stands for: a ``.toml`` path as given; otherwise a built-in model's name
    ("jb1-3"); otherwise an existing file. A folder is never a model: ``sewgen analyze jb1-3`` writes its results
    into ./jb1-3, and the next run must still find the built-in model."""
    text = str(name_or_path)
    p = Path(text)
    if p.suffix.lower() == ".toml":
        return p
    if text in builtin_models():
        return MODELS_DIR / f"{text}.toml"
    try:
        if p.is_file():
            return p
    except OSError as exc:  # a name too long for the file system
        raise ModelFileError(p, "", f"cannot be read ({exc.strerror or exc})") from None
    known = ", ".join(builtin_models())
    raise ModelFileError(p, "", f"neither a model file (.toml) nor a built-in model (built in: {known})")


def is_builtin(path) -> bool:
    """Whether ``path`` is one of the built-in model files."""
    try:
        return Path(path).resolve().parent == MODELS_DIR.resolve()
    except OSError:
        return False


def declaration_problem(exc: BaseException, path) -> str | None:
    """What a user's declaration file did wrong, as ``file:line: problem`` — a syntax error (or bytes that are
    not UTF-8), or an exception raised from the file's own code — or None when ``exc`` did not come from that
    file (then it is sewgen's, and keeps its traceback)."""
    path = Path(path)
    if isinstance(exc, SyntaxError):
        where = f"{exc.filename or path}:{exc.lineno}" if exc.lineno else str(exc.filename or path)
        return f"{where}: syntax error: {exc.msg}"

    def same(name):
        try:
            return Path(name).resolve() == path.resolve()
        except OSError:
            return False

    frames = [f for f in traceback.extract_tb(exc.__traceback__) if same(f.filename)]
    if not frames:
        return None
    return f"{path}:{frames[-1].lineno}: {type(exc).__name__}: {exc}"

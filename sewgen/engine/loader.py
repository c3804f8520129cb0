"""Loading compiled modules: the catalog built at install time, and user mechanisms built on demand.

A user mechanism (a declaration object, a function returning one, or a .py file with ``declare()``) is
derived, rendered and compiled into a cache folder keyed by a hash of everything that goes into the build, so a
second load of the same declaration imports the cached module without recompiling.

The cache is safe to share between processes: a build holds a lock on ``<root>/<module>.lock`` (so two processes
asking for the same new mechanism compile it once and load the same module), compiles in a temporary folder
inside the cache root and renames it into place, and only then writes ``BUILT.json`` (the key and the shared
object's sha256). An entry without a valid marker, or whose shared object does not match it (a partial copy, a
truncated file), is never imported: it is rebuilt. A cached module that still fails to import is rebuilt once,
then reported as a :class:`~sewgen.errors.BuildError` naming the mechanism and the path.

:func:`resolve` turns a :class:`~sewgen.engine.mechanism.Reference` (what a pickled Mechanism holds) back into a
Mechanism, in any process: the catalog by name, a user build from its cache entry, or rebuilt from the generated
sources the reference carries when the entry is gone.
"""
from __future__ import annotations

import contextlib
import hashlib
import importlib.util
import json
import os
import runpy
import shutil
import tempfile
import threading
import zlib
from pathlib import Path

from sewgen.engine.mechanism import RESOLVERS, Mechanism, Reference
from sewgen.errors import BuildError, OutputPathError
from sewgen.files import write_text

try:
    import fcntl
except ImportError:  # not POSIX: the atomic rename alone keeps the cache consistent
    fcntl = None

MARKER = "BUILT.json"
_RESOLVED: dict = {}  # (key, digest) -> the user Mechanism last loaded: unpickling results imports no module again


def _import_path(module: str, path: Path):
    spec = importlib.util.spec_from_file_location(module, str(path))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


_CATALOG = None


def _runnable_avx512():
    """sewgen._kernels_avx512 where it is built and this CPU runs its SIMD loops (``sg_simd_width``), else None."""
    try:
        from sewgen import _kernels_avx512 as wide
    except ImportError:
        return None
    return wide if wide.lib.sg_simd_width(wide.ffi.NULL) > 1 else None


def catalog_module():
    """The compiled catalog: sewgen._kernels_avx512 where it is built and this CPU has AVX-512, else
    sewgen._kernels (sewgen/engine/build.py catalog_levels); or the build named by SEWGEN_KERNELS (CI's sanitizer
    run)."""
    global _CATALOG
    if _CATALOG is None:
        alt = os.environ.get("SEWGEN_KERNELS")
        if alt:
            _CATALOG = _import_path("sewgen._kernels", Path(alt))
        else:
            _CATALOG = _runnable_avx512()
        if _CATALOG is None:
            try:
                from sewgen import _kernels
            except ImportError as exc:
                raise BuildError("the compiled catalog sewgen._kernels is missing: install with `pip install .`"
                                 f" ({exc})") from None
            _CATALOG = _kernels
    return _CATALOG


def catalog() -> list[str]:
    """Names of the built-in mechanisms."""
    mod = catalog_module()
    return [n[3:-9] for n in dir(mod.lib) if n.startswith("sg_") and n.endswith("_manifest")]


def cache_root() -> Path:
    return Path(os.environ.get("SEWGEN_CACHE", Path.home() / ".cache" / "sewgen"))


def _declaration(source):
    from sewgen.derive.model import Mechanism as Declaration

    if isinstance(source, Declaration):
        return source
    if callable(source):
        decl = source()
    else:
        path = Path(source)
        if not path.is_file():
            raise BuildError(f"no mechanism file {path}", file=str(path))
        ns = runpy.run_path(str(path))
        if "declare" not in ns:
            raise BuildError(f"{path}: defines no declare() function", file=str(path))
        decl = ns["declare"]()
    if not isinstance(decl, Declaration):
        raise BuildError(f"{source!r} did not give a derive.Mechanism declaration")
    return decl


def load(source, *, closed_form: bool = True, cache_dir: Path | None = None) -> Mechanism:
    """A mechanism declared outside the catalog: a derive.Mechanism, a function returning one, or a .py file with
    ``declare()``, derived and compiled on first use, then loaded from the cache (``cache_dir``, default
    :func:`cache_root`).

    A declaration *file* already built is loaded without deriving anything (no SymPy): the cache keeps an index
    from the file's text (with the derivation's and the runtime's sources, the flags and ``closed_form``) to
    its build. A declaration that imports other modules of yours is keyed by its own text only: after changing
    those, touch the declaration file (or clear the cache) to rebuild.
    """
    root = Path(cache_dir or cache_root())
    path = Path(source) if isinstance(source, (str, os.PathLike)) else None
    index = _declaration_index(root, path, closed_form) if path is not None and path.is_file() else None
    if index is not None:
        mech = _load_indexed(root, index, str(path.resolve()))
        if mech is not None:
            return mech
    from sewgen.derive import DeclarationError, generate, render_files

    decl = _declaration(source)
    declaration = str(Path(source).resolve()) if path is not None else ""
    try:
        files = render_files([generate(decl, closed_form=closed_form)])
    except DeclarationError as exc:
        raise BuildError(str(exc), mechanism=decl.name, file=declaration or None) from None
    mech = _load_built(root, decl.name, files, declaration)
    if index is not None:
        _write_json(index, {"mechanism": decl.name, "module": mech.build_info.get("folder", ""),
                            "key": mech.build_info["key"]})
    return mech


# -- declaration files already built: no derivation -------------------------------------------------------------

def _derivation_fingerprint() -> bytes:
    """What a build of the same declaration depends on besides its text: the derivation's sources and
    templates, the ABI and units tables, the runtime and the compiler flags."""
    from sewgen.engine.build import RUNTIME_FILES, compile_flags, runtime_dir

    here = Path(__file__).resolve().parents[1]  # sewgen/
    h = hashlib.sha256()
    sources = sorted((here / "derive").rglob("*.py")) + sorted((here / "derive").rglob("*.j2"))
    sources += [here / "abi.py", here / "units.py"] + [runtime_dir() / name for name in RUNTIME_FILES]
    for f in sources:
        h.update(f.name.encode() + b"\0" + f.read_bytes() + b"\0")
    h.update(" ".join(compile_flags()).encode())
    return h.digest()


def _declaration_index(root: Path, path: Path, closed_form: bool) -> Path:
    h = hashlib.sha256(path.read_bytes())
    h.update(b"closed" if closed_form else b"newton")
    h.update(_derivation_fingerprint())
    return root / "declarations" / f"{h.hexdigest()[:24]}.json"


def _load_indexed(root: Path, index: Path, declaration: str) -> Mechanism | None:
    """The build an index entry names, loaded from its folder's generated files; None when incomplete."""
    try:
        entry = json.loads(index.read_text())
        folder = Path(entry["module"])
        if folder.parent != root or _built(folder, entry["key"]) is None:
            return None
        files = {f.name: f.read_text() for f in sorted(folder.iterdir())
                 if f.is_file() and f.name.startswith(("sg_", "manifest")) and f.suffix in (".c", ".h", ".cdef", ".json")}
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if _build_key(files) != entry["key"]:
        return None
    return _load_built(root, entry["mechanism"], files, declaration)


def _write_json(path: Path, data: dict) -> None:
    """``data`` as JSON at ``path``, atomically (a reader sees the old file or the whole new one)."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_text(path, json.dumps(data, indent=1))
    except (OSError, OutputPathError):  # an index is an optimisation: without it the next load derives again
        pass


# -- the cache ------------------------------------------------------------------------------------------------

def _build_key(files: dict) -> str:
    """Hash of everything a build depends on: the generated files, the runtime sources, the compiler flags."""
    from sewgen.engine.build import RUNTIME_FILES, compile_flags, runtime_dir

    h = hashlib.sha256()
    rt = runtime_dir()
    for name in sorted(files):
        h.update(name.encode() + b"\0" + files[name].encode() + b"\0")
    for name in RUNTIME_FILES:  # the ABI (sg_abi.*) is among the generated files
        h.update((rt / name).read_bytes())
    h.update(" ".join(compile_flags()).encode())
    return h.hexdigest()[:20]


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@contextlib.contextmanager
def locked(path: Path):
    """An exclusive lock on ``path`` (created if missing) for the ``with`` block: one builder per cache entry."""
    with open(path, "a+") as fh:
        if fcntl is not None:
            fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            if fcntl is not None:
                fcntl.flock(fh, fcntl.LOCK_UN)


def _built(folder: Path, key: str) -> Path | None:
    """The shared object of a complete entry: the marker names it, for this key, and its hash matches."""
    try:
        marker = json.loads((folder / MARKER).read_text())
        so = folder / marker["so"]
        if marker["key"] == key and so.is_file() and _sha256(so) == marker["sha256"]:
            return so
    except (OSError, ValueError, KeyError, TypeError):
        pass
    return None


def _build(root: Path, folder: Path, module: str, name: str, files: dict, key: str, declaration: str) -> Path:
    """Compile into a temporary folder of ``root``, rename it to ``folder`` and write the marker last.
    The caller holds the entry's lock."""
    from sewgen.engine.build import make_ffi, runtime_object

    tmp = Path(tempfile.mkdtemp(prefix=f".{module}.", dir=root))
    try:
        for fname, text in files.items():
            write_text(tmp / fname, text)
        try:
            runtime = runtime_object(root / "runtime", files["sg_abi.h"])
            so = Path(make_ffi(module, tmp, [name], runtime_object=runtime).compile(tmpdir=str(tmp)))
        except Exception as exc:
            raise BuildError(f"{name}: compiling the generated C failed: {exc}", mechanism=name,
                             file=declaration or str(folder)) from None
        if folder.exists():  # an incomplete or broken entry (no valid marker): nobody may use it
            shutil.rmtree(folder)
        os.rename(tmp, folder)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    so = folder / so.name
    marker = {"key": key, "module": module, "mechanism": name, "so": so.name, "sha256": _sha256(so)}
    write_text(folder / MARKER, json.dumps(marker, indent=1))
    return so


def _load_built(root: Path, name: str, files: dict, declaration: str = "") -> Mechanism:
    """The mechanism ``name`` of the generated ``files``: imported from the cache under ``root``, built first
    if the cache has no complete entry for them."""
    key = _build_key(files)
    module = f"_sg_user_{name}_{key}"
    folder = root / module
    lock = root / f"{module}.lock"
    try:
        root.mkdir(parents=True, exist_ok=True)
        lock.touch()
    except OSError as exc:
        raise BuildError(f"{name}: cannot use the build cache {root}: {exc}", mechanism=name, file=str(root)) from None
    cached, failure = True, None
    with locked(lock):
        so = _built(folder, key)
        if so is not None:
            try:
                mod = _import_path(module, so)
            except ImportError as exc:  # a complete-looking entry that does not load: rebuild it once
                so, failure = None, exc
        if so is None:
            cached = False
            so = _build(root, folder, module, name, files, key, declaration)
            try:
                mod = _import_path(module, so)
            except ImportError as exc:
                before = f" (the cached module failed first: {failure})" if failure else ""
                raise BuildError(f"{name}: cannot import the compiled module {so}: {exc}{before}", mechanism=name,
                                 file=str(so)) from None
    sources = zlib.compress(json.dumps(files, sort_keys=True).encode(), 6)
    ref = Reference("user", name, module=module, folder=str(folder), key=key, declaration=declaration,
                    sources=sources)
    mech = Mechanism(mod.ffi, mod.lib, name, {"cached": cached, "path": str(so), "key": key, "folder": str(folder)},
                     ref)
    _RESOLVED[(key, mech.reference.digest)] = mech  # unpickling in this process finds it
    return mech


# -- the API: the catalog by name, a mechanism of the user's -----------------------------------------------

_MECHANISMS: dict = {}
_MECHANISMS_LOCK = threading.Lock()  # one Mechanism per catalog name, even when threads ask at once


def mechanism(name: str) -> Mechanism:
    """A built-in mechanism by name (see :func:`catalog`)."""
    mech = _MECHANISMS.get(name)
    if mech is None:
        with _MECHANISMS_LOCK:
            if name not in _MECHANISMS:
                names = catalog()
                if name not in names:
                    raise KeyError(f"no built-in mechanism {name!r}; the catalog has: {', '.join(names)}")
                mod = catalog_module()
                _MECHANISMS[name] = Mechanism(mod.ffi, mod.lib, name)
            mech = _MECHANISMS[name]
    return mech


# -- references (unpickling) ------------------------------------------------------------------------------------


def resolve(ref: Reference) -> Mechanism:
    """The Mechanism a :class:`~sewgen.engine.mechanism.Reference` names (what unpickling a Mechanism calls).

    The catalog's by name; a user build from its cache entry, or — where that entry is gone — rebuilt from the
    generated sources the reference carries, in this process's cache (:func:`cache_root`). Either way the
    manifest must be the one the reference was made from: :class:`~sewgen.errors.BuildError` if not.
    """
    if ref.kind == "catalog":
        try:
            mech = mechanism(ref.name)
        except KeyError:
            raise BuildError(f"{ref.name}: no longer in the compiled catalog", mechanism=ref.name) from None
    else:
        mech = _RESOLVED.get((ref.key, ref.digest))
        if mech is None:
            try:
                files = json.loads(zlib.decompress(ref.sources))
            except (zlib.error, ValueError) as exc:
                raise BuildError(f"{ref.name}: the pickled reference's generated sources are unreadable ({exc})",
                                 mechanism=ref.name) from None
            folder = Path(ref.folder)
            root = folder.parent if _built(folder, ref.key) is not None else cache_root()
            mech = _load_built(root, ref.name, files, ref.declaration)
    if mech.reference.digest != ref.digest:
        where = "the compiled catalog" if ref.kind == "catalog" else mech.build_info.get("path", "the build")
        raise BuildError(f"{ref.name}: {where} is not the mechanism this was pickled with (its manifest changed)",
                         mechanism=ref.name, file=ref.declaration or None)
    if ref.kind != "catalog":
        _RESOLVED[(ref.key, ref.digest)] = mech
    return mech


RESOLVERS.append(resolve)

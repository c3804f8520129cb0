"""Loading compiled modules: the catalog built at install time, and user mechanisms built on demand.

A user mechanism (a declaration object, a function returning one, or a .py file with ``declare()``) is
derived, rendered and compiled into a cache folder keyed by a hash of everything that goes into the build,
so a second load of the same declaration imports the cached module without recompiling.
"""
from __future__ import annotations

import hashlib
import importlib.util
import os
import runpy
from pathlib import Path

from .errors import BuildError
from .mechanism import Mechanism


def _import_path(module: str, path: Path):
    spec = importlib.util.spec_from_file_location(module, str(path))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


_CATALOG = None


def catalog_module():
    """The compiled catalog (sewgen._kernels), or the build named by SEWGEN_KERNELS (CI's sanitizer run)."""
    global _CATALOG
    if _CATALOG is None:
        alt = os.environ.get("SEWGEN_KERNELS")
        if alt:
            _CATALOG = _import_path("sewgen._kernels", Path(alt))
        else:
            try:
                from . import _kernels
            except ImportError as exc:
                raise BuildError("the compiled catalog sewgen._kernels is missing: install with `pip install .`"
                                 f" ({exc})") from None
            _CATALOG = _kernels
    return _CATALOG


def catalog_names() -> list[str]:
    mod = catalog_module()
    return [n[3:-9] for n in dir(mod.lib) if n.startswith("sg_") and n.endswith("_manifest")]


def cache_root() -> Path:
    return Path(os.environ.get("SEWGEN_CACHE", Path.home() / ".cache" / "sewgen"))


def _declaration(source):
    from .derive.model import Mechanism as Declaration

    if isinstance(source, Declaration):
        return source
    if callable(source):
        decl = source()
    else:
        path = Path(source)
        if not path.is_file():
            raise BuildError(f"no mechanism file {path}")
        ns = runpy.run_path(str(path))
        if "declare" not in ns:
            raise BuildError(f"{path}: defines no declare() function")
        decl = ns["declare"]()
    if not isinstance(decl, Declaration):
        raise BuildError(f"{source!r} did not give a derive.Mechanism declaration")
    return decl


def load_user(source, *, closed_form: bool = True, cache_dir: Path | None = None) -> Mechanism:
    """Derive, compile (once) and load a mechanism declared outside the catalog."""
    from .derive import DeclarationError, generate, render_files

    from .build import CFLAGS, make_ffi, runtime_dir

    decl = _declaration(source)
    try:
        files = render_files([generate(decl, closed_form=closed_form)])
    except DeclarationError as exc:
        raise BuildError(str(exc)) from None
    h = hashlib.sha256()
    rt = runtime_dir()
    for name in sorted(files):
        h.update(name.encode() + b"\0" + files[name].encode() + b"\0")
    for name in ("sg_runtime.c", "sg_runtime.h"):  # the ABI (sg_abi.*) is among the generated files
        h.update((rt / name).read_bytes())
    h.update(" ".join(CFLAGS + [os.environ.get("SEWGEN_CFLAGS", "")]).encode())
    key = h.hexdigest()[:20]
    module = f"_sg_user_{decl.name}_{key}"
    folder = Path(cache_dir or cache_root()) / module
    built = sorted(folder.glob(f"{module}*.so")) if folder.is_dir() else []
    cached = bool(built)
    if not cached:
        folder.mkdir(parents=True, exist_ok=True)
        for name, text in files.items():
            (folder / name).write_text(text)
        try:
            make_ffi(module, folder, [decl.name]).compile(tmpdir=str(folder))
        except Exception as exc:
            raise BuildError(f"{decl.name}: compiling the generated C failed: {exc}") from None
        built = sorted(folder.glob(f"{module}*.so"))
    mod = _import_path(module, built[0])
    return Mechanism(mod.ffi, mod.lib, decl.name, {"cached": cached, "path": str(built[0])})

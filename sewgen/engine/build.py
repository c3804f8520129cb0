"""cffi builders: the catalog module at install time, user mechanisms at run time (DESIGN.md §4).

``setup.py`` names ``catalog_modules()``'s builders (``sewgen/engine/build.py:catalog_ffi``, and
``catalog_ffi_avx512`` for the AVX-512 module) in ``cffi_modules``; setuptools runs this file on its own, so it
imports nothing from the sewgen package. Flags: -O2 -fpeel-loops -std=c99 and warnings as errors, never
-ffast-math (it would delete the NaN guards); SEWGEN_CFLAGS adds flags (the sanitizer build of CI).
"""
from __future__ import annotations

import ctypes.util
import functools
import hashlib
import json
import os
import platform
import shlex
import subprocess
import sys
import sysconfig
import tempfile
from pathlib import Path

import cffi

HERE = Path(__file__).resolve().parent  # sewgen/engine
PACKAGE = HERE.parent  # sewgen/
#: -fpeel-loops (GCC's -O3 peeling of loops with a small constant trip count, e.g. a vector's lanes): it speeds
#: the SIMD sweeps; it changes no arithmetic.
#: -fno-semantic-interposition: calls within the module stay direct, so the inlined sweep loops inline.
#: -Wno-error=maybe-uninitialized: GCC's "may be used uninitialized" follows the flow through the sweeps' deep
#: inlining only as far as its optimisation level and inlining budget take it, and reports arrays every path that
#: reads them has written (a kernel's outputs on its SG_OK return, an LU's pivots for k < n): it depends on the
#: mechanism's size and the flags, so it stays a warning, never a failed build of a user's mechanism. Every other
#: warning is an error.
CFLAGS = ["-O2", "-fpeel-loops", "-std=c99", "-Wall", "-Wextra", "-Werror", "-Wno-error=maybe-uninitialized",
          "-Wno-unused-parameter", "-fno-semantic-interposition"]


#: The hand-written runtime files every compiled module reads (a user build's cache key hashes them).
RUNTIME_FILES = ("sg_runtime.c", "sg_runtime.h", "sg_simd.h")


#: SEWGEN_SIMD values: the SIMD level a build compiles (csrc/sg_simd.h); "1" (the default): a user build for the
#: building CPU's best level, the catalog for both (below).
SIMD_LEVELS = {"0": None, "avx2": 256, "avx512": 512}

#: CPU flags (/proc/cpuinfo) the AVX-512 level needs: its vectors, 256-bit forms and 64-bit integer masks.
AVX512_FLAGS = ("avx512f", "avx512vl", "avx512dq")


def simd_choice() -> str:
    """The environment's SEWGEN_SIMD (``1`` where unset), checked."""
    choice = os.environ.get("SEWGEN_SIMD", "1").strip().lower()
    if choice not in SIMD_LEVELS and choice != "1":
        raise ValueError(f"SEWGEN_SIMD={choice!r}: expected one of 0, 1, avx2, avx512")
    return choice


def simd_flags(choice: str | None = None) -> tuple[list[str], list[str]]:
    """(compile flags, libraries) of the SIMD loops (csrc/sg_simd.h) at level ``choice`` (a SEWGEN_SIMD value;
    default the environment's): glibc's vector math library on x86-64 Linux, the SIMD code compiled for AVX-512
    (8 positions a vector) or AVX2 (4) and run only where the running CPU has that level (``sg_simd_width``;
    elsewhere the scalar loops); nothing on other platforms or for ``0``. ``1``: AVX-512 where the building CPU
    has it (a user's mechanism is built where it runs), else AVX2."""
    return _simd_flags(simd_choice() if choice is None else choice)


def _cpu_flags() -> set[str]:
    """The building CPU's feature flags (Linux /proc/cpuinfo); empty where it cannot be read."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            for line in f:
                if line.startswith("flags"):
                    return set(line.split(":", 1)[1].split())
    except OSError:
        pass
    return set()


@functools.lru_cache(maxsize=None)
def _simd_flags(choice: str) -> tuple[list[str], list[str]]:
    """simd_flags() of one SEWGEN_SIMD value, the library looked up once a process (find_library runs ldconfig)."""
    if choice == "0" or not (sys.platform.startswith("linux") and platform.machine() in ("x86_64", "AMD64")
                             and ctypes.util.find_library("mvec")):
        return [], []
    if choice == "1":
        choice = "avx512" if all(f in _cpu_flags() for f in AVX512_FLAGS) else "avx2"
    return ["-DSG_HAVE_MVEC", f"-DSG_SIMD_LEVEL={SIMD_LEVELS[choice]}"], ["mvec"]


def compile_flags(extra: list[str] | None = None, simd: str | None = None) -> list[str]:
    """Every flag a module is compiled with: CFLAGS, the SIMD ones (level ``simd``, default SEWGEN_SIMD's),
    ``extra``, then SEWGEN_CFLAGS."""
    return CFLAGS + simd_flags(simd)[0] + (extra or []) + shlex.split(os.environ.get("SEWGEN_CFLAGS", ""))


def runtime_dir() -> Path:
    """The hand-written runtime sources: installed as sewgen/_csrc, or csrc/ in a checkout."""
    for cand in (PACKAGE / "_csrc", PACKAGE.parent / "csrc"):
        if (cand / "sg_runtime.c").is_file():
            return cand
    raise FileNotFoundError("sewgen's C runtime sources (csrc/sg_runtime.c) are missing from this install")


def make_ffi(module: str, kernel_dir: Path, mechanisms: list[str], extra_cflags: list[str] | None = None,
             relative_to: Path | None = None, simd: str | None = None, one_unit: bool = False,
             runtime_object: Path | None = None) -> cffi.FFI:
    """An out-of-line API-mode FFI for the runtime plus the generated kernels of ``mechanisms``, SIMD at level
    ``simd`` (a SEWGEN_SIMD value; default the environment's). ``one_unit``: the runtime and the kernels included
    into the module's own C file rather than compiled as sources of their own, so a second module built from the
    same files in the same build (the catalog's AVX-512 one) shares no object file with the first.
    ``runtime_object``: the runtime already compiled with these flags (:func:`runtime_object`), linked in
    instead of compiling ``sg_runtime.c`` again."""
    rt = runtime_dir()
    ffi = cffi.FFI()
    ffi.cdef((kernel_dir / "sg_abi.cdef").read_text())  # the runtime's API, generated from sewgen/abi.py
    ffi.cdef((kernel_dir / "sg_kernels.cdef").read_text())
    runtime = [] if runtime_object is not None else [rt / "sg_runtime.c"]
    sources = runtime + [kernel_dir / f"sg_{name}.c" for name in mechanisms]
    incs = [rt, kernel_dir]
    if relative_to is not None:  # setuptools wants paths relative to setup.py
        sources = [s.relative_to(relative_to) for s in sources]
        incs = [i.relative_to(relative_to) for i in incs]
    flags = compile_flags(extra_cflags, simd)
    preamble = '#include "sg_kernels.h"\n'
    if one_unit:  # the runtime first: its SSE2 header before the SIMD part's (csrc/sg_runtime.c)
        preamble = "".join(f'#include "{Path(s).name}"\n' for s in sources) + preamble
        sources = []
    ffi.set_source(module, preamble,
                   sources=[str(s) for s in sources], include_dirs=[str(i) for i in incs],
                   extra_compile_args=flags, extra_link_args=[f for f in flags if f.startswith("-fsanitize")],
                   extra_objects=[str(runtime_object)] if runtime_object is not None else [],
                   libraries=["m"] + simd_flags(simd)[1])
    return ffi


def runtime_object(folder: Path, abi_header: str) -> Path:
    """``sg_runtime.c`` compiled once per flag set into ``folder`` (a build cache's ``runtime/``) and reused
    by every user build with the same flags: the object's name is a hash of the runtime's sources, the ABI
    header ``abi_header`` (the text of the generated sg_abi.h) and the flags. Written atomically (a compile
    into a temporary name, then a rename), so concurrent builders at worst compile it twice."""
    from sewgen.files import write_text  # here: setuptools runs this file on its own, without the package

    rt = runtime_dir()
    # As setuptools compiles a module's own sources: Python's CC, CFLAGS and CCSHARED (-fPIC), then ours.
    cc = shlex.split(os.environ.get("CC") or sysconfig.get_config_var("CC") or "cc")
    base = shlex.split(sysconfig.get_config_var("CFLAGS") or "") + shlex.split(os.environ.get("CFLAGS", ""))
    flags = base + shlex.split(sysconfig.get_config_var("CCSHARED") or "-fPIC") + compile_flags()
    h = hashlib.sha256(abi_header.encode())
    for name in RUNTIME_FILES:
        h.update(name.encode() + b"\0" + (rt / name).read_bytes())
    h.update(" ".join(flags).encode())
    obj = folder / f"sg_runtime-{h.hexdigest()[:20]}.o"
    if obj.is_file():
        return obj
    folder.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix=".runtime.", dir=folder) as tmp:
        write_text(Path(tmp) / "sg_abi.h", abi_header)
        part = Path(tmp) / obj.name
        res = subprocess.run([*cc, *flags, f"-I{rt}", f"-I{tmp}", "-c", str(rt / "sg_runtime.c"), "-o", str(part)],
                             capture_output=True, text=True)
        if res.returncode != 0:
            raise RuntimeError(f"compiling {rt / 'sg_runtime.c'} failed:\n{res.stderr[-4000:]}")
        os.replace(part, obj)
    return obj


GENERATED = PACKAGE.parent / "generated"


def _catalog_names() -> list[str]:
    return list(json.loads((GENERATED / "manifest.json").read_text()))


def catalog_levels() -> tuple[str, ...]:
    """The SIMD levels the catalog is built for, one module each: with SIMD (SEWGEN_SIMD ``1``, the default, or
    ``avx512``) ``sewgen._kernels`` for AVX2 and ``sewgen._kernels_avx512`` for AVX-512, whatever the building CPU
    has, and the loader imports the second where the running CPU has AVX-512 (sewgen/engine/loader.py); ``avx2``: the
    first alone; ``0`` or no SIMD on this platform: the first, without SIMD."""
    choice = simd_choice()
    if choice == "0" or not simd_flags("avx2")[0]:
        return ("0",)
    return ("avx2",) if choice == "avx2" else ("avx2", "avx512")


def _catalog_ffi(level: str) -> cffi.FFI:
    module = "sewgen._kernels_avx512" if level == "avx512" else "sewgen._kernels"
    return make_ffi(module, GENERATED, _catalog_names(), relative_to=PACKAGE.parent, simd=level,
                    one_unit=level == "avx512")


def catalog_ffi() -> cffi.FFI:
    """setup.py's first catalog module, sewgen._kernels (AVX2, or no SIMD)."""
    return _catalog_ffi(catalog_levels()[0])


def catalog_ffi_avx512() -> cffi.FFI:
    """setup.py's second catalog module, sewgen._kernels_avx512 (where catalog_levels() has it)."""
    return _catalog_ffi("avx512")


def catalog_modules() -> list[str]:
    """setup.py's cffi_modules: one builder per catalog level."""
    return ["sewgen/engine/build.py:catalog_ffi"] + (["sewgen/engine/build.py:catalog_ffi_avx512"]
                                              if "avx512" in catalog_levels() else [])


SANITIZE = ["-fsanitize=address,undefined", "-fno-sanitize-recover=undefined", "-fno-omit-frame-pointer", "-g",
            "-DSG_DEBUG"]


def build_catalog(outdir: Path, extra_cflags: list[str] | None = None) -> Path:
    """Compile the catalog as one module, ``sewgen._kernels``, into ``outdir`` (a checkout only; CI's sanitized
    build, loaded through SEWGEN_KERNELS) at the environment's SIMD level (SEWGEN_SIMD; by default the building
    CPU's best, as a user build); returns the shared object's path."""
    outdir.mkdir(parents=True, exist_ok=True)
    ffi = make_ffi("sewgen._kernels", GENERATED, _catalog_names(), extra_cflags)
    return Path(ffi.compile(tmpdir=str(outdir)))


if __name__ == "__main__":  # a separate catalog build (CI's sanitized pass), or the sanitizer flags
    import argparse

    ap = argparse.ArgumentParser(prog="python -m sewgen.engine.build",
                                 description="compile the catalog into OUTDIR (SEWGEN_CFLAGS adds flags), or print "
                                             "the sanitizer flags (the one list CI exports as SEWGEN_CFLAGS)")
    ap.add_argument("outdir", type=Path, nargs="?")
    ap.add_argument("--sanitize", action="store_true", help="add -fsanitize=address,undefined and the rest")
    ap.add_argument("--sanitize-flags", action="store_true", help="print the sanitizer flags and exit")
    a = ap.parse_args()
    if a.sanitize_flags:
        print(shlex.join(SANITIZE))
    elif a.outdir is None:
        ap.error("OUTDIR is required")
    else:
        print(build_catalog(a.outdir, SANITIZE if a.sanitize else None))

"""``python -m derive`` regenerates generated/; ``--check`` fails with a unified diff when it is stale."""
from __future__ import annotations

import argparse
import difflib
import sys
import time
from pathlib import Path

from sewgen.files import write_text

from .catalog import CATALOG, declare
from .emit import generate, render_files

ROOT = Path(__file__).resolve().parents[2]  # the checkout: sewgen/derive/ -> ../../
#: What derive writes; anything else in generated/ (object files of an in-place build) is not its business.
GENERATED_SUFFIXES = (".c", ".h", ".cdef", ".json")


def _derived_files(folder: Path) -> set[str]:
    if not folder.is_dir():
        return set()
    return {p.name for p in folder.iterdir() if p.is_file() and p.suffix in GENERATED_SUFFIXES}


def catalog_files() -> dict[str, str]:
    return render_files([generate(declare(name)) for name in CATALOG])


def check(files: dict[str, str], out: Path, stdout=None) -> bool:
    """Whether the folder ``out`` holds exactly ``files`` (a derivation's, by name); a unified diff of every
    difference goes to ``stdout`` (default sys.stdout). Files derive does not write (object files of an
    in-place build) are not compared."""
    stdout = stdout or sys.stdout
    current = True
    present = _derived_files(out)
    for name in sorted(set(files) | present):
        try:
            old = (out / name).read_text() if name in present else ""
        except (OSError, UnicodeDecodeError) as exc:
            old = f"<unreadable: {exc}>\n"
        new = files.get(name, "")
        if old != new:
            current = False
            stdout.writelines(difflib.unified_diff(
                old.splitlines(True), new.splitlines(True), f"generated/{name}", f"derived/{name}"))
    return current


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m sewgen.derive", description=__doc__)
    ap.add_argument("--check", action="store_true", help="compare with generated/ instead of writing")
    ap.add_argument("--out", type=Path, default=ROOT / "generated", help="output folder (default: generated/)")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    files = catalog_files()
    out: Path = args.out
    if args.check:
        if not check(files, out):
            print("generated/ is stale: run `python -m derive`", file=sys.stderr)
            return 1
        print(f"generated/ is current ({len(files)} files, {time.perf_counter() - t0:.1f} s)")
        return 0
    out.mkdir(parents=True, exist_ok=True)
    for name in _derived_files(out) - set(files):
        (out / name).unlink()
    for name, text in files.items():
        write_text(out / name, text, "--out")
    print(f"wrote {len(files)} files to {out} in {time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
